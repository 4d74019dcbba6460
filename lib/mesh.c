/* Triangle mesh container. STL, BVH and inside tests live in their own files. */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/mesh.h"
#include "keysort.h"
#include "mesh_internal.h"

void amp_mesh_init(amp_mesh *m, const amp_allocator *a)
{
    memset(m, 0, sizeof *m);
    m->alloc = a;
}

void amp_mesh_free(amp_mesh *m)
{
    if (!m)
        return;
    amp_free(m->alloc, m->verts);
    amp_free(m->alloc, m->tris);
    amp_mesh_init(m, m->alloc);
}

amp_status amp_mesh_add_vertex(amp_mesh *m, amp_vec3 p, uint32_t *index, amp_error *err)
{
    void *v = m->verts;
    if (!amp_v3_finite(p))
        return amp_fail(err, AMP_ERR_ARG, 0, "vertex coordinate is not finite");
    if (m->nverts >= 0xffffffffUL)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "more than 2^32-1 vertices");
    if (amp_grow(m->alloc, &v, &m->cap_verts, m->nverts + 1, sizeof *m->verts) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for mesh vertices");
    m->verts = v;
    m->verts[m->nverts] = p;
    if (index)
        *index = (uint32_t)m->nverts;
    m->nverts++;
    return AMP_OK;
}

amp_status amp_mesh_add_tri(amp_mesh *m, uint32_t a, uint32_t b, uint32_t c, amp_error *err)
{
    void *t = m->tris;
    if (a >= m->nverts || b >= m->nverts || c >= m->nverts)
        return amp_fail(err, AMP_ERR_ARG, 0, "triangle index out of range");
    if (amp_grow(m->alloc, &t, &m->cap_tris, m->ntris + 1, sizeof *m->tris) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for mesh triangles");
    m->tris = t;
    m->tris[m->ntris].v[0] = a;
    m->tris[m->ntris].v[1] = b;
    m->tris[m->ntris].v[2] = c;
    m->ntris++;
    return AMP_OK;
}

amp_box3 amp_mesh_bbox(const amp_mesh *m)
{
    amp_box3 b = amp_box3_empty();
    size_t i;
    for (i = 0; i < m->nverts; i++)
        b = amp_box3_add(b, m->verts[i]);
    return b;
}

void amp_mesh_translate(amp_mesh *m, amp_vec3 d)
{
    size_t i;
    for (i = 0; i < m->nverts; i++)
        m->verts[i] = amp_v3_add(m->verts[i], d);
}

double amp_mesh_volume(const amp_mesh *m)
{
    /* divergence theorem: sum of signed tetrahedra (origin, a, b, c) / 6 */
    double v = 0.0;
    size_t i;
    for (i = 0; i < m->ntris; i++) {
        amp_vec3 a = m->verts[m->tris[i].v[0]], b = m->verts[m->tris[i].v[1]], c = m->verts[m->tris[i].v[2]];
        v += amp_v3_dot(a, amp_v3_cross(b, c));
    }
    return v / 6.0;
}

static int edge_cmp(const void *pa, const void *pb)
{
    const amp_edge_rec *a = pa, *b = pb;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi)
        return a->hi < b->hi ? -1 : 1;
    return a->up < b->up ? -1 : a->up > b->up;
}

size_t amp_mesh_collect_edges(const amp_allocator *al, const amp_tri *tris, size_t ntris, amp_edge_rec *e,
                              size_t *degenerate)
{
    static const size_t key[3] = {offsetof(amp_edge_rec, lo), offsetof(amp_edge_rec, hi), offsetof(amp_edge_rec, up)};
    size_t i, n = 0;
    for (i = 0; i < ntris; i++) {
        const amp_tri *t = &tris[i];
        int k;
        if (t->v[0] == t->v[1] || t->v[1] == t->v[2] || t->v[0] == t->v[2]) {
            if (degenerate)
                (*degenerate)++;
            continue;
        }
        for (k = 0; k < 3; k++) {
            uint32_t a = t->v[k], b = t->v[(k + 1) % 3];
            e[n].lo = a < b ? a : b;
            e[n].hi = a < b ? b : a;
            e[n].up = a < b;
            e[n].tri = (uint32_t)i;
            n++;
        }
    }
    amp_radix_sort(al, e, n, sizeof *e, key, 3, edge_cmp); /* triangle order within equal keys (stable) */
    return n;
}

amp_status amp_mesh_edges(const amp_mesh *m, amp_mesh_edge_report *out, amp_error *err)
{
    amp_edge_rec *e;
    size_t i, n = 0;
    if (!m || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_edges: NULL argument");
    memset(out, 0, sizeof *out);
    if (m->ntris == 0)
        return AMP_OK;
    e = amp_calloc(m->alloc, m->ntris, 3 * sizeof *e);
    if (!e)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the edge list");
    n = amp_mesh_collect_edges(m->alloc, m->tris, m->ntris, e, &out->degenerate);
    for (i = 0; i < n;) {
        size_t j = i, pos = 0, neg = 0;
        while (j < n && e[j].lo == e[i].lo && e[j].hi == e[i].hi) {
            if (e[j].up)
                pos++;
            else
                neg++;
            j++;
        }
        out->edges++;
        if (j - i == 1)
            out->boundary++;
        else if (j - i > 2)
            out->nonmanifold++;
        else if (pos != 1)
            out->misoriented++;
        i = j;
    }
    amp_free(m->alloc, e);
    out->closed = out->edges > 0 && !out->boundary && !out->nonmanifold && !out->misoriented && !out->degenerate;
    return AMP_OK;
}

static double tri_area(const amp_vec3 *verts, const amp_tri *t)
{
    amp_vec3 a = verts[t->v[0]];
    return 0.5 * amp_v3_len(amp_v3_cross(amp_v3_sub(verts[t->v[1]], a), amp_v3_sub(verts[t->v[2]], a)));
}

amp_status amp_orient_tris(const amp_allocator *al, const amp_vec3 *verts, amp_tri *tris, size_t ntris,
                           size_t *flipped, amp_error *err)
{
    amp_edge_rec *e = NULL;
    uint32_t *nb = NULL, *queue = NULL;
    unsigned char *rel = NULL, *flip = NULL, *seen = NULL;
    size_t i, n = 0, nflip = 0;
    amp_status st = AMP_OK;
    if (flipped)
        *flipped = 0;
    if (ntris == 0)
        return AMP_OK;
    if (ntris > 0x7fffffffUL)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "too many triangles to orient");
    e = amp_calloc(al, ntris, 3 * sizeof *e);
    nb = amp_calloc(al, ntris, 3 * sizeof *nb);
    rel = amp_calloc(al, ntris, 3);
    flip = amp_calloc(al, ntris, 1);
    seen = amp_calloc(al, ntris, 1);
    queue = amp_calloc(al, ntris, sizeof *queue);
    if (!e || !nb || !rel || !flip || !seen || !queue) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory orienting triangles");
        goto done; /* one exit that frees every temporary */
    }
    memset(nb, 0xff, ntris * 3 * sizeof *nb);
    n = amp_mesh_collect_edges(al, tris, ntris, e, NULL);
    /* adjacency across manifold edges only: rel = 1 when the neighbour must be flipped relative to us */
    for (i = 0; i + 1 < n; i++) {
        if (e[i].lo == e[i + 1].lo && e[i].hi == e[i + 1].hi &&
            (i + 2 >= n || e[i + 2].lo != e[i].lo || e[i + 2].hi != e[i].hi) &&
            (i == 0 || e[i - 1].lo != e[i].lo || e[i - 1].hi != e[i].hi)) {
            uint32_t a = e[i].tri, b = e[i + 1].tri;
            int k;
            unsigned char r = e[i].up == e[i + 1].up;
            for (k = 0; k < 3 && nb[3 * (size_t)a + k] != 0xffffffffu; k++)
                ;
            if (k < 3) {
                nb[3 * (size_t)a + k] = b;
                rel[3 * (size_t)a + k] = r;
            }
            for (k = 0; k < 3 && nb[3 * (size_t)b + k] != 0xffffffffu; k++)
                ;
            if (k < 3) {
                nb[3 * (size_t)b + k] = a;
                rel[3 * (size_t)b + k] = r;
            }
        }
    }
    /* breadth-first propagation per component, then keep the majority (by area) orientation */
    for (i = 0; i < ntris; i++) {
        size_t head = 0, tail = 0, q;
        double keep = 0.0, swap = 0.0;
        if (seen[i])
            continue;
        seen[i] = 1;
        queue[tail++] = (uint32_t)i;
        while (head < tail) {
            uint32_t t = queue[head++];
            int k;
            for (k = 0; k < 3; k++) {
                uint32_t o = nb[3 * (size_t)t + k];
                if (o == 0xffffffffu || seen[o])
                    continue;
                seen[o] = 1;
                flip[o] = (unsigned char)(flip[t] ^ rel[3 * (size_t)t + k]);
                queue[tail++] = o;
            }
        }
        for (q = 0; q < tail; q++) {
            double ar = tri_area(verts, &tris[queue[q]]);
            if (flip[queue[q]])
                swap += ar;
            else
                keep += ar;
        }
        for (q = 0; q < tail; q++) {
            uint32_t t = queue[q];
            if (swap > keep)
                flip[t] ^= 1;
            if (flip[t]) {
                uint32_t tmp = tris[t].v[1];
                tris[t].v[1] = tris[t].v[2];
                tris[t].v[2] = tmp;
                nflip++;
            }
        }
    }
done:
    amp_free(al, e);
    amp_free(al, nb);
    amp_free(al, rel);
    amp_free(al, flip);
    amp_free(al, seen);
    amp_free(al, queue);
    if (flipped && st == AMP_OK)
        *flipped = nflip;
    return st;
}

amp_status amp_mesh_orient(amp_mesh *m, size_t *flipped, amp_error *err)
{
    if (!m)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_orient: NULL mesh");
    return amp_orient_tris(m->alloc, m->verts, m->tris, m->ntris, flipped, err);
}
