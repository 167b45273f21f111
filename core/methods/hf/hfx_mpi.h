/* hfx_mpi.h: hfx.h's normal form (the decomposition under hf4, and any
 * factor product built on hfx_rows) distributed over MPI ranks, on the
 * collective eigensolver of hf_mpi.h.  Built only into glint-mpi.
 *
 * Each rank passes the rows it holds: the data rows of its own samples,
 * and, on rank 0 alone, the smoothing rows.  The unknowns some rank's rows
 * reach are agreed (an all-reduce of the flags) and numbered as hfx.c
 * numbers them; each rank accumulates its rows' normal matrix over them;
 * hf_mpi_eig_sum sums and eigen-decomposes it; rank 0 applies hfx.c's own
 * rules (the rcond floor sqrt(nr eps), the cut at rcond s_max, unreached
 * unknowns' zero rows of V: hfx_int.h).  The result is hfx_decomp_build's
 * "normal" form to rounding.
 *
 * The single-process route picks the dense form when B has fewer rows
 * than reached unknowns and may pick the kernel form when there are fewer
 * samples than reached unknowns; those problems are small by nature and
 * are refused here (GLINT_EUNSUPPORTED, saying which), so that a file
 * written here is always what glint fit would have built.
 *
 * Errors are collective (hf_mpi_agree): every rank returns the same code. */
#ifndef GLINT_HFX_MPI_H
#define GLINT_HFX_MPI_H

#include <mpi.h>

#include "hf_mpi.h"
#include "hfx.h"

/* Collective.  local: this rank's rows (local->n the same on every rank;
 * nsamples its data rows, nsmooth 0 except on rank 0); nsamples: the data
 * rows of all ranks (1..SAMPLES_MAX); rcond in (0, 1); gauge_dims as the
 * model states it.  OUT on rank 0: *out (hfx_decomp_free), seconds the
 * collective step's wall time; zeroed elsewhere.  OUT: *st (may be NULL):
 * this rank's figures (t_gram: its rows' normal matrix; t_gain: the rules
 * on rank 0). */
int hfx_mpi_decomp_build(MPI_Comm comm, const hfx_rows *local, long nsamples, double rcond,
                         int gauge_dims, hfx_decomp *out, hf_mpi_stats *st, glint_err *err);

#endif
