/* Step 6 ([P2 §2.2], Fig. 5): support corners where
 * the ring of R̃ is left unprinted by the patching.
 *
 * Circles of radius r are put on the bare stretch p̃ between its two free
 * ends (whose lattice beads already hold a circle each), as many as fit
 * with centres at most 2r apart, the gap spread evenly (Fig. 5a, b; the
 * paper takes at most as many as fit without overlap, which can leave a
 * stretch up to 4r between centres: here the centres are at most 2r apart so
 * that every point of p̃ is within r of a corner). From each centre ṽ' the
 * perpendicular reaches the outer boundary at a, 2r away (R̃ is the inset by
 * 3r, the perimeter bead's centre line by r): the corner is the two edges
 * from ṽ' to the perimeter at a ∓ w, w = r/2 or less so that the corners of
 * a stretch do not overlap (Fig. 5c takes w = r: the circle of radius r
 * around a; the perimeter skips the base, so the part's edge in front of it
 * was left bare 0.41 r deep over 2r, a notch in the outer wall at every
 * tooth; at r/2 it is 0.12 r deep over r), and the perimeter loop runs
 * through them (Fig. 5d: neighbouring corners joined along the boundary), so
 * the corners are part of the island's one stroke. A corner whose edges
 * would cross the island's other paths, or overlap its neighbour, is left
 * out and counted. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

typedef struct tooth {
    double s0, s1; /* arclength of the base on the perimeter loop */
    size_t loop;   /* which perimeter loop */
    amp_pvert tip;
} tooth;

static int cmp_tooth(const void *a, const void *b)
{
    const tooth *x = a, *y = b;
    return x->s0 < y->s0 ? -1 : (x->s0 > y->s0 ? 1 : 0);
}

/* Proper crossing of a-b and c-d; an end within a hair (1e-9 of the
 * lengths) of the other segment counts as touching, not crossing: a leg
 * starts on the perimeter segment it leaves. */
static int cross2(amp_vec2 a, amp_vec2 b, amp_vec2 c, amp_vec2 d)
{
    double d1 = amp_v2_orient(a, b, c), d2 = amp_v2_orient(a, b, d), d3 = amp_v2_orient(c, d, a),
           d4 = amp_v2_orient(c, d, b), e;
    /* the margin e >= 0 only matters where both pairs straddle: the two hypot calls were 18 % of slicing
     * PrusaSlicer's bunny (support corners test every candidate against its neighbours) */
    if (!((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) || !((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)))
        return 0;
    e = 1e-9 * hypot(b.x - a.x, b.y - a.y) * hypot(d.x - c.x, d.y - c.y);
    return ((d1 > e && d2 < -e) || (d1 < -e && d2 > e)) && ((d3 > e && d4 < -e) || (d3 < -e && d4 > e));
}

static amp_vec2 xy(amp_vec3 p) { return amp_v2(p.x, p.y); }

/* Point at arclength s of closed path i (cumulative lengths cl). */
static amp_pvert at_len(const amp_pathset *ps, size_t i, const double *cl, double s, size_t *seg)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    size_t lo = 0, hi = ps->paths[i].n - 1;
    amp_pvert p;
    double t;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (cl[mid] <= s)
            lo = mid;
        else
            hi = mid;
    }
    t = cl[hi] > cl[lo] ? (s - cl[lo]) / (cl[hi] - cl[lo]) : 0;
    p.p = amp_v3_add(v[lo].p, amp_v3_scale(amp_v3_sub(v[hi].p, v[lo].p), t));
    p.r = v[lo].r;
    *seg = lo;
    return p;
}

/* Does segment a-b cross a segment of any path of @p ps (or an accepted
 * tooth leg)? Segments ending at a or b do not count. */
static int near_seg(amp_vec2 q, amp_vec2 a, amp_vec2 b, double tol)
{
    amp_vec2 e;
    if ((q.x == a.x && q.y == a.y) || (q.x == b.x && q.y == b.y))
        return 0; /* a shared vertex (the leg's own base) */
    e = amp_cp_seg_offset(q, a, b, NULL);
    return e.x * e.x + e.y * e.y < tol * tol; /* squared: hypot() was a tenth of the support corners' time */
}

/* Uniform grid of the segments of a pathset (segment = global index of its
 * first vertex), so a corner's legs meet only the segments near them. */
typedef struct sgrid {
    double x0, y0, cell;
    long nx, ny;
    size_t *start, *item;
} sgrid;

static long sg_cell(double v, double o, double c, long n)
{
    long k = (long)floor((v - o) / c);
    return k < 0 ? 0 : (k >= n ? n - 1 : k);
}

static amp_status sg_build(sgrid *g, const amp_pathset *ps, double cell, const amp_allocator *al)
{
    double x1 = -HUGE_VAL, y1 = -HUGE_VAL;
    size_t i, k, pass, ncell;
    memset(g, 0, sizeof *g);
    g->x0 = g->y0 = HUGE_VAL;
    for (i = 0; i < ps->nverts; i++) {
        g->x0 = fmin(g->x0, ps->verts[i].p.x);
        g->y0 = fmin(g->y0, ps->verts[i].p.y);
        x1 = fmax(x1, ps->verts[i].p.x);
        y1 = fmax(y1, ps->verts[i].p.y);
    }
    g->cell = fmax(cell, fmax(x1 - g->x0, y1 - g->y0) / 1024);
    g->nx = (long)((x1 - g->x0) / g->cell) + 1;
    g->ny = (long)((y1 - g->y0) / g->cell) + 1;
    ncell = (size_t)(g->nx * g->ny);
    g->start = amp_calloc(al, ncell + 1, sizeof *g->start);
    if (!g->start)
        return AMP_ERR_NOMEM;
    for (pass = 0; pass < 2; pass++) {
        for (i = 0; i < ps->npaths; i++)
            for (k = ps->paths[i].first; k + 1 < ps->paths[i].first + ps->paths[i].n; k++) {
                amp_vec3 a = ps->verts[k].p, b = ps->verts[k + 1].p;
                long cx0 = sg_cell(fmin(a.x, b.x), g->x0, g->cell, g->nx), cx1 = sg_cell(fmax(a.x, b.x), g->x0, g->cell, g->nx);
                long cy0 = sg_cell(fmin(a.y, b.y), g->y0, g->cell, g->ny), cy1 = sg_cell(fmax(a.y, b.y), g->y0, g->cell, g->ny);
                long x, y;
                for (y = cy0; y <= cy1; y++)
                    for (x = cx0; x <= cx1; x++) {
                        if (pass == 0)
                            g->start[y * g->nx + x + 1]++;
                        else
                            g->item[g->start[y * g->nx + x]++] = k;
                    }
            }
        if (pass == 0) {
            for (i = 0; i < ncell; i++)
                g->start[i + 1] += g->start[i];
            g->item = amp_alloc(al, (g->start[ncell] + 1) * sizeof *g->item);
            if (!g->item)
                return AMP_ERR_NOMEM;
        }
    }
    for (i = ncell; i > 0; i--)
        g->start[i] = g->start[i - 1];
    g->start[0] = 0;
    return AMP_OK;
}

/* Does segment a-b (a corner's leg from its base a on the perimeter to its
 * tip b) cross a segment of @p ps, or touch one within @p hair (a touch would
 * become a crossing once coordinates are rounded)? The accepted legs are
 * crosses_leg's. */
static int blocked(const amp_pathset *ps, const sgrid *g, amp_vec2 a, amp_vec2 b, double hair)
{
    size_t k;
    double x0 = fmin(a.x, b.x) - hair, x1 = fmax(a.x, b.x) + hair, y0 = fmin(a.y, b.y) - hair,
           y1 = fmax(a.y, b.y) + hair;
    long cx0 = sg_cell(x0, g->x0, g->cell, g->nx), cx1 = sg_cell(x1, g->x0, g->cell, g->nx);
    long cy0 = sg_cell(y0, g->y0, g->cell, g->ny), cy1 = sg_cell(y1, g->y0, g->cell, g->ny), x, y;
    for (y = cy0; y <= cy1; y++)
        for (x = cx0; x <= cx1; x++)
            for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                amp_vec2 c = xy(ps->verts[g->item[k]].p), d = xy(ps->verts[g->item[k] + 1].p);
                if (fmax(c.x, d.x) < x0 || fmin(c.x, d.x) > x1 || fmax(c.y, d.y) < y0 || fmin(c.y, d.y) > y1)
                    continue;
                if (cross2(a, b, c, d) || near_seg(b, c, d, hair) || near_seg(c, a, b, hair) ||
                    near_seg(d, a, b, hair))
                    return 1;
            }
    return 0;
}

/* Nearest point of the perimeter loops [0, nperim) of @p ps to q within
 * @p lim: loop and arclength (HUGE_VAL when none is that close). Through the
 * segment grid: a corner only takes a perimeter closer than 3r, and a scan
 * of every perimeter segment per corner grew with the square of the part
 * (the vase). Ties go to the first segment in path order, as a full scan. */
static double nearest_perimeter(const amp_pathset *ps, const sgrid *g, size_t nperim, double *const *cl, amp_vec2 q,
                                double lim, size_t *loop, double *s)
{
    size_t k, bestk = (size_t)-1, i, end = ps->paths[nperim - 1].first + ps->paths[nperim - 1].n;
    double best = HUGE_VAL, bt = 0;
    long cx0 = sg_cell(q.x - lim, g->x0, g->cell, g->nx), cx1 = sg_cell(q.x + lim, g->x0, g->cell, g->nx);
    long cy0 = sg_cell(q.y - lim, g->y0, g->cell, g->ny), cy1 = sg_cell(q.y + lim, g->y0, g->cell, g->ny), x, y;
    for (y = cy0; y <= cy1; y++)
        for (x = cx0; x <= cx1; x++)
            for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                size_t id = g->item[k];
                amp_vec2 e;
                double t, d;
                if (id >= end)
                    continue; /* not a perimeter segment */
                e = amp_cp_seg_offset(q, xy(ps->verts[id].p), xy(ps->verts[id + 1].p), &t);
                /* clearly farther than the best (the margin covers hypot's rounding): no hypot */
                if (e.x * e.x + e.y * e.y > best * best * (1.0 + 1e-9))
                    continue;
                d = hypot(e.x, e.y);
                if (d < best || (d == best && id < bestk)) {
                    best = d;
                    bestk = id;
                    bt = t;
                }
            }
    if (!(best < lim))
        return HUGE_VAL;
    for (i = 0; i < nperim && !(bestk < ps->paths[i].first + ps->paths[i].n); i++)
        ;
    k = bestk - ps->paths[i].first;
    *loop = i;
    *s = cl[i][k] + bt * (cl[i][k + 1] - cl[i][k]);
    return best;
}

/* Replace the vertices of path i of @p ps by w[0 .. m) (later paths move). */
static amp_status replace_path(amp_pathset *ps, size_t i, const amp_pvert *w, size_t m, amp_error *err)
{
    size_t n = ps->paths[i].n, first = ps->paths[i].first, j;
    void *q = ps->verts;
    if (m > n && amp_grow(ps->alloc, &q, &ps->cap_verts, ps->nverts + (m - n), sizeof *ps->verts) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory adding support corners");
    ps->verts = q;
    memmove(ps->verts + first + m, ps->verts + first + n, (ps->nverts - first - n) * sizeof *ps->verts);
    memcpy(ps->verts + first, w, m * sizeof *w);
    for (j = i + 1; j < ps->npaths; j++)
        ps->paths[j].first = ps->paths[j].first + m - n;
    ps->paths[i].n = m;
    ps->nverts = ps->nverts + m - n;
    return AMP_OK;
}

/* Rebuild perimeter loop i of @p ps in place with its teeth (sorted, disjoint). */
static amp_status insert_teeth(amp_pathset *ps, size_t i, const double *cl, const tooth *t, size_t nt,
                               amp_pathset *scratch, amp_error *err)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    size_t n = ps->paths[i].n, k = 0, j, seg;
    amp_status st;
    amp_pathset_clear(scratch);
    if ((st = amp_pathset_begin(scratch, ps->paths[i].role, err)) != AMP_OK)
        return st;
    for (j = 0; j < nt && st == AMP_OK; j++) {
        amp_pvert a = at_len(ps, i, cl, t[j].s0, &seg), b;
        for (; k < n && cl[k] < t[j].s0 && st == AMP_OK; k++)
            st = amp_pathset_push(scratch, v[k].p, v[k].r, err);
        b = at_len(ps, i, cl, t[j].s1, &seg);
        if (st == AMP_OK)
            st = amp_pathset_push(scratch, a.p, a.r, err);
        if (st == AMP_OK)
            st = amp_pathset_push(scratch, t[j].tip.p, a.r, err);
        if (st == AMP_OK)
            st = amp_pathset_push(scratch, b.p, b.r, err);
        for (; k < n && cl[k] <= t[j].s1; k++)
            ;
    }
    for (; k < n && st == AMP_OK; k++)
        st = amp_pathset_push(scratch, v[k].p, v[k].r, err);
    if (st != AMP_OK)
        return st;
    /* same vertex count or more: the path is replaced by moving the tail */
    return replace_path(ps, i, amp_pathset_path_verts(scratch, 0), scratch->paths[0].n, err);
}

/* Centres of the corner circles on bare polyline b: at most 2r apart, the
 * ends excluded on an open stretch (its free ends carry lattice beads). */
static size_t centres(const amp_pvert *b, size_t n, double r, double *len, int *closed)
{
    size_t k;
    double L = 0;
    for (k = 0; k + 1 < n; k++)
        L += amp_v3_dist(b[k].p, b[k + 1].p);
    *len = L;
    *closed = n > 2 && b[0].p.x == b[n - 1].p.x && b[0].p.y == b[n - 1].p.y;
    if (!(L > 0))
        return 0;
    k = (size_t)ceil(L / (2 * r) - 1e-9);
    return *closed ? (k < 3 ? 3 : k) : (k > 0 ? k - 1 : 0);
}

/* Point at arclength s of polyline b. */
static amp_vec2 poly_at(const amp_pvert *b, size_t n, double s)
{
    size_t k;
    for (k = 0; k + 1 < n; k++) {
        double l = amp_v3_dist(b[k].p, b[k + 1].p);
        if (s <= l || k + 2 == n) {
            double t = l > 0 ? fmin(s / l, 1.0) : 0;
            return amp_v2(b[k].p.x + t * (b[k + 1].p.x - b[k].p.x), b[k].p.y + t * (b[k + 1].p.y - b[k].p.y));
        }
        s -= l;
    }
    return xy(b[0].p);
}

/* Is a printed segment of the island's infill strokes (paths after the
 * perimeters: vertex ids from @p end on) within @p lim of q? */
static int infill_within(const amp_pathset *ps, const sgrid *g, size_t end, amp_vec2 q, double lim)
{
    size_t k;
    long cx0 = sg_cell(q.x - lim, g->x0, g->cell, g->nx), cx1 = sg_cell(q.x + lim, g->x0, g->cell, g->nx);
    long cy0 = sg_cell(q.y - lim, g->y0, g->cell, g->ny), cy1 = sg_cell(q.y + lim, g->y0, g->cell, g->ny), x, y;
    for (y = cy0; y <= cy1; y++)
        for (x = cx0; x <= cx1; x++)
            for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                size_t id = g->item[k];
                amp_vec2 e;
                if (id < end || !(ps->verts[id].r > 0) || !(ps->verts[id + 1].r > 0))
                    continue;
                e = amp_cp_seg_offset(q, xy(ps->verts[id].p), xy(ps->verts[id + 1].p), NULL);
                if (e.x * e.x + e.y * e.y <= lim * lim * (1.0 + 1e-9) && hypot(e.x, e.y) <= lim)
                    return 1; /* (hypot only near the bound: most segments are clearly farther) */
            }
    return 0;
}

/* Step 6 for one island: the corners found so far and what they need. */
typedef struct corner_ctx {
    const amp_allocator *al;
    amp_pathset *ps;          /* the island's paths, perimeter loops first */
    size_t nperim;            /* perimeter loops, paths [0, nperim) */
    double r, covered;        /* bead radius; see amp_cp_support_corners */
    amp_contpath_stats *st;
    sgrid sg;                 /* the island's segments */
    double **cl;              /* per perimeter loop: arclength at each vertex */
    tooth *t;                 /* the corners placed */
    size_t nt, cap_t;
    amp_vec2 *legs;           /* the two legs of corner k: legs[4k .. 4k + 3] (two segments) */
    size_t cap_l;
    /* the legs by the cell of their midpoint (lists through leg_next; a big island has thousands of corners,
     * and every new leg was tested against all of them) */
    double lx0, ly0, lcell, lreach; /* lreach: the longest half leg so far */
    long lnx, lny;
    size_t *leg_head, *leg_next, cap_n;
} corner_ctx;

#define NO_LEG ((size_t)-1)

static long leg_cell(double v, double o, double c, long n)
{
    long k = (long)floor((v - o) / c);
    return k < 0 ? 0 : (k >= n ? n - 1 : k);
}

/* Does segment a-b cross an accepted leg? Legs are listed by the cell of their midpoint: a leg that meets
 * a-b's box has its midpoint within lreach of it. */
static int crosses_leg(const corner_ctx *c, amp_vec2 a, amp_vec2 b)
{
    double x0 = fmin(a.x, b.x), x1 = fmax(a.x, b.x), y0 = fmin(a.y, b.y), y1 = fmax(a.y, b.y);
    long cx0 = leg_cell(x0 - c->lreach, c->lx0, c->lcell, c->lnx), cx1 = leg_cell(x1 + c->lreach, c->lx0, c->lcell, c->lnx);
    long cy0 = leg_cell(y0 - c->lreach, c->ly0, c->lcell, c->lny), cy1 = leg_cell(y1 + c->lreach, c->ly0, c->lcell, c->lny);
    long x, y;
    size_t k;
    if (c->nt == 0)
        return 0;
    for (y = cy0; y <= cy1; y++)
        for (x = cx0; x <= cx1; x++)
            for (k = c->leg_head[y * c->lnx + x]; k != NO_LEG; k = c->leg_next[k]) {
                amp_vec2 p = c->legs[2 * k], q = c->legs[2 * k + 1];
                if (fmax(p.x, q.x) < x0 || fmin(p.x, q.x) > x1 || fmax(p.y, q.y) < y0 || fmin(p.y, q.y) > y1)
                    continue; /* cross2 needs the boxes to meet */
                if (cross2(a, b, p, q))
                    return 1;
            }
    return 0;
}

/* List legs 2 nt and 2 nt + 1 (just stored in c->legs) in the cells of their midpoints. */
static amp_status list_legs(corner_ctx *c)
{
    void *q = c->leg_next;
    size_t j;
    if (amp_grow(c->al, &q, &c->cap_n, 2 * c->nt + 2, sizeof *c->leg_next) != AMP_OK)
        return AMP_ERR_NOMEM;
    c->leg_next = q;
    for (j = 2 * c->nt; j < 2 * c->nt + 2; j++) {
        amp_vec2 p = c->legs[2 * j], e = c->legs[2 * j + 1];
        long cell = leg_cell(0.5 * (p.y + e.y), c->ly0, c->lcell, c->lny) * c->lnx +
                    leg_cell(0.5 * (p.x + e.x), c->lx0, c->lcell, c->lnx);
        c->lreach = fmax(c->lreach, 0.5 * fmax(fabs(e.x - p.x), fabs(e.y - p.y)));
        c->leg_next[j] = c->leg_head[cell];
        c->leg_head[cell] = j;
    }
    return AMP_OK;
}

/* The leg grid over the segment grid's extent, cells of 4 r or more (at most 256 x 256). */
static amp_status legs_init(corner_ctx *c)
{
    double w = (double)c->sg.nx * c->sg.cell, h = (double)c->sg.ny * c->sg.cell;
    size_t i, n;
    c->lx0 = c->sg.x0;
    c->ly0 = c->sg.y0;
    c->lcell = fmax(4.0 * c->r, fmax(w, h) / 256.0);
    c->lnx = (long)(w / c->lcell) + 1;
    c->lny = (long)(h / c->lcell) + 1;
    n = (size_t)(c->lnx * c->lny);
    c->leg_head = amp_alloc(c->al, n * sizeof *c->leg_head);
    if (!c->leg_head)
        return AMP_ERR_NOMEM;
    for (i = 0; i < n; i++)
        c->leg_head[i] = NO_LEG;
    return AMP_OK;
}

/* Arclength at every vertex of each perimeter loop. */
static amp_status perimeter_lengths(corner_ctx *c, amp_error *err)
{
    size_t i, k;
    for (i = 0; i < c->nperim; i++) {
        const amp_pvert *v = amp_pathset_path_verts(c->ps, i);
        c->cl[i] = amp_alloc(c->al, (c->ps->paths[i].n + 1) * sizeof **c->cl);
        if (!c->cl[i])
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory adding support corners");
        c->cl[i][0] = 0;
        for (k = 1; k < c->ps->paths[i].n; k++)
            c->cl[i][k] = c->cl[i][k - 1] + amp_v3_dist(v[k - 1].p, v[k].p);
    }
    return AMP_OK;
}

/* Fig. 5: one corner with its tip at the centre @p ctr of a bare stretch and
 * its base (half width @p hw) on the nearest perimeter loop, unless that
 * would cross a path, overlap a neighbour or find no perimeter. */
static amp_status place_corner(corner_ctx *c, amp_vec2 ctr, double hw, amp_error *err)
{
    const amp_pathset *ps = c->ps;
    double r = c->r, s = 0, d, tot;
    size_t loop = 0, seg, last = c->nperim - 1;
    amp_pvert a0, a1;
    void *q = c->t, *ql = c->legs;
    d = nearest_perimeter(ps, &c->sg, c->nperim, c->cl, ctr, 3 * r, &loop, &s);
    /* a skin's strip already runs within `covered` of the ring here: a
     * corner would print its plastic a second time */
    if (c->covered > 0 && infill_within(ps, &c->sg, ps->paths[last].first + ps->paths[last].n, ctr, c->covered))
        return AMP_OK;
    tot = c->cl[loop][ps->paths[loop].n - 1];
    /* the perimeter is 2r out; the base r to either side */
    if (d >= 3 * r &&
        infill_within(ps, &c->sg, ps->paths[last].first + ps->paths[last].n, ctr, 2 * r * (1 + 1e-9))) {
        c->st->corners_touched++; /* every point of the stretch within r of that bead's material already */
        return AMP_OK;
    }
    if (!(d > r && d < 3 * r) || s - hw < 0 || s + hw > tot) {
        c->st->corners_left_out++;
        return AMP_OK;
    }
    a0 = at_len(ps, loop, c->cl[loop], s - hw, &seg);
    a1 = at_len(ps, loop, c->cl[loop], s + hw, &seg);
    if (blocked(ps, &c->sg, xy(a0.p), ctr, 1e-4 * r) || crosses_leg(c, xy(a0.p), ctr) ||
        blocked(ps, &c->sg, xy(a1.p), ctr, 1e-4 * r) || crosses_leg(c, xy(a1.p), ctr)) {
        c->st->corners_left_out++;
        return AMP_OK;
    }
    /* each array is taken back as soon as it has grown: the other's failure must not leave it dangling */
    if (amp_grow(c->al, &q, &c->cap_t, c->nt + 1, sizeof *c->t) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory adding support corners");
    c->t = q;
    if (amp_grow(c->al, &ql, &c->cap_l, 4 * (c->nt + 1), sizeof *c->legs) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory adding support corners");
    c->legs = ql;
    c->legs[4 * c->nt] = xy(a0.p);
    c->legs[4 * c->nt + 1] = ctr;
    c->legs[4 * c->nt + 2] = ctr;
    c->legs[4 * c->nt + 3] = xy(a1.p);
    if (list_legs(c) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory adding support corners");
    c->t[c->nt].s0 = s - hw;
    c->t[c->nt].s1 = s + hw;
    c->t[c->nt].loop = loop;
    c->t[c->nt].tip.p = amp_v3(ctr.x, ctr.y, a0.p.z);
    c->t[c->nt].tip.r = AMP_CP_TOOTH_R(r); /* tagged: the joiner keeps off corners */
    c->nt++;
    return AMP_OK;
}

/* The corners of every bare stretch, at evenly spaced centres along it. */
static amp_status stretch_corners(corner_ctx *c, const amp_pathset *bare, amp_error *err)
{
    size_t i, k;
    amp_status rc = AMP_OK;
    for (i = 0; i < bare->npaths && rc == AMP_OK; i++) {
        const amp_pvert *b = amp_pathset_path_verts(bare, i);
        size_t n = bare->paths[i].n, m;
        double L, hw;
        int closed;
        m = centres(b, n, c->r, &L, &closed);
        /* half the base: r/2 (the notch in the part's edge, see the top), less where the corners of one
         * stretch would overlap */
        hw = m ? fmin(0.5 * c->r, 0.45 * L / (double)(closed ? m : m + 1)) : 0.5 * c->r;
        for (k = 0; k < m && rc == AMP_OK; k++) {
            double at = closed ? L * (double)k / (double)m : L * (double)(k + 1) / (double)(m + 1);
            rc = place_corner(c, poly_at(b, n, at), hw, err);
        }
    }
    return rc;
}

/* Per perimeter loop: its corners sorted by base, overlapping ones left
 * out, the rest built into the loop. */
static amp_status build_corners(corner_ctx *c, amp_pathset *scratch, amp_error *err)
{
    size_t i, k, j;
    amp_status rc = AMP_OK;
    for (i = 0; i < c->nperim && rc == AMP_OK; i++) {
        size_t mt = 0;
        tooth *u = NULL;
        if (c->nt)
            u = amp_alloc(c->al, c->nt * sizeof *u);
        if (c->nt && !u)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory adding support corners");
        for (k = 0; k < c->nt; k++)
            if (c->t[k].loop == i)
                u[mt++] = c->t[k];
        if (mt > 1)
            qsort(u, mt, sizeof *u, cmp_tooth);
        for (k = 0, j = 0; k < mt; k++) {
            if (j > 0 && u[k].s0 < u[j - 1].s1) {
                c->st->corners_left_out++;
                continue;
            }
            u[j++] = u[k];
        }
        c->st->support_corners += j;
        if (j)
            rc = insert_teeth(c->ps, i, c->cl[i], u, j, scratch, err);
        amp_free(c->al, u);
    }
    return rc;
}

amp_status amp_cp_support_corners(amp_pathset *ps, size_t nperim, const amp_pathset *bare, double r, double covered,
                                  amp_contpath_stats *st, amp_error *err)
{
    corner_ctx c;
    size_t i;
    amp_pathset scratch;
    amp_status rc;
    if (nperim == 0 || bare->npaths == 0)
        return AMP_OK;
    memset(&c, 0, sizeof c);
    c.al = ps->alloc;
    c.ps = ps;
    c.nperim = nperim;
    c.r = r;
    c.covered = covered;
    c.st = st;
    amp_pathset_init(&scratch, c.al);
    if (sg_build(&c.sg, ps, 2 * r, c.al) != AMP_OK || legs_init(&c) != AMP_OK ||
        !(c.cl = amp_calloc(c.al, nperim, sizeof *c.cl))) {
        amp_free(c.al, c.sg.start);
        amp_free(c.al, c.sg.item);
        amp_free(c.al, c.leg_head);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory adding support corners");
    }
    if ((rc = perimeter_lengths(&c, err)) == AMP_OK && (rc = stretch_corners(&c, bare, err)) == AMP_OK)
        rc = build_corners(&c, &scratch, err);
    for (i = 0; i < nperim; i++)
        amp_free(c.al, c.cl[i]);
    amp_free(c.al, c.cl);
    amp_free(c.al, c.t);
    amp_free(c.al, c.legs);
    amp_free(c.al, c.leg_head);
    amp_free(c.al, c.leg_next);
    amp_free(c.al, c.sg.start);
    amp_free(c.al, c.sg.item);
    amp_pathset_free(&scratch);
    return rc;
}
