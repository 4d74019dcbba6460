/* ampath slice MESH.stl --layer H --polygons — planar layers ([P2 §2.2] step 1, docs/interfaces.md §4). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "slicetool.h"
#include "svg.h"

const char cmd_slice_usage[] =
    "slice a mesh into layers of polygons with holes (.amp closed paths or an SVG of one layer)\n"
    "usage: ampath slice MESH.stl --layer H [--first-layer H0] [--polygons|--continuous] [-o OUT.amp|OUT.svg]\n"
    "       [--json]\n"
    "  --layer H          layer height in mm (required); layer i is cut at z = (i + 1/2) H above the\n"
    "                     plate (mesh lowest point = 0) and printed at z = (i + 1) H\n"
    "  --first-layer H0   first layer height (default H): layer 0 cut at H0/2, i >= 1 at H0 + (i - 1/2) H\n"
    "  --polygons         each layer's rings as closed paths at the cutting height (the default):\n"
    "                     outer boundaries counter-clockwise, holes clockwise, islands in order\n"
    "  --continuous       paper 2: per island one closed stroke (perimeter loops at r and the Euler\n"
    "                     lattice clipped to the inset by 3r), printed at z = (i + 1) H, every path\n"
    "                     a bead of the layer's height, started where the previous one ended\n"
    "  --radius R         bead half-width in mm (default 0.225: a 0.45 mm bead); also the SVG inset\n"
    "  --nozzle D         nozzle diameter: bead 1.125 D wide (r = 0.5625 D) unless --radius is given\n"
    "  --printer P        printer profile (built-in name or .ini, as for gcode): its nozzle sets the\n"
    "                     bead unless --nozzle or --radius is given\n"
    "  --cell S           sparse lattice cell in mm (default 10 r, about 64 % infill)\n"
    "  --infill P         sparse infill density in % instead (cell = 4 r / (1 - sqrt(1 - P / 100)))\n"
    "  --bottom T, --top T  solid skin thickness in mm (default 0.8 each, 0: none): regions near a\n"
    "                     downward or upward facing surface get the dense lattice (cell 4r)\n"
    "  --eps-c C          warn where a layer overhangs the one below by more than C r (section 2.1,\n"
    "                     0 < C <= 1, default 1; per layer pair in --json)\n"
    "  --grid KIND        square (default), tri or hex\n"
    "  --offset D         mitered offset of the Euler transformation in mm (default r)\n"
    "  --tour KIND        cycle-tree (default, paper section 4) or merge (curves merged where they touch)\n"
    "  --no-perimeter     no perimeter loops\n"
    "  --no-corners       no support corners (step 6, Fig. 5) on the unprinted infill ring stretches\n"
    "  --support-stretches  print those stretches as support paths instead (Remark 2.1)\n"
    "  --pseudo           thin-cell patch stretches as pseudo edges (travel, Figs. 7, 8; each one\n"
    "                     more extrusion start); default printed (--no-pseudo kept for old scripts)\n"
    "  --no-join          perimeter loops and region strokes as separate paths\n"
    "  --no-overlap-cap   keep beads whose plastic exceeds the island's slab (section area x layer\n"
    "                     height) as built; by default they are narrowed to it (narrowed_islands)\n"
    "  -o FILE            OUT.amp: all layers; OUT.svg: one layer with its inset (with --continuous:\n"
    "                     with its strokes, beads drawn at their width)\n"
    "  --layer-index I    layer drawn in the SVG (default: the middle layer)\n"
    "  --z Z              draw the layer cut nearest to height Z mm instead\n"
    "  --json             figures as one JSON object (per layer with --polygons; strokes, starts,\n"
    "                     lengths, check results, overhangs with --continuous)\n"
    "A mesh that is not closed is sliced anyway: section chains that do not close are joined end to\n"
    "head, shortest gaps first (gaps_closed), with a warning on stderr. --continuous checks every path it writes\n"
    "(crossings, edges printed twice, points outside the layer) and exits 1 when one fails.\n"
    "Shells that overlap (bodies exported without a boolean union) are merged layer by layer: a point is\n"
    "solid when the section rings wind around it a positive number of times (overlapping_layers).\n";

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
            /* closed path: the last vertex repeats the first (docs/interfaces.md §4) */
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
        return cli_fail_err("slice", &s.err);
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
        return cli_fail_err("slice", &s.err);
    return CLI_OK;
}

static amp_grid_kind grid_kind(const char *g, int *ok)
{
    *ok = 1;
    if (strcmp(g, "square") == 0)
        return AMP_GRID_SQUARE;
    if (strcmp(g, "tri") == 0)
        return AMP_GRID_TRI;
    if (strcmp(g, "hex") == 0)
        return AMP_GRID_HEX;
    *ok = 0;
    return AMP_GRID_SQUARE;
}

/* One layer's strokes over its section: beads as wide as they print (2r,
 * translucent), centre lines thin, pseudo edges dashed, the start marked. */
static int write_stroke_svg(const char *file, const amp_slices *sl, const amp_pathset *ps, long li, double r)
{
    svg_doc s;
    double x0, y0, x1, y1;
    const amp_layer *L = &sl->layers[li];
    size_t i, k, strokes = 0, starts = 0;
    char line[200];
    int pass;
    slicetool_bbox(sl, &x0, &y0, &x1, &y1);
    if (svg_open(&s, file, x0, y0, x1, y1) != 0)
        return cli_fail("slice", CLI_USAGE, "cannot write '%s'", file);
    svg_polyset(&s, &L->polys, "#ece4f6", "#5b2a86", 1.0);
    for (pass = 0; pass < 3; pass++)
        for (i = 0; i < ps->npaths; i++) {
            const amp_pvert *v = amp_pathset_path_verts(ps, i);
            if (ps->paths[i].n < 2 || fabs(v[0].p.z - L->z_print) > 1e-9)
                continue;
            if (pass == 2) {
                fprintf(s.f, "<circle cx=\"%.5g\" cy=\"%.5g\" r=\"%.4g\" fill=\"#c0392b\"/>\n", v[0].p.x - s.x0,
                        s.y1 - v[0].p.y, 1.2 * r);
                strokes++;
                continue;
            }
            /* pass 0: the beads (printed segments), pass 1: centre lines */
            fprintf(s.f, "<path fill=\"none\" stroke=\"%s\" stroke-width=\"%.4g\" stroke-linecap=\"round\" "
                         "stroke-linejoin=\"round\"%s d=\"",
                    pass == 0 ? "rgba(39,110,176,0.35)" : "#1d3c5a", pass == 0 ? 2 * r : 0.6 * s.px,
                    pass == 0 ? " stroke-opacity=\"0.35\"" : "");
            for (k = 0; k + 1 < ps->paths[i].n; k++) {
                int printed = v[k].r > 0 || v[k + 1].r > 0;
                if (pass == 0 && !printed)
                    continue;
                fprintf(s.f, "M%.5g %.5gL%.5g %.5g", v[k].p.x - s.x0, s.y1 - v[k].p.y, v[k + 1].p.x - s.x0,
                        s.y1 - v[k + 1].p.y);
                if (pass == 1 && printed && k > 0 && !(v[k - 1].r > 0 || v[k].r > 0))
                    starts++;
            }
            fprintf(s.f, "\"/>\n");
        }
    snprintf(line, sizeof line, "layer %ld at z %.4g mm: %lu islands, %lu strokes (red dot: where each starts)", li,
             L->z_print, (unsigned long)L->polys.nislands, (unsigned long)strokes);
    svg_text(&s, 0, line);
    snprintf(line, sizeof line, "blue: beads %.3g mm wide over the section (purple), thin: the nozzle's path", 2 * r);
    svg_text(&s, 1, line);
    (void)starts;
    if (svg_close(&s) != 0)
        return cli_fail("slice", CLI_USAGE, "writing '%s' failed", file);
    return CLI_OK;
}

/* Layer whose printing height is z (the paths of --continuous). */
static const amp_polyset *layer_region(const amp_slices *sl, double z)
{
    size_t i;
    for (i = 0; i < sl->nlayers; i++)
        if (fabs(sl->layers[i].z_print - z) < 1e-9)
            return &sl->layers[i].polys;
    return NULL;
}

/* Extrusion starts counted like a G-code reader would: a printed segment
 * (radius > 0 at an end) after a travel (a new path, or a pseudo edge). */
static size_t count_starts(const amp_pathset *ps)
{
    size_t i, k, starts = 0;
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        int printing = 0;
        for (k = 0; k + 1 < ps->paths[i].n; k++) {
            int pr = (v[k].r > 0 || v[k + 1].r > 0) && amp_v3_dist(v[k].p, v[k + 1].p) > 0;
            int tr = !(v[k].r > 0 || v[k + 1].r > 0) && amp_v3_dist(v[k].p, v[k + 1].p) > 0;
            if (pr && !printing)
                starts++;
            if (pr)
                printing = 1;
            else if (tr)
                printing = 0;
        }
    }
    return starts;
}

/* §2.1: overhang of every layer pair, the pairs beyond c r, the worst. */
static size_t overhangs(const amp_slices *sl, double c, double r, double *per, double *worst, size_t *at)
{
    size_t i, over = 0;
    long q;
    *worst = 0;
    *at = 0;
    /* the layer pairs are independent (the slices use the default allocator): in parallel */
#pragma omp parallel for schedule(dynamic, 8)
    for (q = 0; q < (long)sl->nlayers - 1; q++)
        per[q] = amp_slices_overhang(sl, (size_t)q, 4 * r);
    for (i = 0; i + 1 < sl->nlayers; i++) {
        over += per[i] > c * r;
        if (per[i] > *worst) {
            *worst = per[i];
            *at = i + 1;
        }
    }
    return over;
}

static void json_stats(const amp_contpath_stats *st, const amp_pathset *ps, size_t crossings, size_t repeats,
                       size_t outside, size_t failed, double radius, double t0, const amp_slices *sl,
                       const double *per, double c)
{
    cli_json j;
    size_t i, over = 0;
    double worst = 0;
    cli_json_begin(&j, stdout);
    cli_json_int(&j, "layers", (long long)st->layers);
    cli_json_int(&j, "empty_layers", (long long)st->empty_layers);
    cli_json_int(&j, "islands", (long long)st->islands);
    cli_json_int(&j, "thin_islands", (long long)st->thin_islands);
    cli_json_int(&j, "neck_islands", (long long)st->neck_islands);
    cli_json_int(&j, "dropped_islands", (long long)st->dropped_islands);
    cli_json_int(&j, "island_strokes", (long long)st->island_strokes);
    cli_json_int(&j, "specks", (long long)st->specks);
    cli_json_int(&j, "extrusion_starts", (long long)count_starts(ps));
    cli_json_int(&j, "regions", (long long)st->regions);
    cli_json_int(&j, "skin_regions", (long long)st->skin_regions);
    cli_json_int(&j, "skin_bands", (long long)st->skin_bands);
    cli_json_int(&j, "band_retries", (long long)st->band_retries);
    cli_json_int(&j, "shift_retries", (long long)st->shift_retries);
    cli_json_int(&j, "strokes", (long long)st->strokes);
    cli_json_int(&j, "multi_stroke_regions", (long long)st->multi_stroke);
    cli_json_int(&j, "perimeter_loops", (long long)st->perimeter_loops);
    cli_json_int(&j, "support_paths", (long long)st->support_paths);
    cli_json_int(&j, "paths", (long long)ps->npaths);
    cli_json_int(&j, "travel_moves", (long long)st->travel_moves);
    cli_json_num(&j, "printed_length_mm", st->printed_length);
    cli_json_num(&j, "infill_length_mm", st->infill_length);
    cli_json_num(&j, "travel_length_mm", st->travel_length);
    cli_json_num(&j, "support_length_mm", st->support_length);
    cli_json_num(&j, "unprinted_ring_length_mm", st->unprinted_length);
    cli_json_int(&j, "support_corners", (long long)st->support_corners);
    cli_json_int(&j, "corners_left_out", (long long)st->corners_left_out);
    cli_json_int(&j, "corners_touched", (long long)st->corners_touched);
    cli_json_int(&j, "narrowed_islands", (long long)st->narrowed_islands);
    cli_json_num(&j, "narrowed_mm3", st->narrowed_volume);
    cli_json_int(&j, "cycles", (long long)st->cycles);
    cli_json_int(&j, "tree_levels", (long long)st->tree_levels);
    cli_json_int(&j, "tour_fallbacks", (long long)st->tour_fallbacks);
    cli_json_int(&j, "joins", (long long)st->joins);
    cli_json_num(&j, "pseudo_length_mm", st->pseudo_length);
    cli_json_int(&j, "free_ends", (long long)st->free_ends);
    cli_json_int(&j, "odd_vertices", (long long)st->odd_vertices);
    cli_json_int(&j, "crossings", (long long)crossings);
    cli_json_int(&j, "repeated_edges", (long long)repeats);
    cli_json_int(&j, "outside", (long long)outside);
    cli_json_int(&j, "failed_paths", (long long)failed);
    cli_json_num(&j, "radius", radius);
    for (i = 0; i + 1 < sl->nlayers; i++) {
        over += per[i] > c * radius;
        worst = fmax(worst, per[i]);
    }
    cli_json_num(&j, "eps_c", c);
    cli_json_int(&j, "overhang_pairs", (long long)over);
    cli_json_num(&j, "max_overhang_mm", worst < HUGE_VAL ? worst : -1);
    cli_json_arr(&j, "overhang_mm");
    for (i = 0; i + 1 < sl->nlayers; i++)
        cli_json_num(&j, NULL, per[i] < HUGE_VAL ? per[i] : -1);
    cli_json_close(&j);
    cli_json_arr(&j, "open_chain_layers");
    for (i = 0; i < sl->nlayers; i++)
        if (sl->layers[i].open_chains)
            cli_json_int(&j, NULL, (long long)i);
    cli_json_close(&j);
    cli_json_int(&j, "overlapping_layers", (long long)sl->overlaps);
    cli_json_num(&j, "time_s", cli_now() - t0);
    cli_json_end(&j);
}

/* --continuous: build, check every path independently (crossings, repeated
 * edges, points outside its layer) and report; a failed check is exit 1. */
/* The independent check of every path against its layer, paths in
 * parallel (they are independent; a third of the run on the vase);
 * figures summed, and the first failure's message printed, in path order.
 * AMP_ERR_NOMEM only. */
static amp_status check_paths(const amp_slices *sl, const amp_pathset *ps, int quiet, size_t *crossings,
                              size_t *repeats, size_t *outside, size_t *failed, amp_error *err)
{
    amp_stroke_report *reps = calloc(ps->npaths + 1, sizeof *reps);
    unsigned char *cst = calloc(ps->npaths + 1, 1);
    long n = (long)ps->npaths, li;
    size_t i;
    amp_status rc = AMP_OK;
    if (!reps || !cst) {
        free(reps);
        free(cst);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking the paths");
    }
#pragma omp parallel for schedule(dynamic, 4)
    for (li = 0; li < n; li++) {
        amp_error e;
        size_t q = (size_t)li;
        const amp_polyset *reg = ps->paths[q].n ? layer_region(sl, amp_pathset_path_verts(ps, q)[0].p.z) : NULL;
        amp_status cs = amp_check_path_stroke(ps, q, reg, 1e-6, &reps[q], &e);
        cst[q] = cs == AMP_OK ? 0 : (cs == AMP_ERR_NOMEM ? 2 : 1);
    }
    for (i = 0; i < ps->npaths && rc == AMP_OK; i++) {
        if (cst[i] == 2 || (cst[i] == 1 && *failed == 0)) {
            /* again, serially, for the message */
            const amp_polyset *reg = ps->paths[i].n ? layer_region(sl, amp_pathset_path_verts(ps, i)[0].p.z) : NULL;
            amp_status cs = amp_check_path_stroke(ps, i, reg, 1e-6, &reps[i], err);
            cst[i] = cs == AMP_OK ? 0 : (cs == AMP_ERR_NOMEM ? 2 : 1);
            if (cst[i] == 2)
                rc = AMP_ERR_NOMEM;
            else if (cst[i] == 1 && *failed == 0 && !quiet)
                fprintf(stderr, "ampath slice: path %lu fails its check: %s\n", (unsigned long)i, err->msg);
        }
        *failed += cst[i] != 0;
        *crossings += reps[i].crossings;
        *repeats += reps[i].repeated_edges;
        *outside += reps[i].outside;
    }
    free(reps);
    free(cst);
    return rc;
}

/* The paths of every layer into @p ps (emptied first; progress on a terminal), with the options' per-island
 * stroke verifier when @p verify, without it otherwise. */
static amp_status make_layers(const amp_slices *sl, const amp_contpath_opts *o, int verify, amp_pathset *ps,
                              amp_contpath_stats *st, amp_error *err)
{
    amp_contpath_opts po = *o;
    cli_progress bar;
    amp_status cs;
    amp_pathset_clear(ps);
    if (!verify)
        po.verify_stroke = NULL;
    po.progress = cli_progress_fn;
    po.progress_user = &bar;
    cli_progress_begin(&bar, verify ? "slice again" : "slice");
    cs = amp_contpath_layers(sl, &po, ps, st, err);
    cli_progress_end(&bar);
    return cs;
}

static int run_continuous(const char *file, const char *out, const amp_slices *sl, const amp_contpath_opts *o,
                          int json, double t0, double epsc, long svg_layer)
{
    amp_pathset ps;
    amp_contpath_stats st;
    amp_error err;
    size_t crossings = 0, repeats = 0, outside = 0, failed = 0, over, at;
    double *per = calloc(sl->nlayers + 1, sizeof *per), worst;
    int rc = CLI_OK;
    amp_status cs;
    if (!per)
        return cli_fail("slice", CLI_USAGE, "out of memory");
    amp_pathset_init(&ps, NULL);
    amp_error_clear(&err);
    /* the final check is the skin bands' safety net first: the per-island verifier (o->verify_stroke, the
     * same check once more on most islands: a sixth of the time) runs only when a path fails it */
    cs = make_layers(sl, o, 0, &ps, &st, &err);
    if (cs == AMP_OK)
        cs = check_paths(sl, &ps, 1, &crossings, &repeats, &outside, &failed, &err);
    if (cs == AMP_OK && failed) {
        /* the layers again with the verifier (an island whose banded paths fail it is made again with its
         * skin regions whole), and the check again, with its message */
        crossings = repeats = outside = failed = 0;
        if (o->verify_stroke)
            cs = make_layers(sl, o, 1, &ps, &st, &err);
        if (cs == AMP_OK)
            cs = check_paths(sl, &ps, 0, &crossings, &repeats, &outside, &failed, &err);
    }
    if (cs != AMP_OK) {
        amp_pathset_free(&ps);
        free(per);
        return cli_fail_err("slice", &err);
    }
    over = overhangs(sl, epsc, o->radius, per, &worst, &at);
    if (over && worst < HUGE_VAL)
        fprintf(stderr,
                "ampath slice: warning: %lu layer pairs are not eps-continuous (overhang > %g r = %g mm; worst %.3g mm "
                "under layer %lu at z %.4g): the layer above may sag (`ampath support` lays support under the "
                "overhangs on the job's layers)\n",
                (unsigned long)over, epsc, epsc * o->radius, worst, (unsigned long)at, sl->layers[at].z_print);
    else if (over) /* a section over an empty layer: a piece of the part that starts in mid-air */
        fprintf(stderr,
                "ampath slice: warning: %lu layer pairs are not eps-continuous (overhang > %g r = %g mm); layer %lu at "
                "z %.4g starts over an empty layer (a piece of the part begins in mid-air): it needs support\n",
                (unsigned long)over, epsc, epsc * o->radius, (unsigned long)at, sl->layers[at].z_print);
    if (out && svg_layer >= 0)
        rc = write_stroke_svg(out, sl, &ps, svg_layer, o->radius);
    else if (out) {
        char comment[200];
        snprintf(comment, sizeof comment,
                 "ampath slice --continuous: %lu layers, %lu islands, %lu strokes, radius %g mm",
                 (unsigned long)st.layers, (unsigned long)st.islands, (unsigned long)st.island_strokes, o->radius);
        rc = cli_save_paths("slice", out, &ps, comment);
    }
    if (rc == CLI_OK && json)
        json_stats(&st, &ps, crossings, repeats, outside, failed, o->radius, t0, sl, per, epsc);
    else if (rc == CLI_OK)
        printf("%s: %lu layers, %lu islands, %lu strokes, %lu extrusion starts, %lu travel moves, printed %.1f mm, "
               "travel %.1f mm%s%s\n",
               file, (unsigned long)st.layers, (unsigned long)st.islands, (unsigned long)st.island_strokes,
               (unsigned long)count_starts(&ps), (unsigned long)st.travel_moves, st.printed_length, st.travel_length,
               out ? " -> " : "", out ? out : "");
    if (rc == CLI_OK && failed) {
        fprintf(stderr,
                "ampath slice: %lu paths fail the stroke check (%lu crossings, %lu edges printed twice, %lu points "
                "outside their layer): a bug, please report it\n",
                (unsigned long)failed, (unsigned long)crossings, (unsigned long)repeats, (unsigned long)outside);
        rc = CLI_FAILED;
    }
    if (rc == CLI_OK && st.empty_layers)
        fprintf(stderr,
                "ampath slice: warning: %lu layers with section area got no path (slivers thinner than r/16 or "
                "specks under r/4 across: no centre line for a bead)\n",
                (unsigned long)st.empty_layers);
    amp_pathset_free(&ps);
    free(per);
    return rc;
}

/* The command line, validated: what the polygon and the continuous runs read. */
typedef struct slice_args {
    const char *mesh, *out;
    double layer, first, radius, z, epsc;
    long index;
    int json, continuous, have_z;
    amp_contpath_opts co;
} slice_args;

/* The options as given that only validation reads (slice_parse). */
typedef struct slice_raw {
    const char *grid, *tour, *printer;
    double nozzle, cell, offset, infill, skin_bottom, skin_top;
    int polygons, noperim, stretches, nopseudo, pseudo, nojoin, nocorners, nocap;
    int have_nozzle, have_radius, have_cell, have_offset;
} slice_raw;

/* The bead half-width: --radius, else --nozzle, else the --printer profile's nozzle. */
static int slice_bead(slice_raw *w, slice_args *a)
{
    if (w->printer && !w->have_nozzle && !w->have_radius) {
        /* the profile's nozzle sets the bead (docs/interfaces.md §4: 1.125 x the nozzle), as --nozzle does */
        amp_printer *pr = malloc(sizeof *pr);
        amp_error err;
        if (!pr)
            return cli_fail("slice", CLI_USAGE, "out of memory");
        if (amp_printer_load(pr, w->printer, &err) != AMP_OK) {
            free(pr);
            return cli_fail("slice", CLI_USAGE, "%s", err.msg);
        }
        w->nozzle = pr->nozzle_diameter;
        w->have_nozzle = 1;
        free(pr);
    }
    if (w->have_nozzle && !w->have_radius) {
        if (!(w->nozzle > 0) || !isfinite(w->nozzle))
            return cli_fail("slice", CLI_USAGE, "--nozzle must be positive");
        a->radius = 0.5 * 1.125 * w->nozzle; /* a bead 1.125 x the nozzle wide, as slicers extrude */
    }
    if (!(a->radius > 0) || !isfinite(a->radius))
        return cli_fail("slice", CLI_USAGE, "--radius must be positive");
    return CLI_OK;
}

/* The options of --continuous (a->co) from the lattice, skin and tour options, checked in the order of the
 * messages users know. */
static int slice_contpath(const slice_raw *w, slice_args *a)
{
    amp_contpath_opts *co = &a->co;
    int ok;
    amp_contpath_opts_default(co, a->radius);
    co->verify_stroke = amp_check_path_stroke; /* the skin bands' safety net */
    co->grid = grid_kind(w->grid, &ok);
    if (!ok)
        return cli_fail("slice", CLI_USAGE, "--grid must be square, tri or hex, not '%s'", w->grid);
    if ((w->have_cell && (!(w->cell > 0) || !isfinite(w->cell))) ||
        (w->have_offset && (!(w->offset > 0) || !isfinite(w->offset))))
        return cli_fail("slice", CLI_USAGE, "--cell and --offset must be positive");
    if (w->have_cell)
        co->cell = w->cell;
    if (w->have_offset)
        co->offset = w->offset;
    co->perimeters = !w->noperim;
    co->support_stretches = w->stretches;
    co->pseudo_edges = w->pseudo && !w->nopseudo;
    co->join = !w->nojoin;
    co->support_corners = !w->nocorners;
    co->overlap_cap = !w->nocap;
    if (!(w->skin_bottom >= 0) || !(w->skin_top >= 0) || !isfinite(w->skin_bottom) || !isfinite(w->skin_top))
        return cli_fail("slice", CLI_USAGE, "--bottom and --top must be thicknesses >= 0 mm");
    if (!(a->epsc > 0 && a->epsc <= 1))
        return cli_fail("slice", CLI_USAGE, "--eps-c must be in (0, 1]");
    co->skin_bottom = w->skin_bottom;
    co->skin_top = w->skin_top;
    if (w->have_cell && w->infill > 0)
        return cli_fail("slice", CLI_USAGE, "--cell and --infill exclude each other");
    if (w->infill != 0) {
        if (!(w->infill > 0 && w->infill <= 100))
            return cli_fail("slice", CLI_USAGE, "--infill must be a density in %% (0 < P <= 100)");
        /* every line of a square lattice of cell S carries two beads (a
         * band 4r wide): x = 4r / S of the area lies under the bands of one
         * direction, 2x - x^2 under both; solved for the density */
        co->cell = 4 * a->radius / (1 - sqrt(1 - w->infill / 100));
    }
    if (strcmp(w->tour, "cycle-tree") == 0)
        co->tour = AMP_TOUR_CYCLE_TREE;
    else if (strcmp(w->tour, "merge") == 0)
        co->tour = AMP_TOUR_MERGE;
    else
        return cli_fail("slice", CLI_USAGE, "--tour must be cycle-tree or merge, not '%s'", w->tour);
    return CLI_OK;
}

/* The command line into @p a; every reason to refuse it is printed here (CLI_USAGE). */
static int slice_parse(int argc, char **argv, slice_args *a)
{
    slice_raw w;
    const char *pos[1];
    int npos = 0, rc;
    cli_opt opts[] = {{"layer", CLI_DOUBLE, &a->layer, 0},         {"first-layer", CLI_DOUBLE, &a->first, 0},
                      {"polygons", CLI_FLAG, &w.polygons, 0},      {"output", CLI_STR, &a->out, 0},
                      {"layer-index", CLI_LONG, &a->index, 0},     {"z", CLI_DOUBLE, &a->z, 0},
                      {"radius", CLI_DOUBLE, &a->radius, 0},       {"json", CLI_FLAG, &a->json, 0},
                      {"continuous", CLI_FLAG, &a->continuous, 0}, {"cell", CLI_DOUBLE, &w.cell, 0},
                      {"grid", CLI_STR, &w.grid, 0},               {"offset", CLI_DOUBLE, &w.offset, 0},
                      {"no-perimeter", CLI_FLAG, &w.noperim, 0},   {"support-stretches", CLI_FLAG, &w.stretches, 0},
                      {"no-pseudo", CLI_FLAG, &w.nopseudo, 0},     {"nozzle", CLI_DOUBLE, &w.nozzle, 0},
                      {"no-join", CLI_FLAG, &w.nojoin, 0},         {"pseudo", CLI_FLAG, &w.pseudo, 0},
                      {"tour", CLI_STR, &w.tour, 0},               {"no-corners", CLI_FLAG, &w.nocorners, 0},
                      {"no-overlap-cap", CLI_FLAG, &w.nocap, 0},
                      {"infill", CLI_DOUBLE, &w.infill, 0},        {"bottom", CLI_DOUBLE, &w.skin_bottom, 0},
                      {"top", CLI_DOUBLE, &w.skin_top, 0},         {"eps-c", CLI_DOUBLE, &a->epsc, 0},
                      {"printer", CLI_STR, &w.printer, 0},         {NULL, CLI_FLAG, NULL, 0}};
    memset(a, 0, sizeof *a);
    memset(&w, 0, sizeof w);
    a->radius = 0.225;
    a->index = -1;
    a->epsc = 1.0;
    w.grid = "square";
    w.tour = "cycle-tree";
    w.skin_bottom = w.skin_top = 0.8;
    rc = cli_parse("slice", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (!cli_given(opts, "layer"))
        return cli_fail("slice", CLI_USAGE, "--layer H is required");
    a->mesh = pos[0];
    a->have_z = cli_given(opts, "z");
    w.have_nozzle = cli_given(opts, "nozzle");
    w.have_radius = cli_given(opts, "radius");
    w.have_cell = cli_given(opts, "cell");
    w.have_offset = cli_given(opts, "offset");
    if ((rc = slice_bead(&w, a)) != CLI_OK)
        return rc;
    if (a->continuous && w.polygons)
        return cli_fail("slice", CLI_USAGE, "--polygons and --continuous exclude each other");
    return slice_contpath(&w, a);
}

/* --polygons (the default): the figures of the layers' rings, one JSON object or a line. */
static void report_polygons(const slice_args *a, const amp_mesh *m, const amp_slices *sl, size_t flipped, double t0)
{
    size_t i, r, rings = 0, holes = 0, islands = 0;
    cli_json j;
    for (i = 0; i < sl->nlayers; i++) {
        rings += sl->layers[i].polys.nrings;
        islands += sl->layers[i].polys.nislands;
        for (r = 0; r < sl->layers[i].polys.nrings; r++)
            holes += sl->layers[i].polys.rings[r].hole != 0;
    }
    if (!a->json) {
        printf("%s: %lu layers, %lu polygons (%lu islands, %lu holes)%s%s\n", a->mesh, (unsigned long)sl->nlayers,
               (unsigned long)rings, (unsigned long)islands, (unsigned long)holes, a->out ? " -> " : "",
               a->out ? a->out : "");
        return;
    }
    cli_json_begin(&j, stdout);
    cli_json_int(&j, "layers", (long long)sl->nlayers);
    cli_json_int(&j, "polygons", (long long)rings);
    cli_json_int(&j, "islands", (long long)islands);
    cli_json_int(&j, "holes", (long long)holes);
    cli_json_int(&j, "open_chains", (long long)sl->open_chains);
    cli_json_int(&j, "gaps_closed", (long long)sl->gaps_closed);
    cli_json_int(&j, "overlapping_layers", (long long)sl->overlaps);
    cli_json_int(&j, "nonmanifold", (long long)sl->nonmanifold);
    cli_json_int(&j, "flipped_triangles", (long long)flipped);
    cli_json_int(&j, "triangles", (long long)m->ntris);
    cli_json_num(&j, "layer_height", a->layer);
    cli_json_num(&j, "first_layer", a->first > 0 ? a->first : a->layer);
    cli_json_num(&j, "time_s", cli_now() - t0);
    cli_json_arr(&j, "per_layer");
    for (i = 0; i < sl->nlayers; i++) {
        size_t nh = 0;
        for (r = 0; r < sl->layers[i].polys.nrings; r++)
            nh += sl->layers[i].polys.rings[r].hole != 0;
        cli_json_obj(&j, NULL);
        cli_json_int(&j, "index", (long long)i);
        cli_json_num(&j, "z_cut", sl->layers[i].z_cut);
        cli_json_num(&j, "z_print", sl->layers[i].z_print);
        cli_json_int(&j, "islands", (long long)sl->layers[i].polys.nislands);
        cli_json_int(&j, "polygons", (long long)sl->layers[i].polys.nrings);
        cli_json_int(&j, "holes", (long long)nh);
        cli_json_num(&j, "area_mm2", amp_polyset_area(&sl->layers[i].polys));
        cli_json_int(&j, "open_chains", (long long)sl->layers[i].open_chains);
        cli_json_close(&j);
    }
    cli_json_close(&j);
    cli_json_end(&j);
}

int cmd_slice(int argc, char **argv)
{
    double t0 = cli_now();
    slice_args a;
    amp_mesh m;
    amp_slices sl;
    size_t flipped = 0;
    int svg, rc = slice_parse(argc, argv, &a);
    if (rc != CLI_OK)
        return rc;
    svg = a.out && cli_ends_with(a.out, ".svg");
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    rc = slicetool_load("slice", a.mesh, a.layer, a.first, &m, &sl, &flipped);
    if (rc == CLI_OK && sl.gaps_closed)
        fprintf(stderr, "ampath slice: warning: mesh is not closed: %lu section gaps closed by straight edges\n",
                (unsigned long)sl.gaps_closed);
    if (rc == CLI_OK && sl.open_chains)
        fprintf(stderr, "ampath slice: warning: mesh is not closed: %lu open section chains dropped\n",
                (unsigned long)sl.open_chains);
    if (rc == CLI_OK && a.continuous) {
        long li = svg ? slicetool_pick("slice", &sl, a.index, a.have_z, a.z) : -1;
        rc = li < -1 || (svg && li < 0) ? CLI_USAGE
                                        : run_continuous(a.mesh, a.out, &sl, &a.co, a.json, t0, a.epsc, li);
    } else {
        if (rc == CLI_OK && svg) {
            long li = slicetool_pick("slice", &sl, a.index, a.have_z, a.z);
            rc = li < 0 ? CLI_USAGE : write_svg(a.out, &sl, li, a.radius);
        } else if (rc == CLI_OK && a.out)
            rc = write_amp(a.out, &sl, a.radius, a.layer);
        if (rc == CLI_OK)
            report_polygons(&a, &m, &sl, flipped, t0);
    }
    amp_slices_free(&sl);
    amp_mesh_free(&m);
    return rc;
}
