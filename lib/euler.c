/* The Euler transformation of planar 2-complexes
 * ([P2 §1.3] Fig. 2, [P2 §3] Lemma 3.1, Def. 3.2, Lemma 3.3). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/euler.h"
#include "uf.h"

/* Intersection of the lines p + s*d and q + t*e; 0 when (nearly) parallel. */
static int line_meet(amp_vec2 p, amp_vec2 d, amp_vec2 q, amp_vec2 e, amp_vec2 *out)
{
    double den = d.x * e.y - d.y * e.x, s;
    if (fabs(den) < 1e-14)
        return 0;
    s = ((q.x - p.x) * e.y - (q.y - p.y) * e.x) / den;
    *out = amp_v2(p.x + s * d.x, p.y + s * d.y);
    return 1;
}

typedef struct face_off {
    amp_vec2 *pt;   /* offset polygon vertices (nalive) */
    size_t *alive;  /* surviving edge indices, increasing */
    size_t nalive;
    size_t *corner; /* corner k -> offset vertex index */
    amp_vec2 *dir, *base; /* unit direction and start point of each edge */
    amp_vec2 *corner_pt; /* scratch: the same vertices at time 0 */
} face_off;

/* Vertex between the offset lines of edges e0 and e1 (e1 follows e0) at
 * offset time t; 0 for a reversal (antiparallel consecutive edges). */
static int offset_vertex(const face_off *fo, size_t e0, size_t e1, double t, amp_vec2 *out)
{
    amp_vec2 d0 = fo->dir[e0], d1 = fo->dir[e1];
    amp_vec2 p0 = amp_v2(fo->base[e0].x - t * d0.y, fo->base[e0].y + t * d0.x);
    amp_vec2 p1 = amp_v2(fo->base[e1].x - t * d1.y, fo->base[e1].y + t * d1.x);
    if (line_meet(p0, d0, p1, d1, out))
        return 1;
    /* a straight angle (e.g. a boundary vertex of a Class 3 cell lying on
     * the segment of its neighbours): the miter is the corner shifted along
     * the common normal */
    if (d0.x * d1.x + d0.y * d1.y > 0) {
        *out = p1;
        return 1;
    }
    return 0;
}

/* Do segments ab and cd meet (proper crossing or touching)? */
static int segs_meet(amp_vec2 a, amp_vec2 b, amp_vec2 c, amp_vec2 d)
{
    double o1 = amp_v2_orient(a, b, c), o2 = amp_v2_orient(a, b, d), o3 = amp_v2_orient(c, d, a),
           o4 = amp_v2_orient(c, d, b);
    if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
        return 1;
#define ON(p, q, r, o) ((o) == 0 && fmin(p.x, q.x) <= r.x && r.x <= fmax(p.x, q.x) && fmin(p.y, q.y) <= r.y && r.y <= fmax(p.y, q.y))
    return ON(a, b, c, o1) || ON(a, b, d, o2) || ON(c, d, a, o3) || ON(c, d, b, o4);
#undef ON
}

/*
 * Mitered offset of face f by delta (Class 1 cell, §1.3): the wavefront of
 * the cell's edges moving inward at unit speed, at time delta. Without
 * combinatorial changes every edge must keep a positive length. With them
 * (§3) the edge events are simulated in time order: each edge's length is
 * linear in time between events, the edge that reaches length 0 first is
 * dropped and its neighbours' offset lines meet instead, as long as at
 * least 3 edges remain ("we can reduce at most n-3 edges"). This holds for
 * non-convex cells as well, as long as no reflex corner runs into another
 * edge (a split event, a topological change): the offset of a non-convex
 * cell must therefore be a simple polygon, otherwise it is rejected.
 */
static amp_status miter_face(const amp_cx2 *k, size_t f, double delta, int comb, face_off *fo, amp_error *err)
{
    size_t a = k->fstart[f], n = k->fstart[f + 1] - a, j, i;
    int convex = 1;
    for (i = 0; i < n; i++) {
        amp_vec2 p = k->v[k->fidx[a + i]], q = k->v[k->fidx[a + (i + 1) % n]];
        double dx = q.x - p.x, dy = q.y - p.y, l = hypot(dx, dy);
        if (l == 0)
            return amp_fail(err, AMP_ERR_GEOMETRY, 0, "2-cell %lu has a zero-length edge", (unsigned long)f);
        fo->dir[i] = amp_v2(dx / l, dy / l);
        fo->base[i] = p;
        fo->alive[i] = i;
        if (amp_v2_orient(p, q, k->v[k->fidx[a + (i + 2) % n]]) < 0)
            convex = 0;
    }
    fo->nalive = n;
    for (;;) {
        size_t worst = n, m = fo->nalive;
        double wt = HUGE_VAL;
        /* pt = vertices at time delta, len0 from the vertices at time 0 of
         * the same lines (lengths are linear in time) */
        for (j = 0; j < m; j++) {
            size_t e0 = fo->alive[j], e1 = fo->alive[(j + 1) % m];
            if (!offset_vertex(fo, e0, e1, delta, &fo->pt[j]) || !offset_vertex(fo, e0, e1, 0, &fo->corner_pt[j]))
                return amp_fail(err, AMP_ERR_GEOMETRY, 0, "mitered offset %g of 2-cell %lu degenerates (parallel edges)",
                                delta, (unsigned long)f);
        }
        /* an offset edge runs from the vertex before it to the vertex after it */
        for (j = 0; j < m; j++) {
            size_t e = fo->alive[j], jp = (j + m - 1) % m;
            amp_vec2 s = fo->pt[jp], t = fo->pt[j], s0 = fo->corner_pt[jp], t0 = fo->corner_pt[j];
            double len = (t.x - s.x) * fo->dir[e].x + (t.y - s.y) * fo->dir[e].y;
            double l0 = (t0.x - s0.x) * fo->dir[e].x + (t0.y - s0.y) * fo->dir[e].y, when;
            if (len > 1e-12 * (1 + delta))
                continue;
            /* time at which this edge reaches length 0 */
            when = l0 - len > 0 ? delta * fmax(l0, 0) / (l0 - len) : 0;
            if (worst == n || when < wt) {
                worst = j;
                wt = when;
            }
        }
        if (worst == n)
            break;
        if (!comb)
            return amp_fail(err, AMP_ERR_GEOMETRY, 0,
                            "mitered offset %g of 2-cell %lu changes combinatorially (edge %lu collapses)", delta,
                            (unsigned long)f, (unsigned long)fo->alive[worst]);
        if (m <= 3)
            return amp_fail(err, AMP_ERR_GEOMETRY, 0, "mitered offset %g makes 2-cell %lu vanish (topological change)",
                            delta, (unsigned long)f);
        memmove(fo->alive + worst, fo->alive + worst + 1, (m - worst - 1) * sizeof *fo->alive);
        fo->nalive--;
    }
    /* corners alive[j]+1 .. alive[j+1] (cyclic) all map to vertex j: the
     * end copies of the dropped edges merge (Lemma 3.1) */
    for (j = 0; j < fo->nalive; j++) {
        size_t e0 = fo->alive[j], e1 = fo->alive[(j + 1) % fo->nalive], c = (e0 + 1) % n;
        for (;;) {
            fo->corner[c] = j;
            if (c == e1)
                break;
            c = (c + 1) % n;
        }
    }
    if (amp_ring_area(fo->pt, fo->nalive) <= 0)
        return amp_fail(err, AMP_ERR_GEOMETRY, 0, "mitered offset %g of 2-cell %lu is inverted", delta,
                        (unsigned long)f);
    /* a reflex corner that ran into another edge leaves a self-intersecting
     * offset: a split (topological change, future work in the paper) */
    for (i = 0; !convex && i < fo->nalive; i++)
        for (j = i + 2; j < fo->nalive; j++) {
            size_t m = fo->nalive;
            if (i == 0 && j == m - 1)
                continue;
            if (segs_meet(fo->pt[(i + m - 1) % m], fo->pt[i], fo->pt[(j + m - 1) % m], fo->pt[j]))
                return amp_fail(err, AMP_ERR_GEOMETRY, 0,
                                "mitered offset %g of non-convex 2-cell %lu is not simple (a reflex corner crosses "
                                "an edge: topological change)",
                                delta, (unsigned long)f);
        }
    return AMP_OK;
}

/* Add a cell after removing cyclically repeated consecutive vertices;
 * two remaining vertices make a free 1-cell (a collapsed Class 2 cell). */
static amp_status add_cell(amp_cx2 *out, uint32_t *v, size_t n, int cls, int *collapsed, amp_error *err)
{
    size_t i, m = 0;
    *collapsed = 0;
    for (i = 0; i < n; i++)
        if (m == 0 || v[m - 1] != v[i])
            v[m++] = v[i];
    while (m > 1 && v[m - 1] == v[0])
        m--;
    if (m >= 3)
        return amp_cx2_add_face(out, v, m, cls, err);
    if (m == 2) {
        *collapsed = 1;
        return amp_cx2_add_edge(out, v[0], v[1], err);
    }
    return AMP_OK;
}

/* The working state of T(K): copies of the corners (cmap), kept boundary vertices (bmap), vertex fans. */
typedef struct tstate {
    const amp_cx2 *k;
    amp_cx2 *out;
    amp_euler_stats s;
    uint32_t *cmap;      /* half-edge h -> copy of its corner in the Class 1 cell of its face */
    uint32_t *bmap;      /* boundary vertex of K -> its vertex in K̂ (UINT32_MAX for the others) */
    uint32_t *loop;      /* one cell's vertices */
    size_t *vstart;      /* CSR of the outgoing half-edges per vertex (vhe) */
    size_t *vhe;
    unsigned char *seen; /* half-edge already in a Class 3 fan */
} tstate;

/* Class 1: mitered offsets of every face; cmap[h] = copy of the corner of half-edge h. */
static amp_status class1_cells(tstate *t, const amp_euler_opts *o, face_off *fo, amp_error *err)
{
    const amp_cx2 *k = t->k;
    amp_status rc = AMP_OK;
    size_t f;
    for (f = 0; f < k->nf && rc == AMP_OK; f++) {
        size_t a = k->fstart[f], n = k->fstart[f + 1] - a, j;
        uint32_t base = (uint32_t)t->out->nv;
        if ((rc = miter_face(k, f, o->offset, o->combinatorial, fo, err)) != AMP_OK)
            break;
        t->s.collapsed_edges += n - fo->nalive;
        for (j = 0; j < fo->nalive && rc == AMP_OK; j++)
            rc = amp_cx2_add_vertex(t->out, fo->pt[j], NULL, err);
        for (j = 0; j < n; j++)
            t->cmap[a + j] = base + (uint32_t)fo->corner[j];
        for (j = 0; j < fo->nalive; j++)
            t->loop[j] = base + (uint32_t)j;
        if (rc == AMP_OK)
            rc = amp_cx2_add_face(t->out, t->loop, fo->nalive, AMP_CELL_CLASS1, err);
    }
    return rc;
}

/* The boundary vertices of K stay as vertices of K̂. */
static amp_status keep_boundary(tstate *t, amp_error *err)
{
    const amp_cx2 *k = t->k;
    amp_status rc = AMP_OK;
    size_t h, v;
    for (v = 0; v < k->nv; v++)
        t->bmap[v] = UINT32_MAX;
    for (h = 0; h < k->nfidx && rc == AMP_OK; h++)
        if (k->he_twin[h] == AMP_CX2_NONE) {
            uint32_t ends[2];
            int e;
            ends[0] = k->fidx[h];
            ends[1] = k->fidx[amp_cx2_he_next(k, h)];
            for (e = 0; e < 2 && rc == AMP_OK; e++)
                if (t->bmap[ends[e]] == UINT32_MAX)
                    rc = amp_cx2_add_vertex(t->out, k->v[ends[e]], &t->bmap[ends[e]], err);
        }
    return rc;
}

/* Class 2: one trapezium per edge (a segment where two corners coincide). */
static amp_status class2_cells(tstate *t, amp_error *err)
{
    const amp_cx2 *k = t->k;
    amp_status rc = AMP_OK;
    size_t h;
    int col;
    for (h = 0; h < k->nfidx && rc == AMP_OK; h++) {
        size_t tw = k->he_twin[h], hn = amp_cx2_he_next(k, h);
        if (tw != AMP_CX2_NONE && tw < h)
            continue;
        if (tw != AMP_CX2_NONE) {
            t->loop[0] = t->cmap[amp_cx2_he_next(k, tw)]; /* a in g */
            t->loop[1] = t->cmap[tw];                     /* b in g */
        } else {
            t->loop[0] = t->bmap[k->fidx[h]];
            t->loop[1] = t->bmap[k->fidx[hn]];
        }
        t->loop[2] = t->cmap[hn]; /* b in f */
        t->loop[3] = t->cmap[h];  /* a in f */
        rc = add_cell(t->out, t->loop, 4, AMP_CELL_CLASS2, &col, err);
        t->s.collapsed_class2 += (size_t)col;
    }
    return rc;
}

/* Class 3: the copies of each vertex around it, CCW (outgoing half-edges advance by twin(prev(h))); a
 * boundary fan starts at v itself, so boundary fans go first (pass 0), then the closed ones. */
static amp_status class3_cells(tstate *t, amp_error *err)
{
    const amp_cx2 *k = t->k;
    amp_status rc = AMP_OK;
    size_t h, v, i;
    int col;
    for (h = 0; h < k->nfidx; h++)
        t->vstart[k->fidx[h] + 2]++;
    for (v = 0; v < k->nv; v++)
        t->vstart[v + 2] += t->vstart[v + 1];
    for (h = 0; h < k->nfidx; h++)
        t->vhe[t->vstart[k->fidx[h] + 1]++] = h;
    for (v = 0; v < k->nv && rc == AMP_OK; v++) {
        int pass;
        for (pass = 0; pass < 2 && rc == AMP_OK; pass++)
            for (i = t->vstart[v]; i < t->vstart[v + 1] && rc == AMP_OK; i++) {
                size_t hh = t->vhe[i], m = 0;
                if (t->seen[hh] || (pass == 0 && k->he_twin[hh] != AMP_CX2_NONE))
                    continue;
                if (pass == 0)
                    t->loop[m++] = t->bmap[v];
                for (;;) {
                    size_t p;
                    t->seen[hh] = 1;
                    t->loop[m++] = t->cmap[hh];
                    p = k->he_twin[amp_cx2_he_prev(k, hh)];
                    if (p == AMP_CX2_NONE || t->seen[p] || m > k->nfidx)
                        break;
                    hh = p;
                }
                if (m >= 3)
                    rc = add_cell(t->out, t->loop, m, AMP_CELL_CLASS3, &col, err);
            }
    }
    return rc;
}

static void face_off_free(const amp_allocator *al, face_off *fo)
{
    amp_free(al, fo->pt);
    amp_free(al, fo->alive);
    amp_free(al, fo->corner);
    amp_free(al, fo->dir);
    amp_free(al, fo->base);
    amp_free(al, fo->corner_pt);
}

/* T(K) (§1.3). @p bmap_out (optional, k->nv entries) receives, for every
 * boundary vertex of K, its index in K̂ (UINT32_MAX for the others): the
 * boundary of K is kept as it is, which is what lets Lemma 3.3 glue a
 * transformed sub-complex back into its surroundings. */
static amp_status transform(const amp_cx2 *k, const amp_euler_opts *o, amp_cx2 *out, amp_euler_stats *st,
                            uint32_t *bmap_out, amp_error *err)
{
    const amp_allocator *al = out->alloc;
    tstate t;
    face_off fo;
    size_t f, maxn = 3;
    amp_status rc;
    memset(&t, 0, sizeof t);
    memset(&fo, 0, sizeof fo);
    amp_cx2_free(out);
    if (!o || !(o->offset > 0) || !isfinite(o->offset))
        return amp_fail(err, AMP_ERR_ARG, 0, "Euler transformation needs a positive offset");
    if (k->nxe)
        return amp_fail(err, AMP_ERR_ARG, 0, "input complex is not pure (%lu free edges)", (unsigned long)k->nxe);
    if (!k->built || (k->nf && !k->he_twin))
        return amp_fail(err, AMP_ERR_STATE, 0, "input complex topology not built (amp_cx2_build)");
    for (f = 0; f < k->nf; f++)
        if (amp_cx2_face_size(k, f) > maxn)
            maxn = amp_cx2_face_size(k, f);
    t.k = k;
    t.out = out;
    fo.pt = amp_alloc(al, maxn * sizeof *fo.pt);
    fo.alive = amp_alloc(al, maxn * sizeof *fo.alive);
    fo.corner = amp_alloc(al, maxn * sizeof *fo.corner);
    fo.dir = amp_alloc(al, maxn * sizeof *fo.dir);
    fo.base = amp_alloc(al, maxn * sizeof *fo.base);
    fo.corner_pt = amp_alloc(al, maxn * sizeof *fo.corner_pt);
    t.cmap = amp_alloc(al, (k->nfidx + 1) * sizeof *t.cmap);
    t.bmap = bmap_out ? bmap_out : amp_alloc(al, (k->nv + 1) * sizeof *t.bmap);
    t.loop = amp_alloc(al, (2 * k->nfidx + 4) * sizeof *t.loop);
    t.vstart = amp_calloc(al, k->nv + 2, sizeof *t.vstart);
    t.vhe = amp_alloc(al, (k->nfidx + 1) * sizeof *t.vhe);
    t.seen = amp_calloc(al, k->nfidx + 1, 1);
    if (!fo.pt || !fo.alive || !fo.corner || !fo.dir || !fo.base || !fo.corner_pt || !t.cmap || !t.bmap || !t.loop ||
        !t.vstart || !t.vhe || !t.seen)
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the Euler transformation");
    else if ((rc = class1_cells(&t, o, &fo, err)) == AMP_OK && (rc = keep_boundary(&t, err)) == AMP_OK &&
             (rc = class2_cells(&t, err)) == AMP_OK && (rc = class3_cells(&t, err)) == AMP_OK)
        rc = amp_cx2_build(out, err);
    face_off_free(al, &fo);
    amp_free(al, t.cmap);
    if (t.bmap != bmap_out)
        amp_free(al, t.bmap);
    amp_free(al, t.loop);
    amp_free(al, t.vstart);
    amp_free(al, t.vhe);
    amp_free(al, t.seen);
    if (st)
        *st = t.s;
    return rc;
}

amp_status amp_euler_transform(const amp_cx2 *k, const amp_euler_opts *o, amp_cx2 *out, amp_euler_stats *st,
                               amp_error *err)
{
    return transform(k, o, out, st, NULL, err);
}

/* A quarter of the smallest feature of k: shortest edge and 2*area/perimeter. */
static double feature_size(const amp_cx2 *k)
{
    double best = HUGE_VAL;
    size_t f, j;
    for (f = 0; f < k->nf; f++) {
        size_t a = k->fstart[f], n = k->fstart[f + 1] - a;
        double per = 0, area = 0;
        for (j = 0; j < n; j++) {
            amp_vec2 p = k->v[k->fidx[a + j]], q = k->v[k->fidx[a + (j + 1) % n]];
            double l = hypot(q.x - p.x, q.y - p.y);
            per += l;
            area += p.x * q.y - q.x * p.y;
            if (l < best)
                best = l;
        }
        if (per > 0 && area / per < best)
            best = area / per; /* 0.5*area2/per*2 = 2*area/perimeter */
    }
    return best;
}

/* T(K) without combinatorial changes at offset delta, halved (up to 8
 * times) until every mitered offset is valid: the passes of Def. 3.2 after
 * the first one only need some offset small enough for their cells. */
static amp_status transform_fitting(const amp_cx2 *k, double delta, amp_cx2 *out, uint32_t *bmap, amp_error *err)
{
    amp_euler_opts o;
    amp_status rc = AMP_ERR_GEOMETRY;
    int tries;
    o.combinatorial = 0;
    o.offset = delta;
    for (tries = 0; tries < 8; tries++) {
        rc = transform(k, &o, out, NULL, bmap, err);
        if (rc != AMP_ERR_GEOMETRY)
            break;
        o.offset *= 0.5;
    }
    return rc;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t s = *(const uint64_t *)a, t = *(const uint64_t *)b;
    return s < t ? -1 : (s > t ? 1 : 0);
}

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

/* The Lemma 3.3 repair's working state: the input, k̂ (marked cells, sub), T(k̂), T(T(k̂)) and the maps. */
typedef struct repair {
    const amp_cx2 *khat;
    const amp_allocator *al;
    amp_euler_repair_stats s;
    amp_cx2 sub, t1, t2;     /* k̂ on its own vertices, T(k̂), T(T(k̂)) */
    uint64_t *keys;          /* collapsed edges ê, sorted */
    unsigned char *cover;    /* per collapsed edge: seen on a cell */
    unsigned char *mark;     /* per cell of K̂: in k̂ */
    size_t *par;             /* union-find over cells: components k̂_j */
    uint32_t *vmap, *vback;  /* K̂ vertex <-> sub vertex */
    uint32_t *bmap1, *bmap2; /* boundary vertices through T and T again */
    uint32_t *tmap;          /* T(T(k̂)) vertex -> out vertex */
    uint32_t *loop;          /* one face's vertices (maxn) */
    size_t maxn;             /* largest face of K̂, at least 3 */
} repair;

static void repair_free(repair *r)
{
    amp_cx2_free(&r->sub);
    amp_cx2_free(&r->t1);
    amp_cx2_free(&r->t2);
    amp_free(r->al, r->keys);
    amp_free(r->al, r->cover);
    amp_free(r->al, r->mark);
    amp_free(r->al, r->par);
    amp_free(r->al, r->vmap);
    amp_free(r->al, r->vback);
    amp_free(r->al, r->bmap1);
    amp_free(r->al, r->bmap2);
    amp_free(r->al, r->tmap);
    amp_free(r->al, r->loop);
}

static amp_status repair_nomem(amp_error *err)
{
    return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the Lemma 3.3 repair");
}

/* k̂: the cells with a collapsed edge ê; each must be a Class 3 cell and each ê on some cell. */
static amp_status mark_collapsed_cells(repair *r, amp_error *err)
{
    const amp_cx2 *khat = r->khat;
    size_t i, h, f;
    for (i = 0; i < khat->nxe; i++)
        r->keys[i] = edge_key(khat->xedge[2 * i], khat->xedge[2 * i + 1]);
    if (khat->nxe > 1)
        qsort(r->keys, khat->nxe, sizeof *r->keys, cmp_u64);
    for (h = 0; h < khat->nfidx && khat->nxe; h++) {
        uint64_t key = edge_key(khat->fidx[h], khat->fidx[amp_cx2_he_next(khat, h)]);
        const uint64_t *hit = bsearch(&key, r->keys, khat->nxe, sizeof *r->keys, cmp_u64);
        if (!hit)
            continue;
        f = khat->he_face[h];
        if (khat->fclass[f] != AMP_CELL_CLASS3)
            return amp_fail(err, AMP_ERR_GEOMETRY, 0,
                            "free edge %lu-%lu lies on a 2-cell of class %d, not between Class 3 cells (Lemma 3.3)",
                            (unsigned long)(key >> 32), (unsigned long)(key & 0xffffffffu), khat->fclass[f]);
        r->mark[f] = 1;
        r->cover[hit - r->keys] = 1;
    }
    for (i = 0; i < khat->nxe; i++)
        if (!r->cover[i])
            return amp_fail(err, AMP_ERR_GEOMETRY, 0,
                            "free edge %lu-%lu is in no 2-cell: not a Class 2 cell collapsed between Class 3 cells "
                            "(Lemma 3.3)",
                            (unsigned long)(r->keys[i] >> 32), (unsigned long)(r->keys[i] & 0xffffffffu));
    return AMP_OK;
}

/* The components k̂_j (marked cells joined by shared edges, counted) and the sub-complex k̂ on its own vertices. */
static amp_status extract_subcomplex(repair *r, amp_error *err)
{
    const amp_cx2 *khat = r->khat;
    amp_status rc = AMP_OK;
    size_t i, h, f;
    for (f = 0; f < khat->nf; f++)
        r->par[f] = f;
    for (h = 0; h < khat->nfidx; h++) {
        size_t t = khat->he_twin[h];
        if (t != AMP_CX2_NONE && r->mark[khat->he_face[h]] && r->mark[khat->he_face[t]])
            amp_uf_union(r->par, khat->he_face[h], khat->he_face[t]);
    }
    for (i = 0; i < khat->nv; i++)
        r->vmap[i] = UINT32_MAX;
    for (f = 0; f < khat->nf && rc == AMP_OK; f++) {
        size_t a = khat->fstart[f], n = khat->fstart[f + 1] - a, j;
        if (!r->mark[f])
            continue;
        r->s.cells++;
        r->s.components += amp_uf_find(r->par, f) == f;
        for (j = 0; j < n && rc == AMP_OK; j++) {
            uint32_t v = khat->fidx[a + j];
            if (r->vmap[v] == UINT32_MAX)
                rc = amp_cx2_add_vertex(&r->sub, khat->v[v], &r->vmap[v], err);
            r->loop[j] = r->vmap[v];
        }
        if (rc == AMP_OK)
            rc = amp_cx2_add_face(&r->sub, r->loop, n, AMP_CELL_INPUT, err);
    }
    return rc;
}

/* Def. 3.2 on k̂: T(T(k̂)), offsets a quarter of the smallest feature; tmap glues k̂'s boundary vertices,
 * which survive both passes, back onto K̂'s. */
static amp_status transform_twice(repair *r, amp_error *err)
{
    amp_status rc;
    size_t i;
    r->vback = amp_alloc(r->al, r->sub.nv * sizeof *r->vback);
    r->bmap1 = amp_alloc(r->al, r->sub.nv * sizeof *r->bmap1);
    if (!r->vback || !r->bmap1)
        return repair_nomem(err);
    for (i = 0; i < r->khat->nv; i++)
        if (r->vmap[i] != UINT32_MAX)
            r->vback[r->vmap[i]] = (uint32_t)i;
    if ((rc = amp_cx2_build(&r->sub, err)) != AMP_OK ||
        (rc = transform_fitting(&r->sub, 0.25 * feature_size(&r->sub), &r->t1, r->bmap1, err)) != AMP_OK)
        return rc;
    if (!(r->bmap2 = amp_alloc(r->al, r->t1.nv * sizeof *r->bmap2)))
        return repair_nomem(err);
    if ((rc = transform_fitting(&r->t1, 0.25 * feature_size(&r->t1), &r->t2, r->bmap2, err)) != AMP_OK)
        return rc;
    if (!(r->tmap = amp_alloc(r->al, (r->t2.nv + 1) * sizeof *r->tmap)))
        return repair_nomem(err);
    for (i = 0; i < r->t2.nv; i++)
        r->tmap[i] = UINT32_MAX;
    for (i = 0; i < r->sub.nv; i++) {
        uint32_t u = r->bmap1[i];
        if (u == UINT32_MAX || r->bmap2[u] == UINT32_MAX)
            return amp_fail(err, AMP_ERR_GEOMETRY, 0, "vertex %lu is inside the Class 3 sub-complex (Lemma 3.3)",
                            (unsigned long)r->vback[i]);
        r->tmap[r->bmap2[u]] = r->vback[i];
    }
    return AMP_OK;
}

/* (K̂ \ k̂) ∪ T(T(k̂)) into @p out; the free edges ê are inside k̂ and go with it. */
static amp_status splice_repaired(repair *r, amp_cx2 *out, amp_error *err)
{
    const amp_cx2 *khat = r->khat;
    amp_status rc = AMP_OK;
    size_t i, f;
    for (i = 0; i < khat->nv && rc == AMP_OK; i++)
        rc = amp_cx2_add_vertex(out, khat->v[i], NULL, err);
    for (f = 0; f < khat->nf && rc == AMP_OK; f++)
        if (!r->mark[f])
            rc = amp_cx2_add_face(out, khat->fidx + khat->fstart[f], amp_cx2_face_size(khat, f), khat->fclass[f], err);
    for (i = 0; i < r->t2.nv && rc == AMP_OK; i++)
        if (r->tmap[i] == UINT32_MAX)
            rc = amp_cx2_add_vertex(out, r->t2.v[i], &r->tmap[i], err);
    for (f = 0; f < r->t2.nf && rc == AMP_OK; f++) {
        size_t a = r->t2.fstart[f], n = r->t2.fstart[f + 1] - a, j;
        uint32_t *lp = n <= r->maxn ? r->loop : NULL;
        if (!lp && !(lp = amp_alloc(r->al, n * sizeof *lp)))
            return repair_nomem(err);
        for (j = 0; j < n; j++)
            lp[j] = r->tmap[r->t2.fidx[a + j]];
        rc = amp_cx2_add_face(out, lp, n, r->t2.fclass[f], err);
        if (lp != r->loop)
            amp_free(r->al, lp);
    }
    return rc == AMP_OK ? amp_cx2_build(out, err) : rc;
}

/*
 * Lemma 3.3. k̂ = the Class 3 cells sharing a collapsed Class 2 edge ê (in
 * T(K), ê joins the merged copies P_f = Q_f and P_g = Q_g, so it is the edge
 * between the Class 3 cells of P and Q, and the free 1-cell only repeats it).
 * Every vertex of k̂ lies on its boundary (it is a copy in a Class 1 cell or
 * a boundary vertex of K, never surrounded by Class 3 cells alone) and has an
 * even number of K̂ edges outside k̂ (proof of Lemma 3.3). T(T(k̂)) (Def. 3.2)
 * keeps k̂'s boundary vertices and edges and gives each of them degree 4 per
 * fan, so (K̂ \ k̂) ∪ T(T(k̂)) has even degrees wherever T(K) had only the
 * odd vertices of collapsed Class 2 cells. The components k̂_j are
 * transformed together: T is local (one cell per cell, edge and vertex of
 * k̂, fans taken one by one at a vertex shared by two components), so this
 * equals transforming each k̂_j (each k̃_i) on its own.
 */
amp_status amp_euler_repair(const amp_cx2 *khat, amp_cx2 *out, amp_euler_repair_stats *st, amp_error *err)
{
    repair r;
    size_t f;
    amp_status rc;
    memset(&r, 0, sizeof r);
    if (st)
        *st = r.s;
    if (out == khat)
        return amp_fail(err, AMP_ERR_ARG, 0, "Lemma 3.3 repair needs distinct input and output complexes");
    amp_cx2_free(out);
    if (!khat->built || (khat->nf && !khat->he_twin))
        return amp_fail(err, AMP_ERR_STATE, 0, "complex topology not built (amp_cx2_build)");
    r.khat = khat;
    r.al = out->alloc;
    r.maxn = 3;
    amp_cx2_init(&r.sub, r.al);
    amp_cx2_init(&r.t1, r.al);
    amp_cx2_init(&r.t2, r.al);
    for (f = 0; f < khat->nf; f++)
        if (amp_cx2_face_size(khat, f) > r.maxn)
            r.maxn = amp_cx2_face_size(khat, f);
    r.keys = amp_alloc(r.al, (khat->nxe + 1) * sizeof *r.keys);
    r.cover = amp_calloc(r.al, khat->nxe + 1, 1);
    r.mark = amp_calloc(r.al, khat->nf + 1, 1);
    r.par = amp_alloc(r.al, (khat->nf + 1) * sizeof *r.par);
    r.vmap = amp_alloc(r.al, (khat->nv + 1) * sizeof *r.vmap);
    r.loop = amp_alloc(r.al, (r.maxn + 1) * sizeof *r.loop);
    if (!r.keys || !r.cover || !r.mark || !r.par || !r.vmap || !r.loop)
        rc = repair_nomem(err);
    else if ((rc = mark_collapsed_cells(&r, err)) == AMP_OK && (rc = extract_subcomplex(&r, err)) == AMP_OK) {
        r.s.collapsed_edges = khat->nxe;
        if (r.sub.nf)
            rc = transform_twice(&r, err);
        if (rc == AMP_OK)
            rc = splice_repaired(&r, out, err);
    }
    if (rc != AMP_OK)
        amp_cx2_free(out);
    else if (st)
        *st = r.s;
    repair_free(&r);
    return rc;
}

amp_status amp_euler_generalized(const amp_cx2 *k, const amp_euler_opts *o, amp_cx2 *out, amp_error *err)
{
    amp_cx2 mid, rep;
    amp_euler_stats st;
    amp_status rc;
    amp_cx2_init(&mid, out->alloc);
    amp_cx2_init(&rep, out->alloc);
    /* Def. 3.2: apply the transformation twice */
    rc = amp_euler_transform(k, o, &mid, &st, err);
    /* collapsed Class 2 cells (free edges): Lemma 3.3's local repair first,
     * which also makes the complex pure again for the second pass */
    if (rc == AMP_OK && st.collapsed_class2) {
        rc = amp_euler_repair(&mid, &rep, NULL, err);
        amp_cx2_free(&mid);
        mid = rep;
        amp_cx2_init(&rep, out->alloc);
    }
    if (rc == AMP_OK)
        rc = transform_fitting(&mid, 0.25 * fmin(o->offset, feature_size(&mid)), out, NULL, err);
    amp_cx2_free(&mid);
    return rc;
}
