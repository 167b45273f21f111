/* jobs.h: background jobs with progress, for work too long for a request
 * (cold fits, held-out measurements).
 *
 * A job has a kind ("fit", "holdout"), an owner (a session id: who may
 * read it; "" for internal jobs nobody reads), a function run on a worker
 * thread, and an event log ("progress" events, then one "done" or
 * "failed") that clients poll or stream.  Fit jobs run in submission
 * order, before any queued holdout job, and at most one holdout job runs
 * at a time (with two workers or more, one is always free for fits; the
 * measurement itself waits for the painters' pauses, fitsvc_holdout.c).
 * Jobs live in memory: finished jobs are kept JOBS_KEEP at most and
 * JOBS_KEEP_SECONDS at most; a restart forgets them (their results, e.g.
 * materials, are in the store).
 *
 * Thread-safety: every function may be called from any thread. */
#ifndef GLINTD_JOBS_H
#define GLINTD_JOBS_H

#include <jansson.h>
#include <stdio.h>

#include "err.h"

#define JOBS_MAX_QUEUED 256
#define JOBS_KEEP 1024
#define JOBS_KEEP_SECONDS 3600.0

typedef struct jobs jobs;
typedef struct job job;

/* The work of a job, on a worker thread: 0 and optionally *result (an
 * object whose members join the job's JSON, e.g. {"material_id": ...};
 * stolen), or a negative code with *err set (the job fails with its
 * message). */
typedef int (*job_fn)(job *j, void *arg, json_t **result, glint_err *err);

/* threads: workers (1..64).  idle (may be NULL) is called by one idle
 * worker every idle_period_s seconds (for write-behind work). */
int jobs_open(int threads, void (*idle)(void *cls), void *idle_cls, double idle_period_s,
              jobs **out, glint_err *err);

/* End the event streams promptly (jobs_events answers GLINT_EUNSUPPORTED
 * from now on): call before the HTTP server stops.  Jobs go on. */
void jobs_shutdown(jobs *js);

/* Queued jobs fail ("the daemon stopped before the job ran"), running
 * jobs finish, workers are joined, everything is freed.  Accepts NULL. */
void jobs_close(jobs *js);

/* Queue a job.  `arg` goes to fn and then to arg_free (also when the job
 * never runs).  OUT: id[33] (128 random bits).  GLINT_EBUSY when stopping
 * or when JOBS_MAX_QUEUED jobs wait already. */
int jobs_submit(jobs *js, const char *kind, const char *owner, job_fn fn, void *arg,
                void (*arg_free)(void *), char id[33], glint_err *err);

/* From the job's own thread: 1 once the daemon stops (a long job may give
 * up early); enter `stage` at overall progress p in [0, 1] (stage changes
 * are always logged, progress within a stage in steps of 5%). */
int job_cancelled(job *j);
void job_progress(job *j, const char *stage, double p);

/* The job as JSON {"id", "kind", "state", "progress", "stage", "created",
 * "started"?, "seconds"?, "finished"?, ...result, "error"?} (a new object)
 * and its owner (OUT: owner[33], may be NULL).  GLINT_ENOTFOUND for
 * unknown or expired ids. */
int jobs_get(jobs *js, const char *id, json_t **job, char owner[33], glint_err *err);

/* Events after sequence number `since`, waiting up to timeout_s for one:
 * OUT: *events, an array of {"seq", "type", "job"} (maybe empty);
 * *final = 1 once it ends with the job's last event. */
int jobs_events(jobs *js, const char *id, long long since, double timeout_s, json_t **events,
                int *final, glint_err *err);

typedef struct jobs_stats {
    int queued, running;
    int queued_fits; /* queued jobs that are not held-out measurements */
    unsigned long long done, failed;
} jobs_stats;

void jobs_stats_get(jobs *js, jobs_stats *out);
/* Prometheus text for /metrics. */
void jobs_metrics(jobs *js, FILE *out);

#endif
