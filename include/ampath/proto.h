/*
 * ampath/proto.h — the printer streaming protocol engine (docs/interfaces.md §8).
 *
 * Plain data plus step functions, no I/O, no allocation, no clock: the host
 * feeds the bytes it read from the printer (amp_proto_feed), asks for the
 * next framed line to write (amp_proto_next_tx) and receives events through
 * an optional callback. Time is passed in as a millisecond counter that may
 * wrap. The same engine runs in ampath-bridge and on a microcontroller that
 * drives a printer over a UART (it builds with `make cross`).
 *
 * Marlin flavor: every job line is framed as `N<n> <cmd>*<xor>\n` (comments
 * and surrounding blanks stripped first, XOR of every byte before `*`); the
 * connection starts with `N0 M110 N0` once the boot banner `start` was seen
 * or did not come. Replies understood: `ok` (plain or ADVANCED_OK
 * `ok N<n> P<p> B<b>`), `Resend: <n>` / `rs <n>` (rewind ONCE per error
 * burst: each line that was sent after <n> provokes at most one more request
 * for <n> (an echo) and those are counted and dropped, whenever they come;
 * the engine stays silent until all have come or a settling time ran out;
 * sending during the burst would only have the printer flush the re-sent
 * lines again), `Error:...` (`Last Line: L` names the line of a garbled
 * `Resend:`), `ok T:` (M105's answer acknowledges every line up to that M105:
 * lost oks repaired), `echo:busy: processing` (keep-alive), `wait`,
 * ` T:` temperature reports, `start` (the printer reset: the engine stops and
 * reports the last acknowledged line; it never continues blindly).
 * Klipper flavor: no numbers or checksums, one `ok` per line (also after
 * `!! error`), `// ...` information, `// Klipper state: Shutdown` stops.
 *
 * Readiness: nothing of the job goes out before the printer is
 * ready. Klipper: `STATUS` (answered in every state) is repeated every
 * opts.ready_poll_ms until it answers `Klipper state: Ready`; its `!! ...`
 * replies meanwhile are AMP_EV_WAITING, not errors. Marlin: the boot banner or
 * the `M110` handshake's ok; then, with opts.learn, one provoked resend
 * (`N2 M105` where 1 is expected, then `N1 M105`) tells whether an `ok`
 * follows `Resend:` (a bare ok between the resend and M105's `ok T:`) and
 * whether the firmware speaks ADVANCED_OK (`ok N.. P.. B..`), and a second
 * `M110` resets the numbering. Not ready within opts.ready_ms: AMP_EV_NOTREADY,
 * stopped.
 *
 * Firmware errors: a Klipper `!!` reply and a Marlin `Error:` that is not part
 * of the line-number/checksum protocol are AMP_EV_FWERROR, attributed to the
 * oldest line in flight (both firmwares report an error while running the
 * command whose ok comes next); `// action:...` is AMP_EV_ACTION; unknown-command
 * echoes are AMP_EV_WARNING. The engine keeps going after them (the host
 * decides); halts/kills and Klipper shutdowns stop it (AMP_EV_SHUTDOWN).
 *
 * An "acknowledged" line is one the printer answered with `ok`, i.e. it was
 * executed (Marlin and Klipper send `ok` after running a command). Lines are
 * acknowledged in order, so one number (amp_proto.acked) says where a job
 * stands.
 *
 * Thread-safety: an amp_proto is plain data owned by the caller; distinct
 * objects are independent, one object must not be used by two threads at once.
 */
#ifndef AMPATH_PROTO_H
#define AMPATH_PROTO_H

#include <stddef.h>

#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Marlin's MAX_CMD_SIZE: a framed line (without its newline) must be shorter. */
#define AMP_PROTO_LINE_MAX 96
/** Lines kept for resending (a power of two); bounds the send-ahead window. */
#define AMP_PROTO_RING 32
/** Most lines in flight; the ring keeps AMP_PROTO_RING - AMP_PROTO_MAX_INFLIGHT acknowledged lines
    behind them, so that a resend request after an ok was miscounted on a noisy link can still be served. */
#define AMP_PROTO_MAX_INFLIGHT 24
/** Longest reply line kept (longer replies are truncated, never overrun). */
#define AMP_PROTO_RX_MAX 160

/** Firmware dialect. */
typedef enum amp_proto_flavor {
    AMP_PROTO_MARLIN = 0, /**< line numbers, checksums, Resend */
    AMP_PROTO_KLIPPER = 1 /**< Klipper's pseudo-terminal: plain lines, one ok each */
} amp_proto_flavor;

/** How many lines may be sent ahead of the acknowledgements. */
typedef enum amp_proto_window {
    AMP_PROTO_PINGPONG = 0, /**< one line in flight */
    AMP_PROTO_FIXED = 1,    /**< up to opts.window lines, bounded by the printer's RX buffer */
    AMP_PROTO_ADVANCED = 2  /**< Marlin ADVANCED_OK: the command-queue size is read from `ok N P B` */
} amp_proto_window;

/** Engine states. */
typedef enum amp_proto_state {
    AMP_PROTO_CONNECTING = 0, /**< waiting for the boot banner (or its timeout) */
    AMP_PROTO_SYNCING = 1,    /**< M110 sent, waiting for its ok */
    AMP_PROTO_RUNNING = 2,    /**< streaming */
    AMP_PROTO_STOPPED = 3     /**< reset, shutdown, fatal error or estop: nothing more is sent */
} amp_proto_state;

/** Event kinds delivered to opts.on_event. */
typedef enum amp_proto_event_kind {
    AMP_EV_READY = 0,    /**< handshake done, lines may be submitted */
    AMP_EV_ACK,          /**< line `line` acknowledged */
    AMP_EV_RESEND,       /**< rewound to line `line` (once per error burst) */
    AMP_EV_RESEND_DUP,   /**< a resend request of the same burst, ignored */
    AMP_EV_ERROR,        /**< `Error:` or `!!` reply (text holds it) */
    AMP_EV_BUSY,         /**< `echo:busy:` keep-alive */
    AMP_EV_TEMP,         /**< temperature report (text holds it) */
    AMP_EV_INFO,         /**< `echo:`, `//` or other text */
    AMP_EV_RESET,        /**< `start` mid-job: stopped; `line` = last acknowledged */
    AMP_EV_SHUTDOWN,     /**< Klipper shutdown or Marlin halt: stopped; `line` = last acknowledged */
    AMP_EV_TIMEOUT,      /**< no reply in time; Marlin: a probe line was re-sent */
    AMP_EV_FATAL,        /**< unrecoverable (resend of a line no longer kept); stopped */
    AMP_EV_FWERROR,      /**< firmware error (Klipper `!!`, Marlin non-protocol `Error:`); `line` = line it hit */
    AMP_EV_WARNING,      /**< `Unknown command` echo for one of our lines; `line` = that line */
    AMP_EV_ACTION,       /**< `// action:...` from the firmware (text holds it); `line` = oldest in flight */
    AMP_EV_WAITING,      /**< printer not ready yet (text holds its words) */
    AMP_EV_NOTREADY,     /**< not ready within opts.ready_ms; stopped */
    AMP_EV_LEARNED       /**< Marlin dialect learned at the handshake (text: "resend-ok=0|1 advanced-ok=0|1") */
} amp_proto_event_kind;

/** One event; text points into the engine and is valid during the callback only. */
typedef struct amp_proto_event {
    amp_proto_event_kind kind;
    long line;        /**< line number concerned (see the kind), 0 if none */
    const char *text; /**< the reply line, NUL-terminated ("" if none) */
} amp_proto_event;

typedef void (*amp_proto_event_fn)(void *user, const amp_proto_event *ev);

/** Options; fill with amp_proto_opts_default() then adjust. */
typedef struct amp_proto_opts {
    amp_proto_flavor flavor;    /**< default AMP_PROTO_MARLIN */
    amp_proto_window mode;      /**< default AMP_PROTO_FIXED */
    int window;                 /**< max lines in flight, FIXED/Klipper (default 4 Marlin, 16 Klipper), 1..AMP_PROTO_MAX_INFLIGHT */
    int bufsize;                /**< printer command-queue slots (Marlin BUFSIZE, default 4) */
    int rx_bytes;               /**< bytes the printer's serial RX buffer holds (default 127: Marlin's RX_BUFFER_SIZE 128 as an
                                     AVR ring buffer, one slot kept free; a full queue strands one guard newline) */
    int resend_ok;              /**< non-zero: an `ok` follows every `Resend:` and is no acknowledgement (Marlin, default 1) */
    unsigned long boot_ms;      /**< wait this long for `start` before the handshake (default 3000) */
    unsigned long timeout_ms;   /**< silence (no ok/busy/temperature) before a probe (default 10000) */
    unsigned long settle_ms;    /**< after a rewind, wait at most this long (plus the stale bytes' wire time and
                                     twice the printer's reply time) for the requests the lines sent ahead provoke,
                                     before sending again; the wait ends early when every line sent ahead has
                                     echoed, and an echo that comes later is still counted as one (default 10) */
    int guard_nl;               /**< Marlin: end each line with a second newline (default 1). A corrupted newline
                                     would merge two lines into one that passes the XOR check with odds
                                     1/256; the spare newline keeps them apart (Marlin skips empty lines) */
    unsigned long byte_us;      /**< wire time of one byte in microseconds (10e6 / baud; 0 for a pty) */
    unsigned long ready_ms;     /**< give up when the printer is not ready after this long (default 60000; 0 = never) */
    unsigned long ready_poll_ms; /**< Klipper: repeat `STATUS` this often while not ready (default 1000) */
    int learn;                  /**< Marlin: learn resend_ok and ADVANCED_OK at the handshake (default 1) */
    amp_proto_event_fn on_event; /**< optional event callback */
    void *user;                 /**< passed to on_event */
} amp_proto_opts;

/** One line kept for resending. */
typedef struct amp_proto_slot {
    long n;                             /**< its line number */
    unsigned char len;                  /**< framed bytes including the newline */
    unsigned long t_sent;               /**< when it was last transmitted (ms) */
    char text[AMP_PROTO_LINE_MAX + 8];  /**< framed line */
} amp_proto_slot;

/** The engine; plain data, inspect fields freely, change them only through the functions. */
typedef struct amp_proto {
    amp_proto_opts o;
    amp_proto_state state;
    long next_n;     /**< number the next submitted line gets */
    long send_n;     /**< next line number to transmit */
    long top_sent;   /**< highest line number ever transmitted */
    long acked;      /**< last acknowledged line number (0 = none) */
    long sync_n;     /**< number used by the pending M110, -1 if none */
    long rewind_n;   /**< target of the current error burst, -1 outside a burst */
    int settling;    /**< in a burst: requests for rewind_n are echoes of lines sent ahead */
    long echo_budget; /**< echoes still owed by the lines that were sent after rewind_n */
    unsigned long err_lat; /**< smoothed time from sending a line to the printer's error for it (ms) */
    unsigned long settle_until; /**< end of the settling time */
    int skip_ok;     /**< an ok owed to a Resend is expected */
    int sync_err;    /**< a protocol error came after the handshake's M110: the ok that follows is the refusal's */
    int probing;     /**< a probe is out after a timeout */
    int silent_probes; /**< probes in a row that got no answer (with 30 s or 3 timeouts of silence: AMP_EV_FATAL) */
    unsigned long probe_t0; /**< when the first of them went out */
    int pend_err;      /**< an unclassified `Error:` waits for the next line (a `Resend:` makes it protocol) */
    long pend_line;    /**< the line it hit */
    char pend_text[AMP_PROTO_RX_MAX + 1];
    int estop;       /**< M112 pending, goes before everything */
    int start_seen;  /**< boot banner seen while connecting */
    int resync;      /**< the M110 must be (re)sent */
    int qslots;      /**< command-queue size in use (learned under ADVANCED_OK) */
    int q_cand;      /**< last queue-size estimate; adopted when two oks in a row agree */
    int verify;      /**< end-of-job check requested (amp_proto_verify) */
    int sync_phase;  /**< handshake step: 0 M110, 1 provoked resend out, 2 `N1 M105` out, 3 final M110 */
    int learn_fail;  /**< handshakes whose learning came to nothing (learning is dropped after 2) */
    int m110_out;    /**< M110s sent in this handshake step (more than one: the others may still answer) */
    int stale_oks;   /**< oks of repeated M110s still to come after the handshake; not acknowledgements */
    int saw_ok;      /**< learning: a bare ok came after the provoked Resend */
    int ready_seen;  /**< Klipper: `Klipper state: Ready` seen */
    int adv_seen;    /**< an `ok N.. P.. B..` was seen (the firmware speaks ADVANCED_OK) */
    long last_line;  /**< `Last Line: L` of the latest protocol error, -1 if none */
    int relink;      /**< Marlin: re-handshake after the link came back (amp_proto_link_restored) */
    long relink_base; /**< the printer's last received job line, learned without running anything; -1 unknown */
    long relink_next; /**< the number the next re-handshake M105 gets (the printer's last line + 1) */
    long relink_m105; /**< highest number given to a re-handshake M105 (it may have been received) */
    long relink_cand; /**< a `Resend:` number of the re-handshake not yet confirmed (by `Last Line:` or a second) */
    int relink_temps; /**< `ok T:` replies seen during the re-handshake */
    long adv_prev;   /**< ADVANCED_OK: N of the previous ok, -1 if none (a number that follows it is trusted) */
    long ready_base; /**< acked when the engine last became ready (stale M110 oks come only near it) */
    int line1_reqs;  /**< requests for line 1 (no longer kept) since the last ok: two make a reset */
    unsigned long next_poll; /**< Klipper: time of the next STATUS while not ready */
    unsigned long last_rx; /**< time of the last ok/busy/temperature/start */
    unsigned long t0;      /**< time of init or of the last link restore */
    /* counters */
    long n_sent, n_resent, n_rewinds, n_dups, n_errors, n_timeouts, n_busy, n_garbage;
    long n_fwerrors, n_warnings, n_lost_oks; /**< n_lost_oks: oks placed from ADVANCED_OK numbers */
    size_t rxlen;
    int rx_over; /**< current reply longer than AMP_PROTO_RX_MAX (tail dropped) */
    char rx[AMP_PROTO_RX_MAX + 1];
    amp_proto_slot ring[AMP_PROTO_RING];
} amp_proto;

/** Defaults for @p flavor (see the field comments). */
void amp_proto_opts_default(amp_proto_opts *o, amp_proto_flavor flavor);

/**
 * Start an engine at time @p now_ms. Klipper starts RUNNING at once; Marlin
 * first waits for `start` (at most opts.boot_ms), then sends `N0 M110 N0`.
 * AMP_ERR_ARG on bad options (window or bufsize outside [1, AMP_PROTO_MAX_INFLIGHT]).
 */
amp_status amp_proto_init(amp_proto *p, const amp_proto_opts *o, unsigned long now_ms, amp_error *err);

/**
 * Frame G-code line @p cmd (@p len bytes, no NUL needed) and queue it.
 * Comments (`;` to the end) and blanks are stripped; if nothing is left,
 * *lineno = 0 and nothing is queued. Otherwise *lineno is its line number
 * (Klipper: a running count). Errors: AMP_ERR_LIMIT when the framed line
 * would reach AMP_PROTO_LINE_MAX bytes (nothing is sent: Marlin would reject
 * it), AMP_ERR_STATE when not ready (check amp_proto_can_submit) or stopped,
 * AMP_ERR_PARSE on a newline or NUL inside @p cmd.
 */
amp_status amp_proto_submit(amp_proto *p, const char *cmd, size_t len, long *lineno, amp_error *err);

/** Non-zero when amp_proto_submit can take another line now. */
int amp_proto_can_submit(const amp_proto *p);

/** Number of submitted lines not yet acknowledged. */
long amp_proto_pending(const amp_proto *p);

/**
 * Feed @p n bytes read from the printer at @p now_ms. Lines may be split
 * anywhere across calls; CR, LF and NUL end a line. Events are delivered
 * during the call.
 */
void amp_proto_feed(amp_proto *p, const char *bytes, size_t n, unsigned long now_ms);

/**
 * The next line to write, if the window allows one now: copies it into
 * @p buf (capacity @p cap >= AMP_PROTO_LINE_MAX + 8), sets *len and returns 1;
 * returns 0 when nothing is to be sent. Also runs the boot and reply timeouts
 * (call it at least every amp_proto_wait_ms). The line counts as sent on return.
 */
int amp_proto_next_tx(amp_proto *p, unsigned long now_ms, char *buf, size_t cap, size_t *len);

/** Milliseconds until the next timer of the engine fires (for poll()); -1 if none. */
long amp_proto_wait_ms(const amp_proto *p, unsigned long now_ms);

/**
 * Drop the lines submitted but never transmitted (for a clean stop: the line
 * in flight finishes, nothing new starts). Lines already sent stay, so that
 * resend requests for them can still be served. Returns how many were dropped.
 */
long amp_proto_cancel_unsent(amp_proto *p);

/**
 * Size in bytes (without the newline) that @p cmd would have once stripped and
 * framed as line number @p n for @p flavor; 0 when nothing is left after
 * stripping. Lets a host reject a job before sending any of it: a result of
 * AMP_PROTO_LINE_MAX or more is refused by amp_proto_submit. Thread-safe.
 */
size_t amp_proto_framed_size(amp_proto_flavor flavor, long n, const char *cmd, size_t len);

/**
 * Marlin: confirm that the printer really holds every line counted as
 * acknowledged (an `ok` garbled into existence cannot be ruled out on a noisy
 * link). Re-sends the newest line as a probe: the printer either runs it (it
 * had been lost) or answers `Resend: <next>`, which proves receipt. Call it
 * when amp_proto_pending() reached 0 at the end of a job; wait until
 * amp_proto_pending() is 0 and p->probing and p->verify are 0. No-op for Klipper.
 */
void amp_proto_verify(amp_proto *p);

/** Emergency stop: `M112` goes out next, ahead of the window, and the engine stops. */
void amp_proto_estop(amp_proto *p);

/**
 * The link went away and came back (USB unplug): the partial reply is
 * discarded and, if the job had started (Marlin), the engine re-handshakes
 * without running anything twice or skipping anything (state SYNCING until
 * done, events as for the first handshake):
 *  1. a newline (ends a line the unplug cut), then a line numbered beyond
 *     anything sent (`N<top+2> M105`), refused by
 *     the printer with `Last Line: K` and `Resend: K+1`: K, the last line it
 *     RECEIVED, is learned only when both agree (nothing runs);
 *  2. `N<K+1> M105`: its `ok T:` comes after every queued line up to K ran
 *     (Marlin runs its queue in order), so the lines up to K are acknowledged
 *     exactly, whatever oks the unplug swallowed;
 *  3. `N<K> M110 N<K>`, and streaming goes on from line K+1.
 * A printer that reset meanwhile answers `start` or asks for line 1: the
 * engine stops (AMP_EV_RESET) with the last acknowledged line. Klipper has no
 * line numbers, so nothing can tell which lines in flight ran: the host must
 * stop the job (ampath-bridge does), this function only clears the reply.
 */
void amp_proto_link_restored(amp_proto *p, unsigned long now_ms);

/**
 * The command text of line @p n (as sent, without number and checksum) into
 * @p buf (capacity @p cap, NUL-terminated, truncated to fit). Returns 1, or 0
 * when the line is no longer kept (lines behind the newest AMP_PROTO_RING).
 */
int amp_proto_line_text(const amp_proto *p, long n, char *buf, size_t cap);

/** Static name of an event kind ("ack", "resend", ...). */
const char *amp_proto_event_name(amp_proto_event_kind k);

/** XOR checksum of @p n bytes (Marlin/RepRap line checksum). */
unsigned amp_proto_checksum(const char *s, size_t n);

#ifdef __cplusplus
}
#endif
#endif
