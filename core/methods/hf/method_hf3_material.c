/* method_hf3_material.c: operations on hf3 materials (the factors of
 * hf.h): evaluation, manifest members, files, GPU binding. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fsio.h"
#include "method_hf3.h"


static const char *const factor_names[3] = {"p", "q", "r"};

hf_factors *hf3_factors(const material *m)
{
    return m && m->method == &method_hf3 ? m->data : NULL;
}

int hf3_material_init(material *m, hf_factors *fac, json_t *info, glint_err *err)
{
    hf_factors *f = malloc(sizeof *f);
    if (!f) {
        hf_factors_free(fac);
        memset(fac, 0, sizeof *fac);
        json_decref(info);
        material_init(m, NULL, NULL, NULL);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory making the material");
    }
    *f = *fac;
    memset(fac, 0, sizeof *fac);
    material_init(m, &method_hf3, f, info);
    return 0;
}

static void hf3_eval(const void *data, const double uv[2], const double n[3],
                     const double wi[3], const double wo[3], double rgb[3])
{
    (void)uv;
    hf_factors_eval(data, n, wi, wo, rgb);
}

static void hf3_free(void *data)
{
    hf_factors_free(data);
    free(data);
}

static const char *model_name(hf_model m)
{
    return m == HF_MODEL_BRDF ? "brdf" : "radiance";
}

static int hf3_to_json(const void *data, json_t *root, glint_err *err)
{
    const hf_factors *f = data;
    int R = f->res;
    char mapbuf[96];
    json_t *factors = json_object(), *a = json_array();

    if (!factors || !a) {
        json_decref(factors);
        json_decref(a);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the manifest");
    }
    hf_map_format(&f->map, mapbuf, sizeof mapbuf);
    json_object_set_new(root, "res", json_integer(R));
    json_object_set_new(root, "texels", json_string("node"));
    json_object_set_new(root, "model", json_string(model_name(f->model)));
    json_object_set_new(root, "mapping", json_string(mapbuf));
    for (int c = 0; c < 3; c++)
        json_array_append_new(a, json_real(f->a_used[c]));
    json_object_set_new(root, "a_used", a);
    for (int j = 0; j < 3; j++) {
        json_t *rows = json_array();
        for (int k = 0; k < R; k++) {
            json_t *t = json_array();
            for (int c = 0; c < 3; c++)
                json_array_append_new(t, json_real(f->logf[(j * R + k) * 3 + c]));
            json_array_append_new(rows, t);
        }
        json_object_set_new(factors, factor_names[j], rows);
    }
    json_object_set_new(root, "log_factors", factors);
    json_object_set_new(root, "gauge", json_string("equal mean log per factor and channel"));
    return 0;
}

static int get_number(const json_t *v, double *out)
{
    if (!json_is_number(v))
        return -1;
    *out = json_number_value(v);
    return isfinite(*out) ? 0 : -1;
}

static int hf3_from_json(const json_t *root, const char *file, void **data, glint_err *err)
{
    hf_factors fac, *out;
    const char *model, *mapping;
    json_t *v, *lf;
    int rc = GLINT_EFORMAT, R;

    *data = NULL;
    memset(&fac, 0, sizeof fac);
    v = json_object_get(root, "res");
    if (!json_is_integer(v) || json_integer_value(v) < HF_RES_MIN ||
        json_integer_value(v) > HF_RES_MAX)
        return glint_err_set(err, rc, "%s: res must be an integer in %d..%d", file, HF_RES_MIN,
                             HF_RES_MAX);
    R = (int)json_integer_value(v);
    model = json_string_value(json_object_get(root, "model"));
    mapping = json_string_value(json_object_get(root, "mapping"));
    if (!model || (strcmp(model, "radiance") != 0 && strcmp(model, "brdf") != 0))
        return glint_err_set(err, rc, "%s: model must be \"radiance\" or \"brdf\"", file);
    if (!mapping || hf_map_parse(mapping, &fac.map, err) != 0) {
        if (!mapping)
            return glint_err_set(err, rc, "%s: mapping must be a string", file);
        glint_err_prefix(err, "%s: mapping", file);
        return rc;
    }
    fac.res = R;
    fac.model = strcmp(model, "brdf") == 0 ? HF_MODEL_BRDF : HF_MODEL_RADIANCE;
    v = json_object_get(root, "a_used");
    if (!json_is_array(v) || json_array_size(v) != 3)
        return glint_err_set(err, rc, "%s: a_used must be an array of 3 numbers", file);
    for (int c = 0; c < 3; c++)
        if (get_number(json_array_get(v, (size_t)c), &fac.a_used[c]))
            return glint_err_set(err, rc, "%s: a_used[%d] is not a finite number", file, c);
    lf = json_object_get(root, "log_factors");
    fac.logf = malloc((size_t)9 * R * sizeof *fac.logf);
    if (!fac.logf)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int j = 0; j < 3; j++) {
        json_t *rows = json_object_get(lf, factor_names[j]);
        if (!json_is_array(rows) || json_array_size(rows) != (size_t)R) {
            glint_err_set(err, rc, "%s: log_factors.%s must hold %d texels", file,
                          factor_names[j], R);
            goto fail;
        }
        for (int k = 0; k < R; k++) {
            json_t *t = json_array_get(rows, (size_t)k);
            if (!json_is_array(t) || json_array_size(t) != 3) {
                glint_err_set(err, rc, "%s: log_factors.%s[%d] must be [r, g, b]", file,
                              factor_names[j], k);
                goto fail;
            }
            for (int c = 0; c < 3; c++) {
                double x;
                if (get_number(json_array_get(t, (size_t)c), &x) || fabs(x) > 700.0) {
                    rc = glint_err_set(err, GLINT_ENONFINITE,
                                       "%s: log_factors.%s[%d][%d] is not a finite number in "
                                       "[-700, 700]", file, factor_names[j], k, c);
                    goto fail;
                }
                fac.logf[(j * R + k) * 3 + c] = x;
            }
        }
    }
    out = malloc(sizeof *out);
    if (!out) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto fail;
    }
    *out = fac;
    *data = out;
    return 0;
fail:
    hf_factors_free(&fac);
    return rc;
}

/* factors.exr (linear factor values) and factors.png (each row over its
 * maximum, the scales in the manifest as png_scale); dir NULL: png_scale
 * only.  Both files follow from the log-factors in the manifest. */
static int hf3_save_files(const void *data, const char *dir, json_t *root, glint_err *err)
{
    const hf_factors *f = data;
    int R = f->res, rc;
    img lin = {0}, png = {0};
    json_t *scales = json_object();

    if (!scales)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = img_alloc(&lin, R, 3, 3, err)) || (rc = img_alloc(&png, R, 3, 3, err)))
        goto done;
    for (int j = 0; j < 3; j++) {
        json_t *sc = json_array();
        for (int c = 0; c < 3; c++) {
            double mx = 0.0;
            for (int k = 0; k < R; k++) {
                double v = exp(f->logf[(j * R + k) * 3 + c]);
                lin.px[((size_t)j * R + k) * 3 + c] = (float)v;
                if (v > mx)
                    mx = v;
            }
            for (int k = 0; k < R; k++)
                png.px[((size_t)j * R + k) * 3 + c] =
                    mx > 0.0 ? (float)(lin.px[((size_t)j * R + k) * 3 + c] / mx) : 0.0f;
            json_array_append_new(sc, json_real(mx));
        }
        json_object_set_new(scales, factor_names[j], sc);
    }
    json_object_set(root, "png_scale", scales);
    rc = dir ? img_write_pair(dir, "factors", &lin, &png, err) : 0;
done:
    json_decref(scales);
    img_free(&lin);
    img_free(&png);
    return rc;
}

static json_t *hf3_summary(const void *data)
{
    return json_pack("{s:i}", "res", ((const hf_factors *)data)->res);
}

static const char *map_kind_name(hf_map_kind k)
{
    return k == HF_MAP_ADD ? "add" : k == HF_MAP_SUB ? "sub" : "log";
}

/* The method's members of shader.json. */
static json_t *gpu_manifest(const hf_factors *f)
{
    char mapbuf[96];
    json_t *root = json_object(), *tex = json_object(), *files = json_object(),
           *rows = json_array(), *a = json_array(), *kinds = json_object(),
           *map = json_object();

    hf_map_format(&f->map, mapbuf, sizeof mapbuf);
    for (int c = 0; c < 3; c++)
        json_array_append_new(a, json_real(f->a_used[c]));
    json_object_set_new(root, "res", json_integer(f->res));
    json_object_set_new(root, "model", json_string(model_name(f->model)));
    json_object_set_new(map, "spec", json_string(mapbuf));
    json_object_set_new(map, "kind", json_string(map_kind_name(f->map.kind)));
    json_object_set_new(map, "u_map_kind", json_integer((int)f->map.kind));
    json_object_set_new(map, "a_used", a);
    json_object_set_new(map, "inverse",
                        json_string(f->map.kind == HF_MAP_ADD   ? "max(pqr - a, 0)"
                                    : f->map.kind == HF_MAP_SUB ? "max(a - pqr, 0)"
                                                                : "pqr"));
    json_object_set_new(root, "mapping", map);
    json_array_append_new(rows, json_string("log p (pi_p: wi on the tangent plane)"));
    json_array_append_new(rows, json_string("log q (pi_q: h on the tangent plane)"));
    json_array_append_new(rows, json_string("log r (pi_r: wo on the tangent plane)"));
    json_object_set_new(files, "exr", json_string("glint_factors.exr"));
    json_object_set_new(files, "rgba16f", json_string("glint_factors_rgba16f.bin"));
    json_object_set_new(tex, "uniform", json_string("u_factors"));
    json_object_set_new(tex, "files", files);
    json_object_set_new(tex, "width", json_integer(f->res));
    json_object_set_new(tex, "height", json_integer(3));
    json_object_set_new(tex, "rows", rows);
    json_object_set_new(tex, "values",
                        json_string("natural log of the factor value, per RGB channel; "
                                    "the material is inverse_map(exp(log p + log q + log r))"));
    json_object_set_new(tex, "texels",
                        json_string("node convention: texel k at u = k / (res - 1); "
                                    "the shader fetches texels with texelFetch and "
                                    "interpolates linearly itself"));
    json_object_set_new(tex, "internal_format", json_string("RGBA16F or RGBA32F"));
    json_object_set_new(tex, "filter", json_string("NEAREST, no mipmaps, CLAMP_TO_EDGE"));
    json_object_set_new(tex, "exr_layout",
                        json_string("RGB float, res x 3 pixels, image row 0 = p, 1 = q, 2 = r"));
    json_object_set_new(tex, "rgba16f_layout",
                        json_string("raw IEEE half floats, little endian, RGBA (A = 0), "
                                    "row-major, row 0 = p, 1 = q, 2 = r: upload as is with "
                                    "texImage2D(TEXTURE_2D, 0, RGBA16F, res, 3, 0, RGBA, "
                                    "HALF_FLOAT, data)"));
    json_object_set_new(root, "texture", tex);
    json_object_set_new(kinds, "log", json_integer(0));
    json_object_set_new(kinds, "add", json_integer(1));
    json_object_set_new(kinds, "sub", json_integer(2));
    json_object_set_new(root, "map_kinds", kinds);
    return root;
}

static void uniform(material_gpu *g, const char *name, const char *type, double x, double y,
                    double z, const char *meaning)
{
    material_gpu_uniform *u = &g->uniform[g->nuniforms++];
    u->name = name;
    u->type = type;
    u->v[0] = x;
    u->v[1] = y;
    u->v[2] = z;
    u->meaning = meaning;
}

static int hf3_gpu(const void *data, material_gpu *g, glint_err *err)
{
    const hf_factors *f = data;
    size_t n = (size_t)9 * f->res;

    memset(g, 0, sizeof *g);
    if (f->res < HF_RES_MIN || f->res > HF_RES_MAX || !f->logf)
        return glint_err_set(err, GLINT_EINVAL,
                             "material has no factors (res %d, expected %d..%d)", f->res,
                             HF_RES_MIN, HF_RES_MAX);
    if ((int)f->map.kind < HF_MAP_LOG || (int)f->map.kind > HF_MAP_SUB)
        return glint_err_set(err, GLINT_EINVAL, "material mapping kind %d unknown",
                             (int)f->map.kind);
    g->program = "hf3";
    g->frag_src = hf3_glsl_frag;
    g->tex_uniform = "u_factors";
    g->tex_w = f->res;
    g->tex_h = 3;
    g->tex = malloc(n * sizeof *g->tex);
    g->manifest = gpu_manifest(f);
    if (!g->tex || !g->manifest) {
        material_gpu_free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the factor texture");
    }
    for (size_t i = 0; i < n; i++)
        g->tex[i] = (float)f->logf[i];
    uniform(g, "u_res", "int", f->res, 0, 0, "texels per factor");
    uniform(g, "u_map_kind", "int", (int)f->map.kind, 0, 0,
            "inverse mapping: 0 log, 1 add, 2 sub");
    uniform(g, "u_a", "vec3", f->a_used[0], f->a_used[1], f->a_used[2],
            "mapping offset per channel (a_used)");
    uniform(g, "u_model_brdf", "int", f->model == HF_MODEL_BRDF, 0, 0,
            "1: multiply by n.wi (brdf model); 0: radiance model");
    return 0;
}

static const char *const hf3_derived_files[] = {"factors.exr", "factors.png", NULL};

const material_ops hf3_material_ops = {
    .eval = hf3_eval,
    .free = hf3_free,
    .to_json = hf3_to_json,
    .from_json = hf3_from_json,
    .save_files = hf3_save_files,
    .derived_files = hf3_derived_files,
    .gpu = hf3_gpu,
    .summary = hf3_summary,
    .brdf_explorer = hf3_brdf_explorer,
};
