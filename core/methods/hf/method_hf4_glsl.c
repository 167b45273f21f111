/* method_hf4_glsl.c: the fragment stage of an hf4 material (GLSL ES 3.00):
 * what previews draw with and what the shader export writes as
 * glint_material.frag (bound by method_hf4_material.c). */

#include "glsl_parts.h"
#include "method_hf4.h"

const char hf4_glsl_frag[] =
    "#version 300 es\n"
    "// glint_material.frag: a glint four-factor material (GLSL ES 3.00):\n"
    "// inverse_map(p(pi_p) q(pi_q) r(pi_r) s(u, v)); pi_* the lengths of wi,\n"
    "// h and wo on the tangent plane, (u, v) the texture coordinates.  Pair\n"
    "// it with glint_material.vert.  Bindings (shader.json says more):\n"
    "// u_factors RGB float, NEAREST: rows 0-2 log p, q, r (node texels at\n"
    "// k / (res - 1)); rows 3 .. 3 + u_sres - 1 log s, node (i, j) at row\n"
    "// 3 + j, column i, at (i, j) / (u_sres - 1), bilinear between nodes.\n"
    "// u_map_kind 0 log, 1 add (pqrs - a), 2 sub (a - pqrs); u_model_brdf 1:\n"
    "// times n.wi.  Output: linear radiance for u_light_intensity.\n"
    GLSL_PRECISION
    "uniform highp sampler2D u_factors;\n"
    "uniform int u_res;\n"
    "uniform int u_sres;\n"
    "uniform int u_map_kind;\n"
    "uniform vec3 u_a;\n"
    "uniform int u_model_brdf;\n"
    GLSL_STAGE_IO
    GLSL_UNIT
    GLSL_TANGENT_LEN
    GLSL_FACTOR("u_factors")
    GLSL_NODES("u_factors")
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    "    float ci = dot(n, wi), co = dot(n, wo);\n"
    "    if (!(ci > 0.0) || !(co > 0.0))\n"
    "        return vec3(0.0);\n"
    "    vec3 h = glint_unit(wi + wo);\n"
    "    vec3 s = glint_factor(0, glint_tangent_len(wi, n)) +\n"
    "             glint_factor(1, glint_tangent_len(h, n)) +\n"
    "             glint_factor(2, glint_tangent_len(wo, n)) + glint_nodes(3, v_uv);\n"
    "    vec3 prod = exp(min(s, vec3(88.0)));\n"
    "    vec3 v = u_map_kind == 1 ? prod - u_a : (u_map_kind == 2 ? u_a - prod : prod);\n"
    "    v = max(v, vec3(0.0));\n"
    "    return u_model_brdf == 1 ? v * ci : v;\n"
    "}\n"
    "\n"
    GLSL_MAIN;
