/* Code-generated path sets shared by the G-code and preview tests. */
#include <math.h>

#include "fixture_geom.h"


void fx_helix(amp_pathset *ps, int nstrands, int nper)
{
    int j, k;
    for (j = 0; j < nstrands; j++) {
        double a = 1.0 + 3.0 * (double)(j % 4) / 3.0, phi = 2.0 * AMP_PI * (double)j / (double)nstrands;
        amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
        for (k = 0; k < nper; k++) {
            double t = (double)k / (double)(nper - 1), w = 2.0 * AMP_PI * t;
            /* the strand winds once more around the centre line while following it */
            double ang = phi + 3.0 * w, rho = 20.0 + a * cos(ang), s = sin(1.5 * w);
            amp_vec3 p = amp_v3(rho * cos(w), rho * sin(w), 5.0 + a * sin(ang) + 40.0 * t);
            amp_pathset_push(ps, p, 0.3 + 0.25 * s * s, NULL);
        }
    }
    amp_pathset_begin(ps, AMP_ROLE_SUPPORT, NULL);
    for (k = 0; k <= 8; k++)
        amp_pathset_push(ps, amp_v3(21.0, 0.0, 0.5 * k), 0.25, NULL);
}

void fx_rings(amp_pathset *ps, double cx, double cy, int nlayers, int nrings, int nper, double r)
{
    int i, j, k;
    for (i = 0; i < nlayers; i++)
        for (j = 0; j < nrings; j++) {
            double rad = 4.0 + 0.8 * j, z = 0.3 * (i + 1);
            amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
            for (k = 0; k <= nper; k++) {
                double w = 2.0 * AMP_PI * (double)(k % nper) / (double)nper;
                amp_pathset_push(ps, amp_v3(cx + rad * cos(w), cy + rad * sin(w), z), r, NULL);
            }
        }
}
