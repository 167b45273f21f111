/* glr_draw.c: what every glr image shares (glr_int.h): render targets,
 * the camera projection, the draw itself and the strip-wise readback.
 *
 * Projection (identical to raster.c): camera space x = right.(P - eye),
 * y = up.(P - eye), z = fwd.(P - eye); clip x = x H / (W tan), clip y =
 * -y / tan, clip w = z, so that the centre of GL pixel (i, j) is the ray of
 * image pixel (row j, column i) in scene.h.  The y axis is negated so that
 * GL's row 0 (the bottom of its window) is the image's top row:
 * glReadPixels then returns rows in image order and nothing is flipped on
 * readback.  Near and far planes come from the mesh's bounding sphere
 * relative to the eye; depth is 32-bit float.  Both faces are drawn, as
 * raster.c does, except for closed meshes seen from outside (see
 * glr_mesh_closed in glr_mesh.c); GL_LESS keeps the first of equal depths,
 * as raster.c.
 *
 * Render targets: one framebuffer for G-buffers (three RGBA32F colour
 * buffers + depth) and one for colour images (one RGBA32F + depth).  They
 * grow to the largest size asked and are drawn in the bottom-left w x h
 * corner; they are reallocated only when a request does not fit, or is
 * far smaller (to give memory back).  Readback goes through one reusable
 * strip buffer, so a 4096^2 image needs no full-size RGBA copy. */
#include "glr.h"

#include <GLES3/gl3.h>
#include <math.h>
#include <string.h>

#include "internal/glr_int.h"

#define GLR_PI 3.14159265358979323846

/* ------------------------------------------------------------------------ */
/* Render targets                                                            */
/* ------------------------------------------------------------------------ */

static const char *glr_fbo_statusname(GLenum s)
{
    switch (s) {
    case GL_FRAMEBUFFER_COMPLETE: return "complete";
    case GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT: return "GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT";
    case GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT:
        return "GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT";
    case GL_FRAMEBUFFER_INCOMPLETE_DIMENSIONS: return "GL_FRAMEBUFFER_INCOMPLETE_DIMENSIONS";
    case GL_FRAMEBUFFER_UNSUPPORTED: return "GL_FRAMEBUFFER_UNSUPPORTED";
    case GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE: return "GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE";
    default: return "unknown framebuffer status";
    }
}

void glr_target_release(glr *g, glr_target *t)
{
    if (t->fbo) {
        glDeleteFramebuffers(1, &t->fbo);
        g->st.gl_objects--;
    }
    for (int i = 0; i < 3; i++) {
        if (t->color[i]) {
            glDeleteRenderbuffers(1, &t->color[i]);
            g->st.gl_objects--;
        }
    }
    if (t->depth) {
        glDeleteRenderbuffers(1, &t->depth);
        g->st.gl_objects--;
    }
    memset(t, 0, sizeof *t);
}

static int glr_size_ok(const glr *g, int w, int h, glint_err *err)
{
    if (w < 1 || h < 1 || w > GLR_MAX_SIZE || h > GLR_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "render size %dx%d outside 1..%d", w, h,
                             GLR_MAX_SIZE);
    if (w > g->max_rb || h > g->max_rb || w > g->max_vp[0] || h > g->max_vp[1])
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "render size %dx%d above this driver's limits (renderbuffer %d, "
                             "viewport %dx%d)",
                             w, h, (int)g->max_rb, (int)g->max_vp[0], (int)g->max_vp[1]);
    return 0;
}

/* Make t at least w x h (ncolor RGBA32F buffers + 32F depth) and bind it
 * as the draw and read framebuffer. */
int glr_target_fit(glr *g, glr_target *t, int ncolor, int w, int h, glint_err *err)
{
    static const GLenum bufs[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1,
                                   GL_COLOR_ATTACHMENT2};
    long need = (long)w * h, cap = (long)t->cap_w * t->cap_h;
    int cw, ch;
    GLenum status;
    int rc;

    if (t->fbo && w <= t->cap_w && h <= t->cap_h &&
        !(cap > 16 * need && cap > 1024L * 1024L)) {
        glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
        return 0;
    }
    /* Grow to cover both the old and the new size when that costs at most
     * 4x the request (alternating sizes then settle), else fit exactly. */
    cw = w > t->cap_w ? w : t->cap_w;
    ch = h > t->cap_h ? h : t->cap_h;
    if (!t->fbo || (long)cw * ch > 4 * need || cap > 16 * need) {
        cw = w;
        ch = h;
    }
    if (!t->fbo) {
        glGenFramebuffers(1, &t->fbo);
        g->st.gl_objects++;
        glGenRenderbuffers(ncolor, t->color);
        g->st.gl_objects += ncolor;
        glGenRenderbuffers(1, &t->depth);
        g->st.gl_objects++;
        t->ncolor = ncolor;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    for (int i = 0; i < t->ncolor; i++) {
        glBindRenderbuffer(GL_RENDERBUFFER, t->color[i]);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, cw, ch);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, bufs[i], GL_RENDERBUFFER, t->color[i]);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, t->depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, cw, ch);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t->depth);
    glBindRenderbuffer(GL_RENDERBUFFER, 0);
    glDrawBuffers(t->ncolor, bufs);
    g->st.target_allocs++;
    rc = glr_gl_check(err, "allocating render targets");
    if (rc) {
        glint_err_prefix(err, "%dx%d, %d float colour buffers", cw, ch, t->ncolor);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glr_target_release(g, t);
        return rc;
    }
    status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glr_target_release(g, t);
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "framebuffer of %dx%d with %d RGBA32F buffers is incomplete: %s",
                             cw, ch, ncolor, glr_fbo_statusname(status));
    }
    t->cap_w = cw;
    t->cap_h = ch;
    return 0;
}

int glr_readback(glr *g, int att, int w, int h, glr_strip_fn fn, void *ctx, glint_err *err)
{
    size_t row_bytes = (size_t)w * 4 * sizeof(float);
    int rows = (int)(GLR_STRIP_BYTES / row_bytes);

    if (rows < 1)
        rows = 1;
    glReadBuffer(GL_COLOR_ATTACHMENT0 + (GLenum)att);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    for (int r0 = 0; r0 < h; r0 += rows) {
        int n = h - r0 < rows ? h - r0 : rows;
        glReadPixels(0, r0, w, n, GL_RGBA, GL_FLOAT, g->strip);
        {
            int rc = glr_gl_check(err, "reading pixels back");
            if (rc)
                return rc;
        }
        fn(ctx, r0, n, g->strip);
    }
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Views and drawing                                                         */
/* ------------------------------------------------------------------------ */

static int glr_view_ok(const scene_view *v, glint_err *err)
{
    double d2 = 0.0;

    if (!v)
        return glint_err_set(err, GLINT_EINVAL, "view is NULL");
    for (int i = 0; i < 3; i++) {
        double d = v->target[i] - v->eye[i];
        if (!isfinite(v->eye[i]) || !isfinite(v->target[i]) || !isfinite(v->light[i]))
            return glint_err_set(err, GLINT_EINVAL, "camera or light position is not finite");
        d2 += d * d;
    }
    if (!(d2 > 0.0) || !isfinite(d2))
        return glint_err_set(err, GLINT_EINVAL, "degenerate camera: eye equals target");
    if (!(v->half_fov > 0.0 && v->half_fov < GLR_PI / 2))
        return glint_err_set(err, GLINT_EINVAL,
                             "degenerate camera: half_fov %g outside (0, pi/2)", v->half_fov);
    if (!isfinite(v->light_intensity) || v->light_intensity < 0.0)
        return glint_err_set(err, GLINT_EINVAL, "light intensity %g must be finite and >= 0",
                             v->light_intensity);
    return 0;
}

/* World -> clip matrix of a view (column-major), as described at the top. */
static void glr_view_proj(const scene_view *v, const glr_mesh *m, int w, int h, float out[16])
{
    double F[3], R[3], U[3], t = tan(v->half_fov), dc = 0.0, n, f, A, B, kx, ky, rows[4][4];
    double r = m->radius;

    scene_view_frame(v, F, R, U);
    for (int c = 0; c < 3; c++) {
        double d = m->center[c] - v->eye[c];
        dc += d * d;
    }
    dc = sqrt(dc);
    /* Tight planes around the bounding sphere; an eye inside it gets a
     * near plane at 1e-4 of the far one (raster.c clips at 1e-6 of the
     * eye-target distance: geometry nearer than both is lost here only). */
    f = dc + r * 1.001 + 1e-6;
    n = dc - r * 1.001 - 1e-6;
    if (n < 1e-4 * f)
        n = 1e-4 * f;
    A = (f + n) / (f - n);
    B = -2.0 * f * n / (f - n);
    kx = (double)h / ((double)w * t);
    ky = -1.0 / t;
    for (int c = 0; c < 3; c++) {
        rows[0][c] = kx * R[c];
        rows[1][c] = ky * U[c];
        rows[2][c] = A * F[c];
        rows[3][c] = F[c];
    }
    {
        double re = 0, ue = 0, fe = 0;
        for (int c = 0; c < 3; c++) {
            re += R[c] * v->eye[c];
            ue += U[c] * v->eye[c];
            fe += F[c] * v->eye[c];
        }
        rows[0][3] = -kx * re;
        rows[1][3] = -ky * ue;
        rows[2][3] = -A * fe + B;
        rows[3][3] = -fe;
    }
    for (int col = 0; col < 4; col++)
        for (int row = 0; row < 4; row++)
            out[col * 4 + row] = (float)rows[row][col];
}

/* Is the eye outside the mesh's bounding sphere (so outside every closed
 * surface of it)? */
static int glr_eye_outside(const glr_mesh *m, const scene_view *v)
{
    double d2 = 0.0, r = m->radius * (1.0 + 1e-6) + 1e-9;
    for (int c = 0; c < 3; c++)
        d2 += (v->eye[c] - m->center[c]) * (v->eye[c] - m->center[c]);
    return d2 > r * r;
}

/* Common setup of a draw: program, camera uniforms, target, state, clear. */
int glr_draw(glr *g, GLuint prog, const glr_locs *l, glr_target *t, int ncolor,
             const glr_mesh *m, const scene_view *v, int w, int h, const float clear0[4],
             glint_err *err)
{
    static const float zero[4] = {0, 0, 0, 0};
    float vp[16], eye[3], light[3];
    float one = 1.0f;
    int rc;

    rc = glr_target_fit(g, t, ncolor, w, h, err);
    if (rc)
        return rc;
    glr_view_proj(v, m, w, h, vp);
    for (int c = 0; c < 3; c++) {
        eye[c] = (float)v->eye[c];
        light[c] = (float)v->light[c];
    }
    glUseProgram(prog);
    glUniformMatrix4fv(l->view_proj, 1, GL_FALSE, vp);
    glUniform3fv(l->eye, 1, eye);
    glUniform3fv(l->light, 1, light);
    glViewport(0, 0, w, h);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_BLEND);
    if (m->closed && glr_eye_outside(m, v)) {
        /* The y flip of the projection mirrors the winding: faces that are
         * counter-clockwise seen from outside are clockwise on screen. */
        glEnable(GL_CULL_FACE);
        glCullFace(GL_BACK);
        glFrontFace(m->closed > 0 ? GL_CW : GL_CCW);
        g->st.culled_frames++;
    } else {
        glDisable(GL_CULL_FACE);
    }
    glDisable(GL_DITHER);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    /* Clear only the part that is read back. */
    glEnable(GL_SCISSOR_TEST);
    glScissor(0, 0, w, h);
    glClearBufferfv(GL_COLOR, 0, clear0);
    for (int i = 1; i < ncolor; i++)
        glClearBufferfv(GL_COLOR, i, zero);
    glClearBufferfv(GL_DEPTH, 0, &one);
    glDisable(GL_SCISSOR_TEST);
    glBindVertexArray(m->vao);
    glDrawElements(GL_TRIANGLES, m->nidx, GL_UNSIGNED_INT, NULL);
    glBindVertexArray(0);
    g->st.frames++;
    return glr_gl_check(err, "drawing");
}

int glr_common_checks(glr *g, const glr_mesh *m, const scene_view *v, int w, int h,
                      void *out, glint_err *err)
{
    int rc;

    if (!g)
        return glint_err_set(err, GLINT_EINVAL, "renderer is NULL");
    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "output is NULL");
    rc = glr_mesh_ok(g, m, err);
    if (rc)
        return rc;
    rc = glr_view_ok(v, err);
    if (rc)
        return rc;
    if (w < 1 || h < 1 || w > GLR_MAX_SIZE || h > GLR_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "render size %dx%d outside 1..%d", w, h,
                             GLR_MAX_SIZE);
    rc = glr_enter(g, err);
    if (rc)
        return rc;
    glr_gl_drain();
    return glr_size_ok(g, w, h, err);
}
