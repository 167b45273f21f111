/* method_maps_material.c: operations on maps materials (method_maps.h):
 * evaluation at a surface point, manifest members, files, GPU binding. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fsio.h"
#include "img.h"
#include "method_hf3_parts.h"
#include "method_hf4_parts.h"
#include "method_pbr.h"
#include "internal/method_maps_int.h"
#include "uvtex.h"

#define COEF_EXR "coefficients.exr"
#define COEF_PNG "coefficients.png"

const matmap *maps_matmap(const material *m)
{
    return m && m->method && m->method->mat == &maps_material_ops && m->data
               ? &((const maps_material *)m->data)->mm
               : NULL;
}

/* A product's factors whichever its method: the 1D ones (hf_factors'
 * layout) and, for hf4 products, the spatial factor's log nodes. */
typedef struct prod_view {
    int res, sres; /* sres 0: no spatial factor */
    hf_map_kind kind;
    hf_model model;
    const double *logf, *logs, *a_used;
} prod_view;

static prod_view view_of(const maps_material *x, int k)
{
    prod_view v;
    memset(&v, 0, sizeof v);
    if (x->product == &method_hf4) {
        const hf4_factors *f = x->mm.comp[k].data;
        v.res = f->res, v.sres = f->sres, v.kind = f->map.kind, v.model = f->model;
        v.logf = f->logf, v.logs = f->logs, v.a_used = f->a_used;
    } else {
        const hf_factors *f = x->mm.comp[k].data;
        v.res = f->res, v.kind = f->map.kind, v.model = f->model;
        v.logf = f->logf, v.a_used = f->a_used;
    }
    return v;
}

static void means(maps_material *x)
{
    size_t nt = (size_t)x->mm.res * x->mm.res;
    for (int k = 0; k < x->mm.k; k++) {
        const float *t = x->mm.coef + (size_t)k * nt;
        double s = 0.0;
        for (size_t i = 0; i < nt; i++)
            s += t[i];
        x->mean[k] = nt ? s / (double)nt : 0.0;
    }
}

int maps_material_init(material *m, const method *self, matmap *mm, json_t *info,
                       glint_err *err)
{
    maps_material *x = calloc(1, sizeof *x);
    if (!x) {
        json_decref(info);
        material_init(m, NULL, NULL, NULL);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    x->mm = *mm;
    x->product = mm->k > 0 && mm->comp[0].method ? mm->comp[0].method : &method_hf3;
    memset(mm, 0, sizeof *mm);
    means(x);
    material_init(m, self, x, info);
    return 0;
}

static void maps_eval(const void *data, const double uv[2], const double n[3],
                      const double wi[3], const double wo[3], double rgb[3])
{
    const maps_material *x = data;
    int at = uv && isfinite(uv[0]) && isfinite(uv[1]);
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (int k = 0; k < x->mm.k; k++) {
        double c = at ? matmap_coef(&x->mm, k, uv[0], uv[1]) : x->mean[k], v[3];
        if (!(c > 0.0))
            continue;
        material_eval_at(&x->mm.comp[k], at ? uv : NULL, n, wi, wo, v);
        for (int e = 0; e < 3; e++)
            rgb[e] += c * v[e];
    }
}

static void maps_free(void *data)
{
    maps_material *x = data;
    matmap_free(&x->mm);
    free(x);
}

static int maps_to_json(const void *data, json_t *root, glint_err *err)
{
    const maps_material *x = data;
    json_t *prods = json_array(), *mean = json_array(), *rel = json_array();
    int rc = 0;

    if (!prods || !mean || !rel) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the manifest");
        goto fail;
    }
    for (int k = 0; k < x->mm.k && !rc; k++) {
        json_t *p = json_object();
        if (!p || (rc = x->product->mat->to_json(x->mm.comp[k].data, p, err))) {
            json_decref(p);
            rc = rc ? rc : glint_err_set(err, GLINT_ENOMEM, "out of memory for the manifest");
            goto fail;
        }
        json_array_append_new(prods, p);
        json_array_append_new(mean, json_real(x->mean[k]));
    }
    for (int k = 0; k <= x->mm.k; k++)
        json_array_append_new(rel, json_real(x->mm.rel_rms[k]));
    json_object_set_new(root, "components", json_integer(x->mm.k));
    json_object_set_new(root, "map_res", json_integer(x->mm.res));
    json_object_set_new(root, "stop", json_string(x->mm.stop ? x->mm.stop : "components"));
    json_object_set_new(root, "residual_rel_rms", rel);
    json_object_set_new(
        root, "coefficients",
        json_pack("{s:s, s:s, s:s, s:o}", "exr", COEF_EXR, "png", COEF_PNG, "layout",
                  "one channel, map_res wide, components x map_res high: product k's texture "
                  "in rows k map_res .. (k+1) map_res - 1, its row 0 (v = 0) first; texel "
                  "(i, j) covers u in [i, i+1) / map_res and v in [j, j+1) / map_res; read "
                  "bilinearly between texel centres, clamped at the border",
                  "mean", mean));
    json_object_set_new(root, "products", prods);
    json_object_set_new(root, "product", json_string(x->product->name));
    json_object_set_new(root, "model",
                        json_string(x->product == &method_hf4
                                        ? "sum over k of coefficient_k(uv) x product_k(uv, wi, "
                                          "wo), each product a four-factor one (p q r s(u, v))"
                                    : x->product == &method_pbr
                                        ? "sum over k of coefficient_k(uv) x product_k(wi, wo), "
                                          "each product a pbr material (kd / pi + GGX lobes)"
                                        : "sum over k of coefficient_k(uv) x product_k(wi, wo)"));
    return 0;
fail:
    json_decref(prods);
    json_decref(mean);
    json_decref(rel);
    return rc;
}

/* The directory of the manifest `file` (OUT: dir). */
static void dir_of(const char *file, char *dir, size_t len)
{
    const char *slash = strrchr(file, '/');
    if (!slash)
        snprintf(dir, len, ".");
    else if (slash == file)
        snprintf(dir, len, "/");
    else
        snprintf(dir, len, "%.*s", (int)(slash - file), file);
}

static int read_coefficients(const char *file, maps_material *x, glint_err *err)
{
    char dir[4096], path[4096];
    size_t nt = (size_t)x->mm.res * x->mm.res;
    img im = {0};
    int rc;

    dir_of(file, dir, sizeof dir);
    if ((rc = fsio_join(path, sizeof path, dir, COEF_EXR, err)))
        return rc;
    if ((rc = img_read(path, &im, err))) {
        glint_err_prefix(err, "%s: the coefficient textures", file);
        return rc;
    }
    rc = GLINT_EFORMAT;
    if (im.width != x->mm.res || im.height != x->mm.k * x->mm.res) {
        glint_err_set(err, rc, "%s: %s is %dx%d, expected %dx%d (map_res x components "
                      "map_res)", file, COEF_EXR, im.width, im.height, x->mm.res,
                      x->mm.k * x->mm.res);
        goto done;
    }
    if (!(x->mm.coef = malloc((size_t)x->mm.k * nt * sizeof *x->mm.coef))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    for (size_t i = 0; i < (size_t)x->mm.k * nt; i++) {
        float v = im.px[i * im.channels];
        if (!(v >= 0.0f && v <= 1.0f)) { /* NaN fails too */
            glint_err_set(err, rc, "%s: %s texel %zu of product %zu is %g, outside [0, 1]",
                          file, COEF_EXR, i % nt, i / nt, v);
            goto done;
        }
        x->mm.coef[i] = v;
    }
    rc = 0;
done:
    img_free(&im);
    return rc;
}

static int maps_from_json(const json_t *root, const char *file, void **data, glint_err *err)
{
    maps_material *x = calloc(1, sizeof *x);
    json_t *prods = json_object_get(root, "products"), *v;
    int rc = GLINT_EFORMAT;

    *data = NULL;
    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    v = json_object_get(root, "map_res");
    if (!json_is_integer(v) || json_integer_value(v) < MAPS_RES_MIN ||
        json_integer_value(v) > MAPS_RES_MAX) {
        glint_err_set(err, rc, "%s: map_res must be an integer in %d..%d", file, MAPS_RES_MIN,
                      MAPS_RES_MAX);
        goto fail;
    }
    x->mm.res = (int)json_integer_value(v);
    v = json_object_get(root, "product"); /* absent in files of hf3 products only */
    if (!v || (json_is_string(v) && strcmp(json_string_value(v), "hf3") == 0)) {
        x->product = &method_hf3;
    } else if (json_is_string(v) && strcmp(json_string_value(v), "hf4") == 0) {
        x->product = &method_hf4;
    } else if (json_is_string(v) && strcmp(json_string_value(v), "pbr") == 0) {
        x->product = &method_pbr;
    } else {
        glint_err_set(err, rc, "%s: product must be \"hf3\", \"hf4\" or \"pbr\"", file);
        goto fail;
    }
    if (!json_is_array(prods) || json_array_size(prods) < 1 ||
        json_array_size(prods) > MATMAP_MAX ||
        json_array_size(prods) * (size_t)x->mm.res > MAPS_ROWS_MAX) {
        glint_err_set(err, rc, "%s: products must be an array of 1..%d products (at most %d "
                      "rows of coefficients)", file, MATMAP_MAX, MAPS_ROWS_MAX);
        goto fail;
    }
    for (size_t k = 0; k < json_array_size(prods); k++) {
        void *d = NULL;
        char where[4200];
        snprintf(where, sizeof where, "%s: products[%zu]", file, k);
        if ((rc = x->product->mat->from_json(json_array_get(prods, k), where, &d, err)))
            goto fail;
        material_init(&x->mm.comp[k], x->product, d, NULL);
        x->mm.k = (int)k + 1;
    }
    v = json_object_get(root, "stop");
    x->mm.stop = json_is_string(v) && strcmp(json_string_value(v), "tolerance") == 0 ? "tolerance"
                 : json_is_string(v) && strcmp(json_string_value(v), "no-gain") == 0
                     ? "no-gain"
                     : "components";
    v = json_object_get(root, "residual_rel_rms");
    for (int k = 0; json_is_array(v) && k <= x->mm.k && k < (int)json_array_size(v); k++)
        x->mm.rel_rms[k] = json_number_value(json_array_get(v, (size_t)k));
    if ((rc = read_coefficients(file, x, err)))
        goto fail;
    means(x);
    *data = x;
    return 0;
fail:
    maps_free(x);
    return rc;
}

/* Every product's spatial factor (hf4 products): spatial.exr, linear,
 * s_res wide, K s_res high, product k's nodes in rows k s_res ..
 * (k + 1) s_res - 1 (node (i, j) at row j, column i); spatial.png each
 * product's channel over its maximum (spatial_png_scale[product][channel]). */
static int save_spatial(const maps_material *x, const char *dir, json_t *root, glint_err *err)
{
    int K = x->mm.k, S = view_of(x, 0).sres, rc;
    img lin = {0}, png = {0};
    json_t *scales = json_array();

    if (!scales)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = img_alloc(&lin, S, K * S, 3, err)) || (rc = img_alloc(&png, S, K * S, 3, err)))
        goto done;
    for (int k = 0; k < K; k++) {
        prod_view v = view_of(x, k);
        float *l = lin.px + (size_t)k * S * S * 3, *q = png.px + (size_t)k * S * S * 3;
        double mx[3] = {0, 0, 0};
        for (int t = 0; t < S * S; t++)
            for (int c = 0; c < 3; c++) {
                double e = exp(v.logs[3 * t + c] > 80.0 ? 80.0 : v.logs[3 * t + c]);
                l[3 * t + c] = (float)e;
                mx[c] = e > mx[c] ? e : mx[c];
            }
        for (int t = 0; t < S * S; t++)
            for (int c = 0; c < 3; c++)
                q[3 * t + c] = mx[c] > 0.0 ? (float)(l[3 * t + c] / mx[c]) : 0.0f;
        json_array_append_new(scales, json_pack("[f,f,f]", mx[0], mx[1], mx[2]));
    }
    json_object_set(root, "spatial_png_scale", scales);
    json_object_set_new(root, "spatial_layout",
                        json_string("spatial.exr: RGB float, s_res wide, s_res rows per "
                                    "product (node (i, j) at row j, column i, at u = i / "
                                    "(s_res - 1), v = j / (s_res - 1)), product 0 first; "
                                    "spatial.png: each product's channel over its maximum "
                                    "(spatial_png_scale[product][channel])"));
    rc = img_write_pair(dir, "spatial", &lin, &png, err);
done:
    json_decref(scales);
    img_free(&lin);
    img_free(&png);
    return rc;
}

/* coefficients.exr / .png (method_maps.h), and factors.exr / .png: every
 * product's linear factors, 3 rows each (p, q, r), res wide; the PNG's rows
 * over their maximum as hf3 writes them (png_scale per product); spatial
 * factors of hf4 products as save_spatial writes them. */
static int save_hf_files(const maps_material *x, const char *dir, json_t *root, glint_err *err)
{
    int K = x->mm.k, M = x->mm.res, R = 0, rc;
    size_t nt = (size_t)M * M;
    img c = {0}, lin = {0}, png = {0};
    json_t *scales = json_array();

    for (int k = 0; k < K; k++) {
        prod_view v = view_of(x, k);
        R = v.res > R ? v.res : R;
    }
    if (!scales)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = img_alloc(&c, M, K * M, 1, err)) || (rc = img_alloc(&lin, R, 3 * K, 3, err)) ||
        (rc = img_alloc(&png, R, 3 * K, 3, err)))
        goto done;
    memcpy(c.px, x->mm.coef, (size_t)K * nt * sizeof *c.px);
    for (int k = 0; k < K; k++) {
        prod_view f = view_of(x, k);
        json_t *sk = json_array();
        for (int j = 0; j < 3; j++) {
            json_t *sc = json_array();
            for (int ch = 0; ch < 3; ch++) {
                double mx = 0.0;
                float *row = lin.px + (size_t)(3 * k + j) * R * 3, *prow;
                for (int t = 0; t < f.res; t++) {
                    double v = exp(f.logf[(j * f.res + t) * 3 + ch]);
                    row[3 * t + ch] = (float)v;
                    mx = v > mx ? v : mx;
                }
                prow = png.px + (size_t)(3 * k + j) * R * 3;
                for (int t = 0; t < f.res; t++)
                    prow[3 * t + ch] = mx > 0.0 ? (float)(row[3 * t + ch] / mx) : 0.0f;
                json_array_append_new(sc, json_real(mx));
            }
            json_array_append_new(sk, sc);
        }
        json_array_append_new(scales, sk);
    }
    json_object_set(root, "png_scale", scales);
    json_object_set_new(root, "factors_layout",
                        json_string("factors.exr: RGB float, res wide, 3 rows per product "
                                    "(p, q, r), product 0 first; factors.png: each row over its "
                                    "maximum per channel (png_scale[product][row][channel])"));
    if ((rc = img_write_pair(dir, "coefficients", &c, &c, err)) ||
        (rc = img_write_pair(dir, "factors", &lin, &png, err)))
        goto done;
    if (K > 0 && view_of(x, 0).sres > 0)
        rc = save_spatial(x, dir, root, err);
done:
    json_decref(scales);
    img_free(&c);
    img_free(&lin);
    img_free(&png);
    return rc;
}

/* coefficients.exr / .png alone: pbr products are whole in the manifest. */
static int save_coefficients(const maps_material *x, const char *dir, glint_err *err)
{
    img c = {0};
    int rc = img_alloc(&c, x->mm.res, x->mm.k * x->mm.res, 1, err);
    if (!rc) {
        memcpy(c.px, x->mm.coef, (size_t)x->mm.k * x->mm.res * x->mm.res * sizeof *c.px);
        rc = img_write_pair(dir, "coefficients", &c, &c, err);
    }
    img_free(&c);
    return rc;
}

static int maps_save_files(const void *data, const char *dir, json_t *root, glint_err *err)
{
    const maps_material *x = data;
    return x->product == &method_pbr ? save_coefficients(x, dir, err)
                                     : save_hf_files(x, dir, root, err);
}

static json_t *maps_summary(const void *data)
{
    const maps_material *x = data;
    prod_view f = x->mm.k && x->product != &method_pbr ? view_of(x, 0) : (prod_view){0};
    json_t *o;
    if (x->product == &method_pbr)
        return maps_pbr_summary(x);
    o = json_pack("{s:i, s:i, s:i, s:s, s:s}", "res", f.res, "components", x->mm.k,
                          "map_res", x->mm.res, "stop", x->mm.stop ? x->mm.stop : "components",
                          "product", x->product->name);
    if (o && f.sres > 0)
        json_object_set_new(o, "s_res", json_integer(f.sres));
    return o;
}

/* The GPU texture (RGB float), width max(res, map_res, K, s_res):
 *   rows 3k .. 3k+2   product k's log-factors p, q, r (res texels)
 *   row 3K            texel k: product k's mapping offset a_used
 *   rows 3K+1+b M ..  block b of coefficient rows: texel (i, j) holds the
 *                     coefficients of products 3b, 3b+1, 3b+2 in R, G, B
 *   then, for hf4 products, s_res rows per product: log s, node (i, j) at
 *                     row j, column i of product k's block */
static int maps_gpu(const void *data, material_gpu *g, glint_err *err)
{
    const maps_material *x = data;
    prod_view f0;
    int K = x->mm.k, M = x->mm.res, R, S, W, H, B = (K + 2) / 3, base;

    memset(g, 0, sizeof *g);
    if (K < 1 || !x->mm.coef)
        return glint_err_set(err, GLINT_EINVAL, "material has no products");
    if (x->product == &method_pbr)
        return maps_pbr_gpu(x, g, err);
    f0 = view_of(x, 0);
    R = f0.res;
    S = f0.sres;
    for (int k = 1; k < K; k++) {
        prod_view f = view_of(x, k);
        if (f.res != R || f.sres != S || f.kind != f0.kind || f.model != f0.model)
            return glint_err_set(err, GLINT_EUNSUPPORTED,
                                 "the products differ in res, s_res, mapping or model: the "
                                 "GPU evaluation needs one of each");
    }
    W = R > M ? R : M;
    W = W > K ? W : K;
    W = W > S ? W : S;
    base = 3 * K + 1 + B * M;
    H = base + K * S;
    g->program = "maps";
    g->frag_src = maps_glsl_frag;
    g->tex_uniform = "u_maps";
    g->tex_w = W;
    g->tex_h = H;
    if (!(g->tex = calloc((size_t)W * H * 3, sizeof *g->tex)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the material texture");
    for (int k = 0; k < K; k++) {
        prod_view f = view_of(x, k);
        for (int j = 0; j < 3; j++)
            for (int t = 0; t < R; t++)
                for (int c = 0; c < 3; c++)
                    g->tex[((size_t)(3 * k + j) * W + t) * 3 + c] =
                        (float)f.logf[(j * R + t) * 3 + c];
        for (int c = 0; c < 3; c++)
            g->tex[((size_t)(3 * K) * W + k) * 3 + c] = (float)f.a_used[c];
        for (int j = 0; j < M; j++)
            for (int i = 0; i < M; i++)
                g->tex[((size_t)(3 * K + 1 + (k / 3) * M + j) * W + i) * 3 + k % 3] =
                    x->mm.coef[(size_t)k * M * M + (size_t)j * M + i];
        for (int j = 0; j < S; j++)
            for (int i = 0; i < S; i++)
                for (int c = 0; c < 3; c++)
                    g->tex[((size_t)(base + k * S + j) * W + i) * 3 + c] =
                        (float)f.logs[((size_t)j * S + i) * 3 + c];
    }
    g->nuniforms = 6;
    g->uniform[0] = (material_gpu_uniform){"u_res", "int", {R, 0, 0}, "texels per factor"};
    g->uniform[1] = (material_gpu_uniform){"u_map_res", "int", {M, 0, 0},
                                           "coefficient texels per side"};
    g->uniform[2] = (material_gpu_uniform){"u_k", "int", {K, 0, 0}, "products"};
    g->uniform[3] = (material_gpu_uniform){"u_map_kind", "int", {(int)f0.kind, 0, 0},
                                           "inverse mapping: 0 log, 1 add, 2 sub"};
    g->uniform[4] = (material_gpu_uniform){"u_model_brdf", "int",
                                           {f0.model == HF_MODEL_BRDF, 0, 0},
                                           "1: multiply by n.wi (brdf model)"};
    g->uniform[5] = (material_gpu_uniform){"u_sres", "int", {S, 0, 0},
                                           "nodes per side of each product's spatial factor "
                                           "(0: three-factor products)"};
    g->manifest = json_pack(
        "{s:s, s:i, s:i, s:i, s:i}", "texture_layout",
        "u_maps: RGB float, width max(res, map_res, K, s_res); rows 3k..3k+2 product k's "
        "log-factors p, q, r; row 3K texel k product k's mapping offset; from row 3K+1, blocks "
        "of map_res rows, block b holding the coefficients of products 3b, 3b+1, 3b+2 in R, G, "
        "B (row 0 of a block at v = 0); then (s_res > 0) s_res rows per product of log s, node "
        "(i, j) at row j, column i of the product's block",
        "products", K, "res", R, "map_res", M, "s_res", S);
    if (!g->manifest) {
        material_gpu_free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    return 0;
}

const material_ops maps_material_ops = {
    .eval = maps_eval,
    .free = maps_free,
    .to_json = maps_to_json,
    .from_json = maps_from_json,
    .save_files = maps_save_files,
    .gpu = maps_gpu,
    .summary = maps_summary,
    .spatial = 1,
};
