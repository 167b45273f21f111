/* fitsvc_gbuf.c: fits of G-buffer sets (fitsvc.h: fitsvc_fit_gbuffers).
 *
 * The samples and values come made (core gbfit.h, in the request); this
 * file runs them through the cache like any pattern (prep_try_samples now,
 * else prep_acquire_samples in a job) and records the material as every
 * fit is (fit_record), under the set.
 * Numerics are core's. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "clock.h"
#include "fitsvc.h"
#include "fitsvc_int.h"
#include "material.h"
#include "prep.h"
#include "store.h"

typedef struct gb_task {
    fitsvc *f;
    const method *m;
    void *params;
    char set_id[33];
    samples s;      /* moved into the cache by prep_acquire_samples (then zeroed) */
    float *rgb;     /* 3 n values */
    int nviews;
    unsigned char used[SCENE_MAX_VIEWS];
    size_t bytes;   /* the fit's memory bound (admit.h) */
    srv_timing *tm; /* steps of a fit run now (NULL in a job) */
} gb_task;

static void gb_task_free(void *p)
{
    gb_task *t = p;
    if (!t)
        return;
    samples_free(&t->s);
    free(t->rgb);
    free(t->params);
    free(t);
}

static int gb_execute_run(gb_task *t, prep *p, job *j, json_t **doc, glint_err *err);

/* Fit with a prepared precomputation and store the material (a painter's
 * work to the held-out measurements, which wait: fitsvc_busy).  OUT: *doc. */
static int gb_execute(gb_task *t, prep *p, job *j, json_t **doc, glint_err *err)
{
    int rc;
    fitsvc_busy(t->f, 1);
    rc = gb_execute_run(t, p, j, doc, err);
    fitsvc_busy(t->f, -1);
    return rc;
}

static int gb_execute_run(gb_task *t, prep *p, job *j, json_t **doc, glint_err *err)
{
    material m;
    fit_report rep;
    char mid[33];
    double t0 = glint_now();
    int rc;

    *doc = NULL;
    if (j)
        job_progress(j, "fit", 0.9);
    if ((rc = prep_fit_reusing(p, NULL, t->rgb, NULL, NULL, &m, &rep, err)))
        return rc;
    if (!(rc = fitsvc_material_check(&m, &rep, err))) {
        fit_record_in in = {t->m,     NULL,      NULL, t->set_id, t->used, NULL, t->nviews,
                            glint_now() - t0, t->tm};
        srv_timing_step(t->tm, "fit", t0);
        rc = fit_record(t->f, &in, &m, &rep, mid, doc, err);
    }
    fit_report_free(&rep);
    material_free(&m);
    return rc;
}

static int gb_job(job *j, void *arg, json_t **result, glint_err *err)
{
    gb_task *t = arg;
    glint_cancel cancel = {fitsvc_job_cancelled, j};
    prep *p = NULL;
    json_t *doc = NULL;
    int rc;

    if (t->f->work &&
        (rc = admit_wait(t->f->work, t->bytes, "the fit", fitsvc_job_cancelled, j, err)))
        return rc;
    if (!(rc = prep_acquire_samples(t->f->cache, t->m, t->params, &t->s, fitsvc_job_progress, j,
                                    &cancel, &p, err))) {
        rc = gb_execute(t, p, j, &doc, err);
        prep_release(t->f->cache, p);
    }
    if (t->f->work)
        admit_leave(t->f->work, t->bytes);
    if (rc)
        return rc;
    *result = json_pack("{s:O}", "material_id", json_object_get(doc, "id"));
    json_decref(doc);
    return 0;
}

int fitsvc_fit_gbuffers(fitsvc *f, const char *set_id, const method *m, const void *params,
                        samples *s, float **rgb, json_t **doc, char job_id[33], srv_timing *tm,
                        glint_err *err)
{
    gb_task *t = calloc(1, sizeof *t);
    prep *p = NULL;
    int rc;

    *doc = NULL;
    job_id[0] = '\0';
    if (!t || !(t->params = malloc(m->params_size ? m->params_size : 1))) {
        free(t);
        samples_free(s);
        free(*rgb);
        *rgb = NULL;
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    t->f = f;
    t->m = m;
    memcpy(t->params, params, m->params_size);
    snprintf(t->set_id, sizeof t->set_id, "%s", set_id);
    t->s = *s;
    memset(s, 0, sizeof *s);
    t->rgb = *rgb;
    *rgb = NULL;
    t->nviews = t->s.nviews < SCENE_MAX_VIEWS ? t->s.nviews : SCENE_MAX_VIEWS;
    memcpy(t->used, t->s.used, (size_t)t->nviews);
    t->bytes = method_fit_bytes(m, t->params, t->s.n) + 3 * (size_t)t->s.n * sizeof(float);
    if (prep_try_samples(f->cache, m, t->params, &t->s, &p, NULL) == 0) { /* in memory */
        pthread_mutex_lock(&f->lock);
        f->hits++;
        pthread_mutex_unlock(&f->lock);
        t->tm = tm;
        if (!f->work || !(rc = admit_enter(f->work, t->bytes, "the fit", err))) {
            rc = gb_execute(t, p, NULL, doc, err);
            if (f->work)
                admit_leave(f->work, t->bytes);
        }
        prep_release(f->cache, p);
        gb_task_free(t);
        return rc;
    }
    if (f->work) { /* what can never fit is refused now, not by the job */
        admit_stats st;
        admit_get_stats(f->work, &st);
        if (t->bytes > st.budget && (rc = admit_enter(f->work, t->bytes, "the fit", err))) {
            gb_task_free(t);
            return rc;
        }
    }
    if ((rc = fitsvc_cost_check(f, m, t->params, t->s.n, err))) {
        gb_task_free(t);
        return rc;
    }
    pthread_mutex_lock(&f->lock);
    f->misses++;
    pthread_mutex_unlock(&f->lock);
    return jobs_submit(f->jobs, "fit", set_id, m->name, gb_job, t, gb_task_free, job_id, err);
}
