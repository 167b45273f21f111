/* glsl_parts.h: pieces of text the methods' fragment stages share (GLSL ES
 * 3.00, string literals to concatenate at compile time), so that every
 * method projects, interpolates and shades its inputs the same way.
 *   GLSL_PRECISION   highp float, int and sampler2D
 *   GLSL_STAGE_IO    the renderer's uniforms (u_eye, u_light,
 *                    u_light_intensity), the vertex stage's outputs (v_pos,
 *                    v_nrm, v_uv) and o_color
 *   GLSL_UNIT        glint_unit(v): v normalized (0 stays 0)
 *   GLSL_TANGENT_LEN glint_tangent_len(v, n): |v projected on the tangent
 *                    plane|, clamped to [0, 1] (hf_project)
 *   GLSL_FACTOR(S)   glint_factor(row, u): row `row` of sampler S read with
 *                    hf.h's node hats (hf_hat)
 *   GLSL_NODES(S)    glint_nodes(r0, uv): a spatial factor's log nodes, bilinear
 *   GLSL_PBR_ANGLES  the opening of a glint_material(n, wi, wo) of pbr.h's
 *                    angles: ci, co (0 returned unless both are above 0),
 *                    the half vector h, ch = n.h, cd = wi.h and w5 = (1 -
 *                    cd)^5
 *   GLSL_MAP_COEFS(R0) glint_coefs(b, uv): the coefficients of material-map
 *                    products 3b..3b+2 (R, G, B) at uv, bilinear between
 *                    texel centres, clamped; block b's rows from R0 + b
 *                    u_map_res of the sampler u_maps
 *   GLSL_PBR_LOBE    pbr_lobe(alpha, ks, f0, ci, co, ch, w5): one GGX lobe of
 *                    pbr.h (height-correlated Smith, Schlick Fresnel); needs
 *                    a constant PI
 *   GLSL_TAB_LOOKUP  tab_lookup(u, v): tab.h's table, bilinear, from the
 *                    sampler u_table with u_res_h x u_res_d nodes
 *   GLSL_MAIN        main(): glint_material(n, wi, wo) for the point light */
#ifndef GLINT_GLSL_PARTS_H
#define GLINT_GLSL_PARTS_H

#define GLSL_PRECISION                                                                          \
    "precision highp float;\n"                                                                  \
    "precision highp int;\n"                                                                    \
    "precision highp sampler2D;\n"

#define GLSL_STAGE_IO                                                                           \
    "uniform vec3 u_eye;\n"                                                                     \
    "uniform vec3 u_light;\n"                                                                   \
    "uniform float u_light_intensity;\n"                                                        \
    "in vec3 v_pos;\n"                                                                          \
    "in vec3 v_nrm;\n"                                                                          \
    "in vec2 v_uv;\n"                                                                           \
    "layout(location = 0) out vec4 o_color;\n"                                                  \
    "\n"

#define GLSL_UNIT                                                                               \
    "vec3 glint_unit(vec3 v)\n"                                                                 \
    "{\n"                                                                                       \
    "    float l = length(v);\n"                                                                \
    "    return l > 0.0 ? v / l : v;\n"                                                         \
    "}\n"                                                                                       \
    "\n"

#define GLSL_TANGENT_LEN                                                                        \
    "float glint_tangent_len(vec3 v, vec3 n)\n"                                                 \
    "{\n"                                                                                       \
    "    return clamp(length(v - n * dot(v, n)), 0.0, 1.0);\n"                                  \
    "}\n"                                                                                       \
    "\n"

#define GLSL_FACTOR(S)                                                                          \
    "vec3 glint_factor(int row, float u)\n"                                                     \
    "{\n"                                                                                       \
    "    float x = clamp(u, 0.0, 1.0) * float(u_res - 1);\n"                                    \
    "    int k = min(int(floor(x)), u_res - 2);\n"                                              \
    "    float t = x - float(k);\n"                                                             \
    "    vec3 a = texelFetch(" S ", ivec2(k, row), 0).rgb;\n"                                   \
    "    vec3 b = texelFetch(" S ", ivec2(k + 1, row), 0).rgb;\n"                               \
    "    return (1.0 - t) * a + t * b;\n"                                                       \
    "}\n"                                                                                       \
    "\n"

/* glint_nodes(r0, uv): bilinear between the u_sres x u_sres nodes of a
 * spatial factor stored from row r0 of texture S (node (i, j) at row
 * r0 + j, column i, at (u, v) = (i, j) / (u_sres - 1)); uv clamped. */
#define GLSL_NODES(S)                                                                           \
    "vec3 glint_nodes(int r0, vec2 uv)\n"                                                       \
    "{\n"                                                                                       \
    "    vec2 x = clamp(uv, 0.0, 1.0) * float(u_sres - 1);\n"                                   \
    "    int i = min(int(floor(x.x)), u_sres - 2), j = r0 + min(int(floor(x.y)), u_sres - 2);\n" \
    "    vec2 t = x - vec2(float(i), float(j - r0));\n"                                          \
    "    vec3 a = texelFetch(" S ", ivec2(i, j), 0).rgb;\n"                                      \
    "    vec3 b = texelFetch(" S ", ivec2(i + 1, j), 0).rgb;\n"                                  \
    "    vec3 c = texelFetch(" S ", ivec2(i, j + 1), 0).rgb;\n"                                  \
    "    vec3 d = texelFetch(" S ", ivec2(i + 1, j + 1), 0).rgb;\n"                              \
    "    return (1.0 - t.y) * ((1.0 - t.x) * a + t.x * b) + t.y * ((1.0 - t.x) * c + t.x * d);\n" \
    "}\n"                                                                                       \
    "\n"

#define GLSL_PBR_ANGLES                                                                         \
    "    float ci = dot(n, wi), co = dot(n, wo);\n"                                              \
    "    if (!(ci > 0.0) || !(co > 0.0))\n"                                                      \
    "        return vec3(0.0);\n"                                                                \
    "    vec3 h = glint_unit(wi + wo);\n"                                                        \
    "    float ch = dot(n, h), cd = dot(wi, h), w = 1.0 - cd;\n"                                 \
    "    float w5 = w * w * w * w * w;\n"

#define GLSL_MAP_COEFS(R0)                                                                      \
    "vec3 glint_coefs(int b, vec2 uv)\n"                                                         \
    "{\n"                                                                                        \
    "    float m = float(u_map_res);\n"                                                          \
    "    float x = clamp(uv.x * m - 0.5, 0.0, m - 1.0);\n"                                       \
    "    float y = clamp(uv.y * m - 0.5, 0.0, m - 1.0);\n"                                       \
    "    int i0 = int(floor(x)), j0 = int(floor(y));\n"                                          \
    "    int i1 = min(i0 + 1, u_map_res - 1), j1 = min(j0 + 1, u_map_res - 1);\n"                \
    "    float fx = x - float(i0), fy = y - float(j0);\n"                                        \
    "    int r0 = " R0 " + b * u_map_res;\n"                                                     \
    "    vec3 a = texelFetch(u_maps, ivec2(i0, r0 + j0), 0).rgb;\n"                              \
    "    vec3 c = texelFetch(u_maps, ivec2(i1, r0 + j0), 0).rgb;\n"                              \
    "    vec3 d = texelFetch(u_maps, ivec2(i0, r0 + j1), 0).rgb;\n"                              \
    "    vec3 e = texelFetch(u_maps, ivec2(i1, r0 + j1), 0).rgb;\n"                              \
    "    return (1.0 - fy) * ((1.0 - fx) * a + fx * c) + fy * ((1.0 - fx) * d + fx * e);\n"      \
    "}\n"                                                                                        \
    "\n"

#define GLSL_PBR_LOBE                                                                           \
    "vec3 pbr_lobe(float alpha, vec3 ks, vec3 f0, float ci, float co, float ch, float w5)\n"   \
    "{\n"                                                                                       \
    "    float a2 = alpha * alpha, d = ch * ch * (a2 - 1.0) + 1.0;\n"                           \
    "    float D = a2 / (PI * d * d);\n"                                                        \
    "    float V = 0.5 / (co * sqrt(a2 + (1.0 - a2) * ci * ci) +\n"                             \
    "                     ci * sqrt(a2 + (1.0 - a2) * co * co));\n"                             \
    "    return ks * (D * V) * (f0 + (1.0 - f0) * w5);\n"                                       \
    "}\n"

/* tab_lookup(u, v): u = sqrt(theta_h / (pi/2)), v = theta_d / (pi/2); texel
 * (i, j) of u_table holds the node at u = i / (u_res_h - 1), v = j /
 * (u_res_d - 1) (texelFetch: no filtering needed). */
#define GLSL_TAB_LOOKUP                                                                         \
    "vec3 tab_lookup(float u, float v)\n"                                                       \
    "{\n"                                                                                       \
    "    float x = clamp(u, 0.0, 1.0) * float(u_res_h - 1);\n"                                  \
    "    float y = clamp(v, 0.0, 1.0) * float(u_res_d - 1);\n"                                  \
    "    int i = min(int(floor(x)), u_res_h - 2), j = min(int(floor(y)), u_res_d - 2);\n"      \
    "    float fu = x - float(i), fv = y - float(j);\n"                                         \
    "    vec3 a = texelFetch(u_table, ivec2(i, j), 0).rgb;\n"                                   \
    "    vec3 b = texelFetch(u_table, ivec2(i + 1, j), 0).rgb;\n"                               \
    "    vec3 c = texelFetch(u_table, ivec2(i, j + 1), 0).rgb;\n"                               \
    "    vec3 d = texelFetch(u_table, ivec2(i + 1, j + 1), 0).rgb;\n"                           \
    "    return mix(mix(a, b, fu), mix(c, d, fu), fv);\n"                                       \
    "}\n"

#define GLSL_MAIN                                                                               \
    "void main()\n"                                                                             \
    "{\n"                                                                                       \
    "    vec3 n = glint_unit(v_nrm);\n"                                                         \
    "    vec3 wi = glint_unit(u_light - v_pos);\n"                                              \
    "    vec3 wo = glint_unit(u_eye - v_pos);\n"                                                \
    "    o_color = vec4(glint_material(n, wi, wo) * u_light_intensity, 1.0);\n"                \
    "}\n"

#endif
