/*
 * ampath/printer.h — printer profiles (docs/interfaces.md §5): the machine a job is written
 * for. Bed rectangle and height, nozzle and filament, temperatures, fan,
 * retraction and z-hop, speeds and accelerations, firmware flavour, start and
 * end G-code with placeholders.
 *
 * A profile is plain data (no pointers, no allocation): a built-in one by
 * name (amp_printer_builtin) or one read from the printer/filament/print
 * `.ini` files that PrusaSlicer, SuperSlicer and OrcaSlicer export
 * (amp_printer_parse_ini), starting from the `generic` profile and
 * overriding the keys found. amp_printer_gcode_opts() then fills the G-code
 * writer's options; the bridge and `ampath slice` use the same calls.
 *
 * Built-in profiles (see docs/gcode.md for every value):
 *   generic     220 x 220 x 250 mm, Marlin, 0.4 mm nozzle, 1.75 mm filament (default)
 *   prusa-mk3s  250 x 210 x 210 mm, Marlin (Prusa firmware), mesh-bed levelling in the start
 *   ender3      220 x 220 x 250 mm, Marlin, Z limited to 5 mm/s, 5 mm Bowden retraction
 *   voron-350   350 x 350 x 340 mm, Klipper, 3000 mm/s^2
 *
 * Start and end G-code use PrusaSlicer's macro language (docs/gcode.md,
 * "Printer profiles"): `[key]`, `{expression}` and `{if}{elsif}{else}{endif}`
 * over every key of the `.ini` and the runtime variables of the job
 * (amp_printer_job). amp_printer_gcode_job() expands them with the placed
 * job's values.
 *
 * Units: mm, mm/s, mm/s^2, degrees C; the fan in percent (0..100) as the
 * slicers write it. Thread-safety: functions only touch their arguments.
 */
#ifndef AMPATH_PRINTER_H
#define AMPATH_PRINTER_H

#include <stddef.h>

#include "gcode.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AMP_PRINTER_NAME_MAX 64       /**< name buffer, NUL included */
#define AMP_PRINTER_GCODE_MAX 8192    /**< start/end G-code buffers, NUL included */
#define AMP_PRINTER_UNKNOWN_MAX 4096  /**< unknown `.ini` keys, comma-separated, NUL included */
/**
 * Bytes of `.ini` values kept for the macros (amp_printer.vars). A full
 * PrusaSlicer export (printer, filament and print, a few hundred keys) needs
 * about 10-20 KiB besides its start/end G-code. Keys that do not fit are
 * counted in n_vars_dropped; a macro naming one is refused with a message
 * that says so (they still take effect on the fields, and unknown ones are
 * still listed in `unknown`).
 */
#define AMP_PRINTER_VARS_MAX 32768

/** A printer profile. Fill with amp_printer_builtin() or amp_printer_parse_ini(). */
typedef struct amp_printer {
    char name[AMP_PRINTER_NAME_MAX];  /**< built-in name or the file's base name */
    char model[AMP_PRINTER_NAME_MAX]; /**< `printer_model` ([printer_model] placeholder) */
    int flavor;                       /**< AMP_FLAVOR_MARLIN or AMP_FLAVOR_KLIPPER */
    double bed_min_x, bed_min_y, bed_max_x, bed_max_y; /**< printable rectangle (bounding box of bed_shape) */
    double max_height;                /**< max_print_height */
    double nozzle_diameter, filament_diameter;
    double layer_height, first_layer_height;
    double temp, first_layer_temp;         /**< hot end: other layers, first layer */
    double bed_temp, first_layer_bed_temp; /**< bed: other layers, first layer */
    double fan_percent;               /**< part-cooling fan after the first layers, 0..100 */
    int fan_off_layers;               /**< disable_fan_first_layers */
    double retract_length, retract_speed, retract_lift, retract_before_travel;
    double print_speed, first_layer_speed, travel_speed;
    double accel;                     /**< printing acceleration */
    double max_feed_xy, max_feed_z, max_feed_e;
    /** machine_max_acceleration_x/y (the smaller), _z, _e and _retracting, mm/s^2: the estimate's per-axis limits */
    double max_accel_xy, max_accel_z, max_accel_e, retract_accel;
    double max_volumetric_flow;       /**< mm^3/s */
    double extrusion_multiplier;
    char start_gcode[AMP_PRINTER_GCODE_MAX]; /**< "" = the writer's built-in sequence; placeholders unexpanded */
    char end_gcode[AMP_PRINTER_GCODE_MAX];
    char unknown[AMP_PRINTER_UNKNOWN_MAX];   /**< keys of the `.ini` that ampath does not use, comma-separated */
    size_t n_unknown;                 /**< how many (also those that did not fit in @p unknown) */
    size_t n_keys;                    /**< keys read from the `.ini` */
    /* expanded start/end sequences, written by amp_printer_gcode_opts() and amp_printer_gcode_job() */
    char start_out[AMP_PRINTER_GCODE_MAX];
    char end_out[AMP_PRINTER_GCODE_MAX];
    /** every `.ini` key but start_gcode/end_gcode with its value as written (escapes kept), for the macros:
     *  "key\0value\0" pairs, a later key replacing an earlier one; "" for built-in profiles */
    char vars[AMP_PRINTER_VARS_MAX];
    size_t vars_len;                  /**< bytes of @p vars in use */
    size_t n_vars_dropped;            /**< keys whose value did not fit in @p vars (the name is kept, marked,
                                           while it fits, so that a macro naming it is told why) */
    double bed_radius;                /**< a round bed (bed_shape a regular polygon of 8 or more corners about
                                           the rectangle's centre, as a delta's): the radius of the disc inside
                                           it, mm; 0 = the whole rectangle is printable */
} amp_printer;

/**
 * What the macros know of the job (PrusaSlicer's runtime variables), placed
 * on the bed. amp_printer_job_none() gives the values without a job.
 */
typedef struct amp_printer_job {
    const amp_gcode_opts *opts; /**< the writer's options: their temperatures, filament, retraction, speeds,
                                     first-layer height, bed and height override the profile's fields (the
                                     same keys); NULL = the profile's */
    double max_layer_z;         /**< `max_layer_z`: highest Z printed at, mm (0 without a job) */
    double layer_z;             /**< `layer_z`: first layer's Z in the start, max_layer_z in the end */
    long layer_num;             /**< `layer_num`: 0 in the start, the last layer's index in the end */
    long layers;                /**< `total_layer_count` (0 without a job) */
    double first_layer_min[2];  /**< `first_layer_print_min`: XY box of the first layer on the bed (the bed
                                     without a job) */
    double first_layer_max[2];  /**< `first_layer_print_max` */
} amp_printer_job;

/** Number of built-in profiles. */
size_t amp_printer_builtin_count(void);
/** Name of built-in profile @p i (NULL past the end); index 0 is the default, "generic". */
const char *amp_printer_builtin_name(size_t i);
/** One-line description of built-in profile @p i (NULL past the end). */
const char *amp_printer_builtin_about(size_t i);

/**
 * Fill @p p with built-in profile @p name. AMP_ERR_ARG for NULL or an
 * unknown name (the message lists the built-in names).
 */
amp_status amp_printer_builtin(amp_printer *p, const char *name, amp_error *err);

/**
 * Read a PrusaSlicer/SuperSlicer/OrcaSlicer `.ini` (`key = value` lines,
 * `#`/`;` comments, `[section]` headers ignored) of @p len bytes into @p p:
 * the `generic` profile first, then every key ampath knows (docs/gcode.md
 * lists them; OrcaSlicer's names are aliases); multi-extruder lists take
 * the first value; `\n`, `\r`, `\t`, `\\` and `\"` are unescaped in the G-code
 * strings; percentages of first_layer_speed refer to perimeter_speed.
 * Unknown keys are ignored and collected in p->unknown. Every key but the
 * start/end G-code is also kept, as written, in p->vars for the macros.
 * @p name names the profile (NULL: "ini"). Errors (AMP_ERR_PARSE with the line): a line without
 * `=`, a number that does not parse, an unsupported gcode_flavor, G-code
 * longer than AMP_PRINTER_GCODE_MAX; then amp_printer_check()'s errors.
 */
amp_status amp_printer_parse_ini(amp_printer *p, const char *text, size_t len, const char *name, amp_error *err);

/**
 * A built-in profile when @p spec is one of the names, otherwise the `.ini`
 * file at path @p spec (the profile is named after its base name).
 * Errors: those of amp_printer_builtin (when @p spec contains no '/' and no
 * '.'), amp_read_file and amp_printer_parse_ini.
 */
amp_status amp_printer_load(amp_printer *p, const char *spec, amp_error *err);

/** Check every value's range; AMP_ERR_RANGE naming the field. */
amp_status amp_printer_check(const amp_printer *p, amp_error *err);

/** The job context without a job: no options, max_layer_z = layer_z = 0, no layers, the first layer = the bed. */
void amp_printer_job_none(const amp_printer *p, amp_printer_job *job);

/**
 * Expand @p tmpl, a start or end G-code in PrusaSlicer's macro language
 * (docs/gcode.md lists what is supported), into @p out (@p cap bytes) with
 * the variables of @p p (every `.ini` key; the keys ampath maps resolve to
 * the fields) and of @p job (NULL = amp_printer_job_none). `{if}` blocks may
 * nest (16 deep) and span lines; expressions nest 64 deep. In a comment
 * (after `;`) a placeholder or expression that does not evaluate (an unknown
 * variable, say) is left as it is; elsewhere every error is AMP_ERR_PARSE
 * with err->line the template's line and a message "G-code line L, column C:
 * what" (an unknown variable, a syntax error, an unterminated or unmatched
 * {if}/{else}/{endif}, a bad regular expression, a division by zero, an
 * index out of range, nesting too deep; date/time variables and random() are
 * refused: the output is reproducible). AMP_ERR_LIMIT when @p out is too
 * small (it also holds the evaluation's temporary strings).
 */
amp_status amp_printer_expand_job(const amp_printer *p, const amp_printer_job *job, const char *tmpl, char *out,
                                  size_t cap, amp_error *err);

/** amp_printer_expand_job() without a job (amp_printer_job_none). */
amp_status amp_printer_expand(const amp_printer *p, const char *tmpl, char *out, size_t cap, amp_error *err);

/**
 * Fill @p o (first set to the flavour's defaults) from @p p: bed, height,
 * temperatures, fan, retraction, z-hop, speeds, accelerations, flavour,
 * filament, flow, and the expanded start/end G-code (written into
 * p->start_out / p->end_out, which @p o then points to: @p p must outlive
 * @p o; an empty sequence leaves the writer's built-in one). Placement stays
 * AMP_PLACE_CENTER. The start/end G-code is expanded without a job
 * (amp_printer_job_none): call amp_printer_gcode_job() once the options and
 * the paths are final. Errors: those of amp_printer_check and
 * amp_printer_expand, the message prefixed with "printer 'NAME': start "
 * or "end ".
 */
amp_status amp_printer_gcode_opts(amp_printer *p, amp_gcode_opts *o, amp_error *err);

/**
 * Expand p's start/end G-code again for the job @p ps written with @p o
 * (after amp_printer_gcode_opts() and the caller's changes to @p o: flavour,
 * placement, overrides), so that the macros see the placed job
 * (max_layer_z, first_layer_print_min/max/size, total_layer_count, ...) and
 * o's values for the keys it overrides (amp_printer_job.opts). A sequence
 * the caller replaced (o->start_gcode / o->end_gcode no longer p's) is left
 * alone. When a sequence uses a job variable the writer's dry run
 * (amp_gcode_iter_init) places the job in @p scratch (its content is
 * replaced; NULL = an iterator on the stack, sizeof(amp_gcode_iter) bytes).
 * o->start_gcode / o->end_gcode then point into @p p again. Errors: those of
 * amp_gcode_iter_init (a job that does not fit is refused here) and of
 * amp_printer_expand_job, prefixed with "printer 'NAME': start " or "end ";
 * @p o is then unchanged, but p's expanded texts it points to are not to be
 * used.
 */
amp_status amp_printer_gcode_job(amp_printer *p, amp_gcode_opts *o, const amp_pathset *ps, amp_gcode_iter *scratch,
                                 amp_error *err);

/** Bead width of planar paths for this printer: 1.125 x the nozzle diameter (docs/interfaces.md §4 slice). */
double amp_printer_bead_width(const amp_printer *p);

#ifdef __cplusplus
}
#endif
#endif
