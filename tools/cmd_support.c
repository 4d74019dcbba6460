/* ampath support — support structure under the model (paper 5.3). */
#include <string.h>

#include "checkers.h"
#include "headopt.h"
#include "slicetool.h"

const char cmd_support_usage[] =
    "add support paths under the model and interleave them with the object paths (paper 5.3)\n"
    "usage: ampath support PATHS.amp --mesh MESH.stl|--trivariate F [--spacing S] [--layer H] [--radius R] [--min-gap G]\n"
    "                     [--z-offs Z] [--theta DEG] [--json] -o OUT.amp\n"
    "  --mesh FILE     the model as a closed STL mesh; vertical rays through it find the support volume\n"
    "  --trivariate F  the model as a trivariate (.spl or built-in name): its boundary is tessellated\n"
    "  --spacing S     grid spacing of the rays and of the support rows, mm (default 2)\n"
    "  --layer H       height between support layers, mm (default 0.4; a sliced job's support takes the\n"
    "                  job's own layers, as planar beads printed with each layer)\n"
    "  --radius R      deposition radius of support paths, mm (default 0.2)\n"
    "  --min-gap G     air gaps under the model lower than G need no support, mm (default 1)\n"
    "  --no-pads       no pads: support only where the rays find air of --min-gap or more under the model,\n"
    "                  not also under object beads that would be printed in the air (the check below)\n"
    HEADOPT_HELP
    "  --json          one JSON object: rays, columns, support paths and length, placement, object splits,\n"
    "                  unheld object paths, time\n"
    "  -o FILE         write object and support paths in print order (.amp)\n"
    "Each support piece is printed just before the first object fragment whose head cone lies above it (an\n"
    "object path is split there when needed); object paths the support still leaves unheld (the check of\n"
    "'ampath check', 45-degree rule, air under a bead up to --min-gap) are named. Before the pads, an object\n"
    "path that the check finds in the air over an object path printed later is printed after it when the head\n"
    "cone allows (reported as settled).\n";


static void print_json(const char *input, const char *tri, const char *mesh, const amp_support_opts *o,
                       const amp_support_stats *st, size_t paths_out, const amp_hold_report *hr, double t)
{
    cli_json j;
    size_t i;
    cli_json_begin(&j, stdout);
    cli_json_str(&j, "input", input);
    cli_json_str(&j, tri ? "trivariate" : "mesh", tri ? tri : mesh);
    cli_json_num(&j, "spacing", o->spacing);
    cli_json_num(&j, "layer", st->layer_height);
    cli_json_bool(&j, "sliced", st->sliced);
    cli_json_int(&j, "rays", (long long)st->rays);
    cli_json_int(&j, "columns", (long long)st->columns);
    cli_json_int(&j, "support_paths", (long long)st->paths);
    cli_json_num(&j, "support_length_mm", st->length);
    cli_json_int(&j, "unplaced", (long long)st->unplaced);
    cli_json_int(&j, "object_splits", (long long)st->splits);
    cli_json_int(&j, "conflicts", (long long)st->conflicts);
    cli_json_num(&j, "trimmed_mm", st->trimmed);
    cli_json_int(&j, "settled", (long long)st->settled);
    cli_json_int(&j, "pads", (long long)st->pads);
    cli_json_num(&j, "pad_length_mm", st->pad_length);
    cli_json_int(&j, "paths_out", (long long)paths_out);
    cli_json_int(&j, "unheld_paths", (long long)hr->npaths_failed);
    cli_json_num(&j, "unheld_mm", hr->failed_mm);
    cli_json_arr(&j, "unheld_path_list"); /* the first 100, indices in the output */
    for (i = 0; i < hr->npaths_failed && i < 100; i++)
        cli_json_int(&j, NULL, (long long)hr->paths_failed[i]);
    cli_json_close(&j);
    cli_json_num(&j, "time_s", t);
    cli_json_end(&j);
}

static void print_text(const char *input, const amp_support_stats *st, const amp_hold_report *hr)
{
    size_t i;
    printf("%s: %lu rays, %lu columns need support: %lu support paths, %.1f mm (%lu printed last, %lu object paths "
           "split, %lu conflicts: %.1f mm left out)\n",
           input, (unsigned long)st->rays, (unsigned long)st->columns, (unsigned long)st->paths, st->length,
           (unsigned long)st->unplaced, (unsigned long)st->splits, (unsigned long)st->conflicts, st->trimmed);
    if (st->settled)
        printf("%lu object paths moved so that none is printed before the object bead under it\n",
               (unsigned long)st->settled);
    if (hr->npaths_failed) {
        printf("%lu object paths are not held (%.1f mm in the air), e.g. path", (unsigned long)hr->npaths_failed,
               hr->failed_mm);
        for (i = 0; i < hr->npaths_failed && i < 10; i++)
            printf(" %lu", (unsigned long)hr->paths_failed[i]);
        printf("%s\n", hr->npaths_failed > 10 ? " ..." : "");
    }
}

/* Pads are meant for the first rows over a shallow underside; pads a tenth of the object's length and more
 * mean its rows do not rest on each other (a covering spaced wider than its beads: the box field at
 * spacing 3 with mdr's nominal 0.5 on PrusaSlicer's bunny made 52 m of pads for 113 m of object). */
static void warn_pads(const amp_support_stats *st, double object_length)
{
    if (st->pad_length > 0.1 * object_length && object_length > 0.0)
        fprintf(stderr,
                "ampath support: warning: %lu pads, %.0f mm (%.0f %% of the object's %.0f mm): the object's paths do "
                "not rest on each other; are they spaced wider than their beads (the covering's spacing against "
                "mdr's --nominal radius)?\n",
                (unsigned long)st->pads, st->pad_length, 100.0 * st->pad_length / object_length, object_length);
}

int cmd_support(int argc, char **argv)
{
    const char *pos[1], *output = NULL, *mesh = NULL, *tri = NULL;
    double z_offs = AMP_HEAD_DEFAULT_Z_OFFS, theta = 72.0, t0;
    int json = 0, nopads = 0, npos = 0, rc;
    amp_support_opts o;
    amp_support_stats st;
    amp_hold_opts ho;
    amp_hold_report hr;
    cli_progress bar;
    amp_pathset ps, out;
    amp_mesh m;
    amp_bvh *b = NULL;
    amp_error err;
    cli_opt opts[] = {{"mesh", CLI_STR, &mesh, 0},        {"trivariate", CLI_STR, &tri, 0},
                      {"spacing", CLI_DOUBLE, NULL, 0},   {"layer", CLI_DOUBLE, NULL, 0},
                      {"radius", CLI_DOUBLE, NULL, 0},    {"min-gap", CLI_DOUBLE, NULL, 0},
                      {"z-offs", CLI_DOUBLE, &z_offs, 0}, {"theta", CLI_DOUBLE, &theta, 0},
                      {"json", CLI_FLAG, &json, 0},       {"output", CLI_STR, &output, 0},
                      {"no-pads", CLI_FLAG, &nopads, 0},  {NULL, CLI_FLAG, NULL, 0}};
    amp_support_opts_default(&o);
    opts[2].dst = &o.spacing;
    opts[3].dst = &o.layer_height;
    opts[4].dst = &o.radius;
    opts[5].dst = &o.min_gap;
    rc = cli_parse("support", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (!mesh == !tri)
        return cli_fail("support", CLI_USAGE, "give the model: --mesh MESH.stl or --trivariate F");
    o.find_unheld = nopads ? NULL : amp_check_hold_runs; /* the pads' judge: the check of 'ampath check' */
    if ((rc = headopt_make("support", z_offs, theta, &o.head)) != CLI_OK)
        return rc;
    amp_error_clear(&err);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out, NULL);
    amp_mesh_init(&m, NULL);
    memset(&hr, 0, sizeof hr);
    if ((rc = cli_load_paths("support", pos[0], &ps)) != CLI_OK)
        return rc;
    if (ps.npaths == 0) {
        /* nothing to hold (a field that missed the mesh); the library spun without end on it */
        amp_pathset_free(&ps);
        return cli_fail("support", CLI_USAGE, "%s holds no path to support", pos[0]);
    }
    rc = CLI_USAGE;
    t0 = cli_now();
    if (tri) {
        amp_spline v;
        if ((rc = cli_load_trivariate("support", tri, &v)) != CLI_OK)
            goto done;
        rc = CLI_USAGE;
        if (amp_mesh_from_trivariate(&m, &v, 0, &err) != AMP_OK) {
            amp_spline_free(&v);
            rc = cli_fail_err("support", &err);
            goto done;
        }
        amp_spline_free(&v);
    }
    if ((!tri && (amp_mesh_read_stl_file(&m, mesh, &err) != AMP_OK || slicetool_outward(&m, NULL, &err) != AMP_OK)) ||
        amp_bvh_build(&b, &m, &err) != AMP_OK) {
        rc = cli_fail_err("support", &err);
        goto done;
    }
    cli_progress_begin(&bar, "support");
    o.progress = cli_progress_fn;
    o.progress_user = &bar;
    rc = amp_support(&ps, b, &o, &out, &st, &err) == AMP_OK ? CLI_OK : cli_fail_err("support", &err);
    cli_progress_end(&bar);
    if (rc != CLI_OK)
        goto done;
    rc = CLI_USAGE;
    /* name what the support leaves unheld (the check of `ampath check`, [P1 §5.3]) */
    amp_hold_opts_default(&ho);
    ho.max_gap = o.min_gap;
    if (amp_check_hold(&out, &ho, &hr, &err) != AMP_OK) {
        rc = cli_fail_err("support", &err);
        goto done;
    }
    if (output && cli_save_derived("support", output, &out, "ampath support", pos[0]) != CLI_OK)
        goto done;
    if (json)
        print_json(pos[0], tri, mesh, &o, &st, out.npaths, &hr, cli_now() - t0);
    else
        print_text(pos[0], &st, &hr);
    warn_pads(&st, amp_pathset_length(&ps, AMP_ROLE_OBJECT));
    rc = CLI_OK;
done:
    amp_hold_report_free(&hr);
    amp_bvh_free(b);
    amp_mesh_free(&m);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
    return rc;
}
