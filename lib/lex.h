/*
 * lex.h — internal line lexer shared by the text parsers (.amp, .spl, ASCII STL).
 *
 * Walks a buffer line by line (LF or CRLF), strips `#` comments when asked,
 * and splits lines into whitespace-separated tokens without copying or
 * requiring NUL termination. Never reads past buf + len.
 */
#ifndef AMP_LEX_H
#define AMP_LEX_H

#include <stddef.h>

#include "ampath/status.h"

#define AMP_LEX_MAX_LINE 4096
#define AMP_LEX_MAX_TOKENS 64

typedef struct amp_lex {
    const char *buf;
    size_t len, pos;
    long line;          /* 1-based number of the current line */
    int strip_comments; /* non-zero: '#' starts a comment */
    /* tokens of the current line */
    const char *tok[AMP_LEX_MAX_TOKENS];
    size_t toklen[AMP_LEX_MAX_TOKENS];
    int ntok;
} amp_lex;

void amp_lex_init(amp_lex *lx, const char *buf, size_t len, int strip_comments);

/** Non-zero for the characters that separate tokens (space, tab, CR, VT, FF; a newline ends the line). */
int amp_lex_is_space(char c);

/**
 * Advance to the next line that has at least one token (blank and comment-only
 * lines are skipped). Returns 1 with tokens set, 0 at end of input, or a
 * negative amp_status (line too long, too many tokens, NUL byte) with @p err filled.
 */
int amp_lex_next(amp_lex *lx, amp_error *err);

/**
 * Advance to the next line with at least one token and return it unsplit in
 * *line / *len (comment stripped when asked; no length or field limit, for
 * long numeric lines such as .spl knot vectors). Blank lines and lines with a
 * comment longer than AMP_LEX_MAX_LINE bytes (newline excluded) are refused:
 * only a content line without comment may exceed it, for the caller to judge.
 * Returns 1, 0 at end of input, or a negative amp_status (NUL byte, over-long
 * comment or blank line). Tokens are not set; see amp_lex_split().
 */
int amp_lex_next_line(amp_lex *lx, const char **line, size_t *len, amp_error *err);

/** Split @p line into the tokens of @p lx (as amp_lex_next does). Returns 1, or a negative status (too many fields). */
int amp_lex_split(amp_lex *lx, const char *line, size_t len, amp_error *err);

/** Non-zero when token @p i equals the C string @p s. */
int amp_lex_is(const amp_lex *lx, int i, const char *s);

/** Parse token @p i as a finite double. AMP_ERR_PARSE with line number on failure. */
amp_status amp_lex_double(const amp_lex *lx, int i, double *out, amp_error *err);

/** Parse token @p i as an integer in [lo, hi]. AMP_ERR_PARSE with line number on failure. */
amp_status amp_lex_long(const amp_lex *lx, int i, long lo, long hi, long *out, amp_error *err);

#endif
