/* G-code writer (docs/interfaces.md §5): extrusion, volumetric cap, travels, flavors, limits, and a G-code reader. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fixture_geom.h"
#include "runtool.h"
#include "testutil.h"


/* ------------------------------------------------------------------ a small G-code reader */

typedef struct seg {
    amp_vec3 a, b;
    int arc;        /* 2 or 3: G2/G3 around centre (cx, cy) */
    double cx, cy;
    double e, feed; /* feed mm/s */
    size_t before;  /* travels: number of extrusion segments printed before */
    int support;    /* extrusions: of a support path (planar layers: the vertex z is the bead's top) */
    int fan;        /* extrusions: the part-cooling fan was on */
} seg;

typedef struct gsim {
    int klipper;      /* accept only Klipper's documented commands, and its extrusion limit (below) */
    double klipper_xs; /* Klipper's max_extrude_cross_section, mm^2 (gsim_init: 0.64, its default for 0.4 mm) */
    double filament;  /* mm (1.75) */
    int arcs;         /* accept G2/G3 (firmware with arc support) */
    int xy_known;
    int rel_e, have_e_mode, g90, homed, heated, line_no, last_path, in_support, fan;
    amp_box3 box;     /* every position a move went to */
    double first_e_z; /* z of the first extrusion */
    size_t fan_on_line, fan_off_line, first_ext_line, last_ext_line, hot_change_line;
    amp_vec3 pos;
    double e, f;
    seg *segs;
    size_t nsegs, cap;
    seg *travels; /* XY travel moves (z constant) */
    size_t ntrav, captrav;
    size_t g0_lines, e_only, klipper_cmds;
    double last_abs_e;
    char why[200];
} gsim;

static void gsim_init(gsim *s)
{
    memset(s, 0, sizeof *s);
    s->last_path = -1;
    s->f = -1;
    s->box = amp_box3_empty();
    s->first_e_z = NAN;
    s->klipper_xs = 4.0 * 0.4 * 0.4;
    s->filament = 1.75;
}

static void gsim_free(gsim *s)
{
    free(s->segs);
    free(s->travels);
}

static void push_seg(seg **v, size_t *n, size_t *cap, seg x)
{
    if (*n == *cap) {
        *cap = *cap ? 2 * *cap : 256;
        *v = realloc(*v, *cap * sizeof **v);
    }
    (*v)[(*n)++] = x;
}

#define BAD(...)                                                                                                   \
    do {                                                                                                           \
        snprintf(s->why, sizeof s->why, __VA_ARGS__);                                                              \
        return 0;                                                                                                  \
    } while (0)

/* Parse one line; 0 with s->why on anything a printer would not accept or that breaks the job's structure. */
static int gsim_line(gsim *s, const char *line)
{
    char buf[256], *tok, *save = NULL;
    const char *c = strchr(line, ';');
    size_t n = c ? (size_t)(c - line) : strlen(line);
    int g = -1, m = -1, have[26] = {0};
    double val[26];
    s->line_no++;
    if (strlen(line) > AMP_GCODE_LINE_MAX)
        BAD("line %d longer than %d", s->line_no, AMP_GCODE_LINE_MAX);
    if (c && strncmp(c, "; path ", 7) == 0) {
        int p = atoi(c + 7);
        if (p <= s->last_path)
            BAD("line %d: path %d after path %d", s->line_no, p, s->last_path);
        s->last_path = p;
        s->in_support = strstr(c, " support") != NULL;
    }
    if (n >= sizeof buf)
        BAD("line %d too long", s->line_no);
    memcpy(buf, line, n);
    buf[n] = '\0';
    tok = strtok_r(buf, " \t", &save);
    if (!tok)
        return 1; /* comment or blank */
    if (strcmp(tok, "SET_VELOCITY_LIMIT") == 0) {
        tok = strtok_r(NULL, " \t", &save);
        if (!tok || strncmp(tok, "ACCEL=", 6) != 0 || !(atof(tok + 6) > 0))
            BAD("line %d: bad SET_VELOCITY_LIMIT", s->line_no);
        s->klipper_cmds++;
        return 1;
    }
    if (tok[0] == 'G')
        g = atoi(tok + 1);
    else if (tok[0] == 'M')
        m = atoi(tok + 1);
    else
        BAD("line %d: unknown command '%s'", s->line_no, tok);
    {
        /* Marlin's and Klipper's command sets as far as ampath uses them (Klipper: docs/G-Codes.md; no G21) */
        static const int gs[] = {0, 1, 21, 28, 90, 92}, ms[] = {82, 83, 84, 104, 106, 107, 109, 140, 190, 204};
        size_t i;
        int ok = 0;
        for (i = 0; i < sizeof gs / sizeof gs[0]; i++)
            ok |= g == gs[i] && !(s->klipper && g == 21);
        ok |= s->arcs && (g == 2 || g == 3);
        for (i = 0; i < sizeof ms / sizeof ms[0]; i++)
            ok |= m == ms[i];
        if (!ok || strlen(tok) > 4)
            BAD("line %d: unknown command '%s'%s", s->line_no, tok, s->klipper ? " for Klipper" : "");
    }
    while ((tok = strtok_r(NULL, " \t", &save)) != NULL) {
        char *end;
        int k = tok[0] - 'A';
        double d;
        if (k < 0 || k >= 26 || have[k])
            BAD("line %d: bad or repeated word '%s'", s->line_no, tok);
        d = strtod(tok + 1, &end);
        if (end == tok + 1 || *end || !isfinite(d) || strchr(tok, 'e') || strchr(tok, 'n'))
            BAD("line %d: bad number in '%s'", s->line_no, tok);
        have[k] = 1;
        val[k] = d;
    }
    if (g == 90)
        s->g90 = 1;
    if (g == 28)
        s->homed = 1;
    if (m == 82 || m == 83) {
        s->rel_e = m == 83;
        s->have_e_mode = 1;
    }
    if (m == 109)
        s->heated = 1;
    if (m == 104 && s->heated && !s->hot_change_line)
        s->hot_change_line = (size_t)s->line_no;
    if (m == 106 && !s->fan_on_line)
        s->fan_on_line = (size_t)s->line_no;
    if (m == 106 || m == 107)
        s->fan = m == 106 && !(have['S' - 'A'] && val['S' - 'A'] == 0);
    if (m == 107 && s->nsegs > 0)
        s->fan_off_line = (size_t)s->line_no;
    if (g == 92 && have['E' - 'A'])
        s->e = val['E' - 'A'];
    if (have['F' - 'A']) {
        if (!(val['F' - 'A'] > 0))
            BAD("line %d: feed not positive", s->line_no);
        s->f = val['F' - 'A'] / 60.0;
    }
    if (g == 2 || g == 3) {
        /* a helical arc: the centre must be as far from the start as from the end */
        double cx = s->pos.x + (have['I' - 'A'] ? val['I' - 'A'] : 0), cy = s->pos.y + (have['J' - 'A'] ? val['J' - 'A'] : 0);
        amp_vec3 to = s->pos;
        seg x;
        if (have['X' - 'A'])
            to.x = val['X' - 'A'];
        if (have['Y' - 'A'])
            to.y = val['Y' - 'A'];
        if (have['Z' - 'A'])
            to.z = val['Z' - 'A'];
        if (!have['E' - 'A'] || fabs(hypot(s->pos.x - cx, s->pos.y - cy) - hypot(to.x - cx, to.y - cy)) > 2e-3)
            BAD("line %d: arc without E or with an inconsistent centre", s->line_no);
        x.a = s->pos;
        x.b = to;
        x.arc = g;
        x.cx = cx;
        x.cy = cy;
        x.e = s->rel_e ? val['E' - 'A'] : val['E' - 'A'] - s->e;
        s->e = s->rel_e ? s->e + x.e : val['E' - 'A'];
        x.feed = s->f;
        x.before = 0;
        x.support = s->in_support;
        x.fan = s->fan;
        push_seg(&s->segs, &s->nsegs, &s->cap, x);
        s->pos = to;
        return 1;
    }
    if (g == 0 || g == 1) {
        amp_vec3 to = s->pos;
        double de = 0.0;
        if (!s->g90 || !s->have_e_mode || !s->homed)
            BAD("line %d: move before G28, G90 and the E mode", s->line_no);
        if (s->f <= 0)
            BAD("line %d: move without a feed", s->line_no);
        if (have['X' - 'A'])
            to.x = val['X' - 'A'];
        if (have['Y' - 'A'])
            to.y = val['Y' - 'A'];
        if (have['Z' - 'A'])
            to.z = val['Z' - 'A'];
        if (have['E' - 'A']) {
            if (g == 0)
                BAD("line %d: extrusion in G0", s->line_no);
            de = s->rel_e ? val['E' - 'A'] : val['E' - 'A'] - s->e;
            s->e = s->rel_e ? s->e + de : val['E' - 'A'];
        }
        if (g == 1 && have['E' - 'A'] && (have['X' - 'A'] || have['Y' - 'A'] || have['Z' - 'A'])) {
            seg x;
            memset(&x, 0, sizeof x);
            if (!s->heated)
                BAD("line %d: extrusion before the hot end is heated", s->line_no);
            if (s->klipper && s->klipper_xs > 0 && (to.x != s->pos.x || to.y != s->pos.y)) {
                /* klippy/kinematics/extruder.py check_move: E per mm of XYZ over max_extrude_cross_section /
                 * filament area is refused unless the extrusion is tiny (E <= nozzle x that ratio) */
                double fa = AMP_PI * 0.25 * s->filament * s->filament, ratio = s->klipper_xs / fa;
                double l3 = amp_v3_dist(s->pos, to);
                if (de > 0 && de / l3 > ratio && de > sqrt(s->klipper_xs / 4.0) * ratio)
                    BAD("line %d: Klipper: move exceeds maximum extrusion (%.3f mm^2 vs %.3f mm^2)", s->line_no,
                        de / l3 * fa, s->klipper_xs);
            }
            x.a = s->pos;
            x.b = to;
            x.e = de;
            x.feed = s->f;
            x.before = 0;
            x.support = s->in_support;
            x.fan = s->fan;
            if (de > 0 && isnan(s->first_e_z))
                s->first_e_z = to.z;
            if (de > 0) {
                if (!s->first_ext_line)
                    s->first_ext_line = (size_t)s->line_no;
                s->last_ext_line = (size_t)s->line_no;
            }
            push_seg(&s->segs, &s->nsegs, &s->cap, x);
        } else if (g == 1 && have['E' - 'A']) {
            s->e_only++;
        } else if (g == 0) {
            s->g0_lines++;
            if (have['X' - 'A'] || have['Y' - 'A']) {
                seg x;
                memset(&x, 0, sizeof x);
                x.a = s->pos;
                x.b = to;
                x.e = 0;
                x.feed = s->f;
                x.before = s->nsegs;
                x.support = 0;
                push_seg(&s->travels, &s->ntrav, &s->captrav, x);
            }
        } else {
            BAD("line %d: G1 without E", s->line_no);
        }
        s->pos = to;
        s->xy_known |= have['X' - 'A'] && have['Y' - 'A'];
        if (s->homed && s->xy_known) /* before the first XY move after homing only z is known */
            s->box = amp_box3_add(s->box, to);
    }
    return 1;
}

/* Parse a whole text; returns 1 when every line is accepted. */
/* Filament of the extruding moves read (defined with the tests that use it most). */
static double gsim_filament(const gsim *s);

static int gsim_run(gsim *s, const char *text)
{
    char line[512];
    const char *p = text;
    while (*p) {
        const char *e = strchr(p, '\n');
        size_t n = e ? (size_t)(e - p) : strlen(p);
        if (n >= sizeof line) {
            snprintf(s->why, sizeof s->why, "line %d: overlong", s->line_no + 1);
            return 0;
        }
        memcpy(line, p, n);
        line[n] = '\0';
        if (!gsim_line(s, line))
            return 0;
        p = e ? e + 1 : p + n;
    }
    return 1;
}

/* ------------------------------------------------------------------ independent no-gouge checker */

static double seg2d_point(double px, double py, amp_vec3 a, amp_vec3 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy, t = 0;
    if (l2 > 0)
        t = ((px - a.x) * dx + (py - a.y) * dy) / l2;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(px - (a.x + t * dx), py - (a.y + t * dy));
}

static double seg2d_dist(amp_vec3 a, amp_vec3 b, amp_vec3 c, amp_vec3 d)
{
    double m = seg2d_point(a.x, a.y, c, d);
    double cross1 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    double cross2 = (b.x - a.x) * (d.y - a.y) - (b.y - a.y) * (d.x - a.x);
    double cross3 = (d.x - c.x) * (a.y - c.y) - (d.y - c.y) * (a.x - c.x);
    double cross4 = (d.x - c.x) * (b.y - c.y) - (d.y - c.y) * (b.x - c.x);
    if (((cross1 < 0) != (cross2 < 0)) && ((cross3 < 0) != (cross4 < 0)))
        return 0.0;
    m = fmin(m, seg2d_point(b.x, b.y, c, d));
    m = fmin(m, seg2d_point(c.x, c.y, a, b));
    return fmin(m, seg2d_point(d.x, d.y, a, b));
}

/*
 * The highest z of segment g over its part within @p R of (px, py) in XY
 * (-inf when none): z is linear along g, so it is at one end of that interval.
 */
static double seg_z_near(const seg *g, double px, double py, double R)
{
    double dx = g->b.x - g->a.x, dy = g->b.y - g->a.y, ax = g->a.x - px, ay = g->a.y - py;
    double A = dx * dx + dy * dy, B = ax * dx + ay * dy, C = ax * ax + ay * ay - R * R, disc, u0, u1;
    if (A <= 0.0)
        return C <= 0.0 ? fmax(g->a.z, g->b.z) : -HUGE_VAL;
    disc = B * B - A * C;
    if (disc < 0.0)
        return -HUGE_VAL;
    u0 = fmax(0.0, (-B - sqrt(disc)) / A);
    u1 = fmin(1.0, (-B + sqrt(disc)) / A);
    if (u0 > u1)
        return -HUGE_VAL;
    return fmax(g->a.z + u0 * (g->b.z - g->a.z), g->a.z + u1 * (g->b.z - g->a.z));
}

/* The radius of an extrusion segment, read back from its E: r = sqrt(E (d/2)^2 / (flow L)). */
static double seg_radius(const seg *g, double fil_d, double flow)
{
    double len = amp_v3_dist(g->a, g->b);
    return len > 0 && g->e > 0 ? sqrt(g->e * 0.25 * fil_d * fil_d / (flow * len)) : 0.0;
}

/*
 * The writer's material grid cell (lib/gcode.c: the job's larger xy extent plus a margin of the
 * largest radius + corridor + 1 mm on each side, AMP_GCODE_GRID cells), from the extrusions.
 */
static double writer_cell(const gsim *s, double fil_d, double flow, double corridor)
{
    double x0 = HUGE_VAL, x1 = -HUGE_VAL, y0 = HUGE_VAL, y1 = -HUGE_VAL, rmax = 0;
    size_t k;
    for (k = 0; k < s->nsegs; k++) {
        const seg *g = &s->segs[k];
        x0 = fmin(x0, fmin(g->a.x, g->b.x));
        x1 = fmax(x1, fmax(g->a.x, g->b.x));
        y0 = fmin(y0, fmin(g->a.y, g->b.y));
        y1 = fmax(y1, fmax(g->a.y, g->b.y));
        rmax = fmax(rmax, seg_radius(g, fil_d, flow));
    }
    return (fmax(x1 - x0, y1 - y0) + 2.0 * (rmax + corridor + 1.0)) / AMP_GCODE_GRID;
}

/*
 * Is travel point @p p in an end zone of its travel: within the bead radius + two writer cells
 * (@p cell; 0: no zones) of the end of the extrusion before it or of the start of the next one?
 * There the nozzle is in the bead it leaves or the place of the one it starts (docs/gcode.md).
 * The writer takes the end vertex's radius, E gives the segment's mean one: 0.02 mm covers the
 * difference (radii within the 0.01 mm radius tolerance of the simplification).
 * the head-cone checker count_cone_gouges covers those points, the hop-clearance checker the rest.
 */
static int in_end_zone(const gsim *s, const seg *tr, amp_vec3 p, double cell, double fil_d, double flow)
{
    if (!(cell > 0))
        return 0;
    if (tr->before > 0) {
        const seg *g = &s->segs[tr->before - 1];
        if (hypot(p.x - g->b.x, p.y - g->b.y) < seg_radius(g, fil_d, flow) + 2.0 * cell + 0.02)
            return 1;
    }
    if (tr->before < s->nsegs) {
        const seg *g = &s->segs[tr->before];
        if (hypot(p.x - g->a.x, p.y - g->a.y) < seg_radius(g, fil_d, flow) + 2.0 * cell + 0.02)
            return 1;
    }
    return 0;
}

/*
 * Every XY travel must pass at least @p hop above the top of each earlier
 * extrusion wherever that extrusion's centre line comes within its radius +
 * @p reach of the travel (the top: the centre line's highest z over its part
 * within that distance of the travel point, + r; a support path's planar bead
 * tops out at its vertex z, lib/support.c). The radius comes from the
 * G-code itself (seg_radius). Travel points are sampled every 0.05 mm; those
 * in an end zone (in_end_zone, @p cell 0: none) are left to the cone checker.
 * Returns the number of violations (0 = no gouging); *near
 * counts the travel/segment pairs that were close enough to matter.
 */
static int count_gouges(const gsim *s, double fil_d, double flow, double reach, double hop, double cell, size_t *near)
{
    size_t t, k;
    int bad = 0;
    *near = 0;
    for (t = 0; t < s->ntrav; t++) {
        const seg *tr = &s->travels[t];
        for (k = 0; k < tr->before; k++) {
            const seg *g = &s->segs[k];
            double len = amp_v3_dist(g->a, g->b), r;
            int q, nq;
            if (len <= 0 || g->e <= 0)
                continue;
            r = sqrt(g->e * 0.25 * fil_d * fil_d / (flow * len));
            if (seg2d_dist(tr->a, tr->b, g->a, g->b) > r + reach)
                continue;
            (*near)++;
            nq = 1 + (int)(hypot(tr->b.x - tr->a.x, tr->b.y - tr->a.y) / 0.05);
            for (q = 0; q <= nq; q++) {
                amp_vec3 pt = amp_v3_lerp(tr->a, tr->b, (double)q / nq);
                double top;
                if (in_end_zone(s, tr, pt, cell, fil_d, flow))
                    continue;
                top = seg_z_near(g, pt.x, pt.y, r + reach) + (g->support ? 0.0 : r);
                /* 3-decimal rounding of the G-code, and r read back from E over a simplified chord (the
                 * chord is shorter than the segments it replaces: r comes out a few micrometres larger) */
                if (pt.z < top + hop - 5e-3) {
                    bad++;
                    break;
                }
            }
        }
    }
    return bad;
}

/* ------------------------------------------------------------------ helpers */

static char *gen(const amp_pathset *ps, const amp_gcode_opts *o, amp_gcode_stats *st)
{
    amp_buf b;
    amp_error err;
    amp_status s;
    amp_buf_init(&b, NULL);
    amp_error_clear(&err);
    s = amp_gcode_write(ps, o, amp_buf_sink, &b, st, &err);
    ck_assert_msg(s == AMP_OK, "gcode write: %s", err.msg);
    return b.data;
}

/*
 * The writer as a plain converter: the job's own coordinates on a huge bed,
 * every input segment written, every travel retracted, no fan, one feed.
 * The tests of extrusion, travels and the estimate use it; placement,
 * simplification and the first layer have their own tests.
 */
static void raw_opts(amp_gcode_opts *o, int flavor)
{
    amp_gcode_opts_default(o, flavor);
    o->place = AMP_PLACE_ORIGIN;
    o->bed_min_x = o->bed_min_y = -99999;
    o->bed_max_x = o->bed_max_y = 99999;
    o->max_height = 99999;
    o->chord_tol = o->min_segment = 0;
    o->retract_min_travel = 0;
    o->fan_speed = 0;
    o->first_layer_feed = o->print_feed;
    o->direct_hop = 0; /* every travel retracts and lifts (the direct hops have their own tests) */
    o->max_cross_section = 0; /* no firmware's extrusion limit (Klipper's has its own test) */
}

static void demo_like(amp_pathset *ps)
{
    amp_pathset_init(ps, NULL);
    fx_rings(ps, 0, 0, 4, 3, 48, 0.25);
    fx_helix(ps, 12, 120);
}

/* Expected E of segment k of path i: flow * (pi r^2 L) / (pi (d/2)^2), r the mean of the end radii. */
static double formula_e(const amp_pathset *ps, size_t i, size_t k, const amp_gcode_opts *o)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    double r = 0.5 * (v[k].r + v[k + 1].r), L = amp_v3_dist(v[k].p, v[k + 1].p);
    return o->flow * (AMP_PI * r * r * L) / (AMP_PI * (o->filament_diameter / 2) * (o->filament_diameter / 2));
}

/* ------------------------------------------------------------------ tests */

START_TEST(e_per_segment_matches_formula_for_constant_and_varying_radius)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_iter it;
    amp_error err;
    char line[AMP_GCODE_LINE_CAP];
    size_t checked = 0, varying = 0, i, k, expect = 0;
    int r;
    demo_like(&ps);
    raw_opts(&o, AMP_FLAVOR_KLIPPER); /* relative E: the line's E is the segment's */
    o.filament_diameter = 2.85;
    o.flow = 0.93;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_OK);
    while ((r = amp_gcode_iter_next(&it, line, sizeof line, &err)) == 1) {
        if (it.last.kind == 1) {
            const amp_pvert *v = amp_pathset_path_verts(&ps, it.last.path);
            double want = formula_e(&ps, it.last.path, it.last.seg, &o);
            const char *e = strstr(line, " E");
            ck_assert_msg(fabs(it.last.e - want) <= 1e-9, "path %lu seg %lu: E %.12g, formula %.12g",
                          (unsigned long)it.last.path, (unsigned long)it.last.seg, it.last.e, want);
            ck_assert_ptr_nonnull(e);
            /* the printed value differs only by the 5-decimal rounding */
            ck_assert_msg(fabs(atof(e + 2) - want) <= 1.0001e-5, "'%s' vs %.9f", line, want);
            varying += v[it.last.seg].r != v[it.last.seg + 1].r;
            checked++;
        }
    }
    ck_assert_int_eq(r, 0);
    for (i = 0; i < ps.npaths; i++)
        for (k = 0; k + 1 < ps.paths[i].n; k++)
            expect += amp_v3_dist(amp_pathset_path_verts(&ps, i)[k].p, amp_pathset_path_verts(&ps, i)[k + 1].p) > 1e-9;
    ck_assert_uint_eq(checked, expect);
    ck_assert_uint_gt(varying, 1000);
    ck_assert_uint_gt(checked - varying, 500); /* the rings: constant radius */
    /* total filament = flow * deposited volume / filament area */
    ck_assert_near(it.stats.filament_length,
                   o.flow * amp_pathset_volume(&ps, -1) / (AMP_PI * 2.85 * 2.85 / 4), 1e-9 * it.stats.filament_length);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(volumetric_cap_lowers_feed_exactly_where_needed)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st;
    gsim s;
    char *text;
    size_t k, lowered = 0, kept = 0;
    const int n = 60;
    amp_pathset_init(&ps, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    /* radius ramps 0.2 -> 0.6 mm: the cap pi r^2 v <= 12 mm^3/s at 40 mm/s binds from r = 0.309 mm */
    for (k = 0; k <= (size_t)n; k++)
        amp_pathset_push(&ps, amp_v3(10 + 0.7 * k, 5 + 0.3 * sin(0.2 * k), 0.3), 0.2 + 0.4 * k / n, NULL);
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    o.print_feed = o.first_layer_feed = 40;
    text = gen(&ps, &o, &st);
    gsim_init(&s);
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    ck_assert_uint_eq(s.nsegs, (size_t)n);
    for (k = 0; k < s.nsegs; k++) {
        const amp_pvert *v = ps.verts;
        double r = 0.5 * (v[k].r + v[k + 1].r), area = AMP_PI * r * r;
        if (area * o.print_feed > o.max_volumetric_flow) {
            ck_assert_msg(area * s.segs[k].feed <= o.max_volumetric_flow * (1 + 1e-12), "segment %lu over the cap",
                          (unsigned long)k);
            /* lowered by no more than the 0.1 mm/min resolution of F */
            ck_assert_msg(area * (s.segs[k].feed + 0.1 / 60) > o.max_volumetric_flow, "segment %lu lowered too much",
                          (unsigned long)k);
            lowered++;
        } else {
            ck_assert_msg(fabs(s.segs[k].feed - o.print_feed) < 1e-9, "segment %lu: feed %g without need",
                          (unsigned long)k, s.segs[k].feed);
            kept++;
        }
    }
    ck_assert_uint_gt(lowered, 10);
    ck_assert_uint_gt(kept, 10);
    ck_assert_uint_eq(st.lowered_feed_segments, lowered);
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(travels_lift_above_printed_material)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st;
    gsim s;
    char *text;
    size_t near;
    int hop;
    demo_like(&ps);
    for (hop = 0; hop < 2; hop++) {
        raw_opts(&o, AMP_FLAVOR_MARLIN);
        o.z_hop = hop ? 0.4 : 0.0;
        text = gen(&ps, &o, &st);
        gsim_init(&s);
        ck_assert_msg(gsim_run(&s, text), "%s", s.why);
        ck_assert_uint_ge(s.ntrav, st.travels); /* a travel is a polyline of one or more XY moves */
        ck_assert_int_eq(count_gouges(&s, o.filament_diameter, o.flow, 1.0, o.z_hop, 0, &near), 0);
        ck_assert_uint_gt(near, 100); /* the check had material to look at */
        gsim_free(&s);
        free(text);
    }
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(gouge_checker_catches_a_travel_without_lift)
{
    amp_pathset ps;
    amp_gcode_opts o;
    gsim s;
    char *text, *p, *q;
    size_t near;
    amp_pathset_init(&ps, NULL);
    fx_rings(&ps, 0, 0, 2, 3, 48, 0.25);
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    o.retract_length = 0;
    text = gen(&ps, &o, NULL);
    /* the travel to path 1 without its lift: every G0 up to the first extrusion becomes one XY move at print height */
    p = strstr(text, "; path 1 ");
    ck_assert_ptr_nonnull(p);
    p = strchr(p, '\n') + 1;
    ck_assert(strncmp(p, "G0 Z", 4) == 0);
    q = strchr(p, '\n') + 1;
    memmove(p, q, strlen(q) + 1); /* lift removed */
    ck_assert(strncmp(p, "G0 X", 4) == 0);
    q = strstr(p, " Z");
    if (q && q < strchr(p, '\n'))
        memmove(q, strchr(q, '\n'), strlen(strchr(q, '\n')) + 1); /* the XY move stays at z 0.3 */
    gsim_init(&s);
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    ck_assert_int_gt(count_gouges(&s, o.filament_diameter, o.flow, 1.0, o.z_hop, 0, &near), 0);
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

/*
 * E is set back to 0 (G92 E0) at travels once it has reached 100 mm, so that the firmware's single-precision
 * position keeps the written resolution: on a job of over a metre of filament no E written exceeds 100 mm
 * plus one path's filament, each reset comes at 100 mm or more, and the moves' E (read through the resets)
 * and the filament are those of one long count.
 */
START_TEST(e_is_set_back_to_zero_at_travels_past_100_mm)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st;
    gsim s;
    char *text, *line, *save = NULL;
    double e = 0.0, emax = 0.0;
    size_t resets = 0;
    amp_pathset_init(&ps, NULL);
    fx_helix(&ps, 40, 400); /* strands of about 30 mm of filament each */
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    o.relative_e = 0;
    text = gen(&ps, &o, &st);
    ck_assert(st.filament_length > 1000.0);
    gsim_init(&s);
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    ck_assert_near(gsim_filament(&s), st.filament_length, 1e-3);
    for (line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        const char *ep = strstr(line, " E");
        if (strncmp(line, "G92 E0", 6) == 0) {
            ck_assert_msg(resets == 0 || e >= 100.0, "a reset at E %g", e);
            resets++;
            e = 0.0;
        } else if ((line[0] == 'G') && ep) {
            e = strtod(ep + 2, NULL);
            emax = e > emax ? e : emax;
        }
    }
    ck_assert_uint_ge(resets, (size_t)(st.filament_length / 150.0)); /* the set-up's own one and then some */
    ck_assert_msg(emax < 160.0, "E written up to %g mm", emax);
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(relative_and_absolute_e_agree)
{
    amp_pathset ps;
    amp_gcode_opts o;
    gsim a, r;
    char *ta, *tr;
    size_t k;
    demo_like(&ps);
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    o.relative_e = 0;
    ta = gen(&ps, &o, NULL);
    o.relative_e = 1;
    tr = gen(&ps, &o, NULL);
    ck_assert_ptr_nonnull(strstr(ta, "\nM82"));
    ck_assert_ptr_nonnull(strstr(tr, "\nM83"));
    gsim_init(&a);
    gsim_init(&r);
    ck_assert_msg(gsim_run(&a, ta), "%s", a.why);
    ck_assert_msg(gsim_run(&r, tr), "%s", r.why);
    ck_assert_uint_eq(a.nsegs, r.nsegs);
    ck_assert_uint_eq(a.e_only, r.e_only);
    for (k = 0; k < a.nsegs; k++) {
        /* same moves; E agrees to the last printed digit because both round the absolute value once */
        ck_assert_near(a.segs[k].e, r.segs[k].e, 1e-9);
        ck_assert_near(a.segs[k].b.x, r.segs[k].b.x, 0);
    }
    ck_assert_near(a.e, r.e, 1e-6);
    gsim_free(&a);
    gsim_free(&r);
    free(ta);
    free(tr);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(reader_parses_every_line_of_both_flavors)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st;
    int fl;
    demo_like(&ps);
    for (fl = 0; fl < 2; fl++) {
        gsim s;
        char *text;
        const char *p;
        size_t k = 0, i, j;
        amp_gcode_iter it;
        raw_opts(&o, fl ? AMP_FLAVOR_KLIPPER : AMP_FLAVOR_MARLIN);
        ck_assert_int_eq(o.relative_e, fl);
        text = gen(&ps, &o, &st);
        gsim_init(&s);
        s.klipper = fl; /* only the commands of that firmware */
        s.klipper_xs = o.max_cross_section; /* the plain converter's jobs are not bound to Klipper's default */
        ck_assert_msg(gsim_run(&s, text), "%s: %s", fl ? "klipper" : "marlin", s.why);
        ck_assert_int_eq(s.rel_e, fl);
        ck_assert_uint_eq((size_t)s.line_no, st.lines);
        ck_assert_uint_eq(s.nsegs, st.segments);
        ck_assert_uint_eq(s.klipper_cmds, (size_t)fl);
        ck_assert_int_eq(strstr(text, "\nM204 S1000") != NULL, !fl);
        ck_assert_int_eq(s.last_path, (int)ps.npaths - 1);
        for (p = text; *p; p = strchr(p, '\n') + 1)
            ck_assert_msg(*p != 'N', "line numbers are the sender's job");
        /* the extrusion moves visit the path vertices in order */
        for (i = 0; i < ps.npaths; i++)
            for (j = 1; j < ps.paths[i].n; j++, k++) {
                amp_vec3 v = amp_pathset_path_verts(&ps, i)[j].p;
                ck_assert_msg(amp_v3_dist(v, s.segs[k].b) < 1e-3, "path %lu vertex %lu", (unsigned long)i,
                              (unsigned long)j);
            }
        /* the header's figures (from init) are those of the job written */
        ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_OK);
        ck_assert_uint_eq(it.est.lines, st.lines);
        ck_assert_near(it.est.time, st.time, 1e-9);
        ck_assert_near(it.est.filament_length, st.filament_length, 1e-9);
        ck_assert_uint_eq(it.est.retractions, st.retractions);
        ck_assert_uint_eq(st.retractions, st.travels); /* one per travel except the first, plus the final one */
        gsim_free(&s);
        free(text);
    }
    amp_pathset_free(&ps);
}
END_TEST

static const char *const broken_gcode[] = {
    "G28\nG90\nM82\nG5 X1\n",               /* unknown command */
    "G28\nG90\nM82\nG1 Xnan Y0 E1 F100\n",  /* NaN */
    "G28\nG90\nG1 X1 Y0 E1 F100\n",         /* move before the E mode */
    "; path 3 object\n; path 2 object\n",   /* paths out of order */
    "G28\nG90\nM82\nG0 X1 X2 F100\n",       /* repeated word */
    "M109 S200\nG28\nG90\nM82\nG1 X1e3 E1 F100\n", /* exponent notation */
    "G28 ; the next line has 90 characters\n"
    "M84 ;....................................................................................\n",
};

START_TEST(reader_rejects_broken_gcode)
{
    gsim s;
    gsim_init(&s);
    ck_assert_msg(!gsim_run(&s, broken_gcode[_i]), "case %d accepted", _i);
    ck_assert(s.why[0] != '\0');
    gsim_free(&s);
}
END_TEST

START_TEST(time_estimate_follows_trapezoids_and_junction_limit)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_iter it;
    double a = 1000, v = 50, t, vj, s2;
    int k, n;
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    o.print_feed = o.first_layer_feed = v;
    o.max_volumetric_flow = 1000;
    o.accel = a;
    /* a straight 100 mm line split into n collinear segments: one trapezoid, whatever the look-ahead */
    for (n = 1; n <= 64; n *= 4) {
        amp_pathset_init(&ps, NULL);
        amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
        for (k = 0; k <= n; k++)
            amp_pathset_push(&ps, amp_v3(100.0 * k / n, 0, 0.2), 0.2, NULL);
        ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_OK);
        t = 2 * v / a + (100 - v * v / a) / v;
        ck_assert_near(it.est.print_time, t, 1e-9);
        amp_pathset_free(&ps);
    }
    /* a right angle: the junction deviation rule v^2 = a jd sin(t/2) / (1 - sin(t/2)), t = 90 degrees */
    amp_pathset_init(&ps, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 0.2), 0.2, NULL);
    amp_pathset_push(&ps, amp_v3(50, 0, 0.2), 0.2, NULL);
    amp_pathset_push(&ps, amp_v3(50, 50, 0.2), 0.2, NULL);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_OK);
    s2 = sqrt(0.5);
    vj = sqrt(a * o.junction_deviation * s2 / (1 - s2));
    /* each leg: accelerate from 0 (or vj) to v, cruise, decelerate to vj (or 0) */
    t = 2 * ((v / a) + (v - vj) / a + (50 - v * v / (2 * a) - (v * v - vj * vj) / (2 * a)) / v);
    ck_assert_near(it.est.print_time, t, 1e-9);
    ck_assert_near(amp_gcode_trapezoid_time(1.0, 0, 0, 50, 1000), 2 * sqrt(1.0 / 1000), 1e-12); /* triangle */
    amp_pathset_free(&ps);
}
END_TEST

/* Trapezoid time of a move of @p len at most @p v, from rest to rest, at acceleration @p a. */
static double rest_to_rest(double len, double v, double a)
{
    return len >= v * v / a ? 2.0 * v / a + (len - v * v / a) / v : 2.0 * sqrt(len / a);
}

/* Marlin lowers a move's acceleration until no axis exceeds its own (max_acceleration): a climb of 10 mm
 * accelerates at Z's 100 mm/s^2, not at the 1000 of the moves, and a 45-degree one at 100 sqrt(2); a
 * retraction at the retraction acceleration. Each against the closed form, and with the limits off. */
START_TEST(moves_accelerate_within_each_axis_limit)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_iter it;
    double l45 = 10.0 * sqrt(2.0);
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    o.print_feed = o.first_layer_feed = 30.0;
    o.max_volumetric_flow = 1000;
    ck_assert(o.accel == 1000.0 && o.max_accel_z == 100.0 && o.max_feed_z == 10.0);
    amp_pathset_init(&ps, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 0.2), 0.2, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 10.2), 0.2, NULL);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_OK);
    ck_assert_near(it.est.print_time, rest_to_rest(10.0, 10.0, 100.0), 1e-9); /* 1.1 s, not 1.015 */
    o.max_accel_z = 0.0; /* no limit: the move's own acceleration */
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_OK);
    ck_assert_near(it.est.print_time, rest_to_rest(10.0, 10.0, 1000.0), 1e-9);
    amp_pathset_free(&ps);
    /* 45 degrees in x-z: feed and acceleration both limited by z's share (1 / sqrt 2 of the move) */
    o.max_accel_z = 100.0;
    amp_pathset_init(&ps, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 0.2), 0.2, NULL);
    amp_pathset_push(&ps, amp_v3(10, 0, 10.2), 0.2, NULL);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_OK);
    ck_assert_near(it.est.print_time, rest_to_rest(l45, 10.0 * sqrt(2.0), 100.0 * sqrt(2.0)), 1e-9);
    /* two paths: one retraction, its undoing and the retraction at the end, each from rest to rest at the
     * retraction acceleration */
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(30, 0, 0.2), 0.2, NULL);
    amp_pathset_push(&ps, amp_v3(40, 0, 0.2), 0.2, NULL);
    o.retract_accel = 500.0;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_OK);
    {
        double with = it.est.travel_time;
        o.retract_accel = 3000.0;
        ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_OK);
        ck_assert_near(with - it.est.travel_time,
                       3.0 * (rest_to_rest(o.retract_length, o.retract_speed, 500.0) -
                              rest_to_rest(o.retract_length, o.retract_speed, 3000.0)),
                       1e-9);
    }
    amp_pathset_free(&ps);
    /* bad limits are refused */
    o.max_accel_z = -1.0;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_ERR_ARG);
}
END_TEST

/* Klipper refuses a move whose extrusion cross-section (E per mm of XYZ, times the filament's area) exceeds
 * its max_extrude_cross_section (4 x nozzle^2 = 0.64 mm^2 by default), and the job stops there: a field
 * covering's tubes of the covering radius (0.707 mm at spacing 1: 1.57 mm^2) did. The writer refuses such a job
 * for Klipper, naming the path; Marlin has no such check; a printer.cfg that allows more says so. The test's
 * reader applies Klipper's rule to what is written. */
static void set_radius(amp_pathset *ps, double r)
{
    size_t i;
    for (i = 0; i < ps->nverts; i++)
        ps->verts[i].r = r;
}

START_TEST(klipper_jobs_stay_within_its_extrusion_cross_section)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_iter it;
    amp_error err;
    char *text;
    gsim s;
    amp_pathset_init(&ps, NULL);
    fx_helix(&ps, 6, 60);
    amp_gcode_opts_default(&o, AMP_FLAVOR_KLIPPER);
    /* tubes of 0.45 mm: 0.636 mm^2, within; written and read back under Klipper's rule */
    set_radius(&ps, 0.45);
    text = gen(&ps, &o, NULL);
    gsim_init(&s);
    s.klipper = 1;
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    gsim_free(&s);
    free(text);
    /* 0.5 mm: 0.785 mm^2, refused with the path named */
    set_radius(&ps, 0.5);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_LIMIT);
    ck_assert_ptr_nonnull(strstr(err.msg, "path 0 extrudes 0.785 mm^2"));
    ck_assert_ptr_nonnull(strstr(err.msg, "max_extrude_cross_section"));
    o.max_cross_section = 0; /* written without the limit: the reader (Klipper's rule) stops where Klipper would */
    text = gen(&ps, &o, NULL);
    gsim_init(&s);
    s.klipper = 1;
    ck_assert(!gsim_run(&s, text));
    ck_assert_msg(strstr(s.why, "exceeds maximum extrusion (0.785 mm^2 vs 0.640 mm^2)") != NULL, "%s", s.why);
    gsim_free(&s);
    free(text);
    /* a printer.cfg with max_extrude_cross_section: 1 */
    o.max_cross_section = 1.0;
    text = gen(&ps, &o, NULL);
    gsim_init(&s);
    s.klipper = 1;
    s.klipper_xs = 1.0;
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

/* Klipper corners by its square_corner_velocity (5 mm/s by default): a right angle is taken at exactly that
 * speed whatever the acceleration (klippy/toolhead.py turns it into a junction deviation); Marlin's rule with
 * its 0.05 mm takes the same corner at 11 mm/s at 1000 mm/s^2. */
/* A start or end sequence with a move Klipper would stop at is refused up front, naming the line: the MK3S's
 * intro line (12.5 mm of filament over 40 mm: 0.75 mm^2 against 0.64) stopped a Klipper print before its first
 * layer; an unload of 60 mm beyond max_extrude_only_distance. Marlin takes both. Every built-in profile's own
 * sequences pass under either flavour (the MK3S's intro line is thinner under Klipper). */
START_TEST(klipper_refuses_a_start_or_end_sequence_it_would_stop_at)
{
    static const char intro[] = "G28\nG1 Z0.2 F720\nG1 X10 Y1 F3000\nM83\nG1 X70 Y1 E9 F1000\nG1 X110 Y1 E12.5 F1000\n";
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_iter it;
    amp_error err;
    size_t i;
    int f;
    amp_pathset_init(&ps, NULL);
    fx_helix(&ps, 6, 60);
    set_radius(&ps, 0.3);
    amp_gcode_opts_default(&o, AMP_FLAVOR_KLIPPER);
    o.start_gcode = intro;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_LIMIT);
    ck_assert_msg(strstr(err.msg, "start sequence's line 6") && strstr(err.msg, "0.752 mm^2"), "%s", err.msg);
    o.flavor = AMP_FLAVOR_MARLIN;
    free(gen(&ps, &o, NULL));
    o.flavor = AMP_FLAVOR_KLIPPER;
    o.start_gcode = NULL;
    o.end_gcode = "G91\nG1 E-60 F3000\n";
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_LIMIT);
    ck_assert_msg(strstr(err.msg, "end sequence's line 2") && strstr(err.msg, "max_extrude_only_distance"), "%s",
                  err.msg);
    for (i = 0; i < amp_printer_builtin_count(); i++)
        for (f = 0; f < 2; f++) {
            amp_printer p;
            ck_assert_int_eq(amp_printer_builtin(&p, amp_printer_builtin_name(i), &err), AMP_OK);
            p.flavor = f ? AMP_FLAVOR_KLIPPER : AMP_FLAVOR_MARLIN;
            ck_assert_msg(amp_printer_gcode_opts(&p, &o, &err) == AMP_OK, "%s: %s", p.name, err.msg);
            ck_assert_msg(amp_gcode_iter_init(&it, &ps, &o, &err) == AMP_OK, "%s %d: %s", p.name, f, err.msg);
        }
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(klipper_takes_a_right_angle_at_its_square_corner_velocity)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_iter it;
    double a, v = 50, vj, t, s2 = sqrt(0.5);
    amp_pathset_init(&ps, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 0.2), 0.2, NULL);
    amp_pathset_push(&ps, amp_v3(50, 0, 0.2), 0.2, NULL);
    amp_pathset_push(&ps, amp_v3(50, 50, 0.2), 0.2, NULL);
    for (a = 1000; a <= 3000; a += 2000) {
        raw_opts(&o, AMP_FLAVOR_KLIPPER);
        o.print_feed = o.first_layer_feed = v;
        o.max_volumetric_flow = 1000;
        o.accel = a;
        o.junction_deviation = amp_gcode_junction_default(AMP_FLAVOR_KLIPPER, a);
        ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, NULL), AMP_OK);
        vj = sqrt(a * o.junction_deviation * s2 / (1 - s2));
        ck_assert_double_eq_tol(vj, 5.0, 1e-12);
        t = 2 * ((v / a) + (v - vj) / a + (50 - v * v / (2 * a) - (v * v - vj * vj) / (2 * a)) / v);
        ck_assert_double_eq_tol(it.est.print_time, t, 1e-9);
    }
    amp_gcode_opts_default(&o, AMP_FLAVOR_KLIPPER);
    ck_assert_double_eq_tol(o.junction_deviation, 25.0 * (sqrt(2.0) - 1.0) / o.accel, 1e-15);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    ck_assert_double_eq(o.junction_deviation, 0.05);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(caller_start_and_end_sequences_replace_the_built_in_ones)
{
    amp_pathset ps;
    amp_gcode_opts o;
    char *text;
    gsim s;
    amp_pathset_init(&ps, NULL);
    fx_rings(&ps, 0, 0, 1, 1, 12, 0.3);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    o.start_gcode = "G28\r\n\nM109 S215 ; mine\n";
    o.end_gcode = "M84 ; my end";
    text = gen(&ps, &o, NULL);
    ck_assert_ptr_null(strstr(text, "M140"));
    ck_assert_ptr_nonnull(strstr(text, "\nM109 S215 ; mine\n"));
    ck_assert_ptr_nonnull(strstr(text, "\nM84 ; my end\n"));
    ck_assert_ptr_null(strstr(text, "M104 S0"));
    ck_assert_ptr_null(strstr(text, "\r"));
    gsim_init(&s);
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    gsim_free(&s);
    /* a caller's start without a bed temperature gets M190 first (as PrusaSlicer does); it has M109 */
    ck_assert(strstr(text, "\nM190 S60") < strstr(text, "\nG28"));
    ck_assert_ptr_null(strstr(text, "M104 S215"));
    free(text);
    /* and one without either gets both: M190, M104 before; M109 after it */
    o.start_gcode = "G28 ; only homing";
    text = gen(&ps, &o, NULL);
    ck_assert(strstr(text, "\nM190 S60") < strstr(text, "\nM104 S215"));
    ck_assert(strstr(text, "\nM104 S215") < strstr(text, "\nG28 ; only homing"));
    ck_assert(strstr(text, "\nG28 ; only homing") < strstr(text, "\nM109 S215"));
    free(text);
    /* built-in: first-layer temperatures and homing before anything moves */
    text = gen(&ps, NULL, NULL);
    ck_assert_ptr_nonnull(strstr(text, "\nM140 S60"));
    ck_assert_ptr_nonnull(strstr(text, "\nM109 S215"));
    ck_assert(strstr(text, "\nG28") < strstr(text, "\nG0 "));
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(lines_stay_within_the_length_limit_at_extreme_coordinates)
{
    amp_pathset ps;
    amp_gcode_iter it;
    amp_gcode_opts o;
    amp_error err;
    char line[AMP_GCODE_LINE_CAP];
    size_t longest = 0;
    int r, k;
    amp_pathset_init(&ps, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    for (k = 0; k < 50; k++)
        amp_pathset_push(&ps, amp_v3(-99998.123456 + 0.1 * k, -99997.987654, 99950.5 + 0.01 * k), 0.9, NULL);
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    o.end_lift = 5;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_OK);
    while ((r = amp_gcode_iter_next(&it, line, sizeof line, &err)) == 1)
        if (strlen(line) > longest)
            longest = strlen(line);
    ck_assert_int_eq(r, 0);
    ck_assert_int_eq(amp_gcode_iter_next(&it, line, sizeof line, &err), 0); /* stays at the end */
    ck_assert_uint_le(longest, AMP_GCODE_LINE_MAX);
    ck_assert_uint_gt(longest, 40);
    /* one step further is refused rather than written as an overlong line */
    ps.verts[3].p.x = -100001;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_RANGE);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(bad_input_gives_clear_errors)
{
    amp_pathset ps, empty;
    amp_gcode_opts o;
    amp_gcode_iter it;
    amp_error err;
    char line[AMP_GCODE_LINE_CAP];
    amp_buf b;
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&empty, NULL);
    amp_buf_init(&b, NULL);
    fx_rings(&ps, 0, 0, 1, 1, 12, 0.3);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);

    ck_assert_int_eq(amp_gcode_iter_init(&it, NULL, &o, &err), AMP_ERR_ARG);
    ck_assert_ptr_nonnull(strstr(err.msg, "NULL"));
    ck_assert_int_eq(amp_gcode_iter_init(NULL, &ps, &o, &err), AMP_ERR_ARG);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &empty, &o, &err), AMP_ERR_ARG);
    ck_assert_ptr_nonnull(strstr(err.msg, "empty"));
    /* paths that are single points or repeat one vertex have nothing to print */
    amp_pathset_begin(&empty, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&empty, amp_v3(1, 2, 3), 0.5, NULL);
    amp_pathset_push(&empty, amp_v3(1, 2, 3), 0.5, NULL);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &empty, &o, &err), AMP_ERR_ARG);
    ck_assert_ptr_nonnull(strstr(err.msg, "empty"));
    ck_assert_int_eq(amp_gcode_write(&empty, &o, amp_buf_sink, &b, NULL, &err), AMP_ERR_ARG);
    ck_assert_uint_eq(b.len, 0);

    o.filament_diameter = 0;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_ARG);
    ck_assert_ptr_nonnull(strstr(err.msg, "filament diameter"));
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    o.print_feed = NAN;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_ARG);
    ck_assert_ptr_nonnull(strstr(err.msg, "print feed"));
    amp_gcode_opts_default(&o, 7);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_ARG);
    ck_assert_ptr_nonnull(strstr(err.msg, "flavor"));
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    o.start_gcode = "G28\nM117 this message is far too long for a printer's command buffer once the sender adds N and *\n";
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_LIMIT);
    ck_assert_int_eq(err.line, 2);
    ck_assert_ptr_nonnull(strstr(err.msg, "start"));

    /* a failed init leaves an iterator that refuses to run */
    ck_assert_int_eq(amp_gcode_iter_next(&it, line, sizeof line, &err), AMP_ERR_STATE);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_OK);
    ck_assert_int_eq(amp_gcode_iter_next(&it, line, 40, &err), AMP_ERR_ARG);
    ck_assert_int_eq(amp_gcode_iter_next(&it, NULL, sizeof line, &err), AMP_ERR_ARG);
    ck_assert_int_eq(amp_gcode_write(&ps, &o, NULL, NULL, NULL, &err), AMP_ERR_ARG);
    /* a negative radius smuggled past the path API */
    ps.verts[2].r = -1;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_ARG);
    ck_assert_ptr_nonnull(strstr(err.msg, "vertex 2"));
    amp_buf_free(&b);
    amp_pathset_free(&ps);
    amp_pathset_free(&empty);
}
END_TEST

/* A sink that fails after n calls: the writer stops and passes the status back. */
static amp_status failing_sink(void *user, const char *data, size_t len)
{
    int *n = user;
    (void)data;
    (void)len;
    return (*n)-- > 0 ? AMP_OK : AMP_ERR_IO;
}

START_TEST(sink_failure_stops_the_writer)
{
    amp_pathset ps;
    amp_error err;
    int n = 20;
    amp_pathset_init(&ps, NULL);
    fx_rings(&ps, 0, 0, 1, 2, 12, 0.3);
    ck_assert_int_eq(amp_gcode_write(&ps, NULL, failing_sink, &n, NULL, &err), AMP_ERR_IO);
    ck_assert_ptr_nonnull(strstr(err.msg, "line 21"));
    amp_pathset_free(&ps);
}
END_TEST

/* Rewinding replays the job without running it again: the bridge reads a job twice (check, then send) and the
 * tool writes the iterator it initialised for the figures; both must get the lines amp_gcode_write gives. */
START_TEST(a_rewound_iterator_writes_the_same_job_again)
{
    static amp_gcode_iter it;
    amp_pathset ps, empty;
    amp_gcode_stats st, st2;
    amp_buf b;
    amp_error err;
    char line[AMP_GCODE_LINE_CAP], *once;
    int k;
    demo_like(&ps);
    once = gen(&ps, NULL, &st);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, NULL, &err), AMP_OK);
    for (k = 0; k < 500; k++) /* part of the job read, as a bridge's check that stops early */
        ck_assert_int_eq(amp_gcode_iter_next(&it, line, sizeof line, &err), 1);
    ck_assert_int_eq(amp_gcode_iter_rewind(&it, &err), AMP_OK);
    amp_buf_init(&b, NULL);
    ck_assert_int_eq(amp_gcode_iter_write(&it, amp_buf_sink, &b, &st2, &err), AMP_OK);
    ck_assert_ptr_nonnull(b.data);
    ck_assert_msg(strcmp(once, b.data) == 0, "the rewound job differs from a fresh one");
    ck_assert_uint_eq(st2.lines, st.lines);
    ck_assert_uint_eq(it.est.lines, st.lines); /* the header's figures are the job's */
    ck_assert_double_eq(st2.time, st.time);
    ck_assert_int_eq(amp_gcode_iter_write(&it, amp_buf_sink, &b, NULL, &err), AMP_OK); /* at the end: nothing */
    ck_assert_uint_eq(strlen(b.data), strlen(once));
    /* an iterator init refused cannot be rewound; NULL is an argument error */
    amp_pathset_init(&empty, NULL);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &empty, NULL, &err), AMP_ERR_ARG);
    ck_assert_int_eq(amp_gcode_iter_rewind(&it, &err), AMP_ERR_STATE);
    ck_assert_int_eq(amp_gcode_iter_write(&it, amp_buf_sink, &b, NULL, &err), AMP_ERR_STATE);
    ck_assert_int_eq(amp_gcode_iter_rewind(NULL, &err), AMP_ERR_ARG);
    amp_buf_free(&b);
    free(once);
    amp_pathset_free(&empty);
    amp_pathset_free(&ps);
}
END_TEST

/* A caller that can put the header in front afterwards runs the job once (amp_gcode_iter_init_body): the
 * body and then the header are the job init writes, byte for byte, with the same figures; a move over
 * Klipper's cross-section, which init refuses up front, stops the body where it is reached. */
START_TEST(a_body_run_and_its_header_write_the_job_init_writes)
{
    static amp_gcode_iter it;
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st, st2;
    amp_buf head, body;
    amp_error err;
    char *once, line[AMP_GCODE_LINE_CAP];
    int r;
    demo_like(&ps);
    once = gen(&ps, NULL, &st);
    ck_assert_int_eq(amp_gcode_iter_init_body(&it, &ps, NULL, &err), AMP_OK);
    amp_buf_init(&head, NULL);
    amp_buf_init(&body, NULL);
    ck_assert_int_eq(amp_gcode_iter_header(&it, amp_buf_sink, &head, &err), AMP_ERR_STATE); /* not known yet */
    ck_assert_int_eq(amp_gcode_iter_write(&it, amp_buf_sink, &body, &st2, &err), AMP_OK);
    ck_assert_int_eq(amp_gcode_iter_header(&it, amp_buf_sink, &head, &err), AMP_OK);
    ck_assert_ptr_nonnull(head.data);
    ck_assert_uint_eq(strlen(head.data) + strlen(body.data), strlen(once));
    ck_assert_msg(strncmp(once, head.data, strlen(head.data)) == 0, "the header differs from init's");
    ck_assert_msg(strcmp(once + strlen(head.data), body.data) == 0, "the body differs from init's job");
    ck_assert_uint_eq(it.est.lines, st.lines);
    ck_assert_uint_eq(st2.lines, st.lines);
    ck_assert_double_eq(it.est.time, st.time);
    ck_assert_double_eq(it.est.filament_length, st.filament_length);
    ck_assert_uint_eq(it.est.input_segments, st.input_segments);
    amp_buf_free(&head);
    amp_buf_free(&body);
    /* fat tubes for Klipper: init refuses, the body run stops at the path, with the same message */
    amp_gcode_opts_default(&o, AMP_FLAVOR_KLIPPER);
    set_radius(&ps, 0.5);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_LIMIT);
    ck_assert_int_eq(amp_gcode_iter_init_body(&it, &ps, &o, &err), AMP_OK);
    while ((r = amp_gcode_iter_next(&it, line, sizeof line, &err)) == 1) /* nothing extruded before the stop */
        ck_assert_msg(!(strncmp(line, "G1 X", 4) == 0 && strstr(line, " E")), "extruded before the stop: %s", line);
    ck_assert_int_eq(r, AMP_ERR_LIMIT);
    ck_assert_ptr_nonnull(strstr(err.msg, "path 0 extrudes 0.785 mm^2"));
    ck_assert_int_eq(amp_gcode_iter_next(&it, line, sizeof line, &err), AMP_ERR_LIMIT); /* and stays stopped */
    free(once);
    amp_pathset_free(&ps);
}
END_TEST

/* Files named like the safe writer's temporaries of @p target (".NAME.XXXXXXXX.tmp") in its directory. */
static int temporaries_of(const char *target)
{
    const char *slash = strrchr(target, '/');
    char dir[256], prefix[256];
    struct dirent *e;
    DIR *d;
    int n = 0;
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - target) : 1, slash ? target : ".");
    snprintf(prefix, sizeof prefix, ".%s.", slash ? slash + 1 : target);
    d = opendir(dir);
    ck_assert_ptr_nonnull(d);
    while ((e = readdir(d)) != NULL)
        n += strncmp(e->d_name, prefix, strlen(prefix)) == 0;
    closedir(d);
    return n;
}

START_TEST(gcode_command_writes_file_and_reports_json)
{
    amp_pathset ps;
    const char *in = fx_tmp("cli.amp"), *out = fx_tmp("cli.gcode"), *start = fx_tmp("start.gcode");
    char args[2048], json[4096];
    FILE *f;
    gsim s;
    size_t n;
    char *text;
    int rc;
    amp_pathset_init(&ps, NULL);
    fx_rings(&ps, 0, 0, 2, 2, 24, 0.3);
    ck_assert_int_eq(amp_pathset_write_file(&ps, in, NULL, NULL), AMP_OK);
    f = fopen(start, "w");
    fputs("G28\nM109 S199\n", f);
    fclose(f);
    snprintf(args, sizeof args,
             "gcode %s --flavor klipper --feed 25 --first-layer-feed 25 --chord-tol 0 --min-segment 0 --start %s "
             "--json -o %s", in, start, out);
    rc = fx_run_tool(args, json, sizeof json);
    ck_assert_msg(rc != -2, "AMP_TOOL not set");
    ck_assert_int_eq(rc, 0);
    ck_assert_ptr_nonnull(strstr(json, "\"flavor\":\"klipper\""));
    ck_assert_ptr_nonnull(strstr(json, "\"relative_e\":true"));
    ck_assert_ptr_nonnull(strstr(json, "\"segments\":96"));
    ck_assert_ptr_nonnull(strstr(json, "\"time_s\":"));
    f = fopen(out, "rb");
    ck_assert_ptr_nonnull(f);
    text = calloc(1, 1 << 20);
    n = fread(text, 1, (1 << 20) - 1, f);
    fclose(f);
    ck_assert_uint_gt(n, 1000);
    ck_assert_ptr_nonnull(strstr(text, "\nM109 S199\n"));
    ck_assert_ptr_nonnull(strstr(text, " F1500"));
    gsim_init(&s);
    s.klipper = 1;
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    gsim_free(&s);
    free(text);
    /* bad usage and bad input: exit 2, no output written */
    remove(out);
    snprintf(args, sizeof args, "gcode %s --flavor reprap -o %s", in, out);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    snprintf(args, sizeof args, "gcode %s --filament 0 -o %s", in, out);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    snprintf(args, sizeof args, "gcode %s --start %s -o %s", in, fx_tmp("nope"), out);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    snprintf(args, sizeof args, "gcode %s -o %s", fx_tmp("nope.amp"), out);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    ck_assert_ptr_null(fopen(out, "rb"));
    /* refused halfway through the one run that writes a file (tubes over Klipper's cross-section): no file,
     * and neither the body's temporary nor the output's left beside it */
    amp_pathset_free(&ps);
    amp_pathset_init(&ps, NULL);
    fx_helix(&ps, 6, 60);
    set_radius(&ps, 0.5);
    ck_assert_int_eq(amp_pathset_write_file(&ps, in, NULL, NULL), AMP_OK);
    snprintf(args, sizeof args, "gcode %s --flavor klipper -o %s", in, out);
    ck_assert_int_eq(fx_run_tool(args, json, sizeof json), 2);
    ck_assert_ptr_null(fopen(out, "rb"));
    ck_assert_int_eq(temporaries_of(out), 0);
    remove(in);
    remove(start);
    amp_pathset_free(&ps);
}
END_TEST

static void run_in_bed(gsim *s, const char *text, const amp_gcode_opts *o);

/* "Any command that can run for more than a second shows progress on a terminal": `gcode` draws its bar on a
 * terminal's stderr while it writes a large job, and `check` one naming the check that runs, and neither
 * writes one into a pipe; check's result lines stay whole on stdout. */
START_TEST(gcode_and_check_draw_a_progress_bar_on_a_terminal_only)
{
    amp_pathset ps;
    const char *in = fx_tmp("bar.amp"), *out = fx_tmp("bar.gcode");
    char args[1024], args2[1024], *err = malloc(1 << 16);
    if (!getenv("AMP_TOOL"))
        return;
    ck_assert_ptr_nonnull(err);
    amp_pathset_init(&ps, NULL);
    fx_helix(&ps, 40, 2000); /* 80,000 segments, every one a line without simplification */
    ck_assert_int_eq(amp_pathset_write_file(&ps, in, NULL, NULL), AMP_OK);
    snprintf(args, sizeof args, "gcode %s --chord-tol 0 --min-segment 0 -o %s", in, out);
    ck_assert_int_eq(fx_run_tool_tty(args, err, 1 << 16), 0);
    ck_assert_msg(strstr(err, "gcode        [") && strstr(err, "%"), "no bar on the terminal: '%.300s'", err);
    ck_assert_int_eq(fx_run_tool_ex(args, NULL, 1, err, 1 << 16), 0);
    ck_assert_msg(!strstr(err, "gcode        ["), "a bar in a pipe: '%.300s'", err);
    snprintf(args2, sizeof args2, "check %s --no-support", in);
    fx_run_tool_tty(args2, err, 1 << 16);
    ck_assert_msg(strstr(err, "check gouge"), "no bar on the terminal: '%.300s'", err);
    fx_run_tool_ex(args2, NULL, 1, err, 1 << 16);
    ck_assert_msg(!strstr(err, "check gouge") && strstr(err, "\ngouge: ") && strstr(err, "\nstrokes: "),
                  "a bar in a pipe, or a result line broken: '%.300s'", err);
    remove(in);
    remove(out);
    free(err);
    amp_pathset_free(&ps);
}
END_TEST

/* The G-code of the demo pipeline (docs/interfaces.md §6, smaller eps) parses line by line in the reader. */
START_TEST(demo_pipeline_gcode_parses_in_the_reader)
{
    static const char *const steps[] = {
        "model helix -o %s-helix.spl",
        "model helix -o %s-helix.stl",
        "cover %s-helix.spl --eps 3 --dir u -o %s-c.amp",
        "order %s-c.amp -o %s-o.amp",
        "mdr %s-o.amp --nominal 0.5 -o %s-m.amp",
        "support %s-m.amp --mesh %s-helix.stl -o %s-h.amp",
        /* eps 3 leaves more than 1 mm of air between beads: not held (ampath check's support section), beside the point here */
        "check %s-h.amp --trivariate %s-helix.spl --no-support",
        "gcode %s-h.amp -o %s-h.gcode",
    };
    char dir[256], args[2048], *text = NULL;
    size_t i, len;
    gsim s;
    const char *d;
    snprintf(dir, sizeof dir, "%s", fx_tmp("demo"));
    d = dir;
    for (i = 0; i < sizeof steps / sizeof steps[0]; i++) {
        snprintf(args, sizeof args, steps[i], d, d, d);
        ck_assert_msg(fx_run_tool(args, NULL, 0) == 0, "ampath %s failed", args);
    }
    snprintf(args, sizeof args, "%s-h.gcode", d);
    ck_assert_int_eq(amp_read_file(args, NULL, 0, &text, &len, NULL), AMP_OK);
    ck_assert_uint_gt(len, 100000);
    {
        /* print-ready jobs: on the default printer's bed, the lowest bead resting on it (curved: at its radius) */
        amp_gcode_opts o;
        double lowest = HUGE_VAL, first = NAN;
        size_t k;
        amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
        run_in_bed(&s, text, &o);
        for (k = 0; k < s.nsegs; k++) {
            double sl = amp_v3_dist(s.segs[k].a, s.segs[k].b), bottom;
            if (!(sl > 1e-3 && s.segs[k].e > 0))
                continue;
            bottom = fmin(s.segs[k].a.z, s.segs[k].b.z) - sqrt(s.segs[k].e * 0.25 * 1.75 * 1.75 / sl);
            lowest = fmin(lowest, bottom);
            if (isnan(first))
                first = bottom;
        }
        ck_assert_double_eq_tol(lowest, 0, 0.02);
        /* the first bead printed (support, under the helix's first turn) lies on the bed, not in the air */
        ck_assert_double_eq_tol(first, 0, 0.02);
    }
    ck_assert_uint_gt(s.nsegs, 1000);
    gsim_free(&s);
    amp_free(NULL, text);
    {
        static const char *const files[] = {"helix.spl", "helix.stl", "c.amp", "o.amp", "m.amp", "h.amp", "h.gcode"};
        for (i = 0; i < sizeof files / sizeof files[0]; i++) {
            snprintf(args, sizeof args, "%s-%s", d, files[i]);
            remove(args);
        }
    }
}
END_TEST


/*
 * A direction-field covering of a mesh on the plate, with support under its arch: the field's lowest curves lie
 * half a spacing up (their beads' bottoms 0.5 mm above the plate), the support from the plate would rest on the
 * bed and the part's feet would be printed in the air. Both the part's lowest beads and the support's lie on
 * the bed.
 */
START_TEST(a_field_covering_with_support_rests_its_feet_on_the_bed)
{
    static const char *const steps[] = {
        "model twisted-bridge -o %s.stl",
        "field %s.stl --field box --spacing 2 -o %s-f.amp",
        "order %s-f.amp -o %s-o.amp",
        "mdr %s-o.amp --nominal 1 --mesh %s.stl -o %s-m.amp",
        "support %s-m.amp --mesh %s.stl -o %s-s.amp",
        "gcode %s-s.amp -o %s.gcode",
    };
    char dir[256], args[2048], *text = NULL;
    double low[2] = {HUGE_VAL, HUGE_VAL};
    size_t i, len;
    amp_gcode_opts o;
    gsim s;
    snprintf(dir, sizeof dir, "%s", fx_tmp("feet"));
    for (i = 0; i < sizeof steps / sizeof steps[0]; i++) {
        snprintf(args, sizeof args, steps[i], dir, dir, dir);
        ck_assert_msg(fx_run_tool(args, NULL, 0) == 0, "ampath %s failed", args);
    }
    snprintf(args, sizeof args, "%s.gcode", dir);
    ck_assert_int_eq(amp_read_file(args, NULL, 0, &text, &len, NULL), AMP_OK);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    run_in_bed(&s, text, &o);
    for (i = 0; i < s.nsegs; i++) {
        double sl = amp_v3_dist(s.segs[i].a, s.segs[i].b);
        if (sl > 1e-3 && s.segs[i].e > 0)
            low[s.segs[i].support != 0] = fmin(low[s.segs[i].support != 0], fmin(s.segs[i].a.z, s.segs[i].b.z) -
                                                                            sqrt(s.segs[i].e * 0.25 * 1.75 * 1.75 / sl));
    }
    ck_assert_msg(fabs(low[0]) < 0.02 && fabs(low[1]) < 0.02, "lowest part bead bottom %g, support %g", low[0], low[1]);
    gsim_free(&s);
    amp_free(NULL, text);
    for (i = 0; i < 6; i++) {
        static const char *const ext[] = {".stl", "-f.amp", "-o.amp", "-m.amp", "-s.amp", ".gcode"};
        snprintf(args, sizeof args, "%s%s", dir, ext[i]);
        remove(args);
    }
}
END_TEST

/* ------------------------------------------------------------------ print-ready jobs (docs/interfaces.md §5) */

/*
 * @p layers planar layers of height @p h filling the square [x0, x0+S] x [y0, y0+S]:
 * per layer one boustrophedon path of lines spacing 2r (bead width w = 2r), at z = z0 + (i+1) h.
 */
static void planar_square(amp_pathset *ps, double x0, double y0, double z0, double S, int layers, double h, double r)
{
    int i, k, K = (int)floor(S / (2 * r));
    for (i = 0; i < layers; i++) {
        double z = z0 + (i + 1) * h;
        amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
        amp_pathset_set_height(ps, h, NULL);
        for (k = 0; k < K; k++) {
            double y = y0 + r + 2 * r * k, xa = x0 + r, xb = x0 + S - r;
            amp_pathset_push(ps, amp_v3(k % 2 ? xb : xa, y, z), r, NULL);
            amp_pathset_push(ps, amp_v3(k % 2 ? xa : xb, y, z), r, NULL);
        }
    }
}

/* Parse @p text; assert it is accepted and every position lies in the bed box of @p o. */
static void run_in_bed(gsim *s, const char *text, const amp_gcode_opts *o)
{
    gsim_init(s);
    s->klipper = o->flavor == AMP_FLAVOR_KLIPPER;
    ck_assert_msg(gsim_run(s, text), "%s", s->why);
    ck_assert_msg(s->box.min.x >= o->bed_min_x && s->box.max.x <= o->bed_max_x && s->box.min.y >= o->bed_min_y &&
                      s->box.max.y <= o->bed_max_y && s->box.min.z >= 0 && s->box.max.z <= o->max_height,
                  "moves span %g..%g x %g..%g x %g..%g outside the bed", s->box.min.x, s->box.max.x, s->box.min.y,
                  s->box.max.y, s->box.min.z, s->box.max.z);
}

static double gsim_filament(const gsim *s)
{
    double e = 0;
    size_t k;
    for (k = 0; k < s->nsegs; k++)
        e += s->segs[k].e;
    return e;
}

/*
 * Printing moves write Z only where the height as written changes (modal, as slicers write it): on five planar
 * layers every extruding segment still lies at its layer's height (read back by the simulator), and no printing
 * line repeats the Z the head is already at.
 */
START_TEST(printing_moves_write_z_only_where_it_changes)
{
    amp_pathset ps;
    amp_gcode_opts o;
    gsim s;
    char *text, *line;
    double z = NAN;
    size_t i, without_z = 0;
    amp_pathset_init(&ps, NULL);
    planar_square(&ps, -10, -10, 0, 20, 5, 0.2, 0.225);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    text = gen(&ps, &o, NULL);
    run_in_bed(&s, text, &o);
    for (i = 0; i < s.nsegs; i++)
        if (s.segs[i].e > 0) {
            double lz = 0.2 * floor(s.segs[i].b.z / 0.2 + 0.5);
            ck_assert_double_eq_tol(s.segs[i].a.z, s.segs[i].b.z, 1e-9);
            ck_assert_double_eq_tol(s.segs[i].b.z, lz, 1e-9);
        }
    for (line = text; line && *line; line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
        const char *zw = strchr(line, 'Z'), *end = strchr(line, '\n'), *semi = strchr(line, ';');
        int has_z = zw && (!end || zw < end) && (!semi || zw < semi);
        if (has_z) {
            double nz = atof(zw + 1);
            if (strncmp(line, "G1 X", 4) == 0)
                ck_assert_msg(nz != z, "a printing line repeats Z%g", nz);
            z = nz;
        } else if (strncmp(line, "G1 X", 4) == 0) {
            without_z++;
        }
    }
    ck_assert_uint_gt(without_z, 100);
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(planar_beads_extrude_the_rounded_rectangle)
{
    amp_pathset ps;
    amp_gcode_opts o;
    gsim s;
    char *text;
    const double S = 20, h = 0.2, r = 0.225, fil = AMP_PI * 1.75 * 1.75 / 4;
    double part = S * S * 5 * h, vol, ext;
    size_t i;
    amp_pathset_init(&ps, NULL);
    planar_square(&ps, -10, -10, 0, S, 5, h, r);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    text = gen(&ps, &o, NULL);
    run_in_bed(&s, text, &o);
    vol = amp_pathset_volume(&ps, -1);
    ext = gsim_filament(&s) * fil;
    /* within 3 % of the beads' volume (here only the 5-decimal rounding of E) */
    ck_assert_msg(fabs(ext / vol - 1) < 0.03, "extruded %g mm3, beads %g mm3", ext, vol);
    /* and never more than 1.05 x the part; a slicer-like fill of a solid square is a little below it */
    ck_assert_msg(ext <= 1.05 * part && ext >= 0.85 * part, "extruded %g mm3 for a part of %g mm3", ext, part);
    gsim_free(&s);
    free(text);
    /* the same paths as round tubes of radius r (the volumetric paper's model) overfill by ~75 %: the check bites */
    for (i = 0; i < ps.npaths; i++)
        ps.paths[i].h = 0;
    text = gen(&ps, &o, NULL);
    run_in_bed(&s, text, &o);
    ck_assert_double_gt(gsim_filament(&s) * fil, 1.5 * part);
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(placement_centres_the_job_and_rests_it_on_the_bed)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st;
    gsim s;
    char *text;
    double lowest = HUGE_VAL;
    size_t k;
    /* planar: a job far off the bed, floating at z 7: the first layer comes down to its height, 0.2 mm */
    amp_pathset_init(&ps, NULL);
    planar_square(&ps, -300, 410, 7, 30, 4, 0.2, 0.25);
    amp_gcode_opts_default(&o, AMP_FLAVOR_KLIPPER);
    o.bed_max_x = 250; /* a Prusa-sized bed */
    o.bed_max_y = 210;
    text = gen(&ps, &o, &st);
    run_in_bed(&s, text, &o);
    ck_assert_double_eq_tol(s.first_e_z, 0.2, 1e-6);
    ck_assert_double_eq_tol(st.first_layer_z, 0.2, 1e-9);
    ck_assert_double_eq_tol(0.5 * (s.box.min.x + s.box.max.x), 125, 0.3); /* travels start at the bed centre too */
    ck_assert_double_eq_tol(0.5 * (st.bbox.min.x + st.bbox.max.x), 125, 1e-9);
    ck_assert_double_eq_tol(0.5 * (st.bbox.min.y + st.bbox.max.y), 105, 1e-9);
    ck_assert_ptr_nonnull(strstr(text, "; bounding box "));
    ck_assert_ptr_nonnull(strstr(text, "; placed on the bed, offset "));
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
    /* tubes: the lowest bead rests on the bed (z - r = 0), r read back from E and L */
    demo_like(&ps);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    text = gen(&ps, &o, &st);
    run_in_bed(&s, text, &o);
    for (k = 0; k < s.nsegs; k++) {
        double len = amp_v3_dist(s.segs[k].a, s.segs[k].b), r;
        if (len < 1e-6 || s.segs[k].e <= 0)
            continue;
        r = sqrt(s.segs[k].e * 0.25 * 1.75 * 1.75 / len);
        lowest = fmin(lowest, fmin(s.segs[k].a.z, s.segs[k].b.z) - r);
    }
    ck_assert_double_eq_tol(lowest, 0, 0.01);
    /* a checker that would not notice a move off the bed is no checker */
    {
        size_t n = strlen(text);
        char *bad = malloc(n + 32);
        memcpy(bad, text, n);
        strcpy(bad + n, "G0 X-5 Y10 F6000\n");
        gsim_free(&s);
        gsim_init(&s);
        ck_assert(gsim_run(&s, bad));
        ck_assert_double_lt(s.box.min.x, o.bed_min_x);
        free(bad);
    }
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(place_origin_keeps_coordinates_and_place_at_moves_the_centre)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st;
    amp_pathset_init(&ps, NULL);
    planar_square(&ps, 10, 20, 0, 30, 2, 0.2, 0.25);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    o.place = AMP_PLACE_ORIGIN;
    free(gen(&ps, &o, &st));
    ck_assert_double_eq_tol(st.bbox.min.x, 10.25, 1e-9);
    ck_assert_double_eq_tol(st.bbox.min.z, 0.2, 1e-9);
    o.place = AMP_PLACE_AT;
    o.place_x = 50;
    o.place_y = 60;
    free(gen(&ps, &o, &st));
    ck_assert_double_eq_tol(0.5 * (st.bbox.min.x + st.bbox.max.x), 50, 1e-9);
    ck_assert_double_eq_tol(0.5 * (st.bbox.min.y + st.bbox.max.y), 60, 1e-9);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(a_job_too_big_for_the_bed_is_refused_naming_axis_and_overflow)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_iter it;
    amp_error err;
    const char *in = fx_tmp("big.amp"), *out = fx_tmp("big.gcode");
    char args[1024], tmp[1024];
    FILE *f;
    amp_pathset_init(&ps, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(230, 0, 0.3), 0.3, NULL);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_RANGE);
    ck_assert_msg(strstr(err.msg, " X spans") && strstr(err.msg, "10.000 mm over") && strstr(err.msg, "generic"), "%s",
                  err.msg);
    /* it fits a bigger bed */
    o.bed_max_x = 250;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_OK);
    /* too tall */
    amp_pathset_push(&ps, amp_v3(0, 5, 260), 0.3, NULL);
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_RANGE);
    ck_assert_msg(strstr(err.msg, " Z spans"), "%s", err.msg);
    /* placed at a point too near the edge: Y over */
    ps.verts[2].p = amp_v3(0, 5, 0.3);
    o.place = AMP_PLACE_AT;
    o.place_x = 125;
    o.place_y = 218;
    ck_assert_int_eq(amp_gcode_iter_init(&it, &ps, &o, &err), AMP_ERR_RANGE);
    ck_assert_msg(strstr(err.msg, " Y spans"), "%s", err.msg);
    /* the command: exit 2, a one-line reason, no file (and no temporary) */
    ck_assert_int_eq(amp_pathset_write_file(&ps, in, NULL, NULL), AMP_OK);
    remove(out);
    snprintf(args, sizeof args, "gcode %s -o %s", in, out);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    ck_assert_ptr_null(fopen(out, "rb"));
    snprintf(tmp, sizeof tmp, "%s.tmp", out);
    ck_assert_ptr_null(fopen(tmp, "rb"));
    snprintf(args, sizeof args, "gcode %s --printer prusa-mk3s --place 125,208 -o %s", in, out);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    ck_assert_ptr_null(fopen(out, "rb"));
    snprintf(args, sizeof args, "gcode %s --printer voron-350 -o %s", in, out); /* fits a 350 mm bed */
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    f = fopen(out, "rb");
    ck_assert_ptr_nonnull(f);
    fclose(f);
    snprintf(args, sizeof args, "gcode %s --place 1,2,3 -o %s", in, out);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    remove(out);
    remove(in);
    amp_pathset_free(&ps);
}
END_TEST

/* Distance from p to the polyline of written extrusions s->segs[a..b). */
static double dist_to_written(const gsim *s, size_t a, size_t b, amp_vec3 p)
{
    double best = HUGE_VAL, t;
    size_t k;
    for (k = a; k < b; k++)
        best = fmin(best, sqrt(amp_v3_seg_dist2(p, s->segs[k].a, s->segs[k].b, &t)));
    return best;
}

START_TEST(simplified_paths_stay_within_tolerance_without_micro_segments)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st;
    gsim s;
    char *text;
    size_t k, n = 6000, shortest_at = 0;
    double shortest = HUGE_VAL, worst = 0, fil = AMP_PI * 1.75 * 1.75 / 4;
    amp_pathset_init(&ps, NULL);
    /* a 30 mm arc of radius 10 sampled every 5 um (below a motor step), radius 0.3 +- 0.05 slowly */
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    for (k = 0; k <= n; k++) {
        double a = 3.0 * k / n;
        amp_pathset_push(&ps, amp_v3(10 * cos(a), 10 * sin(a), 0.3 + 0.5 * a), 0.3 + 0.05 * sin(2 * a), NULL);
    }
    /* a corner 0.02004 mm after the start that the 3 decimals written round to 0.020: the firmware (and any
     * reader subtracting the decimals in floating point) sees 0.0199..., so the chord must grow past it */
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(20.00045, 5, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(20.02049, 5, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(20.02049, 9, 0.3), 0.3, NULL);
    /* a whole path of 15 um: written as one segment */
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(0.005, 0, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(0.015, 0, 0.3), 0.3, NULL);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    o.place = AMP_PLACE_ORIGIN;
    o.bed_min_x = o.bed_min_y = -50;
    text = gen(&ps, &o, &st);
    run_in_bed(&s, text, &o);
    ck_assert_uint_eq(st.input_segments, n + 4);
    ck_assert_uint_lt(st.segments * 20, st.input_segments); /* lines saved */
    ck_assert_uint_eq(s.nsegs, st.segments);
    for (k = 0; k + 1 < s.nsegs; k++) {
        double len = amp_v3_dist(s.segs[k].a, s.segs[k].b);
        if (len < shortest) {
            shortest = len;
            shortest_at = k;
        }
    }
    /* lengths as read back from the written decimals */
    ck_assert_msg(shortest >= 0.02, "segment %lu is %.6f mm long", (unsigned long)shortest_at, shortest);
    ck_assert_double_eq_tol(amp_v3_dist(s.segs[s.nsegs - 1].a, s.segs[s.nsegs - 1].b), 0.015, 1e-3);
    /* every input vertex lies within the chord tolerance of what was written (+ the 3-decimal rounding) */
    for (k = 0; k <= n; k++)
        worst = fmax(worst, dist_to_written(&s, 0, s.nsegs - 1, ps.verts[k].p));
    ck_assert_msg(worst <= o.chord_tol + 1e-3, "input vertex %g mm from the written path", worst);
    /* and the plastic is that of the input beads */
    ck_assert_double_eq_tol(gsim_filament(&s) * fil / amp_pathset_volume(&ps, -1), 1, 1e-3);
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

/* Line (1-based) of the first occurrence of @p what at a line start in @p text after line @p after; 0 if none. */
static size_t line_of(const char *text, const char *what, size_t after)
{
    size_t line = 1;
    const char *p = text;
    while (*p) {
        if (line > after && strncmp(p, what, strlen(what)) == 0)
            return line;
        p = strchr(p, '\n');
        if (!p)
            break;
        p++;
        line++;
    }
    return 0;
}

/* A volumetric job may print a tube on the bed after higher ones (Algorithm 2 orders by the head cone, not
 * by height; the demo helix has six such paths): the fan is off for every bead in the first layers, on for
 * every other one, whatever came before. */
START_TEST(fan_is_off_for_every_bead_in_the_first_layers_whatever_the_order)
{
    static const double zs[5] = {0.25, 2.0, 0.3, 3.0, 0.45};
    amp_pathset ps;
    amp_gcode_opts o;
    gsim s;
    char *text;
    size_t k, i, on = 0, off = 0;
    int layers;
    amp_pathset_init(&ps, NULL);
    for (i = 0; i < 5; i++) {
        ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
        for (k = 0; k < 4; k++)
            ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(10.0 * (double)i + 3.0 * (double)k, 5.0 * (double)(k % 2), zs[i]),
                                              0.25, NULL), AMP_OK);
    }
    for (layers = 1; layers <= 2; layers++) {
        amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
        o.fan_off_layers = layers;
        text = gen(&ps, &o, NULL);
        run_in_bed(&s, text, &o);
        for (k = 0; k < s.nsegs; k++) {
            /* the bead's bottom, placed: the lowest tube (z 0.25, r 0.25) rests on the bed */
            double bottom = fmin(s.segs[k].a.z, s.segs[k].b.z) - 0.25;
            int first = bottom < layers * o.first_layer_height - 1e-6;
            ck_assert_msg(s.segs[k].fan == !first, "fan_off_layers %d: a bead at bottom %g with the fan %s", layers,
                          bottom, s.segs[k].fan ? "on" : "off");
            on += s.segs[k].fan;
            off += !s.segs[k].fan;
        }
        ck_assert_uint_gt(s.fan_off_line, s.last_ext_line);
        gsim_free(&s);
        free(text);
    }
    ck_assert_uint_gt(on, 0);
    ck_assert_uint_gt(off, 0);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(first_layer_temperatures_and_fan_come_in_order)
{
    amp_pathset ps;
    amp_gcode_opts o;
    gsim s;
    char *text;
    size_t l2, k;
    int off;
    amp_pathset_init(&ps, NULL);
    planar_square(&ps, 0, 0, 0, 20, 4, 0.2, 0.25);
    for (off = 1; off <= 2; off++) {
        amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
        o.fan_off_layers = off;
        o.fan_speed = 0.5;
        o.first_layer_bed_temp = 65;
        text = gen(&ps, &o, NULL);
        run_in_bed(&s, text, &o);
        /* start: first-layer temperatures, homing, waiting, then the fan is off before anything is printed */
        ck_assert_uint_lt(line_of(text, "M140 S65", 0), line_of(text, "M104 S215", 0));
        ck_assert_uint_lt(line_of(text, "M104 S215", 0), line_of(text, "G28", 0));
        ck_assert_uint_lt(line_of(text, "G28", 0), line_of(text, "M190 S65", 0));
        ck_assert_uint_lt(line_of(text, "M109 S215", 0), line_of(text, "M107", 0));
        ck_assert_uint_lt(line_of(text, "M107", 0), s.first_ext_line);
        /* the first layer at first-layer speed, the others at print speed */
        for (k = 0; k < s.nsegs; k++)
            ck_assert_double_eq_tol(s.segs[k].feed, s.segs[k].b.z < 0.21 ? o.first_layer_feed : o.print_feed, 1e-9);
        /* after the first layer: the other temperatures (bed 60 now), without waiting */
        l2 = line_of(text, "; path 1 ", 0);
        ck_assert_uint_gt(line_of(text, "M104 S210", 0), l2);
        ck_assert_uint_gt(line_of(text, "M140 S60", 0), l2);
        ck_assert_uint_lt(line_of(text, "M140 S60", 0), line_of(text, "G1 X", l2));
        /* the fan (half speed: S128) at the start of layer off + 1, off after the last extrusion */
        ck_assert_uint_gt(s.fan_on_line, line_of(text, off == 1 ? "; path 1 " : "; path 2 ", 0));
        ck_assert_uint_lt(s.fan_on_line, line_of(text, off == 1 ? "; path 2 " : "; path 3 ", 0));
        ck_assert_uint_eq(s.fan_on_line, line_of(text, "M106 S128", 0));
        ck_assert_uint_gt(s.fan_off_line, s.last_ext_line);
        gsim_free(&s);
        free(text);
    }
    /* no fan: no fan commands at all */
    o.fan_speed = 0;
    text = gen(&ps, &o, NULL);
    ck_assert_ptr_null(strstr(text, "M106"));
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(travels_go_straight_over_nothing_and_over_material_only_where_it_is)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st;
    gsim s;
    char *text, *p;
    size_t near, k;
    int diagonal = 0;
    amp_pathset_init(&ps, NULL);
    /* two short planar beads 30 mm apart at z 0.3: the travel between them crosses nothing */
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_set_height(&ps, 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(5, 0, 0.3), 0.3, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_set_height(&ps, 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(35, 0, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(40, 0, 0.3), 0.3, NULL);
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    text = gen(&ps, &o, &st);
    p = strstr(text, "; path 1 ");
    ck_assert_ptr_nonnull(p);
    /* retract, lift by z-hop above the layer, one straight move, descend, unretract */
    ck_assert_msg(strncmp(strchr(p, '\n') + 1, "G1 E", 4) == 0, "%s", p);
    p = strchr(strchr(p, '\n') + 1, '\n') + 1;
    ck_assert(strncmp(p, "G0 Z0.7", 7) == 0);
    p = strchr(p, '\n') + 1;
    ck_assert(strncmp(p, "G0 X35 Y0", 9) == 0);
    p = strchr(p, '\n') + 1;
    ck_assert(strncmp(p, "G0 Z0.3", 7) == 0);
    free(text);
    /* a short hop (1 mm) is not retracted */
    ps.verts[2].p.x = ps.verts[1].p.x + 1;
    o.retract_min_travel = 2;
    free(gen(&ps, &o, &st));
    ck_assert_uint_eq(st.retractions, 1); /* only the final one */
    /* a 6 mm tower in the middle of the way: the travel climbs over it and comes down again, never lower */
    ps.verts[2].p.x = 35;
    amp_pathset_free(&ps);
    amp_pathset_init(&ps, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(5, 0, 0.3), 0.3, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    for (k = 0; k < 20; k++)
        amp_pathset_push(&ps, amp_v3(20 + (k % 2), 0, 0.3 * (k + 1)), 0.3, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(5, 1, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(0, 1, 0.3), 0.3, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(35, 0, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(40, 0, 0.3), 0.3, NULL);
    text = gen(&ps, &o, &st);
    gsim_init(&s);
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    ck_assert_int_eq(count_gouges(&s, o.filament_diameter, o.flow, 1.0, o.z_hop, 0, &near), 0);
    ck_assert_uint_gt(near, 5);
    ck_assert_double_ge(st.max_travel_z, 6.0 + 0.3 + 0.4 - 1e-9);
    for (k = 0; k < s.ntrav; k++)
        diagonal += s.travels[k].a.z != s.travels[k].b.z;
    ck_assert_int_ge(diagonal, 2); /* up and down the flanks, not lifted to the top over the whole way */
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(klipper_reader_rejects_marlin_only_commands)
{
    static const char *const marlin_only[] = {"G28\nG21\n", "G28\nM900 K0.05\n", "G28\nM569 S1 X\n"};
    size_t i;
    for (i = 0; i < sizeof marlin_only / sizeof marlin_only[0]; i++) {
        gsim s;
        gsim_init(&s);
        s.klipper = 1;
        ck_assert_msg(!gsim_run(&s, marlin_only[i]), "case %lu accepted", (unsigned long)i);
        gsim_free(&s);
    }
}
END_TEST


/* Value of a JSON number field (the tools print one object on one line). */
static double json_num(const char *json, const char *key)
{
    char pat[128];
    const char *p;
    snprintf(pat, sizeof pat, "\"%s\":", key);
    p = strstr(json, pat);
    ck_assert_msg(p != NULL, "no %s in %s", key, json);
    return atof(p + strlen(pat));
}

/*
 * Print-ready planar jobs: `slice --continuous` of each built-in mesh, then `gcode`: every coordinate on the
 * generic bed, the first extrusion at the first-layer height, plastic within 3 % of the beads and at most
 * 1.05 x (part + support). Where a path carries no bead height, the test gives
 * its paths h = the layer height, which is what that change writes.
 */
START_TEST(continuous_slices_of_the_builtin_meshes_print_on_the_bed)
{
    static const char *const meshes[] = {"helix", "twisted-bridge", "crocodile-like"};
    char base[256], args[2048], json[8192], *text = NULL;
    size_t len, i, k;
    for (i = 0; i < sizeof meshes / sizeof meshes[0]; i++) {
        amp_pathset ps;
        amp_mesh m;
        amp_gcode_opts o;
        gsim s;
        int planar = 0;
        double part, sup, ext, beads;
        snprintf(base, sizeof base, "%s", fx_tmp(meshes[i]));
        snprintf(args, sizeof args, "model %s -o %s.stl", meshes[i], base);
        ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
        snprintf(args, sizeof args, "slice %s.stl --layer 0.2 --continuous --radius 0.225 -o %s.amp", base, base);
        ck_assert_msg(fx_run_tool(args, NULL, 0) == 0, "%s", args);
        amp_pathset_init(&ps, NULL);
        snprintf(args, sizeof args, "%s.amp", base);
        ck_assert_int_eq(amp_pathset_read_file(&ps, args, NULL), AMP_OK);
        for (k = 0; k < ps.npaths; k++)
            planar |= ps.paths[k].h > 0;
        if (!planar) {
            for (k = 0; k < ps.npaths; k++)
                ps.paths[k].h = 0.2;
            ck_assert_int_eq(amp_pathset_write_file(&ps, args, NULL, NULL), AMP_OK);
        }
        snprintf(args, sizeof args, "gcode %s.amp --mesh %s.stl --json -o %s.gcode", base, base, base);
        ck_assert_msg(fx_run_tool(args, json, sizeof json) == 0, "%s", args);
        snprintf(args, sizeof args, "%s.gcode", base);
        ck_assert_int_eq(amp_read_file(args, NULL, 0, &text, &len, NULL), AMP_OK);
        amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
        run_in_bed(&s, text, &o);
        ck_assert_msg(fabs(s.first_e_z - 0.2) < 1e-6, "%s: first extrusion at z %g", meshes[i], s.first_e_z);
        /* independent figures: the beads from the .amp, the part from the mesh, the plastic from the G-code */
        amp_mesh_init(&m, NULL);
        snprintf(args, sizeof args, "%s.stl", base);
        ck_assert_int_eq(amp_mesh_read_stl_file(&m, args, NULL), AMP_OK);
        part = amp_mesh_volume(&m);
        sup = amp_pathset_volume(&ps, AMP_ROLE_SUPPORT);
        beads = amp_pathset_volume(&ps, -1);
        ext = gsim_filament(&s) * AMP_PI * 1.75 * 1.75 / 4;
        ck_assert_msg(fabs(ext / beads - 1) < 0.03, "%s: extruded %g mm3, beads %g mm3", meshes[i], ext, beads);
        ck_assert_msg(ext <= 1.05 * (part + sup), "%s: extruded %g mm3, part %g + support %g", meshes[i], ext, part,
                      sup);
        ck_assert_double_eq_tol(json_num(json, "part_volume_mm3"), part, 1e-6 * part);
        ck_assert_double_eq_tol(json_num(json, "first_layer_z_mm"), 0.2, 1e-9);
        ck_assert_double_gt(json_num(json, "lines_saved"), 0);
        gsim_free(&s);
        amp_free(NULL, text);
        amp_mesh_free(&m);
        amp_pathset_free(&ps);
        for (k = 0; k < 3; k++) {
            static const char *const ext_[] = {"stl", "amp", "gcode"};
            snprintf(args, sizeof args, "%s.%s", base, ext_[k]);
            remove(args);
        }
    }
}
END_TEST


/* Distance from p to written move k: a chord, or a helical arc (radial and z error, p's angle inside the sweep). */
static double dist_to_move(const seg *m, amp_vec3 p)
{
    double t, R, a0, a1, ap, sweep, f, twopi = 2 * AMP_PI;
    if (!m->arc)
        return sqrt(amp_v3_seg_dist2(p, m->a, m->b, &t));
    R = hypot(m->a.x - m->cx, m->a.y - m->cy);
    a0 = atan2(m->a.y - m->cy, m->a.x - m->cx);
    a1 = atan2(m->b.y - m->cy, m->b.x - m->cx);
    ap = atan2(p.y - m->cy, p.x - m->cx);
    /* counter-clockwise (G3) sweep from a0 to a1; G2 the other way */
    sweep = m->arc == 3 ? fmod(a1 - a0 + 2 * twopi, twopi) : fmod(a0 - a1 + 2 * twopi, twopi);
    f = m->arc == 3 ? fmod(ap - a0 + 2 * twopi, twopi) : fmod(a0 - ap + 2 * twopi, twopi);
    if (f > sweep + 1e-9)
        return HUGE_VAL;
    f = sweep > 0 ? f / sweep : 0;
    return hypot(hypot(p.x - m->cx, p.y - m->cy) - R, p.z - (m->a.z + f * (m->b.z - m->a.z)));
}

START_TEST(arcs_follow_the_input_within_tolerance)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st, lines_only;
    gsim s;
    char *text;
    size_t k, i, n = 4000, arcs = 0;
    double worst = 0, fil = AMP_PI * 1.75 * 1.75 / 4;
    amp_pathset_init(&ps, NULL);
    /* one and a half turns of a helix of radius 12 (pitch 2 mm), sampled every 0.03 mm, then a straight line */
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    for (k = 0; k <= n; k++) {
        double a = 3 * AMP_PI * k / n;
        amp_pathset_push(&ps, amp_v3(12 * cos(a), 12 * sin(a), 0.3 + a / AMP_PI), 0.3 + 0.02 * sin(a), NULL);
    }
    for (k = 1; k <= 50; k++)
        amp_pathset_push(&ps, amp_v3(-12 - 0.1 * k, 0, 3.3), 0.3, NULL);
    amp_gcode_opts_default(&o, AMP_FLAVOR_KLIPPER);
    free(gen(&ps, &o, &lines_only));
    o.arcs = 1;
    text = gen(&ps, &o, &st);
    gsim_init(&s);
    s.klipper = 1;
    s.arcs = 1;
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    for (k = 0; k < s.nsegs; k++)
        arcs += s.segs[k].arc != 0;
    ck_assert_uint_eq(arcs, st.arcs);
    ck_assert_uint_ge(arcs, 3); /* each arc sweeps less than a turn */
    ck_assert_uint_lt(st.segments * 5, lines_only.segments);
    /* every input vertex within the chord tolerance of a written move (placed back into model coordinates) */
    for (i = 0; i < ps.paths[0].n; i++) {
        amp_vec3 p = amp_v3_add(ps.verts[i].p, amp_v3_sub(s.segs[0].a, ps.verts[0].p));
        double best = HUGE_VAL;
        for (k = 0; k < s.nsegs; k++)
            best = fmin(best, dist_to_move(&s.segs[k], p));
        worst = fmax(worst, best);
    }
    ck_assert_msg(worst <= o.chord_tol + 2e-3, "input vertex %g mm from the written moves", worst);
    ck_assert_double_eq_tol(gsim_filament(&s) * fil / amp_pathset_volume(&ps, -1), 1, 1e-3);
    gsim_free(&s);
    /* a reader without arc support refuses the file: the G2/G3 are really there */
    gsim_init(&s);
    s.klipper = 1;
    ck_assert(!gsim_run(&s, text));
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

/* ------------------------------------------------------------------ direct hops */

/* Highest q.z - k |q.xy - p.xy| over the segment g (concave in the parameter: ternary search). */
static double cone_reach(const seg *g, amp_vec3 p, double k)
{
    double lo = 0, hi = 1;
    int it;
    for (it = 0; it < 60; it++) {
        double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
        amp_vec3 q1 = amp_v3_lerp(g->a, g->b, m1), q2 = amp_v3_lerp(g->a, g->b, m2);
        double f1 = q1.z - k * hypot(q1.x - p.x, q1.y - p.y), f2 = q2.z - k * hypot(q2.x - p.x, q2.y - p.y);
        if (f1 < f2)
            lo = m1;
        else
            hi = m2;
    }
    {
        amp_vec3 q = amp_v3_lerp(g->a, g->b, 0.5 * (lo + hi));
        return q.z - k * hypot(q.x - p.x, q.y - p.y);
    }
}

/*
 * A travel of one straight move from exactly where the last extrusion ended to exactly where the next
 * one starts: a direct hop (no lift; the writer's ramps over material take more than one move).
 */
static int is_direct(const gsim *s, const seg *tr)
{
    return tr->before > 0 && amp_v3_dist(s->segs[tr->before - 1].b, tr->a) < 1e-9 && tr->before < s->nsegs &&
           amp_v3_dist(s->segs[tr->before].a, tr->b) < 1e-9;
}

/*
 * Independent head-cone checker of the direct hops and of the travels' end zones
 * (docs/interfaces.md §2, [P1 §5.1]): at every point p of a direct hop and every point
 * of another travel in an end zone (in_end_zone with @p cell; 0: direct hops only),
 * sampled every 0.05 mm, no earlier extrusion centre line rises above the cone, tip
 * z_offs above p, half-angle theta: q.z - cot(theta) |q.xy - p.xy| <= p.z + z_offs
 * (1e-3 for the written rounding). Returns the violations; *hops counts the direct hops seen.
 */
static int count_cone_gouges(const gsim *s, double fil_d, double flow, double z_offs, double theta_deg, double cell,
                             size_t *hops)
{
    double k = 1.0 / tan(theta_deg * AMP_PI / 180.0);
    size_t t, g;
    int bad = 0;
    *hops = 0;
    for (t = 0; t < s->ntrav; t++) {
        const seg *tr = &s->travels[t];
        int q, nq, direct = is_direct(s, tr);
        if (!direct && !(cell > 0))
            continue;
        *hops += (size_t)direct;
        nq = 1 + (int)(amp_v3_dist(tr->a, tr->b) / 0.05);
        for (q = 0; q <= nq; q++) {
            amp_vec3 p = amp_v3_lerp(tr->a, tr->b, (double)q / nq);
            double lim = p.z + z_offs + 1e-3;
            if (!direct && !in_end_zone(s, tr, p, cell, fil_d, flow))
                continue;
            for (g = 0; g < tr->before; g++) {
                const seg *sg = &s->segs[g];
                if (sg->e <= 0 || fmax(sg->a.z, sg->b.z) - k * seg2d_point(p.x, p.y, sg->a, sg->b) <= lim)
                    continue;
                if (cone_reach(sg, p, k) > lim) {
                    bad++;
                    break;
                }
            }
        }
    }
    return bad;
}

/* Keep only the lifted travels (the hop-clearance checker count_gouges applies to them). */
static void keep_lifted_travels(gsim *s)
{
    size_t t, n = 0;
    for (t = 0; t < s->ntrav; t++)
        if (!is_direct(s, &s->travels[t]))
            s->travels[n++] = s->travels[t];
    s->ntrav = n;
}

START_TEST(cone_checker_catches_a_direct_hop_past_a_tower)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st;
    gsim s;
    char *text;
    size_t hops, k;
    amp_pathset_init(&ps, NULL);
    /* a 5 mm column of beads 1 mm beside the line between two short beads 2 mm apart */
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    for (k = 0; k < 10; k++)
        amp_pathset_push(&ps, amp_v3(11 + (k % 2) * 0.5, 1, 0.5 * (k + 1)), 0.3, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(5, 0, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(10, 0, 0.3), 0.3, NULL);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(12, 0, 0.3), 0.3, NULL);
    amp_pathset_push(&ps, amp_v3(17, 0, 0.3), 0.3, NULL);
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    o.direct_hop = 3;
    /* the writer's own cone test keeps the lift: no direct hop past the column */
    text = gen(&ps, &o, &st);
    gsim_init(&s);
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    ck_assert_int_eq(count_cone_gouges(&s, o.filament_diameter, o.flow, 0.5, 72,
                                       writer_cell(&s, o.filament_diameter, o.flow, o.travel_corridor), &hops),
                     0);
    ck_assert_uint_eq(st.direct_hops, 0);
    gsim_free(&s);
    free(text);
    /* told that the head is a needle (cone tip 20 mm up), it hops straight: the checker with the real head objects */
    o.head_z_offs = 20;
    text = gen(&ps, &o, &st);
    gsim_init(&s);
    ck_assert_msg(gsim_run(&s, text), "%s", s.why);
    ck_assert_uint_eq(st.direct_hops, 1);
    ck_assert_int_gt(count_cone_gouges(&s, o.filament_diameter, o.flow, 0.5, 72, 0, &hops), 0);
    ck_assert_uint_eq(hops, 1);
    gsim_free(&s);
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

/* Layers 0.3 mm apart of two rings and a rib between them, then a short bead past the rib: on every layer the
 * hop from the first ring to the bead crosses the rib printed before it. */
static void ribbed_layers(amp_pathset *ps, int nlayers)
{
    int l, k;
    amp_pathset_init(ps, NULL);
    for (l = 0; l < nlayers; l++) {
        double z = 0.3 * (l + 1);
        amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
        amp_pathset_set_height(ps, 0.3, NULL);
        amp_pathset_push(ps, amp_v3(3.5, -2, z), 0.25, NULL);
        amp_pathset_push(ps, amp_v3(3.5, 2, z), 0.25, NULL);
        amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
        amp_pathset_set_height(ps, 0.3, NULL);
        for (k = 0; k <= 24; k++)
            amp_pathset_push(ps, amp_v3(2 * cos(k * AMP_PI / 12), 2 * sin(k * AMP_PI / 12), z), 0.25, NULL);
        amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
        amp_pathset_set_height(ps, 0.3, NULL);
        amp_pathset_push(ps, amp_v3(4.5, 0, z), 0.25, NULL);
        amp_pathset_push(ps, amp_v3(6, 0, z), 0.25, NULL);
        amp_pathset_begin(ps, AMP_ROLE_OBJECT, NULL);
        amp_pathset_set_height(ps, 0.3, NULL);
        for (k = 0; k <= 24; k++)
            amp_pathset_push(ps, amp_v3(10 + 2 * cos(k * AMP_PI / 12), 2 * sin(k * AMP_PI / 12), z), 0.25, NULL);
    }
}

/*
 * A planar job printed layer by layer raises its material grid only when a travel reads it at a height the
 * deferred beads may reach (gcode.c, band_defer). The same job with one tube path appended (no longer
 * layer by layer: every bead raised as printed) must write the same moves up to that path. Raising nothing
 * before a read (band_need a no-op) makes the hops over the ribs direct and fails this.
 */
START_TEST(deferred_material_grid_writes_what_the_eager_grid_writes)
{
    amp_pathset ps;
    amp_gcode_opts o;
    amp_gcode_stats st, st2;
    char *lazy, *eager, *a, *b, *eb;
    ribbed_layers(&ps, 12);
    raw_opts(&o, AMP_FLAVOR_MARLIN);
    o.direct_hop = 3;
    o.retract_min_travel = 2;
    lazy = gen(&ps, &o, &st);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(5, 0, 3.6), 0.25, NULL);
    amp_pathset_push(&ps, amp_v3(6, 0, 3.6), 0.25, NULL);
    eager = gen(&ps, &o, &st2);
    a = strstr(lazy, "; path 0 ");
    b = strstr(eager, "; path 0 ");
    ck_assert_ptr_nonnull(a);
    ck_assert_ptr_nonnull(b);
    eb = strstr(b, "; path 48 "); /* the appended path: the moves before it are the whole job's */
    ck_assert_ptr_nonnull(eb);
    ck_assert_msg(strlen(a) > (size_t)(eb - b) && strncmp(a, b, (size_t)(eb - b)) == 0,
                  "the deferred grid wrote other moves");
    /* the job has direct hops, and the hops across a rib are lifted: one hop a layer past the ring's end */
    ck_assert_uint_gt(st.direct_hops, 0);
    ck_assert_uint_lt(st.direct_hops, st.travels - 11);
    ck_assert_uint_eq(st.direct_hops, st2.direct_hops);
    free(lazy);
    free(eager);
    amp_pathset_free(&ps);
}
END_TEST

/*
 * Travel on a real covering (the demo helix at eps 3 through the tool): direct hops cut the retractions
 * and the travel time share; every direct hop passes the independent cone checker and every lifted travel the
 * hop-clearance checker outside its end zones, where the cone checker applies. Measured: direct hops off (every
 * travel lifted vertically) 53.2 % of the time in travel, 3,539 retractions, travel 0.77 x the extrusion; on, with
 * vertical lifts over the beads' own tops (before the ramps) 43.4 %, 1,487 retractions, 0.683 x; on, ramping out of
 * the bead it leaves and into the one it starts, 39.4 %, 1,372 retractions, 0.613 x. Since the support rows are
 * joined in zigzags: off 42.7 %, 2,063 retractions, 0.543 x; on 34.1 %, 1,453, 0.445 x.
 */
START_TEST(direct_hops_cut_travel_time_on_the_helix_without_gouging)
{
    static const char *const steps[] = {
        "model helix -o %s-helix.spl",
        "model helix -o %s-helix.stl",
        "cover %s-helix.spl --eps 3 --dir u -o %s-c.amp",
        "order %s-c.amp -o %s-o.amp",
        "mdr %s-o.amp --nominal 0.5 -o %s-m.amp",
        "support %s-m.amp --mesh %s-helix.stl -o %s-h.amp",
    };
    char dir[256], args[2048], off[4096], on[4096], *text = NULL;
    size_t i, len, near, hops;
    amp_gcode_opts o;
    gsim s;
    const char *d;
    snprintf(dir, sizeof dir, "%s", fx_tmp("hops"));
    d = dir;
    for (i = 0; i < sizeof steps / sizeof steps[0]; i++) {
        snprintf(args, sizeof args, steps[i], d, d, d);
        ck_assert_msg(fx_run_tool(args, NULL, 0) == 0, "ampath %s failed", args);
    }
    snprintf(args, sizeof args, "gcode %s-h.amp --direct-hop 0 --json -o %s-off.gcode", d, d);
    ck_assert_int_eq(fx_run_tool(args, off, sizeof off), 0);
    snprintf(args, sizeof args, "gcode %s-h.amp --json -o %s-on.gcode", d, d);
    ck_assert_int_eq(fx_run_tool(args, on, sizeof on), 0);
    ck_assert_double_lt(json_num(on, "travel_time_fraction"), json_num(off, "travel_time_fraction") - 0.07);
    /* the ramps (travel_hull's end zones, and direct hops at any rise): before them 43.4 % and 0.683 x */
    ck_assert_double_lt(json_num(on, "travel_time_fraction"), 0.41);
    ck_assert_double_lt(json_num(on, "travel_per_print_length"), 0.65);
    /* since the support prints in zigzags (its rows' short hops gone) 2,063 -> 1,453; halved before */
    ck_assert_double_lt(json_num(on, "retractions"), 0.8 * json_num(off, "retractions"));
    ck_assert_double_lt(json_num(on, "travel_per_print_length"), json_num(off, "travel_per_print_length") - 0.05);
    ck_assert_double_gt(json_num(on, "direct_hops"), 1000);
    amp_gcode_opts_default(&o, AMP_FLAVOR_MARLIN);
    for (i = 0; i < 2; i++) {
        snprintf(args, sizeof args, i ? "%s-on.gcode" : "%s-off.gcode", d);
        ck_assert_int_eq(amp_read_file(args, NULL, 0, &text, &len, NULL), AMP_OK);
        double cell;
        run_in_bed(&s, text, &o);
        /* with direct hops on, the travels' end zones are the cone checker's (ramps), else there are none */
        cell = i ? writer_cell(&s, o.filament_diameter, o.flow, o.travel_corridor) : 0.0;
        ck_assert_int_eq(count_cone_gouges(&s, o.filament_diameter, o.flow, 0.5, 72, cell, &hops), 0);
        if (i)
            ck_assert_uint_gt(hops, 1000);
        keep_lifted_travels(&s);
        /* the hop-clearance rule (z_hop above beads within 1 mm) holds on the lifted travels outside the end zones */
        ck_assert_int_eq(count_gouges(&s, o.filament_diameter, o.flow, 1.0, o.z_hop, cell, &near), 0);
        ck_assert_uint_gt(near, 100);
        gsim_free(&s);
        amp_free(NULL, text);
    }
    {
        static const char *const files[] = {"helix.spl", "helix.stl", "c.amp", "o.amp", "m.amp", "h.amp",
                                            "off.gcode", "on.gcode"};
        for (i = 0; i < sizeof files / sizeof files[0]; i++) {
            snprintf(args, sizeof args, "%s-%s", d, files[i]);
            remove(args);
        }
    }
}
END_TEST

static Suite *gcode_suite(void)
{
    Suite *s = suite_create("gcode");
    TCase *tc = tcase_create("gcode");
    tcase_add_test(tc, e_per_segment_matches_formula_for_constant_and_varying_radius);
    tcase_add_test(tc, volumetric_cap_lowers_feed_exactly_where_needed);
    tcase_add_test(tc, travels_lift_above_printed_material);
    tcase_add_test(tc, gouge_checker_catches_a_travel_without_lift);
    tcase_add_test(tc, relative_and_absolute_e_agree);
    tcase_add_test(tc, e_is_set_back_to_zero_at_travels_past_100_mm);
    tcase_add_test(tc, reader_parses_every_line_of_both_flavors);
    tcase_add_loop_test(tc, reader_rejects_broken_gcode, 0, (int)(sizeof broken_gcode / sizeof broken_gcode[0]));
    tcase_add_test(tc, time_estimate_follows_trapezoids_and_junction_limit);
    tcase_add_test(tc, moves_accelerate_within_each_axis_limit);
    tcase_add_test(tc, klipper_jobs_stay_within_its_extrusion_cross_section);
    tcase_add_test(tc, klipper_takes_a_right_angle_at_its_square_corner_velocity);
    tcase_add_test(tc, klipper_refuses_a_start_or_end_sequence_it_would_stop_at);
    tcase_add_test(tc, caller_start_and_end_sequences_replace_the_built_in_ones);
    tcase_add_test(tc, lines_stay_within_the_length_limit_at_extreme_coordinates);
    tcase_add_test(tc, bad_input_gives_clear_errors);
    tcase_add_test(tc, sink_failure_stops_the_writer);
    tcase_add_test(tc, a_rewound_iterator_writes_the_same_job_again);
    tcase_add_test(tc, a_body_run_and_its_header_write_the_job_init_writes);
    tcase_add_test(tc, gcode_and_check_draw_a_progress_bar_on_a_terminal_only);
    tcase_add_test(tc, gcode_command_writes_file_and_reports_json);
    tcase_add_test(tc, demo_pipeline_gcode_parses_in_the_reader);
    tcase_add_test(tc, planar_beads_extrude_the_rounded_rectangle);
    tcase_add_test(tc, printing_moves_write_z_only_where_it_changes);
    tcase_add_test(tc, a_field_covering_with_support_rests_its_feet_on_the_bed);
    tcase_add_test(tc, placement_centres_the_job_and_rests_it_on_the_bed);
    tcase_add_test(tc, place_origin_keeps_coordinates_and_place_at_moves_the_centre);
    tcase_add_test(tc, a_job_too_big_for_the_bed_is_refused_naming_axis_and_overflow);
    tcase_add_test(tc, simplified_paths_stay_within_tolerance_without_micro_segments);
    tcase_add_test(tc, first_layer_temperatures_and_fan_come_in_order);
    tcase_add_test(tc, fan_is_off_for_every_bead_in_the_first_layers_whatever_the_order);
    tcase_add_test(tc, travels_go_straight_over_nothing_and_over_material_only_where_it_is);
    tcase_add_test(tc, cone_checker_catches_a_direct_hop_past_a_tower);
    tcase_add_test(tc, direct_hops_cut_travel_time_on_the_helix_without_gouging);
    tcase_add_test(tc, deferred_material_grid_writes_what_the_eager_grid_writes);
    tcase_add_test(tc, klipper_reader_rejects_marlin_only_commands);
    tcase_add_test(tc, continuous_slices_of_the_builtin_meshes_print_on_the_bed);
    tcase_add_test(tc, arcs_follow_the_input_within_tolerance);
    tcase_set_timeout(tc, 300);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(gcode_suite)
