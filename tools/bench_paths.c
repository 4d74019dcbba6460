/* Benchmark: .amp write and parse throughput against a plain fprintf/sscanf baseline. */
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "cli.h"

static void make_paths(amp_pathset *ps, size_t npaths, size_t nper)
{
    size_t i, k;
    for (i = 0; i < npaths; i++) {
        amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
        for (k = 0; k < nper; k++)
            amp_pathset_push(ps, amp_v3((double)k * 0.1, (double)i * 0.37, 0.2 * (double)(k % 7)), 0.5, NULL);
    }
}

int bench_paths(cli_json *j, int quick)
{
    amp_pathset ps, back;
    amp_buf buf;
    size_t npaths = quick ? 100 : 2000;
    double t0, t_write, t_parse, t_one, t_base;
    int threads = 1;
    volatile double sink = 0.0;
    int rc = CLI_OK;

    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&back, NULL);
    amp_buf_init(&buf, NULL);
    make_paths(&ps, npaths, 100);
    t0 = cli_now();
    amp_pathset_write(&ps, NULL, amp_buf_sink, &buf, NULL);
    t_write = cli_now() - t0;
    t0 = cli_now();
    if (amp_pathset_parse(&back, buf.data, buf.len, NULL) != AMP_OK || back.nverts != ps.nverts)
        rc = CLI_FAILED;
    t_parse = cli_now() - t0;
    /* baseline of the chunked read (lib/paths_parse.c): the same text on one thread, in one piece */
#ifdef _OPENMP
    threads = omp_get_max_threads();
    omp_set_num_threads(1);
#endif
    amp_pathset_clear(&back);
    t0 = cli_now();
    if (amp_pathset_parse(&back, buf.data, buf.len, NULL) != AMP_OK || back.nverts != ps.nverts)
        rc = CLI_FAILED;
    t_one = cli_now() - t0;
#ifdef _OPENMP
    omp_set_num_threads(threads);
#endif
    /* baseline: strtod over every number, the floor any text parser pays */
    t0 = cli_now();
    {
        char *s = buf.data, *end;
        while (*s) {
            double d = strtod(s, &end);
            if (end == s)
                end = s + 1;
            sink += d;
            s = end;
        }
    }
    t_base = cli_now() - t0;
    (void)sink;
    if (j) {
        cli_json_int(j, "vertices", (long long)ps.nverts);
        cli_json_num(j, "write_s", t_write);
        cli_json_num(j, "parse_s", t_parse);
        cli_json_int(j, "parse_threads", threads);
        cli_json_num(j, "parse_one_thread_s", t_one);
        cli_json_num(j, "strtod_baseline_s", t_base);
        cli_json_num(j, "parse_over_baseline", t_one / cli_positive(t_base));
    } else {
        printf("%lu vertices, %.1f MB: write %.3f s, parse %.3f s on %d thread(s) (one thread %.3f s: %.2fx; "
               "one thread against the bare strtod baseline %.3f s: %.2fx)\n",
               (unsigned long)ps.nverts, buf.len / 1e6, t_write, t_parse, threads, t_one, t_one / cli_positive(t_parse),
               t_base, t_one / cli_positive(t_base));
    }
    amp_buf_free(&buf);
    amp_pathset_free(&ps);
    amp_pathset_free(&back);
    return rc;
}
