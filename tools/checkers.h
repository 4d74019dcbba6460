/*
 * checkers.h — the checkers behind `ampath check` (SPEC §4).
 *
 * tools/cmd_check.c parses the common options once and calls every checker
 * of the table in cmd_check.c. A checker lives in tools/check_NAME.c and
 * implements
 *     int check_NAME(const check_ctx *c, cli_json *j);
 * It decides itself whether it applies (e.g. the gouge check needs object
 * paths), prints one human line when j == NULL, or fills its own JSON section
 * (the dispatcher has already opened the object "NAME": {...}) with at least
 * "ran" (bool) and, when it ran, "ok" (bool). It returns CLI_OK (passed or
 * not applicable), CLI_FAILED (a violation) or CLI_USAGE (bad input, after
 * printing a one-line reason to stderr).
 * To add a checker: write check_NAME.c, declare it below (this header is not named check.h: tests compile with -Itools, and <check.h> is the Check framework), add one row to the
 * table in cmd_check.c (its --no-NAME flag comes with the row).
 */
#ifndef AMP_TOOLS_CHECKERS_H
#define AMP_TOOLS_CHECKERS_H

#include "cli.h"

typedef struct check_ctx {
    const char *paths_file;  /* the PATHS.amp argument */
    const amp_pathset *ps;   /* its paths, loaded */
    const char *trivariate;  /* --trivariate FILE or NULL */
    const char *mesh;        /* --mesh FILE or NULL */
    amp_head head;           /* --z-offs, --theta (validated; paper defaults) */
    double eps;              /* --eps E, mm (default 0.5) */
    int eps_given;           /* --eps appeared on the command line */
    int json;                /* --json */
} check_ctx;

/* No gouging (paper 5.1): no earlier point inside the head cone while a later point is printed. */
int check_gouge(const check_ctx *c, cli_json *j);

#endif
