/*
 * Printer profiles (docs/interfaces.md §5): the built-in machines, range checks, the
 * expansion of start/end G-code for a job, and the mapping onto the G-code
 * writer's options. The `.ini` reader is in printer_ini.c, the macro
 * language in printer_macro.c (with printer_vars.c and printer_regex.c).
 */
#include <math.h>
#include <string.h>

#include "ampath/io.h"
#include "ampath/printer.h"
#include "printer_internal.h"

typedef struct builtin {
    const char *name, *about;
    int flavor;
    double bed_x, bed_y, height;
    double temp, temp1, bed, bed1;
    double retract, retract_speed, lift, before_travel;
    double print, first, travel, accel, max_xy, max_z, max_e, max_flow;
    const char *start, *end;
    double acc_xy, acc_z, acc_e, acc_retract; /* the firmware's per-axis and retraction accelerations */
} builtin;

/* Prusa-style start: heat, home without and then with mesh-bed levelling (Prusa's G80; a Klipper MK3S levels in its
 * own macros), an intro line at the bed's front edge. */
static const char mk3s_start[] = "M140 S[first_layer_bed_temperature] ; bed\n"
                                 "M104 S[first_layer_temperature] ; hot end\n"
                                 "G28 W ; home all without mesh bed levelling\n"
                                 "{if gcode_flavor != \"klipper\"}G80 ; mesh bed levelling (Prusa's firmware)\n{endif}"
                                 "M190 S[first_layer_bed_temperature] ; wait for the bed\n"
                                 "M109 S[first_layer_temperature] ; wait for the hot end\n"
                                 "G1 Z0.2 F720\n"
                                 "G1 X10 Y1 F3000\n"
                                 "M83 ; relative E for the intro line\n"
                                 "G1 X70 Y1 E9 F1000 ; intro line\n"
                                 "{if gcode_flavor == \"klipper\"}G1 X110 Y1 E10 F1000 ; intro line (0.60 mm^2: "
                                 "Klipper stops at 4 x nozzle^2)\n{else}G1 X110 Y1 E12.5 F1000 ; intro line\n{endif}"
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
     220, 220, 250, 210, 215, 60, 60, 1.0, 35, 0.4, 2.0, 30, 20, 120, 1000, 200, 10, 60, 12, NULL, NULL,
     3000, 100, 10000, 3000}, /* Marlin's defaults */
    {"prusa-mk3s", "Prusa i3 MK3S: 250 x 210 x 210 mm, Prusa Marlin, mesh-bed levelling, PLA", AMP_FLAVOR_MARLIN,
     250, 210, 210, 210, 215, 60, 60, 0.8, 35, 0.4, 1.0, 40, 20, 180, 1250, 200, 12, 120, 15, mk3s_start, mk3s_end,
     1000, 200, 5000, 1250}, /* PrusaSlicer's MK3S profile */
    {"ender3", "Creality Ender-3: 220 x 220 x 250 mm, Marlin, Bowden (5 mm retraction), Z 5 mm/s, PLA",
     AMP_FLAVOR_MARLIN, 220, 220, 250, 200, 205, 60, 60, 5.0, 45, 0.2, 2.0, 50, 20, 150, 500, 500, 5, 25, 8,
     ender3_start, NULL, 500, 100, 5000, 500}, /* Creality's Marlin configuration */
    {"voron-350", "Voron 2.4 350: 350 x 350 x 340 mm, Klipper, direct drive, 3000 mm/s^2, PLA", AMP_FLAVOR_KLIPPER,
     350, 350, 340, 210, 215, 60, 60, 0.5, 35, 0.2, 1.5, 80, 30, 250, 3000, 300, 15, 120, 24, NULL, NULL,
     3000, 350, 3000, 3000}, /* a Voron printer.cfg: max_accel, max_z_accel */
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
    p->max_accel_xy = b->acc_xy;
    p->max_accel_z = b->acc_z;
    p->max_accel_e = b->acc_e;
    p->retract_accel = b->acc_retract;
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
            return amp_fail(err, AMP_ERR_RANGE, 0, "printer '%s': %s must lie in [%g, %g] (it is %g)", p->name,   \
                            what, (double)(lo), (double)(hi), (double)(v));                                        \
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
    RANGE(p->bed_radius, 0.0, 1e4, "round bed radius (mm)");
    RANGE(p->max_height, 1.0, 1e4, "max_print_height (mm)");
    RANGE(p->nozzle_diameter, 0.05, 3.0, "nozzle_diameter (mm)");
    RANGE(p->filament_diameter, 0.5, 5.0, "filament_diameter (mm)");
    RANGE(p->layer_height, 0.01, 3.0, "layer_height (mm)");
    RANGE(p->first_layer_height, 0.01, 3.0, "first_layer_height (mm)");
    RANGE(p->temp, 0.0, 500.0, "temperature (C)");
    RANGE(p->first_layer_temp, 0.0, 500.0, "first_layer_temperature (C)");
    RANGE(p->bed_temp, 0.0, 200.0, "bed_temperature (C)");
    RANGE(p->first_layer_bed_temp, 0.0, 200.0, "first_layer_bed_temperature (C)");
    RANGE(p->fan_percent, 0.0, 100.0, "fan speed (%, min_fan_speed / max_fan_speed)");
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
    RANGE(p->max_accel_xy, 0.0, 1e6, "machine_max_acceleration_x/y (mm/s^2)");
    RANGE(p->max_accel_z, 0.0, 1e6, "machine_max_acceleration_z (mm/s^2)");
    RANGE(p->max_accel_e, 0.0, 1e6, "machine_max_acceleration_e (mm/s^2)");
    RANGE(p->retract_accel, 0.0, 1e6, "machine_max_acceleration_retracting (mm/s^2)");
    RANGE(p->max_volumetric_flow, 0.01, 1e4, "max_volumetric_speed (mm^3/s)");
    RANGE(p->extrusion_multiplier, 0.01, 10.0, "extrusion_multiplier");
    return AMP_OK;
}

/* ---------------------------------------------------------------- start and end G-code */

void amp_printer_job_none(const amp_printer *p, amp_printer_job *job)
{
    memset(job, 0, sizeof *job);
    if (p) { /* without a job the first layer may lie anywhere on the bed */
        job->first_layer_min[0] = p->bed_min_x;
        job->first_layer_min[1] = p->bed_min_y;
        job->first_layer_max[0] = p->bed_max_x;
        job->first_layer_max[1] = p->bed_max_y;
    }
}

amp_status amp_printer_expand_job(const amp_printer *p, const amp_printer_job *job, const char *tmpl, char *out,
                                  size_t cap, amp_error *err)
{
    return amp_pr_expand(p, job, tmpl, out, cap, NULL, err);
}

amp_status amp_printer_expand(const amp_printer *p, const char *tmpl, char *out, size_t cap, amp_error *err)
{
    return amp_pr_expand(p, NULL, tmpl, out, cap, NULL, err);
}

/* Expand one of p's sequences; the message names it ("start G-code line 3, ..."). */
static amp_status expand_seq(amp_printer *p, const amp_printer_job *job, int end, int *used, amp_error *err)
{
    amp_status st = amp_pr_expand(p, job, end ? p->end_gcode : p->start_gcode, end ? p->end_out : p->start_out,
                                  AMP_PRINTER_GCODE_MAX, used, err);
    if (st != AMP_OK && err) {
        char msg[AMP_ERROR_MSG_SIZE];
        copy_str(msg, sizeof msg, err->msg);
        amp_fail(err, st, err->line, "printer '%s': %s %s", p->name, end ? "end" : "start", msg);
    }
    return st;
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
        st = expand_seq(p, NULL, 0, NULL, err);
    if (st == AMP_OK)
        st = expand_seq(p, NULL, 1, NULL, err);
    if (st != AMP_OK)
        return st;
    amp_gcode_opts_default(o, p->flavor);
    o->profile = p->name;
    o->bed_min_x = p->bed_min_x;
    o->bed_min_y = p->bed_min_y;
    o->bed_max_x = p->bed_max_x;
    o->bed_max_y = p->bed_max_y;
    o->bed_radius = p->bed_radius;
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
    o->junction_deviation = amp_gcode_junction_default(p->flavor, p->accel);
    o->max_feed_xy = p->max_feed_xy;
    o->max_feed_z = p->max_feed_z;
    o->max_feed_e = p->max_feed_e;
    o->max_cross_section = 4.0 * p->nozzle_diameter * p->nozzle_diameter; /* Klipper's default for the nozzle */
    o->max_accel_xy = p->max_accel_xy;
    o->max_accel_z = p->max_accel_z;
    o->max_accel_e = p->max_accel_e;
    o->retract_accel = p->retract_accel;
    o->start_gcode = p->start_out[0] ? p->start_out : NULL;
    o->end_gcode = p->end_out[0] ? p->end_out : NULL;
    return AMP_OK;
}

/* Is o's sequence (@p cur) still p's own (@p own, its template @p tmpl), not one the caller replaced? */
static int own_seq(const char *cur, const char *own, const char *tmpl)
{
    return tmpl[0] && (cur == own || (!cur && !own[0]));
}

/* The job of the start and end macros from the writer's dry run (it->est). */
static void job_of(const amp_gcode_iter *it, amp_printer_job *job)
{
    const amp_gcode_stats *e = &it->est;
    amp_box3 fl = e->first_layer_bbox;
    if (!(fl.min.x <= fl.max.x)) /* no first layer (a job placed at its own coordinates, above the bed) */
        fl = e->bbox;
    job->max_layer_z = e->bbox.max.z;
    job->layers = (long)e->layers;
    job->first_layer_min[0] = fl.min.x;
    job->first_layer_min[1] = fl.min.y;
    job->first_layer_max[0] = fl.max.x;
    job->first_layer_max[1] = fl.max.y;
    job->layer_z = e->first_layer_z;
    job->layer_num = 0;
}

/* Expand p's own sequences (@p which: 1 start, 2 end) with @p job; *used = a job variable was read. */
static amp_status expand_both(amp_printer *p, amp_printer_job *job, int which, int *used, amp_error *err)
{
    int u = 0;
    amp_status st = AMP_OK;
    double z1 = job->layer_z;
    *used = 0;
    if (which & 1)
        st = expand_seq(p, job, 0, &u, err);
    *used |= u;
    job->layer_num = job->layers > 0 ? job->layers - 1 : 0; /* the end runs after the last layer */
    job->layer_z = job->max_layer_z;
    if (st == AMP_OK && (which & 2))
        st = expand_seq(p, job, 1, &u, err);
    *used |= u;
    job->layer_num = 0;
    job->layer_z = z1;
    return st;
}

/* The dry run of the writer in @p it: the placed job (start/end left out: they are what is being made). */
static amp_status dry_run(amp_gcode_iter *it, const amp_pathset *ps, const amp_gcode_opts *o, amp_error *err)
{
    amp_gcode_opts d = *o;
    d.start_gcode = d.end_gcode = NULL;
    return amp_gcode_iter_init(it, ps, &d, err);
}

static amp_status gcode_job_in(amp_printer *p, amp_gcode_opts *o, const amp_pathset *ps, amp_gcode_iter *it,
                               int which, amp_error *err)
{
    amp_printer_job job;
    amp_status st;
    int used = 0;
    amp_printer_job_none(p, &job);
    job.opts = o;
    job.first_layer_min[0] = o->bed_min_x;
    job.first_layer_min[1] = o->bed_min_y;
    job.first_layer_max[0] = o->bed_max_x;
    job.first_layer_max[1] = o->bed_max_y;
    /* most sequences read no job variable: then the writer's dry run is not needed */
    st = expand_both(p, &job, which, &used, err);
    if (used) {
        st = dry_run(it, ps, o, err);
        if (st == AMP_OK) {
            job_of(it, &job);
            st = expand_both(p, &job, which, &used, err);
        }
    }
    if (st != AMP_OK)
        return st;
    if (which & 1)
        o->start_gcode = p->start_out[0] ? p->start_out : NULL;
    if (which & 2)
        o->end_gcode = p->end_out[0] ? p->end_out : NULL;
    return AMP_OK;
}

/* Without the caller's iterator, one on the stack (as amp_gcode_write). Kept out of line so that a caller
 * that passes its own (small targets) does not get this frame too. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static amp_status gcode_job_on_stack(amp_printer *p, amp_gcode_opts *o, const amp_pathset *ps, int which,
                                     amp_error *err)
{
    amp_gcode_iter it;
    return gcode_job_in(p, o, ps, &it, which, err);
}

amp_status amp_printer_gcode_job(amp_printer *p, amp_gcode_opts *o, const amp_pathset *ps, amp_gcode_iter *scratch,
                                 amp_error *err)
{
    int which;
    if (!p || !o || !ps)
        return amp_fail(err, AMP_ERR_ARG, 0, "printer: NULL profile, options or paths");
    which = (own_seq(o->start_gcode, p->start_out, p->start_gcode) ? 1 : 0) |
            (own_seq(o->end_gcode, p->end_out, p->end_gcode) ? 2 : 0);
    if (!which)
        return AMP_OK;
    return scratch ? gcode_job_in(p, o, ps, scratch, which, err) : gcode_job_on_stack(p, o, ps, which, err);
}
