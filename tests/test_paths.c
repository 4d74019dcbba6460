/* .amp format and in-memory paths (docs/interfaces.md §3). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "../lib/paths_parse.h"
#include "testutil.h"

static amp_status parse(amp_pathset *ps, const char *text, amp_error *err)
{
    return amp_pathset_parse(ps, text, strlen(text), err);
}

START_TEST(roundtrip_preserves_paths_roles_and_radii)
{
    amp_pathset ps, back;
    amp_buf buf;
    amp_error err;
    size_t i, k;
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&back, NULL);
    amp_buf_init(&buf, NULL);
    /* a real helix-like path plus a support path */
    ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, &err), AMP_OK);
    for (k = 0; k < 200; k++) {
        double t = k / 199.0;
        ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(20 * cos(2 * AMP_PI * t), 20 * sin(2 * AMP_PI * t),
                                                      5 + 40 * t),
                                          0.3 + 0.2 * t, &err),
                         AMP_OK);
    }
    ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_SUPPORT, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(0, 0, 0), 0.25, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(0, 0, 4.5), 0.25, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_write(&ps, "made by a test\nsecond line", amp_buf_sink, &buf, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_parse(&back, buf.data, buf.len, &err), AMP_OK);
    ck_assert_uint_eq(back.npaths, 2);
    ck_assert_uint_eq(back.nverts, ps.nverts);
    ck_assert_int_eq(back.paths[1].role, AMP_ROLE_SUPPORT);
    for (i = 0; i < ps.nverts; i++) {
        ck_assert_near(back.verts[i].p.x, ps.verts[i].p.x, 1e-7);
        ck_assert_near(back.verts[i].p.z, ps.verts[i].p.z, 1e-7);
        ck_assert_near(back.verts[i].r, ps.verts[i].r, 1e-9);
    }
    ck_assert_near(amp_pathset_length(&back, AMP_ROLE_SUPPORT), 4.5, 1e-12);
    amp_buf_free(&buf);
    amp_pathset_free(&ps);
    amp_pathset_free(&back);
}
END_TEST

/* The text of @p ps as printf writes it, line by line (the reference of the block writer). */
static void printf_text(const amp_pathset *ps, amp_buf *out)
{
    char line[256];
    size_t i, k;
    ck_assert_int_eq(amp_buf_append(out, "ampath-paths 1\n", 15), AMP_OK);
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        int n = ps->paths[i].h > 0 ? snprintf(line, sizeof line, "path %s %lu %.10g\n",
                                              ps->paths[i].role == AMP_ROLE_SUPPORT ? "support" : "object",
                                              (unsigned long)ps->paths[i].n, ps->paths[i].h)
                                   : snprintf(line, sizeof line, "path %s %lu\n",
                                              ps->paths[i].role == AMP_ROLE_SUPPORT ? "support" : "object",
                                              (unsigned long)ps->paths[i].n);
        ck_assert_int_eq(amp_buf_append(out, line, (size_t)n), AMP_OK);
        for (k = 0; k < ps->paths[i].n; k++) {
            n = snprintf(line, sizeof line, "%.10g %.10g %.10g %.10g\n", v[k].p.x, v[k].p.y, v[k].p.z, v[k].r);
            ck_assert_int_eq(amp_buf_append(out, line, (size_t)n), AMP_OK);
        }
    }
}

/* Paths of @p n vertices each (n[i] may be 0), on a spiral with changing radii. */
static void spiral_paths(amp_pathset *ps, const size_t *n, size_t np)
{
    amp_error err;
    size_t i, k, t = 0;
    for (i = 0; i < np; i++) {
        ck_assert_int_eq(amp_pathset_begin(ps, i % 3 == 2 ? AMP_ROLE_SUPPORT : AMP_ROLE_OBJECT, &err), AMP_OK);
        ps->paths[i].h = i % 2 ? 0.2 : 0.0;
        for (k = 0; k < n[i]; k++, t++)
            ck_assert_int_eq(amp_pathset_push(ps, amp_v3(30 * cos(0.01 * t), 30 * sin(0.01 * t), 1e-3 * t),
                                              0.2 + 1e-5 * (double)(t % 977), &err),
                             AMP_OK);
    }
}

/* The writer's text of @p ps equals printf's, byte for byte. */
static void writes_as_printf(const amp_pathset *ps)
{
    amp_buf got, want;
    amp_error err;
    amp_buf_init(&got, NULL);
    amp_buf_init(&want, NULL);
    printf_text(ps, &want);
    ck_assert_int_eq(amp_pathset_write(ps, NULL, amp_buf_sink, &got, &err), AMP_OK);
    ck_assert_uint_eq(got.len, want.len);
    ck_assert(memcmp(got.data, want.data, want.len) == 0);
    amp_buf_free(&got);
    amp_buf_free(&want);
}

START_TEST(written_text_equals_printf_across_blocks_and_empty_paths)
{
    /* empty paths first, between and last; paths across the writer's blocks of a few thousand vertices,
     * one of exactly 4096, one of 50,000 (several blocks), many short ones */
    size_t n[64], np = 0, i;
    amp_pathset ps;
    n[np++] = 0;
    n[np++] = 0;
    n[np++] = 3;
    n[np++] = 4096;
    n[np++] = 0;
    n[np++] = 50000;
    n[np++] = 4095;
    for (i = 0; i < 40; i++)
        n[np++] = 1 + 37 * i;
    n[np++] = 0;
    n[np++] = 0;
    amp_pathset_init(&ps, NULL);
    spiral_paths(&ps, n, np);
    writes_as_printf(&ps);
    /* only empty paths, and no path at all (the header line alone) */
    amp_pathset_clear(&ps);
    spiral_paths(&ps, n, 2);
    writes_as_printf(&ps);
    amp_pathset_clear(&ps);
    writes_as_printf(&ps);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(bead_height_roundtrips_and_sets_the_planar_cross_section)
{
    amp_pathset ps, back, copy;
    amp_buf buf;
    amp_error err;
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&back, NULL);
    amp_pathset_init(&copy, NULL);
    amp_buf_init(&buf, NULL);
    /* a 10 mm planar bead 0.45 wide, 0.2 high, then the same line as a tube */
    ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_set_height(&ps, 0.2, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(0, 0, 0.2), 0.225, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_push(&ps, amp_v3(10, 0, 0.2), 0.225, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_add(&ps, AMP_ROLE_OBJECT, ps.verts, 2, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_set_height(&ps, -1, &err), AMP_ERR_ARG);
    ck_assert_int_eq(amp_pathset_write(&ps, NULL, amp_buf_sink, &buf, &err), AMP_OK);
    ck_assert_ptr_nonnull(strstr(buf.data, "path object 2 0.2\n"));
    ck_assert_ptr_nonnull(strstr(buf.data, "path object 2\n"));
    ck_assert_int_eq(amp_pathset_parse(&back, buf.data, buf.len, &err), AMP_OK);
    ck_assert_double_eq(back.paths[0].h, 0.2);
    ck_assert_double_eq(back.paths[1].h, 0.0);
    ck_assert_int_eq(amp_pathset_append(&copy, &back, &err), AMP_OK);
    ck_assert_double_eq(copy.paths[0].h, 0.2);
    /* rounded rectangle (w - h) h + pi (h/2)^2, against pi r^2 for the tube */
    ck_assert_near(amp_bead_area(0.225, 0.2), 0.25 * 0.2 + AMP_PI * 0.01, 1e-15);
    ck_assert_near(amp_bead_area(0.05, 0.2), AMP_PI * 0.0025, 1e-15);
    ck_assert_near(amp_pathset_volume(&copy, -1), 10 * (0.25 * 0.2 + AMP_PI * 0.01) + 10 * AMP_PI * 0.225 * 0.225, 1e-12);
    amp_buf_free(&buf);
    amp_pathset_free(&ps);
    amp_pathset_free(&back);
    amp_pathset_free(&copy);
}
END_TEST

/* A point within the tolerance of the last vertex joins it (the smaller radius): in place of the earlier point
 * inside a path, at its own place when it ends the path; the first vertex stays where it is. */
START_TEST(merged_push_joins_a_point_that_repeats_the_last_vertex)
{
    amp_pathset ps;
    const amp_pvert *v;
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
    ck_assert_int_eq(amp_pathset_push_merged(&ps, amp_v3(0, 0, 1), 0.5, 1e-6, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_pathset_push_merged(&ps, amp_v3(5e-7, 0, 1), 0.4, 1e-6, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_pathset_push_merged(&ps, amp_v3(1, 0, 1), 0.5, 1e-6, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_pathset_push_merged(&ps, amp_v3(1, 2e-6, 1), 0.3, 1e-6, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_pathset_push_merged(&ps, amp_v3(1, 2.5e-6, 1), 0.6, 1e-6, 1, NULL), AMP_OK);
    v = amp_pathset_path_verts(&ps, 0);
    ck_assert_uint_eq(ps.paths[0].n, 3);
    ck_assert(v[0].p.x == 0.0 && v[0].r == 0.4); /* the first vertex kept its place, took the smaller radius */
    ck_assert(v[1].p.x == 1.0 && v[1].p.y == 0.0 && v[1].r == 0.5);
    ck_assert(v[2].p.y == 2.5e-6 && v[2].r == 0.3); /* the path ends exactly at its last point */
    /* a path's only vertex is not replaced by its last: two points stay two */
    ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
    ck_assert_int_eq(amp_pathset_push_merged(&ps, amp_v3(0, 0, 0), 0.5, 1e-6, 0, NULL), AMP_OK);
    ck_assert_int_eq(amp_pathset_push_merged(&ps, amp_v3(0, 0, 1e-7), 0.5, 1e-6, 1, NULL), AMP_OK);
    ck_assert_uint_eq(ps.paths[1].n, 1);
    ck_assert(amp_pathset_path_verts(&ps, 1)[0].p.z == 0.0);
    /* bad input: the errors of amp_pathset_push */
    ck_assert_int_eq(amp_pathset_push_merged(&ps, amp_v3(NAN, 0, 0), 0.5, 1e-6, 0, NULL), AMP_ERR_ARG);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(parser_accepts_comments_crlf_and_blank_lines)
{
    amp_pathset ps;
    amp_error err;
    const char *text = "# leading comment\r\nampath-paths 1\r\n\r\npath object 2 # two\r\n"
                       "0 0 0 0.5\r\n  1 0 0   0.5  \r\n# between\npath support 0\n";
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(parse(&ps, text, &err), AMP_OK);
    ck_assert_uint_eq(ps.npaths, 2);
    ck_assert_uint_eq(ps.paths[0].n, 2);
    ck_assert_uint_eq(ps.paths[1].n, 0);
    ck_assert_near(amp_pathset_length(&ps, -1), 1.0, 0);
    amp_pathset_free(&ps);
}
END_TEST

static const struct bad_case {
    const char *text;
    long line;
    const char *needle;
} bad_cases[] = {
    {"", 1, "empty"},
    {"ampath-paths 2\n", 1, "version"},
    {"hello\n", 1, "header"},
    {"ampath-paths 1\npath object\n", 2, "path <role>"},
    {"ampath-paths 1\npath bridge 1\n0 0 0 1\n", 2, "role"},
    {"ampath-paths 1\npath object -1\n", 2, "outside"},
    {"ampath-paths 1\npath object 2\n0 0 0 0.5\n", 4, "missing"},
    {"ampath-paths 1\npath object 1\n0 0 0\n", 3, "found 3 fields"},
    {"ampath-paths 1\npath object 1\n0 0 0 -0.5\n", 3, "negative radius"},
    {"ampath-paths 1\npath object 1\n0 nan 0 0.5\n", 3, "not finite"},
    {"ampath-paths 1\npath object 1\n0 1e999 0 0.5\n", 3, "not finite"},
    {"ampath-paths 1\npath object 1\n0 x1 0 0.5\n", 3, "not a number"},
    {"ampath-paths 1\n0 0 0 0.5\n", 2, "path <role>"},
    {"ampath-paths 1\npath object 99999999999999999999\n", 2, "integer"},
    {"ampath-paths 1\npath object 1 0\n0 0 0 0.5\n", 2, "must be positive"},
    {"ampath-paths 1\npath object 1 -0.2\n0 0 0 0.5\n", 2, "must be positive"},
    {"ampath-paths 1\npath object 1 nan\n0 0 0 0.5\n", 2, "not finite"},
    {"ampath-paths 1\npath object 1 0.2 7\n0 0 0 0.5\n", 2, "path <role>"},
};

START_TEST(parser_rejects_malformed_input_with_line_numbers)
{
    const struct bad_case *c = &bad_cases[_i];
    amp_pathset ps;
    amp_error err;
    amp_pathset_init(&ps, NULL);
    amp_error_clear(&err);
    ck_assert_int_eq(parse(&ps, c->text, &err), AMP_ERR_PARSE);
    ck_assert_msg(err.line == c->line, "case %d: line %ld, expected %ld (%s)", _i, err.line, c->line, err.msg);
    ck_assert_msg(strstr(err.msg, c->needle) != NULL, "case %d: message '%s' lacks '%s'", _i, err.msg, c->needle);
    ck_assert_uint_eq(ps.npaths, 0);
    ck_assert_uint_eq(ps.nverts, 0);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(failed_parse_leaves_existing_paths_untouched)
{
    amp_pathset ps;
    amp_error err;
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(parse(&ps, "ampath-paths 1\npath object 1\n1 2 3 0.5\n", &err), AMP_OK);
    ck_assert_int_eq(parse(&ps, "ampath-paths 1\npath object 1\n1 2 3 0.5\npath object 3\n1 1 1 1\n", &err),
                     AMP_ERR_PARSE);
    ck_assert_uint_eq(ps.npaths, 1);
    ck_assert_uint_eq(ps.nverts, 1);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(overlong_line_and_nul_bytes_are_rejected_without_overrun)
{
    amp_pathset ps;
    amp_error err;
    size_t n = 100000;
    char *text = malloc(n);
    memcpy(text, "ampath-paths 1\n", 15);
    memset(text + 15, '1', n - 15); /* not NUL-terminated on purpose */
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(amp_pathset_parse(&ps, text, n, &err), AMP_ERR_PARSE);
    ck_assert_int_eq(err.line, 2);
    memcpy(text + 15, "path object 1\n0 0\0 0 1\n", 23);
    ck_assert_int_eq(amp_pathset_parse(&ps, text, 38, &err), AMP_ERR_PARSE);
    ck_assert_ptr_nonnull(strstr(err.msg, "NUL"));
    free(text);
    amp_pathset_free(&ps);
}
END_TEST

START_TEST(out_of_memory_is_reported_and_leaves_set_consistent)
{
    fx_failalloc fa;
    amp_pathset ps;
    amp_error err;
    long budget;
    const char *text = "ampath-paths 1\npath object 3\n0 0 0 1\n1 0 0 1\n2 0 0 1\npath support 1\n5 5 5 0\n";
    for (budget = 0; budget < 6; budget++) {
        amp_status st;
        fx_failalloc_init(&fa, budget);
        amp_pathset_init(&ps, &fa.a);
        st = parse(&ps, text, &err);
        ck_assert(st == AMP_OK || st == AMP_ERR_NOMEM);
        if (st != AMP_OK) {
            ck_assert_uint_eq(ps.npaths, 0);
        } else {
            ck_assert_uint_eq(ps.npaths, 2);
        }
        amp_pathset_free(&ps);
    }
}
END_TEST

START_TEST(file_write_is_atomic_and_reads_back)
{
    amp_pathset ps, back;
    amp_error err;
    const char *file = fx_tmp("rt.amp");
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&back, NULL);
    ck_assert_int_eq(parse(&ps, "ampath-paths 1\npath object 2\n0 0 0 1\n3 4 0 1\n", &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_write_file(&ps, file, NULL, &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_read_file(&back, file, &err), AMP_OK);
    ck_assert_near(amp_pathset_length(&back, -1), 5.0, 1e-12);
    ck_assert_near(amp_pathset_volume(&back, -1), 5.0 * AMP_PI, 1e-9);
    remove(file);
    ck_assert_int_eq(amp_pathset_read_file(&back, file, &err), AMP_ERR_IO);
    ck_assert_ptr_nonnull(strstr(err.msg, file));
    amp_pathset_free(&ps);
    amp_pathset_free(&back);
}
END_TEST


/* A text with every form the format allows, made by code: paths of 0..40 vertices of both roles, bead heights,
 * comments on their own lines and after headers, blank lines, CRLF, indented headers, repeated z and r. */
static char *varied_text(unsigned long seed, size_t npaths, size_t *len)
{
    size_t cap = 256 + npaths * 41 * 64, n = 0, i, k;
    char *t = malloc(cap);
    ck_assert_ptr_nonnull(t);
    n += (size_t)sprintf(t + n, "# made by code\nampath-paths 1\n");
    for (i = 0; i < npaths; i++) {
        size_t nv = (seed = seed * 6364136223846793005UL + 1442695040888963407UL) >> 59 & 31;
        int form = (int)(i % 5);
        if (i % 7 == 3)
            nv += 9;
        if (form == 0)
            n += (size_t)sprintf(t + n, "path object %lu\n", (unsigned long)nv);
        else if (form == 1)
            n += (size_t)sprintf(t + n, "  path support %lu # indented, commented\r\n", (unsigned long)nv);
        else if (form == 2)
            n += (size_t)sprintf(t + n, "path object %lu 0.2\n\n# between\n", (unsigned long)nv);
        else if (form == 3)
            n += (size_t)sprintf(t + n, "\tpath support %lu 0.35#tight\n", (unsigned long)nv);
        else
            n += (size_t)sprintf(t + n, "path object %lu\r\n", (unsigned long)nv);
        for (k = 0; k < nv; k++) {
            seed = seed * 6364136223846793005UL + 1442695040888963407UL;
            n += (size_t)sprintf(t + n, "%.10g %.6g %g %s\n", (double)(seed >> 20 & 0xfffff) * 1e-4 - 50.0,
                                 (double)(seed >> 40 & 0xffff) * 3e-3, 0.2 * (double)(i / 9 + 1),
                                 k % 3 ? "0.225" : "0.3");
        }
    }
    *len = n;
    return t;
}

static void same_sets(const amp_pathset *a, const amp_pathset *b)
{
    size_t i;
    ck_assert_uint_eq(a->npaths, b->npaths);
    ck_assert_uint_eq(a->nverts, b->nverts);
    for (i = 0; i < a->npaths; i++) {
        ck_assert_int_eq(a->paths[i].role, b->paths[i].role);
        ck_assert_uint_eq(a->paths[i].first, b->paths[i].first);
        ck_assert_uint_eq(a->paths[i].n, b->paths[i].n);
        ck_assert(a->paths[i].h == b->paths[i].h);
    }
    ck_assert(a->nverts == 0 || memcmp(a->verts, b->verts, a->nverts * sizeof *a->verts) == 0);
}

START_TEST(chunked_read_gives_the_one_piece_read_at_every_chunk_count)
{
    static const size_t counts[] = {2, 3, 4, 5, 7, 9, 16, 64, 1000};
    size_t len, c, used;
    char *text = varied_text(7, 400, &len);
    amp_pathset one, chunked;
    amp_error err;
    amp_pathset_init(&one, NULL);
    ck_assert_int_eq(parse(&one, "ampath-paths 1\npath object 1\n1 2 3 0.5\n", &err), AMP_OK);
    ck_assert_int_eq(amp_pathset_parse_chunks(&one, text, len, 1, &used, &err), AMP_OK);
    ck_assert_uint_eq(used, 1);
    ck_assert_uint_eq(one.npaths, 401);
    for (c = 0; c < sizeof counts / sizeof counts[0]; c++) {
        amp_pathset_init(&chunked, NULL);
        ck_assert_int_eq(parse(&chunked, "ampath-paths 1\npath object 1\n1 2 3 0.5\n", &err), AMP_OK);
        ck_assert_int_eq(amp_pathset_parse_chunks(&chunked, text, len, counts[c], &used, &err), AMP_OK);
        /* read in chunks indeed (not the one-piece fallback): as many as asked, up to the 64 the reader takes */
        ck_assert_uint_eq(used, counts[c] < 64 ? counts[c] : 64);
        same_sets(&one, &chunked);
        amp_pathset_free(&chunked);
    }
    amp_pathset_free(&one);
    free(text);
}
END_TEST

/* The fractions a progress report heard. */
typedef struct heard {
    double f[256];
    size_t n;
} heard;

static void hear(void *user, double fraction)
{
    heard *h = user;
    if (h->n < 256)
        h->f[h->n] = fraction;
    h->n++;
}

/* A read with a progress report is the read without one (a text of several megabytes, so that it is read in
 * chunks), and the report rises to 1 in at most 64 steps; a text under a megabyte is read in one piece and
 * reports 1 once it is read. */
START_TEST(a_read_with_progress_reads_the_same_set_and_reports_up_to_one)
{
    size_t len, k;
    char *text = varied_text(11, 8000, &len);
    amp_pathset plain, reported;
    amp_error err;
    heard h;
    ck_assert_uint_gt(len, (size_t)3 << 20);
    amp_pathset_init(&plain, NULL);
    amp_pathset_init(&reported, NULL);
    ck_assert_int_eq(amp_pathset_parse(&plain, text, len, &err), AMP_OK);
    h.n = 0;
    ck_assert_int_eq(amp_pathset_parse_progress(&reported, text, len, hear, &h, &err), AMP_OK);
    same_sets(&plain, &reported);
    ck_assert_uint_ge(h.n, 2); /* at least one chunk before the last, on the calling thread */
    ck_assert_uint_le(h.n, 64);
    for (k = 0; k < h.n; k++) {
        ck_assert(h.f[k] > 0.0 && h.f[k] <= 1.0);
        ck_assert(k == 0 || h.f[k] > h.f[k - 1]);
    }
    ck_assert(h.f[h.n - 1] == 1.0);
    amp_pathset_free(&reported);
    /* no report: exactly amp_pathset_parse() */
    amp_pathset_init(&reported, NULL);
    ck_assert_int_eq(amp_pathset_parse_progress(&reported, text, len, NULL, NULL, &err), AMP_OK);
    same_sets(&plain, &reported);
    amp_pathset_free(&reported);
    amp_pathset_free(&plain);
    free(text);
    text = varied_text(11, 40, &len);
    amp_pathset_init(&plain, NULL);
    h.n = 0;
    ck_assert_int_eq(amp_pathset_parse_progress(&plain, text, len, hear, &h, &err), AMP_OK);
    ck_assert_uint_eq(plain.npaths, 40);
    ck_assert_uint_eq(h.n, 1);
    ck_assert(h.f[0] == 1.0);
    amp_pathset_free(&plain);
    free(text);
}
END_TEST

/* Replace the line that starts at or after byte @p at (the header line excluded) with @p line. */
static char *with_line(const char *text, size_t len, size_t at, const char *line, size_t *olen)
{
    const char *b = memchr(text + at, '\n', len - at), *e;
    size_t nb, nl = strlen(line);
    char *t;
    ck_assert_ptr_nonnull(b);
    b++;
    e = memchr(b, '\n', len - (size_t)(b - text));
    ck_assert_ptr_nonnull(e);
    nb = (size_t)(b - text);
    t = malloc(len + nl + 1);
    memcpy(t, text, nb);
    memcpy(t + nb, line, nl);
    memcpy(t + nb + nl, e, len - (size_t)(e - text));
    *olen = nb + nl + (len - (size_t)(e - text));
    return t;
}

START_TEST(chunked_read_fails_exactly_as_the_one_piece_read)
{
    /* errors inside a chunk, on a chunk's first line, and paths that run on into the next chunk (a header's
     * count one too high or too low: the next header is read as a vertex, or a vertex as a header) */
    static const char *const lines[] = {"1 2 3", "0 0 0 -0.5", "path object 99", "path object 0", "path bridge 1",
                                        "0 x 0 0.5", "path object 1 -0.2", "1 2 3 4 5"};
    size_t len, l, pos, c;
    char *text = varied_text(11, 300, &len);
    for (l = 0; l < sizeof lines / sizeof lines[0]; l++)
        for (pos = 1; pos < 10; pos += 2) {
            size_t blen;
            char *bad = with_line(text, len, len / 10 * pos, lines[l], &blen);
            amp_pathset one;
            amp_error e1;
            amp_status s1;
            amp_pathset_init(&one, NULL);
            amp_error_clear(&e1);
            s1 = amp_pathset_parse_chunks(&one, bad, blen, 1, NULL, &e1);
            for (c = 2; c <= 5; c++) {
                amp_pathset chunked;
                amp_error e2;
                amp_pathset_init(&chunked, NULL);
                ck_assert_int_eq(parse(&chunked, "ampath-paths 1\npath support 1\n0 0 0 0\n", &e2), AMP_OK);
                amp_error_clear(&e2);
                ck_assert_int_eq(amp_pathset_parse_chunks(&chunked, bad, blen, c, NULL, &e2), s1);
                if (s1 != AMP_OK) {
                    ck_assert_int_eq(e2.line, e1.line);
                    ck_assert_str_eq(e2.msg, e1.msg);
                    ck_assert_uint_eq(chunked.npaths, 1); /* as before the call */
                    ck_assert_uint_eq(chunked.nverts, 1);
                }
                amp_pathset_free(&chunked);
            }
            ck_assert_msg(s1 != AMP_OK || l == 3, "line '%s' at %lu: expected an error", lines[l], (unsigned long)pos);
            amp_pathset_free(&one);
            free(bad);
        }
    free(text);
}
END_TEST

START_TEST(chunked_read_out_of_memory_leaves_the_set_as_it_was)
{
    size_t len;
    char *text = varied_text(3, 60, &len);
    long budget;
    for (budget = 0; budget < 40; budget++) {
        fx_failalloc fa;
        amp_pathset ps;
        amp_error err;
        amp_status st;
        fx_failalloc_init(&fa, budget);
        amp_pathset_init(&ps, &fa.a);
        st = amp_pathset_parse_chunks(&ps, text, len, 4, NULL, &err);
        ck_assert(st == AMP_OK || st == AMP_ERR_NOMEM);
        ck_assert_uint_eq(ps.npaths, st == AMP_OK ? 60 : 0);
        amp_pathset_free(&ps);
    }
    free(text);
}
END_TEST

static Suite *paths_suite(void)
{
    Suite *s = suite_create("paths");
    TCase *tc = tcase_create("amp");
    tcase_add_test(tc, roundtrip_preserves_paths_roles_and_radii);
    tcase_add_test(tc, bead_height_roundtrips_and_sets_the_planar_cross_section);
    tcase_add_test(tc, merged_push_joins_a_point_that_repeats_the_last_vertex);
    tcase_add_test(tc, parser_accepts_comments_crlf_and_blank_lines);
    tcase_add_loop_test(tc, parser_rejects_malformed_input_with_line_numbers, 0,
                        (int)(sizeof bad_cases / sizeof bad_cases[0]));
    tcase_add_test(tc, failed_parse_leaves_existing_paths_untouched);
    tcase_add_test(tc, overlong_line_and_nul_bytes_are_rejected_without_overrun);
    tcase_add_test(tc, out_of_memory_is_reported_and_leaves_set_consistent);
    tcase_add_test(tc, file_write_is_atomic_and_reads_back);
    tcase_add_test(tc, written_text_equals_printf_across_blocks_and_empty_paths);
    tcase_add_test(tc, chunked_read_gives_the_one_piece_read_at_every_chunk_count);
    tcase_add_test(tc, a_read_with_progress_reads_the_same_set_and_reports_up_to_one);
    tcase_add_test(tc, chunked_read_fails_exactly_as_the_one_piece_read);
    tcase_add_test(tc, chunked_read_out_of_memory_leaves_the_set_as_it_was);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(paths_suite)
