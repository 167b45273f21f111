/* method_pbr_detail_material.c: operations on pbr_detail materials
 * (method_pbr_detail.h): evaluation (f_base times the detail, which holds
 * ci), the manifest (the base's members under "base", the detail's under
 * "detail", each read back and validated by its own method), the detail's
 * factor files, the summary and the GPU's fragment stage, which multiplies
 * the two as the CPU does. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "glsl_parts.h"
#include "method_pbr_detail.h"

const pbr_detail_material *pbr_detail_material_of(const material *m)
{
    return m && m->method == &method_pbr_detail ? m->data : NULL;
}

static void pbr_detail_free(void *data)
{
    pbr_detail_material *x = data;
    if (x)
        hf_factors_free(&x->detail);
    free(x);
}

int pbr_detail_material_init(material *m, const pbr_material *base, hf_factors *detail,
                             const double weight[3], json_t *info, glint_err *err)
{
    pbr_detail_material *x = malloc(sizeof *x);
    if (!x) {
        hf_factors_free(detail);
        memset(detail, 0, sizeof *detail);
        json_decref(info);
        material_init(m, NULL, NULL, NULL);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory making the material");
    }
    x->base = *base;
    x->detail = *detail;
    memcpy(x->weight, weight, sizeof x->weight);
    memset(detail, 0, sizeof *detail);
    material_init(m, &method_pbr_detail, x, info);
    return 0;
}

void pbr_detail_base_brdf(const pbr_material *pm, const double n[3], const double wi[3],
                          const double wo[3], double f[3])
{
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    double co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    double h[3], hl;
    f[0] = f[1] = f[2] = 0.0;
    if (!(ci > 0.0) || !(co > 0.0))
        return;
    for (int e = 0; e < 3; e++)
        h[e] = wi[e] + wo[e];
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    if (!(hl > 0.0))
        return;
    pbr_brdf(pm->kd, pm->lobe, pm->sp.nlobes, ci, co,
             (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl,
             (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl, f);
}

static void pbr_detail_eval(const void *data, const double uv[2], const double n[3],
                            const double wi[3], const double wo[3], double rgb[3])
{
    const pbr_detail_material *x = data;
    double f[3], d[3], ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    (void)uv;
    pbr_detail_base_brdf(&x->base, n, wi, wo, f);
    hf_factors_eval(&x->detail, n, wi, wo, d);
    for (int c = 0; c < 3; c++)
        rgb[c] = f[c] * (ci + x->weight[c] * (d[c] - ci));
}

/* ---- the manifest ------------------------------------------------------------------------ */

static int pbr_detail_to_json(const void *data, json_t *root, glint_err *err)
{
    const pbr_detail_material *x = data;
    json_t *b = json_object(), *d = json_object();
    int rc;
    if (!b || !d) {
        json_decref(b);
        json_decref(d);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the manifest");
    }
    json_object_set_new(root, "base", b);
    json_object_set_new(root, "detail", d);
    if ((rc = method_pbr.mat->to_json(&x->base, b, err)) ||
        (rc = method_hf3.mat->to_json(&x->detail, d, err)))
        return rc;
    json_object_set_new(root, "detail_weight",
                        json_pack("[f, f, f]", x->weight[0], x->weight[1], x->weight[2]));
    json_object_set_new(root, "product",
                        json_string("f_base(wi, wo) (no cosine) times ci + detail_weight "
                                    "(detail(wi, wo) - ci), the detail with its cosine: "
                                    "radiance per unit light"));
    return 0;
}

/* One part's members, read by its method (OUT: *data, that method's data). */
static int read_part(const json_t *root, const char *file, const char *key, const method *m,
                     void **data, glint_err *err)
{
    const json_t *o = json_object_get(root, key);
    char where[512];
    if (!json_is_object(o))
        return glint_err_set(err, GLINT_EFORMAT, "%s: %s must be an object", file, key);
    snprintf(where, sizeof where, "%s (%s)", file, key);
    return m->mat->from_json(o, where, data, err);
}

/* detail_weight: three numbers in [0, 1] (OUT w[3]). */
static int read_weight(const json_t *a, const char *file, double w[3], glint_err *err)
{
    if (!json_is_array(a) || json_array_size(a) != 3)
        return glint_err_set(err, GLINT_EFORMAT, "%s: detail_weight must be [r, g, b]", file);
    for (int c = 0; c < 3; c++) {
        const json_t *v = json_array_get(a, (size_t)c);
        w[c] = json_number_value(v);
        if (!json_is_number(v) || !(w[c] >= 0.0 && w[c] <= 1.0))
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s: detail_weight[%d] must be a number in [0, 1]", file, c);
    }
    return 0;
}

static int pbr_detail_from_json(const json_t *root, const char *file, void **data,
                                glint_err *err)
{
    void *b = NULL, *d = NULL;
    double weight[3];
    pbr_detail_material *x;
    int rc;

    *data = NULL;
    if ((rc = read_weight(json_object_get(root, "detail_weight"), file, weight, err)) ||
        (rc = read_part(root, file, "base", &method_pbr, &b, err)) ||
        (rc = read_part(root, file, "detail", &method_hf3, &d, err)))
        goto fail;
    if (!(x = malloc(sizeof *x))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto fail;
    }
    x->base = *(pbr_material *)b;
    x->detail = *(hf_factors *)d;
    memcpy(x->weight, weight, sizeof x->weight);
    free(b);
    free(d); /* its arrays moved into x */
    *data = x;
    return 0;
fail:
    if (b)
        method_pbr.mat->free(b);
    if (d)
        method_hf3.mat->free(d);
    return rc;
}

/* The detail's factor files (factors.exr, factors.png), its png_scale under
 * "detail". */
static int pbr_detail_save_files(const void *data, const char *dir, json_t *root,
                                 glint_err *err)
{
    const pbr_detail_material *x = data;
    json_t *d = json_object_get(root, "detail");
    if (!json_is_object(d))
        return glint_err_set(err, GLINT_EINTERNAL, "manifest without its detail");
    return method_hf3.mat->save_files(&x->detail, dir, d, err);
}

static const char *const pbr_detail_derived_files[] = {"factors.exr", "factors.png", NULL};

/* The base's physical numbers (pbr's summary) and a word on the detail. */
static json_t *pbr_detail_summary(const void *data)
{
    const pbr_detail_material *x = data;
    json_t *s = method_pbr.mat->summary(&x->base);
    if (!s)
        return NULL;
    json_object_set_new(s, "diffuse",
                        json_pack("[f, f, f]", x->base.kd[0], x->base.kd[1], x->base.kd[2]));
    json_object_set_new(s, "detail", json_string("three factors of the ratio to the base"));
    json_object_set_new(s, "detail_res", json_integer(x->detail.res));
    json_object_set_new(s, "detail_weight",
                        json_pack("[f, f, f]", x->weight[0], x->weight[1], x->weight[2]));
    return s;
}

/* ---- the GPU -------------------------------------------------------------------------- */

static const char frag[] =
    "#version 300 es\n"
    "// glint_material.frag: a glint material, a physically based BRDF (kd/pi plus up to\n"
    "// two GGX lobes, height-correlated Smith, Schlick Fresnel) times a detail of three\n"
    "// 1D factors (GLSL ES 3.00).  Pair it with glint_material.vert.\n"
    "//\n"
    "// value = f_base(wi, wo) * (ci + w (detail(wi, wo) - ci)): f_base without the\n"
    "// cosine, w the detail's weight per channel, detail =\n"
    "// inverse_map(p(pi_p) q(pi_q) r(pi_r)) (times n.wi for the brdf model), pi_p,\n"
    "// pi_q, pi_r the lengths of wi, h and wo projected on the tangent plane.\n"
    "// Output: linear radiance for a point light of intensity u_light_intensity;\n"
    "// 0 unless n.wi > 0 and n.wo > 0.  Binding contract in shader.json: u_factors\n"
    "// holds the detail's LOG-factors (width res, height 3; rows p, q, r; node\n"
    "// convention, fetched with texelFetch), the other uniforms as listed there.\n"
    GLSL_PRECISION
    "uniform highp sampler2D u_factors;\n"
    "uniform int u_res;\n"
    "uniform int u_map_kind;\n"
    "uniform vec3 u_a;\n"
    "uniform int u_model_brdf;\n"
    "uniform vec3 u_kd;\n"
    "uniform float u_alpha1;\n"
    "uniform vec3 u_ks1;\n"
    "uniform vec3 u_f01;\n"
    "uniform float u_alpha2;\n"
    "uniform vec3 u_ks2;\n"
    "uniform vec3 u_f02;\n"
    "uniform vec3 u_detail_weight;\n"
    GLSL_STAGE_IO
    "const float PI = 3.14159265358979323846;\n"
    GLSL_UNIT
    GLSL_TANGENT_LEN
    GLSL_FACTOR("u_factors")
    GLSL_PBR_LOBE
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    GLSL_PBR_ANGLES
    "    vec3 f = u_kd / PI + pbr_lobe(u_alpha1, u_ks1, u_f01, ci, co, ch, w5) +\n"
    "             pbr_lobe(u_alpha2, u_ks2, u_f02, ci, co, ch, w5);\n"
    "    vec3 s = glint_factor(0, glint_tangent_len(wi, n)) +\n"
    "             glint_factor(1, glint_tangent_len(h, n)) +\n"
    "             glint_factor(2, glint_tangent_len(wo, n));\n"
    "    vec3 prod = exp(min(s, vec3(88.0))); // bounded: stays finite in float\n"
    "    vec3 v = u_map_kind == 1 ? prod - u_a : (u_map_kind == 2 ? u_a - prod : prod);\n"
    "    v = max(v, vec3(0.0));\n"
    "    vec3 d = u_model_brdf == 1 ? v * ci : v;\n"
    "    return f * (ci + u_detail_weight * (d - ci));\n"
    "}\n"
    "\n"
    GLSL_MAIN;

static void add_uniform(material_gpu *g, const char *name, const char *type, const double v[3],
                        const char *meaning)
{
    material_gpu_uniform *u = &g->uniform[g->nuniforms++];
    u->name = name;
    u->type = type;
    u->v[0] = v[0];
    u->v[1] = v[1];
    u->v[2] = v[2];
    u->meaning = meaning;
}

/* The base's uniforms, after the detail's. */
static void base_uniforms(const pbr_material *pm, material_gpu *g)
{
    static const pbr_lobe none = {1.0, {0, 0, 0}, {0, 0, 0}};
    const pbr_lobe *l1 = &pm->lobe[0], *l2 = pm->sp.nlobes > 1 ? &pm->lobe[1] : &none;
    double a1[3] = {l1->alpha, 0, 0}, a2[3] = {l2->alpha, 0, 0};
    add_uniform(g, "u_kd", "vec3", pm->kd, "the base's diffuse albedo per channel");
    add_uniform(g, "u_alpha1", "float", a1, "GGX roughness of the base's first lobe");
    add_uniform(g, "u_ks1", "vec3", l1->ks, "weight of the first lobe per channel");
    add_uniform(g, "u_f01", "vec3", l1->f0, "Fresnel reflectance at normal incidence, first lobe");
    add_uniform(g, "u_alpha2", "float", a2, "GGX roughness of the base's second lobe");
    add_uniform(g, "u_ks2", "vec3", l2->ks, "weight of the second lobe per channel (0: none)");
    add_uniform(g, "u_f02", "vec3", l2->f0,
                "Fresnel reflectance at normal incidence, second lobe");
}

/* The detail's binding as hf3 makes it (texture, its four uniforms, its
 * manifest under "detail"), the base's uniforms and members added. */
static int pbr_detail_gpu(const void *data, material_gpu *g, glint_err *err)
{
    const pbr_detail_material *x = data;
    json_t *root, *b;
    int rc;

    if ((rc = method_hf3.mat->gpu(&x->detail, g, err)))
        return rc;
    if (g->nuniforms + 8 > MATERIAL_GPU_MAX_UNIFORMS) {
        material_gpu_free(g);
        return glint_err_set(err, GLINT_EINTERNAL, "too many uniforms for the GPU binding");
    }
    g->program = "pbr_detail";
    g->frag_src = frag;
    base_uniforms(&x->base, g);
    add_uniform(g, "u_detail_weight", "vec3", x->weight,
                "the detail's weight per channel (0: the base alone)");
    root = json_object();
    b = json_object();
    if (!root || !b || method_pbr.mat->to_json(&x->base, b, err)) {
        json_decref(root);
        json_decref(b);
        material_gpu_free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    json_object_set_new(root, "base", b);
    json_object_set_new(root, "detail", g->manifest);
    json_object_set_new(root, "product",
                        json_string("f_base (no cosine, uniforms u_kd .. u_f02) times "
                                    "ci + u_detail_weight (detail - ci), the detail from the "
                                    "texture u_factors with u_res, u_map_kind, u_a, "
                                    "u_model_brdf"));
    g->manifest = root;
    return 0;
}

const material_ops pbr_detail_material_ops = {
    .eval = pbr_detail_eval,
    .free = pbr_detail_free,
    .to_json = pbr_detail_to_json,
    .from_json = pbr_detail_from_json,
    .save_files = pbr_detail_save_files,
    .derived_files = pbr_detail_derived_files,
    .gpu = pbr_detail_gpu,
    .summary = pbr_detail_summary,
};
