/* Planar polygons with holes: area, containment, hull and islands. The inward
 * Minkowski offset is in lib/polygon_inset.c. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/polygon.h"
#include "ampath/vec.h"
#include "polygon_internal.h"

void amp_polyset_init(amp_polyset *ps, const amp_allocator *a)
{
    memset(ps, 0, sizeof *ps);
    ps->alloc = a;
}

void amp_polyset_free(amp_polyset *ps)
{
    if (!ps)
        return;
    amp_free(ps->alloc, ps->pts);
    amp_free(ps->alloc, ps->rings);
    amp_polyset_init(ps, ps->alloc);
}

void amp_polyset_clear(amp_polyset *ps)
{
    ps->npts = 0;
    ps->nrings = 0;
    ps->nislands = 0;
}

/* Equal up to rounding (1e-12 relative): a section passing within 1e-16 of a
 * mesh vertex gives such pairs, and the direction of the tiny edge between
 * them would be noise for every later offset. */
static int near_equal(amp_vec2 a, amp_vec2 b)
{
    return fabs(a.x - b.x) <= 1e-12 * (1.0 + fabs(a.x)) && fabs(a.y - b.y) <= 1e-12 * (1.0 + fabs(a.y));
}

amp_status amp_polyset_add(amp_polyset *ps, const amp_vec2 *p, size_t n, amp_error *err)
{
    size_t i, start = ps->npts, m = 0;
    void *v;
    for (i = 0; i < n; i++)
        if (!isfinite(p[i].x) || !isfinite(p[i].y))
            return amp_fail(err, AMP_ERR_ARG, 0, "polygon point is not finite");
    v = ps->pts;
    if (amp_grow(ps->alloc, &v, &ps->cap_pts, ps->npts + n + 1, sizeof *ps->pts) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for polygon points");
    ps->pts = v;
    v = ps->rings;
    if (amp_grow(ps->alloc, &v, &ps->cap_rings, ps->nrings + 1, sizeof *ps->rings) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for polygon rings");
    ps->rings = v;
    for (i = 0; i < n; i++) {
        amp_vec2 q = p[i];
        if (m && near_equal(ps->pts[start + m - 1], q))
            continue; /* consecutive duplicate (e.g. a section through a mesh vertex) */
        ps->pts[start + m++] = q;
    }
    while (m > 1 && near_equal(ps->pts[start], ps->pts[start + m - 1]))
        m--; /* repeated closing point */
    if (m < 3)
        return AMP_OK;
    ps->npts += m;
    ps->rings[ps->nrings].first = start;
    ps->rings[ps->nrings].n = m;
    ps->rings[ps->nrings].island = -1;
    ps->rings[ps->nrings].hole = 0;
    ps->nrings++;
    return AMP_OK;
}

double amp_ring_area(const amp_vec2 *p, size_t n)
{
    double s = 0.0;
    size_t i;
    if (n < 3)
        return 0.0;
    /* shoelace relative to p[0] to limit cancellation far from the origin */
    for (i = 1; i + 1 < n; i++)
        s += amp_v2_orient(p[0], p[i], p[i + 1]);
    return 0.5 * s;
}

void amp_ring_reverse(amp_vec2 *p, size_t n)
{
    size_t i;
    for (i = 0; i < n / 2; i++) {
        amp_vec2 t = p[i];
        p[i] = p[n - 1 - i];
        p[n - 1 - i] = t;
    }
}

int amp_ring_contains(const amp_vec2 *p, size_t n, amp_vec2 q, double tol)
{
    size_t i, j;
    int in = 0;
    for (i = 0, j = n - 1; i < n; j = i++) {
        amp_vec2 a = p[j], b = p[i];
        /* the distance only matters near the segment's box (tol = 0: on it) */
        if (q.y >= fmin(a.y, b.y) - tol && q.y <= fmax(a.y, b.y) + tol && q.x >= fmin(a.x, b.x) - tol &&
            q.x <= fmax(a.x, b.x) + tol && seg_dist2(q, a, b) <= tol * tol)
            return -1;
        /* half-open rule on y: each crossing counted once even at vertices */
        if ((a.y > q.y) != (b.y > q.y)) {
            double x = a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if (q.x < x)
                in = !in;
        }
    }
    return in;
}

int amp_polyset_contains(const amp_polyset *ps, amp_vec2 q, double tol)
{
    size_t i;
    int in = 0;
    for (i = 0; i < ps->nrings; i++) {
        int c = amp_ring_contains(amp_polyset_ring(ps, i), ps->rings[i].n, q, tol);
        if (c < 0)
            return -1;
        in ^= c;
    }
    return in;
}

double amp_polyset_area(const amp_polyset *ps)
{
    double s = 0.0;
    size_t i;
    for (i = 0; i < ps->nrings; i++)
        s += amp_ring_area(amp_polyset_ring(ps, i), ps->rings[i].n);
    return s;
}

double amp_polyset_boundary_dist(const amp_polyset *ps, amp_vec2 q)
{
    double best = HUGE_VAL;
    size_t i, k;
    for (i = 0; i < ps->nrings; i++) {
        const amp_vec2 *p = amp_polyset_ring(ps, i);
        size_t n = ps->rings[i].n;
        for (k = 0; k < n; k++) {
            double d = seg_dist2(q, p[k], p[(k + 1) % n]);
            if (d < best)
                best = d;
        }
    }
    return sqrt(best);
}

/* ---- islands ---- */

/* Bounding box of ring r: [0] min, [1] max. */
static void ring_box(const amp_polyset *ps, size_t r, amp_vec2 *box)
{
    const amp_vec2 *p = amp_polyset_ring(ps, r);
    size_t k;
    box[0] = box[1] = p[0];
    for (k = 1; k < ps->rings[r].n; k++) {
        box[0] = amp_v2(fmin(box[0].x, p[k].x), fmin(box[0].y, p[k].y));
        box[1] = amp_v2(fmax(box[1].x, p[k].x), fmax(box[1].y, p[k].y));
    }
}

static int in_box(const amp_vec2 *box, amp_vec2 q)
{
    return q.x >= box[0].x && q.x <= box[1].x && q.y >= box[0].y && q.y <= box[1].y;
}

/* A point strictly inside or outside every other ring, for nesting tests:
 * first a vertex, else an edge midpoint pushed slightly inward. A ring
 * whose box does not hold the point cannot touch it (a layer of 400 pins
 * tested every pin against every other one). */
static amp_vec2 ring_probe(const amp_polyset *ps, const amp_vec2 *box, size_t r)
{
    const amp_vec2 *p = amp_polyset_ring(ps, r);
    size_t n = ps->rings[r].n, k, i;
    for (k = 0; k < n; k++) {
        int ok = 1;
        for (i = 0; i < ps->nrings && ok; i++)
            if (i != r && in_box(box + 2 * i, p[k]) &&
                amp_ring_contains(amp_polyset_ring(ps, i), ps->rings[i].n, p[k], 0.0) < 0)
                ok = 0;
        if (ok)
            return p[k];
    }
    return amp_v2(0.5 * (p[0].x + p[1].x), 0.5 * (p[0].y + p[1].y));
}

amp_status amp_polyset_organize(amp_polyset *ps, amp_error *err)
{
    size_t n = ps->nrings, i, j, k, nout = 0, npts = 0;
    long *parent = NULL, *depth = NULL, nis = 0;
    double *area = NULL;
    amp_ring *rings = NULL;
    amp_vec2 *pts = NULL, *box = NULL;
    if (n == 0) {
        ps->nislands = 0;
        return AMP_OK;
    }
    parent = amp_calloc(ps->alloc, n, sizeof *parent);
    depth = amp_calloc(ps->alloc, n, sizeof *depth);
    area = amp_calloc(ps->alloc, n, sizeof *area);
    rings = amp_calloc(ps->alloc, n, sizeof *rings);
    pts = amp_calloc(ps->alloc, ps->npts ? ps->npts : 1, sizeof *pts);
    box = amp_calloc(ps->alloc, 2 * n, sizeof *box);
    if (!parent || !depth || !area || !rings || !pts || !box) {
        amp_free(ps->alloc, parent);
        amp_free(ps->alloc, depth);
        amp_free(ps->alloc, area);
        amp_free(ps->alloc, rings);
        amp_free(ps->alloc, pts);
        amp_free(ps->alloc, box);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory organising polygons");
    }
    for (i = 0; i < n; i++) {
        area[i] = amp_ring_area(amp_polyset_ring(ps, i), ps->rings[i].n);
        ring_box(ps, i, box + 2 * i);
    }
    /* nesting: depth = number of rings containing the ring, parent = the
     * smallest of them (rings do not cross, so one probe point decides) */
    for (i = 0; i < n; i++) {
        amp_vec2 q = ring_probe(ps, box, i);
        parent[i] = -1;
        depth[i] = 0;
        for (j = 0; j < n; j++) {
            if (j == i || fabs(area[j]) < fabs(area[i]) || !in_box(box + 2 * j, q))
                continue;
            if (amp_ring_contains(amp_polyset_ring(ps, j), ps->rings[j].n, q, 0.0) == 1) {
                depth[i]++;
                if (parent[i] < 0 || fabs(area[j]) < fabs(area[parent[i]]))
                    parent[i] = (long)j;
            }
        }
    }
    /* outer rings (even depth) open islands; each hole follows its parent */
    for (i = 0; i < n; i++) {
        if (depth[i] % 2)
            continue;
        for (k = 0; k <= n; k++) {
            size_t r = k == 0 ? i : k - 1;
            const amp_vec2 *src;
            int hole = k != 0;
            if (k != 0 && !(depth[r] % 2 == 1 && parent[r] == (long)i))
                continue;
            src = amp_polyset_ring(ps, r);
            memcpy(pts + npts, src, ps->rings[r].n * sizeof *pts);
            /* outer boundaries counter-clockwise, holes clockwise (docs/interfaces.md §4) */
            if ((area[r] < 0) != hole)
                amp_ring_reverse(pts + npts, ps->rings[r].n);
            rings[nout].first = npts;
            rings[nout].n = ps->rings[r].n;
            rings[nout].island = nis;
            rings[nout].hole = hole;
            npts += ps->rings[r].n;
            nout++;
        }
        nis++;
    }
    memcpy(ps->pts, pts, npts * sizeof *pts);
    memcpy(ps->rings, rings, nout * sizeof *rings);
    ps->nrings = nout;
    ps->npts = npts;
    ps->nislands = (size_t)nis;
    amp_free(ps->alloc, parent);
    amp_free(ps->alloc, depth);
    amp_free(ps->alloc, area);
    amp_free(ps->alloc, rings);
    amp_free(ps->alloc, pts);
    amp_free(ps->alloc, box);
    return AMP_OK;
}

/* ---- convex hull ---- */

static int cmp_pt(const void *a, const void *b)
{
    const amp_vec2 *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    if (p->y != q->y)
        return p->y < q->y ? -1 : 1;
    return 0;
}

amp_status amp_convex_hull(const amp_vec2 *pts, size_t n, const amp_allocator *a, amp_vec2 *out, size_t *nout,
                           amp_error *err)
{
    amp_vec2 *s, *h;
    size_t i, k = 0, lo;
    *nout = 0;
    if (n == 0)
        return AMP_OK;
    s = amp_alloc(a, n * sizeof *s);
    h = amp_alloc(a, (2 * n + 1) * sizeof *h);
    if (!s || !h) {
        amp_free(a, s);
        amp_free(a, h);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the convex hull");
    }
    memcpy(s, pts, n * sizeof *s);
    if (n > 1)
        qsort(s, n, sizeof *s, cmp_pt);
    /* Andrew's monotone chain: lower hull then upper hull, dropping
     * collinear points (orient <= 0) */
    for (i = 0; i < n; i++) {
        while (k >= 2 && amp_v2_orient(h[k - 2], h[k - 1], s[i]) <= 0)
            k--;
        h[k++] = s[i];
    }
    lo = k + 1;
    for (i = n - 1; i-- > 0;) {
        while (k >= lo && amp_v2_orient(h[k - 2], h[k - 1], s[i]) <= 0)
            k--;
        h[k++] = s[i];
    }
    if (k > 1)
        k--; /* last point repeats the first */
    if (k > n)
        k = n;
    memcpy(out, h, k * sizeof *out);
    *nout = k;
    amp_free(a, s);
    amp_free(a, h);
    return AMP_OK;
}

amp_status amp_polyset_island(const amp_polyset *P, size_t k, amp_polyset *out, amp_error *err)
{
    size_t r;
    amp_status st = AMP_OK;
    amp_polyset_clear(out);
    for (r = 0; r < P->nrings && st == AMP_OK; r++)
        if (P->rings[r].island == (long)k)
            st = amp_polyset_add(out, amp_polyset_ring(P, r), P->rings[r].n, err);
    if (st == AMP_OK)
        st = amp_polyset_organize(out, err);
    return st;
}
