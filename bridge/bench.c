/*
 * `ampath-bridge --bench [--quick] [--json]` (docs/interfaces.md §7): bridge throughput as a fraction of the serial
 * link's byte capacity, at 115200 and 250000 baud with a 2 ms printer turnaround,
 * ping-pong against the send-ahead window; and the CPU time of the bridge.
 * The printer is ampath-vprinter on a pty (modelled baud and turnaround); the
 * bridge session runs in this process. It lives with the bridge so that the geometry
 * tool `ampath` links neither the bridge nor libserialport.
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bridge.h"
#include "cli.h"


static double cpu_s(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

typedef struct result {
    double lines_s, fraction, cpu_ms_per_kline;
    long lines, bytes;
    int ok;
} result;

/* One run: returns lines/s and the share of the link's byte capacity used host->printer. @p vextra: more
   ampath-vprinter options (NULL-terminated, may be NULL). */
static result run_one(const char *job, int nlines, long baud, amp_proto_window mode, const char *const *vextra,
                      int wire)
{
    char vp[PATH_MAX], link[128], bstr[32], why[256];
    br_cfg cfg;
    br_session *s = calloc(1, sizeof *s);
    result r;
    pid_t pid;
    double t0, c0, el;
    long b0;
    int i, st;
    memset(&r, 0, sizeof r);
    if (!s)
        return r;
    if (cli_program("AMP_VPRINTER", "ampath-vprinter", "tools", vp, sizeof vp) != 0) {
        free(s);
        return r;
    }
    snprintf(link, sizeof link, "/tmp/ampath-bench-%ld.pty", (long)getpid());
    snprintf(bstr, sizeof bstr, "%ld", baud);
    unlink(link);
    pid = fork();
    if (pid == 0) {
        const char *argv[32] = {"ampath-vprinter", "--link", link, "--baud", bstr, "--turnaround", "2",
                                "--bufsize", "8", "--rx-bytes", "128"};
        int a = 11;
        if (!wire) {
            /* the pty's own pace: no modelled wire */
            memmove(argv + 3, argv + 5, 6 * sizeof argv[0]);
            a = 9;
        }
        while (vextra && *vextra && a < 31)
            argv[a++] = *vextra++;
        argv[a] = NULL;
        freopen("/dev/null", "w", stderr);
        execv(vp, (char *const *)argv);
        _exit(127);
    }
    for (i = 0; i < 300 && access(link, F_OK) != 0; i++)
        usleep(10000);
    br_cfg_default(&cfg);
    cfg.device = link;
    cfg.baud = baud;
    cfg.mode = mode;
    cfg.window = mode == AMP_PROTO_PINGPONG ? 1 : 8;
    cfg.bufsize = 8;
    cfg.boot_ms = 200;
    cfg.quiet = 1;
    if (br_session_open(s, &cfg, why, sizeof why) == 0 && br_session_start_job(s, job, 1, why, sizeof why) == 0) {
        /* the clock starts with the first job line: the handshake is not throughput */
        while (s->stop == BR_RUNNING && s->p.state != AMP_PROTO_RUNNING)
            br_session_step(s, NULL, 0, 50);
        t0 = cli_now();
        c0 = cpu_s();
        b0 = s->bytes_out;
        while (s->stop == BR_RUNNING)
            br_session_step(s, NULL, 0, 100);
        el = cli_now() - t0;
        r.ok = s->stop == BR_DONE && s->acked_moves == nlines && s->p.n_timeouts == 0;
        r.lines = s->acked_moves;
        r.bytes = s->bytes_out - b0; /* every byte written to the link while the job ran */
        r.lines_s = (double)r.lines / el;
        r.fraction = ((double)r.bytes / el) / ((double)baud / 10.0);
        r.cpu_ms_per_kline = 1e6 * (cpu_s() - c0) / (double)(r.lines > 0 ? r.lines : 1);
        br_session_close(s);
    }
    free(s);
    kill(pid, SIGTERM);
    waitpid(pid, &st, 0);
    unlink(link);
    return r;
}

/* Every dialect without stalls: every dialect with 0.05 % of the bytes corrupted both ways against the clean run (window of 8 or
   ADVANCED_OK, 2 ms per command); the dialect is learned at the handshake, never given. The pty runs at its
   own pace here: the modelled wire makes the virtual printer handle one error per turn of its loop, which on
   a loaded machine stretches each error burst far beyond what a printer takes (docs/bridge.md, "Limits"). */
static int bench_bridge_noise(cli_json *j, const char *job, int nlines)
{
    static const char *const dia[4][6] = {{"--dialect", "2.1", NULL},
                                          {"--dialect", "prusa", NULL},
                                          {"--dialect", "rs", NULL},
                                          {"--dialect", "2.0", "--advanced-ok", NULL}};
    static const char *const names[4] = {"marlin 2.1 (ok after Resend)", "prusa (Resend, no ok)", "rs N (no ok)",
                                         "ADVANCED_OK"};
    int d, rc = CLI_OK;
    if (j)
        cli_json_arr(j, "bridge_noise");
    for (d = 0; d < 4; d++) {
        const char *noisy[10];
        amp_proto_window mode = d == 3 ? AMP_PROTO_ADVANCED : AMP_PROTO_FIXED;
        int a = 0, b;
        result clean, noise;
        for (b = 0; dia[d][b]; b++)
            noisy[a++] = dia[d][b];
        noisy[a++] = "--corrupt-in";
        noisy[a++] = "0.0005";
        noisy[a++] = "--corrupt-out";
        noisy[a++] = "0.0005";
        noisy[a++] = "--seed";
        noisy[a++] = "7";
        noisy[a] = NULL;
        clean = run_one(job, nlines, 250000, mode, dia[d], 0);
        noise = run_one(job, nlines, 250000, mode, noisy, 0);
        if (!clean.ok || !noise.ok)
            rc = CLI_FAILED;
        if (j) {
            cli_json_obj(j, NULL);
            cli_json_str(j, "dialect", names[d]);
            cli_json_num(j, "clean_lines_per_s", clean.lines_s);
            cli_json_num(j, "noisy_lines_per_s", noise.lines_s);
            cli_json_num(j, "ratio", noise.lines_s / (clean.lines_s > 0 ? clean.lines_s : 1e-9));
            cli_json_bool(j, "all_acknowledged_no_timeout", clean.ok && noise.ok);
            cli_json_close(j);
        } else {
            printf("bridge pty, 0.05 %% corrupted bytes both ways, %-28s: %.0f lines/s vs %.0f clean, "
                   "ratio %.2f (target >= 0.80)%s\n",
                   names[d], noise.lines_s, clean.lines_s, noise.lines_s / (clean.lines_s > 0 ? clean.lines_s : 1e-9),
                   clean.ok && noise.ok ? "" : " (NOT all acknowledged, or a timeout)");
        }
    }
    if (j)
        cli_json_close(j);
    return rc;
}

static int measure(cli_json *j, int quick)
{
    int nlines = quick ? 120 : 600, i, k, rc = CLI_OK;
    const long bauds[2] = {115200, 250000};
    const char *job = "/tmp/ampath-bench-bridge.gcode";
    FILE *f = fopen(job, "w");
    if (!f)
        return CLI_FAILED;
    for (i = 1; i <= nlines; i++)
        fprintf(f, "G1 X%.3f Y%.3f E%.5f F1800\n", 100 + 30 * ((i * 37) % 100) / 100.0, 80 + (i % 50) * 0.4,
                0.0123 * i);
    fclose(f);
    if (j)
        cli_json_arr(j, "bridge");
    for (k = 0; k < 2; k++) {
        result pp = run_one(job, nlines, bauds[k], AMP_PROTO_PINGPONG, NULL, 1);
        result win = run_one(job, nlines, bauds[k], AMP_PROTO_FIXED, NULL, 1);
        if (!pp.ok || !win.ok)
            rc = CLI_FAILED;
        if (j) {
            cli_json_obj(j, NULL);
            cli_json_int(j, "baud", bauds[k]);
            cli_json_num(j, "turnaround_s", 0.002);
            cli_json_int(j, "lines", nlines);
            cli_json_num(j, "pingpong_lines_per_s", pp.lines_s);
            cli_json_num(j, "pingpong_link_fraction", pp.fraction);
            cli_json_num(j, "window_lines_per_s", win.lines_s);
            cli_json_num(j, "window_link_fraction", win.fraction);
            cli_json_num(j, "window_over_pingpong", win.lines_s / (pp.lines_s > 0 ? pp.lines_s : 1e-9));
            cli_json_num(j, "bridge_cpu_ms_per_1000_lines", win.cpu_ms_per_kline);
            /* upper bounds: the printer takes 2 ms per command, the link 10 bits per byte */
            cli_json_num(j, "printer_bound_lines_per_s", 500.0);
            cli_json_num(j, "link_bound_lines_per_s", (double)bauds[k] / 10.0 / (win.lines > 0 ? (double)win.bytes / (double)win.lines : 1));
            cli_json_bool(j, "all_acknowledged", pp.ok && win.ok);
            cli_json_close(j);
        } else {
            printf("bridge %6ld baud, 2 ms turnaround, %d lines: ping-pong %.0f lines/s (%.0f %% of the link), "
                   "window of 8 %.0f lines/s (%.0f %% of the link), %.2fx (bounds: printer 500, link %.0f lines/s); "
                   "bridge CPU %.1f ms per 1000 lines%s\n",
                   bauds[k], nlines, pp.lines_s, 100 * pp.fraction, win.lines_s, 100 * win.fraction,
                   win.lines_s / (pp.lines_s > 0 ? pp.lines_s : 1e-9),
                   (double)bauds[k] / 10.0 / (win.lines > 0 ? (double)win.bytes / (double)win.lines : 1), win.cpu_ms_per_kline,
                   pp.ok && win.ok ? "" : " (NOT all acknowledged)");
        }
    }
    if (j)
        cli_json_close(j);
    if (bench_bridge_noise(j, job, nlines) != CLI_OK)
        rc = CLI_FAILED;
    unlink(job);
    return rc;
}

int br_bench_main(int argc, char **argv)
{
    int json = 0, quick = 0, npos = 0, rc;
    const char *pos[1];
    cli_json j;
    cli_opt opts[] = {{"json", CLI_FLAG, &json, 0}, {"quick", CLI_FLAG, &quick, 0}, {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("bridge --bench", argc, argv, opts, pos, 0, 0, &npos);
    if (rc != CLI_OK)
        return rc;
    /* `ampath bench bridge` runs this and shows its output as its own part (tools/bench_bridge.c) */
    if (json)
        cli_json_begin(&j, stdout);
    rc = measure(json ? &j : NULL, quick);
    if (json)
        cli_json_end(&j);
    return rc;
}
