/* method_hf4.h: the four-factor product as a method, "hf4" (hf4.h has the
 * numerics and conventions).
 *
 * Parameters (hf4_params_t): res (1D factors), s_res (the spatial
 * factor's nodes per side), lambda and lambda_s (smoothing), mapping and
 * model (as hf3), rcond.  One level after the sampling pattern:
 *   decomposition  key "hf4:<pattern hash>:res:s_res:lambda:lambda_s:rcond":
 *                  the design and the kept directions of B; on disk (the
 *                  cache directory's <XXH3-128 of the key>.hf4, checksummed:
 *                  method_hf4.c) the decomposition, the design rebuilt
 * The material's data is an hf4_factors.  On disk: material.json holds
 * the log-factors at full precision (log_factors p, q, r as hf3 writes
 * them, log_s: s_res^2 rows [r, g, b], row j s_res + i for node (i, j));
 * factors.exr / .png the 1D factors (3 rows), spatial.exr / .png the
 * spatial factor (s_res x s_res, linear, row 0 at v = 0 first). */
#ifndef GLINT_METHOD_HF4_H
#define GLINT_METHOD_HF4_H

#include "hf.h"
#include "hf4.h"
#include "material.h"
#include "method.h"

extern const method method_hf4;

typedef struct hf4_params_t {
    int res, sres;
    double lambda, lambda_s, rcond;
    hf_map map;
    hf_model model;
} hf4_params_t;

/* The decomposition level's key for p and a pattern hash (OUT: key), and
 * its file <dir>/<XXH3-128 of the key>.hf4 written from a decomposition:
 * what the level's disk layer reads (glint-mpi writes it too). */
void hf4_level_key(const hf4_params_t *p, const char pattern_hash[33], char *key, size_t len);
int hf4_decomp_save(const hf4_decomp *dc, const char *dir, const char *key, glint_err *err);

/* The factors of an hf4 material (NULL for another method's). */
const hf4_factors *hf4_of(const material *m);

extern const char hf4_glsl_frag[];

#endif
