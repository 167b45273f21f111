/* glr_shaders.h: GLSL ES 3.00 sources of glr's programs, as C strings.
 * Private to the glr*.c files (and their tests).
 *
 * GLR_VERT_SRC is exactly what glr_shader_export() writes to
 * glint_material.vert, with the fragment stage of the material's method
 * (material_gpu, method.h) as glint_material.frag: the preview glint draws
 * and the shader handed to other renderers are the same text.  The
 * G-buffer and base-render fragment stages share the vertex stage.
 *
 * Conventions (must match raster.c, material_eval() and brdf_eval() on
 * the CPU):
 *  - a normal is renormalized after interpolation (left as is if zero);
 *  - wi = normalize(light - P), wo = normalize(eye - P), both world space;
 *  - a value is non-zero only where n.wi > 0 and n.wo > 0. */
#ifndef GLINT_GLR_SHADERS_H
#define GLINT_GLR_SHADERS_H

/* Vertex stage shared by every program. */
static const char GLR_VERT_SRC[] =
    "#version 300 es\n"
    "// glint_material.vert: vertex stage of a glint material (GLSL ES 3.00).\n"
    "// Written by glint (glr_shader_export); pair it with glint_material.frag.\n"
    "//\n"
    "// Binding contract (also in shader.json):\n"
    "//   in  location 0  a_position  vec3  object-space position\n"
    "//   in  location 1  a_normal    vec3  object-space vertex normal\n"
    "//   in  location 2  a_uv        vec2  texture coordinates (passed through)\n"
    "//   uniform mat4 u_model          object -> world (identity for glint's own views)\n"
    "//   uniform mat3 u_normal_matrix  inverse transpose of the upper 3x3 of u_model\n"
    "//   uniform mat4 u_view_proj      world -> clip (any pinhole camera)\n"
    "// Outputs the world-space position and normal the fragment stage shades.\n"
    "precision highp float;\n"
    "layout(location = 0) in vec3 a_position;\n"
    "layout(location = 1) in vec3 a_normal;\n"
    "layout(location = 2) in vec2 a_uv;\n"
    "uniform mat4 u_model;\n"
    "uniform mat3 u_normal_matrix;\n"
    "uniform mat4 u_view_proj;\n"
    "out vec3 v_pos;\n"
    "out vec3 v_nrm;\n"
    "out vec2 v_uv;\n"
    "void main()\n"
    "{\n"
    "    vec4 w = u_model * vec4(a_position, 1.0);\n"
    "    v_pos = w.xyz;\n"
    "    v_nrm = u_normal_matrix * a_normal;\n"
    "    v_uv = a_uv;\n"
    "    gl_Position = u_view_proj * w;\n"
    "}\n";

/* Fragment stage of the G-buffer pass: three float targets.
 *   0: position xyz, 1 (coverage)   1: unit normal xyz, 0   2: uv, 0, 0 */
static const char GLR_GBUF_FRAG_SRC[] =
    "#version 300 es\n"
    "precision highp float;\n"
    "in vec3 v_pos;\n"
    "in vec3 v_nrm;\n"
    "in vec2 v_uv;\n"
    "layout(location = 0) out vec4 o_pos;\n"
    "layout(location = 1) out vec4 o_nrm;\n"
    "layout(location = 2) out vec4 o_uv;\n"
    "void main()\n"
    "{\n"
    "    float l = length(v_nrm);\n"
    "    o_pos = vec4(v_pos, 1.0);\n"
    "    o_nrm = vec4(l > 0.0 ? v_nrm / l : v_nrm, 0.0);\n"
    "    o_uv = vec4(v_uv, 0.0, 0.0);\n"
    "}\n";

/* Fragment stage of the base render: brdf_eval() of brdf.c term by term,
 * times u_gain (scale x light intensity) x n.wi. */
static const char GLR_BASE_FRAG_SRC[] =
    "#version 300 es\n"
    "precision highp float;\n"
    "precision highp int;\n"
    "uniform vec3 u_eye;\n"
    "uniform vec3 u_light;\n"
    "uniform float u_gain;\n"
    "uniform int u_kind; // 0 lambert, 1 phong, 2 blinn, 3 ct (GGX), 4 ward\n"
    "uniform vec3 u_kd;\n"
    "uniform vec3 u_ks;\n"
    "uniform vec3 u_f0;\n"
    "uniform float u_exponent;\n"
    "uniform float u_rough;\n"
    "uniform float u_rough_y; // ward along b (v3_frame); 0: isotropic\n"
    "in vec3 v_pos;\n"
    "in vec3 v_nrm;\n"
    "in vec2 v_uv;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "const float PI = 3.14159265358979323846;\n"
    "\n"
    "vec3 glint_unit(vec3 v)\n"
    "{\n"
    "    float l = length(v);\n"
    "    return l > 0.0 ? v / l : v;\n"
    "}\n"
    "\n"
    "vec3 brdf(vec3 N, vec3 I, vec3 O, float ci, float co)\n"
    "{\n"
    "    vec3 spec = vec3(0.0);\n"
    "    if (u_kind == 1) {\n"
    "        vec3 r = N * (2.0 * ci) - I;\n"
    "        float rv = dot(r, O);\n"
    "        spec = u_ks * ((u_exponent + 2.0) / (2.0 * PI) * pow(max(rv, 0.0), u_exponent));\n"
    "    } else if (u_kind == 2) {\n"
    "        vec3 h = glint_unit(I + O);\n"
    "        float nh = dot(N, h);\n"
    "        spec = u_ks * ((u_exponent + 8.0) / (8.0 * PI) * pow(max(nh, 0.0), u_exponent));\n"
    "    } else if (u_kind == 3) {\n"
    "        float a2 = u_rough * u_rough;\n"
    "        vec3 h = glint_unit(I + O);\n"
    "        float ch = clamp(dot(N, h), 0.0, 1.0), hi = clamp(dot(h, I), 0.0, 1.0);\n"
    "        float t = ch * ch * (a2 - 1.0) + 1.0;\n"
    "        float D = a2 / (PI * t * t);\n"
    "        float cip = max(ci, 1e-12), cop = max(co, 1e-12);\n"
    "        float g1i = 2.0 * cip / (cip + sqrt(a2 + (1.0 - a2) * cip * cip));\n"
    "        float g1o = 2.0 * cop / (cop + sqrt(a2 + (1.0 - a2) * cop * cop));\n"
    "        float dgf = D * g1i * g1o / (4.0 * cip * cop);\n"
    "        float s5 = pow(1.0 - hi, 5.0);\n"
    "        spec = dgf * (u_f0 + (vec3(1.0) - u_f0) * s5);\n"
    "    } else if (u_kind == 4) {\n"
    "        float a2 = u_rough * u_rough;\n"
    "        vec3 h = glint_unit(I + O);\n"
    "        float ch = dot(N, h);\n"
    "        if (ch > 0.0 && u_rough_y > 0.0 && u_rough_y != u_rough) {\n"
    "            vec3 a = vec3(-N.y, N.x, 0.0);\n"
    "            float l = length(a);\n"
    "            vec3 t = l > 1e-6 ? a / l : vec3(1.0, 0.0, 0.0);\n"
    "            vec3 b = cross(N, t);\n"
    "            float ht = dot(h, t) / u_rough, hb = dot(h, b) / u_rough_y;\n"
    "            float e = (ht * ht + hb * hb) / (ch * ch);\n"
    "            spec = u_ks * (exp(-e) / (4.0 * PI * u_rough * u_rough_y * sqrt(ci * co)));\n"
    "        } else if (ch > 0.0) {\n"
    "            float c2 = ch > 1.0 ? 1.0 : ch * ch;\n"
    "            float tan2 = (1.0 - c2) / c2;\n"
    "            spec = u_ks * (exp(-tan2 / a2) / (4.0 * PI * a2 * sqrt(ci * co)));\n"
    "        }\n"
    "    }\n"
    "    return u_kd / PI + spec;\n"
    "}\n"
    "\n"
    "void main()\n"
    "{\n"
    "    vec3 n = glint_unit(v_nrm);\n"
    "    vec3 wi = glint_unit(u_light - v_pos);\n"
    "    vec3 wo = glint_unit(u_eye - v_pos);\n"
    "    float ci = dot(n, wi), co = dot(n, wo);\n"
    "    vec3 c = vec3(0.0);\n"
    "    if (ci > 0.0 && co > 0.0)\n"
    "        c = u_gain * brdf(n, wi, wo, ci, co) * ci;\n"
    "    o_color = vec4(c, 1.0);\n"
    "}\n";

/* Vertex stage of the vertex-colour draw (glr_vertex_colors): the colour of
 * vertex gl_VertexID is texel (id mod u_vcol_w, id / u_vcol_w) of an
 * RGBA32F texture on unit 1, interpolated across the triangle. */
static const char GLR_VCOL_VERT_SRC[] =
    "#version 300 es\n"
    "precision highp float;\n"
    "precision highp int;\n"
    "layout(location = 0) in vec3 a_position;\n"
    "layout(location = 1) in vec3 a_normal;\n"
    "layout(location = 2) in vec2 a_uv;\n"
    "uniform mat4 u_model;\n"
    "uniform mat3 u_normal_matrix;\n"
    "uniform mat4 u_view_proj;\n"
    "uniform highp sampler2D u_vcol;\n"
    "uniform int u_vcol_w;\n"
    "out vec3 v_col;\n"
    "void main()\n"
    "{\n"
    "    int id = gl_VertexID;\n"
    "    v_col = texelFetch(u_vcol, ivec2(id % u_vcol_w, id / u_vcol_w), 0).rgb;\n"
    "    gl_Position = u_view_proj * (u_model * vec4(a_position, 1.0));\n"
    "}\n";

/* Fragment stage of the vertex-colour draw: the colour, alpha 1 (coverage). */
static const char GLR_VCOL_FRAG_SRC[] =
    "#version 300 es\n"
    "precision highp float;\n"
    "in vec3 v_col;\n"
    "layout(location = 0) out vec4 o_col;\n"
    "void main()\n"
    "{\n"
    "    o_col = vec4(v_col, 1.0);\n"
    "}\n";

#endif
