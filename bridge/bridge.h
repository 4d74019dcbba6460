/*
 * bridge.h — internals of ampath-bridge (docs/interfaces.md §8): device links, jobs, and the
 * session loop that drives the protocol engine (include/ampath/proto.h).
 * Linked into ampath-bridge, the tests and tools/ampath (the benchmark).
 */
#ifndef AMP_BRIDGE_H
#define AMP_BRIDGE_H

#include <limits.h>
#include <poll.h>
#include <stdio.h>

#include "ampath/ampath.h"

#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

/* ---- device link: libserialport for real serial ports, a raw termios fd for ptys ---- */
typedef struct br_link {
    int fd;           /* -1 when closed */
    void *sp;         /* struct sp_port * when opened through libserialport */
    int is_pty;
    char real[PATH_MAX];
} br_link;

/** Open @p path (symlinks such as /dev/serial/by-id/... resolved) at @p baud. 0 or -1 with @p why. */
int br_link_open(br_link *l, const char *path, long baud, char *why, size_t whylen);
void br_link_close(br_link *l);

/* ---- jobs: .gcode files (and .amp through the G-code writer when available) ---- */
typedef struct br_job {
    FILE *f;
    int is_amp;          /* .amp: G-code made on the fly by the library's writer (docs/interfaces.md §5) */
    amp_pathset ps;
    amp_gcode_opts go;
    amp_printer pr;  /* .amp: the printer profile the G-code is written for (go points into it) */
    amp_gcode_iter it;
    char path[PATH_MAX];
    long line;       /* job line number of the last line returned (1-based file line) */
    long total;      /* commands in the job (non-empty after stripping) */
    long first_line; /* --resume-from: lines before it are skipped */
    /* resume preamble */
    char pre[16][AMP_PROTO_LINE_MAX];
    int npre, ipre;
} br_job;

/**
 * Open a job and check every line before anything is sent (over-long lines are
 * refused here). @p resume_from > 1 builds the safe-restart preamble from the
 * state the job had reached before that line. An `.amp` job is written for the
 * printer profile @p printer (a built-in name or a PrusaSlicer `.ini`, as
 * `ampath gcode --printer`; NULL = the generic profile): its bed, placement,
 * temperatures, speeds and start/end G-code. @p bars: draw bars on stderr while a job of 16 MB or more is
 * read and checked (a terminal). 0 or -1 with @p why.
 */
int br_job_open(br_job *j, const char *path, amp_proto_flavor flavor, const char *printer, long resume_from,
                int bars, char *why, size_t whylen);
/** Next command: 1 with @p buf and *jobline (0 for preamble lines), 0 at the end, -1 on a read error. */
int br_job_next(br_job *j, char *buf, size_t cap, long *jobline);
void br_job_close(br_job *j);

/** `ampath-bridge --bench [--quick] [--json]`: throughput against the virtual printer (bridge/bench.c);
 *  argv[0] is "--bench". Returns the exit status. */
int br_bench_main(int argc, char **argv);

/* ---- session ---- */
typedef enum br_stop {
    BR_RUNNING = 0,
    BR_DONE,        /* every line acknowledged */
    BR_RESET,       /* printer reset mid-job */
    BR_SHUTDOWN,    /* Klipper shutdown / Marlin halt / estop */
    BR_FATAL,       /* protocol could not recover */
    BR_INTERRUPTED, /* SIGINT/SIGTERM */
    BR_CANCELLED,   /* cancel from the control socket */
    BR_LINK_LOST,   /* the device did not come back */
    BR_JOB_ERROR,   /* unreadable job or a line the printer cannot take */
    BR_PRINTER_ERROR,  /* Klipper `!!`, Marlin `Error:` outside the resend protocol (unless --on-error continue) */
    BR_PRINTER_ACTION, /* `// action:cancel` or `// action:pause` from the firmware */
    BR_NOT_READY       /* the printer did not become ready within --ready-timeout */
} br_stop;

typedef struct br_cfg {
    const char *device;
    long baud;
    int flavor; /* AMP_PROTO_MARLIN, AMP_PROTO_KLIPPER or -1 = auto (M115) */
    amp_proto_window mode;
    int window, bufsize, rx_bytes, resend_ok;
    unsigned long timeout_ms, boot_ms, settle_ms;
    double reconnect_s; /* how long to wait for a lost device */
    unsigned long ready_ms; /* --ready-timeout */
    int on_error_continue;  /* --on-error continue: firmware errors are reported and counted, the job goes on */
    int learn;              /* Marlin: learn resend-ok / ADVANCED_OK at the handshake */
    const char *printer;    /* --printer: profile for .amp jobs (NULL = generic) */
    FILE *log;          /* protocol log, or NULL */
    int progress;       /* progress line on stderr */
    int quiet;
} br_cfg;

void br_cfg_default(br_cfg *c);

#define BR_MAP 64 /* >= AMP_PROTO_RING */

typedef struct br_session {
    br_cfg cfg;
    br_link link;
    amp_proto p;
    int have_job;
    br_job job;
    int job_eof;
    int end_marker; /* the closing M105 was submitted (Marlin) */
    int paused;
    int stopping; /* finish the line in flight, then stop */
    br_stop stop;
    char stop_text[300];
    long map[BR_MAP];      /* engine line number -> last job line up to it (0 = none yet) */
    long cum[BR_MAP];      /* engine line number -> job lines (not preamble) up to it */
    long cum_total, last_jl;
    int verified;
    long sent_moves, acked_moves, last_acked_job_line, first_unacked_job_line;
    long bytes_out; /* bytes written to the device */
    char tx[AMP_PROTO_LINE_MAX + 8];
    size_t txlen, txoff;
    double t_start, t_lost, t_progress;
    double rate_t0;
    long rate_n0;
    /* what the printer said (errors, warnings: reported in status) */
    long n_fwerrors, n_warnings;
    long err_jobline;          /* job line of the first firmware error (0 = before the job / unknown) */
    char err_cmd[AMP_PROTO_LINE_MAX + 8], err_text[200];
    long warn_jobline;
    char warn_text[200];
    char waiting[200];         /* the printer's latest words while not ready */
    char learned[64];          /* dialect learned at the handshake */
    long maybe_from, maybe_to; /* job lines sent but not acknowledged when the job stopped (may have run) */
} br_session;

double br_now(void);

/** Open the device, detect the flavor if asked, start the engine. 0 or -1 with @p why. */
int br_session_open(br_session *s, const br_cfg *cfg, char *why, size_t whylen);
/** Start a job (a .gcode file). 0 or -1 with @p why. */
int br_session_start_job(br_session *s, const char *path, long resume_from, char *why, size_t whylen);
/**
 * One turn of the loop: poll the link and @p extra (their revents are filled),
 * read, feed, write, submit. Waits at most @p max_ms.
 */
void br_session_step(br_session *s, struct pollfd *extra, int nextra, int max_ms);
/** Clean stop: nothing new is sent, the lines in flight are waited for. */
void br_session_request_stop(br_session *s, br_stop why);
/* The job line (file line) of engine line number @p n, 0 for a preamble line or one no longer mapped. */
long br_session_job_line(const br_session *s, long n);
/** The --resume-from line of the job: the first line not acknowledged, or the refused line itself when the
 *  printer refused the last line it acknowledged (nothing after it ran). */
long br_session_resume_line(const br_session *s);
void br_session_close(br_session *s);
const char *br_stop_name(br_stop st);
/** One-line status: "state=... job=... acked=N total=M line=L". */
void br_session_status(const br_session *s, char *buf, size_t cap);
/**
 * The end-of-job report (what the one-shot bridge prints on stdout): commands sent and acknowledged,
 * printer errors and warnings (job line, its text, the printer's words), and for a stop its reason, the
 * last acknowledged job line, the lines that may have run, and the --resume-from line.
 */
void br_session_report(const br_session *s, FILE *f);

#endif
