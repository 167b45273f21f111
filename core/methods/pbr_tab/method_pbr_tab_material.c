/* method_pbr_tab_material.c: operations on pbr_tab materials
 * (method_pbr_tab.h): evaluation (pbr's value with the table's bilinear
 * lookup added or multiplied, a negative result read as 0), the manifest
 * (the base's members under "base", the table's under "table", each read
 * back and validated by its own method, and "combine"), the summary and
 * the GPU's fragment stage, which combines the two as the CPU does. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "glsl_parts.h"
#include "method_pbr_tab.h"

static const char *const combine_names[] = {"add", "multiply"};

const pbr_tab_material *pbr_tab_material_of(const material *m)
{
    return m && m->method && m->method->mat == &pbr_tab_material_ops ? m->data : NULL;
}

static void pbr_tab_free(void *data)
{
    pbr_tab_material *x = data;
    if (x)
        free(x->table.t);
    free(x);
}

int pbr_tab_material_init(material *m, const pbr_material *base, tab_material *table,
                          int combine, json_t *info, glint_err *err)
{
    pbr_tab_material *x = malloc(sizeof *x);
    if (!x) {
        free(table->t);
        table->t = NULL;
        json_decref(info);
        material_init(m, NULL, NULL, NULL);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory making the material");
    }
    x->base = *base;
    x->table = *table;
    x->combine = combine;
    table->t = NULL;
    material_init(m, &method_pbr_tab, x, info);
    return 0;
}

static void pbr_tab_eval(const void *data, const double uv[2], const double n[3],
                         const double wi[3], const double wo[3], double rgb[3])
{
    const pbr_tab_material *x = data;
    double ch, cd, r[3], ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    double co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(ci > 0.0) || !(co > 0.0) || tab_angles(n, wi, wo, &ch, &cd))
        return;
    pbr_material_ops.eval(&x->base, uv, n, wi, wo, rgb); /* f_base ci */
    tab_lookup(&x->table.g, x->table.t, ch, cd, r);
    for (int c = 0; c < 3; c++)
        rgb[c] = x->combine == PBR_TAB_MULTIPLY ? rgb[c] * fmax(r[c], 0.0)
                                                : fmax(rgb[c] + r[c] * ci, 0.0);
}

/* ---- the manifest ------------------------------------------------------------------------ */

static int pbr_tab_to_json(const void *data, json_t *root, glint_err *err)
{
    const pbr_tab_material *x = data;
    json_t *b = json_object(), *r = json_object();
    int rc;
    if (!b || !r) {
        json_decref(b);
        json_decref(r);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the manifest");
    }
    json_object_set_new(root, "base", b);
    json_object_set_new(root, "table", r);
    if ((rc = pbr_material_ops.to_json(&x->base, b, err)) ||
        (rc = tab_material_ops.to_json(&x->table, r, err)))
        return rc;
    json_object_set_new(root, "combine", json_string(combine_names[x->combine]));
    json_object_set_new(root, "product",
                        json_string(x->combine == PBR_TAB_MULTIPLY
                                        ? "f_base(wi, wo) ci (the base's value) times the "
                                          "table at (theta_h, theta_d): radiance per unit "
                                          "light"
                                        : "max(f_base(wi, wo) + table(theta_h, theta_d), 0) "
                                          "ci: radiance per unit light"));
    return 0;
}

/* One part's members, read by its method's operations (OUT: *data). */
static int read_part(const json_t *root, const char *file, const char *key,
                     const material_ops *ops, void **data, glint_err *err)
{
    const json_t *o = json_object_get(root, key);
    char where[512];
    if (!json_is_object(o))
        return glint_err_set(err, GLINT_EFORMAT, "%s: %s must be an object", file, key);
    snprintf(where, sizeof where, "%s (%s)", file, key);
    return ops->from_json(o, where, data, err);
}

static int pbr_tab_from_json(const json_t *root, const char *file, void **data, glint_err *err)
{
    void *b = NULL, *r = NULL;
    const char *comb = json_string_value(json_object_get(root, "combine"));
    pbr_tab_material *x;
    int rc, combine = -1;

    *data = NULL;
    for (int k = 0; comb && k < 2; k++)
        if (!strcmp(comb, combine_names[k]))
            combine = k;
    if (combine < 0)
        return glint_err_set(err, GLINT_EFORMAT, "%s: combine must be \"add\" or \"multiply\"",
                             file);
    if ((rc = read_part(root, file, "base", &pbr_material_ops, &b, err)) ||
        (rc = read_part(root, file, "table", &tab_material_ops, &r, err)))
        goto fail;
    if (!(x = malloc(sizeof *x))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto fail;
    }
    x->base = *(pbr_material *)b;
    x->table = *(tab_material *)r;
    x->combine = combine;
    free(b);
    free(r); /* its table moved into x */
    *data = x;
    return 0;
fail:
    if (b)
        pbr_material_ops.free(b);
    if (r)
        tab_material_ops.free(r);
    return rc;
}

/* The base's physical numbers (pbr's summary), its diffuse colour and the
 * table's range at the table's nodes. */
static json_t *pbr_tab_summary(const void *data)
{
    const pbr_tab_material *x = data;
    json_t *s = pbr_material_ops.summary(&x->base);
    int nodes = tab_nodes(&x->table.g);
    double lo = INFINITY, hi = -INFINITY;
    if (!s)
        return NULL;
    for (size_t k = 0; k < 3 * (size_t)nodes; k++) {
        lo = fmin(lo, x->table.t[k]);
        hi = fmax(hi, x->table.t[k]);
    }
    json_object_set_new(s, "diffuse",
                        json_pack("[f, f, f]", x->base.kd[0], x->base.kd[1], x->base.kd[2]));
    json_object_set_new(s, "detail",
                        json_string(x->combine == PBR_TAB_MULTIPLY
                                        ? "a table of the table to the base over the half "
                                          "and difference angles"
                                        : "a table added to the base over the half and "
                                          "difference angles"));
    json_object_set_new(s, "detail_range", json_pack("[f, f]", lo, hi));
    return s;
}

/* ---- the GPU -------------------------------------------------------------------------- */

static const char frag[] =
    "#version 300 es\n"
    "// glint_material.frag: a glint material, a physically based BRDF (kd/pi plus up to\n"
    "// two GGX lobes, height-correlated Smith, Schlick Fresnel) times a table table over\n"
    "// the half and difference angles (GLSL ES 3.00).  Pair it with glint_material.vert.\n"
    "//\n"
    "// value = max(f_base(wi, wo) + r(theta_h, theta_d), 0) ci (u_combine 0), or\n"
    "// f_base(wi, wo) ci max(r, 0) (u_combine 1): r bilinear on the texture u_table\n"
    "// (texel (i, j) the node at u = sqrt(theta_h / (pi/2)) = i / (res_h - 1),\n"
    "// v = theta_d / (pi/2) = j / (res_d - 1), fetched with texelFetch).  Output: linear radiance for a point light of intensity\n"
    "// u_light_intensity; 0 unless n.wi > 0 and n.wo > 0.\n"
    GLSL_PRECISION
    "uniform highp sampler2D u_table;\n"
    "uniform int u_res_h;\n"
    "uniform int u_res_d;\n"
    "uniform vec3 u_kd;\n"
    "uniform float u_alpha1;\n"
    "uniform vec3 u_ks1;\n"
    "uniform vec3 u_f01;\n"
    "uniform float u_alpha2;\n"
    "uniform vec3 u_ks2;\n"
    "uniform vec3 u_f02;\n"
    "uniform int u_combine;\n"
    GLSL_STAGE_IO
    "const float PI = 3.14159265358979323846;\n"
    "const float HALF_PI = 1.57079632679489662;\n"
    GLSL_UNIT
    GLSL_TAB_LOOKUP
    GLSL_PBR_LOBE
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    GLSL_PBR_ANGLES
    "    vec3 f = u_kd / PI + pbr_lobe(u_alpha1, u_ks1, u_f01, ci, co, ch, w5) +\n"
    "             pbr_lobe(u_alpha2, u_ks2, u_f02, ci, co, ch, w5);\n"
    "    float th = acos(clamp(ch, -1.0, 1.0)), td = acos(clamp(cd, -1.0, 1.0));\n"
    "    vec3 r = tab_lookup(sqrt(th / HALF_PI), td / HALF_PI);\n"
    "    return u_combine == 1 ? f * ci * max(r, vec3(0.0)) : max(f + r, vec3(0.0)) * ci;\n"
    "}\n"
    "\n"
    GLSL_MAIN;

/* The table's binding as tab makes it (texture, its two uniforms), the
 * base's uniforms as pbr makes them, and both manifests. */
static int pbr_tab_gpu(const void *data, material_gpu *g, glint_err *err)
{
    const pbr_tab_material *x = data;
    material_gpu pg;
    json_t *root;
    int rc;

    if ((rc = tab_material_ops.gpu(&x->table, g, err)))
        return rc;
    if ((rc = pbr_material_ops.gpu(&x->base, &pg, err))) {
        material_gpu_free(g);
        return rc;
    }
    if (g->nuniforms + pg.nuniforms + 1 > MATERIAL_GPU_MAX_UNIFORMS || !(root = json_object())) {
        material_gpu_free(g);
        material_gpu_free(&pg);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (GPU binding)");
    }
    for (int k = 0; k < pg.nuniforms; k++)
        g->uniform[g->nuniforms++] = pg.uniform[k];
    g->uniform[g->nuniforms++] = (material_gpu_uniform){
        "u_combine", "int", {x->combine, 0, 0}, "0: the table is added to f_base, 1: it scales it"};
    g->program = "pbr_tab";
    g->frag_src = frag;
    json_object_set_new(root, "base", json_incref(pg.manifest));
    json_object_set_new(root, "table", g->manifest);
    json_object_set_new(root, "product",
                        json_string("f_base (no cosine, uniforms u_kd .. u_f02) and the table "
                                    "from the texture u_table (u_res_h, u_res_d), added "
                                    "(u_combine 0) or multiplied (1), times ci"));
    g->manifest = root;
    material_gpu_free(&pg);
    return 0;
}

const material_ops pbr_tab_material_ops = {
    .eval = pbr_tab_eval,
    .free = pbr_tab_free,
    .to_json = pbr_tab_to_json,
    .from_json = pbr_tab_from_json,
    .gpu = pbr_tab_gpu,
    .summary = pbr_tab_summary,
};
