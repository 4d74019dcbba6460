/* ampath check for continuous strokes ([P2 §4]): independent verification
 * with amp_check_stroke(). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkers.h"
#include "slicetool.h"

/* Layer whose printing or cutting height equals z (within 1e-6 mm). */
static long layer_at(const amp_slices *sl, double z)
{
    size_t i;
    for (i = 0; i < sl->nlayers; i++)
        if (fabs(sl->layers[i].z_print - z) < 1e-6 || fabs(sl->layers[i].z_cut - z) < 1e-6)
            return (long)i;
    return -1;
}

/* A path on one height: a layer's stroke or a flat support row (a path that climbs is a volumetric path, not
 * checked here). */
static int is_planar(const amp_pathset *ps, size_t i)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    size_t k, n = ps->paths[i].n;
    for (k = 1; k < n; k++)
        if (fabs(v[k].p.z - v[0].p.z) > 1e-9)
            return 0;
    return n > 0;
}

/* A layer's stroke: a planar object path. Support paths (`ampath support` under a sliced job's overhangs,
 * Remark 2.1's stretches) are checked for crossings like the strokes, but lie outside the section by design
 * and print no layer of the part. */
static int is_stroke(const amp_pathset *ps, size_t i)
{
    return ps->paths[i].role == AMP_ROLE_OBJECT && is_planar(ps, i);
}

/* Is some island of section @p P printable by a bead of half-width @p r: 1e-3 mm2 or more (the slicer prints even a
 * cone's tip), a box diagonal of r/2 or more, and a mean half-width (area / boundary length) of r/16 or more? A sliver
 * thinner than r/8 (a sphere's top ring cut around a hole, 4 micrometres wide) or a speck under a quarter bead
 * across has no centre line a bead could follow: no slicer prints it. */
static int printable_section(const amp_polyset *P, double r)
{
    size_t k, i, q;
    for (k = 0; k < P->nislands; k++) {
        double area = 0, len = 0, x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
        for (i = 0; i < P->nrings; i++) {
            const amp_vec2 *p = amp_polyset_ring(P, i);
            size_t n = P->rings[i].n;
            if (P->rings[i].island != (long)k)
                continue;
            area += amp_ring_area(p, n);
            for (q = 0; q < n; q++) {
                len += hypot(p[(q + 1) % n].x - p[q].x, p[(q + 1) % n].y - p[q].y);
                x0 = fmin(x0, p[q].x);
                x1 = fmax(x1, p[q].x);
                y0 = fmin(y0, p[q].y);
                y1 = fmax(y1, p[q].y);
            }
        }
        if (area >= 1e-3 && hypot(x1 - x0, y1 - y0) >= 0.5 * r && area >= len * r / 16)
            return 1;
    }
    return 0;
}

/* Layers of the mesh with a printable section (printable_section, for the widest bead of the file's planar paths)
 * but no planar path at their height: a layer left out lays everything above it one layer too high. */
static size_t layers_without_paths(const amp_slices *sl, const amp_pathset *ps)
{
    size_t li, i, k, missing = 0;
    double r = 0;
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        if (is_stroke(ps, i))
            for (k = 0; k < ps->paths[i].n; k++)
                r = fmax(r, v[k].r);
    }
    for (li = 0; li < sl->nlayers; li++) {
        int found = 0;
        if (!printable_section(&sl->layers[li].polys, r))
            continue;
        for (i = 0; i < ps->npaths && !found; i++) {
            const amp_pvert *v = amp_pathset_path_verts(ps, i);
            found = is_stroke(ps, i) && layer_at(sl, v[0].p.z) == (long)li;
        }
        missing += !found;
    }
    return missing;
}

int check_stroke(const check_ctx *c, cli_json *j)
{
    int rc = CLI_OK;
    const amp_pathset *ps = c->ps;
    const char *mesh = c->layer_given ? c->mesh : NULL;
    amp_mesh m;
    amp_slices sl;
    size_t i, segs = 0, pseudo = 0, cross = 0, reps = 0, outside = 0, failed = 0, nolayer = 0, flipped, planar = 0;
    size_t strokes = 0;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    for (i = 0; i < ps->npaths; i++) {
        planar += is_planar(ps, i);
        strokes += is_stroke(ps, i);
    }
    if (strokes == 0 && mesh) {
        if (j) {
            cli_json_bool(j, "ran", 1);
            cli_json_bool(j, "ok", 0);
            cli_json_str(j, "reason", "no planar paths: nothing prints the layers of the mesh");
        } else {
            fprintf(c->out, "strokes: no planar paths: nothing prints the layers of the mesh: FAILED\n");
        }
        fprintf(stderr, "ampath check: no planar paths to print the layers of %s\n", mesh);
        return CLI_FAILED;
    }
    if (planar == 0) {
        if (j) {
            cli_json_bool(j, "ran", 0);
            cli_json_str(j, "reason", "no planar paths");
        } else {
            fprintf(c->out, "strokes: not run (no planar paths)\n");
        }
        return CLI_OK;
    }
    if (mesh)
        rc = slicetool_load("check", mesh, c->layer, c->first_layer, &m, &sl, &flipped);
    for (i = 0; i < ps->npaths && rc == CLI_OK; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        amp_stroke_report rep;
        const amp_polyset *region = NULL;
        amp_status st;
        if (!is_planar(ps, i))
            continue;
        if (mesh && is_stroke(ps, i)) {
            long li = layer_at(&sl, v[0].p.z);
            if (li < 0)
                nolayer++;
            else
                region = &sl.layers[li].polys;
        }
        st = amp_check_path_stroke(ps, i, region, c->tol, &rep, NULL);
        if (st == AMP_ERR_NOMEM) {
            rc = cli_fail("check", CLI_USAGE, "out of memory");
            break;
        }
        failed += st != AMP_OK;
        segs += rep.segments;
        pseudo += rep.pseudo;
        cross += rep.crossings;
        reps += rep.repeated_edges;
        outside += rep.outside;
    }
    if (rc == CLI_OK) {
        size_t missing = mesh ? layers_without_paths(&sl, ps) : 0;
        int ok = failed == 0 && nolayer == 0 && missing == 0;
        if (j) {
            cli_json_bool(j, "ran", 1);
            cli_json_bool(j, "ok", ok);
            cli_json_int(j, "paths", (long long)planar);
            cli_json_int(j, "segments", (long long)segs);
            cli_json_int(j, "pseudo_segments", (long long)pseudo);
            cli_json_int(j, "crossings", (long long)cross);
            cli_json_int(j, "repeated_edges", (long long)reps);
            cli_json_int(j, "outside", (long long)outside);
            cli_json_int(j, "paths_without_layer", (long long)nolayer);
            cli_json_int(j, "layers_without_paths", (long long)missing);
            cli_json_int(j, "failed_paths", (long long)failed);
        } else {
            fprintf(c->out, "strokes: %lu planar paths, %lu crossings, %lu edges printed twice, %lu points outside%s%s: %s\n",
                   (unsigned long)planar, (unsigned long)cross, (unsigned long)reps, (unsigned long)outside,
                   nolayer ? " (some paths match no layer)" : "", missing ? " (some layers have no path)" : "",
                   ok ? "ok" : "FAILED");
        }
        if (!ok && (failed || nolayer))
            fprintf(stderr, "ampath check: %lu of %lu planar paths fail the stroke check%s\n", (unsigned long)failed,
                    (unsigned long)planar, nolayer ? " or match no layer" : "");
        if (missing)
            fprintf(stderr, "ampath check: %lu layers of the mesh have a section but no path\n",
                    (unsigned long)missing);
        if (!ok)
            rc = CLI_FAILED;
    }
    amp_slices_free(&sl);
    amp_mesh_free(&m);
    return rc;
}
