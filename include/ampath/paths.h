/*
 * ampath/paths.h — print paths with a deposition radius per vertex, and the
 * `.amp` text format (docs/interfaces.md §3).
 *
 * An amp_pathset is the in-memory form of a `.amp` file: paths in print order,
 * each a polyline whose vertices carry the material deposition radius (MDR) r.
 * It is plain data: fields may be read directly; modify it only through the
 * functions below so that the arrays stay consistent. Not thread-safe for
 * concurrent modification; concurrent readers are fine.
 */
#ifndef AMPATH_PATHS_H
#define AMPATH_PATHS_H

#include <stddef.h>
#include <stdint.h>

#include "alloc.h"
#include "io.h"
#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/** What a path is printed for. */
typedef enum amp_role {
    AMP_ROLE_OBJECT = 0, /**< part of the model */
    AMP_ROLE_SUPPORT = 1 /**< support structure, removed after printing */
} amp_role;

/** One path vertex: position (mm) and deposition radius r (mm, >= 0). */
typedef struct amp_pvert {
    amp_vec3 p;
    double r;
} amp_pvert;

/**
 * One path: @p n vertices starting at index @p first of amp_pathset.verts.
 * @p h > 0 makes it a planar bead of that height (mm): a layer of height h
 * and width 2r (the continuous tool-path pipeline); h = 0 is a round tube of
 * radius r (the volumetric paper's deposition model, [P1 §5.2]).
 */
typedef struct amp_path {
    amp_role role;
    size_t first;
    size_t n;
    double h;
} amp_path;

/** Paths in print order sharing one vertex array. */
typedef struct amp_pathset {
    const amp_allocator *alloc; /**< allocator for both arrays */
    amp_path *paths;
    size_t npaths, cap_paths;
    amp_pvert *verts;
    size_t nverts, cap_verts;
} amp_pathset;

/** Largest number of vertices accepted in one path by the reader. */
#define AMP_PATH_MAX_VERTS 100000000UL

/** Initialise an empty set that will allocate with @p a (NULL = default). */
void amp_pathset_init(amp_pathset *ps, const amp_allocator *a);
/** Free all memory; the set is empty (and reusable) afterwards. NULL accepted. */
void amp_pathset_free(amp_pathset *ps);
/** Remove all paths, keeping the memory. */
void amp_pathset_clear(amp_pathset *ps);

/**
 * Start a new, empty path with @p role at the end of the set. Following
 * amp_pathset_push() calls append to it. AMP_ERR_NOMEM leaves the set unchanged.
 */
amp_status amp_pathset_begin(amp_pathset *ps, amp_role role, amp_error *err);

/**
 * Append a vertex to the last path (AMP_ERR_STATE if there is none).
 * AMP_ERR_ARG for non-finite coordinates or a negative or non-finite radius.
 */
amp_status amp_pathset_push(amp_pathset *ps, amp_vec3 p, double r, amp_error *err);

/**
 * amp_pathset_push(), except that a point within @p tol mm of the last path's
 * last vertex does not make a new vertex (a segment of no length: a direction
 * a checker cannot take, a "crossing" of its two neighbours by rounding): the
 * two become one with the smaller radius, at the position of the earlier
 * point, or of this one when @p last says it ends the path (so that a path cut
 * from another ends exactly at the cut). A path's first vertex is never merged
 * away. Same errors as amp_pathset_push().
 */
amp_status amp_pathset_push_merged(amp_pathset *ps, amp_vec3 p, double r, double tol, int last, amp_error *err);

/** The tolerance the pipeline's stages merge vertices with (mm): a nanometre, far below a motor step. */
#define AMP_PATH_SAME_POINT 1e-6

/**
 * Make the last path a planar bead of height @p h mm (h > 0), or a tube again
 * (h = 0). AMP_ERR_STATE if there is no path, AMP_ERR_ARG for a negative or
 * non-finite @p h.
 */
amp_status amp_pathset_set_height(amp_pathset *ps, double h, amp_error *err);

/** Append a whole path (copies @p n vertices; a tube, h = 0). Same errors as begin + push. */
amp_status amp_pathset_add(amp_pathset *ps, amp_role role, const amp_pvert *v, size_t n, amp_error *err);

/** Append a copy of path @p i of @p src to @p dst (role, vertices, bead height). Same errors as
 *  amp_pathset_add(). */
amp_status amp_pathset_copy_path(amp_pathset *dst, const amp_pathset *src, size_t i, amp_error *err);

/** Append copies of all paths of @p src to @p dst (roles and bead heights kept). */
amp_status amp_pathset_append(amp_pathset *dst, const amp_pathset *src, amp_error *err);

/** Vertices of path @p i (no bounds check beyond an assert-free contract: i < npaths). */
static inline amp_pvert *amp_pathset_path_verts(const amp_pathset *ps, size_t i)
{
    /* a set of empty paths has no vertex array: NULL + 0 is undefined behaviour (found by tests/fuzz/fuzz_amp.c) */
    return ps->verts ? ps->verts + ps->paths[i].first : NULL;
}

/**
 * A sample of a path's bead: the point @p p on its centre line, the bead's
 * vertical half-extent (h/2 for a planar bead of height h, else its radius),
 * its arc position @p s (mm) along path @p path. The held-path check hands
 * runs of them to the support's pads (check.h amp_check_hold_runs,
 * support.h amp_support_opts.find_unheld).
 */
typedef struct amp_bead_sample {
    amp_vec3 p;
    double half;
    double s;
    uint32_t path;
} amp_bead_sample;

/** Receives a run of @p n consecutive samples of one path; a status other than AMP_OK stops the caller. */
typedef amp_status (*amp_bead_run_fn)(void *user, const amp_bead_sample *run, size_t n, amp_error *err);

/** Length of path @p i in mm. */
double amp_path_length(const amp_pathset *ps, size_t i);
/** Total length of all paths with @p role (role < 0: all paths). */
double amp_pathset_length(const amp_pathset *ps, int role);
/**
 * Σ A L over all segments (r = mean of the segment's end radii): the deposited
 * volume in mm³, with A = π r² for a tube and, for a planar bead of height h
 * and width w = 2r >= h, the rounded rectangle A = (w - h) h + π (h/2)²
 * (w < h: π r²). Pseudo edges (r = 0) deposit nothing.
 */
double amp_pathset_volume(const amp_pathset *ps, int role);
/** Cross-section (mm²) of a bead of radius @p r: a tube (h = 0) or a planar bead of height @p h (docs/interfaces.md §5). */
double amp_bead_area(double r, double h);
/** Bounding box of all vertices (empty box when there are none). */
amp_box3 amp_pathset_bbox(const amp_pathset *ps);

/**
 * Parse `.amp` text (docs/interfaces.md §3) of @p len bytes and append its paths to @p ps.
 * Accepts LF and CRLF, comments (`#` to end of line) anywhere, blank lines,
 * `path <role> <n>` and `path <role> <n> <h>` (planar bead height, > 0).
 * Errors (AMP_ERR_PARSE with the 1-based line in err->line): missing or wrong
 * header, unknown role, bad or missing vertex count, bad bead height, wrong number of fields,
 * non-numeric or non-finite numbers, negative radius, fewer vertices than
 * announced, lines over 4096 bytes. On error @p ps is left as it was before
 * the call. The text need not be NUL-terminated.
 */
amp_status amp_pathset_parse(amp_pathset *ps, const char *text, size_t len, amp_error *err);

/** Size bound of amp_pathset_read_file(): AMP_READ_MAX_DEFAULT (1 GiB) where size_t has 32 bits, 64 GiB where
 *  it has more. On a host `slice --continuous` of a part that fills a printer's bed writes several GB of
 *  .amp, and the next stage must read what the last one wrote; memory is the limit there, not this bound. */
#define AMP_PATHS_READ_MAX ((size_t)1 << (sizeof(size_t) > 4 ? 36 : 30))

/** amp_read_file() (at most AMP_PATHS_READ_MAX bytes) + amp_pathset_parse(); the message names the file. */
amp_status amp_pathset_read_file(amp_pathset *ps, const char *path, amp_error *err);

/**
 * amp_pathset_parse() reporting its progress: @p progress (may be NULL: then exactly amp_pathset_parse()) is
 * called from the calling thread with the fraction of the text read (0..1), at most 64 times. The same paths,
 * errors and messages; a text over a megabyte is read in chunks even on one thread (their counting costs
 * about a tenth of the read).
 */
amp_status amp_pathset_parse_progress(amp_pathset *ps, const char *text, size_t len,
                                      void (*progress)(void *user, double fraction), void *user, amp_error *err);

/** amp_pathset_read_file() reporting the parse's progress as amp_pathset_parse_progress() does. */
amp_status amp_pathset_read_file_progress(amp_pathset *ps, const char *path,
                                          void (*progress)(void *user, double fraction), void *user,
                                          amp_error *err);

/**
 * Write @p ps as `.amp` text through @p sink (`path <role> <n> [<h>]`, h
 * only for planar beads). Coordinates are written with 10 significant digits (sub-micron for parts up to 1 m). @p comment, if not
 * NULL, is written as `# ` lines after the header (newlines allowed).
 */
amp_status amp_pathset_write(const amp_pathset *ps, const char *comment, amp_sink_fn sink, void *user, amp_error *err);

/** Write to a file, replaced atomically through amp_out (io.h: a unique temporary beside it, renamed over it;
 * on any failure the old file is left intact). AMP_ERR_IO with the system's reason. */
amp_status amp_pathset_write_file(const amp_pathset *ps, const char *path, const char *comment, amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
