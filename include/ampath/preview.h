/*
 * ampath/preview.h — pictures of path sets (docs/interfaces.md §4 `ampath preview`): an
 * isometric view and a top view side by side, paths drawn as tubes whose
 * width follows the deposition radius, coloured by print order (support in
 * grey), with a legend; height = width / 2 + 110 pixels.
 *
 * PNG is rasterised here (z-buffered, shaded tubes) and encoded by our own
 * small writer (fixed-Huffman deflate with run-length matches, CRC-32,
 * Adler-32): no image library. SVG merges each path into polylines (one per
 * run of equal width) decimated to one vertex per pixel.
 *
 * Output goes through an amp_sink_fn (a file through amp_out_sink, memory
 * through amp_buf_sink); memory is allocated with the path set's allocator
 * (the PNG needs about 7 bytes per pixel while it is drawn). Reentrant; the
 * path set is only read.
 */
#ifndef AMPATH_PREVIEW_H
#define AMPATH_PREVIEW_H

#include <stddef.h>

#include "io.h"
#include "paths.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Narrowest and widest picture accepted, pixels. */
#define AMP_PREVIEW_MIN_WIDTH 200
#define AMP_PREVIEW_MAX_WIDTH 8000

/** Figures of one picture. */
typedef struct amp_preview_stats {
    int width, height;     /**< picture size in pixels */
    size_t paths, support; /**< paths drawn, of which support */
    size_t vertices;       /**< input vertices */
    size_t drawn;          /**< segments drawn after decimation (both views) */
    size_t bytes;          /**< bytes written to the sink */
} amp_preview_stats;

/**
 * Write a PNG picture of @p ps, @p width pixels wide, through @p sink.
 * @p st (optional) receives the figures. Errors: AMP_ERR_ARG (NULL, no path),
 * AMP_ERR_RANGE (width outside AMP_PREVIEW_MIN_WIDTH..AMP_PREVIEW_MAX_WIDTH),
 * AMP_ERR_NOMEM (nothing written), or the sink's status (the picture is then
 * incomplete).
 */
amp_status amp_preview_png(const amp_pathset *ps, int width, amp_sink_fn sink, void *user, amp_preview_stats *st,
                           amp_error *err);

/** Write an SVG picture of @p ps (same layout and errors as amp_preview_png()). */
amp_status amp_preview_svg(const amp_pathset *ps, int width, amp_sink_fn sink, void *user, amp_preview_stats *st,
                           amp_error *err);

/** Options of amp_preview_png_opts() and amp_preview_svg_opts(). */
typedef struct amp_preview_opts {
    int width; /**< picture width, pixels (AMP_PREVIEW_MIN_WIDTH..AMP_PREVIEW_MAX_WIDTH; default 1600) */
    /** Optional progress report: the fraction (0..1) of the paths' vertices walked for both views, from the
     * calling thread, a few hundred times at most (a job of a few hundred MB takes seconds to draw). */
    void (*progress)(void *user, double fraction);
    void *progress_user; /**< passed to progress */
} amp_preview_opts;

/** Defaults: width 1600, no progress report. */
void amp_preview_opts_default(amp_preview_opts *o);

/** amp_preview_png() with options (the same bytes for the same width); AMP_ERR_ARG when @p o is NULL. */
amp_status amp_preview_png_opts(const amp_pathset *ps, const amp_preview_opts *o, amp_sink_fn sink, void *user,
                                amp_preview_stats *st, amp_error *err);

/** amp_preview_svg() with options (the same bytes for the same width); AMP_ERR_ARG when @p o is NULL. */
amp_status amp_preview_svg_opts(const amp_pathset *ps, const amp_preview_opts *o, amp_sink_fn sink, void *user,
                                amp_preview_stats *st, amp_error *err);

/** CRC-32 (ISO 3309, as PNG uses) of @p n bytes, continuing from @p crc (start with 0). Pure function. */
unsigned long amp_preview_crc32(unsigned long crc, const unsigned char *p, size_t n);

#ifdef __cplusplus
}
#endif
#endif
