/* method_pbr_detail.c: the pbr_detail method's table (method_pbr_detail.h):
 * parameters (hf3's and pbr's), the levels of both keyed as they key them,
 * the fit (the base, the ratio, the detail, the product's errors) and its
 * report. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_hf3_parts.h"
#include "method_pbr_detail.h"

/* ---- parameters ------------------------------------------------------------------------ */

static const char *const fresnel_values[] = {"dielectric", "conductor", NULL};

static const method_param pbr_detail_params_table[] = {
    {.name = "lobes", .label = "highlight layers", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "GGX lobes of the base: 1 (one highlight) or 2 (a sharp highlight over a "
                    "broad sheen)",
     .offset = offsetof(pbr_detail_params, pbr.lobes), .min = 1, .max = PBR_MAX_LOBES},
    {.name = "fresnel", .label = "kind of surface", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_ENUM, .affects = "fit",
     .description = "the base's Fresnel: dielectric (plastic, paint, wood) or conductor "
                    "(metal: a reflectance per colour channel)",
     .offset = offsetof(pbr_detail_params, pbr.fresnel), .values = fresnel_values},
    {.name = "starts", .label = "roughnesses tried", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "starting roughnesses of the base's search; the best fit of them is kept",
     .offset = offsetof(pbr_detail_params, pbr.starts), .min = 1, .max = PBR_MAX_STARTS},
    {.name = "max_iter", .label = "iterations per start", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "Levenberg-Marquardt iterations allowed per start of the base's fit",
     .offset = offsetof(pbr_detail_params, pbr.max_iter), .min = 1, .max = 10000},
    {.name = "start_samples", .label = "samples per start", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "samples each start of the base's fit is fitted on before the best is "
                    "refined on all; 0: all",
     .offset = offsetof(pbr_detail_params, pbr.start_samples), .min = 0, .max = 1 << 24},
    HF3_PARAM_ROWS(pbr_detail_params, hf.),
};

static const method_preset pbr_detail_presets[] = {
    {"draft", "{\"res\": 32}"},
    {"fast", "{\"res\": 64}"},
    {"default", "{\"res\": 128}"},
    {"fine", "{\"res\": 256}"},
};

static void pbr_detail_params_default(void *p)
{
    pbr_detail_params *pp = p;
    method_hf3.params_default(&pp->hf);
    method_pbr.params_default(&pp->pbr);
    /* hf3's brdf model: the factors hold the ratio itself (they are given
     * ratio ci and divide by ci), so an exact base leaves a constant detail,
     * which the factors hold exactly.  With the radiance model they must
     * hold ci, which the smoothing and the hats blur near grazing: on a
     * plastic painting (ct, f0 0.04, rough 0.25, sphere at 64, 12 views,
     * the whole detail) the product's painted RMS was 1.6e-3 with the
     * radiance model and 1.1e-5, the base's own, with the brdf model. */
    pp->hf.model = HF_MODEL_BRDF;
}

/* ---- levels: pbr's, then hf3's two, each under its own params ------------------------ */

static void geom_key(const void *params, const samples *s, const char *prev_key, char *key,
                     size_t len)
{
    method_pbr.levels[0].key(&((const pbr_detail_params *)params)->pbr, s, prev_key, key, len);
}

static int geom_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    method_build_in c = *in;
    c.params = &((const pbr_detail_params *)in->params)->pbr;
    c.prev = NULL;
    c.level = 0;
    return method_pbr.levels[0].build(&c, out, err);
}

/* hf3's level k, seeing only hf3's params and hf3's levels before it. */
static method_build_in hf3_in(const method_build_in *in, int k)
{
    method_build_in c = *in;
    c.params = &((const pbr_detail_params *)in->params)->hf;
    c.prev = k ? in->prev + 1 : NULL;
    c.level = k;
    return c;
}

static void decomp_key(const void *params, const samples *s, const char *prev_key, char *key,
                       size_t len)
{
    (void)prev_key; /* hf3 keys its decomposition from the pattern alone */
    method_hf3.levels[0].key(&((const pbr_detail_params *)params)->hf, s, s->hash, key, len);
}

static int decomp_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    method_build_in c = hf3_in(in, 0);
    return method_hf3.levels[0].build(&c, out, err);
}

static int decomp_load(const method_build_in *in, const char *dir, const char *key,
                       cache_value *out, glint_err *err)
{
    method_build_in c = hf3_in(in, 0);
    return method_hf3.levels[0].load(&c, dir, key, out, err);
}

static int decomp_save(const method_build_in *in, const char *dir, const char *key,
                       const cache_value *v, glint_err *err)
{
    method_build_in c = hf3_in(in, 0);
    return method_hf3.levels[0].save(&c, dir, key, v, err);
}

static void op_key(const void *params, const samples *s, const char *prev_key, char *key,
                   size_t len)
{
    /* prev_key: the decomposition's, as in hf3 */
    method_hf3.levels[1].key(&((const pbr_detail_params *)params)->hf, s, prev_key, key, len);
}

static int op_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    method_build_in c = hf3_in(in, 1);
    return method_hf3.levels[1].build(&c, out, err);
}

enum { LV_GEOM, LV_DECOMP, LV_OP, LV_N };

static const method_level pbr_detail_levels[LV_N] = {
    {.name = "pbr-geom", .progress = 0.05, .key = geom_key, .build = geom_build},
    {.name = "decomposition", .progress = 0.3, .key = decomp_key, .build = decomp_build,
     .load = decomp_load, .save = decomp_save},
    {.name = "operator", .progress = 0.85, .key = op_key, .build = op_build},
};

/* ---- the fit ---------------------------------------------------------------------------- */

/* What the fit works with beside its input: the base's BRDF at every sample,
 * the ratio given to the detail, the floors, and the product's errors. */
typedef struct detail_work {
    float *fb;              /* 3 n: f_base per sample and channel */
    float *ratio;           /* 3 n: y / max(f_base, floor) */
    double floor[3];
    long at_floor[3];
    double weight[3];       /* the detail's weight per channel (detail_weight) */
    double rms, max_abs, rms_base, rms_whole;
    double view_se[SCENE_MAX_VIEWS];
    long view_n[SCENE_MAX_VIEWS];
} detail_work;

static int check_finite(const method_fit_in *in, glint_err *err)
{
    for (long i = 0; i < 3L * in->s->n; i++)
        if (!isfinite(in->rgb[i]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "pbr_detail: painted value %ld (sample %ld, channel %ld) is "
                                 "not finite",
                                 i, i / 3, i % 3);
    return 0;
}

/* The base: pbr's fit on its own level and params. */
static int fit_base(const method_fit_in *in, material *bm, glint_err *err)
{
    method_fit_in c = *in;
    c.params = &((const pbr_detail_params *)in->params)->pbr;
    c.memo = NULL; /* pbr keeps none; the detail's values are of this method's making */
    c.view_tags = NULL;
    c.values_change = NULL;
    return method_pbr.fit(&c, bm, err);
}

/* f_base at every sample (from pbr-geom's cosines), the floors and the
 * ratio y / max(f_base, floor). */
static void ratio_make(const method_fit_in *in, const pbr_material *pm, detail_work *w)
{
    const pbr_geom *g = in->levels[LV_GEOM];
    double sum[3] = {0, 0, 0};
    long n = in->s->n;

    for (long i = 0; i < n; i++) {
        double f[3] = {0, 0, 0};
        if (g->ci[i] > 0.0 && g->co[i] > 0.0)
            pbr_brdf(pm->kd, pm->lobe, pm->sp.nlobes, g->ci[i], g->co[i], g->ch[i], g->cd[i], f);
        for (int c = 0; c < 3; c++) {
            w->fb[3 * i + c] = (float)f[c];
            sum[c] += f[c];
        }
    }
    for (int c = 0; c < 3; c++) {
        double mean = n ? sum[c] / (double)n : 0.0;
        w->floor[c] = mean > 0.0 ? PBR_DETAIL_FLOOR_FRAC * mean : PBR_DETAIL_FLOOR_MIN;
        if (w->floor[c] < PBR_DETAIL_FLOOR_MIN)
            w->floor[c] = PBR_DETAIL_FLOOR_MIN;
        w->at_floor[c] = 0;
    }
    for (long i = 0; i < 3 * n; i++) {
        int c = (int)(i % 3);
        double b = w->fb[i];
        if (b < w->floor[c]) {
            b = w->floor[c];
            w->at_floor[c]++;
        }
        w->ratio[i] = (float)(in->rgb[i] / b);
    }
}

/* The detail: hf3's fit of the ratio on hf3's levels and params. */
static int fit_detail(const method_fit_in *in, const float *ratio, material *hm,
                      glint_err *err)
{
    method_fit_in c = *in;
    c.params = &((const pbr_detail_params *)in->params)->hf;
    c.rgb = ratio;
    c.levels = in->levels + LV_DECOMP;
    c.keys = in->keys + LV_DECOMP;
    c.how = in->how + LV_DECOMP;
    c.spent = in->spent + LV_DECOMP;
    c.disk = in->disk + LV_DECOMP;
    c.memo = NULL;
    c.view_tags = NULL;
    c.values_change = NULL;
    return method_hf3.fit(&c, hm, err);
}

/* The detail at every sample (into w->ratio, which the detail's fit no
 * longer needs): d_c(wi, wo), ci included. */
static void detail_values(const method_fit_in *in, const hf_factors *fac, detail_work *w)
{
    const samples *s = in->s;
    for (long i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], d[3];
        for (int a = 0; a < 3; a++) {
            n[a] = s->nrm[3 * i + a];
            wi[a] = s->wi[3 * i + a];
            wo[a] = s->wo[3 * i + a];
        }
        hf_factors_eval(fac, n, wi, wo, d);
        for (int c = 0; c < 3; c++)
            w->ratio[3 * i + c] = (float)d[c];
    }
}

/* The detail's weight per channel: the value is f_base (ci + t (d - ci)),
 * t in [0, 1] the least-squares fit to the painting (t = 0: the base
 * alone, t = 1: the whole detail), so the product's painted error is never
 * above the base's. */
static void detail_weight(const method_fit_in *in, detail_work *w)
{
    const double *ci = ((const pbr_geom *)in->levels[LV_GEOM])->ci;
    double re[3] = {0, 0, 0}, rr[3] = {0, 0, 0};
    for (long i = 0; i < in->s->n; i++)
        for (int c = 0; c < 3; c++) {
            double fb = w->fb[3 * i + c];
            double r = fb * (w->ratio[3 * i + c] - ci[i]), e = in->rgb[3 * i + c] - fb * ci[i];
            re[c] += r * e;
            rr[c] += r * r;
        }
    for (int c = 0; c < 3; c++) {
        double t = rr[c] > 0.0 ? re[c] / rr[c] : 0.0;
        w->weight[c] = isfinite(t) ? fmin(1.0, fmax(0.0, t)) : 0.0;
    }
}

/* The product's errors on the painted samples, per unit light, at weights
 * t (OUT: *rms, and with w's views and max_abs when full). */
static double product_rms(const method_fit_in *in, detail_work *w, const double t[3], int full)
{
    const samples *s = in->s;
    const double *ci = ((const pbr_geom *)in->levels[LV_GEOM])->ci;
    double ss = 0.0;
    if (full) {
        w->max_abs = 0.0;
        memset(w->view_se, 0, sizeof w->view_se);
        memset(w->view_n, 0, sizeof w->view_n);
    }
    for (long i = 0; i < s->n; i++) {
        double e = 0.0;
        int v = s->view ? s->view[i] : 0;
        for (int c = 0; c < 3; c++) {
            double d = ci[i] + t[c] * (w->ratio[3 * i + c] - ci[i]);
            double r = (double)w->fb[3 * i + c] * d - in->rgb[3 * i + c];
            e += r * r;
            if (full && fabs(r) > w->max_abs)
                w->max_abs = fabs(r);
        }
        ss += e;
        if (full && v >= 0 && v < SCENE_MAX_VIEWS) {
            w->view_se[v] += e;
            w->view_n[v]++;
        }
    }
    return s->n ? sqrt(ss / (3.0 * (double)s->n)) : 0.0;
}

static void product_errors(const method_fit_in *in, const hf_factors *fac, detail_work *w)
{
    static const double none[3] = {0, 0, 0}, whole[3] = {1, 1, 1};
    detail_values(in, fac, w);
    detail_weight(in, w);
    w->rms_base = product_rms(in, w, none, 0);
    w->rms_whole = product_rms(in, w, whole, 0);
    w->rms = product_rms(in, w, w->weight, 1);
}

static json_t *report_weight(const detail_work *w)
{
    return json_pack("{s:[f, f, f], s:f, s:f, s:f, s:s}", "weight", w->weight[0], w->weight[1],
                     w->weight[2], "rms_painted_base", w->rms_base, "rms_painted_whole",
                     w->rms_whole, "rms_painted", w->rms, "rule",
                     "value = f_base (ci + t (detail - ci)) per channel, t in [0, 1] the "
                     "least-squares fit on the painted samples: 0 keeps the base alone, 1 "
                     "the whole detail (errors per unit light)");
}

static json_t *report_floor(const detail_work *w)
{
    return json_pack("{s:f, s:[f, f, f], s:[I, I, I], s:s}", "fraction", PBR_DETAIL_FLOOR_FRAC,
                     "value", w->floor[0], w->floor[1], w->floor[2], "samples_at_floor",
                     (json_int_t)w->at_floor[0], (json_int_t)w->at_floor[1],
                     (json_int_t)w->at_floor[2], "rule",
                     "the detail is fitted to painted / max(base, floor), floor a fraction of "
                     "the base's mean over the samples per channel");
}

/* The report: params, both parts' own reports, the floor, the product's
 * errors. Takes the parts' info references (NULL-safe). */
static json_t *report(const method_fit_in *in, json_t *base_info, json_t *detail_info,
                      const detail_work *w, double t_base, double t_detail, double t0)
{
    int nv = in->s->nviews < SCENE_MAX_VIEWS ? in->s->nviews : SCENE_MAX_VIEWS;
    return json_pack(
        "{s:o, s:o*, s:o*, s:o, s:o, s:{s:s, s:s, s:[s, s, s], s:i}, s:{s:f, s:f, s:f, s:f}, "
        "s:{s:f, s:f, s:o}}",
        "params", method_params_to_json(&method_pbr_detail, in->params), "base", base_info,
        "detail", detail_info, "floor", report_floor(w), "blend", report_weight(w),
        "precomputation", "pattern_hash",
        in->s->hash, "cache_key", in->keys[LV_OP], "cache_keys", in->keys[LV_GEOM],
        in->keys[LV_DECOMP], in->keys[LV_OP],
        "samples", in->s->n, "seconds", "samples", in->pattern_seconds, "base", t_base,
        "detail", t_detail, "fit", glint_now() - t0, "errors", "rms_painted", w->rms,
        "max_abs_painted", w->max_abs, "rms_by_view",
        method_rms_by_view(w->view_se, w->view_n, nv));
}

/* Move the parts' data into one material. */
static int compose(const method_fit_in *in, material *bm, material *hm, detail_work *w,
                   double t_base, double t_detail, double t0, material *out, glint_err *err)
{
    hf_factors *fac = hf3_factors(hm);
    json_t *info;
    product_errors(in, fac, w);
    info = report(in, json_incref(bm->info), json_incref(hm->info), w, t_base, t_detail, t0);
    if (!info)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the report");
    return pbr_detail_material_init(out, pbr_material_of(bm), fac, w->weight, info, err);
}

static int pbr_detail_fit(const method_fit_in *in, material *out, glint_err *err)
{
    double t0 = glint_now(), t1, t2;
    material bm = {0}, hm = {0};
    detail_work w;
    int rc;

    memset(&w, 0, sizeof w);
    memset(out, 0, sizeof *out);
    if ((rc = check_finite(in, err)))
        return rc;
    if ((rc = fit_base(in, &bm, err))) {
        glint_err_prefix(err, "pbr_detail: the base's fit");
        return rc;
    }
    t1 = glint_now();
    w.fb = malloc((size_t)6 * (in->s->n ? in->s->n : 1) * sizeof *w.fb);
    if (!w.fb) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory (%d samples)", in->s->n);
        goto done;
    }
    w.ratio = w.fb + 3 * (size_t)in->s->n;
    ratio_make(in, pbr_material_of(&bm), &w);
    if ((rc = fit_detail(in, w.ratio, &hm, err))) {
        glint_err_prefix(err, "pbr_detail: the detail's fit");
        goto done;
    }
    t2 = glint_now();
    rc = compose(in, &bm, &hm, &w, t1 - t0, t2 - t1, t0, out, err);
done:
    free(w.fb);
    material_free(&bm);
    material_free(&hm);
    return rc;
}

/* ---- resources -------------------------------------------------------------------------- */

static int pbr_detail_holdout_ok(const void *params)
{
    return hf3_holdout_ok(&((const pbr_detail_params *)params)->hf);
}

/* Both parts' bounds (each counts the pattern: a margin) and the base and
 * ratio arrays (24 bytes a sample). */
static size_t pbr_detail_fit_bytes(const void *params, long nsamples)
{
    const pbr_detail_params *p = params;
    size_t a = method_fit_bytes(&method_pbr, &p->pbr, nsamples);
    size_t b = method_fit_bytes(&method_hf3, &p->hf, nsamples);
    size_t c = (size_t)nsamples * 24;
    return a > SIZE_MAX - b - c ? SIZE_MAX : a + b + c;
}

/* Both parts' estimates; the ratio and the product's errors are one more
 * pass over the samples. */
static double pbr_detail_fit_seconds(const void *params, long nsamples)
{
    const pbr_detail_params *p = params;
    return method_fit_seconds(&method_pbr, &p->pbr, nsamples) +
           method_fit_seconds(&method_hf3, &p->hf, nsamples) +
           (double)nsamples * METHOD_SECONDS_PER_SAMPLE;
}

const method method_pbr_detail = {
    .name = "pbr_detail",
    .label = "Physical, with painted detail",
    .summary = "A physically based material (diffuse colour, roughness, Fresnel) with a "
        "correction that keeps what the painting shows beyond it.",
    .when = "Use it when the physical fit is close but misses some of the look (a highlight's "
        "shape, a grazing sheen) and you want both its physical numbers and the detail.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_FACTORS,
    .title = "Physically based BRDF times a three-factor factorization of the remaining ratio",
    .reference = "Walter, Marschner, Li & Torrance, Microfacet Models for Refraction through "
                 "Rough Surfaces, 2007; Jaroszkiewicz & McCool, Fast Extraction of BRDFs and "
                 "Material Maps from Images, GI 2003",
    .description =
        "f = f_pbr(wi, wo) d(wi, wo): f_pbr the pbr method's fit (kd/pi plus GGX lobes, "
        "height-correlated Smith, Schlick Fresnel), d a three-factor homomorphic "
        "factorization p(pi_p) q(pi_q) r(pi_r) fitted to the ratio painted / max(f_pbr, "
        "floor), floor 1% of the base's mean per channel. The base's levels and hf3's are "
        "shared with direct pbr and hf3 fits. The report holds the base's own report "
        "(determined and undetermined parameters) and the detail's. Points: fit_seconds is "
        "the warm fit, rms_painted the RMS error of the product on the painted samples.",
    .schema = "FitParamsPbrDetail.json",
    .params_size = sizeof(pbr_detail_params),
    .params = pbr_detail_params_table,
    .nparams = (int)(sizeof pbr_detail_params_table / sizeof pbr_detail_params_table[0]),
    .presets = pbr_detail_presets,
    .npresets = (int)(sizeof pbr_detail_presets / sizeof pbr_detail_presets[0]),
    .params_default = pbr_detail_params_default,
    .levels = pbr_detail_levels,
    .nlevels = LV_N,
    .fit = pbr_detail_fit,
    .mat = &pbr_detail_material_ops,
    .holdout_ok = pbr_detail_holdout_ok,
    .fit_bytes = pbr_detail_fit_bytes,
    .fit_seconds = pbr_detail_fit_seconds,
};
