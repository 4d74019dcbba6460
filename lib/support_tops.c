/*
 * The object beads' tops on a grid of 1 mm cells (samples every 0.25 mm): what lies under a support pad
 * (lib/support_pads.c) and which object path holds a bead printed before it (lib/support_settle.c).
 */
#include <math.h>
#include <string.h>

#include "support_internal.h"

#define TOP_CELL 1.0
#define TOP_STEP 0.25

static size_t cell_of(const amp_bead_tops *t, double x, double y)
{
    double fx = (x - t->x0) / TOP_CELL, fy = (y - t->y0) / TOP_CELL;
    size_t ix = fx <= 0.0 ? 0 : (size_t)fx >= t->nx ? t->nx - 1 : (size_t)fx;
    size_t iy = fy <= 0.0 ? 0 : (size_t)fy >= t->ny ? t->ny - 1 : (size_t)fy;
    return iy * t->nx + ix;
}

static amp_status add_top(amp_bead_tops *t, amp_vec3 p, double top, double w, size_t path, amp_error *err)
{
    void *q = t->tp;
    if (amp_grow(t->a, &q, &t->cap, t->n + 1, sizeof *t->tp) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the object beads' tops");
    t->tp = q;
    t->tp[t->n].x = p.x;
    t->tp[t->n].y = p.y;
    t->tp[t->n].top = top;
    t->tp[t->n].z = p.z;
    t->tp[t->n].w = w;
    t->tp[t->n].path = (uint32_t)path;
    t->n++;
    t->reach = fmax(t->reach, w);
    return AMP_OK;
}

/* Samples of paths [0, nobj) with a positive radius (a planar bead's top is its path, docs/interfaces.md §3; a
 * tube reaches r above it; a planar bead counts under what rests on it within h/2 of its centre line, as high
 * as wide). */
static amp_status sample_beads(amp_bead_tops *t, const amp_pathset *ps, size_t nobj, amp_error *err)
{
    size_t i, k;
    amp_status st = AMP_OK;
    for (i = 0; i < nobj && st == AMP_OK; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        double h = ps->paths[i].h;
        for (k = 0; k + 1 < ps->paths[i].n && st == AMP_OK; k++) {
            size_t m = (size_t)ceil(amp_v3_dist(v[k].p, v[k + 1].p) / TOP_STEP), j;
            for (j = 0; j <= m && st == AMP_OK; j++) {
                double s = m ? (double)j / (double)m : 0.0, r = v[k].r + s * (v[k + 1].r - v[k].r);
                amp_vec3 q = amp_v3_lerp(v[k].p, v[k + 1].p, s);
                if (r > 0.0)
                    st = add_top(t, q, h > 0.0 ? q.z : q.z + r, h > 0.0 ? 0.5 * h : r, i, err);
            }
        }
    }
    return st;
}

amp_status amp_bead_tops_build(amp_bead_tops *t, const amp_pathset *ps, size_t nobj, amp_error *err)
{
    amp_box3 b = amp_box3_empty();
    size_t i, n, *cnt;
    amp_bead_top *sorted;
    amp_status st;
    memset(t, 0, sizeof *t);
    t->a = ps->alloc;
    if ((st = sample_beads(t, ps, nobj, err)) != AMP_OK)
        return st;
    for (i = 0; i < t->n; i++)
        b = amp_box3_add(b, amp_v3(t->tp[i].x, t->tp[i].y, 0.0));
    t->x0 = t->n ? b.min.x : 0.0;
    t->y0 = t->n ? b.min.y : 0.0;
    t->nx = t->n ? (size_t)((b.max.x - b.min.x) / TOP_CELL) + 1 : 1;
    t->ny = t->n ? (size_t)((b.max.y - b.min.y) / TOP_CELL) + 1 : 1;
    if ((double)t->nx * (double)t->ny > 4e7)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "object too wide for support pads (%lu x %lu cells)",
                        (unsigned long)t->nx, (unsigned long)t->ny);
    n = t->nx * t->ny;
    t->cell = amp_calloc(t->a, n + 1, sizeof *t->cell);
    cnt = amp_calloc(t->a, n + 1, sizeof *cnt);
    sorted = amp_calloc(t->a, t->n + 1, sizeof *sorted);
    if (!t->cell || !cnt || !sorted) {
        amp_free(t->a, cnt);
        amp_free(t->a, sorted);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the object beads' tops");
    }
    for (i = 0; i < t->n; i++)
        t->cell[cell_of(t, t->tp[i].x, t->tp[i].y) + 1]++;
    for (i = 0; i < n; i++)
        t->cell[i + 1] += t->cell[i];
    /* a counting sort keeps each cell's samples in path order */
    for (i = 0; i < t->n; i++) {
        size_t q = cell_of(t, t->tp[i].x, t->tp[i].y);
        sorted[t->cell[q] + cnt[q]++] = t->tp[i];
    }
    amp_free(t->a, t->tp);
    amp_free(t->a, cnt);
    t->tp = sorted;
    t->cap = t->n;
    return AMP_OK;
}

void amp_bead_tops_free(amp_bead_tops *t)
{
    if (!t)
        return;
    amp_free(t->a, t->tp);
    amp_free(t->a, t->cell);
    memset(t, 0, sizeof *t);
}

void amp_bead_tops_near(const amp_bead_tops *t, double x, double y, double d, size_t *x0, size_t *y0, size_t *x1,
                        size_t *y1)
{
    size_t lo = cell_of(t, x - d, y - d), hi = cell_of(t, x + d, y + d);
    *x0 = lo % t->nx;
    *y0 = lo / t->nx;
    *x1 = hi % t->nx;
    *y1 = hi / t->nx;
}
