/*
 * lib/heap.h — internal: the one binary heap of the library, over items of
 * any size (copied in and out), ordered by a caller's "better" relation: the
 * best item comes out first. Sift-up moves an item past its parent only when
 * it is strictly better, sift-down takes the right child only when it is
 * strictly better than the left and stops unless the child is strictly
 * better, so the order of equal items is a deterministic function of the
 * pushes and pops (the rule the orderer, lib/order.c, and MDR, lib/mdr.c,
 * relied on before they moved onto this heap).
 */
#ifndef AMPATH_LIB_HEAP_H
#define AMPATH_LIB_HEAP_H

#include <stddef.h>

#include "ampath/alloc.h"
#include "ampath/status.h"

/** Non-zero when item @p a must come out before item @p b. */
typedef int (*amp_heap_better_fn)(const void *a, const void *b, const void *ctx);

typedef struct amp_heap {
    const amp_allocator *alloc;
    amp_heap_better_fn better;
    const void *ctx;     /* passed to better */
    size_t size;         /* bytes per item */
    unsigned char *item; /* n items, heap-ordered */
    size_t n, cap;
} amp_heap;

/** An empty heap of @p size-byte items. */
void amp_heap_init(amp_heap *h, const amp_allocator *a, size_t size, amp_heap_better_fn better, const void *ctx);
/** Add a copy of @p item: AMP_ERR_NOMEM (the heap unchanged) or AMP_OK. */
amp_status amp_heap_push(amp_heap *h, const void *item);
/** Copy the best item to @p out and remove it; 0 when the heap is empty. */
int amp_heap_pop(amp_heap *h, void *out);
void amp_heap_free(amp_heap *h);

#endif
