/*
 * safeend.c — what a careful host does when a print is stopped by a signal
 * (systemctl stop) or a cancel: the heaters must not stay on over an
 * unattended part. Heaters and fan off, no motion: the nozzle stays where the
 * job left it, which is what --resume-from's preamble assumes (docs/bridge.md).
 */
#include <string.h>

#include "daemon.h"

static const char *const safe_end_lines[] = {"M104 S0", "M140 S0", "M107"};
#define NSAFE ((int)(sizeof safe_end_lines / sizeof safe_end_lines[0]))

int br_safe_end(br_session *s, double max_s, volatile sig_atomic_t *sig, int sig_limit)
{
    br_stop saved = s->stop;
    char text[sizeof s->stop_text];
    int had = s->have_job, i = 0, rc = 0;
    long last = 0;
    double t0 = br_now();
    if (s->link.fd < 0 || s->p.state != AMP_PROTO_RUNNING)
        return 0; /* reset, shut down or gone: the firmware has turned its heaters off, or cannot hear us */
    memcpy(text, s->stop_text, sizeof text);
    /* The session sends only while a job runs: run it without a job for these lines, then restore the
       job's outcome (a reset or shutdown meanwhile shows up as s->stop changing). */
    s->stop = BR_RUNNING;
    s->have_job = 0;
    while (br_now() - t0 < max_s && s->stop == BR_RUNNING && s->p.state == AMP_PROTO_RUNNING && s->link.fd >= 0) {
        if (sig && *sig > sig_limit) {
            rc = -1;
            break;
        }
        if (i < NSAFE && amp_proto_can_submit(&s->p)) {
            long n = 0;
            if (amp_proto_submit(&s->p, safe_end_lines[i], strlen(safe_end_lines[i]), &n, NULL) != AMP_OK)
                break;
            last = n;
            i++;
            continue;
        }
        if (i == NSAFE && s->p.acked >= last && s->txlen == 0) {
            rc = 1;
            break;
        }
        br_session_step(s, NULL, 0, 50);
    }
    if (s->cfg.log) {
        fprintf(s->cfg.log, "%.3f safe end (M104 S0, M140 S0, M107): %s\n", br_now() - s->t_start,
                rc == 1 ? "acknowledged" : "not confirmed");
        fflush(s->cfg.log);
    }
    s->stop = saved;
    s->have_job = had;
    memcpy(s->stop_text, text, sizeof text);
    return rc;
}
