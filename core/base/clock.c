/* clock.c: clocks and timestamps (clock.h). */
#include "clock.h"

#include <stdio.h>

double glint_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void glint_time_iso(time_t t, char buf[GLINT_TIME_LEN])
{
    struct tm tm;
    if (!gmtime_r(&t, &tm) || strftime(buf, GLINT_TIME_LEN, "%Y-%m-%dT%H:%M:%SZ", &tm) == 0)
        snprintf(buf, GLINT_TIME_LEN, "1970-01-01T00:00:00Z");
}

void glint_time_iso_ms(char buf[GLINT_TIME_LEN])
{
    struct timespec ts;
    struct tm tm;
    size_t n;

    clock_gettime(CLOCK_REALTIME, &ts);
    if (!gmtime_r(&ts.tv_sec, &tm) ||
        (n = strftime(buf, GLINT_TIME_LEN, "%Y-%m-%dT%H:%M:%S", &tm)) == 0 || n > 24) {
        snprintf(buf, GLINT_TIME_LEN, "1970-01-01T00:00:00.000Z");
        return;
    }
    snprintf(buf + n, GLINT_TIME_LEN - n, ".%03dZ", (int)(ts.tv_nsec / 1000000) % 1000);
}
