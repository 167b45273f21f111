/* usda.h: a glint material as a text USD layer (.usda): a Material prim
 * whose surface is a UsdPreviewSurface shader (OpenUSD's
 * pxr/usdImaging/plugin/usdShaders/shaders/shaderDefs.usda; read by
 * Omniverse, Houdini Solaris, Blender 4+, usdview, Apple's Quick Look),
 * and, when a mesh is given, the scene's mesh as a UsdGeomMesh bound to it.
 *
 * What it carries: the metallic-roughness material gltf.h makes (the
 * .glb's numbers: the fit, or a pbr material's own parameters with the
 * KHR extensions):
 *   diffuseColor = baseColor (linear; "interpreted as albedo" there),
 *   metallic, roughness (squared into the GGX alpha, as glTF does);
 *   without KHR_materials_specular the metallic workflow
 *   (useSpecularWorkflow 0) with ior = KHR_materials_ior's (1.5 without
 *   it: the dielectric F0 ((1 - ior) / (1 + ior))^2 = 0.04, glTF's);
 *   with it the specular workflow (useSpecularWorkflow 1; a pbr dielectric
 *   maps there, metallic 0) with specularColor = KHR's dielectric f0_c =
 *   min(F0(ior) specularColor_c, 1) specularFactor ("the color at 0
 *   incidence"; its edge is white where KHR's is specularFactor);
 *   KHR_materials_clearcoat: clearcoat = clearcoatFactor,
 *   clearcoatRoughness = clearcoatRoughnessFactor (both white coats of
 *   ior 1.5).
 * Without textures, the average over the surface only, and the layer's
 * doc string says so, with fit_rel_rms: the relative RMS error of the glTF
 * model's fit against the material on the painted views.  With textures
 * (usda_textures: what a USDZ package holds beside the layer, usdz.h) the
 * baked base colour and metallic-roughness of the .glb: UsdUVTexture
 * shaders (sourceColorSpace sRGB and raw; wrap clamp) read at the mesh's
 * primvars:st by a UsdPrimvarReader_float2, connected to diffuseColor,
 * metallic (the texture's B) and roughness (its G), in the metallic
 * workflow with ior 1.5 (the bake fits glTF's core model: the KHR
 * extensions of the average are left out, and the doc says so).  The
 * images' first row is st's t = 1, as USD reads an image (and glTF,
 * whose v is 1 - t).
 *
 * The layer: upAxis "Z" (glint's world up), metersPerUnit 1, defaultPrim
 * "glint" (an Xform) holding Mesh "mesh" (points, normals and primvars:st
 * per vertex, faceVertexCounts all 3, faceVertexIndices, subdivisionScheme
 * "none", orientation rightHanded: the mesh's counter-clockwise triangles;
 * st = glint's uv, origin at the bottom left as in USD) and Material
 * "material" with Shader "surface".  Numbers with 7 significant digits.
 * Thread-safety: none needed (no state). */
#ifndef GLINT_USDA_H
#define GLINT_USDA_H

#include "err.h"
#include "gltf.h"
#include "mesh.h"

#define USDA_IOR 1.5

/* The layer for p, with msh (NULL: the material alone) (OUT: *text,
 * NUL-terminated, malloc'ed: the caller frees; *len its length).  `note`
 * (may be NULL) is one more line of the layer's doc.  GLINT_EINVAL for a
 * p with a value outside [0, 1] or not finite or a mesh without
 * positions, normals or triangles, GLINT_ENOMEM. */
int usda_write(const gltf_pbr *p, const mesh *msh, const char *note, char **text, size_t *len,
               glint_err *err);

/* Asset paths of the baked textures, relative to the layer (inside a
 * package): base colour (sRGB) and metallic-roughness (G roughness, B
 * metallic, linear). */
typedef struct usda_textures {
    const char *base_color, *metallic_roughness;
} usda_textures;

/* usda_write with the textures tex (NULL: none) connected; they need msh
 * with texture coordinates (GLINT_EINVAL otherwise). */
int usda_write_textured(const gltf_pbr *p, const mesh *msh, const usda_textures *tex,
                        const char *note, char **text, size_t *len, glint_err *err);

#endif
