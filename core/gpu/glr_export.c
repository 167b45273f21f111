/* glr_export.c: the material's shader for other renderers (glr.h,
 * glr_shader_export): the same GLSL the preview draws with, the method's
 * texture and a manifest of how to bind them.  Needs no GL context. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "fsio.h"
#include "glr.h"
#include "internal/glr_int.h"
#include "internal/glr_shaders.h"

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

/* Per channel range of the method's texture (hi > lo: a constant channel
 * gets a range of 1 so that it decodes exactly). */
static void tex_range(const material_gpu *gpu, double lo[3], double hi[3])
{
    size_t n = (size_t)gpu->tex_w * gpu->tex_h;
    for (int c = 0; c < 3; c++) {
        lo[c] = n ? gpu->tex[c] : 0.0;
        hi[c] = lo[c];
    }
    for (size_t t = 0; t < n; t++)
        for (int c = 0; c < 3; c++) {
            double v = gpu->tex[3 * t + (size_t)c];
            lo[c] = v < lo[c] ? v : lo[c];
            hi[c] = v > hi[c] ? v : hi[c];
        }
    for (int c = 0; c < 3; c++)
        if (!(hi[c] > lo[c]))
            hi[c] = lo[c] + 1.0;
}

char *glr_glsl_desktop(const char *es)
{
    static const char v[] = "#version 330 core";
    const char *rest = strchr(es, '\n');
    size_t n;
    char *out;
    if (strncmp(es, "#version 300 es", 15) != 0 || !rest)
        return NULL;
    n = strlen(rest);
    if (!(out = malloc(sizeof v - 1 + n + 1)))
        return NULL;
    memcpy(out, v, sizeof v - 1);
    memcpy(out + sizeof v - 1, rest, n + 1);
    return out;
}

static json_t *uniform_value(const material_gpu_uniform *u)
{
    if (strcmp(u->type, "int") == 0)
        return json_integer((json_int_t)u->v[0]);
    if (strcmp(u->type, "float") == 0)
        return json_real(u->v[0]);
    return json_pack("[f, f, f]", u->v[0], u->v[1], u->v[2]);
}

/* shader.json: the generic binding (stages, attributes, the host's
 * uniforms), then the method's constants, texture and members. */
static json_t *glr_manifest(const material *mat, const material_gpu *gpu)
{
    const char *obj = "per object", *frame = "per frame", *light = "per light",
               *cst = "constant";
    json_t *root = json_object(), *attrs = json_array(), *unis = json_array();

    json_object_set_new(root, "format", json_string("glint-shader"));
    json_object_set_new(root, "version", json_integer(1));
    json_object_set_new(root, "language", json_string("GLSL ES 3.00 (OpenGL ES 3.0, WebGL 2)"));
    json_object_set_new(root, "vertex", json_string("glint_material.vert"));
    json_object_set_new(root, "fragment", json_string("glint_material.frag"));
    json_object_set_new(root, "method", json_string(material_method_name(mat)));
    json_array_append_new(attrs, glr_attribute("a_position", 0, "vec3",
                                               "object-space position"));
    json_array_append_new(attrs, glr_attribute("a_normal", 1, "vec3",
                                               "object-space vertex normal (renormalized "
                                               "per fragment)"));
    json_array_append_new(attrs, glr_attribute("a_uv", 2, "vec2",
                                               "texture coordinates (passed through)"));
    json_object_set_new(root, "attributes", attrs);
    json_array_append_new(unis, glr_uniform("u_model", "mat4", NULL, obj,
                                            "object -> world; identity when the mesh is in "
                                            "world space"));
    json_array_append_new(unis, glr_uniform("u_normal_matrix", "mat3", NULL, obj,
                                            "inverse transpose of the upper 3x3 of u_model"));
    json_array_append_new(unis, glr_uniform("u_view_proj", "mat4", NULL, frame,
                                            "world -> clip of the camera"));
    json_array_append_new(unis, glr_uniform("u_eye", "vec3", NULL, frame,
                                            "camera position, world space"));
    json_array_append_new(unis, glr_uniform("u_light", "vec3", NULL, light,
                                            "point light position, world space"));
    json_array_append_new(unis, glr_uniform("u_light_intensity", "float", json_real(GLINT_LIGHT_UNIT), light,
                                            "pi I for a point light of intensity I (no distance "
                                            "fall-off; a white Lambertian facing it reads I); the "
                                            "output is linear radiance"));
    if (gpu->tex)
        json_array_append_new(unis, glr_uniform(gpu->tex_uniform, "sampler2D", json_integer(0),
                                                cst, "texture unit holding the material's "
                                                     "texture"));
    for (int i = 0; i < gpu->nuniforms; i++)
        json_array_append_new(unis, glr_uniform(gpu->uniform[i].name, gpu->uniform[i].type,
                                                uniform_value(&gpu->uniform[i]), cst,
                                                gpu->uniform[i].meaning));
    json_object_set_new(root, "uniforms", unis);
    if (gpu->manifest)
        json_object_update(root, gpu->manifest);
    json_object_set_new(root, "output",
                        json_string("vec4(linear RGB radiance, 1) at location 0; 0 where "
                                    "n.wi <= 0 or n.wo <= 0"));
    json_object_set_new(root, "desktop",
                        json_pack("{s:s, s:s, s:s, s:s}", "language",
                                  "GLSL 3.30 core (OpenGL 3.3 and later)", "vertex",
                                  "glint_material_330.vert", "fragment",
                                  "glint_material_330.frag", "differs",
                                  "only in the #version line: the same code, bindings and "
                                  "results"));
    if (gpu->tex) {
        double lo[3], hi[3];
        tex_range(gpu, lo, hi);
        json_object_set_new(root, "texture_png16",
                            json_pack("{s:s, s:[f,f,f], s:[f,f,f], s:s}", "file",
                                      "glint_factors16.png", "min", lo[0], lo[1], lo[2], "max",
                                      hi[0], hi[1], hi[2], "decode",
                                      "value = min + (max - min) * v / 65535 per channel, v "
                                      "the 16-bit sample (RGB, the texture's layout): within "
                                      "(max - min) / 131070 of the float texture"));
    }
    return root;
}

/* The method's texture as EXR (RGB float) and raw RGBA half floats. */
static int write_texture(const material_gpu *gpu, const char *dir, glint_err *err)
{
    size_t n = (size_t)gpu->tex_w * gpu->tex_h;
    char path[4096];
    uint8_t *half;
    img tex;
    int rc;

    if ((rc = img_alloc(&tex, gpu->tex_w, gpu->tex_h, 3, err)))
        return rc;
    memcpy(tex.px, gpu->tex, 3 * n * sizeof(float));
    rc = fsio_join(path, sizeof path, dir, "glint_factors.exr", err);
    if (!rc)
        rc = img_write(path, &tex, err);
    img_free(&tex);
    if (rc)
        return rc;
    if (!(half = malloc(n * 4 * 2)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the half-float texture");
    for (size_t t = 0; t < n; t++)
        for (int c = 0; c < 4; c++) {
            uint16_t h = c < 3 ? glr_half(gpu->tex[3 * t + (size_t)c]) : 0;
            half[2 * (4 * t + (size_t)c)] = (uint8_t)(h & 0xff);
            half[2 * (4 * t + (size_t)c) + 1] = (uint8_t)(h >> 8);
        }
    rc = fsio_join(path, sizeof path, dir, "glint_factors_rgba16f.bin", err);
    if (!rc)
        rc = fsio_write_atomic(path, half, n * 4 * 2, err);
    free(half);
    if (rc)
        return rc;
    /* 16-bit PNG, each channel scaled to its range (shader.json: texture_png16) */
    {
        double lo[3], hi[3];
        tex_range(gpu, lo, hi);
        if ((rc = img_alloc(&tex, gpu->tex_w, gpu->tex_h, 3, err)))
            return rc;
        for (size_t t = 0; t < n; t++)
            for (int c = 0; c < 3; c++)
                tex.px[3 * t + (size_t)c] =
                    (float)((gpu->tex[3 * t + (size_t)c] - lo[c]) / (hi[c] - lo[c]));
        rc = fsio_join(path, sizeof path, dir, "glint_factors16.png", err);
        if (!rc)
            rc = img_write_png16(path, &tex, err);
        img_free(&tex);
    }
    return rc;
}

/* Write a text file dir/name. */
static int write_text(const char *dir, const char *name, const char *text, glint_err *err)
{
    char path[4096];
    int rc = fsio_join(path, sizeof path, dir, name, err);
    return rc ? rc : fsio_write_atomic(path, text, strlen(text), err);
}

int glr_shader_export(const material *mat, const char *dir, glint_err *err)
{
    char path[4096];
    material_gpu gpu;
    json_t *root = NULL;
    char *text = NULL;
    int rc;

    if ((rc = glr_material_gpu(mat, &gpu, err)))
        return rc;
    if (!dir || !*dir) {
        rc = glint_err_set(err, GLINT_EINVAL, "shader export: no directory");
        goto done;
    }
    if ((rc = fsio_mkdirs(dir, err)))
        goto done;
    rc = write_text(dir, "glint_material.vert", GLR_VERT_SRC, err);
    if (!rc)
        rc = write_text(dir, "glint_material.frag", gpu.frag_src, err);
    if (!rc) {
        char *v = glr_glsl_desktop(GLR_VERT_SRC), *f = glr_glsl_desktop(gpu.frag_src);
        if (!v || !f)
            rc = glint_err_set(err, GLINT_EINTERNAL, "a shader stage is not GLSL ES 3.00");
        if (!rc)
            rc = write_text(dir, "glint_material_330.vert", v, err);
        if (!rc)
            rc = write_text(dir, "glint_material_330.frag", f, err);
        free(v);
        free(f);
    }
    if (!rc && gpu.tex)
        rc = write_texture(&gpu, dir, err);
    if (rc)
        goto done;
    /* shader.json last: its presence means the export is complete */
    root = glr_manifest(mat, &gpu);
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
        glint_err_prefix(err, "exporting the shader to %s", dir ? dir : "");
    free(text);
    json_decref(root);
    material_gpu_free(&gpu);
    return rc;
}
