/* ampath check — independent verification: a dispatcher over the checkers of check.h. */
#include <string.h>

#include "checkers.h"
#include "headopt.h"

typedef struct checker {
    const char *name;
    int (*run)(const check_ctx *c, cli_json *j);
    const char *help;
} checker;

/* One row per checker; each gets a --no-NAME flag. */
static const checker checkers[] = {
    {"gouge", check_gouge, "no point printed earlier inside the head cone while a later point prints (paper 5.1)"},
};
#define NCHECKERS (sizeof checkers / sizeof checkers[0])

const char cmd_check_usage[] =
    "verify paths independently: no gouging (and the other registered checks); exit 1 on a failure\n"
    "usage: ampath check PATHS.amp [--trivariate F | --mesh F] [--z-offs Z] [--theta DEG] [--eps E] [--no-NAME]\n"
    "                    [--json]\n"
    "  --trivariate F  the model as a trivariate (.spl), for checks that need it\n"
    "  --mesh F        the model as a mesh (.stl), for checks that need it\n"
    HEADOPT_HELP
    "  --eps E         tolerance of the coverage checks, mm (default 0.5)\n"
    "  --no-gouge      skip the gouge check (which runs whenever the file has object paths)\n"
    "  --json          one JSON object: {\"ok\": bool, \"NAME\": {\"ran\": bool, \"ok\": bool, ...}, ...}\n"
    "Exit status: 0 all checks passed, 1 a check failed, 2 bad usage or input.\n";

int cmd_check(int argc, char **argv)
{
    const char *pos[1];
    double z_offs = AMP_HEAD_DEFAULT_Z_OFFS, theta = 72.0, eps = 0.5;
    int json = 0, npos = 0, rc, failed = 0, usage = 0;
    int skip[NCHECKERS];
    char names[NCHECKERS][40];
    cli_opt opts[8 + NCHECKERS];
    check_ctx c;
    amp_pathset ps;
    cli_json j;
    size_t i, n = 0;
    memset(&c, 0, sizeof c);
    memset(skip, 0, sizeof skip);
    opts[n++] = (cli_opt){"trivariate", CLI_STR, &c.trivariate, 0};
    opts[n++] = (cli_opt){"mesh", CLI_STR, &c.mesh, 0};
    opts[n++] = (cli_opt){"z-offs", CLI_DOUBLE, &z_offs, 0};
    opts[n++] = (cli_opt){"theta", CLI_DOUBLE, &theta, 0};
    opts[n++] = (cli_opt){"eps", CLI_DOUBLE, &eps, 0};
    opts[n++] = (cli_opt){"json", CLI_FLAG, &json, 0};
    for (i = 0; i < NCHECKERS; i++) {
        snprintf(names[i], sizeof names[i], "no-%s", checkers[i].name);
        opts[n++] = (cli_opt){names[i], CLI_FLAG, &skip[i], 0};
    }
    opts[n] = (cli_opt){NULL, CLI_FLAG, NULL, 0};
    rc = cli_parse("check", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (c.trivariate && c.mesh)
        return cli_fail("check", CLI_USAGE, "give either --trivariate or --mesh, not both");
    if ((rc = headopt_make("check", z_offs, theta, &c.head)) != CLI_OK)
        return rc;
    if (!(eps > 0.0))
        return cli_fail("check", CLI_USAGE, "--eps must be positive (got %g)", eps);
    c.eps = eps;
    c.eps_given = opts[4].seen;
    c.json = json;
    c.paths_file = pos[0];
    amp_pathset_init(&ps, NULL);
    if ((rc = cli_load_paths("check", pos[0], &ps)) != CLI_OK)
        return rc;
    c.ps = &ps;
    if (json) {
        cli_json_begin(&j, stdout);
        cli_json_str(&j, "input", pos[0]);
    }
    for (i = 0; i < NCHECKERS; i++) {
        if (json)
            cli_json_obj(&j, checkers[i].name);
        if (skip[i]) {
            if (json) {
                cli_json_bool(&j, "ran", 0);
                cli_json_str(&j, "reason", "skipped on request");
            } else {
                printf("%s: skipped (--no-%s)\n", checkers[i].name, checkers[i].name);
            }
        } else {
            rc = checkers[i].run(&c, json ? &j : NULL);
            failed |= rc == CLI_FAILED;
            usage |= rc == CLI_USAGE;
        }
        if (json)
            cli_json_close(&j);
    }
    if (json) {
        cli_json_bool(&j, "ok", !failed && !usage);
        cli_json_end(&j);
    }
    amp_pathset_free(&ps);
    return usage ? CLI_USAGE : failed ? CLI_FAILED : CLI_OK;
}
