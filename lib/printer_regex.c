/*
 * Regular expressions of the printer macros (`=~ /re/`, `!~`, one_of): the
 * subset that the slicers' stock profiles use (docs/gcode.md), matched
 * against the whole string as PrusaSlicer's regex_match does. Literals, `.`
 * (any character, newline included, as boost's default), `[a-z]`, `[^...]`,
 * `\d \w \s` and their negations, other `\x` as literals, `( )`, `(?: )`,
 * `|`, `*`, `+`, `?` (a lazy `?` after them changes nothing for a yes/no
 * match), `^` and `$`.
 *
 * The pattern is compiled into a small program and run as a Thompson NFA
 * (every alternative advanced in step): time linear in the subject, no
 * recursion while matching and no exponential backtracking, all in a
 * fixed-size struct on the stack. Compiling recurses only per nested group,
 * at most RE_GROUPS deep.
 */
#include <string.h>

#include "printer_internal.h"

#define RE_PROG_MAX 256 /* instructions: about one per pattern character */
#define RE_CLASS_MAX 16 /* [] classes and \d \w \s */
#define RE_GROUPS 16    /* nested groups */
#define RE_ALTS 64      /* alternatives of one group */

enum { RI_CHAR, RI_ANY, RI_CLASS, RI_SPLIT, RI_JMP, RI_BOL, RI_EOL, RI_MATCH };

typedef struct rinst {
    unsigned char op, c;    /* c: the character, or the class index */
    unsigned short x, y;    /* RI_SPLIT: both targets; RI_JMP: x */
} rinst;

typedef struct re_prog {
    rinst in[RE_PROG_MAX];
    unsigned char cls[RE_CLASS_MAX][32]; /* 256-bit character sets */
    size_t n, ncls;
    const char *p, *end; /* pattern cursor */
    const char *why;     /* first error */
} re_prog;

static int re_error(re_prog *re, const char *why)
{
    if (!re->why)
        re->why = why;
    return -1;
}

static int emit(re_prog *re, int op, int c, size_t x, size_t y)
{
    if (re->n >= RE_PROG_MAX)
        return re_error(re, "too long");
    re->in[re->n].op = (unsigned char)op;
    re->in[re->n].c = (unsigned char)c;
    re->in[re->n].x = (unsigned short)x;
    re->in[re->n].y = (unsigned short)y;
    return (int)re->n++;
}

/*
 * Insert a RI_SPLIT before the instructions [at, n) (a quantifier or an
 * alternative comes after what it applies to). Jumps inside the moved block
 * move with it; jumps from before it to @p at keep entering at the split.
 */
static int insert_split(re_prog *re, size_t at, size_t x, size_t y)
{
    size_t i;
    if (re->n >= RE_PROG_MAX)
        return re_error(re, "too long");
    memmove(&re->in[at + 1], &re->in[at], (re->n - at) * sizeof re->in[0]);
    re->n++;
    for (i = 0; i < re->n; i++) {
        rinst *r = &re->in[i];
        size_t lim = i > at ? at : at + 1; /* from inside the block: >= at moved; from before: > at moved */
        if (i == at || (r->op != RI_SPLIT && r->op != RI_JMP))
            continue;
        if (r->x >= lim)
            r->x++;
        if (r->op == RI_SPLIT && r->y >= lim)
            r->y++;
    }
    re->in[at].op = RI_SPLIT;
    re->in[at].x = (unsigned short)x;
    re->in[at].y = (unsigned short)y;
    return 0;
}

static void set_bit(unsigned char *set, unsigned char ch) { set[ch >> 3] |= (unsigned char)(1u << (ch & 7)); }

/* \d \w \s (and capitals: their complements) into @p set; 0 when @p e is not one of them. */
static int class_escape(unsigned char *set, char e)
{
    unsigned char tmp[32];
    int ch, lower = e | 0x20;
    if (lower != 'd' && lower != 'w' && lower != 's')
        return 0;
    memset(tmp, 0, sizeof tmp);
    for (ch = 0; ch < 256; ch++) {
        int in = lower == 'd'   ? (ch >= '0' && ch <= '9')
                 : lower == 'w' ? (ch >= '0' && ch <= '9') || ((ch | 0x20) >= 'a' && (ch | 0x20) <= 'z') || ch == '_'
                                : ch == ' ' || (ch >= '\t' && ch <= '\r');
        if (in != (e != lower))
            set_bit(tmp, (unsigned char)ch);
    }
    for (ch = 0; ch < 32; ch++)
        set[ch] |= tmp[ch];
    return 1;
}

/* The character of escape `\e` used as a literal. */
static unsigned char literal_escape(char e) { return (unsigned char)(e == 'n' ? '\n' : e == 't' ? '\t' : e == 'r' ? '\r' : e); }

static unsigned char *new_class(re_prog *re)
{
    unsigned char *set;
    if (re->ncls >= RE_CLASS_MAX) {
        re_error(re, "too many [] classes");
        return NULL;
    }
    set = re->cls[re->ncls++];
    memset(set, 0, 32);
    return set;
}

/* [...] after the '[': a set of characters, ranges and \d \w \s, `^` first for the complement. */
static int parse_class(re_prog *re)
{
    unsigned char *set = new_class(re);
    int neg = 0, first = 1, k;
    if (!set)
        return -1;
    if (re->p < re->end && *re->p == '^')
        neg = 1, re->p++;
    while (re->p < re->end && (*re->p != ']' || first)) {
        unsigned char lo = (unsigned char)*re->p++, hi;
        first = 0;
        if (lo == '\\') {
            if (re->p >= re->end)
                return re_error(re, "trailing backslash");
            if (class_escape(set, *re->p)) {
                re->p++;
                continue;
            }
            lo = literal_escape(*re->p++);
        }
        hi = lo;
        if (re->p + 1 < re->end && *re->p == '-' && re->p[1] != ']') {
            hi = (unsigned char)re->p[1];
            re->p += 2;
            if (hi == '\\' && re->p < re->end)
                hi = literal_escape(*re->p++);
            if (hi < lo)
                return re_error(re, "range out of order in []");
        }
        for (k = lo; k <= hi; k++)
            set_bit(set, (unsigned char)k);
    }
    if (re->p >= re->end)
        return re_error(re, "missing ]");
    re->p++;
    if (neg)
        for (k = 0; k < 32; k++)
            set[k] = (unsigned char)~set[k];
    return emit(re, RI_CLASS, (int)(re->ncls - 1), 0, 0);
}

static int parse_alt(re_prog *re, int depth);

/* An escape outside []: a class, a literal; back-references are not supported. */
static int parse_escape(re_prog *re)
{
    char e;
    unsigned char *set;
    if (re->p >= re->end)
        return re_error(re, "trailing backslash");
    e = *re->p++;
    if (e >= '1' && e <= '9')
        return re_error(re, "back-references are not supported");
    if ((e | 0x20) == 'd' || (e | 0x20) == 'w' || (e | 0x20) == 's') {
        if (!(set = new_class(re)))
            return -1;
        class_escape(set, e);
        return emit(re, RI_CLASS, (int)(re->ncls - 1), 0, 0);
    }
    return emit(re, RI_CHAR, literal_escape(e), 0, 0);
}

/* One atom: a group, a class, `.`, `^`, `$`, an escape or a literal character. */
static int parse_atom(re_prog *re, int depth)
{
    char ch = *re->p++;
    switch (ch) {
    case '(':
        if (depth >= RE_GROUPS)
            return re_error(re, "groups nested too deeply");
        if (re->end - re->p >= 2 && re->p[0] == '?' && re->p[1] == ':')
            re->p += 2;
        if (parse_alt(re, depth + 1) < 0)
            return -1;
        if (re->p >= re->end || *re->p != ')')
            return re_error(re, "missing )");
        re->p++;
        return 0;
    case '[': return parse_class(re);
    case '.': return emit(re, RI_ANY, 0, 0, 0);
    case '^': return emit(re, RI_BOL, 0, 0, 0);
    case '$': return emit(re, RI_EOL, 0, 0, 0);
    case '\\': return parse_escape(re);
    case '*': case '+': case '?': return re_error(re, "nothing to repeat");
    case '{': return re_error(re, "repetition {n,m} is not supported");
    default: return emit(re, RI_CHAR, (unsigned char)ch, 0, 0);
    }
}

/* An atom and its quantifiers `*`, `+`, `?` (each may be followed by a lazy `?`). */
static int parse_repeat(re_prog *re, int depth)
{
    size_t s = re->n, e;
    if (parse_atom(re, depth) < 0)
        return -1;
    while (re->p < re->end && (*re->p == '*' || *re->p == '+' || *re->p == '?')) {
        char q = *re->p++;
        if (re->p < re->end && *re->p == '?')
            re->p++; /* lazy: the same yes/no answer */
        e = re->n;
        if (q == '+') {
            if (emit(re, RI_SPLIT, 0, s, e + 1) < 0)
                return -1;
        } else if (insert_split(re, s, s + 1, 0) < 0 || (q == '*' && emit(re, RI_JMP, 0, s, 0) < 0)) {
            return -1;
        } else {
            re->in[s].y = (unsigned short)re->n; /* past the loop (or the optional atom) */
        }
    }
    return 0;
}

/* Alternatives a|b|c: each but the last behind a split, each but the last jumping to the end. */
static int parse_alt(re_prog *re, int depth)
{
    size_t start = re->n, jumps[RE_ALTS], nj = 0, i;
    for (;;) {
        while (re->p < re->end && *re->p != '|' && *re->p != ')')
            if (parse_repeat(re, depth) < 0)
                return -1;
        if (re->p >= re->end || *re->p != '|')
            break;
        re->p++;
        if (nj >= RE_ALTS)
            return re_error(re, "too many alternatives");
        if (insert_split(re, start, start + 1, 0) < 0 || emit(re, RI_JMP, 0, 0, 0) < 0)
            return -1;
        jumps[nj++] = re->n - 1;
        re->in[start].y = (unsigned short)re->n;
        start = re->n;
    }
    for (i = 0; i < nj; i++)
        re->in[jumps[i]].x = (unsigned short)re->n;
    return 0;
}

/* Follow splits, jumps and anchors from @p pc at subject position @p i (of @p n) into @p list. */
static void add_thread(const re_prog *re, unsigned short *list, size_t *nl, unsigned *mark, unsigned gen, size_t pc,
                       size_t i, size_t n)
{
    unsigned short stack[RE_PROG_MAX + 1];
    size_t sp = 0;
    stack[sp++] = (unsigned short)pc;
    while (sp > 0) {
        const rinst *r;
        pc = stack[--sp];
        if (mark[pc] == gen)
            continue;
        mark[pc] = gen;
        r = &re->in[pc];
        if (r->op == RI_JMP)
            stack[sp++] = r->x;
        else if (r->op == RI_SPLIT)
            stack[sp++] = r->y, stack[sp++] = r->x;
        else if (r->op == RI_BOL || r->op == RI_EOL) {
            if (r->op == RI_BOL ? i == 0 : i == n)
                stack[sp++] = (unsigned short)(pc + 1);
        } else
            list[(*nl)++] = (unsigned short)pc;
    }
}

/* Run the program over all of @p s: 1 when some path reaches RI_MATCH at the end. */
static int re_run(const re_prog *re, const char *s, size_t n)
{
    unsigned short a[RE_PROG_MAX], b[RE_PROG_MAX], *cl = a, *nl = b, *t;
    unsigned mark[RE_PROG_MAX];
    size_t ncl = 0, nnl, i, k;
    unsigned gen = 1;
    memset(mark, 0, sizeof mark);
    add_thread(re, cl, &ncl, mark, gen, 0, 0, n);
    for (i = 0; i < n && ncl > 0; i++) {
        unsigned char ch = (unsigned char)s[i];
        nnl = 0;
        gen++;
        for (k = 0; k < ncl; k++) {
            const rinst *r = &re->in[cl[k]];
            if ((r->op == RI_CHAR && r->c == ch) || r->op == RI_ANY ||
                (r->op == RI_CLASS && (re->cls[r->c][ch >> 3] >> (ch & 7) & 1)))
                add_thread(re, nl, &nnl, mark, gen, cl[k] + 1u, i + 1, n);
        }
        t = cl, cl = nl, nl = t;
        ncl = nnl;
    }
    for (k = 0; i == n && k < ncl; k++)
        if (re->in[cl[k]].op == RI_MATCH)
            return 1;
    return 0;
}

amp_status amp_pr_regex(amp_pr_ctx *c, const char *pat, size_t pn, const char *s, size_t sn, const char *at,
                        int *match)
{
    re_prog re;
    re.n = re.ncls = 0;
    re.p = pat;
    re.end = pat + pn;
    re.why = NULL;
    if (parse_alt(&re, 0) == 0 && re.p < re.end)
        re_error(&re, "unmatched )");
    if (!re.why)
        emit(&re, RI_MATCH, 0, 0, 0);
    if (re.why)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "bad regular expression /%.*s/: %s", pn > 60 ? 60 : (int)pn, pat,
                           re.why);
    *match = re_run(&re, s, sn);
    return AMP_OK;
}
