/*
 * Pads (beyond [P1 §5.3]): support traced under the object beads that the
 * grid's support leaves in the air.
 *
 * The rays of lib/support.c see the model, not the paths: where the model's
 * underside lies less than min_gap above what is below it they put no
 * support, yet the lowest curves printed there may float higher (a field's
 * rows are a spacing apart: on a sphere or a torus lying on the bed, the
 * first row over the shallow rim of the underside sits 1.2 mm up with
 * nothing under it). The judge the caller gives (amp_support_opts.find_unheld:
 * the tool's is the held-path check of `ampath check`, which this builder does
 * not link) names those runs, with support printed first; under
 * each failing run a stack of support beads follows its samples, on the
 * support layers (row heights of lib/support.c), from what lies under each
 * sample (the bed, a solid of the model that ends below it, or an object
 * bead) up to its bottom. The pads are then ordered with the other support.
 */
#include <math.h>
#include <string.h>

#include "support_internal.h"

/* Object bead tops on a grid of 1 mm cells (samples every 0.25 mm), for what lies under a pad. */
#define TOP_CELL 1.0
#define TOP_STEP 0.25

typedef struct ptop {
    double x, y, top, z, w; /* w: how far the bead reaches sideways from its centre line */
} ptop;

typedef struct pads {
    amp_pathset *all;
    size_t nobj;
    const amp_bvh *model;
    const amp_support_opts *o;
    const amp_support_layers *L;
    amp_box3 bb; /* the model's box */
    ptop *tp;    /* object bead samples sorted by cell */
    size_t ntp, captp, *cell, nx, ny;
    double x0, y0, reach; /* grid origin; farthest a bead's edge reaches from its centre line */
    double *base;
    size_t capbase;
    amp_support_pads_stats st;
} pads;

static size_t cell_of(const pads *c, double x, double y)
{
    double fx = (x - c->x0) / TOP_CELL, fy = (y - c->y0) / TOP_CELL;
    size_t ix = fx <= 0.0 ? 0 : (size_t)fx >= c->nx ? c->nx - 1 : (size_t)fx;
    size_t iy = fy <= 0.0 ? 0 : (size_t)fy >= c->ny ? c->ny - 1 : (size_t)fy;
    return iy * c->nx + ix;
}

static amp_status add_top(pads *c, amp_vec3 p, double top, double w, amp_error *err)
{
    void *q = c->tp;
    if (amp_grow(c->all->alloc, &q, &c->captp, c->ntp + 1, sizeof *c->tp) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for support pads");
    c->tp = q;
    c->tp[c->ntp].x = p.x;
    c->tp[c->ntp].y = p.y;
    c->tp[c->ntp].top = top;
    c->tp[c->ntp].z = p.z;
    c->tp[c->ntp].w = w;
    c->ntp++;
    c->reach = fmax(c->reach, w);
    return AMP_OK;
}

/* The object beads' samples (a planar bead's top is its path, docs/interfaces.md §3; a tube reaches r above it),
 * bucketed by cell. */
static amp_status tops_build(pads *c, amp_error *err)
{
    const amp_pathset *ps = c->all;
    amp_box3 b = amp_box3_empty();
    size_t i, k, n, *cnt;
    ptop *sorted;
    amp_status st = AMP_OK;
    for (i = 0; i < c->nobj && st == AMP_OK; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        double h = ps->paths[i].h;
        for (k = 0; k + 1 < ps->paths[i].n && st == AMP_OK; k++) {
            size_t m = (size_t)ceil(amp_v3_dist(v[k].p, v[k + 1].p) / TOP_STEP), j;
            for (j = 0; j <= m && st == AMP_OK; j++) {
                double t = m ? (double)j / (double)m : 0.0, r = v[k].r + t * (v[k + 1].r - v[k].r);
                amp_vec3 q = amp_v3_lerp(v[k].p, v[k + 1].p, t);
                if (r > 0.0) /* a planar bead counts under a pad within h/2 of its centre line, as high as wide */
                    st = add_top(c, q, h > 0.0 ? q.z : q.z + r, h > 0.0 ? 0.5 * h : r, err);
            }
        }
    }
    if (st != AMP_OK)
        return st;
    for (i = 0; i < c->ntp; i++)
        b = amp_box3_add(b, amp_v3(c->tp[i].x, c->tp[i].y, 0.0));
    c->x0 = c->ntp ? b.min.x : 0.0;
    c->y0 = c->ntp ? b.min.y : 0.0;
    c->nx = c->ntp ? (size_t)((b.max.x - b.min.x) / TOP_CELL) + 1 : 1;
    c->ny = c->ntp ? (size_t)((b.max.y - b.min.y) / TOP_CELL) + 1 : 1;
    if ((double)c->nx * (double)c->ny > 4e7)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "object too wide for support pads (%lu x %lu cells)",
                        (unsigned long)c->nx, (unsigned long)c->ny);
    n = c->nx * c->ny;
    c->cell = amp_calloc(c->all->alloc, n + 1, sizeof *c->cell);
    cnt = amp_calloc(c->all->alloc, n + 1, sizeof *cnt);
    sorted = amp_calloc(c->all->alloc, c->ntp + 1, sizeof *sorted);
    if (!c->cell || !cnt || !sorted) {
        amp_free(c->all->alloc, cnt);
        amp_free(c->all->alloc, sorted);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for support pads");
    }
    for (i = 0; i < c->ntp; i++)
        c->cell[cell_of(c, c->tp[i].x, c->tp[i].y) + 1]++;
    for (i = 0; i < n; i++)
        c->cell[i + 1] += c->cell[i];
    for (i = 0; i < c->ntp; i++) {
        size_t q = cell_of(c, c->tp[i].x, c->tp[i].y);
        sorted[c->cell[q] + cnt[q]++] = c->tp[i];
    }
    amp_free(c->all->alloc, c->tp);
    amp_free(c->all->alloc, cnt);
    c->tp = sorted;
    c->captp = c->ntp;
    return AMP_OK;
}

/* The highest object bead top under @p p (centre line lower than p, within a bead's reach of a pad bead of
 * radius rs at p) that is no higher than @p bottom; -HUGE_VAL if none. */
static double object_top_below(const pads *c, amp_vec3 p, double bottom, double rs)
{
    double best = -HUGE_VAL, d = rs + c->reach;
    size_t lo = cell_of(c, p.x - d, p.y - d), hi = cell_of(c, p.x + d, p.y + d);
    size_t x0 = lo % c->nx, y0 = lo / c->nx, x1 = hi % c->nx, y1 = hi / c->nx, x, y, k;
    for (y = y0; y <= y1; y++)
        for (x = x0; x <= x1; x++)
            for (k = c->cell[y * c->nx + x]; k < c->cell[y * c->nx + x + 1]; k++) {
                const ptop *q = &c->tp[k];
                if (q->z < p.z - 1e-9 && q->top <= bottom + 1e-9 && q->top > best &&
                    hypot(q->x - p.x, q->y - p.y) <= rs + q->w)
                    best = q->top;
            }
    return best;
}

/* The top of the highest solid stretch of the model that ends at or below @p bottom under (p.x, p.y). */
static amp_status solid_top_below(const pads *c, amp_vec3 p, double bottom, double *below, amp_error *err)
{
    amp_vec3 org = amp_v3(p.x, p.y, fmin(c->bb.min.z, c->L->plate) - 1.0);
    amp_bvh_hit *hits = NULL;
    size_t n = 0, h;
    int inside = 0;
    amp_status st = amp_bvh_ray_all(c->model, org, amp_v3(0, 0, 1), bottom - org.z, &hits, &n, err);
    if (st != AMP_OK)
        return st;
    for (h = 0; h < n; h++) {
        if (hits[h].entering && !inside)
            inside = 1;
        else if (!hits[h].entering && inside) {
            inside = 0;
            *below = fmax(*below, hits[h].p.z);
        }
    }
    amp_bvh_hits_free(c->model, hits);
    return AMP_OK;
}

/* One pad bead path along samples [i, e) of a run on support layer j (a lone sample: a short stroke along
 * the run). */
static amp_status emit_stretch(pads *c, const amp_bead_sample *run, size_t n, size_t i, size_t e, size_t j,
                               amp_error *err)
{
    double rs = c->o->radius, z = amp_support_layer_z(c->L, j), h = amp_support_layer_h(c->L, j);
    size_t k;
    amp_status st = amp_pathset_begin(c->all, AMP_ROLE_SUPPORT, err);
    if (st == AMP_OK && h > 0.0)
        st = amp_pathset_set_height(c->all, h, err);
    if (st == AMP_OK && e == i + 1) {
        amp_vec3 a = run[i > 0 ? i - 1 : i].p, b = run[i + 1 < n ? i + 1 : i].p, d;
        double len = hypot(b.x - a.x, b.y - a.y);
        d = len > 0.0 ? amp_v3((b.x - a.x) / len, (b.y - a.y) / len, 0.0) : amp_v3(1, 0, 0);
        st = amp_pathset_push(c->all, amp_v3(run[i].p.x - 0.125 * d.x, run[i].p.y - 0.125 * d.y, z), rs, err);
        if (st == AMP_OK)
            st = amp_pathset_push(c->all, amp_v3(run[i].p.x + 0.125 * d.x, run[i].p.y + 0.125 * d.y, z), rs, err);
        c->st.length += 0.25;
    }
    for (k = i; st == AMP_OK && e > i + 1 && k < e; k++) {
        st = amp_pathset_push_merged(c->all, amp_v3(run[k].p.x, run[k].p.y, z), rs, AMP_PATH_SAME_POINT, k + 1 == e, err);
        if (k > i)
            c->st.length += hypot(run[k].p.x - run[k - 1].p.x, run[k].p.y - run[k - 1].p.y);
    }
    c->st.paths += st == AMP_OK;
    return st;
}

/* Bottom of the bead of a sample: a sliced job's planar bead hangs its whole height h = 2 half under its path. */
static double sample_bottom(const pads *c, const amp_bead_sample *q)
{
    return q->p.z - (c->L->h > 0.0 ? 2.0 : 1.0) * q->half;
}

/* Does a pad bead of support layer j fit under sample k: above what lies under it, below its bead (planar
 * layers: one layer under it, the rows' contact gap)? */
static int fits(const pads *c, const amp_bead_sample *run, size_t k, size_t j)
{
    double z = amp_support_layer_z(c->L, j), h = amp_support_layer_h(c->L, j), rs = c->o->radius;
    if (h > 0.0)
        return z - h >= c->base[k] - 1e-9 && z <= sample_bottom(c, &run[k]) - c->L->step + 1e-9;
    return z - rs >= c->base[k] - 1e-9 && z + rs <= sample_bottom(c, &run[k]) + 1e-9;
}

/* amp_bead_run_fn: the stack of pads under one unheld run. */
static amp_status pad_run(void *user, const amp_bead_sample *run, size_t n, amp_error *err)
{
    pads *c = user;
    double rs = c->o->radius, zmax = -HUGE_VAL;
    size_t i, j, e;
    amp_status st = AMP_OK;
    void *q = c->base;
    if (!c->cell && (st = tops_build(c, err)) != AMP_OK)
        return st;
    if (amp_grow(c->all->alloc, &q, &c->capbase, n, sizeof *c->base) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for support pads");
    c->base = q;
    for (i = 0; i < n && st == AMP_OK; i++) {
        double bottom = sample_bottom(c, &run[i]);
        c->base[i] = c->L->plate;
        st = solid_top_below(c, run[i].p, bottom, &c->base[i], err);
        c->base[i] = fmax(c->base[i], object_top_below(c, run[i].p, bottom, rs));
        zmax = fmax(zmax, bottom);
    }
    c->st.runs++;
    /* layer j's beads lie on the row height of lib/support.c; a sample takes the layers between its base and
     * its bottom, so the top one ends less than a layer under it */
    for (j = 0; st == AMP_OK; j++) {
        double z = amp_support_layer_z(c->L, j);
        if ((amp_support_layer_h(c->L, j) > 0.0 ? z : z + rs) > zmax + 1e-9)
            break;
        for (i = 0; st == AMP_OK && i < n; i = e) {
            for (e = i; e < n && fits(c, run, e, j); e++)
                ;
            if (e == i)
                e = i + 1;
            else
                st = emit_stretch(c, run, n, i, e, j, err);
        }
    }
    return st;
}

amp_status amp_support_pads(amp_pathset *all, size_t nobj, const amp_bvh *model, const amp_support_opts *o,
                            const amp_support_layers *L, amp_support_pads_stats *out, amp_error *err)
{
    amp_pathset probe;
    pads c;
    size_t i, k;
    amp_status st = AMP_OK;
    memset(&c, 0, sizeof c);
    c.all = all;
    c.nobj = nobj;
    c.model = model;
    c.o = o;
    c.L = L;
    c.bb = amp_bvh_bbox(model);
    /* the judge sees the support first (the order support.c then aims at), then the objects in their order */
    amp_pathset_init(&probe, all->alloc);
    for (k = 0; k < 2 && st == AMP_OK; k++)
        for (i = k ? 0 : nobj; i < (k ? nobj : all->npaths) && st == AMP_OK; i++)
            st = amp_pathset_copy_path(&probe, all, i, err);
    if (st == AMP_OK) /* air lower than min_gap is left on purpose (check.h) */
        st = o->find_unheld(&probe, o->min_gap, pad_run, &c, err);
    amp_pathset_free(&probe);
    amp_free(all->alloc, c.tp);
    amp_free(all->alloc, c.cell);
    amp_free(all->alloc, c.base);
    if (out)
        *out = c.st;
    return st;
}
