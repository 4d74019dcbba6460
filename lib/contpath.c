/* Continuous tool paths ([P2 §2.2] steps 2-6, [P2 §4]):
 * options, steps 2-4 (K and K̂), the region graph and one region's run.
 * Clipping, patching, the tour and the layers live in contpath_*.c. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

#include "ampath/euler.h"

void amp_contpath_opts_default(amp_contpath_opts *o, double r)
{
    memset(o, 0, sizeof *o);
    o->radius = r;
    o->cell = 10 * r;
    o->grid = AMP_GRID_SQUARE;
    o->offset = r;
    o->perimeters = 1;
    o->support_stretches = 0;
    o->pseudo_edges = 0;
    o->join = 1;
    o->support_corners = 1;
    o->skin_bottom = 0.8;
    o->skin_top = 0.8;
    o->skin_cell = 0;
    o->overlap_cap = 1;
}

/* Length of the printed segments of path i (a segment with radius 0 at both
 * ends is a pseudo edge: travel inside the stroke). */
double amp_cp_printed_len(const amp_pathset *ps, size_t i)
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
    amp_euler_stats es;
    amp_status st;
    double cell;
    if (!o || !(o->radius > 0) || !isfinite(o->radius))
        return amp_fail(err, AMP_ERR_ARG, 0, "extruder radius must be positive");
    cell = o->cell > 0 ? o->cell : 10 * o->radius;
    for (i = 0; i < sl->nlayers; i++)
        n += sl->layers[i].polys.npts;
    if (n < 3)
        return amp_fail(err, AMP_ERR_GEOMETRY, 0, "no layer polygon to mesh");
    pts = amp_alloc(al, (n + 1) * sizeof *pts);
    hull = amp_alloc(al, (n + 1) * sizeof *hull);
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
    memset(&es, 0, sizeof es);
    /* step 2: hull of the union of all layers' projections; step 3: K */
    st = amp_convex_hull(pts, n, al, hull, &nh, err);
    /* the lattice starts at the hull's lowest corner: a corner moved out by
     * an odd fraction of a cell lays it off round coordinates, so that a CAD
     * part on a millimetre grid does not put its edges on lattice lines,
     * where the written coordinates (10 digits) could turn a touch into a
     * crossing; K still covers the hull (the hull of both) */
    if (st == AMP_OK) {
        amp_vec2 lo = hull[0];
        for (i = 1; i < nh; i++)
            lo = amp_v2(fmin(lo.x, hull[i].x), fmin(lo.y, hull[i].y));
        memcpy(pts, hull, nh * sizeof *pts);
        pts[nh] = amp_v2(lo.x - 0.2137 * cell, lo.y - 0.3719 * cell);
        st = amp_convex_hull(pts, nh + 1, al, hull, &nh, err);
    }
    if (st == AMP_OK)
        st = amp_cx2_grid(&k, hull, nh, cell, o->grid, err);
    /* step 4: K̂ with mitered offset δ = r, so that rim cells of K (outside
     * every R̃) hold all odd vertices and Class 2 strips are 2r wide */
    eo.offset = o->offset > 0 ? o->offset : o->radius;
    eo.combinatorial = 1;
    if (st == AMP_OK)
        st = amp_euler_transform(&k, &eo, khat, &es, err);
    /* Class 2 cells collapsed to free edges leave odd vertices (Lemma 3.1):
     * the Class 3 cells around them get their generalized transformation
     * (Lemma 3.3). Regular lattices never collapse a Class 2 cell without
     * losing the Class 1 cell too (an error: a topological change), so this
     * acts on lattices with short edges */
    if (st == AMP_OK && es.collapsed_class2 > 0) {
        amp_cx2 rep;
        amp_cx2_init(&rep, al);
        st = amp_euler_repair(khat, &rep, NULL, err);
        if (st == AMP_OK) {
            amp_cx2 t = *khat;
            *khat = rep;
            rep = t;
        }
        amp_cx2_free(&rep);
    }
    amp_cx2_free(&k);
    amp_free(al, pts);
    amp_free(al, hull);
    return st;
}

amp_status amp_cp_vert(amp_cp_graph *g, amp_vec2 p, size_t *id)
{
    void *q = g->v;
    if (amp_grow(g->al, &q, &g->cap_v, g->nv + 1, sizeof *g->v) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->v = q;
    g->v[g->nv] = p;
    *id = g->nv++;
    return AMP_OK;
}

amp_status amp_cp_edge(amp_cp_graph *g, size_t a, size_t b, int pseudo)
{
    void *q = g->edge_u, *r = g->edge_v, *t = g->edge_pseudo;
    if (a == b)
        return AMP_OK;
    if (amp_grow(g->al, &t, &g->cap_edge_pseudo, g->ne + 1, sizeof *g->edge_pseudo) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->edge_pseudo = t;
    g->edge_pseudo[g->ne] = (unsigned char)(pseudo != 0);
    if (amp_grow(g->al, &q, &g->cap_edge_u, g->ne + 1, sizeof *g->edge_u) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->edge_u = q;
    if (amp_grow(g->al, &r, &g->cap_edge_v, g->ne + 1, sizeof *g->edge_v) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->edge_v = r;
    g->edge_u[g->ne] = a;
    g->edge_v[g->ne] = b;
    g->ne++;
    return AMP_OK;
}

void amp_cp_graph_free(amp_cp_graph *g)
{
    amp_free(g->al, g->v);
    amp_free(g->al, g->edge_u);
    amp_free(g->al, g->edge_v);
    amp_free(g->al, g->edge_pseudo);
    amp_free(g->al, g->fends);
    amp_free(g->al, g->pp);
    amp_free(g->al, g->pf);
    amp_free(g->al, g->iv);
    amp_free(g->al, g->cand);
    amp_free(g->al, g->mate);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : (x > y ? 1 : 0);
}

/* Unique undirected 1-cells of K̂ as vertex pairs (lo << 32 | hi). */
amp_status amp_cp_khat_edges(const amp_cx2 *k, const amp_allocator *al, uint64_t **out, size_t *n)
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

/* One gap of a ring: the stretch from free end q to q + 1 (cyclic) of ring
 * group `group` (the free ends of one ring, in order along it). */
typedef struct gap {
    size_t group, end;
    double len;
} gap;

static int cmp_gap(const void *a, const void *b)
{
    const gap *x = a, *y = b;
    return x->len < y->len ? -1 : (x->len > y->len ? 1 : 0);
}

/* Length of a closed ring. */
static double ring_perimeter(const amp_vec2 *p, size_t n)
{
    size_t i;
    double l = 0;
    for (i = 0; i < n; i++)
        l += hypot(p[(i + 1) % n].x - p[i].x, p[(i + 1) % n].y - p[i].y);
    return l;
}

/* One region R̃ on its way through step 5, Figs. 6-8 and §4. */
typedef struct region_ctx {
    amp_cp_graph g;           /* K̂ clipped to R̃, then its patches */
    const amp_polyset *R;     /* the region R̃ */
    const amp_contpath_opts *o;
    double z;
    amp_pathset *out, *bare;  /* strokes; bare ring stretches for step 6 (may be NULL) */
    amp_contpath_stats *st;
    size_t *uf;               /* components of the graph (lib/uf.h) */
    size_t *trial;            /* scratch copy of uf while pairings are tried */
    size_t *group_first;      /* first free end (index into g.fends) of each ring group */
    size_t *group_ends;       /* free ends of each ring group (>= 2) */
    double *gap_len;          /* per free end (index into g.fends): the ring's length from it to the next of its
                               * group, found once (every pairing trial sums them; 4,096 trials at 12 rings) */
    size_t ngroups;
    unsigned char *pairing;   /* per ring group: gap q is patched when q % 2 == pairing */
    gap *gaps;                /* gaps left unpatched by the pairing */
    size_t ngaps;
    amp_cp_patchset P;        /* the patches (ring paths) chosen */
} region_ctx;

/* Step 5, clipping: K̂ clipped to R̃, each vertex's lattice mate, the free
 * ends in order along their rings, and the lattice's components. */
static amp_status region_clip(region_ctx *c, const amp_cx2 *khat, const uint64_t *ke, size_t nke, amp_error *err)
{
    amp_cp_graph *g = &c->g;
    size_t i;
    amp_status rc = amp_cp_clip(khat, ke, nke, c->R, g, err);
    if (rc != AMP_OK)
        return rc;
    g->nlat = g->ne;
    g->nlatv = g->nv;
    if (!(g->mate = amp_alloc(g->al, (g->nv + 1) * sizeof *g->mate)))
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
    for (i = 0; i < g->nv; i++)
        g->mate[i] = NONE;
    for (i = 0; i < g->ne; i++) {
        g->mate[g->edge_u[i]] = g->edge_v[i];
        g->mate[g->edge_v[i]] = g->edge_u[i];
    }
    if (g->nfends > 1)
        qsort(g->fends, g->nfends, sizeof *g->fends, amp_cp_cmp_fend);
    c->st->free_ends += g->nfends;
    c->uf = amp_alloc(g->al, (g->nv + 1) * sizeof *c->uf);
    c->trial = amp_alloc(g->al, (g->nv + 1) * sizeof *c->trial);
    c->group_first = amp_alloc(g->al, (g->nfends + 1) * sizeof *c->group_first);
    c->group_ends = amp_alloc(g->al, (g->nfends + 1) * sizeof *c->group_ends);
    c->pairing = amp_calloc(g->al, g->nfends + 1, 1);
    c->gaps = amp_alloc(g->al, (g->nfends + 1) * sizeof *c->gaps);
    c->gap_len = amp_alloc(g->al, (g->nfends + 1) * sizeof *c->gap_len);
    if (!c->uf || !c->trial || !c->group_first || !c->group_ends || !c->pairing || !c->gaps || !c->gap_len)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
    for (i = 0; i < g->nv; i++)
        c->uf[i] = i;
    for (i = 0; i < g->ne; i++)
        amp_uf_union(c->uf, g->edge_u[i], g->edge_v[i]);
    return AMP_OK;
}

/* Merges of pieces made by one trial of pairings, with the length patched
 * in *len. Exhaustive: bit gk of @p mask is ring group gk's pairing; greedy:
 * the pairings chosen for the groups before @p k, @p mask for group k, none
 * for those after. */
static size_t try_pairings(region_ctx *c, size_t k, unsigned long mask, int greedy, double *len)
{
    size_t merges = 0, gk;
    *len = 0;
    memcpy(c->trial, c->uf, c->g.nv * sizeof *c->trial);
    for (gk = 0; gk < c->ngroups; gk++) {
        int opt = greedy ? (gk < k ? c->pairing[gk] : (gk == k ? (int)mask : -1)) : (int)((mask >> gk) & 1u);
        size_t q, m = c->group_ends[gk];
        if (opt < 0)
            continue;
        for (q = (size_t)opt; q + 1 < m + (size_t)opt; q += 2) {
            const amp_cp_fend *fa = &c->g.fends[c->group_first[gk] + q % m];
            const amp_cp_fend *fb = &c->g.fends[c->group_first[gk] + (q + 1) % m];
            *len += c->gap_len[c->group_first[gk] + q % m];
            merges += (size_t)amp_uf_union(c->trial, fa->node, fb->node);
        }
    }
    return merges;
}

/* Step 5, pairing: on every ring, one of the two alternating pairings of its
 * free ends (gap q printed when q % 2 == pairing). The choice over all rings
 * of the region joins the most pieces (Fig. 6: pieces next to each other
 * along a ring are linked by the path between them), then prints the
 * longer length; exhaustive up to 12 rings, greedy ring by ring beyond. */
static void choose_pairings(region_ctx *c)
{
    size_t i, j, k;
    int greedy;
    unsigned long mask, nmask, bestmask = 0;
    for (i = 0, c->ngroups = 0; i < c->g.nfends; i = j) {
        for (j = i; j < c->g.nfends && c->g.fends[j].ring == c->g.fends[i].ring; j++)
            ;
        if (j - i >= 2) {
            c->group_first[c->ngroups] = i;
            c->group_ends[c->ngroups++] = j - i;
            for (k = i; k < j; k++) {
                const amp_cp_fend *fa = &c->g.fends[k], *fb = &c->g.fends[k + 1 < j ? k + 1 : i];
                c->gap_len[k] = amp_cp_ring_len(c->R, fa->ring, fa->pos, fb->pos);
            }
        }
    }
    greedy = c->ngroups > 12;
    nmask = greedy ? 2ul : 1ul << c->ngroups;
    for (k = 0; k < (greedy ? c->ngroups : 1); k++) {
        size_t bestmerge = 0;
        double bestlen = -1;
        for (mask = 0; mask < nmask; mask++) {
            double len;
            size_t merges = try_pairings(c, k, mask, greedy, &len);
            if (mask == 0 || merges > bestmerge || (merges == bestmerge && len > bestlen)) {
                bestmask = mask;
                bestmerge = merges;
                bestlen = len;
            }
        }
        if (greedy)
            c->pairing[k] = (unsigned char)bestmask;
    }
    if (!greedy)
        for (k = 0; k < c->ngroups; k++)
            c->pairing[k] = (unsigned char)((bestmask >> k) & 1u);
}

/* Step 5, patching: the chosen patches; the other gaps are candidates for
 * joining (Fig. 6), shortest first. */
static amp_status patch_rings(region_ctx *c, amp_error *err)
{
    size_t k, q;
    amp_status rc;
    if (amp_cp_patchset_alloc(c->g.al, &c->P, c->g.nfends) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
    for (k = 0; k < c->ngroups; k++) {
        size_t m = c->group_ends[k];
        for (q = 0; q < m; q++) {
            const amp_cp_fend *fa = &c->g.fends[c->group_first[k] + q];
            const amp_cp_fend *fb = &c->g.fends[c->group_first[k] + (q + 1) % m];
            if (q % 2 == c->pairing[k] && q + 1 < m + c->pairing[k]) {
                if ((rc = amp_cp_patch_add(&c->g, &c->P, c->R, fa, fb, 0, err)) != AMP_OK)
                    return rc;
                amp_uf_union(c->uf, fa->node, fb->node);
            } else {
                c->gaps[c->ngaps].group = k;
                c->gaps[c->ngaps].end = q;
                c->gaps[c->ngaps++].len = c->gap_len[c->group_first[k] + q];
            }
        }
    }
    if (c->ngaps > 1)
        qsort(c->gaps, c->ngaps, sizeof *c->gaps, cmp_gap);
    return AMP_OK;
}

/* Fig. 6, several components: when the pairings leave pieces apart (two
 * pieces that need opposite pairings on one ring, or pieces whose free ends
 * alternate on two rings), neighbouring components — whose free ends follow
 * each other along a ring with no other free end between — are joined by
 * the path p along R̃ between them. The patch is printed once and run back
 * as a pseudo edge over the fresh bead (a doubled edge keeps every vertex
 * even: only the two copies together leave the parity of step 5 intact).
 * Shortest gaps first, like Kruskal, until the region is one component.
 * With perimeters spliced into the island's stroke (@p hub), the perimeter
 * loop runs beside every component: they are spliced to it there
 * (contpath_join.c) instead, which needs no travel inside the stroke. The
 * gaps left are Remark 2.1's support paths or step 6's bare stretches. */
static amp_status join_components(region_ctx *c, int hub, amp_error *err)
{
    amp_contpath_stats *st = c->st;
    int fig6 = !hub;
    size_t i;
    amp_status rc;
    for (i = 0; i < c->ngaps; i++) {
        const gap *gi = &c->gaps[i];
        size_t m = c->group_ends[gi->group];
        const amp_cp_fend *fa = &c->g.fends[c->group_first[gi->group] + gi->end];
        const amp_cp_fend *fb = &c->g.fends[c->group_first[gi->group] + (gi->end + 1) % m];
        if (fig6 && amp_uf_find(c->uf, fa->node) != amp_uf_find(c->uf, fb->node)) {
            if ((rc = amp_cp_patch_add(&c->g, &c->P, c->R, fa, fb, 1, err)) != AMP_OK)
                return rc;
            amp_uf_union(c->uf, fa->node, fb->node);
            st->joins++;
        } else if (c->o->support_stretches) {
            /* Remark 2.1: print the unprinted stretch on its own */
            if ((rc = amp_cp_ring_support(&c->g, c->R, fa, fb, c->out, c->z, c->o->radius, err)) != AMP_OK)
                return rc;
            st->support_paths++;
            st->support_length += gi->len;
        } else {
            st->unprinted_length += gi->len;
            /* step 6: the bare stretch, for the support corners */
            if (c->bare && (rc = amp_cp_ring_support(&c->g, c->R, fa, fb, c->bare, c->z, 0.0, err)) != AMP_OK)
                return rc;
        }
    }
    return AMP_OK;
}

/* Step 6: a ring no lattice edge reaches (a hole in the middle of a cell) is
 * bare as a whole when the region has lattice strokes elsewhere. */
static amp_status bare_rings(region_ctx *c, amp_error *err)
{
    const amp_polyset *R = c->R;
    size_t k, q;
    amp_status rc = AMP_OK;
    for (k = 0; k < R->nrings && c->g.ne > 0; k++) {
        size_t nf = 0;
        const amp_vec2 *p = amp_polyset_ring(R, k);
        for (q = 0; q < c->g.nfends; q++)
            nf += c->g.fends[q].ring == k;
        if (nf)
            continue;
        c->st->unprinted_length += ring_perimeter(p, R->rings[k].n);
        if (c->bare) {
            if ((rc = amp_pathset_begin(c->bare, AMP_ROLE_SUPPORT, err)) != AMP_OK)
                return rc;
            for (q = 0; q <= R->rings[k].n && rc == AMP_OK; q++)
                rc = amp_pathset_push(c->bare, amp_v3(p[q % R->rings[k].n].x, p[q % R->rings[k].n].y, c->z), 0.0,
                                      err);
            if (rc != AMP_OK)
                return rc;
        }
    }
    return AMP_OK;
}

/* Figs. 7, 8: every patch against the printed edges near it (closer than
 * @p D: pseudo), then into the graph (a join twice: printed, and back as a
 * pseudo edge); the pseudo length is added to *pseudo. */
static amp_status patches_into_graph(region_ctx *c, double D, double *pseudo, amp_error *err)
{
    size_t k;
    amp_status rc;
    for (k = 0; k < c->P.n; k++) {
        if ((rc = amp_cp_patch_points(&c->g, &c->P, k, D, err)) != AMP_OK)
            return rc;
        if (amp_cp_add_chain(&c->g, c->P.a[k], c->P.b[k], 0, pseudo) != AMP_OK ||
            (c->P.join[k] && amp_cp_add_chain(&c->g, c->P.a[k], c->P.b[k], 1, pseudo) != AMP_OK))
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
    }
    return AMP_OK;
}

/* §4: the tours of the patched graph (no lattice edge in the region: its
 * outer ring is the stroke), and the region's figures. */
static amp_status region_tours(region_ctx *c, double pseudo, amp_error *err)
{
    amp_contpath_stats *st = c->st;
    amp_pathset *out = c->out;
    const amp_polyset *R = c->R;
    size_t i, ntours, first_path = out->npaths;
    amp_cp_tour_info ti;
    amp_status rc = amp_cp_tour(&c->g, c->z, c->o->radius, (int)c->o->tour, out, &ti, err);
    if (rc != AMP_OK)
        return rc;
    ntours = ti.ntours;
    st->cycles += ti.cycles;
    st->tour_fallbacks += (size_t)ti.fallback;
    if (ti.levels > st->tree_levels)
        st->tree_levels = ti.levels;
    if (ntours == 0 && R->nrings) {
        const amp_vec2 *p = amp_polyset_ring(R, 0);
        size_t n = R->rings[0].n;
        if ((rc = amp_pathset_begin(out, AMP_ROLE_OBJECT, err)) != AMP_OK)
            return rc;
        for (i = 0; i <= n && rc == AMP_OK; i++)
            rc = amp_pathset_push(out, amp_v3(p[i % n].x, p[i % n].y, c->z), c->o->radius, err);
        ntours = 1;
    }
    for (i = first_path; i < out->npaths; i++)
        if (out->paths[i].role == AMP_ROLE_OBJECT)
            st->infill_length += amp_cp_printed_len(out, i);
    st->pseudo_length += pseudo;
    st->regions++;
    st->strokes += ntours;
    st->multi_stroke += ntours > 1;
    st->odd_vertices += ti.nodd;
    return rc;
}

/* Region processing with a prepared K̂ edge list: step 5 (clip, pair,
 * patch), Fig. 6 joins, step 6's bare stretches, Figs. 7-8, §4 tours. */
amp_status amp_cp_region_run(const amp_cx2 *khat, const uint64_t *ke, size_t nke, const amp_polyset *R, double z,
                             const amp_contpath_opts *o, int hub, amp_pathset *out, amp_pathset *bare,
                             amp_contpath_stats *st, amp_error *err)
{
    region_ctx c;
    double D = o->pseudo_edges ? 2 * o->radius * (1 - 1e-9) : 0.0, pseudo = 0;
    amp_status rc;
    memset(&c, 0, sizeof c);
    c.g.al = out->alloc;
    c.R = R;
    c.o = o;
    c.z = z;
    c.out = out;
    c.bare = bare;
    c.st = st;
    if ((rc = region_clip(&c, khat, ke, nke, err)) == AMP_OK) {
        choose_pairings(&c);
        if ((rc = patch_rings(&c, err)) == AMP_OK && (rc = join_components(&c, hub, err)) == AMP_OK &&
            (rc = bare_rings(&c, err)) == AMP_OK && (rc = patches_into_graph(&c, D, &pseudo, err)) == AMP_OK)
            rc = region_tours(&c, pseudo, err);
    }
    amp_cp_graph_free(&c.g);
    amp_free(c.g.al, c.uf);
    amp_free(c.g.al, c.group_first);
    amp_free(c.g.al, c.group_ends);
    amp_free(c.g.al, c.gap_len);
    amp_free(c.g.al, c.trial);
    amp_free(c.g.al, c.pairing);
    amp_free(c.g.al, c.gaps);
    amp_cp_patchset_free(c.g.al, &c.P);
    return rc;
}

amp_status amp_contpath_region(const amp_cx2 *khat, const amp_polyset *region, double z,
                               const amp_contpath_opts *o, amp_pathset *out, amp_contpath_stats *st,
                               amp_error *err)
{
    uint64_t *ke = NULL;
    size_t nke = 0;
    amp_status rc;
    if (amp_cp_khat_edges(khat, out->alloc, &ke, &nke) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the lattice edges");
    rc = amp_cp_region_run(khat, ke, nke, region, z, o, 0, out, NULL, st, err);
    amp_free(out->alloc, ke);
    return rc;
}
