/* The print-head cone (docs/interfaces.md §2, [P1 §5.1] Fig. 9) and the exact segment-cone test of Fig. 10. */
#include <math.h>

#include "ampath/order.h"
#include "order_cone.h"

/* Euclidean length in the plane; coordinates are millimetres, so no overflow guard (hypot) is needed. */
static double len2d(double x, double y) { return sqrt(x * x + y * y); }

void amp_head_default(amp_head *h)
{
    h->z_offs = AMP_HEAD_DEFAULT_Z_OFFS;
    h->theta = AMP_HEAD_DEFAULT_THETA;
}

amp_status amp_head_validate(const amp_head *h, amp_error *err)
{
    const double half_pi = 0.5 * AMP_PI;
    if (!h)
        return amp_fail(err, AMP_ERR_ARG, 0, "no head geometry given");
    if (!isfinite(h->z_offs) || h->z_offs <= 0.0)
        return amp_fail(err, AMP_ERR_RANGE, 0, "z_offs must be a positive number of mm (got %g)", h->z_offs);
    if (!isfinite(h->theta) || h->theta <= 0.0 || h->theta >= half_pi)
        return amp_fail(err, AMP_ERR_RANGE, 0, "theta must lie strictly between 0 and 90 degrees (got %g degrees)",
                        h->theta * 57.295779513082320876);
    return AMP_OK;
}

/*
 * max over t in [0,1] of alpha + beta t - k |w + t e| (w, e in the plane).
 * The function is concave, so the maximum is at an end or at the one
 * stationary point: writing |w + t e| = sqrt(h^2 + |e|^2 (t - t0)^2) around the
 * foot t0 of the line, the derivative vanishes where
 * beta / (k |e|) = y / sqrt(h^2 + y^2) with y = |e| (t - t0).
 */
static double edge_max(double alpha, double beta, double k, double wx, double wy, double ex, double ey)
{
    double best = alpha - k * len2d(wx, wy);
    double v = alpha + beta - k * len2d(wx + ex, wy + ey);
    double e2 = ex * ex + ey * ey;
    if (v > best)
        best = v;
    if (e2 > 0.0) {
        double len = sqrt(e2), t0 = -(wx * ex + wy * ey) / e2;
        double h = len2d(wx + t0 * ex, wy + t0 * ey), rho = beta / (k * len);
        if (rho > -1.0 && rho < 1.0) {
            double t = t0 + rho * h / sqrt(1.0 - rho * rho) / len;
            if (t > 0.0 && t < 1.0) {
                v = alpha + beta * t - k * len2d(wx + t * ex, wy + t * ey);
                if (v > best)
                    best = v;
            }
        }
    }
    return best;
}

double amp_cone_clearance(const amp_head *h, amp_vec3 a0, amp_vec3 a1, amp_vec3 b0, amp_vec3 b1)
{
    return amp_cone_clearance_k(h->z_offs, 1.0 / tan(h->theta), a0, a1, b0, b1);
}

double amp_cone_clearance_k(double zo, double k, amp_vec3 a0, amp_vec3 a1, amp_vec3 b0, amp_vec3 b1)
{
    /* g(s,t) = (b(t).z - a(s).z - z_offs) - k |b(t).xy - a(s).xy| is concave on the unit square:
     * its maximum lies on the boundary (four 1-D problems) or where the xy difference vanishes. */
    amp_vec3 da = amp_v3_sub(a1, a0), db = amp_v3_sub(b1, b0);
    double best, v, det;
    best = edge_max(b0.z - a0.z - zo, db.z, k, b0.x - a0.x, b0.y - a0.y, db.x, db.y);        /* s = 0 */
    v = edge_max(b0.z - a1.z - zo, db.z, k, b0.x - a1.x, b0.y - a1.y, db.x, db.y);           /* s = 1 */
    best = v > best ? v : best;
    v = edge_max(b0.z - a0.z - zo, -da.z, k, b0.x - a0.x, b0.y - a0.y, -da.x, -da.y);        /* t = 0 */
    best = v > best ? v : best;
    v = edge_max(b1.z - a0.z - zo, -da.z, k, b1.x - a0.x, b1.y - a0.y, -da.x, -da.y);        /* t = 1 */
    best = v > best ? v : best;
    /* interior: (b0 - a0).xy + t db.xy - s da.xy = 0 */
    det = -da.x * db.y + db.x * da.y;
    if (fabs(det) > 1e-300) {
        double wx = b0.x - a0.x, wy = b0.y - a0.y;
        double s = (-wx * db.y + db.x * wy) / det;
        double t = (da.x * wy - wx * da.y) / det;
        if (s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0) {
            v = b0.z - a0.z - zo + t * db.z - s * da.z;
            best = v > best ? v : best;
        }
    }
    return best;
}

int amp_fragment_below(const amp_fragments *fs, const amp_head *h, size_t a, size_t b)
{
    return amp_fragment_below_k(fs, h->z_offs, 1.0 / tan(h->theta), a, b);
}

/* q is inside the head printing p, beyond the tolerance (docs/interfaces.md §2) */
static int point_clear(double zo, double k, amp_vec3 p, amp_vec3 q)
{
    double dz = q.z - p.z - zo - AMP_CONE_TOL, dx = q.x - p.x, dy = q.y - p.y;
    return dz > 0.0 && dz * dz > k * k * (dx * dx + dy * dy);
}

/* Box bound of the clearance between segment [a0, a1] and a box: may the cone over the segment reach it? */
static int seg_may_see(double zo, double k, amp_vec3 a0, amp_vec3 a1, const amp_box3 *b)
{
    double lo = a0.z < a1.z ? a0.z : a1.z, room = b->max.z - lo - zo - AMP_CONE_TOL, gx, gy, ex, ey;
    if (room <= 0.0)
        return 0;
    gx = (a0.x < a1.x ? a0.x : a1.x) - b->max.x;
    ex = b->min.x - (a0.x > a1.x ? a0.x : a1.x);
    gy = (a0.y < a1.y ? a0.y : a1.y) - b->max.y;
    ey = b->min.y - (a0.y > a1.y ? a0.y : a1.y);
    gx = gx > ex ? gx : ex;
    gy = gy > ey ? gy : ey;
    gx = gx > 0.0 ? gx : 0.0;
    gy = gy > 0.0 ? gy : 0.0;
    return room * room > k * k * (gx * gx + gy * gy);
}

/*
 * Upper bound of amp_cone_clearance_k: g(s,t) is concave on the unit square (Fig. 10), so it lies under its
 * tangent plane at the centre, whose largest value on the square is at a corner. One square root instead of
 * the closed forms. Below the blocker queries almost every exact test that gets this far fails (neighbours
 * at about the same height), and this bound settles most of them.
 */
static double clearance_bound(double zo, double k, amp_vec3 a0, amp_vec3 a1, amp_vec3 b0, amp_vec3 b1)
{
    double vx = 0.5 * (b0.x + b1.x - a0.x - a1.x), vy = 0.5 * (b0.y + b1.y - a0.y - a1.y);
    double n = sqrt(vx * vx + vy * vy), gs, gt;
    if (!(n > 0.0))
        return HUGE_VAL;
    /* d/ds and d/dt of g at the centre; v = b(t).xy - a(s).xy moves by -da.xy and +db.xy */
    gs = -(a1.z - a0.z) + k * (vx * (a1.x - a0.x) + vy * (a1.y - a0.y)) / n;
    gt = (b1.z - b0.z) - k * (vx * (b1.x - b0.x) + vy * (b1.y - b0.y)) / n;
    return 0.5 * (b0.z + b1.z - a0.z - a1.z) - zo - k * n + 0.5 * (fabs(gs) + fabs(gt));
}

int amp_fragment_below_k(const amp_fragments *fs, double zo, double k, size_t a, size_t b)
{
    const amp_fragment *fa = &fs->frag[a], *fb = &fs->frag[b];
    size_t i, j, na, nb;
    if (a == b)
        return 0;
    /* box bound of the clearance: highest point of b over lowest of a, nearest in xy */
    if (fb->box.max.z - fa->box.min.z - zo - k * amp_box_xy_gap(fa->box, fb->box) <= AMP_CONE_TOL)
        return 0;
    /* quick accept: the clearance of two segments is at least that of any two of their points, and the
     * fragment ends usually show a blocker far below at once */
    if (point_clear(zo, k, fa->p0, fb->p0) || point_clear(zo, k, fa->p0, fb->p1) ||
        point_clear(zo, k, fa->p1, fb->p0) || point_clear(zo, k, fa->p1, fb->p1))
        return 1;
    na = amp_fragment_npoints(fa);
    nb = amp_fragment_npoints(fb);
    for (i = 0; i + 1 < na; i++) {
        amp_vec3 a0 = amp_fragment_point(fs, fa, i), a1 = amp_fragment_point(fs, fa, i + 1);
        /* the box bound again for this segment of a against all of b */
        if (!seg_may_see(zo, k, a0, a1, &fb->box))
            continue;
        for (j = 0; j + 1 < nb; j++) {
            amp_vec3 b0 = amp_fragment_point(fs, fb, j), b1 = amp_fragment_point(fs, fb, j + 1);
            /* the bound's rounding (about 1e-14 mm at these sizes) is far inside the tolerance of 1e-9 mm: a
             * bound at most 0 proves the clearance at most the tolerance */
            if (clearance_bound(zo, k, a0, a1, b0, b1) <= AMP_CONE_TOL - 1e-9)
                continue;
            if (amp_cone_clearance_k(zo, k, a0, a1, b0, b1) > AMP_CONE_TOL)
                return 1;
        }
    }
    return 0;
}
