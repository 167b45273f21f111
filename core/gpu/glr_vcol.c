/* glr_vcol.c: draws with one colour per vertex (glr.h, glr_vertex_colors).
 * The colours travel in an RGBA32F texture on unit 1 that the vertex
 * stage reads by gl_VertexID (GLR_VCOL_VERT_SRC), so the mesh's vertex
 * arrays stay as uploaded. */
#include "glr.h"

#include <GLES3/gl3.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal/glr_int.h"

typedef struct vcol_rb {
    img *im;
    uint8_t *mask;
    float background;
} vcol_rb;

static void vcol_strip(void *vctx, int row0, int nrows, const float *rgba)
{
    vcol_rb *c = vctx;
    size_t n = (size_t)nrows * (size_t)c->im->width, at = (size_t)row0 * c->im->width;
    float *o = c->im->px + at * 3;
    for (size_t p = 0; p < n; p++) {
        int cov = rgba[4 * p + 3] > 0.5f;
        for (int e = 0; e < 3; e++)
            o[3 * p + e] = cov ? rgba[4 * p + e] : c->background;
        if (c->mask)
            c->mask[at + p] = (uint8_t)cov;
    }
}

/* Upload the colours to the texture (made or resized when needed). */
static int vcol_upload(glr *g, const float *rgb, int nverts, int *tw, glint_err *err)
{
    int w = nverts < g->max_tex ? nverts : g->max_tex, h = (nverts + w - 1) / w;
    float *buf;
    if (h > g->max_tex)
        return glint_err_set(err, GLINT_ERANGE,
                             "%d vertices do not fit a %dx%d colour texture", nverts,
                             g->max_tex, g->max_tex);
    if (!(buf = calloc((size_t)w * h * 4, sizeof *buf)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for vertex colours");
    for (int i = 0; i < nverts; i++) {
        memcpy(buf + 4 * (size_t)i, rgb + 3 * (size_t)i, 3 * sizeof *buf);
        buf[4 * (size_t)i + 3] = 1.0f;
    }
    glActiveTexture(GL_TEXTURE1);
    if (!g->vcol_tex) {
        glGenTextures(1, &g->vcol_tex);
        g->st.gl_objects++;
    }
    glBindTexture(GL_TEXTURE_2D, g->vcol_tex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    if (g->vcol_w != w || g->vcol_h != h) {
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, buf);
        g->vcol_w = w;
        g->vcol_h = h;
    } else {
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, buf);
    }
    glActiveTexture(GL_TEXTURE0);
    free(buf);
    *tw = w;
    return glr_gl_check(err, "uploading vertex colours");
}

static int glr_vertex_colors_in(glr *g, const glr_mesh *m, const scene_view *v, int width,
                                int height, const float *rgb, int nverts, float background,
                                img *out, uint8_t *mask, glint_err *err)
{
    const glr_locs *l;
    float clear0[4];
    vcol_rb ctx;
    int tw = 1, rc;

    if (out)
        memset(out, 0, sizeof *out);
    if (!rgb)
        return glint_err_set(err, GLINT_EINVAL, "vertex colours are NULL");
    if (!isfinite(background))
        return glint_err_set(err, GLINT_ENONFINITE, "background is not finite");
    if ((rc = glr_common_checks(g, m, v, width, height, out, err)))
        return rc;
    if (nverts != m->nverts)
        return glint_err_set(err, GLINT_EINVAL, "%d vertex colours for a mesh of %d vertices",
                             nverts, m->nverts);
    for (size_t i = 0; i < 3 * (size_t)nverts; i++)
        if (!isfinite(rgb[i]))
            return glint_err_set(err, GLINT_ENONFINITE, "vertex %zu has a non-finite colour",
                                 i / 3);
    if ((rc = vcol_upload(g, rgb, nverts, &tw, err)))
        return rc;
    l = &g->loc[GLR_PROG_VCOL];
    glUseProgram(g->prog[GLR_PROG_VCOL]);
    glUniform1i(l->vcol, 1);
    glUniform1i(l->vcol_w, tw);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, g->vcol_tex);
    glActiveTexture(GL_TEXTURE0);
    clear0[0] = clear0[1] = clear0[2] = background;
    clear0[3] = 0.0f;
    if ((rc = glr_draw(g, g->prog[GLR_PROG_VCOL], l, &g->ct, 1, m, v, width, height, clear0,
                       err)))
        return rc;
    if ((rc = img_alloc(out, width, height, 3, err)))
        return rc;
    ctx.im = out;
    ctx.mask = mask;
    ctx.background = background;
    if ((rc = glr_readback(g, 0, width, height, vcol_strip, &ctx, err)))
        img_free(out);
    return rc;
}

int glr_vertex_colors(glr *g, const glr_mesh *m, const scene_view *v, int width, int height,
                      const float *rgb, int nverts, float background, img *out, uint8_t *mask,
                      glint_err *err)
{
    int rc = glr_vertex_colors_in(g, m, v, width, height, rgb, nverts, background, out, mask,
                                  err);
    glr_leave(g);
    return rc;
}
