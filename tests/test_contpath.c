/* Continuous strokes per island (paper 2 §2.2 steps 5-6, §4). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fx_meshes.h"
#include "runtool.h"
#include "testutil.h"

/* Check every infill stroke of one layer section independently: one closed
 * stroke per region, no crossing, no edge twice, inside the island. */
static void check_section(const amp_mesh *m, double z, double r, amp_grid_kind kind, size_t want_regions)
{
    amp_slices sl;
    amp_slice_opts so;
    amp_contpath_opts o;
    amp_contpath_stats st;
    amp_cx2 khat;
    amp_polyset P, isl, R, reg;
    amp_pathset ps;
    amp_error err;
    size_t k, q, regions = 0;
    amp_slices_init(&sl, NULL);
    amp_cx2_init(&khat, NULL);
    amp_polyset_init(&P, NULL);
    amp_polyset_init(&isl, NULL);
    amp_polyset_init(&R, NULL);
    amp_polyset_init(&reg, NULL);
    amp_pathset_init(&ps, NULL);
    memset(&st, 0, sizeof st);
    so.layer = 0.5;
    so.first_layer = 0;
    ck_assert_int_eq(amp_slice_mesh(m, &so, &sl, &err), AMP_OK);
    amp_contpath_opts_default(&o, r);
    o.grid = kind;
    ck_assert_msg(amp_contpath_complex(&sl, &o, &khat, &err) == AMP_OK, "%s", err.msg);
    ck_assert_int_eq(amp_slice_plane(m, z, &P, NULL, &err), AMP_OK);
    for (k = 0; k < P.nislands; k++) {
        ck_assert_int_eq(amp_polyset_island(&P, k, &isl, &err), AMP_OK);
        ck_assert_int_eq(amp_polyset_inset(&isl, 3 * r, 0, &R, &err), AMP_OK);
        for (q = 0; q < R.nislands; q++) {
            size_t before = ps.npaths, strokes_before = st.strokes;
            amp_stroke_report rep;
            ck_assert_int_eq(amp_polyset_island(&R, q, &reg, &err), AMP_OK);
            ck_assert_msg(amp_contpath_region(&khat, &reg, z, &o, &ps, &st, &err) == AMP_OK, "%s", err.msg);
            ck_assert_uint_eq(st.strokes - strokes_before, 1); /* exactly one stroke per region */
            ck_assert_uint_eq(ps.npaths - before, 1);
            ck_assert_msg(amp_pathset_stroke_check(&ps, before, &isl, 1e-9, &rep, &err) == AMP_OK, "z %g: %s", z,
                          err.msg);
            ck_assert(rep.closed);
            ck_assert_uint_gt(rep.segments, 10);
            /* and within the clipping region R̃ itself */
            ck_assert_msg(amp_pathset_stroke_check(&ps, before, &reg, 1e-7, &rep, &err) == AMP_OK, "%s", err.msg);
            regions++;
        }
    }
    ck_assert_uint_eq(regions, want_regions);
    ck_assert_uint_eq(st.odd_vertices, 0); /* every vertex even after patching */
    ck_assert_uint_eq(st.multi_stroke, 0);
    ck_assert_uint_gt(st.free_ends, 0);
    ck_assert_uint_eq(st.free_ends % 2, 0); /* handshake lemma */
    ck_assert_msg(st.dropped_length <= 0.03 * st.infill_length, "dropped %g of %g mm", st.dropped_length,
                  st.infill_length);
    amp_pathset_free(&ps);
    amp_polyset_free(&P);
    amp_polyset_free(&isl);
    amp_polyset_free(&R);
    amp_polyset_free(&reg);
    amp_cx2_free(&khat);
    amp_slices_free(&sl);
}

START_TEST(torus_sections_get_one_crossing_free_stroke)
{
    amp_mesh m;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 3), 10.0, 3.0, 96, 48), AMP_OK);
    check_section(&m, 3.0, 0.4, AMP_GRID_SQUARE, 1);
    check_section(&m, 1.2, 0.4, AMP_GRID_HEX, 1);
    check_section(&m, 4.5, 0.3, AMP_GRID_TRI, 1);
    amp_mesh_free(&m);
}
END_TEST

/* block with a hole, joined by a 2 mm neck to a second block, and a
 * separate island (2 mm voxels) */
static const char *const plate[] = {
    "##########............####",
    "##########....######..####",
    "##....####....######..####",
    "##....##############..####",
    "##....####....######..####",
    "##########....######..####",
    "##########............####",
    NULL};

START_TEST(plate_with_holes_islands_and_a_thin_neck_gets_one_stroke_per_region)
{
    amp_mesh m;
    amp_mesh_init(&m, NULL);
    /* the neck (2 mm) is narrower than 6r = 2.4 mm: R̃ splits it, so the two
     * islands give three regions, each with its own single stroke */
    ck_assert_int_eq(fx_voxel_picture(&m, plate, 2, 2.0), AMP_OK);
    check_section(&m, 1.0, 0.4, AMP_GRID_SQUARE, 3);
    check_section(&m, 2.0, 0.4, AMP_GRID_HEX, 3); /* plane through mesh vertices */
    check_section(&m, 3.0, 0.35, AMP_GRID_TRI, 3);
    check_section(&m, 3.0, 0.3, AMP_GRID_TRI, 2); /* 6r = 1.8 mm: the neck carries infill */
    amp_mesh_free(&m);
}
END_TEST

/* a perforated plate: 15 holes, more rings than the exhaustive pairing
 * search takes (greedy choice per ring); the lattice lines fall exactly on
 * the inset's straight edges (vertices on the boundary are nudged off) */
static const char *const sieve[] = {
    "#################",
    "#..#..#..#..#..##",
    "#..#..#..#..#..##",
    "#################",
    "#..#..#..#..#..##",
    "#..#..#..#..#..##",
    "#################",
    "#..#..#..#..#..##",
    "#..#..#..#..#..##",
    "#################",
    NULL};

START_TEST(perforated_plate_with_many_holes_gets_one_stroke)
{
    amp_mesh m;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_voxel_picture(&m, sieve, 1, 3.0), AMP_OK);
    check_section(&m, 1.5, 0.25, AMP_GRID_SQUARE, 1);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(all_layers_of_a_sphere_and_torus_pair)
{
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts so;
    amp_contpath_opts o;
    amp_contpath_stats st;
    amp_pathset ps;
    amp_error err;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 3), 10.0, 3.0, 64, 32), AMP_OK);
    ck_assert_int_eq(fx_sphere(&m, amp_v3(22, 0, 4), 4.0, 48, 24), AMP_OK);
    so.layer = 0.5;
    so.first_layer = 0;
    ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, &err), AMP_OK);
    amp_contpath_opts_default(&o, 0.4);
    ck_assert_msg(amp_contpath_layers(&sl, &o, &ps, &st, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(st.layers, sl.nlayers);
    ck_assert_uint_gt(st.islands, sl.nlayers); /* two bodies on most layers */
    ck_assert_uint_eq(st.strokes, st.islands);
    ck_assert_uint_eq(st.multi_stroke, 0);
    ck_assert_uint_eq(st.odd_vertices, 0);
    ck_assert_uint_eq(ps.npaths, st.strokes + st.perimeter_loops);
    ck_assert_uint_eq(st.travel_moves, ps.npaths - 1);
    ck_assert(st.printed_length > st.infill_length && st.infill_length > 0);
    ck_assert_near(st.printed_length, amp_pathset_length(&ps, AMP_ROLE_OBJECT), 1e-6);
    /* Remark 2.1: stretches printed separately as support */
    amp_pathset_clear(&ps);
    o.support_stretches = 1;
    ck_assert_int_eq(amp_contpath_layers(&sl, &o, &ps, &st, &err), AMP_OK);
    ck_assert_uint_gt(st.support_paths, 0);
    ck_assert_near(st.support_length, amp_pathset_length(&ps, AMP_ROLE_SUPPORT), 1e-6);
    ck_assert_near(st.unprinted_length, 0, 0);
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(built_in_models_get_one_crossing_free_stroke_per_island)
{
    static const char *const names[] = {"helix", "twisted-bridge"};
    size_t n, i;
    for (n = 0; n < 2; n++) {
        amp_mesh m;
        amp_slices sl;
        amp_slice_opts so;
        amp_contpath_opts o;
        amp_contpath_stats st;
        amp_pathset ps;
        amp_error err;
        amp_mesh_init(&m, NULL);
        amp_slices_init(&sl, NULL);
        amp_pathset_init(&ps, NULL);
        ck_assert_msg(amp_mesh_model(names[n], 0, &m, &err) == AMP_OK, "%s", err.msg);
        so.layer = 1.0;
        so.first_layer = 0.4;
        ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, &err), AMP_OK);
        ck_assert_uint_eq(sl.open_chains, 0);
        amp_contpath_opts_default(&o, 0.5);
        ck_assert_msg(amp_contpath_layers(&sl, &o, &ps, &st, &err) == AMP_OK, "%s", err.msg);
        ck_assert_uint_gt(st.islands, sl.nlayers / 2);
        ck_assert_uint_eq(st.strokes, st.islands);
        ck_assert_uint_eq(st.multi_stroke, 0);
        ck_assert_uint_eq(st.odd_vertices, 0);
        ck_assert_msg(st.dropped_length <= 0.05 * st.infill_length, "%s: dropped %g of %g mm", names[n],
                      st.dropped_length, st.infill_length);
        for (i = 0; i < ps.npaths; i++)
            ck_assert_msg(amp_pathset_stroke_check(&ps, i, NULL, 0, NULL, &err) == AMP_OK, "%s path %lu: %s", names[n],
                          (unsigned long)i, err.msg);
        amp_pathset_free(&ps);
        amp_slices_free(&sl);
        amp_mesh_free(&m);
    }
}
END_TEST

START_TEST(stroke_checker_rejects_crossings_repeats_and_escapes)
{
    amp_polyset sq;
    amp_stroke_report rep;
    amp_error err;
    amp_vec2 box[4] = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
    amp_vec2 bowtie[5] = {{1, 1}, {9, 9}, {9, 1}, {1, 9}, {1, 1}};
    amp_vec2 twice[6] = {{1, 1}, {5, 1}, {5, 5}, {1, 1}, {5, 1}, {1, 1}};
    amp_vec2 escape[4] = {{1, 1}, {12, 1}, {1, 5}, {1, 1}};
    /* figure eight touching at (5,5): the passes cross there */
    amp_vec2 eight[7] = {{5, 5}, {8, 8}, {8, 2}, {5, 5}, {2, 8}, {2, 2}, {5, 5}};
    /* two loops touching at (5,5) without crossing */
    amp_vec2 touch[7] = {{5, 5}, {8, 2}, {8, 8}, {5, 5}, {2, 8}, {2, 2}, {5, 5}};
    amp_polyset_init(&sq, NULL);
    ck_assert_int_eq(amp_polyset_add(&sq, box, 4, NULL), AMP_OK);
    ck_assert_int_eq(amp_stroke_check(bowtie, 5, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_eq(rep.crossings, 1);
    ck_assert_int_eq(amp_stroke_check(twice, 6, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_gt(rep.repeated_edges, 0);
    ck_assert_int_eq(amp_stroke_check(escape, 4, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_gt(rep.outside, 0);
    ck_assert_int_eq(amp_stroke_check(eight, 7, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_eq(rep.crossings, 1);
    ck_assert_msg(amp_stroke_check(touch, 7, &sq, 0, &rep, &err) == AMP_OK, "%s", err.msg);
    ck_assert(rep.closed);
    amp_polyset_free(&sq);
}
END_TEST

START_TEST(cli_continuous_gives_one_stroke_per_island_and_check_agrees)
{
    amp_mesh m;
    amp_error err;
    char args[768], out[4096];
    const char *stl = amp_test_tmp("plate.stl"), *amp = amp_test_tmp("plate.amp");
    FILE *f;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_voxel_picture(&m, plate, 3, 2.0), AMP_OK);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --radius 0.4 --continuous -o %s --json", stl, amp);
    ck_assert_int_eq(amp_test_run_tool(args, out, sizeof out), 0);
    /* 12 layers x 3 regions (the neck splits R̃), one stroke each */
    ck_assert_msg(strstr(out, "\"layers\":12,\"islands\":36,\"strokes\":36,\"multi_stroke_islands\":0") != NULL, "%s",
                  out);
    ck_assert_msg(strstr(out, "\"crossings\":0,\"repeated_edges\":0") != NULL, "%s", out);
    ck_assert_msg(strstr(out, "\"odd_vertices\":0") != NULL, "%s", out);
    snprintf(args, sizeof args, "check %s --mesh %s --layer 0.5 --json", amp, stl);
    ck_assert_int_eq(amp_test_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"ok\":true") != NULL, "%s", out);
    /* a crossing path appended: the check fails with exit 1 */
    f = fopen(amp, "a");
    ck_assert(f != NULL);
    fprintf(f, "path object 5\n1 1 0.5 0.4\n9 9 0.5 0.4\n9 1 0.5 0.4\n1 9 0.5 0.4\n1 1 0.5 0.4\n");
    fclose(f);
    ck_assert_int_eq(amp_test_run_tool(args, out, sizeof out), 1);
    ck_assert_msg(strstr(out, "\"crossings\":1") != NULL, "%s", out);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --continuous --grid octagon", stl);
    ck_assert_int_eq(amp_test_run_tool(args, NULL, 0), 2);
    remove(stl);
    remove(amp);
    amp_mesh_free(&m);
}
END_TEST

static Suite *contpath_suite(void)
{
    Suite *s = suite_create("contpath");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 120);
    AMP_ADD_TEST(tc, torus_sections_get_one_crossing_free_stroke);
    AMP_ADD_TEST(tc, plate_with_holes_islands_and_a_thin_neck_gets_one_stroke_per_region);
    AMP_ADD_TEST(tc, perforated_plate_with_many_holes_gets_one_stroke);
    AMP_ADD_TEST(tc, all_layers_of_a_sphere_and_torus_pair);
    AMP_ADD_TEST(tc, built_in_models_get_one_crossing_free_stroke_per_island);
    AMP_ADD_TEST(tc, stroke_checker_rejects_crossings_repeats_and_escapes);
    AMP_ADD_TEST(tc, cli_continuous_gives_one_stroke_per_island_and_check_agrees);
    suite_add_tcase(s, tc);
    return s;
}

AMP_TEST_MAIN(contpath_suite)
