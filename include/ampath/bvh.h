/*
 * ampath/bvh.h — a bounding volume hierarchy over a triangle mesh: ray and
 * segment intersection, closest point, robust inside tests (generalised
 * winding number) and clipping of polylines to the solid ([P1 §4.2]: the
 * covering curves of a direction field are kept where they lie inside the mesh).
 *
 * An amp_bvh is built once from an amp_mesh and is immutable afterwards: it
 * keeps its own copy of the triangles (the mesh may be freed or changed
 * after amp_bvh_build()), so every query below is thread-safe and may be
 * called concurrently from many threads (OpenMP loops) on one amp_bvh.
 * Queries that return arrays allocate with the mesh's allocator, which must
 * then be thread-safe itself when queried concurrently (the default is).
 *
 * Orientation: at build time the triangles are re-oriented consistently per
 * connected component (propagation across manifold edges); each component
 * then keeps the orientation held by the majority of its area. A few flipped
 * triangles in an otherwise outward mesh are therefore repaired, while an
 * intentionally inward shell (a cavity) keeps its meaning.
 */
#ifndef AMPATH_BVH_H
#define AMPATH_BVH_H

#include <stddef.h>

#include "mesh.h"
#include "paths.h"
#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Opaque BVH (see the file comment). */
typedef struct amp_bvh amp_bvh;

/** One intersection of a ray or segment with a triangle. */
typedef struct amp_bvh_hit {
    double t;     /**< parameter along the ray (o + t d); for segments in [0, 1] */
    size_t tri;   /**< index of the triangle in the source mesh */
    double u, v;  /**< barycentric coordinates: p = (1-u-v) a + u b + v c */
    amp_vec3 p;   /**< the point o + t d */
    int entering; /**< 1 when the ray enters the solid there (d against the re-oriented normal), else 0 */
} amp_bvh_hit;

/**
 * Build a BVH (binned surface-area heuristic, at most 4 triangles per leaf)
 * over @p m. *out receives the new object, to be released with amp_bvh_free().
 * Triangles with a repeated vertex index or zero area are ignored.
 * Errors: AMP_ERR_ARG (NULL, index out of range), AMP_ERR_GEOMETRY (no
 * triangle with positive area), AMP_ERR_NOMEM. Allocates with m->alloc.
 */
amp_status amp_bvh_build(amp_bvh **out, const amp_mesh *m, amp_error *err);

/** Release a BVH. NULL is accepted. */
void amp_bvh_free(amp_bvh *b);

/** Number of triangles indexed (degenerate ones excluded). */
size_t amp_bvh_triangles(const amp_bvh *b);
/** Number of triangles whose orientation the build reversed (see the file comment). */
size_t amp_bvh_flipped(const amp_bvh *b);
/** 1 when every edge is shared by exactly two oppositely oriented triangles after the build's orienting. */
int amp_bvh_closed(const amp_bvh *b);
/**
 * Triangles of the caps that close an open mesh for amp_bvh_inside(): fans over the loops of its boundary
 * chain (the edges used more often in one direction than in the other). 0 for a closed mesh and for one
 * whose edges are each used as often both ways (two solids sharing an edge); -1 when the build left the mesh
 * uncapped (not expected; amp_bvh_winding() then decides every inside test).
 */
long amp_bvh_cap_triangles(const amp_bvh *b);
/** Bounding box of the indexed triangles. */
amp_box3 amp_bvh_bbox(const amp_bvh *b);

/**
 * First intersection of the ray o + t d, 0 <= t <= tmax (d need not be unit;
 * tmax may be HUGE_VAL). Returns 1 and fills *hit (if not NULL), or 0.
 * Edges and vertices count as part of every triangle that shares them.
 */
int amp_bvh_ray_first(const amp_bvh *b, amp_vec3 o, amp_vec3 d, double tmax, amp_bvh_hit *hit);

/**
 * All intersections of the ray o + t d with 0 <= t <= tmax, sorted by t.
 * *hits is allocated with the mesh's allocator (free it with
 * amp_bvh_hits_free()); *n is the count (*hits is NULL when 0). A crossing
 * through a shared edge may appear once per triangle sharing it.
 * Errors: AMP_ERR_NOMEM, AMP_ERR_ARG (non-finite input).
 */
amp_status amp_bvh_ray_all(const amp_bvh *b, amp_vec3 o, amp_vec3 d, double tmax, amp_bvh_hit **hits, size_t *n,
                           amp_error *err);

/** amp_bvh_ray_all() for the segment [a, c]: t in [0, 1]. */
amp_status amp_bvh_segment_hits(const amp_bvh *b, amp_vec3 a, amp_vec3 c, amp_bvh_hit **hits, size_t *n,
                                amp_error *err);

/** Free an array returned by amp_bvh_ray_all() or amp_bvh_segment_hits(). NULL accepted. */
void amp_bvh_hits_free(const amp_bvh *b, amp_bvh_hit *hits);

/**
 * Closest point of the surface to @p p: returns the (unsigned) distance,
 * stores the point in *q and the source triangle index in *tri (each may be NULL).
 */
double amp_bvh_closest(const amp_bvh *b, amp_vec3 p, amp_vec3 *q, size_t *tri);

/**
 * Generalised winding number of the surface at @p p (Jacobson et al. 2013):
 * the signed solid angle of all triangles / 4π. About 1 inside and 0 outside
 * a closed outward surface, and a smooth in-between value near holes.
 * Nodes far from @p p (distance > 4 × their radius) use the first-order
 * (dipole) approximation of Barill et al. 2018; near nodes are exact, so the
 * value is exact near the surface, where the inside decision is delicate.
 * The error far away is below 0.02 on the test meshes (tests/test_bvh.c).
 */
double amp_bvh_winding(const amp_bvh *b, amp_vec3 p);

/** Exact winding number (every triangle evaluated, O(n)): the reference for amp_bvh_winding(). */
double amp_bvh_winding_exact(const amp_bvh *b, amp_vec3 p);

/**
 * Non-zero when the winding number at @p p is >= 0.5: robust on meshes with small holes and flipped
 * triangles. On a closed mesh (amp_bvh_closed()) the winding number is an integer off the surface and is
 * taken from the signed crossings of one ray (up to six directions when a ray meets an edge or a vertex).
 * An open mesh is closed by caps over its boundary (amp_bvh_cap_triangles()): its winding number is then
 * the ray's signed count over mesh and caps less the caps' own winding number, the same function. Where
 * every ray meets an edge, or for a point on the surface, amp_bvh_winding() decides. The answers agree
 * wherever both are defined; the ray costs about log n where the solid angles cost every near triangle.
 */
int amp_bvh_inside(const amp_bvh *b, amp_vec3 p);

/**
 * The winding number amp_bvh_inside() compares with 1/2: an integer off a closed mesh, the count over the
 * caps less their winding number on an open one, amp_bvh_winding() where no ray decides. For a caller that
 * needs the margin of a decision (`ampath check` takes a vertex within 1e-4 of 1/2 as on an open mesh's
 * boundary, where `field` cut its curve). Thread-safe.
 */
double amp_bvh_inside_winding(const amp_bvh *b, amp_vec3 p);

/** A voxel map of a closed mesh's solid: opaque, see amp_bvh_voxels_build(). */
typedef struct amp_bvh_voxels amp_bvh_voxels;

/**
 * The voxel map of @p b's solid in at most @p max_cells cubes over its box, into *out (NULL, AMP_OK, for an
 * open mesh, whose winding number varies smoothly near its holes). Every cell the box of a triangle reaches
 * is marked as near the surface; the other cells hold the winding number of a closed mesh unchanged, and each
 * group of them joined by faces takes the amp_bvh_inside() answer at one of its centres. A sampler that
 * tests many points (the field's gap rounds: a part filling 3 % of its box) then casts rays only near the
 * surface. AMP_ERR_ARG (NULL, max_cells outside 1 .. 2^32 - 1), AMP_ERR_NOMEM. Allocates with the BVH's allocator; the map
 * refers to nothing of @p b afterwards. Release with amp_bvh_voxels_free().
 */
amp_status amp_bvh_voxels_build(const amp_bvh *b, size_t max_cells, amp_bvh_voxels **out, amp_error *err);

/**
 * 1 when @p p is inside the solid, 0 outside (the answer amp_bvh_inside() gives), -1 in a cell near the
 * surface, where only amp_bvh_inside() decides. A point outside the mesh's box is outside. Thread-safe.
 */
int amp_bvh_voxels_side(const amp_bvh_voxels *v, amp_vec3 p);

/** Release a voxel map. NULL is accepted. */
void amp_bvh_voxels_free(amp_bvh_voxels *v);

/**
 * Clip the polyline @p v[0..n-1] to the solid and append its inside pieces to
 * @p out as paths of @p role ([P1 §4.2]: "keep the parts inside the mesh").
 * Every segment is cut exactly where it crosses a triangle (segment–triangle
 * intersection through the BVH); each sub-segment is then classified by the
 * winding number at its midpoint (by a ray on a closed mesh, as in
 * amp_bvh_inside()), so that crossings through holes or flipped
 * triangles do not toggle the state wrongly. Cut points lie on the surface;
 * radii are interpolated linearly. Pieces shorter than @p min_len (mm, >= 0)
 * are dropped. On error @p out keeps the pieces appended before the error.
 * Errors: AMP_ERR_ARG (NULL, n > 0 with v NULL, bad min_len, non-finite
 * vertex), AMP_ERR_NOMEM. Thread-safe on @p b (not on @p out).
 */
amp_status amp_bvh_clip_polyline(const amp_bvh *b, const amp_pvert *v, size_t n, double min_len, amp_role role,
                                 amp_pathset *out, amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
