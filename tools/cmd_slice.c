/* ampath slice MESH.stl --layer H --polygons — planar layers (paper 2 §2.2 step 1, SPEC §4). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "slicetool.h"
#include "svg.h"

const char cmd_slice_usage[] =
    "slice a mesh into layers of polygons with holes (.amp closed paths or an SVG of one layer)\n"
    "usage: ampath slice MESH.stl --layer H [--first-layer H0] [--polygons] [-o OUT.amp|OUT.svg] [--json]\n"
    "  --layer H          layer height in mm (required); layer i is cut at z = (i + 1/2) H above the\n"
    "                     plate (mesh lowest point = 0) and printed at z = (i + 1) H\n"
    "  --first-layer H0   height of the first layer in mm (default: H); layer 0 is cut at H0/2,\n"
    "                     layer i >= 1 at H0 + (i - 1/2) H\n"
    "  --polygons         write each layer's polygons (the default product): one closed path per\n"
    "                     ring (last vertex repeats the first) at the cutting height, outer\n"
    "                     boundaries counter-clockwise, holes clockwise, islands in order\n"
    "  -o FILE            OUT.amp: all layers; OUT.svg: a picture of one layer with its inset\n"
    "  --layer-index I    layer drawn in the SVG (default: the middle layer)\n"
    "  --z Z              draw the layer cut nearest to height Z mm instead\n"
    "  --radius R         deposition radius written on every vertex, and the inset drawn in\n"
    "                     the SVG, in mm (default 0.5)\n"
    "  --json             print the figures as one JSON object (layers, polygons, islands, holes,\n"
    "                     area per layer, open chains of an open mesh, time)\n"
    "A mesh that is not closed is sliced anyway; chains that do not close are dropped and counted\n"
    "(open_chains) with a warning on stderr.\n";

static int ends_with(const char *s, const char *suf)
{
    size_t n = strlen(s), m = strlen(suf);
    return n >= m && strcmp(s + n - m, suf) == 0;
}

static int write_amp(const char *file, const amp_slices *sl, double radius, double layer)
{
    amp_pathset ps;
    amp_error err;
    size_t i, r, k;
    char comment[200];
    int rc;
    amp_pathset_init(&ps, NULL);
    amp_error_clear(&err);
    for (i = 0; i < sl->nlayers; i++) {
        const amp_polyset *P = &sl->layers[i].polys;
        for (r = 0; r < P->nrings; r++) {
            const amp_vec2 *p = amp_polyset_ring(P, r);
            size_t n = P->rings[r].n;
            if (amp_pathset_begin(&ps, AMP_ROLE_OBJECT, &err) != AMP_OK)
                goto fail;
            /* closed path: the last vertex repeats the first (SPEC §4) */
            for (k = 0; k <= n; k++)
                if (amp_pathset_push(&ps, amp_v3(p[k % n].x, p[k % n].y, sl->layers[i].z_cut), radius, &err) !=
                    AMP_OK)
                    goto fail;
        }
    }
    snprintf(comment, sizeof comment,
             "ampath slice --polygons: %lu layers of height %g mm; outer rings CCW, holes CW; z = cutting height",
             (unsigned long)sl->nlayers, layer);
    rc = cli_save_paths("slice", file, &ps, comment);
    amp_pathset_free(&ps);
    return rc;
fail:
    amp_pathset_free(&ps);
    return cli_fail_err("slice", &err);
}

static int write_svg(const char *file, const amp_slices *sl, long li, double radius)
{
    svg_doc s;
    double x0, y0, x1, y1;
    amp_polyset inset;
    amp_error err;
    char line[160];
    const amp_layer *L = &sl->layers[li];
    amp_polyset_init(&inset, NULL);
    amp_error_clear(&err);
    slicetool_bbox(sl, &x0, &y0, &x1, &y1);
    if (amp_polyset_inset(&L->polys, radius, 0, &inset, &err) != AMP_OK)
        return cli_fail_err("slice", &err);
    if (svg_open(&s, file, x0, y0, x1, y1) != 0) {
        amp_polyset_free(&inset);
        return cli_fail("slice", CLI_USAGE, "cannot write '%s'", file);
    }
    svg_polyset(&s, &L->polys, "#d9c8f0", "#5b2a86", 1.5);
    svg_polyset(&s, &inset, "none", "#c0392b", 1.0);
    snprintf(line, sizeof line, "layer %ld: cut z = %.4g mm, %lu islands, %lu rings, area %.4g mm2", li, L->z_cut,
             (unsigned long)L->polys.nislands, (unsigned long)L->polys.nrings, amp_polyset_area(&L->polys));
    svg_text(&s, 0, line);
    snprintf(line, sizeof line, "red: inset by r = %.4g mm (%lu islands)", radius, (unsigned long)inset.nislands);
    svg_text(&s, 1, line);
    amp_polyset_free(&inset);
    if (svg_close(&s) != 0)
        return cli_fail("slice", CLI_USAGE, "writing '%s' failed", file);
    return CLI_OK;
}

int cmd_slice(int argc, char **argv)
{
    double layer = 0, first = 0, radius = 0.5, z = 0, t0 = cli_now();
    long index = -1;
    int json = 0, polygons = 0, npos = 0, rc;
    const char *pos[1], *out = NULL;
    amp_mesh m;
    amp_slices sl;
    size_t i, r, rings = 0, holes = 0, islands = 0, flipped = 0;
    cli_opt opts[] = {{"layer", CLI_DOUBLE, &layer, 0},      {"first-layer", CLI_DOUBLE, &first, 0},
                      {"polygons", CLI_FLAG, &polygons, 0},  {"output", CLI_STR, &out, 0},
                      {"layer-index", CLI_LONG, &index, 0},  {"z", CLI_DOUBLE, &z, 0},
                      {"radius", CLI_DOUBLE, &radius, 0},    {"json", CLI_FLAG, &json, 0},
                      {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("slice", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (!opts[0].seen)
        return cli_fail("slice", CLI_USAGE, "--layer H is required");
    if (!(radius > 0) || !isfinite(radius))
        return cli_fail("slice", CLI_USAGE, "--radius must be positive");
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    rc = slicetool_load("slice", pos[0], layer, first, &m, &sl, &flipped);
    if (rc == CLI_OK && sl.open_chains)
        fprintf(stderr, "ampath slice: warning: mesh is not closed: %lu open section chains dropped\n",
                (unsigned long)sl.open_chains);
    if (rc == CLI_OK && out) {
        if (ends_with(out, ".svg")) {
            long li = slicetool_pick("slice", &sl, index, opts[5].seen, z);
            rc = li < 0 ? CLI_USAGE : write_svg(out, &sl, li, radius);
        } else
            rc = write_amp(out, &sl, radius, layer);
    }
    if (rc != CLI_OK)
        goto done;
    for (i = 0; i < sl.nlayers; i++) {
        rings += sl.layers[i].polys.nrings;
        islands += sl.layers[i].polys.nislands;
        for (r = 0; r < sl.layers[i].polys.nrings; r++)
            holes += sl.layers[i].polys.rings[r].hole != 0;
    }
    if (json) {
        cli_json j;
        cli_json_begin(&j, stdout);
        cli_json_int(&j, "layers", (long long)sl.nlayers);
        cli_json_int(&j, "polygons", (long long)rings);
        cli_json_int(&j, "islands", (long long)islands);
        cli_json_int(&j, "holes", (long long)holes);
        cli_json_int(&j, "open_chains", (long long)sl.open_chains);
        cli_json_int(&j, "nonmanifold", (long long)sl.nonmanifold);
        cli_json_int(&j, "flipped_triangles", (long long)flipped);
        cli_json_int(&j, "triangles", (long long)m.ntris);
        cli_json_num(&j, "layer_height", layer);
        cli_json_num(&j, "first_layer", first > 0 ? first : layer);
        cli_json_num(&j, "time_s", cli_now() - t0);
        cli_json_arr(&j, "per_layer");
        for (i = 0; i < sl.nlayers; i++) {
            size_t nh = 0;
            for (r = 0; r < sl.layers[i].polys.nrings; r++)
                nh += sl.layers[i].polys.rings[r].hole != 0;
            cli_json_obj(&j, NULL);
            cli_json_int(&j, "index", (long long)i);
            cli_json_num(&j, "z_cut", sl.layers[i].z_cut);
            cli_json_num(&j, "z_print", sl.layers[i].z_print);
            cli_json_int(&j, "islands", (long long)sl.layers[i].polys.nislands);
            cli_json_int(&j, "polygons", (long long)sl.layers[i].polys.nrings);
            cli_json_int(&j, "holes", (long long)nh);
            cli_json_num(&j, "area_mm2", amp_polyset_area(&sl.layers[i].polys));
            cli_json_close(&j);
        }
        cli_json_close(&j);
        cli_json_end(&j);
    } else
        printf("%s: %lu layers, %lu polygons (%lu islands, %lu holes)%s%s\n", pos[0], (unsigned long)sl.nlayers,
               (unsigned long)rings, (unsigned long)islands, (unsigned long)holes, out ? " -> " : "", out ? out : "");
done:
    amp_slices_free(&sl);
    amp_mesh_free(&m);
    return rc;
}
