/* 2-complexes and the Euler transformation ([P2 §1.3], [P2 §3]). */
#include <math.h>
#include <string.h>

#include "testutil.h"


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

static double seg_dist(amp_vec2 p, amp_vec2 a, amp_vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, t = ((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy);
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    return hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
}

static int cross_sign(amp_vec2 a, amp_vec2 b, amp_vec2 c)
{
    double o = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    return (o > 0) - (o < 0);
}

/*
 * Independent checker of a mitered offset @p m (nm vertices) of the cell @p c
 * (n vertices, CCW) by @p d, combinatorial changes allowed: @p m is a simple
 * CCW polygon inside @p c, no point of it (vertices and 9 points per edge)
 * is closer than d to the boundary of @p c, and every edge of @p m lies on
 * the line of some edge of @p c shifted inward by d, in the same direction;
 * for a convex cell, @p m has the area of the intersection of the shifted
 * half-planes. Returns the number of violations.
 */
static size_t offset_violations(const amp_vec2 *c, size_t n, const amp_vec2 *m, size_t nm, double d)
{
    size_t bad = 0, i, j, e;
    double tol = 1e-9 * (1 + d);
    if (amp_ring_area(m, nm) <= 0)
        bad++;
    for (i = 0; i < nm; i++)
        for (j = i + 2; j < nm; j++) {
            amp_vec2 a = m[i], b = m[(i + 1) % nm], p = m[j], q = m[(j + 1) % nm];
            if (i == 0 && j == nm - 1)
                continue;
            if (cross_sign(a, b, p) * cross_sign(a, b, q) < 0 && cross_sign(p, q, a) * cross_sign(p, q, b) < 0)
                bad++;
        }
    for (i = 0; i < nm; i++) {
        amp_vec2 a = m[i], b = m[(i + 1) % nm];
        int on_line = 0;
        for (j = 0; j <= 10; j++) {
            amp_vec2 p = amp_v2(a.x + (b.x - a.x) * j / 10.0, a.y + (b.y - a.y) * j / 10.0);
            if (amp_ring_contains(c, n, p, 0) != 1)
                bad++;
            for (e = 0; e < n; e++)
                if (seg_dist(p, c[e], c[(e + 1) % n]) < d - tol)
                    bad++;
        }
        for (e = 0; e < n && !on_line; e++) {
            amp_vec2 u = c[e], w = c[(e + 1) % n];
            double l = hypot(w.x - u.x, w.y - u.y), da, db, cr, dot;
            da = ((w.x - u.x) * (a.y - u.y) - (w.y - u.y) * (a.x - u.x)) / l; /* left distance */
            db = ((w.x - u.x) * (b.y - u.y) - (w.y - u.y) * (b.x - u.x)) / l;
            cr = ((w.x - u.x) * (b.y - a.y) - (w.y - u.y) * (b.x - a.x)) / l;
            dot = (w.x - u.x) * (b.x - a.x) + (w.y - u.y) * (b.y - a.y);
            on_line = fabs(da - d) < tol && fabs(db - d) < tol && fabs(cr) < tol && dot > 0;
        }
        bad += !on_line;
    }
    /* a convex cell's mitered offset is all of the intersection of its edges'
     * inner half-planes shifted by d (Sutherland-Hodgman clipping here):
     * equal areas, so no edge was dropped too early */
    {
        amp_vec2 h[2][64];
        size_t nh = n, cur = 0, convex = 1;
        for (e = 0; e < n; e++)
            convex &= cross_sign(c[e], c[(e + 1) % n], c[(e + 2) % n]) >= 0;
        for (i = 0; i < n; i++)
            h[0][i] = c[i];
        for (e = 0; convex && e < n; e++) {
            amp_vec2 u = c[e], w = c[(e + 1) % n];
            double l = hypot(w.x - u.x, w.y - u.y);
            size_t nn = 0;
            for (i = 0; i < nh; i++) {
                amp_vec2 p = h[cur][i], q = h[cur][(i + 1) % nh];
                double sp = ((w.x - u.x) * (p.y - u.y) - (w.y - u.y) * (p.x - u.x)) / l - d;
                double sq = ((w.x - u.x) * (q.y - u.y) - (w.y - u.y) * (q.x - u.x)) / l - d;
                ck_assert_uint_lt(nn + 2, 64);
                if (sp >= 0)
                    h[1 - cur][nn++] = p;
                if ((sp >= 0) != (sq >= 0))
                    h[1 - cur][nn++] = amp_v2(p.x + (q.x - p.x) * sp / (sp - sq), p.y + (q.y - p.y) * sp / (sp - sq));
            }
            cur = 1 - cur;
            nh = nn;
        }
        if (convex && fabs(amp_ring_area(h[cur], nh) - amp_ring_area(m, nm)) > 1e-9 * (1 + fabs(amp_ring_area(c, n))))
            bad++;
    }
    return bad;
}

/* Offsets of all cells of K in K̂ = T(K) (Class 1 cell f is face f of K̂). */
static size_t all_offset_violations(const amp_cx2 *k, const amp_cx2 *kh, double d)
{
    amp_vec2 c[16], m[16];
    size_t f, j, bad = 0;
    for (f = 0; f < k->nf; f++) {
        size_t n = amp_cx2_face_size(k, f), nm = amp_cx2_face_size(kh, f);
        ck_assert_int_eq(kh->fclass[f], AMP_CELL_CLASS1);
        ck_assert(n <= 16 && nm <= n);
        for (j = 0; j < n; j++)
            c[j] = k->v[k->fidx[k->fstart[f] + j]];
        for (j = 0; j < nm; j++)
            m[j] = kh->v[kh->fidx[kh->fstart[f] + j]];
        bad += offset_violations(c, n, m, nm, d);
    }
    return bad;
}

/* Def. 3.2 on @p k: succeeds, a valid complex with Euler characteristic
 * @p chi, every vertex even (amp_cx2_check_even and, for small results,
 * brute-force degrees). */
static void assert_generalized_euler(const amp_cx2 *k, const amp_euler_opts *o, long chi)
{
    amp_cx2 g;
    amp_cx2_report rep;
    amp_error err;
    size_t v;
    amp_cx2_init(&g, NULL);
    ck_assert_msg(amp_euler_generalized(k, o, &g, &err) == AMP_OK, "%s", err.msg);
    ck_assert_msg(amp_cx2_check(&g, &rep, &err) == AMP_OK, "%s", err.msg);
    ck_assert_int_eq(rep.euler_char, chi);
    ck_assert_msg(amp_cx2_check_even(&g, NULL, &err) == AMP_OK, "%s", err.msg);
    for (v = 0; g.nv < 1500 && v < g.nv; v++)
        ck_assert_uint_eq(degree_of(&g, (uint32_t)v) % 2, 0);
    amp_cx2_free(&g);
}

/* Centre (vertex 0) and nring rings of nseg vertices at radii 1..nring,
 * jittered at random (by at most jitter/2 per coordinate, scaled down near
 * the centre when @p scaled), then the fan of triangles around the centre.
 * Ring vertex (r, s) has index 1 + (r - 1) nseg + s. */
static void polar_rings(amp_cx2 *k, int nseg, int nring, double jitter, int scaled, unsigned *seed)
{
    int r, s;
    amp_cx2_init(k, NULL);
    ck_assert_int_eq(amp_cx2_add_vertex(k, amp_v2(0, 0), NULL, NULL), AMP_OK);
    for (r = 1; r <= nring; r++)
        for (s = 0; s < nseg; s++) {
            double t = 2 * AMP_PI * s / nseg, jx, jy, amp = scaled ? jitter * fmin(1.0, r * 2 * AMP_PI / nseg) : jitter;
            *seed = *seed * 1103515245u + 12345u;
            jx = ((*seed >> 8) % 1000 / 1000.0 - 0.5) * amp;
            *seed = *seed * 1103515245u + 12345u;
            jy = ((*seed >> 8) % 1000 / 1000.0 - 0.5) * amp;
            ck_assert_int_eq(amp_cx2_add_vertex(k, amp_v2(r * cos(t) + jx, r * sin(t) + jy), NULL, NULL), AMP_OK);
        }
}

static void polar_fan(amp_cx2 *k, int nseg)
{
    uint32_t v[3];
    int s;
    for (s = 0; s < nseg; s++) {
        v[0] = 0;
        v[1] = (uint32_t)(1 + s);
        v[2] = (uint32_t)(1 + (s + 1) % nseg);
        ck_assert_int_eq(amp_cx2_add_face(k, v, 3, 0, NULL), AMP_OK);
    }
}

/* Polar mesh: a fan of triangles around the centre, then rings of
 * triangles (each quad split in two), every vertex jittered at random.
 * No cell has two adjacent boundary edges. */
static void polar_mesh(amp_cx2 *k, int nseg, int nring, double jitter, unsigned seed)
{
    uint32_t v[3];
    int r, s;
    polar_rings(k, nseg, nring, jitter, 1, &seed);
    polar_fan(k, nseg);
#define PV(rr, ss) ((uint32_t)(1 + ((rr) - 1) * nseg + ((ss) % nseg)))
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
        double t = 2 * AMP_PI * i / 64;
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
        ck_assert_int_eq(amp_cx2_add_vertex(&k, amp_v2(3 * cos(2 * AMP_PI * v / 5), 3 * sin(2 * AMP_PI * v / 5)), &idx[v], NULL),
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

START_TEST(single_cell_with_a_short_edge_drops_it_and_is_euler_after_the_generalized_transform)
{
    /* Fig. 11 with a short edge: a hexagon whose edge 0-1 is 0.1 long */
    amp_vec2 p[6] = {{0, 0}, {0.1, 0}, {2.5, 1.5}, {2.2, 4}, {-2, 4}, {-2.4, 1.5}};
    amp_cx2 k, k1;
    amp_euler_opts o;
    amp_euler_stats st;
    amp_error err;
    uint32_t idx[6];
    size_t v;
    amp_cx2_init(&k, NULL);
    amp_cx2_init(&k1, NULL);
    for (v = 0; v < 6; v++)
        ck_assert_int_eq(amp_cx2_add_vertex(&k, p[v], &idx[v], NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_add_face(&k, idx, 6, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_build(&k, NULL), AMP_OK);
    o.offset = 0.4;
    o.combinatorial = 0;
    ck_assert_int_eq(amp_euler_transform(&k, &o, &k1, NULL, &err), AMP_ERR_GEOMETRY);
    o.combinatorial = 1;
    ck_assert_msg(amp_euler_transform(&k, &o, &k1, &st, &err) == AMP_OK, "%s", err.msg);
    /* a boundary edge's Class 2 cell (a, b, b_f, a_f) becomes a triangle, never an edge */
    ck_assert_uint_eq(st.collapsed_edges, 1);
    ck_assert_uint_eq(st.collapsed_class2, 0);
    ck_assert_uint_eq(amp_cx2_face_size(&k1, 0), 5);
    ck_assert_int_eq(amp_cx2_check_even(&k1, NULL, &err), AMP_ERR_CHECK);
    assert_generalized_euler(&k, &o, 1);
    amp_cx2_free(&k);
    amp_cx2_free(&k1);
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
    amp_cx2_free(&kh);
    amp_cx2_free(&k);
}
END_TEST

/* The 1-skeleton of @p k, each edge once: sorted undirected keys. */
static size_t skeleton(const amp_cx2 *k, uint64_t *e, size_t cap)
{
    size_t f, h, n = 0, i, m = 0;
    for (f = 0; f < k->nf; f++)
        for (h = k->fstart[f]; h < k->fstart[f + 1]; h++) {
            uint32_t a = k->fidx[h], b = k->fidx[h + 1 < k->fstart[f + 1] ? h + 1 : k->fstart[f]];
            ck_assert_uint_lt(n, cap);
            e[n++] = a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
        }
    for (i = 0; i < k->nxe; i++) {
        uint32_t a = k->xedge[2 * i], b = k->xedge[2 * i + 1];
        ck_assert_uint_lt(n, cap);
        e[n++] = a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
    }
    /* insertion sort is enough for the small complexes of these tests */
    for (i = 1; i < n; i++) {
        uint64_t x = e[i];
        size_t j = i;
        for (; j > 0 && e[j - 1] > x; j--)
            e[j] = e[j - 1];
        e[j] = x;
    }
    for (i = 0; i < n; i++)
        if (m == 0 || e[m - 1] != e[i])
            e[m++] = e[i];
    return m;
}

/* Checks of a Lemma 3.3 result @p r of @p kh = T(K): valid complex with the
 * Euler characteristic of K, pure, the ends of every collapsed edge even,
 * exactly @p odd odd vertices left (brute-force degrees and
 * amp_cx2_check_even), and K̂'s Class 1 cells kept as they were (same
 * vertex loops). */
static void check_repaired(const amp_cx2 *kh, const amp_cx2 *r, long chi, size_t odd)
{
    amp_cx2_report rep;
    amp_error err;
    size_t v, f, g, kept = 0, class1 = 0, nodd = 0, codd;
    ck_assert_msg(amp_cx2_check(r, &rep, &err) == AMP_OK, "%s", err.msg);
    ck_assert_int_eq(rep.euler_char, chi);
    ck_assert_int_eq(amp_cx2_check_even(r, &codd, &err), odd ? AMP_ERR_CHECK : AMP_OK);
    ck_assert_uint_eq(codd, odd);
    for (v = 0; v < r->nv; v++)
        nodd += degree_of(r, (uint32_t)v) % 2;
    ck_assert_uint_eq(nodd, odd);
    for (v = 0; v < 2 * kh->nxe; v++)
        ck_assert_uint_eq(degree_of(r, kh->xedge[v]) % 2, 0);
    ck_assert_uint_eq(r->nxe, 0);
    /* every Class 1 cell of K̂ is still there, unchanged */
    for (f = 0; f < kh->nf; f++) {
        if (kh->fclass[f] != AMP_CELL_CLASS1)
            continue;
        class1++;
        for (g = 0; g < r->nf; g++)
            if (amp_cx2_face_size(r, g) == amp_cx2_face_size(kh, f) &&
                memcmp(r->fidx + r->fstart[g], kh->fidx + kh->fstart[f],
                       amp_cx2_face_size(kh, f) * sizeof *kh->fidx) == 0) {
                kept++;
                break;
            }
    }
    ck_assert_uint_eq(kept, class1);
}

START_TEST(lemma_3_3_repairs_the_collapsed_class2_cell_of_fig9)
{
    amp_cx2 k, kh, r;
    amp_euler_opts o;
    amp_euler_stats st;
    amp_euler_repair_stats rs;
    amp_error err;
    uint32_t P;
    uint64_t ek[512];
    size_t odd, ne, i;
    short_edge_complex(&k, 1, &P);
    amp_cx2_init(&kh, NULL);
    amp_cx2_init(&r, NULL);
    o.offset = 0.5;
    o.combinatorial = 1;
    ck_assert_msg(amp_euler_transform(&k, &o, &kh, &st, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(st.collapsed_class2, 1);
    ck_assert_int_eq(amp_cx2_check_even(&kh, &odd, &err), AMP_ERR_CHECK);
    /* the two ends of ê (degree 5), and the corners 2, 3 of each cell, which
     * join two boundary edges, with their copies (Fig. 11): 2 + 4 + 4 */
    ck_assert_uint_eq(odd, 10);
    ck_assert_uint_eq(degree_of(&kh, kh.xedge[0]), 5);
    ck_assert_msg(amp_euler_repair(&kh, &r, &rs, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(rs.collapsed_edges, 1);
    ck_assert_uint_eq(rs.cells, 2); /* the Class 3 cells of P and Q */
    ck_assert_uint_eq(rs.components, 1);
    check_repaired(&kh, &r, 1, 8);
    /* ê itself is gone: it was inside k̂ */
    ne = skeleton(&r, ek, 512);
    for (i = 0; i < ne; i++)
        ck_assert(ek[i] != (((uint64_t)(kh.xedge[0] < kh.xedge[1] ? kh.xedge[0] : kh.xedge[1]) << 32) |
                            (kh.xedge[0] < kh.xedge[1] ? kh.xedge[1] : kh.xedge[0])));
    /* Def. 3.2 with the repair in between: Euler as well */
    assert_generalized_euler(&k, &o, 1);
    amp_cx2_free(&r);
    amp_cx2_free(&kh);
    amp_cx2_free(&k);
}
END_TEST

/* Polar quad mesh: a fan of triangles around the centre, then rings of
 * quads, every vertex jittered; then radial edges of every other ring band
 * are pinched (about one in three, no two in one quad) to a length of
 * 0.02-0.06, a short edge whose two quads both drop it when offset by 0.1
 * (Fig. 9). No cell has two adjacent boundary edges. Returns the number of
 * pinched edges. */
static size_t pinched_polar_quads(amp_cx2 *k, int nseg, int nring, double jitter, unsigned seed, int merge)
{
    uint32_t v[6];
    int r, s;
    size_t pinched = 0;
    polar_rings(k, nseg, nring, jitter, 0, &seed);
#define QV(rr, ss) ((uint32_t)(1 + ((rr) - 1) * nseg + ((ss) % nseg)))
    for (r = 2; r < nring; r += 2)
        for (s = 0; s < nseg; s += 3) {
            amp_vec2 *p, *q, m;
            double len, want;
            seed = seed * 1103515245u + 12345u;
            if ((seed >> 12) % 3 == 0 || s + 3 > nseg)
                continue;
            p = &k->v[QV(r, s)];
            q = &k->v[QV(r + 1, s)];
            m = amp_v2(0.5 * (p->x + q->x), 0.5 * (p->y + q->y));
            len = hypot(q->x - p->x, q->y - p->y);
            want = 0.02 + 0.04 * ((seed >> 16) % 1000 / 1000.0);
            *p = amp_v2(m.x + (p->x - m.x) * want / len, m.y + (p->y - m.y) * want / len);
            *q = amp_v2(m.x + (q->x - m.x) * want / len, m.y + (q->y - m.y) * want / len);
            pinched++;
        }
    /* merge: in the pinched bands, cells s and s+1 with s = 1 mod 3 become
     * one hexagon whose middle inner corner, pushed 0.3 outward (into it),
     * is reflex; every vertex keeps degree >= 3 (not in the rim band, where
     * the middle outer corner would join two boundary edges) */
    for (r = 2; merge && r + 1 < nring; r += 2)
        for (s = 2; s < nseg; s += 3) {
            amp_vec2 *p = &k->v[QV(r, s)];
            double l = hypot(p->x, p->y);
            *p = amp_v2(p->x + 0.3 * p->x / l, p->y + 0.3 * p->y / l);
        }
    polar_fan(k, nseg);
    for (r = 1; r < nring; r++)
        for (s = 0; s < nseg; s++) {
            if (merge && r % 2 == 0 && r + 1 < nring && s % 3 == 1 && s + 2 <= nseg) {
                /* CCW: out along s, the outer arc, in along s+2, the inner arc */
                v[0] = QV(r, s);
                v[1] = QV(r + 1, s);
                v[2] = QV(r + 1, s + 1);
                v[3] = QV(r + 1, s + 2);
                v[4] = QV(r, s + 2);
                v[5] = QV(r, s + 1);
                ck_assert_int_eq(amp_cx2_add_face(k, v, 6, 0, NULL), AMP_OK);
                s++;
                continue;
            }
            v[0] = QV(r, s);
            v[1] = QV(r + 1, s);
            v[2] = QV(r + 1, s + 1);
            v[3] = QV(r, s + 1);
            ck_assert_int_eq(amp_cx2_add_face(k, v, 4, 0, NULL), AMP_OK);
        }
#undef QV
    ck_assert_int_eq(amp_cx2_build(k, NULL), AMP_OK);
    return pinched;
}

START_TEST(lemma_3_3_makes_random_quad_meshes_with_short_edges_euler)
{
    unsigned seed;
    size_t total = 0;
    for (seed = 1; seed <= 12; seed++) {
        amp_cx2 k, kh, r;
        amp_cx2_report rep;
        amp_euler_opts o;
        amp_euler_stats st;
        amp_euler_repair_stats rs;
        amp_error err;
        size_t odd, v, i, pinched = pinched_polar_quads(&k, 18, 7, 0.12, seed, 0);
        ck_assert_msg(amp_cx2_check(&k, &rep, &err) == AMP_OK, "%s", err.msg);
        amp_cx2_init(&kh, NULL);
        amp_cx2_init(&r, NULL);
        o.offset = 0.1;
        o.combinatorial = 1;
        ck_assert_msg(amp_euler_transform(&k, &o, &kh, &st, &err) == AMP_OK, "seed %u: %s", seed, err.msg);
        ck_assert_uint_eq(all_offset_violations(&k, &kh, 0.1), 0);
        /* every pinched edge collapses on both sides: one free 1-cell each */
        ck_assert_uint_eq(st.collapsed_class2, pinched);
        ck_assert_uint_eq(st.collapsed_edges, 2 * pinched);
        total += pinched;
        /* T(K) is odd exactly at the ends of the collapsed edges (Lemma 3.1,
         * π = m = 1: degree 5), everything else has degree 4 */
        ck_assert_int_eq(amp_cx2_check_even(&kh, &odd, &err), pinched ? AMP_ERR_CHECK : AMP_OK);
        ck_assert_uint_eq(odd, 2 * pinched);
        for (i = 0; i < 2 * kh.nxe; i++)
            ck_assert_uint_eq(degree_of(&kh, kh.xedge[i]), 5);
        ck_assert_msg(amp_euler_repair(&kh, &r, &rs, &err) == AMP_OK, "seed %u: %s", seed, err.msg);
        ck_assert_uint_eq(rs.collapsed_edges, pinched);
        ck_assert_uint_eq(rs.cells, 2 * pinched);
        ck_assert_uint_eq(rs.components, pinched);
        check_repaired(&kh, &r, 1, 0);
        /* vertices outside k̂ (the cells with an edge ê) keep their degree */
        {
            unsigned char in_k[4096];
            size_t f, h, e;
            ck_assert_uint_lt(kh.nv, sizeof in_k);
            memset(in_k, 0, sizeof in_k);
            for (f = 0; f < kh.nf; f++)
                for (h = kh.fstart[f]; h < kh.fstart[f + 1]; h++) {
                    uint32_t a = kh.fidx[h], b = kh.fidx[h + 1 < kh.fstart[f + 1] ? h + 1 : kh.fstart[f]];
                    for (e = 0; e < kh.nxe; e++)
                        if ((kh.xedge[2 * e] == a && kh.xedge[2 * e + 1] == b) ||
                            (kh.xedge[2 * e] == b && kh.xedge[2 * e + 1] == a)) {
                            ck_assert_int_eq(kh.fclass[f], AMP_CELL_CLASS3);
                            for (i = kh.fstart[f]; i < kh.fstart[f + 1]; i++)
                                in_k[kh.fidx[i]] = 1;
                        }
                }
            for (v = 0; v < kh.nv; v++)
                if (!in_k[v])
                    ck_assert_uint_eq(degree_of(&r, (uint32_t)v), degree_of(&kh, (uint32_t)v));
                else /* 2 edges outside k̂ (Lemma 3.3 proof), 4 in T(T(k̂)) per fan */
                    ck_assert_uint_eq(degree_of(&r, (uint32_t)v) % 2, 0);
        }
        /* Def. 3.2 with the repair between the passes */
        assert_generalized_euler(&k, &o, 1);
        if (pinched) {
            /* broken results: ê put back makes its two ends odd; a reversed
             * cell of T(T(k̂)) is misoriented */
            size_t f = r.nf - 1, a = r.fstart[f], n = amp_cx2_face_size(&r, f), j;
            ck_assert_int_eq(amp_cx2_add_edge(&r, kh.xedge[0], kh.xedge[1], &err), AMP_OK);
            ck_assert_int_eq(amp_cx2_check_even(&r, &odd, &err), AMP_ERR_CHECK);
            ck_assert_uint_eq(odd, 2);
            for (j = 0; j < n / 2; j++) {
                uint32_t t = r.fidx[a + j];
                r.fidx[a + j] = r.fidx[a + n - 1 - j];
                r.fidx[a + n - 1 - j] = t;
            }
            ck_assert_int_eq(amp_cx2_check(&r, &rep, &err), AMP_ERR_CHECK);
            ck_assert_uint_gt(rep.misoriented, 0);
        }
        amp_cx2_free(&r);
        amp_cx2_free(&kh);
        amp_cx2_free(&k);
    }
    ck_assert_uint_gt(total, 20);
}
END_TEST

START_TEST(generalized_transform_is_euler_on_a_hex_grid_with_short_edges_and_rim_cells)
{
    amp_vec2 pts[48], hull[48];
    size_t n, nh, h, pinched = 0, i;
    unsigned seed = 99;
    unsigned char used[8192];
    amp_cx2 k, kh;
    amp_cx2_report rep;
    amp_euler_opts o;
    amp_euler_stats st;
    amp_error err;
    for (n = 0; n < 48; n++)
        pts[n] = amp_v2(4 + 14 * cos(2 * AMP_PI * n / 48), 2 + 9 * sin(2 * AMP_PI * n / 48));
    ck_assert_int_eq(amp_convex_hull(pts, n, NULL, hull, &nh, NULL), AMP_OK);
    amp_cx2_init(&k, NULL);
    amp_cx2_init(&kh, NULL);
    ck_assert_int_eq(amp_cx2_grid(&k, hull, nh, 1.5, AMP_GRID_HEX, &err), AMP_OK);
    ck_assert_uint_lt(k.nv, sizeof used);
    memset(used, 0, sizeof used);
    /* pinch about a third of the interior edges, none sharing a vertex, to
     * 3-8 % of the cell (Fig. 12: hexagons losing edges on both sides) */
    for (h = 0; h < k.nfidx; h++) {
        size_t t = k.he_twin[h];
        uint32_t a = k.fidx[h], b = k.fidx[amp_cx2_he_next(&k, h)];
        amp_vec2 m;
        double len, want;
        seed = seed * 1103515245u + 12345u;
        if (t == AMP_CX2_NONE || t < h || used[a] || used[b] || (seed >> 12) % 3)
            continue;
        /* keep the neighbours of a pinched edge untouched too */
        for (i = k.fstart[k.he_face[h]]; i < k.fstart[k.he_face[h] + 1]; i++)
            used[k.fidx[i]] = 1;
        for (i = k.fstart[k.he_face[t]]; i < k.fstart[k.he_face[t] + 1]; i++)
            used[k.fidx[i]] = 1;
        m = amp_v2(0.5 * (k.v[a].x + k.v[b].x), 0.5 * (k.v[a].y + k.v[b].y));
        len = hypot(k.v[b].x - k.v[a].x, k.v[b].y - k.v[a].y);
        want = 1.5 * (0.03 + 0.05 * ((seed >> 16) % 1000 / 1000.0));
        k.v[a] = amp_v2(m.x + (k.v[a].x - m.x) * want / len, m.y + (k.v[a].y - m.y) * want / len);
        k.v[b] = amp_v2(m.x + (k.v[b].x - m.x) * want / len, m.y + (k.v[b].y - m.y) * want / len);
        pinched++;
    }
    ck_assert_uint_gt(pinched, 5);
    ck_assert_msg(amp_cx2_check(&k, &rep, &err) == AMP_OK, "%s", err.msg);
    o.offset = 0.25;
    o.combinatorial = 1;
    ck_assert_msg(amp_euler_transform(&k, &o, &kh, &st, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(st.collapsed_class2, pinched);
    ck_assert_int_eq(amp_cx2_check_even(&kh, NULL, &err), AMP_ERR_CHECK);
    assert_generalized_euler(&k, &o, 1);
    amp_cx2_free(&kh);
    amp_cx2_free(&k);
}
END_TEST

START_TEST(offsets_of_random_convex_cells_are_the_intersection_of_shifted_half_planes)
{
    unsigned seed = 4242;
    int trial, ok = 0, changed = 0;
    for (trial = 0; trial < 300; trial++) {
        amp_vec2 pts[12], hull[12];
        size_t n, j;
        uint32_t idx[12];
        amp_cx2 k, kh;
        amp_euler_opts o;
        amp_euler_stats st;
        amp_error err;
        for (j = 0; j < 12; j++) {
            double t, rr;
            seed = seed * 1103515245u + 12345u;
            t = 2 * AMP_PI * ((seed >> 8) % 10000) / 10000.0;
            seed = seed * 1103515245u + 12345u;
            rr = 1 + 0.4 * ((seed >> 8) % 1000) / 1000.0;
            pts[j] = amp_v2(rr * 3 * cos(t), rr * 2 * sin(t));
        }
        ck_assert_int_eq(amp_convex_hull(pts, 12, NULL, hull, &n, NULL), AMP_OK);
        amp_cx2_init(&k, NULL);
        amp_cx2_init(&kh, NULL);
        for (j = 0; j < n; j++)
            ck_assert_int_eq(amp_cx2_add_vertex(&k, hull[j], &idx[j], NULL), AMP_OK);
        ck_assert_int_eq(amp_cx2_add_face(&k, idx, n, 0, NULL), AMP_OK);
        ck_assert_int_eq(amp_cx2_build(&k, NULL), AMP_OK);
        seed = seed * 1103515245u + 12345u;
        o.offset = 0.1 + 1.2 * ((seed >> 8) % 1000) / 1000.0;
        o.combinatorial = 1;
        if (amp_euler_transform(&k, &o, &kh, &st, &err) == AMP_OK) {
            ck_assert_msg(all_offset_violations(&k, &kh, o.offset) == 0, "trial %d", trial);
            ok++;
            changed += st.collapsed_edges > 1;
        } else /* only the cell vanishing (n - 3 edges gone) is refused */
            ck_assert_msg(strstr(err.msg, "vanish") != NULL, "%s", err.msg);
        amp_cx2_free(&kh);
        amp_cx2_free(&k);
    }
    ck_assert_int_gt(ok, 100);
    ck_assert_int_gt(changed, 30); /* several edges dropped in one cell */
}
END_TEST

START_TEST(offsets_of_random_star_shaped_cells_are_valid_or_refused_as_topological_changes)
{
    unsigned seed = 777;
    int trial, ok = 0, dropped = 0, split = 0;
    for (trial = 0; trial < 300; trial++) {
        amp_vec2 pts[12];
        size_t n = 8 + trial % 5, j;
        uint32_t idx[12];
        amp_cx2 k, kh;
        amp_euler_opts o;
        amp_euler_stats st;
        amp_error err;
        int reflex = 0;
        amp_cx2_init(&k, NULL);
        amp_cx2_init(&kh, NULL);
        /* star-shaped around the origin: vertex j at a random angle in
         * sector j (0.95 of it, so neighbours come very close at times and
         * leave short edges) and a random radius */
        for (j = 0; j < n; j++) {
            double t, rr;
            seed = seed * 1103515245u + 12345u;
            t = 2 * AMP_PI * (j + 0.95 * ((seed >> 8) % 1000) / 1000.0) / n;
            seed = seed * 1103515245u + 12345u;
            rr = 1 + 2 * ((seed >> 8) % 1000) / 1000.0;
            pts[j] = amp_v2(rr * cos(t), rr * sin(t));
        }
        for (j = 0; j < n; j++)
            ck_assert_int_eq(amp_cx2_add_vertex(&k, pts[j], &idx[j], NULL), AMP_OK);
        for (j = 0; j < n; j++)
            reflex += cross_sign(pts[j], pts[(j + 1) % n], pts[(j + 2) % n]) < 0;
        ck_assert_int_eq(amp_cx2_add_face(&k, idx, n, 0, NULL), AMP_OK);
        ck_assert_int_eq(amp_cx2_build(&k, NULL), AMP_OK);
        seed = seed * 1103515245u + 12345u;
        o.offset = 0.05 + 0.75 * ((seed >> 8) % 1000) / 1000.0;
        o.combinatorial = 1;
        if (amp_euler_transform(&k, &o, &kh, &st, &err) == AMP_OK) {
            ck_assert_msg(all_offset_violations(&k, &kh, o.offset) == 0, "trial %d", trial);
            ok++;
            dropped += reflex && st.collapsed_edges > 0;
        } else {
            ck_assert_msg(strstr(err.msg, "topological change") != NULL, "%s", err.msg);
            split += strstr(err.msg, "not simple") != NULL;
        }
        amp_cx2_free(&kh);
        amp_cx2_free(&k);
    }
    ck_assert_int_gt(ok, 100);
    ck_assert_msg(dropped > 30, "ok %d dropped %d split %d", ok, dropped, split);
    ck_assert_int_gt(split, 0);    /* and splits detected */
}
END_TEST

START_TEST(combinatorial_changes_in_non_convex_cells_give_true_offsets_and_euler_after_repair)
{
    unsigned seed;
    size_t total = 0;
    for (seed = 1; seed <= 8; seed++) {
        amp_cx2 k, kh, r, k9;
        amp_cx2_report rep;
        amp_euler_opts o;
        amp_euler_stats st;
        amp_error err;
        size_t odd, f, reflex = 0, pinched = pinched_polar_quads(&k, 18, 7, 0.12, seed, 1);
        ck_assert_msg(amp_cx2_check(&k, &rep, &err) == AMP_OK, "%s", err.msg);
        for (f = 0; f < k.nf; f++) {
            size_t a = k.fstart[f], n = amp_cx2_face_size(&k, f), j;
            for (j = 0; j < n; j++)
                reflex += amp_v2_orient(k.v[k.fidx[a + j]], k.v[k.fidx[a + (j + 1) % n]], k.v[k.fidx[a + (j + 2) % n]]) < 0;
        }
        ck_assert_uint_ge(reflex, 12); /* the merged cells are non-convex */
        amp_cx2_init(&kh, NULL);
        amp_cx2_init(&r, NULL);
        amp_cx2_init(&k9, NULL);
        o.offset = 0.1;
        o.combinatorial = 1;
        ck_assert_msg(amp_euler_transform(&k, &o, &kh, &st, &err) == AMP_OK, "seed %u: %s", seed, err.msg);
        ck_assert_uint_eq(st.collapsed_class2, pinched);
        total += pinched;
        /* non-convex cells did drop edges */
        {
            size_t dropped = 0;
            for (f = 0; f < k.nf; f++) {
                size_t a = k.fstart[f], n = amp_cx2_face_size(&k, f), j, rx = 0;
                for (j = 0; j < n; j++)
                    rx += amp_v2_orient(k.v[k.fidx[a + j]], k.v[k.fidx[a + (j + 1) % n]], k.v[k.fidx[a + (j + 2) % n]]) < 0;
                dropped += rx && amp_cx2_face_size(&kh, f) < n;
            }
            ck_assert_uint_gt(dropped, 0);
        }
        /* every Class 1 cell is the true mitered offset, dropped edges included */
        ck_assert_uint_eq(all_offset_violations(&k, &kh, 0.1), 0);
        /* the checker fails on offsets by another distance and on a moved vertex */
        ck_assert_uint_gt(all_offset_violations(&k, &kh, 0.11), 0);
        o.offset = 0.09;
        ck_assert_int_eq(amp_euler_transform(&k, &o, &k9, NULL, &err), AMP_OK);
        ck_assert_uint_gt(all_offset_violations(&k, &k9, 0.1), 0);
        k9.v[k9.fidx[k9.fstart[k.nf / 2]]].x += 0.01;
        ck_assert_uint_gt(all_offset_violations(&k, &k9, 0.09), 0);
        o.offset = 0.1;
        /* odd exactly at the ends of ê, Euler after Lemma 3.3 and after Def. 3.2 */
        ck_assert_int_eq(amp_cx2_check_even(&kh, &odd, &err), pinched ? AMP_ERR_CHECK : AMP_OK);
        ck_assert_uint_eq(odd, 2 * pinched);
        ck_assert_msg(amp_euler_repair(&kh, &r, NULL, &err) == AMP_OK, "seed %u: %s", seed, err.msg);
        check_repaired(&kh, &r, 1, 0);
        assert_generalized_euler(&k, &o, 1);
        amp_cx2_free(&k9);
        amp_cx2_free(&r);
        amp_cx2_free(&kh);
        amp_cx2_free(&k);
    }
    ck_assert_uint_gt(total, 12);
}
END_TEST

START_TEST(a_reflex_corner_running_into_an_edge_is_a_rejected_topological_change)
{
    /* a notch whose reflex corner (2, 0.6) is 0.6 above the bottom edge:
     * fine at offset 0.2, split at 0.5 */
    amp_vec2 p[5] = {{0, 0}, {4, 0}, {4, 3}, {2, 0.6}, {0, 3}};
    amp_cx2 k, kh;
    amp_euler_opts o;
    amp_error err;
    uint32_t idx[5];
    size_t v;
    int comb;
    amp_cx2_init(&k, NULL);
    amp_cx2_init(&kh, NULL);
    for (v = 0; v < 5; v++)
        ck_assert_int_eq(amp_cx2_add_vertex(&k, p[v], &idx[v], NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_add_face(&k, idx, 5, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_build(&k, NULL), AMP_OK);
    for (comb = 0; comb < 2; comb++) {
        o.combinatorial = comb;
        o.offset = 0.2;
        ck_assert_msg(amp_euler_transform(&k, &o, &kh, NULL, &err) == AMP_OK, "%s", err.msg);
        ck_assert_uint_eq(all_offset_violations(&k, &kh, 0.2), 0);
        o.offset = 0.5;
        ck_assert_int_eq(amp_euler_transform(&k, &o, &kh, NULL, &err), AMP_ERR_GEOMETRY);
        ck_assert_msg(strstr(err.msg, "topological change") != NULL, "%s", err.msg);
    }
    amp_cx2_free(&kh);
    amp_cx2_free(&k);
}
END_TEST

START_TEST(interior_vertex_of_degree_two_is_odd_after_one_pass_and_even_after_two)
{
    /* two 3 x 2 cells sharing an edge split by N = (3, 1): a straight angle
     * in both cells, and a Class 3 cell that would be a digon */
    amp_vec2 p[7] = {{0, 0}, {3, 0}, {3, 1}, {3, 2}, {0, 2}, {6, 0}, {6, 2}};
    uint32_t a[5] = {0, 1, 2, 3, 4}, b[5] = {1, 5, 6, 3, 2};
    amp_cx2 k, k1;
    amp_euler_opts o;
    amp_error err;
    size_t v;
    amp_cx2_init(&k, NULL);
    amp_cx2_init(&k1, NULL);
    for (v = 0; v < 7; v++)
        ck_assert_int_eq(amp_cx2_add_vertex(&k, p[v], NULL, NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_add_face(&k, a, 5, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_add_face(&k, b, 5, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_cx2_build(&k, NULL), AMP_OK);
    o.offset = 0.3;
    o.combinatorial = 0;
    ck_assert_msg(amp_euler_transform(&k, &o, &k1, NULL, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(all_offset_violations(&k, &k1, 0.3), 0);
    /* the copies of N in both cells (offset vertex j is the copy of corner
     * j + 1): degree 3 */
    ck_assert_uint_eq(degree_of(&k1, k1.fidx[k1.fstart[0] + 1]), 3);
    ck_assert_uint_eq(degree_of(&k1, k1.fidx[k1.fstart[1] + 3]), 3);
    assert_generalized_euler(&k, &o, 1);
    amp_cx2_free(&k);
    amp_cx2_free(&k1);
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
    /* Lemma 3.3 repair: only free 1-cells between Class 3 cells of a built T(K) */
    {
        amp_cx2 r;
        uint32_t P;
        short_edge_complex(&k, 1, &P);
        amp_cx2_init(&r, NULL);
        o.offset = 0.5;
        o.combinatorial = 1;
        ck_assert_int_eq(amp_euler_transform(&k, &o, &kh, NULL, &err), AMP_OK);
        ck_assert_int_eq(amp_euler_repair(&kh, &kh, NULL, &err), AMP_ERR_ARG);
        ck_assert_int_eq(amp_cx2_add_edge(&kh, kh.fidx[0], kh.fidx[1], &err), AMP_OK); /* an edge of a Class 1 cell */
        ck_assert_int_eq(amp_euler_repair(&kh, &r, NULL, &err), AMP_ERR_GEOMETRY);
        ck_assert(strstr(err.msg, "Class 3") != NULL);
        kh.nxe--;
        ck_assert_int_eq(amp_cx2_add_edge(&kh, kh.fidx[0], kh.fidx[kh.fstart[1]], &err), AMP_OK); /* in no cell */
        ck_assert_int_eq(amp_euler_repair(&kh, &r, NULL, &err), AMP_ERR_GEOMETRY);
        ck_assert(strstr(err.msg, "in no 2-cell") != NULL);
        ck_assert_uint_eq(r.nf, 0);
        ck_assert_int_eq(amp_cx2_add_face(&kh, kh.fidx, 3, AMP_CELL_CLASS3, &err), AMP_OK); /* topology not rebuilt */
        ck_assert_int_eq(amp_euler_repair(&kh, &r, NULL, &err), AMP_ERR_STATE);
        amp_cx2_free(&r);
        amp_cx2_free(&kh);
        amp_cx2_free(&k);
    }
}
END_TEST

static Suite *euler_suite(void)
{
    Suite *s = suite_create("euler");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, euler_transform_of_a_random_triangulation_has_degree_four_everywhere);
    tcase_add_test(tc, generalized_transform_makes_square_tri_and_hex_grids_euler);
    tcase_add_test(tc, single_cell_of_fig11_is_odd_after_one_pass_and_even_after_two);
    tcase_add_test(tc, single_cell_with_a_short_edge_drops_it_and_is_euler_after_the_generalized_transform);
    tcase_add_test(tc, interior_vertex_of_degree_two_is_odd_after_one_pass_and_even_after_two);
    tcase_add_test(tc, checkers_fail_on_broken_complexes);
    tcase_add_test(tc, combinatorial_changes_follow_lemma_3_1_degrees);
    tcase_add_test(tc, lemma_3_3_repairs_the_collapsed_class2_cell_of_fig9);
    tcase_add_test(tc, lemma_3_3_makes_random_quad_meshes_with_short_edges_euler);
    tcase_add_test(tc, generalized_transform_is_euler_on_a_hex_grid_with_short_edges_and_rim_cells);
    tcase_add_test(tc, offsets_of_random_convex_cells_are_the_intersection_of_shifted_half_planes);
    tcase_add_test(tc, offsets_of_random_star_shaped_cells_are_valid_or_refused_as_topological_changes);
    tcase_add_test(tc, combinatorial_changes_in_non_convex_cells_give_true_offsets_and_euler_after_repair);
    tcase_add_test(tc, a_reflex_corner_running_into_an_edge_is_a_rejected_topological_change);
    tcase_add_test(tc, bad_inputs_are_rejected_with_reasons);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(euler_suite)
