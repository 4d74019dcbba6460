/* slicetool.h — shared steps of `ampath slice` and `ampath euler`: load an
 * STL, repair its orientation, slice it, pick a layer. */
#ifndef AMP_TOOLS_SLICETOOL_H
#define AMP_TOOLS_SLICETOOL_H

#include "cli.h"

/**
 * Read @p file, orient it consistently and outward (slicetool_outward) and slice
 * it with layer height @p layer and first layer @p first (<= 0: same).
 * Refuses (CLI_USAGE) when slicetool_estimate() exceeds cli_work.max_segments.
 * Prints its own error; returns CLI_OK or CLI_USAGE. *flipped receives the
 * number of triangles turned.
 */
int slicetool_load(const char *cmd, const char *file, double layer, double first, amp_mesh *m, amp_slices *sl,
                   size_t *flipped);

/**
 * Orient @p m consistently (amp_mesh_orient) and outward: when the enclosed
 * volume comes out negative every triangle is reversed, so that the inside
 * tests of field, support and check see the solid. *flipped (may be NULL)
 * receives the number of triangles reversed in all. amp_mesh_orient's errors.
 */
amp_status slicetool_outward(amp_mesh *m, size_t *flipped, amp_error *err);

/** Estimated section segments over all layers of slicing @p m at height @p layer (see cli_work). */
double slicetool_estimate(const amp_mesh *m, double layer);

/**
 * Layer to draw: @p index if >= 0, else the layer whose cutting height is
 * nearest to @p z (plate coordinates) when @p have_z, else the middle layer.
 * Returns -1 (after printing a reason) when out of range.
 */
long slicetool_pick(const char *cmd, const amp_slices *sl, long index, int have_z, double z);

/** Bounding box (x, y) of every ring of every layer; 0 when there is none. */
int slicetool_bbox(const amp_slices *sl, double *x0, double *y0, double *x1, double *y1);

#endif
