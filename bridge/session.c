/*
 * session.c — the one poll() loop of ampath-bridge: device fd in, engine
 * (lib/proto.c) in the middle, job lines out; hang-ups, clean stops, progress.
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bridge.h"

double br_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static unsigned long ms(double t)
{
    return (unsigned long)(t * 1000.0);
}

void br_cfg_default(br_cfg *c)
{
    memset(c, 0, sizeof *c);
    c->baud = 115200;
    c->flavor = AMP_PROTO_MARLIN;
    c->mode = AMP_PROTO_FIXED;
    c->window = 0; /* flavor default */
    c->bufsize = 4;
    c->rx_bytes = 127;
    c->resend_ok = 1;
    c->timeout_ms = 10000;
    c->boot_ms = 3000;
    c->settle_ms = 10;
    c->reconnect_s = 60;
    c->ready_ms = 60000;
    c->learn = 1;
}

static const char *const stop_names[] = {"running",     "done",      "printer reset", "printer shutdown",
                                         "protocol failure", "interrupted", "cancelled", "device lost",
                                         "job error", "printer error", "printer action", "printer not ready"};

const char *br_stop_name(br_stop st)
{
    return stop_names[st];
}

static void logf_(br_session *s, const char *fmt, ...)
{
    va_list ap;
    if (!s->cfg.log)
        return;
    fprintf(s->cfg.log, "%.3f ", br_now() - s->t_start);
    va_start(ap, fmt);
    vfprintf(s->cfg.log, fmt, ap);
    va_end(ap);
    fputc('\n', s->cfg.log);
    fflush(s->cfg.log);
}

static void set_stop(br_session *s, br_stop st, const char *text)
{
    if (s->stop != BR_RUNNING)
        return;
    s->stop = st;
    if (text && text[0])
        snprintf(s->stop_text, sizeof s->stop_text, "%s", text);
    else if (!s->stopping)
        s->stop_text[0] = '\0'; /* a requested stop keeps the reason it was given */
    logf_(s, "stop: %s %s", br_stop_name(st), s->stop_text);
}

/* Job line of engine line n (0 for none or a preamble line before any job line). */
static long job_line_of(const br_session *s, long n)
{
    return n > 0 && n > s->p.top_sent - BR_MAP ? s->map[n % BR_MAP] : 0;
}

long br_session_job_line(const br_session *s, long n) { return job_line_of(s, n); }

/* The printer refused the last line it acknowledged (Klipper: `!!`, then its `ok`) and ran nothing after it: the
 * job resumes with that line, once fixed (one past it was past the end when the job's last line was the one
 * refused). Otherwise the first line not acknowledged. */
long br_session_resume_line(const br_session *s)
{
    if (s->stop == BR_PRINTER_ERROR && s->err_jobline > 0 && s->err_jobline == s->last_acked_job_line)
        return s->err_jobline;
    return s->first_unacked_job_line;
}

/* Firmware error or action: remember the first one with its job line and text, then stop or go on. */
static void printer_complaint(br_session *s, const amp_proto_event *ev, br_stop why, int fatal)
{
    char cmd[AMP_PROTO_LINE_MAX + 8];
    long jl = job_line_of(s, ev->line);
    if (!amp_proto_line_text(&s->p, ev->line, cmd, sizeof cmd))
        cmd[0] = '\0';
    if (!s->err_text[0]) {
        s->err_jobline = jl;
        snprintf(s->err_cmd, sizeof s->err_cmd, "%s", cmd);
        snprintf(s->err_text, sizeof s->err_text, "%s", ev->text);
    }
    if (!s->cfg.quiet && jl > 0)
        fprintf(stderr, "%sampath-bridge: printer %s at job line %ld (%s): %s\n", s->cfg.progress ? "\n" : "",
                why == BR_PRINTER_ACTION ? "action" : "error", jl, cmd, ev->text);
    else if (!s->cfg.quiet) /* nothing in flight: a heater fault, a menu action */
        fprintf(stderr, "%sampath-bridge: printer %s after job line %ld: %s\n", s->cfg.progress ? "\n" : "",
                why == BR_PRINTER_ACTION ? "action" : "error", s->last_acked_job_line, ev->text);
    if (fatal && s->have_job && s->stop == BR_RUNNING) {
        char msg[sizeof s->stop_text];
        if (jl > 0)
            snprintf(msg, sizeof msg, "job line %ld (%s): %s", jl, cmd, ev->text);
        else
            snprintf(msg, sizeof msg, "after job line %ld: %s", s->last_acked_job_line, ev->text);
        br_session_request_stop(s, why);
        snprintf(s->stop_text, sizeof s->stop_text, "%s", msg); /* kept by set_stop when the lines in flight are done */
    }
}

static void on_event(void *user, const amp_proto_event *ev)
{
    br_session *s = user;
    logf_(s, "< %-10s %ld %s", amp_proto_event_name(ev->kind), ev->line, ev->text);
    switch (ev->kind) {
    case AMP_EV_ERROR:
        break; /* the resend protocol's own errors: in the log only */
    case AMP_EV_FWERROR:
        s->n_fwerrors++;
        printer_complaint(s, ev, BR_PRINTER_ERROR, !s->cfg.on_error_continue);
        break;
    case AMP_EV_ACTION:
        if (strncmp(ev->text, "cancel", 6) == 0 || strncmp(ev->text, "pause", 5) == 0)
            printer_complaint(s, ev, BR_PRINTER_ACTION, 1);
        break;
    case AMP_EV_WARNING:
        s->n_warnings++;
        s->warn_jobline = job_line_of(s, ev->line);
        snprintf(s->warn_text, sizeof s->warn_text, "%s", ev->text);
        if (!s->cfg.quiet)
            fprintf(stderr, "%sampath-bridge: printer warning at job line %ld: %s\n", s->cfg.progress ? "\n" : "",
                    s->warn_jobline, ev->text);
        break;
    case AMP_EV_WAITING:
        snprintf(s->waiting, sizeof s->waiting, "%s", ev->text);
        break;
    case AMP_EV_LEARNED:
        snprintf(s->learned, sizeof s->learned, "%s", ev->text);
        break;
    case AMP_EV_NOTREADY: {
        char msg[sizeof s->stop_text];
        snprintf(msg, sizeof msg, "not ready after %.0f s%s%s", (double)s->cfg.ready_ms / 1000.0,
                 s->waiting[0] ? ": " : "", s->waiting);
        set_stop(s, BR_NOT_READY, msg);
        break;
    }
    case AMP_EV_RESET:
        set_stop(s, BR_RESET, ev->text);
        break;
    case AMP_EV_SHUTDOWN:
        set_stop(s, BR_SHUTDOWN, ev->text);
        break;
    case AMP_EV_FATAL:
        set_stop(s, BR_FATAL, ev->text);
        break;
    case AMP_EV_TIMEOUT:
        if (!s->cfg.quiet)
            fprintf(stderr, "ampath-bridge: no reply from the printer, %s\n", ev->text);
        break;
    default:
        break;
    }
}

/* --flavor auto: ask M115 and wait for its ok (so that it cannot be taken for another line's). */
static int detect_flavor(br_session *s)
{
    double t0 = br_now(), deadline = t0 + (double)s->cfg.boot_ms / 1000.0 + 3.0;
    char line[256];
    size_t len = 0;
    int klipper = 0, sent = 0;
    while (br_now() < deadline) {
        struct pollfd pfd;
        char buf[256];
        ssize_t n, i;
        if (!sent) {
            if (write(s->link.fd, "M115\n", 5) == 5)
                sent = 1;
            logf_(s, "> M115 (flavor detection)");
        }
        pfd.fd = s->link.fd;
        pfd.events = POLLIN;
        if (poll(&pfd, 1, 100) <= 0)
            continue;
        n = read(s->link.fd, buf, sizeof buf);
        if (n <= 0)
            break;
        for (i = 0; i < n; i++) {
            if (buf[i] != '\n' && buf[i] != '\r') {
                if (len < sizeof line - 1)
                    line[len++] = buf[i];
                continue;
            }
            line[len] = '\0';
            len = 0;
            logf_(s, "< %s", line);
            if (strstr(line, "Klipper"))
                klipper = 1;
            if (strcmp(line, "start") == 0)
                sent = 0; /* it booted after our question: ask again */
            if (strncmp(line, "ok", 2) == 0 && sent)
                return klipper ? AMP_PROTO_KLIPPER : AMP_PROTO_MARLIN;
        }
    }
    return klipper ? AMP_PROTO_KLIPPER : AMP_PROTO_MARLIN;
}

int br_session_open(br_session *s, const br_cfg *cfg, char *why, size_t whylen)
{
    amp_proto_opts o;
    amp_error err;
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    s->t_start = br_now();
    s->link.fd = -1;
    if (br_link_open(&s->link, cfg->device, cfg->baud, why, whylen) != 0)
        return -1;
    logf_(s, "opened %s (%s)", s->link.real, s->link.is_pty ? "pty, raw termios" : "libserialport");
    if (cfg->flavor < 0) {
        s->cfg.flavor = detect_flavor(s);
        logf_(s, "flavor: %s", s->cfg.flavor == AMP_PROTO_KLIPPER ? "klipper" : "marlin");
    }
    amp_proto_opts_default(&o, (amp_proto_flavor)s->cfg.flavor);
    o.mode = cfg->mode;
    if (cfg->window > 0)
        o.window = cfg->window;
    o.bufsize = cfg->bufsize;
    o.rx_bytes = cfg->rx_bytes;
    o.resend_ok = cfg->resend_ok;
    o.timeout_ms = cfg->timeout_ms;
    o.settle_ms = cfg->settle_ms;
    o.byte_us = (unsigned long)(10000000L / cfg->baud); /* ptys too: the virtual printer models a wire */
    o.boot_ms = cfg->flavor < 0 ? 0 : cfg->boot_ms; /* detection already waited for the boot */
    o.ready_ms = cfg->ready_ms;
    o.learn = cfg->learn;
    o.on_event = on_event;
    o.user = s;
    if (amp_proto_init(&s->p, &o, ms(br_now()), &err) != AMP_OK) {
        snprintf(why, whylen, "%s", err.msg);
        br_link_close(&s->link);
        return -1;
    }
    return 0;
}

int br_session_start_job(br_session *s, const char *path, long resume_from, char *why, size_t whylen)
{
    if (s->p.state == AMP_PROTO_STOPPED) {
        /* after a reset or shutdown the next job starts with a fresh handshake */
        amp_proto_opts o = s->p.o;
        if (amp_proto_init(&s->p, &o, ms(br_now()), NULL) != AMP_OK) {
            snprintf(why, whylen, "cannot restart the protocol engine");
            return -1;
        }
    }
    if (br_job_open(&s->job, path, (amp_proto_flavor)s->cfg.flavor, s->cfg.printer, resume_from, s->cfg.progress,
                    why, whylen) != 0)
        return -1;
    s->have_job = 1;
    s->job_eof = 0;
    s->end_marker = 0;
    s->paused = 0;
    s->stopping = 0;
    s->stop = BR_RUNNING;
    s->sent_moves = s->acked_moves = 0;
    s->cum_total = s->last_jl = 0;
    s->verified = 0;
    memset(s->map, 0, sizeof s->map);
    memset(s->cum, 0, sizeof s->cum);
    s->last_acked_job_line = 0;
    s->first_unacked_job_line = s->job.first_line;
    s->rate_t0 = br_now();
    s->rate_n0 = 0;
    s->n_fwerrors = s->n_warnings = 0;
    s->err_jobline = s->warn_jobline = 0;
    s->err_cmd[0] = s->err_text[0] = s->warn_text[0] = s->stop_text[0] = '\0';
    s->maybe_from = s->maybe_to = 0;
    logf_(s, "job %s: %ld commands from line %ld", path, s->job.total, s->job.first_line);
    return 0;
}

void br_session_request_stop(br_session *s, br_stop why)
{
    if (s->stopping)
        return;
    s->stopping = (int)why;
    amp_proto_cancel_unsent(&s->p);
    logf_(s, "stopping (%s): finishing the lines in flight", br_stop_name(why));
}

static void hangup(br_session *s, const char *why)
{
    logf_(s, "link lost: %s", why);
    if (!s->cfg.quiet)
        fprintf(stderr, "ampath-bridge: device lost (%s), waiting up to %.0f s for it to come back\n", why,
                s->cfg.reconnect_s);
    br_link_close(&s->link);
    s->txlen = s->txoff = 0; /* a partial line is garbage to the printer: the re-handshake sorts it out */
    s->t_lost = br_now();
    if (s->cfg.flavor == AMP_PROTO_KLIPPER && s->have_job && s->p.state == AMP_PROTO_RUNNING) {
        /* Klipper's pty goes away only with the Klipper host (a restart: unhomed, its queue gone), and its
           lines carry no numbers: nothing could tell which lines in flight ran. Stop and name them. */
        amp_proto_cancel_unsent(&s->p);
        set_stop(s, BR_LINK_LOST, "Klipper's pseudo-terminal went away (a Klipper restart); lines carry no "
                                  "numbers, so the job cannot go on");
    }
}

static void try_reconnect(br_session *s)
{
    char why[256];
    if (s->have_job && br_now() - s->t_lost > s->cfg.reconnect_s) {
        set_stop(s, BR_LINK_LOST, "the device did not come back");
        return;
    }
    if (br_link_open(&s->link, s->cfg.device, s->cfg.baud, why, sizeof why) != 0)
        return;
    logf_(s, "link back: %s", s->link.real);
    if (!s->cfg.quiet)
        fprintf(stderr, "ampath-bridge: device back, asking the printer for the last line it received\n");
    amp_proto_link_restored(&s->p, ms(br_now()));
}

/* Counts from the engine's own numbers (acknowledgements can be revised downwards by a resend request). */
static void account(br_session *s)
{
    long a = s->p.acked, t = s->p.top_sent;
    s->acked_moves = a > 0 ? s->cum[a % BR_MAP] : 0;
    s->sent_moves = t > 0 ? s->cum[t % BR_MAP] : 0;
    s->last_acked_job_line = a > 0 ? s->map[a % BR_MAP] : 0;
    s->first_unacked_job_line = s->last_acked_job_line > 0 ? s->last_acked_job_line + 1 : s->job.first_line;
    /* sent but not acknowledged: after a reset or a lost link their fate is unknown (an ok lost on the
       way, or the line never ran) */
    if (t > a && s->map[t % BR_MAP] >= s->first_unacked_job_line) {
        s->maybe_from = s->first_unacked_job_line;
        s->maybe_to = s->map[t % BR_MAP];
    } else {
        s->maybe_from = s->maybe_to = 0;
    }
}

/* Fill the engine and the write buffer as far as the window allows. */
static void pump(br_session *s)
{
    for (;;) {
        if (s->txlen == 0) {
            if (amp_proto_next_tx(&s->p, ms(br_now()), s->tx, sizeof s->tx, &s->txlen)) {
                s->txoff = 0;
                logf_(s, "> %.*s", (int)(s->txlen - 1), s->tx);
                continue;
            }
        }
        if (s->txlen > 0 || !s->have_job || s->job_eof || s->paused || s->stopping || s->stop != BR_RUNNING)
            return;
        /* one unsent line at most in the engine, so that a stop drops nothing that was promised */
        if (s->p.next_n != s->p.send_n || !amp_proto_can_submit(&s->p))
            return;
        {
            char cmd[AMP_PROTO_LINE_MAX + 8];
            long jl = 0, n = 0;
            amp_error err;
            int r = br_job_next(&s->job, cmd, sizeof cmd, &jl);
            if (r == 0 && s->p.o.flavor == AMP_PROTO_MARLIN && !s->end_marker) {
                /* M105 closes the job: its `ok T:` acknowledges every line before it even when their oks
                   were garbled on the way, so that a lost last ok costs no timeout (lib/proto.c) */
                s->end_marker = 1;
                snprintf(cmd, sizeof cmd, "M105");
                jl = 0;
                r = 1;
            }
            if (r == 0) {
                s->job_eof = 1;
                return;
            }
            if (r < 0) {
                set_stop(s, BR_JOB_ERROR, "read error in the job");
                return;
            }
            if (amp_proto_submit(&s->p, cmd, strlen(cmd), &n, &err) != AMP_OK) {
                char msg[240];
                snprintf(msg, sizeof msg, "job line %ld: %s", jl, err.msg);
                set_stop(s, BR_JOB_ERROR, msg);
                return;
            }
            if (n > 0) {
                if (jl > 0) {
                    s->cum_total++;
                    s->last_jl = jl;
                }
                s->cum[n % BR_MAP] = s->cum_total;
                s->map[n % BR_MAP] = s->last_jl;
            }
        }
    }
}

static void progress(br_session *s, double now, int final)
{
    double el, rate, eta;
    if (!s->cfg.progress || !s->have_job || (!final && now - s->t_progress < 0.5))
        return;
    s->t_progress = now;
    if (s->p.state != AMP_PROTO_RUNNING && s->p.state != AMP_PROTO_STOPPED) {
        fprintf(stderr, "\rwaiting for the printer to become ready (%.0f s of %.0f)%s%.60s   ", now - s->t_start,
                (double)s->cfg.ready_ms / 1000.0, s->waiting[0] ? ": " : "", s->waiting);
        fflush(stderr);
        return;
    }
    el = now - s->rate_t0;
    rate = el > 0 ? (double)s->acked_moves / el : 0;
    eta = rate > 0 ? (double)(s->job.total - s->acked_moves) / rate : 0;
    fprintf(stderr, "\r%ld/%ld lines acknowledged (%.1f %%), ETA %d:%02d   %s", s->acked_moves, s->job.total,
            s->job.total ? 100.0 * (double)s->acked_moves / (double)s->job.total : 100.0, (int)(eta / 60),
            (int)eta % 60, final ? "\n" : "");
    fflush(stderr);
}

void br_session_step(br_session *s, struct pollfd *extra, int nextra, int max_ms)
{
    struct pollfd fds[8];
    int nf = 0, i, wait = max_ms;
    long w;
    double now = br_now();
    if (s->link.fd < 0 && (s->stop == BR_RUNNING || !s->have_job))
        try_reconnect(s);
    if (s->link.fd >= 0 && s->stop == BR_RUNNING)
        pump(s);
    if (s->link.fd >= 0) {
        fds[nf].fd = s->link.fd;
        fds[nf].events = POLLIN | (s->txlen > s->txoff ? POLLOUT : 0);
        fds[nf].revents = 0;
        nf++;
        w = amp_proto_wait_ms(&s->p, ms(now));
        if (w >= 0 && w < wait)
            wait = (int)w + 1;
    } else if (wait > 100) {
        wait = 100;
    }
    for (i = 0; i < nextra && nf < 8; i++) {
        fds[nf] = extra[i];
        fds[nf].revents = 0;
        nf++;
    }
    if (s->cfg.progress && wait > 500)
        wait = 500;
    if (poll(fds, (nfds_t)nf, wait) < 0) {
        if (errno != EINTR)
            set_stop(s, BR_FATAL, strerror(errno));
        for (i = 0; i < nextra; i++)
            extra[i].revents = 0;
        return;
    }
    for (i = 0; i < nextra; i++)
        extra[i].revents = fds[nf - nextra + i].revents;
    if (s->link.fd >= 0) {
        short re = fds[0].revents;
        if (re & POLLIN) {
            char buf[4096];
            ssize_t n = read(s->link.fd, buf, sizeof buf);
            if (n > 0)
                amp_proto_feed(&s->p, buf, (size_t)n, ms(br_now()));
            else if (n == 0 || (errno != EAGAIN && errno != EINTR))
                hangup(s, n == 0 ? "end of file" : strerror(errno));
        } else if (re & (POLLHUP | POLLERR | POLLNVAL)) {
            hangup(s, re & POLLHUP ? "hang-up" : "device error");
        }
        if (s->link.fd >= 0 && s->txlen > s->txoff) {
            ssize_t n = write(s->link.fd, s->tx + s->txoff, s->txlen - s->txoff);
            if (n > 0) {
                s->bytes_out += (long)n;
                s->txoff += (size_t)n;
                if (s->txoff == s->txlen)
                    s->txlen = s->txoff = 0;
            } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
                hangup(s, strerror(errno));
            }
        }
        if (s->link.fd >= 0 && s->stop == BR_RUNNING)
            pump(s);
    }
    if (s->have_job)
        account(s);
    if (s->stop == BR_RUNNING && s->have_job) {
        long inflight = s->p.top_sent - s->p.acked;
        if (s->stopping && (inflight <= 0 || s->p.state == AMP_PROTO_STOPPED) && s->txlen == 0)
            set_stop(s, (br_stop)s->stopping, "");
        else if (s->job_eof && !s->stopping && amp_proto_pending(&s->p) == 0 && s->txlen == 0 && !s->p.probing &&
                 !s->p.verify) {
            if (!s->verified && s->p.o.flavor == AMP_PROTO_MARLIN) {
                /* prove receipt of the last lines before declaring the job done */
                s->verified = 1;
                amp_proto_verify(&s->p);
                logf_(s, "verifying the end of the job");
            } else {
                set_stop(s, BR_DONE, "");
            }
        }
    }
    progress(s, br_now(), s->stop != BR_RUNNING);
}

void br_session_status(const br_session *s, char *buf, size_t cap)
{
    int err = s->stop == BR_PRINTER_ERROR || s->stop == BR_PRINTER_ACTION || s->stop == BR_NOT_READY ||
              (s->stop == BR_SHUTDOWN && s->n_fwerrors > 0); /* a halt the printer reported, not our estop */
    const char *st = err                     ? "error"
                     : s->stop != BR_RUNNING ? "stopped"
                     : !s->have_job          ? "idle"
                     : s->p.state != AMP_PROTO_RUNNING ? "waiting"
                     : s->paused             ? "paused"
                                             : "printing";
    /* the printer's words last: they contain blanks */
    snprintf(buf, cap,
             "state=%s job=%s acked=%ld total=%ld sent=%ld last_acked_line=%ld resume_from=%ld stop=%s errors=%ld "
             "warnings=%ld error_line=%ld message=%s",
             st, s->have_job ? s->job.path : "-", s->acked_moves, s->have_job ? s->job.total : 0, s->sent_moves,
             s->last_acked_job_line, br_session_resume_line(s), s->stop ? br_stop_name(s->stop) : "-", s->n_fwerrors,
             s->n_warnings, s->err_jobline, s->err_text[0] ? s->err_text : s->waiting[0] ? s->waiting : "-");
}

void br_session_report(const br_session *s, FILE *f)
{
    fprintf(f, "sent %ld commands (moves and others), acknowledged %ld\n", s->sent_moves, s->acked_moves);
    if (s->learned[0])
        fprintf(f, "printer dialect: %s\n", s->learned);
    if (s->n_fwerrors > 0)
        fprintf(f, "printer errors: %ld%s; first at job line %ld (%s): %s\n", s->n_fwerrors,
                s->cfg.on_error_continue ? " (--on-error continue)" : "", s->err_jobline,
                s->err_cmd[0] ? s->err_cmd : "-", s->err_text);
    if (s->n_warnings > 0)
        fprintf(f, "printer warnings: %ld; last at job line %ld: %s\n", s->n_warnings, s->warn_jobline, s->warn_text);
    if (s->stop != BR_DONE) {
        fprintf(f, "stopped: %s%s%s; last acknowledged job line %ld; resume with --resume-from %ld\n",
                br_stop_name(s->stop), s->stop_text[0] ? ": " : "", s->stop_text, s->last_acked_job_line,
                br_session_resume_line(s));
        if (s->maybe_from > 0 && s->maybe_to >= s->maybe_from)
            fprintf(f, "lines %ld..%ld may have run: they were sent and their acknowledgement never came "
                       "(check the part before resuming at %ld or %ld)\n",
                    s->maybe_from, s->maybe_to, s->maybe_from, s->maybe_to + 1);
    }
    fflush(f);
}

void br_session_close(br_session *s)
{
    if (s->have_job)
        br_job_close(&s->job);
    s->have_job = 0;
    br_link_close(&s->link);
}
