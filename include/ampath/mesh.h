/*
 * ampath/mesh.h — triangle meshes: STL input/output, welding, a BVH,
 * ray casting, robust inside tests and clipping polylines to a solid.
 *
 * amp_mesh is plain data (read the fields freely, modify through the
 * functions). Triangles index into the vertex array and are oriented
 * counter-clockwise seen from outside (right-hand normal pointing out) when
 * the source is consistent; the inside tests do not rely on it.
 * A mesh is not thread-safe for modification; once built, the mesh and its
 * BVH may be queried from many threads at once.
 */
#ifndef AMPATH_MESH_H
#define AMPATH_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "alloc.h"
#include "io.h"
#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A triangle: three indices into amp_mesh.verts. */
typedef struct amp_tri {
    uint32_t v[3];
} amp_tri;

typedef struct amp_mesh {
    const amp_allocator *alloc;
    amp_vec3 *verts;
    size_t nverts, cap_verts;
    amp_tri *tris;
    size_t ntris, cap_tris;
} amp_mesh;

/** Initialise an empty mesh allocating with @p a (NULL = default). */
void amp_mesh_init(amp_mesh *m, const amp_allocator *a);
/** Free the mesh's memory; it is empty and reusable afterwards. NULL accepted. */
void amp_mesh_free(amp_mesh *m);
/** Append a vertex; *index (if not NULL) receives its index. AMP_ERR_ARG if not finite, AMP_ERR_LIMIT past 2^32-1 vertices. */
amp_status amp_mesh_add_vertex(amp_mesh *m, amp_vec3 p, uint32_t *index, amp_error *err);
/** Append a triangle of existing vertex indices (AMP_ERR_ARG if out of range). */
amp_status amp_mesh_add_tri(amp_mesh *m, uint32_t a, uint32_t b, uint32_t c, amp_error *err);
/** Bounding box of the vertices. */
amp_box3 amp_mesh_bbox(const amp_mesh *m);
/** Translate every vertex by @p d. */
void amp_mesh_translate(amp_mesh *m, amp_vec3 d);

#ifdef __cplusplus
}
#endif
#endif
