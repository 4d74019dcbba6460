/* ampath check — independent verification: a dispatcher over the checkers of checkers.h. */
#define _POSIX_C_SOURCE 200809L /* open_memstream */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "checkers.h"
#include "headopt.h"

typedef struct checker {
    const char *name;
    int (*run)(const check_ctx *c, cli_json *j);
} checker;

/* One row per checker; each gets a --no-NAME flag and a "NAME" section in --json. */
static const checker checkers[] = {
    {"coverage", check_coverage},
    {"gouge", check_gouge},
    {"strokes", check_stroke},
    {"support", check_support},
};
#define NCHECKERS (sizeof checkers / sizeof checkers[0])

const char cmd_check_usage[] =
    "verify paths independently; exit 1 when a check fails\n"
    "usage: ampath check PATHS.amp [--trivariate F | --mesh F [--layer H]] [--z-offs Z] [--theta DEG] [--eps E]\n"
    "                    [--samples N] [--seed S] [--no-NAME] [--json]\n"
    "checks (each runs where it applies; --no-NAME skips it):\n"
    "  coverage   every point of the model within eps of a path, measured by sampling (paper 1 §4);\n"
    "             needs --trivariate, or --mesh without --layer (then also: no vertex > 0.01 mm outside)\n"
    "  gouge      no point printed earlier inside the head cone while a later point prints (paper 1 §5.1);\n"
    "             runs when the file has object paths\n"
    "  strokes    no two segments of a planar path cross, no edge printed twice (paper 2 §4); with --mesh\n"
    "             and --layer also inside the layer polygon of the path's height, and every layer with a\n"
    "             printable island (r/2 across, mean half-width r/16: not a micrometre sliver) has a path\n"
    "             (a file without planar paths fails); runs on planar paths\n"
    "options:\n"
    "  --trivariate F  the model as a trivariate: a .spl file (its first trivariate) or a built-in name\n"
    "  --mesh F        the model as an STL mesh\n"
    "  --layer H       the layer height the paths were sliced with (ampath slice); --first-layer H0 too\n"
    "  --tol T         distance tolerance of the stroke 'inside' test, mm (default 1e-6); with --mesh coverage,\n"
    "                  vertices may lie max(T, 0.01) mm outside the mesh (raise T for a tessellated model)\n"
    HEADOPT_HELP
    "  --eps E         allowed coverage gap, mm; default: the eps recorded by 'ampath cover' in the file,\n"
    "                  else the largest vertex radius\n"
    "  --samples N     coverage samples (default 20000); --seed S their seed (default 1)\n"
    "  --support       run the support check even without support paths (a job that needs none)\n"
    "  --overhang DEG  largest overhang from the vertical that holds a bead (default 45)\n"
    "  --max-gap G     air tolerated under a bead, mm (default 1, as 'ampath support --min-gap')\n"
    "  --bridge B      longest unheld stretch between held points, mm (default 5)\n"
    "  --json          one JSON object: {\"input\", \"coverage\": {\"ran\", \"ok\", ...}, \"gouge\": {...},\n"
    "                  \"strokes\": {...}, \"support\": {...}, \"ok\"}\n"
    "Exit status: 0 all checks passed, 1 a check failed, 2 bad usage or input.\n";

/* The command line into @p c (paths file, model, head, tolerances), @p skip (--no-NAME, one per checker) and
 * @p json; every reason to refuse it is printed here (CLI_USAGE). */
static int check_parse(int argc, char **argv, check_ctx *c, int *skip, int *json)
{
    const char *pos[1];
    double z_offs = AMP_HEAD_DEFAULT_Z_OFFS, theta = 72.0, overhang_deg = 45.0;
    long seed = 1;
    int npos = 0, rc;
    char names[NCHECKERS][40];
    cli_opt opts[20 + NCHECKERS];
    size_t i, n = 0;
    c->samples = 20000;
    c->tol = 1e-6;
    c->max_gap = 1.0;
    c->bridge = 5.0;
    opts[n++] = (cli_opt){"trivariate", CLI_STR, &c->trivariate, 0};
    opts[n++] = (cli_opt){"mesh", CLI_STR, &c->mesh, 0};
    opts[n++] = (cli_opt){"z-offs", CLI_DOUBLE, &z_offs, 0};
    opts[n++] = (cli_opt){"theta", CLI_DOUBLE, &theta, 0};
    opts[n++] = (cli_opt){"eps", CLI_DOUBLE, &c->eps, 0};
    opts[n++] = (cli_opt){"samples", CLI_LONG, &c->samples, 0};
    opts[n++] = (cli_opt){"seed", CLI_LONG, &seed, 0};
    opts[n++] = (cli_opt){"layer", CLI_DOUBLE, &c->layer, 0};
    opts[n++] = (cli_opt){"first-layer", CLI_DOUBLE, &c->first_layer, 0};
    opts[n++] = (cli_opt){"tol", CLI_DOUBLE, &c->tol, 0};
    opts[n++] = (cli_opt){"support", CLI_FLAG, &c->support, 0};
    opts[n++] = (cli_opt){"overhang", CLI_DOUBLE, &overhang_deg, 0};
    opts[n++] = (cli_opt){"max-gap", CLI_DOUBLE, &c->max_gap, 0};
    opts[n++] = (cli_opt){"bridge", CLI_DOUBLE, &c->bridge, 0};
    opts[n++] = (cli_opt){"json", CLI_FLAG, json, 0};
    for (i = 0; i < NCHECKERS; i++) {
        snprintf(names[i], sizeof names[i], "no-%s", checkers[i].name);
        opts[n++] = (cli_opt){names[i], CLI_FLAG, &skip[i], 0};
    }
    opts[n] = (cli_opt){NULL, CLI_FLAG, NULL, 0};
    rc = cli_parse("check", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (c->trivariate && c->mesh)
        return cli_fail("check", CLI_USAGE, "give either --trivariate or --mesh, not both");
    if ((rc = headopt_make("check", z_offs, theta, &c->head)) != CLI_OK)
        return rc;
    c->eps_given = cli_given(opts, "eps");
    if (c->eps_given && !(c->eps > 0.0))
        return cli_fail("check", CLI_USAGE, "--eps must be positive (got %g)", c->eps);
    if (c->samples < 1 || c->samples > 100000000L)
        return cli_fail("check", CLI_USAGE, "--samples must be in 1..100000000");
    c->layer_given = cli_given(opts, "layer");
    if (c->layer_given && !(c->layer > 0.0))
        return cli_fail("check", CLI_USAGE, "--layer must be positive (got %g)", c->layer);
    if (c->layer_given && !c->mesh)
        return cli_fail("check", CLI_USAGE, "--layer needs the --mesh that was sliced");
    if (!(c->tol >= 0.0) || c->tol > 1e3)
        return cli_fail("check", CLI_USAGE, "--tol must be in [0, 1000] mm");
    if (!(overhang_deg >= 0.0 && overhang_deg < 90.0))
        return cli_fail("check", CLI_USAGE, "--overhang must be in [0, 90) degrees (got %g)", overhang_deg);
    if (!(c->max_gap >= 0.0 && c->max_gap <= 1e3) || !(c->bridge >= 0.0 && c->bridge <= 1e4))
        return cli_fail("check", CLI_USAGE, "--max-gap and --bridge must be >= 0 mm");
    c->overhang = overhang_deg / 57.295779513082320876;
    c->seed = (unsigned long)seed;
    c->paths_file = pos[0];
    return CLI_OK;
}

/* Run one checker under the progress bar (on a terminal: the checker running and the share of the checks done;
 * a large job's gouge or coverage check takes seconds). Its human line is held back until the bar's line is
 * cleared, so that the two never share a line of the terminal. */
static int run_checker(const checker *k, check_ctx *c, cli_json *j, double done)
{
    cli_progress bar;
    char *text = NULL, label[32];
    size_t len = 0;
    int rc;
    snprintf(label, sizeof label, "check %s", k->name);
    cli_progress_begin(&bar, label);
    c->out = stdout;
    if (bar.enabled && !j && (c->out = open_memstream(&text, &len)) == NULL)
        c->out = stdout;
    cli_progress_update(&bar, done);
    rc = k->run(c, j);
    if (bar.enabled && j) /* the JSON object goes on at the end: the bar keeps its line, as in other commands */
        cli_progress_end(&bar);
    else if (bar.enabled)
        fputs("\r\033[K", stderr); /* the bar's line cleared: the result takes its place */
    if (c->out != stdout) {
        fclose(c->out);
        if (text)
            fputs(text, stdout);
        free(text);
        c->out = stdout;
    }
    return rc;
}

/* The model is read once before any check runs, so that a bad --trivariate or --mesh is refused with its one
 * line and no partial report (the checkers read it again themselves, each as it needs it). */
static int probe_model(const check_ctx *c)
{
    amp_error err;
    amp_mesh m;
    amp_status st;
    if (c->trivariate) {
        amp_spline v;
        int rc = cli_load_trivariate("check", c->trivariate, &v);
        if (rc == CLI_OK)
            amp_spline_free(&v);
        return rc;
    }
    if (!c->mesh)
        return CLI_OK;
    amp_error_clear(&err);
    amp_mesh_init(&m, NULL);
    st = amp_mesh_read_stl_file(&m, c->mesh, &err);
    amp_mesh_free(&m);
    return st == AMP_OK ? CLI_OK : cli_fail_err("check", &err);
}

int cmd_check(int argc, char **argv)
{
    int json = 0, rc, failed = 0, usage = 0;
    int skip[NCHECKERS];
    check_ctx c;
    amp_pathset ps;
    cli_json j;
    size_t i;
    memset(&c, 0, sizeof c);
    c.out = stdout;
    memset(skip, 0, sizeof skip);
    if ((rc = check_parse(argc, argv, &c, skip, &json)) != CLI_OK)
        return rc;
    amp_pathset_init(&ps, NULL);
    if ((rc = cli_load_paths("check", c.paths_file, &ps)) != CLI_OK)
        return rc;
    if ((rc = probe_model(&c)) != CLI_OK) {
        amp_pathset_free(&ps);
        return rc;
    }
    c.ps = &ps;
    if (json) {
        cli_json_begin(&j, stdout);
        cli_json_str(&j, "input", c.paths_file);
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
            rc = run_checker(&checkers[i], &c, json ? &j : NULL, (double)i / NCHECKERS);
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
