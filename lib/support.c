/* Support structure (paper §5.3): vertical rays find the support volume, a grid fills it, cones order it. */
#include <math.h>
#include <string.h>

#include "order_fragbvh.h"
#include "support_internal.h"

void amp_support_opts_default(amp_support_opts *o)
{
    amp_head_default(&o->head);
    o->spacing = 2.0;
    o->layer_height = 0.4;
    o->radius = 0.2;
    o->min_gap = 1.0;
    o->find_unheld = NULL;
    o->progress = NULL;
    o->progress_user = NULL;
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
    amp_support_layers L; /* L.plate: z of the bed under the job (plate_of) */
} sctx;

double amp_support_layer_z(const amp_support_layers *L, size_t j) { return L->plate + L->first + (double)j * L->step; }

double amp_support_layer_h(const amp_support_layers *L, size_t j) { return j == 0 ? L->h0 : L->h; }

/*
 * Does support layer @p layer print at grid point (ix, iy)? Its bead's middle lies in a column's air above
 * the plate or a lower solid, and under the underside: a tube's centre half a layer under it, a planar
 * bead's top half a layer under it, so that the object bead cut above the underside rests one layer of
 * air above the support (the contact gap slicers leave to break support off).
 */
static int active(const sctx *c, size_t ix, size_t iy, size_t layer)
{
    size_t q, g = iy * c->nx + ix;
    double z = amp_support_layer_z(&c->L, layer), h = amp_support_layer_h(&c->L, layer);
    double mid = z - 0.5 * h;
    for (q = c->first[g]; q < c->first[g + 1]; q++)
        if (mid > c->col[q].z0 && z + 0.5 * c->L.step <= c->col[q].z1)
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
            amp_vec3 org = amp_v3(c->x0 + (double)ix * c->sp, c->y0 + (double)iy * c->sp, fmin(bb.min.z, c->L.plate) - 1.0);
            amp_bvh_hit *hits = NULL;
            size_t n = 0, h;
            double below = c->L.plate; /* top of the last solid stretch, or the plate */
            int inside = 0;
            amp_status s = amp_bvh_ray_all(model, org, amp_v3(0, 0, 1), HUGE_VAL, &hits, &n, err);
            if (s != AMP_OK)
                return s;
            st->rays++;
            for (h = 0; h < n; h++) {
                double z = hits[h].p.z;
                if (hits[h].entering && !inside) {
                    inside = 1;
                    if (z - below >= o->min_gap && z > c->L.plate) {
                        void *p = c->col;
                        if (amp_grow(c->a, &p, &c->capcol, c->ncol + 1, sizeof *c->col) != AMP_OK) {
                            amp_bvh_hits_free(model, hits);
                            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for support columns");
                        }
                        c->col = p;
                        c->col[c->ncol].ix = ix;
                        c->col[c->ncol].iy = iy;
                        c->col[c->ncol].z0 = fmax(below, c->L.plate);
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


/*
 * A run of active rays along one row of a layer. Runs of neighbouring rows
 * whose facing ends are at most one ray apart are printed as one zigzag path,
 * as slicers print support: the connector between them is a support bead like
 * the rows (it is cut into fragments and ordered with them), and one path per
 * region instead of one per row saves a travel, a retraction and a lift per
 * row (issue 14: travel).
 */
typedef struct srun {
    size_t row, i, j; /* rays [i, j) of row `row` */
    size_t next;      /* the run printed after this one in its path, or NORUN */
    int back;         /* printed from j - 1 down to i */
    int linked;       /* has a predecessor */
} srun;
#define NORUN ((size_t)-1)

/* The runs of one layer, row by row, left to right. */
static amp_status layer_runs(const sctx *c, size_t layer, srun **runs, size_t *cap,
                             size_t *n, amp_error *err)
{
    int along_x = layer % 2 == 0;
    size_t nrow = along_x ? c->ny : c->nx, nlen = along_x ? c->nx : c->ny, row, i, j;
    *n = 0;
    for (row = 0; row < nrow; row++)
        for (i = 0; i < nlen; i = j) {
            for (j = i; j < nlen && active(c, along_x ? j : row, along_x ? row : j, layer); j++)
                ;
            if (j == i) {
                j = i + 1;
                continue;
            }
            if (amp_grow(c->a, (void **)runs, cap, *n + 1, sizeof **runs) != AMP_OK)
                return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for support rows");
            (*runs)[*n].row = row;
            (*runs)[*n].i = i;
            (*runs)[*n].j = j;
            (*runs)[*n].next = NORUN;
            (*runs)[*n].back = 0;
            (*runs)[*n].linked = 0;
            (*n)++;
        }
    return AMP_OK;
}

static size_t run_exit(const srun *r) { return r->back ? r->i : r->j - 1; }

static int adjacent(size_t a, size_t b) { return a <= b + 1 && b <= a + 1; }

/*
 * Link each run to a run of the row before that ends a path there with an
 * end next to one of its own: the run enters there and leaves by its other
 * end. A run that starts a path may still turn round to reach its follower.
 */
static int reaches(size_t e, const srun *b) { return adjacent(e, b->i) || adjacent(e, b->j - 1); }

static void link_runs(srun *r, size_t n)
{
    size_t b, a, a0 = 0;
    for (b = 0; b < n; b++) {
        while (a0 < b && r[a0].row + 1 < r[b].row)
            a0++;
        for (a = a0; a < b && r[a].row + 1 == r[b].row; a++) {
            size_t e = run_exit(&r[a]), other = r[a].back ? r[a].j - 1 : r[a].i;
            if (r[a].next != NORUN)
                continue;
            if (!reaches(e, &r[b])) {
                if (r[a].linked || !reaches(other, &r[b]))
                    continue;
                r[a].back = !r[a].back; /* a path's first run: leave by the end that reaches b */
                e = other;
            }
            r[b].back = !adjacent(e, r[b].i);
            r[a].next = b;
            r[b].linked = 1;
            break;
        }
    }
}

/* One path per chain of linked runs; a lone one-ray run is a short row along it, never a point. */
static amp_status emit_runs(const sctx *c, const amp_support_opts *o, size_t layer, const srun *r, size_t n,
                            amp_pathset *sup, amp_error *err)
{
    double z = amp_support_layer_z(&c->L, layer), bh = amp_support_layer_h(&c->L, layer);
    int along_x = layer % 2 == 0;
    size_t h, q, k;
    amp_status s = AMP_OK;
    for (h = 0; s == AMP_OK && h < n; h++) {
        if (r[h].linked)
            continue;
        s = amp_pathset_begin(sup, AMP_ROLE_SUPPORT, err);
        if (s == AMP_OK && bh > 0.0)
            s = amp_pathset_set_height(sup, bh, err);
        if (s == AMP_OK && r[h].next == NORUN && r[h].j == r[h].i + 1) {
            double gx = c->x0 + (double)(along_x ? r[h].i : r[h].row) * c->sp;
            double gy = c->y0 + (double)(along_x ? r[h].row : r[h].i) * c->sp;
            double dx = along_x ? 0.125 * c->sp : 0.0, dy = along_x ? 0.0 : 0.125 * c->sp;
            s = amp_pathset_push(sup, amp_v3(gx - dx, gy - dy, z), o->radius, err);
            if (s == AMP_OK)
                s = amp_pathset_push(sup, amp_v3(gx + dx, gy + dy, z), o->radius, err);
            continue;
        }
        for (q = h; s == AMP_OK && q != NORUN; q = r[q].next)
            for (k = 0; s == AMP_OK && k < r[q].j - r[q].i; k++) {
                size_t t = r[q].back ? r[q].j - 1 - k : r[q].i + k;
                size_t gx = along_x ? t : r[q].row, gy = along_x ? r[q].row : t;
                s = amp_pathset_push(sup, amp_v3(c->x0 + (double)gx * c->sp, c->y0 + (double)gy * c->sp, z),
                                     o->radius, err);
            }
    }
    return s;
}

/* Fill the columns on every layer: rows along x on even layers, along y on odd ones, joined in zigzags. */
static amp_status fill(const sctx *c, const amp_support_opts *o, amp_pathset *sup, amp_error *err)
{
    double ztop = c->L.plate;
    size_t q, layer, n = 0, cap = 0;
    srun *runs = NULL;
    amp_status s = AMP_OK;
    for (q = 0; q < c->ncol; q++)
        ztop = fmax(ztop, c->col[q].z1);
    for (layer = 0; s == AMP_OK && amp_support_layer_z(&c->L, layer) < ztop; layer++) {
        s = layer_runs(c, layer, &runs, &cap, &n, err);
        if (s == AMP_OK) {
            link_runs(runs, n);
            s = emit_runs(c, o, layer, runs, n, sup, err);
        }
    }
    amp_free(c->a, runs);
    return s;
}

/* Layer of support row @p i of @p ps (rows are flat, on z = amp_support_layer_z(layer)). */
static size_t layer_of(const sctx *c, const amp_pathset *ps, size_t i)
{
    double z = (ps->verts[ps->paths[i].first].p.z - amp_support_layer_z(&c->L, 0)) / c->L.step;
    return z > 0.0 ? (size_t)floor(z + 0.5) : 0;
}

/* The support rows of @p all (from path nobj on) again layer by layer, lowest first, each layer in the order
 * made (place_pieces takes the rows of one layer as one range: the pads come after fill's rows). */
static amp_status rows_by_layer(const sctx *c, amp_pathset *all, size_t nobj,
                                amp_error *err)
{
    amp_pathset out;
    size_t i, nl = 0, nr = all->npaths - nobj, *lay = amp_calloc(c->a, nr + 1, sizeof *lay), *at = NULL, *ord = NULL;
    amp_status st = AMP_OK;
    amp_pathset_init(&out, all->alloc);
    if (lay) {
        for (i = 0; i < nr; i++) {
            lay[i] = layer_of(c, all, nobj + i);
            nl = lay[i] + 1 > nl ? lay[i] + 1 : nl;
        }
        at = amp_calloc(c->a, nl + 2, sizeof *at);
        ord = amp_calloc(c->a, nr + 1, sizeof *ord);
    }
    if (!lay || !at || !ord) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for support pads");
        goto done;
    }
    for (i = 0; i < nr; i++) /* counting sort, stable: a layer's rows keep the order they were made in */
        at[lay[i] + 1]++;
    for (i = 0; i < nl; i++)
        at[i + 1] += at[i];
    for (i = 0; i < nr; i++)
        ord[at[lay[i]]++] = nobj + i;
    for (i = 0; i < nobj && st == AMP_OK; i++)
        st = amp_pathset_copy_path(&out, all, i, err);
    for (i = 0; i < nr && st == AMP_OK; i++)
        st = amp_pathset_copy_path(&out, all, ord[i], err);
    if (st == AMP_OK) {
        amp_pathset t = *all;
        *all = out;
        out = t;
    }
done:
    amp_free(c->a, lay);
    amp_free(c->a, at);
    amp_free(c->a, ord);
    amp_pathset_free(&out);
    return st;
}

#define NOPATH 0xffffffffU
/* late[] marker of a support fragment left out */
#define LEFT_OUT (NOPATH - 1)

/*
 * A tree over the object fragments in print order (indices < nf): leaf j holds
 * fragments [j LEAF, (j + 1) LEAF), node i (heap order, root 1, leaves from
 * npow) the box of the object fragments of its index range. The first object
 * fragment above a support fragment is then the first hit of a search that
 * goes left (earlier) first and prunes subtrees whose box no cone can reach;
 * the last one below is its mirror image. Print order is spatially coherent
 * (paths are curves, and the next path starts near the last one), so ranges
 * have small boxes low in the tree.
 */
#define LEAF 4
/* support fragments searched together (consecutive along a row) */
#define BLOCK 16
typedef struct otree {
    amp_box3 *box;
    size_t npow; /* leaves, a power of two */
    uint32_t nf;  /* object fragments: [0, nf) */
} otree;

static int is_object(const amp_fragments *fs, uint32_t g)
{
    return fs->ps->paths[fs->frag[g].path].role == AMP_ROLE_OBJECT;
}

static amp_status otree_build(otree *t, const amp_fragments *fs, uint32_t nf, const amp_allocator *a, amp_error *err)
{
    size_t nleaf = ((size_t)nf + LEAF - 1) / LEAF, i;
    t->nf = nf;
    for (t->npow = 1; t->npow < nleaf; t->npow *= 2)
        ;
    t->box = amp_calloc(a, 2 * t->npow, sizeof *t->box);
    if (!t->box)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for ordering support");
    for (i = 0; i < t->npow; i++) {
        uint32_t g, g1 = (uint32_t)((i + 1) * LEAF < nf ? (i + 1) * LEAF : nf);
        amp_box3 bx = amp_box3_empty();
        for (g = (uint32_t)(i * LEAF); g < g1; g++)
            if (is_object(fs, g))
                bx = amp_box3_union(bx, fs->frag[g].box);
        t->box[t->npow + i] = bx;
    }
    for (i = t->npow; i-- > 1;)
        t->box[i] = amp_box3_union(t->box[2 * i], t->box[2 * i + 1]);
    return AMP_OK;
}

/* May an object fragment in box @p bx be above (want_min) or below (!want_min) a fragment in box @p b? A
 * bound of the cone test of Def. 5.1 (k = cot theta) that only grows when b grows. */
static int may_reach(const amp_box3 *bx, const amp_box3 *b, double zo, double k, int want_min)
{
    double room = want_min ? bx->max.z - b->min.z - zo : b->max.z - bx->min.z - zo;
    /* room - gap <= room (gap >= 0): no room, no square root */
    return room > AMP_CONE_TOL && room - k * amp_box_xy_gap(*bx, *b) > AMP_CONE_TOL;
}

/* Box of the fragments of [f0, f1) still without an answer (out[f] == NOPATH). */
static amp_box3 pending_box(const amp_fragments *fs, uint32_t f0, uint32_t f1, const uint32_t *out)
{
    amp_box3 u = amp_box3_empty();
    uint32_t f;
    for (f = f0; f < f1; f++)
        if (out[f] == NOPATH)
            u = amp_box3_union(u, fs->frag[f].box);
    return u;
}

/*
 * For each support fragment s of [f0, f1) (neighbours along a row: their boxes are close), out[s] = the
 * smallest index (want_min) of an object fragment above s, or the largest (!want_min) of one below it
 * (k = cot theta); NOPATH when none. One depth-first walk for the whole block, in index order (reverse
 * order for the largest), pruned by the box of the fragments still open: every subtree a single
 * fragment's walk would enter is entered, and a fragment's first hit is its answer, so each answer is
 * the one of a walk per fragment, at a fraction of the node visits.
 */
static void search_block(const otree *t, const amp_fragments *fs, double zo, double k, uint32_t f0, uint32_t f1,
                         int want_min, uint32_t *out)
{
    size_t stack[64], top = 0, open = f1 - f0;
    amp_box3 u;
    uint32_t f;
    for (f = f0; f < f1; f++)
        out[f] = NOPATH;
    u = pending_box(fs, f0, f1, out);
    stack[top++] = 1;
    while (top && open) {
        size_t id = stack[--top];
        const amp_box3 *bx = &t->box[id];
        if (bx->min.x > bx->max.x || !may_reach(bx, &u, zo, k, want_min))
            continue;
        if (id >= t->npow) {
            size_t j = id - t->npow, q, found = 0;
            uint32_t g0 = (uint32_t)(j * LEAF), g1 = (uint32_t)((j + 1) * LEAF < t->nf ? (j + 1) * LEAF : t->nf);
            for (f = f0; f < f1; f++) {
                if (out[f] != NOPATH || !may_reach(bx, &fs->frag[f].box, zo, k, want_min))
                    continue;
                for (q = 0; q < (size_t)(g1 - g0); q++) {
                    uint32_t g = want_min ? g0 + (uint32_t)q : g1 - 1 - (uint32_t)q;
                    if (is_object(fs, g) && (want_min ? amp_fragment_below_k(fs, zo, k, f, g)
                                                      : amp_fragment_below_k(fs, zo, k, g, f))) {
                        out[f] = g;
                        found++;
                        break;
                    }
                }
            }
            if (found) {
                open -= found;
                u = pending_box(fs, f0, f1, out);
            }
        } else {
            stack[top++] = want_min ? 2 * id + 1 : 2 * id;
            stack[top++] = want_min ? 2 * id : 2 * id + 1;
        }
    }
}

/* Support fragment f has no gouge-free slot: mark it left out and count it (Lemma 5.1 makes this not happen
 * for fragments shorter than z_offs sin(theta); kept as a guard against rounding, and reported). */
static void leave_out(const amp_fragments *fs, uint32_t *late, size_t f, amp_support_stats *s)
{
    late[f] = LEFT_OUT;
    s->conflicts++;
    s->trimmed += amp_v3_dist(fs->frag[f].p0, fs->frag[f].p1);
}

/*
 * A piece of a support row: fragments [f0, f1) printed together just before
 * object fragment pos (an index into the object fragments, which are in print
 * order; nobj_frag = after the last object path). hi is the last object
 * fragment below the piece (NOPATH: none): pos must stay > hi.
 */
typedef struct piece {
    size_t f0, f1;
    uint32_t pos, hi;
} piece;

/*
 * The insertion point for a piece that may go anywhere in (hi, want]: the
 * start of want's object path when that is still after hi (no object path is
 * split), else want itself (the path is split there). want <= hi (a support
 * piece above moved it too early) is raised to hi + 1.
 */
static uint32_t slot(const amp_fragments *fs, uint32_t nobj_frag, uint32_t hi, uint32_t want)
{
    uint32_t st;
    if (hi != NOPATH && want <= hi)
        want = hi + 1;
    if (want >= nobj_frag)
        return nobj_frag;
    st = (uint32_t)fs->first[fs->frag[want].path];
    return hi == NOPATH || st > hi ? st : want;
}

/*
 * Append fragments [a, b) as paths of @p role, one per run of kept fragments
 * (late[f] != LEFT_OUT; late may be NULL). Fragment cut points inside a
 * segment are collinear and only written where a run starts or ends. Runs of
 * zero length are not written when @p skip_empty.
 */
static amp_status emit_frags(amp_pathset *out, const amp_fragments *fs, amp_role role, double h, size_t a, size_t b,
                             const uint32_t *late, int skip_empty, amp_pvert **run, size_t *cap, amp_error *err)
{
    const amp_pathset *ps = fs->ps;
    size_t f = a;
    amp_status st = AMP_OK;
    while (st == AMP_OK && f < b) {
        size_t n = 0, g;
        double len = 0.0;
        for (; f < b && late && late[f] == LEFT_OUT; f++)
            ;
        for (g = f; g < b && !(late && late[g] == LEFT_OUT); g++) {
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
            len += amp_v3_dist(fr->p0, fr->p1);
            if (g + 1 == b || (late && late[g + 1] == LEFT_OUT)) {
                (*run)[n].p = fr->p1;
                (*run)[n++].r = fr->r1;
            }
        }
        f = g;
        if (n >= 2 && !(skip_empty && !(len > 0.0))) {
            st = amp_pathset_add(out, role, *run, n, err);
            if (st == AMP_OK && h > 0.0)
                st = amp_pathset_set_height(out, h, err);
        }
    }
    return st;
}

/* Cells per support grid spacing in the field of order_pieces (finer cells: less over-approximation). */
#define SUB 4

/*
 * Running minimum over a window of 2k + 1 cells along @p lines lines of @p n cells (stride @p step), cells
 * outside the line counting as NOPATH. Van Herk / Gil-Werman: minima from each block start forwards (g) and
 * from each block end backwards (e), blocks of the window's length, so that every window is one block end
 * part plus one block start part: three comparisons a cell whatever k. Scratch g, e: n + 2k cells each.
 */
static void min_pass(const uint32_t *src, uint32_t *dst, size_t n, size_t step, size_t lines, size_t line_step,
                     size_t k, uint32_t *g, uint32_t *e)
{
    size_t l, i, w = 2 * k + 1, m = n + 2 * k;
    for (l = 0; l < lines; l++) {
        const uint32_t *sl = src + l * line_step;
        for (i = 0; i < m; i++) {
            uint32_t v = i < k || i >= n + k ? NOPATH : sl[(i - k) * step];
            g[i] = i % w == 0 || v < g[i - 1] ? v : g[i - 1];
        }
        for (i = m; i-- > 0;) {
            uint32_t v = i < k || i >= n + k ? NOPATH : sl[(i - k) * step];
            e[i] = i % w == w - 1 || i == m - 1 || v < e[i + 1] ? v : e[i + 1];
        }
        for (i = 0; i < n; i++)
            dst[l * line_step + i * step] = e[i] < g[i + 2 * k] ? e[i] : g[i + 2 * k];
    }
}

/* Chebyshev dilation of a min-field by k cells: rows, then columns, via scratch tmp (and g, e of min_pass). */
static void dilate_min(uint32_t *d, uint32_t *tmp, size_t nx, size_t ny, size_t k, uint32_t *g, uint32_t *e)
{
    min_pass(d, tmp, nx, 1, ny, nx, k, g, e);
    min_pass(tmp, d, ny, nx, nx, 1, k, g, e);
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

/* Smallest slot in the field over the cells of fragment f (its xy box). */
static uint32_t field_min(const sctx *c, const amp_fragments *fs, const uint32_t *d, size_t nx, size_t ny, size_t f)
{
    size_t x0, x1, y0, y1, x, y;
    uint32_t m = NOPATH;
    cell_range(c, &fs->frag[f].box, 0, nx, ny, &x0, &x1, &y0, &y1);
    for (y = y0; y <= y1; y++)
        for (x = x0; x <= x1; x++)
            m = d[y * nx + x] < m ? d[y * nx + x] : m;
    return m;
}

/* Add pieces [p0, p1) of a layer dz above the current one to the field (disc of the cone at that height). */
static void field_add(const sctx *c, const amp_support_opts *o, const amp_fragments *fs, const piece *pcs, size_t p0,
                      size_t p1, double dz, uint32_t *d, size_t nx, size_t ny)
{
    double cs = c->sp / SUB, cot = 1.0 / tan(o->head.theta);
    size_t r = (size_t)ceil((dz - o->head.z_offs) / cot / cs) + 1, k, f, x0, x1, y0, y1, x, y;
    for (k = p0; k < p1; k++)
        for (f = pcs[k].f0; f < pcs[k].f1; f++) {
            cell_range(c, &fs->frag[f].box, r, nx, ny, &x0, &x1, &y0, &y1);
            for (y = y0; y <= y1; y++)
                for (x = x0; x <= x1; x++)
                    d[y * nx + x] = pcs[k].pos < d[y * nx + x] ? pcs[k].pos : d[y * nx + x];
        }
}

/*
 * Cut support row i into as few pieces as possible such that every piece has
 * a slot: after the last object fragment below any of its fragments (late)
 * and no later than the first object fragment or support piece above any of
 * them (first, and the field d of pieces above). Fragments are shorter than
 * z_offs sin(theta), so a single fragment s always has a slot: if object point
 * a is below s and s below point b (object or support), the two cone
 * inequalities add up (|s| < z_offs sin(theta) bounds the move inside s) to a
 * below b, so b is placed after a (§5.1 Def. 5.1). Square cells over-
 * approximate the cones: a bound below late[f] can only come from them and is
 * raised to late[f] + 1.
 */
static amp_status cut_row(const sctx *c, const amp_fragments *fs, size_t i, uint32_t nf, const uint32_t *first,
                          uint32_t *late, const uint32_t *d, size_t nx, size_t ny, piece **pcs, size_t *npc,
                          size_t *pcap, amp_support_stats *s, amp_error *err)
{
    size_t f = fs->first[i];
    while (f < fs->first[i + 1]) {
        piece pc;
        uint32_t lo = NOPATH, hi = NOPATH;
        pc.f0 = f;
        for (; f < fs->first[i + 1]; f++) {
            uint32_t ub = field_min(c, fs, d, nx, ny, f), nlo, nhi = hi;
            ub = first[f] < ub ? first[f] : ub;
            if (late[f] != NOPATH) {
                if (first[f] != NOPATH && first[f] <= late[f]) { /* no slot even alone (rounding only) */
                    if (f > pc.f0)
                        break;
                    leave_out(fs, late, f, s);
                    pc.f0 = f + 1;
                    continue;
                }
                ub = ub <= late[f] ? late[f] + 1 : ub;
                nhi = hi == NOPATH || late[f] > hi ? late[f] : hi;
            }
            nlo = ub < lo ? ub : lo;
            if (nhi != NOPATH && nlo <= nhi)
                break;
            lo = nlo;
            hi = nhi;
        }
        if (f == pc.f0)
            continue;
        pc.f1 = f;
        pc.hi = hi;
        pc.pos = slot(fs, nf, hi, lo == NOPATH ? nf : lo);
        if (amp_grow(c->a, (void **)pcs, pcap, *npc + 1, sizeof **pcs) != AMP_OK)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for ordering support");
        (*pcs)[(*npc)++] = pc;
    }
    return AMP_OK;
}

/*
 * Place the support rows, top layer first. A lower support piece L must be
 * printed no later than any piece H above it (Def. 5.1): a field over a fine
 * xy grid holds, per cell, the smallest slot of the pieces above that cell's
 * points at the current height: H enters once its layer is more than z_offs
 * higher (disc of radius (dz - z_offs) / cot(theta), grown by one cell), and
 * every layer down the discs grow by layer_height / cot(theta). Square cells
 * and square dilation over-approximate the cone (moves pieces earlier, never
 * later). The pieces come out bottom layer first.
 */
static amp_status place_pieces(const sctx *c, const amp_support_opts *o, const amp_fragments *fs, size_t nobj,
                               const uint32_t *first, uint32_t *late, piece **pcs, size_t *npc, amp_support_stats *s,
                               amp_error *err)
{
    double cs = c->sp / SUB, h = c->L.step, cot = 1.0 / tan(o->head.theta);
    size_t nx = c->nx * SUB + 1, ny = c->ny * SUB + 1, i, nl = 0, pcap = 0;
    size_t step = (size_t)ceil(h / cot / cs), lag = (size_t)floor(o->head.z_offs / h) + 1;
    size_t *rfirst, *pfirst;
    uint32_t *d, *tmp, *ge, nf = (uint32_t)fs->first[nobj];
    amp_status st = AMP_OK;
    long l;
    for (i = nobj; i < fs->npaths; i++)
        nl = layer_of(c, fs->ps, i) + 1 > nl ? layer_of(c, fs->ps, i) + 1 : nl;
    if (nl == 0)
        return AMP_OK;
    d = amp_calloc(c->a, nx * ny, sizeof *d);
    tmp = amp_calloc(c->a, nx * ny, sizeof *tmp);
    ge = amp_calloc(c->a, 2 * (nx + ny + 2 * step), sizeof *ge);
    rfirst = amp_calloc(c->a, nl + 2, sizeof *rfirst);
    pfirst = amp_calloc(c->a, 2 * nl + 2, sizeof *pfirst);
    if (!d || !tmp || !ge || !rfirst || !pfirst) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory ordering support pieces");
        goto done;
    }
    /* fill() makes the rows layer by layer: rows of layer l are nobj + [rfirst[l], rfirst[l + 1]) */
    for (i = nobj; i < fs->npaths; i++)
        rfirst[layer_of(c, fs->ps, i) + 1]++;
    for (i = 0; i <= nl; i++)
        rfirst[i + 1] += rfirst[i];
    for (i = 0; i < nx * ny; i++)
        d[i] = NOPATH;
    for (l = (long)nl - 1; st == AMP_OK && l >= 0; l--) {
        size_t m = (size_t)l + lag;
        if ((size_t)l + 1 < nl)
            dilate_min(d, tmp, nx, ny, step, ge, ge + nx + ny + 2 * step);
        if (m < nl) /* layer m is now more than z_offs above layer l; its pieces are [pfirst[2m], pfirst[2m+1]) */
            field_add(c, o, fs, *pcs, pfirst[2 * m], pfirst[2 * m + 1], (double)(m - (size_t)l) * h, d, nx, ny);
        pfirst[2 * (size_t)l] = *npc;
        for (i = nobj + rfirst[l]; st == AMP_OK && i < nobj + rfirst[l + 1]; i++)
            st = cut_row(c, fs, i, nf, first, late, d, nx, ny, pcs, npc, &pcap, s, err);
        pfirst[2 * (size_t)l + 1] = *npc;
        if (o->progress && l % 8 == 0)
            o->progress(o->progress_user, 0.6 + 0.35 * (double)(nl - (size_t)l) / (double)nl);
    }
    /* bottom layer first: a piece is emitted before the pieces above it in the same slot */
    for (i = 0; st == AMP_OK && i < *npc / 2; i++) {
        piece t = (*pcs)[i];
        (*pcs)[i] = (*pcs)[*npc - 1 - i];
        (*pcs)[*npc - 1 - i] = t;
    }
done:
    amp_free(c->a, d);
    amp_free(c->a, tmp);
    amp_free(c->a, ge);
    amp_free(c->a, rfirst);
    amp_free(c->a, pfirst);
    return st;
}

/* Reverse the vertices of paths [p0, out->npaths): a support row prints the same either way. */
static void reverse_paths(amp_pathset *out, size_t p0)
{
    size_t i;
    for (i = p0; i < out->npaths; i++) {
        amp_pvert *v = amp_pathset_path_verts(out, i);
        size_t a = 0, b = out->paths[i].n;
        while (b > a + 1) {
            amp_pvert t = v[a];
            v[a++] = v[--b];
            v[b] = t;
        }
    }
}

/* Is the nearer end (s, or e: *rev) of a piece closer to @p cur than *bd? Then *bd is its squared distance. */
static int nearer(amp_vec3 cur, amp_vec3 s, amp_vec3 e, double *bd, int *rev)
{
    double ds = amp_v3_dist2(cur, s), de = amp_v3_dist2(cur, e);
    if (!(ds < *bd || de < *bd))
        return 0;
    *rev = de < ds;
    *bd = fmin(ds, de);
    return 1;
}

/*
 * The pieces ord[k0, k1) of one slot, layer by layer (lowest first, as made);
 * within a layer (one height: no piece is below another) the nearest piece
 * next, from either end, so that the nozzle travels little between them.
 */
static amp_status emit_slot(amp_pathset *out, const amp_fragments *fs, const uint32_t *late, const piece *pcs,
                            const size_t *ord, size_t k0, size_t k1, unsigned char *used, amp_pvert **run, size_t *cap,
                            amp_error *err)
{
    amp_status st = AMP_OK;
    size_t g0 = k0;
    while (st == AMP_OK && g0 < k1) {
        double z = fs->frag[pcs[ord[g0]].f0].p0.z;
        size_t g1 = g0, left, k;
        while (g1 < k1 && fabs(fs->frag[pcs[ord[g1]].f0].p0.z - z) < 1e-9)
            used[g1++ - k0] = 0;
        for (left = g1 - g0; st == AMP_OK && left > 0; left--) {
            amp_vec3 cur = out->nverts ? out->verts[out->nverts - 1].p : fs->frag[pcs[ord[g0]].f0].p0;
            size_t best = g0, p0 = out->npaths;
            double bd = HUGE_VAL;
            int rev = 0;
            for (k = g0; k < g1; k++) {
                const piece *pc = &pcs[ord[k]];
                if (!used[k - k0] && nearer(cur, fs->frag[pc->f0].p0, fs->frag[pc->f1 - 1].p1, &bd, &rev))
                    best = k;
            }
            used[best - k0] = 1;
            st = emit_frags(out, fs, AMP_ROLE_SUPPORT, fs->ps->paths[fs->frag[pcs[ord[best]].f0].path].h, pcs[ord[best]].f0, pcs[ord[best]].f1, late, 1, run, cap,
                            err);
            if (st == AMP_OK && rev)
                reverse_paths(out, p0);
        }
        g0 = g1;
    }
    return st;
}

/*
 * Emit in print order: object path k, with the pieces placed before each of its
 * fragments; a piece placed inside path k splits it there. Pieces placed after
 * the last object fragment (nothing above them) come last. In one slot the
 * pieces keep the order they were made (layer by layer, lowest first).
 */
static amp_status emit_all(const amp_pathset *in, size_t nobj, const amp_fragments *fs, const uint32_t *late,
                           const piece *pcs, size_t npc, amp_pathset *out, amp_support_stats *s, amp_error *err)
{
    const amp_allocator *a = out->alloc;
    size_t nf = fs->first[nobj], i, g, k = 0, run_cap = 0;
    size_t *cnt = amp_calloc(a, nf + 2, sizeof *cnt), *ord = amp_calloc(a, npc + 1, sizeof *ord);
    unsigned char *used = amp_calloc(a, npc + 1, 1);
    amp_pvert *run = NULL;
    amp_status st = AMP_OK;
    if (!cnt || !ord || !used) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for ordering support");
        goto done;
    }
    for (i = 0; i < npc; i++)
        cnt[(pcs[i].pos >= nf ? nf : pcs[i].pos) + 1]++;
    for (i = 0; i <= nf; i++)
        cnt[i + 1] += cnt[i];
    for (i = 0; i < npc; i++)
        ord[cnt[pcs[i].pos >= nf ? nf : pcs[i].pos]++] = i;
    /* now cnt[g] = end of the pieces of slot g in ord */
    for (i = 0; st == AMP_OK && i < nobj; i++) {
        size_t f0 = fs->first[i], f1 = fs->first[i + 1], cut = f0;
        for (g = f0; st == AMP_OK && g < f1; g++) {
            if (k == cnt[g])
                continue;
            if (g > cut) {
                st = emit_frags(out, fs, in->paths[i].role, in->paths[i].h, cut, g, NULL, 1, &run, &run_cap, err);
                s->splits++;
                cut = g;
            }
            st = emit_slot(out, fs, late, pcs, ord, k, cnt[g], used, &run, &run_cap, err);
            k = cnt[g];
        }
        if (st == AMP_OK && cut == f0) {
            st = amp_pathset_copy_path(out, in, i, err);
        } else if (st == AMP_OK) {
            st = emit_frags(out, fs, in->paths[i].role, in->paths[i].h, cut, f1, NULL, 1, &run, &run_cap, err);
        }
    }
    i = out->npaths;
    if (st == AMP_OK)
        st = emit_slot(out, fs, late, pcs, ord, k, cnt[nf], used, &run, &run_cap, err);
    s->unplaced = out->npaths - i;
done:
    amp_free(a, cnt);
    amp_free(a, ord);
    amp_free(a, used);
    amp_free(a, run);
    return st;
}

/*
 * The bed under the job. `gcode` rests the lowest bead on the bed, so the
 * support's first rows must start where the object's lowest bead bottom (a
 * tube's z - r, a planar bead's z - h) will lie, or one of them is laid in
 * the air: an object resting on the plate z = 0 (docs/interfaces.md §2) has
 * its lowest beads within min_gap of it — below it (the helix's lowest
 * curves lie on z = 0 with their radius below), or above it (a field's
 * lowest curves, half a spacing up with their radius: 0.49 mm on the twisted
 * bridge at 2 mm) — and the plate is that bottom. An object whose beads all
 * float min_gap or more above z = 0 is supported from z = 0.
 */
static double plate_of(const amp_pathset *in, double min_gap)
{
    double z = HUGE_VAL, zc = HUGE_VAL; /* bead bottoms; centre lines (when nothing extrudes) */
    size_t i, k;
    for (i = 0; i < in->npaths; i++) {
        const amp_path *p = &in->paths[i];
        if (p->role != AMP_ROLE_OBJECT)
            continue;
        for (k = 0; k < p->n; k++) {
            const amp_pvert *v = &in->verts[p->first + k];
            zc = fmin(zc, v->p.z);
            if (v->r > 0.0)
                z = fmin(z, v->p.z - (p->h > 0.0 ? p->h : v->r));
        }
    }
    z = z < HUGE_VAL ? z : zc;
    return z < min_gap ? z : 0.0;
}

/*
 * A sliced job (paper 2's layers, `slice --continuous`): every object path a planar bead (h > 0) on one
 * height, the heights never going down along the print order, and the job resting on @p plate. Its support
 * is laid on the same layers, as planar beads of the same heights (L), and printed layer by layer with it
 * (emit_by_layer) instead of in the cone slots of Def. 5.1. Returns 0 for any other job (tubes).
 */
static int sliced_layers(const amp_pathset *in, double plate, amp_support_layers *L)
{
    double zlast = -HUGE_VAL, z0 = HUGE_VAL, h0 = 0.0, h = 0.0;
    size_t i, k;
    for (i = 0; i < in->npaths; i++) {
        const amp_path *p = &in->paths[i];
        const amp_pvert *v = &in->verts[p->first];
        if (p->role != AMP_ROLE_OBJECT || p->n == 0)
            continue;
        if (!(p->h > 0.0) || v[0].p.z < zlast - 1e-9)
            return 0;
        for (k = 1; k < p->n; k++)
            if (fabs(v[k].p.z - v[0].p.z) > 1e-9)
                return 0;
        if (v[0].p.z < z0 - 1e-9) {
            z0 = v[0].p.z;
            h0 = p->h;
        } else if (v[0].p.z > z0 + 1e-9 && h == 0.0) {
            h = p->h; /* the layers above the first */
        }
        zlast = v[0].p.z;
    }
    if (!(z0 < HUGE_VAL) || fabs(z0 - h0 - plate) > 1e-6)
        return 0;
    L->plate = plate;
    L->first = h0;
    L->h0 = h0;
    L->h = L->step = h > 0.0 ? h : h0;
    return 1;
}

/* Height of path @p i's first vertex. */
static double path_z(const amp_pathset *ps, size_t i) { return ps->verts[ps->paths[i].first].p.z; }

/*
 * Emit a sliced job: the object paths in their order, and before the first object path of each height the
 * support paths of the layers up to it (all's paths [nobj, npaths), lowest layer first), nearest next from
 * either end. The support of a layer is printed before the object beads of that layer, which lie beside it
 * (never above: a row ends a layer under the underside), so no cone check is needed.
 */
static amp_status emit_by_layer(const amp_pathset *all, size_t nobj, amp_pathset *out, amp_support_stats *s,
                                amp_error *err)
{
    size_t i, k = nobj, n = all->npaths, m, best;
    unsigned char *used = amp_calloc(out->alloc, n - nobj + 1, 1);
    amp_status st = AMP_OK;
    if (!used)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for ordering support");
    for (i = 0; i <= nobj && st == AMP_OK; i++) {
        double z = i == nobj ? HUGE_VAL : all->paths[i].role == AMP_ROLE_OBJECT && all->paths[i].n ? path_z(all, i)
                                                                                                  : -HUGE_VAL;
        size_t k1 = k;
        while (k1 < n && path_z(all, k1) <= z + 1e-9)
            k1++;
        for (m = k; st == AMP_OK && m < k1; m++) { /* k1 - k paths, each the nearest of the lowest layer left */
            amp_vec3 cur = out->nverts ? out->verts[out->nverts - 1].p : all->verts[all->paths[k].first].p;
            double bd = HUGE_VAL, zl = HUGE_VAL;
            size_t q, p0 = out->npaths;
            int rev = 0;
            for (q = k; q < k1; q++)
                zl = used[q - nobj] ? zl : fmin(zl, path_z(all, q));
            for (best = q = k; q < k1; q++) {
                const amp_pvert *v = amp_pathset_path_verts(all, q);
                if (!used[q - nobj] && path_z(all, q) <= zl + 1e-9 &&
                    nearer(cur, v[0].p, v[all->paths[q].n - 1].p, &bd, &rev))
                    best = q;
            }
            used[best - nobj] = 1;
            st = amp_pathset_copy_path(out, all, best, err);
            if (st == AMP_OK && rev)
                reverse_paths(out, p0);
        }
        if (i == nobj)
            s->unplaced = k1 - k;
        else if (st == AMP_OK)
            st = amp_pathset_copy_path(out, all, i, err);
        k = k1;
    }
    amp_free(out->alloc, used);
    return st;
}

/*
 * §5.3 ordering of @p all (the object paths [0, nobj), settled, then the support made) into @p out: the
 * support below an object fragment is printed before it. Fragments shorter than z_offs sin(theta) make every
 * support fragment's slot non-empty (make_pieces).
 */
static amp_status order_by_cones(const sctx *c, const amp_support_opts *o, const amp_pathset *all, size_t nobj,
                                 amp_pathset *out, amp_support_stats *s, amp_error *err)
{
    amp_fragments fs;
    otree t;
    uint32_t *first = NULL, *late = NULL;
    piece *pcs = NULL;
    size_t npc = 0;
    amp_status stt;
    memset(&t, 0, sizeof t);
    memset(&fs, 0, sizeof fs);
    if ((stt = amp_fragments_build(&fs, all, 0.95 * o->head.z_offs * sin(o->head.theta), c->a, err)) != AMP_OK ||
        (stt = otree_build(&t, &fs, (uint32_t)fs.first[nobj], c->a, err)) != AMP_OK)
        goto done;
    if (fs.n >= LEFT_OUT) {
        stt = amp_fail(err, AMP_ERR_LIMIT, 0, "too many fragments for support");
        goto done;
    }
    first = amp_calloc(c->a, fs.n + 1, sizeof *first);
    late = amp_calloc(c->a, fs.n + 1, sizeof *late);
    if (!first || !late) {
        stt = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for ordering support");
        goto done;
    }
    /* per support fragment: the first object fragment above it (it must come before) and the last one below
     * it (it must come after) */
    {
        long f0 = (long)fs.first[nobj], nb = ((long)fs.n - f0 + BLOCK - 1) / BLOCK, q;
        double k = 1.0 / tan(o->head.theta);
#pragma omp parallel for schedule(dynamic, 4)
        for (q = 0; q < nb; q++) {
            uint32_t b0 = (uint32_t)(f0 + q * BLOCK), b1 = (uint32_t)(f0 + q * BLOCK + BLOCK < (long)fs.n ? f0 + q * BLOCK + BLOCK : (long)fs.n);
            search_block(&t, &fs, o->head.z_offs, k, b0, b1, 1, first);
            search_block(&t, &fs, o->head.z_offs, k, b0, b1, 0, late);
        }
    }
    /* object before support above it, support before object and support above it (Def. 5.1) */
    if (o->progress)
        o->progress(o->progress_user, 0.6);
    if ((stt = place_pieces(c, o, &fs, nobj, first, late, &pcs, &npc, s, err)) == AMP_OK)
        stt = emit_all(all, nobj, &fs, late, pcs, npc, out, s, err);
done:
    amp_free(c->a, t.box);
    amp_free(c->a, first);
    amp_free(c->a, late);
    amp_free(c->a, pcs);
    amp_fragments_free(&fs);
    return stt;
}

amp_status amp_support(const amp_pathset *in, const amp_bvh *model, const amp_support_opts *o, amp_pathset *out,
                       amp_support_stats *st, amp_error *err)
{
    sctx c;
    amp_support_stats s;
    amp_pathset all;
    amp_unheld_runs runs;
    size_t i, nobj;
    int sliced;
    amp_status stt;
    memset(&c, 0, sizeof c);
    memset(&s, 0, sizeof s);
    memset(&runs, 0, sizeof runs);
    if (!in || !model || !o || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_support: NULL argument");
    if ((stt = amp_head_validate(&o->head, err)) != AMP_OK)
        return stt;
    if (!(o->spacing > 0.0) || !(o->layer_height > 0.0) || !(o->radius >= 0.0) || !(o->min_gap >= 0.0) ||
        !isfinite(o->spacing + o->layer_height + o->radius + o->min_gap))
        return amp_fail(err, AMP_ERR_RANGE, 0, "support spacing and layer height must be positive, radius and gap >= 0");
    if (in->npaths >= NOPATH)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "too many paths");
    /* support exists for object paths; with none, the slots between them are undefined */
    for (i = 0; i < in->npaths && in->paths[i].role != AMP_ROLE_OBJECT; i++)
        ;
    if (i == in->npaths)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_support: no object path to support");
    c.a = out->alloc;
    c.L.plate = plate_of(in, o->min_gap);
    sliced = sliced_layers(in, c.L.plate, &c.L);
    if (!sliced) {
        c.L.first = o->radius;
        c.L.step = o->layer_height;
        c.L.h0 = c.L.h = 0.0;
    }
    amp_pathset_init(&all, out->alloc);
    if ((stt = cast_rays(&c, model, o, &s, err)) != AMP_OK)
        goto done;
    nobj = in->npaths;
    if ((stt = amp_pathset_append(&all, in, err)) != AMP_OK || (stt = fill(&c, o, &all, err)) != AMP_OK)
        goto done;
    for (i = nobj; i < all.npaths; i++)
        s.length += amp_path_length(&all, i);
    if (!sliced && (stt = amp_support_settle(&all, nobj, o, &s.settled, &runs, err)) != AMP_OK)
        goto done;
    if (o->find_unheld) {
        amp_support_pads_stats ps;
        if ((stt = amp_support_pads(&all, nobj, model, o, &c.L, &runs, &ps, err)) != AMP_OK)
            goto done;
        s.pads = ps.paths;
        s.pad_length = ps.length;
        if (ps.paths && (stt = rows_by_layer(&c, &all, nobj, err)) != AMP_OK)
            goto done;
    }
    if (o->progress)
        o->progress(o->progress_user, 0.1);
    stt = sliced ? emit_by_layer(&all, nobj, out, &s, err) : order_by_cones(&c, o, &all, nobj, out, &s, err);
    if (stt != AMP_OK)
        goto done;
    s.paths = 0;
    for (i = 0; i < out->npaths; i++)
        s.paths += out->paths[i].role == AMP_ROLE_SUPPORT;
    s.sliced = sliced;
    s.layer_height = c.L.step;
    if (st)
        *st = s;
done:
    amp_free(c.a, c.col);
    amp_free(c.a, c.first);
    amp_unheld_runs_free(&runs);
    amp_pathset_free(&all);
    return stt;
}
