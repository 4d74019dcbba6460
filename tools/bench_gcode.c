/* Benchmark: G-code iterator lines/s against a plain snprintf of the same moves in the same run. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

/* Layers of concentric rings with a radius that varies along each ring (exercises the volumetric cap). */
static void bench_rings(amp_pathset *ps, int layers, int rings, int nper)
{
    int i, j, k;
    for (i = 0; i < layers; i++)
        for (j = 0; j < rings; j++) {
            amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
            for (k = 0; k <= nper; k++) {
                double w = 2.0 * AMP_PI * (double)k / nper, rad = 5.0 + 0.9 * j;
                amp_pathset_push(ps, amp_v3(rad * cos(w), rad * sin(w), 0.3 * (i + 1)),
                                 0.25 + 0.15 * sin(3 * w) * sin(3 * w), NULL);
            }
        }
}

int bench_gcode(cli_json *j, int quick)
{
    amp_pathset ps;
    amp_gcode_iter it;
    amp_error err;
    char line[AMP_GCODE_LINE_CAP];
    size_t lines = 0, bytes = 0, base_lines = 0, base_bytes = 0, i;
    double t0, t_init, t_iter, t_base, e = 0;
    int rc = CLI_OK;
    amp_pathset_init(&ps, NULL);
    bench_rings(&ps, quick ? 10 : 100, 10, 200);
    t0 = cli_now();
    if (amp_gcode_iter_init(&it, &ps, NULL, &err) != AMP_OK) {
        amp_pathset_free(&ps);
        return CLI_FAILED;
    }
    t_init = cli_now() - t0;
    t0 = cli_now();
    while (amp_gcode_iter_next(&it, line, sizeof line, &err) == 1) {
        lines++;
        bytes += strlen(line) + 1;
    }
    t_iter = cli_now() - t0;
    /* baseline: one snprintf per vertex with the same fields, no planning, no checks */
    t0 = cli_now();
    for (i = 0; i < ps.nverts; i++) {
        const amp_pvert *v = &ps.verts[i];
        int n;
        e += v->r * 0.1;
        n = snprintf(line, sizeof line, "G1 X%.3f Y%.3f Z%.3f E%.5f F%.1f", v->p.x, v->p.y, v->p.z, e, 1800.0);
        base_bytes += (size_t)n + 1;
        base_lines++;
    }
    t_base = cli_now() - t0;
    if (lines != it.est.lines)
        rc = CLI_FAILED;
    if (j) {
        cli_json_int(j, "lines", (long long)lines);
        cli_json_int(j, "segments", (long long)it.stats.segments);
        cli_json_num(j, "init_s", t_init);
        cli_json_num(j, "iterate_s", t_iter);
        cli_json_num(j, "lines_per_s", lines / cli_positive(t_iter));
        cli_json_num(j, "snprintf_lines_per_s", base_lines / cli_positive(t_base));
        cli_json_num(j, "iterator_over_snprintf", (lines / cli_positive(t_iter)) /
                                                      (base_lines / cli_positive(t_base)));
        cli_json_num(j, "mbytes_per_s", bytes / 1e6 / cli_positive(t_iter));
    } else {
        printf("%lu lines (%.1f MB): init (estimate pass) %.3f s, lines %.3f s = %.2f M lines/s\n",
               (unsigned long)lines, bytes / 1e6, t_init, t_iter, lines / 1e6 / cli_positive(t_iter));
        printf("plain snprintf baseline: %.2f M lines/s; iterator speed = %.2fx the baseline\n",
               base_lines / 1e6 / cli_positive(t_base),
               (lines / cli_positive(t_iter)) / (base_lines / cli_positive(t_base)));
    }
    (void)base_bytes;
    amp_pathset_free(&ps);
    return rc;
}
