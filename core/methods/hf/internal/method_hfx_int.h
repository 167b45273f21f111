/* method_hfx_int.h: what the methods of factor products with 2D factors
 * (hf4, hf2d: the products hfx.h solves) share as methods, for
 * method_hf4*.c and method_hf2d*.c only.
 *
 * The level: each caches one, the design of the pattern and the
 * decomposition of its rows, built, or read from its file in the cache
 * directory (hfx_decomp_file_load) with the design rebuilt from the
 * pattern.  The fit: the factors from the level, and the report every such
 * material carries (params, precomputation, seconds, errors).  The
 * material: the log nodes in material.json and the GPU binding's common
 * part.  A method says what differs (its types, its calls, the names of
 * its file) in an hfx_method. */
#ifndef GLINT_METHOD_HFX_INT_H
#define GLINT_METHOD_HFX_INT_H

#include <stddef.h>
#include <stdint.h>

#include "cache.h"
#include "hfx.h"
#include "material.h"
#include "method.h"

/* The start of such a method's level struct: what the report says the
 * level took. */
typedef struct hfx_level {
    double t_design;     /* seconds building the design (a loaded level: loading it all) */
    double t_load;       /* seconds reading it from disk (0: built) */
} hfx_level;

#define HFX_HEAD_MAX 8

/* The numbers a decomposition's file begins with, before hfx.h's
 * hfx_decomp_put: nu u32s, then nd doubles. */
typedef struct hfx_file_head {
    uint32_t u[HFX_HEAD_MAX];
    double d[HFX_HEAD_MAX];
    int nu, nd;
} hfx_file_head;

/* What differs between the methods.  The level struct of the method is
 * its own (level_size bytes, an hfx_level first, its hfx_decomp at
 * decomp_at); so is the material's data (factors_size bytes). */
typedef struct hfx_method {
    const method *self;
    size_t level_size;
    size_t decomp_at;
    size_t factors_size;
    const char *magic, *ext;     /* of the decomposition's file (hfx_decomp_file_*) */
    /* The design of the samples s for params, into the level. */
    int (*design)(const void *params, const samples *s, void *level, glint_err *err);
    /* The decomposition of the level's design for params. */
    int (*decompose)(const void *params, void *level, glint_err *err);
    /* What a decomposition's file must begin with for params (OUT: *head),
     * the level's decomposition given the same members; returns its
     * unknowns. */
    int (*file_head)(const void *params, void *level, hfx_file_head *head);
    /* Memory the level holds (the cache's count). */
    size_t (*bytes)(const void *level);
    /* Free the level and all it holds. */
    void (*free)(void *level);
    /* The report's operator_bytes of the level's decomposition. */
    size_t (*operator_bytes)(const void *level);
    /* Fit the painted values rgb with the level (OUT: the zeroed factors,
     * *st; view: each sample's view, for st's errors by view). */
    int (*fit)(const void *params, const void *level, const float *rgb, const int *view,
               void *factors, hfx_fit_stats *st, glint_err *err);
} hfx_method;

/* The level's build and disk load, as method_level's (the method's own
 * save writes what load reads). */
int hfx_level_build(const hfx_method *m, const method_build_in *in, cache_value *out,
                    glint_err *err);
int hfx_level_load(const hfx_method *m, const method_build_in *in, const char *dir,
                   const char *key, cache_value *out, glint_err *err);

/* The fit, as method.fit: the factors of in->levels[0] and their report. */
int hfx_method_fit(const hfx_method *m, const method_fit_in *in, material *out,
                   glint_err *err);

/* count log nodes (v: [r, g, b] each) as a JSON array of [r, g, b]; NULL
 * when out of memory. */
json_t *hfx_log_nodes_json(const double *v, int count);

/* count log nodes from the JSON array a (its size checked by the caller)
 * into v (OUT: 3 count).  GLINT_ENONFINITE naming file and what[k] for a
 * node that is not [r, g, b] of finite numbers in [-700, 700]. */
int hfx_log_nodes_get(const json_t *a, int count, double *v, const char *file,
                      const char *what, glint_err *err);

/* Start g (zeroed first) as a program with one RGB float texture of w x h
 * (zeroed) in u_factors.  GLINT_ENOMEM: g holds nothing. */
int hfx_gpu_begin(material_gpu *g, const char *program, const char *frag_src, int w, int h,
                  glint_err *err);

/* The uniforms of the inverse mapping and the model (OUT: u[3]: u_map_kind,
 * u_a, u_model_brdf). */
void hfx_gpu_mapping(material_gpu_uniform u[3], const hf_map *map, const double a_used[3],
                     hf_model model);

#endif
