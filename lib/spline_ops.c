/*
 * Shape-preserving operations on amp_spline: knot insertion (Boehm), refinement,
 * subdivision, isoparametric extraction, reversal, derivative splines, and the
 * control-polygon length bound of [P1] (Appendix, Lemma A.2).
 * Every operation works on one direction of the homogeneous control net, seen as
 * `outer` × count[d] × `stride` (u fastest), so curves, surfaces and trivariates
 * share the code.
 */
#include <math.h>
#include <string.h>

#include "ampath/spline.h"
#include "spline_internal.h"

static void strides(const amp_spline *s, int d, size_t *stride, size_t *outer)
{
    int e;
    *stride = 1;
    *outer = 1;
    for (e = 0; e < s->dim; e++) {
        if (e < d)
            *stride *= s->count[e];
        else if (e > d)
            *outer *= s->count[e];
    }
}

static int multiplicity(const amp_spline *s, int d, double t)
{
    size_t i, m = s->count[d] + (size_t)s->order[d];
    int r = 0;
    for (i = 0; i < m; i++)
        r += s->knots[d][i] == t;
    return r;
}

/* Boehm's algorithm (NURBS Book A5.1 with r = 1) along direction d. */
static amp_status insert_once(amp_spline *s, int d, double t, amp_error *err)
{
    size_t n = s->count[d], k = (size_t)s->order[d], p = k - 1, stride, outer, a, b, i, span;
    const double *U = s->knots[d];
    double *nU, *ncp;
    strides(s, d, &stride, &outer);
    span = amp_spl_span(U, (int)k, n, t, 0);
    nU = amp_alloc(s->alloc, (n + 1 + k) * sizeof(double));
    ncp = amp_calloc(s->alloc, stride * outer * (n + 1), 4 * sizeof(double));
    if (!nU || !ncp) {
        amp_free(s->alloc, nU);
        amp_free(s->alloc, ncp);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory inserting a knot");
    }
    memcpy(nU, U, (span + 1) * sizeof(double));
    nU[span + 1] = t;
    memcpy(nU + span + 2, U + span + 1, (n + k - span - 1) * sizeof(double));
    for (b = 0; b < outer; b++)
        for (a = 0; a < stride; a++)
            for (i = 0; i <= n; i++) {
                double *q = ncp + 4 * (a + stride * (i + (n + 1) * b));
                const double *pi = s->cp + 4 * (a + stride * (i + n * b)), *pm = pi - 4 * stride;
                int c;
                if (i + p <= span)
                    memcpy(q, pi, 4 * sizeof(double));
                else if (i >= span + 1)
                    memcpy(q, pm, 4 * sizeof(double));
                else {
                    /* U[i+p] >= U[span+1] > U[span] >= U[i]: the denominator is positive */
                    double al = (t - U[i]) / (U[i + p] - U[i]);
                    for (c = 0; c < 4; c++)
                        q[c] = al * pi[c] + (1.0 - al) * pm[c];
                }
            }
    amp_free(s->alloc, s->knots[d]);
    amp_free(s->alloc, s->cp);
    s->knots[d] = nU;
    s->cp = ncp;
    s->count[d] = n + 1;
    s->ncp = stride * outer * (n + 1);
    return AMP_OK;
}

/* Several insertions work on a copy @p c: it replaces @p s when they all succeeded (@p st AMP_OK) and is dropped
 * otherwise, so that s changes all at once or not at all (spline.h). */
static amp_status swap_in(amp_spline *s, amp_spline *c, amp_status st)
{
    if (st == AMP_OK) {
        amp_spline_free(s);
        *s = *c;
    } else {
        amp_spline_free(c);
    }
    return st;
}

amp_status amp_spline_insert_knot(amp_spline *s, int d, double t, int times, amp_error *err)
{
    double lo, hi;
    int i;
    if (!s)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_spline_insert_knot: NULL spline");
    if (d < 0 || d >= s->dim || times < 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "bad direction %d or count %d", d, times);
    amp_spline_domain(s, d, &lo, &hi);
    if (!(t >= lo && t <= hi))
        return amp_fail(err, AMP_ERR_RANGE, 0, "knot %.17g outside the domain [%.17g, %.17g]", t, lo, hi);
    if (multiplicity(s, d, t) + times > s->order[d])
        return amp_fail(err, AMP_ERR_LIMIT, 0, "knot %.17g would get multiplicity above the order %d", t,
                        s->order[d]);
    if (s->count[d] + (size_t)times > AMP_SPLINE_MAX_COUNT)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "too many control points");
    if (times <= 1)
        return times == 1 ? insert_once(s, d, t, err) : AMP_OK; /* one insertion leaves s as it was on failure */
    {
        amp_spline c;
        amp_status st = amp_spline_copy(&c, s, s->alloc, err);
        for (i = 0; i < times && st == AMP_OK; i++)
            st = insert_once(&c, d, t, err);
        return swap_in(s, &c, st);
    }
}

amp_status amp_spline_refine(amp_spline *s, int d, const double *t, size_t n, amp_error *err)
{
    amp_spline c;
    size_t i;
    amp_status st;
    if (!s || (!t && n))
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_spline_refine: NULL argument");
    if (n == 0)
        return AMP_OK;
    st = amp_spline_copy(&c, s, s->alloc, err);
    for (i = 0; i < n && st == AMP_OK; i++)
        st = amp_spline_insert_knot(&c, d, t[i], 1, err);
    return swap_in(s, &c, st);
}

/* A new spline equal to s except that direction d keeps control points first..first+cnt-1 with knots K. */
static amp_status slice(const amp_spline *s, int d, size_t first, size_t cnt, const double *K, amp_spline *out,
                        amp_error *err)
{
    size_t count[AMP_SPLINE_MAX_DIM], stride, outer, a, b, i;
    amp_status st;
    memcpy(count, s->count, sizeof count);
    count[d] = cnt;
    st = amp_spline_create(out, s->alloc, s->dim, s->order, count, s->rational, err);
    if (st != AMP_OK)
        return st;
    for (a = 0; a < (size_t)s->dim; a++)
        if ((int)a != d)
            memcpy(out->knots[a], s->knots[a], (s->count[a] + (size_t)s->order[a]) * sizeof(double));
    memcpy(out->knots[d], K, (cnt + (size_t)s->order[d]) * sizeof(double));
    strides(s, d, &stride, &outer);
    for (b = 0; b < outer; b++)
        for (i = 0; i < cnt; i++)
            for (a = 0; a < stride; a++)
                memcpy(out->cp + 4 * (a + stride * (i + cnt * b)),
                       s->cp + 4 * (a + stride * (first + i + s->count[d] * b)), 4 * sizeof(double));
    return AMP_OK;
}

amp_status amp_spline_split(const amp_spline *s, int d, double t, amp_spline *left, amp_spline *right,
                            amp_error *err)
{
    amp_spline tmp;
    double lo, hi, *K = NULL;
    int k, m;
    size_t a, n;
    amp_status st;
    amp_spline_init(left);
    amp_spline_init(right);
    if (d < 0 || d >= s->dim)
        return amp_fail(err, AMP_ERR_ARG, 0, "bad direction %d", d);
    amp_spline_domain(s, d, &lo, &hi);
    if (!(t > lo && t < hi))
        return amp_fail(err, AMP_ERR_RANGE, 0, "split parameter %.17g not strictly inside (%.17g, %.17g)", t, lo,
                        hi);
    st = amp_spline_copy(&tmp, s, s->alloc, err);
    if (st != AMP_OK)
        return st;
    k = s->order[d];
    m = multiplicity(&tmp, d, t);
    /* multiplicity order-1 makes the curve interpolate one control point at t */
    if (m < k - 1)
        st = amp_spline_insert_knot(&tmp, d, t, k - 1 - m, err);
    if (st == AMP_OK) {
        n = tmp.count[d];
        m = multiplicity(&tmp, d, t);
        for (a = 0; tmp.knots[d][a] != t; a++)
            ;
        K = amp_alloc(s->alloc, (n + (size_t)k + 1) * sizeof(double));
        if (!K)
            st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory splitting");
    }
    if (st == AMP_OK) {
        if (m == k) {
            /* already discontinuous at t: the two halves share no control point */
            st = slice(&tmp, d, 0, a, tmp.knots[d], left, err);
            if (st == AMP_OK)
                st = slice(&tmp, d, a, n - a, tmp.knots[d] + a, right, err);
        } else {
            memcpy(K, tmp.knots[d], (a + (size_t)k - 1) * sizeof(double));
            K[a + (size_t)k - 1] = t;
            st = slice(&tmp, d, 0, a, K, left, err);
            if (st == AMP_OK) {
                K[0] = t;
                memcpy(K + 1, tmp.knots[d] + a, (n + (size_t)k - a) * sizeof(double));
                st = slice(&tmp, d, a - 1, n - a + 1, K, right, err);
            }
        }
    }
    amp_free(s->alloc, K);
    amp_spline_free(&tmp);
    if (st != AMP_OK) {
        amp_spline_free(left);
        amp_spline_free(right);
    }
    return st;
}

amp_status amp_spline_isoparam(const amp_spline *s, int d, double t, amp_spline *out, amp_error *err)
{
    int order[AMP_SPLINE_MAX_DIM], e, j = 0, k;
    size_t count[AMP_SPLINE_MAX_DIM], stride, outer, a, b, span;
    double N[AMP_SPLINE_MAX_ORDER];
    amp_status st;
    amp_spline_init(out);
    if (s->dim < 2 || d < 0 || d >= s->dim)
        return amp_fail(err, AMP_ERR_ARG, 0, "isoparametric extraction needs a surface or trivariate");
    if (isnan(t))
        return amp_fail(err, AMP_ERR_RANGE, 0, "parameter is NaN");
    for (e = 0; e < s->dim; e++)
        if (e != d) {
            order[j] = s->order[e];
            count[j] = s->count[e];
            j++;
        }
    st = amp_spline_create(out, s->alloc, s->dim - 1, order, count, s->rational, err);
    if (st != AMP_OK)
        return st;
    for (e = 0, j = 0; e < s->dim; e++)
        if (e != d) {
            memcpy(out->knots[j], s->knots[e], (s->count[e] + (size_t)s->order[e]) * sizeof(double));
            j++;
        }
    t = amp_spl_clamp(s, d, t);
    k = s->order[d];
    span = amp_spl_span(s->knots[d], k, s->count[d], t, 0);
    amp_spl_basis(s->knots[d], span, k, t, N);
    strides(s, d, &stride, &outer);
    /* homogeneous combination: exact for rational splines too */
    for (b = 0; b < outer; b++)
        for (a = 0; a < stride; a++) {
            double *q = out->cp + 4 * (a + stride * b);
            int c, i;
            for (c = 0; c < 4; c++) {
                double v = 0.0;
                for (i = 0; i < k; i++)
                    v += N[i] * s->cp[4 * (a + stride * (span + 1 - (size_t)k + (size_t)i + s->count[d] * b)) + c];
                q[c] = v;
            }
        }
    return AMP_OK;
}

void amp_spline_reverse(amp_spline *s, int d)
{
    size_t n = s->count[d], m = n + (size_t)s->order[d], stride, outer, a, b, i;
    double lo, hi, *U = s->knots[d];
    amp_spline_domain(s, d, &lo, &hi);
    for (i = 0; i < m / 2; i++) {
        double x = U[i];
        U[i] = U[m - 1 - i];
        U[m - 1 - i] = x;
    }
    for (i = 0; i < m; i++)
        U[i] = lo + hi - U[i];
    strides(s, d, &stride, &outer);
    for (b = 0; b < outer; b++)
        for (a = 0; a < stride; a++)
            for (i = 0; i < n / 2; i++) {
                double tmp[4], *p = s->cp + 4 * (a + stride * (i + n * b)),
                               *q = s->cp + 4 * (a + stride * (n - 1 - i + n * b));
                memcpy(tmp, p, sizeof tmp);
                memcpy(p, q, sizeof tmp);
                memcpy(q, tmp, sizeof tmp);
            }
}

amp_status amp_spline_derivative(const amp_spline *s, int d, amp_spline *out, amp_error *err)
{
    int order[AMP_SPLINE_MAX_DIM], e, k;
    size_t count[AMP_SPLINE_MAX_DIM], stride, outer, a, b, i, n;
    amp_status st;
    amp_spline_init(out);
    if (d < 0 || d >= s->dim)
        return amp_fail(err, AMP_ERR_ARG, 0, "bad direction %d", d);
    if (s->rational)
        return amp_fail(err, AMP_ERR_UNSUPPORTED, 0, "the derivative of a rational spline is not a spline of "
                                                     "the same kind; use amp_spline_eval_derivs");
    if (s->order[d] < 2)
        return amp_fail(err, AMP_ERR_ARG, 0, "order 1 has no derivative spline");
    memcpy(order, s->order, sizeof order);
    memcpy(count, s->count, sizeof count);
    k = order[d];
    n = count[d];
    order[d] = k - 1;
    count[d] = n - 1;
    st = amp_spline_create(out, s->alloc, s->dim, order, count, 0, err);
    if (st != AMP_OK)
        return st;
    for (e = 0; e < s->dim; e++)
        if (e != d)
            memcpy(out->knots[e], s->knots[e], (s->count[e] + (size_t)s->order[e]) * sizeof(double));
    memcpy(out->knots[d], s->knots[d] + 1, (n + (size_t)k - 2) * sizeof(double));
    strides(s, d, &stride, &outer);
    for (b = 0; b < outer; b++)
        for (a = 0; a < stride; a++)
            for (i = 0; i + 1 < n; i++) {
                const double *p0 = s->cp + 4 * (a + stride * (i + n * b)), *p1 = p0 + 4 * stride;
                double *q = out->cp + 4 * (a + stride * (i + (n - 1) * b));
                double du = s->knots[d][i + (size_t)k] - s->knots[d][i + 1];
                /* a zero-length support means the coefficient multiplies a zero basis function */
                double f = du > 0.0 ? (double)(k - 1) / du : 0.0;
                q[0] = f * (p1[0] - p0[0]);
                q[1] = f * (p1[1] - p0[1]);
                q[2] = f * (p1[2] - p0[2]);
                q[3] = 1.0;
            }
    return AMP_OK;
}

double amp_spline_polygon_length_bound(const amp_spline *s, int d, double *seg)
{
    size_t n = s->count[d], stride, outer, a, b, k;
    double total = 0.0;
    strides(s, d, &stride, &outer);
    for (k = 0; k + 1 < n; k++) {
        double mx = 0.0, rmin = HUGE_VAL, rmax = 0.0, R = 0.0;
        amp_vec3 c = amp_v3(0, 0, 0);
        /* Lemma A.2: max over (i, j) of |P_{i,j,k+1} - P_{i,j,k}| */
        for (b = 0; b < outer; b++)
            for (a = 0; a < stride; a++) {
                size_t i0 = a + stride * (k + n * b);
                double w0, w1, l;
                amp_vec3 p0 = amp_spline_cp_get(s, i0, &w0), p1 = amp_spline_cp_get(s, i0 + stride, &w1);
                l = amp_v3_dist(p0, p1);
                mx = l > mx ? l : mx;
                rmin = fmin(rmin, w1 / w0);
                rmax = fmax(rmax, w1 / w0);
                c = amp_v3_add(c, p0);
            }
        if (s->rational && rmax > rmin) {
            /* rational: the isoparametric control points mix layer k with varying weights */
            c = amp_v3_scale(c, 1.0 / (double)(stride * outer));
            for (b = 0; b < outer; b++)
                for (a = 0; a < stride; a++)
                    R = fmax(R, amp_v3_dist(c, amp_spline_cp_get(s, a + stride * (k + n * b), NULL)));
            mx += (rmax / rmin - 1.0) * R;
        }
        if (seg)
            seg[k] = mx;
        total += mx;
    }
    return total;
}
