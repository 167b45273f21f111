/* usdz.h: a USDZ package: several files (a USD layer first, then the
 * textures it names by relative paths) as one download.
 *
 * The format (OpenUSD's "Usdz File Format Specification"): a zip archive
 * whose files are stored, not compressed nor encrypted, each file's data
 * starting at a multiple of 64 bytes from the start of the archive, the
 * first file a USD layer (.usda or .usdc); paths relative, in the
 * archive's own namespace.  zip.h writes exactly that.
 *
 * Thread-safety: no state. */
#ifndef GLINT_USDZ_H
#define GLINT_USDZ_H

#include <stddef.h>

#include "err.h"
#include "gltf.h"
#include "material.h"
#include "scene.h"
#include "zip.h"

/* The package of files[0..n-1] (files[0] a .usda or .usdc layer).  OUT:
 * *out (malloc'ed: the caller frees), *len.  GLINT_EINVAL for a first
 * file that is no USD layer; otherwise zip_pack's errors. */
int usdz_pack(const zip_entry *files, int n, void **out, size_t *len, glint_err *err);

/* A material as a USDZ package (usdz_export.c): glint.usda (usda.h: the
 * scene's mesh bound to a UsdPreviewSurface) and, where the material
 * varies over the surface, the .glb's baked textures
 * (textures/base_color.png, textures/metallic_roughness.png, bake_res x
 * bake_res: gltf_bake_scene) connected in it; else the layer alone, with
 * the average.  The views flagged in `use` (NULL: all) of sc are the
 * painted directions the fit and the bake are measured at.  OUT: *out,
 * *len, *p (the fit), *info (may be NULL: what the bake did).  `note` is
 * one more line of the layer's doc (may be NULL). */
int usdz_export_scene(const material *m, const scene *sc, const unsigned char *use,
                      int bake_res, const char *note, void **out, size_t *len, gltf_pbr *p,
                      gltf_export_info *info, glint_err *err);

#endif
