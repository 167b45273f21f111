/* method_maps.c: the maps method: parameters and fit (method_maps.h).
 * Its material operations are in method_maps_material.c. */
#include "method_maps.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_hf3_parts.h"
#include "internal/method_maps_int.h"
#include "uvtex.h"

const char *const maps_merge_values[] = {"lsq", "min", NULL};

static const method_param maps_params_table[] = {
    HF3_PARAM_ROWS(maps_params, hf.),
    MAPS_PARAM_ROWS(maps_params),
};

static const method_preset maps_presets[] = {
    {"draft", "{\"res\": 32, \"components\": 3, \"map_res\": 64}"},
    {"default", "{\"res\": 64, \"components\": 5, \"map_res\": 128}"},
    {"fine", "{\"res\": 128, \"components\": 8, \"map_res\": 256}"},
};

static void maps_params_default(void *p)
{
    maps_params *mp = p;
    matmap_params d;
    memset(mp, 0, sizeof *mp);
    fit_params_default(&mp->hf);
    mp->hf.res = 64;
    matmap_params_default(&d);
    mp->components = d.components;
    mp->merge = d.merge;
    mp->map_res = d.res;
    mp->tol = d.tol;
    mp->refine = d.refine;
    mp->rounds = d.rounds;
    mp->smooth = d.smooth;
}

int maps_knobs_check(const matmap_params *q, glint_err *err)
{
    if (q->rounds > 0 && q->refine < 1)
        return glint_err_set(err, GLINT_EINVAL,
                             "rounds %d needs refine >= 1: back-fitting refines the "
                             "coefficients after every round", q->rounds);
    if ((long)q->components * q->res > MAPS_ROWS_MAX)
        return glint_err_set(err, GLINT_EINVAL,
                             "components x map_res = %ld exceeds %d: lower one of them",
                             (long)q->components * q->res, MAPS_ROWS_MAX);
    return 0;
}

static int maps_params_check(const void *params, glint_err *err)
{
    matmap_params q;
    MAPS_KNOBS(&q, (const maps_params *)params);
    return maps_knobs_check(&q, err);
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

/* A product per unit light at every sample, at the sample's texture
 * coordinates: what its fit fitted. */
static int src_predict(void *cls, const material *m, float *f, glint_err *err)
{
    const samples *s = ((const src_ctx *)cls)->in->s;
    (void)err;
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], v[3], uv[2];
        for (int c = 0; c < 3; c++) {
            n[c] = s->nrm[3 * (size_t)i + c];
            wi[c] = s->wi[3 * (size_t)i + c];
            wo[c] = s->wo[3 * (size_t)i + c];
        }
        uv[0] = s->uv[2 * (size_t)i];
        uv[1] = s->uv[2 * (size_t)i + 1];
        material_eval_at(m, uv, n, wi, wo, v);
        for (int c = 0; c < 3; c++)
            f[3 * (size_t)i + c] = (float)v[c];
    }
    return 0;
}

/* RMS and max |difference| of the fitted material against the painted
 * values on every sample, per unit light (as hf3 reports them). */
static void painted_errors(const material *m, const samples *s, const float *rgb, double *rms,
                           double *max_abs)
{
    double ss = 0.0, mx = 0.0;
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], v[3], uv[2];
        for (int c = 0; c < 3; c++) {
            n[c] = s->nrm[3 * (size_t)i + c];
            wi[c] = s->wi[3 * (size_t)i + c];
            wo[c] = s->wo[3 * (size_t)i + c];
        }
        uv[0] = s->uv[2 * (size_t)i];
        uv[1] = s->uv[2 * (size_t)i + 1];
        material_eval_at(m, uv, n, wi, wo, v);
        for (int c = 0; c < 3; c++) {
            double d = v[c] - rgb[3 * (size_t)i + c];
            ss += d * d;
            if (fabs(d) > mx)
                mx = fabs(d);
        }
    }
    *rms = s->n ? sqrt(ss / (3.0 * s->n)) : 0.0;
    *max_abs = mx;
}

int maps_fit_with(const method_fit_in *in, const method *self, const method *product,
                  const matmap_params *q, material *out, glint_err *err)
{
    src_ctx x = {in, product};
    matmap_source src = {in->s, src_fit, src_predict, &x};
    matmap mm;
    json_t *info, *pre, *comps, *tim, *errs, *stops;
    double t0 = glint_now(), rms, mx;
    int rc;

    memset(out, 0, sizeof *out);
    if ((rc = matmap_fit_source(&src, in->rgb, q, &mm, err)))
        return rc;
    /* the products' own reports: the first holds the precomputation's */
    pre = json_deep_copy(json_object_get(mm.comp[0].info, "precomputation"));
    comps = json_array();
    for (int k = 0; k < mm.k; k++) {
        json_t *e = json_object_get(mm.comp[k].info, "errors");
        json_array_append_new(
            comps, json_pack("{s:f, s:f, s:I, s:f}", "residual_rel_rms_after", mm.rel_rms[k + 1],
                             "log_residual_rms",
                             json_number_value(json_object_get(e, "log_residual_rms")),
                             "clamped_samples", (json_int_t)mm.clamped[k], "fit_seconds",
                             json_number_value(json_object_get(
                                 json_object_get(mm.comp[k].info, "seconds"), "fit"))));
    }
    stops = json_pack("{s:s, s:f, s:i, s:f, s:s, s:i, s:f, s:f, s:i}", "reason", mm.stop,
                      "residual_rel_rms", mm.rel_rms[mm.k], "components", mm.k, "tolerance",
                      q->tol, "refine", mm.refine, "refine_sweeps", mm.refine_sweeps,
                      "model_rel_rms_greedy", mm.model_rel_rms[0], "model_rel_rms_refined",
                      mm.model_rel_rms[1], "rounds", mm.rounds);
    if (stops && mm.rounds > 0) {
        json_t *rr = json_array();
        for (int i = 0; i <= mm.rounds; i++)
            json_array_append_new(rr, json_real(mm.round_rel_rms[i]));
        json_object_set_new(stops, "model_rel_rms_per_round", rr);
    }
    if ((rc = maps_material_init(out, self, &mm, NULL, err))) {
        matmap_free(&mm);
        json_decref(pre);
        json_decref(comps);
        json_decref(stops);
        return rc;
    }
    painted_errors(out, in->s, in->rgb, &rms, &mx);
    errs = json_pack("{s:f, s:f, s:f}", "rms_painted", rms, "max_abs_painted", mx,
                     "residual_rel_rms", maps_matmap(out)->rel_rms[maps_matmap(out)->k]);
    tim = json_pack("{s:f, s:f}", "maps", maps_matmap(out)->seconds, "fit", glint_now() - t0);
    info = json_pack("{s:o, s:o, s:o, s:o, s:o, s:o, s:s}", "params",
                     method_params_to_json(self, in->params), "precomputation",
                     pre ? pre : json_object(), "seconds", tim, "errors", errs, "components",
                     comps, "stop", stops, "product", product->name);
    json_decref(out->info); /* material_init's empty object */
    out->info = info;
    return 0;
}

static int maps_fit(const method_fit_in *in, material *out, glint_err *err)
{
    matmap_params q;
    MAPS_KNOBS(&q, (const maps_params *)in->params);
    return maps_fit_with(in, &method_maps, &method_hf3, &q, out, err);
}

/* residual, prediction, scales and pairs per sample; textures */
size_t maps_extra_bytes(const matmap_params *q, long nsamples)
{
    return (size_t)nsamples * 64 + (size_t)(q->components + 2) * q->res * q->res * 8;
}

/* The maps need texture coordinates: samples imported without them are
 * refused by the fit with a message (matmap_fit_source). */
static size_t maps_fit_bytes(const void *params, long nsamples)
{
    const maps_params *mp = params;
    matmap_params q;
    MAPS_KNOBS(&q, mp);
    return hf3_fit_bytes(&mp->hf, nsamples) + maps_extra_bytes(&q, nsamples);
}

/* hf3's fit, then the maps' rounds over the samples, per component. */
static double maps_fit_seconds(const void *params, long nsamples)
{
    const maps_params *mp = params;
    return hf3_fit_seconds(&mp->hf, nsamples) +
           (double)(mp->components + 1) * nsamples * METHOD_SECONDS_PER_SAMPLE;
}

static int maps_holdout_ok(const void *params)
{
    return hf3_holdout_ok(&((const maps_params *)params)->hf);
}

static const char *const maps_surface[] = {"coefficients", NULL};

const method method_maps = {
    .name = "maps",
    .label = "Several materials",
    .summary = "Several finishes on one object: a few point-light materials blended "
        "over the surface by textures.",
    .when = "Use it for a logo on plastic, stripes or veins: paint each region as "
        "it should look, and the fit finds the materials and where each one is.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_FACTORS,
    .surface = maps_surface,
    .title = "Material maps: a sum of three-factor products weighted by textures",
    .reference = "Jaroszkiewicz & McCool, Fast Extraction of BRDFs and Material Maps from "
                 "Images, GI 2003, section 4.2",
    .description =
        "For objects painted with several materials (a logo on plastic, veins in marble): the "
        "painting is fitted as a sum of three-factor products, each weighted over the surface "
        "by a coefficient texture on the texture coordinates. Each product fits what the "
        "previous ones left (iterative residual factorization) with the cached operator of "
        "the three-factor method, which it shares; it stops at the tolerance, at the most "
        "components, or when a product no longer helps, and the material says which.",
    .held_out = "leave-one-view-out: for each painted view, fit the others and measure the RMS "
                "error on that view's painted pixels; pooled over views",
    .schema = "FitParamsMaps.json",
    .params_size = sizeof(maps_params),
    .params = maps_params_table,
    .nparams = (int)(sizeof maps_params_table / sizeof maps_params_table[0]),
    .presets = maps_presets,
    .npresets = (int)(sizeof maps_presets / sizeof maps_presets[0]),
    .params_default = maps_params_default,
    .params_check = maps_params_check,
    .levels = hf3_levels,
    .nlevels = HF3_NLEVELS,
    .fit = maps_fit,
    .mat = &maps_material_ops,
    .holdout_ok = maps_holdout_ok,
    .fit_bytes = maps_fit_bytes,
    .fit_seconds = maps_fit_seconds,
};
