/* jobs.h: background jobs with progress, for work too long for a request
 * (cold fits, held-out measurements).
 *
 * A job has a kind ("fit", "holdout"), an owner (a session id: who may
 * read it; "" for internal jobs nobody reads), a target (what it makes for
 * its owner, e.g. a fit's method; "" for none), a function run on a worker
 * thread, and an event log ("progress" events, then one "done" or
 * "failed") that clients poll or stream.
 *
 * Queues.  People's jobs (every kind but "holdout") and background jobs
 * (held-out measurements) wait apart: JOBS_MAX_QUEUED of the first, at
 * most JOBS_MAX_QUEUED_PER_OWNER of one owner, and JOBS_MAX_BACKGROUND of
 * the second, so that neither one owner nor the measurements fill the
 * queue for the others.  A free worker takes a people's job first: the
 * oldest of the owner with the fewest jobs running, and among those the
 * owner served least recently (round robin between owners); a background
 * job only when no people's job waits, and one at a time (with two workers
 * or more, one is always free for fits; the measurement itself waits for
 * the painters' pauses, fitsvc_holdout.c).
 *
 * Cancelling.  A job submitted with a target supersedes the queued jobs of
 * the same owner and target (a painter's newer fit replaces the older one
 * still waiting): they fail at once with "cancelled": "superseded".
 * jobs_cancel stops one job ("deleted"); jobs_stop all ("stopping").  A
 * queued job then never runs; a running one is told through job_cancelled
 * and fails when its function returns an error (a function that finishes
 * anyway is done).  The job's JSON says "cancelled" and why.
 *
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
#define JOBS_MAX_QUEUED_PER_OWNER 8
#define JOBS_MAX_BACKGROUND 256
#define JOBS_TARGET_MAX 32 /* bytes of a target, NUL included (longer ones are cut) */
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

/* Stop: no job starts from now on, queued jobs fail ("the daemon stopped
 * before the job ran", cancelled "stopping"), running ones are told
 * (job_cancelled).  Returns at once; jobs_submit is refused after.
 * Accepts NULL. */
void jobs_stop(jobs *js);

/* jobs_stop, then the workers are joined (running jobs stop or finish)
 * and everything is freed.  Accepts NULL. */
void jobs_close(jobs *js);

/* Queue a job of `owner` (NULL: "") for `target` (NULL or "": none).
 * `arg` goes to fn and then to arg_free (also when the job never runs).
 * Queued people's jobs of the same owner and target are superseded (see
 * above).  OUT: id[33] (128 random bits).  GLINT_EBUSY when stopping,
 * when JOBS_MAX_QUEUED people's jobs or JOBS_MAX_BACKGROUND background
 * jobs wait already, or (kind "owner-queue-full") when the owner has
 * JOBS_MAX_QUEUED_PER_OWNER waiting; the messages name the limit. */
int jobs_submit(jobs *js, const char *kind, const char *owner, const char *target, job_fn fn,
                void *arg, void (*arg_free)(void *), char id[33], glint_err *err);

/* Cancel job `id` (cancelled "deleted"): a queued one fails now, a running
 * one is told and fails when it stops.  OUT: *job, its JSON after (a new
 * object).  GLINT_ENOTFOUND; GLINT_ECONFLICT when it has finished. */
int jobs_cancel(jobs *js, const char *id, json_t **job, glint_err *err);

/* From the job's own thread: 1 once the daemon stops or the job was
 * cancelled (a long job gives up early: glint_cancel's stop); enter `stage`
 * at overall progress p in [0, 1] (stage changes are always logged,
 * progress within a stage in steps of 5%). */
int job_cancelled(job *j);
void job_progress(job *j, const char *stage, double p);

/* The job as JSON {"id", "kind", "state", "progress", "stage", "created",
 * "started"?, "seconds"?, "finished"?, ...result, "error"?, "cancelled"?}
 * (a new object)
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
    int queued_fits;       /* queued people's jobs (not held-out measurements) */
    int queued_background; /* queued held-out measurements */
    int owners;            /* owners with jobs queued */
    unsigned long long done, failed, cancelled; /* cancelled: counted in failed too */
} jobs_stats;

void jobs_stats_get(jobs *js, jobs_stats *out);
/* Prometheus text for /metrics. */
void jobs_metrics(jobs *js, FILE *out);

#endif
