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

/* the judge's sample step (check.h), and the shortest pad */
#define PAD_STEP 0.25

typedef struct pads {
    amp_pathset *all;
    size_t nobj;
    const amp_bvh *model;
    const amp_support_opts *o;
    const amp_support_layers *L;
    amp_box3 bb; /* the model's box */
    amp_bead_tops tops;
    int have_tops;
    double *base;
    size_t capbase;
    amp_support_pads_stats st;
} pads;

/* The highest object bead top under @p p (centre line lower than p, within a bead's reach of a pad bead of
 * radius rs at p) that is no higher than @p bottom; -HUGE_VAL if none. */
static double object_top_below(const pads *c, amp_vec3 p, double bottom, double rs)
{
    const amp_bead_tops *t = &c->tops;
    double best = -HUGE_VAL;
    size_t x0, y0, x1, y1, x, y, k;
    amp_bead_tops_near(t, p.x, p.y, rs + t->reach, &x0, &y0, &x1, &y1);
    for (y = y0; y <= y1; y++)
        for (x = x0; x <= x1; x++)
            for (k = t->cell[y * t->nx + x]; k < t->cell[y * t->nx + x + 1]; k++) {
                const amp_bead_top *q = &t->tp[k];
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

/* One pad bead path along samples [i, e) of a run on support layer j. A stretch shorter than a sample step (a
 * lone sample, or two samples at the ends of a short segment: 0.001 mm on CGAL's camel) is a stroke of one
 * step along the run, centred on it, so that no pad is a speck the writer travels to for nothing. */
static amp_status emit_stretch(pads *c, const amp_bead_sample *run, size_t n, size_t i, size_t e, size_t j,
                               amp_error *err)
{
    double rs = c->o->radius, z = amp_support_layer_z(c->L, j), h = amp_support_layer_h(c->L, j), len = 0.0;
    size_t k;
    int speck;
    amp_status st = amp_pathset_begin(c->all, AMP_ROLE_SUPPORT, err);
    if (st == AMP_OK && h > 0.0)
        st = amp_pathset_set_height(c->all, h, err);
    for (k = i + 1; k < e; k++)
        len += hypot(run[k].p.x - run[k - 1].p.x, run[k].p.y - run[k - 1].p.y);
    speck = len < PAD_STEP;
    if (st == AMP_OK && speck) {
        amp_vec3 a = run[i > 0 ? i - 1 : i].p, b = run[e < n ? e : e - 1].p, m = amp_v3_lerp(run[i].p, run[e - 1].p, 0.5), d;
        double ab = hypot(b.x - a.x, b.y - a.y);
        d = ab > 0.0 ? amp_v3((b.x - a.x) / ab, (b.y - a.y) / ab, 0.0) : amp_v3(1, 0, 0);
        st = amp_pathset_push(c->all, amp_v3(m.x - 0.5 * PAD_STEP * d.x, m.y - 0.5 * PAD_STEP * d.y, z), rs, err);
        if (st == AMP_OK)
            st = amp_pathset_push(c->all, amp_v3(m.x + 0.5 * PAD_STEP * d.x, m.y + 0.5 * PAD_STEP * d.y, z), rs, err);
        len = PAD_STEP;
    }
    for (k = i; st == AMP_OK && !speck && k < e; k++)
        st = amp_pathset_push_merged(c->all, amp_v3(run[k].p.x, run[k].p.y, z), rs, AMP_PATH_SAME_POINT, k + 1 == e, err);
    c->st.length += len;
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
    if (!c->have_tops) {
        c->have_tops = 1;
        if ((st = amp_bead_tops_build(&c->tops, c->all, c->nobj, err)) != AMP_OK)
            return st;
    }
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
                            const amp_support_layers *L, const amp_unheld_runs *known, amp_support_pads_stats *out,
                            amp_error *err)
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
    if (known && known->valid) {
        for (i = k = 0; i < known->nruns && st == AMP_OK; k = known->end[i++])
            st = pad_run(&c, known->sm + k, known->end[i] - k, err);
    } else {
        /* the judge sees the support first (the order support.c then aims at), then the objects in their order */
        amp_pathset_init(&probe, all->alloc);
        for (k = 0; k < 2 && st == AMP_OK; k++)
            for (i = k ? 0 : nobj; i < (k ? nobj : all->npaths) && st == AMP_OK; i++)
                st = amp_pathset_copy_path(&probe, all, i, err);
        if (st == AMP_OK) /* air lower than min_gap is left on purpose (check.h) */
            st = o->find_unheld(&probe, o->min_gap, pad_run, &c, err);
        amp_pathset_free(&probe);
    }
    amp_bead_tops_free(&c.tops);
    amp_free(all->alloc, c.base);
    if (out)
        *out = c.st;
    return st;
}
