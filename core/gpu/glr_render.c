/* glr_render.c: the images a glr draws (glr.h): G-buffers, base renders
 * under an analytic BRDF and material previews.  Each checks its inputs,
 * draws once (glr_draw.c) and reads the target back; what a preview needs
 * of the material itself is in glr_material.c. */
#include "glr.h"

#include <GLES3/gl3.h>
#include <math.h>
#include <string.h>

#include "internal/glr_int.h"
#include "internal/glr_shaders.h"

/* ---- G-buffer ----------------------------------------------------------- */

typedef struct glr_gb_ctx {
    gbuf *g;
    int att;
    double eye[3], light[3];
} glr_gb_ctx;

static void glr_unit3(const double a[3], float out[3])
{
    double l = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double s = l > 0.0 ? 1.0 / l : 1.0;
    for (int c = 0; c < 3; c++)
        out[c] = (float)(a[c] * s);
}

static void glr_gb_strip(void *vctx, int row0, int nrows, const float *rgba)
{
    glr_gb_ctx *c = vctx;
    gbuf *g = c->g;
    size_t W = (size_t)g->width;

    for (int r = 0; r < nrows; r++) {
        for (size_t i = 0; i < W; i++) {
            const float *s = rgba + 4 * ((size_t)r * W + i);
            size_t p = (size_t)(row0 + r) * W + i;
            if (c->att == 0) {
                if (s[3] > 0.5f) {
                    double P[3] = {s[0], s[1], s[2]}, di[3], dout[3];
                    g->mask[p] = 1;
                    for (int k = 0; k < 3; k++) {
                        g->pos[3 * p + k] = s[k];
                        di[k] = c->light[k] - P[k];
                        dout[k] = c->eye[k] - P[k];
                    }
                    glr_unit3(di, g->wi + 3 * p);
                    glr_unit3(dout, g->wo + 3 * p);
                }
            } else if (g->mask[p]) {
                if (c->att == 1) {
                    for (int k = 0; k < 3; k++)
                        g->nrm[3 * p + k] = s[k];
                } else {
                    g->uv[2 * p] = s[0];
                    g->uv[2 * p + 1] = s[1];
                }
            }
        }
    }
}

static int glr_gbuffer_in(glr *g, const glr_mesh *m, const scene_view *v, int width,
                          int height, gbuf *out, glint_err *err)
{
    static const float clear0[4] = {0, 0, 0, 0};
    glr_gb_ctx c;
    int rc;

    if (out)
        memset(out, 0, sizeof *out);
    rc = glr_common_checks(g, m, v, width, height, out, err);
    if (rc)
        return rc;
    rc = glr_draw(g, g->prog[GLR_PROG_GBUF], &g->loc[GLR_PROG_GBUF], &g->gt, 3, m, v, width,
                  height, clear0, err);
    if (rc)
        return rc;
    rc = gbuf_alloc(out, width, height, err);
    if (rc)
        return rc;
    c.g = out;
    for (int k = 0; k < 3; k++) {
        c.eye[k] = v->eye[k];
        c.light[k] = v->light[k];
    }
    for (int att = 0; att < 3; att++) {
        c.att = att;
        rc = glr_readback(g, att, width, height, glr_gb_strip, &c, err);
        if (rc) {
            gbuf_free(out);
            return rc;
        }
    }
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    return 0;
}

/* ---- colour images ------------------------------------------------------ */

static void glr_rgb_strip(void *vctx, int row0, int nrows, const float *rgba)
{
    img *im = vctx;
    size_t n = (size_t)nrows * (size_t)im->width;
    float *o = im->px + (size_t)row0 * (size_t)im->width * 3;

    for (size_t p = 0; p < n; p++) {
        o[3 * p] = rgba[4 * p];
        o[3 * p + 1] = rgba[4 * p + 1];
        o[3 * p + 2] = rgba[4 * p + 2];
    }
}

static int glr_color_readback(glr *g, int w, int h, img *out, glint_err *err)
{
    int rc = img_alloc(out, w, h, 3, err);
    if (rc)
        return rc;
    rc = glr_readback(g, 0, w, h, glr_rgb_strip, out, err);
    if (rc)
        img_free(out);
    return rc;
}

static int glr_base_render_in(glr *g, const glr_mesh *m, const scene_view *v, int width,
                              int height, const brdf *b, double scale, float background,
                              img *out, glint_err *err)
{
    const glr_locs *l;
    float clear0[4], kd[3], ks[3], f0[3];
    int rc;

    if (out)
        memset(out, 0, sizeof *out);
    if (!b)
        return glint_err_set(err, GLINT_EINVAL, "brdf is NULL");
    if ((int)b->kind < BRDF_LAMBERT || (int)b->kind > BRDF_WARD)
        return glint_err_set(err, GLINT_EINVAL, "brdf kind %d is not a model", (int)b->kind);
    if (!isfinite(scale) || scale < 0.0)
        return glint_err_set(err, GLINT_EINVAL, "scale %g must be finite and >= 0", scale);
    if (!isfinite(background))
        return glint_err_set(err, GLINT_ENONFINITE, "background is not finite");
    for (int c = 0; c < 3; c++)
        if (!isfinite(b->kd[c]) || !isfinite(b->ks[c]) || !isfinite(b->f0[c]))
            return glint_err_set(err, GLINT_ENONFINITE, "brdf parameters are not finite");
    if ((b->kind == BRDF_PHONG || b->kind == BRDF_BLINN) &&
        !(b->exponent > 0.0 && isfinite(b->exponent)))
        return glint_err_set(err, GLINT_ERANGE, "brdf exponent %g must be > 0", b->exponent);
    if ((b->kind == BRDF_CT || b->kind == BRDF_WARD) &&
        !(b->roughness > 0.0 && b->roughness <= 1.0))
        return glint_err_set(err, GLINT_ERANGE, "brdf roughness %g outside (0, 1]",
                             b->roughness);
    rc = glr_common_checks(g, m, v, width, height, out, err);
    if (rc)
        return rc;

    l = &g->loc[GLR_PROG_BASE];
    for (int c = 0; c < 3; c++) {
        kd[c] = (float)b->kd[c];
        ks[c] = (float)b->ks[c];
        f0[c] = (float)b->f0[c];
    }
    glUseProgram(g->prog[GLR_PROG_BASE]);
    glUniform1f(l->gain, (float)(scale * view_light_scale(v)));
    glUniform1i(l->kind, (GLint)b->kind);
    glUniform3fv(l->kd, 1, kd);
    glUniform3fv(l->ks, 1, ks);
    glUniform3fv(l->f0, 1, f0);
    glUniform1f(l->exponent, (float)b->exponent);
    glUniform1f(l->rough, (float)b->roughness);
    glUniform1f(l->rough_y, (float)b->roughness_y);
    clear0[0] = clear0[1] = clear0[2] = background;
    clear0[3] = 0.0f;
    rc = glr_draw(g, g->prog[GLR_PROG_BASE], &g->loc[GLR_PROG_BASE], &g->ct, 1, m, v, width,
                  height, clear0, err);
    if (rc)
        return rc;
    return glr_color_readback(g, width, height, out, err);
}

/* ---- material previews -------------------------------------------------- */

static int glr_preview_in(glr *g, const glr_mesh *m, const material *mat,
                          const scene_view *v, int width, int height, float background,
                          img *out, glint_err *err)
{
    const glr_mprog *mp;
    material_gpu gpu;
    float clear0[4];
    int rc;

    if (out)
        memset(out, 0, sizeof *out);
    if (!isfinite(background))
        return glint_err_set(err, GLINT_ENONFINITE, "background is not finite");
    if ((rc = glr_material_gpu(mat, &gpu, err)))
        return rc;
    if ((rc = glr_common_checks(g, m, v, width, height, out, err)) ||
        (rc = glr_material_bind(g, &gpu, v, &mp, err)))
        goto done;
    clear0[0] = clear0[1] = clear0[2] = background;
    clear0[3] = 0.0f;
    if ((rc = glr_draw(g, mp->prog, &mp->loc, &g->ct, 1, m, v, width, height, clear0, err)))
        goto done;
    rc = glr_color_readback(g, width, height, out, err);
done:
    material_gpu_free(&gpu);
    return rc;
}

/* ---- public entry points: enter, work, leave ----------------------------- */

int glr_gbuffer(glr *g, const glr_mesh *m, const scene_view *v, int width, int height,
                gbuf *out, glint_err *err)
{
    int rc = glr_gbuffer_in(g, m, v, width, height, out, err);
    glr_leave(g);
    return rc;
}

int glr_base_render(glr *g, const glr_mesh *m, const scene_view *v, int width, int height,
                    const brdf *b, double scale, float background, img *out, glint_err *err)
{
    int rc = glr_base_render_in(g, m, v, width, height, b, scale, background, out, err);
    glr_leave(g);
    return rc;
}

int glr_preview(glr *g, const glr_mesh *m, const material *mat, const scene_view *v,
                int width, int height, float background, img *out, glint_err *err)
{
    int rc = glr_preview_in(g, m, mat, v, width, height, background, out, err);
    glr_leave(g);
    return rc;
}

/* ---- a caller's fragment stage (checking exported shaders) ------------------ */

static int glr_render_fragment_in(glr *g, const glr_mesh *m, const char *frag_src,
                                  const scene_view *v, int width, int height, img *out,
                                  glint_err *err)
{
    glr_locs l;
    GLuint p;
    float clear0[4] = {0, 0, 0, 0};
    int rc;

    if (out)
        memset(out, 0, sizeof *out);
    if (!frag_src)
        return glint_err_set(err, GLINT_EINVAL, "no fragment stage");
    if ((rc = glr_common_checks(g, m, v, width, height, out, err)))
        return rc;
    glr_gl_drain();
    if (!(p = glr_link(GLR_VERT_SRC, frag_src, "the caller's program", err)))
        return err ? err->code : GLINT_EFORMAT;
    glr_locs_get(p, &l);
    glUseProgram(p);
    {
        static const float id4[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        static const float id3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        glUniformMatrix4fv(l.model, 1, GL_FALSE, id4);
        glUniformMatrix3fv(l.normal_matrix, 1, GL_FALSE, id3);
    }
    glUniform1f(l.light_intensity, (float)view_light_scale(v));
    rc = glr_draw(g, p, &l, &g->ct, 1, m, v, width, height, clear0, err);
    if (!rc)
        rc = glr_color_readback(g, width, height, out, err);
    glDeleteProgram(p);
    return rc;
}

int glr_render_fragment(glr *g, const glr_mesh *m, const char *frag_src, const scene_view *v,
                        int width, int height, img *out, glint_err *err)
{
    int rc = glr_render_fragment_in(g, m, frag_src, v, width, height, out, err);
    glr_leave(g);
    return rc;
}
