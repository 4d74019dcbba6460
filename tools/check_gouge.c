/* `ampath check` gouge checker (paper 5.1): calls the independent amp_check_gouge. */
#include "checkers.h"

int check_gouge(const check_ctx *c, cli_json *j)
{
    size_t i, nobj = 0, nseg = 0;
    amp_gouge_violation v;
    amp_error err;
    amp_status st;
    double t0;
    for (i = 0; i < c->ps->npaths; i++) {
        nobj += c->ps->paths[i].role == AMP_ROLE_OBJECT;
        nseg += c->ps->paths[i].n > 1 ? c->ps->paths[i].n - 1 : c->ps->paths[i].n;
    }
    if (nobj == 0) {
        if (j) {
            cli_json_bool(j, "ran", 0);
            cli_json_str(j, "reason", "no object paths");
        } else {
            fprintf(c->out, "gouge: not run (no object paths)\n");
        }
        return CLI_OK;
    }
    amp_error_clear(&err);
    t0 = cli_now();
    /* every path counts, support included: the head must not hit support printed earlier either */
    st = amp_check_gouge(c->ps, &c->head, AMP_GOUGE_AUTO, AMP_GOUGE_TOL, &v, &err);
    if (st != AMP_OK && st != AMP_ERR_CHECK)
        return cli_fail_err("check", &err);
    if (j) {
        cli_json_bool(j, "ran", 1);
        cli_json_bool(j, "ok", st == AMP_OK);
        cli_json_int(j, "paths", (long long)c->ps->npaths);
        cli_json_int(j, "segments", (long long)nseg);
        cli_json_str(j, "method", nseg < 2000 ? "pairwise" : "grid");
        cli_json_num(j, "z_offs", c->head.z_offs);
        cli_json_num(j, "theta_deg", c->head.theta * 57.295779513082320876);
        cli_json_num(j, "tolerance", AMP_GOUGE_TOL);
        if (st == AMP_ERR_CHECK) {
            cli_json_obj(j, "violation");
            cli_json_int(j, "earlier_path", (long long)v.earlier_path);
            cli_json_int(j, "earlier_segment", (long long)v.earlier_seg);
            cli_json_int(j, "later_path", (long long)v.later_path);
            cli_json_int(j, "later_segment", (long long)v.later_seg);
            cli_json_vec3(j, "earlier_point", v.earlier_point);
            cli_json_vec3(j, "later_point", v.later_point);
            cli_json_num(j, "depth", v.depth);
            cli_json_close(j);
        }
        cli_json_num(j, "time_s", cli_now() - t0);
    } else if (st == AMP_OK) {
        fprintf(c->out, "gouge: ok (%lu segments, z_offs %g mm, theta %g deg)\n", (unsigned long)nseg, c->head.z_offs,
               c->head.theta * 57.295779513082320876);
    } else {
        fprintf(c->out, "gouge: FAILED: %s\n", err.msg);
    }
    if (st == AMP_ERR_CHECK && !j)
        fprintf(stderr, "ampath check: %s\n", err.msg);
    return st == AMP_OK ? CLI_OK : CLI_FAILED;
}
