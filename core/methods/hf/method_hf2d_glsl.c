/* method_hf2d_glsl.c: the fragment stage of an hf2d material (GLSL ES
 * 3.00): what previews draw with and what the shader export writes as
 * glint_material.frag (bound by method_hf2d_material.c). */

#include "glsl_parts.h"
#include "method_hf2d.h"

const char hf2d_glsl_frag[] =
    "#version 300 es\n"
    "// glint_material.frag: a glint hf2d material (GLSL ES 3.00):\n"
    "// inverse_map(p(wi) q(h) r(wo)), each factor 1D over the length of its\n"
    "// vector on the tangent plane or 2D over the vector's parabolic map in\n"
    "// the frame t = normalize(Z x n), b = n x t.  Pair it with\n"
    "// glint_material.vert.  Bindings (shader.json says more): u_factors RGB\n"
    "// float log nodes, NEAREST; u_dims, u_rows: each factor's dimensions and\n"
    "// first row; u_map_kind 0 log, 1 add (pqr - a), 2 sub (a - pqr);\n"
    "// u_model_brdf 1: times n.wi.  Output: linear radiance for\n"
    "// u_light_intensity.\n"
    GLSL_PRECISION
    "uniform highp sampler2D u_factors;\n"
    "uniform int u_res;\n"
    "uniform int u_sres;\n"
    "uniform vec3 u_dims;\n"
    "uniform vec3 u_rows;\n"
    "uniform int u_map_kind;\n"
    "uniform vec3 u_a;\n"
    "uniform int u_model_brdf;\n"
    GLSL_STAGE_IO
    GLSL_UNIT
    GLSL_TANGENT_LEN
    GLSL_FACTOR("u_factors")
    GLSL_NODES("u_factors")
    "vec2 glint_parabolic(vec3 d, vec3 n)\n"
    "{\n"
    "    vec3 a = vec3(-n.y, n.x, 0.0);\n"
    "    float l = length(a);\n"
    "    vec3 t = l > 1e-6 ? a / l : vec3(1.0, 0.0, 0.0);\n"
    "    vec3 b = cross(n, t);\n"
    "    float c = max(dot(d, n), 0.0);\n"
    "    return (vec2(dot(d, t), dot(d, b)) / (1.0 + c) + 1.0) * 0.5;\n"
    "}\n"
    "\n"
    "vec3 glint_any(float dims, float row, vec3 d, vec3 n)\n"
    "{\n"
    "    return dims > 1.5 ? glint_nodes(int(row), glint_parabolic(d, n))\n"
    "                      : glint_factor(int(row), glint_tangent_len(d, n));\n"
    "}\n"
    "\n"
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    "    float ci = dot(n, wi), co = dot(n, wo);\n"
    "    if (!(ci > 0.0) || !(co > 0.0))\n"
    "        return vec3(0.0);\n"
    "    vec3 h = glint_unit(wi + wo);\n"
    "    vec3 s = glint_any(u_dims.x, u_rows.x, wi, n) + glint_any(u_dims.y, u_rows.y, h, n) +\n"
    "             glint_any(u_dims.z, u_rows.z, wo, n);\n"
    "    vec3 prod = exp(min(s, vec3(88.0)));\n"
    "    vec3 v = u_map_kind == 1 ? prod - u_a : (u_map_kind == 2 ? u_a - prod : prod);\n"
    "    v = max(v, vec3(0.0));\n"
    "    return u_model_brdf == 1 ? v * ci : v;\n"
    "}\n"
    "\n"
    GLSL_MAIN;
