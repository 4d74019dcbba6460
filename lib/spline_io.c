/* The .spl text format (docs/interfaces.md §4): reader with line-numbered errors, full-precision writer. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/spline.h"
#include "lex.h"

static const char *const kind_names[] = {"curve", "surface", "trivariate"};

/* Next content line, tokenised unless it is a knots line (those may be arbitrarily long). */
static int next(amp_lex *lx, const char **line, size_t *len, int *is_knots, amp_error *err)
{
    const char *p;
    size_t i = 0;
    int r = amp_lex_next_line(lx, line, len, err);
    if (r <= 0)
        return r;
    p = *line;
    while (i < *len && (p[i] == ' ' || p[i] == '\t'))
        i++;
    *is_knots = *len - i >= 5 && memcmp(p + i, "knots", 5) == 0 && (*len - i == 5 || p[i + 5] == ' ' ||
                                                                     p[i + 5] == '\t' || p[i + 5] == '\r');
    if (*is_knots) {
        lx->ntok = 0;
        return 1;
    }
    if (*len > AMP_LEX_MAX_LINE)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: longer than %d bytes", lx->line, AMP_LEX_MAX_LINE);
    return amp_lex_split(lx, *line, *len, err);
}

/* Parse "knots v1 v2 ..." into U[0..want-1], checking count and monotonicity. */
static amp_status parse_knots(const amp_lex *lx, const char *line, size_t len, double *U, size_t want, int order,
                              int d, amp_error *err)
{
    size_t i = 0, got = 0, run = 1;
    int first = 1;
    while (i < len) {
        char buf[64], *end;
        size_t t;
        double v;
        while (i < len && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r'))
            i++;
        if (i >= len)
            break;
        t = i;
        while (i < len && !(line[i] == ' ' || line[i] == '\t' || line[i] == '\r'))
            i++;
        if (first) { /* the keyword */
            first = 0;
            continue;
        }
        if (i - t >= sizeof buf)
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: knot %lu is not a number", lx->line,
                            (unsigned long)got + 1);
        memcpy(buf, line + t, i - t);
        buf[i - t] = '\0';
        errno = 0;
        v = strtod(buf, &end);
        if (end == buf || *end != '\0' || !isfinite(v))
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: knot %lu '%s' is not a finite number",
                            lx->line, (unsigned long)got + 1, buf);
        if (got >= want)
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: more than the %lu knots of direction %d",
                            lx->line, (unsigned long)want, d + 1);
        if (got > 0 && v < U[got - 1])
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: knots decrease at knot %lu (%.17g < %.17g)",
                            lx->line, (unsigned long)got + 1, v, U[got - 1]);
        run = (got > 0 && v == U[got - 1]) ? run + 1 : 1;
        if (run > (size_t)order)
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: knot %.17g repeats more than the order %d",
                            lx->line, v, order);
        U[got++] = v;
    }
    if (got != want)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: expected %lu knots (count + order), found %lu",
                        lx->line, (unsigned long)want, (unsigned long)got);
    if (!(U[order - 1] < U[want - (size_t)order]))
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: empty parameter domain [%.17g, %.17g]", lx->line,
                        U[order - 1], U[want - (size_t)order]);
    return AMP_OK;
}

/* Read "key v1 .. vdim" as integers in [lo, hi]. */
static amp_status header_ints(const amp_lex *lx, const char *key, int dim, long lo, long hi, amp_status over,
                              long *v, amp_error *err)
{
    int i;
    if (!amp_lex_is(lx, 0, key) || lx->ntok != dim + 1)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: expected '%s' with %d value%s", lx->line, key, dim,
                        dim > 1 ? "s" : "");
    for (i = 0; i < dim; i++) {
        amp_status st = amp_lex_long(lx, i + 1, LONG_MIN, LONG_MAX, &v[i], err);
        if (st != AMP_OK)
            return st;
        if (v[i] < lo || v[i] > hi)
            return amp_fail(err, v[i] > hi ? over : AMP_ERR_PARSE, lx->line, "line %ld: %s %ld outside [%ld, %ld]", lx->line, key, v[i], lo, hi);
    }
    return AMP_OK;
}

/* One object; the current line is its "kind" line. */
static amp_status parse_object(amp_lex *lx, size_t textlen, const amp_allocator *a, amp_spline *s, amp_error *err)
{
    const char *line;
    size_t len, i, ncp = 1;
    int dim = 0, d, r, isk;
    long rational, order[3], count[3];
    int ord[3];
    size_t cnt[3];
    amp_status st;

    for (d = 0; d < 3; d++)
        if (lx->ntok == 2 && amp_lex_is(lx, 1, kind_names[d]))
            dim = d + 1;
    if (!amp_lex_is(lx, 0, "kind") || dim == 0)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: expected 'kind curve|surface|trivariate'",
                        lx->line);
#define NEXT_LINE(what)                                                                                              \
    do {                                                                                                             \
        r = next(lx, &line, &len, &isk, err);                                                                        \
        if (r < 0)                                                                                                   \
            return (amp_status)r;                                                                                    \
        if (r == 0)                                                                                                  \
            return amp_fail(err, AMP_ERR_PARSE, lx->line + 1, "line %ld: end of input, expected %s", lx->line + 1,  \
                            what);                                                                                   \
    } while (0)
    NEXT_LINE("'rational 0|1'");
    st = header_ints(lx, "rational", 1, 0, 1, AMP_ERR_PARSE, &rational, err);
    if (st != AMP_OK)
        return st;
    NEXT_LINE("'order'");
    st = header_ints(lx, "order", dim, 1, AMP_SPLINE_MAX_ORDER, AMP_ERR_LIMIT, order, err);
    if (st != AMP_OK)
        return st;
    NEXT_LINE("'count'");
    st = header_ints(lx, "count", dim, 1, AMP_SPLINE_MAX_COUNT, AMP_ERR_LIMIT, count, err);
    if (st != AMP_OK)
        return st;
    for (d = 0; d < dim; d++) {
        if (count[d] < order[d])
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: count %ld is below the order %ld", lx->line,
                            count[d], order[d]);
        ord[d] = (int)order[d];
        cnt[d] = (size_t)count[d];
        /* every control point needs a line of at least 6 bytes: refuse counts the text cannot hold */
        if (cnt[d] > textlen / 6 / ncp + 1)
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: the input is too short for that many control "
                            "points", lx->line);
        ncp *= cnt[d];
    }
    st = amp_spline_create(s, a, dim, ord, cnt, (int)rational, err);
    if (st != AMP_OK) {
        if (err)
            err->line = lx->line;
        return st;
    }
    for (d = 0; d < dim; d++) {
        r = next(lx, &line, &len, &isk, err);
        if (r < 0)
            return (amp_status)r;
        if (r == 0 || !isk)
            return amp_fail(err, AMP_ERR_PARSE, lx->line + (r == 0), "line %ld: expected 'knots' for direction %d",
                            lx->line + (r == 0), d + 1);
        st = parse_knots(lx, line, len, s->knots[d], cnt[d] + (size_t)ord[d], ord[d], d, err);
        if (st != AMP_OK)
            return st;
    }
    for (i = 0; i < ncp; i++) {
        double x[4] = {0, 0, 0, 1};
        int f, want = rational ? 4 : 3;
        NEXT_LINE("a control point");
        if (lx->ntok != want && !(lx->ntok == 4 && !rational))
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: control point %lu: expected %s, found %d fields",
                            lx->line, (unsigned long)i + 1, rational ? "'x y z w'" : "'x y z'", lx->ntok);
        for (f = 0; f < lx->ntok; f++) {
            st = amp_lex_double(lx, f, &x[f], err);
            if (st != AMP_OK)
                return st;
        }
        if (rational && !(x[3] > 0.0))
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: weight %g is not positive", lx->line, x[3]);
        if (!rational && x[3] != 1.0)
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: weight %g in a non-rational spline (use "
                            "'rational 1')", lx->line, x[3]);
        amp_spline_cp_set(s, i, amp_v3(x[0], x[1], x[2]), x[3]);
    }
#undef NEXT_LINE
    return AMP_OK;
}

void amp_spline_list_free(const amp_allocator *a, amp_spline *list, size_t n)
{
    size_t i;
    for (i = 0; list && i < n; i++)
        amp_spline_free(&list[i]);
    amp_free(a, list);
}

amp_status amp_spline_parse(const char *text, size_t len, const amp_allocator *a, amp_spline **list, size_t *n,
                            amp_error *err)
{
    amp_lex lx;
    const char *line;
    size_t ll, cap = 0, cnt = 0;
    amp_spline *arr = NULL;
    int r, isk;
    amp_status st = AMP_OK;

    if (!list || !n)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_spline_parse: NULL output");
    *list = NULL;
    *n = 0;
    if (!text && len)
        return amp_fail(err, AMP_ERR_ARG, 0, "NULL text");
    amp_lex_init(&lx, text, len, 1);
    r = next(&lx, &line, &ll, &isk, err);
    if (r < 0)
        return (amp_status)r;
    if (r == 0)
        return amp_fail(err, AMP_ERR_PARSE, 1, "line 1: empty input, expected 'ampath-spline 1'");
    if (!amp_lex_is(&lx, 0, "ampath-spline") || lx.ntok != 2)
        return amp_fail(err, AMP_ERR_PARSE, lx.line, "line %ld: expected header 'ampath-spline 1'", lx.line);
    if (!amp_lex_is(&lx, 1, "1"))
        return amp_fail(err, AMP_ERR_PARSE, lx.line, "line %ld: unsupported ampath-spline version", lx.line);
    for (;;) {
        r = next(&lx, &line, &ll, &isk, err);
        if (r < 0) {
            st = (amp_status)r;
            break;
        }
        if (r == 0)
            break;
        /* a repeated header between objects is accepted */
        if (amp_lex_is(&lx, 0, "ampath-spline") && lx.ntok == 2 && amp_lex_is(&lx, 1, "1"))
            continue;
        st = amp_grow(a, (void **)&arr, &cap, cnt + 1, sizeof *arr);
        if (st != AMP_OK) {
            st = amp_fail(err, AMP_ERR_NOMEM, lx.line, "out of memory");
            break;
        }
        amp_spline_init(&arr[cnt]);
        st = parse_object(&lx, len, a, &arr[cnt], err);
        cnt++;
        if (st != AMP_OK)
            break;
    }
    if (st == AMP_OK && cnt == 0)
        st = amp_fail(err, AMP_ERR_PARSE, lx.line, "line %ld: no spline object in the input", lx.line);
    if (st != AMP_OK) {
        amp_spline_list_free(a, arr, cnt);
        return st;
    }
    *list = arr;
    *n = cnt;
    return AMP_OK;
}

amp_status amp_spline_read_file(const char *path, const amp_allocator *a, amp_spline **list, size_t *n,
                                amp_error *err)
{
    char *data;
    size_t len;
    amp_status st;
    *list = NULL;
    *n = 0;
    st = amp_read_file(path, a, 0, &data, &len, err);
    if (st != AMP_OK)
        return st;
    st = amp_spline_parse(data, len, a, list, n, err);
    amp_free(a, data);
    return st;
}

amp_status amp_spline_write(const amp_spline *s, int header, amp_sink_fn sink, void *user, amp_error *err)
{
    amp_status st = AMP_OK;
    size_t i;
    int d;
    if (!s || !sink)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_spline_write: NULL argument");
#define W(...)                                                                                                       \
    do {                                                                                                             \
        st = amp_sinkf(sink, user, __VA_ARGS__);                                                                     \
        if (st != AMP_OK)                                                                                            \
            return amp_fail(err, st, 0, "writing the spline failed");                                                \
    } while (0)
    if (!s || s->dim < 1 || s->dim > 3)
        return amp_fail(err, AMP_ERR_ARG, 0, "not a spline");
    if (header)
        W("ampath-spline 1\n");
    W("kind %s\nrational %d\norder", kind_names[s->dim - 1], s->rational);
    for (d = 0; d < s->dim; d++)
        W(" %d", s->order[d]);
    W("\ncount");
    for (d = 0; d < s->dim; d++)
        W(" %lu", (unsigned long)s->count[d]);
    W("\n");
    for (d = 0; d < s->dim; d++) {
        W("knots");
        for (i = 0; i < s->count[d] + (size_t)s->order[d]; i++)
            W(" %.17g", s->knots[d][i]);
        W("\n");
    }
    for (i = 0; i < s->ncp; i++) {
        double w;
        amp_vec3 p = amp_spline_cp_get(s, i, &w);
        if (s->rational)
            W("%.17g %.17g %.17g %.17g\n", p.x, p.y, p.z, w);
        else
            W("%.17g %.17g %.17g\n", p.x, p.y, p.z);
    }
#undef W
    return st;
}
