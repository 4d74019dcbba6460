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
    double max_volumetric_flow;       /**< mm^3/s */
    double extrusion_multiplier;
    char start_gcode[AMP_PRINTER_GCODE_MAX]; /**< "" = the writer's built-in sequence; placeholders unexpanded */
    char end_gcode[AMP_PRINTER_GCODE_MAX];
    char unknown[AMP_PRINTER_UNKNOWN_MAX];   /**< keys of the `.ini` that ampath does not use, comma-separated */
    size_t n_unknown;                 /**< how many (also those that did not fit in @p unknown) */
    size_t n_keys;                    /**< keys read from the `.ini` */
    /* expanded start/end sequences, written by amp_printer_gcode_opts() */
    char start_out[AMP_PRINTER_GCODE_MAX];
    char end_out[AMP_PRINTER_GCODE_MAX];
} amp_printer;

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
 * Unknown keys are ignored and collected in p->unknown. @p name names the
 * profile (NULL: "ini"). Errors (AMP_ERR_PARSE with the line): a line without
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

/**
 * Expand the placeholders of @p tmpl into @p out (@p cap bytes):
 * `[key]`, `[key_0]`, `{key}` and `{key[0]}` for temperature,
 * first_layer_temperature, bed_temperature, first_layer_bed_temperature,
 * nozzle_diameter, filament_diameter, layer_height, first_layer_height,
 * max_print_height, printer_model, travel_speed, retract_length,
 * initial_extruder, current_extruder (and OrcaSlicer's names for the
 * temperatures). In a comment (after `;`) an unknown placeholder stays as it
 * is; in a command it is an error (AMP_ERR_PARSE, the line and the
 * placeholder named), as is a `{if ...}` block: ampath does not evaluate the
 * slicers' macro language. AMP_ERR_LIMIT when @p out is too small.
 */
amp_status amp_printer_expand(const amp_printer *p, const char *tmpl, char *out, size_t cap, amp_error *err);

/**
 * Fill @p o (first set to the flavour's defaults) from @p p: bed, height,
 * temperatures, fan, retraction, z-hop, speeds, accelerations, flavour,
 * filament, flow, and the expanded start/end G-code (written into
 * p->start_out / p->end_out, which @p o then points to: @p p must outlive
 * @p o; an empty sequence leaves the writer's built-in one). Placement stays
 * AMP_PLACE_CENTER. Errors: those of amp_printer_check and amp_printer_expand.
 */
amp_status amp_printer_gcode_opts(amp_printer *p, amp_gcode_opts *o, amp_error *err);

/** Bead width of planar paths for this printer: 1.125 x the nozzle diameter (docs/interfaces.md §4 slice). */
double amp_printer_bead_width(const amp_printer *p);

#ifdef __cplusplus
}
#endif
#endif
