/* Stable bottom-up merge sort of amp_skey (lib/keysort.h): insertion sort on runs of 16, then merges. */
#include "keysort.h"

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
