/* jobs.c: background jobs with progress (jobs.h). */
#include "jobs.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "clock.h"
#include "ids.h"
#include "log.h"

#define NBUCKETS 256
#define JOB_LOG_MAX 256 /* events kept per job (progress beyond it is dropped) */

enum { J_QUEUED, J_RUNNING, J_DONE, J_FAILED };
static const char *const state_names[4] = {"queued", "running", "done", "failed"};

/* Why a job was cancelled (jobs.h); JOB_CANCEL_NONE: it was not. */
enum { JOB_CANCEL_NONE, JOB_CANCEL_SUPERSEDED, JOB_CANCEL_DELETED, JOB_CANCEL_STOPPING };
static const char *const cancel_names[4] = {"", "superseded", "deleted", "stopping"};

/* The people's jobs of one owner, queued or running (background jobs have
 * none): what the next job is chosen by (next_job). */
typedef struct owner_rec {
    char id[33];
    int queued, running;
    unsigned long long served; /* js->serve_clock when one of its jobs last started */
    struct owner_rec *next;
} owner_rec;

struct job {
    jobs *js;
    char id[33], owner[33], kind[16], target[JOBS_TARGET_MAX];
    owner_rec *own;          /* NULL for background jobs and once finished */
    int cancel;              /* JOB_CANCEL_*: asked to stop (job_cancelled), and why */
    char cancel_by[33];      /* JOB_CANCEL_SUPERSEDED: the job that superseded it */
    int state;
    char stage[32];
    double progress, logged_progress;
    time_t created, started, finished;
    double t_start, t_end;   /* monotonic */
    json_t *result;
    char error[GLINT_ERR_MSG_MAX];
    job_fn fn;
    void *arg;
    void (*arg_free)(void *);
    json_t *log;             /* array of events */
    long long seq;
    job *qnext;              /* queue */
    job *hnext;              /* hash chain */
    job *anext;              /* every job, oldest first */
};

struct jobs {
    pthread_mutex_t lock;
    pthread_cond_t work, change;
    job *qhead;
    job *table[NBUCKETS];
    job *all_head, *all_tail;
    owner_rec *owners;
    unsigned long long serve_clock;
    int njobs, queued, queued_background, running, running_holdouts, stopping, streams_stopped;
    int joined;              /* jobs_close: the workers are gone */
    unsigned long long done, failed, cancelled;
    pthread_t *workers;
    int nworkers;
    void (*idle)(void *);
    void *idle_cls;
    double idle_period;
    pthread_mutex_t idle_lock; /* one idle call at a time */
};

static unsigned bucket_of(const char *s)
{
    unsigned h = 2166136261u;
    while (*s)
        h = (h ^ (unsigned char)*s++) * 16777619u;
    return h % NBUCKETS;
}

static int is_holdout(const job *j)
{
    return strcmp(j->kind, "holdout") == 0;
}


/* The job as JSON (lock held). */
static json_t *job_json(const job *j)
{
    char t[GLINT_TIME_LEN];
    json_t *o = json_object();
    json_object_set_new(o, "id", json_string(j->id));
    json_object_set_new(o, "kind", json_string(j->kind));
    json_object_set_new(o, "state", json_string(state_names[j->state]));
    json_object_set_new(o, "progress", json_real(j->progress));
    json_object_set_new(o, "stage", json_string(j->stage));
    glint_time_iso(j->created, t);
    json_object_set_new(o, "created", json_string(t));
    if (j->state != J_QUEUED) {
        glint_time_iso(j->started, t);
        json_object_set_new(o, "started", json_string(t));
        json_object_set_new(o, "seconds",
                            json_real((j->state >= J_DONE ? j->t_end : glint_now()) - j->t_start));
    }
    if (j->state >= J_DONE) {
        glint_time_iso(j->finished, t);
        json_object_set_new(o, "finished", json_string(t));
    }
    if (j->state == J_DONE && j->result)
        json_object_update(o, j->result);
    if (j->state == J_FAILED)
        json_object_set_new(o, "error", json_string(j->error));
    if (j->cancel != JOB_CANCEL_NONE && j->state != J_DONE)
        json_object_set_new(o, "cancelled", json_string(cancel_names[j->cancel]));
    return o;
}

/* Append an event and wake the listeners (lock held). */
static void job_log(jobs *js, job *j, const char *type)
{
    json_t *ev;
    if (json_array_size(j->log) >= JOB_LOG_MAX && strcmp(type, "progress") == 0)
        return;
    ev = json_pack("{s:I, s:s, s:o}", "seq", (json_int_t)++j->seq, "type", type, "job",
                   job_json(j));
    if (ev)
        json_array_append_new(j->log, ev);
    j->logged_progress = j->progress;
    pthread_cond_broadcast(&js->change);
}

int job_cancelled(job *j)
{
    int stop;
    pthread_mutex_lock(&j->js->lock);
    stop = j->js->stopping || j->cancel != JOB_CANCEL_NONE;
    pthread_mutex_unlock(&j->js->lock);
    return stop;
}

void job_progress(job *j, const char *stage, double p)
{
    jobs *js = j->js;
    int changed;
    if (!(p >= 0.0))
        p = 0.0;
    if (p > 1.0)
        p = 1.0;
    pthread_mutex_lock(&js->lock);
    changed = strcmp(j->stage, stage) != 0;
    if (p > j->progress)
        j->progress = p;
    snprintf(j->stage, sizeof j->stage, "%s", stage);
    if (changed || j->progress - j->logged_progress >= 0.05)
        job_log(js, j, "progress");
    pthread_mutex_unlock(&js->lock);
}

static void job_free(job *j)
{
    if (!j)
        return;
    if (j->arg_free)
        j->arg_free(j->arg);
    json_decref(j->result);
    json_decref(j->log);
    free(j);
}

static job *job_find(jobs *js, const char *id)
{
    for (job *j = js->table[bucket_of(id)]; j; j = j->hnext)
        if (strcmp(j->id, id) == 0)
            return j;
    return NULL;
}

static void table_remove(jobs *js, job *j)
{
    job **pp = &js->table[bucket_of(j->id)];
    while (*pp && *pp != j)
        pp = &(*pp)->hnext;
    if (*pp)
        *pp = j->hnext;
}

/* Forget finished jobs beyond the retention limits (lock held). */
static void expire(jobs *js)
{
    job **pp = &js->all_head, *prev = NULL;
    double now = glint_now();
    while (*pp) {
        job *j = *pp;
        if (j->state >= J_DONE && (js->njobs > JOBS_KEEP || now - j->t_end > JOBS_KEEP_SECONDS)) {
            *pp = j->anext;
            if (js->all_tail == j)
                js->all_tail = prev;
            table_remove(js, j);
            js->njobs--;
            job_free(j);
            continue;
        }
        prev = j;
        pp = &j->anext;
    }
}

/* ---- owners ----------------------------------------------------------------------- */

/* The record of a people's job's owner, made on its first job (lock held;
 * NULL when out of memory). */
static owner_rec *owner_get(jobs *js, const char *id)
{
    owner_rec *o;
    for (o = js->owners; o; o = o->next)
        if (strcmp(o->id, id) == 0)
            return o;
    if (!(o = calloc(1, sizeof *o)))
        return NULL;
    snprintf(o->id, sizeof o->id, "%s", id);
    o->next = js->owners;
    js->owners = o;
    return o;
}

/* Drop an owner with nothing queued or running (lock held). */
static void owner_put(jobs *js, owner_rec *o)
{
    owner_rec **pp = &js->owners;
    if (!o || o->queued > 0 || o->running > 0)
        return;
    while (*pp && *pp != o)
        pp = &(*pp)->next;
    if (*pp)
        *pp = o->next;
    free(o);
}

/* ---- the queue --------------------------------------------------------------------- */

static void dequeue(jobs *js, job *j)
{
    job **pp = &js->qhead;
    while (*pp != j)
        pp = &(*pp)->qnext;
    *pp = j->qnext;
    j->qnext = NULL;
    if (is_holdout(j)) {
        js->queued_background--;
    } else {
        js->queued--;
        if (j->own)
            j->own->queued--;
    }
}

/* The message of a job that was cancelled, by why. */
static void cancel_message(job *j, int ran)
{
    switch (j->cancel) {
    case JOB_CANCEL_SUPERSEDED:
        snprintf(j->error, sizeof j->error,
                 "superseded: a newer %s of the same owner and target (job %s) replaced it "
                 "before it ran", j->kind, j->cancel_by);
        break;
    case JOB_CANCEL_DELETED:
        snprintf(j->error, sizeof j->error, "cancelled (DELETE of the job) %s",
                 ran ? "while it ran" : "before it ran");
        break;
    default:
        snprintf(j->error, sizeof j->error, "the daemon stopped %s",
                 ran ? "while the job ran" : "before the job ran");
        break;
    }
}

/* A queued job ends unrun, cancelled for `why` (lock held): it leaves the
 * queue, fails with the reason, and its argument is freed. */
static void cancel_queued(jobs *js, job *j, int why)
{
    dequeue(js, j);
    j->cancel = why;
    j->state = J_FAILED;
    j->finished = time(NULL);
    j->t_start = j->t_end = glint_now();
    snprintf(j->stage, sizeof j->stage, "%s", why == JOB_CANCEL_SUPERSEDED ? "superseded"
                                                                            : "cancelled");
    cancel_message(j, 0);
    js->failed++;
    js->cancelled++;
    owner_put(js, j->own);
    j->own = NULL;
    if (j->arg_free)
        j->arg_free(j->arg);
    j->arg = NULL;
    j->arg_free = NULL;
    job_log(js, j, "failed");
}

int jobs_submit(jobs *js, const char *kind, const char *owner, const char *target, job_fn fn,
                void *arg, void (*arg_free)(void *), char id[33], glint_err *err)
{
    job *j = calloc(1, sizeof *j), **pp;
    int rc;

    if (!j || !(j->log = json_array())) {
        free(j);
        if (arg_free)
            arg_free(arg);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a job");
    }
    j->js = js;
    j->fn = fn;
    j->arg = arg;
    j->arg_free = arg_free;
    snprintf(j->owner, sizeof j->owner, "%s", owner ? owner : "");
    snprintf(j->kind, sizeof j->kind, "%s", kind ? kind : "fit");
    snprintf(j->target, sizeof j->target, "%s", target ? target : "");
    snprintf(j->stage, sizeof j->stage, "queued");
    if ((rc = glint_id_new_near(owner, j->id, err))) { /* routed with its owner */
        job_free(j);
        return rc;
    }
    j->created = time(NULL);
    pthread_mutex_lock(&js->lock);
    if (js->stopping) {
        rc = glint_err_set(err, GLINT_EBUSY, "the daemon is stopping");
        goto refused;
    }
    if (is_holdout(j)) { /* background work: a queue limit of its own */
        if (js->queued_background >= JOBS_MAX_BACKGROUND) {
            rc = glint_err_set(err, GLINT_EBUSY,
                               "%d background jobs are waiting already (the limit): this one "
                               "is not scheduled", JOBS_MAX_BACKGROUND);
            goto refused;
        }
    } else {
        owner_rec *o = owner_get(js, j->owner);
        if (!o) {
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for a job");
            goto refused;
        }
        int same = 0; /* the owner's queued jobs of the same target: this one replaces them */
        for (job *q = js->qhead; q && j->target[0]; q = q->qnext)
            same += q->own == o && !is_holdout(q) && strcmp(q->target, j->target) == 0;
        if (o->queued - same >= JOBS_MAX_QUEUED_PER_OWNER) {
            rc = glint_err_set(err, GLINT_EBUSY,
                               "%d jobs of owner %s are waiting already (the limit of one "
                               "owner, whatever other owners wait): wait for one to start, or "
                               "cancel one (DELETE /api/v1/jobs/{id})", o->queued, j->owner);
            glint_err_kind(err, "owner-queue-full");
            owner_put(js, o);
            goto refused;
        }
        if (js->queued - same >= JOBS_MAX_QUEUED) {
            rc = glint_err_set(err, GLINT_EBUSY,
                               "%d jobs are waiting already (the limit, all owners): try again "
                               "later", JOBS_MAX_QUEUED);
            owner_put(js, o);
            goto refused;
        }
        o->queued++; /* this one's place, held while the older ones go */
        for (job *q = js->qhead, *next; q && same; q = next) {
            next = q->qnext;
            if (q->own == o && !is_holdout(q) && strcmp(q->target, j->target) == 0) {
                memcpy(q->cancel_by, j->id, 33);
                cancel_queued(js, q, JOB_CANCEL_SUPERSEDED);
                same--;
            }
        }
        j->own = o;
    }
    expire(js);
    j->hnext = js->table[bucket_of(j->id)];
    js->table[bucket_of(j->id)] = j;
    if (js->all_tail)
        js->all_tail->anext = j;
    else
        js->all_head = j;
    js->all_tail = j;
    js->njobs++;
    /* in submission order; next_job chooses among them */
    pp = &js->qhead;
    while (*pp)
        pp = &(*pp)->qnext;
    *pp = j;
    if (is_holdout(j))
        js->queued_background++;
    else
        js->queued++;
    job_log(js, j, "progress");
    memcpy(id, j->id, 33);
    pthread_cond_signal(&js->work);
    pthread_mutex_unlock(&js->lock);
    return 0;
refused:
    pthread_mutex_unlock(&js->lock);
    job_free(j);
    return rc;
}

/* The next job a worker may take (lock held).  People's jobs first: the
 * oldest queued job of the owner with the fewest jobs running, among those
 * the owner whose job started least recently (round robin).  Then a
 * background job, but only while no other runs. */
static job *next_job(jobs *js)
{
    job *best = NULL;
    for (job *j = js->qhead; j; j = j->qnext) {
        const owner_rec *o = j->own, *b;
        if (is_holdout(j) || !o)
            continue;
        b = best ? best->own : NULL;
        if (!b || o->running < b->running || (o->running == b->running && o->served < b->served))
            best = j;
    }
    if (best)
        return best;
    for (job *j = js->qhead; j; j = j->qnext)
        if (is_holdout(j) && js->running_holdouts == 0)
            return j;
    return NULL;
}

static void *worker_main(void *arg)
{
    jobs *js = arg;
    for (;;) {
        job *j = NULL;
        json_t *result = NULL;
        glint_err e;
        int rc;

        pthread_mutex_lock(&js->lock);
        while (!js->stopping && !(j = next_job(js))) {
            struct timespec dl;
            int timed_out;
            clock_gettime(CLOCK_REALTIME, &dl);
            dl.tv_sec += (time_t)(js->idle_period > 1 ? js->idle_period : 1);
            timed_out = pthread_cond_timedwait(&js->work, &js->lock, &dl) == ETIMEDOUT;
            if (timed_out && js->idle && pthread_mutex_trylock(&js->idle_lock) == 0) {
                pthread_mutex_unlock(&js->lock);
                js->idle(js->idle_cls);
                pthread_mutex_unlock(&js->idle_lock);
                pthread_mutex_lock(&js->lock);
            }
        }
        if (js->stopping) {
            pthread_mutex_unlock(&js->lock);
            return NULL;
        }
        dequeue(js, j);
        js->running++;
        js->running_holdouts += is_holdout(j);
        if (j->own) {
            j->own->running++;
            j->own->served = ++js->serve_clock;
        }
        j->state = J_RUNNING;
        j->started = time(NULL);
        j->t_start = glint_now();
        snprintf(j->stage, sizeof j->stage, "started");
        job_log(js, j, "progress");
        pthread_mutex_unlock(&js->lock);

        glint_err_clear(&e);
        rc = j->fn(j, j->arg, &result, &e);

        pthread_mutex_lock(&js->lock);
        js->running--;
        if (is_holdout(j)) {
            js->running_holdouts--;
            pthread_cond_signal(&js->work); /* a queued holdout may go now */
        }
        if (j->own) {
            j->own->running--;
            owner_put(js, j->own);
            j->own = NULL;
            pthread_cond_signal(&js->work); /* another owner's job may come first now */
        }
        j->t_end = glint_now();
        j->finished = time(NULL);
        if (rc == 0) {
            j->state = J_DONE;
            j->progress = 1.0;
            snprintf(j->stage, sizeof j->stage, "done");
            j->result = json_is_object(result) ? result : NULL;
            if (!j->result)
                json_decref(result);
            js->done++;
            job_log(js, j, "done");
        } else {
            json_decref(result);
            j->state = J_FAILED;
            if (j->cancel == JOB_CANCEL_NONE && js->stopping)
                j->cancel = JOB_CANCEL_STOPPING;
            if (j->cancel != JOB_CANCEL_NONE) { /* whatever the work said as it stopped */
                cancel_message(j, 1);
                snprintf(j->stage, sizeof j->stage, "cancelled");
                js->cancelled++;
            } else {
                snprintf(j->error, sizeof j->error, "%s", e.msg[0] ? e.msg : glint_strerror(rc));
            }
            log_redact_paths(j->error, sizeof j->error); /* clients read it */
            js->failed++;
            job_log(js, j, "failed");
        }
        /* the argument (paintings, a scene handle) is not needed any more */
        if (j->arg_free)
            j->arg_free(j->arg);
        j->arg = NULL;
        j->arg_free = NULL;
        pthread_mutex_unlock(&js->lock);
    }
}

int jobs_cancel(jobs *js, const char *id, json_t **out, glint_err *err)
{
    job *j;
    int rc = 0;
    *out = NULL;
    pthread_mutex_lock(&js->lock);
    j = job_find(js, id);
    if (!j) {
        rc = glint_err_set(err, GLINT_ENOTFOUND,
                           "no job %.32s (unknown, or finished over an hour ago)", id);
    } else if (j->state >= J_DONE) {
        rc = glint_err_set(err, GLINT_ECONFLICT, "job %s has finished already (%s)", j->id,
                           state_names[j->state]);
    } else if (j->state == J_QUEUED) {
        cancel_queued(js, j, JOB_CANCEL_DELETED);
    } else if (j->cancel == JOB_CANCEL_NONE) { /* running: it stops at its next question */
        j->cancel = JOB_CANCEL_DELETED;
        job_log(js, j, "progress");
    }
    if (!rc)
        *out = job_json(j);
    pthread_mutex_unlock(&js->lock);
    return rc;
}

int jobs_get(jobs *js, const char *id, json_t **out, char owner[33], glint_err *err)
{
    job *j;
    *out = NULL;
    pthread_mutex_lock(&js->lock);
    j = job_find(js, id);
    if (!j) {
        pthread_mutex_unlock(&js->lock);
        return glint_err_set(err, GLINT_ENOTFOUND,
                             "no job %.32s (unknown, or finished over an hour ago)", id);
    }
    *out = job_json(j);
    if (owner)
        memcpy(owner, j->owner, 33);
    pthread_mutex_unlock(&js->lock);
    return 0;
}

int jobs_events(jobs *js, const char *id, long long since, double timeout_s, json_t **events,
                int *final, glint_err *err)
{
    struct timespec dl;
    json_t *out, *ev;
    job *j;
    size_t i;
    double s;

    *events = NULL;
    *final = 0;
    clock_gettime(CLOCK_REALTIME, &dl);
    s = (double)dl.tv_sec + 1e-9 * dl.tv_nsec + (timeout_s > 0 ? timeout_s : 0);
    dl.tv_sec = (time_t)s;
    dl.tv_nsec = (long)((s - (double)dl.tv_sec) * 1e9);
    pthread_mutex_lock(&js->lock);
    for (;;) {
        j = job_find(js, id);
        if (!j) {
            pthread_mutex_unlock(&js->lock);
            return glint_err_set(err, GLINT_ENOTFOUND, "no job %.32s", id);
        }
        if (js->streams_stopped) {
            pthread_mutex_unlock(&js->lock);
            return glint_err_set(err, GLINT_EUNSUPPORTED, "the daemon is stopping");
        }
        if (j->seq > since || j->state >= J_DONE)
            break;
        if (pthread_cond_timedwait(&js->change, &js->lock, &dl) == ETIMEDOUT)
            break;
    }
    out = json_array();
    json_array_foreach(j->log, i, ev) {
        if (json_integer_value(json_object_get(ev, "seq")) > since)
            json_array_append(out, ev);
    }
    *final = j->state >= J_DONE;
    *events = out;
    pthread_mutex_unlock(&js->lock);
    return 0;
}

int jobs_open(int threads, void (*idle)(void *cls), void *idle_cls, double idle_period_s,
              jobs **out, glint_err *err)
{
    jobs *js;
    *out = NULL;
    if (threads < 1 || threads > 64)
        return glint_err_set(err, GLINT_ERANGE, "worker threads %d outside 1..64", threads);
    js = calloc(1, sizeof *js);
    if (!js || !(js->workers = calloc((size_t)threads, sizeof *js->workers))) {
        free(js);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    pthread_mutex_init(&js->lock, NULL);
    pthread_mutex_init(&js->idle_lock, NULL);
    pthread_cond_init(&js->work, NULL);
    pthread_cond_init(&js->change, NULL);
    js->idle = idle;
    js->idle_cls = idle_cls;
    js->idle_period = idle_period_s;
    for (int i = 0; i < threads; i++) {
        int rc = pthread_create(&js->workers[i], NULL, worker_main, js);
        if (rc) {
            jobs_close(js);
            return glint_err_set(err, GLINT_EINTERNAL, "cannot start a worker thread: %s",
                                 strerror(rc));
        }
        js->nworkers++;
    }
    *out = js;
    return 0;
}

void jobs_shutdown(jobs *js)
{
    if (!js)
        return;
    pthread_mutex_lock(&js->lock);
    js->streams_stopped = 1;
    pthread_cond_broadcast(&js->change);
    pthread_mutex_unlock(&js->lock);
}

void jobs_stop(jobs *js)
{
    if (!js)
        return;
    pthread_mutex_lock(&js->lock);
    if (!js->stopping) {
        js->stopping = 1; /* job_cancelled says so to the running jobs */
        while (js->qhead) /* queued jobs never run */
            cancel_queued(js, js->qhead, JOB_CANCEL_STOPPING);
    }
    pthread_cond_broadcast(&js->work);
    pthread_cond_broadcast(&js->change);
    pthread_mutex_unlock(&js->lock);
}

void jobs_close(jobs *js)
{
    if (!js)
        return;
    jobs_stop(js);
    for (int i = 0; i < js->nworkers; i++)
        pthread_join(js->workers[i], NULL); /* running jobs stop or finish */
    free(js->workers);
    for (job *j = js->all_head, *next; j; j = next) {
        next = j->anext;
        job_free(j);
    }
    while (js->owners) {
        owner_rec *o = js->owners;
        js->owners = o->next;
        free(o);
    }
    pthread_cond_destroy(&js->work);
    pthread_cond_destroy(&js->change);
    pthread_mutex_destroy(&js->idle_lock);
    pthread_mutex_destroy(&js->lock);
    free(js);
}

void jobs_stats_get(jobs *js, jobs_stats *out)
{
    memset(out, 0, sizeof *out);
    if (!js)
        return;
    pthread_mutex_lock(&js->lock);
    out->queued = js->queued + js->queued_background;
    out->queued_fits = js->queued;
    out->queued_background = js->queued_background;
    for (const owner_rec *o = js->owners; o; o = o->next)
        out->owners += o->queued > 0;
    out->running = js->running;
    out->done = js->done;
    out->failed = js->failed;
    out->cancelled = js->cancelled;
    pthread_mutex_unlock(&js->lock);
}

void jobs_metrics(jobs *js, FILE *o)
{
    jobs_stats s;
    jobs_stats_get(js, &s);
    fprintf(o, "# HELP glintd_jobs Fit jobs now, by state.\n# TYPE glintd_jobs gauge\n");
    fprintf(o, "glintd_jobs{state=\"queued\"} %d\n", s.queued);
    fprintf(o, "glintd_jobs{state=\"running\"} %d\n", s.running);
    fprintf(o, "# HELP glintd_jobs_queued Jobs waiting, people's (by all owners) and "
               "background measurements apart.\n# TYPE glintd_jobs_queued gauge\n");
    fprintf(o, "glintd_jobs_queued{queue=\"people\"} %d\n", s.queued_fits);
    fprintf(o, "glintd_jobs_queued{queue=\"background\"} %d\n", s.queued_background);
    fprintf(o, "# HELP glintd_jobs_owners_waiting Owners with jobs waiting (served in turn).\n"
               "# TYPE glintd_jobs_owners_waiting gauge\nglintd_jobs_owners_waiting %d\n",
            s.owners);
    fprintf(o, "# HELP glintd_jobs_finished_total Fit jobs finished, by outcome.\n"
               "# TYPE glintd_jobs_finished_total counter\n");
    fprintf(o, "glintd_jobs_finished_total{state=\"done\"} %llu\n", s.done);
    fprintf(o, "glintd_jobs_finished_total{state=\"failed\"} %llu\n", s.failed);
    fprintf(o, "# HELP glintd_jobs_cancelled_total Jobs cancelled (superseded, deleted, or the "
               "daemon stopping), counted among the failed too.\n"
               "# TYPE glintd_jobs_cancelled_total counter\nglintd_jobs_cancelled_total %llu\n",
            s.cancelled);
}
