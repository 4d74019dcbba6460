/* libFuzzer target: the .amp parser (SPEC §3), and a write/parse round trip of what it accepted. */
#include <stddef.h>
#include <stdint.h>

#include "ampath/ampath.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    amp_pathset ps, back;
    amp_error err;
    amp_buf buf;
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
