/* Shared steps of `ampath slice` and `ampath euler`. */
#include <math.h>

#include "slicetool.h"

/* Work before slicing: every triangle gives one section segment per layer plane
 * it spans, and every layer costs a little on its own, so layers + the sum over triangles of
 * (z extent / H + 1) bounds the segments the slicer will store. */
double slicetool_estimate(const amp_mesh *m, double layer)
{
    amp_box3 b = amp_mesh_bbox(m);
    double total = (b.max.z - b.min.z) / layer + 1;
    size_t t;
    for (t = 0; t < m->ntris; t++) {
        double z0 = m->verts[m->tris[t].v[0]].z, z1 = m->verts[m->tris[t].v[1]].z, z2 = m->verts[m->tris[t].v[2]].z;
        total += (fmax(z0, fmax(z1, z2)) - fmin(z0, fmin(z1, z2))) / layer + 1;
    }
    return total;
}

amp_status slicetool_outward(amp_mesh *m, size_t *flipped, amp_error *err)
{
    size_t i, n = 0;
    amp_status st = amp_mesh_orient(m, &n, err);
    if (st != AMP_OK)
        return st;
    /* consistent now, but all of it may face inward (an STL written with
     * the other winding): then the inside tests see no solid at all */
    if (amp_mesh_volume(m) < 0) {
        for (i = 0; i < m->ntris; i++) {
            uint32_t t = m->tris[i].v[1];
            m->tris[i].v[1] = m->tris[i].v[2];
            m->tris[i].v[2] = t;
        }
        n = m->ntris - n;
    }
    if (flipped)
        *flipped = n;
    return AMP_OK;
}

/* A mesh with no section at all (flat, or far below one layer: a part
 * exported in metres or inches) is refused with its size, not sliced into
 * an empty job or met later as "no layer polygon". */
static int slicetool_nonempty(const char *cmd, const amp_mesh *m, const amp_slices *sl, double layer)
{
    size_t i;
    amp_box3 b = amp_mesh_bbox(m);
    for (i = 0; i < sl->nlayers; i++)
        if (sl->layers[i].polys.nrings) {
            /* as PrusaSlicer asks on loading: a part under 3 mm every way is likely in inches (or cm) */
            if (b.max.x - b.min.x < 3 && b.max.y - b.min.y < 3 && b.max.z - b.min.z < 3)
                fprintf(stderr,
                        "ampath %s: warning: the part is only %.3g x %.3g x %.3g mm: a model made in inches must be "
                        "scaled by 25.4 (in centimetres, by 10) before slicing\n",
                        cmd, b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z);
            return CLI_OK;
        }
    return cli_fail(cmd, CLI_USAGE,
                    "the mesh gives no layer: it is %.4g x %.4g x %.4g mm, %s layer of %g mm (a part in metres "
                    "or inches must be scaled to millimetres)",
                    b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z,
                    b.max.z - b.min.z < 0.5 * layer ? "lower than half a" : "with no closed section in any",
                    layer);
}

int slicetool_load(const char *cmd, const char *file, double layer, double first, amp_mesh *m, amp_slices *sl,
                   size_t *flipped)
{
    amp_error err;
    amp_slice_opts o;
    amp_error_clear(&err);
    if (!(layer > 0) || !isfinite(layer))
        return cli_fail(cmd, CLI_USAGE, "--layer must be a positive height in mm");
    if (first < 0 || !isfinite(first))
        return cli_fail(cmd, CLI_USAGE, "--first-layer must be a positive height in mm");
    if (amp_mesh_read_stl_file(m, file, &err) != AMP_OK)
        return cli_fail_err(cmd, &err);
    if (slicetool_estimate(m, layer) > cli_work.max_segments)
        return cli_work_refuse(cmd, "section segments", slicetool_estimate(m, layer), cli_work.max_segments,
                               "max-segments");
    /* the slicer chains segments by their direction: orientation must agree */
    if (slicetool_outward(m, flipped, &err) != AMP_OK)
        return cli_fail_err(cmd, &err);
    o.layer = layer;
    o.first_layer = first;
    if (amp_slice_mesh(m, &o, sl, &err) != AMP_OK)
        return cli_fail_err(cmd, &err);
    return slicetool_nonempty(cmd, m, sl, layer);
}

long slicetool_pick(const char *cmd, const amp_slices *sl, long index, int have_z, double z)
{
    size_t i, best = 0;
    if (sl->nlayers == 0) {
        cli_fail(cmd, CLI_USAGE, "the mesh gives no layer");
        return -1;
    }
    if (index >= 0) {
        if ((size_t)index >= sl->nlayers) {
            cli_fail(cmd, CLI_USAGE, "--layer-index %ld out of range (0..%lu)", index, (unsigned long)sl->nlayers - 1);
            return -1;
        }
        return index;
    }
    if (!have_z)
        return (long)(sl->nlayers / 2);
    for (i = 1; i < sl->nlayers; i++)
        if (fabs(sl->layers[i].z_cut - z) < fabs(sl->layers[best].z_cut - z))
            best = i;
    return (long)best;
}

int slicetool_bbox(const amp_slices *sl, double *x0, double *y0, double *x1, double *y1)
{
    size_t i, k;
    int any = 0;
    *x0 = *y0 = HUGE_VAL;
    *x1 = *y1 = -HUGE_VAL;
    for (i = 0; i < sl->nlayers; i++)
        for (k = 0; k < sl->layers[i].polys.npts; k++) {
            amp_vec2 p = sl->layers[i].polys.pts[k];
            *x0 = fmin(*x0, p.x);
            *y0 = fmin(*y0, p.y);
            *x1 = fmax(*x1, p.x);
            *y1 = fmax(*y1, p.y);
            any = 1;
        }
    return any;
}
