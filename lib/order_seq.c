/*
 * Re-sequencing of Algorithm 2's sub-curves for short travel (less travel between the printed paths, beyond [P1 §5.1]).
 *
 * Algorithm 2 decides where the curves are cut (its GetBest: fewest new cuts). The order it prints the
 * resulting sub-curves in is only one of the orders its rule allows: any order in which a sub-curve comes
 * after every other sub-curve holding a fragment below one of its own (Def. 5.1) is gouge-free, and the
 * sub-curves, hence the cuts, stay the same. Algorithm 2's order jumps between heights (it takes the longest
 * run anywhere), and on a printer a millimetre of Z costs about twelve of XY (10 mm/s against 120 mm/s), so
 * this pass prints, among the admissible sub-curves, the one whose start is cheapest to reach from where the
 * head stands, with Z weighted: the work at one height band is finished before the head climbs.
 *
 * Admissibility is kept as in Algorithm 2 (lib/order.c): a sub-curve waits on one blocker (an unprinted
 * fragment of another sub-curve below one of its fragments, amp_fbvh_find_any_below_x) and is looked at
 * again only once that blocker is printed; its fragments already found free stay free (printing only
 * removes blockers); only fragments of sub-curves before it in the pass's (gouge-free) input order can block
 * it, and the hierarchy's ranks let the queries skip the rest. The candidates are found lazily: the nearest
 * sub-curve not known to be blocked is tested when a search meets it. Sub-curve ends sit in a 3-D grid whose
 * z cells are zw times thinner, so that the weighted distance is a ring search; far from everything it falls
 * back to a scan of all sub-curves.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "order_internal.h"

#define NONE AMP_FBVH_NONE
/* most fragments of a sub-curve tested pairwise to decide that it may be printed the other way round */
#define REV_MAX 64
/* most grid cells per sub-curve end (empty cells cost a ring search time, not answers) */
#define SEQ_CELLS_PER_END 4.0

enum { PS_UNKNOWN, PS_WAITING, PS_READY, PS_PRINTED };

typedef struct sent {
    uint32_t piece, next; /* next entry of the cell (NONE: last); next free entry when free */
    uint32_t end;         /* 0: start as stored, 1: the other end (printed reversed) */
} sent;

typedef struct best {
    double d;
    uint32_t piece, end;
} best;

typedef struct seq {
    const amp_fragments *fs;
    amp_fbvh *bvh;
    double zo, k, zw;
    amp_order_piece *pc;
    size_t np, alive;
    unsigned char *st, *rev, *ing, *done;
    uint32_t *pos, *last, *pwnext, *whead, *clear; /* last: the blocker p last waited on */
    uint32_t *live, *lpos; /* the unprinted sub-curves (live[0 .. alive-1]) and where each one is in live */
    uint32_t *cell, nx, ny, nz, freel;
    double x0, y0, z0, s;
    sent *ent;
    size_t nent, cap, queries;
    struct best *cand; /* every start a search met, for testing in cost order without searching again */
    size_t ncand, capcand;
    double bound;      /* starts the search did not meet cost at least this much */
    int oom;
    const amp_allocator *a;
    amp_error *err;
} seq;

static amp_vec3 piece_start(const seq *q, uint32_t p, uint32_t end)
{
    const amp_order_piece *c = &q->pc[p];
    int fw = (c->dir > 0) != (end != 0);
    return fw ? q->fs->frag[c->lo].p0 : q->fs->frag[c->hi].p1;
}

static amp_vec3 piece_stop(const seq *q, uint32_t p, int dir)
{
    const amp_order_piece *c = &q->pc[p];
    return dir > 0 ? q->fs->frag[c->hi].p1 : q->fs->frag[c->lo].p0;
}

static double cost(const seq *q, amp_vec3 a, amp_vec3 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, dz = q->zw * (b.z - a.z);
    return sqrt(dx * dx + dy * dy + dz * dz);
}

static uint32_t cidx(double v, double v0, double inv, uint32_t n)
{
    double t = (v - v0) * inv;
    return t <= 0.0 ? 0 : (t >= (double)(n - 1) ? n - 1 : (uint32_t)t);
}

static size_t cell_of(const seq *q, amp_vec3 p)
{
    uint32_t cx = cidx(p.x, q->x0, 1.0 / q->s, q->nx), cy = cidx(p.y, q->y0, 1.0 / q->s, q->ny);
    uint32_t cz = cidx(p.z, q->z0, q->zw / q->s, q->nz);
    return ((size_t)cz * q->ny + cy) * q->nx + cx;
}

/* No fragment of the sub-curve below another of it: it may be printed either way. */
static int reversible(const seq *q, const amp_order_piece *c)
{
    uint32_t i, j;
    if (c->box.max.z - c->box.min.z <= q->zo) /* nothing can be z_offs higher than anything else */
        return 1;
    if (c->hi - c->lo >= REV_MAX)
        return 0;
    for (i = c->lo; i <= c->hi; i++)
        for (j = c->lo; j <= c->hi; j++)
            if (i != j && amp_fragment_below_k(q->fs, q->zo, q->k, i, j))
                return 0;
    return 1;
}

static amp_status grid_init(seq *q)
{
    amp_box3 all = amp_box3_empty();
    double w, h, d;
    size_t i, ncell;
    for (i = 0; i < q->np; i++)
        all = amp_box3_union(all, q->pc[i].box);
    w = all.max.x - all.min.x;
    h = all.max.y - all.min.y;
    d = (all.max.z - all.min.z) * q->zw;
    q->s = fmax(fmax(4.0 * q->fs->max_len, fmax(w, fmax(h, d)) / 256.0), 1e-6);
    for (;;) {
        q->nx = (uint32_t)(w / q->s) + 1;
        q->ny = (uint32_t)(h / q->s) + 1;
        q->nz = (uint32_t)(d / q->s) + 1;
        if ((double)q->nx * q->ny * q->nz <= fmax(SEQ_CELLS_PER_END * 2.0 * (double)q->np, 4096.0))
            break;
        q->s *= 1.25;
    }
    q->x0 = all.min.x;
    q->y0 = all.min.y;
    q->z0 = all.min.z;
    q->freel = NONE;
    ncell = (size_t)q->nx * q->ny * q->nz;
    if (!(q->cell = amp_calloc(q->a, ncell, sizeof *q->cell)))
        return amp_fail(q->err, AMP_ERR_NOMEM, 0, "out of memory for the sub-curve grid");
    for (i = 0; i < ncell; i++)
        q->cell[i] = NONE;
    return AMP_OK;
}

/* Put the missing ends of sub-curve p into the grid. */
static amp_status grid_add(seq *q, uint32_t p)
{
    uint32_t end;
    for (end = 0; end <= (uint32_t)(q->rev[p] != 0); end++) {
        uint32_t id, *head;
        if (q->ing[p] & (1u << end))
            continue;
        head = &q->cell[cell_of(q, piece_start(q, p, end))];
        if (q->freel != NONE) {
            id = q->freel;
            q->freel = q->ent[id].next;
        } else {
            void *m = q->ent;
            if (q->nent >= NONE || amp_grow(q->a, &m, &q->cap, q->nent + 1, sizeof *q->ent) != AMP_OK)
                return amp_fail(q->err, AMP_ERR_NOMEM, 0, "out of memory for the sub-curve grid");
            q->ent = m;
            id = (uint32_t)q->nent++;
        }
        q->ent[id].piece = p;
        q->ent[id].end = end;
        q->ent[id].next = *head;
        *head = id;
        q->ing[p] |= (unsigned char)(1u << end);
    }
    return AMP_OK;
}

static int best_cmp(const void *x, const void *y)
{
    const best *a = x, *b = y;
    if (a->d != b->d)
        return a->d < b->d ? -1 : 1;
    if (a->piece != b->piece)
        return a->piece < b->piece ? -1 : 1;
    return a->end < b->end ? -1 : (a->end > b->end);
}

/* A start the search met: kept as a candidate, and the cheapest so far tracked (ties: lower sub-curve). */
static void consider(seq *q, amp_vec3 at, uint32_t p, uint32_t end, best *b)
{
    best c;
    void *m = q->cand;
    c.d = cost(q, at, piece_start(q, p, end));
    c.piece = p;
    c.end = end;
    if (best_cmp(&c, b) < 0)
        *b = c;
    if (amp_grow(q->a, &m, &q->capcand, q->ncand + 1, sizeof *q->cand) != AMP_OK) {
        q->oom = 1;
        return;
    }
    q->cand = m;
    q->cand[q->ncand++] = c;
}

/* One cell: unlink the entries of sub-curves printed or waiting, consider the others. */
static void scan_cell(seq *q, size_t c, amp_vec3 at, best *b)
{
    uint32_t *link = &q->cell[c];
    while (*link != NONE) {
        uint32_t id = *link;
        sent *en = &q->ent[id];
        if (q->st[en->piece] == PS_WAITING || q->st[en->piece] == PS_PRINTED) {
            q->ing[en->piece] &= (unsigned char)~(1u << en->end);
            *link = en->next;
            en->next = q->freel;
            q->freel = id;
            continue;
        }
        consider(q, at, en->piece, en->end, b);
        link = &en->next;
    }
}

/* The cheapest sub-curve start from @p at among those not known to be blocked (piece NONE: none); every start
 * met is in q->cand, and every start not met costs at least q->bound. */
static best search(seq *q, amp_vec3 at)
{
    best b;
    long hx = (long)cidx(at.x, q->x0, 1.0 / q->s, q->nx), hy = (long)cidx(at.y, q->y0, 1.0 / q->s, q->ny);
    long hz = (long)cidx(at.z, q->z0, q->zw / q->s, q->nz), r, rmax = (long)q->nx, dx, dy, dz;
    size_t visited = 0, budget = 2 * q->alive + 64, i;
    b.d = HUGE_VAL;
    b.piece = b.end = NONE;
    q->ncand = 0;
    q->bound = HUGE_VAL;
    if ((long)q->ny > rmax)
        rmax = (long)q->ny;
    if ((long)q->nz > rmax)
        rmax = (long)q->nz;
    for (r = 0; r <= rmax; r++) {
        /* a cell r rings out is at least (r - 1) cells away in x, y or weighted z */
        if (r > 0 && b.d <= (double)(r - 1) * q->s) {
            q->bound = (double)(r - 1) * q->s;
            return b;
        }
        if (visited > budget)
            break;
        for (dz = -r; dz <= r; dz++)
            for (dy = -r; dy <= r; dy++) {
                long z = hz + dz, y = hy + dy, step = (labs(dz) == r || labs(dy) == r) ? 1 : 2 * r;
                if (z < 0 || z >= (long)q->nz || y < 0 || y >= (long)q->ny)
                    continue;
                for (dx = -r; dx <= r; dx += step ? step : 1) {
                    long x = hx + dx;
                    visited++;
                    if (x >= 0 && x < (long)q->nx)
                        scan_cell(q, ((size_t)z * q->ny + (size_t)y) * q->nx + (size_t)x, at, &b);
                    if (step == 0)
                        break;
                }
            }
    }
    if (r > rmax)
        return b;
    /* far from every candidate: a scan of all sub-curves is cheaper than more rings */
    b.d = HUGE_VAL;
    b.piece = b.end = NONE;
    q->ncand = 0;
    for (i = 0; i < q->alive; i++) {
        uint32_t p = q->live[i];
        if (q->st[p] == PS_UNKNOWN || q->st[p] == PS_READY) {
            consider(q, at, p, 0, &b);
            if (q->rev[p])
                consider(q, at, p, 1, &b);
        }
    }
    return b;
}

/* Is sub-curve p admissible (no unprinted fragment of another sub-curve below it)? If not, it waits on the
 * blocker found. A flat sub-curve is tested in one traversal (amp_fbvh_find_any_below_piece: once it is
 * admissible, proving that nothing is left below fragment by fragment costs a traversal each: at 10^6
 * fragments of layered lines 1.0 M queries against 19 k); a steep one fragment by fragment, from the first
 * one not yet proven free (printing only removes blockers) and near its last blocker (its whole box would
 * reach down over too much: on the demo helix 2.5 x the time). Either way the answer is exact. */
static int admissible(seq *q, uint32_t p)
{
    const amp_order_piece *c = &q->pc[p];
    uint32_t f, g = NONE;
    if (c->box.max.z - c->box.min.z <= 2.0 * q->zo) {
        g = amp_fbvh_find_any_below_piece(q->bvh, q->fs, q->zo, q->k, c->lo, c->hi, p, c->box, q->done);
        q->queries++;
    } else
        for (f = c->lo + q->pos[p]; f <= c->hi; f++) {
            g = amp_fbvh_find_any_below_x(q->bvh, q->fs, q->zo, q->k, f, c->lo, c->hi, p, q->done, q->last[p],
                                          &q->clear[f]);
            q->queries++;
            if (g != NONE) {
                q->pos[p] = f - c->lo;
                break;
            }
        }
    if (g != NONE) {
        q->st[p] = PS_WAITING;
        q->last[p] = g;
        q->pwnext[p] = q->whead[g];
        q->whead[g] = p;
        return 0;
    }
    q->st[p] = PS_READY;
    return 1;
}

/* Print sub-curve p: its fragments are done, the sub-curves waiting on them are candidates again. */
static amp_status print_piece(seq *q, uint32_t p)
{
    const amp_order_piece *c = &q->pc[p];
    uint32_t f;
    amp_status st = AMP_OK;
    q->st[p] = PS_PRINTED;
    q->alive--;
    q->live[q->lpos[p]] = q->live[q->alive]; /* order does not matter: ties go by sub-curve index */
    q->lpos[q->live[q->alive]] = q->lpos[p];
    for (f = c->lo; f <= c->hi; f++) {
        q->done[f] = 1;
        amp_fbvh_deactivate(q->bvh, q->fs, q->done, f);
    }
    for (f = c->lo; f <= c->hi && st == AMP_OK; f++) {
        uint32_t w = q->whead[f];
        q->whead[f] = NONE;
        for (; w != NONE && st == AMP_OK; w = q->pwnext[w]) {
            q->st[w] = PS_UNKNOWN;
            st = grid_add(q, w);
        }
    }
    return st;
}

static void seq_free(seq *q)
{
    amp_free(q->a, q->st);
    amp_free(q->a, q->rev);
    amp_free(q->a, q->ing);
    amp_free(q->a, q->done);
    amp_free(q->a, q->pos);
    amp_free(q->a, q->last);
    amp_free(q->a, q->live);
    amp_free(q->a, q->lpos);
    amp_free(q->a, q->pwnext);
    amp_free(q->a, q->whead);
    amp_free(q->a, q->clear);
    amp_free(q->a, q->cell);
    amp_free(q->a, q->ent);
    amp_free(q->a, q->cand);
}

static amp_status seq_run(seq *q, amp_order_piece *outp)
{
    size_t i, nout = 0;
    amp_vec3 head = amp_v3(0, 0, 0);
    amp_status st = AMP_OK;
    for (i = 0; i < q->np && st == AMP_OK; i++)
        st = grid_add(q, (uint32_t)i);
    while (st == AMP_OK && nout < q->np) {
        best b;
        size_t c;
        if (nout == 0) { /* the first sub-curve of Algorithm 2's order is admissible: start where it did */
            b.piece = 0;
            b.end = 0;
            q->st[0] = PS_READY;
        } else {
            b = search(q, head);
            if (q->oom)
                return amp_fail(q->err, AMP_ERR_NOMEM, 0, "out of memory for re-sequencing");
            if (b.piece == NONE)
                return amp_fail(q->err, AMP_ERR_GEOMETRY, 0,
                                "re-sequencing: no admissible sub-curve among %lu (Lemma 5.1 violated numerically)",
                                (unsigned long)q->alive);
            /* the starts met, cheapest first: the first admissible one cheaper than any start not met is the
             * cheapest admissible start; when every such one waits, search again */
            qsort(q->cand, q->ncand, sizeof *q->cand, best_cmp);
            b.piece = NONE;
            for (c = 0; c < q->ncand && q->cand[c].d <= q->bound; c++) {
                uint32_t p = q->cand[c].piece;
                if (q->st[p] == PS_READY || (q->st[p] == PS_UNKNOWN && admissible(q, p))) {
                    b = q->cand[c];
                    break;
                }
            }
            if (b.piece == NONE && q->bound == HUGE_VAL && c == q->ncand)
                return amp_fail(q->err, AMP_ERR_GEOMETRY, 0,
                                "re-sequencing: no admissible sub-curve among %lu (Lemma 5.1 violated numerically)",
                                (unsigned long)q->alive);
            if (b.piece == NONE)
                continue;
        }
        outp[nout] = q->pc[b.piece];
        if (b.end)
            outp[nout].dir = -outp[nout].dir;
        head = piece_stop(q, b.piece, outp[nout].dir);
        nout++;
        st = print_piece(q, b.piece);
    }
    return st;
}

/* Rank each fragment by its sub-curve's place in the given order, which is gouge-free (Algorithm 2's, or the
 * merged and re-sequenced one): every blocker of sub-curve p then ranks below p, and the blocker queries of p
 * pass over the sub-curves that came after it (most of the hierarchy once the front has moved past them). */
static amp_status rank_pieces(seq *q)
{
    uint32_t *rank = amp_calloc(q->a, q->fs->n, sizeof *rank), f;
    size_t i;
    amp_status st;
    if (!rank)
        return amp_fail(q->err, AMP_ERR_NOMEM, 0, "out of memory for ranking %lu fragments", (unsigned long)q->fs->n);
    for (i = 0; i < q->np; i++)
        for (f = q->pc[i].lo; f <= q->pc[i].hi; f++)
            rank[f] = (uint32_t)i;
    st = amp_fbvh_set_rank(q->bvh, rank, q->err);
    amp_free(q->a, rank);
    return st;
}

amp_status amp_order_resequence(const amp_fragments *fs, amp_fbvh *bvh, double zo, double k, double zw,
                                amp_order_piece *pc, size_t npc, const amp_allocator *a, amp_error *err,
                                size_t *queries)
{
    seq q;
    amp_order_piece *outp;
    size_t i, n = fs->n;
    amp_status st;
    if (npc < 2)
        return AMP_OK;
    memset(&q, 0, sizeof q);
    q.fs = fs;
    q.bvh = bvh;
    q.zo = zo;
    q.k = k;
    q.zw = zw > 0.0 ? zw : 1.0;
    q.pc = pc;
    q.np = q.alive = npc;
    q.a = a;
    q.err = err;
    q.st = amp_calloc(a, npc, 1);
    q.rev = amp_calloc(a, npc, 1);
    q.ing = amp_calloc(a, npc, 1);
    q.pos = amp_calloc(a, npc, sizeof *q.pos);
    q.last = amp_calloc(a, npc, sizeof *q.last);
    q.live = amp_calloc(a, npc, sizeof *q.live);
    q.lpos = amp_calloc(a, npc, sizeof *q.lpos);
    q.pwnext = amp_calloc(a, npc, sizeof *q.pwnext);
    q.done = amp_calloc(a, n, 1);
    q.whead = amp_calloc(a, n, sizeof *q.whead);
    q.clear = amp_calloc(a, n, sizeof *q.clear);
    outp = amp_calloc(a, npc, sizeof *outp);
    if (!q.st || !q.rev || !q.ing || !q.pos || !q.last || !q.live || !q.lpos || !q.pwnext || !q.done || !q.whead || !q.clear || !outp) {
        amp_free(a, outp);
        seq_free(&q);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for re-sequencing %lu sub-curves",
                        (unsigned long)npc);
    }
    for (i = 0; i < n; i++)
        q.whead[i] = q.clear[i] = NONE;
    for (i = 0; i < npc; i++) {
        q.rev[i] = (unsigned char)reversible(&q, &pc[i]);
        q.last[i] = NONE;
        q.live[i] = q.lpos[i] = (uint32_t)i;
    }
    st = rank_pieces(&q);
    if (st == AMP_OK)
        st = grid_init(&q);
    if (st == AMP_OK)
        st = seq_run(&q, outp);
    amp_fbvh_set_rank(bvh, NULL, NULL);
    if (st == AMP_OK)
        memcpy(pc, outp, npc * sizeof *pc);
    if (queries)
        *queries += q.queries;
    amp_free(a, outp);
    seq_free(&q);
    return st;
}
