/* cancel.h: asking long work to stop before it is done.
 *
 * Work whose caller may go away (a preview whose client closed the
 * connection, a job cancelled or superseded, a daemon that stops) takes a
 * `const glint_cancel *` (NULL: never cancelled) and asks it between units
 * of work: a band of rows, a batch of pixels or rays, a view, a level of a
 * precomputation.  Loops ask about every GLINT_CANCEL_WORK units of their
 * innermost work (light evaluations, rays, multiply-adds of a row), so a
 * cancelled render or build stops within milliseconds of work, whatever
 * its size, and the asking costs nothing measurable.  Work that stops
 * returns GLINT_ECANCELLED (err.h) with a message saying what stopped, and
 * leaves nothing behind (outputs freed, as on any error).
 *
 * `stop` may be called from several threads at once (the loops' workers)
 * and must be cheap and thread-safe; once it said 1 it should keep saying
 * so.  It returns 1 to stop, 0 to go on. */
#ifndef GLINT_CANCEL_H
#define GLINT_CANCEL_H

#include "err.h"

typedef struct glint_cancel {
    int (*stop)(void *cls);
    void *cls;
} glint_cancel;

/* Units of innermost work between two questions (see above). */
#define GLINT_CANCEL_WORK 65536L

/* 1 when c says to stop (0 for NULL or a NULL stop). */
static inline int glint_cancelled(const glint_cancel *c)
{
    return c && c->stop && c->stop(c->cls);
}

/* Items of `unit_work` units each between two questions: at least 1. */
static inline long glint_cancel_every(long unit_work)
{
    return unit_work >= GLINT_CANCEL_WORK ? 1 : GLINT_CANCEL_WORK / (unit_work > 0 ? unit_work : 1);
}

/* GLINT_ECANCELLED with "<what> was cancelled" in *err. */
static inline int glint_cancel_err(glint_err *err, const char *what)
{
    return glint_err_set(err, GLINT_ECANCELLED, "%s was cancelled", what);
}

#endif
