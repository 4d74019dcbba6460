/* The checkers' stable key sort (lib/keysort.h): ascending by (k1, k2), equal keys in their first order. */
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

static Suite *keysort_suite(void)
{
    Suite *s = suite_create("keysort");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, sorts_like_a_stable_sort_at_every_size);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(keysort_suite)
