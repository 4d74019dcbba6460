/* Planar slicing of meshes into polygons with holes (paper 2 §2.2 step 1). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <string.h>

#include "fx_meshes.h"
#include "meshfix.h"
#include "runtool.h"
#include "testutil.h"

static size_t count_holes(const amp_polyset *ps)
{
    size_t i, h = 0;
    for (i = 0; i < ps->nrings; i++)
        h += ps->rings[i].hole != 0;
    return h;
}

/* Independent orientation check: outer rings CCW, holes CW, holes after their outer. */
static void assert_oriented(const amp_polyset *ps)
{
    size_t i;
    for (i = 0; i < ps->nrings; i++) {
        double a = amp_ring_area(amp_polyset_ring(ps, i), ps->rings[i].n);
        ck_assert_msg(ps->rings[i].hole ? a < 0 : a > 0, "ring %lu area %g hole %d", (unsigned long)i, a,
                      ps->rings[i].hole);
    }
}

START_TEST(sphere_sections_are_single_discs_with_analytic_area)
{
    amp_mesh m;
    amp_polyset ps;
    amp_section_stats ss;
    static const double zs[] = {-8.0, -5.0, -1.0, 0.3, 4.0, 7.5};
    size_t i;
    amp_mesh_init(&m, NULL);
    amp_polyset_init(&ps, NULL);
    ck_assert_int_eq(fx_sphere(&m, amp_v3(1, 2, 0), 10.0, 256, 128), AMP_OK);
    for (i = 0; i < sizeof zs / sizeof zs[0]; i++) {
        double want = AMP_PI * (100.0 - zs[i] * zs[i]);
        amp_polyset_clear(&ps);
        ck_assert_int_eq(amp_slice_plane(&m, zs[i], &ps, &ss, NULL), AMP_OK);
        ck_assert_uint_eq(ps.nislands, 1);
        ck_assert_uint_eq(ps.nrings, 1);
        ck_assert_uint_eq(ss.open_chains, 0);
        ck_assert_msg(fabs(amp_polyset_area(&ps) - want) < 0.01 * want, "z %g area %g want %g", zs[i],
                      amp_polyset_area(&ps), want);
        assert_oriented(&ps);
    }
    amp_polyset_clear(&ps);
    ck_assert_int_eq(amp_slice_plane(&m, 10.5, &ps, NULL, NULL), AMP_OK);
    ck_assert_uint_eq(ps.nrings, 0);
    amp_polyset_free(&ps);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(torus_sections_are_annuli_with_one_hole_and_analytic_area)
{
    amp_mesh m;
    amp_polyset ps;
    amp_section_stats ss;
    /* z = 0 passes exactly through a ring of mesh vertices (perturbation) */
    static const double zs[] = {-2.5, -1.0, 0.0, 1.7, 2.9};
    size_t i;
    amp_mesh_init(&m, NULL);
    amp_polyset_init(&ps, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), 10.0, 3.0, 256, 128), AMP_OK);
    for (i = 0; i < sizeof zs / sizeof zs[0]; i++) {
        double w = sqrt(9.0 - zs[i] * zs[i]), want = 4 * AMP_PI * 10.0 * w;
        amp_polyset_clear(&ps);
        ck_assert_int_eq(amp_slice_plane(&m, zs[i], &ps, &ss, NULL), AMP_OK);
        ck_assert_uint_eq(ps.nislands, 1);
        ck_assert_uint_eq(ps.nrings, 2);
        ck_assert_uint_eq(count_holes(&ps), 1);
        ck_assert_uint_eq(ss.open_chains, 0);
        ck_assert_msg(fabs(amp_polyset_area(&ps) - want) < 0.01 * want, "z %g area %g want %g", zs[i],
                      amp_polyset_area(&ps), want);
        assert_oriented(&ps);
    }
    amp_polyset_free(&ps);
    amp_mesh_free(&m);
}
END_TEST

static const char *const plate[] = {
    "##########......####",
    "#........#......####",
    "#.####...#..........",
    "#.#..#...#....###...",
    "#.####...#....###...",
    "#........#..........",
    "##########..........",
    "....................",
    "#####.####..........",
    "#####.####..........",
    NULL};

static double count_cells(const char *const *rows)
{
    double n = 0;
    size_t i, j;
    for (i = 0; rows[i]; i++)
        for (j = 0; rows[i][j]; j++)
            n += rows[i][j] == '#';
    return n;
}

START_TEST(voxel_plate_gives_islands_holes_and_exact_areas)
{
    amp_mesh m;
    amp_polyset ps;
    amp_section_stats ss;
    double zs[] = {0.5, 1.0, 2.0, 2.5}; /* 1.0 and 2.0: on a layer of mesh vertices */
    size_t i;
    amp_mesh_init(&m, NULL);
    amp_polyset_init(&ps, NULL);
    ck_assert_int_eq(fx_voxel_picture(&m, plate, 3, 1.0), AMP_OK);
    for (i = 0; i < 4; i++) {
        amp_polyset_clear(&ps);
        ck_assert_int_eq(amp_slice_plane(&m, zs[i], &ps, &ss, NULL), AMP_OK);
        /* frame (with hole) + ring island inside the hole (with its own hole) + 4 blocks */
        ck_assert_uint_eq(ps.nislands, 6);
        ck_assert_uint_eq(count_holes(&ps), 2);
        ck_assert_uint_eq(ss.open_chains, 0);
        ck_assert_near(amp_polyset_area(&ps), count_cells(plate), 1e-9);
        assert_oriented(&ps);
    }
    /* the bottom face lies in the plane z = 0: treated as above, nothing cut */
    amp_polyset_clear(&ps);
    ck_assert_int_eq(amp_slice_plane(&m, 0.0, &ps, &ss, NULL), AMP_OK);
    ck_assert_uint_eq(ps.nrings, 0);
    amp_polyset_free(&ps);
    amp_mesh_free(&m);
}
END_TEST

/* Index of a triangle of @p m crossed by the plane z = @p z (ntris if none). */
static size_t tri_crossing(const amp_mesh *m, double z)
{
    size_t k;
    for (k = 0; k < m->ntris; k++) {
        amp_box3 b = amp_box3_empty();
        b = amp_box3_add(b, m->verts[m->tris[k].v[0]]);
        b = amp_box3_add(b, m->verts[m->tris[k].v[1]]);
        b = amp_box3_add(b, m->verts[m->tris[k].v[2]]);
        if (b.min.z < z && b.max.z > z)
            break;
    }
    return k;
}

START_TEST(open_mesh_sections_are_closed_across_the_gap)
{
    amp_mesh m;
    amp_polyset ps, full;
    amp_section_stats ss;
    size_t k;
    amp_mesh_init(&m, NULL);
    amp_polyset_init(&ps, NULL);
    amp_polyset_init(&full, NULL);
    ck_assert_int_eq(fx_sphere(&m, amp_v3(0, 0, 0), 5.0, 32, 16), AMP_OK);
    ck_assert_int_eq(amp_slice_plane(&m, 0.2, &full, &ss, NULL), AMP_OK);
    /* remove a triangle crossed by the plane z = 0.2: an exported STL with
     * a hole; the section's chain is closed by a straight edge, not dropped
     * (a dropped layer under kept ones would leave those in the air) */
    k = tri_crossing(&m, 0.2);
    ck_assert_uint_lt(k, m.ntris);
    m.tris[k] = m.tris[m.ntris - 1];
    m.ntris--;
    ck_assert_int_eq(amp_slice_plane(&m, 0.2, &ps, &ss, NULL), AMP_OK);
    ck_assert_uint_eq(ss.open_chains, 0);
    ck_assert_uint_eq(ss.gaps_closed, 1);
    ck_assert_uint_eq(ps.nrings, 1);
    assert_oriented(&ps);
    /* the straight edge replaces the chord of the missing facet: the area
     * is the closed sphere's section's within a facet's share */
    ck_assert_double_eq_tol(amp_polyset_area(&ps), amp_polyset_area(&full), 0.05 * amp_polyset_area(&full));
    /* a second, closed sphere in the same plane is sliced as before */
    ck_assert_int_eq(fx_sphere(&m, amp_v3(20, 0, 0), 5.0, 32, 16), AMP_OK);
    amp_polyset_free(&ps);
    amp_polyset_init(&ps, NULL);
    ck_assert_int_eq(amp_slice_plane(&m, 0.2, &ps, &ss, NULL), AMP_OK);
    ck_assert_uint_eq(ss.gaps_closed, 1);
    ck_assert_uint_eq(ps.nrings, 2);
    {
        /* all layers: every one has both discs, the gaps are counted */
        amp_slices sl;
        amp_slice_opts so = {0.1, 0};
        size_t li;
        amp_slices_init(&sl, NULL);
        ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, NULL), AMP_OK);
        for (li = 0; li < sl.nlayers; li++)
            ck_assert_uint_eq(sl.layers[li].polys.nislands, 2);
        ck_assert_uint_eq(sl.open_chains, 0);
        ck_assert_uint_ge(sl.gaps_closed, 1);
        ck_assert_uint_lt(sl.gaps_closed, sl.nlayers / 4);
        amp_slices_free(&sl);
    }
    amp_polyset_free(&ps);
    amp_polyset_free(&full);
    amp_mesh_free(&m);
}
END_TEST

/* An open wall whose section is an arc flatter than a needle (CGAL's cylinder_locally_refined near its base:
 * three arcs of radius 40 mm, none closing) is no region: the layer is empty and the arc counts as an open
 * chain, so that the layer it leaves empty is reported, not a gap "closed" into nothing. */
START_TEST(an_arc_too_flat_to_close_is_reported_open_not_closed)
{
    amp_mesh m;
    amp_polyset ps;
    amp_section_stats ss;
    uint32_t v[2][41];
    int i, k;
    amp_mesh_init(&m, NULL);
    amp_polyset_init(&ps, NULL);
    for (k = 0; k < 2; k++) /* a strip of the wall: 4 degrees of a 100 mm circle in 40 facets, z 0..5 */
        for (i = 0; i < 41; i++) {
            double a = (88.0 + 0.1 * i) * AMP_PI / 180.0;
            ck_assert_int_eq(amp_mesh_add_vertex(&m, amp_v3(100 * cos(a), 100 * sin(a), 5.0 * k), &v[k][i], NULL),
                             AMP_OK);
        }
    for (i = 0; i < 40; i++) {
        ck_assert_int_eq(amp_mesh_add_tri(&m, v[0][i], v[0][i + 1], v[1][i + 1], NULL), AMP_OK);
        ck_assert_int_eq(amp_mesh_add_tri(&m, v[0][i], v[1][i + 1], v[1][i], NULL), AMP_OK);
    }
    ck_assert_int_eq(amp_slice_plane(&m, 2.5, &ps, &ss, NULL), AMP_OK);
    ck_assert_uint_eq(ps.nrings, 0);
    ck_assert_uint_eq(ss.open_chains, 1);
    ck_assert_uint_eq(ss.gaps_closed, 0);
    amp_polyset_free(&ps);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(cracked_mesh_is_sliced_as_if_welded)
{
    /* a facet whose corners are 1 um off its neighbours' (unwelded STL from
     * a CAD export): two chains per section with 1 um gaps, joined */
    amp_mesh m;
    amp_polyset ps, full;
    amp_section_stats ss;
    size_t k;
    int c;
    uint32_t nv[3];
    amp_mesh_init(&m, NULL);
    amp_polyset_init(&ps, NULL);
    amp_polyset_init(&full, NULL);
    ck_assert_int_eq(fx_sphere(&m, amp_v3(0, 0, 0), 5.0, 32, 16), AMP_OK);
    ck_assert_int_eq(amp_slice_plane(&m, 0.2, &full, &ss, NULL), AMP_OK);
    k = tri_crossing(&m, 0.2);
    ck_assert_uint_lt(k, m.ntris);
    for (c = 0; c < 3; c++) {
        amp_vec3 p = m.verts[m.tris[k].v[c]];
        ck_assert_int_eq(amp_mesh_add_vertex(&m, amp_v3(p.x + 1e-3, p.y, p.z), &nv[c], NULL), AMP_OK);
    }
    for (c = 0; c < 3; c++)
        m.tris[k].v[c] = nv[c];
    ck_assert_int_eq(amp_slice_plane(&m, 0.2, &ps, &ss, NULL), AMP_OK);
    ck_assert_uint_eq(ss.open_chains, 0);
    ck_assert_uint_eq(ss.gaps_closed, 2);
    ck_assert_uint_eq(ps.nrings, 1);
    ck_assert_double_eq_tol(amp_polyset_area(&ps), amp_polyset_area(&full), 1e-3 * amp_polyset_area(&full));
    amp_polyset_free(&ps);
    amp_polyset_free(&full);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(layers_are_cut_at_mid_height_with_optional_first_layer)
{
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts o;
    amp_error err;
    size_t i;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(3, 4, 7), 10.0, 3.0, 64, 32), AMP_OK); /* z in [4, 10] */
    o.layer = 0.5;
    o.first_layer = 0;
    ck_assert_int_eq(amp_slice_mesh(&m, &o, &sl, &err), AMP_OK);
    ck_assert_uint_eq(sl.nlayers, 12);
    ck_assert_near(sl.z0, 4.0, 1e-12);
    for (i = 0; i < sl.nlayers; i++) {
        ck_assert_near(sl.layers[i].z_cut, (i + 0.5) * 0.5, 1e-12);
        ck_assert_near(sl.layers[i].z_print, (i + 1) * 0.5, 1e-12);
        ck_assert_uint_eq(sl.layers[i].polys.nislands, 1);
        ck_assert_uint_eq(sl.layers[i].polys.nrings, 2);
    }
    ck_assert_uint_eq(sl.open_chains, 0);
    o.first_layer = 0.3;
    ck_assert_int_eq(amp_slice_mesh(&m, &o, &sl, &err), AMP_OK);
    ck_assert_near(sl.layers[0].z_cut, 0.15, 1e-12);
    ck_assert_near(sl.layers[0].z_print, 0.3, 1e-12);
    ck_assert_near(sl.layers[1].z_cut, 0.55, 1e-12);
    ck_assert_near(sl.layers[1].z_print, 0.8, 1e-12);
    ck_assert_uint_eq(sl.nlayers, 12);
    o.layer = -1;
    ck_assert_int_eq(amp_slice_mesh(&m, &o, &sl, &err), AMP_ERR_ARG);
    ck_assert(strstr(err.msg, "layer") != NULL);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(cli_refuses_a_mesh_in_metres_with_its_size)
{
    /* a 20 mm sphere exported in metres: 0.02 units across, no layer of
     * 0.2 mm cuts it; exit 2, the size and the hint, no output file */
    amp_mesh m;
    amp_error err;
    char args[512], out[4096];
    const char *stl = fx_tmp("metres.stl"), *amp = fx_tmp("metres.amp");
    FILE *f;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_sphere(&m, amp_v3(0, 0, 0), 0.01, 16, 8), AMP_OK);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    remove(amp);
    snprintf(args, sizeof args, "slice %s --layer 0.2 --continuous -o %s", stl, amp);
    ck_assert_int_eq(fx_run_tool_ex(args, NULL, 1, out, sizeof out), 2);
    ck_assert_msg(strstr(out, "0.02 x 0.02 x 0.02 mm") && strstr(out, "metres"), "%s", out);
    f = fopen(amp, "r");
    ck_assert_msg(f == NULL, "no output for a refused mesh");
    snprintf(args, sizeof args, "slice %s --layer 0.2 --polygons -o %s", stl, amp);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    /* scaled to millimetres it slices */
    {
        size_t i;
        for (i = 0; i < m.nverts; i++)
            m.verts[i] = amp_v3(1000 * m.verts[i].x, 1000 * m.verts[i].y, 1000 * m.verts[i].z);
    }
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.2 --polygons -o %s", stl, amp);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(cli_writes_closed_oriented_polygons_per_layer)
{
    amp_mesh m;
    amp_pathset ps;
    amp_error err;
    char args[512], out[8192];
    const char *stl = fx_tmp("torus.stl"), *amp = fx_tmp("torus.amp"), *svg = fx_tmp("torus.svg");
    size_t i;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(5, 5, 9), 10.0, 3.0, 96, 48), AMP_OK); /* z in [6, 12] */
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --polygons -o %s --json", stl, amp);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"layers\":12,\"polygons\":24,\"islands\":12,\"holes\":12") != NULL, "%s", out);
    ck_assert_int_eq(amp_pathset_read_file(&ps, amp, &err), AMP_OK);
    ck_assert_uint_eq(ps.npaths, 24);
    for (i = 0; i < ps.npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(&ps, i);
        size_t n = ps.paths[i].n, k;
        double a = 0;
        ck_assert_uint_gt(n, 4);
        ck_assert(v[0].p.x == v[n - 1].p.x && v[0].p.y == v[n - 1].p.y); /* closed */
        ck_assert_near(v[0].p.z, (i / 2 + 0.5) * 0.5, 1e-6);               /* cut height above the plate */
        ck_assert_near(v[0].r, 0.225, 1e-9); /* default: a 0.45 mm bead */
        for (k = 0; k + 1 < n; k++)
            a += v[k].p.x * v[k + 1].p.y - v[k + 1].p.x * v[k].p.y;
        ck_assert_msg(i % 2 == 0 ? a > 0 : a < 0, "path %lu: outer CCW then hole CW", (unsigned long)i);
    }
    snprintf(args, sizeof args, "slice %s --layer 0.5 --z 3 -o %s", stl, svg);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    {
        FILE *f = fopen(svg, "r");
        char head[64] = {0};
        ck_assert(f != NULL);
        ck_assert(fread(head, 1, sizeof head - 1, f) > 0);
        fclose(f);
        ck_assert(strstr(head, "<?xml") == head);
    }
    snprintf(args, sizeof args, "slice %s --polygons", stl);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2); /* --layer missing */
    snprintf(args, sizeof args, "slice %s.missing --layer 0.5", stl);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    snprintf(args, sizeof args, "euler %s --layer 0.5 --cell 2 --grid tri --json", stl);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"euler\":true") != NULL, "%s", out);
    /* one pass with combinatorial changes: the lattice never collapses a
     * Class 2 cell, so Lemma 3.3 repairs nothing; rim cells stay odd */
    snprintf(args, sizeof args, "euler %s --layer 0.5 --cell 2 --grid hex --single --combinatorial --json", stl);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"collapsed_class2\":0") != NULL && strstr(out, "\"repaired_cells\":0") != NULL &&
                      strstr(out, "\"euler\":false") != NULL,
                  "%s", out);
    snprintf(args, sizeof args, "euler %s --layer 0.5 --cell 2 --grid pentagon", stl);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    remove(stl);
    remove(amp);
    remove(svg);
    amp_pathset_free(&ps);
    amp_mesh_free(&m);
}
END_TEST

/* A stair of voxel blocks (1 mm cells): columns 0-9 on the lower 4 layers
 * of cells, columns 3-12 above: the upper part overhangs by 3 mm. */
static int stair(int i, int j, int k, void *u)
{
    (void)u;
    (void)j;
    return k < 4 ? i < 10 : (i >= 3 && i < 13);
}

START_TEST(overhang_of_consecutive_layers_measures_eps_continuity)
{
    /* §2.1: the layer pair across the step overhangs by 3 mm (the upper
     * layer's far corner is 3 mm from the lower section), every other
     * pair by 0; a layer over an empty one is infinite */
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts so = {0.5, 0};
    amp_error err;
    size_t i;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    ck_assert_int_eq(fx_voxels(&m, 13, 4, 8, 1.0, stair, NULL), AMP_OK);
    ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, &err), AMP_OK);
    ck_assert_uint_eq(sl.nlayers, 16);
    for (i = 0; i + 1 < sl.nlayers; i++) {
        double o = amp_slices_overhang(&sl, i, 0.25);
        if (i == 7)
            ck_assert_double_eq_tol(o, 3.0, 1e-9);
        else
            ck_assert_double_eq_tol(o, 0.0, 1e-9);
    }
    ck_assert_double_eq(amp_slices_overhang(&sl, sl.nlayers - 1, 0.25), 0.0);
    amp_polyset_clear(&sl.layers[3].polys);
    ck_assert(amp_slices_overhang(&sl, 3, 0.25) == HUGE_VAL);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
}
END_TEST

/* A plate on two legs and a block floating 2 mm above the plate (1 mm cells). */
static int floating(int i, int j, int k, void *u)
{
    (void)u;
    (void)j;
    return k < 2 ? (i < 2 || i >= 8) : k < 4 ? 1 : k >= 6 && i >= 3 && i < 7;
}

START_TEST(cli_slice_names_a_piece_that_starts_in_mid_air)
{
    /* the layer over an empty one overhangs without bound: the warning says where the piece begins, not
     * "inf mm" */
    amp_mesh m;
    amp_error err;
    char out[4096];
    char args[600];
    const char *stl = fx_tmp("floating.stl"), *amp = fx_tmp("floating.amp");
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_voxels(&m, 10, 4, 8, 1.0, floating, NULL), AMP_OK);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice '%s' --layer 0.5 --continuous -o '%s'", stl, amp);
    ck_assert_int_eq(fx_run_tool_ex(args, NULL, 1, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "starts over an empty layer (a piece of the part begins in mid-air)"), "%s", out);
    ck_assert_msg(strstr(out, "layer 12 at z 6.5 "), "%s", out); /* the block starts at z 6: layer 12 cuts it at 6.25 */
    ck_assert_msg(!strstr(out, "inf"), "%s", out);
    remove(stl);
    remove(amp);
    amp_mesh_free(&m);
}
END_TEST

/* Box [x0,x1]x[y0,y1]x[z0,z1] as a closed shell of its own, outward or (for a
 * cavity) inward, added to @p m: the bodies of a part exported without a
 * boolean union. */
static void add_box(amp_mesh *m, amp_vec3 lo, amp_vec3 hi, int inward)
{
    static const int f[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                 {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
    uint32_t v[8];
    int i;
    for (i = 0; i < 8; i++) {
        amp_vec3 p = amp_v3((i & 1) ^ (i >> 1 & 1) ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
        ck_assert_int_eq(amp_mesh_add_vertex(m, p, &v[i], NULL), AMP_OK);
    }
    for (i = 0; i < 12; i++)
        ck_assert_int_eq(amp_mesh_add_tri(m, v[f[i][0]], v[f[i][inward ? 2 : 1]], v[f[i][inward ? 1 : 2]], NULL),
                         AMP_OK);
}

static void add_overlapping_bodies(amp_mesh *m)
{
    add_box(m, amp_v3(0, 0, 0), amp_v3(20, 20, 10), 0);
    add_box(m, amp_v3(10, 10, 5), amp_v3(30, 30, 15), 0); /* overlaps the first for z in [5, 10] */
    add_box(m, amp_v3(2, 2, 2), amp_v3(6, 6, 4), 1);      /* a cavity: inward */
    add_box(m, amp_v3(14, 2, 1), amp_v3(18, 6, 3), 0);    /* an insert, same orientation: solid */
}

START_TEST(overlapping_shells_are_sliced_as_their_union)
{
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts so = {0.5, 0};
    size_t i;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    add_overlapping_bodies(&m);
    ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, NULL), AMP_OK);
    ck_assert_uint_eq(sl.nlayers, 30);
    for (i = 0; i < sl.nlayers; i++) {
        const amp_polyset *P = &sl.layers[i].polys;
        double z = sl.layers[i].z_cut, want = z < 5 ? 400 : (z < 10 ? 700 : 400);
        int cavity = z > 2 && z < 4;
        if (cavity)
            want -= 16;
        ck_assert_msg(fabs(amp_polyset_area(P) - want) < 1e-6, "layer %lu at z %g: area %g, want %g",
                      (unsigned long)i, z, amp_polyset_area(P), want);
        ck_assert_uint_eq(P->nislands, 1);
        ck_assert_uint_eq(count_holes(P), (size_t)cavity);
        assert_oriented(P);
    }
    /* resolved: the insert (z in [1, 3]) and the overlap (z in [5, 10]) */
    ck_assert_uint_eq(sl.overlaps, 4 + 10);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(cli_prints_overlapping_bodies_as_one_checked_stroke_per_layer)
{
    amp_mesh m;
    amp_error err;
    char args[1024], out[1 << 16];
    const char *stl = fx_tmp("bodies.stl"), *amp = fx_tmp("bodies.amp");
    amp_mesh_init(&m, NULL);
    add_overlapping_bodies(&m);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --continuous --json -o %s", stl, amp);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"crossings\":0,") && strstr(out, "\"outside\":0,"), "%s", out);
    ck_assert_msg(strstr(out, "\"islands\":30,") && strstr(out, "\"extrusion_starts\":30,"), "%s", out);
    snprintf(args, sizeof args, "check %s --mesh %s --layer 0.5", amp, stl);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    {
        /* the insert is printed solid (even-odd would leave it a hole) */
        amp_pathset ps;
        size_t i, k, inside = 0;
        amp_pathset_init(&ps, NULL);
        ck_assert_int_eq(amp_pathset_read_file(&ps, amp, &err), AMP_OK);
        for (i = 0; i < ps.npaths; i++)
            for (k = 0; k < ps.paths[i].n; k++) {
                amp_vec3 p = ps.verts[ps.paths[i].first + k].p;
                inside += p.z > 1.4 && p.z < 2.6 && p.x > 15 && p.x < 17 && p.y > 3 && p.y < 5;
            }
        ck_assert_uint_gt(inside, 10);
        amp_pathset_free(&ps);
    }
    ck_assert_msg(strstr(out, "\"overlapping_layers\":14,") != NULL, "%s", out);
    amp_mesh_free(&m);
}
END_TEST

/*
 * A comb (a non-convex polygon in the x-z plane, teeth up) extruded 12 mm along y, whose two big faces are
 * fans of triangles from one vertex, as OFF/OBJ converters split polygons: the fan's triangles overlap with
 * opposite orientations, and each vertex is moved up to @p eps off its face (the faces are not quite planar).
 * Its section at height z is the comb's width there times 12 mm, returned in area_at (per z step of 0.1 mm up
 * to 20 mm) with NAN where a notch's floor (moved by eps) lies within 0.05 mm.
 */
static void add_fanned_comb(amp_mesh *m, unsigned long long *seed, double eps, double *area_at)
{
    double px[32], pz[32], x = 40.0, w, notch[8];
    int n = 0, teeth = 2 + (int)(3.0 * fx_rand(seed)), t, k, apex;
    uint32_t base = (uint32_t)m->nverts;
    w = 40.0 / (2 * teeth - 1);
    px[n] = 0, pz[n++] = 0;
    px[n] = 40, pz[n++] = 0;
    for (t = 0; t < teeth; t++) {
        px[n] = x, pz[n++] = 20;
        px[n] = x - w, pz[n++] = 20;
        x -= w;
        if (t < teeth - 1) {
            notch[t] = 6.0 + 6.0 * fx_rand(seed);
            px[n] = x, pz[n++] = notch[t];
            px[n] = x - w, pz[n++] = notch[t];
            x -= w;
        }
    }
    for (k = 0; k <= 200; k++) { /* width at z: the teeth, and the gaps below their notch */
        double z = 0.1 * k, width = teeth * w;
        for (t = 0; t < teeth - 1; t++) {
            width += z < notch[t] ? w : 0.0;
            if (fabs(z - notch[t]) < 0.05)
                width = NAN;
        }
        area_at[k] = 12.0 * width;
    }
    for (k = 0; k < 2 * n; k++) {
        double jx = eps * (2 * fx_rand(seed) - 1), jy = eps * (2 * fx_rand(seed) - 1), jz = eps * (2 * fx_rand(seed) - 1);
        ck_assert_int_eq(amp_mesh_add_vertex(m, amp_v3(px[k % n] + jx, (k < n ? 0.0 : 12.0) + jy, pz[k % n] + jz), NULL, NULL),
                         AMP_OK);
    }
    apex = (int)(n * fx_rand(seed)) % n;
    for (k = 1; k < n - 1; k++) { /* the fans: front (y = 0) seen from -y, back seen from +y */
        uint32_t a = (uint32_t)apex, i = (uint32_t)((apex + k) % n), j = (uint32_t)((apex + k + 1) % n);
        ck_assert_int_eq(amp_mesh_add_tri(m, base + a, base + i, base + j, NULL), AMP_OK);
        ck_assert_int_eq(amp_mesh_add_tri(m, base + (uint32_t)n + a, base + (uint32_t)n + j, base + (uint32_t)n + i, NULL),
                         AMP_OK);
    }
    for (k = 0; k < n; k++) { /* the walls around */
        uint32_t a = (uint32_t)k, b = (uint32_t)((k + 1) % n), an = a + (uint32_t)n, bn = b + (uint32_t)n;
        ck_assert_int_eq(amp_mesh_add_tri(m, base + a, base + bn, base + b, NULL), AMP_OK);
        ck_assert_int_eq(amp_mesh_add_tri(m, base + a, base + an, base + bn, NULL), AMP_OK);
    }
}

/* Fan-triangulated faces (overlapping coplanar triangles, slightly off their plane) cut into rings that run out
 * and back along one line: needles the union cannot order. They are cut out of the rings, and every layer is
 * the comb's section (to within the faces' own offsets) and prints as a checked stroke. Without the cut the
 * second comb already loses part of a tooth's section, and `slice --continuous` failed its own check on such
 * parts (stroke points outside their layer), as on CGAL's fan-triangulated `mpi`. */
START_TEST(fan_triangulated_faces_slice_to_their_section)
{
    unsigned long long seed = 0x5eed5eedULL;
    int trial, failed = 0;
    for (trial = 0; trial < 16; trial++) {
        amp_mesh m;
        amp_slices sl;
        amp_slice_opts so = {0.2, 0};
        amp_error err;
        double area_at[201], eps = trial % 2 ? 0.01 : 0.001;
        char args[1024], out[1 << 16];
        const char *stl = fx_tmp("comb.stl"), *amp = fx_tmp("comb.amp");
        size_t i;
        amp_mesh_init(&m, NULL);
        amp_slices_init(&sl, NULL);
        add_fanned_comb(&m, &seed, eps, area_at);
        ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, NULL), AMP_OK);
        for (i = 0; i < sl.nlayers; i++) {
            double z = sl.layers[i].z_cut, want = area_at[lround(10.0 * z)], got = amp_polyset_area(&sl.layers[i].polys);
            /* the faces' offsets (eps) along the section's 2 x 12 mm of wall and the comb's 40 mm length */
            ck_assert_msg(isnan(want) || fabs(got - want) < 200.0 * eps, "trial %d layer %lu at z %g: area %g, want %g",
                          trial, (unsigned long)i, z, got, want);
        }
        ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
        snprintf(args, sizeof args, "slice %s --layer 0.2 --continuous --json -o %s", stl, amp);
        if (fx_run_tool(args, out, sizeof out) != 0)
            failed++;
        amp_slices_free(&sl);
        amp_mesh_free(&m);
        remove(stl);
        remove(amp);
    }
    ck_assert_int_eq(failed, 0);
}
END_TEST

START_TEST(check_fails_a_job_with_a_layer_left_out_or_without_paths)
{
    /* a continuous job of the overlapping bodies passes; the same job with
     * one layer's stroke removed (the layers above it would print one
     * layer too high) and a job with no path at all fail, exit 1 */
    amp_mesh m;
    amp_pathset ps, cut;
    amp_error err;
    char args[1024], out[1 << 14];
    const char *stl = fx_tmp("gap.stl"), *amp = fx_tmp("gap.amp"), *miss = fx_tmp("gap-miss.amp");
    size_t i;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&cut, NULL);
    add_box(&m, amp_v3(0, 0, 0), amp_v3(12, 8, 4), 0);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --continuous -o %s", stl, amp);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "check %s --mesh %s --layer 0.5 --json", amp, stl);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"layers_without_paths\":0") != NULL, "%s", out);
    ck_assert_int_eq(amp_pathset_read_file(&ps, amp, &err), AMP_OK);
    ck_assert_uint_eq(ps.npaths, 8);
    for (i = 0; i < ps.npaths; i++)
        if (i != 3) {
            ck_assert_int_eq(amp_pathset_add(&cut, ps.paths[i].role, amp_pathset_path_verts(&ps, i), ps.paths[i].n,
                                             &err), AMP_OK);
            ck_assert_int_eq(amp_pathset_set_height(&cut, ps.paths[i].h, &err), AMP_OK);
        }
    ck_assert_int_eq(amp_pathset_write_file(&cut, miss, "test", &err), AMP_OK);
    snprintf(args, sizeof args, "check %s --mesh %s --layer 0.5 --json", miss, stl);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 1);
    ck_assert_msg(strstr(out, "\"layers_without_paths\":1") != NULL, "%s", out);
    amp_pathset_clear(&cut);
    ck_assert_int_eq(amp_pathset_write_file(&cut, miss, "test", &err), AMP_OK);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 1);
    ck_assert_msg(strstr(out, "nothing prints the layers") != NULL, "%s", out);
    amp_pathset_free(&ps);
    amp_pathset_free(&cut);
    amp_mesh_free(&m);
}
END_TEST

/* A triangular prism over (x, y) corners @p t (counter-clockwise), from z0 to z1, normals outward. */
static void add_prism(amp_mesh *m, const double t[3][2], double z0, double z1)
{
    uint32_t v[6];
    int i;
    for (i = 0; i < 6; i++)
        ck_assert_int_eq(amp_mesh_add_vertex(m, amp_v3(t[i % 3][0], t[i % 3][1], i < 3 ? z0 : z1), &v[i], NULL), AMP_OK);
    ck_assert_int_eq(amp_mesh_add_tri(m, v[0], v[2], v[1], NULL), AMP_OK);
    ck_assert_int_eq(amp_mesh_add_tri(m, v[3], v[4], v[5], NULL), AMP_OK);
    for (i = 0; i < 3; i++) {
        ck_assert_int_eq(amp_mesh_add_tri(m, v[i], v[(i + 1) % 3], v[(i + 1) % 3 + 3], NULL), AMP_OK);
        ck_assert_int_eq(amp_mesh_add_tri(m, v[i], v[(i + 1) % 3 + 3], v[i + 3], NULL), AMP_OK);
    }
}

START_TEST(thin_walls_print_once_small_islands_deeper_and_slivers_not_at_all)
{
    /* on a 12 x 8 x 4 mm block, 0.2 mm layers, 0.45 mm beads: a wall 0.23 mm thick and 10 mm long (its
     * inset at r/2 is a loop 5 micrometres wide: printed there and back it was an edge printed twice, the
     * slice failed its own check), a triangular pin of inradius 0.23 mm (its inset at r is a speck the join
     * left out: its layers had no path) and, on the wall, a sliver 4 micrometres thick (no centre line a
     * bead could follow: no path, and the check must not ask for one) */
    static const double tri[3][2] = {{6.0, 6.46}, {5.601628, 5.77}, {6.398372, 5.77}};
    amp_mesh m;
    amp_pathset ps;
    amp_error err;
    char args[1024], out[1 << 14];
    const char *stl = fx_tmp("thin.stl"), *amp = fx_tmp("thin.amp");
    size_t i, walls[12] = {0}, pins[12] = {0}, above = 0;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    add_box(&m, amp_v3(0, 0, 0), amp_v3(12, 8, 4), 0);
    add_box(&m, amp_v3(1, 2, 4), amp_v3(11, 2.23, 6), 0);
    add_prism(&m, tri, 4, 6);
    add_box(&m, amp_v3(1, 2.1, 6), amp_v3(11, 2.104, 6.6), 0);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.2 --continuous -o %s --json", stl, amp);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"empty_layers\":3,") != NULL, "%s", out);
    snprintf(args, sizeof args, "check %s --mesh %s --layer 0.2 --json", amp, stl);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"layers_without_paths\":0") != NULL, "%s", out);
    ck_assert_int_eq(amp_pathset_read_file(&ps, amp, &err), AMP_OK);
    for (i = 0; i < ps.npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(&ps, i);
        size_t n = ps.paths[i].n, k;
        long li = lround(v[0].p.z / 0.2) - 21; /* layers 21..30 print the wall and the pin */
        double len = 0;
        for (k = 1; k < n; k++)
            len += amp_v3_dist(v[k].p, v[k - 1].p);
        above += v[0].p.z > 6.1;
        if (li < 0 || li > 9)
            continue;
        if (v[0].p.y < 3) {
            /* the wall: one open stroke along it, not a loop */
            ck_assert_msg(v[0].p.x != v[n - 1].p.x || v[0].p.y != v[n - 1].p.y, "z %g: a loop", v[0].p.z);
            ck_assert_msg(len > 9.0 && len < 10.2, "z %g: wall stroke %g mm", v[0].p.z, len);
            walls[li]++;
        } else if (v[0].p.y > 5 && v[0].p.x > 5 && v[0].p.x < 7) {
            pins[li]++;
        }
    }
    for (i = 0; i < 10; i++) {
        ck_assert_msg(walls[i] == 1, "layer %lu: %lu wall strokes", (unsigned long)i + 21, (unsigned long)walls[i]);
        ck_assert_msg(pins[i] == 1, "layer %lu: %lu pin strokes", (unsigned long)i + 21, (unsigned long)pins[i]);
    }
    ck_assert_uint_eq(above, 0);
    amp_pathset_free(&ps);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(cli_warns_that_a_part_under_3_mm_may_be_in_inches)
{
    /* a 40 x 30 x 20 mm box exported in inches is 1.57 x 1.18 x 0.79: sliced (it has layers), with the
     * warning PrusaSlicer's question stands for; the box in millimetres gets none */
    amp_mesh m;
    amp_error err;
    char args[1024], out[1 << 12];
    const char *stl = fx_tmp("inch.stl"), *amp = fx_tmp("inch.amp");
    int k;
    for (k = 0; k < 2; k++) {
        double s = k ? 1.0 : 1.0 / 25.4;
        amp_mesh_init(&m, NULL);
        add_box(&m, amp_v3(0, 0, 0), amp_v3(40 * s, 30 * s, 20 * s), 0);
        ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
        snprintf(args, sizeof args, "slice %s --layer 0.2 --continuous -o %s", stl, amp);
        ck_assert_int_eq(fx_run_tool_ex(args, NULL, 1, out, sizeof out), 0);
        ck_assert_msg((strstr(out, "scaled by 25.4") != NULL) == (k == 0), "%s", out);
        amp_mesh_free(&m);
    }
}
END_TEST

/* Slicing out of memory at every allocation in turn: AMP_ERR_NOMEM until the budget suffices, nothing written
 * through a pointer whose growth failed (the chain of a section went on writing its next point: a crash about
 * every 25th allocation of a black-box sweep), nothing leaked. */
START_TEST(slicing_out_of_memory_fails_cleanly_at_every_allocation)
{
    amp_mesh m;
    amp_slice_opts so = {1.0, 0};
    long budget, need = -1;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), 10.0, 3.0, 32, 16), AMP_OK);
    for (budget = 0; budget < 100000 && need < 0; budget++) {
        fx_failalloc fa;
        amp_slices sl;
        amp_polyset one;
        amp_status rc, rp;
        fx_failalloc_init(&fa, budget);
        amp_slices_init(&sl, &fa.a);
        rc = amp_slice_mesh(&m, &so, &sl, NULL);
        ck_assert_msg(rc == AMP_OK || rc == AMP_ERR_NOMEM, "budget %ld: status %d", budget, (int)rc);
        amp_slices_free(&sl);
        fx_failalloc_init(&fa, budget);
        amp_polyset_init(&one, &fa.a);
        rp = amp_slice_plane(&m, 3.3, &one, NULL, NULL);
        ck_assert_msg(rp == AMP_OK || rp == AMP_ERR_NOMEM, "budget %ld: status %d", budget, (int)rp);
        amp_polyset_free(&one);
        ck_assert_msg(fa.live == 0, "budget %ld: %ld blocks left", budget, fa.live);
        if (rc == AMP_OK && rp == AMP_OK)
            need = budget;
    }
    ck_assert_msg(need > 20, "the sweep reached only %ld allocations", need);
    amp_mesh_free(&m);
}
END_TEST

static Suite *slice_suite(void)
{
    Suite *s = suite_create("slice");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, sphere_sections_are_single_discs_with_analytic_area);
    tcase_add_test(tc, torus_sections_are_annuli_with_one_hole_and_analytic_area);
    tcase_add_test(tc, voxel_plate_gives_islands_holes_and_exact_areas);
    tcase_add_test(tc, open_mesh_sections_are_closed_across_the_gap);
    tcase_add_test(tc, an_arc_too_flat_to_close_is_reported_open_not_closed);
    tcase_add_test(tc, cracked_mesh_is_sliced_as_if_welded);
    tcase_add_test(tc, layers_are_cut_at_mid_height_with_optional_first_layer);
    tcase_add_test(tc, cli_writes_closed_oriented_polygons_per_layer);
    tcase_add_test(tc, cli_refuses_a_mesh_in_metres_with_its_size);
    tcase_add_test(tc, overhang_of_consecutive_layers_measures_eps_continuity);
    tcase_add_test(tc, cli_slice_names_a_piece_that_starts_in_mid_air);
    tcase_add_test(tc, overlapping_shells_are_sliced_as_their_union);
    tcase_add_test(tc, fan_triangulated_faces_slice_to_their_section);
    tcase_add_test(tc, cli_prints_overlapping_bodies_as_one_checked_stroke_per_layer);
    tcase_add_test(tc, check_fails_a_job_with_a_layer_left_out_or_without_paths);
    tcase_add_test(tc, thin_walls_print_once_small_islands_deeper_and_slivers_not_at_all);
    tcase_add_test(tc, cli_warns_that_a_part_under_3_mm_may_be_in_inches);
    tcase_add_test(tc, slicing_out_of_memory_fails_cleanly_at_every_allocation);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(slice_suite)
