/* material.h: a fitted material, whatever method made it: evaluation, CPU
 * rendering, errors against reference images, and its files.
 *
 * A material is the method that made it (method.h), the method's own
 * representation of it (opaque here) and an `info` object (parameters,
 * precomputation report, timings, errors).  Everything method-specific
 * goes through the method's material_ops.
 *
 * On disk a material is a directory:
 *   material.json  the manifest: {"format": "glint-material", "version": 1,
 *                  "method": name, <the method's members>, "info": {...}}
 *                  (for hf3: res, texels, model, mapping, a_used, the
 *                  log-factors at full precision, gauge, png_scale)
 *   other files    written by the method (hf3: factors.exr, factors.png;
 *                  material_save_deferred leaves these to
 *                  material_files_ensure).
 * material_load() finds the method by name and validates everything.
 *
 * Ownership: a material owns its data and info (a jansson reference,
 * decref'ed by material_free, which accepts NULL and zeroed materials).
 * Thread-safety: a material is read-only once made; any number of threads
 * may evaluate, render or save it at once.  material_* functions touch no
 * global state. */
#ifndef GLINT_MATERIAL_H
#define GLINT_MATERIAL_H

#include <jansson.h>

#include "cancel.h"
#include "err.h"
#include "gbuf.h"
#include "img.h"
#include "mesh.h"
#include "method.h"
#include "scene.h"

typedef struct material {
    const method *method;  /* what made it (NULL: an empty material) */
    void *data;            /* the method's representation (owned) */
    json_t *info;          /* parameters, statistics, timings (owned reference) */
} material;

/* Make a material of method `meth` from its data (ownership of `data` and
 * of one reference to `info`, which may be NULL, passes to *m). */
void material_init(material *m, const method *meth, void *data, json_t *info);

/* The method's name ("" for an empty material). */
const char *material_method_name(const material *m);

/* Evaluate at a direction pair (unit vectors, OUT rgb[3], per unit light):
 * 0 unless n.wi > 0 and n.wo > 0.  A material that varies over the surface
 * (material_spatial) gives its average over the surface here. */
void material_eval(const material *m, const double n[3], const double wi[3],
                   const double wo[3], double rgb[3]);
/* The same at the surface point with texture coordinates uv (NULL: the
 * average; uv outside [0,1]^2 is clamped to it). */
void material_eval_at(const material *m, const double uv[2], const double n[3],
                      const double wi[3], const double wo[3], double rgb[3]);

/* The same for previews: the method's faster approximation where it has
 * one (method.h, eval_preview), else material_eval. */
void material_eval_preview(const material *m, const double n[3], const double wi[3],
                           const double wo[3], double rgb[3]);
void material_eval_preview_at(const material *m, const double uv[2], const double n[3],
                              const double wi[3], const double wo[3], double rgb[3]);

/* Radiance per unit light under an environment's light (envlit.h's
 * envlit_fn; ctx: a const material *): material_eval_at, and
 * material_eval_preview_at (the method's faster approximation, if any). */
void material_envlit(const void *ctx, const double uv[2], const double n[3],
                     const double wi[3], const double wo[3], double rgb[3]);
void material_envlit_preview(const void *ctx, const double uv[2], const double n[3],
                             const double wi[3], const double wo[3], double rgb[3]);

/* 1 when the material varies over the surface (its value depends on the
 * texture coordinates), 0 when one BRDF holds everywhere. */
int material_spatial(const material *m);

/* Shade a G-buffer: RGB radiance for a light of intensity `intensity`
 * (scene.h's radiance: pi I f cos_i);
 * covered pixels that are not lit and seen get 0, background pixels
 * `background`.  OUT: *out (RGB, allocated here). */
int material_shade(const material *m, const gbuf *g, double intensity,
                   float background, img *out, glint_err *err);

/* CPU reference render of mesh `msh` from view `v` at width x height
 * (rasterized and shaded in bands of rows, so memory beyond the image is
 * bounded by MATERIAL_RENDER_BAND_PIXELS G-buffer pixels).  OUT: *out.
 * cancel (may be NULL) is asked about every GLINT_CANCEL_WORK pixels
 * (cancel.h): GLINT_ECANCELLED, *out freed, once it says to stop. */
#define MATERIAL_RENDER_BAND_PIXELS (1 << 18)
int material_render(const material *m, const mesh *msh, const scene_view *v,
                    int width, int height, img *out, const glint_cancel *cancel,
                    glint_err *err);

/* Error of a material against reference images on the sample pixels
 * (mask, n.wi > 0, n.wo > 0) of nviews G-buffers: RMS and max |difference|
 * over pixels and RGB channels, radiance pi I f cos_i for each view's light
 * intensity I (views may be NULL: I = 1).  truth[v] must be sized like
 * g[v] (1, 3 or 4 channels).  OUT: *rms, *max_abs, *count (any may be
 * NULL). */
int material_error_views(const material *m, const gbuf *g, const scene_view *views,
                         int nviews, const img *truth, double *rms, double *max_abs,
                         long *count, glint_err *err);

/* A few members describing the material for the API (e.g. {"res": 64};
 * a new object). */
json_t *material_summary(const material *m);

/* How the GPU evaluates it (see method.h; release with material_gpu_free). */
int material_gpu_get(const material *m, material_gpu *out, glint_err *err);

/* Write the directory described above (created if missing; every file
 * written atomically, material.json last). */
int material_save(const material *m, const char *dir, glint_err *err);

/* As material_save, but the method's derived files (material_ops.
 * derived_files: for hf3 factors.exr and factors.png) are left unwritten:
 * only material.json, durable when this returns.  For a caller that answers
 * before anyone reads those files (glintd's fit); material_files_ensure
 * writes them on first use.  Methods without derived files: material_save. */
int material_save_deferred(const material *m, const char *dir, glint_err *err);

/* Write the material's derived files when any of them is not in dir: the
 * same files material_save writes, from the manifest alone, each renamed
 * into place and durable when this returns.  When all are there nothing is
 * written.  Concurrent callers are safe: a reader sees a whole file, old or
 * new, with the same content.  OUT: *written (may be NULL), how many were
 * missing. */
int material_files_ensure(const char *dir, int *written, glint_err *err);

/* Read a material from its manifest (a material.json path or its
 * directory).  Validates format, version, method and the method's data. */
int material_load(const char *path, material *out, glint_err *err);

void material_free(material *m);

#endif
