/* Print paths in memory and the `.amp` text format (docs/interfaces.md §3). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ampath/paths.h"
#include "numtext.h"

void amp_pathset_init(amp_pathset *ps, const amp_allocator *a)
{
    memset(ps, 0, sizeof *ps);
    ps->alloc = a;
}

void amp_pathset_free(amp_pathset *ps)
{
    if (!ps)
        return;
    amp_free(ps->alloc, ps->paths);
    amp_free(ps->alloc, ps->verts);
    amp_pathset_init(ps, ps->alloc);
}

void amp_pathset_clear(amp_pathset *ps)
{
    ps->npaths = 0;
    ps->nverts = 0;
}

amp_status amp_pathset_begin(amp_pathset *ps, amp_role role, amp_error *err)
{
    void *p;
    if (!ps)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_pathset_begin: NULL path set");
    p = ps->paths;
    if (role != AMP_ROLE_OBJECT && role != AMP_ROLE_SUPPORT)
        return amp_fail(err, AMP_ERR_ARG, 0, "unknown path role %d", (int)role);
    if (amp_grow(ps->alloc, &p, &ps->cap_paths, ps->npaths + 1, sizeof *ps->paths) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for paths");
    ps->paths = p;
    ps->paths[ps->npaths].role = role;
    ps->paths[ps->npaths].first = ps->nverts;
    ps->paths[ps->npaths].n = 0;
    ps->paths[ps->npaths].h = 0.0;
    ps->npaths++;
    return AMP_OK;
}

amp_status amp_pathset_set_height(amp_pathset *ps, double h, amp_error *err)
{
    if (ps->npaths == 0)
        return amp_fail(err, AMP_ERR_STATE, 0, "amp_pathset_set_height: no path begun");
    if (!isfinite(h) || h < 0.0)
        return amp_fail(err, AMP_ERR_ARG, 0, "bead height %g is negative or not finite", h);
    ps->paths[ps->npaths - 1].h = h;
    return AMP_OK;
}

amp_status amp_pathset_push(amp_pathset *ps, amp_vec3 p, double r, amp_error *err)
{
    void *v = ps->verts;
    if (ps->npaths == 0)
        return amp_fail(err, AMP_ERR_STATE, 0, "amp_pathset_push: no path begun");
    if (!amp_v3_finite(p) || !isfinite(r) || r < 0.0)
        return amp_fail(err, AMP_ERR_ARG, 0, "vertex (%g %g %g) radius %g is not finite or radius negative", p.x, p.y,
                        p.z, r);
    if (amp_grow(ps->alloc, &v, &ps->cap_verts, ps->nverts + 1, sizeof *ps->verts) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for path vertices");
    ps->verts = v;
    ps->verts[ps->nverts].p = p;
    ps->verts[ps->nverts].r = r;
    ps->nverts++;
    ps->paths[ps->npaths - 1].n++;
    return AMP_OK;
}

amp_status amp_pathset_push_merged(amp_pathset *ps, amp_vec3 p, double r, double tol, int last, amp_error *err)
{
    amp_pvert *q;
    if (ps->npaths == 0 || ps->paths[ps->npaths - 1].n < 1 || !amp_v3_finite(p) || !isfinite(r) || r < 0.0)
        return amp_pathset_push(ps, p, r, err); /* its errors, or a path's first vertex */
    q = &ps->verts[ps->nverts - 1];
    if (!(amp_v3_dist2(q->p, p) <= tol * tol))
        return amp_pathset_push(ps, p, r, err);
    /* the first vertex keeps its place: a path starts exactly where it was cut too */
    if (last && ps->paths[ps->npaths - 1].n > 1)
        q->p = p;
    q->r = amp_dmin(q->r, r);
    return AMP_OK;
}

amp_status amp_pathset_add(amp_pathset *ps, amp_role role, const amp_pvert *v, size_t n, amp_error *err)
{
    size_t i, np = ps->npaths, nv = ps->nverts;
    amp_status st = amp_pathset_begin(ps, role, err);
    for (i = 0; st == AMP_OK && i < n; i++)
        st = amp_pathset_push(ps, v[i].p, v[i].r, err);
    if (st != AMP_OK) {
        ps->npaths = np;
        ps->nverts = nv;
    }
    return st;
}

amp_status amp_pathset_copy_path(amp_pathset *dst, const amp_pathset *src, size_t i, amp_error *err)
{
    amp_status st = amp_pathset_add(dst, src->paths[i].role, amp_pathset_path_verts(src, i), src->paths[i].n, err);
    if (st == AMP_OK)
        dst->paths[dst->npaths - 1].h = src->paths[i].h;
    return st;
}

amp_status amp_pathset_append(amp_pathset *dst, const amp_pathset *src, amp_error *err)
{
    size_t i;
    amp_status st = AMP_OK;
    for (i = 0; i < src->npaths && st == AMP_OK; i++)
        st = amp_pathset_copy_path(dst, src, i, err);
    return st;
}

double amp_path_length(const amp_pathset *ps, size_t i)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    double len = 0.0;
    size_t k;
    for (k = 1; k < ps->paths[i].n; k++)
        len += amp_v3_dist(v[k - 1].p, v[k].p);
    return len;
}

double amp_pathset_length(const amp_pathset *ps, int role)
{
    double len = 0.0;
    size_t i;
    for (i = 0; i < ps->npaths; i++)
        if (role < 0 || (int)ps->paths[i].role == role)
            len += amp_path_length(ps, i);
    return len;
}

double amp_bead_area(double r, double h)
{
    double w = 2.0 * r;
    /* docs/interfaces.md §5: a slicer's rounded rectangle; narrower than high it is a tube */
    if (h > 0.0 && w >= h)
        return (w - h) * h + AMP_PI * 0.25 * h * h;
    return AMP_PI * r * r;
}

double amp_pathset_volume(const amp_pathset *ps, int role)
{
    double vol = 0.0;
    size_t i, k;
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        if (role >= 0 && (int)ps->paths[i].role != role)
            continue;
        for (k = 1; k < ps->paths[i].n; k++) {
            double r = 0.5 * (v[k - 1].r + v[k].r);
            vol += amp_bead_area(r, ps->paths[i].h) * amp_v3_dist(v[k - 1].p, v[k].p);
        }
    }
    return vol;
}

amp_box3 amp_pathset_bbox(const amp_pathset *ps)
{
    amp_box3 b = amp_box3_empty();
    size_t i;
    for (i = 0; i < ps->nverts; i++)
        b = amp_box3_add(b, ps->verts[i].p);
    return b;
}

amp_status amp_pathset_read_file(amp_pathset *ps, const char *path, amp_error *err)
{
    return amp_pathset_read_file_progress(ps, path, NULL, NULL, err);
}

amp_status amp_pathset_read_file_progress(amp_pathset *ps, const char *path,
                                          void (*progress)(void *user, double fraction), void *user,
                                          amp_error *err)
{
    char *text;
    size_t len;
    amp_status st = amp_read_file(path, ps->alloc, AMP_PATHS_READ_MAX, &text, &len, err);
    if (st != AMP_OK)
        return st;
    st = amp_pathset_parse_progress(ps, text, len, progress, user, err);
    amp_free(ps->alloc, text);
    if (st != AMP_OK && err) {
        char msg[AMP_ERROR_MSG_SIZE];
        memcpy(msg, err->msg, sizeof msg);
        snprintf(err->msg, sizeof err->msg, "%s: %.*s", path, (int)(sizeof msg - 64), msg);
    }
    return st;
}

static amp_status write_comment(const char *comment, amp_sink_fn sink, void *user)
{
    while (comment && *comment) {
        const char *nl = strchr(comment, '\n');
        size_t n = nl ? (size_t)(nl - comment) : strlen(comment);
        amp_status st = sink(user, "# ", 2);
        if (st == AMP_OK)
            st = sink(user, comment, n);
        if (st == AMP_OK)
            st = sink(user, "\n", 1);
        if (st != AMP_OK)
            return st;
        comment += n + (nl ? 1 : 0);
    }
    return AMP_OK;
}

/* longest line of a path header and of a vertex */
#define HEAD_MAX 64
#define VERT_MAX (4 * AMP_G10_MAX + 1)
/* vertices formatted per block; blocks formatted at once (on the OpenMP threads) before they are written */
#define WBLOCK 4096
#define WBLOCKS 4

/* Where a block of the output starts: path @p i, its vertex @p k; @p nv vertices and @p nh headers in it. */
typedef struct wblock {
    size_t i, k, nv, nh, len;
    char *buf;
} wblock;

static size_t format_head(const amp_pathset *ps, size_t i, char *out)
{
    const char *role = ps->paths[i].role == AMP_ROLE_SUPPORT ? "support" : "object";
    int n = ps->paths[i].h > 0.0 ? snprintf(out, HEAD_MAX, "path %s %lu %.10g\n", role, (unsigned long)ps->paths[i].n,
                                            ps->paths[i].h)
                                 : snprintf(out, HEAD_MAX, "path %s %lu\n", role, (unsigned long)ps->paths[i].n);
    return n > 0 ? (size_t)n : 0;
}

/* The text of the last number written in a column (z and r repeat along a path: a layer's height, a bead's
 * radius), so that a repeat is copied instead of formatted again. */
typedef struct g10_memo {
    double v;
    size_t n; /* 0: none yet */
    char s[AMP_G10_MAX];
} g10_memo;

static size_t format_memo(double v, g10_memo *m, char *out)
{
    /* the same bits, the same text (a -0 and a 0 differ in bits: each keeps its own) */
    if (m->n == 0 || memcmp(&m->v, &v, sizeof v) != 0) {
        m->n = amp_g10_format(v, m->s);
        m->v = v;
    }
    memcpy(out, m->s, m->n);
    return m->n;
}

/* "%.10g %.10g %.10g %.10g\n", without printf's cost on the hot path */
static size_t format_vert(const amp_pvert *v, char *line, g10_memo *mz, g10_memo *mr)
{
    size_t n = amp_g10_format(v->p.x, line);
    line[n++] = ' ';
    n += amp_g10_format(v->p.y, line + n);
    line[n++] = ' ';
    n += format_memo(v->p.z, mz, line + n);
    line[n++] = ' ';
    n += format_memo(v->r, mr, line + n);
    line[n++] = '\n';
    return n;
}

/* The text of block @p b: from vertex k of path i on, nv vertices, with the headers of the paths it starts
 * (paths without vertices included); the last block also heads the empty paths after its last vertex. */
static void format_block(const amp_pathset *ps, wblock *b, int last)
{
    size_t i = b->i, k = b->k, left = b->nv, len = 0;
    g10_memo mz, mr;
    mz.n = mr.n = 0;
    while (i < ps->npaths && (left > 0 || (last && k == 0))) {
        if (k == 0)
            len += format_head(ps, i, b->buf + len);
        if (k >= ps->paths[i].n) {
            i++;
            k = 0;
            continue;
        }
        len += format_vert(amp_pathset_path_verts(ps, i) + k, b->buf + len, &mz, &mr);
        left--;
        if (++k == ps->paths[i].n) {
            i++;
            k = 0;
        }
    }
    b->len = len;
}

/* Plan the next block from (*i, *k): at most WBLOCK vertices; advances (*i, *k) past it. */
static void plan_block(const amp_pathset *ps, size_t *i, size_t *k, wblock *b)
{
    b->i = *i;
    b->k = *k;
    b->nv = b->nh = 0;
    while (*i < ps->npaths && b->nv < WBLOCK) {
        size_t take = ps->paths[*i].n - *k;
        if (*k == 0)
            b->nh++;
        if (take > WBLOCK - b->nv)
            take = WBLOCK - b->nv;
        b->nv += take;
        *k += take;
        if (*k >= ps->paths[*i].n) {
            (*i)++;
            *k = 0;
        }
    }
    if (*i >= ps->npaths) /* the empty paths at the end come with this block */
        b->nh += ps->npaths - b->i;
}

amp_status amp_pathset_write(const amp_pathset *ps, const char *comment, amp_sink_fn sink, void *user, amp_error *err)
{
    wblock b[WBLOCKS];
    size_t i = 0, k = 0, nb, q, cap[WBLOCKS];
    amp_status st;
    if (!ps || !sink)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_pathset_write: NULL argument");
    st = sink(user, "ampath-paths 1\n", 15);
    memset(b, 0, sizeof b);
    memset(cap, 0, sizeof cap);
    if (st == AMP_OK)
        st = write_comment(comment, sink, user);
    while (st == AMP_OK && i < ps->npaths) {
        long t;
        /* plan and size up to WBLOCKS blocks (buffers through the set's allocator, on this thread) */
        for (nb = 0; nb < WBLOCKS && i < ps->npaths; nb++) {
            void *v = b[nb].buf;
            plan_block(ps, &i, &k, &b[nb]);
            if (amp_grow(ps->alloc, &v, &cap[nb], b[nb].nv * VERT_MAX + b[nb].nh * HEAD_MAX + 1, 1) != AMP_OK) {
                st = AMP_ERR_NOMEM;
                break;
            }
            b[nb].buf = v;
        }
        if (st != AMP_OK)
            break;
        /* formatting only reads the set and writes its own block: the text is the same on any thread count */
#pragma omp parallel for schedule(dynamic, 1) if (nb > 1)
        for (t = 0; t < (long)nb; t++)
            format_block(ps, &b[t], i >= ps->npaths && t == (long)nb - 1);
        for (q = 0; q < nb && st == AMP_OK; q++)
            st = sink(user, b[q].buf, b[q].len);
    }
    for (q = 0; q < WBLOCKS; q++)
        amp_free(ps->alloc, b[q].buf);
    if (st != AMP_OK)
        return amp_fail(err, st, 0, "writing paths failed: %s", amp_strerror(st));
    return AMP_OK;
}

typedef struct paths_file_ctx {
    const amp_pathset *ps;
    const char *comment;
} paths_file_ctx;

static amp_status paths_file_writer(void *vctx, amp_sink_fn sink, void *user, amp_error *err)
{
    const paths_file_ctx *c = vctx;
    return amp_pathset_write(c->ps, c->comment, sink, user, err);
}

amp_status amp_pathset_write_file(const amp_pathset *ps, const char *path, const char *comment, amp_error *err)
{
    paths_file_ctx c;
    c.ps = ps;
    c.comment = comment;
    return amp_write_file_atomic(path, paths_file_writer, &c, err);
}
