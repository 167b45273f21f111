/* hf4.c: the four-factor product (hf4.h). */
#include "hf4.h"

#include <cblas.h>
#include <float.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"

#define COS_FLOOR 1e-6 /* as hf_fit's BRDF model */
#define ROW_MAX 10     /* nonzeros of a data row: 2 per 1D factor, 4 for s */

void hf4_design_free(hf4_design *d)
{
    if (!d)
        return;
    hf_design_free(&d->d);
    free(d->ij);
    free(d->txy);
    memset(d, 0, sizeof *d);
}

int hf4_design_build(const samples *s, int res, int sres, hf4_design *out, glint_err *err)
{
    int rc;
    memset(out, 0, sizeof *out);
    if (sres < HF4_SRES_MIN || sres > HF4_SRES_MAX)
        return glint_err_set(err, GLINT_ERANGE, "spatial factor resolution %d outside %d..%d",
                             sres, HF4_SRES_MIN, HF4_SRES_MAX);
    if (!s->has_pos || !s->uv)
        return glint_err_set(err, GLINT_EINVAL,
                             "the four-factor product needs the samples' texture coordinates "
                             "(imported samples have none): paint a scene's views");
    if ((rc = hf_design_build(s, res, &out->d, err)))
        return rc;
    out->sres = sres;
    out->ij = malloc(2 * (size_t)s->n * sizeof *out->ij);
    out->txy = malloc(2 * (size_t)s->n * sizeof *out->txy);
    if (!out->ij || !out->txy) {
        hf4_design_free(out);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d samples", s->n);
    }
    for (int i = 0; i < s->n; i++)
        for (int a = 0; a < 2; a++) {
            int k;
            double t;
            hf_hat(s->uv[2 * (size_t)i + a], sres, &k, &t);
            out->ij[2 * (size_t)i + a] = k;
            out->txy[2 * (size_t)i + a] = t;
        }
    return 0;
}

/* Data row i of A: its nonzeros (OUT: col, w; returns their count). */
static int data_row(const hf4_design *x, int i, int *col, double *w)
{
    int R = x->d.res, S = x->sres, m = 0, base = 3 * R;
    int i0 = x->ij[2 * (size_t)i], j0 = x->ij[2 * (size_t)i + 1];
    double tx = x->txy[2 * (size_t)i], ty = x->txy[2 * (size_t)i + 1];
    for (int j = 0; j < 3; j++) {
        int c = j * R + x->d.k0[3 * (size_t)i + j];
        double t = x->d.t[3 * (size_t)i + j];
        col[m] = c;
        w[m++] = 1.0 - t;
        col[m] = c + 1;
        w[m++] = t;
    }
    col[m] = base + j0 * S + i0;
    w[m++] = (1.0 - tx) * (1.0 - ty);
    col[m] = base + j0 * S + i0 + 1;
    w[m++] = tx * (1.0 - ty);
    col[m] = base + (j0 + 1) * S + i0;
    w[m++] = (1.0 - tx) * ty;
    col[m] = base + (j0 + 1) * S + i0 + 1;
    w[m++] = tx * ty;
    return m;
}

/* Smoothing rows: those of p, q, r when lambda > 0, those of s when
 * lambda_s > 0 (a zero weight adds no row). */
static int rows_1d(int R, double lambda)
{
    return lambda > 0.0 ? 3 * (R - 2) : 0;
}

static int smooth_rows(int R, int S, double lambda, double lambda_s)
{
    return rows_1d(R, lambda) + (lambda_s > 0.0 ? S * S : 0);
}

/* Smoothing row r (0 <= r < smooth_rows): its nonzeros, weights included. */
static int smooth_row(int R, int S, double lambda, double lambda_s, int r, int *col, double *w)
{
    if (r < rows_1d(R, lambda)) {
        int j = r / (R - 2), k = r % (R - 2);
        col[0] = j * R + k;
        col[1] = j * R + k + 1;
        col[2] = j * R + k + 2;
        w[0] = lambda;
        w[1] = -2.0 * lambda;
        w[2] = lambda;
        return 3;
    }
    r -= rows_1d(R, lambda);
    { /* the graph Laplacian at node (i, j): its neighbours on the grid */
        int i = r % S, j = r / S, base = 3 * R, m = 1;
        col[0] = base + j * S + i;
        if (i > 0)
            col[m++] = base + j * S + i - 1;
        if (i + 1 < S)
            col[m++] = base + j * S + i + 1;
        if (j > 0)
            col[m++] = base + (j - 1) * S + i;
        if (j + 1 < S)
            col[m++] = base + (j + 1) * S + i;
        w[0] = -(double)(m - 1) * lambda_s;
        for (int a = 1; a < m; a++)
            w[a] = lambda_s;
        return m;
    }
}

void hf4_decomp_free(hf4_decomp *dc)
{
    if (!dc)
        return;
    free(dc->s2);
    free(dc->V);
    memset(dc, 0, sizeof *dc);
}

static int lambda_ok(double l)
{
    return l >= 0.0 && isfinite(l) && l <= HF_LAMBDA_MAX;
}

/* The kept directions of the normal matrix G (n x n, upper triangle;
 * destroyed). */
static int decomp_normal(double *G, int n, double rcond, hf4_decomp *dc, glint_err *err)
{
    double *e = malloc((size_t)n * sizeof *e), cut;
    int info, rank = 0;
    if (!e)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    info = (int)LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'U', n, G, n, e);
    if (info != 0) {
        free(e);
        return glint_err_set(err, GLINT_ENUMERIC, "eigendecomposition failed (LAPACK info %d)",
                             info);
    }
    dc->s_max = e[n - 1] > 0.0 ? sqrt(e[n - 1]) : 0.0;
    cut = rcond * dc->s_max;
    for (int i = n - 1; i >= 0 && e[i] > cut * cut && e[i] > 0.0; i--)
        rank++;
    dc->s2 = malloc((size_t)(rank ? rank : 1) * sizeof *dc->s2);
    dc->V = malloc((size_t)n * (rank ? rank : 1) * sizeof *dc->V);
    if (!dc->s2 || !dc->V) {
        free(e);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the decomposition");
    }
    for (int k = 0; k < rank; k++) { /* descending */
        int src = n - 1 - k;
        dc->s2[k] = e[src];
        memcpy(dc->V + (size_t)n * k, G + (size_t)n * src, (size_t)n * sizeof *dc->V);
    }
    dc->rank = rank;
    dc->s_min_kept = rank ? sqrt(dc->s2[rank - 1]) : 0.0;
    free(e);
    return 0;
}

/* The kept directions from the SVD of B (rows x n, rows <= n; destroyed). */
static int decomp_dense(double *B, int rows, int n, double rcond, hf4_decomp *dc,
                        glint_err *err)
{
    int m = rows < n ? rows : n, info, rank = 0;
    double *s = malloc((size_t)m * sizeof *s), *U = malloc((size_t)rows * m * sizeof *U),
           *VT = malloc((size_t)m * n * sizeof *VT);
    if (!s || !U || !VT) {
        free(s);
        free(U);
        free(VT);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the SVD");
    }
    info = (int)LAPACKE_dgesdd(LAPACK_COL_MAJOR, 'S', rows, n, B, rows, s, U, rows, VT, m);
    if (info != 0) {
        free(s);
        free(U);
        free(VT);
        return glint_err_set(err, GLINT_ENUMERIC, "SVD failed (LAPACK info %d)", info);
    }
    dc->s_max = s[0];
    while (rank < m && s[rank] > rcond * dc->s_max && s[rank] > 0.0)
        rank++;
    dc->s2 = malloc((size_t)(rank ? rank : 1) * sizeof *dc->s2);
    dc->V = malloc((size_t)n * (rank ? rank : 1) * sizeof *dc->V);
    if (!dc->s2 || !dc->V) {
        free(s);
        free(U);
        free(VT);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the decomposition");
    }
    for (int k = 0; k < rank; k++) {
        dc->s2[k] = s[k] * s[k];
        for (int i = 0; i < n; i++)
            dc->V[(size_t)n * k + i] = VT[k + (size_t)m * i];
    }
    dc->rank = rank;
    dc->s_min_kept = rank ? s[rank - 1] : 0.0;
    free(s);
    free(U);
    free(VT);
    return 0;
}

int hf4_decomp_build(const hf4_design *x, double lambda, double lambda_s, double rcond,
                     hf4_decomp *dc, glint_err *err)
{
    int R = x->d.res, S = x->sres, n = 3 * R + S * S, N = x->d.n;
    int col[ROW_MAX], rc, ns, nr = 0, *idx;
    double w[ROW_MAX], t0 = glint_now();
    size_t rows;

    memset(dc, 0, sizeof *dc);
    if (!lambda_ok(lambda) || !lambda_ok(lambda_s))
        return glint_err_set(err, GLINT_ERANGE, "lambda %g and lambda_s %g must be in 0..%g",
                             lambda, lambda_s, HF_LAMBDA_MAX);
    if (!(rcond > 0.0))
        rcond = HF4_RCOND_DEFAULT;
    if (!(rcond < 1.0) || !isfinite(rcond))
        return glint_err_set(err, GLINT_ERANGE, "rcond %g must be below 1", rcond);
    ns = smooth_rows(R, S, lambda, lambda_s);
    rows = (size_t)N + ns;
    dc->res = R;
    dc->sres = S;
    dc->n = n;
    dc->nsamples = N;
    dc->rows = (int)rows;
    dc->lambda = lambda;
    dc->lambda_s = lambda_s;
    dc->rcond = rcond;
    dc->gauge_dims = 3;
    /* unknowns no row reaches (nodes of s without samples or smoothing, a
     * 1D texel no sample lands on with lambda 0) are exactly null: left out
     * of the decomposition (a smaller matrix, and no rounding left to sort
     * them from the weak directions), their rows of V zero */
    if (!(idx = malloc((size_t)n * sizeof *idx)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int t = 0; t < n; t++)
        idx[t] = -1;
    for (size_t r = 0; r < rows; r++) {
        int m = r < (size_t)N ? data_row(x, (int)r, col, w)
                              : smooth_row(R, S, lambda, lambda_s, (int)(r - N), col, w);
        for (int a = 0; a < m; a++)
            if (w[a] != 0.0)
                idx[col[a]] = 0;
    }
    for (int t = 0; t < n; t++)
        if (idx[t] == 0)
            idx[t] = nr++;
    dc->unreached = n - nr;
    if (rows < (size_t)nr) { /* the dense rows x n matrix is the smaller */
        double *B = calloc(rows * (size_t)nr, sizeof *B);
        dc->form = "dense";
        if (!B) {
            free(idx);
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %zux%d matrix", rows,
                                 nr);
        }
        for (size_t r = 0; r < rows; r++) {
            int m = r < (size_t)N ? data_row(x, (int)r, col, w)
                                  : smooth_row(R, S, lambda, lambda_s, (int)(r - N), col, w);
            for (int a = 0; a < m; a++)
                if (w[a] != 0.0)
                    B[r + rows * idx[col[a]]] += w[a];
        }
        rc = decomp_dense(B, (int)rows, nr, rcond, dc, err);
        free(B);
    } else {
        double *G = calloc((size_t)nr * nr, sizeof *G);
        dc->form = "normal";
        if (!G) {
            free(idx);
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d matrix", nr, nr);
        }
        for (size_t r = 0; r < rows; r++) {
            int m = r < (size_t)N ? data_row(x, (int)r, col, w)
                                  : smooth_row(R, S, lambda, lambda_s, (int)(r - N), col, w);
            for (int a = 0; a < m; a++)
                for (int b = 0; b < m; b++)
                    if (w[a] != 0.0 && w[b] != 0.0 && idx[col[a]] <= idx[col[b]])
                        G[idx[col[a]] + (size_t)nr * idx[col[b]]] += w[a] * w[b];
        }
        /* rounding reaches the eigenvalues of B^T B at about n eps e_max: the
         * normal form resolves singular values down to sqrt(n eps) s_max */
        if (rcond < sqrt(nr * DBL_EPSILON))
            dc->rcond = rcond = sqrt(nr * DBL_EPSILON);
        rc = decomp_normal(G, nr, rcond, dc, err);
        free(G);
    }
    if (!rc && nr < n) { /* V back to every unknown: zero rows where none reaches */
        double *V = calloc((size_t)n * (dc->rank ? dc->rank : 1), sizeof *V);
        if (!V) {
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the decomposition");
        } else {
            for (int k = 0; k < dc->rank; k++)
                for (int t = 0; t < n; t++)
                    if (idx[t] >= 0)
                        V[(size_t)n * k + t] = dc->V[(size_t)nr * k + idx[t]];
            free(dc->V);
            dc->V = V;
        }
    }
    free(idx);
    if (rc) {
        hf4_decomp_free(dc);
        return rc;
    }
    dc->null_dims = n - dc->gauge_dims - dc->rank;
    if (dc->null_dims < 0)
        dc->null_dims = 0;
    dc->seconds = glint_now() - t0;
    return 0;
}

void hf4_factors_free(hf4_factors *f)
{
    if (!f)
        return;
    free(f->logf);
    free(f->logs);
    memset(f, 0, sizeof *f);
}

void hf4_factors_means(hf4_factors *f)
{
    size_t nn = (size_t)f->sres * f->sres;
    for (int c = 0; c < 3; c++) {
        double s = 0.0;
        for (size_t i = 0; i < nn; i++)
            s += exp(f->logs[3 * i + c] > 700.0 ? 700.0 : f->logs[3 * i + c]);
        f->mean_s[c] = s / (double)nn;
    }
}

static double map_inverse(const hf4_factors *f, int c, double prod)
{
    return hf_map_inverse(&f->map, f->a_used[c], prod);
}

void hf4_factors_eval(const hf4_factors *f, const double uv[2], const double n[3],
                      const double wi[3], const double wo[3], double rgb[3])
{
    double pi[3], ci, co, acc[3] = {0.0, 0.0, 0.0}, lin[3] = {1.0, 1.0, 1.0};
    int R = f->res, S = f->sres;

    ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    if (!(ci > 0.0) || !(co > 0.0)) {
        rgb[0] = rgb[1] = rgb[2] = 0.0;
        return;
    }
    hf_project(n, wi, wo, pi);
    for (int j = 0; j < 3; j++) {
        int k;
        double t;
        hf_hat(pi[j], R, &k, &t);
        for (int c = 0; c < 3; c++)
            acc[c] += (1.0 - t) * f->logf[(j * R + k) * 3 + c] +
                      t * f->logf[(j * R + k + 1) * 3 + c];
    }
    if (uv && isfinite(uv[0]) && isfinite(uv[1])) {
        int i0, j0;
        double tx, ty;
        const double *L = f->logs;
        hf_hat(uv[0], S, &i0, &tx);
        hf_hat(uv[1], S, &j0, &ty);
        for (int c = 0; c < 3; c++)
            acc[c] += (1.0 - ty) * ((1.0 - tx) * L[((size_t)j0 * S + i0) * 3 + c] +
                                    tx * L[((size_t)j0 * S + i0 + 1) * 3 + c]) +
                      ty * ((1.0 - tx) * L[((size_t)(j0 + 1) * S + i0) * 3 + c] +
                            tx * L[((size_t)(j0 + 1) * S + i0 + 1) * 3 + c]);
    } else {
        for (int c = 0; c < 3; c++)
            lin[c] = f->mean_s[c];
    }
    for (int c = 0; c < 3; c++) {
        double v = map_inverse(f, c, exp(acc[c] > 700.0 ? 700.0 : acc[c]) * lin[c]);
        rgb[c] = f->model == HF_MODEL_BRDF ? v * ci : v;
    }
}

int hf4_fit(const hf4_design *x, const hf4_decomp *dc, const hf_map *map, hf_model model,
            const float *rgb, hf4_factors *fac, hf4_fit_stats *st_out, glint_err *err)
{
    int R = x->d.res, S = x->sres, n = dc->n, N = x->d.n, k = dc->rank, rc = 0;
    int col[ROW_MAX];
    double w[ROW_MAX], t0 = glint_now(), *f = NULL, *b = NULL, *z = NULL, *y = NULL;
    hf4_fit_stats st;

    memset(fac, 0, sizeof *fac);
    memset(&st, 0, sizeof st);
    if (dc->res != R || dc->sres != S || dc->nsamples != N)
        return glint_err_set(err, GLINT_EINVAL, "decomposition and design do not match");
    if (!(map->eps > 0.0) || !isfinite(map->eps) || !isfinite(map->a) ||
        !isfinite(map->margin) || map->margin < 0.0 ||
        (map->kind == HF_MAP_ADD && !(map->a > 0.0)))
        return glint_err_set(err, GLINT_EINVAL, "invalid mapping parameters");
    for (long i = 0; i < 3L * N; i++)
        if (!isfinite(rgb[i]))
            return glint_err_set(err, GLINT_ENONFINITE, "sample %ld channel %ld is not finite",
                                 i / 3, i % 3);
    f = malloc(3 * (size_t)N * sizeof *f);
    b = calloc(3 * (size_t)n, sizeof *b);
    z = malloc(3 * (size_t)(k ? k : 1) * sizeof *z);
    y = malloc(3 * (size_t)n * sizeof *y);
    fac->logf = malloc(9 * (size_t)R * sizeof *fac->logf);
    fac->logs = malloc(3 * (size_t)S * S * sizeof *fac->logs);
    if (!f || !b || !z || !y || !fac->logf || !fac->logs) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory fitting %d samples", N);
        goto done;
    }
    fac->res = R;
    fac->sres = S;
    fac->model = model;
    fac->map = *map;
    /* the model's quantity and the mapping, as hf_fit */
    for (int c = 0; c < 3; c++) {
        double vmax = 0.0;
        for (int i = 0; i < N; i++) {
            double v = rgb[3 * (size_t)i + c];
            if (model == HF_MODEL_BRDF)
                v /= x->d.cos_i[i] > COS_FLOOR ? x->d.cos_i[i] : COS_FLOOR;
            f[3 * (size_t)i + c] = v;
            vmax = v > vmax ? v : vmax;
        }
        fac->a_used[c] = hf_map_offset(map, vmax);
    }
    for (size_t i = 0; i < 3 * (size_t)N; i++) {
        int c = (int)(i % 3);
        double arg = hf_map_arg(map, fac->a_used[c], f[i]);
        if (!(arg > map->eps)) {
            arg = map->eps;
            st.clamped[c]++;
        }
        f[i] = log(arg);
    }
    /* b = A^T f~ (n x 3, column per channel), z = V^T b / s^2, y = V z */
    for (int i = 0; i < N; i++) {
        int m = data_row(x, i, col, w);
        for (int a = 0; a < m; a++)
            for (int c = 0; c < 3; c++)
                b[col[a] + (size_t)n * c] += w[a] * f[3 * (size_t)i + c];
    }
    if (k > 0) {
        cblas_dgemm(CblasColMajor, CblasTrans, CblasNoTrans, k, 3, n, 1.0, dc->V, n, b, n, 0.0,
                    z, k);
        for (int c = 0; c < 3; c++)
            for (int i = 0; i < k; i++)
                z[i + (size_t)k * c] /= dc->s2[i];
        cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, n, 3, k, 1.0, dc->V, n, z, k,
                    0.0, y, n);
    } else {
        memset(y, 0, 3 * (size_t)n * sizeof *y);
    }
    /* the canonical gauge: equal mean log per factor and channel */
    for (int c = 0; c < 3; c++) {
        double mean[4] = {0, 0, 0, 0}, all;
        double *yc = y + (size_t)n * c;
        for (int j = 0; j < 3; j++) {
            for (int t = 0; t < R; t++)
                mean[j] += yc[j * R + t];
            mean[j] /= R;
        }
        for (int t = 0; t < S * S; t++)
            mean[3] += yc[3 * R + t];
        mean[3] /= (double)S * S;
        all = (mean[0] + mean[1] + mean[2] + mean[3]) / 4.0;
        for (int t = 0; t < n; t++) {
            int j = t < 3 * R ? t / R : 3;
            double v = yc[t] + all - mean[j];
            if (v > HF4_LOG_MAX || v < -HF4_LOG_MAX) {
                v = v > 0.0 ? HF4_LOG_MAX : -HF4_LOG_MAX;
                st.log_clamped++;
            }
            st.log_max = fabs(v) > st.log_max ? fabs(v) : st.log_max;
            yc[t] = v;
            if (t < 3 * R)
                fac->logf[(size_t)t * 3 + c] = v;
            else
                fac->logs[(size_t)(t - 3 * R) * 3 + c] = v;
        }
    }
    hf4_factors_means(fac);
    st.seconds = glint_now() - t0;
    /* diagnostics: log residual and the linear error at every sample */
    {
        double ss = 0.0, se = 0.0, mx = 0.0;
        for (int i = 0; i < N; i++) {
            int m = data_row(x, i, col, w);
            for (int c = 0; c < 3; c++) {
                double ly = 0.0, v, e;
                for (int a = 0; a < m; a++)
                    ly += w[a] * y[col[a] + (size_t)n * c];
                e = ly - f[3 * (size_t)i + c];
                ss += e * e;
                v = map_inverse(fac, c, exp(ly > 700.0 ? 700.0 : ly));
                if (model == HF_MODEL_BRDF)
                    v *= x->d.cos_i[i];
                e = v - rgb[3 * (size_t)i + c];
                se += e * e;
                mx = fabs(e) > mx ? fabs(e) : mx;
            }
        }
        st.log_residual = N ? sqrt(ss / (3.0 * N)) : 0.0;
        st.rms = N ? sqrt(se / (3.0 * N)) : 0.0;
        st.max_abs = mx;
    }
done:
    free(f);
    free(b);
    free(z);
    free(y);
    if (rc)
        hf4_factors_free(fac);
    else if (st_out)
        *st_out = st;
    return rc;
}
