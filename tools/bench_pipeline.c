/*
 * Benchmark (SPEC §7): the full helix pipeline of `make demo` in one process —
 * cover (paper 1 §4.1) → order (§5.1) → MDR (§5.2) → support (§5.3) → G-code
 * (SPEC §5) — stage by stage, next to a baseline measured in the same run: the
 * planar pipeline on the same solid (slice → continuous strokes of paper 2 →
 * G-code), i.e. what a layer-based job of the same part costs.
 */
#include "cli.h"

/* Counts G-code bytes instead of storing them. */
static amp_status count_sink(void *user, const char *data, size_t len)
{
    (void)data;
    *(size_t *)user += len;
    return AMP_OK;
}

typedef struct stage_times {
    double cover, order, mdr, support, gcode;
} stage_times;

static int volumetric(double eps, stage_times *t, size_t *npaths, size_t *subdiv, size_t *bytes)
{
    amp_spline v;
    amp_cover_opts co;
    amp_order_opts oo;
    amp_order_stats ost;
    amp_mdr_opts mo;
    amp_support_opts so;
    amp_gcode_opts go;
    amp_pathset a, b;
    amp_mesh m;
    amp_bvh *bvh = NULL;
    double t0;
    int ok;
    amp_spline_init(&v);
    amp_pathset_init(&a, NULL);
    amp_pathset_init(&b, NULL);
    amp_mesh_init(&m, NULL);
    amp_cover_opts_default(&co);
    co.eps = eps;
    co.dir = 0; /* curves along the helix, as the demo */
    amp_order_opts_default(&oo);
    amp_mdr_opts_default(&mo, 0.5);
    amp_support_opts_default(&so);
    amp_gcode_opts_default(&go, AMP_FLAVOR_MARLIN);
    *bytes = 0;
    t0 = cli_now();
    ok = amp_trivariate_model("helix", NULL, &v, NULL) == AMP_OK && amp_cover_trivariate(&v, &co, &a, NULL, NULL) == AMP_OK;
    t->cover = cli_now() - t0;
    t0 = cli_now();
    ok = ok && amp_order(&a, &oo, &b, &ost, NULL) == AMP_OK;
    t->order = cli_now() - t0;
    amp_pathset_clear(&a);
    t0 = cli_now();
    ok = ok && amp_mdr(&b, &mo, &a, NULL, NULL) == AMP_OK;
    t->mdr = cli_now() - t0;
    amp_pathset_clear(&b);
    t0 = cli_now();
    ok = ok && amp_mesh_from_trivariate(&m, &v, 0, NULL) == AMP_OK && amp_bvh_build(&bvh, &m, NULL) == AMP_OK &&
         amp_support(&a, bvh, &so, &b, NULL, NULL) == AMP_OK;
    t->support = cli_now() - t0;
    t0 = cli_now();
    ok = ok && amp_gcode_write(&b, &go, count_sink, bytes, NULL, NULL) == AMP_OK;
    t->gcode = cli_now() - t0;
    *npaths = b.npaths;
    *subdiv = ok ? ost.subdivisions : 0;
    amp_bvh_free(bvh);
    amp_mesh_free(&m);
    amp_pathset_free(&a);
    amp_pathset_free(&b);
    amp_spline_free(&v);
    return ok;
}

static int planar(double layer, double *t, size_t *strokes, size_t *bytes)
{
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts so;
    amp_contpath_opts co;
    amp_contpath_stats st;
    amp_gcode_opts go;
    amp_pathset ps;
    double t0 = cli_now();
    int ok;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    so.layer = layer;
    so.first_layer = 0;
    amp_contpath_opts_default(&co, 0.5);
    amp_gcode_opts_default(&go, AMP_FLAVOR_MARLIN);
    *bytes = 0;
    ok = amp_mesh_model("helix", 0, &m, NULL) == AMP_OK && amp_slice_mesh(&m, &so, &sl, NULL) == AMP_OK &&
         amp_contpath_layers(&sl, &co, &ps, &st, NULL) == AMP_OK &&
         amp_gcode_write(&ps, &go, count_sink, bytes, NULL, NULL) == AMP_OK;
    *t = cli_now() - t0;
    *strokes = ok ? st.strokes : 0;
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
    return ok;
}

int bench_pipeline(cli_json *j, int quick)
{
    stage_times t;
    double eps = quick ? 2.0 : 1.0, layer = quick ? 1.0 : 0.5, total, t_planar;
    size_t npaths, subdiv, bytes, strokes, pbytes;
    if (!volumetric(eps, &t, &npaths, &subdiv, &bytes) || !planar(layer, &t_planar, &strokes, &pbytes))
        return CLI_FAILED;
    total = t.cover + t.order + t.mdr + t.support + t.gcode;
    if (j) {
        cli_json_num(j, "eps", eps);
        cli_json_num(j, "cover_s", t.cover);
        cli_json_num(j, "order_s", t.order);
        cli_json_num(j, "mdr_s", t.mdr);
        cli_json_num(j, "support_s", t.support);
        cli_json_num(j, "gcode_s", t.gcode);
        cli_json_num(j, "total_s", total);
        cli_json_int(j, "paths", (long long)npaths);
        cli_json_int(j, "subdivisions", (long long)subdiv);
        cli_json_int(j, "gcode_bytes", (long long)bytes);
        cli_json_num(j, "planar_layer", layer);
        cli_json_num(j, "planar_s", t_planar);
        cli_json_int(j, "planar_strokes", (long long)strokes);
        cli_json_num(j, "total_over_planar", total / (t_planar > 0 ? t_planar : 1e-9));
    } else {
        printf("helix pipeline eps %.1f mm: %.2f s total = cover %.2f + order %.2f + mdr %.2f + support %.2f + "
               "gcode %.2f; %lu paths, %lu subdivisions, %.1f MB of G-code\n",
               eps, total, t.cover, t.order, t.mdr, t.support, t.gcode, (unsigned long)npaths,
               (unsigned long)subdiv, (double)bytes / 1e6);
        printf("baseline, planar continuous pipeline on the helix mesh (layer %.1f mm): %.2f s, %lu strokes, "
               "%.1f MB; volumetric / planar = %.2fx\n",
               layer, t_planar, (unsigned long)strokes, (double)pbytes / 1e6, total / (t_planar > 0 ? t_planar : 1e-9));
    }
    return CLI_OK;
}
