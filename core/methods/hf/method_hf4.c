/* method_hf4.c: the four-factor product as a method ("hf4", hf4.h):
 * parameters, the decomposition level and its disk file, the fit (the
 * level's making and the fit's report are those of every method with 2D
 * factors: method_hfx.c), the resource rules. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hf4.h"
#include "internal/method_hfx_int.h"
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
    hfx_level t;
    hf4_design d;
    hf4_decomp dc;
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

/* Memory held: the level, the decomposition's operator and the design's
 * per-sample arrays. */
static size_t level_bytes(const void *level)
{
    const hf4_level *x = level;
    return sizeof *x + op_doubles(&x->dc) * sizeof(double) +
           (size_t)x->d.d.n * (3 * (sizeof(int32_t) + sizeof(double)) + 2 * 12);
}

/* The report counts V and s^2 as op_doubles does. */
static size_t operator_bytes(const void *level)
{
    return op_doubles(&((const hf4_level *)level)->dc) * 8;
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

/* The design of the pattern s for the params' resolutions. */
static int design(const void *params, const samples *s, void *level, glint_err *err)
{
    const hf4_params_t *p = params;
    return hf4_design_build(s, p->res, p->sres, &((hf4_level *)level)->d, err);
}

/* The decomposition of the level's design with the params' weights and cut. */
static int decompose(const void *params, void *level, glint_err *err)
{
    const hf4_params_t *p = params;
    hf4_level *x = level;
    return hf4_decomp_build(&x->d, p->lambda, p->lambda_s, p->rcond, &x->dc, err);
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

/* What a file of the params' decomposition begins with (the loaded level's
 * decomposition told the same); returns its unknowns. */
static int file_head(const void *params, void *level, hfx_file_head *h)
{
    const hf4_params_t *p = params;
    hf4_decomp *dc = &((hf4_level *)level)->dc;
    dc->res = p->res, dc->sres = p->sres, dc->lambda = p->lambda, dc->lambda_s = p->lambda_s;
    *h = (hfx_file_head){.u = {(uint32_t)p->res, (uint32_t)p->sres},
                         .d = {p->lambda, p->lambda_s}, .nu = 2, .nd = 2};
    return 3 * p->res + p->sres * p->sres;
}

/* The factors of the painted values rgb through the level. */
static int fit_factors(const void *params, const void *level, const float *rgb,
                       const int *view, void *factors, hfx_fit_stats *st, glint_err *err)
{
    const hf4_params_t *p = params;
    const hf4_level *x = level;
    return hf4_fit(&x->d, &x->dc, &p->map, p->model, rgb, view, factors, st, err);
}

/* What the adapter of the 2D-factor methods (internal/method_hfx_int.h)
 * needs of hf4: the level and the fit are its. */
static const hfx_method hf4_hfx = {
    .self = &method_hf4,
    .level_size = sizeof(hf4_level),
    .decomp_at = offsetof(hf4_level, dc.x),
    .factors_size = sizeof(hf4_factors),
    .magic = HF4_MAGIC,
    .ext = ".hf4",
    .design = design,
    .decompose = decompose,
    .file_head = file_head,
    .bytes = level_bytes,
    .free = level_free,
    .operator_bytes = operator_bytes,
    .fit = fit_factors,
};

static int level_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    return hfx_level_build(&hf4_hfx, in, out, err);
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
    return hfx_level_load(&hf4_hfx, in, dir, key, out, err);
}

const method_level hf4_levels[HF4_NLEVELS] = {
    {.name = "decomposition", .progress = 0.3, .key = level_key, .build = level_build,
     .load = level_load, .save = level_save},
};

/* ---- the fit -------------------------------------------------------------------------- */

static int hf4_fit_op(const method_fit_in *in, material *out, glint_err *err)
{
    return hfx_method_fit(&hf4_hfx, in, out, err);
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
    .label = "One finish, colour varies",
    .summary = "One finish whose colour and brightness vary over the surface: the "
        "lamp-lit finish times a colour texture.",
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
