/*
 * ampath/alloc.h — the pluggable allocator.
 *
 * Every allocation libampath makes goes through an amp_allocator supplied by
 * the caller (or the default one, which wraps malloc/realloc/free). Objects
 * remember the allocator they were created with and free through it. The
 * one exception is the C library's own qsort(), which the library sorts
 * with: glibc's may take a temporary buffer from malloc for a large array
 * (newlib's, on the Cortex-M build, takes none).
 * Functions taking `const amp_allocator *` accept NULL for the default.
 */
#ifndef AMPATH_ALLOC_H
#define AMPATH_ALLOC_H

#include <stddef.h>

#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * An allocator: three callbacks sharing an opaque user pointer.
 * realloc(user, NULL, n) must behave like alloc(user, n); free(user, NULL)
 * must be a no-op. Returning NULL from alloc/realloc reports out-of-memory;
 * libampath then returns AMP_ERR_NOMEM and leaves its objects consistent.
 */
typedef struct amp_allocator {
    void *(*alloc)(void *user, size_t size);
    void *(*realloc)(void *user, void *ptr, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} amp_allocator;

/** The malloc-based allocator (a constant object; thread-safe as malloc is). */
const amp_allocator *amp_allocator_default(void);

/** Allocate @p size bytes through @p a (NULL = default). Returns NULL on failure or size 0. */
void *amp_alloc(const amp_allocator *a, size_t size);

/** Allocate count*size bytes, zero-filled, with overflow checking. NULL on failure. */
void *amp_calloc(const amp_allocator *a, size_t count, size_t size);

/** Resize @p ptr to count*size bytes with overflow checking. On failure returns NULL and leaves @p ptr valid. */
void *amp_realloc_array(const amp_allocator *a, void *ptr, size_t count, size_t size);

/** Free @p ptr through @p a. NULL is accepted. */
void amp_free(const amp_allocator *a, void *ptr);

/**
 * Grow a dynamic array so that it holds at least @p need elements of @p size
 * bytes. @p *ptr and @p *cap are updated only on success (capacity doubles).
 * Returns AMP_OK or AMP_ERR_NOMEM.
 */
amp_status amp_grow(const amp_allocator *a, void **ptr, size_t *cap, size_t need, size_t size);

#ifdef __cplusplus
}
#endif
#endif
