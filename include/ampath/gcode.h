/*
 * ampath/gcode.h — G-code from print paths with MDR-modulated extrusion (docs/interfaces.md §5).
 *
 * The writer is an iterator over caller memory: amp_gcode_iter_init() checks
 * the options and the paths and computes the estimates, then each
 * amp_gcode_iter_next() call writes exactly one line into a caller buffer.
 * Nothing is allocated (the iterator is plain data of a few kilobytes), so
 * the printer bridge and small firmware can pull lines as the printer takes
 * them without building the file. amp_gcode_write() is the convenience that
 * pushes every line, newline-terminated, into an amp_sink_fn. A caller that
 * can put the header in front afterwards (a file) runs the job once with
 * amp_gcode_iter_init_body() and amp_gcode_iter_header().
 *
 * What is emitted, in order:
 *   1. a header of `;` comments: profile, flavor, placement offset and the
 *      placed bounding box, the estimates (time, filament, lines);
 *   2. the start sequence: the caller's text, or the built-in one (bed and
 *      hot-end first-layer temperatures, G28 homing, waiting for both). A
 *      caller's text without M190/M140 gets `M190 S<first-layer bed>` before
 *      it, one without M109/M104 gets `M104` before and `M109` after it (with
 *      the first-layer temperatures), as PrusaSlicer does;
 *   3. set-up that the rest depends on (always): G21 (Marlin only; Klipper
 *      has millimetres only), G90 (absolute XYZ), M82 or M83, G92 E0, the
 *      acceleration (Marlin `M204 S`, Klipper `SET_VELOCITY_LIMIT ACCEL=`),
 *      M107 when the job uses the fan;
 *   4. per path a comment `; path I ROLE N vertices` (I counts from 0 in
 *      file order); at the first path above the first layer the other-layer
 *      temperatures (M104/M140 without waiting, only when they differ), at
 *      the first path of layer fan_off_layers `M106 S<0..255>`; a travel from
 *      the previous path, then one `G1 X Y Z E [F]` per simplified segment;
 *   5. retraction and a lift of end_lift (at most to the bed's maximum
 *      height), M107 if the fan was on, then the end sequence (caller's text
 *      or built-in: heaters off, fan off, motors off).
 *
 * Placement (docs/interfaces.md §5): AMP_PLACE_CENTER (default) puts the centre of the
 * job's XY bounding box at the centre of the bed, AMP_PLACE_AT at
 * (place_x, place_y); both shift z so that the job rests on the bed: the
 * lowest bead bottom (vertex z - h for planar beads, z - r for tubes) is at
 * z = 0, which puts the first planar layer at its bead height and the lowest
 * tube at its radius. AMP_PLACE_ORIGIN writes the job's own coordinates.
 * Every written X, Y lies in [bed_min, bed_max] and every Z in
 * [0, max_height]; init refuses a job that does not fit (AMP_ERR_RANGE, the
 * message names the axis and the overflow in mm).
 *
 * Extrusion (docs/interfaces.md §5): a segment of length L whose end radii are r0, r1
 * extrudes E = flow * A L / (pi (d/2)^2) mm of filament, r = (r0+r1)/2,
 * d = filament diameter, A = amp_bead_area(r, h): pi r^2 for a tube, the
 * rounded rectangle (2r - h) h + pi (h/2)^2 for a planar bead of height h.
 * Its feed is print_feed (first_layer_feed on the first layer) unless A v
 * would exceed max_volumetric_flow; then it is lowered to
 * max_volumetric_flow / A (rounded down to the 0.1 mm/min printed in F).
 *
 * Clean segments: with chord_tol > 0 each path is simplified greedily: a
 * written segment from vertex k to vertex j replaces the input vertices
 * between them when each lies within chord_tol of the chord and its radius
 * within radius_tol of the radius interpolated along the chord; its E is the
 * sum of the replaced segments' E, so the volume is exact. With min_segment
 * > 0 no extruding segment is shorter than min_segment unless it is a whole
 * path (short pieces are merged with the next, or the last with the one
 * before), measured on the coordinates as written (3 decimals, with half a
 * unit of the last one to spare: a chord of 0.0200 mm that rounds to
 * 0.020 grows past it). chord_tol = min_segment = 0 writes every input segment. With
 * arcs = 1 a run of vertices on one circle in XY (z and radius linear in the
 * angle, each polyline piece within chord_tol of the arc, circle radius
 * 0.5..1000 mm, sweep below 2 pi) that reaches beyond the straight segment is
 * written as one `G2`/`G3 X Y Z I J E` (Marlin ARC_SUPPORT, Klipper
 * [gcode_arcs]); its E is again the exact sum of the replaced segments'.
 *
 * First layer: for planar jobs the paths at the lowest planar layer z; for
 * tube jobs the paths whose lowest bead point lies below first_layer_height
 * above the bed. Layers (for the fan): planar paths count a new layer at each
 * rise of the bead z in print order; tubes are in layer
 * floor(bottom / first_layer_height).
 *
 * Travel (no gouging): between two paths the head retracts (unless the XY
 * distance is below retract_min_travel), rises by z_hop, then follows the
 * lowest polyline from (start, z+z_hop) to (end, z+z_hop) that stays z_hop
 * above all printed material within travel_corridor of the travel line (the
 * upper convex hull of the material heights sampled along the line: a single
 * straight move when nothing printed is in the way), descends and
 * unretracts. The material top is tracked conservatively in a fixed grid of
 * AMP_GCODE_GRID^2 cells over the XY bounding box of the job: every printed
 * segment raises the cells within its radius to its highest z (+ r for
 * tubes), so a travel can be higher than needed but never lower. Beyond the
 * corridor the head cone (tip head_z_offs above the nozzle, half-angle
 * head_theta; docs/interfaces.md §2) must clear every printed centre line (a second grid
 * holds the highest centre line per cell).
 *
 * Direct hops: a travel of at most direct_hop in XY is one
 * straight G0 without retraction or lift, blended into the printing that
 * follows, when along it the head cone clears every printed centre line and,
 * away from its ends (bead radius + 2 cells), no printed material is above
 * the nozzle.
 *
 * Print-time estimate: every move is a block of a look-ahead planner of
 * AMP_GCODE_LOOKAHEAD blocks, like the firmware's block buffer: trapezoidal
 * speed profiles with acceleration `accel`; speed at a junction between two
 * printing segments limited by the junction-deviation rule of Marlin/Grbl
 * (v^2 = accel * jd * sin(t/2) / (1 - sin(t/2)), t the angle between the
 * reversed incoming and the outgoing direction) and by both segments' feeds;
 * the planner must be able to stop at the end of its window and at every
 * travel, retraction and path end. Feeds are clamped to max_feed_xy,
 * max_feed_z (z component) and max_feed_e (filament speed) as firmware does,
 * and each move's acceleration to max_accel_xy, max_accel_z and max_accel_e
 * along its direction (a lift of the head accelerates at Z's 100 mm/s^2, not
 * at the 1000 of the moves); retractions accelerate at retract_accel.
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

/**
 * Cells per side of the material-height grid used to lift travels (compile-time, a power of two from 16
 * to 32768; 128 = 64 KiB a grid, the iterator is then about 160 KiB; -DAMP_GCODE_GRID=32 gives a 20 KiB
 * iterator for small targets, with travels longer because the tops are tracked more coarsely: the demo's
 * travel time 2390 s instead of 1640 s).
 */
#ifndef AMP_GCODE_GRID
#define AMP_GCODE_GRID 128
#endif
/** Nodes of the max-pyramid over the centre-line grid: the levels of side GRID/2, GRID/4, ... 1. */
#define AMP_GCODE_PYRAMID ((AMP_GCODE_GRID * AMP_GCODE_GRID - 1) / 3)
/** Blocks in the look-ahead planner of the time estimate (Marlin's BLOCK_BUFFER_SIZE is 16). */
#define AMP_GCODE_LOOKAHEAD 16
/** Most corners of one travel polyline (the upper hull of the sampled material heights). */
#define AMP_GCODE_HULL 512
/** Longest run of input vertices merged into one written segment by the simplification. */
#define AMP_GCODE_MERGE_MAX 64

/** Placement modes (amp_gcode_opts.place). */
#define AMP_PLACE_CENTER 0 /**< centre of the job's XY box at the bed centre, resting on the bed */
#define AMP_PLACE_ORIGIN 1 /**< the job's own coordinates */
#define AMP_PLACE_AT 2     /**< centre of the job's XY box at (place_x, place_y), resting on the bed */

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
    double travel_corridor;     /**< mm half-width around a travel line checked for material (1.0) */
    double end_lift;            /**< mm the head rises at the end of the job (10) */
    int relative_e;             /**< 1: M83 relative E; 0: M82 absolute E (Marlin 0, Klipper 1) */
    double hotend_temp;         /**< deg C for the built-in start sequence (210; 0 = do not heat) */
    double bed_temp;            /**< deg C for the built-in start sequence (60; 0 = do not heat) */
    const char *start_gcode;    /**< start sequence text (lines), NULL = built-in; not copied */
    const char *end_gcode;      /**< end sequence text (lines), NULL = built-in; not copied */
    double accel;               /**< mm/s^2 for the estimate and the set-up command (1000) */
    double junction_deviation;  /**< mm, junction speed rule of the estimate (Marlin 0.05; Klipper: its
                                     square_corner_velocity 5 mm/s, amp_gcode_junction_default()) */
    double max_feed_xy;         /**< mm/s limit of the XY speed in the estimate (200) */
    double max_feed_z;          /**< mm/s limit of the Z speed, also the feed of travel lifts (10) */
    double max_feed_e;          /**< mm/s limit of the filament speed in the estimate (60) */
    double max_accel_xy;        /**< mm/s^2 per-axis limits of the estimate (Marlin's max_acceleration: a move's */
    double max_accel_z;         /**< acceleration is lowered until no axis exceeds its own): X and Y (3000), */
    double max_accel_e;         /**< Z (100), filament (10000); 0 = no limit */
    double retract_accel;       /**< mm/s^2 of retractions (Marlin's M204 R, 3000; 0: accel) */
    double max_cross_section;   /**< mm^2, Klipper flavour only: Klipper's max_extrude_cross_section (4 x
                                     nozzle^2; 0.64 for the 0.4 mm nozzle). Klipper refuses a move whose E over
                                     its XYZ length, times the filament's area, is larger, and the job stops
                                     there: amp_gcode_iter_init() refuses such a job instead (AMP_ERR_LIMIT,
                                     naming the path). 0 = no limit. Marlin has no such check */
    /* printer and placement (docs/interfaces.md §5); amp_printer_gcode_opts() fills these from a profile */
    const char *profile;        /**< printer name for the header ("generic"); not copied */
    int place;                  /**< AMP_PLACE_CENTER (default), AMP_PLACE_ORIGIN or AMP_PLACE_AT */
    double place_x, place_y;    /**< AMP_PLACE_AT: bed point of the centre of the job's XY box (mm) */
    double bed_min_x, bed_min_y;/**< printable rectangle, mm (0, 0) */
    double bed_max_x, bed_max_y;/**< (220, 220) */
    double max_height;          /**< highest Z written, mm (250) */
    double first_layer_height;  /**< mm (0.2): tube paths whose bead bottom lies below it are first layer */
    double first_layer_feed;    /**< mm/s on the first layer (20) */
    double first_layer_hotend_temp; /**< deg C of the start sequence (215; 0 = do not heat) */
    double first_layer_bed_temp;    /**< deg C of the start sequence (60; 0 = do not heat) */
    int fan_off_layers;         /**< part-cooling fan off for this many layers (1) */
    double fan_speed;           /**< fan after them, 0..1 of full speed (1; 0 = no fan commands) */
    double retract_min_travel;  /**< mm: shorter XY travels do not retract (2; PrusaSlicer retract_before_travel) */
    double chord_tol;           /**< mm, simplification chord tolerance (0.01; 0 = off) */
    double radius_tol;          /**< mm, deposition radius tolerance of the simplification (0.01) */
    double min_segment;         /**< mm, shortest extruding segment unless a whole path (0.02; 0 = off) */
    int arcs;                   /**< 1: fit helical arcs, written as G2/G3 (0; needs firmware arc support) */
    double direct_hop;          /**< mm: XY travels up to this long go straight, without retraction or lift,
                                     when the head cone clears all printed material (3; 0 = never) */
    double head_z_offs;         /**< mm, head cone tip above the nozzle point (docs/interfaces.md §2; 0.5) */
    double head_theta;          /**< degrees, head cone half-angle from the vertical (docs/interfaces.md §2; 72) */
    double bed_radius;          /**< mm: a round bed, the disc of this radius about the rectangle's centre is
                                     printable (0: the whole rectangle) */
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
    double max_travel_z;          /**< highest z a travel rose to (placed) */
    size_t input_segments;        /**< segments of non-zero length in the input paths */
    size_t arcs;                  /**< G2/G3 moves (counted in segments too) */
    size_t travel_moves;          /**< G0 lines */
    double bead_volume;           /**< sum of A L over the printed paths (docs/interfaces.md §5), mm^3 */
    double first_layer_z;         /**< placed z of the first extrusion */
    amp_box3 bbox;                /**< placed bounding box of the printed vertices */
    size_t direct_hops;           /**< travels written as one straight move without retraction or lift */
    amp_box3 first_layer_bbox;    /**< placed bounding box of the first layer's printed vertices (empty if none) */
    size_t layers;                /**< layers as the fan counts them (last layer index + 1; 0 before any path) */
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
    double acc;   /* the move's acceleration: accel lowered by the per-axis limits */
    double vback; /* the highest speed it may enter the next block with, from the window's end at rest */
    int travel;   /* a G0: its time counts as travel time */
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
    int body_only;      /* amp_gcode_iter_init_body: no header lines; est filled at the end */
    size_t xs_path;     /* pass 1: the first path with a move over max_cross_section ((size_t)-1: none) */
    double xs_area;     /* its cross-section, mm^2 */
    int have_pos, retracted, printed_any;
    amp_vec3 pos;       /* exact head position */
    double e_exact;     /* absolute E, exact */
    long long e_units;  /* absolute E as last printed, in 1e-5 mm */
    long long f_units;  /* modal feed as last printed, in 0.1 mm/min (-1 = none) */
    amp_vec3 travel_to;
    amp_vec3 off;       /* placement offset added to every written coordinate */
    double zmax;        /* highest model z a travel may reach (max_height - off.z) */
    double zlow;        /* lowest bead bottom of the job (model z) */
    double z_first;     /* planar: z of the lowest planar layer (model); HUGE_VAL if none */
    double layer_z;     /* planar: z of the current layer */
    int layer;          /* highest layer index so far (planar: the current path's) */
    int path_layer;     /* the current path's own layer (a tube printed after higher ones may lie lower) */
    int first_done, fan_on, travel_retract, path_first;
    amp_vec3 travel_from;
    size_t nxt;         /* end vertex of the next written segment */
    size_t hull_n, hull_i;
    double hull_t[AMP_GCODE_HULL], hull_z[AMP_GCODE_HULL]; /* travel polyline: (fraction, z) corners */
    double fil_area;    /* pi (d/2)^2 */
    double grid_x0, grid_y0, grid_cell;
    float grid[AMP_GCODE_GRID * AMP_GCODE_GRID]; /* top of printed material per cell (-inf = none) */
    float grid_c[AMP_GCODE_GRID * AMP_GCODE_GRID]; /* highest printed centre line per cell (head cone test) */
    float grid_cp[AMP_GCODE_PYRAMID]; /* highest of grid_c per 2^l x 2^l block, levels l = 1, 2, ... (side 1) */
    double zc_max;      /* highest printed centre line so far */
    int band_lazy;      /* a planar job printed layer by layer: material bands raised only when read (gcode.c) */
    int band_pending;   /* the bands written from (band_path, band_seg) on are not in grid yet */
    size_t band_path, band_seg;
    float band_top;     /* their highest top, as grid would hold it */
    double end_r;       /* deposition radius at the end of the last printed segment */
    int direct;         /* the current travel is a direct hop */
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
 * amp_gcode_iter_init() without its run of the whole job: for a caller that
 * can put the header in front afterwards (the ampath tool writes the body to a
 * temporary file), so the job is run once instead of twice. Checks and places
 * the job as init does; the lines are then those of amp_gcode_iter_init() but
 * for the header comment, which is left out (its figures are not known yet).
 * Once amp_gcode_iter_next() has returned 0, it->est holds the figures of the
 * whole job (the header lines counted) and amp_gcode_iter_header() writes the
 * header. A move over max_cross_section, which init refuses, is reported by
 * amp_gcode_iter_next() when reached (AMP_ERR_LIMIT, same message): the lines
 * before it must then be thrown away. amp_gcode_iter_rewind() keeps the
 * header left out. Errors: those of amp_gcode_iter_init() but AMP_ERR_LIMIT.
 */
amp_status amp_gcode_iter_init_body(amp_gcode_iter *it, const amp_pathset *ps, const amp_gcode_opts *o,
                                    amp_error *err);

/**
 * Write the header comment of the job (profile, placement, bounding box, time
 * and filament estimate; newline-terminated lines through @p sink): the lines
 * amp_gcode_iter_init()'s iterator starts with, from it->est. Errors:
 * AMP_ERR_ARG for NULL, AMP_ERR_STATE before the figures are known (an
 * iterator init did not accept, or a body-only one before its end), or the
 * sink's status.
 */
amp_status amp_gcode_iter_header(amp_gcode_iter *it, amp_sink_fn sink, void *user, amp_error *err);

/**
 * Write the next line into @p line (NUL-terminated, no newline, at most
 * AMP_GCODE_LINE_MAX characters). Returns 1 when a line was written, 0 at the
 * end (and on every later call), or a negative amp_status: AMP_ERR_ARG for a
 * NULL argument or @p cap < AMP_GCODE_LINE_CAP, AMP_ERR_STATE for an iterator
 * that init did not accept.
 */
int amp_gcode_iter_next(amp_gcode_iter *it, char *line, size_t cap, amp_error *err);

/**
 * Back to the first line of the job @p it was initialised with, without
 * running it again: the lines that follow are the same as after init (the
 * estimates in it->est are kept). For a caller that reads the job twice (the
 * bridge checks it, then sends it) or that looked at it->est before writing.
 * Errors: AMP_ERR_ARG for NULL, AMP_ERR_STATE for an iterator that init did
 * not accept.
 */
amp_status amp_gcode_iter_rewind(amp_gcode_iter *it, amp_error *err);

/**
 * Write the rest of the job of an initialised iterator through @p sink, one
 * newline-terminated line per call (amp_gcode_write without a second init:
 * init runs the whole job once, so a caller that has already initialised
 * @p it to look at it->est saves that run). @p stats (optional) receives the
 * figures. Errors: AMP_ERR_ARG for NULL, those of amp_gcode_iter_next(), or
 * the sink's status (the job is then incomplete).
 */
amp_status amp_gcode_iter_write(amp_gcode_iter *it, amp_sink_fn sink, void *user, amp_gcode_stats *stats,
                                amp_error *err);

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

/**
 * The flavour's junction deviation at acceleration @p accel (mm/s^2), the default of
 * amp_gcode_opts.junction_deviation: Marlin 0.05 mm; Klipper its cornering (klippy/toolhead.py), the
 * square_corner_velocity scv = 5 mm/s as J = scv^2 (sqrt 2 - 1) / accel, so that a right angle is taken at
 * 5 mm/s. Used by amp_gcode_opts_default() and amp_printer_gcode_opts(); call it again after changing
 * the flavour or the acceleration.
 */
double amp_gcode_junction_default(int flavor, double accel);

#ifdef __cplusplus
}
#endif
#endif
