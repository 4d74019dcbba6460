/* Volume of a trivariate: Gauss-Legendre quadrature of |det J| (the model volume of the
 * over-coverage, [P1 §3.1]); also the largest |det J| seen, which the coverage checker's
 * rejection sampling needs (lib/check_coverage.c). */
#include <math.h>

#include "spline_internal.h"

/* Gauss-Legendre, 3 points on [0, 1] */
static const double gx[3] = {0.1127016653792583, 0.5, 0.8872983346207417};
static const double gw[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

double amp_spl_det_jacobian(const amp_spline *v, const double *p)
{
    amp_vec3 D[8];
    if (amp_spline_eval_derivs(v, p, 1, D, NULL) != AMP_OK)
        return 0;
    /* D[1] = d/du, D[2] = d/dv, D[4] = d/dw */
    return fabs(amp_v3_dot(D[1], amp_v3_cross(D[2], D[4])));
}

double amp_spl_volume(const amp_spline *v, double *jmax)
{
    enum { C = 12 };
    double lo[3], hi[3], vol = 0, jm = 0;
    int d, i, j, k, a, b, c;
    if (jmax)
        *jmax = 0.0;
    if (!v || v->dim != 3 || !v->cp)
        return 0.0; /* not a trivariate (an empty spline): no volume */
    for (d = 0; d < 3; d++)
        amp_spline_domain(v, d, &lo[d], &hi[d]);
    for (k = 0; k < C; k++)
        for (j = 0; j < C; j++)
            for (i = 0; i < C; i++)
                for (c = 0; c < 3; c++)
                    for (b = 0; b < 3; b++)
                        for (a = 0; a < 3; a++) {
                            double p[3], J;
                            p[0] = lo[0] + (hi[0] - lo[0]) * (i + gx[a]) / C;
                            p[1] = lo[1] + (hi[1] - lo[1]) * (j + gx[b]) / C;
                            p[2] = lo[2] + (hi[2] - lo[2]) * (k + gx[c]) / C;
                            J = amp_spl_det_jacobian(v, p);
                            jm = fmax(jm, J);
                            vol += gw[a] * gw[b] * gw[c] * J;
                        }
    if (jmax)
        *jmax = jm;
    return vol * (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]) / (C * C * C);
}

double amp_trivariate_volume(const amp_spline *v) { return amp_spl_volume(v, NULL); }
