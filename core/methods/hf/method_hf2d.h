/* method_hf2d.h: three factors with any of them 2D over parabolic maps, as
 * a method, "hf2d" (hf2d.h has the numerics and conventions).
 *
 * Parameters (hf2d_params_t): res (1D factors), res_2d (nodes per side of
 * a 2D factor), p, q, r ("1d" or "2d" each; q 2D by default: the
 * anisotropic highlight), lambda and lambda_2d (smoothing), mapping and
 * model (as hf3), rcond.  One level after the sampling pattern:
 *   decomposition  key "hf2d:<pattern hash>:res:res_2d:dims:lambda:
 *                  lambda_2d:rcond": the design and the kept directions of
 *                  B; on disk (the cache directory's <XXH3-128 of the
 *                  key>.hf2d, checksummed: method_hf2d.c), the design
 *                  rebuilt from the pattern.
 * The material's data is an hf2d_factors.  On disk: material.json holds the
 * log nodes at full precision (method_hf2d_material.c); factors.exr / .png
 * the factors in the GPU texture's layout. */
#ifndef GLINT_METHOD_HF2D_H
#define GLINT_METHOD_HF2D_H

#include "hf2d.h"
#include "material.h"
#include "method.h"

extern const method method_hf2d;
extern const material_ops hf2d_material_ops;

typedef struct hf2d_params_t {
    int res, sres;
    int dims[3];         /* enum indices: 0 "1d", 1 "2d" */
    double lambda, lambda_2d, rcond;
    hf_map map;
    hf_model model;
} hf2d_params_t;

/* The shape of p's factors; the decomposition level's key for p and a
 * pattern hash (OUT: key); its file <dir>/<XXH3-128 of the key>.hf2d
 * written from a decomposition: what the level's disk layer reads
 * (glint-mpi writes it too). */
hf2d_shape hf2d_shape_of(const hf2d_params_t *p);
void hf2d_level_key(const hf2d_params_t *p, const char pattern_hash[33], char *key, size_t len);
int hf2d_decomp_save(const hf2d_decomp *dc, const char *dir, const char *key, glint_err *err);

/* The factors of an hf2d material (NULL for another method's). */
const hf2d_factors *hf2d_of(const material *m);

extern const char hf2d_glsl_frag[];

#endif
