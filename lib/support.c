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
/* late[] marker of a support fragment left out */
#define LEFT_OUT (NOPATH - 1)

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

/* Support fragment f has no gouge-free slot: mark it left out and count it. */
static void leave_out(const amp_fragments *fs, uint32_t *late, size_t f, amp_support_stats *s)
{
    late[f] = LEFT_OUT;
    s->conflicts++;
    s->trimmed += amp_v3_dist(fs->frag[f].p0, fs->frag[f].p1);
}

/* A piece of a support row: fragments [f0, f1) printed together just before object path pos. */
typedef struct piece {
    size_t f0, f1;
    uint32_t pos;
} piece;

/* Append the fragments of @p pc that are not left out, one path per run of consecutive kept fragments. */
static amp_status emit_piece(amp_pathset *out, const amp_fragments *fs, const uint32_t *late, const piece *pc,
                             amp_pvert **run, size_t *cap, amp_error *err)
{
    const amp_pathset *ps = fs->ps;
    size_t f = pc->f0;
    amp_status st = AMP_OK;
    while (st == AMP_OK && f < pc->f1) {
        size_t n = 0, g;
        for (; f < pc->f1 && late[f] == LEFT_OUT; f++)
            ;
        for (g = f; g < pc->f1 && late[g] != LEFT_OUT; g++) {
            const amp_fragment *fr = &fs->frag[g];
            size_t v;
            if (amp_grow(out->alloc, (void **)run, cap, n + fr->nin + 2, sizeof **run) != AMP_OK)
                return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for support paths");
            if (n == 0) {
                (*run)[n].p = fr->p0;
                (*run)[n++].r = fr->r0;
            }
            for (v = 0; v < fr->nin; v++)
                (*run)[n++] = ps->verts[fr->vfirst + v];
            (*run)[n].p = fr->p1;
            (*run)[n++].r = fr->r1;
        }
        f = g;
        if (n >= 2)
            st = amp_pathset_add(out, AMP_ROLE_SUPPORT, *run, n, err);
    }
    return st;
}

/* Cells per support grid spacing in the field of order_pieces (finer cells: less over-approximation). */
#define SUB 4

/* Running minimum over a window of 2k + 1 cells along @p lines lines of @p n cells (stride @p step). */
static void min_pass(const uint32_t *src, uint32_t *dst, size_t n, size_t step, size_t lines, size_t line_step,
                     size_t k)
{
    size_t l, i, t;
    for (l = 0; l < lines; l++)
        for (i = 0; i < n; i++) {
            uint32_t m = NOPATH;
            for (t = i > k ? i - k : 0; t <= i + k && t < n; t++)
                m = src[l * line_step + t * step] < m ? src[l * line_step + t * step] : m;
            dst[l * line_step + i * step] = m;
        }
}

/* Chebyshev dilation of a min-field by k cells: rows, then columns, via scratch tmp. */
static void dilate_min(uint32_t *d, uint32_t *tmp, size_t nx, size_t ny, size_t k)
{
    min_pass(d, tmp, nx, 1, ny, nx, k);
    min_pass(tmp, d, ny, nx, nx, 1, k);
}

/* Cell range of a fragment's xy box grown by r cells, clamped to the field. */
static void cell_range(const sctx *c, const amp_box3 *b, size_t r, size_t nx, size_t ny, size_t *x0, size_t *x1,
                       size_t *y0, size_t *y1)
{
    double cs = c->sp / SUB;
    long a0 = (long)floor((b->min.x - c->x0) / cs + 0.5) - (long)r, a1 = (long)floor((b->max.x - c->x0) / cs + 0.5) + (long)r;
    long b0 = (long)floor((b->min.y - c->y0) / cs + 0.5) - (long)r, b1 = (long)floor((b->max.y - c->y0) / cs + 0.5) + (long)r;
    *x0 = a0 < 0 ? 0 : (size_t)a0;
    *y0 = b0 < 0 ? 0 : (size_t)b0;
    *x1 = a1 < 0 ? 0 : (size_t)a1 >= nx ? nx - 1 : (size_t)a1;
    *y1 = b1 < 0 ? 0 : (size_t)b1 >= ny ? ny - 1 : (size_t)b1;
}

/*
 * A lower support piece L must be printed no later than any piece H above it:
 * pos(L) = min(pos(L), pos(H)). Going down layer by layer, a field over a fine
 * xy grid holds, per cell, the smallest pos of the pieces above that cell's
 * points at the current height: H enters once it is more than z_offs higher
 * (disc of radius (dz - z_offs) / cot(theta), grown by one cell), and
 * every layer down the discs grow by layer_height / cot(theta). Square cells
 * and square dilation over-approximate the cone, which only ever moves pieces
 * earlier (safe), never later.
 */
static amp_status order_pieces(const sctx *c, const amp_support_opts *o, const amp_fragments *fs, piece *pcs,
                               size_t npc, amp_error *err)
{
    double cs = c->sp / SUB, h = o->layer_height, cot = 1.0 / tan(o->head.theta);
    size_t nx = c->nx * SUB + 1, ny = c->ny * SUB + 1, i, nl = 0, *lfirst;
    size_t step = (size_t)ceil(h / cot / cs), lag = (size_t)floor(o->head.z_offs / h) + 1;
    uint32_t *d, *tmp;
    long l;
    if (npc == 0)
        return AMP_OK;
    for (i = 0; i < npc; i++) {
        size_t li = (size_t)floor(fs->frag[pcs[i].f0].p0.z / h + 0.5);
        nl = li + 1 > nl ? li + 1 : nl;
    }
    d = amp_calloc(c->a, nx * ny, sizeof *d);
    tmp = amp_calloc(c->a, nx * ny, sizeof *tmp);
    lfirst = amp_calloc(c->a, nl + 2, sizeof *lfirst);
    if (!d || !tmp || !lfirst) {
        amp_free(c->a, d);
        amp_free(c->a, tmp);
        amp_free(c->a, lfirst);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory ordering support pieces");
    }
    /* pieces are made layer by layer: lfirst[l] = first piece of layer l */
    for (i = 0; i < npc; i++)
        lfirst[(size_t)floor(fs->frag[pcs[i].f0].p0.z / h + 0.5) + 1]++;
    for (i = 0; i <= nl; i++)
        lfirst[i + 1] += lfirst[i];
    for (i = 0; i < nx * ny; i++)
        d[i] = NOPATH;
    for (l = (long)nl - 1; l >= 0; l--) {
        size_t m = (size_t)l + lag, k;
        if ((size_t)l + 1 < nl)
            dilate_min(d, tmp, nx, ny, step);
        if (m < nl) { /* layer m is now more than z_offs above layer l */
            double dz = (double)(m - (size_t)l) * h - o->head.z_offs;
            size_t r = (size_t)ceil(dz / cot / cs) + 1;
            for (k = lfirst[m]; k < lfirst[m + 1]; k++) {
                size_t f;
                for (f = pcs[k].f0; f < pcs[k].f1; f++) {
                    size_t x0, x1, y0, y1, x, y;
                    cell_range(c, &fs->frag[f].box, r, nx, ny, &x0, &x1, &y0, &y1);
                    for (y = y0; y <= y1; y++)
                        for (x = x0; x <= x1; x++)
                            d[y * nx + x] = pcs[k].pos < d[y * nx + x] ? pcs[k].pos : d[y * nx + x];
                }
            }
        }
        for (k = lfirst[l]; k < lfirst[l + 1]; k++) {
            size_t f;
            for (f = pcs[k].f0; f < pcs[k].f1; f++) {
                size_t x0, x1, y0, y1, x, y;
                cell_range(c, &fs->frag[f].box, 0, nx, ny, &x0, &x1, &y0, &y1);
                for (y = y0; y <= y1; y++)
                    for (x = x0; x <= x1; x++)
                        pcs[k].pos = d[y * nx + x] < pcs[k].pos ? d[y * nx + x] : pcs[k].pos;
            }
        }
    }
    amp_free(c->a, d);
    amp_free(c->a, tmp);
    amp_free(c->a, lfirst);
    return AMP_OK;
}

amp_status amp_support(const amp_pathset *in, const amp_bvh *model, const amp_support_opts *o, amp_pathset *out,
                       amp_support_stats *st, amp_error *err)
{
    sctx c;
    amp_support_stats s;
    amp_pathset all;
    amp_fragments fs;
    amp_fbvh b;
    uint32_t *nmin = NULL, *nmax = NULL, *first = NULL, *late = NULL;
    amp_pvert *run = NULL;
    piece *pcs = NULL;
    size_t run_cap = 0, npc = 0, pcap = 0;
    size_t i, nobj;
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
    for (i = nobj; i < all.npaths; i++)
        s.length += amp_path_length(&all, i);
    /* §5.3 ordering: the support below an object path is printed before it */
    if ((stt = amp_fragments_build(&fs, &all, o->head.z_offs, c.a, err)) != AMP_OK ||
        (stt = amp_fbvh_build(&b, &fs, c.a, err)) != AMP_OK)
        goto done;
    nmin = amp_calloc(c.a, b.nnodes + 1, sizeof *nmin);
    nmax = amp_calloc(c.a, b.nnodes + 1, sizeof *nmax);
    first = amp_calloc(c.a, fs.n + 1, sizeof *first);
    late = amp_calloc(c.a, fs.n + 1, sizeof *late);
    if (!nmin || !nmax || !first || !late) {
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
    /* per support fragment: the first object path above it (it must come before) and the last one below it
     * (it must come after) */
    {
        long f0 = (long)fs.first[nobj], f;
#pragma omp parallel for schedule(dynamic, 64)
        for (f = f0; f < (long)fs.n; f++) {
            first[f] = search(&b, &fs, &o->head, nmin, nmax, nobj, (uint32_t)f, 1);
            late[f] = search(&b, &fs, &o->head, nmin, nmax, nobj, (uint32_t)f, 0);
        }
    }
    /* Cut each row into as few pieces as possible such that every piece has a slot: the first object above
     * any of its fragments comes after the last object below any of them. A fragment with no slot of its own
     * (an object printed later lies below it: a thin overhang gap, a steep underside) is left out. */
    for (i = nobj; i < all.npaths; i++) {
        size_t f = fs.first[i];
        while (f < fs.first[i + 1]) {
            piece pc;
            uint32_t lo = NOPATH, hi = 0;
            int any_late = 0;
            pc.f0 = f;
            for (; f < fs.first[i + 1]; f++) {
                uint32_t nlo = first[f] < lo ? first[f] : lo, nhi = hi;
                int nany = any_late;
                if (late[f] != NOPATH) {
                    nhi = late[f] > hi ? late[f] : hi;
                    nany = 1;
                }
                if (nany && nlo != NOPATH && nhi >= nlo) {
                    if (f == pc.f0) { /* no slot even alone */
                        leave_out(&fs, late, f, &s);
                        pc.f0 = f + 1;
                        continue;
                    }
                    break;
                }
                lo = nlo;
                hi = nhi;
                any_late = nany;
            }
            if (f == pc.f0)
                continue;
            pc.f1 = f;
            pc.pos = lo;
            if ((stt = amp_grow(c.a, (void **)&pcs, &pcap, npc + 1, sizeof *pcs)) != AMP_OK) {
                stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for ordering support");
                goto done;
            }
            pcs[npc++] = pc;
        }
    }
    /* Support-support gouging: a piece must be printed before every piece above it (Def. 5.1). */
    if ((stt = order_pieces(&c, o, &fs, pcs, npc, err)) != AMP_OK)
        goto done;
    /* Moving a piece earlier can put it before an object below it: those fragments are left out too. */
    for (i = 0; i < npc; i++) {
        size_t f;
        for (f = pcs[i].f0; f < pcs[i].f1; f++)
            if (late[f] != NOPATH && late[f] != LEFT_OUT && pcs[i].pos != NOPATH && late[f] >= pcs[i].pos)
                leave_out(&fs, late, f, &s);
    }
    /* emit: the pieces of object path k (in the order they were made) right before it, unplaced ones last */
    {
        size_t *cnt = amp_calloc(c.a, nobj + 2, sizeof *cnt), *ord = amp_calloc(c.a, npc + 1, sizeof *ord);
        size_t k;
        if (!cnt || !ord) {
            amp_free(c.a, cnt);
            amp_free(c.a, ord);
            stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for ordering support");
            goto done;
        }
        for (i = 0; i < npc; i++)
            cnt[(pcs[i].pos == NOPATH ? nobj : pcs[i].pos) + 1]++;
        for (i = 0; i <= nobj; i++)
            cnt[i + 1] += cnt[i];
        for (i = 0; i < npc; i++)
            ord[cnt[pcs[i].pos == NOPATH ? nobj : pcs[i].pos]++] = i;
        for (i = 0, k = 0; stt == AMP_OK && i <= nobj; i++) {
            size_t before = out->npaths;
            for (; stt == AMP_OK && k < cnt[i]; k++)
                stt = emit_piece(out, &fs, late, &pcs[ord[k]], &run, &run_cap, err);
            if (i == nobj)
                s.unplaced = out->npaths - before;
            if (stt == AMP_OK && i < nobj)
                stt = amp_pathset_add(out, in->paths[i].role, amp_pathset_path_verts(in, i), in->paths[i].n, err);
        }
        amp_free(c.a, cnt);
        amp_free(c.a, ord);
    }
    s.paths = 0;
    for (i = 0; i < out->npaths; i++)
        s.paths += out->paths[i].role == AMP_ROLE_SUPPORT;
    if (st)
        *st = s;
done:
    amp_free(c.a, c.col);
    amp_free(c.a, c.first);
    amp_free(c.a, nmin);
    amp_free(c.a, nmax);
    amp_free(c.a, first);
    amp_free(c.a, late);
    amp_free(c.a, pcs);
    amp_free(c.a, run);
    amp_fbvh_free(&b);
    amp_fragments_free(&fs);
    amp_pathset_free(&all);
    return stt;
}
