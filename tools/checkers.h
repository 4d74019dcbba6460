/*
 * checkers.h — the independent checkers behind `ampath check` (docs/interfaces.md §4).
 *
 * tools/cmd_check.c parses the common options once, loads the paths, and
 * calls every checker of its table. A checker lives in tools/check_NAME.c and
 * implements
 *     int check_NAME(const check_ctx *c, cli_json *j);
 * It decides itself whether it applies (the gouge check needs object paths,
 * the coverage check a model), prints one human line to c->out when j == NULL, or fills
 * its own JSON section (the dispatcher has already opened "NAME": {...}) with
 * at least "ran" (bool) and, when it ran, "ok" (bool). It returns CLI_OK
 * (passed or not applicable), CLI_FAILED (a violation) or CLI_USAGE (bad
 * input, after printing a one-line reason to stderr).
 * To add a checker: write check_NAME.c, declare it below, add one row to the
 * table in cmd_check.c (its --no-NAME flag comes with the row).
 * (This header is not named check.h: tests compile with -Itools, and
 * <check.h> is the Check framework.)
 */
#ifndef AMP_TOOLS_CHECKERS_H
#define AMP_TOOLS_CHECKERS_H

#include "cli.h"

typedef struct check_ctx {
    const char *paths_file;  /* the PATHS.amp argument */
    const amp_pathset *ps;   /* its paths, loaded */
    const char *trivariate;  /* --trivariate F (.spl or built-in name) or NULL */
    const char *mesh;        /* --mesh F (.stl) or NULL */
    amp_head head;           /* --z-offs, --theta (validated; paper defaults) */
    double eps;              /* --eps E, mm, when eps_given */
    int eps_given;           /* --eps appeared on the command line */
    long samples;            /* --samples N for the sampled checks */
    unsigned long seed;      /* --seed S */
    double layer;            /* --layer H, mm, when layer_given: the mesh was sliced at H */
    int layer_given;
    double first_layer;      /* --first-layer H0 (0: same as H) */
    double tol;              /* --tol T: distance tolerance of the stroke check */
    int support;             /* --support: require held paths even when the file has no support paths */
    double overhang;         /* --overhang DEG, radians (default 45 degrees) */
    double max_gap;          /* --max-gap G, mm (default 1) */
    double bridge;           /* --bridge B, mm (default 5) */
    FILE *out;               /* where a checker prints its human line (stdout, or the dispatcher's buffer) */
} check_ctx;

/* No gouging (paper 1, §5.1): no earlier point inside the head cone while a later point prints. */
int check_gouge(const check_ctx *c, cli_json *j);

/*
 * Coverage within eps, measured by sampling (paper 1, §4): with --trivariate
 * the volume of the trivariate (tools/check_trivariate.c); with --mesh and no
 * --layer the solid of the mesh, plus no path vertex more than 0.01 mm outside
 * it (tools/check_mesh.c). Without --eps, eps is the one recorded in the
 * path file by `ampath cover` (its eps) or `ampath field` (its covering
 * radius), else the largest vertex radius.
 */
int check_coverage(const check_ctx *c, cli_json *j);
/* That recorded eps of path file @p file, or 0 (tools/check_trivariate.c). */
double check_eps_from_comment(const char *file);
int check_trivariate(const check_ctx *c, cli_json *j);
int check_mesh(const check_ctx *c, cli_json *j);

/*
 * Strokes (paper 2, §4): every planar path (all vertices at one height) has no
 * two crossing segments and no edge printed twice; with --mesh and --layer it
 * also lies inside the layer polygon of its height (tools/check_stroke.c).
 */
int check_stroke(const check_ctx *c, cli_json *j);

/*
 * Support ([P1 §5.3]): every extruded point of an object path is printed
 * over material printed earlier or the bed, within the overhang rule, bridges
 * allowed (lib amp_check_hold, tools/check_support.c). Runs when the file has
 * support paths, or on request (--support).
 */
int check_support(const check_ctx *c, cli_json *j);


#endif
