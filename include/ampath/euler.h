/*
 * ampath/euler.h — the Euler transformation of planar 2-complexes
 * ([P2 §1.3] Fig. 2, [P2 §3] Lemma 3.1, Def. 3.2, Lemma 3.3).
 *
 * K̂ = T(K) consists of
 *   Class 1: the mitered offset f̂ of every 2-cell f of K (offset distance δ);
 *   Class 2: for every edge e = ab, the trapezium between the offset copies of
 *            e in its two faces (a boundary edge: between e itself and its
 *            copy);
 *   Class 3: for every vertex v, the cell of its copies in the faces around v
 *            (a boundary vertex also includes v itself).
 * When no 2-cell has two adjacent boundary edges and no offset changes
 * combinatorially, every vertex of the 1-skeleton of K̂ has degree 4.
 * With combinatorial changes allowed (§3), a mitered offset may lose edges
 * (their end copies merge; Lemma 3.1: degree 2π+4-m), and a Class 2 cell
 * whose edge collapses on both sides becomes a free 1-cell. The generalized
 * transformation T(T(K)) (Def. 3.2) makes the 1-skeleton Euler even when
 * cells have adjacent boundary edges (Fig. 11). Class 2 cells collapsed to
 * edges leave odd vertices (Lemma 3.1, m odd); amp_euler_repair() replaces
 * the Class 3 cells around them by their generalized transformation
 * (Lemma 3.3).
 * Functions are reentrant; inputs are only read.
 */
#ifndef AMPATH_EULER_H
#define AMPATH_EULER_H

#include "complex2.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct amp_euler_opts {
    double offset;     /**< mitered offset distance δ > 0 (same unit as K) */
    int combinatorial; /**< 1: allow mitered offsets to drop collapsing edges (§3), convex or not */
} amp_euler_opts;

typedef struct amp_euler_stats {
    size_t collapsed_edges;  /**< offset edges dropped by combinatorial changes (Σπ) */
    size_t collapsed_class2; /**< Class 2 cells collapsed to a free edge (Σm) */
} amp_euler_stats;

/**
 * Euler transformation K̂ = T(@p k) into @p out (emptied first, built on
 * return). @p k must be a pure complex (no free edges) with CCW faces.
 * Errors: AMP_ERR_ARG (bad offset, free edges in K), AMP_ERR_GEOMETRY when a
 * mitered offset is invalid (an edge collapsing without combinatorial
 * changes allowed, a cell vanishing, or the offset of a non-convex cell not
 * simple because a reflex corner runs into another edge: the topological
 * changes the paper leaves to future work), with the face index in the
 * message; AMP_ERR_NOMEM. @p st is optional.
 * The mitered offset is the wavefront of the cell's edges moved inward by
 * δ; with combinatorial changes its edge events are processed in time
 * order (each edge's length is linear in time between events), for convex
 * and non-convex cells.
 */
amp_status amp_euler_transform(const amp_cx2 *k, const amp_euler_opts *o, amp_cx2 *out, amp_euler_stats *st,
                               amp_error *err);

/** Figures of amp_euler_repair(). */
typedef struct amp_euler_repair_stats {
    size_t collapsed_edges; /**< collapsed Class 2 cells (free 1-cells ê) removed */
    size_t cells;           /**< Class 3 cells of k̂ replaced by T(T(k̂)) */
    size_t components;      /**< edge-connected components k̂_j of k̂ */
} amp_euler_repair_stats;

/**
 * Local repair of Lemma 3.3: in @p khat = T(K) computed with combinatorial
 * changes, the sub-complex k̂ of Class 3 cells that share an edge ê of a
 * collapsed Class 2 cell (the free 1-cells of @p khat) is replaced by its
 * generalized transformation T(T(k̂)) (Def. 3.2, offsets a quarter of the
 * smallest feature of k̂, halved until valid, no combinatorial changes),
 * glued back along k̂'s boundary, which both passes keep; the free 1-cells
 * go with k̂. Result in @p out (emptied first, built on return, a pure
 * complex). Every vertex of @p out has even degree when the only odd
 * vertices of @p khat were those of collapsed Class 2 cells (K without
 * cells having adjacent boundary edges, §1.3); else use
 * amp_euler_generalized(). The rest of @p khat is copied unchanged (same
 * vertex indices; new vertices are appended). Without free 1-cells @p out
 * is a copy. @p st is optional.
 * Errors: AMP_ERR_ARG when @p out is @p khat; AMP_ERR_STATE when @p khat is
 * not built; AMP_ERR_GEOMETRY when a free 1-cell is not an edge of Class 3
 * cells only (not an output of amp_euler_transform), or when k̂ cannot be
 * transformed; AMP_ERR_NOMEM. On error @p out is empty.
 */
amp_status amp_euler_repair(const amp_cx2 *khat, amp_cx2 *out, amp_euler_repair_stats *st, amp_error *err);

/**
 * Generalized Euler transformation (Def. 3.2): T(T(K)). The first pass uses
 * @p o; if it collapses Class 2 cells to edges, Lemma 3.3's local repair
 * (amp_euler_repair) is applied to it. The second pass uses an offset small
 * enough for the cells of that complex (a quarter of min(δ, shortest edge,
 * smallest 2·area/perimeter), halved until valid) without combinatorial
 * changes (its input has no cell with two adjacent boundary edges), so on
 * success every vertex of @p out has even degree (Def. 3.2; the tests check
 * it with amp_cx2_check_even). Errors: those of amp_euler_transform() and
 * amp_euler_repair().
 */
amp_status amp_euler_generalized(const amp_cx2 *k, const amp_euler_opts *o, amp_cx2 *out, amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
