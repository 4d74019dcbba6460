/*
 * ampath/order.h — accessibility of print paths ([P1 §5.1]): the print-head
 * cone, fragments (Def. 5.3), the below relation (Def. 5.1, Figs. 9-10) and
 * the ordering of Algorithm 2 (OrderCurves) with its improvements.
 *
 * Geometry (docs/interfaces.md §2): the head is a downward cone whose tip is z_offs above
 * the point being printed, with half-angle theta from the vertical (+z) axis.
 * A point q lies inside the head printing p when
 *     (q.z - p.z - z_offs) - cot(theta) * |q.xy - p.xy| > 0.
 * Fragment A is below fragment B (A < B, edge A -> B of the accessibility
 * graph, Def. 5.2) when the head printing any point of A contains a point of
 * B: A must then be printed before B.
 *
 * Thread-safety: every function here is reentrant; the read-only objects
 * (amp_fragments, amp_below_graph) may be shared between threads.
 */
#ifndef AMPATH_ORDER_H
#define AMPATH_ORDER_H

#include <stddef.h>
#include <stdint.h>

#include "alloc.h"
#include "head.h"
#include "paths.h"
#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The print-head cone (amp_head, defaults, validation, clearance): head.h. */

/** One fragment (Def. 5.3): a piece of a path shorter than z_offs. */
typedef struct amp_fragment {
    uint32_t path;   /**< index of the source path in the pathset */
    uint32_t nin;    /**< number of original vertices strictly inside the fragment */
    size_t vfirst;   /**< global index (amp_pathset.verts) of the first inside vertex */
    amp_vec3 p0, p1; /**< start and end point (cut points or path ends) */
    double r0, r1;   /**< deposition radius interpolated at p0 and p1 */
    amp_box3 box;    /**< bounding box of the fragment's points */
} amp_fragment;

/**
 * Fragments of a whole pathset. Fragments of one path are consecutive and in
 * path order: path i owns [first[i], first[i+1]); fragment k+1 starts where
 * fragment k ends. Paths without vertices own no fragment; a one-vertex path
 * owns one point fragment.
 */
typedef struct amp_fragments {
    const amp_allocator *alloc;
    const amp_pathset *ps; /**< borrowed: must outlive the fragments */
    amp_fragment *frag;
    size_t n;
    size_t *first; /**< npaths + 1 entries */
    size_t npaths;
    double max_len; /**< every fragment is shorter than this */
} amp_fragments;

/**
 * Cut every path of @p ps into equal pieces shorter than @p max_len (mm, > 0;
 * the ordering uses z_offs, which makes Lemma 5.1 hold). Keeps a pointer to
 * @p ps. Errors: AMP_ERR_ARG (bad max_len, NULL), AMP_ERR_LIMIT (more than
 * 2^32-1 paths or fragments), AMP_ERR_NOMEM. Free with amp_fragments_free().
 */
amp_status amp_fragments_build(amp_fragments *fs, const amp_pathset *ps, double max_len, const amp_allocator *a,
                               amp_error *err);
/** Free the arrays. NULL accepted. */
void amp_fragments_free(amp_fragments *fs);

/** Number of points of fragment @p f (nin + 2; the two ends coincide for a point fragment). */
static inline size_t amp_fragment_npoints(const amp_fragment *f) { return (size_t)f->nin + 2; }
/** Point @p k (0 .. nin+1) of fragment @p f. */
static inline amp_vec3 amp_fragment_point(const amp_fragments *fs, const amp_fragment *f, size_t k)
{
    return k == 0 ? f->p0 : (k <= f->nin ? fs->ps->verts[f->vfirst + k - 1].p : f->p1);
}

/** Non-zero when fragment @p a is below fragment @p b (Def. 5.1, exact). a == b gives 0 (Lemma 5.1). */
int amp_fragment_below(const amp_fragments *fs, const amp_head *h, size_t a, size_t b);

/**
 * The accessibility graph over fragments (Def. 5.2) in compressed rows:
 * the successors of fragment i (fragments that i is below) are
 * to[row[i] .. row[i+1]-1], in increasing order.
 */
typedef struct amp_below_graph {
    const amp_allocator *alloc;
    size_t n, nedges;
    size_t *row; /**< n + 1 entries */
    uint32_t *to;
} amp_below_graph;

/**
 * Build the below graph of @p fs with a bounding volume hierarchy over the
 * fragment boxes (O(n log n + E) for E edges; OpenMP over fragments). The
 * relation of a wide cone is dense (every fragment is below most fragments
 * far above it), so the graph is refused with AMP_ERR_LIMIT when it would
 * hold more than @p max_edges edges; Algorithm 2 (amp_order) never needs it.
 */
amp_status amp_below_graph_build(amp_below_graph *g, const amp_fragments *fs, const amp_head *h, size_t max_edges,
                                 amp_error *err);
/** Free the graph. NULL accepted. */
void amp_below_graph_free(amp_below_graph *g);

/** Default amp_order_opts.travel_z_weight. The generic printer's Z is 12x slower than its XY travel, but
 *  weighting Z that much sends the head far in XY to stay at one height: 3 gave the shortest travel time on
 *  the demo helix (docs/order.md, step 6). */
#define AMP_ORDER_TRAVEL_Z_WEIGHT 3.0

/** Options of amp_order(). Initialise with amp_order_opts_default(). */
typedef struct amp_order_opts {
    amp_head head;
    int improve;      /**< 0: plain greedy Algorithm 2; 1: continuation, look-ahead and merging (default) */
    size_t lookahead; /**< candidate runs simulated per step when improving (default 4) */
    size_t merge_window; /**< most fragments between two sub-curves considered for a merge (default 2000) */
    /** 1 (default): when improving, among runs that are equally good for Algorithm 2 (as few new cuts, as
     *  long after continuation) start the one nearest to where the head stands, and let the nearest run with
     *  as few cuts compete with the heap's best; 0: ties go to the lower run, then curve order. */
    int nearest;
    /** When improving (default AMP_ORDER_TRAVEL_Z_WEIGHT): once the sub-curves are fixed, print them in the
     *  admissible order (each after every sub-curve below it, §5.1) that always takes next the sub-curve whose
     *  start (either end when it may be reversed) is cheapest to reach, a mm of Z counting this many mm of XY;
     *  sub-curves that then continue each other are joined and the merging runs again (then one more
     *  re-sequencing). Never more cuts than without it, shorter travel. 0: off. */
    double travel_z_weight;
    /** Optional progress report, called from the calling thread with the fraction of fragments
     *  printed so far (0..1), a few hundred times per run at most; NULL (default) for none. */
    void (*progress)(void *user, double fraction);
    void *progress_user; /**< passed to progress */
} amp_order_opts;

void amp_order_opts_default(amp_order_opts *o);

/** Figures of one ordering. */
typedef struct amp_order_stats {
    size_t paths_in;      /**< input paths with at least one vertex */
    size_t fragments;     /**< fragments (Def. 5.3) */
    size_t pieces;        /**< output paths */
    size_t subdivisions;  /**< pieces - paths_in: cuts added to make the set printable */
    size_t steps;         /**< iterations of Algorithm 2's loop */
    size_t extended;      /**< fragments appended by continuing the curve just printed */
    size_t merges;        /**< sub-curves merged by the bottom-up pass */
    size_t queries;       /**< below-queries answered by the hierarchy */
} amp_order_stats;

/**
 * Algorithm 2 (OrderCurves): fragment the paths of @p in, then repeatedly
 * print a run of consecutive printable fragments (nothing unprinted below
 * them) of one curve chosen by GetBest (the fewest new cuts, then the
 * longest run). With o->improve the chosen run is continued along its curve
 * while the next fragment is printable, the candidate and direction are
 * chosen by look-ahead, and adjacent sub-curves are merged afterwards when
 * the merged accessibility graph stays acyclic (§5.1, bottom-up).
 * The fragment graph is acyclic by Lemma 5.1, so the loop always ends; an
 * empty printable set would be a numerical failure, reported as
 * AMP_ERR_GEOMETRY rather than looping.
 * Appends the ordered sub-curves to @p out (roles kept, cut points inserted
 * with interpolated radii). @p o NULL = defaults; @p st may be NULL.
 * Errors: AMP_ERR_RANGE (bad head), AMP_ERR_LIMIT, AMP_ERR_NOMEM.
 */
amp_status amp_order(const amp_pathset *in, const amp_order_opts *o, amp_pathset *out, amp_order_stats *st,
                     amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
