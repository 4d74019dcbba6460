/*
 * The covering direction a printer wants (beyond [P1 §4.1], which always covers with iso-w surfaces).
 *
 * Algorithm 1 covers with the iso-surfaces of one direction d and each surface with the curves along its
 * second remaining direction (w for d = u or v, v for d = w). Which d is right depends on how the trivariate
 * is parametrised, and the wrong one is costly on a printer: Algorithm 2 cuts a curve wherever a fragment of
 * it lies below another one of it (Def. 5.1), so curves that climb are cut into pieces shorter than z_offs.
 * Measured with the default head: the built-in helix covered with iso-w surfaces has curves round the disc
 * (68,323 cuts of 73,423 fragments, 72,308 paths), with iso-u ones curves along the sweep (4,275 cuts, 4,556
 * paths); the torus quarter 141,929 cuts against 0; the vase the other way round (0 cuts with w).
 *
 * So the choice samples the trivariate's tangents: each d scores the mean slope |t_z| / |t| of its curves'
 * tangent t (level curves score 0); the lowest wins, ties keep the paper's w. d = u and d = v cover with
 * curves along w alike (the same family, spaced the other way round) and always tie: of those, the one whose
 * own direction is shorter by Lemma A.2's bound is taken (fewer, larger iso-surfaces; the vase lying on its
 * side: 1,045 cuts covered through its wall's thickness u against 1,436 round its circumference v, where the
 * surfaces' tilt would have picked v), u on a tie.
 */
#include <math.h>

#include "ampath/cover.h"

#define PICK_SAMPLES 8 /* per parametric direction: 512 tangents */

/* |a_z| / |a|, or -1 for a vanishing vector (a pole of the parametrisation tells nothing). */
static double slope_of(amp_vec3 a)
{
    double n = amp_v3_len(a);
    return n > 1e-12 ? fabs(a.z) / n : -1.0;
}

amp_status amp_trivariate_slopes(const amp_spline *v, double slope[3], amp_error *err)
{
    double lo[3], hi[3], sum[3] = {0, 0, 0};
    size_t cnt[3] = {0, 0, 0};
    int i, j, k, d;
    if (!v || v->dim != 3 || !slope)
        return amp_fail(err, AMP_ERR_ARG, 0, "the slopes of iso-curves need a trivariate");
    for (d = 0; d < 3; d++)
        amp_spline_domain(v, d, &lo[d], &hi[d]);
    for (i = 0; i < PICK_SAMPLES; i++)
        for (j = 0; j < PICK_SAMPLES; j++)
            for (k = 0; k < PICK_SAMPLES; k++) {
                /* cell centres: no sample on a boundary, where a clamped net may degenerate */
                double par[3], s;
                amp_vec3 dv[8];
                amp_status st;
                par[0] = lo[0] + (hi[0] - lo[0]) * (i + 0.5) / PICK_SAMPLES;
                par[1] = lo[1] + (hi[1] - lo[1]) * (j + 0.5) / PICK_SAMPLES;
                par[2] = lo[2] + (hi[2] - lo[2]) * (k + 0.5) / PICK_SAMPLES;
                if ((st = amp_spline_eval_derivs(v, par, 1, dv, err)) != AMP_OK)
                    return st;
                /* dV/du, dV/dv, dV/dw: dv[1], dv[2], dv[4] */
                for (d = 0; d < 3; d++)
                    if ((s = slope_of(dv[1 << d])) >= 0.0) {
                        sum[d] += s;
                        cnt[d]++;
                    }
            }
    for (d = 0; d < 3; d++)
        slope[d] = cnt[d] ? sum[d] / (double)cnt[d] : 1.0;
    return AMP_OK;
}

amp_status amp_cover_pick_dir(const amp_spline *v, int *dir, double score[3], amp_error *err)
{
    double sl[3];
    amp_status st;
    if (!dir)
        return amp_fail(err, AMP_ERR_ARG, 0, "choosing a covering direction needs somewhere to put it");
    if ((st = amp_trivariate_slopes(v, sl, err)) != AMP_OK)
        return st;
    /* d = u, v cover with curves along w, d = w with curves along v (lib/cover.c) */
    if (score) {
        score[0] = score[1] = sl[2];
        score[2] = sl[1];
    }
    if (!(sl[2] < sl[1]))
        *dir = 2;
    else
        *dir = amp_spline_polygon_length_bound(v, 1, NULL) < amp_spline_polygon_length_bound(v, 0, NULL) ? 1 : 0;
    return AMP_OK;
}

/*
 * Lemma A.2 on the whole control net: the arc length of every direction-@p d
 * isoparametric curve is at most the sum over control segments k of the longest
 * |P_{k+1} - P_k| across the net (weights ignored: an estimate, not a bound).
 */
static double net_length(const amp_spline *v, int d)
{
    size_t idx[3], k, i, j, n = v->count[d];
    int a = d == 0 ? 1 : 0, b = d == 2 ? 1 : 2;
    double total = 0;
    for (k = 0; k + 1 < n; k++) {
        double mx = 0;
        for (j = 0; j < v->count[b]; j++)
            for (i = 0; i < v->count[a]; i++) {
                amp_vec3 p0, p1;
                idx[a] = i;
                idx[b] = j;
                idx[d] = k;
                p0 = amp_spline_cp_get(v, amp_spline_index(v, idx[0], idx[1], idx[2]), NULL);
                idx[d] = k + 1;
                p1 = amp_spline_cp_get(v, amp_spline_index(v, idx[0], idx[1], idx[2]), NULL);
                mx = fmax(mx, amp_v3_dist(p0, p1));
            }
        total += mx;
    }
    return total;
}

/*
 * Work estimate before covering: Algorithm 1 halves the covering direction
 * until neighbouring surfaces are within thr = eps - delta by the Lemma A.2 measure, and
 * each surface is covered the same way by curves, so about (L_d / thr + 1) surfaces of
 * (L_e0 / thr + 1) curves each, every one at most L_e1 long (*length: their total). Measured
 * on the built-in models the count is within a factor of a few of the real one, which is all a
 * refusal needs; the length counts too, because the curves of one direction may be few and
 * long (the helix along w at eps 0.02: 4e5 curves, 100 s and 3.7 GB before it was stopped).
 */
amp_status amp_cover_estimate(const amp_spline *v, const amp_cover_opts *o, double *curves, double *length,
                              amp_error *err)
{
    int d, e0, e1;
    double delta, thr;
    amp_status st;
    if (!v || !o || !curves || !length || v->dim != 3 || !v->cp)
        return amp_fail(err, AMP_ERR_ARG, 0, "cover estimate: needs a trivariate, options and two outputs");
    if (!(o->eps > 0) || !isfinite(o->eps))
        return amp_fail(err, AMP_ERR_ARG, 0, "cover estimate: eps must be positive and finite (got %g)", o->eps);
    d = o->dir;
    if (d == AMP_COVER_AUTO && (st = amp_cover_pick_dir(v, &d, NULL, err)) != AMP_OK)
        return st;
    if (d < 0 || d > 2)
        return amp_fail(err, AMP_ERR_ARG, 0, "cover estimate: direction %d is not u, v, w or auto", d);
    e0 = d == 0 ? 1 : 0;
    e1 = d == 2 ? 1 : 2;
    delta = o->chord_tol > 0 ? fmin(o->chord_tol, 0.5 * o->eps) : o->eps / 20;
    thr = o->eps - delta;
    *curves = (ceil(net_length(v, d) / thr) + 1) * (ceil(net_length(v, e0) / thr) + 1);
    *length = *curves * net_length(v, e1);
    return AMP_OK;
}
