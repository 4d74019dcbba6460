/*
 * Built-in triangle meshes (docs/interfaces.md §4 `ampath model NAME -o FILE.stl`):
 *
 *  helix           the boundary of the helix solid of docs/interfaces.md §4 / paper Fig. 2:
 *                  a disc of radius 5 swept along c(t) = (20 cos 2πt,
 *                  20 sin 2πt, z0 + 40 t) in the plane normal to c'(t),
 *                  closed by two flat caps, lowest point at z = 0.
 *  twisted-bridge  a bridge-like arched beam whose rectangular cross-section
 *                  twists a quarter turn from one end to the other (paper
 *                  Fig. 15: a B-rep bridge covered by a rectangular
 *                  cross-section direction field).
 *  crocodile-like  an organic shape with thin limbs in the spirit of the
 *                  crocodile of paper Figs. 6, 7 and 19: body, head, a curved
 *                  tail and four two-segment legs, blended smoothly and
 *                  polygonised by marching tetrahedra.
 *
 * Every model is closed (each edge shared by two oppositely oriented
 * triangles) and oriented outward; tests/test_mesh.c checks it.
 */
#include <math.h>
#include <string.h>

#include "ampath/mesh.h"
#include "mesh_internal.h"


/* ------------------------------------------------------------ sweeps */

/* Ring of @p nr points of station @p s in [0, 1], and the centre of the ring (for the caps). */
typedef void (*ring_fn)(const void *ctx, double s, size_t nr, amp_vec3 *ring, amp_vec3 *centre);

/*
 * A closed tube: ns + 1 rings of nr points joined by quads (two triangles
 * each) and closed at both ends by triangle fans from the ring centres
 * (valid for rings that are star-shaped around their centre: discs and
 * rectangles). The orientation is made outward at the end from the sign of
 * the enclosed volume.
 */
static amp_status sweep(amp_mesh *m, ring_fn fn, const void *ctx, size_t ns, size_t nr, amp_error *err)
{
    amp_vec3 *ring = amp_calloc(m->alloc, nr, sizeof *ring), centre[2], c;
    size_t s, j, i;
    uint32_t cap[2];
    amp_status st = AMP_OK;
    if (!ring)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory building a sweep");
    for (s = 0; s <= ns && st == AMP_OK; s++) {
        fn(ctx, (double)s / (double)ns, nr, ring, &c);
        if (s == 0)
            centre[0] = c;
        if (s == ns)
            centre[1] = c;
        for (j = 0; j < nr && st == AMP_OK; j++)
            st = amp_mesh_add_vertex(m, ring[j], NULL, err);
    }
    amp_free(m->alloc, ring);
    for (i = 0; i < 2 && st == AMP_OK; i++)
        st = amp_mesh_add_vertex(m, centre[i], &cap[i], err);
    for (s = 0; s < ns && st == AMP_OK; s++)
        for (j = 0; j < nr && st == AMP_OK; j++) {
            uint32_t a = (uint32_t)(s * nr + j), b = (uint32_t)(s * nr + (j + 1) % nr);
            uint32_t c2 = (uint32_t)((s + 1) * nr + (j + 1) % nr), d = (uint32_t)((s + 1) * nr + j);
            st = amp_mesh_add_tri(m, a, b, c2, err);
            if (st == AMP_OK)
                st = amp_mesh_add_tri(m, a, c2, d, err);
        }
    for (j = 0; j < nr && st == AMP_OK; j++) {
        st = amp_mesh_add_tri(m, cap[0], (uint32_t)((j + 1) % nr), (uint32_t)j, err);
        if (st == AMP_OK)
            st = amp_mesh_add_tri(m, cap[1], (uint32_t)(ns * nr + j), (uint32_t)(ns * nr + (j + 1) % nr), err);
    }
    if (st == AMP_OK && amp_mesh_volume(m) < 0)
        for (i = 0; i < m->ntris; i++) {
            uint32_t t = m->tris[i].v[1];
            m->tris[i].v[1] = m->tris[i].v[2];
            m->tris[i].v[2] = t;
        }
    return st;
}

/* Put the lowest point on the plate (z = 0). */
static void to_plate(amp_mesh *m)
{
    amp_box3 b = amp_mesh_bbox(m);
    amp_mesh_translate(m, amp_v3(0, 0, -b.min.z));
}

/* ------------------------------------------------------------- helix */

/* docs/interfaces.md §4: radius 20, pitch 40, disc radius 5; z0 puts the lowest point (on the t = 0 cap) at z = 0. */
#define HX_R 20.0
#define HX_P 40.0
#define HX_A 5.0

static void helix_ring(const void *ctx, double t, size_t nr, amp_vec3 *ring, amp_vec3 *centre)
{
    double w = 2 * AMP_PI * t, k = HX_P / (2 * AMP_PI);
    double len = sqrt(HX_R * HX_R + k * k);
    /* Frenet frame of the helix: N points to the axis, B = T x N */
    amp_vec3 c = amp_v3(HX_R * cos(w), HX_R * sin(w), HX_P * t);
    amp_vec3 n = amp_v3(-cos(w), -sin(w), 0);
    amp_vec3 b = amp_v3(k * sin(w) / len, -k * cos(w) / len, HX_R / len);
    size_t j;
    (void)ctx;
    for (j = 0; j < nr; j++) {
        double th = 2 * AMP_PI * (double)j / (double)nr;
        ring[j] = amp_v3_add(c, amp_v3_add(amp_v3_scale(n, HX_A * cos(th)), amp_v3_scale(b, HX_A * sin(th))));
    }
    *centre = c;
}

/*
 * Tessellation for a boundary within tol: the circle sag a(1 - cos(π/nθ))
 * and the chord sag along t, L²/(8ρ), each get half of tol. L is bounded by
 * the speed of the outermost surface line, |c'|(1 + a κ), and ρ by the
 * innermost radius of curvature, 1/κ - a (κ = R / (R² + k²), k = P/2π).
 * tests/test_mesh.c proves the bound by sampling both surfaces.
 */
static amp_status model_helix(amp_mesh *m, double tol, amp_error *err)
{
    double k = HX_P / (2 * AMP_PI), kappa = HX_R / (HX_R * HX_R + k * k);
    double speed = 2 * AMP_PI * sqrt(HX_R * HX_R + k * k) * (1 + HX_A * kappa), rho = 1 / kappa - HX_A;
    size_t nth = (size_t)ceil(AMP_PI / acos(1 - 0.5 * tol / HX_A));
    size_t nt = (size_t)ceil(speed / sqrt(8 * rho * 0.5 * tol));
    amp_status st;
    if (nth < 8)
        nth = 8;
    st = sweep(m, helix_ring, NULL, nt, nth, err);
    if (st == AMP_OK)
        to_plate(m);
    return st;
}

/* ----------------------------------------------------- twisted bridge */

/*
 * Dimensions (mm): span 80 along x; cross-section 16 wide (y) by 6 thick,
 * perpendicular to x, centred on the arch z = 14 sin(πx/80); the section
 * turns about the x axis linearly from 0 at x = 0 to a quarter turn (π/2) at
 * x = 80. After placing on the plate the ends touch z = 0.
 */
#define BR_L 80.0
#define BR_W 16.0
#define BR_T 6.0
#define BR_H 14.0

typedef struct bridge_ctx {
    size_t per_w, per_t; /* subdivisions of the wide and thin sides */
} bridge_ctx;

static void bridge_ring(const void *vctx, double s, size_t nr, amp_vec3 *ring, amp_vec3 *centre)
{
    const bridge_ctx *ctx = vctx;
    double x = BR_L * s, zc = BR_H * sin(AMP_PI * s), phi = 0.5 * AMP_PI * s, cp = cos(phi), sp = sin(phi);
    size_t j = 0, q, i;
    /* rectangle corners counter-clockwise in (y, z), each side subdivided evenly */
    static const double cy[4] = {-0.5, 0.5, 0.5, -0.5}, cz[4] = {-0.5, -0.5, 0.5, 0.5};
    for (q = 0; q < 4; q++) {
        size_t nseg = q % 2 == 0 ? ctx->per_w : ctx->per_t;
        for (i = 0; i < nseg && j < nr; i++, j++) {
            double f = (double)i / (double)nseg;
            double y = BR_W * (cy[q] + f * (cy[(q + 1) % 4] - cy[q]));
            double z = BR_T * (cz[q] + f * (cz[(q + 1) % 4] - cz[q]));
            ring[j] = amp_v3(x, cp * y - sp * z, zc + sp * y + cp * z);
        }
    }
    *centre = amp_v3(x, 0, zc);
}

static amp_status model_bridge(amp_mesh *m, double tol, amp_error *err)
{
    bridge_ctx ctx;
    /* arch radius of curvature >= L²/(π² H) ≈ 46 mm; the chord sag L²/(8ρ) gets tol/2 */
    double rho = BR_L * BR_L / (AMP_PI * AMP_PI * BR_H), seg = sqrt(8 * rho * 0.5 * tol);
    /* the twisted sides are saddles: stations 0.5 mm apart (at tol 0.05) keep the triangles close to them */
    double ns_twist = ceil(2 * BR_L * sqrt(0.05 / tol));
    size_t ns = (size_t)fmax(ceil(BR_L / seg), ns_twist);
    amp_status st;
    ctx.per_w = (size_t)ceil(BR_W * sqrt(0.05 / tol));
    ctx.per_t = (size_t)ceil(BR_T * sqrt(0.05 / tol));
    st = sweep(m, bridge_ring, &ctx, ns, 2 * (ctx.per_w + ctx.per_t), err);
    if (st == AMP_OK)
        to_plate(m);
    return st;
}

/* ------------------------------------------------------ crocodile-like */

/*
 * Signed distance-like function (negative inside) of the organic shape,
 * body along x. Dimensions (mm): body ellipsoid 60 x 20 x 14, head 32 x 12 x
 * 8, a tail of four tapered segments 55 mm long (radius 6 -> 1.2), four
 * legs of radius 2.4 -> 1.8 with a knee, reaching the ground. Union blended
 * with a polynomial smooth minimum (k = 2 mm) so that limbs join the body
 * without creases.
 */
static double ellipsoid(amp_vec3 p, amp_vec3 c, amp_vec3 r)
{
    amp_vec3 q = amp_v3((p.x - c.x) / r.x, (p.y - c.y) / r.y, (p.z - c.z) / r.z);
    double rm = fmin(r.x, fmin(r.y, r.z));
    return (amp_v3_len(q) - 1.0) * rm;
}

/* Distance to a segment with radius varying linearly from ra to rb. */
static double tapered(amp_vec3 p, amp_vec3 a, amp_vec3 b, double ra, double rb)
{
    double t, d = sqrt(amp_v3_seg_dist2(p, a, b, &t));
    return d - (ra + t * (rb - ra));
}

static double smin(double a, double b, double k)
{
    double h = fmax(k - fabs(a - b), 0.0) / k;
    return fmin(a, b) - h * h * k * 0.25;
}

static double croc_sdf(amp_vec3 p)
{
    static const double tail[5][4] = {
        {-24, 0, 10, 6.0}, {-40, 5, 9, 4.2}, {-55, 3, 8, 3.0}, {-67, -4, 7.5, 2.0}, {-78, -10, 7, 1.2}};
    double d = ellipsoid(p, amp_v3(0, 0, 11), amp_v3(30, 10, 7));
    int i, sx, sy;
    d = smin(d, ellipsoid(p, amp_v3(36, 0, 11), amp_v3(16, 6, 4)), 2.0);
    for (i = 0; i < 4; i++)
        d = smin(d, tapered(p, amp_v3(tail[i][0], tail[i][1], tail[i][2]),
                            amp_v3(tail[i + 1][0], tail[i + 1][1], tail[i + 1][2]), tail[i][3], tail[i + 1][3]),
                 2.0);
    for (sx = -1; sx <= 1; sx += 2)
        for (sy = -1; sy <= 1; sy += 2) {
            amp_vec3 hip = amp_v3(16.0 * sx, 6.0 * sy, 9), knee = amp_v3(19.0 * sx, 15.0 * sy, 6),
                     foot = amp_v3(17.0 * sx, 17.0 * sy, 1.9);
            d = smin(d, tapered(p, hip, knee, 2.6, 2.2), 2.0);
            d = smin(d, tapered(p, knee, foot, 2.2, 1.9), 1.0);
        }
    return d;
}

/* The zero crossing on grid edge (ia, ib), computed from the lower index so that both tets agree bit for bit. */
static amp_vec3 edge_point(const amp_vec3 *gp, const double *gv, size_t ia, size_t ib)
{
    double t;
    if (ia > ib) {
        size_t s = ia;
        ia = ib;
        ib = s;
    }
    t = gv[ia] / (gv[ia] - gv[ib]);
    return amp_v3_lerp(gp[ia], gp[ib], t);
}

static amp_status emit(amp_weld_table *wt, amp_mesh *m, amp_vec3 a, amp_vec3 b, amp_vec3 c, amp_vec3 out_dir,
                       amp_error *err)
{
    uint32_t ia, ib, ic;
    amp_status st;
    if (amp_v3_dot(amp_v3_cross(amp_v3_sub(b, a), amp_v3_sub(c, a)), out_dir) < 0) {
        amp_vec3 t = b;
        b = c;
        c = t;
    }
    if ((st = amp_weld_vertex(wt, m, a, &ia, err)) != AMP_OK || (st = amp_weld_vertex(wt, m, b, &ib, err)) != AMP_OK ||
        (st = amp_weld_vertex(wt, m, c, &ic, err)) != AMP_OK)
        return st;
    return amp_mesh_add_tri(m, ia, ib, ic, err);
}

/*
 * Marching tetrahedra over a cubic grid split into six tetrahedra around the
 * main diagonal (the Freudenthal split, consistent across cube faces): no
 * ambiguous cases, so the surface is closed; each triangle is oriented from
 * the negative (inside) corners towards the positive ones.
 */
static amp_status polygonise(amp_mesh *m, double (*f)(amp_vec3), amp_box3 box, double h, amp_error *err)
{
    static const int tets[6][4] = {{0, 1, 3, 7}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}, {0, 4, 5, 7}, {0, 5, 1, 7}};
    size_t nx = (size_t)ceil((box.max.x - box.min.x) / h) + 1, ny = (size_t)ceil((box.max.y - box.min.y) / h) + 1,
           nz = (size_t)ceil((box.max.z - box.min.z) / h) + 1;
    size_t n = nx * ny * nz, i, j, k;
    amp_vec3 *gp = amp_calloc(m->alloc, n, sizeof *gp);
    double *gv = amp_calloc(m->alloc, n, sizeof *gv);
    amp_weld_table wt;
    amp_status st = AMP_OK;
    if (!gp || !gv) {
        amp_free(m->alloc, gp);
        amp_free(m->alloc, gv);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the model grid");
    }
    for (k = 0; k < nz; k++)
        for (j = 0; j < ny; j++)
            for (i = 0; i < nx; i++) {
                size_t id = (k * ny + j) * nx + i;
                double v;
                gp[id] = amp_v3(box.min.x + h * (double)i, box.min.y + h * (double)j, box.min.z + h * (double)k);
                v = f(gp[id]);
                /* keep crossings away from grid points: float STL output must not merge them */
                if (fabs(v) < 1e-3 * h)
                    v = v < 0 ? -1e-3 * h : 1e-3 * h;
                gv[id] = v;
            }
    amp_weld_init(&wt, m->alloc);
    for (k = 0; k + 1 < nz && st == AMP_OK; k++)
        for (j = 0; j + 1 < ny && st == AMP_OK; j++)
            for (i = 0; i + 1 < nx && st == AMP_OK; i++) {
                size_t c[8];
                int q, t;
                for (q = 0; q < 8; q++)
                    c[q] = ((k + (size_t)(q >> 2 & 1)) * ny + j + (size_t)(q >> 1 & 1)) * nx + i + (size_t)(q & 1);
                for (t = 0; t < 6 && st == AMP_OK; t++) {
                    size_t in[4], out[4];
                    int nin = 0, nout = 0;
                    amp_vec3 cin = amp_v3(0, 0, 0), cout = amp_v3(0, 0, 0), dir;
                    for (q = 0; q < 4; q++) {
                        size_t g = c[tets[t][q]];
                        if (gv[g] < 0) {
                            in[nin++] = g;
                            cin = amp_v3_add(cin, gp[g]);
                        } else {
                            out[nout++] = g;
                            cout = amp_v3_add(cout, gp[g]);
                        }
                    }
                    if (nin == 0 || nout == 0)
                        continue;
                    dir = amp_v3_sub(amp_v3_scale(cout, 1.0 / nout), amp_v3_scale(cin, 1.0 / nin));
                    if (nin == 1)
                        st = emit(&wt, m, edge_point(gp, gv, in[0], out[0]), edge_point(gp, gv, in[0], out[1]),
                                  edge_point(gp, gv, in[0], out[2]), dir, err);
                    else if (nout == 1)
                        st = emit(&wt, m, edge_point(gp, gv, out[0], in[0]), edge_point(gp, gv, out[0], in[1]),
                                  edge_point(gp, gv, out[0], in[2]), dir, err);
                    else {
                        /* two in, two out: the quad a-c, a-d, b-d, b-c */
                        amp_vec3 p0 = edge_point(gp, gv, in[0], out[0]), p1 = edge_point(gp, gv, in[0], out[1]),
                                 p2 = edge_point(gp, gv, in[1], out[1]), p3 = edge_point(gp, gv, in[1], out[0]);
                        st = emit(&wt, m, p0, p1, p2, dir, err);
                        if (st == AMP_OK)
                            st = emit(&wt, m, p0, p2, p3, dir, err);
                    }
                }
            }
    amp_weld_free(&wt);
    amp_free(m->alloc, gp);
    amp_free(m->alloc, gv);
    return st;
}

static amp_status model_crocodile(amp_mesh *m, double tol, amp_error *err)
{
    /* grid step from the tolerance: 16 tol, kept in [0.4, 2] mm (0.8 mm at the default 0.05) */
    double h = fmin(2.0, fmax(0.4, 16 * tol));
    amp_box3 box;
    amp_status st;
    box.min = amp_v3(-84, -24, -2);
    box.max = amp_v3(56, 24, 22);
    st = polygonise(m, croc_sdf, box, h, err);
    if (st == AMP_OK)
        to_plate(m);
    return st;
}

/* ------------------------------------------------------------ registry */

typedef struct model_entry {
    const char *name, *summary;
    amp_status (*build)(amp_mesh *m, double tol, amp_error *err);
} model_entry;

static const model_entry models[] = {
    {"helix", "disc of radius 5 swept along a helix (radius 20, pitch 40, one turn), docs/interfaces.md §4.2 / [P1] Fig. 2",
     model_helix},
    {"twisted-bridge", "arched beam 80 x 16 x 6 mm twisting a quarter turn, paper Fig. 15", model_bridge},
    {"crocodile-like", "organic body with head, curved tail and four thin legs, paper Figs. 6, 19", model_crocodile},
};

#define NMODELS (sizeof models / sizeof models[0])

size_t amp_mesh_model_count(void) { return NMODELS; }

const char *amp_mesh_model_name(size_t i) { return i < NMODELS ? models[i].name : NULL; }

const char *amp_mesh_model_summary(size_t i) { return i < NMODELS ? models[i].summary : NULL; }

amp_status amp_mesh_model(const char *name, double tol, amp_mesh *m, amp_error *err)
{
    size_t i;
    amp_status st;
    if (!name || !m)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_model: NULL argument");
    if (m->nverts || m->ntris)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_model: the mesh must be empty");
    if (tol == 0)
        tol = AMP_MESH_MODEL_TOL;
    if (!isfinite(tol) || tol < 0.005 || tol > 1.0)
        return amp_fail(err, AMP_ERR_RANGE, 0, "model tolerance %g outside [0.005, 1] mm", tol);
    for (i = 0; i < NMODELS; i++)
        if (strcmp(name, models[i].name) == 0) {
            st = models[i].build(m, tol, err);
            if (st != AMP_OK)
                amp_mesh_free(m);
            return st;
        }
    return amp_fail(err, AMP_ERR_ARG, 0, "unknown mesh model '%s' (helix, twisted-bridge, crocodile-like)", name);
}
