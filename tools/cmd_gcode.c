/* ampath gcode PATHS.amp — MDR-modulated G-code, placed on a printer's bed (docs/interfaces.md §4, §5). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

const char cmd_gcode_usage[] =
    "turn ordered paths into G-code for a printer, with extrusion from the deposition radius (docs/interfaces.md §5)\n"
    "usage: ampath gcode PATHS.amp [--printer NAME|FILE.ini] [--place center|origin|X,Y] [options] [-o OUT.gcode]\n"
    "  --printer P             built-in profile (generic, prusa-mk3s, ender3, voron-350; `ampath printer list`)\n"
    "                          or a PrusaSlicer/SuperSlicer/OrcaSlicer .ini (default generic: 220x220x250 Marlin)\n"
    "  --place WHERE           center (default: middle of the bed, resting on it), origin (the job's own\n"
    "                          coordinates) or X,Y (centre of the job at bed point X,Y, resting on it)\n"
    "  --flavor F              marlin or klipper (default: the profile's)\n"
    "  --mesh MESH.stl         the part, to compare the extruded volume with (--json)\n"
    "profile values (each overrides the profile):\n"
    "  --filament D            filament diameter, mm\n"
    "  --flow K                extrusion multiplier\n"
    "  --max-flow Q            hot-end maximum volumetric flow, mm^3/s; the feed is lowered above it\n"
    "  --feed V                print feed, mm/s\n"
    "  --first-layer-feed V    feed on the first layer, mm/s\n"
    "  --travel-feed V         travel feed, mm/s\n"
    "  --retract L             retraction length, mm of filament (0 = none)\n"
    "  --retract-speed V       retraction speed, mm/s\n"
    "  --retract-min-travel D  travels shorter than D mm do not retract\n"
    "  --z-hop H               clearance above printed material during travels, mm\n"
    "  --hotend T              hot-end temperature, C (also the first layer's unless --first-layer-hotend; 0 = none)\n"
    "  --bed T                 bed temperature, C (also the first layer's unless --first-layer-bed; 0 = none)\n"
    "  --first-layer-hotend T, --first-layer-bed T   first-layer temperatures, C\n"
    "  --fan PERCENT           part-cooling fan after the first layers (0 = no fan commands)\n"
    "  --fan-off-layers N      layers printed with the fan off\n"
    "  --accel A               acceleration, mm/s^2, written to the printer and used by the estimate\n"
    "  --max-feed-xy V, --max-feed-z V, --max-feed-e V   axis limits of the estimate, mm/s\n"
    "  --max-accel-xy A, --max-accel-z A, --max-accel-e A   axis acceleration limits of the estimate,\n"
    "                          mm/s^2 (the profile's; 0 = none); --retract-accel A: of retractions\n"
    "  --max-cross-section A   Klipper: its max_extrude_cross_section, mm^2 (4 x nozzle^2; 0 = none); a job\n"
    "                          with a wider bead is refused (Klipper would stop it at that move)\n"
    "writer options:\n"
    "  --chord-tol T           simplification chord tolerance, mm (0.01; 0 = off)\n"
    "  --radius-tol T          deposition radius tolerance of the simplification, mm (0.01)\n"
    "  --min-segment L         shortest extruding segment unless a whole path, mm (0.02; 0 = off)\n"
    "  --arcs                  fit helical arcs within the tolerances and write them as G2/G3 (Marlin with\n"
    "                          ARC_SUPPORT, Klipper with [gcode_arcs])\n"
    "  --corridor W            half-width around a travel line checked for material, mm (1.0;\n"
    "                          beyond it the head cone is checked)\n"
    "  --end-lift H            lift at the end of the job, mm (10)\n"
    "  --direct-hop D          travels up to D mm go straight without retraction or lift where the head\n"
    "                          cone clears the printed material (3; 0 = always retract and lift)\n"
    "  --z-offs Z, --theta DEG head cone of the direct-hop test (docs/interfaces.md §2: 0.5 mm, 72 degrees)\n"
    "  --junction-deviation J  junction deviation of the time estimate, mm (0.05)\n"
    "  --relative-e / --absolute-e   M83 or M82 (default: klipper relative, marlin absolute)\n"
    "  --start FILE, --end FILE      start / end sequence from FILE instead of the profile's (taken as it is;\n"
    "                          the profile's are expanded in the slicers' macro language for the placed job)\n"
    "  -o, --output FILE       write the G-code to FILE (replaced atomically; nothing written on an error)\n"
    "  --json                  the figures as one JSON object (see docs/gcode.md)\n"
    "A job that does not fit the printer's bed volume is refused (exit 2) and nothing is written.\n";

static int read_text(const char *file, char **text)
{
    amp_error err;
    size_t len;
    amp_error_clear(&err);
    if (amp_read_file(file, NULL, 1 << 20, text, &len, &err) != AMP_OK)
        return cli_fail_err("gcode", &err);
    if (memchr(*text, '\0', len))
        return cli_fail("gcode", CLI_USAGE, "%s: contains a NUL byte", file);
    return CLI_OK;
}

/* Put the body written to @p body's temporary after the header, into @p f. */
static amp_status append_body(amp_out *f, amp_out *body, amp_error *err)
{
    static char buf[1 << 16];
    FILE *in;
    size_t n;
    amp_status s = AMP_OK;
    if (fflush(body->f) != 0 || body->werr)
        return amp_fail(err, AMP_ERR_IO, 0, "%s: %s", body->tmp, strerror(body->werr ? body->werr : errno));
    in = fopen(body->tmp, "rb");
    if (!in)
        return amp_fail(err, AMP_ERR_IO, 0, "%s: %s", body->tmp, strerror(errno));
    while (s == AMP_OK && (n = fread(buf, 1, sizeof buf, in)) > 0)
        s = amp_out_sink(f, buf, n);
    if (s == AMP_OK && ferror(in))
        s = amp_fail(err, AMP_ERR_IO, 0, "%s: %s", body->tmp, strerror(errno));
    fclose(in);
    return s;
}

/* The output sink with a progress bar: the share of the job's paths written, every 2^14 lines. */
typedef struct bar_sink {
    amp_out *o;
    const amp_gcode_iter *it;
    cli_progress bar;
    size_t lines;
} bar_sink;

static amp_status bar_write(void *user, const char *data, size_t len)
{
    bar_sink *b = user;
    if ((++b->lines & 0x3fff) == 0 && b->it->ps->npaths)
        cli_progress_update(&b->bar, (double)b->it->path / (double)b->it->ps->npaths);
    return amp_out_sink(b->o, data, len);
}

/* Write the job of @p it through the one safe writer (io.h amp_out: symlinks followed, devices written
 * directly, a unique temporary renamed into place only after a complete, synced write). A file gets the
 * job run once: the body first, into a second temporary beside it, then the header with the figures
 * that run found, then the body (amp_gcode_iter_init_body). A device gets it as init ran it (the header
 * figures from its dry run) since nothing written to it can be taken back. */
static int write_gcode(const char *out, amp_gcode_iter *it, const amp_pathset *ps, const amp_gcode_opts *o,
                       amp_gcode_stats *st)
{
    amp_out f, body;
    amp_error err;
    amp_status s;
    bar_sink bar;
    amp_error_clear(&err);
    if (amp_out_open(&f, out, &err) != AMP_OK)
        return cli_fail_err("gcode", &err);
    bar.it = it;
    bar.lines = 0;
    cli_progress_begin(&bar.bar, "gcode");
    if (f.direct) {
        bar.o = &f;
        s = amp_gcode_iter_init(it, ps, o, &err);
        if (s == AMP_OK)
            s = amp_gcode_iter_write(it, bar_write, &bar, st, &err);
    } else {
        memset(&body, 0, sizeof body);
        bar.o = &body;
        s = amp_gcode_iter_init_body(it, ps, o, &err);
        if (s == AMP_OK)
            s = amp_out_open(&body, out, &err);
        if (s == AMP_OK && (s = amp_gcode_iter_write(it, bar_write, &bar, st, &err)) != AMP_OK && body.werr)
            amp_fail(&err, AMP_ERR_IO, 0, "%s: %s", body.tmp, strerror(body.werr));
        if (s == AMP_OK)
            s = amp_gcode_iter_header(it, amp_out_sink, &f, &err);
        if (s == AMP_OK)
            s = append_body(&f, &body, &err);
        amp_out_abort(&body);
        *st = it->est;
    }
    cli_progress_end(&bar.bar);
    if (s != AMP_OK) {
        if (f.werr)
            amp_fail(&err, AMP_ERR_IO, 0, "%s: %s", f.target, strerror(f.werr));
        amp_out_abort(&f);
        return cli_fail_err("gcode", &err);
    }
    if (amp_out_commit(&f, &err) != AMP_OK)
        return cli_fail_err("gcode", &err);
    return CLI_OK;
}

/* --place center|origin|X,Y */
static int parse_place(const char *s, amp_gcode_opts *o)
{
    char *end;
    if (strcmp(s, "center") == 0 || strcmp(s, "centre") == 0) {
        o->place = AMP_PLACE_CENTER;
        return CLI_OK;
    }
    if (strcmp(s, "origin") == 0) {
        o->place = AMP_PLACE_ORIGIN;
        return CLI_OK;
    }
    o->place = AMP_PLACE_AT;
    o->place_x = strtod(s, &end);
    if (end != s && *end == ',') {
        const char *y = end + 1;
        o->place_y = strtod(y, &end);
        if (end != y && *end == '\0')
            return CLI_OK;
    }
    return cli_fail("gcode", CLI_USAGE, "--place must be center, origin or X,Y (mm), got '%s'", s);
}

/* Figures of the whole job for --json. */
static void print_json(const char *in, const char *out, const amp_printer *pr, const amp_gcode_iter *it,
                       const amp_gcode_stats *st, const amp_pathset *ps, double part, double secs)
{
    cli_json j;
    double sup = amp_pathset_volume(ps, AMP_ROLE_SUPPORT), obj = amp_pathset_volume(ps, AMP_ROLE_OBJECT);
    cli_json_begin(&j, stdout);
    cli_json_str(&j, "input", in);
    cli_json_str(&j, "printer", pr->name);
    cli_json_str(&j, "flavor", it->o.flavor == AMP_FLAVOR_KLIPPER ? "klipper" : "marlin");
    cli_json_bool(&j, "relative_e", it->o.relative_e);
    cli_json_str(&j, "place", it->o.place == AMP_PLACE_ORIGIN ? "origin" : it->o.place == AMP_PLACE_AT ? "at" : "center");
    cli_json_vec3(&j, "offset_mm", it->off);
    cli_json_box(&j, "bbox_mm", st->bbox);
    cli_json_box(&j, "bed_mm", (amp_box3){{it->o.bed_min_x, it->o.bed_min_y, 0.0},
                                         {it->o.bed_max_x, it->o.bed_max_y, it->o.max_height}});
    cli_json_num(&j, "bed_radius_mm", it->o.bed_radius);
    cli_json_num(&j, "first_layer_z_mm", st->first_layer_z);
    cli_json_int(&j, "lines", (long long)st->lines);
    cli_json_int(&j, "paths", (long long)st->paths);
    cli_json_int(&j, "paths_skipped", (long long)st->paths_skipped);
    cli_json_int(&j, "input_segments", (long long)st->input_segments);
    cli_json_int(&j, "segments", (long long)st->segments);
    cli_json_int(&j, "lines_saved", (long long)st->input_segments - (long long)st->segments);
    cli_json_int(&j, "arcs", (long long)st->arcs);
    cli_json_int(&j, "travels", (long long)st->travels);
    cli_json_int(&j, "travel_moves", (long long)st->travel_moves);
    cli_json_int(&j, "retractions", (long long)st->retractions);
    cli_json_int(&j, "direct_hops", (long long)st->direct_hops);
    cli_json_int(&j, "lowered_feed_segments", (long long)st->lowered_feed_segments);
    cli_json_num(&j, "print_length_mm", st->print_length);
    cli_json_num(&j, "travel_length_mm", st->travel_length);
    cli_json_num(&j, "travel_per_print_length", st->travel_length / st->print_length);
    cli_json_num(&j, "filament_mm", st->filament_length);
    cli_json_num(&j, "filament_mm3", st->filament_volume);
    cli_json_num(&j, "bead_volume_mm3", st->bead_volume);
    cli_json_num(&j, "object_bead_volume_mm3", obj);
    cli_json_num(&j, "support_bead_volume_mm3", sup);
    cli_json_num(&j, "extruded_per_bead_volume", st->filament_volume / st->bead_volume);
    if (part > 0.0) {
        cli_json_num(&j, "part_volume_mm3", part);
        cli_json_num(&j, "extruded_per_part_and_support_volume", st->filament_volume / (part + sup));
    }
    cli_json_num(&j, "time_s", st->time);
    cli_json_num(&j, "print_time_s", st->print_time);
    cli_json_num(&j, "travel_time_s", st->travel_time);
    cli_json_num(&j, "travel_time_fraction", st->time > 0.0 ? st->travel_time / st->time : 0.0);
    cli_json_num(&j, "max_travel_z_mm", st->max_travel_z);
    cli_json_int(&j, "printer_keys_read", (long long)pr->n_keys);
    cli_json_csv(&j, "printer_unknown_keys", pr->unknown);
    cli_json_num(&j, "seconds", secs);
    if (out)
        cli_json_str(&j, "output", out);
    cli_json_end(&j);
}

static void print_human(const char *in, const char *out, const amp_printer *pr, const amp_gcode_iter *it,
                        const amp_gcode_stats *st)
{
    long t = (long)(st->time + 0.5);
    printf("%s%s for %s: %lu lines, %lu paths (%lu skipped), %lu segments (%lu input), %lu travels, %lu "
           "retractions (%lu direct hops)\n",
           out ? "wrote " : "", out ? out : in, pr->name, (unsigned long)st->lines, (unsigned long)st->paths,
           (unsigned long)st->paths_skipped, (unsigned long)st->segments, (unsigned long)st->input_segments,
           (unsigned long)st->travels, (unsigned long)st->retractions, (unsigned long)st->direct_hops);
    printf("placed at offset %.3f %.3f %.3f mm: X %.2f..%.2f, Y %.2f..%.2f, Z %.2f..%.2f\n", it->off.x, it->off.y,
           it->off.z, st->bbox.min.x, st->bbox.max.x, st->bbox.min.y, st->bbox.max.y, st->bbox.min.z, st->bbox.max.z);
    printf("printed %.1f mm, travel %.1f mm, filament %.1f mm (%.1f mm^3 for %.1f mm^3 of beads)\n", st->print_length,
           st->travel_length, st->filament_length, st->filament_volume, st->bead_volume);
    printf("estimated time %ld s (%ld:%02ld:%02ld): printing %.0f s, travels %.0f s\n", t, t / 3600, t / 60 % 60,
           t % 60, st->print_time, st->travel_time);
}

/* Override the profile's values with the options the user gave. */
typedef struct cli_vals {
    double filament, flow, max_flow, feed, first_feed, travel_feed, retract, retract_speed, retract_min, z_hop;
    long fan_off_n;
    double hotend, bed, hotend1, bed1, fan, accel, jd, max_xy, max_z, max_e, acc_xy, acc_z, acc_e, acc_r, xs;
    double chord, rtol, minseg, corridor, end_lift, hop, zoffs, theta;
} cli_vals;

#define OVR(name, field, val)                                                                                      \
    do {                                                                                                           \
        if (cli_seen(opts, name))                                                                                  \
            o->field = (val);                                                                                      \
    } while (0)

static int cli_seen(const cli_opt *opts, const char *name)
{
    for (; opts->name; opts++)
        if (strcmp(opts->name, name) == 0)
            return opts->seen;
    return 0;
}

static void apply_overrides(const cli_opt *opts, const cli_vals *v, amp_gcode_opts *o)
{
    OVR("filament", filament_diameter, v->filament);
    OVR("flow", flow, v->flow);
    OVR("max-flow", max_volumetric_flow, v->max_flow);
    OVR("feed", print_feed, v->feed);
    OVR("first-layer-feed", first_layer_feed, v->first_feed);
    OVR("travel-feed", travel_feed, v->travel_feed);
    OVR("retract", retract_length, v->retract);
    OVR("retract-speed", retract_speed, v->retract_speed);
    OVR("retract-min-travel", retract_min_travel, v->retract_min);
    OVR("z-hop", z_hop, v->z_hop);
    OVR("hotend", hotend_temp, v->hotend);
    OVR("hotend", first_layer_hotend_temp, v->hotend);
    OVR("bed", bed_temp, v->bed);
    OVR("bed", first_layer_bed_temp, v->bed);
    OVR("first-layer-hotend", first_layer_hotend_temp, v->hotend1);
    OVR("first-layer-bed", first_layer_bed_temp, v->bed1);
    OVR("fan", fan_speed, v->fan / 100.0);
    OVR("fan-off-layers", fan_off_layers, v->fan_off_n >= 0 && v->fan_off_n <= 100000 ? (int)v->fan_off_n : -1);
    OVR("accel", accel, v->accel);
    OVR("junction-deviation", junction_deviation, v->jd);
    OVR("max-feed-xy", max_feed_xy, v->max_xy);
    OVR("max-feed-z", max_feed_z, v->max_z);
    OVR("max-feed-e", max_feed_e, v->max_e);
    OVR("max-accel-xy", max_accel_xy, v->acc_xy);
    OVR("max-accel-z", max_accel_z, v->acc_z);
    OVR("max-accel-e", max_accel_e, v->acc_e);
    OVR("retract-accel", retract_accel, v->acc_r);
    OVR("max-cross-section", max_cross_section, v->xs);
    OVR("chord-tol", chord_tol, v->chord);
    OVR("radius-tol", radius_tol, v->rtol);
    OVR("min-segment", min_segment, v->minseg);
    OVR("corridor", travel_corridor, v->corridor);
    OVR("end-lift", end_lift, v->end_lift);
    OVR("direct-hop", direct_hop, v->hop);
    OVR("z-offs", head_z_offs, v->zoffs);
    OVR("theta", head_theta, v->theta);
}

/* The part's volume from --mesh (0 when not given); CLI_USAGE on a bad file. */
static int part_volume(const char *mesh, double *vol)
{
    amp_mesh m;
    amp_error err;
    *vol = 0.0;
    if (!mesh)
        return CLI_OK;
    amp_mesh_init(&m, NULL);
    amp_error_clear(&err);
    if (amp_mesh_read_stl_file(&m, mesh, &err) != AMP_OK) {
        amp_mesh_free(&m);
        return cli_fail_err("gcode", &err);
    }
    *vol = amp_mesh_volume(&m);
    amp_mesh_free(&m);
    return CLI_OK;
}

/* Load the paths, expand the profile's start/end G-code for the placed job, check that the job fits (before
 * any file is touched), write it, report. */
static int run_job(const char *in, const char *out, int json, amp_printer *pr, amp_gcode_opts *o, double part)
{
    static amp_gcode_iter it;
    amp_pathset ps;
    amp_gcode_stats st;
    amp_error err;
    double t0;
    int rc;
    amp_pathset_init(&ps, NULL);
    amp_error_clear(&err);
    rc = cli_load_paths("gcode", in, &ps);
    t0 = cli_now();
    if (rc == CLI_OK && amp_printer_gcode_job(pr, o, &ps, &it, &err) != AMP_OK)
        rc = cli_fail_err("gcode", &err);
    if (rc == CLI_OK && out)
        rc = write_gcode(out, &it, &ps, o, &st);
    else if (rc == CLI_OK && amp_gcode_iter_init(&it, &ps, o, &err) != AMP_OK)
        rc = cli_fail_err("gcode", &err);
    else
        st = it.est;
    if (rc == CLI_OK && json)
        print_json(in, out, pr, &it, &st, &ps, part, cli_now() - t0);
    else if (rc == CLI_OK)
        print_human(in, out, pr, &it, &st);
    amp_pathset_free(&ps);
    return rc;
}

int cmd_gcode(int argc, char **argv)
{
    static amp_printer pr;
    amp_gcode_opts o;
    amp_error err;
    cli_vals v;
    const char *pos[1], *flavor = NULL, *out = NULL, *start = NULL, *end = NULL, *printer = "generic", *place = NULL;
    const char *mesh = NULL;
    char *start_text = NULL, *end_text = NULL;
    int json = 0, rel = 0, abs_e = 0, arcs = 0, npos = 0, rc;
    double part = 0.0;
    cli_opt opts[] = {{"printer", CLI_STR, &printer, 0},        {"place", CLI_STR, &place, 0},
                      {"flavor", CLI_STR, &flavor, 0},          {"mesh", CLI_STR, &mesh, 0},
                      {"filament", CLI_DOUBLE, &v.filament, 0}, {"flow", CLI_DOUBLE, &v.flow, 0},
                      {"max-flow", CLI_DOUBLE, &v.max_flow, 0}, {"feed", CLI_DOUBLE, &v.feed, 0},
                      {"first-layer-feed", CLI_DOUBLE, &v.first_feed, 0},
                      {"travel-feed", CLI_DOUBLE, &v.travel_feed, 0},
                      {"retract", CLI_DOUBLE, &v.retract, 0},   {"retract-speed", CLI_DOUBLE, &v.retract_speed, 0},
                      {"retract-min-travel", CLI_DOUBLE, &v.retract_min, 0},
                      {"z-hop", CLI_DOUBLE, &v.z_hop, 0},       {"hotend", CLI_DOUBLE, &v.hotend, 0},
                      {"bed", CLI_DOUBLE, &v.bed, 0},           {"first-layer-hotend", CLI_DOUBLE, &v.hotend1, 0},
                      {"first-layer-bed", CLI_DOUBLE, &v.bed1, 0}, {"fan", CLI_DOUBLE, &v.fan, 0},
                      {"fan-off-layers", CLI_LONG, &v.fan_off_n, 0}, {"accel", CLI_DOUBLE, &v.accel, 0},
                      {"junction-deviation", CLI_DOUBLE, &v.jd, 0}, {"max-feed-xy", CLI_DOUBLE, &v.max_xy, 0},
                      {"max-feed-z", CLI_DOUBLE, &v.max_z, 0},  {"max-feed-e", CLI_DOUBLE, &v.max_e, 0},
                      {"max-accel-xy", CLI_DOUBLE, &v.acc_xy, 0}, {"max-accel-z", CLI_DOUBLE, &v.acc_z, 0},
                      {"max-accel-e", CLI_DOUBLE, &v.acc_e, 0}, {"retract-accel", CLI_DOUBLE, &v.acc_r, 0},
                      {"max-cross-section", CLI_DOUBLE, &v.xs, 0},
                      {"chord-tol", CLI_DOUBLE, &v.chord, 0},   {"radius-tol", CLI_DOUBLE, &v.rtol, 0},
                      {"min-segment", CLI_DOUBLE, &v.minseg, 0}, {"corridor", CLI_DOUBLE, &v.corridor, 0},
                      {"end-lift", CLI_DOUBLE, &v.end_lift, 0}, {"relative-e", CLI_FLAG, &rel, 0},
                      {"arcs", CLI_FLAG, &arcs, 0},             {"direct-hop", CLI_DOUBLE, &v.hop, 0},
                      {"z-offs", CLI_DOUBLE, &v.zoffs, 0},      {"theta", CLI_DOUBLE, &v.theta, 0},
                      {"absolute-e", CLI_FLAG, &abs_e, 0},      {"start", CLI_STR, &start, 0},
                      {"end", CLI_STR, &end, 0},                {"output", CLI_STR, &out, 0},
                      {"json", CLI_FLAG, &json, 0},             {NULL, CLI_FLAG, NULL, 0}};
    memset(&v, 0, sizeof v);
    rc = cli_parse("gcode", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (rel && abs_e)
        return cli_fail("gcode", CLI_USAGE, "--relative-e and --absolute-e exclude each other");
    amp_error_clear(&err);
    if (amp_printer_load(&pr, printer, &err) != AMP_OK || amp_printer_gcode_opts(&pr, &o, &err) != AMP_OK)
        return cli_fail_err("gcode", &err);
    if (flavor) {
        if (strcmp(flavor, "marlin") != 0 && strcmp(flavor, "klipper") != 0)
            return cli_fail("gcode", CLI_USAGE, "--flavor must be marlin or klipper, got '%s'", flavor);
        o.flavor = strcmp(flavor, "klipper") == 0 ? AMP_FLAVOR_KLIPPER : AMP_FLAVOR_MARLIN;
        o.relative_e = o.flavor == AMP_FLAVOR_KLIPPER; /* docs/interfaces.md §5: the flavour's E mode unless asked */
    }
    apply_overrides(opts, &v, &o);
    if (flavor && !cli_seen(opts, "junction-deviation")) /* the flavour's cornering at the acceleration used */
        o.junction_deviation = amp_gcode_junction_default(o.flavor, o.accel);
    if (place && (rc = parse_place(place, &o)) != CLI_OK)
        return rc;
    o.arcs = arcs;
    if (rel)
        o.relative_e = 1;
    if (abs_e)
        o.relative_e = 0;
    if ((rc = part_volume(mesh, &part)) != CLI_OK)
        return rc;
    if (start && (rc = read_text(start, &start_text)) != CLI_OK)
        return rc;
    if (end && (rc = read_text(end, &end_text)) != CLI_OK) {
        amp_free(NULL, start_text);
        return rc;
    }
    if (start_text)
        o.start_gcode = start_text;
    if (end_text)
        o.end_gcode = end_text;
    rc = run_job(pos[0], out, json, &pr, &o, part);
    amp_free(NULL, start_text);
    amp_free(NULL, end_text);
    return rc;
}
