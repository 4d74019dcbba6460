/*
 * daemon.c — `ampath-bridge DEVICE --daemon` (docs/interfaces.md §8; host API, hardened against clients):
 * one poll() over the printer and the control-socket clients; commands act on
 * the session of session.c; subscribers get state, progress and error events.
 * A signal (systemctl stop) or `quit` mid-job stops sending, waits for the
 * lines in flight, reports the resume line and sends the safe end.
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "daemon.h"

/* What status reports after a job ended (the session forgets it at the next submit). */
typedef struct jobrec {
    int have; /* a job was started since the daemon started */
    char path[PATH_MAX];
    long total, acked, sent, line, resume_from;
    br_stop stop;
    char stop_text[300];
    double t_start;
    int safe_end; /* -1 not sent (not needed or --keep-hot), 0 not confirmed, 1 acknowledged */
} jobrec;

typedef struct dstate {
    br_session *s;
    const br_daemon_opts *o;
    volatile sig_atomic_t *sig;
    br_clients cs;
    jobrec rec;
    int stopping_all; /* a signal or quit: finish the job, then leave */
    int done, interrupted;
    double t_stop_req; /* a stop was requested at (0 = none) */
    double t_prog;
    long prog_acked;
    const char *last_state;
    char last_msg[200];
    long errors;
    amp_proto_event_fn chained; /* the session's own event handler */
    void *chained_user;
    char out[BR_CL_IN + 1024];
} dstate;

void br_report(const br_session *s, FILE *out)
{
    /* one report for the one-shot run and the daemon: firmware errors,
     * warnings, the learned dialect, the resume line and the lines that may
     * have run (session.c) */
    br_session_report(s, out);
}

static int job_active(const br_session *s)
{
    return s->have_job && s->stop == BR_RUNNING;
}

static const char *state_of(const dstate *d)
{
    const br_session *s = d->s;
    if (job_active(s))
        return s->stopping ? "stopping" : s->paused ? "paused" : "printing";
    if (!d->rec.have)
        return "idle";
    switch (d->rec.stop) {
    case BR_DONE: return "done";
    case BR_CANCELLED: return "cancelled";
    case BR_INTERRUPTED: return "interrupted";
    default: return "error";
    }
}

/* Live figures while a job runs, the record after it ended. */
static void figures(const dstate *d, long *acked, long *total, long *sent, long *line, long *resume)
{
    const br_session *s = d->s;
    if (job_active(s)) {
        *acked = s->acked_moves, *total = s->job.total, *sent = s->sent_moves;
        *line = s->last_acked_job_line, *resume = br_session_resume_line(s);
    } else {
        *acked = d->rec.acked, *total = d->rec.total, *sent = d->rec.sent;
        *line = d->rec.line, *resume = d->rec.resume_from;
    }
}

static double eta_s(const dstate *d, long acked, long total)
{
    double el = br_now() - d->rec.t_start;
    if (!job_active(d->s) || acked <= 0 || el <= 0)
        return job_active(d->s) ? NAN : 0.0;
    return (double)(total - acked) / ((double)acked / el);
}

static void fill_status(const dstate *d, br_msg *m)
{
    long acked, total, sent, line, resume;
    figures(d, &acked, &total, &sent, &line, &resume);
    br_msg_str(m, "state", state_of(d));
    br_msg_str(m, "job", d->rec.have ? d->rec.path : NULL);
    br_msg_long(m, "acked", acked);
    br_msg_long(m, "total", total);
    br_msg_long(m, "sent", sent);
    br_msg_long(m, "line", line);
    br_msg_long(m, "last_acked_line", line);
    br_msg_long(m, "resume_from", resume);
    br_msg_num(m, "eta_s", eta_s(d, acked, total));
    br_msg_str(m, "stop", d->rec.have && !job_active(d->s) ? br_stop_name(d->rec.stop) : NULL);
    br_msg_str(m, "stop_text", d->rec.have && !job_active(d->s) && d->rec.stop_text[0] ? d->rec.stop_text : NULL);
    br_msg_long(m, "errors", d->errors);
    br_msg_str(m, "last_message", d->last_msg[0] ? d->last_msg : NULL);
}

static void send_msg(dstate *d, br_client *c, const br_msg *m, int json, const br_request *r)
{
    long n = br_msg_render(m, json, r, d->out, sizeof d->out);
    if (n > 0)
        br_client_send(&d->cs, c, d->out, (size_t)n);
}

static void broadcast(dstate *d, const br_msg *m)
{
    int i;
    for (i = 0; i < BR_CL_MAX; i++) {
        br_client *c = &d->cs.cl[i];
        if (c->fd >= 0 && c->subscribed)
            send_msg(d, c, m, c->subscribed == 2, NULL);
    }
}

/* ---- printer events (chained in front of the session's handler) ---- */

/* `Unknown command: "<job text>"` and the like: the job's words stay out of logs others read. */
static void elide_quotes(const char *in, char *out, size_t cap)
{
    size_t k = 0;
    int q = 0;
    for (; *in && k + 4 < cap; in++) {
        if (*in == '"') {
            if (!q)
                out[k++] = '"', out[k++] = '.', out[k++] = '.', out[k++] = '.';
            if (k < cap - 1 && q)
                out[k++] = '"';
            q = !q;
        } else if (!q) {
            out[k++] = *in;
        }
    }
    if (q && k < cap - 1)
        out[k++] = '"';
    out[k] = '\0';
}

/* Marlin's replies that belong to the line-number/checksum resend protocol (the engine handles them, and
   the end-of-job probe provokes one on purpose): not printer errors for the user. */
static int protocol_reply(const char *t)
{
    static const char *const words[] = {"Line Number", "checksum", "Checksum", "Last Line", "Resend", "No Line"};
    size_t i;
    for (i = 0; i < sizeof words / sizeof words[0]; i++)
        if (strstr(t, words[i]))
            return 1;
    return 0;
}

static void on_printer_event(void *user, const amp_proto_event *ev)
{
    dstate *d = user;
    const char *kind = NULL;
    char text[200];
    amp_proto_event e = *ev;
    elide_quotes(ev->text ? ev->text : "", text, sizeof text);
    e.text = text;
    switch (ev->kind) {
    case AMP_EV_ERROR: kind = "error"; break;
    case AMP_EV_RESET: kind = "reset"; break;
    case AMP_EV_SHUTDOWN: kind = "shutdown"; break;
    case AMP_EV_FATAL: kind = "fatal"; break;
    case AMP_EV_TIMEOUT: kind = "timeout"; break;
    /* the firmware's own complaints stop a job too (Klipper `!!`, Marlin `Error:Probing Failed`, `// action:
       cancel`, never ready): a subscriber hears why, not only the `end` that follows */
    case AMP_EV_FWERROR: kind = "firmware"; break;
    case AMP_EV_ACTION:
        if (strncmp(text, "cancel", 6) == 0 || strncmp(text, "pause", 5) == 0)
            kind = "action";
        break;
    case AMP_EV_NOTREADY: kind = "notready"; break;
    default: break;
    }
    if (ev->kind == AMP_EV_ERROR && protocol_reply(text))
        kind = NULL;
    else if ((ev->kind == AMP_EV_INFO || kind) && text[0])
        snprintf(d->last_msg, sizeof d->last_msg, "%s", text);
    if (kind) {
        br_msg m;
        const br_session *s = d->s;
        long hit = ev->kind == AMP_EV_FWERROR || ev->kind == AMP_EV_ACTION ? br_session_job_line(s, ev->line) : 0;
        if (ev->kind != AMP_EV_TIMEOUT)
            d->errors++;
        br_msg_event(&m, ev->kind == AMP_EV_TIMEOUT ? "warning" : "error");
        br_msg_str(&m, "kind", kind);
        br_msg_str(&m, "text", text);
        br_msg_long(&m, "line", !s->have_job ? 0 : hit > 0 ? hit /* the line it hit */ : s->last_acked_job_line);
        broadcast(d, &m);
    }
    if (d->chained)
        d->chained(d->chained_user, &e);
}

/* Put our handler in front of the session's (again if the engine was re-initialised with other options). */
static void hook(dstate *d)
{
    amp_proto_opts *o = &d->s->p.o;
    if (o->on_event == on_printer_event)
        return;
    d->chained = o->on_event;
    d->chained_user = o->user;
    o->on_event = on_printer_event;
    o->user = d;
}

/* ---- jobs ---- */
static void state_event(dstate *d);

static void job_started(dstate *d)
{
    br_session *s = d->s;
    memset(&d->rec, 0, sizeof d->rec);
    d->rec.have = 1;
    snprintf(d->rec.path, sizeof d->rec.path, "%s", s->job.path);
    d->rec.total = s->job.total;
    d->rec.t_start = br_now();
    d->rec.safe_end = -1;
    d->t_stop_req = 0;
    d->prog_acked = -1;
    d->errors = 0;
    d->last_msg[0] = '\0';
    fprintf(stderr, "ampath-bridge: job %s: %ld commands from line %ld\n", s->job.path, s->job.total,
            s->job.first_line);
}

static void request_stop(dstate *d, br_stop why)
{
    if (!job_active(d->s) || d->s->stopping)
        return;
    br_session_request_stop(d->s, why);
    d->t_stop_req = br_now();
}

static void job_ended(dstate *d)
{
    br_session *s = d->s;
    br_msg m;
    jobrec *r = &d->rec;
    if (s->stop == BR_DONE && s->acked_moves <= 0) {
        s->stop = BR_JOB_ERROR; /* a job that sent nothing is never done */
        snprintf(s->stop_text, sizeof s->stop_text, "nothing was sent");
    }
    r->stop = s->stop;
    snprintf(r->stop_text, sizeof r->stop_text, "%s", s->stop_text);
    r->acked = s->acked_moves, r->sent = s->sent_moves, r->line = s->last_acked_job_line;
    r->resume_from = br_session_resume_line(s);
    fprintf(stderr, "ampath-bridge: job %s ended: %s%s%s\n", r->path, br_stop_name(r->stop), r->stop_text[0] ? ": " : "",
            r->stop_text);
    br_report(s, stdout);
    if (r->stop == BR_INTERRUPTED)
        d->interrupted = 1;
    if ((r->stop == BR_INTERRUPTED || r->stop == BR_CANCELLED) && !d->o->keep_hot) {
        double max_s = 2.0 * (double)s->cfg.timeout_ms / 1000.0 + 1.0;
        r->safe_end = br_safe_end(s, max_s < 10 ? max_s : 10, d->sig, 2) == 1;
        printf("safe end (heaters and fan off: M104 S0, M140 S0, M107): %s\n",
               r->safe_end ? "acknowledged by the printer" : "NOT confirmed by the printer");
        fflush(stdout);
    }
    br_job_close(&s->job);
    s->have_job = 0;
    if (d->errors == 0 && r->stop != BR_DONE && r->stop != BR_CANCELLED && r->stop != BR_INTERRUPTED) {
        /* a stop no printer event announced (the device lost, a job line refused before sending): the error
           event a subscriber waits for, before the end */
        br_msg_event(&m, "error");
        br_msg_str(&m, "kind", br_stop_name(r->stop));
        br_msg_str(&m, "text", r->stop_text);
        br_msg_long(&m, "line", r->line);
        broadcast(d, &m);
        d->errors++;
    }
    state_event(d); /* the last state before the end: a host that stops reading at "end" has read it */
    br_msg_event(&m, "end");
    fill_status(d, &m);
    br_msg_long(&m, "safe_end", r->safe_end);
    broadcast(d, &m);
    if (d->stopping_all)
        d->done = 1;
}

/* Stop requests that outlive twice the reply timeout end without waiting further (as the one-shot does). */
static void watch_stops(dstate *d, double now)
{
    br_session *s = d->s;
    double limit = 2.0 * (double)s->cfg.timeout_ms / 1000.0 + 1.0;
    if (*d->sig > 0 && !d->stopping_all) {
        d->stopping_all = 1;
        fprintf(stderr, "ampath-bridge: signal: %s\n",
                job_active(s) ? "stopping after the lines in flight (signal again to stop waiting)" : "exiting");
        request_stop(d, BR_INTERRUPTED);
    }
    if (d->stopping_all && !job_active(s))
        d->done = 1;
    if (job_active(s) && s->stopping && d->t_stop_req > 0 && (now - d->t_stop_req > limit || *d->sig > 1)) {
        s->stop = (br_stop)s->stopping;
        snprintf(s->stop_text, sizeof s->stop_text, "lines in flight not all acknowledged");
    }
}

/* A "state" event when the state changed since the last one. */
static void state_event(dstate *d)
{
    br_msg m;
    const char *st = state_of(d);
    if (st != d->last_state) {
        d->last_state = st;
        br_msg_event(&m, "state");
        br_msg_str(&m, "state", st);
        br_msg_str(&m, "job", d->rec.have ? d->rec.path : NULL);
        broadcast(d, &m);
    }
}

static void progress_events(dstate *d, double now)
{
    br_msg m;
    state_event(d);
    if (job_active(d->s) && d->s->acked_moves != d->prog_acked && now - d->t_prog >= 0.5) {
        long acked, total, sent, line, resume;
        figures(d, &acked, &total, &sent, &line, &resume);
        d->t_prog = now;
        d->prog_acked = acked;
        br_msg_event(&m, "progress");
        br_msg_long(&m, "acked", acked);
        br_msg_long(&m, "total", total);
        br_msg_long(&m, "line", line);
        br_msg_num(&m, "percent", total > 0 ? 100.0 * (double)acked / (double)total : 0.0);
        br_msg_num(&m, "eta_s", eta_s(d, acked, total));
        broadcast(d, &m);
    }
}

/* ---- commands ---- */
static void reply(dstate *d, br_client *c, const br_request *r, int ok, const char *text)
{
    br_msg m;
    br_msg_reply(&m, ok, text);
    send_msg(d, c, &m, r->json, r);
}

static void cmd_submit(dstate *d, br_client *c, const br_request *r)
{
    br_session *s = d->s;
    char why[600], text[PATH_MAX + 64];
    br_msg m;
    if (job_active(s)) {
        reply(d, c, r, 0, "a job is running (cancel it first)");
        return;
    }
    if (d->stopping_all) {
        reply(d, c, r, 0, "the daemon is shutting down");
        return;
    }
    if (s->have_job)
        br_job_close(&s->job);
    s->have_job = 0;
    if (br_session_start_job(s, r->path, r->from, why, sizeof why) != 0) {
        fprintf(stderr, "ampath-bridge: submit refused: %s\n", why);
        reply(d, c, r, 0, why);
        return;
    }
    job_started(d);
    snprintf(text, sizeof text, "started %s (%ld commands)", r->path, s->job.total);
    br_msg_reply(&m, 1, text);
    br_msg_str(&m, "job", r->path);
    br_msg_long(&m, "total", s->job.total);
    br_msg_long(&m, "from", r->from);
    send_msg(d, c, &m, r->json, r);
}

static void cmd_estop(dstate *d, br_client *c, const br_request *r)
{
    br_session *s = d->s;
    if (s->link.fd < 0) {
        reply(d, c, r, 0, "the printer is not connected: nothing could be sent");
        return;
    }
    amp_proto_estop(&s->p);
    if (!job_active(s) && s->txlen == 0) {
        /* no job: the session is not sending, so put the M112 on the wire here */
        size_t len = 0;
        if (amp_proto_next_tx(&s->p, (unsigned long)(br_now() * 1000.0), s->tx, sizeof s->tx, &len)) {
            s->txlen = len;
            s->txoff = 0;
        }
    }
    fprintf(stderr, "ampath-bridge: emergency stop (M112) requested\n");
    reply(d, c, r, 1, "emergency stop (M112) sent");
}

static void cmd_job(dstate *d, br_client *c, const br_request *r)
{
    br_session *s = d->s;
    if (!job_active(s)) {
        reply(d, c, r, 0, "no job running");
        return;
    }
    if (r->cmd == BR_CMD_PAUSE) {
        s->paused = 1;
        reply(d, c, r, 1, "paused (lines in flight finish)");
    } else if (r->cmd == BR_CMD_RESUME) {
        s->paused = 0;
        reply(d, c, r, 1, "resumed");
    } else {
        request_stop(d, BR_CANCELLED);
        reply(d, c, r, 1, "cancelling (lines in flight finish, then heaters off)");
    }
}

static void cmd_status(dstate *d, br_client *c, const br_request *r, const char *text)
{
    br_msg m;
    br_msg_reply(&m, 1, text);
    fill_status(d, &m);
    send_msg(d, c, &m, r->json, r);
}

static void on_line(void *user, br_client *c, const char *line, size_t len)
{
    dstate *d = user;
    br_request r;
    char why[600];
    if (br_request_parse(&r, line, len, why, sizeof why) != 0) {
        reply(d, c, &r, 0, why);
        return;
    }
    if (r.cmd == BR_CMD_NONE)
        return;
    if (c->reserved && !br_cmd_is_priority(r.cmd)) {
        reply(d, c, &r, 0, "too many clients: this connection takes one of estop, cancel, status, pause");
        return;
    }
    switch (r.cmd) {
    case BR_CMD_SUBMIT: cmd_submit(d, c, &r); break;
    case BR_CMD_ESTOP: cmd_estop(d, c, &r); break;
    case BR_CMD_PAUSE:
    case BR_CMD_RESUME:
    case BR_CMD_CANCEL: cmd_job(d, c, &r); break;
    case BR_CMD_STATUS: cmd_status(d, c, &r, NULL); break;
    case BR_CMD_SUBSCRIBE:
        c->subscribed = r.json ? 2 : 1;
        cmd_status(d, c, &r, "subscribed");
        break;
    case BR_CMD_UNSUBSCRIBE:
        c->subscribed = 0;
        reply(d, c, &r, 1, "unsubscribed");
        break;
    case BR_CMD_HELP:
        reply(d, c, &r, 1, "submit PATH [LINE] | status | pause | resume | cancel | estop | subscribe | "
                           "unsubscribe | help | quit (or one JSON object per line: docs/bridge.md)");
        break;
    case BR_CMD_QUIT:
        d->stopping_all = 1;
        request_stop(d, BR_INTERRUPTED);
        reply(d, c, &r, 1, job_active(d->s) ? "bye (after the lines in flight and the safe end)" : "bye");
        break;
    default: break;
    }
}

static int loop_wait(const dstate *d, double now)
{
    const br_session *s = d->s;
    int wait = 200;
    if (s->link.fd >= 0) {
        long w = amp_proto_wait_ms(&s->p, (unsigned long)(now * 1000.0));
        if (w >= 0 && w + 1 < wait)
            wait = (int)w + 1;
    } else if (wait > 100) {
        wait = 100; /* reopen attempts */
    }
    if (job_active(s) && wait > 100)
        wait = 100; /* progress events and stop deadlines */
    return br_clients_wait_ms(&d->cs, now, wait);
}

static void serve(dstate *d)
{
    br_session *s = d->s;
    while (!d->done) {
        struct pollfd pfd[2 + BR_CL_MAX];
        int n = 0, nc;
        double now = br_now();
        hook(d);
        if (s->link.fd >= 0) {
            pfd[0].fd = s->link.fd;
            pfd[0].events = (short)(POLLIN | (s->txlen > s->txoff ? POLLOUT : 0));
            pfd[0].revents = 0;
            n = 1;
        }
        nc = br_clients_pollfds(&d->cs, pfd + n, 1 + BR_CL_MAX);
        if (poll(pfd, (nfds_t)(n + nc), loop_wait(d, now)) < 0 && errno != EINTR)
            break;
        br_session_step(s, NULL, 0, 0);
        br_clients_service(&d->cs, pfd + n, nc, br_now(), on_line, d);
        watch_stops(d, br_now());
        if (s->have_job && s->stop != BR_RUNNING)
            job_ended(d);
        progress_events(d, br_now());
    }
}

int br_daemon_run(br_session *s, br_listener *ls, const br_daemon_opts *o, volatile sig_atomic_t *sig)
{
    dstate *d = calloc(1, sizeof *d);
    int rc;
    if (!d) {
        fprintf(stderr, "ampath-bridge: out of memory\n");
        br_session_close(s);
        br_sock_close(ls);
        return 2;
    }
    d->s = s;
    d->o = o;
    d->sig = sig;
    br_clients_init(&d->cs, ls->fd, o->idle_s);
    fprintf(stderr, "ampath-bridge: daemon on %s, control socket %s\n", s->link.real, ls->path);
    if (s->have_job)
        job_started(d);
    serve(d);
    br_clients_close_all(&d->cs);
    br_sock_close(ls);
    br_session_close(s);
    rc = d->interrupted ? 1 : 0;
    free(d);
    return rc;
}
