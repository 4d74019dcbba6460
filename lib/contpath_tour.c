/* [P2 §4]: the crossover-free tour ([P2 §4.1] cycle
 * tree, [P2 §4.2] traversal).
 *
 * The clipped, patched K̃ of a region is a plane graph whose vertices all
 * have even degree; its 2-cells are the bounded faces of the embedding
 * (found from the rotation system: the edge ends at every vertex sorted by
 * angle). Faces of an Eulerian plane graph can be 2-coloured, so the depth
 * of a face — its distance from the outer face in the dual graph — differs
 * by exactly one across every edge. Edge e gets the level k = min(depth) of
 * its two sides; the level-k edges are the boundary of the union U_k of the
 * faces of depth <= k: the boundary cycles that Algorithm 1 peels off one
 * after the other (C_0 = boundary of K̃, then the cycles of the faces next
 * to it, ...: "concentric circles").
 *
 * FindBoundaryCycles (Algorithm 2): Hierholzer's algorithm on the level-k
 * edges with the paper's edge choice — leave a vertex by the level-k edge
 * next in clockwise order around the region U_k, so no sub-path crosses
 * another (Fig. 14) — and sub-circuits that meet at a vertex in adjacent
 * ends spliced into one circuit.
 *
 * CycleTree (Algorithm 1): pred(C) of a level-k cycle is a level-(k-1)
 * cycle it touches at a vertex where their ends are adjacent (a face of depth
 * k between them: such a vertex exists on every such face's boundary).
 *
 * Traversal (§4.2): at the vertex ṽ of a tree edge {C1, C2}, q = 2: after
 * C1's edge ẽ into ṽ take C2's ẽ'' (its end next to ẽ), after C2's ẽ''' take
 * C1's ẽ' — the transitions (ẽ, ẽ'), (ẽ'', ẽ''') become (ẽ, ẽ''), (ẽ''', ẽ').
 * With q > 2 cycles C1 ⊃ ... ⊃ Cq nested at ṽ the same splice is applied
 * along the tree path, C1-C2, C2-C3, ..., each between adjacent ends, which
 * yields the paper's restrictions ẽ1 -> ẽ2q(-1), ..., ẽ4 -> ẽ2. A splice at
 * adjacent ends keeps every transition of the vertex non-crossing, so the
 * final tour has no crossover; a child is run against its parent's sense.
 *
 * When the 2-colouring fails (degenerate geometry: an edge with one face on
 * both sides), the older transition system is used: ends paired with their
 * angular neighbour and closed curves merged at any vertex in adjacent ends
 * (union-find). It is also available as an option (AMP_TOUR_MERGE).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

typedef struct rot_end {
    size_t end; /* 2 * edge + side: side 0 leaves edge_u, side 1 leaves edge_v */
    double ang;
} rot_end;

static int cmp_rot(const void *a, const void *b)
{
    const rot_end *x = a, *y = b;
    size_t ex = x->end / 2, ey = y->end / 2;
    if (x->ang != y->ang)
        return x->ang < y->ang ? -1 : 1;
    /* equal directions: the two copies of a joining patch (both built from
     * the same polyline in the same direction). Ascending edge order at the
     * nodes where they start, descending where they end: the copies then
     * nest like the two sides of a thin digon, a planar rotation system. */
    if (ex == ey)
        return 0;
    if (x->end % 2 != y->end % 2)
        return x->end % 2 < y->end % 2 ? -1 : 1;
    return (ex < ey) == (x->end % 2 == 0) ? -1 : 1;
}

typedef struct tour {
    amp_cp_graph *g;
    const amp_allocator *al;
    size_t ne2;
    size_t *start;   /* CSR: ends at vertex v are rot[start[v] .. start[v + 1]) */
    rot_end *rot;    /* counter-clockwise around each vertex */
    size_t *pos;     /* pos[end]: its index in rot */
    size_t *partner; /* transition: the end taken after arriving by the other end */
    size_t *face;    /* face[end]: the face on the left of the half-edge */
    size_t *depth;   /* per face */
    size_t *level;   /* per edge */
    size_t *curve;   /* per edge: closed curve of the transition system */
    size_t *uf;      /* per curve: union-find of spliced curves */
    size_t nface, ncurve, maxlevel;
} tour;

static size_t end_at(const amp_cp_graph *g, size_t x) { return x % 2 ? g->edge_v[x / 2] : g->edge_u[x / 2]; }

/* Rotation system: ends grouped by vertex, sorted by angle. */
static void build_rotation(tour *t)
{
    amp_cp_graph *g = t->g;
    size_t i, v;
    for (i = 0; i < g->ne; i++) {
        t->start[g->edge_u[i] + 2]++;
        t->start[g->edge_v[i] + 2]++;
    }
    for (v = 0; v < g->nv; v++)
        t->start[v + 2] += t->start[v + 1];
    for (i = 0; i < t->ne2; i++) {
        size_t at = end_at(g, i), to = end_at(g, i ^ 1u);
        rot_end *re = &t->rot[t->start[at + 1]++];
        re->end = i;
        re->ang = atan2(g->v[to].y - g->v[at].y, g->v[to].x - g->v[at].x);
    }
    for (v = 0; v < g->nv; v++) {
        size_t d = t->start[v + 1] - t->start[v], j;
        if (d > 1)
            qsort(t->rot + t->start[v], d, sizeof *t->rot, cmp_rot);
        for (j = t->start[v]; j < t->start[v + 1]; j++)
            t->pos[t->rot[j].end] = j;
    }
}

/* End next to x around its vertex: +1 counter-clockwise, -1 clockwise. */
static size_t turn(const tour *t, size_t x, int dir)
{
    size_t v = end_at(t->g, x), s = t->start[v], d = t->start[v + 1] - s, p = t->pos[x] - s;
    return t->rot[s + (p + d + (size_t)(dir > 0 ? 1 : d - 1)) % d].end;
}

/* Faces (left of each half-edge: next = clockwise neighbour of the twin at
 * the head), the outer face of every component (least signed area), depths
 * by breadth-first search in the dual, edge levels. Returns 0 when the
 * depths do not differ by one across some edge (not 2-coloured). Scratch:
 * @p fl (ne2 + nface + 1 entries), @p area (one per face), @p queue, @p
 * compf (one per face / vertex). */
static int faces_and_levels(tour *t, size_t *fl, double *area, size_t *queue, size_t *compf)
{
    amp_cp_graph *g = t->g;
    size_t i, x, head = 0, tail = 0, *uf = t->uf, *fstart, *fitem;
    for (i = 0; i < t->ne2; i++)
        t->face[i] = NONE;
    for (i = 0; i < t->ne2; i++) {
        if (t->face[i] != NONE)
            continue;
        area[t->nface] = 0;
        for (x = i; t->face[x] == NONE; x = turn(t, x ^ 1u, -1)) {
            amp_vec2 a = g->v[end_at(g, x)], b = g->v[end_at(g, x ^ 1u)];
            t->face[x] = t->nface;
            area[t->nface] += a.x * b.y - b.x * a.y;
        }
        t->nface++;
    }
    /* CSR of the half-edges of every face */
    fstart = fl;
    fitem = fl + t->nface + 1;
    memset(fstart, 0, (t->nface + 1) * sizeof *fstart);
    for (i = 0; i < t->ne2; i++)
        fstart[t->face[i] + 1]++;
    for (i = 0; i < t->nface; i++)
        fstart[i + 1] += fstart[i];
    for (i = 0; i < t->ne2; i++)
        fitem[fstart[t->face[i]]++] = i;
    for (i = t->nface; i > 0; i--)
        fstart[i] = fstart[i - 1];
    fstart[0] = 0;
    /* per component of the graph, the face of least signed area is outer */
    for (i = 0; i < g->nv; i++)
        uf[i] = i;
    for (i = 0; i < g->ne; i++)
        amp_uf_union(uf, g->edge_u[i], g->edge_v[i]);
    for (i = 0; i < g->nv; i++)
        compf[i] = NONE;
    for (i = 0; i < t->ne2; i++) {
        size_t c = amp_uf_find(uf, end_at(g, i)), f = t->face[i];
        if (compf[c] == NONE || area[f] < area[compf[c]])
            compf[c] = f;
    }
    for (i = 0; i < t->nface; i++)
        t->depth[i] = NONE;
    for (i = 0; i < g->nv; i++)
        if (compf[i] != NONE && t->depth[compf[i]] == NONE) {
            t->depth[compf[i]] = 0;
            queue[tail++] = compf[i];
        }
    while (head < tail) {
        size_t f = queue[head++], k;
        for (k = fstart[f]; k < fstart[f + 1]; k++) {
            size_t h = t->face[fitem[k] ^ 1u];
            if (t->depth[h] == NONE) {
                t->depth[h] = t->depth[f] + 1;
                queue[tail++] = h;
            }
        }
    }
    t->maxlevel = 0;
    for (i = 0; i < g->ne; i++) {
        size_t a = t->depth[t->face[2 * i]], b = t->depth[t->face[2 * i + 1]];
        if (a == NONE || b == NONE || (a + 1 != b && b + 1 != a))
            return 0;
        t->level[i] = a < b ? a : b;
        if (t->level[i] > t->maxlevel)
            t->maxlevel = t->level[i];
    }
    return 1;
}

/* Hierholzer's edge choice (Fig. 14): at every vertex, a level-k end whose
 * left wedge lies deeper (depth k + 1, the far side of its boundary cycle)
 * is paired with the next level-k end counter-clockwise; the ends between
 * belong to deeper cycles, so the transitions of all levels nest. 0 if the
 * ends do not pair up so (not expected for a 2-coloured plane graph). */
static int boundary_transitions(tour *t)
{
    size_t v, i;
    for (i = 0; i < t->ne2; i++)
        t->partner[i] = NONE;
    for (v = 0; v < t->g->nv; v++) {
        size_t s = t->start[v], d = t->start[v + 1] - s;
        for (i = 0; i < d; i++) {
            size_t x = t->rot[s + i].end, k = t->level[x / 2], j;
            if (t->depth[t->face[x]] != k + 1)
                continue;
            for (j = 1; j < d; j++) {
                size_t y = t->rot[s + (i + j) % d].end;
                if (t->level[y / 2] < k)
                    return 0;
                if (t->level[y / 2] == k) {
                    if (t->partner[y] != NONE || t->depth[t->face[y]] != k)
                        return 0;
                    t->partner[x] = y;
                    t->partner[y] = x;
                    break;
                }
            }
        }
    }
    for (i = 0; i < t->ne2; i++)
        if (t->partner[i] == NONE)
            return 0;
    return 1;
}

/* The angular-neighbour transitions of the older method (fallback). */
static size_t neighbour_transitions(tour *t)
{
    size_t v, j, nodd = 0;
    for (v = 0; v < t->g->nv; v++) {
        size_t s = t->start[v], d = t->start[v + 1] - s;
        for (j = 0; j + 1 < d; j += 2) {
            t->partner[t->rot[s + j].end] = t->rot[s + j + 1].end;
            t->partner[t->rot[s + j + 1].end] = t->rot[s + j].end;
        }
        if (d % 2) {
            t->partner[t->rot[s + d - 1].end] = NONE; /* odd vertex: the curve ends here */
            nodd++;
        }
    }
    return nodd;
}

/* Closed curves of the transition system (open ones, from odd vertices, first). */
static void label_curves(tour *t, unsigned char *isopen)
{
    size_t i, x;
    t->ncurve = 0;
    for (i = 0; i < t->g->ne; i++)
        t->curve[i] = NONE;
    for (i = 0; i < t->ne2; i++) {
        if (t->partner[i] != NONE || t->curve[i / 2] != NONE)
            continue;
        for (x = i; x != NONE && t->curve[x / 2] == NONE; x = t->partner[x ^ 1u])
            t->curve[x / 2] = t->ncurve; /* leave by the other end, continue through its partner */
        isopen[t->ncurve++] = 1;
    }
    for (i = 0; i < t->g->ne; i++) {
        if (t->curve[i] != NONE)
            continue;
        for (x = 2 * i; x != NONE && t->curve[x / 2] == NONE; x = t->partner[x ^ 1u])
            t->curve[x / 2] = t->ncurve;
        isopen[t->ncurve++] = 0;
    }
    for (i = 0; i < t->ncurve; i++)
        t->uf[i] = i;
}

/* Splice the curves of adjacent ends x, y: transitions (x, a), (y, d)
 * become (x, y), (a, d) — the q = 2 restriction of §4.2 (after ẽ take ẽ'',
 * after ẽ''' take ẽ'). Neither new transition crosses another transition of
 * the vertex. Returns 1 if spliced. */
static int splice(tour *t, size_t x, size_t y, unsigned char *isopen)
{
    size_t a = t->partner[x], d = t->partner[y], cx, cy;
    if (a == y || a == NONE || d == NONE)
        return 0;
    cx = amp_uf_find(t->uf, t->curve[x / 2]);
    cy = amp_uf_find(t->uf, t->curve[y / 2]);
    if (cx == cy || (isopen[cx] && isopen[cy]))
        return 0; /* two open curves re-paired stay two open curves */
    t->partner[a] = d;
    t->partner[d] = a;
    t->partner[x] = y;
    t->partner[y] = x;
    t->uf[cx] = cy;
    isopen[cy] = (unsigned char)(isopen[cx] | isopen[cy]);
    return 1;
}

/* The splices of cycle_tree at vertex @p v for level @p k: pass 0 joins the level-k sub-circuits that meet
 * in adjacent ends, pass 1 hangs level-(k+1) cycles below level-k ones. Returns the pass-0 splices made. */
static size_t tree_vertex(tour *t, size_t v, size_t k, int pass, unsigned char *isopen)
{
    size_t s = t->start[v], d = t->start[v + 1] - s, p, same = 0;
    for (p = 0; d >= 4 && p < d; p++) {
        size_t x = t->rot[s + p].end, y = t->rot[s + (p + 1) % d].end;
        size_t lx = t->level[x / 2], ly = t->level[y / 2];
        if (pass == 0 && lx == k && ly == k)
            same += (size_t)splice(t, x, y, isopen);
        else if (pass == 1 && ((lx == k && ly == k + 1) || (lx == k + 1 && ly == k)))
            splice(t, x, y, isopen);
    }
    return same;
}

/* Bucket key of the adjacent ends x, y at a vertex: 2k + pass of the tree_vertex call they take part in,
 * NONE for none. */
static size_t pair_key(const tour *t, size_t x, size_t y)
{
    size_t lx = t->level[x / 2], ly = t->level[y / 2];
    if (lx == ly)
        return 2 * lx;
    if (lx == ly + 1 || ly == lx + 1)
        return 2 * (lx < ly ? lx : ly) + 1;
    return NONE;
}

/* The vertices of every (level, pass) in ascending order, by counting: at[first[key] .. first[key + 1]).
 * NULL on allocation failure (cycle_tree then visits every vertex at every level). */
static size_t *tree_buckets(tour *t, size_t nkey, size_t **first_out)
{
    size_t *first = amp_calloc(t->al, nkey + 2, sizeof *first), *last = amp_alloc(t->al, nkey * sizeof *last);
    size_t *at = NULL, v, p, key, n = 0, fill;
    for (fill = 0; fill < 2 && first && last; fill++) {
        for (key = 0; key < nkey; key++)
            last[key] = NONE;
        for (v = 0; v < t->g->nv; v++) {
            size_t s = t->start[v], d = t->start[v + 1] - s;
            for (p = 0; d >= 4 && p < d; p++) {
                key = pair_key(t, t->rot[s + p].end, t->rot[s + (p + 1) % d].end);
                if (key >= nkey || last[key] == v)
                    continue;
                last[key] = v;
                if (fill)
                    at[first[key + 1]++] = v;
                else
                    first[key + 2]++;
            }
        }
        if (!fill) {
            for (key = 0; key < nkey; key++)
                first[key + 2] += first[key + 1];
            n = first[nkey + 1];
            if (!(at = amp_alloc(t->al, (n + 1) * sizeof *at)))
                break;
        }
    }
    amp_free(t->al, last);
    if (!at || !first || !last) {
        amp_free(t->al, at);
        amp_free(t->al, first);
        return NULL;
    }
    *first_out = first;
    return at;
}

/* Algorithms 1 and 2 level by level, k = 0, 1, ...: FindBoundaryCycles
 * splices the level-k sub-circuits that meet in adjacent ends (one Euler
 * circuit per boundary cycle); then every level-(k+1) cycle is hung below a
 * level-k cycle at the first vertex where their ends are adjacent (pred, and
 * the traversal restriction there; several nested cycles at one vertex,
 * q > 2, are spliced one tree edge after the other). Returns the number of
 * boundary cycles (nodes of the cycle tree). Each level visits only the
 * vertices where it has adjacent ends (tree_buckets), in the order a scan
 * of every vertex would meet them: the same splices, in time linear in the
 * graph (the scan per level was quadratic in a solid skin's width: half of
 * slicing a 400 mm plate). */
static size_t cycle_tree(tour *t, unsigned char *isopen)
{
    size_t nkey = 2 * (t->maxlevel + 1), *first = NULL, *at = tree_buckets(t, nkey, &first), k, v, q, same = 0;
    int pass;
    for (k = 0; k <= t->maxlevel; k++)
        for (pass = 0; pass < 2; pass++)
            if (at)
                for (q = first[2 * k + (size_t)pass]; q < first[2 * k + (size_t)pass + 1]; q++)
                    same += tree_vertex(t, at[q], k, pass, isopen);
            else
                for (v = 0; v < t->g->nv; v++)
                    same += tree_vertex(t, v, k, pass, isopen);
    amp_free(t->al, at);
    amp_free(t->al, first);
    return t->ncurve - same;
}

/* The older merging (fallback, AMP_TOUR_MERGE): curves merged at any vertex
 * in adjacent ends, vertex by vertex. */
static void merge_any(tour *t, unsigned char *isopen)
{
    size_t v, p;
    for (v = 0; v < t->g->nv; v++) {
        size_t s = t->start[v], d = t->start[v + 1] - s;
        int again = 1;
        while (again && d >= 4) {
            again = 0;
            for (p = 0; p < d; p++)
                again |= splice(t, t->rot[s + p].end, t->rot[s + (p + 1) % d].end, isopen);
        }
    }
}

/* Trace the tours: open curves from their terminal, then closed ones from a
 * printed end with the outer face on its left (the root cycle run
 * clockwise around the region), then any printed end, then the rest. A
 * pseudo edge is written with radius 0 at both ends; where printing and
 * travel meet the vertex is written twice (a zero-length step), so no
 * segment mixes the two radii (docs/interfaces.md §5: mean radius). */
static amp_status trace(tour *t, double z, double rad, int by_level, amp_pathset *out, size_t *ntours,
                        unsigned char *used, amp_error *err)
{
    amp_cp_graph *g = t->g;
    int pass;
    size_t i;
    amp_status st = AMP_OK;
    for (pass = 0; pass < 4 && st == AMP_OK; pass++)
        for (i = 0; i < t->ne2 && st == AMP_OK; i++) {
            size_t x = i, first = i, at = end_at(g, x);
            double cur;
            if (used[i / 2] || (pass == 0 && t->partner[i] != NONE) ||
                (pass >= 1 && pass <= 2 && g->edge_pseudo[i / 2]) ||
                (pass == 1 && !(by_level && t->depth[t->face[i]] == 0)))
                continue;
            cur = g->edge_pseudo[i / 2] ? 0.0 : rad;
            if ((st = amp_pathset_begin(out, AMP_ROLE_OBJECT, err)) != AMP_OK)
                break;
            st = amp_pathset_push(out, amp_v3(g->v[at].x, g->v[at].y, z), cur, err);
            while (st == AMP_OK) {
                size_t e = x / 2, to = end_at(g, x ^ 1u);
                double r = g->edge_pseudo[e] ? 0.0 : rad;
                used[e] = 1;
                if (r != cur)
                    st = amp_pathset_push(out, amp_v3(g->v[at].x, g->v[at].y, z), r, err);
                if (st == AMP_OK)
                    st = amp_pathset_push(out, amp_v3(g->v[to].x, g->v[to].y, z), r, err);
                cur = r;
                at = to;
                x = t->partner[x ^ 1u];
                if (x == NONE || x == first || used[x / 2])
                    break;
            }
            (*ntours)++;
        }
    return st;
}

amp_status amp_cp_tour(amp_cp_graph *g, double z, double rad, int method, amp_pathset *out, amp_cp_tour_info *info,
                       amp_error *err)
{
    const amp_allocator *al = g->al;
    tour t;
    size_t ne2 = 2 * g->ne, n = (g->nv > ne2 ? g->nv : ne2) + 2;
    unsigned char *used = NULL, *isopen = NULL;
    size_t *fl = NULL, *queue = NULL, *compf = NULL;
    double *area = NULL;
    int by_level = 0;
    amp_status st = AMP_OK;
    memset(info, 0, sizeof *info);
    if (g->ne == 0)
        return AMP_OK;
    memset(&t, 0, sizeof t);
    t.g = g;
    t.al = al;
    t.ne2 = ne2;
    /* faces <= ne2, curves <= ne, vertices nv: n bounds every per-item array */
    t.start = amp_calloc(al, g->nv + 2, sizeof *t.start);
    t.rot = amp_alloc(al, ne2 * sizeof *t.rot);
    t.pos = amp_alloc(al, ne2 * sizeof *t.pos);
    t.partner = amp_alloc(al, ne2 * sizeof *t.partner);
    t.face = amp_alloc(al, ne2 * sizeof *t.face);
    t.depth = amp_alloc(al, n * sizeof *t.depth);
    t.level = amp_alloc(al, g->ne * sizeof *t.level);
    t.curve = amp_alloc(al, g->ne * sizeof *t.curve);
    t.uf = amp_alloc(al, n * sizeof *t.uf);
    fl = amp_alloc(al, (ne2 + n + 2) * sizeof *fl);
    queue = amp_alloc(al, n * sizeof *queue);
    compf = amp_alloc(al, n * sizeof *compf);
    area = amp_alloc(al, n * sizeof *area);
    used = amp_calloc(al, g->ne, 1);
    isopen = amp_calloc(al, n, 1);
    if (!t.start || !t.rot || !t.pos || !t.partner || !t.face || !t.depth || !t.level || !t.curve || !t.uf || !fl ||
        !queue || !compf || !area || !used || !isopen) {
        st = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the tour");
        goto done;
    }
    build_rotation(&t);
    if (method == AMP_TOUR_CYCLE_TREE) {
        by_level = faces_and_levels(&t, fl, area, queue, compf) && boundary_transitions(&t);
        info->fallback = !by_level;
    }
    if (by_level) {
        label_curves(&t, isopen);
        info->cycles = cycle_tree(&t, isopen);
        info->levels = t.maxlevel + 1;
    } else {
        info->nodd = neighbour_transitions(&t);
        label_curves(&t, isopen);
        merge_any(&t, isopen);
    }
    st = trace(&t, z, rad, by_level, out, &info->ntours, used, err);
done:
    amp_free(al, t.start);
    amp_free(al, t.rot);
    amp_free(al, t.pos);
    amp_free(al, t.partner);
    amp_free(al, t.face);
    amp_free(al, t.depth);
    amp_free(al, t.level);
    amp_free(al, t.curve);
    amp_free(al, t.uf);
    amp_free(al, fl);
    amp_free(al, queue);
    amp_free(al, compf);
    amp_free(al, area);
    amp_free(al, used);
    amp_free(al, isopen);
    return st;
}
