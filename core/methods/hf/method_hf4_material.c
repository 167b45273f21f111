/* method_hf4_material.c: operations on hf4 materials (method_hf4.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fsio.h"
#include "img.h"
#include "internal/method_hfx_int.h"
#include "method_hf3_parts.h"
#include "method_hf4.h"

const hf4_factors *hf4_of(const material *m)
{
    return m && m->method == &method_hf4 ? m->data : NULL;
}

/* The 1D part seen as hf3's factors (borrowed: nothing to free). */
static hf_factors as_hf3(const hf4_factors *f)
{
    hf_factors h;
    memset(&h, 0, sizeof h);
    h.res = f->res;
    h.model = f->model;
    h.map = f->map;
    memcpy(h.a_used, f->a_used, sizeof h.a_used);
    h.logf = f->logf;
    return h;
}

static void hf4_eval_op(const void *data, const double uv[2], const double n[3],
                        const double wi[3], const double wo[3], double rgb[3])
{
    hf4_factors_eval(data, uv, n, wi, wo, rgb);
}

static void hf4_free_op(void *data)
{
    hf4_factors_free(data);
    free(data);
}

static int hf4_to_json(const void *data, json_t *root, glint_err *err)
{
    const hf4_factors *f = data;
    hf_factors h = as_hf3(f);
    json_t *ls;
    int rc;
    if ((rc = hf3_material_ops.to_json(&h, root, err)))
        return rc;
    if (!(ls = hfx_log_nodes_json(f->logs, f->sres * f->sres)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the manifest");
    json_object_set_new(root, "s_res", json_integer(f->sres));
    json_object_set_new(root, "log_s", ls);
    json_object_set_new(root, "s_nodes",
                        json_string("node (i, j) at u = i / (s_res - 1), v = j / (s_res - 1): "
                                    "log_s[j s_res + i]; bilinear between nodes"));
    json_object_set_new(root, "gauge",
                        json_string("equal mean log per factor (p, q, r, s) and channel"));
    json_object_set_new(root, "model_formula",
                        json_string("inverse_map(p(pi_p) q(pi_q) r(pi_r) s(u, v))"));
    return 0;
}

static int hf4_from_json(const json_t *root, const char *file, void **data, glint_err *err)
{
    void *hd = NULL;
    hf_factors *h;
    hf4_factors *f;
    json_t *v, *ls;
    int rc, S;

    *data = NULL;
    v = json_object_get(root, "s_res");
    if (!json_is_integer(v) || json_integer_value(v) < HF4_SRES_MIN ||
        json_integer_value(v) > HF4_SRES_MAX)
        return glint_err_set(err, GLINT_EFORMAT, "%s: s_res must be an integer in %d..%d",
                             file, HF4_SRES_MIN, HF4_SRES_MAX);
    S = (int)json_integer_value(v);
    ls = json_object_get(root, "log_s");
    if (!json_is_array(ls) || json_array_size(ls) != (size_t)S * S)
        return glint_err_set(err, GLINT_EFORMAT, "%s: log_s must hold %d nodes", file, S * S);
    if ((rc = hf3_material_ops.from_json(root, file, &hd, err)))
        return rc;
    h = hd;
    if (!(f = calloc(1, sizeof *f)) || !(f->logs = malloc(3 * (size_t)S * S * sizeof *f->logs))) {
        free(f);
        hf_factors_free(h);
        free(h);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    f->res = h->res;
    f->sres = S;
    f->model = h->model;
    f->map = h->map;
    memcpy(f->a_used, h->a_used, sizeof f->a_used);
    f->logf = h->logf;
    free(h);
    if ((rc = hfx_log_nodes_get(ls, S * S, f->logs, file, "log_s", err))) {
        hf4_free_op(f);
        return rc;
    }
    hf4_factors_means(f);
    *data = f;
    return 0;
}

/* factors.exr / .png as hf3 writes them; spatial.exr (linear s) and
 * spatial.png (each channel over its maximum, spatial_png_scale); dir NULL:
 * the manifest's members only.  All four follow from the manifest. */
static const char *const hf4_derived_files[] = {"factors.exr", "factors.png", "spatial.exr",
                                                "spatial.png", NULL};

static int hf4_save_files(const void *data, const char *dir, json_t *root, glint_err *err)
{
    const hf4_factors *f = data;
    hf_factors h = as_hf3(f);
    int S = f->sres, rc;
    img lin = {0}, png = {0};
    double mx[3] = {0, 0, 0};

    if ((rc = hf3_material_ops.save_files(&h, dir, root, err)))
        return rc;
    if ((rc = img_alloc(&lin, S, S, 3, err)) || (rc = img_alloc(&png, S, S, 3, err)))
        goto done;
    for (int t = 0; t < S * S; t++)
        for (int c = 0; c < 3; c++) {
            double v = exp(f->logs[3 * t + c] > 80.0 ? 80.0 : f->logs[3 * t + c]);
            lin.px[3 * t + c] = (float)v;
            mx[c] = v > mx[c] ? v : mx[c];
        }
    for (int t = 0; t < S * S; t++)
        for (int c = 0; c < 3; c++)
            png.px[3 * t + c] = mx[c] > 0.0 ? (float)(lin.px[3 * t + c] / mx[c]) : 0.0f;
    json_object_set_new(root, "spatial_png_scale", json_pack("[f,f,f]", mx[0], mx[1], mx[2]));
    rc = dir ? img_write_pair(dir, "spatial", &lin, &png, err) : 0;
done:
    img_free(&lin);
    img_free(&png);
    return rc;
}

static json_t *hf4_summary(const void *data)
{
    const hf4_factors *f = data;
    return json_pack("{s:i, s:i}", "res", f->res, "s_res", f->sres);
}

/* The texture: width max(res, s_res), rows 0-2 log p, q, r, rows 3 ..
 * 3 + s_res - 1 log s (node (i, j) at row 3 + j, column i). */
static int hf4_gpu(const void *data, material_gpu *g, glint_err *err)
{
    const hf4_factors *f = data;
    int R = f->res, S = f->sres, W = R > S ? R : S, H = 3 + S, rc;

    if ((rc = hfx_gpu_begin(g, "hf4", hf4_glsl_frag, W, H, err)))
        return rc;
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < R; k++)
            for (int c = 0; c < 3; c++)
                g->tex[((size_t)j * W + k) * 3 + c] = (float)f->logf[(j * R + k) * 3 + c];
    for (int jj = 0; jj < S; jj++)
        for (int ii = 0; ii < S; ii++)
            for (int c = 0; c < 3; c++)
                g->tex[((size_t)(3 + jj) * W + ii) * 3 + c] =
                    (float)f->logs[((size_t)jj * S + ii) * 3 + c];
    g->nuniforms = 5;
    g->uniform[0] = (material_gpu_uniform){"u_res", "int", {R, 0, 0}, "texels per 1D factor"};
    g->uniform[1] = (material_gpu_uniform){"u_sres", "int", {S, 0, 0},
                                           "nodes per side of the spatial factor"};
    hfx_gpu_mapping(&g->uniform[2], &f->map, f->a_used, f->model);
    g->manifest = json_pack("{s:s, s:i, s:i}", "texture_layout",
                            "u_factors: RGB float, width max(res, s_res); rows 0-2 log p, q, "
                            "r (node texels); rows 3 .. 3 + s_res - 1 log s, node (i, j) at "
                            "row 3 + j, column i",
                            "res", R, "s_res", S);
    if (!g->manifest) {
        material_gpu_free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    return 0;
}

const material_ops hf4_material_ops = {
    .eval = hf4_eval_op,
    .free = hf4_free_op,
    .to_json = hf4_to_json,
    .from_json = hf4_from_json,
    .save_files = hf4_save_files,
    .derived_files = hf4_derived_files,
    .gpu = hf4_gpu,
    .summary = hf4_summary,
    .spatial = 1,
};
