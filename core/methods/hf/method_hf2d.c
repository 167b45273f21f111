/* method_hf2d.c: three factors, any of them 2D over parabolic maps, as a
 * method ("hf2d", hf2d.h): parameters, the decomposition level and its
 * disk file, the fit (the level's making and the fit's report are those of
 * every method with 2D factors: method_hfx.c), the resource rules. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hf4.h"
#include "internal/method_hfx_int.h"
#include "method_hf2d.h"
#include "method_hf3_parts.h"

/* ---- parameters ------------------------------------------------------------------ */

static const char *const dims_values[] = {"1d", "2d", NULL};

#define DIMS_ROW(NAME, IDX, WHAT, LABEL, GROUP)                                              \
    {.name = NAME, .label = LABEL, .group = GROUP, .type = METHOD_PARAM_ENUM, .affects = "precomputation",                  \
     .description = "factor " NAME " over " WHAT ": 1d over the length of the vector on "   \
                    "the tangent plane (isotropic), 2d over its parabolic map in the "      \
                    "tangent frame (res_2d^2 unknowns: direction around the normal)",       \
     .offset = offsetof(hf2d_params_t, dims) + (IDX) * sizeof(int), .values = dims_values}

static const method_param hf2d_params[] = {
    {.name = "res", .label = "detail", .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "texels per 1D factor", .offset = offsetof(hf2d_params_t, res),
     .min = HF_RES_MIN, .max = HF_RES_MAX},
    {.name = "res_2d", .label = "detail over directions", .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes per side of each 2D factor: its unknowns grow as res_2d^2 and the "
                    "precomputation as the cube of all unknowns",
     .offset = offsetof(hf2d_params_t, sres), .min = HF2D_SRES_MIN, .max = HF2D_SRES_MAX},
    DIMS_ROW("p", 0, "the direction to the light", "light factor: 1D or 2D", METHOD_GROUP_ADVANCED),
    DIMS_ROW("q", 1, "the half vector", "highlight: round (1d) or stretched (2d)", METHOD_GROUP_BASIC),
    DIMS_ROW("r", 2, "the direction to the eye", "view factor: 1D or 2D", METHOD_GROUP_ADVANCED),
    {.name = "lambda", .label = "smoothing of 1D factors", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "precomputation",
     .description = "weight of the smoothing rows of the 1D factors",
     .offset = offsetof(hf2d_params_t, lambda), .min = 0.0, .max = HF_LAMBDA_MAX},
    {.name = "lambda_2d", .label = "smoothing of 2D factors", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "precomputation",
     .description = "weight of the 2D Laplacian of the 2D factors: it also fills the nodes no "
                    "sample reaches (those outside the hemisphere's disc among them)",
     .offset = offsetof(hf2d_params_t, lambda_2d), .min = 0.0, .max = HF_LAMBDA_MAX},
    {.name = "mapping", .label = "log mapping", .group = METHOD_GROUP_ADVANCED, .option = "map", .type = METHOD_PARAM_TEXT, .affects = "fit",
     .description = "mapping to log space (section 3.4)", .offset = offsetof(hf2d_params_t, map),
     .syntax = "log | add[:a] | sub[:margin], optionally ,eps=E", .examples = hf3_map_examples,
     .parse = hf3_map_parse, .format = hf3_map_format},
    {.name = "model", .label = "what the factors fit", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "fit",
     .description = "radiance: factors approximate the painted value; brdf: painted / cos_i",
     .offset = offsetof(hf2d_params_t, model), .values = hf3_model_values},
    {.name = "rcond", .label = "rank cutoff", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "precomputation",
     .description = "relative singular-value cutoff: the gauge and nodes no sample or "
                    "smoothing reaches fall under it",
     .offset = offsetof(hf2d_params_t, rcond), .min = 1e-16, .max = 1.0, .max_exclusive = 1},
};

static const method_preset hf2d_presets[] = {
    {"draft", "{\"res\": 32, \"res_2d\": 16}"},
    {"default", "{\"res\": 32, \"res_2d\": 32}"},
    {"all-2d", "{\"res_2d\": 16, \"p\": \"2d\", \"q\": \"2d\", \"r\": \"2d\"}"},
};

static void hf2d_params_default(void *params)
{
    hf2d_params_t *p = params;
    memset(p, 0, sizeof *p);
    p->res = 32;
    p->sres = 32;
    p->dims[0] = 0;
    p->dims[1] = 1;
    p->dims[2] = 0;
    p->lambda = 0.1;
    p->lambda_2d = 0.1;
    hf_map_default(&p->map, HF_MAP_ADD);
    p->model = HF_MODEL_RADIANCE;
    p->rcond = HF4_RCOND_DEFAULT;
}

hf2d_shape hf2d_shape_of(const hf2d_params_t *p)
{
    hf2d_shape sh = {.res = p->res, .sres = p->sres};
    for (int j = 0; j < 3; j++)
        sh.dims[j] = p->dims[j] ? 2 : 1;
    return sh;
}

/* ---- the decomposition level -------------------------------------------------------- */

typedef struct hf2d_level {
    hfx_level t;
    hf2d_design d;
    hf2d_decomp dc;
} hf2d_level;

static void level_free(void *data)
{
    hf2d_level *x = data;
    hf2d_design_free(&x->d);
    hf2d_decomp_free(&x->dc);
    free(x);
}

void hf2d_level_key(const hf2d_params_t *p, const char pattern_hash[33], char *key, size_t len)
{
    snprintf(key, len, "hf2d:%s:%d:%d:%d%d%d:%.17g:%.17g:%.17g", pattern_hash, p->res, p->sres,
             p->dims[0] + 1, p->dims[1] + 1, p->dims[2] + 1, p->lambda, p->lambda_2d, p->rcond);
}

static void level_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    (void)prev_key;
    hf2d_level_key(params, s->hash, key, len);
}

/* Memory held: the level, the decomposition's operator and the design's
 * per-sample arrays. */
static size_t level_bytes(const void *level)
{
    const hf2d_level *x = level;
    size_t op = x->dc.x.M ? (size_t)x->dc.x.n * x->dc.x.nsamples : (size_t)x->dc.x.n * (x->dc.x.rank + 1);
    return sizeof *x + op * sizeof(double) +
           (size_t)x->d.n * (6 * (sizeof(int32_t) + sizeof(double)) + sizeof(double));
}

/* The report counts V alone, n x rank (level_bytes adds s^2). */
static size_t operator_bytes(const void *level)
{
    const hfx_decomp *g = &((const hf2d_level *)level)->dc.x;
    return (size_t)g->n * (g->M ? g->nsamples : g->rank) * 8;
}

/* The design of the pattern s for the params' resolutions. */
static int design(const void *params, const samples *s, void *level, glint_err *err)
{
    hf2d_shape sh = hf2d_shape_of(params);
    return hf2d_design_build(s, &sh, &((hf2d_level *)level)->d, err);
}

/* The decomposition of the level's design with the params' weights and cut. */
static int decompose(const void *params, void *level, glint_err *err)
{
    const hf2d_params_t *p = params;
    hf2d_level *x = level;
    return hf2d_decomp_build(&x->d, p->lambda, p->lambda_2d, p->rcond, &x->dc, err);
}

/* The disk layer: <dir>/<hash of the key>.hf2d (cfile.h, kind 1) holds the
 * decomposition: u32 res, sres, dims[3]; doubles lambda, lambda_2d; then
 * hfx.h's hfx_decomp_put.  The design is rebuilt from the pattern. */
#define HF2D_MAGIC "GLHF2D01"

int hf2d_decomp_save(const hf2d_decomp *dc, const char *dir, const char *key, glint_err *err)
{
    uint32_t u[5] = {(uint32_t)dc->sh.res, (uint32_t)dc->sh.sres, (uint32_t)dc->sh.dims[0],
                     (uint32_t)dc->sh.dims[1], (uint32_t)dc->sh.dims[2]};
    double d[2] = {dc->lambda, dc->lambda_2d};
    return hfx_decomp_file_save(HF2D_MAGIC, ".hf2d", u, 5, d, 2, &dc->x, dir, key, err);
}

/* What a file of the params' decomposition begins with (the loaded level's
 * decomposition told the same); returns its unknowns. */
static int file_head(const void *params, void *level, hfx_file_head *h)
{
    const hf2d_params_t *p = params;
    hf2d_decomp *dc = &((hf2d_level *)level)->dc;
    int off[4];
    dc->sh = hf2d_shape_of(p);
    dc->lambda = p->lambda, dc->lambda_2d = p->lambda_2d;
    *h = (hfx_file_head){.u = {(uint32_t)dc->sh.res, (uint32_t)dc->sh.sres,
                               (uint32_t)dc->sh.dims[0], (uint32_t)dc->sh.dims[1],
                               (uint32_t)dc->sh.dims[2]},
                         .d = {p->lambda, p->lambda_2d}, .nu = 5, .nd = 2};
    return hf2d_offsets(&dc->sh, off);
}

/* The factors of the painted values rgb through the level. */
static int fit_factors(const void *params, const void *level, const float *rgb,
                       const int *view, void *factors, hfx_fit_stats *st, glint_err *err)
{
    const hf2d_params_t *p = params;
    const hf2d_level *x = level;
    return hf2d_fit(&x->d, &x->dc, &p->map, p->model, rgb, view, factors, st, err);
}

/* What the adapter of the 2D-factor methods (internal/method_hfx_int.h)
 * needs of hf2d: the level and the fit are its. */
static const hfx_method hf2d_hfx = {
    .self = &method_hf2d,
    .level_size = sizeof(hf2d_level),
    .decomp_at = offsetof(hf2d_level, dc.x),
    .factors_size = sizeof(hf2d_factors),
    .magic = HF2D_MAGIC,
    .ext = ".hf2d",
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
    return hfx_level_build(&hf2d_hfx, in, out, err);
}

static int level_save(const method_build_in *in, const char *dir, const char *key,
                      const cache_value *v, glint_err *err)
{
    (void)in;
    return hf2d_decomp_save(&((const hf2d_level *)v->data)->dc, dir, key, err);
}

static int level_load(const method_build_in *in, const char *dir, const char *key,
                      cache_value *out, glint_err *err)
{
    return hfx_level_load(&hf2d_hfx, in, dir, key, out, err);
}

static const method_level hf2d_levels[] = {
    {.name = "decomposition", .progress = 0.3, .key = level_key, .build = level_build,
     .load = level_load, .save = level_save},
};

/* ---- the fit -------------------------------------------------------------------------- */

static int hf2d_fit_op(const method_fit_in *in, material *out, glint_err *err)
{
    return hfx_method_fit(&hf2d_hfx, in, out, err);
}

/* Memory of a cold fit: the normal (or dense) matrix, the eigenvectors and
 * LAPACK's workspace (about 3 n^2), the design, the pattern. */
static size_t hf2d_fit_bytes(const void *params, long nsamples)
{
    const hf2d_params_t *p = params;
    hf2d_shape sh = hf2d_shape_of(p);
    int off[4];
    double n = hf2d_offsets(&sh, off), N = (double)nsamples;
    double b = 320.0 * N + 3.0 * n * n * 8.0 + 112.0 * N;
    return b >= (double)SIZE_MAX ? SIZE_MAX : (size_t)b;
}

/* A cold fit: passes over the samples, then the decomposition of its
 * unknowns (as hf3's). */
static double hf2d_fit_seconds(const void *params, long nsamples)
{
    const hf2d_params_t *p = params;
    hf2d_shape sh = hf2d_shape_of(p);
    int off[4];
    return (double)nsamples * METHOD_SECONDS_PER_SAMPLE +
           2.0 * method_dense_seconds(hf2d_offsets(&sh, off));
}

/* A held-out measurement decomposes once per painted view: affordable up
 * to about 2,000 unknowns (a second each here). */
static int hf2d_holdout_ok(const void *params)
{
    const hf2d_params_t *p = params;
    hf2d_shape sh = hf2d_shape_of(p);
    int off[4];
    return hf2d_offsets(&sh, off) <= 2200;
}

const method method_hf2d = {
    .name = "hf2d",
    .label = "Brushed / anisotropic",
    .summary = "One finish whose highlight depends on direction around the surface: "
        "its look is learnt as a function of the light and view directions.",
    .when = "Use it for brushed metal, satin or a hair-like sheen; directions are "
        "measured around the object's vertical axis.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_FACTORS,
    .title = "Three factors, any of them 2D over parabolic maps (anisotropic)",
    .reference = "Jaroszkiewicz & McCool, Fast Extraction of BRDFs and Material Maps from "
                 "Images, GI 2003, section 3.1; McCool, Ang & Ahmad, Homomorphic "
                 "Factorization of BRDFs, SIGGRAPH 2001",
    .description =
        "One BRDF p(wi) q(h) r(wo) whose factors may depend on the direction around the "
        "normal: each factor is 1D (the length of its vector on the tangent plane, as hf3) or "
        "2D (the parabolic map of the vector in the tangent frame t = Z x n, b = n x t, Z up). A 2D "
        "q holds a highlight stretched along the surface (brushed metal, satin). The "
        "decomposition of the painted views' constraints is cached; each fit applies its "
        "pseudo-inverse in log space.",
    .held_out = "leave-one-view-out: for each painted view, fit the others and measure the RMS "
                "error on that view's painted pixels; pooled over views",
    .schema = "FitParamsHf2d.json",
    .params_size = sizeof(hf2d_params_t),
    .params = hf2d_params,
    .nparams = (int)(sizeof hf2d_params / sizeof hf2d_params[0]),
    .presets = hf2d_presets,
    .npresets = (int)(sizeof hf2d_presets / sizeof hf2d_presets[0]),
    .params_default = hf2d_params_default,
    .levels = hf2d_levels,
    .nlevels = 1,
    .fit = hf2d_fit_op,
    .mat = &hf2d_material_ops,
    .holdout_ok = hf2d_holdout_ok,
    .fit_bytes = hf2d_fit_bytes,
    .fit_seconds = hf2d_fit_seconds,
};
