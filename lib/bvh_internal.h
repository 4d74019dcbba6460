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
    bvh_node *nodes;
    size_t nnodes;
    amp_box3 bbox; /* of the triangles (node boxes are slightly inflated) */
};

#endif
