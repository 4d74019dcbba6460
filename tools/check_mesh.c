/*
 * ampath check --mesh: coverage of a mesh's solid by paths
 * ([P1 §4.2]): samples points inside the mesh (winding-number test), measures the
 * largest distance to the nearest path (the coverage gap), and checks that no
 * path vertex lies outside the mesh by more than 0.01 mm.
 */
#include <math.h>

#include "checkers.h"
#include "slicetool.h"

/* Vertices farther than this outside the mesh fail the check; --tol above it widens it, for
 * paths made on the exact model and checked against its tessellation. */
#define OUTSIDE_TOL 0.01

int check_mesh(const check_ctx *c, cli_json *j)
{
    amp_mesh m;
    amp_bvh *b = NULL;
    const amp_pathset *ps = c->ps;
    amp_error err;
    amp_coverage cov;
    amp_coverage_domain dom = {NULL, NULL, 0.0};
    double gap = 0, mean = 0, worst_out = 0, rmax = 0, eps = c->eps;
    const char *eps_from = "--eps";
    size_t i, outside = 0;
    int rc;
    amp_error_clear(&err);
    amp_mesh_init(&m, NULL);
    if (amp_mesh_read_stl_file(&m, c->mesh, &err) != AMP_OK || slicetool_outward(&m, NULL, &err) != AMP_OK ||
        amp_bvh_build(&b, &m, &err) != AMP_OK) {
        amp_mesh_free(&m);
        return cli_fail_err("check", &err);
    }
    for (i = 0; i < ps->nverts; i++) {
        amp_vec3 p = ps->verts[i].p;
        rmax = ps->verts[i].r > rmax ? ps->verts[i].r : rmax;
        /* an open mesh's inside ends at winding 1/2 across its holes, where `field` cuts its curves: a vertex
         * written there reads back a hair off it (10 digits), so within 1e-4 of 1/2 is on it */
        if (!amp_bvh_inside(b, p) && (amp_bvh_closed(b) || amp_bvh_inside_winding(b, p) < 0.5 - 1e-4)) {
            double d = amp_bvh_closest(b, p, NULL, NULL);
            worst_out = d > worst_out ? d : worst_out;
            outside += d > fmax(OUTSIDE_TOL, c->tol);
        }
    }
    if (!c->eps_given) { /* the covering's recorded claim (mdr changes the radii, not it), else the radius */
        eps = check_eps_from_comment(c->paths_file);
        eps_from = "path file";
        if (!(eps > 0)) {
            eps = rmax;
            eps_from = "largest radius";
        }
    }
    dom.mesh = b;
    if (amp_check_coverage(ps, &dom, (size_t)c->samples, c->seed, &cov, &err) != AMP_OK) {
        rc = cli_fail_err("check", &err);
    } else {
        gap = cov.gap;
        mean = cov.mean;
        rc = gap <= eps && outside == 0 ? CLI_OK : CLI_FAILED;
        if (j) {
            cli_json_bool(j, "ran", 1);
            cli_json_bool(j, "ok", rc == CLI_OK);
            cli_json_str(j, "model", "mesh");
            cli_json_num(j, "eps", eps);
            cli_json_str(j, "eps_from", eps_from);
            cli_json_num(j, "coverage_gap_mm", gap);
            cli_json_num(j, "coverage_gap_mean_mm", mean);
            cli_json_int(j, "samples", c->samples);
            cli_json_int(j, "vertices_outside", (long long)outside);
            cli_json_num(j, "worst_outside_mm", worst_out);
            cli_json_num(j, "volume_mm3", amp_mesh_volume(&m));
            cli_json_num(j, "deposited_mm3", amp_pathset_volume(ps, AMP_ROLE_OBJECT));
            cli_json_num(j, "over_coverage", amp_over_coverage(ps, amp_mesh_volume(&m)));
        } else {
            fprintf(c->out, "coverage: gap %.4f mm (mean %.4f) against eps %.4f over %ld samples; %lu vertices more than "
                   "%.2f mm outside (worst %.4f mm): %s; over-coverage %.3f\n",
                   gap, mean, eps, c->samples, (unsigned long)outside, fmax(OUTSIDE_TOL, c->tol), worst_out,
                   rc == CLI_OK ? "ok" : "FAILED", amp_over_coverage(ps, amp_mesh_volume(&m)));
        }
    }
    amp_bvh_free(b);
    amp_mesh_free(&m);
    return rc;
}
