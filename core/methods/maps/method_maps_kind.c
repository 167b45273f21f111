/* method_maps_kind.c: a method of material maps over another method's
 * products, described by a maps_kind (internal/method_maps_int.h): the
 * checks across its knobs, its fit and report, its resource rules.  maps
 * (method_maps.c) and hybrid (method_hybrid.c) are two of these. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "scene.h"
#include "internal/method_maps_int.h"

const char *const maps_merge_values[] = {"lsq", "min", NULL};

/* ---- parameters ----------------------------------------------------------------------- */

int maps_kind_params_check(const maps_kind *k, const void *params, glint_err *err)
{
    matmap_params q;
    k->knobs(params, &q);
    if (q.rounds > 0 && q.refine < 1)
        return glint_err_set(err, GLINT_EINVAL,
                             "rounds %d needs refine >= 1: back-fitting refines the "
                             "coefficients after every round", q.rounds);
    if ((long)q.components * q.res > MAPS_ROWS_MAX)
        return glint_err_set(err, GLINT_EINVAL,
                             "components x map_res = %ld exceeds %d: lower one of them",
                             (long)q.components * q.res, MAPS_ROWS_MAX);
    return 0;
}

/* ---- fit ------------------------------------------------------------------------------ */

typedef struct src_ctx {
    const method_fit_in *in;
    const method *product;
} src_ctx;

static int src_fit(void *cls, const float *rgb, material *out, glint_err *err)
{
    const src_ctx *x = cls;
    method_fit_in in = *x->in;
    in.rgb = rgb;
    in.memo = NULL; /* values of the maps' own, not the tagged paintings */
    in.view_tags = NULL;
    return x->product->fit(&in, out, err);
}

/* Material m per unit light at sample i of s, at the sample's texture
 * coordinates (OUT: v[3]). */
static void sample_eval(const material *m, const samples *s, int i, double v[3])
{
    double n[3], wi[3], wo[3], uv[2];
    for (int c = 0; c < 3; c++) {
        n[c] = s->nrm[3 * (size_t)i + c];
        wi[c] = s->wi[3 * (size_t)i + c];
        wo[c] = s->wo[3 * (size_t)i + c];
    }
    uv[0] = s->uv[2 * (size_t)i];
    uv[1] = s->uv[2 * (size_t)i + 1];
    material_eval_at(m, uv, n, wi, wo, v);
}

/* A product at every sample: what its fit fitted. */
static int src_predict(void *cls, const material *m, float *f, glint_err *err)
{
    const samples *s = ((const src_ctx *)cls)->in->s;
    (void)err;
    for (int i = 0; i < s->n; i++) {
        double v[3];
        sample_eval(m, s, i, v);
        for (int c = 0; c < 3; c++)
            f[3 * (size_t)i + c] = (float)v[c];
    }
    return 0;
}

/* RMS and max |difference| of the fitted material against the painted
 * values on every sample, per unit light (as hf3 reports them), and the
 * squared differences and samples of each view (vse, vn: s->nviews, zeroed
 * here) apart, for the errors by view. */
static void painted_errors(const material *m, const samples *s, const float *rgb, double *rms,
                           double *max_abs, double *vse, long *vn)
{
    double ss = 0.0, mx = 0.0;
    memset(vse, 0, (size_t)s->nviews * sizeof *vse);
    memset(vn, 0, (size_t)s->nviews * sizeof *vn);
    for (int i = 0; i < s->n; i++) {
        double v[3];
        sample_eval(m, s, i, v);
        for (int c = 0; c < 3; c++) {
            double d = v[c] - rgb[3 * (size_t)i + c];
            ss += d * d;
            vse[s->view[i]] += d * d;
            if (fabs(d) > mx)
                mx = fabs(d);
        }
        vn[s->view[i]]++;
    }
    *rms = s->n ? sqrt(ss / (3.0 * s->n)) : 0.0;
    *max_abs = mx;
}

/* The report's components: per product, from the product's own report
 * and the maps' rounds. */
static json_t *components_report(const matmap *mm)
{
    json_t *comps = json_array();
    for (int k = 0; k < mm->k; k++) {
        json_t *e = json_object_get(mm->comp[k].info, "errors");
        json_array_append_new(
            comps, json_pack("{s:f, s:f, s:I, s:f}", "residual_rel_rms_after", mm->rel_rms[k + 1],
                             "log_residual_rms",
                             json_number_value(json_object_get(e, "log_residual_rms")),
                             "clamped_samples", (json_int_t)mm->clamped[k], "fit_seconds",
                             json_number_value(json_object_get(
                                 json_object_get(mm->comp[k].info, "seconds"), "fit"))));
    }
    return comps;
}

/* The report's stop: why the maps stopped adding products, and what the
 * refinement and rounds gave. */
static json_t *stop_report(const matmap *mm, const matmap_params *q)
{
    json_t *stops = json_pack("{s:s, s:f, s:i, s:f, s:s, s:i, s:f, s:f, s:i}", "reason", mm->stop,
                              "residual_rel_rms", mm->rel_rms[mm->k], "components", mm->k,
                              "tolerance", q->tol, "refine", mm->refine, "refine_sweeps",
                              mm->refine_sweeps, "model_rel_rms_greedy", mm->model_rel_rms[0],
                              "model_rel_rms_refined", mm->model_rel_rms[1], "rounds",
                              mm->rounds);
    if (stops && mm->rounds > 0) {
        json_t *rr = json_array();
        for (int i = 0; i <= mm->rounds; i++)
            json_array_append_new(rr, json_real(mm->round_rel_rms[i]));
        json_object_set_new(stops, "model_rel_rms_per_round", rr);
    }
    return stops;
}

int maps_kind_fit(const maps_kind *k, const method_fit_in *in, material *out, glint_err *err)
{
    src_ctx x = {in, k->product};
    matmap_source src = {in->s, src_fit, src_predict, &x};
    matmap_params q;
    matmap mm;
    json_t *info, *pre, *comps, *tim, *errs, *stops;
    double t0 = glint_now(), rms, mx, vse[SCENE_MAX_VIEWS];
    long vn[SCENE_MAX_VIEWS];
    int rc;

    memset(out, 0, sizeof *out);
    k->knobs(in->params, &q);
    if ((rc = matmap_fit_source(&src, in->rgb, &q, &mm, err)))
        return rc;
    /* the products' own reports: the first holds the precomputation's */
    pre = json_deep_copy(json_object_get(mm.comp[0].info, "precomputation"));
    comps = components_report(&mm);
    stops = stop_report(&mm, &q);
    if ((rc = maps_material_init(out, k->self, &mm, NULL, err))) {
        matmap_free(&mm);
        json_decref(pre);
        json_decref(comps);
        json_decref(stops);
        return rc;
    }
    painted_errors(out, in->s, in->rgb, &rms, &mx, vse, vn);
    errs = json_pack("{s:f, s:f, s:f, s:o}", "rms_painted", rms, "max_abs_painted", mx,
                     "residual_rel_rms", maps_matmap(out)->rel_rms[maps_matmap(out)->k],
                     "rms_by_view", method_rms_by_view(vse, vn, in->s->nviews));
    tim = json_pack("{s:f, s:f}", "maps", maps_matmap(out)->seconds, "fit", glint_now() - t0);
    info = json_pack("{s:o, s:o, s:o, s:o, s:o, s:o, s:s}", "params",
                     method_params_to_json(k->self, in->params), "precomputation",
                     pre ? pre : json_object(), "seconds", tim, "errors", errs, "components",
                     comps, "stop", stops, "product", k->product->name);
    json_decref(out->info); /* material_init's empty object */
    out->info = info;
    return 0;
}

/* ---- resources ------------------------------------------------------------------------ */

int maps_kind_holdout_ok(const maps_kind *k, const void *params)
{
    return k->product->holdout_ok(params);
}

/* The product's fit, then per sample the residual, prediction, scales and
 * pairs, and the textures.  The maps need texture coordinates: samples
 * imported without them are refused by the fit with a message
 * (matmap_fit_source). */
size_t maps_kind_fit_bytes(const maps_kind *k, const void *params, long nsamples)
{
    matmap_params q;
    k->knobs(params, &q);
    return method_fit_bytes(k->product, params, nsamples) + (size_t)nsamples * 64 +
           (size_t)(q.components + 2) * q.res * q.res * 8;
}

/* The product's fit, then the maps' rounds over the samples, per
 * component. */
double maps_kind_fit_seconds(const maps_kind *k, const void *params, long nsamples)
{
    matmap_params q;
    k->knobs(params, &q);
    return method_fit_seconds(k->product, params, nsamples) +
           (double)(q.components + 1) * nsamples * METHOD_SECONDS_PER_SAMPLE;
}
