/* mtlx.h: a glint material as a MaterialX document (.mtlx): one
 * standard_surface shader (Autodesk Standard Surface, MaterialX's
 * libraries/bxdf/standard_surface.mtlx) and the surfacematerial that uses
 * it, which Houdini, Maya, 3ds Max, Substance and MaterialX's own viewer
 * read.
 *
 * What it carries: gltf.h's metallic-roughness fit (the same numbers the
 * .glb holds), mapped input by input:
 *   base 1, base_color = baseColor (linear), metalness = metallic,
 *   specular 1, specular_color (1, 1, 1), specular_roughness = roughness
 *   (both models square it into the GGX alpha), specular_IOR 1.5 (the
 *   glTF model's dielectric f0 = 0.04 = ((1.5 - 1) / (1.5 + 1))^2).
 * The average over the surface only: a material that varies over it is
 * written as its average's fit (the .glb bakes textures; this file names
 * none), and the document says so.  The error figure it states (fit_rel_rms)
 * is the glTF model's against the material on the painted views; Standard
 * Surface's own layering (its diffuse under a dielectric coat, its metal
 * Fresnel) differs from glTF's Appendix B by a few percent at grazing
 * angles, which that figure does not count.
 *
 * Values are written with six significant digits; node names are
 * `name` cut to [A-Za-z0-9_] (a leading letter added).  Thread-safety: none
 * needed (no state). */
#ifndef GLINT_MTLX_H
#define GLINT_MTLX_H

#include "err.h"
#include "gltf.h"

#define MTLX_IOR 1.5 /* glTF 2.0's dielectric: f0 0.04 */

/* The document for p (OUT: *text, NUL-terminated, malloc'ed: the caller
 * frees).  `name` names the nodes (NULL: "glint"); `note` (may be NULL) is
 * one more line of the leading comment (what was fitted to what).
 * GLINT_EINVAL for a p with a value outside [0, 1] or not finite,
 * GLINT_ENOMEM. */
int mtlx_write(const gltf_pbr *p, const char *name, const char *note, char **text,
               glint_err *err);

#endif
