/* `ampath check` support checker ([P1 §5.3]): every object bead held by earlier material or the bed. */
#include "checkers.h"

#define DEG 57.295779513082320876

static void not_run(const check_ctx *c, cli_json *j, const char *why)
{
    if (j) {
        cli_json_bool(j, "ran", 0);
        cli_json_str(j, "reason", why);
    } else {
        fprintf(c->out, "support: not run (%s)\n", why);
    }
}

static void report_json(cli_json *j, const amp_hold_opts *o, const amp_hold_report *r, double t)
{
    size_t i;
    cli_json_bool(j, "ran", 1);
    cli_json_bool(j, "ok", r->failures == 0);
    cli_json_num(j, "overhang_deg", o->overhang * DEG);
    cli_json_num(j, "max_gap_mm", o->max_gap);
    cli_json_num(j, "bridge_mm", o->bridge);
    cli_json_num(j, "step_mm", o->step);
    cli_json_int(j, "samples", (long long)r->samples);
    cli_json_int(j, "unheld_samples", (long long)r->unheld);
    cli_json_int(j, "bridges", (long long)r->bridges);
    cli_json_num(j, "bridged_mm", r->bridged_mm);
    cli_json_int(j, "tips", (long long)r->tips);
    cli_json_int(j, "failures", (long long)r->failures);
    cli_json_num(j, "unheld_mm", r->failed_mm);
    cli_json_int(j, "unheld_paths", (long long)r->npaths_failed);
    cli_json_arr(j, "unheld_path_list"); /* the first 100 */
    for (i = 0; i < r->npaths_failed && i < 100; i++)
        cli_json_int(j, NULL, (long long)r->paths_failed[i]);
    cli_json_close(j);
    if (r->failures) {
        cli_json_int(j, "worst_path", (long long)r->worst_path);
        cli_json_num(j, "worst_mm", r->worst_mm);
        cli_json_vec3(j, "worst_at", r->worst_at);
    }
    cli_json_num(j, "time_s", t);
}

int check_support(const check_ctx *c, cli_json *j)
{
    size_t i, nsup = 0, nobj = 0;
    amp_hold_opts o;
    amp_hold_report r;
    amp_error err;
    double t0;
    for (i = 0; i < c->ps->npaths; i++) {
        nsup += c->ps->paths[i].role == AMP_ROLE_SUPPORT;
        nobj += c->ps->paths[i].role == AMP_ROLE_OBJECT;
    }
    if (nobj == 0) {
        not_run(c, j, "no object paths");
        return CLI_OK;
    }
    if (nsup == 0 && !c->support) {
        not_run(c, j, "no support paths (--support requires every object path to be held)");
        return CLI_OK;
    }
    amp_hold_opts_default(&o);
    o.overhang = c->overhang;
    o.max_gap = c->max_gap;
    o.bridge = c->bridge;
    amp_error_clear(&err);
    t0 = cli_now();
    if (amp_check_hold(c->ps, &o, &r, &err) != AMP_OK) {
        amp_hold_report_free(&r);
        return cli_fail_err("check", &err);
    }
    if (j) {
        report_json(j, &o, &r, cli_now() - t0);
    } else if (r.failures == 0) {
        fprintf(c->out, "support: ok (every object bead held: %lu samples, %lu bridges up to %g mm, overhang %g deg)\n",
               (unsigned long)r.samples, (unsigned long)r.bridges, o.bridge, o.overhang * DEG);
    } else {
        fprintf(c->out, "support: FAILED: %lu object paths unheld, %.1f mm in the air (worst: path %lu, %.1f mm at %.2f %.2f %.2f)\n",
               (unsigned long)r.npaths_failed, r.failed_mm, (unsigned long)r.worst_path, r.worst_mm, r.worst_at.x,
               r.worst_at.y, r.worst_at.z);
    }
    i = r.failures;
    amp_hold_report_free(&r);
    return i == 0 ? CLI_OK : CLI_FAILED;
}
