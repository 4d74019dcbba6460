/*
 * ampath/head.h — the print head as the orderer, the support generator, the
 * G-code travel planner and the gouge checker all see it: a downward cone
 * whose tip is z_offs above the point being printed, with half-angle theta
 * from the vertical (+z) axis ([P1 §5.1], Fig. 9; docs/interfaces.md §2).
 * A point q lies inside the head printing p when
 *     (q.z - p.z - z_offs) - cot(theta) * |q.xy - p.xy| > AMP_CONE_TOL,
 * a small negative number: contact counts (the closed cone of [P1 §5.1],
 * whose sweep along a curve "intersects" the curve z_offs straight above it).
 *
 * Thread-safety: pure functions.
 */
#ifndef AMPATH_HEAD_H
#define AMPATH_HEAD_H

#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Paper defaults (docs/interfaces.md §2): tip 0.5 mm above the printed point, half-angle 0.4*pi (72 degrees). */
#define AMP_HEAD_DEFAULT_Z_OFFS 0.5
#define AMP_HEAD_DEFAULT_THETA (0.4 * AMP_PI)

/**
 * Clearance (mm) above which a point is inside the cone: -1 um, so that contact counts. Rows of a field
 * stacked exactly z_offs apart (`field --spacing 0.5` with the default head) touch the cone's tip: with contact
 * allowed, Algorithm 2 printed an upper row before the row straight under it, whose printing then put the tip
 * in the upper row. The micrometre is a margin over the .amp text's rounding (10 digits: 0.2 um at 200 mm),
 * so that the checker (AMP_GOUGE_TOL, half of it) sees every pair the builders kept apart as apart.
 */
#define AMP_CONE_TOL (-1e-6)

/** The print-head cone. Angles in radians. */
typedef struct amp_head {
    double z_offs; /**< tip height above the printed point, mm, > 0 */
    double theta;  /**< half-angle from the vertical axis, radians, in (0, pi/2) */
} amp_head;

/** Fill @p h with the paper defaults. */
void amp_head_default(amp_head *h);

/**
 * Check a head: AMP_ERR_RANGE with a clear message when z_offs is not a
 * positive finite number or theta is not strictly between 0 and pi/2.
 */
amp_status amp_head_validate(const amp_head *h, amp_error *err);

/**
 * Exact clearance of two segments: the maximum over p in [a0,a1] and q in
 * [b0,b1] of (q.z - p.z - z_offs) - cot(theta) |q.xy - p.xy| (the function is
 * concave, the maximum is found in closed form). A value > AMP_CONE_TOL means
 * the cone swept along segment a (Fig. 10) contains part of segment b.
 * Degenerate segments (a0 == a1) are points. Pure function.
 */
double amp_cone_clearance(const amp_head *h, amp_vec3 a0, amp_vec3 a1, amp_vec3 b0, amp_vec3 b1);

#ifdef __cplusplus
}
#endif
#endif
