/*
 * Built-in trivariates: helix (docs/interfaces.md §4, paper Fig. 2), torus-quarter (paper
 * Fig. 4, ×50 to millimetres) and vase (paper Fig. 18). Circles are rational
 * quadratic arcs, so discs and revolutions are exact; only the helix's height
 * along its arc is approximated (16 arcs keep it within 0.004 mm).
 */
#include <math.h>
#include <string.h>

#include "ampath/spline.h"


static const char *const model_names[] = {"helix", "torus-quarter", "vase", NULL};

const char *const *amp_trivariate_model_names(void) { return model_names; }

/*
 * The unit circle from angle a0 over `arcs` equal rational quadratic arcs
 * (2*arcs+1 control points): xy[2i], xy[2i+1], weight w[i], and knots U
 * (2*arcs+4 values on [0, 1]). Each middle point sits at the arc's bisector at
 * distance 1/cos(half angle) with that cosine as weight (exact circle).
 */
static void circle_arcs(int arcs, double a0, double sweep, double *xy, double *w, double *U)
{
    int j;
    double da = sweep / arcs, c = cos(da / 2);
    for (j = 0; j <= arcs; j++) {
        double a = a0 + da * j;
        xy[4 * j] = cos(a);
        xy[4 * j + 1] = sin(a);
        w[2 * j] = 1.0;
        if (j < arcs) {
            xy[4 * j + 2] = cos(a + da / 2) / c;
            xy[4 * j + 3] = sin(a + da / 2) / c;
            w[2 * j + 1] = c;
        }
    }
    U[0] = U[1] = U[2] = 0.0;
    for (j = 1; j < arcs; j++)
        U[2 * j + 1] = U[2 * j + 2] = (double)j / arcs;
    U[2 * arcs + 1] = U[2 * arcs + 2] = U[2 * arcs + 3] = 1.0;
}

/*
 * The disc of radius r as a rational biquadratic patch over the square (the
 * paper's Fig. 2 cross-section): boundary = four quarter circles, singular at
 * the four corners. (a, b) are in-plane coordinates, u along a, v along b.
 */
static void disc_patch(double r, double a[9], double b[9], double w[9])
{
    static const double corner_deg[4][3] = {{0, 0, 225}, {2, 0, 315}, {0, 2, 135}, {2, 2, 45}};
    double q = r * sqrt(2.0), h = sqrt(0.5);
    int c;
    memset(a, 0, 9 * sizeof(double));
    memset(b, 0, 9 * sizeof(double));
    for (c = 0; c < 4; c++) {
        int idx = (int)corner_deg[c][0] + 3 * (int)corner_deg[c][1];
        a[idx] = r * cos(corner_deg[c][2] * AMP_PI / 180);
        b[idx] = r * sin(corner_deg[c][2] * AMP_PI / 180);
        w[idx] = 1.0;
    }
    b[1] = -q; /* (1,0) */
    b[7] = q;  /* (1,2) */
    a[3] = -q; /* (0,1) */
    a[5] = q;  /* (2,1) */
    w[1] = w[7] = w[3] = w[5] = h;
    w[4] = 0.5; /* the tensor product of the edge weights */
}

static amp_status helix(const amp_allocator *al, amp_spline *s, amp_error *err)
{
    enum { ARCS = 16, NW = 2 * ARCS + 1 };
    const double R = 20.0, H = 40.0, RD = 5.0;
    const int order[3] = {3, 3, 3};
    const size_t count[3] = {3, 3, NW};
    double a[9], b[9], wd[9], xy[2 * NW], wa[NW], U[NW + 3];
    double L = sqrt(4 * AMP_PI * AMP_PI * R * R + H * H), bz = 2 * AMP_PI * R / L, bxy = H / L, z0 = RD * bz;
    size_t i, k;
    amp_status st = amp_spline_create(s, al, 3, order, count, 1, err);
    if (st != AMP_OK)
        return st;
    disc_patch(RD, a, b, wd);
    circle_arcs(ARCS, 0.0, 2 * AMP_PI, xy, wa, U);
    memcpy(s->knots[2], U, sizeof U);
    /*
     * Swept disc: X = c(t) + a N(t) + b B(t) with the helix's Frenet frame
     * N = -(cos φ, sin φ, 0), B = (H/L sin φ, -H/L cos φ, 2πR/L). X is linear
     * in (cos φ, sin φ, 1), so the rational arcs give x, y exactly; the height
     * H t is taken linear in the arc's control index (error < 0.004 mm).
     * z0 = 5·2πR/L puts the lowest point (t = 0, b = -5) on z = 0.
     */
    for (k = 0; k < NW; k++) {
        double cx = xy[2 * k], cy = xy[2 * k + 1], t = (double)k / (2.0 * ARCS);
        for (i = 0; i < 9; i++) {
            amp_vec3 p = amp_v3((R - a[i]) * cx + b[i] * bxy * cy, (R - a[i]) * cy - b[i] * bxy * cx,
                                z0 + H * t + b[i] * bz);
            amp_spline_cp_set(s, i + 9 * k, p, wd[i] * wa[k]);
        }
    }
    return AMP_OK;
}

static amp_status torus_quarter(const amp_allocator *al, amp_spline *s, amp_error *err)
{
    /* paper Fig. 4: major radius 1, minor 0.2, scaled ×50 to millimetres */
    const double R = 50.0, r = 10.0;
    const int order[3] = {3, 3, 3};
    const size_t count[3] = {3, 3, 3};
    double a[9], b[9], wd[9], xy[6], wa[3], U[6];
    size_t i, k;
    amp_status st = amp_spline_create(s, al, 3, order, count, 1, err);
    if (st != AMP_OK)
        return st;
    disc_patch(r, a, b, wd);
    circle_arcs(1, 0.0, AMP_PI / 2, xy, wa, U);
    for (k = 0; k < 3; k++)
        for (i = 0; i < 9; i++)
            amp_spline_cp_set(s, i + 9 * k, amp_v3((R + a[i]) * xy[2 * k], (R + a[i]) * xy[2 * k + 1], r + b[i]),
                              wd[i] * wa[k]);
    return AMP_OK;
}

static amp_status vase(const amp_allocator *al, amp_spline *s, amp_error *err)
{
    /* profile control polygon (paper Fig. 18: the cross-section changes a lot along the height) */
    static const double z[6] = {0, 12, 24, 36, 48, 60};
    static const double r_in[6] = {10, 16, 24, 12, 9, 16};
    static const double r_out[6] = {18, 28, 30, 16, 12, 20};
    const int order[3] = {2, 3, 4};
    const size_t count[3] = {2, 9, 6};
    double xy[18], wa[9], U[12];
    size_t i, j, k;
    amp_status st = amp_spline_create(s, al, 3, order, count, 1, err);
    if (st != AMP_OK)
        return st;
    circle_arcs(4, 0.0, 2 * AMP_PI, xy, wa, U);
    memcpy(s->knots[1], U, sizeof U);
    for (k = 0; k < 6; k++)
        for (j = 0; j < 9; j++)
            for (i = 0; i < 2; i++) {
                double r = i ? r_out[k] : r_in[k];
                amp_spline_cp_set(s, amp_spline_index(s, i, j, k), amp_v3(r * xy[2 * j], r * xy[2 * j + 1], z[k]),
                                  wa[j]);
            }
    return AMP_OK;
}

amp_status amp_trivariate_model(const char *name, const amp_allocator *a, amp_spline *out, amp_error *err)
{
    if (!out)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_trivariate_model: NULL output");
    amp_spline_init(out);
    if (name && strcmp(name, "helix") == 0)
        return helix(a, out, err);
    if (name && strcmp(name, "torus-quarter") == 0)
        return torus_quarter(a, out, err);
    if (name && strcmp(name, "vase") == 0)
        return vase(a, out, err);
    return amp_fail(err, AMP_ERR_ARG, 0, "unknown trivariate model '%s' (known: helix, torus-quarter, vase)",
                    name ? name : "(null)");
}
