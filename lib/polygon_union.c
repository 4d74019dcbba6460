/* The nonzero union of oriented rings: the region a mesh of overlapping
 * shells encloses at one height.
 *
 * [P2 §2.2] step 1 assumes the section of a solid is a set of disjoint
 * rings. Meshes as people export them often are not: parts modelled as
 * separate bodies and saved without a boolean union give sections whose
 * rings cross, share edges (two boxes face to face) or lie inside each other
 * with the same orientation (a pin inside a sleeve). Slicers read such a
 * file by the nonzero rule (a point is solid when the rings wind around it
 * a positive number of times), and so does this file: the rings are split
 * where they meet, each stretch between two meeting points is kept when it
 * separates solid from empty, and the kept pieces are chained into rings.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/polygon.h"
#include "ampath/vec.h"
#include "polygon_internal.h"

typedef struct useg { /* one ring edge, between node ids */
    size_t na, nb;
} useg;


typedef struct upiece {
    size_t na, nb;
    int used;
} upiece;

typedef struct uctx {
    const amp_allocator *al;
    amp_vec2 *node;
    unsigned char *junction; /* node where boundaries meet: the sides of a ring may change there */
    size_t nnode, cap_node, cap_junction;
    useg *seg;
    size_t nseg;
    pg_splits spl;
    amp_polyindex ix; /* rows of the input's edges, for winding queries */
    double delta; /* side offset of a winding sample */
    double tol;   /* points closer than this are one node, and a point this close to an edge lies on it */
    int sign;     /* -1 when the rings are all reversed (a mesh facing inward) */
} uctx;

static amp_status add_node(uctx *c, amp_vec2 p, size_t *id)
{
    void *v = c->node, *w = c->junction;
    if (amp_grow(c->al, &v, &c->cap_node, c->nnode + 1, sizeof *c->node) != AMP_OK)
        return AMP_ERR_NOMEM;
    c->node = v;
    if (amp_grow(c->al, &w, &c->cap_junction, c->nnode + 1, 1) != AMP_OK)
        return AMP_ERR_NOMEM;
    c->junction = w;
    c->node[c->nnode] = p;
    c->junction[c->nnode] = 0;
    *id = c->nnode++;
    return AMP_OK;
}

static amp_status add_split(uctx *c, size_t s, double t, size_t node)
{
    c->junction[node] = 1;
    return pg_splits_add(c->al, &c->spl, s, t, node);
}

/* Nodes and edges of the rings: one node per ring vertex (rings that touch
 * at a vertex are found by meet() and merged by merge_nodes()). */
static amp_status build_nodes(uctx *c, const amp_polyset *ps)
{
    size_t i, r;
    c->node = amp_alloc(c->al, (ps->npts + 1) * sizeof *c->node);
    c->junction = amp_calloc(c->al, ps->npts + 1, 1);
    c->seg = amp_alloc(c->al, (ps->npts + 1) * sizeof *c->seg);
    if (!c->node || !c->junction || !c->seg)
        return AMP_ERR_NOMEM;
    c->cap_node = c->cap_junction = ps->npts + 1;
    memcpy(c->node, ps->pts, ps->npts * sizeof *c->node);
    c->nnode = ps->npts;
    for (r = 0; r < ps->nrings; r++) {
        size_t f = ps->rings[r].first, n = ps->rings[r].n;
        for (i = 0; i < n; i++) {
            c->seg[c->nseg].na = f + i;
            c->seg[c->nseg].nb = f + (i + 1) % n;
            c->nseg++;
        }
    }
    return AMP_OK;
}

/* The row index of the input rings and the side offset of the winding samples. */
static amp_status index_rings(uctx *c, const amp_polyset *ps)
{
    double x0 = HUGE_VAL, x1 = -HUGE_VAL, y0 = HUGE_VAL, y1 = -HUGE_VAL;
    size_t i;
    for (i = 0; i < c->nnode; i++) {
        x0 = fmin(x0, c->node[i].x);
        x1 = fmax(x1, c->node[i].x);
        y0 = fmin(y0, c->node[i].y);
        y1 = fmax(y1, c->node[i].y);
    }
    c->delta = 1e-7 * (1.0 + (x1 - x0) + (y1 - y0) + fmax(fmax(fabs(x0), fabs(x1)), fmax(fabs(y0), fabs(y1))));
    c->tol = 1e-2 * c->delta;
    return amp_polyindex_build(&c->ix, ps, NULL) == AMP_OK ? AMP_OK : AMP_ERR_NOMEM;
}

static double dist2(amp_vec2 a, amp_vec2 b)
{
    return (b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y);
}

/* Parameter of point p along the edge a -> b. */
static double param(amp_vec2 a, amp_vec2 b, amp_vec2 p)
{
    double dx = b.x - a.x, dy = b.y - a.y;
    return ((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy);
}

/* Distance from node @p nd to the line through edge a -> b, times |b - a| (the orientation's magnitude). */
static double off_line(const uctx *c, amp_vec2 a, amp_vec2 b, size_t nd)
{
    return fabs(amp_v2_orient(a, b, c->node[nd]));
}

/* Edges i and j lie on one line (within c->tol): each is split where the other ends inside it. */
static amp_status collinear(uctx *c, size_t i, size_t j)
{
    const useg *e[2];
    size_t k, q;
    int overlap = 0;
    e[0] = &c->seg[i];
    e[1] = &c->seg[j];
    for (k = 0; k < 2; k++) {
        amp_vec2 a = c->node[e[k]->na], b = c->node[e[k]->nb];
        for (q = 0; q < 2; q++) {
            size_t nd = q ? e[1 - k]->nb : e[1 - k]->na;
            double t = param(a, b, c->node[nd]);
            if (nd != e[k]->na && nd != e[k]->nb && t > 0.0 && t < 1.0 &&
                off_line(c, a, b, nd) <= c->tol * sqrt(dist2(a, b))) {
                if (add_split(c, k ? j : i, t, nd) != AMP_OK)
                    return AMP_ERR_NOMEM;
                overlap = 1;
            }
        }
    }
    if (!overlap && !((e[0]->na == e[1]->na && e[0]->nb == e[1]->nb) || (e[0]->na == e[1]->nb && e[0]->nb == e[1]->na)))
        return AMP_OK;
    /* the stretch shared by two boundaries: the sides change at its ends */
    c->junction[e[0]->na] = c->junction[e[0]->nb] = c->junction[e[1]->na] = c->junction[e[1]->nb] = 1;
    return AMP_OK;
}

static int same(amp_vec2 a, amp_vec2 b)
{
    return a.x == b.x && a.y == b.y;
}

/* An end of edge t lying on edge s (within c->tol, strictly between s's ends): s is split there. */
static amp_status end_on(uctx *c, size_t s, amp_vec2 a, amp_vec2 b, size_t nd)
{
    double t = param(a, b, c->node[nd]);
    if (!(t > 0.0 && t < 1.0) || same(c->node[nd], a) || same(c->node[nd], b))
        return AMP_OK;
    return add_split(c, s, t, nd);
}

/* Where edges i and j meet: a crossing becomes one node shared by both, an
 * end lying on the other edge splits it there. */
/*
 * Section points are computed from different mesh edges, so two bodies' faces that meet along a line give
 * boundaries that differ in their last bits: near-collinear edges that would "cross" at a random point of
 * their shared stretch, and ends a rounding error beside the other edge. Within c->tol both count as lying
 * on the other edge (split there, as exact touches are), so that the sides of every piece are constant.
 */
static amp_status meet(uctx *c, size_t i, size_t j)
{
    const useg *s = &c->seg[i], *t = &c->seg[j];
    amp_vec2 a = c->node[s->na], b = c->node[s->nb], p = c->node[t->na], q = c->node[t->nb];
    double d1, d2, d3, d4, u, ts, tt, tol = c->tol;
    int on_p, on_q, on_a, on_b;
    size_t id;
    if (fmax(p.x, q.x) < fmin(a.x, b.x) - tol || fmin(p.x, q.x) > fmax(a.x, b.x) + tol ||
        fmax(p.y, q.y) < fmin(a.y, b.y) - tol || fmin(p.y, q.y) > fmax(a.y, b.y) + tol)
        return AMP_OK;
    if (s->nb == t->na && amp_v2_orient(a, b, q) != 0.0)
        return AMP_OK; /* consecutive edges of a ring that do not fold back */
    if (s->na == t->nb && amp_v2_orient(a, b, p) != 0.0)
        return AMP_OK;
    d1 = amp_v2_orient(a, b, p);
    d2 = amp_v2_orient(a, b, q);
    d3 = amp_v2_orient(p, q, a);
    d4 = amp_v2_orient(p, q, b);
    ts = tol * sqrt(dist2(a, b));
    tt = tol * sqrt(dist2(p, q));
    on_p = fabs(d1) <= ts;
    on_q = fabs(d2) <= ts;
    on_a = fabs(d3) <= tt;
    on_b = fabs(d4) <= tt;
    if ((on_p && on_q) || (on_a && on_b))
        return collinear(c, i, j);
    if (!on_p && !on_q && !on_a && !on_b &&
        ((d1 > 0 && d2 > 0) || (d1 < 0 && d2 < 0) || (d3 > 0 && d4 > 0) || (d3 < 0 && d4 < 0)))
        return AMP_OK;
    if (s->na == t->na || s->na == t->nb || s->nb == t->na || s->nb == t->nb)
        return AMP_OK; /* they meet at a shared node */
    if (same(a, p) || same(a, q) || same(b, p) || same(b, q)) {
        /* rings touching at a vertex: one node after merge_nodes() */
        c->junction[same(a, p) || same(a, q) ? s->na : s->nb] = 1;
        c->junction[same(a, p) || same(b, p) ? t->na : t->nb] = 1;
        return AMP_OK;
    }
    if (on_p || on_q || on_a || on_b) { /* an end on the other edge */
        if ((on_p && end_on(c, i, a, b, t->na) != AMP_OK) || (on_q && end_on(c, i, a, b, t->nb) != AMP_OK) ||
            (on_a && end_on(c, j, p, q, s->na) != AMP_OK) || (on_b && end_on(c, j, p, q, s->nb) != AMP_OK))
            return AMP_ERR_NOMEM;
        return AMP_OK;
    }
    u = d3 / (d3 - d4);
    if (add_node(c, amp_v2(a.x + u * (b.x - a.x), a.y + u * (b.y - a.y)), &id) != AMP_OK ||
        add_split(c, i, u, id) != AMP_OK)
        return AMP_ERR_NOMEM;
    return add_split(c, j, d1 / (d1 - d2), id);
}

typedef struct xspan {
    double x0, x1, y0, y1;
    size_t seg;
} xspan;

static int cmp_xspan(const void *a, const void *b)
{
    const xspan *s = a, *t = b;
    if (s->x0 != t->x0)
        return s->x0 < t->x0 ? -1 : 1;
    return s->seg < t->seg ? -1 : (s->seg > t->seg ? 1 : 0);
}

/* Every pair of edges whose boxes overlap, met once: a sweep over x. */
static amp_status find_meetings(uctx *c)
{
    xspan *x = amp_alloc(c->al, (c->nseg + 1) * sizeof *x);
    size_t i, j;
    amp_status st = AMP_OK;
    if (!x)
        return AMP_ERR_NOMEM;
    for (i = 0; i < c->nseg; i++) {
        amp_vec2 a = c->node[c->seg[i].na], b = c->node[c->seg[i].nb];
        x[i].x0 = fmin(a.x, b.x);
        x[i].x1 = fmax(a.x, b.x);
        x[i].y0 = fmin(a.y, b.y);
        x[i].y1 = fmax(a.y, b.y);
        x[i].seg = i;
    }
    qsort(x, c->nseg, sizeof *x, cmp_xspan);
    for (i = 0; i < c->nseg && st == AMP_OK; i++)
        for (j = i + 1; j < c->nseg && x[j].x0 <= x[i].x1 + c->tol && st == AMP_OK; j++)
            if (x[j].y0 <= x[i].y1 + c->tol && x[j].y1 >= x[i].y0 - c->tol)
                st = x[i].seg < x[j].seg ? meet(c, x[i].seg, x[j].seg) : meet(c, x[j].seg, x[i].seg);
    amp_free(c->al, x);
    return st;
}

typedef struct xkey {
    double x;
    size_t id;
} xkey;

static int cmp_xkey(const void *a, const void *b)
{
    const xkey *s = a, *t = b;
    if (s->x != t->x)
        return s->x < t->x ? -1 : 1;
    return s->id < t->id ? -1 : (s->id > t->id ? 1 : 0);
}

/* One node for the points closer than a rounding error: rings touching at
 * a vertex, and the same meeting computed from two pairs of edges (a slot
 * across two boxes face to face crosses both of their shared edges) must
 * be one node for the pieces to chain and coincide. */
static amp_status merge_nodes(uctx *c)
{
    double tol = c->tol;
    xkey *k = amp_alloc(c->al, (c->nnode + 1) * sizeof *k);
    size_t *rep = amp_alloc(c->al, (c->nnode + 1) * sizeof *rep), i, j;
    if (!k || !rep) {
        amp_free(c->al, k);
        amp_free(c->al, rep);
        return AMP_ERR_NOMEM;
    }
    for (i = 0; i < c->nnode; i++) {
        k[i].x = c->node[i].x;
        k[i].id = i;
        rep[i] = i;
    }
    qsort(k, c->nnode, sizeof *k, cmp_xkey);
    for (i = 0; i < c->nnode; i++)
        for (j = i + 1; j < c->nnode && k[j].x - k[i].x <= tol; j++)
            if (rep[k[j].id] == k[j].id && fabs(c->node[k[j].id].y - c->node[k[i].id].y) <= tol) {
                rep[k[j].id] = rep[k[i].id];
                c->junction[rep[k[i].id]] |= c->junction[k[j].id];
            }
    for (i = 0; i < c->nseg; i++) {
        c->seg[i].na = rep[c->seg[i].na];
        c->seg[i].nb = rep[c->seg[i].nb];
    }
    for (i = 0; i < c->spl.n; i++)
        c->spl.v[i].node = rep[c->spl.v[i].node];
    amp_free(c->al, k);
    amp_free(c->al, rep);
    return AMP_OK;
}

/* Solid (winding > 0) on the left and right of the piece a -> b, sampled
 * beside its midpoint: bit 1 left, bit 0 right. A sample steps delta off the
 * piece, but never across another boundary: where one runs nearer than that
 * beside it (a slit 9 um wide between two rings, CGAL's anchor cut just
 * below the crest of its arches) the sample would land in the ring across
 * the slit and call the piece interior, and the ring it decides for would be
 * lost; the step shrinks until each sample is nearer to the piece than to
 * anything else (coincident edges, within tol, lie as far as the piece), down
 * to twice tol. */
static int sides(const uctx *c, amp_vec2 a, amp_vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l = hypot(dx, dy), d = fmin(c->delta, 0.25 * l);
    amp_vec2 m = amp_v2(0.5 * (a.x + b.x), 0.5 * (a.y + b.y)), pl, pr;
    int left, right;
    for (;;) {
        double near = d - c->tol; /* the piece itself lies d away, an edge coincident with it d +- tol */
        pl = amp_v2(m.x - d * dy / l, m.y + d * dx / l);
        pr = amp_v2(m.x + d * dy / l, m.y - d * dx / l);
        if (d <= 2.0 * c->tol || (amp_polyindex_dist_within(&c->ix, pl, d) >= near &&
                                  amp_polyindex_dist_within(&c->ix, pr, d) >= near))
            break;
        d = fmax(0.25 * d, 2.0 * c->tol);
    }
    left = c->sign * amp_polyindex_winding(&c->ix, pl) > 0;
    right = c->sign * amp_polyindex_winding(&c->ix, pr) > 0;
    return left << 1 | right;
}

static amp_status add_piece(const amp_allocator *al, upiece **pc, size_t *n, size_t *cap, size_t na, size_t nb)
{
    void *v = *pc;
    if (amp_grow(al, &v, cap, *n + 1, sizeof **pc) != AMP_OK)
        return AMP_ERR_NOMEM;
    *pc = v;
    (*pc)[*n].na = na;
    (*pc)[*n].nb = nb;
    (*pc)[*n].used = 0;
    (*n)++;
    return AMP_OK;
}

/* The edges cut at their splits into pieces, in ring order; @p ring_piece
 * (nrings + 1 entries) receives where each ring's pieces start. */
static amp_status cut_pieces(uctx *c, const amp_polyset *ps, upiece **pc, size_t *npc, size_t *ring_piece)
{
    size_t r, i, k = 0, s = 0, cap = 0;
    if (c->spl.n > 1)
        qsort(c->spl.v, c->spl.n, sizeof *c->spl.v, pg_split_cmp);
    for (r = 0; r < ps->nrings; r++) {
        ring_piece[r] = *npc;
        for (i = 0; i < ps->rings[r].n; i++, s++) {
            size_t cur = c->seg[s].na;
            for (; k < c->spl.n && c->spl.v[k].seg == s; k++)
                if (c->spl.v[k].node != cur) {
                    if (add_piece(c->al, pc, npc, &cap, cur, c->spl.v[k].node) != AMP_OK)
                        return AMP_ERR_NOMEM;
                    cur = c->spl.v[k].node;
                }
            if (cur != c->seg[s].nb && add_piece(c->al, pc, npc, &cap, cur, c->seg[s].nb) != AMP_OK)
                return AMP_ERR_NOMEM;
        }
    }
    ring_piece[ps->nrings] = *npc;
    return AMP_OK;
}

static double piece_len2(const uctx *c, const upiece *p)
{
    return dist2(c->node[p->na], c->node[p->nb]);
}

/* Classify the pieces of one ring, [p0, p1), run by run: the sides of a
 * ring only change where another boundary meets it (a junction), so one
 * sample per run decides. Pieces between solid and empty are kept, turned
 * to have the solid on their left; the others are marked used (dropped). */
static void classify_ring(const uctx *c, upiece *pc, size_t p0, size_t p1)
{
    size_t n = p1 - p0, k0 = 0, k, done = 0;
    while (k0 < n && !c->junction[pc[p0 + k0].na])
        k0++;
    if (k0 == n)
        k0 = 0; /* no junction: the whole ring is one run */
    while (done < n) {
        size_t len = 1, best = p0 + (k0 + done) % n;
        int cls;
        while (done + len < n && !c->junction[pc[p0 + (k0 + done + len) % n].na])
            len++;
        for (k = 0; k < len; k++)
            if (piece_len2(c, &pc[p0 + (k0 + done + k) % n]) > piece_len2(c, &pc[best]))
                best = p0 + (k0 + done + k) % n;
        cls = sides(c, c->node[pc[best].na], c->node[pc[best].nb]);
        for (k = 0; k < len; k++) {
            upiece *p = &pc[p0 + (k0 + done + k) % n];
            if (cls == 1) { /* solid on the right only: turn it */
                size_t t = p->na;
                p->na = p->nb;
                p->nb = t;
            }
            p->used = cls != 1 && cls != 2;
        }
        done += len;
    }
}

static int cmp_piece(const void *a, const void *b)
{
    const upiece *s = a, *t = b;
    if (s->used != t->used)
        return s->used < t->used ? -1 : 1;
    if (s->na != t->na)
        return s->na < t->na ? -1 : 1;
    return s->nb < t->nb ? -1 : (s->nb > t->nb ? 1 : 0);
}

/* Kept pieces first, sorted by start node, each once: boundaries that
 * coincide (two boxes face to face) give the same piece twice. Returns the
 * number of kept pieces. */
static size_t unique_pieces(upiece *pc, size_t n)
{
    size_t i, m = 0;
    if (n > 1)
        qsort(pc, n, sizeof *pc, cmp_piece);
    for (i = 0; i < n && !pc[i].used; i++)
        if (m == 0 || pc[i].na != pc[m - 1].na || pc[i].nb != pc[m - 1].nb)
            pc[m++] = pc[i];
    return m;
}

/* Among the unused pieces leaving node v, the one turning least to the
 * left from the piece arriving from u: the first clockwise from the way
 * back. Rings that touch at a node stay apart. npc when none. */
static size_t next_piece(const uctx *c, const upiece *pc, size_t npc, const size_t *first, size_t u, size_t v)
{
    amp_vec2 o = c->node[v];
    double back = atan2(c->node[u].y - o.y, c->node[u].x - o.x), best_a = HUGE_VAL;
    size_t k, best = npc;
    for (k = first[v]; k < npc && pc[k].na == v; k++) {
        double a;
        if (pc[k].used)
            continue;
        a = back - atan2(c->node[pc[k].nb].y - o.y, c->node[pc[k].nb].x - o.x);
        while (a <= 0.0)
            a += 2.0 * AMP_PI;
        if (a < best_a) {
            best_a = a;
            best = k;
        }
    }
    return best;
}

/* The kept pieces chained into rings, added to @p out. */
static amp_status chain_rings(const uctx *c, upiece *pc, size_t npc, amp_polyset *out, amp_error *err)
{
    size_t *first = amp_alloc(c->al, (c->nnode + 1) * sizeof *first), i, len, cap = 0;
    amp_vec2 *ring = NULL;
    amp_status st = AMP_OK;
    if (!first)
        return AMP_ERR_NOMEM;
    for (i = 0; i <= c->nnode; i++)
        first[i] = npc;
    for (i = npc; i-- > 0;)
        first[pc[i].na] = i;
    for (i = 0; i < npc && st == AMP_OK; i++) {
        size_t at = i;
        if (pc[i].used)
            continue;
        for (len = 0; at < npc; at = next_piece(c, pc, npc, first, pc[at].na, pc[at].nb)) {
            void *v = ring;
            pc[at].used = 1;
            if (amp_grow(c->al, &v, &cap, len + 1, sizeof *ring) != AMP_OK) {
                st = AMP_ERR_NOMEM;
                break;
            }
            ring = v;
            ring[len++] = c->node[pc[at].na];
            if (pc[at].nb == pc[i].na)
                break;
        }
        /* a chain that does not come back (rounding at a near-degenerate
         * meeting) is closed anyway rather than losing its solid */
        if (st == AMP_OK && len >= 3)
            st = amp_polyset_add(out, ring, len, err);
    }
    amp_free(c->al, ring);
    amp_free(c->al, first);
    return st;
}

/* Without any meeting, a ring is kept unchanged when it separates solid
 * from empty; 1 when every ring does (nothing to change). */
static int rings_separate(const uctx *c, const amp_polyset *ps)
{
    size_t r, s = 0;
    for (r = 0; r < ps->nrings; s += ps->rings[r].n, r++) {
        size_t i, best = s;
        int cls;
        for (i = s; i < s + ps->rings[r].n; i++)
            if (dist2(c->node[c->seg[i].na], c->node[c->seg[i].nb]) >
                dist2(c->node[c->seg[best].na], c->node[c->seg[best].nb]))
                best = i;
        cls = sides(c, c->node[c->seg[best].na], c->node[c->seg[best].nb]);
        if (cls != 1 && cls != 2)
            return 0;
    }
    return 1;
}

static int any_junction(const uctx *c)
{
    size_t i;
    for (i = 0; i < c->nnode; i++)
        if (c->junction[i])
            return 1;
    return 0;
}

/* Split, classify, keep and chain (the file comment), into @p out. */
static amp_status rebuild(uctx *c, const amp_polyset *ps, amp_polyset *out, amp_error *err)
{
    size_t *ring_piece = amp_alloc(c->al, (ps->nrings + 1) * sizeof *ring_piece), npc = 0, r;
    upiece *pc = NULL;
    amp_status st;
    if (!ring_piece)
        return AMP_ERR_NOMEM;
    st = cut_pieces(c, ps, &pc, &npc, ring_piece);
    if (st == AMP_OK) {
        for (r = 0; r < ps->nrings; r++)
            classify_ring(c, pc, ring_piece[r], ring_piece[r + 1]);
        npc = unique_pieces(pc, npc);
        st = chain_rings(c, pc, npc, out, err);
    }
    amp_free(c->al, pc);
    amp_free(c->al, ring_piece);
    return st;
}

static void uctx_free(uctx *c)
{
    amp_free(c->al, c->node);
    amp_free(c->al, c->junction);
    amp_free(c->al, c->seg);
    amp_free(c->al, c->spl.v);
    amp_polyindex_free(&c->ix);
}

amp_status amp_polyset_union(amp_polyset *ps, int *changed, amp_error *err)
{
    uctx c;
    amp_polyset out;
    amp_status st;
    if (changed)
        *changed = 0;
    if (!ps)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_polyset_union: NULL set");
    if (ps->nrings == 0)
        return AMP_OK;
    memset(&c, 0, sizeof c);
    c.al = ps->alloc;
    /* rings of a mesh that faces inward are all reversed: the set's sign */
    c.sign = amp_polyset_area(ps) < 0 ? -1 : 1;
    amp_polyset_init(&out, ps->alloc);
    st = build_nodes(&c, ps);
    if (st == AMP_OK)
        st = index_rings(&c, ps);
    if (st == AMP_OK)
        st = find_meetings(&c);
    if (st == AMP_OK && (any_junction(&c) || !rings_separate(&c, ps))) {
        st = merge_nodes(&c);
        if (st == AMP_OK)
            st = rebuild(&c, ps, &out, err);
        if (st == AMP_OK) {
            amp_polyset tmp = *ps;
            *ps = out;
            out = tmp;
            if (changed)
                *changed = 1;
        }
    }
    uctx_free(&c);
    amp_polyset_free(&out);
    if (st == AMP_ERR_NOMEM)
        return amp_fail(err, st, 0, "out of memory resolving overlapping polygons");
    return st;
}
