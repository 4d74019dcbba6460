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

int cmd_euler(int argc, char **argv)
{
    double layer = 0, first = 0, cell = 0, offset = 0, z = 0, t0 = cli_now();
    long index = -1;
    int json = 0, single = 0, comb = 0, npos = 0, rc;
    const char *pos[1], *out = NULL, *grid = "square";
    amp_mesh m;
    amp_slices sl;
    amp_cx2 k, kh, k1;
    amp_euler_stats est;
    amp_euler_repair_stats ers;
    amp_cx2_report rk, rh;
    amp_euler_opts eo;
    amp_grid_kind kind;
    amp_error err;
    amp_vec2 *pts = NULL, *hull = NULL;
    size_t i, npts = 0, nh = 0, flipped;
    cli_opt opts[] = {{"layer", CLI_DOUBLE, &layer, 0},        {"first-layer", CLI_DOUBLE, &first, 0},
                      {"cell", CLI_DOUBLE, &cell, 0},          {"grid", CLI_STR, &grid, 0},
                      {"offset", CLI_DOUBLE, &offset, 0},      {"single", CLI_FLAG, &single, 0},
                      {"combinatorial", CLI_FLAG, &comb, 0},   {"layer-index", CLI_LONG, &index, 0},
                      {"z", CLI_DOUBLE, &z, 0},                {"output", CLI_STR, &out, 0},
                      {"json", CLI_FLAG, &json, 0},            {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("euler", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (!opts[0].seen || !opts[2].seen)
        return cli_fail("euler", CLI_USAGE, "--layer H and --cell S are required");
    if (!(cell > 0) || !isfinite(cell))
        return cli_fail("euler", CLI_USAGE, "--cell must be positive");
    if (strcmp(grid, "square") == 0)
        kind = AMP_GRID_SQUARE;
    else if (strcmp(grid, "tri") == 0)
        kind = AMP_GRID_TRI;
    else if (strcmp(grid, "hex") == 0)
        kind = AMP_GRID_HEX;
    else
        return cli_fail("euler", CLI_USAGE, "--grid must be square, tri or hex, not '%s'", grid);
    if (opts[4].seen && (!(offset > 0) || !isfinite(offset)))
        return cli_fail("euler", CLI_USAGE, "--offset must be positive");
    if (out && strlen(out) < 4)
        return cli_fail("euler", CLI_USAGE, "-o needs an .svg file name");
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    amp_cx2_init(&k, NULL);
    amp_cx2_init(&kh, NULL);
    amp_cx2_init(&k1, NULL);
    memset(&est, 0, sizeof est);
    memset(&ers, 0, sizeof ers);
    amp_error_clear(&err);
    rc = slicetool_load("euler", pos[0], layer, first, &m, &sl, &flipped);
    if (rc != CLI_OK)
        goto done;
    /* step 2: convex hull of the union of all layers' projections */
    for (i = 0; i < sl.nlayers; i++)
        npts += sl.layers[i].polys.npts;
    if (npts < 3) {
        rc = cli_fail("euler", CLI_USAGE, "the mesh gives no polygon");
        goto done;
    }
    pts = amp_alloc(NULL, npts * sizeof *pts);
    hull = amp_alloc(NULL, npts * sizeof *hull);
    if (!pts || !hull) {
        rc = cli_fail("euler", CLI_USAGE, "out of memory");
        goto done;
    }
    for (i = 0, npts = 0; i < sl.nlayers; i++) {
        if (sl.layers[i].polys.npts)
            memcpy(pts + npts, sl.layers[i].polys.pts, sl.layers[i].polys.npts * sizeof *pts);
        npts += sl.layers[i].polys.npts;
    }
    eo.offset = opts[4].seen ? offset : cell / 5;
    eo.combinatorial = comb;
    /* steps 3-4: K, then K̂ */
    if (amp_convex_hull(pts, npts, NULL, hull, &nh, &err) != AMP_OK || amp_cx2_grid(&k, hull, nh, cell, kind, &err) != AMP_OK ||
        (single ? amp_euler_transform(&k, &eo, &k1, &est, &err) : amp_euler_generalized(&k, &eo, &kh, &err)) != AMP_OK) {
        rc = cli_fail_err("euler", &err);
        goto done;
    }
    /* one pass: collapsed Class 2 cells get Lemma 3.3's local repair */
    if (single && amp_euler_repair(&k1, &kh, &ers, &err) != AMP_OK) {
        rc = cli_fail_err("euler", &err);
        goto done;
    }
    amp_cx2_check(&k, &rk, NULL);
    if (amp_cx2_check(&kh, &rh, &err) != AMP_OK) {
        rc = cli_fail("euler", CLI_FAILED, "%s", err.msg);
        goto done;
    }
    if (out) {
        long li = slicetool_pick("euler", &sl, index, opts[8].seen, z);
        svg_doc s;
        char line[160];
        double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
        if (li < 0) {
            rc = CLI_USAGE;
            goto done;
        }
        for (i = 0; i < k.nv; i++) {
            x0 = fmin(x0, k.v[i].x);
            y0 = fmin(y0, k.v[i].y);
            x1 = fmax(x1, k.v[i].x);
            y1 = fmax(y1, k.v[i].y);
        }
        if (svg_open(&s, out, x0, y0, x1, y1) != 0) {
            rc = cli_fail_err("euler", &s.err);
            goto done;
        }
        svg_polyset(&s, &sl.layers[li].polys, "#eadcf7", "#5b2a86", 2.0);
        svg_cx2(&s, &k, "#999999", 0.8);
        svg_cx2(&s, &kh, "#1e8449", 0.5);
        snprintf(line, sizeof line, "K: %s grid, cell %.4g mm, %lu cells; K-hat (%s): %lu cells, %lu odd vertices",
                 grid, cell, (unsigned long)rk.faces, single ? "single" : "generalized", (unsigned long)rh.faces,
                 (unsigned long)rh.odd_vertices);
        svg_text(&s, 0, line);
        snprintf(line, sizeof line, "layer %ld at z = %.4g mm", li, sl.layers[li].z_cut);
        svg_text(&s, 1, line);
        if (svg_close(&s) != 0) {
            rc = cli_fail_err("euler", &s.err);
            goto done;
        }
    }
    if (json) {
        cli_json j;
        cli_json_begin(&j, stdout);
        cli_json_int(&j, "layers", (long long)sl.nlayers);
        cli_json_int(&j, "hull_vertices", (long long)nh);
        cli_json_str(&j, "grid", grid);
        cli_json_num(&j, "cell", cell);
        cli_json_num(&j, "offset", eo.offset);
        cli_json_str(&j, "transform", single ? "single" : "generalized");
        if (single) {
            cli_json_int(&j, "collapsed_class2", (long long)est.collapsed_class2);
            cli_json_int(&j, "repaired_cells", (long long)ers.cells);
        }
        report(&j, "K", &rk);
        report(&j, "K_hat", &rh);
        cli_json_bool(&j, "euler", rh.odd_vertices == 0);
        cli_json_num(&j, "time_s", cli_now() - t0);
        cli_json_end(&j);
    } else
        printf("K: %lu cells, %lu edges, %lu vertices; K-hat: %lu cells, %lu edges, %lu vertices, %lu odd\n",
               (unsigned long)rk.faces, (unsigned long)rk.edges, (unsigned long)rk.vertices, (unsigned long)rh.faces,
               (unsigned long)rh.edges, (unsigned long)rh.vertices, (unsigned long)rh.odd_vertices);
    if (!single && rh.odd_vertices)
        rc = CLI_FAILED;
done:
    amp_free(NULL, pts);
    amp_free(NULL, hull);
    amp_cx2_free(&k);
    amp_cx2_free(&kh);
    amp_cx2_free(&k1);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
    return rc;
}
