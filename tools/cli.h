/*
 * cli.h — shared plumbing of the `ampath` commands (docs/interfaces.md §4): option parsing,
 * one-object JSON output, progress bars, error exits, common loaders.
 *
 * A command is a file tools/cmd_NAME.c defining
 *     const char cmd_NAME_usage[];   (first line: one-line summary)
 *     int cmd_NAME(int argc, char **argv);   (argv[0] is "NAME")
 * and the Makefile registers it (tools/commands.inc). A benchmark is a file
 * tools/bench_NAME.c defining `int bench_NAME(cli_json *j, int quick);`
 * (registered in tools/benches.inc) that prints human lines when j == NULL.
 * Exit codes: CLI_OK 0, CLI_FAILED 1 (a check failed), CLI_USAGE 2 (bad usage or input).
 */
#ifndef AMP_TOOLS_CLI_H
#define AMP_TOOLS_CLI_H

#include <stdio.h>

#include "ampath/ampath.h"

enum { CLI_OK = 0, CLI_FAILED = 1, CLI_USAGE = 2 };

typedef enum cli_kind { CLI_FLAG, CLI_STR, CLI_DOUBLE, CLI_LONG, CLI_LIST } cli_kind;

/** A repeatable option (kind CLI_LIST): every value in order; one more than CLI_LIST_MAX is refused. */
#define CLI_LIST_MAX 16
typedef struct cli_list {
    long v[CLI_LIST_MAX]; /* whole numbers, validated and range-checked as CLI_LONG */
    int n;
} cli_list;

/** One option: "--name" (kind FLAG sets *(int *)dst = 1; others take the next argument or --name=value;
 *  LIST appends to a cli_list). */
typedef struct cli_opt {
    const char *name; /* without the leading "--" */
    cli_kind kind;
    void *dst;  /* int *, const char **, double *, long * or cli_list * */
    int seen;   /* set by cli_parse */
} cli_opt;

/**
 * Parse argv[1..argc-1] of command @p cmd: options anywhere, the rest are
 * positionals stored in pos[0..*npos-1]. "--" ends options. Prints a one-line
 * reason and returns CLI_USAGE on unknown options, missing or malformed values,
 * numeric values outside the option's range (one table in cli.c, by option name),
 * or a positional count outside [min_pos, max_pos]; otherwise CLI_OK.
 * Also accepts the work limits (cli_work) of the commands that estimate.
 * The option table ends with an entry whose name is NULL.
 */
int cli_parse(const char *cmd, int argc, char **argv, cli_opt *opts, const char **pos, int min_pos, int max_pos,
              int *npos);

/** Was option @p name (without "--") on the command line of the last cli_parse() over @p opts? */
int cli_given(const cli_opt *opts, const char *name);

/*
 * Work limits: commands whose work grows without bound with a small
 * tolerance or a large input estimate it first and refuse (exit 2, the estimate
 * in the message) above these limits, which --max-curves N, --max-length L (cover) and
 * --max-segments N (slice, euler, check) raise for one run. Documented in the
 * README section "Limits" and ampath(1).
 */
#define CLI_DEFAULT_MAX_CURVES AMP_COVER_MAX_CURVES /* covering curves of cover (amp_cover_estimate) */
#define CLI_DEFAULT_MAX_LENGTH AMP_COVER_MAX_LENGTH /* their total length, mm (the same estimate) */
#define CLI_DEFAULT_MAX_SEGMENTS 2e7 /* section segments over all layers: slice, euler, check --mesh */
typedef struct cli_limits {
    double max_curves;
    double max_length;
    double max_segments;
} cli_limits;
extern cli_limits cli_work; /* set by cli_parse from --max-curves / --max-length / --max-segments */

/** "ampath CMD: refused: about E WHAT estimated, more than the limit of L (raise it with --OPTION N)"; CLI_USAGE. */
int cli_work_refuse(const char *cmd, const char *what, double estimate, double limit, const char *option);

/** Print "ampath CMD: message" to stderr and return @p code. */
int cli_fail(const char *cmd, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/** Report an amp_error from the library: "ampath CMD: <msg or strerror>", returns CLI_USAGE. */
int cli_fail_err(const char *cmd, const amp_error *err);

/* ---- JSON: exactly one object on stdout ---- */
#define CLI_JSON_DEPTH 16
typedef struct cli_json {
    FILE *f;
    int depth;
    int count[CLI_JSON_DEPTH];
    char close[CLI_JSON_DEPTH];
} cli_json;

void cli_json_begin(cli_json *j, FILE *f);
void cli_json_num(cli_json *j, const char *key, double v); /* non-finite -> null */
void cli_json_int(cli_json *j, const char *key, long long v);
void cli_json_str(cli_json *j, const char *key, const char *s);
void cli_json_bool(cli_json *j, const char *key, int v);
void cli_json_obj(cli_json *j, const char *key); /* open a nested object (key NULL inside arrays) */
void cli_json_arr(cli_json *j, const char *key); /* open a nested array */
void cli_json_close(cli_json *j);                /* close the innermost object or array */
void cli_json_vec3(cli_json *j, const char *key, amp_vec3 v); /* "key": [x, y, z] */
void cli_json_box(cli_json *j, const char *key, amp_box3 b);  /* "key": [xmin, ymin, zmin, xmax, ymax, zmax] */
void cli_json_csv(cli_json *j, const char *key, const char *csv); /* "key": ["a", "b"] from "a,b" */
/* members of an object written elsewhere ("k":v,...), without braces, into the open object */
void cli_json_members(cli_json *j, const char *members);
void cli_json_end(cli_json *j);                  /* close everything and print a newline */

/* ---- progress: a bar on stderr only when stderr is a terminal ---- */
typedef struct cli_progress {
    const char *label;
    int enabled;
    int last_permille;
} cli_progress;

void cli_progress_begin(cli_progress *p, const char *label);
void cli_progress_update(cli_progress *p, double fraction);
void cli_progress_end(cli_progress *p);
/** The library's progress callback (amp_progress_fn) drawing the bar of @p user, a cli_progress. */
void cli_progress_fn(void *user, double fraction);

/** Load the first trivariate of a .spl file, or a built-in model by name; prints its own error. */
int cli_load_trivariate(const char *cmd, const char *what, amp_spline *out);
/** 1 when @p s ends with @p suffix. */
int cli_ends_with(const char *s, const char *suffix);
/** The rate guard of the benchmarks: @p seconds, or 1e-9 when it is not positive, as the divisor of a rate or
 *  ratio measured in one run (a step too fast for the clock gives a large finite figure, not inf or NaN). */
double cli_positive(double seconds);

/** Monotonic wall clock in seconds. */
double cli_now(void);

/* ---- loaders that print their own errors (return CLI_OK or CLI_USAGE) ---- */
/* cli_load_paths: on failure @p ps is freed (empty again), so callers may just return. */
int cli_load_paths(const char *cmd, const char *file, amp_pathset *ps);
int cli_save_paths(const char *cmd, const char *file, const amp_pathset *ps, const char *comment);
/*
 * As cli_save_paths() for a command that transforms the paths of @p from:
 * the "# ampath ..." header comments of @p from follow @p comment, so the
 * history (e.g. the eps that `ampath cover` guaranteed, which `ampath check`
 * uses) survives order, mdr and support.
 */
int cli_save_derived(const char *cmd, const char *file, const amp_pathset *ps, const char *comment, const char *from);

/** Strict number: the whole of @p s is a finite number (strtod syntax); 0 and *out set, or -1. */
int cli_number(const char *s, double *out);
/** Strict integer: the whole of @p s is a decimal integer within long; 0 and *out set, or -1. */
int cli_integer(const char *s, long *out);

#ifndef CLI_NO_COMMANDS /* programs other than ampath (ampath-vprinter) use the parser without the command lists */
/* Prototypes of every registered command and benchmark: the lists build/gen/commands.inc and
 * build/gen/benches.inc are generated by the Makefile from the names of tools/cmd_*.c and tools/bench_*.c. */
#define AMP_CMD(name)                                                                                                \
    extern const char cmd_##name##_usage[];                                                                          \
    int cmd_##name(int argc, char **argv);
#include "commands.inc"
#undef AMP_CMD
#define AMP_BENCH(name) int bench_##name(cli_json *j, int quick);
#include "benches.inc"
#undef AMP_BENCH
#endif

/** Path of the program @p name: $@p env when set (tests), else beside this program (an install), else
 *  ../@p dir/@p name beside it (the build tree, where tools/ and bridge/ are siblings). 0, or -1 when it
 *  does not fit @p cap. */
int cli_program(const char *env, const char *name, const char *dir, char *out, size_t cap);

#endif
