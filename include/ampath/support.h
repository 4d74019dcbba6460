/*
 * ampath/support.h — support structure (paper §5.3).
 *
 * Vertical rays on an xy grid (spacing = density) are cast through the model;
 * every stretch of a ray that lies outside the solid but below it (from the
 * plate, or from the top of a lower part of the solid, up to the underside
 * above) is support volume. The plate is where `gcode` will rest the job:
 * the lowest bead bottom of the object paths when it lies below min_gap (the
 * object rests on z = 0: its lowest tubes reach below it, or a field's lowest
 * curves sit half a spacing above it), else z = 0 (an object floating above
 * the plate is supported from it). That volume is filled on the
 * same grid with support paths (role support), one layer every
 * layer_height mm from the plate (the lowest rows' beads rest on it: z =
 * plate + radius + k layer_height), rows along x on even layers and along y
 * on odd ones, the rows of a layer whose facing ends are at most one ray
 * apart joined into one zigzag path (a one-ray column
 * gets a row 0.25 spacing long: no support path has zero length).
 * A sliced job (every object path flat with a bead height h > 0, heights
 * never going down along the job, its first layer resting on the plate:
 * paper 2's layers, contpath.h) gets its support on its own layers instead:
 * planar beads of radius o->radius and the layer's height (layer_height is
 * not used), the top of a row half a layer under the underside (one layer of
 * air under the object bead above), each layer's support printed just before
 * that layer's object paths, nearest next; no object path is split.
 * Settling (opts.find_unheld set, tubes only): two object beads stacked less
 * than z_offs apart are in no Def. 5.1 relation, so the upper may come first,
 * in the air, with no room for a pad under it. Before the pads, each object
 * path the judge finds in the air over an object path printed later is moved
 * after it (or that one before it) when no gouge rule forbids it; rounds are
 * kept while they leave fewer samples in the air (amp_support_stats.settled).
 * Pads (opts.find_unheld set, as the tool does): the rays see the model, not
 * the paths, so object beads can still float (a field's first row over a
 * shallow underside); the judge (the held-path check of check.h), run with
 * the rows printed first, names every unheld run, and a stack of support
 * beads on the same layers follows each run from what lies under it (the
 * bed, a solid of the model ending there, an object bead) up to its bottom.
 * Ordering (Def. 5.1): the rows are cut into fragments shorter than
 * z_offs sin(theta); each support fragment must come after the last object
 * fragment below it and before the first object fragment (and support piece)
 * above it. In a gouge-free object order such a slot always exists (the cone
 * inequalities of "a below s" and "s below b" add up to "a below b"), so no
 * fragment is dropped: a row is cut into as few pieces as possible, each piece
 * goes into its slot, at the start of an object path when the slot allows it,
 * else between two fragments of the object path, which is split there
 * (amp_support_stats.splits). Pieces with nothing above them come last.
 * conflicts / trimmed count fragments left out all the same (rounding only;
 * 0 on every model tried). Whether the object is then actually held is the
 * separate check of check.h (amp_check_hold).
 * Thread-safe; the model's BVH is only read.
 */
#ifndef AMPATH_SUPPORT_H
#define AMPATH_SUPPORT_H

#include <stddef.h>

#include "bvh.h"
#include "order.h"
#include "paths.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * The judge of the pads, exactly the signature of check.h's
 * amp_check_hold_runs: hands @p run every run of object samples of @p ps
 * (in print order) that nothing printed earlier holds within @p max_gap.
 * The builder calls it through amp_support_opts.find_unheld and never links a
 * checker itself: whoever fills the options decides whether pads are made.
 */
typedef amp_status (*amp_support_unheld_fn)(const amp_pathset *ps, double max_gap, amp_bead_run_fn run, void *user,
                                            amp_error *err);

typedef struct amp_support_opts {
    amp_head head;       /**< print head (for the ordering) */
    double spacing;      /**< grid spacing of rays and support rows, mm (default 2) */
    double layer_height; /**< vertical distance of support layers, mm (default 0.4) */
    double radius;       /**< deposition radius of support paths, mm (default 0.2) */
    double min_gap;      /**< ignore air gaps lower than this, mm (default 1) */
    /** Optional progress report (fraction 0..1, from the calling thread, a few hundred times at most). */
    void (*progress)(void *user, double fraction);
    void *progress_user;
    amp_support_unheld_fn find_unheld; /**< NULL (default): the grid's rows only. Else pads under the object
                              beads those rows leave in the air, as this judge finds them (max_gap = min_gap;
                              lib/support_pads.c). Set it to amp_check_hold_runs (check.h) for the behaviour
                              of the ampath tool. (last: python/ampath/_lib.py mirrors this struct) */
} amp_support_opts;

void amp_support_opts_default(amp_support_opts *o);

typedef struct amp_support_stats {
    size_t rays;          /**< vertical rays cast */
    size_t columns;       /**< ray stretches that need support */
    size_t paths;         /**< support paths written (after splitting around conflicts) */
    double length;        /**< length of the support rows made, mm (before trimming) */
    size_t unplaced;      /**< support paths with no object path above (printed last) */
    size_t splits;        /**< object paths split to let support in between their fragments */
    size_t conflicts;     /**< support fragments with no gouge-free slot, left out (0 unless rounding bites) */
    double trimmed;       /**< length left out for those conflicts, mm */
    size_t settled;       /**< object paths moved so that none is printed before the object bead it rests on */
    size_t pads;          /**< pad paths traced under object beads the rows leave in the air (opts.find_unheld) */
    double pad_length;    /**< their length, mm */
    int sliced;           /**< 1: a sliced job, supported on its own layers (planar beads); 0: tubes */
    double layer_height;  /**< height between the support layers made: opts.layer_height, or a sliced job's */
} amp_support_stats;

/**
 * Add support for @p model (BVH of the closed model mesh) under the paths of
 * @p in (a gouge-free print order) and append everything to @p out in print
 * order (object paths keep their order but for settled ones, some split in two or more; support
 * paths are interleaved as described above; support paths already in @p in
 * are kept in place). @p st may be NULL.
 * Errors: AMP_ERR_ARG (NULL arguments, or @p in without an object path), AMP_ERR_RANGE (bad options or head),
 * AMP_ERR_LIMIT, AMP_ERR_NOMEM.
 */
amp_status amp_support(const amp_pathset *in, const amp_bvh *model, const amp_support_opts *o, amp_pathset *out,
                       amp_support_stats *st, amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
