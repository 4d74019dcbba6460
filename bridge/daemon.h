/*
 * daemon.h — ampath-bridge's daemon (docs/interfaces.md §8; trusted printer replies, no client can wedge it): the control
 * socket (plain words and JSON lines), its clients, and the loop that serves
 * them next to the printer session of bridge.h.
 *
 *   jsonl.c    flat JSON objects: parse one request line, write one reply/event line
 *   control.c  requests (plain or JSON) to br_request; replies and events to text
 *   ctlsock.c  where the socket lives (private directory), safe create and remove
 *   clients.c  non-blocking clients: bounded input and output, timeouts, reserved slots
 *   safeend.c  heaters off after an interrupted or cancelled job
 *   daemon.c   the loop: session + clients + commands + events + signals
 */
#ifndef AMP_BRIDGE_DAEMON_H
#define AMP_BRIDGE_DAEMON_H

#include <signal.h>
#include <stddef.h>
#include <sys/types.h>

#include "bridge.h"

/* ---- jsonl.c: one flat JSON object per line (no nesting: requests need none) ---- */
#define BR_JSON_MEMBERS 16

typedef enum br_jtype { BR_J_STR, BR_J_NUM, BR_J_BOOL, BR_J_NULL } br_jtype;

typedef struct br_jmember {
    const char *key; /* NUL-terminated, inside br_jobj.store */
    br_jtype type;
    const char *str; /* BR_J_STR: decoded UTF-8, NUL-terminated (a \u0000 is refused) */
    size_t len;      /* length of str */
    double num;      /* BR_J_NUM */
    int b;           /* BR_J_BOOL */
} br_jmember;

typedef struct br_jobj {
    int n;
    br_jmember m[BR_JSON_MEMBERS];
    char store[8448]; /* decoded keys and strings */
    size_t used;
} br_jobj;

/**
 * Parse @p len bytes (one line, no newline) as one JSON object whose values are
 * strings, numbers, true, false or null. Duplicate keys, nesting, trailing
 * bytes and invalid UTF-8 are refused. 0, or -1 with the reason in @p why.
 */
int br_json_parse(br_jobj *o, const char *text, size_t len, char *why, size_t whylen);
/** The member named @p key, or NULL. */
const br_jmember *br_json_get(const br_jobj *o, const char *key);

/** Writer of one object into a caller's buffer; overflow is sticky and reported by br_jw_end. */
typedef struct br_jw {
    char *buf;
    size_t cap, len;
    int n, overflow;
} br_jw;

void br_jw_begin(br_jw *w, char *buf, size_t cap);
/** A string member; bytes that are not valid UTF-8 become U+FFFD, control bytes are escaped. */
void br_jw_str(br_jw *w, const char *key, const char *val);
void br_jw_long(br_jw *w, const char *key, long v);
/** A number member; a non-finite value is written as null. */
void br_jw_num(br_jw *w, const char *key, double v);
void br_jw_bool(br_jw *w, const char *key, int v);
void br_jw_null(br_jw *w, const char *key);
/** A member copied from a parsed one (the request's "id" echoed in the reply). */
void br_jw_member(br_jw *w, const char *key, const br_jmember *m);
/** Close the object and add the newline: its length, or -1 when it did not fit. */
long br_jw_end(br_jw *w);

/* ---- control.c: requests and replies ---- */
typedef enum br_cmd {
    BR_CMD_NONE = 0,
    BR_CMD_SUBMIT,
    BR_CMD_STATUS,
    BR_CMD_PAUSE,
    BR_CMD_RESUME,
    BR_CMD_CANCEL,
    BR_CMD_ESTOP,
    BR_CMD_SUBSCRIBE,
    BR_CMD_UNSUBSCRIBE,
    BR_CMD_HELP,
    BR_CMD_QUIT
} br_cmd;

typedef struct br_request {
    int json;      /* the request was a JSON object: the reply is one too */
    br_cmd cmd;
    char path[PATH_MAX];
    long from;     /* submit: first job line (1 = the whole job) */
    int has_id;
    br_jmember id; /* JSON "id", echoed in the reply (id.str points into idstr) */
    char idstr[128];
} br_request;

/**
 * Parse one command line (without its newline; NUL bytes and all). Plain form:
 * `submit PATH [LINE]` (PATH may be double-quoted with \" and \\ escapes, for
 * spaces), `status`, `pause`, `resume`, `cancel`, `estop`, `subscribe`,
 * `unsubscribe`, `help`, `quit`. JSON form: {"cmd":"submit","path":P,"from":N,"id":X}.
 * 0, or -1 with a one-line reason in @p why (@p r->json and id are still set,
 * so that the error can be answered in the request's own form).
 */
int br_request_parse(br_request *r, const char *line, size_t len, char *why, size_t whylen);
/** Commands a reserved (overflow) connection may use: estop, cancel, status, pause. */
int br_cmd_is_priority(br_cmd c);
const char *br_cmd_name(br_cmd c);

/** A reply or event: an optional message and typed fields, written plain or as JSON. */
#define BR_KV_MAX 24
typedef struct br_kv {
    const char *key;
    int type; /* 0 string (NULL = null), 1 long, 2 double (non-finite = null), 3 bool */
    const char *s;
    long l;
    double d;
} br_kv;

typedef struct br_msg {
    const char *event; /* NULL for a reply */
    int ok;            /* replies: "ok" or "error" */
    const char *text;  /* replies: message ("error": the reason); may be NULL */
    int n;
    br_kv kv[BR_KV_MAX];
} br_msg;

void br_msg_reply(br_msg *m, int ok, const char *text);
void br_msg_event(br_msg *m, const char *event);
void br_msg_str(br_msg *m, const char *key, const char *s);
void br_msg_long(br_msg *m, const char *key, long v);
void br_msg_num(br_msg *m, const char *key, double v);
void br_msg_bool(br_msg *m, const char *key, int v);
/**
 * Render one line (newline included) into @p buf: plain `ok TEXT k=v ...` /
 * `error TEXT` / `event NAME k=v ...` (values with spaces or quotes quoted), or
 * a JSON object {"ok":..,"id":..,"message"|"error":..,k:v..} / {"event":NAME,k:v..}.
 * Control bytes never reach a plain line. Length, or -1 when it did not fit.
 */
long br_msg_render(const br_msg *m, int json, const br_request *req, char *buf, size_t cap);

/* ---- ctlsock.c: where the socket lives ---- */
/**
 * The default socket path: $XDG_RUNTIME_DIR/ampath-bridge.sock when that
 * directory is ours and private, else ${TMPDIR:-/tmp}/ampath-bridge-UID/ctl.sock
 * in a directory created 0700 and checked (ours, a real directory, no access
 * for others). -1 with @p why when no private place can be had.
 */
int br_sock_default(char *out, size_t cap, char *why, size_t whylen);

typedef struct br_listener {
    int fd;
    char path[PATH_MAX];
    dev_t dev;
    ino_t ino; /* what we created: removed on exit only if it is still that */
} br_listener;

/**
 * Listen on @p path with mode 0600. An existing socket is replaced only when no
 * daemon answers on it and it is ours; anything else (a live daemon, a regular
 * file, another user's socket) is refused and left alone. 0 or -1 with @p why.
 */
int br_sock_listen(br_listener *l, const char *path, char *why, size_t whylen);
/** Close and remove the socket if the path still names the one we created. */
void br_sock_close(br_listener *l);

/* ---- clients.c ---- */
#define BR_CL_NORMAL 16     /* ordinary connections */
#define BR_CL_RESERVED 4    /* beyond those: one priority command each, then closed */
#define BR_CL_MAX (BR_CL_NORMAL + BR_CL_RESERVED)
#define BR_CL_IN 8448       /* longest command line (a JSON submit with a PATH_MAX path) */
#define BR_CL_OUT 65536     /* replies and events waiting for a reader; more: disconnected */
#define BR_RESERVED_S 5.0   /* a reserved connection must send its line within this */
#define BR_CLOSING_S 5.0    /* a closing connection gets this long to take its last reply */

typedef struct br_client {
    int fd; /* -1 = free */
    int reserved;
    int subscribed; /* 0, 1 plain events, 2 JSON events */
    int discarding; /* inside an over-long line: dropped up to its newline */
    int closing;    /* close once the output queue drained */
    int eof;        /* the client closed its side: answer what it sent, then close */
    double t_active, t_open;
    size_t inlen, outlen, outoff;
    char in[BR_CL_IN];
    char out[BR_CL_OUT];
} br_client;

typedef struct br_clients br_clients;
/** One complete line of a client (without the newline; may hold NUL bytes). */
typedef void (*br_line_fn)(void *user, br_client *c, const char *line, size_t len);

struct br_clients {
    int lfd;
    double idle_s; /* a client not subscribed that sends nothing for this long is closed */
    long dropped;  /* clients disconnected for not reading */
    br_client cl[BR_CL_MAX];
};

void br_clients_init(br_clients *cs, int lfd, double idle_s);
/** Fill @p pfd (listener first, then clients); returns the count. */
int br_clients_pollfds(br_clients *cs, struct pollfd *pfd, int cap);
/** Accept, read lines (calling @p fn), flush output, apply the timeouts. */
void br_clients_service(br_clients *cs, const struct pollfd *pfd, int n, double now, br_line_fn fn, void *user);
/** Queue @p n bytes for @p c: 0, or -1 when the queue is full (the client is then disconnected). */
int br_client_send(br_clients *cs, br_client *c, const char *text, size_t n);
void br_client_drop(br_clients *cs, br_client *c);
void br_clients_close_all(br_clients *cs);
/** Milliseconds until the next client deadline (timeouts), at most @p cap. */
int br_clients_wait_ms(const br_clients *cs, double now, int cap);

/* ---- safeend.c ---- */
/**
 * After a job stopped with its lines in flight acknowledged (signal or cancel):
 * send heaters off and fan off (M104 S0, M140 S0, M107 — no motion, so the
 * part stays where --resume-from expects it) and wait up to @p max_s for their
 * acknowledgements. 1 when the printer confirmed them, 0 when not (or the
 * printer was stopped or gone), -1 when @p *sig exceeded @p sig_limit.
 */
int br_safe_end(br_session *s, double max_s, volatile sig_atomic_t *sig, int sig_limit);

/* ---- daemon.c ---- */
typedef struct br_daemon_opts {
    const char *sockpath; /* NULL: br_sock_default (used by the caller, before the device is opened) */
    double idle_s;        /* client idle timeout */
    int keep_hot;         /* no safe end after a signal or cancel */
} br_daemon_opts;

/**
 * Serve the control socket @p ls (from br_sock_listen) until `quit` or a
 * signal (counted in @p *sig).
 * A signal mid-job stops sending, waits for the lines in flight (twice the
 * timeout at most; a second signal stops waiting), reports the resume line,
 * sends the safe end unless keep_hot, and returns. The session and the socket
 * are closed on return. Exit status: 0, or 1 when a job was interrupted.
 */
int br_daemon_run(br_session *s, br_listener *ls, const br_daemon_opts *o, volatile sig_atomic_t *sig);

/** The stop report of the one-shot and the daemon (stdout): counts, reason, resume line. */
void br_report(const br_session *s, FILE *out);

#endif
