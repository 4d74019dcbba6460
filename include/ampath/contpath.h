/*
 * ampath/contpath.h — continuous tool paths per layer from the Euler
 * transformed lattice ([P2 §2.2] steps 2-6, [P2 §4]),
 * and an independent checker of the strokes.
 *
 * Per layer and per island P of the layer (amp_contpath_layers):
 *   - perimeter loops: the rings of the inset of P by r (outer and holes);
 *   - the infill regions R̃_j = parts of the inset of P by 3r (inside the
 *     perimeter bead and one bead radius from it): clip the 1-skeleton of K̂
 *     (step 5; the dense skin lattice near a top or bottom surface), join the
 *     free ends of each ring of R̃_j in alternating pairs by ring paths (of
 *     the two pairings the one that connects the pieces, then the longer),
 *     and trace one closed tour without crossovers per component (§4: cycle
 *     tree over the boundary cycles of the faces by depth, Hierholzer's edge
 *     choice, q = 2 / q > 2 splices; see lib/contpath_tour.c);
 *   - step 6: support corners from the unprinted ring stretches to the
 *     perimeter (Fig. 5), or (Remark 2.1) the stretches as support paths;
 *   - all spliced into one closed stroke by parallel connectors (o->join).
 * amp_contpath_region() is the paper's step 5 + §4 for one region alone:
 * there, components still apart are joined by a ring path printed once and
 * run back as a pseudo edge (Fig. 6), and with o->pseudo_edges patch
 * stretches of thin boundary cells become pseudo edges (Figs. 7, 8).
 * K is a lattice covering the convex hull of all layers (steps 2-3) and K̂ its
 * Euler transformation with mitered offset δ (default r): every vertex of K̂
 * inside R̃ has even degree because the rim cells of K lie outside R̃.
 * A pseudo edge is a stretch of a stroke that the nozzle runs without
 * extruding: its two end vertices carry radius 0 in the path, and where
 * printing and travel meet the vertex is written twice (once with each
 * radius), so that no segment mixes the two (the G-code writer extrudes by
 * the mean radius of a segment, docs/interfaces.md §5).
 * Functions are reentrant; inputs are only read.
 */
#ifndef AMPATH_CONTPATH_H
#define AMPATH_CONTPATH_H

#include <stddef.h>

#include "complex2.h"
#include "paths.h"
#include "polygon.h"
#include "slice.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

struct amp_stroke_report; /* check.h: amp_stroke_report */

/**
 * A stroke verifier, exactly the signature of check.h's amp_check_path_stroke:
 * AMP_OK when path @p i of @p ps passes (in @p region, tolerance @p tol),
 * another status when it fails. @p rep and @p err may be NULL. The builder
 * calls it through amp_contpath_opts.verify_stroke and never links a checker
 * itself: whoever fills the options decides whether the safety net is on.
 */
typedef amp_status (*amp_contpath_verify_fn)(const amp_pathset *ps, size_t i, const amp_polyset *region, double tol,
                                             struct amp_stroke_report *rep, amp_error *err);

/** How §4's tour is built from the patched complex of a region. */
typedef enum amp_tour_method {
    AMP_TOUR_CYCLE_TREE = 0, /**< the paper: boundary cycles by level (Hierholzer), cycle tree, q = 2 / q > 2 splices */
    AMP_TOUR_MERGE = 1       /**< ends paired with their angular neighbour, curves merged wherever they touch */
} amp_tour_method;

typedef struct amp_contpath_opts {
    double radius;         /**< extruder (deposition) radius r > 0, mm */
    double cell;           /**< lattice cell size of K (<= 0: 10 r) */
    amp_grid_kind grid;    /**< lattice of K */
    double offset;         /**< mitered offset δ of K̂ (<= 0: r) */
    int perimeters;        /**< 1: print the perimeter loop(s) of each island */
    int support_stretches; /**< 1: print the unprinted ring stretches as support paths (Remark 2.1) */
    int support_corners;   /**< 1 (default): step 6, corners from the unprinted ring stretches to the perimeter */
    int pseudo_edges;      /**< 1: patch stretches closer than 2r to a lattice piece of their thin boundary
                                cell become pseudo edges (Figs. 7, 8); 0: all patches printed */
    amp_tour_method tour;  /**< §4 construction (default AMP_TOUR_CYCLE_TREE) */
    double skin_bottom;    /**< mm of solid layers over every downward-facing surface (default 0.8; 0: none) */
    double skin_top;       /**< mm of solid layers under every upward-facing surface (default 0.8; 0: none) */
    double skin_cell;      /**< strip width of the solid skins (<= 0: 4 r, where the beads of K̂ lie side by side) */
    int join;              /**< 1: splice each island's perimeter loops and region strokes into one closed
                                stroke (one extrusion start per island); 0: separate closed paths */
    amp_contpath_verify_fn verify_stroke; /**< NULL (default): no retry. Else the safety net of the skin bands:
                                an island printed with skin bands whose paths this verifier rejects (called
                                with tol 1e-6, rep and err NULL) is printed again with its skin regions whole
                                (counted in band_retries); every island it then still rejects is printed
                                again with its infill region moved in, then out, by r/20 (shift_retries), so it
                                is called on every island. Set it to amp_check_path_stroke (check.h) for the
                                behaviour of the ampath tool. AMP_ERR_NOMEM from it stops the run with that
                                error; any other status rejects the path. With OpenMP it is called from the threads that
                                make the islands: it must be thread-safe (amp_check_path_stroke is). */
    /** Optional progress report of amp_contpath_layers() (fraction 0..1 of the layers, from the calling
     *  thread, a few hundred times at most). */
    void (*progress)(void *user, double fraction);
    void *progress_user;
    int overlap_cap;       /**< 1 (default): an island whose beads hold more plastic than its slab (section
                                area x bead height) has its beads narrowed to it (stats.narrowed_islands);
                                0: beads as built. (last: python/ampath/_lib.py mirrors this struct) */
} amp_contpath_opts;

/**
 * Fill @p o with the defaults for radius @p r: square grid, cell 10 r,
 * offset r, perimeters on, joined strokes (one start per island), thin-cell
 * patches printed (pseudo_edges 0: a travel inside a stroke would be one
 * more extrusion start in the G-code; the overlap it avoids is at most a
 * bead's width over a short stretch).
 */
void amp_contpath_opts_default(amp_contpath_opts *o, double r);

typedef struct amp_contpath_stats {
    size_t layers;
    size_t empty_layers;     /**< layers with section area that received no path: only slivers thinner than r/16
                                  and specks under r/4 across (a sphere's top cut around a hole) */
    size_t islands;          /**< islands of the sections (outer ring with its holes) that received paths */
    size_t thin_islands;     /**< islands narrower than 2r printed by a perimeter of a smaller inset */
    size_t dropped_islands;  /**< islands narrower than r/32: nothing printed */
    size_t island_strokes;   /**< object strokes written for the islands (= islands when joined) */
    size_t specks;           /**< closed loops under r/4 across left out when joining (inside other beads) */
    size_t regions;          /**< infill regions R̃_j that received a stroke */
    size_t skin_regions;     /**< of which solid (the dense lattice): a point of them has no part within the
                                  skin thickness above or below */
    size_t strokes;          /**< infill strokes (one per region when all goes well) */
    size_t multi_stroke;     /**< regions that needed more than one stroke */
    size_t perimeter_loops;  /**< perimeter paths */
    size_t support_paths;    /**< Remark 2.1 stretches printed */
    size_t travel_moves;     /**< moves between consecutive paths */
    size_t free_ends;        /**< free-edge end points patched (Σ m) */
    size_t odd_vertices;     /**< odd vertices left after patching (0 expected) */
    size_t cycles;           /**< boundary cycles of the cycle trees (§4.1), over all regions */
    size_t tree_levels;      /**< deepest cycle tree (levels) */
    size_t tour_fallbacks;   /**< regions whose faces were not 2-coloured: AMP_TOUR_MERGE used instead */
    size_t joins;            /**< components joined by a patch printed once and run back as a pseudo edge (Fig. 6) */
    double printed_length;   /**< mm, all object paths, pseudo edges excluded */
    double infill_length;    /**< mm, strokes only, pseudo edges excluded */
    double pseudo_length;    /**< mm, pseudo edges inside the strokes (travel without extrusion) */
    double travel_length;    /**< mm, straight moves between paths (3-D) */
    double support_length;   /**< mm, Remark 2.1 stretches printed */
    double unprinted_length; /**< mm, ring stretches of R̃ left unprinted by the lattice and its patches */
    size_t support_corners;  /**< step 6 corners built into the perimeter loops */
    size_t corners_left_out; /**< corners that would cross a path, overlap a neighbour, or find no perimeter
                                  within 3r and no other bead touching their stretch */
    size_t neck_islands;     /**< islands with infill whose inset by r splits at a neck narrower than a bead:
                                  perimeter (and infill) at the largest smaller offset that holds them together
                                  (last: bindings that mirror this struct, python/ampath/_lib.py, append it) */
    size_t skin_bands;       /**< skin regions printed solid only in a band along their boundary (the
                                  uncovered part), the rest sparse one bead further in */
    size_t band_retries;     /**< islands printed again with whole skin regions (their banded paths failed
                                  the check) */
    size_t corners_touched;  /**< corner centres with no perimeter within 3r whose stretch another bead
                                  touches (a centre line within 2r: the sparse core's ring beside a skin
                                  band); no corner is needed there */
    size_t narrowed_islands; /**< islands whose beads overlapped by more than their slab (section area x
                                  h): narrowed by one factor of their cross-section (opts.overlap_cap) */
    double narrowed_volume;  /**< mm^3 of bead taken off by that narrowing */
    size_t shift_retries;    /**< islands the verifier still rejected, printed again with their infill region
                                  moved in or out by r/20 (a degenerate touch of its ring and the lattice) */
} amp_contpath_stats;

/**
 * Steps 2-4: convex hull of all layers' rings, lattice K of it, K̂ = T(K)
 * into @p khat (emptied first). AMP_ERR_ARG (bad options), AMP_ERR_GEOMETRY
 * (no polygon), AMP_ERR_NOMEM.
 */
amp_status amp_contpath_complex(const amp_slices *sl, const amp_contpath_opts *o, amp_cx2 *khat, amp_error *err);

/**
 * Steps 5 + §4 for one connected region @p region (organised, one island:
 * outer ring and holes): appends the stroke over @p khat clipped to the
 * region (one closed object path; more only if components could not be
 * joined, counted in st->multi_stroke) at height @p z with radius o->radius
 * on printed stretches and 0 on pseudo edges (joins run back, thin cells),
 * and the Remark 2.1 stretches when asked. Updates @p st. AMP_ERR_NOMEM.
 */
amp_status amp_contpath_region(const amp_cx2 *khat, const amp_polyset *region, double z,
                               const amp_contpath_opts *o, amp_pathset *out, amp_contpath_stats *st,
                               amp_error *err);

/**
 * All layers: per island (in nearest-first order) the perimeter loop(s) at
 * r and one stroke per infill region, spliced into one closed stroke when
 * o->join (see contpath_join.c), at each layer's printing height z_print,
 * every path a planar bead of the layer's thickness (amp_path.h). A closed
 * stroke starts at its vertex nearest to where the previous one ended. An
 * island narrower than 2r (no inset by r) gets the perimeter of the inset
 * by r/2, r/4, ... r/32 instead (counted in thin_islands). @p out is
 * appended to. Built with OpenMP, the islands of up to 256 of them at a time
 * are made on the OpenMP threads when @p out uses the default allocator (a
 * caller's allocator is only called from the calling thread); the output is
 * the same whatever the thread count. Errors: AMP_ERR_ARG (NULL @p sl, @p o
 * or @p out, a radius or cell that is not positive), AMP_ERR_LIMIT (a lattice
 * too large), AMP_ERR_GEOMETRY (no layer polygon), AMP_ERR_NOMEM — also when
 * o->verify_stroke reports it (an island is never made again for a verifier
 * out of memory); on an error @p out holds the layers finished before it.
 */
amp_status amp_contpath_layers(const amp_slices *sl, const amp_contpath_opts *o, amp_pathset *out,
                               amp_contpath_stats *st, amp_error *err);

/* The independent stroke checker (amp_check_stroke, amp_check_path_stroke): check.h; it is not linked by
 * the builder (see amp_contpath_opts.verify_stroke). */

#ifdef __cplusplus
}
#endif
#endif
