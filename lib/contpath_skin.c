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

/* Does the window of layers around li reach the bed or the top (every point of the layer uncovered)? */
static int window_open(const amp_slices *sl, size_t li, double below, double above)
{
    double z = sl->layers[li].z_print;
    return (below > 0 && (li == 0 || z - sl->layers[0].z_print < below - 1e-9)) ||
           (above > 0 && (li + 1 == sl->nlayers || sl->layers[sl->nlayers - 1].z_print - z < above - 1e-9));
}

/* Is q covered by the sections of every layer within [z - below, z + above], ends included (other than the
 * layer itself)? Layers beyond the part's ends do not cover. A face exposed under layer k (k - 1 lacks it)
 * makes k .. k + 3 solid at 0.8 mm of 0.2 mm layers, as the bed makes layers 0 .. 3: layer k + 3 must still
 * see k - 1, 0.8 mm below it (with the ends left out such skins were 0.6 mm thick; an independent coverage
 * measure found them). */
static int covered(const amp_slices *sl, const amp_polyindex *ix, size_t li, amp_vec2 q, double below, double above)
{
    double z = sl->layers[li].z_print;
    size_t j;
    if (window_open(sl, li, below, above))
        return 0; /* the first or last layers: the bed is below, the top above */
    for (j = li; j-- > 0 && z - sl->layers[j].z_print < below + 1e-9;)
        if ((ix ? amp_polyindex_contains(&ix[j], q) : amp_polyset_contains(&sl->layers[j].polys, q, 0.0)) != 1)
            return 0;
    for (j = li + 1; j < sl->nlayers && sl->layers[j].z_print - z < above + 1e-9; j++)
        if ((ix ? amp_polyindex_contains(&ix[j], q) : amp_polyset_contains(&sl->layers[j].polys, q, 0.0)) != 1)
            return 0;
    return 1;
}

int amp_cp_region_is_skin(const amp_slices *sl, const amp_polyindex *ix, size_t li, const amp_polyset *R, double below,
                          double above, double step)
{
    return amp_cp_region_skin_depth(sl, ix, li, R, below, above, step) >= 0;
}

/* Depth of a point for the band: its distance from R's boundary, negative outside R (1-Lipschitz; the
 * sign lets a segment outside R be dropped at once by its ends' distances instead of bisected). The
 * bisection needs the depth exactly only where it may beat the deepest found: outside R, -min(d, cap)
 * still bounds it from above; inside, a depth under @p cap is exact, and one that reaches it is measured
 * again in full. Each search then ends a few rows of R's index from the point (full searches from every
 * vertex of the neighbouring sections were a third of slicing a 70k-triangle crocodile). */
static double depth_at(const amp_polyindex *rx, amp_vec2 p, double cap)
{
    double d;
    if (amp_polyindex_contains(rx, p) != 1)
        return -amp_polyindex_dist_within(rx, p, cap);
    d = amp_polyindex_dist_within(rx, p, cap);
    return d < cap ? d : amp_polyindex_dist(rx, p);
}

/* The deepest point of segment a-b (depths da, db) into R, into *best, to within @p tol: the depth is
 * 1-Lipschitz along the segment, so a piece whose ends and length cannot beat *best by more than tol is
 * not split further. *inside = 1 once a point inside R is met. */
static void seg_depth(const amp_polyindex *rx, amp_vec2 a, amp_vec2 b, double da, double db, double tol, int lvl,
                      double *best, int *inside)
{
    double dx = b.x - a.x, dy = b.y - a.y, len = sqrt(dx * dx + dy * dy), dm;
    amp_vec2 m;
    if (da > 0.0 || db > 0.0)
        *inside = 1;
    *best = fmax(*best, fmax(da, db));
    if (0.5 * (da + db + len) <= *best + tol || lvl >= 48)
        return;
    m = amp_v2(0.5 * (a.x + b.x), 0.5 * (a.y + b.y));
    dm = depth_at(rx, m, *best + len + tol);
    seg_depth(rx, a, m, da, dm, tol, lvl + 1, best, inside);
    seg_depth(rx, m, b, dm, db, tol, lvl + 1, best, inside);
}

/* How deep the edges of layer j's section reach into R (box x0, y0, x1, y1), to within tol; 0 when none
 * enters. Ring by ring, so that an edge's end is the next edge's start and its depth is measured once (as
 * many depths as vertices in R's box: two per edge from the rows of the section's index were a third of
 * slicing a 70k-triangle crocodile); an edge outside the box is passed over with a few comparisons. */
static double layer_depth(const amp_slices *sl, size_t j, const amp_polyindex *rx, const double box[4], double tol,
                          int *inside)
{
    const amp_polyset *P = &sl->layers[j].polys;
    double best = 0.0;
    size_t r, k;
    *inside = 0;
    for (r = 0; r < P->nrings; r++) {
        const amp_vec2 *p = amp_polyset_ring(P, r);
        size_t n = P->rings[r].n, have = (size_t)-1;
        double da = 0.0;
        int exact = 0; /* da is a's depth (else only a bound of it, from the edge before) */
        for (k = 0; k < n; k++) {
            amp_vec2 a = p[k], b = p[(k + 1) % n];
            double len, cap, db;
            if (fmax(a.x, b.x) < box[0] || fmin(a.x, b.x) > box[2] || fmax(a.y, b.y) < box[1] ||
                fmin(a.y, b.y) > box[3])
                continue;
            len = hypot(b.x - a.x, b.y - a.y);
            if (have == k && *inside && da + len <= best + tol) {
                /* no point of the edge can beat the deepest (1-Lipschitz from a): b's depth is not measured,
                 * its bound carried on (most edges of a section beside R's boundary end here); only once the
                 * section is known to enter R (edge_depth's test of a section that misses R needs that) */
                da += len;
                exact = 0;
                have = k + 1;
                continue;
            }
            cap = best + len + tol;
            if (have != k || !exact) /* the depth at a, unless the edge before measured it */
                da = depth_at(rx, a, cap);
            db = depth_at(rx, b, cap);
            seg_depth(rx, a, b, da, db, tol, 0, &best, inside);
            da = db;
            exact = 1;
            have = k + 1;
        }
    }
    return best;
}

/*
 * How deep the uncovered points reach from the neighbours' sections: an
 * uncovered point is outside some section L_j of the window, so the
 * uncovered set's boundary inside R lies on the edges of those sections,
 * and its deepest point is on them (or at a deeper point inside it, which
 * the caller's grid looks for). -1 when a section of the window has no edge
 * in R and leaves @p in (a point of R) outside: R is uncovered whole.
 */
static double edge_depth(const amp_slices *sl, const amp_polyindex *ix, size_t li, const amp_polyindex *rx,
                         const double box[4], amp_vec2 in, double below, double above, double tol)
{
    double z = sl->layers[li].z_print, best = 0.0;
    size_t lo = li, hi = li + 1, j;
    /* the window as covered() walks it: down while within below, up while within above */
    while (lo > 0 && z - sl->layers[lo - 1].z_print < below + 1e-9)
        lo--;
    while (hi < sl->nlayers && sl->layers[hi].z_print - z < above + 1e-9)
        hi++;
    for (j = lo; j < hi; j++) {
        double d;
        int inside;
        if (j == li)
            continue;
        d = layer_depth(sl, j, rx, box, tol, &inside);
        if (!inside && (ix ? amp_polyindex_contains(&ix[j], in) : amp_polyset_contains(&sl->layers[j].polys, in, 0.0)) != 1)
            return -1;
        best = fmax(best, d);
    }
    return best;
}

double amp_cp_region_skin_depth(const amp_slices *sl, const amp_polyindex *ix, size_t li, const amp_polyset *R,
                                double below, double above, double step)
{
    double depth = -1, deep = -1, band, tol, box[4];
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, x, y, step0 = step;
    size_t r, k;
    amp_polyindex rx;
    amp_vec2 in;
    int have;
    if (!(below > 0) && !(above > 0))
        return -1;
    if (R->nrings == 0)
        return -1;
    in = amp_polyset_ring(R, 0)[0];
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
    /* next to the bed or the top every point is uncovered: the whole region is solid */
    if (window_open(sl, li, below, above))
        return fmax(x1 - x0, y1 - y0) + step;
    /* a grid inside: a hole opening above the middle of the region (at
     * most about 16 x 16 points: the cost stays linear in the part); R's
     * row index answers them (a full scan of R per point was 8 % of a
     * 100k-triangle torus's slice), the full scans only if it cannot be made */
    step = fmax(step, fmax(x1 - x0, y1 - y0) / 16);
    have = amp_polyindex_build(&rx, R, NULL) == AMP_OK;
    for (y = y0 + 0.5 * step; y < y1; y += step)
        for (x = x0 + 0.5 * step; x < x1; x += step) {
            amp_vec2 q = amp_v2(x, y);
            int inr = have ? amp_polyindex_contains(&rx, q) : amp_polyset_contains(R, q, 0.0);
            if (inr == 1) {
                double d = have ? amp_polyindex_dist(&rx, q) : amp_polyset_boundary_dist(R, q);
                in = q;
                if (!covered(sl, ix, li, q, below, above))
                    deep = fmax(deep, d);
            }
        }
    if (!have) /* no index: the coarse answer (a sample stands for the cell of `step` around it) */
        return fmax(depth, deep) < 0 ? -1 : fmax(depth, deep) + step;
    /* the band as deep as the uncovered points reach, measured on the neighbours' edges (a sampled depth
     * plus the grid's spacing made a band 6 mm wide on a 100 mm part whose slopes leave a rim of 1 mm) */
    box[0] = x0;
    box[1] = y0;
    box[2] = x1;
    box[3] = y1;
    tol = 0.25 * step0;
    /* a region whose samples are all covered is no skin region (the edges are not scanned: that was half of
     * slicing a 70k-triangle crocodile, most of whose regions are covered) */
    if (depth < 0 && deep < 0) {
        amp_polyindex_free(&rx);
        return -1;
    }
    band = edge_depth(sl, ix, li, &rx, box, in, below, above, tol);
    amp_polyindex_free(&rx);
    if (band < 0) /* a section of the window misses R whole */
        return fmax(x1 - x0, y1 - y0) + step;
    /* an uncovered grid sample deeper than every edge: a hole opening above the middle; a sample stands for
     * the cell of `step` around it */
    if (deep > band)
        return deep + step;
    return fmax(band + tol, step0);
}
