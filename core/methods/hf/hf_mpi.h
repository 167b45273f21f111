/* hf_mpi.h: hf3's decomposition (hf.h, eig route) distributed over the
 * ranks of an MPI communicator, with ScaLAPACK's eigensolver.  Built only
 * into glint-mpi (core/cli/mpi_main.c), never into the core library, so
 * that glint and glintd need no MPI.
 *
 * What each rank does
 *   1. accumulates the normal matrix of its own share of the data rows,
 *      A_r^T A_r (n x n, n = 3 res; rank 0 adds lambda^2 L^T L), from a
 *      design of its own samples (hf_design_build on its views);
 *   2. (hf_mpi_eig_sum, below, which hfx_mpi.h's route shares) one
 *      MPI_Reduce_scatter sums the shares straight into ScaLAPACK's 2D
 *      block-cyclic layout (NB x NB blocks on a P_r x P_c grid, P_r the
 *      largest divisor of P at most sqrt(P)): each rank then holds n^2 / P
 *      of G = A^T A + lambda^2 L^T L;
 *   3. adds the gauge shift sigma Z Z^T (sigma from the column sums of G,
 *      the rule of hf_gauge_shift) and runs pdsyevd;
 *   4. the eigenvectors are gathered on rank 0 (MPI_Gatherv of the local
 *      blocks), the directions with singular value below 1 are sent to
 *      every rank, which returns its part of ||A v||^2 over its own rows
 *      (hf_data_norm2_part), summed on rank 0;
 *   5. rank 0 runs the single-process route's own rules on the result
 *      (hf_decomp_from_eig, hf_int.h): the same gauge identification,
 *      null and barely-reached cuts, the same hf_decomp.
 * The decomposition equals hf_decomp_build's (eig route) on the union of
 * the rows to rounding: the sums are taken in another order.
 *
 * Memory per rank: the n x n accumulation and its packed copy (2 n^2
 * doubles) while reducing, then n^2 / P for G and as much for the
 * eigenvectors, plus ScaLAPACK's workspace; rank 0 also holds the n x n
 * gathered eigenvectors and the result.
 *
 * Errors: the call is collective and so is its outcome: every rank returns
 * the same code, with the message of the lowest rank that failed (named
 * when it is not rank 0).  MPI itself is assumed to work (a failed MPI
 * call aborts the job: MPI's default error handler). */
#ifndef GLINT_HF_MPI_H
#define GLINT_HF_MPI_H

#include <mpi.h>

#include "err.h"
#include "hf.h"

/* Block size of the block-cyclic layout. */
#define HF_MPI_NB 64

typedef struct hf_mpi_stats {
    int nprocs, nprow, npcol, nb;  /* the process grid and block size */
    double t_gram;       /* this rank: its share of A^T A */
    double t_wait;       /* waiting for the slowest rank's share (a barrier) */
    double t_reduce;     /* the reduce-scatter into the block-cyclic layout */
    double t_eig;        /* pdsyevd (incl. workspace query and gauge shift) */
    double t_gather;     /* eigenvectors to rank 0 */
    double t_gain;       /* the data norms of the weak candidates, and the keep rules */
    int gain_dirs;       /* directions whose data norm was summed over the ranks */
    double bytes_local;  /* this rank's peak bytes of matrices (excl. ScaLAPACK workspace) */
    double bytes_work;   /* this rank's ScaLAPACK workspace bytes */
} hf_mpi_stats;

/* Collective over comm.  `local`: this rank's rows of A (its design; may
 * hold 0 rows, res must be the same on every rank); `nsamples`: the rows of
 * all ranks together (1..SAMPLES_MAX).  lambda, rcond as hf_decomp_build
 * (route eig).  OUT on rank 0: *out, the decomposition (hf_decomp_free),
 * build_seconds the wall time of the whole collective step; on the other
 * ranks *out is zeroed.  OUT: *st (may be NULL), this rank's figures. */
int hf_mpi_decomp_build(MPI_Comm comm, const hf_design *local, long nsamples, double lambda,
                        double rcond, hf_decomp *out, hf_mpi_stats *st, glint_err *err);

/* The collective eigensolver under both routes: the eigendecomposition of
 * G = sum over the ranks of G_r (n x n, column-major; the upper triangle
 * is read) plus, when Z is given (2 n: hf3's gauge directions), sigma Z Z^T
 * with sigma = hf_gauge_shift of G's column sums (both triangles of every
 * G_r must then be filled).  G_r stays the caller's.  OUT: w[n] on every
 * rank, ascending (rank 0's values); *V on rank 0 the n x n eigenvectors,
 * column-major (malloc'ed: the caller frees), NULL elsewhere; st's grid,
 * t_wait, t_reduce, t_eig, t_gather, bytes_local, bytes_work. */
int hf_mpi_eig_sum(MPI_Comm comm, int n, const double *G, const double *Z, double *w,
                   double **V, hf_mpi_stats *st, glint_err *err);

/* Agree on an outcome: every rank passes its own rc (0 or a code) and
 * message; all return the code of the lowest failing rank (0 if none) and
 * *err holds its message, prefixed with "rank K: " when K is not rank 0
 * (rank 0's own failures, and those every rank meets alike, read as
 * they would on one process). */
int hf_mpi_agree(MPI_Comm comm, int rc, glint_err *err);

#endif
