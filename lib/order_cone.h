/*
 * lib/order_cone.h — internal: the head-cone tests of order_cone.c with k = cot(theta)
 * precomputed, for the hot loops of the fragment BVH, the orderer, support
 * and MDR ([P1 §5.1], Figs. 9-10). The public forms (amp_cone_clearance,
 * amp_fragment_below) are in ampath/head.h and ampath/order.h.
 * Stack: head <- fragment <- cone <- fragbvh <- {order, support, mdr}.
 */
#ifndef AMPATH_LIB_CONE_H
#define AMPATH_LIB_CONE_H

#include <math.h>
#include <stddef.h>

#include "ampath/order.h"

/* A hint to fetch the cache line at p ahead of its use (the blocker queries wait on memory); nothing where the
 * compiler has no such builtin. */
#if defined(__GNUC__)
#define AMP_PREFETCH(p) __builtin_prefetch(p)
#else
#define AMP_PREFETCH(p) ((void)(p))
#endif

/* amp_cone_clearance and amp_fragment_below with k = cot(theta) precomputed (hot loops). */
double amp_cone_clearance_k(double zo, double k, amp_vec3 a0, amp_vec3 a1, amp_vec3 b0, amp_vec3 b1);
int amp_fragment_below_k(const amp_fragments *fs, double zo, double k, size_t a, size_t b);

/* Horizontal distance between the xy projections of two boxes (0 when they overlap). Inline and without
 * fmax: it is the innermost bound of every query. */
static inline double amp_box_xy_gap(amp_box3 a, amp_box3 b)
{
    double dx = a.min.x - b.max.x, dy = a.min.y - b.max.y, ex = b.min.x - a.max.x, ey = b.min.y - a.max.y;
    dx = dx > ex ? dx : ex;
    dy = dy > ey ? dy : ey;
    dx = dx > 0.0 ? dx : 0.0;
    dy = dy > 0.0 ? dy : 0.0;
    return sqrt(dx * dx + dy * dy);
}

#endif
