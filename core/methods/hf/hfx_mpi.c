/* hfx_mpi.c: hfx.h's normal form over MPI ranks (hfx_mpi.h). */
#include <stdlib.h>
#include <string.h>

#include "internal/hfx_int.h"
#include "hfx_mpi.h"
#include "samples.h"

int hfx_mpi_decomp_build(MPI_Comm comm, const hfx_rows *local, long nsamples, double rcond,
                         int gauge_dims, hfx_decomp *out, hf_mpi_stats *st, glint_err *err)
{
    hf_mpi_stats own;
    int n = local->n, nr = 0, rank, rc = 0, *idx = NULL, *hit = NULL;
    long smooth = local->nsmooth, rows;
    double t_start = MPI_Wtime(), t0, *G = NULL, *w = NULL, *V = NULL;

    if (!st)
        st = &own;
    memset(st, 0, sizeof *st);
    memset(out, 0, sizeof *out);
    MPI_Comm_rank(comm, &rank);
    if (nsamples < 1 || nsamples > SAMPLES_MAX)
        rc = glint_err_set(err, GLINT_ERANGE, "%ld samples outside 1..%d", nsamples,
                           SAMPLES_MAX);
    else if (!(rcond > 0.0) || !(rcond < 1.0))
        rc = glint_err_set(err, GLINT_ERANGE, "rcond %g must be in (0, 1)", rcond);
    else if (!(idx = malloc((size_t)n * sizeof *idx)) || !(hit = malloc((size_t)n * sizeof *hit)))
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto done;

    /* the unknowns any rank's rows reach, numbered as hfx.c numbers them */
    hfx_reached(local, idx);
    for (int t = 0; t < n; t++)
        hit[t] = idx[t] == 0;
    MPI_Allreduce(MPI_IN_PLACE, hit, n, MPI_INT, MPI_MAX, comm);
    for (int t = 0; t < n; t++)
        idx[t] = hit[t] ? 0 : -1;
    nr = hfx_number_reached(idx, n);
    MPI_Allreduce(MPI_IN_PLACE, &smooth, 1, MPI_LONG, MPI_SUM, comm);
    rows = nsamples + smooth;
    if (nr < 1)
        rc = glint_err_set(err, GLINT_EINVAL, "no row reaches any unknown");
    else if (rows < nr)
        rc = glint_err_set(err, GLINT_EUNSUPPORTED,
                           "B has %ld rows for %d reached unknowns: the single-process route "
                           "takes the dense form there, which is not distributed (use glint "
                           "fit)", rows, nr);
    else if (nsamples < nr)
        rc = glint_err_set(err, GLINT_EUNSUPPORTED,
                           "%ld samples for %d reached unknowns: the single-process route may "
                           "take the kernel form there, which is not distributed (use glint "
                           "fit)", nsamples, nr);
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto done;

    G = calloc((size_t)nr * nr, sizeof *G);
    w = malloc((size_t)nr * sizeof *w);
    if (!G || !w)
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d normal matrix", nr, nr);
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto done;
    t0 = MPI_Wtime();
    hfx_normal_add(local, idx, nr, G);
    st->t_gram = MPI_Wtime() - t0;
    rc = hf_mpi_eig_sum(comm, nr, G, NULL, w, &V, st, err);
    free(G);
    G = NULL;
    if (rc)
        goto done;

    t0 = MPI_Wtime();
    if (rank == 0) {
        out->n = n;
        out->nsamples = (int)nsamples;
        out->rows = (int)rows;
        out->form = "normal";
        out->rcond = hfx_normal_rcond(rcond, nr);
        out->gauge_dims = gauge_dims;
        out->unreached = n - nr;
        rc = hfx_decomp_from_eig(w, V, nr, out->rcond, out, err);
        if (!rc)
            rc = hfx_decomp_finish(out, idx, nr, err);
    }
    st->t_gain = MPI_Wtime() - t0;
    rc = hf_mpi_agree(comm, rc, err);
    if (!rc && rank == 0)
        out->seconds = MPI_Wtime() - t_start;
done:
    if (rc || rank != 0) {
        hfx_decomp_free(out);
        memset(out, 0, sizeof *out);
    }
    free(idx);
    free(hit);
    free(G);
    free(w);
    free(V);
    return rc;
}
