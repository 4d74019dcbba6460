/* check_stroke.h — `ampath check` for strokes from `ampath slice --continuous`. */
#ifndef AMP_TOOLS_CHECK_STROKE_H
#define AMP_TOOLS_CHECK_STROKE_H

/** Usage lines of the stroke check (for the help text of `ampath check`). */
extern const char check_stroke_usage[];

/**
 * Check every path of a .amp file with amp_stroke_check(): no crossing, no
 * edge printed twice, and with --mesh (+ --layer) inside the layer polygon
 * whose printing (or cutting) height matches the path's z. argv[0] is
 * "check". Returns CLI_OK, CLI_FAILED (a violation) or CLI_USAGE.
 */
int check_stroke(int argc, char **argv);

#endif
