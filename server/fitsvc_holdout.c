/* fitsvc_holdout.c: the held-out error of a fit point (fitsvc.h): one
 * background measurement per point at a time, sharing the memo's images. */
#define _GNU_SOURCE
#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/resource.h>
#include <unistd.h>

#include "admit.h"
#include "clock.h"
#include "fitsvc_int.h"
#include "log.h"
#include "par.h"
#include "prep.h"

/* ---- held-out error ---------------------------------------------------------------- */

/* Seconds without fits or stored paintings a held-out measurement waits
 * for before each of its views (holdout_gate). */
#define HOLDOUT_REST_S 1.0

typedef struct holdout_task {
    fitsvc *f;
    const method *m;
    void *params;
    cache_entry *pattern;    /* the fit's: every painted view's samples */
    int nviews;
    img *paintings;          /* the painted views: shared with the memo, or copies */
    memo_painting **pins;    /* nviews: the memo's (NULL: paintings[v] is a copy) */
    char scene_hash[33];
    char material_id[33];
    char key[1024];
    size_t bytes;            /* memory bound of one of its fits (admit.h) */
} holdout_task;

static void holdout_free(void *p)
{
    holdout_task *h = p;
    if (!h)
        return;
    for (int v = 0; h->paintings && v < h->nviews; v++) {
        if (h->pins && h->pins[v])
            memo_painting_release(h->f->memo, h->pins[v]);
        else
            img_free(&h->paintings[v]);
    }
    if (h->key[0]) { /* no longer scheduled */
        char k[1100];
        snprintf(k, sizeof k, "%s/%s", h->scene_hash, h->key);
        pthread_mutex_lock(&h->f->lock);
        json_object_del(h->f->holdouts, k);
        pthread_mutex_unlock(&h->f->lock);
    }
    free(h->paintings);
    free(h->pins);
    free(h->params);
    cache_release(h->f->cache, h->pattern);
    free(h);
}

/* ---- the painters' activity (fitsvc_int.h) -------------------------------------- */

void fitsvc_busy(fitsvc *f, int delta)
{
    pthread_mutex_lock(&f->lock);
    f->active += delta;
    f->last_active = glint_now();
    pthread_mutex_unlock(&f->lock);
}

double fitsvc_quiet_for(fitsvc *f)
{
    double q;
    pthread_mutex_lock(&f->lock);
    q = f->active > 0 ? 0.0 : glint_now() - f->last_active;
    pthread_mutex_unlock(&f->lock);
    return q;
}

/* One measurement, on a thread of its own at the priority of background
 * work (fitsvc.h, FITSVC_BG_*): the job's worker keeps the priority of the
 * fits it runs next, and a thread that lowers its own priority cannot
 * raise it again without privileges. */
typedef struct holdout_run {
    holdout_task *h;
    job *j;
    json_t *r;
    glint_err err;
    int rc;
    double paused;  /* seconds waited for the painters (holdout_gate) */
} holdout_run;

/* Before each held-out view: 1 once the daemon stops, else 0 when no fit
 * has run and no painting has been stored for HOLDOUT_REST_S, after
 * waiting for that (fitsvc_quiet_for).  A painter's burst of strokes and
 * fits then runs without the measurement beside it, which would take the
 * other core and share the memory bus; it goes on in the pauses, a view at
 * a time.  It does not wait while fit jobs are queued: it holds a worker
 * they may need (with one worker, a painter's cold fits would otherwise
 * queue behind it for as long as the painter works). */
static int holdout_gate(void *cls)
{
    holdout_run *x = cls;
    for (;;) {
        double quiet, wait, t0;
        struct timespec ts;
        jobs_stats js;
        if (job_cancelled(x->j))
            return 1;
        quiet = fitsvc_quiet_for(x->h->f);
        jobs_stats_get(x->h->f->jobs, &js);
        if (quiet >= HOLDOUT_REST_S || js.queued_fits > 0)
            return 0;
        /* in steps of at most 0.1 s: a stopping daemon is not kept waiting */
        wait = HOLDOUT_REST_S - quiet < 0.1 ? HOLDOUT_REST_S - quiet : 0.1;
        ts.tv_sec = 0;
        ts.tv_nsec = (long)(wait * 1e9);
        t0 = glint_now();
        nanosleep(&ts, NULL);
        x->paused += glint_now() - t0;
    }
}

/* The views' builds stop as soon as the job is cancelled (the daemon
 * stops), without the gate's wait. */
static int holdout_stop(void *cls)
{
    holdout_run *x = cls;
    return job_cancelled(x->j);
}

static void holdout_progress(void *cls, const char *stage, double p)
{
    holdout_run *x = cls;
    job_progress(x->j, stage, p);
}

static void background_priority(int level)
{
#ifdef __linux__
    if (level == FITSVC_BG_IDLE) {
        struct sched_param sp;
        memset(&sp, 0, sizeof sp);
        if (pthread_setschedparam(pthread_self(), SCHED_IDLE, &sp) == 0)
            return;
        level = FITSVC_BG_LOW; /* refused: the lowest nice value instead */
    }
    if (level == FITSVC_BG_LOW)
        (void)setpriority(PRIO_PROCESS, (id_t)gettid(), 19);
#else
    (void)level;
#endif
}

static void *holdout_thread(void *arg)
{
    holdout_run *x = arg;
    holdout_task *h = x->h;
    glint_cancel cancel = {holdout_stop, x};
#ifdef __linux__
    (void)pthread_setname_np(pthread_self(), "glintd-holdout"); /* seen in top, ps -L */
#endif
    background_priority(h->f->background);
    /* off the worker pool: a painter's fit that starts meanwhile finds the
     * pool free (par.h), instead of running on its own thread beside a
     * measurement no one waits for */
    par_background(1);
    x->rc = prep_holdout(h->m, h->params, cache_data(h->pattern), h->paintings, holdout_gate,
                         holdout_progress, x, &cancel, &x->r, &x->err);
    par_background(0);
    return NULL;
}

static int holdout_job(job *j, void *arg, json_t **result, glint_err *err)
{
    holdout_task *h = arg;
    holdout_run x;
    pthread_t th;
    int rc;
    /* background work: it measures a fit already answered, so fits and
     * previews people wait on go first (admit.h) */
    admit_ticket t = {.bytes = h->bytes, .cls = ADMIT_BACKGROUND, .gone = fitsvc_job_cancelled,
                      .gone_cls = j};

    (void)result;
    if (h->f->work && (rc = admit_take(h->f->work, &t, "a held-out measurement", 1, err)))
        return rc;
    memset(&x, 0, sizeof x);
    x.h = h;
    x.j = j;
    if (pthread_create(&th, NULL, holdout_thread, &x) == 0)
        pthread_join(th, NULL);
    else /* no thread to spare: not measured now (the point's next fit asks again) */
        x.rc = glint_err_set(&x.err, GLINT_ENOMEM, "no thread for the held-out measurement");
    admit_give(h->f->work, &t);
    if ((rc = x.rc)) {
        *err = x.err;
        return rc;
    }
    json_object_set_new(x.r, "material_id", json_string(h->material_id));
    {
        /* its own time, and apart the time it waited for the painters */
        double s = json_number_value(json_object_get(x.r, "seconds")) - x.paused;
        json_object_set_new(x.r, "seconds", json_real(s > 0.0 ? s : 0.0));
        json_object_set_new(x.r, "paused_seconds", json_real(x.paused));
    }
    return points_set_holdout(h->f->points, h->scene_hash, h->key, x.r, err);
}

void fitsvc_holdout_schedule(fit_task *t, prep *p, const char *material_id, const char *key)
{
    holdout_task *h = calloc(1, sizeof *h);
    glint_err e;
    char id[33];

    if (!h)
        return;
    h->f = t->f;
    h->m = t->m;
    h->nviews = t->nviews;
    h->bytes = t->bytes;
    snprintf(h->material_id, sizeof h->material_id, "%s", material_id);
    snprintf(h->scene_hash, sizeof h->scene_hash, "%s", prep_scene_of(t->scene)->hash);
    {
        /* one measurement per point at a time: the fits of a painter's
         * strokes would otherwise each schedule one while the first runs */
        char k[1100];
        int pending;
        snprintf(k, sizeof k, "%s/%s", h->scene_hash, key);
        pthread_mutex_lock(&t->f->lock);
        pending = json_object_get(t->f->holdouts, k) != NULL;
        if (!pending)
            json_object_set_new(t->f->holdouts, k, json_true());
        pthread_mutex_unlock(&t->f->lock);
        if (pending) {
            holdout_free(h);
            return;
        }
        snprintf(h->key, sizeof h->key, "%s", key);
    }
    h->paintings = calloc((size_t)t->nviews, sizeof *h->paintings);
    h->pins = calloc((size_t)t->nviews, sizeof *h->pins);
    h->params = malloc(t->m->params_size);
    if (!h->paintings || !h->pins || !h->params) {
        holdout_free(h);
        return;
    }
    memcpy(h->params, t->params, t->m->params_size);
    for (int v = 0; v < t->nviews; v++) {
        const img *s = &t->paintings[v];
        if (!t->use[v])
            continue;
        /* the memo's image, pinned once more (no copy), if it still has it */
        if (t->pins[v] && memo_painting_get(t->f->memo, t->session_id, v, t->versions[v],
                                            &h->pins[v]) == 0) {
            h->paintings[v] = *memo_painting_img(h->pins[v]);
            continue;
        }
        if (img_alloc(&h->paintings[v], s->width, s->height, s->channels, &e)) {
            holdout_free(h);
            return;
        }
        memcpy(h->paintings[v].px, s->px,
               (size_t)s->width * s->height * s->channels * sizeof(float));
    }
    h->pattern = cache_ref(t->f->cache, prep_pattern(p));
    if (jobs_submit(t->f->jobs, "holdout", "", NULL, holdout_job, h, holdout_free, id, &e))
        log_line("held-out evaluation not scheduled: %s", e.msg);
}

