/* ampath gcode PATHS.amp — MDR-modulated G-code (SPEC §4, §5). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

const char cmd_gcode_usage[] =
    "turn ordered paths into G-code with extrusion from the deposition radius (SPEC 5)\n"
    "usage: ampath gcode PATHS.amp [--flavor marlin|klipper] [printer options] [-o OUT.gcode] [--json]\n"
    "  --flavor F              marlin (default) or klipper\n"
    "  --filament D            filament diameter, mm (1.75)\n"
    "  --flow K                extrusion multiplier (1.0)\n"
    "  --max-flow Q            hot-end maximum volumetric flow, mm^3/s (12); the feed is lowered above it\n"
    "  --feed V                print feed, mm/s (30)\n"
    "  --travel-feed V         travel feed, mm/s (120)\n"
    "  --retract L             retraction length, mm of filament (1.0; 0 = none)\n"
    "  --retract-speed V       retraction speed, mm/s (35)\n"
    "  --z-hop H               clearance above printed material during travels, mm (0.4)\n"
    "  --corridor W            half-width around a travel line checked for material, mm (2.0)\n"
    "  --end-lift H            lift at the end of the job, mm (10)\n"
    "  --relative-e            relative extrusion, M83 (default for klipper)\n"
    "  --absolute-e            absolute extrusion, M82 (default for marlin)\n"
    "  --hotend T              hot-end temperature of the built-in start, C (210; 0 = no heating)\n"
    "  --bed T                 bed temperature of the built-in start, C (60; 0 = no heating)\n"
    "  --start FILE            start sequence from FILE instead of the built-in one\n"
    "  --end FILE              end sequence from FILE instead of the built-in one\n"
    "  --accel A               acceleration, mm/s^2 (1000), written to the printer and used by the estimate\n"
    "  --junction-deviation J  junction deviation of the time estimate, mm (0.05)\n"
    "  --max-feed-xy V         XY speed limit of the estimate, mm/s (200)\n"
    "  --max-feed-z V          Z speed limit of the estimate and feed of travel lifts, mm/s (10)\n"
    "  --max-feed-e V          filament speed limit of the estimate, mm/s (60)\n"
    "  -o, --output FILE       write the G-code to FILE (replaced atomically)\n"
    "  --json                  print the figures as one JSON object: lines, paths, segments, travels,\n"
    "                          retractions, lowered_feed_segments, print_length_mm, travel_length_mm,\n"
    "                          filament_mm, filament_mm3, time_s, print_time_s, travel_time_s\n"
    "Without -o nothing is written; the figures are printed.\n";

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

/* Through the one safe writer (issue 21): symlinks followed, devices written directly, a
 * unique temporary renamed into place only after a complete, synced write. */
static int write_gcode(const char *out, const amp_pathset *ps, const amp_gcode_opts *o, amp_gcode_stats *st)
{
    amp_out f;
    amp_error err;
    amp_status s;
    amp_error_clear(&err);
    if (amp_out_open(&f, out, &err) != AMP_OK)
        return cli_fail_err("gcode", &err);
    s = amp_gcode_write(ps, o, amp_out_sink, &f, st, &err);
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

int cmd_gcode(int argc, char **argv)
{
    amp_gcode_opts o, d;
    amp_pathset ps;
    amp_gcode_stats st;
    amp_error err;
    const char *pos[1], *flavor = "marlin", *out = NULL, *start = NULL, *end = NULL;
    char *start_text = NULL, *end_text = NULL;
    int json = 0, rel = 0, abs_e = 0, npos = 0, rc, fl;
    double t0;
    cli_opt opts[] = {{"flavor", CLI_STR, &flavor, 0},
                      {"filament", CLI_DOUBLE, &d.filament_diameter, 0},
                      {"flow", CLI_DOUBLE, &d.flow, 0},
                      {"max-flow", CLI_DOUBLE, &d.max_volumetric_flow, 0},
                      {"feed", CLI_DOUBLE, &d.print_feed, 0},
                      {"travel-feed", CLI_DOUBLE, &d.travel_feed, 0},
                      {"retract", CLI_DOUBLE, &d.retract_length, 0},
                      {"retract-speed", CLI_DOUBLE, &d.retract_speed, 0},
                      {"z-hop", CLI_DOUBLE, &d.z_hop, 0},
                      {"corridor", CLI_DOUBLE, &d.travel_corridor, 0},
                      {"end-lift", CLI_DOUBLE, &d.end_lift, 0},
                      {"relative-e", CLI_FLAG, &rel, 0},
                      {"absolute-e", CLI_FLAG, &abs_e, 0},
                      {"hotend", CLI_DOUBLE, &d.hotend_temp, 0},
                      {"bed", CLI_DOUBLE, &d.bed_temp, 0},
                      {"start", CLI_STR, &start, 0},
                      {"end", CLI_STR, &end, 0},
                      {"accel", CLI_DOUBLE, &d.accel, 0},
                      {"junction-deviation", CLI_DOUBLE, &d.junction_deviation, 0},
                      {"max-feed-xy", CLI_DOUBLE, &d.max_feed_xy, 0},
                      {"max-feed-z", CLI_DOUBLE, &d.max_feed_z, 0},
                      {"max-feed-e", CLI_DOUBLE, &d.max_feed_e, 0},
                      {"output", CLI_STR, &out, 0},
                      {"json", CLI_FLAG, &json, 0},
                      {NULL, CLI_FLAG, NULL, 0}};
    cli_opt *op;
    amp_gcode_opts_default(&d, AMP_FLAVOR_MARLIN);
    rc = cli_parse("gcode", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (strcmp(flavor, "marlin") == 0)
        fl = AMP_FLAVOR_MARLIN;
    else if (strcmp(flavor, "klipper") == 0)
        fl = AMP_FLAVOR_KLIPPER;
    else
        return cli_fail("gcode", CLI_USAGE, "--flavor must be marlin or klipper, got '%s'", flavor);
    if (rel && abs_e)
        return cli_fail("gcode", CLI_USAGE, "--relative-e and --absolute-e exclude each other");
    /* flavor defaults first, then every option the user gave */
    amp_gcode_opts_default(&o, fl);
    for (op = opts; op->name; op++) {
        if (op->seen && op->kind == CLI_DOUBLE) {
            size_t off = (size_t)((char *)op->dst - (char *)&d);
            *(double *)((char *)&o + off) = *(double *)op->dst;
        }
    }
    if (rel)
        o.relative_e = 1;
    if (abs_e)
        o.relative_e = 0;
    if (start && (rc = read_text(start, &start_text)) != CLI_OK)
        return rc;
    if (end && (rc = read_text(end, &end_text)) != CLI_OK) {
        amp_free(NULL, start_text);
        return rc;
    }
    o.start_gcode = start_text;
    o.end_gcode = end_text;
    amp_pathset_init(&ps, NULL);
    rc = cli_load_paths("gcode", pos[0], &ps);
    t0 = cli_now();
    if (rc == CLI_OK) {
        if (out) {
            rc = write_gcode(out, &ps, &o, &st);
        } else {
            /* no product without -o (SPEC 4): the iterator's init computes every figure */
            static amp_gcode_iter it;
            amp_error_clear(&err);
            if (amp_gcode_iter_init(&it, &ps, &o, &err) != AMP_OK)
                rc = cli_fail_err("gcode", &err);
            else
                st = it.est;
        }
    }
    if (rc == CLI_OK) {
        double secs = cli_now() - t0;
        if (json) {
            cli_json j;
            cli_json_begin(&j, stdout);
            cli_json_str(&j, "flavor", flavor);
            cli_json_bool(&j, "relative_e", o.relative_e);
            cli_json_int(&j, "lines", (long long)st.lines);
            cli_json_int(&j, "paths", (long long)st.paths);
            cli_json_int(&j, "paths_skipped", (long long)st.paths_skipped);
            cli_json_int(&j, "segments", (long long)st.segments);
            cli_json_int(&j, "travels", (long long)st.travels);
            cli_json_int(&j, "retractions", (long long)st.retractions);
            cli_json_int(&j, "lowered_feed_segments", (long long)st.lowered_feed_segments);
            cli_json_num(&j, "print_length_mm", st.print_length);
            cli_json_num(&j, "travel_length_mm", st.travel_length);
            cli_json_num(&j, "filament_mm", st.filament_length);
            cli_json_num(&j, "filament_mm3", st.filament_volume);
            cli_json_num(&j, "time_s", st.time);
            cli_json_num(&j, "print_time_s", st.print_time);
            cli_json_num(&j, "travel_time_s", st.travel_time);
            cli_json_num(&j, "max_travel_z_mm", st.max_travel_z);
            cli_json_num(&j, "seconds", secs);
            if (out)
                cli_json_str(&j, "output", out);
            cli_json_end(&j);
        } else {
            long t = (long)(st.time + 0.5);
            printf("%s%s: %lu lines, %lu paths (%lu skipped), %lu segments, %lu travels, %lu retractions\n",
                   out ? "wrote " : "", out ? out : pos[0], (unsigned long)st.lines, (unsigned long)st.paths,
                   (unsigned long)st.paths_skipped, (unsigned long)st.segments, (unsigned long)st.travels,
                   (unsigned long)st.retractions);
            printf("printed %.1f mm, filament %.1f mm (%.1f mm^3), %lu segments with lowered feed\n",
                   st.print_length, st.filament_length, st.filament_volume, (unsigned long)st.lowered_feed_segments);
            printf("estimated time %ld s (%ld:%02ld:%02ld): printing %.0f s, travels %.0f s\n", t, t / 3600,
                   t / 60 % 60, t % 60, st.print_time, st.travel_time);
        }
    }
    amp_pathset_free(&ps);
    amp_free(NULL, start_text);
    amp_free(NULL, end_text);
    return rc;
}
