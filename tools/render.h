/*
 * render.h — pictures of path sets for `ampath preview`: an isometric view
 * and a top view side by side, paths drawn as tubes whose width follows the
 * deposition radius, coloured by print order (support in grey), with a legend.
 *
 * PNG is rasterised here (z-buffered, shaded tubes) and encoded by our own
 * small writer (fixed-Huffman deflate with run-length matches, CRC-32,
 * Adler-32): no image library is needed. SVG merges each path into
 * polylines (one per run of equal width) decimated to one vertex per pixel.
 */
#ifndef AMP_TOOLS_RENDER_H
#define AMP_TOOLS_RENDER_H

#include <stdio.h>

#include "ampath/ampath.h"

typedef struct render_stats {
    int width, height;       /* picture size in pixels */
    size_t paths, support;   /* paths drawn, of which support */
    size_t vertices;         /* input vertices */
    size_t drawn;            /* segments drawn after decimation (both views) */
    size_t bytes;            /* bytes written */
} render_stats;

/** Write a PNG picture of @p ps, @p width pixels wide (height = width/2 + legend). 0 on success, -1 on I/O error. */
int render_png(const amp_pathset *ps, int width, FILE *out, render_stats *st);

/** Write an SVG picture of @p ps (same layout). 0 on success, -1 on I/O error. */
int render_svg(const amp_pathset *ps, int width, FILE *out, render_stats *st);

/** CRC-32 (ISO 3309, as PNG uses) of @p n bytes, continuing from @p crc (start with 0). */
unsigned long render_crc32(unsigned long crc, const unsigned char *p, size_t n);

#endif
