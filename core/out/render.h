/* render.h: rendering for the command line and the daemon: base renders
 * (an analytic BRDF: what an artist paints over) and material previews,
 * through EGL or on the CPU, for any camera.
 *
 * Engines.  RENDER_EGL renders through glr.h (a GPU where there is one,
 * llvmpipe otherwise) and fails with GLINT_EUNSUPPORTED when no EGL
 * platform works; RENDER_CPU rasterizes with raster.h and shades on the
 * CPU (the reference: paint.h for base renders, material_render for
 * previews; any size up to SCENE_MAX_SIZE, in bands of rows so memory
 * beyond the image stays bounded); RENDER_AUTO uses EGL when it works and
 * the CPU otherwise (a failed EGL draw is reported once on stderr and
 * redone on the CPU).  Both engines agree to float precision except at
 * silhouettes (glr.h).  The EGL context is opened on first use and kept;
 * meshes uploaded to it are kept by key (the caller's name for a mesh that
 * never changes, e.g. a scene id), the least recently used dropped beyond
 * `gl_meshes`.
 *
 * Cameras.  render_camera_view() turns a request (one of the scene's
 * views, or a free camera: eye, light, optional target, field of view and
 * light intensity) into a scene_view, checked: the daemon's previews and
 * the command line's render use it.
 *
 * Thread-safety: a render may be used from any thread; its EGL work is
 * serialized inside (one draw at a time), CPU renders run concurrently. */
#ifndef GLINT_RENDER_H
#define GLINT_RENDER_H

#include <stddef.h>

#include "cancel.h"
#include "err.h"
#include "img.h"
#include "material.h"
#include "mesh.h"
#include "scene.h"

typedef enum { RENDER_AUTO = 0, RENDER_EGL = 1, RENDER_CPU = 2 } render_engine;

/* "auto", "egl" or "cpu" (GLINT_EINVAL naming them otherwise). */
int render_engine_parse(const char *text, render_engine *out, glint_err *err);

typedef struct render render;

/* An upper bound of the memory one render of width x height pixels takes
 * beyond its inputs, the caller's encoding of the answer (PNG or EXR)
 * included, in bytes: what a service admits a render by.  base: a base
 * render (render_base), else a material preview.  Measured
 * (tests/bench/bench_memory.py: growth of the daemon's peak RSS, llvmpipe,
 * the EGL context opened before): a CPU preview 15 to 16 bytes per pixel, an
 * EGL one 30 to 36 (its float target and depth buffer), a CPU base render 57
 * (a whole G-buffer), plus about 10 MiB whatever the size (a thread's
 * allocator arena, the encoder); the bounds are 20, 40 and 72 bytes per
 * pixel plus RENDER_FIXED_BYTES.  The EGL context itself (about 110 MiB
 * once) is not a render's. */
size_t render_peak_bytes(render_engine eng, int base, int width, int height);

/* The same for render_gbuffer_exr (measured 193 bytes per pixel: the
 * G-buffer, its 17 float channels and the encoder's copy; bound 224). */
size_t render_gbuffer_peak_bytes(int width, int height);

/* The part of the bounds above that does not grow with the size. */
#define RENDER_FIXED_BYTES ((size_t)16 << 20)

/* ---- cost --------------------------------------------------------------------------
 * An estimate of the time one render takes, in seconds of one core, from
 * its parameters: what a service refuses a render by before it starts
 * (glintd --work-max-seconds).  Its terms:
 *   eval   one evaluation of the material (material_eval_at; its preview
 *          evaluation for EGL's vertex shading) or of the base render's
 *          BRDF, timed here and now on a few direction pairs (the least of
 *          three rounds: about a millisecond for the slowest materials,
 *          srbf at basis_res 16);
 *   RENDER_COST_PIXEL_S  a pixel's rasterizing, G-buffer and encoding;
 *   RENDER_COST_RAY_S    a shadow ray (Embree).
 * Every pixel is counted (the object covers a part of them the estimate
 * does not know), and under an environment half the lights (those facing
 * a point):
 *   point light            pixels x (PIXEL + eval), EGL too (llvmpipe
 *                          shades fragments no faster than the CPU:
 *                          measured 16 s and 13 s for an srbf material at
 *                          1024 x 1024);
 *   environment, CPU       pixels x (PIXEL + lights/2 x (eval + RAY if
 *                          shadows));
 *   environment, EGL       pixels x PIXEL + vertices x lights/2 x
 *                          (preview eval + RAY if shadows and the
 *                          vertices' visibility is not cached).
 * RENDER_AUTO is estimated as EGL when the renderer's context works (it is
 * opened by the estimate when not tried yet, as the render would), else
 * as the CPU.  Measured on the 2-vCPU development machine through glintd
 * (a 128 x 128 torus, 3 views): an hf3 preview at 1024 x 1024 on the CPU
 * 0.72 s (estimated 1.0 s); under a sky of 256 lights at 128 x 128 on the
 * CPU, 1.97 s with shadows and 0.59 s without (estimated 5.8 and 1.5 s:
 * about 40% of the pixels are covered); an srbf material (basis_res 10)
 * there 15.2 s (estimated 17.6 s). */
#define RENDER_COST_PIXEL_S 3e-7
#define RENDER_COST_RAY_S 2e-6

struct render_env;

/* The estimate from the evaluations' seconds (eval_preview_s: EGL's vertex
 * shading), for a render of anything; the two below time them. */
double render_cost_seconds(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                           const struct render_env *env, double eval_s, double eval_preview_s,
                           int width, int height);

/* The estimate of render_material (env NULL) or render_material_env, in
 * seconds. */
double render_material_cost(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                            const material *mat, const struct render_env *env, int width,
                            int height);

/* The estimate of render_base (env NULL) or render_base_env (OUT:
 * *seconds); errors as render_brdf_check's. */
int render_base_cost(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                     const char *brdf_spec, const struct render_env *env, int width, int height,
                     double *seconds, glint_err *err);

/* EGL render targets above this many pixels are released after each draw,
 * so what the context keeps between draws stays at 1024 x 1024 buffers. */
#define RENDER_GL_KEEP_PIXELS (1L << 20)

/* quiet: no line on stderr when EGL is unavailable or fails (the command
 * line prints its own).  OUT: *out. */
int render_open(int gl_meshes, int quiet, render **out, glint_err *err);
/* Release the EGL context and the meshes.  Accepts NULL. */
void render_close(render *r);

/* What drew an image, e.g. "egl; llvmpipe (LLVM 15.0.6, 256 bits), ..."
 * or "cpu" (OUT: buf). */
typedef struct render_used {
    char engine[256];
} render_used;

/* The base render of view v: scale * I * f * max(0, n.wi) with the
 * analytic BRDF `brdf_spec` (brdf.h's syntax, e.g. "lambert:kd=0.6", or
 * "merl:NAME", a measured material merl.h's resolver finds, or "sgd:NAME"
 * / "abc:NAME", a published fit of one (measured.h): shaded on the CPU,
 * RENDER_EGL refuses them), 0 on
 * background and unlit pixels.  r may be NULL for RENDER_CPU.  mesh_key
 * names the mesh for the EGL mesh cache (NULL: not cached).  OUT: *out
 * (RGB), *used (may be NULL). */
int render_base(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                const scene_view *v, int width, int height, const char *brdf_spec,
                double scale, img *out, render_used *used, const glint_cancel *cancel,
                glint_err *err);

/* Check a BRDF spec for render_base (0, or GLINT_EINVAL saying why). */
int render_brdf_check(const char *brdf_spec, glint_err *err);

/* A material preview for view v (its light intensity applied), 0 on
 * background pixels. */
int render_material(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                    const material *mat, const scene_view *v, int width, int height, img *out,
                    render_used *used, const glint_cancel *cancel, glint_err *err);

/* ---- under an environment ---------------------------------------------------------
 * Previews and base renders lit by an environment map compressed to
 * `lights` median-cut lights (env.h), with shadows (vis.h), for any camera
 * and any rotation of the environment.  RENDER_EGL shades the mesh's
 * vertices on the CPU and draws them interpolated through EGL (seed 004,
 * equation 22: what the paper's previews do on the GPU), with the method's
 * preview evaluation (material_eval_preview); RENDER_CPU shades every pixel
 * with its own shadow rays and the exact evaluation (the reference;
 * slower).  The two differ by the interpolation across triangles and the
 * preview evaluation's error (measured in BENCHMARKS.md).
 * The lights, the environment and the visibility of the vertices are kept
 * per (mesh_key, environment, rotation, intensity, lights, shadows), the
 * least recently used of RENDER_ENV_CACHE dropped; a new view of a cached
 * entry costs the shading and the draw.  Environment renders are serialized
 * among themselves (one cache lock). */

#define RENDER_ENV_MAX_LIGHTS 1024
#define RENDER_ENV_CACHE 4

typedef struct render_env {
    char spec[64];         /* env.h's spec: a built-in sky or what the resolver knows */
    double rotation_deg;   /* about +z, in [-360, 360] */
    double intensity;      /* radiance scale, (0, 1e6] */
    int lights;            /* 1..RENDER_ENV_MAX_LIGHTS */
    int shadows;           /* cast shadow rays (none needed on convex meshes) */
    int background;        /* draw the environment behind the object, else 0 */
} render_env;

/* spec "studio", rotation 0, intensity 1, 256 lights, shadows and background on. */
void render_env_init(render_env *e);

/* Check the fields (GLINT_EINVAL naming the one out of range). */
int render_env_check(const render_env *e, glint_err *err);

/* What an environment render did. */
typedef struct render_env_info {
    int lights;            /* lights shaded with */
    int convex;            /* shadows asked, mesh convex: no rays */
    int cached;            /* lights and visibility came from the cache */
    long rays;             /* shadow rays cast by this call */
    double prepare_s;      /* loading, compressing, casting (0 when cached) */
    double shade_s;        /* shading vertices or pixels */
    double draw_s;         /* drawing and reading back (EGL) */
    char env[64];          /* the environment's name */
} render_env_info;

/* A material preview under the environment (no light intensity of v: the
 * environment is the light).  info may be NULL. */
int render_material_env(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                        const material *mat, const render_env *env, const scene_view *v,
                        int width, int height, img *out, render_env_info *info,
                        render_used *used, const glint_cancel *cancel, glint_err *err);

/* The material ball: a unit sphere (RENDER_BALL_LAT rings x RENDER_BALL_LON
 * segments, with the built-in sphere's uv) that previews show a material
 * on, whatever the scene's object.  Built once on first use and shared
 * (never freed); its mesh key is RENDER_BALL_KEY.  Coarser than the
 * built-in sphere (256 x 512) so that vertex shading under an environment
 * stays within a frame's time (a ring spans about 4 pixels of a 512 x 512
 * ball framed as the scenes' views frame their object). */
#define RENDER_BALL_LAT 64
#define RENDER_BALL_LON 128
#define RENDER_BALL_KEY "builtin:ball"
int render_ball(const mesh **out, glint_err *err);

/* A base render under the environment: scale x B with the analytic BRDF. */
int render_base_env(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                    const char *brdf_spec, double scale, const render_env *env,
                    const scene_view *v, int width, int height, img *out,
                    render_env_info *info, render_used *used, const glint_cancel *cancel,
                    glint_err *err);

/* The CPU G-buffer of view v as OpenEXR bytes with named channels (mask,
 * P, N, uv, wi, wo, cos_i, cos_o: gbuf.h).  OUT: *data (malloc'ed), *len. */
int render_gbuffer_exr(const mesh *m, const scene_view *v, int width, int height, void **data,
                       size_t *len, glint_err *err);

/* The material's shader for other renderers (GLSL ES 3.00 stages, the
 * method's texture, shader.json): glr_shader_export(), which needs no GL
 * context. */
int render_export_shader(const material *m, const char *dir, glint_err *err);

/* A camera request. */
typedef struct render_camera {
    int view;            /* one of the scene's views, or -1 */
    int has_eye, has_light, has_target;
    double eye[3], light[3], target[3]; /* target defaults to the origin with an eye */
    double fov_deg;      /* vertical field of view in degrees (1..170), 0: the scene's */
    double intensity;    /* light intensity (0..1e6), < 0: the view's (1 for a free camera) */
} render_camera;

void render_camera_init(render_camera *c);

/* The view a request asks for: the scene's view `view` with what the
 * request overrides, or a free camera (eye and light required) with the
 * scene's field of view.  GLINT_EINVAL naming the problem. */
int render_camera_view(const scene *sc, const render_camera *c, scene_view *out,
                       glint_err *err);

/* "x,y,z": three finite numbers, each within 1e6 (0, or GLINT_EINVAL). */
int render_parse_vec3(const char *text, double v[3]);

#endif
