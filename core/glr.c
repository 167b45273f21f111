/* glr.c: headless OpenGL ES 3 rendering through EGL (contract in glr.h,
 * GLSL sources in glr_shaders.h).
 *
 * Context: glr_open() tries EGL platforms in the order of glr.h (only the
 * chosen device when GLINT_EGL_DEVICE is set); on each it
 * initializes the display, binds OpenGL ES, chooses a pbuffer-capable ES3
 * config, creates an ES 3.x context and makes it current, surfaceless when
 * EGL_KHR_surfaceless_context is there, else on a 1x1 pbuffer.  The first
 * platform where all of that works wins; the programs are compiled once.
 * EGL displays are process-wide singletons and eglTerminate() is not
 * reference counted: terminating one glr's display would break every other
 * glr on it.  glr therefore never terminates a display; glr_close destroys
 * its context and surface, and the initialized display stays for the
 * process (a later glr_open reuses it; EGL releases it at exit).  This
 * also keeps LeakSanitizer quiet: Mesa 22.3 loses a few hundred bytes in
 * eglTerminate and unloads the driver, so they cannot be attributed.
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
 * glr_mesh_closed); GL_LESS keeps the first of equal depths, as raster.c.
 *
 * Threads: each public call makes the context current on entry and
 * releases it on return (glr_enter / glr_leave), so a caller that
 * serializes calls may make them from any thread.
 *
 * Render targets: one framebuffer for G-buffers (three RGBA32F colour
 * buffers + depth) and one for colour images (one RGBA32F + depth).  They
 * grow to the largest size asked and are drawn in the bottom-left w x h
 * corner; they are reallocated only when a request does not fit, or is
 * far smaller (to give memory back).  Readback goes through one reusable
 * strip buffer, so a 4096^2 image needs no full-size RGBA copy.
 *
 * Errors: every GL call sequence ends in glr_gl_check(), which turns
 * glGetError() into GLINT_ENOMEM (GL_OUT_OF_MEMORY) or GLINT_EINTERNAL,
 * naming the step; EGL failures carry the EGL error name. */
#include "glr.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fsio.h"
#include "glr_int.h"
#include "glr_shaders.h"

#ifndef EGL_OPENGL_ES3_BIT
#define EGL_OPENGL_ES3_BIT 0x00000040
#endif

#define GLR_PI 3.14159265358979323846
#define GLR_MESH_MAGIC 0x676c726dU /* "glrm" */
#define GLR_MAX_DEVICES 16
#define GLR_STRIP_BYTES ((size_t)8 << 20) /* readback strip buffer */

enum { GLR_PROG_GBUF = 0, GLR_PROG_BASE, GLR_PROG_PREVIEW, GLR_NPROG };

/* Uniform locations of one program (-1 where a program lacks one). */
typedef struct glr_locs {
    GLint model, normal_matrix, view_proj, eye, light;
    /* preview */
    GLint factors, res, map_kind, a, model_brdf, light_intensity;
    /* base */
    GLint gain, kind, kd, ks, f0, exponent, rough;
} glr_locs;

/* An offscreen framebuffer: ncolor RGBA32F colour buffers and a depth
 * buffer, capacity cap_w x cap_h. */
typedef struct glr_target {
    GLuint fbo;
    GLuint color[3];
    GLuint depth;
    int ncolor;
    int cap_w, cap_h;
} glr_target;

struct glr {
    EGLDisplay dpy;
    EGLContext ctx;
    EGLSurface surf; /* EGL_NO_SURFACE when surfaceless */
    GLint gl_major, gl_minor;
    GLint max_rb, max_vp[2], max_tex;
    char desc[320];
    GLuint prog[GLR_NPROG];
    glr_locs loc[GLR_NPROG];
    glr_target gt; /* G-buffers */
    glr_target ct; /* colour */
    GLuint fac_tex;
    int fac_res;
    float *fac_cache; /* what fac_tex holds: 3 x res x 4 floats */
    float *strip;     /* readback buffer, GLR_STRIP_BYTES */
    glr_stats st;
};

struct glr_mesh {
    uint32_t magic;
    const glr *owner;
    GLuint vao, vbo[3], ibo;
    GLsizei nidx;
    double center[3], radius; /* bounding sphere */
    int closed; /* +1 / -1: closed, consistently wound, facing out / in; 0: open */
};

/* ------------------------------------------------------------------------ */
/* EGL and GL error names                                                    */
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

/* Drop errors left by earlier calls (they belong to nobody). */
static void glr_gl_drain(void)
{
    for (int i = 0; i < 64 && glGetError() != GL_NO_ERROR; i++)
        ;
}

/* Turn pending GL errors into a glint error naming `what`. */
static int glr_gl_check(glint_err *err, const char *what)
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
/* Programs                                                                  */
/* ------------------------------------------------------------------------ */

/* Drop trailing white space and turn newlines into spaces (one-line messages). */
static void glr_trim(char *s)
{
    size_t n = strlen(s);
    while (n > 0 && (s[n - 1] == '\n' || s[n - 1] == ' ' || s[n - 1] == '\r'))
        s[--n] = '\0';
    for (size_t i = 0; i < n; i++)
        if (s[i] == '\n')
            s[i] = ' ';
}

static GLuint glr_compile(GLenum type, const char *src, char *log, size_t loglen)
{
    GLuint s = glCreateShader(type);
    GLint ok = 0;

    if (!s) {
        snprintf(log, loglen, "glCreateShader failed");
        return 0;
    }
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLsizei n = 0;
        glGetShaderInfoLog(s, (GLsizei)loglen, &n, log);
        if (n <= 0)
            snprintf(log, loglen, "(no log)");
        glr_trim(log);
        glDeleteShader(s);
        return 0;
    }
    return s;
}

/* Compile and link; 0 on failure with the log in err (GLINT_EFORMAT). */
static GLuint glr_link(const char *vs_src, const char *fs_src, const char *what,
                       glint_err *err)
{
    char log[400];
    GLuint vs, fs, p;
    GLint ok = 0;

    log[0] = '\0';
    vs = glr_compile(GL_VERTEX_SHADER, vs_src, log, sizeof log);
    if (!vs) {
        glint_err_set(err, GLINT_EFORMAT, "%s: vertex shader does not compile: %s", what, log);
        return 0;
    }
    fs = glr_compile(GL_FRAGMENT_SHADER, fs_src, log, sizeof log);
    if (!fs) {
        glDeleteShader(vs);
        glint_err_set(err, GLINT_EFORMAT, "%s: fragment shader does not compile: %s", what,
                      log);
        return 0;
    }
    p = glCreateProgram();
    if (p) {
        glAttachShader(p, vs);
        glAttachShader(p, fs);
        glLinkProgram(p);
        glGetProgramiv(p, GL_LINK_STATUS, &ok);
    }
    /* flagged for deletion; freed with the program */
    glDeleteShader(vs);
    glDeleteShader(fs);
    if (!ok) {
        GLsizei n = 0;
        if (p)
            glGetProgramInfoLog(p, (GLsizei)sizeof log, &n, log);
        if (n <= 0)
            snprintf(log, sizeof log, "(no log)");
        glr_trim(log);
        if (p)
            glDeleteProgram(p);
        glint_err_set(err, GLINT_EFORMAT, "%s: program does not link: %s", what, log);
        return 0;
    }
    return p;
}

static void glr_locs_get(GLuint p, glr_locs *l)
{
    l->model = glGetUniformLocation(p, "u_model");
    l->normal_matrix = glGetUniformLocation(p, "u_normal_matrix");
    l->view_proj = glGetUniformLocation(p, "u_view_proj");
    l->eye = glGetUniformLocation(p, "u_eye");
    l->light = glGetUniformLocation(p, "u_light");
    l->factors = glGetUniformLocation(p, "u_factors");
    l->res = glGetUniformLocation(p, "u_res");
    l->map_kind = glGetUniformLocation(p, "u_map_kind");
    l->a = glGetUniformLocation(p, "u_a");
    l->model_brdf = glGetUniformLocation(p, "u_model_brdf");
    l->light_intensity = glGetUniformLocation(p, "u_light_intensity");
    l->gain = glGetUniformLocation(p, "u_gain");
    l->kind = glGetUniformLocation(p, "u_kind");
    l->kd = glGetUniformLocation(p, "u_kd");
    l->ks = glGetUniformLocation(p, "u_ks");
    l->f0 = glGetUniformLocation(p, "u_f0");
    l->exponent = glGetUniformLocation(p, "u_exponent");
    l->rough = glGetUniformLocation(p, "u_rough");
}

static int glr_programs_build(glr *g, glint_err *err)
{
    static const char *const fs[GLR_NPROG] = {GLR_GBUF_FRAG_SRC, GLR_BASE_FRAG_SRC,
                                              GLR_PREVIEW_FRAG_SRC};
    static const char *const names[GLR_NPROG] = {"G-buffer program", "base-render program",
                                                 "preview program"};
    static const float id4[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    static const float id3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};

    for (int i = 0; i < GLR_NPROG; i++) {
        g->prog[i] = glr_link(GLR_VERT_SRC, fs[i], names[i], err);
        if (!g->prog[i])
            return err ? err->code : GLINT_EFORMAT;
        g->st.gl_objects++;
        glr_locs_get(g->prog[i], &g->loc[i]);
        /* Constant uniforms, set once: glint's meshes are in world space. */
        glUseProgram(g->prog[i]);
        glUniformMatrix4fv(g->loc[i].model, 1, GL_FALSE, id4);
        glUniformMatrix3fv(g->loc[i].normal_matrix, 1, GL_FALSE, id3);
        if (g->loc[i].factors >= 0)
            glUniform1i(g->loc[i].factors, 0);
    }
    glUseProgram(0);
    return glr_gl_check(err, "building the programs");
}

/* ------------------------------------------------------------------------ */
/* Open / close                                                              */
/* ------------------------------------------------------------------------ */

/* Every public call makes g's context current on the calling thread on
 * entry and releases it before returning, so that successive calls may
 * come from different threads (a context current on one thread cannot be
 * made current on another). */
static int glr_enter(const glr *g, glint_err *err)
{
    if (eglGetCurrentContext() == g->ctx)
        return 0;
    if (!eglMakeCurrent(g->dpy, g->surf, g->surf, g->ctx))
        return glint_err_set(err, GLINT_EINTERNAL, "eglMakeCurrent failed (%s)",
                             glr_egl_errname(eglGetError()));
    return 0;
}

static void glr_leave(const glr *g)
{
    if (g && g->ctx != EGL_NO_CONTEXT && eglGetCurrentContext() == g->ctx)
        eglMakeCurrent(g->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

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

static void glr_target_release(glr *g, glr_target *t)
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

void glr_close(glr *g)
{
    if (!g)
        return;
    if (g->ctx != EGL_NO_CONTEXT && glr_enter(g, NULL) == 0) {
        glr_target_release(g, &g->gt);
        glr_target_release(g, &g->ct);
        if (g->fac_tex)
            glDeleteTextures(1, &g->fac_tex);
        for (int i = 0; i < GLR_NPROG; i++)
            if (g->prog[i])
                glDeleteProgram(g->prog[i]);
        glFinish();
    }
    glr_egl_teardown(g);
    /* Free this thread's EGL state unless another context is current. */
    if (eglGetCurrentContext() == EGL_NO_CONTEXT)
        eglReleaseThread();
    free(g->fac_cache);
    free(g->strip);
    free(g);
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

static int glr_program_check_in(glr *g, const char *vert_src, const char *frag_src,
                                glint_err *err)
{
    GLuint p;
    int rc;

    if (!g || !vert_src || !frag_src)
        return glint_err_set(err, GLINT_EINVAL, "glr_program_check: NULL argument");
    rc = glr_enter(g, err);
    if (rc)
        return rc;
    glr_gl_drain();
    p = glr_link(vert_src, frag_src, "shader check", err);
    if (!p)
        return err ? err->code : GLINT_EFORMAT;
    glDeleteProgram(p);
    return glr_gl_check(err, "checking a program");
}

/* ------------------------------------------------------------------------ */
/* Meshes                                                                    */
/* ------------------------------------------------------------------------ */

static int glr_mesh_ok(const glr *g, const glr_mesh *m, glint_err *err)
{
    if (!m)
        return glint_err_set(err, GLINT_EINVAL, "mesh is NULL");
    if (m->magic != GLR_MESH_MAGIC || m->owner != g)
        return glint_err_set(err, GLINT_EINVAL,
                             "not a mesh uploaded to this renderer (freed or foreign)");
    return 0;
}

void glr_mesh_free(glr *g, glr_mesh *m)
{
    if (!m)
        return;
    if (g && m->owner == g && m->magic == GLR_MESH_MAGIC && glr_enter(g, NULL) == 0) {
        if (m->vao) {
            glDeleteVertexArrays(1, &m->vao);
            g->st.gl_objects--;
        }
        for (int i = 0; i < 3; i++) {
            if (m->vbo[i]) {
                glDeleteBuffers(1, &m->vbo[i]);
                g->st.gl_objects--;
            }
        }
        if (m->ibo) {
            glDeleteBuffers(1, &m->ibo);
            g->st.gl_objects--;
        }
        g->st.meshes--;
        glr_leave(g);
    }
    m->magic = 0;
    free(m);
}

/* ---- closed meshes: back faces can be skipped ----------------------------
 * A surface that is closed and consistently wound hides every back face
 * behind a front face for an eye outside it (a ray enters before it
 * leaves), also for several such surfaces that intersect.  Drawing only
 * front faces then changes no pixel and halves the triangles llvmpipe
 * sets up.  A mesh qualifies when, after welding vertices with identical
 * positions and skipping triangles with repeated vertices, every directed
 * edge occurs once and its reverse occurs once.  The orientation is the
 * sign of the enclosed volume.  Meshes above GLR_CLOSED_MAX_TRIS are not
 * analysed (drawn with both faces, like any open mesh). */

#define GLR_CLOSED_MAX_TRIS (4 << 20)

typedef struct glr_wv {
    float x, y, z;
    uint32_t i;
} glr_wv;

static int glr_wv_cmp(const void *pa, const void *pb)
{
    const glr_wv *a = pa, *b = pb;
    if (a->x != b->x)
        return a->x < b->x ? -1 : 1;
    if (a->y != b->y)
        return a->y < b->y ? -1 : 1;
    if (a->z != b->z)
        return a->z < b->z ? -1 : 1;
    return 0;
}

static int glr_u64_cmp(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return a < b ? -1 : a > b;
}

static int glr_mesh_closed(const mesh *m)
{
    size_t nv = (size_t)m->nverts, nt = (size_t)m->ntris, ne = 0;
    glr_wv *wv = NULL;
    uint32_t *weld = NULL;
    uint64_t *edges = NULL;
    double vol = 0.0;
    int closed = 0;

    if (nt > GLR_CLOSED_MAX_TRIS)
        return 0;
    wv = malloc(nv * sizeof *wv);
    weld = malloc(nv * sizeof *weld);
    edges = malloc(3 * nt * sizeof *edges);
    if (!wv || !weld || !edges)
        goto done; /* not knowing is fine: draw both faces */
    for (size_t i = 0; i < nv; i++) {
        wv[i].x = m->pos[3 * i];
        wv[i].y = m->pos[3 * i + 1];
        wv[i].z = m->pos[3 * i + 2];
        wv[i].i = (uint32_t)i;
    }
    qsort(wv, nv, sizeof *wv, glr_wv_cmp);
    for (size_t i = 0; i < nv; i++)
        weld[wv[i].i] = i > 0 && glr_wv_cmp(&wv[i], &wv[i - 1]) == 0 ? weld[wv[i - 1].i]
                                                                      : wv[i].i;
    for (size_t t = 0; t < nt; t++) {
        uint32_t v[3];
        const float *p[3];
        for (int k = 0; k < 3; k++) {
            v[k] = weld[m->tri[3 * t + (size_t)k]];
            p[k] = m->pos + 3 * (size_t)v[k];
        }
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
            continue;
        for (int k = 0; k < 3; k++)
            edges[ne++] = (uint64_t)v[k] << 32 | v[(k + 1) % 3];
        vol += (double)p[0][0] * ((double)p[1][1] * p[2][2] - (double)p[1][2] * p[2][1]) -
               (double)p[0][1] * ((double)p[1][0] * p[2][2] - (double)p[1][2] * p[2][0]) +
               (double)p[0][2] * ((double)p[1][0] * p[2][1] - (double)p[1][1] * p[2][0]);
    }
    if (ne == 0)
        goto done;
    qsort(edges, ne, sizeof *edges, glr_u64_cmp);
    for (size_t i = 0; i < ne; i++) {
        uint64_t rev = edges[i] >> 32 | edges[i] << 32;
        if (i > 0 && edges[i] == edges[i - 1])
            goto done; /* an edge used twice the same way: non-manifold or misoriented */
        if (!bsearch(&rev, edges, ne, sizeof *edges, glr_u64_cmp))
            goto done; /* a boundary edge: open */
    }
    /* vol is 6x the signed volume; a flat or tiny closed surface is left alone */
    closed = vol > 1e-9 ? 1 : vol < -1e-9 ? -1 : 0;
done:
    free(wv);
    free(weld);
    free(edges);
    return closed;
}

static int glr_mesh_upload_in(glr *g, const mesh *msh, glr_mesh **out, glint_err *err)
{
    static const int ncomp[3] = {3, 3, 2};
    glr_mesh *m;
    const float *arrays[3];
    double lo[3], hi[3], r2 = 0.0;
    size_t nv;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "glr_mesh_upload: NULL output");
    *out = NULL;
    if (!g)
        return glint_err_set(err, GLINT_EINVAL, "glr_mesh_upload: renderer is NULL");
    rc = mesh_validate(msh, err);
    if (rc)
        return rc;
    if ((size_t)msh->ntris > (size_t)INT32_MAX / 3)
        return glint_err_set(err, GLINT_ERANGE, "mesh of %d triangles too large to draw",
                             msh->ntris);
    rc = glr_enter(g, err);
    if (rc)
        return rc;
    m = calloc(1, sizeof *m);
    if (!m)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a mesh record");
    m->magic = GLR_MESH_MAGIC;
    m->owner = g;
    g->st.meshes++;

    /* Bounding sphere: box centre, farthest vertex. */
    nv = (size_t)msh->nverts;
    for (int c = 0; c < 3; c++)
        lo[c] = hi[c] = msh->pos[c];
    for (size_t i = 0; i < nv; i++)
        for (int c = 0; c < 3; c++) {
            double x = msh->pos[3 * i + c];
            lo[c] = x < lo[c] ? x : lo[c];
            hi[c] = x > hi[c] ? x : hi[c];
        }
    for (int c = 0; c < 3; c++)
        m->center[c] = 0.5 * (lo[c] + hi[c]);
    for (size_t i = 0; i < nv; i++) {
        double d2 = 0.0;
        for (int c = 0; c < 3; c++) {
            double d = msh->pos[3 * i + c] - m->center[c];
            d2 += d * d;
        }
        r2 = d2 > r2 ? d2 : r2;
    }
    m->radius = sqrt(r2);
    m->closed = glr_mesh_closed(msh);

    glr_gl_drain();
    arrays[0] = msh->pos;
    arrays[1] = msh->nrm;
    arrays[2] = msh->uv;
    glGenVertexArrays(1, &m->vao);
    if (m->vao)
        g->st.gl_objects++;
    glBindVertexArray(m->vao);
    for (int a = 0; a < 3; a++) {
        glGenBuffers(1, &m->vbo[a]);
        if (m->vbo[a])
            g->st.gl_objects++;
        glBindBuffer(GL_ARRAY_BUFFER, m->vbo[a]);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(nv * (size_t)ncomp[a] * sizeof(float)),
                     arrays[a], GL_STATIC_DRAW);
        glVertexAttribPointer((GLuint)a, ncomp[a], GL_FLOAT, GL_FALSE, 0, NULL);
        glEnableVertexAttribArray((GLuint)a);
    }
    glGenBuffers(1, &m->ibo);
    if (m->ibo)
        g->st.gl_objects++;
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m->ibo);
    m->nidx = (GLsizei)(3 * (size_t)msh->ntris);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)((size_t)m->nidx * sizeof(uint32_t)),
                 msh->tri, GL_STATIC_DRAW);
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    rc = glr_gl_check(err, "uploading a mesh");
    if (rc) {
        glint_err_prefix(err, "mesh of %d vertices, %d triangles", msh->nverts, msh->ntris);
        glr_mesh_free(g, m);
        return rc;
    }
    *out = m;
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Render targets                                                            */
/* ------------------------------------------------------------------------ */

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
static int glr_target_fit(glr *g, glr_target *t, int ncolor, int w, int h, glint_err *err)
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

/* Read colour buffer `att` (w x h, RGBA float) and hand every strip of
 * rows to fn(ctx, first_row, nrows, rgba). */
typedef void (*glr_strip_fn)(void *ctx, int row0, int nrows, const float *rgba);

static int glr_readback(glr *g, int att, int w, int h, glr_strip_fn fn, void *ctx,
                        glint_err *err)
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
static int glr_draw(glr *g, int prog, glr_target *t, int ncolor, const glr_mesh *m,
                    const scene_view *v, int w, int h, const float clear0[4], glint_err *err)
{
    static const float zero[4] = {0, 0, 0, 0};
    const glr_locs *l = &g->loc[prog];
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
    glUseProgram(g->prog[prog]);
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

static int glr_common_checks(glr *g, const glr_mesh *m, const scene_view *v, int w, int h,
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
    rc = glr_draw(g, GLR_PROG_GBUF, &g->gt, 3, m, v, width, height, clear0, err);
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
    glUniform1f(l->gain, (float)(scale * v->light_intensity));
    glUniform1i(l->kind, (GLint)b->kind);
    glUniform3fv(l->kd, 1, kd);
    glUniform3fv(l->ks, 1, ks);
    glUniform3fv(l->f0, 1, f0);
    glUniform1f(l->exponent, (float)b->exponent);
    glUniform1f(l->rough, (float)b->roughness);
    clear0[0] = clear0[1] = clear0[2] = background;
    clear0[3] = 0.0f;
    rc = glr_draw(g, GLR_PROG_BASE, &g->ct, 1, m, v, width, height, clear0, err);
    if (rc)
        return rc;
    return glr_color_readback(g, width, height, out, err);
}

/* Upload the log-factors (RGBA32F, res x 3) unless the texture holds them. */
static int glr_factors_upload(glr *g, const hf_factors *f, glint_err *err)
{
    int R = f->res;
    size_t n = (size_t)3 * R * 4;
    float *buf;
    int same;

    if (R > g->max_tex)
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "factor resolution %d above the texture limit %d", R,
                             (int)g->max_tex);
    buf = malloc(n * sizeof *buf);
    if (!buf)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a factor texture");
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < R; k++) {
            float *t = buf + 4 * ((size_t)j * R + k);
            for (int c = 0; c < 3; c++)
                t[c] = (float)f->logf[((size_t)j * R + k) * 3 + c];
            t[3] = 0.0f;
        }
    same = g->fac_tex && g->fac_res == R && g->fac_cache &&
           memcmp(buf, g->fac_cache, n * sizeof *buf) == 0;
    glActiveTexture(GL_TEXTURE0);
    if (!g->fac_tex) {
        glGenTextures(1, &g->fac_tex);
        g->st.gl_objects++;
    }
    glBindTexture(GL_TEXTURE_2D, g->fac_tex);
    if (same) {
        free(buf);
        return 0;
    }
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    if (g->fac_res != R)
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, R, 3, 0, GL_RGBA, GL_FLOAT, buf);
    else
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, R, 3, GL_RGBA, GL_FLOAT, buf);
    g->st.factor_uploads++;
    free(g->fac_cache);
    g->fac_cache = buf;
    g->fac_res = R;
    {
        int rc = glr_gl_check(err, "uploading the factor texture");
        if (rc) {
            g->fac_res = 0; /* force a full re-specification next time */
            return rc;
        }
    }
    return 0;
}

int glr_material_ok(const material *mat, glint_err *err)
{
    const hf_factors *f;

    if (!mat)
        return glint_err_set(err, GLINT_EINVAL, "material is NULL");
    f = &mat->fac;
    if (f->res < HF_RES_MIN || f->res > HF_RES_MAX || !f->logf)
        return glint_err_set(err, GLINT_EINVAL,
                             "material has no factors (res %d, expected %d..%d)", f->res,
                             HF_RES_MIN, HF_RES_MAX);
    if ((int)f->map.kind < HF_MAP_LOG || (int)f->map.kind > HF_MAP_SUB)
        return glint_err_set(err, GLINT_EINVAL, "material mapping kind %d unknown",
                             (int)f->map.kind);
    for (int c = 0; c < 3; c++)
        if (!isfinite(f->a_used[c]))
            return glint_err_set(err, GLINT_ENONFINITE, "material a_used[%d] is not finite",
                                 c);
    for (size_t i = 0; i < (size_t)9 * f->res; i++)
        if (!isfinite(f->logf[i]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "material log-factor %zu (factor %zu, texel %zu) is not finite",
                                 i, i / (3 * (size_t)f->res), (i / 3) % (size_t)f->res);
    return 0;
}

static int glr_preview_in(glr *g, const glr_mesh *m, const material *mat,
                          const scene_view *v, int width, int height, float background,
                          img *out, glint_err *err)
{
    const glr_locs *l;
    const hf_factors *f;
    float clear0[4], a[3];
    int rc;

    if (out)
        memset(out, 0, sizeof *out);
    rc = glr_material_ok(mat, err);
    if (rc)
        return rc;
    if (!isfinite(background))
        return glint_err_set(err, GLINT_ENONFINITE, "background is not finite");
    rc = glr_common_checks(g, m, v, width, height, out, err);
    if (rc)
        return rc;
    f = &mat->fac;
    rc = glr_factors_upload(g, f, err);
    if (rc)
        return rc;
    l = &g->loc[GLR_PROG_PREVIEW];
    for (int c = 0; c < 3; c++)
        a[c] = (float)f->a_used[c];
    glUseProgram(g->prog[GLR_PROG_PREVIEW]);
    glUniform1i(l->res, f->res);
    glUniform1i(l->map_kind, (GLint)f->map.kind);
    glUniform3fv(l->a, 1, a);
    glUniform1i(l->model_brdf, f->model == HF_MODEL_BRDF);
    glUniform1f(l->light_intensity, (float)v->light_intensity);
    clear0[0] = clear0[1] = clear0[2] = background;
    clear0[3] = 0.0f;
    rc = glr_draw(g, GLR_PROG_PREVIEW, &g->ct, 1, m, v, width, height, clear0, err);
    if (rc)
        return rc;
    return glr_color_readback(g, width, height, out, err);
}

/* ---- public entry points: enter, work, leave ----------------------------- */

int glr_program_check(glr *g, const char *vert_src, const char *frag_src, glint_err *err)
{
    int rc = glr_program_check_in(g, vert_src, frag_src, err);
    glr_leave(g);
    return rc;
}

int glr_mesh_upload(glr *g, const mesh *msh, glr_mesh **out, glint_err *err)
{
    int rc = glr_mesh_upload_in(g, msh, out, err);
    glr_leave(g);
    return rc;
}

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
