/* Material deposition radius (paper §5.2, Def. 5.4): simultaneous growth of fragment tubes. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "ampath/mdr.h"
#include "ampath/order.h"
#include "heap.h"

void amp_mdr_opts_default(amp_mdr_opts *o, double nominal)
{
    o->nominal = nominal;
    o->r_min = 0.5 * nominal;
    o->r_max = 1.5 * nominal;
    o->fragment = nominal;
    o->progress = NULL;
    o->progress_user = NULL;
}

/* Squared distance between segments [p1,q1] and [p2,q2] (closest points of two segments, clamped). */
static double seg_seg_dist2(amp_vec3 p1, amp_vec3 q1, amp_vec3 p2, amp_vec3 q2)
{
    amp_vec3 d1 = amp_v3_sub(q1, p1), d2 = amp_v3_sub(q2, p2), r = amp_v3_sub(p1, p2);
    double a = amp_v3_dot(d1, d1), e = amp_v3_dot(d2, d2), f = amp_v3_dot(d2, r), s, t;
    if (a <= 1e-300 && e <= 1e-300)
        return amp_v3_len2(r);
    if (a <= 1e-300) {
        s = 0.0;
        t = f / e;
        t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    } else {
        double c = amp_v3_dot(d1, r);
        if (e <= 1e-300) {
            t = 0.0;
            s = -c / a;
            s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
        } else {
            double b = amp_v3_dot(d1, d2), den = a * e - b * b;
            s = den > 1e-300 ? (b * f - c * e) / den : 0.0;
            s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = -c / a;
                s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
            } else if (t > 1.0) {
                t = 1.0;
                s = (b - c) / a;
                s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
            }
        }
    }
    return amp_v3_dist2(amp_v3_madd(p1, d1, s), amp_v3_madd(p2, d2, t));
}

static double frag_dist(const amp_fragments *fs, size_t a, size_t b)
{
    const amp_fragment *fa = &fs->frag[a], *fb = &fs->frag[b];
    double best = HUGE_VAL;
    size_t i, j;
    for (i = 0; i + 1 < amp_fragment_npoints(fa); i++)
        for (j = 0; j + 1 < amp_fragment_npoints(fb); j++) {
            double d = seg_seg_dist2(amp_fragment_point(fs, fa, i), amp_fragment_point(fs, fa, i + 1),
                                     amp_fragment_point(fs, fb, j), amp_fragment_point(fs, fb, j + 1));
            best = d < best ? d : best;
        }
    return sqrt(best);
}

static double frag_length(const amp_fragments *fs, size_t f)
{
    double len = 0.0;
    size_t k;
    for (k = 0; k + 1 < amp_fragment_npoints(&fs->frag[f]); k++)
        len += amp_v3_dist(amp_fragment_point(fs, &fs->frag[f], k), amp_fragment_point(fs, &fs->frag[f], k + 1));
    return len;
}

/* A uniform grid of points (fragment centres or segment ids) in counting-sort layout. */
typedef struct ugrid {
    amp_box3 box;
    double cell;
    size_t nx, ny, nz;
    size_t *start; /* nx*ny*nz + 1 */
    uint32_t *item;
} ugrid;

static size_t cell_of(const ugrid *g, amp_vec3 p, size_t *ix, size_t *iy, size_t *iz)
{
    double fx = floor((p.x - g->box.min.x) / g->cell), fy = floor((p.y - g->box.min.y) / g->cell),
           fz = floor((p.z - g->box.min.z) / g->cell);
    *ix = fx < 0 ? 0 : (fx >= (double)g->nx ? g->nx - 1 : (size_t)fx);
    *iy = fy < 0 ? 0 : (fy >= (double)g->ny ? g->ny - 1 : (size_t)fy);
    *iz = fz < 0 ? 0 : (fz >= (double)g->nz ? g->nz - 1 : (size_t)fz);
    return (*iz * g->ny + *iy) * g->nx + *ix;
}

static amp_status ugrid_build(ugrid *g, const amp_allocator *a, const amp_vec3 *pts, size_t n, double cell,
                              amp_error *err)
{
    size_t i, ncell, ix, iy, iz;
    memset(g, 0, sizeof *g);
    g->box = amp_box3_empty();
    for (i = 0; i < n; i++)
        g->box = amp_box3_add(g->box, pts[i]);
    if (n == 0)
        g->box.min = g->box.max = amp_v3(0, 0, 0);
    for (;;) {
        amp_vec3 sz = amp_box3_size(g->box);
        g->cell = cell;
        g->nx = (size_t)(sz.x / cell) + 1;
        g->ny = (size_t)(sz.y / cell) + 1;
        g->nz = (size_t)(sz.z / cell) + 1;
        if ((double)g->nx * (double)g->ny * (double)g->nz <= 8.0 * (double)n + 64.0)
            break;
        cell *= 1.5; /* keep the grid linear in the input: coarser cells, more candidates each */
    }
    ncell = g->nx * g->ny * g->nz;
    g->start = amp_calloc(a, ncell + 1, sizeof *g->start);
    g->item = amp_calloc(a, n ? n : 1, sizeof *g->item);
    if (!g->start || !g->item)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for a grid of %lu cells", (unsigned long)ncell);
    for (i = 0; i < n; i++)
        g->start[cell_of(g, pts[i], &ix, &iy, &iz) + 1]++;
    for (i = 0; i < ncell; i++)
        g->start[i + 1] += g->start[i];
    {
        size_t *fill = amp_calloc(a, ncell + 1, sizeof *fill);
        if (!fill)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for a grid");
        memcpy(fill, g->start, (ncell + 1) * sizeof *fill);
        for (i = 0; i < n; i++)
            g->item[fill[cell_of(g, pts[i], &ix, &iy, &iz)]++] = (uint32_t)i;
        amp_free(a, fill);
    }
    return AMP_OK;
}

static void ugrid_free(ugrid *g, const amp_allocator *a)
{
    amp_free(a, g->start);
    amp_free(a, g->item);
}

typedef struct hent {
    double key;
    uint32_t f;
} hent;

/* lib/heap.h's rule (strictly better moves) keeps the order of equal keys a function of the pushes and pops */
static int hent_better(const void *a, const void *b, const void *ctx)
{
    (void)ctx;
    return ((const hent *)a)->key < ((const hent *)b)->key;
}

/*
 * Which neighbour pairs can matter (§5.2 growth). A pair at distance d stops a tube at d/2 when both grow,
 * at d - r' when the other one stopped first at r'; that r' is at most max(d/2, r_min) (the other tube
 * stopped while this one still grew, then was raised to r_min). So the pair's event lies in
 * [min(d/2, d - r_min), max(d/2, d - r_min)]. A tube stops by U = min(r_max, min over its pairs of the upper
 * end), and a pair whose lower end exceeds U can never stop it: only d <= max(2U, U + r_min) is kept. The
 * growth over the kept pairs is exactly the growth over all pairs within 2 r_max, with a bounded number of
 * neighbours per tube instead of every fragment within 2 r_max (57 M pairs at eps 0.5 on the helix).
 */
/* What a neighbour search reads of a candidate, in the grid's item order: a search runs along consecutive
 * entries of each row of cells, and most candidates are turned away by these alone (a load of the fragment
 * itself, far away in memory, was most of the search's time). */
typedef struct gtube {
    amp_vec3 ctr;
    double rho;
    amp_box3 box;
    uint32_t f, path;
} gtube;

typedef struct mdr_ctx {
    const amp_allocator *a;
    const amp_fragments *fs;
    const amp_mdr_opts *o;
    ugrid g;
    amp_vec3 *ctr;
    gtube *gt;      /* the candidates in the grid's item order */
    double *rho;   /* half the box diagonal: every point of the fragment is this close to its centre */
    double *arc;   /* arc length at each fragment's end along its path */
    double rho_max, reach;
    amp_error *err;
} mdr_ctx;

static double pair_upper(const mdr_ctx *c, double d) { return fmax(0.5 * d, d - c->o->r_min); }

/* Fragments i and j (of path pj) may be neighbours at all: along one path only parts further apart than
 * 2 r_max count. */
static int pair_allowed(const mdr_ctx *c, uint32_t i, uint32_t j, uint32_t pj)
{
    const amp_fragments *fs = c->fs;
    if (i == j)
        return 0;
    if (fs->frag[i].path == pj) {
        uint32_t lo = i < j ? i : j, hi = i < j ? j : i;
        return c->arc[hi - 1] - c->arc[lo] >= c->reach;
    }
    return 1;
}

/* One tube's neighbour search: the bound U so far, the distance kept (max(2U, U + r_min)), the ball already
 * searched, and where the kept neighbours go (a caller's buffer; overflow is flagged, not grown, so that the
 * search may run on any thread without allocating). */
typedef struct scan_state {
    double u, cut, done_r;
    uint32_t *other;
    double *dist;
    size_t n, cap;
    int overflow;
} scan_state;

static double cut_of(const mdr_ctx *c, double u) { return fmin(c->reach, fmax(2.0 * u, u + c->o->r_min)); }

/* Squared distance between two boxes: a lower bound of the fragments' distance. */
static double box_dist2(const amp_box3 *a, const amp_box3 *b)
{
    double gx = a->min.x - b->max.x, gy = a->min.y - b->max.y, gz = a->min.z - b->max.z;
    double hx = b->min.x - a->max.x, hy = b->min.y - a->max.y, hz = b->min.z - a->max.z;
    gx = gx > hx ? gx : hx;
    gy = gy > hy ? gy : hy;
    gz = gz > hz ? gz : hz;
    gx = gx > 0.0 ? gx : 0.0;
    gy = gy > 0.0 ? gy : 0.0;
    gz = gz > 0.0 ? gz : 0.0;
    return gx * gx + gy * gy + gz * gz;
}

/* Candidate t (grid entry) of tube i (box @p bi) at squared centre distance d2; returns 1 when the buffer
 * overflowed. */
static int scan_visit(mdr_ctx *c, uint32_t i, const amp_box3 *bi, const gtube *t, double d2, scan_state *s)
{
    uint32_t j = t->f;
    double d, far = s->cut + c->rho[i] + t->rho;
    /* the centre bound sqrt(d2) - rho_i - rho_j > cut; its square root only near the bound (a margin of
     * 2e-9 relative keeps the skipped cases far from rounding) */
    if (!(d2 < far * far * (1.0 - 2e-9)) && sqrt(d2) - c->rho[i] - t->rho > s->cut)
        return 0;
    if (box_dist2(bi, &t->box) > s->cut * s->cut || !pair_allowed(c, i, j, t->path))
        return 0;
    d = frag_dist(c->fs, i, j);
    if (d >= c->reach)
        return 0;
    if (pair_upper(c, d) < s->u) {
        s->u = pair_upper(c, d);
        s->cut = cut_of(c, s->u);
    }
    if (d <= s->cut) {
        if (s->n == s->cap) {
            s->overflow = 1;
            return 1;
        }
        s->other[s->n] = j;
        s->dist[s->n++] = d;
    }
    return 0;
}

/* Call scan_visit for the fragments whose centres lie within @p R of fragment i's centre and beyond @p skip_r
 * (cells in z-y-x order of a box, items in grid order); stops when it reports an overflow. */
static void for_near(mdr_ctx *c, uint32_t i, double R, double skip_r, scan_state *st)
{
    const ugrid *g = &c->g;
    const amp_box3 *bi = &c->fs->frag[i].box;
    amp_vec3 p = c->ctr[i];
    size_t x0, y0, z0, x1, y1, z1, y, z;
    double R2 = R * R, s2 = skip_r > 0.0 ? skip_r * skip_r : -1.0;
    cell_of(g, amp_v3(p.x - R, p.y - R, p.z - R), &x0, &y0, &z0);
    cell_of(g, amp_v3(p.x + R, p.y + R, p.z + R), &x1, &y1, &z1);
    for (z = z0; z <= z1; z++)
        for (y = y0; y <= y1; y++) {
            /* the cells of one row are consecutive in the grid's item order, as the candidates in gt */
            size_t row = (z * g->ny + y) * g->nx, q, qe = g->start[row + x1 + 1];
            for (q = g->start[row + x0]; q < qe; q++) {
                const gtube *t = &c->gt[q];
                double dx = t->ctr.x - p.x, dy = t->ctr.y - p.y, dz = t->ctr.z - p.z;
                double d2 = dx * dx + dy * dy + dz * dz;
                if (d2 <= R2 && d2 > s2 && scan_visit(c, i, bi, t, d2, st))
                    return;
            }
        }
}

/* The neighbours tube i keeps (d <= max(2U, U + r_min)), searched in growing balls: every fragment within
 * d of i has its centre within d + rho_i + rho_max, so the search ends once the ball reaches that for the
 * current distance kept. Returns 0 on buffer overflow. */
static int scan_tube(mdr_ctx *c, uint32_t i, scan_state *s)
{
    double R = 0.5 * c->o->nominal + c->rho[i] + c->rho_max, need;
    size_t k, m = 0;
    s->u = c->o->r_max;
    s->cut = c->reach;
    s->done_r = -1.0;
    s->n = 0;
    s->overflow = 0;
    for (;;) {
        for_near(c, i, R, s->done_r, s);
        if (s->overflow)
            return 0;
        need = s->cut + c->rho[i] + c->rho_max;
        if (R >= need)
            break;
        s->done_r = R;
        R = need;
    }
    for (k = 0; k < s->n; k++)
        if (s->dist[k] <= s->cut) {
            s->other[m] = s->other[k];
            s->dist[m++] = s->dist[k];
        }
    s->n = m;
    return 1;
}

/* Neighbour lists in compressed rows: tube i keeps other[row[i] .. row[i+1]-1] (the pairs that can stop it,
 * with their distances); rother[rrow[i] ..] are the tubes that keep i (those i's stop may concern). */
typedef struct nbrs {
    size_t *row, *rrow;
    uint32_t *other, *rother;
    double *dist;
    uint32_t *ridx; /* dist[ridx[k]] is the distance of reverse entry k (not a copy: 4 bytes a pair less) */
    size_t n, cap;
} nbrs;

static amp_status nbrs_append(mdr_ctx *c, nbrs *nb, const uint32_t *other, const double *dist, size_t n)
{
    if (n == 0)
        return AMP_OK;
    if (nb->n + n > nb->cap) {
        void *p = nb->other, *q = nb->dist;
        size_t cap = nb->cap;
        if (amp_grow(c->a, &p, &cap, nb->n + n, sizeof *nb->other) != AMP_OK)
            return AMP_ERR_NOMEM;
        nb->other = p;
        cap = nb->cap;
        if (amp_grow(c->a, &q, &cap, nb->n + n, sizeof *nb->dist) != AMP_OK)
            return AMP_ERR_NOMEM;
        nb->dist = q;
        nb->cap = cap;
    }
    memcpy(nb->other + nb->n, other, n * sizeof *other);
    memcpy(nb->dist + nb->n, dist, n * sizeof *dist);
    nb->n += n;
    return AMP_OK;
}

#define SCAN_CHUNK 16384
#define SCAN_PER_TUBE 32

/* The reverse lists (who keeps whom), by counting. */
static amp_status nbrs_reverse(mdr_ctx *c, nbrs *nb)
{
    size_t i, q, nf = c->fs->n, *fill;
    nb->rrow = amp_calloc(c->a, nf + 1, sizeof *nb->rrow);
    nb->rother = amp_calloc(c->a, nb->n + 1, sizeof *nb->rother);
    if (nb->n > UINT32_MAX) /* 48 GB of pairs: no allocation of that size succeeds here */
        return AMP_ERR_NOMEM;
    nb->ridx = amp_calloc(c->a, nb->n + 1, sizeof *nb->ridx);
    fill = amp_calloc(c->a, nf + 1, sizeof *fill);
    if (!nb->rrow || !nb->rother || !nb->ridx || !fill) {
        amp_free(c->a, fill);
        return AMP_ERR_NOMEM;
    }
    for (q = 0; q < nb->n; q++)
        nb->rrow[nb->other[q] + 1]++;
    for (i = 0; i < nf; i++)
        nb->rrow[i + 1] += nb->rrow[i];
    memcpy(fill, nb->rrow, (nf + 1) * sizeof *fill);
    for (i = 0; i < nf; i++)
        for (q = nb->row[i]; q < nb->row[i + 1]; q++) {
            size_t at = fill[nb->other[q]]++;
            nb->rother[at] = (uint32_t)i;
            nb->ridx[at] = (uint32_t)q;
        }
    amp_free(c->a, fill);
    return AMP_OK;
}

/*
 * Every tube's kept neighbours. Tubes are searched in chunks of SCAN_CHUNK (few parallel regions), in parallel
 * (OpenMP): each search writes into a fixed slice of a buffer allocated beforehand, and the chunk is appended
 * in tube order afterwards, so the lists are the same whatever the thread count. A tube whose slice
 * overflows is searched again alone.
 */
static amp_status find_neighbours(mdr_ctx *c, nbrs *nb)
{
    size_t nf = c->fs->n, base, slot = SCAN_CHUNK * SCAN_PER_TUBE;
    uint32_t *bo = amp_calloc(c->a, slot, sizeof *bo);
    double *bd = amp_calloc(c->a, slot, sizeof *bd);
    size_t *cnt = amp_calloc(c->a, SCAN_CHUNK, sizeof *cnt);
    amp_status st = AMP_OK;
    nb->row = amp_calloc(c->a, nf + 1, sizeof *nb->row);
    if (!bo || !bd || !cnt || !nb->row)
        st = AMP_ERR_NOMEM;
    for (base = 0; base < nf && st == AMP_OK; base += SCAN_CHUNK) {
        long k, m = (long)(nf - base < SCAN_CHUNK ? nf - base : SCAN_CHUNK);
        if (c->o->progress)
            c->o->progress(c->o->progress_user, 0.5 * (double)base / (double)nf);
#pragma omp parallel for schedule(dynamic, 16)
        for (k = 0; k < m; k++) {
            scan_state s;
            s.other = bo + (size_t)k * SCAN_PER_TUBE;
            s.dist = bd + (size_t)k * SCAN_PER_TUBE;
            s.cap = SCAN_PER_TUBE;
            cnt[k] = scan_tube(c, (uint32_t)(base + (size_t)k), &s) ? s.n : (size_t)-1;
        }
        for (k = 0; k < m && st == AMP_OK; k++) {
            size_t i = base + (size_t)k;
            if (cnt[k] == (size_t)-1) {
                /* a crowded tube: search again with room for every candidate */
                scan_state s;
                size_t cap = SCAN_PER_TUBE;
                memset(&s, 0, sizeof s);
                do {
                    amp_free(c->a, s.other);
                    amp_free(c->a, s.dist);
                    cap *= 4;
                    s.other = amp_calloc(c->a, cap, sizeof *s.other);
                    s.dist = amp_calloc(c->a, cap, sizeof *s.dist);
                    s.cap = cap;
                } while (s.other && s.dist && !scan_tube(c, (uint32_t)i, &s));
                st = s.other && s.dist ? nbrs_append(c, nb, s.other, s.dist, s.n) : AMP_ERR_NOMEM;
                amp_free(c->a, s.other);
                amp_free(c->a, s.dist);
            } else {
                st = nbrs_append(c, nb, bo + (size_t)k * SCAN_PER_TUBE, bd + (size_t)k * SCAN_PER_TUBE, cnt[k]);
            }
            nb->row[i + 1] = nb->n;
        }
    }
    amp_free(c->a, bo);
    amp_free(c->a, bd);
    amp_free(c->a, cnt);
    if (st == AMP_OK && nb->n > 0 && nb->n < nb->cap) {
        /* the lists grew by doubling: give the slack back before the reverse lists raise the peak (a failed
         * shrink keeps the blocks) */
        uint32_t *o = amp_realloc_array(c->a, nb->other, nb->n, sizeof *nb->other);
        double *d;
        if (o)
            nb->other = o;
        d = amp_realloc_array(c->a, nb->dist, nb->n, sizeof *nb->dist);
        if (d)
            nb->dist = d;
        if (o && d)
            nb->cap = nb->n;
    }
    if (st == AMP_OK)
        st = nbrs_reverse(c, nb);
    return st == AMP_OK ? AMP_OK : amp_fail(c->err, AMP_ERR_NOMEM, 0, "out of memory for tube neighbours");
}

/* The tube's stopping radius now: the earliest event over its pairs (d/2 with a growing neighbour, d - r'
 * with one stopped at r'), at most r_max. */
static double tube_key(const mdr_ctx *c, const nbrs *nb, const unsigned char *frozen, const double *r, size_t f)
{
    double key = c->o->r_max;
    size_t q;
    for (q = nb->row[f]; q < nb->row[f + 1]; q++)
        key = fmin(key, frozen[nb->other[q]] ? nb->dist[q] - r[nb->other[q]] : 0.5 * nb->dist[q]);
    return key;
}

/* §5.2: all tubes grow together, event by event. A tube's key only rises when a neighbour stops at r' <= d/2,
 * so it is recomputed when popped (and pushed back if it rose); a neighbour raised to r_min may lower it,
 * and only then is it pushed again. */
static amp_status grow(mdr_ctx *c, const nbrs *nb, double *r, unsigned char *frozen, double *sched,
                       amp_mdr_stats *s)
{
    const amp_mdr_opts *o = c->o;
    size_t i, nfrozen = 0, n = c->fs->n;
    amp_heap heap;
    hent e;
    amp_status st = AMP_OK;
    amp_heap_init(&heap, c->a, sizeof(hent), hent_better, NULL);
    for (i = 0; i < n && st == AMP_OK; i++) {
        if (nb->row[i] == nb->row[i + 1]) {
            frozen[i] = 1;
            r[i] = fmin(fmax(o->nominal, o->r_min), o->r_max);
            s->isolated++;
            continue;
        }
        sched[i] = tube_key(c, nb, frozen, r, i);
        e.key = sched[i];
        e.f = (uint32_t)i;
        st = amp_heap_push(&heap, &e);
    }
    while (st == AMP_OK && amp_heap_pop(&heap, &e)) {
        size_t q;
        double key;
        if (frozen[e.f] || e.key != sched[e.f])
            continue;
        key = tube_key(c, nb, frozen, r, e.f);
        if (key > e.key * (1 + 1e-12) + 1e-15) {
            /* a neighbour stopped earlier, so this tube touches it later than the pair's midpoint */
            sched[e.f] = e.key = key;
            st = amp_heap_push(&heap, &e);
            continue;
        }
        frozen[e.f] = 1;
        if (o->progress && (++nfrozen & 4095) == 0)
            o->progress(o->progress_user, 0.5 + 0.5 * (double)nfrozen / (double)n);
        if (key >= o->r_max)
            s->at_max++;
        if (key < o->r_min * (1 - 1e-9))
            s->at_min++;
        r[e.f] = fmin(fmax(key, o->r_min), o->r_max);
        for (q = nb->rrow[e.f]; q < nb->rrow[e.f + 1] && st == AMP_OK; q++) {
            uint32_t nbo = nb->rother[q];
            double ev = fmax(0.0, nb->dist[nb->ridx[q]] - r[e.f]);
            if (!frozen[nbo] && ev < sched[nbo]) {
                hent nev;
                nev.key = sched[nbo] = ev;
                nev.f = nbo;
                st = amp_heap_push(&heap, &nev);
            }
        }
    }
    amp_heap_free(&heap);
    return st == AMP_OK ? AMP_OK : amp_fail(c->err, AMP_ERR_NOMEM, 0, "out of memory for the growth queue");
}

/* Output: cut points become vertices; a cut point takes the smaller radius of its two fragments. */
static amp_status mdr_emit(const amp_fragments *fs, const amp_pathset *in, const double *r, amp_pathset *out,
                           amp_mdr_stats *s, amp_error *err)
{
    amp_status stt = AMP_OK;
    size_t i;
    s->r_lo = HUGE_VAL;
    s->r_hi = 0.0;
    for (i = 0; i < in->npaths && stt == AMP_OK; i++) {
        size_t f;
        if (in->paths[i].n == 0)
            continue;
        stt = amp_pathset_begin(out, in->paths[i].role, err);
        for (f = fs->first[i]; stt == AMP_OK && f < fs->first[i + 1]; f++) {
            const amp_fragment *fr = &fs->frag[f];
            size_t q;
            s->r_lo = fmin(s->r_lo, r[f]);
            s->r_hi = fmax(s->r_hi, r[f]);
            if (f == fs->first[i])
                stt = amp_pathset_push(out, fr->p0, r[f], err);
            /* a cut point within a nanometre of a vertex is that vertex (its smaller radius) */
            for (q = 0; stt == AMP_OK && q < fr->nin; q++)
                stt = amp_pathset_push_merged(out, in->verts[fr->vfirst + q].p, r[f], AMP_PATH_SAME_POINT, 0, err);
            if (stt == AMP_OK && in->paths[i].n > 1)
                stt = amp_pathset_push_merged(out, fr->p1, f + 1 < fs->first[i + 1] ? fmin(r[f], r[f + 1]) : r[f],
                                              AMP_PATH_SAME_POINT, f + 1 == fs->first[i + 1], err);
        }
    }
    if (stt == AMP_OK)
        s->deposited = amp_pathset_volume(out, -1);
    if (fs->n == 0)
        s->r_lo = 0.0;
    return stt;
}

amp_status amp_mdr(const amp_pathset *in, const amp_mdr_opts *o, amp_pathset *out, amp_mdr_stats *st,
                   amp_error *err)
{
    const amp_allocator *a;
    amp_fragments fs;
    amp_mdr_stats s;
    mdr_ctx c;
    nbrs nb;
    size_t i;
    double *r = NULL, *sched = NULL;
    unsigned char *frozen = NULL;
    amp_status stt;
    if (!in || !o || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mdr: NULL argument");
    a = out->alloc;
    memset(&s, 0, sizeof s);
    memset(&c, 0, sizeof c);
    memset(&nb, 0, sizeof nb);
    if (!(o->nominal > 0.0) || !isfinite(o->nominal) || !(o->fragment > 0.0) || !isfinite(o->fragment))
        return amp_fail(err, AMP_ERR_RANGE, 0, "nominal radius and fragment length must be positive (got %g, %g)",
                        o->nominal, o->fragment);
    if (!(o->r_min >= 0.0) || !(o->r_max >= o->r_min) || !isfinite(o->r_max))
        return amp_fail(err, AMP_ERR_RANGE, 0, "need 0 <= r_min <= r_max (got %g, %g)", o->r_min, o->r_max);
    if ((stt = amp_fragments_build(&fs, in, o->fragment, a, err)) != AMP_OK)
        return stt;
    s.fragments = fs.n;
    c.a = a;
    c.fs = &fs;
    c.o = o;
    c.err = err;
    c.reach = 2.0 * o->r_max;
    c.ctr = amp_calloc(a, fs.n ? fs.n : 1, sizeof *c.ctr);
    c.rho = amp_calloc(a, fs.n ? fs.n : 1, sizeof *c.rho);
    c.arc = amp_calloc(a, fs.n ? fs.n : 1, sizeof *c.arc);
    r = amp_calloc(a, fs.n ? fs.n : 1, sizeof *r);
    sched = amp_calloc(a, fs.n ? fs.n : 1, sizeof *sched);
    frozen = amp_calloc(a, fs.n ? fs.n : 1, 1);
    if (!c.ctr || !c.rho || !c.arc || !r || !sched || !frozen) {
        stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for %lu tubes", (unsigned long)fs.n);
        goto done;
    }
    for (i = 0; i < fs.n; i++) {
        c.ctr[i] = amp_box3_center(fs.frag[i].box);
        c.rho[i] = 0.5 * amp_v3_len(amp_box3_size(fs.frag[i].box));
        c.rho_max = fmax(c.rho_max, c.rho[i]);
        c.arc[i] = (i > 0 && fs.frag[i - 1].path == fs.frag[i].path ? c.arc[i - 1] : 0.0) + frag_length(&fs, i);
    }
    /* cells about a fragment long: the searches reach only a few cells beyond the nearest neighbour */
    if ((stt = ugrid_build(&c.g, a, c.ctr, fs.n, fmax(o->fragment, 2.0 * c.rho_max), err)) != AMP_OK)
        goto done;
    c.gt = amp_calloc(a, fs.n ? fs.n : 1, sizeof *c.gt);
    if (!c.gt) {
        stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for %lu tubes", (unsigned long)fs.n);
        goto done;
    }
    for (i = 0; i < fs.n; i++) {
        uint32_t f = c.g.item[i];
        c.gt[i].ctr = c.ctr[f];
        c.gt[i].rho = c.rho[f];
        c.gt[i].box = fs.frag[f].box;
        c.gt[i].f = f;
        c.gt[i].path = fs.frag[f].path;
    }
    if ((stt = find_neighbours(&c, &nb)) != AMP_OK)
        goto done;
    s.pairs = nb.n;
    if ((stt = grow(&c, &nb, r, frozen, sched, &s)) != AMP_OK)
        goto done;
    stt = mdr_emit(&fs, in, r, out, &s, err);
    if (stt == AMP_OK && st)
        *st = s;
done:
    ugrid_free(&c.g, a);
    amp_free(a, c.ctr);
    amp_free(a, c.gt);
    amp_free(a, c.rho);
    amp_free(a, c.arc);
    amp_free(a, nb.row);
    amp_free(a, nb.other);
    amp_free(a, nb.dist);
    amp_free(a, nb.rrow);
    amp_free(a, nb.rother);
    amp_free(a, nb.ridx);
    amp_free(a, r);
    amp_free(a, sched);
    amp_free(a, frozen);
    amp_fragments_free(&fs);
    return stt;
}

amp_status amp_tubes_union_volume(const amp_pathset *ps, size_t samples, double *volume, amp_error *err)
{
    const amp_allocator *a;
    size_t i, k, nseg = 0, hits = 0, s;
    double rmax = 0.0, maxlen = 0.0;
    amp_vec3 *mid = NULL;
    size_t *segv = NULL;
    ugrid g;
    amp_box3 box;
    uint64_t x = 0x9e3779b97f4a7c15ULL;
    amp_status st;
    if (!ps || !volume)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_tubes_union_volume: NULL argument");
    a = ps->alloc;
    memset(&g, 0, sizeof g);
    *volume = 0.0;
    for (i = 0; i < ps->npaths; i++)
        nseg += ps->paths[i].n > 1 ? ps->paths[i].n - 1 : 0;
    if (nseg == 0 || samples == 0)
        return AMP_OK;
    mid = amp_calloc(a, nseg, sizeof *mid);
    segv = amp_calloc(a, nseg, sizeof *segv);
    if (!mid || !segv) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the volume estimate");
        goto done;
    }
    for (i = 0, s = 0; i < ps->npaths; i++)
        for (k = 0; k + 1 < ps->paths[i].n; k++, s++) {
            const amp_pvert *v = amp_pathset_path_verts(ps, i) + k;
            segv[s] = ps->paths[i].first + k;
            mid[s] = amp_v3_lerp(v[0].p, v[1].p, 0.5);
            rmax = fmax(rmax, fmax(v[0].r, v[1].r));
            maxlen = fmax(maxlen, amp_v3_dist(v[0].p, v[1].p));
        }
    if (rmax <= 0.0) {
        st = AMP_OK;
        goto done;
    }
    if ((st = ugrid_build(&g, a, mid, nseg, 2 * rmax + maxlen, err)) != AMP_OK)
        goto done;
    box = amp_box3_inflate(amp_pathset_bbox(ps), rmax);
    for (k = 0; k < samples; k++) {
        amp_vec3 p, sz = amp_box3_size(box);
        size_t ix, iy, iz, cx, cy, cz, found = 0;
        double u[3];
        int d;
        for (d = 0; d < 3; d++) {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            u[d] = (double)(x >> 11) / 9007199254740992.0;
        }
        p = amp_v3(box.min.x + u[0] * sz.x, box.min.y + u[1] * sz.y, box.min.z + u[2] * sz.z);
        cell_of(&g, p, &ix, &iy, &iz);
        for (cz = iz ? iz - 1 : 0; !found && cz <= iz + 1 && cz < g.nz; cz++)
            for (cy = iy ? iy - 1 : 0; !found && cy <= iy + 1 && cy < g.ny; cy++)
                for (cx = ix ? ix - 1 : 0; !found && cx <= ix + 1 && cx < g.nx; cx++) {
                    size_t c = (cz * g.ny + cy) * g.nx + cx, q;
                    for (q = g.start[c]; !found && q < g.start[c + 1]; q++) {
                        const amp_pvert *v = &ps->verts[segv[g.item[q]]];
                        double rr = fmax(v[0].r, v[1].r);
                        found = amp_v3_seg_dist2(p, v[0].p, v[1].p, NULL) <= rr * rr;
                    }
                }
        hits += found;
    }
    {
        amp_vec3 sz = amp_box3_size(box);
        *volume = sz.x * sz.y * sz.z * (double)hits / (double)samples;
    }
    st = AMP_OK;
done:
    ugrid_free(&g, a);
    amp_free(a, mid);
    amp_free(a, segv);
    return st;
}
