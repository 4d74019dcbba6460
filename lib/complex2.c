/* Planar 2-complexes: half-edges, checker and lattice generators
 * ([P2 §1.3], [P2 §2.2] step 3). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/complex2.h"

void amp_cx2_init(amp_cx2 *k, const amp_allocator *a)
{
    memset(k, 0, sizeof *k);
    k->alloc = a;
}

void amp_cx2_free(amp_cx2 *k)
{
    if (!k)
        return;
    amp_free(k->alloc, k->v);
    amp_free(k->alloc, k->fidx);
    amp_free(k->alloc, k->fstart);
    amp_free(k->alloc, k->fclass);
    amp_free(k->alloc, k->xedge);
    amp_free(k->alloc, k->he_face);
    amp_free(k->alloc, k->he_twin);
    amp_cx2_init(k, k->alloc);
}

amp_status amp_cx2_add_vertex(amp_cx2 *k, amp_vec2 p, uint32_t *id, amp_error *err)
{
    void *v = k->v;
    if (!isfinite(p.x) || !isfinite(p.y))
        return amp_fail(err, AMP_ERR_ARG, 0, "complex vertex is not finite");
    if (k->nv >= 0xffffffffUL)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "more than 2^32-1 complex vertices");
    if (amp_grow(k->alloc, &v, &k->cap_v, k->nv + 1, sizeof *k->v) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for complex vertices");
    k->v = v;
    k->v[k->nv] = p;
    if (id)
        *id = (uint32_t)k->nv;
    k->nv++;
    return AMP_OK;
}

amp_status amp_cx2_add_face(amp_cx2 *k, const uint32_t *idx, size_t n, int cls, amp_error *err)
{
    void *p;
    size_t i, capf_before = k->cap_f;
    if (n < 3)
        return amp_fail(err, AMP_ERR_ARG, 0, "a 2-cell needs at least 3 vertices, got %lu", (unsigned long)n);
    for (i = 0; i < n; i++)
        if (idx[i] >= k->nv)
            return amp_fail(err, AMP_ERR_ARG, 0, "2-cell vertex %lu out of range", (unsigned long)idx[i]);
    p = k->fidx;
    if (amp_grow(k->alloc, &p, &k->cap_fidx, k->nfidx + n, sizeof *k->fidx) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for 2-cells");
    k->fidx = p;
    p = k->fclass;
    if (amp_grow(k->alloc, &p, &k->cap_f, k->nf + 2, sizeof *k->fclass) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for 2-cells");
    k->fclass = p;
    if (k->cap_f != capf_before || !k->fstart) {
        p = amp_realloc_array(k->alloc, k->fstart, k->cap_f, sizeof *k->fstart);
        if (!p)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for 2-cells");
        k->fstart = p;
    }
    if (k->nf == 0)
        k->fstart[0] = 0;
    memcpy(k->fidx + k->nfidx, idx, n * sizeof *idx);
    k->nfidx += n;
    k->fclass[k->nf] = cls;
    k->nf++;
    k->fstart[k->nf] = k->nfidx;
    k->built = 0;
    return AMP_OK;
}

amp_status amp_cx2_add_edge(amp_cx2 *k, uint32_t a, uint32_t b, amp_error *err)
{
    void *p = k->xedge;
    if (a >= k->nv || b >= k->nv || a == b)
        return amp_fail(err, AMP_ERR_ARG, 0, "bad free edge %lu-%lu", (unsigned long)a, (unsigned long)b);
    if (amp_grow(k->alloc, &p, &k->cap_xe, 2 * (k->nxe + 1), sizeof *k->xedge) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for free edges");
    k->xedge = p;
    k->xedge[2 * k->nxe] = a;
    k->xedge[2 * k->nxe + 1] = b;
    k->nxe++;
    return AMP_OK;
}

/* Face of half-edge h by binary search over fstart (used before build). */
static size_t face_of(const amp_cx2 *k, size_t h)
{
    size_t lo = 0, hi = k->nf;
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (k->fstart[mid] <= h)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

size_t amp_cx2_he_next(const amp_cx2 *k, size_t h)
{
    size_t f = k->he_face ? k->he_face[h] : face_of(k, h);
    return h + 1 < k->fstart[f + 1] ? h + 1 : k->fstart[f];
}

size_t amp_cx2_he_prev(const amp_cx2 *k, size_t h)
{
    size_t f = k->he_face ? k->he_face[h] : face_of(k, h);
    return h > k->fstart[f] ? h - 1 : k->fstart[f + 1] - 1;
}

/* One directed edge occurrence, for sorting by undirected key. */
typedef struct ekey {
    uint64_t key;
    size_t h; /* half-edge, or AMP_CX2_NONE for a free edge */
    int fwd;  /* 1 when the occurrence goes from the smaller to the larger index */
} ekey;

static int cmp_ekey(const void *a, const void *b)
{
    const ekey *s = a, *t = b;
    if (s->key != t->key)
        return s->key < t->key ? -1 : 1;
    return s->h < t->h ? -1 : (s->h > t->h ? 1 : 0);
}

/* All edge occurrences (face half-edges and, if @p free_edges, free edges), sorted. */
static ekey *edge_list(const amp_cx2 *k, int free_edges, size_t *n)
{
    size_t f, h, i, m = k->nfidx + (free_edges ? k->nxe : 0);
    ekey *e = amp_alloc(k->alloc, (m ? m : 1) * sizeof *e);
    if (!e)
        return NULL;
    for (f = 0; f < k->nf; f++)
        for (h = k->fstart[f]; h < k->fstart[f + 1]; h++) {
            uint32_t a = k->fidx[h], b = k->fidx[h + 1 < k->fstart[f + 1] ? h + 1 : k->fstart[f]];
            e[h].key = a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
            e[h].h = h;
            e[h].fwd = a < b;
        }
    for (i = 0; free_edges && i < k->nxe; i++) {
        uint32_t a = k->xedge[2 * i], b = k->xedge[2 * i + 1];
        e[k->nfidx + i].key = a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
        e[k->nfidx + i].h = AMP_CX2_NONE;
        e[k->nfidx + i].fwd = 0;
    }
    if (m > 1)
        qsort(e, m, sizeof *e, cmp_ekey);
    *n = m;
    return e;
}

amp_status amp_cx2_build(amp_cx2 *k, amp_error *err)
{
    ekey *e;
    size_t n, i, j, f, h;
    amp_free(k->alloc, k->he_face);
    amp_free(k->alloc, k->he_twin);
    k->he_face = NULL;
    k->he_twin = NULL;
    k->built = 0;
    if (k->nf == 0) {
        k->built = 1;
        return AMP_OK;
    }
    e = edge_list(k, 0, &n);
    k->he_face = amp_alloc(k->alloc, k->nfidx * sizeof *k->he_face);
    k->he_twin = amp_alloc(k->alloc, k->nfidx * sizeof *k->he_twin);
    if (!e || !k->he_face || !k->he_twin) {
        amp_free(k->alloc, e);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for half-edges");
    }
    for (f = 0; f < k->nf; f++)
        for (h = k->fstart[f]; h < k->fstart[f + 1]; h++) {
            k->he_face[h] = f;
            k->he_twin[h] = AMP_CX2_NONE;
        }
    for (i = 0; i < n; i = j) {
        for (j = i + 1; j < n && e[j].key == e[i].key; j++)
            ;
        if (j - i > 2 || (j - i == 2 && e[i].fwd == e[i + 1].fwd)) {
            amp_status st = amp_fail(err, AMP_ERR_GEOMETRY, 0, "edge %lu-%lu is %s",
                                     (unsigned long)(e[i].key >> 32), (unsigned long)(e[i].key & 0xffffffffu),
                                     j - i > 2 ? "in more than two 2-cells" : "used twice in the same direction");
            amp_free(k->alloc, e);
            return st;
        }
        if (j - i == 2) {
            k->he_twin[e[i].h] = e[i + 1].h;
            k->he_twin[e[i + 1].h] = e[i].h;
        }
    }
    amp_free(k->alloc, e);
    k->built = 1;
    return AMP_OK;
}

amp_status amp_cx2_check(const amp_cx2 *k, amp_cx2_report *rep, amp_error *err)
{
    amp_cx2_report r;
    ekey *e;
    size_t n, i, j, f;
    size_t *deg = NULL;
    unsigned char *used = NULL;
    memset(&r, 0, sizeof r);
    e = edge_list(k, 1, &n);
    deg = amp_calloc(k->alloc, k->nv ? k->nv : 1, sizeof *deg);
    used = amp_calloc(k->alloc, k->nv ? k->nv : 1, 1);
    if (!e || !deg || !used) {
        amp_free(k->alloc, e);
        amp_free(k->alloc, deg);
        amp_free(k->alloc, used);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking a complex");
    }
    for (f = 0; f < k->nf; f++) {
        size_t a = k->fstart[f], m = k->fstart[f + 1] - a, p, q;
        double area = 0;
        int bad = m < 3;
        for (p = 0; p < m && !bad; p++) {
            amp_vec2 u = k->v[k->fidx[a + p]], w = k->v[k->fidx[a + (p + 1) % m]];
            area += u.x * w.y - w.x * u.y;
            for (q = p + 1; q < m; q++)
                if (k->fidx[a + p] == k->fidx[a + q])
                    bad = 1;
        }
        if (bad || !(area > 0))
            r.bad_faces++;
        for (p = 0; p < m; p++)
            used[k->fidx[a + p]] = 1;
    }
    for (i = 0; i < k->nxe; i++)
        used[k->xedge[2 * i]] = used[k->xedge[2 * i + 1]] = 1;
    for (i = 0; i < n; i = j) {
        size_t faces = 0, fwd = 0;
        for (j = i; j < n && e[j].key == e[i].key; j++)
            if (e[j].h != AMP_CX2_NONE) {
                faces++;
                fwd += e[j].fwd;
            }
        r.edges++;
        deg[e[i].key >> 32]++;
        deg[e[i].key & 0xffffffffu]++;
        if (faces == 1)
            r.boundary_edges++;
        if (faces > 2)
            r.nonmanifold++;
        else if (faces == 2 && fwd != 1)
            r.misoriented++;
    }
    for (i = 0; i < k->nv; i++) {
        if (!used[i])
            continue;
        r.vertices++;
        r.odd_vertices += deg[i] % 2;
        if (deg[i] > r.max_degree)
            r.max_degree = deg[i];
    }
    r.faces = k->nf;
    r.euler_char = (long)r.vertices - (long)r.edges + (long)r.faces;
    amp_free(k->alloc, e);
    amp_free(k->alloc, deg);
    amp_free(k->alloc, used);
    if (rep)
        *rep = r;
    if (r.nonmanifold || r.misoriented || r.bad_faces)
        return amp_fail(err, AMP_ERR_CHECK, 0, "complex is broken: %lu edges in > 2 cells, %lu misoriented, %lu bad cells",
                        (unsigned long)r.nonmanifold, (unsigned long)r.misoriented, (unsigned long)r.bad_faces);
    return AMP_OK;
}

amp_status amp_cx2_check_even(const amp_cx2 *k, size_t *odd, amp_error *err)
{
    ekey *e;
    size_t n, i, nodd = 0, first = AMP_CX2_NONE;
    size_t *deg;
    e = edge_list(k, 1, &n);
    deg = amp_calloc(k->alloc, k->nv ? k->nv : 1, sizeof *deg);
    if (!e || !deg) {
        amp_free(k->alloc, e);
        amp_free(k->alloc, deg);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking degrees");
    }
    /* degree in the 1-skeleton: distinct edges, however many cells share them */
    for (i = 0; i < n; i++)
        if (i == 0 || e[i].key != e[i - 1].key) {
            deg[e[i].key >> 32]++;
            deg[e[i].key & 0xffffffffu]++;
        }
    for (i = 0; i < k->nv; i++)
        if (deg[i] % 2) {
            if (first == AMP_CX2_NONE)
                first = i;
            nodd++;
        }
    if (odd)
        *odd = nodd;
    if (nodd) {
        amp_status st = amp_fail(err, AMP_ERR_CHECK, 0, "%lu vertices of odd degree (first: vertex %lu at (%g, %g), degree %lu)",
                                 (unsigned long)nodd, (unsigned long)first, k->v[first].x, k->v[first].y,
                                 (unsigned long)deg[first]);
        amp_free(k->alloc, e);
        amp_free(k->alloc, deg);
        return st;
    }
    amp_free(k->alloc, e);
    amp_free(k->alloc, deg);
    return AMP_OK;
}

/* ---- lattice generators ---- */

typedef struct lkey {
    int64_t x, y;
    size_t corner;
} lkey;

static int cmp_lkey(const void *a, const void *b)
{
    const lkey *s = a, *t = b;
    if (s->x != t->x)
        return s->x < t->x ? -1 : 1;
    if (s->y != t->y)
        return s->y < t->y ? -1 : 1;
    return s->corner < t->corner ? -1 : (s->corner > t->corner ? 1 : 0);
}

/* Separating-axis test of two convex CCW polygons: 1 when their interiors meet. */
static int convex_overlap(const amp_vec2 *a, size_t na, const amp_vec2 *b, size_t nb)
{
    size_t pass, i, j;
    for (pass = 0; pass < 2; pass++) {
        const amp_vec2 *p = pass ? b : a, *q = pass ? a : b;
        size_t np = pass ? nb : na, nq = pass ? na : nb;
        for (i = 0; i < np; i++) {
            int sep = 1;
            for (j = 0; j < nq && sep; j++)
                if (amp_v2_orient(p[i], p[(i + 1) % np], q[j]) > 0)
                    sep = 0;
            if (sep)
                return 0;
        }
    }
    return 1;
}

/* A lattice over a hull: integer corner keys (X, Y) map to o + X*ax + Y*ay, ax = (axx, 0), ay = (ayx, ayy). */
typedef struct lattice {
    amp_grid_kind kind;
    double cell, xmin, xmax, ymin, ymax, axx, ayx, ayy;
    amp_vec2 o;
    long j0, j1; /* rows */
    size_t m;    /* corners per cell */
} lattice;

/* The basis and the rows of @p kind over the hull's box (xmin.. set); AMP_ERR_ARG for an unknown kind. */
static amp_status lattice_basis(lattice *L, amp_error *err)
{
    double cell = L->cell;
    L->o = amp_v2(L->xmin - cell, L->ymin - cell);
    L->m = L->kind == AMP_GRID_TRI ? 3 : (L->kind == AMP_GRID_HEX ? 6 : 4);
    if (L->kind == AMP_GRID_SQUARE || L->kind == AMP_GRID_STRIPS_X || L->kind == AMP_GRID_STRIPS_Y) {
        /* a strip lattice is the square lattice stretched along one axis */
        L->axx = L->kind == AMP_GRID_STRIPS_X ? AMP_GRID_STRIP_ASPECT * cell : cell;
        L->ayy = L->kind == AMP_GRID_STRIPS_Y ? AMP_GRID_STRIP_ASPECT * cell : cell;
        L->ayx = 0;
        L->o = amp_v2(L->xmin - L->axx, L->ymin - L->ayy);
        L->j0 = 0, L->j1 = (long)((L->ymax - L->o.y) / L->ayy) + 1;
    } else if (L->kind == AMP_GRID_TRI) {
        L->axx = cell, L->ayx = 0.5 * cell, L->ayy = cell * 0.8660254037844386;
        L->j0 = 0, L->j1 = (long)((L->ymax - L->o.y) / L->ayy) + 1;
    } else if (L->kind == AMP_GRID_HEX) {
        L->axx = cell * 0.8660254037844386, L->ayx = 0, L->ayy = 0.5 * cell;
        L->j0 = 0, L->j1 = (long)((L->ymax - L->o.y) / (1.5 * cell)) + 2;
    } else
        return amp_fail(err, AMP_ERR_ARG, 0, "unknown grid kind %d", (int)L->kind);
    return AMP_OK;
}

/* The columns of row cj. */
static void lattice_row(const lattice *L, long cj, long *i0, long *i1)
{
    if (L->kind == AMP_GRID_TRI) {
        *i0 = (long)floor((L->xmin - L->o.x - cj * L->ayx) / L->cell) - 1;
        *i1 = (long)ceil((L->xmax - L->o.x - cj * L->ayx) / L->cell) + 1;
    } else if (L->kind == AMP_GRID_HEX) {
        *i0 = -1;
        *i1 = (long)((L->xmax - L->o.x) / (L->cell * 1.7320508075688772)) + 2;
    } else {
        *i0 = 0;
        *i1 = (long)((L->xmax - L->o.x) / L->axx) + 1;
    }
}

static amp_vec2 lattice_point(const lattice *L, int64_t X, int64_t Y)
{
    return amp_v2(L->o.x + X * L->axx + Y * L->ayx, L->o.y + Y * L->ayy);
}

/* Corner keys and points of cell (ci, cj) of type t (the two triangles of a rhombus: t = 0, 1). */
static void lattice_cell(const lattice *L, long ci, long cj, size_t t, int64_t *X, int64_t *Y, amp_vec2 *poly)
{
    static const int sq[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    static const int tri[2][3][2] = {{{0, 0}, {1, 0}, {0, 1}}, {{1, 0}, {1, 1}, {0, 1}}};
    static const int hex[6][2] = {{0, -2}, {1, -1}, {1, 1}, {0, 2}, {-1, 1}, {-1, -1}};
    size_t c;
    for (c = 0; c < L->m; c++) {
        if (L->m == 4) {
            X[c] = ci + sq[c][0];
            Y[c] = cj + sq[c][1];
        } else if (L->kind == AMP_GRID_TRI) {
            X[c] = ci + tri[t][c][0];
            Y[c] = cj + tri[t][c][1];
        } else {
            X[c] = 2 * ci + (cj & 1) + hex[c][0];
            Y[c] = 3 * cj + hex[c][1];
        }
        poly[c] = lattice_point(L, X[c], Y[c]);
    }
}

/* The corners of every cell meeting the hull, cell after cell, into *keys; *ncell receives the cells. */
static amp_status lattice_cells(const lattice *L, const amp_vec2 *hull, size_t n, const amp_allocator *al,
                                lkey **keys, size_t *nkeys, size_t *ncell)
{
    size_t cap = 0, ntype = L->kind == AMP_GRID_TRI ? 2 : 1, t, c;
    long ci, cj, i0, i1;
    for (cj = L->j0; cj <= L->j1; cj++) {
        lattice_row(L, cj, &i0, &i1);
        for (ci = i0; ci <= i1; ci++)
            for (t = 0; t < ntype; t++) {
                int64_t X[6], Y[6];
                amp_vec2 poly[6];
                void *p = *keys;
                lattice_cell(L, ci, cj, t, X, Y, poly);
                if (!convex_overlap(poly, L->m, hull, n))
                    continue;
                if (amp_grow(al, &p, &cap, *nkeys + L->m, sizeof **keys) != AMP_OK)
                    return AMP_ERR_NOMEM;
                *keys = p;
                for (c = 0; c < L->m; c++) {
                    (*keys)[*nkeys].x = X[c];
                    (*keys)[*nkeys].y = Y[c];
                    (*keys)[*nkeys].corner = *nkeys;
                    (*nkeys)++;
                }
                (*ncell)++;
            }
    }
    return AMP_OK;
}

/* Weld corners by their integer lattice keys (exact, no float compare) and add the cells to @p k. */
static amp_status lattice_weld(amp_cx2 *k, const lattice *L, lkey *keys, size_t nkeys, size_t ncell, amp_error *err)
{
    uint32_t *vid = amp_alloc(k->alloc, nkeys * sizeof *vid);
    amp_status st = AMP_OK;
    size_t i, j;
    if (!vid)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the grid");
    if (nkeys > 1)
        qsort(keys, nkeys, sizeof *keys, cmp_lkey);
    for (i = 0; i < nkeys && st == AMP_OK; i++) {
        uint32_t id = (uint32_t)k->nv - 1;
        if (i == 0 || keys[i].x != keys[i - 1].x || keys[i].y != keys[i - 1].y)
            st = amp_cx2_add_vertex(k, lattice_point(L, keys[i].x, keys[i].y), &id, err);
        vid[keys[i].corner] = id;
    }
    for (j = 0; j < ncell && st == AMP_OK; j++)
        st = amp_cx2_add_face(k, vid + j * L->m, L->m, AMP_CELL_INPUT, err);
    amp_free(k->alloc, vid);
    return st;
}

amp_status amp_cx2_grid(amp_cx2 *k, const amp_vec2 *hull, size_t n, double cell, amp_grid_kind kind, amp_error *err)
{
    lattice L;
    lkey *keys = NULL;
    size_t nkeys = 0, i, ncell = 0;
    amp_status st;
    amp_cx2_free(k);
    if (!(cell > 0) || !isfinite(cell))
        return amp_fail(err, AMP_ERR_ARG, 0, "cell size must be positive");
    if (n < 3 || amp_ring_area(hull, n) <= 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "hull must be a counter-clockwise polygon with positive area");
    memset(&L, 0, sizeof L);
    L.kind = kind;
    L.cell = cell;
    L.xmin = L.ymin = HUGE_VAL;
    L.xmax = L.ymax = -HUGE_VAL;
    for (i = 0; i < n; i++) {
        L.xmin = fmin(L.xmin, hull[i].x);
        L.xmax = fmax(L.xmax, hull[i].x);
        L.ymin = fmin(L.ymin, hull[i].y);
        L.ymax = fmax(L.ymax, hull[i].y);
    }
    if ((L.xmax - L.xmin) / cell * (L.ymax - L.ymin) / cell > 4e6)
        return amp_fail(err, AMP_ERR_LIMIT, 0,
                        "a lattice of %.0f x %.0f mm in cells of %g mm has more than 4000000 cells: a part in metres "
                        "or inches must be scaled to millimetres; otherwise a larger cell (a lower infill density)",
                        L.xmax - L.xmin, L.ymax - L.ymin, cell);
    if ((st = lattice_basis(&L, err)) != AMP_OK)
        return st;
    st = lattice_cells(&L, hull, n, k->alloc, &keys, &nkeys, &ncell);
    if (st != AMP_OK || ncell == 0) {
        amp_free(k->alloc, keys);
        return st != AMP_OK ? amp_fail(err, st, 0, "out of memory for the grid")
                            : amp_fail(err, AMP_ERR_GEOMETRY, 0, "no grid cell meets the hull");
    }
    st = lattice_weld(k, &L, keys, nkeys, ncell, err);
    amp_free(k->alloc, keys);
    return st == AMP_OK ? amp_cx2_build(k, err) : st;
}
