/* Continuous tool paths: clip K̂ per region, patch free ends, one Euler tour
 * without crossovers (continuous-toolpath-euler.txt §2.2 steps 2-6, §4). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/contpath.h"
#include "ampath/euler.h"

#define NONE ((size_t)-1)

void amp_contpath_opts_default(amp_contpath_opts *o, double r)
{
    memset(o, 0, sizeof *o);
    o->radius = r;
    o->cell = 10 * r;
    o->grid = AMP_GRID_SQUARE;
    o->offset = r;
    o->perimeters = 1;
    o->support_stretches = 0;
}

amp_status amp_contpath_complex(const amp_slices *sl, const amp_contpath_opts *o, amp_cx2 *khat, amp_error *err)
{
    const amp_allocator *al = khat->alloc;
    amp_vec2 *pts, *hull;
    size_t n = 0, nh = 0, i;
    amp_cx2 k;
    amp_euler_opts eo;
    amp_status st;
    if (!o || !(o->radius > 0) || !isfinite(o->radius))
        return amp_fail(err, AMP_ERR_ARG, 0, "extruder radius must be positive");
    for (i = 0; i < sl->nlayers; i++)
        n += sl->layers[i].polys.npts;
    if (n < 3)
        return amp_fail(err, AMP_ERR_GEOMETRY, 0, "no layer polygon to mesh");
    pts = amp_alloc(al, n * sizeof *pts);
    hull = amp_alloc(al, n * sizeof *hull);
    if (!pts || !hull) {
        amp_free(al, pts);
        amp_free(al, hull);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the hull");
    }
    for (i = 0, n = 0; i < sl->nlayers; i++) {
        if (sl->layers[i].polys.npts)
            memcpy(pts + n, sl->layers[i].polys.pts, sl->layers[i].polys.npts * sizeof *pts);
        n += sl->layers[i].polys.npts;
    }
    amp_cx2_init(&k, al);
    /* step 2: hull of the union of all layers' projections; step 3: K */
    st = amp_convex_hull(pts, n, al, hull, &nh, err);
    if (st == AMP_OK)
        st = amp_cx2_grid(&k, hull, nh, o->cell > 0 ? o->cell : 10 * o->radius, o->grid, err);
    /* step 4: K̂ with mitered offset δ = r, so that rim cells of K (outside
     * every R̃) hold all odd vertices and Class 2 strips are 2r wide */
    eo.offset = o->offset > 0 ? o->offset : o->radius;
    eo.combinatorial = 1;
    if (st == AMP_OK)
        st = amp_euler_transform(&k, &eo, khat, NULL, err);
    amp_cx2_free(&k);
    amp_free(al, pts);
    amp_free(al, hull);
    return st;
}

/* ---- the region graph ---- */

typedef struct fend {
    size_t node, ring, comp;
    double pos; /* segment index + parameter along the ring */
} fend;

typedef struct rgraph {
    const amp_allocator *al;
    amp_vec2 *v;
    size_t nv, cap_v;
    size_t *eu, *ev;
    size_t ne, cap_eu, cap_ev;
    fend *fe;
    size_t nfe, cap_fe;
} rgraph;

static amp_status g_vert(rgraph *g, amp_vec2 p, size_t *id)
{
    void *q = g->v;
    if (amp_grow(g->al, &q, &g->cap_v, g->nv + 1, sizeof *g->v) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->v = q;
    g->v[g->nv] = p;
    *id = g->nv++;
    return AMP_OK;
}

static amp_status g_edge(rgraph *g, size_t a, size_t b)
{
    void *q = g->eu, *r = g->ev;
    if (a == b)
        return AMP_OK;
    if (amp_grow(g->al, &q, &g->cap_eu, g->ne + 1, sizeof *g->eu) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->eu = q;
    if (amp_grow(g->al, &r, &g->cap_ev, g->ne + 1, sizeof *g->ev) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->ev = r;
    g->eu[g->ne] = a;
    g->ev[g->ne] = b;
    g->ne++;
    return AMP_OK;
}

static void g_free(rgraph *g)
{
    amp_free(g->al, g->v);
    amp_free(g->al, g->eu);
    amp_free(g->al, g->ev);
    amp_free(g->al, g->fe);
}

static size_t uf_find(size_t *p, size_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

static int uf_union(size_t *p, size_t a, size_t b)
{
    a = uf_find(p, a);
    b = uf_find(p, b);
    if (a == b)
        return 0;
    p[a] = b;
    return 1;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : (x > y ? 1 : 0);
}

/* Unique undirected 1-cells of K̂ as vertex pairs (lo << 32 | hi). */
static amp_status khat_edges(const amp_cx2 *k, const amp_allocator *al, uint64_t **out, size_t *n)
{
    size_t f, h, i, m = 0, w = 0;
    uint64_t *e = amp_alloc(al, (k->nfidx + k->nxe + 1) * sizeof *e);
    if (!e)
        return AMP_ERR_NOMEM;
    for (f = 0; f < k->nf; f++)
        for (h = k->fstart[f]; h < k->fstart[f + 1]; h++) {
            uint64_t a = k->fidx[h], b = k->fidx[h + 1 < k->fstart[f + 1] ? h + 1 : k->fstart[f]];
            e[m++] = a < b ? (a << 32) | b : (b << 32) | a;
        }
    for (i = 0; i < k->nxe; i++) {
        uint64_t a = k->xedge[2 * i], b = k->xedge[2 * i + 1];
        e[m++] = a < b ? (a << 32) | b : (b << 32) | a;
    }
    if (m > 1)
        qsort(e, m, sizeof *e, cmp_u64);
    for (i = 0; i < m; i++)
        if (i == 0 || e[i] != e[i - 1])
            e[w++] = e[i];
    *out = e;
    *n = w;
    return AMP_OK;
}

typedef struct hit {
    double t, pos;
    size_t ring;
} hit;

static int cmp_hit(const void *a, const void *b)
{
    const hit *x = a, *y = b;
    return x->t < y->t ? -1 : (x->t > y->t ? 1 : 0);
}

static int cmp_fend(const void *a, const void *b)
{
    const fend *x = a, *y = b;
    if (x->ring != y->ring)
        return x->ring < y->ring ? -1 : 1;
    return x->pos < y->pos ? -1 : (x->pos > y->pos ? 1 : 0);
}

/* Point at position pos (segment + parameter) of ring r. */
static amp_vec2 ring_point(const amp_polyset *R, size_t r, double pos)
{
    const amp_vec2 *p = amp_polyset_ring(R, r);
    size_t n = R->rings[r].n, s = (size_t)pos % n;
    double u = pos - floor(pos);
    amp_vec2 a = p[s], b = p[(s + 1) % n];
    return amp_v2(a.x + u * (b.x - a.x), a.y + u * (b.y - a.y));
}

/* Length along ring r from position p0 to p1 in ring direction. */
static double ring_len(const amp_polyset *R, size_t r, double p0, double p1)
{
    const amp_vec2 *p = amp_polyset_ring(R, r);
    size_t n = R->rings[r].n, s0 = (size_t)p0, s1 = (size_t)p1, s;
    double len = 0;
    amp_vec2 a = ring_point(R, r, p0), b;
    if (s1 == s0 && p1 >= p0) {
        b = ring_point(R, r, p1);
        return hypot(b.x - a.x, b.y - a.y);
    }
    for (s = (s0 + 1) % n;; s = (s + 1) % n) {
        len += hypot(p[s].x - a.x, p[s].y - a.y);
        a = p[s];
        if (s == s1)
            break;
    }
    b = ring_point(R, r, p1);
    return len + hypot(b.x - a.x, b.y - a.y);
}

/* Add the path along ring r from free end i to free end j (step 5) to the
 * graph, or to @p ps as a support path when @p ps is not NULL. */
static amp_status ring_path(rgraph *g, const amp_polyset *R, const fend *fi, const fend *fj, amp_pathset *ps,
                            double z, double rad, amp_error *err)
{
    const amp_vec2 *p = amp_polyset_ring(R, fi->ring);
    size_t n = R->rings[fi->ring].n, s0 = (size_t)fi->pos, s1 = (size_t)fj->pos, s, prev = fi->node, id;
    amp_status st;
    if (ps) {
        amp_vec2 a = g->v[fi->node], b = g->v[fj->node];
        if ((st = amp_pathset_begin(ps, AMP_ROLE_SUPPORT, err)) != AMP_OK ||
            (st = amp_pathset_push(ps, amp_v3(a.x, a.y, z), rad, err)) != AMP_OK)
            return st;
        if (!(s1 == s0 && fj->pos >= fi->pos))
            for (s = (s0 + 1) % n;; s = (s + 1) % n) {
                if ((st = amp_pathset_push(ps, amp_v3(p[s].x, p[s].y, z), rad, err)) != AMP_OK)
                    return st;
                if (s == s1)
                    break;
            }
        return amp_pathset_push(ps, amp_v3(b.x, b.y, z), rad, err);
    }
    if (!(s1 == s0 && fj->pos >= fi->pos))
        for (s = (s0 + 1) % n;; s = (s + 1) % n) {
            if (g_vert(g, p[s], &id) != AMP_OK || g_edge(g, prev, id) != AMP_OK)
                return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
            prev = id;
            if (s == s1)
                break;
        }
    if (g_edge(g, prev, fj->node) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
    return AMP_OK;
}

/* A node where edge AB crosses a ring (hit @p h), recorded as a free end. */
static amp_status free_end(rgraph *g, amp_vec2 A, amp_vec2 B, const hit *h, size_t *id)
{
    void *q = g->fe;
    if (g_vert(g, amp_v2(A.x + h->t * (B.x - A.x), A.y + h->t * (B.y - A.y)), id) != AMP_OK)
        return AMP_ERR_NOMEM;
    if (amp_grow(g->al, &q, &g->cap_fe, g->nfe + 1, sizeof *g->fe) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->fe = q;
    g->fe[g->nfe].node = *id;
    g->fe[g->nfe].ring = h->ring;
    g->fe[g->nfe].pos = h->pos;
    g->nfe++;
    return AMP_OK;
}

/* Step 5 clipping: the parts of the K̂ edges inside the region, with a node
 * of degree 1 (a free end) where an edge leaves the region. */
static amp_status clip_region(const amp_cx2 *k, const uint64_t *ke, size_t nke, const amp_polyset *R, rgraph *g,
                              amp_error *err)
{
    const amp_allocator *al = g->al;
    double bx0 = HUGE_VAL, by0 = HUGE_VAL, bx1 = -HUGE_VAL, by1 = -HUGE_VAL;
    size_t *node = NULL, i, r, s, nh, caph = 0, *deg = NULL;
    signed char *in = NULL;
    amp_vec2 *kv = NULL;
    double eps;
    hit *h = NULL;
    amp_status st = AMP_OK;
    for (i = 0; i < R->npts; i++) {
        bx0 = fmin(bx0, R->pts[i].x);
        by0 = fmin(by0, R->pts[i].y);
        bx1 = fmax(bx1, R->pts[i].x);
        by1 = fmax(by1, R->pts[i].y);
    }
    node = amp_alloc(al, (k->nv + 1) * sizeof *node);
    in = amp_alloc(al, k->nv + 1);
    kv = amp_alloc(al, (k->nv + 1) * sizeof *kv);
    if (!node || !in || !kv) {
        st = AMP_ERR_NOMEM;
        goto done;
    }
    eps = 1e-9 * (1.0 + fmax(bx1 - bx0, by1 - by0));
    for (i = 0; i < k->nv; i++) {
        amp_vec2 q = k->v[i];
        int tries;
        node[i] = NONE;
        /* a lattice vertex on a ring (CAD parts aligned with the lattice) is
         * moved off it by a few eps along a fixed oblique direction, so that
         * no vertex and no edge of K̂ lies on the boundary of the region */
        for (tries = 0; tries < 8 && q.x >= bx0 - eps && q.x <= bx1 + eps && q.y >= by0 - eps && q.y <= by1 + eps &&
                        amp_polyset_contains(R, q, eps) < 0;
             tries++)
            q = amp_v2(q.x + 2.2 * eps * 0.6, q.y + 2.2 * eps * 0.8);
        kv[i] = q;
        in[i] = q.x >= bx0 && q.x <= bx1 && q.y >= by0 && q.y <= by1 && amp_polyset_contains(R, q, 0.0) == 1;
    }
    for (i = 0; i < nke && st == AMP_OK; i++) {
        size_t a = (size_t)(ke[i] >> 32), b = (size_t)(ke[i] & 0xffffffffu), j;
        amp_vec2 A = kv[a], B = kv[b];
        size_t prevnode;
        if (fmax(A.x, B.x) < bx0 || fmin(A.x, B.x) > bx1 || fmax(A.y, B.y) < by0 || fmin(A.y, B.y) > by1)
            continue;
        nh = 0;
        /* crossings with every ring edge; a ring vertex exactly on the K̂
         * edge counts as lying on its positive side (symbolic perturbation),
         * so a crossing through it is found exactly once; a point exactly on
         * a ring is outside the region throughout */
        for (r = 0; r < R->nrings; r++) {
            const amp_vec2 *p = amp_polyset_ring(R, r);
            size_t n = R->rings[r].n;
            for (s = 0; s < n; s++) {
                amp_vec2 P = p[s], Q = p[(s + 1) % n];
                double d1, d2, d3, d4;
                if (fmax(P.x, Q.x) < fmin(A.x, B.x) || fmin(P.x, Q.x) > fmax(A.x, B.x) ||
                    fmax(P.y, Q.y) < fmin(A.y, B.y) || fmin(P.y, Q.y) > fmax(A.y, B.y))
                    continue;
                d1 = amp_v2_orient(P, Q, A);
                d2 = amp_v2_orient(P, Q, B);
                d3 = amp_v2_orient(A, B, P);
                d4 = amp_v2_orient(A, B, Q);
                /* an end of the K̂ edge on the ring counts as outside (d <= 0),
                 * like the inside test of the vertices and pieces */
                if ((d1 > 0) == (d2 > 0) || (d3 >= 0) == (d4 >= 0) || d1 == d2 || d3 == d4)
                    continue;
                {
                    void *q = h;
                    if (amp_grow(al, &q, &caph, nh + 1, sizeof *h) != AMP_OK) {
                        st = AMP_ERR_NOMEM;
                        goto done;
                    }
                    h = q;
                }
                h[nh].t = d1 / (d1 - d2);
                h[nh].pos = (double)s + fmin(fmax(d3 / (d3 - d4), 0.0), 0.999999999999);
                h[nh].ring = r;
                nh++;
            }
        }
        if (nh == 0) {
            if (!in[a] || !in[b])
                continue;
        }
        if (nh > 1)
            qsort(h, nh, sizeof *h, cmp_hit);
        /* walk the pieces; piece j runs from hit j-1 (or A) to hit j (or B) */
        prevnode = NONE;
        for (j = 0; j <= nh; j++) {
            double t0 = j ? h[j - 1].t : 0.0, t1 = j < nh ? h[j].t : 1.0;
            amp_vec2 m = amp_v2(A.x + 0.5 * (t0 + t1) * (B.x - A.x), A.y + 0.5 * (t0 + t1) * (B.y - A.y));
            size_t u, v;
            int inside = (j == 0 && nh == 0) ? 1 : amp_polyset_contains(R, m, 0.0) == 1;
            if (!inside) {
                prevnode = NONE;
                continue;
            }
            if (j == 0) {
                if (node[a] == NONE && g_vert(g, A, &node[a]) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    goto done;
                }
                u = node[a];
            } else if (prevnode != NONE)
                u = prevnode;
            else {
                if (free_end(g, A, B, &h[j - 1], &u) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    goto done;
                }
            }
            if (j == nh) {
                if (node[b] == NONE && g_vert(g, B, &node[b]) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    goto done;
                }
                v = node[b];
            } else {
                if (free_end(g, A, B, &h[j], &v) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    goto done;
                }
            }
            if (g_edge(g, u, v) != AMP_OK) {
                st = AMP_ERR_NOMEM;
                goto done;
            }
            prevnode = v;
        }
    }
    /* a crossing node shared by two inside pieces (an edge touching the ring
     * from inside) is not a free end: keep only nodes of degree 1 */
    deg = amp_calloc(al, g->nv + 1, sizeof *deg);
    if (!deg) {
        st = AMP_ERR_NOMEM;
        goto done;
    }
    for (i = 0; i < g->ne; i++) {
        deg[g->eu[i]]++;
        deg[g->ev[i]]++;
    }
    for (i = 0, s = 0; i < g->nfe; i++)
        if (deg[g->fe[i].node] == 1)
            g->fe[s++] = g->fe[i];
    g->nfe = s;
done:
    amp_free(al, node);
    amp_free(al, in);
    amp_free(al, kv);
    amp_free(al, h);
    amp_free(al, deg);
    if (st == AMP_ERR_NOMEM)
        return amp_fail(err, st, 0, "out of memory clipping the lattice");
    return st;
}

typedef struct rot_end {
    size_t end; /* 2 * edge + side */
    double ang;
} rot_end;

static int cmp_rot(const void *a, const void *b)
{
    const rot_end *x = a, *y = b;
    return x->ang < y->ang ? -1 : (x->ang > y->ang ? 1 : 0);
}

/* §4: one closed tour per connected component, never crossing itself.
 * At every vertex the edge ends are sorted by angle and paired with their
 * neighbour (a non-crossing transition system): the graph falls apart into
 * closed curves that touch without crossing (the boundary cycles). Two
 * curves meeting at a vertex in adjacent ends x, y (partners a, d) are
 * merged by re-pairing (a,x),(y,d) into (x,y),(a,d): both new transitions
 * still cross no other transition of the vertex, and the two curves become
 * one. The merges form the cycle tree; each merge alternates the direction
 * in which the child cycle is run relative to its parent. */
static amp_status euler_tours(rgraph *g, double z, double rad, amp_pathset *out, size_t *ntours, size_t *nodd,
                              amp_error *err)
{
    const amp_allocator *al = g->al;
    size_t ne2 = 2 * g->ne, i, v, *start = NULL, *partner = NULL, *curve = NULL, *uf = NULL, ncurve = 0;
    rot_end *rot = NULL;
    unsigned char *used = NULL, *isopen = NULL;
    int pass;
    amp_status st = AMP_OK;
    *ntours = 0;
    *nodd = 0;
    if (g->ne == 0)
        return AMP_OK;
    start = amp_calloc(al, g->nv + 2, sizeof *start);
    rot = amp_alloc(al, ne2 * sizeof *rot);
    partner = amp_alloc(al, ne2 * sizeof *partner);
    curve = amp_alloc(al, g->ne * sizeof *curve);
    uf = amp_alloc(al, g->ne * sizeof *uf);
    used = amp_calloc(al, g->ne, 1);
    isopen = amp_calloc(al, g->ne, 1);
    if (!start || !rot || !partner || !curve || !uf || !used || !isopen) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the tour");
        goto done;
    }
    /* rotation system: ends grouped by vertex (CSR), sorted by angle */
    for (i = 0; i < g->ne; i++) {
        start[g->eu[i] + 2]++;
        start[g->ev[i] + 2]++;
    }
    for (v = 0; v < g->nv; v++)
        start[v + 2] += start[v + 1];
    for (i = 0; i < ne2; i++) {
        size_t e = i / 2, at = i % 2 ? g->ev[e] : g->eu[e], to = i % 2 ? g->eu[e] : g->ev[e];
        rot_end *re = &rot[start[at + 1]++];
        re->end = i;
        re->ang = atan2(g->v[to].y - g->v[at].y, g->v[to].x - g->v[at].x);
    }
    for (v = 0; v < g->nv; v++) {
        size_t d = start[v + 1] - start[v], j;
        if (d > 1)
            qsort(rot + start[v], d, sizeof *rot, cmp_rot);
        for (j = 0; j + 1 < d; j += 2) {
            partner[rot[start[v] + j].end] = rot[start[v] + j + 1].end;
            partner[rot[start[v] + j + 1].end] = rot[start[v] + j].end;
        }
        if (d % 2) {
            partner[rot[start[v] + d - 1].end] = NONE; /* odd vertex: the curve ends here */
            (*nodd)++;
        }
    }
    /* label the curves of the transition system; open ones first */
    for (i = 0; i < g->ne; i++)
        curve[i] = NONE;
    for (i = 0; i < ne2; i++) {
        size_t x;
        if (partner[i] != NONE || curve[i / 2] != NONE)
            continue;
        for (x = i; x != NONE && curve[x / 2] == NONE; x = partner[x ^ 1u])
            curve[x / 2] = ncurve; /* leave by the other end, continue through its partner */
        isopen[ncurve++] = 1;
    }
    for (i = 0; i < g->ne; i++) {
        size_t x;
        if (curve[i] != NONE)
            continue;
        for (x = 2 * i; x != NONE && curve[x / 2] == NONE; x = partner[x ^ 1u])
            curve[x / 2] = ncurve;
        isopen[ncurve++] = 0;
    }
    for (i = 0; i < ncurve; i++)
        uf[i] = i;
    /* merge curves at shared vertices (the cycle tree) */
    for (v = 0; v < g->nv; v++) {
        size_t d = start[v + 1] - start[v], p;
        int again = 1;
        while (again && d >= 4) {
            again = 0;
            for (p = 0; p < d; p++) {
                size_t x = rot[start[v] + p].end, y = rot[start[v] + (p + 1) % d].end, a, dd, cx, cy;
                if (partner[x] == y || partner[x] == NONE || partner[y] == NONE)
                    continue;
                cx = uf_find(uf, curve[x / 2]);
                cy = uf_find(uf, curve[y / 2]);
                /* two open curves re-paired stay two open curves: skip */
                if (cx == cy || (isopen[cx] && isopen[cy]))
                    continue;
                a = partner[x];
                dd = partner[y];
                partner[a] = dd;
                partner[dd] = a;
                partner[x] = y;
                partner[y] = x;
                uf[cx] = cy;
                isopen[cy] = (unsigned char)(isopen[cx] | isopen[cy]);
                again = 1;
            }
        }
    }
    /* trace: open curves from their terminal, then closed curves */
    for (pass = 0; pass < 2 && st == AMP_OK; pass++)
        for (i = 0; i < ne2 && st == AMP_OK; i++) {
            size_t x = i, first = i;
            if (used[i / 2] || (pass == 0 && partner[i] != NONE))
                continue;
            if ((st = amp_pathset_begin(out, AMP_ROLE_OBJECT, err)) != AMP_OK)
                break;
            {
                size_t at = x % 2 ? g->ev[x / 2] : g->eu[x / 2];
                st = amp_pathset_push(out, amp_v3(g->v[at].x, g->v[at].y, z), rad, err);
            }
            while (st == AMP_OK) {
                size_t e = x / 2, to = x % 2 ? g->eu[e] : g->ev[e];
                used[e] = 1;
                st = amp_pathset_push(out, amp_v3(g->v[to].x, g->v[to].y, z), rad, err);
                x = partner[x ^ 1u];
                if (x == NONE || x == first || used[x / 2])
                    break;
            }
            (*ntours)++;
        }
done:
    amp_free(al, start);
    amp_free(al, rot);
    amp_free(al, partner);
    amp_free(al, curve);
    amp_free(al, uf);
    amp_free(al, used);
    amp_free(al, isopen);
    return st;
}

/* Region processing with a prepared K̂ edge list. */
static amp_status region_run(const amp_cx2 *khat, const uint64_t *ke, size_t nke, const amp_polyset *R, double z,
                             const amp_contpath_opts *o, amp_pathset *out, amp_contpath_stats *st, amp_error *err)
{
    rgraph g;
    size_t *uf = NULL, *grs = NULL, *grm = NULL, *tmp = NULL, i, j, ngr, ntours = 0, nodd = 0, first_path;
    size_t *cnt = NULL;
    unsigned char *choice = NULL, *dead = NULL;
    amp_status rc;
    memset(&g, 0, sizeof g);
    g.al = out->alloc;
    rc = clip_region(khat, ke, nke, R, &g, err);
    if (rc != AMP_OK)
        goto done;
    if (g.nfe > 1)
        qsort(g.fe, g.nfe, sizeof *g.fe, cmp_fend);
    st->free_ends += g.nfe;
    uf = amp_alloc(g.al, (g.nv + 1) * sizeof *uf);
    if (!uf) {
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
        goto done;
    }
    for (i = 0; i < g.nv; i++)
        uf[i] = i;
    for (i = 0; i < g.ne; i++)
        uf_union(uf, g.eu[i], g.ev[i]);
    /* step 5: on every ring, one of the two alternating pairings of its free
     * ends. The choice over all rings of the region joins the most pieces
     * (Fig. 6: pieces next to each other along the ring are linked), then
     * prints the longer length; exhaustive up to 12 rings, greedy beyond.
     * When the two pairings of a ring conflict (two small pieces whose ends
     * sit at opposite parities), no choice joins everything: the smallest
     * piece left apart is then dropped (its free ends are removed, which
     * keeps every ring even) and the choice is made again. */
    tmp = amp_alloc(g.al, (g.nv + 1) * sizeof *tmp);
    dead = amp_calloc(g.al, g.nv + 1, 1);
    cnt = amp_alloc(g.al, (g.nv + 1) * sizeof *cnt);
    grs = amp_alloc(g.al, (g.nfe + 1) * sizeof *grs);
    grm = amp_alloc(g.al, (g.nfe + 1) * sizeof *grm);
    choice = amp_calloc(g.al, g.nfe + 1, 1);
    if (!tmp || !dead || !cnt || !grs || !grm || !choice) {
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
        goto done;
    }
    for (;;) {
        unsigned long mask, nmask, bestmask = 0;
        size_t bestmerge = 0, k, ncomp = 0, big = NONE, victim = NONE;
        double bestlen = -1;
        int greedy;
        for (i = 0, ngr = 0; i < g.nfe; i = j) {
            for (j = i; j < g.nfe && g.fe[j].ring == g.fe[i].ring; j++)
                ;
            if (j - i >= 2) {
                grs[ngr] = i;
                grm[ngr++] = j - i;
            }
        }
        greedy = ngr > 12;
        nmask = greedy ? 2ul : 1ul << ngr;
        for (k = 0; k < (greedy ? ngr : 1); k++) {
            bestmerge = 0;
            bestlen = -1;
            for (mask = 0; mask < nmask; mask++) {
                size_t merges = 0, gk;
                double len = 0;
                memcpy(tmp, uf, g.nv * sizeof *tmp);
                for (gk = 0; gk < ngr; gk++) {
                    int opt = greedy ? (gk < k ? choice[gk] : (gk == k ? (int)mask : -1)) : (int)((mask >> gk) & 1u);
                    size_t q, m = grm[gk];
                    if (opt < 0)
                        continue;
                    for (q = (size_t)opt; q + 1 < m + (size_t)opt && q + 1 <= m; q += 2) {
                        const fend *fa = &g.fe[grs[gk] + q % m], *fb = &g.fe[grs[gk] + (q + 1) % m];
                        len += ring_len(R, fa->ring, fa->pos, fb->pos);
                        merges += (size_t)uf_union(tmp, fa->node, fb->node);
                    }
                }
                if (mask == 0 || merges > bestmerge || (merges == bestmerge && len > bestlen)) {
                    bestmask = mask;
                    bestmerge = merges;
                    bestlen = len;
                }
            }
            if (greedy)
                choice[k] = (unsigned char)bestmask;
        }
        if (!greedy)
            for (k = 0; k < ngr; k++)
                choice[k] = (unsigned char)((bestmask >> k) & 1u);
        /* the pieces after this choice: the one with most edges stays */
        memcpy(tmp, uf, g.nv * sizeof *tmp);
        for (k = 0; k < ngr; k++) {
            size_t q, m = grm[k];
            for (q = choice[k]; q + 1 < m + choice[k] && q + 1 <= m; q += 2)
                uf_union(tmp, g.fe[grs[k] + q % m].node, g.fe[grs[k] + (q + 1) % m].node);
        }
        memset(cnt, 0, g.nv * sizeof *cnt);
        for (i = 0; i < g.ne; i++)
            if (!dead[uf_find(uf, g.eu[i])])
                cnt[uf_find(tmp, g.eu[i])]++;
        for (i = 0; i < g.nv; i++)
            if (cnt[i]) {
                ncomp++;
                if (big == NONE || cnt[i] > cnt[big])
                    big = i;
            }
        if (ncomp <= 1)
            break;
        /* smallest piece (before patching) outside the big one, with an even
         * number of free ends on every ring */
        memset(cnt, 0, g.nv * sizeof *cnt);
        for (i = 0; i < g.ne; i++)
            cnt[uf_find(uf, g.eu[i])]++;
        for (i = 0; i < g.nv; i++) {
            size_t q;
            int even = 1;
            if (!cnt[i] || dead[i] || uf_find(uf, i) != i || uf_find(tmp, i) == uf_find(tmp, big))
                continue;
            for (q = 0; q < g.nfe && even; q++) {
                size_t c = 0, q2;
                if (uf_find(uf, g.fe[q].node) != i)
                    continue;
                for (q2 = 0; q2 < g.nfe; q2++)
                    c += uf_find(uf, g.fe[q2].node) == i && g.fe[q2].ring == g.fe[q].ring;
                even = c % 2 == 0;
            }
            if (even && (victim == NONE || cnt[i] < cnt[victim]))
                victim = i;
        }
        if (victim == NONE)
            break;
        dead[victim] = 1;
        for (i = 0, j = 0; i < g.nfe; i++)
            if (uf_find(uf, g.fe[i].node) != victim)
                g.fe[j++] = g.fe[i];
        g.nfe = j;
    }
    /* remove the dropped pieces, then patch */
    for (i = 0, j = 0; i < g.ne; i++)
        if (!dead[uf_find(uf, g.eu[i])]) {
            g.eu[j] = g.eu[i];
            g.ev[j++] = g.ev[i];
        } else
            st->dropped_length += hypot(g.v[g.eu[i]].x - g.v[g.ev[i]].x, g.v[g.eu[i]].y - g.v[g.ev[i]].y);
    g.ne = j;
    for (i = 0; i < ngr; i++) {
        size_t m = grm[i], q, opt;
        for (opt = 0; opt < 2; opt++)
            for (q = opt; q + 1 <= m && q + 1 < m + opt; q += 2) {
                const fend *fa = &g.fe[grs[i] + q % m], *fb = &g.fe[grs[i] + (q + 1) % m];
                if (opt == choice[i]) {
                    if ((rc = ring_path(&g, R, fa, fb, NULL, z, o->radius, err)) != AMP_OK)
                        goto done;
                } else {
                    double l = ring_len(R, fa->ring, fa->pos, fb->pos);
                    if (o->support_stretches) {
                        /* Remark 2.1: print the unprinted stretch on its own */
                        if ((rc = ring_path(&g, R, fa, fb, out, z, o->radius, err)) != AMP_OK)
                            goto done;
                        st->support_paths++;
                        st->support_length += l;
                    } else
                        st->unprinted_length += l;
                }
            }
    }
    first_path = out->npaths;
    rc = euler_tours(&g, z, o->radius, out, &ntours, &nodd, err);
    if (rc != AMP_OK)
        goto done;
    if (ntours == 0 && R->nrings) {
        /* no lattice edge reaches this region: its outer ring is the stroke */
        const amp_vec2 *p = amp_polyset_ring(R, 0);
        size_t n = R->rings[0].n;
        if ((rc = amp_pathset_begin(out, AMP_ROLE_OBJECT, err)) != AMP_OK)
            goto done;
        for (i = 0; i <= n && rc == AMP_OK; i++)
            rc = amp_pathset_push(out, amp_v3(p[i % n].x, p[i % n].y, z), o->radius, err);
        ntours = 1;
    }
    for (i = first_path; i < out->npaths; i++)
        st->infill_length += amp_path_length(out, i);
    st->islands++;
    st->strokes += ntours;
    st->multi_stroke += ntours > 1;
    st->odd_vertices += nodd;
done:
    g_free(&g);
    amp_free(g.al, uf);
    amp_free(g.al, grs);
    amp_free(g.al, grm);
    amp_free(g.al, tmp);
    amp_free(g.al, choice);
    amp_free(g.al, dead);
    amp_free(g.al, cnt);
    return rc;
}

amp_status amp_contpath_region(const amp_cx2 *khat, const amp_polyset *region, double z,
                               const amp_contpath_opts *o, amp_pathset *out, amp_contpath_stats *st,
                               amp_error *err)
{
    uint64_t *ke = NULL;
    size_t nke = 0;
    amp_status rc;
    if (khat_edges(khat, out->alloc, &ke, &nke) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the lattice edges");
    rc = region_run(khat, ke, nke, region, z, o, out, st, err);
    amp_free(out->alloc, ke);
    return rc;
}

amp_status amp_contpath_layers(const amp_slices *sl, const amp_contpath_opts *o, amp_pathset *out,
                               amp_contpath_stats *st, amp_error *err)
{
    const amp_allocator *al = out->alloc;
    amp_cx2 khat;
    amp_polyset isl, ins, reg;
    uint64_t *ke = NULL;
    size_t nke = 0, li, k, r, q, p0 = out->npaths;
    amp_contpath_stats s0;
    amp_status rc;
    memset(&s0, 0, sizeof s0);
    amp_cx2_init(&khat, al);
    amp_polyset_init(&isl, al);
    amp_polyset_init(&ins, al);
    amp_polyset_init(&reg, al);
    rc = amp_contpath_complex(sl, o, &khat, err);
    if (rc == AMP_OK && khat_edges(&khat, al, &ke, &nke) != AMP_OK)
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the lattice edges");
    for (li = 0; li < sl->nlayers && rc == AMP_OK; li++) {
        const amp_layer *L = &sl->layers[li];
        s0.layers++;
        for (k = 0; k < L->polys.nislands && rc == AMP_OK; k++) {
            if ((rc = amp_polyset_island(&L->polys, k, &isl, err)) != AMP_OK)
                break;
            if (o->perimeters) {
                /* the perimeter bead's centre line: inset by r */
                if ((rc = amp_polyset_inset(&isl, o->radius, 0, &ins, err)) != AMP_OK)
                    break;
                for (r = 0; r < ins.nrings && rc == AMP_OK; r++) {
                    const amp_vec2 *p = amp_polyset_ring(&ins, r);
                    size_t n = ins.rings[r].n;
                    rc = amp_pathset_begin(out, AMP_ROLE_OBJECT, err);
                    for (q = 0; q <= n && rc == AMP_OK; q++)
                        rc = amp_pathset_push(out, amp_v3(p[q % n].x, p[q % n].y, L->z_print), o->radius, err);
                    s0.perimeter_loops++;
                }
            }
            /* R̃: inside the perimeter bead (2r) and one bead radius more */
            if (rc == AMP_OK)
                rc = amp_polyset_inset(&isl, 3 * o->radius, 0, &ins, err);
            for (q = 0; q < ins.nislands && rc == AMP_OK; q++) {
                if ((rc = amp_polyset_island(&ins, q, &reg, err)) != AMP_OK)
                    break;
                rc = region_run(&khat, ke, nke, &reg, L->z_print, o, out, &s0, err);
            }
        }
    }
    /* figures over the paths written by this call */
    for (q = p0; q < out->npaths && rc == AMP_OK; q++) {
        if (out->paths[q].role == AMP_ROLE_OBJECT)
            s0.printed_length += amp_path_length(out, q);
        if (q > p0 && out->paths[q - 1].n && out->paths[q].n) {
            amp_pvert a = amp_pathset_path_verts(out, q - 1)[out->paths[q - 1].n - 1];
            amp_pvert b = amp_pathset_path_verts(out, q)[0];
            s0.travel_moves++;
            s0.travel_length += amp_v3_dist(a.p, b.p);
        }
    }
    amp_free(al, ke);
    amp_cx2_free(&khat);
    amp_polyset_free(&isl);
    amp_polyset_free(&ins);
    amp_polyset_free(&reg);
    if (st)
        *st = s0;
    return rc;
}

amp_status amp_pathset_stroke_check(const amp_pathset *ps, size_t i, const amp_polyset *region, double tol,
                                    amp_stroke_report *rep, amp_error *err)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    size_t n = ps->paths[i].n, k;
    amp_vec2 *p = amp_alloc(ps->alloc, (n + 1) * sizeof *p);
    amp_status st;
    if (!p)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking a stroke");
    for (k = 0; k < n; k++)
        p[k] = amp_v2(v[k].p.x, v[k].p.y);
    st = amp_stroke_check(p, n, region, tol, rep, err);
    amp_free(ps->alloc, p);
    return st;
}
