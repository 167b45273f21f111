/* hfx.c: the decomposition and fit shared by factor products with 2D
 * factors (hfx.h). */
#include "hfx.h"

#include <cblas.h>
#include <float.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cfile.h"
#include "clock.h"
#include "internal/hfx_int.h"

#define COS_FLOOR 1e-6 /* as hf_fit's BRDF model */

int hfx_smooth_1d(int off, double lambda, int r, int *col, double *w)
{
    col[0] = off + r;
    col[1] = off + r + 1;
    col[2] = off + r + 2;
    w[0] = lambda;
    w[1] = -2.0 * lambda;
    w[2] = lambda;
    return 3;
}

int hfx_smooth_2d(int off, int S, double lambda, int r, int *col, double *w)
{
    int i = r % S, j = r / S, m = 1;
    col[0] = off + j * S + i;
    if (i > 0)
        col[m++] = off + j * S + i - 1;
    if (i + 1 < S)
        col[m++] = off + j * S + i + 1;
    if (j > 0)
        col[m++] = off + (j - 1) * S + i;
    if (j + 1 < S)
        col[m++] = off + (j + 1) * S + i;
    w[0] = -(double)(m - 1) * lambda;
    for (int a = 1; a < m; a++)
        w[a] = lambda;
    return m;
}

void hfx_decomp_free(hfx_decomp *dc)
{
    if (!dc)
        return;
    free(dc->s2);
    free(dc->V);
    free(dc->M);
    memset(dc, 0, sizeof *dc);
}

int hfx_decomp_from_eig(const double *e, const double *vecs, int n, double rcond,
                        hfx_decomp *dc, glint_err *err)
{
    double cut;
    int rank = 0;

    dc->s_max = e[n - 1] > 0.0 ? sqrt(e[n - 1]) : 0.0;
    cut = rcond * dc->s_max;
    for (int i = n - 1; i >= 0 && e[i] > cut * cut && e[i] > 0.0; i--)
        rank++;
    dc->s2 = malloc((size_t)(rank ? rank : 1) * sizeof *dc->s2);
    dc->V = malloc((size_t)n * (rank ? rank : 1) * sizeof *dc->V);
    if (!dc->s2 || !dc->V)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the decomposition");
    for (int k = 0; k < rank; k++) { /* descending */
        int src = n - 1 - k;
        dc->s2[k] = e[src];
        memcpy(dc->V + (size_t)n * k, vecs + (size_t)n * src, (size_t)n * sizeof *dc->V);
    }
    dc->rank = rank;
    dc->s_min_kept = rank ? sqrt(dc->s2[rank - 1]) : 0.0;
    return 0;
}

/* The kept directions of the normal matrix G (n x n, upper triangle;
 * destroyed). */
static int decomp_normal(double *G, int n, double rcond, hfx_decomp *dc, glint_err *err)
{
    double *e = malloc((size_t)n * sizeof *e);
    int info, rc;
    if (!e)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    info = (int)LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'U', n, G, n, e);
    if (info != 0) {
        free(e);
        return glint_err_set(err, GLINT_ENUMERIC, "eigendecomposition failed (LAPACK info %d)",
                             info);
    }
    rc = hfx_decomp_from_eig(e, G, n, rcond, dc, err);
    free(e);
    return rc;
}

/* The kept directions from the SVD of B (rows x n, rows <= n; destroyed). */
static int decomp_dense(double *B, int rows, int n, double rcond, hfx_decomp *dc,
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

int hfx_decomp_build(const hfx_rows *x, double rcond, int gauge_dims, hfx_decomp *dc,
                     glint_err *err)
{
    int n = x->n, N = x->nsamples, col[HFX_ROW_MAX], rc, nr = 0, *idx;
    double w[HFX_ROW_MAX], t0 = glint_now();
    size_t rows = (size_t)N + x->nsmooth;

    memset(dc, 0, sizeof *dc);
    if (!(rcond > 0.0) || !(rcond < 1.0))
        return glint_err_set(err, GLINT_ERANGE, "rcond %g must be in (0, 1)", rcond);
    dc->n = n;
    dc->nsamples = N;
    dc->rows = (int)rows;
    dc->rcond = rcond;
    dc->gauge_dims = gauge_dims;
    /* unknowns no row reaches (nodes without samples or smoothing) are
     * exactly null: left out of the decomposition (a smaller matrix, and no
     * rounding left to sort them from the weak directions), their rows of V
     * zero */
    if (!(idx = malloc((size_t)n * sizeof *idx)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    hfx_reached(x, idx);
    nr = hfx_number_reached(idx, n);
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
            int m = x->row(x->ctx, (int)r, col, w);
            for (int a = 0; a < m; a++)
                if (w[a] != 0.0)
                    B[r + rows * idx[col[a]]] += w[a];
        }
        rc = decomp_dense(B, (int)rows, nr, rcond, dc, err);
        free(B);
    } else if (N < nr && (rc = hfx_kernel_build(x, idx, nr, rcond, dc, err)) != 1) {
        /* the kernel form: done (or failed) */
    } else {
        double *G = calloc((size_t)nr * nr, sizeof *G);
        dc->form = "normal";
        if (!G) {
            free(idx);
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d matrix", nr, nr);
        }
        hfx_normal_add(x, idx, nr, G);
        dc->rcond = rcond = hfx_normal_rcond(rcond, nr);
        rc = decomp_normal(G, nr, rcond, dc, err);
        free(G);
    }
    if (!rc)
        rc = hfx_decomp_finish(dc, idx, nr, err);
    free(idx);
    if (rc) {
        hfx_decomp_free(dc);
        return rc;
    }
    dc->seconds = glint_now() - t0;
    return 0;
}

void hfx_reached(const hfx_rows *x, int *idx)
{
    int col[HFX_ROW_MAX];
    double w[HFX_ROW_MAX];
    size_t rows = (size_t)x->nsamples + x->nsmooth;

    for (int t = 0; t < x->n; t++)
        idx[t] = -1;
    for (size_t r = 0; r < rows; r++) {
        int m = x->row(x->ctx, (int)r, col, w);
        for (int a = 0; a < m; a++)
            if (w[a] != 0.0)
                idx[col[a]] = 0;
    }
}

int hfx_number_reached(int *idx, int n)
{
    int nr = 0;
    for (int t = 0; t < n; t++)
        if (idx[t] == 0)
            idx[t] = nr++;
    return nr;
}

void hfx_normal_add(const hfx_rows *x, const int *idx, int nr, double *G)
{
    int col[HFX_ROW_MAX];
    double w[HFX_ROW_MAX];
    size_t rows = (size_t)x->nsamples + x->nsmooth;

    for (size_t r = 0; r < rows; r++) {
        int m = x->row(x->ctx, (int)r, col, w);
        for (int a = 0; a < m; a++)
            for (int b = 0; b < m; b++)
                if (w[a] != 0.0 && w[b] != 0.0 && idx[col[a]] <= idx[col[b]])
                    G[idx[col[a]] + (size_t)nr * idx[col[b]]] += w[a] * w[b];
    }
}

double hfx_normal_rcond(double rcond, int nr)
{
    /* rounding reaches the eigenvalues of B^T B at about n eps e_max: the
     * normal form resolves singular values down to sqrt(n eps) s_max */
    return rcond < sqrt(nr * DBL_EPSILON) ? sqrt(nr * DBL_EPSILON) : rcond;
}

int hfx_decomp_finish(hfx_decomp *dc, const int *idx, int nr, glint_err *err)
{
    int n = dc->n;

    if (nr < n && !dc->M) { /* V back to every unknown: zero rows where none reaches */
        double *V = calloc((size_t)n * (dc->rank ? dc->rank : 1), sizeof *V);
        if (!V)
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for the decomposition");
        for (int k = 0; k < dc->rank; k++)
            for (int t = 0; t < n; t++)
                if (idx[t] >= 0)
                    V[(size_t)n * k + t] = dc->V[(size_t)nr * k + idx[t]];
        free(dc->V);
        dc->V = V;
    }
    dc->null_dims = n - dc->gauge_dims - dc->rank;
    if (dc->null_dims < 0)
        dc->null_dims = 0;
    return 0;
}

int hfx_fit(const hfx_rows *x, const hfx_decomp *dc, const hfx_problem *pb, const float *rgb,
            double *y, double a_used[3], hfx_fit_stats *st_out, glint_err *err)
{
    int n = dc->n, N = x->nsamples, k = dc->rank, J = pb->nfactors, rc = 0;
    int col[HFX_ROW_MAX];
    double w[HFX_ROW_MAX], t0 = glint_now(), *f = NULL, *b = NULL, *z = NULL;
    const hf_map *map = pb->map;
    hfx_fit_stats st;

    memset(&st, 0, sizeof st);
    if (dc->n != x->n || dc->nsamples != N || J < 1 || J > HFX_FACTORS_MAX ||
        pb->off[0] != 0 || pb->off[J] != n)
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
    if (!f || !b || !z) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory fitting %d samples", N);
        goto done;
    }
    /* the model's quantity and the mapping, as hf_fit */
    for (int c = 0; c < 3; c++) {
        double vmax = 0.0;
        for (int i = 0; i < N; i++) {
            double v = rgb[3 * (size_t)i + c];
            if (pb->model == HF_MODEL_BRDF)
                v /= pb->cos_i[i] > COS_FLOOR ? pb->cos_i[i] : COS_FLOOR;
            f[3 * (size_t)i + c] = v;
            vmax = v > vmax ? v : vmax;
        }
        a_used[c] = hf_map_offset(map, vmax);
    }
    for (size_t i = 0; i < 3 * (size_t)N; i++) {
        int c = (int)(i % 3);
        double arg = hf_map_arg(map, a_used[c], f[i]);
        if (!(arg > map->eps)) {
            arg = map->eps;
            st.clamped[c]++;
        }
        f[i] = log(arg);
    }
    if (dc->M) { /* the kernel form: y = M f~ (f~ is 3 x N with leading dimension 3) */
        cblas_dgemm(CblasColMajor, CblasNoTrans, CblasTrans, n, 3, N, 1.0, dc->M, n, f, 3, 0.0,
                    y, n);
        goto gauge;
    }
    /* b = A^T f~ (n x 3, column per channel), z = V^T b / s^2, y = V z */
    for (int i = 0; i < N; i++) {
        int m = x->row(x->ctx, i, col, w);
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
gauge: /* the canonical gauge: equal mean log per factor and channel */
    for (int c = 0; c < 3; c++) {
        double mean[HFX_FACTORS_MAX] = {0}, all = 0.0;
        double *yc = y + (size_t)n * c;
        for (int j = 0; j < J; j++) {
            for (int t = pb->off[j]; t < pb->off[j + 1]; t++)
                mean[j] += yc[t];
            mean[j] /= (double)(pb->off[j + 1] - pb->off[j]);
        }
        for (int j = 0; j < J; j++)
            all += mean[j];
        all /= (double)J;
        for (int j = 0; j < J; j++)
            for (int t = pb->off[j]; t < pb->off[j + 1]; t++) {
                double v = yc[t] + all - mean[j];
                if (v > pb->log_max || v < -pb->log_max) {
                    v = v > 0.0 ? pb->log_max : -pb->log_max;
                    st.log_clamped++;
                }
                st.log_max = fabs(v) > st.log_max ? fabs(v) : st.log_max;
                yc[t] = v;
            }
    }
    st.seconds = glint_now() - t0;
    /* diagnostics: log residual and the linear error at every sample */
    {
        double ss = 0.0, se = 0.0, mx = 0.0;
        for (int i = 0; i < N; i++) {
            int m = x->row(x->ctx, i, col, w);
            for (int c = 0; c < 3; c++) {
                double ly = 0.0, v, e;
                for (int a = 0; a < m; a++)
                    ly += w[a] * y[col[a] + (size_t)n * c];
                e = ly - f[3 * (size_t)i + c];
                ss += e * e;
                v = hf_map_inverse(map, a_used[c], exp(ly > 700.0 ? 700.0 : ly));
                if (pb->model == HF_MODEL_BRDF)
                    v *= pb->cos_i[i];
                e = v - rgb[3 * (size_t)i + c];
                se += e * e;
                if (pb->view)
                    st.view_se[pb->view[i]] += e * e;
                mx = fabs(e) > mx ? fabs(e) : mx;
            }
            if (pb->view)
                st.view_n[pb->view[i]]++;
        }
        st.log_residual = N ? sqrt(ss / (3.0 * N)) : 0.0;
        st.rms = N ? sqrt(se / (3.0 * N)) : 0.0;
        st.max_abs = mx;
    }
done:
    free(f);
    free(b);
    free(z);
    if (!rc && st_out)
        *st_out = st;
    return rc;
}

static const char *const form_names[3] = {"normal", "dense", "kernel"};

void hfx_decomp_put(cfile_w *b, const hfx_decomp *g)
{
    uint32_t form = 0, u[8];
    double d[4] = {g->rcond, g->s_max, g->s_min_kept, g->seconds};
    for (uint32_t i = 0; i < 3; i++)
        if (g->form && strcmp(g->form, form_names[i]) == 0)
            form = i;
    u[0] = (uint32_t)g->n, u[1] = (uint32_t)g->nsamples, u[2] = (uint32_t)g->rows;
    u[3] = form, u[4] = (uint32_t)g->rank, u[5] = (uint32_t)g->gauge_dims;
    u[6] = (uint32_t)g->null_dims, u[7] = (uint32_t)g->unreached;
    cfile_put(b, u, sizeof u);
    cfile_put(b, d, sizeof d);
    if (form == 2) {
        cfile_put(b, g->M, (size_t)g->n * g->nsamples * sizeof *g->M);
    } else {
        cfile_put(b, g->s2, (size_t)g->rank * sizeof *g->s2);
        cfile_put(b, g->V, (size_t)g->n * g->rank * sizeof *g->V);
    }
}

int hfx_decomp_get(cfile_r *r, int n, int nsamples, hfx_decomp *g, const char *name,
                   glint_err *err)
{
    uint32_t u[8];
    double d[4];
    memset(g, 0, sizeof *g);
    if (cfile_get(r, u, sizeof u) || cfile_get(r, d, sizeof d) || (int)u[0] != n ||
        (int)u[1] != nsamples || u[3] > 2 || u[4] > u[0] || u[5] > u[0] || u[6] > u[0] ||
        u[7] > u[0])
        return glint_err_set(err, GLINT_EFORMAT, "%s: the cached decomposition does not match",
                             name);
    g->n = n, g->nsamples = nsamples, g->rows = (int)u[2], g->form = form_names[u[3]];
    g->rank = (int)u[4], g->gauge_dims = (int)u[5], g->null_dims = (int)u[6];
    g->unreached = (int)u[7];
    g->rcond = d[0], g->s_max = d[1], g->s_min_kept = d[2], g->seconds = d[3];
    if (u[3] == 2) {
        size_t cnt = (size_t)n * nsamples;
        if (!(g->M = malloc((cnt ? cnt : 1) * sizeof *g->M)))
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        if (cfile_get(r, g->M, cnt * sizeof *g->M))
            goto short_file;
        return 0;
    }
    g->s2 = malloc((size_t)(g->rank ? g->rank : 1) * sizeof *g->s2);
    g->V = malloc((size_t)n * (g->rank ? g->rank : 1) * sizeof *g->V);
    if (!g->s2 || !g->V) {
        hfx_decomp_free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    if (cfile_get(r, g->s2, (size_t)g->rank * sizeof *g->s2) ||
        cfile_get(r, g->V, (size_t)n * g->rank * sizeof *g->V))
        goto short_file;
    return 0;
short_file:
    hfx_decomp_free(g);
    return glint_err_set(err, GLINT_EFORMAT, "%s: the cached decomposition has the wrong size",
                         name);
}

int hfx_decomp_file_save(const char *magic, const char *ext, const uint32_t *u, int nu,
                         const double *d, int nd, const hfx_decomp *g, const char *dir,
                         const char *key, glint_err *err)
{
    char name[64];
    cfile_w b;
    cfile_begin(&b, magic, 1);
    cfile_put(&b, u, (size_t)nu * sizeof *u);
    cfile_put(&b, d, (size_t)nd * sizeof *d);
    hfx_decomp_put(&b, g);
    cfile_name(key, ext, name, sizeof name);
    return cfile_write(&b, dir, name, err);
}

int hfx_decomp_file_load(const char *magic, const char *ext, const uint32_t *u, int nu,
                         const double *d, int nd, int n, int nsamples, hfx_decomp *g,
                         const char *dir, const char *key, glint_err *err)
{
    char name[64];
    uint32_t fu[8];
    double fd[8];
    cfile_r r;
    int rc;

    if (nu < 0 || nu > 8 || nd < 0 || nd > 8)
        return glint_err_set(err, GLINT_EINVAL, "hfx_decomp_file_load: header of %d + %d", nu,
                             nd);
    cfile_name(key, ext, name, sizeof name);
    if ((rc = cfile_open(dir, name, magic, 1, (size_t)16 << 30, &r, err)))
        return rc;
    rc = GLINT_EFORMAT;
    if (cfile_get(&r, fu, (size_t)nu * sizeof *fu) || cfile_get(&r, fd, (size_t)nd * sizeof *fd) ||
        memcmp(fu, u, (size_t)nu * sizeof *fu) != 0) {
        glint_err_set(err, rc, "%s: the cached decomposition does not match (key %s)", name, key);
        goto done;
    }
    for (int i = 0; i < nd; i++)
        if (fd[i] != d[i]) {
            glint_err_set(err, rc, "%s: the cached decomposition does not match (key %s)", name,
                          key);
            goto done;
        }
    if ((rc = hfx_decomp_get(&r, n, nsamples, g, name, err)))
        goto done;
    if (!cfile_done(&r))
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: the cached decomposition has the wrong size",
                           name);
done:
    cfile_close(&r);
    return rc;
}
