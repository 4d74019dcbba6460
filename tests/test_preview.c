/* ampath preview: PNG (own encoder) and SVG pictures, checked by an independent PNG reader. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fixture_geom.h"
#include "runtool.h"
#include "testutil.h"

/* ------------------------------------------------------------------ running the tool */

static int run(const char *args, char *out, size_t cap)
{
    int rc = fx_run_tool(args, out, cap);
    ck_assert_msg(rc != -2, "AMP_TOOL not set (run through make check)");
    return rc;
}

static unsigned char *slurp(const char *file, size_t *len)
{
    FILE *f = fopen(file, "rb");
    unsigned char *buf;
    long n;
    ck_assert_msg(f != NULL, "%s missing", file);
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    buf = malloc((size_t)n + 1);
    ck_assert_uint_eq(fread(buf, 1, (size_t)n, f), (size_t)n);
    buf[n] = 0;
    fclose(f);
    *len = (size_t)n;
    return buf;
}

static const char *fixture_file(void)
{
    amp_pathset ps;
    const char *file = fx_tmp("preview.amp");
    amp_pathset_init(&ps, NULL);
    fx_rings(&ps, 0, 0, 4, 3, 48, 0.25);
    fx_helix(&ps, 12, 150);
    ck_assert_int_eq(amp_pathset_write_file(&ps, file, NULL, NULL), AMP_OK);
    amp_pathset_free(&ps);
    return file;
}

/* ------------------------------------------------------------------ an independent PNG reader */

static unsigned long crc_table[256];

static unsigned long crc32_tab(const unsigned char *p, size_t n)
{
    unsigned long c = 0xffffffffUL;
    size_t i;
    if (!crc_table[1]) {
        unsigned long k, v;
        int j;
        for (k = 0; k < 256; k++) {
            for (v = k, j = 0; j < 8; j++)
                v = v & 1 ? 0xedb88320UL ^ (v >> 1) : v >> 1;
            crc_table[k] = v;
        }
    }
    for (i = 0; i < n; i++)
        c = crc_table[(c ^ p[i]) & 0xff] ^ (c >> 8);
    return c ^ 0xffffffffUL;
}

static unsigned long be32(const unsigned char *p)
{
    return ((unsigned long)p[0] << 24) | ((unsigned long)p[1] << 16) | ((unsigned long)p[2] << 8) | p[3];
}

typedef struct bitr {
    const unsigned char *p;
    size_t n, pos; /* bit position */
} bitr;

static int getbit(bitr *b)
{
    int v;
    if (b->pos >= 8 * b->n)
        return -1;
    v = (b->p[b->pos >> 3] >> (b->pos & 7)) & 1;
    b->pos++;
    return v;
}

static long getbits(bitr *b, int n)
{
    long v = 0;
    int i;
    for (i = 0; i < n; i++) {
        int x = getbit(b);
        if (x < 0)
            return -1;
        v |= (long)x << i;
    }
    return v;
}

/* Fixed-Huffman literal/length symbol, MSB-first code bits. */
static int fixed_sym(bitr *b)
{
    int code = 0, i, x;
    for (i = 0; i < 7; i++) {
        if ((x = getbit(b)) < 0)
            return -1;
        code = code << 1 | x;
    }
    if (code <= 23)
        return 256 + code;
    if ((x = getbit(b)) < 0)
        return -1;
    code = code << 1 | x;
    if (code >= 0x30 && code <= 0xbf)
        return code - 0x30;
    if (code >= 0xc0 && code <= 0xc7)
        return 280 + code - 0xc0;
    if ((x = getbit(b)) < 0)
        return -1;
    code = code << 1 | x;
    return code >= 0x190 && code <= 0x1ff ? 144 + code - 0x190 : -1;
}

/* zlib inflate for stored and fixed-Huffman blocks; returns the output length or -1. */
static long inflate_simple(const unsigned char *z, size_t zn, unsigned char *out, size_t cap)
{
    static const unsigned short lbase[] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                           31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
    static const unsigned char lext[] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                         2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
    static const unsigned short dbase[] = {1,   2,   3,   4,   5,   7,    9,    13,   17,   25,   33,   49,   65,    97,    129,
                                           193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
    static const unsigned char dext[] = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
    bitr b;
    size_t o = 0;
    int last = 0;
    unsigned long s1 = 1, s2 = 0, k;
    if (zn < 6 || (z[0] & 15) != 8 || ((z[0] << 8) | z[1]) % 31 != 0)
        return -1;
    b.p = z + 2;
    b.n = zn - 6;
    b.pos = 0;
    while (!last) {
        long type;
        last = getbit(&b);
        type = getbits(&b, 2);
        if (last < 0 || type < 0)
            return -1;
        if (type == 0) {
            size_t len, i;
            b.pos = (b.pos + 7) & ~(size_t)7;
            if (b.pos / 8 + 4 > b.n)
                return -1;
            len = b.p[b.pos / 8] | (size_t)b.p[b.pos / 8 + 1] << 8;
            b.pos += 32;
            if (b.pos / 8 + len > b.n || o + len > cap)
                return -1;
            for (i = 0; i < len; i++)
                out[o++] = b.p[b.pos / 8 + i];
            b.pos += 8 * len;
        } else if (type == 1) {
            for (;;) {
                int s = fixed_sym(&b);
                if (s < 0 || s > 285)
                    return -1;
                if (s < 256) {
                    if (o >= cap)
                        return -1;
                    out[o++] = (unsigned char)s;
                } else if (s == 256) {
                    break;
                } else {
                    long len = lbase[s - 257] + getbits(&b, lext[s - 257]), dist, dcode = 0, i;
                    for (i = 0; i < 5; i++)
                        dcode = dcode << 1 | getbit(&b);
                    if (dcode > 29)
                        return -1;
                    dist = dbase[dcode] + getbits(&b, dext[dcode]);
                    if (dist <= 0 || (size_t)dist > o || o + (size_t)len > cap)
                        return -1;
                    for (i = 0; i < len; i++, o++)
                        out[o] = out[o - (size_t)dist];
                }
            }
        } else {
            return -1; /* dynamic Huffman: not produced by ampath */
        }
    }
    for (k = 0; k < o; k++) {
        s1 = (s1 + out[k]) % 65521UL;
        s2 = (s2 + s1) % 65521UL;
    }
    if (be32(z + zn - 4) != ((s2 << 16) | s1))
        return -1;
    return (long)o;
}

typedef struct png {
    unsigned long w, h;
    unsigned char *rgb;
    char why[120];
} png;

/* Decode an 8-bit RGB PNG; 0 with why on any defect (bad signature, CRC, zlib, filter). */
static int png_read(const unsigned char *d, size_t n, png *img)
{
    static const unsigned char sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    unsigned char *z = NULL, *raw;
    size_t zn = 0, pos = 8, stride, y, x;
    long got;
    int seen_end = 0;
    memset(img, 0, sizeof *img);
    if (n < 8 || memcmp(d, sig, 8) != 0) {
        strcpy(img->why, "signature");
        return 0;
    }
    while (pos + 12 <= n && !seen_end) {
        unsigned long len = be32(d + pos);
        const unsigned char *type = d + pos + 4;
        if (pos + 12 + len > n) {
            strcpy(img->why, "truncated chunk");
            return 0;
        }
        if (crc32_tab(type, 4 + len) != be32(d + pos + 8 + len)) {
            snprintf(img->why, sizeof img->why, "CRC of %.4s", (const char *)type);
            free(z);
            return 0;
        }
        if (memcmp(type, "IHDR", 4) == 0) {
            img->w = be32(type + 4);
            img->h = be32(type + 8);
            if (len != 13 || type[12] != 8 || type[13] != 2 || type[16] != 0) {
                strcpy(img->why, "IHDR not 8-bit RGB");
                return 0;
            }
        } else if (memcmp(type, "IDAT", 4) == 0) {
            z = realloc(z, zn + len);
            memcpy(z + zn, type + 4, len);
            zn += len;
        } else if (memcmp(type, "IEND", 4) == 0) {
            seen_end = 1;
        }
        pos += 12 + len;
    }
    if (!seen_end || !img->w || !img->h) {
        strcpy(img->why, "no IEND or IHDR");
        free(z);
        return 0;
    }
    stride = 3 * img->w;
    raw = malloc((stride + 1) * img->h);
    got = inflate_simple(z, zn, raw, (stride + 1) * img->h);
    free(z);
    if (got != (long)((stride + 1) * img->h)) {
        strcpy(img->why, "zlib data");
        free(raw);
        return 0;
    }
    img->rgb = malloc(stride * img->h);
    for (y = 0; y < img->h; y++) {
        unsigned char f = raw[y * (stride + 1)], *cur = img->rgb + y * stride;
        const unsigned char *in = raw + y * (stride + 1) + 1, *up = y ? cur - stride : NULL;
        for (x = 0; x < stride; x++) {
            int a = x >= 3 ? cur[x - 3] : 0, bb = up ? up[x] : 0, c = (up && x >= 3) ? up[x - 3] : 0, pr;
            switch (f) {
            case 0: pr = 0; break;
            case 1: pr = a; break;
            case 2: pr = bb; break;
            case 3: pr = (a + bb) / 2; break;
            case 4: {
                int p = a + bb - c, pa = abs(p - a), pb = abs(p - bb), pc = abs(p - c);
                pr = pa <= pb && pa <= pc ? a : pb <= pc ? bb : c;
                break;
            }
            default:
                strcpy(img->why, "filter type");
                free(raw);
                return 0;
            }
            cur[x] = (unsigned char)(in[x] + pr);
        }
    }
    free(raw);
    return 1;
}

/* ------------------------------------------------------------------ tests */

START_TEST(png_is_valid_with_requested_size_and_coloured_paths)
{
    const char *in = fixture_file(), *out = fx_tmp("preview.png");
    char args[1024], json[4096];
    unsigned char *d;
    size_t n, i, ink = 0, grey = 0, blue = 0, red = 0;
    png img;
    snprintf(args, sizeof args, "preview %s -o %s --width 800 --json", in, out);
    ck_assert_int_eq(run(args, json, sizeof json), 0);
    ck_assert_ptr_nonnull(strstr(json, "\"width\":800"));
    ck_assert_ptr_nonnull(strstr(json, "\"support\":1"));
    d = slurp(out, &n);
    ck_assert_msg(png_read(d, n, &img), "PNG rejected: %s", img.why);
    ck_assert_uint_eq(img.w, 800);
    ck_assert_uint_eq(img.h, 400 + 110);
    for (i = 0; i < img.w * img.h; i++) {
        const unsigned char *p = img.rgb + 3 * i;
        int r = p[0], g = p[1], b = p[2];
        if (abs(r - 250) + abs(g - 250) + abs(b - 247) > 30)
            ink++;
        if (r == g && g == b && r > 60 && r < 160 && i < img.w * (img.h - 110))
            grey++; /* the support tube (shaded grey), above the legend */
        if (b > 2 * r && b > 100)
            blue++; /* first printed */
        if (r > 2 * b && r > 2 * g && r > 120)
            red++; /* last printed */
    }
    ck_assert_uint_gt(ink, img.w * img.h / 20);
    ck_assert_uint_gt(grey, 20);
    ck_assert_uint_gt(blue, 500);
    ck_assert_uint_gt(red, 500);
    free(img.rgb);
    free(d);
    remove(out);
    remove(in);
}
END_TEST

START_TEST(png_reader_rejects_corrupted_files)
{
    const char *in = fixture_file(), *out = fx_tmp("corrupt.png");
    char args[1024];
    unsigned char *d;
    size_t n;
    png img;
    snprintf(args, sizeof args, "preview %s -o %s --width 400", in, out);
    ck_assert_int_eq(run(args, NULL, 0), 0);
    d = slurp(out, &n);
    d[n / 2] ^= 0x20; /* a bit flip inside the image data: the chunk CRC must catch it */
    ck_assert(!png_read(d, n, &img));
    ck_assert_ptr_nonnull(strstr(img.why, "CRC"));
    d[n / 2] ^= 0x20;
    d[1] = 'X';
    ck_assert(!png_read(d, n, &img));
    ck_assert_ptr_nonnull(strstr(img.why, "signature"));
    free(d);
    remove(out);
    remove(in);
}
END_TEST

START_TEST(svg_is_well_formed_with_one_group_of_polylines_per_view)
{
    const char *in = fixture_file(), *out = fx_tmp("preview.svg");
    char args[1024];
    char *d, *p;
    size_t n, lt = 0, gt = 0, polylines = 0, i;
    snprintf(args, sizeof args, "preview %s -o %s", in, out);
    ck_assert_int_eq(run(args, NULL, 0), 0);
    d = (char *)slurp(out, &n);
    ck_assert(strncmp(d, "<?xml", 5) == 0);
    ck_assert_ptr_nonnull(strstr(d, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"1600\" height=\"910\""));
    ck_assert(n > 7 && strcmp(d + n - 7, "</svg>\n") == 0);
    for (i = 0; i < n; i++) {
        lt += d[i] == '<';
        gt += d[i] == '>';
    }
    ck_assert_uint_eq(lt, gt);
    for (p = d; (p = strstr(p, "<polyline")) != NULL; p++) {
        char *end = strchr(p, '>');
        ck_assert(end && end[-1] == '/');
        polylines++;
    }
    ck_assert_uint_ge(polylines, 2 * 25); /* every path in both views */
    ck_assert_ptr_nonnull(strstr(d, "stroke=\"#969696\"")); /* support in grey */
    ck_assert_ptr_nonnull(strstr(d, "support (1)"));
    ck_assert_ptr_null(strstr(d, "nan"));
    free(d);
    remove(out);
    remove(in);
}
END_TEST

START_TEST(preview_bad_usage_exits_2)
{
    const char *in = fixture_file();
    char args[1024];
    FILE *f;
    snprintf(args, sizeof args, "preview %s", in);
    ck_assert_int_eq(run(args, NULL, 0), 2); /* no -o */
    snprintf(args, sizeof args, "preview %s -o %s", in, fx_tmp("x.jpg"));
    ck_assert_int_eq(run(args, NULL, 0), 2);
    snprintf(args, sizeof args, "preview %s -o %s --width 10", in, fx_tmp("x.png"));
    ck_assert_int_eq(run(args, NULL, 0), 2);
    snprintf(args, sizeof args, "preview %s -o %s", fx_tmp("missing.amp"), fx_tmp("x.png"));
    ck_assert_int_eq(run(args, NULL, 0), 2);
    f = fopen(fx_tmp("empty.amp"), "w");
    fputs("ampath-paths 1\n", f);
    fclose(f);
    snprintf(args, sizeof args, "preview %s -o %s", fx_tmp("empty.amp"), fx_tmp("x.png"));
    ck_assert_int_eq(run(args, NULL, 0), 2);
    remove(fx_tmp("empty.amp"));
    remove(in);
}
END_TEST

/* The renderer lives in the library: the library's pictures written into memory are the
 * tool's files byte for byte, PNG and SVG, at a legend size of each kind. */
START_TEST(library_pictures_are_the_tool_files_byte_for_byte)
{
    static const int widths[] = {400, 800, 1600};
    const char *in = fixture_file();
    amp_pathset ps;
    amp_error err;
    size_t w, n;
    int fmt;
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(amp_pathset_read_file(&ps, in, NULL), AMP_OK);
    for (w = 0; w < 3; w++)
        for (fmt = 0; fmt < 2; fmt++) {
            const char *out = fx_tmp(fmt ? "lib.svg" : "lib.png");
            char args[1024];
            unsigned char *d;
            amp_buf b;
            amp_preview_stats st;
            snprintf(args, sizeof args, "preview %s -o %s --width %d", in, out, widths[w]);
            ck_assert_int_eq(run(args, NULL, 0), 0);
            d = slurp(out, &n);
            amp_buf_init(&b, NULL);
            amp_error_clear(&err);
            ck_assert_int_eq(fmt ? amp_preview_svg(&ps, widths[w], amp_buf_sink, &b, &st, &err)
                                 : amp_preview_png(&ps, widths[w], amp_buf_sink, &b, &st, &err),
                             AMP_OK);
            ck_assert_uint_eq(b.len, n);
            ck_assert_uint_eq(st.bytes, n);
            ck_assert_int_eq(st.height, widths[w] / 2 + 110);
            ck_assert_msg(memcmp(b.data, d, n) == 0, "width %d %s differs", widths[w], fmt ? "svg" : "png");
            amp_buf_free(&b);
            free(d);
            remove(out);
        }
    amp_pathset_free(&ps);
    remove(in);
}
END_TEST

/* A sink that fails once @p left bytes have gone through. */
typedef struct failsink {
    size_t left;
} failsink;
static amp_status fail_sink(void *user, const char *data, size_t len)
{
    failsink *f = user;
    (void)data;
    if (len > f->left)
        return AMP_ERR_IO;
    f->left -= len;
    return AMP_OK;
}

START_TEST(library_preview_reports_sink_memory_and_argument_errors)
{
    amp_pathset ps, empty;
    fx_failalloc fa;
    amp_error err;
    failsink fs;
    amp_buf b;
    amp_preview_stats st;
    amp_pathset_init(&ps, NULL);
    fx_rings(&ps, 0, 0, 4, 3, 48, 0.25);
    fs.left = 5000;
    amp_error_clear(&err);
    ck_assert_int_eq(amp_preview_png(&ps, 400, fail_sink, &fs, &st, &err), AMP_ERR_IO);
    ck_assert_int_eq(err.status, AMP_ERR_IO);
    ck_assert_uint_le(st.bytes, 5000);
    fs.left = 5000;
    ck_assert_int_eq(amp_preview_svg(&ps, 400, fail_sink, &fs, NULL, &err), AMP_ERR_IO);
    amp_buf_init(&b, NULL);
    ck_assert_int_eq(amp_preview_png(&ps, 100, amp_buf_sink, &b, NULL, &err), AMP_ERR_RANGE);
    ck_assert_ptr_nonnull(strstr(err.msg, "200..8000"));
    amp_pathset_init(&empty, NULL);
    ck_assert_int_eq(amp_preview_svg(&empty, 400, amp_buf_sink, &b, NULL, &err), AMP_ERR_ARG);
    ck_assert_uint_eq(b.len, 0);
    /* memory through the path set's allocator: a failing one gives AMP_ERR_NOMEM and writes nothing */
    fx_failalloc_init(&fa, 0);
    ps.alloc = &fa.a;
    ck_assert_int_eq(amp_preview_png(&ps, 400, amp_buf_sink, &b, NULL, &err), AMP_ERR_NOMEM);
    ck_assert_uint_eq(b.len, 0);
    ps.alloc = NULL;
    amp_pathset_free(&ps);
}
END_TEST

/* The fractions a progress report heard. */
typedef struct heard {
    double last;
    size_t n;
    int rising;
} heard;

static void hear(void *user, double fraction)
{
    heard *h = user;
    h->rising = h->rising && fraction > h->last && fraction <= 1.0;
    h->last = fraction;
    h->n++;
}

/* A picture drawn with a progress report is the picture drawn without one, byte for byte; the report rises
 * through a few hundred steps at most to the whole of both views. */
START_TEST(preview_progress_reports_the_vertices_walked_and_changes_no_byte)
{
    amp_pathset ps;
    amp_preview_opts o;
    amp_error err;
    int fmt;
    amp_pathset_init(&ps, NULL);
    fx_helix(&ps, 300, 40); /* reports come after whole paths: many paths */
    for (fmt = 0; fmt < 2; fmt++) {
        amp_buf plain, reported;
        heard h = {0.0, 0, 1};
        amp_buf_init(&plain, NULL);
        amp_buf_init(&reported, NULL);
        amp_preview_opts_default(&o);
        ck_assert_int_eq(o.width, 1600);
        o.width = 800;
        o.progress = hear;
        o.progress_user = &h;
        ck_assert_int_eq(fmt ? amp_preview_svg(&ps, 800, amp_buf_sink, &plain, NULL, &err)
                             : amp_preview_png(&ps, 800, amp_buf_sink, &plain, NULL, &err),
                         AMP_OK);
        ck_assert_int_eq(fmt ? amp_preview_svg_opts(&ps, &o, amp_buf_sink, &reported, NULL, &err)
                             : amp_preview_png_opts(&ps, &o, amp_buf_sink, &reported, NULL, &err),
                         AMP_OK);
        ck_assert_uint_eq(plain.len, reported.len);
        ck_assert(memcmp(plain.data, reported.data, plain.len) == 0);
        ck_assert_msg(h.n >= 100 && h.n <= 300, "%lu reports", (unsigned long)h.n);
        ck_assert(h.rising);
        ck_assert_double_eq_tol(h.last, 1.0, 1e-12);
        amp_buf_free(&plain);
        amp_buf_free(&reported);
    }
    ck_assert_int_eq(amp_preview_png_opts(&ps, NULL, amp_buf_sink, NULL, NULL, &err), AMP_ERR_ARG);
    amp_pathset_free(&ps);
}
END_TEST

/* On a terminal, `preview` draws its bar, and a job of 16 MB or more a bar while it is read (the commands
 * that read a job all read it through one function); into a pipe, neither. */
START_TEST(preview_and_the_reading_of_a_large_job_draw_bars_on_a_terminal_only)
{
    amp_pathset ps;
    const char *in = fx_tmp("big.amp"), *out = fx_tmp("big.png"), *small = fx_tmp("small.amp");
    char args[1024], *err = malloc(1 << 16);
    FILE *f;
    long size;
    if (!getenv("AMP_TOOL"))
        return;
    ck_assert_ptr_nonnull(err);
    amp_pathset_init(&ps, NULL);
    fx_helix(&ps, 100, 4000);
    ck_assert_int_eq(amp_pathset_write_file(&ps, in, NULL, NULL), AMP_OK);
    f = fopen(in, "rb");
    ck_assert_ptr_nonnull(f);
    fseek(f, 0, SEEK_END);
    size = ftell(f);
    fclose(f);
    ck_assert_int_ge(size, 16L << 20);
    snprintf(args, sizeof args, "preview %s -o %s --width 400", in, out);
    ck_assert_int_eq(fx_run_tool_tty(args, err, 1 << 16), 0);
    ck_assert_msg(strstr(err, "reading      [") && strstr(err, "preview      ["), "no bars on the terminal: '%.300s'",
                  err);
    ck_assert_int_eq(fx_run_tool_ex(args, NULL, 1, err, 1 << 16), 0);
    ck_assert_msg(!strstr(err, "["), "a bar in a pipe: '%.300s'", err);
    /* a small job is read without a bar (the command's own bar stays) */
    amp_pathset_free(&ps);
    amp_pathset_init(&ps, NULL);
    fx_helix(&ps, 10, 100);
    ck_assert_int_eq(amp_pathset_write_file(&ps, small, NULL, NULL), AMP_OK);
    snprintf(args, sizeof args, "preview %s -o %s --width 400", small, out);
    ck_assert_int_eq(fx_run_tool_tty(args, err, 1 << 16), 0);
    ck_assert_msg(!strstr(err, "reading") && strstr(err, "preview      ["), "bars of a small job: '%.300s'", err);
    remove(in);
    remove(small);
    remove(out);
    free(err);
    amp_pathset_free(&ps);
}
END_TEST

static Suite *preview_suite(void)
{
    Suite *s = suite_create("preview");
    TCase *tc = tcase_create("preview");
    tcase_add_test(tc, png_is_valid_with_requested_size_and_coloured_paths);
    tcase_add_test(tc, png_reader_rejects_corrupted_files);
    tcase_add_test(tc, svg_is_well_formed_with_one_group_of_polylines_per_view);
    tcase_add_test(tc, preview_bad_usage_exits_2);
    tcase_add_test(tc, library_pictures_are_the_tool_files_byte_for_byte);
    tcase_add_test(tc, library_preview_reports_sink_memory_and_argument_errors);
    tcase_add_test(tc, preview_progress_reports_the_vertices_walked_and_changes_no_byte);
    tcase_add_test(tc, preview_and_the_reading_of_a_large_job_draw_bars_on_a_terminal_only);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(preview_suite)
