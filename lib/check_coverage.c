/*
 * Independent coverage measure ([P1 §4], check.h): sample the solid (a
 * trivariate's volume or a closed mesh's interior) and find, for each sample,
 * the exact distance to the nearest path segment through one uniform segment
 * grid searched in rings of cells. Shares nothing with the builders
 * (lib/cover.c, lib/field.c) except the spline evaluator and the mesh BVH.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/check.h"
#include "spline_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* Uniform grid of path segments (CSR lists per cell) for nearest-segment queries. */
typedef struct seg_grid {
    const amp_allocator *alloc;
    const amp_pathset *ps;
    amp_vec3 o;    /* corner of cell (0, 0, 0) */
    double h;      /* cell side, mm */
    int n[3];
    size_t *start; /* ncells + 1 */
    size_t *items; /* segment = index of its first vertex in ps->verts */
} seg_grid;

static int clampi(int x, int lo, int hi) { return x < lo ? lo : (x > hi ? hi : x); }

static void cell_of(const seg_grid *g, amp_vec3 p, int *c)
{
    c[0] = clampi((int)floor((p.x - g->o.x) / g->h), 0, g->n[0] - 1);
    c[1] = clampi((int)floor((p.y - g->o.y) / g->h), 0, g->n[1] - 1);
    c[2] = clampi((int)floor((p.z - g->o.z) / g->h), 0, g->n[2] - 1);
}

static size_t cell_id(const seg_grid *g, int x, int y, int z)
{
    return (size_t)x + (size_t)g->n[0] * ((size_t)y + (size_t)g->n[1] * (size_t)z);
}

/* Squared distance from p to the nearest segment listed in cell id (best2 if none is nearer). */
static double cell_nearest2(const seg_grid *g, size_t id, amp_vec3 p, double best2)
{
    size_t k;
    for (k = g->start[id]; k < g->start[id + 1]; k++) {
        size_t a = g->items[k];
        double d2 = amp_v3_seg_dist2(p, g->ps->verts[a].p, g->ps->verts[a + 1].p, NULL);
        best2 = d2 < best2 ? d2 : best2;
    }
    return best2;
}

/* Squared distance from p to the box of cell (x, y, z) along one axis: the gap beyond the cell's faces. */
static double axis_gap(double v, double lo, double h)
{
    double d = lo - v > v - (lo + h) ? lo - v : v - (lo + h);
    return d > 0.0 ? d * d : 0.0;
}

/* Exact distance from p to the nearest segment: rings of cells around p's cell until no closer cell can remain.
 * A cell whose box lies farther than the nearest segment so far is passed over: a segment is listed in every
 * cell its box meets, so its nearest point to p lies in a listed cell no farther than it (the minimum, and so the
 * distance, is the one of a scan of every cell; two thirds of the cells of the first rings are skipped on the
 * demo's covering). */
static double grid_nearest(const seg_grid *g, amp_vec3 p)
{
    int c[3], r, rmax = g->n[0] + g->n[1] + g->n[2];
    double best2 = HUGE_VAL;
    cell_of(g, p, c);
    for (r = 0; r <= rmax; r++) {
        int x, y, z;
        /* rings 0..r-1 are done; every cell of ring r or beyond is at least (r-1)*h away (p lies in its cell) */
        if (r > 0 && best2 < HUGE_VAL && sqrt(best2) <= (r - 1) * g->h)
            break;
        for (z = c[2] - r; z <= c[2] + r; z++)
            for (y = c[1] - r; y <= c[1] + r; y++) {
                /* a row inside the ring's faces meets the ring at its two ends only */
                int face = abs(z - c[2]) == r || abs(y - c[1]) == r, step = face || r == 0 ? 1 : 2 * r;
                double gyz;
                if (y < 0 || z < 0 || y >= g->n[1] || z >= g->n[2])
                    continue;
                gyz = axis_gap(p.y, g->o.y + y * g->h, g->h) + axis_gap(p.z, g->o.z + z * g->h, g->h);
                for (x = c[0] - r; x <= c[0] + r; x += step)
                    /* (the margin keeps a cell whose box distance rounding could push past an equal best) */
                    if (x >= 0 && x < g->n[0] &&
                        (gyz + axis_gap(p.x, g->o.x + x * g->h, g->h)) * (1.0 - 1e-9) <= best2)
                        best2 = cell_nearest2(g, cell_id(g, x, y, z), p, best2);
            }
    }
    return sqrt(best2);
}

/* pass 0 (fill NULL) counts, pass 1 fills: each segment goes into every cell its box touches. */
static void grid_insert(seg_grid *g, size_t *fill)
{
    const amp_pathset *ps = g->ps;
    size_t i, k;
    for (i = 0; i < ps->npaths; i++)
        for (k = 1; k < ps->paths[i].n; k++) {
            size_t a = ps->paths[i].first + k - 1;
            int c0[3], c1[3], x, y, z;
            cell_of(g, amp_v3_min(ps->verts[a].p, ps->verts[a + 1].p), c0);
            cell_of(g, amp_v3_max(ps->verts[a].p, ps->verts[a + 1].p), c1);
            for (z = c0[2]; z <= c1[2]; z++)
                for (y = c0[1]; y <= c1[1]; y++)
                    for (x = c0[0]; x <= c1[0]; x++) {
                        size_t id = cell_id(g, x, y, z);
                        if (fill)
                            g->items[fill[id]++] = a;
                        else
                            g->start[id + 1]++;
                    }
        }
}

/* The grid over @p box (which holds every sample) and the paths: about 0.4 segments per cell. */
static amp_status grid_build(seg_grid *g, const amp_pathset *ps, amp_box3 box, amp_error *err)
{
    size_t i, nseg = 0, ncell, *fill;
    amp_vec3 sz;
    double vol;
    for (i = 0; i < ps->npaths; i++)
        nseg += ps->paths[i].n > 1 ? ps->paths[i].n - 1 : 0;
    if (nseg == 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "no path segment to measure the coverage against");
    g->ps = ps;
    box = amp_box3_inflate(amp_box3_union(box, amp_pathset_bbox(ps)), 1e-6);
    sz = amp_box3_size(box);
    vol = fmax(sz.x, 1e-3) * fmax(sz.y, 1e-3) * fmax(sz.z, 1e-3);
    g->h = fmax(cbrt(vol / (double)nseg) * 0.75, fmax(fmax(sz.x, sz.y), sz.z) / 200);
    g->o = box.min;
    g->n[0] = (int)(sz.x / g->h) + 1;
    g->n[1] = (int)(sz.y / g->h) + 1;
    g->n[2] = (int)(sz.z / g->h) + 1;
    ncell = (size_t)g->n[0] * (size_t)g->n[1] * (size_t)g->n[2];
    g->start = amp_calloc(g->alloc, ncell + 1, sizeof *g->start);
    fill = amp_calloc(g->alloc, ncell, sizeof *fill);
    if (g->start && fill) {
        grid_insert(g, NULL);
        for (i = 0; i < ncell; i++)
            g->start[i + 1] += g->start[i];
        g->items = amp_calloc(g->alloc, g->start[ncell] ? g->start[ncell] : 1, sizeof *g->items);
    }
    if (!g->start || !fill || !g->items) {
        amp_free(g->alloc, fill);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the segment grid");
    }
    memcpy(fill, g->start, ncell * sizeof *fill);
    grid_insert(g, fill);
    amp_free(g->alloc, fill);
    return AMP_OK;
}

static void grid_free(seg_grid *g)
{
    amp_free(g->alloc, g->start);
    amp_free(g->alloc, g->items);
}

/* xorshift64 (13, 7, 17): the trivariate's sample stream. */
static double rnd_trivariate(unsigned long *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (double)(*s >> 11) / 9007199254740992.0;
}

/* xorshift64*: the mesh's sample stream. The two streams are kept as they were
 * before the measures were merged so that every reported gap stays the same. */
static double rnd_mesh(unsigned long long *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 0x2545F4914F6CDD1DULL) >> 11) / 9007199254740992.0;
}

/* n parameter triples: the 8 corners, then half uniform in parameters, half uniform in space by rejection. */
static void sample_parameters(const amp_spline *v, size_t samples, unsigned long seed, double jmax, double *par)
{
    unsigned long st = seed ? seed : 88172645463325252UL;
    size_t n = samples + 8, i, tries = 0;
    double lo[3], hi[3];
    int d;
    for (d = 0; d < 3; d++)
        amp_spline_domain(v, d, &lo[d], &hi[d]);
    for (i = 0; i < 8; i++)
        for (d = 0; d < 3; d++)
            par[3 * i + (size_t)d] = (i >> d) & 1 ? hi[d] : lo[d];
    for (i = 8; i < n; i++)
        for (;;) {
            double p[3];
            for (d = 0; d < 3; d++)
                p[d] = lo[d] + (hi[d] - lo[d]) * rnd_trivariate(&st);
            tries++;
            if (i < 8 + samples / 2 || jmax <= 0 || rnd_trivariate(&st) * jmax <= amp_spl_det_jacobian(v, p) ||
                tries > 200 * n) {
                memcpy(par + 3 * i, p, sizeof p);
                break;
            }
        }
}

static amp_status coverage_trivariate(const amp_spline *v, const amp_pathset *ps, size_t samples,
                                      unsigned long seed, amp_coverage *out, amp_error *err)
{
    seg_grid g;
    double jmax, sum = 0, *par = NULL, *dist = NULL;
    size_t n, i;
    long li;
    amp_status st;
    memset(&g, 0, sizeof g);
    g.alloc = v->alloc;
    if (samples < 1000)
        samples = 1000;
    n = samples + 8;
    st = grid_build(&g, ps, amp_spline_cp_bbox(v), err);
    if (st == AMP_OK) {
        par = amp_calloc(v->alloc, n, 3 * sizeof(double));
        dist = amp_calloc(v->alloc, n, sizeof(double));
        if (!par || !dist)
            st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for samples");
    }
    if (st == AMP_OK) {
        out->volume = amp_spl_volume(v, &jmax);
        /* quadrature points may miss the true maximum; a larger bound keeps uniformity */
        sample_parameters(v, samples, seed, jmax * 1.25, par);
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 64)
#endif
        for (li = 0; li < (long)n; li++) {
            amp_vec3 x;
            amp_spline_eval(v, par + 3 * li, &x, NULL);
            dist[li] = grid_nearest(&g, x);
        }
        for (i = 0; i < n; i++) {
            sum += dist[i];
            if (i == 0 || dist[i] > out->gap) {
                out->gap = dist[i];
                memcpy(out->worst_par, par + 3 * i, sizeof out->worst_par);
            }
        }
        amp_spline_eval(v, out->worst_par, &out->worst, NULL);
        out->samples = n;
        out->mean = sum / (double)n;
    }
    amp_free(v->alloc, par);
    amp_free(v->alloc, dist);
    grid_free(&g);
    return st;
}

static amp_status coverage_mesh(const amp_bvh *b, double margin, const amp_pathset *ps, size_t samples,
                                unsigned long seed, amp_coverage *out, amp_error *err)
{
    seg_grid g;
    amp_box3 box = amp_bvh_bbox(b);
    unsigned long long s = 0x9E3779B97F4A7C15ULL ^ (unsigned long long)seed;
    size_t got = 0, tries = 0;
    double sum = 0;
    amp_status st;
    if (samples == 0 || !(margin >= 0))
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_check_coverage: no samples or a negative margin");
    memset(&g, 0, sizeof g);
    g.alloc = ps->alloc;
    if ((st = grid_build(&g, ps, box, err)) != AMP_OK) {
        grid_free(&g);
        return st;
    }
    while (got < samples && tries < 100 * samples) {
        amp_vec3 p = amp_v3(box.min.x + rnd_mesh(&s) * (box.max.x - box.min.x),
                            box.min.y + rnd_mesh(&s) * (box.max.y - box.min.y),
                            box.min.z + rnd_mesh(&s) * (box.max.z - box.min.z));
        double d;
        tries++;
        if (!amp_bvh_inside(b, p) || (margin > 0 && amp_bvh_closest(b, p, NULL, NULL) < margin))
            continue;
        d = grid_nearest(&g, p);
        if (got == 0 || d > out->gap) {
            out->gap = d;
            out->worst = p;
        }
        sum += d;
        got++;
    }
    grid_free(&g);
    if (got == 0)
        return amp_fail(err, AMP_ERR_GEOMETRY, 0, "no sample point fell inside the mesh");
    out->samples = got;
    out->mean = sum / (double)got;
    return AMP_OK;
}

amp_status amp_check_coverage(const amp_pathset *ps, const amp_coverage_domain *d, size_t samples, unsigned long seed,
                              amp_coverage *out, amp_error *err)
{
    amp_status st;
    if (!out || !ps || !d || !d->trivariate == !d->mesh || (d->trivariate && d->trivariate->dim != 3))
        return amp_fail(err, AMP_ERR_ARG, 0, "coverage measurement needs paths and one trivariate or mesh");
    memset(out, 0, sizeof *out);
    if (d->trivariate)
        st = coverage_trivariate(d->trivariate, ps, samples, seed, out, err);
    else
        st = coverage_mesh(d->mesh, d->margin, ps, samples, seed, out, err);
    if (st == AMP_OK)
        out->deposited = amp_pathset_volume(ps, -1);
    return st;
}
