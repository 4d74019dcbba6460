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
    o->pseudo_edges = 1;
}

/* Length of the printed segments of path i (a segment with radius 0 at both
 * ends is a pseudo edge: travel inside the stroke). */
static double printed_len(const amp_pathset *ps, size_t i)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    size_t k;
    double len = 0;
    for (k = 0; k + 1 < ps->paths[i].n; k++)
        if (v[k].r > 0 || v[k + 1].r > 0)
            len += amp_v3_dist(v[k].p, v[k + 1].p);
    return len;
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
    unsigned char *ep; /* 1: pseudo edge (travel inside the stroke, no material) */
    size_t ne, cap_eu, cap_ev, cap_ep;
    size_t nlat; /* edges [0, nlat) are the clipped lattice pieces */
    fend *fe;
    size_t nfe, cap_fe;
    /* scratch of patch_points(): the patch polyline and its segment kinds */
    amp_vec2 *pp;
    unsigned char *pf;
    size_t npp, cap_pp, cap_pf;
    double *iv; /* bad intervals (lo, hi) of one segment */
    size_t cap_iv;
    amp_vec2 *cand; /* segments near one patch, 2 points each */
    size_t cap_cand;
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

static amp_status g_edge(rgraph *g, size_t a, size_t b, int pseudo)
{
    void *q = g->eu, *r = g->ev, *t = g->ep;
    if (a == b)
        return AMP_OK;
    if (amp_grow(g->al, &t, &g->cap_ep, g->ne + 1, sizeof *g->ep) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->ep = t;
    g->ep[g->ne] = (unsigned char)(pseudo != 0);
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
    amp_free(g->al, g->ep);
    amp_free(g->al, g->fe);
    amp_free(g->al, g->pp);
    amp_free(g->al, g->pf);
    amp_free(g->al, g->iv);
    amp_free(g->al, g->cand);
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

/* Append point x (and the kind of the segment that starts at it) to the
 * patch polyline g->pp / g->pf. */
static amp_status pp_push(rgraph *g, amp_vec2 x, unsigned char pseudo)
{
    void *q = g->pp;
    if (amp_grow(g->al, &q, &g->cap_pp, g->npp + 1, sizeof *g->pp) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->pp = q;
    q = g->pf;
    if (amp_grow(g->al, &q, &g->cap_pf, g->npp + 1, sizeof *g->pf) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->pf = q;
    g->pf[g->npp] = pseudo;
    g->pp[g->npp++] = x;
    return AMP_OK;
}

/* The ring points strictly between free ends fi and fj (ring direction):
 * appended to the last path of @p ps, or to the patch polyline g->pp. */
static amp_status ring_walk(const amp_polyset *R, const fend *fi, const fend *fj, rgraph *g, amp_pathset *ps, double z,
                            double rad, amp_error *err)
{
    const amp_vec2 *p = amp_polyset_ring(R, fi->ring);
    size_t n = R->rings[fi->ring].n, s0 = (size_t)fi->pos, s1 = (size_t)fj->pos, s;
    amp_status st;
    if (s1 == s0 && fj->pos >= fi->pos)
        return AMP_OK;
    for (s = (s0 + 1) % n;; s = (s + 1) % n) {
        if (ps) {
            if ((st = amp_pathset_push(ps, amp_v3(p[s].x, p[s].y, z), rad, err)) != AMP_OK)
                return st;
        } else if (pp_push(g, p[s], 0) != AMP_OK)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
        if (s == s1)
            break;
    }
    return AMP_OK;
}

/* Remark 2.1: the unprinted stretch from free end fi to fj as a support path. */
static amp_status ring_support(rgraph *g, const amp_polyset *R, const fend *fi, const fend *fj, amp_pathset *ps,
                               double z, double rad, amp_error *err)
{
    amp_vec2 a = g->v[fi->node], b = g->v[fj->node];
    amp_status st;
    if ((st = amp_pathset_begin(ps, AMP_ROLE_SUPPORT, err)) != AMP_OK ||
        (st = amp_pathset_push(ps, amp_v3(a.x, a.y, z), rad, err)) != AMP_OK ||
        (st = ring_walk(R, fi, fj, g, ps, z, rad, err)) != AMP_OK)
        return st;
    return amp_pathset_push(ps, amp_v3(b.x, b.y, z), rad, err);
}

/* The parameters t in [0, 1] of P + t (Q - P) closer than D to segment AB:
 * the line meets the capsule of AB (convex) in one interval, the hull of its
 * meets with the two end discs and the middle rectangle. 0 if empty. */
static int capsule_interval(amp_vec2 P, amp_vec2 Q, amp_vec2 A, amp_vec2 B, double D, double *lo, double *hi)
{
    double dx = Q.x - P.x, dy = Q.y - P.y, ex = B.x - A.x, ey = B.y - A.y, L = hypot(ex, ey);
    double a0 = HUGE_VAL, a1 = -HUGE_VAL;
    int k;
    for (k = 0; k < 2; k++) {
        /* |P + t d - C|^2 < D^2 */
        amp_vec2 C = k ? B : A;
        double fx = P.x - C.x, fy = P.y - C.y, qa = dx * dx + dy * dy, qb = 2 * (fx * dx + fy * dy),
               qc = fx * fx + fy * fy - D * D, disc = qb * qb - 4 * qa * qc;
        if (qa > 0 && disc > 0) {
            double sq = sqrt(disc);
            a0 = fmin(a0, (-qb - sq) / (2 * qa));
            a1 = fmax(a1, (-qb + sq) / (2 * qa));
        } else if (!(qa > 0) && qc < 0) {
            a0 = fmin(a0, 0.0);
            a1 = fmax(a1, 1.0);
        }
    }
    if (L > 0) {
        /* 0 < (X - A).u < L and |(X - A).n| < D, linear in t */
        double ux = ex / L, uy = ey / L, r0 = -HUGE_VAL, r1 = HUGE_VAL;
        double c[2] = {(P.x - A.x) * ux + (P.y - A.y) * uy, (P.x - A.x) * -uy + (P.y - A.y) * ux};
        double sl[2] = {dx * ux + dy * uy, dx * -uy + dy * ux}, bl[2] = {0, -D}, bh[2] = {L, D};
        for (k = 0; k < 2; k++) {
            if (sl[k] == 0) {
                if (!(c[k] > bl[k] && c[k] < bh[k]))
                    r0 = HUGE_VAL;
                continue;
            }
            {
                double t0 = (bl[k] - c[k]) / sl[k], t1 = (bh[k] - c[k]) / sl[k];
                r0 = fmax(r0, fmin(t0, t1));
                r1 = fmin(r1, fmax(t0, t1));
            }
        }
        if (r0 < r1) {
            a0 = fmin(a0, r0);
            a1 = fmax(a1, r1);
        }
    }
    *lo = fmax(a0, 0.0);
    *hi = fmin(a1, 1.0);
    return *lo < *hi;
}

static int cmp_dbl2(const void *a, const void *b)
{
    const double *x = a, *y = b;
    return x[0] < y[0] ? -1 : (x[0] > y[0] ? 1 : 0);
}

/* The patches of a region: patch k runs along a ring from node a[k] to node
 * b[k] through the raw points pts[p0[k] .. p0[k] + np[k] - 1] (ends included). */
typedef struct patchset {
    size_t *a, *b, *p0, *np; /* room for one patch per gap (at most the number of free ends) */
    unsigned char *join;     /* 1: joins two components (printed once, run back as a pseudo edge) */
    double *box;             /* 4 per patch: bounding box */
    size_t n;
    amp_vec2 *pts;
    size_t npts, cap_pts;
} patchset;

static amp_status patchset_alloc(const amp_allocator *al, patchset *P, size_t room)
{
    memset(P, 0, sizeof *P);
    P->a = amp_alloc(al, (room + 1) * sizeof *P->a);
    P->b = amp_alloc(al, (room + 1) * sizeof *P->b);
    P->p0 = amp_alloc(al, (room + 1) * sizeof *P->p0);
    P->np = amp_alloc(al, (room + 1) * sizeof *P->np);
    P->join = amp_alloc(al, room + 1);
    P->box = amp_alloc(al, 4 * (room + 1) * sizeof *P->box);
    return P->a && P->b && P->p0 && P->np && P->join && P->box ? AMP_OK : AMP_ERR_NOMEM;
}

static void patchset_free(const amp_allocator *al, patchset *P)
{
    amp_free(al, P->a);
    amp_free(al, P->b);
    amp_free(al, P->p0);
    amp_free(al, P->np);
    amp_free(al, P->join);
    amp_free(al, P->pts);
    amp_free(al, P->box);
}

/* Record the patch from free end fi to fj along the ring (step 5). */
static amp_status patch_add(rgraph *g, patchset *P, const amp_polyset *R, const fend *fi, const fend *fj, int join,
                            amp_error *err)
{
    void *q = P->pts;
    size_t i, k = P->n;
    double *bx = P->box + 4 * k;
    g->npp = 0;
    if (pp_push(g, g->v[fi->node], 0) != AMP_OK || ring_walk(R, fi, fj, g, NULL, 0, 0, err) != AMP_OK ||
        pp_push(g, g->v[fj->node], 0) != AMP_OK ||
        amp_grow(g->al, &q, &P->cap_pts, P->npts + g->npp, sizeof *P->pts) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
    P->pts = q;
    P->a[k] = fi->node;
    P->b[k] = fj->node;
    P->p0[k] = P->npts;
    P->np[k] = g->npp;
    P->join[k] = (unsigned char)join;
    bx[0] = bx[1] = HUGE_VAL;
    bx[2] = bx[3] = -HUGE_VAL;
    for (i = 0; i < g->npp; i++) {
        P->pts[P->npts++] = g->pp[i];
        bx[0] = fmin(bx[0], g->pp[i].x);
        bx[1] = fmin(bx[1], g->pp[i].y);
        bx[2] = fmax(bx[2], g->pp[i].x);
        bx[3] = fmax(bx[3], g->pp[i].y);
    }
    P->n++;
    return AMP_OK;
}

static amp_status cand_push(rgraph *g, size_t *ncand, amp_vec2 A, amp_vec2 B)
{
    void *q = g->cand;
    if (amp_grow(g->al, &q, &g->cap_cand, 2 * *ncand + 2, sizeof *g->cand) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->cand = q;
    g->cand[2 * *ncand] = A;
    g->cand[2 * *ncand + 1] = B;
    (*ncand)++;
    return AMP_OK;
}

/* Patch @p self of @p P into g->pp/pf, split into printed and pseudo pieces.
 * Thin boundary cells (§2.2, Figs. 7, 8): a stretch of a patch closer than
 * the bead width D = 2r to a printed edge of the complex that is not
 * adjacent to it — a lattice piece or another patch that does not end at the
 * patch's own free ends — would put material on material; it becomes a
 * pseudo edge (travel inside the stroke, no extrusion). The stretch is
 * bounded by the points where the distance is exactly D, the split points
 * v'_i of Fig. 7; a patch whose cell is unshrinkable (Fig. 8: a parallel
 * edge closer than 2r) becomes pseudo over the whole close stretch. Both
 * patches of a close pair are cut (as both stubs at ṽ_1 in Fig. 7c).
 * D <= 0: no pseudo edges. */
static amp_status patch_points(rgraph *g, const patchset *P, size_t self, double D, amp_error *err)
{
    size_t i, k, ncand = 0, niv, nraw = P->np[self], na = P->a[self], nb = P->b[self];
    const amp_vec2 *raw = P->pts + P->p0[self];
    const double *bs = P->box + 4 * self;
    double bx0 = bs[0] - D, by0 = bs[1] - D, bx1 = bs[2] + D, by1 = bs[3] + D;
    amp_status st = AMP_OK;
    g->npp = 0;
    if (D > 0) {
        /* the printed lattice pieces near the patch, except the stubs at its ends */
        for (i = 0; i < g->nlat && st == AMP_OK; i++) {
            amp_vec2 A = g->v[g->eu[i]], B = g->v[g->ev[i]];
            if (g->ep[i] || g->eu[i] == na || g->ev[i] == na || g->eu[i] == nb || g->ev[i] == nb ||
                fmax(A.x, B.x) < bx0 || fmin(A.x, B.x) > bx1 || fmax(A.y, B.y) < by0 || fmin(A.y, B.y) > by1)
                continue;
            st = cand_push(g, &ncand, A, B);
        }
        /* the other patches, except those sharing a free end with this one */
        for (k = 0; k < P->n && st == AMP_OK; k++) {
            const double *bk = P->box + 4 * k;
            const amp_vec2 *q = P->pts + P->p0[k];
            if (k == self || P->a[k] == na || P->a[k] == nb || P->b[k] == na || P->b[k] == nb || bk[2] < bx0 ||
                bk[0] > bx1 || bk[3] < by0 || bk[1] > by1)
                continue;
            for (i = 0; i + 1 < P->np[k] && st == AMP_OK; i++)
                if (!(fmax(q[i].x, q[i + 1].x) < bx0 || fmin(q[i].x, q[i + 1].x) > bx1 ||
                      fmax(q[i].y, q[i + 1].y) < by0 || fmin(q[i].y, q[i + 1].y) > by1))
                    st = cand_push(g, &ncand, q[i], q[i + 1]);
        }
    }
    for (i = 0; i + 1 < nraw && st == AMP_OK; i++) {
        amp_vec2 P0 = raw[i], Q0 = raw[i + 1];
        double t = 0, len = hypot(Q0.x - P0.x, Q0.y - P0.y), tiny = len > 0 ? 1e-9 * D / len : 1.0;
        niv = 0;
        for (k = 0; k < ncand && st == AMP_OK; k++) {
            double lo, hi;
            void *q = g->iv;
            if (!capsule_interval(P0, Q0, g->cand[2 * k], g->cand[2 * k + 1], D, &lo, &hi) || hi - lo <= tiny)
                continue;
            if (amp_grow(g->al, &q, &g->cap_iv, 2 * niv + 2, sizeof *g->iv) != AMP_OK)
                st = AMP_ERR_NOMEM;
            else {
                g->iv = q;
                g->iv[2 * niv] = lo;
                g->iv[2 * niv + 1] = hi;
                niv++;
            }
        }
        if (niv > 1)
            qsort(g->iv, niv, 2 * sizeof *g->iv, cmp_dbl2);
        /* printed [t, lo], pseudo [lo, hi] for each merged close interval */
        if (st == AMP_OK)
            st = pp_push(g, P0, 0);
        for (k = 0; k < niv && st == AMP_OK; k++) {
            double lo = g->iv[2 * k], hi = g->iv[2 * k + 1];
            while (k + 1 < niv && g->iv[2 * k + 2] <= hi)
                hi = fmax(hi, g->iv[2 * ++k + 1]);
            if (hi <= t)
                continue;
            if (lo > t + tiny) /* the split point v' starts the pseudo piece */
                st = pp_push(g, amp_v2(P0.x + lo * (Q0.x - P0.x), P0.y + lo * (Q0.y - P0.y)), 1);
            else
                g->pf[g->npp - 1] = 1;
            t = hi;
            if (st == AMP_OK && hi < 1 - tiny)
                st = pp_push(g, amp_v2(P0.x + hi * (Q0.x - P0.x), P0.y + hi * (Q0.y - P0.y)), 0);
        }
    }
    if (st == AMP_OK && nraw)
        st = pp_push(g, raw[nraw - 1], 0);
    return st == AMP_OK ? AMP_OK : amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
}

/* The patch polyline g->pp as a chain of graph edges from node @p a to node
 * @p b (new nodes in between); every edge pseudo when @p all_pseudo. Two
 * chains built from the same polyline have the same directions at a and b,
 * which the tour's tie rule needs (parallel copies). */
static amp_status add_chain(rgraph *g, size_t a, size_t b, int all_pseudo, double *pseudo_len)
{
    size_t i, prev = a, id;
    for (i = 1; i < g->npp; i++) {
        int ps = all_pseudo || g->pf[i - 1];
        if (i + 1 == g->npp)
            id = b;
        else if (g_vert(g, g->pp[i], &id) != AMP_OK)
            return AMP_ERR_NOMEM;
        if (g_edge(g, prev, id, ps) != AMP_OK)
            return AMP_ERR_NOMEM;
        if (ps)
            *pseudo_len += hypot(g->pp[i].x - g->pp[i - 1].x, g->pp[i].y - g->pp[i - 1].y);
        prev = id;
    }
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
            if (g_edge(g, u, v, 0) != AMP_OK) {
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
    size_t ex = x->end / 2, ey = y->end / 2;
    if (x->ang != y->ang)
        return x->ang < y->ang ? -1 : 1;
    /* equal directions: the two copies of a joining patch (both built from
     * the same polyline in the same direction). Ascending edge order at the
     * nodes where they start, descending where they end: the copies then
     * nest like the two sides of a thin digon, a planar rotation system. */
    if (ex == ey)
        return 0;
    if (x->end % 2 != y->end % 2)
        return x->end % 2 < y->end % 2 ? -1 : 1;
    return (ex < ey) == (x->end % 2 == 0) ? -1 : 1;
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
    /* trace: open curves from their terminal, then closed curves from a
     * printed edge. A pseudo edge is written with radius 0 at both ends; where
     * printing and travel meet, the vertex is written twice (a zero-length
     * step), so no segment mixes the two radii (SPEC §5: mean radius). */
    for (pass = 0; pass < 3 && st == AMP_OK; pass++)
        for (i = 0; i < ne2 && st == AMP_OK; i++) {
            size_t x = i, first = i, at = x % 2 ? g->ev[x / 2] : g->eu[x / 2];
            double cur;
            if (used[i / 2] || (pass == 0 && partner[i] != NONE) || (pass == 1 && g->ep[i / 2]))
                continue;
            cur = g->ep[i / 2] ? 0.0 : rad;
            if ((st = amp_pathset_begin(out, AMP_ROLE_OBJECT, err)) != AMP_OK)
                break;
            st = amp_pathset_push(out, amp_v3(g->v[at].x, g->v[at].y, z), cur, err);
            while (st == AMP_OK) {
                size_t e = x / 2, to = x % 2 ? g->eu[e] : g->ev[e];
                double r = g->ep[e] ? 0.0 : rad;
                used[e] = 1;
                if (r != cur)
                    st = amp_pathset_push(out, amp_v3(g->v[at].x, g->v[at].y, z), r, err);
                if (st == AMP_OK)
                    st = amp_pathset_push(out, amp_v3(g->v[to].x, g->v[to].y, z), r, err);
                cur = r;
                at = to;
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

/* One gap of a ring: the stretch from free end q to q + 1 (cyclic) of ring group k. */
typedef struct gap {
    size_t k, q;
    double len;
} gap;

static int cmp_gap(const void *a, const void *b)
{
    const gap *x = a, *y = b;
    return x->len < y->len ? -1 : (x->len > y->len ? 1 : 0);
}

/* Region processing with a prepared K̂ edge list. */
static amp_status region_run(const amp_cx2 *khat, const uint64_t *ke, size_t nke, const amp_polyset *R, double z,
                             const amp_contpath_opts *o, amp_pathset *out, amp_contpath_stats *st, amp_error *err)
{
    rgraph g;
    size_t *uf = NULL, *grs = NULL, *grm = NULL, *tmp = NULL, i, j, k, ngr, ntours = 0, nodd = 0, first_path, ngap = 0;
    unsigned char *choice = NULL;
    gap *gp = NULL;
    patchset P;
    double D = o->pseudo_edges ? 2 * o->radius * (1 - 1e-9) : 0.0, pseudo = 0;
    amp_status rc;
    memset(&g, 0, sizeof g);
    memset(&P, 0, sizeof P);
    g.al = out->alloc;
    rc = clip_region(khat, ke, nke, R, &g, err);
    if (rc != AMP_OK)
        goto done;
    g.nlat = g.ne;
    if (g.nfe > 1)
        qsort(g.fe, g.nfe, sizeof *g.fe, cmp_fend);
    st->free_ends += g.nfe;
    uf = amp_alloc(g.al, (g.nv + 1) * sizeof *uf);
    tmp = amp_alloc(g.al, (g.nv + 1) * sizeof *tmp);
    grs = amp_alloc(g.al, (g.nfe + 1) * sizeof *grs);
    grm = amp_alloc(g.al, (g.nfe + 1) * sizeof *grm);
    choice = amp_calloc(g.al, g.nfe + 1, 1);
    gp = amp_alloc(g.al, (g.nfe + 1) * sizeof *gp);
    if (!uf || !tmp || !grs || !grm || !choice || !gp) {
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
        goto done;
    }
    for (i = 0; i < g.nv; i++)
        uf[i] = i;
    for (i = 0; i < g.ne; i++)
        uf_union(uf, g.eu[i], g.ev[i]);
    /* step 5: on every ring, one of the two alternating pairings of its free
     * ends (gap q printed when q % 2 == choice). The choice over all rings
     * of the region joins the most pieces (Fig. 6: pieces next to each other
     * along a ring are linked by the path between them), then prints the
     * longer length; exhaustive up to 12 rings, greedy ring by ring beyond. */
    for (i = 0, ngr = 0; i < g.nfe; i = j) {
        for (j = i; j < g.nfe && g.fe[j].ring == g.fe[i].ring; j++)
            ;
        if (j - i >= 2) {
            grs[ngr] = i;
            grm[ngr++] = j - i;
        }
    }
    {
        int greedy = ngr > 12;
        unsigned long mask, nmask = greedy ? 2ul : 1ul << ngr, bestmask = 0;
        for (k = 0; k < (greedy ? ngr : 1); k++) {
            size_t bestmerge = 0;
            double bestlen = -1;
            for (mask = 0; mask < nmask; mask++) {
                size_t merges = 0, gk;
                double len = 0;
                memcpy(tmp, uf, g.nv * sizeof *tmp);
                for (gk = 0; gk < ngr; gk++) {
                    int opt = greedy ? (gk < k ? choice[gk] : (gk == k ? (int)mask : -1)) : (int)((mask >> gk) & 1u);
                    size_t q, m = grm[gk];
                    if (opt < 0)
                        continue;
                    for (q = (size_t)opt; q + 1 < m + (size_t)opt; q += 2) {
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
    }
    /* the chosen patches; the other gaps are candidates for joining */
    if (patchset_alloc(g.al, &P, g.nfe) != AMP_OK) {
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
        goto done;
    }
    for (k = 0; k < ngr; k++) {
        size_t m = grm[k], q;
        for (q = 0; q < m; q++) {
            const fend *fa = &g.fe[grs[k] + q], *fb = &g.fe[grs[k] + (q + 1) % m];
            if (q % 2 == choice[k] && q + 1 < m + choice[k]) {
                if ((rc = patch_add(&g, &P, R, fa, fb, 0, err)) != AMP_OK)
                    goto done;
                uf_union(uf, fa->node, fb->node);
            } else {
                gp[ngap].k = k;
                gp[ngap].q = q;
                gp[ngap++].len = ring_len(R, fa->ring, fa->pos, fb->pos);
            }
        }
    }
    /* Fig. 6, several components: when the pairings leave pieces apart
     * (two pieces that need opposite pairings on one ring, or pieces whose
     * free ends alternate on two rings), neighbouring components — whose
     * free ends follow each other along a ring with no other free end
     * between — are joined by the path p along R̃ between them. The patch
     * is printed once and run back as a pseudo edge over the fresh bead (a
     * doubled edge keeps every vertex even: only the two copies together
     * leave the parity of step 5 intact). Shortest gaps first, like
     * Kruskal, until the region is one component. */
    if (ngap > 1)
        qsort(gp, ngap, sizeof *gp, cmp_gap);
    for (i = 0; i < ngap; i++) {
        size_t m = grm[gp[i].k];
        const fend *fa = &g.fe[grs[gp[i].k] + gp[i].q], *fb = &g.fe[grs[gp[i].k] + (gp[i].q + 1) % m];
        if (uf_find(uf, fa->node) != uf_find(uf, fb->node)) {
            if ((rc = patch_add(&g, &P, R, fa, fb, 1, err)) != AMP_OK)
                goto done;
            uf_union(uf, fa->node, fb->node);
            st->joins++;
        } else if (o->support_stretches) {
            /* Remark 2.1: print the unprinted stretch on its own */
            if ((rc = ring_support(&g, R, fa, fb, out, z, o->radius, err)) != AMP_OK)
                goto done;
            st->support_paths++;
            st->support_length += gp[i].len;
        } else
            st->unprinted_length += gp[i].len;
    }
    /* Figs. 7, 8: every patch against the printed edges near it, then into
     * the graph (a join twice: printed, and back as a pseudo edge) */
    for (k = 0; k < P.n; k++) {
        if ((rc = patch_points(&g, &P, k, D, err)) != AMP_OK)
            goto done;
        if (add_chain(&g, P.a[k], P.b[k], 0, &pseudo) != AMP_OK ||
            (P.join[k] && add_chain(&g, P.a[k], P.b[k], 1, &pseudo) != AMP_OK)) {
            rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
            goto done;
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
        if (out->paths[i].role == AMP_ROLE_OBJECT)
            st->infill_length += printed_len(out, i);
    st->pseudo_length += pseudo;
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
    amp_free(g.al, gp);
    patchset_free(g.al, &P);
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
            s0.printed_length += printed_len(out, q);
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
    double *r = amp_alloc(ps->alloc, (n + 1) * sizeof *r);
    amp_status st;
    if (!p || !r) {
        amp_free(ps->alloc, p);
        amp_free(ps->alloc, r);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking a stroke");
    }
    for (k = 0; k < n; k++) {
        p[k] = amp_v2(v[k].p.x, v[k].p.y);
        r[k] = v[k].r;
    }
    st = amp_stroke_check_radii(p, r, n, region, tol, rep, err);
    amp_free(ps->alloc, p);
    amp_free(ps->alloc, r);
    return st;
}
