/*
 * ampath/spline.h — B-spline curves, surfaces and trivariates (one type).
 *
 * An amp_spline is a tensor-product B-spline with 1, 2 or 3 parametric
 * directions (curve, surface, trivariate) mapping into R^3, polynomial or
 * rational, of any order 1..AMP_SPLINE_MAX_ORDER per direction, over any
 * non-decreasing knot vector (clamped or not). A Bézier patch is the special
 * case count == order with clamped knots (amp_spline_set_knots_uniform()).
 * [P1 §4.1] and its Appendix work on these objects.
 *
 * Storage: control points are kept in homogeneous form (w·x, w·y, w·z, w), four
 * doubles each, u varying fastest, then v, then w (as in the .spl file). A
 * polynomial spline has w = 1 everywhere. Use amp_spline_cp_get()/_set() to
 * read and write Euclidean points and weights.
 *
 * Domain of direction d: [knots[d][order-1], knots[d][count]]. Evaluation
 * clamps parameters to that domain (documented choice: roundoff in callers
 * never fails) and rejects NaN with AMP_ERR_RANGE. Inside the domain,
 * evaluation is exact at and near knots: a parameter is never snapped onto a
 * knot; at an interior knot the span to its right is used (right-continuous),
 * at the domain end the last non-empty span.
 *
 * Thread-safety: evaluation and queries only read the spline, so any number of
 * threads may evaluate one spline at once; functions that modify it need
 * exclusive access. No function keeps global state.
 */
#ifndef AMPATH_SPLINE_H
#define AMPATH_SPLINE_H

#include <stddef.h>

#include "alloc.h"
#include "io.h"
#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest order (degree + 1) accepted in any direction. */
#define AMP_SPLINE_MAX_ORDER 16
/** Most parametric directions (3 = trivariate). */
#define AMP_SPLINE_MAX_DIM 3
/** Highest derivative order per direction returned by amp_spline_eval_derivs(). */
#define AMP_SPLINE_MAX_DERIV 4
/** Most control points per direction (keeps index arithmetic far from overflow). */
#define AMP_SPLINE_MAX_COUNT 1000000

typedef struct amp_spline {
    const amp_allocator *alloc; /**< allocator of knots and cp (NULL = default) */
    int dim;                    /**< 1 curve, 2 surface, 3 trivariate */
    int rational;               /**< non-zero: weights are meaningful */
    int order[AMP_SPLINE_MAX_DIM];      /**< order per direction (unused entries 1) */
    size_t count[AMP_SPLINE_MAX_DIM];   /**< control points per direction (unused entries 1) */
    double *knots[AMP_SPLINE_MAX_DIM];  /**< count[d] + order[d] knots each (unused NULL) */
    double *cp;                 /**< 4 * ncp doubles: w·x, w·y, w·z, w */
    size_t ncp;                 /**< count[0] * count[1] * count[2] */
} amp_spline;

/** A zeroed, empty spline (safe to pass to amp_spline_free()). */
void amp_spline_init(amp_spline *s);

/**
 * Allocate a spline of @p dim directions with the given orders and counts
 * (arrays of @p dim entries). Knots are set to the clamped uniform vector on
 * [0, 1] and control points to (0, 0, 0, w = 1); fill them afterwards.
 * Errors: AMP_ERR_ARG (dim outside 1..3, count < order, order < 1),
 * AMP_ERR_LIMIT (order > AMP_SPLINE_MAX_ORDER, count > AMP_SPLINE_MAX_COUNT),
 * AMP_ERR_NOMEM. On failure @p s is left empty. @p s must not hold memory.
 */
amp_status amp_spline_create(amp_spline *s, const amp_allocator *a, int dim, const int *order, const size_t *count,
                             int rational, amp_error *err);

/** Release the spline's memory and make it empty. NULL and empty splines are accepted. */
void amp_spline_free(amp_spline *s);

/** Deep copy of @p src into @p dst (which must not hold memory), allocating through @p a. */
amp_status amp_spline_copy(amp_spline *dst, const amp_spline *src, const amp_allocator *a, amp_error *err);

/**
 * Knot vector of direction @p d: uniform on [lo, hi]; clamped (end knots
 * repeated order times, Bézier when count == order) or, when @p clamped is 0,
 * fully uniform with the domain [lo, hi]. AMP_ERR_ARG when d is out of range or lo >= hi.
 */
amp_status amp_spline_set_knots_uniform(amp_spline *s, int d, double lo, double hi, int clamped, amp_error *err);

/**
 * Check the invariants: knots finite and non-decreasing, no knot of multiplicity
 * above order (except at the two outer ends, where order + 0 is the most), a
 * non-empty domain, finite control points, positive weights when rational
 * (weight 1 when not). AMP_ERR_ARG / AMP_ERR_GEOMETRY / AMP_ERR_LIMIT with a reason.
 */
amp_status amp_spline_validate(const amp_spline *s, amp_error *err);

/** Index of control point (i, j, k) in cp / 4 (j, k ignored beyond dim). */
static inline size_t amp_spline_index(const amp_spline *s, size_t i, size_t j, size_t k)
{
    return i + s->count[0] * (j + s->count[1] * k);
}
/** Euclidean control point @p idx and its weight (may be NULL). */
amp_vec3 amp_spline_cp_get(const amp_spline *s, size_t idx, double *weight);
/** Set control point @p idx from a Euclidean point and weight (weight is forced to 1 unless rational). */
void amp_spline_cp_set(amp_spline *s, size_t idx, amp_vec3 p, double weight);

/** Parameter domain of direction @p d (0 <= d < dim); [0, 0] for any other d and for an empty spline. */
void amp_spline_domain(const amp_spline *s, int d, double *lo, double *hi);

/** Bounding box of the Euclidean control points (contains the spline when weights are positive). */
amp_box3 amp_spline_cp_bbox(const amp_spline *s);

/**
 * Point at parameters @p par (dim values). Out-of-domain values are clamped;
 * NaN gives AMP_ERR_RANGE. Thread-safe.
 */
amp_status amp_spline_eval(const amp_spline *s, const double *par, amp_vec3 *out, amp_error *err);

/**
 * All partial derivatives up to order @p nd (0..AMP_SPLINE_MAX_DERIV) in each
 * direction: out[a + (nd+1)*(b + (nd+1)*c)] = ∂^(a+b+c) V / ∂u^a ∂v^b ∂w^c,
 * with (nd+1)^dim entries (b, c = 0 beyond dim). Rational splines use the
 * generalised quotient rule (NURBS Book eq. 4.20 extended to three directions).
 * Derivatives above the degree are zero. Thread-safe.
 */
amp_status amp_spline_eval_derivs(const amp_spline *s, const double *par, int nd, amp_vec3 *out, amp_error *err);

/**
 * One partial derivative ∂^(k0+k1+k2) V / ∂u^k0 ∂v^k1 ∂w^k2 (@p k has dim
 * entries, each 0..AMP_SPLINE_MAX_DERIV). Thread-safe.
 */
amp_status amp_spline_eval_partial(const amp_spline *s, const double *par, const int *k, amp_vec3 *out,
                                   amp_error *err);

/**
 * Batched points at @p n parameter tuples par[i*dim .. i*dim+dim-1] into
 * out[0..n-1] (caller memory). Consecutive parameters in the same knot span
 * reuse the span search. Parallel with OpenMP when built with it (no
 * allocation). Parameters are clamped as in amp_spline_eval(); NaN gives
 * AMP_ERR_RANGE (the other points are still written).
 */
amp_status amp_spline_eval_list(const amp_spline *s, const double *par, size_t n, amp_vec3 *out, amp_error *err);

/**
 * Batched points on a tensor grid: params[d] holds n[d] values for direction d
 * (d < dim); out receives n[0]*...*n[dim-1] points, the first direction
 * varying fastest. Spans and basis values are computed once per grid line and
 * reused for every point (O(n0 k0 + n1 k1 + n2 k2) basis work). Allocates
 * scratch through the spline's allocator; parallel over the outer direction
 * with OpenMP. Errors: AMP_ERR_NOMEM, AMP_ERR_RANGE (NaN).
 */
amp_status amp_spline_eval_grid(const amp_spline *s, const double *const *params, const size_t *n, amp_vec3 *out,
                                amp_error *err);

/**
 * Insert knot @p t @p times times in direction @p d (Boehm's algorithm on the
 * homogeneous control net). The shape is unchanged. @p t must lie inside the
 * domain (AMP_ERR_RANGE otherwise); the multiplicity may not exceed the order
 * (AMP_ERR_LIMIT). AMP_ERR_NOMEM leaves @p s unchanged.
 */
amp_status amp_spline_insert_knot(amp_spline *s, int d, double t, int times, amp_error *err);

/**
 * Insert each of the @p n knots @p t (any order) once in direction @p d (knot
 * refinement), on a copy that replaces @p s at the end: any error (those of
 * amp_spline_insert_knot(), AMP_ERR_NOMEM, AMP_ERR_ARG for NULL) leaves @p s
 * unchanged.
 */
amp_status amp_spline_refine(amp_spline *s, int d, const double *t, size_t n, amp_error *err);

/**
 * Split @p s at parameter @p t of direction @p d into @p left (domain lo..t)
 * and @p right (t..hi), both new splines allocated with s's allocator (neither
 * may hold memory). @p t must be strictly inside the domain (AMP_ERR_RANGE).
 * Together they describe exactly the same shape.
 */
amp_status amp_spline_split(const amp_spline *s, int d, double t, amp_spline *left, amp_spline *right,
                            amp_error *err);

/**
 * Isoparametric extraction: the spline of dim-1 directions obtained by fixing
 * parameter @p d at @p t (a curve from a surface, a surface from a trivariate),
 * exact also for rational splines. @p out must not hold memory. @p t is clamped.
 * AMP_ERR_ARG for a curve (dim 1).
 */
amp_status amp_spline_isoparam(const amp_spline *s, int d, double t, amp_spline *out, amp_error *err);

/** Reverse direction @p d in place: V'(..t..) = V(..lo+hi-t..). */
void amp_spline_reverse(amp_spline *s, int d);

/**
 * Derivative spline along direction @p d of a polynomial spline: order - 1,
 * count - 1. AMP_ERR_UNSUPPORTED for rational splines (use eval_derivs),
 * AMP_ERR_ARG for order 1. @p out must not hold memory.
 */
amp_status amp_spline_derivative(const amp_spline *s, int d, amp_spline *out, amp_error *err);

/**
 * Paper Appendix, Lemma A.2: an upper bound on the arc length of every
 * isoparametric curve in direction @p d (the "w" direction of the lemma):
 * the sum over segments k of max over the other indices (i, j) of
 * |P_{i,j,k+1} - P_{i,j,k}|. @p seg (may be NULL) receives the count[d]-1
 * per-segment maxima. For rational splines the lemma's step is not valid as
 * stated; we add the weight term (r_max / r_min - 1) · R_k where r = w_{k+1}/w_k
 * ranges over (i, j) and R_k is the radius of layer k's control points about
 * their centroid — a sound bound that equals the paper's when the weight
 * ratios do not vary (see docs/splines.md). Returns the total bound.
 */
double amp_spline_polygon_length_bound(const amp_spline *s, int d, double *seg);

/* ---- the .spl text format (docs/interfaces.md §4) ---- */

/**
 * Parse every object of a .spl text (@p len bytes, NUL not required).
 * On success *list holds *n splines allocated with @p a (free with
 * amp_spline_list_free()). Errors: AMP_ERR_PARSE with the line number for
 * malformed text, non-monotone knots, wrong counts, non-positive weights;
 * AMP_ERR_LIMIT for orders above AMP_SPLINE_MAX_ORDER; AMP_ERR_NOMEM.
 * On failure nothing is allocated. Thread-safe.
 */
amp_status amp_spline_parse(const char *text, size_t len, const amp_allocator *a, amp_spline **list, size_t *n,
                            amp_error *err);

/** Free @p n splines and the array returned by amp_spline_parse(). */
void amp_spline_list_free(const amp_allocator *a, amp_spline *list, size_t n);

/** Read a .spl file (amp_read_file + amp_spline_parse); AMP_ERR_IO when it cannot be read. */
amp_status amp_spline_read_file(const char *path, const amp_allocator *a, amp_spline **list, size_t *n,
                                amp_error *err);

/**
 * Write one object (with the "ampath-spline 1" header when @p header is
 * non-zero; further objects of the same file are written without it) in
 * full precision (%.17g). Errors are the sink's.
 */
amp_status amp_spline_write(const amp_spline *s, int header, amp_sink_fn sink, void *user, amp_error *err);

/* ---- built-in trivariates (lib/spline_models.c) ---- */

/**
 * Build the built-in trivariate @p name into @p out (must not hold memory):
 *  - "helix": docs/interfaces.md §4 / paper Fig. 2, disc of radius 5 mm swept along the helix
 *    of radius 20 mm and pitch 40 mm, lowest point at z = 0; (u, v) map the
 *    square onto the disc exactly (rational biquadratic), w follows the helix
 *    (16 rational quadratic arcs: x, y exact, z within 0.004 mm).
 *  - "torus-quarter": paper Fig. 4 (major radius 1, minor 0.2) scaled ×50 to
 *    millimetres: major 50 mm, minor 10 mm, a 90° sweep about the z axis, resting on z = 0. Exact.
 *  - "vase": paper Fig. 18, a revolved thick wall 60 mm high whose radii and
 *    wall thickness vary along its length (u across the wall, v around — a
 *    periodic direction — and w along the height). Exact revolution.
 * AMP_ERR_ARG for an unknown name (the message lists the names).
 */
amp_status amp_trivariate_model(const char *name, const amp_allocator *a, amp_spline *out, amp_error *err);

/** NULL-terminated list of the built-in trivariate names. */
const char *const *amp_trivariate_model_names(void);

/** Volume of a trivariate (mm^3): Gauss–Legendre quadrature of |det J| (3 points per direction per cell of a
 * 12^3 grid). Pure function; 0 where evaluation fails, and for anything but a trivariate with control points. */
double amp_trivariate_volume(const amp_spline *v);

#ifdef __cplusplus
}
#endif
#endif
