/* ampath check — minimal dispatcher written on the slice branch: it only
 * knows the stroke check (tools/check_stroke.c). The full dispatcher over
 * tools/check_*.c is owned by another engineer; merge keeps theirs and adds
 * check_stroke to it. */
#include "check_stroke.h"
#include "cli.h"

const char cmd_check_usage[] =
    "independent verification of a path file: strokes without crossings, each edge printed once\n"
    "usage: ampath check PATHS.amp [--mesh MESH.stl --layer H [--first-layer H0]] [--tol T] [--json]\n"
    "Exit status 1 when a check fails.\n";

int cmd_check(int argc, char **argv) { return check_stroke(argc, argv); }
