/* fitsvc.c: fits as a service (fitsvc.h). */
#include "fitsvc.h"
#include "fitsvc_int.h"

#include <malloc.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "clock.h"
#include "events.h"
#include "ids.h"
#include "json_text.h"
#include "log.h"
#include "material.h"
#include "par.h"
#include "prep.h"
#include "scenes.h"
#include "store.h"


/* ---- scenes ----------------------------------------------------------------------- */

static int src_load(void *cls, const char *id, const scene **out, glint_err *err)
{
    return scenes_load(cls, id, out, err);
}

static void src_unload(void *cls, const scene *sc)
{
    (void)cls;
    scenes_unload(sc);
}

int fitsvc_scene(fitsvc *f, const char *scene_id, cache_entry **out, glint_err *err)
{
    prep_scene_source src = {src_load, src_unload, f->st};
    *out = NULL;
    if (scene_id && !scene_id[0]) { /* a material fitted from a G-buffer set */
        glint_err_set(err, GLINT_EUNSUPPORTED,
                      "this material was fitted from uploaded G-buffers (a G-buffer set): it "
                      "has no scene or mesh, which this needs; use a material fitted through a "
                      "session on a scene");
        return glint_err_kind(err, "no-scene");
    }
    if (!glint_id_valid(scene_id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no scene %.40s", scene_id ? scene_id : "");
    return prep_scene_acquire(f->cache, scene_id, &src, out, err);
}

/* ---- materials ------------------------------------------------------------------------ */

int fitsvc_material_doc(fitsvc *f, const char *id, memo_doc *out, glint_err *err)
{
    json_t *j = NULL;
    const char *sid, *scid, *set = "";
    int rc;

    memset(out, 0, sizeof *out);
    if (!glint_id_valid(id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no material %.40s", id ? id : "");
    if (memo_doc_get(f->memo, id, out) == 0)
        return 0;
    if ((rc = store_material_get(f->st, id, &j, err)))
        return rc == GLINT_ENOTFOUND ? glint_err_set(err, rc, "no material %s", id) : rc;
    sid = json_string_value(json_object_get(j, "session_id"));
    scid = json_string_value(json_object_get(j, "scene_id"));
    if (!sid && !scid && json_is_string(json_object_get(j, "gbuffer_set_id"))) {
        sid = scid = ""; /* fitted from a G-buffer set (fitsvc_gbuf.c): no session, no scene */
        set = json_string_value(json_object_get(j, "gbuffer_set_id"));
    }
    if (!sid || !scid) {
        json_decref(j);
        return glint_err_set(err, GLINT_EINTERNAL, "material %s names no session or scene", id);
    }
    if (f->links) /* the links of today, whatever the record was stored with */
        json_object_set_new(j, "links", f->links(id, sid, scid, set));
    snprintf(out->session, sizeof out->session, "%s", sid);
    snprintf(out->scene, sizeof out->scene, "%s", scid);
    out->text = json_text(j, 0);
    json_decref(j);
    if (!out->text)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    out->len = strlen(out->text);
    memo_doc_put(f->memo, id, out->session, out->scene, out->text, out->len);
    return 0;
}

/* ---- fit tasks --------------------------------------------------------------------- */


static void task_free(void *p)
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

/* The views' paintings (task_read_paintings); listed[nviews]: scratch. */
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
static int task_read_paintings(fit_task *t, glint_err *err)
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
static int task_bytes(fit_task *t, glint_err *err)
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

/* ---- running a fit ------------------------------------------------------------------ */

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
    if ((rc = task_read_paintings(t, err)))
        goto out;
    t0 = srv_timing_step(tm, "paintings", t0);
    if ((rc = task_bytes(t, err)))
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
    rc = jobs_submit(f->jobs, "fit", session_id, m->name, fit_job, t, task_free, job_id, err);
    return rc; /* the job owns the task (freed even on failure) */
out:
    task_free(t);
    return rc;
}

/* ---- life cycle ----------------------------------------------------------------------- */

static void idle_flush(void *cls)
{
    points_flush(cls, 1);
}

int fitsvc_open(const fitsvc_config *cfg, store *st, events *ev, fitsvc **out, glint_err *err)
{
    fitsvc *f;
    char dir[4200];
    int rc;

    *out = NULL;
    /* A fit allocates a few arrays of 0.1 to 30 MiB (samples, log values,
     * diagnostics) and frees them at once.  With glibc's defaults these go
     * to fresh mmaps or trimmed heap tops, and every fit pays the page
     * faults again (measured: 38 -> 22 ms for a warm fit of 393,512
     * samples).  Keep them in the heap.  Process-wide: startup only. */
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 64 << 20);
    if (!(f = calloc(1, sizeof *f)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    f->st = st;
    f->ev = ev;
    f->work = cfg->work;
    f->background = cfg->background;
    f->links = cfg->links;
    pthread_mutex_init(&f->lock, NULL);
    if (!(f->holdouts = json_object())) {
        free(f);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    if (cfg->cache_dir)
        snprintf(dir, sizeof dir, "%s/points", cfg->cache_dir);
    if ((rc = cache_open(cfg->cache_dir, cfg->budget, &f->cache, err)) ||
        (rc = memo_open(cfg->budget / 8, cfg->budget / 32, &f->memo, err)) ||
        (rc = points_open(cfg->cache_dir ? dir : NULL, &f->points, err)) ||
        (rc = jobs_open(cfg->threads, idle_flush, f->points, POINTS_SAVE_PERIOD_S, &f->jobs,
                        err)) ||
        (st && (rc = fitsvc_pixels_start(f, err)))) {
        fitsvc_close(f);
        return rc;
    }
    /* every level of every method shows in /metrics from the start */
    cache_declare_level(f->cache, "scene");
    cache_declare_level(f->cache, "pattern");
    for (int i = 0; i < method_count(); i++)
        for (int l = 0; l < method_at(i)->nlevels; l++)
            cache_declare_level(f->cache, method_at(i)->levels[l].name);
    *out = f;
    return 0;
}

void fitsvc_shutdown(fitsvc *f)
{
    if (f)
        jobs_shutdown(f->jobs);
}

void fitsvc_stop(fitsvc *f)
{
    if (f)
        jobs_stop(f->jobs);
}

void fitsvc_close(fitsvc *f)
{
    if (!f)
        return;
    jobs_close(f->jobs); /* running jobs finish first: they hold cache entries */
    fitsvc_pixels_stop(f); /* holds the memo's paintings while it writes */
    fitsvc_memo_close(f);
    points_close(f->points);
    memo_close(f->memo);
    cache_close(f->cache);
    json_decref(f->holdouts);
    pthread_mutex_destroy(&f->lock);
    free(f);
}

cache *fitsvc_cache(fitsvc *f)
{
    return f->cache;
}

jobs *fitsvc_jobs(fitsvc *f)
{
    return f->jobs;
}

memo *fitsvc_memo(fitsvc *f)
{
    return f->memo;
}

points *fitsvc_points(fitsvc *f)
{
    return f->points;
}

void fitsvc_metrics(fitsvc *f, FILE *o)
{
    cache_stats s;
    unsigned long long hits, misses;

    pthread_mutex_lock(&f->lock);
    hits = f->hits;
    misses = f->misses;
    pthread_mutex_unlock(&f->lock);
    cache_stats_get(f->cache, &s);
    fprintf(o, "# HELP glintd_fit_requests_total Fit requests by whether the whole "
               "precomputation was in memory.\n# TYPE glintd_fit_requests_total counter\n");
    fprintf(o, "glintd_fit_requests_total{cache=\"hit\"} %llu\n", hits);
    fprintf(o, "glintd_fit_requests_total{cache=\"miss\"} %llu\n", misses);
    fprintf(o, "# HELP glintd_fitcache_lookups_total Precomputation cache lookups by level and "
               "outcome (hit: in memory; joined: waited for another request's build; built).\n"
               "# TYPE glintd_fitcache_lookups_total counter\n");
    for (int l = 0; l < s.nlevels; l++) {
        const cache_level_stats *ls = &s.level[l];
        fprintf(o, "glintd_fitcache_lookups_total{level=\"%s\",outcome=\"hit\"} %llu\n",
                ls->name, ls->hits);
        fprintf(o, "glintd_fitcache_lookups_total{level=\"%s\",outcome=\"joined\"} %llu\n",
                ls->name, ls->joins);
        fprintf(o, "glintd_fitcache_lookups_total{level=\"%s\",outcome=\"built\"} %llu\n",
                ls->name, ls->builds);
    }
    fprintf(o, "# HELP glintd_fitcache_build_failures_total Builds that failed, by level.\n"
               "# TYPE glintd_fitcache_build_failures_total counter\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_build_failures_total{level=\"%s\"} %llu\n",
                s.level[l].name, s.level[l].failures);
    fprintf(o, "# HELP glintd_fitcache_build_seconds_total Time spent building, by level.\n"
               "# TYPE glintd_fitcache_build_seconds_total counter\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_build_seconds_total{level=\"%s\"} %.6f\n", s.level[l].name,
                s.level[l].build_seconds);
    fprintf(o, "# HELP glintd_fitcache_evictions_total Entries evicted (least recently used) to "
               "keep the byte budget.\n# TYPE glintd_fitcache_evictions_total counter\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_evictions_total{level=\"%s\"} %llu\n", s.level[l].name,
                s.level[l].evictions);
    fprintf(o, "# HELP glintd_fitcache_bytes Bytes held in memory, by level.\n"
               "# TYPE glintd_fitcache_bytes gauge\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_bytes{level=\"%s\"} %zu\n", s.level[l].name,
                s.level[l].bytes);
    fprintf(o, "# HELP glintd_fitcache_entries Entries in memory, by level.\n"
               "# TYPE glintd_fitcache_entries gauge\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_entries{level=\"%s\"} %zu\n", s.level[l].name,
                s.level[l].entries);
    fprintf(o, "# HELP glintd_fitcache_budget_bytes The in-memory budget.\n"
               "# TYPE glintd_fitcache_budget_bytes gauge\nglintd_fitcache_budget_bytes %zu\n",
            s.budget);
    {
        unsigned long long loads = 0, builds = 0, rebuilds = 0;
        for (int l = 0; l < s.nlevels; l++) {
            loads += s.level[l].disk_loads;
            builds += s.level[l].disk_builds;
            rebuilds += s.level[l].disk_rebuilds;
        }
        fprintf(o, "# HELP glintd_fitcache_disk_total Disk-backed levels by what the disk "
                   "cache answered.\n# TYPE glintd_fitcache_disk_total counter\n");
        fprintf(o, "glintd_fitcache_disk_total{outcome=\"loaded\"} %llu\n", loads);
        fprintf(o, "glintd_fitcache_disk_total{outcome=\"built\"} %llu\n", builds);
        fprintf(o, "glintd_fitcache_disk_total{outcome=\"rebuilt\"} %llu\n", rebuilds);
    }
    memo_metrics(f->memo, o);
    fitsvc_pixels_metrics(f, o);
    fitsvc_memo_metrics(f, o);
    jobs_metrics(f->jobs, o);
}
