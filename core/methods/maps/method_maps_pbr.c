/* method_maps_pbr.c: what a maps material with pbr products (pbr_maps,
 * method_pbr_maps.h) has of its own: its summary and its GPU binding,
 * whose fragment stage evaluates what maps_eval() does on the CPU, the
 * products' pbr_brdf() (tests/unit/test_pbr_maps.c compares them). */
#include <stdlib.h>
#include <string.h>

#include "glsl_parts.h"
#include "method_pbr.h"
#include "internal/method_maps_int.h"

static const char frag[] =
    "#version 300 es\n"
    "// glint_material.frag: a glint material map of physically based materials\n"
    "// (GLSL ES 3.00), for glint_material.vert: f = sum_k c_k(uv) f_k(wi, wo), each f_k\n"
    "// kd / pi plus up to two GGX lobes (height-correlated Smith, Schlick Fresnel);\n"
    "// radiance for u_light_intensity.  u_maps (RGB float, texelFetch; shader.json has\n"
    "// the layout): row k < u_k product k's parameters (texel 0 kd, 1 (alpha1, alpha2,\n"
    "// lobes), 2 ks1, 3 F0 1, 4 ks2, 5 F0 2), then blocks of u_map_res rows, block b\n"
    "// holding the coefficients of products 3b, 3b+1, 3b+2 in R, G, B.\n"
    GLSL_PRECISION
    "uniform highp sampler2D u_maps;\n"
    "uniform int u_map_res;\n"
    "uniform int u_k;\n"
    GLSL_STAGE_IO
    "const float PI = 3.14159265358979323846;\n"
    GLSL_UNIT
    GLSL_PBR_LOBE
    "// The coefficients of products 3b..3b+2 at uv (bilinear between texel\n"
    "// centres, clamped at the border).\n"
    GLSL_MAP_COEFS("u_k")
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    GLSL_PBR_ANGLES
    "    vec3 acc = vec3(0.0), cs = vec3(0.0);\n"
    "    for (int k = 0; k < 32; k++) {\n"
    "        if (k >= u_k)\n"
    "            break;\n"
    "        if (k % 3 == 0)\n"
    "            cs = glint_coefs(k / 3, v_uv);\n"
    "        float c = cs[k % 3];\n"
    "        if (!(c > 0.0))\n"
    "            continue;\n"
    "        vec3 a = texelFetch(u_maps, ivec2(1, k), 0).rgb;\n"
    "        vec3 f = texelFetch(u_maps, ivec2(0, k), 0).rgb / PI +\n"
    "                 pbr_lobe(a.x, texelFetch(u_maps, ivec2(2, k), 0).rgb,\n"
    "                          texelFetch(u_maps, ivec2(3, k), 0).rgb, ci, co, ch, w5);\n"
    "        if (a.z > 1.5)\n"
    "            f += pbr_lobe(a.y, texelFetch(u_maps, ivec2(4, k), 0).rgb,\n"
    "                          texelFetch(u_maps, ivec2(5, k), 0).rgb, ci, co, ch, w5);\n"
    "        acc += c * f;\n"
    "    }\n"
    "    return acc * ci;\n"
    "}\n"
    "\n"
    GLSL_MAIN;

#define PARAM_TEXELS 6

static void put3(float *t, const double *v)
{
    for (int c = 0; c < 3; c++)
        t[c] = (float)v[c];
}

int maps_pbr_gpu(const maps_material *x, material_gpu *g, glint_err *err)
{
    int K = x->mm.k, M = x->mm.res, B = (K + 2) / 3;
    int W = M > PARAM_TEXELS ? M : PARAM_TEXELS, H = K + B * M;

    memset(g, 0, sizeof *g);
    g->program = "maps_pbr";
    g->frag_src = frag;
    g->tex_uniform = "u_maps";
    g->tex_w = W;
    g->tex_h = H;
    if (!(g->tex = calloc((size_t)W * H * 3, sizeof *g->tex)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the material texture");
    for (int k = 0; k < K; k++) {
        const pbr_material *pm = pbr_material_of(&x->mm.comp[k]);
        float *row = g->tex + (size_t)k * W * 3;
        double a[3] = {pm->lobe[0].alpha, pm->sp.nlobes > 1 ? pm->lobe[1].alpha : 0.5,
                       pm->sp.nlobes};
        put3(row, pm->kd);
        put3(row + 3, a);
        put3(row + 6, pm->lobe[0].ks);
        put3(row + 9, pm->lobe[0].f0);
        if (pm->sp.nlobes > 1) {
            put3(row + 12, pm->lobe[1].ks);
            put3(row + 15, pm->lobe[1].f0);
        }
        for (int j = 0; j < M; j++)
            for (int i = 0; i < M; i++)
                g->tex[((size_t)(K + (k / 3) * M + j) * W + i) * 3 + k % 3] =
                    x->mm.coef[(size_t)k * M * M + (size_t)j * M + i];
    }
    g->nuniforms = 2;
    g->uniform[0] = (material_gpu_uniform){"u_map_res", "int", {M, 0, 0},
                                           "coefficient texels per side"};
    g->uniform[1] = (material_gpu_uniform){"u_k", "int", {K, 0, 0}, "products"};
    g->manifest = json_pack(
        "{s:s, s:i, s:i}", "texture_layout",
        "u_maps: RGB float, width max(map_res, 6); row k < K product k's parameters (texel 0 "
        "kd, 1 (alpha of lobe 1, alpha of lobe 2, lobes), 2 ks of lobe 1, 3 F0 of lobe 1, 4 ks "
        "of lobe 2, 5 F0 of lobe 2); from row K, blocks of map_res rows, block b holding the "
        "coefficients of products 3b, 3b+1, 3b+2 in R, G, B (row 0 of a block at v = 0)",
        "products", K, "map_res", M);
    if (!g->manifest) {
        material_gpu_free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    return 0;
}

json_t *maps_pbr_summary(const maps_material *x)
{
    const pbr_material *pm = x->mm.k ? pbr_material_of(&x->mm.comp[0]) : NULL;
    json_t *kd = json_array();
    double d[3] = {0, 0, 0};
    /* the average diffuse colour over the surface: the coefficients' means */
    for (int k = 0; k < x->mm.k; k++)
        for (int c = 0; c < 3; c++)
            d[c] += x->mean[k] * pbr_material_of(&x->mm.comp[k])->kd[c];
    for (int c = 0; c < 3; c++)
        json_array_append_new(kd, json_real(d[c]));
    return json_pack("{s:i, s:i, s:s, s:s, s:i, s:s, s:o}", "components", x->mm.k, "map_res",
                     x->mm.res, "stop", x->mm.stop ? x->mm.stop : "components", "product",
                     "pbr", "lobes", pm ? pm->sp.nlobes : 0, "fresnel",
                     pm && pm->sp.fresnel == PBR_CONDUCTOR ? "conductor" : "dielectric",
                     "diffuse", kd);
}
