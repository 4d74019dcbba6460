/* 2-complexes and the Euler transformation (paper 2 §1.3, §3). */
#include <math.h>
#include <string.h>

#include "testutil.h"

#define PI 3.14159265358979323846

/* Add neighbour o of v (given edge a-b) to nb[] once. */
static void add_nb(uint32_t *nb, size_t *n, uint32_t v, uint32_t a, uint32_t b)
{
    uint32_t o = a == v ? b : a;
    size_t i;
    if (a != v && b != v)
        return;
    for (i = 0; i < *n && nb[i] != o; i++)
        ;
    if (i == *n && *n < 256)
        nb[(*n)++] = o;
}

/* Degree of vertex v in the 1-skeleton, counted here by brute force. */
static size_t degree_of(const amp_cx2 *k, uint32_t v)
{
    uint32_t nb[256];
    size_t n = 0, f, h, j;
    for (f = 0; f < k->nf; f++)
        for (h = k->fstart[f]; h < k->fstart[f + 1]; h++)
            add_nb(nb, &n, v, k->fidx[h], k->fidx[h + 1 < k->fstart[f + 1] ? h + 1 : k->fstart[f]]);
    for (j = 0; j < k->nxe; j++)
        add_nb(nb, &n, v, k->xedge[2 * j], k->xedge[2 * j + 1]);
    return n;
}

static size_t count_class(const amp_cx2 *k, int cls)
{
    size_t f, n = 0;
    for (f = 0; f < k->nf; f++)
        n += k->fclass[f] == cls;
    return n;
}

/* Polar mesh: a fan of triangles around the centre, then rings of
 * triangles (each quad split in two), every vertex jittered at random.
 * No cell has two adjacent boundary edges. */
static void polar_mesh(amp_cx2 *k, int nseg, int nring, double jitter, unsigned seed)
{
    uint32_t c, v[3];
    int r, s;
    amp_cx2_init(k, NULL);
    ck_assert_int_eq(amp_cx2_add_vertex(k, amp_v2(0, 0), &c, NULL), AMP_OK);
    for (r = 1; r <= nring; r++)
        for (s = 0; s < nseg; s++) {
            double t = 2 * PI * s / nseg, jx, jy, amp = jitter * fmin(1.0, r * 2 * PI / nseg);
            seed = seed * 1103515245u + 12345u;
            jx = ((seed >> 8) % 1000 / 1000.0 - 0.5) * amp;
            seed = seed * 1103515245u + 12345u;
            jy = ((seed >> 8) % 1000 / 1000.0 - 0.5) * amp;
            ck_assert_int_eq(amp_cx2_add_vertex(k, amp_v2(r * cos(t) + jx, r * sin(t) + jy), NULL, NULL), AMP_OK);
        }
#define PV(rr, ss) ((uint32_t)(1 + ((rr) - 1) * nseg + ((ss) % nseg)))
    for (s = 0; s < nseg; s++) {
        v[0] = c;
        v[1] = PV(1, s);
        v[2] = PV(1, s + 1);
        ck_assert_int_eq(amp_cx2_add_face(k, v, 3, 0, NULL), AMP_OK);
    }
    for (r = 1; r < nring; r++)
        for (s = 0; s < nseg; s++) {
            /* quad a b (inner ring) c d (outer ring), CCW as a d c b, split in two */
            uint32_t a = PV(r, s), b = PV(r, s + 1), cc = PV(r + 1, s + 1), d = PV(r + 1, s);
            v[0] = a;
            v[1] = d;
            v[2] = cc;
            ck_assert_int_eq(amp_cx2_add_face(k, v, 3, 0, NULL), AMP_OK);
            v[0] = a;
            v[1] = cc;
            v[2] = b;
            ck_assert_int_eq(amp_cx2_add_face(k, v, 3, 0, NULL), AMP_OK);
        }
#undef PV
    ck_assert_int_eq(amp_cx2_build(k, NULL), AMP_OK);
}

START_TEST(euler_transform_of_a_random_triangulation_has_degree_four_everywhere)
{
    amp_cx2 k, kh;
    amp_cx2_report rep, rk;
    amp_euler_opts o;
    amp_error err;
    unsigned seed;
    for (seed = 1; seed <= 5; seed++) {
        polar_mesh(&k, 16, 6, 0.3, seed);
        ck_assert_int_eq(amp_cx2_check(&k, &rk, &err), AMP_OK);
        ck_assert_int_eq(rk.euler_char, 1);
        amp_cx2_init(&kh, NULL);
        o.offset = 0.03;
        o.combinatorial = 0;
        ck_assert_msg(amp_euler_transform(&k, &o, &kh, NULL, &err) == AMP_OK, "%s", err.msg);
        ck_assert_msg(amp_cx2_check(&kh, &rep, &err) == AMP_OK, "%s", err.msg);
        ck_assert_int_eq(amp_cx2_check_even(&kh, NULL, &err), AMP_OK);
        ck_assert_uint_eq(rep.max_degree, 4);
        ck_assert_int_eq(rep.euler_char, 1);
        /* Fig. 2: one Class 1 cell per face, one Class 2 per edge, one Class 3 per vertex */
        ck_assert_uint_eq(count_class(&kh, 1), rk.faces);
        ck_assert_uint_eq(count_class(&kh, 2), rk.edges);
        ck_assert_uint_eq(count_class(&kh, 3), rk.vertices);
        amp_cx2_free(&kh);
        amp_cx2_free(&k);
    }
}
END_TEST

START_TEST(generalized_transform_makes_square_tri_and_hex_grids_euler)
{
    amp_vec2 pts[64], hull[64];
    size_t n = 0, nh, i;
    amp_grid_kind kinds[3] = {AMP_GRID_SQUARE, AMP_GRID_TRI, AMP_GRID_HEX};
    for (i = 0; i < 64; i++) {
        double t = 2 * PI * i / 64;
        pts[n++] = amp_v2(30 + 20 * cos(t), -5 + 12 * sin(t));
    }
    ck_assert_int_eq(amp_convex_hull(pts, n, NULL, hull, &nh, NULL), AMP_OK);
    for (i = 0; i < 3; i++) {
        amp_cx2 k, kh, k1;
        amp_cx2_report rep;
        amp_euler_opts o;
        amp_error err;
        size_t odd;
        amp_cx2_init(&k, NULL);
        amp_cx2_init(&kh, NULL);
        amp_cx2_init(&k1, NULL);
        ck_assert_msg(amp_cx2_grid(&k, hull, nh, 2.5, kinds[i], &err) == AMP_OK, "%s", err.msg);
        ck_assert_msg(amp_cx2_check(&k, &rep, &err) == AMP_OK, "%s", err.msg);
        ck_assert_int_eq(rep.euler_char, 1);
        ck_assert_uint_gt(rep.faces, 20);
        o.offset = 0.4;
        o.combinatorial = 0;
        /* one pass: square and hexagon cells at the rim have adjacent
         * boundary edges and leave odd vertices (the rim triangles of this
         * hull happen to have one boundary edge each) */
        ck_assert_int_eq(amp_euler_transform(&k, &o, &k1, NULL, &err), AMP_OK);
        if (kinds[i] != AMP_GRID_TRI) {
            ck_assert_msg(amp_cx2_check_even(&k1, &odd, &err) == AMP_ERR_CHECK, "grid %d", (int)i);
            ck_assert_uint_gt(odd, 0);
        }
        ck_assert_msg(amp_euler_generalized(&k, &o, &kh, &err) == AMP_OK, "%s", err.msg);
        ck_assert_msg(amp_cx2_check(&kh, &rep, &err) == AMP_OK, "%s", err.msg);
        ck_assert_msg(amp_cx2_check_even(&kh, NULL, &err) == AMP_OK, "grid %d: %s", (int)i, err.msg);
        ck_assert_int_eq(rep.euler_char, 1);
        amp_cx2_free(&k);
        amp_cx2_free(&k1);
        amp_cx2_free(&kh);
    }
}
END_TEST

START_TEST(single_cell_of_fig11_is_odd_after_one_pass_and_even_after_two)
{
    amp_cx2 k, k1, k2;
    amp_euler_opts o;
    amp_cx2_report rep;
    amp_error err;
    size_t odd, v;
    uint32_t idx[5];
    amp_cx2_init(&k, NULL);
    amp_cx2_init(&k1, NULL);
    amp_cx2_init(&k2, NULL);
    /* a pentagon: every pair of adjacent edges is on the boundary */
    for (v = 0; v < 5; v++)
        ck_assert_int_eq(amp_cx2_add_vertex(&k, amp_v2(3 * cos(2 * PI * v / 5), 3 * sin(2 * PI * v / 5)), &idx[v], NULL),
                         AMP_OK);
    ck_assert_int_eq(amp_cx2_add_face(&k, idx, 5, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_build(&k, NULL), AMP_OK);
    o.offset = 0.5;
    o.combinatorial = 0;
    ck_assert_int_eq(amp_euler_transform(&k, &o, &k1, NULL, &err), AMP_OK);
    ck_assert_int_eq(amp_cx2_check_even(&k1, &odd, &err), AMP_ERR_CHECK);
    ck_assert_uint_eq(odd, 10); /* all vertices odd (circled in Fig. 11) */
    for (v = 0; v < k1.nv; v++)
        ck_assert_uint_eq(degree_of(&k1, (uint32_t)v), 3);
    ck_assert_int_eq(amp_euler_generalized(&k, &o, &k2, &err), AMP_OK);
    ck_assert_int_eq(amp_cx2_check(&k2, &rep, &err), AMP_OK);
    ck_assert_int_eq(amp_cx2_check_even(&k2, &odd, &err), AMP_OK);
    ck_assert_uint_eq(odd, 0);
    ck_assert_int_eq(rep.euler_char, 1);
    amp_cx2_free(&k);
    amp_cx2_free(&k1);
    amp_cx2_free(&k2);
}
END_TEST

START_TEST(checkers_fail_on_broken_complexes)
{
    amp_cx2 k, kh;
    amp_euler_opts o;
    amp_cx2_report rep;
    amp_error err;
    size_t odd, f, a, n;
    polar_mesh(&k, 12, 3, 0.0, 7);
    amp_cx2_init(&kh, NULL);
    o.offset = 0.05;
    o.combinatorial = 0;
    ck_assert_int_eq(amp_euler_transform(&k, &o, &kh, NULL, &err), AMP_OK);
    ck_assert_int_eq(amp_cx2_check_even(&kh, &odd, &err), AMP_OK);
    /* a stray 1-cell between copies in two distant Class 1 cells: two odd vertices */
    ck_assert_int_eq(amp_cx2_add_edge(&kh, kh.fidx[0], kh.fidx[kh.fstart[k.nf - 1]], &err), AMP_OK);
    ck_assert_int_eq(amp_cx2_check_even(&kh, &odd, &err), AMP_ERR_CHECK);
    ck_assert_uint_eq(odd, 2);
    ck_assert(strstr(err.msg, "odd degree") != NULL);
    /* reverse one face: misoriented edges and a negative-area cell */
    f = 0;
    a = k.fstart[f];
    n = amp_cx2_face_size(&k, f);
    {
        uint32_t t = k.fidx[a];
        k.fidx[a] = k.fidx[a + n - 1];
        k.fidx[a + n - 1] = t;
    }
    ck_assert_int_eq(amp_cx2_check(&k, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_gt(rep.misoriented, 0);
    ck_assert_uint_eq(rep.bad_faces, 1);
    ck_assert_int_eq(amp_cx2_build(&k, &err), AMP_ERR_GEOMETRY);
    amp_cx2_free(&k);
    amp_cx2_free(&kh);
}
END_TEST

/* Two cells sharing the short edge PQ: f above (acute angles at P, Q: its
 * offset drops PQ), g below with obtuse angles (keeps it), or a mirror of f. */
static void short_edge_complex(amp_cx2 *k, int mirror, uint32_t *P)
{
    amp_vec2 pts[6] = {{0, 0}, {0.5, 0}, {1.5, 3}, {-1, 3}, {-3, -1.5}, {3.5, -1.5}};
    uint32_t id[6], f[4], g[4];
    size_t i;
    if (mirror) {
        pts[4] = amp_v2(-1, -3);
        pts[5] = amp_v2(1.5, -3);
    }
    amp_cx2_init(k, NULL);
    for (i = 0; i < 6; i++)
        ck_assert_int_eq(amp_cx2_add_vertex(k, pts[i], &id[i], NULL), AMP_OK);
    f[0] = id[0], f[1] = id[1], f[2] = id[2], f[3] = id[3];
    g[0] = id[4], g[1] = id[5], g[2] = id[1], g[3] = id[0];
    ck_assert_int_eq(amp_cx2_add_face(k, f, 4, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_add_face(k, g, 4, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_build(k, NULL), AMP_OK);
    *P = id[0];
}

START_TEST(combinatorial_changes_follow_lemma_3_1_degrees)
{
    amp_cx2 k, kh;
    amp_euler_opts o;
    amp_euler_stats st;
    amp_error err;
    uint32_t P, v;
    size_t found = 0;
    short_edge_complex(&k, 0, &P);
    amp_cx2_init(&kh, NULL);
    o.offset = 0.5;
    o.combinatorial = 0;
    ck_assert_int_eq(amp_euler_transform(&k, &o, &kh, NULL, &err), AMP_ERR_GEOMETRY);
    ck_assert(strstr(err.msg, "combinatorially") != NULL);
    o.combinatorial = 1;
    ck_assert_msg(amp_euler_transform(&k, &o, &kh, &st, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(st.collapsed_edges, 1);
    ck_assert_uint_eq(st.collapsed_class2, 0);
    /* the merged copy of P and Q in f (first Class 1 cell) has degree 2π+4 = 6 */
    for (v = 0; v < 3; v++)
        if (degree_of(&kh, kh.fidx[kh.fstart[0] + v]) == 6)
            found++;
    ck_assert_uint_eq(found, 1);
    ck_assert_uint_eq(amp_cx2_face_size(&kh, 0), 3);
    ck_assert_int_eq(amp_cx2_check(&kh, NULL, &err), AMP_OK);
    amp_cx2_free(&kh);
    amp_cx2_free(&k);
    /* both sides collapse: the Class 2 cell becomes an edge, degree 2π+4-m = 5 */
    short_edge_complex(&k, 1, &P);
    ck_assert_msg(amp_euler_transform(&k, &o, &kh, &st, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(st.collapsed_edges, 2);
    ck_assert_uint_eq(st.collapsed_class2, 1);
    ck_assert_uint_eq(kh.nxe, 1);
    ck_assert_uint_eq(degree_of(&kh, kh.xedge[0]), 5);
    ck_assert_uint_eq(degree_of(&kh, kh.xedge[1]), 5);
    ck_assert_int_eq(amp_cx2_check_even(&kh, NULL, &err), AMP_ERR_CHECK);
    ck_assert_int_eq(amp_euler_generalized(&k, &o, &kh, &err), AMP_ERR_UNSUPPORTED);
    amp_cx2_free(&kh);
    amp_cx2_free(&k);
}
END_TEST

START_TEST(bad_inputs_are_rejected_with_reasons)
{
    amp_cx2 k, kh;
    amp_euler_opts o;
    amp_error err;
    amp_vec2 hull[3] = {{0, 0}, {1, 0}, {0, 1}};
    uint32_t idx[3] = {0, 1, 7};
    polar_mesh(&k, 6, 1, 0, 1);
    amp_cx2_init(&kh, NULL);
    o.offset = -1;
    o.combinatorial = 0;
    ck_assert_int_eq(amp_euler_transform(&k, &o, &kh, NULL, &err), AMP_ERR_ARG);
    o.offset = 5; /* larger than the cells: inverted offsets */
    ck_assert_int_eq(amp_euler_transform(&k, &o, &kh, NULL, &err), AMP_ERR_GEOMETRY);
    ck_assert_int_eq(amp_cx2_add_face(&k, idx, 3, 0, &err), AMP_ERR_ARG);
    ck_assert_int_eq(amp_cx2_grid(&kh, hull, 3, 0.0, AMP_GRID_SQUARE, &err), AMP_ERR_ARG);
    amp_ring_reverse(hull, 3);
    ck_assert_int_eq(amp_cx2_grid(&kh, hull, 3, 0.1, AMP_GRID_HEX, &err), AMP_ERR_ARG);
    amp_cx2_free(&k);
    amp_cx2_free(&kh);
}
END_TEST

static Suite *euler_suite(void)
{
    Suite *s = suite_create("euler");
    TCase *tc = tcase_create("core");
    AMP_ADD_TEST(tc, euler_transform_of_a_random_triangulation_has_degree_four_everywhere);
    AMP_ADD_TEST(tc, generalized_transform_makes_square_tri_and_hex_grids_euler);
    AMP_ADD_TEST(tc, single_cell_of_fig11_is_odd_after_one_pass_and_even_after_two);
    AMP_ADD_TEST(tc, checkers_fail_on_broken_complexes);
    AMP_ADD_TEST(tc, combinatorial_changes_follow_lemma_3_1_degrees);
    AMP_ADD_TEST(tc, bad_inputs_are_rejected_with_reasons);
    suite_add_tcase(s, tc);
    return s;
}

AMP_TEST_MAIN(euler_suite)
