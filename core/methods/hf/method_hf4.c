/* method_hf4.c: the four-factor product as a method ("hf4", hf4.h):
 * parameters, the decomposition level, the fit, and its material (the
 * factors, files, GPU binding). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "fsio.h"
#include "hf4.h"
#include "img.h"
#include "material.h"
#include "method_hf4_parts.h"

/* ---- parameters ------------------------------------------------------------------ */

static const method_param hf4_params[] = {
    HF4_PARAM_ROWS(hf4_params_t, ),
};

static const method_preset hf4_presets[] = {
    {"draft", "{\"res\": 32, \"s_res\": 16}"},
    {"default", "{\"res\": 32, \"s_res\": 32}"},
    {"fine", "{\"res\": 64, \"s_res\": 48}"},
};

static void hf4_params_default(void *params)
{
    hf4_params_t *p = params;
    memset(p, 0, sizeof *p);
    p->res = 32;
    p->sres = 32;
    p->lambda = 0.1;
    p->lambda_s = 0.1;
    hf_map_default(&p->map, HF_MAP_ADD);
    p->model = HF_MODEL_RADIANCE;
    p->rcond = HF4_RCOND_DEFAULT;
}

/* ---- the decomposition level -------------------------------------------------------- */

typedef struct hf4_level {
    hf4_design d;
    hf4_decomp dc;
    double t_design;
    double t_load;       /* seconds reading it from disk (0: built) */
} hf4_level;

/* Doubles the decomposition holds: V and s^2, or the kernel form's M. */
static size_t op_doubles(const hf4_decomp *dc)
{
    return dc->x.M ? (size_t)dc->x.n * dc->x.nsamples : (size_t)dc->x.n * (dc->x.rank + 1);
}

static void level_free(void *data)
{
    hf4_level *x = data;
    hf4_design_free(&x->d);
    hf4_decomp_free(&x->dc);
    free(x);
}

void hf4_level_key(const hf4_params_t *p, const char pattern_hash[33], char *key, size_t len)
{
    snprintf(key, len, "hf4:%s:%d:%d:%.17g:%.17g:%.17g", pattern_hash, p->res, p->sres,
             p->lambda, p->lambda_s, p->rcond);
}

static void level_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    (void)prev_key;
    hf4_level_key(params, s->hash, key, len);
}

static int level_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const hf4_params_t *p = in->params;
    hf4_level *x = calloc(1, sizeof *x);
    double t0 = glint_now();
    int rc;
    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (in->progress)
        in->progress(in->progress_cls, "design", 0.25);
    if ((rc = hf4_design_build(in->s, p->res, p->sres, &x->d, err))) {
        free(x);
        return rc;
    }
    x->t_design = glint_now() - t0;
    if (in->progress)
        in->progress(in->progress_cls, "decomposition", 0.3);
    if ((rc = hf4_decomp_build(&x->d, p->lambda, p->lambda_s, p->rcond, &x->dc, err))) {
        level_free(x);
        return rc;
    }
    out->data = x;
    out->bytes = sizeof *x + op_doubles(&x->dc) * sizeof(double) +
                 (size_t)x->d.d.n * (3 * (sizeof(int32_t) + sizeof(double)) + 2 * 12);
    out->free = level_free;
    return 0;
}

/* The disk layer: <dir>/<hash of the key>.hf4 (cfile.h, kind 1) holds the
 * decomposition: u32 res, sres; doubles lambda, lambda_s; then hfx.h's
 * hfx_decomp_put.  The design is rebuilt from the pattern (a
 * millisecond). */
#define HF4_MAGIC "GLHF4D02"

int hf4_decomp_save(const hf4_decomp *dc, const char *dir, const char *key, glint_err *err)
{
    uint32_t u[2] = {(uint32_t)dc->res, (uint32_t)dc->sres};
    double d[2] = {dc->lambda, dc->lambda_s};
    return hfx_decomp_file_save(HF4_MAGIC, ".hf4", u, 2, d, 2, &dc->x, dir, key, err);
}

static int level_save(const method_build_in *in, const char *dir, const char *key,
                      const cache_value *v, glint_err *err)
{
    (void)in;
    return hf4_decomp_save(&((const hf4_level *)v->data)->dc, dir, key, err);
}

static int level_load(const method_build_in *in, const char *dir, const char *key,
                      cache_value *out, glint_err *err)
{
    const hf4_params_t *p = in->params;
    hf4_level *x = calloc(1, sizeof *x);
    uint32_t u[2] = {(uint32_t)p->res, (uint32_t)p->sres};
    double d[2] = {p->lambda, p->lambda_s}, t0 = glint_now();
    int rc;

    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    x->dc.res = p->res, x->dc.sres = p->sres, x->dc.lambda = d[0], x->dc.lambda_s = d[1];
    if ((rc = hfx_decomp_file_load(HF4_MAGIC, ".hf4", u, 2, d, 2,
                                   3 * p->res + p->sres * p->sres, in->s->n, &x->dc.x, dir, key,
                                   err)) ||
        (rc = hf4_design_build(in->s, p->res, p->sres, &x->d, err))) {
        level_free(x);
        return rc;
    }
    x->t_load = x->t_design = glint_now() - t0;
    out->data = x;
    out->bytes = sizeof *x + op_doubles(&x->dc) * sizeof(double) +
                 (size_t)x->d.d.n * (3 * (sizeof(int32_t) + sizeof(double)) + 2 * 12);
    out->free = level_free;
    return 0;
}

const method_level hf4_levels[HF4_NLEVELS] = {
    {.name = "decomposition", .progress = 0.3, .key = level_key, .build = level_build,
     .load = level_load, .save = level_save},
};

/* ---- the fit -------------------------------------------------------------------------- */

static int hf4_fit_op(const method_fit_in *in, material *out, glint_err *err)
{
    const hf4_params_t *p = in->params;
    const hf4_level *x = in->levels[0];
    hf4_factors *fac = calloc(1, sizeof *fac);
    hf4_fit_stats st;
    json_t *pre, *tim, *errs;
    double t0 = glint_now();
    int rc;

    memset(out, 0, sizeof *out);
    if (!fac)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = hf4_fit(&x->d, &x->dc, &p->map, p->model, in->rgb, fac, &st, err))) {
        free(fac);
        return rc;
    }
    pre = json_pack("{s:s, s:s, s:i, s:i, s:i, s:s, s:i, s:i, s:i, s:f, s:f, s:f}",
                    "pattern_hash", in->s->hash, "cache_key", in->keys[0], "samples", in->s->n,
                    "unknowns", x->dc.x.n, "rows", x->dc.x.rows, "form", x->dc.x.form,
                    "numerical_rank", x->dc.x.rank, "gauge_dims", x->dc.x.gauge_dims, "null_dims",
                    x->dc.x.null_dims, "rcond", x->dc.x.rcond, "s_max", x->dc.x.s_max,
                    "s_min_kept", x->dc.x.s_min_kept);
    json_object_set_new(pre, "unreached", json_integer(x->dc.x.unreached));
    json_object_set_new(pre, "operator_bytes",
                        json_integer((json_int_t)(op_doubles(&x->dc) * 8)));
    tim = json_pack("{s:f, s:f, s:f, s:f}", "samples", in->pattern_seconds, "design",
                    in->how[0] == CACHE_BUILT ? x->t_design : 0.0, "decomposition",
                    in->how[0] != CACHE_BUILT           ? in->spent[0]
                    : in->disk[0] == CACHE_DISK_LOADED ? x->t_load
                                                        : x->dc.x.seconds,
                    "fit",
                    glint_now() - t0);
    errs = json_pack("{s:f, s:f, s:f, s:[i,i,i], s:f, s:I}", "rms_painted", st.rms,
                     "max_abs_painted", st.max_abs, "log_residual_rms", st.log_residual,
                     "clamped", st.clamped[0], st.clamped[1], st.clamped[2], "log_max",
                     st.log_max, "log_clamped", (json_int_t)st.log_clamped);
    material_init(out, &method_hf4, fac,
                  json_pack("{s:o, s:o, s:o, s:o}", "params",
                            method_params_to_json(&method_hf4, p), "precomputation", pre,
                            "seconds", tim, "errors", errs));
    return 0;
}

/* Memory of a cold fit: the normal (or dense) matrix and the eigenvectors,
 * the design, the pattern. */
size_t hf4_fit_bytes(const void *params, long nsamples)
{
    const hf4_params_t *p = params;
    double n = 3.0 * p->res + (double)p->sres * p->sres, N = (double)nsamples;
    double b = 320.0 * N + 3.0 * n * n * 8.0 + 64.0 * N;
    return b >= (double)SIZE_MAX ? SIZE_MAX : (size_t)b;
}

/* A cold fit: passes over the samples, then the decomposition of 3 res +
 * s_res^2 unknowns (as hf3's). */
double hf4_fit_seconds(const void *params, long nsamples)
{
    const hf4_params_t *p = params;
    return (double)nsamples * METHOD_SECONDS_PER_SAMPLE +
           2.0 * method_dense_seconds(3.0 * p->res + (double)p->sres * p->sres);
}

int hf4_holdout_ok(const void *params)
{
    return ((const hf4_params_t *)params)->sres <= 32;
}

static const char *const hf4_surface[] = {"spatial", NULL};

const method method_hf4 = {
    .name = "hf4",
    .label = "One material, varying colour",
    .summary = "One finish whose colour and brightness vary over the surface: the "
        "point-light material times a colour texture.",
    .when = "Use it for a faded print, dirt or a painted pattern on one finish; "
        "different highlights in different places need several materials.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_FACTORS,
    .surface = hf4_surface,
    .title = "Four-factor product: three 1D factors times a spatial factor s(u, v)",
    .reference = "Jaroszkiewicz & McCool, Fast Extraction of BRDFs and Material Maps from "
                 "Images, GI 2003, section 4.2",
    .description =
        "One BRDF whose brightness and colour vary over the surface: p(pi_p) q(pi_q) r(pi_r) "
        "s(u, v), s a texture over the texture coordinates (s_res nodes per side). The "
        "decomposition of the painted views' constraints (3 res + s_res^2 unknowns) is cached; "
        "each fit applies its pseudo-inverse in log space. For a pattern of different "
        "highlights (gold on plastic) use material maps (maps).",
    .held_out = "leave-one-view-out: for each painted view, fit the others and measure the RMS "
                "error on that view's painted pixels; pooled over views",
    .schema = "FitParamsHf4.json",
    .params_size = sizeof(hf4_params_t),
    .params = hf4_params,
    .nparams = (int)(sizeof hf4_params / sizeof hf4_params[0]),
    .presets = hf4_presets,
    .npresets = (int)(sizeof hf4_presets / sizeof hf4_presets[0]),
    .params_default = hf4_params_default,
    .levels = hf4_levels,
    .nlevels = HF4_NLEVELS,
    .fit = hf4_fit_op,
    .mat = &hf4_material_ops,
    .holdout_ok = hf4_holdout_ok,
    .fit_bytes = hf4_fit_bytes,
    .fit_seconds = hf4_fit_seconds,
};
