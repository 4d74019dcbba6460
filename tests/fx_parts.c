/* "Real" parts by marching tetrahedra (see fx_parts.h). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fx_parts.h"


/* crossing point of grid edge (i, j): one vertex per edge, found by hashing */
typedef struct edge_map {
    uint64_t *key; /* (i << 32 | j) + 1, 0 = empty */
    uint32_t *vid;
    size_t cap, n;
} edge_map;

static size_t em_slot(const edge_map *e, uint64_t k)
{
    size_t h = (size_t)((k * 0x9E3779B97F4A7C15ull) >> 17) & (e->cap - 1);
    while (e->key[h] && e->key[h] != k)
        h = (h + 1) & (e->cap - 1);
    return h;
}

static amp_status em_grow(edge_map *e)
{
    edge_map n;
    size_t i;
    n.cap = e->cap ? 2 * e->cap : 1024;
    n.n = e->n;
    n.key = calloc(n.cap, sizeof *n.key);
    n.vid = calloc(n.cap, sizeof *n.vid);
    if (!n.key || !n.vid) {
        free(n.key);
        free(n.vid);
        return AMP_ERR_NOMEM;
    }
    for (i = 0; i < e->cap; i++)
        if (e->key[i]) {
            size_t s = em_slot(&n, e->key[i]);
            n.key[s] = e->key[i];
            n.vid[s] = e->vid[i];
        }
    free(e->key);
    free(e->vid);
    *e = n;
    return AMP_OK;
}

typedef struct mt_grid {
    amp_mesh *m;
    edge_map em;
    amp_vec3 lo;
    double step;
    int nx, ny, nz;
    double *val;
} mt_grid;

static amp_vec3 grid_point(const mt_grid *g, size_t id)
{
    size_t i = id % (size_t)g->nx, j = (id / (size_t)g->nx) % (size_t)g->ny, k = id / ((size_t)g->nx * g->ny);
    return amp_v3(g->lo.x + g->step * (double)i, g->lo.y + g->step * (double)j, g->lo.z + g->step * (double)k);
}

/* The vertex where the surface crosses grid edge (a, b), a inside, b outside. */
static amp_status cross_vertex(mt_grid *g, size_t a, size_t b, uint32_t *out)
{
    uint64_t k = (((uint64_t)(a < b ? a : b) << 32) | (uint64_t)(a < b ? b : a)) + 1;
    size_t s;
    if (2 * (g->em.n + 1) > g->em.cap && em_grow(&g->em) != AMP_OK)
        return AMP_ERR_NOMEM;
    s = em_slot(&g->em, k);
    if (!g->em.key[s]) {
        double fa = g->val[a], fb = g->val[b], t = fa / (fa - fb);
        amp_vec3 pa = grid_point(g, a), pb = grid_point(g, b);
        amp_status st;
        /* strictly inside the edge: no two crossing points coincide */
        t = fmin(fmax(t, 0.02), 0.98);
        st = amp_mesh_add_vertex(g->m, amp_v3_add(pa, amp_v3_scale(amp_v3_sub(pb, pa), t)), &g->em.vid[s], NULL);
        if (st != AMP_OK)
            return st;
        g->em.key[s] = k;
        g->em.n++;
    }
    *out = g->em.vid[s];
    return AMP_OK;
}

/* Triangle (a, b, c) turned so that its normal points along @p out. */
static amp_status tri_toward(amp_mesh *m, uint32_t a, uint32_t b, uint32_t c, amp_vec3 out)
{
    amp_vec3 n = amp_v3_cross(amp_v3_sub(m->verts[b], m->verts[a]), amp_v3_sub(m->verts[c], m->verts[a]));
    return amp_v3_dot(n, out) < 0 ? amp_mesh_add_tri(m, a, c, b, NULL) : amp_mesh_add_tri(m, a, b, c, NULL);
}

/* One tetrahedron of grid points t[4]: one triangle (1 or 3 inside) or a quad (2 inside). */
static amp_status mt_tet(mt_grid *g, const size_t t[4])
{
    size_t in[4], outv[4], ni = 0, no = 0, i;
    amp_vec3 ci = amp_v3(0, 0, 0), co = amp_v3(0, 0, 0), dir;
    uint32_t q[4];
    amp_status st;
    for (i = 0; i < 4; i++) {
        if (g->val[t[i]] < 0) {
            in[ni++] = t[i];
            ci = amp_v3_add(ci, grid_point(g, t[i]));
        } else {
            outv[no++] = t[i];
            co = amp_v3_add(co, grid_point(g, t[i]));
        }
    }
    if (ni == 0 || no == 0)
        return AMP_OK;
    dir = amp_v3_sub(amp_v3_scale(co, 1.0 / (double)no), amp_v3_scale(ci, 1.0 / (double)ni));
    if (ni == 1 || no == 1) {
        size_t lone = ni == 1 ? in[0] : outv[0];
        const size_t *other = ni == 1 ? outv : in;
        for (i = 0; i < 3; i++)
            if ((st = cross_vertex(g, ni == 1 ? lone : other[i], ni == 1 ? other[i] : lone, &q[i])) != AMP_OK)
                return st;
        return tri_toward(g->m, q[0], q[1], q[2], dir);
    }
    /* quad in0-out0, in0-out1, in1-out1, in1-out0 (a cycle around the tet) */
    if ((st = cross_vertex(g, in[0], outv[0], &q[0])) != AMP_OK ||
        (st = cross_vertex(g, in[0], outv[1], &q[1])) != AMP_OK ||
        (st = cross_vertex(g, in[1], outv[1], &q[2])) != AMP_OK ||
        (st = cross_vertex(g, in[1], outv[0], &q[3])) != AMP_OK)
        return st;
    if ((st = tri_toward(g->m, q[0], q[1], q[2], dir)) != AMP_OK)
        return st;
    return tri_toward(g->m, q[0], q[2], q[3], dir);
}

amp_status fx_implicit(amp_mesh *m, double (*f)(amp_vec3, void *), void *user, amp_vec3 lo, amp_vec3 hi,
                       double step)
{
    /* Kuhn triangulation: the six tetrahedra 0 - e_a - e_a + e_b - 7 of a cube (corner bits x 1, y 2, z 4) */
    static const int kuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
    mt_grid g;
    size_t i, npts;
    int x, y, z, c, k;
    amp_status st = AMP_OK;
    memset(&g, 0, sizeof g);
    g.m = m;
    g.lo = lo;
    g.step = step;
    g.nx = (int)ceil((hi.x - lo.x) / step) + 1;
    g.ny = (int)ceil((hi.y - lo.y) / step) + 1;
    g.nz = (int)ceil((hi.z - lo.z) / step) + 1;
    npts = (size_t)g.nx * (size_t)g.ny * (size_t)g.nz;
    g.val = malloc(npts * sizeof *g.val);
    if (!g.val)
        return AMP_ERR_NOMEM;
    for (i = 0; i < npts; i++) {
        double v = f(grid_point(&g, i), user);
        g.val[i] = v == 0 ? 1e-12 : v; /* a grid point on the surface counts as outside */
    }
    for (z = 0; z + 1 < g.nz && st == AMP_OK; z++)
        for (y = 0; y + 1 < g.ny && st == AMP_OK; y++)
            for (x = 0; x + 1 < g.nx && st == AMP_OK; x++) {
                size_t corner[8];
                for (c = 0; c < 8; c++)
                    corner[c] = (size_t)(x + (c & 1)) + (size_t)g.nx * ((size_t)(y + ((c >> 1) & 1)) +
                                                                        (size_t)g.ny * (size_t)(z + ((c >> 2) & 1)));
                for (k = 0; k < 6 && st == AMP_OK; k++) {
                    size_t t[4];
                    for (c = 0; c < 4; c++)
                        t[c] = corner[kuhn[k][c]];
                    st = mt_tet(&g, t);
                }
            }
    free(g.val);
    free(g.em.key);
    free(g.em.vid);
    return st;
}

/* ---- the parts (signed "distance-like" functions, negative inside) ---- */

static double torus_f(amp_vec3 p, void *u)
{
    double q = hypot(p.x, p.y) - 15;
    (void)u;
    return hypot(q, p.z - 5) - 5;
}

static double box2(double x, double y, double hx, double hy, double rad)
{
    double qx = fabs(x) - hx + rad, qy = fabs(y) - hy + rad;
    return hypot(fmax(qx, 0), fmax(qy, 0)) + fmin(fmax(qx, qy), 0) - rad;
}

static double idler_f(amp_vec3 p, void *u)
{
    double plate = box2(p.x, p.y, 15, 11, 4), d;
    (void)u;
    d = fmax(plate, fmax(-p.z, p.z - 6));
    d = fmax(d, 5 - hypot(p.x + 3, p.y));       /* bore */
    d = fmax(d, 1.7 - hypot(p.x - 10, p.y - 6)); /* screw holes */
    d = fmax(d, 1.7 - hypot(p.x - 10, p.y + 6));
    return d;
}

static double screw_f(amp_vec3 p, void *u)
{
    double a = atan2(p.y, p.x) - 0.9 * p.z, rho = hypot(p.x, p.y);
    double shaft = fmax(rho - (2.5 + 0.5 * cos(3 * a)), fmax(-p.z, p.z - 12));
    double head = fmax(rho - 4.5, fmax(p.z - 15, 12 - p.z));
    (void)u;
    return fmin(shaft, head);
}

static double ball(amp_vec3 p, double x, double y, double z, double r)
{
    return sqrt((p.x - x) * (p.x - x) + (p.y - y) * (p.y - y) + (p.z - z) * (p.z - z)) - r;
}

static double smin(double a, double b, double k)
{
    double h = fmax(k - fabs(a - b), 0) / k;
    return fmin(a, b) - h * h * k * 0.25;
}

static double bunny_f(amp_vec3 p, void *u)
{
    amp_vec3 q = amp_v3(p.x, p.y, p.z);
    double body, d;
    (void)u;
    /* body: a squashed ball */
    q.z = (p.z - 11) * 1.25;
    body = sqrt(q.x * q.x + (q.y * 1.2) * (q.y * 1.2) + q.z * q.z) - 12;
    d = smin(body, ball(p, 9, 0, 22, 7), 4);                   /* head */
    d = smin(d, ball(p, 3, 4, 29, 2.2), 2);                     /* ear roots */
    d = smin(d, ball(p, 3, -4, 29, 2.2), 2);
    d = smin(d, ball(p, 2, 4.5, 33, 2.0), 2);                   /* ear tips */
    d = smin(d, ball(p, 2, -4.5, 33, 2.0), 2);
    d = smin(d, ball(p, -12, 0, 8, 3.5), 3);                    /* tail */
    return fmax(d, -p.z); /* flat bottom */
}

const char *fx_part_name(fx_part p)
{
    static const char *const names[] = {"torus", "idler", "screw", "bunny", "open"};
    return p < FX_PART_COUNT ? names[p] : "?";
}

amp_status fx_part_mesh(amp_mesh *m, fx_part p, double step)
{
    amp_mesh tmp;
    size_t i;
    uint32_t base = (uint32_t)m->nverts;
    amp_status st;
    double s = step > 0 ? step : 0.6;
    switch (p) {
    case FX_PART_TORUS:
        return fx_implicit(m, torus_f, NULL, amp_v3(-21, -21, -0.7), amp_v3(21, 21, 10.7), s);
    case FX_PART_IDLER:
        return fx_implicit(m, idler_f, NULL, amp_v3(-16.1, -12.1, -0.3), amp_v3(16.1, 12.1, 6.3), s);
    case FX_PART_SCREW:
        return fx_implicit(m, screw_f, NULL, amp_v3(-5.1, -5.1, -0.3), amp_v3(5.1, 5.1, 15.3), s);
    case FX_PART_BUNNY:
        return fx_implicit(m, bunny_f, NULL, amp_v3(-17, -16, -0.3), amp_v3(18, 16, 36), s);
    case FX_PART_OPEN:
        amp_mesh_init(&tmp, m->alloc);
        st = fx_implicit(&tmp, bunny_f, NULL, amp_v3(-17, -16, -0.3), amp_v3(18, 16, 36), s);
        for (i = 0; i < tmp.nverts && st == AMP_OK; i++)
            st = amp_mesh_add_vertex(m, tmp.verts[i], NULL, NULL);
        /* drop the back upper quarter: sections above z 14 are open there */
        for (i = 0; i < tmp.ntris && st == AMP_OK; i++) {
            const amp_tri *t = &tmp.tris[i];
            amp_vec3 c = amp_v3_scale(
                amp_v3_add(amp_v3_add(tmp.verts[t->v[0]], tmp.verts[t->v[1]]), tmp.verts[t->v[2]]), 1.0 / 3);
            if (c.x < -4 && c.z > 14)
                continue;
            st = amp_mesh_add_tri(m, base + t->v[0], base + t->v[1], base + t->v[2], NULL);
        }
        amp_mesh_free(&tmp);
        return st;
    default:
        return AMP_ERR_ARG;
    }
}
