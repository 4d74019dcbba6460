/* BVH over fragment boxes: the accelerated below relation of [P1 §5.1] (see order_fragbvh.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "order_fragbvh.h"

#define LEAF_SIZE 4
#define STACK_MAX 128

#define DIAG 0.70710678118654752440
static const double dir_x[AMP_FBVH_NDIR] = {1.0, -1.0, 0.0, 0.0, DIAG, DIAG, -DIAG, -DIAG};
static const double dir_y[AMP_FBVH_NDIR] = {0.0, 0.0, 1.0, -1.0, DIAG, -DIAG, DIAG, -DIAG};

/* The highest u.q over the xy box (the corner furthest along u). */
static inline double box_maxproj(const amp_fbvh_box5 *bx, int u)
{
    return (dir_x[u] > 0.0 ? dir_x[u] * bx->x1 : dir_x[u] * bx->x0) +
           (dir_y[u] > 0.0 ? dir_y[u] * bx->y1 : dir_y[u] * bx->y0);
}

/* The lowest u.p over the box (the corner furthest against u). */
static inline double box_minproj(const amp_box3 *bx, int u)
{
    return (dir_x[u] > 0.0 ? dir_x[u] * bx->min.x : dir_x[u] * bx->max.x) +
           (dir_y[u] > 0.0 ? dir_y[u] * bx->min.y : dir_y[u] * bx->max.y);
}

static void dmin_empty(amp_fbvh_cone *a)
{
    int u;
    for (u = 0; u < AMP_FBVH_NDIR; u++)
        a->m[u] = HUGE_VAL;
}

/* the cone bounds of leaf @p id from its fragments not done (done NULL: all) */
static void dmin_leaf(amp_fbvh *b, const unsigned char *done, uint32_t id)
{
    amp_fbvh_cone *a = &b->cone[id];
    uint32_t q;
    int u;
    dmin_empty(a);
    for (q = b->act[id].lo; q < b->act[id].hi; q++) {
        const amp_fbvh_box5 *fb = &b->fbox[q];
        if (done && done[b->order[q]])
            continue;
        for (u = 0; u < AMP_FBVH_NDIR; u++)
            a->m[u] = amp_dmin(a->m[u], fb->minz - b->k * box_maxproj(fb, u));
    }
}

/* node p's cone bounds from its children's; 1 when they changed */
static int dmin_merge(amp_fbvh *b, uint32_t p)
{
    amp_fbvh_cone *a = &b->cone[p];
    const amp_fbvh_cone *l = &b->cone[b->act[p].left], *r = &b->cone[b->act[p].right];
    int u, changed = 0;
    for (u = 0; u < AMP_FBVH_NDIR; u++) {
        double m = amp_dmin(l->m[u], r->m[u]);
        changed |= m != a->m[u];
        a->m[u] = m;
    }
    return changed;
}

static void dmin_fill(amp_fbvh *b, const unsigned char *done)
{
    size_t i;
    for (i = b->nnodes; i-- > 0;) {
        if (b->act[i].left == 0)
            dmin_leaf(b, done, (uint32_t)i);
        else
            dmin_merge(b, (uint32_t)i);
    }
}

static void rank_fill(amp_fbvh *b);

amp_status amp_fbvh_set_cone(amp_fbvh *b, double k, amp_error *err)
{
    if (b->nnodes == 0)
        return AMP_OK;
    if (!b->cone_mem) {
        b->cone_mem = amp_calloc(b->alloc, b->nnodes + 1, sizeof *b->cone);
        if (!b->cone_mem)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the fragment hierarchy's cone bounds");
        b->cone = (amp_fbvh_cone *)(((uintptr_t)b->cone_mem + 63u) & ~(uintptr_t)63u);
    }
    b->k = k;
    dmin_fill(b, NULL);
    return AMP_OK;
}

typedef struct mkey {
    uint64_t code;
    uint32_t id;
} mkey;

static int mkey_cmp(const void *a, const void *b)
{
    const mkey *x = a, *y = b;
    if (x->code != y->code)
        return x->code < y->code ? -1 : 1;
    return x->id < y->id ? -1 : (x->id > y->id);
}

/* spread the low 21 bits of v to every third bit */
static uint64_t spread3(uint64_t v)
{
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

static uint64_t quantise(double x, double lo, double hi)
{
    double t = hi > lo ? (x - lo) / (hi - lo) : 0.0;
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    return (uint64_t)(t * 2097151.0);
}

void amp_fbvh_free(amp_fbvh *b)
{
    if (!b)
        return;
    amp_free(b->alloc, b->node);
    amp_free(b->alloc, b->act_mem);
    amp_free(b->alloc, b->cone_mem);
    amp_free(b->alloc, b->frank);
    amp_free(b->alloc, b->fbox);
    amp_free(b->alloc, b->order);
    amp_free(b->alloc, b->leaf);
    memset(b, 0, sizeof *b);
}

/* The fragments in Morton order of their box centres (order, fbox): neighbours in the order are near in space,
 * so that ranges of it make tight boxes. */
static amp_status fbvh_sort_morton(amp_fbvh *b, const amp_fragments *fs, const amp_allocator *a, amp_error *err)
{
    size_t n = fs->n, i;
    amp_box3 all = amp_box3_empty();
    mkey *keys = amp_calloc(a, n, sizeof *keys);
    if (!keys)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the fragment hierarchy");
    for (i = 0; i < n; i++)
        all = amp_box3_union(all, fs->frag[i].box);
    for (i = 0; i < n; i++) {
        amp_vec3 c = amp_box3_center(fs->frag[i].box);
        keys[i].code = spread3(quantise(c.x, all.min.x, all.max.x)) | spread3(quantise(c.y, all.min.y, all.max.y)) << 1 |
                       spread3(quantise(c.z, all.min.z, all.max.z)) << 2;
        keys[i].id = (uint32_t)i;
    }
    qsort(keys, n, sizeof *keys, mkey_cmp);
    for (i = 0; i < n; i++) {
        const amp_box3 *bx = &fs->frag[keys[i].id].box;
        b->order[i] = keys[i].id;
        b->fbox[i].x0 = bx->min.x;
        b->fbox[i].y0 = bx->min.y;
        b->fbox[i].x1 = bx->max.x;
        b->fbox[i].y1 = bx->max.y;
        b->fbox[i].minz = bx->min.z;
    }
    amp_free(a, keys);
    return AMP_OK;
}

/* Split ranges of the Morton order at their middle: depth is log2(n / LEAF_SIZE). */
static void fbvh_split_ranges(amp_fbvh *b, size_t n)
{
    uint32_t stack[STACK_MAX];
    size_t top = 0;
    b->nnodes = 1;
    b->node[0].lo = 0;
    b->node[0].hi = (uint32_t)n;
    b->node[0].parent = AMP_FBVH_NONE;
    stack[top++] = 0;
    while (top) {
        uint32_t id = stack[--top];
        amp_fbvh_node *nd = &b->node[id];
        if (nd->hi - nd->lo <= LEAF_SIZE) {
            uint32_t q;
            for (q = nd->lo; q < nd->hi; q++)
                b->leaf[b->order[q]] = id;
            continue;
        } else {
            uint32_t mid = nd->lo + (nd->hi - nd->lo) / 2, l = (uint32_t)b->nnodes, r = l + 1;
            b->node[l].lo = nd->lo;
            b->node[l].hi = mid;
            b->node[r].lo = mid;
            b->node[r].hi = nd->hi;
            b->node[l].parent = b->node[r].parent = id;
            nd->left = l;
            nd->right = r;
            b->nnodes += 2;
            stack[top++] = l;
            stack[top++] = r;
        }
    }
}

/* The nodes' boxes and their compact copies (act). Children always follow their parent: fill backwards. */
static void fbvh_fill_boxes(amp_fbvh *b, const amp_fragments *fs)
{
    size_t i;
    for (i = b->nnodes; i-- > 0;) {
        amp_fbvh_node *nd = &b->node[i];
        if (nd->left == 0) {
            uint32_t q;
            nd->box = amp_box3_empty();
            for (q = nd->lo; q < nd->hi; q++)
                nd->box = amp_box3_union(nd->box, fs->frag[b->order[q]].box);
        } else {
            nd->box = amp_box3_union(b->node[nd->left].box, b->node[nd->right].box);
        }
        nd->minz = nd->box.min.z;
        b->act[i].bx.x0 = nd->box.min.x;
        b->act[i].bx.y0 = nd->box.min.y;
        b->act[i].bx.x1 = nd->box.max.x;
        b->act[i].bx.y1 = nd->box.max.y;
        b->act[i].bx.minz = nd->minz;
        b->act[i].left = nd->left;
        b->act[i].right = nd->right;
        b->act[i].lo = nd->lo;
        b->act[i].hi = nd->hi;
        b->act[i].parent = nd->parent;
    }
}

amp_status amp_fbvh_build(amp_fbvh *b, const amp_fragments *fs, const amp_allocator *a, amp_error *err)
{
    size_t n = fs->n;
    amp_status st;
    memset(b, 0, sizeof *b);
    b->alloc = a;
    b->k = NAN;
    if (n == 0)
        return AMP_OK;
    b->node = amp_calloc(a, 2 * n + 1, sizeof *b->node);
    b->fbox = amp_calloc(a, n, sizeof *b->fbox);
    b->order = amp_calloc(a, n, sizeof *b->order);
    b->leaf = amp_calloc(a, n, sizeof *b->leaf);
    if (!b->node || !b->fbox || !b->order || !b->leaf) {
        amp_fbvh_free(b);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the fragment hierarchy");
    }
    if ((st = fbvh_sort_morton(b, fs, a, err)) != AMP_OK) {
        amp_fbvh_free(b);
        return st;
    }
    fbvh_split_ranges(b, n);
    /* the tree has about n / 2 nodes of the 2 n + 1 reserved: return the rest (a failed shrink keeps the block) */
    {
        amp_fbvh_node *shrunk = amp_realloc_array(a, b->node, b->nnodes, sizeof *b->node);
        if (shrunk)
            b->node = shrunk;
    }
    b->act_mem = amp_calloc(a, b->nnodes + 1, sizeof *b->act);
    b->act = b->act_mem ? (amp_fbvh_act *)(((uintptr_t)b->act_mem + 63u) & ~(uintptr_t)63u) : NULL;
    if (!b->act) {
        amp_fbvh_free(b);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the fragment hierarchy");
    }
    fbvh_fill_boxes(b, fs);
    return AMP_OK;
}

void amp_fbvh_reactivate(amp_fbvh *b)
{
    size_t i;
    for (i = 0; i < b->nnodes; i++) {
        const amp_box3 *bx = &b->node[i].box;
        b->node[i].minz = bx->min.z;
        b->act[i].bx.x0 = bx->min.x;
        b->act[i].bx.y0 = bx->min.y;
        b->act[i].bx.x1 = bx->max.x;
        b->act[i].bx.y1 = bx->max.y;
        b->act[i].bx.minz = bx->min.z;
    }
    if (b->cone)
        dmin_fill(b, NULL);
    if (b->frank)
        rank_fill(b);
}


/* The unprinted bounds of leaf @p id from its fragments. */
static void act_leaf(amp_fbvh *b, const unsigned char *done, uint32_t id)
{
    amp_fbvh_box5 *a = &b->act[id].bx;
    uint32_t q, mr = b->frank ? AMP_FBVH_NONE : 0;
    a->x0 = a->y0 = a->minz = HUGE_VAL;
    a->x1 = a->y1 = -HUGE_VAL;
    for (q = b->act[id].lo; q < b->act[id].hi; q++) {
        const amp_fbvh_box5 *fb = &b->fbox[q];
        if (done[b->order[q]])
            continue;
        if (b->frank && b->frank[q] < mr)
            mr = b->frank[q];
        a->x0 = amp_dmin(a->x0, fb->x0);
        a->y0 = amp_dmin(a->y0, fb->y0);
        a->x1 = amp_dmax(a->x1, fb->x1);
        a->y1 = amp_dmax(a->y1, fb->y1);
        a->minz = amp_dmin(a->minz, fb->minz);
    }
    b->act[id].minrank = mr;
}

/* the lowest rank below each node, all fragments unprinted */
static void rank_fill(amp_fbvh *b)
{
    size_t i;
    for (i = b->nnodes; i-- > 0;) {
        amp_fbvh_act *a = &b->act[i];
        uint32_t q, mr = b->frank ? AMP_FBVH_NONE : 0, l, r;
        if (b->frank && a->left == 0) {
            for (q = a->lo; q < a->hi; q++)
                mr = b->frank[q] < mr ? b->frank[q] : mr;
        } else if (b->frank) {
            l = b->act[a->left].minrank;
            r = b->act[a->right].minrank;
            mr = l < r ? l : r;
        }
        a->minrank = mr;
    }
}

amp_status amp_fbvh_set_rank(amp_fbvh *b, const uint32_t *rank, amp_error *err)
{
    size_t n = b->nnodes ? b->act[0].hi : 0, q;
    if (!rank) {
        amp_free(b->alloc, b->frank);
        b->frank = NULL;
    } else if (n) {
        if (!b->frank && !(b->frank = amp_calloc(b->alloc, n, sizeof *b->frank))) {
            rank_fill(b);
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the fragment hierarchy's ranks");
        }
        for (q = 0; q < n; q++)
            b->frank[q] = rank[b->order[q]];
    }
    rank_fill(b);
    return AMP_OK;
}

void amp_fbvh_deactivate(amp_fbvh *b, const amp_fragments *fs, const unsigned char *done, uint32_t f)
{
    uint32_t id = b->leaf[f];
    int cone = b->cone != NULL, dchanged;
    (void)fs;
    act_leaf(b, done, id);
    if (cone)
        dmin_leaf(b, done, id);
    b->node[id].minz = b->act[id].bx.minz;
    /* the printed regions shrink out of the boxes: the queries below prune on what is still unprinted */
    while (b->act[id].parent != AMP_FBVH_NONE) {
        uint32_t p = b->act[id].parent;
        const amp_fbvh_box5 *l = &b->act[b->act[p].left].bx, *r = &b->act[b->act[p].right].bx;
        amp_fbvh_box5 *a = &b->act[p].bx;
        double x0 = amp_dmin(l->x0, r->x0), y0 = amp_dmin(l->y0, r->y0), x1 = amp_dmax(l->x1, r->x1), y1 = amp_dmax(l->y1, r->y1);
        double mz = amp_dmin(l->minz, r->minz);
        uint32_t lr = b->act[b->act[p].left].minrank, rr = b->act[b->act[p].right].minrank, mr = lr < rr ? lr : rr;
        dchanged = cone && dmin_merge(b, p);
        if (x0 == a->x0 && y0 == a->y0 && x1 == a->x1 && y1 == a->y1 && mz == a->minz && !dchanged &&
            mr == b->act[p].minrank)
            break;
        b->act[p].minrank = mr;
        a->x0 = x0;
        a->y0 = y0;
        a->x1 = x1;
        a->y1 = y1;
        a->minz = b->node[p].minz = mz;
        id = p;
    }
}

uint32_t amp_fbvh_find_below(const amp_fbvh *b, const amp_fragments *fs, const amp_head *h, uint32_t f,
                             const unsigned char *done, size_t *tests)
{
    uint32_t stack[STACK_MAX];
    size_t top = 0, ntests = 0;
    const amp_fragment *fr = &fs->frag[f];
    double k = 1.0 / tan(h->theta), reach = fr->box.max.z - h->z_offs - AMP_CONE_TOL, bestz = -HUGE_VAL;
    uint32_t found = AMP_FBVH_NONE;
    if (b->nnodes == 0)
        return found;
    stack[top++] = 0;
    /* Branch and bound for a blocker whose lowest point is high: it tends to be printed last of all the
     * fragments below f, so f is rarely woken up again before it becomes printable. The search stops at one
     * within 2 z_offs of the highest possible, so that wide flat layers are not scanned in full. */
    while (top && bestz < reach - 2.0 * h->z_offs) {
        const amp_fbvh_node *nd = &b->node[stack[--top]];
        /* a fragment g below f needs a point lower than f's top by z_offs plus the cone's run over the xy gap */
        if (nd->minz >= reach - k * amp_box_xy_gap(nd->box, fr->box) || nd->box.max.z <= bestz)
            continue;
        if (nd->left == 0) {
            uint32_t q;
            for (q = nd->lo; q < nd->hi; q++) {
                uint32_t g = b->order[q];
                if (g == f || done[g] || fs->frag[g].box.min.z <= bestz)
                    continue;
                ntests++;
                if (amp_fragment_below_k(fs, h->z_offs, k, g, f)) {
                    found = g;
                    bestz = fs->frag[g].box.min.z;
                }
            }
        } else if (top + 2 <= STACK_MAX) {
            /* the higher child is searched first, so that the bound tightens early */
            const amp_fbvh_node *l = &b->node[nd->left], *r = &b->node[nd->right];
            if (l->box.max.z > r->box.max.z) {
                stack[top++] = nd->right;
                stack[top++] = nd->left;
            } else {
                stack[top++] = nd->left;
                stack[top++] = nd->right;
            }
        }
    }
    if (tests)
        *tests += ntests;
    return found;
}

/* How deep a node's unprinted fragments may reach into the cone under fragment box @p fb: the room under f's
 * reach and the xy gap, squared; nothing under the node can be below f unless room > 0 and k^2 gap^2 < room^2. */
static inline double act_reach2(const amp_fbvh_box5 *nd, double reach, double k2, const amp_box3 *fb, double *room)
{
    double gx, gy, ex, ey;
    *room = reach - nd->minz;
    gx = nd->x0 - fb->max.x;
    ex = fb->min.x - nd->x1;
    gy = nd->y0 - fb->max.y;
    ey = fb->min.y - nd->y1;
    gx = gx > ex ? gx : ex;
    gy = gy > ey ? gy : ey;
    gx = gx > 0.0 ? gx : 0.0;
    gy = gy > 0.0 ? gy : 0.0;
    return k2 * (gx * gx + gy * gy);
}

static inline int act_pass(const amp_fbvh_box5 *nd, double reach, double k2, const amp_box3 *fb)
{
    double room, g2 = act_reach2(nd, reach, k2, fb, &room);
    return room > 0.0 && g2 < room * room;
}

/* room minus the cone's run over the gap (mm), or -1 when the node cannot hold a fragment below f */
static inline double act_slack(const amp_fbvh_box5 *nd, double reach, double k2, const amp_box3 *fb)
{
    double room, g2 = act_reach2(nd, reach, k2, fb, &room);
    if (!(room > 0.0 && g2 < room * room))
        return -1.0;
    return g2 > 0.0 ? room - sqrt(g2) : room; /* over f's own box (no gap) no root: the sqrt was 30 % of the search */
}

/* One blocker query's bounds: the fragment's box, its reach, and for the nodes' cone bounds (when the hierarchy
 * holds them for this k) c_u = k min u.p over the box minus the reach: a node with m_u + c_u >= 0 for some u
 * holds no fragment below any point of the box. */
typedef struct coneq {
    const amp_box3 *fb;
    double reach, k2;
    int dir;
    uint32_t rank; /* only fragments ranked below it count (AMP_FBVH_NONE: all) */
    double c[AMP_FBVH_NDIR];
} coneq;

static inline void coneq_init(coneq *c, const amp_fbvh *b, double k, const amp_box3 *fb, double reach, uint32_t rank)
{
    int u;
    c->rank = b->frank ? rank : AMP_FBVH_NONE;
    c->fb = fb;
    c->reach = reach;
    c->k2 = k * k;
    c->dir = b->cone && b->k == k;
    if (c->dir)
        for (u = 0; u < AMP_FBVH_NDIR; u++)
            c->c[u] = k * box_minproj(fb, u) - reach;
}

/* the most any cone bound clears node @p id by (>= 0: nothing in it is below the box) */
static inline double dir_excess(const amp_fbvh *b, uint32_t id, const coneq *c)
{
    const double *m = b->cone[id].m;
    double e = m[0] + c->c[0];
    int u;
    for (u = 1; u < AMP_FBVH_NDIR; u++)
        e = amp_dmax(e, m[u] + c->c[u]);
    return e;
}

static inline int node_pass(const amp_fbvh *b, uint32_t id, const coneq *c)
{
    return b->act[id].minrank < c->rank && act_pass(&b->act[id].bx, c->reach, c->k2, c->fb) &&
           (!c->dir || dir_excess(b, id, c) < 0.0);
}

/* how deep the cone may reach into node @p id (mm), -1 when it cannot hold a fragment below the box */
static inline double node_slack(const amp_fbvh *b, uint32_t id, const coneq *c)
{
    double s, e;
    if (b->act[id].minrank >= c->rank)
        return -1.0;
    s = act_slack(&b->act[id].bx, c->reach, c->k2, c->fb);
    if (s <= 0.0 || !c->dir)
        return s;
    e = dir_excess(b, id, c);
    return e >= 0.0 ? -1.0 : amp_dmin(s, -e);
}

/* Search the subtree of @p root, skipping child @p skip, for any active fragment below f; first found wins.
 * Reads only the compact unprinted bounds (amp_fbvh_act): printed fragments no longer widen the boxes. Nodes
 * are bounded when pushed, and the child reaching deeper into the cone is searched first: it holds a blocker
 * most often. */

/* The children worth a visit (slack > 0) on the stack, the one the cone reaches deeper on top. */
static inline size_t push_by_slack(uint32_t *stack, size_t top, uint32_t l, uint32_t r, double sl, double sr)
{
    if (sl > 0.0 && sr > 0.0) {
        stack[top++] = sl > sr ? r : l;
        stack[top++] = sl > sr ? l : r;
    } else if (sl > 0.0) {
        stack[top++] = l;
    } else if (sr > 0.0) {
        stack[top++] = r;
    }
    return top;
}

static uint32_t subtree_any_below(const amp_fbvh *b, const amp_fragments *fs, double zo, double k, uint32_t f,
                                  const coneq *c, uint32_t xlo, uint32_t xhi, const unsigned char *done, uint32_t root,
                                  uint32_t skip, uint32_t clear)
{
    uint32_t stack[STACK_MAX];
    size_t top = 0;
    const amp_fragment *fr = &fs->frag[f];
    double reach = c->reach, k2 = c->k2;
    if (root == skip || !node_pass(b, root, c))
        return AMP_FBVH_NONE;
    stack[top++] = root;
    while (top) {
        const amp_fbvh_act *nd = &b->act[stack[--top]];
        if (nd->left == 0) {
            uint32_t q;
            for (q = nd->lo; q < nd->hi; q++) {
                uint32_t g = b->order[q];
                /* the box bound from the leaf-ordered copy first: most candidates end here, without touching
                 * the fragment itself */
                if ((g < xlo || g > xhi) && (!b->frank || b->frank[q] < c->rank) && !done[g] &&
                    act_pass(&b->fbox[q], reach, k2, &fr->box) &&
                    amp_fragment_below_k(fs, zo, k, g, f))
                    return g;
            }
        } else if (top + 2 <= STACK_MAX) {
            uint32_t l = nd->left, r = nd->right;
            double sl = l == skip || l == clear ? 0.0 : node_slack(b, l, c);
            double sr = r == skip || r == clear ? 0.0 : node_slack(b, r, c);
            top = push_by_slack(stack, top, nd->left, nd->right, sl, sr);
        }
    }
    return AMP_FBVH_NONE;
}

static uint32_t range_of(const amp_fbvh *b, uint32_t id)
{
    return id == AMP_FBVH_NONE ? 0 : b->act[id].hi - b->act[id].lo;
}

uint32_t amp_fbvh_find_any_below_x(const amp_fbvh *b, const amp_fragments *fs, double zo, double k, uint32_t f,
                                   uint32_t xlo, uint32_t xhi, uint32_t rank, const unsigned char *done, uint32_t near,
                                   uint32_t *clear)
{
    uint32_t id, prev = AMP_FBVH_NONE, cl = clear ? *clear : AMP_FBVH_NONE;
    const amp_fragment *fr = &fs->frag[f];
    coneq c;
    if (b->nnodes == 0)
        return AMP_FBVH_NONE;
    coneq_init(&c, b, k, &fr->box, fr->box.max.z - zo - AMP_CONE_TOL, rank);
    /* the hierarchy from the leaf of @p near upwards: every level adds the sibling subtree, so the fragments
     * near it are tried first and the whole tree is covered once the root is reached */
    for (id = b->leaf[near == AMP_FBVH_NONE ? f : near]; id != AMP_FBVH_NONE; prev = id, id = b->act[id].parent) {
        uint32_t g;
        if (id == cl)
            continue; /* proven clear by an earlier query of f */
        if (prev == AMP_FBVH_NONE) {
            g = subtree_any_below(b, fs, zo, k, f, &c, xlo, xhi, done, id, prev, cl);
        } else {
            /* the level adds prev's sibling: searched straight away when its slack is positive. The level's own
             * node need not be tested first: its bounds are the union of its children's (lower m_u and minz,
             * smaller gap), so it passes whenever the sibling has slack */
            uint32_t sib = b->act[id].left == prev ? b->act[id].right : b->act[id].left;
            g = AMP_FBVH_NONE;
            if (sib != cl && node_slack(b, sib, &c) > 0.0)
                g = subtree_any_below(b, fs, zo, k, f, &c, xlo, xhi, done, sib, AMP_FBVH_NONE, cl);
        }
        if (g != AMP_FBVH_NONE) {
            /* every level below this one held no blocker of f: printing only ever removes blockers, so that
             * subtree stays clear for f's later queries (the larger of the two clear subtrees is kept) */
            if (clear && range_of(b, prev) > range_of(b, cl))
                *clear = prev;
            return g;
        }
    }
    return AMP_FBVH_NONE;
}

/* Is some fragment of the sub-curve [lo, hi] above unprinted fragment g (g outside it)? Box bound per fragment
 * first (its own box against g's leaf-ordered box), then the exact test. */
static int piece_over(const amp_fbvh *b, const amp_fragments *fs, double zo, double k, uint32_t lo, uint32_t hi,
                      uint32_t q)
{
    uint32_t f, g = b->order[q];
    double k2 = k * k;
    for (f = lo; f <= hi; f++) {
        const amp_box3 *fb = &fs->frag[f].box;
        if (act_pass(&b->fbox[q], fb->max.z - zo - AMP_CONE_TOL, k2, fb) && amp_fragment_below_k(fs, zo, k, g, f))
            return 1;
    }
    return 0;
}

uint32_t amp_fbvh_find_any_below_piece(const amp_fbvh *b, const amp_fragments *fs, double zo, double k,
                                       uint32_t lo, uint32_t hi, uint32_t rank, amp_box3 box,
                                       const unsigned char *done)
{
    uint32_t stack[STACK_MAX];
    size_t top = 0;
    double reach = box.max.z - zo - AMP_CONE_TOL, k2 = k * k;
    coneq c;
    if (b->nnodes == 0)
        return AMP_FBVH_NONE;
    coneq_init(&c, b, k, &box, reach, rank);
    if (!node_pass(b, 0, &c))
        return AMP_FBVH_NONE;
    stack[top++] = 0;
    while (top) {
        const amp_fbvh_act *nd = &b->act[stack[--top]];
        if (nd->left == 0) {
            uint32_t q;
            for (q = nd->lo; q < nd->hi; q++) {
                uint32_t g = b->order[q];
                if ((g < lo || g > hi) && (!b->frank || b->frank[q] < c.rank) && !done[g] &&
                    act_pass(&b->fbox[q], reach, k2, &box) &&
                    piece_over(b, fs, zo, k, lo, hi, q))
                    return g;
            }
        } else if (top + 2 <= STACK_MAX) {
            double sl = node_slack(b, nd->left, &c);
            double sr = node_slack(b, nd->right, &c);
            top = push_by_slack(stack, top, nd->left, nd->right, sl, sr);
        }
    }
    return AMP_FBVH_NONE;
}

uint32_t amp_fbvh_find_any_below(const amp_fbvh *b, const amp_fragments *fs, double zo, double k, uint32_t f,
                                 const unsigned char *done, uint32_t near, uint32_t *clear)
{
    return amp_fbvh_find_any_below_x(b, fs, zo, k, f, f, f, AMP_FBVH_NONE, done, near, clear);
}

size_t amp_fbvh_for_above(const amp_fbvh *b, const amp_fragments *fs, const amp_head *h, uint32_t f,
                          int (*cb)(void *user, uint32_t g), void *user)
{
    uint32_t stack[STACK_MAX];
    size_t top = 0, count = 0;
    const amp_fragment *fr = &fs->frag[f];
    double k = 1.0 / tan(h->theta), floor_z = fr->box.min.z + h->z_offs + AMP_CONE_TOL;
    if (b->nnodes == 0)
        return 0;
    stack[top++] = 0;
    while (top) {
        const amp_fbvh_node *nd = &b->node[stack[--top]];
        if (nd->box.max.z <= floor_z + k * amp_box_xy_gap(nd->box, fr->box))
            continue;
        if (nd->left == 0) {
            uint32_t q;
            for (q = nd->lo; q < nd->hi; q++) {
                uint32_t g = b->order[q];
                if (amp_fragment_below_k(fs, h->z_offs, k, f, g)) {
                    count++;
                    if (cb && cb(user, g))
                        return count;
                }
            }
        } else if (top + 2 <= STACK_MAX) {
            stack[top++] = nd->left;
            stack[top++] = nd->right;
        }
    }
    return count;
}
