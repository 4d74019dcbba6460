/* The internal stable sorts (lib/keysort.h): the checkers' (k1, k2) key sort and the mesh's radix sort by
 * uint32_t fields; ascending, equal keys in their first order. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "../lib/keysort.h"
#include "testutil.h"

/* The reference: qsort with the index as the last tie-break is the stable order. */
static int cmp_ref(const void *p, const void *q)
{
    const amp_skey *a = p, *b = q;
    if (a->k1 != b->k1)
        return a->k1 < b->k1 ? -1 : 1;
    if (a->k2 != b->k2)
        return a->k2 < b->k2 ? -1 : 1;
    return a->i < b->i ? -1 : (a->i > b->i ? 1 : 0);
}

START_TEST(sorts_like_a_stable_sort_at_every_size)
{
    static const size_t sizes[] = {0, 1, 2, 15, 16, 17, 31, 33, 100, 1000, 4097};
    unsigned long s = 99;
    size_t c, i;
    for (c = 0; c < sizeof sizes / sizeof sizes[0]; c++) {
        size_t n = sizes[c];
        amp_skey *k = malloc((n + 1) * sizeof *k), *tmp = malloc((n + 1) * sizeof *tmp), *ref = malloc((n + 1) * sizeof *ref);
        ck_assert(k && tmp && ref);
        for (i = 0; i < n; i++) {
            s = s * 6364136223846793005UL + 1442695040888963407UL;
            k[i].k1 = (double)((s >> 33) % 13) - 6.0; /* many equal keys, negative and -0.0 among them */
            k[i].k2 = (s >> 40) % 3 == 0 ? -0.0 : (double)((s >> 45) % 4);
            k[i].i = i;
            ref[i] = k[i];
        }
        amp_skey_sort(k, tmp, n);
        qsort(ref, n, sizeof *ref, cmp_ref);
        for (i = 0; i < n; i++)
            ck_assert_msg(k[i].i == ref[i].i, "size %lu, position %lu: item %lu, want %lu", (unsigned long)n,
                          (unsigned long)i, (unsigned long)k[i].i, (unsigned long)ref[i].i);
        free(k);
        free(tmp);
        free(ref);
    }
}
END_TEST

/* A record like the mesh's: two keys, a payload, odd size (20 bytes). */
typedef struct rrec {
    uint32_t a, b, pay, pad, idx;
} rrec;

static int cmp_rrec(const void *p, const void *q)
{
    const rrec *x = p, *y = q;
    if (x->a != y->a)
        return x->a < y->a ? -1 : 1;
    if (x->b != y->b)
        return x->b < y->b ? -1 : 1;
    return x->idx < y->idx ? -1 : (x->idx > y->idx ? 1 : 0);
}

START_TEST(radix_sorts_like_a_stable_sort_over_every_digit)
{
    static const size_t sizes[] = {0, 1, 2, 3, 100, 5000};
    static const size_t off[2] = {offsetof(rrec, a), offsetof(rrec, b)};
    /* keys spread over all 32 bits, a narrow range (digits shared by all: skipped passes), and many ties */
    static const uint32_t masks[] = {0xffffffffu, 0x000007ffu, 0x00000003u, 0xf0000001u};
    unsigned long s = 7;
    size_t c, m, i;
    for (m = 0; m < sizeof masks / sizeof masks[0]; m++)
        for (c = 0; c < sizeof sizes / sizeof sizes[0]; c++) {
            size_t n = sizes[c];
            rrec *r = malloc((n + 1) * sizeof *r), *tmp = malloc((n + 1) * sizeof *tmp),
                 *ref = malloc((n + 1) * sizeof *ref);
            ck_assert(r && tmp && ref);
            for (i = 0; i < n; i++) {
                s = s * 6364136223846793005UL + 1442695040888963407UL;
                r[i].a = (uint32_t)(s >> 32) & masks[m];
                s = s * 6364136223846793005UL + 1442695040888963407UL;
                r[i].b = (uint32_t)(s >> 32) & masks[(m + 1) % 4];
                r[i].pay = (uint32_t)(r[i].a ^ r[i].b);
                r[i].pad = 0;
                r[i].idx = (uint32_t)i;
                ref[i] = r[i];
            }
            amp_radix_u32(r, tmp, n, sizeof *r, off, 2);
            qsort(ref, n, sizeof *ref, cmp_rrec);
            for (i = 0; i < n; i++)
                ck_assert_msg(r[i].idx == ref[i].idx && r[i].pay == (r[i].a ^ r[i].b),
                              "mask %lu size %lu position %lu: item %lu, want %lu", (unsigned long)m, (unsigned long)n,
                              (unsigned long)i, (unsigned long)r[i].idx, (unsigned long)ref[i].idx);
            free(r);
            free(tmp);
            free(ref);
        }
}
END_TEST

static Suite *keysort_suite(void)
{
    Suite *s = suite_create("keysort");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, sorts_like_a_stable_sort_at_every_size);
    tcase_add_test(tc, radix_sorts_like_a_stable_sort_over_every_digit);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(keysort_suite)
