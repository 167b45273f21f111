/* timing.h: the steps of a request's work, sent to the client as a
 * Server-Timing header (W3C Server Timing: "decode;dur=1.234,
 * store;dur=0.912", milliseconds), which browsers' developer tools show and
 * tests/bench/bench_daemon.py reads.  A handler times its own steps and
 * passes the struct down to the services it calls. */
#ifndef GLINTD_TIMING_H
#define GLINTD_TIMING_H

#include <stddef.h>

#define SRV_TIMING_MAX 12

typedef struct srv_timing {
    int n;
    const char *name[SRV_TIMING_MAX]; /* static tokens */
    double ms[SRV_TIMING_MAX];
} srv_timing;

/* Record step `name` begun at t0 (seconds, glint_now()); returns the time
 * now, the next step's start.  Steps beyond SRV_TIMING_MAX are dropped; a
 * NULL t records nothing but still returns the time. */
double srv_timing_step(srv_timing *t, const char *name, double t0);

/* The header's value (OUT: buf; "" when no step was recorded). */
void srv_timing_format(const srv_timing *t, char *buf, size_t len);

#endif
