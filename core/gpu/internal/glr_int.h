/* glr_int.h: internals shared by the files of the glr module.  Not part of
 * core's contract (that is glr.h); only glr*.c and tests include it.
 *
 * The module, one concern per file:
 *   glr.c              context: EGL platform selection, open / close,
 *                      entering and leaving the context, GL error checks
 *   glr_program.c      compiling and linking the programs, uniform locations
 *   glr_mesh.c         meshes: upload, bounding sphere, closed-surface test
 *   glr_draw.c         render targets, camera projection, the common draw
 *                      and the strip-wise readback
 *   glr_render.c       the images: G-buffers, base renders, previews
 *   glr_material.c     what previews need of a material (any method): its
 *                      program, texture and uniforms (material_gpu)
 *   glr_export.c       the shader export (no GL context)
 *   glr_vcol.c         draws with one colour per vertex (environment-lit previews)
 *   glr_shaders.h      GLSL sources of the generic stages
 *
 * Every public entry makes the context current (glr_enter), works, and
 * releases it (glr_leave); the internal functions below assume the context
 * is current unless they say otherwise. */
#ifndef GLINT_GLR_INT_H
#define GLINT_GLR_INT_H

#include <EGL/egl.h>
#include <GLES3/gl3.h>
#include <stddef.h>
#include <stdint.h>

#include "err.h"
#include "glr.h"
#include "material.h"

#define GLR_STRIP_BYTES ((size_t)8 << 20) /* readback strip buffer */

enum { GLR_PROG_GBUF = 0, GLR_PROG_BASE, GLR_PROG_VCOL, GLR_NPROG };
#define GLR_MAX_MATERIAL_PROGS 8

/* Uniform locations of one program (-1 where a program lacks one). */
typedef struct glr_locs {
    GLint model, normal_matrix, view_proj, eye, light, light_intensity;
    /* base */
    GLint gain, kind, kd, ks, f0, exponent, rough, rough_y;
    /* vertex colours */
    GLint vcol, vcol_w;
} glr_locs;

/* A material program: a method's fragment stage with the shared vertex
 * stage, compiled on first use. */
typedef struct glr_mprog {
    char name[32];
    GLuint prog;
    glr_locs loc;
} glr_mprog;

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
    glr_mprog mprog[GLR_MAX_MATERIAL_PROGS];
    int nmprog;
    GLuint mat_tex;        /* the material texture (unit 0) */
    int mat_tex_w, mat_tex_h;
    float *mat_tex_cache;  /* what mat_tex holds: w x h x 4 floats */
    GLuint vcol_tex;       /* per-vertex colours (unit 1), vcol_w x vcol_h */
    int vcol_w, vcol_h;
    float *strip;     /* readback buffer, GLR_STRIP_BYTES */
    glr_stats st;
};

struct glr_mesh {
    uint32_t magic;
    const glr *owner;
    GLuint vao, vbo[3], ibo;
    GLsizei nidx;
    int nverts;
    double center[3], radius; /* bounding sphere */
    int closed; /* +1 / -1: closed, consistently wound, facing out / in; 0: open */
};

/* ---- glr.c: context and GL errors --------------------------------------- */

/* Make g's context current on the calling thread (a no-op when it is):
 * 0, or GLINT_EINTERNAL with the EGL error's name. */
int glr_enter(const glr *g, glint_err *err);
/* Release g's context if it is current on this thread.  Accepts NULL. */
void glr_leave(const glr *g);
/* Drop GL errors left by earlier calls (they belong to nobody). */
void glr_gl_drain(void);
/* Turn pending GL errors into a glint error naming the step `what`:
 * GLINT_ENOMEM for GL_OUT_OF_MEMORY, else GLINT_EINTERNAL; 0 if none. */
int glr_gl_check(glint_err *err, const char *what);

/* ---- glr_program.c ------------------------------------------------------- */

/* Compile and link every program of g (g->prog, g->loc) and set their
 * constant uniforms.  0, or GLINT_EFORMAT with the compiler's or linker's
 * log; the programs made before a failure stay in g for glr_close. */
int glr_programs_build(glr *g, glint_err *err);

/* Link a vertex and fragment stage (0 with *err set: GLINT_EFORMAT and the
 * log); `what` names it in messages.  Its uniform locations (OUT: *l). */
GLuint glr_link(const char *vs_src, const char *fs_src, const char *what, glint_err *err);
void glr_locs_get(GLuint p, glr_locs *l);

/* ---- glr_mesh.c ---------------------------------------------------------- */

/* Is m a live mesh uploaded to g?  0 or GLINT_EINVAL. */
int glr_mesh_ok(const glr *g, const glr_mesh *m, glint_err *err);

/* ---- glr_draw.c ---------------------------------------------------------- */

/* Delete t's framebuffer and renderbuffers (those that exist) and zero t. */
void glr_target_release(glr *g, glr_target *t);
/* Make t at least w x h (ncolor RGBA32F buffers + 32F depth) and bind it as
 * the draw and read framebuffer. */
int glr_target_fit(glr *g, glr_target *t, int ncolor, int w, int h, glint_err *err);

/* Checks shared by every draw (renderer, output, mesh, view, size), then
 * enter the context and drain old GL errors.  On failure the context may
 * be current: the caller leaves it as usual. */
int glr_common_checks(glr *g, const glr_mesh *m, const scene_view *v, int w, int h,
                      void *out, glint_err *err);

/* One draw of mesh m seen from v into target t (ncolor buffers, w x h):
 * program `prog` (uniform locations l) with its camera uniforms (other
 * uniforms are the caller's, set before), state, clear (colour buffer 0 to
 * clear0, the others to 0, depth to 1), draw. */
int glr_draw(glr *g, GLuint prog, const glr_locs *l, glr_target *t, int ncolor,
             const glr_mesh *m, const scene_view *v, int w, int h, const float clear0[4],
             glint_err *err);

/* Read colour buffer `att` of the bound target (w x h, RGBA float) and hand
 * every strip of rows, top row first, to fn(ctx, first_row, nrows, rgba). */
typedef void (*glr_strip_fn)(void *ctx, int row0, int nrows, const float *rgba);
int glr_readback(glr *g, int att, int w, int h, glr_strip_fn fn, void *ctx, glint_err *err);

/* ---- glr_material.c -------------------------------------------------------- */

/* How the GPU evaluates a material (material_gpu_get), checked: a shader,
 * a finite texture and finite uniforms.  Needs no GL context.  OUT: *gpu
 * (material_gpu_free). */
int glr_material_gpu(const material *mat, material_gpu *gpu, glint_err *err);

/* Make the material's program current (compiled on first use) and give it
 * its texture on unit 0 (uploaded only when it changed), its uniforms and
 * the light intensity of view v.  OUT: *prog. */
int glr_material_bind(glr *g, const material_gpu *gpu, const scene_view *v,
                      const glr_mprog **prog, glint_err *err);

#endif
