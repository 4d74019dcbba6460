/* Held-path check ([P1 §5.3]): every object bead is printed over earlier material or the bed. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "ampath/check.h"

void amp_hold_opts_default(amp_hold_opts *o)
{
    o->overhang = 0.25 * AMP_PI;
    o->max_gap = 1.0;
    o->bridge = 5.0;
    o->cantilever = 1.0;
    o->step = 0.25;
}

void amp_hold_report_free(amp_hold_report *rep)
{
    if (!rep)
        return;
    amp_free(rep->alloc, rep->paths_failed);
    rep->paths_failed = NULL;
    rep->npaths_failed = 0;
}

typedef amp_bead_sample hsample;

typedef struct hctx {
    const amp_allocator *a;
    hsample *sm;
    size_t n, cap;
    size_t *cell_first, *cell_of, *sorted;
    size_t nx, ny, nz;
    double cs;
    amp_box3 bb;
    double hmax;
} hctx;

static amp_status add_sample(hctx *c, amp_vec3 p, double half, double s, size_t path, amp_error *err)
{
    void *q = c->sm;
    if (c->n >= 0x7fffffffU)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "more than 2^31 samples: raise the sample step");
    if (amp_grow(c->a, &q, &c->cap, c->n + 1, sizeof *c->sm) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for support-check samples");
    c->sm = q;
    c->sm[c->n].p = p;
    c->sm[c->n].half = half;
    c->sm[c->n].s = s;
    c->sm[c->n].path = (uint32_t)path;
    c->n++;
    c->hmax = fmax(c->hmax, half);
    return AMP_OK;
}

/* Samples in print order: every `step` mm along each segment whose radius is positive (not a pseudo edge). */
static amp_status sample_paths(hctx *c, const amp_pathset *ps, double step, amp_error *err)
{
    size_t i, k;
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        double h = ps->paths[i].h, s = 0.0;
        if (ps->paths[i].n == 1 && v[0].r > 0.0) {
            amp_status st = add_sample(c, v[0].p, h > 0.0 ? 0.5 * h : v[0].r, 0.0, i, err);
            if (st != AMP_OK)
                return st;
        }
        for (k = 0; k + 1 < ps->paths[i].n; k++) {
            double len = amp_v3_dist(v[k].p, v[k + 1].p), t;
            size_t m = (size_t)ceil(len / step), j;
            if (v[k].r > 0.0 || v[k + 1].r > 0.0)
                for (j = (k == 0 ? 0 : 1); j <= m; j++) {
                    double r;
                    amp_status st;
                    t = m ? (double)j / (double)m : 0.0;
                    r = v[k].r + t * (v[k + 1].r - v[k].r);
                    if (!(r > 0.0))
                        continue;
                    st = add_sample(c, amp_v3_lerp(v[k].p, v[k + 1].p, t), h > 0.0 ? 0.5 * h : r, s + t * len, i, err);
                    if (st != AMP_OK)
                        return st;
                }
            s += len;
        }
    }
    return AMP_OK;
}

static size_t cell_index(const hctx *c, amp_vec3 p, size_t *ix, size_t *iy, size_t *iz)
{
    double fx = (p.x - c->bb.min.x) / c->cs, fy = (p.y - c->bb.min.y) / c->cs, fz = (p.z - c->bb.min.z) / c->cs;
    *ix = fx <= 0 ? 0 : (size_t)fx >= c->nx ? c->nx - 1 : (size_t)fx;
    *iy = fy <= 0 ? 0 : (size_t)fy >= c->ny ? c->ny - 1 : (size_t)fy;
    *iz = fz <= 0 ? 0 : (size_t)fz >= c->nz ? c->nz - 1 : (size_t)fz;
    return (*iz * c->ny + *iy) * c->nx + *ix;
}

/* A uniform grid over the samples (counting sort by cell), cells of at least `reach` / 2 mm, at most ~8M cells. */
static amp_status build_grid(hctx *c, double reach, amp_error *err)
{
    size_t i, ncell, ix, iy, iz;
    c->bb = amp_box3_empty();
    for (i = 0; i < c->n; i++)
        c->bb = amp_box3_add(c->bb, c->sm[i].p);
    if (c->n == 0) /* nothing printed (pseudo edges only): one cell, not an empty box's infinite extent */
        c->bb.min = c->bb.max = amp_v3(0, 0, 0);
    c->cs = fmax(0.5 * reach, 0.25);
    for (;;) {
        c->nx = (size_t)((c->bb.max.x - c->bb.min.x) / c->cs) + 1;
        c->ny = (size_t)((c->bb.max.y - c->bb.min.y) / c->cs) + 1;
        c->nz = (size_t)((c->bb.max.z - c->bb.min.z) / c->cs) + 1;
        if ((double)c->nx * (double)c->ny * (double)c->nz <= 8e6)
            break;
        c->cs *= 1.5;
    }
    ncell = c->nx * c->ny * c->nz;
    c->cell_first = amp_calloc(c->a, ncell + 1, sizeof *c->cell_first);
    c->cell_of = amp_calloc(c->a, c->n + 1, sizeof *c->cell_of);
    c->sorted = amp_calloc(c->a, c->n + 1, sizeof *c->sorted);
    if (!c->cell_first || !c->cell_of || !c->sorted)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the support-check grid");
    for (i = 0; i < c->n; i++) {
        c->cell_of[i] = cell_index(c, c->sm[i].p, &ix, &iy, &iz);
        c->cell_first[c->cell_of[i] + 1]++;
    }
    for (i = 0; i < ncell; i++)
        c->cell_first[i + 1] += c->cell_first[i];
    /* samples stay in print order inside each cell: the scan below can stop at the first later sample */
    for (i = 0; i < c->n; i++)
        c->sorted[c->cell_first[c->cell_of[i]]++] = i;
    for (i = ncell; i > 0; i--)
        c->cell_first[i] = c->cell_first[i - 1];
    c->cell_first[0] = 0;
    return AMP_OK;
}

/* Does an earlier sample listed in @p cell hold sample t (p)? The cell lists are in print order: the scan stops
 * at the first later sample. */
static int cell_holds(const hctx *c, const amp_hold_opts *o, const hsample *p, size_t t, size_t cell, double tn)
{
    size_t k;
    for (k = c->cell_first[cell]; k < c->cell_first[cell + 1] && c->sorted[k] < t; k++) {
        const hsample *q = &c->sm[c->sorted[k]];
        double dz = p->p.z - q->p.z, dx = p->p.x - q->p.x, dy = p->p.y - q->p.y;
        if (dz > 0.0 && (p->p.z - p->half) - (q->p.z + q->half) <= o->max_gap + 1e-9 &&
            sqrt(dx * dx + dy * dy) <= dz * tn + 1e-9)
            return 1;
    }
    return 0;
}

/* Is sample t held by the bed or by an earlier sample (see check.h)? The answer is a yes/no over the cells
 * within reach, so they are read where a holder most likely lies: the level below first, the sample's own
 * column first in each level, and its own level (the path's own earlier samples beside it) last: 41 samples
 * read a call instead of 62 on the demo. */
static int held(const hctx *c, const amp_hold_opts *o, size_t t)
{
    const hsample *p = &c->sm[t];
    double tn = tan(o->overhang), dzmax = p->half + o->max_gap + c->hmax, rxy = dzmax * tn + 1e-9;
    size_t x0, y0, z0, x1, y1, z1, x, y, z, px, py, pz, i;
    if (p->p.z - p->half <= o->max_gap + 1e-9)
        return 1;
    cell_index(c, amp_v3(p->p.x - rxy, p->p.y - rxy, p->p.z - dzmax), &x0, &y0, &z0);
    cell_index(c, amp_v3(p->p.x + rxy, p->p.y + rxy, p->p.z), &x1, &y1, &z1);
    cell_index(c, p->p, &px, &py, &pz);
    for (i = 0; i <= z1 - z0; i++) {
        z = i < z1 - z0 ? z1 - 1 - i : z1; /* z1 - 1 down to z0, then z1 */
        if (cell_holds(c, o, p, t, (z * c->ny + py) * c->nx + px, tn))
            return 1;
        for (y = y0; y <= y1; y++)
            for (x = x0; x <= x1; x++)
                if ((x != px || y != py) && cell_holds(c, o, p, t, (z * c->ny + y) * c->nx + x, tn))
                    return 1;
    }
    return 0;
}

static amp_status note_failure(amp_hold_report *rep, size_t path, double len, amp_vec3 at, amp_error *err)
{
    size_t cap = rep->npaths_failed;
    rep->failures++;
    rep->failed_mm += len;
    if (rep->failures == 1 || len > rep->worst_mm) {
        rep->worst_mm = len;
        rep->worst_path = path;
        rep->worst_at = at;
    }
    if (rep->npaths_failed && rep->paths_failed[rep->npaths_failed - 1] == path)
        return AMP_OK;
    {
        void *q = rep->paths_failed;
        /* capacity tracks the count exactly: failures are rare, a realloc each is fine */
        if (amp_grow(rep->alloc, &q, &cap, rep->npaths_failed + 1, sizeof *rep->paths_failed) != AMP_OK)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory listing unheld paths");
        rep->paths_failed = q;
    }
    rep->paths_failed[rep->npaths_failed++] = path;
    return AMP_OK;
}

/* Runs of unheld samples along each object path: bridges (held both sides, short) or failures. */
static amp_status judge_runs(const hctx *c, const amp_pathset *ps, const amp_hold_opts *o, const unsigned char *ok,
                             amp_hold_report *rep, amp_bead_run_fn fail, void *user, amp_error *err)
{
    size_t i = 0;
    while (i < c->n) {
        size_t path = c->sm[i].path, j = i, e;
        int before, after;
        if (ps->paths[path].role != AMP_ROLE_OBJECT || ok[i]) {
            i++;
            continue;
        }
        for (e = i; e < c->n && c->sm[e].path == path && !ok[e]; e++)
            ;
        /* unheld run [i, e) of one path: a bridge between held samples, or a short tip off a held sample */
        before = i > 0 && c->sm[i - 1].path == path;
        after = e < c->n && c->sm[e].path == path;
        amp_status st = AMP_OK;
        if (before && after && c->sm[e].s - c->sm[i - 1].s <= o->bridge + 1e-9) {
            rep->bridges++;
            rep->bridged_mm += c->sm[e].s - c->sm[i - 1].s;
        } else if (before != after && (before ? c->sm[e - 1].s - c->sm[i - 1].s : c->sm[e].s - c->sm[i].s) <=
                                          o->cantilever + 1e-9) {
            rep->tips++;
        } else {
            st = note_failure(rep, path, c->sm[e - 1].s - c->sm[j].s + o->step, c->sm[j].p, err);
        }
        if (st == AMP_OK && fail)
            st = fail(user, &c->sm[i], e - i, err);
        if (st != AMP_OK)
            return st;
        i = e;
    }
    return AMP_OK;
}

/* amp_check_hold(), handing every unheld run to @p fail (NULL: none) as it is judged. */
static amp_status hold_scan(const amp_pathset *ps, const amp_hold_opts *o, amp_hold_report *rep, amp_bead_run_fn fail,
                            void *user, amp_error *err)
{
    hctx c;
    unsigned char *ok = NULL;
    amp_status st;
    long t;
    if (!ps || !o || !rep)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_check_hold: NULL argument");
    memset(rep, 0, sizeof *rep);
    rep->alloc = ps->alloc;
    if (!(o->overhang >= 0.0 && o->overhang < 0.5 * AMP_PI) || !(o->max_gap >= 0.0) ||
        !(o->bridge >= 0.0) || !(o->cantilever >= 0.0) || !(o->step > 0.0) ||
        !isfinite(o->max_gap + o->bridge + o->cantilever + o->step))
        return amp_fail(err, AMP_ERR_RANGE, 0,
                        "support check: overhang must be in [0, 90) degrees, gap, bridge and tip >= 0, step > 0");
    memset(&c, 0, sizeof c);
    c.a = ps->alloc;
    if ((st = sample_paths(&c, ps, o->step, err)) != AMP_OK)
        goto done;
    if ((st = build_grid(&c, c.hmax * 2.0 + o->max_gap, err)) != AMP_OK)
        goto done;
    ok = amp_calloc(c.a, c.n + 1, 1);
    if (!ok) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the support check");
        goto done;
    }
#pragma omp parallel for schedule(dynamic, 256)
    for (t = 0; t < (long)c.n; t++)
        ok[t] = ps->paths[c.sm[t].path].role != AMP_ROLE_OBJECT || held(&c, o, (size_t)t);
    for (t = 0; t < (long)c.n; t++)
        if (ps->paths[c.sm[t].path].role == AMP_ROLE_OBJECT) {
            rep->samples++;
            rep->unheld += !ok[t];
        }
    st = judge_runs(&c, ps, o, ok, rep, fail, user, err);
done:
    amp_free(c.a, ok);
    amp_free(c.a, c.sm);
    amp_free(c.a, c.cell_first);
    amp_free(c.a, c.cell_of);
    amp_free(c.a, c.sorted);
    return st;
}

amp_status amp_check_hold(const amp_pathset *ps, const amp_hold_opts *o, amp_hold_report *rep, amp_error *err)
{
    return hold_scan(ps, o, rep, NULL, NULL, err);
}

amp_status amp_check_hold_runs(const amp_pathset *ps, double max_gap, amp_bead_run_fn run, void *user,
                               amp_error *err)
{
    amp_hold_opts o;
    amp_hold_report rep;
    amp_status st;
    if (!ps || !run)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_check_hold_runs: NULL argument");
    memset(&rep, 0, sizeof rep);
    amp_hold_opts_default(&o);
    o.max_gap = max_gap;
    st = hold_scan(ps, &o, &rep, run, user, err);
    amp_hold_report_free(&rep);
    return st;
}
