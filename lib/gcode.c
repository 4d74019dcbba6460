/*
 * G-code writer (SPEC §5): an allocation-free line iterator over a path set.
 *
 * The iterator is a small state machine (header, start sequence, set-up,
 * paths with their travels, teardown, end sequence). Init runs it once
 * without formatting (pass 1) to obtain the figures the header prints; the
 * caller's calls to amp_gcode_iter_next() then run it again (pass 2) and
 * format each line with an integer fixed-point formatter (no printf on the
 * hot path, no locale, no exponents).
 */
#include <math.h>
#include <stdarg.h>
#include <string.h>

#include "ampath/gcode.h"
#include "ampath/version.h"

#define GC_MAGIC 0x67636f64u
#define GC_PI 3.14159265358979323846
#define GC_MIN_SEG 1e-9      /* segments shorter than this (mm) are not printed */
#define GC_COORD_MAX 99999.0 /* keeps every number short enough for AMP_GCODE_LINE_MAX */

enum { PH_HEADER, PH_START, PH_SETUP, PH_PATHS, PH_TEARDOWN, PH_END, PH_DONE };
/* sub-steps of PH_PATHS */
enum { PS_COMMENT, PS_RETRACT, PS_LIFT, PS_XY, PS_DESCEND, PS_UNRETRACT, PS_SEGS };
enum { MOVE_NONE = 0, MOVE_PRINT = 1, MOVE_TRAVEL = 2, MOVE_E = 3 };

void amp_gcode_opts_default(amp_gcode_opts *o, int flavor)
{
    memset(o, 0, sizeof *o);
    o->flavor = flavor;
    o->filament_diameter = 1.75;
    o->flow = 1.0;
    o->max_volumetric_flow = 12.0;
    o->print_feed = 30.0;
    o->travel_feed = 120.0;
    o->retract_length = 1.0;
    o->retract_speed = 35.0;
    o->z_hop = 0.4;
    o->travel_corridor = 2.0;
    o->end_lift = 10.0;
    o->relative_e = flavor == AMP_FLAVOR_KLIPPER; /* SPEC §5: Klipper uses M83 by default */
    o->hotend_temp = 210.0;
    o->bed_temp = 60.0;
    o->start_gcode = NULL;
    o->end_gcode = NULL;
    o->accel = 1000.0;
    o->junction_deviation = 0.05;
    o->max_feed_xy = 200.0;
    o->max_feed_z = 10.0;
    o->max_feed_e = 60.0;
}

/* ---------------------------------------------------------------- line builder */

typedef struct lb {
    char *b; /* NULL in pass 1: nothing is formatted */
    size_t n;
} lb;

static void lb_str(lb *l, const char *s)
{
    if (!l->b)
        return;
    while (*s && l->n < AMP_GCODE_LINE_MAX)
        l->b[l->n++] = *s++;
    l->b[l->n] = '\0';
}

/* " Xnnn.ddd": value given in units of 10^-dec, trailing zeros dropped. */
static void lb_fixed(lb *l, char letter, long long units, int dec)
{
    char tmp[32];
    int k = 0, i, neg = units < 0;
    unsigned long long u = neg ? (unsigned long long)(-(units + 1)) + 1u : (unsigned long long)units;
    if (!l->b)
        return;
    /* digits in reverse: dec fraction digits, then the integer part */
    for (i = 0; i < dec; i++) {
        tmp[k++] = (char)('0' + (int)(u % 10u));
        u /= 10u;
    }
    {
        int start = 0; /* drop trailing zeros of the fraction (they are first in tmp) */
        while (start < dec && tmp[start] == '0')
            start++;
        memmove(tmp, tmp + start, (size_t)(k - start));
        k -= start;
        if (k > 0)
            tmp[k++] = '.';
    }
    do {
        tmp[k++] = (char)('0' + (int)(u % 10u));
        u /= 10u;
    } while (u);
    if (neg)
        tmp[k++] = '-';
    if (letter) {
        if (l->n + 2 > AMP_GCODE_LINE_MAX)
            return;
        if (l->n > 0)
            l->b[l->n++] = ' ';
        l->b[l->n++] = letter;
    }
    while (k > 0 && l->n < AMP_GCODE_LINE_MAX)
        l->b[l->n++] = tmp[--k];
    l->b[l->n] = '\0';
}

static long long units_of(double v, double scale) { return llround(v * scale); }

static void lb_num(lb *l, char letter, double v, int dec)
{
    double scale = dec == 1 ? 10.0 : dec == 3 ? 1000.0 : dec == 5 ? 100000.0 : 1.0;
    lb_fixed(l, letter, units_of(v, scale), dec);
}

/* ---------------------------------------------------------------- material grid */

static int grid_index(double v, double v0, double cell)
{
    double f = floor((v - v0) / cell);
    if (!(f >= 0.0))
        return 0;
    if (f > (double)(AMP_GCODE_GRID - 1))
        return AMP_GCODE_GRID - 1;
    return (int)f;
}

/*
 * Visit every cell within @p w (plus half a sampling step) of the XY segment
 * a-b: samples every half cell, each covering a box of half-width w + h/2, so
 * every point within w of the segment lies in a visited cell (conservative).
 * mode 0: raise cells to @p top; mode 1: return the highest cell.
 */
static double grid_walk(amp_gcode_iter *it, amp_vec3 a, amp_vec3 b, double w, double top, int mode)
{
    double dx = b.x - a.x, dy = b.y - a.y, len = sqrt(dx * dx + dy * dy), h, best = -HUGE_VAL;
    double cell = it->grid_cell;
    long steps = (long)ceil(len / (0.5 * cell)), s;
    if (steps < 1)
        steps = 1;
    h = len / (double)steps;
    w += 0.5 * h;
    for (s = 0; s <= steps; s++) {
        double t = (double)s / (double)steps, px = a.x + t * dx, py = a.y + t * dy;
        int i0 = grid_index(px - w, it->grid_x0, cell), i1 = grid_index(px + w, it->grid_x0, cell);
        int j0 = grid_index(py - w, it->grid_y0, cell), j1 = grid_index(py + w, it->grid_y0, cell);
        int i, j;
        for (j = j0; j <= j1; j++)
            for (i = i0; i <= i1; i++) {
                float *c = &it->grid[j * AMP_GCODE_GRID + i];
                if (mode == 0) {
                    if ((double)*c < top) {
                        *c = (float)top;
                        if ((double)*c < top) /* float rounding must not lower the top */
                            *c = nextafterf(*c, HUGE_VALF);
                    }
                } else if ((double)*c > best) {
                    best = (double)*c;
                }
            }
    }
    return best;
}

/* ---------------------------------------------------------------- time estimate */

double amp_gcode_trapezoid_time(double len, double v0, double v1, double vmax, double accel)
{
    double da, dd, vp;
    if (len <= 0.0)
        return 0.0;
    if (vmax <= 0.0 || accel <= 0.0)
        return vmax > 0.0 ? len / vmax : 0.0;
    if (v0 > vmax)
        v0 = vmax;
    if (v1 > vmax)
        v1 = vmax;
    da = (vmax * vmax - v0 * v0) / (2.0 * accel);
    dd = (vmax * vmax - v1 * v1) / (2.0 * accel);
    if (da + dd <= len)
        return (vmax - v0) / accel + (vmax - v1) / accel + (len - da - dd) / vmax;
    /* triangle: the peak where the acceleration and deceleration ramps meet */
    vp = sqrt(0.5 * (2.0 * accel * len + v0 * v0 + v1 * v1));
    if (vp < v0)
        vp = v0;
    if (vp < v1)
        vp = v1;
    return (vp - v0) / accel + (vp - v1) / accel;
}

static amp_gcode_block *plan_at(amp_gcode_iter *it, size_t k)
{
    return &it->plan[(it->plan_head + k) % AMP_GCODE_LOOKAHEAD];
}

/*
 * Execute the oldest planned block: a backward pass over the window (which
 * must end at rest, as a firmware planner with a finite buffer must) gives the
 * highest speed it may leave with; a forward step from its entry speed gives
 * the reachable one.
 */
static void plan_commit(amp_gcode_iter *it)
{
    double a = it->o.accel, vexit = 0.0, t;
    amp_gcode_block *b0 = plan_at(it, 0);
    size_t k;
    for (k = it->plan_n; k-- > 1;) {
        amp_gcode_block *b = plan_at(it, k);
        double ventry = sqrt(vexit * vexit + 2.0 * a * b->len);
        vexit = ventry < b->vjunc ? ventry : b->vjunc;
    }
    {
        double reach = sqrt(it->plan_v * it->plan_v + 2.0 * a * b0->len);
        if (vexit > reach)
            vexit = reach;
        if (vexit > b0->vnom)
            vexit = b0->vnom;
    }
    t = amp_gcode_trapezoid_time(b0->len, it->plan_v, vexit, b0->vnom, a);
    it->stats.time += t;
    it->stats.print_time += t;
    it->plan_v = vexit;
    it->plan_head = (it->plan_head + 1) % AMP_GCODE_LOOKAHEAD;
    it->plan_n--;
}

static void plan_flush(amp_gcode_iter *it)
{
    while (it->plan_n > 0)
        plan_commit(it);
    it->plan_v = 0.0;
}

/* Junction speed limit between unit directions u1 (incoming) and u2 (Grbl/Marlin junction deviation). */
static double junction_speed(const amp_gcode_opts *o, const amp_gcode_block *p, const amp_gcode_block *b)
{
    double c = -(p->ux * b->ux + p->uy * b->uy + p->uz * b->uz), s;
    if (c > 0.999999)
        return 0.0; /* reversal */
    if (c < -0.999999)
        return HUGE_VAL; /* straight on */
    s = sqrt(0.5 * (1.0 - c));
    return sqrt(o->accel * o->junction_deviation * s / (1.0 - s));
}

static void plan_print(amp_gcode_iter *it, amp_vec3 d, double len, double feed, double de)
{
    amp_gcode_block b;
    double v = feed, hxy = sqrt(d.x * d.x + d.y * d.y);
    b.len = len;
    b.ux = d.x / len;
    b.uy = d.y / len;
    b.uz = d.z / len;
    /* the firmware clamps each axis to its maximum feed */
    if (hxy > 0.0 && v * hxy / len > it->o.max_feed_xy)
        v = it->o.max_feed_xy * len / hxy;
    if (fabs(d.z) > 0.0 && v * fabs(d.z) / len > it->o.max_feed_z)
        v = it->o.max_feed_z * len / fabs(d.z);
    if (de > 0.0 && v * de / len > it->o.max_feed_e)
        v = it->o.max_feed_e * len / de;
    b.vnom = v;
    if (it->plan_n == 0) {
        b.vjunc = it->plan_v; /* from rest after a flush, or continuing speed */
    } else {
        const amp_gcode_block *p = plan_at(it, it->plan_n - 1);
        double vj = junction_speed(&it->o, p, &b);
        if (vj > p->vnom)
            vj = p->vnom;
        if (vj > b.vnom)
            vj = b.vnom;
        b.vjunc = vj;
    }
    if (it->plan_n == AMP_GCODE_LOOKAHEAD)
        plan_commit(it);
    *plan_at(it, it->plan_n) = b;
    it->plan_n++;
}

/* A move outside the print planner: from rest to rest. */
static void plan_single(amp_gcode_iter *it, double len, double v)
{
    double t;
    plan_flush(it);
    t = amp_gcode_trapezoid_time(len, 0.0, 0.0, v, it->o.accel);
    it->stats.time += t;
    it->stats.travel_time += t;
}

/* ---------------------------------------------------------------- option and input checks */

static amp_status check_text(const char *text, const char *what, amp_error *err)
{
    long line = 1;
    const char *s = text;
    while (*s) {
        const char *e = strchr(s, '\n');
        size_t n = e ? (size_t)(e - s) : strlen(s);
        while (n > 0 && (s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == '\t'))
            n--;
        if (n > AMP_GCODE_LINE_MAX)
            return amp_fail(err, AMP_ERR_LIMIT, line, "%s sequence: line %ld has %lu characters, at most %d allowed",
                            what, line, (unsigned long)n, AMP_GCODE_LINE_MAX);
        if (!e)
            break;
        s = e + 1;
        line++;
    }
    return AMP_OK;
}

#define NEED(cond, name, rule)                                                                                     \
    do {                                                                                                           \
        if (!(cond))                                                                                               \
            return amp_fail(err, AMP_ERR_ARG, 0, "gcode option %s must be %s", name, rule);                        \
    } while (0)

static amp_status check_opts(const amp_gcode_opts *o, amp_error *err)
{
    NEED(o->flavor == AMP_FLAVOR_MARLIN || o->flavor == AMP_FLAVOR_KLIPPER, "flavor", "marlin or klipper");
    NEED(isfinite(o->filament_diameter) && o->filament_diameter > 0.0 && o->filament_diameter <= 10.0,
         "filament diameter", "in (0, 10] mm");
    NEED(isfinite(o->flow) && o->flow > 0.0 && o->flow <= 10.0, "flow", "in (0, 10]");
    NEED(isfinite(o->max_volumetric_flow) && o->max_volumetric_flow > 0.0 && o->max_volumetric_flow <= 1e4,
         "max volumetric flow", "in (0, 10000] mm^3/s");
    NEED(isfinite(o->print_feed) && o->print_feed > 0.0 && o->print_feed <= 1e4, "print feed", "in (0, 10000] mm/s");
    NEED(isfinite(o->travel_feed) && o->travel_feed > 0.0 && o->travel_feed <= 1e4, "travel feed",
         "in (0, 10000] mm/s");
    NEED(isfinite(o->retract_length) && o->retract_length >= 0.0 && o->retract_length <= 100.0, "retract length",
         "in [0, 100] mm");
    NEED(isfinite(o->retract_speed) && o->retract_speed > 0.0 && o->retract_speed <= 1e4, "retract speed",
         "in (0, 10000] mm/s");
    NEED(isfinite(o->z_hop) && o->z_hop >= 0.0 && o->z_hop <= 1000.0, "z-hop", "in [0, 1000] mm");
    NEED(isfinite(o->travel_corridor) && o->travel_corridor >= 0.0 && o->travel_corridor <= 1000.0,
         "travel corridor", "in [0, 1000] mm");
    NEED(isfinite(o->end_lift) && o->end_lift >= 0.0 && o->end_lift <= 1000.0, "end lift", "in [0, 1000] mm");
    NEED(isfinite(o->hotend_temp) && o->hotend_temp >= 0.0 && o->hotend_temp <= 500.0, "hotend temperature",
         "in [0, 500] C");
    NEED(isfinite(o->bed_temp) && o->bed_temp >= 0.0 && o->bed_temp <= 200.0, "bed temperature", "in [0, 200] C");
    NEED(isfinite(o->accel) && o->accel > 0.0 && o->accel <= 1e6, "acceleration", "in (0, 1e6] mm/s^2");
    NEED(isfinite(o->junction_deviation) && o->junction_deviation >= 0.0 && o->junction_deviation <= 10.0,
         "junction deviation", "in [0, 10] mm");
    NEED(isfinite(o->max_feed_xy) && o->max_feed_xy > 0.0, "max feed xy", "positive");
    NEED(isfinite(o->max_feed_z) && o->max_feed_z > 0.0, "max feed z", "positive");
    NEED(isfinite(o->max_feed_e) && o->max_feed_e > 0.0, "max feed e", "positive");
    if (o->start_gcode && check_text(o->start_gcode, "start", err) != AMP_OK)
        return AMP_ERR_LIMIT;
    if (o->end_gcode && check_text(o->end_gcode, "end", err) != AMP_OK)
        return AMP_ERR_LIMIT;
    return AMP_OK;
}

/* Index of the first segment of non-zero length of path @p i at or after @p k, or n-1 if none. */
static size_t next_segment(const amp_pathset *ps, size_t i, size_t k)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    size_t n = ps->paths[i].n;
    for (; k + 1 < n; k++)
        if (amp_v3_dist(v[k].p, v[k + 1].p) > GC_MIN_SEG)
            return k;
    return n > 0 ? n - 1 : 0;
}

static void reset_run(amp_gcode_iter *it, int pass)
{
    size_t i;
    it->pass = pass;
    it->phase = PH_HEADER;
    it->sub = 0;
    it->path = 0;
    it->seg = 0;
    it->text = NULL;
    it->have_pos = 0;
    it->retracted = 0;
    it->printed_any = 0;
    it->pos = amp_v3(0, 0, 0);
    it->e_exact = 0.0;
    it->e_units = 0;
    it->f_units = -1;
    it->travel_z = 0.0;
    it->travel_to = amp_v3(0, 0, 0);
    for (i = 0; i < AMP_GCODE_GRID * AMP_GCODE_GRID; i++)
        it->grid[i] = -HUGE_VALF;
    it->plan_head = it->plan_n = 0;
    it->plan_v = 0.0;
    it->plan_print = 0;
    memset(&it->stats, 0, sizeof it->stats);
    it->stats.max_travel_z = -HUGE_VAL;
    memset(&it->last, 0, sizeof it->last);
}

static int step(amp_gcode_iter *it, lb *l);

amp_status amp_gcode_iter_init(amp_gcode_iter *it, const amp_pathset *ps, const amp_gcode_opts *o, amp_error *err)
{
    amp_box3 bb = amp_box3_empty();
    double rmax = 0.0, margin, ext;
    size_t i, nseg = 0;
    amp_status st;
    if (!it)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: NULL iterator");
    it->magic = 0;
    if (!ps)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: NULL path set");
    if (o)
        it->o = *o;
    else
        amp_gcode_opts_default(&it->o, AMP_FLAVOR_MARLIN);
    st = check_opts(&it->o, err);
    if (st != AMP_OK)
        return st;
    if (ps->npaths > 0 && (!ps->paths || !ps->verts))
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: inconsistent path set");
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v;
        size_t k;
        if (ps->paths[i].first > ps->nverts || ps->paths[i].n > ps->nverts - ps->paths[i].first)
            return amp_fail(err, AMP_ERR_ARG, 0, "gcode: path %lu lies outside the vertex array", (unsigned long)i);
        v = amp_pathset_path_verts(ps, i);
        for (k = 0; k < ps->paths[i].n; k++) {
            if (!amp_v3_finite(v[k].p) || !isfinite(v[k].r) || v[k].r < 0.0)
                return amp_fail(err, AMP_ERR_ARG, 0, "gcode: path %lu vertex %lu is not finite or has a negative radius",
                                (unsigned long)i, (unsigned long)k);
            if (fabs(v[k].p.x) > GC_COORD_MAX || fabs(v[k].p.y) > GC_COORD_MAX || fabs(v[k].p.z) > GC_COORD_MAX ||
                v[k].r > 1000.0)
                return amp_fail(err, AMP_ERR_RANGE, 0, "gcode: path %lu vertex %lu lies beyond +-%g mm",
                                (unsigned long)i, (unsigned long)k, GC_COORD_MAX);
            bb = amp_box3_add(bb, v[k].p);
            if (v[k].r > rmax)
                rmax = v[k].r;
        }
        if (next_segment(ps, i, 0) + 1 < ps->paths[i].n)
            nseg++;
    }
    if (nseg == 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: empty path set: no path has a segment of non-zero length");
    if (bb.max.z + rmax + it->o.z_hop + it->o.end_lift > GC_COORD_MAX)
        return amp_fail(err, AMP_ERR_RANGE, 0, "gcode: the job rises beyond %g mm", GC_COORD_MAX);
    it->ps = ps;
    it->fil_area = GC_PI * 0.25 * it->o.filament_diameter * it->o.filament_diameter;
    /* the grid covers every vertex with its radius and a travel corridor around it */
    margin = rmax + it->o.travel_corridor + 1.0;
    ext = fmax(bb.max.x - bb.min.x, bb.max.y - bb.min.y) + 2.0 * margin;
    it->grid_x0 = bb.min.x - margin;
    it->grid_y0 = bb.min.y - margin;
    it->grid_cell = ext / AMP_GCODE_GRID;
    /* pass 1: the whole job without formatting, for the figures of the header */
    reset_run(it, 1);
    {
        lb none = {NULL, 0};
        int r;
        while ((r = step(it, &none)) >= 0)
            if (r == 1)
                it->stats.lines++;
    }
    it->est = it->stats;
    reset_run(it, 2);
    it->magic = GC_MAGIC;
    return AMP_OK;
}

/* ---------------------------------------------------------------- moves */

static void set_last(amp_gcode_iter *it, int kind, amp_vec3 to, double e, double feed, double r, double len)
{
    it->last.kind = kind;
    it->last.path = it->path;
    it->last.seg = it->seg;
    it->last.to = to;
    it->last.e = e;
    it->last.feed = feed;
    it->last.r = r;
    it->last.length = len;
}

/* Emit " F" when the modal feed changes; returns the feed in mm/s as the firmware will use it. */
static double put_feed(amp_gcode_iter *it, lb *l, long long f_units)
{
    if (f_units != it->f_units) {
        lb_fixed(l, 'F', f_units, 1);
        it->f_units = f_units;
    }
    return (double)f_units / 600.0;
}

static void put_e(amp_gcode_iter *it, lb *l)
{
    long long u = llround(it->e_exact * 1e5);
    lb_fixed(l, 'E', it->o.relative_e ? u - it->e_units : u, 5);
    it->e_units = u;
}

/* Retract (sign -1) or unretract (+1) by exactly the printed retraction length. */
static void move_e(amp_gcode_iter *it, lb *l, int sign)
{
    long long ru = llround(it->o.retract_length * 1e5);
    double feed, v = fmin(it->o.retract_speed, it->o.max_feed_e);
    lb_str(l, "G1");
    it->e_exact = (double)(it->e_units + sign * ru) * 1e-5;
    put_e(it, l);
    feed = put_feed(it, l, llround(it->o.retract_speed * 600.0));
    it->retracted = sign < 0;
    if (sign < 0)
        it->stats.retractions++;
    plan_single(it, it->o.retract_length, v);
    set_last(it, MOVE_E, it->pos, (double)(sign * ru) * 1e-5, feed, 0.0, 0.0);
}

static void move_travel(amp_gcode_iter *it, lb *l, amp_vec3 to, int xy, int z, double v)
{
    /* have_pos: 0 = unknown (after homing), 1 = only z known, 2 = known */
    double len = it->have_pos == 2 ? amp_v3_dist(it->pos, to) : 0.0, feed;
    lb_str(l, "G0");
    if (xy) {
        lb_num(l, 'X', to.x, 3);
        lb_num(l, 'Y', to.y, 3);
    }
    if (z)
        lb_num(l, 'Z', to.z, 3);
    feed = put_feed(it, l, llround(v * 600.0));
    it->stats.travel_length += len;
    plan_single(it, len, fmin(feed, xy ? it->o.max_feed_xy : it->o.max_feed_z));
    if (z && to.z > it->stats.max_travel_z)
        it->stats.max_travel_z = to.z;
    it->pos = to;
    it->have_pos = it->have_pos == 2 || xy ? 2 : 1;
    set_last(it, MOVE_TRAVEL, to, 0.0, feed, 0.0, len);
}

/* One extrusion segment k -> k+1 of the current path (SPEC §5). */
static void move_print(amp_gcode_iter *it, lb *l, size_t k)
{
    const amp_pvert *v = amp_pathset_path_verts(it->ps, it->path);
    amp_vec3 a = v[k].p, b = v[k + 1].p, d = amp_v3_sub(b, a);
    double len = amp_v3_len(d), r = 0.5 * (v[k].r + v[k + 1].r), area = GC_PI * r * r;
    /* E = flow * (pi r^2 L) / (pi (d/2)^2) */
    double de = it->o.flow * area * len / it->fil_area, feed, top;
    long long fu = llround(it->o.print_feed * 600.0);
    if (area * it->o.print_feed > it->o.max_volumetric_flow) {
        /* volumetric cap: lower the feed, rounded down so that the printed F respects the cap */
        fu = (long long)floor(it->o.max_volumetric_flow / area * 600.0);
        if (fu < 1)
            fu = 1;
        it->stats.lowered_feed_segments++;
    }
    lb_str(l, "G1");
    lb_num(l, 'X', b.x, 3);
    lb_num(l, 'Y', b.y, 3);
    lb_num(l, 'Z', b.z, 3);
    it->e_exact += de;
    put_e(it, l);
    feed = put_feed(it, l, fu);
    it->stats.segments++;
    it->stats.print_length += len;
    it->stats.filament_length += de;
    it->stats.filament_volume += de * it->fil_area;
    plan_print(it, d, len, feed, de);
    /* material top: the tube of radius r around the segment */
    top = fmax(a.z, b.z) + fmax(v[k].r, v[k + 1].r);
    grid_walk(it, a, b, fmax(v[k].r, v[k + 1].r), top, 0);
    it->pos = b;
    it->printed_any = 1;
    set_last(it, MOVE_PRINT, b, de, feed, r, len);
}

/* ---------------------------------------------------------------- sequences */

static const char *flavor_name(int f) { return f == AMP_FLAVOR_KLIPPER ? "klipper" : "marlin"; }

/*
 * A minimal formatter for comment lines, so that the library needs no
 * floating-point printf (newlib-nano leaves it out): %s string, %u unsigned
 * long, %z unsigned long in two digits, %fN double with N decimals (trailing
 * zeros dropped).
 */
static void lb_fmt(lb *l, const char *fmt, ...)
{
    va_list ap;
    char one[2] = {0, 0};
    if (!l->b)
        return;
    va_start(ap, fmt);
    for (; *fmt; fmt++) {
        if (*fmt != '%' || !fmt[1]) {
            one[0] = *fmt;
            lb_str(l, one);
            continue;
        }
        switch (*++fmt) {
        case 's': lb_str(l, va_arg(ap, const char *)); break;
        case 'u': lb_fixed(l, 0, (long long)va_arg(ap, unsigned long), 0); break;
        case 'z': {
            unsigned long v = va_arg(ap, unsigned long);
            one[0] = (char)('0' + (int)(v / 10 % 10));
            lb_str(l, one);
            one[0] = (char)('0' + (int)(v % 10));
            lb_str(l, one);
            break;
        }
        case 'f': {
            int dec = fmt[1] >= '0' && fmt[1] <= '9' ? *++fmt - '0' : 1;
            double v = va_arg(ap, double), sc = 1.0;
            int k;
            for (k = 0; k < dec; k++)
                sc *= 10.0;
            lb_fixed(l, 0, units_of(v, sc), dec);
            break;
        }
        default: one[0] = *fmt; lb_str(l, one); break;
        }
    }
    va_end(ap);
}

/* Header comment line @p k; returns 0 past the last one. */
static int header_line(amp_gcode_iter *it, lb *l, size_t k)
{
    const amp_gcode_stats *e = &it->est;
    unsigned long t = e->time > 0.0 ? (unsigned long)(e->time + 0.5) : 0;
    switch (k) {
    case 0: lb_str(l, "; generated by ampath " AMP_VERSION_STRING ": MDR-modulated extrusion (SPEC 5)"); return 1;
    case 1:
        lb_fmt(l, "; flavor %s, %s E, filament %f3 mm, flow %f4", flavor_name(it->o.flavor),
               it->o.relative_e ? "relative" : "absolute", it->o.filament_diameter, it->o.flow);
        return 1;
    case 2:
        lb_fmt(l, "; estimated print time %u s (%u:%z:%z), moves only", t, t / 3600, t / 60 % 60, t % 60);
        return 1;
    case 3: lb_fmt(l, "; filament used %f1 mm (%f1 mm3)", e->filament_length, e->filament_volume); return 1;
    case 4:
        lb_fmt(l, "; paths %u printed, %u skipped, %u segments, %f1 mm printed", (unsigned long)e->paths,
               (unsigned long)e->paths_skipped, (unsigned long)e->segments, e->print_length);
        return 1;
    case 5:
        lb_fmt(l, "; travels %u (%f1 mm), retractions %u, lowered feeds %u", (unsigned long)e->travels,
               e->travel_length, (unsigned long)e->retractions, (unsigned long)e->lowered_feed_segments);
        return 1;
    case 6: lb_fmt(l, "; lines %u", (unsigned long)e->lines); return 1;
    default: return 0;
    }
}

/* Built-in start sequence line @p k (lines skipped for an unheated bed or hot end); -1 past the end. */
static int builtin_start(amp_gcode_iter *it, lb *l, size_t k)
{
    const amp_gcode_opts *o = &it->o;
    switch (k) {
    case 0: if (o->bed_temp <= 0.0) return 0; lb_str(l, "M140"); lb_num(l, 'S', o->bed_temp, 1); lb_str(l, " ; bed"); return 1;
    case 1: if (o->hotend_temp <= 0.0) return 0; lb_str(l, "M104"); lb_num(l, 'S', o->hotend_temp, 1); lb_str(l, " ; hot end"); return 1;
    case 2: lb_str(l, "G28 ; home all axes"); return 1;
    case 3: if (o->bed_temp <= 0.0) return 0; lb_str(l, "M190"); lb_num(l, 'S', o->bed_temp, 1); lb_str(l, " ; wait for the bed"); return 1;
    case 4: if (o->hotend_temp <= 0.0) return 0; lb_str(l, "M109"); lb_num(l, 'S', o->hotend_temp, 1); lb_str(l, " ; wait for the hot end"); return 1;
    default: return -1;
    }
}

static int builtin_end(lb *l, size_t k)
{
    static const char *const lines[] = {"M104 S0 ; hot end off", "M140 S0 ; bed off", "M107 ; fan off",
                                        "M84 ; motors off"};
    if (k >= sizeof lines / sizeof lines[0])
        return -1;
    lb_str(l, lines[k]);
    return 1;
}

/* Next non-blank line of a caller sequence; 0 at its end. */
static int text_line(amp_gcode_iter *it, lb *l)
{
    const char *s = it->text;
    while (s && *s) {
        const char *e = strchr(s, '\n');
        size_t n = e ? (size_t)(e - s) : strlen(s), i;
        const char *next = e ? e + 1 : s + n;
        while (n > 0 && (s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == '\t'))
            n--;
        if (n > 0) {
            if (l->b) {
                for (i = 0; i < n && i < AMP_GCODE_LINE_MAX; i++)
                    l->b[i] = s[i];
                l->b[i] = '\0';
                l->n = i;
            }
            it->text = next;
            return 1;
        }
        s = next;
    }
    it->text = s;
    return 0;
}

static int setup_line(amp_gcode_iter *it, lb *l, size_t k)
{
    switch (k) {
    case 0: lb_str(l, "G21 ; millimetres"); return 1;
    case 1: lb_str(l, "G90 ; absolute XYZ"); return 1;
    case 2: lb_str(l, it->o.relative_e ? "M83 ; relative E" : "M82 ; absolute E"); return 1;
    case 3: lb_str(l, "G92 E0"); return 1;
    case 4:
        lb_str(l, it->o.flavor == AMP_FLAVOR_KLIPPER ? "SET_VELOCITY_LIMIT ACCEL=" : "M204 S");
        lb_fixed(l, 0, units_of(it->o.accel, 10.0), 1);
        lb_str(l, " ; acceleration");
        return 1;
    default: return -1;
    }
}

/* ---------------------------------------------------------------- the state machine */

/* Advance by one unit: 1 = a line was produced, 0 = state changed without a line, -1 = done. */
static int step(amp_gcode_iter *it, lb *l)
{
    const amp_pathset *ps = it->ps;
    int r;
    switch (it->phase) {
    case PH_HEADER:
        if (it->pass == 1 ? it->sub < 7 : header_line(it, l, it->sub)) {
            it->sub++;
            return 1;
        }
        it->phase = PH_START;
        it->sub = 0;
        it->text = it->o.start_gcode;
        return 0;
    case PH_START:
        r = it->o.start_gcode ? text_line(it, l) : builtin_start(it, l, it->sub++);
        if (r > 0)
            return 1;
        if (r == 0 && !it->o.start_gcode)
            return 0; /* a skipped built-in line */
        it->phase = PH_SETUP;
        it->sub = 0;
        return 0;
    case PH_SETUP:
        if (setup_line(it, l, it->sub) > 0) {
            it->sub++;
            return 1;
        }
        it->phase = PH_PATHS;
        it->sub = PS_COMMENT;
        it->path = 0;
        return 0;
    case PH_PATHS: {
        const amp_path *p;
        const amp_pvert *v;
        if (it->path >= ps->npaths) {
            it->phase = PH_TEARDOWN;
            it->sub = 0;
            return 0;
        }
        p = &ps->paths[it->path];
        v = amp_pathset_path_verts(ps, it->path);
        switch (it->sub) {
        case PS_COMMENT:
            it->seg = next_segment(ps, it->path, 0);
            if (l->b) {
                lb_fmt(l, "; path %u %s %u vertices%s", (unsigned long)it->path,
                         p->role == AMP_ROLE_SUPPORT ? "support" : "object", (unsigned long)p->n,
                         it->seg + 1 < p->n ? "" : " (skipped: no segment of non-zero length)");
            }
            if (it->seg + 1 >= p->n) {
                it->stats.paths_skipped++;
                it->path++;
                return 1;
            }
            it->stats.paths++;
            it->travel_to = v[0].p;
            if (it->have_pos == 2 && amp_v3_dist(it->pos, it->travel_to) <= GC_MIN_SEG) {
                it->sub = PS_SEGS; /* the path starts where the last one ended: no travel */
                return 1;
            }
            /* no gouging: rise above the printed material near the travel line */
            it->travel_z = fmax(it->travel_to.z, it->have_pos ? it->pos.z : it->travel_to.z);
            if (it->printed_any)
                it->travel_z = fmax(it->travel_z, grid_walk(it, it->pos, it->travel_to, it->o.travel_corridor, 0.0, 1));
            it->travel_z += it->o.z_hop;
            it->stats.travels++;
            it->sub = PS_RETRACT;
            return 1;
        case PS_RETRACT:
            it->sub = PS_LIFT;
            if (it->printed_any && it->o.retract_length > 0.0 && !it->retracted) {
                move_e(it, l, -1);
                return 1;
            }
            return 0;
        case PS_LIFT:
            it->sub = PS_XY;
            if (!it->have_pos || it->travel_z > it->pos.z) {
                amp_vec3 to = it->have_pos ? it->pos : it->travel_to;
                to.z = it->travel_z;
                move_travel(it, l, to, 0, 1, fmin(it->o.travel_feed, it->o.max_feed_z));
                return 1;
            }
            return 0;
        case PS_XY:
            it->sub = PS_DESCEND;
            if (it->have_pos < 2 || it->pos.x != it->travel_to.x || it->pos.y != it->travel_to.y) {
                move_travel(it, l, amp_v3(it->travel_to.x, it->travel_to.y, it->pos.z), 1, 0, it->o.travel_feed);
                return 1;
            }
            return 0;
        case PS_DESCEND:
            it->sub = PS_UNRETRACT;
            if (it->pos.z != it->travel_to.z) {
                move_travel(it, l, it->travel_to, 0, 1, fmin(it->o.travel_feed, it->o.max_feed_z));
                return 1;
            }
            return 0;
        case PS_UNRETRACT:
            it->sub = PS_SEGS;
            if (it->retracted) {
                move_e(it, l, +1);
                return 1;
            }
            return 0;
        default: /* PS_SEGS: it->seg is the next segment of non-zero length */
            if (it->seg + 1 < p->n) {
                move_print(it, l, it->seg);
                it->seg = next_segment(ps, it->path, it->seg + 1);
                return 1;
            }
            it->path++;
            it->sub = PS_COMMENT;
            return 0;
        }
    }
    case PH_TEARDOWN:
        if (it->sub == 0) {
            it->sub = 1;
            if (it->o.retract_length > 0.0 && !it->retracted) {
                move_e(it, l, -1);
                return 1;
            }
            return 0;
        }
        if (it->sub == 1) {
            it->sub = 2;
            if (it->o.end_lift > 0.0) {
                amp_vec3 to = it->pos;
                to.z += it->o.end_lift;
                move_travel(it, l, to, 0, 1, fmin(it->o.travel_feed, it->o.max_feed_z));
                return 1;
            }
            return 0;
        }
        plan_flush(it);
        it->phase = PH_END;
        it->sub = 0;
        it->text = it->o.end_gcode;
        return 0;
    case PH_END:
        r = it->o.end_gcode ? text_line(it, l) : builtin_end(l, it->sub++);
        if (r > 0)
            return 1;
        plan_flush(it);
        it->phase = PH_DONE;
        return 0;
    default:
        return -1;
    }
}

int amp_gcode_iter_next(amp_gcode_iter *it, char *line, size_t cap, amp_error *err)
{
    lb l;
    int r;
    if (!it || !line)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: NULL iterator or line buffer");
    if (cap < AMP_GCODE_LINE_CAP)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: line buffer of %lu bytes, at least %d needed",
                        (unsigned long)cap, AMP_GCODE_LINE_CAP);
    if (it->magic != GC_MAGIC)
        return amp_fail(err, AMP_ERR_STATE, 0, "gcode: iterator not initialised (or init failed)");
    l.b = line;
    l.n = 0;
    line[0] = '\0';
    for (;;) {
        it->last.kind = MOVE_NONE;
        r = step(it, &l);
        if (r == 1) {
            it->stats.lines++;
            return 1;
        }
        if (r < 0)
            return 0;
        l.n = 0;
        line[0] = '\0';
    }
}

amp_status amp_gcode_write(const amp_pathset *ps, const amp_gcode_opts *o, amp_sink_fn sink, void *user,
                           amp_gcode_stats *stats, amp_error *err)
{
    amp_gcode_iter it;
    char line[AMP_GCODE_LINE_CAP + 1];
    amp_status st;
    int r;
    if (!sink)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: NULL sink");
    st = amp_gcode_iter_init(&it, ps, o, err);
    if (st != AMP_OK)
        return st;
    while ((r = amp_gcode_iter_next(&it, line, AMP_GCODE_LINE_CAP, err)) == 1) {
        size_t n = strlen(line);
        line[n] = '\n';
        st = sink(user, line, n + 1);
        if (st != AMP_OK)
            return amp_fail(err, st, 0, "gcode: writing line %lu failed: %s", (unsigned long)it.stats.lines,
                            amp_strerror(st));
    }
    if (r < 0)
        return (amp_status)r;
    if (stats)
        *stats = it.stats;
    return AMP_OK;
}
