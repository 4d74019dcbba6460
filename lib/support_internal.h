/* Internal interface between the support builder (lib/support.c) and its pads (lib/support_pads.c). */
#ifndef AMP_SUPPORT_INTERNAL_H
#define AMP_SUPPORT_INTERNAL_H

#include "ampath/support.h"

/*
 * Heights of the support layers, shared by the rows (support.c) and the pads: layer j's beads lie on
 * z = plate + first + j step. Tubes (h = 0, the volumetric paper's beads): radius o->radius centred
 * there, first = o->radius, step = o->layer_height. A sliced job (every object path a planar bead,
 * printed layer by layer): the job's own layers, planar beads of the job's height with their top at z
 * (first = h0, the first layer's height; step = h the others').
 */
typedef struct amp_support_layers {
    double plate, first, step, h0, h;
} amp_support_layers;

/* z of support layer @p j (bead centre for tubes, bead top for planar beads). */
double amp_support_layer_z(const amp_support_layers *L, size_t j);
/* Bead height of support layer @p j: 0 for tubes. */
double amp_support_layer_h(const amp_support_layers *L, size_t j);

typedef struct amp_support_pads_stats {
    size_t runs;   /* failing runs of the held-path check padded */
    size_t paths;  /* pad paths added */
    double length; /* their length, mm */
} amp_support_pads_stats;

/*
 * Append to @p all (object paths [0, nobj), then the support made so far) the pads under every run of object
 * beads that the judge o->find_unheld (max_gap = o->min_gap) finds in the air with that support printed
 * first: support beads of radius o->radius on the support layers @p L, each under a sample of the run
 * from what lies below it (the bed, a solid of @p model ending there, an object bead) up to the sample's
 * bottom (planar layers: a layer under it, as the rows). AMP_ERR_NOMEM, AMP_ERR_LIMIT.
 */
amp_status amp_support_pads(amp_pathset *all, size_t nobj, const amp_bvh *model, const amp_support_opts *o,
                            const amp_support_layers *L, amp_support_pads_stats *out, amp_error *err);

#endif
