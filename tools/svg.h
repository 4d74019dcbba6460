/*
 * svg.h — minimal SVG writer for the slicing and Euler pictures (plain text,
 * millimetre coordinates, y up as on the build plate).
 */
#ifndef AMP_TOOLS_SVG_H
#define AMP_TOOLS_SVG_H

#include <stdio.h>

#include "ampath/ampath.h"

typedef struct svg_doc {
    FILE *f;       /* out.f while open */
    amp_out out;   /* the safe writer (io.h): no partial file ever replaces an old one */
    amp_error err; /* why svg_open or svg_close failed */
    double x0, y1; /* left and top in mm (y is flipped) */
    double px;     /* nominal stroke unit: 1/500 of the larger side */
} svg_doc;

/** Open @p path for a picture of the box [xmin, xmax] x [ymin, ymax] (mm) plus a margin. 0, or -1 with s->err. */
int svg_open(svg_doc *s, const char *path, double xmin, double ymin, double xmax, double ymax);
/** Rings of @p ps as one even-odd path. @p fill may be "none"; @p width in multiples of s->px. */
void svg_polyset(svg_doc *s, const amp_polyset *ps, const char *fill, const char *stroke, double width);
/** Every 1-cell of @p k (face edges and free edges), once per face side. */
void svg_cx2(svg_doc *s, const amp_cx2 *k, const char *stroke, double width);
/** A text line at the top left. */
void svg_text(svg_doc *s, int line, const char *text);
/** Finish, close and put the file in place; 0, or -1 with s->err when writing failed (the old file then stays). */
int svg_close(svg_doc *s);

#endif
