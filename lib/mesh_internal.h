/* mesh_internal.h — helpers shared by lib/mesh.c and lib/bvh.c (not installed). */
#ifndef AMP_MESH_INTERNAL_H
#define AMP_MESH_INTERNAL_H

#include "ampath/mesh.h"

/**
 * amp_mesh_orient() on a bare triangle array (the BVH orients its own copy
 * without touching the caller's mesh). Allocates temporaries with @p al.
 */
amp_status amp_orient_tris(const amp_allocator *al, const amp_vec3 *verts, amp_tri *tris, size_t ntris,
                           size_t *flipped, amp_error *err);

#endif
