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
 * fit's extrapolation, anisotropy).  So is how anisotropic the material is
 * (out->anisotropy: its change when the pairs turn about the normal).  Above
 * GLTF_ANISO_NOTE a material uniform over the surface is also fitted with
 * KHR_materials_anisotropy (out->aniso, gltf_aniso.c), which the .glb
 * carries with the mesh's TANGENT when it is the closer; MaterialX and USD
 * keep the isotropic fit, and the note says which file holds what.
 *
 * pbr materials.  A material of pbr, pbr_env or pbr_detail (its base) is
 * physically based already: its parameters are also mapped directly onto
 * glTF with KHR_materials_ior, KHR_materials_specular and
 * KHR_materials_clearcoat (gltf_direct.c: roughness sqrt(alpha), a
 * dielectric's ior and ks, a conductor's ks F0, the sharper of two lobes as
 * the coat), the KHR model evaluated as gltf_khr.c states it.  The mapping
 * and the fit are both measured over the fit's pairs with the
 * height-correlated Smith G (pbr's own, and what glTF viewers render;
 * gltf_direct.c says why), and the closer is written: out->exact, the two
 * errors and a note of what the mapping clamps or leaves out are reported
 * with the file (its extras, extensionsUsed declaring each extension).
 *
 * Textures.  A material that varies over the surface (material_spatial) is
 * also fitted per texel of a res x res grid over its texture coordinates
 * (gltf_bake_material): the average's fit first, then each texel's from
 * the best of it and a coarse grid, with the material evaluated at the
 * texel's centre over the directions painted in and around the texel (at
 * least GLTF_BAKE_MIN_PAIRS, at most GLTF_BAKE_PAIRS), pulled towards the
 * average where those directions cannot tell metallic from roughness
 * (GLTF_BAKE_PULL; gltf_bake.c says why and how much).  The .glb
 * then holds baseColorTexture (8-bit PNG, sRGB-encoded as glTF requires)
 * and metallicRoughnessTexture (8-bit PNG, linear: G roughness, B
 * metallic, R 1), with the factors 1 and TEXCOORD_0 the mesh's uv (glTF's
 * v is 1 - glint's: texture row 0, the image's top, is glint's v = 1).
 * Each texel's relative RMS is reported (median and max).  Without the
 * mesh's texture coordinates, or with res 0, the average alone is written
 * and the extras say why.  Cost (measured, BENCHMARKS.md, a maps material
 * of 5 products on two cores other jobs shared): 0.6 to 1 ms per texel,
 * 0.65 to 1.15 s for the default 32 x 32, 2.7 s for 64 x 64, 9.3 s for
 * 128 x 128; the rows run on par.h's pool (no faster than one thread while
 * the machine was loaded; the result does not depend on the threads).
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

/* The KHR material extensions a material uses (gltf_khr.c gives their
 * model).  Each is written to the file, and evaluated, only when its flag
 * is set; a zeroed struct is the core model alone. */
typedef struct gltf_khr {
    int ior_used;              /* KHR_materials_ior */
    double ior;                /* >= 1 (the core model's: 1.5) */
    int specular_used;         /* KHR_materials_specular */
    double specular;           /* specularFactor, [0, 1] */
    double specular_color[3];  /* specularColorFactor, >= 0 (may exceed 1) */
    int clearcoat_used;        /* KHR_materials_clearcoat */
    double clearcoat;          /* clearcoatFactor, [0, 1] */
    double clearcoat_roughness; /* clearcoatRoughnessFactor, [0, 1]: alpha = its square */
} gltf_khr;

#define GLTF_NOTE_MAX 400

/* An anisotropic material's fit with KHR_materials_anisotropy (gltf_aniso.c,
 * the .glb only): the core model with the extension's lobe (gltf_aniso_brdf).
 * The tangent is glint's (vec3.h's v3_frame: t = normalize(Z x n), +X at
 * the poles), written as the mesh's TANGENT (w 1: bitangent n x t). */
typedef struct gltf_aniso {
    int used;          /* the .glb carries it: closer than the isotropic fit */
    double strength;   /* anisotropyStrength, [0, 1]: alpha along the direction is
                          mix(roughness^2, 1, strength^2) */
    double rotation;   /* anisotropyRotation, radians in [0, pi): the direction, from
                          the tangent towards the bitangent */
    double base[3], metallic, roughness; /* the core parameters fitted with it */
    double rel_rms;    /* of f cos over the fit's pairs, relative to the material's */
} gltf_aniso;

enum { GLTF_SMITH_SEPARABLE = 0, GLTF_SMITH_CORRELATED = 1 };

typedef struct gltf_pbr {
    double base[3];      /* baseColorFactor, linear, [0, 1] */
    double metallic;     /* [0, 1] */
    double roughness;    /* [0, 1]: alpha = roughness^2 */
    double rel_rms;      /* of f cos over the pairs, relative to the material's: the
                            error of what is written (the fit's or the mapping's) */
    int pairs;           /* direction pairs with the light and the eye above the surface */
    int spatial;         /* the material varies over the surface: its average was fitted */
    gltf_khr khr;        /* the extensions used (zero: none) */
    int exact;           /* 1: a pbr material's own parameters, mapped (gltf_direct.c);
                            0: the least-squares fit of the core model */
    double rel_rms_exact;  /* the mapping's relative RMS over the same pairs (NaN: the
                              material is not a pbr one: no mapping) */
    double rel_rms_fitted; /* the fit's */
    int smith;             /* the form of Smith's G the three errors were measured with:
                              GLTF_SMITH_SEPARABLE (the fit's own, gltf_brdf) or, for a pbr
                              material, GLTF_SMITH_CORRELATED (gltf_direct.c says why) */
    double anisotropy;     /* how much the material turns with the surface: the relative
                              RMS change of its f cos over the fit's pairs when both
                              directions turn GLTF_ANISO_TURN about the normal (0: it is
                              isotropic); the glTF material is isotropic */
    gltf_aniso aniso;      /* with anisotropy above GLTF_ANISO_NOTE (a uniform material
                              that is no pbr one): the .glb's anisotropic fit */
    char note[GLTF_NOTE_MAX]; /* what the mapping clamps or leaves out, and what the files
                                 do with an anisotropic material ("" when nothing) */
} gltf_pbr;

/* The turn (radians: 75 degrees, which no symmetry of a lobe undoes), and the
 * change above which the note says the glTF material is isotropic. */
#define GLTF_ANISO_TURN 1.3089969389957472
#define GLTF_ANISO_NOTE 0.02

/* f of the glTF model at unit n, wi (L), wo (V) (OUT: rgb, no cosine; 0
 * below either horizon): the core model above, or with p's extensions the
 * KHR model (gltf_khr_brdf). */
void gltf_brdf(const gltf_pbr *p, const double n[3], const double wi[3], const double wo[3],
               double rgb[3]);

/* The KHR model (gltf_khr.c's header states it) with p's extensions: the
 * core model's dielectric-metal mix in its layered form (fresnel_mix,
 * conductor_fresnel), KHR_materials_ior's and KHR_materials_specular's
 * dielectric Fresnel, KHR_materials_clearcoat's coat.  OUT: rgb as
 * gltf_brdf. */
void gltf_khr_brdf(const gltf_pbr *p, const double n[3], const double wi[3], const double wo[3],
                   double rgb[3]);

/* The same with Smith's G in the form asked: GLTF_SMITH_SEPARABLE
 * (Appendix B's text, gltf_brdf's) or GLTF_SMITH_CORRELATED (the
 * height-correlated form Khronos's glTF-Sample-Viewer and three.js
 * implement, and pbr's model uses). */
void gltf_khr_brdf_smith(const gltf_pbr *p, int smith, const double n[3], const double wi[3],
                         const double wo[3], double rgb[3]);

/* f of an anisotropic fit (OUT: rgb as gltf_brdf): the core model in its
 * layered form (gltf_khr.c) with KHR_materials_anisotropy's lobe: along the
 * direction T (the tangent of v3_frame(n) turned by a->rotation) alpha_t =
 * mix(alpha, 1, strength^2), across it alpha_b = alpha = roughness^2, the
 * anisotropic GGX D and the height-correlated V the extension states (V
 * clamped to [0, 1]). */
void gltf_aniso_brdf(const gltf_aniso *a, const double n[3], const double wi[3],
                     const double wo[3], double rgb[3]);

/* Does p use an extension? */
int gltf_khr_any(const gltf_pbr *p);

/* The names of the extensions the .glb of p uses, in order (OUT: up to
 * GLTF_KHR_MAX pointers to static strings: ior, specular, clearcoat, and
 * anisotropy for p->aniso.used); returns how many. */
#define GLTF_KHR_MAX 4
int gltf_khr_names(const gltf_pbr *p, const char *names[GLTF_KHR_MAX]);

/* Fit m at the painted directions: every (n / GLTF_FIT_MAX_SAMPLES)-th
 * sample of s (the material's own frame at each: n, wi, wo of the
 * sample), or, with s NULL, the GLTF_FIT_PAIRS pairs over the hemisphere
 * (OUT: *out).  A pbr material (pbr, pbr_env; pbr_detail's base) is also
 * mapped parameter by parameter onto the KHR model (gltf_direct.c) and
 * measured over the same pairs: the mapping is kept (out->exact 1) unless
 * its relative RMS is above the fit's; both figures are in *out. */
#define GLTF_FIT_MAX_SAMPLES 4096
int gltf_fit_material(const material *m, const samples *s, gltf_pbr *out, glint_err *err);

/* The same for any reflectance given as radiance per unit light, f cos
 * (OUT: rad): what the tests fit analytic truths with. */
typedef void (*gltf_fn)(const void *ctx, const double n[3], const double wi[3],
                        const double wo[3], double rad[3]);
int gltf_fit(gltf_fn fn, const void *ctx, const samples *s, gltf_pbr *out, glint_err *err);

/* Fit the anisotropic model to fn at the pairs of gltf_fit (OUT: out->aniso;
 * used 1 when its relative RMS is below out->rel_rms, the isotropic fit's):
 * a grid over rotation, strength and roughness at the isotropic metallic on
 * a quarter of the pairs, then a finer one around its best, with metallic,
 * on all of them, then each in turn with halving steps; the base colour
 * exact for each (least squares in the layered form, linear in it). */
int gltf_fit_aniso(gltf_fn fn, const void *ctx, const samples *s, gltf_pbr *out,
                   glint_err *err);

/* The fit alone, as gltf_export_scene makes it: m fitted at the samples of
 * the views flagged in `use` (NULL: all) of scene sc (OUT: *out).  What
 * the MaterialX and USD exports carry (mtlx.h, usda.h). */
int gltf_fit_scene(const material *m, const scene *sc, const unsigned char *use, gltf_pbr *out,
                   glint_err *err);

/* ---- textures ---------------------------------------------------------------------------- */

#define GLTF_BAKE_RES_DEFAULT 32  /* texels per side */
#define GLTF_BAKE_RES_MAX 256
#define GLTF_BAKE_PAIRS 256       /* direction pairs per texel, at most */
#define GLTF_BAKE_MIN_PAIRS 48    /* the painted neighbourhood grows until it has them */
#define GLTF_BAKE_R_LEVELS 200    /* roughnesses tabulated: (j + 1) / 200 */
#define GLTF_BAKE_PULL 1e-3       /* towards the average, in squared relative error */

/* Per-texel parameters, in the image's layout: texel t = row * res + col,
 * row 0 the top (glTF v = (row + 0.5) / res, glint v = 1 - that), u =
 * (col + 0.5) / res.  Owns its arrays (gltf_bake_free, which accepts a
 * zeroed struct). */
typedef struct gltf_bake {
    int res;
    float *base;                 /* 3 per texel, linear, [0, 1] */
    float *metallic, *roughness; /* 1 per texel, [0, 1]; alpha = roughness^2 */
    float *rel_rms;              /* 1 per texel: of f cos over the pairs */
    double rel_rms_median, rel_rms_max;
    int pairs;                   /* direction pairs per texel, at most */
    int far_texels;              /* fitted over all the painted directions: none near */
    long nonfinite;              /* values of the material taken as 0 (not finite) */
    double seconds;              /* the whole bake, wall clock */
} gltf_bake;

/* Fit m per texel of a res x res grid (1..GLTF_BAKE_RES_MAX) at
 * GLTF_BAKE_PAIRS of s's samples (NULL: of the hemisphere's pairs), each
 * search started from avg (gltf_fit_material's result) and a coarse grid.
 * Parallel over rows (par.h).  OUT: *out. */
int gltf_bake_material(const material *m, const samples *s, const gltf_pbr *avg, int res,
                       gltf_bake *out, glint_err *err);
void gltf_bake_free(gltf_bake *b);

/* The two textures as PNG bytes (OUT: malloc'ed, caller frees): base
 * colour sRGB-encoded, metallic-roughness linear (G roughness, B metallic,
 * R 1). */
int gltf_bake_png(const gltf_bake *b, void **base_png, size_t *base_len, void **mr_png,
                  size_t *mr_len, glint_err *err);

/* ---- the file --------------------------------------------------------------------------- */

/* A binary glTF 2.0 file: the mesh (positions, normals, texture
 * coordinates, indices) with the material p, or with bake's textures when
 * bake is not NULL (the factors then 1; the mesh must have uv),
 * `extras_json` (a JSON object's text, or NULL) as the material's extras.
 * OUT: *glb (free()), *len. */
int gltf_write_glb(const mesh *msh, const gltf_pbr *p, const gltf_bake *bake, const char *name,
                   const char *extras_json, void **glb, size_t *len, glint_err *err);

/* What an export did beyond the average's fit. */
typedef struct gltf_export_info {
    int baked;                   /* textures written */
    int res, pairs;              /* of the textures */
    double rel_rms_median, rel_rms_max, seconds;
    char note[160];              /* why not baked ("" when baked or not spatial) */
} gltf_export_info;

/* The fit and the textures of an export, without the file: m fitted at
 * the samples of the views flagged in `use` (NULL: all) of scene sc (OUT:
 * *out) and, when it varies over the surface and sc's mesh has texture
 * coordinates, baked at bake_res x bake_res texels (bake_res 0: the
 * average only) into *bake (gltf_bake_free; info->baked says whether, and
 * info->note why not).  What the .glb, and the USDZ package (usdz.h),
 * carry. */
int gltf_bake_scene(const material *m, const scene *sc, const unsigned char *use, int bake_res,
                    gltf_pbr *out, gltf_bake *bake, gltf_export_info *info, glint_err *err);

/* The two textures of a package (the USDZ and MaterialX ones), as PNG
 * bytes (gltf_bake_png), NULL where not baked. */
typedef struct gltf_pngs {
    void *base, *mr;
    size_t base_len, mr_len;
} gltf_pngs;

/* gltf_bake_scene, then, where it baked (info->baked), the textures as PNG
 * (OUT: *out, *png: gltf_pngs_free, also after a failure; *info). */
int gltf_bake_scene_png(const material *m, const scene *sc, const unsigned char *use,
                        int bake_res, gltf_pbr *out, gltf_pngs *png, gltf_export_info *info,
                        glint_err *err);
void gltf_pngs_free(gltf_pngs *png);

/* The whole export: the material fitted at the samples of the views
 * flagged in `use` (NULL: all) of scene sc, and baked at bake_res x
 * bake_res texels when it varies over the surface (bake_res 0: the average
 * only; else 1..GLTF_BAKE_RES_MAX), written with sc's mesh (OUT: *glb,
 * *len, *out, *info; info may be NULL). */
int gltf_export_scene(const material *m, const scene *sc, const unsigned char *use,
                      int bake_res, void **glb, size_t *len, gltf_pbr *out,
                      gltf_export_info *info, glint_err *err);

#endif
