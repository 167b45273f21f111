/* method_srbf_material.c: operations on srbf materials (method_srbf.h):
 * evaluation, manifest members and GPU binding (the fragment stage:
 * method_srbf_glsl.c).
 *
 * Manifest members: "basis": {"res", "J", "sigma", "lambda", "layout":
 * "hemicube"}, "static": {"term", "f0", "alpha"}, "diffuse": [r, g, b],
 * "lobes": [[c_r, c_g, c_b], ...] (J entries, centre order of srbf.h),
 * "centres": [[x, y, z], ...] (the J unit centres in the local frame, for
 * readers; ignored when read back: the basis defines them),
 * "frame": the shading frame's convention. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "method_srbf.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

int srbf_material_init(material *m, srbf_material *sm, json_t *info, glint_err *err)
{
    srbf_material *d = malloc(sizeof *d);
    if (!d) {
        free(sm->c);
        srbf_basis_free(&sm->b);
        memset(sm, 0, sizeof *sm);
        json_decref(info);
        material_init(m, NULL, NULL, NULL);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory making the material");
    }
    *d = *sm;
    d->ptab = NULL;
    d->ptab_n = 0;
    memset(sm, 0, sizeof *sm);
    material_init(m, &method_srbf, d, info);
    return 0;
}

const srbf_material *srbf_material_of(const material *m)
{
    return m && m->method == &method_srbf ? m->data : NULL;
}

static void to_local(const double n[3], const double v[3], double out[3])
{
    double t[3], b[3];
    srbf_frame(n, t, b);
    out[0] = t[0] * v[0] + t[1] * v[1] + t[2] * v[2];
    out[1] = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
    out[2] = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
}

void srbf_material_eval(const srbf_material *sm, const double n[3], const double wi[3],
                        const double wo[3], double rgb[3])
{
    double li[3], lo[3], h[3], hl, s, p[3];
    to_local(n, wi, li);
    to_local(n, wo, lo);
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(li[2] > 0.0) || !(lo[2] > 0.0))
        return;
    for (int e = 0; e < 3; e++)
        h[e] = li[e] + lo[e];
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    if (hl > 0.0)
        for (int e = 0; e < 3; e++)
            h[e] /= hl;
    s = srbf_static_eval(&sm->st, li, lo);
    srbf_p(&sm->b, sm->c, h, p);
    for (int c = 0; c < 3; c++)
        rgb[c] = sm->rho[c] / M_PI + p[c] * s;
}

void srbf_material_albedo(const srbf_material *sm, const double wo[3], int nq, double rgb[3])
{
    srbf_albedo(&sm->b, &sm->st, sm->c, wo, nq, rgb);
    for (int c = 0; c < 3; c++)
        rgb[c] += sm->rho[c];
}

/* The method interface's evaluation is radiance per unit light: f (n.wi). */
static void srbf_eval_op(const void *data, const double uv[2], const double n[3],
                         const double wi[3], const double wo[3], double rgb[3])
{
    (void)uv;
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    srbf_material_eval(data, n, wi, wo, rgb);
    for (int c = 0; c < 3; c++)
        rgb[c] *= ci > 0.0 ? ci : 0.0;
}

static void srbf_preview_op(const void *data, const double uv[2], const double n[3],
                            const double wi[3], const double wo[3], double rgb[3])
{
    (void)uv;
    srbf_material_eval_preview(data, n, wi, wo, rgb);
}

static void srbf_free_op(void *data)
{
    srbf_material *sm = data;
    free(sm->ptab);
    free(sm->c);
    srbf_basis_free(&sm->b);
    free(sm);
}

static const char *static_name(srbf_static_kind k)
{
    return k == SRBF_STATIC_SMITH ? "smith" : "paper";
}

static int srbf_to_json(const void *data, json_t *root, glint_err *err)
{
    const srbf_material *sm = data;
    json_t *lobes = json_array(), *centres = json_array();
    if (!lobes || !centres) {
        json_decref(lobes);
        json_decref(centres);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the manifest");
    }
    for (int j = 0; j < sm->b.J; j++) {
        json_array_append_new(lobes, json_pack("[f,f,f]", sm->c[j], sm->c[sm->b.J + j],
                                               sm->c[2 * sm->b.J + j]));
        json_array_append_new(centres, json_pack("[f,f,f]", sm->b.xi[3 * j], sm->b.xi[3 * j + 1],
                                                 sm->b.xi[3 * j + 2]));
    }
    json_object_set_new(root, "basis",
                        json_pack("{s:i, s:i, s:f, s:f, s:s}", "res", sm->b.res, "J", sm->b.J,
                                  "sigma", sm->b.sigma, "lambda", sm->b.lambda, "layout",
                                  "hemicube"));
    json_object_set_new(root, "static",
                        json_pack("{s:s, s:f, s:f}", "term", static_name(sm->st.kind), "f0",
                                  sm->st.f0, "alpha", sm->st.alpha));
    json_object_set_new(root, "diffuse", json_pack("[f,f,f]", sm->rho[0], sm->rho[1], sm->rho[2]));
    json_object_set_new(root, "lobes", lobes);
    json_object_set_new(root, "centres", centres); /* informative: from_json rebuilds them */
    json_object_set_new(root, "frame",
                        json_string("t = normalize(+z x n) (at the poles normalize(+x x n)), "
                                    "b = n x t; centres and h in (t, b, n)"));
    return 0;
}

static int num(const json_t *v, double lo, double hi, double *out)
{
    if (!json_is_number(v))
        return -1;
    *out = json_number_value(v);
    return isfinite(*out) && *out >= lo && *out <= hi ? 0 : -1;
}

static int srbf_from_json(const json_t *root, const char *file, void **data, glint_err *err)
{
    const json_t *basis = json_object_get(root, "basis"), *st = json_object_get(root, "static");
    const json_t *diff = json_object_get(root, "diffuse"), *lobes = json_object_get(root, "lobes");
    const json_t *term;
    srbf_material *sm = calloc(1, sizeof *sm);
    double res, sigma;
    int rc;

    if (!sm)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (!json_is_object(basis) || num(json_object_get(basis, "res"), SRBF_MIN_RES, SRBF_MAX_RES,
                                      &res) ||
        num(json_object_get(basis, "sigma"), SRBF_MIN_SIGMA, SRBF_MAX_SIGMA, &sigma)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: basis needs res (%d..%d) and sigma", file,
                           SRBF_MIN_RES, SRBF_MAX_RES);
        goto fail;
    }
    if ((rc = srbf_basis_make((int)res, sigma, &sm->b, err)))
        goto fail;
    term = json_object_get(st, "term");
    if (!json_is_object(st) || !json_is_string(term) ||
        (strcmp(json_string_value(term), "paper") && strcmp(json_string_value(term), "smith")) ||
        num(json_object_get(st, "f0"), 0.0, 1.0, &sm->st.f0) ||
        num(json_object_get(st, "alpha"), 0.0, 1.0, &sm->st.alpha)) {
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: static needs term (paper or smith), f0 and alpha in [0, 1]", file);
        goto fail;
    }
    sm->st.kind = strcmp(json_string_value(term), "smith") ? SRBF_STATIC_PAPER : SRBF_STATIC_SMITH;
    if (!json_is_array(diff) || json_array_size(diff) != 3) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: diffuse must be [r, g, b]", file);
        goto fail;
    }
    /* either sign: constraints none fits negative values (method_srbf.h) */
    for (int c = 0; c < 3; c++)
        if (num(json_array_get(diff, c), -SRBF_MAX_WEIGHT, SRBF_MAX_WEIGHT, &sm->rho[c])) {
            rc = glint_err_set(err, GLINT_EFORMAT,
                               "%s: diffuse[%d] must be a finite number within +-%g", file, c,
                               SRBF_MAX_WEIGHT);
            goto fail;
        }
    if (!json_is_array(lobes) || (int)json_array_size(lobes) != sm->b.J) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: lobes must hold %d [r, g, b] entries", file,
                           sm->b.J);
        goto fail;
    }
    if (!(sm->c = malloc((size_t)3 * sm->b.J * sizeof *sm->c))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto fail;
    }
    for (int j = 0; j < sm->b.J; j++) {
        const json_t *e = json_array_get(lobes, j);
        for (int c = 0; c < 3; c++)
            if (!json_is_array(e) || json_array_size(e) != 3 ||
                num(json_array_get(e, c), -SRBF_MAX_WEIGHT, SRBF_MAX_WEIGHT,
                    &sm->c[(size_t)c * sm->b.J + j])) {
                rc = glint_err_set(err, GLINT_EFORMAT,
                                   "%s: lobes[%d] must be three finite numbers within +-%g",
                                   file, j, SRBF_MAX_WEIGHT);
                goto fail;
            }
    }
    *data = sm;
    return 0;
fail:
    srbf_free_op(sm);
    return rc;
}

static int srbf_save_files(const void *data, const char *dir, json_t *manifest, glint_err *err)
{
    (void)data;
    (void)dir;
    (void)manifest;
    (void)err;
    return 0; /* everything is in material.json */
}

/* The GPU form: the lobes in a J x 2 RGB float texture (row 0: centres,
 * row 1: weights per channel). */
static int srbf_gpu(const void *data, material_gpu *out, glint_err *err)
{
    const srbf_material *sm = data;
    int J = sm->b.J;
    memset(out, 0, sizeof *out);
    out->program = "srbf";
    out->frag_src = srbf_glsl_frag;
    out->tex_uniform = "u_lobes";
    out->tex_w = J;
    out->tex_h = 2;
    if (!(out->tex = malloc((size_t)J * 2 * 3 * sizeof *out->tex)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int j = 0; j < J; j++)
        for (int c = 0; c < 3; c++) {
            out->tex[3 * j + c] = (float)sm->b.xi[3 * j + c];
            out->tex[3 * (J + j) + c] = (float)sm->c[(size_t)c * J + j];
        }
    out->nuniforms = 6;
    out->uniform[0] = (material_gpu_uniform){"u_lobes_n", "int", {J, 0, 0}, "lobes J"};
    out->uniform[1] = (material_gpu_uniform){"u_lambda", "float", {sm->b.lambda, 0, 0},
                                             "sharpness of each lobe exp(lambda (h.xi - 1))"};
    out->uniform[2] = (material_gpu_uniform){"u_rho", "vec3",
                                             {sm->rho[0], sm->rho[1], sm->rho[2]},
                                             "diffuse albedo (the BRDF's diffuse part is rho/pi)"};
    out->uniform[3] = (material_gpu_uniform){"u_static", "int", {sm->st.kind, 0, 0},
                                             "0: F/(a+b-ab); 1: F G2/(4ab) (Smith-GGX)"};
    out->uniform[4] = (material_gpu_uniform){"u_f0", "float", {sm->st.f0, 0, 0},
                                             "Schlick's F0"};
    out->uniform[5] = (material_gpu_uniform){"u_alpha", "float", {sm->st.alpha, 0, 0},
                                             "GGX roughness of the Smith term"};
    out->manifest = json_pack("{s:s, s:i}", "texture_layout",
                              "u_lobes: width J, height 2, RGB float; row 0 the lobe centres "
                              "in the local frame, row 1 the weights per channel",
                              "lobes", J);
    return 0;
}

/* weights_negative and a negative diffuse say what constraints none made:
 * a BRDF that is negative in places (the exports clamp it to 0 there and
 * say so, merl.h). */
static json_t *srbf_summary(const void *data)
{
    const srbf_material *sm = data;
    int used = 0, negative = 0;
    for (int j = 0; j < 3 * sm->b.J; j++) {
        used += sm->c[j] > 0.0;
        negative += sm->c[j] < 0.0;
    }
    return json_pack("{s:i, s:f, s:[f,f,f], s:s, s:i, s:i}", "lobes", sm->b.J, "sigma",
                     sm->b.sigma, "diffuse", sm->rho[0], sm->rho[1], sm->rho[2], "static",
                     static_name(sm->st.kind), "weights_nonzero", used, "weights_negative",
                     negative);
}

const material_ops srbf_material_ops = {
    .eval = srbf_eval_op,
    .eval_preview = srbf_preview_op,
    .free = srbf_free_op,
    .to_json = srbf_to_json,
    .from_json = srbf_from_json,
    .save_files = srbf_save_files,
    .gpu = srbf_gpu,
    .summary = srbf_summary,
};
