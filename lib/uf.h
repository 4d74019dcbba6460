/*
 * lib/uf.h — internal: the one union-find of the library (disjoint sets over
 * 0..n-1 in a parent array; p[x] == x for a root). Path halving; union makes
 * the root of a's set point at the root of b's, so the result depends only on
 * the order of the unions (deterministic).
 */
#ifndef AMPATH_LIB_UF_H
#define AMPATH_LIB_UF_H

#include <stddef.h>

/** Root of x's set (halves the path on the way). */
static inline size_t amp_uf_find(size_t *p, size_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

/** Join the sets of a and b; 1 when they were apart, 0 when already one set. */
static inline int amp_uf_union(size_t *p, size_t a, size_t b)
{
    a = amp_uf_find(p, a);
    b = amp_uf_find(p, b);
    if (a == b)
        return 0;
    p[a] = b;
    return 1;
}

#endif
