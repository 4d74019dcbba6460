/* Support structure (paper §5.3): rays find the volume, support paths are interleaved before the paths above. */
#include <math.h>
#include <string.h>

#include <stdio.h>

#include "runtool.h"
#include "testutil.h"

/* A closed box [x0,x1] x [y0,y1] x [z0,z1], triangles oriented outward. */
static void box_mesh(amp_mesh *m, amp_vec3 lo, amp_vec3 hi)
{
    static const int f[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                 {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
    int i;
    for (i = 0; i < 8; i++) {
        amp_vec3 p = amp_v3((i == 1 || i == 2 || i == 5 || i == 6) ? hi.x : lo.x,
                            (i == 2 || i == 3 || i == 6 || i == 7) ? hi.y : lo.y, i >= 4 ? hi.z : lo.z);
        ck_assert_int_eq(amp_mesh_add_vertex(m, p, NULL, NULL), AMP_OK);
    }
    for (i = 0; i < 12; i++)
        ck_assert_int_eq(amp_mesh_add_tri(m, (uint32_t)f[i][0], (uint32_t)f[i][1], (uint32_t)f[i][2], NULL), AMP_OK);
}

/* Object paths filling a slab 10 x 10 mm from z = 3 to 5 that floats above the plate, in a printable order. */
static void slab_paths(amp_pathset *ps)
{
    double z, y;
    int k;
    for (z = 3.25; z < 5; z += 0.5)
        for (y = 0.25; y < 10; y += 0.5) {
            ck_assert_int_eq(amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
            for (k = 0; k <= 20; k++)
                ck_assert_int_eq(amp_pathset_push(ps, amp_v3(0.25 + 0.475 * k, y, z), 0.25, NULL), AMP_OK);
        }
}

START_TEST(floating_slab_gets_support_printed_before_the_paths_above)
{
    amp_mesh m;
    amp_bvh *b = NULL;
    amp_pathset ps, out, late;
    amp_support_opts o;
    amp_support_stats st;
    amp_error err;
    size_t i, first_obj = (size_t)-1, nsup = 0;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out, NULL);
    amp_pathset_init(&late, NULL);
    box_mesh(&m, amp_v3(0, 0, 3), amp_v3(10, 10, 5));
    ck_assert_int_eq(amp_bvh_build(&b, &m, &err), AMP_OK);
    slab_paths(&ps);
    amp_support_opts_default(&o);
    o.spacing = 1.0;
    ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, &err), AMP_OK);
    ck_assert_uint_eq(st.rays, 11 * 11);
    ck_assert_uint_eq(st.columns, st.rays); /* every ray hits the slab's underside */
    ck_assert_uint_gt(st.paths, 10);
    ck_assert_uint_eq(out.npaths, ps.npaths + st.paths);
    for (i = 0; i < out.npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(&out, i);
        size_t k;
        if (out.paths[i].role == AMP_ROLE_OBJECT) {
            if (first_obj == (size_t)-1)
                first_obj = i;
            continue;
        }
        nsup++;
        for (k = 0; k < out.paths[i].n; k++) {
            ck_assert(v[k].p.z > 0 && v[k].p.z < 3);
            ck_assert(v[k].p.x >= 0 && v[k].p.x <= 10 && v[k].p.y >= 0 && v[k].p.y <= 10);
        }
    }
    ck_assert_uint_eq(nsup, st.paths);
    ck_assert_uint_gt(first_obj, 0); /* the lowest support comes first */
    /* the interleaved order never gouges; support appended after the object does */
    ck_assert_msg(amp_gouge_check(&out, &o.head, AMP_GOUGE_AUTO, AMP_GOUGE_TOL, NULL, &err) == AMP_OK, "%s", err.msg);
    ck_assert_int_eq(amp_pathset_append(&late, &ps, &err), AMP_OK);
    for (i = 0; i < out.npaths; i++)
        if (out.paths[i].role == AMP_ROLE_SUPPORT)
            ck_assert_int_eq(amp_pathset_add(&late, AMP_ROLE_SUPPORT, amp_pathset_path_verts(&out, i), out.paths[i].n, &err),
                             AMP_OK);
    ck_assert_int_eq(amp_gouge_check(&late, &o.head, AMP_GOUGE_AUTO, AMP_GOUGE_TOL, NULL, &err), AMP_ERR_CHECK);
    ck_assert_uint_eq(st.conflicts, 0);
    amp_bvh_free(b);
    amp_mesh_free(&m);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
    amp_pathset_free(&late);
}
END_TEST

START_TEST(model_on_the_plate_needs_no_support_and_bad_options_fail)
{
    amp_mesh m;
    amp_bvh *b = NULL;
    amp_pathset ps, out;
    amp_support_opts o;
    amp_support_stats st;
    amp_error err;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out, NULL);
    box_mesh(&m, amp_v3(0, 0, 0), amp_v3(10, 10, 5));
    ck_assert_int_eq(amp_bvh_build(&b, &m, &err), AMP_OK);
    slab_paths(&ps);
    amp_support_opts_default(&o);
    ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, &err), AMP_OK);
    ck_assert_uint_eq(st.columns, 0);
    ck_assert_uint_eq(out.npaths, ps.npaths);
    o.spacing = 0;
    ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, &err), AMP_ERR_RANGE);
    amp_support_opts_default(&o);
    o.head.theta = 2.0;
    ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, &err), AMP_ERR_RANGE);
    ck_assert_ptr_nonnull(strstr(err.msg, "theta"));
    amp_bvh_free(b);
    amp_mesh_free(&m);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
}
END_TEST

START_TEST(support_command_writes_interleaved_paths_and_rejects_bad_models)
{
    amp_mesh m;
    amp_pathset ps, back;
    amp_error err;
    char args[2048], out[4096];
    const char *stl = amp_test_tmp("slab.stl"), *in = amp_test_tmp("slab.amp"), *res = amp_test_tmp("slab-sup.amp");
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&back, NULL);
    box_mesh(&m, amp_v3(0, 0, 3), amp_v3(10, 10, 5));
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    slab_paths(&ps);
    ck_assert_int_eq(amp_pathset_write_file(&ps, in, NULL, &err), AMP_OK);
    snprintf(args, sizeof args, "support %s --mesh %s --spacing 1 --json -o %s", in, stl, res);
    ck_assert_int_eq(amp_test_run_tool(args, out, sizeof out), 0);
    ck_assert_ptr_nonnull(strstr(out, "\"rays\":121,"));
    ck_assert_int_eq(amp_pathset_read_file(&back, res, &err), AMP_OK);
    ck_assert_uint_gt(back.npaths, ps.npaths);
    ck_assert_int_eq(back.paths[0].role, AMP_ROLE_SUPPORT);
    snprintf(args, sizeof args, "check %s --json", res);
    ck_assert_int_eq(amp_test_run_tool(args, out, sizeof out), 0);
    snprintf(args, sizeof args, "support %s --trivariate no-such.spl -o %s", in, res);
    ck_assert_int_eq(amp_test_run_tool(args, out, sizeof out), 2);
    snprintf(args, sizeof args, "support %s -o %s", in, res);
    ck_assert_int_eq(amp_test_run_tool(args, out, sizeof out), 2);
    remove(stl);
    remove(in);
    remove(res);
    amp_mesh_free(&m);
    amp_pathset_free(&ps);
    amp_pathset_free(&back);
}
END_TEST

/* --trivariate tessellates the trivariate's boundary: the same support as its boundary mesh. */
START_TEST(support_from_a_trivariate_matches_its_boundary_mesh)
{
    char args[2048], a[4096], b[4096];
    const char *stl = amp_test_tmp("tq.stl"), *in = amp_test_tmp("tq.amp"), *res = amp_test_tmp("tq-sup.amp");
    snprintf(args, sizeof args, "cover torus-quarter --eps 3 -o %s", in);
    ck_assert_int_eq(amp_test_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "order %s -o %s", in, in);
    ck_assert_int_eq(amp_test_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "model torus-quarter -o %s", stl);
    ck_assert_int_eq(amp_test_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "support %s --trivariate torus-quarter --json -o %s", in, res);
    ck_assert_int_eq(amp_test_run_tool(args, a, sizeof a), 0);
    snprintf(args, sizeof args, "support %s --mesh %s --json -o %s", in, stl, res);
    ck_assert_int_eq(amp_test_run_tool(args, b, sizeof b), 0);
    /* the torus rests on z = 0 with its lower half overhanging: support is needed */
    ck_assert_msg(strstr(a, "\"support_paths\":0,") == NULL, "%s", a);
    /* the same rays hit the same columns (the tessellations differ a little: the trimming may too) */
    ck_assert_ptr_nonnull(strstr(a, ",\"support_paths\""));
    ck_assert_ptr_nonnull(strstr(b, ",\"support_paths\""));
    *strstr(a, ",\"support_paths\"") = 0;
    *strstr(b, ",\"support_paths\"") = 0;
    ck_assert_str_eq(strstr(a, "\"rays\""), strstr(b, "\"rays\""));
    /* support placed between ordered object paths keeps the whole sequence gouge-free */
    snprintf(args, sizeof args, "check %s --json", res);
    ck_assert_int_eq(amp_test_run_tool(args, a, sizeof a), 0);
    ck_assert_msg(strstr(a, "\"gouge\":{\"ran\":true,\"ok\":true") != NULL, "%s", a);
    remove(stl);
    remove(in);
    remove(res);
}
END_TEST

static Suite *support_suite(void)
{
    Suite *s = suite_create("support");
    TCase *tc = tcase_create("support");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, floating_slab_gets_support_printed_before_the_paths_above);
    tcase_add_test(tc, model_on_the_plate_needs_no_support_and_bad_options_fail);
    tcase_add_test(tc, support_command_writes_interleaved_paths_and_rejects_bad_models);
    tcase_add_test(tc, support_from_a_trivariate_matches_its_boundary_mesh);
    suite_add_tcase(s, tc);
    return s;
}

AMP_TEST_MAIN(support_suite)
