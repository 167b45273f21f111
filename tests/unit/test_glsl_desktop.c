/* The shader export's desktop stages (glr_glsl_desktop, glint_material_330.*)
 * compile and link in a desktop OpenGL 3.3 core context: the shared vertex
 * stage with each built-in method's fragment stage.  The context is made
 * here through EGL with the OpenGL API bound (llvmpipe without a GPU); the
 * GL entry points come from eglGetProcAddress, so nothing links libGL. */
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "glr.h"
#include "glr_shaders.h"
#include "method_hf2d.h"
#include "method_hf3.h"
#include "method_hf4.h"
#include "method_maps.h"
#include "method_srbf.h"

typedef unsigned int gl_uint;
typedef int gl_int;
typedef unsigned int gl_enum;
#define GL_FRAGMENT_SHADER 0x8B30
#define GL_VERTEX_SHADER 0x8B31
#define GL_COMPILE_STATUS 0x8B81
#define GL_LINK_STATUS 0x8B82
#define GL_VERSION 0x1F02

static struct {
    gl_uint (*create_shader)(gl_enum);
    void (*shader_source)(gl_uint, int, const char *const *, const gl_int *);
    void (*compile_shader)(gl_uint);
    void (*get_shaderiv)(gl_uint, gl_enum, gl_int *);
    void (*get_shader_log)(gl_uint, int, int *, char *);
    gl_uint (*create_program)(void);
    void (*attach_shader)(gl_uint, gl_uint);
    void (*link_program)(gl_uint);
    void (*get_programiv)(gl_uint, gl_enum, gl_int *);
    void (*get_program_log)(gl_uint, int, int *, char *);
    const unsigned char *(*get_string)(gl_enum);
} gl;

static char why[256];

/* Fetch an entry point into the function pointer at `slot` (1 if found). */
static int get_proc(const char *name, void *slot, size_t size)
{
    __eglMustCastToProperFunctionPointerType p = eglGetProcAddress(name);
    if (!p || size != sizeof p)
        return 0;
    memcpy(slot, &p, sizeof p);
    return 1;
}

/* A current desktop OpenGL 3.3 core context, or 0 with `why` set. */
static int desktop_context(void)
{
    typedef EGLDisplay (*gpd_fn)(EGLenum, void *, const EGLint *);
    static const EGLint cfg_attr[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                      EGL_OPENGL_BIT, EGL_NONE};
    static const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    static const EGLint pb_attr[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
    gpd_fn gpd = (gpd_fn)eglGetProcAddress("eglGetPlatformDisplayEXT");
    EGLDisplay dpy = gpd ? gpd(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL)
                         : eglGetDisplay(EGL_DEFAULT_DISPLAY);
    EGLConfig cfg;
    EGLContext ctx;
    EGLSurface surf;
    EGLint n = 0, maj, min;
    if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &maj, &min))
        return snprintf(why, sizeof why, "no EGL display"), 0;
    if (!eglBindAPI(EGL_OPENGL_API))
        return snprintf(why, sizeof why, "eglBindAPI(OpenGL) failed"), 0;
    if (!eglChooseConfig(dpy, cfg_attr, &cfg, 1, &n) || n < 1)
        return snprintf(why, sizeof why, "no OpenGL pbuffer config"), 0;
    if ((ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctx_attr)) == EGL_NO_CONTEXT)
        return snprintf(why, sizeof why, "no OpenGL 3.3 core context (0x%x)", eglGetError()), 0;
    surf = eglCreatePbufferSurface(dpy, cfg, pb_attr);
    if (!eglMakeCurrent(dpy, surf, surf, ctx))
        return snprintf(why, sizeof why, "eglMakeCurrent failed (0x%x)", eglGetError()), 0;
#define GET(f, name) (get_proc(name, &gl.f, sizeof gl.f))
    if (!GET(create_shader, "glCreateShader") || !GET(shader_source, "glShaderSource") ||
        !GET(compile_shader, "glCompileShader") || !GET(get_shaderiv, "glGetShaderiv") ||
        !GET(get_shader_log, "glGetShaderInfoLog") || !GET(create_program, "glCreateProgram") ||
        !GET(attach_shader, "glAttachShader") || !GET(link_program, "glLinkProgram") ||
        !GET(get_programiv, "glGetProgramiv") || !GET(get_program_log, "glGetProgramInfoLog") ||
        !GET(get_string, "glGetString"))
        return snprintf(why, sizeof why, "missing GL entry points"), 0;
#undef GET
    printf("  desktop context: %s\n", (const char *)gl.get_string(GL_VERSION));
    return 1;
}

/* Compile and link; 0, or -1 with the log printed. */
static int build(const char *vert, const char *frag, const char *what)
{
    const char *src[2] = {vert, frag};
    gl_uint prog = gl.create_program();
    char log[2048];
    gl_int ok;
    for (int k = 0; k < 2; k++) {
        gl_uint sh = gl.create_shader(k ? GL_FRAGMENT_SHADER : GL_VERTEX_SHADER);
        gl.shader_source(sh, 1, &src[k], NULL);
        gl.compile_shader(sh);
        gl.get_shaderiv(sh, GL_COMPILE_STATUS, &ok);
        if (!ok) {
            gl.get_shader_log(sh, sizeof log, NULL, log);
            fprintf(stderr, "  %s: %s stage: %s\n", what, k ? "fragment" : "vertex", log);
            return -1;
        }
        gl.attach_shader(prog, sh);
    }
    gl.link_program(prog);
    gl.get_programiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) {
        gl.get_program_log(prog, sizeof log, NULL, log);
        fprintf(stderr, "  %s: link: %s\n", what, log);
        return -1;
    }
    return 0;
}

TEST(every_method_in_a_desktop_context)
{
    static const struct { const char *name, *frag; } methods[] = {
        {"hf3", hf3_glsl_frag}, {"srbf", srbf_glsl_frag}, {"hf4", hf4_glsl_frag},
        {"hf2d", hf2d_glsl_frag}, {"maps", maps_glsl_frag}};
    char *vert = glr_glsl_desktop(GLR_VERT_SRC);
    ASSERT(vert && strncmp(vert, "#version 330 core\n", 18) == 0);
    ASSERT_MSG(desktop_context(), "%s", why);
    for (size_t i = 0; i < sizeof methods / sizeof *methods; i++) {
        char *frag = glr_glsl_desktop(methods[i].frag);
        ASSERT(frag);
        ASSERT_MSG(build(vert, frag, methods[i].name) == 0, "%s does not build", methods[i].name);
        printf("  %s: compiles and links as GLSL 3.30 core\n", methods[i].name);
        free(frag);
    }
    /* and a broken one is seen as broken */
    ASSERT(build(vert, "#version 330 core\nvoid main() { nonsense; }\n", "broken") != 0);
    ASSERT(glr_glsl_desktop("#version 100\n") == NULL);
    free(vert);
}

TEST_LIST {
    TEST_ENTRY(every_method_in_a_desktop_context),
};

TEST_MAIN()
