/* Step 5 (clipping): the pieces of the K̂ edges inside a region, with free
 * ends where an edge leaves it ([P2 §2.2]). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

typedef struct hit {
    double t, pos;
    size_t ring;
} hit;


static int cmp_hit(const void *a, const void *b)
{
    const hit *x = a, *y = b;
    return x->t < y->t ? -1 : (x->t > y->t ? 1 : 0);
}


/* Uniform grid of the ring segments of the region (about one segment per
 * cell), so that a lattice edge or point meets only the segments near it:
 * the clipping costs O(lattice + ring) instead of their product. */
typedef struct rgrid {
    double x0, y0, cell;
    long nx, ny;
    size_t *start, *item; /* CSR: cell -> segment ids */
    amp_vec2 *a, *b;      /* segment id -> ends */
    size_t *ring, *seg;   /* segment id -> ring, index in the ring */
    size_t *stamp;        /* last query that met a segment (dedup over cells) */
    size_t nseg, query;
} rgrid;

static long rg_cell(double v, double o, double c, long n)
{
    long k = (long)floor((v - o) / c);
    return k < 0 ? 0 : (k >= n ? n - 1 : k);
}

static void rg_free(const amp_allocator *al, rgrid *g)
{
    amp_free(al, g->start);
    amp_free(al, g->item);
    amp_free(al, g->a);
    amp_free(al, g->b);
    amp_free(al, g->ring);
    amp_free(al, g->seg);
    amp_free(al, g->stamp);
}

static amp_status rg_build(rgrid *g, const amp_polyset *R, double bx0, double by0, double bx1, double by1,
                           const amp_allocator *al)
{
    size_t r, k, id = 0, pass, ncell;
    memset(g, 0, sizeof *g);
    g->nseg = R->npts;
    g->a = amp_alloc(al, (g->nseg + 1) * sizeof *g->a);
    g->b = amp_alloc(al, (g->nseg + 1) * sizeof *g->b);
    g->ring = amp_alloc(al, (g->nseg + 1) * sizeof *g->ring);
    g->seg = amp_alloc(al, (g->nseg + 1) * sizeof *g->seg);
    g->stamp = amp_calloc(al, g->nseg + 1, sizeof *g->stamp);
    if (!g->a || !g->b || !g->ring || !g->seg || !g->stamp)
        return AMP_ERR_NOMEM;
    for (r = 0; r < R->nrings; r++) {
        const amp_vec2 *p = amp_polyset_ring(R, r);
        size_t n = R->rings[r].n;
        for (k = 0; k < n; k++, id++) {
            g->a[id] = p[k];
            g->b[id] = p[(k + 1) % n];
            g->ring[id] = r;
            g->seg[id] = k;
        }
    }
    g->cell = fmax(fmax(bx1 - bx0, by1 - by0) / ceil(sqrt((double)g->nseg + 1.0)), 1e-9);
    g->x0 = bx0;
    g->y0 = by0;
    g->nx = (long)((bx1 - bx0) / g->cell) + 1;
    g->ny = (long)((by1 - by0) / g->cell) + 1;
    ncell = (size_t)(g->nx * g->ny);
    g->start = amp_calloc(al, ncell + 1, sizeof *g->start);
    if (!g->start)
        return AMP_ERR_NOMEM;
    for (pass = 0; pass < 2; pass++) {
        for (id = 0; id < g->nseg; id++) {
            long cx0 = rg_cell(fmin(g->a[id].x, g->b[id].x), g->x0, g->cell, g->nx);
            long cx1 = rg_cell(fmax(g->a[id].x, g->b[id].x), g->x0, g->cell, g->nx);
            long cy0 = rg_cell(fmin(g->a[id].y, g->b[id].y), g->y0, g->cell, g->ny);
            long cy1 = rg_cell(fmax(g->a[id].y, g->b[id].y), g->y0, g->cell, g->ny), x, y;
            for (y = cy0; y <= cy1; y++)
                for (x = cx0; x <= cx1; x++) {
                    size_t c = (size_t)(y * g->nx + x);
                    if (pass == 0)
                        g->start[c + 1]++;
                    else
                        g->item[g->start[c]++] = id;
                }
        }
        if (pass == 0) {
            for (k = 0; k < ncell; k++)
                g->start[k + 1] += g->start[k];
            g->item = amp_alloc(al, (g->start[ncell] + 1) * sizeof *g->item);
            if (!g->item)
                return AMP_ERR_NOMEM;
        }
    }
    for (k = ncell; k > 0; k--)
        g->start[k] = g->start[k - 1];
    g->start[0] = 0;
    return AMP_OK;
}

/* Is q within eps of a ring segment? */
static int rg_near(const rgrid *g, amp_vec2 q, double eps)
{
    long cx0 = rg_cell(q.x - eps, g->x0, g->cell, g->nx), cx1 = rg_cell(q.x + eps, g->x0, g->cell, g->nx);
    long cy0 = rg_cell(q.y - eps, g->y0, g->cell, g->ny), cy1 = rg_cell(q.y + eps, g->y0, g->cell, g->ny), x, y;
    size_t k;
    for (y = cy0; y <= cy1; y++)
        for (x = cx0; x <= cx1; x++)
            for (k = g->start[y * g->nx + x]; k < g->start[y * g->nx + x + 1]; k++) {
                amp_vec2 e = amp_cp_seg_offset(q, g->a[g->item[k]], g->b[g->item[k]], NULL);
                if (hypot(e.x, e.y) <= eps)
                    return 1;
            }
    return 0;
}

/* Point in region (even-odd over all rings, half-open crossing rule, as
 * amp_ring_contains): a ray to +x counted in the row of cells of q, each
 * crossing only in the cell that holds it. */
static int rg_inside(const rgrid *g, amp_vec2 q)
{
    long cy = rg_cell(q.y, g->y0, g->cell, g->ny), cx = rg_cell(q.x, g->x0, g->cell, g->nx), x;
    size_t k, cnt = 0;
    if (q.y < g->y0 || q.y > g->y0 + g->cell * (double)g->ny || q.x > g->x0 + g->cell * (double)g->nx)
        return 0;
    for (x = cx; x < g->nx; x++)
        for (k = g->start[cy * g->nx + x]; k < g->start[cy * g->nx + x + 1]; k++) {
            amp_vec2 a = g->a[g->item[k]], b = g->b[g->item[k]];
            double xi;
            if ((a.y > q.y) == (b.y > q.y))
                continue;
            xi = a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if (xi > q.x && rg_cell(xi, g->x0, g->cell, g->nx) == x)
                cnt++;
        }
    return (int)(cnt & 1u);
}

/* A node where edge AB crosses a ring (hit @p h), recorded as a free end. */
static amp_status free_end(amp_cp_graph *g, amp_vec2 A, amp_vec2 B, const hit *h, size_t *id)
{
    void *q = g->fends;
    if (amp_cp_vert(g, amp_v2(A.x + h->t * (B.x - A.x), A.y + h->t * (B.y - A.y)), id) != AMP_OK)
        return AMP_ERR_NOMEM;
    if (amp_grow(g->al, &q, &g->cap_fends, g->nfends + 1, sizeof *g->fends) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->fends = q;
    g->fends[g->nfends].node = *id;
    g->fends[g->nfends].ring = h->ring;
    g->fends[g->nfends].pos = h->pos;
    g->nfends++;
    return AMP_OK;
}

/* One clipping of K̂ to a region R̃ (step 5). */
typedef struct clip_ctx {
    const amp_allocator *al;
    amp_cp_graph *g;                /* the pieces inside R̃ */
    rgrid rg;                       /* the ring segments of R̃ */
    double bx0, by0, bx1, by1, eps; /* bounding box of R̃; eps: its scale times 1e-9 */
    size_t *node;                   /* K̂ vertex -> its graph node (NONE: none yet) */
    signed char *in;                /* K̂ vertex inside R̃ */
    amp_vec2 *kv;                   /* K̂ vertex as clipped (moved off the rings) */
    hit *h;                         /* the crossings of the current K̂ edge with the rings */
    size_t nh, caph;
} clip_ctx;

/* A lattice vertex on a ring (CAD parts aligned with the lattice) is moved
 * off it by a few eps along a fixed oblique direction, so that no vertex and
 * no edge of K̂ lies on the boundary of the region; then inside or not. */
static void place_vertices(clip_ctx *c, const amp_cx2 *k)
{
    double eps = c->eps;
    size_t i;
    for (i = 0; i < k->nv; i++) {
        amp_vec2 q = k->v[i];
        int tries;
        c->node[i] = NONE;
        for (tries = 0; tries < 8 && q.x >= c->bx0 - eps && q.x <= c->bx1 + eps && q.y >= c->by0 - eps &&
                        q.y <= c->by1 + eps && rg_near(&c->rg, q, eps);
             tries++)
            q = amp_v2(q.x + 2.2 * eps * 0.6, q.y + 2.2 * eps * 0.8);
        c->kv[i] = q;
        c->in[i] = q.x >= c->bx0 && q.x <= c->bx1 && q.y >= c->by0 && q.y <= c->by1 && rg_inside(&c->rg, q);
    }
}

/* The crossings of K̂ edge AB with every ring edge, into c->h (unsorted); a
 * ring vertex exactly on the K̂ edge counts as lying on its positive side
 * (symbolic perturbation), so a crossing through it is found exactly once; a
 * point exactly on a ring is outside the region throughout. */
static amp_status edge_crossings(clip_ctx *c, amp_vec2 A, amp_vec2 B)
{
    rgrid *rg = &c->rg;
    long cx0 = rg_cell(fmin(A.x, B.x), rg->x0, rg->cell, rg->nx);
    long cx1 = rg_cell(fmax(A.x, B.x), rg->x0, rg->cell, rg->nx);
    long cy0 = rg_cell(fmin(A.y, B.y), rg->y0, rg->cell, rg->ny);
    long cy1 = rg_cell(fmax(A.y, B.y), rg->y0, rg->cell, rg->ny);
    long cx, cy;
    size_t kk;
    c->nh = 0;
    rg->query++;
    /* every ring segment whose cells the K̂ edge's box meets, once */
    for (cy = cy0; cy <= cy1; cy++)
        for (cx = cx0; cx <= cx1; cx++)
            for (kk = rg->start[cy * rg->nx + cx]; kk < rg->start[cy * rg->nx + cx + 1]; kk++) {
                size_t sid = rg->item[kk];
                amp_vec2 P = rg->a[sid], Q = rg->b[sid];
                double d1, d2, d3, d4;
                void *q = c->h;
                if (rg->stamp[sid] == rg->query)
                    continue;
                rg->stamp[sid] = rg->query;
                if (fmax(P.x, Q.x) < fmin(A.x, B.x) || fmin(P.x, Q.x) > fmax(A.x, B.x) ||
                    fmax(P.y, Q.y) < fmin(A.y, B.y) || fmin(P.y, Q.y) > fmax(A.y, B.y))
                    continue;
                d1 = amp_v2_orient(P, Q, A);
                d2 = amp_v2_orient(P, Q, B);
                d3 = amp_v2_orient(A, B, P);
                d4 = amp_v2_orient(A, B, Q);
                /* an end of the K̂ edge on the ring counts as outside (d <= 0),
                 * like the inside test of the vertices and pieces */
                if ((d1 > 0) == (d2 > 0) || (d3 >= 0) == (d4 >= 0) || d1 == d2 || d3 == d4)
                    continue;
                if (amp_grow(c->al, &q, &c->caph, c->nh + 1, sizeof *c->h) != AMP_OK)
                    return AMP_ERR_NOMEM;
                c->h = q;
                c->h[c->nh].t = d1 / (d1 - d2);
                c->h[c->nh].pos = (double)rg->seg[sid] + fmin(fmax(d3 / (d3 - d4), 0.0), 0.999999999999);
                c->h[c->nh].ring = rg->ring[sid];
                c->nh++;
            }
    return AMP_OK;
}

/* The pieces of K̂ edge a-b (ends A, B as clipped) between its sorted
 * crossings that lie inside R̃, into the graph: piece j runs from hit j-1
 * (or A) to hit j (or B); a hit ends a piece at a free end. */
static amp_status edge_pieces(clip_ctx *c, size_t a, size_t b, amp_vec2 A, amp_vec2 B)
{
    amp_cp_graph *g = c->g;
    const hit *h = c->h;
    size_t j, nh = c->nh, prevnode = NONE;
    for (j = 0; j <= nh; j++) {
        double t0 = j ? h[j - 1].t : 0.0, t1 = j < nh ? h[j].t : 1.0;
        amp_vec2 m = amp_v2(A.x + 0.5 * (t0 + t1) * (B.x - A.x), A.y + 0.5 * (t0 + t1) * (B.y - A.y));
        size_t u, v;
        int inside = (j == 0 && nh == 0) ? 1 : rg_inside(&c->rg, m);
        if (!inside) {
            prevnode = NONE;
            continue;
        }
        if (j == 0) {
            if (c->node[a] == NONE && amp_cp_vert(g, A, &c->node[a]) != AMP_OK)
                return AMP_ERR_NOMEM;
            u = c->node[a];
        } else if (prevnode != NONE)
            u = prevnode;
        else if (free_end(g, A, B, &h[j - 1], &u) != AMP_OK)
            return AMP_ERR_NOMEM;
        if (j == nh) {
            if (c->node[b] == NONE && amp_cp_vert(g, B, &c->node[b]) != AMP_OK)
                return AMP_ERR_NOMEM;
            v = c->node[b];
        } else if (free_end(g, A, B, &h[j], &v) != AMP_OK)
            return AMP_ERR_NOMEM;
        if (amp_cp_edge(g, u, v, 0) != AMP_OK)
            return AMP_ERR_NOMEM;
        prevnode = v;
    }
    return AMP_OK;
}

/* A crossing node shared by two inside pieces (an edge touching the ring
 * from inside) is not a free end: keep only nodes of degree 1. */
static amp_status keep_free_ends(const amp_allocator *al, amp_cp_graph *g)
{
    size_t i, s, *deg = amp_calloc(al, g->nv + 1, sizeof *deg);
    if (!deg)
        return AMP_ERR_NOMEM;
    for (i = 0; i < g->ne; i++) {
        deg[g->edge_u[i]]++;
        deg[g->edge_v[i]]++;
    }
    for (i = 0, s = 0; i < g->nfends; i++)
        if (deg[g->fends[i].node] == 1)
            g->fends[s++] = g->fends[i];
    g->nfends = s;
    amp_free(al, deg);
    return AMP_OK;
}

/* Step 5 clipping: the parts of the K̂ edges inside the region, with a node
 * of degree 1 (a free end) where an edge leaves the region. */
amp_status amp_cp_clip(const amp_cx2 *k, const uint64_t *ke, size_t nke, const amp_polyset *R, amp_cp_graph *g,
                              amp_error *err)
{
    clip_ctx c;
    size_t i;
    amp_status st = AMP_OK;
    memset(&c, 0, sizeof c);
    c.al = g->al;
    c.g = g;
    c.bx0 = c.by0 = HUGE_VAL;
    c.bx1 = c.by1 = -HUGE_VAL;
    for (i = 0; i < R->npts; i++) {
        c.bx0 = fmin(c.bx0, R->pts[i].x);
        c.by0 = fmin(c.by0, R->pts[i].y);
        c.bx1 = fmax(c.bx1, R->pts[i].x);
        c.by1 = fmax(c.by1, R->pts[i].y);
    }
    c.node = amp_alloc(c.al, (k->nv + 1) * sizeof *c.node);
    c.in = amp_alloc(c.al, k->nv + 1);
    c.kv = amp_alloc(c.al, (k->nv + 1) * sizeof *c.kv);
    if (!c.node || !c.in || !c.kv) {
        st = AMP_ERR_NOMEM;
        goto done;
    }
    c.eps = 1e-9 * (1.0 + fmax(c.bx1 - c.bx0, c.by1 - c.by0));
    if (R->npts == 0 || rg_build(&c.rg, R, c.bx0, c.by0, c.bx1, c.by1, c.al) != AMP_OK) {
        st = R->npts == 0 ? AMP_OK : AMP_ERR_NOMEM;
        goto done;
    }
    place_vertices(&c, k);
    for (i = 0; i < nke && st == AMP_OK; i++) {
        size_t a = (size_t)(ke[i] >> 32), b = (size_t)(ke[i] & 0xffffffffu);
        amp_vec2 A = c.kv[a], B = c.kv[b];
        if (fmax(A.x, B.x) < c.bx0 || fmin(A.x, B.x) > c.bx1 || fmax(A.y, B.y) < c.by0 || fmin(A.y, B.y) > c.by1)
            continue;
        if ((st = edge_crossings(&c, A, B)) != AMP_OK)
            goto done;
        if (c.nh == 0 && (!c.in[a] || !c.in[b]))
            continue;
        if (c.nh > 1)
            qsort(c.h, c.nh, sizeof *c.h, cmp_hit);
        st = edge_pieces(&c, a, b, A, B);
    }
    if (st == AMP_OK)
        st = keep_free_ends(c.al, g);
done:
    amp_free(c.al, c.node);
    amp_free(c.al, c.in);
    amp_free(c.al, c.kv);
    amp_free(c.al, c.h);
    rg_free(c.al, &c.rg);
    if (st == AMP_ERR_NOMEM)
        return amp_fail(err, st, 0, "out of memory clipping the lattice");
    return st;
}
