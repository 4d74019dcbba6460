/* §4: the crossover-free tour (continuous-toolpath-euler.txt §4). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

typedef struct rot_end {
    size_t end; /* 2 * edge + side */
    double ang;
} rot_end;

static int cmp_rot(const void *a, const void *b)
{
    const rot_end *x = a, *y = b;
    size_t ex = x->end / 2, ey = y->end / 2;
    if (x->ang != y->ang)
        return x->ang < y->ang ? -1 : 1;
    /* equal directions: the two copies of a joining patch (both built from
     * the same polyline in the same direction). Ascending edge order at the
     * nodes where they start, descending where they end: the copies then
     * nest like the two sides of a thin digon, a planar rotation system. */
    if (ex == ey)
        return 0;
    if (x->end % 2 != y->end % 2)
        return x->end % 2 < y->end % 2 ? -1 : 1;
    return (ex < ey) == (x->end % 2 == 0) ? -1 : 1;
}

/* §4: one closed tour per connected component, never crossing itself.
 * At every vertex the edge ends are sorted by angle and paired with their
 * neighbour (a non-crossing transition system): the graph falls apart into
 * closed curves that touch without crossing (the boundary cycles). Two
 * curves meeting at a vertex in adjacent ends x, y (partners a, d) are
 * merged by re-pairing (a,x),(y,d) into (x,y),(a,d): both new transitions
 * still cross no other transition of the vertex, and the two curves become
 * one. The merges form the cycle tree; each merge alternates the direction
 * in which the child cycle is run relative to its parent. */
amp_status amp_cp_tour(amp_cp_graph *g, double z, double rad, amp_pathset *out, size_t *ntours, size_t *nodd,
                              amp_error *err)
{
    const amp_allocator *al = g->al;
    size_t ne2 = 2 * g->ne, i, v, *start = NULL, *partner = NULL, *curve = NULL, *uf = NULL, ncurve = 0;
    rot_end *rot = NULL;
    unsigned char *used = NULL, *isopen = NULL;
    int pass;
    amp_status st = AMP_OK;
    *ntours = 0;
    *nodd = 0;
    if (g->ne == 0)
        return AMP_OK;
    start = amp_calloc(al, g->nv + 2, sizeof *start);
    rot = amp_alloc(al, ne2 * sizeof *rot);
    partner = amp_alloc(al, ne2 * sizeof *partner);
    curve = amp_alloc(al, g->ne * sizeof *curve);
    uf = amp_alloc(al, g->ne * sizeof *uf);
    used = amp_calloc(al, g->ne, 1);
    isopen = amp_calloc(al, g->ne, 1);
    if (!start || !rot || !partner || !curve || !uf || !used || !isopen) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the tour");
        goto done;
    }
    /* rotation system: ends grouped by vertex (CSR), sorted by angle */
    for (i = 0; i < g->ne; i++) {
        start[g->eu[i] + 2]++;
        start[g->ev[i] + 2]++;
    }
    for (v = 0; v < g->nv; v++)
        start[v + 2] += start[v + 1];
    for (i = 0; i < ne2; i++) {
        size_t e = i / 2, at = i % 2 ? g->ev[e] : g->eu[e], to = i % 2 ? g->eu[e] : g->ev[e];
        rot_end *re = &rot[start[at + 1]++];
        re->end = i;
        re->ang = atan2(g->v[to].y - g->v[at].y, g->v[to].x - g->v[at].x);
    }
    for (v = 0; v < g->nv; v++) {
        size_t d = start[v + 1] - start[v], j;
        if (d > 1)
            qsort(rot + start[v], d, sizeof *rot, cmp_rot);
        for (j = 0; j + 1 < d; j += 2) {
            partner[rot[start[v] + j].end] = rot[start[v] + j + 1].end;
            partner[rot[start[v] + j + 1].end] = rot[start[v] + j].end;
        }
        if (d % 2) {
            partner[rot[start[v] + d - 1].end] = NONE; /* odd vertex: the curve ends here */
            (*nodd)++;
        }
    }
    /* label the curves of the transition system; open ones first */
    for (i = 0; i < g->ne; i++)
        curve[i] = NONE;
    for (i = 0; i < ne2; i++) {
        size_t x;
        if (partner[i] != NONE || curve[i / 2] != NONE)
            continue;
        for (x = i; x != NONE && curve[x / 2] == NONE; x = partner[x ^ 1u])
            curve[x / 2] = ncurve; /* leave by the other end, continue through its partner */
        isopen[ncurve++] = 1;
    }
    for (i = 0; i < g->ne; i++) {
        size_t x;
        if (curve[i] != NONE)
            continue;
        for (x = 2 * i; x != NONE && curve[x / 2] == NONE; x = partner[x ^ 1u])
            curve[x / 2] = ncurve;
        isopen[ncurve++] = 0;
    }
    for (i = 0; i < ncurve; i++)
        uf[i] = i;
    /* merge curves at shared vertices (the cycle tree) */
    for (v = 0; v < g->nv; v++) {
        size_t d = start[v + 1] - start[v], p;
        int again = 1;
        while (again && d >= 4) {
            again = 0;
            for (p = 0; p < d; p++) {
                size_t x = rot[start[v] + p].end, y = rot[start[v] + (p + 1) % d].end, a, dd, cx, cy;
                if (partner[x] == y || partner[x] == NONE || partner[y] == NONE)
                    continue;
                cx = amp_cp_uf_find(uf, curve[x / 2]);
                cy = amp_cp_uf_find(uf, curve[y / 2]);
                /* two open curves re-paired stay two open curves: skip */
                if (cx == cy || (isopen[cx] && isopen[cy]))
                    continue;
                a = partner[x];
                dd = partner[y];
                partner[a] = dd;
                partner[dd] = a;
                partner[x] = y;
                partner[y] = x;
                uf[cx] = cy;
                isopen[cy] = (unsigned char)(isopen[cx] | isopen[cy]);
                again = 1;
            }
        }
    }
    /* trace: open curves from their terminal, then closed curves from a
     * printed edge. A pseudo edge is written with radius 0 at both ends; where
     * printing and travel meet, the vertex is written twice (a zero-length
     * step), so no segment mixes the two radii (SPEC §5: mean radius). */
    for (pass = 0; pass < 3 && st == AMP_OK; pass++)
        for (i = 0; i < ne2 && st == AMP_OK; i++) {
            size_t x = i, first = i, at = x % 2 ? g->ev[x / 2] : g->eu[x / 2];
            double cur;
            if (used[i / 2] || (pass == 0 && partner[i] != NONE) || (pass == 1 && g->ep[i / 2]))
                continue;
            cur = g->ep[i / 2] ? 0.0 : rad;
            if ((st = amp_pathset_begin(out, AMP_ROLE_OBJECT, err)) != AMP_OK)
                break;
            st = amp_pathset_push(out, amp_v3(g->v[at].x, g->v[at].y, z), cur, err);
            while (st == AMP_OK) {
                size_t e = x / 2, to = x % 2 ? g->eu[e] : g->ev[e];
                double r = g->ep[e] ? 0.0 : rad;
                used[e] = 1;
                if (r != cur)
                    st = amp_pathset_push(out, amp_v3(g->v[at].x, g->v[at].y, z), r, err);
                if (st == AMP_OK)
                    st = amp_pathset_push(out, amp_v3(g->v[to].x, g->v[to].y, z), r, err);
                cur = r;
                at = to;
                x = partner[x ^ 1u];
                if (x == NONE || x == first || used[x / 2])
                    break;
            }
            (*ntours)++;
        }
done:
    amp_free(al, start);
    amp_free(al, rot);
    amp_free(al, partner);
    amp_free(al, curve);
    amp_free(al, uf);
    amp_free(al, used);
    amp_free(al, isopen);
    return st;
}
