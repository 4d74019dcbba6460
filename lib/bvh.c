/*
 * BVH over a triangle mesh: rays, segments, closest points, the generalised
 * winding number and polyline clipping ([P1 §4.2]: covering curves are cut
 * to the mesh and only the inside parts are printed).
 *
 * The tree is built with a binned surface-area heuristic. Each node also
 * carries its area vector and area-weighted centroid, which gives the
 * first-order far-field ("dipole") term of the winding number (Barill et al.,
 * Fast Winding Numbers, 2018); near nodes are evaluated exactly with the
 * Van Oosterom–Strackee solid angle.
 */
#include <math.h>
#include <string.h>

#include "ampath/bvh.h"
#include "bvh_internal.h"
#include "mesh_internal.h"

#define LEAF_MAX 4
#define MAX_DEPTH 60
#define STACK_SIZE 128
#define NBINS 16
/* far-field criterion: |p - centroid| > BETA * radius */
#define BETA 4.0

/* ------------------------------------------------------------------ build */

typedef struct build_ctx {
    const amp_allocator *a;
    bvh_tri *tris;
    amp_vec3 *cent; /* triangle centroids, permuted with tris */
    amp_box3 *tbox; /* triangle boxes (tri_box), permuted with tris: computed once, read at every level */
    bvh_node *nodes;
    size_t nnodes, cap; /* nodes grow as needed: about 0.7 per triangle are used of the 2 the worst case needs */
    int nomem;
} build_ctx;

static amp_box3 tri_box(const bvh_tri *t)
{
    amp_box3 b = amp_box3_empty();
    b = amp_box3_add(b, t->p[0]);
    b = amp_box3_add(b, t->p[1]);
    return amp_box3_add(b, t->p[2]);
}

/* amp_box3_union by comparisons (no libm call): the same boxes for the finite, non-NaN coordinates a BVH
 * holds (a -0 / +0 choice aside, which the node inflation and box_area do not see). */
static amp_box3 box_join(amp_box3 a, const amp_box3 *b)
{
    a.min.x = b->min.x < a.min.x ? b->min.x : a.min.x;
    a.min.y = b->min.y < a.min.y ? b->min.y : a.min.y;
    a.min.z = b->min.z < a.min.z ? b->min.z : a.min.z;
    a.max.x = b->max.x > a.max.x ? b->max.x : a.max.x;
    a.max.y = b->max.y > a.max.y ? b->max.y : a.max.y;
    a.max.z = b->max.z > a.max.z ? b->max.z : a.max.z;
    return a;
}

static double box_area(amp_box3 b)
{
    amp_vec3 s;
    if (amp_box3_is_empty(b))
        return 0.0;
    s = amp_box3_size(b);
    return s.x * s.y + s.y * s.z + s.z * s.x;
}

static double axis_of(amp_vec3 v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }

static void swap_tri(build_ctx *c, size_t i, size_t j)
{
    bvh_tri t = c->tris[i];
    amp_vec3 p = c->cent[i];
    amp_box3 bx = c->tbox[i];
    c->tris[i] = c->tris[j];
    c->tris[j] = t;
    c->cent[i] = c->cent[j];
    c->cent[j] = p;
    c->tbox[i] = c->tbox[j];
    c->tbox[j] = bx;
}

/* Fill the dipole data of a leaf from its triangles. */
static void leaf_moments(build_ctx *c, bvh_node *nd)
{
    amp_vec3 area = amp_v3(0, 0, 0), cw = amp_v3(0, 0, 0);
    double asum = 0.0, r = 0.0;
    size_t i;
    int k;
    for (i = nd->first; i < nd->first + nd->count; i++) {
        const bvh_tri *t = &c->tris[i];
        amp_vec3 n = amp_v3_scale(amp_v3_cross(amp_v3_sub(t->p[1], t->p[0]), amp_v3_sub(t->p[2], t->p[0])), 0.5);
        double a = amp_v3_len(n);
        area = amp_v3_add(area, n);
        cw = amp_v3_madd(cw, c->cent[i], a);
        asum += a;
    }
    nd->area = area;
    nd->cent = asum > 0 ? amp_v3_scale(cw, 1.0 / asum) : amp_box3_center(nd->box);
    for (i = nd->first; i < nd->first + nd->count; i++)
        for (k = 0; k < 3; k++)
            r = fmax(r, amp_v3_dist(nd->cent, c->tris[i].p[k]));
    nd->radius = r;
}

/* Room for one more node (zeroed); 0 when out of memory (c->nomem then stays set). */
static int node_room(build_ctx *c)
{
    void *p = c->nodes;
    size_t cap = c->cap;
    if (c->nnodes < c->cap)
        return 1;
    if (c->nomem || amp_grow(c->a, &p, &cap, c->nnodes + 1, sizeof *c->nodes) != AMP_OK) {
        c->nomem = 1;
        return 0;
    }
    memset((bvh_node *)p + c->cap, 0, (cap - c->cap) * sizeof *c->nodes);
    c->nodes = p;
    c->cap = cap;
    return 1;
}

static uint32_t build_node(build_ctx *c, size_t first, size_t count, int depth)
{
    uint32_t id;
    bvh_node *nd;
    amp_box3 cb = amp_box3_empty();
    size_t i, mid = 0;
    int axis, best_axis = -1, best_bin = -1;
    double best_cost = HUGE_VAL;
    if (!node_room(c))
        return 0;
    id = (uint32_t)c->nnodes++;
    nd = &c->nodes[id];
    nd->box = amp_box3_empty();
    for (i = first; i < first + count; i++) {
        nd->box = box_join(nd->box, &c->tbox[i]);
        cb = amp_box3_add(cb, c->cent[i]);
    }
    {
        /* inflate by a relative 1e-9 so that the exact slab test never drops a hit on a face */
        amp_vec3 sz = amp_box3_size(nd->box);
        double mag = fmax(fmax(fabs(nd->box.min.x), fabs(nd->box.max.x)),
                          fmax(fmax(fabs(nd->box.min.y), fabs(nd->box.max.y)), fmax(fabs(nd->box.min.z), fabs(nd->box.max.z))));
        nd->box = amp_box3_inflate(nd->box, 1e-9 * (mag + fmax(sz.x, fmax(sz.y, sz.z))) + 1e-300);
    }
    nd->first = (uint32_t)first;
    nd->count = (uint32_t)count;
    nd->left = nd->right = 0;
    if (count > LEAF_MAX && depth < MAX_DEPTH) {
        /* binned SAH over centroid bounds on each axis */
        for (axis = 0; axis < 3; axis++) {
            double lo = axis_of(cb.min, axis), hi = axis_of(cb.max, axis), scale;
            amp_box3 bb[NBINS], lb[NBINS];
            size_t bn[NBINS], ln[NBINS], rn;
            amp_box3 rb;
            int k;
            if (!(hi > lo))
                continue;
            scale = NBINS / (hi - lo);
            for (k = 0; k < NBINS; k++) {
                bb[k] = amp_box3_empty();
                bn[k] = 0;
            }
            for (i = first; i < first + count; i++) {
                int bin = (int)((axis_of(c->cent[i], axis) - lo) * scale);
                bin = bin < 0 ? 0 : (bin >= NBINS ? NBINS - 1 : bin);
                bb[bin] = box_join(bb[bin], &c->tbox[i]);
                bn[bin]++;
            }
            lb[0] = bb[0];
            ln[0] = bn[0];
            for (k = 1; k < NBINS; k++) {
                lb[k] = amp_box3_union(lb[k - 1], bb[k]);
                ln[k] = ln[k - 1] + bn[k];
            }
            rb = amp_box3_empty();
            rn = 0;
            for (k = NBINS - 1; k >= 1; k--) {
                double cost;
                rb = amp_box3_union(rb, bb[k]);
                rn += bn[k];
                if (ln[k - 1] == 0 || rn == 0)
                    continue;
                cost = box_area(lb[k - 1]) * (double)ln[k - 1] + box_area(rb) * (double)rn;
                if (cost < best_cost) {
                    best_cost = cost;
                    best_axis = axis;
                    best_bin = k;
                }
            }
        }
        if (best_axis >= 0) {
            double lo = axis_of(cb.min, best_axis), hi = axis_of(cb.max, best_axis), scale = NBINS / (hi - lo);
            size_t j = first + count;
            i = first;
            while (i < j) {
                int bin = (int)((axis_of(c->cent[i], best_axis) - lo) * scale);
                bin = bin < 0 ? 0 : (bin >= NBINS ? NBINS - 1 : bin);
                if (bin < best_bin)
                    i++;
                else
                    swap_tri(c, i, --j);
            }
            mid = i;
        }
        if (mid > first && mid < first + count) {
            uint32_t l = build_node(c, first, mid - first, depth + 1);
            uint32_t r = build_node(c, mid, first + count - mid, depth + 1);
            nd = &c->nodes[id]; /* the children may have moved the array */
            nd->left = l;
            nd->right = r;
            nd->count = 0;
            /* dipole moments add; centroid and radius follow in finish_moments() */
            nd->area = amp_v3_add(c->nodes[l].area, c->nodes[r].area);
            return id;
        }
    }
    leaf_moments(c, nd);
    return id;
}

/*
 * Second pass: area-weighted centroids and radii of interior nodes from the
 * leaves up (children always have larger indices than their parent).
 */
static void finish_moments(build_ctx *c, double *absarea)
{
    size_t i;
    for (i = c->nnodes; i-- > 0;) {
        bvh_node *nd = &c->nodes[i];
        if (nd->count > 0) {
            size_t t;
            double a = 0.0;
            for (t = nd->first; t < nd->first + nd->count; t++) {
                const bvh_tri *tr = &c->tris[t];
                a += 0.5 * amp_v3_len(amp_v3_cross(amp_v3_sub(tr->p[1], tr->p[0]), amp_v3_sub(tr->p[2], tr->p[0])));
            }
            absarea[i] = a;
        } else {
            const bvh_node *l = &c->nodes[nd->left], *r = &c->nodes[nd->right];
            double al = absarea[nd->left], ar = absarea[nd->right], s = al + ar;
            absarea[i] = s;
            nd->cent = s > 0 ? amp_v3_scale(amp_v3_add(amp_v3_scale(l->cent, al), amp_v3_scale(r->cent, ar)), 1.0 / s)
                             : amp_box3_center(nd->box);
            nd->radius = fmax(amp_v3_dist(nd->cent, l->cent) + l->radius, amp_v3_dist(nd->cent, r->cent) + r->radius);
        }
    }
}

int amp_bvh_tri_ok(amp_vec3 a, amp_vec3 b, amp_vec3 c)
{
    amp_vec3 ab = amp_v3_sub(b, a), ac = amp_v3_sub(c, a);
    double l = fmax(amp_v3_len2(ab), fmax(amp_v3_len2(ac), amp_v3_dist2(b, c)));
    return amp_v3_len(amp_v3_cross(ab, ac)) > 1e-12 * l;
}

/* Whether the oriented copy @p tris of @p m's triangles is closed (amp_mesh_edges() on a view of it). */
static amp_status closed_after_orienting(const amp_mesh *m, amp_tri *tris, int *closed, amp_error *err)
{
    amp_mesh view = *m;
    amp_mesh_edge_report r;
    amp_status st;
    view.tris = tris;
    st = amp_mesh_edges(&view, &r, err);
    *closed = st == AMP_OK && r.closed;
    return st;
}

amp_status amp_bvh_build_tris(amp_bvh **out, const amp_allocator *al, const amp_vec3 *verts, const amp_tri *tris,
                              size_t ntris, amp_error *err)
{
    amp_bvh *b;
    build_ctx c;
    double *absarea;
    size_t i, n = 0;
    *out = NULL;
    memset(&c, 0, sizeof c);
    for (i = 0; i < ntris; i++)
        n += amp_bvh_tri_ok(verts[tris[i].v[0]], verts[tris[i].v[1]], verts[tris[i].v[2]]);
    if (n == 0)
        return amp_fail(err, AMP_ERR_GEOMETRY, 0, "mesh has no triangle with positive area");
    b = amp_calloc(al, 1, sizeof *b);
    if (!b)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory building the BVH");
    b->alloc = al;
    b->tris = amp_calloc(al, n, sizeof *b->tris);
    c.cap = n;
    c.nodes = amp_calloc(al, c.cap, sizeof *c.nodes);
    c.cent = amp_calloc(al, n, sizeof *c.cent);
    c.tbox = amp_calloc(al, n, sizeof *c.tbox);
    if (!b->tris || !c.nodes || !c.cent || !c.tbox) {
        amp_free(al, c.cent);
        amp_free(al, c.tbox);
        amp_free(al, c.nodes);
        amp_bvh_free(b);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory building the BVH");
    }
    b->bbox = amp_box3_empty();
    for (i = 0, n = 0; i < ntris; i++) {
        amp_vec3 p0 = verts[tris[i].v[0]], p1 = verts[tris[i].v[1]], p2 = verts[tris[i].v[2]];
        if (!amp_bvh_tri_ok(p0, p1, p2))
            continue;
        b->tris[n].p[0] = p0;
        b->tris[n].p[1] = p1;
        b->tris[n].p[2] = p2;
        b->tris[n].src = i;
        c.cent[n] = amp_v3_scale(amp_v3_add(amp_v3_add(p0, p1), p2), 1.0 / 3.0);
        c.tbox[n] = tri_box(&b->tris[n]);
        b->bbox = amp_box3_union(b->bbox, c.tbox[n]);
        n++;
    }
    b->ntris = n;
    c.a = al;
    c.tris = b->tris;
    build_node(&c, 0, n, 0);
    amp_free(al, c.cent);
    amp_free(al, c.tbox);
    b->nodes = c.nodes;
    b->nnodes = c.nnodes;
    absarea = c.nomem ? NULL : amp_calloc(al, c.nnodes, sizeof *absarea);
    if (!absarea) {
        amp_bvh_free(b);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory building the BVH");
    }
    finish_moments(&c, absarea);
    amp_free(al, absarea);
    if (c.nnodes < c.cap) { /* the slack back (a failed shrink keeps the block) */
        bvh_node *q = amp_realloc_array(al, c.nodes, c.nnodes, sizeof *c.nodes);
        if (q)
            b->nodes = q;
    }
    *out = b;
    return AMP_OK;
}

amp_status amp_bvh_build(amp_bvh **out, const amp_mesh *m, amp_error *err)
{
    amp_bvh *b = NULL;
    amp_tri *tris;
    size_t i, flipped = 0;
    int closed = 0;
    amp_status st;
    if (!out || !m)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_bvh_build: NULL argument");
    *out = NULL;
    if (m->ntris > 0x7fffffffUL)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "amp_bvh_build: more than 2^31 triangles");
    for (i = 0; i < m->ntris; i++) {
        int k;
        for (k = 0; k < 3; k++)
            if (m->tris[i].v[k] >= m->nverts)
                return amp_fail(err, AMP_ERR_ARG, 0, "triangle %lu: vertex index out of range", (unsigned long)i);
    }
    /* orient a private copy of the index triangles (mesh stays untouched) */
    tris = amp_calloc(m->alloc, m->ntris ? m->ntris : 1, sizeof *tris);
    if (!tris)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory building the BVH");
    if (m->ntris)
        memcpy(tris, m->tris, m->ntris * sizeof *tris);
    st = amp_orient_tris(m->alloc, m->verts, tris, m->ntris, &flipped, err);
    if (st == AMP_OK)
        st = closed_after_orienting(m, tris, &closed, err);
    if (st == AMP_OK)
        st = amp_bvh_build_tris(&b, m->alloc, m->verts, tris, m->ntris, err);
    if (st == AMP_OK) {
        b->flipped = flipped;
        b->closed = closed;
        /* an open mesh: caps over its boundary make the winding number a ray's count again (bvh_cap.c) */
        if (!closed && (st = amp_bvh_cap_build(b, m->verts, tris, m->ntris, err)) != AMP_OK) {
            amp_bvh_free(b);
            b = NULL;
        }
    }
    amp_free(m->alloc, tris);
    *out = b;
    return st;
}

void amp_bvh_free(amp_bvh *b)
{
    if (!b)
        return;
    amp_bvh_free(b->cap);
    amp_free(b->alloc, b->tris);
    amp_free(b->alloc, b->nodes);
    amp_free(b->alloc, b);
}

size_t amp_bvh_triangles(const amp_bvh *b) { return b->ntris; }
size_t amp_bvh_flipped(const amp_bvh *b) { return b->flipped; }
int amp_bvh_closed(const amp_bvh *b) { return b->closed; }
long amp_bvh_cap_triangles(const amp_bvh *b) { return b->closed ? 0 : !b->capped ? -1 : b->cap ? (long)b->cap->ntris : 0; }
amp_box3 amp_bvh_bbox(const amp_bvh *b) { return b->bbox; }

/* ------------------------------------------------------------------- rays */

/* fmin and fmax by comparisons, NaN dropped as they drop it: the compiler inlines these and not the libm calls
 * (the sign of a zero result may differ, which no comparison below sees) */
static double min_nan(double a, double b) { return a < b || b != b ? a : b; }
static double max_nan(double a, double b) { return a > b || b != b ? a : b; }

/* Slab test; min_nan/max_nan drop the NaN of 0 * inf when the origin lies on a slab plane. */
static int ray_box(amp_box3 bx, amp_vec3 o, amp_vec3 inv, double tmax)
{
    double t1 = (bx.min.x - o.x) * inv.x, t2 = (bx.max.x - o.x) * inv.x;
    double lo = min_nan(t1, t2), hi = max_nan(t1, t2);
    t1 = (bx.min.y - o.y) * inv.y;
    t2 = (bx.max.y - o.y) * inv.y;
    lo = max_nan(lo, min_nan(t1, t2));
    hi = min_nan(hi, max_nan(t1, t2));
    t1 = (bx.min.z - o.z) * inv.z;
    t2 = (bx.max.z - o.z) * inv.z;
    lo = max_nan(lo, min_nan(t1, t2));
    hi = min_nan(hi, max_nan(t1, t2));
    /* exact comparison: node boxes are inflated at build time, so touching hits are kept */
    return hi >= max_nan(lo, 0.0) && lo <= tmax;
}

/*
 * Möller–Trumbore with a tiny tolerance on the barycentric bounds, so that a
 * ray through a shared edge hits both neighbours rather than slipping between
 * them (duplicates are harmless to the clipper, misses are not).
 */
static int ray_tri(const bvh_tri *t, amp_vec3 o, amp_vec3 d, double tmax, double *tt, double *uu, double *vv)
{
    const double eps = 1e-12;
    amp_vec3 e1 = amp_v3_sub(t->p[1], t->p[0]), e2 = amp_v3_sub(t->p[2], t->p[0]);
    amp_vec3 pv = amp_v3_cross(d, e2), tv, qv;
    double det = amp_v3_dot(e1, pv), inv, u, v, s;
    double scale = amp_v3_len(e1) * amp_v3_len(e2) * amp_v3_len(d);
    if (fabs(det) <= 1e-15 * scale)
        return 0; /* parallel: a segment in the triangle's plane does not cross it */
    inv = 1.0 / det;
    tv = amp_v3_sub(o, t->p[0]);
    u = amp_v3_dot(tv, pv) * inv;
    if (u < -eps || u > 1 + eps)
        return 0;
    qv = amp_v3_cross(tv, e1);
    v = amp_v3_dot(d, qv) * inv;
    if (v < -eps || u + v > 1 + eps)
        return 0;
    s = amp_v3_dot(e2, qv) * inv;
    if (s < 0 || s > tmax)
        return 0;
    *tt = s;
    *uu = u;
    *vv = v;
    return 1;
}

static amp_vec3 inv_dir(amp_vec3 d)
{
    return amp_v3(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
}

static void fill_hit(const amp_bvh *b, const bvh_tri *t, amp_vec3 o, amp_vec3 d, double s, double u, double v,
                     amp_bvh_hit *h)
{
    amp_vec3 n = amp_v3_cross(amp_v3_sub(t->p[1], t->p[0]), amp_v3_sub(t->p[2], t->p[0]));
    (void)b;
    h->t = s;
    h->tri = t->src;
    h->u = u;
    h->v = v;
    h->p = amp_v3_madd(o, d, s);
    h->entering = amp_v3_dot(n, d) < 0;
}

int amp_bvh_ray_first(const amp_bvh *b, amp_vec3 o, amp_vec3 d, double tmax, amp_bvh_hit *hit)
{
    uint32_t stack[STACK_SIZE];
    int sp = 0, found = 0;
    amp_vec3 inv = inv_dir(d);
    double best = tmax, bu = 0, bv = 0;
    const bvh_tri *bt = NULL;
    if (!amp_v3_finite(o) || !amp_v3_finite(d) || isnan(tmax))
        return 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const bvh_node *nd = &b->nodes[stack[--sp]];
        if (!ray_box(nd->box, o, inv, best))
            continue;
        if (nd->count) {
            uint32_t i;
            for (i = nd->first; i < nd->first + nd->count; i++) {
                double s, u, v;
                if (ray_tri(&b->tris[i], o, d, best, &s, &u, &v)) {
                    best = s;
                    bu = u;
                    bv = v;
                    bt = &b->tris[i];
                    found = 1;
                }
            }
        } else {
            stack[sp++] = nd->left;
            stack[sp++] = nd->right;
        }
    }
    if (found && hit)
        fill_hit(b, bt, o, d, best, bu, bv, hit);
    return found;
}

static int hit_cmp(const amp_bvh_hit *a, const amp_bvh_hit *b) { return a->t < b->t ? -1 : (a->t > b->t); }

/* Insertion sort: hit lists along one segment are short. */
static void sort_hits(amp_bvh_hit *h, size_t n)
{
    size_t i, j;
    for (i = 1; i < n; i++) {
        amp_bvh_hit x = h[i];
        for (j = i; j > 0 && hit_cmp(&h[j - 1], &x) > 0; j--)
            h[j] = h[j - 1];
        h[j] = x;
    }
}

amp_status amp_bvh_ray_all(const amp_bvh *b, amp_vec3 o, amp_vec3 d, double tmax, amp_bvh_hit **hits, size_t *n,
                           amp_error *err)
{
    uint32_t stack[STACK_SIZE];
    int sp = 0;
    amp_vec3 inv = inv_dir(d);
    amp_bvh_hit *h = NULL;
    size_t nh = 0, cap = 0;
    if (!b || !hits || !n)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_bvh_ray_all: NULL argument");
    *hits = NULL;
    *n = 0;
    if (!amp_v3_finite(o) || !amp_v3_finite(d) || isnan(tmax))
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_bvh_ray_all: non-finite ray");
    stack[sp++] = 0;
    while (sp > 0) {
        const bvh_node *nd = &b->nodes[stack[--sp]];
        if (!ray_box(nd->box, o, inv, tmax))
            continue;
        if (nd->count) {
            uint32_t i;
            for (i = nd->first; i < nd->first + nd->count; i++) {
                double s, u, v;
                void *p = h;
                if (!ray_tri(&b->tris[i], o, d, tmax, &s, &u, &v))
                    continue;
                if (amp_grow(b->alloc, &p, &cap, nh + 1, sizeof *h) != AMP_OK) {
                    amp_free(b->alloc, h);
                    return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory collecting ray hits");
                }
                h = p;
                fill_hit(b, &b->tris[i], o, d, s, u, v, &h[nh++]);
            }
        } else {
            stack[sp++] = nd->left;
            stack[sp++] = nd->right;
        }
    }
    sort_hits(h, nh);
    *hits = h;
    *n = nh;
    return AMP_OK;
}

amp_status amp_bvh_segment_hits(const amp_bvh *b, amp_vec3 a, amp_vec3 c, amp_bvh_hit **hits, size_t *n,
                                amp_error *err)
{
    return amp_bvh_ray_all(b, a, amp_v3_sub(c, a), 1.0, hits, n, err);
}

void amp_bvh_hits_free(const amp_bvh *b, amp_bvh_hit *hits)
{
    if (b)
        amp_free(b->alloc, hits);
}

/* --------------------------------------------------------- closest point */

static double box_dist2(amp_box3 b, amp_vec3 p)
{
    double dx = max_nan(max_nan(b.min.x - p.x, 0.0), p.x - b.max.x);
    double dy = max_nan(max_nan(b.min.y - p.y, 0.0), p.y - b.max.y);
    double dz = max_nan(max_nan(b.min.z - p.z, 0.0), p.z - b.max.z);
    return dx * dx + dy * dy + dz * dz;
}

/* Closest point on triangle abc to p (Ericson, Real-Time Collision Detection §5.1.5). */
static amp_vec3 closest_on_tri(amp_vec3 p, amp_vec3 a, amp_vec3 b, amp_vec3 c)
{
    amp_vec3 ab = amp_v3_sub(b, a), ac = amp_v3_sub(c, a), ap = amp_v3_sub(p, a), bp, cp;
    double d1 = amp_v3_dot(ab, ap), d2 = amp_v3_dot(ac, ap), d3, d4, d5, d6, va, vb, vc, v, w, den;
    if (d1 <= 0 && d2 <= 0)
        return a;
    bp = amp_v3_sub(p, b);
    d3 = amp_v3_dot(ab, bp);
    d4 = amp_v3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3)
        return b;
    vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return amp_v3_madd(a, ab, d1 / (d1 - d3));
    cp = amp_v3_sub(p, c);
    d5 = amp_v3_dot(ab, cp);
    d6 = amp_v3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6)
        return c;
    vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return amp_v3_madd(a, ac, d2 / (d2 - d6));
    va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return amp_v3_madd(b, amp_v3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    den = 1.0 / (va + vb + vc);
    v = vb * den;
    w = vc * den;
    return amp_v3_add(a, amp_v3_add(amp_v3_scale(ab, v), amp_v3_scale(ac, w)));
}

double amp_bvh_closest(const amp_bvh *b, amp_vec3 p, amp_vec3 *q, size_t *tri)
{
    uint32_t stack[STACK_SIZE];
    int sp = 0;
    double best = HUGE_VAL;
    amp_vec3 bq = p;
    size_t bt = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const bvh_node *nd = &b->nodes[stack[--sp]];
        if (box_dist2(nd->box, p) >= best)
            continue;
        if (nd->count) {
            uint32_t i;
            for (i = nd->first; i < nd->first + nd->count; i++) {
                const bvh_tri *t = &b->tris[i];
                amp_vec3 x = closest_on_tri(p, t->p[0], t->p[1], t->p[2]);
                double d2 = amp_v3_dist2(p, x);
                if (d2 < best) {
                    best = d2;
                    bq = x;
                    bt = t->src;
                }
            }
        } else {
            /* visit the nearer child first so that the bound tightens sooner */
            double dl = box_dist2(b->nodes[nd->left].box, p), dr = box_dist2(b->nodes[nd->right].box, p);
            if (dl < dr) {
                stack[sp++] = nd->right;
                stack[sp++] = nd->left;
            } else {
                stack[sp++] = nd->left;
                stack[sp++] = nd->right;
            }
        }
    }
    if (q)
        *q = bq;
    if (tri)
        *tri = bt;
    return sqrt(best);
}

/* ------------------------------------------------------ winding number */

/* Signed solid angle of triangle abc seen from p (Van Oosterom & Strackee 1983). */
static double solid_angle(const bvh_tri *t, amp_vec3 p)
{
    amp_vec3 a = amp_v3_sub(t->p[0], p), b = amp_v3_sub(t->p[1], p), c = amp_v3_sub(t->p[2], p);
    double la = amp_v3_len(a), lb = amp_v3_len(b), lc = amp_v3_len(c);
    double num = amp_v3_dot(a, amp_v3_cross(b, c));
    double den = la * lb * lc + amp_v3_dot(a, b) * lc + amp_v3_dot(b, c) * la + amp_v3_dot(c, a) * lb;
    return 2.0 * atan2(num, den);
}

double amp_bvh_winding_exact(const amp_bvh *b, amp_vec3 p)
{
    double s = 0.0;
    size_t i;
    for (i = 0; i < b->ntris; i++)
        s += solid_angle(&b->tris[i], p);
    return s / (4.0 * AMP_PI);
}

double amp_bvh_winding(const amp_bvh *b, amp_vec3 p)
{
    uint32_t stack[STACK_SIZE];
    int sp = 0;
    double s = 0.0;
    stack[sp++] = 0;
    while (sp > 0) {
        const bvh_node *nd = &b->nodes[stack[--sp]];
        amp_vec3 r = amp_v3_sub(nd->cent, p);
        double d2 = amp_v3_len2(r);
        if (d2 > BETA * BETA * nd->radius * nd->radius) {
            /* far field: solid angle of a small patch ≈ A·r / |r|^3 (dipole term) */
            s += amp_v3_dot(nd->area, r) / (d2 * sqrt(d2));
        } else if (nd->count) {
            uint32_t i;
            for (i = nd->first; i < nd->first + nd->count; i++)
                s += solid_angle(&b->tris[i], p);
        } else {
            stack[sp++] = nd->left;
            stack[sp++] = nd->right;
        }
    }
    return s / (4.0 * AMP_PI);
}

/* ------------------------------------------------ winding number by a ray */

/*
 * Six ray directions, one per side of the box, each tilted off its axis by irrational-looking amounts so that
 * the grid points and axis-aligned faces of a CAD part do not line up with them. Unit length.
 */
static const double RAY_DIRS[6][3] = {
    {0.99982, 0.01730, 0.00815},  {-0.99982, 0.00815, -0.01730}, {0.01151, 0.99980, 0.01629},
    {-0.01629, -0.99980, 0.01151}, {0.01366, 0.00922, 0.99986},  {0.00922, -0.01366, -0.99986},
};

/* Smallest barycentric coordinate of a crossing that proves it passes through the inside of its triangle. */
#define RAY_MARGIN 1e-9

/*
 * The signed count of the surface crossings of the ray o + t d, t > 0: +1 where it leaves through a face
 * (d along the oriented normal), -1 where it enters. Returns 0 when the count proves nothing: the ray meets
 * an edge or a vertex (a crossing might be counted twice or not at all) or o lies on the surface.
 */
static int ray_count(const amp_bvh *b, amp_vec3 o, amp_vec3 d, int *w)
{
    uint32_t stack[STACK_SIZE];
    int sp = 0, sum = 0;
    amp_vec3 inv = inv_dir(d);
    double tmin = 1e-9 * (1.0 + amp_v3_len(o));
    stack[sp++] = 0;
    while (sp > 0) {
        const bvh_node *nd = &b->nodes[stack[--sp]];
        if (!ray_box(nd->box, o, inv, HUGE_VAL))
            continue;
        if (nd->count) {
            uint32_t i;
            for (i = nd->first; i < nd->first + nd->count; i++) {
                const bvh_tri *t = &b->tris[i];
                double s, u, v;
                amp_vec3 n;
                if (!ray_tri(t, o, d, HUGE_VAL, &s, &u, &v))
                    continue;
                if (s <= tmin || u < RAY_MARGIN || v < RAY_MARGIN || 1.0 - u - v < RAY_MARGIN)
                    return 0;
                n = amp_v3_cross(amp_v3_sub(t->p[1], t->p[0]), amp_v3_sub(t->p[2], t->p[0]));
                sum += amp_v3_dot(n, d) > 0 ? 1 : -1;
            }
        } else {
            stack[sp++] = nd->left;
            stack[sp++] = nd->right;
        }
    }
    *w = sum;
    return 1;
}

/*
 * The winding number at @p p. On a closed, consistently oriented mesh it is an integer off the surface, the
 * signed crossing count of any ray from p: one walk down the tree, where the generalised winding number
 * evaluates a solid angle per near triangle (on a coarse mesh, nearly all of them). An open mesh closed by
 * its caps (bvh_cap.c) is such a surface too: the count over mesh and caps, less the caps' solid angles. The
 * ray leaves through the nearest side of the box; when it proves nothing (see ray_count) the next direction
 * is tried, and after the sixth, or on a mesh left uncapped, the generalised winding number decides.
 */
static double winding_of(const amp_bvh *b, amp_vec3 p)
{
    double side[6];
    int k, first = 0, w, wc = 0;
    if (!(b->closed || b->capped) || !amp_v3_finite(p))
        return amp_bvh_winding(b, p);
    side[0] = b->bbox.max.x - p.x;
    side[1] = p.x - b->bbox.min.x;
    side[2] = b->bbox.max.y - p.y;
    side[3] = p.y - b->bbox.min.y;
    side[4] = b->bbox.max.z - p.z;
    side[5] = p.z - b->bbox.min.z;
    for (k = 1; k < 6; k++)
        if (side[k] < side[first])
            first = k;
    for (k = 0; k < 6; k++) {
        const double *d = RAY_DIRS[(first + k) % 6];
        amp_vec3 dir = amp_v3(d[0], d[1], d[2]);
        if (ray_count(b, p, dir, &w) && (!b->cap || ray_count(b->cap, p, dir, &wc)))
            return b->cap ? (double)(w + wc) - amp_bvh_winding(b->cap, p) : (double)w;
    }
    return amp_bvh_winding(b, p);
}

int amp_bvh_inside(const amp_bvh *b, amp_vec3 p) { return winding_of(b, p) >= 0.5; }
double amp_bvh_inside_winding(const amp_bvh *b, amp_vec3 p) { return winding_of(b, p); }

/* --------------------------------------------------------------- clipping */

typedef struct piece {
    const amp_allocator *alloc;
    amp_pvert *v;
    size_t n, cap;
    double len;
} piece;

static amp_status piece_push(piece *pc, amp_vec3 p, double r, amp_error *err)
{
    void *q = pc->v;
    if (pc->n > 0) {
        double l = amp_v3_dist(pc->v[pc->n - 1].p, p);
        if (l == 0.0)
            return AMP_OK; /* the cut point equals the vertex: keep one */
        pc->len += l;
    }
    if (amp_grow(pc->alloc, &q, &pc->cap, pc->n + 1, sizeof *pc->v) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory clipping a polyline");
    pc->v = q;
    pc->v[pc->n].p = p;
    pc->v[pc->n].r = r;
    pc->n++;
    return AMP_OK;
}

static amp_status piece_flush(piece *pc, double min_len, amp_role role, amp_pathset *out, amp_error *err)
{
    amp_status st = AMP_OK;
    if (pc->n >= 2 && pc->len >= min_len && pc->len > 0)
        st = amp_pathset_add(out, role, pc->v, pc->n, err);
    pc->n = 0;
    pc->len = 0.0;
    return st;
}

/* The clipper's state along one polyline: the piece being built and whether it is open. */
typedef struct clipper {
    piece pc;
    int open;
    double min_len;
    amp_role role;
    amp_pathset *out;
    int have_end, have_start; /* open meshes: in_end holds the state at the last segment's end vertex */
    int in_end, in_start;     /* (measured once: it is the next segment's start) */
} clipper;

/* The stretch [s0, s1] of segment a + t d (radii ra .. rb) is inside (@p in) or not: extend or start the
 * open piece, or end it. */
static amp_status clip_run(clipper *cl, int in, amp_vec3 a, amp_vec3 d, double ra, double rb, double s0, double s1,
                           amp_error *err)
{
    amp_status st = AMP_OK;
    if (!in) {
        if (cl->open) {
            cl->open = 0;
            return piece_flush(&cl->pc, cl->min_len, cl->role, cl->out, err);
        }
        return AMP_OK;
    }
    if (!cl->open) {
        st = piece_push(&cl->pc, s0 == 0.0 ? a : amp_v3_madd(a, d, s0), ra + s0 * (rb - ra), err);
        cl->open = 1;
    }
    if (st == AMP_OK)
        st = piece_push(&cl->pc, s1 == 1.0 ? amp_v3_add(a, d) : amp_v3_madd(a, d, s1), ra + s1 * (rb - ra), err);
    return st;
}

/* Where between t_in (inside) and t_out (outside) segment a + t d crosses winding 1/2 (open meshes: the
 * winding number changes continuously near a hole), to a millionth of the segment: the last point found
 * inside, so that the piece kept ends where the winding number says inside (a check of its vertices agrees). */
static double half_crossing(const amp_bvh *b, amp_vec3 a, amp_vec3 d, double t_in, double t_out)
{
    int k;
    for (k = 0; k < 20; k++) {
        double m = 0.5 * (t_in + t_out);
        if (winding_of(b, amp_v3_madd(a, d, m)) >= 0.5)
            t_in = m;
        else
            t_out = m;
    }
    return t_in;
}

/* One stretch between surface crossings, classified by its middle; on an open mesh also by its ends that are
 * polyline vertices (no surface there), split where the winding number crosses 1/2 on the way, so that no
 * kept vertex lies where the winding number says outside. */
static amp_status clip_stretch(const amp_bvh *b, clipper *cl, amp_vec3 a, amp_vec3 d, double ra, double rb, double s0,
                               double s1, int end0, int end1, double *wlast, amp_error *err)
{
    double tm = 0.5 * (s0 + s1), c0 = s0, c1 = s1;
    int in, in0, in1;
    amp_status st = AMP_OK;
    *wlast = winding_of(b, amp_v3_madd(a, d, tm));
    in = *wlast >= 0.5;
    if (b->closed || (!end0 && !end1))
        return clip_run(cl, in, a, d, ra, rb, s0, s1, err);
    in0 = !end0 ? in : cl->have_start ? cl->in_start : winding_of(b, amp_v3_madd(a, d, s0)) >= 0.5;
    in1 = end1 ? winding_of(b, amp_v3_madd(a, d, s1)) >= 0.5 : in;
    if (end1) {
        cl->in_end = in1;
        cl->have_end = 1;
    }
    if (in0 != in)
        c0 = in ? half_crossing(b, a, d, tm, s0) : half_crossing(b, a, d, s0, tm);
    if (in1 != in)
        c1 = in ? half_crossing(b, a, d, tm, s1) : half_crossing(b, a, d, s1, tm);
    if (c0 > s0)
        st = clip_run(cl, in0, a, d, ra, rb, s0, c0, err);
    if (st == AMP_OK)
        st = clip_run(cl, in, a, d, ra, rb, c0, c1, err);
    if (st == AMP_OK && c1 < s1)
        st = clip_run(cl, in1, a, d, ra, rb, c1, s1, err);
    return st;
}

amp_status amp_bvh_clip_polyline(const amp_bvh *b, const amp_pvert *v, size_t n, double min_len, amp_role role,
                                 amp_pathset *out, amp_error *err)
{
    clipper cl;
    size_t i;
    int known = 0, skipped = 0;
    double wlast = 0.0;
    amp_status st = AMP_OK;
    if (!b || !out || (n > 0 && !v))
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_bvh_clip_polyline: NULL argument");
    if (!isfinite(min_len) || min_len < 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_bvh_clip_polyline: min_len must be finite and >= 0");
    for (i = 0; i < n; i++)
        if (!amp_v3_finite(v[i].p) || !isfinite(v[i].r))
            return amp_fail(err, AMP_ERR_ARG, 0, "amp_bvh_clip_polyline: vertex %lu is not finite", (unsigned long)i);
    memset(&cl, 0, sizeof cl);
    cl.pc.alloc = b->alloc;
    cl.min_len = min_len;
    cl.role = role;
    cl.out = out;
    for (i = 0; i + 1 < n && st == AMP_OK; i++) {
        amp_vec3 a = v[i].p, c = v[i + 1].p, d = amp_v3_sub(c, a);
        amp_bvh_hit *h = NULL;
        size_t nh = 0, k;
        double s0 = 0.0;
        if (amp_v3_len2(d) == 0.0)
            continue;
        cl.have_start = cl.have_end; /* this segment starts where the last one ended */
        cl.in_start = cl.in_end;
        cl.have_end = 0;
        st = amp_bvh_ray_all(b, a, d, 1.0, &h, &nh, err);
        if (st != AMP_OK)
            break;
        /*
         * Without a crossing the winding number of a closed mesh keeps its
         * value: while the last value was clearly 0 or 1, keep the state and
         * re-check every 8th segment. An open mesh's changes continuously
         * near its holes: every segment is looked at, ends included.
         */
        if (nh == 0 && b->closed && known && fabs(wlast - 0.5) > 0.45 && ++skipped < 8) {
            if (cl.open)
                st = piece_push(&cl.pc, c, v[i + 1].r, err);
            continue;
        }
        skipped = 0;
        /* breakpoints 0 < t_1 <= ... < 1, then one classification per sub-segment */
        for (k = 0; k <= nh && st == AMP_OK; k++) {
            double s1 = k < nh ? h[k].t : 1.0;
            if (s1 > 1.0)
                s1 = 1.0;
            if (s1 - s0 <= 1e-12)
                continue; /* a duplicate hit on a shared edge, or a hit at a vertex */
            st = clip_stretch(b, &cl, a, d, v[i].r, v[i + 1].r, s0, s1, s0 == 0.0, k == nh, &wlast, err);
            known = 1;
            s0 = s1;
        }
        amp_bvh_hits_free(b, h);
    }
    if (st == AMP_OK && cl.open)
        st = piece_flush(&cl.pc, min_len, role, out, err);
    amp_free(b->alloc, cl.pc.v);
    return st;
}
