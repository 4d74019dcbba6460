/* ampath order — fragments and Algorithm 2 ([P1 §5.1]): a gouge-free print order. */
#include <string.h>

#include "cli.h"
#include "headopt.h"

const char cmd_order_usage[] =
    "order paths for printing without gouging (paper 5.1: fragments, below graph, Algorithm 2)\n"
    "usage: ampath order PATHS.amp [--z-offs Z] [--theta DEG] [--greedy] [--compare] [--nearest 0|1] [--travel-z W]\n"
    "                   [--max-edges N] [--json]\n"
    "                   -o ORDERED.amp\n"
    HEADOPT_HELP
    "  --greedy        write the plain greedy order of Algorithm 2 instead of the improved one\n"
    "                  (continuation of the curve just printed, look-ahead, merging of adjacent sub-curves)\n"
    "  --compare       compute both orderings and report both (the plain greedy one is the baseline of the\n"
    "                  improvements; it is computed only on request)\n"
    "  --nearest M     1 (default): among equally good runs start the one nearest to the head; 0: off\n"
    "  --travel-z W    re-sequence the sub-curves for travel, a mm of Z costing W mm of XY (default 3; 0: off,\n"
    "                  Algorithm 2's own order); same sub-curves and cuts, each still after everything below it\n"
    "  --lookahead K   candidate runs simulated per step when improving (default 16, 1..16)\n"
    "  --max-edges N   also list the below graph up to N edges, for the report (default 0: skip; slow, ordering never needs it)\n"
    "  --json          print one JSON object: fragments, below-graph edges, subdivisions greedy vs improved, times\n"
    "  -o FILE         write the ordered paths (.amp); cut points get interpolated radii\n"
    "Without --compare only the ordering written is computed.\n";


/* The command line, validated; o holds the head and the ordering options. */
typedef struct order_args {
    const char *input, *output;
    double z_offs, theta, travel_z;
    long max_edges, nearest;
    int json, greedy, compare;
    amp_order_opts o;
} order_args;

/* The figures of the orderings run (greedy: g, improved: i) and of the below graph. */
typedef struct order_result {
    amp_order_stats sg, si;
    double t_greedy, t_improved, t_graph;
    size_t edges;
    int graph_done, do_g, do_i;
} order_result;

/* The command line into @p a; every reason to refuse it is printed here (CLI_USAGE). */
static int order_parse(int argc, char **argv, order_args *a)
{
    const char *pos[1];
    long lookahead = 16;
    int npos = 0, rc;
    cli_opt opts[] = {{"z-offs", CLI_DOUBLE, &a->z_offs, 0},  {"theta", CLI_DOUBLE, &a->theta, 0},
                      {"greedy", CLI_FLAG, &a->greedy, 0},    {"max-edges", CLI_LONG, &a->max_edges, 0},
                      {"lookahead", CLI_LONG, &lookahead, 0}, {"json", CLI_FLAG, &a->json, 0},
                      {"compare", CLI_FLAG, &a->compare, 0},  {"nearest", CLI_LONG, &a->nearest, 0},
                      {"travel-z", CLI_DOUBLE, &a->travel_z, 0},
                      {"output", CLI_STR, &a->output, 0},     {NULL, CLI_FLAG, NULL, 0}};
    memset(a, 0, sizeof *a);
    a->z_offs = AMP_HEAD_DEFAULT_Z_OFFS;
    a->theta = 72.0;
    a->travel_z = AMP_ORDER_TRAVEL_Z_WEIGHT;
    a->nearest = 1;
    rc = cli_parse("order", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    a->input = pos[0];
    amp_order_opts_default(&a->o);
    if ((rc = headopt_make("order", a->z_offs, a->theta, &a->o.head)) != CLI_OK)
        return rc;
    if (a->max_edges < 0)
        return cli_fail("order", CLI_USAGE, "--max-edges must be >= 0");
    if (lookahead < 1 || lookahead > 16)
        return cli_fail("order", CLI_USAGE, "--lookahead must be between 1 and 16");
    a->o.lookahead = (size_t)lookahead;
    if (a->nearest < 0 || a->nearest > 1)
        return cli_fail("order", CLI_USAGE, "--nearest must be 0 or 1");
    a->o.nearest = (int)a->nearest;
    if (!(a->travel_z >= 0.0 && a->travel_z <= 1e6))
        return cli_fail("order", CLI_USAGE, "--travel-z must be between 0 and 1e6");
    a->o.travel_z_weight = a->travel_z;
    return CLI_OK;
}

/* One ordering (plain greedy or improved) of @p ps into @p out, timed, with its progress bar. */
static amp_status order_once(amp_order_opts *o, const amp_pathset *ps, int improve, cli_progress *bar,
                             amp_pathset *out, amp_order_stats *st, double *seconds, amp_error *err)
{
    double t0 = cli_now();
    amp_status s;
    o->improve = improve;
    cli_progress_begin(bar, improve ? "order" : "order greedy");
    s = amp_order(ps, o, out, st, err);
    cli_progress_end(bar);
    if (s == AMP_OK)
        *seconds = cli_now() - t0;
    return s;
}

/* The explicit graph is for reporting only: a wide cone makes it dense, so it is capped (its failures leave it
 * unlisted, not the run failed). */
static void order_graph(const order_args *a, const amp_pathset *ps, order_result *r)
{
    amp_fragments fs;
    amp_below_graph g;
    amp_error err;
    double t0;
    amp_error_clear(&err);
    if (a->max_edges > 0 && amp_fragments_build(&fs, ps, a->o.head.z_offs, NULL, &err) == AMP_OK) {
        t0 = cli_now();
        if (amp_below_graph_build(&g, &fs, &a->o.head, (size_t)a->max_edges, &err) == AMP_OK) {
            r->edges = g.nedges;
            r->graph_done = 1;
            amp_below_graph_free(&g);
        }
        r->t_graph = cli_now() - t0;
        amp_fragments_free(&fs);
    }
}

static void order_json(const order_args *a, const order_result *r)
{
    const amp_order_stats *w = a->greedy ? &r->sg : &r->si; /* the ordering written */
    cli_json j;
    cli_json_begin(&j, stdout);
    cli_json_str(&j, "input", a->input);
    cli_json_num(&j, "z_offs", a->z_offs);
    cli_json_num(&j, "theta_deg", a->theta);
    cli_json_int(&j, "paths_in", (long long)w->paths_in);
    cli_json_int(&j, "fragments", (long long)w->fragments);
    if (r->graph_done)
        cli_json_int(&j, "below_edges", (long long)r->edges);
    else
        cli_json_num(&j, "below_edges", HUGE_VAL);
    cli_json_bool(&j, "below_edges_complete", r->graph_done);
    if (r->do_g)
        cli_json_int(&j, "subdivisions_greedy", (long long)r->sg.subdivisions);
    if (r->do_i)
        cli_json_int(&j, "subdivisions_improved", (long long)r->si.subdivisions);
    cli_json_int(&j, "subdivisions", (long long)w->subdivisions);
    cli_json_int(&j, "paths_out", (long long)w->pieces);
    if (r->do_g)
        cli_json_int(&j, "steps_greedy", (long long)r->sg.steps);
    if (r->do_i) {
        cli_json_int(&j, "steps_improved", (long long)r->si.steps);
        cli_json_int(&j, "continued_fragments", (long long)r->si.extended);
        cli_json_int(&j, "merges", (long long)r->si.merges);
    }
    cli_json_int(&j, "queries", (long long)w->queries);
    cli_json_str(&j, "written", a->greedy ? "greedy" : "improved");
    cli_json_bool(&j, "nearest", a->nearest != 0);
    cli_json_num(&j, "travel_z", a->travel_z);
    if (r->do_g)
        cli_json_num(&j, "time_greedy_s", r->t_greedy);
    if (r->do_i)
        cli_json_num(&j, "time_improved_s", r->t_improved);
    cli_json_num(&j, "time_graph_s", r->t_graph);
    cli_json_num(&j, "time_s", r->t_greedy + r->t_improved + r->t_graph);
    cli_json_end(&j);
}

static void order_text(const order_args *a, const order_result *r)
{
    const amp_order_stats *in = r->do_i ? &r->si : &r->sg; /* --greedy alone runs no improved ordering */
    printf("%s: %lu paths, %lu fragments (z_offs %g mm, theta %g deg)\n", a->input, (unsigned long)in->paths_in,
           (unsigned long)in->fragments, a->z_offs, a->theta);
    if (r->graph_done)
        printf("below graph: %lu edges (%.3f s)\n", (unsigned long)r->edges, r->t_graph);
    else if (a->max_edges == 0)
        printf("below graph: not listed (--max-edges 0)\n");
    else
        printf("below graph: more than %ld edges, not listed (ordering does not need it)\n", a->max_edges);
    if (r->do_g)
        printf("subdivisions, plain greedy: %lu (%.3f s)\n", (unsigned long)r->sg.subdivisions, r->t_greedy);
    if (r->do_i)
        printf("subdivisions, improved: %lu (%.3f s; %lu fragments continued, %lu merges)\n",
               (unsigned long)r->si.subdivisions, r->t_improved, (unsigned long)r->si.extended,
               (unsigned long)r->si.merges);
    if (a->output)
        printf("wrote %lu paths to %s\n", (unsigned long)(a->greedy ? r->sg : r->si).pieces, a->output);
}

int cmd_order(int argc, char **argv)
{
    order_args a;
    order_result r;
    amp_pathset ps, out_g, out_i;
    amp_error err;
    cli_progress bar;
    int rc = order_parse(argc, argv, &a);
    if (rc != CLI_OK)
        return rc;
    a.o.progress = cli_progress_fn;
    a.o.progress_user = &bar;
    memset(&r, 0, sizeof r);
    r.do_g = a.greedy || a.compare;
    r.do_i = !a.greedy || a.compare;
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out_g, NULL);
    amp_pathset_init(&out_i, NULL);
    amp_error_clear(&err);
    if ((rc = cli_load_paths("order", a.input, &ps)) != CLI_OK)
        return rc;
    if ((r.do_g && order_once(&a.o, &ps, 0, &bar, &out_g, &r.sg, &r.t_greedy, &err) != AMP_OK) ||
        (r.do_i && order_once(&a.o, &ps, 1, &bar, &out_i, &r.si, &r.t_improved, &err) != AMP_OK)) {
        rc = cli_fail_err("order", &err);
        goto cleanup;
    }
    order_graph(&a, &ps, &r);
    if (a.output) {
        char comment[256];
        snprintf(comment, sizeof comment, "ampath order: z_offs %g mm, theta %g deg, %s, %lu subdivisions", a.z_offs,
                 a.theta, a.greedy ? "plain greedy" : "improved", (unsigned long)(a.greedy ? r.sg : r.si).subdivisions);
        if (cli_save_derived("order", a.output, a.greedy ? &out_g : &out_i, comment, a.input) != CLI_OK) {
            rc = CLI_USAGE;
            goto cleanup;
        }
    }
    if (a.json)
        order_json(&a, &r);
    else
        order_text(&a, &r);
cleanup:
    amp_pathset_free(&ps);
    amp_pathset_free(&out_g);
    amp_pathset_free(&out_i);
    return rc;
}
