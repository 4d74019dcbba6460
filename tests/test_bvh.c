/* BVH: rays, closest points, winding-number inside tests, polyline clipping. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "meshfix.h"
#include "testutil.h"

#define TR 20.0 /* torus major radius */
#define Tr 5.0  /* tube radius */

static amp_bvh *build(const amp_mesh *m)
{
    amp_bvh *b = NULL;
    amp_error err;
    ck_assert_int_eq(amp_bvh_build(&b, m, &err), AMP_OK);
    return b;
}

static amp_vec3 rand_point(unsigned long long *s, double half)
{
    return amp_v3((2 * fx_rand(s) - 1) * half, (2 * fx_rand(s) - 1) * half,
                  (2 * fx_rand(s) - 1) * half * 0.4);
}

START_TEST(ray_through_torus_hits_four_times_alternating)
{
    amp_mesh m;
    amp_bvh *b;
    amp_bvh_hit first, *h;
    size_t n, i;
    amp_error err;
    /* off-axis so that the ray avoids vertices; expected crossings from the exact torus */
    double y = 0.21, z = 0.37, o = -100;
    double q = sqrt(Tr * Tr - z * z);
    double xs[4];
    xs[0] = -sqrt((TR + q) * (TR + q) - y * y);
    xs[1] = -sqrt((TR - q) * (TR - q) - y * y);
    xs[2] = -xs[1];
    xs[3] = -xs[0];
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 96, 48), AMP_OK);
    b = build(&m);
    ck_assert_uint_eq(amp_bvh_triangles(b), m.ntris);
    ck_assert_uint_eq(amp_bvh_flipped(b), 0);
    ck_assert_int_eq(amp_bvh_ray_first(b, amp_v3(o, y, z), amp_v3(1, 0, 0), HUGE_VAL, &first), 1);
    ck_assert_near(first.p.x, xs[0], 0.05);
    ck_assert_int_eq(first.entering, 1);
    ck_assert_int_eq(amp_bvh_ray_all(b, amp_v3(o, y, z), amp_v3(2, 0, 0), HUGE_VAL, &h, &n, &err), AMP_OK);
    ck_assert_uint_eq(n, 4);
    for (i = 0; i < n; i++) {
        ck_assert_near(h[i].p.x, xs[i], 0.05);
        ck_assert_near(h[i].t, (h[i].p.x - o) / 2, 1e-9);
        ck_assert_int_eq(h[i].entering, i % 2 == 0);
    }
    amp_bvh_hits_free(b, h);
    /* tmax stops early; a ray pointing away misses */
    ck_assert_int_eq(amp_bvh_ray_first(b, amp_v3(o, y, z), amp_v3(1, 0, 0), 50, NULL), 0);
    ck_assert_int_eq(amp_bvh_ray_first(b, amp_v3(o, y, z), amp_v3(-1, 0, 0), HUGE_VAL, NULL), 0);
    /* a segment inside the tube crosses nothing */
    ck_assert_int_eq(amp_bvh_segment_hits(b, amp_v3(TR, 0, -1), amp_v3(TR, 0, 1), &h, &n, &err), AMP_OK);
    ck_assert_uint_eq(n, 0);
    ck_assert_ptr_null(h);
    amp_bvh_free(b);
    amp_mesh_free(&m);
}
END_TEST

static double brute_dist(const amp_mesh *m, amp_vec3 p) { return fx_mesh_dist(m, p); }

START_TEST(closest_point_matches_brute_force)
{
    amp_mesh m;
    amp_bvh *b;
    unsigned long long s = 12345;
    int k;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 48, 24), AMP_OK);
    b = build(&m);
    for (k = 0; k < 300; k++) {
        amp_vec3 p = rand_point(&s, 35), q;
        size_t t;
        double d = amp_bvh_closest(b, p, &q, &t);
        ck_assert_near(d, brute_dist(&m, p), 1e-9);
        ck_assert_near(amp_v3_dist(p, q), d, 1e-9);
        ck_assert_uint_lt(t, m.ntris);
        /* inscribed tessellation: tube chord 5(1-cos(pi/24)) + ring chord 25(1-cos(pi/48)) < 0.1 mm */
        ck_assert_near(d, fabs(fx_torus_sdf(p, TR, Tr)), 0.1);
    }
    amp_bvh_free(b);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(hierarchical_winding_number_matches_exact)
{
    amp_mesh m;
    amp_bvh *b;
    unsigned long long s = 777;
    double maxerr = 0;
    int k;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 96, 48), AMP_OK);
    b = build(&m);
    for (k = 0; k < 400; k++) {
        amp_vec3 p = rand_point(&s, 40);
        maxerr = fmax(maxerr, fabs(amp_bvh_winding(b, p) - amp_bvh_winding_exact(b, p)));
    }
    ck_assert_msg(maxerr < 0.02, "max |approx - exact| = %g", maxerr);
    amp_bvh_free(b);
    amp_mesh_free(&m);
}
END_TEST

/*
 * Point-in-mesh on a real non-convex mesh (a torus) with holes punched in it
 * (deleted triangles) and flipped triangles: every sample farther than
 * `margin` from the exact surface must be classified like the exact torus.
 */
static void classify_against_torus(const amp_mesh *m, double margin, size_t *wrong, size_t *tested)
{
    amp_bvh *b = build(m);
    unsigned long long s = 4242;
    int k;
    *wrong = *tested = 0;
    for (k = 0; k < 3000; k++) {
        amp_vec3 p = rand_point(&s, 30);
        double sd = fx_torus_sdf(p, TR, Tr);
        if (fabs(sd) < margin)
            continue;
        (*tested)++;
        *wrong += amp_bvh_inside(b, p) != (sd < 0);
    }
    amp_bvh_free(b);
}

START_TEST(inside_test_is_right_on_torus_with_holes_and_flips)
{
    amp_mesh m;
    size_t wrong, tested, i, holes = 0, flips = 0;
    amp_error err;
    amp_mesh_edge_report er;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 96, 48), AMP_OK);
    classify_against_torus(&m, 0.1, &wrong, &tested);
    ck_assert_uint_gt(tested, 2000);
    ck_assert_uint_eq(wrong, 0);
    /* flip every 17th triangle, then punch a hole every 23rd (delete) */
    for (i = 0; i < m.ntris; i += 17) {
        uint32_t t = m.tris[i].v[1];
        m.tris[i].v[1] = m.tris[i].v[2];
        m.tris[i].v[2] = t;
        flips++;
    }
    for (i = 0; i < m.ntris; i += 23) {
        m.tris[i] = m.tris[--m.ntris];
        holes++;
    }
    ck_assert_int_eq(amp_mesh_edges(&m, &er, &err), AMP_OK);
    ck_assert_uint_gt(er.boundary, 3 * holes - 10);
    ck_assert_uint_gt(er.misoriented, flips);
    classify_against_torus(&m, 1.0, &wrong, &tested);
    ck_assert_uint_gt(tested, 1500);
    ck_assert_msg(wrong == 0, "%lu of %lu points misclassified", (unsigned long)wrong, (unsigned long)tested);
    amp_mesh_free(&m);
}
END_TEST

/*
 * On a closed mesh amp_bvh_inside() counts the crossings of a ray. Its hard cases are the points whose rays
 * meet an edge or a vertex: a lattice of points aligned with the faces, edges and corners of a box with a
 * cavity (so that rays from the cavity and the wall cross both shells), and points on
 * the lines through a coarse torus's vertices along the axes. Every point off the surface must get the
 * answer of the exact winding number.
 */
static size_t disagreements(const amp_bvh *b, const amp_vec3 *p, size_t n, size_t *tested)
{
    size_t i, bad = 0;
    for (i = 0; i < n; i++) {
        if (amp_bvh_closest(b, p[i], NULL, NULL) < 1e-6)
            continue; /* on the surface: either answer is right */
        (*tested)++;
        bad += amp_bvh_inside(b, p[i]) != (amp_bvh_winding_exact(b, p[i]) >= 0.5);
    }
    return bad;
}

START_TEST(ray_inside_test_agrees_with_exact_winding_where_rays_meet_edges)
{
    amp_mesh box, tor;
    amp_bvh *b;
    amp_vec3 *p = malloc(40000 * sizeof *p);
    size_t n = 0, tested = 0, i;
    int x, y, z, a;
    ck_assert_ptr_nonnull(p);
    amp_mesh_init(&box, NULL);
    amp_mesh_init(&tor, NULL);
    ck_assert_int_eq(fx_box(&box, amp_v3(0, 0, 0), amp_v3(10, 10, 10), 0), AMP_OK);
    ck_assert_int_eq(fx_box(&box, amp_v3(2, 3, 4), amp_v3(7, 7, 7), 1), AMP_OK); /* a cavity: rays cross shells */
    ck_assert_int_eq(fx_torus(&tor, amp_v3(0, 0, 0), TR, Tr, 12, 6), AMP_OK);
    b = build(&box);
    ck_assert_int_eq(amp_bvh_closed(b), 1);
    for (x = -2; x <= 22; x++)
        for (y = -2; y <= 22; y++)
            for (z = -2; z <= 22; z += 2)
                p[n++] = amp_v3(0.5 * x, 0.5 * y, 0.5 * z);
    ck_assert_uint_eq(disagreements(b, p, n, &tested), 0);
    ck_assert_uint_gt(tested, 6000);
    amp_bvh_free(b);
    b = build(&tor);
    ck_assert_int_eq(amp_bvh_closed(b), 1);
    for (i = n = 0; i < tor.nverts; i++)
        for (a = -8; a <= 8; a++) {
            amp_vec3 v = tor.verts[i];
            p[n++] = amp_v3(v.x + 0.75 * a, v.y, v.z);
            p[n++] = amp_v3(v.x, v.y + 0.75 * a, v.z);
            p[n++] = amp_v3(v.x, v.y, v.z + 0.75 * a);
        }
    tested = 0;
    ck_assert_uint_eq(disagreements(b, p, n, &tested), 0);
    ck_assert_uint_gt(tested, 2500);
    amp_bvh_free(b);
    /* a missing triangle opens the mesh: the winding number decides, and still rightly far from the hole */
    tor.tris[0] = tor.tris[--tor.ntris];
    b = build(&tor);
    ck_assert_int_eq(amp_bvh_closed(b), 0);
    ck_assert_int_eq(amp_bvh_inside(b, amp_v3(TR, 0, 0)), 1);
    ck_assert_int_eq(amp_bvh_inside(b, amp_v3(0, 0, 0)), 0);
    amp_bvh_free(b);
    amp_mesh_free(&box);
    amp_mesh_free(&tor);
    free(p);
}
END_TEST

/* Points of @p n random ones around box @p lo..hi where amp_bvh_inside() and the exact winding number
 * disagree, among those off the surface whose exact winding is clearly on one side of 1/2 (*tested). */
static size_t open_disagreements(const amp_bvh *b, amp_vec3 lo, amp_vec3 hi, size_t n, size_t *tested)
{
    unsigned long long s = 99;
    size_t i, bad = 0;
    *tested = 0;
    for (i = 0; i < n; i++) {
        amp_vec3 p = amp_v3(lo.x + (hi.x - lo.x) * fx_rand(&s), lo.y + (hi.y - lo.y) * fx_rand(&s),
                            lo.z + (hi.z - lo.z) * fx_rand(&s));
        double w = amp_bvh_winding_exact(b, p);
        if (fabs(w - 0.5) < 0.02 || amp_bvh_closest(b, p, NULL, NULL) < 1e-6)
            continue;
        (*tested)++;
        bad += amp_bvh_inside(b, p) != (w >= 0.5);
    }
    return bad;
}

/* Append box @p lo..hi to @p m, its corners welded to the vertices @p m has at the same place. */
static void add_welded_box(amp_mesh *m, amp_vec3 lo, amp_vec3 hi)
{
    amp_mesh b;
    size_t i, k, t;
    uint32_t idx[8];
    amp_mesh_init(&b, NULL);
    ck_assert_int_eq(fx_box(&b, lo, hi, 0), AMP_OK);
    for (i = 0; i < b.nverts; i++) {
        for (k = 0; k < m->nverts && !(m->verts[k].x == b.verts[i].x && m->verts[k].y == b.verts[i].y &&
                                      m->verts[k].z == b.verts[i].z);
             k++)
            ;
        if (k == m->nverts)
            ck_assert_int_eq(amp_mesh_add_vertex(m, b.verts[i], NULL, NULL), AMP_OK);
        idx[i] = (uint32_t)k;
    }
    for (t = 0; t < b.ntris; t++)
        ck_assert_int_eq(amp_mesh_add_tri(m, idx[b.tris[t].v[0]], idx[b.tris[t].v[1]], idx[b.tris[t].v[2]], NULL),
                         AMP_OK);
    amp_mesh_free(&b);
}

/*
 * An open mesh is closed by caps over its boundary chain (lib/bvh_cap.c), and its inside test counts a ray's
 * crossings over mesh and caps less the caps' winding number: the generalised winding number, without a solid
 * angle per near triangle. Wherever the exact winding number is clearly on one side of 1/2 the answer is its:
 * on a box with its top missing (inside, the winding is between 1/2 and 1 up to the opening: one square cap of
 * 2 triangles), on the torus with holes and flipped triangles (a cap per hole), and on two boxes sharing an
 * edge (non-manifold, each edge used as often both ways: no cap, the count alone).
 */
START_TEST(open_mesh_inside_test_counts_rays_over_caps_of_its_boundary)
{
    amp_mesh m;
    amp_bvh *b;
    size_t i, tested, holes = 0;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_box(&m, amp_v3(0, 0, 0), amp_v3(10, 10, 10), 0), AMP_OK);
    m.tris[3] = m.tris[--m.ntris]; /* the top face's two triangles (faces 2 and 3 of fx_box) */
    m.tris[2] = m.tris[--m.ntris];
    b = build(&m);
    ck_assert_int_eq(amp_bvh_closed(b), 0);
    ck_assert_int_eq(amp_bvh_cap_triangles(b), 2);
    ck_assert_int_eq(amp_bvh_inside(b, amp_v3(5, 5, 9.9)), 1); /* winding just above 1/2 under the opening */
    ck_assert_int_eq(amp_bvh_inside(b, amp_v3(5, 5, 10.1)), 0);
    ck_assert_uint_eq(open_disagreements(b, amp_v3(-3, -3, -3), amp_v3(13, 13, 13), 4000, &tested), 0);
    ck_assert_uint_gt(tested, 3000);
    amp_bvh_free(b);
    amp_mesh_free(&m);
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 96, 48), AMP_OK);
    for (i = 0; i < m.ntris; i += 17) {
        uint32_t t = m.tris[i].v[1];
        m.tris[i].v[1] = m.tris[i].v[2];
        m.tris[i].v[2] = t;
    }
    for (i = 0; i < m.ntris; i += 23, holes++)
        m.tris[i] = m.tris[--m.ntris];
    b = build(&m);
    ck_assert_int_eq(amp_bvh_closed(b), 0);
    ck_assert_int_ge(amp_bvh_cap_triangles(b), (long)holes); /* a hole is a loop of 3 or more edges */
    ck_assert_uint_eq(open_disagreements(b, amp_v3(-30, -30, -8), amp_v3(30, 30, 8), 4000, &tested), 0);
    ck_assert_uint_gt(tested, 3000);
    amp_bvh_free(b);
    amp_mesh_free(&m);
    amp_mesh_init(&m, NULL);
    add_welded_box(&m, amp_v3(0, 0, 0), amp_v3(10, 10, 10));
    add_welded_box(&m, amp_v3(10, 10, 0), amp_v3(20, 20, 10)); /* the edge x = y = 10 is used four times */
    ck_assert_uint_eq(m.nverts, 14);
    b = build(&m);
    ck_assert_int_eq(amp_bvh_closed(b), 0);
    ck_assert_int_eq(amp_bvh_cap_triangles(b), 0);
    ck_assert_uint_eq(open_disagreements(b, amp_v3(-3, -3, -3), amp_v3(23, 23, 13), 4000, &tested), 0);
    ck_assert_uint_gt(tested, 3500);
    amp_bvh_free(b);
    amp_mesh_free(&m);
}
END_TEST

/* `ampath check` takes an open mesh's vertex within 1e-4 of winding 1/2 as on its boundary, where `field` cut
 * the curve by amp_bvh_inside(): it must read the same winding number, amp_bvh_inside_winding(). That one is
 * exact up to the caps' far field, and agrees with the inside test by definition; the hierarchical
 * amp_bvh_winding() strays further from the exact sum (CGAL's 270-triangle blob: a cut point read below
 * 1/2 - 1e-4 by it and was reported 0.1 mm outside). */
START_TEST(inside_winding_is_the_number_the_inside_test_decides_on)
{
    amp_mesh m;
    amp_bvh *b;
    unsigned long long s = 5;
    double err_in = 0, err_hier = 0;
    size_t i;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 24, 12), AMP_OK);
    for (i = 0; i < m.ntris; i += 7)
        m.tris[i] = m.tris[--m.ntris];
    b = build(&m);
    ck_assert_int_gt(amp_bvh_cap_triangles(b), 0);
    for (i = 0; i < 3000; i++) {
        amp_vec3 p = rand_point(&s, 30);
        double w = amp_bvh_winding_exact(b, p), wi = amp_bvh_inside_winding(b, p);
        if (amp_bvh_closest(b, p, NULL, NULL) < 1e-6)
            continue;
        ck_assert_int_eq(wi >= 0.5, amp_bvh_inside(b, p));
        err_in = fmax(err_in, fabs(wi - w));
        err_hier = fmax(err_hier, fabs(amp_bvh_winding(b, p) - w));
    }
    /* 0.0015 against 0.0065 (the caps' far field against the whole mesh's) */
    ck_assert_msg(err_in < 3e-3 && err_in < 0.5 * err_hier, "inside winding strays %g from the exact sum (%g)", err_in,
                  err_hier);
    amp_bvh_free(b);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(inward_inner_shell_is_a_cavity_not_flipped)
{
    amp_mesh m;
    amp_bvh *b;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_box(&m, amp_v3(0, 0, 0), amp_v3(10, 10, 10), 0), AMP_OK);
    ck_assert_int_eq(fx_box(&m, amp_v3(3, 3, 3), amp_v3(7, 7, 7), 1), AMP_OK);
    ck_assert_near(amp_mesh_volume(&m), 1000 - 64, 1e-9);
    b = build(&m);
    ck_assert_uint_eq(amp_bvh_flipped(b), 0);
    ck_assert_int_eq(amp_bvh_inside(b, amp_v3(1, 1, 1)), 1);
    ck_assert_int_eq(amp_bvh_inside(b, amp_v3(5, 5, 5)), 0);
    ck_assert_int_eq(amp_bvh_inside(b, amp_v3(11, 5, 5)), 0);
    ck_assert_near(amp_bvh_winding(b, amp_v3(5, 5, 5)), 0.0, 1e-9);
    amp_bvh_free(b);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(concurrent_queries_match_serial)
{
    amp_mesh m;
    amp_bvh *b;
    int in[2000], k, bad = 0;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 96, 48), AMP_OK);
    b = build(&m);
#pragma omp parallel for
    for (k = 0; k < 2000; k++) {
        unsigned long long s = 99 + (unsigned long long)k;
        in[k] = amp_bvh_inside(b, rand_point(&s, 30));
    }
    for (k = 0; k < 2000; k++) {
        unsigned long long s = 99 + (unsigned long long)k;
        bad += in[k] != amp_bvh_inside(b, rand_point(&s, 30));
    }
    ck_assert_int_eq(bad, 0);
    amp_bvh_free(b);
    amp_mesh_free(&m);
}
END_TEST

/*
 * Independent checker of a clipping result: every vertex inside the exact
 * torus (within tol), every end point that is not an input end point on the
 * surface of the mesh (within 1e-9 of a triangle).
 */
static int clip_ok(const amp_pathset *ps, const amp_mesh *m, const amp_pvert *in, size_t nin, double tol)
{
    size_t i, k;
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        size_t n = ps->paths[i].n;
        for (k = 0; k < n; k++)
            if (fx_torus_sdf(v[k].p, TR, Tr) > tol)
                return 0;
        for (k = 0; k < n; k += n - 1) {
            if (!(amp_v3_dist(v[k].p, in[0].p) == 0 || amp_v3_dist(v[k].p, in[nin - 1].p) == 0) &&
                brute_dist(m, v[k].p) > 1e-9)
                return 0;
            if (n == 1)
                break;
        }
    }
    return 1;
}

START_TEST(clip_straight_line_through_torus_gives_two_exact_pieces)
{
    amp_mesh m;
    amp_bvh *b;
    amp_pathset ps, whole;
    amp_pvert line[7];
    amp_error err;
    int k;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&whole, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 96, 48), AMP_OK);
    b = build(&m);
    for (k = 0; k < 7; k++) {
        line[k].p = amp_v3(-40 + 80 * k / 6.0, 0.21, 0.37);
        line[k].r = 0.2 + 0.1 * k;
    }
    ck_assert_int_eq(amp_bvh_clip_polyline(b, line, 7, 0.0, AMP_ROLE_OBJECT, &ps, &err), AMP_OK);
    ck_assert_uint_eq(ps.npaths, 2);
    ck_assert_near(amp_pathset_length(&ps, -1), 2 * 2 * sqrt(Tr * Tr - 0.37 * 0.37), 0.1);
    ck_assert(clip_ok(&ps, &m, line, 7, 0.06));
    /* radius interpolated along x: r(x) = 0.2 + 0.1 (x + 40) / (80/6) */
    for (k = 0; k < (int)ps.nverts; k++)
        ck_assert_near(ps.verts[k].r, 0.2 + 0.1 * (ps.verts[k].p.x + 40) / (80.0 / 6.0), 1e-12);
    /* min_len drops both pieces (each ~10 mm) */
    amp_pathset_clear(&ps);
    ck_assert_int_eq(amp_bvh_clip_polyline(b, line, 7, 11.0, AMP_ROLE_OBJECT, &ps, &err), AMP_OK);
    ck_assert_uint_eq(ps.npaths, 0);
    /* the checker rejects an unclipped polyline */
    ck_assert_int_eq(amp_pathset_add(&whole, AMP_ROLE_OBJECT, line, 7, &err), AMP_OK);
    ck_assert(!clip_ok(&whole, &m, line, 7, 0.06));
    /* bad arguments */
    ck_assert_int_eq(amp_bvh_clip_polyline(b, line, 7, -1, AMP_ROLE_OBJECT, &ps, &err), AMP_ERR_ARG);
    ck_assert_int_eq(amp_bvh_clip_polyline(b, NULL, 7, 0, AMP_ROLE_OBJECT, &ps, &err), AMP_ERR_ARG);
    amp_bvh_free(b);
    amp_pathset_free(&ps);
    amp_pathset_free(&whole);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(clip_circle_in_torus_with_missing_triangle_stays_whole)
{
    /* a circle along the tube's core: entirely inside, even where a triangle is missing nearby */
    amp_mesh m;
    amp_bvh *b;
    amp_pathset ps;
    amp_pvert c[201];
    amp_error err;
    int k;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 96, 48), AMP_OK);
    m.tris[100] = m.tris[--m.ntris];
    b = build(&m);
    for (k = 0; k <= 200; k++) {
        double u = 2 * AMP_PI * k / 200;
        c[k].p = amp_v3((TR + 3) * cos(u), (TR + 3) * sin(u), 1.0);
        c[k].r = 0.4;
    }
    ck_assert_int_eq(amp_bvh_clip_polyline(b, c, 201, 0.0, AMP_ROLE_OBJECT, &ps, &err), AMP_OK);
    ck_assert_uint_eq(ps.npaths, 1);
    ck_assert_uint_eq(ps.nverts, 201);
    amp_bvh_free(b);
    amp_pathset_free(&ps);
    amp_mesh_free(&m);
}
END_TEST


/*
 * A curve of a helix-following field (paper Fig. 13: a square cross-section
 * field around the helix) that weaves in and out of the disc: offset
 * (u, v) = (7 sin 5πt, 1) in the normal-plane frame, t in [-0.05, 1.05].
 * Exactly, the point is inside iff t in [0, 1] and u² + v² < 25.
 */
START_TEST(clip_helix_field_curve_to_helix_mesh)
{
    amp_mesh m;
    amp_bvh *b;
    amp_pathset ps;
    amp_pvert *c;
    amp_error err;
    size_t n = 3001, i, k, expect = 0;
    int was_in = 0;
    amp_mesh_init(&m, NULL);
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(amp_mesh_model("helix", 0, &m, &err), AMP_OK);
    b = build(&m);
    c = malloc(n * sizeof *c);
    for (i = 0; i < n; i++) {
        double t = -0.05 + 1.1 * (double)i / (double)(n - 1), u = 7 * sin(5 * AMP_PI * t);
        int in = t >= 0 && t <= 1 && u * u + 1 < 25;
        c[i].p = fx_helix_point(t, u, 1);
        c[i].r = 0.5;
        expect += in && !was_in;
        was_in = in;
    }
    ck_assert_int_eq(amp_bvh_clip_polyline(b, c, n, 0.0, AMP_ROLE_OBJECT, &ps, &err), AMP_OK);
    ck_assert_uint_eq(ps.npaths, expect);
    ck_assert_uint_ge(expect, 5);
    for (i = 0; i < ps.npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(&ps, i);
        size_t nv = ps.paths[i].n;
        for (k = 0; k < nv; k++) {
            double t;
            /* inside the mesh, hence inside the exact solid up to the mesh tolerance (0.05 mm, test_mesh.c) */
            ck_assert_msg(amp_bvh_winding_exact(b, v[k].p) > 0.5 || fx_mesh_dist(&m, v[k].p) < 1e-9,
                          "vertex outside the mesh");
            ck_assert_msg(fx_helix_axis_dist(v[k].p, &t) <= 5 + 0.05, "vertex %g outside the helix solid",
                          fx_helix_axis_dist(v[k].p, &t) - 5);
        }
        /* both ends are cut points on the surface */
        ck_assert_msg(fx_mesh_dist(&m, v[0].p) <= 1e-9, "start %g from the surface", fx_mesh_dist(&m, v[0].p));
        ck_assert_msg(fx_mesh_dist(&m, v[nv - 1].p) <= 1e-9, "end %g from the surface",
                      fx_mesh_dist(&m, v[nv - 1].p));
    }
    free(c);
    amp_bvh_free(b);
    amp_pathset_free(&ps);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(voxel_map_answers_as_the_ray_test_and_defers_only_near_the_surface)
{
    /* a torus with a box around it and a cavity in the box (three shells, one solid): sampled over a box
     * larger than the mesh's, every answer of the map equals amp_bvh_inside, and most samples are answered
     * (the field's gap rounds sample a part that fills a few per cent of its box: every sample was a ray) */
    amp_mesh m;
    amp_bvh *b;
    amp_bvh_voxels *v = NULL;
    amp_error err;
    unsigned long long seed = 11;
    size_t i, deferred = 0, inside = 0, wrong = 0, n = 200000;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 0), TR, Tr, 96, 48), AMP_OK);
    ck_assert_int_eq(fx_box(&m, amp_v3(30, -8, -8), amp_v3(46, 8, 8), 0), AMP_OK);
    ck_assert_int_eq(fx_box(&m, amp_v3(34, -4, -4), amp_v3(42, 4, 4), 1), AMP_OK);
    b = build(&m);
    ck_assert_int_eq(amp_bvh_voxels_build(b, 1u << 16, &v, &err), AMP_OK);
    ck_assert_ptr_nonnull(v);
    for (i = 0; i < n; i++) {
        amp_vec3 p = amp_v3(-30 + 80 * fx_rand(&seed), -30 + 60 * fx_rand(&seed), -10 + 20 * fx_rand(&seed));
        int side = amp_bvh_voxels_side(v, p), in = amp_bvh_inside(b, p);
        inside += in;
        if (side < 0)
            deferred++;
        else
            wrong += side != in;
    }
    ck_assert_uint_eq(wrong, 0);
    ck_assert_uint_gt(inside, n / 20);
    ck_assert_msg(deferred < n / 4, "%lu of %lu samples deferred", (unsigned long)deferred, (unsigned long)n);
    ck_assert_int_eq(amp_bvh_voxels_side(v, amp_v3(38, 0, 0)), 0); /* the cavity */
    ck_assert_int_eq(amp_bvh_voxels_side(v, amp_v3(31, 7, 0)), 1);
    ck_assert_int_eq(amp_bvh_voxels_side(v, amp_v3(NAN, 0, 0)), -1);
    amp_bvh_voxels_free(v);
    ck_assert_int_eq(amp_bvh_voxels_build(b, 0, &v, &err), AMP_ERR_ARG);
    amp_bvh_free(b);
    /* an open mesh has no map: its winding number is not constant away from the surface near a hole */
    m.tris[100] = m.tris[--m.ntris];
    b = build(&m);
    ck_assert_int_eq(amp_bvh_voxels_build(b, 1u << 16, &v, &err), AMP_OK);
    ck_assert_ptr_null(v);
    amp_bvh_free(b);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(bvh_rejects_empty_and_degenerate_meshes)
{
    amp_mesh m;
    amp_bvh *b = NULL;
    amp_error err;
    uint32_t a, c, d;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(amp_bvh_build(&b, &m, &err), AMP_ERR_GEOMETRY);
    ck_assert_ptr_null(b);
    ck_assert_int_eq(amp_mesh_add_vertex(&m, amp_v3(0, 0, 0), &a, &err), AMP_OK);
    ck_assert_int_eq(amp_mesh_add_vertex(&m, amp_v3(1, 1, 1), &c, &err), AMP_OK);
    ck_assert_int_eq(amp_mesh_add_vertex(&m, amp_v3(2, 2, 2), &d, &err), AMP_OK);
    ck_assert_int_eq(amp_mesh_add_tri(&m, a, c, d, &err), AMP_OK);
    ck_assert_int_eq(amp_bvh_build(&b, &m, &err), AMP_ERR_GEOMETRY);
    ck_assert_int_eq(amp_bvh_build(NULL, &m, &err), AMP_ERR_ARG);
    amp_mesh_free(&m);
}
END_TEST

static Suite *bvh_suite(void)
{
    Suite *s = suite_create("bvh");
    TCase *tc = tcase_create("bvh");
    tcase_add_test(tc, ray_through_torus_hits_four_times_alternating);
    tcase_add_test(tc, closest_point_matches_brute_force);
    tcase_add_test(tc, hierarchical_winding_number_matches_exact);
    tcase_add_test(tc, inside_test_is_right_on_torus_with_holes_and_flips);
    tcase_add_test(tc, open_mesh_inside_test_counts_rays_over_caps_of_its_boundary);
    tcase_add_test(tc, inside_winding_is_the_number_the_inside_test_decides_on);
    tcase_add_test(tc, ray_inside_test_agrees_with_exact_winding_where_rays_meet_edges);
    tcase_add_test(tc, inward_inner_shell_is_a_cavity_not_flipped);
    tcase_add_test(tc, concurrent_queries_match_serial);
    tcase_add_test(tc, clip_straight_line_through_torus_gives_two_exact_pieces);
    tcase_add_test(tc, clip_circle_in_torus_with_missing_triangle_stays_whole);
    tcase_add_test(tc, clip_helix_field_curve_to_helix_mesh);
    tcase_add_test(tc, bvh_rejects_empty_and_degenerate_meshes);
    tcase_add_test(tc, voxel_map_answers_as_the_ray_test_and_defers_only_near_the_surface);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(bvh_suite)
