/*
 * Independent coverage measurement for volumetric coverings (issue 4): sample
 * the trivariate's volume and find, for each sample, the exact distance to the
 * nearest path segment through a uniform grid. Shares nothing with lib/cover.c
 * except the spline evaluator.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/cover.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* Gauss-Legendre, 3 points on [0, 1] */
static const double gx[3] = {0.1127016653792583, 0.5, 0.8872983346207417};
static const double gw[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

static double jac(const amp_spline *v, const double *p)
{
    amp_vec3 D[8];
    if (amp_spline_eval_derivs(v, p, 1, D, NULL) != AMP_OK)
        return 0;
    /* D[1] = d/du, D[2] = d/dv, D[4] = d/dw */
    return fabs(amp_v3_dot(D[1], amp_v3_cross(D[2], D[4])));
}

/* Volume and the largest |det J| seen at the quadrature points. */
static double volume_and_max(const amp_spline *v, double *jmax)
{
    enum { C = 12 };
    double lo[3], hi[3], vol = 0, jm = 0;
    int d, i, j, k, a, b, c;
    for (d = 0; d < 3; d++)
        amp_spline_domain(v, d, &lo[d], &hi[d]);
    for (k = 0; k < C; k++)
        for (j = 0; j < C; j++)
            for (i = 0; i < C; i++)
                for (c = 0; c < 3; c++)
                    for (b = 0; b < 3; b++)
                        for (a = 0; a < 3; a++) {
                            double p[3], J;
                            p[0] = lo[0] + (hi[0] - lo[0]) * (i + gx[a]) / C;
                            p[1] = lo[1] + (hi[1] - lo[1]) * (j + gx[b]) / C;
                            p[2] = lo[2] + (hi[2] - lo[2]) * (k + gx[c]) / C;
                            J = jac(v, p);
                            jm = fmax(jm, J);
                            vol += gw[a] * gw[b] * gw[c] * J;
                        }
    if (jmax)
        *jmax = jm;
    return vol * (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]) / (C * C * C);
}

double amp_trivariate_volume(const amp_spline *v) { return volume_and_max(v, NULL); }

typedef struct seggrid {
    amp_vec3 o;
    double h;
    int n[3];
    size_t *start; /* ncells + 1 */
    size_t *seg;   /* segment ids per cell */
    const amp_pathset *ps;
    size_t *sa;    /* segment id -> first vertex index */
} seggrid;

static int clampi(int x, int lo, int hi) { return x < lo ? lo : (x > hi ? hi : x); }

static void cell_of(const seggrid *g, amp_vec3 p, int *c)
{
    c[0] = clampi((int)floor((p.x - g->o.x) / g->h), 0, g->n[0] - 1);
    c[1] = clampi((int)floor((p.y - g->o.y) / g->h), 0, g->n[1] - 1);
    c[2] = clampi((int)floor((p.z - g->o.z) / g->h), 0, g->n[2] - 1);
}

static double nearest(const seggrid *g, amp_vec3 p)
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
                if (y < 0 || z < 0 || y >= g->n[1] || z >= g->n[2])
                    continue;
                for (x = c[0] - r; x <= c[0] + r; x += step) {
                    size_t id, k;
                    if (x < 0 || x >= g->n[0])
                        continue;
                    id = (size_t)x + (size_t)g->n[0] * ((size_t)y + (size_t)g->n[1] * (size_t)z);
                    for (k = g->start[id]; k < g->start[id + 1]; k++) {
                        size_t a = g->sa[g->seg[k]];
                        double d2 = amp_v3_seg_dist2(p, g->ps->verts[a].p, g->ps->verts[a + 1].p, NULL);
                        best2 = d2 < best2 ? d2 : best2;
                    }
                }
            }
    }
    return sqrt(best2);
}

/* Each segment goes into every cell its box touches. */
static amp_status build_grid(seggrid *g, const amp_pathset *ps, amp_box3 box, const amp_allocator *al,
                             amp_error *err)
{
    size_t i, k, nseg = 0, ncell, pass;
    amp_vec3 sz;
    double vol;
    for (i = 0; i < ps->npaths; i++)
        nseg += ps->paths[i].n > 1 ? ps->paths[i].n - 1 : 0;
    if (nseg == 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "no path segment to measure against");
    g->ps = ps;
    box = amp_box3_inflate(box, 1e-6);
    sz = amp_box3_size(box);
    vol = fmax(sz.x, 1e-3) * fmax(sz.y, 1e-3) * fmax(sz.z, 1e-3);
    g->h = cbrt(vol / (double)nseg) * 0.75;
    g->h = fmax(g->h, fmax(fmax(sz.x, sz.y), sz.z) / 200);
    g->o = box.min;
    g->n[0] = (int)(sz.x / g->h) + 1;
    g->n[1] = (int)(sz.y / g->h) + 1;
    g->n[2] = (int)(sz.z / g->h) + 1;
    ncell = (size_t)g->n[0] * (size_t)g->n[1] * (size_t)g->n[2];
    g->start = amp_calloc(al, ncell + 1, sizeof(size_t));
    g->sa = amp_calloc(al, nseg, sizeof(size_t));
    if (!g->start || !g->sa)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the segment grid");
    nseg = 0;
    for (i = 0; i < ps->npaths; i++)
        for (k = 1; k < ps->paths[i].n; k++)
            g->sa[nseg++] = ps->paths[i].first + k - 1;
    for (pass = 0; pass < 2; pass++) {
        size_t s, *cur = NULL;
        if (pass == 1) {
            size_t c;
            for (c = 1; c <= ncell; c++)
                g->start[c] += g->start[c - 1];
            g->seg = amp_calloc(al, g->start[ncell] ? g->start[ncell] : 1, sizeof(size_t));
            cur = amp_calloc(al, ncell, sizeof(size_t));
            if (!g->seg || !cur) {
                amp_free(al, cur);
                return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the segment grid");
            }
            memcpy(cur, g->start, ncell * sizeof(size_t));
        }
        for (s = 0; s < nseg; s++) {
            amp_vec3 a = ps->verts[g->sa[s]].p, b = ps->verts[g->sa[s] + 1].p;
            int c0[3], c1[3], x, y, z;
            cell_of(g, amp_v3_min(a, b), c0);
            cell_of(g, amp_v3_max(a, b), c1);
            for (z = c0[2]; z <= c1[2]; z++)
                for (y = c0[1]; y <= c1[1]; y++)
                    for (x = c0[0]; x <= c1[0]; x++) {
                        size_t id = (size_t)x + (size_t)g->n[0] * ((size_t)y + (size_t)g->n[1] * (size_t)z);
                        if (pass == 0)
                            g->start[id + 1]++;
                        else
                            g->seg[cur[id]++] = s;
                    }
        }
        amp_free(al, cur);
    }
    return AMP_OK;
}

static double rnd(unsigned long *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (double)(*s >> 11) / 9007199254740992.0;
}

amp_status amp_cover_measure_gap(const amp_spline *v, const amp_pathset *ps, size_t samples, unsigned long seed,
                                 amp_cover_gap *out, amp_error *err)
{
    seggrid g;
    double lo[3], hi[3], jmax, *par = NULL, *dist = NULL;
    unsigned long st_rng = seed ? seed : 88172645463325252UL;
    size_t n, i, tries = 0;
    long li;
    amp_status st;
    amp_box3 box;
    int d;
    memset(&g, 0, sizeof g);
    memset(out, 0, sizeof *out);
    if (!v || v->dim != 3 || !ps)
        return amp_fail(err, AMP_ERR_ARG, 0, "coverage measurement needs a trivariate and paths");
    if (samples < 1000)
        samples = 1000;
    for (d = 0; d < 3; d++)
        amp_spline_domain(v, d, &lo[d], &hi[d]);
    box = amp_box3_union(amp_spline_cp_bbox(v), amp_pathset_bbox(ps));
    st = build_grid(&g, ps, box, v->alloc, err);
    n = samples + 8;
    if (st == AMP_OK) {
        par = amp_calloc(v->alloc, n, 3 * sizeof(double));
        dist = amp_calloc(v->alloc, n, sizeof(double));
        if (!par || !dist)
            st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for samples");
    }
    if (st == AMP_OK) {
        out->volume = volume_and_max(v, &jmax);
        jmax *= 1.25; /* quadrature points may miss the true maximum; a larger bound keeps uniformity */
        for (i = 0; i < 8; i++)
            for (d = 0; d < 3; d++)
                par[3 * i + (size_t)d] = (i >> d) & 1 ? hi[d] : lo[d];
        for (i = 8; i < n; i++) {
            for (;;) {
                double p[3];
                for (d = 0; d < 3; d++)
                    p[d] = lo[d] + (hi[d] - lo[d]) * rnd(&st_rng);
                tries++;
                /* first half: uniform in parameters; second half: uniform in space by rejection */
                if (i < 8 + samples / 2 || jmax <= 0 || rnd(&st_rng) * jmax <= jac(v, p) || tries > 200 * n) {
                    memcpy(par + 3 * i, p, sizeof p);
                    break;
                }
            }
        }
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 64)
#endif
        for (li = 0; li < (long)n; li++) {
            amp_vec3 x;
            amp_spline_eval(v, par + 3 * li, &x, NULL);
            dist[li] = nearest(&g, x);
        }
        for (i = 0; i < n; i++)
            if (i == 0 || dist[i] > out->gap) {
                out->gap = dist[i];
                memcpy(out->worst_par, par + 3 * i, sizeof out->worst_par);
            }
        amp_spline_eval(v, out->worst_par, &out->worst, NULL);
        out->samples = n;
        out->deposited = amp_pathset_volume(ps, -1);
    }
    amp_free(v->alloc, par);
    amp_free(v->alloc, dist);
    amp_free(v->alloc, g.start);
    amp_free(v->alloc, g.seg);
    amp_free(v->alloc, g.sa);
    return st;
}
