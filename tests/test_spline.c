/* Splines (include/ampath/spline.h): closed forms, shape-preserving operations, .spl format, built-in models. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtool.h"
#include "testutil.h"


static unsigned long rng_state = 12345;
static int dbl_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : (x > y);
}

static double rnd(void)
{
    rng_state = rng_state * 6364136223846793005UL + 1442695040888963407UL;
    return (double)((rng_state >> 11) & 0xFFFFFFFFFFUL) / (double)0xFFFFFFFFFFUL;
}

/* A polynomial spline with random control points in [-10, 10]^3 and, when @p nonuniform, random interior knots. */
static void random_spline(amp_spline *s, int dim, const int *order, const size_t *count, int rational, int clamped,
                          int nonuniform)
{
    int d;
    size_t i;
    ck_assert_int_eq(amp_spline_create(s, NULL, dim, order, count, rational, NULL), AMP_OK);
    for (d = 0; d < dim; d++) {
        size_t m = count[d] + (size_t)order[d];
        ck_assert_int_eq(amp_spline_set_knots_uniform(s, d, 0.0, 1.0, clamped, NULL), AMP_OK);
        if (nonuniform) {
            /* sorted random knots keep the clamped ends */
            double t = clamped ? 0.0 : -0.5;
            for (i = clamped ? (size_t)order[d] : 0; i < (clamped ? count[d] : m); i++) {
                t += 0.05 + rnd();
                s->knots[d][i] = t;
            }
            if (clamped) {
                t += 0.05 + rnd();
                for (i = count[d]; i < m; i++)
                    s->knots[d][i] = t;
            }
        }
    }
    for (i = 0; i < s->ncp; i++)
        amp_spline_cp_set(s, i, amp_v3(20 * rnd() - 10, 20 * rnd() - 10, 20 * rnd() - 10),
                          rational ? 0.3 + 2 * rnd() : 1.0);
    ck_assert_int_eq(amp_spline_validate(s, NULL), AMP_OK);
}

static amp_vec3 ev(const amp_spline *s, double u, double v, double w)
{
    double p[3] = {u, v, w};
    amp_vec3 out;
    ck_assert_int_eq(amp_spline_eval(s, p, &out, NULL), AMP_OK);
    return out;
}

/* A point of the domain at fractions (a, b, c). */
static void dom_point(const amp_spline *s, double a, double b, double c, double *p)
{
    double f[3] = {a, b, c}, lo, hi;
    int d;
    for (d = 0; d < s->dim; d++) {
        amp_spline_domain(s, d, &lo, &hi);
        p[d] = lo + (hi - lo) * f[d];
    }
}

START_TEST(rational_quadratic_circle_is_exactly_a_circle)
{
    /* unit circle of radius 7 from four 90-degree arcs: weights sqrt(2)/2 at the corners */
    static const double c[9][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    static const double U[12] = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
    amp_spline s;
    int order = 3, i;
    size_t count = 9;
    ck_assert_int_eq(amp_spline_create(&s, NULL, 1, &order, &count, 1, NULL), AMP_OK);
    memcpy(s.knots[0], U, sizeof U);
    for (i = 0; i < 9; i++)
        amp_spline_cp_set(&s, (size_t)i, amp_v3(7 * c[i][0], 7 * c[i][1], 3), i % 2 ? sqrt(0.5) : 1.0);
    for (i = 0; i <= 4000; i++) {
        double t = i / 4000.0;
        amp_vec3 d[3];
        ck_assert_int_eq(amp_spline_eval_derivs(&s, &t, 2, d, NULL), AMP_OK);
        ck_assert_near(hypot(d[0].x, d[0].y), 7.0, 1e-13 * 7);
        ck_assert_near(d[0].z, 3.0, 1e-14);
        /* tangent perpendicular to the radius; curvature vector points to the centre */
        ck_assert_near(d[0].x * d[1].x + d[0].y * d[1].y, 0.0, 1e-9 * amp_v3_len(d[1]));
        {
            amp_vec3 cr = amp_v3_cross(d[1], d[2]);
            double kappa = amp_v3_len(cr) / pow(amp_v3_len(d[1]), 3);
            ck_assert_near(kappa, 1.0 / 7.0, 1e-9);
        }
    }
    amp_spline_free(&s);
}
END_TEST

static amp_vec3 de_casteljau(const amp_vec3 *P, int n, double t)
{
    amp_vec3 q[AMP_SPLINE_MAX_ORDER];
    int r, i;
    memcpy(q, P, (size_t)n * sizeof *q);
    for (r = 1; r < n; r++)
        for (i = 0; i < n - r; i++)
            q[i] = amp_v3_lerp(q[i], q[i + 1], t);
    return q[0];
}

START_TEST(clamped_bezier_equals_de_casteljau)
{
    int orders[3] = {2, 4, 9}, oi, i, j;
    for (oi = 0; oi < 3; oi++) {
        amp_spline s, surf;
        int k = orders[oi], ks[2];
        size_t n = (size_t)k, ns[2];
        amp_vec3 P[AMP_SPLINE_MAX_ORDER], row[AMP_SPLINE_MAX_ORDER], col[AMP_SPLINE_MAX_ORDER];
        random_spline(&s, 1, &k, &n, 0, 1, 0);
        for (i = 0; i < k; i++)
            P[i] = amp_spline_cp_get(&s, (size_t)i, NULL);
        for (i = 0; i <= 200; i++) {
            double t = i / 200.0;
            amp_vec3 a = ev(&s, t, 0, 0), b = de_casteljau(P, k, t);
            ck_assert_msg(amp_v3_dist(a, b) < 1e-12 * 10, "order %d t %g: %g", k, t, amp_v3_dist(a, b));
        }
        /* tensor-product Bézier surface against nested de Casteljau */
        ks[0] = k;
        ks[1] = 3;
        ns[0] = (size_t)k;
        ns[1] = 3;
        random_spline(&surf, 2, ks, ns, 0, 1, 0);
        for (i = 0; i <= 20; i++)
            for (j = 0; j <= 20; j++) {
                double u = i / 20.0, v = j / 20.0;
                int a, b;
                for (b = 0; b < 3; b++) {
                    for (a = 0; a < k; a++)
                        row[a] = amp_spline_cp_get(&surf, amp_spline_index(&surf, (size_t)a, (size_t)b, 0), NULL);
                    col[b] = de_casteljau(row, k, u);
                }
                ck_assert(amp_v3_dist(ev(&surf, u, v, 0), de_casteljau(col, 3, v)) < 1e-12 * 10);
            }
        amp_spline_free(&s);
        amp_spline_free(&surf);
    }
}
END_TEST

START_TEST(derivatives_match_finite_differences_and_the_derivative_spline)
{
    amp_spline s, d1, d2;
    int k = 5, i;
    size_t n = 11;
    /* unclamped, non-uniform quartic */
    random_spline(&s, 1, &k, &n, 0, 0, 1);
    ck_assert_int_eq(amp_spline_derivative(&s, 0, &d1, NULL), AMP_OK);
    ck_assert_int_eq(amp_spline_derivative(&d1, 0, &d2, NULL), AMP_OK);
    for (i = 0; i <= 300; i++) {
        double t[1], h = 1e-6, lo, hi;
        amp_vec3 D[3], fd;
        amp_spline_domain(&s, 0, &lo, &hi);
        t[0] = lo + (hi - lo) * (0.001 + 0.998 * i / 300.0);
        ck_assert_int_eq(amp_spline_eval_derivs(&s, t, 2, D, NULL), AMP_OK);
        ck_assert(amp_v3_dist(D[1], ev(&d1, t[0], 0, 0)) < 1e-10 * (1 + amp_v3_len(D[1])));
        ck_assert(amp_v3_dist(D[2], ev(&d2, t[0], 0, 0)) < 1e-9 * (1 + amp_v3_len(D[2])));
        fd = amp_v3_scale(amp_v3_sub(ev(&s, t[0] + h, 0, 0), ev(&s, t[0] - h, 0, 0)), 0.5 / h);
        ck_assert_msg(amp_v3_dist(D[1], fd) < 1e-5 * (1 + amp_v3_len(D[1])), "t %g: %g", t[0],
                      amp_v3_dist(D[1], fd));
    }
    amp_spline_free(&s);
    amp_spline_free(&d1);
    amp_spline_free(&d2);
}
END_TEST

START_TEST(rational_trivariate_partials_match_finite_differences)
{
    amp_spline s;
    int i, a, b, c;
    ck_assert_int_eq(amp_trivariate_model("helix", NULL, &s, NULL), AMP_OK);
    for (i = 0; i < 40; i++) {
        double p[3], h = 1e-5;
        amp_vec3 D[27];
        dom_point(&s, 0.05 + 0.9 * rnd(), 0.05 + 0.9 * rnd(), 0.05 + 0.9 * rnd(), p);
        ck_assert_int_eq(amp_spline_eval_derivs(&s, p, 2, D, NULL), AMP_OK);
        for (c = 0; c < 3; c++) {
            /* first partials from the points, second partials from the first */
            double q1[3], q2[3];
            amp_vec3 fd, A[27], B[27];
            memcpy(q1, p, sizeof p);
            memcpy(q2, p, sizeof p);
            q1[c] += h;
            q2[c] -= h;
            ck_assert_int_eq(amp_spline_eval_derivs(&s, q1, 2, A, NULL), AMP_OK);
            ck_assert_int_eq(amp_spline_eval_derivs(&s, q2, 2, B, NULL), AMP_OK);
            fd = amp_v3_scale(amp_v3_sub(A[0], B[0]), 0.5 / h);
            a = c == 0 ? 1 : 0;
            b = c == 1 ? 1 : 0;
            {
                int idx = a + 3 * (b + 3 * (c == 2));
                ck_assert_msg(amp_v3_dist(D[idx], fd) < 1e-5 * (1 + amp_v3_len(D[idx])), "dir %d: %g", c,
                              amp_v3_dist(D[idx], fd));
            }
            /* d/dc of the u-partial: mixed and pure second derivatives */
            fd = amp_v3_scale(amp_v3_sub(A[1], B[1]), 0.5 / h);
            {
                int idx = 1 + (c == 0) + 3 * ((c == 1) + 3 * (c == 2));
                ck_assert_msg(amp_v3_dist(D[idx], fd) < 1e-4 * (1 + amp_v3_len(D[idx])), "second dir %d: %g", c,
                              amp_v3_dist(D[idx], fd));
            }
        }
    }
    amp_spline_free(&s);
}
END_TEST

/* Largest distance between two splines over a grid of their common domain. */
static double max_grid_diff(const amp_spline *a, const amp_spline *b, int n)
{
    int i, j, l;
    double mx = 0;
    for (i = 0; i <= n; i++)
        for (j = 0; j <= (a->dim > 1 ? n : 0); j++)
            for (l = 0; l <= (a->dim > 2 ? n : 0); l++) {
                double p[3];
                amp_vec3 x, y;
                dom_point(a, (double)i / n, (double)j / n, (double)l / n, p);
                ck_assert_int_eq(amp_spline_eval(a, p, &x, NULL), AMP_OK);
                ck_assert_int_eq(amp_spline_eval(b, p, &y, NULL), AMP_OK);
                mx = fmax(mx, amp_v3_dist(x, y));
            }
    return mx;
}

START_TEST(knot_insertion_and_refinement_leave_the_shape_unchanged)
{
    amp_spline s, r;
    int k[3] = {4, 3, 2}, d;
    size_t n[3] = {7, 5, 4};
    random_spline(&s, 3, k, n, 1, 0, 1);
    ck_assert_int_eq(amp_spline_copy(&r, &s, NULL, NULL), AMP_OK);
    for (d = 0; d < 3; d++) {
        double lo, hi, t[5];
        int i;
        amp_spline_domain(&s, d, &lo, &hi);
        for (i = 0; i < 5; i++)
            t[i] = lo + (hi - lo) * rnd();
        ck_assert_int_eq(amp_spline_refine(&r, d, t, 5, NULL), AMP_OK);
        /* an existing knot raised to full multiplicity, plus the domain end */
        ck_assert_int_eq(amp_spline_insert_knot(&r, d, r.knots[d][r.order[d]], 1, NULL), AMP_OK);
        ck_assert_uint_eq(r.count[d], n[d] + 6);
    }
    ck_assert_int_eq(amp_spline_validate(&r, NULL), AMP_OK);
    ck_assert_double_le(max_grid_diff(&s, &r, 12), 1e-12 * 20);
    /* over-insertion is refused, not undefined */
    ck_assert_int_eq(amp_spline_insert_knot(&r, 0, r.knots[0][5], 9, NULL), AMP_ERR_LIMIT);
    ck_assert_int_eq(amp_spline_insert_knot(&r, 0, 1e9, 1, NULL), AMP_ERR_RANGE);
    amp_spline_free(&s);
    amp_spline_free(&r);
}
END_TEST

START_TEST(split_halves_reproduce_the_spline)
{
    amp_spline s, l, r;
    int k[2] = {4, 3}, d, i;
    size_t n[2] = {8, 6};
    random_spline(&s, 2, k, n, 1, 1, 1);
    for (d = 0; d < 2; d++) {
        double lo, hi, t;
        amp_spline_domain(&s, d, &lo, &hi);
        t = lo + 0.37 * (hi - lo);
        ck_assert_int_eq(amp_spline_split(&s, d, t, &l, &r, NULL), AMP_OK);
        ck_assert_int_eq(amp_spline_validate(&l, NULL), AMP_OK);
        ck_assert_int_eq(amp_spline_validate(&r, NULL), AMP_OK);
        for (i = 0; i <= 100; i++) {
            double f = i / 100.0, p[2], q[2];
            amp_vec3 a, b;
            dom_point(&s, 0.3, 0.3, 0, p);
            memcpy(q, p, sizeof p);
            q[d] = lo + (t - lo) * f;
            ck_assert_int_eq(amp_spline_eval(&l, q, &a, NULL), AMP_OK);
            ck_assert_int_eq(amp_spline_eval(&s, q, &b, NULL), AMP_OK);
            ck_assert_double_le(amp_v3_dist(a, b), 1e-12 * 20);
            q[d] = t + (hi - t) * f;
            ck_assert_int_eq(amp_spline_eval(&r, q, &a, NULL), AMP_OK);
            ck_assert_int_eq(amp_spline_eval(&s, q, &b, NULL), AMP_OK);
            ck_assert_double_le(amp_v3_dist(a, b), 1e-12 * 20);
        }
        amp_spline_free(&l);
        amp_spline_free(&r);
    }
    ck_assert_int_eq(amp_spline_split(&s, 0, 0.0, &l, &r, NULL), AMP_ERR_RANGE);
    amp_spline_free(&s);
}
END_TEST

START_TEST(evaluation_near_knots_is_exact_and_continuous)
{
    /* cubic with a C0 knot (multiplicity 3) at 0.5 and simple knots elsewhere */
    static const double U[] = {0, 0, 0, 0, 0.25, 0.5, 0.5, 0.5, 0.75, 1, 1, 1, 1};
    amp_spline s, l, r;
    int k = 4, i;
    size_t n = 9;
    random_spline(&s, 1, &k, &n, 0, 1, 0);
    memcpy(s.knots[0], U, sizeof U);
    for (i = 0; i < 5; i++) {
        double t = U[4 + i], dmax = 0;
        amp_vec3 D[2], a = ev(&s, t - 1e-12, 0, 0), b = ev(&s, t + 1e-12, 0, 0), c = ev(&s, t, 0, 0);
        amp_spline_eval_derivs(&s, &t, 1, D, NULL);
        dmax = 2 * amp_v3_len(D[1]) + 2000; /* one-sided derivatives may differ at the C0 knot */
        ck_assert_msg(amp_v3_dist(a, c) <= dmax * 1e-12 + 1e-12 * 10, "knot %g: %g", t, amp_v3_dist(a, c));
        ck_assert_msg(amp_v3_dist(b, c) <= dmax * 1e-12 + 1e-12 * 10, "knot %g: %g", t, amp_v3_dist(b, c));
    }
    /* near (not at) the C0 knot the value is that of the piece [0.25, 0.5] itself: no snapping onto 0.5 */
    ck_assert_int_eq(amp_spline_split(&s, 0, 0.5, &l, &r, NULL), AMP_OK);
    {
        amp_spline l2, r2;
        amp_vec3 P[4];
        int j;
        double t = 0.5 - 1e-5, f = (t - 0.25) / 0.25;
        ck_assert_int_eq(amp_spline_split(&l, 0, 0.25, &l2, &r2, NULL), AMP_OK);
        ck_assert_uint_eq(r2.count[0], 4); /* the Bézier piece on [0.25, 0.5] */
        for (j = 0; j < 4; j++)
            P[j] = amp_spline_cp_get(&r2, (size_t)j, NULL);
        ck_assert_double_le(amp_v3_dist(ev(&s, t, 0, 0), de_casteljau(P, 4, f)), 1e-12 * 10);
        ck_assert_double_gt(amp_v3_dist(ev(&s, t, 0, 0), ev(&s, 0.5, 0, 0)), 1e-9);
        amp_spline_free(&l2);
        amp_spline_free(&r2);
    }
    amp_spline_free(&l);
    amp_spline_free(&r);
    amp_spline_free(&s);
}
END_TEST

START_TEST(isoparametric_extraction_matches_the_trivariate)
{
    amp_spline v, surf, curve;
    int d, i;
    ck_assert_int_eq(amp_trivariate_model("vase", NULL, &v, NULL), AMP_OK);
    for (d = 0; d < 3; d++) {
        double p[3], t, q[2];
        dom_point(&v, 0.3, 0.61, 0.77, p);
        t = p[d];
        ck_assert_int_eq(amp_spline_isoparam(&v, d, t, &surf, NULL), AMP_OK);
        ck_assert_int_eq(surf.dim, 2);
        ck_assert_int_eq(amp_spline_isoparam(&surf, 1, 0.4, &curve, NULL), AMP_OK);
        for (i = 0; i < 50; i++) {
            int e, j = 0;
            amp_vec3 a, b;
            dom_point(&v, rnd(), rnd(), rnd(), p);
            p[d] = t;
            for (e = 0; e < 3; e++)
                if (e != d)
                    q[j++] = p[e];
            ck_assert_int_eq(amp_spline_eval(&surf, q, &a, NULL), AMP_OK);
            ck_assert_int_eq(amp_spline_eval(&v, p, &b, NULL), AMP_OK);
            ck_assert_double_le(amp_v3_dist(a, b), 1e-12 * 60);
            q[1] = 0.4;
            ck_assert_int_eq(amp_spline_eval(&curve, q, &a, NULL), AMP_OK);
            ck_assert_int_eq(amp_spline_eval(&surf, q, &b, NULL), AMP_OK);
            ck_assert_double_le(amp_v3_dist(a, b), 1e-12 * 60);
        }
        amp_spline_free(&surf);
        amp_spline_free(&curve);
    }
    ck_assert_int_eq(amp_spline_isoparam(&curve, 0, 0.5, &surf, NULL), AMP_ERR_ARG);
    amp_spline_free(&v);
}
END_TEST

START_TEST(reversal_mirrors_the_parameter)
{
    amp_spline s, r;
    int k[2] = {3, 4}, i;
    size_t n[2] = {6, 7};
    random_spline(&s, 2, k, n, 1, 0, 1);
    ck_assert_int_eq(amp_spline_copy(&r, &s, NULL, NULL), AMP_OK);
    amp_spline_reverse(&r, 1);
    ck_assert_int_eq(amp_spline_validate(&r, NULL), AMP_OK);
    for (i = 0; i < 100; i++) {
        double p[2], lo, hi, q[2];
        amp_vec3 a, b;
        dom_point(&s, rnd(), rnd(), 0, p);
        amp_spline_domain(&s, 1, &lo, &hi);
        q[0] = p[0];
        q[1] = lo + hi - p[1];
        amp_spline_eval(&s, p, &a, NULL);
        amp_spline_eval(&r, q, &b, NULL);
        ck_assert_double_le(amp_v3_dist(a, b), 1e-11);
    }
    amp_spline_free(&s);
    amp_spline_free(&r);
}
END_TEST

START_TEST(batched_list_and_grid_match_single_points)
{
    int k[3] = {4, 4, 4}, dim;
    size_t n[3] = {9, 7, 6};
    for (dim = 1; dim <= 3; dim++) {
        amp_spline s;
        double g[3][13], *par, *gp[3];
        size_t ng[3] = {13, 5, 4}, tot = 1, i;
        amp_vec3 *out, *out2;
        int d;
        random_spline(&s, dim, k, n, dim == 3, dim != 2, 1);
        for (d = 0; d < dim; d++) {
            double lo, hi;
            amp_spline_domain(&s, d, &lo, &hi);
            for (i = 0; i < ng[d]; i++) /* unsorted, including both ends and out-of-domain (clamped) */
                g[d][i] = i == 0 ? hi : i == 1 ? lo - 1 : lo + (hi - lo) * rnd();
            gp[d] = g[d];
            tot *= ng[d];
        }
        out = malloc(tot * sizeof *out);
        out2 = malloc(tot * sizeof *out);
        par = malloc(tot * 3 * sizeof *par);
        ck_assert_int_eq(amp_spline_eval_grid(&s, (const double *const *)gp, ng, out, NULL), AMP_OK);
        for (i = 0; i < tot; i++) {
            size_t i0 = i % ng[0], i1 = (i / ng[0]) % ng[1], i2 = i / (ng[0] * ng[1]);
            double p[3] = {g[0][i0], dim > 1 ? g[1][i1] : 0, dim > 2 ? g[2][i2] : 0};
            memcpy(par + i * (size_t)dim, p, (size_t)dim * sizeof(double));
            ck_assert_double_le(amp_v3_dist(out[i], ev(&s, p[0], p[1], p[2])), 1e-12 * 20);
        }
        ck_assert_int_eq(amp_spline_eval_list(&s, par, tot, out2, NULL), AMP_OK);
        for (i = 0; i < tot; i++)
            ck_assert_double_le(amp_v3_dist(out[i], out2[i]), 1e-12 * 20);
        par[0] = NAN;
        ck_assert_int_eq(amp_spline_eval_list(&s, par, tot, out2, NULL), AMP_ERR_RANGE);
        free(out);
        free(out2);
        free(par);
        amp_spline_free(&s);
    }
}
END_TEST

/* Arc length of an isoparametric curve of direction d through the other parameters' fractions (a, b), sampled. */
static double iso_length(const amp_spline *s, int d, double a, double b)
{
    double f[3], p[3], lo, hi, len = 0;
    amp_vec3 prev = amp_v3(0, 0, 0), cur;
    int i, e, j = 0;
    for (e = 0; e < 3; e++)
        f[e] = e == d ? 0 : (j++ == 0 ? a : b);
    dom_point(s, f[0], f[1], f[2], p);
    amp_spline_domain(s, d, &lo, &hi);
    for (i = 0; i <= 2000; i++) {
        p[d] = lo + (hi - lo) * i / 2000.0;
        amp_spline_eval(s, p, &cur, NULL);
        if (i)
            len += amp_v3_dist(prev, cur);
        prev = cur;
    }
    return len;
}

/* Speed: a long parameter list in random order (the knot index, 256 points and more) gives exactly the points
 * of the same list sorted and of short lists (the span cache), for orders 2..5, uniform and random knots,
 * knots of multiplicity 2, parameters on knots, at and beyond both domain ends. */
START_TEST(shuffled_long_lists_give_the_points_of_sorted_and_short_lists)
{
    int k;
    for (k = 2; k <= 5; k++) {
        int nonuniform;
        for (nonuniform = 0; nonuniform < 2; nonuniform++) {
            amp_spline s;
            int order[1];
            size_t count[1] = {40}, n = 3000, i, *perm = malloc(3000 * sizeof *perm);
            double *par = malloc(n * sizeof *par), *sorted = malloc(n * sizeof *sorted), lo, hi;
            amp_vec3 *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *c = malloc(n * sizeof *c);
            order[0] = k;
            random_spline(&s, 1, order, count, 0, 1, nonuniform);
            if (nonuniform)
                s.knots[0][k + 10] = s.knots[0][k + 9]; /* a double knot inside */
            amp_spline_domain(&s, 0, &lo, &hi);
            for (i = 0; i < n; i++) {
                if (i % 7 == 0)
                    par[i] = s.knots[0][(size_t)k - 1 + i % (count[0] - (size_t)k + 2)];
                else
                    par[i] = lo - 0.1 + (hi - lo + 0.2) * rnd();
                perm[i] = i;
            }
            par[1] = lo;
            par[2] = hi;
            for (i = n; i > 1; i--) {
                size_t q = (size_t)(rnd() * (double)i) % i, t = perm[i - 1];
                perm[i - 1] = perm[q];
                perm[q] = t;
            }
            for (i = 0; i < n; i++)
                sorted[i] = par[i];
            qsort(sorted, n, sizeof *sorted, dbl_cmp);
            for (i = 0; i < n; i++)
                par[i] = sorted[perm[i]];
            ck_assert_int_eq(amp_spline_eval_list(&s, par, n, a, NULL), AMP_OK);
            ck_assert_int_eq(amp_spline_eval_list(&s, sorted, n, b, NULL), AMP_OK);
            for (i = 0; i < n; i += 200)
                ck_assert_int_eq(amp_spline_eval_list(&s, par + i, n - i < 200 ? n - i : 200, c + i, NULL), AMP_OK);
            for (i = 0; i < n; i++) {
                ck_assert_msg(a[i].x == b[perm[i]].x && a[i].y == b[perm[i]].y && a[i].z == b[perm[i]].z,
                              "order %d: t = %.17g differs between shuffled and sorted lists", k, par[i]);
                ck_assert_msg(a[i].x == c[i].x && a[i].y == c[i].y && a[i].z == c[i].z,
                              "order %d: t = %.17g differs between a long and a short list", k, par[i]);
            }
            amp_spline_free(&s);
            free(perm);
            free(par);
            free(sorted);
            free(a);
            free(b);
            free(c);
        }
    }
}
END_TEST

START_TEST(control_polygon_bound_holds_and_is_tight_on_a_straight_net)
{
    amp_spline s;
    int k[3] = {2, 2, 3}, d, i;
    size_t n[3] = {2, 2, 4}, idx;
    double seg[8], bound;
    const char *const *names = amp_trivariate_model_names();
    /* a straight prism: w-lines are straight, the bound equals their length */
    ck_assert_int_eq(amp_spline_create(&s, NULL, 3, k, n, 0, NULL), AMP_OK);
    for (idx = 0; idx < s.ncp; idx++)
        amp_spline_cp_set(&s, idx, amp_v3((double)(idx % 2), (double)((idx / 2) % 2), 3.0 * (double)(idx / 4)), 1);
    bound = amp_spline_polygon_length_bound(&s, 2, seg);
    ck_assert_near(bound, 9.0, 1e-12);
    ck_assert_near(seg[1], 3.0, 1e-12);
    ck_assert_near(iso_length(&s, 2, 0.3, 0.6), 9.0, 1e-9);
    amp_spline_free(&s);
    /* Lemma A.2 on every built-in (rational) model and direction: no isocurve is longer */
    for (i = 0; names[i]; i++) {
        ck_assert_int_eq(amp_trivariate_model(names[i], NULL, &s, NULL), AMP_OK);
        for (d = 0; d < 3; d++) {
            int t;
            bound = amp_spline_polygon_length_bound(&s, d, NULL);
            for (t = 0; t < 10; t++) {
                double L = iso_length(&s, d, rnd(), rnd());
                ck_assert_msg(L <= bound * (1 + 1e-12), "%s dir %d: length %g > bound %g", names[i], d, L, bound);
            }
        }
        amp_spline_free(&s);
    }
}
END_TEST

START_TEST(spl_roundtrip_keeps_several_objects)
{
    amp_spline a, b, c, *list;
    amp_buf buf;
    size_t n;
    amp_error err;
    int k1 = 4, k3[3] = {2, 3, 4};
    size_t n1 = 70, n3[3] = {2, 4, 5};
    random_spline(&a, 1, &k1, &n1, 0, 0, 1); /* a knots line of 74 values: longer than the lexer's field limit */
    random_spline(&c, 3, k3, n3, 1, 1, 1);
    ck_assert_int_eq(amp_trivariate_model("torus-quarter", NULL, &b, NULL), AMP_OK);
    amp_buf_init(&buf, NULL);
    ck_assert_int_eq(amp_spline_write(&a, 1, amp_buf_sink, &buf, NULL), AMP_OK);
    ck_assert_int_eq(amp_spline_write(&b, 0, amp_buf_sink, &buf, NULL), AMP_OK);
    ck_assert_int_eq(amp_buf_append(&buf, "# a comment and a repeated header\nampath-spline 1\n", 50), AMP_OK);
    ck_assert_int_eq(amp_spline_write(&c, 0, amp_buf_sink, &buf, NULL), AMP_OK);
    ck_assert_int_eq(amp_spline_parse(buf.data, buf.len, NULL, &list, &n, &err), AMP_OK);
    ck_assert_uint_eq(n, 3);
    ck_assert_double_le(max_grid_diff(&a, &list[0], 50), 1e-12 * 20);
    ck_assert_double_le(max_grid_diff(&b, &list[1], 8), 1e-12 * 60);
    ck_assert_double_le(max_grid_diff(&c, &list[2], 8), 1e-12 * 20);
    ck_assert_int_eq(list[2].rational, 1);
    amp_spline_list_free(NULL, list, n);
    amp_buf_free(&buf);
    amp_spline_free(&a);
    amp_spline_free(&b);
    amp_spline_free(&c);
}
END_TEST

#define HDR "ampath-spline 1\n"
#define CURVE2 "kind curve\nrational 0\norder 2\ncount 2\n"
static const struct bad_case {
    const char *text;
    amp_status st;
    long line;
    const char *needle;
} bad_cases[] = {
    {"", AMP_ERR_PARSE, 1, "empty"},
    {"ampath-spline 2\n", AMP_ERR_PARSE, 1, "version"},
    {HDR, AMP_ERR_PARSE, 1, "no spline"},
    {HDR "kind blob\n", AMP_ERR_PARSE, 2, "kind curve"},
    {HDR CURVE2 "knots 0 1 0 1\n0 0 0\n1 1 1\n", AMP_ERR_PARSE, 6, "decrease"},
    {HDR CURVE2 "knots 0 0 1\n0 0 0\n1 1 1\n", AMP_ERR_PARSE, 6, "expected 4 knots"},
    {HDR CURVE2 "knots 0 0 1 1 1\n0 0 0\n1 1 1\n", AMP_ERR_PARSE, 6, "more than"},
    {HDR CURVE2 "knots 0 0 0 1\n0 0 0\n1 1 1\n", AMP_ERR_PARSE, 6, "repeats"},
    {HDR CURVE2 "knots 1 1 1 1\n", AMP_ERR_PARSE, 6, "repeats"},
    {HDR CURVE2 "knots 0 0 1 1\n0 0 0\n", AMP_ERR_PARSE, 8, "end of input"},
    {HDR CURVE2 "knots 0 0 1 1\n0 0 0\n1 1\n", AMP_ERR_PARSE, 8, "found 2 fields"},
    {HDR CURVE2 "knots 0 0 1 nan\n", AMP_ERR_PARSE, 6, "finite"},
    {HDR CURVE2 "0 0 0\n", AMP_ERR_PARSE, 6, "knots"},
    {HDR "kind curve\nrational 1\norder 2\ncount 2\nknots 0 0 1 1\n0 0 0 1\n1 1 1 0\n", AMP_ERR_PARSE, 8,
     "not positive"},
    {HDR "kind curve\nrational 1\norder 2\ncount 2\nknots 0 0 1 1\n0 0 0 -2\n1 1 1 1\n", AMP_ERR_PARSE, 7,
     "not positive"},
    {HDR "kind curve\nrational 0\norder 2\ncount 2\nknots 0 0 1 1\n0 0 0 3\n1 1 1\n", AMP_ERR_PARSE, 7, "weight"},
    {HDR "kind curve\nrational 0\norder 17\ncount 20\n", AMP_ERR_LIMIT, 4, "order 17"},
    {HDR "kind curve\nrational 0\norder 0\ncount 20\n", AMP_ERR_PARSE, 4, "order 0"},
    {HDR "kind curve\nrational 0\norder 3\ncount 2\n", AMP_ERR_PARSE, 5, "below the order"},
    {HDR "kind curve\nrational 0\norder 2\ncount 100000\n", AMP_ERR_PARSE, 5, "too short"},
    {HDR "kind surface\nrational 0\norder 2\n", AMP_ERR_PARSE, 4, "2 values"},
    {HDR "kind curve\nrational 2\n", AMP_ERR_PARSE, 3, "rational"},
};

START_TEST(malformed_spl_is_rejected_with_line_numbers)
{
    const struct bad_case *c = &bad_cases[_i];
    amp_spline *list = (amp_spline *)&list;
    size_t n = 99;
    amp_error err;
    amp_error_clear(&err);
    ck_assert_int_eq(amp_spline_parse(c->text, strlen(c->text), NULL, &list, &n, &err), c->st);
    ck_assert_msg(err.line == c->line, "case %d: line %ld, expected %ld (%s)", _i, err.line, c->line, err.msg);
    ck_assert_msg(strstr(err.msg, c->needle) != NULL, "case %d: message '%s' lacks '%s'", _i, err.msg, c->needle);
    ck_assert_ptr_null(list);
    ck_assert_uint_eq(n, 0);
}
END_TEST

START_TEST(bad_arguments_get_errors_not_undefined_behaviour)
{
    amp_spline s;
    int k = 17, k2[2] = {3, 3};
    size_t n = 20, n2[2] = {3, 3};
    double p[2] = {NAN, 0.5};
    amp_vec3 out, D[9];
    amp_error err;
    ck_assert_int_eq(amp_spline_create(&s, NULL, 1, &k, &n, 0, &err), AMP_ERR_LIMIT);
    k = 4;
    n = 3;
    ck_assert_int_eq(amp_spline_create(&s, NULL, 1, &k, &n, 0, &err), AMP_ERR_ARG);
    ck_assert_int_eq(amp_spline_create(&s, NULL, 4, &k, &n, 0, &err), AMP_ERR_ARG);
    random_spline(&s, 2, k2, n2, 1, 1, 0);
    ck_assert_int_eq(amp_spline_eval(&s, p, &out, &err), AMP_ERR_RANGE);
    ck_assert_int_eq(amp_spline_eval_derivs(&s, p + 1, 5, D, &err), AMP_ERR_ARG);
    /* out-of-domain parameters are clamped (documented) */
    p[0] = -3;
    p[1] = 7;
    ck_assert_int_eq(amp_spline_eval(&s, p, &out, &err), AMP_OK);
    ck_assert_double_le(amp_v3_dist(out, ev(&s, 0, 1, 0)), 0);
    s.cp[3] = -1; /* a negative weight */
    ck_assert_int_eq(amp_spline_validate(&s, &err), AMP_ERR_GEOMETRY);
    s.cp[3] = 1;
    s.knots[0][2] = 2; /* knots decrease */
    ck_assert_int_eq(amp_spline_validate(&s, &err), AMP_ERR_GEOMETRY);
    {
        amp_spline ds;
        ck_assert_int_eq(amp_spline_derivative(&s, 0, &ds, &err), AMP_ERR_UNSUPPORTED);
        amp_spline_free(&ds);
    }
    amp_spline_free(&s);
    {
        fx_failalloc fa;
        long budget;
        for (budget = 0; budget < 4; budget++) {
            amp_status st;
            fx_failalloc_init(&fa, budget);
            st = amp_trivariate_model("helix", &fa.a, &s, &err);
            ck_assert(st == AMP_OK || st == AMP_ERR_NOMEM);
            amp_spline_free(&s);
        }
    }
    ck_assert_int_eq(amp_trivariate_model("teapot", NULL, &s, &err), AMP_ERR_ARG);
    ck_assert_ptr_nonnull(strstr(err.msg, "helix"));
}
END_TEST

/* Distance from p to the exact helix solid of docs/interfaces.md §4: min over t of the distance to the disc at c(t). */
static double helix_solid_dist(amp_vec3 p, double *tbest)
{
    const double R = 20, H = 40, RD = 5, L = sqrt(4 * AMP_PI * AMP_PI * R * R + H * H), z0 = RD * 2 * AMP_PI * R / L;
    double best = HUGE_VAL, bt = 0, lo, hi;
    int i, pass;
    lo = 0;
    hi = 1;
    for (pass = 0; pass < 4; pass++) {
        double step = (hi - lo) / 200, t0 = bt;
        for (i = 0; i <= 200; i++) {
            double t = lo + step * i, ph = 2 * AMP_PI * t, dist;
            amp_vec3 c = amp_v3(R * cos(ph), R * sin(ph), z0 + H * t);
            amp_vec3 T = amp_v3_scale(amp_v3(-2 * AMP_PI * R * sin(ph), 2 * AMP_PI * R * cos(ph), H), 1 / L);
            amp_vec3 q = amp_v3_sub(p, c);
            double hn = amp_v3_dot(q, T), rr = sqrt(fmax(0, amp_v3_len2(q) - hn * hn));
            dist = rr <= RD ? fabs(hn) : hypot(hn, rr - RD);
            if (t < 0 || t > 1)
                continue;
            if (dist < best) {
                best = dist;
                bt = t;
            }
        }
        (void)t0;
        lo = fmax(0, bt - 2 * step);
        hi = fmin(1, bt + 2 * step);
    }
    if (tbest)
        *tbest = bt;
    return best;
}

START_TEST(helix_model_is_within_0_05_mm_of_the_swept_disc)
{
    amp_spline s;
    int i, j, l;
    double worst = 0, worst_boundary = 0, zmin = HUGE_VAL;
    const double R = 20, H = 40, L = sqrt(4 * AMP_PI * AMP_PI * R * R + H * H);
    ck_assert_int_eq(amp_trivariate_model("helix", NULL, &s, NULL), AMP_OK);
    for (l = 0; l <= 64; l++)
        for (j = 0; j <= 8; j++)
            for (i = 0; i <= 8; i++) {
                amp_vec3 p = ev(&s, i / 8.0, j / 8.0, l / 64.0);
                double t, dd = helix_solid_dist(p, &t);
                worst = fmax(worst, dd);
                zmin = fmin(zmin, p.z);
                if (i == 0 || i == 8 || j == 0 || j == 8) {
                    /* the spline's side boundary lies on the tube of radius 5 around the helix */
                    double ph = 2 * AMP_PI * t;
                    amp_vec3 c = amp_v3(R * cos(ph), R * sin(ph), 5 * 2 * AMP_PI * R / L + H * t);
                    worst_boundary = fmax(worst_boundary, fabs(amp_v3_dist(p, c) - 5.0));
                }
            }
    ck_assert_msg(worst <= 0.05, "spline point %g mm outside the solid", worst);
    ck_assert_msg(worst_boundary <= 0.05, "spline boundary %g mm off the tube", worst_boundary);
    ck_assert_near(zmin, 0.0, 0.05);
    /* and the checker notices a wrong model: a disc of radius 5.2 is not within 0.05 mm */
    {
        amp_vec3 c = ev(&s, 0.5, 0.5, 0.3), e = ev(&s, 1.0, 0.5, 0.3);
        amp_vec3 out = amp_v3_add(e, amp_v3_scale(amp_v3_normalize(amp_v3_sub(e, c)), 0.2));
        ck_assert_double_gt(helix_solid_dist(out, NULL), 0.15);
    }
    amp_spline_free(&s);
}
END_TEST

START_TEST(torus_quarter_and_vase_are_exact_revolutions)
{
    amp_spline s;
    int i;
    ck_assert_int_eq(amp_trivariate_model("torus-quarter", NULL, &s, NULL), AMP_OK);
    for (i = 0; i < 2000; i++) {
        double u = rnd(), v = rnd(), w = rnd();
        amp_vec3 p = ev(&s, u, v, w);
        double rho = hypot(p.x, p.y), d = hypot(rho - 50, p.z - 10);
        ck_assert_double_le(d, 10 + 1e-9);
        ck_assert(p.x >= -1e-9 && p.y >= -1e-9);
        if (i % 4 == 0) /* side boundary exactly on the torus */
            ck_assert_near(hypot(hypot(ev(&s, 1, v, w).x, ev(&s, 1, v, w).y) - 50, ev(&s, 1, v, w).z - 10), 10,
                           1e-9);
    }
    amp_spline_free(&s);
    ck_assert_int_eq(amp_trivariate_model("vase", NULL, &s, NULL), AMP_OK);
    for (i = 0; i < 500; i++) {
        double u = rnd(), w = rnd();
        amp_vec3 a = ev(&s, u, rnd(), w), b = ev(&s, u, rnd(), w);
        ck_assert_near(hypot(a.x, a.y), hypot(b.x, b.y), 1e-9);
        ck_assert_near(a.z, b.z, 1e-9);
    }
    {
        /* the wall's cross-section area changes substantially along the height */
        amp_vec3 i0 = ev(&s, 0, 0, 0.45), o0 = ev(&s, 1, 0, 0.45), i1 = ev(&s, 0, 0, 0.8), o1 = ev(&s, 1, 0, 0.8);
        double a0 = AMP_PI * (o0.x * o0.x - i0.x * i0.x), a1 = AMP_PI * (o1.x * o1.x - i1.x * i1.x);
        ck_assert_double_gt(fmax(a0, a1) / fmin(a0, a1), 2.0);
    }
    amp_spline_free(&s);
}
END_TEST

/* ---- the CLI ---- */
static int run_tool(const char *args, const char *stdin_text, char *out, size_t cap)
{
    return fx_run_tool_ex(args, stdin_text ? stdin_text : "", 1, out, cap);
}

START_TEST(cli_model_and_eval_print_full_precision_points)
{
    char args[512], out[4096];
    const char *spl = fx_tmp("helix.spl");
    amp_spline s;
    double x, y, z;
    amp_vec3 e, d;
    snprintf(args, sizeof args, "model helix -o %s", spl);
    ck_assert_int_eq(run_tool(args, NULL, NULL, 0), 0);
    ck_assert_int_eq(amp_trivariate_model("helix", NULL, &s, NULL), AMP_OK);
    snprintf(args, sizeof args, "eval %s", spl);
    ck_assert_int_eq(run_tool(args, "0.25 0.5 0.125\n", out, sizeof out), 0);
    ck_assert_int_eq(sscanf(out, "%lf %lf %lf", &x, &y, &z), 3);
    e = ev(&s, 0.25, 0.5, 0.125);
    /* the file holds Euclidean points: reading them back may differ from memory in the last bit */
    ck_assert_near(x, e.x, 1e-13 * 50);
    ck_assert_near(z, e.z, 1e-13 * 50);
    snprintf(args, sizeof args, "eval %s --derivative w", spl);
    ck_assert_int_eq(run_tool(args, "# comment\n\n0.25 0.5 0.125\n", out, sizeof out), 0);
    ck_assert_int_eq(sscanf(out, "%lf %lf %lf", &x, &y, &z), 3);
    {
        double p[3] = {0.25, 0.5, 0.125};
        int k[3] = {0, 0, 1};
        amp_spline_eval_partial(&s, p, k, &d, NULL);
    }
    ck_assert_near(y, d.y, 1e-12 * amp_v3_len(d));
    /* wrong tuple size, outside the domain, unknown derivative: exit 2 with the stdin line */
    ck_assert_int_eq(run_tool(args, "0.5 0.5\n", out, sizeof out), 2);
    ck_assert_ptr_nonnull(strstr(out, "line 1"));
    snprintf(args, sizeof args, "eval %s", spl);
    ck_assert_int_eq(run_tool(args, "0.5 0.5 0.5\n0.5 0.5 1.5\n", out, sizeof out), 2);
    ck_assert_ptr_nonnull(strstr(out, "outside the domain"));
    snprintf(args, sizeof args, "eval %s --derivative q", spl);
    ck_assert_int_eq(run_tool(args, "0.5 0.5 0.5\n", out, sizeof out), 2);
    /* --json: the points at full precision; a refused line leaves nothing on stdout (not the object of the
     * points before it, well formed, that a caller reading stdout alone would take for the run) */
    snprintf(args, sizeof args, "eval %s --json", spl);
    ck_assert_int_eq(fx_run_tool_ex(args, "0.25 0.5 0.125\n", 0, out, sizeof out), 0);
    ck_assert_int_eq(sscanf(out, "{\"points\":[[%lf,%lf,%lf]],\"count\":1}", &x, &y, &z), 3);
    ck_assert(x == e.x || fabs(x - e.x) <= 1e-13 * 50);
    {
        char again[4096];
        snprintf(args, sizeof args, "eval %s", spl);
        ck_assert_int_eq(fx_run_tool_ex(args, "0.25 0.5 0.125\n", 0, again, sizeof again), 0);
        ck_assert_int_eq(sscanf(again, "%lf", &d.x), 1);
        ck_assert(d.x == x); /* the same 17 digits as the text output */
    }
    snprintf(args, sizeof args, "eval %s --json", spl);
    ck_assert_int_eq(fx_run_tool_ex(args, "0.5 0.5 0.5\n0.5 0.5 1.5\n", 0, out, sizeof out), 2);
    ck_assert_str_eq(out, "");
    /* .stl output gives the mesh of the model; a trivariate-only model gives its tessellated boundary */
    snprintf(args, sizeof args, "model helix -o %s --json", fx_tmp("helix.stl"));
    ck_assert_int_eq(run_tool(args, NULL, out, sizeof out), 0);
    ck_assert_ptr_nonnull(strstr(out, "\"kind\":\"mesh\""));
    remove(fx_tmp("helix.stl"));
    snprintf(args, sizeof args, "model vase -o %s", fx_tmp("vase.stl"));
    ck_assert_int_eq(run_tool(args, NULL, out, sizeof out), 0);
    remove(fx_tmp("vase.stl"));
    ck_assert_int_eq(run_tool("model teapot -o /tmp/teapot.stl", NULL, out, sizeof out), 2);
    ck_assert_ptr_nonnull(strstr(out, "unknown mesh model"));
    ck_assert_int_eq(run_tool("model teapot -o /tmp/x.spl", NULL, out, sizeof out), 2);
    remove(spl);
    amp_spline_free(&s);
}
END_TEST

START_TEST(parser_out_of_memory_is_reported_without_leaks)
{
    fx_failalloc fa;
    amp_spline v, *list;
    amp_buf buf;
    size_t n;
    long budget;
    amp_buf_init(&buf, NULL);
    ck_assert_int_eq(amp_trivariate_model("vase", NULL, &v, NULL), AMP_OK);
    ck_assert_int_eq(amp_spline_write(&v, 1, amp_buf_sink, &buf, NULL), AMP_OK);
    ck_assert_int_eq(amp_spline_write(&v, 0, amp_buf_sink, &buf, NULL), AMP_OK);
    for (budget = 0; budget < 12; budget++) {
        amp_status st;
        fx_failalloc_init(&fa, budget);
        st = amp_spline_parse(buf.data, buf.len, &fa.a, &list, &n, NULL);
        ck_assert(st == AMP_OK || st == AMP_ERR_NOMEM);
        if (st == AMP_OK) {
            ck_assert_uint_eq(n, 2);
            amp_spline_list_free(&fa.a, list, n);
        } else
            ck_assert_ptr_null(list);
    }
    amp_buf_free(&buf);
    amp_spline_free(&v);
}
END_TEST

/* Knot insertion several times over, and refinement, out of memory at every allocation in turn: the spline is
 * left exactly as it was (the first of two insertions used to stay, though spline.h promises no change). */
START_TEST(knot_insertion_out_of_memory_leaves_the_spline_unchanged)
{
    static const double knots[3] = {0.31, 0.62, 0.77};
    amp_spline v;
    int op;
    ck_assert_int_eq(amp_trivariate_model("vase", NULL, &v, NULL), AMP_OK);
    for (op = 0; op < 2; op++) {
        long budget, need = -1;
        for (budget = 0; budget < 1000 && need < 0; budget++) {
            fx_failalloc fa;
            amp_spline c;
            amp_status st;
            int d;
            fx_failalloc_init(&fa, 1L << 30);
            ck_assert_int_eq(amp_spline_copy(&c, &v, &fa.a, NULL), AMP_OK);
            fa.count = 0;
            fa.budget = budget;
            st = op == 0 ? amp_spline_insert_knot(&c, 2, 0.43, 2, NULL) : amp_spline_refine(&c, 0, knots, 3, NULL);
            fa.budget = 1L << 30;
            if (st == AMP_OK)
                need = budget;
            else {
                ck_assert_int_eq(st, AMP_ERR_NOMEM);
                ck_assert_uint_eq(c.ncp, v.ncp);
                for (d = 0; d < 3; d++) {
                    ck_assert_uint_eq(c.count[d], v.count[d]);
                    ck_assert(memcmp(c.knots[d], v.knots[d], (v.count[d] + (size_t)v.order[d]) * sizeof(double)) == 0);
                }
                ck_assert(memcmp(c.cp, v.cp, 4 * v.ncp * sizeof(double)) == 0);
            }
            amp_spline_free(&c);
            ck_assert_msg(fa.live == 0, "budget %ld: %ld blocks left", budget, fa.live);
        }
        ck_assert_msg(need > 1, "op %d: the sweep ended at budget %ld", op, need); /* several allocations failed */
    }
    amp_spline_free(&v);
}
END_TEST

/* An empty spline (fresh from amp_spline_init, or freed) is refused by every evaluator with AMP_ERR_ARG and has
 * no volume or domain; the Python binding's `Trivariate().eval()` crashed in the contraction. */
START_TEST(an_empty_spline_is_refused_by_the_evaluators)
{
    amp_spline s;
    double par[3] = {0.5, 0.5, 0.5}, lo = 1, hi = 1;
    const double *grid[3] = {par, par + 1, par + 2};
    size_t n[3] = {1, 1, 1};
    int k[3] = {0, 0, 0};
    amp_vec3 out[64];
    amp_spline_init(&s);
    ck_assert_int_eq(amp_spline_eval(&s, par, out, NULL), AMP_ERR_ARG);
    ck_assert_int_eq(amp_spline_eval_derivs(&s, par, 1, out, NULL), AMP_ERR_ARG);
    ck_assert_int_eq(amp_spline_eval_partial(&s, par, k, out, NULL), AMP_ERR_ARG);
    ck_assert_int_eq(amp_spline_eval_list(&s, par, 1, out, NULL), AMP_ERR_ARG);
    ck_assert_int_eq(amp_spline_eval_grid(&s, grid, n, out, NULL), AMP_ERR_ARG);
    ck_assert(amp_trivariate_volume(&s) == 0.0);
    amp_spline_domain(&s, 0, &lo, &hi);
    ck_assert(lo == 0.0 && hi == 0.0);
    amp_spline_free(&s);
}
END_TEST

static Suite *spline_suite(void)
{
    Suite *s = suite_create("spline");
    TCase *tc = tcase_create("spline");
    tcase_add_test(tc, rational_quadratic_circle_is_exactly_a_circle);
    tcase_add_test(tc, clamped_bezier_equals_de_casteljau);
    tcase_add_test(tc, derivatives_match_finite_differences_and_the_derivative_spline);
    tcase_add_test(tc, rational_trivariate_partials_match_finite_differences);
    tcase_add_test(tc, knot_insertion_and_refinement_leave_the_shape_unchanged);
    tcase_add_test(tc, knot_insertion_out_of_memory_leaves_the_spline_unchanged);
    tcase_add_test(tc, an_empty_spline_is_refused_by_the_evaluators);
    tcase_add_test(tc, split_halves_reproduce_the_spline);
    tcase_add_test(tc, evaluation_near_knots_is_exact_and_continuous);
    tcase_add_test(tc, isoparametric_extraction_matches_the_trivariate);
    tcase_add_test(tc, reversal_mirrors_the_parameter);
    tcase_add_test(tc, batched_list_and_grid_match_single_points);
    tcase_add_test(tc, shuffled_long_lists_give_the_points_of_sorted_and_short_lists);
    tcase_add_test(tc, control_polygon_bound_holds_and_is_tight_on_a_straight_net);
    tcase_add_test(tc, spl_roundtrip_keeps_several_objects);
    tcase_add_loop_test(tc, malformed_spl_is_rejected_with_line_numbers, 0,
                        (int)(sizeof bad_cases / sizeof bad_cases[0]));
    tcase_add_test(tc, bad_arguments_get_errors_not_undefined_behaviour);
    tcase_add_test(tc, parser_out_of_memory_is_reported_without_leaks);
    tcase_add_test(tc, helix_model_is_within_0_05_mm_of_the_swept_disc);
    tcase_add_test(tc, torus_quarter_and_vase_are_exact_revolutions);
    tcase_add_test(tc, cli_model_and_eval_print_full_precision_points);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(spline_suite)
