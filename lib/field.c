/*
 * Direction-field covering of a mesh ([P1 §4.2]): the iso-curves of a field
 * F(u, v, w) in one direction, sampled on a grid or honeycomb of the other
 * two parameters at a spacing in millimetres, clipped to the mesh; and the
 * coverage gap measured by sampling the solid.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/cover.h"
#include "ampath/field.h"
#include "ampath/spline.h"
#include "field_internal.h"


/* ------------------------------------------------------------ built-ins */

/* helix-square: the docs/interfaces.md §4 helix (radius 20, pitch 40, z0 = 5π/√(π²+1)) with a 12 mm square section. */
static amp_status eval_helix_square(const amp_field *f, const double uvw[3], amp_vec3 *out, amp_error *err)
{
    const double R = 20, P = 40, k = P / (2 * AMP_PI), len = sqrt(R * R + k * k), z0 = 5 * 2 * AMP_PI * R / (2 * AMP_PI * len);
    double w = 2 * AMP_PI * uvw[2], a = f->p[0] * (uvw[0] - 0.5), b = f->p[0] * (uvw[1] - 0.5);
    /* Frenet frame: N towards the axis, B = T x N, both normal to c'(t) (as in lib/mesh_models.c) */
    amp_vec3 c = amp_v3(R * cos(w), R * sin(w), z0 + P * uvw[2]);
    amp_vec3 n = amp_v3(-cos(w), -sin(w), 0), bb = amp_v3(k * sin(w) / len, -k * cos(w) / len, R / len);
    (void)err;
    *out = amp_v3_add(c, amp_v3_add(amp_v3_scale(n, a), amp_v3_scale(bb, b)));
    return AMP_OK;
}

/* box: x = lerp(xmin, xmax, w) along the curve, (u, v) across y and z. */
static amp_status eval_box(const amp_field *f, const double uvw[3], amp_vec3 *out, amp_error *err)
{
    (void)err;
    *out = amp_v3(f->p[0] + uvw[2] * (f->p[3] - f->p[0]), f->p[1] + uvw[0] * (f->p[4] - f->p[1]),
                  f->p[2] + uvw[1] * (f->p[5] - f->p[2]));
    return AMP_OK;
}

/* The box field once its lattice is centred (amp_field_cover): the same map. */
static amp_status eval_box_centred(const amp_field *f, const double uvw[3], amp_vec3 *out, amp_error *err)
{
    return eval_box(f, uvw, out, err);
}

/* sweep: C(w) + u N(w) + v B(w), w the arc length along the spine (mm), straight beyond the ends. */
static amp_status eval_sweep(const amp_field *f, const double uvw[3], amp_vec3 *out, amp_error *err)
{
    const amp_sweep *sw = f->user;
    double w = uvw[2], L = sw->s[sw->n - 1];
    amp_vec3 c, t, n;
    (void)err;
    if (w <= 0 || w >= L) {
        size_t e = w <= 0 ? 0 : sw->n - 1;
        c = amp_v3_add(sw->p[e], amp_v3_scale(sw->t[e], w <= 0 ? w : w - L));
        t = sw->t[e];
        n = sw->nrm[e];
    } else {
        size_t lo = 0, hi = sw->n - 1;
        double a;
        while (hi - lo > 1) {
            size_t mid = (lo + hi) / 2;
            if (sw->s[mid] <= w)
                lo = mid;
            else
                hi = mid;
        }
        a = (w - sw->s[lo]) / (sw->s[hi] - sw->s[lo]);
        c = amp_v3_lerp(sw->p[lo], sw->p[hi], a);
        t = amp_v3_normalize(amp_v3_lerp(sw->t[lo], sw->t[hi], a));
        n = amp_v3_lerp(sw->nrm[lo], sw->nrm[hi], a);
        n = amp_v3_normalize(amp_v3_sub(n, amp_v3_scale(t, amp_v3_dot(n, t))));
    }
    *out = amp_v3_add(c, amp_v3_add(amp_v3_scale(n, uvw[0]), amp_v3_scale(amp_v3_cross(t, n), uvw[1])));
    return AMP_OK;
}

amp_status amp_field_sweep(amp_field *f, amp_sweep *sw, const amp_vec3 *pts, size_t n, double side, amp_error *err)
{
    double lo[3], hi[3];
    amp_vec3 d0;
    size_t i;
    if (!f || !sw || !pts || n < 2 || n > AMP_SWEEP_MAX || !(side > 0) || !isfinite(side))
        return amp_fail(err, AMP_ERR_ARG, 0, "sweep: need 2..%d spine points and a positive side", AMP_SWEEP_MAX);
    sw->n = n;
    sw->s[0] = 0;
    for (i = 0; i < n; i++) {
        if (!isfinite(pts[i].x) || !isfinite(pts[i].y) || !isfinite(pts[i].z))
            return amp_fail(err, AMP_ERR_ARG, 0, "sweep: spine point %lu is not finite", (unsigned long)i);
        sw->p[i] = pts[i];
        if (i > 0) {
            double l = amp_v3_dist(pts[i - 1], pts[i]);
            if (!(l > 1e-6))
                return amp_fail(err, AMP_ERR_GEOMETRY, 0, "sweep: spine segment %lu is shorter than 1e-6 mm",
                                (unsigned long)(i - 1));
            sw->s[i] = sw->s[i - 1] + l;
        }
    }
    for (i = 0; i < n; i++) {
        amp_vec3 a = amp_v3_normalize(amp_v3_sub(sw->p[i > 0 ? i : 1], sw->p[i > 0 ? i - 1 : 0]));
        amp_vec3 b = amp_v3_normalize(amp_v3_sub(sw->p[i + 1 < n ? i + 1 : n - 1], sw->p[i + 1 < n ? i : n - 2]));
        if (amp_v3_dot(a, b) < -0.985)
            return amp_fail(err, AMP_ERR_GEOMETRY, 0, "sweep: the spine turns back on itself at point %lu",
                            (unsigned long)i);
        sw->t[i] = amp_v3_normalize(amp_v3_add(a, b));
    }
    /* any normal to start with, then the double-reflection rotation-minimizing frame (Wang et al. 2008) */
    d0 = fabs(sw->t[0].x) < 0.9 ? amp_v3(1, 0, 0) : amp_v3(0, 1, 0);
    sw->nrm[0] = amp_v3_normalize(amp_v3_sub(d0, amp_v3_scale(sw->t[0], amp_v3_dot(d0, sw->t[0]))));
    for (i = 0; i + 1 < n; i++) {
        amp_vec3 v1 = amp_v3_sub(sw->p[i + 1], sw->p[i]), rl, tl, v2;
        double c1 = amp_v3_dot(v1, v1), c2;
        rl = amp_v3_sub(sw->nrm[i], amp_v3_scale(v1, 2 / c1 * amp_v3_dot(v1, sw->nrm[i])));
        tl = amp_v3_sub(sw->t[i], amp_v3_scale(v1, 2 / c1 * amp_v3_dot(v1, sw->t[i])));
        v2 = amp_v3_sub(sw->t[i + 1], tl);
        c2 = amp_v3_dot(v2, v2);
        sw->nrm[i + 1] = c2 > 1e-18 ? amp_v3_sub(rl, amp_v3_scale(v2, 2 / c2 * amp_v3_dot(v2, rl))) : rl;
        sw->nrm[i + 1] = amp_v3_normalize(sw->nrm[i + 1]);
    }
    lo[0] = lo[1] = -side / 2;
    hi[0] = hi[1] = side / 2;
    lo[2] = -side / 2;
    hi[2] = sw->s[n - 1] + side / 2;
    return amp_field_custom(f, eval_sweep, sw, lo, hi, 2, err);
}

static const char *const field_names[] = {"helix-square", "box", NULL};

const char *const *amp_field_names(void) { return field_names; }

amp_status amp_field_custom(amp_field *f, amp_field_eval_fn eval, const void *user, const double lo[3],
                            const double hi[3], int dir, amp_error *err)
{
    int d;
    if (!f || !eval || !lo || !hi || dir < 0 || dir > 2)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_field_custom: bad argument");
    memset(f, 0, sizeof *f);
    for (d = 0; d < 3; d++) {
        if (!(lo[d] < hi[d]) || !isfinite(lo[d]) || !isfinite(hi[d]))
            return amp_fail(err, AMP_ERR_ARG, 0, "field domain of direction %d is empty or not finite", d);
        f->lo[d] = lo[d];
        f->hi[d] = hi[d];
    }
    f->eval = eval;
    f->user = user;
    f->dir = dir;
    return AMP_OK;
}

amp_status amp_field_builtin(amp_field *f, const char *name, amp_box3 box, amp_error *err)
{
    static const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    amp_status st;
    if (!f || !name)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_field_builtin: NULL argument");
    if (strcmp(name, "helix-square") == 0) {
        st = amp_field_custom(f, eval_helix_square, NULL, lo, hi, 2, err);
        /* w slightly beyond [0, 1]: the curves cross the helix end caps rather than end on them */
        f->lo[2] = -0.02;
        f->hi[2] = 1.02;
        f->p[0] = 12.0;
        return st;
    }
    if (strcmp(name, "box") == 0) {
        if (amp_box3_is_empty(box) || !amp_v3_finite(box.min) || !amp_v3_finite(box.max))
            return amp_fail(err, AMP_ERR_ARG, 0, "field 'box' needs the mesh's bounding box");
        /* the curves run 1 mm beyond the part; across them, amp_field_cover centres the lattice on the box */
        box.min.x -= 1.0;
        box.max.x += 1.0;
        st = amp_field_custom(f, eval_box, NULL, lo, hi, 2, err);
        f->p[0] = box.min.x;
        f->p[1] = box.min.y;
        f->p[2] = box.min.z;
        f->p[3] = box.max.x;
        f->p[4] = box.max.y;
        f->p[5] = box.max.z;
        return st;
    }
    return amp_fail(err, AMP_ERR_ARG, 0, "unknown field '%s' (helix-square, box)", name);
}

/* A trivariate spline as a field: its parameter box, curves along dir. */
static amp_status eval_spline(const amp_field *f, const double uvw[3], amp_vec3 *out, amp_error *err)
{
    return amp_spline_eval((const amp_spline *)f->user, uvw, out, err);
}

amp_status amp_field_from_spline(amp_field *f, const amp_spline *s, int dir, amp_error *err)
{
    double lo[3], hi[3];
    int d;
    if (!f || !s)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_field_from_spline: NULL argument");
    if (s->dim != 3)
        return amp_fail(err, AMP_ERR_ARG, 0, "a direction field must be a trivariate (this spline has %d directions)",
                        s->dim);
    for (d = 0; d < 3; d++)
        amp_spline_domain(s, d, &lo[d], &hi[d]);
    if (dir == AMP_FIELD_AUTO) {
        double sl[3], len[3];
        amp_status st = amp_trivariate_slopes(s, sl, err);
        if (st != AMP_OK)
            return st;
        dir = 2;
        len[2] = amp_spline_polygon_length_bound(s, 2, NULL);
        /* the most level curves (Def. 5.1 cuts only climbing ones); of level ones the longest (fewer paths:
         * the vase through its wall, u, 19,661 paths; round it, v, 4,998) */
        for (d = 0; d < 2; d++) {
            len[d] = amp_spline_polygon_length_bound(s, d, NULL);
            if (sl[d] < sl[dir] - 1e-6 || (fabs(sl[d] - sl[dir]) <= 1e-6 && len[d] > len[dir]))
                dir = d;
        }
    }
    return amp_field_custom(f, eval_spline, s, lo, hi, dir, err);
}

void amp_field_opts_default(amp_field_opts *o)
{
    o->spacing = 1.0;
    o->pattern = AMP_PATTERN_GRID;
    o->step = 0;
    o->min_len = -1;
    o->radius = 0;
    o->shells = 0;
    o->within = NULL;
    o->without = NULL;
    o->nwithout = 0;
    o->progress = NULL;
    o->progress_user = NULL;
}

/* ------------------------------------------------------------- covering */

/* Parameters (a, b, c) = (across 1, across 2, along) mapped to (u, v, w) by the field's curve direction. */
void amp_field_to_uvw(const amp_field *f, double a, double b, double c, double uvw[3])
{
    int da = (f->dir + 1) % 3, db = (f->dir + 2) % 3;
    uvw[da] = f->lo[da] + a * (f->hi[da] - f->lo[da]);
    uvw[db] = f->lo[db] + b * (f->hi[db] - f->lo[db]);
    uvw[f->dir] = f->lo[f->dir] + c * (f->hi[f->dir] - f->lo[f->dir]);
}

/*
 * Largest length (mm) of an iso-curve along parameter @p which (0 = a, 1 = b,
 * 2 = c) over a 5 x 5 set of positions of the two others, each curve measured
 * as a polyline of @p nseg segments.
 */
static amp_status max_iso_length(const amp_field *f, int which, int nseg, double *out, amp_error *err)
{
    int i, j, k;
    double best = 0;
    for (i = 0; i < 5; i++)
        for (j = 0; j < 5; j++) {
            double len = 0, x = i / 4.0, y = j / 4.0, uvw[3];
            amp_vec3 prev = amp_v3(0, 0, 0), p;
            for (k = 0; k <= nseg; k++) {
                double t = (double)k / nseg;
                amp_status st;
                if (which == 0)
                    amp_field_to_uvw(f, t, x, y, uvw);
                else if (which == 1)
                    amp_field_to_uvw(f, x, t, y, uvw);
                else
                    amp_field_to_uvw(f, x, y, t, uvw);
                if ((st = f->eval(f, uvw, &p, err)) != AMP_OK)
                    return st;
                if (!amp_v3_finite(p))
                    return amp_fail(err, AMP_ERR_GEOMETRY, 0, "field value is not finite");
                if (k > 0)
                    len += amp_v3_dist(prev, p);
                prev = p;
            }
            best = fmax(best, len);
        }
    *out = best;
    return AMP_OK;
}

amp_status amp_field_curve(const amp_field *f, double a, double b, size_t nc, double r, amp_pvert *curve,
                           double *len, amp_error *err)
{
    size_t k;
    amp_status st = AMP_OK;
    for (k = 0; k <= nc && st == AMP_OK; k++) {
        double uvw[3];
        amp_field_to_uvw(f, a, b, (double)k / (double)nc, uvw);
        st = f->eval(f, uvw, &curve[k].p, err);
        curve[k].r = r;
        if (k > 0 && len)
            *len += amp_v3_dist(curve[k - 1].p, curve[k].p);
    }
    return st;
}

/* ------------------------------------------------ regions (several fields) */

/* Is p in the part of the solid this field covers: inside the mesh, inside `within` (if any), in no `without`? */
int amp_field_member(const amp_bvh *b, const amp_field_opts *o, amp_vec3 p)
{
    size_t i;
    if (!amp_bvh_inside(b, p) || (o->within && !amp_bvh_inside(o->within, p)))
        return 0;
    for (i = 0; i < o->nwithout; i++)
        if (amp_bvh_inside(o->without[i], p))
            return 0;
    return 1;
}

static int has_regions(const amp_field_opts *o) { return o->within != NULL || o->nwithout > 0; }

/* Emit the member runs of one clipped piece: sampled every 0.25 mm, each boundary found by bisection. */
static amp_status keep_member_runs(const amp_bvh *b, const amp_field_opts *o, const amp_pvert *v, size_t n,
                                   double min_len, amp_pathset *out, amp_error *err)
{
    amp_pvert *run = NULL;
    size_t cap = 0, m = 0, k;
    double len = 0.0;
    amp_status st = AMP_OK;
    int prev = n ? amp_field_member(b, o, v[0].p) : 0;
    if (prev && amp_grow(out->alloc, (void **)&run, &cap, 1, sizeof *run) == AMP_OK)
        run[m++] = v[0];
    for (k = 0; st == AMP_OK && k + 1 < n; k++) {
        double sl = amp_v3_dist(v[k].p, v[k + 1].p), t0 = 0.0;
        size_t ns = (size_t)ceil(sl / 0.25), j;
        for (j = 1; st == AMP_OK && j <= (ns ? ns : 1); j++) {
            double t1 = ns ? (double)j / (double)ns : 1.0, a = t0, c = t1;
            amp_pvert x;
            int cur = amp_field_member(b, o, amp_v3_lerp(v[k].p, v[k + 1].p, t1)), it;
            if (cur != prev) /* bisect the crossing between t0 and t1 */
                for (it = 0; it < 20; it++) {
                    double mid = 0.5 * (a + c);
                    if (amp_field_member(b, o, amp_v3_lerp(v[k].p, v[k + 1].p, mid)) == prev)
                        a = mid;
                    else
                        c = mid;
                }
            x.p = amp_v3_lerp(v[k].p, v[k + 1].p, cur != prev ? (prev ? a : c) : t1);
            x.r = v[k].r + (cur != prev ? (prev ? a : c) : t1) * (v[k + 1].r - v[k].r);
            if (prev || cur) {
                if (amp_grow(out->alloc, (void **)&run, &cap, m + 1, sizeof *run) != AMP_OK) {
                    st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for field curves");
                    break;
                }
                if (j == (ns ? ns : 1) || cur != prev) { /* interior samples of a straight segment need no vertex */
                    if (m)
                        len += amp_v3_dist(run[m - 1].p, x.p);
                    run[m++] = x;
                }
            }
            if (prev && !cur) {
                if (m > 1 && len >= min_len)
                    st = amp_pathset_add(out, AMP_ROLE_OBJECT, run, m, err);
                m = 0;
                len = 0.0;
            }
            prev = cur;
            t0 = t1;
        }
    }
    if (st == AMP_OK && prev && m > 1 && len >= min_len)
        st = amp_pathset_add(out, AMP_ROLE_OBJECT, run, m, err);
    amp_free(out->alloc, run);
    return st;
}

/* Clip a curve to the solid and, with regions, to this field's part of it. */
amp_status amp_field_clip(const amp_bvh *b, const amp_field_opts *o, const amp_pvert *v, size_t n, double min_len,
                          amp_pathset *out, amp_error *err)
{
    amp_pathset tmp;
    amp_status st;
    size_t i;
    if (!has_regions(o))
        return amp_bvh_clip_polyline(b, v, n, min_len, AMP_ROLE_OBJECT, out, err);
    amp_pathset_init(&tmp, out->alloc);
    st = amp_bvh_clip_polyline(b, v, n, 0.0, AMP_ROLE_OBJECT, &tmp, err);
    for (i = 0; st == AMP_OK && i < tmp.npaths; i++)
        st = keep_member_runs(b, o, amp_pathset_path_verts(&tmp, i), tmp.paths[i].n, min_len, out, err);
    amp_pathset_free(&tmp);
    return st;
}

/* ------------------------------------------- trivariate fields: Algorithm 1 */

/* A copy of @p s with parameter directions 0 and 1 exchanged (so that curves along u become curves along v). */
static amp_status swap_uv(const amp_spline *s, amp_spline *t, amp_error *err)
{
    int order[3];
    size_t count[3], i, j, k, m;
    amp_status st;
    order[0] = s->order[1];
    order[1] = s->order[0];
    order[2] = s->order[2];
    count[0] = s->count[1];
    count[1] = s->count[0];
    count[2] = s->count[2];
    if ((st = amp_spline_create(t, s->alloc, 3, order, count, s->rational, err)) != AMP_OK)
        return st;
    for (m = 0; m < count[0] + (size_t)order[0]; m++)
        t->knots[0][m] = s->knots[1][m];
    for (m = 0; m < count[1] + (size_t)order[1]; m++)
        t->knots[1][m] = s->knots[0][m];
    for (m = 0; m < count[2] + (size_t)order[2]; m++)
        t->knots[2][m] = s->knots[2][m];
    for (k = 0; k < count[2]; k++)
        for (j = 0; j < count[1]; j++)
            for (i = 0; i < count[0]; i++) {
                double w;
                amp_vec3 p = amp_spline_cp_get(s, amp_spline_index(s, j, i, k), &w);
                amp_spline_cp_set(t, amp_spline_index(t, i, j, k), p, w);
            }
    return AMP_OK;
}

/*
 * §4.2 step 1: a trivariate field is covered by Algorithm 1 and the adaptive
 * iso-curves (§4.1, cover.h) with eps = the pattern's covering radius, so the
 * bound holds for any parametrization of the field; the curves are then cut
 * to the mesh. cover.c makes surfaces across direction d and curves along
 * e1 = (d == 2 ? 1 : 2): curves along w use d = 0, along v d = 2, and along u
 * the field with u and v exchanged, d = 2.
 */
static amp_status cover_spline_field(const amp_spline *v, int dir, const amp_bvh *b, const amp_field_opts *o,
                                     double eps, double r, double min_len, amp_pathset *out, amp_field_stats *s,
                                     amp_error *err)
{
    amp_spline sw;
    amp_cover_opts co;
    amp_cover_stats cs;
    amp_pathset tmp;
    amp_status st = AMP_OK;
    size_t i, p0 = out->npaths;
    amp_spline_init(&sw);
    amp_pathset_init(&tmp, out->alloc);
    amp_cover_opts_default(&co);
    co.eps = eps;
    co.radius = r;
    co.dir = dir == 2 ? 0 : 2;
    co.progress = o->progress;
    co.progress_user = o->progress_user;
    if (dir == 0)
        st = swap_uv(v, &sw, err);
    if (st == AMP_OK)
        st = amp_cover_trivariate(dir == 0 ? &sw : v, &co, &tmp, &cs, err);
    for (i = 0; st == AMP_OK && i < tmp.npaths; i++)
        st = amp_field_clip(b, o, amp_pathset_path_verts(&tmp, i), tmp.paths[i].n, min_len, out, err);
    s->curves = cs.curves;
    s->length_before = cs.length;
    s->bound = eps;
    s->bound_met = st == AMP_OK && !cs.depth_limited;
    s->route = AMP_FIELD_ROUTE_ALGORITHM1;
    for (i = p0; i < out->npaths; i++)
        s->length_after += amp_path_length(out, i);
    s->pieces = out->npaths - p0;
    amp_spline_free(&sw);
    amp_pathset_free(&tmp);
    return st;
}

/* ------------------------------------- other fields: adaptive seeding in space */

/* Finest subdivision of a base cell of the adaptive lattice: 2^QDEPTH per side. */
#define QDEPTH 5
/* Sample points of a cell's bound: a (QS + 1)^2 grid over it, edges and centre included (QS even), corners not. */
#define QS 4

/* The curves of the adaptive lattice, hashed by their integer position (ia, ib) in units of 1/(n 2^QDEPTH). */
typedef struct qctx {
    const amp_field *f;
    const amp_bvh *b;
    const amp_field_opts *o;
    const amp_allocator *a;
    amp_error *err;
    size_t na, nb, ncs;    /* base cells across a and b; c samples of the bound */
    double target;         /* covering radius to meet, mm */
    uint64_t *key;         /* hash slots: key + 1 (0 = empty) */
    size_t *idx, hcap;     /* slot -> curve index */
    amp_vec3 *pts;         /* curve k: pts[k (ncs + 1) ..] */
    unsigned char *in;     /* inside the mesh, per point */
    uint64_t *ck;          /* curve k's key */
    size_t ncur, capcur;
    double worst;          /* largest cell bound among the leaves */
    size_t deep;           /* leaves stopped by QDEPTH (or maxcur) above the target */
    size_t maxcur;         /* most curves kept in memory */
    struct qsample *sc;    /* the bound's grid points met so far (open addressing, x = 0: empty) */
    size_t sccap, scn;
    amp_vec3 *sp;          /* their samples: ncs + 1 points per grid point, in order of arrival */
    unsigned char *sin;    /* and whether each is a member */
    size_t spcap;          /* grid points sp has room for */
    amp_vec3 *tp;          /* one grid point's samples when the table is full (ncs + 1) */
    unsigned char *tin;
} qctx;

/* A grid point of the cell bound: lattice coordinates in quarters of the finest cell (x + 1, y); its ncs + 1
 * c-samples and their membership start at sp[at], sin[at]. Neighbouring cells share their edges' points, and a
 * split cell half of its parent's: each one is evaluated and classified once, and looked up once per cell. */
typedef struct qsample {
    uint64_t x, y;
    size_t at;
} qsample;

#define QSAMPLE_MAX ((size_t)1 << 24) /* beyond this many samples, evaluate without keeping (about 0.4 GB) */

static size_t qs_slot(const qctx *q, uint64_t x, uint64_t y)
{
    uint64_t h = (x * 0x9E3779B97F4A7C15ULL) ^ (y * 0xC2B2AE3D27D4EB4FULL);
    size_t i = (size_t)(h >> 17) & (q->sccap - 1);
    while (q->sc[i].x && (q->sc[i].x != x || q->sc[i].y != y))
        i = (i + 1) & (q->sccap - 1);
    return i;
}

/* Room for one more grid point: the table doubled at half load, the samples grown; 0 when they may not grow
 * (then nothing more is kept). */
static int qs_room(qctx *q)
{
    qsample *old = q->sc, *nw;
    size_t oldcap = q->sccap, i, cap = oldcap ? 2 * oldcap : 1024, n = q->ncs + 1;
    if ((q->scn + 1) * n > QSAMPLE_MAX)
        return 0;
    if (q->scn + 1 > q->spcap) {
        size_t c = q->spcap ? 2 * q->spcap : 512;
        amp_vec3 *p = amp_realloc_array(q->a, q->sp, c * n, sizeof *p);
        unsigned char *in;
        if (!p)
            return 0;
        q->sp = p;
        if (!(in = amp_realloc_array(q->a, q->sin, c * n, 1)))
            return 0;
        q->sin = in;
        q->spcap = c;
    }
    if (q->sccap && 2 * (q->scn + 1) <= q->sccap)
        return 1;
    if (!(nw = amp_calloc(q->a, cap, sizeof *nw)))
        return 0;
    q->sc = nw;
    q->sccap = cap;
    for (i = 0; i < oldcap; i++)
        if (old[i].x)
            q->sc[qs_slot(q, old[i].x, old[i].y)] = old[i];
    amp_free(q->a, old);
    return 1;
}

static void q_uvw(const qctx *q, uint64_t ia, uint64_t ib, double c, double uvw[3])
{
    amp_field_to_uvw(q->f, (double)ia / (double)(q->na << QDEPTH), (double)ib / (double)(q->nb << QDEPTH), c, uvw);
}

static amp_status q_grow(qctx *q)
{
    size_t cap = q->capcur ? 2 * q->capcur : 256, h, k;
    amp_vec3 *p = amp_realloc_array(q->a, q->pts, cap * (q->ncs + 1), sizeof *p);
    unsigned char *in;
    uint64_t *ck;
    if (!p)
        return amp_fail(q->err, AMP_ERR_NOMEM, 0, "out of memory for field curves");
    q->pts = p;
    if (!(in = amp_realloc_array(q->a, q->in, cap * (q->ncs + 1), 1)))
        return amp_fail(q->err, AMP_ERR_NOMEM, 0, "out of memory for field curves");
    q->in = in;
    if (!(ck = amp_realloc_array(q->a, q->ck, cap, sizeof *ck)))
        return amp_fail(q->err, AMP_ERR_NOMEM, 0, "out of memory for field curves");
    q->ck = ck;
    q->capcur = cap;
    /* rehash into twice the curve capacity */
    amp_free(q->a, q->key);
    amp_free(q->a, q->idx);
    q->hcap = 2 * cap;
    q->key = amp_calloc(q->a, q->hcap, sizeof *q->key);
    q->idx = amp_calloc(q->a, q->hcap, sizeof *q->idx);
    if (!q->key || !q->idx)
        return amp_fail(q->err, AMP_ERR_NOMEM, 0, "out of memory for field curves");
    for (k = 0; k < q->ncur; k++) {
        for (h = (size_t)(q->ck[k] * 0x9E3779B97F4A7C15ULL >> 20) % q->hcap; q->key[h]; h = (h + 1) % q->hcap)
            ;
        q->key[h] = q->ck[k] + 1;
        q->idx[h] = k;
    }
    return AMP_OK;
}

/* The curve at (ia, ib): sampled at the ncs + 1 c-values of the bound, with inside flags. */
static amp_status q_curve(qctx *q, uint64_t ia, uint64_t ib, size_t *out)
{
    uint64_t key = ia << 32 | ib;
    size_t h, k;
    amp_status st;
    if (q->ncur + 1 > q->capcur / 2 + q->capcur / 4 || !q->capcur)
        if ((st = q_grow(q)) != AMP_OK)
            return st;
    for (h = (size_t)(key * 0x9E3779B97F4A7C15ULL >> 20) % q->hcap; q->key[h]; h = (h + 1) % q->hcap)
        if (q->key[h] == key + 1) {
            *out = q->idx[h];
            return AMP_OK;
        }
    q->key[h] = key + 1;
    q->idx[h] = q->ncur;
    q->ck[q->ncur] = key;
    for (k = 0; k <= q->ncs; k++) {
        double uvw[3];
        amp_vec3 *p = &q->pts[q->ncur * (q->ncs + 1) + k];
        q_uvw(q, ia, ib, (double)k / (double)q->ncs, uvw);
        if ((st = q->f->eval(q->f, uvw, p, q->err)) != AMP_OK)
            return st;
        q->in[q->ncur * (q->ncs + 1) + k] = (unsigned char)amp_field_member(q->b, q->o, *p);
    }
    *out = q->ncur++;
    return AMP_OK;
}

/*
 * The c-samples of grid point (i, j) of the cell (ia, ib, sa, sb) and their membership, from the table or
 * evaluated (and kept while there is room). The pointers hold until the next call.
 */
static amp_status q_samples(qctx *q, uint64_t ia, uint64_t ib, uint64_t sa, uint64_t sb, int i, int j,
                            const amp_vec3 **pts, const unsigned char **in)
{
    uint64_t X = QS * ia + sa * (uint64_t)i + 1, Y = QS * ib + sb * (uint64_t)j;
    size_t slot = 0, k, n = q->ncs + 1;
    amp_vec3 *p;
    unsigned char *m;
    amp_status st;
    if (q->sccap && q->sc[slot = qs_slot(q, X, Y)].x) {
        *pts = q->sp + q->sc[slot].at * n;
        *in = q->sin + q->sc[slot].at * n;
        return AMP_OK;
    }
    if (qs_room(q)) {
        qsample *e = &q->sc[qs_slot(q, X, Y)];
        e->x = X;
        e->y = Y;
        e->at = q->scn++;
        p = q->sp + e->at * n;
        m = q->sin + e->at * n;
    } else {
        if (!q->tp && (!(q->tp = amp_calloc(q->a, n, sizeof *q->tp)) || !(q->tin = amp_calloc(q->a, n, 1))))
            return amp_fail(q->err, AMP_ERR_NOMEM, 0, "out of memory for field curves");
        p = q->tp;
        m = q->tin;
    }
    for (k = 0; k < n; k++) {
        double uvw[3];
        /* the same lattice point gives the same uvw whichever cell asks (sa i / QS is exact) */
        amp_field_to_uvw(q->f, ((double)ia + (double)sa * i / QS) / (double)(q->na << QDEPTH),
                         ((double)ib + (double)sb * j / QS) / (double)(q->nb << QDEPTH), (double)k / (double)q->ncs,
                         uvw);
        if ((st = q->f->eval(q->f, uvw, &p[k], q->err)) != AMP_OK)
            return st;
        m[k] = (unsigned char)amp_field_member(q->b, q->o, p[k]);
    }
    *pts = p;
    *in = m;
    return AMP_OK;
}

/*
 * A grid point inside the solid where no candidate curve is inside at the same c (a sliver of the solid, thin
 * along the curves, between their samples): its distance to the nearest inside sample of a candidate at any c
 * still bounds its distance to printed material, where "infinitely far" made the finest cells fail the target.
 */
static double nearest_inside_any_c(const qctx *q, const size_t *cand, size_t nc, amp_vec3 x)
{
    size_t t, k, n = q->ncs + 1;
    double d = HUGE_VAL;
    for (t = 0; t < nc; t++)
        for (k = 0; k < n; k++)
            if (q->in[cand[t] * n + k])
                d = fmin(d, amp_v3_dist(x, q->pts[cand[t] * n + k]));
    return d;
}

/*
 * Bound of a cell: over the QS x QS grid points of the cell at every c-sample that lie
 * inside the mesh, the largest distance to the nearest candidate curve at the
 * same c (an upper bound on the distance to that curve), counting only
 * candidate points inside the mesh (the rest is clipped away). Candidates:
 * the cell's four corners and the 4 x 4 base-lattice curves around its base
 * cell (all of them are printed), so that a sliver of the solid next to the
 * surface is not refined for want of a corner inside it.
 */
static amp_status q_bound(qctx *q, uint64_t ia, uint64_t ib, uint64_t sa, uint64_t sb, double *bound)
{
    size_t cand[20], nc = 0, k, n = q->ncs + 1, t;
    uint64_t bi = ia >> QDEPTH, bj = ib >> QDEPTH, x, y;
    int i, j;
    amp_status st;
    *bound = 0.0;
    for (t = 0; t < 4; t++)
        if ((st = q_curve(q, ia + (t & 1 ? sa : 0), ib + (t & 2 ? sb : 0), &cand[nc++])) != AMP_OK)
            return st;
    if (sa < ((uint64_t)1 << QDEPTH) || sb < ((uint64_t)1 << QDEPTH))
        for (y = bj ? bj - 1 : 0; y <= bj + 2 && y <= q->nb; y++)
            for (x = bi ? bi - 1 : 0; x <= bi + 2 && x <= q->na; x++)
                if ((st = q_curve(q, x << QDEPTH, y << QDEPTH, &cand[nc++])) != AMP_OK)
                    return st;
    /* an edge longer than 2 target that may touch the solid: its middle is about half its length from both
     * curves, even where the grid points miss the solid (a field stretched within one cell) */
    for (k = 0; k <= q->ncs; k++)
        for (t = 0; t < 4; t++) {
            static const int e0[4] = {0, 2, 0, 1}, e1[4] = {1, 3, 2, 3};
            amp_vec3 p0 = q->pts[cand[e0[t]] * n + k], p1 = q->pts[cand[e1[t]] * n + k], mid;
            double len = amp_v3_dist(p0, p1);
            if (len <= 2.0 * q->target * (1 + 1e-9) || len / 2 <= *bound)
                continue;
            mid = amp_v3_lerp(p0, p1, 0.5);
            if (amp_field_member(q->b, q->o, mid) || amp_bvh_closest(q->b, mid, NULL, NULL) <= len / 2)
                *bound = len / 2;
        }
    for (j = 0; j <= QS; j++)
        for (i = 0; i <= QS; i++) {
            const amp_vec3 *x3 = NULL;
            const unsigned char *in = NULL;
            if ((i == 0 || i == QS) && (j == 0 || j == QS))
                continue; /* a corner: on its curve */
            if ((st = q_samples(q, ia, ib, sa, sb, i, j, &x3, &in)) != AMP_OK)
                return st;
            for (k = 0; k <= q->ncs; k++) {
                double d = HUGE_VAL;
                if (!in[k])
                    continue;
                for (t = 0; t < nc; t++)
                    if (q->in[cand[t] * n + k])
                        d = fmin(d, amp_v3_dist(x3[k], q->pts[cand[t] * n + k]));
                /* a grid point on the surface itself (a lattice plane through a face of a box) tests inside
                 * while every curve along that face tests outside: the solid next to it decides, not it */
                if (d == HUGE_VAL && amp_bvh_closest(q->b, x3[k], NULL, NULL) <= 1e-9 * (1.0 + amp_v3_len(x3[k])))
                    continue;
                if (d == HUGE_VAL)
                    d = nearest_inside_any_c(q, cand, nc, x3[k]);
                *bound = fmax(*bound, d);
            }
        }
    return AMP_OK;
}

/* Longest distance in space between the corner curves along a (which = 0) or b (1) over the c-samples. */
static double q_edge(qctx *q, uint64_t ia, uint64_t ib, uint64_t sa, uint64_t sb, int which)
{
    size_t c00, c10, c01, c11, k, n = q->ncs + 1;
    double m = 0.0;
    /* the four corners exist: q_bound made them */
    if (q_curve(q, ia, ib, &c00) != AMP_OK || q_curve(q, ia + sa, ib, &c10) != AMP_OK ||
        q_curve(q, ia, ib + sb, &c01) != AMP_OK || q_curve(q, ia + sa, ib + sb, &c11) != AMP_OK)
        return 0.0;
    for (k = 0; k < n; k++)
        m = fmax(m, which == 0 ? fmax(amp_v3_dist(q->pts[c00 * n + k], q->pts[c10 * n + k]),
                                      amp_v3_dist(q->pts[c01 * n + k], q->pts[c11 * n + k]))
                               : fmax(amp_v3_dist(q->pts[c00 * n + k], q->pts[c01 * n + k]),
                                      amp_v3_dist(q->pts[c10 * n + k], q->pts[c11 * n + k])));
    return m;
}

/*
 * Split a cell in two, across its longer side in space, while its bound
 * exceeds the target (adaptive seeding: curves where neighbours drift apart);
 * a split adds the two curves in the middle of that side's edges.
 */
static amp_status q_refine(qctx *q, uint64_t ia, uint64_t ib, uint64_t sa, uint64_t sb)
{
    double bound;
    amp_status st = q_bound(q, ia, ib, sa, sb, &bound);
    if (st != AMP_OK)
        return st;
    /* the half diagonal of a full cell is exactly the target; maxcur bounds the memory of a wild field */
    if ((sa > 1 || sb > 1) && bound > q->target * (1 + 1e-9) && q->ncur + 2 <= q->maxcur) {
        int along_a = sb == 1 || (sa > 1 && q_edge(q, ia, ib, sa, sb, 0) >= q_edge(q, ia, ib, sa, sb, 1));
        if (along_a) {
            if ((st = q_refine(q, ia, ib, sa / 2, sb)) == AMP_OK)
                st = q_refine(q, ia + sa / 2, ib, sa / 2, sb);
        } else if ((st = q_refine(q, ia, ib, sa, sb / 2)) == AMP_OK) {
            st = q_refine(q, ia, ib + sb / 2, sa, sb / 2);
        }
        return st;
    }
    q->worst = fmax(q->worst, bound);
    q->deep += bound > q->target * (1 + 1e-9);
    return AMP_OK;
}

static int key_cmp(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    /* rows of b, then a along the row */
    uint64_t ka = (a & 0xffffffffU) << 32 | a >> 32, kb = (b & 0xffffffffU) << 32 | b >> 32;
    return ka < kb ? -1 : ka > kb;
}

/* The adaptive lattice: base cells of at most S, refined where the cell bound exceeds the target. */
static amp_status cover_adaptive(const amp_field *f, const amp_bvh *b, const amp_field_opts *o, size_t na, size_t nb,
                                 size_t nc, double target, double r, double min_len, amp_pathset *out,
                                 amp_field_stats *s, amp_error *err)
{
    qctx q;
    size_t i, j, p0 = out->npaths;
    uint64_t *keys = NULL;
    amp_pvert *curve = NULL;
    amp_status st = AMP_OK;
    memset(&q, 0, sizeof q);
    q.f = f;
    q.b = b;
    q.o = o;
    q.a = out->alloc;
    q.err = err;
    q.na = na;
    q.nb = nb;
    q.ncs = nc < 64 ? nc : 64 + (nc - 64) / 4;
    q.target = target;
    q.maxcur = (na + 1) * (nb + 1) + 4000000 / (q.ncs + 1); /* inserted curves: about 100 MB of samples at most */
    for (j = 0; j < nb && st == AMP_OK; j++) {
        for (i = 0; i < na && st == AMP_OK; i++)
            st = q_refine(&q, (uint64_t)i << QDEPTH, (uint64_t)j << QDEPTH, (uint64_t)1 << QDEPTH,
                          (uint64_t)1 << QDEPTH);
        if (o->progress)
            o->progress(o->progress_user, 0.8 * (double)(j + 1) / (double)nb);
    }
    if (st == AMP_OK && (!(keys = amp_calloc(q.a, q.ncur + 1, sizeof *keys)) ||
                         !(curve = amp_calloc(q.a, nc + 1, sizeof *curve))))
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for field curves");
    if (st == AMP_OK) {
        memcpy(keys, q.ck, q.ncur * sizeof *keys);
        qsort(keys, q.ncur, sizeof *keys, key_cmp);
    }
    for (i = 0; st == AMP_OK && i < q.ncur; i++) {
        st = amp_field_curve(f, (double)(keys[i] >> 32) / (double)(na << QDEPTH),
                             (double)(keys[i] & 0xffffffffU) / (double)(nb << QDEPTH), nc, r, curve, &s->length_before,
                             err);
        if (st == AMP_OK)
            st = amp_field_clip(b, o, curve, nc + 1, min_len, out, err);
        s->curves++;
    }
    if (st == AMP_OK) {
        /* features finer than the cell samples: the field's curves through the measured gaps */
        amp_field_seeds sd;
        sd.pts = q.pts;
        sd.key = q.ck;
        sd.ncur = q.ncur;
        sd.ncs = q.ncs;
        sd.da = (double)(na << QDEPTH);
        sd.db = (double)(nb << QDEPTH);
        st = amp_field_fill_gaps(f, b, o, &sd, nc, target, r, min_len, out, &s->gap_curves, &s->gap_left, err);
    }
    s->bound = q.worst;
    s->bound_met = q.deep == 0;
    s->inserted = q.ncur - (na + 1) * (nb + 1);
    s->route = AMP_FIELD_ROUTE_ADAPTIVE;
    for (i = p0; i < out->npaths; i++)
        s->length_after += amp_path_length(out, i);
    s->pieces = out->npaths - p0;
    amp_free(q.a, keys);
    amp_free(q.a, curve);
    amp_free(q.a, q.key);
    amp_free(q.a, q.idx);
    amp_free(q.a, q.pts);
    amp_free(q.a, q.in);
    amp_free(q.a, q.ck);
    amp_free(q.a, q.sc);
    amp_free(q.a, q.sp);
    amp_free(q.a, q.sin);
    amp_free(q.a, q.tp);
    amp_free(q.a, q.tin);
    return st;
}

/* ------------------------------------------------- surface layer (shells) */

/*
 * Shell curves ([P1 §4.2], like a slicer's perimeters but along the field):
 * the lattice curves at corners (i/na, j/nb) that run within the band
 * [-S/2, S/2) of signed distance to the surface, shifted j S deeper for shell
 * j, are projected onto the surface offset inward by d_j = S/2 + j S (the
 * closest surface point moved d_j along the inward direction). A lattice
 * point lies in one band per normal line, so neighbouring shell curves are
 * about S apart along the surface and follow the field's direction projected
 * onto it. Runs of consecutive samples in the band whose projection is inside
 * the solid become paths (at least min_len long).
 */
static amp_status cover_shells(const amp_field *f, const amp_bvh *b, const amp_field_opts *o, size_t na, size_t nb,
                               size_t nc, double S, double r, int shells, double min_len, amp_pathset *out,
                               amp_field_stats *s, amp_error *err)
{
    amp_pvert *run = amp_calloc(out->alloc, nc + 1, sizeof *run);
    size_t i, j, k, p0 = out->npaths;
    int sh;
    amp_status st = AMP_OK;
    if (!run)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for shell curves");
    for (sh = 0; sh < shells && st == AMP_OK; sh++) {
        double d = 0.5 * S + sh * S, lo = -0.5 * S - sh * S, hi = 0.5 * S - sh * S;
        for (j = 0; j <= nb && st == AMP_OK; j++)
            for (i = 0; i <= na && st == AMP_OK; i++) {
                size_t n = 0;
                for (k = 0; k <= nc + 1 && st == AMP_OK; k++) {
                    amp_vec3 p, q, x;
                    double uvw[3], dist, sd, len = 0;
                    int ok = 0;
                    if (k <= nc) {
                        amp_field_to_uvw(f, (double)i / (double)na, (double)j / (double)nb, (double)k / (double)nc,
                                         uvw);
                        if ((st = f->eval(f, uvw, &p, err)) != AMP_OK)
                            break;
                        dist = amp_bvh_closest(b, p, &q, NULL);
                        sd = amp_bvh_inside(b, p) ? -dist : dist;
                        if (dist > 1e-9 && sd >= lo && sd < hi) {
                            /* inward direction: towards p from q when p is inside, away from p otherwise */
                            amp_vec3 in = amp_v3_scale(amp_v3_sub(p, q), (sd < 0 ? 1.0 : -1.0) / dist);
                            x = amp_v3_madd(q, in, d);
                            ok = amp_field_member(b, o, x) && amp_bvh_closest(b, x, NULL, NULL) >= 0.9 * d;
                        }
                    }
                    if (ok && (n == 0 || amp_v3_dist(run[n - 1].p, x) > 1e-6)) {
                        run[n].p = x;
                        run[n++].r = r;
                        continue;
                    }
                    if (ok)
                        continue;
                    {
                        size_t m;
                        for (m = 1; m < n; m++)
                            len += amp_v3_dist(run[m - 1].p, run[m].p);
                    }
                    if (n > 1 && len >= min_len)
                        st = amp_pathset_add(out, AMP_ROLE_OBJECT, run, n, err);
                    n = 0;
                }
            }
    }
    for (i = p0; i < out->npaths; i++) {
        s->shell_paths++;
        s->shell_length += amp_path_length(out, i);
    }
    amp_free(out->alloc, run);
    return st;
}

/* Curve k of the honeycomb as a seed of the gap rounds: its lattice position in half cells, and ncs + 1 samples
 * (the curve's own when ncs = nc; else @p curve, clipped and written already, is evaluated again at ncs). */
static amp_status uniform_seed(const amp_field *f, amp_field_seeds *sd, amp_vec3 *pts, uint64_t *key, size_t k,
                               uint64_t ia, uint64_t ib, amp_pvert *curve, size_t nc, amp_error *err)
{
    size_t i;
    amp_status st = AMP_OK;
    key[k] = ia << 32 | ib;
    if (sd->ncs != nc)
        st = amp_field_curve(f, (double)ia / sd->da, (double)ib / sd->db, sd->ncs, 0.0, curve, NULL, err);
    for (i = 0; st == AMP_OK && i <= sd->ncs; i++)
        pts[k * (sd->ncs + 1) + i] = curve[i].p;
    return st;
}

/* The plain lattice (honeycomb): curves at the cell centres of an na x nb pattern, then the field's curves
 * through the gaps that sampling the solid finds (as the adaptive route's last step): the lattice alone
 * leaves thin features uncovered (0.87 mm against the 0.58 mm covering radius on CGAL's bull at S = 1). */
static amp_status cover_uniform(const amp_field *f, const amp_bvh *b, const amp_field_opts *o, size_t na, size_t nb,
                                size_t nc, double target, double r, double min_len, amp_pathset *out,
                                amp_field_stats *stats, amp_error *err)
{
    amp_field_stats s = *stats;
    size_t j, i, p0, ncur = 0;
    amp_pvert *curve = NULL;
    amp_vec3 *pts;
    uint64_t *key;
    amp_field_seeds sd;
    amp_status st = AMP_OK;
    sd.ncs = nc < 64 ? nc : 64 + (nc - 64) / 4;
    sd.da = 2.0 * (double)na;
    sd.db = 2.0 * (double)nb;
    curve = amp_calloc(out->alloc, nc + 1, sizeof *curve);
    key = amp_calloc(out->alloc, (na + 1) * nb + 1, sizeof *key);
    pts = amp_calloc(out->alloc, ((na + 1) * nb + 1) * (sd.ncs + 1), sizeof *pts);
    if (!curve || !key || !pts) {
        amp_free(out->alloc, curve);
        amp_free(out->alloc, key);
        amp_free(out->alloc, pts);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for a covering curve");
    }
    p0 = out->npaths;
    for (j = 0; j < nb && st == AMP_OK; j++) {
        int odd = o->pattern == AMP_PATTERN_HEX && (j & 1);
        size_t count = na + (size_t)odd;
        for (i = 0; i < count && st == AMP_OK; i++) {
            /* cell centres; odd honeycomb rows are shifted by half a spacing (and gain one curve) */
            uint64_t ia = 2 * i + (odd ? 0 : 1), ib = 2 * j + 1;
            st = amp_field_curve(f, (double)ia / sd.da, (double)ib / sd.db, nc, r, curve, &s.length_before, err);
            if (st == AMP_OK)
                st = amp_field_clip(b, o, curve, nc + 1, min_len, out, err);
            if (st == AMP_OK)
                st = uniform_seed(f, &sd, pts, key, ncur++, ia, ib, curve, nc, err);
            s.curves++;
        }
    }
    sd.pts = pts;
    sd.key = key;
    sd.ncur = ncur;
    if (st == AMP_OK)
        st = amp_field_fill_gaps(f, b, o, &sd, nc, target, r, min_len, out, &s.gap_curves, &s.gap_left, err);
    amp_free(out->alloc, curve);
    amp_free(out->alloc, key);
    amp_free(out->alloc, pts);
    for (i = p0; i < out->npaths; i++)
        s.length_after += amp_path_length(out, i);
    s.pieces = out->npaths - p0;
    s.route = AMP_FIELD_ROUTE_UNIFORM;
    s.bound = NAN;
    s.bound_met = -1;
    *stats = s;
    return st;
}

amp_status amp_field_cover(const amp_field *f, const amp_bvh *b, const amp_field_opts *o, amp_pathset *out,
                           amp_field_stats *stats, amp_error *err)
{
    amp_field_stats s;
    double la, lb, lc, S, step, min_len, r, row, target;
    size_t na, nb, nc;
    amp_status st;
    if (!f || !f->eval || !b || !o || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_field_cover: NULL argument");
    S = o->spacing;
    if (!isfinite(S) || S <= 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "spacing must be a positive number of mm");
    if (f->eval == eval_box) {
        /* curves half a spacing inside the part's faces, never on them: a curve on a face is half outside
         * the part when printed, and curves along a box's faces (a lattice from the box's corner) test
         * neither in nor out, so the covering bound failed on every box */
        amp_field fb = *f;
        fb.p[1] -= 0.5 * S;
        fb.p[2] -= 0.5 * S;
        fb.p[4] += 0.5 * S;
        fb.p[5] += 0.5 * S;
        fb.eval = eval_box_centred;
        return amp_field_cover(&fb, b, o, out, stats, err);
    }
    if (o->pattern != AMP_PATTERN_GRID && o->pattern != AMP_PATTERN_HEX)
        return amp_fail(err, AMP_ERR_ARG, 0, "unknown pattern");
    step = o->step > 0 ? o->step : fmin(0.5, S / 2);
    min_len = o->min_len >= 0 ? o->min_len : S / 2;
    /* covering radius of the lattice: half diagonal of a square, circumradius of a triangle */
    target = o->pattern == AMP_PATTERN_GRID ? S * sqrt(2.0) / 2 : S / sqrt(3.0);
    r = o->radius > 0 ? o->radius : target;
    if (!isfinite(step) || !isfinite(min_len) || !isfinite(r))
        return amp_fail(err, AMP_ERR_ARG, 0, "field options must be finite");
    memset(&s, 0, sizeof s);
    s.radius = r;
    s.target = target;
    if (o->shells < 0 || o->shells > 100)
        return amp_fail(err, AMP_ERR_ARG, 0, "shells must be in 0..100");
    if ((st = max_iso_length(f, 0, 32, &la, err)) != AMP_OK || (st = max_iso_length(f, 1, 32, &lb, err)) != AMP_OK ||
        (st = max_iso_length(f, 2, 256, &lc, err)) != AMP_OK)
        return st;
    /* rows across b: S apart (grid) or S·√3/2 apart (honeycomb); S apart along a */
    row = o->pattern == AMP_PATTERN_GRID ? S : S * sqrt(3.0) / 2;
    /* ceil with a relative slack: a 12 mm side at S = 1 gives 12 curves, not 13 from 12.000000001 */
    na = (size_t)ceil(la / S * (1 - 1e-9));
    nb = (size_t)ceil(lb / row * (1 - 1e-9));
    nc = (size_t)ceil(lc / step);
    na = na ? na : 1;
    nb = nb ? nb : 1;
    nc = nc < 2 ? 2 : nc;
    if ((double)(na + 1) * (double)(nb + 1) * (double)(nc + 1) > 1e7)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "covering needs %.3g curve samples (limit 1e7): raise the spacing",
                        (double)(na + 1) * (double)(nb + 1) * (double)(nc + 1));
    if (f->eval == eval_spline) {
        st = cover_spline_field((const amp_spline *)f->user, f->dir, b, o, target, r, min_len, out, &s, err);
    } else {
        s.grid_a = na;
        s.grid_b = nb;
        st = o->pattern == AMP_PATTERN_GRID ? cover_adaptive(f, b, o, na, nb, nc, target, r, min_len, out, &s, err)
                                            : cover_uniform(f, b, o, na, nb, nc, target, r, min_len, out, &s, err);
    }
    if (st == AMP_OK && o->shells > 0)
        st = cover_shells(f, b, o, na, nb, nc, S, r, o->shells, min_len, out, &s, err);
    if (stats)
        *stats = s;
    return st;
}
