/* hf_mpi.c: hf3's eig-route decomposition over MPI ranks with ScaLAPACK
 * (hf_mpi.h says what each rank does).  Layout conventions: every matrix
 * is column-major; a global entry (i, j) of the n x n block-cyclic matrix
 * lives on grid process ((i / NB) mod P_r, (j / NB) mod P_c) at local
 * (i / (NB P_r)) NB + i mod NB, likewise for j, with leading dimension
 * max(1, local rows). */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal/hf_int.h"
#include "hf_mpi.h"

/* ScaLAPACK and BLACS (Debian's libscalapack-openmpi ships no header).
 * The trailing size_t arguments are gfortran's hidden lengths of the
 * character arguments. */
extern int Csys2blacs_handle(MPI_Comm comm);
extern void Cfree_blacs_system_handle(int handle);
extern void Cblacs_gridinit(int *ctxt, const char *order, int nprow, int npcol);
extern void Cblacs_gridinfo(int ctxt, int *nprow, int *npcol, int *myrow, int *mycol);
extern void Cblacs_gridexit(int ctxt);
extern int numroc_(const int *n, const int *nb, const int *iproc, const int *isrc,
                   const int *nprocs);
extern void descinit_(int *desc, const int *m, const int *n, const int *mb, const int *nb,
                      const int *irsrc, const int *icsrc, const int *ctxt, const int *lld,
                      int *info);
extern void pdsyevd_(const char *jobz, const char *uplo, const int *n, double *a,
                     const int *ia, const int *ja, const int *desca, double *w, double *z,
                     const int *iz, const int *jz, const int *descz, double *work,
                     const int *lwork, int *iwork, const int *liwork, int *info, size_t ljobz,
                     size_t luplo);

int hf_mpi_agree(MPI_Comm comm, int rc, glint_err *err)
{
    struct {
        int code;
        char msg[GLINT_ERR_MSG_MAX];
    } m;
    int rank, nprocs, mine, lowest;

    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &nprocs);
    mine = rc ? rank : nprocs;
    MPI_Allreduce(&mine, &lowest, 1, MPI_INT, MPI_MIN, comm);
    if (lowest == nprocs)
        return 0;
    memset(&m, 0, sizeof m);
    if (rank == lowest) {
        m.code = rc;
        snprintf(m.msg, sizeof m.msg, "%s", err->code == rc ? err->msg : "failed");
    }
    MPI_Bcast(&m, (int)sizeof m, MPI_BYTE, lowest, comm);
    if (lowest > 0 && strncmp(m.msg, "rank ", 5) != 0)
        return glint_err_set(err, m.code, "rank %d: %s", lowest, m.msg);
    return glint_err_set(err, m.code, "%s", m.msg);
}

/* P_r x P_c = P with P_r the largest divisor of P at most sqrt(P). */
static void grid_shape(int nprocs, int *nprow, int *npcol)
{
    int r = (int)sqrt((double)nprocs);
    while (r > 1 && nprocs % r)
        r--;
    *nprow = r < 1 ? 1 : r;
    *npcol = nprocs / *nprow;
}

/* Global index of local index l on process coordinate p of np. */
static int l2g(int l, int nb, int p, int np)
{
    return (l / nb) * nb * np + p * nb + l % nb;
}

/* The grid and where every rank sits on it. */
typedef struct grid {
    int ctxt, handle;
    int nprocs, rank, nprow, npcol, myrow, mycol;
    int *coord;          /* 2 per rank: row, column */
    int n, nb, mloc, nloc, lld;
} grid;

static int local_rows(const grid *g, int q)
{
    return numroc_(&g->n, &g->nb, &g->coord[2 * q], (const int[]){0}, &g->nprow);
}

static int local_cols(const grid *g, int q)
{
    return numroc_(&g->n, &g->nb, &g->coord[2 * q + 1], (const int[]){0}, &g->npcol);
}

/* The full n x n matrix `full` and every rank's local block-cyclic array
 * laid one after another, rank by rank (`packed`): to_packed copies full
 * into packed (and sets counts[P], the local arrays' sizes), otherwise
 * packed into full (full is only read when to_packed). */
static void block_cyclic_copy(const grid *g, double *full, double *packed, int to_packed,
                              int *counts)
{
    size_t off = 0;
    int n = g->n;

    for (int q = 0; q < g->nprocs; q++) {
        int mq = local_rows(g, q), nq = local_cols(g, q);
        int pr = g->coord[2 * q], pc = g->coord[2 * q + 1];
        for (int lj = 0; lj < nq; lj++) {
            int j = l2g(lj, g->nb, pc, g->npcol);
            for (int li = 0; li < mq; li++) {
                double *a = &full[l2g(li, g->nb, pr, g->nprow) + (size_t)n * j];
                double *b = &packed[off + li + (size_t)mq * lj];
                if (to_packed)
                    *b = *a;
                else
                    *a = *b;
            }
        }
        if (counts)
            counts[q] = mq * nq;
        off += (size_t)mq * nq;
    }
}

/* The data norms rank 0 collected: sqrt of the summed parts of the
 * candidate columns idx[0..k-1]. */
typedef struct gains {
    int k, missing;
    const int *idx;
    const double *sum2;
} gains;

static double gathered_norm(void *cls, int col, const double *v)
{
    gains *g = cls;
    (void)v;
    for (int a = 0; a < g->k; a++)
        if (g->idx[a] == col)
            return sqrt(g->sum2[a]);
    g->missing = 1; /* cannot happen: every direction below 1 is a candidate */
    return INFINITY;
}

/* Steps 4-5 (hf_mpi.h): ||A v|| of the directions below 1 over every
 * rank's rows, then the keep rules on rank 0.  w replicated; V on rank 0. */
static int gains_and_keep(MPI_Comm comm, const hf_design *local, const double *w,
                          const double *V, const double *Z, hf_decomp *dc, hf_mpi_stats *st,
                          glint_err *err)
{
    int n = 3 * local->res, k = 0, rc = 0, rank;
    int *idx = malloc((size_t)n * sizeof *idx);
    double *cols = NULL, *part = NULL, *sum2 = NULL;

    MPI_Comm_rank(comm, &rank);
    if (rank == 0 && idx)
        for (int i = 0; i < n; i++)
            if (sqrt(w[i] > 0.0 ? w[i] : 0.0) < 1.0)
                idx[k++] = i;
    MPI_Bcast(&k, 1, MPI_INT, 0, comm);
    cols = malloc((size_t)n * (k ? k : 1) * sizeof *cols);
    part = calloc((size_t)(k ? k : 1), sizeof *part);
    sum2 = calloc((size_t)(k ? k : 1), sizeof *sum2);
    if (!idx || !cols || !part || !sum2)
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for %d directions' data norms", k);
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto done;
    if (rank == 0)
        for (int a = 0; a < k; a++)
            memcpy(cols + (size_t)n * a, V + (size_t)n * idx[a], (size_t)n * sizeof *cols);
    MPI_Bcast(idx, k, MPI_INT, 0, comm);
    MPI_Bcast(cols, n * k, MPI_DOUBLE, 0, comm);
    for (int a = 0; a < k; a++)
        part[a] = local->n > 0 ? hf_data_norm2_part(local, cols + (size_t)n * a) : 0.0;
    MPI_Reduce(part, sum2, k, MPI_DOUBLE, MPI_SUM, 0, comm);
    if (st)
        st->gain_dirs = k;
    if (rank == 0) {
        gains gs = {k, 0, idx, sum2};
        rc = hf_decomp_from_eig(dc, w, V, Z, gathered_norm, &gs, err);
        if (rc == 0 && gs.missing)
            rc = glint_err_set(err, GLINT_EINTERNAL,
                               "a direction's data norm was asked for but not collected");
    }
    rc = hf_mpi_agree(comm, rc, err);
done:
    free(idx);
    free(cols);
    free(part);
    free(sum2);
    return rc;
}

static void grid_close(grid *g)
{
    if (g->ctxt >= 0)
        Cblacs_gridexit(g->ctxt);
    if (g->handle >= 0)
        Cfree_blacs_system_handle(g->handle);
    free(g->coord);
    g->ctxt = g->handle = -1;
    g->coord = NULL;
}

static int grid_open(MPI_Comm comm, int n, grid *g, glint_err *err)
{
    int rc = 0, mine[2];

    memset(g, 0, sizeof *g);
    g->ctxt = g->handle = -1;
    MPI_Comm_rank(comm, &g->rank);
    MPI_Comm_size(comm, &g->nprocs);
    grid_shape(g->nprocs, &g->nprow, &g->npcol);
    g->n = n;
    g->nb = HF_MPI_NB;
    g->handle = Csys2blacs_handle(comm);
    g->ctxt = g->handle;
    Cblacs_gridinit(&g->ctxt, "Row", g->nprow, g->npcol);
    Cblacs_gridinfo(g->ctxt, &g->nprow, &g->npcol, &g->myrow, &g->mycol);
    if (g->myrow < 0 || g->mycol < 0)
        rc = glint_err_set(err, GLINT_EINTERNAL, "rank %d is not on the %dx%d process grid",
                           g->rank, g->nprow, g->npcol);
    g->coord = malloc((size_t)2 * g->nprocs * sizeof *g->coord);
    if (!rc && !g->coord)
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = hf_mpi_agree(comm, rc, err)))
        return rc;
    mine[0] = g->myrow;
    mine[1] = g->mycol;
    MPI_Allgather(mine, 2, MPI_INT, g->coord, 2, MPI_INT, comm);
    g->mloc = local_rows(g, g->rank);
    g->nloc = local_cols(g, g->rank);
    g->lld = g->mloc > 1 ? g->mloc : 1;
    return 0;
}

/* The reduce-scatter of every rank's G, the gauge shift along Z (if given)
 * and pdsyevd.  OUT: loc (the sum, destroyed), zloc (eigenvectors,
 * local), w (on every rank: rank 0's). */
static int reduce_and_solve(const grid *gr, MPI_Comm comm, const double *G, const double *Z,
                            double *loc, double *zloc, double *w, hf_mpi_stats *st,
                            glint_err *err)
{
    int n = gr->n, rc = 0, info = 0, desc[9], lwork = -1, liwork = -1, one = 1, izero = 0;
    double *send = malloc((size_t)n * n * sizeof *send);
    double *colsum = calloc((size_t)n, sizeof *colsum), *work = NULL, wq = 0.0, sigma, t0;
    int *counts = malloc((size_t)gr->nprocs * sizeof *counts), *iwork = NULL, iwq = 0;

    if (!send || !colsum || !counts)
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d matrix", n, n);
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto done;
    block_cyclic_copy(gr, (double *)G, send, 1, counts);
    t0 = MPI_Wtime();
    MPI_Barrier(comm); /* the wait for the slowest share, timed apart */
    st->t_wait = MPI_Wtime() - t0;
    t0 = MPI_Wtime();
    MPI_Reduce_scatter(send, loc, counts, MPI_DOUBLE, MPI_SUM, comm);
    st->t_reduce = MPI_Wtime() - t0;
    free(send);
    send = NULL;

    t0 = MPI_Wtime();
    for (int lj = 0; Z && lj < gr->nloc; lj++) {
        int j = l2g(lj, gr->nb, gr->mycol, gr->npcol);
        for (int li = 0; li < gr->mloc; li++)
            colsum[j] += fabs(loc[li + (size_t)gr->lld * lj]);
    }
    if (Z)
        MPI_Allreduce(MPI_IN_PLACE, colsum, n, MPI_DOUBLE, MPI_SUM, comm);
    sigma = hf_gauge_shift(colsum, n);
    for (int lj = 0; Z && lj < gr->nloc; lj++) {
        int j = l2g(lj, gr->nb, gr->mycol, gr->npcol);
        for (int li = 0; li < gr->mloc; li++) {
            int i = l2g(li, gr->nb, gr->myrow, gr->nprow);
            loc[li + (size_t)gr->lld * lj] += sigma * (Z[i] * Z[j] + Z[n + i] * Z[n + j]);
        }
    }
    descinit_(desc, &n, &n, &gr->nb, &gr->nb, &izero, &izero, &gr->ctxt, &gr->lld, &info);
    if (info == 0)
        pdsyevd_("V", "U", &n, loc, &one, &one, desc, w, zloc, &one, &one, desc, &wq, &lwork,
                 &iwq, &liwork, &info, 1, 1);
    if (info != 0) {
        rc = glint_err_set(err, GLINT_ENUMERIC, "ScaLAPACK set-up failed (info %d) for n = %d",
                           info, n);
    } else {
        /* The query returns the documented minimum, which under-states what
         * two routines pdsyevd calls need on grids with more than one
         * process (ScaLAPACK 2.2): PDLASRT max(N, NP (NB + NQ)) and PDORMTR
         * max(NB (NB - 1) / 2, (NP + NQ) NB) + NB^2, each of the workspace
         * after pdsyevd's first 2 N; they reject less.  Take the largest. */
        double np = gr->mloc, nq = gr->nloc, nb = gr->nb;
        double doc = 1.0 + 6.0 * n + 2.0 * np * nq;
        double tri = 3.0 * n + (nb * (np + 1.0) > 3.0 * nb ? nb * (np + 1.0) : 3.0 * nb);
        double need = (doc > tri ? doc : tri) + 2.0 * n;
        double srt = (np * (nb + nq) > n ? np * (nb + nq) : n) + 2.0 * n;
        double orm = ((np + nq) * nb > nb * (nb - 1.0) / 2.0 ? (np + nq) * nb
                                                             : nb * (nb - 1.0) / 2.0) +
                     nb * nb + 2.0 * n;
        if (srt > need)
            need = srt;
        if (orm > need)
            need = orm;
        if (wq > need)
            need = wq;
        if (need > (double)INT_MAX - 1.0)
            rc = glint_err_set(err, GLINT_ERANGE, "pdsyevd's workspace (%.0f doubles) "
                               "exceeds a Fortran integer", need);
        lwork = rc ? 1 : (int)need + 1;
        /* pdsyevd's query can under-state LIWORK (PDLASRT then rejects it):
         * its documented minimum is 7 N + 8 NPCOL + 2 */
        liwork = 7 * n + 8 * gr->npcol + 2;
        if (iwq > liwork)
            liwork = iwq;
        work = malloc((size_t)lwork * sizeof *work);
        iwork = malloc((size_t)liwork * sizeof *iwork);
        if (!rc && (!work || !iwork))
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for pdsyevd's workspace "
                               "(%d doubles)", lwork);
        st->bytes_work = (double)lwork * sizeof *work + (double)liwork * sizeof *iwork;
    }
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto done;
    pdsyevd_("V", "U", &n, loc, &one, &one, desc, w, zloc, &one, &one, desc, work, &lwork,
             iwork, &liwork, &info, 1, 1);
    if (info != 0)
        rc = glint_err_set(err, GLINT_ENUMERIC, "pdsyevd failed (info %d) for n = %d on a "
                           "%dx%d grid", info, n, gr->nprow, gr->npcol);
    rc = hf_mpi_agree(comm, rc, err);
    /* every rank uses rank 0's eigenvalues (the keep rules run there) */
    MPI_Bcast(w, n, MPI_DOUBLE, 0, comm);
    st->t_eig = MPI_Wtime() - t0;
done:
    free(send);
    free(colsum);
    free(counts);
    free(work);
    free(iwork);
    return rc;
}

int hf_mpi_eig_sum(MPI_Comm comm, int n, const double *G, const double *Z, double *w,
                   double **V, hf_mpi_stats *st, glint_err *err)
{
    grid gr = {.ctxt = -1, .handle = -1};
    double t0, *loc = NULL, *zloc = NULL, *gath = NULL;
    int *counts = NULL, *displs = NULL, rc = 0;
    size_t nloc_elems;

    *V = NULL;
    if (n < 1 || (double)n * n > INT_MAX)
        rc = glint_err_set(err, GLINT_ERANGE, "a %dx%d matrix is beyond the distributed "
                           "eigensolver's int counts", n, n);
    if ((rc = hf_mpi_agree(comm, rc, err)) || (rc = grid_open(comm, n, &gr, err)))
        goto done;
    st->nprocs = gr.nprocs;
    st->nprow = gr.nprow;
    st->npcol = gr.npcol;
    st->nb = gr.nb;
    nloc_elems = (size_t)gr.lld * (gr.nloc > 0 ? gr.nloc : 1);
    loc = malloc(nloc_elems * sizeof *loc);
    zloc = malloc(nloc_elems * sizeof *zloc);
    if (!loc || !zloc)
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the local blocks");
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto done;
    /* the peak: the caller's G and the packed copy with the local blocks
     * (rank 0 later holds the gathered copy and V instead: no more) */
    st->bytes_local = (double)2 * n * n * sizeof(double) + 2.0 * nloc_elems * sizeof(double);
    if ((rc = reduce_and_solve(&gr, comm, G, Z, loc, zloc, w, st, err)))
        goto done;
    free(loc);
    loc = NULL;

    t0 = MPI_Wtime();
    if (gr.rank == 0) {
        counts = malloc((size_t)gr.nprocs * sizeof *counts);
        displs = malloc((size_t)gr.nprocs * sizeof *displs);
        gath = malloc((size_t)n * n * sizeof *gath);
        *V = malloc((size_t)n * n * sizeof **V);
        if (!counts || !displs || !gath || !*V) {
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory gathering %dx%d eigenvectors",
                               n, n);
        } else {
            for (int q = 0, off = 0; q < gr.nprocs; q++) {
                counts[q] = local_rows(&gr, q) * local_cols(&gr, q);
                displs[q] = off;
                off += counts[q];
            }
        }
    }
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto done;
    MPI_Gatherv(zloc, gr.mloc * gr.nloc, MPI_DOUBLE, gath, counts, displs, MPI_DOUBLE, 0, comm);
    if (gr.rank == 0)
        block_cyclic_copy(&gr, *V, gath, 0, NULL);
    st->t_gather = MPI_Wtime() - t0;
done:
    if (rc) {
        free(*V);
        *V = NULL;
    }
    grid_close(&gr);
    free(loc);
    free(zloc);
    free(gath);
    free(counts);
    free(displs);
    return rc;
}

int hf_mpi_decomp_build(MPI_Comm comm, const hf_design *local, long nsamples, double lambda,
                        double rcond, hf_decomp *out, hf_mpi_stats *st, glint_err *err)
{
    hf_mpi_stats own;
    double t_start = MPI_Wtime(), t0, *G = NULL, *w = NULL, *Z = NULL, *V = NULL;
    int rc = 0, n, rank;

    if (!st)
        st = &own;
    memset(st, 0, sizeof *st);
    memset(out, 0, sizeof *out);
    MPI_Comm_rank(comm, &rank);
    if (nsamples < 1 || nsamples > SAMPLES_MAX)
        rc = glint_err_set(err, GLINT_ERANGE, "%ld samples outside 1..%d", nsamples,
                           SAMPLES_MAX);
    else
        rc = hf_decomp_begin(local->res, (int)nsamples, lambda, HF_ROUTE_EIG, rcond, out, err);
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto fail;
    n = out->n;
    G = malloc((size_t)n * n * sizeof *G);
    w = malloc((size_t)n * sizeof *w);
    Z = malloc((size_t)2 * n * sizeof *Z);
    if (!G || !w || !Z)
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d normal matrix", n, n);
    if ((rc = hf_mpi_agree(comm, rc, err)))
        goto fail;
    hf_gauge_vectors(local->res, Z);
    t0 = MPI_Wtime();
    hf_normal_matrix(local, rank == 0 ? out->lambda : 0.0, G); /* 0 rows: lambda^2 L^T L or 0 */
    st->t_gram = MPI_Wtime() - t0;
    rc = hf_mpi_eig_sum(comm, n, G, Z, w, &V, st, err);
    free(G);
    G = NULL;
    if (rc)
        goto fail;
    t0 = MPI_Wtime();
    rc = gains_and_keep(comm, local, w, V, Z, out, st, err);
    st->t_gain = MPI_Wtime() - t0;
    if (rc)
        goto fail;
    out->build_seconds = MPI_Wtime() - t_start;
    if (rank != 0)
        memset(out, 0, sizeof *out);
    goto done;
fail:
    hf_decomp_free(out);
done:
    free(G);
    free(w);
    free(Z);
    free(V);
    return rc;
}
