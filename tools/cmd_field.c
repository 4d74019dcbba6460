/* ampath field MESH.stl --field NAME --spacing S — [P1 §4.2]: direction-field curves clipped to a mesh. */
#include <stdlib.h>
#include <string.h>

#include "checkers.h"
#include "slicetool.h"

const char cmd_field_usage[] =
    "cover a mesh with the curves of a direction field, clipped to the mesh (paper 4.2)\n"
    "usage: ampath field MESH.stl --field NAME --spacing S [options] [-o PATHS.amp] [--json]\n"
    "  --field F         built-in field: helix-square (12 mm square swept along the built-in helix; contains the\n"
    "                    helix model), box (lines parallel to x over the mesh's bounding box), sweep (a\n"
    "                    square of side --side swept along the spine --along, paper Fig. 6); or a\n"
    "                    trivariate: a .spl file (its first trivariate) or a built-in trivariate name\n"
    "                    (helix, torus-quarter, vase); required\n"
    "  --along FILE      sweep: the spine, the first path of a .amp file (2..256 points)\n"
    "  --side W          sweep: side of the square cross-section, mm (default 6)\n"
    "  --dir D           for a trivariate field: the direction of the curves, u, v or w; default auto:\n"
    "                    the one whose curves are the most level (the ordering cuts climbing curves)\n"
    "  --spacing S       distance between neighbouring curves, mm (default 1)\n"
    "  --pattern P       grid (square lattice, covering radius S*sqrt(2)/2) or hex (honeycomb, S/sqrt(3));\n"
    "                    default grid\n"
    "  --step D          sampling step along each curve, mm (default min(0.5, S/2))\n"
    "  --min-len L       drop clipped pieces shorter than L mm (default S/2)\n"
    "  --radius R        deposition radius written to the paths, mm (default: the covering radius)\n"
    "  --within R.stl    cover only the part of the mesh inside the closed region mesh R (several fields in\n"
    "                    one model: one run per field); --without R.stl: only the part outside R; no gap is\n"
    "                    measured then: merge the parts' paths and run 'ampath check --mesh MESH.stl'\n"
    "  --shells N        surface layer: N shells of curves following the surface, S/2, 3S/2, ... inside it,\n"
    "                    along the field's direction (default 0)\n"
    "  --samples N       points sampled in the mesh to measure the coverage gap (default 10000; 0 = skip)\n"
    "  -o, --output FILE write the paths (.amp); nothing is written without it\n"
    "  --json            print one JSON object with the figures\n"
    "figures: curves, paths kept, lengths before/after clipping (mm), mesh and deposited volume (mm^3),\n"
    "coverage gap (largest distance from a sampled inside point to the nearest path, mm) over the whole\n"
    "solid and over points at least S from the surface, with the lattice's covering radius as the bound.\n"
    "The covering radius is met in space, for any parametrization: a trivariate field is covered by\n"
    "Algorithm 1 with eps = the covering radius (paper 4.2 step 1, route algorithm1); other fields on the\n"
    "grid pattern by an adaptive lattice that inserts curves where neighbours drift apart and next to the\n"
    "surface (route adaptive; bound_mm is the sampled bound it meets), then adds the field's curve through\n"
    "every gap a sampled measure of the result finds (gap_curves; features finer than the cells' samples);\n"
    "hex is the plain lattice (uniform), with the same curves through the measured gaps.\n"
    "exit status: 0 ok, 1 the field cannot meet the spacing (its cells' bound fails and the curves through the\n"
    "measured gaps do not close them) or the measured gap exceeds the covering radius\n"
    "(paths still written), 2 bad usage or input\n";

/* The figures of one run (JSON or human lines). */
typedef struct report {
    const char *field, *pattern;
    int dir; /* of a trivariate field's curves (0 u, 1 v, 2 w), -1 for the others */
    double spacing, mesh_volume, deposited, gap_all, gap_in, mean, t_cover, t_gap;
    long samples, shells;
    const amp_field_stats *st;
} report;

static void print_report(const report *r, int json)
{
    if (json) {
        cli_json j;
        cli_json_begin(&j, stdout);
        cli_json_str(&j, "field", r->field);
        cli_json_str(&j, "pattern", r->pattern);
        if (r->dir >= 0) {
            char d[2] = {0, 0};
            d[0] = "uvw"[r->dir];
            cli_json_str(&j, "dir", d);
        }
        cli_json_num(&j, "spacing_mm", r->spacing);
        cli_json_int(&j, "curves", (long long)r->st->curves);
        cli_json_int(&j, "paths", (long long)r->st->pieces);
        cli_json_arr(&j, "grid");
        cli_json_int(&j, NULL, (long long)r->st->grid_a);
        cli_json_int(&j, NULL, (long long)r->st->grid_b);
        cli_json_close(&j);
        cli_json_num(&j, "length_before_mm", r->st->length_before);
        cli_json_num(&j, "length_after_mm", r->st->length_after);
        cli_json_num(&j, "radius_mm", r->st->radius);
        cli_json_num(&j, "mesh_volume_mm3", r->mesh_volume);
        cli_json_num(&j, "deposited_volume_mm3", r->deposited);
        cli_json_int(&j, "gap_samples", r->samples);
        if (r->gap_all >= 0) {
            cli_json_num(&j, "coverage_gap_mm", r->gap_all);
            cli_json_num(&j, "coverage_gap_mean_mm", r->mean);
        }
        if (r->gap_in >= 0)
            cli_json_num(&j, "coverage_gap_interior_mm", r->gap_in);
        cli_json_num(&j, "covering_radius_mm", r->st->target);
        cli_json_str(&j, "route", r->st->route == AMP_FIELD_ROUTE_ALGORITHM1 ? "algorithm1"
                                  : r->st->route == AMP_FIELD_ROUTE_ADAPTIVE ? "adaptive" : "uniform");
        cli_json_num(&j, "bound_mm", r->st->bound);
        if (r->st->bound_met >= 0)
            cli_json_bool(&j, "bound_met", r->st->bound_met);
        cli_json_int(&j, "inserted_curves", (long long)r->st->inserted);
        if (r->st->route != AMP_FIELD_ROUTE_ALGORITHM1) {
            cli_json_int(&j, "gap_curves", (long long)r->st->gap_curves);
            cli_json_int(&j, "gap_samples_left", (long long)r->st->gap_left);
        }
        cli_json_int(&j, "shells", r->shells);
        cli_json_int(&j, "shell_paths", (long long)r->st->shell_paths);
        cli_json_num(&j, "shell_length_mm", r->st->shell_length);
        cli_json_num(&j, "cover_s", r->t_cover);
        cli_json_num(&j, "gap_s", r->t_gap);
        cli_json_end(&j);
    } else {
        printf("%s, %s pattern, S = %g mm: %lu curves (%lu x %lu), %lu paths kept, %.1f of %.1f mm inside\n",
               r->field, r->pattern, r->spacing, (unsigned long)r->st->curves, (unsigned long)r->st->grid_a,
               (unsigned long)r->st->grid_b, (unsigned long)r->st->pieces, r->st->length_after, r->st->length_before);
        printf("radius %.3f mm, mesh volume %.1f mm^3, deposited %.1f mm^3\n", r->st->radius, r->mesh_volume,
               r->deposited);
        if (r->gap_all >= 0)
            printf("coverage gap %.3f mm (mean %.3f), %s%.3f mm at least S inside; %ld samples\n", r->gap_all,
                   r->mean, r->gap_in >= 0 ? "" : "n/a ", r->gap_in >= 0 ? r->gap_in : 0.0, r->samples);
        if (r->st->bound_met >= 0)
            printf("%s covering: bound %.3f mm against the covering radius %.3f mm (%lu curves inserted, %lu through "
                   "measured gaps)%s\n",
                   r->st->route == AMP_FIELD_ROUTE_ALGORITHM1 ? "Algorithm 1" : "adaptive", r->st->bound, r->st->target,
                   (unsigned long)r->st->inserted, (unsigned long)r->st->gap_curves,
                   r->st->bound_met ? "" : ": the cells cannot meet the spacing");
        else if (r->st->route == AMP_FIELD_ROUTE_UNIFORM)
            printf("plain lattice: %lu curves through measured gaps, %lu samples of the last round still farther than "
                   "the covering radius\n", (unsigned long)r->st->gap_curves, (unsigned long)r->st->gap_left);
    }
}


/* The sweep field of --along SPINE.amp (its first path) and --side W; *sw is malloc'ed and must outlive f. */
static int load_sweep(const char *along, double side, amp_field *f, amp_sweep **sw)
{
    amp_pathset spine;
    amp_vec3 pts[AMP_SWEEP_MAX];
    amp_error err;
    size_t i, n;
    amp_error_clear(&err);
    amp_pathset_init(&spine, NULL);
    if (cli_load_paths("field", along, &spine) != CLI_OK)
        return CLI_USAGE;
    n = spine.npaths ? spine.paths[0].n : 0;
    for (i = 0; i < n && i < AMP_SWEEP_MAX; i++)
        pts[i] = amp_pathset_path_verts(&spine, 0)[i].p;
    amp_pathset_free(&spine);
    *sw = malloc(sizeof **sw);
    if (!*sw)
        return cli_fail("field", CLI_USAGE, "out of memory");
    if (amp_field_sweep(f, *sw, pts, n, side, &err) != AMP_OK) {
        free(*sw);
        *sw = NULL;
        return cli_fail("field", CLI_USAGE, "%s: %s", along, err.msg);
    }
    return CLI_OK;
}

/* A mesh and its BVH, or nothing when @p path is NULL. A mesh that is not closed is used all the same (the
 * inside tests take the generalized winding number, which a hole changes only near it), with a warning, as
 * `slice` gives one. */
static amp_status load_mesh(const char *path, amp_mesh *m, amp_bvh **b, amp_error *err)
{
    amp_mesh_edge_report er;
    amp_status st;
    if (!path)
        return AMP_OK;
    if ((st = amp_mesh_read_stl_file(m, path, err)) != AMP_OK || (st = slicetool_outward(m, NULL, err)) != AMP_OK)
        return st;
    if (amp_mesh_edges(m, &er, NULL) == AMP_OK && !er.closed)
        fprintf(stderr,
                "ampath field: warning: %s is not closed (%lu boundary, %lu non-manifold edges): inside is where "
                "its surface winds around a point at least half a turn (generalized winding number)\n",
                path, (unsigned long)er.boundary, (unsigned long)er.nonmanifold);
    return amp_bvh_build(b, m, err);
}

/* Coverage gap over the whole solid and over points at least S inside (a thinner solid has none: -1). */
static int measure_gap(const amp_pathset *ps, const amp_bvh *b, long samples, double spacing, double *gap_all,
                       double *gap_in, double *mean)
{
    amp_error err;
    amp_coverage g;
    amp_coverage_domain dom = {NULL, NULL, 0.0};
    dom.mesh = b;
    amp_error_clear(&err);
    if (amp_check_coverage(ps, &dom, (size_t)samples, 1, &g, &err) != AMP_OK)
        return cli_fail_err("field", &err);
    *gap_all = g.gap;
    *mean = g.mean;
    dom.margin = spacing;
    *gap_in = amp_check_coverage(ps, &dom, (size_t)samples, 2, &g, &err) == AMP_OK ? g.gap : -1;
    return CLI_OK;
}

/* Exit 1 when the field cannot meet the spacing or the measured gap exceeds the covering radius. */
static int judge(const amp_field_stats *st, double spacing, double gap_all, size_t npaths)
{
    if (npaths == 0) {
        /* an empty covering covers nothing: a part smaller than the spacing, or a field beside the part */
        fprintf(stderr, "ampath field: no curve piece long enough (--min-len, default S/2) lies inside the part "
                        "(smaller than the spacing %g mm, or the field misses it): nothing to print\n", spacing);
        return CLI_FAILED;
    }
    if (st->bound_met == 0) {
        /* the cells' sampled bound fails, but the curves through the measured gaps closed them: both the
         * library's measure and ours (other samples) find every sample within the covering radius */
        if (st->route == AMP_FIELD_ROUTE_ADAPTIVE && st->gap_left == 0 && gap_all >= 0 &&
            gap_all <= st->target * (1 + 1e-6)) {
            fprintf(stderr, "ampath field: warning: the lattice's cell bound is %.3f mm > %.3f mm somewhere; %lu "
                            "curves through the measured gaps bring the measured gap to %.3f mm\n",
                    st->bound, st->target, (unsigned long)st->gap_curves, gap_all);
            return CLI_OK;
        }
        fprintf(stderr, "ampath field: the field cannot meet spacing %g mm: covering bound %.3f mm > %.3f mm\n",
                spacing, st->bound, st->target);
        if (st->gap_left > 0)
            /* the curve through such a gap was clipped to a piece shorter than --min-len (a sliver of the part
             * thinner than the spacing: a cube less a sphere, OpenSCAD's example004) */
            fprintf(stderr, "ampath field: %lu sampled points are still farther than %.3f mm from every path, in "
                            "features too thin for a piece of --min-len (default S/2 = %g mm): a smaller --min-len "
                            "(e.g. %g) covers them\n",
                    (unsigned long)st->gap_left, st->target, 0.5 * spacing, 0.1 * spacing);
        return CLI_FAILED;
    }
    if (gap_all > st->target * (1 + 1e-6)) {
        /* e.g. a mesh reaching outside the field's volume, or the plain honeycomb next to the surface */
        fprintf(stderr, "ampath field: measured coverage gap %.3f mm exceeds the covering radius %.3f mm\n", gap_all,
                st->target);
        return CLI_FAILED;
    }
    return CLI_OK;
}

/* The command line, validated. */
typedef struct field_args {
    const char *mesh, *field, *pattern, *out, *dir, *along, *within, *without;
    double side, spacing, step, min_len, radius;
    long samples, shells;
    int json, builtin, sweep; /* builtin: helix-square or box; sweep: --field sweep; neither: a trivariate */
} field_args;

/* The command line into @p a; every reason to refuse it is printed here (CLI_USAGE). */
static int field_parse(int argc, char **argv, field_args *a)
{
    const char *pos[1];
    int npos = 0, rc;
    cli_opt opts[] = {{"field", CLI_STR, &a->field, 0},         {"spacing", CLI_DOUBLE, &a->spacing, 0},
                      {"pattern", CLI_STR, &a->pattern, 0},     {"step", CLI_DOUBLE, &a->step, 0},
                      {"min-len", CLI_DOUBLE, &a->min_len, 0},  {"radius", CLI_DOUBLE, &a->radius, 0},
                      {"samples", CLI_LONG, &a->samples, 0},    {"output", CLI_STR, &a->out, 0},
                      {"json", CLI_FLAG, &a->json, 0},          {"dir", CLI_STR, &a->dir, 0},
                      {"along", CLI_STR, &a->along, 0},         {"side", CLI_DOUBLE, &a->side, 0},
                      {"shells", CLI_LONG, &a->shells, 0},      {"within", CLI_STR, &a->within, 0},
                      {"without", CLI_STR, &a->without, 0},     {NULL, CLI_FLAG, NULL, 0}};
    memset(a, 0, sizeof *a);
    a->pattern = "grid";
    a->dir = "auto";
    a->side = 6.0;
    a->spacing = 1.0;
    a->min_len = -1;
    a->samples = 10000;
    rc = cli_parse("field", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    a->mesh = pos[0];
    if (!a->field)
        return cli_fail("field", CLI_USAGE, "--field NAME is required (helix-square, box, sweep, or a trivariate)");
    if (strcmp(a->pattern, "grid") != 0 && strcmp(a->pattern, "hex") != 0)
        return cli_fail("field", CLI_USAGE, "--pattern must be grid or hex, not '%s'", a->pattern);
    if (a->shells < 0 || a->shells > 100)
        return cli_fail("field", CLI_USAGE, "--shells must be in 0..100");
    if (a->samples < 0)
        return cli_fail("field", CLI_USAGE, "--samples must be >= 0");
    if (strcmp(a->dir, "auto") != 0 && strcmp(a->dir, "u") != 0 && strcmp(a->dir, "v") != 0 &&
        strcmp(a->dir, "w") != 0)
        return cli_fail("field", CLI_USAGE, "--dir must be auto, u, v or w, not '%s'", a->dir);
    a->builtin = strcmp(a->field, "helix-square") == 0 || strcmp(a->field, "box") == 0;
    a->sweep = strcmp(a->field, "sweep") == 0;
    if (a->sweep != (a->along != NULL))
        return cli_fail("field", CLI_USAGE, "--along SPINE.amp goes with --field sweep (and is required by it)");
    return CLI_OK;
}

/* The covering of @p f over the mesh @p b into @p ps, timed (*seconds), with its progress bar; @p rb are the
 * --within and --without regions (NULL: none). */
static int field_cover(const field_args *a, const amp_field *f, const amp_bvh *b, amp_bvh *const rb[2],
                       amp_pathset *ps, amp_field_stats *st, double *seconds)
{
    amp_field_opts o;
    cli_progress bar;
    amp_error err;
    double t0;
    int rc;
    amp_error_clear(&err);
    amp_field_opts_default(&o);
    o.spacing = a->spacing;
    o.pattern = strcmp(a->pattern, "hex") == 0 ? AMP_PATTERN_HEX : AMP_PATTERN_GRID;
    o.step = a->step;
    o.min_len = a->min_len;
    o.radius = a->radius;
    o.shells = (int)a->shells;
    o.within = rb[0];
    o.without = (const amp_bvh *const *)&rb[1];
    o.nwithout = rb[1] != NULL;
    t0 = cli_now();
    cli_progress_begin(&bar, "field");
    o.progress = cli_progress_fn;
    o.progress_user = &bar;
    rc = amp_field_cover(f, b, &o, ps, st, &err) == AMP_OK ? CLI_OK : cli_fail_err("field", &err);
    cli_progress_end(&bar);
    *seconds = cli_now() - t0;
    return rc;
}

int cmd_field(int argc, char **argv)
{
    field_args a;
    amp_mesh m, rm[2];
    amp_bvh *b = NULL, *rb[2] = {NULL, NULL};
    double t0, t_cover, t_gap = 0, gap_all = -1, gap_in = -1, mean = -1;
    amp_field f;
    amp_spline spl;
    amp_sweep *sw = NULL;
    amp_field_stats st;
    amp_pathset ps;
    amp_error err;
    int rc = field_parse(argc, argv, &a);
    if (rc != CLI_OK)
        return rc;
    amp_spline_init(&spl);
    amp_error_clear(&err);
    if (a.sweep) {
        if ((rc = load_sweep(a.along, a.side, &f, &sw)) != CLI_OK)
            return rc;
    } else if (!a.builtin && cli_load_trivariate("field", a.field, &spl) != CLI_OK)
        return CLI_USAGE;
    amp_mesh_init(&m, NULL);
    amp_mesh_init(&rm[0], NULL);
    amp_mesh_init(&rm[1], NULL);
    amp_pathset_init(&ps, NULL);
    if (load_mesh(a.within, &rm[0], &rb[0], &err) != AMP_OK || load_mesh(a.without, &rm[1], &rb[1], &err) != AMP_OK ||
        load_mesh(a.mesh, &m, &b, &err) != AMP_OK ||
        (a.sweep     ? AMP_OK
         : a.builtin ? amp_field_builtin(&f, a.field, amp_mesh_bbox(&m), &err)
                     : amp_field_from_spline(&f, &spl, a.dir[0] == 'a' ? AMP_FIELD_AUTO : a.dir[0] - 'u', &err)) !=
            AMP_OK) {
        rc = cli_fail_err("field", &err);
        goto done;
    }
    rc = field_cover(&a, &f, b, rb, &ps, &st, &t_cover);
    if (a.within || a.without)
        a.samples = 0; /* the gap of one part is not the model's: check the merged paths with 'ampath check --mesh' */
    if (rc == CLI_OK && a.samples > 0 && ps.npaths > 0) {
        t0 = cli_now();
        rc = measure_gap(&ps, b, a.samples, a.spacing, &gap_all, &gap_in, &mean);
        t_gap = cli_now() - t0;
    }
    if (rc == CLI_OK && a.out) {
        /* the covering radius as `cover` records its eps: `check --mesh` holds the paths to it after mdr */
        char note[160];
        snprintf(note, sizeof note,
                 "ampath field: direction-field curves clipped to the mesh, eps %.10g (covering radius)", st.target);
        rc = cli_save_paths("field", a.out, &ps, note);
    }
    if (rc == CLI_OK) {
        report r;
        memset(&r, 0, sizeof r);
        r.field = a.field;
        r.pattern = a.pattern;
        r.dir = a.builtin || a.sweep ? -1 : f.dir;
        r.st = &st;
        r.spacing = a.spacing, r.mesh_volume = amp_mesh_volume(&m), r.deposited = amp_pathset_volume(&ps, -1);
        r.samples = a.samples, r.shells = a.shells, r.gap_all = gap_all, r.gap_in = gap_in, r.mean = mean;
        r.t_cover = t_cover, r.t_gap = t_gap;
        print_report(&r, a.json);
        rc = judge(&st, a.spacing, gap_all, ps.npaths);
    }
done:
    amp_bvh_free(b);
    amp_bvh_free(rb[0]);
    amp_bvh_free(rb[1]);
    amp_mesh_free(&rm[0]);
    amp_mesh_free(&rm[1]);
    amp_pathset_free(&ps);
    amp_mesh_free(&m);
    amp_spline_free(&spl);
    free(sw);
    return rc;
}
