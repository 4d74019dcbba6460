/* Algorithm 2 (OrderCurves, [P1 §5.1]) over fragments, with continuation, look-ahead and bottom-up merging. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/order.h"
#include "heap.h"
#include "keysort.h"
#include "order_internal.h"

#define NONE AMP_FBVH_NONE
/* longest continuation simulated per candidate during look-ahead */
#define LOOKAHEAD_CAP 64
/* most sub-curves between two merge partners */
#define MERGE_MAX_PIECES 256
/* runs at least this fraction as long as the longest equally cut one are equally good for the nearest choice */
#define NEAR_LEN_SLACK 0.9

void amp_order_opts_default(amp_order_opts *o)
{
    amp_head_default(&o->head);
    o->improve = 1;
    o->lookahead = 16;
    o->merge_window = 2000;
    o->nearest = 1;
    o->travel_z_weight = AMP_ORDER_TRAVEL_Z_WEIGHT;
    o->progress = NULL;
    o->progress_user = NULL;
}

/* ---- the below graph (Def. 5.2), for reporting and tests ---- */

void amp_below_graph_free(amp_below_graph *g)
{
    if (!g)
        return;
    amp_free(g->alloc, g->row);
    amp_free(g->alloc, g->to);
    g->row = NULL;
    g->to = NULL;
    g->n = g->nedges = 0;
}

typedef struct edge_sink {
    uint32_t *to;  /* NULL while counting */
    size_t count;
    size_t limit;
} edge_sink;

static int edge_cb(void *user, uint32_t gi)
{
    edge_sink *s = user;
    if (s->to)
        s->to[s->count] = gi;
    s->count++;
    return s->count > s->limit;
}

static int u32_cmp(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : (x > y);
}

amp_status amp_below_graph_build(amp_below_graph *g, const amp_fragments *fs, const amp_head *h, size_t max_edges,
                                 amp_error *err)
{
    amp_fbvh bvh;
    amp_status st;
    size_t i, total = 0;
    long n, f;
    int over = 0;
    if (!g || !fs || !h)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_below_graph_build: NULL argument");
    memset(g, 0, sizeof *g);
    g->alloc = fs->alloc;
    if ((st = amp_head_validate(h, err)) != AMP_OK)
        return st;
    if ((st = amp_fbvh_build(&bvh, fs, fs->alloc, err)) != AMP_OK)
        return st;
    g->n = fs->n;
    g->row = amp_calloc(fs->alloc, fs->n + 1, sizeof *g->row);
    if (!g->row) {
        amp_fbvh_free(&bvh);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the below graph");
    }
    n = (long)fs->n;
    /* pass 1: count the successors of every fragment (each query is independent) */
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : total)
    for (f = 0; f < n; f++) {
        edge_sink s;
        int stop;
#pragma omp atomic read
        stop = over;
        if (stop)
            continue;
        s.to = NULL;
        s.count = 0;
        s.limit = max_edges;
        amp_fbvh_for_above(&bvh, fs, h, (uint32_t)f, edge_cb, &s);
        g->row[f + 1] = s.count;
        total += s.count;
        if (s.count > max_edges) {
#pragma omp atomic write
            over = 1;
        }
    }
    if (over || total > max_edges) {
        amp_fbvh_free(&bvh);
        amp_below_graph_free(g);
        return amp_fail(err, AMP_ERR_LIMIT, 0, "the below graph has more than %lu edges", (unsigned long)max_edges);
    }
    for (i = 0; i < fs->n; i++)
        g->row[i + 1] += g->row[i];
    g->nedges = total;
    g->to = total ? amp_calloc(fs->alloc, total, sizeof *g->to) : NULL;
    if (total && !g->to) {
        amp_fbvh_free(&bvh);
        amp_below_graph_free(g);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for %lu edges", (unsigned long)total);
    }
    /* pass 2: fill the rows */
#pragma omp parallel for schedule(dynamic, 64)
    for (f = 0; f < n; f++) {
        edge_sink s;
        s.to = g->to + g->row[f];
        s.count = 0;
        s.limit = (size_t)-1;
        amp_fbvh_for_above(&bvh, fs, h, (uint32_t)f, edge_cb, &s);
        qsort(s.to, s.count, sizeof *s.to, u32_cmp);
    }
    amp_fbvh_free(&bvh);
    return AMP_OK;
}

/* ---- ordering state ---- */

typedef amp_order_piece piece; /* fragments lo..hi of one path, printed lo..hi (dir +1) or hi..lo (dir -1) */

typedef struct runent {
    uint32_t cuts, len, s, e;
    double zmin;
} runent;

/* Printable runs by the xy cell of each end, one list per number of new cuts (0, 1, 2): the nearest run of
 * GetBest's best class is found by a ring search around the head. Entries are removed lazily (a run that grew,
 * shrank or was printed is unlinked when a search meets it). */
typedef struct rgent {
    uint32_t s, e;    /* the run */
    uint32_t next;    /* next entry of the cell, NONE at the end; next free entry when free */
    uint32_t end;     /* 0: the entry stands for the run's start point, 1: for its end point */
} rgent;

typedef struct rgrid {
    uint32_t *cell;   /* 3 * nx * ny list heads */
    uint32_t nx, ny;
    double x0, y0, inv, size;
    rgent *ent;
    size_t nent, cap, live[3];
    uint32_t freel;
} rgrid;

typedef struct orderer {
    const amp_allocator *a;
    const amp_fragments *fs;
    const amp_head *h;
    double k; /* cot(theta) */
    const amp_order_opts *o;
    amp_fbvh bvh;
    unsigned char *done;  /* 0 unprinted, 1 printed, 2 printed tentatively (look-ahead) */
    unsigned char *ready; /* nothing unprinted below: member of the set B of Alg. 2, line 4 */
    uint32_t *whead, *wnext, *rs, *re;
    uint32_t *waits; /* the blocker an unprinted, unready fragment waits on */
    uint32_t *clear; /* per fragment, a subtree of the hierarchy its earlier queries proved free of blockers */
    uint32_t *batch, *found, *sorttmp; /* fragments to query again, their answers, room to sort them (release_range) */
    double *rz;
    amp_heap heap; /* of runent, best by run_better: GetBest's candidates */
    piece *pc;
    size_t npc, cap_pc;
    size_t nprinted;
    rgrid grid;          /* printable runs by position, for the nearest choice (NULL cells: not used) */
    amp_vec3 head_pos;   /* where the last printed run ended */
    int have_head;
    amp_order_stats st;
    amp_error *err;
} orderer;

static uint32_t cfirst(const orderer *o, uint32_t f) { return (uint32_t)o->fs->first[o->fs->frag[f].path]; }
static uint32_t clast(const orderer *o, uint32_t f) { return (uint32_t)o->fs->first[o->fs->frag[f].path + 1] - 1; }

/* The fragment after @p f in direction @p d on the curve [lo, hi], or NONE past its end. */
static uint32_t step_along(uint32_t f, int d, uint32_t lo, uint32_t hi)
{
    if (d > 0)
        return f < hi ? f + 1 : NONE;
    return f > lo ? f - 1 : NONE;
}

/* GetBest's preference: fewer new cuts, then a longer run, then the lower run (Lemma 5.1), then curve order.
 * lib/heap.h's rule (strictly better moves) keeps the order of equal runs a function of the pushes and pops. */
static int run_better(const void *xp, const void *yp, const void *ctx)
{
    const runent *x = xp, *y = yp;
    (void)ctx;
    if (x->cuts != y->cuts)
        return x->cuts < y->cuts;
    if (x->len != y->len)
        return x->len > y->len;
    if (x->zmin != y->zmin)
        return x->zmin < y->zmin;
    return x->s < y->s;
}

static amp_status heap_insert(orderer *o, const runent *r)
{
    if (amp_heap_push(&o->heap, r) != AMP_OK)
        return amp_fail(o->err, AMP_ERR_NOMEM, 0, "out of memory for the printable runs");
    return AMP_OK;
}

static amp_status rgrid_add(orderer *o, uint32_t s, uint32_t e, uint32_t cuts);

/* A new printable run [s, e]: into the heap of GetBest and, for the nearest choice, into the grid. */
static amp_status heap_push(orderer *o, uint32_t s, uint32_t e)
{
    runent r;
    amp_status st;
    r.s = s;
    r.e = e;
    r.len = e - s + 1;
    r.cuts = (uint32_t)(s != cfirst(o, s)) + (uint32_t)(e != clast(o, e));
    r.zmin = o->rz[s];
    if ((st = heap_insert(o, &r)) != AMP_OK)
        return st;
    return o->grid.cell ? rgrid_add(o, s, e, r.cuts) : AMP_OK;
}

static int run_valid(const orderer *o, const runent *r)
{
    return o->ready[r->s] && !o->done[r->s] && !o->done[r->e] && o->re[r->s] == r->e && o->rs[r->e] == r->s;
}

/* ---- printable runs by position (nearest choice) ---- */

static void rgrid_free(const amp_allocator *a, rgrid *g)
{
    amp_free(a, g->cell);
    amp_free(a, g->ent);
    memset(g, 0, sizeof *g);
}

/* Cells of about 4 fragments' extent over the xy box of all fragments, at most 512 a side. */
static amp_status rgrid_init(orderer *o)
{
    rgrid *g = &o->grid;
    amp_box3 all = amp_box3_empty();
    double w, hgt, side;
    size_t i, ncell;
    for (i = 0; i < o->fs->n; i++)
        all = amp_box3_union(all, o->fs->frag[i].box);
    w = all.max.x - all.min.x;
    hgt = all.max.y - all.min.y;
    side = 4.0 * o->fs->max_len;
    side = fmax(side, sqrt(fmax(w * hgt, 1e-12) / 262144.0));
    side = fmax(side, fmax(w, hgt) / 512.0);
    side = fmax(side, 1e-6);
    g->size = side;
    g->inv = 1.0 / side;
    g->x0 = all.min.x;
    g->y0 = all.min.y;
    g->nx = (uint32_t)(w / side) + 1;
    g->ny = (uint32_t)(hgt / side) + 1;
    g->freel = NONE;
    ncell = 3 * (size_t)g->nx * g->ny;
    g->cell = amp_calloc(o->a, ncell, sizeof *g->cell);
    if (!g->cell)
        return amp_fail(o->err, AMP_ERR_NOMEM, 0, "out of memory for the run grid");
    for (i = 0; i < ncell; i++)
        g->cell[i] = NONE;
    return AMP_OK;
}

static uint32_t rgrid_cx(const rgrid *g, double x)
{
    double t = (x - g->x0) * g->inv;
    return t <= 0.0 ? 0 : (t >= (double)(g->nx - 1) ? g->nx - 1 : (uint32_t)t);
}

static uint32_t rgrid_cy(const rgrid *g, double y)
{
    double t = (y - g->y0) * g->inv;
    return t <= 0.0 ? 0 : (t >= (double)(g->ny - 1) ? g->ny - 1 : (uint32_t)t);
}

static amp_vec3 run_end_point(const orderer *o, uint32_t s, uint32_t e, uint32_t end)
{
    return end ? o->fs->frag[e].p1 : o->fs->frag[s].p0;
}

static amp_status rgrid_add(orderer *o, uint32_t s, uint32_t e, uint32_t cuts)
{
    rgrid *g = &o->grid;
    uint32_t end;
    for (end = 0; end < 2; end++) {
        amp_vec3 p = run_end_point(o, s, e, end);
        uint32_t id, *head = &g->cell[((size_t)cuts * g->ny + rgrid_cy(g, p.y)) * g->nx + rgrid_cx(g, p.x)];
        if (g->freel != NONE) {
            id = g->freel;
            g->freel = g->ent[id].next;
        } else {
            void *q = g->ent;
            if (g->nent >= NONE || amp_grow(o->a, &q, &g->cap, g->nent + 1, sizeof *g->ent) != AMP_OK)
                return amp_fail(o->err, AMP_ERR_NOMEM, 0, "out of memory for the run grid");
            g->ent = q;
            id = (uint32_t)g->nent++;
        }
        g->ent[id].s = s;
        g->ent[id].e = e;
        g->ent[id].end = end;
        g->ent[id].next = *head;
        *head = id;
        g->live[cuts]++;
    }
    return AMP_OK;
}

/* Scan one cell: drop stale entries, keep the nearest valid run end (ties: lower start fragment). */
static void rgrid_scan(orderer *o, uint32_t cuts, uint32_t cx, uint32_t cy, amp_vec3 at, runent *best,
                       double *bestd, uint32_t *bestend)
{
    rgrid *g = &o->grid;
    uint32_t *link = &g->cell[((size_t)cuts * g->ny + cy) * g->nx + cx];
    while (*link != NONE) {
        uint32_t id = *link;
        rgent *en = &g->ent[id];
        runent r;
        double d;
        r.s = en->s;
        r.e = en->e;
        if (!run_valid(o, &r)) {
            *link = en->next;
            en->next = g->freel;
            g->freel = id;
            g->live[cuts]--;
            continue;
        }
        d = amp_v3_dist(at, run_end_point(o, r.s, r.e, en->end));
        if (d < *bestd || (d == *bestd && (r.s < best->s || (r.s == best->s && en->end < *bestend)))) {
            *bestd = d;
            *best = r;
            *bestend = en->end;
        }
        link = &en->next;
    }
}

/* The printable run with @p cuts new cuts whose nearer end is nearest to @p at; 0 when there is none. */
static int rgrid_nearest(orderer *o, uint32_t cuts, amp_vec3 at, runent *out, double *dist)
{
    rgrid *g = &o->grid;
    uint32_t cx = rgrid_cx(g, at.x), cy = rgrid_cy(g, at.y), r, rmax = g->nx > g->ny ? g->nx : g->ny, bestend = 0;
    double bestd = HUGE_VAL;
    runent best;
    memset(&best, 0, sizeof best);
    best.s = NONE;
    for (r = 0; r <= rmax && g->live[cuts]; r++) {
        long j, i, step;
        /* every point of ring r is at least (r - 1) cells from the head's cell in xy */
        if (r > 0 && bestd <= (double)(r - 1) * g->size)
            break;
        for (j = (long)cy - (long)r; j <= (long)cy + (long)r; j++) {
            if (j < 0 || j >= (long)g->ny)
                continue;
            step = (j == (long)cy - (long)r || j == (long)cy + (long)r) ? 1 : 2 * (long)r;
            for (i = (long)cx - (long)r; i <= (long)cx + (long)r; i += step ? step : 1) {
                if (i >= 0 && i < (long)g->nx)
                    rgrid_scan(o, cuts, (uint32_t)i, (uint32_t)j, at, &best, &bestd, &bestend);
                if (step == 0)
                    break;
            }
        }
    }
    if (best.s == NONE)
        return 0;
    best.len = best.e - best.s + 1;
    best.cuts = cuts;
    best.zmin = o->rz[best.s];
    *out = best;
    *dist = bestd;
    return 1;
}

/* Pop the best run still printable as a whole; 0 when none is left. */
static int pop_valid(orderer *o, runent *out)
{
    runent r;
    while (amp_heap_pop(&o->heap, &r)) {
        if (run_valid(o, &r)) {
            *out = r;
            return 1;
        }
    }
    return 0;
}

static int open_at(const orderer *o, uint32_t f) { return o->ready[f] && !o->done[f]; }

/* f entered B (Alg. 2, line 4): join it with the printable neighbours on its curve; the start of its run. */
static uint32_t join_ready(orderer *o, uint32_t f)
{
    uint32_t s = f, e = f;
    double z = o->fs->frag[f].box.min.z;
    o->ready[f] = 1;
    if (f > cfirst(o, f) && open_at(o, f - 1)) {
        s = o->rs[f - 1];
        z = fmin(z, o->rz[s]);
    }
    if (f < clast(o, f) && open_at(o, f + 1)) {
        e = o->re[f + 1];
        z = fmin(z, o->rz[f + 1]);
    }
    o->re[s] = e;
    o->rs[e] = s;
    o->rz[s] = z;
    return s;
}

/* Fragments that entered B together: joined one by one, and each run they end in offered to GetBest once (a
 * run pushed at every fragment that joins it leaves the heap mostly stale entries: a line of 250 fragments
 * becoming printable in one batch pushed 250 runs). starts[i] is overwritten with the run start of
 * entered[i]. Offering the runs after the whole batch changes no choice: the heap and the grid order runs
 * by their own keys, and the stale entries were skipped. */
static amp_status enter_batch(orderer *o, const uint32_t *entered, uint32_t *starts, size_t n)
{
    size_t i;
    amp_status st = AMP_OK;
    for (i = 0; i < n; i++)
        starts[i] = join_ready(o, entered[i]);
    for (i = 0; i < n && st == AMP_OK; i++) {
        uint32_t s = starts[i];
        /* still a run start (not joined into a run further back since) and not offered yet in this batch */
        if (o->rs[o->re[s]] == s && !(o->ready[s] & 2)) {
            o->ready[s] |= 2;
            st = heap_push(o, s, o->re[s]);
        }
    }
    for (i = 0; i < n; i++)
        o->ready[starts[i]] &= 1;
    return st;
}

static void mark_done(orderer *o, uint32_t f)
{
    o->done[f] = 1;
    o->nprinted++;
    amp_fbvh_deactivate(&o->bvh, o->fs, o->done, f);
}

/* Fragments [s, e] were printed: the fragments waiting on them look for another blocker or become printable.
 * The queries only read the printed marks and the hierarchy; they are answered first and applied afterwards
 * in the order of the waiting lists. (Run in parallel they gained nothing: most batches are a few fragments,
 * and a thread waiting between batches slows the ordering on a shared machine.) */
static amp_status release_range(orderer *o, uint32_t s, uint32_t e)
{
    size_t nb = 0, nr = 0, k;
    long q;
    uint32_t f;
    for (f = s; f <= e; f++) {
        uint32_t w = o->whead[f];
        o->whead[f] = NONE;
        for (; w != NONE; w = o->wnext[w])
            if (!o->done[w])
                o->batch[nb++] = w;
    }
    /* in fragment order: neighbours on a curve follow each other, so the hint below finds a live blocker at
     * once more often (8.6 M queries instead of 9.2 M on 10^6 layered fragments), and their loads go forward.
     * The answers are applied in this order too: which fragment enters B first in one batch changes nothing */
    if (nb > 1) {
        static const size_t off[1] = {0};
        amp_radix_u32(o->batch, o->sorttmp, nb, sizeof *o->batch, off, 1);
    }
    for (q = 0; q < (long)nb; q++) {
        /* a waiter next to the previous one on its curve is most likely blocked by the same live fragment: the
         * search starts there rather than at its own blocker just printed */
        uint32_t w = o->batch[q], near = o->waits[w];
        if (q + 1 < (long)nb) /* the next waiter's box, a cache miss otherwise (the queries wait on memory) */
            AMP_PREFETCH(&o->fs->frag[o->batch[q + 1]].box);
        if (q > 0 && o->found[q - 1] != NONE && (o->batch[q - 1] == w + 1 || o->batch[q - 1] + 1 == w) &&
            o->fs->frag[w].path == o->fs->frag[o->batch[q - 1]].path)
            near = o->found[q - 1];
        o->found[q] = amp_fbvh_find_any_below(&o->bvh, o->fs, o->h->z_offs, o->k, w, o->done, near, &o->clear[w]);
    }
    o->st.queries += nb;
    /* the blocked ones wait on their new blocker; the others (kept at the front of batch) enter B */
    for (k = 0; k < nb; k++) {
        uint32_t w = o->batch[k], g = o->found[k];
        if (g == NONE)
            o->batch[nr++] = w;
        else {
            o->wnext[w] = o->whead[g];
            o->whead[g] = w;
            o->waits[w] = g;
        }
    }
    return enter_batch(o, o->batch, o->found, nr);
}

static amp_status release(orderer *o, uint32_t f) { return release_range(o, f, f); }

/* x (printable, at one end of its run) is printed alone: the rest of its run stays a run. */
static amp_status split_off(orderer *o, uint32_t x)
{
    if (x == cfirst(o, x) || !open_at(o, x - 1)) {
        uint32_t e = o->re[x];
        if (e > x) {
            o->re[x + 1] = e;
            o->rs[e] = x + 1;
            o->rz[x + 1] = o->rz[x];
            return heap_push(o, x + 1, e);
        }
    } else {
        uint32_t s = o->rs[x];
        if (s < x) {
            o->re[s] = x - 1;
            o->rs[x - 1] = s;
            return heap_push(o, s, x - 1);
        }
    }
    return AMP_OK;
}

static amp_status add_piece(orderer *o, uint32_t lo, uint32_t hi, int dir)
{
    void *p = o->pc;
    piece *q;
    uint32_t f;
    if (amp_grow(o->a, &p, &o->cap_pc, o->npc + 1, sizeof *o->pc) != AMP_OK)
        return amp_fail(o->err, AMP_ERR_NOMEM, 0, "out of memory for sub-curves");
    o->pc = p;
    q = &o->pc[o->npc++];
    q->path = o->fs->frag[lo].path;
    q->lo = lo;
    q->hi = hi;
    q->dir = dir;
    q->box = amp_box3_empty();
    for (f = lo; f <= hi; f++)
        q->box = amp_box3_union(q->box, o->fs->frag[f].box);
    return AMP_OK;
}

/* Print the whole run [s, e] (all of it is in B, so any order inside it is valid). */
static amp_status print_run(orderer *o, uint32_t s, uint32_t e)
{
    uint32_t f;
    for (f = s; f <= e; f++)
        mark_done(o, f);
    return release_range(o, s, e);
}

/* Look-ahead: how many fragments past the run would become printable one after another in direction dir. */
static uint32_t simulate(orderer *o, uint32_t s, uint32_t e, int dir)
{
    uint32_t f, x, cnt = 0, lo = cfirst(o, s), hi = clast(o, s);
    for (f = s; f <= e; f++)
        o->done[f] = 2;
    x = step_along(dir > 0 ? e : s, dir, lo, hi);
    while (x != NONE && cnt < LOOKAHEAD_CAP && !o->done[x]) {
        /* a fragment still waiting on a blocker that is not in the simulated run stays blocked, and a ready one
         * stays printable: only a fragment waiting on the run itself needs a query */
        if (!o->ready[x] && o->done[o->waits[x]] != 2)
            break;
        if (!o->ready[x]) {
            o->st.queries++;
            if (amp_fbvh_find_any_below(&o->bvh, o->fs, o->h->z_offs, o->k, x, o->done, o->waits[x], NULL) != NONE)
                break;
        }
        o->done[x] = 2;
        cnt++;
        x = step_along(x, dir, lo, hi);
    }
    for (f = s; f <= e; f++)
        o->done[f] = 0;
    for (f = 1; f <= cnt; f++)
        o->done[dir > 0 ? e + f : s - f] = 0;
    return cnt;
}

static amp_status step_plain(orderer *o)
{
    runent r;
    if (!pop_valid(o, &r))
        return amp_fail(o->err, AMP_ERR_GEOMETRY, 0,
                        "inaccessibility cycle among %lu unprinted fragments (Lemma 5.1 violated numerically)",
                        (unsigned long)(o->fs->n - o->nprinted));
    o->st.steps++;
    if (add_piece(o, r.s, r.e, 1) != AMP_OK)
        return AMP_ERR_NOMEM;
    return print_run(o, r.s, r.e);
}

/* One way to print a candidate run: its direction and what the look-ahead predicts. */
typedef struct choice {
    uint32_t cuts, len; /* new cuts and run length after the continuation */
    double dist;        /* from the head to the start in this direction */
    int dir;
} choice;

/*
 * GetBest among the options (Alg. 2, line 5): fewest new cuts after the look-ahead's continuation. Runs as
 * good as that and within NEAR_LEN_SLACK of the longest such run count as equally good, and the one that
 * starts nearest to the head is taken (shorter travel between paths); without the nearest choice
 * the longest run is taken. Ties keep the first option (heap order, then forward before backward).
 */
static size_t choose(const orderer *o, const choice *c, size_t n)
{
    size_t i, best = 0;
    uint32_t cuts = 3, len = 0;
    for (i = 0; i < n; i++)
        if (c[i].cuts < cuts || (c[i].cuts == cuts && c[i].len > len)) {
            cuts = c[i].cuts;
            len = c[i].len;
            best = i;
        }
    if (!o->grid.cell || !o->have_head)
        return best;
    for (i = 0; i < n; i++)
        if (c[i].cuts == cuts && (double)c[i].len >= NEAR_LEN_SLACK * (double)len &&
            (c[i].dist < c[best].dist || (c[i].dist == c[best].dist && c[i].len > c[best].len)))
            best = i;
    return best;
}

static amp_status step_improved(orderer *o)
{
    runent cand[17];
    choice opt[34];
    size_t nc = 0, i, best, k = o->o->lookahead, from_grid = (size_t)-1;
    int bestdir;
    uint32_t x;
    amp_status st;
    if (k < 1)
        k = 1;
    if (k > 16)
        k = 16;
    while (nc < k && pop_valid(o, &cand[nc])) {
        for (i = 0; i < nc && cand[i].s != cand[nc].s; i++)
            ;
        if (i == nc)
            nc++;
    }
    if (nc == 0)
        return amp_fail(o->err, AMP_ERR_GEOMETRY, 0,
                        "inaccessibility cycle among %lu unprinted fragments (Lemma 5.1 violated numerically)",
                        (unsigned long)(o->fs->n - o->nprinted));
    if (o->grid.cell && o->have_head) {
        /* the nearest run with as few cuts as GetBest's best competes with the heap's longest runs */
        double d;
        if (rgrid_nearest(o, cand[0].cuts, o->head_pos, &cand[nc], &d)) {
            for (i = 0; i < nc && cand[i].s != cand[nc].s; i++)
                ;
            if (i == nc)
                from_grid = nc++;
        }
    }
    for (i = 0; i < nc; i++) {
        /* look ahead in both directions: how far the curve can be continued right after this run */
        uint32_t s = cand[i].s, e = cand[i].e, lo = cfirst(o, s), hi = clast(o, s);
        uint32_t fw = simulate(o, s, e, 1), bw = simulate(o, s, e, -1);
        choice *f = &opt[2 * i], *b = &opt[2 * i + 1];
        f->cuts = (uint32_t)(s != lo) + (uint32_t)(e + fw != hi);
        b->cuts = (uint32_t)(s - bw != lo) + (uint32_t)(e != hi);
        f->len = e - s + 1 + fw;
        b->len = e - s + 1 + bw;
        f->dir = 1;
        b->dir = -1;
        f->dist = o->have_head ? amp_v3_dist(o->head_pos, o->fs->frag[s].p0) : 0.0;
        b->dist = o->have_head ? amp_v3_dist(o->head_pos, o->fs->frag[e].p1) : 0.0;
    }
    best = choose(o, opt, 2 * nc);
    bestdir = opt[best].dir;
    best /= 2;
    /* the runs not chosen go back to the heap (the grid still holds them) */
    for (i = 0; i < nc; i++)
        if (i != best && i != from_grid && (st = heap_insert(o, &cand[i])) != AMP_OK)
            return st;
    o->st.steps++;
    {
        uint32_t s = cand[best].s, e = cand[best].e, lo = cfirst(o, s), hi = clast(o, s);
        if ((st = print_run(o, s, e)) != AMP_OK)
            return st;
        o->have_head = 1;
        /* prefer continuing the curve just printed: extend while the next fragment has become printable */
        if (bestdir > 0) {
            for (x = e + 1; e < hi && x <= hi && open_at(o, x); x++) {
                if ((st = split_off(o, x)) != AMP_OK)
                    return st;
                mark_done(o, x);
                o->st.extended++;
                if ((st = release(o, x)) != AMP_OK)
                    return st;
            }
            o->head_pos = o->fs->frag[x - 1].p1;
            return add_piece(o, s, x - 1, 1);
        }
        for (x = s; x > lo && open_at(o, x - 1); x--) {
            if ((st = split_off(o, x - 1)) != AMP_OK)
                return st;
            mark_done(o, x - 1);
            o->st.extended++;
            if ((st = release(o, x - 1)) != AMP_OK)
                return st;
        }
        o->head_pos = o->fs->frag[x].p0;
        return add_piece(o, x, e, -1);
    }
}

/* ---- bottom-up merging of adjacent sub-curves (§5.1) ---- */

static int piece_below(const orderer *o, const piece *a, const piece *b)
{
    double k = 1.0 / tan(o->h->theta);
    uint32_t i, j;
    if (b->box.max.z - a->box.min.z - o->h->z_offs - k * amp_box_xy_gap(a->box, b->box) <= AMP_CONE_TOL)
        return 0;
    for (i = a->lo; i <= a->hi; i++) {
        /* the pair's box bound (the first test of amp_fragment_below_k) against all of b at once: b's box holds
         * every fragment's, so it is never smaller, and a fragment of a that fails it fails every pair */
        const amp_box3 *ab = &o->fs->frag[i].box;
        if (b->box.max.z - ab->min.z - o->h->z_offs - k * amp_box_xy_gap(*ab, b->box) <= AMP_CONE_TOL)
            continue;
        for (j = b->lo; j <= b->hi; j++)
            if (amp_fragment_below_k(o->fs, o->h->z_offs, k, i, j))
                return 1;
    }
    return 0;
}

/* The print-order end and start fragments of a piece; a one-fragment piece may be printed either way. */
static uint32_t piece_end(const piece *p) { return p->dir > 0 ? p->hi : p->lo; }


/* The state of one merging pass: the print sequence (seq, NONE for a merged-away slot) and each sub-curve's
 * place in it (pos), each fragment's sub-curve (owner), and the window S between a pair (win, ins). */
typedef struct merger {
    uint32_t *seq, *pos, *owner, *win;
    unsigned char *ins; /* win[w] must stay after p: reachable from p in G_a */
    size_t nwin;
} merger;

static void merge_free(const orderer *o, merger *m)
{
    amp_free(o->a, m->seq);
    amp_free(o->a, m->pos);
    amp_free(o->a, m->owner);
    amp_free(o->a, m->win);
    amp_free(o->a, m->ins);
}

static amp_status merge_init(orderer *o, merger *m)
{
    size_t n = o->npc, i;
    m->seq = amp_calloc(o->a, n ? n : 1, sizeof *m->seq);
    m->pos = amp_calloc(o->a, n ? n : 1, sizeof *m->pos);
    m->owner = amp_calloc(o->a, o->fs->n ? o->fs->n : 1, sizeof *m->owner);
    m->win = amp_calloc(o->a, MERGE_MAX_PIECES, sizeof *m->win);
    m->ins = amp_calloc(o->a, MERGE_MAX_PIECES, 1);
    m->nwin = 0;
    if (!m->seq || !m->pos || !m->owner || !m->win || !m->ins) {
        merge_free(o, m);
        return amp_fail(o->err, AMP_ERR_NOMEM, 0, "out of memory for merging");
    }
    for (i = 0; i < n; i++) {
        uint32_t f;
        m->seq[i] = m->pos[i] = (uint32_t)i;
        for (f = o->pc[i].lo; f <= o->pc[i].hi; f++)
            m->owner[f] = (uint32_t)i;
    }
    return AMP_OK;
}

/* The pair to merge [P1 §5.1, bottom-up]: the sub-curve q that continues p = seq[a] on its curve, printed later,
 * in the same direction (a one-fragment p may turn round: *flip). NONE when there is none. */
static uint32_t merge_partner(const orderer *o, const merger *m, size_t a, int *flip)
{
    const piece *p = &o->pc[m->seq[a]], *q;
    uint32_t lo = (uint32_t)o->fs->first[p->path], hi = (uint32_t)o->fs->first[p->path + 1] - 1, nf, qid;
    int pd, qd;
    *flip = 0;
    nf = step_along(piece_end(p), p->dir, lo, hi);
    if (nf == NONE && p->lo == p->hi) {
        /* a single fragment can be printed the other way round */
        *flip = 1;
        nf = step_along(p->lo, -p->dir, lo, hi);
    }
    if (nf == NONE)
        return NONE;
    qid = m->owner[nf];
    q = &o->pc[qid];
    if (m->pos[qid] <= a)
        return NONE;
    pd = *flip ? -p->dir : p->dir;
    qd = q->lo == q->hi ? pd : q->dir;
    if (qd != pd || (qd > 0 ? q->lo : q->hi) != nf)
        return NONE;
    return qid;
}

/* The sub-curves printed between positions a and b into win; 0 when they are more than the window allows. */
static int merge_window(const orderer *o, merger *m, size_t a, size_t b)
{
    uint32_t nfr = 0;
    size_t x;
    m->nwin = 0;
    for (x = a + 1; x < b; x++) {
        if (m->seq[x] == NONE)
            continue;
        if (m->nwin >= MERGE_MAX_PIECES)
            return 0;
        m->win[m->nwin++] = m->seq[x];
        nfr += o->pc[m->seq[x]].hi - o->pc[m->seq[x]].lo + 1;
        if (nfr > o->o->merge_window)
            return 0;
    }
    return 1;
}

/* Merging p and q keeps G_a acyclic [P1 §5.1] unless q depends on something in S, the sub-curves between them
 * reachable from p (marked in ins: they must stay after it). */
static int merge_keeps_acyclic(const orderer *o, merger *m, const piece *p, const piece *q)
{
    size_t w, t;
    for (w = 0; w < m->nwin; w++) {
        m->ins[w] = piece_below(o, p, &o->pc[m->win[w]]);
        for (t = 0; t < w && !m->ins[w]; t++)
            m->ins[w] = m->ins[t] && piece_below(o, &o->pc[m->win[t]], &o->pc[m->win[w]]);
    }
    for (w = 0; w < m->nwin; w++)
        if (m->ins[w] && piece_below(o, &o->pc[m->win[w]], q))
            return 0;
    return 1;
}

/* Merge q into p and re-sequence positions a..b as [not in S] p+q [in S] tombstones; the new place of p. */
static size_t merge_apply(orderer *o, merger *m, size_t a, uint32_t qid, int flip)
{
    uint32_t pid = m->seq[a], x;
    piece *p = &o->pc[pid], *q = &o->pc[qid];
    size_t b = m->pos[qid], at = a, w;
    if (flip)
        p->dir = -p->dir;
    p->lo = p->lo < q->lo ? p->lo : q->lo;
    p->hi = p->hi > q->hi ? p->hi : q->hi;
    p->box = amp_box3_union(p->box, q->box);
    for (x = q->lo; x <= q->hi; x++)
        m->owner[x] = pid;
    for (w = 0; w < m->nwin; w++)
        if (!m->ins[w]) {
            m->seq[at] = m->win[w];
            m->pos[m->win[w]] = (uint32_t)at++;
        }
    m->seq[at] = pid;
    m->pos[pid] = (uint32_t)at;
    a = at++;
    for (w = 0; w < m->nwin; w++)
        if (m->ins[w]) {
            m->seq[at] = m->win[w];
            m->pos[m->win[w]] = (uint32_t)at++;
        }
    for (; at <= b; at++)
        m->seq[at] = NONE;
    return a;
}

/* The sub-curves in their new order, merged-away slots dropped. */
static amp_status merge_compact(orderer *o, const merger *m)
{
    size_t n = o->npc, i, k = 0;
    piece *np = amp_calloc(o->a, n ? n : 1, sizeof *np);
    if (!np)
        return amp_fail(o->err, AMP_ERR_NOMEM, 0, "out of memory for merging");
    for (i = 0; i < n; i++)
        if (m->seq[i] != NONE)
            np[k++] = o->pc[m->seq[i]];
    if (k) /* an empty input has no sub-curve array at all */
        memcpy(o->pc, np, k * sizeof *np);
    o->npc = k;
    amp_free(o->a, np);
    return AMP_OK;
}

/* One bottom-up pass [P1 §5.1]: each sub-curve in print order absorbs the sub-curves that continue it while
 * G_a stays acyclic. */
static amp_status merge_pass(orderer *o, size_t *merged_out)
{
    merger m;
    size_t a, merged = 0;
    amp_status st;
    if ((st = merge_init(o, &m)) != AMP_OK)
        return st;
    for (a = 0; a < o->npc; a++) {
        for (;;) {
            uint32_t qid;
            int flip;
            if (m.seq[a] == NONE)
                break;
            qid = merge_partner(o, &m, a, &flip);
            if (qid == NONE || !merge_window(o, &m, a, m.pos[qid]) ||
                !merge_keeps_acyclic(o, &m, &o->pc[m.seq[a]], &o->pc[qid]))
                break;
            a = merge_apply(o, &m, a, qid, flip);
            merged++;
        }
    }
    st = merge_compact(o, &m);
    merge_free(o, &m);
    if (st == AMP_OK)
        *merged_out = merged;
    return st;
}

/* Consecutive sub-curves in print order that continue each other on their curve (the second starts at the
 * fragment after the first one's last, in the same direction) are one sub-curve: the same fragments in the
 * same order, one cut fewer. The re-sequencing makes such pairs (a curve continued as soon as its next
 * sub-curve is admissible, at no travel). */
static size_t join_contiguous(orderer *o)
{
    size_t i, m = 0, joined = 0;
    for (i = 0; i < o->npc; i++) {
        piece *p = m ? &o->pc[m - 1] : NULL, *q = &o->pc[i];
        if (p && p->path == q->path && p->dir == q->dir &&
            ((p->dir > 0 && q->lo == p->hi + 1) || (p->dir < 0 && q->hi + 1 == p->lo))) {
            p->lo = p->lo < q->lo ? p->lo : q->lo;
            p->hi = p->hi > q->hi ? p->hi : q->hi;
            p->box = amp_box3_union(p->box, q->box);
            joined++;
            continue;
        }
        o->pc[m++] = *q;
    }
    o->npc = m;
    return joined;
}

/* Re-sequence the sub-curves for travel (lib/order_seq.c) on the hierarchy with every fragment active again,
 * then join the ones that continue each other. */
static amp_status travel_pass(orderer *o)
{
    amp_status st;
    amp_fbvh_reactivate(&o->bvh);
    st = amp_order_resequence(o->fs, &o->bvh, o->h->z_offs, o->k, o->o->travel_z_weight, o->pc, o->npc, o->a, o->err,
                              &o->st.queries);
    if (st == AMP_OK)
        o->st.merges += join_contiguous(o);
    return st;
}

/* ---- output ---- */

/* The cut point after fragment f of run p (in print direction) need not be written: it lies on a straight
 * stretch between the point before it and the next fragment's first point (no turn, relative 1e-9), or
 * within 1e-9 mm of one of them. */
static int cut_is_straight(const orderer *o, const amp_pathset *in, const piece *p, uint32_t f)
{
    const amp_fragment *a = &o->fs->frag[p->dir > 0 ? p->lo + f : p->hi - f];
    const amp_fragment *b = &o->fs->frag[p->dir > 0 ? p->lo + f + 1 : p->hi - f - 1];
    amp_vec3 c = p->dir > 0 ? a->p1 : a->p0, prev, next, u, w;
    if (a->nin)
        prev = in->verts[a->vfirst + (p->dir > 0 ? a->nin - 1 : 0)].p;
    else
        prev = p->dir > 0 ? a->p0 : a->p1;
    if (b->nin)
        next = in->verts[b->vfirst + (p->dir > 0 ? 0 : b->nin - 1)].p;
    else
        next = p->dir > 0 ? b->p1 : b->p0;
    u = amp_v3_sub(c, prev);
    w = amp_v3_sub(next, c);
    if (amp_v3_len2(u) <= 1e-18 || amp_v3_len2(w) <= 1e-18)
        return 1; /* the cut falls on a vertex that is written anyway */
    return amp_v3_dot(u, w) > 0 &&
           amp_v3_len2(amp_v3_cross(u, w)) <= 1e-18 * amp_v3_len2(u) * amp_v3_len2(w);
}

static amp_status emit(const orderer *o, const amp_pathset *in, amp_pathset *out, amp_error *err)
{
    size_t i;
    for (i = 0; i < o->npc; i++) {
        const piece *p = &o->pc[i];
        uint32_t f, q;
        amp_status st = amp_pathset_begin(out, in->paths[p->path].role, err);
        for (f = 0; st == AMP_OK && f <= p->hi - p->lo; f++) {
            const amp_fragment *fr = &o->fs->frag[p->dir > 0 ? p->lo + f : p->hi - f];
            if (f == 0)
                st = p->dir > 0 ? amp_pathset_push(out, fr->p0, fr->r0, err) : amp_pathset_push(out, fr->p1, fr->r1, err);
            for (q = 0; st == AMP_OK && q < fr->nin; q++) {
                const amp_pvert *v = &in->verts[fr->vfirst + (p->dir > 0 ? q : fr->nin - 1 - q)];
                st = amp_pathset_push_merged(out, v->p, v->r, AMP_PATH_SAME_POINT, 0, err);
            }
            /* consecutive fragments share their cut point; a one-vertex path is a single point. A cut point
             * inside a run lies on a segment of the input: it is written only where it is a corner (an input
             * vertex at the cut), so the output keeps the input's vertices, not one per fragment. A cut that
             * falls within a nanometre of an input vertex is that vertex (the demo helix had 427 such pairs). */
            if (st == AMP_OK && in->paths[p->path].n > 1 &&
                (f == p->hi - p->lo || !cut_is_straight(o, in, p, f)))
                st = amp_pathset_push_merged(out, p->dir > 0 ? fr->p1 : fr->p0, p->dir > 0 ? fr->r1 : fr->r0,
                                             AMP_PATH_SAME_POINT, f == p->hi - p->lo, err);
        }
        if (st != AMP_OK)
            return st;
    }
    return AMP_OK;
}

/* Alg. 2, line 4 for the initial set: independent queries, run in parallel, applied in fragment order. */
static amp_status initial_set(orderer *o)
{
    size_t i, n = o->fs->n, nr = 0;
    long f;
#pragma omp parallel for schedule(dynamic, 256)
    for (f = 0; f < (long)n; f++)
        o->found[f] =
            amp_fbvh_find_any_below(&o->bvh, o->fs, o->h->z_offs, o->k, (uint32_t)f, o->done, NONE, &o->clear[f]);
    o->st.queries += n;
    for (i = 0; i < n; i++) {
        uint32_t g = o->found[i];
        if (g == NONE)
            o->batch[nr++] = (uint32_t)i;
        else {
            o->wnext[i] = o->whead[g];
            o->whead[g] = (uint32_t)i;
            o->waits[i] = g;
        }
    }
    return enter_batch(o, o->batch, o->found, nr);
}

static void orderer_free(orderer *o)
{
    amp_fbvh_free(&o->bvh);
    amp_free(o->a, o->done);
    amp_free(o->a, o->ready);
    amp_free(o->a, o->whead);
    amp_free(o->a, o->wnext);
    amp_free(o->a, o->rs);
    amp_free(o->a, o->re);
    amp_free(o->a, o->rz);
    amp_free(o->a, o->waits);
    amp_free(o->a, o->clear);
    amp_free(o->a, o->batch);
    amp_free(o->a, o->sorttmp);
    amp_free(o->a, o->found);
    amp_heap_free(&o->heap);
    amp_free(o->a, o->pc);
    rgrid_free(o->a, &o->grid);
}

/* The orderer's working arrays over n fragments. */
static amp_status orderer_alloc(orderer *o, size_t n)
{
    size_t i;
    o->done = amp_calloc(o->a, n + 1, 1);
    o->ready = amp_calloc(o->a, n + 1, 1);
    o->whead = amp_calloc(o->a, n + 1, sizeof *o->whead);
    o->wnext = amp_calloc(o->a, n + 1, sizeof *o->wnext);
    o->rs = amp_calloc(o->a, n + 1, sizeof *o->rs);
    o->re = amp_calloc(o->a, n + 1, sizeof *o->re);
    o->rz = amp_calloc(o->a, n + 1, sizeof *o->rz);
    o->waits = amp_calloc(o->a, n + 1, sizeof *o->waits);
    o->clear = amp_calloc(o->a, n + 1, sizeof *o->clear);
    o->batch = amp_calloc(o->a, n + 1, sizeof *o->batch);
    o->found = amp_calloc(o->a, n + 1, sizeof *o->found);
    o->sorttmp = amp_calloc(o->a, n + 1, sizeof *o->sorttmp);
    if (!o->done || !o->ready || !o->whead || !o->wnext || !o->rs || !o->re || !o->rz || !o->waits || !o->clear ||
        !o->batch || !o->found || !o->sorttmp)
        return amp_fail(o->err, AMP_ERR_NOMEM, 0, "out of memory for ordering %lu fragments", (unsigned long)n);
    for (i = 0; i < n; i++)
        o->whead[i] = o->wnext[i] = o->clear[i] = NONE;
    return AMP_OK;
}

/* OrderCurves [P1 §5.1, Alg. 2, lines 3-8]: print a best sequence of the printable set B until every
 * fragment is printed. */
static amp_status order_curves(orderer *o)
{
    const amp_order_opts *opts = o->o;
    size_t n = o->fs->n, next_report = 0;
    amp_status st = initial_set(o);
    while (st == AMP_OK && o->nprinted < n) {
        st = opts->improve ? step_improved(o) : step_plain(o);
        if (opts->progress && o->nprinted >= next_report) {
            opts->progress(opts->progress_user, (double)o->nprinted / (double)n);
            next_report = o->nprinted + n / 256 + 1;
        }
    }
    return st;
}

/* Bottom-up merging [P1 §5.1] until a pass merges nothing (at most four passes); the merges into *merged. */
static amp_status merge_passes(orderer *o, size_t *merged)
{
    size_t m = 0, pass;
    amp_status st = AMP_OK;
    *merged = 0;
    for (pass = 0; pass < 4 && st == AMP_OK; pass++) {
        st = merge_pass(o, &m);
        *merged += m;
        if (m == 0)
            break;
    }
    return st;
}

/* Merging, then the cheapest admissible travel order of the final sub-curves. */
static amp_status improve_subcurves(orderer *o)
{
    size_t merged = 0;
    amp_status st = merge_passes(o, &merged);
    o->st.merges += merged;
    if (st == AMP_OK && o->o->travel_z_weight > 0.0 && o->npc > 1) {
        /* the sub-curves are final: print them in the cheapest admissible order. That order puts sub-curves of
         * one curve next to each other that Algorithm 2's order kept apart: merging again finds more (demo
         * helix: 4 531 -> 4 275 cuts), and the merged set is re-sequenced once more. */
        st = travel_pass(o);
        if (st == AMP_OK)
            st = merge_passes(o, &merged);
        else
            merged = 0;
        o->st.merges += merged;
        if (st == AMP_OK && merged)
            st = travel_pass(o);
    }
    return st;
}

amp_status amp_order(const amp_pathset *in, const amp_order_opts *opts, amp_pathset *out, amp_order_stats *stats,
                     amp_error *err)
{
    amp_order_opts defaults;
    amp_fragments fs;
    orderer o;
    amp_status st;
    size_t i;
    if (!in || !out)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_order: NULL pathset");
    if (!opts) {
        amp_order_opts_default(&defaults);
        opts = &defaults;
    }
    if ((st = amp_head_validate(&opts->head, err)) != AMP_OK)
        return st;
    /* Alg. 2, line 2: fragments shorter than z_offs, so that Lemma 5.1 holds (by the contact margin too: a
     * fragment's rise stays clear of its own cone's tip) */
    if ((st = amp_fragments_build(&fs, in, opts->head.z_offs + 4.0 * AMP_CONE_TOL, out->alloc, err)) != AMP_OK)
        return st;
    memset(&o, 0, sizeof o);
    o.a = out->alloc;
    o.fs = &fs;
    o.h = &opts->head;
    o.k = 1.0 / tan(opts->head.theta);
    o.o = opts;
    o.err = err;
    amp_heap_init(&o.heap, o.a, sizeof(runent), run_better, NULL);
    for (i = 0; i < in->npaths; i++)
        o.st.paths_in += in->paths[i].n > 0;
    o.st.fragments = fs.n;
    if ((st = amp_fbvh_build(&o.bvh, &fs, o.a, err)) != AMP_OK) {
        amp_fragments_free(&fs);
        return st;
    }
    if ((st = amp_fbvh_set_cone(&o.bvh, o.k, err)) != AMP_OK) {
        amp_fbvh_free(&o.bvh);
        amp_fragments_free(&fs);
        return st;
    }
    if ((st = orderer_alloc(&o, fs.n)) != AMP_OK)
        goto done;
    if (opts->improve && opts->nearest && fs.n > 0)
        st = rgrid_init(&o);
    if (st == AMP_OK)
        st = order_curves(&o);
    if (st == AMP_OK && opts->improve)
        st = improve_subcurves(&o);
    if (st == AMP_OK)
        st = emit(&o, in, out, err);
    o.st.pieces = o.npc;
    o.st.subdivisions = o.npc > o.st.paths_in ? o.npc - o.st.paths_in : 0;
    if (stats)
        *stats = o.st;
done:
    orderer_free(&o);
    amp_fragments_free(&fs);
    return st;
}
