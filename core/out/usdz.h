/* usdz.h: a USDZ package: several files (a USD layer first, then the
 * textures it names by relative paths) as one download.
 *
 * The format (OpenUSD's "Usdz File Format Specification"): a zip archive
 * whose files are stored, not compressed nor encrypted, each file's data
 * starting at a multiple of 64 bytes from the start of the archive (the
 * local headers' extra field pads to it), the first file a USD layer
 * (.usda or .usdc); paths relative, in the archive's own namespace.  The
 * writer makes exactly that: local file headers, the data, the central
 * directory and its end record (no ZIP64: at most 65,535 files and 4 GiB,
 * refused beyond), CRC-32 by libdeflate, times set to 1980-01-01 so that
 * a package is a function of its files.
 *
 * Thread-safety: no state. */
#ifndef GLINT_USDZ_H
#define GLINT_USDZ_H

#include <stddef.h>

#include "err.h"
#include "gltf.h"
#include "material.h"
#include "scene.h"

#define USDZ_ALIGN 64
#define USDZ_MAX_FILES 64

typedef struct usdz_file {
    const char *path;   /* relative, '/'-separated, no "..", at most 255 bytes */
    const void *data;
    size_t len;
} usdz_file;

/* The package of files[0..n-1] (files[0] a .usda or .usdc layer).  OUT:
 * *out (malloc'ed: the caller frees), *len.  GLINT_EINVAL for a bad path
 * or a first file that is no USD layer, GLINT_ERANGE beyond the sizes
 * above, GLINT_ENOMEM. */
int usdz_pack(const usdz_file *files, int n, void **out, size_t *len, glint_err *err);

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
