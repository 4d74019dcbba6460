/*
 * Settling (beyond [P1 §5.1]): no object bead printed before the object bead it rests on.
 *
 * Algorithm 2 orders by the head cone alone: fragment A must come before B when B reaches into the cone of
 * the head printing A, z_offs over its tip (Def. 5.1). Two beads stacked less than z_offs apart are in no
 * such relation, so either may come first. When the upper one does, it is laid in the air, and no support
 * pad fits under it since the lower bead will fill that room: a field's curves inserted at half a spacing
 * near the surface are exactly z_offs apart at 1 mm (camel, man, cheese and hand of CGAL's meshes). The
 * judge of the pads (amp_support_opts.find_unheld) names the beads in the air; for each, the earliest
 * object path printed later that lies under it (the judge's rule: a 45 degree cone, gap at most min_gap) is
 * moved just before it, or else the upper path just after it, whichever Def. 5.1 allows for every path
 * passed over. Rounds repeat while the judge finds fewer samples in the air.
 */
#include <math.h>
#include <string.h>

#include "order_cone.h"
#include "support_internal.h"

#define NONE ((uint32_t)0xffffffffu)
/* rounds of moves, each judged as a whole */
#define SETTLE_ROUNDS 8

/* An upper object path in the air and the later object path under it. */
typedef struct rest {
    uint32_t upper, lower;
} rest;

typedef struct settler {
    const amp_pathset *all;
    size_t nobj, nrows;
    const amp_support_opts *o;
    double zo, k;
    amp_fragments fs; /* built with pbox at the first rest to settle (most jobs have none) */
    amp_box3 *pbox;
    amp_bead_tops tops; /* built at the first sample in the air */
    int have_tops;
    uint32_t *perm, *pos, *saved; /* perm: position -> path; pos: path -> position */
    rest *rs;
    size_t nrs, caprs, unheld;
    amp_unheld_runs *runs;
    amp_error *err;
} settler;

void amp_unheld_runs_free(amp_unheld_runs *r)
{
    if (!r)
        return;
    amp_free(r->a, r->sm);
    amp_free(r->a, r->end);
    memset(r, 0, sizeof *r);
}

/* Keep a run as the judge handed it, for the pads. */
static amp_status keep_run(settler *s, const amp_bead_sample *run, size_t n)
{
    amp_unheld_runs *r = s->runs;
    void *m = r->sm, *e = r->end;
    if (amp_grow(r->a, &m, &r->cap, r->n + n, sizeof *r->sm) != AMP_OK)
        return amp_fail(s->err, AMP_ERR_NOMEM, 0, "out of memory for the samples in the air");
    r->sm = m;
    if (amp_grow(r->a, &e, &r->capruns, r->nruns + 1, sizeof *r->end) != AMP_OK)
        return amp_fail(s->err, AMP_ERR_NOMEM, 0, "out of memory for the samples in the air");
    r->end = e;
    memcpy(r->sm + r->n, run, n * sizeof *run);
    r->n += n;
    r->end[r->nruns++] = r->n;
    return AMP_OK;
}

/* Def. 5.1 on whole paths: does path x hold a fragment below one of path y (x must come before y)? */
static int path_below(const settler *s, uint32_t x, uint32_t y)
{
    const amp_box3 *bx = &s->pbox[x], *by = &s->pbox[y];
    size_t f, g;
    if (x == y || by->max.z - bx->min.z - s->zo - s->k * amp_box_xy_gap(*bx, *by) <= AMP_CONE_TOL)
        return 0;
    for (f = s->fs.first[x]; f < s->fs.first[x + 1]; f++)
        for (g = s->fs.first[y]; g < s->fs.first[y + 1]; g++)
            if (amp_fragment_below_k(&s->fs, s->zo, s->k, f, g))
                return 1;
    return 0;
}

/* The object path printed after path p, earliest, with a bead under sample q (the judge's 45 degree rule,
 * gap at most min_gap); NONE if none. */
static uint32_t later_holder(const settler *s, uint32_t p, const amp_bead_sample *q)
{
    const amp_bead_tops *t = &s->tops;
    double bottom = q->p.z - q->half;
    uint32_t best = NONE;
    size_t x0, y0, x1, y1, x, y, i;
    /* a holder's top reaches at least bottom - min_gap, so its centre is at most half + min_gap + reach
     * lower, and as far sideways */
    amp_bead_tops_near(t, q->p.x, q->p.y, q->half + s->o->min_gap + t->reach, &x0, &y0, &x1, &y1);
    for (y = y0; y <= y1; y++)
        for (x = x0; x <= x1; x++)
            for (i = t->cell[y * t->nx + x]; i < t->cell[y * t->nx + x + 1]; i++) {
                const amp_bead_top *b = &t->tp[i];
                double dz = q->p.z - b->z;
                if (s->pos[b->path] > s->pos[p] && (best == NONE || s->pos[b->path] < s->pos[best]) &&
                    dz > 1e-9 && bottom - b->top <= s->o->min_gap + 1e-9 && hypot(b->x - q->p.x, b->y - q->p.y) <= dz)
                    best = b->path;
            }
    return best;
}

/* amp_bead_run_fn: count the object samples in the air and note, once per upper path, the path under them. */
static amp_status note_run(void *user, const amp_bead_sample *run, size_t n, amp_error *err)
{
    settler *s = user;
    size_t i;
    amp_status st = keep_run(s, run, n);
    if (st == AMP_OK && !s->have_tops) {
        s->have_tops = 1;
        st = amp_bead_tops_build(&s->tops, s->all, s->nobj, err);
    }
    for (i = 0; i < n && st == AMP_OK; i++) {
        uint32_t p, h;
        if (run[i].path < s->nrows)
            continue;
        s->unheld++;
        p = s->perm[run[i].path - s->nrows];
        if (s->nrs && s->rs[s->nrs - 1].upper == p)
            continue;
        if ((h = later_holder(s, p, &run[i])) != NONE) {
            void *m = s->rs;
            if (amp_grow(s->all->alloc, &m, &s->caprs, s->nrs + 1, sizeof *s->rs) != AMP_OK)
                return amp_fail(s->err, AMP_ERR_NOMEM, 0, "out of memory for settling");
            s->rs = m;
            s->rs[s->nrs].upper = p;
            s->rs[s->nrs++].lower = h;
        }
    }
    return st;
}

/* Judge the order perm as the pads will: the support rows first, then the object paths. */
static amp_status judge(settler *s)
{
    amp_pathset probe;
    size_t i;
    amp_status st = AMP_OK;
    s->nrs = s->unheld = 0;
    s->runs->n = s->runs->nruns = 0;
    amp_pathset_init(&probe, s->all->alloc);
    for (i = s->nobj; i < s->all->npaths && st == AMP_OK; i++)
        st = amp_pathset_copy_path(&probe, s->all, i, s->err);
    for (i = 0; i < s->nobj && st == AMP_OK; i++)
        st = amp_pathset_copy_path(&probe, s->all, s->perm[i], s->err);
    if (st == AMP_OK)
        st = s->o->find_unheld(&probe, s->o->min_gap, note_run, s, s->err);
    amp_pathset_free(&probe);
    return st;
}

/* Move the path at position from to position to, shifting those between by one. */
static void move(settler *s, size_t from, size_t to)
{
    uint32_t p = s->perm[from];
    size_t i;
    if (from > to)
        memmove(&s->perm[to + 1], &s->perm[to], (from - to) * sizeof *s->perm);
    else
        memmove(&s->perm[from], &s->perm[from + 1], (to - from) * sizeof *s->perm);
    s->perm[to] = p;
    for (i = from < to ? from : to; i <= (from < to ? to : from); i++)
        s->pos[s->perm[i]] = (uint32_t)i;
}

/* The lower path just before the upper one (nothing passed over must precede it), or else the upper just
 * after the lower (it must precede nothing passed over). */
static int settle_one(settler *s, const rest *r)
{
    size_t a = s->pos[r->upper], b = s->pos[r->lower], i;
    if (b < a)
        return 0;
    for (i = a; i < b && !path_below(s, s->perm[i], r->lower); i++)
        ;
    if (i == b) {
        move(s, b, a);
        return 1;
    }
    for (i = a + 1; i <= b && !path_below(s, r->upper, s->perm[i]); i++)
        ;
    if (i > b) {
        move(s, a, b);
        return 1;
    }
    return 0;
}

static amp_status settler_init(settler *s)
{
    const amp_allocator *a = s->all->alloc;
    size_t i;
    s->perm = amp_calloc(a, s->nobj, sizeof *s->perm);
    s->pos = amp_calloc(a, s->nobj, sizeof *s->pos);
    s->saved = amp_calloc(a, s->nobj, sizeof *s->saved);
    if (!s->perm || !s->pos || !s->saved)
        return amp_fail(s->err, AMP_ERR_NOMEM, 0, "out of memory for settling %lu paths", (unsigned long)s->nobj);
    for (i = 0; i < s->nobj; i++)
        s->perm[i] = s->pos[i] = (uint32_t)i;
    return AMP_OK;
}

/* The fragments (Def. 5.3, as the ordering cut them) and boxes of the object paths, for Def. 5.1. */
static amp_status cone_geometry(settler *s)
{
    size_t i, f;
    amp_status st = amp_fragments_build(&s->fs, s->all, 0.95 * s->zo * sin(s->o->head.theta), s->all->alloc, s->err);
    if (st != AMP_OK)
        return st;
    if (!(s->pbox = amp_calloc(s->all->alloc, s->nobj, sizeof *s->pbox)))
        return amp_fail(s->err, AMP_ERR_NOMEM, 0, "out of memory for settling %lu paths", (unsigned long)s->nobj);
    for (i = 0; i < s->nobj; i++) {
        s->pbox[i] = amp_box3_empty();
        for (f = s->fs.first[i]; f < s->fs.first[i + 1]; f++)
            s->pbox[i] = amp_box3_union(s->pbox[i], s->fs.frag[f].box);
    }
    return AMP_OK;
}

/* Rounds of moves while each leaves fewer samples in the air; *moved: paths moved by the rounds kept. The
 * runs kept are those of the order left unless a round was undone. */
static amp_status settle_rounds(settler *s, size_t *moved)
{
    size_t round, i, before, n;
    amp_status st = judge(s);
    s->runs->valid = 1;
    if (st == AMP_OK && s->nrs)
        st = cone_geometry(s);
    for (round = 0; st == AMP_OK && round < SETTLE_ROUNDS && s->nrs; round++) {
        before = s->unheld;
        memcpy(s->saved, s->perm, s->nobj * sizeof *s->perm);
        for (i = n = 0; i < s->nrs; i++)
            n += (size_t)settle_one(s, &s->rs[i]);
        if (!n || (st = judge(s)) != AMP_OK)
            break;
        if (s->unheld >= before) { /* no better as a whole: back to the order before the round */
            memcpy(s->perm, s->saved, s->nobj * sizeof *s->perm);
            s->runs->valid = 0;
            break;
        }
        *moved += n;
    }
    return st;
}

/* @p all with its object paths in the order perm. */
static amp_status reorder(settler *s, amp_pathset *all)
{
    amp_pathset out;
    size_t i;
    amp_status st = AMP_OK;
    amp_pathset_init(&out, all->alloc);
    for (i = 0; i < all->npaths && st == AMP_OK; i++)
        st = amp_pathset_copy_path(&out, all, i < s->nobj ? s->perm[i] : i, s->err);
    if (st != AMP_OK) {
        amp_pathset_free(&out);
        return st;
    }
    amp_pathset_free(all);
    *all = out;
    return AMP_OK;
}

amp_status amp_support_settle(amp_pathset *all, size_t nobj, const amp_support_opts *o, size_t *moved,
                              amp_unheld_runs *runs, amp_error *err)
{
    settler s;
    size_t i;
    amp_status st;
    *moved = 0;
    runs->valid = 0;
    if (!o->find_unheld || nobj < 2 || nobj >= NONE)
        return AMP_OK;
    for (i = 0; i < nobj; i++)
        if (all->paths[i].role != AMP_ROLE_OBJECT)
            return AMP_OK;
    memset(&s, 0, sizeof s);
    s.all = all;
    s.nobj = nobj;
    s.nrows = all->npaths - nobj;
    s.o = o;
    s.zo = o->head.z_offs;
    s.k = 1.0 / tan(o->head.theta);
    s.err = err;
    s.runs = runs;
    runs->a = all->alloc;
    if ((st = settler_init(&s)) == AMP_OK)
        st = settle_rounds(&s, moved);
    amp_fragments_free(&s.fs);
    if (st == AMP_OK && *moved)
        st = reorder(&s, all);
    amp_bead_tops_free(&s.tops);
    amp_free(all->alloc, s.pbox);
    amp_free(all->alloc, s.perm);
    amp_free(all->alloc, s.pos);
    amp_free(all->alloc, s.saved);
    amp_free(all->alloc, s.rs);
    return st;
}
