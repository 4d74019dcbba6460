/*
 * lib/keysort.h — internal: a stable sort of (k1, k2) keys carrying an index,
 * for the checkers' sweeps. It gives the order glibc's qsort gave them (its
 * merge sort is stable too) without a comparison call per step: the sorts
 * were a fifth of slicing a 536-layer part, where the stroke checker sorts
 * every stroke's vertices, edges and segments.
 */
#ifndef AMPATH_LIB_KEYSORT_H
#define AMPATH_LIB_KEYSORT_H

#include <stddef.h>

typedef struct amp_skey {
    double k1, k2; /* ascending by k1, then k2; equal keys keep their order */
    size_t i;      /* the caller's payload (usually the item's index) */
} amp_skey;

/* Sort @p k[0, n) in place; @p tmp has room for n keys (its content is lost). */
void amp_skey_sort(amp_skey *k, amp_skey *tmp, size_t n);

#endif
