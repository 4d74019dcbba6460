/* ampath euler MESH.stl --layer H --cell S — the complex K of the layers' hull and its Euler
 * transformation K̂ as a picture ([P2 §2.2] steps 1-4, [P2 §1.3], Def. 3.2). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "slicetool.h"
#include "svg.h"

const char cmd_euler_usage[] =
    "mesh the hull of all layers with a 2-complex K and draw K and its Euler transformation\n"
    "usage: ampath euler MESH.stl --layer H --cell S [--grid square|tri|hex] -o OUT.svg [--json]\n"
    "  --layer H          layer height in mm (required), as for 'ampath slice'\n"
    "  --first-layer H0   first layer height in mm (default: H)\n"
    "  --cell S           edge length of the grid cells of K in mm (required)\n"
    "  --grid KIND        square (default), tri or hex lattice covering the convex hull of the\n"
    "                     union of all layers' polygons (paper 2 §2.2 steps 2-3)\n"
    "  --offset D         mitered offset of the transformation in mm (default: S/5)\n"
    "  --single           apply the transformation once (§1.3), plus Lemma 3.3's local repair\n"
    "                     where Class 2 cells collapse; the default is the generalized\n"
    "                     transformation T(T(K)) (Def. 3.2), Euler even at rim cells with\n"
    "                     adjacent boundary edges\n"
    "  --combinatorial    let mitered offsets drop collapsing edges (§3, Lemma 3.1); Class 2\n"
    "                     cells collapsed to edges are repaired (Lemma 3.3)\n"
    "  --layer-index I    layer whose polygons are drawn (default: the middle layer); --z Z picks\n"
    "                     the layer cut nearest to Z mm\n"
    "  -o OUT.svg         the picture: layer polygons (purple), K (grey), K-hat (green)\n"
    "  --json             figures: cells, edges and vertices of K and K-hat, odd vertices,\n"
    "                     collapsed Class 2 cells and repaired Class 3 cells (--single), time\n"
    "Exit status 1 when the generalized transformation leaves a vertex of odd degree.\n";

static void report(cli_json *j, const char *key, const amp_cx2_report *r)
{
    cli_json_obj(j, key);
    cli_json_int(j, "vertices", (long long)r->vertices);
    cli_json_int(j, "edges", (long long)r->edges);
    cli_json_int(j, "faces", (long long)r->faces);
    cli_json_int(j, "euler_characteristic", r->euler_char);
    cli_json_int(j, "odd_vertices", (long long)r->odd_vertices);
    cli_json_int(j, "max_degree", (long long)r->max_degree);
    cli_json_close(j);
}

/* The command line, validated. */
typedef struct euler_args {
    const char *mesh, *out, *grid;
    double layer, first, cell, offset, z;
    long index;
    int json, single, comb, have_offset, have_z;
    amp_grid_kind kind;
} euler_args;

/* K, K̂ and what the report needs of one run. */
typedef struct euler_run {
    amp_slices sl;
    amp_cx2 k, kh, k1;
    amp_euler_stats est;
    amp_euler_repair_stats ers;
    amp_cx2_report rk, rh;
    amp_euler_opts eo;
    size_t nh; /* hull vertices */
} euler_run;

/* The command line into @p a; every reason to refuse it is printed here (CLI_USAGE). */
static int euler_parse(int argc, char **argv, euler_args *a)
{
    const char *pos[1];
    int npos = 0, rc;
    cli_opt opts[] = {{"layer", CLI_DOUBLE, &a->layer, 0},      {"first-layer", CLI_DOUBLE, &a->first, 0},
                      {"cell", CLI_DOUBLE, &a->cell, 0},        {"grid", CLI_STR, &a->grid, 0},
                      {"offset", CLI_DOUBLE, &a->offset, 0},    {"single", CLI_FLAG, &a->single, 0},
                      {"combinatorial", CLI_FLAG, &a->comb, 0}, {"layer-index", CLI_LONG, &a->index, 0},
                      {"z", CLI_DOUBLE, &a->z, 0},              {"output", CLI_STR, &a->out, 0},
                      {"json", CLI_FLAG, &a->json, 0},          {NULL, CLI_FLAG, NULL, 0}};
    memset(a, 0, sizeof *a);
    a->index = -1;
    a->grid = "square";
    rc = cli_parse("euler", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    a->mesh = pos[0];
    a->have_offset = cli_given(opts, "offset");
    a->have_z = cli_given(opts, "z");
    if (!cli_given(opts, "layer") || !cli_given(opts, "cell"))
        return cli_fail("euler", CLI_USAGE, "--layer H and --cell S are required");
    if (!(a->cell > 0) || !isfinite(a->cell))
        return cli_fail("euler", CLI_USAGE, "--cell must be positive");
    if (strcmp(a->grid, "square") == 0)
        a->kind = AMP_GRID_SQUARE;
    else if (strcmp(a->grid, "tri") == 0)
        a->kind = AMP_GRID_TRI;
    else if (strcmp(a->grid, "hex") == 0)
        a->kind = AMP_GRID_HEX;
    else
        return cli_fail("euler", CLI_USAGE, "--grid must be square, tri or hex, not '%s'", a->grid);
    if (a->have_offset && (!(a->offset > 0) || !isfinite(a->offset)))
        return cli_fail("euler", CLI_USAGE, "--offset must be positive");
    if (a->out && strlen(a->out) < 4)
        return cli_fail("euler", CLI_USAGE, "-o needs an .svg file name");
    return CLI_OK;
}

/* Steps 2-4 on the sliced layers r->sl: their convex hull, K over it, then K̂, both checked. */
static int euler_complexes(const euler_args *a, euler_run *r)
{
    const amp_slices *sl = &r->sl;
    amp_vec2 *pts, *hull;
    amp_error err;
    size_t i, npts = 0;
    int rc = CLI_OK;
    amp_error_clear(&err);
    /* step 2: convex hull of the union of all layers' projections */
    for (i = 0; i < sl->nlayers; i++)
        npts += sl->layers[i].polys.npts;
    if (npts < 3)
        return cli_fail("euler", CLI_USAGE, "the mesh gives no polygon");
    pts = amp_alloc(NULL, npts * sizeof *pts);
    hull = amp_alloc(NULL, npts * sizeof *hull);
    if (!pts || !hull) {
        amp_free(NULL, pts);
        amp_free(NULL, hull);
        return cli_fail("euler", CLI_USAGE, "out of memory");
    }
    for (i = 0, npts = 0; i < sl->nlayers; i++) {
        if (sl->layers[i].polys.npts)
            memcpy(pts + npts, sl->layers[i].polys.pts, sl->layers[i].polys.npts * sizeof *pts);
        npts += sl->layers[i].polys.npts;
    }
    r->eo.offset = a->have_offset ? a->offset : a->cell / 5;
    r->eo.combinatorial = a->comb;
    /* steps 3-4: K, then K̂ */
    if (amp_convex_hull(pts, npts, NULL, hull, &r->nh, &err) != AMP_OK ||
        amp_cx2_grid(&r->k, hull, r->nh, a->cell, a->kind, &err) != AMP_OK ||
        (a->single ? amp_euler_transform(&r->k, &r->eo, &r->k1, &r->est, &err)
                   : amp_euler_generalized(&r->k, &r->eo, &r->kh, &err)) != AMP_OK)
        rc = cli_fail_err("euler", &err);
    /* one pass: collapsed Class 2 cells get Lemma 3.3's local repair */
    else if (a->single && amp_euler_repair(&r->k1, &r->kh, &r->ers, &err) != AMP_OK)
        rc = cli_fail_err("euler", &err);
    amp_free(NULL, pts);
    amp_free(NULL, hull);
    if (rc != CLI_OK)
        return rc;
    amp_cx2_check(&r->k, &r->rk, NULL);
    if (amp_cx2_check(&r->kh, &r->rh, &err) != AMP_OK)
        return cli_fail("euler", CLI_FAILED, "%s", err.msg);
    return CLI_OK;
}

/* -o OUT.svg: one layer's polygons under K and K̂, framed by K. */
static int euler_svg(const euler_args *a, const euler_run *r)
{
    long li = slicetool_pick("euler", &r->sl, a->index, a->have_z, a->z);
    svg_doc s;
    char line[160];
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
    size_t i;
    if (li < 0)
        return CLI_USAGE;
    for (i = 0; i < r->k.nv; i++) {
        x0 = fmin(x0, r->k.v[i].x);
        y0 = fmin(y0, r->k.v[i].y);
        x1 = fmax(x1, r->k.v[i].x);
        y1 = fmax(y1, r->k.v[i].y);
    }
    if (svg_open(&s, a->out, x0, y0, x1, y1) != 0)
        return cli_fail_err("euler", &s.err);
    svg_polyset(&s, &r->sl.layers[li].polys, "#eadcf7", "#5b2a86", 2.0);
    svg_cx2(&s, &r->k, "#999999", 0.8);
    svg_cx2(&s, &r->kh, "#1e8449", 0.5);
    snprintf(line, sizeof line, "K: %s grid, cell %.4g mm, %lu cells; K-hat (%s): %lu cells, %lu odd vertices",
             a->grid, a->cell, (unsigned long)r->rk.faces, a->single ? "single" : "generalized",
             (unsigned long)r->rh.faces, (unsigned long)r->rh.odd_vertices);
    svg_text(&s, 0, line);
    snprintf(line, sizeof line, "layer %ld at z = %.4g mm", li, r->sl.layers[li].z_cut);
    svg_text(&s, 1, line);
    if (svg_close(&s) != 0)
        return cli_fail_err("euler", &s.err);
    return CLI_OK;
}

static void euler_report(const euler_args *a, const euler_run *r, double t0)
{
    cli_json j;
    if (!a->json) {
        printf("K: %lu cells, %lu edges, %lu vertices; K-hat: %lu cells, %lu edges, %lu vertices, %lu odd\n",
               (unsigned long)r->rk.faces, (unsigned long)r->rk.edges, (unsigned long)r->rk.vertices,
               (unsigned long)r->rh.faces, (unsigned long)r->rh.edges, (unsigned long)r->rh.vertices,
               (unsigned long)r->rh.odd_vertices);
        return;
    }
    cli_json_begin(&j, stdout);
    cli_json_int(&j, "layers", (long long)r->sl.nlayers);
    cli_json_int(&j, "hull_vertices", (long long)r->nh);
    cli_json_str(&j, "grid", a->grid);
    cli_json_num(&j, "cell", a->cell);
    cli_json_num(&j, "offset", r->eo.offset);
    cli_json_str(&j, "transform", a->single ? "single" : "generalized");
    if (a->single) {
        cli_json_int(&j, "collapsed_class2", (long long)r->est.collapsed_class2);
        cli_json_int(&j, "repaired_cells", (long long)r->ers.cells);
    }
    report(&j, "K", &r->rk);
    report(&j, "K_hat", &r->rh);
    cli_json_bool(&j, "euler", r->rh.odd_vertices == 0);
    cli_json_num(&j, "time_s", cli_now() - t0);
    cli_json_end(&j);
}

int cmd_euler(int argc, char **argv)
{
    double t0 = cli_now();
    euler_args a;
    euler_run r;
    amp_mesh m;
    size_t flipped;
    int rc = euler_parse(argc, argv, &a);
    if (rc != CLI_OK)
        return rc;
    memset(&r, 0, sizeof r);
    amp_mesh_init(&m, NULL);
    amp_slices_init(&r.sl, NULL);
    amp_cx2_init(&r.k, NULL);
    amp_cx2_init(&r.kh, NULL);
    amp_cx2_init(&r.k1, NULL);
    rc = slicetool_load("euler", a.mesh, a.layer, a.first, &m, &r.sl, &flipped);
    if (rc == CLI_OK)
        rc = euler_complexes(&a, &r);
    if (rc == CLI_OK && a.out)
        rc = euler_svg(&a, &r);
    if (rc == CLI_OK) {
        euler_report(&a, &r, t0);
        if (!a.single && r.rh.odd_vertices)
            rc = CLI_FAILED;
    }
    amp_cx2_free(&r.k);
    amp_cx2_free(&r.kh);
    amp_cx2_free(&r.k1);
    amp_slices_free(&r.sl);
    amp_mesh_free(&m);
    return rc;
}
