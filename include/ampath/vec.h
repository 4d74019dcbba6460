/*
 * ampath/vec.h — 3-D vectors and axis-aligned boxes.
 *
 * Plain values passed by value; every function is a pure static inline
 * (thread-safe, no allocation, no error cases).
 */
#ifndef AMPATH_VEC_H
#define AMPATH_VEC_H

#include <math.h>

#ifdef __cplusplus
extern "C" {
#endif

/** π to double precision: the one definition of the project (C99 has no M_PI). */
#define AMP_PI 3.14159265358979323846

typedef struct amp_vec3 {
    double x, y, z;
} amp_vec3;

/** Axis-aligned box; an empty box has min > max (see amp_box3_empty()). */
typedef struct amp_box3 {
    amp_vec3 min, max;
} amp_box3;

/** Smaller / larger of two numbers that are not NaN: a comparison, where libm's fmin / fmax are calls
 *  (their NaN rules keep compilers from inlining them) — a few percent of a slice in hot loops. */
static inline double amp_dmin(double a, double b) { return a < b ? a : b; }
static inline double amp_dmax(double a, double b) { return a > b ? a : b; }

static inline amp_vec3 amp_v3(double x, double y, double z) { amp_vec3 r; r.x = x; r.y = y; r.z = z; return r; }
static inline amp_vec3 amp_v3_add(amp_vec3 a, amp_vec3 b) { return amp_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline amp_vec3 amp_v3_sub(amp_vec3 a, amp_vec3 b) { return amp_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline amp_vec3 amp_v3_scale(amp_vec3 a, double s) { return amp_v3(a.x * s, a.y * s, a.z * s); }
/** a + s*b */
static inline amp_vec3 amp_v3_madd(amp_vec3 a, amp_vec3 b, double s) { return amp_v3(a.x + s * b.x, a.y + s * b.y, a.z + s * b.z); }
static inline double amp_v3_dot(amp_vec3 a, amp_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline amp_vec3 amp_v3_cross(amp_vec3 a, amp_vec3 b)
{
    return amp_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double amp_v3_len2(amp_vec3 a) { return amp_v3_dot(a, a); }
static inline double amp_v3_len(amp_vec3 a) { return sqrt(amp_v3_dot(a, a)); }
static inline double amp_v3_dist(amp_vec3 a, amp_vec3 b) { return amp_v3_len(amp_v3_sub(a, b)); }
static inline double amp_v3_dist2(amp_vec3 a, amp_vec3 b) { return amp_v3_len2(amp_v3_sub(a, b)); }
/** Linear interpolation a + t (b - a). */
static inline amp_vec3 amp_v3_lerp(amp_vec3 a, amp_vec3 b, double t) { return amp_v3_madd(a, amp_v3_sub(b, a), t); }
/** Unit vector along @p a; the zero vector stays zero. */
static inline amp_vec3 amp_v3_normalize(amp_vec3 a)
{
    double l = amp_v3_len(a);
    return l > 0.0 ? amp_v3_scale(a, 1.0 / l) : a;
}
static inline amp_vec3 amp_v3_min(amp_vec3 a, amp_vec3 b) { return amp_v3(fmin(a.x, b.x), fmin(a.y, b.y), fmin(a.z, b.z)); }
static inline amp_vec3 amp_v3_max(amp_vec3 a, amp_vec3 b) { return amp_v3(fmax(a.x, b.x), fmax(a.y, b.y), fmax(a.z, b.z)); }
/** Non-zero when all three coordinates are finite (no NaN, no Inf). */
static inline int amp_v3_finite(amp_vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

/** The empty box: the identity of amp_box3_add(). */
static inline amp_box3 amp_box3_empty(void)
{
    amp_box3 b;
    b.min = amp_v3(HUGE_VAL, HUGE_VAL, HUGE_VAL);
    b.max = amp_v3(-HUGE_VAL, -HUGE_VAL, -HUGE_VAL);
    return b;
}
static inline int amp_box3_is_empty(amp_box3 b) { return b.min.x > b.max.x || b.min.y > b.max.y || b.min.z > b.max.z; }
static inline amp_box3 amp_box3_add(amp_box3 b, amp_vec3 p)
{
    b.min = amp_v3_min(b.min, p);
    b.max = amp_v3_max(b.max, p);
    return b;
}
static inline amp_box3 amp_box3_union(amp_box3 a, amp_box3 b)
{
    a.min = amp_v3_min(a.min, b.min);
    a.max = amp_v3_max(a.max, b.max);
    return a;
}
/** Grow the box by @p d on every side. */
static inline amp_box3 amp_box3_inflate(amp_box3 b, double d)
{
    b.min = amp_v3(b.min.x - d, b.min.y - d, b.min.z - d);
    b.max = amp_v3(b.max.x + d, b.max.y + d, b.max.z + d);
    return b;
}
static inline int amp_box3_contains(amp_box3 b, amp_vec3 p)
{
    return p.x >= b.min.x && p.x <= b.max.x && p.y >= b.min.y && p.y <= b.max.y && p.z >= b.min.z && p.z <= b.max.z;
}
static inline int amp_box3_overlap(amp_box3 a, amp_box3 b)
{
    return a.min.x <= b.max.x && b.min.x <= a.max.x && a.min.y <= b.max.y && b.min.y <= a.max.y &&
           a.min.z <= b.max.z && b.min.z <= a.max.z;
}
static inline amp_vec3 amp_box3_center(amp_box3 b) { return amp_v3_scale(amp_v3_add(b.min, b.max), 0.5); }
static inline amp_vec3 amp_box3_size(amp_box3 b) { return amp_v3_sub(b.max, b.min); }

/** Squared distance from @p p to the segment [a, b]; *t receives the closest parameter if not NULL. */
static inline double amp_v3_seg_dist2(amp_vec3 p, amp_vec3 a, amp_vec3 b, double *t)
{
    amp_vec3 ab = amp_v3_sub(b, a);
    double l2 = amp_v3_len2(ab), s = 0.0;
    if (l2 > 0.0) {
        s = amp_v3_dot(amp_v3_sub(p, a), ab) / l2;
        s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    }
    if (t)
        *t = s;
    return amp_v3_dist2(p, amp_v3_madd(a, ab, s));
}

#ifdef __cplusplus
}
#endif
#endif
