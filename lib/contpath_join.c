/* One extrusion start per island (beyond [P2]:
 * every extrusion start is a blob and a seam on the print): the perimeter
 * loops of an island and the closed strokes of its infill regions are
 * spliced into one closed stroke. Two loops X and Y that run side by side
 * (the perimeter at r and the ring of R̃ at 3r, or two perimeter loops of a
 * thin island) are joined by two parallel connectors
 * p1-q1 and p2-q2, |p1 p2| = 2r: X is run from p2 round to p1, the connector
 * to q1, Y round the long way to q2, the connector back to p2 (the stretch
 * p1 p2 of X and q1 q2 of Y is left out; the two connector beads cover it).
 * The connectors are printed; they must not cross any segment of the island,
 * which is tested before a splice is taken. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

#define JNONE 0xffffffffu

/* The loops are cyclic lists of vertices in one pool: a splice relinks a
 * handful of vertices, and the segment grid changes only there (rebuilding
 * it after every splice was a third of `slice --continuous` on many-island
 * parts). A vertex keeps the loop it was made for: its union-find root is
 * the live loop it is in now (the absorbing loop stays its set's root). */
typedef struct jvert {
    amp_pvert v;
    uint32_t next, prev;
    uint32_t loop;
    int32_t c[4]; /* the grid cells of its segment while listed (x0, y0, x1, y1); c[0] < 0: not listed */
} jvert;

typedef struct jloop {
    uint32_t head; /* where the loop is written from */
    size_t n;
    int alive;
    int wall; /* a ring of the island's section: connectors must not cross it */
} jloop;

typedef struct jcell {
    uint32_t *s; /* the vertices whose segment (s -> next) passes the cell's box */
    uint32_t n, cap;
} jcell;

/* Uniform grid over the segments of the live loops (cell >= connector length), fixed at the start: splices
 * only cut into segments, so nothing leaves its box. */
typedef struct jgrid {
    double x0, y0, cell;
    long nx, ny;
    jcell *c;
} jgrid;

typedef struct joiner {
    const amp_allocator *al;
    jvert *v;
    size_t nv, capv;
    jloop *lp;
    size_t nl;
    jgrid g;
    double r, dmax;
    uint32_t touched[16]; /* vertices whose segment a splice changed (re-listed at its end) */
    size_t ntouched;
} joiner;

static long cell_of(const jgrid *g, double v, double o, long n)
{
    long c = (long)floor((v - o) / g->cell);
    return c < 0 ? 0 : (c >= n ? n - 1 : c);
}

static void grid_free(const amp_allocator *al, jgrid *g)
{
    long i;
    for (i = 0; g->c && i < g->nx * g->ny; i++)
        amp_free(al, g->c[i].s);
    amp_free(al, g->c);
    memset(g, 0, sizeof *g);
}

/* Take the segment of vertex s out of the grid (nothing when it is not listed). */
static void grid_del(joiner *J, uint32_t s)
{
    jvert *V = &J->v[s];
    long x, y;
    if (V->c[0] < 0)
        return;
    for (y = V->c[1]; y <= V->c[3]; y++)
        for (x = V->c[0]; x <= V->c[2]; x++) {
            jcell *c = &J->g.c[y * J->g.nx + x];
            uint32_t k;
            for (k = 0; k < c->n && c->s[k] != s; k++)
                ;
            if (k < c->n)
                c->s[k] = c->s[--c->n];
        }
    V->c[0] = -1;
}

/* List the segment of vertex s in the cells of its bounding box. */
static amp_status grid_add(joiner *J, uint32_t s)
{
    jgrid *g = &J->g;
    jvert *V = &J->v[s];
    amp_vec3 a = V->v.p, b = J->v[V->next].v.p;
    long x, y;
    V->c[0] = (int32_t)cell_of(g, a.x < b.x ? a.x : b.x, g->x0, g->nx);
    V->c[2] = (int32_t)cell_of(g, a.x < b.x ? b.x : a.x, g->x0, g->nx);
    V->c[1] = (int32_t)cell_of(g, a.y < b.y ? a.y : b.y, g->y0, g->ny);
    V->c[3] = (int32_t)cell_of(g, a.y < b.y ? b.y : a.y, g->y0, g->ny);
    for (y = V->c[1]; y <= V->c[3]; y++)
        for (x = V->c[0]; x <= V->c[2]; x++) {
            jcell *c = &g->c[y * g->nx + x];
            size_t cap = c->cap;
            void *q = c->s;
            if (amp_grow(J->al, &q, &cap, (size_t)c->n + 1, sizeof *c->s) != AMP_OK)
                return AMP_ERR_NOMEM;
            c->s = q;
            c->cap = (uint32_t)cap;
            c->s[c->n++] = s;
        }
    return AMP_OK;
}

/* The grid over the bounding box of every loop, every segment listed. */
static amp_status grid_build(joiner *J)
{
    jgrid *g = &J->g;
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
    size_t i;
    amp_status st = AMP_OK;
    for (i = 0; i < J->nv; i++) {
        x0 = fmin(x0, J->v[i].v.p.x);
        y0 = fmin(y0, J->v[i].v.p.y);
        x1 = fmax(x1, J->v[i].v.p.x);
        y1 = fmax(y1, J->v[i].v.p.y);
    }
    g->cell = fmax(J->dmax, fmax(x1 - x0, y1 - y0) / 512.0);
    g->x0 = x0;
    g->y0 = y0;
    g->nx = (long)((x1 - x0) / g->cell) + 1;
    g->ny = (long)((y1 - y0) / g->cell) + 1;
    if (!(g->c = amp_calloc(J->al, (size_t)(g->nx * g->ny), sizeof *g->c)))
        return AMP_ERR_NOMEM;
    for (i = 0; i < J->nv && st == AMP_OK; i++)
        st = grid_add(J, (uint32_t)i);
    return st;
}

static amp_vec2 P2v(amp_vec3 p) { return amp_v2(p.x, p.y); }

/* The live loop vertex s is in. */
static size_t loop_of(const joiner *J, size_t *uf, uint32_t s) { return amp_uf_find(uf, J->v[s].loop); }

/* Does segment a come before segment b in the loop written from @p head? */
static int comes_before(const joiner *J, uint32_t head, uint32_t a, uint32_t b)
{
    uint32_t s;
    if (a == head || b == head)
        return a == head;
    if (J->v[a].next == b || J->v[b].next == a)
        return J->v[a].next == b;
    for (s = J->v[head].next; s != a && s != b; s = J->v[s].next)
        ;
    return s == a;
}

/* Which segment wins a tie of distances: the one met first by a scan of the
 * 3 x 3 cells row by row, each cell's segments by loop and by place in the
 * loop (the order the grid had when it was rebuilt after every splice; the
 * walls fix its box, so the cells stay the same). */
typedef struct jkey {
    long rank;
    size_t loop;
    uint32_t s;
} jkey;

static int key_before(const joiner *J, const jkey *x, const jkey *y)
{
    if (x->rank != y->rank)
        return x->rank < y->rank;
    if (x->loop != y->loop)
        return x->loop < y->loop;
    return comes_before(J, J->lp[x->loop].head, x->s, y->s);
}

/* Nearest point to q on a printed segment of a live loop other than those
 * with uf root @p skip, within dmax: loop, segment (its first vertex),
 * parameter. 0 if none. */
static int nearest(const joiner *J, size_t *uf, size_t skip, amp_vec2 q, size_t *ol, uint32_t *oi, double *ot,
                   double *od)
{
    const jgrid *g = &J->g;
    long cx = cell_of(g, q.x, g->x0, g->nx), cy = cell_of(g, q.y, g->y0, g->ny), x, y;
    double best = J->dmax;
    int found = 0;
    uint32_t k;
    jkey bk = {0, 0, 0};
    for (y = cy - 1; y <= cy + 1; y++)
        for (x = cx - 1; x <= cx + 1; x++) {
            const jcell *c;
            if (x < 0 || y < 0 || x >= g->nx || y >= g->ny)
                continue;
            c = &g->c[y * g->nx + x];
            for (k = 0; k < c->n; k++) {
                uint32_t s = c->s[k];
                const jvert *A = &J->v[s], *B = &J->v[A->next];
                size_t l = loop_of(J, uf, s);
                amp_vec2 e;
                double t, d;
                if (J->lp[l].wall || l == skip || !(A->v.r == J->r) || !(B->v.r == J->r))
                    continue; /* printed at the nominal radius: not a pseudo edge, not a corner */
                e = amp_cp_seg_offset(q, P2v(A->v.p), P2v(B->v.p), &t);
                /* clearly farther than the best (the margin covers hypot's rounding): no hypot */
                if (e.x * e.x + e.y * e.y > best * best * (1.0 + 1e-9))
                    continue;
                d = hypot(e.x, e.y);
                if (d < best || (d == best && found)) {
                    jkey key;
                    key.rank = (A->c[1] > cy - 1 ? A->c[1] - (cy - 1) : 0) * 3 + (A->c[0] > cx - 1 ? A->c[0] - (cx - 1) : 0);
                    key.loop = l;
                    key.s = s;
                    if (d == best && !key_before(J, &key, &bk))
                        continue;
                    bk = key;
                    best = d;
                    *ol = l;
                    *oi = s;
                    *ot = t;
                    found = 1;
                }
            }
        }
    *od = best;
    return found;
}

static int proper_cross(amp_vec2 a, amp_vec2 b, amp_vec2 c, amp_vec2 d)
{
    double d1 = amp_v2_orient(a, b, c), d2 = amp_v2_orient(a, b, d), d3 = amp_v2_orient(c, d, a),
           d4 = amp_v2_orient(c, d, b);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

/* Does connector a-b touch any segment of the live loops other than the
 * segments @p sa and @p sb it ends on? Touching includes passing
 * within a tiny distance of a vertex (collinear cases). */
static int connector_blocked(const joiner *J, amp_vec2 a, amp_vec2 b, uint32_t sa, uint32_t sb)
{
    const jgrid *g = &J->g;
    long cx0 = cell_of(g, amp_dmin(a.x, b.x), g->x0, g->nx), cx1 = cell_of(g, amp_dmax(a.x, b.x), g->x0, g->nx);
    long cy0 = cell_of(g, amp_dmin(a.y, b.y), g->y0, g->ny), cy1 = cell_of(g, amp_dmax(a.y, b.y), g->y0, g->ny), x, y;
    double tiny = 1e-7 * J->r;
    amp_vec3 A3 = amp_v3(a.x, a.y, 0), B3 = amp_v3(b.x, b.y, 0);
    uint32_t k;
    for (y = cy0; y <= cy1; y++)
        for (x = cx0; x <= cx1; x++) {
            const jcell *cl = &g->c[y * g->nx + x];
            for (k = 0; k < cl->n; k++) {
                uint32_t s = cl->s[k];
                amp_vec2 c = P2v(J->v[s].v.p), d = P2v(J->v[J->v[s].next].v.p);
                if (s == sa || s == sb)
                    continue;
                if (proper_cross(a, b, c, d))
                    return 1;
                /* a vertex of the island on the connector, or the
                 * connector's end on another segment */
                if (amp_v3_seg_dist2(amp_v3(c.x, c.y, 0), A3, B3, NULL) < tiny * tiny ||
                    amp_v3_seg_dist2(amp_v3(d.x, d.y, 0), A3, B3, NULL) < tiny * tiny)
                    return 1;
            }
        }
    return 0;
}

/* Point at parameter t of the segment of vertex s. */
static amp_pvert seg_point(const joiner *J, uint32_t s, double t)
{
    amp_pvert a = J->v[s].v, b = J->v[J->v[s].next].v, p;
    p.p = amp_v3_add(a.p, amp_v3_scale(amp_v3_sub(b.p, a.p), t));
    p.r = a.r;
    return p;
}

static double seg_len(const joiner *J, uint32_t s) { return amp_v3_dist(J->v[s].v.p, J->v[J->v[s].next].v.p); }

/* A splice: X is left between (sx, t1) and (sx2, t2) (forward), Y between
 * (j1, u1) and (j2, u2) (forward when ybackward, else backward); sx, sx2,
 * j1, j2 are the segments' first vertices. */
typedef struct cut {
    size_t lx, ly;
    uint32_t sx, sx2, j1, j2;
    double t1, t2, u1, u2;
    size_t xk, fw, bw; /* forward segments sx -> sx2 on X, j1 -> j2 and j2 -> j1 on Y */
    int ybackward;
} cut;

/* A new vertex of loop @p loop, unlinked (the pool has room: see splice). */
static uint32_t vnew(joiner *J, amp_pvert p, size_t loop)
{
    jvert *V = &J->v[J->nv];
    V->v = p;
    V->next = V->prev = (uint32_t)J->nv;
    V->loop = (uint32_t)loop;
    V->c[0] = -1;
    return (uint32_t)J->nv++;
}

static int same_vert(amp_pvert a, amp_pvert b) { return a.p.x == b.p.x && a.p.y == b.p.y && a.p.z == b.p.z && a.r == b.r; }

/* a's segment now ends at b: a is re-listed at the end of the splice. */
static void link(joiner *J, uint32_t a, uint32_t b)
{
    grid_del(J, a);
    J->v[a].next = b;
    J->v[b].prev = a;
    J->touched[J->ntouched++] = a;
}

/* Drop vertex s (a left-out stretch, or a repeat of the vertex before it). */
static void drop(joiner *J, uint32_t s)
{
    grid_del(J, s);
    J->v[s].loop = JNONE;
}

/* Drop the vertices after @p from up to @p to (forward); nothing when from == to. */
static void drop_stretch(joiner *J, uint32_t from, uint32_t to)
{
    while (from != to) {
        from = J->v[from].next;
        drop(J, from);
    }
}

/* Append the linked run s .. e (forward) after *tail, the run's first vertex dropped when it repeats *tail
 * (wpush's rule: the runs themselves hold no repeats); *m counts the vertices kept. */
static void append_run(joiner *J, uint32_t *tail, uint32_t s, uint32_t e, size_t len, size_t *m)
{
    if (same_vert(J->v[*tail].v, J->v[s].v)) {
        drop(J, s);
        if (s == e)
            return;
        s = J->v[s].next;
        len--;
    }
    link(J, *tail, s);
    *tail = e;
    *m += len;
}

/* Turn the run s .. e (forward) round: it then runs e .. s. Its segments are re-listed. */
static amp_status reverse_run(joiner *J, uint32_t s, uint32_t e)
{
    uint32_t x = s;
    amp_status st = AMP_OK;
    for (;;) {
        uint32_t nx = J->v[x].next;
        grid_del(J, x);
        if (x == e)
            break;
        x = nx;
    }
    for (x = s;; x = J->v[x].prev) {
        uint32_t t = J->v[x].next;
        J->v[x].next = J->v[x].prev;
        J->v[x].prev = t;
        if (x == e)
            break;
    }
    /* inner links now run e .. s; the ends are linked by the caller, which lists them */
    for (x = e; x != s && st == AMP_OK; x = J->v[x].next)
        st = grid_add(J, x);
    return st;
}

/* Splice loop Y into X (see the file comment); X becomes the joined loop,
 * written from p2: X from p2 round to p1, the connector to q1, Y the long
 * way round to q2, the connector back. Vertices that repeat the one before
 * them are dropped (and the last one when it closes onto p2). */
static amp_status splice(joiner *J, const cut *c)
{
    jloop *X = &J->lp[c->lx], *Y = &J->lp[c->ly];
    uint32_t p2, p1, q1, q2, xs = J->v[c->sx2].next, ys, ye, tail;
    size_t m = 1, k, xrun = X->n - c->xk, yrun = Y->n - (c->ybackward ? c->fw : c->bw);
    amp_status st = AMP_OK;
    J->ntouched = 0;
    p2 = vnew(J, seg_point(J, c->sx2, c->t2), c->lx);
    p1 = vnew(J, seg_point(J, c->sx, c->t1), c->lx);
    q1 = vnew(J, seg_point(J, c->j1, c->u1), c->lx);
    q2 = vnew(J, seg_point(J, c->j2, c->u2), c->lx);
    drop_stretch(J, c->sx, c->sx2);
    if (c->ybackward) {
        /* Y's run is j1 back to j2 + 1: the short stretch q1 -> q2 runs forward */
        uint32_t after = J->v[c->j2].next;
        drop_stretch(J, c->j1, c->j2);
        if ((st = reverse_run(J, after, c->j1)) != AMP_OK)
            return st;
        ys = c->j1;
        ye = after;
    } else {
        ys = J->v[c->j1].next;
        ye = c->j2;
        drop_stretch(J, c->j2, c->j1);
    }
    tail = p2;
    append_run(J, &tail, xs, c->sx, xrun, &m);
    append_run(J, &tail, p1, p1, 1, &m);
    append_run(J, &tail, q1, q1, 1, &m);
    append_run(J, &tail, ys, ye, yrun, &m);
    append_run(J, &tail, q2, q2, 1, &m);
    if (m > 1 && J->v[tail].v.p.x == J->v[p2].v.p.x && J->v[tail].v.p.y == J->v[p2].v.p.y &&
        J->v[tail].v.r == J->v[p2].v.r) {
        uint32_t t = J->v[tail].prev;
        drop(J, tail);
        tail = t;
        m--;
    }
    link(J, tail, p2);
    for (k = 0; k < J->ntouched && st == AMP_OK; k++) {
        uint32_t s = J->touched[k];
        grid_del(J, s); /* listed twice when linked twice */
        if (J->v[s].loop != JNONE)
            st = grid_add(J, s);
    }
    X->head = p2;
    X->n = m;
    Y->n = 0;
    Y->alive = 0;
    return st;
}

/* Forward segment counts (j1, u1) -> (j2, u2) and back on a loop of n
 * segments, when one of them is at most 8 (the left-out stretch of Y is
 * short); 0 when both are longer. */
static int spans(const joiner *J, size_t n, uint32_t j1, double u1, uint32_t j2, double u2, size_t *fw, size_t *bw)
{
    uint32_t s;
    size_t k;
    if (j1 == j2) {
        *fw = u2 >= u1 ? 0 : n;
        *bw = u1 >= u2 ? 0 : n;
        return 1;
    }
    for (k = 1, s = J->v[j1].next; k <= 8 && s != j2; k++)
        s = J->v[s].next;
    if (s == j2 && k <= 8) {
        *fw = k;
        *bw = n - k;
        return 1;
    }
    for (k = 1, s = J->v[j2].next; k <= 8 && s != j1; k++)
        s = J->v[s].next;
    if (s == j1 && k <= 8) {
        *bw = k;
        *fw = n - k;
        return 1;
    }
    return 0;
}

/* Length of a loop forward from (j1, u1) to (j2, u2), all the way round when (j2, u2) lies just behind; the walk
 * stops once the length passes @p cap. */
static double forward_len(const joiner *J, uint32_t j1, double u1, uint32_t j2, double u2, double cap)
{
    double len;
    uint32_t s;
    if (j1 == j2 && u2 >= u1)
        return (u2 - u1) * seg_len(J, j1);
    len = (1 - u1) * seg_len(J, j1);
    for (s = J->v[j1].next; s != j2 && len <= cap; s = J->v[s].next)
        len += seg_len(J, s);
    return len + u2 * seg_len(J, j2);
}

/* Is Y's left-out stretch the one forward from q1 to q2 (spans' fw segments)? The shorter by length: by
 * segment count, a long thin loop of few segments (two 33 mm strands of a skin band, 7 segments in all,
 * against 4 round its end) lost its strands to the splice and left a 1 mm strip of a top skin bare
 * (CGAL's fandisk). The side of at most 8 segments is measured whole, the other only as far as it
 * needs to be. */
static int leave_forward(const joiner *J, const cut *c)
{
    double f, b;
    if (c->fw <= c->bw) {
        f = forward_len(J, c->j1, c->u1, c->j2, c->u2, HUGE_VAL);
        b = forward_len(J, c->j2, c->u2, c->j1, c->u1, f);
    } else {
        b = forward_len(J, c->j2, c->u2, c->j1, c->u1, HUGE_VAL);
        f = forward_len(J, c->j1, c->u1, c->j2, c->u2, b);
    }
    return f <= b;
}

/* Segments from..from+cnt (forward) all printed at the nominal radius r? */
static int all_printed(const joiner *J, uint32_t from, size_t cnt)
{
    size_t i;
    for (i = 0; i <= cnt + 1; i++, from = J->v[from].next)
        if (!(J->v[from].v.r == J->r))
            return 0; /* a pseudo edge (0) or a corner's tip (tagged) */
    return 1;
}

/* p2: the point at arc length ell after the midpoint p1 of segment sx of a
 * loop of n segments, at most 8 segments on (*steps of them); 0 if the loop
 * turns away or is too short. */
static int second_point(const joiner *J, size_t n, uint32_t sx, double ell, uint32_t *sx2, double *t2, size_t *steps)
{
    double need = ell, len;
    uint32_t i = sx;
    size_t k;
    double t = 0.5;
    for (k = 0; k < 8 && k < n; k++) {
        double l = seg_len(J, i);
        len = l * (1 - t);
        if (len >= need) {
            *sx2 = i;
            *t2 = t + need / l;
            *steps = k;
            return 1;
        }
        need -= len;
        i = J->v[i].next;
        t = 0;
    }
    return 0;
}

/* Parameter @p u on the segment of s moved off its ends by a tenth of the
 * segment or a tenth of a bead radius, whichever is less. */
static double into_segment(const joiner *J, uint32_t s, double u)
{
    double len = seg_len(J, s);
    double m = fmin(0.1, 0.1 * J->r / fmax(len, 1e-12));
    return fmin(fmax(u, m), 1 - m);
}

/* q1 == q2: both nearest points of Y are one corner of it (a small loop, or
 * the end of a skin strip). The connectors then straddle that corner: q1
 * on the segment before it and q2 on the one after, each up to half the
 * connector spacing from the corner, in the order that keeps the two
 * connectors from crossing (spreading both over one long segment would
 * stretch a connector across the strips beside it). */
static void straddle_corner(const joiner *J, cut *c, amp_vec2 p1, amp_vec2 p2, double ell)
{
    uint32_t a = c->u1 >= 0.5 ? c->j1 : J->v[c->j1].prev, b = J->v[a].next;
    double la = seg_len(J, a), lb = seg_len(J, b);
    c->j1 = a;
    c->u1 = 1 - fmin(0.5 * ell, 0.4 * la) / fmax(la, 1e-12);
    c->j2 = b;
    c->u2 = fmin(0.5 * ell, 0.4 * lb) / fmax(lb, 1e-12);
    if (proper_cross(p1, P2v(seg_point(J, c->j1, c->u1).p), p2, P2v(seg_point(J, c->j2, c->u2).p))) {
        uint32_t j = c->j1;
        double u = c->u1;
        c->j1 = c->j2;
        c->u1 = c->u2;
        c->j2 = j;
        c->u2 = u;
    }
}

/* Try a splice of the loop holding segment sx of lx with another set. */
static int try_segment(joiner *J, size_t *uf, size_t lx, uint32_t sx, double ell, amp_status *st)
{
    double d1, d2;
    size_t l2, rx = amp_uf_find(uf, lx);
    uint32_t j2;
    amp_vec2 p1, p2, q1, q2;
    cut c;
    c.lx = lx;
    c.sx = sx;
    c.t1 = 0.5;
    if (seg_len(J, sx) < 1e-6 * J->r || !second_point(J, J->lp[lx].n, sx, ell, &c.sx2, &c.t2, &c.xk) ||
        !all_printed(J, sx, c.xk))
        return 0;
    p1 = P2v(seg_point(J, sx, c.t1).p);
    p2 = P2v(seg_point(J, c.sx2, c.t2).p);
    if (!nearest(J, uf, rx, p1, &c.ly, &c.j1, &c.u1, &d1) || !nearest(J, uf, rx, p2, &l2, &j2, &c.u2, &d2) ||
        l2 != c.ly || d1 < 1e-3 * J->r || d2 < 1e-3 * J->r)
        return 0;
    c.j2 = j2;
    /* a nearest point at a corner of Y (its vertex cone) moves into the
     * segment: a connector ending on a vertex would touch the segment
     * before it too. The move is a tenth of a bead at most: on a long
     * segment (a skin strip) a tenth of its length would stretch the
     * connector across the strips beside it */
    c.u1 = into_segment(J, c.j1, c.u1);
    c.u2 = into_segment(J, c.j2, c.u2);
    q1 = P2v(seg_point(J, c.j1, c.u1).p);
    q2 = P2v(seg_point(J, c.j2, c.u2).p);
    if (hypot(q1.x - q2.x, q1.y - q2.y) < 1e-3 * ell)
        straddle_corner(J, &c, p1, p2, ell);
    /* the left-out stretch of Y must be short and printed throughout */
    if (!spans(J, J->lp[c.ly].n, c.j1, c.u1, c.j2, c.u2, &c.fw, &c.bw))
        return 0;
    c.ybackward = leave_forward(J, &c);
    if (!all_printed(J, c.ybackward ? c.j1 : c.j2, c.ybackward ? c.fw : c.bw))
        return 0;
    q1 = P2v(seg_point(J, c.j1, c.u1).p);
    q2 = P2v(seg_point(J, c.j2, c.u2).p);
    if (proper_cross(p1, q1, p2, q2))
        return 0;
    if (connector_blocked(J, p1, q1, sx, c.j1) || connector_blocked(J, p2, q2, c.sx2, c.j2))
        return 0;
    *st = splice(J, &c);
    if (*st == AMP_OK)
        amp_uf_union(uf, c.ly, lx);
    return 1;
}

/* Does the loop fit in a box of diagonal @p d? */
static int speck(const amp_pvert *v, size_t n, double d)
{
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
    size_t i;
    for (i = 0; i < n; i++) {
        x0 = fmin(x0, v[i].p.x);
        y0 = fmin(y0, v[i].p.y);
        x1 = fmax(x1, v[i].p.x);
        y1 = fmax(y1, v[i].p.y);
    }
    return hypot(x1 - x0, y1 - y0) < d;
}

/* Is path i of @p in a closed object loop (joined; anything else is copied
 * as it is)? */
static int closed_object(const amp_pathset *in, size_t i)
{
    const amp_pvert *v = amp_pathset_path_verts(in, i);
    size_t n = in->paths[i].n;
    return in->paths[i].role == AMP_ROLE_OBJECT && n >= 4 && v[0].p.x == v[n - 1].p.x && v[0].p.y == v[n - 1].p.y;
}

/* A new loop of the n vertices v (a repeat of the vertex before dropped: wpush's rule), a set of its own in @p uf. */
static void add_loop(joiner *J, size_t *uf, const amp_pvert *v, size_t n, int wall)
{
    jloop *L = &J->lp[J->nl];
    size_t k;
    uint32_t first = (uint32_t)J->nv, last = first;
    L->n = 0;
    for (k = 0; k < n; k++) {
        if (L->n && same_vert(J->v[last].v, v[k]))
            continue;
        last = vnew(J, v[k], J->nl);
        if (L->n) {
            J->v[last - 1].next = last;
            J->v[last].prev = last - 1;
        }
        L->n++;
    }
    J->v[last].next = first;
    J->v[first].prev = last;
    L->head = first;
    L->alive = 1;
    L->wall = wall;
    uf[J->nl] = J->nl;
    J->nl++;
}

/* The closed object loops of paths [first, npaths) of @p in into J's loops,
 * each a set of its own in @p uf; specks left out are counted in *nspeck. */
static void collect_loops(joiner *J, size_t *uf, const amp_pathset *in, size_t first, size_t *nspeck)
{
    size_t i;
    int big = 0;
    /* a loop under a bead across (r) next to larger ones is a speck: a
     * lattice piece cutting a corner of a region, too small for a splice's
     * two connectors; alone it is the island's print and stays unless under
     * r/4 */
    for (i = first; i < in->npaths && !big; i++) {
        const amp_pvert *v = amp_pathset_path_verts(in, i);
        size_t n = in->paths[i].n;
        big = in->paths[i].role == AMP_ROLE_OBJECT && n >= 4 && !speck(v, n, J->r);
    }
    for (i = first; i < in->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(in, i);
        size_t n = in->paths[i].n;
        if (!closed_object(in, i))
            continue;
        if (speck(v, n, big ? J->r : 0.25 * J->r)) {
            (*nspeck)++; /* a loop smaller than a quarter bead: inside the beads around it */
            continue;
        }
        /* the cyclic loop drops the closing vertex unless it carries
         * another radius (a tour ending on a pseudo edge) */
        add_loop(J, uf, v, v[n - 1].r == v[0].r ? n - 1 : n, 0);
    }
}

/* The section's rings, as walls in the grid: connectors may not cross them. */
static void add_walls(joiner *J, size_t *uf, const amp_polyset *walls)
{
    size_t i, k;
    for (i = 0; i < walls->nrings; i++) {
        const amp_vec2 *p = amp_polyset_ring(walls, i);
        jloop *L = &J->lp[J->nl];
        uint32_t first = (uint32_t)J->nv;
        L->n = walls->rings[i].n;
        for (k = 0; k < L->n; k++) {
            amp_pvert w;
            w.p = amp_v3(p[k].x, p[k].y, 0);
            w.r = 0;
            vnew(J, w, J->nl);
            J->v[first + k].next = (uint32_t)(k + 1 < L->n ? first + k + 1 : first);
            J->v[first + k].prev = (uint32_t)(k > 0 ? first + k - 1 : first + L->n - 1);
        }
        L->head = first;
        L->alive = L->wall = 1;
        uf[J->nl] = J->nl;
        J->nl++;
    }
}

/* Splices until one set is left or none is found: connectors 2r apart (their
 * beads just touch), closer where a loop offers no straight stretch that
 * long (small infill components). */
static amp_status splice_all(joiner *J, size_t *uf, size_t sets)
{
    size_t i, k;
    int pass, progress;
    amp_status st = AMP_OK;
    for (pass = 0; pass < 3 && sets > 1 && st == AMP_OK; pass++) {
        double ell = 2 * J->r / (double)(1 << pass);
        progress = 1;
        while (sets > 1 && progress && st == AMP_OK) {
            progress = 0;
            for (k = 0; k < J->nl && !progress && st == AMP_OK; k++) {
                uint32_t s = J->lp[k].head;
                for (i = 0; J->lp[k].alive && !J->lp[k].wall && i < J->lp[k].n && !progress && st == AMP_OK; i++) {
                    progress = try_segment(J, uf, k, s, ell, &st);
                    s = J->v[s].next;
                }
            }
            sets -= (size_t)progress;
        }
    }
    return st;
}

/* Loops the splices could not join that fit in a box of diagonal 2r (a lattice piece cutting a corner of the
 * region, 0.3 mm, too small for a splice's two connectors): dropped and counted as specks, so that the island
 * keeps one stroke (CGAL's `eight`, a layer of 2 islands and 3 strokes; the beads around cover the piece). The
 * largest loop, and any larger straggler, stay. */
static void drop_stragglers(joiner *J, size_t *nspeck)
{
    size_t k, big = (size_t)-1, alive = 0;
    for (k = 0; k < J->nl; k++)
        if (J->lp[k].alive && !J->lp[k].wall) {
            alive++;
            if (big == (size_t)-1 || J->lp[k].n > J->lp[big].n)
                big = k;
        }
    if (alive < 2)
        return;
    for (k = 0; k < J->nl; k++) {
        double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
        uint32_t s;
        size_t i;
        if (k == big || !J->lp[k].alive || J->lp[k].wall)
            continue;
        for (i = 0, s = J->lp[k].head; i < J->lp[k].n; i++, s = J->v[s].next) {
            x0 = fmin(x0, J->v[s].v.p.x);
            y0 = fmin(y0, J->v[s].v.p.y);
            x1 = fmax(x1, J->v[s].v.p.x);
            y1 = fmax(y1, J->v[s].v.p.y);
        }
        if (hypot(x1 - x0, y1 - y0) < 2.0 * J->r) {
            J->lp[k].alive = 0;
            (*nspeck)++;
        }
    }
}

/* The joined loops closed again, then the rest of @p in (open strokes,
 * support stretches) unchanged, at height @p h (> 0). */
static amp_status write_joined(const joiner *J, const amp_pathset *in, size_t first, double h, amp_pathset *out,
                               size_t *nout, amp_error *err)
{
    size_t i, k;
    amp_status st = AMP_OK;
    for (k = 0; k < J->nl && st == AMP_OK; k++) {
        const jloop *L = &J->lp[k];
        if (!L->alive || L->wall)
            continue;
        uint32_t s = L->head;
        st = amp_pathset_begin(out, AMP_ROLE_OBJECT, err);
        for (i = 0; i <= L->n && st == AMP_OK; i++, s = J->v[s].next)
            st = amp_pathset_push(out, J->v[s].v.p, J->v[s].v.r, err);
        if (st == AMP_OK && h > 0)
            st = amp_pathset_set_height(out, h, err);
        (*nout)++;
    }
    for (i = first; i < in->npaths && st == AMP_OK; i++) {
        const amp_pvert *v = amp_pathset_path_verts(in, i);
        if (closed_object(in, i))
            continue; /* joined above, or a speck */
        if ((st = amp_pathset_add(out, in->paths[i].role, v, in->paths[i].n, err)) == AMP_OK && h > 0)
            st = amp_pathset_set_height(out, h, err);
        *nout += in->paths[i].role == AMP_ROLE_OBJECT;
    }
    return st;
}

amp_status amp_cp_join_loops(const amp_pathset *in, size_t first, const amp_polyset *walls, double r, double h,
                             amp_pathset *out, size_t *nout, size_t *nspeck, amp_error *err)
{
    joiner J;
    size_t *uf = NULL, i, sets, nloops = in->npaths - first + walls->nrings + 1;
    amp_status st = AMP_OK;
    memset(&J, 0, sizeof J);
    J.al = out->alloc;
    J.r = r;
    J.dmax = 4.5 * r;
    *nout = 0;
    /* every vertex the join can make: the loops', the walls', and four per splice (at most one per loop) */
    J.capv = 4 * nloops;
    for (i = first; i < in->npaths; i++)
        J.capv += in->paths[i].n;
    for (i = 0; i < walls->nrings; i++)
        J.capv += walls->rings[i].n;
    J.lp = amp_calloc(J.al, nloops, sizeof *J.lp);
    J.v = J.capv < JNONE ? amp_alloc(J.al, J.capv * sizeof *J.v) : NULL;
    uf = amp_alloc(J.al, nloops * sizeof *uf);
    if (!J.lp || !J.v || !uf)
        st = AMP_ERR_NOMEM;
    else
        collect_loops(&J, uf, in, first, nspeck);
    sets = J.nl;
    if (st == AMP_OK && sets > 1) {
        add_walls(&J, uf, walls);
        if ((st = grid_build(&J)) == AMP_OK)
            st = splice_all(&J, uf, sets);
        if (st == AMP_OK)
            drop_stragglers(&J, nspeck);
    }
    if (st == AMP_OK)
        st = write_joined(&J, in, first, h, out, nout, err);
    amp_free(J.al, J.v);
    amp_free(J.al, J.lp);
    amp_free(J.al, uf);
    grid_free(J.al, &J.g);
    if (st == AMP_ERR_NOMEM)
        return amp_fail(err, st, 0, "out of memory joining the strokes of an island");
    return st;
}
