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


int cmd_order(int argc, char **argv)
{
    const char *pos[1], *output = NULL;
    double z_offs = AMP_HEAD_DEFAULT_Z_OFFS, theta = 72.0, travel_z = AMP_ORDER_TRAVEL_Z_WEIGHT, t0, t_greedy = 0.0, t_improved = 0.0, t_graph = 0.0;
    long max_edges = 0, lookahead = 16, nearest = 1;
    int json = 0, greedy = 0, compare = 0, npos = 0, rc, graph_done = 0, do_g, do_i;
    amp_pathset ps, out_g, out_i;
    amp_order_opts o;
    amp_order_stats sg, si;
    amp_error err;
    amp_fragments fs;
    amp_below_graph g;
    size_t edges = 0;
    cli_opt opts[] = {{"z-offs", CLI_DOUBLE, &z_offs, 0}, {"theta", CLI_DOUBLE, &theta, 0},
                      {"greedy", CLI_FLAG, &greedy, 0},   {"max-edges", CLI_LONG, &max_edges, 0},
                      {"lookahead", CLI_LONG, &lookahead, 0}, {"json", CLI_FLAG, &json, 0},
                      {"compare", CLI_FLAG, &compare, 0},  {"nearest", CLI_LONG, &nearest, 0},
                      {"travel-z", CLI_DOUBLE, &travel_z, 0},
                      {"output", CLI_STR, &output, 0},    {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("order", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    cli_progress bar;
    amp_order_opts_default(&o);
    o.progress = cli_progress_fn;
    o.progress_user = &bar;
    if ((rc = headopt_make("order", z_offs, theta, &o.head)) != CLI_OK)
        return rc;
    if (max_edges < 0)
        return cli_fail("order", CLI_USAGE, "--max-edges must be >= 0");
    if (lookahead < 1 || lookahead > 16)
        return cli_fail("order", CLI_USAGE, "--lookahead must be between 1 and 16");
    o.lookahead = (size_t)lookahead;
    if (nearest < 0 || nearest > 1)
        return cli_fail("order", CLI_USAGE, "--nearest must be 0 or 1");
    o.nearest = (int)nearest;
    if (!(travel_z >= 0.0 && travel_z <= 1e6))
        return cli_fail("order", CLI_USAGE, "--travel-z must be between 0 and 1e6");
    o.travel_z_weight = travel_z;
    do_g = greedy || compare;
    do_i = !greedy || compare;
    memset(&sg, 0, sizeof sg);
    memset(&si, 0, sizeof si);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out_g, NULL);
    amp_pathset_init(&out_i, NULL);
    amp_error_clear(&err);
    if ((rc = cli_load_paths("order", pos[0], &ps)) != CLI_OK)
        return rc;
    rc = CLI_USAGE;
    if (do_g) {
        t0 = cli_now();
        o.improve = 0;
        cli_progress_begin(&bar, "order greedy");
        if (amp_order(&ps, &o, &out_g, &sg, &err) != AMP_OK)
            goto fail;
        cli_progress_end(&bar);
        t_greedy = cli_now() - t0;
    }
    if (do_i) {
        t0 = cli_now();
        o.improve = 1;
        cli_progress_begin(&bar, "order");
        if (amp_order(&ps, &o, &out_i, &si, &err) != AMP_OK)
            goto fail;
        cli_progress_end(&bar);
        t_improved = cli_now() - t0;
    }
    /* the explicit graph is for reporting only: a wide cone makes it dense, so it is capped */
    if (max_edges > 0 && amp_fragments_build(&fs, &ps, o.head.z_offs, NULL, &err) == AMP_OK) {
        t0 = cli_now();
        if (amp_below_graph_build(&g, &fs, &o.head, (size_t)max_edges, &err) == AMP_OK) {
            edges = g.nedges;
            graph_done = 1;
            amp_below_graph_free(&g);
        }
        t_graph = cli_now() - t0;
        amp_fragments_free(&fs);
    }
    if (output) {
        char comment[256];
        snprintf(comment, sizeof comment, "ampath order: z_offs %g mm, theta %g deg, %s, %lu subdivisions", z_offs,
                 theta, greedy ? "plain greedy" : "improved", (unsigned long)(greedy ? sg : si).subdivisions);
        if (cli_save_derived("order", output, greedy ? &out_g : &out_i, comment, pos[0]) != CLI_OK)
            goto cleanup;
    }
    if (json) {
        cli_json j;
        cli_json_begin(&j, stdout);
        cli_json_str(&j, "input", pos[0]);
        cli_json_num(&j, "z_offs", z_offs);
        cli_json_num(&j, "theta_deg", theta);
        cli_json_int(&j, "paths_in", (long long)(greedy ? sg : si).paths_in);
        cli_json_int(&j, "fragments", (long long)(greedy ? sg : si).fragments);
        if (graph_done)
            cli_json_int(&j, "below_edges", (long long)edges);
        else
            cli_json_num(&j, "below_edges", HUGE_VAL);
        cli_json_bool(&j, "below_edges_complete", graph_done);
        if (do_g)
            cli_json_int(&j, "subdivisions_greedy", (long long)sg.subdivisions);
        if (do_i)
            cli_json_int(&j, "subdivisions_improved", (long long)si.subdivisions);
        cli_json_int(&j, "subdivisions", (long long)(greedy ? sg : si).subdivisions);
        cli_json_int(&j, "paths_out", (long long)(greedy ? sg : si).pieces);
        if (do_g)
            cli_json_int(&j, "steps_greedy", (long long)sg.steps);
        if (do_i) {
            cli_json_int(&j, "steps_improved", (long long)si.steps);
            cli_json_int(&j, "continued_fragments", (long long)si.extended);
            cli_json_int(&j, "merges", (long long)si.merges);
        }
        cli_json_int(&j, "queries", (long long)(greedy ? sg : si).queries);
        cli_json_str(&j, "written", greedy ? "greedy" : "improved");
        cli_json_bool(&j, "nearest", nearest != 0);
        cli_json_num(&j, "travel_z", travel_z);
        if (do_g)
            cli_json_num(&j, "time_greedy_s", t_greedy);
        if (do_i)
            cli_json_num(&j, "time_improved_s", t_improved);
        cli_json_num(&j, "time_graph_s", t_graph);
        cli_json_num(&j, "time_s", t_greedy + t_improved + t_graph);
        cli_json_end(&j);
    } else {
        printf("%s: %lu paths, %lu fragments (z_offs %g mm, theta %g deg)\n", pos[0], (unsigned long)si.paths_in,
               (unsigned long)si.fragments, z_offs, theta);
        if (graph_done)
            printf("below graph: %lu edges (%.3f s)\n", (unsigned long)edges, t_graph);
        else if (max_edges == 0)
            printf("below graph: not listed (--max-edges 0)\n");
        else
            printf("below graph: more than %ld edges, not listed (ordering does not need it)\n", max_edges);
        if (do_g)
            printf("subdivisions, plain greedy: %lu (%.3f s)\n", (unsigned long)sg.subdivisions, t_greedy);
        if (do_i)
            printf("subdivisions, improved: %lu (%.3f s; %lu fragments continued, %lu merges)\n",
                   (unsigned long)si.subdivisions, t_improved, (unsigned long)si.extended, (unsigned long)si.merges);
        if (output)
            printf("wrote %lu paths to %s\n", (unsigned long)(greedy ? sg : si).pieces, output);
    }
    rc = CLI_OK;
    goto cleanup;
fail:
    cli_progress_end(&bar);
    rc = cli_fail_err("order", &err);
cleanup:
    amp_pathset_free(&ps);
    amp_pathset_free(&out_g);
    amp_pathset_free(&out_i);
    return rc;
}
