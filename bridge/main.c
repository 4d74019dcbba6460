/*
 * ampath-bridge — stream a job to a Marlin or Klipper printer (docs/interfaces.md §8).
 * One-shot: `ampath-bridge DEVICE JOB [options]`; daemon: `--daemon` with a
 * Unix control socket (mode 0600), in daemon.c. This file: options and the
 * one-shot run. See docs/bridge.md and ampath-bridge(1).
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h" /* numbers validated as ampath and ampath-vprinter do */
#include "daemon.h"

static const char usage[] =
    "usage: ampath-bridge DEVICE [JOB] [options]\n"
    "       ampath-bridge --bench [--quick] [--json]   throughput against the virtual printer (make bench)\n"
    "Streams JOB (.gcode, or .amp converted with the G-code writer) to the printer on DEVICE\n"
    "(a serial port, a /dev/serial/by-id link, or a pty such as Klipper's /tmp/printer).\n"
    "  --baud N             link rate (default 115200; 250000 and other rates work)\n"
    "  --flavor F           marlin | klipper | auto (asks M115) (default marlin, or the --printer profile's)\n"
    "  --window W           pingpong | N lines in flight | advanced (ADVANCED_OK) (default 4; klipper 16)\n"
    "  --bufsize N          printer command queue, Marlin BUFSIZE (default 4)\n"
    "  --rx-bytes N         bytes the printer's serial RX buffer holds (default 127: RX_BUFFER_SIZE 128 on AVR)\n"
    "  --no-resend-ok       the firmware sends no ok after 'Resend:' (default: learned at the handshake)\n"
    "  --resend-ok          the firmware sends an ok after 'Resend:' (no learning either)\n"
    "  --ready-timeout S    wait at most S seconds for the printer to become ready (default 60)\n"
    "  --on-error E         stop (default): a firmware error (Klipper '!!', Marlin 'Error:' outside the\n"
    "                       resend protocol) stops the job, exit 1; continue: report and count it, go on\n"
    "  --timeout S          silence (no ok, busy or temperature) before a probe, seconds (default 10)\n"
"  --settle-ms MS       after a resend request, wait at most MS (plus the wire time of the lines sent\n"
    "                       ahead and twice the printer's reply time) for their echoes (default 10)\n"
    "  --boot-wait S        wait for the 'start' banner before the handshake, seconds (default 3)\n"
    "  --reconnect S        how long to wait for an unplugged device to return, seconds (default 60);\n"
    "                       then it learns the last line the printer received (nothing runs),\n"
    "                       M110 to it and goes on: nothing runs twice or is skipped\n"
    "  --resume-from LINE   start the job at file line LINE after a safe restart (lift, home X Y,\n"
    "                       re-heat, return); use the line the bridge reported when it stopped\n"
    "  --printer P          printer profile for .amp jobs (built-in name or PrusaSlicer .ini, as ampath gcode\n"
    "                       --printer): bed, placement, temperatures, speeds, start/end G-code (default generic)\n"
    "  --log FILE           protocol log (every line sent and received, events), created 0600\n"
    "  --quiet              no progress line and no printer messages on stderr\n"
    "  --keep-hot           after a signal or cancel, leave the heaters on (default: M104 S0, M140 S0, M107)\n"
    "  --daemon             keep the port open and take commands on --socket\n"
    "  --socket PATH        control socket for --daemon (default $XDG_RUNTIME_DIR/ampath-bridge.sock, or\n"
    "                       ${TMPDIR:-/tmp}/ampath-bridge-UID/ctl.sock in a private 0700 directory), mode 0600\n"
    "  --client-timeout S   close control clients idle for S seconds (default 600; subscribers exempt)\n"
    "Control socket: one command per line, one reply line ('ok ...' or 'error ...'), or one JSON object:\n"
    "  submit PATH [LINE] | status | pause | resume | cancel | estop | subscribe | unsubscribe | help | quit\n"
    "  (a PATH with spaces in double quotes; {\"cmd\":\"submit\",\"path\":\"/a b/job.gcode\",\"id\":1})\n"
    "Exit status: 0 job done, 1 job stopped (printer error, reset, shutdown, not ready, interrupted, device\n"
    "lost), 2 bad usage or input.\n";

static volatile sig_atomic_t sig_count;
static void on_signal(int sig)
{
    (void)sig;
    sig_count++;
}

static int fail(const char *fmt, const char *a)
{
    fprintf(stderr, "ampath-bridge: ");
    fprintf(stderr, fmt, a);
    fputc('\n', stderr);
    return 2;
}

/* The log holds the job and the printer's words: private from the start. */
static FILE *open_log(const char *path)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_NOCTTY, 0600);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (!f && fd >= 0)
        close(fd);
    return f;
}

/* The socket is taken before the device is opened: a refused second daemon must not touch the printer
   (opening a serial port resets many boards). */
static int run_daemon(const br_cfg *cfg, const br_daemon_opts *o, const char *job, long resume_from)
{
    br_listener ls;
    br_session *s;
    char why[600], path[PATH_MAX];
    if (o->sockpath)
        snprintf(path, sizeof path, "%s", o->sockpath);
    if ((!o->sockpath && br_sock_default(path, sizeof path, why, sizeof why) != 0) ||
        br_sock_listen(&ls, path, why, sizeof why) != 0)
        return fail("%s", why);
    s = calloc(1, sizeof *s);
    if (!s || br_session_open(s, cfg, why, sizeof why) != 0 ||
        (job && br_session_start_job(s, job, resume_from, why, sizeof why) != 0)) {
        if (s && s->link.fd >= 0)
            br_session_close(s);
        free(s);
        br_sock_close(&ls);
        return fail("%s", s ? why : "out of memory");
    }
    {
        int rc = br_daemon_run(s, &ls, o, &sig_count);
        free(s);
        return rc;
    }
}

static int one_shot(const br_cfg *cfg, const char *job, long resume_from, int keep_hot)
{
    br_session *s = calloc(1, sizeof *s);
    char why[600];
    double t_stop = 0, limit = 2.0 * (double)cfg->timeout_ms / 1000.0 + 1.0;
    int rc;
    if (!s)
        return fail("%s", "out of memory");
    if (br_session_open(s, cfg, why, sizeof why) != 0) {
        free(s);
        return fail("%s", why);
    }
    if (br_session_start_job(s, job, resume_from, why, sizeof why) != 0) {
        br_session_close(s);
        free(s);
        return fail("%s", why);
    }
    while (s->stop == BR_RUNNING) {
        br_session_step(s, NULL, 0, 1000);
        if (sig_count == 1 && !s->stopping) {
            fprintf(stderr, "\nampath-bridge: stopping after the lines in flight (signal again to stop now)\n");
            br_session_request_stop(s, BR_INTERRUPTED);
            t_stop = br_now();
        }
        /* the forced stop is for a signal only: a printer-error stop keeps its own report */
        if (s->stopping && s->stop == BR_RUNNING && sig_count > 0 && (sig_count > 1 || br_now() - t_stop > limit)) {
            s->stop = BR_INTERRUPTED;
            snprintf(s->stop_text, sizeof s->stop_text, "lines in flight not all acknowledged");
        }
    }
    /* a job that sent nothing is never "done" */
    rc = s->stop == BR_DONE && s->acked_moves > 0 ? 0 : 1;
    br_report(s, stdout);
    if (s->stop == BR_INTERRUPTED && !keep_hot) {
        int r = br_safe_end(s, limit < 10 ? limit : 10, &sig_count, 2);
        printf("safe end (heaters and fan off: M104 S0, M140 S0, M107): %s\n",
               r == 1 ? "acknowledged by the printer" : "NOT confirmed by the printer");
    }
    br_session_close(s);
    free(s);
    return rc;
}

/* The command line as cli_parse() leaves it; apply_options() checks what the table cannot and fills the
 * configuration (only the options given: the rest keep br_cfg_default()'s values). */
typedef struct bopts {
    int daemon, keep_hot, quiet, no_resend_ok, resend_ok;
    double client_timeout, ready_timeout, timeout, settle_ms, boot_wait, reconnect;
    long baud, bufsize, rx_bytes, resume_from;
    const char *printer, *on_error, *flavor, *window, *log, *socket;
} bopts;

/* A printer profile is checked now, so that a bad one is bad usage before the port is opened; *flavor: its
 * firmware (AMP_FLAVOR_*). */
static int check_printer(const char *spec, int *flavor)
{
    amp_printer *pr = malloc(sizeof *pr);
    amp_error err;
    int rc = 0;
    if (!pr)
        return fail("out of memory%s", "");
    if (amp_printer_load(pr, spec, &err) != AMP_OK)
        rc = fail("%s", err.msg);
    else
        *flavor = pr->flavor;
    free(pr);
    return rc;
}

static int apply_words(const bopts *o, const cli_opt *opts, br_cfg *cfg)
{
    double d;
    if (o->on_error && strcmp(o->on_error, "stop") != 0 && strcmp(o->on_error, "continue") != 0)
        return fail("bad --on-error %s (stop or continue)", o->on_error);
    cfg->on_error_continue = o->on_error && strcmp(o->on_error, "continue") == 0;
    if (cli_given(opts, "flavor")) {
        if (strcmp(o->flavor, "marlin") == 0)
            cfg->flavor = AMP_PROTO_MARLIN;
        else if (strcmp(o->flavor, "klipper") == 0)
            cfg->flavor = AMP_PROTO_KLIPPER;
        else if (strcmp(o->flavor, "auto") == 0)
            cfg->flavor = -1;
        else
            return fail("bad --flavor %s (marlin, klipper or auto)", o->flavor);
    }
    if (cli_given(opts, "window")) {
        if (strcmp(o->window, "pingpong") == 0)
            cfg->mode = AMP_PROTO_PINGPONG;
        else if (strcmp(o->window, "advanced") == 0)
            cfg->mode = AMP_PROTO_ADVANCED;
        else if (cli_number(o->window, &d) == 0 && d == (int)d && d >= 1 && d <= AMP_PROTO_MAX_INFLIGHT) {
            cfg->mode = AMP_PROTO_FIXED;
            cfg->window = (int)d;
        } else
            return fail("bad --window %s (pingpong, advanced or 1..24)", o->window);
    }
    if (o->no_resend_ok && o->resend_ok)
        return fail("%s", "--resend-ok and --no-resend-ok contradict each other");
    if (o->no_resend_ok || o->resend_ok) {
        cfg->resend_ok = o->resend_ok;
        cfg->learn = 0;
    }
    if (o->printer) {
        int fl = AMP_FLAVOR_MARLIN;
        if (check_printer(o->printer, &fl) != 0)
            return 2;
        /* the profile names the firmware: a Klipper printer is not handshaken as a Marlin one (and its .amp jobs
         * are written with Klipper's commands) unless --flavor says otherwise */
        if (!cli_given(opts, "flavor"))
            cfg->flavor = fl == AMP_FLAVOR_KLIPPER ? AMP_PROTO_KLIPPER : AMP_PROTO_MARLIN;
    }
    cfg->printer = o->printer ? o->printer : cfg->printer;
    return 0;
}

static int apply_options(const bopts *o, const cli_opt *opts, br_cfg *cfg, br_daemon_opts *dopts)
{
    if (apply_words(o, opts, cfg) != 0)
        return 2;
    if (cli_given(opts, "client-timeout"))
        dopts->idle_s = o->client_timeout;
    if (cli_given(opts, "ready-timeout"))
        cfg->ready_ms = (unsigned long)(o->ready_timeout * 1000);
    if (cli_given(opts, "baud"))
        cfg->baud = o->baud;
    if (cli_given(opts, "bufsize"))
        cfg->bufsize = (int)o->bufsize;
    if (cli_given(opts, "rx-bytes"))
        cfg->rx_bytes = (int)o->rx_bytes;
    if (cli_given(opts, "timeout"))
        cfg->timeout_ms = (unsigned long)(o->timeout * 1000);
    if (cli_given(opts, "settle-ms"))
        cfg->settle_ms = (unsigned long)o->settle_ms;
    if (cli_given(opts, "boot-wait"))
        cfg->boot_ms = (unsigned long)(o->boot_wait * 1000);
    if (cli_given(opts, "reconnect"))
        cfg->reconnect_s = o->reconnect;
    dopts->keep_hot = o->keep_hot;
    return 0;
}

int main(int argc, char **argv)
{
    br_cfg cfg;
    br_daemon_opts dopts;
    const char *pos[2] = {NULL, NULL};
    int npos = 0, i, rc;
    bopts o;
    cli_opt opts[] = {{"daemon", CLI_FLAG, &o.daemon, 0},
                      {"keep-hot", CLI_FLAG, &o.keep_hot, 0},
                      {"quiet", CLI_FLAG, &o.quiet, 0},
                      {"no-resend-ok", CLI_FLAG, &o.no_resend_ok, 0},
                      {"resend-ok", CLI_FLAG, &o.resend_ok, 0},
                      {"client-timeout", CLI_DOUBLE, &o.client_timeout, 0},
                      {"ready-timeout", CLI_DOUBLE, &o.ready_timeout, 0},
                      {"timeout", CLI_DOUBLE, &o.timeout, 0},
                      {"settle-ms", CLI_DOUBLE, &o.settle_ms, 0},
                      {"boot-wait", CLI_DOUBLE, &o.boot_wait, 0},
                      {"reconnect", CLI_DOUBLE, &o.reconnect, 0},
                      {"baud", CLI_LONG, &o.baud, 0},
                      {"bufsize", CLI_LONG, &o.bufsize, 0},
                      {"rx-bytes", CLI_LONG, &o.rx_bytes, 0},
                      {"resume-from", CLI_LONG, &o.resume_from, 0},
                      {"printer", CLI_STR, &o.printer, 0},
                      {"on-error", CLI_STR, &o.on_error, 0},
                      {"flavor", CLI_STR, &o.flavor, 0},
                      {"window", CLI_STR, &o.window, 0},
                      {"log", CLI_STR, &o.log, 0},
                      {"socket", CLI_STR, &o.socket, 0},
                      {NULL, CLI_FLAG, NULL, 0}};

    if (argc > 1 && strcmp(argv[1], "--bench") == 0)
        return br_bench_main(argc - 1, argv + 1);
    br_cfg_default(&cfg);
    memset(&dopts, 0, sizeof dopts);
    memset(&o, 0, sizeof o);
    o.resume_from = 1;
    dopts.idle_s = 600;
    for (i = 1; i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            fputs(usage, stdout);
            return 0;
        }
    /* ampath's option parser (tools/cli.c): numbers whole and within the ranges of its table */
    if (cli_parse("ampath-bridge", argc, argv, opts, pos, 1, 2, &npos) != CLI_OK)
        return 2;
    if ((rc = apply_options(&o, opts, &cfg, &dopts)) != 0)
        return rc;
    if (!o.daemon && npos < 2)
        return fail("%s", "missing JOB (or use --daemon)");
    cfg.device = pos[0];
    cfg.quiet = o.quiet;
    cfg.progress = !o.quiet && isatty(2);
    if (o.log && !(cfg.log = open_log(o.log)))
        return fail("cannot write the log %s", o.log);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGPIPE, SIG_IGN);
    dopts.sockpath = o.socket;
    rc = o.daemon ? run_daemon(&cfg, &dopts, npos == 2 ? pos[1] : NULL, o.resume_from)
                  : one_shot(&cfg, pos[1], o.resume_from, dopts.keep_hot);
    if (cfg.log)
        fclose(cfg.log);
    return rc;
}
