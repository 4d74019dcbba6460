/*
 * Caps over an open mesh's boundary, for its inside test (lib/bvh.c winding_of).
 *
 * The winding number of a closed, oriented surface is an integer off it: the signed crossing count of any
 * ray, one walk down the tree. An open mesh M (holes, non-manifold or flipped pieces) has the generalised
 * winding number w_M instead (Jacobson et al. 2013), a solid angle per near triangle: 42 s of `field` on a
 * 2,000-triangle 3ds Max export whose every sample sits near a thin wall. Closing M with a cap C whose
 * boundary is the reverse of M's boundary chain (each of its loops triangulated) makes M + C a cycle, so
 *   w_M(p) = w_{M+C}(p) - w_C(p) = (the ray's signed count over M and C) - (C's solid angles) / 4 pi,
 * the same function, exact but for the caps' few solid angles. The chain is the sum of the oriented edges
 * of the triangles the tree keeps: an edge used once each way cancels, so a non-manifold mesh whose edges
 * are used as often in both directions needs no cap at all.
 */
#include <stdlib.h>
#include <string.h>

#include "bvh_internal.h"
#include "mesh_internal.h"

typedef struct dedge {
    uint32_t from, to;
} dedge;

static int dedge_cmp(const void *a, const void *b)
{
    const dedge *x = a, *y = b;
    if (x->from != y->from)
        return x->from < y->from ? -1 : 1;
    return x->to < y->to ? -1 : x->to > y->to;
}

/* The boundary chain of @p t[0..n-1] as directed edges into *out (each as often as its net use); the count. */
static size_t chain_edges(const amp_allocator *al, const amp_tri *t, size_t n, amp_edge_rec *e, dedge *out)
{
    size_t ne = amp_mesh_collect_edges(al, t, n, e, NULL), i, j, nd = 0;
    for (i = 0; i < ne; i = j) {
        long net = 0;
        for (j = i; j < ne && e[j].lo == e[i].lo && e[j].hi == e[i].hi; j++)
            net += e[j].up ? 1 : -1;
        for (; net != 0; net += net > 0 ? -1 : 1) {
            out[nd].from = net > 0 ? e[i].lo : e[i].hi;
            out[nd].to = net > 0 ? e[i].hi : e[i].lo;
            nd++;
        }
    }
    return nd;
}

/* First edge out of @p v in the sorted @p d not used yet (cursor per vertex: its first unused edge). */
static size_t next_out(const dedge *d, size_t nd, const unsigned char *used, uint32_t v)
{
    size_t lo = 0, hi = nd;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (d[mid].from < v)
            lo = mid + 1;
        else
            hi = mid;
    }
    for (; lo < nd && d[lo].from == v; lo++)
        if (!used[lo])
            return lo;
    return nd;
}

/* The cap of the stretch v(a) .. v(b) of a loop closed by the chord v(a) -> v(b): triangle (v(a), v(b), v(m))
 * at its middle m and the caps of both halves, whose boundary is the chord less the stretch. Halving keeps the
 * triangles near the boundary as small as its edges (a fan from one vertex made long slivers, every one of
 * them near a point by the hole, and the caps' winding number cost a solid angle each). */
static void halves(const uint32_t *loop, size_t a, size_t b, amp_tri *cap, size_t *ncap)
{
    size_t m = a + (b - a) / 2;
    if (b - a < 2)
        return;
    cap[*ncap].v[0] = loop[a];
    cap[*ncap].v[1] = loop[b];
    cap[*ncap].v[2] = loop[m];
    (*ncap)++;
    halves(loop, a, m, cap, ncap);
    halves(loop, m, b, cap, ncap);
}

/* The caps of the chain's loops: loop v(0) .. v(k-1) gets halves(0, k - 1), whose boundary is the loop
 * reversed (the chord v(0) -> v(k-1) less the stretch). Every vertex of a chain has as many edges in as out,
 * so a walk from an edge returns to its start; 0 when one does not (it cannot: then no caps). */
static int fan_loops(const dedge *d, size_t nd, unsigned char *used, uint32_t *loop, amp_tri *fan, size_t *nfan)
{
    size_t i;
    *nfan = 0;
    for (i = 0; i < nd; i++) {
        size_t n = 0;
        uint32_t start = d[i].from;
        size_t at = i;
        if (used[i])
            continue;
        for (;;) {
            used[at] = 1;
            loop[n++] = d[at].from;
            if (d[at].to == start)
                break;
            at = next_out(d, nd, used, d[at].to);
            if (at == nd)
                return 0;
        }
        halves(loop, 0, n - 1, fan, nfan);
    }
    return 1;
}

amp_status amp_bvh_cap_build(amp_bvh *b, const amp_vec3 *verts, const amp_tri *tris, size_t ntris, amp_error *err)
{
    const amp_allocator *al = b->alloc;
    amp_tri *kept = amp_alloc(al, (ntris ? ntris : 1) * sizeof *kept), *fan = NULL;
    amp_edge_rec *e = amp_alloc(al, (3 * ntris + 1) * sizeof *e);
    dedge *d = amp_alloc(al, (3 * ntris + 1) * sizeof *d);
    unsigned char *used = NULL;
    uint32_t *loop = NULL;
    size_t i, nk = 0, nd = 0, nfan = 0;
    amp_status st = AMP_OK;
    if (!kept || !e || !d)
        st = AMP_ERR_NOMEM;
    for (i = 0; st == AMP_OK && i < ntris; i++) /* the triangles the tree holds: their chain is its boundary */
        if (amp_bvh_tri_ok(verts[tris[i].v[0]], verts[tris[i].v[1]], verts[tris[i].v[2]]))
            kept[nk++] = tris[i];
    if (st == AMP_OK)
        nd = chain_edges(al, kept, nk, e, d);
    if (st == AMP_OK && nd > 0) {
        qsort(d, nd, sizeof *d, dedge_cmp);
        used = amp_calloc(al, nd, 1);
        loop = amp_alloc(al, nd * sizeof *loop);
        fan = amp_alloc(al, nd * sizeof *fan);
        if (!used || !loop || !fan)
            st = AMP_ERR_NOMEM;
    }
    if (st == AMP_OK && (nd == 0 || fan_loops(d, nd, used, loop, fan, &nfan))) {
        b->capped = 1;
        /* caps of no area (loops along a line) add no crossing and no solid angle */
        if (nfan > 0 && amp_bvh_build_tris(&b->cap, al, verts, fan, nfan, NULL) == AMP_ERR_NOMEM)
            st = AMP_ERR_NOMEM;
        if (st != AMP_OK)
            b->capped = 0;
    }
    amp_free(al, kept);
    amp_free(al, e);
    amp_free(al, d);
    amp_free(al, used);
    amp_free(al, loop);
    amp_free(al, fan);
    return st == AMP_OK ? AMP_OK : amp_fail(err, st, 0, "out of memory closing the mesh's boundary for its inside test");
}
