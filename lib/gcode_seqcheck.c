/*
 * The caller's start and end sequences as Klipper reads them. Klipper stops a
 * job at a move whose extrusion is wider than max_extrude_cross_section (the E
 * of a move per millimetre of its XYZ length, times the filament's area) and at
 * an extrude-only move longer than max_extrude_only_distance (50 mm unless
 * printer.cfg says otherwise). The writer checks its own paths for the first
 * (gcode.c, xs_fail); a profile's sequence can break either — a Marlin
 * profile's intro line (Prusa's MK3S: 12.5 mm of filament over 40 mm, 0.75
 * mm^2 against the 0.64 of a 0.4 mm nozzle) stopped a Klipper print before its
 * first layer. So the sequence's moves are followed as Klipper follows them
 * (G90/G91, M82/M83, G92) and the job is refused up front, naming the line.
 * An axis's position is known only once a move set it (after G28 it is where
 * the endstop is): a move from an unknown position is not measured.
 */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gcode_internal.h"

#define EXTRUDE_ONLY_MAX 50.0 /* Klipper's default max_extrude_only_distance, mm */

static const char axes[3] = {'X', 'Y', 'Z'};

typedef struct seq_state {
    double pos[3], e;
    int known[3], rel, rel_e;
} seq_state;

/* The value of word @p letter on the line [s, end) (case-insensitive), 1 if present. */
static int word(const char *s, const char *end, char letter, double *v)
{
    for (; s < end; s++)
        if (toupper((unsigned char)*s) == letter && (s + 1 < end) &&
            (isdigit((unsigned char)s[1]) || s[1] == '-' || s[1] == '+' || s[1] == '.')) {
            *v = strtod(s + 1, NULL);
            return isfinite(*v);
        }
    return 0;
}

/* The command word of a line: G1, M83, ... (0 when none). */
static int command(const char *s, const char *end, char *letter)
{
    while (s < end && isspace((unsigned char)*s))
        s++;
    if (s + 1 >= end || !isdigit((unsigned char)s[1]))
        return -1;
    *letter = (char)toupper((unsigned char)*s);
    return atoi(s + 1);
}

/* One move line: its extrusion against Klipper's two limits (0: fits; 1: too wide; 2: extrude-only too long).
 * As Klipper's extruder check_move: a move without X/Y motion, or a retraction, is extrude-only; a move whose
 * E is under nozzle x the ratio limit is not measured (the nozzle taken as sqrt(max_cross_section / 4)). */
static int move_fails(seq_state *q, const amp_gcode_opts *o, const char *s, const char *end, double *area)
{
    double d2 = 0.0, de = 0.0, v, fil = AMP_PI * 0.25 * o->filament_diameter * o->filament_diameter;
    int a, measured = 1, xy = 0;
    for (a = 0; a < 3; a++) {
        double d;
        if (!word(s, end, axes[a], &v))
            continue;
        if (q->rel) {
            d = v;
            q->pos[a] += v;
        } else {
            d = q->known[a] ? v - q->pos[a] : 0.0;
            measured &= q->known[a]; /* from where the endstop left it: not measured */
            q->pos[a] = v;
            q->known[a] = 1;
        }
        d2 += d * d;
        xy |= a < 2 && (d != 0.0 || !measured);
    }
    if (word(s, end, 'E', &v)) {
        de = q->rel_e ? v : v - q->e;
        q->e = q->rel_e ? q->e + v : v;
    }
    *area = fabs(de);
    if (de == 0.0 || !measured)
        return 0;
    if (!xy || de < 0.0)
        return fabs(de) > EXTRUDE_ONLY_MAX ? 2 : 0;
    if (o->max_cross_section <= 0.0 || !(d2 > 0.0))
        return 0;
    *area = de * fil / sqrt(d2);
    return *area > o->max_cross_section * (1.0 + 1e-6) &&
                   de > sqrt(0.25 * o->max_cross_section) * o->max_cross_section / fil
               ? 1
               : 0;
}

amp_status amp_gc_klipper_sequence_fits(const amp_gcode_opts *o, const char *text, const char *what, amp_error *err)
{
    seq_state q;
    long line = 1;
    const char *s = text;
    memset(&q, 0, sizeof q);
    if (!text || o->flavor != AMP_FLAVOR_KLIPPER)
        return AMP_OK;
    while (*s) {
        const char *nl = strchr(s, '\n'), *end = nl ? nl : s + strlen(s), *semi = memchr(s, ';', (size_t)(end - s));
        const char *stop = semi ? semi : end;
        char letter = 0;
        int c = command(s, stop, &letter), fail;
        double area, v;
        if (letter == 'G' && (c == 0 || c == 1)) {
            fail = move_fails(&q, o, s, stop, &area);
            if (fail == 1)
                return amp_fail(err, AMP_ERR_LIMIT, line,
                                "gcode: the %s sequence's line %ld (%.*s) extrudes %.3g mm^2 of cross-section, more "
                                "than Klipper takes (%.3g mm^2: max_extrude_cross_section, 4 x nozzle^2): Klipper "
                                "would stop the job there; give a start/end sequence for Klipper or, if printer.cfg "
                                "allows more, say so with --max-cross-section",
                                what, line, (int)(stop - s > 60 ? 60 : stop - s), s, area, o->max_cross_section);
            if (fail == 2)
                return amp_fail(err, AMP_ERR_LIMIT, line,
                                "gcode: the %s sequence's line %ld (%.*s) moves the filament %.3g mm without moving "
                                "the head, more than Klipper's max_extrude_only_distance (%g mm by default): Klipper "
                                "would stop the job there",
                                what, line, (int)(stop - s > 60 ? 60 : stop - s), s, area, EXTRUDE_ONLY_MAX);
        } else if (letter == 'G' && c == 90) {
            q.rel = 0;
        } else if (letter == 'G' && c == 91) {
            q.rel = 1;
        } else if (letter == 'M' && (c == 82 || c == 83)) {
            q.rel_e = c == 83;
        } else if (letter == 'G' && c == 92) {
            int a;
            for (a = 0; a < 3; a++)
                if (word(s, stop, axes[a], &v)) {
                    q.pos[a] = v;
                    q.known[a] = 1;
                }
            if (word(s, stop, 'E', &v))
                q.e = v;
        } else if (letter == 'G' && c == 28) {
            q.known[0] = q.known[1] = q.known[2] = 0;
        }
        if (!nl)
            break;
        s = nl + 1;
        line++;
    }
    return AMP_OK;
}
