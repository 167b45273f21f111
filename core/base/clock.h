/* clock.h: clocks and timestamps shared by core, the command line and the
 * daemon.
 *
 * glint_now() is a monotonic clock in seconds (for durations: never goes
 * back, unaffected by the wall clock being set).  Timestamps are RFC 3339
 * in UTC.  Every function is thread-safe and cannot fail. */
#ifndef GLINT_CLOCK_H
#define GLINT_CLOCK_H

#include <time.h>

#define GLINT_TIME_LEN 32

/* Monotonic time in seconds (CLOCK_MONOTONIC). */
double glint_now(void);

/* `t` as "2024-05-01T12:00:00Z" (OUT: buf[GLINT_TIME_LEN]). */
void glint_time_iso(time_t t, char buf[GLINT_TIME_LEN]);

/* The current wall-clock time with milliseconds, "2024-05-01T12:00:00.123Z"
 * (OUT: buf[GLINT_TIME_LEN]). */
void glint_time_iso_ms(char buf[GLINT_TIME_LEN]);

#endif
