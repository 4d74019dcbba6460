/* Row index of a polygon set for many point queries (containment and
 * distance to the boundary) at a cost of one row instead of every edge. */
#include <math.h>
#include <string.h>

#include "ampath/polygon.h"
#include "polygon_internal.h"

static long row_of(const amp_polyindex *ix, double v)
{
    long k = (long)floor((v - ix->y0) / ix->h);
    return k < 0 ? 0 : (k >= ix->nrow ? ix->nrow - 1 : k);
}

void amp_polyindex_free(amp_polyindex *ix)
{
    const amp_allocator *al = ix->P ? ix->P->alloc : NULL;
    if (!ix->P)
        return;
    amp_free(al, ix->start);
    amp_free(al, ix->item);
    amp_free(al, ix->a);
    amp_free(al, ix->b);
    memset(ix, 0, sizeof *ix);
}

amp_status amp_polyindex_build(amp_polyindex *ix, const amp_polyset *P, amp_error *err)
{
    const amp_allocator *al = P->alloc;
    size_t r, k, id = 0, round, n = P->npts;
    double y1 = -HUGE_VAL;
    memset(ix, 0, sizeof *ix);
    ix->P = P;
    ix->y0 = HUGE_VAL;
    ix->a = amp_alloc(al, (n + 1) * sizeof *ix->a);
    ix->b = amp_alloc(al, (n + 1) * sizeof *ix->b);
    /* 4 sqrt(n) rows: a point test scans about sqrt(n) / 4 short edges (the skin test asks thousands
     * of points per layer); the rows cost O(n + rows) to build */
    ix->nrow = 4 * (long)sqrt((double)n) + 1;
    ix->start = amp_calloc(al, (size_t)ix->nrow + 1, sizeof *ix->start);
    if (!ix->a || !ix->b || !ix->start)
        goto nomem;
    for (r = 0; r < P->nrings; r++) {
        const amp_vec2 *p = amp_polyset_ring(P, r);
        size_t m = P->rings[r].n;
        for (k = 0; k < m; k++, id++) {
            ix->a[id] = p[k];
            ix->b[id] = p[(k + 1) % m];
            ix->y0 = fmin(ix->y0, p[k].y);
            y1 = fmax(y1, p[k].y);
        }
    }
    if (id == 0)
        ix->y0 = y1 = 0;
    ix->h = fmax((y1 - ix->y0) / (double)ix->nrow, 1e-12);
    for (round = 0; round < 2; round++) {
        for (k = 0; k < id; k++) {
            long r0 = row_of(ix, fmin(ix->a[k].y, ix->b[k].y)), r1 = row_of(ix, fmax(ix->a[k].y, ix->b[k].y)), q;
            for (q = r0; q <= r1; q++) {
                if (round == 0)
                    ix->start[q + 1]++;
                else
                    ix->item[ix->start[q]++] = k;
            }
        }
        if (round == 0) {
            for (k = 0; k < (size_t)ix->nrow; k++)
                ix->start[k + 1] += ix->start[k];
            if (!(ix->item = amp_alloc(al, (ix->start[ix->nrow] + 1) * sizeof *ix->item)))
                goto nomem;
        }
    }
    for (k = (size_t)ix->nrow; k > 0; k--)
        ix->start[k] = ix->start[k - 1];
    ix->start[0] = 0;
    return AMP_OK;
nomem:
    amp_polyindex_free(ix);
    return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory indexing a polygon set");
}

int amp_polyindex_contains(const amp_polyindex *ix, amp_vec2 q)
{
    long rq;
    size_t k;
    int in = 0;
    if (!ix->item || ix->P->npts == 0)
        return 0;
    rq = row_of(ix, q.y);
    /* a point outside the rows' span crosses nothing */
    if (q.y < ix->y0 || q.y > ix->y0 + ix->h * (double)ix->nrow)
        return 0;
    for (k = ix->start[rq]; k < ix->start[rq + 1]; k++) {
        amp_vec2 a = ix->a[ix->item[k]], b = ix->b[ix->item[k]];
        if (q.y >= fmin(a.y, b.y) && q.y <= fmax(a.y, b.y) && q.x >= fmin(a.x, b.x) && q.x <= fmax(a.x, b.x) &&
            seg_dist2(q, a, b) <= 0.0)
            return -1;
        /* the half-open rule of amp_ring_contains: each crossing once */
        if ((a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y))
            in = !in;
    }
    return in;
}

int amp_polyindex_winding(const amp_polyindex *ix, amp_vec2 q)
{
    long rq;
    size_t k;
    int w = 0;
    if (!ix->item || ix->P->npts == 0 || q.y < ix->y0 || q.y > ix->y0 + ix->h * (double)ix->nrow)
        return 0;
    rq = row_of(ix, q.y);
    /* Sunday's rule: an upward edge with q on its left counts +1, a downward one with q on its right -1 */
    for (k = ix->start[rq]; k < ix->start[rq + 1]; k++) {
        amp_vec2 a = ix->a[ix->item[k]], b = ix->b[ix->item[k]];
        if (a.y <= q.y) {
            if (b.y > q.y && amp_v2_orient(a, b, q) > 0)
                w++;
        } else if (b.y <= q.y && amp_v2_orient(a, b, q) < 0)
            w--;
    }
    return w;
}

double amp_polyindex_dist_within(const amp_polyindex *ix, amp_vec2 q, double cap)
{
    double best = cap < HUGE_VAL ? cap * cap : HUGE_VAL;
    long rq, lo, hi, d;
    size_t k;
    if (!ix->item || ix->P->npts == 0)
        return cap;
    rq = row_of(ix, q.y);
    /* rows outward from q's row until the next row is farther than the best (or the cap) */
    for (d = 0; d <= ix->nrow; d++) {
        double gap;
        lo = rq - d;
        hi = rq + d;
        if (lo < 0 && hi >= ix->nrow)
            break;
        /* the nearest y a segment listed in row lo (or hi) can have */
        gap = d == 0 ? 0 : fmin(lo >= 0 ? q.y - (ix->y0 + ix->h * (double)(lo + 1)) : HUGE_VAL,
                                hi < ix->nrow ? ix->y0 + ix->h * (double)hi - q.y : HUGE_VAL);
        if (gap > 0 && gap * gap > best)
            break;
        for (k = lo >= 0 ? ix->start[lo] : 0; lo >= 0 && k < ix->start[lo + 1]; k++)
            best = fmin(best, seg_dist2(q, ix->a[ix->item[k]], ix->b[ix->item[k]]));
        for (k = hi < ix->nrow && d > 0 ? ix->start[hi] : 0; hi < ix->nrow && d > 0 && k < ix->start[hi + 1]; k++)
            best = fmin(best, seg_dist2(q, ix->a[ix->item[k]], ix->b[ix->item[k]]));
    }
    return best < HUGE_VAL ? fmin(sqrt(best), cap) : cap;
}

double amp_polyindex_dist(const amp_polyindex *ix, amp_vec2 q) { return amp_polyindex_dist_within(ix, q, HUGE_VAL); }
