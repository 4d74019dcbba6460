/*
 * MDR maximality (paper 1 §5.2, Def. 5.4), checked independently of lib/mdr.c:
 * tubes grow until they touch, so no tube below r_max can grow without
 * overlapping the tube of another path.
 */
#include <math.h>

#include "testutil.h"

/* Straight path along x at (y, z), vertices every 0.25 mm from x = 0 to 10. */
static void line_y(amp_pathset *ps, double y, double z)
{
    int k;
    ck_assert_int_eq(amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
    for (k = 0; k <= 40; k++)
        ck_assert_int_eq(amp_pathset_push(ps, amp_v3(0.25 * k, y, z), 0.5, NULL), AMP_OK);
}

/*
 * Independent maximality: for every vertex v (radius r < r_max - tol) some
 * segment of another path, with tube radius max(r_a, r_b), lies within
 * r + that radius + tol: growing v's tube by tol would overlap it. Vertices
 * with no other path within 2 r_max are isolated (nominal radius by
 * definition, mdr.h) and skipped. Returns the number of vertices that could grow.
 */
static size_t could_grow(const amp_pathset *ps, double r_max, double tol, double *worst)
{
    size_t i, j, k, m, bad = 0;
    *worst = 0.0;
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        for (k = 0; k < ps->paths[i].n; k++) {
            double slack = HUGE_VAL, near = HUGE_VAL;
            if (v[k].r >= r_max - tol)
                continue;
            for (j = 0; j < ps->npaths; j++) {
                const amp_pvert *w = amp_pathset_path_verts(ps, j);
                if (j == i)
                    continue;
                for (m = 0; m + 1 < ps->paths[j].n; m++) {
                    double d = sqrt(amp_v3_seg_dist2(v[k].p, w[m].p, w[m + 1].p, NULL));
                    slack = fmin(slack, d - v[k].r - fmax(w[m].r, w[m + 1].r));
                    near = fmin(near, d);
                }
            }
            if (slack > tol && near <= 2.0 * r_max) {
                bad++;
                *worst = fmax(*worst, slack);
            }
        }
    }
    return bad;
}

/* Radius of the middle vertex of path i. */
static double mid_radius(const amp_pathset *ps, size_t i)
{
    return amp_pathset_path_verts(ps, i)[ps->paths[i].n / 2].r;
}

/*
 * Three parallel lines: A at y = 0, B at y = 1, C at y = 2.6. A and B touch
 * first (r = 0.5) and freeze; C keeps growing until it touches B's frozen
 * tube: r_C = 1.6 - 0.5 = 1.1 (below r_max = 1.5). A tube that stopped at
 * half the distance to its frozen neighbour would end at 0.8.
 */
START_TEST(a_tube_grows_until_it_touches_a_frozen_neighbour)
{
    amp_pathset in, out;
    amp_mdr_opts o;
    amp_mdr_stats st;
    amp_error err;
    double worst;
    amp_pathset_init(&in, NULL);
    amp_pathset_init(&out, NULL);
    line_y(&in, 0.0, 5.0);
    line_y(&in, 1.0, 5.0);
    line_y(&in, 2.6, 5.0);
    amp_mdr_opts_default(&o, 1.0);
    ck_assert_int_eq(amp_mdr(&in, &o, &out, &st, &err), AMP_OK);
    ck_assert_near(mid_radius(&out, 0), 0.5, 1e-6);
    ck_assert_near(mid_radius(&out, 1), 0.5, 1e-6);
    ck_assert_near(mid_radius(&out, 2), 1.1, 1e-6);
    ck_assert_uint_eq(could_grow(&out, o.r_max, 1e-6, &worst), 0);
    amp_pathset_free(&in);
    amp_pathset_free(&out);
}
END_TEST

/*
 * Lines at pseudo-random spacings in two layers 0.9 mm apart: every tube below
 * r_max touches another path's tube.
 */
START_TEST(no_tube_can_grow_without_overlapping_a_neighbour)
{
    amp_pathset in, out;
    amp_mdr_opts o;
    amp_mdr_stats st;
    amp_error err;
    unsigned long x = 12345;
    double y = 0.0, worst;
    int i;
    size_t bad;
    amp_pathset_init(&in, NULL);
    amp_pathset_init(&out, NULL);
    for (i = 0; i < 24; i++) {
        x = x * 1103515245UL + 12345UL;
        y += 0.6 + 0.8 * (double)((x >> 16) & 0x7fff) / 32767.0; /* gaps 0.6 .. 1.4 mm */
        line_y(&in, y, i % 2 ? 5.9 : 5.0);
    }
    amp_mdr_opts_default(&o, 0.5);
    o.r_min = 0.0; /* no clamping from below: every radius is the growth's own */
    ck_assert_int_eq(amp_mdr(&in, &o, &out, &st, &err), AMP_OK);
    ck_assert_uint_gt(st.fragments, 24 * 9);
    bad = could_grow(&out, o.r_max, 1e-6, &worst);
    ck_assert_msg(bad == 0, "%lu vertices could grow by up to %g mm", (unsigned long)bad, worst);
    amp_pathset_free(&in);
    amp_pathset_free(&out);
}
END_TEST

static Suite *mdr_max_suite(void)
{
    Suite *s = suite_create("mdr_maximality");
    TCase *tc = tcase_create("mdr_maximality");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, a_tube_grows_until_it_touches_a_frozen_neighbour);
    tcase_add_test(tc, no_tube_can_grow_without_overlapping_a_neighbour);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(mdr_max_suite)
