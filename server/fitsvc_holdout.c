/* fitsvc_holdout.c: the held-out error of a fit point (fitsvc.h): one
 * background measurement per point at a time, sharing the memo's images. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "fitsvc_int.h"
#include "log.h"
#include "par.h"
#include "prep.h"

/* ---- held-out error ---------------------------------------------------------------- */

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

static int holdout_job(job *j, void *arg, json_t **result, glint_err *err)
{
    holdout_task *h = arg;
    json_t *r = NULL;
    int rc;

    (void)result;
    if (h->f->work && (rc = admit_wait(h->f->work, h->bytes, "a held-out measurement",
                                       fitsvc_job_cancelled, j, err)))
        return rc;
    /* off the worker pool: a painter's fit that starts meanwhile finds the
     * pool free (par.h), instead of running on its own thread beside a
     * measurement no one waits for */
    par_background(1);
    rc = prep_holdout(h->m, h->params, cache_data(h->pattern), h->paintings, fitsvc_job_cancelled,
                      fitsvc_job_progress, j, &r, err);
    par_background(0);
    if (h->f->work)
        admit_leave(h->f->work, h->bytes);
    if (rc)
        return rc;
    json_object_set_new(r, "material_id", json_string(h->material_id));
    return points_set_holdout(h->f->points, h->scene_hash, h->key, r, err);
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
    if (jobs_submit(t->f->jobs, "holdout", "", holdout_job, h, holdout_free, id, &e))
        log_line("held-out evaluation not scheduled: %s", e.msg);
}

