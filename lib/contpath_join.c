/* One extrusion start per island (beyond [P2]:
 * every extrusion start is a blob and a seam on the print): the perimeter
 * loops of an island and the closed strokes of its infill regions are
 * spliced into one closed stroke. Two loops X and Y that run side by side
 * (the perimeter at r and the ring of R̃ at 3r, or two perimeter loops of a
 * thin island) are joined by two parallel connectors
 * p1-q1 and p2-q2, |p1 p2| = 2r: X is run from p2 round to p1, the connector
 * to q1, Y round the long way to q2, the connector back to p2 (the stretch
 * p1 p2 of X and q1 q2 of Y is left out; the two connector beads cover it).
 * The connectors are printed; they must not cross any segment of the island,
 * which is tested before a splice is taken. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

/* A cyclic loop (no repeated last vertex) owned by the joiner. */
typedef struct jloop {
    amp_pvert *v;
    size_t n;
    int alive;
    int wall; /* a ring of the island's section: connectors must not cross it */
} jloop;

typedef struct jseg {
    size_t loop, i; /* segment i -> i + 1 (cyclic) of loop */
} jseg;

/* Uniform grid of all segments of the live loops (cell >= connector length). */
typedef struct jgrid {
    double x0, y0, cell;
    long nx, ny;
    size_t *start;
    jseg *item;
} jgrid;

typedef struct joiner {
    const amp_allocator *al;
    jloop *lp;
    size_t nl;
    jgrid g;
    double r, dmax;
} joiner;

static long cell_of(const jgrid *g, double v, double o, long n)
{
    long c = (long)floor((v - o) / g->cell);
    return c < 0 ? 0 : (c >= n ? n - 1 : c);
}

static void grid_free(const amp_allocator *al, jgrid *g)
{
    amp_free(al, g->start);
    amp_free(al, g->item);
    memset(g, 0, sizeof *g);
}

/* Every segment is listed in the cells of its bounding box. */
static amp_status grid_build(joiner *J)
{
    jgrid *g = &J->g;
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
    size_t l, i, pass, total = 0;
    grid_free(J->al, g);
    for (l = 0; l < J->nl; l++)
        for (i = 0; J->lp[l].alive && i < J->lp[l].n; i++) {
            x0 = fmin(x0, J->lp[l].v[i].p.x);
            y0 = fmin(y0, J->lp[l].v[i].p.y);
            x1 = fmax(x1, J->lp[l].v[i].p.x);
            y1 = fmax(y1, J->lp[l].v[i].p.y);
        }
    g->cell = fmax(J->dmax, fmax(x1 - x0, y1 - y0) / 512.0);
    g->x0 = x0;
    g->y0 = y0;
    g->nx = (long)((x1 - x0) / g->cell) + 1;
    g->ny = (long)((y1 - y0) / g->cell) + 1;
    g->start = amp_calloc(J->al, (size_t)(g->nx * g->ny) + 1, sizeof *g->start);
    if (!g->start)
        return AMP_ERR_NOMEM;
    for (pass = 0; pass < 2; pass++) {
        for (l = 0; l < J->nl; l++)
            for (i = 0; J->lp[l].alive && i < J->lp[l].n; i++) {
                amp_vec3 a = J->lp[l].v[i].p, b = J->lp[l].v[(i + 1) % J->lp[l].n].p;
                long cx0 = cell_of(g, fmin(a.x, b.x), g->x0, g->nx), cx1 = cell_of(g, fmax(a.x, b.x), g->x0, g->nx);
                long cy0 = cell_of(g, fmin(a.y, b.y), g->y0, g->ny), cy1 = cell_of(g, fmax(a.y, b.y), g->y0, g->ny);
                long x, y;
                for (y = cy0; y <= cy1; y++)
                    for (x = cx0; x <= cx1; x++) {
                        size_t c = (size_t)(y * g->nx + x);
                        if (pass == 0)
                            g->start[c + 1]++;
                        else {
                            g->item[g->start[c]].loop = l;
                            g->item[g->start[c]++].i = i;
                        }
                    }
            }
        if (pass == 0) {
            for (i = 0; i < (size_t)(g->nx * g->ny); i++)
                g->start[i + 1] += g->start[i];
            total = g->start[g->nx * g->ny];
            g->item = amp_alloc(J->al, (total + 1) * sizeof *g->item);
            if (!g->item)
                return AMP_ERR_NOMEM;
        }
    }
    for (i = (size_t)(g->nx * g->ny); i > 0; i--)
        g->start[i] = g->start[i - 1];
    g->start[0] = 0;
    return AMP_OK;
}

static amp_vec2 P2v(amp_vec3 p) { return amp_v2(p.x, p.y); }

/* Nearest point to q on a printed segment of a live loop other than those
 * with uf root @p skip, within dmax: loop, segment, parameter. 0 if none. */
static int nearest(const joiner *J, const size_t *uf, size_t skip, amp_vec2 q, size_t *ol, size_t *oi, double *ot,
                   double *od)
{
    const jgrid *g = &J->g;
    long cx = cell_of(g, q.x, g->x0, g->nx), cy = cell_of(g, q.y, g->y0, g->ny), x, y;
    double best = J->dmax;
    int found = 0;
    size_t k;
    for (y = cy - 1; y <= cy + 1; y++)
        for (x = cx - 1; x <= cx + 1; x++) {
            if (x < 0 || y < 0 || x >= g->nx || y >= g->ny)
                continue;
            for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                const jloop *L = &J->lp[g->item[k].loop];
                size_t i = g->item[k].i, j = (i + 1) % L->n;
                amp_vec2 a = P2v(L->v[i].p), b = P2v(L->v[j].p);
                double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy, t, d;
                if (L->wall || amp_uf_find((size_t *)uf, g->item[k].loop) == skip || !(L->v[i].r == J->r) ||
                    !(L->v[j].r == J->r))
                    continue; /* printed at the nominal radius: not a pseudo edge, not a corner */
                t = l2 > 0 ? ((q.x - a.x) * dx + (q.y - a.y) * dy) / l2 : 0;
                t = fmin(fmax(t, 0.0), 1.0);
                d = hypot(a.x + t * dx - q.x, a.y + t * dy - q.y);
                if (d < best) {
                    best = d;
                    *ol = g->item[k].loop;
                    *oi = i;
                    *ot = t;
                    found = 1;
                }
            }
        }
    *od = best;
    return found;
}

static int proper_cross(amp_vec2 a, amp_vec2 b, amp_vec2 c, amp_vec2 d)
{
    double d1 = amp_v2_orient(a, b, c), d2 = amp_v2_orient(a, b, d), d3 = amp_v2_orient(c, d, a),
           d4 = amp_v2_orient(c, d, b);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

/* Does connector a-b touch any segment of the live loops other than the
 * segments (la, ia) and (lb, ib) it ends on? Touching includes passing
 * within a tiny distance of a vertex (collinear cases). */
static int connector_blocked(const joiner *J, amp_vec2 a, amp_vec2 b, size_t la, size_t ia, size_t lb, size_t ib)
{
    const jgrid *g = &J->g;
    long cx0 = cell_of(g, fmin(a.x, b.x), g->x0, g->nx), cx1 = cell_of(g, fmax(a.x, b.x), g->x0, g->nx);
    long cy0 = cell_of(g, fmin(a.y, b.y), g->y0, g->ny), cy1 = cell_of(g, fmax(a.y, b.y), g->y0, g->ny), x, y;
    double tiny = 1e-7 * J->r;
    size_t k;
    for (y = cy0; y <= cy1; y++)
        for (x = cx0; x <= cx1; x++)
            for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                const jloop *L = &J->lp[g->item[k].loop];
                size_t i = g->item[k].i, j = (i + 1) % L->n;
                amp_vec2 c = P2v(L->v[i].p), d = P2v(L->v[j].p);
                amp_vec3 A3 = amp_v3(a.x, a.y, 0), B3 = amp_v3(b.x, b.y, 0);
                if ((g->item[k].loop == la && i == ia) || (g->item[k].loop == lb && i == ib))
                    continue;
                if (proper_cross(a, b, c, d))
                    return 1;
                /* a vertex of the island on the connector, or the
                 * connector's end on another segment */
                if (amp_v3_seg_dist2(amp_v3(c.x, c.y, 0), A3, B3, NULL) < tiny * tiny ||
                    amp_v3_seg_dist2(amp_v3(d.x, d.y, 0), A3, B3, NULL) < tiny * tiny)
                    return 1;
            }
    return 0;
}

/* Append v unless it repeats the last vertex exactly (position and radius:
 * a vertex written twice with two radii marks a pseudo edge and stays). */
static size_t wpush(amp_pvert *w, size_t m, amp_pvert v)
{
    if (m && w[m - 1].p.x == v.p.x && w[m - 1].p.y == v.p.y && w[m - 1].p.z == v.p.z && w[m - 1].r == v.r)
        return m;
    w[m++] = v;
    return m;
}

/* Point at parameter t of segment i of loop L. */
static amp_pvert seg_point(const jloop *L, size_t i, double t)
{
    amp_pvert a = L->v[i], b = L->v[(i + 1) % L->n], p;
    p.p = amp_v3_add(a.p, amp_v3_scale(amp_v3_sub(b.p, a.p), t));
    p.r = a.r;
    return p;
}

/* A splice: X is left between (sx, t1) and (sx2, t2) (forward), Y between
 * (j1, u1) and (j2, u2) (forward when ybackward, else backward). */
typedef struct cut {
    size_t lx, sx, sx2, ly, j1, j2;
    double t1, t2, u1, u2;
    int ybackward;
} cut;

/* Splice loop Y into X (see the file comment); X becomes the joined loop. */
static amp_status splice(joiner *J, const cut *c)
{
    jloop *X = &J->lp[c->lx], *Y = &J->lp[c->ly];
    size_t n = X->n + Y->n + 8, m = 0, i;
    amp_pvert *w = amp_alloc(J->al, n * sizeof *w);
    if (!w)
        return AMP_ERR_NOMEM;
    /* X from p2 round to p1 */
    m = wpush(w, m, seg_point(X, c->sx2, c->t2));
    for (i = (c->sx2 + 1) % X->n;; i = (i + 1) % X->n) {
        m = wpush(w, m, X->v[i]);
        if (i == c->sx)
            break;
    }
    m = wpush(w, m, seg_point(X, c->sx, c->t1));
    /* Y from q1 the long way round to q2 */
    m = wpush(w, m, seg_point(Y, c->j1, c->u1));
    if (c->ybackward) {
        /* the short stretch q1 -> q2 runs forward: go backward from j1 to j2 + 1 */
        for (i = c->j1;; i = (i + Y->n - 1) % Y->n) {
            m = wpush(w, m, Y->v[i]);
            if (i == (c->j2 + 1) % Y->n)
                break;
        }
    } else {
        for (i = (c->j1 + 1) % Y->n;; i = (i + 1) % Y->n) {
            m = wpush(w, m, Y->v[i]);
            if (i == c->j2)
                break;
        }
    }
    m = wpush(w, m, seg_point(Y, c->j2, c->u2));
    if (m > 1 && w[m - 1].p.x == w[0].p.x && w[m - 1].p.y == w[0].p.y && w[m - 1].r == w[0].r)
        m--;
    amp_free(J->al, X->v);
    amp_free(J->al, Y->v);
    Y->v = NULL;
    Y->n = 0;
    Y->alive = 0;
    X->v = w;
    X->n = m;
    return AMP_OK;
}

/* Forward segment count from (j1, u1) to (j2, u2) on a loop of n segments. */
static size_t forward_span(size_t n, size_t j1, double u1, size_t j2, double u2)
{
    if (j1 == j2 && u2 >= u1)
        return 0;
    return (j2 + n - j1) % n == 0 ? n : (j2 + n - j1) % n;
}

/* Segments from..from+cnt (cyclic) of L all printed at the nominal radius r? */
static int all_printed(const jloop *L, size_t from, size_t cnt, double r)
{
    size_t i;
    for (i = 0; i <= cnt + 1; i++)
        if (!(L->v[(from + i) % L->n].r == r))
            return 0; /* a pseudo edge (0) or a corner's tip (tagged) */
    return 1;
}

/* p2: the point at arc length ell after the midpoint p1 of segment sx of X,
 * at most 8 segments on; 0 if the loop turns away or is too short. */
static int second_point(const jloop *X, size_t sx, double ell, size_t *sx2, double *t2)
{
    double need = ell, len;
    size_t i = sx, k;
    double t = 0.5;
    for (k = 0; k < 8 && k < X->n; k++) {
        amp_vec3 a = X->v[i].p, b = X->v[(i + 1) % X->n].p;
        len = amp_v3_dist(a, b) * (1 - t);
        if (len >= need) {
            *sx2 = i;
            *t2 = t + need / amp_v3_dist(a, b);
            return 1;
        }
        need -= len;
        i = (i + 1) % X->n;
        t = 0;
    }
    return 0;
}

/* Parameter @p u on segment i of L moved off its ends by a tenth of the
 * segment or a tenth of a bead radius, whichever is less. */
static double into_segment(const jloop *L, size_t i, double u, double r)
{
    double len = amp_v3_dist(L->v[i].p, L->v[(i + 1) % L->n].p);
    double m = fmin(0.1, 0.1 * r / fmax(len, 1e-12));
    return fmin(fmax(u, m), 1 - m);
}

/* q1 == q2: both nearest points of Y are one corner of it (a small loop, or
 * the end of a skin strip). The connectors then straddle that corner: q1
 * on the segment before it and q2 on the one after, each up to half the
 * connector spacing from the corner, in the order that keeps the two
 * connectors from crossing (spreading both over one long segment would
 * stretch a connector across the strips beside it). */
static void straddle_corner(const joiner *J, cut *c, amp_vec2 p1, amp_vec2 p2, double ell)
{
    const jloop *Y = &J->lp[c->ly];
    size_t a = c->u1 >= 0.5 ? c->j1 : (c->j1 + Y->n - 1) % Y->n, b = (a + 1) % Y->n;
    double la = amp_v3_dist(Y->v[a].p, Y->v[b].p), lb = amp_v3_dist(Y->v[b].p, Y->v[(b + 1) % Y->n].p);
    c->j1 = a;
    c->u1 = 1 - fmin(0.5 * ell, 0.4 * la) / fmax(la, 1e-12);
    c->j2 = b;
    c->u2 = fmin(0.5 * ell, 0.4 * lb) / fmax(lb, 1e-12);
    if (proper_cross(p1, P2v(seg_point(Y, c->j1, c->u1).p), p2, P2v(seg_point(Y, c->j2, c->u2).p))) {
        size_t j = c->j1;
        double u = c->u1;
        c->j1 = c->j2;
        c->u1 = c->u2;
        c->j2 = j;
        c->u2 = u;
    }
}

/* Try a splice of the loop holding segment sx of lx with another set. */
static int try_segment(joiner *J, size_t *uf, size_t lx, size_t sx, double ell, amp_status *st)
{
    const jloop *X = &J->lp[lx];
    double d1, d2;
    size_t l2, rx = amp_uf_find(uf, lx), fw, bw;
    amp_pvert P1, P2, Q1, Q2;
    amp_vec2 p1, p2, q1, q2;
    cut c;
    c.lx = lx;
    c.sx = sx;
    c.t1 = 0.5;
    if (amp_v3_dist(X->v[sx].p, X->v[(sx + 1) % X->n].p) < 1e-6 * J->r ||
        !second_point(X, sx, ell, &c.sx2, &c.t2) || !all_printed(X, sx, forward_span(X->n, sx, 0, c.sx2, 0), J->r))
        return 0;
    P1 = seg_point(X, sx, c.t1);
    P2 = seg_point(X, c.sx2, c.t2);
    p1 = P2v(P1.p);
    p2 = P2v(P2.p);
    if (!nearest(J, uf, rx, p1, &c.ly, &c.j1, &c.u1, &d1) || !nearest(J, uf, rx, p2, &l2, &c.j2, &c.u2, &d2) ||
        l2 != c.ly || d1 < 1e-3 * J->r || d2 < 1e-3 * J->r)
        return 0;
    /* a nearest point at a corner of Y (its vertex cone) moves into the
     * segment: a connector ending on a vertex would touch the segment
     * before it too. The move is a tenth of a bead at most: on a long
     * segment (a skin strip) a tenth of its length would stretch the
     * connector across the strips beside it */
    c.u1 = into_segment(&J->lp[c.ly], c.j1, c.u1, J->r);
    c.u2 = into_segment(&J->lp[c.ly], c.j2, c.u2, J->r);
    Q1 = seg_point(&J->lp[c.ly], c.j1, c.u1);
    Q2 = seg_point(&J->lp[c.ly], c.j2, c.u2);
    if (hypot(Q1.p.x - Q2.p.x, Q1.p.y - Q2.p.y) < 1e-3 * ell)
        straddle_corner(J, &c, p1, p2, ell);
    /* the left-out stretch of Y must be short and printed throughout */
    fw = forward_span(J->lp[c.ly].n, c.j1, c.u1, c.j2, c.u2);
    bw = forward_span(J->lp[c.ly].n, c.j2, c.u2, c.j1, c.u1);
    if (fw > 8 && bw > 8)
        return 0;
    c.ybackward = fw <= bw;
    if (!all_printed(&J->lp[c.ly], c.ybackward ? c.j1 : c.j2, c.ybackward ? fw : bw, J->r))
        return 0;
    q1 = P2v(seg_point(&J->lp[c.ly], c.j1, c.u1).p);
    q2 = P2v(seg_point(&J->lp[c.ly], c.j2, c.u2).p);
    if (proper_cross(p1, q1, p2, q2))
        return 0;
    if (connector_blocked(J, p1, q1, lx, sx, c.ly, c.j1) || connector_blocked(J, p2, q2, lx, c.sx2, c.ly, c.j2))
        return 0;
    *st = splice(J, &c);
    if (*st == AMP_OK) {
        amp_uf_union(uf, c.ly, lx);
        *st = grid_build(J);
    }
    return 1;
}

/* Does the loop fit in a box of diagonal @p d? */
static int speck(const amp_pvert *v, size_t n, double d)
{
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
    size_t i;
    for (i = 0; i < n; i++) {
        x0 = fmin(x0, v[i].p.x);
        y0 = fmin(y0, v[i].p.y);
        x1 = fmax(x1, v[i].p.x);
        y1 = fmax(y1, v[i].p.y);
    }
    return hypot(x1 - x0, y1 - y0) < d;
}

/* Is path i of @p in a closed object loop (joined; anything else is copied
 * as it is)? */
static int closed_object(const amp_pathset *in, size_t i)
{
    const amp_pvert *v = amp_pathset_path_verts(in, i);
    size_t n = in->paths[i].n;
    return in->paths[i].role == AMP_ROLE_OBJECT && n >= 4 && v[0].p.x == v[n - 1].p.x && v[0].p.y == v[n - 1].p.y;
}

/* The closed object loops of paths [first, npaths) of @p in into J's loops,
 * each a set of its own in @p uf; specks left out are counted in *nspeck. */
static amp_status collect_loops(joiner *J, size_t *uf, const amp_pathset *in, size_t first, size_t *nspeck)
{
    size_t i;
    int big = 0;
    /* a loop under a bead across (r) next to larger ones is a speck: a
     * lattice piece cutting a corner of a region, too small for a splice's
     * two connectors; alone it is the island's print and stays unless under
     * r/4 */
    for (i = first; i < in->npaths && !big; i++) {
        const amp_pvert *v = amp_pathset_path_verts(in, i);
        size_t n = in->paths[i].n;
        big = in->paths[i].role == AMP_ROLE_OBJECT && n >= 4 && !speck(v, n, J->r);
    }
    for (i = first; i < in->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(in, i);
        size_t n = in->paths[i].n;
        jloop *L = &J->lp[J->nl];
        if (!closed_object(in, i))
            continue;
        if (speck(v, n, big ? J->r : 0.25 * J->r)) {
            (*nspeck)++; /* a loop smaller than a quarter bead: inside the beads around it */
            continue;
        }
        if (!(L->v = amp_alloc(J->al, n * sizeof *L->v)))
            return AMP_ERR_NOMEM;
        /* the cyclic loop drops the closing vertex unless it carries
         * another radius (a tour ending on a pseudo edge) */
        L->n = v[n - 1].r == v[0].r ? n - 1 : n;
        memcpy(L->v, v, L->n * sizeof *v);
        L->alive = 1;
        uf[J->nl] = J->nl;
        J->nl++;
    }
    return AMP_OK;
}

/* The section's rings, as walls in the grid: connectors may not cross them. */
static amp_status add_walls(joiner *J, size_t *uf, const amp_polyset *walls)
{
    size_t i, k;
    for (i = 0; i < walls->nrings; i++) {
        const amp_vec2 *p = amp_polyset_ring(walls, i);
        jloop *L = &J->lp[J->nl];
        L->n = walls->rings[i].n;
        if (!(L->v = amp_alloc(J->al, (L->n + 1) * sizeof *L->v)))
            return AMP_ERR_NOMEM;
        for (k = 0; k < L->n; k++) {
            L->v[k].p = amp_v3(p[k].x, p[k].y, 0);
            L->v[k].r = 0;
        }
        L->alive = L->wall = 1;
        uf[J->nl] = J->nl;
        J->nl++;
    }
    return AMP_OK;
}

/* Splices until one set is left or none is found: connectors 2r apart (their
 * beads just touch), closer where a loop offers no straight stretch that
 * long (small infill components). */
static amp_status splice_all(joiner *J, size_t *uf, size_t sets)
{
    size_t i, k;
    int pass, progress;
    amp_status st = AMP_OK;
    for (pass = 0; pass < 3 && sets > 1 && st == AMP_OK; pass++) {
        double ell = 2 * J->r / (double)(1 << pass);
        progress = 1;
        while (sets > 1 && progress && st == AMP_OK) {
            progress = 0;
            for (k = 0; k < J->nl && !progress && st == AMP_OK; k++)
                for (i = 0; J->lp[k].alive && !J->lp[k].wall && i < J->lp[k].n && !progress && st == AMP_OK; i++)
                    progress = try_segment(J, uf, k, i, ell, &st);
            sets -= (size_t)progress;
        }
    }
    return st;
}

/* The joined loops closed again, then the rest of @p in (open strokes,
 * support stretches) unchanged, at height @p h (> 0). */
static amp_status write_joined(const joiner *J, const amp_pathset *in, size_t first, double h, amp_pathset *out,
                               size_t *nout, amp_error *err)
{
    size_t i, k;
    amp_status st = AMP_OK;
    for (k = 0; k < J->nl && st == AMP_OK; k++) {
        const jloop *L = &J->lp[k];
        if (!L->alive || L->wall)
            continue;
        st = amp_pathset_begin(out, AMP_ROLE_OBJECT, err);
        for (i = 0; i <= L->n && st == AMP_OK; i++)
            st = amp_pathset_push(out, L->v[i % L->n].p, L->v[i % L->n].r, err);
        if (st == AMP_OK && h > 0)
            st = amp_pathset_set_height(out, h, err);
        (*nout)++;
    }
    for (i = first; i < in->npaths && st == AMP_OK; i++) {
        const amp_pvert *v = amp_pathset_path_verts(in, i);
        if (closed_object(in, i))
            continue; /* joined above, or a speck */
        if ((st = amp_pathset_add(out, in->paths[i].role, v, in->paths[i].n, err)) == AMP_OK && h > 0)
            st = amp_pathset_set_height(out, h, err);
        *nout += in->paths[i].role == AMP_ROLE_OBJECT;
    }
    return st;
}

amp_status amp_cp_join_loops(const amp_pathset *in, size_t first, const amp_polyset *walls, double r, double h,
                             amp_pathset *out, size_t *nout, size_t *nspeck, amp_error *err)
{
    joiner J;
    size_t *uf = NULL, k, sets;
    amp_status st;
    memset(&J, 0, sizeof J);
    J.al = out->alloc;
    J.r = r;
    J.dmax = 4.5 * r;
    *nout = 0;
    J.lp = amp_calloc(J.al, in->npaths - first + walls->nrings + 1, sizeof *J.lp);
    uf = amp_alloc(J.al, (in->npaths - first + walls->nrings + 1) * sizeof *uf);
    st = !J.lp || !uf ? AMP_ERR_NOMEM : collect_loops(&J, uf, in, first, nspeck);
    sets = J.nl;
    if (st == AMP_OK && sets > 1 && (st = add_walls(&J, uf, walls)) == AMP_OK && (st = grid_build(&J)) == AMP_OK)
        st = splice_all(&J, uf, sets);
    if (st == AMP_OK)
        st = write_joined(&J, in, first, h, out, nout, err);
    for (k = 0; J.lp && k < J.nl; k++)
        amp_free(J.al, J.lp[k].v);
    amp_free(J.al, J.lp);
    amp_free(J.al, uf);
    grid_free(J.al, &J.g);
    if (st == AMP_ERR_NOMEM)
        return amp_fail(err, st, 0, "out of memory joining the strokes of an island");
    return st;
}
