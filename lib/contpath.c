/* Continuous tool paths (continuous-toolpath-euler.txt §2.2 steps 2-6, §4):
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

void amp_cp_graph_free(amp_cp_graph *g)
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

/* Length of a closed ring. */
static double ring_perimeter(const amp_vec2 *p, size_t n)
{
    size_t i;
    double l = 0;
    for (i = 0; i < n; i++)
        l += hypot(p[(i + 1) % n].x - p[i].x, p[(i + 1) % n].y - p[i].y);
    return l;
}

/* Region processing with a prepared K̂ edge list. */
amp_status amp_cp_region_run(const amp_cx2 *khat, const uint64_t *ke, size_t nke, const amp_polyset *R, double z,
                             const amp_contpath_opts *o, int hub, amp_pathset *out, amp_pathset *bare,
                             amp_contpath_stats *st, amp_error *err)
{
    amp_cp_graph g;
    size_t *uf = NULL, *grs = NULL, *grm = NULL, *tmp = NULL, i, j, k, ngr, ntours = 0, nodd = 0, first_path, ngap = 0;
    unsigned char *choice = NULL;
    gap *gp = NULL;
    amp_cp_patchset P;
    amp_cp_tour_info ti;
    int fig6;
    double D = o->pseudo_edges ? 2 * o->radius * (1 - 1e-9) : 0.0, pseudo = 0;
    amp_status rc;
    memset(&g, 0, sizeof g);
    memset(&P, 0, sizeof P);
    g.al = out->alloc;
    rc = amp_cp_clip(khat, ke, nke, R, &g, err);
    if (rc != AMP_OK)
        goto done;
    g.nlat = g.ne;
    g.nlatv = g.nv;
    if (!(g.mate = amp_alloc(g.al, (g.nv + 1) * sizeof *g.mate))) {
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
        goto done;
    }
    for (i = 0; i < g.nv; i++)
        g.mate[i] = NONE;
    for (i = 0; i < g.ne; i++) {
        g.mate[g.eu[i]] = g.ev[i];
        g.mate[g.ev[i]] = g.eu[i];
    }
    if (g.nfe > 1)
        qsort(g.fe, g.nfe, sizeof *g.fe, amp_cp_cmp_fend);
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
        amp_uf_union(uf, g.eu[i], g.ev[i]);
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
                        const amp_cp_fend *fa = &g.fe[grs[gk] + q % m], *fb = &g.fe[grs[gk] + (q + 1) % m];
                        len += amp_cp_ring_len(R, fa->ring, fa->pos, fb->pos);
                        merges += (size_t)amp_uf_union(tmp, fa->node, fb->node);
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
    if (amp_cp_patchset_alloc(g.al, &P, g.nfe) != AMP_OK) {
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
        goto done;
    }
    for (k = 0; k < ngr; k++) {
        size_t m = grm[k], q;
        for (q = 0; q < m; q++) {
            const amp_cp_fend *fa = &g.fe[grs[k] + q], *fb = &g.fe[grs[k] + (q + 1) % m];
            if (q % 2 == choice[k] && q + 1 < m + choice[k]) {
                if ((rc = amp_cp_patch_add(&g, &P, R, fa, fb, 0, err)) != AMP_OK)
                    goto done;
                amp_uf_union(uf, fa->node, fb->node);
            } else {
                gp[ngap].k = k;
                gp[ngap].q = q;
                gp[ngap++].len = amp_cp_ring_len(R, fa->ring, fa->pos, fb->pos);
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
    /* With perimeters spliced into the island's stroke (o->join), the
     * perimeter loop runs beside every component: they are spliced to it
     * there (contpath_join.c) instead, which needs no travel inside the
     * stroke. Fig. 6 stays for strokes without perimeters or joining. */
    fig6 = !hub;
    for (i = 0; i < ngap; i++) {
        size_t m = grm[gp[i].k];
        const amp_cp_fend *fa = &g.fe[grs[gp[i].k] + gp[i].q], *fb = &g.fe[grs[gp[i].k] + (gp[i].q + 1) % m];
        if (fig6 && amp_uf_find(uf, fa->node) != amp_uf_find(uf, fb->node)) {
            if ((rc = amp_cp_patch_add(&g, &P, R, fa, fb, 1, err)) != AMP_OK)
                goto done;
            amp_uf_union(uf, fa->node, fb->node);
            st->joins++;
        } else if (o->support_stretches) {
            /* Remark 2.1: print the unprinted stretch on its own */
            if ((rc = amp_cp_ring_support(&g, R, fa, fb, out, z, o->radius, err)) != AMP_OK)
                goto done;
            st->support_paths++;
            st->support_length += gp[i].len;
        } else {
            st->unprinted_length += gp[i].len;
            /* step 6: the bare stretch, for the support corners */
            if (bare && (rc = amp_cp_ring_support(&g, R, fa, fb, bare, z, 0.0, err)) != AMP_OK)
                goto done;
        }
    }
    /* a ring no lattice edge reaches (a hole in the middle of a cell) is
     * bare as a whole when the region has lattice strokes elsewhere */
    for (k = 0; k < R->nrings && g.ne > 0; k++) {
        size_t q, nf = 0;
        const amp_vec2 *p = amp_polyset_ring(R, k);
        for (q = 0; q < g.nfe; q++)
            nf += g.fe[q].ring == k;
        if (nf)
            continue;
        st->unprinted_length += ring_perimeter(p, R->rings[k].n);
        if (bare) {
            if ((rc = amp_pathset_begin(bare, AMP_ROLE_SUPPORT, err)) != AMP_OK)
                goto done;
            for (q = 0; q <= R->rings[k].n && rc == AMP_OK; q++)
                rc = amp_pathset_push(bare, amp_v3(p[q % R->rings[k].n].x, p[q % R->rings[k].n].y, z), 0.0, err);
            if (rc != AMP_OK)
                goto done;
        }
    }
    /* Figs. 7, 8: every patch against the printed edges near it, then into
     * the graph (a join twice: printed, and back as a pseudo edge) */
    for (k = 0; k < P.n; k++) {
        if ((rc = amp_cp_patch_points(&g, &P, k, D, err)) != AMP_OK)
            goto done;
        if (amp_cp_add_chain(&g, P.a[k], P.b[k], 0, &pseudo) != AMP_OK ||
            (P.join[k] && amp_cp_add_chain(&g, P.a[k], P.b[k], 1, &pseudo) != AMP_OK)) {
            rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
            goto done;
        }
    }
    first_path = out->npaths;
    rc = amp_cp_tour(&g, z, o->radius, (int)o->tour, out, &ti, err);
    if (rc != AMP_OK)
        goto done;
    ntours = ti.ntours;
    nodd = ti.nodd;
    st->cycles += ti.cycles;
    st->tour_fallbacks += (size_t)ti.fallback;
    if (ti.levels > st->tree_levels)
        st->tree_levels = ti.levels;
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
            st->infill_length += amp_cp_printed_len(out, i);
    st->pseudo_length += pseudo;
    st->regions++;
    st->strokes += ntours;
    st->multi_stroke += ntours > 1;
    st->odd_vertices += nodd;
done:
    amp_cp_graph_free(&g);
    amp_free(g.al, uf);
    amp_free(g.al, grs);
    amp_free(g.al, grm);
    amp_free(g.al, tmp);
    amp_free(g.al, choice);
    amp_free(g.al, gp);
    amp_cp_patchset_free(g.al, &P);
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
