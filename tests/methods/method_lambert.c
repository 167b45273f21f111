/* method_lambert.c: a method that exists only in test builds, to show that a
 * method is one core file plus one registration line: a constant-colour
 * Lambert fit, f = albedo / pi, least squares over the painted samples
 * (radiance = albedo / pi * n.wi per unit light):
 *
 *   albedo_c = pi * sum_i(v_ic ci) / sum_i(ci^2),  clamped to [0, albedo_max]
 *
 * One precomputation level ("lambert-gram": sum ci^2 over the pattern) so
 * the cache, the job path and the reports are exercised; no files beyond
 * material.json; a GLSL fragment stage with one uniform. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "material.h"
#include "method.h"

typedef struct lambert_params {
    double albedo_max;
} lambert_params;

typedef struct lambert_gram {
    double sum_c2;
    int n;
} lambert_gram;

static const method_param params[] = {
    {.name = "albedo_max", .label = "brightest colour allowed", .type = METHOD_PARAM_NUMBER,
     .affects = "fit",
     .description = "largest albedo allowed per channel (energy conservation is 1)",
     .offset = offsetof(lambert_params, albedo_max), .min = 0.0, .max = 10.0,
     .min_exclusive = 1},
};

static void params_default(void *p)
{
    ((lambert_params *)p)->albedo_max = 1.0;
}

static void gram_key(const void *p, const samples *s, const char *prev, char *key, size_t len)
{
    (void)p;
    (void)s;
    snprintf(key, len, "lambert-gram:%s", prev);
}

static int gram_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    lambert_gram *g = calloc(1, sizeof *g);
    if (!g)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (in->progress)
        in->progress(in->progress_cls, "lambert-gram", 0.5);
    for (int i = 0; i < in->s->n; i++)
        g->sum_c2 += in->s->cos_i[i] * in->s->cos_i[i];
    g->n = in->s->n;
    out->data = g;
    out->bytes = sizeof *g;
    out->free = free;
    return 0;
}

static const method_level levels[] = {
    {.name = "lambert-gram", .progress = 0.5, .key = gram_key, .build = gram_build},
};

extern const method method_lambert_test;

static int fit(const method_fit_in *in, material *out, glint_err *err)
{
    const lambert_params *p = in->params;
    const lambert_gram *g = in->levels[0];
    double *albedo = calloc(3, sizeof *albedo), ss = 0.0;
    json_t *info;

    if (!albedo)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (!(g->sum_c2 > 0.0)) {
        free(albedo);
        return glint_err_set(err, GLINT_ENUMERIC, "no lit sample to fit");
    }
    for (int c = 0; c < 3; c++) {
        double num = 0.0;
        for (int i = 0; i < in->s->n; i++)
            num += in->rgb[3 * i + c] * in->s->cos_i[i];
        albedo[c] = fmin(fmax(M_PI * num / g->sum_c2, 0.0), p->albedo_max);
    }
    for (int i = 0; i < in->s->n; i++)
        for (int c = 0; c < 3; c++) {
            double d = albedo[c] / M_PI * in->s->cos_i[i] - in->rgb[3 * i + c];
            ss += d * d;
        }
    info = json_pack("{s:o, s:{s:s, s:s, s:i}, s:{s:f, s:f}, s:{s:f}}", "params",
                     method_params_to_json(&method_lambert_test, p), "precomputation",
                     "pattern_hash", in->s->hash, "cache_key", in->keys[0], "samples", in->s->n,
                     "seconds", "samples", in->pattern_seconds, "fit", 0.0, "errors",
                     "rms_painted", sqrt(ss / (3.0 * in->s->n)));
    material_init(out, &method_lambert_test, albedo, info);
    return 0;
}

static void eval(const void *data, const double uv[2], const double n[3], const double wi[3],
                 const double wo[3], double rgb[3])
{
    (void)uv;
    const double *albedo = data;
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    double co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    for (int c = 0; c < 3; c++)
        rgb[c] = ci > 0.0 && co > 0.0 ? albedo[c] / M_PI * ci : 0.0;
}

static int to_json(const void *data, json_t *root, glint_err *err)
{
    const double *a = data;
    (void)err;
    json_object_set_new(root, "albedo", json_pack("[f, f, f]", a[0], a[1], a[2]));
    return 0;
}

static int from_json(const json_t *root, const char *file, void **data, glint_err *err)
{
    json_t *a = json_object_get(root, "albedo");
    double *albedo;
    if (!json_is_array(a) || json_array_size(a) != 3)
        return glint_err_set(err, GLINT_EFORMAT, "%s: albedo must be [r, g, b]", file);
    if (!(albedo = malloc(3 * sizeof *albedo)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int c = 0; c < 3; c++) {
        json_t *v = json_array_get(a, (size_t)c);
        albedo[c] = json_number_value(v);
        if (!json_is_number(v) || !isfinite(albedo[c]) || albedo[c] < 0.0) {
            free(albedo);
            return glint_err_set(err, GLINT_EFORMAT, "%s: albedo[%d] is not a number >= 0",
                                 file, c);
        }
    }
    *data = albedo;
    return 0;
}

static const char frag[] =
    "#version 300 es\n"
    "// a constant-colour Lambert material (a test method)\n"
    "precision highp float;\n"
    "uniform vec3 u_albedo;\n"
    "uniform vec3 u_eye;\n"
    "uniform vec3 u_light;\n"
    "uniform float u_light_intensity;\n"
    "in vec3 v_pos;\n"
    "in vec3 v_nrm;\n"
    "in vec2 v_uv;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "vec3 glint_unit(vec3 v) { float l = length(v); return l > 0.0 ? v / l : v; }\n"
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    "    float ci = dot(n, wi), co = dot(n, wo);\n"
    "    if (!(ci > 0.0) || !(co > 0.0))\n"
    "        return vec3(0.0);\n"
    "    return u_albedo / 3.14159265358979323846 * ci;\n"
    "}\n"
    "void main()\n"
    "{\n"
    "    vec3 n = glint_unit(v_nrm);\n"
    "    o_color = vec4(glint_material(n, glint_unit(u_light - v_pos), glint_unit(u_eye - v_pos))"
    " * u_light_intensity, 1.0);\n"
    "}\n";

static int gpu(const void *data, material_gpu *g, glint_err *err)
{
    const double *a = data;
    (void)err;
    memset(g, 0, sizeof *g);
    g->program = "lambert-test";
    g->frag_src = frag;
    g->nuniforms = 1;
    g->uniform[0] = (material_gpu_uniform){"u_albedo", "vec3", {a[0], a[1], a[2]},
                                           "diffuse albedo per channel"};
    g->manifest = json_pack("{s:[f, f, f]}", "albedo", a[0], a[1], a[2]);
    return 0;
}

static const material_ops ops = {
    .eval = eval,
    .free = free,
    .to_json = to_json,
    .from_json = from_json,
    .gpu = gpu,
};

const method method_lambert_test = {
    .name = "lambert-test",
    .label = "Flat colour (test build)",
    .summary = "One diffuse colour for the whole object, without a highlight: a "
        "Lambert surface.",
    .when = "Use it to check that a method reaches the studio from its table alone; "
        "test builds only.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_NONE,
    .title = "Constant-colour Lambert (test build only)",
    .description = "One albedo for the whole object, least squares over the painted samples.",
    .params_size = sizeof(lambert_params),
    .params = params,
    .nparams = 1,
    .params_default = params_default,
    .levels = levels,
    .nlevels = 1,
    .fit = fit,
    .mat = &ops,
};
