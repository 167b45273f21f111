/* prep_holdout.c: the held-out error of a fit (prep.h), and what prep.c
 * and it share (prep_int.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "prep.h"
#include "internal/prep_int.h"

/* A pattern's cache file was cut short while `who` read it (samples.h). */
int prep_torn_error(glint_err *err, const char *who)
{
    return glint_err_set(err, GLINT_EIO, "the sampling pattern's cache file was cut short while "
                         "%s read it: the next fit reads it again, or rebuilds it", who);
}

/* The material under each sample's point light, times its intensity, for
 * the samples of view k (every sample when k < 0; the others untouched). */
void prep_point_lit(const samples *s, const material *m, int k, float *rgb)
{
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], v[3], uv[2] = {0.0, 0.0};
        if (k >= 0 && s->view[i] != k)
            continue;
        for (int c = 0; c < 3; c++) {
            n[c] = s->nrm[3 * i + c];
            wi[c] = s->wi[3 * i + c];
            wo[c] = s->wo[3 * i + c];
        }
        if (s->uv) {
            uv[0] = s->uv[2 * (size_t)i];
            uv[1] = s->uv[2 * (size_t)i + 1];
        }
        material_eval_at(m, s->uv ? uv : NULL, n, wi, wo, v);
        for (int c = 0; c < 3; c++)
            rgb[3 * i + c] = (float)(v[c] * s->intensity[i]);
    }
}

/* ---- held-out error ------------------------------------------------------------------ */

/* RMS and max |pred - painted| over view k's samples of s and RGB;
 * samples pred gives no value (NaN) are not counted. */
static void view_error(const samples *s, const float *pred, int k, const img *painting,
                       double *rms, double *max_abs, long *count)
{
    double ss = 0.0, mx = 0.0;
    long cnt = 0;
    for (int i = 0; i < s->n; i++) {
        const float *px;
        if (s->view[i] != k || isnan(pred[3 * i]))
            continue;
        px = painting->px + (size_t)s->pixel[i] * painting->channels;
        for (int ch = 0; ch < 3; ch++) {
            double d = (double)pred[3 * i + ch] - px[painting->channels == 1 ? 0 : ch];
            ss += d * d;
            if (fabs(d) > mx)
                mx = fabs(d);
        }
        cnt++;
    }
    *rms = cnt ? sqrt(ss / (3.0 * cnt)) : 0.0;
    *max_abs = mx;
    *count = cnt;
}

static int painting_check(const samples *all, int k, const img *painting, glint_err *err)
{
    if (!painting->px || painting->width != all->width || painting->height != all->height ||
        painting->channels < 1 || painting->channels == 2 || painting->channels > 4)
        return glint_err_set(err, GLINT_EINVAL, "painting of view %d does not match its view",
                             k);
    return 0;
}

/* The error of m on the samples of view k: RMS and max |fitted - painted|
 * over the view's samples and RGB, the fitted values from the method's
 * own model (prep_predict) on a preparation of view k's samples alone,
 * made in c; samples it gives no value (NaN) are not counted. */
static int error_on_view(const method *mt, const void *params, cache *c, const material *m,
                         const samples *all, int k, const img *painting, double *rms,
                         double *max_abs, long *count, const glint_cancel *cancel,
                         glint_err *err)
{
    unsigned char use[SCENE_MAX_VIEWS];
    samples one;
    prep *p = NULL;
    const samples *s = all;
    float *pred = NULL;
    int rc = 0;

    if ((rc = painting_check(all, k, painting, err)))
        return rc;
    if (mt->predict) {
        for (int v = 0; v < SCENE_MAX_VIEWS; v++)
            use[v] = v == k;
        if ((rc = samples_subset(all, use, NULL, &one, err)) ||
            (rc = prep_acquire_samples(c, mt, params, &one, NULL, NULL, cancel, &p, err)))
            return rc;
        s = prep_samples(p);
    }
    if (!(pred = malloc((size_t)3 * (s->n ? s->n : 1) * sizeof *pred))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for %d samples", s->n);
        goto out;
    }
    if (p)
        rc = prep_predict(p, m, pred, err);
    else
        prep_point_lit(s, m, k, pred);
    if (rc)
        goto out;
    view_error(s, pred, k, painting, rms, max_abs, count);
out:
    free(pred);
    if (p)
        prep_release(c, p);
    return rc;
}

/* View k held out: the method fitted to the other views' samples (the
 * pattern those views alone make, prepared in c) and measured on k. */
static int error_fold(const method *m, const void *params, cache *c, const samples *all,
                      const img *paintings, int k, double *rms, double *mabs, long *cnt,
                      const glint_cancel *cancel, glint_err *err)
{
    unsigned char use[SCENE_MAX_VIEWS];
    samples fold;
    prep *p = NULL;
    material mat;
    int rc;
    for (int v = 0; v < all->nviews; v++)
        use[v] = all->used[v] && v != k;
    rc = samples_subset(all, use, NULL, &fold, err);
    if (rc == 0 &&
        (rc = prep_acquire_samples(c, m, params, &fold, NULL, NULL, cancel, &p, err)) == 0) {
        rc = prep_fit(p, paintings, NULL, &mat, err);
        prep_release(c, p);
    }
    if (rc == 0) {
        rc = error_on_view(m, params, c, &mat, all, k, &paintings[k], rms, mabs, cnt, cancel,
                           err);
        material_free(&mat);
    }
    return rc;
}

/* View k held out of a fit on the preparation of every sample (method.
 * fits_held): the samples of view k left out, then predicted. */
static int error_held(const prep *full, const img *paintings, int k, double *rms, double *mabs,
                      long *cnt, glint_err *err)
{
    const samples *s = prep_samples(full);
    unsigned char *held = malloc((size_t)(s->n ? s->n : 1));
    float *rgb = malloc((size_t)3 * (s->n ? s->n : 1) * sizeof *rgb);
    float *pred = malloc((size_t)3 * (s->n ? s->n : 1) * sizeof *pred);
    material mat;
    int rc;
    memset(&mat, 0, sizeof mat);
    if (!held || !rgb || !pred) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for %d samples", s->n);
        goto out;
    }
    for (int i = 0; i < s->n; i++)
        held[i] = s->view[i] == k;
    if (!(rc = painting_check(s, k, &paintings[k], err)) &&
        !(rc = samples_gather(s, paintings, rgb, err)) &&
        !(rc = prep_fit_held(full, rgb, held, &mat, err)) &&
        !(rc = prep_predict(full, &mat, pred, err)))
        view_error(s, pred, k, &paintings[k], rms, mabs, cnt);
out:
    material_free(&mat);
    free(held);
    free(rgb);
    free(pred);
    return rc;
}

int prep_holdout(const method *m, const void *params, const samples *all,
                 const img *paintings, int (*cancelled)(void *cls), prep_progress_fn cb,
                 void *cls, const glint_cancel *cancel, json_t **result, glint_err *err)
{
    unsigned char use[SCENE_MAX_VIEWS];
    cache *c = NULL;
    prep *full = NULL;
    json_t *per = NULL;
    double ss = 0.0, mx = 0.0, t0 = glint_now();
    long total = 0;
    int rc, nused = 0, done = 0;

    *result = NULL;
    for (int v = 0; v < all->nviews; v++)
        nused += all->used[v] != 0;
    if (nused < 2)
        return glint_err_set(err, GLINT_EINVAL, "a held-out error needs 2 painted views, not %d",
                             nused);
    /* a private cache: the folds' precomputations are not worth keeping */
    if ((rc = cache_open(NULL, 0, &c, err)))
        return rc;
    /* a method that leaves samples out of a fit needs one preparation of
     * every sample; the others one of each fold and one of each view */
    if (m->fits_held && m->predict) {
        samples copy;
        for (int v = 0; v < all->nviews && v < SCENE_MAX_VIEWS; v++)
            use[v] = all->used[v];
        if ((rc = samples_subset(all, use, NULL, &copy, err)) ||
            (rc = prep_acquire_samples(c, m, params, &copy, NULL, NULL, cancel, &full, err)))
            goto out;
    }
    if (!(per = json_array())) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto out;
    }
    for (int k = 0; k < all->nviews; k++) {
        double rms = 0.0, mabs = 0.0;
        long cnt = 0;
        if (!all->used[k])
            continue;
        if ((cancelled && cancelled(cls)) || glint_cancelled(cancel)) {
            rc = glint_cancel_err(err, "the held-out measurement");
            goto out;
        }
        if (cb)
            cb(cls, "holdout", (double)done / nused);
        rc = full ? error_held(full, paintings, k, &rms, &mabs, &cnt, err)
                  : error_fold(m, params, c, all, paintings, k, &rms, &mabs, &cnt, cancel, err);
        if (rc) {
            glint_err_prefix(err, "holding out view %d", k);
            goto out;
        }
        json_array_append_new(per, json_pack("{s:i, s:f, s:I}", "view", k, "rms", rms, "pixels",
                                             (json_int_t)cnt));
        ss += rms * rms * 3.0 * (double)cnt;
        total += cnt;
        if (mabs > mx)
            mx = mabs;
        done++;
    }
    if (samples_torn(all)) {
        rc = prep_torn_error(err, "the held-out measurement");
        goto out;
    }
    *result = json_pack("{s:s, s:f, s:f, s:I, s:i, s:o, s:f}", "method", "leave-one-view-out",
                        "rms", total ? sqrt(ss / (3.0 * (double)total)) : 0.0, "max_abs", mx,
                        "pixels", (json_int_t)total, "views", nused, "per_view", per,
                        "seconds", glint_now() - t0);
    per = NULL;
    if (!*result)
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
out:
    json_decref(per);
    if (full)
        prep_release(c, full);
    cache_close(c);
    return rc;
}
