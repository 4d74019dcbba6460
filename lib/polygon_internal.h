/* lib/polygon_internal.h — internal: what the polygon_*.c files and polygon.c share. */
#ifndef AMPATH_LIB_POLYGON_INTERNAL_H
#define AMPATH_LIB_POLYGON_INTERNAL_H

#include "ampath/alloc.h"
#include "ampath/vec.h"

/* Squared distance from q to the segment [a, b]. */
static inline double seg_dist2(amp_vec2 q, amp_vec2 a, amp_vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy, t = 0.0, ex, ey;
    if (l2 > 0.0) {
        t = ((q.x - a.x) * dx + (q.y - a.y) * dy) / l2;
        t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    }
    ex = a.x + t * dx - q.x;
    ey = a.y + t * dy - q.y;
    return ex * ex + ey * ey;
}

/* A point where segment @p seg is cut, at parameter t along it; node: the
 * shared id of the point (the inset's crossings, the union's meetings). */
typedef struct pg_split {
    size_t seg;
    double t;
    size_t node;
} pg_split;

/* A growable list of cuts. */
typedef struct pg_splits {
    pg_split *v;
    size_t n, cap;
} pg_splits;

static inline amp_status pg_splits_add(const amp_allocator *al, pg_splits *l, size_t seg, double t, size_t node)
{
    void *v = l->v;
    if (amp_grow(al, &v, &l->cap, l->n + 1, sizeof *l->v) != AMP_OK)
        return AMP_ERR_NOMEM;
    l->v = v;
    l->v[l->n].seg = seg;
    l->v[l->n].t = t;
    l->v[l->n].node = node;
    l->n++;
    return AMP_OK;
}

/* Cuts by segment, then along it. */
static inline int pg_split_cmp(const void *a, const void *b)
{
    const pg_split *s = a, *t = b;
    if (s->seg != t->seg)
        return s->seg < t->seg ? -1 : 1;
    return s->t < t->t ? -1 : (s->t > t->t ? 1 : 0);
}

#endif
