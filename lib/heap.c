/* The binary heap of lib/heap.h. */
#include <string.h>

#include "heap.h"

void amp_heap_init(amp_heap *h, const amp_allocator *a, size_t size, amp_heap_better_fn better, const void *ctx)
{
    memset(h, 0, sizeof *h);
    h->alloc = a;
    h->size = size;
    h->better = better;
    h->ctx = ctx;
}

amp_status amp_heap_push(amp_heap *h, const void *item)
{
    void *p = h->item;
    size_t i, sz = h->size;
    if (amp_grow(h->alloc, &p, &h->cap, h->n + 1, sz) != AMP_OK)
        return AMP_ERR_NOMEM;
    h->item = p;
    i = h->n++;
    while (i > 0 && h->better(item, h->item + (i - 1) / 2 * sz, h->ctx)) {
        memcpy(h->item + i * sz, h->item + (i - 1) / 2 * sz, sz);
        i = (i - 1) / 2;
    }
    memcpy(h->item + i * sz, item, sz);
    return AMP_OK;
}

int amp_heap_pop(amp_heap *h, void *out)
{
    size_t i = 0, n, sz = h->size;
    const unsigned char *last;
    if (h->n == 0)
        return 0;
    memcpy(out, h->item, sz);
    n = --h->n;
    last = h->item + n * sz; /* stays in place: the sift below writes only slots < n */
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= n)
            break;
        if (c + 1 < n && h->better(h->item + (c + 1) * sz, h->item + c * sz, h->ctx))
            c++;
        if (!h->better(h->item + c * sz, last, h->ctx))
            break;
        memcpy(h->item + i * sz, h->item + c * sz, sz);
        i = c;
    }
    if (n)
        memcpy(h->item + i * sz, last, sz);
    return 1;
}

void amp_heap_free(amp_heap *h)
{
    amp_free(h->alloc, h->item);
    h->item = NULL;
    h->n = h->cap = 0;
}
