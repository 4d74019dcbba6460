/* Internal interface between the support builder (lib/support.c) and its pads (lib/support_pads.c). */
#ifndef AMP_SUPPORT_INTERNAL_H
#define AMP_SUPPORT_INTERNAL_H

#include "ampath/support.h"

typedef struct amp_support_pads_stats {
    size_t runs;   /* failing runs of the held-path check padded */
    size_t paths;  /* pad paths added */
    double length; /* their length, mm */
} amp_support_pads_stats;

/*
 * Append to @p all (object paths [0, nobj), then the support made so far) the pads under every run of object
 * beads that the judge o->find_unheld (max_gap = o->min_gap) finds in the air with that support printed
 * first: support beads of radius o->radius on the support layers above @p plate, each under a
 * sample of the run from what lies below it (the bed, a solid of @p model ending there, an object bead) up
 * to the sample's bottom. AMP_ERR_NOMEM, AMP_ERR_LIMIT.
 */
amp_status amp_support_pads(amp_pathset *all, size_t nobj, const amp_bvh *model, const amp_support_opts *o,
                            double plate, amp_support_pads_stats *out, amp_error *err);

#endif
