/* Material deposition radius (paper §5.2, Def. 5.4). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define PI AMP_PI

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

/* Reference segment distance: the closest pair is an end of one segment against the other segment, or an
 * interior pair where the connecting line is perpendicular to both (then the lines' distance). */
static double ref_seg_dist(amp_vec3 p1, amp_vec3 q1, amp_vec3 p2, amp_vec3 q2)
{
    amp_vec3 d1 = amp_v3_sub(q1, p1), d2 = amp_v3_sub(q2, p2), w = amp_v3_sub(p1, p2);
    double best = fmin(fmin(amp_v3_seg_dist2(p1, p2, q2, NULL), amp_v3_seg_dist2(q1, p2, q2, NULL)),
                       fmin(amp_v3_seg_dist2(p2, p1, q1, NULL), amp_v3_seg_dist2(q2, p1, q1, NULL)));
    double a = amp_v3_dot(d1, d1), b = amp_v3_dot(d1, d2), c = amp_v3_dot(d2, d2), d = amp_v3_dot(d1, w),
           e = amp_v3_dot(d2, w), den = a * c - b * b;
    if (den > 1e-12 * a * c) {
        double s = (b * e - c * d) / den, t = (a * e - b * d) / den;
        if (s > 0 && s < 1 && t > 0 && t < 1)
            best = fmin(best, amp_v3_dist2(amp_v3_madd(p1, d1, s), amp_v3_madd(p2, d2, t)));
    }
    return sqrt(best);
}

/* Def. 5.4 by brute force: every pair of fragments within 2 r_max (not the same path closer than 2 r_max along
 * it), and the tubes frozen one at a time, always the one that touches first. */
static void reference_radii(const amp_fragments *fs, const amp_mdr_opts *o, double *r)
{
    size_t n = fs->n, i, j, a, b, left = n;
    double *dist = calloc(n * n, sizeof *dist), *arc = calloc(n, sizeof *arc);
    unsigned char *frozen = calloc(n, 1), *any = calloc(n, 1);
    ck_assert(dist && arc && frozen && any);
    for (i = 0; i < n; i++) {
        const amp_fragment *f = &fs->frag[i];
        double len = 0;
        for (a = 0; a + 1 < amp_fragment_npoints(f); a++)
            len += amp_v3_dist(amp_fragment_point(fs, f, a), amp_fragment_point(fs, f, a + 1));
        arc[i] = (i > 0 && fs->frag[i - 1].path == f->path ? arc[i - 1] : 0.0) + len;
    }
    for (i = 0; i < n; i++)
        for (j = i + 1; j < n; j++) {
            const amp_fragment *fi = &fs->frag[i], *fj = &fs->frag[j];
            double d = HUGE_VAL;
            if (fi->path == fj->path && arc[j - 1] - arc[i] < 2 * o->r_max) {
                dist[i * n + j] = dist[j * n + i] = HUGE_VAL;
                continue;
            }
            for (a = 0; a + 1 < amp_fragment_npoints(fi); a++)
                for (b = 0; b + 1 < amp_fragment_npoints(fj); b++)
                    d = fmin(d, ref_seg_dist(amp_fragment_point(fs, fi, a), amp_fragment_point(fs, fi, a + 1),
                                             amp_fragment_point(fs, fj, b), amp_fragment_point(fs, fj, b + 1)));
            if (d >= 2 * o->r_max)
                d = HUGE_VAL;
            dist[i * n + j] = dist[j * n + i] = d;
            any[i] |= d < HUGE_VAL;
            any[j] |= d < HUGE_VAL;
        }
    for (i = 0; i < n; i++)
        if (!any[i]) {
            frozen[i] = 1;
            r[i] = o->nominal;
            left--;
        }
    while (left--) {
        size_t bi = n;
        double bk = HUGE_VAL;
        for (i = 0; i < n; i++) {
            double k = o->r_max;
            if (frozen[i])
                continue;
            for (j = 0; j < n; j++)
                if (j != i && dist[i * n + j] < HUGE_VAL)
                    k = fmin(k, frozen[j] ? dist[i * n + j] - r[j] : 0.5 * dist[i * n + j]);
            if (k < bk) {
                bk = k;
                bi = i;
            }
        }
        frozen[bi] = 1;
        r[bi] = fmin(fmax(bk, o->r_min), o->r_max);
    }
    free(dist);
    free(arc);
    free(frozen);
    free(any);
}

/* The bounded neighbour search keeps only the pairs that can stop a tube: the radii must be those of the
 * growth over every pair within 2 r_max. Random wavy paths at 0.1..1.6 mm spacing (some closer than 2 r_min,
 * so that tubes are raised to r_min) and a hairpin that comes back along itself. */
START_TEST(bounded_neighbours_give_the_radii_of_all_pairs)
{
    amp_pathset ps, out;
    amp_fragments fs;
    amp_mdr_opts o;
    amp_mdr_stats st;
    amp_error err;
    double *r, y = 0.0;
    size_t i, f, v = 0;
    unsigned seed = 12345;
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out, NULL);
    for (i = 0; i < 8; i++) {
        int k;
        seed = seed * 1103515245u + 12345u;
        y += 0.1 + 1.5 * (double)(seed >> 16 & 0x7fff) / 32768.0;
        ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
        for (k = 0; k <= 24; k++)
            ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(0.3 * k, y + 0.3 * sin(0.7 * k + (double)i),
                                                          0.2 * cos(0.4 * k * (double)i)), 0.5, NULL), AMP_OK);
    }
    ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
    for (i = 0; i <= 40; i++) {
        double t = PI * (double)i / 40.0;
        ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(3.0 + 2.0 * sin(t), -2.0 + 0.6 * cos(t), 0.5), 0.5, NULL),
                         AMP_OK);
    }
    amp_mdr_opts_default(&o, 0.5);
    ck_assert_int_eq(amp_mdr(&ps, &o, &out, &st, &err), AMP_OK);
    ck_assert_int_eq(amp_fragments_build(&fs, &ps, o.fragment, NULL, &err), AMP_OK);
    r = calloc(fs.n, sizeof *r);
    reference_radii(&fs, &o, r);
    for (i = 0; i < ps.npaths; i++)
        for (f = fs.first[i]; f < fs.first[i + 1]; f++) {
            size_t q, nv = fs.frag[f].nin + 1 + (f == fs.first[i]);
            for (q = 0; q < nv; q++, v++) {
                double want = q + 1 == nv && f + 1 < fs.first[i + 1] ? fmin(r[f], r[f + 1]) : r[f];
                ck_assert_msg(fabs(out.verts[v].r - want) < 1e-9, "vertex %lu: radius %.12g, all pairs give %.12g",
                              (unsigned long)v, out.verts[v].r, want);
            }
        }
    ck_assert_uint_eq(v, out.nverts);
    ck_assert_uint_gt(st.at_min, 0);
    free(r);
    amp_fragments_free(&fs);
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
}
END_TEST

/* Every allocation of the MDR (neighbour search buffers, lists, growth queue) may fail: an error, no leak. */
START_TEST(mdr_survives_out_of_memory)
{
    amp_pathset ps;
    long budget;
    int ok = 0;
    amp_pathset_init(&ps, NULL);
    fan(&ps, 6, 0.5);
    for (budget = 0; budget < 120; budget++) {
        fx_failalloc fa;
        amp_pathset out;
        amp_mdr_opts o;
        amp_error err;
        amp_status st;
        fx_failalloc_init(&fa, budget);
        amp_pathset_init(&out, &fa.a);
        amp_mdr_opts_default(&o, 0.5);
        st = amp_mdr(&ps, &o, &out, NULL, &err);
        ck_assert(st == AMP_OK || st == AMP_ERR_NOMEM);
        ok |= st == AMP_OK;
        amp_pathset_free(&out);
    }
    ck_assert(ok);
    amp_pathset_free(&ps);
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
    tcase_add_test(tc, bounded_neighbours_give_the_radii_of_all_pairs);
    tcase_add_test(tc, mdr_survives_out_of_memory);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(mdr_suite)
