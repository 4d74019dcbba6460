/* Line lexer for the text formats: bounded, copy-free, line-numbered. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lex.h"
#include "numtext.h"

void amp_lex_init(amp_lex *lx, const char *buf, size_t len, int strip_comments)
{
    memset(lx, 0, sizeof *lx);
    lx->buf = buf;
    lx->len = len;
    lx->strip_comments = strip_comments;
}

int amp_lex_is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

int amp_lex_next_line(amp_lex *lx, const char **line, size_t *len, amp_error *err)
{
    while (lx->pos < lx->len) {
        size_t start = lx->pos, end, i, raw;
        const char *nl = memchr(lx->buf + start, '\n', lx->len - start);
        end = nl ? (size_t)(nl - lx->buf) : lx->len;
        lx->pos = nl ? end + 1 : lx->len;
        lx->line++;
        if (memchr(lx->buf + start, '\0', end - start))
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: NUL byte in text", lx->line);
        raw = end - start - (end > start && lx->buf[end - 1] == '\r'); /* CRLF: the CR is the newline's */
        if (lx->strip_comments) {
            const char *h = memchr(lx->buf + start, '#', end - start);
            if (h)
                end = (size_t)(h - lx->buf);
        }
        for (i = start; i < end && amp_lex_is_space(lx->buf[i]); i++)
            ;
        /* The documented 4,096-byte line limit holds for every physical line: a long
         * comment or blank line is refused here, a long content line by amp_lex_next (only
         * a .spl knots line, without comment, may be longer; see lex.h). */
        if (raw > AMP_LEX_MAX_LINE && (i == end || end - start != raw))
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: longer than %d bytes", lx->line,
                            AMP_LEX_MAX_LINE);
        if (i < end) {
            *line = lx->buf + start;
            *len = end - start;
            return 1;
        }
    }
    return 0;
}

int amp_lex_split(amp_lex *lx, const char *line, size_t len, amp_error *err)
{
    size_t i = 0;
    lx->ntok = 0;
    while (i < len) {
        size_t t;
        while (i < len && amp_lex_is_space(line[i]))
            i++;
        if (i >= len)
            break;
        t = i;
        while (i < len && !amp_lex_is_space(line[i]))
            i++;
        if (lx->ntok == AMP_LEX_MAX_TOKENS)
            return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: more than %d fields", lx->line,
                            AMP_LEX_MAX_TOKENS);
        lx->tok[lx->ntok] = line + t;
        lx->toklen[lx->ntok] = i - t;
        lx->ntok++;
    }
    return lx->ntok > 0;
}

int amp_lex_next(amp_lex *lx, amp_error *err)
{
    const char *line;
    size_t len;
    int r = amp_lex_next_line(lx, &line, &len, err);
    if (r <= 0)
        return r;
    if (len > AMP_LEX_MAX_LINE)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: longer than %d bytes", lx->line, AMP_LEX_MAX_LINE);
    return amp_lex_split(lx, line, len, err);
}

int amp_lex_is(const amp_lex *lx, int i, const char *s)
{
    size_t n = strlen(s);
    return i < lx->ntok && lx->toklen[i] == n && memcmp(lx->tok[i], s, n) == 0;
}

/* Copy a token into a NUL-terminated scratch buffer so strtod cannot overrun. */
static int tok_copy(const amp_lex *lx, int i, char *out, size_t cap)
{
    if (i >= lx->ntok || lx->toklen[i] >= cap)
        return 0;
    memcpy(out, lx->tok[i], lx->toklen[i]);
    out[lx->toklen[i]] = '\0';
    return 1;
}

amp_status amp_lex_double(const amp_lex *lx, int i, double *out, amp_error *err)
{
    char s[64], *end;
    double v;
    if (i >= lx->ntok)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: missing field %d", lx->line, i + 1);
    if (i < lx->ntok && amp_dec_parse(lx->tok[i], lx->toklen[i], out))
        return AMP_OK; /* a plain decimal: strtod's value without its cost */
    if (!tok_copy(lx, i, s, sizeof s))
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: field %d is not a number", lx->line, i + 1);
    errno = 0;
    v = strtod(s, &end);
    if (end == s || *end != '\0')
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: field %d '%s' is not a number", lx->line, i + 1, s);
    if (!isfinite(v))
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: field %d is not finite", lx->line, i + 1);
    *out = v;
    return AMP_OK;
}

amp_status amp_lex_long(const amp_lex *lx, int i, long lo, long hi, long *out, amp_error *err)
{
    char s[32], *end;
    long v;
    if (i >= lx->ntok)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: missing field %d", lx->line, i + 1);
    if (!tok_copy(lx, i, s, sizeof s))
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: field %d is not an integer", lx->line, i + 1);
    errno = 0;
    v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno == ERANGE)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: field %d '%s' is not an integer", lx->line, i + 1,
                        s);
    if (v < lo || v > hi)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: %ld is outside [%ld, %ld]", lx->line, v, lo, hi);
    *out = v;
    return AMP_OK;
}
