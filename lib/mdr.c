/* Material deposition radius (paper §5.2, Def. 5.4): simultaneous growth of fragment tubes. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "ampath/mdr.h"
#include "ampath/order.h"

void amp_mdr_opts_default(amp_mdr_opts *o, double nominal)
{
    o->nominal = nominal;
    o->r_min = 0.5 * nominal;
    o->r_max = 1.5 * nominal;
    o->fragment = nominal;
    o->progress = NULL;
    o->progress_user = NULL;
}

/* Squared distance between segments [p1,q1] and [p2,q2] (closest points of two segments, clamped). */
static double seg_seg_dist2(amp_vec3 p1, amp_vec3 q1, amp_vec3 p2, amp_vec3 q2)
{
    amp_vec3 d1 = amp_v3_sub(q1, p1), d2 = amp_v3_sub(q2, p2), r = amp_v3_sub(p1, p2);
    double a = amp_v3_dot(d1, d1), e = amp_v3_dot(d2, d2), f = amp_v3_dot(d2, r), s, t;
    if (a <= 1e-300 && e <= 1e-300)
        return amp_v3_len2(r);
    if (a <= 1e-300) {
        s = 0.0;
        t = f / e;
        t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    } else {
        double c = amp_v3_dot(d1, r);
        if (e <= 1e-300) {
            t = 0.0;
            s = -c / a;
            s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
        } else {
            double b = amp_v3_dot(d1, d2), den = a * e - b * b;
            s = den > 1e-300 ? (b * f - c * e) / den : 0.0;
            s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = -c / a;
                s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
            } else if (t > 1.0) {
                t = 1.0;
                s = (b - c) / a;
                s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
            }
        }
    }
    return amp_v3_dist2(amp_v3_madd(p1, d1, s), amp_v3_madd(p2, d2, t));
}

static double frag_dist(const amp_fragments *fs, size_t a, size_t b)
{
    const amp_fragment *fa = &fs->frag[a], *fb = &fs->frag[b];
    double best = HUGE_VAL;
    size_t i, j;
    for (i = 0; i + 1 < amp_fragment_npoints(fa); i++)
        for (j = 0; j + 1 < amp_fragment_npoints(fb); j++) {
            double d = seg_seg_dist2(amp_fragment_point(fs, fa, i), amp_fragment_point(fs, fa, i + 1),
                                     amp_fragment_point(fs, fb, j), amp_fragment_point(fs, fb, j + 1));
            best = d < best ? d : best;
        }
    return sqrt(best);
}

static double frag_length(const amp_fragments *fs, size_t f)
{
    double len = 0.0;
    size_t k;
    for (k = 0; k + 1 < amp_fragment_npoints(&fs->frag[f]); k++)
        len += amp_v3_dist(amp_fragment_point(fs, &fs->frag[f], k), amp_fragment_point(fs, &fs->frag[f], k + 1));
    return len;
}

/* A uniform grid of points (fragment centres or segment ids) in counting-sort layout. */
typedef struct ugrid {
    amp_box3 box;
    double cell;
    size_t nx, ny, nz;
    size_t *start; /* nx*ny*nz + 1 */
    uint32_t *item;
} ugrid;

static size_t cell_of(const ugrid *g, amp_vec3 p, size_t *ix, size_t *iy, size_t *iz)
{
    double fx = floor((p.x - g->box.min.x) / g->cell), fy = floor((p.y - g->box.min.y) / g->cell),
           fz = floor((p.z - g->box.min.z) / g->cell);
    *ix = fx < 0 ? 0 : (fx >= (double)g->nx ? g->nx - 1 : (size_t)fx);
    *iy = fy < 0 ? 0 : (fy >= (double)g->ny ? g->ny - 1 : (size_t)fy);
    *iz = fz < 0 ? 0 : (fz >= (double)g->nz ? g->nz - 1 : (size_t)fz);
    return (*iz * g->ny + *iy) * g->nx + *ix;
}

static amp_status ugrid_build(ugrid *g, const amp_allocator *a, const amp_vec3 *pts, size_t n, double cell,
                              amp_error *err)
{
    size_t i, ncell, ix, iy, iz;
    memset(g, 0, sizeof *g);
    g->box = amp_box3_empty();
    for (i = 0; i < n; i++)
        g->box = amp_box3_add(g->box, pts[i]);
    if (n == 0)
        g->box.min = g->box.max = amp_v3(0, 0, 0);
    for (;;) {
        amp_vec3 sz = amp_box3_size(g->box);
        g->cell = cell;
        g->nx = (size_t)(sz.x / cell) + 1;
        g->ny = (size_t)(sz.y / cell) + 1;
        g->nz = (size_t)(sz.z / cell) + 1;
        if ((double)g->nx * (double)g->ny * (double)g->nz <= 4.0 * (double)n + 64.0)
            break;
        cell *= 1.5; /* keep the grid linear in the input: coarser cells, more candidates each */
    }
    ncell = g->nx * g->ny * g->nz;
    g->start = amp_calloc(a, ncell + 1, sizeof *g->start);
    g->item = amp_calloc(a, n ? n : 1, sizeof *g->item);
    if (!g->start || !g->item)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for a grid of %lu cells", (unsigned long)ncell);
    for (i = 0; i < n; i++)
        g->start[cell_of(g, pts[i], &ix, &iy, &iz) + 1]++;
    for (i = 0; i < ncell; i++)
        g->start[i + 1] += g->start[i];
    {
        size_t *fill = amp_calloc(a, ncell + 1, sizeof *fill);
        if (!fill)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for a grid");
        memcpy(fill, g->start, (ncell + 1) * sizeof *fill);
        for (i = 0; i < n; i++)
            g->item[fill[cell_of(g, pts[i], &ix, &iy, &iz)]++] = (uint32_t)i;
        amp_free(a, fill);
    }
    return AMP_OK;
}

static void ugrid_free(ugrid *g, const amp_allocator *a)
{
    amp_free(a, g->start);
    amp_free(a, g->item);
}

typedef struct nb {
    uint32_t other;
    double d;
} nb;

typedef struct hent {
    double key;
    uint32_t f;
} hent;

static amp_status hpush(const amp_allocator *a, hent **h, size_t *n, size_t *cap, double key, uint32_t f)
{
    void *p = *h;
    size_t i;
    if (amp_grow(a, &p, cap, *n + 1, sizeof **h) != AMP_OK)
        return AMP_ERR_NOMEM;
    *h = p;
    i = (*n)++;
    while (i > 0 && (*h)[(i - 1) / 2].key > key) {
        (*h)[i] = (*h)[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    (*h)[i].key = key;
    (*h)[i].f = f;
    return AMP_OK;
}

static hent hpop(hent *h, size_t *n)
{
    hent top = h[0], last = h[--*n];
    size_t i = 0;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= *n)
            break;
        if (c + 1 < *n && h[c + 1].key < h[c].key)
            c++;
        if (h[c].key >= last.key)
            break;
        h[i] = h[c];
        i = c;
    }
    if (*n)
        h[i] = last;
    return top;
}

amp_status amp_mdr(const amp_pathset *in, const amp_mdr_opts *o, amp_pathset *out, amp_mdr_stats *st,
                   amp_error *err)
{
    const amp_allocator *a = out->alloc;
    amp_fragments fs;
    amp_mdr_stats s;
    ugrid g;
    amp_vec3 *ctr = NULL;
    size_t *row = NULL, npairs = 0, cap_pairs = 0, i, nh = 0, caph = 0, nfrozen = 0;
    nb *adj = NULL;
    uint32_t(*pairs)[2] = NULL;
    double *pd = NULL, *r = NULL, reach;
    unsigned char *frozen = NULL;
    hent *heap = NULL;
    amp_status stt;
    memset(&s, 0, sizeof s);
    memset(&g, 0, sizeof g);
    if (!in || !o || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mdr: NULL argument");
    if (!(o->nominal > 0.0) || !isfinite(o->nominal) || !(o->fragment > 0.0) || !isfinite(o->fragment))
        return amp_fail(err, AMP_ERR_RANGE, 0, "nominal radius and fragment length must be positive (got %g, %g)",
                        o->nominal, o->fragment);
    if (!(o->r_min >= 0.0) || !(o->r_max >= o->r_min) || !isfinite(o->r_max))
        return amp_fail(err, AMP_ERR_RANGE, 0, "need 0 <= r_min <= r_max (got %g, %g)", o->r_min, o->r_max);
    if ((stt = amp_fragments_build(&fs, in, o->fragment, a, err)) != AMP_OK)
        return stt;
    s.fragments = fs.n;
    reach = 2.0 * o->r_max;
    ctr = amp_calloc(a, fs.n ? fs.n : 1, sizeof *ctr);
    r = amp_calloc(a, fs.n ? fs.n : 1, sizeof *r);
    frozen = amp_calloc(a, fs.n ? fs.n : 1, 1);
    row = amp_calloc(a, fs.n + 1, sizeof *row);
    if (!ctr || !r || !frozen || !row) {
        stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for %lu tubes", (unsigned long)fs.n);
        goto done;
    }
    for (i = 0; i < fs.n; i++) {
        ctr[i] = amp_box3_center(fs.frag[i].box);
        /* r[] holds the arc length at each fragment's end until the growth starts */
        r[i] = (i > 0 && fs.frag[i - 1].path == fs.frag[i].path ? r[i - 1] : 0.0) + frag_length(&fs, i);
    }
    /* neighbour pairs: fragment centres within reach + one fragment length (each reaches half of it) */
    if ((stt = ugrid_build(&g, a, ctr, fs.n, reach + o->fragment, err)) != AMP_OK)
        goto done;
    for (i = 0; i < fs.n; i++) {
        size_t ix, iy, iz, x, y, z;
        if (o->progress && (i & 4095) == 0) /* finding neighbours: the first half of the work */
            o->progress(o->progress_user, 0.5 * (double)i / (double)fs.n);
        cell_of(&g, ctr[i], &ix, &iy, &iz);
        for (z = iz ? iz - 1 : 0; z <= iz + 1 && z < g.nz; z++)
            for (y = iy ? iy - 1 : 0; y <= iy + 1 && y < g.ny; y++)
                for (x = ix ? ix - 1 : 0; x <= ix + 1 && x < g.nx; x++) {
                    size_t c = (z * g.ny + y) * g.nx + x, q;
                    for (q = g.start[c]; q < g.start[c + 1]; q++) {
                        uint32_t j = g.item[q];
                        double d;
                        if (j <= i)
                            continue;
                        /* along one path the tube is continuous: only parts further apart than 2 r_max count */
                        if (fs.frag[i].path == fs.frag[j].path && r[j - 1] - r[i] < reach)
                            continue;
                        if (amp_v3_dist(ctr[i], ctr[j]) > reach + o->fragment)
                            continue;
                        d = frag_dist(&fs, i, j);
                        if (d >= reach)
                            continue;
                        {
                            void *pp = pairs, *dd = pd;
                            size_t c2 = cap_pairs;
                            if (amp_grow(a, &pp, &c2, npairs + 1, sizeof *pairs) != AMP_OK) {
                                stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for tube neighbours");
                                goto done;
                            }
                            pairs = pp;
                            c2 = cap_pairs;
                            if (amp_grow(a, &dd, &c2, npairs + 1, sizeof *pd) != AMP_OK) {
                                stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for tube neighbours");
                                goto done;
                            }
                            pd = dd;
                            cap_pairs = c2;
                        }
                        pairs[npairs][0] = (uint32_t)i;
                        pairs[npairs][1] = j;
                        pd[npairs++] = d;
                        row[i + 1]++;
                        row[j + 1]++;
                    }
                }
    }
    s.pairs = npairs;
    for (i = 0; i < fs.n; i++)
        row[i + 1] += row[i];
    adj = amp_calloc(a, 2 * npairs + 1, sizeof *adj);
    if (!adj) {
        stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for tube neighbours");
        goto done;
    }
    {
        size_t *fill = amp_calloc(a, fs.n + 1, sizeof *fill);
        if (!fill) {
            stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for tube neighbours");
            goto done;
        }
        memcpy(fill, row, (fs.n + 1) * sizeof *fill);
        for (i = 0; i < npairs; i++) {
            adj[fill[pairs[i][0]]].other = pairs[i][1];
            adj[fill[pairs[i][0]]++].d = pd[i];
            adj[fill[pairs[i][1]]].other = pairs[i][0];
            adj[fill[pairs[i][1]]++].d = pd[i];
        }
        amp_free(a, fill);
    }
    memset(r, 0, fs.n * sizeof *r);
    /* §5.2: all tubes grow together; an event is a tube touching another (d/2 if both grow, d - r if one stopped) */
    for (i = 0; i < fs.n; i++) {
        size_t q;
        double key = o->r_max;
        if (row[i] == row[i + 1]) {
            frozen[i] = 1;
            r[i] = fmin(fmax(o->nominal, o->r_min), o->r_max);
            s.isolated++;
            continue;
        }
        for (q = row[i]; q < row[i + 1]; q++)
            key = fmin(key, 0.5 * adj[q].d);
        if (hpush(a, &heap, &nh, &caph, key, (uint32_t)i) != AMP_OK) {
            stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the growth queue");
            goto done;
        }
    }
    while (nh) {
        hent e = hpop(heap, &nh);
        size_t q;
        double key = o->r_max;
        if (frozen[e.f])
            continue;
        for (q = row[e.f]; q < row[e.f + 1]; q++)
            key = fmin(key, frozen[adj[q].other] ? adj[q].d - r[adj[q].other] : 0.5 * adj[q].d);
        if (key > e.key * (1 + 1e-12) + 1e-15) {
            /* a neighbour stopped earlier, so this tube touches it later than the pair's midpoint */
            if (hpush(a, &heap, &nh, &caph, key, e.f) != AMP_OK) {
                stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the growth queue");
                goto done;
            }
            continue;
        }
        frozen[e.f] = 1;
        if (o->progress && (++nfrozen & 4095) == 0)
            o->progress(o->progress_user, 0.5 + 0.5 * (double)nfrozen / (double)fs.n);
        if (key >= o->r_max)
            s.at_max++;
        if (key < o->r_min * (1 - 1e-9))
            s.at_min++;
        r[e.f] = fmin(fmax(key, o->r_min), o->r_max);
        for (q = row[e.f]; q < row[e.f + 1]; q++) {
            uint32_t nbo = adj[q].other;
            if (!frozen[nbo] && hpush(a, &heap, &nh, &caph, fmax(0.0, adj[q].d - r[e.f]), nbo) != AMP_OK) {
                stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the growth queue");
                goto done;
            }
        }
    }
    /* output: cut points become vertices; a cut point takes the smaller radius of its two fragments */
    s.r_lo = HUGE_VAL;
    s.r_hi = 0.0;
    for (i = 0; i < in->npaths && stt == AMP_OK; i++) {
        size_t f;
        if (in->paths[i].n == 0)
            continue;
        stt = amp_pathset_begin(out, in->paths[i].role, err);
        for (f = fs.first[i]; stt == AMP_OK && f < fs.first[i + 1]; f++) {
            const amp_fragment *fr = &fs.frag[f];
            size_t q;
            s.r_lo = fmin(s.r_lo, r[f]);
            s.r_hi = fmax(s.r_hi, r[f]);
            if (f == fs.first[i])
                stt = amp_pathset_push(out, fr->p0, r[f], err);
            for (q = 0; stt == AMP_OK && q < fr->nin; q++)
                stt = amp_pathset_push(out, in->verts[fr->vfirst + q].p, r[f], err);
            if (stt == AMP_OK && in->paths[i].n > 1)
                stt = amp_pathset_push(out, fr->p1, f + 1 < fs.first[i + 1] ? fmin(r[f], r[f + 1]) : r[f], err);
        }
    }
    if (stt == AMP_OK)
        s.deposited = amp_pathset_volume(out, -1);
    if (fs.n == 0)
        s.r_lo = 0.0;
    if (st)
        *st = s;
done:
    ugrid_free(&g, a);
    amp_free(a, ctr);
    amp_free(a, r);
    amp_free(a, frozen);
    amp_free(a, row);
    amp_free(a, adj);
    amp_free(a, pairs);
    amp_free(a, pd);
    amp_free(a, heap);
    amp_fragments_free(&fs);
    return stt;
}

amp_status amp_tubes_union_volume(const amp_pathset *ps, size_t samples, double *volume, amp_error *err)
{
    const amp_allocator *a = ps->alloc;
    size_t i, k, nseg = 0, hits = 0, s;
    double rmax = 0.0, maxlen = 0.0;
    amp_vec3 *mid = NULL;
    size_t *segv = NULL;
    ugrid g;
    amp_box3 box;
    uint64_t x = 0x9e3779b97f4a7c15ULL;
    amp_status st;
    memset(&g, 0, sizeof g);
    *volume = 0.0;
    for (i = 0; i < ps->npaths; i++)
        nseg += ps->paths[i].n > 1 ? ps->paths[i].n - 1 : 0;
    if (nseg == 0 || samples == 0)
        return AMP_OK;
    mid = amp_calloc(a, nseg, sizeof *mid);
    segv = amp_calloc(a, nseg, sizeof *segv);
    if (!mid || !segv) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the volume estimate");
        goto done;
    }
    for (i = 0, s = 0; i < ps->npaths; i++)
        for (k = 0; k + 1 < ps->paths[i].n; k++, s++) {
            const amp_pvert *v = amp_pathset_path_verts(ps, i) + k;
            segv[s] = ps->paths[i].first + k;
            mid[s] = amp_v3_lerp(v[0].p, v[1].p, 0.5);
            rmax = fmax(rmax, fmax(v[0].r, v[1].r));
            maxlen = fmax(maxlen, amp_v3_dist(v[0].p, v[1].p));
        }
    if (rmax <= 0.0) {
        st = AMP_OK;
        goto done;
    }
    if ((st = ugrid_build(&g, a, mid, nseg, 2 * rmax + maxlen, err)) != AMP_OK)
        goto done;
    box = amp_box3_inflate(amp_pathset_bbox(ps), rmax);
    for (k = 0; k < samples; k++) {
        amp_vec3 p, sz = amp_box3_size(box);
        size_t ix, iy, iz, cx, cy, cz, found = 0;
        double u[3];
        int d;
        for (d = 0; d < 3; d++) {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            u[d] = (double)(x >> 11) / 9007199254740992.0;
        }
        p = amp_v3(box.min.x + u[0] * sz.x, box.min.y + u[1] * sz.y, box.min.z + u[2] * sz.z);
        cell_of(&g, p, &ix, &iy, &iz);
        for (cz = iz ? iz - 1 : 0; !found && cz <= iz + 1 && cz < g.nz; cz++)
            for (cy = iy ? iy - 1 : 0; !found && cy <= iy + 1 && cy < g.ny; cy++)
                for (cx = ix ? ix - 1 : 0; !found && cx <= ix + 1 && cx < g.nx; cx++) {
                    size_t c = (cz * g.ny + cy) * g.nx + cx, q;
                    for (q = g.start[c]; !found && q < g.start[c + 1]; q++) {
                        const amp_pvert *v = &ps->verts[segv[g.item[q]]];
                        double rr = fmax(v[0].r, v[1].r);
                        found = amp_v3_seg_dist2(p, v[0].p, v[1].p, NULL) <= rr * rr;
                    }
                }
        hits += found;
    }
    {
        amp_vec3 sz = amp_box3_size(box);
        *volume = sz.x * sz.y * sz.z * (double)hits / (double)samples;
    }
    st = AMP_OK;
done:
    ugrid_free(&g, a);
    amp_free(a, mid);
    amp_free(a, segv);
    return st;
}
