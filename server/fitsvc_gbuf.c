/* fitsvc_gbuf.c: fits of G-buffer sets (fitsvc.h: fitsvc_fit_gbuffers).
 *
 * The samples and values come made (core gbfit.h, in the request); this
 * file runs them through the cache like any pattern (prep_try_samples now,
 * else prep_acquire_samples in a job), stores the material's files under
 * blobs "materials/<id>/" before its row, and answers the material object.
 * Numerics are core's. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "clock.h"
#include "fitsvc.h"
#include "fitsvc_int.h"
#include "ids.h"
#include "json_text.h"
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

static json_t *gb_links(const char *mid, const char *set_id)
{
    char b[8][160];
    snprintf(b[0], sizeof b[0], "/api/v1/materials/%s", mid);
    snprintf(b[1], sizeof b[1], "/api/v1/materials/%s/factors.png", mid);
    snprintf(b[2], sizeof b[2], "/api/v1/materials/%s/factors.exr", mid);
    snprintf(b[3], sizeof b[3], "/api/v1/materials/%s/shader", mid);
    snprintf(b[4], sizeof b[4], "/api/v1/materials/%s/package", mid);
    snprintf(b[5], sizeof b[5], "/api/v1/materials/%s/eval", mid);
    snprintf(b[6], sizeof b[6], "/api/v1/materials/%s/merl.binary", mid);
    snprintf(b[7], sizeof b[7], "/api/v1/gbuffer-sets/%s", set_id);
    return json_pack("{s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:s}", "self", b[0], "factors_png",
                     b[1], "factors_exr", b[2], "shader", b[3], "package", b[4], "eval", b[5],
                     "merl", b[6], "gbuffer_set", b[7]);
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
    fitsvc *f = t->f;
    material m;
    char mid[33], name[128], dir[4096], created[GLINT_TIME_LEN];
    json_t *d = NULL, *views, *summary;
    double t0 = glint_now();
    int rc;

    *doc = NULL;
    if (j)
        job_progress(j, "fit", 0.9);
    if ((rc = prep_fit(p, NULL, t->rgb, &m, err)))
        return rc;
    if ((rc = fitsvc_material_check(&m, err))) {
        material_free(&m);
        return rc;
    }
    t0 = srv_timing_step(t->tm, "fit", t0);
    if ((rc = glint_id_new_near(t->set_id, mid, err)))
        goto done;
    snprintf(name, sizeof name, "materials/%s", mid);
    if ((rc = store_blob_path(f->st, name, dir, sizeof dir, err)) ||
        (rc = material_save_deferred(&m, dir, err)))
        goto done;
    t0 = srv_timing_step(t->tm, "save", t0);
    glint_time_iso(time(NULL), created);
    views = json_array();
    for (int v = 0; v < t->nviews; v++)
        if (t->used[v])
            json_array_append_new(views, json_integer(v));
    d = json_pack("{s:s, s:s, s:s, s:s, s:o}", "id", mid, "gbuffer_set_id", t->set_id,
                  "created", created, "method", t->m->name, "views_used", views);
    if (!d) {
        rc = glint_err_set(err, GLINT_ENOMEM, "cannot build the material object");
        goto done;
    }
    summary = material_summary(&m);
    json_object_update(d, summary);
    json_decref(summary);
    json_object_set(d, "params", json_object_get(m.info, "params"));
    json_object_set(d, "errors", json_object_get(m.info, "errors"));
    json_object_set(d, "seconds", json_object_get(m.info, "seconds"));
    json_object_set(d, "precomputation", json_object_get(m.info, "precomputation"));
    if (json_object_get(m.info, "choice")) /* method auto: what it chose and why */
        json_object_set(d, "choice", json_object_get(m.info, "choice"));
    json_object_set_new(d, "links", gb_links(mid, t->set_id));
    if ((rc = store_material_put(f->st, mid, t->set_id, d, err)))
        goto done;
    srv_timing_step(t->tm, "record", t0);
    {
        char *text = json_text(d, 0);
        if (text)
            memo_doc_put(f->memo, mid, "", "", text, strlen(text));
        free(text);
    }
    *doc = d;
    d = NULL;
done:
    json_decref(d);
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
