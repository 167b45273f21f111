/* method_tab_material.c: operations on tab materials (method_tab.h):
 * evaluation (the bilinear lookup of tab.h times n.wi, per unit light; 0
 * unless n.wi > 0 and n.wo > 0; a negative interpolant, possible only in a
 * table fitted without the constraint, reads as 0), the manifest's members
 * (the table in material.json at full precision, validated when read), the
 * GPU's fragment stage (the table as one float texture, res_h x res_d,
 * read with texelFetch and interpolated in the shader) and the summary
 * (base_colour: pi times the table at theta_h = theta_d = 0, which reads a
 * Lambertian's albedo). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "glsl_parts.h"
#include "method_tab.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

const tab_material *tab_material_of(const material *m)
{
    return m && m->method && m->method->mat == &tab_material_ops ? m->data : NULL;
}

void tab_material_free(void *data)
{
    tab_material *tm = data;
    if (tm)
        free(tm->t);
    free(tm);
}

static void tab_mat_eval(const void *data, const double uv[2], const double n[3],
                         const double wi[3], const double wo[3], double rgb[3])
{
    const tab_material *tm = data;
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    double co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    double ch, cd, f[3];
    (void)uv;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(ci > 0.0) || !(co > 0.0) || tab_angles(n, wi, wo, &ch, &cd))
        return;
    tab_lookup(&tm->g, tm->t, ch, cd, f);
    for (int c = 0; c < 3; c++)
        rgb[c] = fmax(f[c], 0.0) * ci;
}

static int tab_mat_to_json(const void *data, json_t *root, glint_err *err)
{
    const tab_material *tm = data;
    json_t *rows = json_array();
    for (int j = 0; rows && j < tm->g.res_d; j++) {
        json_t *row = json_array();
        for (int i = 0; row && i < tm->g.res_h; i++) {
            const double *v = tm->t + 3 * (size_t)(j * tm->g.res_h + i);
            if (json_array_append_new(row, json_pack("[f, f, f]", v[0], v[1], v[2]))) {
                json_decref(row);
                row = NULL;
            }
        }
        if (!row || json_array_append_new(rows, row)) {
            json_decref(rows);
            rows = NULL;
        }
    }
    if (!rows || json_object_set_new(root, "res_h", json_integer(tm->g.res_h)) ||
        json_object_set_new(root, "res_d", json_integer(tm->g.res_d)) ||
        json_object_set_new(root, "table", rows))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab manifest)");
    return 0;
}

/* An integer member in [lo, hi]. */
static int read_int(const json_t *root, const char *file, const char *name, int lo, int hi,
                    int *out, glint_err *err)
{
    const json_t *v = json_object_get(root, name);
    json_int_t x = json_integer_value(v);
    if (!json_is_integer(v) || x < lo || x > hi)
        return glint_err_set(err, GLINT_EFORMAT, "%s: %s must be an integer in [%d, %d]", file,
                             name, lo, hi);
    *out = (int)x;
    return 0;
}

/* The table's rows into t (3 nodes doubles). */
static int read_table(const json_t *rows, const char *file, const tab_grid *g, double *t,
                      glint_err *err)
{
    if (!json_is_array(rows) || (int)json_array_size(rows) != g->res_d)
        return glint_err_set(err, GLINT_EFORMAT, "%s: table must be an array of res_d = %d rows",
                             file, g->res_d);
    for (int j = 0; j < g->res_d; j++) {
        const json_t *row = json_array_get(rows, (size_t)j);
        if (!json_is_array(row) || (int)json_array_size(row) != g->res_h)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s: table[%d] must be an array of res_h = %d [r, g, b]", file,
                                 j, g->res_h);
        for (int i = 0; i < g->res_h; i++) {
            const json_t *v = json_array_get(row, (size_t)i);
            if (!json_is_array(v) || json_array_size(v) != 3)
                return glint_err_set(err, GLINT_EFORMAT, "%s: table[%d][%d] must be [r, g, b]",
                                     file, j, i);
            for (int c = 0; c < 3; c++) {
                const json_t *x = json_array_get(v, (size_t)c);
                double y = json_number_value(x);
                if (!json_is_number(x) || !isfinite(y))
                    return glint_err_set(err, GLINT_EFORMAT,
                                         "%s: table[%d][%d] must hold finite numbers", file, j,
                                         i);
                t[3 * (size_t)(j * g->res_h + i) + c] = y;
            }
        }
    }
    return 0;
}

static int tab_mat_from_json(const json_t *root, const char *file, void **data, glint_err *err)
{
    tab_grid g;
    tab_material *tm;
    int rc;
    if ((rc = read_int(root, file, "res_h", TAB_RES_H_MIN, TAB_RES_H_MAX, &g.res_h, err)) ||
        (rc = read_int(root, file, "res_d", TAB_RES_D_MIN, TAB_RES_D_MAX, &g.res_d, err)))
        return rc;
    if (tab_nodes(&g) > TAB_MAX_NODES)
        return glint_err_set(err, GLINT_EFORMAT, "%s: res_h x res_d must be at most %d", file,
                             TAB_MAX_NODES);
    if (!(tm = calloc(1, sizeof *tm)) || !(tm->t = malloc(3 * (size_t)tab_nodes(&g) * sizeof *tm->t))) {
        tab_material_free(tm);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab table)");
    }
    tm->g = g;
    if ((rc = read_table(json_object_get(root, "table"), file, &g, tm->t, err))) {
        tab_material_free(tm);
        return rc;
    }
    *data = tm;
    return 0;
}

static const char frag[] =
    "#version 300 es\n"
    "// tab: f(theta_h, theta_d) tabulated, bilinear; u = sqrt(theta_h / (pi/2)),\n"
    "// v = theta_d / (pi/2); texel (i, j) holds the node at u = i / (res_h - 1),\n"
    "// v = j / (res_d - 1) (fetched with texelFetch: no filtering needed)\n"
    GLSL_PRECISION
    "uniform sampler2D u_table;\n"
    "uniform int u_res_h;\n"
    "uniform int u_res_d;\n"
    GLSL_STAGE_IO
    "const float HALF_PI = 1.57079632679489662;\n"
    GLSL_UNIT
    GLSL_TAB_LOOKUP
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    "    float ci = dot(n, wi), co = dot(n, wo);\n"
    "    if (!(ci > 0.0) || !(co > 0.0))\n"
    "        return vec3(0.0);\n"
    "    vec3 h = glint_unit(wi + wo);\n"
    "    float th = acos(clamp(dot(n, h), -1.0, 1.0));\n"
    "    float td = acos(clamp(dot(wi, h), -1.0, 1.0));\n"
    "    vec3 f = tab_lookup(sqrt(th / HALF_PI), td / HALF_PI);\n"
    "    return max(f, vec3(0.0)) * ci;\n"
    "}\n"
    GLSL_MAIN;

static int tab_mat_gpu(const void *data, material_gpu *g, glint_err *err)
{
    const tab_material *tm = data;
    size_t n = 3 * (size_t)tab_nodes(&tm->g);
    memset(g, 0, sizeof *g);
    g->program = "tab";
    g->frag_src = frag;
    g->tex_uniform = "u_table";
    g->tex_w = tm->g.res_h;
    g->tex_h = tm->g.res_d;
    g->tex = malloc(n * sizeof *g->tex);
    g->manifest = json_object();
    if (!g->tex || !g->manifest || tab_mat_to_json(tm, g->manifest, err)) {
        material_gpu_free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab texture)");
    }
    for (size_t k = 0; k < n; k++)
        g->tex[k] = (float)tm->t[k];
    g->nuniforms = 2;
    g->uniform[0] = (material_gpu_uniform){"u_res_h", "int", {tm->g.res_h, 0, 0},
                                           "nodes along theta_h (texture width)"};
    g->uniform[1] = (material_gpu_uniform){"u_res_d", "int", {tm->g.res_d, 0, 0},
                                           "nodes along theta_d (texture height)"};
    return 0;
}

static json_t *tab_mat_summary(const void *data)
{
    const tab_material *tm = data;
    const double *t0 = tm->t;
    return json_pack("{s:i, s:i, s:[f, f, f]}", "res_h", tm->g.res_h, "res_d", tm->g.res_d,
                     "base_colour", M_PI * fmax(t0[0], 0.0), M_PI * fmax(t0[1], 0.0),
                     M_PI * fmax(t0[2], 0.0));
}

const material_ops tab_material_ops = {
    .eval = tab_mat_eval,
    .free = tab_material_free,
    .to_json = tab_mat_to_json,
    .from_json = tab_mat_from_json,
    .gpu = tab_mat_gpu,
    .summary = tab_mat_summary,
};
