/*
 * printer_internal.h — shared by the printer profile modules (not installed):
 * printer_ini.c stores the `.ini` values, printer_vars.c resolves variables,
 * printer_regex.c matches `=~`, printer_macro.c evaluates PrusaSlicer's
 * macro language (docs/gcode.md, "Printer profiles").
 *
 * An evaluation owns no memory: the caller's output buffer holds the
 * expanded text at its front and the temporary strings of the expressions
 * (concatenations, unescaped strings, digits()) at its back, so a template
 * needs no buffer but the one it is expanded into, and both share its limit.
 */
#ifndef AMP_PRINTER_INTERNAL_H
#define AMP_PRINTER_INTERNAL_H

#include <stddef.h>

#include "ampath/printer.h"

/* Limits that bound the evaluator's recursion and its stack (the library runs on small targets). */
#define AMP_PR_IF_MAX 16     /* nested {if} blocks */
#define AMP_PR_DEPTH_MAX 64  /* nested expression calls (about 4 per level of parentheses) */
#define AMP_PR_INT_MAX 2147483647LL /* integers are 32-bit as in PrusaSlicer; beyond, arithmetic goes decimal */

/* Value types: MV_NONE is what an expression in a skipped {if} branch gives (parsed, not evaluated). */
enum { MV_NONE, MV_NIL, MV_BOOL, MV_INT, MV_NUM, MV_STR };

typedef struct amp_pr_val {
    int t;
    long long i;   /* MV_BOOL (0 or 1) and MV_INT */
    double d;      /* MV_NUM */
    const char *s; /* MV_STR: n bytes, not NUL-terminated (the template, the profile or the arena) */
    size_t n;
} amp_pr_val;

/* State of one expansion. */
typedef struct amp_pr_ctx {
    const amp_printer *p;
    const amp_printer_job *job;
    const char *src, *s;   /* template and cursor */
    char *out;             /* output: text in [0, o), temporary strings in [lo, cap) */
    size_t cap, o, lo;
    int depth;             /* expression recursion */
    int skip;              /* inside a branch not taken: parse, do not evaluate */
    int used_job;          /* a variable of the placed job was read (amp_printer_gcode_job) */
    amp_status st;         /* first error: status, position, message */
    const char *at;
    char msg[AMP_ERROR_MSG_SIZE];
} amp_pr_ctx;

/* Record the first error at @p at (a position in the template; NULL = the cursor) and return @p st. */
amp_status amp_pr_fail(amp_pr_ctx *c, amp_status st, const char *at, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
/* @p n bytes from the back of the output buffer; NULL (AMP_ERR_LIMIT recorded) when it is full. */
char *amp_pr_alloc(amp_pr_ctx *c, size_t n);

/* printer_vars.c */
/* Keep `key = value` of the `.ini` for the macros (a later key replaces an earlier one). */
void amp_pr_vars_set(amp_printer *p, const char *key, size_t kn, const char *val, size_t vn);
/*
 * Variable @p name (@p n bytes) at @p index (-1: none given = the first value; the `.ini` does not
 * say which keys are lists, so any value is a list of one) into *v (MV_NIL for an undefined value);
 * *count (optional) = the number of values. Errors name the variable: unknown, refused (date and
 * time), dropped (did not fit in p->vars), index out of range.
 */
amp_status amp_pr_var(amp_pr_ctx *c, const char *name, size_t n, long index, const char *at, amp_pr_val *v,
                      size_t *count);
/* Would amp_pr_var() know @p name (whatever its value)? */
int amp_pr_var_known(const amp_printer *p, const char *name, size_t n);
/* A decimal number in strict syntax ([+-]digits[.digits][e[+-]digits], nothing else): 1 with *v set. */
int amp_pr_number(const char *s, size_t n, amp_pr_val *v);

/* printer_regex.c */
/* Does all of @p s match the regular expression @p pat (ECMAScript subset, docs/gcode.md)? *match = 0/1. */
amp_status amp_pr_regex(amp_pr_ctx *c, const char *pat, size_t pn, const char *s, size_t sn, const char *at,
                        int *match);

/* printer_macro.c */
/* Text of a value as PrusaSlicer prints it into @p buf (at least 32 bytes for numbers); returns its length
 * and sets *s to the text (buf, or the string itself). */
size_t amp_pr_text(const amp_pr_val *v, char *buf, const char **s);
/* Expand @p tmpl (see amp_printer_expand_job); *used_job (optional) = a job variable was read. */
amp_status amp_pr_expand(const amp_printer *p, const amp_printer_job *job, const char *tmpl, char *out, size_t cap,
                         int *used_job, amp_error *err);

#endif
