/* admit.h: admission of expensive work (renders, G-buffers, fits) against a
 * memory budget and a number of slots.
 *
 * Each piece of work states an upper bound of the memory it will take
 * (render_peak_bytes, method_fit_bytes, ...) and holds that much of the
 * budget, and one slot, while it runs.  A request that cannot enter now is
 * waits a little (wait_s, glintd --work-wait) and is refused when no room
 * was made by then (the API answers 503 with Retry-After); a background job
 * waits its turn.  What can never fit, a bound beyond the whole budget, is
 * refused as too large (413), naming the budget.  So the memory of the work
 * in flight stays under the budget, whatever the clients send.
 *
 * Time.  Each piece of work also states an estimate of its time
 * (render_material_cost, method_fit_seconds, ...: seconds of one core at
 * measured rates); admit_cost refuses one whose estimate exceeds the
 * limit (glintd --work-max-seconds) before it starts (413, kind
 * "too-expensive", naming the estimate and the limit).  Work that runs is
 * cancelled when its client goes away or the daemon stops (cancel.h), and
 * says so (admit_cancelled: counted in /metrics).  admit_stop refuses
 * everything from then on and ends the waits at once.
 *
 * Priorities and fairness.  Work comes in two classes: interactive (what a
 * person waits on: fits, previews that follow the mouse, base renders) and
 * background (renders a client asked for at low priority, such as the
 * studio's reference renders for its error table, exports, the held-out
 * measurements after fits).  Background work never takes the last
 * `reserve` slots (glintd --work-interactive), nor more memory than the
 * unreserved slots' share of the budget once some of it runs, and never
 * enters while interactive work waits for room, so a stroke's fit or a
 * preview does not queue behind renders that take minutes.  Work that
 * names its client (admit_ticket.client: the owner key a browser sends, else
 * the client's address) holds at most `per_client` slots at once (glintd
 * --work-per-client), so one person cannot take the whole budget; this is
 * fairness between well-behaved clients, the connection front's per-address
 * limits are the defence.  Work with no client (jobs, body parsing) is not
 * counted per client.  A request's wait polls its `gone` callback (the client
 * closed its connection, the daemon stops) and gives up at once, so a
 * request abandoned while it waits never takes a slot.
 *
 * A NULL admit admits everything (enter, wait, leave and metrics accept it).
 * Thread-safety: every function may be called from any thread. */
#ifndef GLINTD_ADMIT_H
#define GLINTD_ADMIT_H

#include <stddef.h>
#include <stdio.h>

#include "err.h"

typedef struct admit admit;

/* budget: bytes; slots: pieces of work at once (>= 1); wait_s: how long
 * admit_enter waits for room, in [0, 3600] seconds. */
int admit_open(size_t budget, int slots, double wait_s, admit **out, glint_err *err);
/* Accepts NULL.  No work may be in flight. */
void admit_close(admit *a);

/* admit_enter and admit_wait admit interactive work of no client in
 * particular (admit_take for a class and a client).
 * Enter within wait_s or not at all: 0 with `bytes` held (admit_leave
 * them); GLINT_ETOOBIG (kind "over-budget") at once when bytes exceed the
 * whole budget; GLINT_EBUSY (kind "busy") when the budget or the slots
 * stayed taken.
 * `what` names the work in messages ("a 4096x4096 preview"). */
int admit_enter(admit *a, size_t bytes, const char *what, glint_err *err);

/* Enter, waiting for room: polls cancelled(cls) (may be NULL) about every
 * 100 ms and gives up (GLINT_EBUSY, kind "cancelled") when it says so.  Else
 * errors as admit_enter's, but never "busy". */
int admit_wait(admit *a, size_t bytes, const char *what, int (*cancelled)(void *), void *cls,
               glint_err *err);

void admit_leave(admit *a, size_t bytes);

typedef enum admit_class {
    ADMIT_INTERACTIVE = 0, /* a person waits on it */
    ADMIT_BACKGROUND = 1,  /* reference renders, exports: after interactive work */
} admit_class;
#define ADMIT_CLASSES 2
#define ADMIT_CLIENT_MAX 72

/* One piece of work as admit_take sees it.  The caller fills bytes, cls,
 * client ("" or NULL-terminated empty: not counted per client; longer keys
 * are cut), gone/gone_cls (may be NULL); admit_take fills the rest and
 * admit_give reads it.  Lives on the caller's stack for as long as the work
 * runs. */
typedef struct admit_ticket {
    size_t bytes;
    admit_class cls;
    char client[ADMIT_CLIENT_MAX];
    int (*gone)(void *); /* polled about every 100 ms while waiting: 1 gives up */
    void *gone_cls;
    int held;            /* OUT: 1 once admitted, until admit_give */
} admit_ticket;

/* Enter with the class and the client of t: within wait_s (forever = 0)
 * or until room is made (forever = 1, for jobs).  Errors as admit_enter's
 * and admit_wait's; a refusal for the per-client cap or for the reserve
 * of interactive work says so in plain words (kind "busy" as before), and
 * a client that went away while waiting gets GLINT_EBUSY with kind
 * "cancelled".  Accepts a NULL admit (admits). */
int admit_take(admit *a, admit_ticket *t, const char *what, int forever, glint_err *err);

/* Give back what admit_take held (no-op when it holds nothing). */
void admit_give(admit *a, admit_ticket *t);

/* The slots kept for interactive work (0 .. slots - 1) and the slots one
 * client may hold at once (>= 1; slots for no cap).  admit_open sets
 * 1 (0 with one slot) and max(1, slots / 2). */
void admit_limit_classes(admit *a, int reserve, int per_client);

/* The largest estimate (seconds) of one piece of work admit_cost admits;
 * 0: no limit (the default). */
void admit_limit_seconds(admit *a, double seconds);

/* 0 when an estimate of `seconds` is within the limit; else GLINT_ETOOBIG
 * with kind "too-expensive" and a message naming `what`, the estimate and
 * the limit.  Holds nothing.  A NULL admit admits. */
int admit_cost(admit *a, double seconds, const char *what, glint_err *err);

/* A piece of admitted work stopped because it was cancelled (its client
 * went away, the daemon stopped): counted for /metrics.  Call it as well
 * as admit_leave. */
void admit_cancelled(admit *a);

/* The daemon stops: admit_enter and admit_wait refuse from now on
 * (GLINT_EBUSY, kind "stopping"), and those waiting return at once. */
void admit_stop(admit *a);

typedef struct admit_stats {
    size_t budget, held, peak;   /* bytes */
    int slots, running;
    int reserve, per_client;     /* admit_limit_classes */
    int running_by[ADMIT_CLASSES];       /* of running, by admit_class */
    int waiting_by[ADMIT_CLASSES];       /* admit_take calls waiting for room now */
    double max_seconds;          /* admit_limit_seconds (0: none) */
    long long admitted, refused_busy, refused_size, refused_cost, waited, cancelled;
    long long refused_by[ADMIT_CLASSES]; /* busy refusals by class */
    long long refused_client;    /* ... of them for the per-client cap */
    long long gone_waiting;      /* requests whose client went away while they waited */
} admit_stats;

void admit_get_stats(admit *a, admit_stats *out);

/* Prometheus text for /metrics. */
void admit_metrics(admit *a, FILE *out);

#endif
