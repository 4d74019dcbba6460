/* The inward Minkowski offset of a polygon set, [P2 §2.2] step 5
 * (amp_polyset_inset of include/ampath/polygon.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/polygon.h"
#include "ampath/vec.h"
#include "polygon_internal.h"

/* ---- inward Minkowski offset ---- */

/* |p - q| <= d, without hypot (its overflow care is a call per vertex pair; coordinates are millimetres) */
static inline int within(amp_vec2 p, amp_vec2 q, double d)
{
    double dx = p.x - q.x, dy = p.y - q.y;
    return dx * dx + dy * dy <= d * d;
}

typedef struct raw_seg {
    amp_vec2 a, b;
    size_t na, nb; /* node ids of the end points */
} raw_seg;


typedef struct inset_ctx {
    const amp_allocator *al;
    raw_seg *seg;
    size_t nseg, cap_seg;
    amp_vec2 *node;
    size_t nnode, cap_node;
    pg_splits spl;
    double dropped; /* longest chain dropped at a dead end (mm) */
} inset_ctx;

static amp_status new_node(inset_ctx *c, amp_vec2 p, size_t *id)
{
    void *v = c->node;
    if (amp_grow(c->al, &v, &c->cap_node, c->nnode + 1, sizeof *c->node) != AMP_OK)
        return AMP_ERR_NOMEM;
    c->node = v;
    c->node[c->nnode] = p;
    *id = c->nnode++;
    return AMP_OK;
}

static amp_status add_seg(inset_ctx *c, size_t na, size_t nb)
{
    void *v = c->seg;
    if (na == nb)
        return AMP_OK;
    if (amp_grow(c->al, &v, &c->cap_seg, c->nseg + 1, sizeof *c->seg) != AMP_OK)
        return AMP_ERR_NOMEM;
    c->seg = v;
    c->seg[c->nseg].a = c->node[na];
    c->seg[c->nseg].b = c->node[nb];
    c->seg[c->nseg].na = na;
    c->seg[c->nseg].nb = nb;
    c->nseg++;
    return AMP_OK;
}

static amp_status add_split(inset_ctx *c, size_t s, double t, size_t node)
{
    return pg_splits_add(c->al, &c->spl, s, t, node);
}

/* Raw offset curve of one ring to its interior side (left when @p left):
 * edges shifted by r, direct joins at convex vertices (trimmed later) and
 * circumscribed arcs around reflex vertices, so that every point of the raw
 * curve is at distance <= r from its own edge and the true offset boundary
 * {d = r} is contained in it. */
static amp_status raw_ring(inset_ctx *c, const amp_vec2 *p, size_t n, int left, double r, double dstep)
{
    size_t k, first = 0, prev = 0, have = 0, id;
    amp_status st;
    for (k = 0; k < n; k++) {
        size_t i0 = left ? k : n - 1 - k, i1 = left ? (k + 1) % n : (2 * n - 2 - k) % n;
        size_t i2 = left ? (k + 2) % n : (3 * n - 3 - k) % n;
        amp_vec2 a = p[i0], b = p[i1], q = p[i2];
        double dx = b.x - a.x, dy = b.y - a.y, l = hypot(dx, dy), ex = q.x - b.x, ey = q.y - b.y, m = hypot(ex, ey);
        amp_vec2 n1, n2, sa, sb;
        size_t ida, idb;
        if (l == 0.0 || m == 0.0)
            continue;
        n1 = amp_v2(-dy / l, dx / l);
        n2 = amp_v2(-ey / m, ex / m);
        sa = amp_v2(a.x + r * n1.x, a.y + r * n1.y);
        sb = amp_v2(b.x + r * n1.x, b.y + r * n1.y);
        if ((st = new_node(c, sa, &ida)) != AMP_OK || (st = new_node(c, sb, &idb)) != AMP_OK)
            return st;
        if (have && (st = add_seg(c, prev, ida)) != AMP_OK)
            return st;
        if (!have)
            first = ida;
        have = 1;
        if ((st = add_seg(c, ida, idb)) != AMP_OK)
            return st;
        prev = idb;
        if (amp_v2_orient(a, b, q) < 0) {
            /* reflex vertex b: arc from n1 to n2 turning right, by tangent segments */
            double a0 = atan2(n1.y, n1.x), a1 = atan2(n2.y, n2.x), sweep = a0 - a1, rc;
            int steps, j;
            while (sweep < 0)
                sweep += 2 * AMP_PI;
            while (sweep >= 2 * AMP_PI)
                sweep -= 2 * AMP_PI;
            steps = (int)ceil(sweep / dstep);
            if (steps < 1)
                steps = 1;
            if (steps > 4096)
                steps = 4096;
            rc = r / cos(0.5 * sweep / steps);
            for (j = 1; j <= steps; j++) {
                double ang = a0 - (j - 0.5) * sweep / steps;
                if ((st = new_node(c, amp_v2(b.x + rc * cos(ang), b.y + rc * sin(ang)), &id)) != AMP_OK)
                    return st;
                if ((st = add_seg(c, prev, id)) != AMP_OK)
                    return st;
                prev = id;
            }
        }
    }
    if (have)
        return add_seg(c, prev, first);
    return AMP_OK;
}

static int cmp_seg_x(const void *a, const void *b)
{
    const raw_seg *s = a, *t = b;
    double x = amp_dmin(s->a.x, s->b.x), y = amp_dmin(t->a.x, t->b.x);
    return x < y ? -1 : (x > y ? 1 : 0);
}

/* Intersect segments i and j once; the crossing becomes one shared node. */
static amp_status intersect(inset_ctx *c, size_t i, size_t j)
{
    raw_seg *s = &c->seg[i], *t = &c->seg[j];
    double d1 = amp_v2_orient(s->a, s->b, t->a), d2 = amp_v2_orient(s->a, s->b, t->b);
    double d3 = amp_v2_orient(t->a, t->b, s->a), d4 = amp_v2_orient(t->a, t->b, s->b), den, u, v;
    size_t id;
    amp_status st;
    if (s->na == t->na || s->na == t->nb || s->nb == t->na || s->nb == t->nb)
        return AMP_OK; /* neighbours in a raw chain meet at their shared node */
    if ((d1 > 0 && d2 > 0) || (d1 < 0 && d2 < 0) || (d3 > 0 && d4 > 0) || (d3 < 0 && d4 < 0))
        return AMP_OK;
    den = d3 - d4;
    if (den == 0.0 || d1 - d2 == 0.0)
        return AMP_OK; /* collinear overlap: pieces are classified independently */
    u = d3 / den;               /* parameter on s */
    v = d1 / (d1 - d2);         /* parameter on t */
    if (u <= 0.0 && v <= 0.0)
        return AMP_OK;
    if (u <= 0.0)
        return add_split(c, j, v, s->na); /* T-junction at an end of s */
    if (u >= 1.0)
        return add_split(c, j, v, s->nb);
    if (v <= 0.0)
        return add_split(c, i, u, t->na);
    if (v >= 1.0)
        return add_split(c, i, u, t->nb);
    if ((st = new_node(c, amp_v2(s->a.x + u * (s->b.x - s->a.x), s->a.y + u * (s->b.y - s->a.y)), &id)) != AMP_OK)
        return st;
    if ((st = add_split(c, i, u, id)) != AMP_OK)
        return st;
    return add_split(c, j, v, id);
}

/* Uniform grid of the original edges, to find quickly whether an edge lies
 * closer than r to a point. */
typedef struct egrid {
    double x0, y0, cell;
    long nx, ny;
    size_t *start, *item; /* CSR: cell -> edge indices */
    amp_vec2 *ea, *eb;
    size_t ne;
} egrid;

static void egrid_range(const egrid *g, double xa, double xb, double ya, double yb, long *ix0, long *ix1, long *iy0,
                        long *iy1)
{
    *ix0 = (long)floor((xa - g->x0) / g->cell);
    *ix1 = (long)floor((xb - g->x0) / g->cell);
    *iy0 = (long)floor((ya - g->y0) / g->cell);
    *iy1 = (long)floor((yb - g->y0) / g->cell);
    *ix0 = *ix0 < 0 ? 0 : (*ix0 >= g->nx ? g->nx - 1 : *ix0);
    *ix1 = *ix1 < 0 ? 0 : (*ix1 >= g->nx ? g->nx - 1 : *ix1);
    *iy0 = *iy0 < 0 ? 0 : (*iy0 >= g->ny ? g->ny - 1 : *iy0);
    *iy1 = *iy1 < 0 ? 0 : (*iy1 >= g->ny ? g->ny - 1 : *iy1);
}

static amp_status egrid_build(egrid *g, const amp_polyset *in, double r, const amp_allocator *al)
{
    double xa = HUGE_VAL, xb = -HUGE_VAL, ya = HUGE_VAL, yb = -HUGE_VAL;
    size_t i, k, e = 0, pass, total = 0;
    memset(g, 0, sizeof *g);
    g->ne = in->npts;
    g->ea = amp_alloc(al, (g->ne + 1) * sizeof *g->ea);
    g->eb = amp_alloc(al, (g->ne + 1) * sizeof *g->eb);
    if (!g->ea || !g->eb)
        return AMP_ERR_NOMEM;
    for (i = 0; i < in->nrings; i++) {
        const amp_vec2 *p = amp_polyset_ring(in, i);
        size_t n = in->rings[i].n;
        for (k = 0; k < n; k++, e++) {
            g->ea[e] = p[k];
            g->eb[e] = p[(k + 1) % n];
            xa = amp_dmin(xa, p[k].x);
            xb = amp_dmax(xb, p[k].x);
            ya = amp_dmin(ya, p[k].y);
            yb = amp_dmax(yb, p[k].y);
        }
    }
    g->cell = fmax(r, fmax(xb - xa, yb - ya) / 256.0);
    if (!(g->cell > 0))
        g->cell = 1.0;
    g->x0 = xa;
    g->y0 = ya;
    g->nx = (long)((xb - xa) / g->cell) + 1;
    g->ny = (long)((yb - ya) / g->cell) + 1;
    g->start = amp_calloc(al, (size_t)(g->nx * g->ny + 1), sizeof *g->start);
    if (!g->start)
        return AMP_ERR_NOMEM;
    /* two passes: count, then fill (CSR) */
    for (pass = 0; pass < 2; pass++) {
        for (e = 0; e < g->ne; e++) {
            long ix0, ix1, iy0, iy1, x, y;
            egrid_range(g, amp_dmin(g->ea[e].x, g->eb[e].x), amp_dmax(g->ea[e].x, g->eb[e].x), amp_dmin(g->ea[e].y, g->eb[e].y),
                        amp_dmax(g->ea[e].y, g->eb[e].y), &ix0, &ix1, &iy0, &iy1);
            for (y = iy0; y <= iy1; y++)
                for (x = ix0; x <= ix1; x++) {
                    size_t cidx = (size_t)(y * g->nx + x);
                    if (pass == 0)
                        g->start[cidx + 1]++;
                    else
                        g->item[g->start[cidx]++] = e;
                }
        }
        if (pass == 0) {
            for (i = 0; i < (size_t)(g->nx * g->ny); i++)
                g->start[i + 1] += g->start[i];
            total = g->start[g->nx * g->ny];
            g->item = amp_alloc(al, (total + 1) * sizeof *g->item);
            if (!g->item)
                return AMP_ERR_NOMEM;
        }
    }
    /* the fill pass advanced start[c] to the end of cell c: shift back */
    for (i = (size_t)(g->nx * g->ny); i > 0; i--)
        g->start[i] = g->start[i - 1];
    g->start[0] = 0;
    return AMP_OK;
}

static void egrid_free(egrid *g, const amp_allocator *al)
{
    amp_free(al, g->ea);
    amp_free(al, g->eb);
    amp_free(al, g->start);
    amp_free(al, g->item);
}

/* Non-zero when some edge is closer than @p lim to q. */
static int egrid_closer(const egrid *g, amp_vec2 q, double lim)
{
    long ix0, ix1, iy0, iy1, x, y;
    size_t k;
    egrid_range(g, q.x - lim, q.x + lim, q.y - lim, q.y + lim, &ix0, &ix1, &iy0, &iy1);
    for (y = iy0; y <= iy1; y++)
        for (x = ix0; x <= ix1; x++) {
            size_t cidx = (size_t)(y * g->nx + x);
            for (k = g->start[cidx]; k < g->start[cidx + 1]; k++) {
                size_t e = g->item[k];
                if (seg_dist2(q, g->ea[e], g->eb[e]) < lim * lim)
                    return 1;
            }
        }
    return 0;
}

/* Point in the region of the grid's edges (even-odd, half-open rule as
 * amp_ring_contains with tol 0): a ray to +x through the row of cells of q,
 * each crossing counted in the cell that holds it. Linear in the row, not
 * in the whole boundary. */
static int egrid_inside(const egrid *g, amp_vec2 q)
{
    long ix0, ix1, iy0, iy1, x;
    size_t k, cnt = 0;
    egrid_range(g, q.x, q.x, q.y, q.y, &ix0, &ix1, &iy0, &iy1);
    if (q.y < g->y0 || q.y > g->y0 + g->cell * (double)g->ny)
        return 0;
    for (x = ix0; x < g->nx; x++) {
        size_t cidx = (size_t)(iy0 * g->nx + x);
        for (k = g->start[cidx]; k < g->start[cidx + 1]; k++) {
            amp_vec2 a = g->ea[g->item[k]], b = g->eb[g->item[k]];
            double xi;
            long cx, d0, d1, d2;
            if ((a.y > q.y) == (b.y > q.y))
                continue;
            xi = a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if (!(q.x < xi))
                continue;
            egrid_range(g, xi, xi, q.y, q.y, &cx, &d0, &d1, &d2);
            cnt += cx == x;
        }
    }
    return (int)(cnt & 1u);
}

/* Copy ring p into out without the vertices closer than tol to the segment
 * joining their kept predecessor and their successor. Returns the count. */
static size_t simplify_ring(const amp_vec2 *p, size_t n, double tol, amp_vec2 *out)
{
    size_t i, m = 0, pass;
    for (i = 0; i < n; i++) {
        /* pop while the last kept point is nearly on the chord to p[i] */
        while (m >= 2 && seg_dist2(out[m - 1], out[m - 2], p[i]) < tol * tol)
            m--;
        out[m++] = p[i];
    }
    /* the closing corner(s) */
    for (pass = 0; pass < 2 && m >= 3; pass++) {
        if (seg_dist2(out[m - 1], out[m - 2], out[0]) < tol * tol)
            m--;
        else if (seg_dist2(out[0], out[m - 1], out[1]) < tol * tol) {
            memmove(out, out + 1, (m - 1) * sizeof *out);
            m--;
        }
    }
    return m;
}

typedef struct piece {
    size_t na, nb;
    int used;
} piece;

/* Remove needles from a stitched ring in place: a vertex equal to its
 * predecessor, and the tip B of a back-and-forth A-B-A (a swallowtail piece
 * run both ways) or of a tiny loop A-B-C-A within @p small of A, cyclically.
 * Returns the new count. */
static size_t despike(amp_vec2 *p, size_t n, double tol, double small)
{
    size_t m = 0, i, pass;
    for (i = 0; i < n; i++) {
        size_t k;
        if (m >= 1 && within(p[i], p[m - 1], tol))
            continue;
        /* p[i] repeats p[m - k] for a small k: p[m - k + 1 .. m - 1] is a
         * needle (k = 2) or a tiny loop within @p small of it; cut it out */
        for (k = 2; k <= 8 && k <= m; k++)
            if (within(p[i], p[m - k], tol)) {
                size_t q;
                for (q = m - k + 1; q < m; q++)
                    if (!within(p[q], p[i], small))
                        break;
                if (q == m)
                    break;
            }
        if (k <= 8 && k <= m) {
            m -= k - 1;
            continue;
        }
        p[m++] = p[i];
    }
    /* the seam: the same patterns across the end of the array */
    for (pass = 0; pass < 4 && m >= 3; pass++) {
        if (within(p[0], p[m - 1], tol))
            m--;
        else if (within(p[1], p[m - 1], tol)) {
            memmove(p, p + 1, (m - 1) * sizeof *p); /* p[0] was a tip */
            m -= 2;
        } else if (within(p[0], p[m - 2], tol))
            m -= 2; /* p[m - 1] was a tip, p[m - 2] repeats p[0] */
    }
    return m;
}

/* Cut small loops out of a stitched ring in place: where segment i properly
 * crosses segment j within the next 16 segments (a swallowtail piece kept
 * on both sides, so the ring crosses itself near a tight reflex corner),
 * the vertices between become the crossing point. Returns the new count. */
static size_t untangle(amp_vec2 *p, size_t n)
{
    size_t i, j, k, m, from = 0;
    int again = 1;
    while (again && n >= 4) {
        again = 0;
        for (i = from; i + 2 < n && !again; i++) {
            amp_vec2 a = p[i], b = p[i + 1];
            double x0 = amp_dmin(a.x, b.x), x1 = amp_dmax(a.x, b.x), y0 = amp_dmin(a.y, b.y), y1 = amp_dmax(a.y, b.y);
            for (j = i + 2; j < n && j <= i + 16 && !again; j++) {
                amp_vec2 c = p[j], d = p[(j + 1) % n];
                double d1, d2, d3, d4, t;
                /* disjoint boxes cannot cross properly (most pairs end here) */
                if (amp_dmax(c.x, d.x) < x0 || amp_dmin(c.x, d.x) > x1 || amp_dmax(c.y, d.y) < y0 || amp_dmin(c.y, d.y) > y1)
                    continue;
                d1 = amp_v2_orient(a, b, c);
                d2 = amp_v2_orient(a, b, d);
                d3 = amp_v2_orient(c, d, a);
                d4 = amp_v2_orient(c, d, b);
                if ((j + 1) % n == i || !(((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) &&
                                          ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))))
                    continue;
                t = d3 / (d3 - d4);
                p[i + 1] = amp_v2(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y));
                /* drop p[i + 2 .. j] */
                for (k = i + 2, m = j + 1; m < n; k++, m++)
                    p[k] = p[m];
                n -= j - i - 1;
                again = 1;
                /* the pairs of segments before i - 16 reach only segments before i, unchanged and found
                 * uncrossed: the scan goes on from there, finding the same first crossing as from 0 */
                from = i > 16 ? i - 16 : 0;
            }
        }
    }
    return n;
}

/* Cut loops pinched off at a repeated vertex out of a stitched ring in place: where p[j] repeats p[i]
 * (within @p tol, at most 64 vertices on) and the loop p[i .. j - 1] encloses less than @p small, the
 * loop goes. The offset of a sliver leaves such a lobe where its two sides meet at a vertex (a torus's
 * first layer at 0.15 mm: a lobe of 5e-5 mm^2 at an inset of 0.06 mm); the ring passes the pinch twice
 * there, and a path along it crosses itself at that point. Returns the new count. */
static size_t cut_pinched(amp_vec2 *p, size_t n, double tol, double small)
{
    size_t i = 0, j;
    while (i + 3 < n) {
        for (j = i + 3; j < n && j <= i + 64; j++)
            if (within(p[j], p[i], tol) && fabs(amp_ring_area(p + i, j - i)) < small)
                break;
        if (j < n && j <= i + 64 && n - (j - i) >= 3) {
            memmove(p + i + 1, p + j + 1, (n - j - 1) * sizeof *p);
            n -= j - i;
            continue; /* p[i] may pinch again */
        }
        i++;
    }
    return n;
}

/* Rotate a ring in place by half its length (three reversals). */
static void rotate_half(amp_vec2 *p, size_t n)
{
    size_t h = n / 2;
    amp_ring_reverse(p, h);
    amp_ring_reverse(p + h, n - h);
    amp_ring_reverse(p, n);
}

/* Unused piece whose start is nearest to node @p nb within @p tol (npc + 1:
 * the ring's start node @p start is nearer: close the ring; npc: none). */
static size_t bridge_gap(const inset_ctx *c, const piece *pc, size_t npc, size_t nb, size_t start, double tol)
{
    amp_vec2 q = c->node[nb];
    double best = hypot(c->node[start].x - q.x, c->node[start].y - q.y);
    size_t i, at = best <= tol ? npc + 1 : npc;
    if (!(best <= tol))
        best = tol;
    for (i = 0; i < npc; i++) {
        double d;
        if (pc[i].used)
            continue;
        d = hypot(c->node[pc[i].na].x - q.x, c->node[pc[i].na].y - q.y);
        if (d < best) {
            best = d;
            at = i;
        }
    }
    return at;
}

/* The pieces of the raw offset curves that lie on the offset boundary. */
typedef struct piece_list {
    piece *pc;
    size_t n, cap;
} piece_list;

/* Step 1: the raw offset curves of every ring, on the interior side given by
 * the parity of its nesting depth. */
static amp_status raw_offsets(inset_ctx *c, const amp_polyset *in, double r, double dstep)
{
    size_t i, j;
    amp_status st = AMP_OK;
    for (i = 0; i < in->nrings && st == AMP_OK; i++) {
        const amp_vec2 *p = amp_polyset_ring(in, i);
        size_t n = in->rings[i].n, depth = 0;
        double area = amp_ring_area(p, n);
        for (j = 0; j < in->nrings; j++)
            if (j != i && amp_ring_contains(amp_polyset_ring(in, j), in->rings[j].n, p[0], 0.0) == 1)
                depth++;
        st = raw_ring(c, p, n, (area > 0) == (depth % 2 == 0), r, dstep);
    }
    return st;
}

/* Step 2: all mutual crossings of the raw segments (sweep over x). */
static amp_status raw_crossings(inset_ctx *c)
{
    size_t i, j;
    amp_status st = AMP_OK;
    if (c->nseg > 1)
        qsort(c->seg, c->nseg, sizeof *c->seg, cmp_seg_x);
    for (i = 0; i < c->nseg && st == AMP_OK; i++) {
        double xmax = amp_dmax(c->seg[i].a.x, c->seg[i].b.x);
        double ylo = amp_dmin(c->seg[i].a.y, c->seg[i].b.y), yhi = amp_dmax(c->seg[i].a.y, c->seg[i].b.y);
        for (j = i + 1; j < c->nseg && st == AMP_OK; j++) {
            if (amp_dmin(c->seg[j].a.x, c->seg[j].b.x) > xmax)
                break;
            if (amp_dmax(c->seg[j].a.y, c->seg[j].b.y) < ylo || amp_dmin(c->seg[j].a.y, c->seg[j].b.y) > yhi)
                continue;
            st = intersect(c, i, j);
        }
    }
    return st;
}

/* Step 3: split the raw segments at their crossings and keep the pieces on
 * the offset boundary {d = r} (midpoint no closer than r to the input,
 * and inside it), into @p pl. */
static amp_status boundary_pieces(inset_ctx *c, const egrid *g, double r, piece_list *pl)
{
    double lim = r * (1.0 - 1e-9);
    size_t i, k;
    if (c->spl.n > 1)
        qsort(c->spl.v, c->spl.n, sizeof *c->spl.v, pg_split_cmp);
    for (i = 0, k = 0; i < c->nseg; i++) {
        size_t cur = c->seg[i].na, nxt;
        for (;;) {
            if (k < c->spl.n && c->spl.v[k].seg == i)
                nxt = c->spl.v[k++].node;
            else
                nxt = c->seg[i].nb;
            if (nxt != cur) {
                amp_vec2 a = c->node[cur], b = c->node[nxt], m = amp_v2(0.5 * (a.x + b.x), 0.5 * (a.y + b.y));
                if (!egrid_closer(g, m, lim) && egrid_inside(g, m)) {
                    void *v = pl->pc;
                    if (amp_grow(c->al, &v, &pl->cap, pl->n + 1, sizeof *pl->pc) != AMP_OK)
                        return AMP_ERR_NOMEM;
                    pl->pc = v;
                    pl->pc[pl->n].na = cur;
                    pl->pc[pl->n].nb = nxt;
                    pl->pc[pl->n].used = 0;
                    pl->n++;
                }
            }
            cur = nxt;
            if (nxt == c->seg[i].nb && !(k < c->spl.n && c->spl.v[k].seg == i))
                break;
        }
    }
    return AMP_OK;
}

/* Step 4, one ring: the chain of unused pieces from piece @p i (pieces
 * sorted by start node, @p first: a node's first piece) until it closes,
 * into *loop (*len vertices; 0: the chain was dropped, its length kept in
 * c->dropped when it is the longest yet). */
static amp_status trace_ring(inset_ctx *c, piece_list *pl, const size_t *first, size_t i, double r,
                             amp_vec2 **loop, size_t *cap_loop, size_t *len)
{
    piece *pc = pl->pc;
    size_t npc = pl->n, start = pc[i].na, at = i;
    *len = 0;
    for (;;) {
        void *v = *loop;
        size_t nb;
        pc[at].used = 1;
        if (amp_grow(c->al, &v, cap_loop, *len + 1, sizeof **loop) != AMP_OK)
            return AMP_ERR_NOMEM;
        *loop = v;
        (*loop)[(*len)++] = c->node[pc[at].na];
        nb = pc[at].nb;
        if (nb == start)
            return AMP_OK;
        /* next unused piece leaving node nb */
        for (at = first[nb]; at < npc && pc[at].na == nb && pc[at].used; at++)
            ;
        if (at >= npc || pc[at].na != nb) {
            /* dead end: a sliver piece of a swallowtail (crossings of nearly
             * parallel raw segments) was misclassified. Bridge the gap to
             * the nearest piece start, or close the ring, when it is within
             * r/4 (the boundary moves by at most the gap); otherwise the
             * chain is dropped. */
            at = bridge_gap(c, pc, npc, nb, start, 0.25 * r);
            if (at == npc + 1)
                return AMP_OK;
            if (at >= npc) {
                double l = 0.0;
                size_t q;
                for (q = 1; q < *len; q++)
                    l += hypot((*loop)[q].x - (*loop)[q - 1].x, (*loop)[q].y - (*loop)[q - 1].y);
                if (l > c->dropped)
                    c->dropped = l;
                *len = 0;
                return AMP_OK;
            }
        }
    }
}

/* Step 4, cleaning a stitched ring: spikes and small loops out, and once
 * more half a turn on (a needle or loop across the seam). */
static size_t clean_ring(amp_vec2 *loop, size_t len, double r)
{
    if (len >= 3)
        len = despike(loop, len, 1e-9 * r, 0.05 * r);
    if (len >= 4)
        len = untangle(loop, len);
    if (len >= 4)
        len = cut_pinched(loop, len, 1e-9 * r, 0.1 * r * r);
    if (len >= 4) {
        rotate_half(loop, len);
        len = despike(loop, len, 1e-9 * r, 0.05 * r);
        if (len >= 4)
            len = untangle(loop, len);
        if (len >= 4)
            len = cut_pinched(loop, len, 1e-9 * r, 0.1 * r * r);
    }
    return len;
}

/* Step 4: stitch the pieces into rings by node ids, into @p out. */
static amp_status stitch_rings(inset_ctx *c, piece_list *pl, double r, amp_polyset *out, amp_error *err)
{
    size_t *first, i, len, cap_loop = 0, npc = pl->n;
    amp_vec2 *loop = NULL;
    amp_status st = AMP_OK;
    piece *sorted;
    if (!(first = amp_calloc(c->al, c->nnode + 2, sizeof *first)))
        return AMP_ERR_NOMEM;
    if (!(sorted = amp_alloc(c->al, (npc + 1) * sizeof *sorted))) {
        amp_free(c->al, first);
        return AMP_ERR_NOMEM;
    }
    /* the pieces by start node, in the order made within a node (a stable counting sort: the order a stable
     * comparison sort gives, on every C library) */
    for (i = 0; i < npc; i++)
        first[pl->pc[i].na + 1]++;
    for (i = 0; i < c->nnode; i++)
        first[i + 1] += first[i];
    for (i = 0; i < npc; i++)
        sorted[first[pl->pc[i].na]++] = pl->pc[i];
    if (npc)
        memcpy(pl->pc, sorted, npc * sizeof *sorted);
    amp_free(c->al, sorted);
    /* first[na] is now the end of na's pieces: a node's first piece, npc for a node without any */
    for (i = c->nnode; i > 0; i--)
        first[i] = first[i - 1];
    first[0] = 0;
    for (i = 0; i <= c->nnode; i++)
        if (i == c->nnode || first[i] == first[i + 1])
            first[i] = npc;
    for (i = 0; i < npc && st == AMP_OK; i++) {
        if (pl->pc[i].used)
            continue;
        if ((st = trace_ring(c, pl, first, i, r, &loop, &cap_loop, &len)) != AMP_OK)
            break;
        len = clean_ring(loop, len, r);
        if (len >= 3 && fabs(amp_ring_area(loop, len)) > 1e-4 * r * r)
            st = amp_polyset_add(out, loop, len, err);
    }
    amp_free(c->al, first);
    amp_free(c->al, loop);
    return st;
}

/* The inward offset of [P2 §2.2] step 5: raw offset curves (1), their
 * crossings (2), the pieces on the boundary {d = r} (3), stitched (4). */
static amp_status inset_core(const amp_polyset *in, double r, double arc_tol, amp_polyset *out, double *dropped,
                             amp_error *err)
{
    inset_ctx c;
    egrid g;
    piece_list pl;
    double dstep;
    amp_status st;
    amp_polyset_clear(out);
    if (in->nrings == 0)
        return AMP_OK;
    memset(&c, 0, sizeof c);
    memset(&g, 0, sizeof g);
    memset(&pl, 0, sizeof pl);
    c.al = out->alloc;
    if (!(arc_tol > 0))
        arc_tol = r / 100.0;
    dstep = 2.0 * acos(r / (r + arc_tol));
    if (!(dstep > 1e-3))
        dstep = 1e-3;
    if ((st = raw_offsets(&c, in, r, dstep)) == AMP_OK && (st = raw_crossings(&c)) == AMP_OK &&
        (st = egrid_build(&g, in, r, c.al)) == AMP_OK && (st = boundary_pieces(&c, &g, r, &pl)) == AMP_OK &&
        (st = stitch_rings(&c, &pl, r, out, err)) == AMP_OK)
        st = amp_polyset_organize(out, err);
    *dropped = c.dropped;
    amp_free(c.al, c.seg);
    amp_free(c.al, c.node);
    amp_free(c.al, c.spl.v);
    amp_free(c.al, pl.pc);
    egrid_free(&g, c.al);
    if (st == AMP_ERR_NOMEM)
        return amp_fail(err, st, 0, "out of memory computing the inset");
    return st;
}

/* The input's rings freed of vertices within @p tol of the chord of their neighbours, into @p simp. */
static amp_status simplified(const amp_polyset *in, double tol, amp_polyset *simp, amp_error *err)
{
    amp_vec2 *tmp = amp_alloc(simp->alloc, (in->npts + 1) * sizeof *tmp);
    size_t i;
    amp_status st = AMP_OK;
    if (!tmp)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory computing the inset");
    amp_polyset_clear(simp);
    for (i = 0; i < in->nrings && st == AMP_OK; i++) {
        size_t n = simplify_ring(amp_polyset_ring(in, i), in->rings[i].n, tol, tmp);
        if (n >= 3)
            st = amp_polyset_add(simp, tmp, n, err);
    }
    amp_free(simp->alloc, tmp);
    return st;
}

amp_status amp_polyset_inset(const amp_polyset *in, double r, double arc_tol, amp_polyset *out, amp_error *err)
{
    amp_polyset simp;
    double dropped = 0.0;
    amp_status st;
    if (!(r > 0) || !isfinite(r))
        return amp_fail(err, AMP_ERR_ARG, 0, "inset radius must be positive, got %g", r);
    /* rings freed of vertices within r/10^4 of the chord of their neighbours:
     * float noise of STL coordinates would otherwise give micro-arcs whose
     * crossings are below rounding; the offset is computed for this ring */
    amp_polyset_init(&simp, out->alloc);
    st = simplified(in, 1e-4 * r, &simp, err);
    if (st == AMP_OK)
        st = inset_core(&simp, r, arc_tol, out, &dropped, err);
    /* a chain longer than 2r lost at a dead end is a ring of the offset, not a swallowtail's sliver: a notch
     * of a few micrometres at a pinch (two cubes of a Menger sponge meeting at an edge, cut at 14 mm) makes
     * raw arcs cross nearly tangentially, and an arc step (r/4 and more) goes missing. Freed of the notch
     * (vertices within r/100 of their chord: the arcs' own tolerance), the offset is computed again */
    if (st == AMP_OK && dropped > 2 * r && (st = simplified(in, 1e-2 * r, &simp, err)) == AMP_OK)
        st = inset_core(&simp, r, arc_tol, out, &dropped, err);
    amp_polyset_free(&simp);
    return st;
}
