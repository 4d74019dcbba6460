/* ampath mdr — material deposition radius per vertex (paper 5.2, Def. 5.4). */
#include <string.h>

#include "checkers.h"

const char cmd_mdr_usage[] =
    "set the material deposition radius (MDR) along the paths (paper 5.2): tubes grow until they touch\n"
    "usage: ampath mdr PATHS.amp [--nominal R] [--min R] [--max R] [--fragment L]\n"
    "                  [--trivariate F | --mesh F | --volume V] [--samples N] [--json] -o OUT.amp\n"
    "  --nominal R   radius of tubes with no neighbour, mm (default 0.5)\n"
    "  --min R       smallest radius, mm (default nominal / 2); tubes raised to it may overlap\n"
    "  --max R       largest radius, mm (default 1.5 * nominal)\n"
    "  --fragment L  length of the pieces that carry one radius each, mm (default: nominal)\n"
    "  --trivariate F, --mesh F, --volume V\n"
    "                the model the paths cover (.spl or built-in name, closed .stl, or its volume in mm^3):\n"
    "                over-coverage = deposited / model volume, the figure 'ampath check' reports too\n"
    "                (docs/order.md); without a model it is not reported (null), and 'overlap' = deposited /\n"
    "                volume of the union of the tubes (Monte Carlo) says how much is deposited twice\n"
    "  --samples N   Monte-Carlo samples of the union estimate (default 200000)\n"
    "  --json        one JSON object: fragments, radii, deposited volume, over-coverage, time\n"
    "  -o FILE       write the paths with cut points inserted and r set per vertex (.amp)\n"
    "Over-coverage = sum(pi r^2 L) of the object paths / model volume: 1 = as much plastic as the part holds.\n";


/* Volume of the model: a trivariate (quadrature) or a closed mesh (divergence theorem). */
static int model_volume(const char *tri, const char *mesh, double *volume)
{
    amp_error err;
    amp_error_clear(&err);
    if (tri) {
        amp_spline v;
        int rc = cli_load_trivariate("mdr", tri, &v);
        if (rc != CLI_OK)
            return rc;
        *volume = amp_trivariate_volume(&v);
        amp_spline_free(&v);
    } else {
        amp_mesh m;
        amp_mesh_init(&m, NULL);
        if (amp_mesh_read_stl_file(&m, mesh, &err) != AMP_OK) {
            amp_mesh_free(&m);
            return cli_fail_err("mdr", &err);
        }
        *volume = amp_mesh_volume(&m);
        amp_mesh_free(&m);
    }
    if (!(*volume > 0.0))
        return cli_fail("mdr", CLI_USAGE, "the model has no positive volume (%g mm^3)", *volume);
    return CLI_OK;
}

/* The command line, validated; o holds the radii and the fragment length. */
typedef struct mdr_args {
    const char *input, *output, *tri, *mesh;
    double volume; /* --volume, or -1 */
    long samples;
    int json, have_volume;
    amp_mdr_opts o;
} mdr_args;

/* What the report shows of one run. */
typedef struct mdr_figures {
    amp_mdr_stats st;
    double volume, union_vol, t_mdr, t_vol; /* volume, union_vol: -1 when not known */
} mdr_figures;

/* The command line into @p a; every reason to refuse it is printed here (CLI_USAGE). */
static int mdr_parse(int argc, char **argv, mdr_args *a)
{
    const char *pos[1];
    double nominal = 0.5, rmin = -1, rmax = -1, frag = -1;
    int npos = 0, rc;
    cli_opt opts[] = {{"nominal", CLI_DOUBLE, &nominal, 0},   {"min", CLI_DOUBLE, &rmin, 0},
                      {"max", CLI_DOUBLE, &rmax, 0},           {"fragment", CLI_DOUBLE, &frag, 0},
                      {"volume", CLI_DOUBLE, &a->volume, 0},   {"samples", CLI_LONG, &a->samples, 0},
                      {"json", CLI_FLAG, &a->json, 0},         {"output", CLI_STR, &a->output, 0},
                      {"trivariate", CLI_STR, &a->tri, 0},     {"mesh", CLI_STR, &a->mesh, 0},
                      {NULL, CLI_FLAG, NULL, 0}};
    memset(a, 0, sizeof *a);
    a->volume = -1;
    a->samples = 200000;
    rc = cli_parse("mdr", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    a->input = pos[0];
    a->have_volume = cli_given(opts, "volume");
    if (!(nominal > 0.0))
        return cli_fail("mdr", CLI_USAGE, "--nominal must be positive (got %g)", nominal);
    amp_mdr_opts_default(&a->o, nominal);
    if (cli_given(opts, "min"))
        a->o.r_min = rmin;
    if (cli_given(opts, "max"))
        a->o.r_max = rmax;
    if (cli_given(opts, "fragment"))
        a->o.fragment = frag;
    if (a->have_volume && !(a->volume > 0.0))
        return cli_fail("mdr", CLI_USAGE, "--volume must be positive (got %g)", a->volume);
    if ((a->have_volume != 0) + (a->tri != NULL) + (a->mesh != NULL) > 1)
        return cli_fail("mdr", CLI_USAGE, "give at most one of --trivariate, --mesh, --volume");
    if (a->samples < 1000)
        return cli_fail("mdr", CLI_USAGE, "--samples must be at least 1000");
    return CLI_OK;
}

static void mdr_report(const mdr_args *a, const amp_pathset *out, const mdr_figures *f)
{
    const amp_mdr_stats *st = &f->st;
    cli_json j;
    if (!a->json) {
        printf("%s: %lu fragments, %lu neighbour pairs; radius %.4f .. %.4f mm (%lu at min, %lu at max, %lu "
               "isolated)\n",
               a->input, (unsigned long)st->fragments, (unsigned long)st->pairs, st->r_lo, st->r_hi,
               (unsigned long)st->at_min, (unsigned long)st->at_max, (unsigned long)st->isolated);
        if (f->volume > 0)
            printf("deposited %.3f mm^3, model volume %.3f mm^3: over-coverage %.4f\n", st->deposited, f->volume,
                   amp_over_coverage(out, f->volume));
        else
            printf("deposited %.3f mm^3, union of the tubes %.3f mm^3 (estimated): overlap %.4f (give the model "
                   "for the over-coverage)\n", st->deposited, f->union_vol, st->deposited / f->union_vol);
        return;
    }
    cli_json_begin(&j, stdout);
    cli_json_str(&j, "input", a->input);
    cli_json_num(&j, "nominal", a->o.nominal);
    cli_json_num(&j, "r_min", a->o.r_min);
    cli_json_num(&j, "r_max", a->o.r_max);
    cli_json_num(&j, "fragment", a->o.fragment);
    cli_json_int(&j, "paths", (long long)out->npaths);
    cli_json_int(&j, "fragments", (long long)st->fragments);
    cli_json_int(&j, "neighbour_pairs", (long long)st->pairs);
    cli_json_int(&j, "at_min", (long long)st->at_min);
    cli_json_int(&j, "at_max", (long long)st->at_max);
    cli_json_int(&j, "isolated", (long long)st->isolated);
    cli_json_num(&j, "radius_lo", st->r_lo);
    cli_json_num(&j, "radius_hi", st->r_hi);
    cli_json_num(&j, "deposited_mm3", st->deposited);
    cli_json_num(&j, "volume_mm3", f->volume > 0 ? f->volume : NAN);
    cli_json_num(&j, "over_coverage", amp_over_coverage(out, f->volume));
    cli_json_num(&j, "tubes_union_mm3", f->union_vol > 0 ? f->union_vol : NAN);
    cli_json_num(&j, "overlap", f->union_vol > 0 ? st->deposited / f->union_vol : NAN);
    cli_json_num(&j, "time_mdr_s", f->t_mdr);
    cli_json_num(&j, "time_volume_s", f->t_vol);
    cli_json_end(&j);
}

int cmd_mdr(int argc, char **argv)
{
    cli_progress bar;
    amp_status st_mdr;
    mdr_args a;
    mdr_figures f;
    double t0;
    amp_pathset ps, out;
    amp_error err;
    int rc = mdr_parse(argc, argv, &a);
    if (rc != CLI_OK)
        return rc;
    f.volume = a.volume;
    f.union_vol = -1;
    f.t_vol = 0;
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&out, NULL);
    amp_error_clear(&err);
    if ((rc = cli_load_paths("mdr", a.input, &ps)) != CLI_OK)
        return rc;
    t0 = cli_now();
    cli_progress_begin(&bar, "mdr");
    a.o.progress = cli_progress_fn;
    a.o.progress_user = &bar;
    st_mdr = amp_mdr(&ps, &a.o, &out, &f.st, &err);
    cli_progress_end(&bar);
    if (st_mdr != AMP_OK) {
        rc = cli_fail_err("mdr", &err);
        goto done;
    }
    f.t_mdr = cli_now() - t0;
    t0 = cli_now();
    if ((a.tri || a.mesh) && (rc = model_volume(a.tri, a.mesh, &f.volume)) != CLI_OK)
        goto done;
    if (!a.have_volume && !a.tri && !a.mesh &&
        amp_tubes_union_volume(&out, (size_t)a.samples, &f.union_vol, &err) != AMP_OK) {
        rc = cli_fail_err("mdr", &err);
        goto done;
    }
    f.t_vol = cli_now() - t0;
    if (a.output && (rc = cli_save_derived("mdr", a.output, &out, "ampath mdr", a.input)) != CLI_OK)
        goto done;
    mdr_report(&a, &out, &f);
    rc = CLI_OK;
done:
    amp_pathset_free(&ps);
    amp_pathset_free(&out);
    return rc;
}
