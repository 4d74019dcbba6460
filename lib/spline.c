/*
 * Tensor-product B-splines of 1..3 directions: construction, evaluation,
 * derivatives, batched evaluation. Algorithms follow Piegl & Tiller, "The NURBS
 * Book" (A2.1 span search, A2.2/A2.3 basis functions and derivatives, eq. 4.20
 * rational derivatives) generalised to three directions; control points are
 * homogeneous so rational and polynomial splines share every code path.
 */
#include <math.h>
#include <string.h>

#include "ampath/spline.h"
#include "spline_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

void amp_spline_init(amp_spline *s)
{
    int d;
    memset(s, 0, sizeof *s);
    for (d = 0; d < AMP_SPLINE_MAX_DIM; d++) {
        s->order[d] = 1;
        s->count[d] = 1;
    }
}

void amp_spline_free(amp_spline *s)
{
    int d;
    if (!s)
        return;
    for (d = 0; d < AMP_SPLINE_MAX_DIM; d++)
        amp_free(s->alloc, s->knots[d]);
    amp_free(s->alloc, s->cp);
    amp_spline_init(s);
}

amp_status amp_spline_create(amp_spline *s, const amp_allocator *a, int dim, const int *order, const size_t *count,
                             int rational, amp_error *err)
{
    int d;
    size_t i, ncp = 1;
    if (!s)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_spline_create: NULL spline");
    amp_spline_init(s);
    s->alloc = a;
    if (dim < 1 || dim > AMP_SPLINE_MAX_DIM || !order || !count)
        return amp_fail(err, AMP_ERR_ARG, 0, "spline dimension %d outside 1..3", dim);
    for (d = 0; d < dim; d++) {
        if (order[d] < 1)
            return amp_fail(err, AMP_ERR_ARG, 0, "order %d in direction %d is below 1", order[d], d);
        if (order[d] > AMP_SPLINE_MAX_ORDER)
            return amp_fail(err, AMP_ERR_LIMIT, 0, "order %d in direction %d is above the maximum %d", order[d], d,
                            AMP_SPLINE_MAX_ORDER);
        if (count[d] > AMP_SPLINE_MAX_COUNT)
            return amp_fail(err, AMP_ERR_LIMIT, 0, "%lu control points in direction %d exceed the maximum %d",
                            (unsigned long)count[d], d, AMP_SPLINE_MAX_COUNT);
        if (count[d] < (size_t)order[d])
            return amp_fail(err, AMP_ERR_ARG, 0, "%lu control points in direction %d are fewer than the order %d",
                            (unsigned long)count[d], d, order[d]);
        if (ncp > ((size_t)-1 / 4 / sizeof(double)) / count[d])
            return amp_fail(err, AMP_ERR_NOMEM, 0, "control net too large");
        ncp *= count[d];
    }
    s->dim = dim;
    s->rational = rational != 0;
    for (d = 0; d < dim; d++) {
        s->order[d] = order[d];
        s->count[d] = count[d];
        s->knots[d] = amp_calloc(a, count[d] + (size_t)order[d], sizeof(double));
        if (!s->knots[d]) {
            amp_spline_free(s);
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for knots");
        }
        amp_spline_set_knots_uniform(s, d, 0.0, 1.0, 1, NULL);
    }
    s->ncp = ncp;
    s->cp = amp_calloc(a, ncp, 4 * sizeof(double));
    if (!s->cp) {
        amp_spline_free(s);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for %lu control points", (unsigned long)ncp);
    }
    for (i = 0; i < ncp; i++)
        s->cp[4 * i + 3] = 1.0;
    s->alloc = a;
    return AMP_OK;
}

amp_status amp_spline_copy(amp_spline *dst, const amp_spline *src, const amp_allocator *a, amp_error *err)
{
    int d;
    amp_status st;
    if (!dst || !src)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_spline_copy: NULL argument");
    st = amp_spline_create(dst, a, src->dim, src->order, src->count, src->rational, err);
    if (st != AMP_OK)
        return st;
    for (d = 0; d < src->dim; d++)
        memcpy(dst->knots[d], src->knots[d], (src->count[d] + (size_t)src->order[d]) * sizeof(double));
    memcpy(dst->cp, src->cp, src->ncp * 4 * sizeof(double));
    return AMP_OK;
}

amp_status amp_spline_set_knots_uniform(amp_spline *s, int d, double lo, double hi, int clamped, amp_error *err)
{
    size_t n, i, m;
    int k;
    if (d < 0 || d >= s->dim || !(lo < hi))
        return amp_fail(err, AMP_ERR_ARG, 0, "bad direction %d or interval [%g, %g]", d, lo, hi);
    n = s->count[d];
    k = s->order[d];
    m = n + (size_t)k;
    if (clamped) {
        /* k equal knots at each end, n-k+1 uniform spans in between */
        size_t spans = n - (size_t)k + 1;
        for (i = 0; i < m; i++) {
            size_t j = i < (size_t)k ? 0 : (i >= n ? spans : i - (size_t)k + 1);
            s->knots[d][i] = j == spans ? hi : lo + (hi - lo) * (double)j / (double)spans;
        }
    } else {
        /* uniform knots; the domain [knots[k-1], knots[n]] is mapped onto [lo, hi] */
        size_t spans = n - (size_t)k + 1;
        double h = (hi - lo) / (double)spans;
        for (i = 0; i < m; i++)
            s->knots[d][i] = lo + h * ((double)i - (double)(k - 1));
        s->knots[d][n] = hi;
    }
    return AMP_OK;
}

amp_status amp_spline_validate(const amp_spline *s, amp_error *err)
{
    int d;
    size_t i;
    if (!s || s->dim < 1 || s->dim > AMP_SPLINE_MAX_DIM || !s->cp)
        return amp_fail(err, AMP_ERR_ARG, 0, "not a spline");
    for (d = 0; d < s->dim; d++) {
        const double *U = s->knots[d];
        size_t n = s->count[d], m = n + (size_t)s->order[d], run = 1;
        if (s->order[d] < 1 || s->order[d] > AMP_SPLINE_MAX_ORDER)
            return amp_fail(err, AMP_ERR_LIMIT, 0, "order %d outside 1..%d", s->order[d], AMP_SPLINE_MAX_ORDER);
        if (n < (size_t)s->order[d])
            return amp_fail(err, AMP_ERR_ARG, 0, "fewer control points than the order in direction %d", d);
        for (i = 0; i < m; i++) {
            if (!isfinite(U[i]))
                return amp_fail(err, AMP_ERR_GEOMETRY, 0, "knot %lu of direction %d is not finite",
                                (unsigned long)i + 1, d);
            if (i > 0 && U[i] < U[i - 1])
                return amp_fail(err, AMP_ERR_GEOMETRY, 0, "knots of direction %d decrease at knot %lu", d,
                                (unsigned long)i + 1);
            run = (i > 0 && U[i] == U[i - 1]) ? run + 1 : 1;
            if (run > (size_t)s->order[d])
                return amp_fail(err, AMP_ERR_GEOMETRY, 0,
                                "knot %.17g of direction %d has multiplicity above the order %d", U[i], d,
                                s->order[d]);
        }
        if (!(U[s->order[d] - 1] < U[n]))
            return amp_fail(err, AMP_ERR_GEOMETRY, 0, "empty parameter domain in direction %d", d);
    }
    for (i = 0; i < s->ncp; i++) {
        const double *p = s->cp + 4 * i;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]) || !isfinite(p[3]))
            return amp_fail(err, AMP_ERR_GEOMETRY, 0, "control point %lu is not finite", (unsigned long)i + 1);
        if (s->rational ? !(p[3] > 0.0) : p[3] != 1.0)
            return amp_fail(err, AMP_ERR_GEOMETRY, 0, "control point %lu has weight %g (%s)", (unsigned long)i + 1,
                            p[3], s->rational ? "must be positive" : "must be 1 when not rational");
    }
    return AMP_OK;
}

amp_vec3 amp_spline_cp_get(const amp_spline *s, size_t idx, double *weight)
{
    const double *p = s->cp + 4 * idx;
    if (weight)
        *weight = p[3];
    return amp_v3(p[0] / p[3], p[1] / p[3], p[2] / p[3]);
}

void amp_spline_cp_set(amp_spline *s, size_t idx, amp_vec3 p, double weight)
{
    double *q = s->cp + 4 * idx;
    double w = s->rational ? weight : 1.0;
    q[0] = p.x * w;
    q[1] = p.y * w;
    q[2] = p.z * w;
    q[3] = w;
}

void amp_spline_domain(const amp_spline *s, int d, double *lo, double *hi)
{
    if (!s || d < 0 || d >= s->dim || !s->knots[d]) { /* an empty spline (amp_spline_init) has no domain */
        *lo = *hi = 0.0;
        return;
    }
    *lo = s->knots[d][s->order[d] - 1];
    *hi = s->knots[d][s->count[d]];
}

/* An evaluator's argument check: a spline with control points (not one fresh from amp_spline_init or freed),
 * the parameters and the output. */
static amp_status usable(const amp_spline *s, const void *par, const void *out, amp_error *err)
{
    if (!s || !par || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "spline evaluation: NULL argument");
    if (s->dim < 1 || s->dim > AMP_SPLINE_MAX_DIM || !s->cp)
        return amp_fail(err, AMP_ERR_ARG, 0, "spline evaluation: an empty spline (no control points)");
    return AMP_OK;
}

amp_box3 amp_spline_cp_bbox(const amp_spline *s)
{
    amp_box3 b = amp_box3_empty();
    size_t i;
    for (i = 0; i < s->ncp; i++)
        b = amp_box3_add(b, amp_spline_cp_get(s, i, NULL));
    return b;
}

/* ---- spans and basis functions ---- */

double amp_spl_clamp(const amp_spline *s, int d, double t)
{
    double lo, hi;
    amp_spline_domain(s, d, &lo, &hi);
    return t < lo ? lo : (t > hi ? hi : t);
}

/*
 * NURBS Book A2.1 without snapping: the span i in [k-1, n-1] with
 * U[i] <= t < U[i+1], or the last non-empty span when t is the domain end.
 * @p hint (a previous span) is tried first so that runs of nearby parameters
 * skip the binary search.
 */
size_t amp_spl_span(const double *U, int k, size_t n, double t, size_t hint)
{
    size_t lo = (size_t)k - 1, hi = n, mid;
    if (t >= U[n]) {
        size_t i = n - 1;
        while (i > lo && U[i] == U[n])
            i--;
        return i;
    }
    if (hint >= lo && hint < n && U[hint] <= t && t < U[hint + 1])
        return hint;
    if (t <= U[lo]) {
        while (U[lo] == U[lo + 1])
            lo++;
        return lo;
    }
    while (hi - lo > 1) {
        mid = lo + (hi - lo) / 2;
        if (t < U[mid])
            hi = mid;
        else
            lo = mid;
    }
    return lo;
}

/*
 * NURBS Book A2.2: the k non-zero basis functions on span i. Denominators are
 * >= U[i+1]-U[i] > 0. @p inv (may be NULL) holds their reciprocals
 * inv[j*AMP_SPLINE_MAX_ORDER + r], precomputed per span by batched callers.
 */
static void basis_inv(const double *U, size_t i, int k, double t, const double *inv, double *N)
{
    double left[AMP_SPLINE_MAX_ORDER], right[AMP_SPLINE_MAX_ORDER];
    int j, r;
    N[0] = 1.0;
    for (j = 1; j < k; j++) {
        double saved = 0.0;
        left[j] = t - U[i + 1 - (size_t)j];
        right[j] = U[i + (size_t)j] - t;
        for (r = 0; r < j; r++) {
            double tmp = inv ? N[r] * inv[j * AMP_SPLINE_MAX_ORDER + r] : N[r] / (right[r + 1] + left[j - r]);
            N[r] = saved + right[r + 1] * tmp;
            saved = left[j - r] * tmp;
        }
        N[j] = saved;
    }
}

void amp_spl_basis(const double *U, size_t i, int k, double t, double *N) { basis_inv(U, i, k, t, NULL, N); }

/*
 * NURBS Book A2.3: basis functions and their derivatives up to @p nd on span i;
 * ders[q * k + j] = d^q N_{i-k+1+j} / dt^q. Rows above the degree are zero.
 */
void amp_spl_basis_ders(const double *U, size_t i, int k, double t, int nd, double *ders)
{
    double ndu[AMP_SPLINE_MAX_ORDER][AMP_SPLINE_MAX_ORDER], a[2][AMP_SPLINE_MAX_ORDER];
    double left[AMP_SPLINE_MAX_ORDER], right[AMP_SPLINE_MAX_ORDER];
    int p = k - 1, j, r, q, top = nd < p ? nd : p;
    ndu[0][0] = 1.0;
    for (j = 1; j <= p; j++) {
        double saved = 0.0;
        left[j] = t - U[i + 1 - (size_t)j];
        right[j] = U[i + (size_t)j] - t;
        for (r = 0; r < j; r++) {
            double tmp;
            ndu[j][r] = right[r + 1] + left[j - r]; /* lower triangle: knot differences */
            tmp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * tmp;
            saved = left[j - r] * tmp;
        }
        ndu[j][j] = saved;
    }
    for (j = 0; j <= p; j++)
        ders[j] = ndu[j][p];
    for (q = 1; q <= nd; q++)
        for (j = 0; j <= p; j++)
            ders[q * k + j] = 0.0;
    for (r = 0; r <= p; r++) {
        int s1 = 0, s2 = 1;
        a[0][0] = 1.0;
        for (q = 1; q <= top; q++) {
            double dd = 0.0;
            int rk = r - q, pk = p - q, j1, j2, tmpi;
            if (r >= q) {
                a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
                dd = a[s2][0] * ndu[rk][pk];
            }
            j1 = rk >= -1 ? 1 : -rk;
            j2 = (r - 1 <= pk) ? q - 1 : p - r;
            for (j = j1; j <= j2; j++) {
                a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
                dd += a[s2][j] * ndu[rk + j][pk];
            }
            if (r <= pk) {
                a[s2][q] = -a[s1][q - 1] / ndu[pk + 1][r];
                dd += a[s2][q] * ndu[r][pk];
            }
            ders[q * k + r] = dd;
            tmpi = s1;
            s1 = s2;
            s2 = tmpi;
        }
    }
    {
        double f = (double)p;
        for (q = 1; q <= top; q++) {
            for (j = 0; j <= p; j++)
                ders[q * k + j] *= f;
            f *= (double)(p - q);
        }
    }
}

/* Span and basis of every direction at one parameter tuple; NaN -> AMP_ERR_RANGE. */
static amp_status prepare(const amp_spline *s, const double *par, size_t *span, double N[][AMP_SPLINE_MAX_ORDER],
                          amp_error *err)
{
    int d;
    for (d = 0; d < s->dim; d++) {
        double t;
        if (isnan(par[d]))
            return amp_fail(err, AMP_ERR_RANGE, 0, "parameter %d is NaN", d + 1);
        t = amp_spl_clamp(s, d, par[d]);
        span[d] = amp_spl_span(s->knots[d], s->order[d], s->count[d], t, 0);
        amp_spl_basis(s->knots[d], span[d], s->order[d], t, N[d]);
    }
    for (; d < AMP_SPLINE_MAX_DIM; d++) {
        span[d] = 0;
        N[d][0] = 1.0;
    }
    return AMP_OK;
}

/* Homogeneous point from spans and basis values: the tensor contraction. */
static void contract(const amp_spline *s, const size_t *span, double N[][AMP_SPLINE_MAX_ORDER], double h[4])
{
    int k0 = s->order[0], k1 = s->dim > 1 ? s->order[1] : 1, k2 = s->dim > 2 ? s->order[2] : 1, a, b, c;
    size_t n0 = s->count[0], n1 = s->count[1];
    size_t f0 = span[0] + 1 - (size_t)k0, f1 = s->dim > 1 ? span[1] + 1 - (size_t)k1 : 0,
           f2 = s->dim > 2 ? span[2] + 1 - (size_t)k2 : 0;
    h[0] = h[1] = h[2] = h[3] = 0.0;
    for (c = 0; c < k2; c++)
        for (b = 0; b < k1; b++) {
            double nbc = N[1][b] * N[2][c];
            const double *p = s->cp + 4 * (f0 + n0 * (f1 + (size_t)b + n1 * (f2 + (size_t)c)));
            double x = 0, y = 0, z = 0, w = 0;
            for (a = 0; a < k0; a++, p += 4) {
                x += N[0][a] * p[0];
                y += N[0][a] * p[1];
                z += N[0][a] * p[2];
                w += N[0][a] * p[3];
            }
            h[0] += nbc * x;
            h[1] += nbc * y;
            h[2] += nbc * z;
            h[3] += nbc * w;
        }
}

static amp_vec3 project(const amp_spline *s, const double h[4])
{
    if (!s->rational)
        return amp_v3(h[0], h[1], h[2]);
    return amp_v3(h[0] / h[3], h[1] / h[3], h[2] / h[3]);
}

amp_status amp_spline_eval(const amp_spline *s, const double *par, amp_vec3 *out, amp_error *err)
{
    size_t span[AMP_SPLINE_MAX_DIM];
    double N[AMP_SPLINE_MAX_DIM][AMP_SPLINE_MAX_ORDER], h[4];
    amp_status st = usable(s, par, out, err);
    if (st != AMP_OK)
        return st;
    st = prepare(s, par, span, N, err);
    if (st != AMP_OK)
        return st;
    contract(s, span, N, h);
    *out = project(s, h);
    return AMP_OK;
}

static double binom(int n, int k)
{
    double r = 1.0;
    int i;
    for (i = 1; i <= k; i++)
        r = r * (double)(n - k + i) / (double)i;
    return r;
}

amp_status amp_spline_eval_derivs(const amp_spline *s, const double *par, int nd, amp_vec3 *out, amp_error *err)
{
    enum { M = AMP_SPLINE_MAX_DERIV + 1 };
    double D[AMP_SPLINE_MAX_DIM][M * AMP_SPLINE_MAX_ORDER];
    double A[M * M * M][4];
    size_t span[AMP_SPLINE_MAX_DIM], first[AMP_SPLINE_MAX_DIM];
    int d, ndd[AMP_SPLINE_MAX_DIM], kk[AMP_SPLINE_MAX_DIM], a, b, c, i, j, l, m1 = nd + 1;
    if (usable(s, par, out, err) != AMP_OK)
        return AMP_ERR_ARG;
    if (nd < 0 || nd > AMP_SPLINE_MAX_DERIV)
        return amp_fail(err, AMP_ERR_ARG, 0, "derivative order %d outside 0..%d", nd, AMP_SPLINE_MAX_DERIV);
    for (d = 0; d < AMP_SPLINE_MAX_DIM; d++) {
        if (d < s->dim) {
            double t;
            if (isnan(par[d]))
                return amp_fail(err, AMP_ERR_RANGE, 0, "parameter %d is NaN", d + 1);
            t = amp_spl_clamp(s, d, par[d]);
            kk[d] = s->order[d];
            span[d] = amp_spl_span(s->knots[d], kk[d], s->count[d], t, 0);
            amp_spl_basis_ders(s->knots[d], span[d], kk[d], t, nd, D[d]);
            ndd[d] = nd;
            first[d] = span[d] + 1 - (size_t)kk[d];
        } else {
            kk[d] = 1;
            D[d][0] = 1.0;
            ndd[d] = 0;
            first[d] = 0;
        }
    }
    /* homogeneous derivatives A[a,b,c] = sum N0^(a) N1^(b) N2^(c) P^w */
    for (c = 0; c <= ndd[2]; c++)
        for (b = 0; b <= ndd[1]; b++)
            for (a = 0; a <= ndd[0]; a++) {
                double *h = A[a + m1 * (b + m1 * c)];
                h[0] = h[1] = h[2] = h[3] = 0.0;
                for (l = 0; l < kk[2]; l++)
                    for (j = 0; j < kk[1]; j++) {
                        double f = D[1][b * kk[1] + j] * D[2][c * kk[2] + l];
                        const double *p;
                        if (f == 0.0)
                            continue;
                        p = s->cp + 4 * (first[0] + s->count[0] * (first[1] + (size_t)j +
                                                                   s->count[1] * (first[2] + (size_t)l)));
                        for (i = 0; i < kk[0]; i++, p += 4) {
                            double g = f * D[0][a * kk[0] + i];
                            h[0] += g * p[0];
                            h[1] += g * p[1];
                            h[2] += g * p[2];
                            h[3] += g * p[3];
                        }
                    }
            }
    /* eq. 4.20 generalised: S = (A - sum_{(i,j,l) != 0} C C C w_{ijl} S_{a-i,b-j,c-l}) / w */
    for (c = 0; c <= ndd[2]; c++)
        for (b = 0; b <= ndd[1]; b++)
            for (a = 0; a <= ndd[0]; a++) {
                const double *h = A[a + m1 * (b + m1 * c)];
                amp_vec3 v = amp_v3(h[0], h[1], h[2]);
                if (s->rational) {
                    for (l = 0; l <= c; l++)
                        for (j = 0; j <= b; j++)
                            for (i = 0; i <= a; i++) {
                                double wq;
                                if (i == 0 && j == 0 && l == 0)
                                    continue;
                                wq = A[i + m1 * (j + m1 * l)][3];
                                if (wq == 0.0)
                                    continue;
                                v = amp_v3_madd(v, out[(a - i) + m1 * ((b - j) + m1 * (c - l))],
                                                -binom(a, i) * binom(b, j) * binom(c, l) * wq);
                            }
                    v = amp_v3_scale(v, 1.0 / A[0][3]);
                }
                out[a + m1 * (b + m1 * c)] = v;
            }
    return AMP_OK;
}

amp_status amp_spline_eval_partial(const amp_spline *s, const double *par, const int *k, amp_vec3 *out,
                                   amp_error *err)
{
    amp_vec3 all[(AMP_SPLINE_MAX_DERIV + 1) * (AMP_SPLINE_MAX_DERIV + 1) * (AMP_SPLINE_MAX_DERIV + 1)];
    int d, nd = 0, kk[AMP_SPLINE_MAX_DIM] = {0, 0, 0};
    amp_status st = usable(s, par, out, err);
    if (st != AMP_OK)
        return st;
    if (!k)
        return amp_fail(err, AMP_ERR_ARG, 0, "spline evaluation: NULL derivative orders");
    for (d = 0; d < s->dim; d++) {
        if (k[d] < 0 || k[d] > AMP_SPLINE_MAX_DERIV)
            return amp_fail(err, AMP_ERR_ARG, 0, "derivative order %d outside 0..%d", k[d], AMP_SPLINE_MAX_DERIV);
        kk[d] = k[d];
        nd = k[d] > nd ? k[d] : nd;
    }
    st = amp_spline_eval_derivs(s, par, nd, all, err);
    if (st == AMP_OK)
        *out = all[kk[0] + (nd + 1) * (kk[1] + (nd + 1) * kk[2])];
    return st;
}

/* ---- batched evaluation ---- */

/*
 * A point of a cubic curve at t in span u[0] <= t < u[1] from its four control points @p p (x y z w each):
 * the recurrence of NURBS Book A2.2 written out (compilers at -O2 do not unroll it), with the span's
 * reciprocal knot differences i<j><r> = 1 / (u[1 + r] - u[1 + r - j]) given, so no division per point.
 */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline amp_vec3 cubic_point(const double *p, const double *u, double t, double i10, double i20, double i21,
                                   double i30, double i31, double i32)
{
    double l1 = t - u[0], l2 = t - u[-1], l3 = t - u[-2], r1 = u[1] - t, r2 = u[2] - t, r3 = u[3] - t;
    double n0, n1, n2, tmp, sv, Nb[4];
    tmp = i10;
    n0 = r1 * tmp;
    n1 = l1 * tmp;
    tmp = n0 * i20;
    n0 = r1 * tmp;
    sv = l2 * tmp;
    tmp = n1 * i21;
    n1 = sv + r2 * tmp;
    n2 = l1 * tmp;
    tmp = n0 * i30;
    Nb[0] = r1 * tmp;
    sv = l3 * tmp;
    tmp = n1 * i31;
    Nb[1] = sv + r2 * tmp;
    sv = l2 * tmp;
    tmp = n2 * i32;
    Nb[2] = sv + r3 * tmp;
    Nb[3] = l1 * tmp;
    return amp_v3(Nb[0] * p[0] + Nb[1] * p[4] + Nb[2] * p[8] + Nb[3] * p[12],
                  Nb[0] * p[1] + Nb[1] * p[5] + Nb[2] * p[9] + Nb[3] * p[13],
                  Nb[0] * p[2] + Nb[1] * p[6] + Nb[2] * p[10] + Nb[3] * p[14]);
}

/*
 * Points of a polynomial curve at a list of parameters. The reciprocals of the
 * knot differences of Cox-de Boor (NURBS Book A2.2) depend only on the span, so
 * they are computed once per span and the per-point basis needs no division:
 * same recurrence, same stability.
 */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline int curve_block(const amp_spline *s, const double *par, size_t n, amp_vec3 *out, const int k)
{
    size_t i, span0 = 0;
    int bad = 0;
    const double *U = s->knots[0];
        double inv[AMP_SPLINE_MAX_ORDER * AMP_SPLINE_MAX_ORDER], lo, hi;
        int a, j, r;
        size_t cur = (size_t)-1, nc = s->count[0];
        memset(inv, 0, sizeof inv);
        amp_spline_domain(s, 0, &lo, &hi);
        for (i = 0; i < n; i++) {
            double t = par[i], x = 0, y = 0, z = 0;
            const double *p;
            double Nb[AMP_SPLINE_MAX_ORDER];
            if (isnan(t)) {
                bad = 1;
                out[i] = amp_v3(NAN, NAN, NAN);
                continue;
            }
            t = t < lo ? lo : (t > hi ? hi : t);
            if (cur == (size_t)-1 || !(U[cur] <= t && t < U[cur + 1])) {
                span0 = amp_spl_span(U, k, nc, t, span0);
                if (span0 != cur) {
                    cur = span0;
                    for (j = 1; j < k; j++)
                        for (r = 0; r < j; r++)
                            inv[j * AMP_SPLINE_MAX_ORDER + r] =
                                1.0 / (U[cur + 1 + (size_t)r] - U[cur + 1 + (size_t)r - (size_t)j]);
                }
            }
            if (k == 4) {
                const double *I = inv;
                out[i] = cubic_point(s->cp + 4 * (cur - 3), U + cur, t, I[AMP_SPLINE_MAX_ORDER],
                                     I[2 * AMP_SPLINE_MAX_ORDER], I[2 * AMP_SPLINE_MAX_ORDER + 1],
                                     I[3 * AMP_SPLINE_MAX_ORDER], I[3 * AMP_SPLINE_MAX_ORDER + 1],
                                     I[3 * AMP_SPLINE_MAX_ORDER + 2]);
                continue;
            }
            basis_inv(U, cur, k, t, inv, Nb);
            p = s->cp + 4 * (cur + 1 - (size_t)k);
            for (a = 0; a < k; a++, p += 4) {
                x += Nb[a] * p[0];
                y += Nb[a] * p[1];
                z += Nb[a] * p[2];
            }
            out[i] = amp_v3(x, y, z);
        }
        return bad;
}

/*
 * A small knot index for unsorted parameter lists: the span holding the start of each of nb equal buckets of
 * the domain, and every span's reciprocal knot differences in the compact order (j, r) -> j(j-1)/2 + r. A
 * point's span is its bucket's span moved over the few knots inside the bucket, so a shuffled list costs a
 * table read instead of a binary search and k(k-1)/2 divisions per point; the spans and reciprocals are the
 * ones the sorted path computes, so both give the same bits.
 */
typedef struct span_index {
    size_t *bucket;
    double *inv;
    size_t nb, first, last, ntri;
    double lo, scale;
} span_index;

static void span_index_free(const amp_spline *s, span_index *x)
{
    amp_free(s->alloc, x->bucket);
    amp_free(s->alloc, x->inv);
}

/* Build the index of a polynomial curve; 0 (and nothing allocated) when memory is short. */
static int span_index_build(const amp_spline *s, span_index *x)
{
    const double *U = s->knots[0];
    int k = s->order[0], j, r;
    size_t nc = s->count[0], b, i;
    double hi;
    memset(x, 0, sizeof *x);
    amp_spline_domain(s, 0, &x->lo, &hi);
    x->first = amp_spl_span(U, k, nc, x->lo, 0);
    x->last = amp_spl_span(U, k, nc, hi, 0);
    x->nb = 2 * (x->last - x->first + 1);
    x->scale = hi > x->lo ? (double)x->nb / (hi - x->lo) : 0.0;
    x->ntri = (size_t)k * (size_t)(k - 1) / 2;
    x->bucket = amp_calloc(s->alloc, x->nb, sizeof *x->bucket);
    x->inv = amp_calloc(s->alloc, (x->last + 1) * (x->ntri ? x->ntri : 1), sizeof *x->inv);
    if (!x->bucket || !x->inv) {
        span_index_free(s, x);
        return 0;
    }
    for (b = 0, i = x->first; b < x->nb; b++) {
        double t = x->lo + (double)b / x->scale;
        while (i < x->last && t >= U[i + 1])
            i++;
        x->bucket[b] = i;
    }
    for (i = x->first; i <= x->last; i++)
        for (j = 1; j < k; j++)
            for (r = 0; r < j; r++)
                x->inv[i * x->ntri + (size_t)(j * (j - 1) / 2 + r)] =
                    1.0 / (U[i + 1 + (size_t)r] - U[i + 1 + (size_t)r - (size_t)j]);
    return 1;
}

/* The span of t (clamped to the domain), as amp_spl_span finds it. */
static inline size_t span_index_find(const span_index *x, const double *U, double t)
{
    double f = (t - x->lo) * x->scale;
    size_t i = x->bucket[f <= 0.0 ? 0 : (f >= (double)(x->nb - 1) ? x->nb - 1 : (size_t)f)];
    while (i < x->last && t >= U[i + 1])
        i++;
    while (i > x->first && t < U[i]) /* rounding of the bucket may land one knot late */
        i--;
    return i;
}

#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline int curve_block_indexed(const amp_spline *s, const span_index *x, const double *par, size_t n,
                                      amp_vec3 *out, const int k)
{
    const double *U = s->knots[0];
    double lo = x->lo, hi;
    size_t i, cur = x->first;
    int bad = 0;
    amp_spline_domain(s, 0, &lo, &hi);
    for (i = 0; i < n; i++) {
        double t = par[i], Nb[AMP_SPLINE_MAX_ORDER], xx = 0, y = 0, z = 0;
        const double *p, *I;
        int a, j, r;
        if (isnan(t)) {
            bad = 1;
            out[i] = amp_v3(NAN, NAN, NAN);
            continue;
        }
        t = t < lo ? lo : (t > hi ? hi : t);
        if (!(U[cur] <= t && t < U[cur + 1]))
            cur = span_index_find(x, U, t);
        I = x->inv + cur * x->ntri;
        if (k == 4) {
            out[i] = cubic_point(s->cp + 4 * (cur - 3), U + cur, t, I[0], I[1], I[2], I[3], I[4], I[5]);
            continue;
        }
        /* NURBS Book A2.2 with the span's reciprocals (basis_inv's recurrence) */
        Nb[0] = 1.0;
        for (j = 1; j < k; j++) {
            double saved = 0.0;
            for (r = 0; r < j; r++) {
                double tmp = Nb[r] * I[j * (j - 1) / 2 + r];
                Nb[r] = saved + (U[cur + 1 + (size_t)r] - t) * tmp;
                saved = (t - U[cur + 1 + (size_t)r - (size_t)j]) * tmp;
            }
            Nb[j] = saved;
        }
        p = s->cp + 4 * (cur + 1 - (size_t)k);
        for (a = 0; a < k; a++, p += 4) {
            xx += Nb[a] * p[0];
            y += Nb[a] * p[1];
            z += Nb[a] * p[2];
        }
        out[i] = amp_v3(xx, y, z);
    }
    return bad;
}

static int indexed_block(const amp_spline *s, const span_index *x, const double *par, size_t n, amp_vec3 *out)
{
    switch (s->order[0]) {
    case 2:
        return curve_block_indexed(s, x, par, n, out, 2);
    case 3:
        return curve_block_indexed(s, x, par, n, out, 3);
    case 4:
        return curve_block_indexed(s, x, par, n, out, 4);
    default:
        return curve_block_indexed(s, x, par, n, out, s->order[0]);
    }
}

/* One block of a parameter list, sequential, reusing the previous span as a hint. */
static int eval_block(const amp_spline *s, const double *par, size_t n, amp_vec3 *out)
{
    size_t span[AMP_SPLINE_MAX_DIM] = {0, 0, 0}, i;
    double N[AMP_SPLINE_MAX_DIM][AMP_SPLINE_MAX_ORDER], h[4];
    int d, bad = 0, dim = s->dim;
    for (d = dim; d < AMP_SPLINE_MAX_DIM; d++)
        N[d][0] = 1.0;
    if (dim == 1 && !s->rational) {
        /* constant orders let the compiler unroll the recurrence (cubic is the common case) */
        switch (s->order[0]) {
        case 2:
            return curve_block(s, par, n, out, 2);
        case 3:
            return curve_block(s, par, n, out, 3);
        case 4:
            return curve_block(s, par, n, out, 4);
        default:
            return curve_block(s, par, n, out, s->order[0]);
        }
    }
    for (i = 0; i < n; i++) {
        const double *q = par + i * (size_t)dim;
        for (d = 0; d < dim; d++) {
            double t = q[d];
            if (isnan(t))
                break;
            t = amp_spl_clamp(s, d, t);
            span[d] = amp_spl_span(s->knots[d], s->order[d], s->count[d], t, span[d]);
            amp_spl_basis(s->knots[d], span[d], s->order[d], t, N[d]);
        }
        if (d < dim) {
            bad = 1;
            out[i] = amp_v3(NAN, NAN, NAN);
            continue;
        }
        contract(s, span, N, h);
        out[i] = project(s, h);
    }
    return bad;
}

amp_status amp_spline_eval_list(const amp_spline *s, const double *par, size_t n, amp_vec3 *out, amp_error *err)
{
    enum { BLOCK = 512 };
    long nb = (long)((n + BLOCK - 1) / BLOCK), b;
    int bad = 0, indexed = 0;
    span_index x;
    if (n > 0 && usable(s, par, out, err) != AMP_OK)
        return AMP_ERR_ARG;
    /* a polynomial curve and a list long enough to pay for the index: spans by table (unsorted lists) */
    if (s->dim == 1 && !s->rational && n >= 256)
        indexed = span_index_build(s, &x);
#ifdef _OPENMP
#pragma omp parallel for schedule(static) reduction(| : bad) if (n > 4 * BLOCK)
#endif
    for (b = 0; b < nb; b++) {
        size_t lo = (size_t)b * BLOCK, m = n - lo < BLOCK ? n - lo : BLOCK;
        bad |= indexed ? indexed_block(s, &x, par + lo, m, out + lo)
                       : eval_block(s, par + lo * (size_t)s->dim, m, out + lo);
    }
    if (indexed)
        span_index_free(s, &x);
    if (bad)
        return amp_fail(err, AMP_ERR_RANGE, 0, "NaN parameter in batched evaluation");
    return AMP_OK;
}

/* Each grid line's span and basis, once: shared by every point on it. */
typedef struct grid_basis {
    size_t ng[AMP_SPLINE_MAX_DIM];    /* grid lines per direction (1 beyond dim) */
    size_t *span[AMP_SPLINE_MAX_DIM]; /* knot span per grid line */
    double *bas[AMP_SPLINE_MAX_DIM];  /* order non-zero basis functions per grid line */
} grid_basis;

static amp_status grid_bases(const amp_spline *s, const double *const *params, const size_t *n, grid_basis *g,
                             amp_error *err)
{
    int d;
    for (d = 0; d < s->dim; d++) {
        size_t i;
        int k = s->order[d];
        g->ng[d] = n[d];
        g->span[d] = amp_calloc(s->alloc, g->ng[d] ? g->ng[d] : 1, sizeof(size_t));
        g->bas[d] = amp_calloc(s->alloc, g->ng[d] ? g->ng[d] : 1, (size_t)k * sizeof(double));
        if (!g->span[d] || !g->bas[d])
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for grid basis");
        for (i = 0; i < g->ng[d]; i++) {
            double t = params[d][i];
            if (isnan(t))
                return amp_fail(err, AMP_ERR_RANGE, 0, "NaN parameter in grid direction %d", d + 1);
            t = amp_spl_clamp(s, d, t);
            g->span[d][i] = amp_spl_span(s->knots[d], k, s->count[d], t, i ? g->span[d][i - 1] : 0);
            amp_spl_basis(s->knots[d], g->span[d][i], k, t, g->bas[d] + i * (size_t)k);
        }
    }
    return AMP_OK;
}

/* Row o of the grid (one (v, w) grid point, every u): the net contracted over v and w into Q for the u columns
 * cmin..cmax that any grid point touches, then each point from its k0 columns of Q. */
static void grid_row(const amp_spline *s, const grid_basis *g, long o, size_t cmin, size_t cmax, double *Q,
                     amp_vec3 *out)
{
    int dim = s->dim, k0 = s->order[0], k1 = dim > 1 ? s->order[1] : 1, k2 = dim > 2 ? s->order[2] : 1, a, b, c;
    size_t n0c = s->count[0], i1 = (size_t)o % g->ng[1], i2 = (size_t)o / g->ng[1], i0, col;
    size_t f1 = dim > 1 ? g->span[1][i1] + 1 - (size_t)k1 : 0, f2 = dim > 2 ? g->span[2][i2] + 1 - (size_t)k2 : 0;
    const double *N1 = dim > 1 ? g->bas[1] + i1 * (size_t)k1 : NULL, *N2 = dim > 2 ? g->bas[2] + i2 * (size_t)k2 : NULL;
    amp_vec3 *row = out + (size_t)o * g->ng[0];
    for (col = cmin; col <= cmax; col++) {
        double *q = Q + 4 * col;
        q[0] = q[1] = q[2] = q[3] = 0.0;
        for (c = 0; c < k2; c++)
            for (b = 0; b < k1; b++) {
                double f = (N1 ? N1[b] : 1.0) * (N2 ? N2[c] : 1.0);
                const double *p = s->cp + 4 * (col + n0c * (f1 + (size_t)b + s->count[1] * (f2 + (size_t)c)));
                q[0] += f * p[0];
                q[1] += f * p[1];
                q[2] += f * p[2];
                q[3] += f * p[3];
            }
    }
    for (i0 = 0; i0 < g->ng[0]; i0++) {
        const double *N0 = g->bas[0] + i0 * (size_t)k0, *q = Q + 4 * (g->span[0][i0] + 1 - (size_t)k0);
        double h[4] = {0, 0, 0, 0};
        for (a = 0; a < k0; a++, q += 4) {
            h[0] += N0[a] * q[0];
            h[1] += N0[a] * q[1];
            h[2] += N0[a] * q[2];
            h[3] += N0[a] * q[3];
        }
        row[i0] = project(s, h);
    }
}

amp_status amp_spline_eval_grid(const amp_spline *s, const double *const *params, const size_t *n, amp_vec3 *out,
                                amp_error *err)
{
    grid_basis g = {{1, 1, 1}, {NULL, NULL, NULL}, {NULL, NULL, NULL}};
    double *scratch = NULL;
    int d, nthreads = 1, empty = 0;
    long outer, o;
    amp_status st = usable(s, params, out, err);
    size_t n0c, cmin = 0, cmax = 0, i;
    if (st != AMP_OK || !n)
        return st != AMP_OK ? st : amp_fail(err, AMP_ERR_ARG, 0, "spline evaluation: NULL argument");
    n0c = s->count[0];
#ifdef _OPENMP
    nthreads = omp_get_max_threads();
#endif
    st = grid_bases(s, params, n, &g, err);
    /* per thread: the u-column of the net contracted over v and w for one (v, w) grid point */
    if (st == AMP_OK && !(scratch = amp_calloc(s->alloc, (size_t)nthreads * n0c, 4 * sizeof(double))))
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for grid scratch");
    for (d = 0; d < s->dim; d++)
        empty |= g.ng[d] == 0;
    if (st == AMP_OK && !empty) {
        /* the u columns any grid point touches (parameters need not be sorted) */
        cmin = cmax = g.span[0][0];
        for (i = 1; i < g.ng[0]; i++) {
            cmin = g.span[0][i] < cmin ? g.span[0][i] : cmin;
            cmax = g.span[0][i] > cmax ? g.span[0][i] : cmax;
        }
        cmin = cmin + 1 - (size_t)s->order[0];
        outer = (long)(g.ng[1] * g.ng[2]);
#ifdef _OPENMP
#pragma omp parallel for schedule(static) if (outer > 1 && g.ng[0] * (size_t)outer > 4096)
#endif
        for (o = 0; o < outer; o++) {
            int tid = 0;
#ifdef _OPENMP
            tid = omp_get_thread_num();
#endif
            grid_row(s, &g, o, cmin, cmax, scratch + (size_t)tid * n0c * 4, out);
        }
    }
    amp_free(s->alloc, scratch);
    for (d = 0; d < AMP_SPLINE_MAX_DIM; d++) {
        amp_free(s->alloc, g.span[d]);
        amp_free(s->alloc, g.bas[d]);
    }
    return st;
}
