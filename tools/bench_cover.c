/*
 * Benchmark: covering the built-in helix at eps 0.5 mm ([P1 §4.1]):
 * wall time, surfaces, curves, measured gap, against a same-run baseline — the
 * time to evaluate the trivariate at every path vertex once (the floor any
 * covering that outputs these vertices pays).
 */
#include <stdlib.h>

#include "cli.h"

int bench_cover(cli_json *j, int quick)
{
    amp_spline v;
    amp_cover_opts o;
    amp_cover_stats st;
    amp_coverage g;
    amp_coverage_domain dom = {NULL, NULL, 0.0};
    amp_pathset ps;
    double t0, t_cover, t_base, t_gap, *par;
    size_t i, n;
    amp_vec3 *pts;
    int rc = CLI_OK;
    if (amp_trivariate_model("helix", NULL, &v, NULL) != AMP_OK)
        return CLI_FAILED;
    amp_cover_opts_default(&o);
    o.eps = quick ? 2.0 : 0.5;
    o.dir = 2; /* the paper's w, as every earlier run of this benchmark (the most curves: the heaviest case) */
    amp_pathset_init(&ps, NULL);
    t0 = cli_now();
    if (amp_cover_trivariate(&v, &o, &ps, &st, NULL) != AMP_OK) {
        amp_spline_free(&v);
        return CLI_FAILED;
    }
    t_cover = cli_now() - t0;
    /* baseline: one evaluation per output vertex, at random parameters */
    n = ps.nverts;
    par = malloc(3 * n * sizeof *par);
    pts = malloc(n * sizeof *pts);
    for (i = 0; i < 3 * n; i++)
        par[i] = (double)((i * 2654435761UL) % 1000003UL) / 1000003.0;
    t0 = cli_now();
    for (i = 0; i < n; i++)
        amp_spline_eval(&v, par + 3 * i, &pts[i], NULL);
    t_base = cli_now() - t0;
    t0 = cli_now();
    dom.trivariate = &v;
    if (amp_check_coverage(&ps, &dom, quick ? 5000 : 20000, 1, &g, NULL) != AMP_OK || g.gap > o.eps)
        rc = CLI_FAILED;
    t_gap = cli_now() - t0;
    if (j) {
        cli_json_num(j, "eps", o.eps);
        cli_json_num(j, "cover_s", t_cover);
        cli_json_int(j, "surfaces", (long long)st.surfaces);
        cli_json_int(j, "curves", (long long)st.curves);
        cli_json_int(j, "vertices", (long long)st.vertices);
        cli_json_num(j, "length_mm", st.length);
        cli_json_num(j, "eval_per_vertex_baseline_s", t_base);
        cli_json_num(j, "cover_over_baseline", t_cover / cli_positive(t_base));
        cli_json_num(j, "coverage_gap_mm", g.gap);
        cli_json_num(j, "gap_measurement_s", t_gap);
        cli_json_num(j, "over_coverage", g.volume > 0 ? g.deposited / g.volume : 0);
    } else
        printf("helix eps %.2f mm: %.3f s, %lu surfaces, %lu curves, %lu vertices, %.0f mm of path; "
               "x%.1f the per-vertex evaluation baseline (%.3f s); measured gap %.3f mm (%.3f s), "
               "over-coverage %.2f\n",
               o.eps, t_cover, (unsigned long)st.surfaces, (unsigned long)st.curves, (unsigned long)st.vertices,
               st.length, t_cover / cli_positive(t_base), t_base, g.gap, t_gap,
               g.volume > 0 ? g.deposited / g.volume : 0);
    free(par);
    free(pts);
    amp_pathset_free(&ps);
    amp_spline_free(&v);
    return rc;
}
