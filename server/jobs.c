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

struct job {
    jobs *js;
    char id[33], owner[33], kind[16];
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
    int njobs, queued, running, running_holdouts, stopping, streams_stopped;
    unsigned long long done, failed;
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
    stop = j->js->stopping;
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

int jobs_submit(jobs *js, const char *kind, const char *owner, job_fn fn, void *arg,
                void (*arg_free)(void *), char id[33], glint_err *err)
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
    snprintf(j->stage, sizeof j->stage, "queued");
    if ((rc = glint_id_new_near(owner, j->id, err))) { /* routed with its owner */
        job_free(j);
        return rc;
    }
    j->created = time(NULL);
    pthread_mutex_lock(&js->lock);
    if (js->stopping || js->queued >= JOBS_MAX_QUEUED) {
        int stopping = js->stopping;
        pthread_mutex_unlock(&js->lock);
        job_free(j);
        return stopping ? glint_err_set(err, GLINT_EBUSY, "the daemon is stopping")
                        : glint_err_set(err, GLINT_EBUSY,
                                        "%d jobs are waiting already (the limit): try again "
                                        "later", JOBS_MAX_QUEUED);
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
    /* fit jobs go before queued holdout jobs (background measurements) */
    pp = &js->qhead;
    while (*pp && !(!is_holdout(j) && is_holdout(*pp)))
        pp = &(*pp)->qnext;
    j->qnext = *pp;
    *pp = j;
    js->queued++;
    job_log(js, j, "progress");
    memcpy(id, j->id, 33);
    pthread_cond_signal(&js->work);
    pthread_mutex_unlock(&js->lock);
    return 0;
}

/* The next job a worker may take (lock held): the first queued one, but a
 * holdout job only while no other runs. */
static job *next_job(jobs *js)
{
    for (job *j = js->qhead; j; j = j->qnext)
        if (!is_holdout(j) || js->running_holdouts == 0)
            return j;
    return NULL;
}

static void dequeue(jobs *js, job *j)
{
    job **pp = &js->qhead;
    while (*pp != j)
        pp = &(*pp)->qnext;
    *pp = j->qnext;
    j->qnext = NULL;
    js->queued--;
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
            snprintf(j->error, sizeof j->error, "%s", e.msg[0] ? e.msg : glint_strerror(rc));
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

void jobs_close(jobs *js)
{
    if (!js)
        return;
    pthread_mutex_lock(&js->lock);
    js->stopping = 1;
    for (job *j = js->qhead; j; j = j->qnext) { /* queued jobs never run */
        j->state = J_FAILED;
        j->finished = time(NULL);
        j->t_start = j->t_end = glint_now();
        snprintf(j->error, sizeof j->error, "the daemon stopped before the job ran");
        js->failed++;
        job_log(js, j, "failed");
    }
    js->qhead = NULL;
    js->queued = 0;
    pthread_cond_broadcast(&js->work);
    pthread_cond_broadcast(&js->change);
    pthread_mutex_unlock(&js->lock);
    for (int i = 0; i < js->nworkers; i++)
        pthread_join(js->workers[i], NULL); /* running jobs finish */
    free(js->workers);
    for (job *j = js->all_head, *next; j; j = next) {
        next = j->anext;
        job_free(j);
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
    out->queued = js->queued;
    for (const job *j = js->qhead; j; j = j->qnext)
        out->queued_fits += !is_holdout(j);
    out->running = js->running;
    out->done = js->done;
    out->failed = js->failed;
    pthread_mutex_unlock(&js->lock);
}

void jobs_metrics(jobs *js, FILE *o)
{
    jobs_stats s;
    jobs_stats_get(js, &s);
    fprintf(o, "# HELP glintd_jobs Fit jobs now, by state.\n# TYPE glintd_jobs gauge\n");
    fprintf(o, "glintd_jobs{state=\"queued\"} %d\n", s.queued);
    fprintf(o, "glintd_jobs{state=\"running\"} %d\n", s.running);
    fprintf(o, "# HELP glintd_jobs_finished_total Fit jobs finished, by outcome.\n"
               "# TYPE glintd_jobs_finished_total counter\n");
    fprintf(o, "glintd_jobs_finished_total{state=\"done\"} %llu\n", s.done);
    fprintf(o, "glintd_jobs_finished_total{state=\"failed\"} %llu\n", s.failed);
}
