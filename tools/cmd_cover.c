/* ampath cover TRIVARIATE — [P1 §4.1]: adaptive iso-surfaces (Algorithm 1), then iso-curves (docs/interfaces.md §4). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkers.h"
#include "cli.h"

const char cmd_cover_usage[] =
    "cover a trivariate (.spl or built-in name) by print paths within eps (paper 1, 4.1)\n"
    "usage: ampath cover TRIVARIATE --eps E [--dir auto|u|v|w] [--min-depth M] [--measure iso|arclen]\n"
    "                    -o PATHS.amp [--radius R] [--chord-tol T] [--cells N] [--samples S] [--json]\n"
    "  TRIVARIATE      a .spl file (its first trivariate) or a built-in model name (helix, torus-quarter, vase)\n"
    "  --eps E         required: largest distance from any point of the volume to a path, mm\n"
    "  --dir D         direction of the covering iso-surfaces (the paper's is w); default auto: the one whose\n"
    "                  curves are the most level, so that Algorithm 2 cuts them least (docs/splines.md)\n"
    "  --min-depth M   Algorithm 1's minimal subdivision depth m, default 0 (periodic volumes need m >= 1)\n"
    "  --measure X     arclen (default): Appendix Lemma A.1/A.2 bound, guarantees coverage;\n"
    "                  iso: the paper's iso-distance, may leave the Fig. 5 gap\n"
    "  --radius R      nominal deposition radius on every vertex, default 0.5 mm\n"
    "  --chord-tol T   polyline deviation from the curves, default eps/20 mm (part of the eps budget)\n"
    "  --cells N       trimming cells per parametric direction (1..64), default 16\n"
    "  --samples S     samples of the coverage measurement reported with --json, default 20000 (0: skip)\n"
    "  --max-curves N  refuse when the curves estimated from Lemma A.2 on the control net exceed N\n"
    "                  (default 1e6: runs of minutes and gigabytes)\n"
    "  --max-length L  the same for their total length, mm (default 5e7: 50 km)\n"
    "  -o FILE         write the paths (.amp)\n"
    "  --json          {dir, dir_scores, surfaces, curves, vertices, length_mm, coverage_gap_mm, over_coverage, volume_mm3,\n"
    "                   deposited_mm3, time_s, depth_limited}\n";

/* The command line, validated; o holds the covering options but the direction of auto. */
typedef struct cover_args {
    const char *input, *out, *measure;
    double eps, chord;
    long m, samples;
    int json;
    amp_cover_opts o;
} cover_args;

/* What the report shows of one covering. */
typedef struct cover_figures {
    amp_cover_stats st;
    amp_coverage gap;
    double score[3], seconds;
    char dirname[2];
} cover_figures;

/* The command line into @p a; every reason to refuse it is printed here (CLI_USAGE). */
static int cover_parse(int argc, char **argv, cover_args *a)
{
    const char *pos[1], *dir = "auto";
    double radius = 0.5;
    long cells = 16;
    int npos = 0, rc;
    cli_opt opts[] = {{"eps", CLI_DOUBLE, &a->eps, 0},          {"dir", CLI_STR, &dir, 0},
                      {"min-depth", CLI_LONG, &a->m, 0},        {"measure", CLI_STR, &a->measure, 0},
                      {"radius", CLI_DOUBLE, &radius, 0},       {"chord-tol", CLI_DOUBLE, &a->chord, 0},
                      {"cells", CLI_LONG, &cells, 0},           {"samples", CLI_LONG, &a->samples, 0},
                      {"output", CLI_STR, &a->out, 0},          {"json", CLI_FLAG, &a->json, 0},
                      {NULL, CLI_FLAG, NULL, 0}};
    memset(a, 0, sizeof *a);
    a->measure = "arclen";
    a->samples = 20000;
    rc = cli_parse("cover", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    a->input = pos[0];
    if (!cli_given(opts, "eps") || !(a->eps > 0))
        return cli_fail("cover", CLI_USAGE, "--eps E (> 0, mm) is required");
    amp_cover_opts_default(&a->o);
    a->o.eps = a->eps;
    a->o.radius = radius;
    a->o.chord_tol = a->chord;
    if (strcmp(dir, "auto") == 0)
        a->o.dir = AMP_COVER_AUTO;
    else if (strlen(dir) == 1 && strchr("uvw", dir[0]))
        a->o.dir = dir[0] == 'u' ? 0 : dir[0] == 'v' ? 1 : 2;
    else
        return cli_fail("cover", CLI_USAGE, "--dir must be auto, u, v or w");
    if (strcmp(a->measure, "arclen") == 0)
        a->o.measure = AMP_COVER_ARCLEN;
    else if (strcmp(a->measure, "iso") == 0)
        a->o.measure = AMP_COVER_ISO;
    else
        return cli_fail("cover", CLI_USAGE, "--measure must be iso or arclen");
    if (a->m < 0 || a->m > 30 || cells < 1 || cells > 64 || a->samples < 0 || !(radius > 0) || a->chord < 0)
        return cli_fail("cover", CLI_USAGE, "option out of range (0 <= m <= 30, 1 <= cells <= 64, radius > 0)");
    a->o.min_depth = (int)a->m;
    a->o.cells = (int)cells;
    return CLI_OK;
}

/* The direction (auto: the picked one) and the work estimate, refused above the limits. */
static int cover_direction(cover_args *a, const amp_spline *v, cover_figures *f)
{
    amp_error err;
    double curves, length;
    int picked;
    amp_error_clear(&err);
    /* the scores are reported whatever was asked; the choice is taken only for auto */
    if (amp_cover_pick_dir(v, &picked, f->score, &err) != AMP_OK)
        return cli_fail_err("cover", &err);
    if (a->o.dir == AMP_COVER_AUTO)
        a->o.dir = picked;
    f->dirname[0] = "uvw"[a->o.dir];
    if (amp_cover_estimate(v, &a->o, &curves, &length, &err) != AMP_OK)
        return cli_fail_err("cover", &err);
    if (!(curves <= cli_work.max_curves))
        return cli_work_refuse("cover", "covering curves", curves, cli_work.max_curves, "max-curves");
    if (!(length <= cli_work.max_length))
        return cli_work_refuse("cover", "mm of paths", length, cli_work.max_length, "max-length");
    return CLI_OK;
}

static void cover_json(const cover_args *a, const cover_figures *f)
{
    cli_json j;
    cli_json_begin(&j, stdout);
    cli_json_num(&j, "eps", a->eps);
    cli_json_str(&j, "measure", a->measure);
    cli_json_str(&j, "dir", f->dirname);
    cli_json_obj(&j, "dir_scores");
    cli_json_num(&j, "u", f->score[0]);
    cli_json_num(&j, "v", f->score[1]);
    cli_json_num(&j, "w", f->score[2]);
    cli_json_close(&j);
    cli_json_int(&j, "min_depth", a->m);
    cli_json_int(&j, "surfaces", (long long)f->st.surfaces);
    cli_json_int(&j, "curves", (long long)f->st.curves);
    cli_json_int(&j, "vertices", (long long)f->st.vertices);
    cli_json_num(&j, "length_mm", f->st.length);
    if (a->samples > 0) {
        cli_json_num(&j, "coverage_gap_mm", f->gap.gap);
        cli_json_int(&j, "coverage_samples", (long long)f->gap.samples);
        cli_json_num(&j, "volume_mm3", f->gap.volume);
        cli_json_num(&j, "deposited_mm3", f->gap.deposited);
        cli_json_num(&j, "over_coverage", f->gap.volume > 0 ? f->gap.deposited / f->gap.volume : 0);
    }
    cli_json_bool(&j, "depth_limited", f->st.depth_limited);
    cli_json_num(&j, "time_s", f->seconds);
    cli_json_end(&j);
}

/* Algorithm 1 on @p v into @p ps, timed, then the paths saved (-o) and their coverage measured (--json). */
static int cover_run(cover_args *a, const amp_spline *v, amp_pathset *ps, cover_figures *f)
{
    amp_coverage_domain dom = {NULL, NULL, 0.0};
    amp_error err;
    cli_progress bar;
    char comment[200];
    double t0;
    amp_status st;
    amp_error_clear(&err);
    cli_progress_begin(&bar, "cover");
    a->o.progress = cli_progress_fn;
    a->o.progress_user = &bar;
    t0 = cli_now();
    st = amp_cover_trivariate(v, &a->o, ps, &f->st, &err);
    cli_progress_end(&bar);
    if (st != AMP_OK)
        return cli_fail_err("cover", &err);
    f->seconds = cli_now() - t0;
    if (f->st.depth_limited)
        fprintf(stderr, "ampath cover: warning: recursion depth limit reached; coverage is not guaranteed\n");
    snprintf(comment, sizeof comment, "ampath cover %s: eps %.17g measure %s dir %s min-depth %ld", a->input,
             a->eps, a->measure, f->dirname, a->m);
    if (a->out && cli_save_paths("cover", a->out, ps, comment) != CLI_OK)
        return CLI_USAGE;
    dom.trivariate = v;
    if (a->json && a->samples > 0 &&
        amp_check_coverage(ps, &dom, (size_t)a->samples, 1, &f->gap, &err) != AMP_OK)
        return cli_fail_err("cover", &err);
    return CLI_OK;
}

int cmd_cover(int argc, char **argv)
{
    cover_args a;
    cover_figures f;
    amp_spline v;
    amp_pathset ps;
    int rc = cover_parse(argc, argv, &a);
    if (rc != CLI_OK)
        return rc;
    rc = cli_load_trivariate("cover", a.input, &v);
    if (rc != CLI_OK)
        return rc;
    memset(&f, 0, sizeof f);
    amp_pathset_init(&ps, NULL);
    rc = cover_direction(&a, &v, &f);
    if (rc == CLI_OK)
        rc = cover_run(&a, &v, &ps, &f);
    if (rc == CLI_OK && a.json)
        cover_json(&a, &f);
    else if (rc == CLI_OK) /* one line, as every command prints without --json */
        printf("%s: eps %g mm, dir %s, %lu iso-surfaces, %lu curves, %.1f mm of paths%s%s%s\n", a.input, a.eps,
               f.dirname, (unsigned long)f.st.surfaces, (unsigned long)f.st.curves, f.st.length,
               f.st.depth_limited ? " (depth limit reached)" : "", a.out ? " -> " : "", a.out ? a.out : "");
    amp_spline_free(&v);
    amp_pathset_free(&ps);
    return rc;
}
