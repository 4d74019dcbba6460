/*
 * Curves through the gaps of a field's covering (field_internal.h).
 *
 * The adaptive lattice (lib/field.c) checks its covering radius on a 5 x 5 grid per cell at samples along
 * the curves: a sampled bound. Features finer than those samples (a screw's threads, a recycling symbol's
 * strokes, a bed's ribs) can still leave solid farther than the radius from every printed curve, and
 * `ampath check` then measures a gap above it. Here the covering is measured the way the checker measures
 * it (uniform samples of the solid, exact distance to the nearest segment), and the field's own curve
 * through each gap is added: the paths stay curves of the field ([P1 §4.2]), only more of them.
 */
#include <math.h>
#include <string.h>

#include "ampath/check.h"
#include "field_internal.h"

#define GAP_ROUNDS 4          /* measure, add curves; the last measurement only reports */
#define GAP_SAMPLES 20000     /* samples of the solid per measurement (the checker's default count) */
#define GAP_SEED 0x6A9C0F3Bul /* a stream of our own: the checker's samples stay independent */
#define GAP_POINTS_MAX 4096   /* gaps looked at per round, farthest first */
#define GAP_SEEDS_MAX 65536   /* curve samples tried as Newton's starting point */

/* F at lattice position x = (a, b, c). */
static amp_status field_at(const amp_field *f, const double x[3], amp_vec3 *p, amp_error *err)
{
    double uvw[3];
    amp_field_to_uvw(f, x[0], x[1], x[2], uvw);
    return f->eval(f, uvw, p, err);
}

/* The lattice position of the covering's sample nearest to @p p (every stride-th sample). */
static void nearest_seed(const amp_field_seeds *sd, amp_vec3 p, double x[3])
{
    size_t n = sd->ncur * (sd->ncs + 1), stride = n / GAP_SEEDS_MAX + 1, i, best = 0;
    double bd = HUGE_VAL;
    uint64_t key;
    for (i = 0; i < n; i += stride) {
        double d = amp_v3_dist2(sd->pts[i], p);
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    key = sd->key[best / (sd->ncs + 1)];
    x[0] = (double)(key >> 32) / sd->da;
    x[1] = (double)(key & 0xffffffffu) / sd->db;
    x[2] = (double)(best % (sd->ncs + 1)) / (double)sd->ncs;
}

static double clamp01(double v) { return v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v); }

/*
 * Solve F(x) = p by Newton's method from the nearest seed, with a forward-difference Jacobian and x kept in
 * the domain. 1 when it lands within @p tol of p; 0 when p is beyond the field's reach (or F is singular).
 */
static int invert(const amp_field *f, const amp_field_seeds *sd, amp_vec3 p, double tol, double x[3])
{
    amp_error err;
    int it, d;
    nearest_seed(sd, p, x);
    for (it = 0; it < 30; it++) {
        amp_vec3 g, col[3], e;
        double det, rhs[3], dx[3];
        if (field_at(f, x, &g, &err) != AMP_OK)
            return 0;
        e = amp_v3_sub(g, p);
        if (amp_v3_len(e) <= tol)
            return 1;
        for (d = 0; d < 3; d++) {
            double xh[3], h = x[d] < 0.5 ? 1e-7 : -1e-7;
            amp_vec3 gh;
            memcpy(xh, x, sizeof xh);
            xh[d] += h;
            if (field_at(f, xh, &gh, &err) != AMP_OK)
                return 0;
            col[d] = amp_v3_scale(amp_v3_sub(gh, g), 1.0 / h);
        }
        /* J dx = -e by Cramer's rule: columns col[0..2] */
        det = amp_v3_dot(col[0], amp_v3_cross(col[1], col[2]));
        if (!(fabs(det) > 1e-300))
            return 0;
        rhs[0] = -e.x;
        rhs[1] = -e.y;
        rhs[2] = -e.z;
        {
            amp_vec3 r = amp_v3(rhs[0], rhs[1], rhs[2]);
            dx[0] = amp_v3_dot(r, amp_v3_cross(col[1], col[2])) / det;
            dx[1] = amp_v3_dot(col[0], amp_v3_cross(r, col[2])) / det;
            dx[2] = amp_v3_dot(col[0], amp_v3_cross(col[1], r)) / det;
        }
        for (d = 0; d < 3; d++)
            x[d] = clamp01(x[d] + dx[d]);
    }
    return 0;
}

/* Is @p p within @p lim of path @p i of @p ps? */
static int near_path(const amp_pathset *ps, size_t i, amp_vec3 p, double lim)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    size_t k;
    for (k = 0; k + 1 < ps->paths[i].n; k++)
        if (amp_v3_seg_dist2(p, v[k].p, v[k + 1].p, NULL) <= lim * lim)
            return 1;
    return 0;
}

/* Is @p p within @p lim of a path of @p ps from @p from on (box[j]: the box of path from + j)? */
static int near_paths(const amp_pathset *ps, size_t from, const amp_box3 *box, amp_vec3 p, double lim)
{
    size_t i;
    for (i = from; i < ps->npaths; i++) {
        const amp_box3 *b = &box[i - from];
        if (p.x >= b->min.x - lim && p.x <= b->max.x + lim && p.y >= b->min.y - lim && p.y <= b->max.y + lim &&
            p.z >= b->min.z - lim && p.z <= b->max.z + lim && near_path(ps, i, p, lim))
            return 1;
    }
    return 0;
}

/* The field's curve at lattice position (a, b), clipped; its pieces kept as amp_field_fill_gaps() says. */
static amp_status add_curve(const amp_field *f, const amp_bvh *b, const amp_field_opts *o, const double x[3],
                            size_t nc, double r, double min_len, amp_vec3 gap, double target, amp_pvert *curve,
                            amp_pathset *out, amp_error *err)
{
    amp_pathset tmp;
    size_t i, k;
    amp_status st = AMP_OK;
    for (k = 0; k <= nc && st == AMP_OK; k++) {
        double y[3];
        y[0] = x[0];
        y[1] = x[1];
        y[2] = (double)k / (double)nc;
        st = field_at(f, y, &curve[k].p, err);
        curve[k].r = r;
    }
    if (st != AMP_OK)
        return st;
    amp_pathset_init(&tmp, out->alloc);
    st = amp_field_clip(b, o, curve, nc + 1, 0.0, &tmp, err);
    for (i = 0; st == AMP_OK && i < tmp.npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(&tmp, i);
        if (amp_path_length(&tmp, i) >= min_len || near_path(&tmp, i, gap, target))
            st = amp_pathset_add(out, AMP_ROLE_OBJECT, v, tmp.paths[i].n, err);
    }
    amp_pathset_free(&tmp);
    return st;
}

/* The boxes of the paths added since @p from that *nbox does not hold yet (for near_paths). */
static amp_status boxes_since(const amp_pathset *ps, size_t from, amp_box3 **box, size_t *cap, size_t *nbox,
                              amp_error *err)
{
    size_t i, k;
    void *m = *box;
    if (ps->npaths > from && amp_grow(ps->alloc, &m, cap, ps->npaths - from, sizeof **box) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the gap curves");
    *box = m;
    for (i = from + *nbox; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        (*box)[i - from] = amp_box3_empty();
        for (k = 0; k < ps->paths[i].n; k++)
            (*box)[i - from] = amp_box3_add((*box)[i - from], v[k].p);
    }
    *nbox = ps->npaths - from;
    return AMP_OK;
}

amp_status amp_field_fill_gaps(const amp_field *f, const amp_bvh *b, const amp_field_opts *o,
                               const amp_field_seeds *sd, size_t nc, double target, double r, double min_len,
                               amp_pathset *out, size_t *added, double *gap_after, amp_error *err)
{
    amp_pvert *curve = amp_calloc(out->alloc, nc + 1, sizeof *curve);
    amp_box3 *box = NULL;
    size_t boxcap = 0;
    int round;
    amp_status st = AMP_OK;
    *added = 0;
    *gap_after = 0.0;
    if (!curve)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the gap curves");
    for (round = 0; st == AMP_OK && sd->ncur > 0 && out->npaths > 0; round++) {
        amp_check_gap *g = NULL;
        amp_coverage cov;
        size_t ng = 0, i, from = out->npaths, before = *added, nbox = 0;
        st = amp_check_coverage_gaps(out, b, GAP_SAMPLES, GAP_SEED + (unsigned long)round, target, &g, &ng, &cov,
                                     err);
        if (st != AMP_OK)
            break;
        *gap_after = cov.gap;
        for (i = 0; st == AMP_OK && round < GAP_ROUNDS && i < ng && i < GAP_POINTS_MAX; i++) {
            double x[3];
            /* a gap within reach of a curve added in this round is closed by it */
            if (!amp_field_member(b, o, g[i].p) ||
                (out->npaths > from && ((st = boxes_since(out, from, &box, &boxcap, &nbox, err)) != AMP_OK ||
                                        near_paths(out, from, box, g[i].p, target))))
                continue;
            if (!invert(f, sd, g[i].p, 1e-3 * target, x))
                continue;
            st = add_curve(f, b, o, x, nc, r, min_len, g[i].p, target, curve, out, err);
            (*added)++;
        }
        amp_free(out->alloc, g);
        if (round >= GAP_ROUNDS || *added == before)
            break;
    }
    amp_free(out->alloc, curve);
    amp_free(out->alloc, box);
    return st;
}
