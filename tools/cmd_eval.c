/* ampath eval SPLINE — points and derivatives of a .spl object at parameters read from stdin (docs/interfaces.md §4). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

const char cmd_eval_usage[] =
    "evaluate a spline (.spl) at parameter tuples read from stdin\n"
    "usage: ampath eval SPLINE.spl [--derivative D] [--object I] [--json]\n"
    "  stdin            one tuple per line: 'u' (curve), 'u v' (surface) or 'u v w' (trivariate);\n"
    "                   blank lines and '#' comments are skipped\n"
    "  stdout           one point 'x y z' per line, full double precision (%.17g)\n"
    "  --derivative D   default 0 (the point). An integer N: the N-th derivative along the first\n"
    "                   parameter u; or a word over u, v, w naming a partial derivative, e.g. 'v',\n"
    "                   'uv' (d2/du dv), 'ww'. At most 4 per direction.\n"
    "  --object I       which object of a multi-object file, counted from 0 (default 0)\n"
    "  --json           print {\"points\": [[x, y, z], ...], \"count\": N} instead (full precision; nothing\n"
    "                   on stdout when a line is refused)\n"
    "Parameters outside the spline's domain are rejected (exit 2, with the line number);\n"
    "the library itself clamps them (see docs/splines.md).\n";

/* Parse --derivative into per-direction orders. */
static int parse_deriv(const char *d, int dim, int k[3])
{
    char *end;
    long n;
    k[0] = k[1] = k[2] = 0;
    if (!d)
        return 1;
    errno = 0;
    n = strtol(d, &end, 10);
    if (end != d && *end == '\0') {
        if (n < 0 || n > AMP_SPLINE_MAX_DERIV)
            return 0;
        k[0] = (int)n;
        return 1;
    }
    for (; *d; d++) {
        int e = *d == 'u' ? 0 : *d == 'v' ? 1 : *d == 'w' ? 2 : -1;
        if (e < 0 || e >= dim || ++k[e] > AMP_SPLINE_MAX_DERIV)
            return 0;
    }
    return 1;
}

/* The parameters on one stdin line (a '#' comment cut off): how many, 0 for a blank line, -1 when one is not a
 * finite number or there are more than 3. */
static int parse_params(char *line, double par[3])
{
    char *p = line, *hash = strchr(line, '#'), *end;
    int got = 0;
    if (hash)
        *hash = '\0';
    for (;;) {
        double v;
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')
            p++;
        if (!*p)
            break;
        errno = 0;
        v = strtod(p, &end);
        if (end == p || !isfinite(v) || got == 3)
            return -1;
        par[got++] = v;
        p = end;
    }
    return got;
}

/* The first direction whose parameter lies outside the spline's domain, or s->dim when none does. */
static int outside_domain(const amp_spline *s, const double *par, double *lo, double *hi)
{
    int d;
    for (d = 0; d < s->dim; d++) {
        amp_spline_domain(s, d, lo, hi);
        if (par[d] < lo[0] || par[d] > hi[0])
            break;
    }
    return d;
}

/* Every stdin line evaluated and printed (as JSON into @p j when it is not NULL); the first bad line stops the
 * run with its message (CLI_USAGE), the points before it printed. */
static int eval_lines(const amp_spline *s, const int k[3], cli_json *j, int *count)
{
    char line[4096];
    long lineno = 0;
    amp_error err;
    amp_error_clear(&err);
    while (fgets(line, sizeof line, stdin)) {
        double par[3], lo, hi;
        amp_vec3 out;
        int got, d;
        lineno++;
        if (!strchr(line, '\n') && !feof(stdin))
            return cli_fail("eval", CLI_USAGE, "stdin line %ld: too long", lineno);
        got = parse_params(line, par);
        if (got == 0)
            continue;
        if (got != s->dim)
            return cli_fail("eval", CLI_USAGE, "stdin line %ld: expected %d finite parameter(s)", lineno, s->dim);
        if ((d = outside_domain(s, par, &lo, &hi)) < s->dim)
            return cli_fail("eval", CLI_USAGE,
                            "stdin line %ld: parameter %d = %.17g outside the domain [%.17g, %.17g]", lineno, d + 1,
                            par[d], lo, hi);
        if (amp_spline_eval_partial(s, par, k, &out, &err) != AMP_OK)
            return cli_fail("eval", CLI_USAGE, "stdin line %ld: %s", lineno, err.msg);
        (*count)++;
        if (j) { /* full precision, as the text output */
            char pt[96];
            snprintf(pt, sizeof pt, "[%.17g,%.17g,%.17g]", out.x, out.y, out.z);
            cli_json_members(j, pt);
        } else
            printf("%.17g %.17g %.17g\n", out.x, out.y, out.z);
    }
    return CLI_OK;
}

int cmd_eval(int argc, char **argv)
{
    const char *pos[1], *deriv = NULL;
    long object = 0;
    int json = 0, npos = 0, rc, k[3], count = 0;
    amp_spline *list = NULL, *s;
    size_t n = 0;
    amp_error err;
    cli_json j;
    FILE *body = NULL;
    cli_opt opts[] = {{"derivative", CLI_STR, &deriv, 0},
                      {"object", CLI_LONG, &object, 0},
                      {"json", CLI_FLAG, &json, 0},
                      {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("eval", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    amp_error_clear(&err);
    if (amp_spline_read_file(pos[0], NULL, &list, &n, &err) != AMP_OK)
        return cli_fail("eval", CLI_USAGE, "%s: %s", pos[0], err.msg);
    if (object < 0 || (size_t)object >= n) {
        amp_spline_list_free(NULL, list, n);
        return cli_fail("eval", CLI_USAGE, "--object %ld: the file holds %lu object(s)", object, (unsigned long)n);
    }
    s = &list[object];
    if (!parse_deriv(deriv, s->dim, k)) {
        int dim = s->dim;
        amp_spline_list_free(NULL, list, n);
        return cli_fail("eval", CLI_USAGE, "--derivative '%s': expected 0..%d or a word over the %d direction(s)",
                        deriv, AMP_SPLINE_MAX_DERIV, dim);
    }
    if (json) {
        /* the object goes out whole or not at all: a bad line after good ones must not leave a well-formed
         * object of the points before it on stdout (a caller reading stdout alone would take it for the run) */
        if (!(body = tmpfile())) {
            amp_spline_list_free(NULL, list, n);
            return cli_fail("eval", CLI_USAGE, "cannot create a temporary file for --json: %s", strerror(errno));
        }
        cli_json_begin(&j, body);
        cli_json_arr(&j, "points");
    }
    rc = eval_lines(s, k, json ? &j : NULL, &count);
    if (json) {
        int c;
        cli_json_close(&j);
        cli_json_int(&j, "count", count);
        cli_json_end(&j);
        rewind(body);
        while (rc == CLI_OK && (c = getc(body)) != EOF)
            putchar(c);
        fclose(body);
    }
    amp_spline_list_free(NULL, list, n);
    return rc;
}
