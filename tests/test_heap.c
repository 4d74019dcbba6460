/* The library's one binary heap (lib/heap.h): best first, equal items in a fixed order, no item lost. */
#include <stdint.h>
#include <stdlib.h>

#include "../lib/heap.h"
#include "testutil.h"

typedef struct item {
    double key;
    uint32_t id;
} item;

static int key_less(const void *a, const void *b, const void *ctx)
{
    (void)ctx;
    return ((const item *)a)->key < ((const item *)b)->key;
}

START_TEST(pops_in_order_of_the_better_relation)
{
    amp_heap h;
    item it, prev;
    uint32_t i, seen = 0;
    unsigned long s = 12345;
    amp_heap_init(&h, NULL, sizeof(item), key_less, NULL);
    for (i = 0; i < 1000; i++) {
        s = s * 6364136223846793005UL + 1442695040888963407UL;
        it.key = (double)((s >> 33) % 97); /* many equal keys */
        it.id = i;
        ck_assert_int_eq(amp_heap_push(&h, &it), AMP_OK);
    }
    ck_assert_uint_eq(h.n, 1000);
    ck_assert(amp_heap_pop(&h, &prev));
    seen++;
    while (amp_heap_pop(&h, &it)) {
        ck_assert_msg(prev.key <= it.key, "%g popped before %g", prev.key, it.key);
        prev = it;
        seen++;
    }
    ck_assert_uint_eq(seen, 1000);
    ck_assert_int_eq(amp_heap_pop(&h, &it), 0);
    amp_heap_free(&h);
}
END_TEST

/* The sift rules of lib/heap.h fix where equal items go: the same pushes give the same pops. */
START_TEST(equal_items_come_out_in_a_fixed_order)
{
    amp_heap h;
    item it;
    static const double keys[] = {2, 1, 1, 3, 1, 2, 1};
    static const uint32_t want[] = {1, 6, 4, 2, 5, 0, 3}; /* where the sift rules put them */
    size_t i;
    amp_heap_init(&h, NULL, sizeof(item), key_less, NULL);
    for (i = 0; i < 7; i++) {
        it.key = keys[i];
        it.id = (uint32_t)i;
        ck_assert_int_eq(amp_heap_push(&h, &it), AMP_OK);
    }
    for (i = 0; i < 7; i++) {
        ck_assert(amp_heap_pop(&h, &it));
        ck_assert_uint_eq(it.id, want[i]);
    }
    amp_heap_free(&h);
}
END_TEST

static Suite *heap_suite(void)
{
    Suite *s = suite_create("heap");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, pops_in_order_of_the_better_relation);
    tcase_add_test(tc, equal_items_come_out_in_a_fixed_order);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(heap_suite)
