/*
 * control.c — the control socket's language (docs/interfaces.md §8; plain words and JSON lines):
 * a request is one line, plain words for people and scripts or one JSON object
 * for host software; every request gets exactly one reply line in its own form,
 * and subscribers get event lines. Pure functions: the daemon does the acting.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon.h"

static const struct {
    const char *name;
    br_cmd cmd;
} cmds[] = {{"submit", BR_CMD_SUBMIT},       {"status", BR_CMD_STATUS},
            {"pause", BR_CMD_PAUSE},         {"resume", BR_CMD_RESUME},
            {"cancel", BR_CMD_CANCEL},       {"estop", BR_CMD_ESTOP},
            {"subscribe", BR_CMD_SUBSCRIBE}, {"unsubscribe", BR_CMD_UNSUBSCRIBE},
            {"help", BR_CMD_HELP},           {"quit", BR_CMD_QUIT}};

static const char command_list[] =
    "submit PATH [LINE] | status | pause | resume | cancel | estop | subscribe | unsubscribe | help | quit";

const char *br_cmd_name(br_cmd c)
{
    size_t i;
    for (i = 0; i < sizeof cmds / sizeof cmds[0]; i++)
        if (cmds[i].cmd == c)
            return cmds[i].name;
    return "none";
}

int br_cmd_is_priority(br_cmd c)
{
    return c == BR_CMD_ESTOP || c == BR_CMD_CANCEL || c == BR_CMD_STATUS || c == BR_CMD_PAUSE;
}

static br_cmd lookup(const char *w, size_t n)
{
    size_t i;
    for (i = 0; i < sizeof cmds / sizeof cmds[0]; i++)
        if (strlen(cmds[i].name) == n && memcmp(cmds[i].name, w, n) == 0)
            return cmds[i].cmd;
    return BR_CMD_NONE;
}

static int fail(char *why, size_t whylen, const char *fmt, const char *a)
{
    snprintf(why, whylen, fmt, a);
    return -1;
}

/* A job line number: digits only, >= 1. */
static int parse_from(const char *s, size_t n, long *out)
{
    size_t i;
    long v = 0;
    if (n == 0 || n > 9)
        return -1;
    for (i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9')
            return -1;
        v = v * 10 + (s[i] - '0');
    }
    if (v < 1)
        return -1;
    *out = v;
    return 0;
}

static int check_path(br_request *r, char *why, size_t whylen)
{
    if (r->path[0] == '\0')
        return fail(why, whylen, "%s", "submit needs a job path");
    if (r->path[0] != '/')
        return fail(why, whylen, "%s", "the job path must be absolute (the daemon does not know your directory)");
    return 0;
}

/* submit's arguments: PATH (bare, or "quoted" with \" and \\) then an optional LINE, nothing else. */
static int plain_submit(br_request *r, const char *a, size_t n, char *why, size_t whylen)
{
    size_t i = 0, k = 0;
    if (n > 0 && a[0] == '"') {
        for (i = 1; i < n && a[i] != '"'; i++) {
            if (a[i] == '\\' && i + 1 < n && (a[i + 1] == '"' || a[i + 1] == '\\'))
                i++;
            if (k >= sizeof r->path - 1)
                return fail(why, whylen, "%s", "job path too long");
            r->path[k++] = a[i];
        }
        if (i >= n)
            return fail(why, whylen, "%s", "unterminated quote in the job path");
        i++;
        if (i < n && a[i] != ' ' && a[i] != '\t')
            return fail(why, whylen, "%s", "text right after the closing quote of the job path");
    } else {
        for (; i < n && a[i] != ' ' && a[i] != '\t'; i++) {
            if (k >= sizeof r->path - 1)
                return fail(why, whylen, "%s", "job path too long");
            r->path[k++] = a[i];
        }
    }
    r->path[k] = '\0';
    if (check_path(r, why, whylen) != 0)
        return -1;
    while (i < n && (a[i] == ' ' || a[i] == '\t'))
        i++;
    if (i < n) {
        size_t j = i;
        char word[64];
        while (j < n && a[j] != ' ' && a[j] != '\t')
            j++;
        snprintf(word, sizeof word, "%.*s", (int)(j - i), a + i);
        if (parse_from(a + i, j - i, &r->from) != 0)
            return fail(why, whylen,
                        "submit PATH [LINE]: '%s' is not a line number (quote a path with spaces: "
                        "submit \"/my dir/job.gcode\")",
                        word);
        while (j < n && (a[j] == ' ' || a[j] == '\t'))
            j++;
        if (j < n)
            return fail(why, whylen, "%s", "submit PATH [LINE]: too many arguments");
    }
    return 0;
}

static int plain(br_request *r, const char *s, size_t n, char *why, size_t whylen)
{
    size_t w = 0;
    char word[32];
    while (w < n && s[w] != ' ' && s[w] != '\t')
        w++;
    r->cmd = lookup(s, w);
    if (r->cmd == BR_CMD_NONE) {
        snprintf(word, sizeof word, "%.*s", (int)(w < 24 ? w : 24), s);
        snprintf(why, whylen, "unknown command '%s%s' (%s)", word, w > 24 ? "..." : "", command_list);
        return -1;
    }
    while (w < n && (s[w] == ' ' || s[w] == '\t'))
        w++;
    if (r->cmd == BR_CMD_SUBMIT)
        return plain_submit(r, s + w, n - w, why, whylen);
    if (w < n)
        return fail(why, whylen, "%s takes no arguments", br_cmd_name(r->cmd));
    return 0;
}

static void take_id(br_request *r, const br_jmember *id)
{
    r->has_id = 1;
    r->id = *id;
    r->id.key = "id";
    if (id->type == BR_J_STR) {
        snprintf(r->idstr, sizeof r->idstr, "%s", id->str);
        r->id.str = r->idstr;
    }
}

static int json(br_request *r, const char *s, size_t n, char *why, size_t whylen)
{
    static br_jobj o; /* 8 KB: not on the stack of a loop that also holds a session */
    const br_jmember *m;
    int i;
    if (br_json_parse(&o, s, n, why, whylen) != 0)
        return -1;
    if ((m = br_json_get(&o, "id")) != NULL)
        take_id(r, m);
    m = br_json_get(&o, "cmd");
    if (!m || m->type != BR_J_STR)
        return fail(why, whylen, "%s", "a request needs \"cmd\" (a string)");
    r->cmd = lookup(m->str, m->len);
    if (r->cmd == BR_CMD_NONE)
        return fail(why, whylen, "unknown cmd (%s)", command_list);
    for (i = 0; i < o.n; i++) {
        const br_jmember *x = &o.m[i];
        if (strcmp(x->key, "cmd") == 0 || strcmp(x->key, "id") == 0)
            continue;
        if (r->cmd == BR_CMD_SUBMIT && strcmp(x->key, "path") == 0) {
            if (x->type != BR_J_STR || x->len >= sizeof r->path)
                return fail(why, whylen, "%s", "\"path\" must be a string shorter than PATH_MAX");
            memcpy(r->path, x->str, x->len + 1);
        } else if (r->cmd == BR_CMD_SUBMIT && strcmp(x->key, "from") == 0) {
            if (x->type != BR_J_NUM || x->num < 1 || x->num > 1e9 || x->num != (double)(long)x->num)
                return fail(why, whylen, "%s", "\"from\" must be a job line number >= 1");
            r->from = (long)x->num;
        } else {
            snprintf(why, whylen, "unknown key \"%.40s\" for %s", x->key, br_cmd_name(r->cmd));
            return -1;
        }
    }
    if (r->cmd == BR_CMD_SUBMIT)
        return check_path(r, why, whylen);
    return 0;
}

int br_request_parse(br_request *r, const char *line, size_t len, char *why, size_t whylen)
{
    size_t a = 0, b = len, i;
    memset(r, 0, sizeof *r);
    r->from = 1;
    why[0] = '\0';
    while (a < b && (line[a] == ' ' || line[a] == '\t'))
        a++;
    while (b > a && (line[b - 1] == ' ' || line[b - 1] == '\t' || line[b - 1] == '\r'))
        b--;
    r->json = a < b && line[a] == '{';
    for (i = a; i < b; i++) {
        unsigned char c = (unsigned char)line[i];
        if (c == '\0')
            return fail(why, whylen, "%s", "NUL byte in the command: ignored");
        if ((c < 0x20 && c != '\t') || c == 0x7f)
            return fail(why, whylen, "%s", "control byte in the command: ignored");
    }
    if (a == b)
        return 0; /* a blank line: no command, no reply */
    return r->json ? json(r, line + a, b - a, why, whylen) : plain(r, line + a, b - a, why, whylen);
}

/* ---- replies and events ---- */
void br_msg_reply(br_msg *m, int ok, const char *text)
{
    memset(m, 0, sizeof *m);
    m->ok = ok;
    m->text = text;
}

void br_msg_event(br_msg *m, const char *event)
{
    memset(m, 0, sizeof *m);
    m->ok = 1;
    m->event = event;
}

static br_kv *add(br_msg *m, const char *key, int type)
{
    br_kv *kv;
    if (m->n >= BR_KV_MAX)
        return NULL;
    kv = &m->kv[m->n++];
    kv->key = key;
    kv->type = type;
    return kv;
}

void br_msg_str(br_msg *m, const char *key, const char *s)
{
    br_kv *kv = add(m, key, 0);
    if (kv)
        kv->s = s;
}

void br_msg_long(br_msg *m, const char *key, long v)
{
    br_kv *kv = add(m, key, 1);
    if (kv)
        kv->l = v;
}

void br_msg_num(br_msg *m, const char *key, double v)
{
    br_kv *kv = add(m, key, 2);
    if (kv)
        kv->d = v;
}

void br_msg_bool(br_msg *m, const char *key, int v)
{
    br_kv *kv = add(m, key, 3);
    if (kv)
        kv->l = v != 0;
}

typedef struct pbuf {
    char *b;
    size_t cap, len;
    int overflow;
} pbuf;

static void pput(pbuf *p, const char *s, size_t n)
{
    if (p->overflow || p->len + n + 1 > p->cap) {
        p->overflow = 1;
        return;
    }
    memcpy(p->b + p->len, s, n);
    p->len += n;
    p->b[p->len] = '\0';
}

/* A plain value: control bytes become '?', so no reply can hold a second line. */
static void pvalue(pbuf *p, const char *s, int quote_if_needed)
{
    size_t i, n = strlen(s);
    int q = quote_if_needed && (n == 0 || strpbrk(s, " \t\"") != NULL);
    if (q)
        pput(p, "\"", 1);
    for (i = 0; i < n; i++) {
        char c = s[i];
        if ((unsigned char)c < 0x20 || c == 0x7f)
            c = '?';
        if (q && (c == '"' || c == '\\'))
            pput(p, "\\", 1);
        pput(p, &c, 1);
    }
    if (q)
        pput(p, "\"", 1);
}

static long render_plain(const br_msg *m, char *buf, size_t cap)
{
    pbuf p = {buf, cap, 0, cap == 0};
    int i;
    char t[48];
    if (m->event) {
        pput(&p, "event ", 6);
        pvalue(&p, m->event, 0);
    } else {
        pput(&p, m->ok ? "ok" : "error", m->ok ? 2 : 5);
        if (m->text && m->text[0]) {
            pput(&p, " ", 1);
            pvalue(&p, m->text, 0);
        }
    }
    for (i = 0; i < m->n; i++) {
        const br_kv *kv = &m->kv[i];
        pput(&p, " ", 1);
        pput(&p, kv->key, strlen(kv->key));
        pput(&p, "=", 1);
        if (kv->type == 0)
            pvalue(&p, kv->s ? kv->s : "-", 1);
        else {
            if (kv->type == 1)
                snprintf(t, sizeof t, "%ld", kv->l);
            else if (kv->type == 2 && kv->d == kv->d && kv->d < 1e15 && kv->d > -1e15)
                snprintf(t, sizeof t, "%.1f", kv->d);
            else if (kv->type == 2)
                snprintf(t, sizeof t, "-");
            else
                snprintf(t, sizeof t, "%s", kv->l ? "true" : "false");
            pput(&p, t, strlen(t));
        }
    }
    pput(&p, "\n", 1);
    return p.overflow ? -1 : (long)p.len;
}

static long render_json(const br_msg *m, const br_request *req, char *buf, size_t cap)
{
    br_jw w;
    int i;
    br_jw_begin(&w, buf, cap);
    if (m->event) {
        br_jw_str(&w, "event", m->event);
    } else {
        br_jw_bool(&w, "ok", m->ok);
        if (req && req->has_id)
            br_jw_member(&w, "id", &req->id);
        if (m->text)
            br_jw_str(&w, m->ok ? "message" : "error", m->text);
    }
    for (i = 0; i < m->n; i++) {
        const br_kv *kv = &m->kv[i];
        if (kv->type == 0) {
            if (kv->s)
                br_jw_str(&w, kv->key, kv->s);
            else
                br_jw_null(&w, kv->key);
        } else if (kv->type == 1)
            br_jw_long(&w, kv->key, kv->l);
        else if (kv->type == 2)
            br_jw_num(&w, kv->key, kv->d);
        else
            br_jw_bool(&w, kv->key, (int)kv->l);
    }
    return br_jw_end(&w);
}

long br_msg_render(const br_msg *m, int json_form, const br_request *req, char *buf, size_t cap)
{
    return json_form ? render_json(m, req, buf, cap) : render_plain(m, buf, cap);
}
