/* hfx.h: the solver that factor products with 2D factors share (hf4.h's
 * four-factor product, hf2d.h's factors over parabolic maps): a product of
 * J factors, each a set of nodes with hat weights, fitted in log space
 * through a cached decomposition of
 *
 *     B = [A; smoothing rows],
 *
 * A's rows the samples' sparse hat weights.  A model supplies the rows
 * (struct hfx_rows) and the factors' node ranges; this module owns the
 * decomposition and the fit, so that every such model treats unreached
 * nodes, the gauge, the rank cut and the range the same way.
 *
 * Conventions
 *  - Rows: r < nsamples are data rows (unweighted), the rest smoothing
 *    rows with their weights included; a row has at most HFX_ROW_MAX
 *    nonzeros.
 *  - Unknowns that no row reaches are exactly null: left out of the
 *    decomposition, their rows of V zero (counted: unreached).
 *  - Form: "normal" (eigendecomposition of B^T B, LAPACK dsyevd) or
 *    "dense" (SVD of B, dgesdd), whichever matrix is smaller; the normal
 *    form raises rcond to sqrt(n eps) (what its eigenvalues resolve) and
 *    reports the rcond it used.  "kernel" when there are fewer samples
 *    than unknowns but the smoothing rows make B tall (few samples, fine
 *    factors: seed 000's Table 2): with K = L^T L (the smoothing rows'
 *    normal matrix, block diagonal by factor, each distinct block
 *    eigendecomposed once, or written down for a grid's Laplacian:
 *    K = Q diag(e) Q^T) and the data rows A, the
 *    unknowns are y = Z a + Q1 b, Z the null space of K (e = 0: constants,
 *    and lines for second differences), Q1 the rest.  Eliminating a by
 *    least squares (W0 = A Z, its pseudo-inverse cut at rcond, P the
 *    projector off its range) leaves a ridge problem in b whose normal
 *    matrix W1^T P W1 + diag(e1) (W1 = A Q1) is inverted through the
 *    samples' side (push-through identity):
 *        b = diag(1/e1) W1^T P (I + P W1 diag(1/e1) W1^T P)^-1 P f~,
 *        a = W0^+ (f~ - W1 b),
 *    an N x N Cholesky instead of an n x n eigendecomposition.  The result
 *    is the operator itself, y = M f~ (n x N): the exact least-squares
 *    solution with every direction the smoothing reaches kept (nothing cut
 *    but the null directions of W0), where the normal form cuts those with
 *    s_i <= rcond s_max.  s_max and s_min_kept are then those of the
 *    smoothing rows alone (B's kept singular values are at least
 *    s_min_kept).
 *  - Directions with s_i <= rcond s_max are cut (the gauge among them):
 *    the solution is the minimum-norm one on the rest, then shifted into
 *    the canonical gauge: equal mean log over each factor's nodes, channel
 *    by channel (the product is unchanged), each value clamped to
 *    +-log_max and counted.
 *  - The mapping and model are hf.h's (hf_map, hf_model).
 *
 * Thread-safety: a decomposition is read-only once built; fits may share
 * it. */
#ifndef GLINT_HFX_H
#define GLINT_HFX_H

#include <stdint.h>

#include "err.h"
#include "hf.h"

#define HFX_ROW_MAX 16 /* nonzeros of a row: 4 per 2D factor, 2 per 1D one */
#define HFX_FACTORS_MAX 4

typedef struct hfx_rows {
    const void *ctx;
    int n;               /* unknowns */
    int nsamples;        /* data rows */
    int nsmooth;         /* smoothing rows after them */
    /* row r's nonzeros (OUT: col, w; returns their count <= HFX_ROW_MAX) */
    int (*row)(const void *ctx, int r, int *col, double *w);
    /* Optional (nfactors 0: none): the factors' unknowns, off[nfactors + 1],
     * when every smoothing row stays within one factor; this allows the
     * kernel form. */
    int nfactors;
    const int *off;
    /* Optional (may be NULL): per factor, S when its smoothing rows are
     * hfx_smooth_2d's over all of its S x S nodes (their eigenvectors are
     * then known: products of DCT-II cosines), else 0. */
    const int *grid;
} hfx_rows;

typedef struct hfx_decomp {
    int n, nsamples;
    int rows;            /* of B: samples + smoothing rows */
    const char *form;    /* "normal" or "dense" */
    double rcond;        /* the cut used */
    int rank;            /* directions kept */
    int gauge_dims;      /* as the model states it */
    int null_dims;       /* other directions cut, unreached ones included */
    int unreached;       /* unknowns no row reaches */
    double s_max, s_min_kept;
    double *s2;          /* rank: s_i^2, descending */
    double *V;           /* n x rank, column-major (normal and dense forms) */
    double *M;           /* kernel form: the operator, n x nsamples, column-major */
    int grid_blocks;     /* kernel form: smoothing blocks whose eigenvectors were written
                            down (hfx_rows.grid), not computed */
    double seconds;
} hfx_decomp;

/* Decompose B (rcond in (0, 1)).  GLINT_ENOMEM, or GLINT_ENUMERIC when
 * LAPACK fails. */
int hfx_decomp_build(const hfx_rows *x, double rcond, int gauge_dims, hfx_decomp *out,
                     glint_err *err);
void hfx_decomp_free(hfx_decomp *dc);

/* The decomposition in a cache file (cfile.h), after the model's own
 * fields: u32 n, nsamples, rows, form (0 normal, 1 dense, 2 kernel), rank,
 * gauge_dims, null_dims, unreached; doubles rcond, s_max, s_min_kept,
 * seconds; then s2[rank] and V[n rank], or for the kernel form M[n
 * nsamples].  hfx_decomp_get checks n and nsamples against the expected
 * ones and every count against the rest (GLINT_EFORMAT naming `name`). */
struct cfile_w;
struct cfile_r;
void hfx_decomp_put(struct cfile_w *b, const hfx_decomp *g);
int hfx_decomp_get(struct cfile_r *r, int n, int nsamples, hfx_decomp *g, const char *name,
                   glint_err *err);

/* A decomposition's file in a cache directory: <dir>/<hash of key><ext>
 * (cfile.h, kind 1, magic 8 bytes), a header of nu u32 and nd doubles (the
 * method's shape and weights), then hfx_decomp_put.  load checks the
 * header against u and d exactly and reads the decomposition for n
 * unknowns and nsamples samples (GLINT_EFORMAT, naming the file, when
 * anything differs).  nu, nd at most 8. */
int hfx_decomp_file_save(const char *magic, const char *ext, const uint32_t *u, int nu,
                         const double *d, int nd, const hfx_decomp *g, const char *dir,
                         const char *key, glint_err *err);
int hfx_decomp_file_load(const char *magic, const char *ext, const uint32_t *u, int nu,
                         const double *d, int nd, int n, int nsamples, hfx_decomp *g,
                         const char *dir, const char *key, glint_err *err);

#define HFX_MAX_VIEWS 256 /* scene.h's SCENE_MAX_VIEWS */

typedef struct hfx_fit_stats {
    int clamped[3];      /* samples floored at eps before the log, per channel */
    long log_clamped;    /* log-factor values clamped to +-log_max */
    double log_max;      /* largest |log-factor| returned */
    double log_residual; /* RMS of A y - f~ over samples and channels (log space) */
    double rms, max_abs; /* reconstruction - sample, linear */
    double seconds;      /* the fit (mapping, application, gauge) */
    /* with the problem's view: rms's sums view by view, the squared linear
     * errors of each view's samples over the channels and its samples */
    double view_se[HFX_MAX_VIEWS];
    long view_n[HFX_MAX_VIEWS];
} hfx_fit_stats;

/* What a fit needs besides the rows and the decomposition. */
typedef struct hfx_problem {
    const hf_map *map;
    hf_model model;
    const double *cos_i; /* nsamples: n.wi (the brdf model divides by it) */
    int nfactors;        /* J */
    const int *off;      /* J + 1: factor j's unknowns are off[j] .. off[j+1]-1 */
    double log_max;      /* range of a returned log value */
    const int *view;     /* nsamples: each sample's view (< HFX_MAX_VIEWS), for the errors by
                            view; NULL: none */
} hfx_problem;

/* Fit RGB samples (3 nsamples, sample-major).  OUT: y (n x 3, column per
 * channel: the log nodes in the canonical gauge), a_used[3] (the mapping's
 * offsets), *st (may be NULL).  GLINT_EINVAL for a mismatch or bad
 * mapping, GLINT_ENONFINITE for a non-finite value. */
int hfx_fit(const hfx_rows *x, const hfx_decomp *dc, const hfx_problem *pb, const float *rgb,
            double *y, double a_used[3], hfx_fit_stats *st, glint_err *err);

/* Smoothing rows of one 1D factor at unknowns off.. (R nodes): R - 2
 * second differences [1 -2 1] weighted by lambda.  Row r (0 <= r < R-2). */
int hfx_smooth_1d(int off, double lambda, int r, int *col, double *w);
/* Smoothing rows of an S x S grid at unknowns off.. (node (i, j) at
 * off + j S + i): the graph Laplacian weighted by lambda, a row per node
 * (0 <= r < S^2): its neighbours minus as many times the node. */
int hfx_smooth_2d(int off, int S, double lambda, int r, int *col, double *w);

#endif
