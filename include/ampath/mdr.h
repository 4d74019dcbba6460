/*
 * ampath/mdr.h — material deposition radius (paper §5.2, Def. 5.4).
 *
 * Every path is cut into fragments; each fragment carries a virtual tube.
 * All tubes grow at the same rate from zero; a tube stops when it touches the
 * tube of another fragment (a fragment of another path, or of the same path
 * further away along it than 2 * r_max), or when it reaches r_max — "expand
 * the radius of each fragment's virtual tube until it touches the virtual
 * tube of another fragment" (§5.2). The simultaneous growth is computed
 * exactly, event by event (a Dijkstra-like sweep over neighbour pairs). The
 * radii are then clamped to [r_min, r_max]; a fragment with no neighbour
 * within 2 * r_max gets the nominal radius. Thread-safe (no shared state).
 */
#ifndef AMPATH_MDR_H
#define AMPATH_MDR_H

#include <stddef.h>

#include "paths.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct amp_mdr_opts {
    double nominal;  /**< radius of isolated fragments, mm (paper default 0.5) */
    double r_min;    /**< lower bound, mm (default nominal / 2) */
    double r_max;    /**< upper bound, mm (default 1.5 * nominal) */
    double fragment; /**< fragment length, mm (default: nominal) */
    /** Optional progress report, called from the calling thread with the fraction done (0..1), a few
     *  hundred times per run at most; NULL (default) for none. */
    void (*progress)(void *user, double fraction);
    void *progress_user; /**< passed to progress */
} amp_mdr_opts;

/** Defaults for @p nominal (mm). */
void amp_mdr_opts_default(amp_mdr_opts *o, double nominal);

typedef struct amp_mdr_stats {
    size_t fragments;  /**< fragments (tubes) */
    size_t pairs;      /**< neighbour pairs closer than 2 r_max */
    size_t at_min;     /**< tubes raised to r_min (they may overlap a neighbour) */
    size_t at_max;     /**< tubes stopped by r_max */
    size_t isolated;   /**< tubes without neighbour (nominal radius) */
    double r_lo, r_hi; /**< smallest and largest radius assigned */
    double deposited;  /**< sum of pi r^2 L over the output, mm^3 */
} amp_mdr_stats;

/**
 * Compute the MDR of every path of @p in and append the paths to @p out with
 * the fragment cut points inserted as vertices: an inner vertex takes its
 * fragment's radius, a cut point the smaller of its two fragments' radii.
 * Errors: AMP_ERR_RANGE (non-positive nominal or fragment, r_min > r_max,
 * r_min < 0), AMP_ERR_LIMIT, AMP_ERR_NOMEM. @p st may be NULL.
 */
amp_status amp_mdr(const amp_pathset *in, const amp_mdr_opts *o, amp_pathset *out, amp_mdr_stats *st,
                   amp_error *err);

/**
 * Monte-Carlo estimate of the volume of the union of the tubes of @p ps
 * (each segment a capsule of radius max(r_a, r_b)) with @p samples points
 * (deterministic sequence). Used as the volume of the over-coverage ratio
 * sum(pi r^2 L) / volume when the model's volume is not given.
 */
amp_status amp_tubes_union_volume(const amp_pathset *ps, size_t samples, double *volume, amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
