/* The pluggable allocator and overflow-checked array helpers. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/alloc.h"

static void *std_alloc(void *user, size_t size)
{
    (void)user;
    return malloc(size);
}

static void *std_realloc(void *user, void *ptr, size_t size)
{
    (void)user;
    return realloc(ptr, size);
}

static void std_free(void *user, void *ptr)
{
    (void)user;
    free(ptr);
}

static const amp_allocator default_allocator = {std_alloc, std_realloc, std_free, NULL};

const amp_allocator *amp_allocator_default(void) { return &default_allocator; }

void *amp_alloc(const amp_allocator *a, size_t size)
{
    if (!a)
        a = &default_allocator;
    return size ? a->alloc(a->user, size) : NULL;
}

void *amp_calloc(const amp_allocator *a, size_t count, size_t size)
{
    void *p;
    if (count && size > SIZE_MAX / count)
        return NULL;
    p = amp_alloc(a, count * size);
    if (p)
        memset(p, 0, count * size);
    return p;
}

void *amp_realloc_array(const amp_allocator *a, void *ptr, size_t count, size_t size)
{
    if (!a)
        a = &default_allocator;
    if ((count && size > SIZE_MAX / count) || count * size == 0)
        return NULL;
    return a->realloc(a->user, ptr, count * size);
}

void amp_free(const amp_allocator *a, void *ptr)
{
    if (!ptr)
        return;
    if (!a)
        a = &default_allocator;
    a->free(a->user, ptr);
}

amp_status amp_grow(const amp_allocator *a, void **ptr, size_t *cap, size_t need, size_t size)
{
    size_t ncap;
    void *p;
    if (need <= *cap)
        return AMP_OK;
    ncap = *cap ? *cap : 16;
    while (ncap < need) {
        if (ncap > SIZE_MAX / 2)
            return AMP_ERR_NOMEM;
        ncap *= 2;
    }
    p = amp_realloc_array(a, *ptr, ncap, size);
    if (!p)
        return AMP_ERR_NOMEM;
    *ptr = p;
    *cap = ncap;
    return AMP_OK;
}
