/* Independent gouge checker (see check.h): numerical clearance, pairwise or with a column pyramid. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "ampath/check.h"

/* One segment in print order: vertices a and b of the pathset (a == b for a one-vertex path). Its box and its
 * path are not kept: they are found from the vertices when needed (a sliced part fit for a printer's bed has
 * tens of millions of segments; 16 bytes each instead of 80 halve the check's peak). */
typedef struct gseg {
    size_t a, b;
} gseg;

typedef struct gctx {
    const amp_pathset *ps;
    double k, zo, tol;
    gseg *seg;
    size_t n;
} gctx;

static amp_box3 seg_box(const gctx *c, const gseg *s)
{
    amp_vec3 p = c->ps->verts[s->a].p, q = c->ps->verts[s->b].p;
    amp_box3 b;
    b.min.x = p.x < q.x ? p.x : q.x;
    b.max.x = p.x < q.x ? q.x : p.x;
    b.min.y = p.y < q.y ? p.y : q.y;
    b.max.y = p.y < q.y ? q.y : p.y;
    b.min.z = p.z < q.z ? p.z : q.z;
    b.max.z = p.z < q.z ? q.z : p.z;
    return b;
}

/* The path holding vertex @p a and a's index in it: the last path starting at or before a (an empty path starts
 * where the next one does, so it is never the last). */
static void seg_place(const amp_pathset *ps, size_t a, size_t *path, size_t *k)
{
    size_t lo = 0, hi = ps->npaths;
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (ps->paths[mid].first <= a)
            lo = mid;
        else
            hi = mid;
    }
    *path = lo;
    *k = a - ps->paths[lo].first;
}

/* Length in the plane: coordinates are millimetres, so hypot's overflow guard only costs time (a third of
 * `ampath check` on the demo). */
static double len_xy(double x, double y) { return sqrt(x * x + y * y); }

/* Highest value of q.z - kk |q.xy - p.xy| for q on [s0, s1]; *uq receives the best parameter. */
static double best_on_segment(amp_vec3 p, amp_vec3 s0, amp_vec3 s1, double kk, double *uq)
{
    double dx = s1.x - s0.x, dy = s1.y - s0.y, dz = s1.z - s0.z;
    double L2 = dx * dx + dy * dy, best, v, u;
    best = s0.z - kk * len_xy(s0.x - p.x, s0.y - p.y);
    *uq = 0.0;
    v = s1.z - kk * len_xy(s1.x - p.x, s1.y - p.y);
    if (v > best) {
        best = v;
        *uq = 1.0;
    }
    if (L2 > 0.0 && kk * kk * L2 > dz * dz) {
        /* stationary point: w = u - c with dz^2 (hd^2 + L^2 w^2) = kk^2 L^4 w^2, w of the sign of dz */
        double L = sqrt(L2), c = ((p.x - s0.x) * dx + (p.y - s0.y) * dy) / L2;
        double hd = len_xy(s0.x + c * dx - p.x, s0.y + c * dy - p.y);
        u = c + dz * hd / (L * sqrt(kk * kk * L2 - dz * dz));
        if (u > 0.0 && u < 1.0) {
            v = s0.z + u * dz - kk * len_xy(s0.x + u * dx - p.x, s0.y + u * dy - p.y);
            if (v > best) {
                best = v;
                *uq = u;
            }
        }
    }
    return best;
}

/*
 * Clearance of earlier segment s against later segment t: max over p on t, q on s
 * of q.z - p.z - zo - k |q.xy - p.xy|. The inner maximum is exact; the outer
 * function of p's parameter is concave (a partial maximum of a concave
 * function), so a golden-section search finds its maximum.
 */
static double pair_clearance(const gctx *c, const gseg *s, const gseg *t, amp_vec3 *qo, amp_vec3 *po)
{
    amp_vec3 s0 = c->ps->verts[s->a].p, s1 = c->ps->verts[s->b].p;
    amp_vec3 t0 = c->ps->verts[t->a].p, t1 = c->ps->verts[t->b].p;
    const double gr = 0.61803398874989484820;
    double lo = 0.0, hi = 1.0, x1, x2, f1, f2, u, best, bu = 0.0, bv = 0.0;
    int it;
#define PHI(vv, uu) (best_on_segment(amp_v3_lerp(t0, t1, (vv)), s0, s1, c->k, &(uu)) - (t0.z + (vv) * (t1.z - t0.z)))
    best = PHI(0.0, u);
    bu = u;
    f1 = PHI(1.0, u);
    if (f1 > best) {
        best = f1;
        bu = u;
        bv = 1.0;
    }
    x1 = hi - gr * (hi - lo);
    x2 = lo + gr * (hi - lo);
    f1 = PHI(x1, u);
    f2 = PHI(x2, u);
    for (it = 0; it < 64 && hi - lo > 1e-13; it++) {
        if (f1 < f2) {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + gr * (hi - lo);
            f2 = PHI(x2, u);
        } else {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - gr * (hi - lo);
            f1 = PHI(x1, u);
        }
    }
    x1 = 0.5 * (lo + hi);
    f1 = PHI(x1, u);
    if (f1 > best) {
        best = f1;
        bu = u;
        bv = x1;
    }
#undef PHI
    *qo = amp_v3_lerp(s0, s1, bu);
    *po = amp_v3_lerp(t0, t1, bv);
    return best - c->zo;
}

/* Earlier points of one segment against its later points: the worst pair is its start against its end. */
static double self_clearance(const gctx *c, const gseg *t)
{
    amp_vec3 a = c->ps->verts[t->a].p, b = c->ps->verts[t->b].p;
    return (a.z - b.z) - c->k * len_xy(b.x - a.x, b.y - a.y) - c->zo;
}

/* (ternaries, not fmax: this runs for every pyramid cell the grid method visits) */
static double box_gap_xy(amp_box3 a, amp_box3 b)
{
    double dx = a.min.x - b.max.x, ex = b.min.x - a.max.x, dy = a.min.y - b.max.y, ey = b.min.y - a.max.y;
    dx = dx > ex ? dx : ex;
    dy = dy > ey ? dy : ey;
    dx = dx > 0.0 ? dx : 0.0;
    dy = dy > 0.0 ? dy : 0.0;
    return len_xy(dx, dy);
}

/*
 * Upper bound of pair_clearance: the clearance c(u, v) = q(u).z - p(v).z - zo - k |q(u).xy - p(v).xy| is
 * concave on the unit square, so it lies under its tangent plane at the centre, whose largest value on the
 * square is at a corner. It spares the golden-section search for the pairs that are clearly apart.
 */
static double pair_bound(const gctx *c, const gseg *s, const gseg *t)
{
    amp_vec3 s0 = c->ps->verts[s->a].p, s1 = c->ps->verts[s->b].p;
    amp_vec3 t0 = c->ps->verts[t->a].p, t1 = c->ps->verts[t->b].p;
    double wx = 0.5 * (s0.x + s1.x - t0.x - t1.x), wy = 0.5 * (s0.y + s1.y - t0.y - t1.y), w = len_xy(wx, wy);
    double du, dv;
    if (!(w > 0.0))
        return HUGE_VAL;
    /* w = q.xy - p.xy moves by +ds.xy with u and by -dt.xy with v */
    du = (s1.z - s0.z) - c->k * (wx * (s1.x - s0.x) + wy * (s1.y - s0.y)) / w;
    dv = -(t1.z - t0.z) + c->k * (wx * (t1.x - t0.x) + wy * (t1.y - t0.y)) / w;
    return 0.5 * (s0.z + s1.z - t0.z - t1.z) - c->zo - c->k * w + 0.5 * (fabs(du) + fabs(dv));
}

/* Distance in the plane from point p to segment [a, b]. */
static double pt_seg_xy(amp_vec3 p, amp_vec3 a, amp_vec3 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, L2 = dx * dx + dy * dy, u = 0.0;
    if (L2 > 0.0) {
        u = ((p.x - a.x) * dx + (p.y - a.y) * dy) / L2;
        u = u < 0.0 ? 0.0 : (u > 1.0 ? 1.0 : u);
    }
    return len_xy(a.x + u * dx - p.x, a.y + u * dy - p.y);
}

static double orient_xy(amp_vec3 a, amp_vec3 b, amp_vec3 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

/* Distance between the plane projections of two segments (0 when they cross). */
static double seg_seg_xy(amp_vec3 a0, amp_vec3 a1, amp_vec3 b0, amp_vec3 b1)
{
    double o1 = orient_xy(a0, a1, b0), o2 = orient_xy(a0, a1, b1), o3 = orient_xy(b0, b1, a0),
           o4 = orient_xy(b0, b1, a1);
    if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
        return 0.0;
    return fmin(fmin(pt_seg_xy(a0, b0, b1), pt_seg_xy(a1, b0, b1)), fmin(pt_seg_xy(b0, a0, a1), pt_seg_xy(b1, a0, a1)));
}

/* Test earlier segment si against later ti (box @p tb); returns 1 and fills v on a violation. */
static int test_pair(const gctx *c, size_t si, size_t ti, const amp_box3 *tb, amp_gouge_violation *v)
{
    const gseg *s = &c->seg[si], *t = &c->seg[ti];
    amp_vec3 q, p;
    double d;
    if (si == ti) {
        d = self_clearance(c, t);
        q = c->ps->verts[t->a].p;
        p = c->ps->verts[t->b].p;
    } else {
        amp_box3 sb;
        double za = c->ps->verts[s->a].p.z, zb = c->ps->verts[s->b].p.z;
        /* nothing of s above t's lowest point by z_offs: the bound below without its gap term, from two loads */
        if ((za > zb ? za : zb) - tb->min.z - c->zo <= c->tol)
            return 0;
        sb = seg_box(c, s);
        if (sb.max.z - tb->min.z - c->zo - c->k * box_gap_xy(sb, *tb) <= c->tol)
            return 0;
        /* the same bound with the segments' own plane distance: most neighbours stop here */
        if (sb.max.z - tb->min.z - c->zo -
                c->k * seg_seg_xy(c->ps->verts[s->a].p, c->ps->verts[s->b].p, c->ps->verts[t->a].p,
                                  c->ps->verts[t->b].p) <= c->tol)
            return 0;
        /* (1e-9 mm is far above the bound's rounding at millimetre coordinates) */
        if (pair_bound(c, s, t) <= c->tol - 1e-9)
            return 0;
        d = pair_clearance(c, s, t, &q, &p);
    }
    if (d <= c->tol)
        return 0;
    seg_place(c->ps, s->a, &v->earlier_path, &v->earlier_seg);
    seg_place(c->ps, t->a, &v->later_path, &v->later_seg);
    v->earlier_point = q;
    v->later_point = p;
    v->depth = d;
    return 1;
}

static size_t check_pairwise(const gctx *c, amp_gouge_violation *out)
{
    size_t first = (size_t)-1;
    long t, n = (long)c->n;
#pragma omp parallel for schedule(dynamic, 16)
    for (t = 0; t < n; t++) {
        size_t s, cur;
        amp_gouge_violation v;
#pragma omp atomic read
        cur = first;
        if ((size_t)t > cur)
            continue;
        amp_box3 tb = seg_box(c, &c->seg[t]);
        for (s = 0; s <= (size_t)t; s++)
            if (test_pair(c, s, (size_t)t, &tb, &v))
                break;
        if (s <= (size_t)t) {
#pragma omp critical(amp_gouge_first)
            {
                if ((size_t)t < first) {
#pragma omp atomic write
                    first = (size_t)t;
                    *out = v;
                }
            }
        }
    }
    return first;
}

/*
 * Grid method: segments are visited in print order and inserted into the xy
 * columns their boxes cover after being tested, so the grid only ever holds
 * earlier segments. A pyramid of per-cell maximum heights prunes every region
 * whose highest earlier point is below the cone of the segment under test.
 */
/* The column grid over the earlier segments with its max-height pyramid. */
typedef struct gpyramid {
    const amp_allocator *a;
    amp_box3 all;       /* box of every segment */
    size_t P, L;        /* P x P columns at level 0; L levels, each halving the side */
    size_t off[12];     /* start of level l in maxz */
    double cw, ch;      /* column width and depth at level 0, mm */
    double *maxz;       /* highest earlier point per cell of every level (-inf: none) */
    size_t *start;      /* column x's segments: ent[start[x] .. start[x] + fill[x]), in print order */
    uint32_t *fill;
    uint32_t *stamp;    /* segment s was tested against segment i when stamp[s] == i + 1 */
    /* segment s's top rounded up to a float: most segments of a column that reaches the cone lie below the
     * tested segment by more than z_offs, and their tops turn them away without a load of their vertices or
     * stamp (80 % of the pairs on the demo; test_pair's first test, with a top never lower than the exact one,
     * so no pair it would test is left out). Per segment, not per column entry: a long segment over fine
     * columns has hundreds of entries */
    float *top;
    uint32_t *ent;      /* every column's room for all the segments whose box covers it (counted first:
                         * a column is read as one run, not a linked list chased through memory) */
} gpyramid;

static size_t column_of(double v, double lo, double w, size_t P)
{
    return (size_t)fmax(0.0, fmin((double)P - 1, floor((v - lo) / w)));
}

/* The columns [x0, x1] x [y0, y1] that box @p b covers. */
static void columns_of(const gpyramid *g, const amp_box3 *b, size_t *x0, size_t *x1, size_t *y0, size_t *y1)
{
    *x0 = column_of(b->min.x, g->all.min.x, g->cw, g->P);
    *x1 = column_of(b->max.x, g->all.min.x, g->cw, g->P);
    *y0 = column_of(b->min.y, g->all.min.y, g->ch, g->P);
    *y1 = column_of(b->max.y, g->all.min.y, g->ch, g->P);
}

static amp_status pyramid_init(gpyramid *g, const gctx *c, amp_error *err)
{
    size_t i, total = 0;
    g->all = amp_box3_empty();
    g->P = 1;
    for (i = 0; i < c->n; i++)
        g->all = amp_box3_union(g->all, seg_box(c, &c->seg[i]));
    while (g->P < 1024 && g->P * g->P * 16 < c->n)
        g->P *= 2;
    for (g->L = 0, i = g->P; i >= 1; i /= 2) {
        g->off[g->L++] = total;
        total += i * i;
    }
    g->cw = fmax((g->all.max.x - g->all.min.x) / (double)g->P, 1e-9);
    g->ch = fmax((g->all.max.y - g->all.min.y) / (double)g->P, 1e-9);
    g->maxz = amp_calloc(g->a, total, sizeof *g->maxz);
    g->start = amp_calloc(g->a, g->P * g->P + 1, sizeof *g->start);
    g->fill = amp_calloc(g->a, g->P * g->P, sizeof *g->fill);
    g->stamp = amp_calloc(g->a, c->n, sizeof *g->stamp);
    g->top = amp_calloc(g->a, c->n, sizeof *g->top);
    if (!g->maxz || !g->start || !g->fill || !g->stamp || !g->top)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the gouge grid");
    for (i = 0; i < total; i++)
        g->maxz[i] = -HUGE_VAL;
    for (i = 0; i < c->n; i++) {
        size_t x0, x1, y0, y1, ix, iy;
        amp_box3 b = seg_box(c, &c->seg[i]);
        columns_of(g, &b, &x0, &x1, &y0, &y1);
        for (iy = y0; iy <= y1; iy++)
            for (ix = x0; ix <= x1; ix++)
                g->start[iy * g->P + ix + 1]++;
    }
    for (i = 0; i < g->P * g->P; i++)
        g->start[i + 1] += g->start[i];
    g->ent = amp_calloc(g->a, g->start[g->P * g->P] + 1, sizeof *g->ent);
    if (!g->ent)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the gouge grid");
    return AMP_OK;
}

static void pyramid_free(gpyramid *g)
{
    amp_free(g->a, g->maxz);
    amp_free(g->a, g->start);
    amp_free(g->a, g->fill);
    amp_free(g->a, g->stamp);
    amp_free(g->a, g->ent);
    amp_free(g->a, g->top);
}

/* May cell (x, y) of level l hold an earlier point inside the cone over segment t's box? Compares the cell's
 * highest earlier point with the cone, squared (no root per cell). */
static int cell_may_gouge(const gpyramid *g, const gctx *c, const amp_box3 *tb, size_t l, size_t x, size_t y)
{
    double sz = (double)((size_t)1 << l);
    double room = g->maxz[g->off[l] + y * (g->P >> l) + x] - tb->min.z - c->zo - c->tol;
    double rx0, ry0, gx, gy, ex, ey;
    if (room <= 0.0)
        return 0;
    rx0 = g->all.min.x + (double)x * g->cw * sz;
    ry0 = g->all.min.y + (double)y * g->ch * sz;
    gx = rx0 - tb->max.x;
    ex = tb->min.x - (rx0 + g->cw * sz);
    gy = ry0 - tb->max.y;
    ey = tb->min.y - (ry0 + g->ch * sz);
    gx = gx > ex ? gx : ex;
    gy = gy > ey ? gy : ey;
    gx = gx > 0.0 ? gx : 0.0;
    gy = gy > 0.0 ? gy : 0.0;
    return c->k * c->k * (gx * gx + gy * gy) < room * room;
}

/* The earliest segment (i itself included) that segment i gouges, (size_t)-1 if none; *out its violation.
 * The earlier segments are queried coarse to fine. */
static size_t earliest_gouged(gpyramid *g, const gctx *c, size_t i, amp_gouge_violation *out)
{
    amp_box3 tb = seg_box(c, &c->seg[i]);
    size_t stk[3 * 64], top = 0, best = (size_t)-1;
    amp_gouge_violation v;
    if (test_pair(c, i, i, &tb, &v)) {
        best = i;
        *out = v;
    }
    /* a cell is tested before it is pushed: three of four children fail, and a push and pop each cost more
     * than the test (the same cells are visited in the same order) */
    if (cell_may_gouge(g, c, &tb, g->L - 1, 0, 0)) {
        stk[top++] = g->L - 1;
        stk[top++] = 0;
        stk[top++] = 0;
    }
    while (top) {
        size_t y = stk[--top], x = stk[--top], l = stk[--top], dx, dy, e, ee;
        if (l > 0) {
            for (dy = 0; dy < 2; dy++)
                for (dx = 0; dx < 2; dx++)
                    if (cell_may_gouge(g, c, &tb, l - 1, 2 * x + dx, 2 * y + dy)) {
                        stk[top++] = l - 1;
                        stk[top++] = 2 * x + dx;
                        stk[top++] = 2 * y + dy;
                    }
            continue;
        }
        for (e = g->start[y * g->P + x], ee = e + g->fill[y * g->P + x]; e < ee; e++) {
            uint32_t s = g->ent[e];
            if ((double)g->top[s] - tb.min.z - c->zo <= c->tol || g->stamp[s] == i + 1 || s >= best)
                continue;
            g->stamp[s] = (uint32_t)(i + 1);
            if (test_pair(c, s, i, &tb, &v)) {
                best = s;
                *out = v;
            }
        }
    }
    return best;
}

/* Insert segment i into the columns its box covers (their room was counted), and raise the pyramid. */
static void pyramid_insert(gpyramid *g, const gctx *c, size_t i)
{
    amp_box3 tb = seg_box(c, &c->seg[i]);
    size_t x0, x1, y0, y1, ix, iy;
    float top = (float)tb.max.z;
    if ((double)top < tb.max.z)
        top = nextafterf(top, HUGE_VALF);
    g->top[i] = top;
    columns_of(g, &tb, &x0, &x1, &y0, &y1);
    for (iy = y0; iy <= y1; iy++)
        for (ix = x0; ix <= x1; ix++) {
            size_t l, cx = ix, cy = iy, col = iy * g->P + ix;
            g->ent[g->start[col] + g->fill[col]++] = (uint32_t)i;
            for (l = 0; l < g->L; l++, cx /= 2, cy /= 2) {
                double *m = &g->maxz[g->off[l] + cy * (g->P >> l) + cx];
                if (*m >= tb.max.z)
                    break;
                *m = tb.max.z;
            }
        }
}

/* The first segment in print order that gouges an earlier one ((size_t)-1: none), its violation in *out. */
static size_t check_grid(const gctx *c, amp_gouge_violation *out, amp_error *err, amp_status *st)
{
    gpyramid g;
    size_t i, found = (size_t)-1;
    memset(&g, 0, sizeof g);
    g.a = c->ps->alloc;
    if ((*st = pyramid_init(&g, c, err)) == AMP_OK)
        for (i = 0; i < c->n; i++) {
            if (earliest_gouged(&g, c, i, out) != (size_t)-1) {
                found = i;
                break;
            }
            pyramid_insert(&g, c, i);
        }
    pyramid_free(&g);
    return found;
}

amp_status amp_check_gouge(const amp_pathset *ps, const amp_head *h, amp_gouge_method m, double tol,
                           amp_gouge_violation *vout, amp_error *err)
{
    gctx c;
    size_t i, k, n = 0, first;
    amp_gouge_violation v;
    amp_status st = AMP_OK;
    if (!ps || !h)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_check_gouge: NULL argument");
    if (m != AMP_GOUGE_AUTO && m != AMP_GOUGE_PAIRWISE && m != AMP_GOUGE_GRID)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_check_gouge: unknown method %d", (int)m);
    if (!isfinite(h->z_offs) || h->z_offs <= 0.0 || !isfinite(h->theta) || h->theta <= 0.0 ||
        h->theta >= 0.5 * AMP_PI)
        return amp_fail(err, AMP_ERR_RANGE, 0, "head needs z_offs > 0 and theta in (0, 90) degrees (got %g mm, %g deg)",
                        h->z_offs, h->theta * 57.295779513082320876);
    if (!isfinite(tol) || tol < -h->z_offs)
        return amp_fail(err, AMP_ERR_RANGE, 0, "gouge tolerance must be finite and above -z_offs (got %g)", tol);
    memset(&c, 0, sizeof c);
    c.ps = ps;
    c.k = 1.0 / tan(h->theta);
    c.zo = h->z_offs;
    c.tol = tol;
    for (i = 0; i < ps->npaths; i++)
        n += ps->paths[i].n > 1 ? ps->paths[i].n - 1 : ps->paths[i].n;
    if (n >= 0xffffffffUL)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "too many segments for the gouge check (%lu)", (unsigned long)n);
    if (n == 0)
        return AMP_OK;
    c.seg = amp_calloc(ps->alloc, n, sizeof *c.seg);
    if (!c.seg)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for %lu segments", (unsigned long)n);
    for (i = 0; i < ps->npaths; i++) {
        size_t np = ps->paths[i].n, f = ps->paths[i].first;
        for (k = 0; k + 1 < np || (np == 1 && k == 0); k++) {
            gseg *s = &c.seg[c.n++];
            s->a = f + k;
            s->b = np == 1 ? f : f + k + 1;
        }
    }
    if (m == AMP_GOUGE_AUTO)
        m = n < 2000 ? AMP_GOUGE_PAIRWISE : AMP_GOUGE_GRID;
    first = m == AMP_GOUGE_PAIRWISE ? check_pairwise(&c, &v) : check_grid(&c, &v, err, &st);
    amp_free(ps->alloc, c.seg);
    if (st != AMP_OK)
        return st;
    if (first == (size_t)-1)
        return AMP_OK;
    if (vout)
        *vout = v;
    return amp_fail(err, AMP_ERR_CHECK, 0,
                    "gouge: path %lu point (%.4f %.4f %.4f) is %.4g mm inside the head while path %lu prints (%.4f %.4f "
                    "%.4f)",
                    (unsigned long)v.earlier_path, v.earlier_point.x, v.earlier_point.y, v.earlier_point.z, v.depth,
                    (unsigned long)v.later_path, v.later_point.x, v.later_point.y, v.later_point.z);
}
