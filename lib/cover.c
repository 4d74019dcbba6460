/*
 * Volumetric covering (paper 1 §4.1): Algorithm 1 CoverVolumeWithSurfaces over
 * a trivariate, then each (trimmed) iso-surface covered by adaptive iso-curves
 * (Elber & Cohen [17]: boundary curves, then intermediate curves recursively
 * where a neighbouring pair does not cover), then adaptive flattening. The
 * error budget and the two measures are described in include/ampath/cover.h.
 */
#include <math.h>
#include <string.h>

#include "ampath/cover.h"
#include "spline_internal.h"

void amp_cover_opts_default(amp_cover_opts *o)
{
    o->eps = 1.0;
    o->dir = AMP_COVER_AUTO;
    o->min_depth = 0;
    o->measure = AMP_COVER_ARCLEN;
    o->radius = 0.5;
    o->chord_tol = 0.0;
    o->cells = 16;
    o->max_depth = 24;
    o->progress = NULL;
    o->progress_user = NULL;
}

double amp_over_coverage(const amp_pathset *ps, double model_volume)
{
    if (!ps || !(model_volume > 0.0) || !isfinite(model_volume))
        return NAN;
    return amp_pathset_volume(ps, AMP_ROLE_OBJECT) / model_volume;
}

typedef struct ctx {
    const amp_spline *v; /* the trivariate */
    amp_spline ref;      /* v with every cell boundary of the two surface directions as a knot (arc-length bounds) */
    amp_cover_opts o;
    int d, e0, e1, G;    /* d: the paper's w; surfaces are (e0, e1); curves run along e1 */
    double thr, delta;   /* neighbours must be within thr; delta: chordal tolerance */
    double lo[3], hi[3];
    size_t blo[3][64], bhi[3][64]; /* control-index range of each cell, per direction, in ref */
    amp_pathset *out;
    amp_cover_stats st;
    amp_error *err;
} ctx;

static double cell_b(const ctx *c, int e, int i) { return c->lo[e] + (c->hi[e] - c->lo[e]) * (double)i / c->G; }

/* ---- bounds from the control net (Appendix, Lemma A.2 restricted to a block of cells) ---- */

/*
 * Bound on the arc length of the direction-@p dd isoparametric curves of the
 * slab @p s whose other parameters lie in the given control-index blocks: sum
 * over segments k of the max over the block of |P_{k+1} - P_k|, with the
 * rational correction of amp_spline_polygon_length_bound().
 */
static double block_bound(const amp_spline *s, int dd, const size_t *ilo, const size_t *ihi)
{
    size_t k, n = s->count[dd], idx[3];
    double total = 0;
    int a = dd == 0 ? 1 : 0, b = dd == 2 ? 1 : 2;
    if (s->dim == 2)
        b = -1;
    for (k = 0; k + 1 < n; k++) {
        double mx = 0, rmin = HUGE_VAL, rmax = 0, R = 0, cnt = 0;
        amp_vec3 cen = amp_v3(0, 0, 0);
        size_t i, j, jlo = b >= 0 ? ilo[b] : 0, jhi = b >= 0 ? ihi[b] : 0;
        for (j = jlo; j <= jhi; j++)
            for (i = ilo[a]; i <= ihi[a]; i++) {
                double w0, w1;
                size_t i0, i1;
                amp_vec3 p0, p1;
                idx[a] = i;
                if (b >= 0)
                    idx[b] = j;
                idx[dd] = k;
                i0 = amp_spline_index(s, idx[0], s->dim > 1 ? idx[1] : 0, s->dim > 2 ? idx[2] : 0);
                idx[dd] = k + 1;
                i1 = amp_spline_index(s, idx[0], s->dim > 1 ? idx[1] : 0, s->dim > 2 ? idx[2] : 0);
                p0 = amp_spline_cp_get(s, i0, &w0);
                p1 = amp_spline_cp_get(s, i1, &w1);
                mx = fmax(mx, amp_v3_dist(p0, p1));
                rmin = fmin(rmin, w1 / w0);
                rmax = fmax(rmax, w1 / w0);
                cen = amp_v3_add(cen, p0);
                cnt += 1;
            }
        if (s->rational && rmax > rmin) {
            cen = amp_v3_scale(cen, 1.0 / cnt);
            for (j = jlo; j <= jhi; j++)
                for (i = ilo[a]; i <= ihi[a]; i++) {
                    idx[a] = i;
                    if (b >= 0)
                        idx[b] = j;
                    idx[dd] = k;
                    R = fmax(R, amp_v3_dist(cen, amp_spline_cp_get(s, amp_spline_index(s, idx[0], s->dim > 1 ? idx[1] : 0,
                                                                                       s->dim > 2 ? idx[2] : 0),
                                                                   NULL)));
                }
            mx += (rmax / rmin - 1.0) * R;
        }
        total += mx;
    }
    return total;
}

/* The part of @p s between a and b in direction dd (copies when a/b are the domain ends). */
static amp_status slab(const amp_spline *s, int dd, double a, double b, amp_spline *out, amp_error *err)
{
    double lo, hi;
    amp_spline l, r;
    amp_status st;
    amp_spline_domain(s, dd, &lo, &hi);
    if (a <= lo && b >= hi)
        return amp_spline_copy(out, s, s->alloc, err);
    if (a <= lo)
        st = amp_spline_split(s, dd, b, out, &r, err);
    else {
        st = amp_spline_split(s, dd, a, &l, &r, err);
        amp_spline_free(&l);
        if (st != AMP_OK)
            return st;
        if (b >= hi) {
            *out = r;
            return AMP_OK;
        }
        {
            amp_spline mid = r;
            st = amp_spline_split(&mid, dd, b, out, &r, err);
            amp_spline_free(&mid);
        }
    }
    amp_spline_free(&r);
    return st;
}

/* Control-index range [lo, hi] of the basis functions that are non-zero on [a, b) in direction e of s. */
static void index_range(const amp_spline *s, int e, double a, double b, size_t *lo, size_t *hi)
{
    const double *U = s->knots[e];
    int k = s->order[e];
    size_t sa = amp_spl_span(U, k, s->count[e], a, 0), sb = amp_spl_span(U, k, s->count[e], b, 0);
    /* b is an open end: step back from a span starting exactly at b */
    while (sb > sa && U[sb] >= b)
        sb--;
    *lo = sa + 1 - (size_t)k;
    *hi = sb;
}

/* ---- Algorithm 1 measure per trimming cell ---- */

/*
 * need[c0 + G c1] = 1 where cell (c0, c1), active in @p mask, has its
 * neighbours at wl and wh further apart than thr. Returns the count or a negative status.
 */
static long surface_need(ctx *c, const amp_spline *sl, double wl, double wh, const unsigned char *mask,
                         unsigned char *need)
{
    int G = c->G, c0, c1;
    long cnt = 0;
    if (c->o.measure == AMP_COVER_ARCLEN) {
        for (c1 = 0; c1 < G; c1++)
            for (c0 = 0; c0 < G; c0++) {
                size_t ilo[3], ihi[3];
                int i = c0 + G * c1;
                need[i] = 0;
                if (!mask[i])
                    continue;
                ilo[c->e0] = c->blo[c->e0][c0];
                ihi[c->e0] = c->bhi[c->e0][c0];
                ilo[c->e1] = c->blo[c->e1][c1];
                ihi[c->e1] = c->bhi[c->e1][c1];
                /* Lemma A.2 on the cell's block of the slab: every w-curve through the cell is shorter */
                if (block_bound(sl, c->d, ilo, ihi) > c->thr) {
                    need[i] = 1;
                    cnt++;
                }
            }
        return cnt;
    }
    /* iso-distance: |V(.,.,wl) - V(.,.,wh)| on the corners, edge midpoints and centre of each cell */
    {
        int S = 2 * G + 1, a, b;
        for (c1 = 0; c1 < G; c1++)
            for (c0 = 0; c0 < G; c0++) {
                int i = c0 + G * c1;
                double mx = 0;
                need[i] = 0;
                if (!mask[i])
                    continue;
                for (b = 0; b < 3; b++)
                    for (a = 0; a < 3; a++) {
                        double p[3], q[3];
                        amp_vec3 x, y;
                        p[c->e0] = c->lo[c->e0] + (c->hi[c->e0] - c->lo[c->e0]) * (2.0 * c0 + a) / (S - 1);
                        p[c->e1] = c->lo[c->e1] + (c->hi[c->e1] - c->lo[c->e1]) * (2.0 * c1 + b) / (S - 1);
                        memcpy(q, p, sizeof p);
                        p[c->d] = wl;
                        q[c->d] = wh;
                        amp_spline_eval(c->v, p, &x, NULL);
                        amp_spline_eval(c->v, q, &y, NULL);
                        mx = fmax(mx, amp_v3_dist(x, y));
                    }
                if (mx > c->thr) {
                    need[i] = 1;
                    cnt++;
                }
            }
    }
    return cnt;
}

/* ---- curves: flattening and Elber-Cohen covering of one surface ---- */

static amp_vec3 surf_pt(const ctx *c, double w, double s, double t)
{
    double p[3];
    amp_vec3 x;
    p[c->d] = w;
    p[c->e0] = s;
    p[c->e1] = t;
    amp_spline_eval(c->v, p, &x, NULL);
    return x;
}

/* Adaptive flattening of C(t) = V(w, s, t) on [t0, t1]: split while a quarter point is off the chord by > delta. */
static amp_status flatten(ctx *c, double w, double s, double t0, double t1, amp_vec3 p0, amp_vec3 p1, int depth)
{
    static const double f[3] = {0.25, 0.5, 0.75};
    double dev = 0;
    int i;
    amp_vec3 pm = surf_pt(c, w, s, 0.5 * (t0 + t1));
    for (i = 0; i < 3; i++)
        dev = fmax(dev, sqrt(amp_v3_seg_dist2(i == 1 ? pm : surf_pt(c, w, s, t0 + (t1 - t0) * f[i]), p0, p1, NULL)));
    if (dev > c->delta && depth < 16) {
        amp_status st = flatten(c, w, s, t0, 0.5 * (t0 + t1), p0, pm, depth + 1);
        if (st == AMP_OK)
            st = flatten(c, w, s, 0.5 * (t0 + t1), t1, pm, p1, depth + 1);
        return st;
    }
    c->st.vertices++;
    return amp_pathset_push(c->out, p1, c->o.radius, c->err);
}

/* Emit the curve V(w, s, .) over every maximal run of t-cells set in @p cells. */
static amp_status emit_curve(ctx *c, double w, double s, const unsigned char *cells)
{
    int G = c->G, a = 0, b, j;
    while (a < G) {
        amp_status st;
        amp_vec3 p0;
        size_t first;
        if (!cells[a]) {
            a++;
            continue;
        }
        for (b = a; b < G && cells[b]; b++)
            ;
        st = amp_pathset_begin(c->out, AMP_ROLE_OBJECT, c->err);
        if (st != AMP_OK)
            return st;
        first = c->out->nverts;
        p0 = surf_pt(c, w, s, cell_b(c, c->e1, a));
        st = amp_pathset_push(c->out, p0, c->o.radius, c->err);
        c->st.vertices++;
        /* at least two pieces per cell, refined where the chord is off by more than delta */
        for (j = 2 * a; j < 2 * b && st == AMP_OK; j++) {
            double t0 = c->lo[c->e1] + (c->hi[c->e1] - c->lo[c->e1]) * j / (2.0 * G),
                   t1 = c->lo[c->e1] + (c->hi[c->e1] - c->lo[c->e1]) * (j + 1) / (2.0 * G);
            amp_vec3 p1 = surf_pt(c, w, s, t1);
            st = flatten(c, w, s, t0, t1, c->out->verts[c->out->nverts - 1].p, p1, 0);
        }
        if (st != AMP_OK)
            return st;
        {
            size_t k;
            for (k = first + 1; k < c->out->nverts; k++)
                c->st.length += amp_v3_dist(c->out->verts[k - 1].p, c->out->verts[k].p);
        }
        c->st.curves++;
        a = b;
    }
    return AMP_OK;
}

typedef struct surf {
    double w;
    const unsigned char *mask; /* G x G: c0 + G c1 */
    amp_spline s;              /* iso-surface of ref at w (arc-length bounds) */
} surf;

/* t-cells (subset of @p A) whose s-neighbours at sa, sb are further apart than thr; returns the count. */
static int curve_need(ctx *c, surf *S, double sa, double sb, const unsigned char *A, unsigned char *N)
{
    int G = c->G, c0, c1, cnt = 0;
    amp_spline sl;
    int have = 0;
    for (c1 = 0; c1 < G; c1++) {
        int active = 0;
        N[c1] = 0;
        if (!A[c1])
            continue;
        /* only columns that still hold a trimmed cell between sa and sb */
        for (c0 = 0; c0 < G && !active; c0++)
            active = S->mask[c0 + G * c1] && cell_b(c, c->e0, c0) < sb && cell_b(c, c->e0, c0 + 1) > sa;
        if (!active)
            continue;
        if (c->o.measure == AMP_COVER_ARCLEN) {
            size_t ilo[2], ihi[2];
            if (!have) {
                /* the surface's direction 0 is e0 (s), direction 1 is e1 (t) */
                if (slab(&S->s, 0, sa, sb, &sl, c->err) != AMP_OK)
                    return -1;
                have = 1;
            }
            ilo[1] = c->blo[c->e1][c1];
            ihi[1] = c->bhi[c->e1][c1];
            ilo[0] = 0;
            ihi[0] = 0;
            N[c1] = block_bound(&sl, 0, ilo, ihi) > c->thr;
        } else {
            double mx = 0;
            int k;
            for (k = 0; k <= 2; k++) {
                double t = cell_b(c, c->e1, c1) + (cell_b(c, c->e1, c1 + 1) - cell_b(c, c->e1, c1)) * k / 2.0;
                mx = fmax(mx, amp_v3_dist(surf_pt(c, S->w, sa, t), surf_pt(c, S->w, sb, t)));
            }
            N[c1] = mx > c->thr;
        }
        cnt += N[c1];
    }
    if (have)
        amp_spline_free(&sl);
    return cnt;
}

/* Elber & Cohen: between the curves at sa and sb (present on A), add the middle curve where needed, recursively. */
static amp_status cover_curves(ctx *c, surf *S, double sa, double sb, const unsigned char *A, int depth)
{
    unsigned char N[64];
    int n = curve_need(c, S, sa, sb, A, N);
    double sm = 0.5 * (sa + sb);
    amp_status st;
    if (n < 0)
        return c->err ? c->err->status : AMP_ERR_NOMEM;
    if (n == 0)
        return AMP_OK;
    if (depth >= c->o.max_depth) {
        c->st.depth_limited = 1;
        return AMP_OK;
    }
    st = cover_curves(c, S, sa, sm, N, depth + 1);
    if (st == AMP_OK)
        st = emit_curve(c, S->w, sm, N);
    if (st == AMP_OK)
        st = cover_curves(c, S, sm, sb, N, depth + 1);
    return st;
}

/* One covering surface V(., ., w) trimmed to @p mask: boundary curves, then the recursion. */
static amp_status cover_surface(ctx *c, double w, const unsigned char *mask)
{
    surf S;
    unsigned char A[64];
    int G = c->G, c0, c1, any = 0;
    amp_status st = AMP_OK;
    for (c1 = 0; c1 < G; c1++) {
        A[c1] = 0;
        for (c0 = 0; c0 < G; c0++)
            A[c1] |= mask[c0 + G * c1];
        any |= A[c1];
    }
    if (!any)
        return AMP_OK;
    S.w = w;
    S.mask = mask;
    amp_spline_init(&S.s);
    if (c->o.measure == AMP_COVER_ARCLEN) {
        st = amp_spline_isoparam(&c->ref, c->d, w, &S.s, c->err);
        /* isoparam keeps the remaining directions in increasing order: e0 < e1, so dir 0 = s, dir 1 = t */
        if (st != AMP_OK)
            return st;
    }
    c->st.surfaces++;
    if (st == AMP_OK)
        st = emit_curve(c, w, c->lo[c->e0], A);
    if (st == AMP_OK)
        st = cover_curves(c, &S, c->lo[c->e0], c->hi[c->e0], A, 0);
    if (st == AMP_OK)
        st = emit_curve(c, w, c->hi[c->e0], A);
    amp_spline_free(&S.s);
    /* surfaces come in increasing w (in-order recursion): w itself measures progress */
    if (c->o.progress)
        c->o.progress(c->o.progress_user, (w - c->lo[c->d]) / (c->hi[c->d] - c->lo[c->d]));
    return st;
}

/*
 * Algorithm 1, CoverSubVolume: lines 5-16, with the trimming cells of the
 * parent. @p sl is the slab of ref between wl and wh (arc-length measure; owned
 * and freed here): the children's slabs are its two halves, so each level
 * splits ever smaller nets.
 */
static amp_status cover_sub(ctx *c, amp_spline *sl, double wl, double wh, const unsigned char *parent, int m,
                            int depth)
{
    unsigned char need[64 * 64];
    long n;
    double wm = 0.5 * (wl + wh);
    amp_status st = AMP_OK;
    amp_spline left, right;
    amp_spline_init(&left);
    amp_spline_init(&right);
    if (m > 0) {
        /* line 9-10: within the minimal depth the middle surface is not trimmed */
        memcpy(need, parent, (size_t)(c->G * c->G));
        n = 1;
    } else
        n = surface_need(c, sl, wl, wh, parent, need);
    if (n <= 0 || depth >= c->o.max_depth) {
        if (n > 0)
            c->st.depth_limited = 1;
        amp_spline_free(sl);
        return n < 0 ? (amp_status)n : AMP_OK;
    }
    if (c->o.measure == AMP_COVER_ARCLEN)
        st = amp_spline_split(sl, c->d, wm, &left, &right, c->err);
    amp_spline_free(sl);
    if (st == AMP_OK)
        st = cover_sub(c, &left, wl, wm, need, m - 1, depth + 1);
    else
        amp_spline_free(&left);
    if (st == AMP_OK)
        st = cover_surface(c, wm, need); /* line 14: S^t_mid */
    if (st == AMP_OK)
        st = cover_sub(c, &right, wm, wh, need, m - 1, depth + 1);
    else
        amp_spline_free(&right);
    return st;
}

amp_status amp_cover_trivariate(const amp_spline *v, const amp_cover_opts *opts, amp_pathset *out,
                                amp_cover_stats *stats, amp_error *err)
{
    ctx *c;
    unsigned char full[64 * 64];
    int e, i;
    amp_status st = AMP_OK;
    if (!v || v->dim != 3 || !opts || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "covering needs a trivariate");
    if (!(opts->eps > 0) || !isfinite(opts->eps) || opts->dir < AMP_COVER_AUTO || opts->dir > 2 || opts->min_depth < 0 ||
        opts->min_depth > 30 || !(opts->radius > 0) || opts->cells > 64)
        return amp_fail(err, AMP_ERR_ARG, 0, "bad covering options (eps > 0, dir 0..2 or auto, 0 <= m <= 30, radius > 0, "
                                             "cells <= 64)");
    c = amp_calloc(v->alloc, 1, sizeof *c);
    if (!c)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory");
    c->v = v;
    c->o = *opts;
    if (c->o.dir == AMP_COVER_AUTO && (st = amp_cover_pick_dir(v, &c->o.dir, NULL, err)) != AMP_OK) {
        amp_free(v->alloc, c);
        return st;
    }
    c->st.dir = c->o.dir;
    c->G = opts->cells > 0 ? opts->cells : 16;
    if (c->o.max_depth <= 0)
        c->o.max_depth = 24;
    c->delta = opts->chord_tol > 0 ? fmin(opts->chord_tol, 0.5 * opts->eps) : opts->eps / 20;
    c->thr = opts->eps - c->delta; /* eps_s = eps_c = thr / 2 */
    c->d = c->o.dir;
    c->e0 = c->d == 0 ? 1 : 0;
    c->e1 = c->d == 2 ? 1 : 2;
    c->out = out;
    c->err = err;
    for (e = 0; e < 3; e++)
        amp_spline_domain(v, e, &c->lo[e], &c->hi[e]);
    st = amp_spline_copy(&c->ref, v, v->alloc, err);
    /* cell boundaries as knots of multiplicity order-1: each cell gets its own small control block */
    for (e = 0; e < 3 && st == AMP_OK; e++) {
        if (e == c->d)
            continue;
        for (i = 1; i < c->G && st == AMP_OK; i++) {
            double t = cell_b(c, e, i);
            int have = 0;
            size_t j;
            for (j = 0; j < c->ref.count[e] + (size_t)c->ref.order[e]; j++)
                have += c->ref.knots[e][j] == t;
            if (have < c->ref.order[e] - 1)
                st = amp_spline_insert_knot(&c->ref, e, t, c->ref.order[e] - 1 - have, err);
        }
        for (i = 0; i < c->G && st == AMP_OK; i++)
            index_range(&c->ref, e, cell_b(c, e, i), cell_b(c, e, i + 1), &c->blo[e][i], &c->bhi[e][i]);
    }
    memset(full, 1, sizeof full);
    /* line 2: V(u,v,0) ∪ CoverSubVolume ∪ V(u,v,1) */
    if (st == AMP_OK)
        st = cover_surface(c, c->lo[c->d], full);
    if (st == AMP_OK) {
        amp_spline top;
        amp_spline_init(&top);
        if (opts->measure == AMP_COVER_ARCLEN)
            st = amp_spline_copy(&top, &c->ref, v->alloc, err);
        if (st == AMP_OK)
            st = cover_sub(c, &top, c->lo[c->d], c->hi[c->d], full, opts->min_depth, 0);
    }
    if (st == AMP_OK)
        st = cover_surface(c, c->hi[c->d], full);
    if (stats)
        *stats = c->st;
    amp_spline_free(&c->ref);
    amp_free(v->alloc, c);
    return st;
}
