/* hfx_int.h: internals of hfx.c, for hfx*.c only. */
#ifndef GLINT_HFX_INT_H
#define GLINT_HFX_INT_H

#include "hfx.h"

/* The kernel form (hfx.h) of the reduced problem: idx[n] maps unknowns to
 * the nr reached ones (-1: unreached).  Fills dc->M, form, rank, s_max,
 * s_min_kept.  Returns 1 (dc untouched) when the form does not apply (no
 * factors given, a smoothing row across factors, a large null space of
 * the smoothing), else 0 or an error code. */
int hfx_kernel_build(const hfx_rows *x, const int *idx, int nr, double rcond, hfx_decomp *dc,
                     glint_err *err);

/* ---- the normal form's steps, shared with the distributed route ---- */
/* (hfx.c; hfx_mpi.c runs them on rows split among MPI ranks) */

/* Mark the unknowns x's rows reach (OUT: idx[x->n]: 0 reached, -1 not). */
void hfx_reached(const hfx_rows *x, int *idx);
/* Number the marked unknowns in order (idx[t] = 0..nr-1; -1 stays);
 * returns nr. */
int hfx_number_reached(int *idx, int n);
/* G += the normal matrix of x's rows over the reached unknowns (nr x nr,
 * column-major, upper triangle only). */
void hfx_normal_add(const hfx_rows *x, const int *idx, int nr, double *G);
/* The rcond the normal form uses for nr unknowns: at least sqrt(nr eps). */
double hfx_normal_rcond(double rcond, int nr);
/* The kept directions from eigenpairs of the normal matrix (e ascending,
 * vecs n x n column-major, as dsyevd returns them): s_max, the cut at
 * rcond s_max, s2, V (n x rank), rank, s_min_kept. */
int hfx_decomp_from_eig(const double *e, const double *vecs, int n, double rcond,
                        hfx_decomp *dc, glint_err *err);
/* V back to every unknown (zero rows where idx is -1) and null_dims. */
int hfx_decomp_finish(hfx_decomp *dc, const int *idx, int nr, glint_err *err);

#endif
