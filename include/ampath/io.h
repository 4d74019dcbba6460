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
#include <stdio.h>

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

/** Size bound of amp_read_file() when its max_len is 0: 1 GiB. */
#define AMP_READ_MAX_DEFAULT ((size_t)1 << 30)

/**
 * Read a whole file into memory allocated with @p a. On success *data holds
 * *len bytes followed by a NUL (not counted), owned by the caller (free with
 * amp_free(a, *data)). On failure nothing is allocated and @p err says why.
 * @p max_len bounds the size accepted (0 = AMP_READ_MAX_DEFAULT): on POSIX
 * systems a larger regular file is refused from its size (fstat) before any
 * byte is read, with AMP_ERR_LIMIT and the size in the message; pipes and
 * devices are read up to the bound. Errors: AMP_ERR_ARG, AMP_ERR_IO (cannot
 * open, a directory, read error), AMP_ERR_LIMIT, AMP_ERR_NOMEM.
 */
amp_status amp_read_file(const char *path, const amp_allocator *a, size_t max_len, char **data, size_t *len,
                         amp_error *err);

/** Longest output path amp_out_open() accepts, including the NUL (also after resolving symlinks). */
#define AMP_OUT_PATH_MAX 4096

/**
 * An output file being written: the one safe path of every writer of the
 * library and of the ampath tool. Plain data owned by the caller (about 8 KB:
 * give it static or automatic storage on a hosted system).
 *
 * On POSIX systems amp_out_open():
 *  - follows symbolic links (up to 40) and writes to their final target, so a
 *    link stays a link;
 *  - writes devices, FIFOs and sockets directly (no temporary, no rename:
 *    `/dev/null` stays a device; `/dev/full` reports ENOSPC at commit);
 *  - for a regular or new file, creates a temporary with a fresh unique name
 *    (".NAME.XXXXXXXX.tmp", O_EXCL) in the target's directory; commit flushes,
 *    fsyncs, closes and renames it over the target, which keeps the replaced
 *    file's permission bits (and owner when allowed). Any failure (disk full,
 *    EFBIG, a failing device) removes the temporary and leaves the old file
 *    intact, and is reported with the system's reason.
 *  - refuses a directory, and an existing file the caller may not write.
 * Elsewhere (the freestanding cross build) it falls back to stdio:
 * PATH.tmp written and renamed.
 */
typedef struct amp_out {
    FILE *f;                       /**< write the content here (or through amp_out_sink) */
    int direct;                    /**< non-zero: f is the target itself (a device or FIFO) */
    int werr;                      /**< errno of the first failed amp_out_sink write, 0 if none */
    char target[AMP_OUT_PATH_MAX]; /**< the file that receives the content, symlinks resolved */
    char tmp[AMP_OUT_PATH_MAX];    /**< the temporary being written, "" when direct or closed */
} amp_out;

/**
 * Open @p path for writing as described at amp_out. On success o->f is ready;
 * finish with amp_out_commit() or amp_out_abort(). On failure nothing is left
 * open or created. Errors: AMP_ERR_ARG (NULL, empty or too long a path),
 * AMP_ERR_IO (with the system's reason: a directory, permission, ...).
 */
amp_status amp_out_open(amp_out *o, const char *path, amp_error *err);

/** amp_sink_fn adaptor: @p user is an amp_out *; records the errno of a failed write in o->werr. */
amp_status amp_out_sink(void *user, const char *data, size_t len);

/**
 * Finish: flush, fsync (regular files), close and rename the temporary into
 * place. Closes o->f in every case. On failure (a write error seen earlier
 * included) the temporary is removed, the target is untouched, and AMP_ERR_IO
 * says why ("PATH: No space left on device").
 */
amp_status amp_out_commit(amp_out *o, amp_error *err);

/** Give up: close o->f and remove the temporary; the target is untouched. Safe on a closed amp_out. */
void amp_out_abort(amp_out *o);

/** A writer for amp_write_file_atomic(): push the content of @p ctx through @p sink. */
typedef amp_status (*amp_writer_fn)(void *ctx, amp_sink_fn sink, void *user, amp_error *err);

/**
 * Write a file safely through amp_out: @p write pushes the content through a
 * sink; on success it is committed, on any failure the target is untouched
 * (devices and FIFOs, which are written directly, may have received part of
 * it). Errors: AMP_ERR_ARG, AMP_ERR_IO with the system's reason (ENOSPC ...),
 * or the writer's own status.
 */
amp_status amp_write_file_atomic(const char *path, amp_writer_fn write, void *ctx, amp_error *err);

/** amp_sink_fn adaptor: @p user is a FILE *. */
amp_status amp_file_sink(void *user, const char *data, size_t len);

#ifdef __cplusplus
}
#endif
#endif
