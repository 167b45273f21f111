/* material.h: a fitted material (the factored BRDF), its evaluation,
 * CPU reference rendering, and its files.
 *
 * On disk a material is a directory:
 *   material.json  manifest: method, every parameter, the log-factors at
 *                  full precision (authoritative), mapping offsets, timings
 *                  and errors (the `info` object), texel convention.
 *   factors.exr    3 rows (p, q, r) x res texels, RGB, linear factor values
 *                  in the canonical gauge (mean log equal across factors).
 *   factors.png    the same rows, each divided by its own maximum (the
 *                  scales are in the manifest, "png_scale").
 * Evaluation of a pixel: value_c = inverse_map_c(p q r) (x cos_i for the
 * brdf model), with log-linear interpolation between node texels, exactly
 * hf_factors_eval().  Ownership: a material owns its factors and its info
 * object (a jansson reference, decref'ed by material_free). */
#ifndef GLINT_MATERIAL_H
#define GLINT_MATERIAL_H

#include <jansson.h>

#include "err.h"
#include "gbuf.h"
#include "hf.h"
#include "img.h"
#include "mesh.h"
#include "scene.h"

typedef struct material {
    char method[16];  /* "hf3": three 1D factors */
    hf_factors fac;
    json_t *info;     /* parameters, statistics, timings (owned reference) */
} material;

/* Take ownership of fitted factors (moved: *fac is zeroed) and of `info`
 * (a new reference is stolen; may be NULL). */
void material_init(material *m, hf_factors *fac, json_t *info);

/* Evaluate at a direction pair (unit vectors, OUT rgb[3]). */
void material_eval(const material *m, const double n[3], const double wi[3],
                   const double wo[3], double rgb[3]);

/* Shade a G-buffer: RGB radiance for a light of intensity `intensity`
 * (per pixel value x intensity); pixels that are not lit and visible get 0,
 * background pixels `background`.  OUT: *out (RGB, allocated here). */
int material_shade(const material *m, const gbuf *g, double intensity,
                   float background, img *out, glint_err *err);

/* Rasterize `mesh` from view `v` at width x height, then shade (CPU
 * reference render) of mesh `msh`.  OUT: *out. */
int material_render(const material *m, const mesh *msh, const scene_view *v,
                    int width, int height, img *out, glint_err *err);

/* Write the directory described above (created if missing; files written
 * atomically). */
int material_save(const material *m, const char *dir, glint_err *err);

/* Read a material from its manifest (a material.json path or its
 * directory).  Validates format, version, method, sizes and finiteness. */
int material_load(const char *path, material *out, glint_err *err);

/* The manifest as a new JSON object (caller decrefs). */
json_t *material_to_json(const material *m);

void material_free(material *m);

#endif
