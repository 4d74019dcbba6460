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

/** A directed edge (lo, hi) with the direction it was used in. */
typedef struct amp_edge_rec {
    uint32_t lo, hi;
    uint32_t up;  /* 1: lo -> hi in the triangle, 0: hi -> lo */
    uint32_t tri; /* triangle index in @p tris, for adjacency */
} amp_edge_rec;

/**
 * The 3 directed edges of every non-degenerate triangle of @p tris into e (room for 3 ntris), sorted so that
 * the uses of one undirected edge are adjacent (triangle order within them). Returns the count;
 * *degenerate (if not NULL) counts skipped triangles.
 */
size_t amp_mesh_collect_edges(const amp_allocator *al, const amp_tri *tris, size_t ntris, amp_edge_rec *e,
                              size_t *degenerate);

/** Exact vertex welding table (open addressing over coordinate bits; -0 == +0). */
typedef struct amp_weld_table {
    const amp_allocator *alloc;
    uint32_t *slot; /* vertex indices into the mesh, 0xffffffff = free */
    size_t cap, used;
} amp_weld_table;

void amp_weld_init(amp_weld_table *t, const amp_allocator *a);
void amp_weld_free(amp_weld_table *t);
/** Index of the vertex of @p m at exactly @p p, appending it when new. AMP_ERR_NOMEM, AMP_ERR_LIMIT. */
amp_status amp_weld_vertex(amp_weld_table *t, amp_mesh *m, amp_vec3 p, uint32_t *out, amp_error *err);

/**
 * Split the triangles of @p m from @p t0 on whose boundary edges (used by one triangle) a boundary vertex
 * lies (within float rounding): a fan from the opposite corner, so the neighbours' edges meet again
 * (lib/mesh_tjunction.c). *splits counts the vertices inserted into edges. Skipped when boundary edges x
 * boundary vertices exceed 5e7 (an open scan). AMP_ERR_NOMEM, AMP_ERR_LIMIT.
 */
amp_status amp_mesh_split_tjunctions(amp_mesh *m, size_t t0, size_t *splits, amp_error *err);

#endif
