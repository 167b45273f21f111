/* hf_decomp.c: decomposition of B = [A; lambda L] into singular values and
 * right singular vectors, on the complement of the gauge directions.
 *
 * Gauge: both routes add sigma z z^T for the two known null directions z
 * (eig route: to B^T B; SVD route: as two extra rows sqrt(sigma) z^T of B),
 * with sigma larger than any other eigenvalue.  Because B z = 0 exactly, the
 * z become the top two singular directions with a clean gap; they are
 * identified (|Z^T v| ~ 1 is checked), dropped and reported.  What remains
 * is B restricted to the gauge complement: its own rank deficiency (e.g.
 * texels reached by no sample when lambda = 0) is decided by rcond, and the
 * directions the samples barely reach by their data gain (hf.h). */
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal/hf_int.h"

double hf_rcond_default(hf_route route)
{
    /* Both routes apply the operator as M A^T f with M = V diag(c/s) V^T:
     * rounding in A^T f (relative eps) reaches component i amplified by
     * (s_max / s_i)^2.  Directions below 1e-6 s_max would turn that into
     * more than 2e-4 of noise, so they count as rank deficiency.  The eig
     * route also cannot resolve them: eigenvalues of B^T B carry errors of
     * about n eps s_max^2, i.e. singular values below ~2e-7 s_max are noise.
     * (The reference's smallest kept values sit between 3e-2 and 7e-5 s_max
     * for lambda >= 0.01: nothing a useful fit needs is cut.) */
    (void)route;
    return 1e-6;
}

double hf_data_norm2_part(const hf_design *d, const double *v)
{
    int R = d->res;
    double a2 = 0.0;

    for (int i = 0; i < d->n; i++) {
        double r = 0.0;
        for (int j = 0; j < 3; j++) {
            const double *vk = v + j * R + d->k0[3 * i + j];
            double t = d->t[3 * i + j];
            r += (1.0 - t) * vk[0] + t * vk[1];
        }
        a2 += r * r;
    }
    return a2;
}

/* ||A v||: the data rows' part of ||B v||, one pass over the samples
 * (hf_data_norm_fn for a design held whole). */
static double data_norm(void *cls, int col, const double *v)
{
    (void)col;
    return sqrt(hf_data_norm2_part(cls, v));
}

/* The keep rules (hf_int.h): gauge, null (rcond) and barely reached
 * (data gain) directions out, the others kept in descending order. */
int hf_decomp_keep(hf_decomp *dc, const double *vals, const double *vecs, int m,
                   const int *order, const double *Z, hf_data_norm_fn norm, void *cls,
                   glint_err *err)
{
    double rcond = dc->rcond;
    int n = dc->n, ngauge = 0, kept = 0, exact = 0;
    double smax = -1.0;
    int *keep = malloc((size_t)m * sizeof *keep);

    if (!keep)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory in the decomposition");
    for (int a = 0; a < m; a++) {
        int i = order[a];
        const double *v = vecs + (size_t)n * i;
        double p1 = 0.0, p2 = 0.0;
        for (int r = 0; r < n; r++) {
            p1 += Z[r] * v[r];
            p2 += Z[n + r] * v[r];
        }
        if (a < 2) {
            /* The deflated gauge directions must be the top two. */
            if (p1 * p1 + p2 * p2 < 1.0 - 1e-6) {
                free(keep);
                return glint_err_set(err, GLINT_ENUMERIC,
                                     "gauge deflation failed: top direction %d lies %.3g "
                                     "inside the gauge space (expected 1)",
                                     a, p1 * p1 + p2 * p2);
            }
            ngauge++;
            continue;
        }
        if (smax < 0.0) {
            smax = vals[i];
            dc->s_null = rcond * smax;
        }
        if (!(vals[i] > dc->s_null && vals[i] > 0.0)) {
            dc->null_dims++;
            continue;
        }
        if (vals[i] < 1.0) {
            /* gain = ||A v|| / s^2 <= 1 / s: only here can it exceed 1 */
            double gain = norm(cls, i, v) / (vals[i] * vals[i]);
            if (gain > dc->gain_max) {
                dc->weak_dims++;
                if (vals[i] > dc->s_weak)
                    dc->s_weak = vals[i];
                continue;
            }
            if (!exact || gain > dc->gain_kept)
                dc->gain_kept = gain;
            exact = 1;
        }
        keep[kept++] = i;
    }
    if (kept > 0 && !exact)
        dc->gain_kept = 1.0 / vals[keep[kept - 1]]; /* every s_i >= 1: a bound, <= 1 */
    dc->gauge_dims = ngauge;
    dc->rank = kept;
    dc->s = malloc((size_t)(kept ? kept : 1) * sizeof *dc->s);
    dc->V = malloc((size_t)n * (kept ? kept : 1) * sizeof *dc->V);
    if (!dc->s || !dc->V) {
        free(keep);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory in the decomposition");
    }
    for (int k = 0; k < kept; k++) {
        dc->s[k] = vals[keep[k]];
        memcpy(dc->V + (size_t)n * k, vecs + (size_t)n * keep[k], (size_t)n * sizeof(double));
    }
    free(keep);
    if (kept == 0)
        return glint_err_set(err, GLINT_ENUMERIC,
                             "the constraint matrix has rank 0 (%d null, %d barely reached "
                             "directions)", dc->null_dims, dc->weak_dims);
    return 0;
}

double hf_gauge_shift(const double *colsum, int n)
{
    double m = 0.0;
    for (int c = 0; c < n; c++)
        if (colsum[c] > m)
            m = colsum[c];
    return 2.0 * m + 1.0;
}

int hf_decomp_from_eig(hf_decomp *dc, const double *w, const double *vecs, const double *Z,
                       hf_data_norm_fn norm, void *cls, glint_err *err)
{
    int n = dc->n, rc;
    double *sv = malloc((size_t)n * sizeof *sv);
    int *order = malloc((size_t)n * sizeof *order);

    if (!sv || !order) {
        free(sv);
        free(order);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory in the decomposition");
    }
    /* Ascending eigenvalues: descending order is reverse. */
    for (int i = 0; i < n; i++) {
        sv[i] = sqrt(w[i] > 0.0 ? w[i] : 0.0);
        order[i] = n - 1 - i;
    }
    rc = hf_decomp_keep(dc, sv, vecs, n, order, Z, norm, cls, err);
    free(sv);
    free(order);
    return rc;
}

static int build_eig(const hf_design *d, hf_decomp *dc, const double *Z, glint_err *err)
{
    int n = dc->n, rc;
    lapack_int info;
    double *G = malloc((size_t)n * n * sizeof *G);
    double *w = malloc((size_t)n * sizeof *w);
    double *sv = malloc((size_t)n * sizeof *sv);
    double sigma;

    if (!G || !w || !sv) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d normal matrix", n, n);
        goto done;
    }
    hf_normal_matrix(d, dc->lambda, G);
    /* sigma above every eigenvalue: twice the largest absolute column sum. */
    for (int c = 0; c < n; c++) {
        double sum = 0.0;
        for (int r = 0; r < n; r++)
            sum += fabs(G[r + (size_t)n * c]);
        sv[c] = sum;
    }
    sigma = hf_gauge_shift(sv, n);
    for (int c = 0; c < n; c++)
        for (int r = 0; r < n; r++)
            G[r + (size_t)n * c] += sigma * (Z[r] * Z[c] + Z[n + r] * Z[n + c]);

    info = LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'U', n, G, n, w);
    if (info != 0) {
        rc = glint_err_set(err, GLINT_ENUMERIC, "LAPACKE_dsyevd failed (info %d) for n = %d",
                           (int)info, n);
        goto done;
    }
    rc = hf_decomp_from_eig(dc, w, G, Z, data_norm, (void *)d, err);
done:
    free(G);
    free(w);
    free(sv);
    return rc;
}

static int build_svd(const hf_design *d, hf_decomp *dc, const double *Z, glint_err *err)
{
    int n = dc->n, rows = 0, ldb = 0, rc, m;
    lapack_int info;
    double *B = NULL, *B2 = NULL, *s = NULL, *vt = NULL, *vecs = NULL;
    int *order = NULL;
    double fro = 0.0, root;

    B = hf_dense_B(d, dc->lambda, &rows, &ldb);
    if (!B)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the dense constraint matrix");
    /* Zero rows below, so that m >= n: dgesdd with jobz 'O' and m < n would
     * leave V^T in B2 (its first m rows) and need U elsewhere; zero rows
     * change neither the singular values nor V. */
    m = rows + 2 > n ? rows + 2 : n;
    B2 = calloc((size_t)m * n, sizeof *B2);
    s = malloc((size_t)n * sizeof *s);
    vt = malloc((size_t)n * n * sizeof *vt);
    vecs = malloc((size_t)n * n * sizeof *vecs);
    order = malloc((size_t)n * sizeof *order);
    if (!B2 || !s || !vt || !vecs || !order) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d SVD", m, n);
        goto done;
    }
    for (int c = 0; c < n; c++) {
        for (int r = 0; r < rows; r++) {
            double v = B[r + (size_t)ldb * c];
            B2[r + (size_t)m * c] = v;
            fro += v * v;
        }
    }
    root = sqrt(2.0 * fro) + 1.0; /* above ||B||_2 */
    for (int c = 0; c < n; c++) {
        B2[rows + (size_t)m * c] = root * Z[c];
        B2[rows + 1 + (size_t)m * c] = root * Z[n + c];
    }
    /* jobz 'O': U overwrites B2, V^T goes to vt; no m x n copy of U. */
    info = LAPACKE_dgesdd(LAPACK_COL_MAJOR, 'O', m, n, B2, m, s, NULL, m, vt, n);
    if (info != 0) {
        rc = glint_err_set(err, GLINT_ENUMERIC, "LAPACKE_dgesdd failed (info %d) for %dx%d",
                           (int)info, m, n);
        goto done;
    }
    for (int k = 0; k < n; k++) {
        for (int r = 0; r < n; r++)
            vecs[r + (size_t)n * k] = vt[k + (size_t)n * r];
        order[k] = k;
    }
    rc = hf_decomp_keep(dc, s, vecs, n, order, Z, data_norm, (void *)d, err);
done:
    free(B);
    free(B2);
    free(s);
    free(vt);
    free(vecs);
    free(order);
    return rc;
}

int hf_decomp_begin(int res, int nsamples, double lambda, hf_route route, double rcond,
                    hf_decomp *out, glint_err *err)
{
    memset(out, 0, sizeof *out);
    if (nsamples < 1 || res < HF_RES_MIN || res > HF_RES_MAX)
        return glint_err_set(err, GLINT_EINVAL, "decomposition needs a non-empty design");
    if (!isfinite(lambda) || lambda < 0.0 || lambda > HF_LAMBDA_MAX)
        return glint_err_set(err, GLINT_ERANGE, "lambda %g outside [0, %g]", lambda,
                             HF_LAMBDA_MAX);
    if (route != HF_ROUTE_EIG && route != HF_ROUTE_SVD)
        return glint_err_set(err, GLINT_EINVAL, "unknown decomposition route %d", (int)route);
    if (!(rcond > 0.0))
        rcond = hf_rcond_default(route);
    if (!isfinite(rcond) || rcond >= 1.0)
        return glint_err_set(err, GLINT_ERANGE, "rcond %g outside (0, 1)", rcond);
    out->res = res;
    out->n = 3 * res;
    out->nsamples = nsamples;
    out->lambda = lambda;
    out->route = route;
    out->rcond = rcond;
    out->gain_max = HF_GAIN_MAX;
    return 0;
}

int hf_decomp_build(const hf_design *d, double lambda, hf_route route,
                    double rcond, hf_decomp *out, glint_err *err)
{
    double t0 = hf_now(), *Z = NULL;
    int rc;

    memset(out, 0, sizeof *out);
    if (!d)
        return glint_err_set(err, GLINT_EINVAL, "decomposition needs a non-empty design");
    if ((rc = hf_decomp_begin(d->res, d->n, lambda, route, rcond, out, err)))
        return rc;
    Z = malloc((size_t)2 * out->n * sizeof *Z);
    if (!Z)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    hf_gauge_vectors(d->res, Z);
    rc = route == HF_ROUTE_EIG ? build_eig(d, out, Z, err) : build_svd(d, out, Z, err);
    free(Z);
    if (rc != 0) {
        hf_decomp_free(out);
        return rc;
    }
    out->build_seconds = hf_now() - t0;
    return 0;
}

void hf_decomp_free(hf_decomp *dc)
{
    if (!dc)
        return;
    free(dc->s);
    free(dc->V);
    memset(dc, 0, sizeof *dc);
}
