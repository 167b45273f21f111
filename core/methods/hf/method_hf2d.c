/* method_hf2d.c: three factors, any of them 2D over parabolic maps, as a
 * method ("hf2d", hf2d.h): parameters, the decomposition level and its
 * disk file, the fit. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "hf4.h"
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
    {.name = "res", .label = "detail (texels per 1D factor)", .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "texels per 1D factor", .offset = offsetof(hf2d_params_t, res),
     .min = HF_RES_MIN, .max = HF_RES_MAX},
    {.name = "res_2d", .label = "detail of a 2D factor (nodes per side)", .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes per side of each 2D factor: its unknowns grow as res_2d^2 and the "
                    "precomputation as the cube of all unknowns",
     .offset = offsetof(hf2d_params_t, sres), .min = HF2D_SRES_MIN, .max = HF2D_SRES_MAX},
    DIMS_ROW("p", 0, "the direction to the light", "light factor: 1D or 2D", METHOD_GROUP_ADVANCED),
    DIMS_ROW("q", 1, "the half vector", "highlight factor: 1D or 2D", METHOD_GROUP_BASIC),
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
    hf2d_design d;
    hf2d_decomp dc;
    double t_design;
    double t_load;       /* seconds reading it from disk (0: built) */
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

static size_t level_bytes(const hf2d_level *x)
{
    size_t op = x->dc.x.M ? (size_t)x->dc.x.n * x->dc.x.nsamples : (size_t)x->dc.x.n * (x->dc.x.rank + 1);
    return sizeof *x + op * sizeof(double) +
           (size_t)x->d.n * (6 * (sizeof(int32_t) + sizeof(double)) + sizeof(double));
}

static int level_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const hf2d_params_t *p = in->params;
    hf2d_shape sh = hf2d_shape_of(p);
    hf2d_level *x = calloc(1, sizeof *x);
    double t0 = glint_now();
    int rc;
    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (in->progress)
        in->progress(in->progress_cls, "design", 0.25);
    if ((rc = hf2d_design_build(in->s, &sh, &x->d, err))) {
        free(x);
        return rc;
    }
    x->t_design = glint_now() - t0;
    if (in->progress)
        in->progress(in->progress_cls, "decomposition", 0.3);
    if ((rc = hf2d_decomp_build(&x->d, p->lambda, p->lambda_2d, p->rcond, &x->dc, err))) {
        level_free(x);
        return rc;
    }
    out->data = x;
    out->bytes = level_bytes(x);
    out->free = level_free;
    return 0;
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

static int level_save(const method_build_in *in, const char *dir, const char *key,
                      const cache_value *v, glint_err *err)
{
    (void)in;
    return hf2d_decomp_save(&((const hf2d_level *)v->data)->dc, dir, key, err);
}

static int level_load(const method_build_in *in, const char *dir, const char *key,
                      cache_value *out, glint_err *err)
{
    const hf2d_params_t *p = in->params;
    hf2d_shape sh = hf2d_shape_of(p);
    hf2d_level *x = calloc(1, sizeof *x);
    uint32_t u[5] = {(uint32_t)sh.res, (uint32_t)sh.sres, (uint32_t)sh.dims[0],
                     (uint32_t)sh.dims[1], (uint32_t)sh.dims[2]};
    double d[2] = {p->lambda, p->lambda_2d}, t0 = glint_now();
    int rc, off[4];

    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    x->dc.sh = sh;
    x->dc.lambda = d[0], x->dc.lambda_2d = d[1];
    if ((rc = hfx_decomp_file_load(HF2D_MAGIC, ".hf2d", u, 5, d, 2, hf2d_offsets(&sh, off),
                                   in->s->n, &x->dc.x, dir, key, err)) ||
        (rc = hf2d_design_build(in->s, &sh, &x->d, err))) {
        level_free(x);
        return rc;
    }
    x->t_load = x->t_design = glint_now() - t0;
    out->data = x;
    out->bytes = level_bytes(x);
    out->free = level_free;
    return 0;
}

static const method_level hf2d_levels[] = {
    {.name = "decomposition", .progress = 0.3, .key = level_key, .build = level_build,
     .load = level_load, .save = level_save},
};

/* ---- the fit -------------------------------------------------------------------------- */

static int hf2d_fit_op(const method_fit_in *in, material *out, glint_err *err)
{
    const hf2d_params_t *p = in->params;
    const hf2d_level *x = in->levels[0];
    const hfx_decomp *g = &x->dc.x;
    hf2d_factors *fac = calloc(1, sizeof *fac);
    hfx_fit_stats st;
    json_t *pre, *tim, *errs;
    double t0 = glint_now();
    int rc;

    memset(out, 0, sizeof *out);
    if (!fac)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = hf2d_fit(&x->d, &x->dc, &p->map, p->model, in->rgb, fac, &st, err))) {
        free(fac);
        return rc;
    }
    pre = json_pack("{s:s, s:s, s:i, s:i, s:i, s:s, s:i, s:i, s:i, s:f, s:f, s:f}",
                    "pattern_hash", in->s->hash, "cache_key", in->keys[0], "samples", in->s->n,
                    "unknowns", g->n, "rows", g->rows, "form", g->form, "numerical_rank",
                    g->rank, "gauge_dims", g->gauge_dims, "null_dims", g->null_dims, "rcond",
                    g->rcond, "s_max", g->s_max, "s_min_kept", g->s_min_kept);
    json_object_set_new(pre, "unreached", json_integer(g->unreached));
    json_object_set_new(pre, "operator_bytes",
                        json_integer((json_int_t)((size_t)g->n * (g->M ? g->nsamples : g->rank) *
                                                  8)));
    tim = json_pack("{s:f, s:f, s:f, s:f}", "samples", in->pattern_seconds, "design",
                    in->how[0] == CACHE_BUILT ? x->t_design : 0.0, "decomposition",
                    in->how[0] != CACHE_BUILT           ? in->spent[0]
                    : in->disk[0] == CACHE_DISK_LOADED ? x->t_load
                                                        : g->seconds,
                    "fit", glint_now() - t0);
    errs = json_pack("{s:f, s:f, s:f, s:[i,i,i], s:f, s:I}", "rms_painted", st.rms,
                     "max_abs_painted", st.max_abs, "log_residual_rms", st.log_residual,
                     "clamped", st.clamped[0], st.clamped[1], st.clamped[2], "log_max",
                     st.log_max, "log_clamped", (json_int_t)st.log_clamped);
    material_init(out, &method_hf2d, fac,
                  json_pack("{s:o, s:o, s:o, s:o}", "params",
                            method_params_to_json(&method_hf2d, p), "precomputation", pre,
                            "seconds", tim, "errors", errs));
    return 0;
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
    .label = "Brushed or anisotropic material",
    .summary = "One finish whose highlight depends on direction around the surface: "
        "factors that are 2D maps of the light, half and view directions.",
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
