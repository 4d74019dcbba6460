/* ampath check for continuous strokes (paper 2 §4): independent verification
 * with amp_stroke_check(). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check_stroke.h"
#include "slicetool.h"

const char check_stroke_usage[] =
    "  --mesh MESH.stl    also check that every path lies inside the layer polygon of its height\n"
    "  --layer H          layer height used by 'ampath slice' (required with --mesh)\n"
    "  --first-layer H0   first layer height used by 'ampath slice' (default: H)\n"
    "  --tol T            distance tolerance for 'inside', mm (default 1e-6)\n"
    "  --json             figures: paths, segments, crossings, repeated_edges, outside, failed_paths, ok\n";

/* Layer whose printing or cutting height equals z (within 1e-6 mm). */
static long layer_at(const amp_slices *sl, double z)
{
    size_t i;
    for (i = 0; i < sl->nlayers; i++)
        if (fabs(sl->layers[i].z_print - z) < 1e-6 || fabs(sl->layers[i].z_cut - z) < 1e-6)
            return (long)i;
    return -1;
}

int check_stroke(int argc, char **argv)
{
    double layer = 0, first = 0, tol = 1e-6;
    int json = 0, npos = 0, rc;
    const char *pos[1], *mesh = NULL;
    amp_pathset ps;
    amp_mesh m;
    amp_slices sl;
    size_t i, segs = 0, cross = 0, reps = 0, outside = 0, failed = 0, nolayer = 0, flipped;
    cli_opt opts[] = {{"mesh", CLI_STR, &mesh, 0},      {"layer", CLI_DOUBLE, &layer, 0},
                      {"first-layer", CLI_DOUBLE, &first, 0}, {"tol", CLI_DOUBLE, &tol, 0},
                      {"json", CLI_FLAG, &json, 0},     {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("check", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (mesh && !opts[1].seen)
        return cli_fail("check", CLI_USAGE, "--mesh needs the --layer height used for slicing");
    if (!(tol >= 0) || !isfinite(tol))
        return cli_fail("check", CLI_USAGE, "--tol must be >= 0");
    amp_pathset_init(&ps, NULL);
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    rc = cli_load_paths("check", pos[0], &ps);
    if (rc == CLI_OK && mesh)
        rc = slicetool_load("check", mesh, layer, first, &m, &sl, &flipped);
    for (i = 0; i < ps.npaths && rc == CLI_OK; i++) {
        const amp_pvert *v = amp_pathset_path_verts(&ps, i);
        amp_stroke_report rep;
        const amp_polyset *region = NULL;
        amp_status st;
        if (mesh && ps.paths[i].n) {
            long li = layer_at(&sl, v[0].p.z);
            if (li < 0)
                nolayer++;
            else
                region = &sl.layers[li].polys;
        }
        st = amp_pathset_stroke_check(&ps, i, region, tol, &rep, NULL);
        if (st == AMP_ERR_NOMEM) {
            rc = cli_fail("check", CLI_USAGE, "out of memory");
            break;
        }
        failed += st != AMP_OK;
        segs += rep.segments;
        cross += rep.crossings;
        reps += rep.repeated_edges;
        outside += rep.outside;
    }
    if (rc == CLI_OK) {
        int ok = failed == 0 && nolayer == 0;
        if (json) {
            cli_json j;
            cli_json_begin(&j, stdout);
            cli_json_int(&j, "paths", (long long)ps.npaths);
            cli_json_int(&j, "segments", (long long)segs);
            cli_json_int(&j, "crossings", (long long)cross);
            cli_json_int(&j, "repeated_edges", (long long)reps);
            cli_json_int(&j, "outside", (long long)outside);
            cli_json_int(&j, "paths_without_layer", (long long)nolayer);
            cli_json_int(&j, "failed_paths", (long long)failed);
            cli_json_bool(&j, "ok", ok);
            cli_json_end(&j);
        } else
            printf("%s: %lu paths, %lu crossings, %lu edges printed twice, %lu points outside%s: %s\n", pos[0],
                   (unsigned long)ps.npaths, (unsigned long)cross, (unsigned long)reps, (unsigned long)outside,
                   nolayer ? " (some paths match no layer)" : "", ok ? "ok" : "FAILED");
        if (!ok) {
            if (!json)
                fprintf(stderr, "ampath check: %lu of %lu paths fail the stroke check\n", (unsigned long)failed,
                        (unsigned long)ps.npaths);
            rc = CLI_FAILED;
        }
    }
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
    return rc;
}
