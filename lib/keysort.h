/*
 * lib/keysort.h — internal: a stable sort of (k1, k2) keys carrying an index,
 * for the checkers' sweeps, and a stable radix sort of records by uint32_t
 * fields (the mesh's edges and triangles). It gives the order glibc's qsort gave them (its
 * merge sort is stable too) without a comparison call per step: the sorts
 * were a fifth of slicing a 536-layer part, where the stroke checker sorts
 * every stroke's vertices, edges and segments.
 */
#ifndef AMPATH_LIB_KEYSORT_H
#define AMPATH_LIB_KEYSORT_H

#include <stddef.h>
#include <stdint.h>

#include "ampath/alloc.h"

typedef struct amp_skey {
    double k1, k2; /* ascending by k1, then k2; equal keys keep their order */
    size_t i;      /* the caller's payload (usually the item's index) */
} amp_skey;

/* Sort @p k[0, n) in place; @p tmp has room for n keys (its content is lost). */
void amp_skey_sort(amp_skey *k, amp_skey *tmp, size_t n);

/*
 * Stable LSD radix sort of the @p n records of @p size bytes at @p base by
 * the uint32_t fields at byte offsets @p off[0] (most significant) ..
 * off[nkeys - 1], ascending; equal records keep their order (the order a
 * stable comparison sort gives, without a call per comparison: sorting the
 * edges of a 1.25 M-triangle mesh with qsort was a quarter of `field` on it).
 * 11-bit digits, a digit that all records share costs one counting pass.
 * @p tmp has room for n records; the result is in @p base.
 */
void amp_radix_u32(void *base, void *tmp, size_t n, size_t size, const size_t *off, int nkeys);

/*
 * amp_radix_u32 with its copy from @p al; without memory for it, qsort with
 * @p cmp, which must order as the fields do and break ties by the records'
 * own content as they stand (the result is then the same, if glibc's merge
 * sort manages the memory).
 */
void amp_radix_sort(const amp_allocator *al, void *base, size_t n, size_t size, const size_t *off, int nkeys,
                    int (*cmp)(const void *, const void *));

#endif
