/*
 * ampath/slice.h — planar slicing of a triangle mesh into layers of
 * polygons with holes ([P2 §2.2] step 1, docs/interfaces.md §4).
 *
 * Layer i is cut at mid-height of its slab and its paths are printed at the
 * slab's top: with first-layer height H0 and layer height H, layer 0 spans
 * [0, H0] and layer i >= 1 spans [H0 + (i-1)H, H0 + iH]; without a first
 * layer height (H0 = H) this is the cut z = (i + 1/2)H and print z = (i+1)H of
 * docs/interfaces.md §4. Heights are measured from the mesh's lowest point (the mesh placed
 * on the plate).
 *
 * Sections are built by topology: each triangle crossing the plane gives one
 * segment whose ends are identified by the mesh EDGES they lie on (vertex
 * index pairs), and segments are chained through those edge ids, never by
 * comparing coordinates. Vertices exactly on the cutting plane are treated as
 * lying slightly above it (symbolic perturbation), so every crossing is a
 * proper sign change of an edge. Chains that do not close (an open mesh:
 * a crack, a missing triangle) are joined end to head, shortest gaps first,
 * into rings and counted (gaps_closed); edges crossed by more than two
 * segments (non-manifold) are counted. Functions are reentrant; the mesh is only read.
 */
#ifndef AMPATH_SLICE_H
#define AMPATH_SLICE_H

#include <stddef.h>

#include "alloc.h"
#include "mesh.h"
#include "polygon.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Slicing parameters (millimetres). */
typedef struct amp_slice_opts {
    double layer;       /**< layer height H > 0 */
    double first_layer; /**< first layer height H0 (<= 0: same as layer) */
} amp_slice_opts;

/** One layer: cutting height, printing height and its organised polygons. */
typedef struct amp_layer {
    double z_cut;      /**< height of the section (above the plate) */
    double z_print;    /**< height at which the layer's paths are printed */
    amp_polyset polys; /**< islands: CCW outer ring followed by its CW holes */
    size_t open_chains; /**< section chains of this layer that did not close (dropped: open mesh) */
} amp_layer;

/** All layers of a mesh plus the defects met while slicing. */
typedef struct amp_slices {
    const amp_allocator *alloc;
    amp_layer *layers;
    size_t nlayers;
    double z0;               /**< lowest mesh z (subtract it to place the mesh on the plate) */
    size_t open_chains;      /**< chains that did not close, over all layers (open mesh) */
    size_t nonmanifold;      /**< edges crossed by more than two segments, over all layers */
    size_t gaps_closed;      /**< open chains joined into rings, over all layers */
    size_t overlaps;         /**< layers whose rings overlapped (shells exported without a union), resolved by the nonzero rule */
} amp_slices;

/** Counters of one section. */
typedef struct amp_section_stats {
    size_t segments;    /**< triangle-plane segments */
    size_t open_chains; /**< chains dropped because they did not close (more than 1024 in a section, or too short for a ring) */
    size_t gaps_closed; /**< open chains joined, shortest gaps first, into rings: cracks or holes of an unclosed mesh */
    size_t nonmanifold; /**< section points shared by more than two segments */
    int overlaps;       /**< 1 when the rings overlapped and were replaced by their nonzero union (amp_polyset_union) */
} amp_section_stats;

/**
 * Cut @p m with the plane z = @p z (mesh coordinates) and append the closed
 * section polygons to @p out, organised in islands (outer CCW, holes CW,
 * amp_polyset_organize). @p stats (optional) receives the counters.
 * Triangles are assumed oriented counter-clockwise from outside (a mesh
 * facing inward as a whole is read as if it faced outward). Rings that
 * overlap (shells that cross or lie inside each other) are merged by the
 * nonzero rule (amp_polyset_union); the orientation of each ring matters
 * only there.
 * AMP_ERR_ARG for a non-finite z, AMP_ERR_NOMEM.
 */
amp_status amp_slice_plane(const amp_mesh *m, double z, amp_polyset *out, amp_section_stats *stats, amp_error *err);

/** Initialise an empty result allocating with @p a (NULL = default). */
void amp_slices_init(amp_slices *s, const amp_allocator *a);
/** Free every layer. NULL accepted. */
void amp_slices_free(amp_slices *s);

/**
 * Slice the whole mesh into layers (see the file comment for heights).
 * Layers are cut while the cutting height stays below the top of the mesh.
 * @p out is emptied first. AMP_ERR_ARG for a non-positive or non-finite
 * height or an empty mesh, AMP_ERR_LIMIT over 1,000,000 layers, AMP_ERR_NOMEM.
 * Open-mesh defects are not errors: they are counted in @p out.
 */
amp_status amp_slice_mesh(const amp_mesh *m, const amp_slice_opts *o, amp_slices *out, amp_error *err);

/**
 * ε-continuity of layers i and i + 1 ([P2 §2.1]):
 * the largest distance from a point of layer i + 1's section to layer i's
 * section (0 when it lies inside), i.e. the overhang; the pair is
 * ε-continuous for ε = c r when this is <= c r. Sampled at the vertices of
 * layer i + 1's rings (about 512 per layer) and a grid of spacing @p step
 * (<= 0: 1 mm; at least a 24th of the layer's extent) inside them, so it
 * may miss an overhang narrower than the sampling. Returns 0 when i + 1 >= nlayers or layer i + 1 is empty; a
 * layer over an empty one overhangs by +inf (HUGE_VAL).
 */
double amp_slices_overhang(const amp_slices *sl, size_t i, double step);

#ifdef __cplusplus
}
#endif
#endif
