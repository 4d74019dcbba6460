/*
 * gcode_internal.h — shared between the G-code writer (gcode.c) and its
 * print-time estimate (gcode_estimate.c). Not installed.
 */
#ifndef AMP_GCODE_INTERNAL_H
#define AMP_GCODE_INTERNAL_H

#include "ampath/gcode.h"

/*
 * Queue a move of direction @p d (length @p len, filament @p de) at @p feed
 * mm/s in the look-ahead planner; @p travel: a G0 (its time counts as travel).
 * Firmware blends G0 and G1 blocks alike at their junctions.
 */
void amp_gc_plan_move(amp_gcode_iter *it, amp_vec3 d, double len, double feed, double de, int travel);
/* A move outside the print planner (travel, retraction): from rest to rest at @p v mm/s. */
void amp_gc_plan_single(amp_gcode_iter *it, double len, double v);
/* Execute every planned block and come to rest. */
void amp_gc_plan_flush(amp_gcode_iter *it);

/* The start or end sequence @p text (@p what: "start", "end") for Klipper: AMP_ERR_LIMIT naming the line when a
 * move of it would stop a Klipper job (max_extrude_cross_section, max_extrude_only_distance); AMP_OK for any
 * other flavour (gcode_seqcheck.c). */
amp_status amp_gc_klipper_sequence_fits(const amp_gcode_opts *o, const char *text, const char *what, amp_error *err);

/* A helical arc from the current vertex to vertex @p end: centre (cx, cy), clockwise or not, length in XYZ. */
typedef struct amp_gc_arc {
    double cx, cy, len;
    int cw;
    size_t end;
} amp_gc_arc;

/*
 * The longest arc from vertex @p k of the path @p v (n vertices) that keeps
 * every vertex within o->chord_tol (and its radius within o->radius_tol) and
 * reaches beyond @p line_end (the end of the straight segment the writer would
 * take); 1 with *arc filled, 0 when no such arc exists (gcode_arc.c).
 */
int amp_gc_fit_arc(const amp_pvert *v, size_t n, size_t k, size_t line_end, const amp_gcode_opts *o, amp_gc_arc *arc);

#endif
