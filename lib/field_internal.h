/* field_internal.h — helpers shared by lib/field.c and lib/field_gaps.c (not installed). */
#ifndef AMP_FIELD_INTERNAL_H
#define AMP_FIELD_INTERNAL_H

#include <stdint.h>

#include "ampath/field.h"

/** Is @p p in the part of the solid this field covers: inside the mesh, inside o->within (if any), in no without? */
int amp_field_member(const amp_bvh *b, const amp_field_opts *o, amp_vec3 p);

/** The field's parameters at lattice position (a, b) in [0, 1]^2 and c in [0, 1] along the curves. */
void amp_field_to_uvw(const amp_field *f, double a, double b, double c, double uvw[3]);

/** The field's curve at lattice position (a, b): nc + 1 samples at c = k / nc into @p curve (radius @p r);
 *  its polyline length is added to *len, sample by sample (len may be NULL). The evaluator's errors. */
amp_status amp_field_curve(const amp_field *f, double a, double b, size_t nc, double r, amp_pvert *curve,
                           double *len, amp_error *err);

/** Clip a sampled curve to the covered part (mesh and regions); pieces shorter than @p min_len are dropped. */
amp_status amp_field_clip(const amp_bvh *b, const amp_field_opts *o, const amp_pvert *v, size_t n, double min_len,
                          amp_pathset *out, amp_error *err);

/** Where the covering's curves are: starting points for the inversion of the field (amp_field_fill_gaps). */
typedef struct amp_field_seeds {
    const amp_vec3 *pts;  /**< curve k's samples at pts[k (ncs + 1) ..], c = i / ncs */
    const uint64_t *key;  /**< curve k's lattice position: (ia << 32) | ib */
    size_t ncur, ncs;
    double da, db;        /**< a = ia / da, b = ib / db */
} amp_field_seeds;

/**
 * Curves through the covering's gaps: rounds of sampling the covered part of the solid uniformly (100,000
 * samples, twice as many after each round that found gaps, up to 800,000; seeds of its own) and adding the
 * field's curve through every sample farther than @p target from all of @p out's paths, up to 6 rounds and
 * a last one that only counts. The curve's lattice position comes
 * from inverting the field at the sample (Newton from the nearest seed); samples the field does not reach
 * are left. Pieces are kept at least @p min_len long, or shorter where they pass within @p target of their
 * sample. *added counts the curves, *left the samples the last round still found far (0: none).
 * AMP_ERR_NOMEM, the evaluator's errors.
 */
amp_status amp_field_fill_gaps(const amp_field *f, const amp_bvh *b, const amp_field_opts *o,
                               const amp_field_seeds *sd, size_t nc, double target, double r, double min_len,
                               amp_pathset *out, size_t *added, size_t *left, amp_error *err);

#endif
