/* Step 5 (clipping): the pieces of the K̂ edges inside a region, with free
 * ends where an edge leaves it (continuous-toolpath-euler.txt §2.2). */
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

/* A node where edge AB crosses a ring (hit @p h), recorded as a free end. */
static amp_status free_end(amp_cp_graph *g, amp_vec2 A, amp_vec2 B, const hit *h, size_t *id)
{
    void *q = g->fe;
    if (amp_cp_vert(g, amp_v2(A.x + h->t * (B.x - A.x), A.y + h->t * (B.y - A.y)), id) != AMP_OK)
        return AMP_ERR_NOMEM;
    if (amp_grow(g->al, &q, &g->cap_fe, g->nfe + 1, sizeof *g->fe) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->fe = q;
    g->fe[g->nfe].node = *id;
    g->fe[g->nfe].ring = h->ring;
    g->fe[g->nfe].pos = h->pos;
    g->nfe++;
    return AMP_OK;
}

/* Step 5 clipping: the parts of the K̂ edges inside the region, with a node
 * of degree 1 (a free end) where an edge leaves the region. */
amp_status amp_cp_clip(const amp_cx2 *k, const uint64_t *ke, size_t nke, const amp_polyset *R, amp_cp_graph *g,
                              amp_error *err)
{
    const amp_allocator *al = g->al;
    double bx0 = HUGE_VAL, by0 = HUGE_VAL, bx1 = -HUGE_VAL, by1 = -HUGE_VAL;
    size_t *node = NULL, i, r, s, nh, caph = 0, *deg = NULL;
    signed char *in = NULL;
    amp_vec2 *kv = NULL;
    double eps;
    hit *h = NULL;
    amp_status st = AMP_OK;
    for (i = 0; i < R->npts; i++) {
        bx0 = fmin(bx0, R->pts[i].x);
        by0 = fmin(by0, R->pts[i].y);
        bx1 = fmax(bx1, R->pts[i].x);
        by1 = fmax(by1, R->pts[i].y);
    }
    node = amp_alloc(al, (k->nv + 1) * sizeof *node);
    in = amp_alloc(al, k->nv + 1);
    kv = amp_alloc(al, (k->nv + 1) * sizeof *kv);
    if (!node || !in || !kv) {
        st = AMP_ERR_NOMEM;
        goto done;
    }
    eps = 1e-9 * (1.0 + fmax(bx1 - bx0, by1 - by0));
    for (i = 0; i < k->nv; i++) {
        amp_vec2 q = k->v[i];
        int tries;
        node[i] = NONE;
        /* a lattice vertex on a ring (CAD parts aligned with the lattice) is
         * moved off it by a few eps along a fixed oblique direction, so that
         * no vertex and no edge of K̂ lies on the boundary of the region */
        for (tries = 0; tries < 8 && q.x >= bx0 - eps && q.x <= bx1 + eps && q.y >= by0 - eps && q.y <= by1 + eps &&
                        amp_polyset_contains(R, q, eps) < 0;
             tries++)
            q = amp_v2(q.x + 2.2 * eps * 0.6, q.y + 2.2 * eps * 0.8);
        kv[i] = q;
        in[i] = q.x >= bx0 && q.x <= bx1 && q.y >= by0 && q.y <= by1 && amp_polyset_contains(R, q, 0.0) == 1;
    }
    for (i = 0; i < nke && st == AMP_OK; i++) {
        size_t a = (size_t)(ke[i] >> 32), b = (size_t)(ke[i] & 0xffffffffu), j;
        amp_vec2 A = kv[a], B = kv[b];
        size_t prevnode;
        if (fmax(A.x, B.x) < bx0 || fmin(A.x, B.x) > bx1 || fmax(A.y, B.y) < by0 || fmin(A.y, B.y) > by1)
            continue;
        nh = 0;
        /* crossings with every ring edge; a ring vertex exactly on the K̂
         * edge counts as lying on its positive side (symbolic perturbation),
         * so a crossing through it is found exactly once; a point exactly on
         * a ring is outside the region throughout */
        for (r = 0; r < R->nrings; r++) {
            const amp_vec2 *p = amp_polyset_ring(R, r);
            size_t n = R->rings[r].n;
            for (s = 0; s < n; s++) {
                amp_vec2 P = p[s], Q = p[(s + 1) % n];
                double d1, d2, d3, d4;
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
                {
                    void *q = h;
                    if (amp_grow(al, &q, &caph, nh + 1, sizeof *h) != AMP_OK) {
                        st = AMP_ERR_NOMEM;
                        goto done;
                    }
                    h = q;
                }
                h[nh].t = d1 / (d1 - d2);
                h[nh].pos = (double)s + fmin(fmax(d3 / (d3 - d4), 0.0), 0.999999999999);
                h[nh].ring = r;
                nh++;
            }
        }
        if (nh == 0) {
            if (!in[a] || !in[b])
                continue;
        }
        if (nh > 1)
            qsort(h, nh, sizeof *h, cmp_hit);
        /* walk the pieces; piece j runs from hit j-1 (or A) to hit j (or B) */
        prevnode = NONE;
        for (j = 0; j <= nh; j++) {
            double t0 = j ? h[j - 1].t : 0.0, t1 = j < nh ? h[j].t : 1.0;
            amp_vec2 m = amp_v2(A.x + 0.5 * (t0 + t1) * (B.x - A.x), A.y + 0.5 * (t0 + t1) * (B.y - A.y));
            size_t u, v;
            int inside = (j == 0 && nh == 0) ? 1 : amp_polyset_contains(R, m, 0.0) == 1;
            if (!inside) {
                prevnode = NONE;
                continue;
            }
            if (j == 0) {
                if (node[a] == NONE && amp_cp_vert(g, A, &node[a]) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    goto done;
                }
                u = node[a];
            } else if (prevnode != NONE)
                u = prevnode;
            else {
                if (free_end(g, A, B, &h[j - 1], &u) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    goto done;
                }
            }
            if (j == nh) {
                if (node[b] == NONE && amp_cp_vert(g, B, &node[b]) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    goto done;
                }
                v = node[b];
            } else {
                if (free_end(g, A, B, &h[j], &v) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    goto done;
                }
            }
            if (amp_cp_edge(g, u, v, 0) != AMP_OK) {
                st = AMP_ERR_NOMEM;
                goto done;
            }
            prevnode = v;
        }
    }
    /* a crossing node shared by two inside pieces (an edge touching the ring
     * from inside) is not a free end: keep only nodes of degree 1 */
    deg = amp_calloc(al, g->nv + 1, sizeof *deg);
    if (!deg) {
        st = AMP_ERR_NOMEM;
        goto done;
    }
    for (i = 0; i < g->ne; i++) {
        deg[g->eu[i]]++;
        deg[g->ev[i]]++;
    }
    for (i = 0, s = 0; i < g->nfe; i++)
        if (deg[g->fe[i].node] == 1)
            g->fe[s++] = g->fe[i];
    g->nfe = s;
done:
    amp_free(al, node);
    amp_free(al, in);
    amp_free(al, kv);
    amp_free(al, h);
    amp_free(al, deg);
    if (st == AMP_ERR_NOMEM)
        return amp_fail(err, st, 0, "out of memory clipping the lattice");
    return st;
}
