/* glr.h: headless OpenGL ES 3 rendering through EGL, with no window system.
 *
 * On machines without a GPU this is Mesa's llvmpipe; where a GPU exists, the
 * vendor's driver.  glr_open() picks a working platform by itself, in this
 * order: EGL_PLATFORM_SURFACELESS_MESA, EGL devices (EGL_EXT_platform_device),
 * the default display; if none gives an OpenGL ES 3 context it fails with a
 * message listing what each attempt said.  Environment: libEGL (libglvnd)
 * and a Mesa driver (package libgl1-mesa-dri) or a vendor EGL driver;
 * EGL_PLATFORM need not be set.  GLINT_EGL_DEVICE=N picks the N-th device
 * of eglQueryDevicesEXT (from 0); then only that device is tried.
 * GLINT_EGL=off makes glr_open fail (GLINT_EUNSUPPORTED) so that automatic
 * renders take the CPU: the sanitizer build's daemon runs so in the test
 * command (llvmpipe's JIT hung a preview under AddressSanitizer).
 *
 * A glr holds one context and the compiled programs; create it once per
 * process and reuse it (rendering never pays for context creation).  A glr
 * must be used by one thread at a time (the caller serializes); each call
 * makes its context current on the calling thread and releases it before
 * returning, so successive calls may come from different threads.
 *
 * Conventions are the CPU rasterizer's (raster.h, scene.h): the same camera,
 * projection and pixel centres, so G-buffers agree with raster_view() and
 * previews with material_shade() on the CPU G-buffer.  Images come back with
 * row 0 at the top.  Agreement is to float precision except where a pixel
 * centre lies within the GPU's sub-pixel snapping (llvmpipe: 1/256 pixel)
 * of a silhouette or occluding edge: there coverage can differ.
 *
 * Sizes: width and height in 1..GLR_MAX_SIZE (else GLINT_ERANGE; sizes the
 * driver cannot allocate give GLINT_EUNSUPPORTED).  Render targets are kept
 * between calls and reallocated only when a size does not fit.  GL errors
 * become GLINT_ENOMEM (GL_OUT_OF_MEMORY) or GLINT_EINTERNAL, with the GL
 * error's name and the step in the message; nothing aborts.
 *
 * Meshes that are closed and consistently wound (checked at upload) are
 * drawn front faces only while the eye is outside their bounding sphere,
 * which changes no pixel (such a back face always lies behind a front
 * face) and halves the triangles to set up; other meshes are drawn with
 * both faces, as raster.c does. */
#ifndef GLINT_GLR_H
#define GLINT_GLR_H

#include <stdint.h>

#include "brdf.h"
#include "err.h"
#include "gbuf.h"
#include "img.h"
#include "material.h"
#include "mesh.h"
#include "scene.h"

#define GLR_MAX_SIZE 4096

typedef struct glr glr;           /* context + programs (opaque) */
typedef struct glr_mesh glr_mesh; /* a mesh uploaded to a glr (opaque) */

/* Create the context and compile the programs (OUT: *out).  Fails with
 * GLINT_EUNSUPPORTED when no platform gives an OpenGL ES 3 context with
 * float colour buffers (the message lists each attempt), GLINT_EINVAL for
 * a malformed GLINT_EGL_DEVICE.  Several glr may live in one process. */
int glr_open(glr **out, glint_err *err);
/* Release the context, programs and targets.  Accepts NULL. */
void glr_close(glr *g);

/* Release the render targets when they hold more than keep_pixels pixels
 * (a large preview's buffers are not kept between draws: what the context
 * holds between calls stays bounded).  Accepts NULL. */
void glr_trim_targets(glr *g, long keep_pixels);

/* Renderer and platform in words, e.g. "llvmpipe (LLVM 15.0.6, 256 bits),
 * OpenGL ES 3.2 Mesa 22.3.6, EGL 1.5 surfaceless".  Owned by g. */
const char *glr_describe(const glr *g);

/* Upload a mesh (positions, normals, uvs, indices) after mesh_validate()
 * (its errors are returned).  The glr_mesh belongs to g and must be freed
 * (glr_mesh_free, which accepts NULL) before glr_close; passing it to
 * another glr gives GLINT_EINVAL. */
int glr_mesh_upload(glr *g, const mesh *m, glr_mesh **out, glint_err *err);
void glr_mesh_free(glr *g, glr_mesh *m);

/* G-buffer of a view (same channels as raster_view; OUT: *out, allocated
 * here, caller frees with gbuf_free).  Position, normal (renormalized per
 * fragment) and uv come from RGBA32F targets; wi and wo are computed on
 * readback in double from the position. */
int glr_gbuffer(glr *g, const glr_mesh *m, const scene_view *v, int width, int height,
                gbuf *out, glint_err *err);

/* Base render: the view shaded with an analytic BRDF (the image an artist
 * paints over): scale * light intensity * f * max(0, n.wi) on covered
 * pixels, `background` elsewhere.  RGB float (OUT: *out, allocated here). */
int glr_base_render(glr *g, const glr_mesh *m, const scene_view *v, int width, int height,
                    const brdf *b, double scale, float background, img *out,
                    glint_err *err);

/* Preview of a fitted material for any camera and point light: the shader
 * evaluates exactly the factor product that hf_factors_eval() evaluates on
 * the CPU (the exponent of the summed log-factors is capped at 88 instead
 * of 700, to stay finite in float).  Values are per the view's light
 * intensity; `background` where nothing is drawn, 0 on covered pixels
 * that are not lit and seen, like material_shade().  RGB float, up to
 * GLR_MAX_SIZE square (OUT: *out, allocated here).  The factor texture is
 * uploaded only when the material's factors change. */
int glr_preview(glr *g, const glr_mesh *m, const material *mat, const scene_view *v,
                int width, int height, float background, img *out, glint_err *err);

/* Draw the mesh with one colour per vertex (rgb: 3 floats for each of the
 * mesh's nverts vertices, in the order uploaded), interpolated across each
 * triangle (perspective-correct): how environment-lit previews are drawn
 * (envlit.h).  Background pixels get `background`.  OUT: *out (RGB,
 * allocated here) and, when mask is not NULL, mask[width x height]: 1
 * where the mesh covers the pixel, 0 elsewhere.  Non-finite colours:
 * GLINT_ENONFINITE. */
int glr_vertex_colors(glr *g, const glr_mesh *m, const scene_view *v, int width, int height,
                      const float *rgb, int nverts, float background, img *out, uint8_t *mask,
                      glint_err *err);

/* Write the material's shader for use in any OpenGL ES 3 / WebGL 2
 * renderer: dir/glint_material.frag and .vert (GLSL ES 3.00), the factor
 * texture dir/glint_factors.exr (log-factors, RGB float, 3 rows of res
 * texels) plus dir/glint_factors_rgba16f.bin (raw half floats for WebGL) and
 * dir/glint_factors16.png (16 bits, each channel scaled to its range), the
 * same stages as GLSL 3.30 core (glint_material_330.*), and
 * dir/shader.json, the manifest of how to bind them (attribute, uniform and
 * texture names, texel convention, mapping constants and their values).
 * The fragment shader is the very text glr_preview() draws with.  Needs no
 * GL context; dir is created if missing; files are written atomically. */
int glr_shader_export(const material *mat, const char *dir, glint_err *err);

/* The desktop variant of a GLSL ES 3.00 stage: "#version 330 core" for its
 * first line (precision qualifiers are accepted and ignored there), the
 * rest the same text; the shader export writes it as glint_material_330.*.
 * malloc'ed, or NULL when `es` does not start "#version 300 es". */
char *glr_glsl_desktop(const char *es);

/* Compile and link a vertex + fragment pair in g's context (e.g. the files
 * glr_shader_export wrote), then delete it: 0, or GLINT_EFORMAT with the
 * compiler's or linker's log in the message. */
int glr_program_check(glr *g, const char *vert_src, const char *frag_src, glint_err *err);

/* Draw mesh m from view v (w x h, RGB) with a fragment stage of the
 * caller's (GLSL ES 3.00: GLSL_STAGE_IO's inputs and o_color, glsl_parts.h)
 * after the shared vertex stage, u_eye, u_light and u_light_intensity set
 * from v: how exported shader code (e.g. a BRDF Explorer BRDF()) is run
 * to be checked.  GLINT_EFORMAT with the compiler's log if it does not
 * build. */
int glr_render_fragment(glr *g, const glr_mesh *m, const char *frag_src, const scene_view *v,
                        int width, int height, img *out, glint_err *err);

/* Counters for tests and benchmarks (context reuse, leaks); OUT: *out
 * (zeros for a NULL g). */
typedef struct glr_stats {
    long gl_objects;     /* GL objects g created that are still alive */
    long meshes;         /* glr_mesh objects alive */
    long frames;         /* draws done (G-buffer, base render, preview) */
    long culled_frames;  /* of which drew front faces only (closed mesh, eye outside) */
    long target_allocs;  /* render-target (re)allocations */
    long factor_uploads; /* factor texture uploads (skipped when unchanged) */
} glr_stats;

void glr_get_stats(const glr *g, glr_stats *out);

#endif
