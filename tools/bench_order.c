/* Benchmark (docs/interfaces.md §7): ordering time (Algorithm 2, [P1 §5.1]) against fragment count, with a same-run
 * pairwise baseline (all pairs of fragments tested, then a topological sort) on the small sizes. */
#include <stdlib.h>

#include "cli.h"

/* Wavy layers of parallel lines 0.4 mm apart, crossing direction every layer: about n fragments of 0.5 mm. */
static void layers(amp_pathset *ps, size_t n)
{
    size_t nl = n >= 100000 ? 40 : 10, l, i, k;
    double side = sqrt((double)n / (4.0 * (double)nl)), step = 0.5;
    size_t nlines = (size_t)(side / step) + 1, nseg = (size_t)(side / 0.25) + 1;
    for (l = 0; l < nl; l++)
        for (i = 0; i < nlines; i++) {
            amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
            for (k = 0; k <= nseg; k++) {
                double u = side * (double)k / (double)nseg, v = step * (double)i;
                double x = l % 2 ? v : u, y = l % 2 ? u : v;
                amp_pathset_push(ps, amp_v3(x, y, 0.4 * (double)l + 0.3 * sin(x / 3.0) * cos(y / 4.0)), 0.25, NULL);
            }
        }
}

/* Baseline: the below graph by testing every ordered pair, then Kahn's topological order. */
static double pairwise_order(const amp_pathset *ps, const amp_head *h, size_t *edges)
{
    amp_fragments fs;
    size_t a, b, *indeg, *queue, head = 0, tail = 0, done = 0;
    double t0 = cli_now();
    *edges = 0;
    if (amp_fragments_build(&fs, ps, h->z_offs, NULL, NULL) != AMP_OK)
        return -1;
    indeg = calloc(fs.n + 1, sizeof *indeg);
    queue = calloc(fs.n + 1, sizeof *queue);
    for (a = 0; a < fs.n; a++)
        for (b = 0; b < fs.n; b++)
            if (amp_fragment_below(&fs, h, a, b)) {
                indeg[b]++;
                (*edges)++;
            }
    for (a = 0; a < fs.n; a++)
        if (indeg[a] == 0)
            queue[tail++] = a;
    while (head < tail) {
        a = queue[head++];
        done++;
        for (b = 0; b < fs.n; b++)
            if (indeg[b] && amp_fragment_below(&fs, h, a, b) && --indeg[b] == 0)
                queue[tail++] = b;
    }
    free(indeg);
    free(queue);
    b = fs.n;
    amp_fragments_free(&fs);
    return done == b ? cli_now() - t0 : -1;
}

int bench_order(cli_json *j, int quick)
{
    static const size_t sizes[] = {1000, 10000, 100000, 1000000};
    size_t ns = quick ? 2 : 4, i, worse = 0;
    amp_order_opts o, og;
    double t_big = -1;
    int rc = CLI_OK;
    amp_order_opts_default(&o);
    amp_order_opts_default(&og);
    og.improve = 0;
    if (j)
        cli_json_arr(j, "sizes");
    for (i = 0; i < ns; i++) {
        amp_pathset ps, out;
        amp_order_stats st, sg;
        amp_error err;
        double t0, t_order, t_greedy, t_pair = -1;
        size_t edges = 0;
        amp_pathset_init(&ps, NULL);
        amp_pathset_init(&out, NULL);
        layers(&ps, sizes[i]);
        t0 = cli_now();
        if (amp_order(&ps, &o, &out, &st, &err) != AMP_OK) {
            fprintf(stderr, "bench order: %s\n", err.msg);
            rc = CLI_FAILED;
        }
        t_order = cli_now() - t0;
        amp_pathset_clear(&out);
        t0 = cli_now();
        if (amp_order(&ps, &og, &out, &sg, &err) != AMP_OK) {
            fprintf(stderr, "bench order: %s\n", err.msg);
            rc = CLI_FAILED;
        }
        t_greedy = cli_now() - t0;
        worse += st.subdivisions > sg.subdivisions;
        if (st.fragments >= 1000000)
            t_big = t_order;
        if (sizes[i] <= (quick ? 1000u : 10000u))
            t_pair = pairwise_order(&ps, &o.head, &edges);
        if (j) {
            cli_json_obj(j, NULL);
            cli_json_int(j, "fragments", (long long)st.fragments);
            cli_json_int(j, "paths", (long long)st.paths_in);
            cli_json_int(j, "subdivisions", (long long)st.subdivisions);
            cli_json_int(j, "subdivisions_greedy", (long long)sg.subdivisions);
            cli_json_num(j, "order_s", t_order);
            cli_json_num(j, "greedy_s", t_greedy);
            cli_json_num(j, "fragments_per_s", (double)st.fragments / cli_positive(t_order));
            if (t_pair >= 0) {
                cli_json_num(j, "pairwise_s", t_pair);
                cli_json_int(j, "pairwise_edges", (long long)edges);
                cli_json_num(j, "speedup_over_pairwise", t_pair / cli_positive(t_order));
            }
            cli_json_close(j);
        } else {
            printf("%8lu fragments (%lu paths): order %.3f s (%.0f fragments/s, %lu subdivisions); plain greedy %.3f s, "
                   "%lu subdivisions",
                   (unsigned long)st.fragments, (unsigned long)st.paths_in, t_order,
                   (double)st.fragments / cli_positive(t_order), (unsigned long)st.subdivisions, t_greedy,
                   (unsigned long)sg.subdivisions);
            if (t_pair >= 0)
                printf("; pairwise baseline %.3f s (%lu edges): %.1fx faster", t_pair, (unsigned long)edges,
                       t_pair / cli_positive(t_order));
            printf("\n");
            fflush(stdout);
        }
        amp_pathset_free(&ps);
        amp_pathset_free(&out);
    }
    if (j) {
        cli_json_close(j);
        if (t_big >= 0) {
            cli_json_num(j, "million_s", t_big);
            cli_json_bool(j, "million_met", t_big <= 5.0);
        }
        cli_json_bool(j, "never_more_cuts_than_greedy", worse == 0);
    } else {
        if (t_big >= 0)
            printf("  target 10^6 fragments ordered in <= 5 s (1 thread unless OMP_NUM_THREADS): %.2f s %s\n", t_big,
                   t_big <= 5.0 ? "met" : "NOT MET");
        printf("  target improved ordering never cuts more than plain greedy: %lu of %lu sizes cut more, %s\n",
               (unsigned long)worse, (unsigned long)ns, worse == 0 ? "met" : "NOT MET");
    }
    return rc;
}
