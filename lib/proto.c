/*
 * proto.c — printer streaming protocol engine (docs/interfaces.md §8).
 *
 * No I/O, no allocation, no printf: the framed lines live in a fixed ring so
 * that any line not yet acknowledged can be sent again, and reply lines are
 * assembled in a fixed buffer. See include/ampath/proto.h for the model.
 */
#include "ampath/proto.h"

#include <string.h>

#define RING_MASK (AMP_PROTO_RING - 1)

#if (AMP_PROTO_RING & (AMP_PROTO_RING - 1)) != 0
#error "AMP_PROTO_RING must be a power of two"
#endif

static const char *const ev_names[] = {"ready",   "ack",     "resend",  "resend-dup", "error",    "busy",
                                       "temp",    "info",    "reset",   "shutdown",   "timeout",  "fatal",
                                       "fwerror", "warning", "action",  "waiting",    "notready", "learned"};

const char *amp_proto_event_name(amp_proto_event_kind k)
{
    unsigned i = (unsigned)k;
    if (i >= sizeof ev_names / sizeof ev_names[0])
        return "unknown";
    return ev_names[i];
}

unsigned amp_proto_checksum(const char *s, size_t n)
{
    unsigned cs = 0;
    size_t i;
    for (i = 0; i < n; i++)
        cs ^= (unsigned char)s[i];
    return cs & 0xffu;
}

void amp_proto_opts_default(amp_proto_opts *o, amp_proto_flavor flavor)
{
    memset(o, 0, sizeof *o);
    o->flavor = flavor;
    o->mode = AMP_PROTO_FIXED;
    o->window = flavor == AMP_PROTO_KLIPPER ? 16 : 4;
    o->bufsize = 4;
    o->rx_bytes = 127; /* RX_BUFFER_SIZE 128: an AVR ring buffer holds one byte less */
    o->resend_ok = 1;
    o->boot_ms = 3000;
    o->timeout_ms = 10000;
    o->settle_ms = 10;
    o->guard_nl = flavor == AMP_PROTO_MARLIN;
    o->byte_us = 0;
    o->ready_ms = 60000;
    o->ready_poll_ms = 1000;
    o->learn = 1;
}

static void emit(amp_proto *p, amp_proto_event_kind k, long line, const char *text)
{
    amp_proto_event ev;
    if (!p->o.on_event)
        return;
    ev.kind = k;
    ev.line = line;
    ev.text = text ? text : "";
    p->o.on_event(p->o.user, &ev);
}

amp_status amp_proto_init(amp_proto *p, const amp_proto_opts *o, unsigned long now_ms, amp_error *err)
{
    if (!p || !o)
        return amp_fail(err, AMP_ERR_ARG, 0, "proto: NULL argument");
    if (o->window < 1 || o->window > AMP_PROTO_MAX_INFLIGHT || o->bufsize < 1 || o->bufsize > AMP_PROTO_MAX_INFLIGHT)
        return amp_fail(err, AMP_ERR_ARG, 0, "proto: window and bufsize must lie in [1, %d]", AMP_PROTO_MAX_INFLIGHT);
    if (o->rx_bytes < AMP_PROTO_LINE_MAX)
        return amp_fail(err, AMP_ERR_ARG, 0, "proto: rx_bytes must be at least %d", AMP_PROTO_LINE_MAX);
    if (o->flavor != AMP_PROTO_MARLIN && o->flavor != AMP_PROTO_KLIPPER)
        return amp_fail(err, AMP_ERR_ARG, 0, "proto: unknown flavor");
    memset(p, 0, sizeof *p);
    p->o = *o;
    p->next_n = 1;
    p->send_n = 1;
    p->sync_n = -1;
    p->rewind_n = -1;
    p->last_line = -1;
    p->relink_base = -1;
    p->adv_prev = -1;
    p->qslots = o->bufsize;
    p->last_rx = p->t0 = now_ms;
    p->state = AMP_PROTO_CONNECTING; /* Klipper too: nothing is sent before it reports Ready */
    return AMP_OK;
}

long amp_proto_pending(const amp_proto *p)
{
    return p->next_n - 1 - p->acked;
}

int amp_proto_can_submit(const amp_proto *p)
{
    /* the ring keeps some acknowledged lines too: see AMP_PROTO_MAX_INFLIGHT */
    return p->state == AMP_PROTO_RUNNING && !p->estop && p->next_n - 1 - p->acked < AMP_PROTO_MAX_INFLIGHT;
}

static size_t put_long(char *dst, long v)
{
    char tmp[24];
    size_t n = 0, i;
    unsigned long u = v < 0 ? 0UL - (unsigned long)v : (unsigned long)v;
    do {
        tmp[n++] = (char)('0' + (int)(u % 10));
        u /= 10;
    } while (u);
    i = 0;
    if (v < 0)
        dst[i++] = '-';
    while (n)
        dst[i++] = tmp[--n];
    return i;
}

/* Frame "N<n> <cmd>*<cs>\n" (Marlin) or "<cmd>\n" (Klipper) into slot @p s; 0 if too long. */
static int frame(amp_proto *p, amp_proto_slot *s, long n, const char *cmd, size_t len)
{
    char tmp[AMP_PROTO_LINE_MAX + 40];
    size_t k = 0;
    if (len >= AMP_PROTO_LINE_MAX)
        return 0;
    if (p->o.flavor == AMP_PROTO_MARLIN) {
        unsigned cs;
        tmp[k++] = 'N';
        k += put_long(tmp + k, n);
        tmp[k++] = ' ';
        memcpy(tmp + k, cmd, len);
        k += len;
        cs = amp_proto_checksum(tmp, k);
        tmp[k++] = '*';
        k += put_long(tmp + k, (long)cs);
    } else {
        memcpy(tmp, cmd, len);
        k = len;
    }
    /* Marlin's MAX_CMD_SIZE counts the terminating NUL: a line of 96 or more bytes never passes */
    if (k >= AMP_PROTO_LINE_MAX)
        return 0;
    tmp[k++] = '\n';
    if (p->o.guard_nl && p->o.flavor == AMP_PROTO_MARLIN)
        tmp[k++] = '\n';
    memcpy(s->text, tmp, k);
    s->len = (unsigned char)k;
    s->n = n;
    return 1;
}

/* Strip a ';' comment and surrounding blanks: [*a, *b) is what goes on the wire. 0 on a line break or NUL. */
static int strip(const char *cmd, size_t len, size_t *a, size_t *b)
{
    size_t i;
    for (i = 0; i < len; i++) {
        if (cmd[i] == '\n' || cmd[i] == '\r' || cmd[i] == '\0')
            return 0;
        if (cmd[i] == ';')
            break; /* Marlin comments run to the end of the line; the checksum covers the stripped text */
    }
    *b = i;
    /* a later line break would still split the line on the wire */
    for (; i < len; i++)
        if (cmd[i] == '\n' || cmd[i] == '\r' || cmd[i] == '\0')
            return 0;
    *a = 0;
    while (*a < *b && (cmd[*a] == ' ' || cmd[*a] == '\t'))
        (*a)++;
    while (*b > *a && (cmd[*b - 1] == ' ' || cmd[*b - 1] == '\t'))
        (*b)--;
    return 1;
}

size_t amp_proto_framed_size(amp_proto_flavor flavor, long n, const char *cmd, size_t len)
{
    size_t a, b, k;
    char digits[24];
    if (!cmd || !strip(cmd, len, &a, &b) || a == b)
        return 0;
    if (flavor == AMP_PROTO_KLIPPER)
        return b - a;
    k = put_long(digits, n);
    /* "N<n> " + cmd + "*" + checksum digits (computed, they vary from 1 to 3) */
    {
        unsigned cs = 'N';
        size_t i;
        for (i = 0; i < k; i++)
            cs ^= (unsigned char)digits[i];
        cs ^= ' ';
        for (i = a; i < b; i++)
            cs ^= (unsigned char)cmd[i];
        cs &= 0xffu;
        return 1 + k + 1 + (b - a) + 1 + (cs >= 100 ? 3 : cs >= 10 ? 2 : 1);
    }
}

amp_status amp_proto_submit(amp_proto *p, const char *cmd, size_t len, long *lineno, amp_error *err)
{
    size_t a, b;
    amp_proto_slot *s;
    if (lineno)
        *lineno = 0;
    if (!p || (!cmd && len))
        return amp_fail(err, AMP_ERR_ARG, 0, "proto: NULL argument");
    if (!strip(cmd, len, &a, &b))
        return amp_fail(err, AMP_ERR_PARSE, 0, "proto: line break or NUL inside a command");
    if (a == b)
        return AMP_OK;
    if (b - a == 4 && memcmp(cmd + a, "M112", 4) == 0) {
        /* both firmwares act on M112 as soon as it is read, ahead of their queues */
        amp_proto_estop(p);
        return AMP_OK;
    }
    if (p->state != AMP_PROTO_RUNNING || !amp_proto_can_submit(p))
        return amp_fail(err, AMP_ERR_STATE, 0, "proto: cannot take a line now (%s)",
                        p->state == AMP_PROTO_STOPPED ? "stopped" : "window full or not connected");
    s = &p->ring[p->next_n & RING_MASK];
    if (!frame(p, s, p->next_n, cmd + a, b - a))
        return amp_fail(err, AMP_ERR_LIMIT, 0, "proto: line of %lu bytes exceeds the printer's %d-byte limit",
                        (unsigned long)(b - a), AMP_PROTO_LINE_MAX - 1);
    if (lineno)
        *lineno = p->next_n;
    p->next_n++;
    return AMP_OK;
}

long amp_proto_cancel_unsent(amp_proto *p)
{
    long keep = p->top_sent + 1 > p->send_n ? p->top_sent + 1 : p->send_n, dropped = 0;
    if (p->next_n > keep) {
        dropped = p->next_n - keep;
        p->next_n = keep;
    }
    return dropped;
}

void amp_proto_verify(amp_proto *p)
{
    if (p->o.flavor == AMP_PROTO_MARLIN && p->state == AMP_PROTO_RUNNING && p->top_sent > 0)
        p->verify = 1;
}

void amp_proto_estop(amp_proto *p)
{
    p->estop = 1;
}

void amp_proto_link_restored(amp_proto *p, unsigned long now_ms)
{
    p->rxlen = 0;
    p->rx_over = 0;
    p->last_rx = p->t0 = now_ms;
    /* stale error replies of a burst may have been lost with the link: do not wait for them */
    p->rewind_n = -1;
    p->settling = 0;
    p->echo_budget = 0;
    p->pend_err = 0;
    p->probing = 0;
    p->verify = 0;
    p->skip_ok = 0;
    p->sync_err = 0;
    p->last_line = -1;
    if (p->o.flavor != AMP_PROTO_MARLIN || p->state == AMP_PROTO_STOPPED || p->state == AMP_PROTO_CONNECTING)
        return;
    if (p->state == AMP_PROTO_SYNCING && !p->relink) {
        p->sync_phase = 0; /* no job line went out yet: the handshake starts over */
        p->resync = 1;
        return;
    }
    /* Re-handshake (proto.h): the printer kept its queue and line counter, but the oks it sent while
       unplugged are gone, and lines sent before the unplug may or may not have arrived. Re-sending from the
       last acknowledged line with M110 would run the received ones twice; the probe of a running job would
       run the newest line if it was lost, but not tell when the queued lines are done. */
    if (!p->relink) {
        p->relink = 1;
        p->relink_base = -1;
        p->relink_m105 = 0;
        p->relink_cand = -1;
        p->relink_temps = 0;
    }
    p->state = AMP_PROTO_SYNCING;
    p->sync_phase = 1;
    p->resync = 1;
    p->m110_out = 0;
}

static int has_temp(const char *s);
static int fuzzy(const char *s, const char *pat);

static void stop(amp_proto *p, amp_proto_event_kind k, const char *text)
{
    p->state = AMP_PROTO_STOPPED;
    emit(p, k, p->acked, text);
}

static int starts(const char *s, const char *prefix)
{
    return strncmp(s, prefix, strlen(prefix)) == 0;
}

/* Parse a decimal after optional blanks; returns 1 and *v on success. */
static int parse_long(const char *s, long *v)
{
    long x = 0;
    int nd = 0;
    while (*s == ' ')
        s++;
    if (s[0] == '0' && s[1] != '\0')
        return 0; /* Marlin prints no leading zero: "Resend: 201" with the 2 garbled into ':' once read as 1 */
    while (*s >= '0' && *s <= '9' && nd < 12) {
        x = x * 10 + (*s - '0');
        s++;
        nd++;
    }
    if (nd == 0 || nd >= 12)
        return 0;
    if (*s != '\0')
        return 0; /* trailing garbage, a blank too: a garbled number is worse than none ("Resend: 10" with its
                     0 garbled into a blank (one bit) read as 1, a reset: the stop seen once in 72 runs) */
    *v = x;
    return 1;
}

/* ADVANCED_OK: "ok N<n> P<p> B<b>"; returns 1 when N and B were both found. */
static int parse_adv(const char *s, long *n, long *b)
{
    int have_n = 0, have_b = 0;
    while (*s) {
        if ((*s == 'N' || *s == 'B' || *s == 'P') && s[-1] == ' ') {
            char c = *s++;
            long x = 0;
            int nd = 0;
            while (*s >= '0' && *s <= '9' && nd < 12) {
                x = x * 10 + (*s++ - '0');
                nd++;
            }
            if (nd == 0)
                return 0;
            if (c == 'N') {
                *n = x;
                have_n = 1;
            } else if (c == 'B') {
                *b = x;
                have_b = 1;
            }
        } else {
            s++;
        }
    }
    return have_n && have_b;
}

/* An ok: the printer ran the next line in order. That line must have been sent, but need not lie before
   send_n: after a rewind on a request that was an old burst's echo after all, the printer may already hold
   (and run) lines from the rewind point on; dropping their oks made a whole job lag one line, and a reset
   report then named a line that had run (found by the reset soak). */
static void ack_one(amp_proto *p)
{
    if (p->acked < p->top_sent) {
        p->acked++;
        p->line1_reqs = 0;
        if (p->send_n <= p->acked)
            p->send_n = p->acked + 1; /* it ran: do not send it again */
        if (p->rewind_n >= 0 && p->acked >= p->rewind_n) {
            p->rewind_n = -1; /* the re-sent line went through: the burst is over */
            p->settling = 0;
            p->echo_budget = 0;
        }
        emit(p, AMP_EV_ACK, p->acked, p->rx);
    } else {
        p->n_garbage++; /* an ok for nothing in flight */
        emit(p, AMP_EV_INFO, 0, p->rx);
    }
}

/* Is line k still kept, and is its command @p cmd (a 4-character word such as M105)? */
static int slot_is(const amp_proto *p, long k, const char *cmd)
{
    const amp_proto_slot *sl = &p->ring[k & RING_MASK];
    const char *sp = memchr(sl->text, ' ', sl->len);
    return sl->n == k && sp && strncmp(sp + 1, cmd, 4) == 0 && (sp[5] == '*' || sp[5] == ' ');
}

/* Is line k a job M105 still kept? */
static int is_m105(const amp_proto *p, long k) { return slot_is(p, k, "M105"); }

/* `ok T:` is M105's answer and nothing else's: it acknowledges the oldest M105 in flight and, since Marlin
   runs commands in order, every line before it, whose oks may have been garbled away. Returns 1 if used. */
static int ack_through_m105(amp_proto *p)
{
    long k;
    for (k = p->acked + 1; k <= p->top_sent; k++) {
        if (is_m105(p, k)) {
            while (p->acked < k)
                ack_one(p);
            return 1;
        }
    }
    return 0;
}

static void become_ready(amp_proto *p)
{
    /* an M110 sent again after a timeout may still answer: its ok is no job line's (the job would run one
       line off and a reset report name the wrong line). Swallowing one too many only delays an ack. */
    p->stale_oks = p->o.flavor == AMP_PROTO_MARLIN && p->m110_out > 1 ? p->m110_out - 1 : 0;
    p->m110_out = 0;
    if (p->relink) {
        p->relink = 0;
        p->send_n = p->relink_base + 1; /* the printer holds (and has run) everything up to it */
        p->relink_base = -1;
    }
    p->ready_base = p->acked;
    p->adv_prev = -1;
    p->state = AMP_PROTO_RUNNING;
    p->resync = 0;
    p->skip_ok = 0;
    p->sync_err = 0;
    p->last_line = -1;
    emit(p, AMP_EV_READY, 0, p->rx);
}

/* Re-handshake (proto.h, amp_proto_link_restored), phases 1 and 2: plain oks are the queued lines' (or a
   Resend's) and place nothing; an `ok T:` answers an M105. Once one of OUR M105s answered, every job line up
   to the base ran (Marlin runs its queue in order, ours came after them): the job's own M105s still queued
   may answer first, so the barrier is the (c+1)-th `ok T:` with c of them in the range. */
static void relink_ok(amp_proto *p, const char *s)
{
    long k, c = 0;
    if (!has_temp(s))
        return;
    p->relink_temps++;
    if (p->sync_phase != 2 || p->relink_base < 0)
        return;
    for (k = p->acked + 1; k <= p->relink_base; k++)
        c += is_m105(p, k);
    if (p->relink_temps < c + 1)
        return;
    while (p->acked < p->relink_base) {
        p->acked++;
        emit(p, AMP_EV_ACK, p->acked, s);
    }
    p->sync_phase = 3; /* M110 N<base>: our M105 used the next number */
    p->resync = 1;
}

/* Re-handshake: the printer refused our line and names the last line it received (m - 1). */
static void relink_resend(amp_proto *p, long m, long ll)
{
    p->skip_ok = 0; /* oks place nothing here */
    p->resync = 1;
    p->sync_phase = 1; /* ask again, unless the answer is conclusive */
    if (ll != m - 1 && m != p->relink_cand) {
        p->relink_cand = m; /* a garbled number must not name the base: `Last Line:` or a second answer agrees */
        return;
    }
    p->relink_cand = -1;
    if (p->relink_base >= 0) {
        /* known base: the printer holds it (nothing sent), or one of our M105s after it */
        if (m - 1 >= p->relink_base && m - 1 <= p->relink_m105) {
            p->relink_next = m;
            p->sync_phase = 2;
        } else if (m == 1) {
            stop(p, AMP_EV_RESET, "printer asks for line 1 after the link came back: it restarted");
        }
        return;
    }
    if (m == 1 && p->top_sent >= 1) {
        /* its line counter is back at 0: it restarted while unplugged (banner lost), or line 1 never arrived;
           lines whose oks the unplug swallowed may have run before a restart, so no host can go on safely */
        stop(p, AMP_EV_RESET, "printer asks for line 1 after the link came back: it restarted");
        return;
    }
    if (m - 1 < p->acked || m - 1 > p->top_sent || (m > 1 && p->ring[(m - 1) & RING_MASK].n != m - 1 && m - 1 > p->acked))
        return; /* not a line it can hold: garbled beyond both checks; ask again */
    p->relink_base = m - 1;
    p->relink_next = m;
    p->sync_phase = 2;
}

/* Marlin handshake (see proto.h, "Readiness"): the ok of M110, then the provoked resend and M105. */
static void sync_ok(amp_proto *p, const char *s)
{
    long n = 0, b = 0;
    if (parse_adv(s + 2, &n, &b))
        p->adv_seen = 1;
    if (p->relink && p->sync_phase != 3) {
        relink_ok(p, s);
        return;
    }
    if ((p->sync_phase == 0 || p->sync_phase == 3) && has_temp(s))
        return; /* an M105's answer (a learning or re-handshake M105 answered late), never the M110's */
    if ((p->sync_phase == 0 || p->sync_phase == 3) && p->skip_ok) {
        p->skip_ok = 0; /* the Resend's ok: now the M110 goes out again */
        p->resync = 1;
        return;
    }
    if ((p->sync_phase == 0 || p->sync_phase == 3) && p->sync_err) {
        /* the M110 was refused (garbled on the way) and the Resend after the error was garbled too: this ok
           is the refusal's. Taken for the M110's, the job would start one line off: after an unplug its first
           line went to the number the re-handshake's M105 had used, and the printer skipped it (unplug soak) */
        p->sync_err = 0;
        if (p->m110_out > 0)
            p->m110_out--;
        p->resync = 1;
        return;
    }
    if (p->sync_phase == 0 || p->sync_phase == 3) {
        if (p->sync_phase == 0 && p->o.learn && p->learn_fail < 2) {
            p->sync_phase = 1;
            p->resync = 1;
            p->m110_out = 0; /* a second answer of a repeated M110 would come now and be ignored (phase 1) */
            return;
        }
        become_ready(p);
        return;
    }
    if (p->sync_phase != 2)
        return; /* phase 1: an ok before the provoked Resend is stale */
    if (!has_temp(s)) {
        if (p->saw_ok == 0)
            p->saw_ok = 1; /* the ok Marlin sends after Resend: (M105's own ok carries T:) */
        return;
    }
    if (p->saw_ok == 2) {
        /* a garbled line came between the Resend and M105's answer: it may have been the ok; ask again */
        p->learn_fail++;
        p->sync_phase = p->learn_fail < 2 ? 1 : 3;
        p->resync = 1;
        return;
    }
    p->o.resend_ok = p->saw_ok == 1;
    if (p->o.mode == AMP_PROTO_ADVANCED && !p->adv_seen)
        p->o.mode = AMP_PROTO_FIXED; /* ADVANCED_OK asked for, not spoken: the fixed window */
    emit(p, AMP_EV_LEARNED, p->o.resend_ok,
         p->o.resend_ok ? (p->adv_seen ? "resend-ok=1 advanced-ok=1" : "resend-ok=1 advanced-ok=0")
                        : (p->adv_seen ? "resend-ok=0 advanced-ok=1" : "resend-ok=0 advanced-ok=0"));
    p->sync_phase = 3; /* M110 again: M105 used line 1 */
    p->resync = 1;
}

/* ADVANCED_OK: `ok N<n> P<p> B<b>`, where n is the number of the line this ok is for (Marlin prints the N of
   the command it just ran) and b the free queue slots, one low (the command still holds its slot). Lines run
   in order, once each, so the numbers of consecutive oks go up by one; a number that follows the previous
   one is trusted, and places the oks that were lost before it (or drops one counted that was none, e.g. a
   reply garbled into "ok"); an unconfirmed number (the first, or after a gap: maybe a garbled digit) only
   counts as one ok, and the next ok confirms it. */
static void adv_ok(amp_proto *p, long n, long b)
{
    int confirmed = p->adv_prev >= 0 && n == p->adv_prev + 1;
    p->adv_prev = n;
    if (!confirmed || n < 1 || n > p->top_sent || n < p->ready_base) {
        ack_one(p);
    } else if (n > p->acked) {
        if (n > p->acked + 1) {
            p->n_lost_oks += n - p->acked - 1;
            emit(p, AMP_EV_INFO, n, "lost oks placed by the ADVANCED_OK line number");
        }
        while (p->acked < n)
            ack_one(p);
    } else if (n < p->acked) {
        p->acked = n; /* an ok was counted that was none: the line may not have run yet */
    }
    if (p->o.mode == AMP_PROTO_ADVANCED) {
        /* b + 1 slots are free now, counting the one this command leaves: a lower bound of the queue size
           (the lines received behind it hold the others). Raise the window to it, never shrink it on it; a
           garbled digit must not open the window, so the lower of two oks in a row counts. */
        long q = b + 1, lo;
        if (q > AMP_PROTO_MAX_INFLIGHT)
            q = AMP_PROTO_MAX_INFLIGHT;
        lo = q < p->q_cand ? q : p->q_cand;
        if (lo > p->qslots)
            p->qslots = (int)lo;
        p->q_cand = (int)q;
    }
}

static void on_ok(amp_proto *p, unsigned long now)
{
    long n = 0, b = 0;
    p->last_rx = now;
    if (p->state == AMP_PROTO_SYNCING) {
        sync_ok(p, p->rx);
        return;
    }
    if (p->state != AMP_PROTO_RUNNING)
        return;
    p->last_line = -1;
    if (p->stale_oks > 0 && p->acked - p->ready_base < p->qslots) {
        p->stale_oks--; /* the answer of a repeated handshake M110 (only near the start of the job) */
        emit(p, AMP_EV_INFO, 0, p->rx);
        return;
    }
    if (p->skip_ok) {
        /* Marlin answers each rejected line with "Resend: n" and an ok that acknowledges nothing */
        p->skip_ok = 0;
        return;
    }
    p->probing = 0;
    if (has_temp(p->rx)) {
        /* `ok T:` answers an M105 and nothing else: with none in flight it is a late answer of one (the
           handshake's), and counting it would acknowledge a line that may not have run */
        if (!ack_through_m105(p)) {
            p->n_garbage++;
            emit(p, AMP_EV_INFO, 0, p->rx);
        }
        return;
    }
    if (parse_adv(p->rx + 2, &n, &b))
        adv_ok(p, n, b);
    else
        ack_one(p);
}

/* A Resend during a handshake (the learning's, the M110's, or the re-handshake's). */
static void sync_resend(amp_proto *p, long m, long ll)
{
    if (p->relink && p->sync_phase != 3) {
        relink_resend(p, m, ll);
        return;
    }
    if (p->sync_phase == 1 || p->sync_phase == 2) {
        p->sync_phase = 2; /* the provoked request (or N1 M105 was garbled): M105 goes out next */
        p->saw_ok = 0;
        p->skip_ok = 0;    /* the ok after it is what learning looks for */
        p->resync = 1;
        return;
    }
    /* phases 0 and 3: the M110 itself was garbled. The ok that follows the Resend must not pass for the
       M110's (the job would start one line off): send M110 again only once it is in. */
    p->sync_err = 0; /* the Resend answers for the error before it */
    if (p->m110_out > 0)
        p->m110_out--; /* that M110 is answered */
    p->resync = !p->skip_ok;
}

/* A request for line m, no longer kept (@p ll: the `Last Line:` of the error before it, -1 if none). */
static void resend_not_kept(amp_proto *p, long m, long ll)
{
    if (m == 1 && ll != 0 && ++p->line1_reqs < 2) {
        /* one witness only (no `Last Line: 0` before it): maybe a garbled number; a restarted printer asks
           again for the next line or the probe */
        p->n_garbage++;
        emit(p, AMP_EV_INFO, m, p->rx);
    } else if (m == 1) {
        emit(p, AMP_EV_INFO, m, p->rx); /* the request itself, for the log */
        stop(p, AMP_EV_RESET, "printer asks for line 1: it restarted (banner lost)");
    } else if (m <= p->acked) {
        p->n_garbage++; /* far behind every line in flight: a garbled number; the probe sorts it out */
        emit(p, AMP_EV_INFO, m, p->rx);
    } else {
        stop(p, AMP_EV_FATAL, "resend requested for a line no longer kept");
    }
}

static void on_resend(amp_proto *p, long m, int with_ok, unsigned long now)
{
    long k, ll = p->last_line;
    unsigned long stale_bytes = 0;
    p->last_rx = now;
    if (with_ok && p->o.resend_ok)
        p->skip_ok = 1;
    p->last_line = -1;
    if (p->state == AMP_PROTO_SYNCING) {
        sync_resend(p, m, ll);
        return;
    }
    if (p->state != AMP_PROTO_RUNNING)
        return;
    if (m < 1 || m > p->top_sent + 1) {
        p->n_garbage++; /* a garbled number, or a request for a line never sent: ignore */
        emit(p, AMP_EV_INFO, m, p->rx);
        return;
    }
    if (m < p->next_n && p->ring[m & RING_MASK].n != m) {
        resend_not_kept(p, m, ll);
        return;
    }
    /* lines from m on were not received, so they cannot have been executed */
    if (p->acked >= m)
        p->acked = m - 1;
    if (p->probing) {
        /* The link was silent without busy: the printer is idle, so every line it received (< m) has run;
           oks lost on the way are made up for here. */
        p->probing = 0;
        while (p->acked < m - 1) {
            p->acked++;
            emit(p, AMP_EV_ACK, p->acked, p->rx);
        }
        p->rewind_n = -1;
        p->settling = 0;
        p->echo_budget = 0;
        if (m < p->send_n) {
            p->n_rewinds++;
            emit(p, AMP_EV_RESEND, m, p->rx);
        }
        p->send_n = m;
        return;
    }
    if (p->rewind_n == m && (p->settling || p->echo_budget > 0)) {
        /* After an error Marlin drops its receive buffer, so each line sent ahead provokes another
           request for the same line (or its cut tail does, once): rewind once per burst, not once per
           error, and keep quiet while the echoes arrive. Each line that was sent after m when we rewound
           can echo at most once, whenever its echo comes: counting them, not the clock, tells an old
           burst's echo from a new request (a loaded host once read slow echoes as new requests, rewound
           on each, and the re-sent lines were cut by the next flush: a livelock). */
        unsigned long ext = now + p->o.settle_ms + 2 * p->err_lat;
        if (p->echo_budget > 0)
            p->echo_budget--;
        if (p->settling && ext - p->settle_until < (1UL << 30))
            p->settle_until = ext;
        if (p->echo_budget == 0)
            p->settling = 0; /* every line sent ahead has answered: the burst is over, re-send now */
        p->n_dups++;
        emit(p, AMP_EV_RESEND_DUP, m, p->rx);
        return;
    }
    if (m >= p->send_n) {
        /* the printer already holds the lines before m (we had rewound too far on a garbled number):
           go forward; if m itself was garbled, the printer's next request puts us right */
        p->send_n = m;
        p->rewind_n = -1;
        p->settling = 0;
        p->echo_budget = 0;
        return;
    }
    for (k = m; k <= p->top_sent && k < p->send_n; k++)
        stale_bytes += p->ring[k & RING_MASK].len;
    if (p->ring[m & RING_MASK].n == m && m <= p->top_sent) {
        /* how long the printer took to answer line m: the scale on which the echoes arrive */
        unsigned long lat = now - p->ring[m & RING_MASK].t_sent;
        if (lat > p->o.timeout_ms / 4)
            lat = p->o.timeout_ms / 4;
        p->err_lat = p->err_lat ? (3 * p->err_lat + lat) / 4 : lat;
    }
    p->echo_budget = p->send_n - 1 - m; /* lines sent after m: each echoes at most once */
    if (p->echo_budget < 0)
        p->echo_budget = 0;
    p->rewind_n = m;
    p->settling = 1;
    p->settle_until = now + p->o.settle_ms + 2 * p->err_lat + stale_bytes * p->o.byte_us / 1000UL;
    p->send_n = m;
    p->n_rewinds++;
    emit(p, AMP_EV_RESEND, m, p->rx);
}

/* How many of the first bytes of s match pattern position by position. */
static int fuzzy(const char *s, const char *pat)
{
    int k = 0, i;
    for (i = 0; pat[i] && s[i]; i++)
        k += s[i] == pat[i];
    return k;
}

static int has_temp(const char *s)
{
    return strstr(s, " T:") != NULL || starts(s, "T:") || starts(s, "B:");
}

/* Is a heating wait (M109, M190, M191) among the lines sent and not acknowledged? While one runs, its
   temperature reports (every second) are the printer's only sign of life. Auto-reports (M155) come whatever
   happens to the oks: taken as life, they kept a link whose oks were lost from ever probing (the window
   full, the printer idle, the job stalled for good). */
static int heating_in_flight(const amp_proto *p)
{
    long n;
    for (n = p->acked + 1; n <= p->top_sent && n <= p->acked + AMP_PROTO_MAX_INFLIGHT; n++)
        if (slot_is(p, n, "M109") || slot_is(p, n, "M190") || slot_is(p, n, "M191"))
            return 1;
    return 0;
}

/* An `Error:` text (after the prefix) of the line-number/checksum protocol? Fuzzy, because on a noisy link
   a garbled protocol error must not pass for a firmware error that stops the job. */
static int protocol_error(const char *s)
{
    static const char *const msgs[] = {"Line Number is not Last Line Number+1", "checksum mismatch",
                                       "No Checksum with line number", "No Line Number with checksum",
                                       "Wrong checksum", "Missing checksum", "expected line"};
    size_t i, n = strlen(s);
    if (strstr(s, "Last Line") || strstr(s, "ast Line:"))
        return 1;
    for (i = 0; i < sizeof msgs / sizeof msgs[0]; i++) {
        size_t m = strlen(msgs[i]), k = n < m ? n : m;
        /* whole, or cut short by a byte garbled into a line end: compare what there is, allowing one
           wrong byte in eight and one more (a cut line may be garbled too: "No L)ne") */
        if (fuzzy(s, msgs[i]) + (int)(k / 8) + (k < m ? (k >= 4) : 2) >= (int)k)
            return 1;
    }
    return 0;
}

/* The oldest line in flight: both firmwares report an error while running the command whose ok comes next. */
static long head_line(const amp_proto *p)
{
    return p->acked < p->top_sent ? p->acked + 1 : 0;
}

static void fw_error(amp_proto *p, const char *s)
{
    p->n_fwerrors++;
    emit(p, AMP_EV_FWERROR, p->state == AMP_PROTO_RUNNING ? head_line(p) : 0, s);
}

/* An `Error:` neither recognisably of the resend protocol nor a halt waits for the next line: Marlin
   follows a protocol error at once with `Resend:`/`rs`, a firmware error never (on a noisy link a protocol
   error can be garbled beyond recognition, and must not stop the job). */
static void settle_pending_error(amp_proto *p, int next_is_resend)
{
    if (!p->pend_err)
        return;
    p->pend_err = 0;
    if (next_is_resend) {
        p->n_garbage++;
        emit(p, AMP_EV_ERROR, 0, p->pend_text);
        return;
    }
    p->n_fwerrors++;
    emit(p, AMP_EV_FWERROR, p->pend_line, p->pend_text);
}

/* `// action:cancel`, `//action:pause`, ... (OctoPrint's action commands, sent by Marlin's host actions). */
static int action(amp_proto *p, const char *s)
{
    if (starts(s, "// action:") || starts(s, "//action:")) {
        emit(p, AMP_EV_ACTION, p->state == AMP_PROTO_RUNNING ? head_line(p) : 0, strchr(s, ':') + 1);
        return 1;
    }
    return 0;
}

static void marlin_error(amp_proto *p, const char *s)
{
    p->n_errors++;
    if (protocol_error(s + 6)) {
        const char *ll = strstr(s, "Line:");
        if (!(ll && parse_long(ll + 5, &p->last_line)))
            p->last_line = -1;
        if (p->state == AMP_PROTO_SYNCING && (p->sync_phase == 0 || p->sync_phase == 3) && p->m110_out > 0)
            p->sync_err = 1; /* our M110 refused: its Resend, or the ok after it, settles it (sync_ok) */
        emit(p, AMP_EV_ERROR, 0, s);
        return;
    }
    /* thermal runaway, MINTEMP, kill(), a failed probe...: the command at the head of the queue */
    if (strstr(s, "halted") || strstr(s, "kill") || strstr(s, "stopped") || strstr(s, "Stopped")) {
        fw_error(p, s);
        if (p->state != AMP_PROTO_STOPPED)
            stop(p, AMP_EV_SHUTDOWN, s);
        return;
    }
    p->pend_err = 1;
    p->pend_line = p->state == AMP_PROTO_RUNNING ? head_line(p) : 0;
    strncpy(p->pend_text, s, sizeof p->pend_text - 1);
    p->pend_text[sizeof p->pend_text - 1] = '\0';
}

/* Marlin answers an unknown command with an ok. If the text is one of our lines in flight it is a warning
   for that line; if not, it is the tail of a line cut by an RX flush, and that ok acknowledges nothing. */
static void marlin_unknown(amp_proto *p, const char *s)
{
    const char *q = strchr(s, '"'), *qe = q ? strrchr(q + 1, '"') : NULL;
    long k;
    for (k = p->acked + 1; q && qe && k < p->send_n; k++) {
        const amp_proto_slot *sl = &p->ring[k & RING_MASK];
        const char *a = memchr(sl->text, ' ', sl->len), *b = NULL;
        size_t i;
        for (i = sl->len; i > 0; i--)
            if (sl->text[i - 1] == '*') {
                b = sl->text + i - 1;
                break;
            }
        if (a && b && b > a && (size_t)(b - a - 1) == (size_t)(qe - q - 1) &&
            memcmp(a + 1, q + 1, (size_t)(b - a - 1)) == 0) {
            p->n_warnings++;
            emit(p, AMP_EV_WARNING, k, s);
            return;
        }
    }
    p->skip_ok = 1;
    emit(p, AMP_EV_INFO, 0, s);
}

/* The boot banner `start`: expected while connecting, a late boot during the handshake, a reset mid-job. */
static void on_start(amp_proto *p, const char *s, unsigned long now)
{
    p->last_rx = now;
    if (p->state == AMP_PROTO_CONNECTING) {
        p->start_seen = 1;
    } else if (p->state == AMP_PROTO_SYNCING && p->relink) {
        stop(p, AMP_EV_RESET, s); /* it restarted while unplugged (or when the port was opened) */
    } else if (p->state == AMP_PROTO_SYNCING) {
        p->resync = 1; /* the banner came late and our M110 went to a booting printer */
        p->sync_phase = 0;
        p->skip_ok = 0;
        p->m110_out = 0; /* it answers none of the M110s sent before */
    } else if (p->state == AMP_PROTO_RUNNING) {
        if (p->next_n == 1) {
            p->state = AMP_PROTO_SYNCING;
            p->resync = 1;
            p->sync_phase = 0;
        } else {
            /* the printer lost its queue and position: never continue blindly */
            stop(p, AMP_EV_RESET, s);
        }
    }
}

static void handle_marlin(amp_proto *p, const char *s, unsigned long now)
{
    long m;
    if (p->pend_err) {
        int rs = starts(s, "Resend") || starts(s, "resend") || starts(s, "rs ") || fuzzy(s, "Resend:") >= 5;
        /* a fragment (the rest of the error, split off by a byte garbled into a line end) decides nothing */
        if (rs || starts(s, "ok") || starts(s, "Error:") || starts(s, "error:") || starts(s, "echo:") ||
            starts(s, "//") || starts(s, "start") || starts(s, "wait") || starts(s, "busy:") || has_temp(s))
            settle_pending_error(p, rs);
    }
    if (s[0] == 'o' && s[1] == 'k' && (s[2] == '\0' || s[2] == ' ')) {
        on_ok(p, now);
        if (has_temp(s))
            emit(p, AMP_EV_TEMP, 0, s);
        return;
    }
    if (starts(s, "Resend:") || starts(s, "resend:")) {
        if (parse_long(s + 7, &m))
            on_resend(p, m, 1, now);
        else if (p->last_line >= 1 && p->last_line + 1 <= p->top_sent &&
                 p->ring[(p->last_line + 1) & RING_MASK].n == p->last_line + 1)
            on_resend(p, p->last_line + 1, 1, now); /* the number is garbled; the error before it named the line
                                                       (only a line still kept: never "line 1", a reset) */
        else {
            if (p->o.resend_ok && p->state == AMP_PROTO_RUNNING)
                p->skip_ok = 1; /* its ok still comes */
            p->n_garbage++;
        }
        return;
    }
    if (starts(s, "rs ")) {
        if (parse_long(s + 3, &m))
            on_resend(p, m, 0, now);
        else
            p->n_garbage++;
        return;
    }
    if (starts(s, "start") && (s[5] == '\0' || s[5] == ' ')) {
        on_start(p, s, now);
        return;
    }
    if (starts(s, "Error:") || starts(s, "error:")) {
        marlin_error(p, s);
        return;
    }
    if (action(p, s))
        return;
    if (starts(s, "echo:Unknown command:") && p->state == AMP_PROTO_RUNNING) {
        marlin_unknown(p, s);
        return;
    }
    if (starts(s, "echo:busy:") || starts(s, "busy:")) {
        p->last_rx = now;
        if (p->relink)
            p->t0 = now; /* re-handshake behind a long command (M109): the printer is alive, keep waiting */
        p->n_busy++;
        emit(p, AMP_EV_BUSY, 0, s);
        return;
    }
    if (strcmp(s, "wait") == 0) {
        /* Marlin says wait when its queue is empty and it is idle. It keeps nothing alive; but if we still
           count lines in flight, their oks were lost (or the lines were): probe now instead of after the timeout. */
        if (p->state == AMP_PROTO_RUNNING && p->send_n - 1 > p->acked && !p->probing && !p->settling)
            p->last_rx = now - p->o.timeout_ms;
        return;
    }
    if (has_temp(s)) {
        if (heating_in_flight(p)) {
            p->last_rx = now; /* M109/M190 report every second while heating */
            if (p->relink)
                p->t0 = now;
        }
        emit(p, AMP_EV_TEMP, 0, s);
        return;
    }
    if (!starts(s, "echo:") && !starts(s, "//")) {
        p->n_garbage++;
        if (p->state == AMP_PROTO_SYNCING && p->sync_phase == 2)
            p->saw_ok = 2; /* could have been the ok after Resend: learning is inconclusive */
        if (p->o.resend_ok && p->state == AMP_PROTO_RUNNING && fuzzy(s, "Resend:") >= 5) {
            /* a garbled "Resend:": its ok must not count as an acknowledgement (an ok too few is
               repaired by the probe, an ok too many could hide a lost line) */
            const char *c = strchr(s, ':');
            p->skip_ok = 1;
            if (c && parse_long(c + 1, &m))
                on_resend(p, m, 0, now);
            return;
        }
        if (strlen(s) == 5 && fuzzy(s, "start") >= 4 && p->state == AMP_PROTO_RUNNING && p->next_n > 1) {
            stop(p, AMP_EV_RESET, s); /* a garbled boot banner is still a reset */
            return;
        }
    }
    emit(p, AMP_EV_INFO, 0, s);
}

static void handle_klipper(amp_proto *p, const char *s, unsigned long now)
{
    int syncing = p->state == AMP_PROTO_SYNCING;
    if (s[0] == 'o' && s[1] == 'k' && (s[2] == '\0' || s[2] == ' ')) {
        p->last_rx = now;
        if (p->state == AMP_PROTO_RUNNING) {
            ack_one(p);
        } else if (syncing && p->sync_n > 0) {
            /* the ok of our STATUS: ready, or ask again after ready_poll_ms */
            p->sync_n = 0;
            if (p->ready_seen)
                become_ready(p);
            else
                p->next_poll = now + p->o.ready_poll_ms;
        }
        return;
    }
    if (syncing && (starts(s, "!!") || starts(s, "//"))) {
        /* STATUS answers `// Klipper state: Ready`, or `!! <why>` and `!! Klipper state: Not ready` */
        if (strstr(s, "Klipper state: Ready"))
            p->ready_seen = 1;
        else if (starts(s, "!!") || strstr(s, "Klipper state:"))
            emit(p, AMP_EV_WAITING, 0, s);
        else
            emit(p, AMP_EV_INFO, 0, s);
        return;
    }
    if (strstr(s, "Klipper state: Shutdown") && (starts(s, "//") || starts(s, "!!"))) {
        if (p->state != AMP_PROTO_STOPPED)
            stop(p, AMP_EV_SHUTDOWN, s);
        return;
    }
    if (starts(s, "!!")) {
        /* "!! Move out of range", "!! Must home axis first", "!! Printer is not ready" (a restart underneath
           us), a macro's error: the failed command still gets its ok, the host decides what happens next */
        p->n_errors++;
        fw_error(p, s);
        return;
    }
    if (starts(s, "// Unknown command")) {
        p->n_warnings++;
        emit(p, AMP_EV_WARNING, head_line(p), s);
        return;
    }
    if (action(p, s))
        return;
    if (has_temp(s)) {
        p->last_rx = now;
        emit(p, AMP_EV_TEMP, 0, s);
        return;
    }
    emit(p, AMP_EV_INFO, 0, s);
}

/* A Marlin reply line that two replies became when the newline between them was garbled: an `ok` next to
   a control character (Marlin prints none). Splits it in place and handles both parts; 0 if not such a line.
   Only next to an `ok`: a control character inside a number must keep that number unparseable. */
static int split_merged(amp_proto *p, char *s, unsigned long now)
{
    size_t i, n = strlen(s);
    for (i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        int ctl = (c < 0x20 && c != '\t') || c == 0x7f;
        if (!ctl)
            continue;
        if ((i == 2 && s[0] == 'o' && s[1] == 'k') ||
            (s[i + 1] == 'o' && s[i + 2] == 'k' && (s[i + 3] == '\0' || s[i + 3] == ' '))) {
            s[i] = '\0';
            handle_marlin(p, s, now);
            handle_marlin(p, s + i + 1, now);
            return 1;
        }
    }
    return 0;
}

static void handle_line(amp_proto *p, unsigned long now)
{
    char *s = p->rx;
    while (*s == ' ' && s[1] == ' ')
        s++;
    if (p->o.flavor == AMP_PROTO_KLIPPER) {
        handle_klipper(p, s, now);
        return;
    }
    if (split_merged(p, s, now))
        return;
    if (strlen(s) == 2 && (s[0] == 'o' || s[1] == 'k')) {
        /* "ok" with one byte garbled: Marlin sends no other two-byte line, and a lost ok stalls the window
           until the timeout probe */
        s[0] = 'o';
        s[1] = 'k';
    }
    handle_marlin(p, s, now);
}

void amp_proto_feed(amp_proto *p, const char *bytes, size_t n, unsigned long now_ms)
{
    size_t i;
    for (i = 0; i < n; i++) {
        char c = bytes[i];
        if (c == '\n' || c == '\r' || c == '\0') {
            if (p->rxlen > 0) {
                p->rx[p->rxlen] = '\0';
                handle_line(p, now_ms);
            }
            p->rxlen = 0;
            p->rx_over = 0;
        } else if (p->rxlen < AMP_PROTO_RX_MAX) {
            p->rx[p->rxlen++] = c;
        } else {
            p->rx_over = 1;
        }
    }
}

/* May line p->send_n go out now? */
static int window_allows(const amp_proto *p)
{
    long inflight = p->send_n - 1 - p->acked, k, bytes;
    long lim;
    if (p->o.mode == AMP_PROTO_PINGPONG)
        return inflight < 1;
    if (p->o.flavor == AMP_PROTO_KLIPPER)
        return inflight < p->o.window; /* Klipper stops reading at 20 pending lines */
    lim = p->o.mode == AMP_PROTO_ADVANCED ? AMP_PROTO_MAX_INFLIGHT : p->o.window;
    if (inflight >= lim)
        return 0;
    /* The oldest qslots lines sit in the command queue (ok comes after execution); the rest wait in the
       serial RX buffer, which must not overflow: Marlin has no flow control. With the queue full Marlin
       stops reading at the last queued line's newline: its guard newline stays in the buffer too. */
    bytes = p->ring[p->send_n & RING_MASK].len + (p->o.guard_nl ? 1 : 0);
    for (k = p->acked + 1 + p->qslots; k < p->send_n; k++)
        bytes += p->ring[k & RING_MASK].len;
    return inflight < p->qslots || bytes <= p->o.rx_bytes;
}

static int copy_out(const char *src, size_t n, char *buf, size_t cap, size_t *len)
{
    if (n > cap)
        return 0;
    memcpy(buf, src, n);
    *len = n;
    return 1;
}

/* Klipper readiness: `STATUS` now and then until it answers Ready (a reply lost: again after the timeout). */
static int klipper_poll(amp_proto *p, unsigned long now, char *buf, size_t cap, size_t *len)
{
    if (p->sync_n > 0 && now - p->last_rx >= p->o.timeout_ms)
        p->sync_n = 0;
    if (p->sync_n > 0 || now - p->next_poll >= (1UL << 30))
        return 0; /* a STATUS is out, or the next one is not due (wrap-safe) */
    p->sync_n = 1;
    p->last_rx = now;
    return copy_out("STATUS\n", 7, buf, cap, len);
}

/* Marlin handshake line of the current phase (proto.h, "Readiness"). */
static int marlin_sync(amp_proto *p, unsigned long now, char *buf, size_t cap, size_t *len)
{
    amp_proto_slot tmp;
    char cmd[32];
    size_t k;
    long base = p->next_n - 1;
    if (!p->resync && now - p->last_rx >= p->o.timeout_ms) {
        p->n_timeouts++;
        emit(p, AMP_EV_TIMEOUT, 0, "no answer during the handshake");
        if (!p->relink && (p->sync_phase == 1 || p->sync_phase == 2))
            p->learn_fail++;
        p->sync_phase = p->relink ? 1 : 0; /* start over from M110; re-handshake: ask for the last line again */
        p->resync = 1;
        p->skip_ok = 0;
    }
    if (!p->resync)
        return 0;
    p->resync = 0;
    p->last_rx = now;
    if (p->relink) {
        /* re-handshake: phase 1 asks with a number beyond any the printer can expect, phase 2 is the M105
           after the last line it holds, phase 3 the M110 that makes the next job line welcome */
        base = p->relink_base;
        if (p->sync_phase == 1) {
            /* a newline first: the unplug may have cut a line in the printer's buffer, and the query must not
               be appended to it (the merged line could pass the checksum with odds 1/256 and run) */
            p->sync_n = (p->top_sent > p->relink_m105 ? p->top_sent : p->relink_m105) + 2;
            frame(p, &tmp, p->sync_n, "M105", 4);
            memmove(tmp.text + 1, tmp.text, tmp.len);
            tmp.text[0] = '\n';
            return copy_out(tmp.text, tmp.len + 1u, buf, cap, len);
        }
        if (p->sync_phase == 2) {
            p->sync_n = p->relink_next;
            if (p->relink_m105 < p->sync_n)
                p->relink_m105 = p->sync_n;
            frame(p, &tmp, p->sync_n, "M105", 4);
            return copy_out(tmp.text, tmp.len, buf, cap, len);
        }
    } else if (p->sync_phase == 1 || p->sync_phase == 2) {
        /* phase 1: N<base+2> where base+1 is expected provokes a resend; phase 2: N<base+1> M105 */
        p->sync_n = base + (p->sync_phase == 1 ? 2 : 1);
        frame(p, &tmp, p->sync_n, "M105", 4);
        return copy_out(tmp.text, tmp.len, buf, cap, len);
    }
    /* "N<k> M110 N<k>": the printer expects N<k+1> next */
    p->m110_out++;
    p->sync_err = 0;
    p->sync_n = base;
    memcpy(cmd, "M110 N", 6);
    k = 6 + put_long(cmd + 6, base);
    frame(p, &tmp, base, cmd, k);
    return copy_out(tmp.text, tmp.len, buf, cap, len);
}

int amp_proto_line_text(const amp_proto *p, long n, char *buf, size_t cap)
{
    const amp_proto_slot *sl;
    const char *a, *b;
    size_t k;
    if (!cap)
        return 0;
    buf[0] = '\0';
    if (n < 1 || n >= p->next_n)
        return 0;
    sl = &p->ring[n & RING_MASK];
    if (sl->n != n)
        return 0;
    a = sl->text;
    b = sl->text + sl->len;
    while (b > a && (b[-1] == '\n'))
        b--;
    if (p->o.flavor == AMP_PROTO_MARLIN) {
        const char *sp = memchr(a, ' ', (size_t)(b - a)), *st = b;
        while (st > a && st[-1] != '*')
            st--;
        if (sp && st > sp + 1) {
            a = sp + 1;
            b = st - 1;
        }
    }
    k = (size_t)(b - a) < cap - 1 ? (size_t)(b - a) : cap - 1;
    memcpy(buf, a, k);
    buf[k] = '\0';
    return 1;
}

int amp_proto_next_tx(amp_proto *p, unsigned long now, char *buf, size_t cap, size_t *len)
{
    amp_proto_slot *s;
    if (p->estop) {
        p->estop = 0;
        if (p->state != AMP_PROTO_STOPPED)
            stop(p, AMP_EV_SHUTDOWN, "emergency stop");
        return copy_out("M112\n", 5, buf, cap, len);
    }
    if (p->state == AMP_PROTO_STOPPED)
        return 0;
    if (p->state != AMP_PROTO_RUNNING && p->o.ready_ms && now - p->t0 >= p->o.ready_ms) {
        stop(p, AMP_EV_NOTREADY, "the printer did not become ready in time");
        return 0;
    }
    if (p->state == AMP_PROTO_CONNECTING) {
        if (p->o.flavor == AMP_PROTO_MARLIN && !p->start_seen && now - p->t0 < p->o.boot_ms)
            return 0;
        p->state = AMP_PROTO_SYNCING;
        p->resync = 1;
        p->sync_phase = 0;
        p->next_poll = now;
    }
    if (p->state == AMP_PROTO_SYNCING)
        return p->o.flavor == AMP_PROTO_KLIPPER ? klipper_poll(p, now, buf, cap, len) : marlin_sync(p, now, buf, cap, len);
    /* RUNNING */
    if ((p->send_n - 1 > p->acked || p->probing) && now - p->last_rx >= p->o.timeout_ms) {
        settle_pending_error(p, 0);
        p->n_timeouts++;
        p->last_rx = now;
        if (p->o.flavor == AMP_PROTO_KLIPPER) {
            emit(p, AMP_EV_TIMEOUT, p->acked + 1, "no reply");
            return 0;
        }
        /* Probe: send the newest line again. The line numbers make this safe: the printer either runs it
           (it was lost) or answers with Resend: <the line it expects>. */
        if (p->probing && ++p->silent_probes >= 3 &&
            now - p->probe_t0 >= (3 * p->o.timeout_ms > 30000 ? 3 * p->o.timeout_ms : 30000)) {
            /* probes unanswered for long, no busy: a halted printer whose last words were garbled (a slow
               host or printer only costs more probes: the line numbers make them harmless) */
            stop(p, AMP_EV_FATAL, "the printer answers nothing (probes unanswered for 30 s or more)");
            return 0;
        }
        if (!p->probing) {
            p->silent_probes = 0;
            p->probe_t0 = now;
        }
        p->probing = 1;
        p->skip_ok = 0;
        p->rewind_n = -1;
        p->settling = 0;
        p->echo_budget = 0;
        emit(p, AMP_EV_TIMEOUT, p->send_n - 1, "no reply, probing");
        s = &p->ring[(p->send_n - 1) & RING_MASK];
        p->n_resent++;
        return copy_out(s->text, s->len, buf, cap, len);
    }
    if (p->settling) {
        if (now - p->settle_until >= (1UL << 30))
            return 0; /* still settling (wrap-safe: settle_until lies ahead of now) */
        p->settling = 0;
    }
    if (p->verify && !p->probing && p->send_n - 1 == p->acked && p->send_n == p->next_n) {
        p->verify = 0;
        p->probing = 1;
        p->skip_ok = 0;
        p->last_rx = now;
        s = &p->ring[(p->send_n - 1) & RING_MASK];
        p->n_resent++;
        return copy_out(s->text, s->len, buf, cap, len);
    }
    if (p->probing || p->send_n >= p->next_n || !window_allows(p))
        return 0;
    s = &p->ring[p->send_n & RING_MASK];
    if (!copy_out(s->text, s->len, buf, cap, len))
        return 0;
    if (p->send_n <= p->top_sent)
        p->n_resent++;
    else
        p->n_sent++;
    if (p->send_n > p->top_sent)
        p->top_sent = p->send_n;
    s->t_sent = now;
    if (p->send_n - 1 == p->acked)
        p->last_rx = now; /* the reply clock starts with the first line in flight */
    p->send_n++;
    return 1;
}

long amp_proto_wait_ms(const amp_proto *p, unsigned long now)
{
    unsigned long el;
    if (p->estop)
        return 0;
    if (p->state == AMP_PROTO_STOPPED)
        return -1;
    if (p->state == AMP_PROTO_CONNECTING) {
        el = now - p->t0;
        if (p->o.flavor == AMP_PROTO_KLIPPER)
            return 0;
        return p->start_seen || el >= p->o.boot_ms ? 0 : (long)(p->o.boot_ms - el);
    }
    if (p->state == AMP_PROTO_SYNCING && p->o.flavor == AMP_PROTO_KLIPPER) {
        if (p->sync_n > 0) {
            el = now - p->last_rx;
            return el >= p->o.timeout_ms ? 0 : (long)(p->o.timeout_ms - el);
        }
        return p->next_poll - now >= (1UL << 30) ? 0 : (long)(p->next_poll - now);
    }
    if (p->verify)
        return 0;
    if (p->settling && p->settle_until - now < (1UL << 30))
        return (long)(p->settle_until - now);
    if (p->state == AMP_PROTO_SYNCING || p->send_n - 1 > p->acked || p->probing) {
        if (p->resync)
            return 0;
        el = now - p->last_rx;
        return el >= p->o.timeout_ms ? 0 : (long)(p->o.timeout_ms - el);
    }
    return -1;
}
