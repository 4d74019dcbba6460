/*
 * STL reader and writer, exact and tolerance vertex welding.
 *
 * STL stores every triangle with its own three corners, so a reader must weld
 * them back into a shared-vertex mesh before anything topological (closedness,
 * BVH inside tests, the clipping of field covers) can work. Exact welding uses an
 * open-addressing hash over the coordinate bit patterns; tolerance welding a
 * uniform grid.
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ampath/mesh.h"
#include "keysort.h"
#include "lex.h"
#include "mesh_internal.h"

/* ---------------------------------------------------------------- hashing */

/* Exact-position table: slots hold vertex indices into m->verts (WELD_EMPTY = free). */
static uint64_t mix64(uint64_t h)
{
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return h;
}

static uint64_t dbits(double d)
{
    uint64_t u;
    d += 0.0; /* -0 becomes +0 so that both weld together */
    memcpy(&u, &d, sizeof u);
    return u;
}

static uint64_t hash_point(amp_vec3 p)
{
    return mix64(dbits(p.x) ^ mix64(dbits(p.y) ^ mix64(dbits(p.z))));
}

static int same_point(amp_vec3 a, amp_vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

#define WELD_EMPTY 0xffffffffu

static amp_status weld_resize(amp_weld_table *t, const amp_mesh *m, size_t cap)
{
    uint32_t *s = amp_calloc(t->alloc, cap, sizeof *s);
    size_t i;
    if (!s)
        return AMP_ERR_NOMEM;
    memset(s, 0xff, cap * sizeof *s);
    for (i = 0; i < t->cap; i++) {
        uint32_t v = t->slot[i];
        size_t h;
        if (v == WELD_EMPTY)
            continue;
        h = (size_t)hash_point(m->verts[v]) & (cap - 1);
        while (s[h] != WELD_EMPTY)
            h = (h + 1) & (cap - 1);
        s[h] = v;
    }
    amp_free(t->alloc, t->slot);
    t->slot = s;
    t->cap = cap;
    return AMP_OK;
}

void amp_weld_init(amp_weld_table *t, const amp_allocator *a)
{
    memset(t, 0, sizeof *t);
    t->alloc = a;
}

void amp_weld_free(amp_weld_table *t)
{
    amp_free(t->alloc, t->slot);
    amp_weld_init(t, t->alloc);
}

amp_status amp_weld_vertex(amp_weld_table *t, amp_mesh *m, amp_vec3 p, uint32_t *out, amp_error *err)
{
    size_t h;
    amp_status st;
    if ((t->used + 1) * 2 > t->cap && weld_resize(t, m, t->cap ? t->cap * 2 : 1024) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the vertex weld table");
    h = (size_t)hash_point(p) & (t->cap - 1);
    while (t->slot[h] != WELD_EMPTY) {
        if (same_point(m->verts[t->slot[h]], p)) {
            *out = t->slot[h];
            return AMP_OK;
        }
        h = (h + 1) & (t->cap - 1);
    }
    st = amp_mesh_add_vertex(m, p, out, err);
    if (st != AMP_OK)
        return st;
    t->slot[h] = *out;
    t->used++;
    return AMP_OK;
}

/* ------------------------------------------------------------- the reader */

typedef struct stl_reader {
    amp_mesh *m;
    amp_weld_table wt;
    size_t triangles, degenerate;
} stl_reader;

/*
 * Zero area: two equal corners, or |(b-a)x(c-a)| tiny against the longest
 * edge squared (collinear up to rounding). Such triangles carry no surface
 * and would give undefined normals to the BVH and the winding number.
 */
static int tri_degenerate(amp_vec3 a, amp_vec3 b, amp_vec3 c)
{
    amp_vec3 ab = amp_v3_sub(b, a), ac = amp_v3_sub(c, a), bc = amp_v3_sub(c, b);
    double l = fmax(amp_v3_len2(ab), fmax(amp_v3_len2(ac), amp_v3_len2(bc)));
    if (same_point(a, b) || same_point(b, c) || same_point(a, c))
        return 1;
    return amp_v3_len(amp_v3_cross(ab, ac)) <= 1e-12 * l;
}

static amp_status add_triangle(stl_reader *r, const amp_vec3 *p, amp_error *err)
{
    uint32_t idx[3];
    int k;
    amp_status st;
    r->triangles++;
    if (tri_degenerate(p[0], p[1], p[2])) {
        r->degenerate++;
        return AMP_OK;
    }
    for (k = 0; k < 3; k++)
        if ((st = amp_weld_vertex(&r->wt, r->m, p[k], &idx[k], err)) != AMP_OK)
            return st;
    return amp_mesh_add_tri(r->m, idx[0], idx[1], idx[2], err);
}

static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static float lef(const unsigned char *b)
{
    uint32_t u = le32(b);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static amp_status read_binary(stl_reader *r, const unsigned char *d, size_t len, amp_error *err)
{
    uint32_t n, i;
    if (len < 84)
        return amp_fail_at(err, AMP_ERR_PARSE, (long)len, "binary STL truncated: %lu bytes, header needs 84",
                           (unsigned long)len);
    n = le32(d + 80);
    if (n == 0)
        return amp_fail_at(err, AMP_ERR_PARSE, 80, "STL holds no triangles");
    /* compare in 64 bits: 84 + 50 n overflows a 32-bit size_t */
    if ((uint64_t)len < 84 + 50 * (uint64_t)n)
        return amp_fail_at(err, AMP_ERR_PARSE, 80,
                           "binary STL announces %lu triangles (%.0f bytes) but the file has %lu bytes", (unsigned long)n,
                           84.0 + 50.0 * n, (unsigned long)len);
    for (i = 0; i < n; i++) {
        const unsigned char *t = d + 84 + 50 * (size_t)i;
        amp_vec3 p[3];
        int k, c;
        amp_status st;
        for (k = 0; k < 3; k++) {
            double c3[3];
            for (c = 0; c < 3; c++) {
                float f = lef(t + 12 + 12 * k + 4 * c);
                if (!isfinite(f))
                    return amp_fail_at(err, AMP_ERR_PARSE, (long)(t + 12 + 12 * k + 4 * c - d),
                                       "triangle %lu: vertex coordinate is not finite", (unsigned long)i + 1);
                c3[c] = f;
            }
            p[k] = amp_v3(c3[0], c3[1], c3[2]);
        }
        if ((st = add_triangle(r, p, err)) != AMP_OK) {
            if (err)
                err->offset = (long)(t - d);
            return st;
        }
    }
    return AMP_OK;
}

/* Case-insensitive keyword test: exporters write "SOLID", "Facet", ... */
static int kw(const amp_lex *lx, int i, const char *s)
{
    size_t n = strlen(s), k;
    if (i >= lx->ntok || lx->toklen[i] != n)
        return 0;
    for (k = 0; k < n; k++) {
        char c = lx->tok[i][k];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != s[k])
            return 0;
    }
    return 1;
}

/* Next line must be exactly the keywords @p a [@p b]. */
static amp_status expect(amp_lex *lx, const char *a, const char *b, amp_error *err)
{
    int rc = amp_lex_next(lx, err);
    if (rc < 0)
        return (amp_status)rc;
    if (rc == 0)
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: file ends where '%s%s%s' was expected", lx->line, a,
                        b ? " " : "", b ? b : "");
    if (!kw(lx, 0, a) || (b && !kw(lx, 1, b)) || lx->ntok != (b ? 2 : 1))
        return amp_fail(err, AMP_ERR_PARSE, lx->line, "line %ld: expected '%s%s%s'", lx->line, a, b ? " " : "",
                        b ? b : "");
    return AMP_OK;
}

static amp_status read_ascii(stl_reader *r, const char *text, size_t len, amp_error *err)
{
    amp_lex lx;
    int rc, in_solid = 0;
    amp_status st;
    amp_lex_init(&lx, text, len, 0);
    while ((rc = amp_lex_next(&lx, err)) > 0) {
        amp_vec3 p[3];
        int k;
        if (!in_solid) {
            if (!kw(&lx, 0, "solid"))
                return amp_fail(err, AMP_ERR_PARSE, lx.line, "line %ld: expected 'solid'", lx.line);
            in_solid = 1;
            continue;
        }
        if (kw(&lx, 0, "endsolid")) {
            in_solid = 0;
            continue;
        }
        if (!kw(&lx, 0, "facet"))
            return amp_fail(err, AMP_ERR_PARSE, lx.line, "line %ld: expected 'facet' or 'endsolid'", lx.line);
        /* "facet normal nx ny nz": the normal is ignored but must be well-formed text */
        if (lx.ntok != 5 || !kw(&lx, 1, "normal"))
            return amp_fail(err, AMP_ERR_PARSE, lx.line, "line %ld: expected 'facet normal nx ny nz'", lx.line);
        if ((st = expect(&lx, "outer", "loop", err)) != AMP_OK)
            return st;
        for (k = 0; k < 3; k++) {
            double c[3];
            int i;
            rc = amp_lex_next(&lx, err);
            if (rc < 0)
                return (amp_status)rc;
            if (rc == 0)
                return amp_fail(err, AMP_ERR_PARSE, lx.line, "line %ld: file ends inside a facet", lx.line);
            if (!kw(&lx, 0, "vertex") || lx.ntok != 4)
                return amp_fail(err, AMP_ERR_PARSE, lx.line, "line %ld: expected 'vertex x y z'", lx.line);
            for (i = 0; i < 3; i++)
                if ((st = amp_lex_double(&lx, i + 1, &c[i], err)) != AMP_OK)
                    return st;
            p[k] = amp_v3(c[0], c[1], c[2]);
        }
        if ((st = expect(&lx, "endloop", NULL, err)) != AMP_OK || (st = expect(&lx, "endfacet", NULL, err)) != AMP_OK)
            return st;
        if ((st = add_triangle(r, p, err)) != AMP_OK) {
            if (err)
                err->line = lx.line;
            return st;
        }
    }
    if (rc < 0)
        return (amp_status)rc;
    if (in_solid)
        return amp_fail(err, AMP_ERR_PARSE, lx.line, "line %ld: file ends without 'endsolid'", lx.line);
    if (r->triangles == 0)
        return amp_fail(err, AMP_ERR_PARSE, lx.line, "STL holds no triangles");
    return AMP_OK;
}

/* ------------------------------------------------------- duplicate facets */

/*
 * A mesh exported twice into one file, or two solids sharing a face, gives
 * triangles with the same three welded corners. Copies in one orientation
 * make every edge non-manifold; a face and its reverse are a zero-thickness
 * double wall that encloses nothing. Either way the slicer sees no solid, so
 * after welding a copy is dropped, and a face met in both orientations is
 * dropped entirely. Identity is the sorted corner triple; the parity of the
 * sort tells the orientation (a rotation is an even permutation, a reversal
 * an odd one).
 */
typedef struct tri_key {
    uint32_t v[3]; /* corners, ascending */
    uint32_t odd;  /* 1: the stored order is an odd permutation of v */
    size_t idx;    /* triangle index from the first triangle of this read */
} tri_key;

static void key_swap(uint32_t *a, uint32_t *b, uint32_t *odd)
{
    uint32_t t = *a;
    *a = *b;
    *b = t;
    *odd ^= 1u;
}

static tri_key tri_key_of(const amp_tri *t, size_t idx)
{
    tri_key k;
    k.v[0] = t->v[0];
    k.v[1] = t->v[1];
    k.v[2] = t->v[2];
    k.odd = 0;
    k.idx = idx;
    /* three compare-swaps sort a triple; each swap is a transposition */
    if (k.v[0] > k.v[1])
        key_swap(&k.v[0], &k.v[1], &k.odd);
    if (k.v[1] > k.v[2])
        key_swap(&k.v[1], &k.v[2], &k.odd);
    if (k.v[0] > k.v[1])
        key_swap(&k.v[0], &k.v[1], &k.odd);
    return k;
}

/* The sort's fields, most significant first (amp_radix_sort; cmp_tri_key is its fallback). */
static const size_t tri_key_fields[3] = {offsetof(tri_key, v[0]), offsetof(tri_key, v[1]), offsetof(tri_key, v[2])};

/* Corners, then file order: qsort is not stable, and the copy kept must be the first one. */
static int cmp_tri_key(const void *pa, const void *pb)
{
    const tri_key *a = pa, *b = pb;
    int i;
    for (i = 0; i < 3; i++)
        if (a->v[i] != b->v[i])
            return a->v[i] < b->v[i] ? -1 : 1;
    return a->idx < b->idx ? -1 : a->idx > b->idx;
}

/*
 * Mark the triangles to drop in the sorted @p k (first corner set to
 * WELD_EMPTY, which no vertex index reaches): all but the first of a group
 * in one orientation, the whole group when both orientations occur (the two
 * solids it separates merge). Returns the number marked; *cancelled says
 * whether a whole group went (its corners may now be unused).
 */
static size_t mark_duplicates(amp_tri *tris, const tri_key *k, size_t n, int *cancelled)
{
    size_t i = 0, j, dropped = 0;
    while (i < n) {
        int both = 0;
        for (j = i + 1; j < n && memcmp(k[j].v, k[i].v, sizeof k[i].v) == 0; j++)
            both |= k[j].odd != k[i].odd;
        if (j - i > 1) {
            size_t q;
            for (q = both ? i : i + 1; q < j; q++)
                tris[k[q].idx].v[0] = WELD_EMPTY;
            dropped += both ? j - i : j - i - 1;
            *cancelled |= both;
        }
        i = j;
    }
    return dropped;
}

/* Drop the vertices from @p nv0 on that no triangle from @p nt0 on uses, keeping their order. */
static amp_status drop_unused_vertices(amp_mesh *m, size_t nv0, size_t nt0, amp_error *err)
{
    size_t n = m->nverts - nv0, i, nv = 0;
    uint32_t *map = amp_alloc(m->alloc, n * sizeof *map);
    int c;
    if (!map)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for dropping duplicate STL triangles");
    memset(map, 0xff, n * sizeof *map);
    for (i = nt0; i < m->ntris; i++)
        for (c = 0; c < 3; c++)
            map[m->tris[i].v[c] - nv0] = 0;
    for (i = 0; i < n; i++)
        if (map[i] != WELD_EMPTY) {
            map[i] = (uint32_t)(nv0 + nv);
            m->verts[nv0 + nv++] = m->verts[nv0 + i];
        }
    for (i = nt0; i < m->ntris; i++)
        for (c = 0; c < 3; c++)
            m->tris[i].v[c] = map[m->tris[i].v[c] - nv0];
    m->nverts = nv0 + nv;
    amp_free(m->alloc, map);
    return AMP_OK;
}

/*
 * Drop duplicate and cancelling triangles among those this read appended
 * (from @p nt0 and @p nv0 on: the weld table was fresh, so they share no
 * vertex with earlier content). The kept triangles keep their file order, so
 * a file without duplicates reads exactly as before. O(n log n).
 */
static amp_status drop_duplicates(amp_mesh *m, size_t nv0, size_t nt0, size_t *dropped, amp_error *err)
{
    size_t n = m->ntris - nt0, i, nt = nt0;
    tri_key *k;
    int cancelled = 0;
    *dropped = 0;
    if (n < 2)
        return AMP_OK;
    if (!(k = amp_alloc(m->alloc, n * sizeof *k)))
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for finding duplicate STL triangles");
    for (i = 0; i < n; i++)
        k[i] = tri_key_of(&m->tris[nt0 + i], i);
    /* stable: equal corner sets stay in file order, as cmp_tri_key's index tie-break orders them */
    amp_radix_sort(m->alloc, k, n, sizeof *k, tri_key_fields, 3, cmp_tri_key);
    *dropped = mark_duplicates(m->tris + nt0, k, n, &cancelled);
    amp_free(m->alloc, k);
    if (*dropped == 0)
        return AMP_OK;
    for (i = nt0; i < m->ntris; i++)
        if (m->tris[i].v[0] != WELD_EMPTY)
            m->tris[nt++] = m->tris[i];
    m->ntris = nt;
    /* a cancelled face may have been the only user of a corner */
    return cancelled ? drop_unused_vertices(m, nv0, nt0, err) : AMP_OK;
}

/* "solid" after optional leading white space. */
static int starts_solid(const unsigned char *d, size_t len)
{
    size_t i = 0;
    while (i < len && (d[i] == ' ' || d[i] == '\t' || d[i] == '\r' || d[i] == '\n'))
        i++;
    return len - i >= 5 && (memcmp(d + i, "solid", 5) == 0 || memcmp(d + i, "SOLID", 5) == 0);
}

/*
 * Vertices less than 1e-9 of the part's diagonal apart are one vertex: the exact weld keeps two corners that an
 * ASCII exporter wrote as 0 and -5.66485e-16 (OpenSCAD's issue945e.stl), and the mesh stays open there. Far
 * below any printable feature (60 nm on a 60 mm part), and the triangles that collapse had no area to print.
 */
static amp_status weld_near(amp_mesh *m, size_t *merged, amp_error *err)
{
    amp_box3 b = amp_mesh_bbox(m);
    size_t nv = m->nverts;
    amp_status st;
    if (nv < 2)
        return AMP_OK;
    st = amp_mesh_weld(m, 1e-9 * amp_v3_len(amp_v3_sub(b.max, b.min)), err);
    *merged = nv - m->nverts;
    return st;
}

amp_status amp_mesh_read_stl_ex(amp_mesh *m, const void *data, size_t len, amp_stl_stats *stats, amp_error *err)
{
    const unsigned char *d = data;
    stl_reader r;
    size_t nv0, nt0, dups = 0, tj = 0, near = 0;
    int binary;
    amp_status st;
    if (!m || (!data && len))
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_read_stl: NULL argument");
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (len == 0)
        return amp_fail_at(err, AMP_ERR_PARSE, 0, "empty STL file");
    /* Sec. "solid" binary files: the exact size 84 + 50 n decides, not the first word. */
    binary = !starts_solid(d, len) || (len >= 84 && (uint64_t)len == 84 + 50 * (uint64_t)le32(d + 80));
    memset(&r, 0, sizeof r);
    r.m = m;
    amp_weld_init(&r.wt, m->alloc);
    nv0 = m->nverts;
    nt0 = m->ntris;
    st = binary ? read_binary(&r, d, len, err) : read_ascii(&r, (const char *)d, len, err);
    if (st == AMP_OK && nv0 == 0 && nt0 == 0) /* a fresh mesh: nothing of the caller's is welded */
        st = weld_near(m, &near, err);
    if (st == AMP_OK)
        st = drop_duplicates(m, nv0, nt0, &dups, err);
    if (st == AMP_OK) /* an exporter's T-junctions (lib/mesh_tjunction.c) */
        st = amp_mesh_split_tjunctions(m, nt0, &tj, err);
    if (st == AMP_OK && m->ntris == nt0)
        st = dups ? amp_fail(err, AMP_ERR_GEOMETRY, 0,
                             "no STL triangle is left: %lu have zero area, %lu are duplicates or cancelling opposite "
                             "faces",
                             (unsigned long)r.degenerate, (unsigned long)dups)
                  : amp_fail(err, AMP_ERR_GEOMETRY, 0, "all %lu STL triangles have zero area",
                             (unsigned long)r.triangles);
    amp_weld_free(&r.wt);
    if (st != AMP_OK) {
        m->nverts = nv0;
        m->ntris = nt0;
        return st;
    }
    if (stats) {
        stats->binary = binary;
        stats->triangles = r.triangles;
        stats->degenerate = r.degenerate;
        stats->duplicates = dups;
        stats->tjunctions = tj;
        stats->near_welded = near;
        stats->vertices = m->nverts - nv0;
    }
    return AMP_OK;
}

amp_status amp_mesh_read_stl(amp_mesh *m, const void *data, size_t len, amp_error *err)
{
    return amp_mesh_read_stl_ex(m, data, len, NULL, err);
}

amp_status amp_mesh_read_stl_file_ex(amp_mesh *m, const char *path, amp_stl_stats *stats, amp_error *err)
{
    char *data;
    size_t len;
    amp_status st;
    if (!m || !path)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_read_stl_file: NULL argument");
    st = amp_read_file(path, m->alloc, AMP_STL_MAX_FILE, &data, &len, err);
    if (st != AMP_OK)
        return st;
    st = amp_mesh_read_stl_ex(m, data, len, stats, err);
    amp_free(m->alloc, data);
    if (st != AMP_OK && err) {
        char msg[AMP_ERROR_MSG_SIZE];
        memcpy(msg, err->msg, sizeof msg);
        if (err->offset >= 0)
            snprintf(err->msg, sizeof err->msg, "%s: byte %ld: %.*s", path, err->offset, (int)(sizeof msg - 64), msg);
        else
            snprintf(err->msg, sizeof err->msg, "%s: %.*s", path, (int)(sizeof msg - 64), msg);
    }
    return st;
}

amp_status amp_mesh_read_stl_file(amp_mesh *m, const char *path, amp_error *err)
{
    return amp_mesh_read_stl_file_ex(m, path, NULL, err);
}

/* ------------------------------------------------------------- the writer */

static void put32(unsigned char *b, uint32_t u)
{
    b[0] = (unsigned char)u;
    b[1] = (unsigned char)(u >> 8);
    b[2] = (unsigned char)(u >> 16);
    b[3] = (unsigned char)(u >> 24);
}

static void putf(unsigned char *b, double d)
{
    float f = (float)d;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    put32(b, u);
}

static amp_vec3 tri_normal(const amp_mesh *m, size_t i)
{
    const amp_tri *t = &m->tris[i];
    amp_vec3 a = m->verts[t->v[0]], b = m->verts[t->v[1]], c = m->verts[t->v[2]];
    return amp_v3_normalize(amp_v3_cross(amp_v3_sub(b, a), amp_v3_sub(c, a)));
}

static amp_status write_binary(const amp_mesh *m, amp_sink_fn sink, void *user, amp_error *err)
{
    enum { BATCH = 64 };
    unsigned char buf[50 * BATCH];
    size_t i, nb = 0;
    amp_status st;
    if (m->ntris > 0xffffffffUL)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "binary STL holds at most 2^32-1 triangles");
    for (i = 0; i < m->nverts; i++) {
        amp_vec3 p = m->verts[i];
        if (fabs(p.x) > 3e38 || fabs(p.y) > 3e38 || fabs(p.z) > 3e38)
            return amp_fail(err, AMP_ERR_RANGE, 0, "vertex %lu does not fit a float", (unsigned long)i);
    }
    memset(buf, 0, 84);
    memcpy(buf, "ampath binary STL", 17);
    put32(buf + 80, (uint32_t)m->ntris);
    if ((st = sink(user, (const char *)buf, 84)) != AMP_OK)
        return amp_fail(err, st, 0, "writing the STL header failed");
    for (i = 0; i < m->ntris; i++) {
        unsigned char *t = buf + 50 * nb;
        amp_vec3 n = tri_normal(m, i);
        int k;
        putf(t, n.x);
        putf(t + 4, n.y);
        putf(t + 8, n.z);
        for (k = 0; k < 3; k++) {
            amp_vec3 p = m->verts[m->tris[i].v[k]];
            putf(t + 12 + 12 * k, p.x);
            putf(t + 16 + 12 * k, p.y);
            putf(t + 20 + 12 * k, p.z);
        }
        t[48] = t[49] = 0;
        if (++nb == BATCH || i + 1 == m->ntris) {
            if ((st = sink(user, (const char *)buf, 50 * nb)) != AMP_OK)
                return amp_fail(err, st, 0, "writing STL triangles failed");
            nb = 0;
        }
    }
    return AMP_OK;
}

static amp_status write_ascii(const amp_mesh *m, amp_sink_fn sink, void *user, amp_error *err)
{
    size_t i;
    amp_status st = amp_sinkf(sink, user, "solid ampath\n");
    for (i = 0; st == AMP_OK && i < m->ntris; i++) {
        amp_vec3 n = tri_normal(m, i);
        int k;
        st = amp_sinkf(sink, user, "facet normal %.9g %.9g %.9g\n outer loop\n", n.x, n.y, n.z);
        for (k = 0; st == AMP_OK && k < 3; k++) {
            amp_vec3 p = m->verts[m->tris[i].v[k]];
            st = amp_sinkf(sink, user, "  vertex %.17g %.17g %.17g\n", p.x, p.y, p.z);
        }
        if (st == AMP_OK)
            st = amp_sinkf(sink, user, " endloop\nendfacet\n");
    }
    if (st == AMP_OK)
        st = amp_sinkf(sink, user, "endsolid ampath\n");
    return st == AMP_OK ? AMP_OK : amp_fail(err, st, 0, "writing ASCII STL failed");
}

amp_status amp_mesh_write_stl(const amp_mesh *m, int binary, amp_sink_fn sink, void *user, amp_error *err)
{
    if (!m || !sink)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_write_stl: NULL argument");
    return binary ? write_binary(m, sink, user, err) : write_ascii(m, sink, user, err);
}

typedef struct stl_file_ctx {
    const amp_mesh *m;
    int binary;
} stl_file_ctx;

static amp_status stl_file_writer(void *vctx, amp_sink_fn sink, void *user, amp_error *err)
{
    const stl_file_ctx *c = vctx;
    return amp_mesh_write_stl(c->m, c->binary, sink, user, err);
}

amp_status amp_mesh_write_stl_file(const amp_mesh *m, const char *path, int binary, amp_error *err)
{
    stl_file_ctx c;
    if (!m || !path)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_write_stl_file: NULL argument");
    c.m = m;
    c.binary = binary;
    return amp_write_file_atomic(path, stl_file_writer, &c, err);
}

/* -------------------------------------------------------- tolerance weld */

static uint64_t cell_hash(long long x, long long y, long long z)
{
    return mix64((uint64_t)x * 0x9e3779b97f4a7c15ULL ^ mix64((uint64_t)y ^ mix64((uint64_t)z)));
}

static long long cell_of(double c, double h)
{
    double q = floor(c / h);
    /* clamp far-away coordinates: only the neighbourhood test needs exactness */
    if (q > 4e18)
        q = 4e18;
    if (q < -4e18)
        q = -4e18;
    return (long long)q;
}

amp_status amp_mesh_weld(amp_mesh *m, double tol, amp_error *err)
{
    uint32_t *head = NULL, *next = NULL, *map = NULL, *newidx = NULL;
    size_t cap = 1, i, nt = 0, nv = 0;
    double h;
    if (!m || !isfinite(tol) || tol < 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_mesh_weld: tolerance must be finite and >= 0");
    if (m->nverts == 0)
        return AMP_OK;
    /* grid cell = tol, so that any partner within tol lies in the 27 neighbour cells */
    h = tol > 0 ? tol : 1.0;
    while (cap < 2 * m->nverts)
        cap *= 2;
    head = amp_alloc(m->alloc, cap * sizeof *head);
    next = amp_alloc(m->alloc, m->nverts * sizeof *next);
    map = amp_alloc(m->alloc, m->nverts * sizeof *map);
    newidx = amp_alloc(m->alloc, m->nverts * sizeof *newidx);
    if (!head || !next || !map || !newidx) {
        amp_free(m->alloc, head);
        amp_free(m->alloc, next);
        amp_free(m->alloc, map);
        amp_free(m->alloc, newidx);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for welding");
    }
    memset(head, 0xff, cap * sizeof *head);
    for (i = 0; i < m->nverts; i++) {
        amp_vec3 p = m->verts[i];
        long long cx = cell_of(p.x, h), cy = cell_of(p.y, h), cz = cell_of(p.z, h);
        int dx, dy, dz;
        uint32_t found = WELD_EMPTY;
        for (dx = -1; dx <= 1 && found == WELD_EMPTY; dx++)
            for (dy = -1; dy <= 1 && found == WELD_EMPTY; dy++)
                for (dz = -1; dz <= 1 && found == WELD_EMPTY; dz++) {
                    uint32_t v = head[cell_hash(cx + dx, cy + dy, cz + dz) & (cap - 1)];
                    for (; v != WELD_EMPTY; v = next[v])
                        if (tol > 0 ? amp_v3_dist(m->verts[v], p) <= tol : same_point(m->verts[v], p)) {
                            found = v;
                            break;
                        }
                }
        if (found != WELD_EMPTY) {
            map[i] = found;
        } else {
            size_t b = cell_hash(cx, cy, cz) & (cap - 1);
            map[i] = (uint32_t)i;
            next[i] = head[b];
            head[b] = (uint32_t)i;
        }
    }
    /* re-index triangles, drop collapsed ones, then compact the used vertices */
    memset(newidx, 0xff, m->nverts * sizeof *newidx);
    for (i = 0; i < m->ntris; i++) {
        amp_tri t = m->tris[i];
        int k;
        for (k = 0; k < 3; k++)
            t.v[k] = map[t.v[k]];
        if (t.v[0] == t.v[1] || t.v[1] == t.v[2] || t.v[0] == t.v[2])
            continue;
        m->tris[nt++] = t;
    }
    m->ntris = nt;
    for (i = 0; i < nt; i++) {
        int k;
        for (k = 0; k < 3; k++)
            newidx[m->tris[i].v[k]] = 0;
    }
    for (i = 0; i < m->nverts; i++)
        if (newidx[i] == 0) {
            newidx[i] = (uint32_t)nv;
            m->verts[nv++] = m->verts[i];
        }
    for (i = 0; i < nt; i++) {
        int k;
        for (k = 0; k < 3; k++)
            m->tris[i].v[k] = newidx[m->tris[i].v[k]];
    }
    m->nverts = nv;
    amp_free(m->alloc, head);
    amp_free(m->alloc, next);
    amp_free(m->alloc, map);
    amp_free(m->alloc, newidx);
    return AMP_OK;
}
