/* Shared plumbing of the ampath commands. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"

/* A program of its own ("ampath-bridge") or a command of ampath ("cover"). */
static int is_program(const char *cmd)
{
    return strncmp(cmd, "ampath-", 7) == 0 || strcmp(cmd, "ampath") == 0;
}

/* The reason is one line whatever the file names and values in it hold: control characters are written as
 * escapes (a newline in a name made a reason of two lines). */
int cli_fail(const char *cmd, int code, const char *fmt, ...)
{
    char msg[2048];
    const unsigned char *c;
    va_list ap;
    fprintf(stderr, is_program(cmd) ? "%s: " : "ampath %s: ", cmd);
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    for (c = (const unsigned char *)msg; *c; c++) {
        if (*c == '\n')
            fputs("\\n", stderr);
        else if (*c < 0x20 || *c == 0x7f)
            fprintf(stderr, "\\x%02x", *c);
        else
            fputc(*c, stderr);
    }
    fputc('\n', stderr);
    return code;
}

int cli_fail_err(const char *cmd, const amp_error *err)
{
    return cli_fail(cmd, CLI_USAGE, "%s", err->msg[0] ? err->msg : amp_strerror(err->status));
}

/*
 * Accepted ranges of the numeric options, by name (and command where one name means
 * different things), checked once here for every command: a value outside is
 * refused with exit 2 before any work, instead of `--feed 1e-300` writing F0 or
 * `--layer 1e308` giving 0 layers. The bounds are physical plausibility for an FDM printer
 * and its geometry (mm, mm/s, degrees, C), generous on both sides; the first match wins.
 * Options not listed (seeds, indices) take any value their command accepts.
 */
typedef struct cli_range {
    const char *cmd; /* NULL: every command */
    const char *name;
    double lo, hi;
} cli_range;

static const cli_range cli_ranges[] = {
    {"model", "tol", 0.005, 1},    /* mesh tessellation tolerance (as amp_mesh_model): smaller means runaway triangle counts */
    {NULL, "tol", 1e-12, 100},     /* check: the inside test's distance tolerance */
    {NULL, "eps", 1e-4, 1e4},      /* coverage bound; the work estimate of cover refuses most small values */
    {"gcode", "chord-tol", 0, 10}, /* 0: write every input segment */
    {NULL, "chord-tol", 1e-6, 100},
    {NULL, "layer", 1e-3, 100},
    {NULL, "first-layer", 0, 100}, /* 0: same as --layer */
    {NULL, "radius", 1e-3, 100},
    {NULL, "nominal", 1e-3, 100},
    {NULL, "min", 1e-3, 100},
    {NULL, "max", 1e-3, 100},
    {NULL, "fragment", 1e-3, 1e4},
    {NULL, "volume", 1e-9, 1e15},
    {NULL, "spacing", 1e-3, 1e4},
    {NULL, "step", 1e-3, 1e4},
    {NULL, "min-len", 0, 1e4},
    {NULL, "side", 1e-2, 1e4},
    {NULL, "min-gap", 0, 1e4},
    {NULL, "cell", 1e-3, 1e4},
    {NULL, "offset", 1e-4, 1e4},
    {NULL, "z", -1e5, 1e5},
    {NULL, "z-offs", -1e4, 1e4},
    {NULL, "theta", -360, 360},
    {NULL, "cells", 1, 64},
    {NULL, "min-depth", 0, 30},
    {NULL, "samples", 0, 1e9},
    {NULL, "width", 200, 8000},
    {NULL, "lookahead", 1, 16},
    {NULL, "max-edges", 0, 1e9},
    {NULL, "object", 0, 1e6},
    /* printing (gcode) */
    {NULL, "filament", 0.5, 5},
    {NULL, "flow", 0.01, 10},
    {NULL, "max-flow", 0.1, 1000},
    {NULL, "feed", 0.1, 1000},
    {NULL, "travel-feed", 0.1, 2000},
    {NULL, "retract", 0, 100},
    {NULL, "retract-speed", 0.1, 1000},
    {NULL, "z-hop", 0, 100},
    {NULL, "corridor", 0, 1000},
    {NULL, "end-lift", 0, 1000},
    {NULL, "hotend", 0, 500},
    {NULL, "bed", 0, 200},
    {NULL, "accel", 1, 1e6},
    {NULL, "junction-deviation", 0, 100},
    {NULL, "max-feed-xy", 0.1, 1e4},
    {NULL, "max-feed-z", 0.1, 1e4},
    {NULL, "max-feed-e", 0.1, 1e4},
    {NULL, "max-accel-xy", 0, 1e6},
    {NULL, "max-accel-z", 0, 1e6},
    {NULL, "max-accel-e", 0, 1e6},
    {NULL, "retract-accel", 0, 1e6},
    {NULL, "max-cross-section", 0, 1e4},
    {NULL, "first-layer-feed", 0.1, 1000},
    {NULL, "retract-min-travel", 0, 1000},
    {NULL, "first-layer-hotend", 0, 500},
    {NULL, "first-layer-bed", 0, 200},
    {NULL, "fan", 0, 100},
    {NULL, "fan-off-layers", 0, 1e6},
    {NULL, "radius-tol", 0, 10},
    {NULL, "min-segment", 0, 10},
    /* ampath-bridge (its own program: the ranges of its options) */
    {"ampath-bridge", "client-timeout", 1e-3, 86400},
    {"ampath-bridge", "ready-timeout", 1e-3, 86400},
    {"ampath-bridge", "baud", 50, 4e6},
    {"ampath-bridge", "bufsize", 1, AMP_PROTO_MAX_INFLIGHT},
    {"ampath-bridge", "rx-bytes", AMP_PROTO_LINE_MAX, 65536},
    {"ampath-bridge", "timeout", 1e-3, 3600},
    {"ampath-bridge", "settle-ms", 0, 10000},
    {"ampath-bridge", "boot-wait", 0, 600},
    {"ampath-bridge", "reconnect", 0, 1e6},
    {"ampath-bridge", "resume-from", 1, 1e15},
    /* work limits */
    {NULL, "max-curves", 1, 1e15},
    {NULL, "max-length", 1, 1e15},
    {NULL, "max-segments", 1, 1e15},
};

static int check_range(const char *cmd, const cli_opt *o, double v, const char *val)
{
    size_t i;
    for (i = 0; i < sizeof cli_ranges / sizeof cli_ranges[0]; i++) {
        const cli_range *r = &cli_ranges[i];
        if (strcmp(r->name, o->name) != 0 || (r->cmd && strcmp(r->cmd, cmd) != 0))
            continue;
        if (v < r->lo || v > r->hi)
            return cli_fail(cmd, CLI_USAGE, "--%s must lie in [%g, %g], got '%s'", o->name, r->lo, r->hi, val);
        if (strcmp(o->name, "first-layer") == 0 && v != 0 && v < 1e-3)
            return cli_fail(cmd, CLI_USAGE, "--first-layer must be 0 (the --layer height) or lie in [0.001, 100], got '%s'",
                            val);
        return CLI_OK;
    }
    return CLI_OK;
}

int cli_number(const char *s, double *out)
{
    char *end;
    double d;
    if (strpbrk(s, "xX"))
        return -1; /* strtod's hexadecimal floats: 0x10 is not the 10 a user meant */
    errno = 0;
    d = strtod(s, &end);
    if (end == s || *end || !isfinite(d))
        return -1;
    *out = d;
    return 0;
}

int cli_integer(const char *s, long *out)
{
    char *end;
    long l;
    errno = 0;
    l = strtol(s, &end, 10);
    if (end == s || *end || errno)
        return -1;
    *out = l;
    return 0;
}

static int set_value(const char *cmd, cli_opt *o, const char *val)
{
    switch (o->kind) {
    case CLI_STR:
        *(const char **)o->dst = val;
        return CLI_OK;
    case CLI_DOUBLE: {
        double d;
        if (cli_number(val, &d) != 0)
            return cli_fail(cmd, CLI_USAGE, "--%s expects a number, got '%s'", o->name, val);
        if (check_range(cmd, o, d, val) != CLI_OK)
            return CLI_USAGE;
        *(double *)o->dst = d;
        return CLI_OK;
    }
    case CLI_LONG: {
        long l;
        if (cli_integer(val, &l) != 0)
            return cli_fail(cmd, CLI_USAGE, "--%s expects an integer, got '%s'", o->name, val);
        if (check_range(cmd, o, (double)l, val) != CLI_OK)
            return CLI_USAGE;
        *(long *)o->dst = l;
        return CLI_OK;
    }
    case CLI_LIST: {
        cli_list *l = o->dst;
        long v;
        if (cli_integer(val, &v) != 0)
            return cli_fail(cmd, CLI_USAGE, "--%s expects an integer, got '%s'", o->name, val);
        if (l->n >= CLI_LIST_MAX)
            return cli_fail(cmd, CLI_USAGE, "--%s given more than %d times", o->name, CLI_LIST_MAX);
        if (check_range(cmd, o, (double)v, val) != CLI_OK)
            return CLI_USAGE;
        l->v[l->n++] = v;
        return CLI_OK;
    }
    case CLI_FLAG:
        break;
    }
    return cli_fail(cmd, CLI_USAGE, "--%s takes no value", o->name);
}

/* ---- work limits: estimated before the work, overridable per run ---- */
cli_limits cli_work = {CLI_DEFAULT_MAX_CURVES, CLI_DEFAULT_MAX_LENGTH, CLI_DEFAULT_MAX_SEGMENTS};

/* The --max-... options of the commands that estimate their work: accepted next to the
 * command's own table, so that the commands sharing a loader need no option of their own. */
static cli_opt *work_limit_opt(const char *cmd, const char *name, size_t len)
{
    static cli_opt curves = {"max-curves", CLI_DOUBLE, &cli_work.max_curves, 0};
    static cli_opt length = {"max-length", CLI_DOUBLE, &cli_work.max_length, 0};
    static cli_opt segments = {"max-segments", CLI_DOUBLE, &cli_work.max_segments, 0};
    cli_opt *o = NULL;
    if (strcmp(cmd, "cover") == 0)
        o = strlen(length.name) == len && strncmp(length.name, name, len) == 0 ? &length : &curves;
    else if (strcmp(cmd, "slice") == 0 || strcmp(cmd, "euler") == 0 || strcmp(cmd, "check") == 0)
        o = &segments;
    return o && strlen(o->name) == len && strncmp(o->name, name, len) == 0 ? o : NULL;
}

int cli_work_refuse(const char *cmd, const char *what, double estimate, double limit, const char *option)
{
    return cli_fail(cmd, CLI_USAGE,
                    "refused: about %.3g %s estimated, more than the limit of %.3g (raise it with --%s N)", estimate,
                    what, limit, option);
}

int cli_given(const cli_opt *opts, const char *name)
{
    for (; opts->name; opts++)
        if (strcmp(opts->name, name) == 0)
            return opts->seen;
    return 0;
}

/* Where the usage of @p cmd is: 'ampath help CMD' or 'ampath-bridge --help' (one static buffer). */
static const char *help_ref(const char *cmd)
{
    static char buf[96];
    snprintf(buf, sizeof buf, is_program(cmd) ? "'%s --help'" : "'ampath help %s'", cmd);
    return buf;
}

/* Is @p path the file @p out names (both existing)? */
static int same_file(const char *path, const struct stat *out)
{
    struct stat s;
    return path && stat(path, &s) == 0 && s.st_dev == out->st_dev && s.st_ino == out->st_ino;
}

/* -o naming one of the command's input files: the product would replace it (`gcode job.amp -o job.amp` turned
 * the .amp into G-code, `slice part.stl -o part.stl` the mesh into paths). Refused, except the path set that
 * order, mdr and support rewrite in place (they read it whole before the output replaces it atomically). */
static int clobbers_input(const char *cmd, const cli_opt *opts, const char **pos, int n)
{
    static const char *const in_place[] = {"order", "mdr", "support"};
    const cli_opt *o;
    const char *out = NULL;
    struct stat so;
    int k, keep = 0;
    for (o = opts; o && o->name; o++)
        if (o->kind == CLI_STR && o->seen && strcmp(o->name, "output") == 0)
            out = *(const char *const *)o->dst;
    if (!out || stat(out, &so) != 0 || !S_ISREG(so.st_mode))
        return CLI_OK;
    for (k = 0; k < 3; k++)
        keep |= strcmp(cmd, in_place[k]) == 0;
    for (k = 0; k < n; k++)
        if (!(k == 0 && keep) && same_file(pos[k], &so))
            return cli_fail(cmd, CLI_USAGE, "-o %s is the input %s: it would be overwritten (write to another file)",
                            out, pos[k]);
    for (o = opts; o && o->name; o++)
        if (o->kind == CLI_STR && o->seen && strcmp(o->name, "output") != 0 &&
            same_file(*(const char *const *)o->dst, &so))
            return cli_fail(cmd, CLI_USAGE, "-o %s is the --%s file: it would be overwritten (write to another file)",
                            out, o->name);
    return CLI_OK;
}

int cli_parse(const char *cmd, int argc, char **argv, cli_opt *opts, const char **pos, int min_pos, int max_pos,
              int *npos)
{
    int i, n = 0, only_pos = 0;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!only_pos && strcmp(a, "--") == 0) {
            only_pos = 1;
            continue;
        }
        if (!only_pos && a[0] == '-' && a[1] == '-' && a[2]) {
            const char *name = a + 2, *eq = strchr(name, '=');
            size_t len = eq ? (size_t)(eq - name) : strlen(name);
            cli_opt *o = opts;
            while (o && o->name && !(strlen(o->name) == len && strncmp(o->name, name, len) == 0))
                o++;
            if (!o || !o->name)
                o = work_limit_opt(cmd, name, len);
            if (!o)
                return cli_fail(cmd, CLI_USAGE, "unknown option '%s' (see %s)", a, help_ref(cmd));
            o->seen = 1;
            if (o->kind == CLI_FLAG) {
                if (eq)
                    return cli_fail(cmd, CLI_USAGE, "--%s takes no value", o->name);
                *(int *)o->dst = 1;
                continue;
            }
            if (!eq && i + 1 >= argc)
                return cli_fail(cmd, CLI_USAGE, "--%s needs a value", o->name);
            if (set_value(cmd, o, eq ? eq + 1 : argv[++i]) != CLI_OK)
                return CLI_USAGE;
            continue;
        }
        if (!only_pos && a[0] == '-' && a[1] && !(a[1] >= '0' && a[1] <= '9') && a[1] != '.') {
            /* short options: only -o FILE is common to all commands */
            cli_opt *o = opts;
            if (strcmp(a, "-o") == 0) {
                while (o && o->name && strcmp(o->name, "output") != 0)
                    o++;
                if (o && o->name) {
                    if (i + 1 >= argc)
                        return cli_fail(cmd, CLI_USAGE, "-o needs a file name");
                    o->seen = 1;
                    *(const char **)o->dst = argv[++i];
                    continue;
                }
            }
            return cli_fail(cmd, CLI_USAGE, "unknown option '%s' (see %s)", a, help_ref(cmd));
        }
        if (n >= max_pos)
            return cli_fail(cmd, CLI_USAGE, "unexpected argument '%s' (see %s)", a, help_ref(cmd));
        pos[n++] = a;
    }
    if (n < min_pos)
        return cli_fail(cmd, CLI_USAGE, "missing argument (see %s)", help_ref(cmd));
    if (npos)
        *npos = n;
    return clobbers_input(cmd, opts, pos, n);
}

/* ---- JSON ---- */
static void json_key(cli_json *j, const char *key)
{
    if (j->count[j->depth]++ > 0)
        fputc(',', j->f);
    if (key) {
        const char *s;
        fputc('"', j->f);
        for (s = key; *s; s++)
            fputc(*s, j->f);
        fputs("\":", j->f);
    }
}

void cli_json_members(cli_json *j, const char *members)
{
    json_key(j, NULL);
    fputs(members, j->f);
}

void cli_json_begin(cli_json *j, FILE *f)
{
    memset(j, 0, sizeof *j);
    j->f = f;
    j->close[0] = '}';
    fputc('{', f);
}

void cli_json_num(cli_json *j, const char *key, double v)
{
    json_key(j, key);
    if (isfinite(v))
        fprintf(j->f, "%.12g", v);
    else
        fputs("null", j->f);
}

void cli_json_int(cli_json *j, const char *key, long long v)
{
    json_key(j, key);
    fprintf(j->f, "%lld", v);
}

void cli_json_bool(cli_json *j, const char *key, int v)
{
    json_key(j, key);
    fputs(v ? "true" : "false", j->f);
}

void cli_json_str(cli_json *j, const char *key, const char *s)
{
    json_key(j, key);
    fputc('"', j->f);
    for (; s && *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(j->f, "\\%c", c);
        else if (c < 0x20)
            fprintf(j->f, "\\u%04x", c);
        else
            fputc(c, j->f);
    }
    fputc('"', j->f);
}

static void json_open(cli_json *j, const char *key, char open, char close)
{
    json_key(j, key);
    fputc(open, j->f);
    if (j->depth + 1 < CLI_JSON_DEPTH) {
        j->depth++;
        j->count[j->depth] = 0;
        j->close[j->depth] = close;
    }
}

void cli_json_obj(cli_json *j, const char *key) { json_open(j, key, '{', '}'); }
void cli_json_arr(cli_json *j, const char *key) { json_open(j, key, '[', ']'); }

void cli_json_close(cli_json *j)
{
    if (j->depth > 0) {
        fputc(j->close[j->depth], j->f);
        j->depth--;
    }
}

void cli_json_csv(cli_json *j, const char *key, const char *csv)
{
    const char *u;
    cli_json_arr(j, key);
    for (u = csv; *u;) {
        char item[128];
        size_t n = strcspn(u, ",");
        snprintf(item, sizeof item, "%.*s", (int)(n < 127 ? n : 127), u);
        cli_json_str(j, NULL, item);
        u += n + (u[n] == ',');
    }
    cli_json_close(j);
}

void cli_json_vec3(cli_json *j, const char *key, amp_vec3 v)
{
    cli_json_arr(j, key);
    cli_json_num(j, NULL, v.x);
    cli_json_num(j, NULL, v.y);
    cli_json_num(j, NULL, v.z);
    cli_json_close(j);
}

void cli_json_box(cli_json *j, const char *key, amp_box3 b)
{
    cli_json_arr(j, key);
    cli_json_num(j, NULL, b.min.x);
    cli_json_num(j, NULL, b.min.y);
    cli_json_num(j, NULL, b.min.z);
    cli_json_num(j, NULL, b.max.x);
    cli_json_num(j, NULL, b.max.y);
    cli_json_num(j, NULL, b.max.z);
    cli_json_close(j);
}

void cli_json_end(cli_json *j)
{
    while (j->depth > 0)
        cli_json_close(j);
    fputs("}\n", j->f);
    fflush(j->f);
}

/* ---- progress ---- */
void cli_progress_begin(cli_progress *p, const char *label)
{
    p->label = label;
    p->enabled = isatty(STDERR_FILENO);
    p->last_permille = -1;
}

void cli_progress_update(cli_progress *p, double fraction)
{
    int permille, i, filled;
    if (!p->enabled)
        return;
    if (fraction < 0.0)
        fraction = 0.0;
    if (fraction > 1.0)
        fraction = 1.0;
    permille = (int)(fraction * 1000.0);
    if (permille == p->last_permille)
        return;
    p->last_permille = permille;
    filled = permille * 30 / 1000;
    fprintf(stderr, "\r%-12s [", p->label);
    for (i = 0; i < 30; i++)
        fputc(i < filled ? '#' : ' ', stderr);
    fprintf(stderr, "] %5.1f%%", permille / 10.0);
    fflush(stderr);
}

void cli_progress_end(cli_progress *p)
{
    if (p->enabled && p->last_permille >= 0) {
        cli_progress_update(p, 1.0);
        fputc('\n', stderr);
    }
}

double cli_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Files from this size on show a bar while they are read (PrusaSlicer's bunny sliced, 25 MB, reads in about
 * 0.1 s; a bed-sized job of several hundred MB in seconds). */
#define CLI_READ_BAR_BYTES ((off_t)16 << 20)

int cli_load_paths(const char *cmd, const char *file, amp_pathset *ps)
{
    amp_error err;
    cli_progress bar;
    struct stat sb;
    int big = stat(file, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size >= CLI_READ_BAR_BYTES;
    amp_status st;
    amp_error_clear(&err);
    cli_progress_begin(&bar, "reading");
    st = amp_pathset_read_file_progress(ps, file, big ? cli_progress_fn : NULL, &bar, &err);
    cli_progress_end(&bar);
    if (st != AMP_OK) {
        /* the parser keeps what it had grown: release it here, once for every command,
         * so that a bad input exits 2 and not 1 with a leak report under ASan */
        amp_pathset_free(ps);
        return cli_fail_err(cmd, &err);
    }
    return CLI_OK;
}

int cli_save_derived(const char *cmd, const char *file, const amp_pathset *ps, const char *comment, const char *from)
{
    char all[2048], line[512];
    size_t n;
    int lines = 0;
    FILE *f = fopen(from, "r");
    snprintf(all, sizeof all, "%s", comment);
    n = strlen(all);
    /* the header: the magic line, then comment lines until the first path */
    while (f && lines < 16 && fgets(line, sizeof line, f)) {
        size_t k = strlen(line);
        if (line[0] != '#' && strncmp(line, "ampath-paths", 12) != 0)
            break;
        if (strncmp(line, "# ampath ", 9) != 0 || strchr(line, '\n') == NULL)
            continue;
        line[k - 1] = 0;
        if (n + k + 1 < sizeof all && strstr(all, line + 2) == NULL) {
            snprintf(all + n, sizeof all - n, "\n%s", line + 2);
            n += strlen(all + n);
        }
        lines++;
    }
    if (f)
        fclose(f);
    return cli_save_paths(cmd, file, ps, all);
}

int cli_save_paths(const char *cmd, const char *file, const amp_pathset *ps, const char *comment)
{
    amp_error err;
    amp_error_clear(&err);
    if (amp_pathset_write_file(ps, file, comment, &err) != AMP_OK)
        return cli_fail_err(cmd, &err);
    return CLI_OK;
}

void cli_progress_fn(void *user, double fraction) { cli_progress_update((cli_progress *)user, fraction); }

int cli_ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

double cli_positive(double seconds) { return seconds > 0 ? seconds : 1e-9; }

int cli_load_trivariate(const char *cmd, const char *what, amp_spline *out)
{
    amp_error err;
    amp_spline *list;
    size_t n, i;
    const char *const *names = amp_trivariate_model_names();
    amp_error_clear(&err);
    for (i = 0; names[i]; i++)
        if (strcmp(names[i], what) == 0) {
            if (amp_trivariate_model(what, NULL, out, &err) != AMP_OK)
                return cli_fail_err(cmd, &err);
            return CLI_OK;
        }
    if (!strchr(what, '/') && !cli_ends_with(what, ".spl") && access(what, F_OK) != 0) {
        char known[256] = "";
        for (i = 0; names[i]; i++) /* a name, not a file: say which names there are */
            snprintf(known + strlen(known), sizeof known - strlen(known), "%s%s", i ? ", " : "", names[i]);
        return cli_fail(cmd, CLI_USAGE, "'%s' is neither a built-in trivariate (%s) nor a .spl file", what, known);
    }
    if (amp_spline_read_file(what, NULL, &list, &n, &err) != AMP_OK)
        return strncmp(err.msg, what, strlen(what)) == 0 ? cli_fail(cmd, CLI_USAGE, "%s", err.msg) /* names it */
                                                            : cli_fail(cmd, CLI_USAGE, "%s: %s", what, err.msg);
    for (i = 0; i < n && list[i].dim != 3; i++)
        ;
    if (i == n) {
        amp_spline_list_free(NULL, list, n);
        return cli_fail(cmd, CLI_USAGE, "%s: no trivariate in the file", what);
    }
    *out = list[i];
    amp_spline_init(&list[i]);
    amp_spline_list_free(NULL, list, n);
    return CLI_OK;
}

int cli_program(const char *env, const char *name, const char *dir, char *out, size_t cap)
{
    const char *e = env ? getenv(env) : NULL;
    char exe[4096], *slash;
    ssize_t n;
    if (e && *e)
        return snprintf(out, cap, "%s", e) < (int)cap ? 0 : -1;
    n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    exe[n > 0 ? n : 0] = '\0';
    if (n <= 0 || !(slash = strrchr(exe, '/')))
        return snprintf(out, cap, "%s/%s", dir, name) < (int)cap ? 0 : -1;
    *slash = '\0';
    /* installed: side by side; build tree: tools/ and bridge/ are siblings */
    if (snprintf(out, cap, "%s/%s", exe, name) < (int)cap && access(out, X_OK) == 0)
        return 0;
    return snprintf(out, cap, "%s/../%s/%s", exe, dir, name) < (int)cap ? 0 : -1;
}
