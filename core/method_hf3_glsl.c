/* method_hf3_glsl.c: the fragment stage of an hf3 material (GLSL ES 3.00):
 * what previews draw with and what the shader export writes as
 * glint_material.frag.  It must evaluate exactly what hf_factors_eval()
 * evaluates on the CPU (tests/unit/test_glr.c compares them). */

#include "glsl_parts.h"
#include "method_hf3.h"

const char hf3_glsl_frag[] =
    "#version 300 es\n"
    "// glint_material.frag: a glint material, three 1D factors (GLSL ES 3.00).\n"
    "// Written by glint (glr_shader_export); pair it with glint_material.vert.\n"
    "//\n"
    "// The material is f ~ inverse_map(p(pi_p) q(pi_q) r(pi_r)), where pi_p,\n"
    "// pi_q, pi_r are the lengths of wi, h = normalize(wi + wo) and wo\n"
    "// projected on the tangent plane (each in [0, 1]).  Output: linear\n"
    "// radiance for a point light of intensity u_light_intensity (no tone\n"
    "// mapping, no gamma); 0 unless n.wi > 0 and n.wo > 0.\n"
    "//\n"
    "// Binding contract (also in shader.json):\n"
    "//   uniform highp sampler2D u_factors  the LOG-factors: width res, height 3;\n"
    "//       row 0 = log p, row 1 = log q, row 2 = log r; RGB = channels.\n"
    "//       Texel k sits at u = k / (res - 1) (node convention); the shader\n"
    "//       fetches texels with texelFetch and interpolates them itself, so\n"
    "//       the texture may be RGBA32F or RGBA16F and needs no filtering\n"
    "//       (set NEAREST, no mipmaps).\n"
    "//   uniform int   u_res            texels per factor (res, >= 2)\n"
    "//   uniform int   u_map_kind       0 = log: value = pqr\n"
    "//                                  1 = add: value = max(pqr - a, 0)\n"
    "//                                  2 = sub: value = max(a - pqr, 0)\n"
    "//   uniform vec3  u_a              the mapping offset a per channel (a_used)\n"
    "//   uniform int   u_model_brdf     1: the factors are a BRDF, multiply by n.wi;\n"
    "//                                  0: they are radiance (already include n.wi)\n"
    "//   uniform vec3  u_eye            camera position, world space\n"
    "//   uniform vec3  u_light          point light position, world space\n"
    "//   uniform float u_light_intensity  light intensity (no distance fall-off)\n"
    "//   out location 0  o_color        vec4(radiance RGB, 1)\n"
    GLSL_PRECISION
    "uniform highp sampler2D u_factors;\n"
    "uniform int u_res;\n"
    "uniform int u_map_kind;\n"
    "uniform vec3 u_a;\n"
    "uniform int u_model_brdf;\n"
    GLSL_STAGE_IO
    GLSL_UNIT
    "// Length of v projected on the plane orthogonal to the unit normal n.\n"
    GLSL_TANGENT_LEN
    "// Log-factor of row `row` at u in [0, 1]: hat interpolation between\n"
    "// node texels k0 = min(floor(u (res-1)), res-2) and k0 + 1.\n"
    GLSL_FACTOR("u_factors")
    "// The material at unit n, wi, wo (per unit light intensity).\n"
    "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)\n"
    "{\n"
    "    float ci = dot(n, wi), co = dot(n, wo);\n"
    "    if (!(ci > 0.0) || !(co > 0.0))\n"
    "        return vec3(0.0);\n"
    "    vec3 h = glint_unit(wi + wo);\n"
    "    vec3 s = glint_factor(0, glint_tangent_len(wi, n)) +\n"
    "             glint_factor(1, glint_tangent_len(h, n)) +\n"
    "             glint_factor(2, glint_tangent_len(wo, n));\n"
    "    vec3 prod = exp(min(s, vec3(88.0))); // bounded: stays finite in float\n"
    "    vec3 v = u_map_kind == 1 ? prod - u_a : (u_map_kind == 2 ? u_a - prod : prod);\n"
    "    v = max(v, vec3(0.0));\n"
    "    return u_model_brdf == 1 ? v * ci : v;\n"
    "}\n"
    "\n"
    GLSL_MAIN;
