/*
 * The `.amp` reader (docs/interfaces.md §3): the header line, then path headers each followed by its vertex
 * lines.
 *
 * A large text is read in chunks that begin at path headers, on every thread: the chunks' paths and vertices
 * are counted first (headers only), the set grows once to hold them, and each chunk is parsed straight into
 * its place by the same line code as a one-piece read, through a view of the set whose allocator refuses to
 * allocate (threads never call the caller's allocator; a chunk that would need more room than it counted is
 * not clean). A chunk that does not parse cleanly on its own (an error, or a path running on into the next
 * chunk) sends the whole text to the one-piece read, which gives the error, its line and its message as
 * before; the paths read are the same either way.
 */
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "lex.h"
#include "paths_parse.h"

/* below this a text is read in one piece: a chunk's counting and set-up cost more than it saves */
#define CHUNK_MIN_BYTES ((size_t)1 << 20)
#define CHUNKS_MAX 64

/* z and r repeat along a path: the same text as the line before is the same number */
typedef struct memo {
    const char *tok[2];
    size_t len[2];
    double val[2];
} memo;

static amp_status vertex_line(amp_pathset *ps, amp_lex *lx, memo *m, amp_error *err)
{
    double x[4];
    int i;
    amp_status st = AMP_OK;
    if (lx->ntok != 4)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: expected 'x y z r', found %d fields", lx->line,
                        lx->ntok);
    for (i = 0; i < 4 && st == AMP_OK; i++) {
        if (i >= 2 && m->len[i - 2] && lx->toklen[i] == m->len[i - 2] &&
            memcmp(lx->tok[i], m->tok[i - 2], m->len[i - 2]) == 0) {
            x[i] = m->val[i - 2];
            continue;
        }
        st = amp_lex_double(lx, i, &x[i], err);
        if (i >= 2 && st == AMP_OK) {
            m->tok[i - 2] = lx->tok[i];
            m->len[i - 2] = lx->toklen[i];
            m->val[i - 2] = x[i];
        }
    }
    if (st != AMP_OK)
        return st;
    if (x[3] < 0.0)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: negative radius %g", lx->line, x[3]);
    st = amp_pathset_push(ps, amp_v3(x[0], x[1], x[2]), x[3], err);
    if (st != AMP_OK && err)
        err->line = lx->line;
    return st;
}

/* `path <role> <n> [<h>]`: a new path, *remaining its vertex count. */
static amp_status header_line(amp_pathset *ps, amp_lex *lx, long *remaining, amp_error *err)
{
    amp_role role;
    long n;
    double h = 0.0;
    amp_status st;
    if (!amp_lex_is(lx, 0, "path"))
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: expected 'path <role> <n>'", lx->line);
    if (lx->ntok != 3 && lx->ntok != 4)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: expected 'path <role> <n> [<h>]'", lx->line);
    if (amp_lex_is(lx, 1, "object"))
        role = AMP_ROLE_OBJECT;
    else if (amp_lex_is(lx, 1, "support"))
        role = AMP_ROLE_SUPPORT;
    else
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: unknown role (expected object or support)", lx->line);
    st = amp_lex_long(lx, 2, 0, (long)AMP_PATH_MAX_VERTS, &n, err);
    if (st == AMP_OK && lx->ntok == 4)
        st = amp_lex_double(lx, 3, &h, err);
    if (st != AMP_OK)
        return st;
    if (lx->ntok == 4 && !(h > 0.0))
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: bead height %g must be positive", lx->line, h);
    if ((st = amp_pathset_begin(ps, role, err)) != AMP_OK)
        return st;
    ps->paths[ps->npaths - 1].h = h;
    *remaining = n;
    return AMP_OK;
}

/* The lines of @p lx up to its end into @p ps; *remaining: vertices still due in the last path. */
static amp_status parse_body(amp_pathset *ps, amp_lex *lx, long *remaining, amp_error *err)
{
    memo m;
    int r;
    amp_status st = AMP_OK;
    memset(&m, 0, sizeof m);
    while (st == AMP_OK && (r = amp_lex_next(lx, err)) > 0) {
        if (*remaining > 0) {
            if ((st = vertex_line(ps, lx, &m, err)) == AMP_OK)
                (*remaining)--;
        } else
            st = header_line(ps, lx, remaining, err);
    }
    return st != AMP_OK ? st : (r < 0 ? (amp_status)r : AMP_OK);
}

/* The `ampath-paths 1` line; the lexer stands after it. */
static amp_status file_header(amp_lex *lx, amp_error *err)
{
    int r = amp_lex_next(lx, err);
    if (r < 0)
        return (amp_status)r;
    if (r == 0)
        return amp_fail(err, AMP_ERR_PARSE, 1, "line 1: empty input, expected 'ampath-paths 1'");
    if (!amp_lex_is(lx, 0, "ampath-paths") || lx->ntok != 2)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: expected header 'ampath-paths 1'", lx->line);
    if (!amp_lex_is(lx, 1, "1"))
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: unsupported ampath-paths version", lx->line);
    return AMP_OK;
}

static amp_status parse_one_piece(amp_pathset *ps, const char *text, size_t len, amp_error *err)
{
    amp_lex lx;
    size_t np0 = ps->npaths, nv0 = ps->nverts;
    long remaining = 0;
    amp_status st;
    amp_lex_init(&lx, text, len, 1);
    st = file_header(&lx, err);
    if (st == AMP_OK)
        st = parse_body(ps, &lx, &remaining, err);
    if (st == AMP_OK && remaining > 0)
        st = amp_fail(err, AMP_ERR_PARSE, lx.line + 1, "line %ld: end of input, %ld vertices missing in last path",
                      lx.line + 1, remaining);
    if (st != AMP_OK) {
        ps->npaths = np0;
        ps->nverts = nv0;
    }
    return st;
}

/* Is "path" the first token of the line from @p at (as the lexer splits it, comments cut)? */
static int path_token(const char *t, size_t at, size_t len)
{
    while (at < len && amp_lex_is_space(t[at]))
        at++;
    if (len - at < 4 || memcmp(t + at, "path", 4) != 0)
        return 0;
    return at + 4 == len || amp_lex_is_space(t[at + 4]) || t[at + 4] == '\n' || t[at + 4] == '#';
}

/* The start of the first line after @p from that is a path header (len: none). */
static size_t next_header(const char *t, size_t len, size_t from)
{
    while (from < len) {
        const char *nl = memchr(t + from, '\n', len - from);
        if (!nl)
            return len;
        from = (size_t)(nl - t) + 1;
        if (path_token(t, from, len))
            return from;
    }
    return len;
}

/* The paths and vertices chunk [b, e) announces (its headers' counts); 0 when a header cannot be read. */
static int count_chunk(const char *t, size_t b, size_t e, size_t *np, size_t *nv)
{
    amp_lex lx;
    size_t pos = b;
    *np = *nv = 0;
    amp_lex_init(&lx, t, e, 1);
    while (pos < e) {
        const char *nl = memchr(t + pos, '\n', e - pos);
        size_t end = nl ? (size_t)(nl - t) : e, cut;
        const char *hash;
        long n;
        if (path_token(t, pos, end)) {
            hash = memchr(t + pos, '#', end - pos);
            cut = hash ? (size_t)(hash - t) : end;
            if (cut - pos > AMP_LEX_MAX_LINE || amp_lex_split(&lx, t + pos, cut - pos, NULL) <= 0 ||
                !amp_lex_is(&lx, 0, "path") || amp_lex_long(&lx, 2, 0, (long)AMP_PATH_MAX_VERTS, &n, NULL) != AMP_OK)
                return 0;
            (*np)++;
            *nv += (size_t)n;
        }
        pos = end + 1;
    }
    return 1;
}

/* No allocation: a chunk's view of the set has exactly the room it counted. */
static void *no_alloc(void *user, size_t size)
{
    (void)user;
    (void)size;
    return NULL;
}

static void *no_realloc(void *user, void *ptr, size_t size)
{
    (void)user;
    (void)ptr;
    (void)size;
    return NULL;
}

static void no_free(void *user, void *ptr)
{
    (void)user;
    (void)ptr;
}

static const amp_allocator none = {no_alloc, no_realloc, no_free, NULL};

typedef struct chunk {
    size_t b, e;   /* bytes of the text */
    size_t np, nv; /* paths and vertices it announces */
    size_t p0, v0; /* where they go in the set */
    int ok;
} chunk;

/* Chunk c parsed into its place: clean when it fills exactly the room it counted and ends with its last path. */
static void parse_chunk(amp_pathset *ps, const char *text, chunk *c)
{
    amp_pathset view;
    amp_lex lx;
    long remaining = 0;
    size_t k;
    amp_pathset_init(&view, &none);
    view.paths = ps->paths + c->p0;
    view.cap_paths = c->np;
    view.verts = ps->verts + c->v0;
    view.cap_verts = c->nv;
    amp_lex_init(&lx, text + c->b, c->e - c->b, 1);
    c->ok = parse_body(&view, &lx, &remaining, NULL) == AMP_OK && remaining == 0 && view.npaths == c->np &&
            view.nverts == c->nv;
    for (k = 0; c->ok && k < view.npaths; k++)
        view.paths[k].first += c->v0;
}

/* Chunk bounds after the header (which ends at @p body): about equal, each beginning at a path header. */
static size_t split_chunks(const char *text, size_t len, size_t body, size_t nchunks, chunk *c)
{
    size_t n = 0, j;
    for (j = 0; j < nchunks; j++) {
        size_t b = j == 0 ? body : next_header(text, len, body + (len - body) / nchunks * j);
        if (b >= len || (n > 0 && b <= c[n - 1].b))
            continue;
        c[n].b = b;
        n++;
    }
    for (j = 0; j < n; j++)
        c[j].e = j + 1 < n ? c[j + 1].b : len;
    return n;
}

/* The chunks read in their places; 0 (and the set as it was) when one is not clean or the room is missing.
 * @p pg (may be NULL) hears of the chunks done, from the calling thread. */
static int parse_chunked(amp_pathset *ps, const char *text, chunk *c, size_t n, const amp_parse_progress *pg)
{
    size_t np0 = ps->npaths, nv0 = ps->nverts, np = np0, nv = nv0, j, done = 0;
    long k;
    int ok = 1;
    void *p = ps->paths, *v = ps->verts;
    for (j = 0; j < n; j++) {
        c[j].p0 = np;
        c[j].v0 = nv;
        np += c[j].np;
        nv += c[j].nv;
    }
    if (amp_grow(ps->alloc, &p, &ps->cap_paths, np, sizeof *ps->paths) != AMP_OK)
        return 0;
    ps->paths = p;
    if (amp_grow(ps->alloc, &v, &ps->cap_verts, nv, sizeof *ps->verts) != AMP_OK)
        return 0;
    ps->verts = v;
#pragma omp parallel for schedule(dynamic, 1)
    for (k = 0; k < (long)n; k++) {
        parse_chunk(ps, text, &c[k]);
        if (pg && pg->fn) {
            size_t d;
#pragma omp atomic capture
            d = ++done;
#ifdef _OPENMP
            if (omp_get_thread_num() == 0 && d < n)
#else
            if (d < n)
#endif
                pg->fn(pg->user, (double)d / (double)n);
        }
    }
    if (pg && pg->fn)
        pg->fn(pg->user, 1.0); /* the last chunk may end on another thread */
    for (j = 0; j < n; j++)
        ok = ok && c[j].ok;
    ps->npaths = ok ? np : np0;
    ps->nverts = ok ? nv : nv0;
    return ok;
}

amp_status amp_pathset_parse_chunks(amp_pathset *ps, const char *text, size_t len, size_t nchunks, size_t *used,
                                    amp_error *err)
{
    return amp_pathset_parse_chunks_progress(ps, text, len, nchunks, used, NULL, err);
}

amp_status amp_pathset_parse_chunks_progress(amp_pathset *ps, const char *text, size_t len, size_t nchunks,
                                             size_t *used, const amp_parse_progress *pg, amp_error *err)
{
    chunk c[CHUNKS_MAX];
    amp_lex lx;
    size_t n, j;
    int ok = 1;
    if (used)
        *used = 1;
    if (!text && len)
        return amp_fail(err, AMP_ERR_ARG, 0, "NULL text");
    if (nchunks > CHUNKS_MAX)
        nchunks = CHUNKS_MAX;
    amp_lex_init(&lx, text, len, 1);
    if (nchunks < 2 || file_header(&lx, NULL) != AMP_OK)
        return parse_one_piece(ps, text, len, err);
    n = split_chunks(text, len, lx.pos, nchunks, c);
    for (j = 0; j < n && ok; j++)
        ok = count_chunk(text, c[j].b, c[j].e, &c[j].np, &c[j].nv);
    if (n < 2 || !ok || !parse_chunked(ps, text, c, n, pg))
        return parse_one_piece(ps, text, len, err);
    if (used)
        *used = n;
    return AMP_OK;
}

amp_status amp_pathset_parse(amp_pathset *ps, const char *text, size_t len, amp_error *err)
{
    size_t n = len / CHUNK_MIN_BYTES;
    if (!ps || (!text && len))
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_pathset_parse: NULL argument");
#ifdef _OPENMP
    if (n > (size_t)omp_get_max_threads())
        n = (size_t)omp_get_max_threads();
#else
    n = 1; /* one thread: the chunks would only add their counting */
#endif
    return amp_pathset_parse_chunks(ps, text, len, n, NULL, err);
}

amp_status amp_pathset_parse_progress(amp_pathset *ps, const char *text, size_t len,
                                      void (*progress)(void *user, double fraction), void *user, amp_error *err)
{
    amp_parse_progress pg;
    amp_status st;
    size_t n = len / CHUNK_MIN_BYTES, used = 1;
    if (!progress)
        return amp_pathset_parse(ps, text, len, err);
    /* chunks of a megabyte or more, up to CHUNKS_MAX, on any thread count: the report counts them (one
     * thread pays for their counting, about a tenth of the read) */
    pg.fn = progress;
    pg.user = user;
    st = amp_pathset_parse_chunks_progress(ps, text, len, n > CHUNKS_MAX ? CHUNKS_MAX : n, &used, &pg, err);
    if (st == AMP_OK && used == 1)
        progress(user, 1.0); /* read in one piece */
    return st;
}
