/* Stable bottom-up merge sort of amp_skey (lib/keysort.h): insertion sort on runs of 16, then merges; a stable
 * radix sort of records by uint32_t fields. */
#include "keysort.h"

#include <stdlib.h>
#include <string.h>

#define RUN 16

static int before(const amp_skey *a, const amp_skey *b)
{
    return a->k1 < b->k1 || (a->k1 == b->k1 && a->k2 < b->k2);
}

static void insertion(amp_skey *k, size_t n)
{
    size_t i, j;
    for (i = 1; i < n; i++) {
        amp_skey x = k[i];
        for (j = i; j > 0 && before(&x, &k[j - 1]); j--)
            k[j] = k[j - 1];
        k[j] = x;
    }
}

/* Merge the sorted runs a[0, na) and b[0, nb) into out; on equal keys a's come first (stable). */
static void merge(const amp_skey *a, size_t na, const amp_skey *b, size_t nb, amp_skey *out)
{
    size_t i = 0, j = 0, o = 0;
    while (i < na && j < nb)
        out[o++] = before(&b[j], &a[i]) ? b[j++] : a[i++];
    while (i < na)
        out[o++] = a[i++];
    while (j < nb)
        out[o++] = b[j++];
}

void amp_skey_sort(amp_skey *k, amp_skey *tmp, size_t n)
{
    amp_skey *src = k, *dst = tmp, *t;
    size_t w, s;
    for (s = 0; s < n; s += RUN)
        insertion(k + s, n - s < RUN ? n - s : RUN);
    for (w = RUN; w < n; w *= 2) {
        for (s = 0; s < n; s += 2 * w) {
            size_t na = n - s < w ? n - s : w, nb = n - s - na < w ? n - s - na : w;
            merge(src + s, na, src + s + na, nb, dst + s);
        }
        t = src;
        src = dst;
        dst = t;
    }
    if (src != k)
        memcpy(k, src, n * sizeof *k);
}

#define DIGIT_BITS 11
#define DIGITS (1u << DIGIT_BITS)

static uint32_t field_at(const unsigned char *rec, size_t off)
{
    uint32_t v;
    memcpy(&v, rec + off, sizeof v);
    return v;
}

void amp_radix_u32(void *base, void *tmp, size_t n, size_t size, const size_t *off, int nkeys)
{
    unsigned char *src = base, *dst = tmp, *t;
    size_t count[DIGITS], i, d;
    int f, shift;
    /* least significant first: every pass is stable, so earlier passes break the later ones' ties */
    for (f = nkeys - 1; f >= 0; f--)
        for (shift = 0; shift < 32; shift += DIGIT_BITS) {
            size_t sum = 0;
            memset(count, 0, sizeof count);
            for (i = 0; i < n; i++)
                count[(field_at(src + i * size, off[f]) >> shift) & (DIGITS - 1)]++;
            if (n == 0 || count[(field_at(src, off[f]) >> shift) & (DIGITS - 1)] == n)
                continue; /* one digit for all: the order stands */
            for (d = 0; d < DIGITS; d++) {
                size_t c = count[d];
                count[d] = sum;
                sum += c;
            }
            for (i = 0; i < n; i++) {
                const unsigned char *r = src + i * size;
                memcpy(dst + size * count[(field_at(r, off[f]) >> shift) & (DIGITS - 1)]++, r, size);
            }
            t = src;
            src = dst;
            dst = t;
        }
    if (src != (unsigned char *)base)
        memcpy(base, src, n * size);
}

void amp_radix_sort(const amp_allocator *al, void *base, size_t n, size_t size, const size_t *off, int nkeys,
                    int (*cmp)(const void *, const void *))
{
    void *tmp = n > 1 ? amp_alloc(al, n * size) : NULL;
    if (tmp)
        amp_radix_u32(base, tmp, n, size, off, nkeys);
    else if (n > 1)
        qsort(base, n, size, cmp);
    amp_free(al, tmp);
}
