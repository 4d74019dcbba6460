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

/* One sample of an object bead: centre (x, y, z), the top of the bead there, how far it reaches sideways from
 * its centre line (w), and its path. */
typedef struct amp_bead_top {
    double x, y, top, z, w;
    uint32_t path;
} amp_bead_top;

/* The samples of the object beads (every 0.25 mm), bucketed by 1 mm cells in xy: the samples of cell c are
 * tp[cell[c] .. cell[c + 1]), in path order; reach is the largest w. */
typedef struct amp_bead_tops {
    const amp_allocator *a;
    amp_bead_top *tp;
    size_t n, cap, *cell, nx, ny;
    double x0, y0, reach;
} amp_bead_tops;

/* The tops of paths [0, nobj) of @p ps (pseudo edges left out). AMP_ERR_NOMEM, AMP_ERR_LIMIT (over 4e7 cells);
 * on failure @p t still needs amp_bead_tops_free. */
amp_status amp_bead_tops_build(amp_bead_tops *t, const amp_pathset *ps, size_t nobj, amp_error *err);
void amp_bead_tops_free(amp_bead_tops *t);
/* The cells [x0, x1] x [y0, y1] (cell c = y nx + x) that hold every sample within @p d of (x, y) in xy. */
void amp_bead_tops_near(const amp_bead_tops *t, double x, double y, double d, size_t *x0, size_t *y0, size_t *x1,
                        size_t *y1);

/* The runs of object samples a judge found in the air, as it handed them over (samples, and where each run
 * ends); valid: they are the runs of the paths in their present order. */
typedef struct amp_unheld_runs {
    const amp_allocator *a;
    amp_bead_sample *sm;
    size_t n, cap, *end, nruns, capruns;
    int valid;
} amp_unheld_runs;

void amp_unheld_runs_free(amp_unheld_runs *r);

/*
 * Reorder the object paths [0, nobj) of @p all (the support rows after them) so that an object bead the judge
 * o->find_unheld finds in the air is not printed before the object bead under it: the lower path is moved
 * just before the upper one, or the upper just after the lower, when no gouge rule (Def. 5.1, o->head) forbids
 * it; a round that leaves more samples in the air than the one before is undone. *moved: paths moved. @p runs
 * receives the judge's runs (valid when they are those of the order left). Nothing is done without a judge
 * or when a path of [0, nobj) is not an object path. AMP_ERR_NOMEM.
 */
amp_status amp_support_settle(amp_pathset *all, size_t nobj, const amp_support_opts *o, size_t *moved,
                              amp_unheld_runs *runs, amp_error *err);

typedef struct amp_support_pads_stats {
    size_t runs;   /* failing runs of the held-path check padded */
    size_t paths;  /* pad paths added */
    double length; /* their length, mm */
} amp_support_pads_stats;

/*
 * Append to @p all (object paths [0, nobj), then the support made so far) the pads under every run of object
 * beads that the judge o->find_unheld (max_gap = o->min_gap) finds in the air with that support printed
 * first (@p known, when valid: those runs, already judged by amp_support_settle): support beads of radius o->radius on the support layers @p L, each under a sample of the run
 * from what lies below it (the bed, a solid of @p model ending there, an object bead) up to the sample's
 * bottom (planar layers: a layer under it, as the rows). AMP_ERR_NOMEM, AMP_ERR_LIMIT.
 */
amp_status amp_support_pads(amp_pathset *all, size_t nobj, const amp_bvh *model, const amp_support_opts *o,
                            const amp_support_layers *L, const amp_unheld_runs *known, amp_support_pads_stats *out,
                            amp_error *err);

#endif
