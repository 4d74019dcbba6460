/*
 * ampath/io.h — byte sinks for writers and whole-file helpers.
 *
 * Writers in libampath never touch FILE* directly: they push text through an
 * amp_sink, so that they work into memory, a socket or a UART as well as a
 * file. The file helpers below are the only functions of the library that use
 * stdio; they are thread-safe as long as distinct files are used.
 */
#ifndef AMPATH_IO_H
#define AMPATH_IO_H

#include <stddef.h>

#include "alloc.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * A byte sink: write @p len bytes of @p data, return AMP_OK or an error
 * (which aborts the writer that called it and is passed back to its caller).
 */
typedef amp_status (*amp_sink_fn)(void *user, const char *data, size_t len);

/** A growable in-memory buffer usable as a sink (amp_buf_sink). */
typedef struct amp_buf {
    const amp_allocator *alloc; /**< allocator used for data (NULL = default) */
    char *data;                 /**< bytes written so far, always NUL-terminated when non-NULL */
    size_t len;                 /**< number of bytes in data, excluding the NUL */
    size_t cap;                 /**< allocated capacity of data */
} amp_buf;

/** Initialise an empty buffer using allocator @p a (NULL = default). */
void amp_buf_init(amp_buf *b, const amp_allocator *a);
/** Release the buffer's memory and make it empty again. */
void amp_buf_free(amp_buf *b);
/** Append bytes; AMP_ERR_NOMEM on failure (the buffer keeps its old content). */
amp_status amp_buf_append(amp_buf *b, const char *data, size_t len);
/** amp_sink_fn adaptor: @p user is an amp_buf *. */
amp_status amp_buf_sink(void *user, const char *data, size_t len);

/**
 * printf into a sink through a small stack buffer (lines up to 512 bytes;
 * longer output returns AMP_ERR_LIMIT). Used by the text writers.
 */
amp_status amp_sinkf(amp_sink_fn sink, void *user, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/**
 * Read a whole file into memory allocated with @p a. On success *data holds
 * *len bytes followed by a NUL (not counted), owned by the caller (free with
 * amp_free(a, *data)). On failure nothing is allocated and @p err says why.
 * @p max_len bounds the size accepted (0 = 1 GiB).
 */
amp_status amp_read_file(const char *path, const amp_allocator *a, size_t max_len, char **data, size_t *len,
                         amp_error *err);

/** A writer for amp_write_file_atomic(): push the content of @p ctx through @p sink. */
typedef amp_status (*amp_writer_fn)(void *ctx, amp_sink_fn sink, void *user, amp_error *err);

/**
 * Write a file atomically: @p write fills PATH.tmp, which is then renamed to
 * @p path; on any failure PATH.tmp is removed and @p path is untouched.
 * Errors: AMP_ERR_ARG (path too long), AMP_ERR_IO, or the writer's status.
 */
amp_status amp_write_file_atomic(const char *path, amp_writer_fn write, void *ctx, amp_error *err);

/** amp_sink_fn adaptor: @p user is a FILE *. */
amp_status amp_file_sink(void *user, const char *data, size_t len);

#ifdef __cplusplus
}
#endif
#endif
