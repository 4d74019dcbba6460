/* Support structure (paper §5.3): vertical rays find the support volume, a grid fills it, cones order it. */
#include <math.h>
#include <string.h>

#include "ampath/support.h"
#include "fragbvh.h"

void amp_support_opts_default(amp_support_opts *o)
{
    amp_head_default(&o->head);
    o->spacing = 2.0;
    o->layer_height = 0.4;
    o->radius = 0.2;
    o->min_gap = 1.0;
}

/* One stretch of a vertical ray that needs support: air from z0 (plate or solid) up to the underside z1. */
typedef struct column {
    size_t ix, iy;
    double z0, z1;
} column;

typedef struct sctx {
    const amp_allocator *a;
    column *col;
    size_t ncol, capcol;
    size_t *first; /* columns of grid point i: [first[i], first[i+1]) */
    size_t nx, ny;
    double x0, y0, sp;
} sctx;

static int active(const sctx *c, size_t ix, size_t iy, double z, double h)
{
    size_t q, g = iy * c->nx + ix;
    for (q = c->first[g]; q < c->first[g + 1]; q++)
        if (z > c->col[q].z0 && z <= c->col[q].z1 - 0.5 * h)
            return 1;
    return 0;
}

/* Vertical rays (§5.3) through the model on the grid; columns are stored grid point by grid point. */
static amp_status cast_rays(sctx *c, const amp_bvh *model, const amp_support_opts *o, amp_support_stats *st,
                            amp_error *err)
{
    amp_box3 bb = amp_bvh_bbox(model);
    size_t ix, iy;
    c->sp = o->spacing;
    c->nx = (size_t)((bb.max.x - bb.min.x) / o->spacing) + 1;
    c->ny = (size_t)((bb.max.y - bb.min.y) / o->spacing) + 1;
    if ((double)c->nx * (double)c->ny > 4e7)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "support grid of %lu x %lu rays is too fine (spacing %g mm)",
                        (unsigned long)c->nx, (unsigned long)c->ny, o->spacing);
    c->x0 = 0.5 * (bb.min.x + bb.max.x) - 0.5 * (double)(c->nx - 1) * o->spacing;
    c->y0 = 0.5 * (bb.min.y + bb.max.y) - 0.5 * (double)(c->ny - 1) * o->spacing;
    c->first = amp_calloc(c->a, c->nx * c->ny + 1, sizeof *c->first);
    if (!c->first)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the support grid");
    for (iy = 0; iy < c->ny; iy++)
        for (ix = 0; ix < c->nx; ix++) {
            amp_vec3 org = amp_v3(c->x0 + (double)ix * c->sp, c->y0 + (double)iy * c->sp, fmin(bb.min.z, 0.0) - 1.0);
            amp_bvh_hit *hits = NULL;
            size_t n = 0, h;
            double below = 0.0; /* top of the last solid stretch, or the plate */
            int inside = 0;
            amp_status s = amp_bvh_ray_all(model, org, amp_v3(0, 0, 1), HUGE_VAL, &hits, &n, err);
            if (s != AMP_OK)
                return s;
            st->rays++;
            for (h = 0; h < n; h++) {
                double z = hits[h].p.z;
                if (hits[h].entering && !inside) {
                    inside = 1;
                    if (z - below >= o->min_gap && z > 0.0) {
                        void *p = c->col;
                        if (amp_grow(c->a, &p, &c->capcol, c->ncol + 1, sizeof *c->col) != AMP_OK) {
                            amp_bvh_hits_free(model, hits);
                            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for support columns");
                        }
                        c->col = p;
                        c->col[c->ncol].ix = ix;
                        c->col[c->ncol].iy = iy;
                        c->col[c->ncol].z0 = fmax(below, 0.0);
                        c->col[c->ncol].z1 = z;
                        c->ncol++;
                    }
                } else if (!hits[h].entering && inside) {
                    inside = 0;
                    below = z;
                }
            }
            amp_bvh_hits_free(model, hits);
            c->first[iy * c->nx + ix + 1] = c->ncol;
        }
    st->columns = c->ncol;
    return AMP_OK;
}

/* Fill the columns with rows on every layer: along x on even layers, along y on odd ones. */
static amp_status fill(const sctx *c, const amp_support_opts *o, amp_pathset *sup, amp_error *err)
{
    double ztop = 0.0, h = o->layer_height;
    size_t q, layer;
    for (q = 0; q < c->ncol; q++)
        ztop = fmax(ztop, c->col[q].z1);
    for (layer = 0; (double)(layer + 1) * h < ztop; layer++) {
        double z = (double)(layer + 1) * h;
        int along_x = layer % 2 == 0;
        size_t nrow = along_x ? c->ny : c->nx, nlen = along_x ? c->nx : c->ny, row, i;
        for (row = 0; row < nrow; row++) {
            i = 0;
            while (i < nlen) {
                size_t j;
                if (!active(c, along_x ? i : row, along_x ? row : i, z, h)) {
                    i++;
                    continue;
                }
                for (j = i; j < nlen && active(c, along_x ? j : row, along_x ? row : j, z, h); j++)
                    ;
                {
                    amp_status s = amp_pathset_begin(sup, AMP_ROLE_SUPPORT, err);
                    size_t k;
                    for (k = i; s == AMP_OK && k < j; k++) {
                        size_t gx = along_x ? k : row, gy = along_x ? row : k;
                        s = amp_pathset_push(sup, amp_v3(c->x0 + (double)gx * c->sp, c->y0 + (double)gy * c->sp, z),
                                             o->radius, err);
                    }
                    if (s != AMP_OK)
                        return s;
                }
                i = j;
            }
        }
    }
    return AMP_OK;
}

#define NOPATH 0xffffffffU

/*
 * Over the object fragments, the smallest path index (want_min) of a fragment
 * above s, or the largest (!want_min) of a fragment below s. Branch and bound
 * on per-node index bounds; NOPATH when none.
 */
static uint32_t search(const amp_fbvh *b, const amp_fragments *fs, const amp_head *hd, const uint32_t *nmin,
                       const uint32_t *nmax, size_t nobj, uint32_t s, int want_min)
{
    uint32_t stack[128], best = NOPATH;
    size_t top = 0;
    double k = 1.0 / tan(hd->theta);
    const amp_fragment *fr = &fs->frag[s];
    stack[top++] = 0;
    while (top) {
        uint32_t id = stack[--top];
        const amp_fbvh_node *nd = &b->node[id];
        double gap = k * amp_box_xy_gap(nd->box, fr->box);
        if (nmin[id] == NOPATH)
            continue;
        if (want_min ? (best != NOPATH && nmin[id] >= best) : (best != NOPATH && nmax[id] <= best))
            continue;
        if (want_min ? nd->box.max.z - fr->box.min.z - hd->z_offs - gap <= AMP_CONE_TOL
                     : fr->box.max.z - nd->box.min.z - hd->z_offs - gap <= AMP_CONE_TOL)
            continue;
        if (nd->left == 0) {
            uint32_t q;
            for (q = nd->lo; q < nd->hi; q++) {
                uint32_t g = b->order[q], p = fs->frag[g].path;
                if (p >= nobj || (best != NOPATH && (want_min ? p >= best : p <= best)))
                    continue;
                if (want_min ? amp_fragment_below_k(fs, hd->z_offs, k, s, g)
                             : amp_fragment_below_k(fs, hd->z_offs, k, g, s))
                    best = p;
            }
        } else if (top + 2 <= 128) {
            stack[top++] = nd->left;
            stack[top++] = nd->right;
        }
    }
    return best;
}

amp_status amp_support(const amp_pathset *in, const amp_bvh *model, const amp_support_opts *o, amp_pathset *out,
                       amp_support_stats *st, amp_error *err)
{
    sctx c;
    amp_support_stats s;
    amp_pathset all;
    amp_fragments fs;
    amp_fbvh b;
    uint32_t *nmin = NULL, *nmax = NULL, *pos = NULL;
    size_t i, nobj, nsup;
    amp_status stt;
    memset(&c, 0, sizeof c);
    memset(&s, 0, sizeof s);
    memset(&b, 0, sizeof b);
    memset(&fs, 0, sizeof fs);
    if (!in || !model || !o || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_support: NULL argument");
    if ((stt = amp_head_validate(&o->head, err)) != AMP_OK)
        return stt;
    if (!(o->spacing > 0.0) || !(o->layer_height > 0.0) || !(o->radius >= 0.0) || !(o->min_gap >= 0.0) ||
        !isfinite(o->spacing + o->layer_height + o->radius + o->min_gap))
        return amp_fail(err, AMP_ERR_RANGE, 0, "support spacing and layer height must be positive, radius and gap >= 0");
    if (in->npaths >= NOPATH)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "too many paths");
    c.a = out->alloc;
    amp_pathset_init(&all, out->alloc);
    if ((stt = cast_rays(&c, model, o, &s, err)) != AMP_OK)
        goto done;
    nobj = in->npaths;
    if ((stt = amp_pathset_append(&all, in, err)) != AMP_OK || (stt = fill(&c, o, &all, err)) != AMP_OK)
        goto done;
    nsup = all.npaths - nobj;
    s.paths = nsup;
    for (i = nobj; i < all.npaths; i++)
        s.length += amp_path_length(&all, i);
    /* §5.3 ordering: the support below an object path is printed before it */
    if ((stt = amp_fragments_build(&fs, &all, o->head.z_offs, c.a, err)) != AMP_OK ||
        (stt = amp_fbvh_build(&b, &fs, c.a, err)) != AMP_OK)
        goto done;
    nmin = amp_calloc(c.a, b.nnodes + 1, sizeof *nmin);
    nmax = amp_calloc(c.a, b.nnodes + 1, sizeof *nmax);
    pos = amp_calloc(c.a, nsup + 1, sizeof *pos);
    if (!nmin || !nmax || !pos) {
        stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for ordering support");
        goto done;
    }
    for (i = b.nnodes; i-- > 0;) {
        const amp_fbvh_node *nd = &b.node[i];
        nmin[i] = NOPATH;
        nmax[i] = 0;
        if (nd->left == 0) {
            uint32_t q;
            for (q = nd->lo; q < nd->hi; q++) {
                uint32_t p = fs.frag[b.order[q]].path;
                if (p < nobj && in->paths[p].role == AMP_ROLE_OBJECT) {
                    nmin[i] = p < nmin[i] ? p : nmin[i];
                    nmax[i] = p > nmax[i] ? p : nmax[i];
                }
            }
        } else {
            nmin[i] = nmin[nd->left] < nmin[nd->right] ? nmin[nd->left] : nmin[nd->right];
            nmax[i] = nmax[nd->left] > nmax[nd->right] ? nmax[nd->left] : nmax[nd->right];
        }
    }
    {
        long si;
        size_t conflicts = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : conflicts)
        for (si = 0; si < (long)nsup; si++) {
            size_t path = nobj + (size_t)si, f;
            uint32_t best = NOPATH, late = NOPATH;
            for (f = fs.first[path]; f < fs.first[path + 1]; f++) {
                uint32_t p = search(&b, &fs, &o->head, nmin, nmax, nobj, (uint32_t)f, 1);
                best = p < best ? p : best;
            }
            for (f = fs.first[path]; best != NOPATH && f < fs.first[path + 1]; f++) {
                uint32_t p = search(&b, &fs, &o->head, nmin, nmax, nobj, (uint32_t)f, 0);
                if (p != NOPATH && (late == NOPATH || p > late))
                    late = p;
            }
            pos[si] = best;
            conflicts += late != NOPATH && late >= best;
        }
        s.conflicts = conflicts;
    }
    /* Supports are made bottom-up, layer by layer: a support printed after a higher one could lie below it
     * (support-support gouge), so each is moved no later than every support made after it (suffix minimum). */
    for (i = nsup; i-- > 1;)
        if (pos[i] < pos[i - 1])
            pos[i - 1] = pos[i];
    /* emit: the supports of object path i (in layer order) right before it */
    {
        size_t *cnt = amp_calloc(c.a, nobj + 2, sizeof *cnt), *ord = amp_calloc(c.a, nsup + 1, sizeof *ord);
        size_t k;
        if (!cnt || !ord) {
            amp_free(c.a, cnt);
            amp_free(c.a, ord);
            stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for ordering support");
            goto done;
        }
        for (i = 0; i < nsup; i++)
            cnt[(pos[i] == NOPATH ? nobj : pos[i]) + 1]++;
        for (i = 0; i <= nobj; i++)
            cnt[i + 1] += cnt[i];
        for (i = 0; i < nsup; i++)
            ord[cnt[pos[i] == NOPATH ? nobj : pos[i]]++] = i;
        s.unplaced = cnt[nobj] - (nobj ? cnt[nobj - 1] : 0);
        for (i = 0, k = 0; stt == AMP_OK && i <= nobj; i++) {
            for (; stt == AMP_OK && k < cnt[i]; k++)
                stt = amp_pathset_add(out, AMP_ROLE_SUPPORT, amp_pathset_path_verts(&all, nobj + ord[k]),
                                      all.paths[nobj + ord[k]].n, err);
            if (stt == AMP_OK && i < nobj)
                stt = amp_pathset_add(out, in->paths[i].role, amp_pathset_path_verts(in, i), in->paths[i].n, err);
        }
        amp_free(c.a, cnt);
        amp_free(c.a, ord);
    }
    if (st)
        *st = s;
done:
    amp_free(c.a, c.col);
    amp_free(c.a, c.first);
    amp_free(c.a, nmin);
    amp_free(c.a, nmax);
    amp_free(c.a, pos);
    amp_fbvh_free(&b);
    amp_fragments_free(&fs);
    amp_pathset_free(&all);
    return stt;
}
