/* All layers: islands in print order, perimeters (thin islands included),
 * regions, one stroke per island, bead heights, stroke starts
 * ([P2 §2.2]; print-ready G-code and fewer starts than a slicer). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"
#ifdef _OPENMP
#include <omp.h>
#endif
#include "numtext.h"

/* Work state of amp_contpath_layers(): the lattices and indexes (shared, read-only once built), one
 * island's scratch (isl .. bare_skin: a work context per thread, workers_new) and the print order of the
 * islands (at, have_at, done: the calling thread's context only). */
typedef struct lctx {
    const amp_slices *sl;
    const amp_contpath_opts *o;
    amp_cx2 khat, kskin[2]; /* sparse infill; solid skins along x (even layers) and y (odd) */
    uint64_t *ke, *kse[2];
    size_t nke, nkse[2];
    int skins;
    amp_polyindex *lix; /* row index of every layer's section (skin tests) */
    amp_polyset isl, ins, reg;
    amp_polyset bin, core, band, reg2; /* a skin band split off a region (skin_band) */
    int no_bands;                      /* 1: skin regions whole (an island printed again) */
    double reg_shift;                  /* extra inset of R̃ (mm; +-r/20 when an island is printed again) */
    double perim_in;                   /* perimeter this much nearer the boundary than r (r/16 on a last retry) */
    amp_pathset tmp;  /* one island's paths before joining */
    amp_pathset bare; /* one island's unprinted ring stretches (step 6) */
    amp_pathset bare_skin; /* those of its solid regions */
    amp_pathset retry;     /* an island made again (shift_retry) */
    amp_vec2 at;     /* where the nozzle is (end of the last stroke) */
    int have_at;
    unsigned char *done; /* islands of the layer already printed */
    size_t cap_done;
} lctx;

/* Closed path @p k of @p ps (last vertex = first) is rotated to start at
 * its vertex nearest to @p q among those whose two segments are printed, so
 * that the stroke begins where the nozzle is (less travel between strokes);
 * an open one is reversed when its end is the nearer. */
static amp_status rotate_to(amp_pathset *ps, size_t k, amp_vec2 q, amp_error *err)
{
    amp_pvert *v = amp_pathset_path_verts(ps, k), *w;
    size_t n = ps->paths[k].n, i, best = 0;
    double bd = HUGE_VAL;
    if (n >= 2 && (v[0].p.x != v[n - 1].p.x || v[0].p.y != v[n - 1].p.y) &&
        hypot(v[n - 1].p.x - q.x, v[n - 1].p.y - q.y) < hypot(v[0].p.x - q.x, v[0].p.y - q.y)) {
        /* an open path (a thin wall) starts at its end nearer to q */
        for (i = 0; i < n / 2; i++) {
            amp_pvert t = v[i];
            v[i] = v[n - 1 - i];
            v[n - 1 - i] = t;
        }
        return AMP_OK;
    }
    if (n < 4 || v[0].p.x != v[n - 1].p.x || v[0].p.y != v[n - 1].p.y || v[0].r != v[n - 1].r)
        return AMP_OK;
    for (i = 0; i + 1 < n; i++) {
        size_t prev = i ? i - 1 : n - 2;
        double d = hypot(v[i].p.x - q.x, v[i].p.y - q.y);
        if (d < bd && v[i].r > 0 && v[prev].r > 0 && v[i + 1].r > 0) {
            bd = d;
            best = i;
        }
    }
    if (best == 0)
        return AMP_OK;
    w = amp_alloc(ps->alloc, n * sizeof *w);
    if (!w)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory ordering the strokes");
    memcpy(w, v + best, (n - 1 - best) * sizeof *w);
    memcpy(w + (n - 1 - best), v, (best + 1) * sizeof *w);
    memcpy(v, w, n * sizeof *w);
    amp_free(ps->alloc, w);
    return AMP_OK;
}

/* Paths [first, npaths) of @p ps (the last ones) lose the vertices closer
 * than @p tol to the last kept one (same radius): micro-segments from
 * splices and swallowtail remnants, below a motor step, would be written as
 * moves without extrusion. A radius change (a pseudo edge's doubled vertex)
 * stays; the last vertex of a path stays (closure); a needle A-B-A left by
 * the merging loses its tip. Where a pseudo run ends, the joint (the vertex
 * doubled with the printed radius) is kept rather than the vertex before
 * it: the run back over a printed edge must end on the very vertex the
 * printed copy kept, or the two copies interleave there (a crossing found
 * on the helix with --no-join). Paths left without
 * length are removed. */
static void compact_tail(amp_pathset *ps, size_t first, double tol)
{
    size_t i, w = first < ps->npaths ? ps->paths[first].first : ps->nverts, np = first;
    for (i = first; i < ps->npaths; i++) {
        amp_pvert *v = ps->verts + ps->paths[i].first;
        size_t n = ps->paths[i].n, k, m = 0, start = w;
        double len = 0;
        for (k = 0; k < n; k++) {
            amp_pvert x = v[k];
            if (m > 0) {
                amp_pvert *last = &ps->verts[w - 1];
                double d = amp_v3_dist(x.p, last->p);
                if (d < tol && x.r == last->r) {
                    int joint = k + 1 < n && v[k + 1].r != x.r, last_joint = m > 1 && ps->verts[w - 2].r != last->r;
                    if ((k + 1 == n && m > 1) || (joint && !last_joint))
                        *last = x; /* keep the closing vertex, or the joint where printing resumes */
                    else if (joint)
                        goto keep; /* a pseudo run shorter than tol keeps both its joints */
                    continue;
                }
                if (m > 1 && k + 1 < n && amp_v3_dist(x.p, ps->verts[w - 2].p) < tol && x.r == ps->verts[w - 2].r &&
                    last->r == x.r) {
                    w--; /* A -> B -> A: the tip B of a needle goes */
                    m--;
                    continue;
                }
            keep:
                len += d;
            }
            ps->verts[w++] = x;
            m++;
        }
        if (m < 2 || !(len > 0)) {
            w = start; /* nothing left to print */
            continue;
        }
        ps->paths[np] = ps->paths[i];
        ps->paths[np].first = start;
        ps->paths[np].n = m;
        np++;
    }
    ps->npaths = np;
    ps->nverts = w;
}

/* Closed paths of every ring of @p P at height z, radius r, into c->tmp. */
/* Ring p[0..n-1] as one closed perimeter loop at height z into c->tmp. */
static amp_status loop_path(lctx *c, const amp_vec2 *p, size_t n, double z, amp_contpath_stats *s0, amp_error *err)
{
    size_t q;
    amp_status rc = amp_pathset_begin(&c->tmp, AMP_ROLE_OBJECT, err);
    for (q = 0; q <= n && rc == AMP_OK; q++)
        rc = amp_pathset_push(&c->tmp, amp_v3(p[q % n].x, p[q % n].y, z), c->o->radius, err);
    s0->perimeter_loops++;
    return rc;
}

static amp_status ring_paths(lctx *c, const amp_polyset *P, double z, amp_contpath_stats *s0, amp_error *err)
{
    size_t r;
    amp_status rc = AMP_OK;
    for (r = 0; r < P->nrings && rc == AMP_OK; r++)
        rc = loop_path(c, amp_polyset_ring(P, r), P->rings[r].n, z, s0, err);
    return rc;
}

/* The perimeters of a thin island (rings of its inset by d < r). A ring whose
 * two sides lie closer than r/4 (its mean width 2 area / length) would be a
 * loop printed there and back over the same line, the second pass on the
 * first (an OpenSCAD part's sliver 0.23 mm wide, 12 mm long: after the merge
 * of points within a micrometre, A-B-A, an edge printed twice): it is printed
 * once, from one end to the other along one side, as slicers print a thin
 * wall. A ring under r/2 long stays a loop (a speck, for the join's rule). */
static amp_status thin_ring_paths(lctx *c, const amp_polyset *P, double z, amp_contpath_stats *s0, amp_error *err)
{
    size_t r, q, a, b;
    amp_status rc = AMP_OK;
    for (r = 0; r < P->nrings && rc == AMP_OK; r++) {
        const amp_vec2 *p = amp_polyset_ring(P, r);
        size_t n = P->rings[r].n;
        double len = 0.0, da = -1.0, db = -1.0, d;
        for (q = 0; q < n; q++)
            len += hypot(p[(q + 1) % n].x - p[q].x, p[(q + 1) % n].y - p[q].y);
        if (!(2.0 * fabs(amp_ring_area(p, n)) < 0.25 * c->o->radius * len) || len < c->o->radius) {
            rc = loop_path(c, p, n, z, s0, err);
            continue;
        }
        /* its ends: the vertex farthest from the first, and the one farthest from that */
        for (q = 0, a = 0; q < n; q++)
            if ((d = hypot(p[q].x - p[0].x, p[q].y - p[0].y)) > da) {
                da = d;
                a = q;
            }
        for (q = 0, b = a; q < n; q++)
            if ((d = hypot(p[q].x - p[a].x, p[q].y - p[a].y)) > db) {
                db = d;
                b = q;
            }
        rc = amp_pathset_begin(&c->tmp, AMP_ROLE_OBJECT, err);
        for (q = a; rc == AMP_OK; q = (q + 1) % n) {
            rc = amp_pathset_push(&c->tmp, amp_v3(p[q].x, p[q].y, z), c->o->radius, err);
            if (q == b)
                break;
        }
        s0->perimeter_loops++;
    }
    return rc;
}

/* An island with infill whose inset by r falls apart into lobes joined by
 * necks narrower than a bead (a lobe each would be a stroke each, one
 * more extrusion start, and the neck would stay bare). Its perimeter is taken at the
 * largest offset d < r (bisection between r/32 and r, to 1/64 r) at which the
 * inset holds it in the fewest pieces; the loop then runs up one side of
 * the neck and back down the other, printing it, and joins the lobes in one
 * stroke. The whole island's paths move out by r - d (R̃ at d + 2r, so the
 * perimeter keeps its bead's distance to the infill); the bead overhangs the
 * section by r - d on that island only. c->ins receives the inset at d.
 * *dp = r when no smaller offset has fewer pieces. */
static amp_status neck_offset(lctx *c, double *dp, amp_error *err)
{
    double r = c->o->radius, lo = r / 32, hi = r;
    size_t n_r = c->ins.nislands, n_lo, k;
    amp_status rc = amp_polyset_inset(&c->isl, lo, 0, &c->ins, err);
    *dp = r;
    if (rc != AMP_OK || c->ins.nrings == 0 || (n_lo = c->ins.nislands) >= n_r)
        return rc == AMP_OK ? amp_polyset_inset(&c->isl, r, 0, &c->ins, err) : rc;
    for (k = 0; k < 6 && rc == AMP_OK; k++) {
        double mid = 0.5 * (lo + hi);
        rc = amp_polyset_inset(&c->isl, mid, 0, &c->ins, err);
        if (rc == AMP_OK && c->ins.nrings && c->ins.nislands <= n_lo)
            lo = mid;
        else
            hi = mid;
    }
    /* back off by twice the bracket: at the last lo the neck may be a hair wide (the ring touches itself;
     * an offset a few 1e-4 mm further splits it, and nearer the split the pieces came and went: a bunny's
     * ear at 26.2 mm wrote a loop whose two sides crossed at the micrometre scale); here the neck is at
     * least four brackets wide, still in the fewest pieces (r/32 was, and fewer is kept) */
    if (rc == AMP_OK && lo - 2 * (hi - lo) > r / 32) {
        rc = amp_polyset_inset(&c->isl, lo - 2 * (hi - lo), 0, &c->ins, err);
        if (rc == AMP_OK && c->ins.nrings && c->ins.nislands <= n_lo)
            lo -= 2 * (hi - lo);
    }
    if (rc == AMP_OK && (rc = amp_polyset_inset(&c->isl, lo, 0, &c->ins, err)) == AMP_OK)
        *dp = lo;
    return rc;
}

/* Steps 5 and §4 for region @p R of layer li, over the skin lattice of the
 * layer's direction or the sparse K̂; its bare stretches kept for step 6. */
static amp_status run_region(lctx *c, size_t li, const amp_polyset *R, int skin, amp_contpath_stats *s0,
                             amp_error *err)
{
    const amp_contpath_opts *o = c->o;
    return amp_cp_region_run(skin ? &c->kskin[li & 1] : &c->khat, skin ? c->kse[li & 1] : c->ke,
                             skin ? c->nkse[li & 1] : c->nke, R, c->sl->layers[li].z_print, o,
                             o->join && o->perimeters, &c->tmp,
                             o->support_corners && !o->support_stretches ? (skin ? &c->bare_skin : &c->bare) : NULL,
                             s0, err);
}

/* Skins only where needed, without polygon booleans (the sparse lattice
 * inside a region keeps the slice fast and light where no skin is due): every
 * uncovered point of region R̃ = c->reg lies within @p w of its boundary
 * (amp_cp_region_skin_depth), so the band R̃ minus its inset by w is solid
 * and the inset by w + 2r (one bead further in, so the two parts' strokes
 * lie side by side like a perimeter and its infill) keeps the sparse
 * lattice. R̃ minus an inset of itself needs no boolean: the inset's rings
 * lie strictly inside at distance w, so the band is R̃'s rings plus the
 * inset's rings reversed, nested again by amp_polyset_organize. c->core
 * is left empty when nothing sparse remains (the whole region is solid:
 * a flat top or bottom, or an uncovered point deep inside) or a piece of
 * it would be smaller than (4r)^2. */
static amp_status skin_band(lctx *c, double w, amp_error *err)
{
    const double r = c->o->radius;
    amp_status rc = amp_polyset_inset(&c->reg, w + 2 * r, 0, &c->core, err);
    size_t k, i;
    if (rc != AMP_OK || c->core.nrings == 0)
        return rc;
    /* a core piece under (4r)^2 would be a loop too small to splice (or a
     * speck left bare inside the band's hole): the region stays whole */
    for (k = 0; k < c->core.nislands; k++) {
        if ((rc = amp_polyset_island(&c->core, k, &c->reg2, err)) != AMP_OK)
            return rc;
        if (amp_polyset_area(&c->reg2) < 16 * r * r) {
            amp_polyset_clear(&c->core);
            return AMP_OK;
        }
    }
    if ((rc = amp_polyset_inset(&c->reg, w, 0, &c->bin, err)) != AMP_OK)
        return rc;
    amp_polyset_clear(&c->band);
    for (k = 0; k < c->reg.nrings && rc == AMP_OK; k++)
        rc = amp_polyset_add(&c->band, amp_polyset_ring(&c->reg, k), c->reg.rings[k].n, err);
    for (k = 0; k < c->bin.nrings && rc == AMP_OK; k++) {
        size_t first = c->band.npts, n = c->bin.rings[k].n;
        rc = amp_polyset_add(&c->band, amp_polyset_ring(&c->bin, k), n, err);
        for (i = 0; rc == AMP_OK && i < n / 2; i++) {
            amp_vec2 t = c->band.pts[first + i];
            c->band.pts[first + i] = c->band.pts[first + n - 1 - i];
            c->band.pts[first + n - 1 - i] = t;
        }
    }
    return rc == AMP_OK ? amp_polyset_organize(&c->band, err) : rc;
}

/* Does every ring of @p P fit in a box of diagonal @p d (a speck for the join, amp_cp_join_loops)? */
static int all_specks(const amp_polyset *P, double d)
{
    size_t i;
    for (i = 0; i < P->nrings; i++) {
        const amp_vec2 *p = amp_polyset_ring(P, i);
        double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
        size_t k;
        for (k = 0; k < P->rings[i].n; k++) {
            x0 = fmin(x0, p[k].x);
            y0 = fmin(y0, p[k].y);
            x1 = fmax(x1, p[k].x);
            y1 = fmax(y1, p[k].y);
        }
        if (!(hypot(x1 - x0, y1 - y0) < d))
            return 0;
    }
    return 1;
}

/* One island (c->isl) of a layer into c->tmp: perimeter loop(s) at r (or,
 * for an island narrower than 2r, at the deepest smaller inset that exists:
 * every island with area is printed) and the strokes of its regions. */
static amp_status island_paths(lctx *c, size_t li, amp_contpath_stats *s0, amp_error *err)
{
    const amp_layer *L = &c->sl->layers[li];
    const amp_contpath_opts *o = c->o;
    double d, dp = o->radius - c->perim_in;
    size_t q, nperim = 0;
    amp_status rc = amp_polyset_inset(&c->isl, dp, 0, &c->ins, err);
    int thin = rc == AMP_OK && (c->ins.nrings == 0 || all_specks(&c->ins, 0.25 * o->radius));
    if (rc == AMP_OK && c->ins.nislands > 1) {
        /* the perimeter falls apart into lobes joined by necks thinner than
         * a bead; without infill (a sliver) the island is treated as thin,
         * so that a smaller inset may hold it in one piece */
        rc = amp_polyset_inset(&c->isl, 3 * o->radius, 0, &c->reg, err);
        thin = rc == AMP_OK && c->reg.nrings == 0;
        if (rc == AMP_OK && !thin && o->perimeters && (rc = neck_offset(c, &dp, err)) == AMP_OK)
            s0->neck_islands += dp < o->radius;
    }
    if (thin) {
        /* thin island: the bead (2r wide) is wider than the part here; its
         * centre line is the inset by the largest d < r that exists and
         * falls apart into the fewest pieces (a wavy sliver splits where it
         * is thinnest; a piece each would be a stroke each) */
        int speck = c->ins.nrings == 0 || all_specks(&c->ins, 0.25 * o->radius);
        double best_d = c->ins.nrings ? dp : 0;
        size_t best_n = c->ins.nrings ? c->ins.nislands : (size_t)-1;
        for (d = 0.5 * o->radius; d >= o->radius / 32 && rc == AMP_OK && (best_n > 1 || speck); d *= 0.5) {
            rc = amp_polyset_inset(&c->isl, d, 0, &c->ins, err);
            if (rc == AMP_OK && c->ins.nrings && (c->ins.nislands < best_n || speck)) {
                /* a loop under r/4 across is a speck the join leaves out (inside the beads
                 * around it): an island whose inset at r is one gets a deeper loop, whole */
                speck = all_specks(&c->ins, 0.25 * o->radius);
                best_n = c->ins.nislands;
                best_d = d;
            }
        }
        if (rc == AMP_OK && best_d > 0 && (rc = amp_polyset_inset(&c->isl, best_d, 0, &c->ins, err)) == AMP_OK) {
            s0->thin_islands += best_d < o->radius;
            return thin_ring_paths(c, &c->ins, L->z_print, s0, err);
        }
        if (rc == AMP_OK)
            s0->dropped_islands++;
        return rc;
    }
    if (rc == AMP_OK && o->perimeters) {
        rc = ring_paths(c, &c->ins, L->z_print, s0, err);
        nperim = c->tmp.npaths;
    }
    amp_pathset_clear(&c->bare);
    amp_pathset_clear(&c->bare_skin);
    /* R̃: inside the perimeter bead (2r) and one bead radius more */
    if (rc == AMP_OK)
        rc = amp_polyset_inset(&c->isl, dp + 2 * o->radius + c->reg_shift, 0, &c->ins, err);
    for (q = 0; q < c->ins.nislands && rc == AMP_OK; q++) {
        int skin;
        double w;
        if ((rc = amp_polyset_island(&c->ins, q, &c->reg, err)) != AMP_OK)
            break;
        /* a speck of R̃ (under a hundredth of a bead's cross-section) is
         * filled by the beads around it */
        if (amp_polyset_area(&c->reg) < 1e-2 * o->radius * o->radius)
            continue;
        /* a solid region gets support corners (step 6) only where no strip
         * runs within r of the ring's unprinted stretch (a strip parallel to
         * the ring up to a bead inside it leaves a sliver that wide bare);
         * elsewhere its strips lie within r of the ring and corners over
         * them would print that plastic twice */
        w = c->skins ? amp_cp_region_skin_depth(c->sl, c->lix, li, &c->reg, o->skin_bottom, o->skin_top,
                                                 4 * o->radius)
                     : -1;
        skin = w >= 0;
        s0->skin_regions += (size_t)skin;
        /* bands need the perimeter to splice the two parts (without it, or
         * without joining, the region stays whole: Fig. 6's joins across
         * a band crossed its strips on the helix) */
        if (skin && o->perimeters && o->join && !c->no_bands && (rc = skin_band(c, w, err)) == AMP_OK &&
            c->core.nrings) {
            /* solid only where needed: the band, then the sparse core */
            size_t k;
            s0->skin_bands++;
            rc = run_region(c, li, &c->band, 1, s0, err);
            for (k = 0; k < c->core.nislands && rc == AMP_OK; k++)
                if ((rc = amp_polyset_island(&c->core, k, &c->reg2, err)) == AMP_OK &&
                    amp_polyset_area(&c->reg2) >= 1e-2 * o->radius * o->radius)
                    rc = run_region(c, li, &c->reg2, 0, s0, err);
        } else if (rc == AMP_OK)
            rc = run_region(c, li, &c->reg, skin, s0, err);
    }
    /* without perimeters, an island too narrow for any infill would stay
     * bare: its perimeter is printed after all (an empty first layer puts
     * the whole part in the air) */
    if (rc == AMP_OK && !o->perimeters && c->tmp.npaths == 0 &&
        (rc = amp_polyset_inset(&c->isl, o->radius, 0, &c->ins, err)) == AMP_OK)
        rc = ring_paths(c, &c->ins, L->z_print, s0, err);
    /* step 6: corners from the bare stretches to the perimeter */
    if (rc == AMP_OK && nperim)
        rc = amp_cp_support_corners(&c->tmp, nperim, &c->bare, o->radius, 0.0, s0, err);
    if (rc == AMP_OK && nperim && c->bare_skin.npaths)
        rc = amp_cp_support_corners(&c->tmp, nperim, &c->bare_skin, o->radius, 0.5 * o->radius, s0, err);
    return rc;
}

/* The unprinted island of layer L nearest to the nozzle (by its outer ring). */
static size_t next_island(const lctx *c, const amp_layer *L)
{
    size_t k, r, i, best = NONE;
    double bd = HUGE_VAL;
    for (r = 0; r < L->polys.nrings; r++) {
        const amp_vec2 *p = amp_polyset_ring(&L->polys, r);
        k = (size_t)L->polys.rings[r].island;
        if (L->polys.rings[r].hole || c->done[k])
            continue;
        if (!c->have_at)
            return k;
        for (i = 0; i < L->polys.rings[r].n; i++) {
            double d = hypot(p[i].x - c->at.x, p[i].y - c->at.y);
            if (d < bd) {
                bd = d;
                best = k;
            }
        }
    }
    return best;
}

/* One layer: its islands nearest first, each joined and started near the nozzle. */
/* Island c->isl of layer li into @p out (paths from @p first on): its
 * paths, joined, tips untagged, coordinates as written, micro-segments
 * merged. *nobj: object strokes written. */
static amp_status island_once(lctx *c, size_t li, double h, amp_pathset *out, size_t first, size_t *nobj,
                              amp_contpath_stats *s0, amp_error *err)
{
    size_t i;
    amp_status rc;
    amp_pathset_clear(&c->tmp);
    if ((rc = island_paths(c, li, s0, err)) != AMP_OK)
        return rc;
    if (c->o->join)
        rc = amp_cp_join_loops(&c->tmp, 0, &c->isl, c->o->radius, h, out, nobj, &s0->specks, err);
    else {
        rc = amp_pathset_append(out, &c->tmp, err);
        for (i = first, *nobj = 0; i < out->npaths; i++) {
            out->paths[i].h = h;
            *nobj += out->paths[i].role == AMP_ROLE_OBJECT;
        }
    }
    /* corners' tips lose their tag (contpath_internal.h); coordinates as written */
    for (i = out->npaths > first ? out->paths[first].first : out->nverts; i < out->nverts; i++) {
        if (out->verts[i].r == AMP_CP_TOOTH_R(c->o->radius))
            out->verts[i].r = c->o->radius;
        /* as the .amp writer will write them (10 significant digits, docs/interfaces.md §3): the checks then
         * judge the coordinates the printer gets, and a touch that rounding would turn into a crossing is
         * caught before the file exists */
        out->verts[i].p.x = amp_g10_round(out->verts[i].p.x);
        out->verts[i].p.y = amp_g10_round(out->verts[i].p.y);
    }
    compact_tail(out, first, 1e-3);
    return rc;
}

/* Bead height of layer li: the first layer from the plate, the others from the layer below. */
static double layer_h(const amp_slices *sl, size_t li)
{
    const amp_layer *L = &sl->layers[li];
    return li == 0 ? L->z_print : L->z_print - sl->layers[li - 1].z_print;
}

/* One island's paths, made apart from the others: they do not depend on
 * where the nozzle is (only the order of the islands and the start of each
 * stroke do, decided afterwards in layer_emit), so the islands of many
 * layers are made at once, in parallel, and the output is the same whatever
 * the thread count. */
typedef struct ijob {
    size_t li, k;          /* layer, island of its section */
    amp_pathset ps;        /* the island's paths as island_once leaves them */
    amp_contpath_stats s;  /* its figures, counted from zero */
    size_t nobj;           /* object strokes among them */
    amp_status rc;
    amp_error err;
} ijob;

/* Do the island's paths pass the caller's verifier (o->verify_stroke; none: they pass)? A verifier out of
 * memory is the job's error (j->rc), not a rejection (the island was made again, and its paths changed, for an
 * allocation that failed): the answer is then 1, so that no retry follows. */
static int island_clean(const amp_contpath_opts *o, const amp_pathset *out, const amp_polyset *sec, ijob *j)
{
    size_t i;
    if (!o->verify_stroke)
        return 1;
    for (i = 0; i < out->npaths; i++) {
        amp_status st = o->verify_stroke(out, i, sec, 1e-6, NULL, NULL);
        if (st == AMP_ERR_NOMEM) {
            j->rc = amp_fail(&j->err, AMP_ERR_NOMEM, 0, "out of memory verifying the strokes of an island");
            return 1;
        }
        if (st != AMP_OK)
            return 0;
    }
    return 1;
}

/* Radius of a planar bead of height @p h whose cross-section is @p a (the inverse of amp_bead_area). */
static double bead_radius(double a, double h)
{
    double w = (a - AMP_PI * 0.25 * h * h) / h + h;
    return w >= h ? 0.5 * w : sqrt(a / AMP_PI);
}

/*
 * The island's plastic capped at its slab (section area x h). Beads overlap
 * where the lattice is clipped to a narrow or slanting strip and where a
 * perimeter meets itself across a strip narrower than two beads (a
 * recycling symbol's arms: 6 % more bead than part); a printer pushes that
 * plastic out all the same, and it piles up under the nozzle. The beads of
 * such an island are narrowed by one factor of their cross-section, so that
 * the plastic extruded is at most the volume the beads fill. Returns the
 * volume taken off (mm^3).
 */
static double overlap_cap(amp_pathset *ps, const amp_polyset *isl, double h)
{
    double slab = amp_polyset_area(isl) * h, v = amp_pathset_volume(ps, -1), v0 = v;
    size_t i;
    int pass;
    /* the cross-section is linear in r for beads wider than high (one pass); narrower ones are round */
    for (pass = 0; pass < 4 && v > slab && v > 0.0; pass++) {
        double s = slab / v;
        for (i = 0; i < ps->nverts; i++)
            if (ps->verts[i].r > 0.0)
                ps->verts[i].r = bead_radius(s * amp_bead_area(ps->verts[i].r, h), h);
        v = amp_pathset_volume(ps, -1);
    }
    return v0 - v;
}

/*
 * An island the verifier still rejects hangs on a degenerate touch (the torus
 * meshed at 1.3 mm, 0.2 mm layers, r 0.2: at z 3.4 the region's ring runs
 * within 0.001 mm of a lattice line, and the patch edge from the ring's
 * crossing back to a lattice vertex crosses the ring stretch before it). Such
 * a touch does not survive a small move: the island is made again with its
 * infill region R̃ moved in by r/20, then out by r/20 (the beads stay within
 * the part: R̃ lies 3r inside it, the lattice's beads reach r beyond it), then
 * with its perimeter r/16 nearer the boundary (a strip exactly 2r wide makes
 * the inset by r touch itself along a stretch, which the loop then runs both
 * ways: an edge printed twice, OpenSCAD's example013 at 0.1 mm layers), the
 * first that passes kept; with none, the first try stays in j (the
 * caller's final check reports it). Counted in shift_retries.
 */
static void shift_retry(lctx *w, ijob *j, double h)
{
    static const double shift[3] = {0.05, -0.05, 0.0}, perim[3] = {0.0, 0.0, 1.0 / 16};
    int k, bands = j->s.band_retries > 0;
    for (k = 0; k < 3; k++) {
        amp_contpath_stats s;
        size_t nobj = 0;
        memset(&s, 0, sizeof s);
        amp_pathset_clear(&w->retry);
        w->reg_shift = shift[k] * w->o->radius;
        w->perim_in = perim[k] * w->o->radius;
        w->no_bands = bands;
        j->rc = island_once(w, j->li, h, &w->retry, 0, &nobj, &s, &j->err);
        w->reg_shift = w->perim_in = 0.0;
        w->no_bands = 0;
        if (j->rc != AMP_OK)
            return;
        if (island_clean(w->o, &w->retry, &w->isl, j)) {
            if (j->rc != AMP_OK)
                return; /* the verifier ran out of memory: no further try */
            amp_pathset_clear(&j->ps);
            j->rc = amp_pathset_append(&j->ps, &w->retry, &j->err);
            j->nobj = nobj;
            s.band_retries = (size_t)bands;
            s.shift_retries = 1;
            j->s = s;
            return;
        }
    }
}

/* The island of job j with the scratch of work context w. An island printed
 * with skin bands whose paths the caller's verifier (o->verify_stroke)
 * rejects is made again with its skin regions whole (a band's rings come
 * from an inset, and a slip of it can meet the core's: seen once in 624
 * sweep runs, the bunny meshed at 0.45 mm, 0.25 mm layers, r 0.2); one it
 * still rejects, with its region moved (shift_retry). */
static void island_job(lctx *w, ijob *j)
{
    const amp_layer *L = &w->sl->layers[j->li];
    double h = layer_h(w->sl, j->li);
    amp_pathset_clear(&j->ps);
    memset(&j->s, 0, sizeof j->s);
    j->nobj = 0;
    j->rc = amp_polyset_island(&L->polys, j->k, &w->isl, &j->err);
    if (j->rc == AMP_OK)
        j->rc = island_once(w, j->li, h, &j->ps, 0, &j->nobj, &j->s, &j->err);
    /* each version of the island checked once (island_clean is 1 without a verifier) */
    if (j->rc == AMP_OK && !island_clean(w->o, &j->ps, &w->isl, j)) {
        if (j->s.skin_bands > 0) {
            amp_pathset_clear(&j->ps);
            memset(&j->s, 0, sizeof j->s);
            j->s.band_retries = 1;
            w->no_bands = 1;
            j->rc = island_once(w, j->li, h, &j->ps, 0, &j->nobj, &j->s, &j->err);
            w->no_bands = 0;
        }
        if (j->rc == AMP_OK && (j->s.band_retries == 0 || !island_clean(w->o, &j->ps, &w->isl, j)))
            shift_retry(w, j, h);
    }
    if (j->rc == AMP_OK && w->o->overlap_cap) {
        double cut = overlap_cap(&j->ps, &w->isl, h);
        j->s.narrowed_islands += cut > 0.0;
        j->s.narrowed_volume += cut;
    }
}

/* s += one island's figures (all counts and lengths add up; the deepest cycle tree is the deeper one). */
static void stats_add(amp_contpath_stats *s, const amp_contpath_stats *d)
{
    s->layers += d->layers;
    s->empty_layers += d->empty_layers;
    s->islands += d->islands;
    s->thin_islands += d->thin_islands;
    s->dropped_islands += d->dropped_islands;
    s->island_strokes += d->island_strokes;
    s->specks += d->specks;
    s->regions += d->regions;
    s->skin_regions += d->skin_regions;
    s->strokes += d->strokes;
    s->multi_stroke += d->multi_stroke;
    s->perimeter_loops += d->perimeter_loops;
    s->support_paths += d->support_paths;
    s->travel_moves += d->travel_moves;
    s->free_ends += d->free_ends;
    s->odd_vertices += d->odd_vertices;
    s->cycles += d->cycles;
    s->tree_levels = d->tree_levels > s->tree_levels ? d->tree_levels : s->tree_levels;
    s->tour_fallbacks += d->tour_fallbacks;
    s->joins += d->joins;
    s->printed_length += d->printed_length;
    s->infill_length += d->infill_length;
    s->pseudo_length += d->pseudo_length;
    s->travel_length += d->travel_length;
    s->support_length += d->support_length;
    s->unprinted_length += d->unprinted_length;
    s->support_corners += d->support_corners;
    s->corners_left_out += d->corners_left_out;
    s->neck_islands += d->neck_islands;
    s->skin_bands += d->skin_bands;
    s->band_retries += d->band_retries;
    s->corners_touched += d->corners_touched;
    s->narrowed_islands += d->narrowed_islands;
    s->narrowed_volume += d->narrowed_volume;
    s->shift_retries += d->shift_retries;
}

/* Layer li from its islands' jobs (jobs[k]: island k): the islands nearest
 * first, each stroke started near the nozzle. */
static amp_status layer_emit(lctx *c, size_t li, const ijob *jobs, amp_pathset *out, amp_contpath_stats *s0,
                             amp_error *err)
{
    const amp_layer *L = &c->sl->layers[li];
    size_t n, k, before = out->npaths, i;
    amp_status rc = AMP_OK;
    void *q = c->done;
    if (amp_grow(out->alloc, &q, &c->cap_done, L->polys.nislands + 1, 1) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory ordering the islands");
    c->done = q;
    memset(c->done, 0, L->polys.nislands + 1);
    for (n = 0; n < L->polys.nislands && rc == AMP_OK; n++) {
        size_t first = out->npaths;
        const ijob *j;
        k = next_island(c, L);
        if (k == NONE)
            break;
        c->done[k] = 1;
        j = &jobs[k];
        if (j->rc != AMP_OK) {
            if (err)
                *err = j->err;
            return j->rc;
        }
        if ((rc = amp_pathset_append(out, &j->ps, err)) != AMP_OK)
            break;
        stats_add(s0, &j->s);
        s0->islands += out->npaths > first;
        s0->island_strokes += j->nobj;
        for (i = first; i < out->npaths && rc == AMP_OK; i++) {
            if (c->have_at)
                rc = rotate_to(out, i, c->at, err);
            if (out->paths[i].n) {
                amp_pvert e = amp_pathset_path_verts(out, i)[out->paths[i].n - 1];
                c->at = amp_v2(e.p.x, e.p.y);
                c->have_at = 1;
            }
        }
    }
    s0->empty_layers += rc == AMP_OK && out->npaths == before && amp_polyset_area(&L->polys) > 0;
    return rc;
}

/* The per-island scratch of a work context (isl .. bare_skin). */
static void scratch_init(lctx *w, const amp_allocator *al)
{
    amp_polyset_init(&w->isl, al);
    amp_polyset_init(&w->ins, al);
    amp_polyset_init(&w->reg, al);
    amp_polyset_init(&w->bin, al);
    amp_polyset_init(&w->core, al);
    amp_polyset_init(&w->band, al);
    amp_polyset_init(&w->reg2, al);
    amp_pathset_init(&w->tmp, al);
    amp_pathset_init(&w->bare, al);
    amp_pathset_init(&w->bare_skin, al);
    amp_pathset_init(&w->retry, al);
    w->no_bands = 0;
    w->reg_shift = w->perim_in = 0.0;
}

static void scratch_free(lctx *w)
{
    amp_polyset_free(&w->isl);
    amp_polyset_free(&w->ins);
    amp_polyset_free(&w->reg);
    amp_polyset_free(&w->bin);
    amp_polyset_free(&w->core);
    amp_polyset_free(&w->band);
    amp_polyset_free(&w->reg2);
    amp_pathset_free(&w->tmp);
    amp_pathset_free(&w->bare);
    amp_pathset_free(&w->bare_skin);
    amp_pathset_free(&w->retry);
}

/* Lattice t: K̂ (t = 0), the solid one along x (1) or y (2), and its edge list. */
static amp_status lattice(lctx *c, int t, const amp_allocator *al, amp_error *err)
{
    const amp_contpath_opts *o = c->o;
    amp_contpath_opts so = *o;
    amp_cx2 *k = t ? &c->kskin[t - 1] : &c->khat;
    uint64_t **e = t ? &c->kse[t - 1] : &c->ke;
    size_t *ne = t ? &c->nkse[t - 1] : &c->nke;
    amp_status rc;
    if (t) {
        /* the solid lattices: strips 4r wide with offset r, so that the
         * beads along the long sides lie side by side and cover the region
         * once (a square lattice of 4r covers it twice: beads both ways),
         * along x on even layers and along y on odd ones, as slicers turn
         * their solid infill by 90 degrees */
        so.cell = o->skin_cell > 0 ? o->skin_cell : 4 * o->radius;
        so.grid = t == 2 ? AMP_GRID_STRIPS_Y : AMP_GRID_STRIPS_X;
        so.offset = o->radius;
    }
    rc = amp_contpath_complex(c->sl, &so, k, err);
    if (rc == AMP_OK && amp_cp_khat_edges(k, al, e, ne) != AMP_OK)
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the lattice edges");
    return rc;
}

/* May work that allocates through @p al run on the OpenMP threads? Only with the default allocator
 * (malloc): a caller's allocator need not be thread-safe (include/ampath/contpath.h). */
static int threads_may_allocate(const amp_allocator *al) { return al == NULL || al == amp_allocator_default(); }

/* The lattices and the sections' row indexes (skin tests), each independent of the others: on the OpenMP
 * threads when they may allocate. */
static amp_status shared_init(lctx *c, const amp_allocator *al, amp_error *err)
{
    const amp_slices *sl = c->sl;
    amp_error e[3];
    amp_status r[3] = {AMP_OK, AMP_OK, AMP_OK}, rc = AMP_OK;
    int par = threads_may_allocate(al), n, t, bad = 0;
    long li;
    c->skins = c->o->skin_bottom > 0 || c->o->skin_top > 0;
    n = c->skins ? 3 : 1;
    (void)par;
#pragma omp parallel for schedule(dynamic, 1) if (par && n > 1)
    for (t = 0; t < n; t++)
        r[t] = lattice(c, t, al, &e[t]);
    for (t = 0; t < n && rc == AMP_OK; t++)
        if ((rc = r[t]) != AMP_OK && err)
            *err = e[t];
    if (rc == AMP_OK && c->skins) {
        if (!(c->lix = amp_calloc(al, sl->nlayers + 1, sizeof *c->lix)))
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory indexing the sections");
#pragma omp parallel for schedule(dynamic, 16) reduction(| : bad) if (par)
        for (li = 0; li < (long)sl->nlayers; li++)
            bad |= amp_polyindex_build(&c->lix[li], &sl->layers[li].polys, NULL) != AMP_OK;
        if (bad)
            rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory indexing the sections");
    }
    return rc;
}

static void shared_free(lctx *c, const amp_allocator *al)
{
    size_t li;
    for (li = 0; c->lix && li < c->sl->nlayers; li++)
        amp_polyindex_free(&c->lix[li]);
    amp_free(al, c->lix);
    amp_free(al, c->ke);
    amp_free(al, c->kse[0]);
    amp_free(al, c->kse[1]);
    amp_cx2_free(&c->kskin[0]);
    amp_cx2_free(&c->kskin[1]);
    amp_cx2_free(&c->khat);
    amp_free(al, c->done);
}

/* islands made at once before they are written (a layer with more is made alone) */
#define JOBS_MAX 256

/* Work contexts: copies of c sharing its read-only lattices, each with its own scratch; one per thread. */
static lctx *workers_new(const lctx *c, const amp_allocator *al, size_t *nw)
{
    size_t n = 1, t;
    lctx *w;
#ifdef _OPENMP
    if (threads_may_allocate(al))
        n = (size_t)omp_get_max_threads();
#endif
    w = amp_calloc(al, n, sizeof *w);
    for (t = 0; w && t < n; t++) {
        w[t] = *c;
        w[t].done = NULL;
        w[t].cap_done = 0;
        scratch_init(&w[t], al);
    }
    *nw = n;
    return w;
}

/* Make the jobs [0, n) (in parallel when there is more than one work context). */
static void run_jobs(lctx *w, size_t nw, ijob *jobs, size_t n)
{
    long q;
    (void)nw;
#pragma omp parallel for schedule(dynamic, 1) num_threads((int)nw) if (nw > 1 && n > 1)
    for (q = 0; q < (long)n; q++) {
        size_t t = 0;
#ifdef _OPENMP
        t = (size_t)omp_get_thread_num();
#endif
        island_job(&w[t], &jobs[q]);
    }
}

/* Layers [l0, l1) with every island of them in (*jobs)[0 ..) in layer order: as many layers as JOBS_MAX
 * islands hold, at least one (the array grows for a layer of more). */
static amp_status plan_jobs(const amp_slices *sl, size_t l0, ijob **jobs, size_t *cap, size_t *njobs, size_t *l1,
                            const amp_allocator *al, amp_error *err)
{
    size_t n = 0, k, li = l0;
    while (li < sl->nlayers && (li == l0 || n + sl->layers[li].polys.nislands <= JOBS_MAX)) {
        size_t ni = sl->layers[li].polys.nislands, old = *cap;
        void *v = *jobs;
        if (amp_grow(al, &v, cap, n + ni, sizeof **jobs) != AMP_OK)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the island work");
        *jobs = v;
        for (k = old; k < *cap; k++)
            amp_pathset_init(&(*jobs)[k].ps, al);
        for (k = 0; k < ni; k++, n++) {
            (*jobs)[n].li = li;
            (*jobs)[n].k = k;
        }
        li++;
    }
    *njobs = n;
    *l1 = li;
    return AMP_OK;
}

amp_status amp_contpath_layers(const amp_slices *sl, const amp_contpath_opts *o, amp_pathset *out,
                               amp_contpath_stats *st, amp_error *err)
{
    const amp_allocator *al;
    lctx c, *w;
    ijob *jobs = NULL;
    size_t li, q, p0, nw = 0, nj = 0, cap = 0;
    amp_contpath_stats s0;
    amp_status rc;
    if (!sl || !o || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_contpath_layers: NULL argument");
    al = out->alloc;
    p0 = out->npaths;
    memset(&s0, 0, sizeof s0);
    memset(&c, 0, sizeof c);
    c.sl = sl;
    c.o = o;
    amp_cx2_init(&c.khat, al);
    amp_cx2_init(&c.kskin[0], al);
    amp_cx2_init(&c.kskin[1], al);
    rc = shared_init(&c, al, err);
    w = rc == AMP_OK ? workers_new(&c, al, &nw) : NULL;
    if (rc == AMP_OK && !w)
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the island work");
    for (li = 0; li < sl->nlayers && rc == AMP_OK;) {
        size_t l1 = li, base = 0;
        if ((rc = plan_jobs(sl, li, &jobs, &cap, &nj, &l1, al, err)) != AMP_OK)
            break;
        run_jobs(w, nw, jobs, nj);
        for (; li < l1 && rc == AMP_OK; li++) {
            s0.layers++;
            rc = layer_emit(&c, li, jobs + base, out, &s0, err);
            base += sl->layers[li].polys.nislands;
        }
        if (o->progress)
            o->progress(o->progress_user, (double)li / (double)sl->nlayers);
    }
    /* figures over the paths written by this call */
    for (q = p0; q < out->npaths && rc == AMP_OK; q++) {
        if (out->paths[q].role == AMP_ROLE_OBJECT)
            s0.printed_length += amp_cp_printed_len(out, q);
        if (q > p0 && out->paths[q - 1].n && out->paths[q].n) {
            amp_pvert a = amp_pathset_path_verts(out, q - 1)[out->paths[q - 1].n - 1];
            amp_pvert b = amp_pathset_path_verts(out, q)[0];
            s0.travel_moves++;
            s0.travel_length += amp_v3_dist(a.p, b.p);
        }
    }
    for (q = 0; q < cap; q++)
        amp_pathset_free(&jobs[q].ps);
    amp_free(al, jobs);
    for (q = 0; w && q < nw; q++)
        scratch_free(&w[q]);
    amp_free(al, w);
    shared_free(&c, al);
    if (st)
        *st = s0;
    return rc;
}
