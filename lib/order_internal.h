/*
 * order_internal.h (internal) — what Algorithm 2 (lib/order.c) hands to the re-sequencing of its sub-curves
 * (lib/order_seq.c).
 */
#ifndef AMP_LIB_ORDER_INTERNAL_H
#define AMP_LIB_ORDER_INTERNAL_H

#include "order_fragbvh.h"

/* A sub-curve: fragments [lo, hi] of one path, printed lo..hi (dir +1) or hi..lo (dir -1). */
typedef struct amp_order_piece {
    uint32_t path, lo, hi;
    int dir;
    amp_box3 box;
} amp_order_piece;

/*
 * Re-sequence the sub-curves @p pc (a gouge-free order: every fragment below another comes first) for short
 * travel: the same sub-curves (so the same cuts), printed in a new order in which each sub-curve comes only
 * after every other sub-curve's fragment below it (Alg. 2's rule, at sub-curve level), chosen greedily as the
 * admissible one whose start is cheapest to reach from where the head stands: sqrt(dxy^2 + (zw dz)^2), zw the
 * cost of a mm of Z relative to a mm of XY. A sub-curve with no fragment below another of its own may be
 * printed either way. @p bvh must have every fragment active (freshly built). Deterministic. *queries grows by
 * the blocker queries made.
 */
amp_status amp_order_resequence(const amp_fragments *fs, amp_fbvh *bvh, double zo, double k, double zw,
                                amp_order_piece *pc, size_t npc, const amp_allocator *a, amp_error *err,
                                size_t *queries);

#endif
