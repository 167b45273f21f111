/* method_hf3.h: the three-factor homomorphic factorization as a method
 * (Jaroszkiewicz & McCool 2003): method_hf3, its parameters, and what the
 * families built on it (maps, auto) and the tests need of its material.
 *
 * Parameters are fit_params (below); levels after the sampling pattern:
 *   decomposition  key pcache_key_hf(pattern hash, res, lambda, route, rcond):
 *                  the design (sparse rows) and the decomposition of
 *                  B = [A; lambda L]; on disk through pcache.h
 *   operator       key "<decomposition key>/<regularization>/<precision>"
 * The material's data is an hf_factors (hf.h). */
#ifndef GLINT_METHOD_HF3_H
#define GLINT_METHOD_HF3_H

#include "hf.h"
#include "material.h"
#include "method.h"

extern const method method_hf3;

/* hf3's parameters (method_params_to_json spells them). */
typedef struct fit_params {
    int res;            /* texels per factor (default 128: the knee in BENCHMARKS.md) */
    double lambda;      /* Laplacian weight (default 0.1) */
    hf_reg reg;         /* default trunc:full */
    hf_map map;         /* default add:0.1 (log(0.1 + f)) */
    hf_model model;     /* default radiance */
    hf_precision prec;  /* default double */
    hf_route route;     /* default eig */
    double rcond;       /* 0: hf_rcond_default */
} fit_params;

/* The defaults above (OUT: *p). */
void fit_params_default(fit_params *p);

/* Dense B of the svd route above this many bytes is refused (GLINT_ERANGE,
 * naming the eig route): the SVD's workspace is a few times B. */
#define HF3_SVD_MAX_BYTES ((size_t)1 << 30)

/* The fragment stage of an hf3 material (GLSL ES 3.00): what previews draw
 * and the shader export writes as glint_material.frag. */
extern const char hf3_glsl_frag[];
/* BRDF Explorer's analytic .brdf text of an hf3 material (hf_factors data),
 * exact (method_hf3_glsl.c). */
int hf3_brdf_explorer(const void *data, char **text, glint_err *err);

/* The factors of an hf3 material (NULL for another method's). */
hf_factors *hf3_factors(const material *m);

/* An hf3 material from fitted factors (moved: *fac is zeroed) and info
 * (one reference stolen; may be NULL).  GLINT_ENOMEM: the factors and info
 * are released and *m is a material with no data (material_free). */
int hf3_material_init(material *m, hf_factors *fac, json_t *info, glint_err *err);

/* The level values (what cache_data() of each level holds). */
typedef struct hf3_decomp {
    hf_design d;
    hf_decomp dc;
    double t_design, t_decomp;  /* seconds, as built */
} hf3_decomp;

/* Design + decomposition for a pattern (the decomposition level's build;
 * the tests' direct path too, tests/unit/fit.h), reporting the stages "design" (0.25) and
 * "decomposition" (0.3) through `progress` (may be NULL).  OUT: *out
 * (hf3_decomp_clear releases it). */
int hf3_decomp_make(const fit_params *p, const samples *s,
                    void (*progress)(void *cls, const char *stage, double fraction), void *cls,
                    hf3_decomp *out, glint_err *err);
void hf3_decomp_clear(hf3_decomp *x);

/* Everything a fit reports, with what the preparation measured. */
typedef struct hf3_prepared {
    const fit_params *params;
    const samples *s;
    const hf_design *d;
    const hf_decomp *dc;
    const hf_op *op;
    const char *cache_key;      /* the decomposition's key */
    int cache_hit;              /* disk: 1 loaded, 0 built, -1 rebuilt */
    double t_samples, t_design, t_decomp, t_op;
    const hf_fit_reuse *reuse;  /* NULL: none (hf_fit_with) */
} hf3_prepared;

/* Fit painted values (3 s->n, per unit light) and make the material with
 * its info {"params", "precomputation", "seconds", "errors"}; t_start is
 * when the fit began (glint_now()), for seconds.fit. */
int hf3_fit_material(const hf3_prepared *pp, const float *rgb, double t_start, material *out,
                     glint_err *err);

#endif
