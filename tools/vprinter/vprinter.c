/*
 * ampath-vprinter — a virtual 3-D printer on a pseudo-terminal (docs/interfaces.md §8).
 *
 * Speaks Marlin (2.1 or 2.0 dialect, BUFSIZE, RX buffer, ADVANCED_OK, a planner
 * draining at a modelled speed, a modelled baud rate) or Klipper's pty protocol,
 * injects faults from a seeded PRNG, and records every command it EXECUTED with
 * its line number, so that a test can prove each move ran exactly once, in order.
 *
 * One state machine (struct vp) and one poll() loop. See `ampath-vprinter --help`.
 */
#define _XOPEN_SOURCE 600
#define _DEFAULT_SOURCE

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#define CLI_NO_COMMANDS
#include "../cli.h" /* cli_number, cli_integer: the numbers of ampath's option parser */

#define MAX_CMD 96   /* Marlin MAX_CMD_SIZE */
#define QMAX 64      /* command queue capacity upper bound */
#define PLAN_MAX 64  /* planner slots upper bound */
#define OUT_MAX (1 << 20)
#define LIST_MAX 16

static const char usage[] =
    "usage: ampath-vprinter [options]\n"
    "Creates a pseudo-terminal that behaves like a printer; prints its path (or makes --link PATH).\n"
    "  --link PATH          symlink to the pty slave (recreated after a hang-up)\n"
    "  --log FILE           record every executed command as '<line> <command>'\n"
    "  --flavor F           marlin (default) | klipper\n"
    "  --dialect D          Marlin resend reply: 2.1 (Resend + ok, default) | 2.0 (Resend + ok_to_send,\n"
    "                       with ADVANCED_OK fields) | prusa or bare (Resend without ok) | rs (rs N, no ok)\n"
    "  --bed X,Y,Z          bed volume in mm (default 220,220,250): Klipper answers '!! Move out of range'\n"
    "                       outside it; Marlin clamps (software endstops) and the log marks '# out of bed'\n"
    "  --max-extrude-cross-section A   Klipper: a move whose E per mm of XYZ times the 1.75 mm filament's\n"
    "                       area exceeds A mm^2 is refused ('!! Move exceeds maximum extrusion'; default 0.64,\n"
    "                       Klipper's for a 0.4 mm nozzle; 0 = no check)\n"
    "  --bufsize N          command queue slots (default 4)\n"
    "  --rx-bytes N         serial RX buffer bytes; overflowing bytes are lost (default 128)\n"
    "  --advanced-ok        answer 'ok N<n> P<p> B<b>' (B one low, as Marlin)\n"
    "  --planner N          planner slots (default 16)\n"
    "  --speed MM_S         modelled head speed for G0/G1 (default 0 = instant)\n"
    "  --baud N             modelled link rate, both ways (default 0 = unlimited)\n"
    "  --turnaround MS      time to process each command before its ok (default 0)\n"
    "  --boot-ms MS         delay before the 'start' banner, at start and after a reset (default 0)\n"
    "  --seed N             PRNG seed for the faults (default 1)\n"
    "  --corrupt-in P / --corrupt-out P   fraction of bytes corrupted host->printer / printer->host\n"
    "  --drop-in P / --drop-out P         fraction of bytes dropped\n"
    "  --corrupt-line K     corrupt one byte of the K-th received line (repeatable, up to 16)\n"
    "  --lose-line K        the K-th received line vanishes (repeatable)\n"
    "  --lose-ok K          no ok for the K-th executed command (repeatable)\n"
    "  --busy-at K --busy-secs S   the K-th executed command stays busy S s ('echo:busy: processing')\n"
    "  --busy-interval S    keep-alive period (default 2)\n"
    "  --heat-secs S        M109/M190 take S s, reporting ' T:' every busy-interval (default 0)\n"
    "  --wait-ms MS         print 'wait' after MS idle with an empty queue (default 0 = never)\n"
    "  --reset-after K      reset after executing K commands (repeatable: counts restart)\n"
    "  --hangup-after K --hangup-secs S   unplug after K executed commands (repeatable, counts from the\n"
    "                       start): the pty and --link vanish, the printer keeps running its queue and its\n"
    "                       replies are lost; a new pty (and link) appears after S s. State is kept\n"
    "  --hangup-reset       the printer also resets at each unplug (its banner is lost if --boot-ms < S)\n"
    "  --error-at K         Klipper: the K-th received line fails ('!! ...' then ok)\n"
    "  --shutdown-after K   Klipper: shut down after K executed commands\n"
    "  --ready-after-ms MS  Klipper: '!! Printer is not ready' (+ ok) to everything but STATUS for MS ms\n"
    "  --halt-after K       Marlin: thermal runaway and 'Error:Printer halted. kill() called!' after K commands\n"
    "  --action-at K --action NAME   '// action:NAME' (default cancel) after the K-th executed command\n"
    "Klipper mode refuses moves before G28 ('!! Must home axis first') and answers unknown commands with\n"
    "'// Unknown command'; Marlin mode answers 'echo:Unknown command' (+ ok). Neither logs those as executed.\n"
    "Klipper mode skips a leading line number 'N<n> ' and drops a '*checksum' (unchecked), as Klipper does.\n";

typedef struct plan_move {
    double dur;
} plan_move;

typedef struct vp {
    /* options */
    const char *link, *logpath;
    int klipper, dialect; /* 21, 20, 1 = bare, 2 = rs */
    int bufsize, rx_bytes, adv_ok, planner;
    double speed, baud, turnaround, boot, busy_secs, busy_interval, heat_secs, wait_s, hangup_secs;
    double corrupt_in, corrupt_out, drop_in, drop_out;
    long corrupt_line[LIST_MAX], lose_line[LIST_MAX], lose_ok[LIST_MAX], reset_after[LIST_MAX];
    int n_corrupt_line, n_lose_line, n_lose_ok, n_reset_after;
    long busy_at, error_at, shutdown_after, halt_after, action_at;
    long hangup_after[LIST_MAX];
    int n_hangup, hang_idx, hangup_reset;
    long last_exec_n; /* line number of the last executed command (ADVANCED_OK with an empty queue) */
    const char *action;
    double bed[3], ready_at;
    double off[3]; /* G92 offsets: bed position = logical position - off (both firmwares check the bed) */
    int homed;
    long out_of_bed;
    unsigned long long rng;
    /* link */
    int mfd, sfd;
    char slave[256];
    /* modelled wire: bytes the host wrote, each with the time its last bit arrives */
    char wire[8192];
    double wire_t[8192];
    int wire_len;
    double wire_in_t, out_free;
    /* RX: bytes read from the link waiting for the parser (capacity rx_bytes) */
    char rxq[4096];
    int rxlen;
    char line[MAX_CMD + 2];
    int linelen, line_over;
    /* output */
    char *out;
    size_t outlen;
    size_t protect; /* leading bytes of out sent without faults */
    /* Marlin */
    long last_n;
    char q[QMAX][MAX_CMD + 2];
    long qn[QMAX];
    int qhead, qcount;
    double plan_end[PLAN_MAX]; /* completion times of planned moves, FIFO */
    int plan_head, plan_count;
    double x, y, z, e, f;
    int rel, erel;      /* G91, M83 */
    double max_cross;   /* Klipper: max_extrude_cross_section, mm^2 (0.64: its default for a 0.4 mm nozzle) */
    int booting;
    double boot_at;
    /* executing a long command */
    int exec_busy; /* 1 busy, 2 heating */
    double exec_until, next_keepalive, exec_ready_at;
    int exec_has;
    double last_activity;
    /* counters */
    long received, executed, since_reset, reset_idx, overruns;
    int klipper_shutdown;
    FILE *logf;
    int hung;
    double reopen_at;
    int in_hit; /* a byte of the current incoming line was corrupted */
} vp;

static volatile sig_atomic_t quit_flag;
static void on_signal(int sig)
{
    (void)sig;
    quit_flag = 1;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double rnd01(vp *v)
{
    v->rng ^= v->rng << 13;
    v->rng ^= v->rng >> 7;
    v->rng ^= v->rng << 17;
    return (double)(v->rng >> 11) / 9007199254740992.0;
}

static int in_list(const long *l, int n, long k)
{
    int i;
    for (i = 0; i < n; i++)
        if (l[i] == k)
            return 1;
    return 0;
}

static void say(vp *v, const char *fmt, ...)
{
    va_list ap;
    int n;
    if (v->hung)
        return;
    va_start(ap, fmt);
    n = vsnprintf(v->out + v->outlen, OUT_MAX - v->outlen, fmt, ap);
    va_end(ap);
    if (n > 0 && v->outlen + (size_t)n < OUT_MAX)
        v->outlen += (size_t)n;
}

static void logf_line(vp *v, const char *fmt, ...)
{
    va_list ap;
    if (!v->logf)
        return;
    va_start(ap, fmt);
    vfprintf(v->logf, fmt, ap);
    va_end(ap);
    fflush(v->logf);
}

/* ---------------- pty ---------------- */

static int open_pty(vp *v)
{
    struct termios t;
    char *name;
    v->mfd = posix_openpt(O_RDWR | O_NOCTTY);
    if (v->mfd < 0 || grantpt(v->mfd) != 0 || unlockpt(v->mfd) != 0 || !(name = ptsname(v->mfd))) {
        perror("ampath-vprinter: pty");
        return -1;
    }
    snprintf(v->slave, sizeof v->slave, "%s", name);
    /* Keep a slave fd open: the line discipline must be raw before the host opens it (no echo of our
       banner back to us), and the master then never sees a hang-up when the host closes and reopens. */
    v->sfd = open(v->slave, O_RDWR | O_NOCTTY);
    if (v->sfd < 0 || tcgetattr(v->sfd, &t) != 0) {
        perror("ampath-vprinter: slave");
        return -1;
    }
    cfmakeraw(&t);
    tcsetattr(v->sfd, TCSANOW, &t);
    fcntl(v->mfd, F_SETFL, fcntl(v->mfd, F_GETFL) | O_NONBLOCK);
    if (v->link) {
        char tmp[1024];
        snprintf(tmp, sizeof tmp, "%s.tmp%ld", v->link, (long)getpid());
        unlink(tmp);
        if (symlink(v->slave, tmp) != 0 || rename(tmp, v->link) != 0) {
            perror("ampath-vprinter: --link");
            return -1;
        }
    }
    return 0;
}

static void close_pty(vp *v)
{
    /* the link first: a host that sees the hang-up must not follow it to a pty number that another
       program may already have been given */
    if (v->link)
        unlink(v->link);
    if (v->mfd >= 0)
        close(v->mfd);
    if (v->sfd >= 0)
        close(v->sfd);
    v->mfd = v->sfd = -1;
}

/* ---------------- printer model ---------------- */

static void do_reset(vp *v, double now)
{
    v->last_n = 0;
    v->qcount = v->qhead = 0;
    v->plan_count = v->plan_head = 0;
    v->rxlen = 0;
    v->linelen = 0;
    v->exec_busy = 0;
    v->exec_has = 0;
    v->since_reset = 0;
    v->booting = 1;
    v->boot_at = now + v->boot;
    v->outlen = 0; /* whatever was still going out dies with the MCU */
    v->protect = 0;
    logf_line(v, "# reset\n");
}

static double num_arg(const char *cmd, char letter, double def, int *seen)
{
    const char *s = cmd;
    while ((s = strchr(s, letter)) != NULL) {
        if (s > cmd && s[-1] == ' ') {
            char *end;
            double d = strtod(s + 1, &end);
            if (end != s + 1) {
                if (seen)
                    *seen = 1;
                return d;
            }
        }
        s++;
    }
    return def;
}

static int is_cmd(const char *c, const char *name)
{
    size_t n = strlen(name);
    return strncmp(c, name, n) == 0 && (c[n] == '\0' || c[n] == ' ');
}

/* Commands the modelled firmwares accept (the rest get their unknown-command answer). */
static const char *const marlin_cmds[] = {"G0", "G1", "G2", "G3", "G4", "G10", "G11", "G20", "G21", "G28", "G29",
    "G90", "G91", "G92", "M17", "M18", "M73", "M82", "M83", "M84", "M104", "M105", "M106", "M107", "M109", "M110", "M114",
    "M115", "M117", "M140", "M190", "M201", "M203", "M204", "M205", "M220", "M221", "M400", "M500", "M501",
    "M503", "M900", "T0", NULL};
static const char *const klipper_cmds[] = {"G0", "G1", "G4", "G28", "G90", "G91", "G92", "M18", "M73", "M82",
    "M83", "M84", "M104", "M105", "M106", "M107", "M109", "M110", "M114", "M115", "M117", "M140", "M190", "M204",
    "M220", "M221", "M400", "SET_VELOCITY_LIMIT", "SET_PRESSURE_ADVANCE", "TURN_OFF_HEATERS", "STATUS", NULL};

static int known(const char *const *list, const char *cmd)
{
    size_t n = strcspn(cmd, " ");
    int i;
    for (i = 0; list[i]; i++)
        if (strlen(list[i]) == n && strncmp(list[i], cmd, n) == 0)
            return 1;
    return 0;
}

/* Target of a G0/G1 in bed coordinates (absolute or relative, as the printer would compute it). */
static void move_target(const vp *v, const char *cmd, double t[3]);

static int outside_bed(const vp *v, const double t[3])
{
    int i;
    for (i = 0; i < 3; i++)
        if (t[i] - v->off[i] < -1e-6 || t[i] - v->off[i] > v->bed[i] + 1e-6)
            return 1;
    return 0;
}

/* @p n: the line number of the command this ok is for (Marlin's ok_to_send prints the N of the command at
   the head of its queue: the one just run, or after a Resend the next one waiting) */
static void send_ok(vp *v, long n)
{
    if (in_list(v->lose_ok, v->n_lose_ok, v->executed))
        return;
    if (v->adv_ok && !v->klipper)
        /* sent while the command still holds its queue slot: B is one low, as in Marlin */
        say(v, "ok N%ld P%d B%d\n", n, v->planner - v->plan_count, v->bufsize - v->qcount);
    else
        say(v, "ok\n");
}

static void planner_drain(vp *v, double now)
{
    while (v->plan_count > 0 && v->plan_end[v->plan_head] <= now) {
        v->plan_head = (v->plan_head + 1) % PLAN_MAX;
        v->plan_count--;
    }
}

/* The E position after move @p cmd (M82 absolute or M83 relative). */
static double new_e(const vp *v, const char *cmd)
{
    int has;
    double e = num_arg(cmd, 'E', 0.0, &has);
    return !has ? v->e : v->erel ? v->e + e : e;
}

/* Length of the move from the head to @p t. */
static double move_len(const vp *v, const double t[3])
{
    return sqrt((t[0] - v->x) * (t[0] - v->x) + (t[1] - v->y) * (t[1] - v->y) + (t[2] - v->z) * (t[2] - v->z));
}

/* G0/G1: 0 while the planner is full (Marlin blocks in the handler until it has room), 1 when planned. */
static int exec_move(vp *v, const char *cmd, long n, double now)
{
    double d, t[3];
    planner_drain(v, now);
    if (v->plan_count >= v->planner)
        return 0;
    move_target(v, cmd, t);
    if (outside_bed(v, t)) {
        v->out_of_bed++; /* Marlin's software endstops clamp the move without a word */
        logf_line(v, "# out of bed: %ld %s\n", n, cmd);
    }
    v->f = num_arg(cmd, 'F', v->f, NULL);
    v->e = new_e(v, cmd);
    d = move_len(v, t);
    v->x = t[0];
    v->y = t[1];
    v->z = t[2];
    if (v->speed > 0) {
        double start = v->plan_count ? v->plan_end[(v->plan_head + v->plan_count - 1) % PLAN_MAX] : now;
        v->plan_end[(v->plan_head + v->plan_count) % PLAN_MAX] = start + d / v->speed;
        v->plan_count++;
    }
    return 1;
}

/* Start executing the head command. Returns 1 when it finished (ok sent), 0 while it is still running. */
static int execute(vp *v, const char *cmd, long n, double now)
{
    if (!v->exec_has) {
        v->exec_has = 1;
        v->exec_ready_at = now + v->turnaround;
        v->exec_busy = 0;
        if (v->busy_at > 0 && v->executed + 1 == v->busy_at && v->busy_secs > 0) {
            v->exec_busy = 1;
            v->exec_until = now + v->busy_secs;
            v->next_keepalive = now + v->busy_interval;
        } else if ((is_cmd(cmd, "M109") || is_cmd(cmd, "M190")) && v->heat_secs > 0) {
            v->exec_busy = 2;
            v->exec_until = now + v->heat_secs;
            v->next_keepalive = now + v->busy_interval;
        }
    }
    if (!v->klipper && !known(marlin_cmds, cmd)) {
        /* Marlin: unknown command (e.g. the tail of a line cut by an RX flush, or SET_VELOCITY_LIMIT): echo,
           no-op, ok */
        say(v, "echo:Unknown command: \"%s\"\n", cmd);
        v->last_exec_n = n;
        send_ok(v, n);
        v->exec_has = 0;
        return 1;
    }
    if (v->exec_busy) {
        if (now >= v->next_keepalive) {
            if (v->exec_busy == 1 || v->klipper)
                say(v, v->klipper ? "// busy\n" : "echo:busy: processing\n");
            if (v->exec_busy == 2)
                say(v, " T:%.1f /210.0 B:60.0 /60.0 @:127 B@:0 W:?\n", 150.0 + 60.0 * (1 - (v->exec_until - now) / v->heat_secs));
            v->next_keepalive = now + v->busy_interval;
        }
        if (now < v->exec_until)
            return 0;
    }
    if (now < v->exec_ready_at)
        return 0;
    if (is_cmd(cmd, "G0") || is_cmd(cmd, "G1")) {
        if (!exec_move(v, cmd, n, now))
            return 0;
    } else if (is_cmd(cmd, "M400")) {
        planner_drain(v, now);
        if (v->plan_count > 0)
            return 0;
    } else if (is_cmd(cmd, "G28")) {
        /* "G28 X Y" homes X and Y only (the resume preamble must not crash Z into the part) */
        int all = !strchr(cmd + 3, 'X') && !strchr(cmd + 3, 'Y') && !strchr(cmd + 3, 'Z');
        v->homed = 1;
        if (all || strchr(cmd + 3, 'X'))
            v->x = v->off[0] = 0;
        if (all || strchr(cmd + 3, 'Y'))
            v->y = v->off[1] = 0;
        if (all || strchr(cmd + 3, 'Z'))
            v->z = v->off[2] = 0;
    } else if (is_cmd(cmd, "M82") || is_cmd(cmd, "M83")) {
        v->erel = is_cmd(cmd, "M83");
    } else if (is_cmd(cmd, "G92")) {
        double nx = num_arg(cmd, 'X', v->x, NULL), ny = num_arg(cmd, 'Y', v->y, NULL),
               nz = num_arg(cmd, 'Z', v->z, NULL);
        v->e = num_arg(cmd, 'E', v->e, NULL);
        v->off[0] += nx - v->x;
        v->off[1] += ny - v->y;
        v->off[2] += nz - v->z;
        v->x = nx;
        v->y = ny;
        v->z = nz;
    } else if (is_cmd(cmd, "G90")) {
        v->rel = 0;
    } else if (is_cmd(cmd, "G91")) {
        v->rel = 1;
    } else if (is_cmd(cmd, "M105")) {
        v->executed++;
        v->since_reset++;
        logf_line(v, "%ld %s\n", n, cmd);
        say(v, "ok T:210.0 /210.0 B:60.0 /60.0 @:0 B@:0\n");
        v->exec_has = 0;
        return 1;
    } else if (is_cmd(cmd, "M115")) {
        if (v->klipper)
            say(v, "// FIRMWARE_NAME:Klipper FIRMWARE_VERSION:v0.12.0\n");
        else
            say(v, "FIRMWARE_NAME:Marlin 2.1.2 (ampath-vprinter) SOURCE_CODE_URL:github.com/MarlinFirmware/Marlin "
                   "PROTOCOL_VERSION:1.0 MACHINE_TYPE:3D Printer EXTRUDER_COUNT:1\nCap:ADVANCED_OK:%d\n",
                v->adv_ok);
    }
    v->executed++;
    v->since_reset++;
    v->last_exec_n = n;
    logf_line(v, "%ld %s\n", n, cmd);
    send_ok(v, n);
    v->exec_has = 0;
    v->exec_busy = 0;
    return 1;
}

/* A complete line arrived (Marlin). Mirrors GCodeQueue::get_serial_commands. */
static void marlin_line(vp *v, char *s, int over)
{
    char *star, *cmd = s;
    long n = -1;
    int m110;
    while (*s == ' ')
        s++;
    if (*s == '\0')
        return;
    v->received++;
    if (in_list(v->lose_line, v->n_lose_line, v->received))
        return;
    if (in_list(v->corrupt_line, v->n_corrupt_line, v->received))
        s[strlen(s) / 2] ^= 0x04; /* a flipped bit on the wire: the checksum must catch it */
    if (over)
        logf_line(v, "# overlong line received\n");
    if (*s == 'N') {
        unsigned cs = 0, want;
        char *p, *end;
        n = strtol(s + 1, &end, 10);
        cmd = end;
        while (*cmd == ' ')
            cmd++;
        m110 = strstr(s, "M110") != NULL;
        if (n != v->last_n + 1 && !m110) {
            say(v, "Error:Line Number is not Last Line Number+1, Last Line: %ld\n", v->last_n);
            goto resend;
        }
        star = strrchr(s, '*');
        if (!star) {
            say(v, "Error:No Checksum with line number, Last Line: %ld\n", v->last_n);
            goto resend;
        }
        for (p = s; p < star; p++)
            cs ^= (unsigned char)*p;
        want = (unsigned)strtoul(star + 1, &end, 10);
        if (end == star + 1 || *end != '\0' || want != cs) {
            say(v, "Error:checksum mismatch, Last Line: %ld\n", v->last_n);
            goto resend;
        }
        *star = '\0';
        v->last_n = n;
    } else {
        star = strchr(s, '*');
        if (star) {
            say(v, "Error:No Line Number with checksum, Last Line: %ld\n", v->last_n);
            goto resend;
        }
        cmd = s;
    }
    /* trailing blanks */
    {
        size_t l = strlen(cmd);
        while (l && cmd[l - 1] == ' ')
            cmd[--l] = '\0';
    }
    if (is_cmd(cmd, "M110")) {
        int seen = 0;
        double k = num_arg(cmd, 'N', 0, &seen);
        v->last_n = seen ? (long)k : (n >= 0 ? n : 0);
    }
    {
        int slot = (v->qhead + v->qcount) % QMAX;
        snprintf(v->q[slot], sizeof v->q[slot], "%s", cmd);
        v->qn[slot] = n < 0 ? 0 : n;
        v->qcount++;
    }
    return;
resend:
    if (getenv("AMP_VPRINTER_TRACE"))
        logf_line(v, "# rejected (last %ld): %s\n", v->last_n, s);
    v->rxlen = 0; /* Marlin flushes its RX buffer with the resend request */
    v->linelen = 0;
    if (v->dialect == 2)
        say(v, "rs %ld\n", v->last_n + 1);
    else {
        say(v, "Resend: %ld\n", v->last_n + 1);
        if (v->dialect == 21)
            say(v, "ok\n");
        else if (v->dialect == 20)
            send_ok(v, v->qcount ? v->qn[v->qhead] : v->last_exec_n);
    }
}

/* Klipper: lines carry no numbers; a failed command gets "!! ..." and still an ok. */
static void klipper_line(vp *v, char *s)
{
    char *p;
    int slot;
    while (*s == ' ')
        s++;
    if ((p = strchr(s, ';')) != NULL)
        *p = '\0';
    p = s + strlen(s);
    while (p > s && p[-1] == ' ')
        *--p = '\0';
    /* as Klipper's gcode.py: a leading line number is skipped and a
     * '*checksum' is a parameter nobody reads, so a host speaking Marlin's
     * numbered lines is obeyed (unchecked), not answered "Unknown command" */
    if (*s == 'N' && isdigit((unsigned char)s[1])) {
        for (p = s + 1; isdigit((unsigned char)*p); p++)
            ;
        if (*p == ' ') {
            for (s = p; *s == ' '; s++)
                ;
            if ((p = strrchr(s, '*')) != NULL) {
                *p = '\0';
                while (p > s && p[-1] == ' ')
                    *--p = '\0';
            }
        }
    }
    if (*s == '\0')
        return;
    v->received++;
    if (in_list(v->lose_line, v->n_lose_line, v->received))
        return;
    slot = (v->qhead + v->qcount) % QMAX;
    snprintf(v->q[slot], sizeof v->q[slot], "%s", s);
    v->qn[slot] = v->received;
    v->qcount++;
}

static void klipper_shutdown(vp *v, const char *why)
{
    if (v->klipper_shutdown)
        return;
    v->klipper_shutdown = 1;
    v->qcount = 0;
    v->exec_has = 0;
    say(v, "!! %s\n// Klipper state: Shutdown\n", why);
    logf_line(v, "# shutdown\n");
}

static void move_target(const vp *v, const char *cmd, double t[3])
{
    t[0] = num_arg(cmd, 'X', v->rel ? 0 : v->x, NULL);
    t[1] = num_arg(cmd, 'Y', v->rel ? 0 : v->y, NULL);
    t[2] = num_arg(cmd, 'Z', v->rel ? 0 : v->z, NULL);
    if (v->rel) {
        t[0] += v->x;
        t[1] += v->y;
        t[2] += v->z;
    }
}

/* Klipper's answer to a command it does not run: 1 when answered (with its ok). */
static int klipper_refuse(vp *v, const char *cmd, double now)
{
    double t[3];
    if (now < v->ready_at && !is_cmd(cmd, "M115") && !is_cmd(cmd, "M110")) {
        /* Klipper runs only a few commands (STATUS, M115, M110, M112, RESTART...) before it is ready */
        say(v, "!! Printer is not ready\nok\n");
        return 1;
    }
    if (!known(klipper_cmds, cmd)) {
        say(v, "// Unknown command:\"%.*s\"\nok\n", (int)strcspn(cmd, " "), cmd);
        return 1;
    }
    if (is_cmd(cmd, "G0") || is_cmd(cmd, "G1")) {
        move_target(v, cmd, t);
        if (!v->homed && (strchr(cmd, 'X') || strchr(cmd, 'Y') || strchr(cmd, 'Z'))) {
            say(v, "!! Must home axis first: %.3f %.3f %.3f [%.3f]\nok\n", t[0], t[1], t[2], v->e);
            return 1;
        }
        if (outside_bed(v, t)) {
            say(v, "!! Move out of range: %.3f %.3f %.3f [%.3f]\nok\n", t[0], t[1], t[2], v->e);
            return 1;
        }
        if (v->max_cross > 0.0 && (t[0] != v->x || t[1] != v->y)) {
            /* klippy/kinematics/extruder.py check_move: E per mm of XYZ over the cross-section limit over the
             * filament's area (1.75 mm) is refused unless the extrusion is tiny (E <= nozzle x that ratio) */
            double fa = 3.14159265358979 * 0.875 * 0.875, ratio = v->max_cross / fa, de = new_e(v, cmd) - v->e;
            double l3 = move_len(v, t);
            if (de > 0.0 && de / l3 > ratio && de > sqrt(v->max_cross / 4.0) * ratio) {
                say(v, "!! Move exceeds maximum extrusion (%.3fmm^2 vs %.3fmm^2)\nok\n", de / l3 * fa, v->max_cross);
                return 1;
            }
        }
    }
    return 0;
}

static void klipper_exec(vp *v, double now)
{
    char *cmd = v->q[v->qhead];
    long n = v->qn[v->qhead];
    if (is_cmd(cmd, "STATUS")) {
        /* answered in every state, never logged as executed */
        if (v->klipper_shutdown)
            say(v, "!! Shutdown\n!! Klipper state: Shutdown\nok\n");
        else if (now < v->ready_at)
            say(v, "!! Printer is not ready\n!! Klipper state: Not ready\nok\n");
        else
            say(v, "// Klipper state: Ready\nok\n");
    } else if (v->klipper_shutdown) {
        say(v, "!! Printer is not ready\nok\n");
    } else if (v->error_at > 0 && n == v->error_at) {
        say(v, "!! Move out of range: %s\nok\n", cmd);
    } else if (klipper_refuse(v, cmd, now)) {
        /* answered */
    } else {
        if (!execute(v, cmd, n, now))
            return;
        if (v->shutdown_after > 0 && v->executed == v->shutdown_after) {
            klipper_shutdown(v, "MCU 'mcu' shutdown: Timer too close"); /* drops the queue */
            return;
        }
    }
    v->qhead = (v->qhead + 1) % QMAX;
    v->qcount--;
}

/* Move bytes from the RX buffer into lines while the queue has room (Marlin reads only then). */
static void parse_rx(vp *v)
{
    int i = 0;
    int qcap = v->klipper ? 20 : v->bufsize;
    while (i < v->rxlen && v->qcount < qcap) {
        char c = v->rxq[i++];
        if (c == '\n' || c == '\r') {
            v->line[v->linelen] = '\0';
            if (v->linelen > 0) {
                if (v->klipper)
                    klipper_line(v, v->line);
                else
                    marlin_line(v, v->line, v->line_over);
            }
            v->linelen = 0;
            v->line_over = 0;
            if (v->rxlen == 0) /* flushed by an error */
                return;
        } else if (v->linelen < MAX_CMD - 1) {
            v->line[v->linelen++] = c;
        } else {
            v->line_over = 1; /* Marlin drops the rest; the checksum then fails */
        }
    }
    memmove(v->rxq, v->rxq + i, (size_t)(v->rxlen - i));
    v->rxlen -= i;
}

/* Bytes from the host (after link faults). */
static void on_bytes(vp *v, const char *b, ssize_t n, double now)
{
    ssize_t i;
    for (i = 0; i < n; i++) {
        char c = b[i];
        if (v->drop_in > 0 && rnd01(v) < v->drop_in)
            continue;
        /* At most one corrupted byte per line: Marlin's XOR checksum cannot see two flips of the same bit
           in one line, so no host could pass a model with more (see docs/bridge.md, "Limits"). */
        /* The '*' is spared too: a line cut by Marlin's RX flush whose '*' is lost runs as an unnumbered
           command, a hole in the protocol no host can close (docs/bridge.md, "Limits"). */
        /* Likewise no flip turns a byte into one that hides the '*' from Marlin: NUL ends the C string it
           searches, ';' starts a comment, CR/LF end the line. On a whole numbered line that is only another
           checksum error, but on a cut tail it is the same hole as a lost '*' (found as a move run twice
           with line number 0 in the executed log: a blank flipped to NUL in a tail cut by an RX flush). */
        if (v->corrupt_in > 0 && !v->in_hit && c != '*' && rnd01(v) < v->corrupt_in) {
            int bit = (int)(rnd01(v) * 7), k;
            for (k = 0; k < 7; k++) {
                char t = (char)(c ^ (1 << ((bit + k) % 7)));
                if (t != '\0' && t != ';' && t != '\n' && t != '\r') {
                    c = t;
                    break;
                }
            }
            v->in_hit = 1;
        }
        if (b[i] == '\n')
            v->in_hit = 0;
        if (v->klipper && c == 'M' && i + 3 < n && memcmp(b + i, "M112", 4) == 0) {
            klipper_shutdown(v, "Shutdown due to M112"); /* acted on when read, ahead of the queue */
            continue;
        }
        if (!v->klipper && i + 3 < n && memcmp(b + i, "M112", 4) == 0 && (i == 0 || b[i - 1] == '\n')) {
            /* EMERGENCY_PARSER: kill() at once */
            say(v, "Error:Printer halted. kill() called!\n");
            logf_line(v, "# M112 kill\n");
            v->qcount = 0;
            v->exec_has = 0;
            v->rxlen = 0;
            v->booting = 2; /* halted: ignores everything until reset */
            return;
        }
        if (v->booting)
            continue; /* bytes sent to a booting MCU are lost */
        if (v->rxlen >= (v->klipper ? (int)sizeof v->rxq : v->rx_bytes))
            parse_rx(v); /* the main loop keeps moving lines into the queue while it has room */
        if (v->rxlen < (v->klipper ? (int)sizeof v->rxq : v->rx_bytes))
            v->rxq[v->rxlen++] = c; /* Marlin has no flow control: overflow drops bytes */
        else {
            if (v->overruns++ == 0 || v->overruns % 100 == 0)
                logf_line(v, "# RX overrun (%ld so far)\n", v->overruns);
        }
    }
    (void)now;
}

static void step(vp *v, double now)
{
    if (v->booting == 1 && now >= v->boot_at) {
        v->booting = 0;
        say(v, "start\necho:Marlin 2.1.2 (ampath-vprinter)\necho: Last Updated: 2023-01-01\n");
    }
    if (v->booting)
        return;
    parse_rx(v);
    while (v->qcount > 0) {
        if (v->klipper) {
            int before = v->qcount;
            klipper_exec(v, now);
            if (v->qcount == before)
                break;
        } else {
            int slot = v->qhead;
            if (!execute(v, v->q[slot], v->qn[slot], now))
                break;
            v->qhead = (v->qhead + 1) % QMAX;
            v->qcount--;
        }
        v->last_activity = now;
        if (v->n_reset_after > v->reset_idx && v->since_reset == v->reset_after[v->reset_idx]) {
            v->reset_idx++;
            {
                /* the replies already produced reach the host intact (a brown-out between moves), then the
                   MCU restarts: a move whose ok is lost in a reset cannot be told from one never run */
                size_t keep = v->outlen;
                do_reset(v, now);
                v->outlen = keep;
                v->protect = keep;
            }
            return;
        }
        if (v->action_at > 0 && v->executed == v->action_at) {
            v->action_at = 0;
            say(v, "// action:%s\n", v->action);
        }
        if (!v->klipper && v->halt_after > 0 && v->executed == v->halt_after) {
            /* a heater fault while printing: Marlin reports it and kill()s, answering nothing more */
            say(v, "Error:Thermal Runaway, system stopped! Heater_ID: 0\nError:Printer halted. kill() called!\n");
            logf_line(v, "# halted\n");
            v->qcount = 0;
            v->exec_has = 0;
            v->rxlen = 0;
            v->booting = 2;
            return;
        }
        if (v->n_hangup > v->hang_idx && v->executed == v->hangup_after[v->hang_idx] && !v->hung) {
            /* USB unplugged: the device node goes, the host's bytes stop, the printer keeps running its
               queue and what it says is lost (the oks of the lines still queued among it) */
            v->hang_idx++;
            v->hung = 1;
            v->reopen_at = now + v->hangup_secs;
            logf_line(v, "# hangup\n");
            close_pty(v);
            v->outlen = 0;
            v->wire_len = 0; /* bytes still on the wire die with the cable */
            if (v->hangup_reset)
                do_reset(v, now); /* the board lost its power with the cable */
            return;
        }
        parse_rx(v);
    }
    if (v->wait_s > 0 && v->qcount == 0 && !v->exec_has && now - v->last_activity >= v->wait_s) {
        say(v, "wait\n");
        v->last_activity = now;
    }
}

static void flush_out(vp *v, double now)
{
    size_t i, n, k = 0, consumed;
    ssize_t w;
    char tmp[4096];
    size_t src[4096];
    if (v->mfd < 0 || v->outlen == 0)
        return;
    n = v->outlen;
    if (v->baud > 0) {
        /* 10 bits per byte; no credit piles up while the line is idle */
        double bt = 10.0 / v->baud;
        size_t nmax;
        if (v->out_free < now - bt)
            v->out_free = now - bt;
        nmax = (size_t)((now - v->out_free) / bt + 1e-6); /* the idle case gives exactly one byte */
        if (n > nmax)
            n = nmax;
    }
    if (n > sizeof tmp)
        n = sizeof tmp;
    if (n == 0)
        return;
    /* faults on the way out, byte by byte */
    for (i = 0; i < n; i++) {
        char c = v->out[i];
        int faults = i >= v->protect;
        if (faults && v->drop_out > 0 && rnd01(v) < v->drop_out)
            continue;
        if (faults && v->corrupt_out > 0 && rnd01(v) < v->corrupt_out)
            c ^= (char)(1 << (int)(rnd01(v) * 7));
        src[k] = i;
        tmp[k++] = c;
    }
    w = k ? write(v->mfd, tmp, k) : 0;
    if (w < 0)
        return; /* EAGAIN: the host is not reading; try again later */
    consumed = (size_t)w < k ? src[w] : n;
    memmove(v->out, v->out + consumed, v->outlen - consumed);
    v->outlen -= consumed;
    v->protect = v->protect > consumed ? v->protect - consumed : 0;
    if (v->baud > 0)
        v->out_free += (double)consumed * 10.0 / v->baud;
}

/* What cli_parse() cannot store in the printer directly (units, words, lists); apply_options() moves it. */
typedef struct vopts {
    const char *flavor, *dialect, *bed;
    long bufsize, rx_bytes, planner, seed;
    double turnaround_ms, boot_ms, wait_ms, ready_ms;
    cli_list corrupt_line, lose_line, lose_ok, reset_after, hangup_after;
} vopts;

static void copy_list(long *dst, int *n, const cli_list *l)
{
    memcpy(dst, l->v, (size_t)l->n * sizeof *dst);
    *n = l->n;
}

static int apply_words(vp *v, const vopts *o, const cli_opt *opts)
{
    if (cli_given(opts, "flavor") && strcmp(o->flavor, "klipper") != 0 && strcmp(o->flavor, "marlin") != 0)
        return cli_fail("ampath-vprinter", -1, "bad --flavor %s (marlin or klipper)", o->flavor);
    v->klipper = cli_given(opts, "flavor") && strcmp(o->flavor, "klipper") == 0;
    if (cli_given(opts, "dialect")) {
        if (strcmp(o->dialect, "2.1") == 0)
            v->dialect = 21;
        else if (strcmp(o->dialect, "2.0") == 0)
            v->dialect = 20;
        else if (strcmp(o->dialect, "bare") == 0 || strcmp(o->dialect, "prusa") == 0)
            v->dialect = 1;
        else if (strcmp(o->dialect, "rs") == 0)
            v->dialect = 2;
        else
            return cli_fail("ampath-vprinter", -1, "bad --dialect %s (2.1, 2.0, prusa, bare or rs)", o->dialect);
    }
    if (cli_given(opts, "bed") && (sscanf(o->bed, "%lf,%lf,%lf", &v->bed[0], &v->bed[1], &v->bed[2]) != 3 ||
                                   v->bed[0] <= 0 || v->bed[1] <= 0 || v->bed[2] <= 0))
        return cli_fail("ampath-vprinter", -1, "bad --bed %s (X,Y,Z in mm, each > 0)", o->bed);
    return 0;
}

static int apply_options(vp *v, const vopts *o, const cli_opt *opts)
{
    if (apply_words(v, o, opts) != 0)
        return -1;
    if (o->bufsize < 1 || o->bufsize > QMAX || o->planner < 1 || o->planner > PLAN_MAX || o->rx_bytes < 1 ||
        o->rx_bytes > (long)sizeof v->rxq || v->busy_interval <= 0) {
        fprintf(stderr, "ampath-vprinter: --bufsize 1..%d, --planner 1..%d, --rx-bytes 1..%d\n", QMAX, PLAN_MAX,
                (int)sizeof v->rxq);
        return -1;
    }
    v->bufsize = (int)o->bufsize;
    v->planner = (int)o->planner;
    v->rx_bytes = (int)o->rx_bytes;
    if (cli_given(opts, "seed"))
        v->rng = (unsigned long long)o->seed * 2654435761ULL + 1;
    v->turnaround = o->turnaround_ms / 1000.0;
    v->boot = o->boot_ms / 1000.0;
    v->wait_s = o->wait_ms / 1000.0;
    v->ready_at = o->ready_ms / 1000.0;
    copy_list(v->corrupt_line, &v->n_corrupt_line, &o->corrupt_line);
    copy_list(v->lose_line, &v->n_lose_line, &o->lose_line);
    copy_list(v->lose_ok, &v->n_lose_ok, &o->lose_ok);
    copy_list(v->reset_after, &v->n_reset_after, &o->reset_after);
    copy_list(v->hangup_after, &v->n_hangup, &o->hangup_after);
    return 0;
}

int main(int argc, char **argv)
{
    static vp V;
    vp *v = &V;
    int i;
    double last;
    vopts o;
    cli_opt opts[] = {{"advanced-ok", CLI_FLAG, &V.adv_ok, 0},
                      {"hangup-reset", CLI_FLAG, &V.hangup_reset, 0},
                      {"link", CLI_STR, &V.link, 0},
                      {"log", CLI_STR, &V.logpath, 0},
                      {"action", CLI_STR, &V.action, 0},
                      {"flavor", CLI_STR, &o.flavor, 0},
                      {"dialect", CLI_STR, &o.dialect, 0},
                      {"bed", CLI_STR, &o.bed, 0},
                      {"bufsize", CLI_LONG, &o.bufsize, 0},
                      {"rx-bytes", CLI_LONG, &o.rx_bytes, 0},
                      {"planner", CLI_LONG, &o.planner, 0},
                      {"seed", CLI_LONG, &o.seed, 0},
                      {"busy-at", CLI_LONG, &V.busy_at, 0},
                      {"error-at", CLI_LONG, &V.error_at, 0},
                      {"shutdown-after", CLI_LONG, &V.shutdown_after, 0},
                      {"halt-after", CLI_LONG, &V.halt_after, 0},
                      {"action-at", CLI_LONG, &V.action_at, 0},
                      {"speed", CLI_DOUBLE, &V.speed, 0},
                      {"baud", CLI_DOUBLE, &V.baud, 0},
                      {"busy-secs", CLI_DOUBLE, &V.busy_secs, 0},
                      {"busy-interval", CLI_DOUBLE, &V.busy_interval, 0},
                      {"heat-secs", CLI_DOUBLE, &V.heat_secs, 0},
                      {"max-extrude-cross-section", CLI_DOUBLE, &V.max_cross, 0},
                      {"hangup-secs", CLI_DOUBLE, &V.hangup_secs, 0},
                      {"corrupt-in", CLI_DOUBLE, &V.corrupt_in, 0},
                      {"corrupt-out", CLI_DOUBLE, &V.corrupt_out, 0},
                      {"drop-in", CLI_DOUBLE, &V.drop_in, 0},
                      {"drop-out", CLI_DOUBLE, &V.drop_out, 0},
                      {"turnaround", CLI_DOUBLE, &o.turnaround_ms, 0},
                      {"boot-ms", CLI_DOUBLE, &o.boot_ms, 0},
                      {"wait-ms", CLI_DOUBLE, &o.wait_ms, 0},
                      {"ready-after-ms", CLI_DOUBLE, &o.ready_ms, 0},
                      {"corrupt-line", CLI_LIST, &o.corrupt_line, 0},
                      {"lose-line", CLI_LIST, &o.lose_line, 0},
                      {"lose-ok", CLI_LIST, &o.lose_ok, 0},
                      {"reset-after", CLI_LIST, &o.reset_after, 0},
                      {"hangup-after", CLI_LIST, &o.hangup_after, 0},
                      {NULL, CLI_FLAG, NULL, 0}};
    memset(v, 0, sizeof *v);
    v->dialect = 21;
    v->bufsize = 4;
    v->rx_bytes = 128;
    v->planner = 16;
    v->busy_interval = 2;
    v->rng = 1;
    v->mfd = v->sfd = -1;
    v->bed[0] = v->bed[1] = 220;
    v->bed[2] = 250;
    v->max_cross = 4.0 * 0.4 * 0.4;
    v->action = "cancel";
    memset(&o, 0, sizeof o);
    o.bufsize = v->bufsize;
    o.rx_bytes = v->rx_bytes;
    o.planner = v->planner;
    for (i = 1; i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            fputs(usage, stdout);
            return 0;
        }
    /* ampath's option parser (tools/cli.c) */
    if (cli_parse("ampath-vprinter", argc, argv, opts, NULL, 0, 0, NULL) != CLI_OK || apply_options(v, &o, opts)) {
        fprintf(stderr, "%s", usage);
        return 2;
    }
    v->out = malloc(OUT_MAX);
    if (!v->out)
        return 1;
    if (v->logpath && !(v->logf = fopen(v->logpath, "w"))) {
        perror("ampath-vprinter: --log");
        return 2;
    }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGPIPE, SIG_IGN);
    if (open_pty(v) != 0)
        return 1;
    if (!v->link)
        printf("%s\n", v->slave);
    fflush(stdout);
    last = now_s();
    v->last_activity = last;
    v->ready_at += last; /* --ready-after-ms counts from the start */
    if (v->klipper) {
        v->booting = 0;
    } else {
        v->booting = 1;
        v->boot_at = last + v->boot;
    }
    while (!quit_flag) {
        struct pollfd pfd;
        double now = now_s();
        int timeout = 50, rc;
        last = now;
        if (v->hung) {
            if (now >= v->reopen_at) {
                v->hung = 0;
                if (open_pty(v) != 0)
                    return 1;
                logf_line(v, "# reopened\n");
            } else {
                step(v, now); /* unplugged, not stopped: the queue runs on, the replies go nowhere */
                v->outlen = 0;
                v->protect = 0;
                usleep(2000);
                continue;
            }
        }
        if (v->wire_len > 0) {
            /* deliver the bytes whose modelled arrival time has come */
            int k = 0;
            while (k < v->wire_len && v->wire_t[k] <= now)
                k++;
            if (k > 0) {
                on_bytes(v, v->wire, k, now);
                memmove(v->wire, v->wire + k, (size_t)(v->wire_len - k));
                memmove(v->wire_t, v->wire_t + k, (size_t)(v->wire_len - k) * sizeof v->wire_t[0]);
                v->wire_len -= k;
            }
        }
        step(v, now);
        flush_out(v, now);
        if (v->outlen > 0 || v->wire_len > 0 || v->qcount > 0 || v->booting == 1 || v->exec_has || v->plan_count > 0)
            timeout = 1;
        pfd.fd = v->mfd;
        pfd.events = POLLIN;
        /* Marlin stops taking bytes into its line buffer when the queue is full; the RX buffer fills */
        rc = poll(&pfd, 1, timeout);
        if (rc > 0 && (pfd.revents & POLLIN)) {
            char buf[512];
            ssize_t n, cap = (ssize_t)sizeof buf;
            if (v->baud > 0)
                cap = (ssize_t)sizeof v->wire - v->wire_len < cap ? (ssize_t)sizeof v->wire - v->wire_len : cap;
            if (v->klipper) {
                /* Klipper stops reading at 20 pending lines, and never drops what it read */
                ssize_t room = (ssize_t)sizeof v->rxq - v->rxlen;
                cap = v->qcount >= 20 ? 0 : (room < cap ? room : cap);
            }
            if (cap > 0) {
                n = read(v->mfd, buf, (size_t)cap);
                if (n > 0 && v->baud > 0) {
                    ssize_t b;
                    if (v->wire_in_t < now)
                        v->wire_in_t = now;
                    for (b = 0; b < n; b++) {
                        v->wire_in_t += 10.0 / v->baud;
                        v->wire[v->wire_len] = buf[b];
                        v->wire_t[v->wire_len++] = v->wire_in_t;
                    }
                } else if (n > 0) {
                    on_bytes(v, buf, n, now);
                }
            } else {
                usleep(500);
            }
        }
    }
    fprintf(stderr, "ampath-vprinter: received %ld lines, executed %ld commands, %ld RX overruns, %ld moves out of bed\n",
            v->received, v->executed, v->overruns, v->out_of_bed);
    close_pty(v);
    if (v->logf)
        fclose(v->logf);
    free(v->out);
    return 0;
}
