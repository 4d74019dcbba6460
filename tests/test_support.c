/* Support structure (paper §5.3): rays find the volume, support paths are interleaved before the paths above. */
#include <math.h>
#include <string.h>

#include <stdio.h>
#include <stdlib.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "fx_meshes.h"
#include "fx_parts.h"
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

static amp_hold_report hold(const amp_pathset *ps);

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
    /* seven layers (z 0.2 .. 2.6, the slab's underside at 3), each a full 11 x 11 square: one zigzag path each */
    ck_assert_uint_eq(st.paths, 7);
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
            /* rows and their connectors step one ray at a time (the zigzag never jumps across the square) */
            ck_assert(k == 0 || fabs(amp_v3_dist(v[k - 1].p, v[k].p) - 1.0) < 1e-9);
        }
        ck_assert_uint_eq(out.paths[i].n, 121);
    }
    ck_assert_uint_eq(nsup, st.paths);
    ck_assert_uint_gt(first_obj, 0); /* the lowest support comes first */
    /* the interleaved order never gouges; support appended after the object does */
    ck_assert_msg(amp_check_gouge(&out, &o.head, AMP_GOUGE_AUTO, AMP_GOUGE_TOL, NULL, &err) == AMP_OK, "%s", err.msg);
    ck_assert_int_eq(amp_pathset_append(&late, &ps, &err), AMP_OK);
    for (i = 0; i < out.npaths; i++)
        if (out.paths[i].role == AMP_ROLE_SUPPORT)
            ck_assert_int_eq(amp_pathset_add(&late, AMP_ROLE_SUPPORT, amp_pathset_path_verts(&out, i), out.paths[i].n, &err),
                             AMP_OK);
    ck_assert_int_eq(amp_check_gouge(&late, &o.head, AMP_GOUGE_AUTO, AMP_GOUGE_TOL, NULL, &err), AMP_ERR_CHECK);
    ck_assert_uint_eq(st.conflicts, 0);
    amp_bvh_free(b);
    amp_mesh_free(&m);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
    amp_pathset_free(&late);
}
END_TEST

START_TEST(model_on_the_plate_needs_no_rows_its_floating_paths_get_pads_and_bad_options_fail)
{
    amp_hold_report hr;
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
    ck_assert(o.find_unheld == NULL); /* the library links no checker: no pads unless asked */
    ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, &err), AMP_OK);
    ck_assert_uint_eq(st.columns, 0);
    ck_assert_uint_eq(out.npaths, ps.npaths);
    /* the paths themselves float 3 mm over the bed inside the model: the pads hold them */
    hr = hold(&out);
    ck_assert_uint_gt(hr.failures, 0);
    amp_hold_report_free(&hr);
    amp_pathset_clear(&out);
    o.find_unheld = amp_check_hold_runs;
    ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, &err), AMP_OK);
    ck_assert_uint_eq(st.columns, 0);
    ck_assert_uint_gt(st.pads, 0);
    hr = hold(&out);
    ck_assert_uint_eq(hr.failures, 0);
    amp_hold_report_free(&hr);
    o.spacing = 0;
    ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, &err), AMP_ERR_RANGE);
    amp_support_opts_default(&o);
    o.head.theta = 2.0;
    ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, &err), AMP_ERR_RANGE);
    ck_assert_ptr_nonnull(strstr(err.msg, "theta"));
    /* nothing to support: refused at once (it used to search slots forever) */
    amp_support_opts_default(&o);
    ps.npaths = ps.nverts = 0;
    ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, &err), AMP_ERR_ARG);
    ck_assert_ptr_nonnull(strstr(err.msg, "no object path"));
    amp_bvh_free(b);
    amp_mesh_free(&m);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
}
END_TEST

START_TEST(support_command_refuses_a_file_without_paths)
{
    /* a field that missed the mesh leaves a file with no path: support spun
     * without end on it; now exit 2 with a reason and no output */
    amp_mesh m;
    amp_error err;
    char args[2048], out[4096];
    const char *stl = fx_tmp("slab0.stl"), *in = fx_tmp("empty0.amp"), *res = fx_tmp("empty0-sup.amp");
    FILE *f;
    amp_mesh_init(&m, NULL);
    box_mesh(&m, amp_v3(0, 0, 3), amp_v3(10, 10, 5));
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    f = fopen(in, "w");
    ck_assert_ptr_nonnull(f);
    fputs("ampath-paths 1\n", f);
    fclose(f);
    remove(res);
    snprintf(args, sizeof args, "support %s --mesh %s -o %s", in, stl, res);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 2);
    f = fopen(res, "r");
    ck_assert_msg(f == NULL, "no output written");
    remove(stl);
    remove(in);
    amp_mesh_free(&m);
}
END_TEST

/*
 * The support starts on the bed the job is printed on (`gcode` rests the lowest bead on it). A floor of object
 * beads beside a floating slab: centred on z = 0 (bead bottoms at -0.3, as the helix's first curves), or half a
 * field spacing up (bottoms at 0.5, within min_gap of the plate): the lowest support rows lie at that bottom,
 * and every support layer is a whole number of layer heights above them. A floor whose beads float min_gap or
 * more above the plate (bottoms at 1.7) does not rest on it: the support starts at z = 0.
 */
START_TEST(support_rows_start_on_the_lowest_bead_bottom)
{
    static const double floor_z[] = {0.0, 0.8, 2.0}, plate[] = {-0.3, 0.5, 0.0};
    amp_mesh m;
    amp_bvh *b = NULL;
    amp_support_opts o;
    size_t c;
    amp_mesh_init(&m, NULL);
    box_mesh(&m, amp_v3(0, 0, 3), amp_v3(10, 10, 5));
    ck_assert_int_eq(amp_bvh_build(&b, &m, NULL), AMP_OK);
    amp_support_opts_default(&o);
    o.spacing = 1.0;
    for (c = 0; c < 3; c++) {
        amp_pathset ps, out;
        amp_support_stats st;
        double lowest = HUGE_VAL;
        size_t i, k;
        int y;
        amp_pathset_init(&ps, NULL);
        amp_pathset_init(&out, NULL);
        for (y = 0; y < 4; y++) { /* the floor beside the slab: tubes of radius 0.3 */
            ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
            ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(20, 0.6 * y, floor_z[c]), 0.3, NULL), AMP_OK);
            ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(30, 0.6 * y, floor_z[c]), 0.3, NULL), AMP_OK);
        }
        slab_paths(&ps);
        ck_assert_int_eq(amp_support(&ps, b, &o, &out, &st, NULL), AMP_OK);
        ck_assert_uint_ge(st.paths, 6);
        for (i = 0; i < out.npaths; i++) {
            const amp_pvert *v = amp_pathset_path_verts(&out, i);
            if (out.paths[i].role != AMP_ROLE_SUPPORT)
                continue;
            for (k = 0; k < out.paths[i].n; k++) {
                double layers = (v[k].p.z - v[k].r - plate[c]) / o.layer_height;
                lowest = fmin(lowest, v[k].p.z - v[k].r);
                ck_assert_double_eq_tol(layers, floor(layers + 0.5), 1e-9);
            }
        }
        ck_assert_msg(fabs(lowest - plate[c]) < 1e-12, "floor at z %g: support from %g, not %g", floor_z[c], lowest,
                      plate[c]);
        amp_pathset_free(&out);
        amp_pathset_free(&ps);
    }
    amp_bvh_free(b);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(support_command_writes_interleaved_paths_and_rejects_bad_models)
{
    amp_mesh m;
    amp_pathset ps, back;
    amp_error err;
    char args[2048], out[4096];
    const char *stl = fx_tmp("slab.stl"), *in = fx_tmp("slab.amp"), *res = fx_tmp("slab-sup.amp");
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&back, NULL);
    box_mesh(&m, amp_v3(0, 0, 3), amp_v3(10, 10, 5));
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    slab_paths(&ps);
    ck_assert_int_eq(amp_pathset_write_file(&ps, in, NULL, &err), AMP_OK);
    snprintf(args, sizeof args, "support %s --mesh %s --spacing 1 --json -o %s", in, stl, res);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_ptr_nonnull(strstr(out, "\"rays\":121,"));
    ck_assert_int_eq(amp_pathset_read_file(&back, res, &err), AMP_OK);
    ck_assert_uint_gt(back.npaths, ps.npaths);
    ck_assert_int_eq(back.paths[0].role, AMP_ROLE_SUPPORT);
    snprintf(args, sizeof args, "check %s --json", res);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    snprintf(args, sizeof args, "support %s --trivariate no-such.spl -o %s", in, res);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 2);
    snprintf(args, sizeof args, "support %s -o %s", in, res);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 2);
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
    const char *stl = fx_tmp("tq.stl"), *in = fx_tmp("tq.amp"), *res = fx_tmp("tq-sup.amp");
    /* the paper's direction: at eps 3 its short steep curves all rest on something, where the level arcs
     * of the chosen direction lie 3 mm apart and the check's support part (1 mm gaps) fails them */
    snprintf(args, sizeof args, "cover torus-quarter --eps 3 --dir w -o %s", in);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "order %s -o %s", in, in);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "model torus-quarter -o %s", stl);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "support %s --trivariate torus-quarter --json -o %s", in, res);
    ck_assert_int_eq(fx_run_tool(args, a, sizeof a), 0);
    snprintf(args, sizeof args, "support %s --mesh %s --json -o %s", in, stl, res);
    ck_assert_int_eq(fx_run_tool(args, b, sizeof b), 0);
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
    ck_assert_int_eq(fx_run_tool(args, a, sizeof a), 0);
    ck_assert_msg(strstr(a, "\"gouge\":{\"ran\":true,\"ok\":true") != NULL, "%s", a);
    remove(stl);
    remove(in);
    remove(res);
}
END_TEST


/* Sum of the lengths of the paths of one role; counts the paths of zero length. */
static double role_length(const amp_pathset *ps, amp_role role, size_t *zero)
{
    double sum = 0.0;
    size_t i;
    *zero = 0;
    for (i = 0; i < ps->npaths; i++)
        if (ps->paths[i].role == role) {
            double l = amp_path_length(ps, i);
            sum += l;
            *zero += !(l > 0.0);
        }
    return sum;
}

/* The length of the shortest support path of the paths file @p file. */
static double shortest_support(const char *file)
{
    amp_pathset ps;
    amp_error err;
    double m = HUGE_VAL;
    size_t i;
    amp_pathset_init(&ps, NULL);
    ck_assert_msg(amp_pathset_read_file(&ps, file, &err) == AMP_OK, "%s", err.msg);
    for (i = 0; i < ps.npaths; i++)
        if (ps.paths[i].role == AMP_ROLE_SUPPORT)
            m = fmin(m, amp_path_length(&ps, i));
    amp_pathset_free(&ps);
    return m;
}

/* A number after "key": in a JSON text. */
static double json_num(const char *js, const char *key)
{
    char pat[128];
    const char *p;
    snprintf(pat, sizeof pat, "\"%s\":", key);
    p = strstr(js, pat);
    ck_assert_msg(p != NULL, "%s missing in %s", key, js);
    return strtod(p + strlen(pat), NULL);
}

/*
 * The helix covered along u at eps 2 mm and ordered: its support used to drop
 * 9,356 fragments (4,470 mm, 17 % of the rows) that had no gouge-free slot
 * between whole object paths. Slots between object fragments (splitting an
 * object path where needed) exist for every fragment (Lemma 5.1 argument in
 * lib/support.c): nothing is dropped, no path has zero length, the sequence
 * is gouge-free and every object path is held; the same job without its
 * support fails the support check.
 */
START_TEST(helix_support_keeps_every_fragment_and_holds_every_path)
{
    char args[2048], js[16384];
    const char *cov = fx_tmp("hx-u2.amp"), *ord = fx_tmp("hx-u2o.amp"), *res = fx_tmp("hx-u2s.amp");
    amp_pathset out;
    amp_error err;
    size_t zero;
    double made, kept;
    amp_pathset_init(&out, NULL);
    snprintf(args, sizeof args, "cover helix --eps 2 --dir u -o %s", cov);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "order %s -o %s", cov, ord);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "support %s --trivariate helix --json -o %s", ord, res);
    ck_assert_int_eq(fx_run_tool(args, js, sizeof js), 0);
    ck_assert_msg(json_num(js, "conflicts") == 0 && json_num(js, "trimmed_mm") == 0, "%s", js);
    ck_assert_msg(json_num(js, "unheld_paths") == 0, "%s", js);
    made = json_num(js, "support_length_mm") + json_num(js, "pad_length_mm");
    ck_assert_int_eq(amp_pathset_read_file(&out, res, &err), AMP_OK);
    kept = role_length(&out, AMP_ROLE_SUPPORT, &zero);
    ck_assert_uint_eq(zero, 0);
    ck_assert_msg(made > 20000.0 && fabs(kept - made) <= 1e-6 * made, "made %g mm, printed %g mm", made, kept);
    role_length(&out, AMP_ROLE_OBJECT, &zero);
    ck_assert_uint_eq(zero, 0);
    snprintf(args, sizeof args, "check %s --no-coverage --json", res);
    ck_assert_int_eq(fx_run_tool(args, js, sizeof js), 0);
    ck_assert_msg(strstr(js, "\"gouge\":{\"ran\":true,\"ok\":true") != NULL, "%s", js);
    ck_assert_msg(strstr(js, "\"support\":{\"ran\":true,\"ok\":true") != NULL, "%s", js);
    /* the ordered job without support: object beads in the air under the overhang */
    snprintf(args, sizeof args, "check %s --no-coverage --no-gouge --support --json", ord);
    ck_assert_int_eq(fx_run_tool(args, js, sizeof js), 1);
    ck_assert_msg(json_num(js, "unheld_paths") >= 10 && json_num(js, "unheld_mm") > 100.0, "%s", js);
    /* without --support a job with no support paths is not judged */
    snprintf(args, sizeof args, "check %s --no-coverage --no-gouge --json", ord);
    ck_assert_int_eq(fx_run_tool(args, js, sizeof js), 0);
    ck_assert_msg(strstr(js, "\"support\":{\"ran\":false") != NULL, "%s", js);
    amp_pathset_free(&out);
    remove(cov);
    remove(ord);
    remove(res);
}
END_TEST

/* field box -> order -> mdr -> support [--no-pads] of @p stl; returns the support's JSON in js. */
static void field_job(const char *stl, const char *tag, double spacing, const char *pads, char *js, size_t cap,
                      const char **res)
{
    char args[2048], name[64];
    const char *cov, *ord, *mdr;
    snprintf(name, sizeof name, "%s-f.amp", tag);
    cov = fx_tmp(name);
    snprintf(args, sizeof args, "field %s --field box --spacing %g -o %s", stl, spacing, cov);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(name, sizeof name, "%s-o.amp", tag);
    ord = fx_tmp(name);
    snprintf(args, sizeof args, "order %s -o %s", cov, ord);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(name, sizeof name, "%s-m.amp", tag);
    mdr = fx_tmp(name);
    snprintf(args, sizeof args, "mdr %s --nominal 0.5 --mesh %s -o %s", ord, stl, mdr);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(name, sizeof name, "%s-s%s.amp", tag, pads);
    *res = fx_tmp(name);
    snprintf(args, sizeof args, "support %s --mesh %s %s --json -o %s", mdr, stl, pads, *res);
    ck_assert_int_eq(fx_run_tool_ex(args, NULL, 1, js, cap), 0); /* the JSON, then stderr */
    remove(cov);
    remove(ord);
    remove(mdr);
}

/*
 * A sphere and a torus lying on the bed, covered by a field: over the shallow rim of their undersides the
 * rays find less than min_gap of air and put no support, yet the first row of curves there floats more
 * than min_gap up. The pads hold it: `ampath check` (held paths, no gouging) passes with them and fails
 * without them (--no-pads).
 */
START_TEST(pads_hold_the_lowest_rows_of_a_field_over_a_shallow_underside)
{
    static const char *const tags[] = {"sphere", "torus"};
    char js[16384], args[2048], stl[1024];
    const char *res;
    int k;
    for (k = 0; k < 2; k++) {
        amp_mesh m;
        amp_error err;
        amp_mesh_init(&m, NULL);
        if (k == 0)
            ck_assert_int_eq(fx_sphere(&m, amp_v3(0, 0, 15), 15, 64, 32), AMP_OK);
        else
            ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 2.83), 11.44, 2.83, 96, 32), AMP_OK); /* PrusaSlicer's */
        snprintf(args, sizeof args, "%s.stl", tags[k]);
        snprintf(stl, sizeof stl, "%s", fx_tmp(args)); /* fx_tmp's buffers are reused */
        ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
        amp_mesh_free(&m);
        field_job(stl, tags[k], 1.0, "--no-pads", js, sizeof js, &res);
        ck_assert_msg(json_num(js, "pads") == 0 && json_num(js, "unheld_paths") > 0, "%s: %s", tags[k], js);
        snprintf(args, sizeof args, "check %s --mesh %s --json", res, stl);
        ck_assert_int_eq(fx_run_tool(args, NULL, 0), 1);
        remove(res);
        field_job(stl, tags[k], 1.0, "", js, sizeof js, &res);
        ck_assert_msg(!strstr(js, "do not rest on each other"), "%s: %s", tags[k], js);
        ck_assert_msg(json_num(js, "pads") > 0 && json_num(js, "unheld_paths") == 0, "%s: %s", tags[k], js);
        ck_assert_msg(json_num(js, "conflicts") == 0, "%s: %s", tags[k], js);
        /* no pad is a speck: a stretch of samples at the ends of a short segment (14 pads under 0.2 mm on the
         * sphere, 6 on the torus) is a stroke of a sample step */
        ck_assert_uint_eq(shortest_support(res) >= 0.25 - 1e-9, 1);
        snprintf(args, sizeof args, "check %s --mesh %s --json", res, stl);
        ck_assert_msg(fx_run_tool(args, js, sizeof js) == 0, "%s: %s", tags[k], js);
        remove(res);
        remove(stl);
    }
}
END_TEST

/* A covering whose rows are spaced wider than their beads (box field at spacing 3, mdr's nominal 0.5) does
 * not rest on itself: its pads come to most of its length, and `support` says so on stderr (at spacing 1,
 * pads a few millimetres, nothing said). */
START_TEST(support_warns_when_the_rows_do_not_rest_on_each_other)
{
    char js[16384], stl[1024];
    const char *res;
    amp_mesh m;
    amp_error err;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_sphere(&m, amp_v3(0, 0, 8), 8, 48, 24), AMP_OK);
    snprintf(stl, sizeof stl, "%s", fx_tmp("wide.stl"));
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    amp_mesh_free(&m);
    field_job(stl, "wide", 3.0, "", js, sizeof js, &res);
    ck_assert_msg(json_num(js, "pads") > 0 && strstr(js, "do not rest on each other"), "%s", js);
    remove(res);
    field_job(stl, "wide", 1.0, "", js, sizeof js, &res);
    ck_assert_msg(json_num(js, "pads") > 0 && !strstr(js, "do not rest on each other"), "%s", js);
    remove(res);
    remove(stl);
}
END_TEST

/* Height of the mesh's underside straight above @p p (the first surface a ray up meets); HUGE_VAL if none. */
static double underside_above(const amp_bvh *b, amp_vec3 p)
{
    amp_bvh_hit *hits = NULL;
    size_t n = 0, k;
    double z = HUGE_VAL;
    ck_assert_int_eq(amp_bvh_ray_all(b, p, amp_v3(0, 0, 1), HUGE_VAL, &hits, &n, NULL), AMP_OK);
    for (k = 0; k < n; k++)
        z = fmin(z, hits[k].p.z);
    amp_bvh_hits_free(b, hits);
    return z;
}

/*
 * A sliced job (`slice --continuous`, 0.3 mm first layer, 0.2 mm layers) of the blobby bunny (head and ears
 * overhang its body): its support is laid on the job's own layers as planar beads of the layer's height
 * (round tubes 0.4 mm apart would extrude the wrong plastic and stand between the layers), printed with each
 * layer before the object beads of that layer (heights never go down along the job), its top one layer
 * under the underside above it; `check --layer --support` passes it (strokes, gouge, every bead held).
 */
START_TEST(a_sliced_job_gets_planar_support_on_its_own_layers)
{
    char args[4096], js[16384], stl[1024], sl[1024], sup[1024];
    amp_mesh m;
    amp_bvh *b = NULL;
    amp_pathset ps;
    amp_error err;
    size_t i, k, nsup = 0;
    double zlast = 0.0;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(fx_part_mesh(&m, FX_PART_BUNNY, 0.0), AMP_OK);
    snprintf(stl, sizeof stl, "%s", fx_tmp("sbunny.stl"));
    snprintf(sl, sizeof sl, "%s", fx_tmp("sbunny.amp"));
    snprintf(sup, sizeof sup, "%s", fx_tmp("sbunny-sup.amp"));
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    ck_assert_int_eq(amp_bvh_build(&b, &m, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.2 --first-layer 0.3 --continuous -o %s", stl, sl);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "support %s --mesh %s -o %s --json", sl, stl, sup);
    ck_assert_int_eq(fx_run_tool(args, js, sizeof js), 0);
    ck_assert_msg(strstr(js, "\"layer\":0.2,\"sliced\":true") != NULL, "%s", js);
    ck_assert_int_eq(amp_pathset_read_file(&ps, sup, &err), AMP_OK);
    for (i = 0; i < ps.npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(&ps, i);
        double z = v[0].p.z, layer = (z - 0.3) / 0.2, h = ps.paths[i].h;
        ck_assert_msg(z >= zlast - 1e-9, "path %lu at z %g after z %g", (unsigned long)i, z, zlast);
        zlast = z;
        if (ps.paths[i].role != AMP_ROLE_SUPPORT)
            continue;
        nsup++;
        ck_assert_msg(fabs(layer - floor(layer + 0.5)) < 1e-6, "support path %lu at z %g: not a layer", (unsigned long)i, z);
        ck_assert_msg(fabs(h - (z < 0.31 ? 0.3 : 0.2)) < 1e-9, "support path %lu at z %g has bead height %g",
                      (unsigned long)i, z, h);
        for (k = 0; k < ps.paths[i].n; k++) {
            ck_assert(fabs(v[k].p.z - z) < 1e-9);
            /* on the grid's rays (a lone ray's short row ends a quarter spacing off them) */
            if (ps.paths[i].n > 2 || amp_path_length(&ps, i) > 0.6)
                ck_assert_msg(underside_above(b, v[k].p) >= z + 0.5 * h - 1e-6, "support at (%g %g %g) reaches the part",
                              v[k].p.x, v[k].p.y, z);
        }
    }
    ck_assert_uint_gt(nsup, 50);
    snprintf(args, sizeof args, "check %s --mesh %s --layer 0.2 --first-layer 0.3 --support --json", sup, stl);
    ck_assert_msg(fx_run_tool(args, js, sizeof js) == 0, "%s", js);
    amp_pathset_free(&ps);
    amp_bvh_free(b);
    amp_mesh_free(&m);
    remove(stl);
    remove(sl);
    remove(sup);
}
END_TEST

/* One straight object path from a to b, radius r, sampled in vertices 0.5 mm apart or closer. */
static void line_path(amp_pathset *ps, amp_role role, amp_vec3 a, amp_vec3 b, double r)
{
    size_t k, n = (size_t)ceil(amp_v3_dist(a, b) / 0.5);
    ck_assert_int_eq(amp_pathset_begin(ps, role, NULL), AMP_OK);
    for (k = 0; k <= n; k++)
        ck_assert_int_eq(amp_pathset_push(ps, amp_v3_lerp(a, b, (double)k / (double)n), r, NULL), AMP_OK);
}

static amp_hold_report hold(const amp_pathset *ps)
{
    amp_hold_opts o;
    amp_hold_report r;
    amp_error err;
    amp_hold_opts_default(&o);
    ck_assert_msg(amp_check_hold(ps, &o, &r, &err) == AMP_OK, "%s", err.msg);
    return r;
}

/* A floating slab is not held; the same slab on its support is; the support printed after it is not. */
START_TEST(hold_check_needs_material_printed_earlier_under_each_bead)
{
    amp_pathset slab, sup, both, late;
    amp_hold_report r;
    amp_error err;
    double x, z;
    amp_pathset_init(&slab, NULL);
    amp_pathset_init(&sup, NULL);
    amp_pathset_init(&both, NULL);
    amp_pathset_init(&late, NULL);
    slab_paths(&slab); /* z 3.25 .. 4.75, beads of radius 0.25 */
    r = hold(&slab);
    ck_assert_uint_gt(r.failures, 0);
    ck_assert_uint_eq(r.npaths_failed, 20); /* the 20 rows of the first layer; every layer above rests on it */
    ck_assert_uint_eq(r.paths_failed[0], 0);
    ck_assert_uint_eq(r.paths_failed[19], 19);
    amp_hold_report_free(&r);
    /* support: rows across the slab rows, every 0.4 mm up to 2.8 mm, 1 mm apart */
    for (z = 0.4; z < 2.9; z += 0.4)
        for (x = 0.5; x < 10; x += 1.0)
            line_path(&sup, AMP_ROLE_SUPPORT, amp_v3(x, 0, z), amp_v3(x, 10, z), 0.2);
    ck_assert_int_eq(amp_pathset_append(&both, &sup, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_append(&both, &slab, &err), AMP_OK);
    r = hold(&both);
    ck_assert_uint_eq(r.failures, 0);
    ck_assert_uint_gt(r.samples, 1500); /* 80 rows of 9.5 mm, every 0.25 mm */
    amp_hold_report_free(&r);
    ck_assert_int_eq(amp_pathset_append(&late, &slab, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_append(&late, &sup, &err), AMP_OK);
    r = hold(&late);
    ck_assert_uint_eq(r.npaths_failed, 20);
    amp_hold_report_free(&r);
    amp_pathset_free(&slab);
    amp_pathset_free(&sup);
    amp_pathset_free(&both);
    amp_pathset_free(&late);
}
END_TEST

/* Rows along x over a 10 x 10 x 4 mm box on the bed, radius 0.25, named by letter, in the order of @p names;
 * supported with the pads' judge, the result checked gouge-free; its object rows by name into @p got. */
static amp_support_stats settle_rows(const char *names, char *got, amp_hold_report *hr)
{
    static const struct {
        char name;
        double x0, x1, y, z;
    } rows[] = {{'T', 0.5, 9.5, 5, 0.25}, {'X', 8, 9.5, 4, 0.25}, {'A', 0.5, 9.5, 5, 1.5}, {'B', 0.5, 3, 5, 1.9}};
    amp_mesh m;
    amp_bvh *b = NULL;
    amp_pathset ps, out;
    amp_support_opts o;
    amp_support_stats st;
    amp_error err;
    size_t i, k, n = 0;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out, NULL);
    box_mesh(&m, amp_v3(0, 0, 0), amp_v3(10, 10, 4));
    ck_assert_int_eq(amp_bvh_build(&b, &m, &err), AMP_OK);
    for (i = 0; names[i]; i++)
        for (k = 0; k < sizeof rows / sizeof rows[0]; k++)
            if (rows[k].name == names[i])
                line_path(&ps, AMP_ROLE_OBJECT, amp_v3(rows[k].x0, rows[k].y, rows[k].z),
                          amp_v3(rows[k].x1, rows[k].y, rows[k].z), 0.25);
    amp_support_opts_default(&o);
    ck_assert_msg(amp_check_gouge(&ps, &o.head, AMP_GOUGE_AUTO, AMP_GOUGE_TOL, NULL, &err) == AMP_OK, "%s", err.msg);
    o.find_unheld = amp_check_hold_runs;
    ck_assert_msg(amp_support(&ps, b, &o, &out, &st, &err) == AMP_OK, "%s", err.msg);
    ck_assert_msg(amp_check_gouge(&out, &o.head, AMP_GOUGE_AUTO, AMP_GOUGE_TOL, NULL, &err) == AMP_OK, "%s", err.msg);
    for (i = 0; i < out.npaths; i++) {
        amp_vec3 p = amp_pathset_path_verts(&out, i)[0].p;
        for (k = 0; out.paths[i].role == AMP_ROLE_OBJECT && k < sizeof rows / sizeof rows[0]; k++)
            if (fabs(p.y - rows[k].y) < 1e-9 && fabs(p.z - rows[k].z) < 1e-9 && fabs(p.x - rows[k].x0) < 1e-9)
                got[n++] = rows[k].name;
    }
    got[n] = 0;
    *hr = hold(&out);
    amp_bvh_free(b);
    amp_mesh_free(&m);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
    return st;
}

/*
 * Two beads stacked less than z_offs apart are in no Def. 5.1 relation, so the ordering may print the upper one
 * first, in the air with no room for a pad under it (CGAL's camel, man, cheese and hand covered by a 1 mm field;
 * exactly z_offs apart the cone's tip touches the upper one, which counts since AMP_CONE_TOL < 0). Row B rests
 * 0.4 mm over row A alone (T, on the bed under both, is 1.15 mm under B's bead). Printed T B A, A moves before
 * B; printed T B X A, the short row X under A's far end must come before A, so B moves after A instead.
 */
START_TEST(an_object_bead_is_not_printed_before_the_bead_it_rests_on)
{
    static const char *const in[] = {"TBA", "TBXA", "TAB"}, *const want[] = {"TAB", "TXAB", "TAB"};
    char got[8];
    int i;
    for (i = 0; i < 3; i++) {
        amp_hold_report hr;
        amp_support_stats st = settle_rows(in[i], got, &hr);
        ck_assert_msg(strcmp(got, want[i]) == 0, "%s: printed %s", in[i], got);
        ck_assert_uint_eq(st.settled, i < 2);
        ck_assert_uint_eq(hr.failures, 0);
        amp_hold_report_free(&hr);
    }
}
END_TEST

/* A job of pseudo edges only (radius 0: nothing printed) has no bead to hold and none to check: the check ends at
 * once (the grid over no sample was sized from an empty box's infinite extent and grew its cells forever: a
 * black-box run of `ampath support` on such a file never ended). */
START_TEST(hold_check_of_a_job_with_nothing_printed_ends_at_once)
{
    amp_pathset ps;
    amp_hold_report r;
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
    ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(5, 5, 5), 0.0, NULL), AMP_OK);
    ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(6, 5, 5), 0.0, NULL), AMP_OK);
    r = hold(&ps);
    ck_assert_uint_eq(r.failures, 0);
    amp_hold_report_free(&r);
    amp_pathset_free(&ps);
}
END_TEST

/* Bridges between two pillars: up to 5 mm pass, longer ones fail; a short tip off a pillar passes. */
START_TEST(hold_check_allows_short_bridges_and_tips_only)
{
    static const double span[3] = {4.0, 8.0, 0.0};
    int t;
    for (t = 0; t < 3; t++) {
        amp_pathset ps;
        amp_hold_report r;
        double z, x1 = 1.0 + span[t];
        amp_pathset_init(&ps, NULL);
        /* two pillars of stacked short beads from the bed up to z 4.8 at x = 0 and x = x1 (one for the tip) */
        for (z = 0.2; z < 4.9; z += 0.4) {
            line_path(&ps, AMP_ROLE_OBJECT, amp_v3(-0.5, 0, z), amp_v3(0.5, 0, z), 0.2);
            if (t < 2)
                line_path(&ps, AMP_ROLE_OBJECT, amp_v3(x1 - 0.5, 0, z), amp_v3(x1 + 0.5, 0, z), 0.2);
        }
        if (t < 2) /* the deck across */
            line_path(&ps, AMP_ROLE_OBJECT, amp_v3(-0.5, 0, 5.2), amp_v3(x1 + 0.5, 0, 5.2), 0.2);
        else /* a tip: 0.6 mm beyond the last held point (1.9 mm: 45 degrees up from the pillar 1.4 mm lower) */
            line_path(&ps, AMP_ROLE_OBJECT, amp_v3(-0.5, 0, 5.2), amp_v3(2.5, 0, 5.2), 0.2);
        r = hold(&ps);
        if (t == 1) {
            ck_assert_uint_eq(r.failures, 1);
            ck_assert_uint_eq(r.npaths_failed, 1);
            ck_assert_uint_eq(r.paths_failed[0], ps.npaths - 1);
            ck_assert_msg(r.worst_mm > 4.5 && r.worst_mm < 8.5, "unheld %g mm", r.worst_mm);
        } else {
            ck_assert_msg(r.failures == 0, "span %g: %lu failures", span[t], (unsigned long)r.failures);
            ck_assert_uint_eq(r.bridges, (size_t)(t == 0 ? 1 : 0));
            ck_assert_uint_eq(r.tips, (size_t)(t == 2 ? 1 : 0));
        }
        amp_hold_report_free(&r);
        amp_pathset_free(&ps);
    }
}
END_TEST

/* The 45-degree rule: a wall leaning 40 degrees from the vertical stands, one leaning 60 degrees does not. */
START_TEST(hold_check_applies_the_overhang_rule)
{
    static const double lean[2] = {40.0, 60.0};
    int t;
    for (t = 0; t < 2; t++) {
        amp_pathset ps;
        amp_hold_report r;
        double z, sh = tan(lean[t] / 57.295779513082320876);
        int layer = 0;
        amp_pathset_init(&ps, NULL);
        for (z = 0.2; z < 10; z += 0.4, layer++)
            line_path(&ps, AMP_ROLE_OBJECT, amp_v3(z * sh, 0, z), amp_v3(z * sh, 10, z), 0.2);
        r = hold(&ps);
        if (t == 0) {
            ck_assert_uint_eq(r.failures, 0);
        } else {
            /* layers up to the bed tolerance are held by the bed; every one after the first layer above 1 mm fails */
            ck_assert_uint_gt(r.npaths_failed, (size_t)layer - 4);
        }
        amp_hold_report_free(&r);
        amp_pathset_free(&ps);
    }
}
END_TEST

#ifdef _OPENMP
/* Support of the ordered helix (coarse) on @p threads OpenMP threads. */
static void helix_support(const amp_pathset *ord, const amp_bvh *bvh, int threads, amp_pathset *out)
{
    amp_support_opts so;
    amp_support_stats st;
    amp_error err;
    omp_set_num_threads(threads);
    amp_support_opts_default(&so);
    ck_assert_msg(amp_support(ord, bvh, &so, out, &st, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_gt(st.paths, 1000); /* thousands of support fragments: many blocks for the threads */
    ck_assert_uint_eq(st.conflicts, 0);
}

/* Speed: the slot search runs blocks of support fragments on OpenMP threads; the answers, and so the
 * support file, must not depend on the thread count. */
START_TEST(support_on_the_helix_is_identical_on_one_and_two_threads)
{
    amp_spline v;
    amp_cover_opts co;
    amp_order_opts oo;
    amp_pathset cov, ord, s1, s2;
    amp_mesh m;
    amp_bvh *bvh = NULL;
    amp_error err;
    int saved = omp_get_max_threads();
    amp_spline_init(&v);
    amp_pathset_init(&cov, NULL);
    amp_pathset_init(&ord, NULL);
    amp_pathset_init(&s1, NULL);
    amp_pathset_init(&s2, NULL);
    amp_mesh_init(&m, NULL);
    amp_cover_opts_default(&co);
    co.eps = 2.0;
    co.dir = 0;
    amp_order_opts_default(&oo);
    ck_assert_int_eq(amp_trivariate_model("helix", NULL, &v, &err), AMP_OK);
    ck_assert_int_eq(amp_cover_trivariate(&v, &co, &cov, NULL, &err), AMP_OK);
    ck_assert_int_eq(amp_order(&cov, &oo, &ord, NULL, &err), AMP_OK);
    ck_assert_int_eq(amp_mesh_from_trivariate(&m, &v, 0, &err), AMP_OK);
    ck_assert_int_eq(amp_bvh_build(&bvh, &m, &err), AMP_OK);
    helix_support(&ord, bvh, 1, &s1);
    helix_support(&ord, bvh, 2, &s2);
    omp_set_num_threads(saved);
    fx_assert_same_paths(&s1, &s2);
    amp_bvh_free(bvh);
    amp_mesh_free(&m);
    amp_pathset_free(&cov);
    amp_pathset_free(&ord);
    amp_pathset_free(&s1);
    amp_pathset_free(&s2);
    amp_spline_free(&v);
}
END_TEST
#endif

static Suite *support_suite(void)
{
    Suite *s = suite_create("support");
    TCase *tc = tcase_create("support");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, floating_slab_gets_support_printed_before_the_paths_above);
    tcase_add_test(tc, model_on_the_plate_needs_no_rows_its_floating_paths_get_pads_and_bad_options_fail);
    tcase_add_test(tc, support_rows_start_on_the_lowest_bead_bottom);
    tcase_add_test(tc, support_command_writes_interleaved_paths_and_rejects_bad_models);
    tcase_add_test(tc, support_command_refuses_a_file_without_paths);
    tcase_add_test(tc, support_from_a_trivariate_matches_its_boundary_mesh);
    tcase_add_test(tc, helix_support_keeps_every_fragment_and_holds_every_path);
    tcase_add_test(tc, support_warns_when_the_rows_do_not_rest_on_each_other);
    tcase_add_test(tc, pads_hold_the_lowest_rows_of_a_field_over_a_shallow_underside);
    tcase_add_test(tc, a_sliced_job_gets_planar_support_on_its_own_layers);
    tcase_add_test(tc, hold_check_needs_material_printed_earlier_under_each_bead);
    tcase_add_test(tc, hold_check_allows_short_bridges_and_tips_only);
    tcase_add_test(tc, hold_check_of_a_job_with_nothing_printed_ends_at_once);
    tcase_add_test(tc, hold_check_applies_the_overhang_rule);
    tcase_add_test(tc, an_object_bead_is_not_printed_before_the_bead_it_rests_on);
#ifdef _OPENMP
    tcase_add_test(tc, support_on_the_helix_is_identical_on_one_and_two_threads);
#endif
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(support_suite)
