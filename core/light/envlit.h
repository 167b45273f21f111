/* envlit.h: radiance under an environment's lights, with shadows: at the
 * vertices of a mesh (what previews interpolate, seed 004 section 4.2,
 * equation 22) and at the pixels of a G-buffer (the reference, and what
 * truths are painted with).
 *
 * Conventions.  With lights k of direction d_k and power P_k (env.h:
 * radiance x solid angle, RGB), the radiance leaving x towards wo is
 *
 *     B(x, wo) = scale x sum_k V_k(x) P_k R(n, d_k, wo)
 *
 * where R is radiance per unit light, f(d_k, wo) max(0, n.d_k)
 * (material_eval(); for an analytic BRDF brdf_eval() x n.d_k, see
 * brdf_envlit), and V_k(x) is 1 when the light is seen from x (vis.h;
 * taken as 1 everywhere when shadows are off or the mesh is convex).
 *
 * At vertices, wo points from the vertex to the eye.  Where a vertex faces
 * away from the eye (n.wo < ENVLIT_GRAZE), wo is bent towards the
 * surface until n.wo = ENVLIT_GRAZE, so that triangles along a silhouette,
 * whose pixels face the eye, do not interpolate towards black; pixels are
 * shaded with their own wo, unbent.
 *
 * Thread-safety: the functions share nothing; envlit_vertices runs on
 * `nthreads` threads (<= 0: the machine's cores). */
#ifndef GLINT_ENVLIT_H
#define GLINT_ENVLIT_H

#include <stdint.h>

#include "cancel.h"
#include "env.h"
#include "err.h"
#include "gbuf.h"
#include "img.h"
#include "mesh.h"

#define ENVLIT_GRAZE 0.02
/* Vertices are shaded only for triangles that may face the eye: those with
 * a vertex whose normal turns away from the eye by less than
 * asin(ENVLIT_CULL) past the horizon (n.wo > -ENVLIT_CULL); others get 0. */
#define ENVLIT_CULL 0.2
/* Dihedral tolerance (radians) for calling a mesh convex (vis_mesh_convex). */
#define ENVLIT_CONVEX_TOL 1e-6

/* Radiance per unit light R(uv, n, wi, wo) at the surface point with
 * texture coordinates uv (NULL where the surface has none) (OUT: rgb). */
typedef void (*envlit_fn)(const void *ctx, const double uv[2], const double n[3],
                          const double wi[3], const double wo[3], double rgb[3]);

/* envlit_fn adapters live with what they shade: brdf_envlit (brdf.h),
 * merl_envlit (merl.h), material_envlit and material_envlit_preview
 * (material.h). */

/* The whole sum at one point (OUT: acc): over the lights k above n's
 * horizon (n . dir_k > 0) and visible (bits NULL, or bit k set in vis.h's
 * packing), power_k times R(uv, n, dir_k, wo), as envlit_gbuf sums an
 * envlit_fn.  For a shader that computes it in one pass faster than a call
 * a light (brdf_envlit_sum, brdf.h). */
typedef void (*envlit_sum_fn)(const void *ctx, const env_lights *l, const uint64_t *bits,
                              const double uv[2], const double n[3], const double wo[3],
                              double acc[3]);

/* Visibility of every light from every vertex of a mesh. */
typedef struct envlit_vis {
    int nverts, k, words;
    uint64_t *bits;      /* nverts x VIS_WORDS(k), vis.h's packing; NULL: all seen */
    int convex;          /* shadows were asked for, the mesh is convex: none cast */
    long rays;           /* shadow rays cast */
    double seconds;      /* wall time of the casting */
} envlit_vis;

/* Cast the shadow rays of every vertex (shadows = 0, or a convex mesh:
 * no rays, bits NULL).  OUT: *out (envlit_vis_free).  cancel: as below. */
int envlit_vis_vertices(const mesh *m, const env_lights *l, int shadows, envlit_vis *out,
                        const glint_cancel *cancel, glint_err *err);
void envlit_vis_free(envlit_vis *v);

/* B at every vertex for the eye (OUT: rgb, 3 floats per vertex).  vis
 * must come from the same mesh and lights.  cancel (may be NULL) is asked
 * about every GLINT_CANCEL_WORK light evaluations (cancel.h):
 * GLINT_ECANCELLED once it says to stop. */
int envlit_vertices(const mesh *m, const env_lights *l, const envlit_vis *vis, envlit_fn fn,
                    const void *ctx, const double eye[3], double scale, int nthreads,
                    float *rgb, const glint_cancel *cancel, glint_err *err);

/* B at every covered pixel of a G-buffer of mesh m, shadow rays cast per
 * pixel when `shadows` is set (and the mesh is not convex); 0 elsewhere.
 * The pixels are shaded in blocks on par.h's pool (each pixel's value is
 * the same whichever thread shades it): fn is called from several threads
 * at once, as envlit_vertices calls it.
 * OUT: *out (RGB, allocated here; freed when cancelled, as on any error).
 * cancel: as envlit_vertices'. */
int envlit_gbuf(const gbuf *g, const mesh *m, const env_lights *l, int shadows, envlit_fn fn,
                const void *ctx, double scale, img *out, const glint_cancel *cancel,
                glint_err *err);
/* The same with each pixel's sum taken by sum (ctx is its) instead. */
int envlit_gbuf_summed(const gbuf *g, const mesh *m, const env_lights *l, int shadows,
                       envlit_sum_fn sum, const void *ctx, double scale, img *out,
                       const glint_cancel *cancel, glint_err *err);

/* Fill the pixels of `out` where mask is 0 (all when mask is NULL) with
 * the map's radiance along the camera ray of view v (scene.h's pixel
 * centres), rotated by psi and scaled by intensity. */
struct scene_view;
void envlit_background(const env_map *map, double psi, double intensity,
                       const struct scene_view *v, const uint8_t *mask, img *out);

#endif
