/*
 * ampath/polygon.h — planar polygons with holes: orientation, area,
 * point-in-polygon, convex hull, islands and the inward (Minkowski) offset.
 *
 * Used by the layer slicer and the continuous tool-path framework of
 * [P2 §2.2] (steps 1, 2 and 5).
 *
 * A ring is a closed polygon stored WITHOUT repeating its first vertex.
 * An amp_polyset holds rings in one shared point array; after
 * amp_polyset_organize() the rings are grouped in islands: each island is one
 * outer ring (counter-clockwise, positive area) followed by its holes
 * (clockwise, negative area), and ring.island gives the island index.
 * Everything is plain data; functions on distinct objects are thread-safe.
 */
#ifndef AMPATH_POLYGON_H
#define AMPATH_POLYGON_H

#include <stddef.h>

#include "alloc.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A point or vector of the plane. */
typedef struct amp_vec2 {
    double x, y;
} amp_vec2;

static inline amp_vec2 amp_v2(double x, double y) { amp_vec2 r; r.x = x; r.y = y; return r; }
/** z-component of the cross product (b - a) x (c - a): > 0 when a, b, c turn left. */
static inline double amp_v2_orient(amp_vec2 a, amp_vec2 b, amp_vec2 c)
{
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

/** One closed ring: @p n points starting at amp_polyset.pts[first]. */
typedef struct amp_ring {
    size_t first, n;
    long island; /**< island index after amp_polyset_organize(), -1 before */
    int hole;    /**< 1 for a hole (clockwise) after amp_polyset_organize() */
} amp_ring;

/** A set of rings sharing one point array. */
typedef struct amp_polyset {
    const amp_allocator *alloc;
    amp_vec2 *pts;
    size_t npts, cap_pts;
    amp_ring *rings;
    size_t nrings, cap_rings;
    size_t nislands; /**< set by amp_polyset_organize() */
} amp_polyset;

/** Initialise an empty set allocating with @p a (NULL = default). */
void amp_polyset_init(amp_polyset *ps, const amp_allocator *a);
/** Free the memory; the set is empty and reusable afterwards. NULL accepted. */
void amp_polyset_free(amp_polyset *ps);
/** Remove all rings, keeping the memory. */
void amp_polyset_clear(amp_polyset *ps);
/**
 * Append a ring of @p n points (copied). A repeated closing point is dropped,
 * as are consecutive duplicates (equal within 1e-12 relative); rings left with fewer than 3 points are
 * silently skipped. AMP_ERR_ARG on non-finite points, AMP_ERR_NOMEM.
 */
amp_status amp_polyset_add(amp_polyset *ps, const amp_vec2 *p, size_t n, amp_error *err);
/** Points of ring @p i. */
static inline const amp_vec2 *amp_polyset_ring(const amp_polyset *ps, size_t i) { return ps->pts + ps->rings[i].first; }

/**
 * Group rings into islands by nesting depth (even depth = outer boundary,
 * odd = hole of the smallest ring containing it), orient outer rings
 * counter-clockwise and holes clockwise, and reorder rings so that each
 * island is its outer ring followed by its holes. Rings must not cross each
 * other (touching is tolerated). AMP_ERR_NOMEM only.
 */
amp_status amp_polyset_organize(amp_polyset *ps, amp_error *err);

/**
 * Resolve rings that overlap by the nonzero rule, before
 * amp_polyset_organize(): the region becomes the points around which the
 * rings wind a positive number of times (counter-clockwise counts +1; when
 * the rings' signed areas sum to less than zero, every ring counts reversed,
 * as for a mesh facing inward). Rings that cross, share a stretch of edge,
 * touch at a vertex, or lie inside a ring of the same orientation (parts
 * exported as overlapping bodies) are replaced by the boundary of that
 * region: disjoint rings, solid on their left, not yet organised. A set whose
 * rings meet nowhere and each separate solid from empty is left untouched
 * (byte for byte) and *changed (optional) stays 0; otherwise *changed = 1.
 * About n log n time (a sweep over x, rows of edges for the winding numbers). AMP_ERR_ARG for a
 * NULL set, AMP_ERR_NOMEM (the set is then unchanged).
 */
amp_status amp_polyset_union(amp_polyset *ps, int *changed, amp_error *err);

/**
 * Copy island @p k of an organised set @p P (its outer ring and holes) into
 * @p out (cleared first), organised. AMP_ERR_NOMEM.
 */
amp_status amp_polyset_island(const amp_polyset *P, size_t k, amp_polyset *out, amp_error *err);

/** Signed area of a ring (shoelace): > 0 counter-clockwise. */
double amp_ring_area(const amp_vec2 *p, size_t n);
/** Reverse a ring in place. */
void amp_ring_reverse(amp_vec2 *p, size_t n);
/**
 * Point in ring: 1 inside, 0 outside, -1 on the boundary (within @p tol).
 * Crossing-number test with the half-open rule, so a point is never counted
 * twice at a vertex.
 */
int amp_ring_contains(const amp_vec2 *p, size_t n, amp_vec2 q, double tol);
/** Point in the region of a set (even-odd over all rings): 1 inside, 0 outside, -1 on a boundary. */
int amp_polyset_contains(const amp_polyset *ps, amp_vec2 q, double tol);
/** Sum of signed ring areas (islands minus holes once organised). */
double amp_polyset_area(const amp_polyset *ps);
/** Distance from @p q to the nearest ring edge of the set (HUGE_VAL when empty). */
double amp_polyset_boundary_dist(const amp_polyset *ps, amp_vec2 q);

/**
 * Row index of a polygon set for many point queries (a full ring scan per
 * sample point made the skin and overhang tests quadratic). Segments are listed
 * in horizontal rows (about 4 sqrt(n) of them); a query scans one row, or
 * rows outward until the nearest segment is found. The set @p P is
 * borrowed and must outlive the index; memory through P's allocator.
 */
typedef struct amp_polyindex {
    const amp_polyset *P;
    double y0, h;
    long nrow;
    size_t *start, *item; /* segment ids of row k: item[start[k] .. start[k + 1]) */
    amp_vec2 *a, *b;      /* segment id -> its ends */
} amp_polyindex;
/** Build the index of @p P (an empty set gives an empty index). AMP_ERR_NOMEM. */
amp_status amp_polyindex_build(amp_polyindex *ix, const amp_polyset *P, amp_error *err);
/** Release the index (not the set); safe on a zeroed or freed index. */
void amp_polyindex_free(amp_polyindex *ix);
/** As amp_polyset_contains(P, q, 0): 1 inside, 0 outside, -1 on an edge (even-odd, half-open rule). */
int amp_polyindex_contains(const amp_polyindex *ix, amp_vec2 q);
/** Winding number of the rings of P around q: counter-clockwise rings count +1, clockwise -1 (the nonzero rule). */
int amp_polyindex_winding(const amp_polyindex *ix, amp_vec2 q);
/** As amp_polyset_boundary_dist(P, q): distance to the nearest edge (HUGE_VAL when empty). */
double amp_polyindex_dist(const amp_polyindex *ix, amp_vec2 q);
/** min(@p cap, amp_polyindex_dist(ix, q)): the rows are scanned outward only up to @p cap (a point far from
 *  the set costs a few rows, not all of them between it and the set). */
double amp_polyindex_dist_within(const amp_polyindex *ix, amp_vec2 q, double cap);

/**
 * Convex hull of @p n points (Andrew's monotone chain, exact orientation
 * signs for doubles up to rounding). Writes the hull counter-clockwise,
 * without collinear points, to @p out (caller-allocated, room for @p n
 * points) and its size to *nout. Fewer than 3 distinct points give *nout < 3.
 * Allocates scratch through @p a. AMP_ERR_NOMEM.
 */
amp_status amp_convex_hull(const amp_vec2 *pts, size_t n, const amp_allocator *a, amp_vec2 *out, size_t *nout,
                           amp_error *err);

/**
 * Inward Minkowski offset (erosion by a disc of radius @p r > 0) of the
 * region bounded by the rings of @p in (even-odd rule): the set of points of
 * the region at distance >= r from its boundary (§2.2 step 5, R̃_j).
 *
 * Method (see docs/slice.md): rings are first freed of vertices closer than
 * r/10^4 to the chord of their neighbours (float noise); every ring is offset to its interior side,
 * with circular arcs (circumscribed polylines, @p arc_tol maximal sagitta,
 * 0 = r/100) around reflex vertices; all raw offset segments are split at
 * their mutual intersections (each intersection computed once and shared by
 * both segments, so pieces are joined by topology, not float equality); a
 * piece is kept when its midpoint lies inside the region at distance >= r
 * (1e-9 relative tolerance) from the boundary; kept pieces are stitched into
 * closed rings. Topology changes come out naturally: a neck narrower than 2r
 * splits an island, small islands vanish, holes grow and may merge.
 * The result in @p out (cleared first) is organised (islands, CCW outers, CW
 * holes). AMP_ERR_ARG for r <= 0, AMP_ERR_NOMEM.
 */
amp_status amp_polyset_inset(const amp_polyset *in, double r, double arc_tol, amp_polyset *out, amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
