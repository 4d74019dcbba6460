/* Independent checker of continuous strokes (paper 2 §4: no crossovers,
 * every edge once, inside the polygon). Shares no code with lib/contpath.c. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/contpath.h"

typedef struct vkey {
    double x, y;
    size_t i;
} vkey;

static int cmp_vkey(const void *a, const void *b)
{
    const vkey *s = a, *t = b;
    if (s->x != t->x)
        return s->x < t->x ? -1 : 1;
    if (s->y != t->y)
        return s->y < t->y ? -1 : 1;
    return s->i < t->i ? -1 : (s->i > t->i ? 1 : 0);
}

typedef struct ekey2 {
    size_t a, b;
    amp_vec2 at;
} ekey2;

static int cmp_ekey2(const void *p, const void *q)
{
    const ekey2 *s = p, *t = q;
    if (s->a != t->a)
        return s->a < t->a ? -1 : 1;
    return s->b < t->b ? -1 : (s->b > t->b ? 1 : 0);
}

typedef struct seg2 {
    amp_vec2 a, b;
    size_t ia, ib;
    double xmin;
    int pseudo; /* travel inside the stroke: no material */
} seg2;

static int cmp_seg2(const void *p, const void *q)
{
    const seg2 *s = p, *t = q;
    return s->xmin < t->xmin ? -1 : (s->xmin > t->xmin ? 1 : 0);
}

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
    double w = 6.283185307179586;
    double ab = fmod(b - a + 2 * w, w), ac = fmod(c - a + 2 * w, w);
    return ac > 0 && ac < ab;
}

typedef struct pass {
    size_t v;
    amp_vec2 at;
    double in, out;
} pass;

static int cmp_pass(const void *p, const void *q)
{
    const pass *s = p, *t = q;
    return s->v < t->v ? -1 : (s->v > t->v ? 1 : 0);
}

amp_status amp_stroke_check(const amp_vec2 *pts, size_t n, const amp_polyset *region, double tol,
                            amp_stroke_report *rep, amp_error *err)
{
    return amp_stroke_check_radii(pts, NULL, n, region, tol, rep, err);
}

amp_status amp_stroke_check_radii(const amp_vec2 *pts, const double *rad, size_t n, const amp_polyset *region,
                                  double tol, amp_stroke_report *rep, amp_error *err)
{
    size_t ne = 0;
    const amp_allocator *al = region ? region->alloc : NULL;
    amp_stroke_report r;
    vkey *vk = NULL;
    size_t *id = NULL, i, j, ns = 0, np = 0, nid = 0;
    seg2 *sg = NULL;
    ekey2 *ek = NULL;
    pass *ps = NULL;
    amp_status st = AMP_OK;
    amp_vec2 where = amp_v2(0, 0); /* first violation, for the message */
    int found = 0;
    memset(&r, 0, sizeof r);
    if (n == 0)
        goto report;
    vk = amp_alloc(al, n * sizeof *vk);
    id = amp_alloc(al, n * sizeof *id);
    sg = amp_alloc(al, n * sizeof *sg);
    ek = amp_alloc(al, n * sizeof *ek);
    ps = amp_alloc(al, n * sizeof *ps);
    if (!vk || !id || !sg || !ek || !ps) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking a stroke");
        goto out;
    }
    r.closed = n > 1 && pts[0].x == pts[n - 1].x && pts[0].y == pts[n - 1].y;
    /* identical coordinates = the same vertex */
    for (i = 0; i < n; i++) {
        vk[i].x = pts[i].x;
        vk[i].y = pts[i].y;
        vk[i].i = i;
    }
    if (n > 1)
        qsort(vk, n, sizeof *vk, cmp_vkey);
    for (i = 0; i < n; i++) {
        if (i && (vk[i].x != vk[i - 1].x || vk[i].y != vk[i - 1].y))
            nid++;
        id[vk[i].i] = nid;
    }
    for (i = 0; i + 1 < n; i++) {
        if (id[i] == id[i + 1])
            continue;
        sg[ns].a = pts[i];
        sg[ns].b = pts[i + 1];
        sg[ns].ia = id[i];
        sg[ns].ib = id[i + 1];
        sg[ns].xmin = fmin(pts[i].x, pts[i + 1].x);
        sg[ns].pseudo = rad && rad[i] == 0 && rad[i + 1] == 0;
        if (sg[ns].pseudo)
            r.pseudo++;
        else {
            /* only material counts as printed twice */
            ek[ne].a = id[i] < id[i + 1] ? id[i] : id[i + 1];
            ek[ne].b = id[i] < id[i + 1] ? id[i + 1] : id[i];
            ek[ne].at = pts[i];
            ne++;
        }
        ns++;
    }
    r.segments = ns;
    if (ne > 1)
        qsort(ek, ne, sizeof *ek, cmp_ekey2);
    for (i = 1; i < ne; i++)
        if (ek[i].a == ek[i - 1].a && ek[i].b == ek[i - 1].b) {
            r.repeated_edges++;
            if (!found++)
                where = ek[i].at;
        }
    /* segment pairs, swept over x */
    if (ns > 1)
        qsort(sg, ns, sizeof *sg, cmp_seg2);
    for (i = 0; i < ns; i++) {
        double xmax = fmax(sg[i].a.x, sg[i].b.x);
        for (j = i + 1; j < ns && sg[j].xmin <= xmax; j++) {
            if (sg[i].ia == sg[j].ia || sg[i].ia == sg[j].ib || sg[i].ib == sg[j].ia || sg[i].ib == sg[j].ib)
                continue;
            if (seg_conflict(&sg[i], &sg[j])) {
                r.crossings++;
                if (!found++)
                    where = sg[i].a;
            }
        }
    }
    /* passes through a vertex visited more than once must not interleave */
    for (i = 0; i < n; i++) {
        size_t a = i, b = i;
        if (i == 0 || i == n - 1) {
            if (!r.closed || i == n - 1)
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
    if (np > 1)
        qsort(ps, np, sizeof *ps, cmp_pass);
    for (i = 0; i < np; i++)
        for (j = i + 1; j < np && ps[j].v == ps[i].v; j++) {
            int c1 = in_arc(ps[i].in, ps[i].out, ps[j].in), c2 = in_arc(ps[i].in, ps[i].out, ps[j].out);
            if (ps[j].in != ps[i].in && ps[j].in != ps[i].out && ps[j].out != ps[i].in && ps[j].out != ps[i].out &&
                c1 != c2) {
                r.crossings++;
                if (!found++)
                    where = ps[i].at;
            }
        }
    if (region)
        for (i = 0; i < n; i++) {
            if (amp_polyset_contains(region, pts[i], tol) == 0) {
                r.outside++;
                if (!found++)
                    where = pts[i];
            }
            if (i + 1 < n) {
                amp_vec2 mid = amp_v2(0.5 * (pts[i].x + pts[i + 1].x), 0.5 * (pts[i].y + pts[i + 1].y));
                if (amp_polyset_contains(region, mid, tol) == 0) {
                    r.outside++;
                    if (!found++)
                        where = mid;
                }
            }
        }
report:
    if (r.crossings || r.repeated_edges || r.outside)
        st = amp_fail(err, AMP_ERR_CHECK, 0,
                      "stroke: %lu crossings, %lu edges printed twice, %lu points outside (first near %.6g, %.6g)",
                      (unsigned long)r.crossings, (unsigned long)r.repeated_edges, (unsigned long)r.outside, where.x,
                      where.y);
out:
    amp_free(al, vk);
    amp_free(al, id);
    amp_free(al, sg);
    amp_free(al, ek);
    amp_free(al, ps);
    if (rep)
        *rep = r;
    return st;
}
