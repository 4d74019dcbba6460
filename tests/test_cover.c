/* Volumetric covering (include/ampath/cover.h): Algorithm 1 + Elber-Cohen curves, checked by the independent gap measurement. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "runtool.h"
#include "testutil.h"

/* The independent coverage measure of @p ps over trivariate @p v (amp_check_coverage). */
static amp_status tri_gap(const amp_spline *v, const amp_pathset *ps, size_t n, unsigned long seed, amp_coverage *g,
                          amp_error *err)
{
    amp_coverage_domain d = {NULL, NULL, 0.0};
    d.trivariate = v;
    return amp_check_coverage(ps, &d, n, seed, g, err);
}

static double cover_gap(const amp_spline *v, const amp_cover_opts *o, amp_cover_stats *st, amp_pathset *keep)
{
    amp_pathset ps;
    amp_coverage g;
    amp_error err;
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(amp_cover_trivariate(v, o, &ps, st, &err), AMP_OK);
    ck_assert_int_eq(tri_gap(v, &ps, 6000, 7, &g, &err), AMP_OK);
    if (keep)
        *keep = ps;
    else
        amp_pathset_free(&ps);
    return g.gap;
}

START_TEST(arclen_covering_of_the_builtin_models_is_within_eps)
{
    static const struct {
        const char *name;
        double eps;
    } cases[] = {{"helix", 2}, {"torus-quarter", 2}, {"vase", 2}, {"vase", 1}};
    size_t i;
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        amp_spline v;
        amp_cover_opts o;
        amp_cover_stats st;
        double gap;
        ck_assert_int_eq(amp_trivariate_model(cases[i].name, NULL, &v, NULL), AMP_OK);
        amp_cover_opts_default(&o);
        o.eps = cases[i].eps;
        gap = cover_gap(&v, &o, &st, NULL);
        ck_assert_msg(gap <= o.eps, "%s eps %g: gap %g", cases[i].name, o.eps, gap);
        ck_assert_msg(gap > 0.25 * o.eps, "%s eps %g: gap %g suspiciously small", cases[i].name, o.eps, gap);
        ck_assert_int_eq(st.depth_limited, 0);
        ck_assert_uint_ge(st.surfaces, 3);
        ck_assert_uint_ge(st.curves, st.surfaces);
        amp_spline_free(&v);
    }
}
END_TEST

typedef struct prog {
    double last;
    int calls, monotone;
} prog;

static void on_progress(void *user, double f)
{
    prog *p = user;
    p->monotone &= f >= p->last && f <= 1.0;
    p->last = f;
    p->calls++;
}

START_TEST(every_vertex_lies_in_the_torus_quarter)
{
    amp_spline v;
    amp_cover_opts o;
    amp_cover_stats st;
    amp_pathset ps;
    size_t i;
    ck_assert_int_eq(amp_trivariate_model("torus-quarter", NULL, &v, NULL), AMP_OK);
    amp_cover_opts_default(&o);
    o.eps = 2;
    o.dir = 1; /* the paper's Fig. 4(f): v-isoparametric surfaces */
    {
        prog pr = {0, 0, 1};
        o.progress = on_progress;
        o.progress_user = &pr;
        ck_assert_double_le(cover_gap(&v, &o, &st, &ps), 2.0);
        ck_assert_int_eq((size_t)pr.calls, st.surfaces);
        ck_assert(pr.monotone);
        ck_assert_near(pr.last, 1.0, 0);
    }
    for (i = 0; i < ps.nverts; i++) {
        amp_vec3 p = ps.verts[i].p;
        ck_assert_double_le(hypot(hypot(p.x, p.y) - 50, p.z - 10), 10 + 1e-9);
        ck_assert(p.x >= -1e-9 && p.y >= -1e-9);
        ck_assert_near(ps.verts[i].r, 0.5, 0);
    }
    ck_assert_near(st.length, amp_pathset_length(&ps, -1), 1e-6 * st.length);
    amp_pathset_free(&ps);
    amp_spline_free(&v);
}
END_TEST

/* Paper Fig. 5: two close surfaces (1 mm apart) whose w-isocurves bulge 7.5 mm sideways in between. */
static void bulge(amp_spline *v)
{
    int k[3] = {2, 2, 3};
    size_t n[3] = {2, 2, 3}, i, j, l;
    ck_assert_int_eq(amp_spline_create(v, NULL, 3, k, n, 0, NULL), AMP_OK);
    for (l = 0; l < 3; l++)
        for (j = 0; j < 2; j++)
            for (i = 0; i < 2; i++)
                amp_spline_cp_set(v, amp_spline_index(v, i, j, l),
                                  amp_v3(10.0 * i + (l == 1 ? 15 : 0), 10.0 * j, l == 0 ? 0 : (l == 1 ? 0.5 : 1)), 1);
}

START_TEST(arclen_measure_closes_the_fig5_gap_that_iso_distance_leaves)
{
    amp_spline v;
    amp_cover_opts o;
    amp_cover_stats st;
    double gap_iso, gap_iso_m, gap_arc;
    bulge(&v);
    amp_cover_opts_default(&o);
    o.eps = 2;
    o.measure = AMP_COVER_ISO;
    gap_iso = cover_gap(&v, &o, &st, NULL);
    ck_assert_uint_eq(st.surfaces, 2); /* Δ_iso <= eps everywhere: Algorithm 1 stops at once */
    ck_assert_msg(gap_iso > 5.0, "iso-distance gap %g", gap_iso);
    o.min_depth = 3;
    gap_iso_m = cover_gap(&v, &o, &st, NULL);
    ck_assert_msg(gap_iso_m <= o.eps, "iso with m = 3: gap %g", gap_iso_m);
    o.min_depth = 0;
    o.measure = AMP_COVER_ARCLEN;
    gap_arc = cover_gap(&v, &o, &st, NULL);
    ck_assert_msg(gap_arc <= o.eps, "arc-length gap %g", gap_arc);
    ck_assert_uint_gt(st.surfaces, 2);
    amp_spline_free(&v);
}
END_TEST

START_TEST(periodic_direction_needs_the_minimal_depth_with_iso_distance)
{
    /* the vase around its axis: V(u, 0, w) = V(u, 1, w), so Δ_iso between the two boundary surfaces is 0 */
    amp_spline v;
    amp_cover_opts o;
    amp_cover_stats st;
    double g0, g2, ga;
    ck_assert_int_eq(amp_trivariate_model("vase", NULL, &v, NULL), AMP_OK);
    amp_cover_opts_default(&o);
    o.eps = 2;
    o.dir = 1;
    o.measure = AMP_COVER_ISO;
    g0 = cover_gap(&v, &o, &st, NULL);
    ck_assert_uint_eq(st.surfaces, 2);
    ck_assert_msg(g0 > 10, "m = 0 gap %g", g0);
    o.min_depth = 2;
    g2 = cover_gap(&v, &o, &st, NULL);
    ck_assert_msg(g2 <= o.eps, "m = 2 gap %g", g2);
    o.min_depth = 0;
    o.measure = AMP_COVER_ARCLEN; /* the arc-length bound needs no m */
    ga = cover_gap(&v, &o, &st, NULL);
    ck_assert_msg(ga <= o.eps, "arc-length gap %g", ga);
    amp_spline_free(&v);
}
END_TEST

START_TEST(gap_measurement_fails_on_a_thinned_covering)
{
    amp_spline v;
    amp_cover_opts o;
    amp_cover_stats st;
    amp_pathset ps, thin;
    amp_coverage g;
    size_t i;
    ck_assert_int_eq(amp_trivariate_model("vase", NULL, &v, NULL), AMP_OK);
    amp_cover_opts_default(&o);
    o.eps = 2;
    ck_assert_double_le(cover_gap(&v, &o, &st, &ps), 2.0);
    /* keep one path in four: the independent measurement must notice */
    amp_pathset_init(&thin, NULL);
    for (i = 0; i < ps.npaths; i += 4)
        ck_assert_int_eq(amp_pathset_add(&thin, AMP_ROLE_OBJECT, amp_pathset_path_verts(&ps, i), ps.paths[i].n, NULL),
                         AMP_OK);
    ck_assert_int_eq(tri_gap(&v, &thin, 6000, 3, &g, NULL), AMP_OK);
    ck_assert_msg(g.gap > o.eps, "thinned covering gap %g", g.gap);
    ck_assert_near(g.volume, amp_trivariate_volume(&v), 1e-9 * g.volume);
    amp_pathset_free(&thin);
    amp_pathset_free(&ps);
    amp_spline_free(&v);
}
END_TEST

START_TEST(volume_and_gap_measurement_agree_with_closed_forms)
{
    /* torus quarter: volume = (pi r^2)(2 pi R)/4; a single path on the centre circle leaves gap 10 (the surface) */
    amp_spline v;
    amp_pathset ps;
    amp_coverage g;
    int i;
    const double PI = AMP_PI;
    ck_assert_int_eq(amp_trivariate_model("torus-quarter", NULL, &v, NULL), AMP_OK);
    ck_assert_near(amp_trivariate_volume(&v), PI * 100 * 2 * PI * 50 / 4, 1e-3);
    amp_pathset_init(&ps, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    for (i = 0; i <= 2000; i++)
        amp_pathset_push(&ps, amp_v3(50 * cos(PI / 2 * i / 2000), 50 * sin(PI / 2 * i / 2000), 10), 0.5, NULL);
    ck_assert_int_eq(tri_gap(&v, &ps, 4000, 5, &g, NULL), AMP_OK);
    ck_assert_near(g.gap, 10.0, 1e-3); /* the corners of the parameter box lie on the boundary */
    amp_pathset_free(&ps);
    amp_spline_free(&v);
}
END_TEST


/* A trilinear trivariate (order 2, 2 x 2 x 2) from its eight corners P(i, j, k) and weights. */
static void trilinear(amp_spline *v, const amp_vec3 *P, const double *w)
{
    int k[3] = {2, 2, 2}, i;
    size_t n[3] = {2, 2, 2};
    ck_assert_int_eq(amp_spline_create(v, NULL, 3, k, n, w != NULL, NULL), AMP_OK);
    for (i = 0; i < 8; i++)
        amp_spline_cp_set(v, amp_spline_index(v, (size_t)(i & 1), (size_t)((i >> 1) & 1), (size_t)(i >> 2)), P[i],
                          w ? w[i] : 1.0);
}

/*
 * Wedge A: x = 16 u, y = 4 v, z = w (0.5 + 15.5 u): the w-curves are 0.5 mm
 * long at u = 0 and 16 mm at u = 1. Covered along w at eps 1 (neighbours
 * within thr = 0.95 mm), the thick end needs 2^5 - 1 = 31 middle surfaces
 * (16 / 2^4 > 0.95 >= 16 / 2^5); the thin end none. Untrimmed, each of those
 * would span the whole 16 mm in u, and Elber-Cohen's halving covers a surface
 * 16 mm wide with curves 16 / 2^5 = 0.5 mm apart (16 / 2^4 > 0.95): 33 curves,
 * 33 * 33 = 1089 in all. Trimmed to the cells whose w-curves are too long
 * (Algorithm 1, lines 6-10), a middle surface of depth k only reaches where
 * h(u) > 0.95 * 2^(k-1): the curves fill the wedge, whose volume is about half
 * its bounding box (mean h 8.25 of 16 mm). Measured: 567 curves.
 */
START_TEST(trimmed_mid_surfaces_cover_a_wedge_with_far_fewer_curves)
{
    amp_vec3 P[8];
    amp_spline v;
    amp_cover_opts o;
    amp_cover_stats st;
    double gap;
    int i;
    for (i = 0; i < 8; i++) {
        int a = i & 1, b = (i >> 1) & 1, c = i >> 2;
        P[i] = amp_v3(16.0 * a, 4.0 * b, c * (0.5 + 15.5 * a));
    }
    trilinear(&v, P, NULL);
    amp_cover_opts_default(&o);
    o.eps = 1.0;
    o.dir = 2;
    gap = cover_gap(&v, &o, &st, NULL);
    ck_assert_msg(gap <= o.eps, "gap %g", gap);
    ck_assert_int_eq(st.depth_limited, 0);
    ck_assert_msg(st.surfaces == 33, "%lu surfaces", (unsigned long)st.surfaces);
    ck_assert_msg(st.curves < 0.6 * 1089, "%lu curves, untrimmed needs 1089", (unsigned long)st.curves);
    amp_spline_free(&v);
}
END_TEST

/*
 * Wedge B: x = u (0.5 + 15.5 v), y = 16 v, z = 4 w: on every w-surface the
 * v-curves at u = 0 and u = 1 are 0.5 mm apart at v = 0 and 16 mm at v = 1.
 * Elber-Cohen adds the middle curve only over the t-cells where its
 * neighbours are too far apart. At v = 1 the halving needs 2^5 - 1 = 31
 * middle curves (16 / 2^4 > 0.95 >= 16 / 2^5); drawn over the whole range,
 * each is 16 mm long: 31 * 16 + 2 * 16 = 528 mm per surface. Drawn where
 * needed, the curves fill the surface's trapezoid, about half the rectangle
 * (mean width 8.25 of 16 mm). Measured: 249 mm per surface.
 */
START_TEST(elber_cohen_mid_curves_cover_only_where_neighbours_drift_apart)
{
    amp_vec3 P[8];
    amp_spline v;
    amp_cover_opts o;
    amp_cover_stats st;
    double gap, per_surface;
    int i;
    for (i = 0; i < 8; i++) {
        int a = i & 1, b = (i >> 1) & 1, c = i >> 2;
        P[i] = amp_v3(a * (0.5 + 15.5 * b), 16.0 * b, 4.0 * c);
    }
    trilinear(&v, P, NULL);
    amp_cover_opts_default(&o);
    o.eps = 1.0;
    o.dir = 2;
    gap = cover_gap(&v, &o, &st, NULL);
    ck_assert_msg(gap <= o.eps, "gap %g", gap);
    per_surface = st.length / (double)st.surfaces;
    ck_assert_msg(per_surface < 0.6 * 528.0, "%g mm per surface (%lu surfaces, %lu curves)", per_surface,
                  (unsigned long)st.surfaces, (unsigned long)st.curves);
    amp_spline_free(&v);
}
END_TEST

/*
 * Lemma A.2 for a rational trivariate: layer k = 1 has weight 100 at one
 * corner. The w-curve at u = 1/2, v = 0 runs from (5, 0, 0) to
 * (100 (0,0,1) + (10,0,1)) / 101 = (0.099, 0, 1): 5.0 mm, while no control
 * edge along w is longer than 1 mm, so the lemma's polynomial bound (the sum
 * of the longest edges) is violated; the weight-ratio correction restores it.
 * Covered along w at eps 2 with one trimming cell (the cell's control block
 * is the whole net; finer cells refine the net by knot insertion, which
 * evens out the weights inside each block), a bound without the correction
 * would see 1 mm curves and add no middle surface: two surfaces 5 mm apart
 * along that curve, against neighbours within thr = 1.9 mm that Algorithm 1
 * promises. (The sampled gap then happens to stay at 0.77 mm, the v-curves
 * crowding where the weight pulls the top surface; the guarantee is lost all
 * the same.) Measured with the correction: 30 surfaces, gap 0.40 mm.
 */
START_TEST(rational_correction_of_lemma_a2_is_needed_and_sufficient)
{
    amp_vec3 P[8];
    double w[8], bound, edge = 0.0, len = 0.0, gap;
    amp_spline v;
    amp_cover_opts o;
    amp_cover_stats st;
    int i;
    for (i = 0; i < 8; i++) {
        int a = i & 1, b = (i >> 1) & 1, c = i >> 2;
        P[i] = amp_v3(10.0 * a, 10.0 * b, c);
        w[i] = i == 4 ? 100.0 : 1.0;
    }
    trilinear(&v, P, w);
    for (i = 0; i < 4; i++)
        edge = fmax(edge, amp_v3_dist(P[i], P[i + 4]));
    {
        double p[3] = {0.5, 0.0, 0.0}, q[3] = {0.5, 0.0, 1.0};
        amp_vec3 x, y;
        amp_spline_eval(&v, p, &x, NULL);
        amp_spline_eval(&v, q, &y, NULL);
        len = amp_v3_dist(x, y); /* the curve is a straight segment (degree 1 in w) */
    }
    ck_assert_msg(len > 4.5 * edge, "curve %g, longest edge %g", len, edge);
    bound = amp_spline_polygon_length_bound(&v, 2, NULL);
    ck_assert_msg(bound >= len, "bound %g < curve length %g", bound, len);
    amp_cover_opts_default(&o);
    o.eps = 2.0;
    o.dir = 2;
    o.cells = 1;
    gap = cover_gap(&v, &o, &st, NULL);
    ck_assert_msg(gap <= o.eps, "gap %g > eps (%lu surfaces)", gap, (unsigned long)st.surfaces);
    /* the 5 mm w-curve must be cut into pieces of at most thr = 1.9 mm: halving needs 4, 3 middle surfaces */
    ck_assert_msg(st.surfaces >= 5, "%lu surfaces", (unsigned long)st.surfaces);
    amp_spline_free(&v);
}
END_TEST


/* The number after "key": in a JSON text (the first occurrence after @p from). */
static double json_after(const char *js, const char *from, const char *key)
{
    char pat[128];
    const char *p = from ? strstr(js, from) : js;
    ck_assert_msg(p != NULL, "%s missing in %s", from, js);
    snprintf(pat, sizeof pat, "\"%s\":", key);
    p = strstr(p, pat);
    ck_assert_msg(p != NULL, "%s missing in %s", key, js);
    return strtod(p + strlen(pat), NULL);
}

/* One over-coverage (cover.h amp_over_coverage): mdr and check report the same figure on the same result. */
START_TEST(mdr_and_check_report_one_over_coverage)
{
    char args[1024], a[8192], b[8192];
    const char *cov = fx_tmp("oc-cover.amp"), *m = fx_tmp("oc-mdr.amp");
    amp_pathset ps;
    amp_spline v;
    amp_error err;
    double om, oc, want;
    snprintf(args, sizeof args, "cover torus-quarter --eps 3 -o %s", cov);
    ck_assert_int_eq(fx_run_tool(args, a, sizeof a), 0);
    /* without --json one line, as every command: the figures and the file written (it printed nothing) */
    ck_assert_msg(strstr(a, "torus-quarter: eps 3 mm, ") == a && strstr(a, " curves, ") && strstr(a, cov) &&
                      strchr(a, '\n') == strrchr(a, '\n'),
                  "%s", a);
    snprintf(args, sizeof args, "mdr %s --nominal 1 --trivariate torus-quarter --json -o %s", cov, m);
    ck_assert_int_eq(fx_run_tool(args, a, sizeof a), 0);
    snprintf(args, sizeof args, "check %s --trivariate torus-quarter --no-gouge --samples 2000 --json", m);
    fx_run_tool(args, b, sizeof b); /* the gap may exceed eps after MDR: only the figure matters here */
    om = json_after(a, NULL, "over_coverage");
    oc = json_after(b, "\"coverage\"", "over_coverage");
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(amp_pathset_read_file(&ps, m, &err), AMP_OK);
    ck_assert_int_eq(amp_trivariate_model("torus-quarter", NULL, &v, NULL), AMP_OK);
    want = amp_pathset_volume(&ps, AMP_ROLE_OBJECT) / amp_trivariate_volume(&v);
    ck_assert_msg(fabs(om - want) <= 1e-6 * want && fabs(oc - want) <= 1e-6 * want, "mdr %g, check %g, want %g", om,
                  oc, want);
    /* without a model mdr does not guess one: null, and the union-of-tubes overlap instead */
    snprintf(args, sizeof args, "mdr %s --nominal 1 --json", cov);
    ck_assert_int_eq(fx_run_tool(args, a, sizeof a), 0);
    ck_assert_ptr_nonnull(strstr(a, "\"over_coverage\":null"));
    ck_assert_msg(json_after(a, NULL, "overlap") > 0.5, "%s", a);
    amp_spline_free(&v);
    amp_pathset_free(&ps);
    remove(cov);
    remove(m);
}
END_TEST

START_TEST(bad_input_is_rejected)
{
    amp_spline v;
    amp_cover_opts o;
    amp_pathset ps;
    amp_error err;
    int k[2] = {2, 2};
    size_t n[2] = {2, 2};
    amp_coverage g;
    amp_pathset_init(&ps, NULL);
    amp_cover_opts_default(&o);
    ck_assert_int_eq(amp_spline_create(&v, NULL, 2, k, n, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_cover_trivariate(&v, &o, &ps, NULL, &err), AMP_ERR_ARG);
    amp_spline_free(&v);
    ck_assert_int_eq(amp_trivariate_model("vase", NULL, &v, NULL), AMP_OK);
    o.eps = 0;
    ck_assert_int_eq(amp_cover_trivariate(&v, &o, &ps, NULL, &err), AMP_ERR_ARG);
    o.eps = 1;
    o.dir = 3;
    ck_assert_int_eq(amp_cover_trivariate(&v, &o, &ps, NULL, &err), AMP_ERR_ARG);
    o.dir = AMP_COVER_AUTO - 1;
    ck_assert_int_eq(amp_cover_trivariate(&v, &o, &ps, NULL, &err), AMP_ERR_ARG);
    ck_assert_int_eq(amp_cover_pick_dir(NULL, &o.dir, NULL, &err), AMP_ERR_ARG);
    ck_assert_int_eq(tri_gap(&v, &ps, 1000, 1, &g, &err), AMP_ERR_ARG); /* no paths */
    ck_assert_uint_eq(ps.npaths, 0);
    amp_spline_free(&v);
}
END_TEST

/* The cuts Algorithm 2 makes in a covering of @p v at eps 4 along direction @p dir (AMP_COVER_AUTO: the
 * chosen one, returned in *chosen). */
static size_t cuts_along(const amp_spline *v, int dir, int *chosen)
{
    amp_cover_opts co;
    amp_cover_stats cs;
    amp_order_opts oo;
    amp_order_stats os;
    amp_pathset a, b;
    amp_error err;
    amp_pathset_init(&a, NULL);
    amp_pathset_init(&b, NULL);
    amp_cover_opts_default(&co);
    co.eps = 4.0;
    co.dir = dir;
    amp_order_opts_default(&oo);
    ck_assert_int_eq(amp_cover_trivariate(v, &co, &a, &cs, &err), AMP_OK);
    ck_assert_int_eq(amp_order(&a, &oo, &b, &os, &err), AMP_OK);
    if (chosen)
        *chosen = cs.dir;
    amp_pathset_free(&a);
    amp_pathset_free(&b);
    return os.subdivisions;
}

/* Beyond [P1 §4.1]: covering along the wrong direction makes curves that climb, and Algorithm 2 cuts them to
 * pieces (the helix along w: 2,001 cuts at eps 4, along u or v 157). The automatic choice must land on a
 * direction whose cuts are within 10 % (plus 20) of the fewest any direction gives, measured by ordering all
 * three: on the helix, the torus quarter, the vase standing and the vase lying on its side. It fails when
 * the choice is removed (always w: the helix) or u and v are told apart the other way (the lying vase). */
START_TEST(the_automatic_direction_covers_with_the_curves_ordering_cuts_least)
{
    const char *names[] = {"helix", "torus-quarter", "vase", "vase"};
    int m;
    for (m = 0; m < 4; m++) {
        amp_spline v;
        size_t c[3], cauto, lo;
        int d, chosen = -1, picked = -1;
        double score[3];
        ck_assert_int_eq(amp_trivariate_model(names[m], NULL, &v, NULL), AMP_OK);
        if (m == 3) { /* lying down: y and z swapped (a mirror image, which does not matter here) */
            size_t i, ncp = v.count[0] * v.count[1] * v.count[2];
            for (i = 0; i < ncp; i++) {
                double w;
                amp_vec3 p = amp_spline_cp_get(&v, i, &w), q = amp_v3(p.x, p.z, p.y);
                amp_spline_cp_set(&v, i, q, w);
            }
        }
        ck_assert_int_eq(amp_cover_pick_dir(&v, &picked, score, NULL), AMP_OK);
        for (d = 0, lo = (size_t)-1; d < 3; d++) {
            c[d] = cuts_along(&v, d, NULL);
            lo = c[d] < lo ? c[d] : lo;
        }
        cauto = cuts_along(&v, AMP_COVER_AUTO, &chosen);
        ck_assert_int_eq(chosen, picked);
        ck_assert_uint_eq(cauto, c[chosen]);
        if (!((double)cauto <= 1.1 * (double)lo + 20.0))
            ck_abort_msg("%s%s: auto chose %c (%lu cuts; scores u %.3f v %.3f w %.3f), cuts u %lu v %lu w %lu",
                         names[m], m == 3 ? " lying" : "", "uvw"[chosen], (unsigned long)cauto, score[0], score[1],
                         score[2], (unsigned long)c[0], (unsigned long)c[1], (unsigned long)c[2]);
        amp_spline_free(&v);
    }
}
END_TEST

/* The tool's stdout and stderr, as a user sees them. */
static int run(const char *args, char *out, size_t cap)
{
    return fx_run_tool_ex(args, NULL, 1, out, cap);
}

START_TEST(cli_cover_and_check_report_and_fail_properly)
{
    char args[1024], out[8192];
    const char *amp = fx_tmp("vase.amp"), *thin = fx_tmp("thin.amp");
    amp_pathset ps, t;
    size_t i;
    snprintf(args, sizeof args, "cover vase --eps 2 --samples 3000 --json -o %s", amp);
    ck_assert_int_eq(run(args, out, sizeof out), 0);
    ck_assert_ptr_nonnull(strstr(out, "\"curves\":"));
    ck_assert_ptr_nonnull(strstr(out, "\"coverage_gap_mm\":"));
    ck_assert_ptr_nonnull(strstr(out, "\"over_coverage\":"));
    ck_assert_int_eq(out[0], '{');
    snprintf(args, sizeof args, "check %s --trivariate vase --samples 3000", amp);
    ck_assert_int_eq(run(args, out, sizeof out), 0);
    ck_assert_ptr_nonnull(strstr(out, "eps 2.0000 mm from path file"));
    /* a thinned file fails the check with exit 1 */
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&t, NULL);
    ck_assert_int_eq(amp_pathset_read_file(&ps, amp, NULL), AMP_OK);
    for (i = 0; i < ps.npaths; i += 3)
        amp_pathset_add(&t, AMP_ROLE_OBJECT, amp_pathset_path_verts(&ps, i), ps.paths[i].n, NULL);
    ck_assert_int_eq(amp_pathset_write_file(&t, thin, NULL, NULL), AMP_OK);
    snprintf(args, sizeof args, "check %s --trivariate vase --eps 2 --samples 3000 --json", thin);
    ck_assert_int_eq(run(args, out, sizeof out), 1);
    ck_assert_ptr_nonnull(strstr(out, "\"ok\":false"));
    ck_assert_int_eq(run("cover vase --eps -1 -o /dev/null", out, sizeof out), 2);
    ck_assert_int_eq(run("cover vase --eps 1 --dir q -o /dev/null", out, sizeof out), 2);
    /* an unknown name is named as one, with the built-ins (it read "nope: nope: No such file or directory") */
    ck_assert_int_eq(run("cover nope --eps 1 -o /dev/null", out, sizeof out), 2);
    ck_assert_ptr_nonnull(strstr(out, "'nope' is neither a built-in trivariate (helix, torus-quarter, vase)"));
    /* the default direction is chosen, and named in the report */
    ck_assert_int_eq(run("cover helix --eps 4 --samples 0 --json -o /dev/null", out, sizeof out), 0);
    ck_assert_ptr_nonnull(strstr(out, "\"dir\":\"v\",\"dir_scores\":{\"u\":"));
    ck_assert_int_eq(run("cover vase --eps 4 --dir auto --samples 0 --json -o /dev/null", out, sizeof out), 0);
    ck_assert_ptr_nonnull(strstr(out, "\"dir\":\"w\""));
    ck_assert_int_eq(run("cover nothing.spl --eps 1 -o /dev/null", out, sizeof out), 2);
    remove(amp);
    remove(thin);
    amp_pathset_free(&ps);
    amp_pathset_free(&t);
}
END_TEST

#ifdef _OPENMP
/* Appends G-code text to a growing buffer. */
typedef struct text_buf {
    char *p;
    size_t n, cap;
} text_buf;

static amp_status text_sink(void *user, const char *data, size_t len)
{
    text_buf *b = user;
    if (b->n + len > b->cap) {
        b->cap = 2 * (b->n + len);
        b->p = realloc(b->p, b->cap);
        ck_assert_ptr_nonnull(b->p);
    }
    memcpy(b->p + b->n, data, len);
    b->n += len;
    return AMP_OK;
}

/* The helix job of `make demo` (coarser), every stage with @p threads OpenMP threads; its G-code in @p g and the
 * ordered paths with their radii in @p ordered. */
static void helix_job(int threads, text_buf *g, amp_pathset *ordered)
{
    amp_spline v;
    amp_cover_opts co;
    amp_order_opts oo;
    amp_mdr_opts mo;
    amp_support_opts so;
    amp_gcode_opts go;
    amp_pathset a, b, c;
    amp_mesh m;
    amp_bvh *bvh = NULL;
    amp_error err;
    omp_set_num_threads(threads);
    amp_spline_init(&v);
    amp_pathset_init(&a, NULL);
    amp_pathset_init(&b, NULL);
    amp_pathset_init(&c, NULL);
    amp_mesh_init(&m, NULL);
    amp_cover_opts_default(&co);
    co.eps = 2.0;
    co.dir = 0;
    amp_order_opts_default(&oo);
    amp_mdr_opts_default(&mo, 0.5);
    amp_support_opts_default(&so);
    amp_gcode_opts_default(&go, AMP_FLAVOR_MARLIN);
    ck_assert_int_eq(amp_trivariate_model("helix", NULL, &v, &err), AMP_OK);
    ck_assert_int_eq(amp_cover_trivariate(&v, &co, &a, NULL, &err), AMP_OK);
    ck_assert_int_eq(amp_order(&a, &oo, &b, NULL, &err), AMP_OK);
    ck_assert_int_eq(amp_mdr(&b, &mo, ordered, NULL, &err), AMP_OK);
    ck_assert_int_eq(amp_mesh_from_trivariate(&m, &v, 0, &err), AMP_OK);
    ck_assert_int_eq(amp_bvh_build(&bvh, &m, &err), AMP_OK);
    ck_assert_int_eq(amp_support(ordered, bvh, &so, &c, NULL, &err), AMP_OK);
    ck_assert_int_eq(amp_gcode_write(&c, &go, text_sink, g, NULL, &err), AMP_OK);
    amp_bvh_free(bvh);
    amp_mesh_free(&m);
    amp_pathset_free(&a);
    amp_pathset_free(&b);
    amp_pathset_free(&c);
    amp_spline_free(&v);
}

/* Speed: the library's parallel parts (coverage, ordering's first queries, MDR neighbour search, support
 * rays) must not change any output: the whole job on 1 and on 2 threads, byte for byte. */
START_TEST(helix_job_is_byte_identical_on_one_and_two_threads)
{
    text_buf g1 = {NULL, 0, 0}, g2 = {NULL, 0, 0};
    amp_pathset p1, p2;
    int saved = omp_get_max_threads();
    amp_pathset_init(&p1, NULL);
    amp_pathset_init(&p2, NULL);
    helix_job(1, &g1, &p1);
    helix_job(2, &g2, &p2);
    omp_set_num_threads(saved);
    fx_assert_same_paths(&p1, &p2);
    ck_assert_uint_gt(g1.n, 100000);
    ck_assert_uint_eq(g1.n, g2.n);
    ck_assert(memcmp(g1.p, g2.p, g1.n) == 0);
    amp_pathset_free(&p1);
    amp_pathset_free(&p2);
    free(g1.p);
    free(g2.p);
}
END_TEST
#endif

static Suite *cover_suite(void)
{
    Suite *s = suite_create("cover");
    TCase *tc = tcase_create("cover");
    tcase_add_test(tc, arclen_covering_of_the_builtin_models_is_within_eps);
    tcase_add_test(tc, every_vertex_lies_in_the_torus_quarter);
    tcase_add_test(tc, arclen_measure_closes_the_fig5_gap_that_iso_distance_leaves);
    tcase_add_test(tc, periodic_direction_needs_the_minimal_depth_with_iso_distance);
    tcase_add_test(tc, the_automatic_direction_covers_with_the_curves_ordering_cuts_least);
    tcase_add_test(tc, gap_measurement_fails_on_a_thinned_covering);
    tcase_add_test(tc, volume_and_gap_measurement_agree_with_closed_forms);
    tcase_add_test(tc, bad_input_is_rejected);
    tcase_add_test(tc, cli_cover_and_check_report_and_fail_properly);
    tcase_add_test(tc, trimmed_mid_surfaces_cover_a_wedge_with_far_fewer_curves);
    tcase_add_test(tc, elber_cohen_mid_curves_cover_only_where_neighbours_drift_apart);
    tcase_add_test(tc, rational_correction_of_lemma_a2_is_needed_and_sufficient);
    tcase_add_test(tc, mdr_and_check_report_one_over_coverage);
#ifdef _OPENMP
    tcase_add_test(tc, helix_job_is_byte_identical_on_one_and_two_threads);
#endif
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(cover_suite)
