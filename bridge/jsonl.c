/*
 * jsonl.c — the JSON half of the control socket (the host API of docs/interfaces.md §8): one flat
 * object per line in, one per line out. Requests need no nesting, so nesting
 * is refused rather than half-supported; output is always valid UTF-8 (printer
 * messages arrive over a noisy wire and may hold any byte).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon.h"

typedef struct jp {
    const char *s;
    size_t i, n;
    br_jobj *o;
    const char *err;
} jp;

static void ws(jp *p)
{
    while (p->i < p->n && (p->s[p->i] == ' ' || p->s[p->i] == '\t' || p->s[p->i] == '\r' || p->s[p->i] == '\n'))
        p->i++;
}

/* Length of the valid UTF-8 sequence at s (at most n bytes), 0 if invalid. */
static size_t utf8_len(const unsigned char *s, size_t n)
{
    size_t k, i;
    unsigned long cp;
    if (s[0] < 0x80)
        return 1;
    if (s[0] >= 0xc2 && s[0] <= 0xdf)
        k = 2, cp = s[0] & 0x1f;
    else if (s[0] >= 0xe0 && s[0] <= 0xef)
        k = 3, cp = s[0] & 0x0f;
    else if (s[0] >= 0xf0 && s[0] <= 0xf4)
        k = 4, cp = s[0] & 0x07;
    else
        return 0;
    if (n < k)
        return 0;
    for (i = 1; i < k; i++) {
        if ((s[i] & 0xc0) != 0x80)
            return 0;
        cp = (cp << 6) | (s[i] & 0x3f);
    }
    if ((k == 3 && (cp < 0x800 || (cp >= 0xd800 && cp <= 0xdfff))) || (k == 4 && (cp < 0x10000 || cp > 0x10ffff)))
        return 0;
    return k;
}

static int put(jp *p, char c)
{
    if (p->o->used >= sizeof p->o->store - 1) {
        p->err = "request too large";
        return -1;
    }
    p->o->store[p->o->used++] = c;
    return 0;
}

static int put_cp(jp *p, unsigned long cp)
{
    if (cp < 0x80)
        return put(p, (char)cp);
    if (cp < 0x800)
        return put(p, (char)(0xc0 | (cp >> 6))) || put(p, (char)(0x80 | (cp & 0x3f)));
    if (cp < 0x10000)
        return put(p, (char)(0xe0 | (cp >> 12))) || put(p, (char)(0x80 | ((cp >> 6) & 0x3f))) ||
               put(p, (char)(0x80 | (cp & 0x3f)));
    return put(p, (char)(0xf0 | (cp >> 18))) || put(p, (char)(0x80 | ((cp >> 12) & 0x3f))) ||
           put(p, (char)(0x80 | ((cp >> 6) & 0x3f))) || put(p, (char)(0x80 | (cp & 0x3f)));
}

static int hex4(jp *p, unsigned long *v)
{
    int k;
    *v = 0;
    if (p->i + 4 > p->n)
        return -1;
    for (k = 0; k < 4; k++) {
        char c = p->s[p->i++];
        *v <<= 4;
        if (c >= '0' && c <= '9')
            *v |= (unsigned long)(c - '0');
        else if (c >= 'a' && c <= 'f')
            *v |= (unsigned long)(c - 'a' + 10);
        else if (c >= 'A' && c <= 'F')
            *v |= (unsigned long)(c - 'A' + 10);
        else
            return -1;
    }
    return 0;
}

static int escape(jp *p)
{
    unsigned long cp, lo;
    char c = p->s[p->i++];
    switch (c) {
    case '"': case '\\': case '/': return put(p, c);
    case 'b': return put(p, '\b');
    case 'f': return put(p, '\f');
    case 'n': return put(p, '\n');
    case 'r': return put(p, '\r');
    case 't': return put(p, '\t');
    case 'u':
        if (hex4(p, &cp) != 0)
            break;
        if (cp >= 0xd800 && cp <= 0xdbff) { /* a surrogate pair: the low half must follow */
            if (p->i + 2 > p->n || p->s[p->i] != '\\' || p->s[p->i + 1] != 'u')
                break;
            p->i += 2;
            if (hex4(p, &lo) != 0 || lo < 0xdc00 || lo > 0xdfff)
                break;
            cp = 0x10000 + ((cp - 0xd800) << 10) + (lo - 0xdc00);
        } else if ((cp >= 0xdc00 && cp <= 0xdfff) || cp == 0) {
            break; /* a lone low surrogate; NUL would cut the string short */
        }
        return put_cp(p, cp);
    default: break;
    }
    p->err = "bad escape in a string";
    return -1;
}

/* A string at p->i (on the opening quote): decoded into the store; its start and length. */
static int string(jp *p, const char **out, size_t *outlen)
{
    size_t start = p->o->used;
    p->i++;
    while (p->i < p->n) {
        unsigned char c = (unsigned char)p->s[p->i];
        size_t k;
        if (c == '"') {
            p->i++;
            *out = p->o->store + start;
            *outlen = p->o->used - start;
            return put(p, '\0');
        }
        if (c < 0x20) {
            p->err = "control byte in a string";
            return -1;
        }
        if (c == '\\') {
            p->i++;
            if (p->i >= p->n || escape(p) != 0) {
                p->err = p->err ? p->err : "bad escape in a string";
                return -1;
            }
            continue;
        }
        k = utf8_len((const unsigned char *)p->s + p->i, p->n - p->i);
        if (k == 0) {
            p->err = "invalid UTF-8";
            return -1;
        }
        while (k--)
            if (put(p, p->s[p->i++]) != 0)
                return -1;
    }
    p->err = "unterminated string";
    return -1;
}

static int word(jp *p, const char *w)
{
    size_t k = strlen(w);
    if (p->i + k <= p->n && memcmp(p->s + p->i, w, k) == 0) {
        p->i += k;
        return 1;
    }
    return 0;
}

static int digits(const jp *p, size_t *i)
{
    size_t k = *i;
    while (*i < p->n && p->s[*i] >= '0' && p->s[*i] <= '9')
        (*i)++;
    return *i > k;
}

/* JSON's grammar: -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)? */
static int number(jp *p, double *v)
{
    char tmp[64];
    size_t i = p->i;
    if (i < p->n && p->s[i] == '-')
        i++;
    if (i < p->n && p->s[i] == '0')
        i++;
    else if (!digits(p, &i))
        return -1;
    if (i < p->n && p->s[i] == '.') {
        i++;
        if (!digits(p, &i))
            return -1;
    }
    if (i < p->n && (p->s[i] == 'e' || p->s[i] == 'E')) {
        i++;
        if (i < p->n && (p->s[i] == '+' || p->s[i] == '-'))
            i++;
        if (!digits(p, &i))
            return -1;
    }
    if (i - p->i >= sizeof tmp)
        return -1;
    memcpy(tmp, p->s + p->i, i - p->i);
    tmp[i - p->i] = '\0';
    *v = strtod(tmp, NULL);
    if (!isfinite(*v))
        return -1;
    p->i = i;
    return 0;
}

static int value(jp *p, br_jmember *m)
{
    char c = p->s[p->i];
    if (c == '"') {
        m->type = BR_J_STR;
        return string(p, &m->str, &m->len);
    }
    if (c == '{' || c == '[') {
        p->err = "nested objects and arrays are not supported";
        return -1;
    }
    if (word(p, "true")) {
        m->type = BR_J_BOOL;
        m->b = 1;
    } else if (word(p, "false")) {
        m->type = BR_J_BOOL;
        m->b = 0;
    } else if (word(p, "null")) {
        m->type = BR_J_NULL;
    } else if (number(p, &m->num) == 0) {
        m->type = BR_J_NUM;
    } else {
        p->err = "bad value";
        return -1;
    }
    return 0;
}

static int member(jp *p)
{
    br_jmember *m;
    size_t klen;
    if (p->o->n >= BR_JSON_MEMBERS) {
        p->err = "too many members";
        return -1;
    }
    m = &p->o->m[p->o->n];
    memset(m, 0, sizeof *m);
    if (p->i >= p->n || p->s[p->i] != '"') {
        p->err = "expected a key";
        return -1;
    }
    if (string(p, &m->key, &klen) != 0)
        return -1;
    if (br_json_get(p->o, m->key)) {
        p->err = "duplicate key";
        return -1;
    }
    ws(p);
    if (p->i >= p->n || p->s[p->i] != ':') {
        p->err = "expected ':'";
        return -1;
    }
    p->i++;
    ws(p);
    if (p->i >= p->n || value(p, m) != 0) {
        p->err = p->err ? p->err : "missing value";
        return -1;
    }
    p->o->n++;
    return 0;
}

int br_json_parse(br_jobj *o, const char *text, size_t len, char *why, size_t whylen)
{
    jp p;
    memset(&p, 0, sizeof p);
    p.s = text;
    p.n = len;
    p.o = o;
    o->n = 0;
    o->used = 0;
    ws(&p);
    if (p.i >= p.n || p.s[p.i] != '{') {
        snprintf(why, whylen, "JSON: expected an object");
        return -1;
    }
    p.i++;
    ws(&p);
    if (p.i < p.n && p.s[p.i] == '}') {
        p.i++;
    } else {
        for (;;) {
            if (member(&p) != 0)
                goto bad;
            ws(&p);
            if (p.i < p.n && p.s[p.i] == ',') {
                p.i++;
                ws(&p);
                continue;
            }
            if (p.i < p.n && p.s[p.i] == '}') {
                p.i++;
                break;
            }
            p.err = "expected ',' or '}'";
            goto bad;
        }
    }
    ws(&p);
    if (p.i != p.n) {
        p.err = "bytes after the object";
        goto bad;
    }
    return 0;
bad:
    snprintf(why, whylen, "JSON: %s at byte %lu", p.err ? p.err : "syntax error", (unsigned long)p.i + 1);
    return -1;
}

const br_jmember *br_json_get(const br_jobj *o, const char *key)
{
    int i;
    for (i = 0; i < o->n; i++)
        if (strcmp(o->m[i].key, key) == 0)
            return &o->m[i];
    return NULL;
}

/* ---- writer ---- */
static void w_raw(br_jw *w, const char *s, size_t n)
{
    if (w->overflow || w->len + n + 1 > w->cap) {
        w->overflow = 1;
        return;
    }
    memcpy(w->buf + w->len, s, n);
    w->len += n;
    w->buf[w->len] = '\0';
}

static void w_string(br_jw *w, const char *s)
{
    const unsigned char *u = (const unsigned char *)(s ? s : "");
    size_t n = strlen((const char *)u), i = 0;
    w_raw(w, "\"", 1);
    while (i < n) {
        char esc[8];
        size_t k;
        if (u[i] == '"' || u[i] == '\\') {
            esc[0] = '\\';
            esc[1] = (char)u[i];
            w_raw(w, esc, 2);
            i++;
        } else if (u[i] < 0x20 || u[i] == 0x7f) {
            snprintf(esc, sizeof esc, "\\u%04x", u[i]);
            w_raw(w, esc, 6);
            i++;
        } else if ((k = utf8_len(u + i, n - i)) == 0) {
            w_raw(w, "\\ufffd", 6); /* a byte garbled on the wire: still valid JSON */
            i++;
        } else {
            w_raw(w, (const char *)u + i, k);
            i += k;
        }
    }
    w_raw(w, "\"", 1);
}

static void w_key(br_jw *w, const char *key)
{
    if (w->n++ > 0)
        w_raw(w, ",", 1);
    w_string(w, key);
    w_raw(w, ":", 1);
}

void br_jw_begin(br_jw *w, char *buf, size_t cap)
{
    w->buf = buf;
    w->cap = cap;
    w->len = 0;
    w->n = 0;
    w->overflow = cap < 4;
    if (!w->overflow)
        buf[0] = '\0';
    w_raw(w, "{", 1);
}

void br_jw_str(br_jw *w, const char *key, const char *val)
{
    w_key(w, key);
    w_string(w, val);
}

void br_jw_long(br_jw *w, const char *key, long v)
{
    char t[32];
    w_key(w, key);
    snprintf(t, sizeof t, "%ld", v);
    w_raw(w, t, strlen(t));
}

void br_jw_num(br_jw *w, const char *key, double v)
{
    char t[40];
    w_key(w, key);
    if (!isfinite(v)) {
        w_raw(w, "null", 4);
        return;
    }
    snprintf(t, sizeof t, "%.10g", v);
    w_raw(w, t, strlen(t));
}

void br_jw_bool(br_jw *w, const char *key, int v)
{
    w_key(w, key);
    w_raw(w, v ? "true" : "false", v ? 4 : 5);
}

void br_jw_null(br_jw *w, const char *key)
{
    w_key(w, key);
    w_raw(w, "null", 4);
}

void br_jw_member(br_jw *w, const char *key, const br_jmember *m)
{
    switch (m->type) {
    case BR_J_STR: br_jw_str(w, key, m->str); break;
    case BR_J_NUM: br_jw_num(w, key, m->num); break;
    case BR_J_BOOL: br_jw_bool(w, key, m->b); break;
    default: br_jw_null(w, key); break;
    }
}

long br_jw_end(br_jw *w)
{
    w_raw(w, "}\n", 2);
    return w->overflow ? -1 : (long)w->len;
}
