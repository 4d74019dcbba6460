/*
 * ampath check PATHS.amp — independent verification (SPEC §4). This minimal
 * dispatcher handles --trivariate (tools/check_trivariate.c); the full
 * dispatcher with the other checkers (tools/check_*.c) replaces it at merge.
 */
#include <string.h>

#include "check_stroke.h"
#include "checkers.h"

const char cmd_check_usage[] =
    "verify paths independently: coverage of a trivariate within eps (sampled); exit 1 on a failure\n"
    "usage: ampath check PATHS.amp --trivariate F|--mesh MESH.stl [--eps E] [--samples N] [--seed S] [--json]\n"
    "  --trivariate F  a .spl file (its first trivariate) or a built-in model name\n"
    "  --mesh M        an STL mesh: coverage gap of its solid (points sampled inside it) and no path vertex\n"
    "                  more than 0.01 mm outside it\n"
    "  --eps E         allowed gap in mm; default: the eps recorded by 'ampath cover' in the file,\n"
    "                  else the largest vertex radius\n"
    "  --samples N     volume samples, half uniform in parameters, half uniform in space (default 20000)\n"
    "  --seed S        sampling seed (default 1)\n"
    "  --json          {\"ok\", \"trivariate_coverage\": {eps, coverage_gap_mm, samples, worst_point, ...}}\n";

int cmd_check(int argc, char **argv)
{
    int k;
    for (k = 1; k < argc && strncmp(argv[k], "--trivariate", 12) != 0 && strncmp(argv[k], "--mesh", 6) != 0; k++)
        ;
    if (k == argc)
        return check_stroke(argc, argv);
    {
    const char *pos[1], *tri = NULL, *mesh = NULL;
    double eps = 0;
    long samples = 20000, seed = 1;
    int json = 0, npos = 0, rc;
    cli_json j;
    cli_opt opts[] = {{"trivariate", CLI_STR, &tri, 0}, {"eps", CLI_DOUBLE, &eps, 0},
                      {"samples", CLI_LONG, &samples, 0}, {"seed", CLI_LONG, &seed, 0},
                      {"json", CLI_FLAG, &json, 0},       {"mesh", CLI_STR, &mesh, 0},
                      {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("check", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (!tri && !mesh)
        return cli_fail("check", CLI_USAGE, "this build checks coverage only: give --trivariate F or --mesh M");
    if (opts[1].seen && !(eps > 0))
        return cli_fail("check", CLI_USAGE, "--eps must be positive");
    if (samples < 1 || samples > 100000000L)
        return cli_fail("check", CLI_USAGE, "--samples must be in 1..100000000");
    if (json)
        cli_json_begin(&j, stdout);
    rc = tri ? check_trivariate(pos[0], tri, eps, samples, (unsigned long)seed, json ? &j : NULL) : CLI_OK;
    if (mesh && rc != CLI_USAGE) {
        int rm = check_mesh(pos[0], mesh, eps, samples, (unsigned long)seed, json ? &j : NULL);
        rc = rm == CLI_USAGE || rc == CLI_OK ? rm : rc;
    }
    if (json) {
        if (rc != CLI_USAGE)
            cli_json_bool(&j, "ok", rc == CLI_OK);
        cli_json_end(&j);
    }
    return rc;
}
}
