/* Material deposition radius (paper §5.2, Def. 5.4). */
#include <math.h>
#include <string.h>

#include "testutil.h"

#define PI 3.14159265358979323846

/* A fan of straight lines from a common hub: their spacing grows along them, so radii must vary. */
static void fan(amp_pathset *ps, int nlines, double spread)
{
    int i, k;
    for (i = 0; i < nlines; i++) {
        double ang = spread * ((double)i / (nlines - 1) - 0.5);
        ck_assert_int_eq(amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
        for (k = 0; k <= 40; k++) {
            double rr = 2.0 + 0.25 * k;
            ck_assert_int_eq(amp_pathset_push(ps, amp_v3(rr * cos(ang), rr * sin(ang), 0.1 * i), 0.5, NULL), AMP_OK);
        }
    }
}

/* Independent overlap check: sampled segment distances (never below the true distance). */
static double sampled_dist(amp_vec3 a0, amp_vec3 a1, amp_vec3 b0, amp_vec3 b1)
{
    double best = HUGE_VAL;
    int i, j;
    for (i = 0; i <= 16; i++)
        for (j = 0; j <= 16; j++)
            best = fmin(best, amp_v3_dist(amp_v3_lerp(a0, a1, i / 16.0), amp_v3_lerp(b0, b1, j / 16.0)));
    return best;
}

/* Segment pairs of different paths whose tubes overlap (r + r' > distance); *checked counts close pairs. */
static size_t overlaps(const amp_pathset *out, double rmax, size_t *checked)
{
    size_t pi, pj, i, k, bad = 0;
    *checked = 0;
    for (pi = 0; pi < out->npaths; pi++)
        for (pj = pi + 1; pj < out->npaths; pj++) {
            const amp_pvert *a = amp_pathset_path_verts(out, pi), *b = amp_pathset_path_verts(out, pj);
            for (i = 0; i + 1 < out->paths[pi].n; i++)
                for (k = 0; k + 1 < out->paths[pj].n; k++) {
                    double ra = fmax(a[i].r, a[i + 1].r), rb = fmax(b[k].r, b[k + 1].r);
                    double d = sampled_dist(a[i].p, a[i + 1].p, b[k].p, b[k + 1].p);
                    if (d > 2 * rmax)
                        continue;
                    (*checked)++;
                    bad += ra + rb > d + 1e-9;
                }
        }
    return bad;
}

START_TEST(tube_radii_stay_in_bounds_and_never_overlap)
{
    amp_pathset ps, out;
    amp_mdr_opts o;
    amp_mdr_stats st;
    amp_error err;
    size_t i, checked = 0;
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out, NULL);
    fan(&ps, 9, 1.2);
    amp_mdr_opts_default(&o, 0.5);
    o.r_min = 0.05;
    o.r_max = 0.8;
    o.fragment = 0.5;
    ck_assert_int_eq(amp_mdr(&ps, &o, &out, &st, &err), AMP_OK);
    ck_assert_uint_eq(out.npaths, ps.npaths);
    ck_assert_near(amp_pathset_length(&out, -1), amp_pathset_length(&ps, -1), 1e-9);
    for (i = 0; i < out.nverts; i++) {
        ck_assert(out.verts[i].r >= o.r_min - 1e-12);
        ck_assert(out.verts[i].r <= o.r_max + 1e-12);
    }
    ck_assert_msg(st.r_hi > 1.5 * st.r_lo, "radii should vary along a fan: %g .. %g", st.r_lo, st.r_hi);
    ck_assert_uint_eq(st.at_min, 0);
    ck_assert_uint_eq(overlaps(&out, o.r_max, &checked), 0);
    ck_assert_uint_gt(checked, 100);
    /* the checker is not blind: the same paths with the largest radius everywhere overlap */
    for (i = 0; i < out.nverts; i++)
        out.verts[i].r = o.r_max;
    ck_assert_uint_gt(overlaps(&out, o.r_max, &checked), 10);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
}
END_TEST

START_TEST(parallel_lines_get_half_their_spacing_and_tubes_fill_the_volume)
{
    amp_pathset ps, out;
    amp_mdr_opts o;
    amp_mdr_stats st;
    amp_error err;
    double vol;
    int i, k;
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out, NULL);
    for (i = 0; i < 6; i++) {
        ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
        for (k = 0; k <= 20; k++)
            ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(k * 0.5, 0.6 * i, 0), 0.5, NULL), AMP_OK);
    }
    amp_mdr_opts_default(&o, 0.5);
    ck_assert_int_eq(amp_mdr(&ps, &o, &out, &st, &err), AMP_OK);
    for (i = 0; i < (int)out.nverts; i++)
        ck_assert_near(out.verts[i].r, 0.3, 1e-9);
    /* no overlap: the union of the tubes holds all deposited material */
    ck_assert_int_eq(amp_tubes_union_volume(&out, 200000, &vol, &err), AMP_OK);
    ck_assert_msg(fabs(st.deposited / vol - 1.0) < 0.08, "over-coverage %g", st.deposited / vol);
    amp_pathset_free(&out);
    amp_pathset_init(&out, NULL);
    /* a single isolated line gets the nominal radius */
    ps.npaths = 1;
    ps.nverts = 21;
    ck_assert_int_eq(amp_mdr(&ps, &o, &out, &st, &err), AMP_OK);
    ck_assert_near(out.verts[0].r, 0.5, 1e-12);
    ck_assert_uint_eq(st.isolated, st.fragments);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
}
END_TEST

START_TEST(bad_mdr_bounds_are_rejected)
{
    amp_pathset ps, out;
    amp_mdr_opts o;
    amp_error err;
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out, NULL);
    fan(&ps, 3, 0.5);
    amp_mdr_opts_default(&o, 0.5);
    o.r_min = 1.0;
    o.r_max = 0.2;
    ck_assert_int_eq(amp_mdr(&ps, &o, &out, NULL, &err), AMP_ERR_RANGE);
    ck_assert_ptr_nonnull(strstr(err.msg, "r_min"));
    amp_mdr_opts_default(&o, -1);
    ck_assert_int_eq(amp_mdr(&ps, &o, &out, NULL, &err), AMP_ERR_RANGE);
    ck_assert_uint_eq(out.npaths, 0);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
}
END_TEST

static Suite *mdr_suite(void)
{
    Suite *s = suite_create("mdr");
    TCase *tc = tcase_create("mdr");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, tube_radii_stay_in_bounds_and_never_overlap);
    tcase_add_test(tc, parallel_lines_get_half_their_spacing_and_tubes_fill_the_volume);
    tcase_add_test(tc, bad_mdr_bounds_are_rejected);
    suite_add_tcase(s, tc);
    return s;
}

AMP_TEST_MAIN(mdr_suite)
