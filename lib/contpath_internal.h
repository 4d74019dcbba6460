/*
 * contpath_internal.h — shared state of the continuous-path modules
 * (lib/contpath*.c, [P2 §2.2] steps 5-6, [P2 §4]).
 * Not installed; functions follow the library's rules (caller's allocator,
 * amp_status results, no global state).
 */
#ifndef AMPATH_CONTPATH_INTERNAL_H
#define AMPATH_CONTPATH_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "ampath/contpath.h"
#include "uf.h"

#define NONE ((size_t)-1)

/* The offset from q to the point of segment a-b nearest to it (that point at parameter *t of the segment,
 * t NULL: not wanted): the one measure of the nearest-segment searches of the continuous paths (clipping,
 * joining, support corners), so that they agree to the last bit. */
static inline amp_vec2 amp_cp_seg_offset(amp_vec2 q, amp_vec2 a, amp_vec2 b, double *t)
{
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy;
    double u = l2 > 0 ? amp_dmin(amp_dmax(((q.x - a.x) * dx + (q.y - a.y) * dy) / l2, 0.0), 1.0) : 0;
    if (t)
        *t = u;
    return amp_v2(a.x + u * dx - q.x, a.y + u * dy - q.y);
}

/* A free end: the node where a K̂ edge leaves the region, on ring `ring` at
 * position `pos` (segment index + parameter). */
typedef struct amp_cp_fend {
    size_t node, ring, comp;
    double pos; /* segment index + parameter along the ring */
} amp_cp_fend;

typedef struct amp_cp_graph {
    const amp_allocator *al;
    amp_vec2 *v;
    size_t nv, cap_v;
    size_t *edge_u, *edge_v; /* edge i joins nodes edge_u[i] and edge_v[i] */
    unsigned char *edge_pseudo; /* 1: pseudo edge (travel inside the stroke, no material) */
    size_t ne, cap_edge_u, cap_edge_v, cap_edge_pseudo;
    size_t nlat; /* edges [0, nlat) are the clipped lattice pieces */
    size_t *mate; /* per node < nlatv: the other end of its last lattice edge (NONE: none) */
    size_t nlatv;
    amp_cp_fend *fends; /* free ends: lattice nodes of degree 1 on a ring */
    size_t nfends, cap_fends;
    /* scratch of amp_cp_patch_points(): the patch polyline and its segment kinds */
    amp_vec2 *pp;
    unsigned char *pf;
    size_t npp, cap_pp, cap_pf;
    double *iv; /* bad intervals (lo, hi) of one segment */
    size_t cap_iv;
    amp_vec2 *cand; /* segments near one patch, 2 points each */
    size_t cap_cand;
} amp_cp_graph;

/* The patches of a region: patch k runs along a ring from node a[k] to node
 * b[k] through the raw points pts[p0[k] .. p0[k] + np[k] - 1] (ends included). */
typedef struct amp_cp_patchset {
    size_t *a, *b, *p0, *np; /* room for one patch per gap (at most the number of free ends) */
    unsigned char *join;     /* 1: joins two components (printed once, run back as a pseudo edge) */
    double *box;             /* 4 per patch: bounding box */
    size_t n;
    amp_vec2 *pts;
    size_t npts, cap_pts;
} amp_cp_patchset;

/* ---- graph (contpath.c) ---- */
amp_status amp_cp_vert(amp_cp_graph *g, amp_vec2 p, size_t *id);
/** Edge a-b (none when a == b); pseudo: travel inside the stroke. */
amp_status amp_cp_edge(amp_cp_graph *g, size_t a, size_t b, int pseudo);
void amp_cp_graph_free(amp_cp_graph *g);
/** Unique undirected 1-cells of K̂ as vertex pairs (lo << 32 | hi). */
amp_status amp_cp_khat_edges(const amp_cx2 *k, const amp_allocator *al, uint64_t **out, size_t *n);
/** Printed length of path i (pseudo segments, radius 0 at both ends, excluded). */
double amp_cp_printed_len(const amp_pathset *ps, size_t i);
/**
 * Steps 5 + §4 for one region with a prepared K̂ edge list. @p hub: a
 * perimeter loop will be spliced with the region's strokes (contpath_join.c),
 * so components are left apart for it instead of Fig. 6's doubled paths.
 * @p bare (optional) receives the ring stretches left unprinted (step 6),
 * one open polyline each (a whole bare ring closed), radius 0.
 */
amp_status amp_cp_region_run(const amp_cx2 *khat, const uint64_t *ke, size_t nke, const amp_polyset *R, double z,
                             const amp_contpath_opts *o, int hub, amp_pathset *out, amp_pathset *bare,
                             amp_contpath_stats *st, amp_error *err);

/* ---- step 5, clipping (contpath_clip.c) ---- */
amp_status amp_cp_clip(const amp_cx2 *k, const uint64_t *ke, size_t nke, const amp_polyset *R, amp_cp_graph *g,
                       amp_error *err);

/* ---- step 5, patching; Figs. 6-8 (contpath_patch.c) ---- */
int amp_cp_cmp_fend(const void *a, const void *b);
double amp_cp_ring_len(const amp_polyset *R, size_t r, double p0, double p1);
amp_status amp_cp_pp_push(amp_cp_graph *g, amp_vec2 x, unsigned char pseudo);
amp_status amp_cp_ring_walk(const amp_polyset *R, const amp_cp_fend *fi, const amp_cp_fend *fj, amp_cp_graph *g,
                            amp_pathset *ps, double z, double rad, amp_error *err);
amp_status amp_cp_ring_support(amp_cp_graph *g, const amp_polyset *R, const amp_cp_fend *fi, const amp_cp_fend *fj,
                               amp_pathset *ps, double z, double rad, amp_error *err);
amp_status amp_cp_patchset_alloc(const amp_allocator *al, amp_cp_patchset *P, size_t room);
void amp_cp_patchset_free(const amp_allocator *al, amp_cp_patchset *P);
amp_status amp_cp_patch_add(amp_cp_graph *g, amp_cp_patchset *P, const amp_polyset *R, const amp_cp_fend *fi,
                            const amp_cp_fend *fj, int join, amp_error *err);
amp_status amp_cp_patch_points(amp_cp_graph *g, const amp_cp_patchset *P, size_t self, double D, amp_error *err);
amp_status amp_cp_add_chain(amp_cp_graph *g, size_t a, size_t b, int all_pseudo, double *pseudo_len);

/* ---- §4, the tour (contpath_tour.c) ---- */
typedef struct amp_cp_tour_info {
    size_t ntours;   /* closed (or open) strokes written */
    size_t nodd;     /* odd vertices met (0 expected) */
    size_t cycles;   /* boundary cycles of the cycle tree */
    size_t levels;   /* depth of the cycle tree */
    int fallback;    /* 1: faces not 2-coloured, the angular-neighbour merging was used */
} amp_cp_tour_info;
/**
 * §4: one closed crossover-free tour per component of @p g, appended to
 * @p out (radius @p rad, 0 on pseudo edges) at height @p z; @p method
 * AMP_TOUR_CYCLE_TREE or AMP_TOUR_MERGE.
 */
amp_status amp_cp_tour(amp_cp_graph *g, double z, double rad, int method, amp_pathset *out, amp_cp_tour_info *info,
                       amp_error *err);

/* ---- solid skins (contpath_skin.c) ---- */
/**
 * 1 when a sample of region @p R of layer @p li (ring vertices, a grid of
 * spacing @p step inside) is not covered by every section within @p below
 * mm under and @p above mm over the layer (the part's ends count as
 * uncovered): the region is printed solid. @p ix: row indexes of the
 * layers' sections (one per layer; NULL: plain scans).
 */
int amp_cp_region_is_skin(const amp_slices *sl, const amp_polyindex *ix, size_t li, const amp_polyset *R, double below,
                          double above, double step);
/**
 * As amp_cp_region_is_skin, and how deep: -1 when every sample is covered,
 * else the largest distance from R's boundary of an uncovered sample plus
 * @p step (the grid spacing used), so every uncovered point of R lies within
 * that distance of its boundary (up to the sampling).
 */
double amp_cp_region_skin_depth(const amp_slices *sl, const amp_polyindex *ix, size_t li, const amp_polyset *R,
                                double below, double above, double step);

/* ---- step 6, support corners (contpath_support.c) ---- */
/* While an island is assembled, a corner's tip carries this radius (r less
 * 2^-30 r): the joiner takes no segment ending at a tip for a splice, and
 * the layer code restores r before the paths are written. */
#define AMP_CP_TOOTH_R(r) ((r) * (1.0 - 0x1p-30))
/**
 * Corners (Fig. 5) on the bare ring stretches @p bare of one island, built
 * into its perimeter loops, paths [0, nperim) of @p ps (closed, radius r).
 * Counts support_corners and corners_left_out in @p st. @p covered > 0:
 * no corner where a printed infill segment passes within that distance of
 * its centre (skins: the strips cover the ring there). AMP_ERR_NOMEM.
 */
amp_status amp_cp_support_corners(amp_pathset *ps, size_t nperim, const amp_pathset *bare, double r, double covered,
                                  amp_contpath_stats *st, amp_error *err);

/* ---- one start per island (contpath_join.c) ---- */
/**
 * Join the closed object loops among paths [first, npaths) of @p in (one
 * island's perimeters and region strokes, radius @p r) into as few closed
 * strokes as crossing-free splices inside the rings @p walls (the island's
 * section) allow, appended to @p out with bead
 * height @p h (0: none); other paths are copied. *nout: object paths
 * written; loops smaller than r/4 across are left out and counted in *nspeck.
 */
amp_status amp_cp_join_loops(const amp_pathset *in, size_t first, const amp_polyset *walls, double r, double h,
                             amp_pathset *out, size_t *nout, size_t *nspeck, amp_error *err);

#endif
