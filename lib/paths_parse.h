/*
 * paths_parse.h — internal: the `.amp` reader in chunks (lib/paths_parse.c), for the tests.
 */
#ifndef AMP_PATHS_PARSE_H
#define AMP_PATHS_PARSE_H

#include "ampath/paths.h"

/**
 * amp_pathset_parse() reading the body in at most @p nchunks chunks that start at path headers (counted
 * first, then parsed into their places, in parallel under OpenMP). The result, the error and the message are
 * those of the one-chunk read: a chunk that does not parse cleanly on its own sends the whole text to it.
 * *@p used (may be NULL) receives the number of chunks the text was read in (1: one piece, or the fallback).
 */
amp_status amp_pathset_parse_chunks(amp_pathset *ps, const char *text, size_t len, size_t nchunks, size_t *used,
                                    amp_error *err);

/** A progress report of the chunked read: fn(user, chunks done / chunks), from the calling thread. */
typedef struct amp_parse_progress {
    void (*fn)(void *user, double fraction);
    void *user;
} amp_parse_progress;

/** amp_pathset_parse_chunks() reporting to @p pg (may be NULL) as chunks are read. */
amp_status amp_pathset_parse_chunks_progress(amp_pathset *ps, const char *text, size_t len, size_t nchunks,
                                             size_t *used, const amp_parse_progress *pg, amp_error *err);

#endif
