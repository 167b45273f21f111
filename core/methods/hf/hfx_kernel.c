/* hfx_kernel.c: the kernel form of hfx.h's decomposition (few samples,
 * many unknowns, smoothing on every factor): the operator through an
 * N x N Cholesky instead of an n x n eigendecomposition.  The algebra is
 * in hfx.h. */
#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal/hfx_int.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Null eigenvalues of K: at or below this fraction of the largest.  The
 * smallest non-zero ones of the smoothing glint builds are far above it:
 * (pi / 512)^4 / 16 = 9e-11 for second differences over 512 texels,
 * (pi / 64)^4 / 64 = 9e-8 for the graph Laplacian of a 64 x 64 grid; the
 * rounding of the zero ones is about n eps = 1e-13. */
#define NULL_REL 1e-12
/* The kernel form is taken only while K's null space is this small (the
 * elimination of a is a dense SVD of N x k). */
#define KERNEL_NULL_MAX 64

typedef struct block {
    int b0, n;           /* reduced unknowns b0 .. b0 + n - 1 */
    double *K;           /* n x n */
    double *Q, *e;       /* eigenvectors (n x n) and eigenvalues, ascending */
    int same_as;         /* an earlier block with the same K, or -1 */
} block;

/* The eigenvectors of an S x S grid's smoothing block K = w^2 L^2 (L the
 * graph Laplacian of hfx_smooth_2d; w from K's corner, where (L^2)_ii =
 * deg^2 + deg = 6): products of the path graph's DCT-II vectors
 * c_k(i) = sqrt((k ? 2 : 1) / S) cos(pi k (i + 1/2) / S), eigenvalues
 * w^2 (mu_a + mu_b)^2 with mu_k = 2 - 2 cos(pi k / S).  Checked against
 * K on a few vectors; 1 when K is not such a block (the caller then
 * eigendecomposes it), -1 out of memory. */
static int grid_eigen(block *b, int S)
{
    int n = b->n;
    double w2, worst = 0.0, *c = NULL, *v = NULL;
    if (S < 2 || n != S * S || !(b->K[0] > 0.0))
        return 1;
    w2 = b->K[0] / 6.0;
    b->Q = malloc((size_t)n * n * sizeof *b->Q);
    b->e = malloc((size_t)n * sizeof *b->e);
    c = malloc((size_t)S * S * sizeof *c);
    v = malloc((size_t)n * sizeof *v);
    if (!b->Q || !b->e || !c || !v) {
        free(c);
        free(v);
        return -1;
    }
    for (int k = 0; k < S; k++)
        for (int i = 0; i < S; i++)
            c[k * S + i] = sqrt((k ? 2.0 : 1.0) / S) * cos(M_PI * k * (i + 0.5) / S);
    for (int kb = 0; kb < S; kb++)
        for (int ka = 0; ka < S; ka++) {
            int col = kb * S + ka;
            double mu = 4.0 - 2.0 * cos(M_PI * ka / S) - 2.0 * cos(M_PI * kb / S);
            double *q = b->Q + (size_t)n * col;
            b->e[col] = w2 * mu * mu;
            for (int jb = 0; jb < S; jb++)
                for (int ja = 0; ja < S; ja++)
                    q[jb * S + ja] = c[ka * S + ja] * c[kb * S + jb];
        }
    /* K q = e q on a spread of vectors (the highest, the lowest non-zero, a middle one) */
    for (int t = 0; t < 4; t++) {
        int col = t == 0 ? 1 : t == 1 ? n - 1 : t == 2 ? n / 2 : S + 1;
        const double *q = b->Q + (size_t)n * col;
        cblas_dgemv(CblasColMajor, CblasNoTrans, n, n, 1.0, b->K, n, q, 1, 0.0, v, 1);
        for (int i = 0; i < n; i++)
            worst = fmax(worst, fabs(v[i] - b->e[col] * q[i]));
    }
    free(c);
    free(v);
    if (!(worst <= 1e-9 * (w2 * 64.0))) { /* 64 w^2: the largest eigenvalue's bound */
        free(b->Q);
        free(b->e);
        b->Q = b->e = NULL;
        return 1;
    }
    return 0;
}

static void blocks_free(block *bl, int nb)
{
    for (int j = 0; j < nb; j++) {
        free(bl[j].K);
        if (bl[j].same_as < 0) {
            free(bl[j].Q);
            free(bl[j].e);
        }
    }
    free(bl);
}

/* The kernel form's state from step to step (hfx_kernel_build): the
 * smoothing's blocks, the columns of Q = blockdiag(Q_j) sorted into null
 * (W0's) and kept (W1's), and the N x N products. */
typedef struct kernel {
    const hfx_rows *x;
    const int *idx;      /* unknowns to reduced ones (hfx_int.h) */
    int N, nr, nb;       /* samples, reduced unknowns, blocks (factors) */
    block *bl;
    int *where;          /* nr: each reduced unknown's block */
    int *cls;            /* nr: Q's column null (0) or kept (1) */
    double *eig;         /* nr: its eigenvalue of K */
    double emax, emin_pos;
    int k, m;            /* null and kept columns */
    int kk, r;           /* min(N, k); W0's rank at rcond */
    double *W;           /* N x nr: A Q, then scratch */
    double *W0, *W1;     /* N x k, N x m: its null and kept columns */
    double *U, *sv, *VT; /* W0 = U S V^T */
    double *C, *X, *T;   /* N x N */
    double *Y;           /* nr x N: the operator in Q's columns */
    double *Mr;          /* N x m: P W1 */
} kernel;

/* The blocks in the reduced unknowns (idx is monotone), each with its K
 * zeroed, and the block of each reduced unknown. */
static int block_layout(kernel *kn, glint_err *err)
{
    const hfx_rows *x = kn->x;
    block *bl = kn->bl;
    for (int j = 0, t0 = 0; j < kn->nb; j++) {
        bl[j].b0 = t0;
        for (int t = x->off[j]; t < x->off[j + 1]; t++)
            bl[j].n += kn->idx[t] >= 0;
        t0 += bl[j].n;
        bl[j].same_as = -1;
        if (bl[j].n && !(bl[j].K = calloc((size_t)bl[j].n * bl[j].n, sizeof *bl[j].K)))
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    if (!(kn->where = malloc((size_t)kn->nr * sizeof *kn->where)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int j = 0; j < kn->nb; j++)
        for (int t = 0; t < bl[j].n; t++)
            kn->where[bl[j].b0 + t] = j;
    return 0;
}

/* K per block, from the smoothing rows.  Returns 1 (no kernel form) at a
 * row across blocks. */
static int smoothing_blocks(kernel *kn)
{
    const hfx_rows *x = kn->x;
    const int *idx = kn->idx, *where = kn->where;
    block *bl = kn->bl;
    int N = kn->N, col[HFX_ROW_MAX];
    double w[HFX_ROW_MAX];
    for (int rr = N; rr < N + x->nsmooth; rr++) {
        int mm = x->row(x->ctx, rr, col, w), j = -1;
        for (int a = 0; a < mm; a++) {
            if (w[a] == 0.0)
                continue;
            if (j < 0)
                j = where[idx[col[a]]];
            else if (where[idx[col[a]]] != j)
                return 1;
        }
        for (int a = 0; a < mm; a++)
            for (int b = 0; b < mm; b++)
                if (w[a] != 0.0 && w[b] != 0.0)
                    bl[j].K[(idx[col[a]] - bl[j].b0) + (size_t)bl[j].n * (idx[col[b]] - bl[j].b0)] +=
                        w[a] * w[b];
    }
    return 0;
}

/* The distinct blocks (same_as), and whether the form pays: its flops (the
 * blocks' eigendecompositions, the N x N Cholesky and solves, the products
 * with W1 and Q) against the normal form's eigendecomposition of nr x nr
 * (about 4 nr^3 with the back-transformation).  Returns 1 when it does
 * not. */
static int kernel_pays(kernel *kn)
{
    const hfx_rows *x = kn->x;
    block *bl = kn->bl;
    int N = kn->N, nr = kn->nr;
    double ck = (double)N * N * N + 6.0 * nr * (double)N * N, cn = 4.0 * (double)nr * nr * nr;
    for (int j = 0; j < kn->nb; j++) {
        int n = bl[j].n;
        for (int i = 0; i < j && bl[j].same_as < 0 && n; i++)
            if (bl[i].n == n && bl[i].same_as < 0 &&
                memcmp(bl[i].K, bl[j].K, (size_t)n * n * sizeof *bl[j].K) == 0)
                bl[j].same_as = i;
        ck += 2.0 * n * (double)n * N +
              (bl[j].same_as < 0 && !(x->grid && x->grid[j] > 0) ? 4.0 * n * (double)n * n
                                                                  : 0.0);
    }
    return ck >= cn;
}

/* Eigendecompose each distinct block once (a grid's written down: OUT
 * dc->grid_blocks counts them); a repeated block shares the first's. */
static int block_eigen(kernel *kn, hfx_decomp *dc, glint_err *err)
{
    const hfx_rows *x = kn->x;
    block *bl = kn->bl;
    for (int j = 0; j < kn->nb; j++) {
        int n = bl[j].n;
        if (!n)
            continue;
        if (bl[j].same_as >= 0) {
            bl[j].Q = bl[bl[j].same_as].Q;
            bl[j].e = bl[bl[j].same_as].e;
            continue;
        }
        if (x->grid && x->grid[j] > 0) {
            int g = grid_eigen(&bl[j], x->grid[j]);
            if (g < 0)
                return glint_err_set(err, GLINT_ENOMEM, "out of memory");
            if (g == 0) {
                dc->grid_blocks++;
                continue;
            }
        }
        bl[j].Q = malloc((size_t)n * n * sizeof *bl[j].Q);
        bl[j].e = malloc((size_t)n * sizeof *bl[j].e);
        if (!bl[j].Q || !bl[j].e)
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        memcpy(bl[j].Q, bl[j].K, (size_t)n * n * sizeof *bl[j].Q);
        if (LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'U', n, bl[j].Q, n, bl[j].e) != 0)
            return glint_err_set(err, GLINT_ENUMERIC,
                                 "eigendecomposition of the smoothing failed");
    }
    return 0;
}

/* The columns of Q = blockdiag(Q_j): null (cls 0, eigenvalue at most
 * NULL_REL of the largest) or kept (cls 1); OUT k, m, emax, emin_pos.
 * Returns 1 (no kernel form) when the null space is empty or too large,
 * or nothing is kept. */
static int classify_columns(kernel *kn, glint_err *err)
{
    block *bl = kn->bl;
    int nr = kn->nr, k = 0;
    double emax = 0.0, emin_pos = INFINITY;
    for (int j = 0; j < kn->nb; j++)
        if (bl[j].n)
            emax = bl[j].e[bl[j].n - 1] > emax ? bl[j].e[bl[j].n - 1] : emax;
    kn->emax = emax;
    if (!(kn->cls = malloc((size_t)nr * sizeof *kn->cls)) ||
        !(kn->eig = malloc((size_t)nr * sizeof *kn->eig)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int j = 0; j < kn->nb; j++)
        for (int t = 0; t < bl[j].n; t++) {
            double e = bl[j].e[t];
            kn->eig[bl[j].b0 + t] = e;
            kn->cls[bl[j].b0 + t] = e > NULL_REL * emax;
            k += !kn->cls[bl[j].b0 + t];
            if (kn->cls[bl[j].b0 + t] && e < emin_pos)
                emin_pos = e;
        }
    kn->emin_pos = emin_pos;
    kn->k = k;
    kn->m = nr - k;
    return !(emax > 0.0) || k > KERNEL_NULL_MAX || k < 1 || kn->m < 1;
}

/* W = A Q (N x nr): a data row of A touches a few rows of Q; W0, W1 its
 * null and kept columns. */
static int data_columns(kernel *kn, glint_err *err)
{
    const hfx_rows *x = kn->x;
    const block *bl = kn->bl;
    int N = kn->N, nr = kn->nr, col[HFX_ROW_MAX];
    double w[HFX_ROW_MAX], *W;
    kn->W = W = calloc((size_t)N * nr, sizeof *W);
    kn->W0 = malloc((size_t)N * kn->k * sizeof *kn->W0);
    kn->W1 = malloc((size_t)N * kn->m * sizeof *kn->W1);
    if (!W || !kn->W0 || !kn->W1)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %dx%d", N, nr);
    for (int i = 0; i < N; i++) {
        int mm = x->row(x->ctx, i, col, w);
        for (int a = 0; a < mm; a++) {
            int t, j, l;
            if (w[a] == 0.0)
                continue;
            t = kn->idx[col[a]];
            j = kn->where[t];
            l = t - bl[j].b0;
            for (int c = 0; c < bl[j].n; c++)
                W[i + (size_t)N * (bl[j].b0 + c)] += w[a] * bl[j].Q[l + (size_t)bl[j].n * c];
        }
    }
    for (int t = 0, a = 0, b = 0; t < nr; t++)
        memcpy(kn->cls[t] ? kn->W1 + (size_t)N * b++ : kn->W0 + (size_t)N * a++,
               W + (size_t)N * t, (size_t)N * sizeof *W);
    return 0;
}

/* W0 = U S V^T; its range (rank r at rcond) is what eliminating a takes
 * out.  W is scratch from here. */
static int null_svd(kernel *kn, double rcond, glint_err *err)
{
    int N = kn->N, k = kn->k, kk = N < k ? N : k, r = 0;
    kn->kk = kk;
    kn->U = malloc((size_t)N * kk * sizeof *kn->U);
    kn->sv = malloc((size_t)kk * sizeof *kn->sv);
    kn->VT = malloc((size_t)kk * k * sizeof *kn->VT);
    if (!kn->U || !kn->sv || !kn->VT)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    memcpy(kn->W, kn->W0, (size_t)N * k * sizeof *kn->W);
    if (LAPACKE_dgesdd(LAPACK_COL_MAJOR, 'S', N, k, kn->W, N, kn->sv, kn->U, N, kn->VT, kk) != 0)
        return glint_err_set(err, GLINT_ENUMERIC, "SVD of the smoothing's null space failed");
    while (r < kk && kn->sv[r] > rcond * kn->sv[0] && kn->sv[r] > 0.0)
        r++;
    kn->r = r;
    return 0;
}

/* The N x N work matrices, and Mr = P W1 = W1 - U_r (U_r^T W1). */
static int project_kept(kernel *kn, glint_err *err)
{
    int N = kn->N, m = kn->m, r = kn->r;
    kn->C = malloc((size_t)N * N * sizeof *kn->C);
    kn->X = malloc((size_t)N * N * sizeof *kn->X);
    kn->T = malloc((size_t)N * N * sizeof *kn->T);
    kn->Y = malloc((size_t)kn->nr * N * sizeof *kn->Y);
    kn->Mr = malloc((size_t)N * m * sizeof *kn->Mr);
    if (!kn->C || !kn->X || !kn->T || !kn->Y || !kn->Mr)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %dx%d", N, N);
    memcpy(kn->Mr, kn->W1, (size_t)N * m * sizeof *kn->Mr);
    if (r) {
        double *UtW = malloc((size_t)r * m * sizeof *UtW);
        if (!UtW)
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        cblas_dgemm(CblasColMajor, CblasTrans, CblasNoTrans, r, m, N, 1.0, kn->U, N, kn->W1, N,
                    0.0, UtW, r);
        cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, N, m, r, -1.0, kn->U, N, UtW, r,
                    1.0, kn->Mr, N);
        free(UtW);
    }
    return 0;
}

/* C = I + S S^T with S = P W1 diag(e1^-1/2) (into W), then its Cholesky. */
static int kernel_cholesky(kernel *kn, glint_err *err)
{
    int N = kn->N, m = kn->m;
    double *W = kn->W, *C = kn->C;
    for (int t = 0, b = 0; t < kn->nr; t++)
        if (kn->cls[t]) {
            double sc = 1.0 / sqrt(kn->eig[t]);
            for (int i = 0; i < N; i++)
                W[i + (size_t)N * b] = kn->Mr[i + (size_t)N * b] * sc;
            b++;
        }
    memset(C, 0, (size_t)N * N * sizeof *C);
    for (int i = 0; i < N; i++)
        C[i + (size_t)N * i] = 1.0;
    cblas_dsyrk(CblasColMajor, CblasUpper, CblasNoTrans, N, m, 1.0, W, N, 1.0, C, N);
    if (LAPACKE_dpotrf(LAPACK_COL_MAJOR, 'U', N, C, N) != 0)
        return glint_err_set(err, GLINT_ENUMERIC, "Cholesky of the kernel matrix failed");
    return 0;
}

/* The kept columns' part: X = C^-1 P (P = I - U_r U_r^T), then
 * Mb = diag(1/e1) (P W1)^T X (m x N, into W), its rows into Y's kept
 * rows. */
static int kept_rows(kernel *kn, glint_err *err)
{
    int N = kn->N, nr = kn->nr, m = kn->m, r = kn->r;
    double *W = kn->W, *X = kn->X, *Y = kn->Y;
    memset(X, 0, (size_t)N * N * sizeof *X);
    for (int i = 0; i < N; i++)
        X[i + (size_t)N * i] = 1.0;
    if (r)
        cblas_dgemm(CblasColMajor, CblasNoTrans, CblasTrans, N, N, r, -1.0, kn->U, N, kn->U, N,
                    1.0, X, N);
    if (LAPACKE_dpotrs(LAPACK_COL_MAJOR, 'U', N, N, kn->C, N, X, N) != 0)
        return glint_err_set(err, GLINT_ENUMERIC, "kernel solve failed");
    cblas_dgemm(CblasColMajor, CblasTrans, CblasNoTrans, m, N, N, 1.0, kn->Mr, N, X, N, 0.0, W,
                m);
    for (int t = 0, b = 0; t < nr; t++)
        if (kn->cls[t]) {
            for (int i = 0; i < N; i++)
                W[b + (size_t)m * i] /= kn->eig[t];
            for (int i = 0; i < N; i++)
                Y[t + (size_t)nr * i] = W[b + (size_t)m * i];
            b++;
        }
    return 0;
}

/* The null columns' part: T = I - W1 Mb; Ma = V_r S_r^-1 U_r^T T (k x N),
 * into Y's null rows. */
static void null_rows(kernel *kn)
{
    int N = kn->N, nr = kn->nr, m = kn->m, r = kn->r, kk = kn->kk;
    double *X = kn->X, *T = kn->T;
    memset(T, 0, (size_t)N * N * sizeof *T);
    for (int i = 0; i < N; i++)
        T[i + (size_t)N * i] = 1.0;
    cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, N, N, m, -1.0, kn->W1, N, kn->W, m,
                1.0, T, N);
    /* X <- S_r^-1 U_r^T T (r x N), then Ma = V_r X */
    if (r)
        cblas_dgemm(CblasColMajor, CblasTrans, CblasNoTrans, r, N, N, 1.0, kn->U, N, T, N, 0.0,
                    X, r);
    for (int i = 0; i < N; i++)
        for (int q = 0; q < r; q++)
            X[q + (size_t)r * i] /= kn->sv[q];
    for (int t = 0, a = 0; t < nr; t++)
        if (!kn->cls[t]) {
            for (int i = 0; i < N; i++) {
                double acc = 0.0;
                for (int q = 0; q < r; q++)
                    acc += kn->VT[q + (size_t)kk * a] * X[q + (size_t)r * i];
                kn->Y[t + (size_t)nr * i] = acc;
            }
            a++;
        }
}

/* The operator M = Q Y block by block (through W), its rows back to every
 * unknown (OUT: dc->M). */
static int operator_rows(kernel *kn, hfx_decomp *dc, glint_err *err)
{
    const hfx_rows *x = kn->x;
    const block *bl = kn->bl;
    int N = kn->N, nr = kn->nr;
    if (!(dc->M = calloc((size_t)x->n * N, sizeof *dc->M)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the operator");
    for (int j = 0; j < kn->nb; j++) {
        int n = bl[j].n;
        if (!n)
            continue;
        cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, n, N, n, 1.0, bl[j].Q, n,
                    kn->Y + bl[j].b0, nr, 0.0, kn->W, n);
        for (int i = 0; i < N; i++)
            for (int t = x->off[j]; t < x->off[j + 1]; t++)
                if (kn->idx[t] >= 0)
                    dc->M[t + (size_t)x->n * i] = kn->W[(kn->idx[t] - bl[j].b0) + (size_t)n * i];
    }
    return 0;
}

static void kernel_free(kernel *kn)
{
    free(kn->Mr);
    free(kn->W);
    free(kn->W0);
    free(kn->W1);
    free(kn->U);
    free(kn->sv);
    free(kn->VT);
    free(kn->C);
    free(kn->X);
    free(kn->T);
    free(kn->Y);
    free(kn->cls);
    free(kn->eig);
    free(kn->where);
    blocks_free(kn->bl, kn->nb);
}

int hfx_kernel_build(const hfx_rows *x, const int *idx, int nr, double rcond, hfx_decomp *dc,
                     glint_err *err)
{
    kernel kn;
    int rc;

    if (x->nfactors < 1 || !x->off || x->nsmooth == 0)
        return 1;
    memset(&kn, 0, sizeof kn);
    kn.x = x;
    kn.idx = idx;
    kn.N = x->nsamples;
    kn.nr = nr;
    kn.nb = x->nfactors;
    if (!(kn.bl = calloc((size_t)kn.nb, sizeof *kn.bl)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    /* rc 1 from a step: the kernel form does not apply (or pay) here */
    if (!(rc = block_layout(&kn, err)) && !(rc = smoothing_blocks(&kn)) &&
        !(rc = kernel_pays(&kn)) && !(rc = block_eigen(&kn, dc, err)) &&
        !(rc = classify_columns(&kn, err)) && !(rc = data_columns(&kn, err)) &&
        !(rc = null_svd(&kn, rcond, err)) && !(rc = project_kept(&kn, err)) &&
        !(rc = kernel_cholesky(&kn, err)) && !(rc = kept_rows(&kn, err))) {
        null_rows(&kn);
        if (!(rc = operator_rows(&kn, dc, err))) {
            dc->form = "kernel";
            dc->rank = kn.m + kn.r;
            dc->s_max = sqrt(kn.emax);
            dc->s_min_kept = sqrt(kn.emin_pos);
        }
    }
    if (rc == 1)
        dc->grid_blocks = 0;
    kernel_free(&kn);
    return rc;
}
