/* Shared test helpers (linked into every test program). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"

const char *fx_prog(const char *env)
{
    const char *p = getenv(env);
    ck_assert_msg(p != NULL, "%s not set (run through make check)", env);
    return p;
}

void fx_msleep(int ms)
{
    struct timespec ts;
    ts.tv_sec = ms / 1000;
    ts.tv_nsec = (long)(ms % 1000) * 1000000L;
    nanosleep(&ts, NULL);
}

int fx_split(char *s, char **argv, int n)
{
    char *tok = strtok(s, " ");
    while (tok && n < FX_MAXARGS - 1) {
        argv[n++] = tok;
        tok = strtok(NULL, " ");
    }
    argv[n] = NULL;
    return n;
}

const char *fx_tmpdir(void)
{
    /* tests/run.sh makes one fresh directory per run: pids wrap at 32,768, and a file left in /tmp by an
     * earlier run under the same pid was once read as this run's (a stale daemon banner) */
    const char *d = getenv("AMP_TEST_TMP");
    return d && *d ? d : "/tmp";
}

const char *fx_tmp(const char *name)
{
    static char buf[8][256];
    static int next;
    char *b = buf[next++ & 7];
    snprintf(b, sizeof buf[0], "%s/ampath-test-%ld-%s", fx_tmpdir(), (long)getpid(), name);
    return b;
}

static void *fa_alloc(void *user, size_t size)
{
    fx_failalloc *f = user;
    void *p;
    if (f->count >= f->budget)
        return NULL;
    f->count++;
    p = malloc(size);
    f->live += p != NULL;
    return p;
}

static void *fa_realloc(void *user, void *ptr, size_t size)
{
    fx_failalloc *f = user;
    void *p;
    if (f->count >= f->budget)
        return NULL;
    f->count++;
    p = realloc(ptr, size);
    f->live += p != NULL && ptr == NULL;
    return p;
}

static void fa_free(void *user, void *ptr)
{
    fx_failalloc *f = user;
    f->live -= ptr != NULL;
    free(ptr);
}

void fx_failalloc_init(fx_failalloc *f, long budget)
{
    f->a.alloc = fa_alloc;
    f->a.realloc = fa_realloc;
    f->a.free = fa_free;
    f->a.user = f;
    f->budget = budget;
    f->count = 0;
    f->live = 0;
}

void fx_assert_same_paths(const amp_pathset *a, const amp_pathset *b)
{
    size_t i;
    ck_assert_uint_eq(a->npaths, b->npaths);
    ck_assert_uint_eq(a->nverts, b->nverts);
    for (i = 0; i < a->npaths; i++)
        ck_assert_msg(a->paths[i].role == b->paths[i].role && a->paths[i].first == b->paths[i].first &&
                          a->paths[i].n == b->paths[i].n && a->paths[i].h == b->paths[i].h,
                      "path %lu differs", (unsigned long)i);
    for (i = 0; i < a->nverts; i++)
        ck_assert_msg(memcmp(&a->verts[i], &b->verts[i], sizeof a->verts[i]) == 0, "vertex %lu differs",
                      (unsigned long)i);
}
