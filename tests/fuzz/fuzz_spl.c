/* libFuzzer target: the .spl reader must reject or accept any bytes without undefined behaviour,
 * and whatever it accepts must validate, evaluate and write. */
#include <stddef.h>
#include <stdint.h>

#include "ampath/ampath.h"

static amp_status null_sink(void *user, const char *data, size_t len)
{
    (void)user;
    (void)data;
    (void)len;
    return AMP_OK;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    amp_spline *list;
    size_t n, i;
    if (amp_spline_parse((const char *)data, size, NULL, &list, &n, NULL) != AMP_OK)
        return 0;
    for (i = 0; i < n; i++) {
        double p[3] = {0.5, 0.5, 0.5};
        amp_vec3 out, d[125];
        if (amp_spline_validate(&list[i], NULL) != AMP_OK)
            __builtin_trap();
        amp_spline_eval(&list[i], p, &out, NULL);
        amp_spline_eval_derivs(&list[i], p, 2, d, NULL);
        amp_spline_write(&list[i], 1, null_sink, NULL, NULL);
    }
    amp_spline_list_free(NULL, list, n);
    return 0;
}
