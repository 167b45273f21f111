/* hf2d.h: three factors of which any may be 2D, over parabolic maps of
 * the vectors in the surface's tangent frame (Jaroszkiewicz & McCool 2003,
 * section 3.1 and Figure 2; the parameterization of McCool, Ang and Ahmad
 * 2001), for materials whose highlight depends on direction around the
 * normal (brushed, anisotropic paint):
 *
 *     f(wi, wo) ~ p(wi) q(h) r(wo),
 *
 * each factor either 1D over the length of its vector projected on the
 * tangent plane (hf.h's pi_p, pi_q, pi_r: an isotropic factor) or 2D over
 * the parabolic map of the vector.
 *
 * Conventions
 *  - Frame: vec3.h's v3_frame(n): t = normalize(Z x n), b = n x t (Z the
 *    world's up axis; t = +X at the poles n = +-Z).  A frame from the normal alone needs nothing
 *    but the samples' normals: imported samples, the CPU and the GPU
 *    evaluate it alike.
 *  - Parabolic map of a unit direction d (d.n clamped to >= 0):
 *        (x, y) = (d.t, d.b) / (1 + d.n) in the unit disc,
 *        (u, v) = ((x + 1) / 2, (y + 1) / 2) in [0, 1]^2,
 *    so that the normal maps to the centre and the horizon to the circle
 *    of radius 1/2 around it.  A 2D factor has S x S nodes, node (i, j)
 *    at (u, v) = (i, j) / (S - 1), bilinear hats between them (hf4.h's
 *    convention); nodes outside the disc are reached only by smoothing.
 *  - Unknowns: the factors' log nodes in order p, q, r (R for a 1D
 *    factor, S^2 for a 2D one), offsets off[0..3].
 *  - Smoothing: second differences [1 -2 1] weighted by lambda on 1D
 *    factors, the graph Laplacian of hf4.h's s weighted by lambda_2d on
 *    2D ones; a zero weight adds no rows.
 *  - Gauge: a constant moves freely between the three factors: gauge_dims
 *    2.  Decomposition, rank cut, unreached nodes and the canonical gauge
 *    (equal mean log per factor and channel) are hfx.h's.
 *  - Range: each log value is clamped to +-HF2D_LOG_MAX (a product of
 *    three stays a finite float); the fit counts what it clamped.
 *
 * Thread-safety: a decomposition is read-only once built; fits may share
 * it. */
#ifndef GLINT_HF2D_H
#define GLINT_HF2D_H

#include <stdint.h>

#include "err.h"
#include "hf.h"
#include "hfx.h"
#include "samples.h"

#define HF2D_SRES_MIN 4
#define HF2D_SRES_MAX 64
#define HF2D_LOG_MAX HF_LOG_FACTOR_MAX

typedef struct hf2d_shape {
    int res;             /* nodes of a 1D factor */
    int sres;            /* nodes per side of a 2D factor */
    int dims[3];         /* 1 or 2, for p, q, r */
} hf2d_shape;

/* GLINT_ERANGE for a resolution or a dimension out of range. */
int hf2d_shape_check(const hf2d_shape *sh, glint_err *err);
/* Offsets of the factors' unknowns (OUT: off[4]); returns off[3]. */
int hf2d_offsets(const hf2d_shape *sh, int off[4]);

typedef struct hf2d_design {
    hf2d_shape sh;
    int n;               /* samples */
    int off[4];
    int32_t *k;          /* 6n: per sample and factor, k0 (1D) or i0, j0 (2D) */
    double *t;           /* 6n: the hat weights of k0 + 1, or of i0 + 1 and j0 + 1 */
    double *cos_i;       /* n: n.wi */
} hf2d_design;

int hf2d_design_build(const samples *s, const hf2d_shape *sh, hf2d_design *out,
                      glint_err *err);
void hf2d_design_free(hf2d_design *d);

/* The parabolic map of unit d at unit normal nrm (OUT: uv[2], in [0,1]^2). */
void hf2d_parabolic(const double nrm[3], const double d[3], double uv[2]);

typedef struct hf2d_decomp {
    hf2d_shape sh;
    double lambda, lambda_2d;
    hfx_decomp x;
} hf2d_decomp;

/* rcond <= 0: HF4_RCOND_DEFAULT.  GLINT_ERANGE: a weight negative,
 * non-finite or above HF_LAMBDA_MAX, rcond >= 1. */
int hf2d_decomp_build(const hf2d_design *d, double lambda, double lambda_2d, double rcond,
                      hf2d_decomp *out, glint_err *err);
void hf2d_decomp_free(hf2d_decomp *dc);

/* B's rows as hfx.h's rows: the data rows of d's samples, then lambda's
 * (1D factors) and lambda_2d's (2D factors) smoothing rows, none for a
 * zero weight.  c is the storage the rows refer to (it and d must outlive
 * them).  What hf2d_decomp_build decomposes, and what a distributed route
 * splits (hfx_mpi.h). */
typedef struct hf2d_rows_ctx {
    const hf2d_design *x;
    double lambda, lambda_2d;
    int start[4];        /* first smoothing row of each factor (relative), and the total */
    int grid[3];         /* S for a 2D factor with smoothing (hfx_rows.grid) */
} hf2d_rows_ctx;
hfx_rows hf2d_rows(const hf2d_design *d, double lambda, double lambda_2d, hf2d_rows_ctx *c);

typedef struct hf2d_factors {
    hf2d_shape sh;
    int off[4];
    hf_model model;
    hf_map map;
    double a_used[3];
    double *logy;        /* off[3] x 3: (off[j] + node) * 3 + c; a 2D node (i, j) is j S + i */
} hf2d_factors;

/* Fit RGB samples (3 n, sample-major).  OUT: *fac, *st (may be NULL). */
int hf2d_fit(const hf2d_design *d, const hf2d_decomp *dc, const hf_map *map, hf_model model,
             const float *rgb, const int *view, hf2d_factors *fac, hfx_fit_stats *st,
             glint_err *err);

/* The material at unit vectors (OUT rgb[3]); 0 unless n.wi > 0 and
 * n.wo > 0. */
void hf2d_factors_eval(const hf2d_factors *f, const double n[3], const double wi[3],
                       const double wo[3], double rgb[3]);
void hf2d_factors_free(hf2d_factors *f);

#endif
