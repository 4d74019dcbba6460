/*
 * ampath/complex2.h — planar 2-complexes (polygonal cells) with an explicit
 * half-edge structure and a consistency checker ([P2 §1.3],
 * [P2 §2.2] step 3).
 *
 * A complex is a set of vertices (points of the plane), 2-cells given as
 * counter-clockwise vertex loops, and optional free 1-cells (edges in no
 * 2-cell, e.g. a Class 2 cell collapsed to an edge, §3 Fig. 9). After
 * amp_cx2_build() every face corner is a half-edge: half-edge h of face f
 * goes from corner k to corner k+1; he_twin[h] is the opposite half-edge of
 * the neighbouring face or AMP_CX2_NONE on the boundary.
 * Plain data: read the fields, modify through the functions. Not thread-safe
 * for modification; concurrent readers are fine.
 */
#ifndef AMPATH_COMPLEX2_H
#define AMPATH_COMPLEX2_H

#include <stddef.h>
#include <stdint.h>

#include "alloc.h"
#include "polygon.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AMP_CX2_NONE ((size_t)-1)

/** Cell classes of the Euler transformation (0 = input cell). */
enum { AMP_CELL_INPUT = 0, AMP_CELL_CLASS1 = 1, AMP_CELL_CLASS2 = 2, AMP_CELL_CLASS3 = 3 };

typedef struct amp_cx2 {
    const amp_allocator *alloc;
    amp_vec2 *v; /**< vertex positions */
    size_t nv, cap_v;
    uint32_t *fidx; /**< concatenated face loops; half-edge h starts at vertex fidx[h] */
    size_t nfidx, cap_fidx;
    size_t *fstart; /**< face f spans fidx[fstart[f] .. fstart[f+1]-1]; nf+1 entries */
    int *fclass;    /**< class of each face (AMP_CELL_*) */
    size_t nf, cap_f;
    uint32_t *xedge; /**< free 1-cells: pairs of vertex indices */
    size_t nxe, cap_xe;
    /* topology, valid after amp_cx2_build() */
    size_t *he_face; /**< face of each half-edge */
    size_t *he_twin; /**< opposite half-edge or AMP_CX2_NONE */
    int built;
} amp_cx2;

/** Figures of a complex computed by amp_cx2_check(). */
typedef struct amp_cx2_report {
    size_t vertices;    /**< vertices used by a cell */
    size_t edges;       /**< distinct 1-cells (face edges + free edges) */
    size_t faces;       /**< 2-cells */
    long euler_char;    /**< V - E + F */
    size_t boundary_edges;
    size_t nonmanifold; /**< edges in more than two faces */
    size_t misoriented; /**< edges used twice in the same direction */
    size_t bad_faces;   /**< faces with < 3 vertices, a repeated vertex or area <= 0 */
    size_t odd_vertices;
    size_t max_degree;
} amp_cx2_report;

void amp_cx2_init(amp_cx2 *k, const amp_allocator *a);
void amp_cx2_free(amp_cx2 *k);
/** Append a vertex; *id (optional) receives its index. AMP_ERR_ARG if not finite, AMP_ERR_NOMEM. */
amp_status amp_cx2_add_vertex(amp_cx2 *k, amp_vec2 p, uint32_t *id, amp_error *err);
/** Append a 2-cell (CCW loop of @p n >= 3 existing vertex indices) of class @p cls. Invalidates the topology. */
amp_status amp_cx2_add_face(amp_cx2 *k, const uint32_t *idx, size_t n, int cls, amp_error *err);
/** Append a free 1-cell between two distinct existing vertices. */
amp_status amp_cx2_add_edge(amp_cx2 *k, uint32_t a, uint32_t b, amp_error *err);
/** Number of corners (= half-edges) of face @p f. */
static inline size_t amp_cx2_face_size(const amp_cx2 *k, size_t f) { return k->fstart[f + 1] - k->fstart[f]; }
/** Next half-edge in the same face. */
size_t amp_cx2_he_next(const amp_cx2 *k, size_t h);
/** Previous half-edge in the same face. */
size_t amp_cx2_he_prev(const amp_cx2 *k, size_t h);

/**
 * Build the half-edge topology (twins). AMP_ERR_GEOMETRY when an edge lies
 * in more than two faces or twice in the same direction (the message names
 * the vertices); AMP_ERR_NOMEM.
 */
amp_status amp_cx2_build(amp_cx2 *k, amp_error *err);

/**
 * Independent consistency check: recomputes everything from the face loops
 * (not from the half-edge arrays): each edge in at most two faces with
 * opposite directions, faces simple enough (>= 3 distinct vertices, positive
 * area), Euler characteristic V - E + F, and 1-skeleton degrees.
 * Fills @p rep (optional). Returns AMP_ERR_CHECK with a reason when the
 * structure is broken (nonmanifold, misoriented or bad faces), else AMP_OK.
 */
amp_status amp_cx2_check(const amp_cx2 *k, amp_cx2_report *rep, amp_error *err);

/**
 * Euler check of the 1-skeleton: AMP_OK when every vertex has even degree,
 * AMP_ERR_CHECK naming the first odd vertex otherwise. *odd (optional)
 * receives the number of odd vertices. Independent of the transformation code.
 */
amp_status amp_cx2_check_even(const amp_cx2 *k, size_t *odd, amp_error *err);

/**
 * Grid kinds for amp_cx2_grid(). The strip kinds are rectangles @p cell wide
 * and AMP_GRID_STRIP_ASPECT x @p cell long, along x or along y: with offset
 * cell / 4 the beads of their Euler transformation lie side by side along
 * the long sides and cover the area once (the short sides add 1 /
 * AMP_GRID_STRIP_ASPECT), where a square lattice of the same cell covers it
 * twice (its beads run both ways) — the solid skins of the continuous paths.
 */
typedef enum amp_grid_kind {
    AMP_GRID_SQUARE = 0,
    AMP_GRID_TRI = 1,
    AMP_GRID_HEX = 2,
    AMP_GRID_STRIPS_X = 3,
    AMP_GRID_STRIPS_Y = 4
} amp_grid_kind;

/** Length over width of the cells of AMP_GRID_STRIPS_X and _Y. */
#define AMP_GRID_STRIP_ASPECT 80

/**
 * Mesh a convex polygon @p hull (CCW, @p n >= 3 points) with a pure
 * 2-complex K (§2.2 step 3): the cells of a regular square, equilateral
 * triangle or hexagon lattice of edge length @p cell (or of a strip lattice,
 * see amp_grid_kind) that meet the hull's
 * interior. K covers the hull (cells are not cut, so no sliver cells appear;
 * the excess is removed by clipping per layer). @p k is emptied first and is
 * built on return. AMP_ERR_ARG for a bad cell size or hull, AMP_ERR_LIMIT
 * over 4,000,000 cells, AMP_ERR_NOMEM.
 */
amp_status amp_cx2_grid(amp_cx2 *k, const amp_vec2 *hull, size_t n, double cell, amp_grid_kind kind, amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
