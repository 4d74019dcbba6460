/*
 * ampath-bridge — stream a job to a Marlin or Klipper printer (SPEC §8).
 * One-shot: `ampath-bridge DEVICE JOB [options]`; daemon: `--daemon` with a
 * Unix control socket (mode 0600). See docs/bridge.md and ampath-bridge(1).
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include "bridge.h"

static const char usage[] =
    "usage: ampath-bridge DEVICE [JOB] [options]\n"
    "Streams JOB (.gcode, or .amp converted with the G-code writer) to the printer on DEVICE\n"
    "(a serial port, a /dev/serial/by-id link, or a pty such as Klipper's /tmp/printer).\n"
    "  --baud N             link rate (default 115200; 250000 and other rates work)\n"
    "  --flavor F           marlin | klipper | auto (asks M115) (default marlin)\n"
    "  --window W           pingpong | N lines in flight | advanced (ADVANCED_OK) (default 4; klipper 16)\n"
    "  --bufsize N          printer command queue, Marlin BUFSIZE (default 4)\n"
    "  --rx-bytes N         printer serial RX buffer in bytes (default 128)\n"
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
    "                       the printer then says which line it expects, so nothing runs twice\n"
    "  --resume-from LINE   start the job at file line LINE after a safe restart (lift, home X Y,\n"
    "                       re-heat, return); use the line the bridge reported when it stopped\n"
    "  --log FILE           protocol log (every line sent and received, events)\n"
    "  --quiet              no progress line and no printer messages on stderr\n"
    "  --daemon             keep the port open and take commands on --socket\n"
    "  --socket PATH        control socket for --daemon (default $XDG_RUNTIME_DIR/ampath-bridge.sock or\n"
    "                       /tmp/ampath-bridge-UID.sock), created with mode 0600\n"
    "Control socket: one command per line, one reply line ('ok ...' or 'error ...'):\n"
    "  submit PATH [LINE] | status | pause | resume | cancel | estop | quit\n"
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

static void report(br_session *s)
{
    br_session_report(s, stdout);
}

/* ---- daemon ---- */
#define MAXCL 4
typedef struct client {
    int fd;
    char buf[1024];
    size_t len;
} client;

static void reply(int fd, const char *msg)
{
    size_t n = strlen(msg);
    ssize_t w = write(fd, msg, n);
    (void)w;
}

static int command(br_session *s, client *c, char *line)
{
    char out[1200], why[512];
    char *arg = strchr(line, ' ');
    if (arg)
        *arg++ = '\0';
    if (strcmp(line, "status") == 0) {
        br_session_status(s, out, sizeof out - 8);
        strcat(out, "\n");
        memmove(out + 3, out, strlen(out) + 1);
        memcpy(out, "ok ", 3);
        reply(c->fd, out);
    } else if (strcmp(line, "submit") == 0) {
        char *path = arg ? strtok(arg, " ") : NULL, *from = path ? strtok(NULL, " ") : NULL;
        if (!path)
            reply(c->fd, "error submit needs a job path\n");
        else if (s->have_job && s->stop == BR_RUNNING)
            reply(c->fd, "error a job is running\n");
        else {
            if (s->have_job)
                br_job_close(&s->job);
            s->have_job = 0;
            if (br_session_start_job(s, path, from ? atol(from) : 1, why, sizeof why) != 0) {
                snprintf(out, sizeof out, "error %s\n", why);
                reply(c->fd, out);
            } else {
                snprintf(out, sizeof out, "ok started %s (%ld commands)\n", path, s->job.total);
                reply(c->fd, out);
            }
        }
    } else if (strcmp(line, "pause") == 0) {
        s->paused = 1;
        reply(c->fd, "ok paused (lines in flight finish)\n");
    } else if (strcmp(line, "resume") == 0) {
        s->paused = 0;
        reply(c->fd, "ok resumed\n");
    } else if (strcmp(line, "cancel") == 0) {
        if (s->have_job && s->stop == BR_RUNNING) {
            br_session_request_stop(s, BR_CANCELLED);
            reply(c->fd, "ok cancelling (lines in flight finish)\n");
        } else
            reply(c->fd, "error no job running\n");
    } else if (strcmp(line, "estop") == 0) {
        amp_proto_estop(&s->p);
        reply(c->fd, "ok emergency stop (M112) sent\n");
    } else if (strcmp(line, "quit") == 0) {
        reply(c->fd, "ok bye\n");
        return 1;
    } else {
        reply(c->fd, "error unknown command (submit PATH [LINE] | status | pause | resume | cancel | estop | quit)\n");
    }
    return 0;
}

static int run_daemon(br_session *s, const char *sockpath)
{
    struct sockaddr_un sa;
    client cl[MAXCL];
    int lfd, i, quit = 0;
    mode_t old;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    if (strlen(sockpath) >= sizeof sa.sun_path)
        return fail("socket path too long: %s", sockpath);
    strcpy(sa.sun_path, sockpath);
    lfd = socket(AF_UNIX, SOCK_STREAM, 0);
    unlink(sockpath);
    old = umask(077); /* created 0600 from the start: no window where others could connect */
    if (lfd < 0 || bind(lfd, (struct sockaddr *)&sa, sizeof sa) != 0 || listen(lfd, 4) != 0) {
        umask(old);
        return fail("cannot create the control socket %s", sockpath);
    }
    umask(old);
    chmod(sockpath, 0600);
    for (i = 0; i < MAXCL; i++)
        cl[i].fd = -1;
    fprintf(stderr, "ampath-bridge: daemon on %s, control socket %s\n", s->link.real, sockpath);
    while (!quit && sig_count == 0) {
        struct pollfd ex[1 + MAXCL];
        int n = 0, idx[MAXCL];
        ex[n].fd = lfd;
        ex[n].events = POLLIN;
        n++;
        for (i = 0; i < MAXCL; i++)
            if (cl[i].fd >= 0) {
                ex[n].fd = cl[i].fd;
                ex[n].events = POLLIN;
                idx[n - 1] = i;
                n++;
            }
        br_session_step(s, ex, n, 200);
        if (s->have_job && s->stop != BR_RUNNING) {
            char st[600];
            br_session_status(s, st, sizeof st);
            fprintf(stderr, "ampath-bridge: job ended: %s\n", st);
            report(s);
            br_job_close(&s->job);
            s->job.f = NULL;
            s->have_job = 0;
        }
        if (ex[0].revents & POLLIN) {
            int fd = accept(lfd, NULL, NULL);
            for (i = 0; i < MAXCL && fd >= 0; i++)
                if (cl[i].fd < 0) {
                    cl[i].fd = fd;
                    cl[i].len = 0;
                    fd = -1;
                }
            if (fd >= 0) {
                reply(fd, "error too many clients\n");
                close(fd);
            }
        }
        for (i = 1; i < n; i++) {
            client *c = &cl[idx[i - 1]];
            ssize_t r;
            char *nl;
            if (!(ex[i].revents & (POLLIN | POLLHUP)))
                continue;
            r = read(c->fd, c->buf + c->len, sizeof c->buf - 1 - c->len);
            if (r <= 0) {
                close(c->fd);
                c->fd = -1;
                continue;
            }
            c->len += (size_t)r;
            c->buf[c->len] = '\0';
            while ((nl = strchr(c->buf, '\n')) != NULL) {
                *nl = '\0';
                if (nl > c->buf && nl[-1] == '\r')
                    nl[-1] = '\0';
                if (command(s, c, c->buf))
                    quit = 1;
                memmove(c->buf, nl + 1, c->len - (size_t)(nl + 1 - c->buf) + 1);
                c->len -= (size_t)(nl + 1 - c->buf);
            }
            if (c->len >= sizeof c->buf - 1) {
                reply(c->fd, "error line too long\n");
                c->len = 0;
            }
        }
    }
    for (i = 0; i < MAXCL; i++)
        if (cl[i].fd >= 0)
            close(cl[i].fd);
    close(lfd);
    unlink(sockpath);
    br_session_close(s);
    return 0;
}

static int parse_num(const char *s, double *v)
{
    char *end;
    *v = strtod(s, &end);
    return end != s && *end == '\0';
}

int main(int argc, char **argv)
{
    br_cfg cfg;
    br_session *s;
    const char *pos[2] = {NULL, NULL}, *logpath = NULL, *sockpath = NULL;
    char why[512], defsock[PATH_MAX];
    long resume_from = 1;
    int npos = 0, i, daemon = 0, quiet = 0, rc;
    double t_stop = 0;

    br_cfg_default(&cfg);
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        double d;
#define NEEDVAL                                                                                                      \
    do {                                                                                                             \
        if (!val)                                                                                                    \
            return fail("%s needs a value", a);                                                                      \
        i++;                                                                                                         \
    } while (0)
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(usage, stdout);
            return 0;
        } else if (strcmp(a, "--daemon") == 0) {
            daemon = 1;
        } else if (strcmp(a, "--quiet") == 0) {
            quiet = 1;
        } else if (strcmp(a, "--no-resend-ok") == 0) {
            cfg.resend_ok = 0;
            cfg.learn = 0;
        } else if (strcmp(a, "--resend-ok") == 0) {
            cfg.resend_ok = 1;
            cfg.learn = 0;
        } else if (strcmp(a, "--ready-timeout") == 0) {
            NEEDVAL;
            if (!parse_num(val, &d) || d <= 0 || d > 86400)
                return fail("bad --ready-timeout %s", val);
            cfg.ready_ms = (unsigned long)(d * 1000);
        } else if (strcmp(a, "--on-error") == 0) {
            NEEDVAL;
            if (strcmp(val, "stop") == 0)
                cfg.on_error_continue = 0;
            else if (strcmp(val, "continue") == 0)
                cfg.on_error_continue = 1;
            else
                return fail("bad --on-error %s (stop or continue)", val);
        } else if (strcmp(a, "--baud") == 0) {
            NEEDVAL;
            if (!parse_num(val, &d) || d < 50 || d > 4000000)
                return fail("bad --baud %s", val);
            cfg.baud = (long)d;
        } else if (strcmp(a, "--flavor") == 0) {
            NEEDVAL;
            if (strcmp(val, "marlin") == 0)
                cfg.flavor = AMP_PROTO_MARLIN;
            else if (strcmp(val, "klipper") == 0)
                cfg.flavor = AMP_PROTO_KLIPPER;
            else if (strcmp(val, "auto") == 0)
                cfg.flavor = -1;
            else
                return fail("bad --flavor %s (marlin, klipper or auto)", val);
        } else if (strcmp(a, "--window") == 0) {
            NEEDVAL;
            if (strcmp(val, "pingpong") == 0)
                cfg.mode = AMP_PROTO_PINGPONG;
            else if (strcmp(val, "advanced") == 0)
                cfg.mode = AMP_PROTO_ADVANCED;
            else if (parse_num(val, &d) && d >= 1 && d <= AMP_PROTO_MAX_INFLIGHT) {
                cfg.mode = AMP_PROTO_FIXED;
                cfg.window = (int)d;
            } else
                return fail("bad --window %s (pingpong, advanced or 1..24)", val);
        } else if (strcmp(a, "--bufsize") == 0) {
            NEEDVAL;
            if (!parse_num(val, &d) || d < 1 || d > AMP_PROTO_MAX_INFLIGHT)
                return fail("bad --bufsize %s (1..24)", val);
            cfg.bufsize = (int)d;
        } else if (strcmp(a, "--rx-bytes") == 0) {
            NEEDVAL;
            if (!parse_num(val, &d) || d < AMP_PROTO_LINE_MAX || d > 65536)
                return fail("bad --rx-bytes %s (96..65536)", val);
            cfg.rx_bytes = (int)d;
        } else if (strcmp(a, "--timeout") == 0) {
            NEEDVAL;
            if (!parse_num(val, &d) || d <= 0 || d > 3600)
                return fail("bad --timeout %s", val);
            cfg.timeout_ms = (unsigned long)(d * 1000);
        } else if (strcmp(a, "--settle-ms") == 0) {
            NEEDVAL;
            if (!parse_num(val, &d) || d < 0 || d > 10000)
                return fail("bad --settle-ms %s", val);
            cfg.settle_ms = (unsigned long)d;
        } else if (strcmp(a, "--boot-wait") == 0) {
            NEEDVAL;
            if (!parse_num(val, &d) || d < 0 || d > 600)
                return fail("bad --boot-wait %s", val);
            cfg.boot_ms = (unsigned long)(d * 1000);
        } else if (strcmp(a, "--reconnect") == 0) {
            NEEDVAL;
            if (!parse_num(val, &d) || d < 0)
                return fail("bad --reconnect %s", val);
            cfg.reconnect_s = d;
        } else if (strcmp(a, "--resume-from") == 0) {
            NEEDVAL;
            if (!parse_num(val, &d) || d < 1)
                return fail("bad --resume-from %s", val);
            resume_from = (long)d;
        } else if (strcmp(a, "--log") == 0) {
            NEEDVAL;
            logpath = val;
        } else if (strcmp(a, "--socket") == 0) {
            NEEDVAL;
            sockpath = val;
        } else if (a[0] == '-' && a[1] == '-') {
            return fail("unknown option %s (see --help)", a);
        } else if (npos < 2) {
            pos[npos++] = a;
        } else {
            return fail("too many arguments: %s", a);
        }
#undef NEEDVAL
    }
    if (npos < 1)
        return fail("%s", "missing DEVICE (see --help)");
    if (!daemon && npos < 2)
        return fail("%s", "missing JOB (or use --daemon)");
    cfg.device = pos[0];
    cfg.quiet = quiet;
    cfg.progress = !quiet && isatty(2);
    if (logpath && !(cfg.log = fopen(logpath, "w")))
        return fail("cannot write the log %s", logpath);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGPIPE, SIG_IGN);
    s = calloc(1, sizeof *s);
    if (!s)
        return fail("%s", "out of memory");
    if (br_session_open(s, &cfg, why, sizeof why) != 0) {
        free(s);
        return fail("%s", why);
    }
    if (daemon) {
        if (!sockpath) {
            const char *rt = getenv("XDG_RUNTIME_DIR");
            if (rt && *rt)
                snprintf(defsock, sizeof defsock, "%s/ampath-bridge.sock", rt);
            else
                snprintf(defsock, sizeof defsock, "/tmp/ampath-bridge-%ld.sock", (long)getuid());
            sockpath = defsock;
        }
        if (npos == 2 && br_session_start_job(s, pos[1], resume_from, why, sizeof why) != 0) {
            br_session_close(s);
            free(s);
            return fail("%s", why);
        }
        rc = run_daemon(s, sockpath);
        free(s);
        if (cfg.log)
            fclose(cfg.log);
        return rc;
    }
    if (br_session_start_job(s, pos[1], resume_from, why, sizeof why) != 0) {
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
        if (s->stopping && s->stop == BR_RUNNING && sig_count > 0 &&
            (sig_count > 1 || br_now() - t_stop > 2.0 * (double)cfg.timeout_ms / 1000.0 + 1.0)) {
            s->stop = BR_INTERRUPTED;
            snprintf(s->stop_text, sizeof s->stop_text, "lines in flight not all acknowledged");
        }
    }
    report(s);
    rc = s->stop == BR_DONE ? 0 : 1;
    br_session_close(s);
    free(s);
    if (cfg.log)
        fclose(cfg.log);
    return rc;
}
