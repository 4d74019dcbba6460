/*
 * G-code writer (docs/interfaces.md §5): an allocation-free line iterator over a path set.
 *
 * The iterator is a small state machine (header, start sequence, set-up,
 * paths with their travels, teardown, end sequence). Init checks the job,
 * places it on the bed and runs the machine once without formatting (pass 1)
 * to obtain the figures the header prints (amp_gcode_iter_init_body skips that
 * run and the header; amp_gcode_iter_header writes it after the last line); the caller's calls to
 * amp_gcode_iter_next() then run it again (pass 2) and format each line with
 * an integer fixed-point formatter (no printf on the hot path, no locale, no
 * exponents). The print-time estimate lives in gcode_estimate.c.
 */
#include <math.h>
#include <stdarg.h>
#include <string.h>

#include "ampath/version.h"
#include "gcode_internal.h"

#define GC_MAGIC 0x67636f64u
#define GC_MIN_SEG 1e-9      /* segments shorter than this (mm) are not printed */
#define GC_COORD_MAX 99999.0 /* keeps every number short enough for AMP_GCODE_LINE_MAX */
#define GC_FIT_TOL 5e-4      /* half the 0.001 mm resolution of the written coordinates */
#define GC_HEADER_LINES 9
#if AMP_GCODE_GRID < 16 || AMP_GCODE_GRID > 32768 || (AMP_GCODE_GRID & (AMP_GCODE_GRID - 1)) != 0
#error "AMP_GCODE_GRID must be a power of two from 16 to 32768 (the head-cone test's max-pyramid halves it)"
#endif
#define GC_CONE_GROUP 8 /* travel samples sharing one head-cone floor */
/* E is set back to 0 (G92 E0) at a travel once it has reached 100 mm: Marlin keeps positions in single
 * precision floats, whose step at E = 10^5 mm (a bed-sized job's filament) is 0.008 mm, the whole E of a
 * short segment; below 128 mm it is finer than the 10^-5 mm written (PrusaSlicer resets E every layer). */
#define GC_E_RESET_UNITS 10000000LL

enum { PH_HEADER, PH_START, PH_SETUP, PH_PATHS, PH_TEARDOWN, PH_END, PH_DONE };
/* sub-steps of PH_PATHS */
enum {
    PS_COMMENT, PS_HOTEND, PS_BED, PS_FAN, PS_PLAN, PS_RETRACT, PS_ERESET, PS_LIFT, PS_HULL, PS_DESCEND, PS_UNRETRACT,
    PS_SEGS
};
/* sub-steps of PH_START around a caller's sequence (PrusaSlicer's automatic temperatures) */
enum { ST_BED_WAIT, ST_HOT_SET, ST_TEXT, ST_HOT_WAIT, ST_DONE };
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
    o->travel_corridor = 1.0;
    o->end_lift = 10.0;
    o->relative_e = flavor == AMP_FLAVOR_KLIPPER; /* docs/interfaces.md §5: Klipper uses M83 by default */
    o->max_cross_section = 4.0 * 0.4 * 0.4; /* Klipper's default for the 0.4 mm nozzle (Klipper flavour only) */
    o->hotend_temp = 210.0;
    o->bed_temp = 60.0;
    o->start_gcode = NULL;
    o->end_gcode = NULL;
    o->accel = 1000.0;
    o->junction_deviation = amp_gcode_junction_default(flavor, o->accel);
    o->max_feed_xy = 200.0;
    o->max_feed_z = 10.0;
    o->max_feed_e = 60.0;
    /* Marlin's DEFAULT_MAX_ACCELERATION and DEFAULT_RETRACT_ACCELERATION */
    o->max_accel_xy = 3000.0;
    o->max_accel_z = 100.0;
    o->max_accel_e = 10000.0;
    o->retract_accel = 3000.0;
    /* the generic printer of docs/interfaces.md §5: 220 x 220 x 250 mm */
    o->profile = "generic";
    o->place = AMP_PLACE_CENTER;
    o->bed_max_x = 220.0;
    o->bed_max_y = 220.0;
    o->max_height = 250.0;
    o->first_layer_height = 0.2;
    o->first_layer_feed = 20.0;
    o->first_layer_hotend_temp = 215.0;
    o->first_layer_bed_temp = 60.0;
    o->fan_off_layers = 1;
    o->fan_speed = 1.0;
    o->retract_min_travel = 2.0;
    o->chord_tol = 0.01;
    o->radius_tol = 0.01;
    o->min_segment = 0.02;
    o->direct_hop = 3.0;
    o->head_z_offs = 0.5;
    o->head_theta = 72.0;
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
    double f = (v - v0) / cell;
    if (!(f >= 0.0))
        return 0;
    if (f >= (double)(AMP_GCODE_GRID - 1))
        return AMP_GCODE_GRID - 1;
    return (int)f; /* truncation is floor here (0 <= f < GRID); floor() was a third of grid_walk's time */
}

/* The smallest float >= v: a cell raised to it is never below v, and a float c is below v exactly when it is
 * below this. */
static float float_up(double v)
{
    float f = (float)v;
    return (double)f < v ? nextafterf(f, HUGE_VALF) : f;
}

/*
 * The cells within @p w of the XY segment a-b, row by row: row j's band of y,
 * widened by w, clips the segment, and the clipped piece's x extent widened
 * by w gives the row's columns. Every point within w of the segment is in a
 * listed cell (the piece of the segment within w of a point of the band lies
 * in the widened band, and the point within w of it in x); the ends are
 * padded by a millionth of a cell against rounding. Rows *r0 .. *r1, columns
 * lo[j] .. hi[j]; none when *r0 > *r1.
 */
static void segment_cells(const amp_gcode_iter *it, amp_vec3 a, amp_vec3 b, double w, int *lo, int *hi, int *r0,
                          int *r1)
{
    double cell = it->grid_cell, pad = 1e-6 * cell, dy = b.y - a.y, dx = b.x - a.x, idy = dy != 0.0 ? 1.0 / dy : 0.0;
    int j;
    w += pad;
    /* plain comparisons, not fmin/fmax (finite coordinates; those were calls into libm here) */
    *r0 = grid_index((a.y < b.y ? a.y : b.y) - w, it->grid_y0, cell);
    *r1 = grid_index((a.y > b.y ? a.y : b.y) + w, it->grid_y0, cell);
    for (j = *r0; j <= *r1; j++) {
        /* the band of row j (the edge rows reach on: grid_index clamps) */
        double ylo = j == 0 ? -HUGE_VAL : it->grid_y0 + (double)j * cell - w;
        double yhi = j == AMP_GCODE_GRID - 1 ? HUGE_VAL : it->grid_y0 + (double)(j + 1) * cell + w;
        double t0 = 0.0, t1 = 1.0, xa, xb;
        if (dy != 0.0) {
            double ta = (ylo - a.y) * idy, tb = (yhi - a.y) * idy;
            double tl = ta < tb ? ta : tb, th = ta < tb ? tb : ta;
            t0 = tl > t0 ? tl : t0;
            t1 = th < t1 ? th : t1;
        }
        if (dy == 0.0 ? (a.y < ylo || a.y > yhi) : t0 > t1) {
            lo[j] = 1; /* an empty row (the widened band misses the segment) */
            hi[j] = 0;
            continue;
        }
        xa = a.x + t0 * dx;
        xb = a.x + t1 * dx;
        lo[j] = grid_index((xa < xb ? xa : xb) - w, it->grid_x0, cell);
        hi[j] = grid_index((xa > xb ? xa : xb) + w, it->grid_x0, cell);
    }
}

/* What grid_raise raises: the material band (grid) and the centre line (grid_c and its pyramid). */
#define GR_BAND 1
#define GR_CENTRE 2

/* Start of level l (side AMP_GCODE_GRID >> l, l >= 1) in the max-pyramid grid_cp. */
static size_t pyramid_level(int l)
{
    size_t off = 0;
    int m;
    for (m = 1; m < l; m++)
        off += (size_t)(AMP_GCODE_GRID >> m) * (size_t)(AMP_GCODE_GRID >> m);
    return off;
}

/* Centre-line cell (i, j) was raised to @p v: the blocks over it are raised too, up to the first one already
 * as high (every block above that one is at least as high). */
static void pyramid_raise(amp_gcode_iter *it, int i, int j, float v)
{
    size_t off = 0;
    int side = AMP_GCODE_GRID / 2;
    for (; side >= 1; off += (size_t)side * (size_t)side, side /= 2) {
        float *c;
        i /= 2;
        j /= 2;
        c = &it->grid_cp[off + (size_t)j * (size_t)side + (size_t)i];
        if (*c >= v)
            break;
        *c = v;
    }
}

/*
 * Raise every cell within @p w of the XY segment a-b to @p top in the
 * material grid (w > 0 only), and every cell within @p wc of it (0: the cells
 * it passes through) to @p topc in the centre-line grid and its blocks
 * (segment_cells: the cells of the segment's neighbourhood row by row, each
 * raised once; the samples every half cell this replaces boxed in up to six
 * times as many cells). @p parts: GR_BAND (the material grid), GR_CENTRE (the
 * centre-line grid) or both.
 */
static void grid_raise(amp_gcode_iter *it, amp_vec3 a, amp_vec3 b, double w, double wc, double top, double topc,
                       int parts)
{
    int lo[AMP_GCODE_GRID], hi[AMP_GCODE_GRID], r0, r1, i, j;
    float ftop = float_up(top), ftopc = float_up(topc);
    if (w > 0.0 && (parts & GR_BAND)) {
        segment_cells(it, a, b, w, lo, hi, &r0, &r1);
        for (j = r0; j <= r1; j++) {
            float *row = &it->grid[j * AMP_GCODE_GRID];
            for (i = lo[j]; i <= hi[j]; i++)
                row[i] = row[i] < ftop ? ftop : row[i];
        }
    }
    if (!(parts & GR_CENTRE))
        return;
    segment_cells(it, a, b, wc, lo, hi, &r0, &r1);
    for (j = r0; j <= r1; j++) {
        float *row = &it->grid_c[j * AMP_GCODE_GRID];
        for (i = lo[j]; i <= hi[j]; i++)
            if (row[i] < ftopc) {
                row[i] = ftopc;
                pyramid_raise(it, i, j, ftopc);
            }
    }
}

/* Highest material top in the cells of the box of half-width @p w around (px, py); -HUGE_VAL if none. */
static double grid_top_box(const amp_gcode_iter *it, const float *grid, double px, double py, double w)
{
    double cell = it->grid_cell, best = -HUGE_VAL;
    int i0 = grid_index(px - w, it->grid_x0, cell), i1 = grid_index(px + w, it->grid_x0, cell);
    int j0 = grid_index(py - w, it->grid_y0, cell), j1 = grid_index(py + w, it->grid_y0, cell);
    int i, j;
    for (j = j0; j <= j1; j++)
        for (i = i0; i <= i1; i++)
            if ((double)grid[j * AMP_GCODE_GRID + i] > best)
                best = (double)grid[j * AMP_GCODE_GRID + i];
    return best;
}

/* ---------------------------------------------------------------- option and input checks */

/* Length written of a start/end line of @p n characters: a line over
 * AMP_GCODE_LINE_MAX loses its comment (stock profiles document their
 * commands at length: "M201 X1000 Y1000 Z200 E5000 ; sets maximum
 * accelerations, mm/sec^2"); the command itself must fit. */
static size_t text_len(const char *s, size_t n)
{
    const char *c;
    while (n > 0 && (s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == '\t'))
        n--;
    if (n <= AMP_GCODE_LINE_MAX || !(c = memchr(s, ';', n)))
        return n;
    n = (size_t)(c - s);
    while (n > 0 && (s[n - 1] == ' ' || s[n - 1] == '\t'))
        n--;
    return n;
}

static amp_status check_text(const char *text, const char *what, amp_error *err)
{
    long line = 1;
    const char *s = text;
    while (*s) {
        const char *e = strchr(s, '\n');
        size_t n = text_len(s, e ? (size_t)(e - s) : strlen(s));
        if (n > AMP_GCODE_LINE_MAX)
            return amp_fail(err, AMP_ERR_LIMIT, line,
                            "%s sequence: line %ld has %lu characters before its comment, at most %d allowed", what,
                            line, (unsigned long)n, AMP_GCODE_LINE_MAX);
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
#define IN(v, lo, hi) (isfinite(v) && (v) >= (lo) && (v) <= (hi))

static amp_status check_opts(const amp_gcode_opts *o, amp_error *err)
{
    NEED(o->flavor == AMP_FLAVOR_MARLIN || o->flavor == AMP_FLAVOR_KLIPPER, "flavor", "marlin or klipper");
    NEED(IN(o->filament_diameter, 1e-9, 10.0), "filament diameter", "in (0, 10] mm");
    NEED(IN(o->flow, 1e-9, 10.0), "flow", "in (0, 10]");
    NEED(IN(o->max_volumetric_flow, 1e-9, 1e4), "max volumetric flow", "in (0, 10000] mm^3/s");
    NEED(IN(o->print_feed, 1e-9, 1e4), "print feed", "in (0, 10000] mm/s");
    NEED(IN(o->travel_feed, 1e-9, 1e4), "travel feed", "in (0, 10000] mm/s");
    NEED(IN(o->retract_length, 0.0, 100.0), "retract length", "in [0, 100] mm");
    NEED(IN(o->retract_speed, 1e-9, 1e4), "retract speed", "in (0, 10000] mm/s");
    NEED(IN(o->z_hop, 0.0, 1000.0), "z-hop", "in [0, 1000] mm");
    NEED(IN(o->travel_corridor, 0.0, 1000.0), "travel corridor", "in [0, 1000] mm");
    NEED(IN(o->end_lift, 0.0, 1000.0), "end lift", "in [0, 1000] mm");
    NEED(IN(o->hotend_temp, 0.0, 500.0), "hotend temperature", "in [0, 500] C");
    NEED(IN(o->bed_temp, 0.0, 200.0), "bed temperature", "in [0, 200] C");
    NEED(IN(o->first_layer_hotend_temp, 0.0, 500.0), "first-layer hotend temperature", "in [0, 500] C");
    NEED(IN(o->first_layer_bed_temp, 0.0, 200.0), "first-layer bed temperature", "in [0, 200] C");
    NEED(IN(o->accel, 1e-9, 1e6), "acceleration", "in (0, 1e6] mm/s^2");
    NEED(IN(o->junction_deviation, 0.0, 10.0), "junction deviation", "in [0, 10] mm");
    NEED(isfinite(o->max_feed_xy) && o->max_feed_xy > 0.0, "max feed xy", "positive");
    NEED(isfinite(o->max_feed_z) && o->max_feed_z > 0.0, "max feed z", "positive");
    NEED(isfinite(o->max_feed_e) && o->max_feed_e > 0.0, "max feed e", "positive");
    NEED(IN(o->max_accel_xy, 0.0, 1e6) && IN(o->max_accel_z, 0.0, 1e6) && IN(o->max_accel_e, 0.0, 1e6),
         "max acceleration per axis", "in [0, 1e6] mm/s^2 (0: no limit)");
    NEED(IN(o->retract_accel, 0.0, 1e6), "retract acceleration", "in [0, 1e6] mm/s^2 (0: the acceleration)");
    NEED(IN(o->max_cross_section, 0.0, 1e4), "max cross-section", "in [0, 10000] mm^2 (0: no limit)");
    NEED(o->place >= AMP_PLACE_CENTER && o->place <= AMP_PLACE_AT, "place", "center, origin or a bed point");
    NEED(IN(o->place_x, -GC_COORD_MAX, GC_COORD_MAX) && IN(o->place_y, -GC_COORD_MAX, GC_COORD_MAX), "place point",
         "finite, within +-99999 mm");
    NEED(IN(o->bed_min_x, -GC_COORD_MAX, GC_COORD_MAX) && IN(o->bed_max_x, o->bed_min_x + 1e-3, GC_COORD_MAX),
         "bed x range", "min < max within +-99999 mm");
    NEED(IN(o->bed_min_y, -GC_COORD_MAX, GC_COORD_MAX) && IN(o->bed_max_y, o->bed_min_y + 1e-3, GC_COORD_MAX),
         "bed y range", "min < max within +-99999 mm");
    NEED(IN(o->bed_radius, 0.0, GC_COORD_MAX), "bed radius", "0 (a rectangle) or a radius up to 99999 mm");
    NEED(IN(o->max_height, 1e-3, GC_COORD_MAX), "max height", "in (0, 99999] mm");
    NEED(IN(o->first_layer_height, 1e-3, 10.0), "first-layer height", "in (0, 10] mm");
    NEED(IN(o->first_layer_feed, 1e-9, 1e4), "first-layer feed", "in (0, 10000] mm/s");
    NEED(o->fan_off_layers >= 0 && o->fan_off_layers <= 100000, "fan off layers", "in [0, 100000]");
    NEED(IN(o->fan_speed, 0.0, 1.0), "fan speed", "in [0, 1]");
    NEED(IN(o->retract_min_travel, 0.0, 1000.0), "retract min travel", "in [0, 1000] mm");
    NEED(IN(o->direct_hop, 0.0, 1000.0), "direct hop", "in [0, 1000] mm");
    NEED(IN(o->head_z_offs, 0.0, 1000.0), "head z_offs", "in [0, 1000] mm");
    NEED(IN(o->head_theta, 1.0, 89.0), "head theta", "in [1, 89] degrees");
    NEED(IN(o->chord_tol, 0.0, 10.0), "chord tolerance", "in [0, 10] mm");
    NEED(IN(o->radius_tol, 0.0, 10.0), "radius tolerance", "in [0, 10] mm");
    NEED(IN(o->min_segment, 0.0, 10.0), "min segment", "in [0, 10] mm");
    if (o->start_gcode && check_text(o->start_gcode, "start", err) != AMP_OK)
        return AMP_ERR_LIMIT;
    if (o->end_gcode && check_text(o->end_gcode, "end", err) != AMP_OK)
        return AMP_ERR_LIMIT;
    if (amp_gc_klipper_sequence_fits(o, o->start_gcode, "start", err) != AMP_OK ||
        amp_gc_klipper_sequence_fits(o, o->end_gcode, "end", err) != AMP_OK)
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

/* Depth of a bead below its vertex: h for a planar bead, r for a tube (docs/interfaces.md §5). */
static double bead_depth(const amp_path *p, double r) { return p->h > 0.0 ? p->h : r; }

/* Does vertex @p i lie within the tolerances of the chord v[k] -> v[j] (position and radius)? */
static int chord_keeps(const amp_gcode_opts *o, const amp_pvert *v, size_t k, size_t j, size_t i)
{
    amp_vec3 d = amp_v3_sub(v[j].p, v[k].p), q = amp_v3_sub(v[i].p, v[k].p);
    double l2 = amp_v3_dot(d, d), t = l2 > 0.0 ? amp_v3_dot(q, d) / l2 : 0.0;
    amp_vec3 foot;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    foot = amp_v3_add(v[k].p, amp_v3_scale(d, t));
    if (amp_v3_dist(foot, v[i].p) > o->chord_tol)
        return 0;
    /* the deposition radius must follow the chord too (MDR, [P1 §5.2]); E stays exact either way */
    return fabs(v[k].r + t * (v[j].r - v[k].r) - v[i].r) <= o->radius_tol;
}

/*
 * Length of the move v[a] -> v[b] as the firmware reads it: both ends placed
 * and rounded to the 3 decimals put_coord writes. A chord of 0.0201 mm may be
 * written as 0.019 mm, so min_segment is tested on this, with half a unit of
 * the last digit to spare for readers that subtract the decimals in floating
 * point (0.199 - 0.179 < 0.02 there).
 */
static double written_length(const amp_gcode_iter *it, amp_vec3 a, amp_vec3 b)
{
    double d = amp_v3_dist(a, b), q[3];
    int c;
    if (d > it->o.min_segment + 2e-3) /* rounding moves a length by at most sqrt(3) 1e-3 */
        return d;
    a = amp_v3_add(a, it->off);
    b = amp_v3_add(b, it->off);
    q[0] = (double)(llround(b.x * 1e3) - llround(a.x * 1e3));
    q[1] = (double)(llround(b.y * 1e3) - llround(a.y * 1e3));
    q[2] = (double)(llround(b.z * 1e3) - llround(a.z * 1e3));
    for (d = 0.0, c = 0; c < 3; c++)
        d += q[c] * q[c];
    return sqrt(d) * 1e-3 - 5e-4;
}

/*
 * End vertex of the written segment that starts at vertex @p k of path @p i
 * (clean segments, docs/interfaces.md §5): the farthest vertex whose chord keeps every
 * vertex in between within the tolerances, extended while the chord is
 * shorter than min_segment; a short remainder joins the last segment.
 */
static size_t next_vertex(const amp_gcode_iter *it, size_t i, size_t k)
{
    const amp_pathset *ps = it->ps;
    const amp_gcode_opts *o = &it->o;
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    size_t n = ps->paths[i].n, j = next_segment(ps, i, k) + 1, m, lim;
    double rest = 0.0;
    if (j >= n)
        return n - 1;
    if (o->chord_tol <= 0.0 && o->min_segment <= 0.0)
        return j;
    lim = k + AMP_GCODE_MERGE_MAX < n - 1 ? k + AMP_GCODE_MERGE_MAX : n - 1;
    for (m = j + 1; m <= lim; m++) {
        int keep = written_length(it, v[k].p, v[j].p) < o->min_segment; /* a chord still too short must grow */
        size_t t;
        if (!keep && o->chord_tol > 0.0)
            for (keep = 1, t = k + 1; t < m && keep; t++)
                keep = chord_keeps(o, v, k, m, t);
        if (!keep)
            break;
        if (amp_v3_dist(v[k].p, v[m].p) > GC_MIN_SEG) /* never a chord of zero length (closed loops) */
            j = m;
    }
    /* a remainder shorter than min_segment (as written) joins this segment */
    for (m = j; m + 1 < n && rest < o->min_segment + 2e-3; m++)
        rest += amp_v3_dist(v[m].p, v[m + 1].p);
    if (m + 1 >= n && (rest < o->min_segment || written_length(it, v[j].p, v[n - 1].p) < o->min_segment) &&
        amp_v3_dist(v[k].p, v[n - 1].p) > GC_MIN_SEG)
        j = n - 1;
    return j;
}

/* End vertex of the written move from vertex @p k of path @p i: the chord of next_vertex or, with arcs on,
 * the arc that replaces it (*use_arc set, *arc filled). */
static size_t next_move(const amp_gcode_iter *it, size_t i, size_t k, amp_gc_arc *arc, int *use_arc)
{
    size_t j = next_vertex(it, i, k);
    *use_arc = it->o.arcs && amp_gc_fit_arc(amp_pathset_path_verts(it->ps, i), it->ps->paths[i].n, k, j, &it->o, arc);
    return *use_arc ? arc->end : j;
}

/* ---------------------------------------------------------------- scan and placement */

typedef struct job_scan {
    amp_box3 bb;  /* vertices */
    double rmax, zlow, z_first;
    size_t printable, input_segments;
    int rising;   /* every printed path planar, level, and none below the one before (band_defer) */
} job_scan;

static amp_status scan_paths(const amp_pathset *ps, job_scan *js, amp_error *err)
{
    size_t i, k;
    js->bb = amp_box3_empty();
    js->rmax = 0.0;
    js->zlow = js->z_first = HUGE_VAL;
    js->printable = js->input_segments = 0;
    js->rising = 1;
    if (ps->npaths > 0 && (!ps->paths || !ps->verts))
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: inconsistent path set");
    for (i = 0; i < ps->npaths; i++) {
        const amp_path *p = &ps->paths[i];
        const amp_pvert *v;
        if (p->first > ps->nverts || p->n > ps->nverts - p->first)
            return amp_fail(err, AMP_ERR_ARG, 0, "gcode: path %lu lies outside the vertex array", (unsigned long)i);
        if (!isfinite(p->h) || p->h < 0.0 || p->h > 100.0)
            return amp_fail(err, AMP_ERR_ARG, 0, "gcode: path %lu has a bead height outside [0, 100] mm",
                            (unsigned long)i);
        if (next_segment(ps, i, 0) + 1 >= p->n)
            continue; /* skipped: nothing to print, and it must not move the placement */
        v = amp_pathset_path_verts(ps, i);
        if (p->h <= 0.0 || (js->printable > 0 && v[0].p.z < js->bb.max.z))
            js->rising = 0;
        js->printable++;
        for (k = 0; k < p->n; k++) {
            if (!amp_v3_finite(v[k].p) || !isfinite(v[k].r) || v[k].r < 0.0)
                return amp_fail(err, AMP_ERR_ARG, 0, "gcode: path %lu vertex %lu is not finite or has a negative radius",
                                (unsigned long)i, (unsigned long)k);
            if (fabs(v[k].p.x) > GC_COORD_MAX || fabs(v[k].p.y) > GC_COORD_MAX || fabs(v[k].p.z) > GC_COORD_MAX ||
                v[k].r > 1000.0)
                return amp_fail(err, AMP_ERR_RANGE, 0, "gcode: path %lu vertex %lu lies beyond +-%g mm",
                                (unsigned long)i, (unsigned long)k, GC_COORD_MAX);
            if (v[k].p.z != v[0].p.z)
                js->rising = 0;
            js->bb = amp_box3_add(js->bb, v[k].p);
            js->rmax = fmax(js->rmax, v[k].r);
            js->zlow = fmin(js->zlow, v[k].p.z - bead_depth(p, v[k].r));
            if (p->h > 0.0)
                js->z_first = fmin(js->z_first, v[k].p.z);
            if (k + 1 < p->n && amp_v3_dist(v[k].p, v[k + 1].p) > GC_MIN_SEG)
                js->input_segments++;
        }
    }
    if (js->printable == 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: empty path set: no path has a segment of non-zero length");
    return AMP_OK;
}

/* One axis of the fit check: the placed range [lo, hi] must lie in [b0, b1]. */
static amp_status fit_axis(const amp_gcode_opts *o, char axis, double lo, double hi, double b0, double b1,
                           amp_error *err)
{
    double over = fmax(0.0, b0 - lo) + fmax(0.0, hi - b1);
    if (over <= GC_FIT_TOL)
        return AMP_OK;
    return amp_fail(err, AMP_ERR_RANGE, 0,
                    "gcode: the job does not fit printer '%s': %c spans %.3f..%.3f mm after placement, the bed "
                    "%.3f..%.3f mm (%.3f mm over)",
                    o->profile ? o->profile : "?", axis, lo, hi, b0, b1, over);
}

/*
 * A round bed: every printed vertex, placed, within the disc (its straight moves between them then are too:
 * the disc is convex). The same vertices as the box of the scan: those of paths with something to print.
 */
static amp_status fit_disc(const amp_gcode_opts *o, const amp_pathset *ps, amp_vec3 off, amp_error *err)
{
    double cx = 0.5 * (o->bed_min_x + o->bed_max_x), cy = 0.5 * (o->bed_min_y + o->bed_max_y), far = 0.0;
    size_t i, k;
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        if (next_segment(ps, i, 0) + 1 >= ps->paths[i].n)
            continue;
        for (k = 0; k < ps->paths[i].n; k++)
            far = fmax(far, hypot(v[k].p.x + off.x - cx, v[k].p.y + off.y - cy));
    }
    if (far <= o->bed_radius + GC_FIT_TOL)
        return AMP_OK;
    return amp_fail(err, AMP_ERR_RANGE, 0,
                    "gcode: the job does not fit printer '%s': after placement it reaches %.3f mm from the centre "
                    "(%.3f, %.3f) of the round bed of radius %.3f mm (%.3f mm over)",
                    o->profile ? o->profile : "?", far, cx, cy, o->bed_radius, far - o->bed_radius);
}

/* The placement offset (docs/interfaces.md §5) and the check that the placed job fits the bed volume. */
static amp_status place_job(amp_gcode_iter *it, const amp_pathset *ps, const job_scan *js, amp_error *err)
{
    const amp_gcode_opts *o = &it->o;
    amp_vec3 off = amp_v3(0, 0, 0);
    amp_status st;
    if (o->place != AMP_PLACE_ORIGIN) {
        double cx = o->place == AMP_PLACE_AT ? o->place_x : 0.5 * (o->bed_min_x + o->bed_max_x);
        double cy = o->place == AMP_PLACE_AT ? o->place_y : 0.5 * (o->bed_min_y + o->bed_max_y);
        off = amp_v3(cx - 0.5 * (js->bb.min.x + js->bb.max.x), cy - 0.5 * (js->bb.min.y + js->bb.max.y), 0.0 - js->zlow);
    }
    it->off = off;
    st = fit_axis(o, 'X', js->bb.min.x + off.x, js->bb.max.x + off.x, o->bed_min_x, o->bed_max_x, err);
    if (st == AMP_OK)
        st = fit_axis(o, 'Y', js->bb.min.y + off.y, js->bb.max.y + off.y, o->bed_min_y, o->bed_max_y, err);
    if (st == AMP_OK)
        st = fit_axis(o, 'Z', js->bb.min.z + off.z, js->bb.max.z + off.z, 0.0, o->max_height, err);
    if (st == AMP_OK && o->bed_radius > 0.0)
        st = fit_disc(o, ps, off, err);
    if (st != AMP_OK)
        return st;
    it->zmax = o->max_height - off.z;
    it->zlow = js->zlow;
    it->z_first = js->z_first;
    return AMP_OK;
}

static void reset_run(amp_gcode_iter *it, int pass)
{
    size_t i;
    it->pass = pass;
    it->xs_path = (size_t)-1;
    it->xs_area = 0.0;
    it->phase = PH_HEADER;
    it->sub = 0;
    it->path = 0;
    it->seg = it->nxt = 0;
    it->text = NULL;
    it->have_pos = 0;
    it->retracted = 0;
    it->printed_any = 0;
    it->pos = amp_v3(0, 0, 0);
    it->e_exact = 0.0;
    it->e_units = 0;
    it->f_units = -1;
    it->travel_to = it->travel_from = amp_v3(0, 0, 0);
    it->layer = it->path_layer = 0;
    it->layer_z = it->z_first;
    it->first_done = it->fan_on = it->travel_retract = it->path_first = 0;
    it->hull_n = it->hull_i = 0;
    for (i = 0; i < AMP_GCODE_GRID * AMP_GCODE_GRID; i++)
        it->grid[i] = it->grid_c[i] = -HUGE_VALF;
    for (i = 0; i < AMP_GCODE_PYRAMID; i++)
        it->grid_cp[i] = -HUGE_VALF;
    it->zc_max = -HUGE_VAL;
    it->band_pending = 0;
    it->end_r = 0.0;
    it->direct = 0;
    it->plan_head = it->plan_n = 0;
    it->plan_v = 0.0;
    it->plan_print = 0;
    memset(&it->stats, 0, sizeof it->stats);
    it->stats.max_travel_z = -HUGE_VAL;
    it->stats.first_layer_z = HUGE_VAL;
    it->stats.bbox = it->stats.first_layer_bbox = amp_box3_empty();
    memset(&it->last, 0, sizeof it->last);
}

static int step(amp_gcode_iter *it, lb *l);

/* What both inits share: check the options and the job, place it, frame the material grids. */
static amp_status prepare(amp_gcode_iter *it, const amp_pathset *ps, const amp_gcode_opts *o, job_scan *js,
                          amp_error *err)
{
    double margin, ext;
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
    if (st == AMP_OK)
        st = scan_paths(ps, js, err);
    if (st == AMP_OK)
        st = place_job(it, ps, js, err);
    if (st != AMP_OK)
        return st;
    if (js->bb.max.z + it->off.z + js->rmax + it->o.z_hop + it->o.end_lift > GC_COORD_MAX)
        return amp_fail(err, AMP_ERR_RANGE, 0, "gcode: the job rises beyond %g mm", GC_COORD_MAX);
    it->ps = ps;
    it->fil_area = AMP_PI * 0.25 * it->o.filament_diameter * it->o.filament_diameter;
    /* the grid (model coordinates) covers every vertex with its radius and a travel corridor around it */
    margin = js->rmax + it->o.travel_corridor + 1.0;
    ext = fmax(js->bb.max.x - js->bb.min.x, js->bb.max.y - js->bb.min.y) + 2.0 * margin;
    it->grid_x0 = js->bb.min.x - margin;
    it->grid_y0 = js->bb.min.y - margin;
    it->grid_cell = ext / AMP_GCODE_GRID;
    it->band_lazy = js->rising;
    it->body_only = 0;
    memset(&it->est, 0, sizeof it->est);
    it->est.input_segments = js->input_segments;
    return AMP_OK;
}

/* The job refused for a move over the printer's cross-section (found by either pass). */
static amp_status xs_fail(const amp_gcode_iter *it, amp_error *err)
{
    return amp_fail(err, AMP_ERR_LIMIT, 0,
                    "gcode: path %lu extrudes %.3g mm^2 of cross-section (a bead of radius %.3g mm), more than the "
                    "printer takes (%.3g mm^2: Klipper's max_extrude_cross_section, 4 x nozzle^2, would stop the "
                    "job there): lower the radius (ampath mdr --nominal, field --radius) or, if printer.cfg allows "
                    "more, say so with --max-cross-section",
                    (unsigned long)it->xs_path, it->xs_area, sqrt(it->xs_area / AMP_PI), it->o.max_cross_section);
}

amp_status amp_gcode_iter_init(amp_gcode_iter *it, const amp_pathset *ps, const amp_gcode_opts *o, amp_error *err)
{
    job_scan js;
    amp_status st = prepare(it, ps, o, &js, err);
    if (st != AMP_OK)
        return st;
    /* pass 1: the whole job without formatting, for the figures of the header */
    reset_run(it, 1);
    {
        lb none = {NULL, 0};
        int r;
        while ((r = step(it, &none)) >= 0)
            if (r == 1)
                it->stats.lines++;
    }
    it->stats.input_segments = js.input_segments;
    if (it->xs_path != (size_t)-1)
        return xs_fail(it, err);
    it->est = it->stats;
    it->magic = GC_MAGIC;
    return amp_gcode_iter_rewind(it, err);
}

amp_status amp_gcode_iter_init_body(amp_gcode_iter *it, const amp_pathset *ps, const amp_gcode_opts *o,
                                    amp_error *err)
{
    job_scan js;
    amp_status st = prepare(it, ps, o, &js, err);
    if (st != AMP_OK)
        return st;
    it->body_only = 1;
    it->magic = GC_MAGIC;
    return amp_gcode_iter_rewind(it, err);
}

amp_status amp_gcode_iter_rewind(amp_gcode_iter *it, amp_error *err)
{
    if (!it)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: NULL iterator");
    if (it->magic != GC_MAGIC)
        return amp_fail(err, AMP_ERR_STATE, 0, "gcode: iterator not initialised (or init failed)");
    /* pass 2 from its start: the placement, the grid's frame and the figures of pass 1 (it->est) stay */
    reset_run(it, 2);
    it->stats.input_segments = it->est.input_segments;
    return AMP_OK;
}

/* ---------------------------------------------------------------- moves */

static void set_last(amp_gcode_iter *it, int kind, amp_vec3 to, double e, double feed, double r, double len)
{
    it->last.kind = kind;
    it->last.path = it->path;
    it->last.seg = it->seg;
    it->last.to = amp_v3_add(to, it->off);
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

/* A model coordinate as written: placed on the bed (docs/interfaces.md §5). */
static void put_coord(amp_gcode_iter *it, lb *l, char axis, double v)
{
    double off = axis == 'X' ? it->off.x : axis == 'Y' ? it->off.y : it->off.z;
    lb_num(l, axis, v + off, 3);
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
    amp_gc_plan_single(it, it->o.retract_length, v);
    set_last(it, MOVE_E, it->pos, (double)(sign * ru) * 1e-5, feed, 0.0, 0.0);
}

/* A G0 to @p to (model coordinates) with the axes that change; z is capped at the bed's height. */
static void move_travel(amp_gcode_iter *it, lb *l, amp_vec3 to, int xy, double v)
{
    /* have_pos: 0 = unknown (after homing), 1 = only z known, 2 = known */
    double len, feed;
    int z;
    to.z = fmin(to.z, it->zmax);
    z = it->have_pos == 0 || to.z != it->pos.z;
    len = it->have_pos == 2 ? amp_v3_dist(it->pos, to) : 0.0;
    lb_str(l, "G0");
    if (xy) {
        put_coord(it, l, 'X', to.x);
        put_coord(it, l, 'Y', to.y);
    }
    if (z)
        put_coord(it, l, 'Z', to.z);
    if (!xy) /* a lift or descent: at the z axis' speed */
        v = fmin(v, it->o.max_feed_z);
    feed = put_feed(it, l, llround(v * 600.0));
    it->stats.travel_length += len;
    it->stats.travel_moves++;
    /* the planner clamps the z component to max_feed_z as firmware does */
    if (it->have_pos == 2)
        amp_gc_plan_move(it, amp_v3_sub(to, it->pos), len, feed, 0.0, 1);
    if (z && to.z + it->off.z > it->stats.max_travel_z)
        it->stats.max_travel_z = to.z + it->off.z;
    it->pos = to;
    it->have_pos = it->have_pos == 2 || xy ? 2 : 1;
    set_last(it, MOVE_TRAVEL, to, 0.0, feed, 0.0, len);
}

/* Raise the material grid by the bead of segment v[a] -> v[b] of path @p p. */
static void raise_material(amp_gcode_iter *it, const amp_path *p, const amp_pvert *va, const amp_pvert *vb, int parts)
{
    double r = fmax(va->r, vb->r);
    /* a planar bead's top is its vertex z (layer top); a tube rises r above its centre line */
    double top = fmax(va->p.z, vb->p.z) + (p->h > 0.0 ? 0.0 : r);
    /* and the centre line, for the head cone of direct hops (the model of [P1 §5.1] and `ampath check`) */
    grid_raise(it, va->p, vb->p, r > 0.0 ? r : 0.0, 0.0, top, fmax(va->p.z, vb->p.z), parts);
    if (parts & GR_CENTRE) {
        it->zc_max = fmax(it->zc_max, fmax(va->p.z, vb->p.z));
        it->end_r = vb->r;
    }
}

/*
 * Raise the material grid by the bead written over input vertices k..j with
 * cross-section @p area. A tube's bead as written is fatter than the input's
 * (the chord is shorter than the segments it replaces, and E keeps their
 * volume) and lies within chord_tol of them: its top is taken as the input's
 * with the radius read back from E and chord_tol added, so that travels
 * clear what the G-code really deposits (a reader of the G-code sees that bead).
 */
static void raise_written(amp_gcode_iter *it, const amp_path *p, const amp_pvert *v, size_t k, size_t j, double area,
                          int straight, int parts)
{
    double re = p->h > 0.0 ? 0.0 : sqrt(area / AMP_PI) + it->o.chord_tol;
    size_t m;
    if (straight && p->h > 0.0 && j > k + 1) {
        /* a planar chord over several input segments (a straight line of the lattice: a third of the twisted
         * bridge's segments): one raise along the chord, widened by the farthest its input strays from it
         * (measured: chord_tol, or more where min_segment grew the chord), with the widest bead and the
         * highest top among its vertices */
        double d2 = 0.0, rmax = 0.0, zmax = -HUGE_VAL, dev;
        amp_vec3 a = v[k].p, b = v[j].p;
        for (m = k; m <= j; m++) {
            double ex = v[m].p.x, ey = v[m].p.y, e2 = amp_v3_seg_dist2(amp_v3(ex, ey, 0.0), amp_v3(a.x, a.y, 0.0),
                                                                     amp_v3(b.x, b.y, 0.0), NULL);
            d2 = e2 > d2 ? e2 : d2;
            rmax = v[m].r > rmax ? v[m].r : rmax;
            zmax = v[m].p.z > zmax ? v[m].p.z : zmax;
        }
        dev = sqrt(d2);
        grid_raise(it, a, b, rmax > 0.0 ? rmax + dev : 0.0, dev, zmax, zmax, parts);
        if (parts & GR_CENTRE) {
            it->zc_max = fmax(it->zc_max, zmax);
            it->end_r = v[j].r;
        }
        return;
    }
    for (m = k; m < j; m++) {
        amp_pvert a = v[m], b = v[m + 1];
        if (p->h <= 0.0 && (a.r > 0.0 || b.r > 0.0)) {
            a.r = fmax(a.r, re);
            b.r = fmax(b.r, re);
        }
        raise_material(it, p, &a, &b, parts);
    }
}

/*
 * Deferred material bands (it->band_lazy: a planar job printed layer by
 * layer, as `slice` writes it). There every later travel starts on a layer at
 * least as high as the material printed so far and rises or stays level, and
 * the material grid is only ever compared with heights on that travel's line
 * (travel_hull) or at its nozzle away from the ends (direct_ok): a bead of a
 * lower layer can never change an answer. So a written segment raises only
 * the centre-line grid when printed; the segments since the last raise are
 * the range from (band_path, band_seg) to the path being travelled to, with
 * the highest top band_top, and a read at a height below band_top raises the
 * range first (band_flush: the same moves again), while the first segment of
 * a higher layer drops it. Every read answers as if all had been raised (the
 * G-code is the same; tests/test_gcode.c compares it with the eager grid's), and
 * a part with one island a layer raises no band at all (the bands were a
 * fifth of `gcode`'s time on PrusaSlicer's bunny, in both passes).
 */
static void band_defer(amp_gcode_iter *it, double top, size_t k)
{
    float ft = float_up(top);
    /* 1e-6 below: every later read height is at least this segment's z, up to rounding (amp_v3_lerp) */
    if (it->band_pending && (double)it->band_top < top - 1e-6)
        it->band_pending = 0;
    if (!it->band_pending) {
        it->band_pending = 1;
        it->band_path = it->path;
        it->band_seg = k;
        it->band_top = ft;
    } else if (ft > it->band_top) {
        it->band_top = ft;
    }
}

/* Raise the deferred bands (band_defer) before a read at height @p z that they may reach above. */
static void band_need(amp_gcode_iter *it, double z)
{
    size_t q, k;
    if (!it->band_pending || !((double)it->band_top > z))
        return;
    for (q = it->band_path, k = it->band_seg; q < it->path; q++, k = 0) {
        const amp_path *p = &it->ps->paths[q];
        const amp_pvert *v = amp_pathset_path_verts(it->ps, q);
        while (k + 1 < p->n && next_segment(it->ps, q, k) + 1 < p->n) { /* print_step's moves */
            amp_gc_arc arc;
            int use_arc;
            size_t j = next_move(it, q, k, &arc, &use_arc);
            raise_written(it, p, v, k, j, 0.0 /* planar: the area only sizes tubes */, !use_arc, GR_BAND);
            k = j;
        }
    }
    it->band_pending = 0;
}

/*
 * The written segment from vertex k to vertex j of the current path (docs/interfaces.md §5,
 * clean segments): a straight G1, or with @p arc a G2/G3 along it.
 */
static void move_print(amp_gcode_iter *it, lb *l, size_t k, size_t j, const amp_gc_arc *arc)
{
    const amp_path *p = &it->ps->paths[it->path];
    const amp_pvert *v = amp_pathset_path_verts(it->ps, it->path);
    amp_vec3 a = v[k].p, b = v[j].p, d = amp_v3_sub(b, a);
    double len = arc ? arc->len : amp_v3_len(d), vol = 0.0, de, feed, area;
    double base = it->path_first ? it->o.first_layer_feed : it->o.print_feed;
    long long fu = llround(base * 600.0);
    size_t m;
    /* E = flow * sum A L / (pi (d/2)^2) over the input segments replaced: the volume stays exact */
    for (m = k; m < j; m++)
        vol += amp_bead_area(0.5 * (v[m].r + v[m + 1].r), p->h) * amp_v3_dist(v[m].p, v[m + 1].p);
    de = it->o.flow * vol / it->fil_area;
    area = len > 0.0 ? vol / len : 0.0;
    /* the cross-section the firmware reads off the line: E over the XYZ length (Klipper checks moves with XY) */
    if (it->o.flavor == AMP_FLAVOR_KLIPPER && it->o.max_cross_section > 0.0 && it->xs_path == (size_t)-1 &&
        len > 0.0 && (d.x != 0.0 || d.y != 0.0) &&
        de * it->fil_area / len > it->o.max_cross_section * (1.0 - 1e-6)) {
        it->xs_path = it->path;
        it->xs_area = de * it->fil_area / len;
    }
    if (it->band_lazy) {
        band_defer(it, fmax(a.z, b.z), k);
        raise_written(it, p, v, k, j, area, arc == NULL, GR_CENTRE);
    } else {
        raise_written(it, p, v, k, j, area, arc == NULL, GR_BAND | GR_CENTRE);
    }
    if (area * base > it->o.max_volumetric_flow) {
        /* volumetric cap: lower the feed, rounded down so that the printed F respects the cap */
        fu = (long long)floor(it->o.max_volumetric_flow / area * 600.0);
        if (fu < 1)
            fu = 1;
        it->stats.lowered_feed_segments++;
    }
    lb_str(l, arc ? (arc->cw ? "G2" : "G3") : "G1");
    put_coord(it, l, 'X', b.x);
    put_coord(it, l, 'Y', b.y);
    /* Z only where it changes as written (modal, as slicers write it: a planar layer's lines stay short) */
    if (it->have_pos != 2 || units_of(b.z + it->off.z, 1e3) != units_of(it->pos.z + it->off.z, 1e3))
        put_coord(it, l, 'Z', b.z);
    if (arc) { /* the centre relative to the start, as G2/G3 take it */
        lb_num(l, 'I', arc->cx - a.x, 3);
        lb_num(l, 'J', arc->cy - a.y, 3);
        it->stats.arcs++;
    }
    it->e_exact += de;
    put_e(it, l);
    feed = put_feed(it, l, fu);
    it->stats.segments++;
    it->stats.print_length += len;
    it->stats.filament_length += de;
    it->stats.filament_volume += de * it->fil_area;
    it->stats.bead_volume += vol;
    if (de > 0.0 && !it->printed_any)
        it->stats.first_layer_z = fmin(a.z, b.z) + it->off.z;
    it->stats.bbox = amp_box3_add(amp_box3_add(it->stats.bbox, amp_v3_add(a, it->off)), amp_v3_add(b, it->off));
    if (it->path_first) /* for the start G-code's first_layer_print_min/max (printer.h) */
        it->stats.first_layer_bbox = amp_box3_add(amp_box3_add(it->stats.first_layer_bbox, amp_v3_add(a, it->off)),
                                                  amp_v3_add(b, it->off));
    /* an arc enters the planner as one block of its length along its chord */
    amp_gc_plan_move(it, arc && amp_v3_len(d) > 0.0 ? amp_v3_scale(d, len / amp_v3_len(d)) : d, len, feed, de, 0);
    it->pos = b;
    if (de > 0.0)
        it->printed_any = 1;
    set_last(it, MOVE_PRINT, b, de, feed, len > 0.0 ? sqrt(area / AMP_PI) : 0.0, len);
}

/* the gap from (px, py) to a square's edge along one axis (0 inside); ternaries, not fmax: the library call
 * was a sixth of `gcode`'s time, and no operand is ever NaN */
static inline double axis_gap(double p, double x0, double side)
{
    double a = x0 - p, b = p - (x0 + side), d = a > b ? a : b;
    return d > 0.0 ? d : 0.0;
}

static inline double rect_dist2(double px, double py, double x0, double y0, double side)
{
    double dx = axis_gap(px, x0, side), dy = axis_gap(py, y0, side);
    return dx * dx + dy * dy;
}


/* May a block of centre-line height @p c at squared distance @p d2 raise the floor above @p lo? No when the
 * cone's run over the distance exceeds the room by a clear margin (the exact formula would not raise lo
 * either, and its square root is skipped). */
static inline int may_raise(double c, double d2, double k, double zo, double hh, double lo)
{
    double room = c - zo + k * hh - lo;
    return room > 0.0 && !(k * k * d2 > room * room * (1.0 + 1e-6) + 1e-12);
}

/*
 * The lowest nozzle height over the interval of half-width @p hh around
 * (@p px, @p py) whose head cone (docs/interfaces.md §2: tip z_offs above the nozzle,
 * half-angle theta; [P1 §5.1]) clears every printed centre line — the
 * criterion Algorithm 2 and `ampath check` apply to printing points — at
 * least @p lo; the search stops once it passes @p stop. Each centre-line
 * point lies in a cell of grid_c holding at least its z and is no nearer than
 * that cell's rectangle. The max-pyramid grid_cp bounds every block of cells:
 * a block too low to matter at its distance is skipped whole, from the whole
 * grid down (the children nearer the point first), so the answer is the
 * maximum over the cells the exact formula would raise it at, as a scan of
 * every cell would give it (it was two thirds of the writer's time on the demo
 * with two fixed levels).
 */
static double cone_floor(const amp_gcode_iter *it, double px, double py, double hh, double lo, double stop)
{
    double k = 1.0 / tan(it->o.head_theta * AMP_PI / 180.0), cell = it->grid_cell;
    double zo = it->o.head_z_offs;
    int stack[3 * 4 * 16], top = 0, levels = 0, side;
    size_t off[16];
    if (it->zc_max - zo + k * hh <= lo)
        return lo;
    for (side = AMP_GCODE_GRID / 2; side >= 1; side /= 2) {
        levels++;
        off[levels] = pyramid_level(levels);
    }
    /* (level, x, y) from the top level (one block: the whole grid) down; level 0 is grid_c itself */
    stack[top++] = levels;
    stack[top++] = 0;
    stack[top++] = 0;
    while (top) {
        int y = stack[--top], x = stack[--top], l = stack[--top], n = AMP_GCODE_GRID >> l, q, cx[4], cy[4];
        double bs = cell * (double)(1 << l), c, d2[4];
        if (l == 0) {
            double d;
            c = (double)it->grid_c[y * AMP_GCODE_GRID + x];
            d = rect_dist2(px, py, it->grid_x0 + x * cell, it->grid_y0 + y * cell, cell);
            if (may_raise(c, d, k, zo, hh, lo)) {
                double v = c - zo - k * (sqrt(d) - hh);
                if (v > lo)
                    lo = v;
                if (lo > stop)
                    return lo;
            }
            continue;
        }
        c = (double)it->grid_cp[off[l] + (size_t)y * (size_t)n + (size_t)x];
        if (!may_raise(c, rect_dist2(px, py, it->grid_x0 + x * bs, it->grid_y0 + y * bs, bs), k, zo, hh, lo))
            continue;
        /* the four children, the farthest pushed first (the nearest is searched first and raises lo soonest) */
        for (q = 0; q < 4; q++) {
            cx[q] = 2 * x + (q & 1);
            cy[q] = 2 * y + (q >> 1);
            d2[q] = rect_dist2(px, py, it->grid_x0 + cx[q] * 0.5 * bs, it->grid_y0 + cy[q] * 0.5 * bs, 0.5 * bs);
        }
        for (q = 0; q < 4; q++) {
            int m, far = 0;
            for (m = 1; m < 4; m++)
                far = d2[m] > d2[far] ? m : far;
            stack[top++] = l - 1;
            stack[top++] = cx[far];
            stack[top++] = cy[far];
            d2[far] = -1.0;
        }
    }
    return lo;
}

static int cone_clear(const amp_gcode_iter *it, double px, double py, double z, double hh)
{
    return cone_floor(it, px, py, hh, z, z) <= z; /* from z up: blocks below the cone at z need no look */
}

/* The higher of @p z and the material top in the box of half-width @p w around (px, py) (band_need first). */
static double band_top_box(amp_gcode_iter *it, double px, double py, double w, double z)
{
    band_need(it, z);
    return fmax(grid_top_box(it, it->grid, px, py, w), z);
}

/*
 * The travel polyline from it->pos to it->travel_to (docs/interfaces.md §5: gouge-free,
 * as low as is safe): the upper convex hull, in (fraction of the line, z),
 * of the start and the end themselves, of the head-cone floor everywhere and,
 * away from the ends, of the material tops sampled along the line within the
 * corridor and the line between the ends, both + z_hop (over nothing it
 * travels straight at z-hop height). Within the bead radius and two grid cells of either end
 * (@p rb: the radius at the next path's start) the nozzle is in the bead it
 * leaves or in the place of the one it starts — the rule of the direct hops
 * (direct_ok) — so only the cone applies there: the head ramps up from the
 * end it leaves and down onto the start instead of lifting and descending
 * vertically (short travel: at the z axis' 10 mm/s the vertical lifts over
 * the beads' own tops were 40 % of the demo's travel time). With direct_hop 0
 * there are no end zones and the ends are lifted by z_hop (the old rule). Each sample's box
 * covers half a step either side, so its height holds over that interval;
 * the hull is the lowest polyline of straight moves above all of them.
 */
static void travel_hull(amp_gcode_iter *it, double rb)
{
    amp_vec3 a = it->pos, b = it->travel_to;
    double dx = b.x - a.x, dy = b.y - a.y, len = sqrt(dx * dx + dy * dy), hop = it->o.z_hop;
    int ramp = it->o.direct_hop > 0.0; /* direct_hop 0: every travel lifts vertically by z_hop over all material */
    double zs = ramp ? a.z : a.z + hop, ze = ramp ? b.z : b.z + hop, w, dt, cf = -HUGE_VAL;
    double ea = ramp ? it->end_r + 2.0 * it->grid_cell : -1.0, eb = ramp ? rb + 2.0 * it->grid_cell : -1.0;
    long steps = (long)ceil(len / (0.5 * it->grid_cell)), s, maxs = (AMP_GCODE_HULL - 4) / 2 - 1;
    size_t n = 0;
    if (steps < 1)
        steps = 1;
    if (steps > maxs)
        steps = maxs;
    w = it->o.travel_corridor + 0.5 * len / (double)steps;
    dt = 0.5 / (double)steps;
    it->travel_from = a;
    for (s = 0; s <= steps + 1; s++) {
        double t, z, tt[2];
        int q;
        if (s == steps + 1) { /* the end, then nothing more */
            t = 1.0;
            z = ze;
        } else {
            t = (double)s / (double)steps;
            /* the material tops count wherever the sample's interval reaches out of both end zones */
            z = (t + dt) * len > ea && (1.0 - t + dt) * len > eb
                    ? band_top_box(it, a.x + t * dx, a.y + t * dy, w, a.z + t * (b.z - a.z)) + hop
                    : -HUGE_VAL;
            if (s % GC_CONE_GROUP == 0) { /* one cone floor for the interval of the next samples */
                double tc = fmin(1.0, (s + 0.5 * (GC_CONE_GROUP - 1)) / (double)steps);
                /* from min(zs, ze) up: the hull of the ends is never lower */
                cf = cone_floor(it, a.x + tc * dx, a.y + tc * dy, (0.5 * GC_CONE_GROUP + 0.5) * len / (double)steps,
                                fmin(zs, ze), HUGE_VAL);
            }
            /* beyond the corridor: the head cone (docs/interfaces.md §2) clear of every printed centre line */
            z = fmax(z, cf);
            if (s == 0)
                zs = fmax(zs, z);
            if (s == steps)
                ze = fmax(ze, z);
            if (n == 0) {
                it->hull_t[0] = 0.0;
                it->hull_z[0] = fmin(zs, it->zmax);
                n = 1;
            }
            if (!(z > -HUGE_VAL))
                continue;
        }
        tt[0] = fmax(0.0, t - dt);
        tt[1] = fmin(1.0, t + dt);
        for (q = s == steps + 1 ? 1 : 0; q < 2; q++) {
            double pt = tt[q], pz = fmin(q == 1 && s == steps + 1 ? ze : z, it->zmax);
            /* monotone chain: drop corners that lie on or below the chord of their neighbours */
            while (n >= 2 && (it->hull_t[n - 1] - it->hull_t[n - 2]) * (pz - it->hull_z[n - 2]) -
                                     (it->hull_z[n - 1] - it->hull_z[n - 2]) * (pt - it->hull_t[n - 2]) >=
                                 -1e-6) /* float tops of the grid: 1 nm bumps are not corners */
                n--;
            if (n >= 1 && pt <= it->hull_t[n - 1]) { /* same fraction: keep the higher point */
                if (pz > it->hull_z[n - 1])
                    it->hull_z[n - 1] = pz;
                continue;
            }
            it->hull_t[n] = pt;
            it->hull_z[n] = pz;
            n++;
        }
    }
    it->hull_n = n;
    it->hull_i = 1;
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

/* "; printer NAME: bed ..": a long profile name (an exported .ini's file
 * name) is shortened so that the bed, which a reader checks the job
 * against, stays on the line. */
static int printer_line(lb *l, const amp_gcode_opts *o)
{
    char rest[AMP_GCODE_LINE_CAP + 1];
    lb r;
    const char *name = o->profile ? o->profile : "-";
    size_t room, n = strlen(name), i;
    if (!l->b)
        return 1;
    r.b = rest;
    r.n = 0;
    if (o->bed_radius > 0.0)
        lb_fmt(&r, ": round bed radius %f1 about (%f1, %f1), height %f1 mm", o->bed_radius,
               0.5 * (o->bed_min_x + o->bed_max_x), 0.5 * (o->bed_min_y + o->bed_max_y), o->max_height);
    else
        lb_fmt(&r, ": bed %f1..%f1 x %f1..%f1, height %f1 mm", o->bed_min_x, o->bed_max_x, o->bed_min_y,
               o->bed_max_y, o->max_height);
    lb_str(l, "; printer ");
    room = AMP_GCODE_LINE_MAX > l->n + r.n ? AMP_GCODE_LINE_MAX - l->n - r.n : 0;
    for (i = 0; i < n && i < room; i++)
        l->b[l->n++] = n > room && i + 3 >= room ? '.' : name[i];
    l->b[l->n] = '\0';
    lb_str(l, rest);
    return 1;
}

/* Header comment line @p k; returns 0 past the last one. */
static int header_line(amp_gcode_iter *it, lb *l, size_t k)
{
    const amp_gcode_stats *e = &it->est;
    const amp_gcode_opts *o = &it->o;
    unsigned long t = e->time > 0.0 ? (unsigned long)(e->time + 0.5) : 0;
    switch (k) {
    case 0: lb_str(l, "; generated by ampath " AMP_VERSION_STRING ": MDR-modulated extrusion (docs/interfaces.md §5)"); return 1;
    case 1: return printer_line(l, o);
    case 2:
        lb_fmt(l, "; flavor %s, %s E, filament %f3 mm, flow %f4", flavor_name(o->flavor),
               o->relative_e ? "relative" : "absolute", o->filament_diameter, o->flow);
        return 1;
    case 3:
        lb_fmt(l, "; placed %s, offset %f3 %f3 %f3 mm", o->place == AMP_PLACE_ORIGIN ? "as given" : "on the bed",
               it->off.x, it->off.y, it->off.z);
        return 1;
    case 4:
        lb_fmt(l, "; bounding box %f2..%f2 x %f2..%f2 x %f2..%f2", e->bbox.min.x, e->bbox.max.x, e->bbox.min.y,
               e->bbox.max.y, e->bbox.min.z, e->bbox.max.z);
        return 1;
    case 5:
        lb_fmt(l, "; estimated print time %u s (%u:%z:%z), moves only", t, t / 3600, t / 60 % 60, t % 60);
        return 1;
    case 6: lb_fmt(l, "; filament used %f1 mm (%f1 mm3)", e->filament_length, e->filament_volume); return 1;
    case 7:
        lb_fmt(l, "; paths %u (%u skipped), %u segments of %u, %f1 mm printed", (unsigned long)e->paths,
               (unsigned long)e->paths_skipped, (unsigned long)e->segments, (unsigned long)e->input_segments,
               e->print_length);
        return 1;
    case 8:
        lb_fmt(l, "; travels %u (%f1 mm), retractions %u, lines %u", (unsigned long)e->travels, e->travel_length,
               (unsigned long)e->retractions, (unsigned long)e->lines);
        return 1;
    default: return 0;
    }
}

/* "CMD S<t> ; note" for a temperature. */
static int temp_line(lb *l, const char *cmd, double t, const char *note)
{
    lb_str(l, cmd);
    lb_num(l, 'S', t, 1);
    lb_str(l, note);
    return 1;
}

/* Built-in start sequence line @p k (lines skipped for an unheated bed or hot end); -1 past the end. */
static int builtin_start(amp_gcode_iter *it, lb *l, size_t k)
{
    const amp_gcode_opts *o = &it->o;
    double bed = o->first_layer_bed_temp, hot = o->first_layer_hotend_temp;
    switch (k) {
    case 0: return bed > 0.0 ? temp_line(l, "M140", bed, " ; bed") : 0;
    case 1: return hot > 0.0 ? temp_line(l, "M104", hot, " ; hot end") : 0;
    case 2: lb_str(l, "G28 ; home all axes"); return 1;
    case 3: return bed > 0.0 ? temp_line(l, "M190", bed, " ; wait for the bed") : 0;
    case 4: return hot > 0.0 ? temp_line(l, "M109", hot, " ; wait for the hot end") : 0;
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
        n = text_len(s, n);
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

/* Does the caller's sequence command any of the codes in @p codes (e.g. "M109", "M104")? */
static int text_has(const char *text, const char *c1, const char *c2)
{
    const char *s;
    for (s = text; *s; s++) {
        if ((s == text || s[-1] == '\n' || s[-1] == ' ') &&
            (strncmp(s, c1, strlen(c1)) == 0 || strncmp(s, c2, strlen(c2)) == 0)) {
            char c = s[strlen(c1)];
            if (c == ' ' || c == '\0' || c == '\n' || c == '\r' || c == ';')
                return 1;
        }
        if (*s == ';') /* the rest of the line is a comment */
            while (s[1] && s[1] != '\n')
                s++;
    }
    return 0;
}

/*
 * A caller's start sequence, wrapped like PrusaSlicer does it: without a bed
 * temperature command it is preceded by M190 (first-layer bed), without a
 * hot-end one by M104 and followed by M109 (first-layer hot end).
 */
static int start_line(amp_gcode_iter *it, lb *l)
{
    const amp_gcode_opts *o = &it->o;
    switch (it->sub) {
    case ST_BED_WAIT:
        it->sub = ST_HOT_SET;
        if (o->first_layer_bed_temp > 0.0 && !text_has(o->start_gcode, "M190", "M140"))
            return temp_line(l, "M190", o->first_layer_bed_temp, " ; wait for the bed");
        return 0;
    case ST_HOT_SET:
        it->sub = ST_TEXT;
        if (o->first_layer_hotend_temp > 0.0 && !text_has(o->start_gcode, "M109", "M104"))
            return temp_line(l, "M104", o->first_layer_hotend_temp, " ; hot end");
        return 0;
    case ST_TEXT:
        if (text_line(it, l))
            return 1;
        it->sub = ST_HOT_WAIT;
        return 0;
    case ST_HOT_WAIT:
        it->sub = ST_DONE;
        if (o->first_layer_hotend_temp > 0.0 && !text_has(o->start_gcode, "M109", "M104"))
            return temp_line(l, "M109", o->first_layer_hotend_temp, " ; wait for the hot end");
        return 0;
    default: return -1;
    }
}

/* Set-up line @p k: 1 written, 0 skipped for this flavor or job, -1 past the end. */
static int setup_line(amp_gcode_iter *it, lb *l, size_t k)
{
    int klipper = it->o.flavor == AMP_FLAVOR_KLIPPER;
    switch (k) {
    case 0: if (klipper) return 0; lb_str(l, "G21 ; millimetres"); return 1; /* Klipper knows no G20/G21 */
    case 1: lb_str(l, "G90 ; absolute XYZ"); return 1;
    case 2: lb_str(l, it->o.relative_e ? "M83 ; relative E" : "M82 ; absolute E"); return 1;
    case 3: lb_str(l, "G92 E0"); return 1;
    case 4:
        lb_str(l, klipper ? "SET_VELOCITY_LIMIT ACCEL=" : "M204 S");
        lb_fixed(l, 0, units_of(it->o.accel, 10.0), 1);
        lb_str(l, " ; acceleration");
        return 1;
    case 5: if (it->o.fan_speed <= 0.0) return 0; lb_str(l, "M107 ; part-cooling fan off for the first layers"); return 1;
    default: return -1;
    }
}

/* ---------------------------------------------------------------- the state machine */

/*
 * Classify the path that starts (docs/interfaces.md §5 first layer): first-layer or not,
 * and its layer for the fan. Planar jobs know their layers from the bead z;
 * tubes count layers of first_layer_height from the bed.
 */
static void begin_path(amp_gcode_iter *it, const amp_path *p, const amp_pvert *v)
{
    double zmin = HUGE_VAL, bottom = HUGE_VAL;
    size_t k;
    for (k = 0; k < p->n; k++) {
        zmin = fmin(zmin, v[k].p.z);
        bottom = fmin(bottom, v[k].p.z - bead_depth(p, v[k].r));
    }
    bottom += it->off.z;
    if (p->h > 0.0) {
        it->path_first = zmin <= it->z_first + 1e-6;
        if (zmin > it->layer_z + 1e-6) {
            it->layer++;
            it->layer_z = zmin;
        }
        it->path_layer = it->layer;
    } else {
        long lay = (long)floor(bottom / it->o.first_layer_height + 1e-9);
        it->path_first = bottom < it->o.first_layer_height - 1e-6;
        it->path_layer = lay < 0 ? 0 : (lay > 100000 ? 100000 : (int)lay);
        if (it->path_layer > it->layer)
            it->layer = it->path_layer;
    }
    if ((size_t)it->layer + 1 > it->stats.layers) /* total_layer_count of the printer macros */
        it->stats.layers = (size_t)it->layer + 1;
}

/*
 * May the travel to the start of the next path (radius @p rb) be a direct hop:
 * one straight move, no retraction, no lift (slicers' travel without z-hop
 * inside the part)? When it is at most direct_hop long and at every point the
 * head cone is clear (cone_clear) and, away from its ends, no printed
 * material rises above the nozzle, whatever it rises or falls (the lifted
 * travels ramp through their end zones on the cone test too: a band would only cost).
 * Within the bead radius and two grid cells
 * of either end the nozzle is in the bead it leaves or in the place of the one
 * it starts, where the cone test alone applies (the grid's cells there hold
 * those beads' own tops).
 */
static int direct_ok(amp_gcode_iter *it, double dxy, double rb)
{
    amp_vec3 a = it->pos, b = it->travel_to;
    double cell = it->grid_cell, hh, dz;
    double ea = it->end_r + 2.0 * cell, eb = rb + 2.0 * cell;
    long steps = (long)ceil(dxy / (0.5 * cell)), s;
    /* any rise or fall: the end zones are left to the cone test as in travel_hull's ramps */
    if (!(dxy <= it->o.direct_hop) || !it->printed_any || it->have_pos != 2)
        return 0;
    if (steps < 1)
        steps = 1;
    hh = 0.5 * dxy / (double)steps;
    dz = 0.5 * fabs(b.z - a.z) / (double)steps;
    for (s = 0; s <= steps; s++) {
        double t = (double)s / (double)steps;
        amp_vec3 p = amp_v3_lerp(a, b, t);
        double zlo = p.z - dz; /* lowest nozzle height of the interval */
        if (!cone_clear(it, p.x, p.y, zlo, hh))
            return 0;
        if (t * dxy - hh >= ea && (1.0 - t) * dxy - hh >= eb && band_top_box(it, p.x, p.y, hh, zlo) > zlo)
            return 0;
    }
    return 1;
}

/* Decide the travel to the current path; 0 when the path starts where the head is (no travel). */
static int plan_travel(amp_gcode_iter *it, const amp_pvert *v)
{
    double dxy;
    it->travel_to = v[0].p;
    if (it->have_pos == 2 && amp_v3_dist(it->pos, it->travel_to) <= GC_MIN_SEG)
        return 0;
    it->stats.travels++;
    dxy = it->have_pos == 2 ? hypot(it->travel_to.x - it->pos.x, it->travel_to.y - it->pos.y) : HUGE_VAL;
    /* short hops need no retraction (PrusaSlicer's retract_before_travel) */
    it->travel_retract = it->printed_any && it->o.retract_length > 0.0 && !it->retracted &&
                         dxy >= it->o.retract_min_travel;
    it->direct = direct_ok(it, dxy, v[0].r);
    if (it->direct) { /* straight from end to start, the pressure kept */
        it->stats.direct_hops++;
        it->travel_retract = 0;
        it->travel_from = it->pos;
        it->hull_t[0] = 0.0;
        it->hull_z[0] = it->pos.z;
        it->hull_t[1] = 1.0;
        it->hull_z[1] = it->travel_to.z;
        it->hull_n = 2;
        it->hull_i = 1;
    } else if (it->printed_any && it->have_pos == 2) {
        travel_hull(it, v[0].r);
    } else { /* the first approach: lift above the start, move, descend */
        double zt = fmin(fmax(it->travel_to.z, it->have_pos ? it->pos.z : it->travel_to.z) + it->o.z_hop, it->zmax);
        it->travel_from = it->have_pos == 2 ? it->pos : it->travel_to;
        it->hull_t[0] = 0.0;
        it->hull_z[0] = zt;
        it->hull_t[1] = 1.0;
        it->hull_z[1] = zt;
        it->hull_n = 2;
        it->hull_i = 1;
    }
    return 1;
}

/* One line (or none) of a path: the per-path sub-steps in order. */
/* The comment that opens a path; a path without a segment of non-zero length is skipped. */
static int path_comment(amp_gcode_iter *it, lb *l, const amp_path *p, const amp_pvert *v)
{
    int skip;
    it->seg = next_segment(it->ps, it->path, 0);
    skip = it->seg + 1 >= p->n;
    lb_fmt(l, "; path %u %s %u vertices%s", (unsigned long)it->path,
           p->role == AMP_ROLE_SUPPORT ? "support" : "object", (unsigned long)p->n,
           skip ? " (skipped: no segment of non-zero length)" : "");
    if (skip) {
        it->stats.paths_skipped++;
        it->path++;
        return 1;
    }
    it->seg = 0;
    it->stats.paths++;
    begin_path(it, p, v);
    it->sub = PS_HOTEND;
    return 1;
}

/* Above the first layer: the other layers' temperatures, once; the part-cooling fan for every path from its
 * layer on. A volumetric job may print a path on the bed after higher ones (Algorithm 2 orders by the head
 * cone, not by height): the fan goes off for it and on again after, as it is off for the first layers. */
static int layer_settings(amp_gcode_iter *it, lb *l)
{
    const amp_gcode_opts *o = &it->o;
    switch (it->sub) {
    case PS_HOTEND:
        it->sub = PS_BED;
        if (!it->path_first && !it->first_done && o->hotend_temp > 0.0 && o->hotend_temp != o->first_layer_hotend_temp)
            return temp_line(l, "M104", o->hotend_temp, " ; hot end after the first layer");
        return 0;
    case PS_BED:
        it->sub = PS_FAN;
        if (!it->path_first && !it->first_done) {
            it->first_done = 1;
            if (o->bed_temp > 0.0 && o->bed_temp != o->first_layer_bed_temp)
                return temp_line(l, "M140", o->bed_temp, " ; bed after the first layer");
        }
        return 0;
    default: /* PS_FAN */
        it->sub = PS_PLAN;
        if (!it->fan_on && o->fan_speed > 0.0 && it->path_layer >= o->fan_off_layers) {
            it->fan_on = 1;
            lb_str(l, "M106");
            lb_fixed(l, 'S', llround(o->fan_speed * 255.0), 0);
            lb_str(l, " ; part-cooling fan");
            return 1;
        }
        if (it->fan_on && it->path_layer < o->fan_off_layers) {
            it->fan_on = 0;
            lb_str(l, "M107 ; part-cooling fan off: this path lies in the first layers");
            return 1;
        }
        return 0;
    }
}

/* The travel to the path's start: plan, retract, lift, the hull's hops, descend, unretract. */
static int travel_step(amp_gcode_iter *it, lb *l, const amp_pvert *v)
{
    const amp_gcode_opts *o = &it->o;
    switch (it->sub) {
    case PS_PLAN:
        it->sub = plan_travel(it, v) ? PS_RETRACT : PS_SEGS;
        return 0;
    case PS_RETRACT:
        it->sub = PS_ERESET;
        if (it->travel_retract) {
            move_e(it, l, -1);
            return 1;
        }
        return 0;
    case PS_ERESET:
        it->sub = PS_LIFT;
        if ((it->e_units < 0 ? -it->e_units : it->e_units) >= GC_E_RESET_UNITS) {
            /* the E written from here on counts from 0; the moves' E are the same */
            lb_str(l, "G92 E0");
            it->e_exact -= (double)it->e_units * 1e-5;
            it->e_units = 0;
            return 1;
        }
        return 0;
    case PS_LIFT:
        it->sub = PS_HULL;
        if (!it->have_pos || fmin(it->hull_z[0], it->zmax) > it->pos.z) {
            amp_vec3 to = it->have_pos ? it->pos : it->travel_to;
            to.z = it->hull_z[0];
            move_travel(it, l, to, 0, o->travel_feed);
            return 1;
        }
        return 0;
    case PS_HULL:
        if (it->hull_i < it->hull_n) {
            double t = it->hull_t[it->hull_i];
            amp_vec3 to = amp_v3_lerp(it->travel_from, it->travel_to, t);
            if (it->hull_i + 1 == it->hull_n)
                to = it->travel_to; /* exactly the path's start in XY */
            to.z = it->hull_z[it->hull_i++];
            move_travel(it, l, to, 1, o->travel_feed);
            return 1;
        }
        it->sub = PS_DESCEND;
        return 0;
    case PS_DESCEND:
        it->sub = PS_UNRETRACT;
        if (it->pos.z != it->travel_to.z) {
            move_travel(it, l, it->travel_to, 0, o->travel_feed);
            return 1;
        }
        return 0;
    default: /* PS_UNRETRACT */
        it->sub = PS_SEGS;
        if (!it->direct) /* the head stops where it lands (an unretract usually sits there); a direct hop flows on */
            amp_gc_plan_flush(it);
        if (it->retracted) {
            move_e(it, l, +1);
            return 1;
        }
        return 0;
    }
}

/* One printing move (a segment, or a fitted arc over several); at the path's end, on to the next path. */
static int print_step(amp_gcode_iter *it, lb *l, const amp_path *p)
{
    /* it->seg is the vertex the head is at */
    if (it->seg + 1 < p->n && next_segment(it->ps, it->path, it->seg) + 1 < p->n) {
        amp_gc_arc arc;
        int use_arc;
        it->nxt = next_move(it, it->path, it->seg, &arc, &use_arc);
        move_print(it, l, it->seg, it->nxt, use_arc ? &arc : NULL);
        it->seg = it->nxt;
        return 1;
    }
    it->path++;
    it->sub = PS_COMMENT;
    return 0;
}

static int step_path(amp_gcode_iter *it, lb *l)
{
    const amp_path *p = &it->ps->paths[it->path];
    const amp_pvert *v = amp_pathset_path_verts(it->ps, it->path);
    switch (it->sub) {
    case PS_COMMENT:
        return path_comment(it, l, p, v);
    case PS_HOTEND:
    case PS_BED:
    case PS_FAN:
        return layer_settings(it, l);
    case PS_PLAN:
    case PS_RETRACT:
    case PS_ERESET:
    case PS_LIFT:
    case PS_HULL:
    case PS_DESCEND:
    case PS_UNRETRACT:
        return travel_step(it, l, v);
    default:
        return print_step(it, l, p);
    }
}

/* Retraction, lift (capped at the bed's height) and the fan off before the end sequence. */
static int step_teardown(amp_gcode_iter *it, lb *l)
{
    switch (it->sub++) {
    case 0:
        if (it->o.retract_length > 0.0 && !it->retracted) {
            move_e(it, l, -1);
            return 1;
        }
        return 0;
    case 1:
        if (it->o.end_lift > 0.0 && it->pos.z < it->zmax) {
            amp_vec3 to = it->pos;
            to.z += it->o.end_lift;
            move_travel(it, l, to, 0, it->o.travel_feed);
            return 1;
        }
        return 0;
    case 2:
        if (it->fan_on) {
            lb_str(l, "M107 ; part-cooling fan off");
            return 1;
        }
        return 0;
    default:
        amp_gc_plan_flush(it);
        it->phase = PH_END;
        it->sub = 0;
        it->text = it->o.end_gcode;
        return 0;
    }
}

/* Advance by one unit: 1 = a line was produced, 0 = state changed without a line, -1 = done. */
static int step(amp_gcode_iter *it, lb *l)
{
    int r;
    switch (it->phase) {
    case PH_HEADER:
        if (it->body_only ? 0 : it->pass == 1 ? it->sub < GC_HEADER_LINES : header_line(it, l, it->sub)) {
            it->sub++;
            return 1;
        }
        it->phase = PH_START;
        it->sub = 0;
        it->text = it->o.start_gcode;
        return 0;
    case PH_START:
        r = it->o.start_gcode ? start_line(it, l) : builtin_start(it, l, it->sub++);
        if (r > 0)
            return 1;
        if (r == 0)
            return 0; /* a skipped line */
        it->phase = PH_SETUP;
        it->sub = 0;
        return 0;
    case PH_SETUP:
        r = setup_line(it, l, it->sub++);
        if (r >= 0)
            return r;
        it->phase = PH_PATHS;
        it->sub = PS_COMMENT;
        it->path = 0;
        return 0;
    case PH_PATHS:
        if (it->path >= it->ps->npaths) {
            it->phase = PH_TEARDOWN;
            it->sub = 0;
            return 0;
        }
        return step_path(it, l);
    case PH_TEARDOWN: return step_teardown(it, l);
    case PH_END:
        r = it->o.end_gcode ? text_line(it, l) : builtin_end(l, it->sub++);
        if (r > 0)
            return 1;
        amp_gc_plan_flush(it);
        it->phase = PH_DONE;
        if (it->body_only) { /* the figures of the whole job, as pass 1 finds them (header lines included) */
            it->stats.lines += GC_HEADER_LINES;
            it->est = it->stats;
        }
        return 0;
    default: return -1;
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
        if (it->xs_path != (size_t)-1) /* only a body-only run gets here: init refused the job otherwise */
            return xs_fail(it, err);
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

amp_status amp_gcode_iter_write(amp_gcode_iter *it, amp_sink_fn sink, void *user, amp_gcode_stats *stats,
                                amp_error *err)
{
    char line[AMP_GCODE_LINE_CAP + 1];
    amp_status st;
    int r;
    if (!it || !sink)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: NULL iterator or sink");
    while ((r = amp_gcode_iter_next(it, line, AMP_GCODE_LINE_CAP, err)) == 1) {
        size_t n = strlen(line);
        line[n] = '\n';
        st = sink(user, line, n + 1);
        if (st != AMP_OK)
            return amp_fail(err, st, 0, "gcode: writing line %lu failed: %s", (unsigned long)it->stats.lines,
                            amp_strerror(st));
    }
    if (r < 0)
        return (amp_status)r;
    if (stats)
        *stats = it->stats;
    return AMP_OK;
}

amp_status amp_gcode_iter_header(amp_gcode_iter *it, amp_sink_fn sink, void *user, amp_error *err)
{
    char line[AMP_GCODE_LINE_CAP + 1];
    size_t k;
    if (!it || !sink)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: NULL iterator or sink");
    if (it->magic != GC_MAGIC)
        return amp_fail(err, AMP_ERR_STATE, 0, "gcode: iterator not initialised (or init failed)");
    if (it->body_only && it->est.lines == 0)
        return amp_fail(err, AMP_ERR_STATE, 0, "gcode: the header's figures are known once the body's last line is out");
    for (k = 0;; k++) {
        lb l;
        amp_status st;
        l.b = line;
        l.n = 0;
        line[0] = '\0';
        if (!header_line(it, &l, k))
            return AMP_OK;
        line[l.n] = '\n';
        st = sink(user, line, l.n + 1);
        if (st != AMP_OK)
            return amp_fail(err, st, 0, "gcode: writing header line %lu failed: %s", (unsigned long)k + 1,
                            amp_strerror(st));
    }
}

amp_status amp_gcode_write(const amp_pathset *ps, const amp_gcode_opts *o, amp_sink_fn sink, void *user,
                           amp_gcode_stats *stats, amp_error *err)
{
    amp_gcode_iter it;
    amp_status st;
    if (!sink)
        return amp_fail(err, AMP_ERR_ARG, 0, "gcode: NULL sink");
    st = amp_gcode_iter_init(&it, ps, o, err);
    return st != AMP_OK ? st : amp_gcode_iter_write(&it, sink, user, stats, err);
}
