/*
 * ampath/check.h — the independent checkers. Each verifies a product of the
 * builders without sharing their code: a checker is never included or linked
 * by a builder (lib/check_*.c include only this header and the data headers),
 * so a bug in a builder cannot hide in its own check. `ampath check` runs them
 * (tools/check_*.c mirror lib/check_*.c).
 *
 *   amp_check_gouge        lib/check_gouge.c     no point printed earlier lies inside the head ([P1 §5.1])
 *   amp_check_stroke       lib/check_stroke.c    a continuous stroke neither crosses nor repeats itself ([P2 §4])
 *   amp_check_coverage     lib/check_coverage.c  distance from the solid to the paths ([P1 §4])
 *   amp_check_hold         lib/check_support.c   every object bead is held when printed ([P1 §5.3])
 *
 * Every checker returns AMP_ERR_CHECK with a reason when its property fails
 * (except amp_check_coverage, which measures and leaves the verdict to the
 * caller), AMP_ERR_ARG on bad input, AMP_ERR_NOMEM.
 */
#ifndef AMPATH_CHECK_H
#define AMPATH_CHECK_H

#include <stddef.h>

#include "bvh.h"
#include "head.h"
#include "paths.h"
#include "polygon.h"
#include "spline.h"
#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------ gouge
 *
 * Paths are printed in order, each from its first to its last vertex. The
 * check fails when a point printed earlier lies inside the head cone
 * (amp_head, docs/interfaces.md §2) while a later point is printed: for an earlier point q
 * and a later point p, (q.z - p.z - z_offs) - cot(theta) |q.xy - p.xy| > tol.
 * Earlier points include the earlier part of the same path and of the same
 * segment (a steep descent gouges itself).
 *
 * This code shares nothing with the orderer (the orderer): it maximises the
 * clearance numerically (golden-section search over the later segment with an
 * exact inner maximum over the earlier one), so it can check it.
 * Thread-safe; the pairwise method uses OpenMP.
 */

typedef enum amp_gouge_method {
    AMP_GOUGE_AUTO = 0,     /**< pairwise below 2000 segments, grid above */
    AMP_GOUGE_PAIRWISE = 1, /**< every pair of segments: O(S^2) */
    AMP_GOUGE_GRID = 2      /**< earlier segments in a column grid with a max-height pyramid, visited in print order */
} amp_gouge_method;

/** The first violation: the earliest later segment, and for it the earliest earlier segment. */
typedef struct amp_gouge_violation {
    size_t earlier_path, earlier_seg; /**< segment k joins vertices k and k+1 of the path (0 for a one-vertex path) */
    size_t later_path, later_seg;
    amp_vec3 earlier_point;           /**< the printed point inside the head ... */
    amp_vec3 later_point;             /**< ... while this point is printed */
    double depth;                     /**< how far inside the cone, mm (> tol; 0 for contact) */
} amp_gouge_violation;

/** Default tolerance (mm): a point within half a micrometre of the cone's surface, or outside, is no gouge;
 *  contact (clearance 0) is one, as for the builders (AMP_CONE_TOL, whose margin is twice this: a pair they
 *  keep apart stays apart through the .amp text's rounding). A negative tolerance counts contact. */
#define AMP_GOUGE_TOL (-5e-7)

/**
 * Check @p ps for gouging with head @p h. Returns AMP_OK when no violation
 * exists, AMP_ERR_CHECK when one does (then @p v, if not NULL, holds the first
 * one and err->msg says where), AMP_ERR_RANGE for a bad head or tolerance,
 * AMP_ERR_NOMEM. Both methods report the same first violation.
 */
amp_status amp_check_gouge(const amp_pathset *ps, const amp_head *h, amp_gouge_method m, double tol,
                           amp_gouge_violation *v, amp_error *err);

/* ----------------------------------------------------------------- stroke */

/** Findings of amp_check_stroke(). */
typedef struct amp_stroke_report {
    size_t segments;       /**< non-degenerate segments checked */
    size_t pseudo;         /**< of which pseudo edges (radius 0 at both ends; only with radii) */
    size_t crossings;      /**< pairs of segments crossing, and crossing passes through a shared vertex */
    size_t repeated_edges; /**< printed segments printed more than once (same end points, either direction) */
    size_t outside;        /**< vertices or segment midpoints outside the region (beyond tol) */
    int closed;            /**< 1 when the last point equals the first */
} amp_stroke_report;

/**
 * Independent checker of one stroke (a polyline of @p n points): no two
 * segments cross (proper crossings, and at a vertex visited several times the
 * passes must not interleave in the cyclic order of their directions), no
 * segment is printed twice, and, if @p region is not NULL, every vertex and
 * segment midpoint lies in the region or within @p tol of it. Fills @p rep
 * (optional) and returns AMP_ERR_CHECK with a reason on any violation,
 * AMP_ERR_NOMEM, AMP_ERR_ARG for NULL @p pts with n > 0, else AMP_OK. Shares
 * no code with the stroke builder. Every segment counts as printed (see
 * amp_check_stroke_radii()). Scratch memory comes from @p region's allocator
 * (the default allocator when @p region is NULL) and is freed before return.
 */
amp_status amp_check_stroke(const amp_vec2 *pts, size_t n, const amp_polyset *region, double tol,
                            amp_stroke_report *rep, amp_error *err);

/**
 * amp_check_stroke() with the deposition radius @p rad of every point (NULL:
 * all printed). A segment whose two ends have radius 0 is a pseudo edge
 * (travel inside the stroke): it may run over printed segments (collinear
 * overlap and repetition are allowed for it, since it deposits nothing), but
 * it must still not properly cross any segment, its passes through shared
 * vertices must not interleave, and it must stay inside the region.
 */
amp_status amp_check_stroke_radii(const amp_vec2 *pts, const double *rad, size_t n, const amp_polyset *region,
                                  double tol, amp_stroke_report *rep, amp_error *err);

/**
 * amp_check_stroke_radii() on path @p i of @p ps (its x, y and radii; z is
 * ignored). A scratch copy is allocated with the set's allocator
 * (AMP_ERR_NOMEM); AMP_ERR_ARG for NULL @p ps or no path @p i.
 */
amp_status amp_check_path_stroke(const amp_pathset *ps, size_t i, const amp_polyset *region, double tol,
                                    amp_stroke_report *rep, amp_error *err);

/* --------------------------------------------------------------- coverage */

/** Figures of a coverage measurement (amp_check_coverage()). */
typedef struct amp_coverage {
    double gap;          /**< largest distance from a sample of the solid to the nearest path segment (mm) */
    double mean;         /**< mean of those distances (mm) */
    amp_vec3 worst;      /**< the sample that attains the gap */
    double worst_par[3]; /**< its parameters (trivariate domain; 0 for a mesh) */
    size_t samples;      /**< samples measured */
    double volume;       /**< volume of the trivariate (mm^3, Gauss quadrature of |det J|); 0 for a mesh */
    double deposited;    /**< sum of A L over the paths (mm^3, amp_pathset_volume()) */
} amp_coverage;

/** The solid whose coverage is measured: exactly one of @c trivariate and @c mesh. */
typedef struct amp_coverage_domain {
    const amp_spline *trivariate; /**< a trivariate (dim 3), or NULL */
    const amp_bvh *mesh;          /**< the BVH of a closed mesh, or NULL */
    double margin;                /**< mesh only: samples keep at least this distance (mm, >= 0) from the surface */
} amp_coverage_domain;

/**
 * Coverage measure ([P1 §4]): how far the solid of @p d is from the paths of
 * @p ps, independently of how they were made. Every sample's distance to the
 * nearest path segment is exact (a uniform segment grid searched in rings of
 * cells). The samples, reproducible from @p seed:
 * - a trivariate: max(@p samples, 1000) points, half uniformly in parameter
 *   space and half uniformly in space (rejection sampling with acceptance
 *   |det J| / max |det J|), plus the 8 corners of the domain;
 * - a mesh: @p samples points (>= 1) uniform in the solid and at least
 *   d->margin from its surface. Inside (margin >= S) a lattice cover of
 *   spacing S has gap <= its covering radius; next to the surface the
 *   clipped-away curves leave up to about S.
 * Errors: AMP_ERR_ARG (no path segment, not exactly one solid, a trivariate of
 * dim != 3, samples 0 for a mesh, negative margin), AMP_ERR_GEOMETRY (a mesh:
 * no sample found in 100 x samples tries), AMP_ERR_NOMEM. @p out is zeroed
 * first. Thread-safe; OpenMP over the trivariate's samples.
 */
amp_status amp_check_coverage(const amp_pathset *ps, const amp_coverage_domain *d, size_t samples, unsigned long seed,
                              amp_coverage *out, amp_error *err);

/* ----------------------------------------------------- support: held paths
 *
 * Is every object path held when it is printed? ([P1 §5.3]: support exists
 * so that no bead is laid in the air.)
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

/** Options of amp_check_hold(). Initialise with amp_hold_opts_default(). */
typedef struct amp_hold_opts {
    double overhang; /**< largest overhang from the vertical, radians, in [0, pi/2) (default pi/4) */
    double max_gap;  /**< air tolerated under a bead, mm, >= 0 (default 1) */
    double bridge;   /**< longest bridge between held points, mm, >= 0 (default 5) */
    double cantilever; /**< longest unheld tip at a path end, mm, >= 0 (default 1) */
    double step;     /**< sample spacing along the paths, mm, > 0 (default 0.25) */
} amp_hold_opts;

void amp_hold_opts_default(amp_hold_opts *o);

/** Result of amp_check_hold(). Free with amp_hold_report_free(). */
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
amp_status amp_check_hold(const amp_pathset *ps, const amp_hold_opts *o, amp_hold_report *rep, amp_error *err);

/** Free the arrays of @p rep. NULL accepted. */
void amp_hold_report_free(amp_hold_report *rep);

/**
 * amp_check_hold() with the default options but @p max_gap, handing every
 * unheld run of samples (a failure, a bridge or a tip alike: samples of one
 * object path in order) to @p run as it is judged; the report is not kept.
 * The signature of support.h's amp_support_unheld_fn: set
 * amp_support_opts.find_unheld to this function for the pads of `ampath
 * support`. Errors: those of amp_check_hold(), or the first that @p run returns.
 */
amp_status amp_check_hold_runs(const amp_pathset *ps, double max_gap, amp_bead_run_fn run, void *user,
                               amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
