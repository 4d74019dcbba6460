/* lib/polygon_internal.h — internal: what lib/polygon.c, lib/polygon_inset.c and lib/polygon_index.c share. */
#ifndef AMPATH_LIB_POLYGON_INTERNAL_H
#define AMPATH_LIB_POLYGON_INTERNAL_H

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

#endif
