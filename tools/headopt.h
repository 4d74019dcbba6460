/* headopt.h — the print-head options shared by order, check, support and mdr (docs/interfaces.md §2, §4). */
#ifndef AMP_TOOLS_HEADOPT_H
#define AMP_TOOLS_HEADOPT_H

#include "cli.h"

/* Option help lines, for the usage strings. */
#define HEADOPT_HELP                                                                                                 \
    "  --z-offs Z      tip of the head cone above the printed point, mm (default 0.5)\n"                             \
    "  --theta DEG     half-angle of the head cone from the vertical, degrees, in (0, 90) (default 72 = 0.4 pi)\n"

/* Turn the CLI values (mm, degrees) into a validated amp_head; prints the reason and returns CLI_USAGE if bad. */
static inline int headopt_make(const char *cmd, double z_offs, double theta_deg, amp_head *h)
{
    amp_error err;
    amp_error_clear(&err);
    h->z_offs = z_offs;
    h->theta = theta_deg * AMP_PI / 180.0;
    if (amp_head_validate(h, &err) != AMP_OK)
        return cli_fail_err(cmd, &err);
    return CLI_OK;
}

#endif
