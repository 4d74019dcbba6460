/*
 * The daemon of ampath-bridge and its control socket (docs/interfaces.md §8; host API and hardening: "The bridge and
 * its daemon"). Unit tests of the request language (plain and JSON), then the real daemon against the
 * virtual printer (tools/ampath-vprinter) with hostile clients: never-reading floods, idle crowds,
 * over-long lines and NUL bytes, FIFOs and devices as jobs, squatted and stale sockets, a second daemon,
 * a shared device, SIGTERM mid-job. Every wait polls with a generous deadline: nothing sleeps and hopes.
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "daemon.h"
#include "testutil.h"

#define DEADLINE 120.0 /* seconds: generous, a loaded machine under ASan is slow; never reached when working */

static const char *FAST = "--timeout 0.3 --settle-ms 5 --boot-wait 0.3 --baud 1000000";

/* ------------------------------------------------------------------ unit: the request language */

static br_request req;

static int parse(const char *line, char *why)
{
    return br_request_parse(&req, line, strlen(line), why, 600);
}

START_TEST(plain_submit_takes_quoted_paths_with_spaces_and_refuses_stray_words)
{
    char why[600];
    ck_assert_int_eq(parse("submit \"/tmp/my jobs/a \\\"b\\\".gcode\" 12", why), 0);
    ck_assert_int_eq(req.cmd, BR_CMD_SUBMIT);
    ck_assert_str_eq(req.path, "/tmp/my jobs/a \"b\".gcode");
    ck_assert_int_eq(req.from, 12);
    ck_assert_int_eq(parse("submit /tmp/job.gcode", why), 0);
    ck_assert_int_eq(req.from, 1);
    /* `submit PATH abc` used to mean line 1 silently */
    ck_assert_int_eq(parse("submit /tmp/job.gcode abc", why), -1);
    ck_assert_ptr_nonnull(strstr(why, "'abc' is not a line number"));
    ck_assert_int_eq(parse("submit /tmp/job.gcode 0", why), -1);
    ck_assert_int_eq(parse("submit /tmp/job.gcode 5 6", why), -1);
    ck_assert_int_eq(parse("submit /tmp/my job.gcode", why), -1); /* unquoted spaces: refused, not guessed */
    ck_assert_int_eq(parse("submit \"/tmp/unterminated", why), -1);
    ck_assert_int_eq(parse("submit job.gcode", why), -1);
    ck_assert_ptr_nonnull(strstr(why, "absolute"));
    ck_assert_int_eq(parse("submit", why), -1);
    ck_assert_int_eq(parse("status now", why), -1);
}
END_TEST

START_TEST(unknown_command_nul_and_control_bytes_answer_one_line)
{
    char why[600];
    static const char nul[] = "stat\0us";
    ck_assert_int_eq(parse("frobnicate", why), -1);
    ck_assert_ptr_nonnull(strstr(why, "unknown command 'frobnicate'"));
    ck_assert_ptr_null(strchr(why, '\n'));
    ck_assert_int_eq(br_request_parse(&req, nul, sizeof nul - 1, why, sizeof why), -1);
    ck_assert_ptr_nonnull(strstr(why, "NUL"));
    ck_assert_int_eq(parse("status\033[2J", why), -1);
    ck_assert_int_eq(parse("   ", why), 0);
    ck_assert_int_eq(req.cmd, BR_CMD_NONE); /* blank lines are ignored, not answered */
    ck_assert_int_eq(parse("status\r", why), 0);
    ck_assert_int_eq(req.cmd, BR_CMD_STATUS);
    ck_assert_int_eq(br_cmd_is_priority(BR_CMD_ESTOP), 1);
    ck_assert_int_eq(br_cmd_is_priority(BR_CMD_SUBMIT), 0);
}
END_TEST

START_TEST(json_requests_parse_with_escapes_and_ids)
{
    char why[600];
    ck_assert_int_eq(parse("{\"cmd\":\"submit\",\"path\":\"/tmp/caf\\u00e9 \\ud83d\\ude00.gcode\",\"from\":3,"
                           "\"id\":\"abc\"}",
                           why),
                     0);
    ck_assert_int_eq(req.json, 1);
    ck_assert_int_eq(req.cmd, BR_CMD_SUBMIT);
    ck_assert_str_eq(req.path, "/tmp/caf\xc3\xa9 \xf0\x9f\x98\x80.gcode");
    ck_assert_int_eq(req.from, 3);
    ck_assert_int_eq(req.has_id, 1);
    ck_assert_str_eq(req.id.str, "abc");
    ck_assert_int_eq(parse(" { \"cmd\" : \"status\" , \"id\" : 42 } ", why), 0);
    ck_assert_int_eq(req.cmd, BR_CMD_STATUS);
    ck_assert(req.id.type == BR_J_NUM && req.id.num == 42);
}
END_TEST

START_TEST(json_parser_refuses_what_it_does_not_understand)
{
    /* each of these must fail: the checker is shown failing on broken input */
    static const char *const bad[] = {
        "{\"cmd\":\"status\"",                  /* unterminated */
        "{\"cmd\":\"status\"} x",               /* trailing bytes */
        "{\"cmd\":\"status\",\"cmd\":\"quit\"}", /* duplicate key */
        "{\"cmd\":{\"a\":1}}",                  /* nesting */
        "{\"cmd\":[1]}",                        /* arrays */
        "{\"cmd\":\"st\\x\"}",                  /* bad escape */
        "{\"cmd\":\"\\u0000\"}",                /* NUL inside a string */
        "{\"cmd\":\"\\udc00\"}",                /* lone surrogate */
        "{\"cmd\":\"\xff\"}",                   /* invalid UTF-8 */
        "{\"cmd\":01}",                         /* leading zero */
        "{\"cmd\":1.}",                         /* bad number */
        "{\"cmd\":tru}",                        /* bad literal */
        "{\"cmd\":\"submit\",\"path\":\"/a\",\"frm\":2}", /* unknown key */
        "{\"cmd\":\"submit\",\"path\":\"/a\",\"from\":2.5}",
        "{\"cmd\":\"status\",\"path\":\"/a\"}",
        "{\"cmd\":\"reboot\"}",
        "{\"path\":\"/a\"}",
        "[\"status\"]",
    };
    size_t i;
    char why[600];
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        ck_assert_msg(parse(bad[i], why) == -1, "accepted: %s", bad[i]);
        ck_assert_int_eq(req.json, bad[i][0] == '{');
        ck_assert_ptr_null(strchr(why, '\n'));
    }
}
END_TEST

START_TEST(json_writer_escapes_control_bytes_and_repairs_garbled_utf8)
{
    char buf[512], why[200];
    br_jw w;
    br_jobj o;
    long n;
    const br_jmember *m;
    br_jw_begin(&w, buf, sizeof buf);
    br_jw_str(&w, "text", "ok\n\"q\"\\ \x01 caf\xc3\xa9 \xff\xfe end"); /* bytes garbled on the wire */
    br_jw_long(&w, "n", -7);
    br_jw_num(&w, "eta", NAN);
    br_jw_bool(&w, "b", 1);
    n = br_jw_end(&w);
    ck_assert_int_gt(n, 0);
    ck_assert_int_eq(buf[n - 1], '\n');
    ck_assert_ptr_eq(strchr(buf, '\n'), buf + n - 1); /* one line */
    ck_assert_int_eq(br_json_parse(&o, buf, (size_t)n - 1, why, sizeof why), 0);
    m = br_json_get(&o, "text");
    ck_assert_ptr_nonnull(m);
    ck_assert_str_eq(m->str, "ok\n\"q\"\\ \x01 caf\xc3\xa9 \xef\xbf\xbd\xef\xbf\xbd end");
    ck_assert(br_json_get(&o, "eta")->type == BR_J_NULL);
    ck_assert(br_json_get(&o, "n")->num == -7);
    /* overflow is reported, never a cut object */
    br_jw_begin(&w, buf, 16);
    br_jw_str(&w, "text", "a long string that does not fit");
    ck_assert_int_eq(br_jw_end(&w), -1);
}
END_TEST

START_TEST(plain_replies_quote_values_and_never_hold_a_second_line)
{
    char buf[512];
    br_msg m;
    long n;
    br_msg_reply(&m, 1, NULL);
    br_msg_str(&m, "state", "printing");
    br_msg_str(&m, "job", "/tmp/my job.gcode");
    br_msg_str(&m, "last_message", "!! bad\nline");
    br_msg_str(&m, "stop", NULL);
    br_msg_long(&m, "acked", 12);
    n = br_msg_render(&m, 0, NULL, buf, sizeof buf);
    ck_assert_int_gt(n, 0);
    ck_assert_str_eq(buf, "ok state=printing job=\"/tmp/my job.gcode\" last_message=\"!! bad?line\" stop=- acked=12\n");
    br_msg_event(&m, "progress");
    br_msg_long(&m, "acked", 3);
    ck_assert_int_gt(br_msg_render(&m, 1, NULL, buf, sizeof buf), 0);
    ck_assert_str_eq(buf, "{\"event\":\"progress\",\"acked\":3}\n");
    br_msg_reply(&m, 0, "no job running");
    ck_assert_int_gt(br_msg_render(&m, 0, NULL, buf, sizeof buf), 0);
    ck_assert_str_eq(buf, "error no job running\n");
}
END_TEST

/* ------------------------------------------------------------------ processes */

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Children die with the test (a failed assertion must not leave daemons behind). */
static pid_t spawn(char **argv, const char *out, const char *err, const char *in, const char *tmpdir)
{
    pid_t pid;
    /* scratch names repeat when pids wrap (pid_max 32768): a file left by an
     * older run must not be read as this child's output before the child has
     * opened (truncated) it — daemon_start polls stderr for its banner */
    if (out)
        unlink(out);
    if (err)
        unlink(err);
    pid = fork();
    ck_assert_int_ge(pid, 0);
    if (pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (!freopen(in ? in : "/dev/null", "r", stdin) || !freopen(out ? out : "/dev/null", "w", stdout) ||
            !freopen(err ? err : "/dev/null", "w", stderr))
            _exit(126);
        if (tmpdir) {
            unsetenv("XDG_RUNTIME_DIR");
            setenv("TMPDIR", tmpdir, 1);
        }
        execv(argv[0], argv);
        _exit(127);
    }
    return pid;
}

/* Exit status of @p pid, waiting at most DEADLINE (then killed: -1). */
static int wait_exit(pid_t pid)
{
    double t0 = now_s();
    int st;
    while (now_s() - t0 < DEADLINE) {
        pid_t r = waitpid(pid, &st, WNOHANG);
        if (r == pid)
            return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        fx_msleep(10);
    }
    kill(pid, SIGKILL);
    waitpid(pid, &st, 0);
    return -1;
}

static const char *slurp(const char *path)
{
    static char buf[65536];
    FILE *f = fopen(path, "r");
    size_t n = 0;
    buf[0] = '\0';
    if (f) {
        n = fread(buf, 1, sizeof buf - 1, f);
        fclose(f);
    }
    buf[n] = '\0';
    return buf;
}

static int count_in_file(const char *path, const char *needle)
{
    char buf[1024];
    int c = 0;
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    while (fgets(buf, sizeof buf, f))
        c += strstr(buf, needle) != NULL;
    fclose(f);
    return c;
}

typedef struct vpr {
    pid_t pid;
    char link[256], log[256];
} vpr;

static void vp_start(vpr *v, const char *tag, const char *opts)
{
    char buf[1024], name[64];
    char *argv[FX_MAXARGS];
    int n = 0;
    double t0 = now_s();
    snprintf(name, sizeof name, "vp-link-%s", tag);
    snprintf(v->link, sizeof v->link, "%s", fx_tmp(name));
    snprintf(name, sizeof name, "vp-log-%s", tag);
    snprintf(v->log, sizeof v->log, "%s", fx_tmp(name));
    unlink(v->link);
    unlink(v->log);
    snprintf(buf, sizeof buf, "%s", opts);
    argv[n++] = (char *)fx_prog("AMP_VPRINTER");
    argv[n++] = "--link";
    argv[n++] = v->link;
    argv[n++] = "--log";
    argv[n++] = v->log;
    fx_split(buf, argv, n);
    v->pid = spawn(argv, NULL, NULL, NULL, NULL);
    while (access(v->link, F_OK) != 0 && now_s() - t0 < DEADLINE)
        fx_msleep(10);
    ck_assert_msg(access(v->link, F_OK) == 0, "virtual printer did not create %s", v->link);
}

static void vp_stop(vpr *v)
{
    int st;
    kill(v->pid, SIGTERM);
    waitpid(v->pid, &st, 0);
}

/* Commands the printer executed that are not the handshake (M110) */
static int executed_job_commands(const vpr *v)
{
    char buf[512];
    int c = 0;
    FILE *f = fopen(v->log, "r");
    if (!f)
        return 0;
    while (fgets(buf, sizeof buf, f))
        c += buf[0] != '#' && !strstr(buf, "M110") && !strstr(buf, "M115") && !strstr(buf, "M105"); /* the handshake */
    fclose(f);
    return c;
}

typedef struct dmn {
    pid_t pid;
    char sock[256], out[256], err[256];
} dmn;

static int try_connect(const char *sock)
{
    struct sockaddr_un sa;
    int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    snprintf(sa.sun_path, sizeof sa.sun_path, "%s", sock);
    if (fd >= 0 && connect(fd, (struct sockaddr *)&sa, sizeof sa) == 0)
        return fd;
    if (fd >= 0)
        close(fd);
    return -1;
}

/* Start the daemon; sock NULL = its default (tmpdir set: TMPDIR, no XDG_RUNTIME_DIR). Waits until it answers,
   or returns its exit status if it exits first (else -1 = running). */
static int daemon_start(dmn *d, const vpr *v, const char *tag, const char *sock, const char *opts,
                        const char *tmpdir)
{
    char buf[1024], name[64];
    char *argv[FX_MAXARGS];
    int n = 0, st;
    double t0 = now_s();
    snprintf(d->sock, sizeof d->sock, "%s", sock ? sock : ""); /* fx_tmp's buffers rotate */
    snprintf(name, sizeof name, "d-out-%s", tag);
    snprintf(d->out, sizeof d->out, "%s", fx_tmp(name));
    snprintf(name, sizeof name, "d-err-%s", tag);
    snprintf(d->err, sizeof d->err, "%s", fx_tmp(name));
    snprintf(buf, sizeof buf, "%s", opts);
    argv[n++] = (char *)fx_prog("AMP_BRIDGE");
    argv[n++] = (char *)v->link;
    argv[n++] = "--daemon";
    if (sock) {
        argv[n++] = "--socket";
        argv[n++] = d->sock;
    }
    fx_split(buf, argv, n);
    d->pid = spawn(argv, d->out, d->err, NULL, tmpdir);
    /* up when it says so on stderr (a connect could reach another daemon on the same path) */
    while (now_s() - t0 < DEADLINE) {
        const char *p;
        if (waitpid(d->pid, &st, WNOHANG) == d->pid)
            return WIFEXITED(st) ? WEXITSTATUS(st) : 128;
        if ((p = strstr(slurp(d->err), "control socket ")) != NULL && strchr(p, '\n')) {
            p += strlen("control socket ");
            snprintf(d->sock, sizeof d->sock, "%.*s", (int)strcspn(p, "\n"), p);
            return -1;
        }
        fx_msleep(10);
    }
    ck_abort_msg("daemon did not come up: %s", slurp(d->err));
    return -2;
}

/* A client with a line buffer. */
typedef struct cli {
    int fd;
    size_t len;
    char buf[1 << 17];
} cli;

static void cli_open(cli *c, const char *sock)
{
    c->fd = try_connect(sock);
    c->len = 0;
    ck_assert_msg(c->fd >= 0, "cannot connect to %s: %s", sock, strerror(errno));
}

static void cli_send(cli *c, const char *s, size_t n)
{
    while (n > 0) {
        ssize_t w = write(c->fd, s, n);
        ck_assert_msg(w > 0, "write: %s", strerror(errno));
        s += w;
        n -= (size_t)w;
    }
}

static void cli_say(cli *c, const char *s)
{
    cli_send(c, s, strlen(s));
}

/* One line (without the newline) into out: 1, 0 at EOF, -1 after DEADLINE. */
static int cli_line(cli *c, char *out, size_t cap)
{
    double t0 = now_s();
    for (;;) {
        char *nl = memchr(c->buf, '\n', c->len);
        struct pollfd p;
        ssize_t r;
        if (nl) {
            size_t n = (size_t)(nl - c->buf);
            snprintf(out, cap, "%.*s", (int)n, c->buf);
            memmove(c->buf, nl + 1, c->len - n - 1);
            c->len -= n + 1;
            return 1;
        }
        if (now_s() - t0 > DEADLINE)
            return -1;
        p.fd = c->fd;
        p.events = POLLIN;
        if (poll(&p, 1, 100) <= 0)
            continue;
        r = read(c->fd, c->buf + c->len, sizeof c->buf - c->len);
        if (r <= 0)
            return 0;
        c->len += (size_t)r;
    }
}

static void cli_close(cli *c)
{
    if (c->fd >= 0)
        close(c->fd);
    c->fd = -1;
}

/* One request on a fresh connection, its reply line (static). */
static const char *ask(const char *sock, const char *line)
{
    static cli c;
    static char out[8192];
    cli_open(&c, sock);
    cli_say(&c, line);
    cli_say(&c, "\n");
    ck_assert_msg(cli_line(&c, out, sizeof out) == 1, "no reply to %s", line);
    cli_close(&c);
    return out;
}

/* A number from a JSON status. */
static double status_num(const char *sock, const char *key, char *state, size_t cap)
{
    static br_jobj o;
    char why[200];
    const char *r = ask(sock, "{\"cmd\":\"status\"}");
    const br_jmember *m;
    ck_assert_msg(br_json_parse(&o, r, strlen(r), why, sizeof why) == 0, "%s: %s", why, r);
    if (state) {
        m = br_json_get(&o, "state");
        snprintf(state, cap, "%s", m && m->type == BR_J_STR ? m->str : "?");
    }
    m = br_json_get(&o, key);
    return m && m->type == BR_J_NUM ? m->num : -1;
}

/* Wait until the job state is @p want (or any end state when want is NULL). */
static void wait_state(const char *sock, const char *want)
{
    char st[64];
    double t0 = now_s();
    while (now_s() - t0 < DEADLINE) {
        status_num(sock, "acked", st, sizeof st);
        if (want ? strcmp(st, want) == 0 : strcmp(st, "printing") != 0 && strcmp(st, "stopping") != 0)
            return;
        fx_msleep(20);
    }
    ck_abort_msg("state %s never reached (now %s)", want ? want : "end", st);
}

static void wait_acked(const char *sock, long n)
{
    double t0 = now_s();
    while (now_s() - t0 < DEADLINE && status_num(sock, "acked", NULL, 0) < n)
        fx_msleep(20);
    ck_assert_int_ge((long)status_num(sock, "acked", NULL, 0), n);
}

static void daemon_quit(dmn *d)
{
    const char *r = ask(d->sock, "quit");
    ck_assert_msg(strncmp(r, "ok bye", 6) == 0, "%s", r);
    ck_assert_int_eq(wait_exit(d->pid), 0);
    ck_assert_msg(strstr(slurp(d->err), "Sanitizer") == NULL, "%s", slurp(d->err));
}

/* Job: a header then n unique moves (as tests/test_bridge.c). */
static const char *make_job(const char *name, int n, const char *extra_at_10)
{
    static char path[256];
    FILE *f;
    int i;
    snprintf(path, sizeof path, "%s", fx_tmp(name));
    f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fprintf(f, "; ampath test job\nG90\nM82\nG92 E0\n");
    for (i = 1; i <= n; i++) {
        fprintf(f, "G1 X%.2f Y%.2f E%.4f F%d ; move %d\n", 100 + 40 * sin(i * 0.1), 100 + 40 * cos(i * 0.13),
                0.01 * i, 1200 + i % 7, i);
        if (i == 10 && extra_at_10)
            fprintf(f, "%s\n", extra_at_10);
    }
    fclose(f);
    return path;
}

typedef struct lines {
    int n;
    char l[4000][96];
} lines;

static void moves_of(const char *path, int is_log, lines *out)
{
    char buf[512];
    FILE *f = fopen(path, "r");
    ck_assert_ptr_nonnull(f);
    out->n = 0;
    while (fgets(buf, sizeof buf, f) && out->n < 4000) {
        char *s = buf, *c;
        if (is_log) {
            if (buf[0] == '#' || !(s = strchr(buf, ' ')))
                continue;
            s++;
        }
        if ((c = strchr(s, ';')) != NULL)
            *c = '\0';
        s[strcspn(s, "\r\n")] = '\0';
        while (*s && s[strlen(s) - 1] == ' ')
            s[strlen(s) - 1] = '\0';
        if (strncmp(s, "G1 X", 4) == 0 && strstr(s, " E") != NULL)
            snprintf(out->l[out->n++], sizeof out->l[0], "%s", s);
    }
    fclose(f);
}

static void assert_executed_equals_job(const vpr *v, const char *job, int upto)
{
    static lines a, b;
    int i, n;
    moves_of(job, 0, &a);
    moves_of(v->log, 1, &b);
    n = upto >= 0 ? upto : a.n;
    ck_assert_msg(b.n == n, "executed %d moves, job has %d", b.n, n);
    for (i = 0; i < n; i++)
        ck_assert_msg(strcmp(a.l[i], b.l[i]) == 0, "move %d: job '%s', executed '%s'", i + 1, a.l[i], b.l[i]);
}

/* ------------------------------------------------------------------ the daemon at work */

START_TEST(json_client_subscribes_and_follows_a_whole_job)
{
    vpr v;
    dmn d;
    cli c;
    static br_jobj o;
    char line[8192], why[200], req2[600];
    const char *job = make_job("my job.gcode", 200, NULL); /* a path with a space, in JSON */
    long last_acked = -1, nprog = 0, total = -1;
    int saw_printing = 0, saw_done_state = 0, ended = 0;
    vp_start(&v, "a", "--turnaround 3");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), FAST, NULL), -1);
    cli_open(&c, d.sock);
    cli_say(&c, "{\"cmd\":\"subscribe\",\"id\":1}\n");
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_int_eq(br_json_parse(&o, line, strlen(line), why, sizeof why), 0);
    ck_assert(br_json_get(&o, "ok")->b == 1 && br_json_get(&o, "id")->num == 1);
    ck_assert_str_eq(br_json_get(&o, "state")->str, "idle");
    snprintf(req2, sizeof req2, "{\"cmd\":\"submit\",\"path\":\"%s\",\"id\":\"job-1\"}\n", job);
    cli_say(&c, req2);
    /* replies and events share the line stream: events carry "event", replies "ok" */
    while (!ended) {
        const br_jmember *ev;
        ck_assert_msg(cli_line(&c, line, sizeof line) == 1, "stream ended early");
        ck_assert_msg(br_json_parse(&o, line, strlen(line), why, sizeof why) == 0, "%s: %s", why, line);
        ev = br_json_get(&o, "event");
        if (!ev) {
            ck_assert_msg(br_json_get(&o, "ok")->b == 1, "%s", line);
            ck_assert_str_eq(br_json_get(&o, "id")->str, "job-1");
            total = (long)br_json_get(&o, "total")->num;
            continue;
        }
        if (strcmp(ev->str, "state") == 0) {
            saw_printing |= strcmp(br_json_get(&o, "state")->str, "printing") == 0;
            saw_done_state |= strcmp(br_json_get(&o, "state")->str, "done") == 0;
        } else if (strcmp(ev->str, "progress") == 0) {
            long a = (long)br_json_get(&o, "acked")->num;
            ck_assert_int_ge(a, last_acked); /* never backwards */
            ck_assert_int_eq((long)br_json_get(&o, "total")->num, 203);
            last_acked = a;
            nprog++;
        } else if (strcmp(ev->str, "end") == 0) {
            ck_assert_str_eq(br_json_get(&o, "state")->str, "done");
            ck_assert_int_eq((long)br_json_get(&o, "acked")->num, 203);
            ck_assert_int_eq((long)br_json_get(&o, "total")->num, 203);
            ck_assert_int_eq((long)br_json_get(&o, "errors")->num, 0);
            ended = 1;
        } else {
            ck_abort_msg("unexpected event: %s", line);
        }
    }
    ck_assert_int_eq(total, 203); /* 3 header commands and 200 moves */
    ck_assert_int_ge(nprog, 1);
    ck_assert(saw_printing);
    ck_assert(saw_done_state); /* before the end: a host that stops reading at "end" has read it */
    cli_close(&c);
    daemon_quit(&d);
    vp_stop(&v);
    assert_executed_equals_job(&v, job, -1);
}
END_TEST

/* A job the firmware refuses (Klipper without G28: `!! Must home axis first` from the first move on): a
 * subscriber hears "error" events of kind "firmware", the first naming job line 5 (the comment, G90, M82 and
 * G92 come first), then the end with state "error" and as many errors as events. Before, only the end came,
 * with errors 0 (an independent client found it: the firmware's own complaints were not events). */
START_TEST(a_firmware_refusal_is_an_error_event_before_the_end)
{
    vpr v;
    dmn d;
    cli c;
    static br_jobj o;
    char line[8192], why[200], sub[600];
    const char *job = make_job("refused.gcode", 100, NULL);
    int ended = 0, errors = 0, first_line = -1;
    vp_start(&v, "a", "--flavor klipper");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), "--flavor klipper", NULL), -1);
    cli_open(&c, d.sock);
    cli_say(&c, "{\"cmd\":\"subscribe\"}\n");
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    snprintf(sub, sizeof sub, "{\"cmd\":\"submit\",\"path\":\"%s\"}\n", job);
    cli_say(&c, sub);
    while (!ended) {
        const br_jmember *ev;
        ck_assert_msg(cli_line(&c, line, sizeof line) == 1, "stream ended early");
        ck_assert_msg(br_json_parse(&o, line, strlen(line), why, sizeof why) == 0, "%s: %s", why, line);
        if (!(ev = br_json_get(&o, "event")))
            continue;
        if (strcmp(ev->str, "error") == 0) {
            ck_assert_str_eq(br_json_get(&o, "kind")->str, "firmware");
            ck_assert_ptr_nonnull(strstr(br_json_get(&o, "text")->str, "!! Must home axis first"));
            if (errors++ == 0)
                first_line = (int)br_json_get(&o, "line")->num;
        } else if (strcmp(ev->str, "end") == 0) {
            ck_assert_int_ge(errors, 1); /* the events came first */
            ck_assert_str_eq(br_json_get(&o, "state")->str, "error");
            ck_assert_int_eq((long)br_json_get(&o, "errors")->num, errors);
            ended = 1;
        }
    }
    ck_assert_int_eq(first_line, 5);
    cli_close(&c);
    daemon_quit(&d);
    vp_stop(&v);
}
END_TEST

START_TEST(client_that_never_reads_is_dropped_while_printing_goes_on)
{
    vpr v;
    dmn d;
    cli *flood = calloc(1, sizeof *flood);
    const char *job = make_job("job.gcode", 300, NULL);
    char chunk[7 * 512], line[8192];
    double t0;
    int i, dropped = 0;
    vp_start(&v, "a", "--turnaround 5");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), FAST, NULL), -1);
    snprintf(line, sizeof line, "submit %s", job);
    ck_assert_ptr_nonnull(strstr(ask(d.sock, line), "ok started"));
    for (i = 0; i < 512; i++)
        memcpy(chunk + 7 * i, "status\n", 7);
    cli_open(flood, d.sock);
    fcntl(flood->fd, F_SETFL, O_NONBLOCK);
    /* ask and ask and never read: the daemon must cut it off instead of blocking on it */
    for (t0 = now_s(); !dropped && now_s() - t0 < DEADLINE;) {
        ssize_t w = send(flood->fd, chunk, sizeof chunk, MSG_NOSIGNAL);
        if (w < 0 && errno != EAGAIN) {
            dropped = 1; /* EPIPE / ECONNRESET: the daemon closed it */
        } else if (w < 0) {
            struct pollfd p = {flood->fd, POLLOUT, 0};
            poll(&p, 1, 100);
            dropped = (p.revents & (POLLHUP | POLLERR)) != 0;
        }
    }
    ck_assert_msg(dropped, "the daemon kept a client that never reads");
    /* meanwhile everyone else is served and the job goes on to the end (a daemon blocked in write()
       towards the flooder would never get there) */
    wait_state(d.sock, NULL);
    ck_assert_ptr_nonnull(strstr(ask(d.sock, "status"), "ok state=done"));
    cli_close(flood);
    free(flood);
    daemon_quit(&d);
    vp_stop(&v);
    assert_executed_equals_job(&v, job, -1);
}
END_TEST

START_TEST(crowd_of_idle_clients_cannot_lock_out_estop)
{
    vpr v;
    dmn d;
    static cli crowd[BR_CL_NORMAL + 8];
    cli c;
    char line[8192];
    int i;
    vp_start(&v, "a", "--flavor klipper");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), "--flavor klipper --client-timeout 600",
                                  NULL),
                     -1);
    /* fill every ordinary slot (each proves it was admitted), then more that just sit there */
    for (i = 0; i < BR_CL_NORMAL; i++) {
        cli_open(&crowd[i], d.sock);
        cli_say(&crowd[i], "status\n");
        ck_assert_int_eq(cli_line(&crowd[i], line, sizeof line), 1);
        ck_assert_ptr_nonnull(strstr(line, "ok state=idle"));
    }
    /* an overflow connection takes priority commands only, answered in one line */
    cli_open(&c, d.sock);
    cli_say(&c, "submit /tmp/x.gcode\n");
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_msg(strstr(line, "error too many clients") != NULL, "%s", line);
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 0); /* and closed */
    cli_close(&c);
    for (i = BR_CL_NORMAL; i < BR_CL_NORMAL + 8; i++)
        cli_open(&crowd[i], d.sock); /* more than the reserved slots, all silent */
    cli_open(&c, d.sock);
    cli_say(&c, "estop\n");
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_msg(strncmp(line, "ok emergency stop", 17) == 0, "%s", line);
    cli_close(&c);
    {
        /* the printer got it */
        double t0 = now_s();
        while (count_in_file(v.log, "# shutdown") == 0 && now_s() - t0 < DEADLINE)
            fx_msleep(20);
        ck_assert_int_eq(count_in_file(v.log, "# shutdown"), 1);
    }
    /* quit is no priority command: refused while the crowd holds every slot */
    ck_assert_ptr_nonnull(strstr(ask(d.sock, "quit"), "error too many clients"));
    for (i = 0; i < BR_CL_NORMAL + 8; i++)
        cli_close(&crowd[i]);
    daemon_quit(&d);
    vp_stop(&v);
}
END_TEST

START_TEST(idle_client_is_closed_after_the_client_timeout)
{
    vpr v;
    dmn d;
    cli c;
    char line[8192];
    vp_start(&v, "a", "");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), "--client-timeout 0.5 --boot-wait 0.3",
                                  NULL),
                     -1);
    cli_open(&c, d.sock);
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_str_eq(line, "error idle timeout: closed");
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 0);
    cli_close(&c);
    /* a subscriber waits for events as long as it likes: still there after several timeouts */
    cli_open(&c, d.sock);
    cli_say(&c, "subscribe\n");
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_msg(strncmp(line, "ok subscribed", 13) == 0, "%s", line);
    {
        struct pollfd p = {c.fd, POLLIN, 0};
        ck_assert_int_eq(poll(&p, 1, 2000), 0); /* nothing arrives, the connection stays open */
    }
    cli_say(&c, "status\n");
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_ptr_nonnull(strstr(line, "ok state=idle"));
    cli_close(&c);
    daemon_quit(&d);
    vp_stop(&v);
}
END_TEST

START_TEST(overlong_line_is_discarded_whole_and_nul_does_not_wedge)
{
    vpr v;
    dmn d;
    cli c;
    char line[8192];
    static char big[3 * BR_CL_IN + 16];
    static const char nul[] = "stat\0us\n";
    vp_start(&v, "a", "");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), "--boot-wait 0.3", NULL), -1);
    cli_open(&c, d.sock);
    /* 3 buffers of x ending in "quit": the tail must not run as a command */
    memset(big, 'x', sizeof big);
    memcpy(big + sizeof big - 6, "quit\n", 5);
    cli_send(&c, big, sizeof big - 1);
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_msg(strstr(line, "error line too long") != NULL, "%s", line);
    cli_send(&c, nul, sizeof nul - 1);
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_msg(strstr(line, "error NUL byte") != NULL, "%s", line);
    /* a JSON line too long is answered in JSON */
    big[0] = '{';
    cli_send(&c, big, sizeof big - 1);
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_msg(strncmp(line, "{\"ok\":false,\"error\":\"line too long", 34) == 0, "%s", line);
    /* an unknown command: one line, and the connection still works */
    cli_say(&c, "frobnicate\nstatus\n");
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_msg(strncmp(line, "error unknown command 'frobnicate'", 34) == 0, "%s", line);
    ck_assert_int_eq(cli_line(&c, line, sizeof line), 1);
    ck_assert_ptr_nonnull(strstr(line, "ok state=idle"));
    cli_close(&c);
    ck_assert_int_eq(waitpid(d.pid, NULL, WNOHANG), 0); /* no "quit" ran */
    daemon_quit(&d);
    vp_stop(&v);
}
END_TEST

static void sigterm_mid_job(int keep_hot)
{
    vpr v;
    dmn d;
    char opts[256], line[600];
    const char *job = make_job("a \"quoted\" job.gcode", 1000, NULL), *out, *p; /* 10 s: stopped long before */
    long last = 0, resume = 0;
    int rc;
    static lines ex;
    vp_start(&v, "a", "--turnaround 10");
    snprintf(opts, sizeof opts, "%s%s", FAST, keep_hot ? " --keep-hot" : "");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), opts, NULL), -1);
    /* a path with spaces and quotes, in the plain form */
    snprintf(line, sizeof line, "submit \"%.*s\\\"quoted\\\" job.gcode\"", (int)(strstr(job, "\"") - job), job);
    ck_assert_ptr_nonnull(strstr(ask(d.sock, line), "ok started"));
    wait_acked(d.sock, 20);
    kill(d.pid, SIGTERM); /* what systemctl stop sends */
    rc = wait_exit(d.pid);
    ck_assert_msg(strstr(slurp(d.err), "Sanitizer") == NULL, "%s", slurp(d.err));
    out = slurp(d.out);
    ck_assert_msg(rc == 1, "exit %d: %s", rc, out);
    ck_assert_msg(strstr(out, "stopped: interrupted") != NULL, "%s", out);
    p = strstr(out, "last acknowledged job line ");
    ck_assert_ptr_nonnull(p);
    ck_assert_int_eq(sscanf(p, "last acknowledged job line %ld; resume with --resume-from %ld", &last, &resume), 2);
    ck_assert_int_eq(resume, last + 1);
    ck_assert_int_lt(last, 1004);
    ck_assert_int_eq(access(d.sock, F_OK), -1); /* its socket is gone */
    vp_stop(&v);
    /* the lines in flight were acknowledged: the printer ran exactly the moves up to the reported line */
    assert_executed_equals_job(&v, job, (int)last - 4);
    moves_of(v.log, 1, &ex);
    if (keep_hot) {
        ck_assert_int_eq(count_in_file(v.log, "M104 S0"), 0);
        ck_assert_ptr_null(strstr(out, "safe end"));
    } else {
        /* then heaters and fan off, and no motion after them */
        char buf[256];
        int after = 0, moves_after = 0, n104 = 0;
        FILE *f = fopen(v.log, "r");
        ck_assert_ptr_nonnull(strstr(out, "safe end (heaters and fan off: M104 S0, M140 S0, M107): acknowledged"));
        while (fgets(buf, sizeof buf, f)) {
            if (strstr(buf, " M104 S0"))
                after = 1, n104++;
            if (after && (strstr(buf, " G1 ") || strstr(buf, " G0 ") || strstr(buf, " G28")))
                moves_after++;
        }
        fclose(f);
        ck_assert_int_eq(n104, 1);
        ck_assert_int_eq(count_in_file(v.log, " M140 S0"), 1);
        ck_assert_int_eq(count_in_file(v.log, " M107"), 1);
        ck_assert_int_eq(moves_after, 0);
    }
}

START_TEST(sigterm_mid_job_waits_for_acks_reports_resume_line_and_turns_heaters_off)
{
    sigterm_mid_job(0);
}
END_TEST

START_TEST(sigterm_mid_job_with_keep_hot_leaves_the_heaters_alone)
{
    sigterm_mid_job(1);
}
END_TEST

START_TEST(cancel_finishes_the_lines_in_flight_then_turns_heaters_off)
{
    vpr v;
    dmn d;
    char line[600];
    const char *job = make_job("job.gcode", 1000, NULL), *r;
    long last;
    vp_start(&v, "a", "--turnaround 10");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), FAST, NULL), -1);
    snprintf(line, sizeof line, "{\"cmd\":\"submit\",\"path\":\"%s\"}", job);
    ck_assert_ptr_nonnull(strstr(ask(d.sock, line), "\"ok\":true"));
    wait_acked(d.sock, 10);
    ck_assert_ptr_nonnull(strstr(ask(d.sock, "{\"cmd\":\"cancel\",\"id\":9}"), "{\"ok\":true,\"id\":9"));
    wait_state(d.sock, "cancelled");
    last = (long)status_num(d.sock, "last_acked_line", NULL, 0);
    r = ask(d.sock, "cancel");
    ck_assert_str_eq(r, "error no job running");
    daemon_quit(&d);
    vp_stop(&v);
    assert_executed_equals_job(&v, job, (int)last - 4);
    ck_assert_int_eq(count_in_file(v.log, " M104 S0"), 1);
}
END_TEST

START_TEST(second_daemon_on_the_same_socket_refuses_and_leaves_the_first_alone)
{
    vpr v1, v2;
    dmn a, b;
    char sock[256];
    snprintf(sock, sizeof sock, "%s", fx_tmp("ctl.sock"));
    vp_start(&v1, "1", "");
    vp_start(&v2, "2", "");
    ck_assert_int_eq(daemon_start(&a, &v1, "a", sock, "--boot-wait 0.3", NULL), -1);
    ck_assert_int_eq(daemon_start(&b, &v2, "b", sock, "--boot-wait 0.3", NULL), 2);
    ck_assert_msg(strstr(slurp(b.err), "already listening") != NULL, "%s", slurp(b.err));
    ck_assert_ptr_nonnull(strstr(ask(sock, "status"), "ok state=idle"));
    /* the refused daemon never opened its printer (opening a port resets many boards) */
    vp_stop(&v2);
    ck_assert_int_eq(count_in_file(v2.log, "M110"), 0);
    daemon_quit(&a);
    vp_stop(&v1);
}
END_TEST

START_TEST(socket_path_that_is_not_a_stale_socket_is_never_unlinked)
{
    vpr v;
    dmn d;
    char file[256], sock[256];
    struct sockaddr_un sa;
    struct stat st;
    int fd;
    FILE *f;
    snprintf(file, sizeof file, "%s", fx_tmp("precious.txt"));
    snprintf(sock, sizeof sock, "%s", fx_tmp("stale.sock"));
    f = fopen(file, "w");
    fputs("precious\n", f);
    fclose(f);
    vp_start(&v, "a", "");
    ck_assert_int_eq(daemon_start(&d, &v, "a", file, "--boot-wait 0.3", NULL), 2);
    ck_assert_ptr_nonnull(strstr(slurp(d.err), "not a socket"));
    ck_assert_str_eq(slurp(file), "precious\n");
    /* another user's stale socket: left alone */
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    snprintf(sa.sun_path, sizeof sa.sun_path, "%.100s", sock);
    unlink(sock);
    fd = socket(AF_UNIX, SOCK_STREAM, 0);
    ck_assert_int_eq(bind(fd, (struct sockaddr *)&sa, sizeof sa), 0);
    close(fd); /* no listener: stale */
    if (getuid() == 0) {
        ck_assert_int_eq(chown(sock, 65534, 65534), 0);
        ck_assert_int_eq(daemon_start(&d, &v, "b", sock, "--boot-wait 0.3", NULL), 2);
        ck_assert_msg(strstr(slurp(d.err), "socket of uid 65534") != NULL, "%s", slurp(d.err));
        ck_assert_int_eq(lstat(sock, &st), 0);
        ck_assert_int_eq(chown(sock, 0, 0), 0);
    }
    /* our own stale socket (a crashed daemon): replaced */
    ck_assert_int_eq(daemon_start(&d, &v, "c", sock, "--boot-wait 0.3", NULL), -1);
    ck_assert_int_eq(stat(sock, &st), 0);
    ck_assert_int_eq(st.st_mode & 0777, 0600);
    daemon_quit(&d);
    ck_assert_int_eq(access(sock, F_OK), -1);
    vp_stop(&v);
}
END_TEST

START_TEST(default_socket_lives_in_a_private_directory_and_a_squatted_one_is_refused)
{
    vpr v;
    dmn d;
    char tmp[256], dir[300], link[300], sockp[400];
    struct stat st;
    snprintf(tmp, sizeof tmp, "%s", fx_tmp("tmpdir"));
    snprintf(dir, sizeof dir, "%s/ampath-bridge-%ld", tmp, (long)getuid());
    snprintf(sockp, sizeof sockp, "%s/ctl.sock", dir);
    mkdir(tmp, 0755);
    vp_start(&v, "a", "");
    /* a directory others may write into: whoever planted it would receive our commands */
    ck_assert_int_eq(mkdir(dir, 0777), 0);
    chmod(dir, 0777);
    ck_assert_int_eq(daemon_start(&d, &v, "a", NULL, "--boot-wait 0.3", tmp), 2);
    ck_assert_msg(strstr(slurp(d.err), "is not private") != NULL, "%s", slurp(d.err));
    if (getuid() == 0) {
        chmod(dir, 0700);
        ck_assert_int_eq(chown(dir, 65534, 65534), 0); /* another user's directory */
        ck_assert_int_eq(daemon_start(&d, &v, "b", NULL, "--boot-wait 0.3", tmp), 2);
        ck_assert_msg(strstr(slurp(d.err), "owner uid 65534") != NULL, "%s", slurp(d.err));
    }
    rmdir(dir);
    /* a symlink to somewhere else */
    snprintf(link, sizeof link, "%s/elsewhere", tmp);
    mkdir(link, 0700);
    ck_assert_int_eq(symlink(link, dir), 0);
    ck_assert_int_eq(daemon_start(&d, &v, "c", NULL, "--boot-wait 0.3", tmp), 2);
    ck_assert_msg(strstr(slurp(d.err), "is not a directory") != NULL, "%s", slurp(d.err));
    unlink(dir);
    /* nothing there: created 0700, socket 0600 inside */
    ck_assert_int_eq(daemon_start(&d, &v, "d", NULL, "--boot-wait 0.3", tmp), -1);
    ck_assert_str_eq(d.sock, sockp);
    ck_assert_int_eq(lstat(dir, &st), 0);
    ck_assert(S_ISDIR(st.st_mode));
    ck_assert_int_eq(st.st_mode & 0777, 0700);
    ck_assert_int_eq(stat(sockp, &st), 0);
    ck_assert_int_eq(st.st_mode & 0777, 0600);
    daemon_quit(&d);
    vp_stop(&v);
    rmdir(dir);
    rmdir(link);
    rmdir(tmp);
}
END_TEST

START_TEST(two_programs_never_share_the_printer)
{
    vpr v;
    dmn d;
    char *argv[12], out[256];
    int n = 0, rc, fd;
    const char *job = make_job("job.gcode", 20, NULL);
    vp_start(&v, "a", "");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), "--boot-wait 0.3", NULL), -1);
    snprintf(out, sizeof out, "%s", fx_tmp("oneshot-out"));
    argv[n++] = (char *)fx_prog("AMP_BRIDGE");
    argv[n++] = v.link;
    argv[n++] = (char *)job;
    argv[n++] = "--boot-wait";
    argv[n++] = "0.3";
    argv[n] = NULL;
    rc = wait_exit(spawn(argv, out, out, NULL, NULL));
    ck_assert_msg(rc == 2, "exit %d: %s", rc, slurp(out));
    ck_assert_msg(strstr(slurp(out), "in use by another program") != NULL, "%s", slurp(out));
    daemon_quit(&d);
    /* any program holding the lock (flock, as OctoPrint's pyserial exclusive=True) keeps the bridge out */
    fd = open(v.link, O_RDWR | O_NOCTTY | O_NONBLOCK);
    ck_assert_int_ge(fd, 0);
    ck_assert_int_eq(flock(fd, LOCK_EX | LOCK_NB), 0);
    rc = wait_exit(spawn(argv, out, out, NULL, NULL));
    ck_assert_msg(rc == 2, "exit %d: %s", rc, slurp(out));
    close(fd);
    /* released: the job runs */
    rc = wait_exit(spawn(argv, out, out, NULL, NULL));
    ck_assert_msg(rc == 0, "exit %d: %s", rc, slurp(out));
    vp_stop(&v);
    assert_executed_equals_job(&v, job, -1);
}
END_TEST

START_TEST(fifo_and_device_submits_are_refused_at_once)
{
    vpr v;
    dmn d;
    char fifo[256], line[600];
    const char *r;
    snprintf(fifo, sizeof fifo, "%s", fx_tmp("job-fifo.gcode"));
    unlink(fifo);
    ck_assert_int_eq(mkfifo(fifo, 0600), 0);
    vp_start(&v, "a", "");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), "--boot-wait 0.3", NULL), -1);
    snprintf(line, sizeof line, "submit %s", fifo);
    r = ask(d.sock, line); /* no writer: an open() that blocked would hang the daemon here */
    ck_assert_msg(strstr(r, "is not a regular file") != NULL, "%s", r);
    r = ask(d.sock, "submit /dev/zero");
    ck_assert_msg(strstr(r, "is not a regular file") != NULL, "%s", r);
    r = ask(d.sock, "{\"cmd\":\"submit\",\"path\":\"/dev/urandom\"}");
    ck_assert_msg(strstr(r, "\"ok\":false") != NULL && strstr(r, "is not a regular file") != NULL, "%s", r);
    ck_assert_ptr_nonnull(strstr(ask(d.sock, "status"), "ok state=idle"));
    daemon_quit(&d);
    vp_stop(&v);
    ck_assert_int_eq(executed_job_commands(&v), 0);
    unlink(fifo);
}
END_TEST

START_TEST(job_piped_on_stdin_is_refused_and_a_redirected_file_runs)
{
    vpr v;
    char *argv[12], out[256], cmd[1024];
    int n = 0, rc;
    const char *job = make_job("job.gcode", 30, NULL);
    vp_start(&v, "a", "");
    snprintf(out, sizeof out, "%s", fx_tmp("oneshot-out"));
    argv[n++] = (char *)fx_prog("AMP_BRIDGE");
    argv[n++] = v.link;
    argv[n++] = "/dev/stdin";
    argv[n++] = "--boot-wait";
    argv[n++] = "0.3";
    argv[n] = NULL;
    /* a pipe: was "sent 0 commands", exit 0 */
    snprintf(cmd, sizeof cmd, "cat %s | %s %s /dev/stdin --boot-wait 0.3 > %s 2>&1", job, fx_prog("AMP_BRIDGE"), v.link,
             out);
    rc = system(cmd);
    ck_assert_msg(WIFEXITED(rc) && WEXITSTATUS(rc) == 2, "exit %d: %s", WEXITSTATUS(rc), slurp(out));
    ck_assert_msg(strstr(slurp(out), "is not a regular file") != NULL, "%s", slurp(out));
    ck_assert_int_eq(executed_job_commands(&v), 0);
    /* stdin redirected from a file is a regular file: streamed */
    rc = wait_exit(spawn(argv, out, out, job, NULL));
    ck_assert_msg(rc == 0, "exit %d: %s", rc, slurp(out));
    ck_assert_ptr_nonnull(strstr(slurp(out), "acknowledged 33"));
    vp_stop(&v);
    assert_executed_equals_job(&v, job, -1);
}
END_TEST

static void write_file(const char *path, const char *text, size_t n)
{
    FILE *f = fopen(path, "wb");
    ck_assert_ptr_nonnull(f);
    fwrite(text, 1, n, f);
    fclose(f);
}

START_TEST(only_gcode_is_submitted_and_nothing_is_sent_before_the_check)
{
    static const struct {
        const char *name, *text;
        size_t n;
        const char *why;
    } bad[] = {
#define TXT(s) s, sizeof s - 1
        {"passwd.gcode", TXT("G90\nroot:x:0:0:root:/root:/bin/bash\n"), "not a G-code command"},
        {"star.gcode", TXT("G90\nG1 X10 Y10\nM117 50*2\n"), "'*' in a command"},
        {"ctl.gcode", TXT("G90\nG1 X1\x1b[2J\n"), "control byte 0x1b"},
        {"nul.gcode", TXT("G90\nG1 X1\0junk\nG1 X2\n"), "NUL byte"},
        {"empty.gcode", TXT("; nothing but comments\n\n   \n"), "no commands to send"},
        {"words.gcode", TXT("The quick brown fox\n"), "not a G-code command"},
#undef TXT
    };
    vpr v;
    dmn d;
    size_t i;
    char line[600];
    vp_start(&v, "a", "");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), "--boot-wait 0.3", NULL), -1);
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        const char *path = fx_tmp(bad[i].name), *r;
        write_file(path, bad[i].text, bad[i].n);
        snprintf(line, sizeof line, "submit %s", path);
        r = ask(d.sock, line);
        ck_assert_msg(strncmp(r, "error ", 6) == 0 && strstr(r, bad[i].why) != NULL, "%s: %s", bad[i].name, r);
    }
    daemon_quit(&d);
    vp_stop(&v);
    ck_assert_int_eq(executed_job_commands(&v), 0);
}
END_TEST

START_TEST(log_is_private_and_printer_echoes_of_job_lines_stay_off_stderr)
{
    vpr v;
    dmn d;
    char opts[600], line[600];
    struct stat st;
    char log[256];
    const char *job = fx_tmp("homed.gcode");
    FILE *f = fopen(job, "w");
    int i;
    /* homed first: Klipper refuses moves before G28 (the job would stop there) */
    ck_assert_ptr_nonnull(f);
    fputs("G28\nG90\nM82\nG92 E0\n", f);
    for (i = 1; i <= 40; i++)
        fprintf(f, "G1 X%d Y%d E%.2f F1200\n%s", 100 + i, 100 + i % 7, 0.01 * i, i == 10 ? "FROBNICATE SECRET=hunter2\n" : "");
    fclose(f);
    snprintf(log, sizeof log, "%s", fx_tmp("bridge.log"));
    unlink(log);
    vp_start(&v, "a", "--flavor klipper");
    snprintf(opts, sizeof opts, "--flavor klipper --timeout 1 --log %s", log);
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), opts, NULL), -1);
    ck_assert_int_eq(stat(log, &st), 0);
    ck_assert_int_eq(st.st_mode & 0777, 0600);
    snprintf(line, sizeof line, "submit %s", job);
    ck_assert_ptr_nonnull(strstr(ask(d.sock, line), "ok started"));
    wait_state(d.sock, NULL);
    daemon_quit(&d);
    vp_stop(&v);
    /* the printer's complaint is reported, without the job's words */
    ck_assert_msg(strstr(slurp(d.err), "Unknown command") != NULL, "%s", slurp(d.err));
    ck_assert_msg(strstr(slurp(d.err), "FROBNICATE") == NULL, "%s", slurp(d.err));
    ck_assert_msg(strstr(slurp(d.err), "hunter2") == NULL, "%s", slurp(d.err));
}
END_TEST

/* The Python client of docs/bridge.md, extracted and run as it stands: the documented example works. */
START_TEST(python_example_in_the_docs_follows_a_job_to_its_end)
{
    vpr v;
    dmn d;
    static char doc[1 << 17];
    char script[256], out[256], cmd[1200];
    const char *job = make_job("job.gcode", 60, NULL), *a, *b;
    FILE *f = fopen("docs/bridge.md", "r");
    size_t n;
    int rc;
    ck_assert_msg(f != NULL, "docs/bridge.md not found: run from the source tree (make check does)");
    n = fread(doc, 1, sizeof doc - 1, f);
    fclose(f);
    doc[n] = '\0';
    a = strstr(doc, "```python\n");
    ck_assert_ptr_nonnull(a);
    a += strlen("```python\n");
    b = strstr(a, "```");
    ck_assert_ptr_nonnull(b);
    snprintf(script, sizeof script, "%s", fx_tmp("follow.py"));
    write_file(script, a, (size_t)(b - a));
    if (system("python3 -c 'import json, socket' >/dev/null 2>&1") != 0) {
        fprintf(stderr, "python_example_in_the_docs_follows_a_job_to_its_end: no python3, not run\n");
        return;
    }
    vp_start(&v, "a", "--turnaround 2");
    ck_assert_int_eq(daemon_start(&d, &v, "a", fx_tmp("ctl.sock"), FAST, NULL), -1);
    snprintf(out, sizeof out, "%s", fx_tmp("follow.out"));
    snprintf(cmd, sizeof cmd, "python3 %s %s %s > %s 2>&1", script, d.sock, job, out);
    rc = system(cmd);
    ck_assert_msg(WIFEXITED(rc) && WEXITSTATUS(rc) == 0, "exit %d: %s", WEXITSTATUS(rc), slurp(out));
    ck_assert_msg(strstr(slurp(out), "done - resume with --resume-from 65") != NULL, "%s", slurp(out));
    ck_assert_msg(strstr(slurp(out), "/63 (") != NULL, "%s",
                  slurp(out));
    /* refused jobs end it with the reason */
    snprintf(cmd, sizeof cmd, "python3 %s %s /dev/zero > %s 2>&1", script, d.sock, out);
    rc = system(cmd);
    ck_assert_msg(WIFEXITED(rc) && WEXITSTATUS(rc) == 1, "exit %d: %s", WEXITSTATUS(rc), slurp(out));
    ck_assert_ptr_nonnull(strstr(slurp(out), "refused: /dev/zero is not a regular file"));
    daemon_quit(&d);
    vp_stop(&v);
    assert_executed_equals_job(&v, job, -1);
}
END_TEST

static Suite *daemon_suite(void)
{
    Suite *s = suite_create("daemon");
    TCase *unit = tcase_create("language"), *tc = tcase_create("daemon");
    tcase_add_test(unit, plain_submit_takes_quoted_paths_with_spaces_and_refuses_stray_words);
    tcase_add_test(unit, unknown_command_nul_and_control_bytes_answer_one_line);
    tcase_add_test(unit, json_requests_parse_with_escapes_and_ids);
    tcase_add_test(unit, json_parser_refuses_what_it_does_not_understand);
    tcase_add_test(unit, json_writer_escapes_control_bytes_and_repairs_garbled_utf8);
    tcase_add_test(unit, plain_replies_quote_values_and_never_hold_a_second_line);
    suite_add_tcase(s, unit);
    tcase_set_timeout(tc, 600);
    tcase_add_test(tc, json_client_subscribes_and_follows_a_whole_job);
    tcase_add_test(tc, a_firmware_refusal_is_an_error_event_before_the_end);
    tcase_add_test(tc, client_that_never_reads_is_dropped_while_printing_goes_on);
    tcase_add_test(tc, crowd_of_idle_clients_cannot_lock_out_estop);
    tcase_add_test(tc, idle_client_is_closed_after_the_client_timeout);
    tcase_add_test(tc, overlong_line_is_discarded_whole_and_nul_does_not_wedge);
    tcase_add_test(tc, sigterm_mid_job_waits_for_acks_reports_resume_line_and_turns_heaters_off);
    tcase_add_test(tc, sigterm_mid_job_with_keep_hot_leaves_the_heaters_alone);
    tcase_add_test(tc, cancel_finishes_the_lines_in_flight_then_turns_heaters_off);
    tcase_add_test(tc, second_daemon_on_the_same_socket_refuses_and_leaves_the_first_alone);
    tcase_add_test(tc, socket_path_that_is_not_a_stale_socket_is_never_unlinked);
    tcase_add_test(tc, default_socket_lives_in_a_private_directory_and_a_squatted_one_is_refused);
    tcase_add_test(tc, two_programs_never_share_the_printer);
    tcase_add_test(tc, fifo_and_device_submits_are_refused_at_once);
    tcase_add_test(tc, job_piped_on_stdin_is_refused_and_a_redirected_file_runs);
    tcase_add_test(tc, only_gcode_is_submitted_and_nothing_is_sent_before_the_check);
    tcase_add_test(tc, log_is_private_and_printer_echoes_of_job_lines_stay_off_stderr);
    tcase_add_test(tc, python_example_in_the_docs_follows_a_job_to_its_end);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(daemon_suite)
