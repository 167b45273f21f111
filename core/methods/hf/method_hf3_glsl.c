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

/* ---- BRDF Explorer ------------------------------------------------------------------- */

#include <math.h>
#include <stdlib.h>

#include "buf.h"

/* The material as BRDF Explorer's analytic .brdf file: a GLSL function
 * vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) returning f (BRDF
 * Explorer multiplies by n.L itself), with the log-factors embedded as
 * constant arrays at full float precision and the evaluation of
 * hf_factors_eval: hat interpolation of the log-factors at the projected
 * lengths, exp, the inverse mapping, divided by n.L for the radiance
 * model.  Written in the subset of GLSL that desktop GLSL and GLSL ES 3.00
 * share (explicit float literals, no PI), so glint checks it with its own
 * renderer (tests/unit/test_glr.c). */
int hf3_brdf_explorer(const void *data, char **text, glint_err *err)
{
    const hf_factors *f = data;
    static const char *const names[3] = {"glint_p", "glint_q", "glint_r"};
    glint_buf b = {0};
    int R = f->res, rc = 0;

    *text = NULL;
    if (!f || R < 2 || !f->logf)
        return glint_err_set(err, GLINT_EINVAL, "no factors to write");
    rc |= glint_buf_printf(&b,
                           "analytic\n"
                           "\n"
                           "# A glint material (method hf3: three 1D factors, seed 000):\n"
                           "#   f = inverse_map(p(pi_p) q(pi_q) r(pi_r))%s,\n"
                           "# pi_p, pi_q, pi_r the lengths of L, H = normalize(L + V) and V\n"
                           "# projected on the tangent plane; the factors are embedded below\n"
                           "# as log-factors at %d nodes (node k at pi = k / %d), interpolated\n"
                           "# linearly in the log.  Mapping: %s, offset a = %.9g %.9g %.9g.\n"
                           "# The material is the BRDF of what was painted: a painted value\n"
                           "# is pi I f cos under a light of intensity I (a white Lambertian\n"
                           "# facing it reads I).\n"
                           "\n"
                           "::begin parameters\n"
                           "::end parameters\n"
                           "\n"
                           "::begin shader\n"
                           "\n",
                           f->model == HF_MODEL_BRDF ? "" : " / n.L (fitted as radiance)", R,
                           R - 1,
                           f->map.kind == HF_MAP_ADD   ? "add (max(pqr - a, 0))"
                           : f->map.kind == HF_MAP_SUB ? "sub (max(a - pqr, 0))"
                                                       : "log (pqr)",
                           f->a_used[0], f->a_used[1], f->a_used[2]);
    for (int j = 0; j < 3; j++) {
        rc |= glint_buf_printf(&b, "const vec3 %s[%d] = vec3[%d](\n", names[j], R, R);
        for (int k = 0; k < R; k++) {
            const double *v = f->logf + (size_t)(j * R + k) * 3;
            rc |= glint_buf_printf(&b, "    vec3(%.9e, %.9e, %.9e)%s\n", v[0], v[1], v[2],
                                   k + 1 < R ? "," : ");");
        }
    }
    for (int j = 0; j < 3; j++)
        rc |= glint_buf_printf(&b,
                               "\nvec3 %s_at(float u)\n"
                               "{\n"
                               "    float x = clamp(u, 0.0, 1.0) * %d.0;\n"
                               "    int k = int(min(floor(x), %d.0));\n"
                               "    float t = x - float(k);\n"
                               "    return (1.0 - t) * %s[k] + t * %s[k + 1];\n"
                               "}\n",
                               names[j], R - 1, R - 2, names[j], names[j]);
    rc |= glint_buf_printf(
        &b,
        "\nfloat glint_tangent_len(vec3 v, vec3 n)\n"
        "{\n"
        "    return clamp(length(v - n * dot(v, n)), 0.0, 1.0);\n"
        "}\n"
        "\n"
        "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)\n"
        "{\n"
        "    float ci = dot(N, L), co = dot(N, V);\n"
        "    if (!(ci > 0.0) || !(co > 0.0))\n"
        "        return vec3(0.0);\n"
        "    vec3 H = normalize(L + V);\n"
        "    vec3 s = glint_p_at(glint_tangent_len(L, N)) + glint_q_at(glint_tangent_len(H, N)) +\n"
        "             glint_r_at(glint_tangent_len(V, N));\n"
        "    vec3 prod = exp(min(s, vec3(88.0)));\n"
        "    vec3 a = vec3(%.9e, %.9e, %.9e);\n"
        "    vec3 v = max(%s, vec3(0.0));\n"
        "    return %s;\n"
        "}\n"
        "\n"
        "::end shader\n",
        f->a_used[0], f->a_used[1], f->a_used[2],
        f->map.kind == HF_MAP_ADD ? "prod - a" : f->map.kind == HF_MAP_SUB ? "a - prod" : "prod",
        f->model == HF_MODEL_BRDF ? "v" : "v / ci");
    if (rc) {
        glint_buf_free(&b);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the .brdf text");
    }
    *text = glint_buf_steal(&b, NULL);
    return *text ? 0 : glint_err_set(err, GLINT_ENOMEM, "out of memory");
}
