/* The held-path check's failing runs, for ampath support's pads (lib/support.c); see amp_check_hold in check.h. */
#ifndef AMP_CHECK_HOLD_INTERNAL_H
#define AMP_CHECK_HOLD_INTERNAL_H

#include <stdint.h>

#include "ampath/check.h"

/* One sample of an extruding segment; s is its arc position on its path. */
typedef struct amp_hold_sample {
    amp_vec3 p;
    double half; /* vertical half-extent of the bead */
    double s;
    uint32_t path;
} amp_hold_sample;

/* Called for every unheld run, failing or not (a bridge or a tip: samples [0, n) of one object path, in
 * order); its error stops the scan. */
typedef amp_status (*amp_hold_fail_fn)(void *user, const amp_hold_sample *run, size_t n, amp_error *err);

/* amp_check_hold(), calling @p fail (NULL: none) for each unheld run as it is judged. */
amp_status amp_hold_scan(const amp_pathset *ps, const amp_hold_opts *o, amp_hold_report *rep, amp_hold_fail_fn fail,
                         void *user, amp_error *err);

#endif
