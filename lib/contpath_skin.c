/* Solid skins (beyond the paper: a sparse lattice alone leaves top and
 * bottom surfaces open): a region of a layer is printed
 * solid — with a second Euler lattice K̂_s whose cell is small enough that
 * its beads touch (square cell 4r, offset r: Class 2 strips 2r wide, Class
 * 1 and 3 cells 2r across, every bead covering r to each side) — when some
 * point of it has no part within the bottom skin thickness below it or the
 * top skin thickness above it (a downward- or upward-facing surface is
 * near). The same clipping, patching and tour give one stroke per region,
 * so the island keeps one stroke. Without polygon booleans the whole region
 * is solid when any of its sample points (its ring vertices and a grid
 * inside it) is uncovered: at worst more solid infill than a slicer's. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

/* Is q covered by the sections of every layer within [z - below, z + above]
 * (other than the layer itself)? Layers beyond the part's ends do not cover. */
static int covered(const amp_slices *sl, const amp_polyindex *ix, size_t li, amp_vec2 q, double below, double above)
{
    double z = sl->layers[li].z_print;
    size_t j;
    if (below > 0 && (li == 0 || z - sl->layers[0].z_print < below - 1e-9))
        return 0; /* the first layers: the bed is below */
    if (above > 0 && (li + 1 == sl->nlayers || sl->layers[sl->nlayers - 1].z_print - z < above - 1e-9))
        return 0; /* the last layers: the top is above */
    for (j = li; j-- > 0 && z - sl->layers[j].z_print < below - 1e-9;)
        if ((ix ? amp_polyindex_contains(&ix[j], q) : amp_polyset_contains(&sl->layers[j].polys, q, 0.0)) != 1)
            return 0;
    for (j = li + 1; j < sl->nlayers && sl->layers[j].z_print - z < above - 1e-9; j++)
        if ((ix ? amp_polyindex_contains(&ix[j], q) : amp_polyset_contains(&sl->layers[j].polys, q, 0.0)) != 1)
            return 0;
    return 1;
}

int amp_cp_region_is_skin(const amp_slices *sl, const amp_polyindex *ix, size_t li, const amp_polyset *R, double below,
                          double above, double step)
{
    return amp_cp_region_skin_depth(sl, ix, li, R, below, above, step) >= 0;
}

double amp_cp_region_skin_depth(const amp_slices *sl, const amp_polyindex *ix, size_t li, const amp_polyset *R,
                                double below, double above, double step)
{
    double depth = -1;
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, x, y;
    size_t r, k;
    amp_polyindex rx;
    int have;
    if (!(below > 0) && !(above > 0))
        return -1;
    for (r = 0; r < R->nrings; r++) {
        const amp_vec2 *p = amp_polyset_ring(R, r);
        size_t n = R->rings[r].n, stride = n / 64 + 1;
        for (k = 0; k < n; k++) {
            x0 = fmin(x0, p[k].x);
            y0 = fmin(y0, p[k].y);
            x1 = fmax(x1, p[k].x);
            y1 = fmax(y1, p[k].y);
            if (depth < 0 && k % stride == 0 && !covered(sl, ix, li, p[k], below, above))
                depth = 0;
        }
    }
    /* a grid inside: a hole opening above the middle of the region (at
     * most about 16 x 16 points: the cost stays linear in the part); R's
     * row index answers them (a full scan of R per point was 8 % of a
     * 100k-triangle torus's slice), the full scans only if it cannot be made */
    step = fmax(step, fmax(x1 - x0, y1 - y0) / 16);
    have = amp_polyindex_build(&rx, R, NULL) == AMP_OK;
    for (y = y0 + 0.5 * step; y < y1; y += step)
        for (x = x0 + 0.5 * step; x < x1; x += step) {
            amp_vec2 q = amp_v2(x, y);
            int in = have ? amp_polyindex_contains(&rx, q) : amp_polyset_contains(R, q, 0.0);
            if (in == 1 && !covered(sl, ix, li, q, below, above))
                depth = fmax(depth, have ? amp_polyindex_dist(&rx, q) : amp_polyset_boundary_dist(R, q));
        }
    if (have)
        amp_polyindex_free(&rx);
    /* a sample stands for the cell of `step` around it */
    return depth < 0 ? -1 : depth + step;
}
