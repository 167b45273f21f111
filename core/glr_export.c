/* glr_export.c: the material's shader for other renderers (glr.h,
 * glr_shader_export): the same GLSL the preview draws with, the factor
 * texture and a manifest of how to bind them.  Needs no GL context. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "fsio.h"
#include "glr.h"
#include "glr_int.h"
#include "glr_shaders.h"

/* ------------------------------------------------------------------------ */
/* Shader export                                                             */
/* ------------------------------------------------------------------------ */

/* IEEE half from float, round to nearest even (overflow -> inf). */
static uint16_t glr_half(float x)
{
    union {
        float f;
        uint32_t u;
    } v;
    uint32_t sign, exp, man;

    v.f = x;
    sign = (v.u >> 16) & 0x8000u;
    exp = (v.u >> 23) & 0xffu;
    man = v.u & 0x7fffffu;
    if (exp == 0xffu) /* inf or NaN */
        return (uint16_t)(sign | 0x7c00u | (man ? 0x200u : 0u));
    {
        int e = (int)exp - 127 + 15;
        if (e >= 31)
            return (uint16_t)(sign | 0x7c00u);
        if (e <= 0) { /* subnormal half or zero */
            uint32_t m, shift, r, half;
            if (e < -10)
                return (uint16_t)sign;
            m = man | 0x800000u;
            shift = (uint32_t)(14 - e);
            r = m >> shift;
            half = 1u << (shift - 1);
            if ((m & ((1u << shift) - 1)) > half || ((m & ((1u << shift) - 1)) == half && (r & 1u)))
                r++;
            return (uint16_t)(sign | r);
        }
        {
            uint32_t h = ((uint32_t)e << 10) | (man >> 13);
            uint32_t rest = man & 0x1fffu;
            if (rest > 0x1000u || (rest == 0x1000u && (h & 1u)))
                h++; /* may carry into the exponent: still correct */
            return (uint16_t)(sign | h);
        }
    }
}

static const char *glr_map_name(hf_map_kind k)
{
    return k == HF_MAP_ADD ? "add" : k == HF_MAP_SUB ? "sub" : "log";
}

/* One uniform of the manifest.  A uniform with a value is a constant of
 * this material (set it once to that value); one without is set by the
 * host renderer ("set": per object, per frame or per light). */
static json_t *glr_uniform(const char *name, const char *type, json_t *value, const char *set,
                           const char *what)
{
    json_t *u = json_object();
    json_object_set_new(u, "name", json_string(name));
    json_object_set_new(u, "type", json_string(type));
    json_object_set_new(u, "value", value ? value : json_null());
    json_object_set_new(u, "set", json_string(set));
    json_object_set_new(u, "meaning", json_string(what));
    return u;
}

static json_t *glr_attribute(const char *name, int loc, const char *type, const char *what)
{
    json_t *a = json_object();
    json_object_set_new(a, "name", json_string(name));
    json_object_set_new(a, "location", json_integer(loc));
    json_object_set_new(a, "type", json_string(type));
    json_object_set_new(a, "meaning", json_string(what));
    return a;
}

static json_t *glr_manifest(const material *mat)
{
    const hf_factors *f = &mat->fac;
    char mapbuf[96];
    json_t *root = json_object(), *attrs = json_array(), *unis = json_array(),
           *tex = json_object(), *files = json_object(), *rows = json_array(),
           *a = json_array(), *kinds = json_object(), *map = json_object();

    hf_map_format(&f->map, mapbuf, sizeof mapbuf);
    for (int c = 0; c < 3; c++)
        json_array_append_new(a, json_real(f->a_used[c]));
    json_object_set_new(root, "format", json_string("glint-shader"));
    json_object_set_new(root, "version", json_integer(1));
    json_object_set_new(root, "language", json_string("GLSL ES 3.00 (OpenGL ES 3.0, WebGL 2)"));
    json_object_set_new(root, "vertex", json_string("glint_material.vert"));
    json_object_set_new(root, "fragment", json_string("glint_material.frag"));
    json_object_set_new(root, "method", json_string(mat->method[0] ? mat->method : "hf3"));
    json_object_set_new(root, "res", json_integer(f->res));
    json_object_set_new(root, "model",
                        json_string(f->model == HF_MODEL_BRDF ? "brdf" : "radiance"));

    json_object_set_new(map, "spec", json_string(mapbuf));
    json_object_set_new(map, "kind", json_string(glr_map_name(f->map.kind)));
    json_object_set_new(map, "u_map_kind", json_integer((int)f->map.kind));
    json_object_set_new(map, "a_used", a);
    json_object_set_new(map, "inverse",
                        json_string(f->map.kind == HF_MAP_ADD   ? "max(pqr - a, 0)"
                                    : f->map.kind == HF_MAP_SUB ? "max(a - pqr, 0)"
                                                                : "pqr"));
    json_object_set_new(root, "mapping", map);

    json_array_append_new(attrs, glr_attribute("a_position", 0, "vec3",
                                               "object-space position"));
    json_array_append_new(attrs, glr_attribute("a_normal", 1, "vec3",
                                               "object-space vertex normal (renormalized "
                                               "per fragment)"));
    json_array_append_new(attrs, glr_attribute("a_uv", 2, "vec2",
                                               "texture coordinates (passed through, unused "
                                               "by this material)"));
    json_object_set_new(root, "attributes", attrs);

    {
        const char *obj = "per object", *frame = "per frame", *light = "per light",
                   *cst = "constant";
        json_t *u[] = {
            glr_uniform("u_model", "mat4", NULL, obj,
                        "object -> world; identity when the mesh is in world space"),
            glr_uniform("u_normal_matrix", "mat3", NULL, obj,
                        "inverse transpose of the upper 3x3 of u_model"),
            glr_uniform("u_view_proj", "mat4", NULL, frame, "world -> clip of the camera"),
            glr_uniform("u_eye", "vec3", NULL, frame, "camera position, world space"),
            glr_uniform("u_light", "vec3", NULL, light, "point light position, world space"),
            glr_uniform("u_light_intensity", "float", json_real(1.0), light,
                        "light intensity (no distance fall-off); the output is linear "
                        "radiance"),
            glr_uniform("u_factors", "sampler2D", json_integer(0), cst,
                        "texture unit holding the factor texture"),
            glr_uniform("u_res", "int", json_integer(f->res), cst, "texels per factor"),
            glr_uniform("u_map_kind", "int", json_integer((int)f->map.kind), cst,
                        "inverse mapping: 0 log, 1 add, 2 sub"),
            glr_uniform("u_a", "vec3", json_deep_copy(a), cst,
                        "mapping offset per channel (a_used)"),
            glr_uniform("u_model_brdf", "int", json_integer(f->model == HF_MODEL_BRDF), cst,
                        "1: multiply by n.wi (brdf model); 0: radiance model"),
        };
        for (size_t i = 0; i < sizeof u / sizeof u[0]; i++)
            json_array_append_new(unis, u[i]);
    }
    json_object_set_new(root, "uniforms", unis);

    json_array_append_new(rows, json_string("log p (pi_p: wi on the tangent plane)"));
    json_array_append_new(rows, json_string("log q (pi_q: h on the tangent plane)"));
    json_array_append_new(rows, json_string("log r (pi_r: wo on the tangent plane)"));
    json_object_set_new(files, "exr", json_string("glint_factors.exr"));
    json_object_set_new(files, "rgba16f", json_string("glint_factors_rgba16f.bin"));
    json_object_set_new(tex, "uniform", json_string("u_factors"));
    json_object_set_new(tex, "files", files);
    json_object_set_new(tex, "width", json_integer(f->res));
    json_object_set_new(tex, "height", json_integer(3));
    json_object_set_new(tex, "rows", rows);
    json_object_set_new(tex, "values",
                        json_string("natural log of the factor value, per RGB channel; "
                                    "the material is inverse_map(exp(log p + log q + log r))"));
    json_object_set_new(tex, "texels",
                        json_string("node convention: texel k at u = k / (res - 1); "
                                    "the shader fetches texels with texelFetch and "
                                    "interpolates linearly itself"));
    json_object_set_new(tex, "internal_format", json_string("RGBA16F or RGBA32F"));
    json_object_set_new(tex, "filter", json_string("NEAREST, no mipmaps, CLAMP_TO_EDGE"));
    json_object_set_new(tex, "exr_layout",
                        json_string("RGB float, res x 3 pixels, image row 0 = p, 1 = q, 2 = r"));
    json_object_set_new(tex, "rgba16f_layout",
                        json_string("raw IEEE half floats, little endian, RGBA (A = 0), "
                                    "row-major, row 0 = p, 1 = q, 2 = r: upload as is with "
                                    "texImage2D(TEXTURE_2D, 0, RGBA16F, res, 3, 0, RGBA, "
                                    "HALF_FLOAT, data)"));
    json_object_set_new(root, "texture", tex);
    json_object_set_new(kinds, "log", json_integer(0));
    json_object_set_new(kinds, "add", json_integer(1));
    json_object_set_new(kinds, "sub", json_integer(2));
    json_object_set_new(root, "map_kinds", kinds);
    json_object_set_new(root, "output",
                        json_string("vec4(linear RGB radiance, 1) at location 0; 0 where "
                                    "n.wi <= 0 or n.wo <= 0"));
    return root;
}

int glr_shader_export(const material *mat, const char *dir, glint_err *err)
{
    char path[4096];
    img tex;
    uint8_t *half = NULL;
    json_t *root = NULL;
    char *text = NULL;
    int R, rc;

    memset(&tex, 0, sizeof tex);
    rc = glr_material_ok(mat, err);
    if (rc)
        return rc;
    if (!dir || !*dir)
        return glint_err_set(err, GLINT_EINVAL, "shader export: no directory");
    rc = fsio_mkdirs(dir, err);
    if (rc)
        return rc;
    R = mat->fac.res;

    rc = fsio_join(path, sizeof path, dir, "glint_material.vert", err);
    if (!rc)
        rc = fsio_write_atomic(path, GLR_VERT_SRC, strlen(GLR_VERT_SRC), err);
    if (!rc)
        rc = fsio_join(path, sizeof path, dir, "glint_material.frag", err);
    if (!rc)
        rc = fsio_write_atomic(path, GLR_PREVIEW_FRAG_SRC, strlen(GLR_PREVIEW_FRAG_SRC), err);
    if (rc)
        goto done;

    /* factor texture as EXR: res x 3, RGB log values */
    rc = img_alloc(&tex, R, 3, 3, err);
    if (rc)
        goto done;
    for (size_t i = 0; i < (size_t)9 * R; i++)
        tex.px[i] = (float)mat->fac.logf[i];
    rc = fsio_join(path, sizeof path, dir, "glint_factors.exr", err);
    if (!rc)
        rc = img_write(path, &tex, err);
    if (rc)
        goto done;

    /* the same as raw RGBA16F */
    half = malloc((size_t)R * 3 * 4 * 2);
    if (!half) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the half-float texture");
        goto done;
    }
    for (size_t t = 0; t < (size_t)3 * R; t++)
        for (int c = 0; c < 4; c++) {
            uint16_t h = c < 3 ? glr_half((float)mat->fac.logf[3 * t + (size_t)c]) : 0;
            half[2 * (4 * t + (size_t)c)] = (uint8_t)(h & 0xff);
            half[2 * (4 * t + (size_t)c) + 1] = (uint8_t)(h >> 8);
        }
    rc = fsio_join(path, sizeof path, dir, "glint_factors_rgba16f.bin", err);
    if (!rc)
        rc = fsio_write_atomic(path, half, (size_t)R * 3 * 4 * 2, err);
    if (rc)
        goto done;

    root = glr_manifest(mat);
    text = root ? json_dumps(root, JSON_INDENT(2) | JSON_REAL_PRECISION(17)) : NULL;
    if (!text) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for shader.json");
        goto done;
    }
    rc = fsio_join(path, sizeof path, dir, "shader.json", err);
    if (!rc)
        rc = fsio_write_atomic(path, text, strlen(text), err);

done:
    if (rc)
        glint_err_prefix(err, "exporting the shader to %s", dir);
    free(text);
    json_decref(root);
    free(half);
    img_free(&tex);
    return rc;
}
