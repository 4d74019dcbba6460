/*
 * T-junctions of an STL: a vertex lying on the edge of a neighbouring triangle instead of being one of its
 * corners. Exporters write them where a face was split on one side of an edge and not on the other
 * (OpenSCAD's issue 945 and 1580 files, often with a needle triangle of three collinear corners that the
 * reader drops as degenerate), and the surface is then open along that edge though nothing is missing:
 * `info` said "NOT closed", `slice` closed the section gaps with straight edges and a warning, `field`
 * fell back to the winding number. Splitting the long edge's triangle at every such vertex makes the
 * edges meet again; the surface does not move.
 */
#include <math.h>

#include "mesh_internal.h"

/* Boundary edges and boundary vertices beyond which the pairwise search is not tried (an open scan). */
#define TJ_PAIRS_MAX 50000000.0
#define TJ_PASSES 3

/* The edges of triangles [t0, ntris) used once (boundary), packed at the front of e (tri: the mesh's index);
 * returns their count. */
static size_t boundary_edges(const amp_mesh *m, size_t t0, amp_edge_rec *e)
{
    size_t i, j, nb = 0, n = amp_mesh_collect_edges(m->alloc, m->tris + t0, m->ntris - t0, e, NULL);
    for (i = 0; i < n; i = j) {
        for (j = i + 1; j < n && e[j].lo == e[i].lo && e[j].hi == e[i].hi; j++)
            ;
        if (j == i + 1) {
            e[nb] = e[i];
            e[nb++].tri += (uint32_t)t0;
        }
    }
    return nb;
}

/* Parameter in (0, 1) of @p v on the segment a b when it lies on it (within rounding of float coordinates),
 * else -1. */
static double on_segment(amp_vec3 a, amp_vec3 b, amp_vec3 v)
{
    amp_vec3 d = amp_v3_sub(b, a);
    double l2 = amp_v3_dot(d, d), t, tol;
    if (!(l2 > 0.0))
        return -1.0;
    t = amp_v3_dot(amp_v3_sub(v, a), d) / l2;
    tol = 1e-6 * (sqrt(l2) + fmax(fabs(a.x), fmax(fabs(a.y), fabs(a.z))) + 1.0);
    if (t * sqrt(l2) < tol || (1.0 - t) * sqrt(l2) < tol)
        return -1.0;
    return amp_v3_dist(amp_v3_add(a, amp_v3_scale(d, t)), v) <= tol ? t : -1.0;
}

/* Split triangle e->tri at the vertices of @p cand (boundary vertices) that lie on its edge e, in order
 * along it: a fan from the opposite corner. Returns the number of vertices inserted (0: none on it). */
static amp_status split_edge(amp_mesh *m, const amp_edge_rec *e, const uint32_t *cand, size_t nc, double *t,
                             uint32_t *on, size_t *added, amp_error *err)
{
    amp_tri tr = m->tris[e->tri];
    uint32_t a = e->up ? e->lo : e->hi, k = tr.v[0] == a ? 0 : tr.v[1] == a ? 1 : 2;
    uint32_t b = tr.v[(k + 1) % 3], c = tr.v[(k + 2) % 3], prev = a;
    size_t i, j, n = 0;
    amp_status st = AMP_OK;
    *added = 0;
    for (i = 0; i < nc; i++) {
        double s = cand[i] == a || cand[i] == b || cand[i] == c ? -1.0
                                                                : on_segment(m->verts[a], m->verts[b], m->verts[cand[i]]);
        if (s < 0.0)
            continue;
        for (j = n++; j > 0 && t[j - 1] > s; j--) { /* insertion by parameter: few per edge */
            t[j] = t[j - 1];
            on[j] = on[j - 1];
        }
        t[j] = s;
        on[j] = cand[i];
    }
    for (i = 0; i <= n && st == AMP_OK; i++) {
        uint32_t next = i < n ? on[i] : b;
        if (i == 0) {
            m->tris[e->tri].v[0] = prev;
            m->tris[e->tri].v[1] = next;
            m->tris[e->tri].v[2] = c;
        } else {
            st = amp_mesh_add_tri(m, prev, next, c, err);
        }
        prev = next;
    }
    *added = n;
    return st;
}

amp_status amp_mesh_split_tjunctions(amp_mesh *m, size_t t0, size_t *splits, amp_error *err)
{
    /* a file of collinear slivers could fan every boundary edge at every vertex: at most as many new triangles
     * as the file had (a real export has a few T-junctions per seam) */
    size_t cap = 2 * (m->ntris - t0) + 1024;
    int pass;
    amp_status st = AMP_OK;
    *splits = 0;
    if (m->ntris <= t0) /* no triangle read (every one degenerate or collapsed): the caller says so */
        return AMP_OK;
    for (pass = 0; pass < TJ_PASSES && st == AMP_OK; pass++) {
        size_t nt = m->ntris, nb, nv = 0, i, found = 0;
        amp_edge_rec *e = amp_calloc(m->alloc, 3 * (nt - t0) + 1, sizeof *e);
        unsigned char *mark = amp_calloc(m->alloc, m->nverts + 1, 1), *busy = amp_calloc(m->alloc, nt - t0 + 1, 1);
        uint32_t *cand = NULL, *on = NULL;
        double *t = NULL;
        if (e && mark && busy) {
            nb = boundary_edges(m, t0, e);
            for (i = 0; i < nb; i++)
                mark[e[i].lo] = mark[e[i].hi] = 1;
            for (i = 0; i < m->nverts; i++)
                nv += mark[i];
            cand = amp_calloc(m->alloc, nv + 1, sizeof *cand);
            on = amp_calloc(m->alloc, nv + 1, sizeof *on);
            t = amp_calloc(m->alloc, nv + 1, sizeof *t);
        }
        if (!e || !mark || !busy || !cand || !on || !t) {
            st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the mesh's T-junctions");
        } else if (nb > 0 && (double)nb * (double)nv <= TJ_PAIRS_MAX) {
            for (nv = 0, i = 0; i < m->nverts; i++)
                if (mark[i])
                    cand[nv++] = (uint32_t)i;
            /* one edge per triangle a pass: a split triangle's other edges wait for the next pass */
            for (i = 0; i < nb && st == AMP_OK && m->ntris - t0 < cap; i++) {
                size_t added = 0;
                if (busy[e[i].tri - t0])
                    continue;
                st = split_edge(m, &e[i], cand, nv, t, on, &added, err);
                busy[e[i].tri - t0] = added > 0;
                found += added;
            }
        }
        amp_free(m->alloc, e);
        amp_free(m->alloc, mark);
        amp_free(m->alloc, busy);
        amp_free(m->alloc, cand);
        amp_free(m->alloc, on);
        amp_free(m->alloc, t);
        *splits += found;
        if (found == 0)
            break;
    }
    return st;
}
