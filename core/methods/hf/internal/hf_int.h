/* hf_int.h: internals of the hf module, for hf*.c and the unit tests only. */
#ifndef GLINT_HF_INT_H
#define GLINT_HF_INT_H

#include "hf.h"

/* Dense B = [A; lambda L] (rows = n_samples + 3, cols = 3R),
 * column-major with leading dimension *ldb = rows.  malloc'ed; caller frees. */
double *hf_dense_B(const hf_design *d, double lambda, int *rows, int *ldb);

/* G = A^T A + lambda^2 L^T L assembled from the sparse rows, n x n,
 * both triangles filled (symmetric), column-major.  OUT: G[n*n]. */
void hf_normal_matrix(const hf_design *d, double lambda, double *G);

/* The two orthonormal gauge directions (OUT: Z[2 * n], column-major). */
void hf_gauge_vectors(int res, double *Z);

/* Laplacian row r (0 <= r < R-2) of one factor: entries at r, r+1, r+2. */
static inline void hf_laplacian_row(int r, int cols[3], double vals[3])
{
    cols[0] = r; cols[1] = r + 1; cols[2] = r + 2;
    vals[0] = 1.0; vals[1] = -2.0; vals[2] = 1.0;
}

/* Sparse transpose product t = A^T f for 3 channels (f: 3n sample-major,
 * OUT t: 3 * (3R) unknown-major, channel-minor). */
void hf_At_f(const hf_design *d, const double *f, double *t);

/* Log-space prediction A y for every sample (y: 3R x 3 channel-minor,
 * OUT: out[3 * n]). */
void hf_A_y(const hf_design *d, const double *y, double *out);

/* ---- the decomposition's rules, shared with the distributed route ---- */
/* (hf_decomp.c; hf_mpi.c runs the same rules on eigenpairs it gathered) */

/* Check the arguments of a decomposition of `nsamples` data rows and fill
 * out's header (res, n, nsamples, lambda, route, rcond: the default when
 * rcond <= 0, gain_max); everything else zeroed.  The errors of
 * hf_decomp_build. */
int hf_decomp_begin(int res, int nsamples, double lambda, hf_route route, double rcond,
                    hf_decomp *out, glint_err *err);

/* The gauge shift sigma added along the two gauge directions of the
 * normal matrix: 2 max_c colsum[c] + 1, with colsum[c] = sum_r |G[r,c]|
 * (above every eigenvalue of G). */
double hf_gauge_shift(const double *colsum, int n);

/* ||A v|| for direction v (column `col` of the vectors given to the keep
 * rules): how the keep rules reach the samples.  Called only for
 * directions with singular value below 1 (see hf_decomp in hf.h). */
typedef double (*hf_data_norm_fn)(void *cls, int col, const double *v);

/* Sum over the design's rows of (A v)_i^2: ||A v||^2 for a whole design,
 * a part of it for a share of the rows. */
double hf_data_norm2_part(const hf_design *d, const double *v);

/* The keep rules: of m singular pairs (vals[i], column i of vecs, n x m
 * column-major, n = dc->n) taken in the order order[0..m-1] (descending
 * values), the first two must lie in the gauge space Z (else
 * GLINT_ENUMERIC) and are dropped; of the others, those at or below
 * rcond * s_max are null, those with gain norm() / s^2 above gain_max
 * barely reached; the rest are kept.  dc's header must be filled
 * (hf_decomp_begin); OUT: dc->s, dc->V, rank and the counts. */
int hf_decomp_keep(hf_decomp *dc, const double *vals, const double *vecs, int m,
                   const int *order, const double *Z, hf_data_norm_fn norm, void *cls,
                   glint_err *err);

/* The eig route's last step: eigenpairs (w ascending, as LAPACK's dsyevd
 * returns them; vecs n x n column-major) of the normal matrix with the
 * gauge shift added, through the keep rules. */
int hf_decomp_from_eig(hf_decomp *dc, const double *w, const double *vecs, const double *Z,
                       hf_data_norm_fn norm, void *cls, glint_err *err);

/* ---- the sample-level passes of a fit (hf_stream.c) ---- */

/* Chunks of the sample-level passes: at most HF_MAX_CHUNKS of at least
 * HF_MIN_CHUNK samples, a function of the count alone (so results do not
 * depend on the number of threads). */
#define HF_MIN_CHUNK 4096
#define HF_MAX_CHUNKS 32
void hf_chunking(long n, int *chunk, int *nchunks);

/* What a pass reads: the design, the RGB samples, the mapping with its
 * offsets a[3] (a_used) and the model. */
typedef struct hf_stream {
    const hf_design *d;
    const float *rgb;
    const hf_map *map;
    hf_model model;
    const double *a;
    int single;          /* the logs in single precision (HF_F32), summed in double */
} hf_stream;

/* t = A^T f~ with f~ the log-mapped samples (OUT: t[9R], clamped[3]:
 * samples floored at eps per channel; *reused: chunks whose sums came from
 * reuse's memo, see hf_fit_with).  -1 when out of memory, 1 when a sample
 * is not finite (t is then meaningless), else 0.  reuse may be NULL. */
int hf_stream_forward(const hf_stream *x, const hf_fit_reuse *reuse, double *t,
                      int clamped[3], int *reused);

/* log_residual, rms, max_abs, diag_samples, diag_stride and diag_runs of *st for the
 * factors fac (hf.h).  -1 when out of memory (st untouched). */
int hf_stream_diagnostics(const hf_stream *x, const hf_factors *fac, hf_fit_stats *st);

/* Monotonic clock in seconds. */
double hf_now(void);

#endif
