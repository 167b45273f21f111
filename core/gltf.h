/* gltf.h: a glint material as glTF 2.0's metallic-roughness material, on
 * the scene's mesh, in a binary glTF file (.glb) that Blender, three.js and
 * every glTF viewer read.
 *
 * The model (glTF 2.0 specification, Appendix B, "BRDF implementation"):
 *   c_diff = (1 - metallic) baseColor,  f0 = 0.04 (1 - metallic) + metallic baseColor,
 *   F = f0 + (1 - f0) (1 - |V.H|)^5,  alpha = roughness^2,
 *   D = alpha^2 / (pi ((N.H)^2 (alpha^2 - 1) + 1)^2),
 *   G = G1(N.L) G1(N.V),  G1(x) = 2x / (x + sqrt(alpha^2 + (1 - alpha^2) x^2)),
 *   f = (1 - F) c_diff / pi + F D G / (4 |N.L| |N.V|).
 * The roughness convention is the specification's: alpha = roughness^2
 * (glint's ct truths take alpha itself: ct:rough=a is roughness sqrt(a)).
 *
 * The fit: least squares of the radiance f cos(theta_i) against the
 * material's (its value per unit light) over the painted directions (the
 * samples of the views the material was fitted to: where the painting
 * says something; elsewhere a fit only extrapolates), or over
 * GLTF_FIT_PAIRS direction pairs spread over the hemispheres.  For fixed metallic and roughness each channel's f cos is a
 * quadratic in its base colour, so the squared error is a quartic
 * minimized exactly on [0, 1]; metallic and roughness are searched on a
 * grid and refined.  The relative RMS of the best fit is reported: what the
 * material loses in the glTF model (a painted highlight no GGX lobe has, a
 * fit's extrapolation, anisotropy).  A material that varies over the
 * surface is fitted at its average (no textures are baked).
 * Thread-safety: reads the material only. */
#ifndef GLINT_GLTF_H
#define GLINT_GLTF_H

#include <stddef.h>

#include "err.h"
#include "material.h"
#include "mesh.h"
#include "samples.h"
#include "scene.h"

#define GLTF_FIT_LIGHTS 24
#define GLTF_FIT_VIEWS 96
#define GLTF_FIT_PAIRS (GLTF_FIT_LIGHTS * GLTF_FIT_VIEWS)

typedef struct gltf_pbr {
    double base[3];      /* baseColorFactor, linear, [0, 1] */
    double metallic;     /* [0, 1] */
    double roughness;    /* [0, 1]: alpha = roughness^2 */
    double rel_rms;      /* of f cos over the fit's pairs, relative to the material's */
    int pairs;           /* direction pairs with the light and the eye above the surface */
    int spatial;         /* the material varies over the surface: its average was fitted */
} gltf_pbr;

/* f of the glTF model at unit n, wi (L), wo (V) (OUT: rgb, no cosine; 0
 * below either horizon). */
void gltf_brdf(const gltf_pbr *p, const double n[3], const double wi[3], const double wo[3],
               double rgb[3]);

/* Fit m at the painted directions: every (n / GLTF_FIT_MAX_SAMPLES)-th
 * sample of s (the material's own frame at each: n, wi, wo of the
 * sample), or, with s NULL, the GLTF_FIT_PAIRS pairs over the hemisphere
 * (OUT: *out). */
#define GLTF_FIT_MAX_SAMPLES 4096
int gltf_fit_material(const material *m, const samples *s, gltf_pbr *out, glint_err *err);

/* The same for any reflectance given as radiance per unit light, f cos
 * (OUT: rad): what the tests fit analytic truths with. */
typedef void (*gltf_fn)(const void *ctx, const double n[3], const double wi[3],
                        const double wo[3], double rad[3]);
int gltf_fit(gltf_fn fn, const void *ctx, const samples *s, gltf_pbr *out, glint_err *err);

/* A binary glTF 2.0 file: the mesh (positions, normals, texture
 * coordinates, indices) with the material p, `extras_json` (a JSON object's
 * text, or NULL) as the material's extras.  OUT: *glb (free()), *len. */
int gltf_write_glb(const mesh *msh, const gltf_pbr *p, const char *name,
                   const char *extras_json, void **glb, size_t *len, glint_err *err);

/* The whole export: the material fitted at the samples of the views
 * flagged in `use` (NULL: all) of scene sc, written with sc's mesh (OUT:
 * *glb, *len, *out). */
int gltf_export_scene(const material *m, const scene *sc, const unsigned char *use, void **glb,
                      size_t *len, gltf_pbr *out, glint_err *err);

#endif
