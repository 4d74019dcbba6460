/*
 * checkers.h — the independent checkers behind `ampath check` (tools/check_*.c).
 * Each returns a CLI exit code: CLI_OK (0) pass, CLI_FAILED (1) a violation,
 * CLI_USAGE (2) bad input; with @p j non-NULL it adds its figures to that JSON
 * object instead of printing a human summary.
 */
#ifndef AMP_TOOLS_CHECKERS_H
#define AMP_TOOLS_CHECKERS_H

#include "cli.h"

/**
 * Coverage of a trivariate by the paths of @p paths_file (issue 4): samples the
 * volume (uniform in parameters and uniform in space), measures the largest
 * distance to the nearest path (amp_cover_measure_gap) and fails when it
 * exceeds @p eps. eps <= 0: taken from the "ampath cover ... eps E" comment of
 * the path file, else the largest vertex radius. @p spl_file is a .spl file or
 * a built-in model name.
 */
int check_trivariate(const char *paths_file, const char *spl_file, double eps, long samples, unsigned long seed,
                     cli_json *j);

/**
 * Coverage of the solid of the mesh @p mesh_file (STL) by the paths of
 * @p paths_file (issue 5): the largest distance from @p samples points drawn
 * inside the mesh to the nearest path must be <= @p eps (eps <= 0: the
 * largest vertex radius), and no path vertex may lie more than 0.01 mm
 * outside the mesh. tools/check_mesh.c.
 */
int check_mesh(const char *paths_file, const char *mesh_file, double eps, long samples, unsigned long seed,
               cli_json *j);

/** Load the first trivariate of a .spl file, or a built-in model by name; prints its own error. */
int cli_load_trivariate(const char *cmd, const char *what, amp_spline *out);

#endif
