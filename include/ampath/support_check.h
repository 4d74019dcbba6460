/*
 * ampath/support_check.h — is every object path held when it is printed?
 * (paper 1 §5.3: support exists so that no bead is laid in the air.)
 *
 * An independent check of a print order, used by `ampath check` (its
 * "support" section) and by `ampath support` to name the object paths that
 * its support leaves unheld. It knows nothing of how the support was made.
 *
 * The paths are sampled every `step` mm along their extruding segments
 * (radius > 0; pseudo edges are neither material nor tested). A sample p of an
 * object path is *held* when, at the moment it is printed,
 *   - the bed is under it: the bottom of its bead is at most max_gap above
 *     z = 0, or
 *   - material printed earlier is under it (any earlier sample q, of any path,
 *     including earlier points of p's own path): q lies lower (q.z < p.z),
 *     within the overhang cone below p (|p.xy - q.xy| <= (p.z - q.z) tan(overhang),
 *     the slicers' 45-degree rule by default), and the air between the bottom
 *     of p's bead and the top of q's is at most max_gap.
 * A bead's vertical half-extent is h/2 for a planar path with bead height h,
 * else its radius r. A maximal run of unheld samples along one path is a
 * *bridge* when held samples bound it on both sides and the span between them
 * is at most `bridge` mm; a run at one end of a path, off a held sample, is a
 * *tip* when it reaches at most `cantilever` mm beyond it (a bead end hanging
 * over an edge by about its width); any other unheld run is a failure (a bead
 * printed in the air, or a long cantilever).
 * max_gap defaults to 1 mm, the same as amp_support_opts.min_gap: air lower
 * than that is what `ampath support` leaves unsupported on purpose.
 * Thread-safe (reads only its input; OpenMP over samples when enabled).
 */
#ifndef AMPATH_SUPPORT_CHECK_H
#define AMPATH_SUPPORT_CHECK_H

#include <stddef.h>

#include "paths.h"
#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Options of amp_hold_check(). Initialise with amp_hold_opts_default(). */
typedef struct amp_hold_opts {
    double overhang; /**< largest overhang from the vertical, radians, in [0, pi/2) (default pi/4) */
    double max_gap;  /**< air tolerated under a bead, mm, >= 0 (default 1) */
    double bridge;   /**< longest bridge between held points, mm, >= 0 (default 5) */
    double cantilever; /**< longest unheld tip at a path end, mm, >= 0 (default 1) */
    double step;     /**< sample spacing along the paths, mm, > 0 (default 0.25) */
} amp_hold_opts;

void amp_hold_opts_default(amp_hold_opts *o);

/** Result of amp_hold_check(). Free with amp_hold_report_free(). */
typedef struct amp_hold_report {
    const amp_allocator *alloc;
    size_t samples;       /**< object samples tested */
    size_t unheld;        /**< of them, with nothing under them */
    size_t bridges;       /**< unheld runs accepted as bridges */
    double bridged_mm;    /**< their total span, mm */
    size_t tips;          /**< unheld runs accepted as tips at a path end */
    size_t failures;      /**< unheld runs that are not bridges */
    double failed_mm;     /**< their total length, mm */
    size_t npaths_failed; /**< object paths with at least one failure */
    size_t *paths_failed; /**< their indices in the pathset, increasing (owned) */
    size_t worst_path;    /**< path of the longest failing run (when failures > 0) */
    double worst_mm;      /**< its length, mm */
    amp_vec3 worst_at;    /**< its first sample */
} amp_hold_report;

/**
 * Check that every object path of @p ps (in print order) is held, as defined
 * above. Fills @p rep (caller frees it with amp_hold_report_free(), also after
 * an error). Allocates with ps->alloc.
 * Errors: AMP_ERR_ARG (NULL), AMP_ERR_RANGE (bad options),
 * AMP_ERR_LIMIT (more than 2^31 samples), AMP_ERR_NOMEM.
 */
amp_status amp_hold_check(const amp_pathset *ps, const amp_hold_opts *o, amp_hold_report *rep, amp_error *err);

/** Free the arrays of @p rep. NULL accepted. */
void amp_hold_report_free(amp_hold_report *rep);

#ifdef __cplusplus
}
#endif
#endif
