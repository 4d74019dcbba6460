/* The PNG encoder of the previews (no image library): CRC-32, a deflate stream of literal and run-length
 * matches, chunks. Split out of preview.c, which draws the raster. */
#include <string.h>

#include "preview_internal.h"

unsigned long amp_preview_crc32(unsigned long crc, const unsigned char *p, size_t n)
{
    size_t i;
    int k;
    crc = ~crc & 0xffffffffUL;
    for (i = 0; i < n; i++) {
        crc ^= p[i];
        for (k = 0; k < 8; k++)
            crc = (crc >> 1) ^ (0xedb88320UL & (0UL - (crc & 1UL)));
    }
    return ~crc & 0xffffffffUL;
}

typedef struct bitw {
    const amp_allocator *a;
    unsigned char *buf;
    size_t len, cap;
    unsigned long acc;
    int nbits;
    int oom;
} bitw;

static void bw_byte(bitw *b, unsigned char c)
{
    if (b->len == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 65536;
        unsigned char *p = amp_realloc_array(b->a, b->buf, cap, 1);
        if (!p) {
            b->oom = 1;
            return;
        }
        b->buf = p;
        b->cap = cap;
    }
    b->buf[b->len++] = c;
}

/* Append @p n bits of @p v, least significant first (deflate's bit order). */
static void bw_bits(bitw *b, unsigned long v, int n)
{
    b->acc |= v << b->nbits;
    b->nbits += n;
    while (b->nbits >= 8) {
        bw_byte(b, (unsigned char)(b->acc & 0xff));
        b->acc >>= 8;
        b->nbits -= 8;
    }
}

/* Huffman codes go most significant bit first. */
static void bw_code(bitw *b, unsigned v, int n)
{
    unsigned r = 0;
    int i;
    for (i = 0; i < n; i++)
        r |= ((v >> i) & 1u) << (n - 1 - i);
    bw_bits(b, r, n);
}

/* Fixed Huffman literal/length symbol (RFC 1951 §3.2.6). */
static void put_sym(bitw *b, unsigned s)
{
    if (s < 144)
        bw_code(b, 0x30 + s, 8);
    else if (s < 256)
        bw_code(b, 0x190 + (s - 144), 9);
    else if (s < 280)
        bw_code(b, s - 256, 7);
    else
        bw_code(b, 0xc0 + (s - 280), 8);
}

static const unsigned short DIST_BASE[30] = {1,   2,   3,   4,   5,   7,    9,    13,   17,   25,
                                             33,  49,  65,  97,  129, 193,  257,  385,  513,  769,
                                             1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
static const unsigned char DIST_EXTRA[30] = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6,
                                             6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

/* A match of @p len (3..258) at distance @p dist (1..32768), RFC 1951 §3.2.5. */
static void put_match(bitw *b, unsigned len, unsigned dist)
{
    static const unsigned short base[] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                          31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
    static const unsigned char extra[] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                          2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
    int i = 28, d = 29;
    while (base[i] > len)
        i--;
    put_sym(b, 257 + (unsigned)i);
    if (extra[i])
        bw_bits(b, len - base[i], extra[i]);
    while (DIST_BASE[d] > dist)
        d--;
    bw_code(b, (unsigned)d, 5); /* fixed distance codes are 5 bits */
    if (DIST_EXTRA[d])
        bw_bits(b, dist - DIST_BASE[d], DIST_EXTRA[d]);
}

/*
 * zlib stream of @p data: one fixed-Huffman deflate block. Instead of a
 * general LZ77 search, each position tries a few distances that pay off in
 * pictures: the previous byte and pixel (runs, flat colour) and the same
 * place one or two rows above (@p row bytes per row, filter byte included).
 */
static void deflate_rle(bitw *b, const unsigned char *data, size_t n, size_t row)
{
    size_t cand[7], ncand = 0, i = 0, k;
    unsigned long s1 = 1, s2 = 0;
    size_t try_d[7];
    try_d[0] = 1;
    try_d[1] = 3;
    try_d[2] = 6;
    try_d[3] = row;
    try_d[4] = row - 3;
    try_d[5] = row + 3;
    try_d[6] = 2 * row;
    for (k = 0; k < 7; k++)
        if (try_d[k] >= 1 && try_d[k] <= 32768)
            cand[ncand++] = try_d[k];
    bw_byte(b, 0x78); /* CM 8, 32K window */
    bw_byte(b, 0x01); /* FCHECK: 0x7801 % 31 == 0 */
    bw_bits(b, 1, 1); /* BFINAL */
    bw_bits(b, 1, 2); /* BTYPE 01: fixed Huffman */
    while (i < n) {
        size_t best = 0, bestd = 0, c;
        for (c = 0; c < ncand; c++) {
            size_t d = cand[c], len = 0;
            if (d > i)
                continue;
            while (i + len < n && len < 258 && data[i + len] == data[i + len - d])
                len++;
            if (len > best) {
                best = len;
                bestd = d;
            }
        }
        if (best >= 3) {
            put_match(b, (unsigned)best, (unsigned)bestd);
            i += best;
        } else {
            put_sym(b, data[i]);
            i++;
        }
    }
    put_sym(b, 256);
    if (b->nbits)
        bw_bits(b, 0, 8 - b->nbits);
    for (k = 0; k < n; k++) {
        s1 = (s1 + data[k]) % 65521UL;
        s2 = (s2 + s1) % 65521UL;
    }
    bw_byte(b, (unsigned char)(s2 >> 8));
    bw_byte(b, (unsigned char)s2);
    bw_byte(b, (unsigned char)(s1 >> 8));
    bw_byte(b, (unsigned char)s1);
}

static void put_be32(pv_out *o, unsigned long v)
{
    unsigned char c[4];
    c[0] = (unsigned char)(v >> 24);
    c[1] = (unsigned char)(v >> 16);
    c[2] = (unsigned char)(v >> 8);
    c[3] = (unsigned char)v;
    pv_put(o, c, 4);
}

static void put_chunk(pv_out *o, const char *type, const unsigned char *data, size_t n)
{
    unsigned long crc = amp_preview_crc32(0, (const unsigned char *)type, 4);
    crc = amp_preview_crc32(crc, data, n);
    put_be32(o, (unsigned long)n);
    pv_put(o, type, 4);
    pv_put(o, data, n);
    put_be32(o, crc);
}

int amp_pv_write_png(pv_out *o, const raster *r, const amp_allocator *a)
{
    static const unsigned char sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    unsigned char ihdr[13];
    size_t stride = 3 * (size_t)r->w, y, x, n = (stride + 1) * (size_t)r->h, off;
    unsigned char *filt = amp_alloc(a, n);
    bitw b;
    if (!filt)
        return -1;
    /* filter "Up" on every row: identical rows and flat areas become zeros */
    for (y = 0; y < (size_t)r->h; y++) {
        unsigned char *f = filt + y * (stride + 1);
        const unsigned char *cur = r->rgb + y * stride, *prev = y ? cur - stride : NULL;
        f[0] = 2;
        for (x = 0; x < stride; x++)
            f[1 + x] = (unsigned char)(cur[x] - (prev ? prev[x] : 0));
    }
    memset(&b, 0, sizeof b);
    b.a = a;
    deflate_rle(&b, filt, n, stride + 1);
    amp_free(a, filt);
    if (b.oom) {
        amp_free(a, b.buf);
        return -1;
    }
    for (x = 0; x < 4; x++) {
        ihdr[x] = (unsigned char)((unsigned long)r->w >> (24 - 8 * x));
        ihdr[4 + x] = (unsigned char)((unsigned long)r->h >> (24 - 8 * x));
    }
    ihdr[8] = 8;  /* bit depth */
    ihdr[9] = 2;  /* colour type RGB */
    ihdr[10] = 0; /* deflate */
    ihdr[11] = 0; /* adaptive filtering */
    ihdr[12] = 0; /* no interlace */
    pv_put(o, sig, 8);
    put_chunk(o, "IHDR", ihdr, 13);
    /* IDAT chunks of at most 1 MiB */
    for (off = 0; o->st == AMP_OK && off < b.len;) {
        size_t m = b.len - off > (1u << 20) ? (1u << 20) : b.len - off;
        put_chunk(o, "IDAT", b.buf + off, m);
        off += m;
    }
    put_chunk(o, "IEND", NULL, 0);
    amp_free(a, b.buf);
    return 0;
}

