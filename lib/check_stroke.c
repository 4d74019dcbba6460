/* Independent checker of continuous strokes ([P2 §4]: no crossovers,
 * every edge once, inside the polygon). Shares no code with lib/contpath.c. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/check.h"
#include "keysort.h"

typedef struct ekey2 {
    size_t a, b;
    amp_vec2 at;
} ekey2;

typedef struct seg2 {
    amp_vec2 a, b;
    size_t ia, ib;
    double xmin, ymin, ymax;
    int pseudo; /* travel inside the stroke: no material */
} seg2;

static int sgn(double v) { return (v > 0) - (v < 0); }

/* Proper crossing or collinear overlap of two segments without a shared end. */
static int seg_conflict(const seg2 *s, const seg2 *t)
{
    int o1 = sgn(amp_v2_orient(s->a, s->b, t->a)), o2 = sgn(amp_v2_orient(s->a, s->b, t->b));
    int o3 = sgn(amp_v2_orient(t->a, t->b, s->a)), o4 = sgn(amp_v2_orient(t->a, t->b, s->b));
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return 1;
    /* a pseudo edge deposits nothing: it may run over material, only a
     * proper crossing makes the stroke cross itself */
    if (s->pseudo || t->pseudo)
        return 0;
    if (o1 == 0 && o2 == 0) {
        /* collinear: overlapping interiors print material twice */
        double dx = s->b.x - s->a.x, dy = s->b.y - s->a.y;
        double u0 = (t->a.x - s->a.x) * dx + (t->a.y - s->a.y) * dy, u1 = (t->b.x - s->a.x) * dx + (t->b.y - s->a.y) * dy;
        double l2 = dx * dx + dy * dy;
        return fmax(fmin(u0, u1), 0.0) < fmin(fmax(u0, u1), l2);
    }
    /* an end of one segment in the interior of the other (T-junction) */
    if ((o1 == 0 && o3 * o4 < 0) || (o2 == 0 && o3 * o4 < 0) || (o3 == 0 && o1 * o2 < 0) || (o4 == 0 && o1 * o2 < 0))
        return 1;
    return 0;
}

/* Is angle c strictly inside the CCW arc from a to b? */
static int in_arc(double a, double b, double c)
{
    double w = 2.0 * AMP_PI;
    double ab = fmod(b - a + 2 * w, w), ac = fmod(c - a + 2 * w, w);
    return ac > 0 && ac < ab;
}

typedef struct pass {
    size_t v;
    amp_vec2 at;
    double in, out;
} pass;

/* Rows in y of the region's segments, so a point test scans one row. */
typedef struct yrows {
    double y0, h;
    long nrow;
    size_t *start, *item;
    amp_vec2 *a, *b;
} yrows;

static long row_of(const yrows *y, double v)
{
    long k = (long)floor((v - y->y0) / y->h);
    return k < 0 ? 0 : (k >= y->nrow ? y->nrow - 1 : k);
}

static void yrows_free(const amp_allocator *al, yrows *y)
{
    amp_free(al, y->start);
    amp_free(al, y->item);
    amp_free(al, y->a);
    amp_free(al, y->b);
}

/* The rows of the region's segments whose y-range meets [wy0, wy1], the
 * band of the stroke: every crossing of a query's ray in that band is among
 * them (a layer of 400 pins built all 400 rings for each pin's stroke). */
static int yrows_build(yrows *y, const amp_polyset *R, double wy0, double wy1, const amp_allocator *al)
{
    size_t r, k, id = 0, round, n;
    double y1 = -HUGE_VAL;
    memset(y, 0, sizeof *y);
    y->y0 = HUGE_VAL;
    y->a = amp_alloc(al, (R->npts + 1) * sizeof *y->a);
    y->b = amp_alloc(al, (R->npts + 1) * sizeof *y->b);
    if (!y->a || !y->b)
        return 0;
    for (r = 0; r < R->nrings; r++) {
        const amp_vec2 *p = amp_polyset_ring(R, r);
        size_t m = R->rings[r].n;
        for (k = 0; k < m; k++) {
            amp_vec2 a = p[k], b = p[(k + 1) % m];
            if (fmax(a.y, b.y) < wy0 || fmin(a.y, b.y) > wy1)
                continue;
            y->a[id] = a;
            y->b[id++] = b;
            y->y0 = fmin(y->y0, fmin(a.y, b.y));
            y1 = fmax(y1, fmax(a.y, b.y));
        }
    }
    n = id;
    if (n == 0) { /* nothing in the band: every query is outside */
        y->y0 = wy0;
        y1 = wy1;
    }
    y->nrow = 4 * (long)sqrt((double)n) + 1; /* rows of about sqrt(n) / 4 edges: a query scans one or two */
    y->h = fmax((y1 - y->y0) / (double)y->nrow, 1e-12);
    y->start = amp_calloc(al, (size_t)y->nrow + 1, sizeof *y->start);
    if (!y->start)
        return 0;
    for (round = 0; round < 2; round++) {
        for (id = 0; id < n; id++) {
            long r0 = row_of(y, fmin(y->a[id].y, y->b[id].y)), r1 = row_of(y, fmax(y->a[id].y, y->b[id].y)), q;
            for (q = r0; q <= r1; q++) {
                if (round == 0)
                    y->start[q + 1]++;
                else
                    y->item[y->start[q]++] = id;
            }
        }
        if (round == 0) {
            for (k = 0; k < (size_t)y->nrow; k++)
                y->start[k + 1] += y->start[k];
            y->item = amp_alloc(al, (y->start[y->nrow] + 1) * sizeof *y->item);
            if (!y->item)
                return 0;
        }
    }
    for (k = (size_t)y->nrow; k > 0; k--)
        y->start[k] = y->start[k - 1];
    y->start[0] = 0;
    return 1;
}

static double dist2(amp_vec2 q, amp_vec2 a, amp_vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy, t = 0, ex, ey;
    if (l2 > 0)
        t = amp_dmin(amp_dmax(((q.x - a.x) * dx + (q.y - a.y) * dy) / l2, 0.0), 1.0);
    ex = a.x + t * dx - q.x;
    ey = a.y + t * dy - q.y;
    return ex * ex + ey * ey;
}

/* 0 outside, 1 inside (even-odd, half-open crossing rule), -1 within tol
 * of the boundary. */
static int yrows_contains(const yrows *y, amp_vec2 q, double tol)
{
    long r0 = row_of(y, q.y - tol), r1 = row_of(y, q.y + tol), r, rq = row_of(y, q.y);
    size_t k;
    int in = 0;
    for (r = r0; r <= r1; r++)
        for (k = y->start[r]; k < y->start[r + 1]; k++) {
            amp_vec2 a = y->a[y->item[k]], b = y->b[y->item[k]];
            /* a segment within tol is within 2 tol of q in x (whatever the rounding): most are not */
            if ((q.x < a.x - 2 * tol && q.x < b.x - 2 * tol) || (q.x > a.x + 2 * tol && q.x > b.x + 2 * tol))
                continue;
            if (dist2(q, a, b) <= tol * tol)
                return -1;
        }
    for (k = y->start[rq]; k < y->start[rq + 1]; k++) {
        amp_vec2 a = y->a[y->item[k]], b = y->b[y->item[k]];
        if ((a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y))
            in = !in;
    }
    return in;
}

amp_status amp_check_stroke(const amp_vec2 *pts, size_t n, const amp_polyset *region, double tol,
                            amp_stroke_report *rep, amp_error *err)
{
    return amp_check_stroke_radii(pts, NULL, n, region, tol, rep, err);
}

/* One stroke under check: its points, vertex ids (identical coordinates = the same vertex), the findings. */
typedef struct stroke_scan {
    const amp_allocator *al;
    const amp_vec2 *pts;
    const double *rad;
    size_t n;
    size_t *id;
    amp_stroke_report r;
    amp_vec2 where; /* first violation, for the message */
    int found;
} stroke_scan;

static void note(stroke_scan *s, amp_vec2 at)
{
    if (!s->found++)
        s->where = at;
}

/* id[i]: the same number for points with identical coordinates. */
static void vertex_ids(stroke_scan *s, amp_skey *vk, amp_skey *tmp)
{
    size_t i, nid = 0;
    for (i = 0; i < s->n; i++) {
        vk[i].k1 = s->pts[i].x;
        vk[i].k2 = s->pts[i].y;
        vk[i].i = i;
    }
    amp_skey_sort(vk, tmp, s->n);
    for (i = 0; i < s->n; i++) {
        if (i && (vk[i].k1 != vk[i - 1].k1 || vk[i].k2 != vk[i - 1].k2))
            nid++;
        s->id[vk[i].i] = nid;
    }
}

/* The non-degenerate segments into @p sg (returns their number); printed edges printed twice are counted. */
static size_t segments_and_repeats(stroke_scan *s, seg2 *sg, ekey2 *ek, amp_skey *key, amp_skey *tmp)
{
    const amp_vec2 *pts = s->pts;
    const size_t *id = s->id;
    size_t i, ns = 0, ne = 0;
    for (i = 0; i + 1 < s->n; i++) {
        if (id[i] == id[i + 1])
            continue;
        sg[ns].a = pts[i];
        sg[ns].b = pts[i + 1];
        sg[ns].ia = id[i];
        sg[ns].ib = id[i + 1];
        sg[ns].xmin = amp_dmin(pts[i].x, pts[i + 1].x);
        sg[ns].ymin = amp_dmin(pts[i].y, pts[i + 1].y);
        sg[ns].ymax = amp_dmax(pts[i].y, pts[i + 1].y);
        sg[ns].pseudo = s->rad && s->rad[i] == 0 && s->rad[i + 1] == 0;
        if (sg[ns].pseudo)
            s->r.pseudo++;
        else {
            /* only material counts as printed twice */
            ek[ne].a = id[i] < id[i + 1] ? id[i] : id[i + 1];
            ek[ne].b = id[i] < id[i + 1] ? id[i + 1] : id[i];
            ek[ne].at = pts[i];
            ne++;
        }
        ns++;
    }
    s->r.segments = ns;
    for (i = 0; i < ne; i++) {
        key[i].k1 = (double)ek[i].a; /* vertex ids < n: exact in a double */
        key[i].k2 = (double)ek[i].b;
        key[i].i = i;
    }
    amp_skey_sort(key, tmp, ne);
    for (i = 1; i < ne; i++)
        if (key[i].k1 == key[i - 1].k1 && key[i].k2 == key[i - 1].k2) {
            s->r.repeated_edges++;
            note(s, ek[key[i].i].at);
        }
    return ns;
}

/* Strip of height @p h from @p y0 (of @p nq) that holds @p y. */
static long strip_of(double y, double y0, double h, long nq)
{
    double f = (y - y0) / h;
    return !(f > 0.0) ? 0 : f >= (double)(nq - 1) ? nq - 1 : (long)f;
}

/* The conflicts between the segments sg[list[0 .. m)] (ascending positions in the x order; NULL: sg[0 .. m))
 * whose y overlap begins in strip @p q of @p nq (every pair once: in the strip of the higher of their lows);
 * *cnt counts them, *bi, *bj the first pair in the order of one sweep over all. */
static void strip_conflicts(const seg2 *sg, const size_t *list, size_t m, long q, long nq, double y0, double h,
                            size_t *cnt, size_t *bi, size_t *bj)
{
    size_t a, b;
    for (a = 0; a < m; a++) {
        size_t ia = list ? list[a] : a;
        const seg2 *si = &sg[ia];
        double xmax = amp_dmax(si->a.x, si->b.x);
        for (b = a + 1; b < m && sg[list ? list[b] : b].xmin <= xmax; b++) {
            size_t ib = list ? list[b] : b;
            const seg2 *sj = &sg[ib];
            if (sj->ymin > si->ymax || sj->ymax < si->ymin)
                continue;
            if (nq > 1 && strip_of(amp_dmax(si->ymin, sj->ymin), y0, h, nq) != q)
                continue; /* counted in another strip */
            if (si->ia == sj->ia || si->ia == sj->ib || si->ib == sj->ia || si->ib == sj->ib)
                continue;
            if (seg_conflict(si, sj) && (!(*cnt)++ || ia < *bi || (ia == *bi && ib < *bj))) {
                *bi = ia;
                *bj = ib;
            }
        }
    }
}

/*
 * Segment pairs without a shared vertex that cross or overlap (@p sg0 sorted
 * by xmin into @p sg). A sweep over x meets every pair whose x ranges overlap:
 * in a wide solid skin that is every segment of a column, quadratic in the
 * width (the stroke check was a third of slicing a 400 mm plate). So the
 * sweep runs in horizontal strips of about sqrt(n) segments' height, each
 * segment in the strips its y range covers, and a pair counts only in the
 * strip where its y overlap begins: the same pairs, each once, in time about
 * linear. Without memory for the strips, or when the segments are mostly
 * tall, one strip (the plain sweep).
 */
static void count_crossings(stroke_scan *s, const seg2 *sg0, size_t ns, amp_skey *key, amp_skey *tmp, seg2 *sg)
{
    size_t i, cnt = 0, bi = 0, bj = 0, *start = NULL, *list = NULL;
    long nq = ns > 64 ? (long)sqrt((double)ns) : 1, q;
    double y0 = HUGE_VAL, y1 = -HUGE_VAL, h;
    for (i = 0; i < ns; i++) {
        key[i].k1 = sg0[i].xmin;
        key[i].k2 = 0.0;
        key[i].i = i;
        y0 = amp_dmin(y0, sg0[i].ymin);
        y1 = amp_dmax(y1, sg0[i].ymax);
    }
    amp_skey_sort(key, tmp, ns);
    for (i = 0; i < ns; i++)
        sg[i] = sg0[key[i].i];
    nq = nq > 65536 ? 65536 : nq;
    h = y1 > y0 ? (y1 - y0) / (double)nq : 1.0;
    if (nq > 1 && (start = amp_calloc(s->al, (size_t)nq + 2, sizeof *start)) != NULL) {
        int fill;
        for (fill = 0; fill < 2 && start; fill++) {
            for (i = 0; i < ns; i++)
                for (q = strip_of(sg[i].ymin, y0, h, nq); q <= strip_of(sg[i].ymax, y0, h, nq); q++) {
                    if (fill)
                        list[start[q + 1]++] = i;
                    else
                        start[q + 2]++;
                }
            if (!fill) {
                for (q = 0; q < nq; q++)
                    start[q + 2] += start[q + 1];
                /* tall segments through many strips (up to n sqrt n entries) are what the plain sweep is
                 * good at: then no strips */
                if (start[nq + 1] > 16 * ns + 4096 ||
                    !(list = amp_alloc(s->al, (start[nq + 1] + 1) * sizeof *list))) {
                    amp_free(s->al, start);
                    start = NULL;
                }
            }
        }
    }
    if (start) {
        for (q = 0; q < nq; q++)
            strip_conflicts(sg, list + start[q], start[q + 1] - start[q], q, nq, y0, h, &cnt, &bi, &bj);
    } else {
        strip_conflicts(sg, NULL, ns, 0, 1, y0, h, &cnt, &bi, &bj);
    }
    amp_free(s->al, start);
    amp_free(s->al, list);
    if (cnt) {
        s->r.crossings += cnt;
        note(s, sg[bi].a); /* the place a sweep over all would have met first */
    }
}

/* Passes through a vertex visited more than once must not interleave in the cyclic order of directions. */
static void count_interleaved_passes(stroke_scan *s, pass *ps, amp_skey *key, amp_skey *tmp)
{
    const amp_vec2 *pts = s->pts;
    const size_t *id = s->id;
    size_t i, j, n = s->n, np = 0;
    for (i = 0; i < n; i++) {
        size_t a = i, b = i;
        if (i == 0 || i == n - 1) {
            if (!s->r.closed || i == n - 1)
                continue;
            a = n - 1;
        }
        while (a > 0 && id[a - 1] == id[i])
            a--;
        while (b + 1 < n && id[b + 1] == id[i])
            b++;
        if (a == 0 || b + 1 >= n || b != i)
            continue;
        ps[np].v = id[i];
        ps[np].at = pts[i];
        ps[np].in = atan2(pts[a - 1].y - pts[i].y, pts[a - 1].x - pts[i].x);
        ps[np].out = atan2(pts[b + 1].y - pts[i].y, pts[b + 1].x - pts[i].x);
        np++;
    }
    for (i = 0; i < np; i++) {
        key[i].k1 = (double)ps[i].v;
        key[i].k2 = 0.0;
        key[i].i = i;
    }
    amp_skey_sort(key, tmp, np);
    for (i = 0; i < np; i++) {
        const pass *pi = &ps[key[i].i];
        for (j = i + 1; j < np && ps[key[j].i].v == pi->v; j++) {
            const pass *pj = &ps[key[j].i];
            int c1 = in_arc(pi->in, pi->out, pj->in), c2 = in_arc(pi->in, pi->out, pj->out);
            if (pj->in != pi->in && pj->in != pi->out && pj->out != pi->in && pj->out != pi->out && c1 != c2) {
                s->r.crossings++;
                note(s, pi->at);
            }
        }
    }
}

/* Every vertex and segment midpoint inside the region or within tol of it. */
static void count_outside(stroke_scan *s, const yrows *yr, double tol)
{
    const amp_vec2 *pts = s->pts;
    size_t i;
    for (i = 0; i < s->n; i++) {
        if (yrows_contains(yr, pts[i], tol) == 0) {
            s->r.outside++;
            note(s, pts[i]);
        }
        if (i + 1 < s->n) {
            amp_vec2 mid = amp_v2(0.5 * (pts[i].x + pts[i + 1].x), 0.5 * (pts[i].y + pts[i + 1].y));
            if (yrows_contains(yr, mid, tol) == 0) {
                s->r.outside++;
                note(s, mid);
            }
        }
    }
}

/* The band of y the stroke spans: [*lo, *hi]. */
static void band_of(const amp_vec2 *pts, size_t n, double *lo, double *hi)
{
    size_t i;
    *lo = HUGE_VAL;
    *hi = -HUGE_VAL;
    for (i = 0; i < n; i++) {
        *lo = fmin(*lo, pts[i].y);
        *hi = fmax(*hi, pts[i].y);
    }
}

amp_status amp_check_stroke_radii(const amp_vec2 *pts, const double *rad, size_t n, const amp_polyset *region,
                                  double tol, amp_stroke_report *rep, amp_error *err)
{
    const amp_allocator *al = region ? region->alloc : NULL;
    stroke_scan s;
    amp_skey *key = NULL, *tmp = NULL;
    seg2 *sg = NULL, *by_x = NULL;
    ekey2 *ek = NULL;
    pass *ps = NULL;
    amp_status st = AMP_OK;
    yrows yr;
    double lo = 0, hi = 0;
    if (!pts && n)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_check_stroke: NULL points");
    memset(&s, 0, sizeof s);
    memset(&yr, 0, sizeof yr);
    s.al = al;
    s.pts = pts;
    s.rad = rad;
    s.n = n;
    if (n > 0) {
        key = amp_alloc(al, n * sizeof *key);
        tmp = amp_alloc(al, n * sizeof *tmp);
        s.id = amp_alloc(al, n * sizeof *s.id);
        sg = amp_alloc(al, n * sizeof *sg);
        by_x = amp_alloc(al, n * sizeof *by_x);
        ek = amp_alloc(al, n * sizeof *ek);
        ps = amp_alloc(al, n * sizeof *ps);
        if (!key || !tmp || !s.id || !sg || !by_x || !ek || !ps)
            st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking a stroke");
    }
    if (n > 0 && st == AMP_OK) {
        s.r.closed = n > 1 && pts[0].x == pts[n - 1].x && pts[0].y == pts[n - 1].y;
        vertex_ids(&s, key, tmp);
        count_crossings(&s, sg, segments_and_repeats(&s, sg, ek, key, tmp), key, tmp, by_x);
        count_interleaved_passes(&s, ps, key, tmp);
        if (region && region->npts)
            band_of(pts, n, &lo, &hi);
        if (region && region->npts && !yrows_build(&yr, region, lo - tol, hi + tol, al))
            st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking a stroke");
        else if (region && region->npts)
            count_outside(&s, &yr, tol);
    }
    if (st == AMP_OK && (s.r.crossings || s.r.repeated_edges || s.r.outside))
        st = amp_fail(err, AMP_ERR_CHECK, 0,
                      "stroke: %lu crossings, %lu edges printed twice, %lu points outside (first near %.6g, %.6g)",
                      (unsigned long)s.r.crossings, (unsigned long)s.r.repeated_edges, (unsigned long)s.r.outside,
                      s.where.x, s.where.y);
    amp_free(al, key);
    amp_free(al, tmp);
    amp_free(al, s.id);
    amp_free(al, sg);
    amp_free(al, by_x);
    amp_free(al, ek);
    amp_free(al, ps);
    yrows_free(al, &yr);
    if (rep)
        *rep = s.r;
    return st;
}

amp_status amp_check_path_stroke(const amp_pathset *ps, size_t i, const amp_polyset *region, double tol,
                                 amp_stroke_report *rep, amp_error *err)
{
    const amp_pvert *v;
    size_t n, k;
    amp_vec2 *p;
    double *r;
    amp_status st;
    if (!ps || i >= ps->npaths)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_check_path_stroke: no path %lu", (unsigned long)i);
    v = amp_pathset_path_verts(ps, i);
    n = ps->paths[i].n;
    p = amp_alloc(ps->alloc, (n + 1) * sizeof *p);
    r = amp_alloc(ps->alloc, (n + 1) * sizeof *r);
    if (!p || !r) {
        amp_free(ps->alloc, p);
        amp_free(ps->alloc, r);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking a stroke");
    }
    for (k = 0; k < n; k++) {
        p[k] = amp_v2(v[k].p.x, v[k].p.y);
        r[k] = v[k].r;
    }
    st = amp_check_stroke_radii(p, r, n, region, tol, rep, err);
    amp_free(ps->alloc, p);
    amp_free(ps->alloc, r);
    return st;
}
