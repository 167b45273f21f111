/* method_hf2d_material.c: operations on hf2d materials (method_hf2d.h).
 *
 * material.json members: res, res_2d, dims ([1|2, 1|2, 1|2] for p, q, r),
 * model, mapping, a_used (as hf3), log_nodes {p, q, r}: each factor's log
 * nodes, [r, g, b] per node (a 2D factor's node (i, j) at j res_2d + i),
 * and the conventions in words (frame, parabolic, gauge). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "img.h"
#include "internal/method_hfx_int.h"
#include "method_hf2d.h"

static const char *const factor_names[3] = {"p", "q", "r"};

const hf2d_factors *hf2d_of(const material *m)
{
    return m && m->method == &method_hf2d ? m->data : NULL;
}

static void eval_op(const void *data, const double uv[2], const double n[3], const double wi[3],
                    const double wo[3], double rgb[3])
{
    (void)uv;
    hf2d_factors_eval(data, n, wi, wo, rgb);
}

static void free_op(void *data)
{
    hf2d_factors_free(data);
    free(data);
}

static int to_json(const void *data, json_t *root, glint_err *err)
{
    const hf2d_factors *f = data;
    char mapbuf[96];
    json_t *nodes = json_object(), *a = json_array(), *dims = json_array();

    if (!nodes || !a || !dims) {
        json_decref(nodes);
        json_decref(a);
        json_decref(dims);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the manifest");
    }
    hf_map_format(&f->map, mapbuf, sizeof mapbuf);
    json_object_set_new(root, "res", json_integer(f->sh.res));
    json_object_set_new(root, "res_2d", json_integer(f->sh.sres));
    for (int j = 0; j < 3; j++)
        json_array_append_new(dims, json_integer(f->sh.dims[j]));
    json_object_set_new(root, "dims", dims);
    json_object_set_new(root, "model",
                        json_string(f->model == HF_MODEL_BRDF ? "brdf" : "radiance"));
    json_object_set_new(root, "mapping", json_string(mapbuf));
    for (int c = 0; c < 3; c++)
        json_array_append_new(a, json_real(f->a_used[c]));
    json_object_set_new(root, "a_used", a);
    for (int j = 0; j < 3; j++)
        json_object_set_new(nodes, factor_names[j],
                            hfx_log_nodes_json(f->logy + 3 * (size_t)f->off[j],
                                               f->off[j + 1] - f->off[j]));
    json_object_set_new(root, "log_nodes", nodes);
    json_object_set_new(root, "frame",
                        json_string("t = normalize(Z x n), b = n x t; t = +X where |Z x n| "
                                    "<= 1e-6"));
    json_object_set_new(root, "parabolic",
                        json_string("a 2D factor of unit d: (u, v) = ((d.t, d.b) / (1 + "
                                    "max(d.n, 0)) + 1) / 2, node (i, j) at (i, j) / (res_2d "
                                    "- 1), bilinear; a 1D factor: |d - n (d.n)|, node k at k / "
                                    "(res - 1); d = wi, h, wo for p, q, r"));
    json_object_set_new(root, "gauge", json_string("equal mean log per factor and channel"));
    json_object_set_new(root, "model_formula", json_string("inverse_map(p(wi) q(h) r(wo))"));
    return 0;
}

/* Each factor's log nodes from the manifest's log_nodes into f->logy (its
 * shape set). */
static int nodes_from_json(hf2d_factors *f, const json_t *nodes, const char *file,
                           glint_err *err)
{
    for (int j = 0; j < 3; j++) {
        json_t *rows = json_object_get(nodes, factor_names[j]);
        int cnt = f->off[j + 1] - f->off[j], rc;
        char what[16];
        if (!json_is_array(rows) || json_array_size(rows) != (size_t)cnt)
            return glint_err_set(err, GLINT_EFORMAT, "%s: log_nodes.%s must hold %d nodes",
                                 file, factor_names[j], cnt);
        snprintf(what, sizeof what, "log_nodes.%s", factor_names[j]);
        if ((rc = hfx_log_nodes_get(rows, cnt, f->logy + 3 * (size_t)f->off[j], file, what,
                                    err)))
            return rc;
    }
    return 0;
}

/* The factors' shape from the manifest's res, res_2d and dims (OUT: *sh). */
static int shape_from_json(const json_t *root, const char *file, hf2d_shape *sh,
                           glint_err *err)
{
    json_t *v, *dims;
    v = json_object_get(root, "res");
    sh->res = json_is_integer(v) ? (int)json_integer_value(v) : -1;
    v = json_object_get(root, "res_2d");
    sh->sres = json_is_integer(v) ? (int)json_integer_value(v) : -1;
    dims = json_object_get(root, "dims");
    if (!json_is_array(dims) || json_array_size(dims) != 3)
        return glint_err_set(err, GLINT_EFORMAT, "%s: dims must be an array of 3 integers",
                             file);
    for (int j = 0; j < 3; j++) {
        json_t *d = json_array_get(dims, (size_t)j);
        sh->dims[j] = json_is_integer(d) ? (int)json_integer_value(d) : -1;
    }
    if (hf2d_shape_check(sh, err)) {
        glint_err_prefix(err, "%s", file);
        return GLINT_EFORMAT;
    }
    return 0;
}

static int from_json(const json_t *root, const char *file, void **data, glint_err *err)
{
    hf2d_factors *f;
    const char *model, *mapping;
    json_t *v;
    hf2d_shape sh;
    hf_map map;
    int rc = GLINT_EFORMAT, n;

    *data = NULL;
    if (shape_from_json(root, file, &sh, err))
        return rc;
    model = json_string_value(json_object_get(root, "model"));
    mapping = json_string_value(json_object_get(root, "mapping"));
    if (!model || (strcmp(model, "radiance") != 0 && strcmp(model, "brdf") != 0))
        return glint_err_set(err, rc, "%s: model must be \"radiance\" or \"brdf\"", file);
    if (!mapping)
        return glint_err_set(err, rc, "%s: mapping must be a string", file);
    if (hf_map_parse(mapping, &map, err)) {
        glint_err_prefix(err, "%s: mapping", file);
        return rc;
    }
    if (!(f = calloc(1, sizeof *f)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    f->sh = sh;
    n = hf2d_offsets(&sh, f->off);
    f->model = strcmp(model, "brdf") == 0 ? HF_MODEL_BRDF : HF_MODEL_RADIANCE;
    f->map = map;
    v = json_object_get(root, "a_used");
    for (int c = 0; c < 3; c++) {
        json_t *x = json_array_get(v, (size_t)c);
        f->a_used[c] = json_is_number(x) ? json_number_value(x) : NAN;
        if (!json_is_array(v) || json_array_size(v) != 3 || !isfinite(f->a_used[c])) {
            free_op(f);
            return glint_err_set(err, rc, "%s: a_used must be an array of 3 finite numbers",
                                 file);
        }
    }
    if (!(f->logy = malloc(3 * (size_t)n * sizeof *f->logy))) {
        free_op(f);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    if ((rc = nodes_from_json(f, json_object_get(root, "log_nodes"), file, err))) {
        free_op(f);
        return rc;
    }
    *data = f;
    return 0;
}

/* The texture layout shared by the files and the GPU: width max(res,
 * res_2d); a 1D factor takes one row (node k at column k), a 2D factor
 * res_2d rows (node (i, j) at column i of its first row + j); p, q, r in
 * order.  OUT: row0[3] (each factor's first row), *w, *h. */
static void layout(const hf2d_factors *f, int row0[3], int *w, int *h)
{
    int r = 0;
    for (int j = 0; j < 3; j++) {
        row0[j] = r;
        r += f->sh.dims[j] == 2 ? f->sh.sres : 1;
    }
    *w = f->sh.res > f->sh.sres ? f->sh.res : f->sh.sres;
    *h = r;
}

/* Fill the layout with each log node through fn (OUT: px, RGB). */
static void fill(const hf2d_factors *f, float *px, double (*fn)(double))
{
    int row0[3], W, H, S = f->sh.sres;
    layout(f, row0, &W, &H);
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < f->off[j + 1] - f->off[j]; k++) {
            int x = f->sh.dims[j] == 2 ? k % S : k, y = row0[j] + (f->sh.dims[j] == 2 ? k / S : 0);
            for (int c = 0; c < 3; c++)
                px[((size_t)y * W + x) * 3 + c] =
                    (float)fn(f->logy[3 * (size_t)(f->off[j] + k) + c]);
        }
}

static double ident(double x)
{
    return x;
}

static double expo(double x)
{
    return exp(x > 80.0 ? 80.0 : x);
}

/* factors.exr (linear node values in the layout) and factors.png (each
 * channel over its maximum, png_scale); dir NULL: the manifest's members
 * only.  Both follow from the log nodes in the manifest. */
static int save_files(const void *data, const char *dir, json_t *root, glint_err *err)
{
    const hf2d_factors *f = data;
    int row0[3], W, H, rc;
    img lin = {0}, png = {0};
    double mx[3] = {0, 0, 0};

    layout(f, row0, &W, &H);
    if ((rc = img_alloc(&lin, W, H, 3, err)) || (rc = img_alloc(&png, W, H, 3, err)))
        goto done;
    memset(lin.px, 0, (size_t)W * H * 3 * sizeof *lin.px);
    fill(f, lin.px, expo);
    for (size_t i = 0; i < (size_t)W * H * 3; i++)
        mx[i % 3] = lin.px[i] > mx[i % 3] ? lin.px[i] : mx[i % 3];
    for (size_t i = 0; i < (size_t)W * H * 3; i++)
        png.px[i] = mx[i % 3] > 0.0 ? (float)(lin.px[i] / mx[i % 3]) : 0.0f;
    json_object_set_new(root, "png_scale", json_pack("[f,f,f]", mx[0], mx[1], mx[2]));
    json_object_set_new(root, "factors_layout",
                        json_pack("{s:i, s:i, s:[i,i,i], s:s}", "width", W, "height", H,
                                  "first_row", row0[0], row0[1], row0[2], "nodes",
                                  "1D: node k at column k of its row; 2D: node (i, j) at "
                                  "column i, row first_row + j"));
    rc = dir ? img_write_pair(dir, "factors", &lin, &png, err) : 0;
done:
    img_free(&lin);
    img_free(&png);
    return rc;
}

static const char *const derived_files[] = {"factors.exr", "factors.png", NULL};

static json_t *summary(const void *data)
{
    const hf2d_factors *f = data;
    return json_pack("{s:i, s:i, s:[i,i,i]}", "res", f->sh.res, "res_2d", f->sh.sres, "dims",
                     f->sh.dims[0], f->sh.dims[1], f->sh.dims[2]);
}

static int gpu(const void *data, material_gpu *g, glint_err *err)
{
    const hf2d_factors *f = data;
    int row0[3], W, H, rc;

    layout(f, row0, &W, &H);
    if ((rc = hfx_gpu_begin(g, "hf2d", hf2d_glsl_frag, W, H, err)))
        return rc;
    fill(f, g->tex, ident);
    g->nuniforms = 7;
    g->uniform[0] = (material_gpu_uniform){"u_res", "int", {f->sh.res, 0, 0},
                                           "nodes per 1D factor"};
    g->uniform[1] = (material_gpu_uniform){"u_sres", "int", {f->sh.sres, 0, 0},
                                           "nodes per side of a 2D factor"};
    g->uniform[2] = (material_gpu_uniform){"u_dims", "vec3",
                                           {f->sh.dims[0], f->sh.dims[1], f->sh.dims[2]},
                                           "1 or 2: dimensions of p, q, r"};
    g->uniform[3] = (material_gpu_uniform){"u_rows", "vec3", {row0[0], row0[1], row0[2]},
                                           "first texture row of p, q, r"};
    hfx_gpu_mapping(&g->uniform[4], &f->map, f->a_used, f->model);
    g->manifest = json_pack("{s:s, s:i, s:i}", "texture_layout",
                            "u_factors: RGB float log nodes, width max(res, res_2d); a 1D "
                            "factor one row (node k at column k), a 2D factor res_2d rows "
                            "(node (i, j) at column i, row u_rows + j); p, q, r in order",
                            "res", f->sh.res, "res_2d", f->sh.sres);
    if (!g->manifest) {
        material_gpu_free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    return 0;
}

const material_ops hf2d_material_ops = {
    .eval = eval_op,
    .free = free_op,
    .to_json = to_json,
    .from_json = from_json,
    .save_files = save_files,
    .derived_files = derived_files,
    .gpu = gpu,
    .summary = summary,
    .spatial = 0,
};
