/*
 * PrusaSlicer's macro language in start/end G-code (docs/gcode.md, "Printer
 * profiles"): text with `[key]` placeholders, `{expression; ...}` blocks
 * whose values are printed, and `{if}{elsif}{else}{endif}` that may nest,
 * span lines or sit inside one line. Exported slicer profiles use it
 * throughout, so the stock ones expand as the slicer would.
 *
 * A recursive-descent evaluator over the template text with a depth bound
 * (AMP_PR_DEPTH_MAX) and an explicit stack for {if} (AMP_PR_IF_MAX), so its
 * stack use is bounded on small targets. Numbers are printed without float
 * printf (newlib-nano has none): integers in decimal, decimals with six
 * significant digits as C++'s ostream does. Inside a branch not taken the
 * text is parsed (syntax errors count) but not evaluated (its variables need
 * not exist), as in PrusaSlicer.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "printer_internal.h"

/* ---------------------------------------------------------------- errors, memory, output */

amp_status amp_pr_fail(amp_pr_ctx *c, amp_status st, const char *at, const char *fmt, ...)
{
    va_list ap;
    if (c->st != AMP_OK)
        return c->st; /* the first error is the one to report */
    c->st = st;
    c->at = at ? at : c->s;
    va_start(ap, fmt);
    if (vsnprintf(c->msg, sizeof c->msg, fmt, ap) < 0)
        c->msg[0] = '\0';
    va_end(ap);
    return st;
}

char *amp_pr_alloc(amp_pr_ctx *c, size_t n)
{
    if (c->lo < c->o + 1 || c->lo - c->o - 1 < n) {
        amp_pr_fail(c, AMP_ERR_LIMIT, NULL, "expanded G-code longer than %lu bytes (with its temporary strings)",
                    (unsigned long)c->cap - 1);
        return NULL;
    }
    c->lo -= n;
    return c->out + c->lo;
}

static amp_status put(amp_pr_ctx *c, const char *s, size_t n)
{
    if (c->lo < c->o + 1 || c->lo - c->o - 1 < n)
        return amp_pr_fail(c, AMP_ERR_LIMIT, NULL, "expanded G-code longer than %lu bytes",
                           (unsigned long)c->cap - 1);
    memmove(c->out + c->o, s, n);
    c->o += n;
    c->out[c->o] = '\0';
    return AMP_OK;
}

/* ---------------------------------------------------------------- numbers as text */

static size_t fmt_int(char *buf, long long v)
{
    char tmp[24];
    unsigned long long u = v < 0 ? 0ULL - (unsigned long long)v : (unsigned long long)v;
    size_t k = 0, n = 0;
    do {
        tmp[k++] = (char)('0' + (int)(u % 10));
        u /= 10;
    } while (u);
    if (v < 0)
        buf[n++] = '-';
    while (k)
        buf[n++] = tmp[--k];
    buf[n] = '\0';
    return n;
}

/* Six significant digits of |v| (> 0) as an integer in [100000, 999999] and the decimal exponent. */
static long long six_digits(double a, int *e)
{
    long long m;
    *e = (int)floor(log10(a));
    m = llround(a * pow(10.0, 5 - *e));
    if (m >= 1000000) /* log10 rounded up, or the rounding carried: one digit fewer */
        m = llround(a * pow(10.0, 5 - ++*e));
    else if (m < 100000)
        m = llround(a * pow(10.0, 5 - --*e));
    if (m >= 1000000) {
        m = (m + 5) / 10;
        ++*e;
    }
    return m;
}

/* A decimal as C++'s ostream prints it (%g: 6 significant digits, trailing zeros dropped). */
static size_t fmt_g(char *buf, double v)
{
    char dig[6];
    size_t n = 0;
    int e, k, nd = 6;
    long long m;
    if (v != v || fabs(v) > 1.7e308)
        return (size_t)sprintf(buf, "%s", v != v ? "nan" : v < 0 ? "-inf" : "inf");
    if (fabs(v) < 1e-300) /* zero (also -0), and subnormals */
        return (size_t)sprintf(buf, "0");
    m = six_digits(fabs(v), &e);
    for (k = 5; k >= 0; k--, m /= 10)
        dig[k] = (char)('0' + (int)(m % 10));
    while (nd > 1 && dig[nd - 1] == '0')
        nd--;
    if (v < 0)
        buf[n++] = '-';
    if (e < -4 || e >= 6) { /* d.ddddde+XX */
        buf[n++] = dig[0];
        if (nd > 1)
            buf[n++] = '.';
        for (k = 1; k < nd; k++)
            buf[n++] = dig[k];
        buf[n++] = 'e';
        buf[n++] = e < 0 ? '-' : '+';
        if (e > -10 && e < 10)
            buf[n++] = '0';
        n += fmt_int(buf + n, e < 0 ? -e : e);
    } else {
        for (k = 0; k <= e; k++) /* the integer part; none for e < 0 */
            buf[n++] = dig[k];
        if (e < 0)
            buf[n++] = '0';
        if (nd > e + 1)
            buf[n++] = '.';
        for (k = e + 1; k < 0; k++)
            buf[n++] = '0';
        for (k = e + 1 > 0 ? e + 1 : 0; k < nd; k++)
            buf[n++] = dig[k];
    }
    buf[n] = '\0';
    return n;
}

size_t amp_pr_text(const amp_pr_val *v, char *buf, const char **s)
{
    *s = buf;
    switch (v->t) {
    case MV_STR: *s = v->s; return v->n;
    case MV_BOOL: *s = v->i ? "true" : "false"; return v->i ? 4 : 5;
    case MV_INT: return fmt_int(buf, v->i);
    case MV_NUM: return fmt_g(buf, v->d);
    default: buf[0] = '\0'; return 0;
    }
}

/* ---------------------------------------------------------------- lexing */

static int is_id0(char ch) { return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || ch == '_'; }
static int is_id(char ch) { return is_id0(ch) || (ch >= '0' && ch <= '9'); }

/* Blanks and line ends inside a macro, as PrusaSlicer's skipper. */
static void ws(amp_pr_ctx *c)
{
    while (*c->s == ' ' || *c->s == '\t' || *c->s == '\r' || *c->s == '\n')
        c->s++;
}

/* Length of the identifier at @p s (0 if none). */
static size_t ident(const char *s)
{
    size_t n = 0;
    if (!is_id0(*s))
        return 0;
    while (is_id(s[n]))
        n++;
    return n;
}

/* Is the identifier at @p s (length @p n) the word @p w? */
static int is_word(const char *s, size_t n, const char *w) { return strlen(w) == n && memcmp(s, w, n) == 0; }

static amp_status expect(amp_pr_ctx *c, char ch)
{
    ws(c);
    if (*c->s != ch) {
        const char *e = c->s;
        while (*e && *e != '\n' && e - c->s < 16)
            e++;
        return amp_pr_fail(c, AMP_ERR_PARSE, NULL, "expected '%c'%s%.*s%s", ch, *c->s ? " before '" : " at the end",
                           (int)(e - c->s), c->s, *c->s ? "'" : "");
    }
    c->s++;
    return AMP_OK;
}

/* Bound the recursion (and so the stack) of the expression parser. */
static amp_status enter(amp_pr_ctx *c)
{
    if (++c->depth > AMP_PR_DEPTH_MAX)
        return amp_pr_fail(c, AMP_ERR_PARSE, NULL, "expression nested too deeply (more than %d levels)",
                           AMP_PR_DEPTH_MAX);
    return AMP_OK;
}

static amp_status leave(amp_pr_ctx *c, amp_status st)
{
    c->depth--;
    return st;
}

/* ---------------------------------------------------------------- values */

static const char *type_name(const amp_pr_val *v)
{
    static const char *const names[] = {"nothing", "nil (undefined)", "a boolean", "an integer", "a number",
                                        "a string"};
    return names[v->t];
}

static int numeric(const amp_pr_val *v) { return v->t == MV_INT || v->t == MV_NUM; }
static double num(const amp_pr_val *v) { return v->t == MV_NUM ? v->d : (double)v->i; }

/* A condition: booleans, and numbers (non-zero = true), since the .ini writes booleans as 0 and 1. */
static amp_status truth(amp_pr_ctx *c, const amp_pr_val *v, const char *at, int *out)
{
    if (v->t == MV_BOOL || v->t == MV_INT || v->t == MV_NUM) {
        *out = v->t == MV_NUM ? v->d != 0.0 : v->i != 0;
        return AMP_OK;
    }
    return amp_pr_fail(c, AMP_ERR_PARSE, at, "expected a boolean expression, got %s", type_name(v));
}

static void set_bool(amp_pr_val *v, int b)
{
    v->t = MV_BOOL;
    v->i = b != 0;
}

/* An integer result; beyond 32 bits (PrusaSlicer's int) it goes on as a decimal instead of overflowing. */
static void set_int(amp_pr_val *v, long long i)
{
    if (i > AMP_PR_INT_MAX || i < -AMP_PR_INT_MAX) {
        v->t = MV_NUM;
        v->d = (double)i;
    } else {
        v->t = MV_INT;
        v->i = i;
    }
}

/* An integer argument (an index, digits()): integers, and decimals without a fraction (the .ini's numbers). */
static amp_status whole(amp_pr_ctx *c, const amp_pr_val *v, const char *at, const char *what, long long *out)
{
    if (v->t == MV_INT || (v->t == MV_NUM && v->d == floor(v->d) && fabs(v->d) <= (double)AMP_PR_INT_MAX)) {
        *out = v->t == MV_INT ? v->i : (long long)v->d;
        return AMP_OK;
    }
    return amp_pr_fail(c, AMP_ERR_PARSE, at, "%s must be an integer, got %s", what, type_name(v));
}

/* a + b of two strings (or a string and a value printed as text), in the arena. */
static amp_status concat(amp_pr_ctx *c, amp_pr_val *a, const amp_pr_val *b)
{
    char ba[40], bb[40], *d;
    const char *sa, *sb;
    size_t na = amp_pr_text(a, ba, &sa), nb = amp_pr_text(b, bb, &sb);
    if (!(d = amp_pr_alloc(c, na + nb)))
        return c->st;
    memcpy(d, sa, na);
    memcpy(d + na, sb, nb);
    a->t = MV_STR;
    a->s = d;
    a->n = na + nb;
    return AMP_OK;
}

/* ---------------------------------------------------------------- operators */

enum { OP_NONE, OP_OR, OP_AND, OP_EQ, OP_NE, OP_MATCH, OP_NMATCH, OP_LE, OP_GE, OP_LT, OP_GT, OP_ADD, OP_SUB, OP_MUL,
       OP_DIV, OP_MOD };
/* precedence per operator, as PrusaSlicer's grammar: or < and < equality, =~ < relations < + - < * / % */
static const int prec[] = {0, 1, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 6, 6, 6};

/* The binary operator at @p s and its length. */
static int op_at(const char *s, size_t *len)
{
    static const struct {
        const char *t;
        int op;
    } ops[] = {{"||", OP_OR}, {"&&", OP_AND}, {"==", OP_EQ}, {"!=", OP_NE}, {"<>", OP_NE}, {"=~", OP_MATCH},
               {"!~", OP_NMATCH}, {"<=", OP_LE}, {">=", OP_GE}, {"<", OP_LT}, {">", OP_GT}, {"+", OP_ADD},
               {"-", OP_SUB}, {"*", OP_MUL}, {"/", OP_DIV}, {"%", OP_MOD}};
    size_t i, n = ident(s);
    if (n) {
        *len = n;
        return is_word(s, n, "or") ? OP_OR : is_word(s, n, "and") ? OP_AND : OP_NONE;
    }
    for (i = 0; i < sizeof ops / sizeof ops[0]; i++)
        if (strncmp(s, ops[i].t, strlen(ops[i].t)) == 0) {
            *len = strlen(ops[i].t);
            return ops[i].op;
        }
    return OP_NONE;
}

/* + - * / % of two numbers: integers stay integers (division truncates, as in PrusaSlicer). */
static amp_status arith(amp_pr_ctx *c, int op, const char *at, amp_pr_val *a, const amp_pr_val *b)
{
    static const char *const sym[] = {"+", "-", "*", "/", "%"};
    if (!numeric(a) || !numeric(b))
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "'%s' needs numbers, got %s and %s", sym[op - OP_ADD],
                           type_name(a), type_name(b));
    if ((op == OP_DIV || op == OP_MOD) && num(b) == 0.0)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "division by zero");
    if (a->t == MV_INT && b->t == MV_INT) {
        long long x = a->i, y = b->i;
        set_int(a, op == OP_ADD ? x + y : op == OP_SUB ? x - y : op == OP_MUL ? x * y : op == OP_DIV ? x / y : x % y);
        return AMP_OK;
    }
    a->d = op == OP_ADD ? num(a) + num(b) : op == OP_SUB ? num(a) - num(b) : op == OP_MUL ? num(a) * num(b)
         : op == OP_DIV ? num(a) / num(b) : fmod(num(a), num(b));
    a->t = MV_NUM;
    return AMP_OK;
}

/*
 * == != < > <= >=: numbers by value (equal within 1e-8 when a decimal is
 * involved), strings (or a string and a value as text) by their bytes,
 * booleans only for (in)equality. A boolean and a number compare as 0/1:
 * the .ini writes booleans as numbers.
 */
static amp_status compare(amp_pr_ctx *c, int op, const char *at, amp_pr_val *a, const amp_pr_val *b)
{
    int r = 0;
    if (a->t == MV_NIL || b->t == MV_NIL)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "cannot compare a nil (undefined) value");
    if (a->t == MV_STR || b->t == MV_STR) {
        char ba[40], bb[40];
        const char *sa, *sb;
        size_t na = amp_pr_text(a, ba, &sa), nb = amp_pr_text(b, bb, &sb);
        int m = memcmp(sa, sb, na < nb ? na : nb);
        r = m ? m : (na > nb) - (na < nb);
    } else if (a->t == MV_BOOL && b->t == MV_BOOL && op != OP_EQ && op != OP_NE) {
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "booleans compare only with == and !=");
    } else if (a->t == MV_INT && b->t == MV_INT) {
        r = (a->i > b->i) - (a->i < b->i);
    } else if (a->t == MV_BOOL || b->t == MV_BOOL || (op != OP_EQ && op != OP_NE)) {
        double x = a->t == MV_BOOL ? (double)a->i : num(a), y = b->t == MV_BOOL ? (double)b->i : num(b);
        r = (x > y) - (x < y);
    } else {
        r = fabs(num(a) - num(b)) < 1e-8 ? 0 : 1;
    }
    set_bool(a, op == OP_EQ ? r == 0 : op == OP_NE ? r != 0 : op == OP_LT ? r < 0 : op == OP_GT ? r > 0
               : op == OP_LE ? r <= 0 : r >= 0);
    return AMP_OK;
}

static amp_status apply(amp_pr_ctx *c, int op, const char *at, amp_pr_val *a, const amp_pr_val *b)
{
    int x = 0, y = 0;
    if (op == OP_OR || op == OP_AND) {
        if (truth(c, a, at, &x) != AMP_OK || truth(c, b, at, &y) != AMP_OK)
            return c->st;
        set_bool(a, op == OP_OR ? x || y : x && y);
        return AMP_OK;
    }
    if (op == OP_ADD && (a->t == MV_STR || b->t == MV_STR))
        return concat(c, a, b);
    if (op >= OP_ADD)
        return arith(c, op, at, a, b);
    return compare(c, op, at, a, b);
}

/* A regular expression literal /.../ (`\/` for a slash): its text between the slashes. */
static amp_status regex_lit(amp_pr_ctx *c, const char **pat, size_t *pn)
{
    const char *s;
    ws(c);
    if (*c->s != '/')
        return amp_pr_fail(c, AMP_ERR_PARSE, NULL, "expected a regular expression /.../");
    for (s = c->s + 1; *s && *s != '/'; s++)
        if (*s == '\\' && s[1])
            s++;
    if (!*s)
        return amp_pr_fail(c, AMP_ERR_PARSE, NULL, "unterminated regular expression");
    *pat = c->s + 1;
    *pn = (size_t)(s - c->s - 1);
    c->s = s + 1;
    return AMP_OK;
}

/* a =~ /re/, a !~ /re/: the whole string must match. */
static amp_status regex_op(amp_pr_ctx *c, int op, const char *at, amp_pr_val *a)
{
    const char *pat;
    size_t pn;
    int m = 0;
    if (regex_lit(c, &pat, &pn) != AMP_OK || c->skip)
        return c->st;
    if (a->t != MV_STR)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "the left side of %s must be a string, got %s",
                           op == OP_MATCH ? "=~" : "!~", type_name(a));
    if (amp_pr_regex(c, pat, pn, a->s, a->n, at, &m) != AMP_OK)
        return c->st;
    set_bool(a, op == OP_MATCH ? m : !m);
    return AMP_OK;
}

/* ---------------------------------------------------------------- expressions */

static amp_status expr(amp_pr_ctx *c, amp_pr_val *v);
static amp_status unary(amp_pr_ctx *c, amp_pr_val *v);

/* Operators of precedence >= @p minp, left-associative (precedence climbing). */
static amp_status binary(amp_pr_ctx *c, int minp, amp_pr_val *v)
{
    amp_status st = enter(c);
    if (st == AMP_OK)
        st = unary(c, v);
    while (st == AMP_OK) {
        amp_pr_val r;
        const char *at;
        size_t len = 0;
        int op;
        ws(c);
        at = c->s;
        op = op_at(c->s, &len);
        if (op == OP_NONE || prec[op] < minp)
            break;
        c->s += len;
        if (op == OP_MATCH || op == OP_NMATCH)
            st = regex_op(c, op, at, v);
        else if ((st = binary(c, prec[op] + 1, &r)) == AMP_OK && !c->skip)
            st = apply(c, op, at, v, &r);
    }
    return leave(c, st);
}

/* cond ? a : b (the branch not taken is parsed only), or one binary expression. */
static amp_status expr(amp_pr_ctx *c, amp_pr_val *v)
{
    amp_pr_val b;
    const char *at;
    int cond = 0, skip = c->skip;
    amp_status st = enter(c);
    if (st == AMP_OK)
        st = binary(c, 1, v);
    ws(c);
    if (st != AMP_OK || *c->s != '?')
        return leave(c, st);
    at = c->s++;
    if (!skip && truth(c, v, at, &cond) != AMP_OK)
        return leave(c, c->st);
    c->skip = skip || !cond;
    st = expr(c, v);
    if (st == AMP_OK)
        st = expect(c, ':');
    c->skip = skip || cond;
    if (st == AMP_OK)
        st = expr(c, &b);
    c->skip = skip;
    if (st == AMP_OK && !skip && !cond)
        *v = b;
    return leave(c, st);
}

/* A number literal: an integer, or a decimal when it has a point or an exponent. */
static amp_status number_lit(amp_pr_ctx *c, amp_pr_val *v)
{
    const char *s = c->s, *e = s;
    int dec = 0;
    while (*e >= '0' && *e <= '9')
        e++;
    if (*e == '.')
        for (dec = 1, e++; *e >= '0' && *e <= '9'; e++)
            ;
    if ((*e == 'e' || *e == 'E') &&
        ((e[1] >= '0' && e[1] <= '9') || ((e[1] == '+' || e[1] == '-') && e[2] >= '0' && e[2] <= '9')))
        for (dec = 1, e += 2; *e >= '0' && *e <= '9'; e++)
            ;
    c->s = e;
    if (!amp_pr_number(s, (size_t)(e - s), v))
        return amp_pr_fail(c, AMP_ERR_PARSE, s, "bad number '%.*s'", (int)(e - s > 30 ? 30 : e - s), s);
    if (!dec && v->d <= (double)AMP_PR_INT_MAX)
        set_int(v, (long long)v->d);
    return AMP_OK;
}

/* "text" with the escapes \" \\ \n \r (PrusaSlicer's), unescaped into the arena when it has any. */
static amp_status string_lit(amp_pr_ctx *c, amp_pr_val *v)
{
    const char *s = c->s + 1, *e;
    char *d;
    size_t k = 0;
    for (e = s; *e && *e != '"'; e++)
        if (*e == '\\') {
            if (e[1] != '"' && e[1] != '\\' && e[1] != 'n' && e[1] != 'r')
                return amp_pr_fail(c, AMP_ERR_PARSE, e, "invalid escape sequence in a string (\\\" \\\\ \\n \\r)");
            e++;
        }
    if (!*e)
        return amp_pr_fail(c, AMP_ERR_PARSE, c->s, "unterminated string");
    c->s = e + 1;
    v->t = MV_STR;
    v->s = s;
    v->n = (size_t)(e - s);
    if (c->skip || !memchr(s, '\\', v->n))
        return AMP_OK;
    if (!(d = amp_pr_alloc(c, v->n)))
        return c->st;
    for (; s < e; s++) {
        char ch = *s;
        if (ch == '\\') {
            ch = *++s;
            ch = ch == 'n' ? '\n' : ch == 'r' ? '\r' : ch;
        }
        d[k++] = ch;
    }
    v->s = d;
    v->n = k;
    return AMP_OK;
}

/* name or name[index] (index an additive expression, an integer >= 0); *index = -1 when none. */
static amp_status var_ref(amp_pr_ctx *c, const char **name, size_t *n, long *index)
{
    amp_pr_val ix;
    long long k = 0;
    const char *at;
    *name = c->s;
    *n = ident(c->s);
    *index = -1;
    if (*n == 0)
        return amp_pr_fail(c, AMP_ERR_PARSE, NULL, "expected a variable name");
    c->s += *n;
    ws(c);
    if (*c->s != '[')
        return AMP_OK;
    at = ++c->s;
    if (binary(c, prec[OP_ADD], &ix) != AMP_OK || expect(c, ']') != AMP_OK || c->skip)
        return c->st;
    if (whole(c, &ix, at, "an index", &k) != AMP_OK)
        return c->st;
    if (k < 0)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "index %ld out of range: negative", (long)k);
    *index = (long)k;
    return AMP_OK;
}

static amp_status variable(amp_pr_ctx *c, amp_pr_val *v)
{
    const char *at = c->s, *name;
    size_t n;
    long index;
    if (var_ref(c, &name, &n, &index) != AMP_OK || c->skip)
        return c->st;
    if (amp_pr_var(c, name, n, index, at, v, NULL) != AMP_OK)
        return c->st;
    if (v->t == MV_NIL)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "'%.*s' is nil (undefined); is_nil() tests for it",
                           n > 40 ? 40 : (int)n, name);
    return AMP_OK;
}

/* (a[, b[, c]]) with @p lo..@p hi arguments. */
static amp_status args(amp_pr_ctx *c, amp_pr_val *a, int lo, int hi, int *na)
{
    *na = 0;
    if (expect(c, '(') != AMP_OK)
        return c->st;
    for (;;) {
        if (expr(c, &a[(*na)++]) != AMP_OK)
            return c->st;
        ws(c);
        if (*c->s != ',' || *na >= hi)
            break;
        c->s++;
    }
    if (*na < lo)
        return amp_pr_fail(c, AMP_ERR_PARSE, NULL, "expected ',' and another argument");
    return expect(c, ')');
}

/* |x| with @p dec decimals (printf's %.*f without float printf); -1 when it needs more than 18 digits. */
static int fixed(char *buf, double x, int dec)
{
    unsigned long long p10 = 1, k, f;
    int i, n = 0;
    if (dec > 17 || fabs(x) * pow(10.0, dec) >= 9e18)
        return -1;
    for (i = 0; i < dec; i++)
        p10 *= 10;
    k = (unsigned long long)llround(fabs(x) * (double)p10);
    if (x < 0)
        buf[n++] = '-';
    n += (int)fmt_int(buf + n, (long long)(k / p10));
    if (dec > 0) {
        buf[n++] = '.';
        for (i = dec - 1, f = k % p10; i >= 0; i--, f /= 10)
            buf[n + i] = (char)('0' + (int)(f % 10));
        n += dec;
    }
    buf[n] = '\0';
    return n;
}

/* digits(x, width[, decimals]) and zdigits(): x right-aligned in width, padded with blanks or zeros. */
static amp_status fn_digits(amp_pr_ctx *c, int zero, const char *at, const amp_pr_val *a, int na, amp_pr_val *v)
{
    char buf[96], *d;
    long long w = 0, dec = -1;
    int len, pad, sign;
    if (!numeric(&a[0]))
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "digits(): the value must be a number, got %s", type_name(&a[0]));
    if (whole(c, &a[1], at, "digits() width", &w) != AMP_OK ||
        (na == 3 && whole(c, &a[2], at, "digits() decimals", &dec) != AMP_OK))
        return c->st;
    w = w < 0 ? 0 : w > 64 ? 64 : w;
    if (dec < 0 && a[0].t == MV_NUM && fabs(a[0].d) >= 9e18)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "digits(): the value is too large");
    len = dec < 0 ? (int)fmt_int(buf, a[0].t == MV_INT ? a[0].i : llround(a[0].d))
                  : fixed(buf, num(&a[0]), dec > 64 ? 64 : (int)dec);
    if (len < 0)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "digits(): more than 18 digits");
    pad = w > len ? (int)w - len : 0;
    if (!(d = amp_pr_alloc(c, (size_t)(len + pad))))
        return c->st;
    sign = zero && buf[0] == '-'; /* zeros go after the sign, as printf's %0*d */
    memcpy(d, buf, (size_t)sign);
    memset(d + sign, zero ? '0' : ' ', (size_t)pad);
    memcpy(d + sign + pad, buf + sign, (size_t)(len - sign));
    v->t = MV_STR;
    v->s = d;
    v->n = (size_t)(len + pad);
    return AMP_OK;
}

/* min max int round digits zdigits. */
static amp_status fn_math(amp_pr_ctx *c, const char *f, size_t n, const char *at, amp_pr_val *v)
{
    amp_pr_val a[3];
    int na, two = is_word(f, n, "min") || is_word(f, n, "max"), dig = is_word(f, n, "digits") || is_word(f, n, "zdigits");
    if (args(c, a, two || dig ? 2 : 1, dig ? 3 : two ? 2 : 1, &na) != AMP_OK || c->skip)
        return c->st;
    if (dig)
        return fn_digits(c, f[0] == 'z', at, a, na, v);
    if (!numeric(&a[0]) || (two && !numeric(&a[1])))
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "%.*s() needs numbers, got %s", (int)n, f, type_name(&a[0]));
    *v = a[0];
    if (two && a[0].t == MV_INT && a[1].t == MV_INT)
        set_int(v, (f[1] == 'i') == (a[1].i < a[0].i) ? a[1].i : a[0].i);
    else if (two) {
        v->t = MV_NUM;
        v->d = f[1] == 'i' ? fmin(num(&a[0]), num(&a[1])) : fmax(num(&a[0]), num(&a[1]));
    } else if (a[0].t == MV_NUM) {
        double r = f[0] == 'r' ? floor(a[0].d + 0.5) : a[0].d < 0 ? ceil(a[0].d) : floor(a[0].d);
        if (a[0].d < 0 && f[0] == 'r') /* std::round: halves away from zero */
            r = -floor(-a[0].d + 0.5);
        if (fabs(r) > (double)AMP_PR_INT_MAX)
            return amp_pr_fail(c, AMP_ERR_PARSE, at, "%.*s(): out of the integer range", (int)n, f);
        set_int(v, (long long)r);
    }
    return AMP_OK;
}

/* One pattern of one_of(): "text" (equal), /re/ or ~"re" (the whole string matches); *found set. */
static amp_status one_of_item(amp_pr_ctx *c, const amp_pr_val *x, int *found)
{
    amp_pr_val p;
    const char *at = c->s, *pat;
    size_t pn;
    int re = *c->s == '/' || *c->s == '~', m = 0;
    if (*c->s == '/') {
        if (regex_lit(c, &pat, &pn) != AMP_OK)
            return c->st;
        p.t = MV_STR, p.s = pat, p.n = pn;
    } else {
        c->s += *c->s == '~';
        if (unary(c, &p) != AMP_OK)
            return c->st;
    }
    if (c->skip || *found)
        return AMP_OK;
    if (p.t != MV_STR)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "one_of(): a pattern must be a string, got %s", type_name(&p));
    if (re && amp_pr_regex(c, p.s, p.n, x->s, x->n, at, &m) != AMP_OK)
        return c->st;
    *found = re ? m : p.n == x->n && memcmp(p.s, x->s, p.n) == 0;
    return AMP_OK;
}

/* one_of(x, pattern, ...): does the string x equal or match one of the patterns? */
static amp_status fn_one_of(amp_pr_ctx *c, const char *at, amp_pr_val *v)
{
    amp_pr_val x;
    int found = 0;
    if (expect(c, '(') != AMP_OK || unary(c, &x) != AMP_OK)
        return c->st;
    if (!c->skip && x.t != MV_STR)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "one_of(): the first argument must be a string, got %s",
                           type_name(&x));
    ws(c);
    c->s += *c->s == ',';
    for (;;) {
        ws(c);
        if (*c->s == ')' || !*c->s)
            break;
        if (one_of_item(c, &x, &found) != AMP_OK)
            return c->st;
        ws(c);
        c->s += *c->s == ',';
    }
    if (expect(c, ')') != AMP_OK)
        return c->st;
    set_bool(v, found);
    return AMP_OK;
}

/* is_nil(var[i]), size(var), empty(var): functions of a variable, not of a value. */
static amp_status fn_var(amp_pr_ctx *c, const char *f, size_t fn, amp_pr_val *v)
{
    const char *at, *name;
    size_t n, count = 0;
    long index;
    int nil = f[0] == 'i';
    if (expect(c, '(') != AMP_OK)
        return c->st;
    ws(c);
    at = c->s;
    if (var_ref(c, &name, &n, &index) != AMP_OK || expect(c, ')') != AMP_OK || c->skip)
        return c->st;
    if (!nil && index >= 0)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "%.*s() takes a variable, not one of its values", (int)fn, f);
    if (amp_pr_var(c, name, n, index, at, v, &count) != AMP_OK)
        return c->st;
    if (!nil && count == 1 && v->t == MV_STR && v->n == 0) /* an empty list is written as an empty value */
        count = 0;
    if (nil)
        set_bool(v, v->t == MV_NIL);
    else if (f[0] == 's')
        set_int(v, (long long)count);
    else
        set_bool(v, count == 0);
    return AMP_OK;
}

/* Words at the start of a value: true, false, not, a function or a variable. */
static amp_status word(amp_pr_ctx *c, amp_pr_val *v)
{
    static const char *const math[] = {"min", "max", "int", "round", "digits", "zdigits"};
    static const char *const bad[] = {"if", "elsif", "else", "endif", "then", "and", "or"};
    const char *w = c->s, *at = c->s;
    size_t n = ident(w), i;
    if (is_word(w, n, "true") || is_word(w, n, "false")) {
        c->s += n;
        set_bool(v, n == 4);
        return AMP_OK;
    }
    for (i = 0; i < sizeof math / sizeof math[0]; i++)
        if (is_word(w, n, math[i]))
            return c->s += n, fn_math(c, w, n, at, v);
    if (is_word(w, n, "one_of"))
        return c->s += n, fn_one_of(c, at, v);
    if (is_word(w, n, "is_nil") || is_word(w, n, "size") || is_word(w, n, "empty"))
        return c->s += n, fn_var(c, w, n, v);
    if (is_word(w, n, "random"))
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "random() is refused: the same job must give the same G-code");
    if (is_word(w, n, "interpolate_table"))
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "interpolate_table() is not supported");
    if (is_word(w, n, "local") || is_word(w, n, "global") || is_word(w, n, "repeat"))
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "variables of the macros (local, global, repeat) are not supported");
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++)
        if (is_word(w, n, bad[i]))
            return amp_pr_fail(c, AMP_ERR_PARSE, at, "unexpected '%s' (expected a value)", bad[i]);
    return variable(c, v);
}

/* - + ! not ( ) literals, functions and variables. */
static amp_status unary(amp_pr_ctx *c, amp_pr_val *v)
{
    const char *at;
    amp_status st = enter(c);
    int b = 0;
    memset(v, 0, sizeof *v);
    ws(c);
    at = c->s;
    if (st != AMP_OK)
        return leave(c, st);
    if (*at == '(') {
        c->s++;
        if (expr(c, v) == AMP_OK)
            expect(c, ')');
    } else if (*at == '-' || *at == '+' || *at == '!' || (ident(at) == 3 && memcmp(at, "not", 3) == 0)) {
        c->s += *at == 'n' ? 3 : 1;
        if (unary(c, v) == AMP_OK && !c->skip) {
            if (*at == '!' || *at == 'n') {
                if (truth(c, v, at, &b) == AMP_OK)
                    set_bool(v, !b);
            } else if (!numeric(v)) {
                amp_pr_fail(c, AMP_ERR_PARSE, at, "unary '%c' needs a number, got %s", *at, type_name(v));
            } else if (*at == '-') {
                if (v->t == MV_INT)
                    v->i = -v->i;
                else
                    v->d = -v->d;
            }
        }
    } else if ((*at >= '0' && *at <= '9') || (*at == '.' && at[1] >= '0' && at[1] <= '9')) {
        number_lit(c, v);
    } else if (*at == '"') {
        string_lit(c, v);
    } else if (is_id0(*at)) {
        word(c, v);
    } else {
        amp_pr_fail(c, AMP_ERR_PARSE, at, "expected a value%s%.*s%s", *at ? " before '" : " at the end",
                    (int)strcspn(at, "\n") > 16 ? 16 : (int)strcspn(at, "\n"), at, *at ? "'" : "");
    }
    if (c->skip)
        v->t = MV_NONE;
    return leave(c, c->st);
}

/* ---------------------------------------------------------------- the text */

enum { D_NONE, D_IF, D_ELSIF, D_ELSE, D_ENDIF };

typedef struct ifblk {
    const char *at;                   /* the {if}, for "{if} without {endif}" */
    unsigned char parent;             /* the text around the block is output */
    unsigned char active;             /* the current branch is output */
    unsigned char taken, in_else;     /* a branch was output; {else} seen */
} ifblk;

typedef struct mstate {
    amp_pr_ctx c;
    ifblk ifs[AMP_PR_IF_MAX];         /* open {if} blocks: an explicit stack, no recursion */
    int ni;
    int comment;                      /* after a ';' on this line of the template */
} mstate;

static int active(const mstate *m) { return m->ni == 0 || m->ifs[m->ni - 1].active; }

/* The condition of {if} / {elsif} (evaluated when @p eval, parsed always) and the closing brace. */
static amp_status condition(amp_pr_ctx *c, int eval, int *out)
{
    amp_pr_val v;
    const char *at;
    int skip = c->skip;
    *out = 0;
    ws(c);
    at = c->s;
    c->skip = !eval;
    if (expr(c, &v) == AMP_OK && eval)
        truth(c, &v, at, out);
    c->skip = skip;
    return c->st != AMP_OK ? c->st : expect(c, '}');
}

/* {if c}, {elsif c}, {else}, {endif} (after the word): open, switch or close a block. */
static amp_status directive(mstate *m, int d, const char *open)
{
    amp_pr_ctx *c = &m->c;
    ifblk *b = m->ni ? &m->ifs[m->ni - 1] : NULL;
    int t = 0;
    if (d == D_IF) {
        if (m->ni >= AMP_PR_IF_MAX)
            return amp_pr_fail(c, AMP_ERR_PARSE, open, "{if} blocks nested deeper than %d", AMP_PR_IF_MAX);
        b = &m->ifs[m->ni];
        b->at = open;
        b->parent = (unsigned char)active(m);
        b->in_else = 0;
        if (condition(c, b->parent, &t) != AMP_OK)
            return c->st;
        b->active = b->taken = (unsigned char)(b->parent && t);
        m->ni++;
    } else if (!b || (d != D_ENDIF && b->in_else)) {
        static const char *const what[] = {"", "", "{elsif}", "{else}", "{endif}"};
        return amp_pr_fail(c, AMP_ERR_PARSE, open, b ? "%s after {else}" : "%s without {if}", what[d]);
    } else if (d == D_ELSIF) {
        if (condition(c, b->parent && !b->taken, &t) != AMP_OK)
            return c->st;
        b->active = (unsigned char)(b->parent && !b->taken && t);
        b->taken |= b->active;
    } else if (expect(c, '}') != AMP_OK) {
        return c->st;
    } else if (d == D_ELSE) {
        b->active = (unsigned char)(b->parent && !b->taken);
        b->taken = b->in_else = 1;
    } else {
        m->ni--;
    }
    c->skip = !active(m);
    return AMP_OK;
}

/* `name =` ahead (an assignment, which ampath does not support)? */
static int assignment(const char *s)
{
    size_t n = ident(s);
    int depth = 0;
    if (n == 0)
        return 0;
    for (s += n; *s == ' ' || *s == '\t'; s++)
        ;
    if (*s == '[')
        for (; *s && (depth += (*s == '[') - (*s == ']')) > 0; s++)
            ;
    for (s += *s == ']'; *s == ' ' || *s == '\t'; s++)
        ;
    return *s == '=' && s[1] != '=' && s[1] != '~';
}

/*
 * e_retracted[i] = x: PrusaSlicer's output variables (e_retracted, e_restart_extra, e_position) tell its
 * writer the extruder's state after the sequence (the XL's start ends with one). Accepted and evaluated,
 * without effect: ampath's writer keeps its own extruder state. Other assignments are refused.
 */
static amp_status output_assignment(amp_pr_ctx *c)
{
    amp_pr_val v;
    const char *at = c->s, *name;
    size_t n;
    long index;
    if (var_ref(c, &name, &n, &index) != AMP_OK)
        return c->st;
    if (!is_word(name, n, "e_retracted") && !is_word(name, n, "e_restart_extra") && !is_word(name, n, "e_position"))
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "assignments are not supported in the macros (but to e_retracted, "
                           "e_restart_extra, e_position, which ampath ignores)");
    if (expect(c, '=') != AMP_OK)
        return c->st;
    return expr(c, &v);
}

/* expression; expression; ... } : each value printed. */
static amp_status statements(amp_pr_ctx *c)
{
    for (;;) {
        amp_pr_val v;
        char buf[40];
        const char *t;
        ws(c);
        if (*c->s == ';') {
            c->s++;
            continue;
        }
        if (*c->s == '}') {
            c->s++;
            return AMP_OK;
        }
        if (assignment(c->s)) {
            if (output_assignment(c) != AMP_OK)
                return c->st;
        } else if (expr(c, &v) != AMP_OK) {
            return c->st;
        } else if (!c->skip) {
            size_t n = amp_pr_text(&v, buf, &t);
            if (put(c, t, n) != AMP_OK)
                return c->st;
        }
        ws(c);
        if (*c->s != ';' && *c->s != '}')
            return expect(c, '}');
    }
}

/* In a comment a block that does not evaluate is kept as it is, up to its closing character on the line
 * (ampath's behaviour before the macros; PrusaSlicer refuses it); a lone opening character stays too. */
static amp_status verbatim(mstate *m, const char *open, char close)
{
    amp_pr_ctx *c = &m->c;
    const char *e = open + 1;
    while (*e && *e != '\n' && *e != close)
        e++;
    e = *e == close ? e + 1 : open + 1;
    c->s = e;
    return c->skip ? AMP_OK : put(c, open, (size_t)(e - open));
}

/* Back to the state before a block that failed in a comment, which verbatim() then copies. */
static amp_status recover(mstate *m, const char *open, char close, size_t o, size_t lo)
{
    amp_pr_ctx *c = &m->c;
    if (!m->comment || c->st == AMP_ERR_LIMIT)
        return c->st;
    c->st = AMP_OK;
    c->o = o;
    c->out[o] = '\0';
    c->lo = lo;
    c->depth = 0;
    c->skip = !active(m);
    return verbatim(m, open, close);
}

/* { ... } at the cursor: a directive, or statements whose values are printed. */
static amp_status macro(mstate *m)
{
    amp_pr_ctx *c = &m->c;
    const char *open = c->s, *w;
    size_t o = c->o, lo = c->lo, n;
    int d;
    c->s++;
    ws(c);
    w = c->s;
    n = ident(w);
    d = is_word(w, n, "if") ? D_IF : is_word(w, n, "elsif") ? D_ELSIF : is_word(w, n, "else") ? D_ELSE
      : is_word(w, n, "endif") ? D_ENDIF : D_NONE;
    if (d != D_NONE) {
        c->s += n;
        return directive(m, d, open);
    }
    if (*w == '}' || (!strchr(w, '}') && m->comment)) /* "{}" and a lone '{' in a comment: text */
        return verbatim(m, open, '}');
    if (!strchr(w, '}'))
        return amp_pr_fail(c, AMP_ERR_PARSE, open, "'{' without a closing '}'");
    if (statements(c) != AMP_OK)
        return recover(m, open, '}', o, lo);
    c->lo = lo; /* the block's temporary strings are no longer needed */
    return AMP_OK;
}

/* [key], [key_N], [key[N]], [key[var]]: the parts of the legacy placeholder at @p s; 0 when it is none. */
static int legacy_form(const char *s, const char **name, size_t *n, const char **ix, size_t *ixn, const char **end)
{
    s++;
    *name = s;
    *n = ident(s);
    *ix = NULL;
    *ixn = 0;
    if (*n == 0)
        return 0;
    s += *n;
    if (*s == '[') {
        *ix = ++s;
        while (is_id(*s))
            s++;
        *ixn = (size_t)(s - *ix);
        if (*ixn == 0 || *s++ != ']')
            return 0;
    }
    if (*s != ']')
        return 0;
    *end = s + 1;
    return 1;
}

/* The index of [key[N]] or [key[var]] (var an integer variable). */
static amp_status legacy_index(amp_pr_ctx *c, const char *ix, size_t ixn, long *index)
{
    amp_pr_val v;
    long long k = 0;
    if (*ix >= '0' && *ix <= '9') {
        if (!amp_pr_number(ix, ixn, &v) || ixn > 9)
            return amp_pr_fail(c, AMP_ERR_PARSE, ix, "bad index '%.*s'", ixn > 20 ? 20 : (int)ixn, ix);
        *index = (long)v.d;
        return AMP_OK;
    }
    if (amp_pr_var(c, ix, ixn, -1, ix, &v, NULL) != AMP_OK || whole(c, &v, ix, "an index", &k) != AMP_OK)
        return c->st;
    if (k < 0)
        return amp_pr_fail(c, AMP_ERR_PARSE, ix, "index %ld out of range: negative", (long)k);
    *index = (long)k;
    return AMP_OK;
}

/* The value of a legacy placeholder as text: key_N is value N of key unless key_N is itself a variable. */
static amp_status legacy_value(amp_pr_ctx *c, const char *at, const char *name, size_t n, const char *ix, size_t ixn)
{
    amp_pr_val v;
    char buf[40];
    const char *t;
    long index = -1;
    size_t k = n;
    if (ix && legacy_index(c, ix, ixn, &index) != AMP_OK)
        return c->st;
    while (!ix && k > 0 && name[k - 1] >= '0' && name[k - 1] <= '9')
        k--;
    if (!ix && k > 1 && k < n && n - k <= 9 && name[k - 1] == '_' && !amp_pr_var_known(c->p, name, n) &&
        amp_pr_var_known(c->p, name, k - 1)) {
        amp_pr_number(name + k, n - k, &v);
        index = (long)v.d;
        n = k - 1;
    }
    if (amp_pr_var(c, name, n, index, at, &v, NULL) != AMP_OK)
        return c->st;
    if (v.t == MV_NIL)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "'%.*s' is nil (undefined)", n > 40 ? 40 : (int)n, name);
    if (v.t == MV_BOOL) /* PrusaSlicer writes the value as the .ini does: 1 or 0 */
        return put(c, v.i ? "1" : "0", 1);
    k = amp_pr_text(&v, buf, &t);
    return put(c, t, k);
}

/* [ at the cursor: a legacy placeholder, or text when none follows (a '[' without ']' on the line). */
static amp_status legacy(mstate *m)
{
    amp_pr_ctx *c = &m->c;
    const char *open = c->s, *name, *ix, *end, *e;
    size_t n, ixn, o = c->o, lo = c->lo;
    if (legacy_form(open, &name, &n, &ix, &ixn, &end)) {
        c->s = end;
        if (c->skip || legacy_value(c, open + 1, name, n, ix, ixn) == AMP_OK)
            return AMP_OK;
        return recover(m, open, ']', o, lo);
    }
    for (e = open + 1; *e && *e != '\n' && *e != ']'; e++)
        ;
    if (*e != ']' || m->comment || c->skip) {
        c->s = open + 1;
        return c->skip ? AMP_OK : put(c, "[", 1);
    }
    return amp_pr_fail(c, AMP_ERR_PARSE, open, "expected a variable name in [%.*s]", (int)(e - open - 1) > 30 ? 30 :
                       (int)(e - open - 1), open + 1);
}

/* The template: text copied, placeholders and blocks expanded. */
static amp_status run(mstate *m)
{
    amp_pr_ctx *c = &m->c;
    while (*c->s && c->st == AMP_OK) {
        const char *s = c->s;
        if (*s == '{') {
            macro(m);
            continue;
        }
        if (*s == '[') {
            legacy(m);
            continue;
        }
        for (; *s && *s != '{' && *s != '['; s++)
            m->comment = *s == ';' ? 1 : *s == '\n' ? 0 : m->comment;
        if (!c->skip)
            put(c, c->s, (size_t)(s - c->s));
        c->s = s;
    }
    if (c->st == AMP_OK && m->ni > 0)
        amp_pr_fail(c, AMP_ERR_PARSE, m->ifs[m->ni - 1].at, "{if} without {endif}");
    return c->st;
}

amp_status amp_pr_expand(const amp_printer *p, const amp_printer_job *job, const char *tmpl, char *out, size_t cap,
                         int *used_job, amp_error *err)
{
    mstate m;
    amp_pr_ctx *c = &m.c;
    const char *s, *ls;
    long line = 1;
    if (!p || !tmpl || !out || cap == 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "printer: NULL argument to expand");
    memset(&m, 0, sizeof m);
    c->p = p;
    c->job = job;
    c->src = c->s = tmpl;
    c->out = out;
    c->cap = c->lo = cap;
    out[0] = '\0';
    run(&m);
    if (used_job)
        *used_job = c->used_job;
    if (c->st == AMP_OK)
        return AMP_OK;
    if (c->st == AMP_ERR_LIMIT)
        return amp_fail(err, c->st, 0, "%s", c->msg);
    for (s = ls = tmpl; s < c->at && *s; s++)
        if (*s == '\n')
            line++, ls = s + 1;
    return amp_fail(err, c->st, line, "G-code line %ld, column %ld: %s", line, (long)(c->at - ls) + 1, c->msg);
}
