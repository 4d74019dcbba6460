/*
 * ampath/cover.h — covering a trivariate by print paths (paper 1 §4.1,
 * Algorithm 1 CoverVolumeWithSurfaces, the Appendix, and Elber & Cohen's
 * adaptive iso-curve covering of surfaces) and an independent measurement of
 * the coverage gap.
 *
 * Error budget. A volume point p is within ε of a path when it is within ε_s of
 * a covering surface point q, q within ε_c of a covering curve point, and that
 * point within δ (the chordal tolerance) of the polyline. We use
 * ε_s = ε_c = (ε − δ) / 2 and δ = chord_tol (default ε/20), so both recursions
 * stop when the measured "distance between neighbours" is at most ε − δ:
 *  - AMP_COVER_ARCLEN (default): the Appendix's bound. Lemma A.2 on the
 *    control net of the slab between two neighbours, per trimming cell, bounds
 *    the arc length L of every isoparametric curve joining them; L ≤ ε − δ
 *    gives every point of such a curve within (ε − δ)/2 of an end (Lemma A.1).
 *    This is sound: the measured gap is always ≤ ε.
 *  - AMP_COVER_ISO: the paper's Δ_iso, the distance between corresponding
 *    points of the two neighbours, evaluated on a sample grid of each trimming
 *    cell (corners, edge midpoints, centre). As the paper shows (Fig. 5) this
 *    does not guarantee coverage when the isoparametric curves between the
 *    neighbours bulge; the minimal depth m (min_depth) forces extra levels.
 *
 * Trimming (the domain D^t of Algorithm 1, line 13) is represented by a
 * uniform grid of `cells` × `cells` parameter cells per surface: a cell is kept
 * when the measure exceeds the threshold there. The recursion only refines
 * cells that the parent kept, which is the paper's "common trimmed portion"
 * (equivalent for the monotone arc-length measure). Curves are drawn over whole
 * cells, so they may extend a little beyond the exact D^t — never outside the
 * volume, since they are isoparametric curves of V.
 *
 * Thread-safety: functions only read their inputs; no global state.
 */
#ifndef AMPATH_COVER_H
#define AMPATH_COVER_H

#include <stddef.h>

#include "paths.h"
#include "spline.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum amp_cover_measure {
    AMP_COVER_ARCLEN = 0, /**< Appendix Lemma A.1/A.2 control-polygon arc-length bound (sound) */
    AMP_COVER_ISO = 1     /**< paper's iso-distance Δ_iso (sampled; may leave the Fig. 5 gap) */
} amp_cover_measure;

/** amp_cover_opts.dir: let amp_cover_pick_dir() choose the covering direction. */
#define AMP_COVER_AUTO (-1)

typedef struct amp_cover_opts {
    double eps;                /**< largest allowed distance from a volume point to a path (mm), > 0 */
    int dir;                   /**< direction whose iso-surfaces cover the volume (0 u, 1 v, 2 w = paper), or
                                    AMP_COVER_AUTO: the one amp_cover_pick_dir() chooses */
    int min_depth;             /**< Algorithm 1's m: levels subdivided regardless of the measure (>= 0) */
    amp_cover_measure measure; /**< see above */
    double radius;             /**< nominal deposition radius written on every vertex (mm), > 0 */
    double chord_tol;          /**< polyline deviation from the curve (mm); <= 0 means eps / 20 */
    int cells;                 /**< trimming cells per parametric direction (1..64); <= 0 means 16 */
    int max_depth;             /**< recursion limit per level; <= 0 means 24 */
    /** Optional progress report: called from the calling thread with the fraction of the
     *  covering direction done (0..1), after each covering surface. NULL = none. */
    void (*progress)(void *user, double fraction);
    void *progress_user;       /**< passed to progress */
} amp_cover_opts;

/** Defaults: eps 1 mm, dir AMP_COVER_AUTO, m 0, arc-length measure, radius 0.5 mm, δ = eps/20, 16 cells, no progress. */
void amp_cover_opts_default(amp_cover_opts *o);

typedef struct amp_cover_stats {
    size_t surfaces;      /**< covering (trimmed) iso-surfaces, boundaries included */
    size_t curves;        /**< covering iso-curve pieces (each a path) */
    size_t vertices;      /**< polyline vertices written */
    double length;        /**< total path length (mm) */
    int depth_limited;    /**< non-zero when max_depth stopped a recursion (coverage not guaranteed) */
    int dir;              /**< the covering direction used (0 u, 1 v, 2 w): opts->dir or the one chosen */
} amp_cover_stats;

/**
 * The covering direction that suits a printer (docs/splines.md): Algorithm 1's
 * iso-surfaces of direction d are covered by curves along w (d = u, v) or v
 * (d = w), and Algorithm 2 cuts a curve wherever it climbs over itself, so the
 * direction whose curves are the most level wins (score: the mean |t_z| / |t|
 * of their tangents at 512 interior samples; ties keep w). Between u and v
 * (the same curves, always the same score) the one with the shorter Lemma A.2
 * bound (amp_spline_polygon_length_bound) is taken, u on a tie. Writes the
 * choice to *@p dir and, when @p score is not NULL, each direction's score
 * (lower is better). Thread-safe, no allocation.
 * Errors: AMP_ERR_ARG (not a trivariate, NULL @p dir), AMP_ERR_RANGE (NaN in
 * the control net).
 */
amp_status amp_cover_pick_dir(const amp_spline *v, int *dir, double score[3], amp_error *err);

/**
 * How level the iso-curves of trivariate @p v are along each parametric
 * direction: slope[d] is the mean |t_z| / |t| of the tangent t = dV/d(u, v, w)
 * at 8 x 8 x 8 interior parameter samples (0: level; points where t vanishes
 * are skipped). What amp_cover_pick_dir() and amp_field_from_spline()'s
 * automatic direction compare. Thread-safe, no allocation. Errors: AMP_ERR_ARG
 * (not a trivariate, NULL @p slope), AMP_ERR_RANGE (NaN in the net).
 */
amp_status amp_trivariate_slopes(const amp_spline *v, double slope[3], amp_error *err);

/**
 * Cover the trivariate @p v (dim 3) by paths appended to @p out (role object,
 * radius opts->radius on every vertex), in the order surfaces were produced
 * (low to high parameter of opts->dir). @p stats may be NULL.
 * Errors: AMP_ERR_ARG (not a trivariate, bad options), AMP_ERR_NOMEM (paths
 * already appended stay in @p out).
 */
amp_status amp_cover_trivariate(const amp_spline *v, const amp_cover_opts *opts, amp_pathset *out,
                                amp_cover_stats *stats, amp_error *err);

/** The work limits `ampath cover` and the Python binding refuse a covering above (overridable per run). */
#define AMP_COVER_MAX_CURVES 1e6 /**< covering curves */
#define AMP_COVER_MAX_LENGTH 5e7 /**< their total length, mm */

/**
 * The work of amp_cover_trivariate(@p v, @p o) estimated before it starts (a
 * small eps grows it without bound): *@p curves, the number of covering curves
 * by Lemma A.2 on the control net (about (L_d / thr + 1) surfaces of
 * (L_e0 / thr + 1) curves, thr = eps - delta, in the direction o->dir, or the
 * one amp_cover_pick_dir() takes for auto), and *@p length, their total length
 * in mm. Within a factor of a few of the real counts on the built-in models:
 * enough to refuse a runaway covering (the helix along w at eps 0.02 took 100 s
 * and 3.7 GB before it was stopped). Thread-safe, no allocation. Errors:
 * AMP_ERR_ARG (not a trivariate, NULL, eps not positive, a bad direction),
 * those of amp_cover_pick_dir().
 */
amp_status amp_cover_estimate(const amp_spline *v, const amp_cover_opts *o, double *curves, double *length,
                              amp_error *err);

/* The independent coverage measure (amp_check_coverage): check.h. */

/**
 * The over-coverage of a covering (paper 1 §3.1: material deposited more than
 * once is excess): the material the object paths deposit, Σ A·L with the
 * cross-section A of each segment (amp_pathset_volume(), role object only:
 * support is not part of the model), divided by the volume of the model they
 * cover (@p model_volume, mm^3: the trivariate's amp_trivariate_volume() or a
 * closed mesh's amp_mesh_volume()). 1: as much plastic as the part holds;
 * above 1: excess; below 1: the tubes leave voids. The one figure that
 * `ampath mdr` and `ampath check` report as "over_coverage" (docs/order.md).
 * Returns NaN when @p model_volume is not positive and finite.
 */
double amp_over_coverage(const amp_pathset *ps, double model_volume);

/* amp_trivariate_volume(): spline.h. */

#ifdef __cplusplus
}
#endif
#endif
