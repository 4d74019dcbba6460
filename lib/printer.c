/*
 * Printer profiles (docs/interfaces.md §5): the built-in machines, range checks, the
 * placeholder expansion of start/end G-code, and the mapping onto the G-code
 * writer's options. The `.ini` reader is in printer_ini.c.
 */
#include <math.h>
#include <string.h>

#include "ampath/io.h"
#include "ampath/printer.h"

typedef struct builtin {
    const char *name, *about;
    int flavor;
    double bed_x, bed_y, height;
    double temp, temp1, bed, bed1;
    double retract, retract_speed, lift, before_travel;
    double print, first, travel, accel, max_xy, max_z, max_e, max_flow;
    const char *start, *end;
} builtin;

/* Prusa-style start: heat, home without and then with mesh-bed levelling, an intro line at the bed's front edge. */
static const char mk3s_start[] = "M140 S[first_layer_bed_temperature] ; bed\n"
                                 "M104 S[first_layer_temperature] ; hot end\n"
                                 "G28 W ; home all without mesh bed levelling\n"
                                 "G80 ; mesh bed levelling\n"
                                 "M190 S[first_layer_bed_temperature] ; wait for the bed\n"
                                 "M109 S[first_layer_temperature] ; wait for the hot end\n"
                                 "G1 Z0.2 F720\n"
                                 "G1 X10 Y1 F3000\n"
                                 "M83 ; relative E for the intro line\n"
                                 "G1 X70 Y1 E9 F1000 ; intro line\n"
                                 "G1 X110 Y1 E12.5 F1000 ; intro line\n"
                                 "G92 E0\n";
static const char mk3s_end[] = "M104 S0 ; hot end off\n"
                               "M140 S0 ; bed off\n"
                               "M107 ; fan off\n"
                               "G1 X0 Y200 F3000 ; present the print\n"
                               "M84 ; motors off\n";
/* Creality-style start: two purge lines along the left edge. */
static const char ender3_start[] = "M140 S[first_layer_bed_temperature] ; bed\n"
                                   "M104 S[first_layer_temperature] ; hot end\n"
                                   "G28 ; home all axes\n"
                                   "M190 S[first_layer_bed_temperature] ; wait for the bed\n"
                                   "M109 S[first_layer_temperature] ; wait for the hot end\n"
                                   "M82 ; absolute E for the purge lines\n"
                                   "G92 E0\n"
                                   "G1 Z2 F300\n"
                                   "G1 X0.5 Y20 Z0.3 F5000 ; purge line start\n"
                                   "G1 X0.5 Y200 Z0.3 F1500 E15 ; purge line\n"
                                   "G1 X0.8 Y200 Z0.3 F5000\n"
                                   "G1 X0.8 Y20 Z0.3 F1500 E30 ; second purge line\n"
                                   "G92 E0\n"
                                   "G1 Z2 F300\n";

static const builtin builtins[] = {
    {"generic", "generic 220 x 220 x 250 mm Marlin printer, 0.4 mm nozzle, 1.75 mm PLA (default)", AMP_FLAVOR_MARLIN,
     220, 220, 250, 210, 215, 60, 60, 1.0, 35, 0.4, 2.0, 30, 20, 120, 1000, 200, 10, 60, 12, NULL, NULL},
    {"prusa-mk3s", "Prusa i3 MK3S: 250 x 210 x 210 mm, Prusa Marlin, mesh-bed levelling, PLA", AMP_FLAVOR_MARLIN,
     250, 210, 210, 210, 215, 60, 60, 0.8, 35, 0.4, 1.0, 40, 20, 180, 1250, 200, 12, 120, 15, mk3s_start, mk3s_end},
    {"ender3", "Creality Ender-3: 220 x 220 x 250 mm, Marlin, Bowden (5 mm retraction), Z 5 mm/s, PLA",
     AMP_FLAVOR_MARLIN, 220, 220, 250, 200, 205, 60, 60, 5.0, 45, 0.2, 2.0, 50, 20, 150, 500, 500, 5, 25, 8,
     ender3_start, NULL},
    {"voron-350", "Voron 2.4 350: 350 x 350 x 340 mm, Klipper, direct drive, 3000 mm/s^2, PLA", AMP_FLAVOR_KLIPPER,
     350, 350, 340, 210, 215, 60, 60, 0.5, 35, 0.2, 1.5, 80, 30, 250, 3000, 300, 15, 120, 24, NULL, NULL},
};
#define NBUILTIN (sizeof builtins / sizeof builtins[0])

size_t amp_printer_builtin_count(void) { return NBUILTIN; }
const char *amp_printer_builtin_name(size_t i) { return i < NBUILTIN ? builtins[i].name : NULL; }
const char *amp_printer_builtin_about(size_t i) { return i < NBUILTIN ? builtins[i].about : NULL; }

static void copy_str(char *dst, size_t cap, const char *src)
{
    size_t n = src ? strlen(src) : 0;
    if (n >= cap)
        n = cap - 1;
    if (n)
        memcpy(dst, src, n);
    dst[n] = '\0';
}

amp_status amp_printer_builtin(amp_printer *p, const char *name, amp_error *err)
{
    const builtin *b = NULL;
    size_t i;
    if (!p || !name)
        return amp_fail(err, AMP_ERR_ARG, 0, "printer: NULL profile or name");
    for (i = 0; i < NBUILTIN; i++)
        if (strcmp(builtins[i].name, name) == 0)
            b = &builtins[i];
    if (!b)
        return amp_fail(err, AMP_ERR_ARG, 0, "unknown printer '%s' (built-in: generic, prusa-mk3s, ender3, voron-350; or "
                        "a PrusaSlicer .ini file)", name);
    memset(p, 0, sizeof *p);
    copy_str(p->name, sizeof p->name, b->name);
    copy_str(p->model, sizeof p->model, b->name);
    p->flavor = b->flavor;
    p->bed_max_x = b->bed_x;
    p->bed_max_y = b->bed_y;
    p->max_height = b->height;
    p->nozzle_diameter = 0.4;
    p->filament_diameter = 1.75;
    p->layer_height = p->first_layer_height = 0.2;
    p->temp = b->temp;
    p->first_layer_temp = b->temp1;
    p->bed_temp = b->bed;
    p->first_layer_bed_temp = b->bed1;
    p->fan_percent = 100.0;
    p->fan_off_layers = 1;
    p->retract_length = b->retract;
    p->retract_speed = b->retract_speed;
    p->retract_lift = b->lift;
    p->retract_before_travel = b->before_travel;
    p->print_speed = b->print;
    p->first_layer_speed = b->first;
    p->travel_speed = b->travel;
    p->accel = b->accel;
    p->max_feed_xy = b->max_xy;
    p->max_feed_z = b->max_z;
    p->max_feed_e = b->max_e;
    p->max_volumetric_flow = b->max_flow;
    p->extrusion_multiplier = 1.0;
    copy_str(p->start_gcode, sizeof p->start_gcode, b->start);
    copy_str(p->end_gcode, sizeof p->end_gcode, b->end);
    return AMP_OK;
}

amp_status amp_printer_load(amp_printer *p, const char *spec, amp_error *err)
{
    char *text = NULL, name[AMP_PRINTER_NAME_MAX];
    const char *base, *dot;
    size_t len = 0;
    amp_status st;
    if (!p || !spec)
        return amp_fail(err, AMP_ERR_ARG, 0, "printer: NULL profile or name");
    if (!strchr(spec, '/') && !strchr(spec, '.'))
        return amp_printer_builtin(p, spec, err);
    st = amp_read_file(spec, NULL, 4u << 20, &text, &len, err);
    if (st != AMP_OK)
        return st;
    base = strrchr(spec, '/') ? strrchr(spec, '/') + 1 : spec;
    copy_str(name, sizeof name, base);
    dot = strrchr(name, '.');
    if (dot && dot != name)
        name[dot - name] = '\0';
    st = amp_printer_parse_ini(p, text, len, name, err);
    if (st != AMP_OK && err && err->line > 0) {
        char msg[AMP_ERROR_MSG_SIZE];
        copy_str(msg, sizeof msg, err->msg);
        amp_fail(err, st, err->line, "%s:%ld: %s", spec, err->line, msg);
    }
    amp_free(NULL, text);
    return st;
}

#define RANGE(v, lo, hi, what)                                                                                     \
    do {                                                                                                           \
        if (!(isfinite(v) && (v) >= (lo) && (v) <= (hi)))                                                          \
            return amp_fail(err, AMP_ERR_RANGE, 0, "printer '%s': %s must lie in [%g, %g]", p->name, what,         \
                            (double)(lo), (double)(hi));                                                           \
    } while (0)

amp_status amp_printer_check(const amp_printer *p, amp_error *err)
{
    if (!p)
        return amp_fail(err, AMP_ERR_ARG, 0, "printer: NULL profile");
    if (p->flavor != AMP_FLAVOR_MARLIN && p->flavor != AMP_FLAVOR_KLIPPER)
        return amp_fail(err, AMP_ERR_RANGE, 0, "printer '%s': flavor must be marlin or klipper", p->name);
    RANGE(p->bed_max_x - p->bed_min_x, 1.0, 1e4, "bed width (mm)");
    RANGE(p->bed_max_y - p->bed_min_y, 1.0, 1e4, "bed depth (mm)");
    RANGE(p->bed_min_x, -1e4, 1e4, "bed origin x (mm)");
    RANGE(p->bed_min_y, -1e4, 1e4, "bed origin y (mm)");
    RANGE(p->max_height, 1.0, 1e4, "max_print_height (mm)");
    RANGE(p->nozzle_diameter, 0.05, 3.0, "nozzle_diameter (mm)");
    RANGE(p->filament_diameter, 0.5, 5.0, "filament_diameter (mm)");
    RANGE(p->layer_height, 0.01, 3.0, "layer_height (mm)");
    RANGE(p->first_layer_height, 0.01, 3.0, "first_layer_height (mm)");
    RANGE(p->temp, 0.0, 500.0, "temperature (C)");
    RANGE(p->first_layer_temp, 0.0, 500.0, "first_layer_temperature (C)");
    RANGE(p->bed_temp, 0.0, 200.0, "bed_temperature (C)");
    RANGE(p->first_layer_bed_temp, 0.0, 200.0, "first_layer_bed_temperature (C)");
    RANGE(p->fan_percent, 0.0, 100.0, "fan speed (%)");
    RANGE((double)p->fan_off_layers, 0.0, 100000.0, "disable_fan_first_layers");
    RANGE(p->retract_length, 0.0, 100.0, "retract_length (mm)");
    RANGE(p->retract_speed, 0.1, 1e4, "retract_speed (mm/s)");
    RANGE(p->retract_lift, 0.0, 100.0, "retract_lift (mm)");
    RANGE(p->retract_before_travel, 0.0, 1000.0, "retract_before_travel (mm)");
    RANGE(p->print_speed, 0.1, 1e4, "print speed (mm/s)");
    RANGE(p->first_layer_speed, 0.1, 1e4, "first_layer_speed (mm/s)");
    RANGE(p->travel_speed, 0.1, 1e4, "travel_speed (mm/s)");
    RANGE(p->accel, 1.0, 1e6, "acceleration (mm/s^2)");
    RANGE(p->max_feed_xy, 0.1, 1e5, "machine_max_feedrate_x/y (mm/s)");
    RANGE(p->max_feed_z, 0.01, 1e5, "machine_max_feedrate_z (mm/s)");
    RANGE(p->max_feed_e, 0.1, 1e5, "machine_max_feedrate_e (mm/s)");
    RANGE(p->max_volumetric_flow, 0.01, 1e4, "max_volumetric_speed (mm^3/s)");
    RANGE(p->extrusion_multiplier, 0.01, 10.0, "extrusion_multiplier");
    return AMP_OK;
}

/* ---------------------------------------------------------------- placeholders */

/* Value of placeholder @p name (length @p n): 1 number in *v, 2 the string *s, 0 unknown. */
static int placeholder(const amp_printer *p, const char *name, size_t n, double *v, const char **s)
{
    static const struct {
        const char *key;
        int field;
    } keys[] = {{"temperature", 0},
                {"nozzle_temperature", 0},
                {"first_layer_temperature", 1},
                {"nozzle_temperature_initial_layer", 1},
                {"bed_temperature", 2},
                {"hot_plate_temp", 2},
                {"first_layer_bed_temperature", 3},
                {"hot_plate_temp_initial_layer", 3},
                {"bed_temperature_initial_layer_single", 3},
                {"nozzle_diameter", 4},
                {"filament_diameter", 5},
                {"layer_height", 6},
                {"first_layer_height", 7},
                {"initial_layer_print_height", 7},
                {"max_print_height", 8},
                {"travel_speed", 9},
                {"retract_length", 10},
                {"initial_extruder", 11},
                {"current_extruder", 11},
                {"initial_tool", 11},
                {"printer_model", 12}};
    size_t i;
    for (i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        if (strlen(keys[i].key) != n || strncmp(keys[i].key, name, n) != 0)
            continue;
        switch (keys[i].field) {
        case 0: *v = p->temp; return 1;
        case 1: *v = p->first_layer_temp; return 1;
        case 2: *v = p->bed_temp; return 1;
        case 3: *v = p->first_layer_bed_temp; return 1;
        case 4: *v = p->nozzle_diameter; return 1;
        case 5: *v = p->filament_diameter; return 1;
        case 6: *v = p->layer_height; return 1;
        case 7: *v = p->first_layer_height; return 1;
        case 8: *v = p->max_height; return 1;
        case 9: *v = p->travel_speed; return 1;
        case 10: *v = p->retract_length; return 1;
        case 11: *v = 0.0; return 1;
        default: *s = p->model; return 2;
        }
    }
    return 0;
}

/* A number with at most 3 decimals, trailing zeros dropped (no float printf: the library builds for newlib-nano). */
static size_t fmt_num(char *buf, double v)
{
    long long u = llround(fabs(v) * 1000.0);
    char tmp[32];
    size_t k = 0, n = 0;
    int i, frac = (int)(u % 1000);
    long long ip = u / 1000;
    if (v < 0 && u > 0)
        buf[n++] = '-';
    do {
        tmp[k++] = (char)('0' + (int)(ip % 10));
        ip /= 10;
    } while (ip && k < sizeof tmp);
    while (k)
        buf[n++] = tmp[--k];
    if (frac) {
        buf[n++] = '.';
        for (i = 100; i > 0 && frac; i /= 10) {
            buf[n++] = (char)('0' + frac / i);
            frac %= i;
        }
    }
    buf[n] = '\0';
    return n;
}

/* Name part of a placeholder body "key", "key[0]" or "key_0": its length. */
static size_t placeholder_name(const char *b, size_t n)
{
    size_t k = 0, j;
    while (k < n && b[k] != '[')
        k++;
    if (k < n) /* key[digits] */
        return k;
    for (j = n; j > 0 && b[j - 1] >= '0' && b[j - 1] <= '9'; j--)
        ;
    if (j < n && j > 1 && b[j - 1] == '_') /* key_digits */
        return j - 1;
    return n;
}

static amp_status put(char *out, size_t cap, size_t *o, const char *s, size_t n, amp_error *err)
{
    if (*o + n + 1 > cap)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "expanded G-code longer than %lu bytes", (unsigned long)cap - 1);
    memcpy(out + *o, s, n);
    *o += n;
    out[*o] = '\0';
    return AMP_OK;
}

amp_status amp_printer_expand(const amp_printer *p, const char *tmpl, char *out, size_t cap, amp_error *err)
{
    size_t o = 0;
    long line = 1;
    int comment = 0;
    const char *s;
    if (!p || !tmpl || !out || cap == 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "printer: NULL argument to expand");
    out[0] = '\0';
    for (s = tmpl; *s; s++) {
        char close = *s == '[' ? ']' : *s == '{' ? '}' : 0;
        const char *e = close ? strchr(s + 1, close) : NULL;
        const char *nl = strchr(s, '\n');
        amp_status st;
        if (*s == '\n') {
            line++;
            comment = 0;
        } else if (*s == ';') {
            comment = 1;
        }
        if (e && (!nl || e < nl) && e > s + 1) {
            size_t body = (size_t)(e - s - 1), nn = placeholder_name(s + 1, body);
            double v = 0.0;
            const char *str = NULL;
            int kind = placeholder(p, s + 1, nn, &v, &str);
            if (kind == 0 && !comment)
                return amp_fail(err, AMP_ERR_PARSE, line,
                                "G-code line %ld: placeholder %.*s is not supported (ampath expands the temperatures, "
                                "diameters and heights; no {if} blocks): replace it in the profile", line,
                                (int)(body + 2 > 60 ? 60 : body + 2), s);
            if (kind != 0) {
                char num[40];
                st = kind == 1 ? put(out, cap, &o, num, fmt_num(num, v), err) : put(out, cap, &o, str, strlen(str), err);
                if (st != AMP_OK)
                    return st;
                s = e;
                continue;
            }
        }
        st = put(out, cap, &o, s, 1, err);
        if (st != AMP_OK)
            return st;
    }
    return AMP_OK;
}

/* ---------------------------------------------------------------- the writer's options */

double amp_printer_bead_width(const amp_printer *p) { return p ? 1.125 * p->nozzle_diameter : 0.45; }

amp_status amp_printer_gcode_opts(amp_printer *p, amp_gcode_opts *o, amp_error *err)
{
    amp_status st;
    if (!p || !o)
        return amp_fail(err, AMP_ERR_ARG, 0, "printer: NULL profile or options");
    st = amp_printer_check(p, err);
    if (st == AMP_OK)
        st = amp_printer_expand(p, p->start_gcode, p->start_out, sizeof p->start_out, err);
    if (st == AMP_OK)
        st = amp_printer_expand(p, p->end_gcode, p->end_out, sizeof p->end_out, err);
    if (st != AMP_OK)
        return st;
    amp_gcode_opts_default(o, p->flavor);
    o->profile = p->name;
    o->bed_min_x = p->bed_min_x;
    o->bed_min_y = p->bed_min_y;
    o->bed_max_x = p->bed_max_x;
    o->bed_max_y = p->bed_max_y;
    o->max_height = p->max_height;
    o->filament_diameter = p->filament_diameter;
    o->flow = p->extrusion_multiplier;
    o->max_volumetric_flow = p->max_volumetric_flow;
    o->print_feed = p->print_speed;
    o->first_layer_feed = p->first_layer_speed;
    o->travel_feed = p->travel_speed;
    o->retract_length = p->retract_length;
    o->retract_speed = p->retract_speed;
    o->z_hop = p->retract_lift;
    o->retract_min_travel = p->retract_before_travel;
    o->hotend_temp = p->temp;
    o->bed_temp = p->bed_temp;
    o->first_layer_hotend_temp = p->first_layer_temp;
    o->first_layer_bed_temp = p->first_layer_bed_temp;
    o->first_layer_height = p->first_layer_height;
    o->fan_off_layers = p->fan_off_layers;
    o->fan_speed = p->fan_percent / 100.0;
    o->accel = p->accel;
    o->max_feed_xy = p->max_feed_xy;
    o->max_feed_z = p->max_feed_z;
    o->max_feed_e = p->max_feed_e;
    o->start_gcode = p->start_out[0] ? p->start_out : NULL;
    o->end_gcode = p->end_out[0] ? p->end_out : NULL;
    return AMP_OK;
}
