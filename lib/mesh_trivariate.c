/*
 * The boundary of a trivariate as a triangle mesh: the model that support
 * rays are cast against when the object is given as a trivariate (paper 1,
 * §5.3 "vertical rays on a grid against the model").
 */
#include <math.h>
#include <stdlib.h>

#include "ampath/mesh.h"
#include "ampath/spline.h"

#define MAX_RES 64
/* Sample step along the control polygon (mm): keeps the chordal error of arcs of radius >= 10 mm below 0.02 mm. */
#define STEP_MM 1.0

/* Parameters of one direction: res samples per non-empty knot span, both ends included. */
static amp_status params_of(const amp_spline *v, int d, int res, double **out, size_t *n, amp_error *err)
{
    const double *k = v->knots[d];
    size_t i, spans = 0, at = 0;
    double *t;
    double bound = amp_spline_polygon_length_bound(v, d, NULL);
    for (i = (size_t)v->order[d] - 1; i < v->count[d]; i++)
        spans += k[i + 1] > k[i];
    if (spans > 0 && ceil(bound / (double)spans / STEP_MM) > res)
        res = bound / (double)spans / STEP_MM < MAX_RES ? (int)ceil(bound / (double)spans / STEP_MM) : MAX_RES;
    t = amp_calloc(v->alloc, spans * (size_t)res + 1, sizeof *t);
    if (!t)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory sampling the trivariate boundary");
    for (i = (size_t)v->order[d] - 1; i < v->count[d]; i++) {
        int s;
        if (!(k[i + 1] > k[i]))
            continue;
        for (s = 0; s < res; s++)
            t[at++] = k[i] + (k[i + 1] - k[i]) * s / res;
    }
    t[at++] = k[v->count[d]];
    *out = t;
    *n = at;
    return AMP_OK;
}

/* One face: direction d fixed at parameter td; the other two directions a < b sampled. */
static amp_status add_face(amp_mesh *m, const amp_spline *v, int d, double td, double *const *t, const size_t *n,
                           amp_error *err)
{
    int a = d == 0 ? 1 : 0, b = d == 2 ? 1 : 2;
    size_t i, j, base = m->nverts;
    amp_status st;
    for (i = 0; i < n[a]; i++)
        for (j = 0; j < n[b]; j++) {
            double par[3];
            amp_vec3 p;
            par[d] = td;
            par[a] = t[a][i];
            par[b] = t[b][j];
            if ((st = amp_spline_eval(v, par, &p, err)) != AMP_OK ||
                (st = amp_mesh_add_vertex(m, p, NULL, err)) != AMP_OK)
                return st;
        }
    for (i = 0; i + 1 < n[a]; i++)
        for (j = 0; j + 1 < n[b]; j++) {
            uint32_t q00 = (uint32_t)(base + i * n[b] + j), q01 = q00 + 1;
            uint32_t q10 = (uint32_t)(q00 + n[b]), q11 = q10 + 1;
            if ((st = amp_mesh_add_tri(m, q00, q10, q11, err)) != AMP_OK ||
                (st = amp_mesh_add_tri(m, q00, q11, q01, err)) != AMP_OK)
                return st;
        }
    return AMP_OK;
}

/* A triangle's vertex set (sorted) and its index, to find coinciding faces by sorting. */
typedef struct tri_key {
    uint32_t v[3];
    size_t at;
} tri_key;

static int key_cmp(const void *pa, const void *pb)
{
    const tri_key *a = pa, *b = pb;
    int i;
    for (i = 0; i < 3; i++)
        if (a->v[i] != b->v[i])
            return a->v[i] < b->v[i] ? -1 : 1;
    return 0;
}

/* Faces that coincide after welding (the two sides of a closed direction's seam) lie inside the solid: drop both. */
static amp_status drop_twins(amp_mesh *m, amp_error *err)
{
    tri_key *key = amp_calloc(m->alloc, m->ntris ? m->ntris : 1, sizeof *key);
    size_t i, j, out = 0;
    if (!key)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory removing seam faces");
    for (i = 0; i < m->ntris; i++) {
        uint32_t a = m->tris[i].v[0], b = m->tris[i].v[1], c = m->tris[i].v[2], t;
        if (a > b) { t = a; a = b; b = t; }
        if (b > c) { t = b; b = c; c = t; }
        if (a > b) { t = a; a = b; b = t; }
        key[i].v[0] = a;
        key[i].v[1] = b;
        key[i].v[2] = c;
        key[i].at = i;
    }
    qsort(key, m->ntris, sizeof *key, key_cmp);
    for (i = 0; i < m->ntris; i = j) {
        for (j = i + 1; j < m->ntris && key_cmp(&key[i], &key[j]) == 0; j++)
            ;
        if (j - i > 1)
            for (; i < j; i++)
                m->tris[key[i].at].v[0] = m->tris[key[i].at].v[1]; /* collapsed: removed below */
    }
    for (i = 0; i < m->ntris; i++)
        if (m->tris[i].v[0] != m->tris[i].v[1])
            m->tris[out++] = m->tris[i];
    m->ntris = out;
    amp_free(m->alloc, key);
    return AMP_OK;
}

amp_status amp_mesh_from_trivariate(amp_mesh *m, const struct amp_spline *v, int res, amp_error *err)
{
    double *t[3] = {NULL, NULL, NULL};
    size_t n[3], i;
    amp_status st = AMP_OK;
    amp_box3 box;
    int d;
    if (!m || !v || v->dim != 3 || m->nverts || m->ntris || res < 0 || res > MAX_RES)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_from_trivariate: need a trivariate, an empty mesh and "
                                             "res in 0..%d", MAX_RES);
    if (res == 0)
        res = AMP_MESH_TRIVARIATE_RES;
    for (d = 0; d < 3 && st == AMP_OK; d++)
        st = params_of(v, d, res, &t[d], &n[d], err);
    for (d = 0; d < 3 && st == AMP_OK; d++) {
        double lo, hi;
        amp_spline_domain(v, d, &lo, &hi);
        if ((st = add_face(m, v, d, lo, t, n, err)) == AMP_OK)
            st = add_face(m, v, d, hi, t, n, err);
    }
    for (d = 0; d < 3; d++)
        amp_free(v->alloc, t[d]);
    if (st == AMP_OK) {
        /* Collapsed faces and closed directions (a revolved seam) weld into one closed surface. */
        box = amp_mesh_bbox(m);
        st = amp_mesh_weld(m, 1e-9 * amp_v3_len(amp_v3_sub(box.max, box.min)), err);
    }
    if (st == AMP_OK)
        st = drop_twins(m, err);
    if (st == AMP_OK)
        st = amp_mesh_weld(m, 0.0, err); /* drops the vertices only the seam faces used */
    if (st == AMP_OK)
        st = amp_mesh_orient(m, NULL, err);
    if (st == AMP_OK && amp_mesh_volume(m) < 0)
        for (i = 0; i < m->ntris; i++) {
            uint32_t s = m->tris[i].v[1];
            m->tris[i].v[1] = m->tris[i].v[2];
            m->tris[i].v[2] = s;
        }
    if (st == AMP_OK && !(amp_mesh_volume(m) > 0))
        st = amp_fail(err, AMP_ERR_GEOMETRY, 0, "the trivariate's boundary encloses no volume");
    if (st != AMP_OK)
        amp_mesh_free(m);
    return st;
}
