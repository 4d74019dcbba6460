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

struct amp_spline;

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

/** Signed volume enclosed by the triangles (divergence theorem; positive for a closed outward mesh), mm^3. */
double amp_mesh_volume(const amp_mesh *m);

/** Edge topology of a mesh, filled by amp_mesh_edges(). */
typedef struct amp_mesh_edge_report {
    size_t edges;          /**< distinct undirected edges */
    size_t boundary;       /**< edges used by exactly one triangle (holes) */
    size_t nonmanifold;    /**< edges used by three or more triangles */
    size_t misoriented;    /**< edges used twice in the same direction (inconsistent orientation) */
    size_t degenerate;     /**< triangles with a repeated vertex index */
    int closed;            /**< 1 when every edge is shared by exactly two oppositely oriented triangles */
} amp_mesh_edge_report;

/**
 * Classify every edge of @p m (sorts a temporary edge list allocated with the
 * mesh's allocator). A mesh is closed (watertight and consistently oriented)
 * when boundary == nonmanifold == misoriented == degenerate == 0 and it has
 * triangles. AMP_ERR_NOMEM on allocation failure. Thread-safe for concurrent readers.
 */
amp_status amp_mesh_edges(const amp_mesh *m, amp_mesh_edge_report *out, amp_error *err);

/**
 * Make the orientation consistent: triangles are flipped so that every
 * manifold edge is used in opposite directions by its two triangles
 * (propagation per connected component across manifold edges); each
 * component then keeps the orientation of the majority of its area, so a few
 * flipped triangles are repaired while a whole inward shell (a cavity) stays
 * inward. *flipped (may be NULL) receives the number of triangles reversed.
 * AMP_ERR_NOMEM (mesh unchanged), AMP_ERR_LIMIT past 2^31 triangles.
 */
amp_status amp_mesh_orient(amp_mesh *m, size_t *flipped, amp_error *err);

/* ---- STL (lib/mesh_stl.c) ---- */

/** What the STL reader saw (amp_mesh_read_stl_ex()). */
typedef struct amp_stl_stats {
    int binary;          /**< 1 binary, 0 ASCII */
    size_t triangles;    /**< triangles in the file */
    size_t degenerate;   /**< triangles dropped: zero area (repeated or collinear corners) */
    size_t vertices;     /**< distinct vertices after welding (exact, then near_welded) */
    size_t duplicates;   /**< triangles dropped: exact copies of another (same corners), or pairs of opposite faces */
    size_t tjunctions;   /**< vertices found on a neighbour's edge (a T-junction): that triangle is split there */
    size_t near_welded;  /**< vertices merged into another less than 1e-9 of the part's diagonal away (an ASCII
                              exporter's -5.7e-16 for 0), with the triangles that collapse */
} amp_stl_stats;

/** Largest STL accepted by amp_mesh_read_stl_file() (bytes). */
#define AMP_STL_MAX_FILE ((size_t)1 << 30)

/**
 * Parse an STL file image of @p len bytes and append its triangles to @p m
 * (initialised by the caller; on error @p m is restored to its previous
 * content). Binary and ASCII are auto-detected: a binary file is one whose
 * size is exactly 84 + 50 n for the count n in its header, even if it starts
 * with "solid" (many exporters do that); otherwise a file starting with
 * "solid" is ASCII; anything else must be binary with at least 84 + 50 n bytes
 * (trailing bytes are ignored). ASCII accepts LF and CRLF, any case of the
 * keywords, several solids; normals are ignored (orientation comes from the
 * vertex order). Vertices with bit-identical coordinates are merged (exact
 * welding via a hash; -0 equals +0); use amp_mesh_weld() for a tolerance.
 * Zero-area triangles (two equal corners or collinear corners) are dropped
 * and counted. After welding, triangles with the same three corners (in any
 * rotation) are duplicates: of copies in one orientation the first is kept;
 * a face that also occurs reversed (a zero-thickness double wall) is dropped
 * with all its copies; both are counted in `duplicates`. Errors (AMP_ERR_PARSE; err->offset for binary, err->line for
 * ASCII): empty file, truncated header or triangle, a count larger than the
 * file, NaN or Inf coordinates, malformed ASCII, lines over 4096 bytes, a file
 * with no usable triangle; AMP_ERR_NOMEM; AMP_ERR_LIMIT past 2^32-1 vertices.
 * The data need not be NUL-terminated. Reentrant.
 */
amp_status amp_mesh_read_stl(amp_mesh *m, const void *data, size_t len, amp_error *err);

/** amp_mesh_read_stl() also reporting what it saw in @p stats (may be NULL). */
amp_status amp_mesh_read_stl_ex(amp_mesh *m, const void *data, size_t len, amp_stl_stats *stats, amp_error *err);

/** Read the STL file at @p path (amp_read_file() + amp_mesh_read_stl()); messages name the file. */
amp_status amp_mesh_read_stl_file(amp_mesh *m, const char *path, amp_error *err);

/** amp_mesh_read_stl_file() with @p stats (may be NULL). */
amp_status amp_mesh_read_stl_file_ex(amp_mesh *m, const char *path, amp_stl_stats *stats, amp_error *err);

/**
 * Write @p m as STL through @p sink: binary (@p binary non-zero; coordinates
 * rounded to float, little-endian, normals computed from the vertex order)
 * or ASCII (17 significant digits, exact round trip). Errors: AMP_ERR_LIMIT
 * for more than 2^32-1 triangles in binary, AMP_ERR_RANGE for coordinates
 * outside float range in binary, or the sink's status.
 */
amp_status amp_mesh_write_stl(const amp_mesh *m, int binary, amp_sink_fn sink, void *user, amp_error *err);

/** Write to a file, replaced atomically through amp_out (io.h: a unique temporary beside it, renamed over it;
 * on any failure the old file is left intact). AMP_ERR_IO with the system's reason. */
amp_status amp_mesh_write_stl_file(const amp_mesh *m, const char *path, int binary, amp_error *err);

/**
 * Merge vertices closer than @p tol (>= 0; 0 merges exact duplicates): each
 * vertex maps to the first earlier kept vertex within @p tol (greedy, in index
 * order, via a uniform grid hash), triangles are re-indexed, triangles that
 * collapse (repeated index) are removed, and unused vertices are dropped
 * (compaction keeps the relative order). AMP_ERR_ARG for a negative or
 * non-finite @p tol, AMP_ERR_NOMEM (mesh unchanged). Not thread-safe on @p m.
 */
amp_status amp_mesh_weld(amp_mesh *m, double tol, amp_error *err);

/* ---- built-in meshes (lib/mesh_models.c) ---- */

/** Default tolerance of amp_mesh_model(): the boundary is within 0.05 mm of the exact shape (docs/interfaces.md §4). */
#define AMP_MESH_MODEL_TOL 0.05

/**
 * Build the built-in mesh @p name into the empty mesh @p m (docs/interfaces.md §4
 * `ampath model NAME -o FILE.stl`):
 * - "helix": the boundary of the helix solid (a disc of radius 5 swept along
 *   c(t) = (20 cos 2πt, 20 sin 2πt, z0 + 40 t), t in [0, 1], in the plane
 *   normal to c'(t), flat end caps, lowest point at z = 0); every point of
 *   the mesh is within @p tol of the exact boundary and vice versa.
 * - "twisted-bridge": an arched beam (span 80 mm along x, section 16 x 6 mm
 *   centred on z = 14 sin(πx/80), turning a quarter turn about x from end to
 *   end), ends on z = 0 (paper Fig. 15); vertices lie on the exact sweep.
 * - "crocodile-like": an organic shape (body, head, curved tail, four thin
 *   legs of radius about 2 mm), blended implicit surface polygonised by
 *   marching tetrahedra with a grid step of 16 tol clamped to [0.4, 2] mm.
 * Every model is closed, consistently oriented outward (positive volume)
 * and rests on z = 0. @p tol is in mm, 0 means AMP_MESH_MODEL_TOL.
 * Errors: AMP_ERR_ARG (unknown name, NULL, non-empty mesh), AMP_ERR_RANGE
 * (tol outside [0.005, 1]), AMP_ERR_NOMEM (the mesh is left empty).
 * Reentrant.
 */
amp_status amp_mesh_model(const char *name, double tol, amp_mesh *m, amp_error *err);

/** Default samples per knot span of amp_mesh_from_trivariate(). */
#define AMP_MESH_TRIVARIATE_RES 8

/**
 * Tessellate the boundary of the trivariate @p v (its six faces u, v, w =
 * lo/hi) into the empty mesh @p m: each face is sampled on a grid of
 * @p res points per knot span and direction (0: AMP_MESH_TRIVARIATE_RES;
 * at most 64), split into triangles, then the faces are welded (relative
 * tolerance 1e-9 of the box diagonal, so closed directions such as a revolved
 * seam and collapsed faces join up), oriented consistently and outward
 * (positive volume). This is how `ampath support --trivariate` and
 * `ampath model NAME -o F.stl` for a trivariate get a mesh to cast rays on
 * (paper 1, §5.3). The chordal error is that of the sampling grid.
 * Errors: AMP_ERR_ARG (NULL, not a trivariate, non-empty mesh, res > 64),
 * AMP_ERR_GEOMETRY (the boundary encloses no volume), AMP_ERR_NOMEM or
 * AMP_ERR_LIMIT (the mesh is left empty). Reentrant; @p v is not modified.
 */
amp_status amp_mesh_from_trivariate(amp_mesh *m, const struct amp_spline *v, int res, amp_error *err);

/** Number of built-in mesh models. */
size_t amp_mesh_model_count(void);
/** Name of model @p i (NULL when i is out of range); static string. */
const char *amp_mesh_model_name(size_t i);
/** One-line description of model @p i (NULL when out of range); static string. */
const char *amp_mesh_model_summary(size_t i);

#ifdef __cplusplus
}
#endif
#endif
