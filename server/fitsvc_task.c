/* fitsvc_task.c: what a session's fit needs before it runs (fitsvc_int.h):
 * its paintings, read as a snapshot (from the memo, the decoded pixels kept
 * beside an upload, or the upload), its samples and its memory bound; and
 * the checks and job callbacks every fit shares. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "fitsvc_int.h"
#include "log.h"
#include "material.h"
#include "par.h"
#include "prep.h"
#include "store.h"

void fit_task_free(void *p)
{
    fit_task *t = p;
    if (!t)
        return;
    for (int v = 0; t->paintings && v < t->nviews; v++) {
        if (t->pins && t->pins[v])
            memo_painting_release(t->f->memo, t->pins[v]);
        else
            img_free(&t->paintings[v]);
    }
    free(t->paintings);
    free(t->pins);
    free(t->use);
    free(t->versions);
    free(t->params);
    cache_release(t->f->cache, t->scene);
    free(t);
}

/* Reading the paintings the memo does not hold, one view per task on the
 * worker pool (par.h): after a restart a 12-view fit reads 12 images.  A
 * view's decoded pixels kept beside its upload (store.h) are read first;
 * else the upload is read and decoded.  Its version may have moved on
 * since the list: version[v] says what was read (0: no painting now). */
typedef struct read_ctx {
    fit_task *t;
    img *im;
    int *rc;
    glint_err *err;
    int *views;
    int64_t *version;
    unsigned char *kept, *invalid;
} read_ctx;

static void read_run(void *ctx, int i)
{
    read_ctx *x = ctx;
    int v = x->views[i], rc;
    void *data = NULL;
    size_t len = 0;
    glint_err pe;

    rc = store_painting_pixels_get(x->t->f->st, x->t->session_id, v, 0, &x->im[v],
                                   &x->version[v], &pe);
    if (rc == 0 && (rc = img_to_rgb(&x->im[v], &pe)) == 0) {
        x->kept[v] = 1;
        return;
    }
    img_free(&x->im[v]);
    if (rc == GLINT_EFORMAT) /* decoded again below, and kept again after */
        log_line("painting of session %s view %d: %s", x->t->session_id, v, pe.msg);
    rc = store_painting_get(x->t->f->st, x->t->session_id, v, &data, &len, &x->version[v],
                            &x->err[v]);
    if (rc == GLINT_ENOTFOUND) {
        x->version[v] = 0;
        return;
    }
    if (!rc) {
        rc = img_read_mem(data, len, &x->im[v], &x->err[v]);
        if (!rc && (rc = img_to_rgb(&x->im[v], &x->err[v])))
            img_free(&x->im[v]);
        x->invalid[v] = rc != 0;
    }
    free(data);
    x->rc[v] = rc;
}

/* The views' paintings (fit_task_read_paintings); listed[nviews]: scratch. */
static int read_views(fit_task *t, const scene *sc, int64_t *listed, glint_err *err)
{
    int nv = sc->nviews, nread = 0, npixels = 0, rc = 0;
    json_t *list = NULL, *it;
    size_t i;
    img *im = calloc((size_t)nv, sizeof *im);
    int *rcs = calloc((size_t)nv, sizeof *rcs), *views = calloc((size_t)nv, sizeof *views);
    glint_err *errs = calloc((size_t)nv, sizeof *errs);
    int64_t *version = calloc((size_t)nv, sizeof *version);
    unsigned char *flags = calloc((size_t)nv, 2);

    if (!im || !rcs || !views || !errs || !version || !flags) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    /* the versions first, in one query: a painting the memo holds at its
     * version is not read from the store at all */
    if ((rc = store_paintings_list(t->f->st, t->session_id, &list, err)))
        goto done;
    json_array_foreach(list, i, it) {
        int v = (int)json_integer_value(json_object_get(it, "view"));
        if (v >= 0 && v < nv)
            listed[v] = json_integer_value(json_object_get(it, "version"));
    }
    json_decref(list);
    for (int v = 0; v < nv; v++)
        if (listed[v] > 0 && /* else never painted: not in the pattern */
            memo_painting_get(t->f->memo, t->session_id, v, listed[v], &t->pins[v]) != 0)
            views[nread++] = v;
    {
        read_ctx x = {t, im, rcs, errs, views, version, flags, flags + nv};
        par_run(nread, read_run, &x);
    }
    for (int k = 0; k < nread; k++) {
        int v = views[k];
        if (rcs[v]) {
            *err = errs[v];
            glint_err_prefix(err, "painting of view %d", v);
            if (flags[nv + v])
                rc = glint_err_kind(err, "invalid-painting");
            else
                rc = rcs[v];
            goto done;
        }
        listed[v] = version[v];
        if (version[v] <= 0)
            continue;
        npixels += flags[v];
        if (memo_painting_get(t->f->memo, t->session_id, v, version[v], &t->pins[v]) == 0)
            continue; /* another fit put it meanwhile */
        if (memo_painting_put(t->f->memo, t->session_id, v, listed[v], &im[v], &t->pins[v])) {
            t->paintings[v] = im[v]; /* not kept by the memo: the task's own */
            memset(&im[v], 0, sizeof im[v]);
        } else if (!flags[v]) { /* decoded: kept beside its upload for the next restart */
            fitsvc_painting_stored(t->f, t->session_id, v, listed[v]);
        }
    }
    fitsvc_pixels_count(t->f, npixels, nread - npixels);
    for (int v = 0; v < nv; v++) {
        if (listed[v] <= 0)
            continue;
        if (t->pins[v]) /* shared read-only with the memo */
            t->paintings[v] = *memo_painting_img(t->pins[v]);
        if (t->paintings[v].width != sc->width || t->paintings[v].height != sc->height) {
            /* painted at a multiple of the raster (the scene's paint_scale):
             * the fit reads it at the raster's pixel centres (img.h) */
            img r;
            if (img_to_raster(&t->paintings[v], sc->width, sc->height, &r, err)) {
                glint_err_prefix(err, "painting of view %d", v);
                rc = glint_err_kind(err, "invalid-painting");
                goto done;
            }
            if (t->pins[v]) {
                memo_painting_release(t->f->memo, t->pins[v]);
                t->pins[v] = NULL;
            } else {
                img_free(&t->paintings[v]);
            }
            t->paintings[v] = r;
        }
        t->use[v] = 1;
        t->versions[v] = listed[v];
        t->nused++;
    }
    if (!t->nused) {
        glint_err_set(err, GLINT_EINVAL,
                      "session %s has no painting yet: paint or upload at least one view "
                      "before fitting", t->session_id);
        rc = glint_err_kind(err, "no-paintings");
    }
done:
    for (int v = 0; im && v < nv; v++)
        img_free(&im[v]);
    free(im);
    free(rcs);
    free(views);
    free(errs);
    free(version);
    free(flags);
    return rc;
}

/* Read the session's paintings (a snapshot).  OUT: t->paintings, use,
 * versions. */
int fit_task_read_paintings(fit_task *t, glint_err *err)
{
    const scene *sc = prep_scene_of(t->scene)->sc;
    int64_t *listed;
    int rc;

    t->nviews = sc->nviews;
    t->paintings = calloc((size_t)sc->nviews, sizeof *t->paintings);
    t->use = calloc((size_t)sc->nviews, 1);
    t->versions = calloc((size_t)sc->nviews, sizeof *t->versions);
    t->pins = calloc((size_t)sc->nviews, sizeof *t->pins);
    listed = calloc((size_t)sc->nviews, sizeof *listed);
    if (!t->paintings || !t->use || !t->versions || !t->pins || !listed) {
        free(listed);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    rc = read_views(t, sc, listed, err);
    free(listed);
    return rc;
}

/* The samples of the task's views, from fitsvc's scene counts or the
 * scene's document (then kept there).  Under no lock. */
static int task_samples(fit_task *t, long *n, glint_err *err)
{
    fitsvc *f = t->f;
    fit_scene_counts got, *slot = NULL;
    json_t *doc = NULL, *views;
    int rc, found = 0;

    pthread_mutex_lock(&f->lock);
    for (lru_node *x = f->counts_lru.head; x && !found; x = x->next) {
        fit_scene_counts *c = lru_entry(x, fit_scene_counts, node);
        if (strcmp(c->id, t->scene_id) == 0 && c->nviews == t->nviews) {
            lru_touch(&f->counts_lru, x);
            memcpy(got.n, c->n, (size_t)t->nviews * sizeof got.n[0]);
            found = 1;
        }
    }
    pthread_mutex_unlock(&f->lock);
    if (!found) {
        if (t->nviews > SCENE_MAX_VIEWS)
            return glint_err_set(err, GLINT_EINTERNAL, "scene %s has %d views", t->scene_id,
                                 t->nviews);
        if ((rc = store_scene_get(f->st, t->scene_id, &doc, err)))
            return rc;
        views = json_object_get(doc, "views");
        for (int v = 0; v < t->nviews; v++)
            got.n[v] = (long)json_integer_value(
                json_object_get(json_array_get(views, (size_t)v), "samples"));
        json_decref(doc);
        pthread_mutex_lock(&f->lock);
        if (f->counts_lru.n < FITSVC_SCENES) { /* an empty slot */
            for (int i = 0; i < FITSVC_SCENES && !slot; i++)
                if (!f->counts[i].id[0])
                    slot = &f->counts[i];
            lru_push(&f->counts_lru, &slot->node);
        } else { /* the least recently used */
            slot = lru_entry(lru_oldest(&f->counts_lru), fit_scene_counts, node);
            lru_touch(&f->counts_lru, &slot->node);
        }
        snprintf(slot->id, sizeof slot->id, "%s", t->scene_id);
        slot->nviews = t->nviews;
        memcpy(slot->n, got.n, (size_t)t->nviews * sizeof got.n[0]);
        pthread_mutex_unlock(&f->lock);
    }
    *n = 0;
    for (int v = 0; v < t->nviews; v++)
        if (t->use[v])
            *n += got.n[v];
    return 0;
}

/* The fit's memory bound: the method's for the samples of the painted views
 * (counted when the scene was created), and the paintings.  OUT: t->bytes. */
int fit_task_bytes(fit_task *t, glint_err *err)
{
    const scene *sc = prep_scene_of(t->scene)->sc;
    long n = 0;
    int rc;

    if ((rc = task_samples(t, &n, err)))
        return rc;
    t->nsamples = n;
    t->bytes = method_fit_bytes(t->m, t->params, n) +
               (size_t)t->nused * (size_t)sc->width * (size_t)sc->height * 3 * sizeof(float);
    return 0;
}

int fitsvc_cost_check(fitsvc *f, const method *m, const void *params, long nsamples,
                      glint_err *err)
{
    char what[96];
    snprintf(what, sizeof what, "a cold %s fit of %ld samples", m->name, nsamples);
    return admit_cost(f->work, method_fit_seconds(m, params, nsamples), what, err);
}

int fitsvc_material_check(const material *m, const fit_report *r, glint_err *err)
{
    if (r->errors_ok)
        return 0;
    glint_err_set(err, GLINT_ENUMERIC,
                  "the %s fit gave no finite error statistics (values out of scale), so no "
                  "material was kept: check the parameters that scale the painting",
                  m->method ? m->method->name : "");
    return glint_err_kind(err, "numerical-failure");
}

int fitsvc_job_cancelled(void *cls)
{
    return job_cancelled(cls);
}

void fitsvc_job_progress(void *cls, const char *stage, double p)
{
    job_progress(cls, stage, p);
}
