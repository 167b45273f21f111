/* timing.c: Server-Timing steps (timing.h). */
#include "timing.h"

#include <stdio.h>

#include "clock.h"

double srv_timing_step(srv_timing *t, const char *name, double t0)
{
    double now = glint_now();
    if (t && t->n < SRV_TIMING_MAX) {
        t->name[t->n] = name;
        t->ms[t->n++] = 1e3 * (now - t0);
    }
    return now;
}

void srv_timing_format(const srv_timing *t, char *buf, size_t len)
{
    size_t at = 0;
    if (len)
        buf[0] = '\0';
    for (int i = 0; i < t->n && at < len; i++) {
        int k = snprintf(buf + at, len - at, "%s%s;dur=%.3f", i ? ", " : "", t->name[i],
                         t->ms[i]);
        if (k < 0 || (size_t)k >= len - at) {
            buf[at] = '\0';
            break;
        }
        at += (size_t)k;
    }
}
