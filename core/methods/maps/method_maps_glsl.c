/* method_maps_glsl.c: the fragment stage of a maps material (GLSL ES
 * 3.00): what previews draw with and what the shader export writes.  It
 * must evaluate what maps_eval() evaluates on the CPU (tests/unit/
 * test_maps.c compares them). */

#include "glsl_parts.h"
#include "method_maps.h"

const char maps_glsl_frag[] =
    "#version 300 es\n"
    "// glint_material.frag: a glint material map (GLSL ES 3.00), for\n"
    "// glint_material.vert: f = sum_k c_k(uv) inverse_map_k(p_k(pi_p)\n"
    "// q_k(pi_q) r_k(pi_r) [s_k(uv)]), pi_* the lengths of wi, h, wo on the\n"
    "// tangent plane; radiance for u_light_intensity.  u_maps (RGB float,\n"
    "// NEAREST; shader.json has the layout): log p, q, r per product, the\n"
    "// mapping offsets, the coefficients (3 products per block), then\n"
    "// (u_sres > 0) u_sres rows of log s per product.\n"
    GLSL_PRECISION
    "uniform highp sampler2D u_maps;\n"
    "uniform int u_res;\n"
    "uniform int u_map_res;\n"
    "uniform int u_k;\n"
    "uniform int u_map_kind;\n"
    "uniform int u_model_brdf;\n"
    "uniform int u_sres;\n"
    GLSL_STAGE_IO
    GLSL_UNIT
    GLSL_TANGENT_LEN
    GLSL_FACTOR("u_maps")
    "// The coefficients of products 3b..3b+2 at uv (bilinear between texel\n"
    "// centres, clamped at the border).\n"
    GLSL_MAP_COEFS("3 * u_k + 1")
    GLSL_NODES("u_maps")
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    "    float ci = dot(n, wi), co = dot(n, wo);\n"
    "    if (!(ci > 0.0) || !(co > 0.0))\n"
    "        return vec3(0.0);\n"
    "    vec3 h = glint_unit(wi + wo);\n"
    "    float up = glint_tangent_len(wi, n), uq = glint_tangent_len(h, n),\n"
    "          ur = glint_tangent_len(wo, n);\n"
    "    vec3 acc = vec3(0.0), cs = vec3(0.0);\n"
    "    int r0 = 3 * u_k + 1 + ((u_k + 2) / 3) * u_map_res;\n"
    "    for (int k = 0; k < 32; k++) {\n"
    "        if (k >= u_k)\n"
    "            break;\n"
    "        if (k % 3 == 0)\n"
    "            cs = glint_coefs(k / 3, v_uv);\n"
    "        float c = cs[k % 3];\n"
    "        if (!(c > 0.0))\n"
    "            continue;\n"
    "        vec3 s = glint_factor(3 * k, up) + glint_factor(3 * k + 1, uq) +\n"
    "                 glint_factor(3 * k + 2, ur);\n"
    "        if (u_sres > 1)\n"
    "            s += glint_nodes(r0 + k * u_sres, v_uv);\n"
    "        vec3 prod = exp(min(s, vec3(88.0)));\n"
    "        vec3 a = texelFetch(u_maps, ivec2(k, 3 * u_k), 0).rgb;\n"
    "        vec3 v = u_map_kind == 1 ? prod - a : (u_map_kind == 2 ? a - prod : prod);\n"
    "        acc += c * max(v, vec3(0.0));\n"
    "    }\n"
    "    return u_model_brdf == 1 ? acc * ci : acc;\n"
    "}\n"
    "\n"
    GLSL_MAIN;
