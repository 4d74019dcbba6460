/*
 * job.c — job sources of ampath-bridge: .gcode files, checked whole before the
 * first byte goes out, and the safe-restart preamble for --resume-from.
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bridge.h"

#define JOB_LINE_MAX 4096
/* Jobs from this size on show bars while they are read and checked, before the first line goes out (a
 * bed-sized .amp job is parsed and written twice there: seconds of silence otherwise). */
#define JOB_BAR_BYTES ((off_t)16 << 20)

/* The bar of the job's preparation on stderr (a terminal: the session's progress flag), as ampath's own. */
typedef struct jbar {
    int on, permille;
    const char *label; /* the bar being drawn; NULL: none */
} jbar;

static void jbar_show(jbar *b, const char *label, double f)
{
    int p, i;
    if (!b->on)
        return;
    p = (int)((f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f) * 1000.0);
    if (label == b->label && p == b->permille)
        return;
    if (b->label && label != b->label)
        fputc('\n', stderr);
    b->label = label;
    b->permille = p;
    fprintf(stderr, "\r%-12s [", label);
    for (i = 0; i < 30; i++)
        fputc(i < p * 30 / 1000 ? '#' : ' ', stderr);
    fprintf(stderr, "] %5.1f%%", p / 10.0);
    fflush(stderr);
}

/* The bar's line ended (at 100 % when @p done). */
static void jbar_end(jbar *b, int done)
{
    if (!b->on || !b->label)
        return;
    if (done)
        jbar_show(b, b->label, 1.0);
    fputc('\n', stderr);
    b->label = NULL;
}

static void jbar_read(void *user, double f) { jbar_show(user, "reading", f); }

/* Printer state reached by the lines before the resume point (what a restart must restore). */
typedef struct job_state {
    double x, y, z, e, f;
    double hot, bed;
    int rel_xyz, rel_e;
} job_state;

static int word(const char *s, char letter, double *v)
{
    const char *p = s;
    while ((p = strchr(p, letter)) != NULL) {
        if (p == s || p[-1] == ' ') {
            char *end;
            double d = strtod(p + 1, &end);
            if (end != p + 1) {
                *v = d;
                return 1;
            }
        }
        p++;
    }
    return 0;
}

static int is_cmd(const char *c, const char *name)
{
    size_t n = strlen(name);
    return strncmp(c, name, n) == 0 && (c[n] == '\0' || c[n] == ' ');
}

static void track(job_state *st, const char *c)
{
    double v;
    if (is_cmd(c, "G0") || is_cmd(c, "G1")) {
        if (word(c, 'X', &v))
            st->x = st->rel_xyz ? st->x + v : v;
        if (word(c, 'Y', &v))
            st->y = st->rel_xyz ? st->y + v : v;
        if (word(c, 'Z', &v))
            st->z = st->rel_xyz ? st->z + v : v;
        if (word(c, 'E', &v))
            st->e = st->rel_e ? st->e + v : v;
        if (word(c, 'F', &v))
            st->f = v;
    } else if (is_cmd(c, "G92")) {
        if (word(c, 'X', &v))
            st->x = v;
        if (word(c, 'Y', &v))
            st->y = v;
        if (word(c, 'Z', &v))
            st->z = v;
        if (word(c, 'E', &v))
            st->e = v;
    } else if (is_cmd(c, "G28")) {
        st->x = st->y = st->z = 0;
    } else if (is_cmd(c, "G90")) {
        st->rel_xyz = 0;
        st->rel_e = 0; /* G90 also sets absolute E in Marlin unless M83 follows */
    } else if (is_cmd(c, "G91")) {
        st->rel_xyz = 1;
        st->rel_e = 1;
    } else if (is_cmd(c, "M82")) {
        st->rel_e = 0;
    } else if (is_cmd(c, "M83")) {
        st->rel_e = 1;
    } else if ((is_cmd(c, "M104") || is_cmd(c, "M109")) && word(c, 'S', &v)) {
        st->hot = v;
    } else if ((is_cmd(c, "M140") || is_cmd(c, "M190")) && word(c, 'S', &v)) {
        st->bed = v;
    }
}

/* Strip comment and blanks in place; returns the command (possibly ""). */
static char *clean(char *s)
{
    char *p = strchr(s, ';'), *e;
    if (p)
        *p = '\0';
    s[strcspn(s, "\r\n")] = '\0';
    while (*s == ' ' || *s == '\t')
        s++;
    e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || e[-1] == '\t'))
        *--e = '\0';
    return s;
}

/* One raw line of the job (comment included): 1, 0 at the end, -1 on an error. */
static int job_read(br_job *j, char *buf, size_t cap)
{
    if (j->is_amp) {
        int r = amp_gcode_iter_next(&j->it, buf, cap, NULL);
        return r > 0 ? 1 : r == 0 ? 0 : -1;
    }
    if (!fgets(buf, (int)cap, j->f))
        return ferror(j->f) ? -1 : 0;
    return 1;
}

/* Back to the first line (the job is read twice: check, then send). */
static int job_restart(br_job *j)
{
    if (j->is_amp)
        return amp_gcode_iter_rewind(&j->it, NULL) == AMP_OK ? 0 : -1; /* the same lines, not a new run */
    rewind(j->f);
    return 0;
}

static int ends_with(const char *s, const char *suf)
{
    size_t a = strlen(s), b = strlen(suf);
    return a >= b && strcmp(s + a - b, suf) == 0;
}

/* .amp: parse the paths and start the G-code writer for the printer profile;
 * the firmware flavour is the one the bridge speaks, whatever the profile says. */
static int open_amp(br_job *j, const char *path, amp_proto_flavor flavor, const char *printer, jbar *bar,
                    char *why, size_t whylen)
{
    char *text = NULL;
    size_t len = 0;
    amp_error err;
    amp_error_clear(&err);
    amp_pathset_init(&j->ps, NULL);
    if (amp_read_file(path, NULL, AMP_PATHS_READ_MAX, &text, &len, &err) != AMP_OK ||
        amp_pathset_parse_progress(&j->ps, text, len, bar->on ? jbar_read : NULL, bar, &err) != AMP_OK) {
        snprintf(why, whylen, "%s:%ld: %s", path, err.line, err.msg);
        amp_free(NULL, text);
        amp_pathset_free(&j->ps);
        return -1;
    }
    amp_free(NULL, text);
    if (amp_printer_load(&j->pr, printer ? printer : "generic", &err) != AMP_OK ||
        amp_printer_gcode_opts(&j->pr, &j->go, &err) != AMP_OK) {
        snprintf(why, whylen, "%s", err.msg);
        amp_pathset_free(&j->ps);
        return -1;
    }
    j->go.flavor = flavor == AMP_PROTO_KLIPPER ? AMP_FLAVOR_KLIPPER : AMP_FLAVOR_MARLIN;
    jbar_end(bar, 1);
    if (bar->on) /* init runs the whole job once for the header's figures; no bar there */
        fprintf(stderr, "preparing    the G-code of %lu paths (the writer's first run)\n", (unsigned long)j->ps.npaths);
    /* the profile's start/end macros see the placed job, as in `ampath gcode` */
    if (amp_printer_gcode_job(&j->pr, &j->go, &j->ps, &j->it, &err) != AMP_OK ||
        amp_gcode_iter_init(&j->it, &j->ps, &j->go, &err) != AMP_OK) {
        snprintf(why, whylen, "%s: %s", path, err.msg);
        amp_pathset_free(&j->ps);
        return -1;
    }
    j->is_amp = 1;
    return 0;
}

static void pre(br_job *j, const char *fmt, double a, double b)
{
    if (j->npre < 16)
        snprintf(j->pre[j->npre++], sizeof j->pre[0], fmt, a, b);
}

/* Restart safely where the job stopped: the printer lost its position and temperatures.
   Z is assumed not to have moved (lead screws hold); lift first so the nozzle clears the part,
   home X and Y only (homing Z would crash into the print), heat away from the part, come back. */
static void build_preamble(br_job *j, const job_state *st)
{
    pre(j, "G90", 0, 0);
    pre(j, "G92 Z%.3f", st->z, 0);
    pre(j, "G1 Z%.3f F600", st->z + 5.0, 0);
    pre(j, "G28 X Y", 0, 0);
    if (st->bed > 0)
        pre(j, "M190 S%.0f", st->bed, 0);
    if (st->hot > 0)
        pre(j, "M109 S%.0f", st->hot, 0);
    pre(j, "G1 X%.3f Y%.3f F3000", st->x, st->y);
    pre(j, "G1 Z%.3f F600", st->z, 0);
    pre(j, "G92 E%.5f", st->rel_e ? 0.0 : st->e, 0);
    pre(j, st->rel_e ? "M83" : "M82", 0, 0);
    if (st->rel_xyz)
        pre(j, "G91", 0, 0);
    if (st->f > 0)
        pre(j, "G1 F%.0f", st->f, 0);
}

static int not_regular(const char *path, char *why, size_t whylen)
{
    snprintf(why, whylen,
             "%s is not a regular file (a pipe or device cannot be checked before sending): save the job to a "
             "file first",
             path);
    return -1;
}

/* Hardening: a job is a regular file. A FIFO would block the daemon in open(), /dev/zero would never end,
   and neither can be read twice (checked whole, then sent). stat() first: opening a device is not harmless
   (a second printer's serial port resets its board, /dev/ptmx makes a terminal); then the file opened
   without blocking is checked again, in case the name changed hands between the two. */
static int check_source(const char *path, char *why, size_t whylen)
{
    struct stat st;
    int fd;
    if (stat(path, &st) != 0) {
        snprintf(why, whylen, "%s: %s", path, strerror(errno));
        return -1;
    }
    if (!S_ISREG(st.st_mode))
        return not_regular(path, why, whylen);
    fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY);
    if (fd < 0) {
        snprintf(why, whylen, "%s: %s", path, strerror(errno));
        return -1;
    }
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return not_regular(path, why, whylen);
    }
    close(fd);
    return 0;
}

/* G1, M104, T0, G29.1, G1X10 (no spaces): a letter, a number, then a space, a letter or the end. */
static int classic_command(const char *c)
{
    const unsigned char *u = (const unsigned char *)c;
    size_t i = 1;
    if (!isalpha(u[0]) || !isdigit(u[1]))
        return 0;
    while (isdigit(u[i]))
        i++;
    if (u[i] == '.' && isdigit(u[i + 1]))
        for (i++; isdigit(u[i]); i++)
            ;
    return u[i] == '\0' || u[i] == ' ' || u[i] == '\t' || isalpha(u[i]) || u[i] == '-';
}

/* Klipper's extended commands: NAME or NAME KEY=VALUE ... (SET_VELOCITY_LIMIT ACCEL=500, PRINT_START). */
static int extended_command(const char *c)
{
    const unsigned char *u = (const unsigned char *)c;
    size_t i = 0;
    if (!isalpha(u[0]) && u[0] != '_')
        return 0;
    while (isalnum(u[i]) || u[i] == '_')
        i++;
    if (u[i] == '\0')
        return 1;
    if (u[i] != ' ' && u[i] != '\t')
        return 0;
    while (u[i] == ' ' || u[i] == '\t')
        i++;
    for (; u[i] && u[i] != ' ' && u[i] != '\t'; i++)
        if (u[i] == '=')
            return 1;
    return 0;
}

/* Hardening: a job must parse as G-code before anything is sent (`submit /etc/shadow` must not stream a
   password file to the printer); '*' would end the checksummed part of a Marlin line early. */
static int check_command(const char *c, amp_proto_flavor flavor, char *bad, size_t cap)
{
    const unsigned char *u = (const unsigned char *)c;
    size_t i;
    for (i = 0; u[i]; i++)
        if ((u[i] < 0x20 && u[i] != '\t') || u[i] == 0x7f) {
            snprintf(bad, cap, "control byte 0x%02x in a command", u[i]);
            return -1;
        }
    if (!classic_command(c) && !(flavor == AMP_PROTO_KLIPPER && extended_command(c))) {
        snprintf(bad, cap, "not a G-code command (%s)",
                 flavor == AMP_PROTO_KLIPPER ? "a letter and a number such as G1, or NAME KEY=VALUE"
                                             : "a letter and a number such as G1 or M104");
        return -1;
    }
    if (strchr(c, '*')) {
        snprintf(bad, cap, "'*' in a command (it would end the checksummed part of the line)");
        return -1;
    }
    return 0;
}

/* The share of the job's first pass done: paths written (.amp) or bytes read (.gcode). */
static double pass_done(br_job *j, off_t size)
{
    if (j->is_amp)
        return j->it.ps->npaths ? (double)j->it.path / (double)j->it.ps->npaths : 1.0;
    return size > 0 ? (double)ftell(j->f) / (double)size : 1.0;
}

int br_job_open(br_job *j, const char *path, amp_proto_flavor flavor, const char *printer, long resume_from,
                int bars, char *why, size_t whylen)
{
    char buf[JOB_LINE_MAX];
    long line = 0, worst_n;
    job_state st;
    struct stat sb;
    jbar bar;
    memset(j, 0, sizeof *j);
    memset(&st, 0, sizeof st);
    snprintf(j->path, sizeof j->path, "%s", path);
    j->first_line = resume_from > 1 ? resume_from : 1;
    if (check_source(path, why, whylen) != 0)
        return -1;
    bar.on = bars && stat(path, &sb) == 0 && sb.st_size >= JOB_BAR_BYTES;
    bar.permille = -1;
    bar.label = NULL;
    if (ends_with(path, ".amp")) {
        if (open_amp(j, path, flavor, printer, &bar, why, whylen) != 0) {
            jbar_end(&bar, 0);
            return -1;
        }
    } else {
        j->f = fopen(path, "r");
        if (!j->f) {
            snprintf(why, whylen, "%s: %s", path, strerror(errno));
            return -1;
        }
    }
    /* first pass: count, check every line fits the printer, and track the state for a resume */
    for (;;) {
        char *c, bad[160];
        size_t n;
        long pos0 = j->is_amp ? 0 : ftell(j->f);
        int r = job_read(j, buf, sizeof buf);
        if (r < 0) {
            snprintf(why, whylen, "%s: read error", path);
            goto fail;
        }
        if (r == 0)
            break;
        n = strlen(buf);
        line++;
        if ((line & 4095) == 0)
            jbar_show(&bar, "checking", pass_done(j, bar.on ? sb.st_size : 0));
        if (!j->is_amp && ftell(j->f) - pos0 != (long)n) {
            snprintf(why, whylen, "%s:%ld: NUL byte: not a G-code text file; nothing was sent", path, line);
            goto fail;
        }
        if (!j->is_amp && n == sizeof buf - 1 && buf[n - 1] != '\n') {
            snprintf(why, whylen, "%s:%ld: line longer than %d bytes", path, line, JOB_LINE_MAX - 2);
            goto fail;
        }
        c = clean(buf);
        if (*c == '\0')
            continue;
        if (!j->is_amp && check_command(c, flavor, bad, sizeof bad) != 0) {
            snprintf(why, whylen, "%s:%ld: %s; nothing was sent", path, line, bad);
            goto fail;
        }
        if (line < j->first_line) {
            track(&st, c);
            continue;
        }
        j->total++;
        /* the worst case: line numbers grow with the job (plus preamble and handshake) */
        worst_n = j->total + 100;
        if (amp_proto_framed_size(flavor, worst_n, c, strlen(c)) >= AMP_PROTO_LINE_MAX) {
            snprintf(why, whylen,
                     "%s:%ld: line too long for the printer (framed it would reach %d bytes or more; Marlin's "
                     "MAX_CMD_SIZE is %d): nothing was sent",
                     path, line, AMP_PROTO_LINE_MAX, AMP_PROTO_LINE_MAX);
            goto fail;
        }
    }
    if (resume_from > line + 1) {
        snprintf(why, whylen, "%s: --resume-from %ld is past the end (%ld lines)", path, resume_from, line);
        goto fail;
    }
    if (j->total == 0) {
        snprintf(why, whylen, "%s: no commands to send%s", path, resume_from > 1 ? " from that line" : "");
        goto fail;
    }
    if (resume_from > 1)
        build_preamble(j, &st);
    if (job_restart(j) != 0) {
        snprintf(why, whylen, "%s: cannot restart the G-code writer", path);
        goto fail;
    }
    j->line = 0;
    jbar_end(&bar, 1);
    return 0;
fail:
    jbar_end(&bar, 0);
    br_job_close(j);
    return -1;
}

int br_job_next(br_job *j, char *buf, size_t cap, long *jobline)
{
    char tmp[JOB_LINE_MAX];
    if (j->ipre < j->npre) {
        snprintf(buf, cap, "%s", j->pre[j->ipre++]);
        *jobline = 0;
        return 1;
    }
    if (!j->f && !j->is_amp)
        return 0;
    for (;;) {
        char *c;
        int r = job_read(j, tmp, sizeof tmp);
        if (r <= 0)
            return r;
        j->line++;
        c = clean(tmp);
        if (*c == '\0' || j->line < j->first_line)
            continue;
        snprintf(buf, cap, "%s", c);
        *jobline = j->line;
        return 1;
    }
}

void br_job_close(br_job *j)
{
    if (j->f)
        fclose(j->f);
    j->f = NULL;
    if (j->is_amp)
        amp_pathset_free(&j->ps);
    j->is_amp = 0;
}
