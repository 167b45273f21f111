/* mtlx.h: a glint material as a MaterialX document (.mtlx): one
 * standard_surface shader (Autodesk Standard Surface, MaterialX's
 * libraries/bxdf/standard_surface.mtlx) and the surfacematerial that uses
 * it, which Houdini, Maya, 3ds Max, Substance and MaterialX's own viewer
 * read.
 *
 * What it carries: the metallic-roughness material gltf.h makes (the same
 * numbers the .glb holds: the fit, or a pbr material's own parameters with
 * the KHR extensions), mapped input by input:
 *   base 1, base_color = baseColor (linear), metalness = metallic,
 *   specular_roughness = roughness (both models square it into the GGX
 *   alpha);
 *   the dielectric's reflectance: KHR's f0_c = min(F0(ior)
 *   specularColor_c, 1) (F0(ior) = ((ior - 1) / (ior + 1))^2; ior 1.5 and
 *   specularColor 1 without the extensions: f0 0.04) becomes specular_IOR
 *   with F0 the largest channel's f0 (at most MTLX_F0_MAX) and
 *   specular_color f0_c / that, specular = specularFactor (1 without
 *   KHR_materials_specular; 0 where every f0 is 0).  Exact at normal
 *   incidence; Standard Surface's specular_color tints the grazing
 *   reflectance too, where KHR's is specularFactor in every channel;
 *   KHR_materials_clearcoat: coat = clearcoatFactor, coat_roughness =
 *   clearcoatRoughnessFactor, coat_IOR 1.5 (KHR's coat).
 * A material that varies over the surface: mtlx_write writes its
 * average's fit and says so; mtlx_write_textured reads base_color,
 * metalness and specular_roughness from the .glb's baked textures (a
 * nodegraph of image nodes: the base colour sRGB-encoded, colorspace
 * srgb_texture; the metallic-roughness image raw, its G the roughness and
 * its B the metalness through extract nodes; clamped at the edges) over
 * the mesh's texture coordinates, whose (0, 0) is the image's lower-left
 * corner in MaterialX as in glint; specular_IOR 1.5 there (the bake fits
 * glTF's core model).  mtlx_export_scene packs that document with its
 * textures as a zip (zip.h): glint.mtlx first, then the two PNG images.
 * The error figure it states (fit_rel_rms) is the glTF model's against the material on the painted views; Standard
 * Surface's own layering (its diffuse under a dielectric coat, its metal
 * Fresnel) differs from glTF's Appendix B by a few percent at grazing
 * angles, which that figure does not count.
 *
 * Values are written with six significant digits; node names are
 * `name` cut to [A-Za-z0-9_] (a leading letter added).  Thread-safety: none
 * needed (no state). */
#ifndef GLINT_MTLX_H
#define GLINT_MTLX_H

#include <stddef.h>

#include "err.h"
#include "gltf.h"
#include "material.h"
#include "scene.h"

#define MTLX_IOR 1.5 /* glTF 2.0's dielectric: f0 0.04 */
#define MTLX_F0_MAX 0.9 /* specular_IOR 37.97 at most: a reflectance of 1 has no ior */

/* The document for p (OUT: *text, NUL-terminated, malloc'ed: the caller
 * frees).  `name` names the nodes (NULL: "glint"); `note` (may be NULL) is
 * one more line of the leading comment (what was fitted to what).
 * GLINT_EINVAL for a p with a value outside [0, 1] or not finite (an ior
 * below 1, a negative specular colour), GLINT_ENOMEM. */
int mtlx_write(const gltf_pbr *p, const char *name, const char *note, char **text,
               glint_err *err);

/* The baked textures' paths, relative to the document (printable ASCII,
 * none of < > & " ' \, no ".."). */
typedef struct mtlx_textures {
    const char *base_color, *metallic_roughness;
} mtlx_textures;

/* mtlx_write with tex's textures read by the shader (tex NULL: none, as
 * mtlx_write).  GLINT_EINVAL also for a path the document cannot name. */
int mtlx_write_textured(const gltf_pbr *p, const char *name, const char *note,
                        const mtlx_textures *tex, char **text, glint_err *err);

/* A material as a MaterialX package (mtlx_export.c): a zip of glint.mtlx
 * and, where the material varies over the surface, the .glb's baked
 * textures (textures/base_color.png, textures/metallic_roughness.png,
 * bake_res x bake_res: gltf_bake_scene) that it reads; else the document
 * alone, with the average.  The views flagged in `use` (NULL: all) of sc
 * are the painted directions the fit and the bake are measured at.  OUT:
 * *out, *len, *p (the fit), *info (may be NULL: what the bake did).
 * `name` and `note` as mtlx_write's. */
int mtlx_export_scene(const material *m, const scene *sc, const unsigned char *use,
                      int bake_res, const char *name, const char *note, void **out,
                      size_t *len, gltf_pbr *p, gltf_export_info *info, glint_err *err);

#endif
