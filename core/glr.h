/* glr.h: headless OpenGL ES 3 rendering through EGL, with no window system.
 *
 * On machines without a GPU this is Mesa's llvmpipe; where a GPU exists, the
 * vendor's driver.  glr_open() picks a working platform by itself, in this
 * order: EGL_PLATFORM_SURFACELESS_MESA, EGL devices (EGL_EXT_platform_device),
 * the default display; if none gives an OpenGL ES 3 context it fails with a
 * message listing what each attempt said.  Environment: libEGL (libglvnd)
 * and a Mesa driver (package libgl1-mesa-dri) or a vendor EGL driver;
 * EGL_PLATFORM need not be set.  GLINT_EGL_DEVICE=N picks the N-th device.
 *
 * A glr holds one context and the compiled programs; create it once per
 * process and reuse it (rendering never pays for context creation).  A glr
 * must be used by one thread at a time; each call makes its context current
 * on the calling thread.
 *
 * Conventions are the CPU rasterizer's (raster.h, scene.h): the same camera,
 * projection and pixel centres, so G-buffers agree with raster_view() and
 * previews with material_shade() on the CPU G-buffer.  Images come back with
 * row 0 at the top. */
#ifndef GLINT_GLR_H
#define GLINT_GLR_H

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

/* Create the context and compile the programs (OUT: *out). */
int glr_open(glr **out, glint_err *err);
void glr_close(glr *g);

/* Renderer and platform in words, e.g. "llvmpipe (LLVM 15.0.6, 256 bits),
 * EGL 1.5 surfaceless". */
const char *glr_describe(const glr *g);

/* Upload a mesh (positions, normals, uvs, indices).  The glr_mesh belongs to
 * g and must be freed before glr_close. */
int glr_mesh_upload(glr *g, const mesh *m, glr_mesh **out, glint_err *err);
void glr_mesh_free(glr *g, glr_mesh *m);

/* G-buffer of a view (same channels as raster_view). */
int glr_gbuffer(glr *g, const glr_mesh *m, const scene_view *v, int width, int height,
                gbuf *out, glint_err *err);

/* Base render: the view shaded with an analytic BRDF (the image an artist
 * paints over): scale * light intensity * f * max(0, n.wi) on covered
 * pixels, `background` elsewhere.  RGB float. */
int glr_base_render(glr *g, const glr_mesh *m, const scene_view *v, int width, int height,
                    const brdf *b, double scale, float background, img *out,
                    glint_err *err);

/* Preview of a fitted material for any camera and point light: the shader
 * evaluates exactly the factor product that hf_factors_eval() evaluates on
 * the CPU.  RGB float, up to GLR_MAX_SIZE square. */
int glr_preview(glr *g, const glr_mesh *m, const material *mat, const scene_view *v,
                int width, int height, float background, img *out, glint_err *err);

/* Write the material's shader for use in any OpenGL ES 3 / WebGL 2
 * renderer: dir/glint_material.frag and .vert (GLSL ES 3.00), the factor
 * texture dir/glint_factors.exr (log-factors, RGB float, 3 rows of res
 * texels) plus dir/glint_factors_rgba16f.bin (raw half floats for WebGL), and
 * dir/shader.json, the manifest of how to bind them (attribute, uniform and
 * texture names, texel convention, mapping constants). */
int glr_shader_export(const material *mat, const char *dir, glint_err *err);

#endif
