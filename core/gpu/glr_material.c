/* glr_material.c: what a preview needs of a material, whatever its method:
 * the method's fragment stage compiled once per program name, its float
 * texture (uploaded only when it changes) and its uniforms (material_gpu,
 * method.h).  The draw itself is generic (glr_render.c, glr_draw.c). */
#include "glr.h"

#include <GLES3/gl3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal/glr_int.h"
#include "internal/glr_shaders.h"

int glr_material_gpu(const material *mat, material_gpu *gpu, glint_err *err)
{
    int rc;
    memset(gpu, 0, sizeof *gpu);
    if (!mat || !mat->method || !mat->data)
        return glint_err_set(err, GLINT_EINVAL, "material is NULL or empty");
    if ((rc = material_gpu_get(mat, gpu, err)))
        return rc;
    if (!gpu->frag_src || !gpu->program || strlen(gpu->program) >= sizeof(((glr_mprog *)0)->name)) {
        material_gpu_free(gpu);
        return glint_err_set(err, GLINT_EINTERNAL, "method %s gives no usable shader",
                             mat->method->name);
    }
    if (gpu->tex) {
        size_t n = (size_t)gpu->tex_w * gpu->tex_h * 3;
        if (gpu->tex_w < 1 || gpu->tex_h < 1 || !gpu->tex_uniform) {
            material_gpu_free(gpu);
            return glint_err_set(err, GLINT_EINTERNAL, "method %s gives a bad texture",
                                 mat->method->name);
        }
        for (size_t i = 0; i < n; i++)
            if (!isfinite(gpu->tex[i])) {
                material_gpu_free(gpu);
                return glint_err_set(err, GLINT_ENONFINITE,
                                     "material texture value %zu (texel %zu, row %zu) is not "
                                     "finite", i, (i / 3) % (size_t)gpu->tex_w,
                                     i / (3 * (size_t)gpu->tex_w));
            }
    }
    for (int i = 0; i < gpu->nuniforms; i++)
        for (int c = 0; c < 3; c++)
            if (!isfinite(gpu->uniform[i].v[c])) {
                material_gpu_free(gpu);
                return glint_err_set(err, GLINT_ENONFINITE, "material uniform %s is not finite",
                                     gpu->uniform[i].name);
            }
    return 0;
}

/* The program of a method (compiled on first use). */
static const glr_mprog *material_program(glr *g, const material_gpu *gpu, glint_err *err)
{
    static const float id4[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    static const float id3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    char what[64];
    glr_mprog *mp;

    for (int i = 0; i < g->nmprog; i++)
        if (strcmp(g->mprog[i].name, gpu->program) == 0)
            return &g->mprog[i];
    if (g->nmprog == GLR_MAX_MATERIAL_PROGS) {
        glint_err_set(err, GLINT_EUNSUPPORTED, "more than %d material programs",
                      GLR_MAX_MATERIAL_PROGS);
        return NULL;
    }
    mp = &g->mprog[g->nmprog];
    snprintf(what, sizeof what, "%s material program", gpu->program);
    if (!(mp->prog = glr_link(GLR_VERT_SRC, gpu->frag_src, what, err)))
        return NULL;
    g->st.gl_objects++;
    snprintf(mp->name, sizeof mp->name, "%s", gpu->program);
    glr_locs_get(mp->prog, &mp->loc);
    glUseProgram(mp->prog);
    glUniformMatrix4fv(mp->loc.model, 1, GL_FALSE, id4);
    glUniformMatrix3fv(mp->loc.normal_matrix, 1, GL_FALSE, id3);
    g->nmprog++;
    return mp;
}

/* Upload the material's texture (RGBA32F) to unit 0 unless it holds it. */
static int texture_upload(glr *g, const material_gpu *gpu, glint_err *err)
{
    int w = gpu->tex_w, h = gpu->tex_h, rc;
    size_t n = (size_t)w * h * 4;
    float *buf;
    int same;

    if (w > g->max_tex || h > g->max_tex)
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "material texture %dx%d above the texture limit %d", w, h,
                             (int)g->max_tex);
    if (!(buf = malloc(n * sizeof *buf)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a material texture");
    for (size_t t = 0; t < (size_t)w * h; t++) {
        for (int c = 0; c < 3; c++)
            buf[4 * t + c] = gpu->tex[3 * t + c];
        buf[4 * t + 3] = 0.0f;
    }
    same = g->mat_tex && g->mat_tex_w == w && g->mat_tex_h == h && g->mat_tex_cache &&
           memcmp(buf, g->mat_tex_cache, n * sizeof *buf) == 0;
    glActiveTexture(GL_TEXTURE0);
    if (!g->mat_tex) {
        glGenTextures(1, &g->mat_tex);
        g->st.gl_objects++;
    }
    glBindTexture(GL_TEXTURE_2D, g->mat_tex);
    if (same) {
        free(buf);
        return 0;
    }
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    if (g->mat_tex_w != w || g->mat_tex_h != h)
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, buf);
    else
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, buf);
    g->st.factor_uploads++;
    free(g->mat_tex_cache);
    g->mat_tex_cache = buf;
    g->mat_tex_w = w;
    g->mat_tex_h = h;
    if ((rc = glr_gl_check(err, "uploading the material texture"))) {
        g->mat_tex_w = g->mat_tex_h = 0; /* force a full re-specification next time */
        return rc;
    }
    return 0;
}

int glr_material_bind(glr *g, const material_gpu *gpu, const scene_view *v,
                      const glr_mprog **out, glint_err *err)
{
    const glr_mprog *mp = material_program(g, gpu, err);
    int rc;

    *out = NULL;
    if (!mp)
        return err ? err->code : GLINT_EINTERNAL;
    if (gpu->tex && (rc = texture_upload(g, gpu, err)))
        return rc;
    glUseProgram(mp->prog);
    if (gpu->tex)
        glUniform1i(glGetUniformLocation(mp->prog, gpu->tex_uniform), 0);
    for (int i = 0; i < gpu->nuniforms; i++) {
        const material_gpu_uniform *u = &gpu->uniform[i];
        GLint loc = glGetUniformLocation(mp->prog, u->name);
        if (strcmp(u->type, "int") == 0)
            glUniform1i(loc, (GLint)u->v[0]);
        else if (strcmp(u->type, "float") == 0)
            glUniform1f(loc, (float)u->v[0]);
        else
            glUniform3f(loc, (float)u->v[0], (float)u->v[1], (float)u->v[2]);
    }
    glUniform1f(mp->loc.light_intensity, (float)view_light_scale(v)); /* scene.h: pi I */
    *out = mp;
    return glr_gl_check(err, "binding the material");
}
