/* method_pbr_material.c: operations on pbr materials (method_pbr.h):
 * evaluation (f ci per unit light, 0 unless n.wi > 0 and n.wo > 0), the
 * manifest's members and the GPU's fragment stage.
 *
 * The manifest holds the direct parameters of pbr.h (not the common form,
 * which is derived): read back, every value is checked against its bounds
 * (pbr_bounds), so a material read is one the fit could have made. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "glsl_parts.h"
#include "method_pbr.h"

static const char *const fresnel_names[] = {"dielectric", "conductor"};

void pbr_material_sync(pbr_material *pm)
{
    memcpy(pm->kd, pm->p, sizeof pm->kd);
    pbr_lobes_of(&pm->sp, pm->p, pm->lobe);
}

const pbr_material *pbr_material_of(const material *m)
{
    return m && m->method && m->method->mat == &pbr_material_ops ? m->data : NULL;
}

static void pbr_mat_eval(const void *data, const double uv[2], const double n[3],
                         const double wi[3], const double wo[3], double rgb[3])
{
    const pbr_material *pm = data;
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    double co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    double h[3], hl, ch, cd, f[3];
    (void)uv;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(ci > 0.0) || !(co > 0.0))
        return;
    for (int e = 0; e < 3; e++)
        h[e] = wi[e] + wo[e];
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    if (!(hl > 0.0))
        return;
    ch = (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl;
    cd = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl;
    pbr_brdf(pm->kd, pm->lobe, pm->sp.nlobes, ci, co, ch, cd, f);
    for (int c = 0; c < 3; c++)
        rgb[c] = f[c] * ci;
}

static int pbr_mat_to_json(const void *data, json_t *root, glint_err *err)
{
    const pbr_material *pm = data;
    json_t *lobes = json_array();
    (void)err;
    for (int l = 0; l < pm->sp.nlobes; l++) {
        const double *q = pm->p + 3 + 5 * l;
        json_t *o = pm->sp.fresnel == PBR_DIELECTRIC
                        ? json_pack("{s:f, s:[f, f, f], s:f}", "alpha", q[0], "ks", q[1], q[2],
                                    q[3], "ior", q[4])
                        : json_pack("{s:f, s:f, s:[f, f, f]}", "alpha", q[0], "ks", q[1], "f0",
                                    q[2], q[3], q[4]);
        json_array_append_new(lobes, o);
    }
    json_object_set_new(root, "fresnel", json_string(fresnel_names[pm->sp.fresnel]));
    json_object_set_new(root, "diffuse", json_pack("[f, f, f]", pm->p[0], pm->p[1], pm->p[2]));
    json_object_set_new(root, "lobes", lobes);
    return 0;
}

/* One bounded number of the manifest into *out (k: its index, for bounds). */
static int read_num(const json_t *v, const char *file, const char *what, double lo, double hi,
                    double *out, glint_err *err)
{
    double x = json_number_value(v);
    if (!json_is_number(v) || !isfinite(x) || x < lo || x > hi)
        return glint_err_set(err, GLINT_EFORMAT, "%s: %s must be a number in [%g, %g]", file,
                             what, lo, hi);
    *out = x;
    return 0;
}

static int read_rgb(const json_t *a, const char *file, const char *what, double lo, double hi,
                    double *out, glint_err *err)
{
    if (!json_is_array(a) || json_array_size(a) != 3)
        return glint_err_set(err, GLINT_EFORMAT, "%s: %s must be [r, g, b]", file, what);
    for (int c = 0; c < 3; c++) {
        int rc = read_num(json_array_get(a, (size_t)c), file, what, lo, hi, out + c, err);
        if (rc)
            return rc;
    }
    return 0;
}

static int pbr_mat_from_json(const json_t *root, const char *file, void **data, glint_err *err)
{
    const char *fr = json_string_value(json_object_get(root, "fresnel"));
    const json_t *lobes = json_object_get(root, "lobes");
    double lo[PBR_MAXP], hi[PBR_MAXP];
    pbr_material pm, *out;
    int rc;

    memset(&pm, 0, sizeof pm);
    if (!fr || (strcmp(fr, "dielectric") && strcmp(fr, "conductor")))
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s: fresnel must be \"dielectric\" or \"conductor\"", file);
    pm.sp.fresnel = strcmp(fr, "dielectric") ? PBR_CONDUCTOR : PBR_DIELECTRIC;
    if (!json_is_array(lobes) || json_array_size(lobes) < 1 ||
        json_array_size(lobes) > PBR_MAX_LOBES)
        return glint_err_set(err, GLINT_EFORMAT, "%s: lobes must be an array of 1 or %d lobes",
                             file, PBR_MAX_LOBES);
    pm.sp.nlobes = (int)json_array_size(lobes);
    pbr_bounds(&pm.sp, lo, hi);
    if ((rc = read_rgb(json_object_get(root, "diffuse"), file, "diffuse", lo[0], hi[0], pm.p,
                       err)))
        return rc;
    for (int l = 0; l < pm.sp.nlobes; l++) {
        const json_t *o = json_array_get(lobes, (size_t)l);
        int b = 3 + 5 * l;
        if (!json_is_object(o))
            return glint_err_set(err, GLINT_EFORMAT, "%s: lobes[%d] must be an object", file, l);
        if ((rc = read_num(json_object_get(o, "alpha"), file, "lobes[].alpha", lo[b], hi[b],
                           pm.p + b, err)))
            return rc;
        if (pm.sp.fresnel == PBR_DIELECTRIC)
            rc = read_rgb(json_object_get(o, "ks"), file, "lobes[].ks", lo[b + 1], hi[b + 1],
                          pm.p + b + 1, err) ||
                 read_num(json_object_get(o, "ior"), file, "lobes[].ior", lo[b + 4], hi[b + 4],
                          pm.p + b + 4, err);
        else
            rc = read_num(json_object_get(o, "ks"), file, "lobes[].ks", lo[b + 1], hi[b + 1],
                          pm.p + b + 1, err) ||
                 read_rgb(json_object_get(o, "f0"), file, "lobes[].f0", lo[b + 2], hi[b + 2],
                          pm.p + b + 2, err);
        if (rc)
            return err ? err->code : GLINT_EFORMAT;
    }
    pbr_material_sync(&pm);
    if (!(out = malloc(sizeof *out)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    *out = pm;
    *data = out;
    return 0;
}

static const char frag[] =
    "#version 300 es\n"
    "// pbr: kd/pi + up to two GGX lobes, height-correlated Smith, Schlick Fresnel\n"
    GLSL_PRECISION
    "uniform vec3 u_kd;\n"
    "uniform float u_alpha1;\n"
    "uniform vec3 u_ks1;\n"
    "uniform vec3 u_f01;\n"
    "uniform float u_alpha2;\n"
    "uniform vec3 u_ks2;\n"
    "uniform vec3 u_f02;\n"
    GLSL_STAGE_IO
    "const float PI = 3.14159265358979323846;\n"
    GLSL_UNIT
    GLSL_PBR_LOBE
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    GLSL_PBR_ANGLES
    "    vec3 f = u_kd / PI + pbr_lobe(u_alpha1, u_ks1, u_f01, ci, co, ch, w5) +\n"
    "             pbr_lobe(u_alpha2, u_ks2, u_f02, ci, co, ch, w5);\n"
    "    return f * ci;\n"
    "}\n"
    GLSL_MAIN;

static int pbr_mat_gpu(const void *data, material_gpu *g, glint_err *err)
{
    const pbr_material *pm = data;
    pbr_lobe none = {1.0, {0, 0, 0}, {0, 0, 0}};
    const pbr_lobe *l1 = &pm->lobe[0], *l2 = pm->sp.nlobes > 1 ? &pm->lobe[1] : &none;
    memset(g, 0, sizeof *g);
    g->program = "pbr";
    g->frag_src = frag;
    g->nuniforms = 7;
    g->uniform[0] = (material_gpu_uniform){"u_kd", "vec3", {pm->kd[0], pm->kd[1], pm->kd[2]},
                                           "diffuse albedo per channel"};
    g->uniform[1] = (material_gpu_uniform){"u_alpha1", "float", {l1->alpha, 0, 0},
                                           "GGX roughness of the first lobe"};
    g->uniform[2] = (material_gpu_uniform){"u_ks1", "vec3", {l1->ks[0], l1->ks[1], l1->ks[2]},
                                           "weight of the first lobe per channel"};
    g->uniform[3] = (material_gpu_uniform){"u_f01", "vec3", {l1->f0[0], l1->f0[1], l1->f0[2]},
                                           "Fresnel reflectance at normal incidence, first lobe"};
    g->uniform[4] = (material_gpu_uniform){"u_alpha2", "float", {l2->alpha, 0, 0},
                                           "GGX roughness of the second lobe"};
    g->uniform[5] = (material_gpu_uniform){"u_ks2", "vec3", {l2->ks[0], l2->ks[1], l2->ks[2]},
                                           "weight of the second lobe per channel (0: none)"};
    g->uniform[6] = (material_gpu_uniform){"u_f02", "vec3", {l2->f0[0], l2->f0[1], l2->f0[2]},
                                           "Fresnel reflectance at normal incidence, second lobe"};
    g->manifest = json_object();
    if (!g->manifest || pbr_mat_to_json(pm, g->manifest, err)) {
        json_decref(g->manifest);
        g->manifest = NULL;
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    return 0;
}

static json_t *pbr_mat_summary(const void *data)
{
    const pbr_material *pm = data;
    return json_pack("{s:i, s:s, s:f}", "lobes", pm->sp.nlobes, "fresnel",
                     fresnel_names[pm->sp.fresnel], "alpha", pm->lobe[0].alpha);
}

const material_ops pbr_material_ops = {
    .eval = pbr_mat_eval,
    .free = free,
    .to_json = pbr_mat_to_json,
    .from_json = pbr_mat_from_json,
    .gpu = pbr_mat_gpu,
    .summary = pbr_mat_summary,
};
