/*
 * ampath/gcode.h — G-code from print paths with MDR-modulated extrusion (SPEC §5).
 *
 * The writer is an iterator over caller memory: amp_gcode_iter_init() checks
 * the options and the paths and computes the estimates, then each
 * amp_gcode_iter_next() call writes exactly one line into a caller buffer.
 * Nothing is allocated (the iterator is plain data of a few kilobytes), so
 * the printer bridge and small firmware can pull lines as the printer takes
 * them without building the file. amp_gcode_write() is the convenience that
 * pushes every line, newline-terminated, into an amp_sink_fn.
 *
 * What is emitted, in order:
 *   1. a header of `;` comments: flavor, the estimates (time, filament, lines)
 *   2. the start sequence: the caller's text, or the built-in one (bed and
 *      hot-end temperatures, G28 homing, waiting for temperatures);
 *   3. set-up that the rest depends on (always): G21, G90 (absolute XYZ),
 *      M82 or M83 (absolute or relative E), G92 E0, the acceleration
 *      (Marlin `M204 S`, Klipper `SET_VELOCITY_LIMIT ACCEL=`);
 *   4. per path a comment `; path I ROLE N vertices` (I counts from 0 in
 *      file order), a travel from the previous path, then one
 *      `G1 X Y Z E [F]` per segment of non-zero length;
 *   5. retraction and a vertical lift of end_lift, then the end sequence
 *      (caller's text or built-in: heaters off, fan off, motors off).
 *
 * Extrusion (SPEC §5): a segment of length L whose end radii are r0, r1
 * extrudes E = flow * (pi r^2 L) / (pi (d/2)^2) mm of filament, r = (r0+r1)/2,
 * d = filament diameter. Its feed is print_feed unless pi r^2 v would exceed
 * max_volumetric_flow; then it is lowered to max_volumetric_flow / (pi r^2)
 * (rounded down to the 0.1 mm/min printed in F).
 *
 * Travel (no gouging): between two paths the head retracts, rises to
 * z_travel = max(top of printed material within travel_corridor of the
 * travel line, start z, end z) + z_hop, moves in XY with G0, descends, and
 * unretracts. The material top is tracked conservatively in a fixed grid of
 * AMP_GCODE_GRID^2 cells over the XY bounding box of the job: every printed
 * segment raises the cells within its radius to its highest z + r, and a
 * travel reads every cell within the corridor of its line, so the lift can be
 * higher than needed but never lower.
 *
 * Print-time estimate: every move is a block of a look-ahead planner of
 * AMP_GCODE_LOOKAHEAD blocks, like the firmware's block buffer: trapezoidal
 * speed profiles with acceleration `accel`; speed at a junction between two
 * printing segments limited by the junction-deviation rule of Marlin/Grbl
 * (v^2 = accel * jd * sin(t/2) / (1 - sin(t/2)), t the angle between the
 * reversed incoming and the outgoing direction) and by both segments' feeds;
 * the planner must be able to stop at the end of its window and at every
 * travel, retraction and path end. Feeds are clamped to max_feed_xy,
 * max_feed_z (z component) and max_feed_e (filament speed) as firmware does.
 * Heating and homing time are not included.
 *
 * Numbers: X Y Z with 3 decimals, E with 5, F (mm/min) with 1, trailing
 * zeros dropped; no exponent notation, no locale dependence. Every line is at
 * most AMP_GCODE_LINE_MAX characters, so that a sender can add `N<line>` and
 * `*<checksum>` within Marlin's MAX_CMD_SIZE of 96. E values are rounded once
 * on the absolute scale, so relative E values add up exactly to the absolute
 * ones. Line numbers and checksums are not written (that is the sender's job).
 *
 * Thread-safety: an iterator is used by one thread at a time; any number of
 * iterators may read the same amp_pathset concurrently.
 */
#ifndef AMPATH_GCODE_H
#define AMPATH_GCODE_H

#include <stddef.h>

#include "io.h"
#include "paths.h"
#include "status.h"
#include "vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Firmware flavors. */
#define AMP_FLAVOR_MARLIN 0
#define AMP_FLAVOR_KLIPPER 1

/** Longest line produced, without the NUL. */
#define AMP_GCODE_LINE_MAX 80
/** Smallest buffer accepted by amp_gcode_iter_next() (line + NUL). */
#define AMP_GCODE_LINE_CAP (AMP_GCODE_LINE_MAX + 1)

/** Cells per side of the material-height grid used to lift travels (compile-time; 32 = 4 KiB). */
#ifndef AMP_GCODE_GRID
#define AMP_GCODE_GRID 32
#endif
/** Blocks in the look-ahead planner of the time estimate (Marlin's BLOCK_BUFFER_SIZE is 16). */
#define AMP_GCODE_LOOKAHEAD 16

/** Printer and G-code options. Fill with amp_gcode_opts_default(), then change fields. */
typedef struct amp_gcode_opts {
    int flavor;                 /**< AMP_FLAVOR_MARLIN or AMP_FLAVOR_KLIPPER */
    double filament_diameter;   /**< mm (1.75) */
    double flow;                /**< extrusion multiplier (1.0) */
    double max_volumetric_flow; /**< mm^3/s the hot end melts at most (12) */
    double print_feed;          /**< mm/s along printing segments (30) */
    double travel_feed;         /**< mm/s of G0 moves (120) */
    double retract_length;      /**< mm of filament pulled back before a travel (1.0; 0 = none) */
    double retract_speed;       /**< mm/s of filament for retract and unretract (35) */
    double z_hop;               /**< mm of clearance above printed material during a travel (0.4) */
    double travel_corridor;     /**< mm half-width around a travel line checked for material (2.0) */
    double end_lift;            /**< mm the head rises at the end of the job (10) */
    int relative_e;             /**< 1: M83 relative E; 0: M82 absolute E (Marlin 0, Klipper 1) */
    double hotend_temp;         /**< deg C for the built-in start sequence (210; 0 = do not heat) */
    double bed_temp;            /**< deg C for the built-in start sequence (60; 0 = do not heat) */
    const char *start_gcode;    /**< start sequence text (lines), NULL = built-in; not copied */
    const char *end_gcode;      /**< end sequence text (lines), NULL = built-in; not copied */
    double accel;               /**< mm/s^2 for the estimate and the set-up command (1000) */
    double junction_deviation;  /**< mm, junction speed rule of the estimate (0.05) */
    double max_feed_xy;         /**< mm/s limit of the XY speed in the estimate (200) */
    double max_feed_z;          /**< mm/s limit of the Z speed, also the feed of travel lifts (10) */
    double max_feed_e;          /**< mm/s limit of the filament speed in the estimate (60) */
} amp_gcode_opts;

/** Figures of a job. Times in seconds, lengths in mm, volumes in mm^3. */
typedef struct amp_gcode_stats {
    size_t lines;                 /**< lines written (all of them, comments included) */
    size_t paths;                 /**< paths printed (at least one segment of non-zero length) */
    size_t paths_skipped;         /**< paths without a segment of non-zero length */
    size_t segments;              /**< G1 extrusion moves */
    size_t travels;               /**< travels between paths (including the first approach) */
    size_t retractions;           /**< retractions (each followed by an unretraction except at the end) */
    size_t lowered_feed_segments; /**< segments whose feed the volumetric cap lowered */
    double print_length;          /**< length of the extrusion moves */
    double travel_length;         /**< length of the G0 moves (lifts, XY, descents) */
    double filament_length;       /**< filament pushed by extrusion moves (retractions excluded) */
    double filament_volume;       /**< = filament_length * pi (d/2)^2 */
    double time;                  /**< estimated print time (moves only; no heating, no homing) */
    double print_time;            /**< part of time spent in extrusion moves */
    double travel_time;           /**< part spent in travels, retractions and lifts */
    double max_travel_z;          /**< highest z a travel rose to */
} amp_gcode_stats;

/** The motion of the last line (for callers that follow the head; kind 0 = the line was not a move). */
typedef struct amp_gcode_move {
    int kind;        /**< 0 none, 1 extrusion segment, 2 travel (G0), 3 retract/unretract (E only) */
    size_t path;     /**< path index of an extrusion segment or of the path a travel goes to */
    size_t seg;      /**< segment index within the path (extrusion) */
    amp_vec3 to;     /**< target position (exact, before rounding to 3 decimals) */
    double e;        /**< filament delta of this move, exact (before rounding) */
    double feed;     /**< mm/s as printed in F (F / 60) */
    double r;        /**< mean deposition radius of an extrusion segment */
    double length;   /**< length of the move in XYZ */
} amp_gcode_move;

/** One planner block of the estimate (internal; part of the iterator's plain data). */
typedef struct amp_gcode_block {
    double len, vnom, vjunc, ux, uy, uz;
} amp_gcode_block;

/**
 * The iterator: plain data, no pointers to owned memory. Read-only for the
 * caller except through the functions; `path` (current path index), `stats`
 * (figures of the lines written so far), `est` (figures of the whole job,
 * known after init) and `last` may be read at any time.
 */
typedef struct amp_gcode_iter {
    unsigned magic;     /* set by a successful init */
    amp_gcode_opts o;
    const amp_pathset *ps;
    int phase;          /* state machine: header, start, set-up, paths, end */
    size_t sub;         /* line index within the phase */
    size_t path, seg;   /* current path and segment */
    const char *text;   /* position in a start or end sequence */
    int pass;           /* 1 = estimate (init), 2 = lines */
    int have_pos, retracted, printed_any;
    amp_vec3 pos;       /* exact head position */
    double e_exact;     /* absolute E, exact */
    long long e_units;  /* absolute E as last printed, in 1e-5 mm */
    long long f_units;  /* modal feed as last printed, in 0.1 mm/min (-1 = none) */
    double travel_z;
    amp_vec3 travel_to;
    double fil_area;    /* pi (d/2)^2 */
    double grid_x0, grid_y0, grid_cell;
    float grid[AMP_GCODE_GRID * AMP_GCODE_GRID]; /* top of printed material per cell (-inf = none) */
    amp_gcode_block plan[AMP_GCODE_LOOKAHEAD];
    size_t plan_head, plan_n;
    double plan_v;      /* entry speed of the oldest block */
    int plan_print;     /* the planned blocks are extrusion moves (1) or travel (0) */
    amp_gcode_stats stats;
    amp_gcode_stats est;
    amp_gcode_move last;
} amp_gcode_iter;

/**
 * Fill @p o with the defaults of @p flavor (documented per field above;
 * relative_e is 1 for Klipper, 0 for Marlin). An unknown flavor gives the
 * Marlin defaults with o->flavor set as given (amp_gcode_iter_init rejects it).
 */
void amp_gcode_opts_default(amp_gcode_opts *o, int flavor);

/**
 * Check @p o (NULL = Marlin defaults) and @p ps, and compute the figures of
 * the whole job into it->est by running the job once without formatting
 * (O(number of vertices), no allocation). @p ps and the start/end texts must
 * stay unchanged while the iterator is used; the options are copied.
 * Errors: AMP_ERR_ARG for NULL, an empty path set (no segment of non-zero
 * length), a non-finite vertex or an option out of range (the message names
 * the option); AMP_ERR_LIMIT for a start/end line longer than
 * AMP_GCODE_LINE_MAX (err->line = its line in that text); AMP_ERR_RANGE for
 * coordinates beyond +-99999 mm.
 */
amp_status amp_gcode_iter_init(amp_gcode_iter *it, const amp_pathset *ps, const amp_gcode_opts *o, amp_error *err);

/**
 * Write the next line into @p line (NUL-terminated, no newline, at most
 * AMP_GCODE_LINE_MAX characters). Returns 1 when a line was written, 0 at the
 * end (and on every later call), or a negative amp_status: AMP_ERR_ARG for a
 * NULL argument or @p cap < AMP_GCODE_LINE_CAP, AMP_ERR_STATE for an iterator
 * that init did not accept.
 */
int amp_gcode_iter_next(amp_gcode_iter *it, char *line, size_t cap, amp_error *err);

/**
 * Write the whole job through @p sink, one newline-terminated line per call.
 * @p stats (optional) receives the figures. Errors: those of init, or the
 * sink's status (the job is then incomplete).
 */
amp_status amp_gcode_write(const amp_pathset *ps, const amp_gcode_opts *o, amp_sink_fn sink, void *user,
                           amp_gcode_stats *stats, amp_error *err);

/**
 * Time of a move of length @p len from speed @p v0 to @p v1 with cruise
 * speed at most @p vmax and acceleration @p accel (trapezoid or triangle).
 * Exposed for tests and the preview; requires v0, v1 reachable within len.
 */
double amp_gcode_trapezoid_time(double len, double v0, double v1, double vmax, double accel);

#ifdef __cplusplus
}
#endif
#endif
