/*
 * order_fragbvh.h (internal) — bounding volume hierarchy over fragment boxes, the
 * acceleration structure of the below relation ([P1 §5.1]: "we are using a
 * BVH query to find ... all sub-curves that are above other sub-curves").
 * Leaves hold up to 4 fragments in Morton order. Each node also keeps the
 * lowest z of its fragments that are still unprinted, and their cone bounds
 * (amp_fbvh_set_cone), so that Algorithm 2's "is anything unprinted below f"
 * query prunes printed regions and low fragments far from f.
 * Queries only read the tree (thread-safe); amp_fbvh_deactivate writes.
 */
#ifndef AMP_LIB_FRAGBVH_H
#define AMP_LIB_FRAGBVH_H

#include <math.h>
#include <stdint.h>

#include "ampath/order.h"
#include "order_cone.h"

#define AMP_FBVH_NONE 0xffffffffU

typedef struct amp_fbvh_node {
    amp_box3 box;
    double minz;          /* lowest box.min.z of the still active fragments below the node */
    uint32_t lo, hi;      /* range of amp_fbvh.order */
    uint32_t left, right; /* children; left == 0 marks a leaf (the root is node 0) */
    uint32_t parent;
} amp_fbvh_node;

/* An xy box and a lowest z: what the blocker query's bound reads (minz +inf: empty). */
typedef struct amp_fbvh_box5 {
    double x0, y0, x1, y1, minz;
} amp_fbvh_box5;

/* Directions u of the cone bounds: +-x, +-y and the four diagonals. */
#define AMP_FBVH_NDIR 8

/* What Algorithm 2's blocker query reads of a node, in one compact array: the xy box and lowest z of the
 * fragments below it that are still unprinted (empty when all are printed), its children and its range. */
typedef struct amp_fbvh_act {
    amp_fbvh_box5 bx;
    uint32_t left, right, lo, hi;
    uint32_t minrank; /* lowest rank of those fragments (amp_fbvh_set_rank; 0 without ranks, empty: NONE) */
    uint32_t parent;  /* as in the node (AMP_FBVH_NONE at the root): the walks up read one cache line a level.
                       * 64 bytes, and the array 64-byte aligned: one cache line a node */
} amp_fbvh_act;

/* A node's cone bounds (amp_fbvh_set_cone): per direction u, the lowest z - k u.q over the box corners q of
 * its unprinted fragments (+inf when all are printed). Read only when the node's box bound passes. */
typedef struct amp_fbvh_cone {
    double m[AMP_FBVH_NDIR]; /* 64 bytes: one cache line */
} amp_fbvh_cone;

typedef struct amp_fbvh {
    const amp_allocator *alloc;
    amp_fbvh_node *node;
    amp_fbvh_act *act;    /* per node, refreshed by amp_fbvh_deactivate (inside act_mem, cache-line aligned) */
    void *act_mem;
    amp_fbvh_cone *cone;  /* per node, NULL until amp_fbvh_set_cone (inside cone_mem, cache-line aligned) */
    void *cone_mem;
    amp_fbvh_box5 *fbox;  /* per fragment in leaf order (order[q]): its xy box and lowest z */
    size_t nnodes;
    uint32_t *order; /* fragment ids in leaf order */
    uint32_t *leaf;  /* leaf node of each fragment */
    uint32_t *frank; /* per fragment in leaf order, its rank (amp_fbvh_set_rank); NULL: no ranks */
    double k;        /* the cone slope of cone[] (NaN: not set, the queries use the boxes alone) */
} amp_fbvh;

amp_status amp_fbvh_build(amp_fbvh *b, const amp_fragments *fs, const amp_allocator *a, amp_error *err);
void amp_fbvh_free(amp_fbvh *b);

/* Keep, per node, the cone bounds for slope @p k (= cot theta) of the still unprinted fragments: for every
 * direction u, m_u = min (z - k u.q) over their box corners. Since k |p - q| >= k u.(p - q), a fragment below
 * p needs m_u + k u.p < p.z - z_offs for every u: a node whose low fragments lie far away from p is passed
 * over although its box reaches low and near. Queries with another k use the boxes alone. Kept up to date by
 * amp_fbvh_deactivate and amp_fbvh_reactivate; 64 bytes a node. Errors: AMP_ERR_NOMEM (the hierarchy is left
 * without cone bounds, still correct). */
amp_status amp_fbvh_set_cone(amp_fbvh *b, double k, amp_error *err);

/* Rank every fragment (@p rank, per fragment id; NULL: drop the ranks): the queries that pass a rank then
 * count only the unprinted fragments ranked below it, and nodes whose unprinted fragments all rank at or above
 * it are passed over. The re-sequencing ranks fragments by their sub-curve's place in a gouge-free order: a
 * blocker of a sub-curve must come before it in every such order, so it ranks below it. Kept up to date by
 * amp_fbvh_deactivate and amp_fbvh_reactivate. Errors: AMP_ERR_NOMEM (no ranks kept, still correct). */
amp_status amp_fbvh_set_rank(amp_fbvh *b, const uint32_t *rank, amp_error *err);

/* Every fragment unprinted again: the hierarchy as amp_fbvh_build left it (the node boxes never shrink, only
 * the unprinted bounds do), without sorting again. */
void amp_fbvh_reactivate(amp_fbvh *b);

/* Fragment f is done (done[f] != 0): refresh the unprinted bounds (xy box, lowest z) on its way to the root. */
void amp_fbvh_deactivate(amp_fbvh *b, const amp_fragments *fs, const unsigned char *done, uint32_t f);

/* Some fragment g != f not done (done[g] == 0) below f (Def. 5.1), preferring high ones; AMP_FBVH_NONE if none.
 * Bounds may be stale (lower) for fragments marked done without amp_fbvh_deactivate: still correct.
 * *tests (if not NULL) is increased by the number of exact fragment tests. */
uint32_t amp_fbvh_find_below(const amp_fbvh *b, const amp_fragments *fs, const amp_head *h, uint32_t f,
                             const unsigned char *done, size_t *tests);

/* Some fragment g != f not done below f (head: tip height zo, k = cot(theta)), AMP_FBVH_NONE if none;
 * searched outwards from the leaf of @p near (f itself when AMP_FBVH_NONE), so a blocker close to @p near is
 * found first. Any blocker will do: this is the cheap form of amp_fbvh_find_below for Algorithm 2's waiting
 * lists. @p clear (NULL: not used) is f's slot for a subtree known to hold no blocker of f (AMP_FBVH_NONE at
 * first): it is skipped, and a larger subtree proven clear by this search is stored there. A subtree stays
 * clear only while marks in @p done are never taken back: pass NULL for tentative marks (look-ahead). */
uint32_t amp_fbvh_find_any_below(const amp_fbvh *b, const amp_fragments *fs, double zo, double k, uint32_t f,
                                 const unsigned char *done, uint32_t near, uint32_t *clear);

/* amp_fbvh_find_any_below with the fragments [xlo, xhi] (f among them) counted as printed: the blockers of f
 * outside the sub-curve it belongs to (the re-sequencing of whole sub-curves, lib/order_seq.c); with ranks set
 * and @p rank not AMP_FBVH_NONE, only fragments ranked below @p rank count. */
uint32_t amp_fbvh_find_any_below_x(const amp_fbvh *b, const amp_fragments *fs, double zo, double k, uint32_t f,
                                   uint32_t xlo, uint32_t xhi, uint32_t rank, const unsigned char *done, uint32_t near,
                                   uint32_t *clear);

/* Some fragment g outside [lo, hi], not done, below any fragment of the sub-curve [lo, hi] (whose fragments'
 * boxes are inside @p box), AMP_FBVH_NONE if none: one traversal for the whole sub-curve. @p rank as for
 * amp_fbvh_find_any_below_x. */
uint32_t amp_fbvh_find_any_below_piece(const amp_fbvh *b, const amp_fragments *fs, double zo, double k,
                                       uint32_t lo, uint32_t hi, uint32_t rank, amp_box3 box,
                                       const unsigned char *done);

/* Call cb(user, g) for every fragment g that f is below (g above f); stop early when cb returns non-zero.
 * Returns the number of fragments reported. */
size_t amp_fbvh_for_above(const amp_fbvh *b, const amp_fragments *fs, const amp_head *h, uint32_t f,
                          int (*cb)(void *user, uint32_t g), void *user);

#endif
