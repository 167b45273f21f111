/* brdfx.c: BRDF Explorer's analytic .brdf file for any method, from the
 * material's own GPU evaluation (method.h, material_ops.gpu).
 *
 * BRDF Explorer (Walt Disney Animation Studios) compiles the GLSL between
 * "::begin shader" and "::end shader" into its plots and lit views and
 * calls vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y); its parameters
 * ("::begin parameters": float NAME MIN MAX DEFAULT) become uniforms with
 * sliders.  It binds no textures and no uniforms of its own choosing, so
 * the method's fragment stage is rewritten here:
 *   - its constant uniforms become constants with the material's values;
 *   - its one texture becomes a constant array of vec3 (row-major, row 0
 *     first) read by glint_fetch(p, lod), which replaces texelFetch(tex, p,
 *     lod) exactly (texels are fetched, never filtered, by every method);
 *     infinite texels (a log-factor of 0) are written as -+1e30, which the
 *     stages take through exp() to 0 or clamp as they do infinity;
 *   - the stage's header comment (its bindings) and the renderer's inputs (u_eye, u_light, u_light_intensity, v_pos,
 *     v_nrm, o_color) and main() are dropped; v_uv, which only materials
 *     that vary over the surface read, becomes the point (surface_u,
 *     surface_v): two parameters, so BRDF Explorer's sliders walk the
 *     surface;
 *   - BRDF(L, V, N, X, Y) = glint_material(N, L, V) / (N.L): the stage's
 *     radiance per unit light divided by the cosine, 0 below either
 *     horizon.  X and Y are not read: each method builds its own tangent
 *     frame from N as it does on the GPU and the CPU (the method's header).
 * The result is the same text that runs in glint's previews, so it
 * evaluates the material exactly as glint does (tests/unit/test_brdfx.c
 * renders it against the CPU's evaluation for every method).
 * Thread-safety: reads the material only. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdfx.h"
#include "buf.h"
#include "method.h"

/* Texels beyond this make a shader that compilers take long over (Mesa's
 * llvmpipe: 80 KB of text in 1.6 s, 280 KB in 14 s, 134,400 texels not in 10
 * minutes): the MERL table is offered instead. */
#define BRDFX_MAX_TEXELS 8192

/* A float as a GLSL literal (always with a point or exponent; infinities
 * as +-1e30). */
static int put_float(glint_buf *b, double v)
{
    if (isinf(v))
        v = v > 0 ? 1e30 : -1e30;
    return glint_buf_printf(b, "%.9e", v);
}

/* Is `name` the identifier at s (not part of a longer one)? */
static int ident_at(const char *line, const char *s, const char *name)
{
    size_t n = strlen(name);
    if (strncmp(s, name, n))
        return 0;
    if (s > line && (isalnum((unsigned char)s[-1]) || s[-1] == '_'))
        return 0;
    return !(isalnum((unsigned char)s[n]) || s[n] == '_');
}

/* One line of the stage's body with texelFetch(tex, and v_uv replaced. */
static int put_body_line(glint_buf *b, const char *line, size_t len, const char *tex)
{
    char fetch[96];
    size_t fl = 0;
    int rc = 0;
    if (tex)
        fl = (size_t)snprintf(fetch, sizeof fetch, "texelFetch(%s, ", tex);
    for (size_t i = 0; i < len && !rc;) {
        const char *s = line + i;
        if (tex && len - i >= fl && !strncmp(s, fetch, fl)) {
            rc = glint_buf_printf(b, "glint_fetch(");
            i += fl;
        } else if (len - i >= 4 && ident_at(line, s, "v_uv")) {
            rc = glint_buf_printf(b, "vec2(surface_u, surface_v)");
            i += 4;
        } else {
            rc = glint_buf_append(b, s, 1);
            i++;
        }
    }
    return rc ? rc : glint_buf_append(b, "\n", 1);
}

static const material_gpu_uniform *find_uniform(const material_gpu *g, const char *name,
                                                size_t len)
{
    for (int i = 0; i < g->nuniforms; i++)
        if (strlen(g->uniform[i].name) == len && !strncmp(g->uniform[i].name, name, len))
            return &g->uniform[i];
    return NULL;
}

static int put_uniform(glint_buf *b, const material_gpu_uniform *u)
{
    int rc;
    if (!strcmp(u->type, "int"))
        return glint_buf_printf(b, "const int %s = %d; // %s\n", u->name, (int)u->v[0],
                                u->meaning);
    if (!strcmp(u->type, "float")) {
        rc = glint_buf_printf(b, "const float %s = ", u->name);
        rc |= put_float(b, u->v[0]);
        return rc | glint_buf_printf(b, "; // %s\n", u->meaning);
    }
    rc = glint_buf_printf(b, "const vec3 %s = vec3(", u->name);
    for (int c = 0; c < 3; c++) {
        rc |= put_float(b, u->v[c]);
        rc |= glint_buf_printf(b, c < 2 ? ", " : "); // %s\n", u->meaning);
    }
    return rc;
}

static int put_texture(glint_buf *b, const material_gpu *g)
{
    int W = g->tex_w, H = g->tex_h, rc;
    long n = (long)W * H;
    rc = glint_buf_printf(b, "// %s: %d x %d texels, row-major, row 0 first\n", g->tex_uniform,
                          W, H);
    rc |= glint_buf_printf(b, "const vec3 glint_tex[%ld] = vec3[%ld](\n", n, n);
    for (long i = 0; i < n && !rc; i++) {
        rc |= glint_buf_printf(b, "    vec3(");
        for (int c = 0; c < 3; c++) {
            rc |= put_float(b, g->tex[3 * i + c]);
            rc |= glint_buf_printf(b, c < 2 ? ", " : i + 1 < n ? ")," : "));");
        }
        rc |= glint_buf_append(b, "\n", 1);
    }
    rc |= glint_buf_printf(b,
                           "\n"
                           "vec4 glint_fetch(ivec2 p, int lod)\n"
                           "{\n"
                           "    return vec4(glint_tex[clamp(p.x, 0, %d) + %d * clamp(p.y, 0, %d)],"
                           " 1.0);\n"
                           "}\n"
                           "\n",
                           W - 1, W, H - 1);
    return rc;
}

/* Check what the rewrite relies on: finite texels and uniforms, a texture
 * of a sane size, a stage that defines glint_material and ends in main(). */
static int check_gpu(const material_gpu *g, const char *meth, glint_err *err)
{
    long n = (long)g->tex_w * g->tex_h;
    if (!g->frag_src || !strstr(g->frag_src, "vec3 glint_material(vec3 n, vec3 wi, vec3 wo)") ||
        !strstr(g->frag_src, "\nvoid main()"))
        return glint_err_set(err, GLINT_EINTERNAL,
                             "method %s's fragment stage has no glint_material() and main()",
                             meth);
    if (g->tex_uniform) {
        if (!g->tex || g->tex_w < 1 || g->tex_h < 1)
            return glint_err_set(err, GLINT_EINTERNAL, "method %s's texture is empty", meth);
        if (n > BRDFX_MAX_TEXELS)
            return glint_err_set(err, GLINT_EUNSUPPORTED,
                                 "the material's texture has %ld texels, more than the %d a "
                                 ".brdf file embeds (fit with a smaller map_res, s_res or "
                                 "res); its MERL table (merl.binary, glint export-merl) opens "
                                 "in BRDF Explorer too",
                                 n, BRDFX_MAX_TEXELS);
        for (long i = 0; i < 3 * n; i++)
            if (isnan(g->tex[i]))
                return glint_err_set(err, GLINT_EINVAL,
                                     "the material's texture holds NaN at texel %ld", i / 3);
    }
    for (int i = 0; i < g->nuniforms; i++)
        for (int c = 0; c < 3; c++)
            if (!isfinite(g->uniform[i].v[c]))
                return glint_err_set(err, GLINT_EINVAL, "the material's %s is not finite",
                                     g->uniform[i].name);
    return 0;
}

/* The lines of the stage, rewritten (see the top of the file). */
static int put_stage(glint_buf *b, const material_gpu *g, const char *meth, glint_err *err)
{
    static const char *const dropped[] = {"u_eye", "u_light", "u_light_intensity"};
    const char *s = g->frag_src;
    int rc = 0;

    while (*s && !rc) {
        const char *e = strchr(s, '\n');
        size_t len = e ? (size_t)(e - s) : strlen(s);
        const char *next = e ? e + 1 : s + len;
        char type[32], name[64];
        if (!strncmp(s, "void main()", 11))
            break; /* the renderer's shading: the last function of every stage */
        if (!strncmp(s, "#version", 8) || !strncmp(s, "precision ", 10) ||
            !strncmp(s, "//", 2) || /* the stage's header: its bindings, gone here */
            !strncmp(s, "in ", 3) || !strncmp(s, "layout(", 7)) {
            s = next;
            continue;
        }
        if (!strncmp(s, "uniform ", 8)) {
            const material_gpu_uniform *u;
            int k = sscanf(s, "uniform highp sampler2D %63[A-Za-z0-9_];", name);
            if (k == 1 || sscanf(s, "uniform sampler2D %63[A-Za-z0-9_];", name) == 1) {
                if (!g->tex_uniform || strcmp(name, g->tex_uniform))
                    return glint_err_set(err, GLINT_EINTERNAL,
                                         "method %s's sampler %s is not its texture", meth,
                                         name);
                rc = put_texture(b, g);
            } else if (sscanf(s, "uniform %31s %63[A-Za-z0-9_];", type, name) == 2) {
                int drop = 0;
                for (size_t i = 0; i < sizeof dropped / sizeof *dropped; i++)
                    drop |= !strcmp(name, dropped[i]);
                if (!drop) {
                    if (!(u = find_uniform(g, name, strlen(name))))
                        return glint_err_set(err, GLINT_EINTERNAL,
                                             "method %s's uniform %s has no value", meth,
                                             name);
                    rc = put_uniform(b, u);
                }
            } else {
                return glint_err_set(err, GLINT_EINTERNAL,
                                     "method %s's stage declares '%.*s'", meth, (int)len, s);
            }
            s = next;
            continue;
        }
        rc = put_body_line(b, s, len, g->tex_uniform);
        s = next;
    }
    return rc ? glint_err_set(err, GLINT_ENOMEM, "out of memory for the .brdf text") : 0;
}

int brdfx_from_gpu(const material *m, char **text, glint_err *err)
{
    const char *name = material_method_name(m);
    int spatial = material_spatial(m), rc;
    material_gpu g;
    glint_buf b = {0};

    *text = NULL;
    if ((rc = material_gpu_get(m, &g, err))) {
        if (rc == GLINT_EUNSUPPORTED)
            glint_err_prefix(err, "no .brdf file: its MERL table (merl.binary) opens in BRDF "
                                  "Explorer instead");
        return rc;
    }
    if ((rc = check_gpu(&g, name, err)))
        goto done;
    rc = glint_buf_printf(
        &b,
        "analytic\n"
        "\n"
        "# A glint material (method %s), written from the GLSL that glint's previews\n"
        "# run: BRDF(L, V, N, X, Y) = glint_material(N, L, V) / N.L, the material's\n"
        "# f cos over the cosine (0 below either horizon).  X and Y\n"
        "# are not read: the method builds its tangent frame from N as glint does.\n"
        "# The material is the BRDF of what was painted: a painted value is pi I f cos\n"
        "# under a light of intensity I (a white Lambertian facing it reads I).\n"
        "%s"
        "\n"
        "::begin parameters\n"
        "%s"
        "::end parameters\n"
        "\n"
        "::begin shader\n"
        "\n",
        name,
        spatial ? "# The material varies over the surface: it is evaluated at the surface\n"
                  "# point of texture coordinates (surface_u, surface_v), the parameters.\n"
                : "",
        spatial ? "float surface_u 0 1 0.5\nfloat surface_v 0 1 0.5\n" : "");
    if (rc) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the .brdf text");
        goto done;
    }
    if ((rc = put_stage(&b, &g, name, err)))
        goto done;
    if (glint_buf_printf(&b,
                         "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)\n"
                         "{\n"
                         "    float ci = dot(N, L);\n"
                         "    if (!(ci > 0.0) || !(dot(N, V) > 0.0))\n"
                         "        return vec3(0.0);\n"
                         "    return glint_material(N, L, V) / ci;\n"
                         "}\n"
                         "\n"
                         "::end shader\n")) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the .brdf text");
        goto done;
    }
    if (!(*text = glint_buf_steal(&b, NULL)))
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
done:
    glint_buf_free(&b);
    material_gpu_free(&g);
    return rc;
}

int brdfx_material(const material *m, char **text, glint_err *err)
{
    *text = NULL;
    if (!m || !m->method)
        return glint_err_set(err, GLINT_EINVAL, "no material");
    if (!m->method->mat->brdf_explorer)
        return brdfx_from_gpu(m, text, err);
    return m->method->mat->brdf_explorer(m->data, text, err);
}
