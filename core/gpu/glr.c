/* glr.c: the glr context: EGL platform selection, open / close, entering
 * and leaving the context, GL error checks (contract in glr.h, internals
 * and the module's file layout in glr_int.h).
 *
 * Context: glr_open() tries EGL platforms in the order of glr.h (only the
 * chosen device when GLINT_EGL_DEVICE is set); on each it
 * initializes the display, binds OpenGL ES, chooses a pbuffer-capable ES3
 * config, creates an ES 3.x context and makes it current, surfaceless when
 * EGL_KHR_surfaceless_context is there, else on a 1x1 pbuffer.  The first
 * platform where all of that works wins; the programs are compiled once
 * (glr_program.c).
 * EGL displays are process-wide singletons and eglTerminate() is not
 * reference counted: terminating one glr's display would break every other
 * glr on it.  glr therefore never terminates a display; glr_close destroys
 * its context and surface, and the initialized display stays for the
 * process (a later glr_open reuses it; EGL releases it at exit).  This
 * also keeps LeakSanitizer quiet: Mesa 22.3 loses a few hundred bytes in
 * eglTerminate and unloads the driver, so they cannot be attributed.
 *
 * Threads: each public call makes the context current on entry and
 * releases it on return (glr_enter / glr_leave), so a caller that
 * serializes calls may make them from any thread.
 *
 * Errors: every GL call sequence ends in glr_gl_check(), which turns
 * glGetError() into GLINT_ENOMEM (GL_OUT_OF_MEMORY) or GLINT_EINTERNAL,
 * naming the step; EGL failures carry the EGL error name. */
#include "glr.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal/glr_int.h"

#ifndef EGL_OPENGL_ES3_BIT
#define EGL_OPENGL_ES3_BIT 0x00000040
#endif

#define GLR_MAX_DEVICES 16

/* ------------------------------------------------------------------------ */
/* EGL and GL errors                                                         */
/* ------------------------------------------------------------------------ */

static const char *glr_egl_errname(EGLint e)
{
    switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
    }
}

static const char *glr_gl_errname(GLenum e)
{
    switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    default: return "unknown GL error";
    }
}

/* Drop errors left by earlier calls (they belong to nobody). */
void glr_gl_drain(void)
{
    for (int i = 0; i < 64 && glGetError() != GL_NO_ERROR; i++)
        ;
}

/* Turn pending GL errors into a glint error naming `what`. */
int glr_gl_check(glint_err *err, const char *what)
{
    GLenum e = glGetError(), more;
    int n = 0;

    if (e == GL_NO_ERROR)
        return 0;
    while ((more = glGetError()) != GL_NO_ERROR && n < 64)
        n++;
    return glint_err_set(err, e == GL_OUT_OF_MEMORY ? GLINT_ENOMEM : GLINT_EINTERNAL,
                         "OpenGL ES error during %s: %s (0x%04x)%s", what, glr_gl_errname(e),
                         (unsigned)e, n ? " and more" : "");
}

/* ------------------------------------------------------------------------ */
/* Context creation                                                          */
/* ------------------------------------------------------------------------ */

static int glr_has_ext(const char *list, const char *name)
{
    size_t n = strlen(name);
    const char *p = list;

    if (!list)
        return 0;
    while ((p = strstr(p, name)) != NULL) {
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0'))
            return 1;
        p += n;
    }
    return 0;
}

/* Release what glr_try_display set up (any part may be missing); the
 * display stays initialized (see the top of this file). */
static void glr_egl_teardown(glr *g)
{
    if (g->dpy != EGL_NO_DISPLAY) {
        if (eglGetCurrentContext() == g->ctx && g->ctx != EGL_NO_CONTEXT)
            eglMakeCurrent(g->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (g->surf != EGL_NO_SURFACE)
            eglDestroySurface(g->dpy, g->surf);
        if (g->ctx != EGL_NO_CONTEXT)
            eglDestroyContext(g->dpy, g->ctx);
    }
    g->dpy = EGL_NO_DISPLAY;
    g->ctx = EGL_NO_CONTEXT;
    g->surf = EGL_NO_SURFACE;
}

/* Try one display: on success g holds a current ES 3 context and returns 1;
 * on failure everything is released and `why` says what failed. */
static int glr_try_display(glr *g, EGLDisplay dpy, const char *platform, char *why,
                           size_t whylen)
{
    static const EGLint cfg_attr[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT,
                                      EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT,
                                      EGL_NONE};
    static const EGLint ctx_attr[] = {EGL_CONTEXT_CLIENT_VERSION, 3, EGL_NONE};
    static const EGLint pb_attr[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
    EGLint maj = 0, min = 0, ncfg = 0;
    EGLConfig cfg;
    const char *exts;
    int surfaceless;

    if (dpy == EGL_NO_DISPLAY) {
        snprintf(why, whylen, "%s: no display (%s)", platform, glr_egl_errname(eglGetError()));
        return 0;
    }
    if (!eglInitialize(dpy, &maj, &min)) {
        snprintf(why, whylen, "%s: eglInitialize failed (%s)", platform,
                 glr_egl_errname(eglGetError()));
        return 0;
    }
    g->dpy = dpy;
    if (!eglBindAPI(EGL_OPENGL_ES_API)) {
        snprintf(why, whylen, "%s: eglBindAPI(OpenGL ES) failed (%s)", platform,
                 glr_egl_errname(eglGetError()));
        goto fail;
    }
    if (!eglChooseConfig(dpy, cfg_attr, &cfg, 1, &ncfg) || ncfg < 1) {
        snprintf(why, whylen, "%s: no ES3 pbuffer config (%s)", platform,
                 glr_egl_errname(eglGetError()));
        goto fail;
    }
    g->ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctx_attr);
    if (g->ctx == EGL_NO_CONTEXT) {
        snprintf(why, whylen, "%s: eglCreateContext(ES 3) failed (%s)", platform,
                 glr_egl_errname(eglGetError()));
        goto fail;
    }
    exts = eglQueryString(dpy, EGL_EXTENSIONS);
    surfaceless = glr_has_ext(exts, "EGL_KHR_surfaceless_context");
    if (!surfaceless) {
        g->surf = eglCreatePbufferSurface(dpy, cfg, pb_attr);
        if (g->surf == EGL_NO_SURFACE) {
            snprintf(why, whylen, "%s: eglCreatePbufferSurface failed (%s)", platform,
                     glr_egl_errname(eglGetError()));
            goto fail;
        }
    }
    if (!eglMakeCurrent(dpy, g->surf, g->surf, g->ctx)) {
        snprintf(why, whylen, "%s: eglMakeCurrent failed (%s)", platform,
                 glr_egl_errname(eglGetError()));
        goto fail;
    }
    glGetIntegerv(GL_MAJOR_VERSION, &g->gl_major);
    glGetIntegerv(GL_MINOR_VERSION, &g->gl_minor);
    if (g->gl_major < 3) {
        snprintf(why, whylen, "%s: context is OpenGL ES %d.%d, need 3.0", platform,
                 (int)g->gl_major, (int)g->gl_minor);
        goto fail;
    }
    {
        const char *rend = (const char *)glGetString(GL_RENDERER);
        const char *ver = (const char *)glGetString(GL_VERSION);
        snprintf(g->desc, sizeof g->desc, "%s, %s, EGL %d.%d %s%s", rend ? rend : "?",
                 ver ? ver : "?", (int)maj, (int)min, platform,
                 surfaceless ? "" : " (pbuffer)");
    }
    return 1;

fail:
    glr_egl_teardown(g);
    return 0;
}

typedef EGLDisplay(EGLAPIENTRYP glr_getplatformdisplay_fn)(EGLenum, void *, const EGLint *);

/* Append "; text" to the attempts log. */
static void glr_log_append(char *log, size_t len, const char *text)
{
    size_t used = strlen(log);
    if (used + 3 < len)
        snprintf(log + used, len - used, "%s%s", used ? "; " : "", text);
}

static int glr_try_devices(glr *g, glr_getplatformdisplay_fn gpd, const char *cexts,
                           int want, char *log, size_t loglen)
{
    PFNEGLQUERYDEVICESEXTPROC qdev;
    EGLDeviceEXT devs[GLR_MAX_DEVICES];
    EGLint ndev = 0;
    char why[256];

    if (!gpd || !glr_has_ext(cexts, "EGL_EXT_platform_device")) {
        glr_log_append(log, loglen, "device: EGL_EXT_platform_device not available");
        return 0;
    }
    qdev = (PFNEGLQUERYDEVICESEXTPROC)eglGetProcAddress("eglQueryDevicesEXT");
    if (!qdev || !qdev(GLR_MAX_DEVICES, devs, &ndev) || ndev < 1) {
        glr_log_append(log, loglen, "device: no EGL devices");
        return 0;
    }
    if (want >= 0 && want >= ndev) {
        snprintf(why, sizeof why, "device: GLINT_EGL_DEVICE=%d but only %d device(s)", want,
                 (int)ndev);
        glr_log_append(log, loglen, why);
        return 0;
    }
    for (int i = 0; i < ndev; i++) {
        char name[48];
        if (want >= 0 && i != want)
            continue;
        snprintf(name, sizeof name, "device %d", i);
        if (glr_try_display(g, gpd(EGL_PLATFORM_DEVICE_EXT, devs[i], NULL), name, why,
                            sizeof why))
            return 1;
        glr_log_append(log, loglen, why);
    }
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Entering and leaving the context                                          */
/* ------------------------------------------------------------------------ */

/* Every public call makes g's context current on the calling thread on
 * entry and releases it before returning, so that successive calls may
 * come from different threads (a context current on one thread cannot be
 * made current on another). */
int glr_enter(const glr *g, glint_err *err)
{
    if (eglGetCurrentContext() == g->ctx)
        return 0;
    if (!eglMakeCurrent(g->dpy, g->surf, g->surf, g->ctx))
        return glint_err_set(err, GLINT_EINTERNAL, "eglMakeCurrent failed (%s)",
                             glr_egl_errname(eglGetError()));
    return 0;
}

void glr_leave(const glr *g)
{
    if (g && g->ctx != EGL_NO_CONTEXT && eglGetCurrentContext() == g->ctx)
        eglMakeCurrent(g->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

/* ------------------------------------------------------------------------ */
/* Open / close                                                              */
/* ------------------------------------------------------------------------ */

int glr_open(glr **out, glint_err *err)
{
    char log[GLINT_ERR_MSG_MAX], why[256];
    const char *cexts, *env;
    glr_getplatformdisplay_fn gpd;
    glr *g;
    int want = -1, ok = 0, rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "glr_open: NULL output");
    *out = NULL;
    env = getenv("GLINT_EGL");
    if (env && strcmp(env, "off") == 0)
        return glint_err_set(err, GLINT_EUNSUPPORTED, "EGL is turned off (GLINT_EGL=off)");
    env = getenv("GLINT_EGL_DEVICE");
    if (env && *env) {
        char *end;
        long v;
        errno = 0;
        v = strtol(env, &end, 10);
        if (*end != '\0' || errno || v < 0 || v >= GLR_MAX_DEVICES)
            return glint_err_set(err, GLINT_EINVAL,
                                 "GLINT_EGL_DEVICE='%.32s' is not a device number 0..%d", env,
                                 GLR_MAX_DEVICES - 1);
        want = (int)v;
    }
    g = calloc(1, sizeof *g);
    if (!g)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a renderer");
    g->dpy = EGL_NO_DISPLAY;
    g->ctx = EGL_NO_CONTEXT;
    g->surf = EGL_NO_SURFACE;
    g->strip = malloc(GLR_STRIP_BYTES);
    if (!g->strip) {
        free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a readback buffer");
    }

    log[0] = '\0';
    cexts = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS); /* client extensions */
    if (!cexts)
        eglGetError(); /* EGL 1.4 without client extensions: clear the error */
    gpd = (glr_getplatformdisplay_fn)eglGetProcAddress("eglGetPlatformDisplayEXT");
    if (!glr_has_ext(cexts, "EGL_EXT_platform_base"))
        gpd = NULL;

    /* An explicit device choice is the only one tried. */
    if (want >= 0)
        ok = glr_try_devices(g, gpd, cexts, want, log, sizeof log);
    if (!ok && want < 0) {
        if (gpd && glr_has_ext(cexts, "EGL_MESA_platform_surfaceless")) {
            ok = glr_try_display(g, gpd(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL),
                                 "surfaceless", why, sizeof why);
            if (!ok)
                glr_log_append(log, sizeof log, why);
        } else {
            glr_log_append(log, sizeof log,
                           "surfaceless: EGL_MESA_platform_surfaceless not available");
        }
    }
    if (!ok && want < 0)
        ok = glr_try_devices(g, gpd, cexts, -1, log, sizeof log);
    if (!ok && want < 0) {
        ok = glr_try_display(g, eglGetDisplay(EGL_DEFAULT_DISPLAY), "default display", why,
                             sizeof why);
        if (!ok)
            glr_log_append(log, sizeof log, why);
    }
    if (!ok) {
        glr_close(g);
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "no OpenGL ES 3 context through EGL: %s", log);
    }

    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &g->max_rb);
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, g->max_vp);
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &g->max_tex);
    {
        /* 32-bit float colour buffers: core in ES 3.2, else the extension */
        const char *ext = (const char *)glGetString(GL_EXTENSIONS);
        int fl = (g->gl_major > 3 || (g->gl_major == 3 && g->gl_minor >= 2)) ||
                 glr_has_ext(ext, "GL_EXT_color_buffer_float");
        if (!fl) {
            rc = glint_err_set(err, GLINT_EUNSUPPORTED,
                               "%s: float colour buffers (GL_EXT_color_buffer_float) are "
                               "not supported",
                               g->desc);
            glr_close(g);
            return rc;
        }
    }
    glr_gl_drain();
    rc = glr_programs_build(g, err);
    if (rc) {
        glint_err_prefix(err, "%s", g->desc);
        glr_close(g);
        return rc;
    }
    glr_leave(g);
    *out = g;
    return 0;
}

void glr_close(glr *g)
{
    if (!g)
        return;
    if (g->ctx != EGL_NO_CONTEXT && glr_enter(g, NULL) == 0) {
        glr_target_release(g, &g->gt);
        glr_target_release(g, &g->ct);
        if (g->mat_tex)
            glDeleteTextures(1, &g->mat_tex);
        if (g->vcol_tex)
            glDeleteTextures(1, &g->vcol_tex);
        for (int i = 0; i < GLR_NPROG; i++)
            if (g->prog[i])
                glDeleteProgram(g->prog[i]);
        for (int i = 0; i < g->nmprog; i++)
            glDeleteProgram(g->mprog[i].prog);
        glFinish();
    }
    glr_egl_teardown(g);
    /* Free this thread's EGL state unless another context is current. */
    if (eglGetCurrentContext() == EGL_NO_CONTEXT)
        eglReleaseThread();
    free(g->mat_tex_cache);
    free(g->strip);
    free(g);
}

void glr_trim_targets(glr *g, long keep_pixels)
{
    glr_target *ts[2];
    if (!g || g->ctx == EGL_NO_CONTEXT)
        return;
    ts[0] = &g->gt;
    ts[1] = &g->ct;
    for (int i = 0; i < 2; i++) {
        int nc = ts[i]->ncolor;
        if (!ts[i]->fbo || (long)ts[i]->cap_w * ts[i]->cap_h <= keep_pixels)
            continue;
        if (glr_enter(g, NULL))
            return;
        /* Deleting the buffers is not enough: the driver keeps their storage
         * while its framebuffer state refers to them, until another target is
         * validated.  So bind a 1 x 1 one and clear it. */
        glr_target_release(g, ts[i]);
        if (glr_target_fit(g, ts[i], nc, 1, 1, NULL) == 0)
            glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        glFinish();
    }
    glr_leave(g);
}

const char *glr_describe(const glr *g)
{
    return g ? g->desc : "no renderer";
}

void glr_get_stats(const glr *g, glr_stats *out)
{
    if (!out)
        return;
    if (!g) {
        memset(out, 0, sizeof *out);
        return;
    }
    *out = g->st;
}
