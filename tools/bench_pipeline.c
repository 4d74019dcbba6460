/*
 * Benchmark (docs/interfaces.md §7): the full helix pipeline of `make demo` in one process —
 * cover ([P1 §4.1]) → order (§5.1) → MDR (§5.2) → support (§5.3) → G-code
 * (docs/interfaces.md §5), then `check` — stage by stage with time and peak memory, at eps 1
 * (the demo) and eps 0.5, on 1 and 2 threads; the travel figures of the G-code
 * with the re-sequenced order and, as the same-run baseline, Algorithm 2's own order; and the
 * planar pipeline on the same solid (slice → continuous strokes → G-code) as the
 * baseline of what a layer-based job of the same part costs. Each of
 * the speed targets (README "Speed and memory") is printed with its figure and "met" / "not met".
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "checkers.h"
#include "cli.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* ---- a counting allocator: peak of the bytes live through the caller's allocator ---- */

typedef struct counter {
    size_t live, peak;
    double cpu0; /* process CPU time at the stage's start (cpu_now) */
} counter;

typedef union hdr {
    size_t size;
    long double ld; /* C99 has no max_align_t: these keep the payload aligned for any type */
    void *p;
    long long ll;
} hdr;

static void count_add(counter *c, size_t add, size_t sub)
{
#pragma omp critical(bench_counter)
    {
        c->live = c->live + add - sub;
        if (c->live > c->peak)
            c->peak = c->live;
    }
}

static void *cnt_alloc(void *user, size_t size)
{
    hdr *h = malloc(sizeof *h + size);
    if (!h)
        return NULL;
    h->size = size;
    count_add(user, size, 0);
    return h + 1;
}

static void *cnt_realloc(void *user, void *ptr, size_t size)
{
    hdr *h = ptr ? (hdr *)ptr - 1 : NULL, *n;
    size_t old = h ? h->size : 0;
    n = realloc(h, sizeof *n + size);
    if (!n)
        return NULL;
    n->size = size;
    count_add(user, size, old);
    return n + 1;
}

static void cnt_free(void *user, void *ptr)
{
    hdr *h = ptr ? (hdr *)ptr - 1 : NULL;
    if (!h)
        return;
    count_add(user, 0, h->size);
    free(h);
}

/* Counts G-code bytes and hashes them (FNV-1a), so that runs can be compared without storing the file. */
typedef struct gsink {
    size_t bytes;
    uint64_t hash;
} gsink;

static amp_status count_sink(void *user, const char *data, size_t len)
{
    gsink *g = user;
    size_t i;
    for (i = 0; i < len; i++)
        g->hash = (g->hash ^ (unsigned char)data[i]) * 0x100000001b3ULL;
    g->bytes += len;
    return AMP_OK;
}

/* The G-code stage as `ampath gcode -o FILE` runs it: the job once, body then header (the hash covers them
 * in that order, the same for every thread count). */
static int gcode_once(const amp_pathset *ps, const amp_gcode_opts *go, gsink *g, amp_gcode_stats *gs)
{
    static amp_gcode_iter it;
    return amp_gcode_iter_init_body(&it, ps, go, NULL) == AMP_OK &&
           amp_gcode_iter_write(&it, count_sink, g, gs, NULL) == AMP_OK &&
           amp_gcode_iter_header(&it, count_sink, g, NULL) == AMP_OK;
}

enum { ST_COVER, ST_ORDER, ST_MDR, ST_SUPPORT, ST_GCODE, ST_CHECK, NSTAGES };
static const char *const stage_name[NSTAGES] = {"cover", "order", "mdr", "support", "gcode", "check"};

typedef struct vrun {
    double t[NSTAGES];
    double cpu[NSTAGES]; /* process CPU time of the stage: on one thread, its work whatever the load */
    size_t peak[NSTAGES]; /* bytes live at the stage's peak (what earlier stages left included) */
    size_t peak_all;      /* over the pipeline, check excluded */
    size_t fragments, subdivisions, paths;
    int check_ok;
    gsink g;
    amp_gcode_stats gs;
} vrun;

static double pipeline_s(const vrun *r) { return r->t[ST_COVER] + r->t[ST_ORDER] + r->t[ST_MDR] + r->t[ST_SUPPORT] + r->t[ST_GCODE]; }

/* The independent checks of `ampath check` (gouging, coverage of the trivariate) on the final paths. */
static int run_check(const amp_pathset *ps, double eps)
{
    check_ctx c;
    cli_json j;
    FILE *null = fopen("/dev/null", "w");
    int ok;
    if (!null)
        return 0;
    memset(&c, 0, sizeof c);
    c.paths_file = "bench";
    c.ps = ps;
    c.trivariate = "helix";
    amp_head_default(&c.head);
    c.eps = eps;
    c.eps_given = 1;
    c.samples = 20000;
    c.tol = 1e-6;
    cli_json_begin(&j, null);
    cli_json_obj(&j, "gouge");
    ok = check_gouge(&c, &j) == CLI_OK;
    cli_json_close(&j);
    cli_json_obj(&j, "coverage");
    ok = check_coverage(&c, &j) == CLI_OK && ok;
    cli_json_end(&j);
    fclose(null);
    return ok;
}

/* User + system CPU time of the process, s. */
static double cpu_now(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

static void stage_begin(counter *c, double *t0)
{
    c->peak = c->live;
    c->cpu0 = cpu_now();
    *t0 = cli_now();
}

static void stage_end(counter *c, vrun *r, int s, double t0)
{
    r->t[s] = cli_now() - t0;
    r->cpu[s] = cpu_now() - c->cpu0;
    r->peak[s] = c->peak;
    if (s != ST_CHECK && c->peak > r->peak_all)
        r->peak_all = c->peak;
}

/* cover → order → mdr → support → gcode (→ check) of the helix at @p eps on @p threads threads; @p travel_z
 * is the order's re-sequencing weight (0: Algorithm 2's own order, the travel baseline). */
static int volumetric(double eps, double travel_z, int threads, int check, vrun *r)
{
    counter cnt = {0, 0, 0.0};
    amp_allocator al = {cnt_alloc, cnt_realloc, cnt_free, NULL};
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
    al.user = &cnt;
    memset(r, 0, sizeof *r);
    r->g.hash = 0xcbf29ce484222325ULL;
#ifdef _OPENMP
    omp_set_num_threads(threads);
#else
    (void)threads;
#endif
    amp_spline_init(&v);
    amp_pathset_init(&a, &al);
    amp_pathset_init(&b, &al);
    amp_mesh_init(&m, &al);
    amp_cover_opts_default(&co);
    co.eps = eps;
    co.dir = 0; /* curves along the helix, as the demo */
    amp_order_opts_default(&oo);
    oo.travel_z_weight = travel_z;
    amp_mdr_opts_default(&mo, 0.5);
    amp_support_opts_default(&so);
    so.find_unheld = amp_check_hold_runs; /* as `ampath support` */
    amp_gcode_opts_default(&go, AMP_FLAVOR_MARLIN);
    stage_begin(&cnt, &t0);
    ok = amp_trivariate_model("helix", &al, &v, NULL) == AMP_OK && amp_cover_trivariate(&v, &co, &a, NULL, NULL) == AMP_OK;
    stage_end(&cnt, r, ST_COVER, t0);
    stage_begin(&cnt, &t0);
    ok = ok && amp_order(&a, &oo, &b, &ost, NULL) == AMP_OK;
    stage_end(&cnt, r, ST_ORDER, t0);
    amp_pathset_clear(&a);
    stage_begin(&cnt, &t0);
    ok = ok && amp_mdr(&b, &mo, &a, NULL, NULL) == AMP_OK;
    stage_end(&cnt, r, ST_MDR, t0);
    amp_pathset_clear(&b);
    stage_begin(&cnt, &t0);
    ok = ok && amp_mesh_from_trivariate(&m, &v, 0, NULL) == AMP_OK && amp_bvh_build(&bvh, &m, NULL) == AMP_OK &&
         amp_support(&a, bvh, &so, &b, NULL, NULL) == AMP_OK;
    stage_end(&cnt, r, ST_SUPPORT, t0);
    amp_bvh_free(bvh);
    amp_mesh_free(&m);
    amp_pathset_clear(&a);
    stage_begin(&cnt, &t0);
    ok = ok && gcode_once(&b, &go, &r->g, &r->gs);
    stage_end(&cnt, r, ST_GCODE, t0);
    if (ok && check) {
        stage_begin(&cnt, &t0);
        r->check_ok = run_check(&b, eps);
        stage_end(&cnt, r, ST_CHECK, t0);
    }
    r->paths = b.npaths;
    r->fragments = ost.fragments;
    r->subdivisions = ost.subdivisions;
    amp_pathset_free(&a);
    amp_pathset_free(&b);
    amp_spline_free(&v);
#ifdef _OPENMP
    omp_set_num_threads(omp_get_num_procs());
#endif
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
    gsink g = {0, 0};
    double t0 = cli_now();
    int ok;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    so.layer = layer;
    so.first_layer = 0;
    amp_contpath_opts_default(&co, 0.5); /* no per-island verifier: the tool's first pass */
    amp_gcode_opts_default(&go, AMP_FLAVOR_MARLIN);
    ok = amp_mesh_model("helix", 0, &m, NULL) == AMP_OK && amp_slice_mesh(&m, &so, &sl, NULL) == AMP_OK &&
         amp_contpath_layers(&sl, &co, &ps, &st, NULL) == AMP_OK &&
         amp_gcode_write(&ps, &go, count_sink, &g, NULL, NULL) == AMP_OK;
    *t = cli_now() - t0;
    *strokes = ok ? st.strokes : 0;
    *bytes = g.bytes;
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
    return ok;
}

/* Subdivisions of the plain greedy Algorithm 2 on the helix covering at @p eps (the improvements' baseline). */
static size_t greedy_subdivisions(double eps)
{
    amp_spline v;
    amp_cover_opts co;
    amp_order_opts oo;
    amp_order_stats ost;
    amp_pathset a, b;
    size_t n = 0;
    amp_spline_init(&v);
    amp_pathset_init(&a, NULL);
    amp_pathset_init(&b, NULL);
    amp_cover_opts_default(&co);
    co.eps = eps;
    co.dir = 0;
    amp_order_opts_default(&oo);
    oo.improve = 0;
    if (amp_trivariate_model("helix", NULL, &v, NULL) == AMP_OK && amp_cover_trivariate(&v, &co, &a, NULL, NULL) == AMP_OK &&
        amp_order(&a, &oo, &b, &ost, NULL) == AMP_OK)
        n = ost.subdivisions;
    amp_pathset_free(&a);
    amp_pathset_free(&b);
    amp_spline_free(&v);
    return n;
}

static void machine(char *cpu, size_t cap, long *nproc)
{
    FILE *f = fopen("/proc/cpuinfo", "r");
    char line[512];
    snprintf(cpu, cap, "unknown CPU");
    while (f && fgets(line, sizeof line, f)) {
        char *c = strchr(line, ':');
        if (strncmp(line, "model name", 10) == 0 && c) {
            snprintf(cpu, cap, "%s", c + 2);
            cpu[strcspn(cpu, "\n")] = 0;
            break;
        }
    }
    if (f)
        fclose(f);
#ifdef _OPENMP
    *nproc = omp_get_num_procs();
#else
    *nproc = 1;
#endif
}

static void print_run(const char *label, double eps, const vrun *r)
{
    int s;
    printf("%s eps %.1f mm, %lu fragments: pipeline %.2f s, peak %.1f MB =", label, eps, (unsigned long)r->fragments,
           pipeline_s(r), (double)r->peak_all / 1e6);
    for (s = 0; s < ST_CHECK; s++)
        printf("%s %s %.2f s / %.1f MB", s ? " +" : "", stage_name[s], r->t[s], (double)r->peak[s] / 1e6);
    if (r->t[ST_CHECK] > 0)
        printf("; check %.2f s / %.1f MB (%s)", r->t[ST_CHECK], (double)r->peak[ST_CHECK] / 1e6,
               r->check_ok ? "passed" : "FAILED");
    printf("\n");
}

static void json_run(cli_json *j, const char *key, double eps, const vrun *r)
{
    int s;
    char k[64];
    cli_json_obj(j, key);
    cli_json_num(j, "eps", eps);
    cli_json_int(j, "fragments", (long long)r->fragments);
    for (s = 0; s < NSTAGES; s++) {
        snprintf(k, sizeof k, "%s_s", stage_name[s]);
        cli_json_num(j, k, r->t[s]);
        snprintf(k, sizeof k, "%s_peak_mb", stage_name[s]);
        cli_json_num(j, k, (double)r->peak[s] / 1e6);
    }
    cli_json_num(j, "pipeline_s", pipeline_s(r));
    cli_json_num(j, "peak_mb", (double)r->peak_all / 1e6);
    cli_json_int(j, "subdivisions", (long long)r->subdivisions);
    cli_json_int(j, "paths", (long long)r->paths);
    cli_json_num(j, "print_length_mm", r->gs.print_length);
    cli_json_num(j, "travel_length_mm", r->gs.travel_length);
    cli_json_num(j, "travel_over_extrusion", r->gs.travel_length / fmax(r->gs.print_length, 1e-9));
    cli_json_num(j, "travel_time_share", r->gs.travel_time / fmax(r->gs.time, 1e-9));
    cli_json_int(j, "retractions", (long long)r->gs.retractions);
    cli_json_int(j, "gcode_bytes", (long long)r->g.bytes);
    cli_json_close(j);
}

/* Per stage CPU time of a 1-thread run: on a loaded machine the wall clock also counts other jobs' time. */
static double pipeline_cpu(const vrun *r) { return r->cpu[ST_COVER] + r->cpu[ST_ORDER] + r->cpu[ST_MDR] + r->cpu[ST_SUPPORT] + r->cpu[ST_GCODE]; }

static void stage_cpu(cli_json *j, const char *key, const char *label, const vrun *r)
{
    int s;
    char k[64];
    if (j) {
        cli_json_obj(j, key);
        for (s = 0; s < NSTAGES; s++) {
            snprintf(k, sizeof k, "%s_s", stage_name[s]);
            cli_json_num(j, k, r->cpu[s]);
        }
        cli_json_num(j, "pipeline_s", pipeline_cpu(r));
        cli_json_close(j);
        return;
    }
    printf("  CPU time, %s: pipeline %.2f s =", label, pipeline_cpu(r));
    for (s = 0; s < ST_CHECK; s++)
        printf("%s %s %.2f s", s ? " +" : "", stage_name[s], r->cpu[s]);
    if (r->t[ST_CHECK] > 0)
        printf("; check %.2f s", r->cpu[ST_CHECK]);
    printf("\n");
}

/* Per stage: how much faster 2 threads run it than 1 (the stages' share of the pipeline's thread speed-up). */
static void stage_speedups(cli_json *j, const vrun *one, const vrun *two)
{
    int s;
    char k[64];
    if (j)
        cli_json_obj(j, "stage_speedup_2_threads");
    else
        printf("  2 threads / 1 thread per stage:");
    for (s = 0; s < ST_CHECK; s++) {
        double r = one->t[s] / fmax(two->t[s], 1e-9);
        if (j) {
            snprintf(k, sizeof k, "%s", stage_name[s]);
            cli_json_num(j, k, r);
        } else {
            printf("%s %s %.2fx", s ? "," : "", stage_name[s], r);
        }
    }
    if (j)
        cli_json_close(j);
    else
        printf("\n");
}

static void target(cli_json *j, const char *key, const char *text, double figure, double limit, int below, const char *unit)
{
    int met = below ? figure <= limit : figure >= limit;
    if (j) {
        cli_json_obj(j, key);
        cli_json_num(j, "figure", figure);
        cli_json_num(j, "limit", limit);
        cli_json_bool(j, "met", met);
        cli_json_close(j);
    } else {
        printf("  target %-52s %8.3f %-4s (%s %g) %s\n", text, figure, unit, below ? "<=" : ">=", limit,
               met ? "met" : "NOT MET");
    }
}

/* Every run of the benchmark and the figures derived from them. */
typedef struct pipeline_figs {
    vrun d, dn, f1, f2; /* demo, demo without re-sequencing, fine on 1 and on 2 threads */
    double e1, e2, layer, t_planar, xt, xm, ratio;
    size_t strokes, pbytes, g1, g2;
    long nproc;
    char cpu[256];
    struct rusage ru;
    int quick;
} pipeline_figs;

/* The runs, with one progress bar over them all; 0 when one fails (the bar left as it was). */
static int pipeline_runs(pipeline_figs *p)
{
    cli_progress bar;
    machine(p->cpu, sizeof p->cpu, &p->nproc);
    cli_progress_begin(&bar, "bench pipeline");
    if (!volumetric(p->e1, AMP_ORDER_TRAVEL_Z_WEIGHT, 1, 1, &p->d))
        return 0;
    cli_progress_update(&bar, 0.15);
    if (!volumetric(p->e1, 0.0, 1, 0, &p->dn))
        return 0;
    cli_progress_update(&bar, 0.25);
    p->g1 = greedy_subdivisions(p->e1);
    cli_progress_update(&bar, 0.3);
    if (!volumetric(p->e2, AMP_ORDER_TRAVEL_Z_WEIGHT, 1, 0, &p->f1))
        return 0;
    cli_progress_update(&bar, 0.55);
    if (!volumetric(p->e2, AMP_ORDER_TRAVEL_Z_WEIGHT, 2, 0, &p->f2))
        return 0;
    cli_progress_update(&bar, 0.8);
    p->g2 = greedy_subdivisions(p->e2);
    if (!planar(p->layer, &p->t_planar, &p->strokes, &p->pbytes))
        return 0;
    cli_progress_end(&bar);
    getrusage(RUSAGE_SELF, &p->ru);
    /* growth exponents: log(time ratio) / log(fragment ratio) */
    p->ratio = (double)p->f1.fragments / (double)(p->d.fragments ? p->d.fragments : 1);
    p->xt = log(pipeline_s(&p->f1) / fmax(pipeline_s(&p->d), 1e-9)) / log(p->ratio);
    p->xm = log((double)p->f1.peak_all / fmax((double)p->d.peak_all, 1.0)) / log(p->ratio);
    return 1;
}

/* The figures into the benchmark's JSON object; leaves "targets" open for pipeline_targets. */
static void pipeline_json(cli_json *j, const pipeline_figs *p)
{
    cli_json_str(j, "cpu", p->cpu);
    cli_json_int(j, "nproc", p->nproc);
    json_run(j, "demo", p->e1, &p->d);
    json_run(j, "demo_without_resequencing", p->e1, &p->dn);
    json_run(j, "fine", p->e2, &p->f1);
    json_run(j, "fine_2_threads", p->e2, &p->f2);
    stage_speedups(j, &p->f1, &p->f2);
    stage_cpu(j, "demo_cpu", NULL, &p->d);
    stage_cpu(j, "fine_cpu", NULL, &p->f1);
    cli_json_int(j, "greedy_subdivisions_demo", (long long)p->g1);
    cli_json_int(j, "greedy_subdivisions_fine", (long long)p->g2);
    cli_json_num(j, "time_exponent", p->xt);
    cli_json_num(j, "memory_exponent", p->xm);
    cli_json_bool(j, "threads_identical", p->f1.g.hash == p->f2.g.hash && p->f1.g.bytes == p->f2.g.bytes);
    cli_json_num(j, "planar_s", p->t_planar);
    cli_json_int(j, "planar_strokes", (long long)p->strokes);
    cli_json_num(j, "max_rss_mb", (double)p->ru.ru_maxrss / 1e3);
    cli_json_obj(j, "targets");
}

static void pipeline_text(const pipeline_figs *p)
{
    const vrun *d = &p->d, *dn = &p->dn, *f1 = &p->f1, *f2 = &p->f2;
    printf("machine: %s, %ld processors; times are wall clock, memory is the peak of the bytes live through the "
           "caller's allocator (process max RSS %.0f MB)\n",
           p->cpu, p->nproc, (double)p->ru.ru_maxrss / 1e3);
    print_run("demo helix, 1 thread,", p->e1, d);
    printf("  travel %.1f m for %.1f m of extrusion = %.2fx, travel %.0f %% of the estimated %.0f s, %lu retractions; "
           "baseline, Algorithm 2's own order (no re-sequencing, same run): %.2fx, %.0f %%, %lu subdivisions\n",
           d->gs.travel_length / 1e3, d->gs.print_length / 1e3, d->gs.travel_length / fmax(d->gs.print_length, 1e-9),
           100.0 * d->gs.travel_time / fmax(d->gs.time, 1e-9), d->gs.time, (unsigned long)d->gs.retractions,
           dn->gs.travel_length / fmax(dn->gs.print_length, 1e-9),
           100.0 * dn->gs.travel_time / fmax(dn->gs.time, 1e-9), (unsigned long)dn->subdivisions);
    printf("  subdivisions %lu, plain greedy %lu\n", (unsigned long)d->subdivisions, (unsigned long)p->g1);
    print_run("fine helix, 1 thread,", p->e2, f1);
    printf("  travel %.2fx of extrusion, %.0f %% of the time; subdivisions %lu, plain greedy %lu\n",
           f1->gs.travel_length / fmax(f1->gs.print_length, 1e-9),
           100.0 * f1->gs.travel_time / fmax(f1->gs.time, 1e-9), (unsigned long)f1->subdivisions,
           (unsigned long)p->g2);
    print_run("fine helix, 2 threads,", p->e2, f2);
    stage_speedups(NULL, f1, f2);
    stage_cpu(NULL, "", "demo, 1 thread", d);
    stage_cpu(NULL, "", "eps 0.5, 1 thread", f1);
    printf("  eps %.1f -> %.1f: fragments x%.2f, pipeline time x%.2f (exponent %.2f), peak memory x%.2f (exponent "
           "%.2f); 2 threads %.2fx faster, G-code %s\n",
           p->e1, p->e2, p->ratio, pipeline_s(f1) / fmax(pipeline_s(d), 1e-9), p->xt,
           (double)f1->peak_all / fmax((double)d->peak_all, 1.0), p->xm, pipeline_s(f1) / fmax(pipeline_s(f2), 1e-9),
           f1->g.hash == f2->g.hash && f1->g.bytes == f2->g.bytes ? "byte-identical" : "DIFFERS");
    printf("baseline, planar continuous pipeline on the helix mesh (layer %.1f mm): %.2f s, %lu strokes, %.1f MB; "
           "volumetric / planar = %.2fx\n",
           p->layer, p->t_planar, (unsigned long)p->strokes, (double)p->pbytes / 1e6,
           pipeline_s(d) / fmax(p->t_planar, 1e-9));
    printf("speed and travel targets%s:\n", p->quick ? " (--quick: coarser sizes, not the targets' own)" : "");
}

/* Each speed and travel target with its figure, "met" or "not met" (README "Speed and memory"). */
static void pipeline_targets(cli_json *j, const pipeline_figs *p)
{
    const vrun *d = &p->d, *dn = &p->dn, *f1 = &p->f1, *f2 = &p->f2;
    target(j, "demo_pipeline_s", "demo pipeline time (s), 1 thread", pipeline_s(d), 1.0, 1, "s");
    target(j, "demo_check_s", "demo check time (s), 1 thread", d->t[ST_CHECK], 0.5, 1, "s");
    target(j, "demo_pipeline_cpu_s", "demo pipeline CPU time (s), 1 thread", pipeline_cpu(d), 1.0, 1, "s");
    target(j, "demo_check_cpu_s", "demo check CPU time (s), 1 thread", d->cpu[ST_CHECK], 0.5, 1, "s");
    target(j, "fine_pipeline_s", "eps 0.5 pipeline time (s), 1 thread", pipeline_s(f1), 8.0, 1, "s");
    target(j, "fine_pipeline_cpu_s", "eps 0.5 pipeline CPU time (s), 1 thread", pipeline_cpu(f1), 8.0, 1, "s");
    target(j, "fine_peak_mb", "eps 0.5 pipeline peak memory (MB)", (double)f1->peak_all / 1e6, 300.0, 1, "MB");
    target(j, "time_exponent", "time growth exponent eps 1 -> 0.5", p->xt, 1.1, 1, "");
    target(j, "memory_exponent", "memory growth exponent eps 1 -> 0.5", p->xm, 1.1, 1, "");
    target(j, "thread_speedup", "eps 0.5 pipeline speed-up on 2 threads", pipeline_s(f1) / fmax(pipeline_s(f2), 1e-9),
           1.6, 0, "x");
    target(j, "threads_identical", "G-code identical on 1 and 2 threads (1 = yes)",
           f1->g.hash == f2->g.hash && f1->g.bytes == f2->g.bytes, 1.0, 0, "");
    target(j, "improved_vs_greedy_demo", "subdivisions improved - greedy, demo",
           (double)d->subdivisions - (double)p->g1, 0.0, 1, "");
    target(j, "improved_vs_greedy_fine", "subdivisions improved - greedy, eps 0.5",
           (double)f1->subdivisions - (double)p->g2, 0.0, 1, "");
    target(j, "demo_subdivisions", "demo subdivisions (before the nearest choice: 4813)", (double)d->subdivisions,
           4813.0, 1, "");
    target(j, "travel_over_extrusion", "demo travel / extrusion length",
           d->gs.travel_length / fmax(d->gs.print_length, 1e-9), 0.5, 1, "x");
    target(j, "travel_time_share", "demo travel share of the estimated time",
           d->gs.travel_time / fmax(d->gs.time, 1e-9), 0.3, 1, "");
    target(j, "travel_over_extrusion_baseline", "baseline (Alg. 2's own order): travel / extrusion",
           dn->gs.travel_length / fmax(dn->gs.print_length, 1e-9), 0.5, 1, "x");
    target(j, "travel_time_share_baseline", "baseline (Alg. 2's own order): travel share of time",
           dn->gs.travel_time / fmax(dn->gs.time, 1e-9), 0.3, 1, "");
    target(j, "subdivisions_vs_baseline", "demo subdivisions - baseline's (never more cuts)",
           (double)d->subdivisions - (double)dn->subdivisions, 0.0, 1, "");
}

int bench_pipeline(cli_json *j, int quick)
{
    pipeline_figs p;
    memset(&p, 0, sizeof p);
    p.quick = quick;
    p.e1 = quick ? 2.0 : 1.0;
    p.e2 = quick ? 1.0 : 0.5;
    p.layer = quick ? 1.0 : 0.5;
    if (!pipeline_runs(&p))
        return CLI_FAILED;
    if (j)
        pipeline_json(j, &p);
    else
        pipeline_text(&p);
    pipeline_targets(j, &p);
    if (j)
        cli_json_close(j);
    return p.d.check_ok ? CLI_OK : CLI_FAILED;
}
