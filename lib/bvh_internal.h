/*
 * The BVH's layout (lib/bvh.c), shared with its voxel map (lib/bvh_voxels.c).
 * Internal: not installed.
 */
#ifndef AMP_BVH_INTERNAL_H
#define AMP_BVH_INTERNAL_H

#include <stdint.h>

#include "ampath/bvh.h"

typedef struct bvh_node {
    amp_box3 box;
    amp_vec3 area; /* Σ ½ (b-a)×(c-a): the dipole moment of the node's surface */
    amp_vec3 cent; /* area-weighted centroid */
    double radius; /* max distance from cent to any corner in the node */
    uint32_t left, right; /* children (interior) */
    uint32_t first, count; /* triangle range (leaf when count > 0) */
} bvh_node;

typedef struct bvh_tri {
    amp_vec3 p[3];
    size_t src; /* index in the source mesh */
} bvh_tri;

struct amp_bvh {
    const amp_allocator *alloc;
    bvh_tri *tris;
    size_t ntris, flipped;
    int closed; /* every edge shared by two oppositely oriented triangles (after orienting): see winding_of */
    int capped; /* open, with its boundary chain closed by cap (bvh_cap.c): winding_of counts rays too */
    struct amp_bvh *cap; /* the caps' own tree (NULL when every edge is used as often each way) */
    bvh_node *nodes;
    size_t nnodes;
    amp_box3 bbox; /* of the triangles (node boxes are slightly inflated) */
};

/* Non-zero when triangle abc has an area the tree keeps (not a sliver of zero area). */
int amp_bvh_tri_ok(amp_vec3 a, amp_vec3 b, amp_vec3 c);

/* The tree over the non-degenerate triangles of @p tris (indices into @p verts), taken as oriented: no
 * orienting, no closedness test (closed = capped = 0, cap = NULL). Errors: AMP_ERR_GEOMETRY when no triangle
 * has an area, AMP_ERR_NOMEM. */
amp_status amp_bvh_build_tris(amp_bvh **out, const amp_allocator *al, const amp_vec3 *verts, const amp_tri *tris,
                              size_t ntris, amp_error *err);

/* The caps of an open mesh (bvh_cap.c): b->cap over the boundary chain of the oriented @p tris (the
 * triangles b was built from), b->capped set. AMP_ERR_NOMEM only; a chain it cannot close leaves b uncapped. */
amp_status amp_bvh_cap_build(amp_bvh *b, const amp_vec3 *verts, const amp_tri *tris, size_t ntris, amp_error *err);

#endif
