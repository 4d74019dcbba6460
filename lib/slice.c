/* Planar slicing: triangle-plane sections chained by shared mesh edges
 * ([P2 §2.2] step 1). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/slice.h"

typedef struct sseg {
    uint64_t ks, ke; /* mesh edges (lo << 32 | hi) where the segment starts and ends */
    size_t next;     /* following segment of the chain, or SIZE_MAX */
    int used, has_prev;
} sseg;

typedef struct skey {
    uint64_t k;
    size_t seg;
} skey;

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

static int cmp_key(const void *a, const void *b)
{
    const skey *s = a, *t = b;
    if (s->k != t->k)
        return s->k < t->k ? -1 : 1;
    return s->seg < t->seg ? -1 : (s->seg > t->seg ? 1 : 0);
}

/* Section point on mesh edge @p k, computed from the edge in canonical
 * (lo, hi) order so that both triangles sharing it get the same bits. */
static amp_vec2 edge_point(const amp_mesh *m, uint64_t k, double z)
{
    amp_vec3 a = m->verts[k >> 32], b = m->verts[k & 0xffffffffu];
    double t = (z - a.z) / (b.z - a.z);
    return amp_v2(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y));
}

/* First index of key @p k among the sorted starts, or n. */
static size_t find_key(const skey *s, size_t n, uint64_t k)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (s[mid].k < k)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && s[lo].k == k ? lo : n;
}

/* The section segments: one per triangle the plane z crosses, from the
 * mesh edge it enters by to the one it leaves by, into *seg (*nseg).
 * Triangles tri[0..ntri) in that order, or all of them when tri is NULL. */
static amp_status cut_triangles(const amp_mesh *m, const uint32_t *tri, size_t ntri, double z, const amp_allocator *al,
                                sseg **seg, size_t *nseg)
{
    size_t i, cap = 0;
    for (i = 0; i < ntri; i++) {
        const uint32_t *v = m->tris[tri ? tri[i] : i].v;
        /* symbolic perturbation: a vertex on the plane counts as above it */
        int s[3], k, kin = -1, kout = -1;
        void *p = *seg;
        sseg *g;
        for (k = 0; k < 3; k++)
            s[k] = m->verts[v[k]].z >= z;
        if (s[0] == s[1] && s[1] == s[2])
            continue;
        /* with the solid's outward normals, walking the triangle edges, the
         * section leaves through the edge going from above to below and
         * arrives through the edge going from below to above: this orders
         * the segment with the solid on its left (outer boundaries CCW) */
        for (k = 0; k < 3; k++) {
            int n = (k + 1) % 3;
            if (s[k] && !s[n])
                kout = k;
            if (!s[k] && s[n])
                kin = k;
        }
        if (amp_grow(al, &p, &cap, *nseg + 1, sizeof **seg) != AMP_OK)
            return AMP_ERR_NOMEM;
        *seg = p;
        g = &(*seg)[(*nseg)++];
        g->ks = edge_key(v[kout], v[(kout + 1) % 3]);
        g->ke = edge_key(v[kin], v[(kin + 1) % 3]);
        g->next = SIZE_MAX;
        g->used = 0;
        g->has_prev = 0;
    }
    return AMP_OK;
}

/* Link each segment to the one starting on the edge where it ends:
 * topology (edge ids), not coordinates. Counts edges where two segments
 * start (a non-manifold mesh) in st0->nonmanifold. */
static amp_status link_segments(const amp_allocator *al, sseg *seg, size_t nseg, amp_section_stats *st0)
{
    size_t i;
    skey *starts = amp_alloc(al, nseg * sizeof *starts);
    if (!starts)
        return AMP_ERR_NOMEM;
    for (i = 0; i < nseg; i++) {
        starts[i].k = seg[i].ks;
        starts[i].seg = i;
    }
    if (nseg > 1)
        qsort(starts, nseg, sizeof *starts, cmp_key);
    for (i = 0; i + 1 < nseg; i++)
        if (starts[i].k == starts[i + 1].k)
            st0->nonmanifold++;
    for (i = 0; i < nseg; i++) {
        size_t j = find_key(starts, nseg, seg[i].ke);
        if (j < nseg) {
            seg[i].next = starts[j].seg;
            seg[starts[j].seg].has_prev = 1;
        }
    }
    amp_free(al, starts);
    return AMP_OK;
}

/* Open chains (a mesh with cracks or a missing triangle, as exported STL
 * often is) are joined end to head, shortest gaps first, into rings, as
 * slicers close a section instead of losing the layer (a layer lost under
 * closed ones would leave those printed in the air). */
/* More open chains than this in one section: the mesh is too broken for the
 * quadratic pairing below; they are dropped (and counted). */
#define GAP_CHAINS_MAX 1024

static double gap_dist(amp_vec2 a, amp_vec2 b)
{
    return hypot(a.x - b.x, a.y - b.y);
}

typedef struct ochain {
    size_t first, n; /* points [first, first + n) of the open chains' buffer */
} ochain;

typedef struct gpair {
    double d;
    size_t tail, head;
} gpair;

static int cmp_gpair(const void *a, const void *b)
{
    const gpair *s = a, *t = b;
    if (s->d != t->d)
        return s->d < t->d ? -1 : 1;
    return s->tail != t->tail ? (s->tail < t->tail ? -1 : 1) : (s->head < t->head ? -1 : (s->head > t->head));
}

/* Each chain's tail to the nearest free head (shortest gaps first) in
 * nxt[]: a permutation, so every run is a cycle. */
static amp_status pair_gaps(const amp_allocator *al, const amp_vec2 *pt, const ochain *c, size_t k, size_t *nxt)
{
    size_t i, j, np = 0;
    gpair *pr = amp_alloc(al, k * k * sizeof *pr);
    char *taken = amp_calloc(al, 2 * k, 1);
    if (!pr || !taken) {
        amp_free(al, pr);
        amp_free(al, taken);
        return AMP_ERR_NOMEM;
    }
    for (i = 0; i < k; i++)
        for (j = 0; j < k; j++) {
            pr[np].d = gap_dist(pt[c[i].first + c[i].n - 1], pt[c[j].first]);
            pr[np].tail = i;
            pr[np++].head = j;
        }
    qsort(pr, np, sizeof *pr, cmp_gpair);
    for (i = 0; i < k; i++)
        nxt[i] = SIZE_MAX;
    for (i = 0; i < np; i++)
        if (!taken[pr[i].tail] && !taken[k + pr[i].head]) {
            taken[pr[i].tail] = taken[k + pr[i].head] = 1;
            nxt[pr[i].tail] = pr[i].head;
        }
    amp_free(al, pr);
    amp_free(al, taken);
    return AMP_OK;
}

/* Widest needle cut out of a section ring, mm: a spike A-B-C of no material (the ring runs out to B and back
 * along the same line) within 10 micrometres of its line, a fiftieth of a bead. */
#define NEEDLE_TOL 1e-2

/* Does the ring turn back at b (a -> b -> c) along one line, within NEEDLE_TOL of it? */
static int needle_at(amp_vec2 a, amp_vec2 b, amp_vec2 c)
{
    double ux = b.x - a.x, uy = b.y - a.y, vx = c.x - b.x, vy = c.y - b.y;
    double lu = sqrt(ux * ux + uy * uy), lv = sqrt(vx * vx + vy * vy);
    return ux * vx + uy * vy < 0.0 && fabs(ux * vy - uy * vx) <= NEEDLE_TOL * (lu > lv ? lu : lv);
}

/*
 * Cut needles out of ring p[0..n) in place; returns the new count (below 3: nothing is left). Coplanar faces
 * that overlap with opposite orientations (a non-convex polygon split into a fan of triangles by an OFF or OBJ
 * converter, a zero-thickness fin) cut into segments that run out and back along one line: the chained ring
 * gets spikes of no area whose near-collinear edges the union cannot order, and the section is left with
 * pieces on both sides of a line (CGAL's `mpi` fan-triangulated: 7,146 stroke points outside their layer).
 * The spike's tip goes (a stack: a tip cut may leave another), then the same across the ring's seam.
 */
static size_t cut_needles(amp_vec2 *p, size_t n)
{
    size_t m = 0, i, pass;
    for (i = 0; i < n; i++) {
        p[m++] = p[i];
        while (m >= 3 && needle_at(p[m - 3], p[m - 2], p[m - 1])) {
            p[m - 2] = p[m - 1];
            m--;
        }
    }
    for (pass = 0; pass < n && m >= 3; pass++) {
        if (needle_at(p[m - 2], p[m - 1], p[0]))
            m--;
        else if (needle_at(p[m - 1], p[0], p[1])) {
            memmove(p, p + 1, (m - 1) * sizeof *p);
            m--;
        } else
            break;
    }
    return m;
}

/* Open chains joined across their gaps into rings (added to @p out,
 * counted in st0->gaps_closed); the chains of a run too short for a ring
 * are dropped and counted in st0->open_chains. */
static amp_status close_gaps(const amp_vec2 *pt, const ochain *c, size_t k, amp_polyset *out,
                             amp_section_stats *st0, amp_error *err)
{
    const amp_allocator *al = out->alloc;
    size_t *nxt, i, pass, cap = 0, len;
    char *seen;
    amp_vec2 *ring = NULL;
    amp_status st = AMP_OK;
    if (k == 0 || k > GAP_CHAINS_MAX) {
        st0->open_chains += k;
        return AMP_OK;
    }
    nxt = amp_alloc(al, k * sizeof *nxt);
    seen = amp_calloc(al, 2 * k, 1); /* [0, k): walked; [k, 2k): has a predecessor */
    if (!nxt || !seen || (st = pair_gaps(al, pt, c, k, nxt)) != AMP_OK) {
        amp_free(al, nxt);
        amp_free(al, seen);
        return AMP_ERR_NOMEM;
    }
    for (i = 0; i < k; i++)
        if (nxt[i] != SIZE_MAX)
            seen[k + nxt[i]] = 1;
    /* pass 0 walks the runs that start at a chain without predecessor (they
     * stay open), pass 1 the cycles */
    for (pass = 0; pass < 2 && st == AMP_OK; pass++)
        for (i = 0; i < k && st == AMP_OK; i++) {
            size_t at = i, nch = 0, q;
            if (seen[i] || (pass == 0 && seen[k + i]))
                continue;
            for (len = 0; at != SIZE_MAX && !seen[at]; at = nxt[at], nch++) {
                void *p = ring;
                seen[at] = 1;
                if (amp_grow(al, &p, &cap, len + c[at].n, sizeof *ring) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    break;
                }
                ring = p;
                for (q = 0; q < c[at].n; q++) /* a closed gap of length 0 gives no repeated point */
                    if (len == 0 || gap_dist(ring[len - 1], pt[c[at].first + q]) > 0)
                        ring[len++] = pt[c[at].first + q];
            }
            if (st == AMP_OK && pass == 1 && len >= 3) {
                if (gap_dist(ring[len - 1], ring[0]) == 0)
                    len--;
                len = cut_needles(ring, len);
                /* a chain closed by its own chord that is all needle (an arc of an open wall, 10 um deep) is
                 * no region: it counts as open, so the layer it leaves empty is reported */
                if (len >= 3) {
                    st0->gaps_closed += nch;
                    st = amp_polyset_add(out, ring, len, err);
                } else
                    st0->open_chains += nch;
            } else if (st == AMP_OK)
                st0->open_chains += nch;
        }
    amp_free(al, ring);
    amp_free(al, nxt);
    amp_free(al, seen);
    return st;
}

/* The linked segments walked into rings: closed loops added to @p out;
 * open chains (from segments nobody leads to) collected, with the point
 * where their last segment ends, for close_gaps. */
static amp_status chain_segments(const amp_mesh *m, double z, sseg *seg, size_t nseg, amp_polyset *out,
                                 amp_section_stats *st0, amp_error *err)
{
    const amp_allocator *al = out->alloc;
    amp_vec2 *loop = NULL;
    ochain *oc = NULL;
    size_t i, pass, cap_loop = 0, cap_oc = 0, noc = 0, len = 0;
    amp_status st = AMP_OK;
    for (pass = 0; pass < 2 && st == AMP_OK; pass++)
        for (i = 0; i < nseg && st == AMP_OK; i++) {
            size_t at = i, last = i, start = len;
            int closed = 0;
            void *p;
            if (seg[i].used || (pass == 0 && seg[i].has_prev))
                continue;
            while (at != SIZE_MAX && !seg[at].used && st == AMP_OK) {
                p = loop;
                if (amp_grow(al, &p, &cap_loop, len + 2, sizeof *loop) != AMP_OK) {
                    st = AMP_ERR_NOMEM;
                    break;
                }
                loop = p;
                seg[at].used = 1;
                loop[len++] = edge_point(m, seg[at].ks, z);
                last = at;
                at = seg[at].next;
                if (at == i)
                    closed = 1;
            }
            if (st != AMP_OK)
                break;
            if (closed) {
                size_t k = cut_needles(loop + start, len - start);
                if (k >= 3)
                    st = amp_polyset_add(out, loop + start, k, err);
                len = start;
                continue;
            }
            loop[len++] = edge_point(m, seg[last].ke, z);
            p = oc;
            if (amp_grow(al, &p, &cap_oc, noc + 1, sizeof *oc) != AMP_OK) {
                st = AMP_ERR_NOMEM;
                break;
            }
            oc = p;
            oc[noc].first = start;
            oc[noc++].n = len - start;
        }
    if (st == AMP_OK)
        st = close_gaps(loop, oc, noc, out, st0, err);
    amp_free(al, loop);
    amp_free(al, oc);
    return st;
}

/* [P2 §2.2] step 1 at one height: cut, link, chain, resolve overlapping
 * shells (nonzero rule), organize; the triangles @p tri (ascending, NULL:
 * all) are those the plane may cross. */
static amp_status slice_plane(const amp_mesh *m, const uint32_t *tri, size_t ntri, double z, amp_polyset *out,
                              amp_section_stats *stats, amp_error *err)
{
    const amp_allocator *al = out->alloc;
    sseg *seg = NULL;
    size_t nseg = 0;
    amp_section_stats st0;
    amp_status st;
    memset(&st0, 0, sizeof st0);
    if (!isfinite(z))
        return amp_fail(err, AMP_ERR_ARG, 0, "cutting height is not finite");
    st = cut_triangles(m, tri, ntri, z, al, &seg, &nseg);
    st0.segments = st == AMP_OK ? nseg : 0;
    if (st == AMP_OK && nseg > 0 && (st = link_segments(al, seg, nseg, &st0)) == AMP_OK &&
        (st = chain_segments(m, z, seg, nseg, out, &st0, err)) == AMP_OK &&
        (st = amp_polyset_union(out, &st0.overlaps, err)) == AMP_OK)
        st = amp_polyset_organize(out, err);
    amp_free(al, seg);
    if (stats)
        *stats = st0;
    if (st == AMP_ERR_NOMEM)
        return amp_fail(err, st, 0, "out of memory slicing at z = %g", z);
    return st;
}

amp_status amp_slice_plane(const amp_mesh *m, double z, amp_polyset *out, amp_section_stats *stats, amp_error *err)
{
    return slice_plane(m, NULL, m->ntris, z, out, stats, err);
}

void amp_slices_init(amp_slices *s, const amp_allocator *a)
{
    memset(s, 0, sizeof *s);
    s->alloc = a;
}

void amp_slices_free(amp_slices *s)
{
    size_t i;
    if (!s)
        return;
    for (i = 0; i < s->nlayers; i++)
        amp_polyset_free(&s->layers[i].polys);
    amp_free(s->alloc, s->layers);
    amp_slices_init(s, s->alloc);
}

/* The triangles a rising plane crosses, kept from layer to layer: every
 * layer scanning the whole mesh cost more than the rest of slicing on a
 * million-triangle scan. Triangles enter in the order of their lowest z and
 * leave once the plane is above them; the active ones stay in index order,
 * so segments come out in the order of a full scan (identical sections). */
typedef struct zkey {
    double zlo;
    uint32_t t;
} zkey;

typedef struct tsweep {
    zkey *byz;
    uint32_t *act, *tmp;
    size_t n, next, nact;
} tsweep;

static int cmp_zkey(const void *a, const void *b)
{
    const zkey *s = a, *t = b;
    if (s->zlo != t->zlo)
        return s->zlo < t->zlo ? -1 : 1;
    return s->t < t->t ? -1 : (s->t > t->t ? 1 : 0);
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t s = *(const uint32_t *)a, t = *(const uint32_t *)b;
    return s < t ? -1 : (s > t ? 1 : 0);
}

static double tri_zmax(const amp_mesh *m, uint32_t t)
{
    const uint32_t *v = m->tris[t].v;
    return fmax(m->verts[v[0]].z, fmax(m->verts[v[1]].z, m->verts[v[2]].z));
}

static amp_status sweep_init(tsweep *w, const amp_mesh *m, const amp_allocator *al)
{
    size_t i;
    memset(w, 0, sizeof *w);
    w->n = m->ntris;
    w->byz = amp_alloc(al, (w->n + 1) * sizeof *w->byz);
    w->act = amp_alloc(al, (w->n + 1) * sizeof *w->act);
    w->tmp = amp_alloc(al, (w->n + 1) * sizeof *w->tmp);
    if (!w->byz || !w->act || !w->tmp)
        return AMP_ERR_NOMEM;
    for (i = 0; i < w->n; i++) {
        const uint32_t *v = m->tris[i].v;
        w->byz[i].zlo = fmin(m->verts[v[0]].z, fmin(m->verts[v[1]].z, m->verts[v[2]].z));
        w->byz[i].t = (uint32_t)i;
    }
    qsort(w->byz, w->n, sizeof *w->byz, cmp_zkey);
    return AMP_OK;
}

static void sweep_free(tsweep *w, const amp_allocator *al)
{
    amp_free(al, w->byz);
    amp_free(al, w->act);
    amp_free(al, w->tmp);
}

/* Move the plane up to z: a triangle is crossed when zlo < z <= zmax (a
 * vertex on the plane counts as above it, as cut_triangles decides). */
static void sweep_to(tsweep *w, const amp_mesh *m, double z)
{
    size_t i, j, k, nkeep = 0, nnew = 0;
    for (i = 0; i < w->nact; i++)
        if (tri_zmax(m, w->act[i]) >= z)
            w->act[nkeep++] = w->act[i];
    for (; w->next < w->n && w->byz[w->next].zlo < z; w->next++)
        if (tri_zmax(m, w->byz[w->next].t) >= z)
            w->tmp[nnew++] = w->byz[w->next].t;
    qsort(w->tmp, nnew, sizeof *w->tmp, cmp_u32);
    /* merge the kept and the new, both ascending, through the free end of tmp */
    memmove(w->tmp + w->n - nnew, w->tmp, nnew * sizeof *w->tmp);
    for (i = 0, j = w->n - nnew, k = 0; i < nkeep || j < w->n;)
        w->tmp[k++] = j >= w->n || (i < nkeep && w->act[i] < w->tmp[j]) ? w->act[i++] : w->tmp[j++];
    memcpy(w->act, w->tmp, k * sizeof *w->act);
    w->nact = k;
}

amp_status amp_slice_mesh(const amp_mesh *m, const amp_slice_opts *o, amp_slices *out, amp_error *err)
{
    amp_box3 b;
    double h, h0, top;
    size_t n, i;
    amp_status st;
    tsweep w;
    amp_slices_free(out);
    memset(&w, 0, sizeof w);
    if (!o || !(o->layer > 0) || !isfinite(o->layer))
        return amp_fail(err, AMP_ERR_ARG, 0, "layer height must be positive");
    if (!isfinite(o->first_layer))
        return amp_fail(err, AMP_ERR_ARG, 0, "first layer height is not finite");
    if (m->ntris == 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "mesh has no triangles");
    h = o->layer;
    h0 = o->first_layer > 0 ? o->first_layer : h;
    b = amp_mesh_bbox(m);
    top = b.max.z - b.min.z;
    out->z0 = b.min.z;
    /* number of layers whose cutting height lies below the top */
    for (n = 0; (n == 0 ? 0.5 * h0 : h0 + (n - 0.5) * h) < top; n++)
        if (n >= 1000000)
            return amp_fail(err, AMP_ERR_LIMIT, 0, "more than 1000000 layers (height %g, layer %g)", top, h);
    out->layers = amp_calloc(out->alloc, n ? n : 1, sizeof *out->layers);
    if (!out->layers || sweep_init(&w, m, out->alloc) != AMP_OK) {
        sweep_free(&w, out->alloc);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for %lu layers", (unsigned long)n);
    }
    for (i = 0, st = AMP_OK; i < n && st == AMP_OK; i++) {
        amp_layer *L = &out->layers[i];
        amp_section_stats ss;
        L->z_cut = i == 0 ? 0.5 * h0 : h0 + (i - 0.5) * h;
        L->z_print = i == 0 ? h0 : h0 + i * h;
        amp_polyset_init(&L->polys, out->alloc);
        out->nlayers = i + 1;
        sweep_to(&w, m, b.min.z + L->z_cut);
        st = slice_plane(m, w.act, w.nact, b.min.z + L->z_cut, &L->polys, &ss, err);
        if (st != AMP_OK)
            break;
        out->open_chains += ss.open_chains;
        out->gaps_closed += ss.gaps_closed;
        out->overlaps += (size_t)ss.overlaps;
        L->open_chains = ss.open_chains;
        out->nonmanifold += ss.nonmanifold;
    }
    sweep_free(&w, out->alloc);
    return st;
}

/* Distance from q to the section P (0 inside), through its row index when
 * there is one. */
static double dist_to_section(const amp_polyset *P, const amp_polyindex *ix, amp_vec2 q)
{
    if (ix)
        return amp_polyindex_contains(ix, q) != 0 ? 0.0 : amp_polyindex_dist(ix, q);
    if (amp_polyset_contains(P, q, 0.0) != 0)
        return 0.0;
    return amp_polyset_boundary_dist(P, q);
}

double amp_slices_overhang(const amp_slices *sl, size_t i, double step)
{
    const amp_polyset *lo, *up;
    amp_polyindex ilo, iup;
    double worst = 0, x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, x, y;
    size_t k;
    int have_lo, have_up;
    if (i + 1 >= sl->nlayers)
        return 0;
    lo = &sl->layers[i].polys;
    up = &sl->layers[i + 1].polys;
    if (up->npts == 0)
        return 0;
    if (lo->npts == 0)
        return HUGE_VAL;
    if (!(step > 0))
        step = 1.0;
    /* row indexes: a sample costs one row, not every edge (linear cost,
     * on large sections); without memory for them the plain scans give the same */
    have_lo = amp_polyindex_build(&ilo, lo, NULL) == AMP_OK;
    have_up = amp_polyindex_build(&iup, up, NULL) == AMP_OK;
    /* the upper rings' vertices (about 512 of them at most): the overhang
     * of a slanted wall */
    for (k = 0; k < up->npts; k++) {
        if (k % (up->npts / 512 + 1) == 0)
            worst = fmax(worst, dist_to_section(lo, have_lo ? &ilo : NULL, up->pts[k]));
        x0 = fmin(x0, up->pts[k].x);
        y0 = fmin(y0, up->pts[k].y);
        x1 = fmax(x1, up->pts[k].x);
        y1 = fmax(y1, up->pts[k].y);
    }
    /* inside: a bridge over a hole of the layer below (at most about
     * 24 x 24 points) */
    step = fmax(step, fmax(x1 - x0, y1 - y0) / 24);
    for (y = y0 + 0.5 * step; y < y1; y += step)
        for (x = x0 + 0.5 * step; x < x1; x += step)
            if ((have_up ? amp_polyindex_contains(&iup, amp_v2(x, y)) : amp_polyset_contains(up, amp_v2(x, y), 0.0)) ==
                1)
                worst = fmax(worst, dist_to_section(lo, have_lo ? &ilo : NULL, amp_v2(x, y)));
    if (have_lo)
        amp_polyindex_free(&ilo);
    if (have_up)
        amp_polyindex_free(&iup);
    return worst;
}
