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

/* Monotonic clock in seconds. */
double hf_now(void);

#endif
