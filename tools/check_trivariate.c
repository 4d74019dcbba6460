/* ampath check --trivariate: independent ε-coverage measurement of a volumetric covering ([P1 §4.1]). */
#include <stdlib.h>
#include <string.h>

#include "checkers.h"

/* The eps recorded in a comment of the path file by `ampath cover` (its eps) or `ampath field` (its covering
 * radius), or 0: the covering's own claim, which later steps (order, mdr, support) keep in the file's header. */
double check_eps_from_comment(const char *file)
{
    static const char *const tags[] = {"# ampath cover", "# ampath field"};
    char *data, *p;
    size_t len, t;
    double eps = 0;
    if (amp_read_file(file, NULL, 0, &data, &len, NULL) != AMP_OK)
        return 0;
    for (t = 0; t < 2 && eps <= 0; t++)
        for (p = data; (p = strstr(p, tags[t])) != NULL; p++) {
            char *e = strstr(p, " eps "), *nl = strchr(p, '\n');
            if (e && (!nl || e < nl)) {
                eps = strtod(e + 5, NULL);
                break;
            }
        }
    amp_free(NULL, data);
    return eps > 0 ? eps : 0;
}

int check_trivariate(const check_ctx *c, cli_json *j)
{
    amp_spline v;
    amp_coverage g;
    amp_coverage_domain dom = {NULL, NULL, 0.0};
    amp_error err;
    int rc;
    double eps = c->eps;
    const char *eps_from = "--eps";
    rc = cli_load_trivariate("check", c->trivariate, &v);
    if (rc != CLI_OK)
        return rc;
    if (!c->eps_given) {
        size_t i;
        eps = check_eps_from_comment(c->paths_file);
        eps_from = "path file";
        if (!(eps > 0)) {
            eps_from = "largest radius";
            for (i = 0; i < c->ps->nverts; i++)
                eps = c->ps->verts[i].r > eps ? c->ps->verts[i].r : eps;
        }
    }
    amp_error_clear(&err);
    dom.trivariate = &v;
    if (amp_check_coverage(c->ps, &dom, (size_t)c->samples, c->seed, &g, &err) != AMP_OK) {
        amp_spline_free(&v);
        return cli_fail_err("check", &err);
    }
    rc = g.gap <= eps ? CLI_OK : CLI_FAILED;
    if (j) {
        cli_json_bool(j, "ran", 1);
        cli_json_bool(j, "ok", rc == CLI_OK);
        cli_json_str(j, "model", "trivariate");
        cli_json_num(j, "eps", eps);
        cli_json_str(j, "eps_from", eps_from);
        cli_json_num(j, "coverage_gap_mm", g.gap);
        cli_json_int(j, "samples", (long long)g.samples);
        cli_json_vec3(j, "worst_point", g.worst);
        cli_json_arr(j, "worst_parameters");
        cli_json_num(j, NULL, g.worst_par[0]);
        cli_json_num(j, NULL, g.worst_par[1]);
        cli_json_num(j, NULL, g.worst_par[2]);
        cli_json_close(j);
        cli_json_num(j, "volume_mm3", g.volume);
        cli_json_num(j, "deposited_mm3", amp_pathset_volume(c->ps, AMP_ROLE_OBJECT));
        cli_json_num(j, "over_coverage", amp_over_coverage(c->ps, g.volume));
    } else {
        fprintf(c->out, "coverage: largest distance to a path %.4f mm over %lu samples (eps %.4f mm from %s): %s\n", g.gap,
               (unsigned long)g.samples, eps, eps_from, rc == CLI_OK ? "ok" : "FAILED");
        fprintf(c->out, "coverage: worst point (%.3f %.3f %.3f) at parameters (%.4f %.4f %.4f); over-coverage %.3f\n",
               g.worst.x, g.worst.y, g.worst.z, g.worst_par[0], g.worst_par[1], g.worst_par[2],
               amp_over_coverage(c->ps, g.volume));
    }
    if (rc != CLI_OK)
        fprintf(stderr, "ampath check: coverage gap %.4f mm exceeds eps %.4f mm\n", g.gap, eps);
    amp_spline_free(&v);
    return rc;
}
