/*
 * Reader of the printer/filament/print `.ini` files that PrusaSlicer,
 * SuperSlicer and OrcaSlicer export (docs/interfaces.md §5): `key = value` lines, the
 * slicers' own key names (OrcaSlicer's as aliases), the first value of a
 * multi-extruder list, C-style escapes in the G-code strings. Unknown keys
 * are collected, not fatal: a full slicer export has hundreds of keys that
 * only matter to a slicer. Every value is also kept as written for the
 * start/end G-code macros (printer_vars.c).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/printer.h"
#include "printer_internal.h"

enum {
    K_BED_SHAPE, K_MAX_HEIGHT, K_NOZZLE, K_FILAMENT, K_LAYER, K_FIRST_LAYER, K_TEMP, K_TEMP1, K_BED, K_BED1,
    K_RETRACT, K_RETRACT_SPEED, K_LIFT, K_BEFORE_TRAVEL, K_TRAVEL, K_PERIMETER, K_FIRST_SPEED, K_FAN_MIN, K_FAN_MAX,
    K_FAN_ALWAYS, K_FAN_OFF, K_COOLING, K_FLAVOR, K_START, K_END, K_ACCEL, K_FEED_X, K_FEED_Y, K_FEED_Z, K_FEED_E,
    K_ACC_X, K_ACC_Y, K_ACC_Z, K_ACC_E, K_ACC_RETRACT, K_VOLUMETRIC, K_MULTIPLIER, K_MODEL
};

static const struct {
    const char *key;
    int k;
} ini_keys[] = {
    {"bed_shape", K_BED_SHAPE}, {"printable_area", K_BED_SHAPE},
    {"max_print_height", K_MAX_HEIGHT}, {"printable_height", K_MAX_HEIGHT},
    {"nozzle_diameter", K_NOZZLE}, {"filament_diameter", K_FILAMENT},
    {"layer_height", K_LAYER}, {"first_layer_height", K_FIRST_LAYER}, {"initial_layer_print_height", K_FIRST_LAYER},
    {"temperature", K_TEMP}, {"nozzle_temperature", K_TEMP},
    {"first_layer_temperature", K_TEMP1}, {"nozzle_temperature_initial_layer", K_TEMP1},
    {"bed_temperature", K_BED}, {"hot_plate_temp", K_BED},
    {"first_layer_bed_temperature", K_BED1}, {"hot_plate_temp_initial_layer", K_BED1},
    {"retract_length", K_RETRACT}, {"retraction_length", K_RETRACT},
    {"retract_speed", K_RETRACT_SPEED}, {"retraction_speed", K_RETRACT_SPEED},
    {"retract_lift", K_LIFT}, {"z_hop", K_LIFT},
    {"retract_before_travel", K_BEFORE_TRAVEL}, {"retraction_minimum_travel", K_BEFORE_TRAVEL},
    {"travel_speed", K_TRAVEL},
    {"perimeter_speed", K_PERIMETER}, {"outer_wall_speed", K_PERIMETER},
    {"first_layer_speed", K_FIRST_SPEED}, {"initial_layer_speed", K_FIRST_SPEED},
    {"min_fan_speed", K_FAN_MIN}, {"fan_min_speed", K_FAN_MIN},
    {"max_fan_speed", K_FAN_MAX}, {"fan_max_speed", K_FAN_MAX},
    {"fan_always_on", K_FAN_ALWAYS},
    {"disable_fan_first_layers", K_FAN_OFF}, {"close_fan_the_first_x_layers", K_FAN_OFF},
    {"cooling", K_COOLING},
    {"gcode_flavor", K_FLAVOR},
    {"start_gcode", K_START}, {"machine_start_gcode", K_START},
    {"end_gcode", K_END}, {"machine_end_gcode", K_END},
    {"machine_max_acceleration_extruding", K_ACCEL}, {"default_acceleration", K_ACCEL},
    {"machine_max_feedrate_x", K_FEED_X}, {"machine_max_feedrate_y", K_FEED_Y},
    {"machine_max_feedrate_z", K_FEED_Z}, {"machine_max_feedrate_e", K_FEED_E},
    {"machine_max_acceleration_x", K_ACC_X}, {"machine_max_acceleration_y", K_ACC_Y},
    {"machine_max_acceleration_z", K_ACC_Z}, {"machine_max_acceleration_e", K_ACC_E},
    {"machine_max_acceleration_retracting", K_ACC_RETRACT},
    {"max_volumetric_speed", K_VOLUMETRIC}, {"filament_max_volumetric_speed", K_VOLUMETRIC},
    {"extrusion_multiplier", K_MULTIPLIER}, {"filament_flow_ratio", K_MULTIPLIER},
    {"printer_model", K_MODEL},
};

/* Settings that combine several keys, resolved after the whole file is read. */
typedef struct ini_ctx {
    double fan_min, fan_max, first_speed, perimeter;
    int fan_always, fan_always_seen, orca_fan, first_speed_pct, have_fan;
} ini_ctx;

static int key_id(const char *k, size_t n)
{
    size_t i;
    for (i = 0; i < sizeof ini_keys / sizeof ini_keys[0]; i++)
        if (strlen(ini_keys[i].key) == n && strncmp(ini_keys[i].key, k, n) == 0)
            return ini_keys[i].k;
    return -1;
}

/* The first number of a (comma- or semicolon-separated) value; *pct set when it ends with '%'. */
static int first_number(const char *v, size_t n, double *out, int *pct)
{
    char buf[64], *end;
    size_t k = 0;
    while (k < n && v[k] != ',' && v[k] != ';' && k + 1 < sizeof buf) {
        buf[k] = v[k];
        k++;
    }
    while (k > 0 && (buf[k - 1] == ' ' || buf[k - 1] == '"'))
        k--;
    buf[k] = '\0';
    *pct = k > 0 && buf[k - 1] == '%';
    if (*pct)
        buf[--k] = '\0';
    end = buf;
    while (*end == ' ' || *end == '"')
        end++;
    *out = strtod(end, &end);
    return k > 0 && *end == '\0' && isfinite(*out);
}

/* A decimal number up to @p stop or @p end (strtod alone would read "0x0" as hexadecimal); advances *s. */
static int dec_number(const char **s, const char *end, char stop, double *out)
{
    char buf[48], *e;
    size_t k = 0;
    while (*s < end && (**s == ' ' || **s == '"'))
        (*s)++;
    while (*s < end && **s != stop && **s != ',' && **s != 'x' && **s != 'X' && k + 1 < sizeof buf)
        buf[k++] = *(*s)++;
    while (k > 0 && (buf[k - 1] == ' ' || buf[k - 1] == '"'))
        k--;
    buf[k] = '\0';
    *out = strtod(buf, &e);
    return k > 0 && *e == '\0' && isfinite(*out);
}

/* The next "XxY" of a bed_shape value: 1, 0 at its end, -1 when malformed. */
static int bed_point(const char **s, const char *end, double *x, double *y)
{
    while (*s < end && (**s == ' ' || **s == ',' || **s == '"'))
        (*s)++;
    if (*s == end)
        return 0;
    if (!dec_number(s, end, 'x', x) || *s == end || (**s != 'x' && **s != 'X'))
        return -1;
    (*s)++;
    return dec_number(s, end, ',', y) ? 1 : -1;
}

/* bed_shape: 1 read, 0 malformed, -1 an outline that holds no rectangle about its centre (*fill: the share
 * of its bounding box it covers). */
#define BED_NOT_BOX (-1)

/* Side a-b of an outline and the box (cx +- hx, cy +- hy): 1 when it meets the box's open interior
 * (Liang-Barsky with strict bounds: a side along the box's edge does not). */
static int side_meets_box(const double a[2], const double b[2], const double c[2], const double h[2])
{
    double t0 = 0.0, t1 = 1.0;
    int k;
    for (k = 0; k < 2; k++) {
        double d = b[k] - a[k], lo = c[k] - h[k], hi = c[k] + h[k];
        if (d == 0.0) {
            if (!(a[k] > lo && a[k] < hi))
                return 0;
        } else {
            double u = (lo - a[k]) / d, w = (hi - a[k]) / d;
            t0 = fmax(t0, fmin(u, w));
            t1 = fmin(t1, fmax(u, w));
        }
    }
    return t0 < t1;
}

/* Does the box (c +- h) lie inside the outline of bed_shape value v? Its centre inside (even-odd) and no
 * side meeting its interior: then the outline's boundary does not enter it. */
static int box_inside(const char *v, size_t n, const double c[2], const double h[2])
{
    const char *s = v, *end = v + n;
    double p[2], first[2] = {0, 0}, prev[2] = {0, 0};
    int k, in = 0;
    for (k = 0;; k++) {
        int more = bed_point(&s, end, &p[0], &p[1]) == 1;
        if (!more) { /* the closing side */
            p[0] = first[0];
            p[1] = first[1];
        }
        if (k == 0) {
            first[0] = p[0];
            first[1] = p[1];
        } else {
            if (side_meets_box(prev, p, c, h))
                return 0;
            if ((prev[1] > c[1]) != (p[1] > c[1]) &&
                c[0] < prev[0] + (c[1] - prev[1]) * (p[0] - prev[0]) / (p[1] - prev[1]))
                in = !in;
        }
        if (!more)
            return in;
        prev[0] = p[0];
        prev[1] = p[1];
    }
}

/* The largest box of the outline's bounding-box proportions about its centre that lies inside it (bisection
 * of the scale); 0 when even a twentieth of the box does not fit (the centre on or outside the outline). */
static int inner_box(amp_printer *p, const char *v, size_t n)
{
    double c[2], h[2], half[2], lo = 0.0, hi = 1.0;
    int it;
    c[0] = 0.5 * (p->bed_min_x + p->bed_max_x);
    c[1] = 0.5 * (p->bed_min_y + p->bed_max_y);
    half[0] = 0.5 * (p->bed_max_x - p->bed_min_x);
    half[1] = 0.5 * (p->bed_max_y - p->bed_min_y);
    for (it = 0; it < 50; it++) {
        double m = 0.5 * (lo + hi);
        h[0] = m * half[0];
        h[1] = m * half[1];
        if (box_inside(v, n, c, h))
            lo = m;
        else
            hi = m;
    }
    if (lo < 0.05)
        return 0;
    p->bed_min_x = c[0] - lo * half[0];
    p->bed_max_x = c[0] + lo * half[0];
    p->bed_min_y = c[1] - lo * half[1];
    p->bed_max_y = c[1] + lo * half[1];
    return 1;
}

/*
 * bed_shape = 0x0,250x0,250x210,0x210: the bounding box of the outline, read in place. A delta's round bed
 * is a polygon of many corners (72 in exponent notation) about the box's centre: when every side of the
 * outline stays within 3 % of its farthest corner's distance from the centre (a regular 16-gon or finer),
 * the printable region is the disc inside it, its radius the nearest side's distance. Any other outline
 * that does not fill its box (a rectangle, corners repeated or not) is the largest box of its proportions
 * about its centre that fits inside it (cut corners: a box that misses them); none, as with a triangle
 * whose box's centre lies on its long side, and it is refused: its box would put a job half off the bed.
 */
static int bed_shape(amp_printer *p, const char *v, size_t n, double *fill)
{
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, x, y, cx, cy, dmin = HUGE_VAL, dmax = 0.0;
    double area = 0.0;
    const char *s = v, *end = v + n;
    amp_vec3 o = amp_v3(0, 0, 0), first = o, prev = o;
    int pts = 0, r, k;
    while ((r = bed_point(&s, end, &x, &y)) == 1) {
        x0 = x < x0 ? x : x0;
        x1 = x > x1 ? x : x1;
        y0 = y < y0 ? y : y0;
        y1 = y > y1 ? y : y1;
        pts++;
    }
    if (r < 0 || pts < 3)
        return 0;
    p->bed_min_x = x0;
    p->bed_min_y = y0;
    p->bed_max_x = x1;
    p->bed_max_y = y1;
    cx = 0.5 * (x0 + x1);
    cy = 0.5 * (y0 + y1);
    for (s = v, k = 0; bed_point(&s, end, &x, &y) == 1; k++) {
        amp_vec3 c = amp_v3(x - cx, y - cy, 0.0);
        dmax = fmax(dmax, amp_v3_len(c));
        if (k == 0)
            first = c;
        else { /* the side from the previous corner */
            dmin = fmin(dmin, sqrt(amp_v3_seg_dist2(o, prev, c, NULL)));
            area += prev.x * c.y - c.x * prev.y;
        }
        prev = c;
    }
    dmin = fmin(dmin, sqrt(amp_v3_seg_dist2(o, prev, first, NULL))); /* the closing side */
    area = 0.5 * fabs(area + prev.x * first.y - first.x * prev.y);
    p->bed_radius = pts >= 8 && dmin >= 0.97 * dmax ? dmin : 0.0;
    *fill = (x1 > x0 && y1 > y0) ? area / ((x1 - x0) * (y1 - y0)) : 0.0;
    if (p->bed_radius > 0.0 || *fill >= 0.999)
        return 1;
    return inner_box(p, v, n) ? 1 : BED_NOT_BOX;
}

/* A G-code string with the slicers' C-style escapes; surrounding double quotes are removed. */
static amp_status gcode_string(char *dst, size_t cap, const char *v, size_t n, long line, amp_error *err)
{
    size_t i, o = 0;
    if (n >= 2 && v[0] == '"' && v[n - 1] == '"') {
        v++;
        n -= 2;
    }
    for (i = 0; i < n; i++) {
        char c = v[i];
        if (c == '\\' && i + 1 < n) {
            char e = v[++i];
            c = e == 'n' ? '\n' : e == 'r' ? '\r' : e == 't' ? '\t' : e;
        }
        if (o + 1 >= cap)
            return amp_fail(err, AMP_ERR_PARSE, line, "G-code longer than %lu bytes", (unsigned long)cap - 1);
        dst[o++] = c;
    }
    dst[o] = '\0';
    return AMP_OK;
}

static int is_word(const char *v, size_t n, const char *w)
{
    return strlen(w) == n && strncmp(v, w, n) == 0;
}

/* The firmwares whose G-code is Marlin's for every command ampath writes
 * (G0/G1/G2/G3, G28, G90, G92, M82/M83, M104/M109, M140/M190, M106/M107,
 * M204, M84) and whose serial protocol takes Marlin's numbered lines:
 * RepRapFirmware (Duet), Repetier, Smoothieware, Sprinter and Teacup
 * profiles are written as Marlin jobs rather than refused. */
static int marlin_dialect(const char *v, size_t n)
{
    return (n >= 6 && strncmp(v, "marlin", 6) == 0) || is_word(v, n, "prusa") || is_word(v, n, "reprap") ||
           is_word(v, n, "reprapfirmware") || is_word(v, n, "repetier") || is_word(v, n, "smoothie") ||
           is_word(v, n, "sprinter") || is_word(v, n, "teacup");
}

static amp_status flavor_of(amp_printer *p, const char *v, size_t n, long line, amp_error *err)
{
    if (marlin_dialect(v, n))
        p->flavor = AMP_FLAVOR_MARLIN;
    else if (is_word(v, n, "klipper"))
        p->flavor = AMP_FLAVOR_KLIPPER;
    else /* makerware, sailfish (x3g), mach3, machinekit, no-extrusion: not a 3D printer's text G-code */
        return amp_fail(err, AMP_ERR_PARSE, line,
                        "gcode_flavor %.*s is not supported (marlin, marlin2, marlinlegacy, klipper; reprap, "
                        "reprapfirmware, repetier, smoothie, sprinter and teacup are written as Marlin)",
                        (int)(n > 40 ? 40 : n), v);
    return AMP_OK;
}

static void note_unknown(amp_printer *p, const char *k, size_t n)
{
    size_t have = strlen(p->unknown);
    p->n_unknown++;
    if (have + n + 2 < sizeof p->unknown) {
        if (have)
            p->unknown[have++] = ',';
        memcpy(p->unknown + have, k, n);
        p->unknown[have + n] = '\0';
    }
}

/* One known numeric key. */
static void set_number(amp_printer *p, ini_ctx *c, int id, double x, int pct)
{
    switch (id) {
    case K_MAX_HEIGHT: p->max_height = x; break;
    case K_NOZZLE: p->nozzle_diameter = x; break;
    case K_FILAMENT: p->filament_diameter = x; break;
    case K_LAYER: p->layer_height = x; break;
    case K_FIRST_LAYER: p->first_layer_height = pct ? x / 100.0 * p->layer_height : x; break;
    case K_TEMP: p->temp = x; break;
    case K_TEMP1: p->first_layer_temp = x; break;
    case K_BED: p->bed_temp = x; break;
    case K_BED1: p->first_layer_bed_temp = x; break;
    case K_RETRACT: p->retract_length = x; break;
    case K_RETRACT_SPEED: p->retract_speed = x; break;
    case K_LIFT: p->retract_lift = x; break;
    case K_BEFORE_TRAVEL: p->retract_before_travel = x; break;
    case K_TRAVEL: p->travel_speed = x; break;
    case K_PERIMETER: c->perimeter = x; break;
    case K_FIRST_SPEED: c->first_speed = x; c->first_speed_pct = pct; break;
    case K_FAN_MIN: c->fan_min = x; c->have_fan = 1; break;
    case K_FAN_MAX: c->fan_max = x; c->have_fan = 1; break;
    case K_FAN_ALWAYS: c->fan_always = x != 0.0; c->fan_always_seen = 1; break;
    /* out of range is kept out of range (amp_printer_check refuses it, naming the key), never clamped into
     * a value the user did not write: -2 first layers without fan would have run the fan on the first */
    case K_FAN_OFF: p->fan_off_layers = x < -1e6 ? -1000000 : x > 100000 ? 100001 : (int)floor(x); break;
    /* the machine limits and the volumetric speed: 0 is "not set" (PrusaSlicer: unlimited), the default stays */
    case K_ACCEL: if (x != 0) p->accel = x; break;
    case K_FEED_X: if (x != 0) p->max_feed_xy = x; break;
    case K_FEED_Y: if (x < 0 || (x > 0 && x < p->max_feed_xy)) p->max_feed_xy = x; break;
    case K_FEED_Z: if (x != 0) p->max_feed_z = x; break;
    case K_FEED_E: if (x != 0) p->max_feed_e = x; break;
    case K_ACC_X: if (x != 0) p->max_accel_xy = x; break;
    case K_ACC_Y: if (x < 0 || (x > 0 && x < p->max_accel_xy)) p->max_accel_xy = x; break;
    case K_ACC_Z: if (x != 0) p->max_accel_z = x; break;
    case K_ACC_E: if (x != 0) p->max_accel_e = x; break;
    case K_ACC_RETRACT: if (x != 0) p->retract_accel = x; break;
    case K_VOLUMETRIC: if (x != 0) p->max_volumetric_flow = x; break;
    case K_MULTIPLIER: p->extrusion_multiplier = x; break;
    default: break; /* K_COOLING: no layer-time cooling in ampath */
    }
}

/* One `key = value` line. */
static amp_status ini_line(amp_printer *p, ini_ctx *c, const char *s, size_t n, long line, amp_error *err)
{
    const char *eq = memchr(s, '=', n), *v;
    size_t kn, vn;
    int id, pct;
    double x;
    if (!eq)
        return amp_fail(err, AMP_ERR_PARSE, line, "expected 'key = value'");
    kn = (size_t)(eq - s);
    while (kn > 0 && (s[kn - 1] == ' ' || s[kn - 1] == '\t'))
        kn--;
    v = eq + 1;
    vn = n - (size_t)(v - s);
    while (vn > 0 && (*v == ' ' || *v == '\t'))
        v++, vn--;
    p->n_keys++;
    id = key_id(s, kn);
    if (id != K_START && id != K_END) /* every value for the macros: they may read any key */
        amp_pr_vars_set(p, s, kn, v, vn);
    if (id < 0) {
        note_unknown(p, s, kn);
        return AMP_OK;
    }
    if (kn >= 3 && (strncmp(s, "fan_", 4) == 0 || strncmp(s, "close_fan", 9) == 0))
        c->orca_fan = 1;
    switch (id) {
    case K_BED_SHAPE: {
        double fill = 0.0;
        int r = bed_shape(p, v, vn, &fill);
        if (r == BED_NOT_BOX)
            return amp_fail(err, AMP_ERR_RANGE, line,
                            "bed_shape: no rectangle about the outline's centre fits inside it (it fills %.0f %% "
                            "of its bounding box): ampath places jobs on a rectangular or round bed; give the "
                            "largest rectangle inside the bed",
                            100.0 * fill);
        return r ? AMP_OK : amp_fail(err, AMP_ERR_PARSE, line, "bed_shape: expected XxY,XxY,...");
    }
    case K_FLAVOR: return flavor_of(p, v, vn, line, err);
    case K_START: return gcode_string(p->start_gcode, sizeof p->start_gcode, v, vn, line, err);
    case K_END: return gcode_string(p->end_gcode, sizeof p->end_gcode, v, vn, line, err);
    case K_MODEL:
        if (vn >= sizeof p->model)
            vn = sizeof p->model - 1;
        memcpy(p->model, v, vn);
        p->model[vn] = '\0';
        return AMP_OK;
    default:
        if (vn == 0 || (vn == 3 && strncmp(v, "nil", 3) == 0))
            return AMP_OK; /* an unset value keeps the default */
        if (!first_number(v, vn, &x, &pct))
            return amp_fail(err, AMP_ERR_PARSE, line, "%.*s: '%.*s' is not a number", (int)(kn > 60 ? 60 : kn), s,
                            (int)(vn > 40 ? 40 : vn), v);
        set_number(p, c, id, x, pct);
        return AMP_OK;
    }
}

/*
 * Fan: PrusaSlicer runs min_fan_speed all the time with fan_always_on and
 * speeds up only for short layers (which ampath does not model); without
 * fan_always_on the fan stays off. OrcaSlicer has no such switch and runs
 * fan_min_speed.
 */
static void ini_finish(amp_printer *p, const ini_ctx *c)
{
    if (c->perimeter > 0)
        p->print_speed = c->perimeter;
    if (c->first_speed > 0)
        p->first_layer_speed = c->first_speed_pct ? c->first_speed / 100.0 * p->print_speed : c->first_speed;
    if (c->have_fan || c->fan_always_seen)
        p->fan_percent = (c->fan_always_seen ? c->fan_always : c->orca_fan) ? c->fan_min : 0.0;
    /* a fan speed outside 0..100 % is refused even where it would not be used (PrusaSlicer refuses it) */
    if (c->have_fan && !(c->fan_min >= 0.0 && c->fan_min <= 100.0))
        p->fan_percent = c->fan_min;
    else if (c->have_fan && !(c->fan_max >= 0.0 && c->fan_max <= 100.0))
        p->fan_percent = c->fan_max;
}

amp_status amp_printer_parse_ini(amp_printer *p, const char *text, size_t len, const char *name, amp_error *err)
{
    ini_ctx c;
    size_t pos = 0;
    long line = 0;
    amp_status st;
    if (!p || (!text && len))
        return amp_fail(err, AMP_ERR_ARG, 0, "printer: NULL profile or text");
    st = amp_printer_builtin(p, "generic", err);
    if (st != AMP_OK)
        return st;
    memset(&c, 0, sizeof c);
    c.fan_min = p->fan_percent;
    p->model[0] = '\0';
    if (name) {
        size_t n = strlen(name) < sizeof p->name - 1 ? strlen(name) : sizeof p->name - 1;
        memcpy(p->name, name, n);
        p->name[n] = '\0';
    } else {
        strcpy(p->name, "ini");
    }
    while (pos < len) {
        const char *s = text + pos, *e = memchr(s, '\n', len - pos);
        size_t n = e ? (size_t)(e - s) : len - pos;
        pos += n + (e ? 1 : 0);
        line++;
        while (n > 0 && (s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == '\t'))
            n--;
        while (n > 0 && (*s == ' ' || *s == '\t'))
            s++, n--;
        if (n == 0 || *s == '#' || *s == ';' || *s == '[')
            continue;
        if (memchr(s, '\0', n))
            return amp_fail(err, AMP_ERR_PARSE, line, "NUL byte");
        st = ini_line(p, &c, s, n, line, err);
        if (st != AMP_OK)
            return st;
    }
    ini_finish(p, &c);
    return amp_printer_check(p, err);
}
