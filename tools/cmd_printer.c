/* ampath printer list|show — the printer profiles that gcode, slice and the bridge take (docs/interfaces.md §5). */
#include <stdio.h>
#include <string.h>

#include "cli.h"

const char cmd_printer_usage[] =
    "list the built-in printer profiles, or show one (or a slicer .ini) as ampath reads it\n"
    "usage: ampath printer list [--json]\n"
    "       ampath printer show NAME|FILE.ini [--json]\n"
    "  NAME is a built-in profile (generic, prusa-mk3s, ender3, voron-350); FILE a PrusaSlicer,\n"
    "  SuperSlicer or OrcaSlicer printer/filament/print .ini (or several concatenated).\n"
    "  show prints every value ampath uses, the start and end G-code expanded without a job\n"
    "  (max_layer_z 0, the first layer the whole bed), and the keys of the file that ampath does not\n"
    "  use for the machine (\"unknown_keys\" in --json; the start/end macros may still read them).\n";

static void json_profile(const amp_printer *p)
{
    cli_json j;
    cli_json_begin(&j, stdout);
    cli_json_str(&j, "name", p->name);
    cli_json_str(&j, "model", p->model);
    cli_json_str(&j, "flavor", p->flavor == AMP_FLAVOR_KLIPPER ? "klipper" : "marlin");
    cli_json_box(&j, "bed_mm", (amp_box3){{p->bed_min_x, p->bed_min_y, 0.0}, {p->bed_max_x, p->bed_max_y, p->max_height}});
    cli_json_num(&j, "bed_radius_mm", p->bed_radius);
    cli_json_num(&j, "max_height_mm", p->max_height);
    cli_json_num(&j, "nozzle_diameter_mm", p->nozzle_diameter);
    cli_json_num(&j, "bead_width_mm", amp_printer_bead_width(p));
    cli_json_num(&j, "filament_diameter_mm", p->filament_diameter);
    cli_json_num(&j, "layer_height_mm", p->layer_height);
    cli_json_num(&j, "first_layer_height_mm", p->first_layer_height);
    cli_json_num(&j, "temperature_c", p->temp);
    cli_json_num(&j, "first_layer_temperature_c", p->first_layer_temp);
    cli_json_num(&j, "bed_temperature_c", p->bed_temp);
    cli_json_num(&j, "first_layer_bed_temperature_c", p->first_layer_bed_temp);
    cli_json_num(&j, "fan_percent", p->fan_percent);
    cli_json_int(&j, "fan_off_layers", p->fan_off_layers);
    cli_json_num(&j, "retract_length_mm", p->retract_length);
    cli_json_num(&j, "retract_speed_mm_s", p->retract_speed);
    cli_json_num(&j, "z_hop_mm", p->retract_lift);
    cli_json_num(&j, "retract_before_travel_mm", p->retract_before_travel);
    cli_json_num(&j, "print_speed_mm_s", p->print_speed);
    cli_json_num(&j, "first_layer_speed_mm_s", p->first_layer_speed);
    cli_json_num(&j, "travel_speed_mm_s", p->travel_speed);
    cli_json_num(&j, "acceleration_mm_s2", p->accel);
    cli_json_num(&j, "max_feed_xy_mm_s", p->max_feed_xy);
    cli_json_num(&j, "max_feed_z_mm_s", p->max_feed_z);
    cli_json_num(&j, "max_feed_e_mm_s", p->max_feed_e);
    cli_json_num(&j, "max_accel_xy_mm_s2", p->max_accel_xy);
    cli_json_num(&j, "max_accel_z_mm_s2", p->max_accel_z);
    cli_json_num(&j, "max_accel_e_mm_s2", p->max_accel_e);
    cli_json_num(&j, "retract_accel_mm_s2", p->retract_accel);
    cli_json_num(&j, "max_volumetric_flow_mm3_s", p->max_volumetric_flow);
    cli_json_num(&j, "extrusion_multiplier", p->extrusion_multiplier);
    cli_json_str(&j, "start_gcode", p->start_out);
    cli_json_str(&j, "end_gcode", p->end_out);
    cli_json_int(&j, "keys_read", (long long)p->n_keys);
    cli_json_int(&j, "unknown_key_count", (long long)p->n_unknown);
    cli_json_csv(&j, "unknown_keys", p->unknown);
    cli_json_end(&j);
}

static void human_profile(const amp_printer *p)
{
    printf("printer %s (%s firmware)\n", p->name, p->flavor == AMP_FLAVOR_KLIPPER ? "Klipper" : "Marlin");
    printf("  bed X %g..%g, Y %g..%g, height %g mm\n", p->bed_min_x, p->bed_max_x, p->bed_min_y, p->bed_max_y,
           p->max_height);
    if (p->bed_radius > 0.0)
        printf("  round bed: printable within %g mm of its centre\n", p->bed_radius);
    printf("  nozzle %g mm (planar beads %g mm wide), filament %g mm, layers %g mm (first %g mm)\n",
           p->nozzle_diameter, amp_printer_bead_width(p), p->filament_diameter, p->layer_height, p->first_layer_height);
    printf("  hot end %g C (first layer %g C), bed %g C (first layer %g C)\n", p->temp, p->first_layer_temp,
           p->bed_temp, p->first_layer_bed_temp);
    printf("  fan %g %% after %d layer(s); retract %g mm at %g mm/s (not below %g mm of travel), z-hop %g mm\n",
           p->fan_percent, p->fan_off_layers, p->retract_length, p->retract_speed, p->retract_before_travel,
           p->retract_lift);
    printf("  speeds: print %g, first layer %g, travel %g mm/s; acceleration %g mm/s^2; limits XY %g, Z %g, E %g "
           "mm/s; flow %g mm^3/s; multiplier %g\n",
           p->print_speed, p->first_layer_speed, p->travel_speed, p->accel, p->max_feed_xy, p->max_feed_z,
           p->max_feed_e, p->max_volumetric_flow, p->extrusion_multiplier);
    printf("  axis accelerations: XY %g, Z %g, E %g mm/s^2; retraction %g mm/s^2 (0: no limit)\n", p->max_accel_xy,
           p->max_accel_z, p->max_accel_e, p->retract_accel);
    printf("  start G-code: %s\n", p->start_out[0] ? "" : "(built-in: heat, home, wait)");
    if (p->start_out[0])
        printf("%s\n", p->start_out);
    printf("  end G-code: %s\n", p->end_out[0] ? "" : "(built-in: heaters, fan and motors off)");
    if (p->end_out[0])
        printf("%s\n", p->end_out);
    if (p->n_keys)
        printf("  %lu keys read, %lu not used for the machine (the start/end macros may read them): %s\n",
               (unsigned long)p->n_keys, (unsigned long)p->n_unknown, p->unknown);
}

int cmd_printer(int argc, char **argv)
{
    static amp_printer p;
    amp_gcode_opts o;
    amp_error err;
    const char *pos[2];
    int json = 0, npos = 0, rc;
    size_t i;
    cli_opt opts[] = {{"json", CLI_FLAG, &json, 0}, {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("printer", argc, argv, opts, pos, 1, 2, &npos);
    if (rc != CLI_OK)
        return rc;
    if (strcmp(pos[0], "list") == 0 && npos == 1) {
        cli_json j;
        if (!json) {
            for (i = 0; i < amp_printer_builtin_count(); i++)
                printf("%-12s %s\n", amp_printer_builtin_name(i), amp_printer_builtin_about(i));
            return CLI_OK;
        }
        cli_json_begin(&j, stdout);
        cli_json_arr(&j, "printers");
        for (i = 0; i < amp_printer_builtin_count(); i++) {
            cli_json_obj(&j, NULL);
            cli_json_str(&j, "name", amp_printer_builtin_name(i));
            cli_json_str(&j, "about", amp_printer_builtin_about(i));
            cli_json_close(&j);
        }
        cli_json_close(&j);
        cli_json_end(&j);
        return CLI_OK;
    }
    if (strcmp(pos[0], "show") != 0 || npos != 2)
        return cli_fail("printer", CLI_USAGE, "usage: ampath printer list | show NAME|FILE.ini [--json]");
    amp_error_clear(&err);
    if (amp_printer_load(&p, pos[1], &err) != AMP_OK || amp_printer_gcode_opts(&p, &o, &err) != AMP_OK)
        return cli_fail_err("printer", &err);
    if (json)
        json_profile(&p);
    else
        human_profile(&p);
    return CLI_OK;
}
