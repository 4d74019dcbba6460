/*
 * ampath/field.h — covering a mesh with the curves of a direction field
 * ([P1 §4.2] and §5.4, Figs. 6, 7, 13, 15): a map F(u, v, w) -> R³ whose
 * iso-curves in one parametric direction are the covering curves; they are
 * sampled on a grid or honeycomb of the other two parameters at a spacing S
 * in millimetres, cut to the mesh (amp_bvh_clip_polyline) and written as
 * paths with the covering radius of the pattern.
 *
 * An amp_field is plain data describing the map; built-in fields are
 * analytic, and any other map (a trivariate spline, a user function) plugs in
 * through amp_field_custom(). Evaluation must be thread-safe and pure.
 */
#ifndef AMPATH_FIELD_H
#define AMPATH_FIELD_H

#include <stddef.h>

#include "bvh.h"
#include "paths.h"
#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

struct amp_field;

/** Evaluate the field at parameters uvw (inside the domain). Must be thread-safe. */
typedef amp_status (*amp_field_eval_fn)(const struct amp_field *f, const double uvw[3], amp_vec3 *out, amp_error *err);

/** A direction field: F over the box [lo, hi] of parameters; curves run along direction @p dir. */
typedef struct amp_field {
    amp_field_eval_fn eval;
    const void *user;      /**< the custom evaluator's data (NULL for built-ins) */
    double lo[3], hi[3];   /**< parameter domain */
    int dir;               /**< 0, 1 or 2: the parameter that varies along a covering curve */
    double p[8];           /**< parameters of built-in fields */
} amp_field;

/**
 * Built-in field @p name:
 * - "helix-square": a square cross-section of side 12 mm swept along the
 *   helix of docs/interfaces.md §4 (radius 20, pitch 40, same z0 as the `helix` model) in
 *   the plane normal to the helix; it contains the `helix` solid (paper
 *   Fig. 13b). Curves follow the helix (dir = 2, w in [-0.02, 1.02] so that
 *   they cross the end caps instead of ending on them).
 * - "box": straight lines parallel to x filling @p box inflated by 1 mm (to
 *   compare with planar slicing); pass the mesh's bounding box.
 * AMP_ERR_ARG for an unknown name (the message lists the names) or an empty
 * box for "box".
 */
amp_status amp_field_builtin(amp_field *f, const char *name, amp_box3 box, amp_error *err);

/** NULL-terminated list of built-in field names. */
const char *const *amp_field_names(void);

/** A field from a user evaluator over [lo, hi]; curves along @p dir (0..2). AMP_ERR_ARG on a bad domain. */
amp_status amp_field_custom(amp_field *f, amp_field_eval_fn eval, const void *user, const double lo[3],
                            const double hi[3], int dir, amp_error *err);

/** Most vertices of a sweep spine (amp_sweep is caller memory of fixed size). */
#define AMP_SWEEP_MAX 256

/**
 * A square cross-section swept along a polyline spine ([P1 §4.2], Fig. 6:
 * the crocodile's legs get their own field along each leg). Filled by
 * amp_field_sweep(); plain caller memory (about 15 KB), no allocation.
 */
typedef struct amp_sweep {
    size_t n;                     /**< spine vertices */
    amp_vec3 p[AMP_SWEEP_MAX];    /**< spine */
    amp_vec3 t[AMP_SWEEP_MAX];    /**< unit tangent at each vertex (mean of the adjacent segments) */
    amp_vec3 nrm[AMP_SWEEP_MAX];  /**< rotation-minimizing normal at each vertex (double reflection) */
    double s[AMP_SWEEP_MAX];      /**< arc length at each vertex, mm */
} amp_sweep;

/**
 * The field of a square of side @p side mm swept along the polyline @p pts
 * (@p n points): F(u, v, w) = C(w) + u N(w) + v B(w), with w the arc length
 * in mm, extended straight by side/2 beyond both ends so that the curves
 * cross the model's surface there, (u, v) in [-side/2, side/2] mm, and the
 * frame (T, N, B) interpolated between rotation-minimizing frames at the
 * vertices (so the curves are continuous through the bends and do not
 * twist). Curves run along the spine (dir = 2). @p sw receives the spine and
 * frames and must outlive @p f. Errors: AMP_ERR_ARG (NULL, n < 2,
 * n > AMP_SWEEP_MAX, side not positive, a non-finite point),
 * AMP_ERR_GEOMETRY (a segment shorter than 1e-6 mm, or the spine turning back
 * on itself by more than 170 degrees). Reentrant.
 */
amp_status amp_field_sweep(amp_field *f, amp_sweep *sw, const amp_vec3 *pts, size_t n, double side, amp_error *err);

struct amp_spline;

/** amp_field_from_spline()'s @p dir: the direction whose iso-curves are the most level. */
#define AMP_FIELD_AUTO (-1)

/**
 * A trivariate spline ([P1 §4.2]: "a trivariate that specifies the external
 * direction field") as a field over its parameter domain, curves along
 * @p dir (0 u, 1 v, 2 w), or with AMP_FIELD_AUTO along the direction whose
 * iso-curves are the most level (amp_trivariate_slopes(); slopes within 1e-6
 * tie, and of tied ones the longest by the Lemma A.2 bound wins, w first on a
 * tie): curves that climb are cut to pieces by Algorithm 2 (the vase along w:
 * 271,483 cuts at spacing 1.4, along v none). The choice is f->dir. The spline
 * is referenced, not copied: it must outlive @p f. AMP_ERR_ARG when it is not
 * a trivariate or dir is out of range.
 */
amp_status amp_field_from_spline(amp_field *f, const struct amp_spline *s, int dir, amp_error *err);

/** Sampling pattern of the curves across the field. */
typedef enum amp_pattern {
    AMP_PATTERN_GRID = 0, /**< square grid, spacing S: covering radius S·√2/2 */
    AMP_PATTERN_HEX = 1   /**< honeycomb (triangular lattice), spacing S: covering radius S/√3 */
} amp_pattern;

/** Options of amp_field_cover(); amp_field_opts_default() fills the defaults. */
typedef struct amp_field_opts {
    double spacing;      /**< S, mm, > 0 (default 1) */
    amp_pattern pattern; /**< default AMP_PATTERN_GRID */
    double step;         /**< sampling step along a curve, mm (default min(0.5, S/2)) */
    double min_len;      /**< clipped pieces shorter than this are dropped, mm (default S/2) */
    double radius;       /**< deposition radius written to the paths; 0 = the pattern's covering radius */
    int shells;          /**< surface layer: shell curves at S/2, 3S/2, ... inside the surface (default 0) */
    /** Several fields in one model: this field covers only the part of the solid inside @p within (a closed
     *  region mesh's BVH; NULL: everywhere) and outside every region of @p without (the parts other fields
     *  cover). The adaptive lattice treats the region's boundary like the surface, so the bound holds up to
     *  the seam on each side. Borrowed; default NULL / 0. */
    const amp_bvh *within;
    const amp_bvh *const *without;
    size_t nwithout;
    /** Optional progress report (fraction 0..1, from the calling thread, a few hundred times at most). */
    void (*progress)(void *user, double fraction);
    void *progress_user;
} amp_field_opts;

void amp_field_opts_default(amp_field_opts *o);

/** How a field was covered (see amp_field_cover()). */
typedef enum amp_field_route {
    AMP_FIELD_ROUTE_ALGORITHM1 = 1, /**< trivariate field: Algorithm 1 + adaptive iso-curves (§4.1), then clipped */
    AMP_FIELD_ROUTE_ADAPTIVE = 2,   /**< grid pattern: adaptive lattice refined in space */
    AMP_FIELD_ROUTE_UNIFORM = 3     /**< honeycomb: the plain lattice, no bound checked */
} amp_field_route;

/** Figures of one covering. */
typedef struct amp_field_stats {
    size_t curves;         /**< covering curves generated */
    size_t pieces;         /**< paths kept after clipping */
    size_t grid_a, grid_b; /**< base cells across the two other parameters (0 for a trivariate field) */
    double length_before;  /**< total length of the curves before clipping, mm */
    double length_after;   /**< total length of the kept paths, mm */
    double radius;         /**< deposition radius used, mm */
    double target;         /**< the covering radius aimed at: S sqrt(2)/2 (grid) or S / sqrt(3) (hex), mm */
    double bound;          /**< the covering radius the curves meet (see amp_field_cover()); NaN: not checked */
    int bound_met;         /**< 1: bound <= target; 0: the field cannot meet the spacing; -1: not checked */
    size_t inserted;       /**< adaptive route: curves added beyond the base lattice */
    amp_field_route route; /**< which covering was used */
    size_t shell_paths;    /**< surface layer: shell paths written (after the covering curves) */
    double shell_length;   /**< their length, mm */
    size_t gap_curves;     /**< adaptive and uniform routes: curves added through the gaps the sampled measure found */
    size_t gap_left;       /**< adaptive and uniform routes: samples still farther than the target in the last round */
} amp_field_stats;

/**
 * Cover the solid of @p b with the curves of @p f and append the inside
 * pieces to @p out (role object), aiming at a covering radius
 * target = S sqrt(2)/2 (grid) or S/sqrt(3) (hex) everywhere in the solid:
 * - a trivariate field (amp_field_from_spline) is covered by Algorithm 1 and
 *   the adaptive iso-curves of §4.1 with eps = target (§4.2 step 1), whatever
 *   its parametrization; the curves are then clipped to the mesh. The bound
 *   holds in the trivariate's volume (stats.bound = target, unless the
 *   recursion hit its depth limit);
 * - any other field with the grid pattern is covered by an adaptive lattice:
 *   base cells of at most S in space (the largest iso-curve length over a 5 x 5
 *   set of positions, divided by S), each split in two across its longer side
 *   while some point of it inside the mesh (a 5 x 5 grid over the cell at every
 *   sample along the curves) is farther than target from the nearest nearby
 *   curve at the same position along them, counting only curve points inside
 *   the mesh (the rest is clipped away): curves are inserted where neighbours
 *   drift apart and next to the surface, down to 1/32 of a base cell.
 *   stats.bound is the largest such cell figure, a sampled upper bound;
 *   bound_met = 0 when a finest cell still exceeds the target (the field
 *   cannot meet the spacing there). The solid is then sampled (100,000
 *   uniform samples, twice as many in each next round while gaps are
 *   found) and the field's curve through every sample farther than target
 *   from all paths is added (its lattice position by Newton's method on the
 *   field), in up to 6 rounds: features finer than the cell samples
 *   (threads, thin ribs) get their curves; stats.gap_curves
 *   counts them, stats.gap_left the samples a last round still finds far;
 * - the honeycomb is the plain lattice at the cell centres (no bound checked), then the same curves through
 *   the measured gaps (its curves are the seeds; stats.gap_curves, stats.gap_left).
 * With o->shells = N > 0 a surface layer follows: N shells of curves on the
 * surface offset inward by S/2, 3S/2, ...: the lattice curves (corners of the
 * base cells) that run within S/2 of the surface (shifted j S inward for
 * shell j) projected onto the offset surface, so that the skin is printed as
 * smooth curves along the field's direction (slicers' perimeters); they are
 * appended after the covering curves and add to its material.
 * Errors: AMP_ERR_ARG (bad options), the evaluator's errors, AMP_ERR_LIMIT
 * (more than 10^7 curve samples), AMP_ERR_NOMEM. @p stats may be NULL.
 * Thread-safe on @p f and @p b.
 */
amp_status amp_field_cover(const amp_field *f, const amp_bvh *b, const amp_field_opts *o, amp_pathset *out,
                           amp_field_stats *stats, amp_error *err);

/* The coverage of a field's paths is measured by amp_check_coverage() (check.h). */

#ifdef __cplusplus
}
#endif
#endif
