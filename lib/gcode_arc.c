/*
 * Arc fitting for the G-code writer (docs/interfaces.md §5 clean segments, `--arcs`): the
 * longest run of path vertices that lies on one circle in XY, with z and the
 * deposition radius linear in the swept angle (helical arcs, as Marlin's and
 * Klipper's G2/G3 take them), within the writer's tolerances.
 */
#include <math.h>

#include "gcode_internal.h"

#define ARC_MAX 512           /* input vertices per arc at most */
#define ARC_MIN_R 0.5         /* mm: smaller circles are left to lines */
#define ARC_MAX_R 1000.0      /* mm: flatter ones are lines */

/* Circle through the XY projections of a, b, c; 0 when they are (nearly) collinear. */
static int circumcircle(amp_vec3 a, amp_vec3 b, amp_vec3 c, double *cx, double *cy, double *R)
{
    double d = 2.0 * (a.x * (b.y - c.y) + b.x * (c.y - a.y) + c.x * (a.y - b.y));
    double a2 = a.x * a.x + a.y * a.y, b2 = b.x * b.x + b.y * b.y, c2 = c.x * c.x + c.y * c.y;
    if (fabs(d) < 1e-12)
        return 0;
    *cx = (a2 * (b.y - c.y) + b2 * (c.y - a.y) + c2 * (a.y - b.y)) / d;
    *cy = (a2 * (c.x - b.x) + b2 * (a.x - c.x) + c2 * (b.x - a.x)) / d;
    *R = hypot(a.x - *cx, a.y - *cy);
    return *R >= ARC_MIN_R && *R <= ARC_MAX_R;
}

/* Do vertices k..m of @p v form one arc within the tolerances? Fills @p a. */
static int arc_ok(const amp_pvert *v, size_t k, size_t m, double tol, double rtol, amp_gc_arc *a)
{
    double cx, cy, R, sweep = 0.0, prev, s = 0.0, dz = v[m].p.z - v[k].p.z, dr = v[m].r - v[k].r;
    size_t i;
    if (m < k + 2 || !circumcircle(v[k].p, v[(k + m) / 2].p, v[m].p, &cx, &cy, &R))
        return 0;
    prev = atan2(v[k].p.y - cy, v[k].p.x - cx);
    for (i = k + 1; i <= m; i++) {
        double ang = atan2(v[i].p.y - cy, v[i].p.x - cx), d = ang - prev, L;
        d -= 2.0 * AMP_PI * floor((d + AMP_PI) / (2.0 * AMP_PI)); /* into [-pi, pi) */
        if (fabs(hypot(v[i].p.x - cx, v[i].p.y - cy) - R) > tol || fabs(d) > 0.5 * AMP_PI)
            return 0;
        if (d != 0.0) {
            if (s == 0.0)
                s = d > 0 ? 1.0 : -1.0;
            else if (d * s < 0.0)
                return 0; /* the turn changes direction */
        }
        /* the polyline between vertices must not leave the arc by more than tol (sagitta) */
        L = hypot(v[i].p.x - v[i - 1].p.x, v[i].p.y - v[i - 1].p.y);
        if (L * L / (8.0 * R) > tol)
            return 0;
        sweep += d;
        prev = ang;
    }
    if (s == 0.0 || fabs(sweep) >= 2.0 * AMP_PI - 0.1)
        return 0;
    /* z and the deposition radius follow the swept angle linearly (a helical arc with a linear bead) */
    prev = atan2(v[k].p.y - cy, v[k].p.x - cx);
    for (i = k + 1, s = 0.0; i < m; i++) {
        double ang = atan2(v[i].p.y - cy, v[i].p.x - cx), d = ang - prev, f;
        d -= 2.0 * AMP_PI * floor((d + AMP_PI) / (2.0 * AMP_PI));
        s += d;
        prev = ang;
        f = s / sweep;
        if (fabs(v[k].p.z + f * dz - v[i].p.z) > tol || fabs(v[k].r + f * dr - v[i].r) > rtol)
            return 0;
    }
    a->cx = cx;
    a->cy = cy;
    a->cw = sweep < 0.0;
    a->end = m;
    a->len = hypot(R * sweep, dz);
    return 1;
}

/* Length of the path from vertex @p m to its end, stopping once it reaches @p enough. */
static double rest_length(const amp_pvert *v, size_t n, size_t m, double enough)
{
    double rest = 0.0;
    for (; m + 1 < n && rest < enough; m++)
        rest += amp_v3_dist(v[m].p, v[m + 1].p);
    return rest;
}

int amp_gc_fit_arc(const amp_pvert *v, size_t n, size_t k, size_t line_end, const amp_gcode_opts *o, amp_gc_arc *arc)
{
    size_t good = 0, lo, hi, lim = k + ARC_MAX < n - 1 ? k + ARC_MAX : n - 1, m;
    amp_gc_arc a;
    m = line_end + 1 > k + 3 ? line_end + 1 : k + 3;
    if (m > lim || !arc_ok(v, k, m, o->chord_tol, o->radius_tol, &a))
        return 0;
    good = m;
    *arc = a;
    /* grow geometrically, then bisect between the last good end and the first bad one */
    for (;;) {
        size_t next = k + (good - k) * 3 / 2 + 1;
        if (next > lim)
            next = lim;
        if (next <= good)
            break;
        if (arc_ok(v, k, next, o->chord_tol, o->radius_tol, &a)) {
            good = next;
            *arc = a;
            continue;
        }
        for (lo = good + 1, hi = next - 1; lo <= hi;) {
            size_t mid = lo + (hi - lo) / 2;
            if (arc_ok(v, k, mid, o->chord_tol, o->radius_tol, &a)) {
                good = mid;
                *arc = a;
                lo = mid + 1;
            } else {
                hi = mid - 1;
            }
        }
        break;
    }
    /* no remainder shorter than min_segment after the arc (it could not be written alone) */
    while (good < n - 1 && rest_length(v, n, good, o->min_segment) < o->min_segment) {
        if (good <= line_end + 1 || !arc_ok(v, k, good - 1, o->chord_tol, o->radius_tol, &a))
            return 0;
        good--;
        *arc = a;
    }
    return arc->len >= o->min_segment;
}
