/* fitsvc_session.c: fits of a session's paintings (fitsvc.h: fitsvc_fit).
 *
 * The task (fitsvc_task.c) reads the paintings and bounds the fit's memory;
 * with the precomputation in memory the fit runs in the request, else a job
 * builds what is missing and fits.  The fit goes through the session's
 * memo (what the views not repainted since still give), is recorded as
 * every fit is (fit_record), and adds a point to the scene's record, with
 * its held-out measurement scheduled once per configuration. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "clock.h"
#include "fitsvc.h"
#include "fitsvc_int.h"
#include "log.h"
#include "material.h"
#include "par.h"
#include "prep.h"

/* Fit with a prepared precomputation and store the material.  OUT: *doc,
 * the API's material object. */
static int fit_execute(fit_task *t, prep *p, job *j, json_t **doc, glint_err *err)
{
    fitsvc *f = t->f;
    const prep_scene *ps = prep_scene_of(t->scene);
    material m;
    fit_report rep;
    char mid[33], key[1024];
    json_t *d = NULL;
    double t0 = glint_now(), fit_s;
    int rc, was_hit = prep_was_hit(p);

    *doc = NULL;
    if (j)
        job_progress(j, "fit", 0.9);
    {
        /* the session's memo of this point: what the views not repainted
         * since its last fit still give (prep_fit_reusing) */
        uint64_t *tags = calloc((size_t)t->nviews, sizeof *tags);
        method_memo mm;
        points_key(t->m, t->params, t->use, t->nviews, key, sizeof key);
        fitsvc_memo_take(f, t->session_id, key, &mm);
        for (int v = 0; tags && v < t->nviews; v++)
            tags[v] = t->use[v] ? (uint64_t)t->versions[v] : 0;
        rc = prep_fit_reusing(p, t->paintings, NULL, tags, tags ? &mm : NULL, &m, &rep, err);
        free(tags);
        if (!rc && (rc = fitsvc_material_check(&m, &rep, err))) {
            fit_report_free(&rep);
            material_free(&m);
        }
        if (rc) { /* what the memo holds stays true of its tags */
            fitsvc_memo_put(f, t->session_id, key, &mm, 0, 0);
            return rc;
        }
        fitsvc_memo_put(f, t->session_id, key, &mm, rep.stream_chunks_reused, rep.stream_chunks);
    }
    fit_s = glint_now() - t0;
    t0 = srv_timing_step(t->tm, "fit", t0);
    {
        fit_record_in in = {t->m,      t->session_id, t->scene_id, NULL, t->use,
                            t->versions, t->nviews,   fit_s,       t->tm};
        if ((rc = fit_record(f, &in, &m, &rep, mid, &d, err)))
            goto done;
    }
    t0 = glint_now();
    { /* the scene's record grows */
        glint_err pe;
        if (points_record(f->points, ps->hash, key, t->m->name, rep.params,
                          json_object_get(d, "views_used"), prep_samples(p)->n, fit_s,
                          strcmp(rep.memory, "built") == 0 ? rep.cold_seconds : -1.0,
                          rep.from_disk, rep.rms_painted, mid, &pe))
            log_line("recording a fit point: %s", pe.msg);
        if (t->nused >= 2 && (!t->m->holdout_ok || t->m->holdout_ok(t->params)) &&
            !points_has_holdout(f->points, ps->hash, key))
            fitsvc_holdout_schedule(t, p, mid, key);
    }
    srv_timing_step(t->tm, "publish", t0);
    pthread_mutex_lock(&f->lock);
    if (was_hit)
        f->hits++;
    else
        f->misses++;
    pthread_mutex_unlock(&f->lock);
    *doc = d;
    d = NULL;
done:
    json_decref(d);
    fit_report_free(&rep);
    material_free(&m);
    return rc;
}

static int fit_job_run(job *j, fit_task *t, json_t **result, glint_err *err);

/* The job of a fit whose precomputation was not in memory. */
static int fit_job(job *j, void *arg, json_t **result, glint_err *err)
{
    fit_task *t = arg;
    fitsvc *f = t->f;
    int rc;
    fitsvc_busy(f, 1);
    rc = fit_job_run(j, t, result, err);
    fitsvc_busy(f, -1);
    return rc;
}

static int fit_job_run(job *j, fit_task *t, json_t **result, glint_err *err)
{
    glint_cancel cancel = {fitsvc_job_cancelled, j};
    prep_request rq = {t->m, t->params, t->scene, t->use, &cancel};
    prep *p = NULL;
    json_t *doc = NULL;
    int rc;

    if (t->f->work &&
        (rc = admit_wait(t->f->work, t->bytes, "the fit", fitsvc_job_cancelled, j, err)))
        return rc;
    if (!(rc = prep_acquire(t->f->cache, &rq, fitsvc_job_progress, j, &p, err))) {
        rc = fit_execute(t, p, j, &doc, err);
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

static int fit_now_or_queue(fitsvc *f, const char *session_id, const char *scene_id,
                            const method *m, const void *params, json_t **doc,
                            char job_id[33], srv_timing *tm, glint_err *err);

int fitsvc_fit(fitsvc *f, const char *session_id, const char *scene_id, const method *m,
               const void *params, json_t **doc, char job_id[33], srv_timing *tm,
               glint_err *err)
{
    int rc;
    fitsvc_busy(f, 1);
    par_warm(); /* the pool's worker wakes while the scene and paintings are found */
    rc = fit_now_or_queue(f, session_id, scene_id, m, params, doc, job_id, tm, err);
    fitsvc_busy(f, -1);
    return rc;
}

static int fit_now_or_queue(fitsvc *f, const char *session_id, const char *scene_id,
                            const method *m, const void *params, json_t **doc,
                            char job_id[33], srv_timing *tm, glint_err *err)
{
    fit_task *t = calloc(1, sizeof *t);
    prep *p = NULL;
    prep_request rq;
    double t0 = glint_now();
    int rc;

    *doc = NULL;
    job_id[0] = '\0';
    if (!t || !(t->params = malloc(m->params_size ? m->params_size : 1))) {
        free(t);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    t->f = f;
    t->m = m;
    memcpy(t->params, params, m->params_size);
    snprintf(t->session_id, sizeof t->session_id, "%s", session_id);
    snprintf(t->scene_id, sizeof t->scene_id, "%s", scene_id);
    if ((rc = fitsvc_scene(f, scene_id, &t->scene, err))) {
        if (rc == GLINT_ENOTFOUND) {
            glint_err_set(err, rc, "the session's scene %s no longer exists", scene_id);
            glint_err_kind(err, "scene-gone");
        }
        goto out;
    }
    t0 = srv_timing_step(tm, "scene", t0);
    if ((rc = fit_task_read_paintings(t, err)))
        goto out;
    t0 = srv_timing_step(tm, "paintings", t0);
    if ((rc = fit_task_bytes(t, err)))
        goto out;
    t0 = srv_timing_step(tm, "bound", t0);
    rq = (prep_request){m, t->params, t->scene, t->use, NULL};
    if (prep_try(f->cache, &rq, &p, NULL) == 0) { /* in memory: fit now */
        srv_timing_step(tm, "prepared", t0);
        t->tm = tm;
        if (!f->work || !(rc = admit_enter(f->work, t->bytes, "the fit", err))) {
            rc = fit_execute(t, p, NULL, doc, err);
            if (f->work)
                admit_leave(f->work, t->bytes);
        }
        prep_release(f->cache, p);
        goto out;
    }
    /* what can never fit is refused now, not by the job */
    if (f->work) {
        admit_stats st;
        admit_get_stats(f->work, &st);
        if (t->bytes > st.budget && (rc = admit_enter(f->work, t->bytes, "the fit", err)))
            goto out;
    }
    if ((rc = fitsvc_cost_check(f, m, t->params, t->nsamples, err)))
        goto out;
    rc = jobs_submit(f->jobs, "fit", session_id, m->name, fit_job, t, fit_task_free, job_id, err);
    return rc; /* the job owns the task (freed even on failure) */
out:
    fit_task_free(t);
    return rc;
}
