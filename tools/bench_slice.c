/* Benchmark (docs/interfaces.md §7): slicing + continuous paths on a ~100k-triangle mesh,
 * against a plain per-layer rectilinear infill made by the same tool
 * (extrusion starts, travel). */
#define _POSIX_C_SOURCE 200809L /* readlink */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"

/* A bumpy torus (R 30, r 9 mm) with nu x nv quads: 2 nu nv triangles. */
static int make_mesh(amp_mesh *m, int nu, int nv)
{
    int i, j;
    const double tau = 2.0 * AMP_PI;
    for (i = 0; i < nu; i++)
        for (j = 0; j < nv; j++) {
            double u = tau * i / nu, v = tau * j / nv, rr = 9 + 1.5 * sin(5 * u), rho = 30 + rr * cos(v);
            if (amp_mesh_add_vertex(m, amp_v3(rho * cos(u), rho * sin(u), 12 + rr * sin(v)), NULL, NULL) != AMP_OK)
                return -1;
        }
    for (i = 0; i < nu; i++)
        for (j = 0; j < nv; j++) {
            uint32_t a = (uint32_t)(i * nv + j), b = (uint32_t)(((i + 1) % nu) * nv + j);
            uint32_t c = (uint32_t)(((i + 1) % nu) * nv + (j + 1) % nv), d = (uint32_t)(i * nv + (j + 1) % nv);
            if (amp_mesh_add_tri(m, a, b, c, NULL) != AMP_OK || amp_mesh_add_tri(m, a, c, d, NULL) != AMP_OK)
                return -1;
        }
    return 0;
}

typedef struct rect_stats {
    size_t starts;
    double length, travel;
} rect_stats;

/* Plain rectilinear infill of one region: scan lines every @p s (alternating
 * direction), every interval its own extrusion; travel from the end of one
 * interval to the start of the next. */
static void rectilinear(const amp_polyset *R, double s, amp_vec2 *last, int *have, rect_stats *rs)
{
    double y0 = HUGE_VAL, y1 = -HUGE_VAL, y, xs[4096];
    size_t i, k;
    int line = 0;
    for (i = 0; i < R->npts; i++) {
        y0 = fmin(y0, R->pts[i].y);
        y1 = fmax(y1, R->pts[i].y);
    }
    for (y = y0 + 0.5 * s; y < y1; y += s, line++) {
        size_t nx = 0;
        for (i = 0; i < R->nrings; i++) {
            const amp_vec2 *p = amp_polyset_ring(R, i);
            size_t n = R->rings[i].n;
            for (k = 0; k < n && nx < 4096; k++) {
                amp_vec2 a = p[k], b = p[(k + 1) % n];
                if ((a.y > y) != (b.y > y))
                    xs[nx++] = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
            }
        }
        /* insertion sort: few crossings per line */
        for (i = 1; i < nx; i++)
            for (k = i; k > 0 && xs[k - 1] > xs[k]; k--) {
                double t = xs[k];
                xs[k] = xs[k - 1];
                xs[k - 1] = t;
            }
        for (i = 0; i + 1 < nx; i += 2) {
            size_t q = line % 2 ? nx - 2 - i : i;
            amp_vec2 a = amp_v2(line % 2 ? xs[q + 1] : xs[q], y), b = amp_v2(line % 2 ? xs[q] : xs[q + 1], y);
            if (*have)
                rs->travel += hypot(a.x - last->x, a.y - last->y);
            rs->starts++;
            rs->length += fabs(b.x - a.x);
            *last = b;
            *have = 1;
        }
    }
}

/* A square plate of side @p side mm, 4 mm thick, lying on the plate (12 triangles, outward). */
static int plate_mesh(amp_mesh *m, double side)
{
    static const int tri[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                   {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
    uint32_t id[8];
    int k;
    for (k = 0; k < 8; k++)
        if (amp_mesh_add_vertex(m, amp_v3((k % 4 == 1 || k % 4 == 2) ? side : 0, (k % 4 >= 2) ? side : 0, k >= 4 ? 4 : 0),
                                &id[k], NULL) != AMP_OK)
            return -1;
    for (k = 0; k < 12; k++)
        if (amp_mesh_add_tri(m, id[tri[k][0]], id[tri[k][1]], id[tri[k][2]], NULL) != AMP_OK)
            return -1;
    return 0;
}

/*
 * Scaling series (the cost must grow linearly; docs/slice.md): the time per
 * printed millimetre should stay flat as the part grows. @p plate 0: the
 * bumpy torus scaled by s in x and y (a quarter size at s = 1), 1 mm layers;
 * 1: a square plate 4 mm thick of side 25 s mm, 0.2 mm layers — its sparse
 * layers' cycle trees are as deep as the plate is wide (a scan of every
 * vertex per level made the 200 mm plate cost 1.3 x per mm what the 100 mm
 * one did). Default continuous paths.
 */
static int scaling(cli_json *j, int quick, int plate)
{
    static const double scales[] = {1, 2, 4, 8, 16};
    size_t ns = plate ? (quick ? 3 : 4) : (quick ? 3 : 5), i, v;
    double per[5], lo = HUGE_VAL, hi = 0, grow = 0;
    int rc = CLI_OK;
    const char *what = plate ? "plate" : "torus";
    if (j)
        cli_json_arr(j, plate ? "plate_scaling" : "scaling");
    for (i = 0; i < ns && rc == CLI_OK; i++) {
        amp_mesh m;
        amp_slices sl;
        amp_slice_opts so;
        amp_contpath_opts o;
        amp_contpath_stats st;
        amp_pathset ps;
        double t0, t;
        amp_mesh_init(&m, NULL);
        amp_slices_init(&sl, NULL);
        amp_pathset_init(&ps, NULL);
        if ((plate ? plate_mesh(&m, 25 * scales[i]) : make_mesh(&m, 96, 48)) != 0)
            rc = CLI_FAILED;
        for (v = 0; !plate && v < m.nverts; v++)
            m.verts[v] = amp_v3(m.verts[v].x * scales[i] / 4, m.verts[v].y * scales[i] / 4, m.verts[v].z / 4);
        so.layer = plate ? 0.2 : 0.5;
        so.first_layer = 0;
        amp_contpath_opts_default(&o, 0.225); /* no per-island verifier: the tool's first pass */
        t0 = cli_now();
        if (rc == CLI_OK && (amp_slice_mesh(&m, &so, &sl, NULL) != AMP_OK ||
                             amp_contpath_layers(&sl, &o, &ps, &st, NULL) != AMP_OK))
            rc = CLI_FAILED;
        t = cli_now() - t0;
        per[i] = rc == CLI_OK && st.printed_length > 0 ? 1e6 * t / st.printed_length : 0;
        if (i > 0 && lo > 0) /* the cost per mm at this scale against the cheapest smaller one: > 1 is superlinear */
            grow = fmax(grow, per[i] / lo);
        lo = fmin(lo, per[i]);
        hi = fmax(hi, per[i]);
        if (rc == CLI_OK && j) {
            cli_json_obj(j, NULL);
            cli_json_num(j, "scale", scales[i]);
            cli_json_num(j, "time_s", t);
            cli_json_num(j, "printed_mm", st.printed_length);
            cli_json_num(j, "us_per_mm", per[i]);
            cli_json_close(j);
        } else if (rc == CLI_OK)
            printf("%s x%g: %.3f s for %.0f mm printed (%.2f us/mm)\n", what, scales[i], t, st.printed_length, per[i]);
        amp_pathset_free(&ps);
        amp_slices_free(&sl);
        amp_mesh_free(&m);
    }
    if (j) {
        cli_json_close(j);
        cli_json_num(j, plate ? "plate_scaling_spread" : "scaling_spread", lo > 0 ? hi / lo : 0);
        cli_json_num(j, plate ? "plate_scaling_growth" : "scaling_growth", grow);
    } else if (rc == CLI_OK) {
        printf("%s: time per printed mm from x1 to x%g: spread %.2fx (flat is 1; the small parts carry the fixed "
               "costs)\n", what, scales[ns - 1], lo > 0 ? hi / lo : 0);
        printf("  target growth of the time per printed mm with the %s (largest ratio to a smaller part's): %.2fx "
               "(<= 1.25) %s\n", what, grow, grow <= 1.25 ? "met" : "NOT MET");
    }
    return rc;
}

/* Wall time of a shell command (-1 when it fails). */
static double timed(const char *cmd)
{
    double t0 = cli_now();
    int rc = system(cmd);
    double t = cli_now() - t0;
    return rc == 0 ? t : -1;
}

/* Median of the first @p n (1 or 3) values. */
static double median3(const double *v, size_t n)
{
    if (n < 3)
        return v[0];
    if ((v[0] <= v[1]) == (v[1] <= v[2]))
        return v[1];
    if ((v[1] <= v[0]) == (v[0] <= v[2]))
        return v[0];
    return v[2];
}

/* One mesh side by side: ours = `ampath slice --continuous` + `ampath gcode`
 * as processes (this very binary), PrusaSlicer = headless --export-gcode;
 * both 0.2 mm layers, 0.45 mm beads (0.4 mm nozzle) and 20 % sparse infill
 * (PrusaSlicer's default; ours is 64 % unless told), files written. */
static void side_by_side(cli_json *j, const char *name, const amp_mesh *m, double *worst, int quick)
{
    char stl[256], amp[256], gc[256], gp[256], cmd[2400], cmd2[1200], self[512];
    const char *tmp = getenv("TMPDIR");
    amp_error err;
    double ours, theirs, ratio, to[3], tt[3], tr[3];
    size_t k, reps = quick ? 1 : 3;
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0)
        snprintf(self, sizeof self, "ampath");
    else
        self[n] = 0;
    snprintf(stl, sizeof stl, "%s/ampath-bench-%ld.stl", tmp ? tmp : "/tmp", (long)getpid());
    snprintf(amp, sizeof amp, "%s/ampath-bench-%ld.amp", tmp ? tmp : "/tmp", (long)getpid());
    snprintf(gc, sizeof gc, "%s/ampath-bench-%ld.gcode", tmp ? tmp : "/tmp", (long)getpid());
    snprintf(gp, sizeof gp, "%s/ampath-bench-%ld-prusa.gcode", tmp ? tmp : "/tmp", (long)getpid());
    if (amp_mesh_write_stl_file(m, stl, 1, &err) != AMP_OK)
        return;
    snprintf(cmd, sizeof cmd,
             "'%s' slice '%s' --layer 0.2 --radius 0.225 --infill 20 --continuous -o '%s' >/dev/null 2>&1 && "
             "'%s' gcode '%s' -o '%s' >/dev/null 2>&1",
             self, stl, amp, self, amp, gc);
    snprintf(cmd2, sizeof cmd2,
             "prusa-slicer --export-gcode --layer-height 0.2 --nozzle-diameter 0.4 --extrusion-width 0.45 --fill-density 20%% "
             "--center 125,105 -o '%s' '%s' >/dev/null 2>&1",
             gp, stl);
    /* pair by pair, the two runs of a pair back to back (the machine's speed drifts): the medians of the pairs */
    for (k = 0; k < reps; k++) {
        to[k] = timed(cmd);
        tt[k] = timed(cmd2);
        tr[k] = to[k] > 0 && tt[k] > 0 ? to[k] / tt[k] : HUGE_VAL;
    }
    ours = median3(to, reps);
    theirs = median3(tt, reps);
    ratio = median3(tr, reps);
    remove(stl);
    remove(amp);
    remove(gc);
    remove(gp);
    if (ours > 0 && theirs > 0 && ratio < HUGE_VAL && ratio > *worst)
        *worst = ratio;
    if (j) {
        cli_json_obj(j, NULL);
        cli_json_str(j, "mesh", name);
        cli_json_int(j, "triangles", (long long)m->ntris);
        cli_json_num(j, "continuous_gcode_s", ours);
        cli_json_num(j, "prusaslicer_s", theirs);
        cli_json_num(j, "ratio", ours > 0 && theirs > 0 && ratio < HUGE_VAL ? ratio : -1);
        cli_json_close(j);
    } else if (ours > 0 && theirs > 0)
        printf("  %-16s %7lu triangles: ours %6.2f s, PrusaSlicer %6.2f s (%.2fx, median of %lu pairs)\n", name,
               (unsigned long)m->ntris, ours, theirs, ratio, (unsigned long)reps);
    else
        printf("  %-16s failed (ours %s, PrusaSlicer %s)\n", name, ours > 0 ? "ok" : "failed",
               theirs > 0 ? "ok" : "failed");
}

/* The real parts of the side by side: PrusaSlicer's own shapes as Debian installs them (its 107 mm bunny is
 * the one part above the target), when present. */
static const char *const prusa_shapes[] = {"bunny", "torus", "M3x10_screw"};
#define PRUSA_SHAPES "/usr/share/PrusaSlicer/shapes/"

/* Side by side with PrusaSlicer (the speed target: slice --continuous +
 * gcode in at most half PrusaSlicer's wall time) on the built-in meshes, the
 * bench's bumpy torus and PrusaSlicer's shapes, when `prusa-slicer` is installed (`make bench`
 * installs Debian's package); skipped with a message otherwise. */
static void prusa(cli_json *j, const amp_mesh *torus, int quick)
{
    size_t k, nm = quick ? 1 : amp_mesh_model_count();
    double worst = 0;
    if (system("command -v prusa-slicer >/dev/null 2>&1") != 0) {
        if (j)
            cli_json_str(j, "prusaslicer", "skipped: prusa-slicer is not installed");
        else
            printf("PrusaSlicer side by side: skipped (prusa-slicer is not installed)\n");
        return;
    }
    if (j)
        cli_json_arr(j, "prusaslicer");
    else
        printf("PrusaSlicer side by side (slice --continuous + gcode vs --export-gcode; 0.2 mm layers, 0.45 mm beads, "
               "20 %% infill):\n");
    side_by_side(j, "bumpy-torus", torus, &worst, quick);
    for (k = 0; k < nm; k++) {
        amp_mesh m;
        amp_mesh_init(&m, NULL);
        if (amp_mesh_model(amp_mesh_model_name(k), 0, &m, NULL) == AMP_OK)
            side_by_side(j, amp_mesh_model_name(k), &m, &worst, quick);
        amp_mesh_free(&m);
    }
    for (k = 0; !quick && k < sizeof prusa_shapes / sizeof *prusa_shapes; k++) {
        char path[256];
        amp_mesh m;
        amp_mesh_init(&m, NULL);
        snprintf(path, sizeof path, PRUSA_SHAPES "%s.stl", prusa_shapes[k]);
        if (amp_mesh_read_stl_file(&m, path, NULL) == AMP_OK)
            side_by_side(j, prusa_shapes[k], &m, &worst, quick);
        amp_mesh_free(&m);
    }
    if (j) {
        cli_json_close(j);
        cli_json_num(j, "continuous_vs_prusaslicer_worst", worst);
    } else
        printf("  worst ratio %.2fx (target <= 0.5x)\n", worst);
}

/* The figures of the torus run: the continuous paths and the rectilinear baseline. */
typedef struct torus_run {
    double t_slice, t_cont, t_rect, spacing;
    size_t perims;
    rect_stats rs;
    amp_contpath_stats st;
} torus_run;

/* Baseline: same perimeters and infill regions, rectilinear lines at the spacing that prints the same infill
 * length as the continuous paths (@p infill_length). */
static void rect_baseline(const amp_slices *sl, double radius, double infill_length, torus_run *t)
{
    amp_polyset isl, ins;
    double area = 0;
    size_t li, k;
    amp_polyset_init(&isl, NULL);
    amp_polyset_init(&ins, NULL);
    for (li = 0; li < sl->nlayers; li++)
        for (k = 0; k < sl->layers[li].polys.nislands; k++) {
            amp_polyset_island(&sl->layers[li].polys, k, &isl, NULL);
            amp_polyset_inset(&isl, 3 * radius, 0, &ins, NULL);
            area += amp_polyset_area(&ins);
        }
    t->spacing = infill_length > 0 ? area / infill_length : 1.0;
    for (li = 0; li < sl->nlayers; li++) {
        amp_vec2 last = amp_v2(0, 0);
        int have = 0;
        for (k = 0; k < sl->layers[li].polys.nislands; k++) {
            amp_polyset_island(&sl->layers[li].polys, k, &isl, NULL);
            amp_polyset_inset(&isl, radius, 0, &ins, NULL);
            t->perims += ins.nrings;
            amp_polyset_inset(&isl, 3 * radius, 0, &ins, NULL);
            rectilinear(&ins, t->spacing, &last, &have, &t->rs);
        }
    }
    amp_polyset_free(&isl);
    amp_polyset_free(&ins);
}

static void torus_report(cli_json *j, const amp_mesh *m, const amp_slices *sl, const amp_pathset *ps,
                         const torus_run *t)
{
    size_t starts_c = ps->npaths, starts_r = t->rs.starts + t->perims, q;
    double travel_c = 0; /* within layers, as for the baseline */
    for (q = 1; q < ps->npaths; q++) {
        amp_pvert a = amp_pathset_path_verts(ps, q - 1)[ps->paths[q - 1].n - 1], c = amp_pathset_path_verts(ps, q)[0];
        if (a.p.z == c.p.z)
            travel_c += amp_v3_dist(a.p, c.p);
    }
    if (j) {
        cli_json_int(j, "triangles", (long long)m->ntris);
        cli_json_int(j, "layers", (long long)sl->nlayers);
        cli_json_num(j, "slice_s", t->t_slice);
        cli_json_num(j, "continuous_s", t->t_cont);
        cli_json_int(j, "islands", (long long)t->st.islands);
        cli_json_int(j, "strokes", (long long)t->st.strokes);
        cli_json_int(j, "continuous_extrusion_starts", (long long)starts_c);
        cli_json_int(j, "rectilinear_extrusion_starts", (long long)starts_r);
        cli_json_num(j, "starts_ratio", (double)starts_c / (double)(starts_r ? starts_r : 1));
        cli_json_num(j, "continuous_infill_mm", t->st.infill_length);
        cli_json_num(j, "rectilinear_infill_mm", t->rs.length);
        cli_json_num(j, "rectilinear_spacing_mm", t->spacing);
        cli_json_num(j, "continuous_travel_mm", travel_c);
        cli_json_num(j, "travel_ratio", travel_c / cli_positive(t->rs.travel));
        cli_json_num(j, "rectilinear_travel_mm", t->rs.travel);
        cli_json_num(j, "rectilinear_s", t->t_rect);
    } else {
        printf("%lu triangles, %lu layers: slice %.3f s, continuous paths %.3f s (%lu islands, %lu strokes)\n",
               (unsigned long)m->ntris, (unsigned long)sl->nlayers, t->t_slice, t->t_cont,
               (unsigned long)t->st.islands, (unsigned long)t->st.strokes);
        printf("extrusion starts: continuous %lu vs rectilinear %lu (%.3fx); infill %.0f vs %.0f mm (spacing %.2f "
               "mm)\n",
               (unsigned long)starts_c, (unsigned long)starts_r, (double)starts_c / (double)(starts_r ? starts_r : 1),
               t->st.infill_length, t->rs.length, t->spacing);
        printf("travel within layers: continuous %.0f mm vs rectilinear %.0f mm (%.3fx)\n", travel_c, t->rs.travel,
               travel_c / cli_positive(t->rs.travel));
    }
}

int bench_slice(cli_json *j, int quick)
{
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts so;
    amp_contpath_opts o;
    amp_pathset ps;
    torus_run t;
    double t0;
    int rc = CLI_OK, nu = quick ? 64 : 224, nv = quick ? 32 : 224;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    memset(&t, 0, sizeof t);
    if (make_mesh(&m, nu, nv) != 0)
        return CLI_FAILED;
    so.layer = quick ? 1.0 : 0.2;
    so.first_layer = 0;
    amp_contpath_opts_default(&o, 0.25); /* no per-island verifier: the tool's first pass */
    o.cell = 4.0;
    t0 = cli_now();
    if (amp_slice_mesh(&m, &so, &sl, NULL) != AMP_OK)
        rc = CLI_FAILED;
    t.t_slice = cli_now() - t0;
    t0 = cli_now();
    if (rc == CLI_OK && amp_contpath_layers(&sl, &o, &ps, &t.st, NULL) != AMP_OK)
        rc = CLI_FAILED;
    t.t_cont = cli_now() - t0;
    t0 = cli_now();
    if (rc == CLI_OK)
        rect_baseline(&sl, o.radius, t.st.infill_length, &t);
    t.t_rect = cli_now() - t0;
    if (rc == CLI_OK) {
        torus_report(j, &m, &sl, &ps, &t);
        prusa(j, &m, quick);
    }
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
    if (rc == CLI_OK)
        rc = scaling(j, quick, 0);
    if (rc == CLI_OK)
        rc = scaling(j, quick, 1);
    return rc;
}
