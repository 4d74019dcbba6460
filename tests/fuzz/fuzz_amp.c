/* libFuzzer target: the .amp parser (docs/interfaces.md §3), and a write/parse round trip of what it accepted. */
#include <limits.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "ampath/ampath.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    amp_pathset ps, back;
    amp_error err;
    amp_buf buf;
#if defined(AMP_FUZZ_PLANT_TRAP)
    /* make fuzz-selftest: a planted crash on any input that looks like a path file (every seed) */
    if (size >= 6 && memcmp(data, "ampath", 6) == 0)
        __builtin_trap();
#elif defined(AMP_FUZZ_PLANT_UBSAN)
    /* make fuzz-selftest: planted undefined behaviour (signed overflow) on the same inputs */
    if (size >= 6 && memcmp(data, "ampath", 6) == 0) {
        volatile int big = INT_MAX;
        int sum = big + (int)size;
        if (sum == 42)
            return 1;
    }
#endif
    amp_pathset_init(&ps, NULL);
    if (amp_pathset_parse(&ps, (const char *)data, size, &err) == AMP_OK) {
        amp_pathset_init(&back, NULL);
        amp_buf_init(&buf, NULL);
        (void)amp_pathset_length(&ps, -1);
        (void)amp_pathset_volume(&ps, -1);
        if (amp_pathset_write(&ps, "fuzz", amp_buf_sink, &buf, &err) == AMP_OK &&
            amp_pathset_parse(&back, buf.data, buf.len, &err) != AMP_OK)
            __builtin_trap(); /* what the writer emits must parse again */
        amp_buf_free(&buf);
        amp_pathset_free(&back);
    }
    amp_pathset_free(&ps);
    return 0;
}
