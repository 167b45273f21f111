/* material.c: fitted materials: evaluation, CPU shading, files. */
#include "material.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fsio.h"
#include "raster.h"

#define MATERIAL_JSON_MAX (64u << 20)

static const char *const factor_names[3] = {"p", "q", "r"};

void material_init(material *m, hf_factors *fac, json_t *info)
{
    memset(m, 0, sizeof *m);
    strcpy(m->method, "hf3");
    m->fac = *fac;
    memset(fac, 0, sizeof *fac);
    m->info = info ? info : json_object();
}

void material_free(material *m)
{
    if (!m)
        return;
    hf_factors_free(&m->fac);
    json_decref(m->info);
    memset(m, 0, sizeof *m);
}

void material_eval(const material *m, const double n[3], const double wi[3],
                   const double wo[3], double rgb[3])
{
    hf_factors_eval(&m->fac, n, wi, wo, rgb);
}

int material_shade(const material *m, const gbuf *g, double intensity, float background,
                   img *out, glint_err *err)
{
    int rc;
    size_t np;

    if (!isfinite(intensity) || intensity < 0.0)
        return glint_err_set(err, GLINT_EINVAL, "light intensity %g must be finite and >= 0",
                             intensity);
    rc = img_alloc(out, g->width, g->height, 3, err);
    if (rc)
        return rc;
    np = (size_t)g->width * g->height;
    for (size_t p = 0; p < np; p++) {
        float *o = out->px + 3 * p;
        double n[3], wi[3], wo[3], rgb[3];
        if (!g->mask[p]) {
            o[0] = o[1] = o[2] = background;
            continue;
        }
        for (int c = 0; c < 3; c++) {
            n[c] = g->nrm[3 * p + c];
            wi[c] = g->wi[3 * p + c];
            wo[c] = g->wo[3 * p + c];
        }
        hf_factors_eval(&m->fac, n, wi, wo, rgb);
        for (int c = 0; c < 3; c++)
            o[c] = (float)(rgb[c] * intensity);
    }
    return 0;
}

int material_render(const material *m, const mesh *msh, const scene_view *v, int width,
                    int height, img *out, glint_err *err)
{
    gbuf g;
    int rc = raster_view(msh, v, width, height, &g, err);
    if (rc)
        return rc;
    rc = material_shade(m, &g, v->light_intensity, 0.0f, out, err);
    gbuf_free(&g);
    return rc;
}

static const char *model_name(hf_model m)
{
    return m == HF_MODEL_BRDF ? "brdf" : "radiance";
}

json_t *material_to_json(const material *m)
{
    const hf_factors *f = &m->fac;
    int R = f->res;
    char mapbuf[96];
    json_t *root = json_object(), *factors = json_object(), *a = json_array();

    hf_map_format(&f->map, mapbuf, sizeof mapbuf);
    json_object_set_new(root, "format", json_string("glint-material"));
    json_object_set_new(root, "version", json_integer(1));
    json_object_set_new(root, "method", json_string(m->method));
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
    json_object_set_new(root, "info", json_deep_copy(m->info ? m->info : json_object()));
    return root;
}

int material_save(const material *m, const char *dir, glint_err *err)
{
    const hf_factors *f = &m->fac;
    int R = f->res, rc;
    char path[4096];
    img lin = {0}, png = {0};
    json_t *root = NULL, *scales;
    char *text = NULL;

    rc = fsio_mkdirs(dir, err);
    if (rc)
        return rc;
    rc = img_alloc(&lin, R, 3, 3, err);
    if (rc)
        return rc;
    rc = img_alloc(&png, R, 3, 3, err);
    if (rc)
        goto done;
    root = material_to_json(m);
    scales = json_object();
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
    json_object_set_new(root, "png_scale", scales);
    if ((rc = fsio_join(path, sizeof path, dir, "factors.exr", err)) ||
        (rc = img_write(path, &lin, err)))
        goto done;
    if ((rc = fsio_join(path, sizeof path, dir, "factors.png", err)) ||
        (rc = img_write(path, &png, err)))
        goto done;
    text = json_dumps(root, JSON_INDENT(1) | JSON_REAL_PRECISION(17));
    if (!text) {
        rc = glint_err_set(err, GLINT_ENOMEM, "cannot serialize the material manifest");
        goto done;
    }
    if ((rc = fsio_join(path, sizeof path, dir, "material.json", err)))
        goto done;
    rc = fsio_write_atomic(path, text, strlen(text), err);
done:
    free(text);
    json_decref(root);
    img_free(&lin);
    img_free(&png);
    return rc;
}

static int get_number(const json_t *v, double *out)
{
    if (!json_is_number(v))
        return -1;
    *out = json_number_value(v);
    return isfinite(*out) ? 0 : -1;
}

int material_load(const char *path, material *out, glint_err *err)
{
    char file[4096], *text = NULL;
    size_t len;
    json_t *root = NULL, *v, *lf;
    json_error_t jerr;
    hf_factors fac;
    int rc, R;
    const char *model, *mapping;
    size_t plen = strlen(path);

    memset(out, 0, sizeof *out);
    memset(&fac, 0, sizeof fac);
    if (plen > 5 && strcmp(path + plen - 5, ".json") == 0)
        snprintf(file, sizeof file, "%s", path);
    else if ((rc = fsio_join(file, sizeof file, path, "material.json", err)))
        return rc;
    rc = fsio_read_all(file, MATERIAL_JSON_MAX, &text, &len, err);
    if (rc)
        return rc;
    root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    free(text);
    if (!root)
        return glint_err_set(err, GLINT_EFORMAT, "%s: line %d: %s", file, jerr.line, jerr.text);
    rc = GLINT_EFORMAT;
    if (!json_is_object(root) || !json_is_string(json_object_get(root, "format")) ||
        strcmp(json_string_value(json_object_get(root, "format")), "glint-material") != 0) {
        glint_err_set(err, rc, "%s is not a glint material (format != glint-material)", file);
        goto fail;
    }
    v = json_object_get(root, "version");
    if (!json_is_integer(v) || json_integer_value(v) != 1) {
        glint_err_set(err, rc, "%s: unsupported material version", file);
        goto fail;
    }
    v = json_object_get(root, "method");
    if (!json_is_string(v) || strcmp(json_string_value(v), "hf3") != 0) {
        glint_err_set(err, rc, "%s: unsupported method (hf3 expected)", file);
        goto fail;
    }
    v = json_object_get(root, "res");
    if (!json_is_integer(v) || json_integer_value(v) < HF_RES_MIN ||
        json_integer_value(v) > HF_RES_MAX) {
        glint_err_set(err, rc, "%s: res must be an integer in %d..%d", file, HF_RES_MIN,
                      HF_RES_MAX);
        goto fail;
    }
    R = (int)json_integer_value(v);
    model = json_string_value(json_object_get(root, "model"));
    mapping = json_string_value(json_object_get(root, "mapping"));
    if (!model || (strcmp(model, "radiance") != 0 && strcmp(model, "brdf") != 0)) {
        glint_err_set(err, rc, "%s: model must be \"radiance\" or \"brdf\"", file);
        goto fail;
    }
    if (!mapping || hf_map_parse(mapping, &fac.map, err) != 0) {
        glint_err_prefix(err, "%s: mapping", file);
        goto fail;
    }
    fac.res = R;
    fac.model = strcmp(model, "brdf") == 0 ? HF_MODEL_BRDF : HF_MODEL_RADIANCE;
    v = json_object_get(root, "a_used");
    if (!json_is_array(v) || json_array_size(v) != 3) {
        glint_err_set(err, rc, "%s: a_used must be an array of 3 numbers", file);
        goto fail;
    }
    for (int c = 0; c < 3; c++)
        if (get_number(json_array_get(v, (size_t)c), &fac.a_used[c])) {
            glint_err_set(err, rc, "%s: a_used[%d] is not a finite number", file, c);
            goto fail;
        }
    lf = json_object_get(root, "log_factors");
    fac.logf = malloc((size_t)9 * R * sizeof *fac.logf);
    if (!fac.logf) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto fail;
    }
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
                    glint_err_set(err, GLINT_ENONFINITE,
                                  "%s: log_factors.%s[%d][%d] is not a finite number in "
                                  "[-700, 700]", file, factor_names[j], k, c);
                    rc = GLINT_ENONFINITE;
                    goto fail;
                }
                fac.logf[(j * R + k) * 3 + c] = x;
            }
        }
    }
    v = json_object_get(root, "info");
    material_init(out, &fac, json_is_object(v) ? json_incref(v) : NULL);
    json_decref(root);
    return 0;
fail:
    hf_factors_free(&fac);
    json_decref(root);
    return rc;
}
