/* hf4.h: the four-factor product (Jaroszkiewicz & McCool 2003, section
 * 4.2): a three-factor BRDF times a spatial factor over the surface's
 * texture coordinates,
 *
 *     f(x, wi, wo) ~ p(pi_p) q(pi_q) r(pi_r) s(u, v),
 *
 * fitted in log space like hf.h's three factors (the same projections,
 * hats, mappings and models), with the spatial factor's log on an S x S
 * grid of nodes.
 *
 * Conventions
 *  - Unknowns y = [log p (R), log q (R), log r (R), log s (S^2)],
 *    n = 3R + S^2; s's node (i, j) (column i, row j) at u = i / (S-1),
 *    v = j / (S-1), index 3R + j S + i; bilinear hats between the four
 *    nodes around (u, v) (clamped to [0,1]^2), the 2D analogue of hf_hat.
 *  - Smoothing: hf.h's second differences [1 -2 1] on p, q, r weighted by
 *    lambda, and the grid's graph Laplacian on s weighted by lambda_s: a
 *    row per node, its neighbours (4 inside, 3 on an edge, 2 at a corner)
 *    minus as many times the node, so that every node is tied to its
 *    neighbours; data rows unweighted.  A zero weight adds no rows.
 *  - Gauge: a constant moves freely between the four factors, so B has an
 *    exact 3-dimensional null space; nodes of s that no sample reaches add
 *    null directions when lambda_s = 0 (with lambda_s > 0 the Laplacian
 *    fills them from their neighbours, harmonically; a 1D texel that no
 *    sample reaches likewise with lambda).  Both are cut with
 *    every direction whose singular value is at or below rcond s_max, so
 *    the solution is the minimum-norm one on the rest; it is then shifted
 *    into the canonical gauge: equal mean log over each factor's nodes,
 *    channel by channel (the product is unchanged).  Reports count them:
 *    gauge_dims 3, null_dims the rest of the cut.
 *  - Form of the decomposition: the operator is B^+ = V diag(1/s^2) V^T
 *    A^T with V, s from either
 *      "normal": the eigendecomposition of B^T B (n x n, LAPACK dsyevd), or
 *      "dense":  the SVD of B itself (rows x n, rows = samples + smoothing
 *                rows, LAPACK dgesdd),
 *    whichever matrix is smaller (the dense one only when a scene has
 *    fewer rows than unknowns: a large S over few samples), or
 *      "kernel": fewer samples than unknowns but smoothing on every
 *                factor: hfx.h's N x N route, the operator itself;
 *    the decomposition says which (form).  The normal form squares the
 *    condition number: rcond defaults to 1e-6 as for hf.h's eig route,
 *    and the normal form raises a smaller one to sqrt(n eps), the smallest
 *    relative singular value its eigenvalues resolve (the decomposition
 *    reports the rcond it used).
 *  - Range: each log-factor is clamped to +-HF4_LOG_MAX (the product of
 *    four stays a finite float), and the fit counts the values it clamped.
 *
 * Sizes: HF4_SRES_MAX bounds S (S^2 = 4096 unknowns: the normal form is
 * 150 MB at R = 64 and its decomposition takes tens of seconds here).
 *
 * Thread-safety: a decomposition is read-only once built; fits may share
 * it. */
#ifndef GLINT_HF4_H
#define GLINT_HF4_H

#include <stdint.h>

#include "err.h"
#include "hf.h"
#include "hfx.h"
#include "samples.h"

#define HF4_SRES_MIN 2
#define HF4_SRES_MAX 64
#define HF4_LOG_MAX 22.0 /* 4 x 22 = 88 < log FLT_MAX */

typedef struct hf4_design {
    hf_design d;         /* the three 1D factors (hf.h) */
    int sres;            /* S */
    int32_t *ij;         /* 2n: node (i0, j0) below each sample's uv */
    double *txy;         /* 2n: bilinear weights of i0 + 1 and j0 + 1 */
} hf4_design;

/* GLINT_EINVAL: samples without texture coordinates; GLINT_ERANGE: res
 * or sres out of range. */
int hf4_design_build(const samples *s, int res, int sres, hf4_design *out, glint_err *err);
void hf4_design_free(hf4_design *d);

typedef struct hf4_decomp {
    int res, sres;
    double lambda, lambda_s;
    hfx_decomp x;        /* form, rank, gauge_dims (3), null_dims, unreached, the
                            kept directions or the kernel operator: hfx.h */
} hf4_decomp;

/* The default relative cut of the kept singular values.  1e-6 let a fit of
 * 317 samples with lambda_s = 0 blow up (tests/unit/test_hf4.c,
 * few_samples_no_smoothing_of_s); with smoothing, 1e-6 and 1e-4 give the
 * same errors to 4 digits (tests/bench/bench_hf4.c --rcond). */
#define HF4_RCOND_DEFAULT 1e-4

/* Decompose B = [A; lambda L1; lambda_s L2] (rcond <= 0: HF4_RCOND_DEFAULT).
 * GLINT_ERANGE: lambda or lambda_s negative, non-finite or above
 * HF_LAMBDA_MAX; GLINT_ENUMERIC when LAPACK fails. */
int hf4_decomp_build(const hf4_design *d, double lambda, double lambda_s, double rcond,
                     hf4_decomp *out, glint_err *err);
void hf4_decomp_free(hf4_decomp *dc);

/* B's rows as hfx.h's rows: the data rows of d's samples, then lambda's
 * and lambda_s's smoothing rows (none for a zero weight), with the
 * factors' node ranges.  c is the storage the rows refer to (it and d must
 * outlive them).  What hf4_decomp_build decomposes, and what a
 * distributed route splits (hfx_mpi.h). */
typedef struct hf4_rows_ctx {
    const hf4_design *x;
    double lambda, lambda_s;
    int off[5];          /* the factors' unknowns: p, q, r, s */
    int grid[4];         /* hfx_rows.grid: s's side when it is smoothed */
} hf4_rows_ctx;
hfx_rows hf4_rows(const hf4_design *d, double lambda, double lambda_s, hf4_rows_ctx *c);

typedef struct hf4_factors {
    int res, sres;
    hf_model model;
    hf_map map;
    double a_used[3];
    double *logf;        /* 3R x 3: (j R + k) * 3 + c, as hf_factors */
    double *logs;        /* S^2 x 3: (j S + i) * 3 + c */
    double mean_s[3];    /* mean of s (linear) over its nodes: the value without uv */
} hf4_factors;

/* clamped, log_clamped (beyond HF4_LOG_MAX), log_max, log_residual, rms,
 * max_abs, seconds: hfx.h */
typedef hfx_fit_stats hf4_fit_stats;

/* Fit RGB samples (3 n, sample-major, per unit light).  OUT: *fac, *st (may
 * be NULL).  GLINT_ENONFINITE for a non-finite value. */
int hf4_fit(const hf4_design *d, const hf4_decomp *dc, const hf_map *map, hf_model model,
            const float *rgb, const int *view, hf4_factors *fac, hf4_fit_stats *st,
            glint_err *err);

/* The material at uv (NULL: mean_s) and unit vectors (OUT rgb[3]); 0
 * unless n.wi > 0 and n.wo > 0. */
void hf4_factors_eval(const hf4_factors *f, const double uv[2], const double n[3],
                      const double wi[3], const double wo[3], double rgb[3]);
/* mean_s from logs. */
void hf4_factors_means(hf4_factors *f);
void hf4_factors_free(hf4_factors *f);

#endif
