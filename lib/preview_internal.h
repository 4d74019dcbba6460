/*
 * lib/preview_internal.h — internal: what the picture writer (preview.c) and the PNG encoder
 * (preview_png.c) share: the raster and the counted output through the caller's sink.
 */
#ifndef AMPATH_LIB_PREVIEW_INTERNAL_H
#define AMPATH_LIB_PREVIEW_INTERNAL_H

#include "ampath/preview.h"

typedef struct raster {
    int w, h;
    unsigned char *rgb;
    float *depth;
    unsigned char col[3];
} raster;

/* The caller's sink with a byte count; the first error is kept and later writes are skipped. */
typedef struct pv_out {
    amp_sink_fn sink;
    void *user;
    size_t bytes;
    amp_status st;
} pv_out;

static inline void pv_put(pv_out *o, const void *data, size_t n)
{
    if (o->st == AMP_OK && n) {
        o->st = o->sink(o->user, data, n);
        if (o->st == AMP_OK)
            o->bytes += n;
    }
}


/* Encode the raster as a PNG (filter Up, deflate with run-length matches) and write it; -1 when memory ran
 * out (nothing written then). */
int amp_pv_write_png(pv_out *o, const raster *r, const amp_allocator *a);

#endif
