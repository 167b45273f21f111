/* lsq_chol.c: the Cholesky factor of H over the solver's free variables
 * (lsq_impl.h), kept across the active-set iterations: a column added or
 * removed per bound that changes, a new factor when a block changes many. */
#include "internal/lsq_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Add variable j to the factor: R grows by a column (Rt y = H[ord, j]) and
 * a diagonal sqrt(H_jj - y.y); a pivot that vanishes (a column H already
 * spans) is raised to 1e-13 H_jj, a ridge on that variable alone. */
void lsq_chol_add(const lsq_problem *pr, lsq_work *w, int j)
{
    int n = pr->n, k = w->k;
    double d = pr->H[(size_t)j * n + j], *y = w->col;
    /* R' y = H[ord, j] by rows of R (contiguous), then y becomes column k */
    for (int i = 0; i < k; i++)
        y[i] = pr->H[(size_t)w->ord[i] * n + j];
    lsq_solve_rt(w, n, y);
    for (int i = 0; i < k; i++) {
        w->R[(size_t)i * n + k] = y[i];
        d -= y[i] * y[i];
    }
    {
        double hjj = pr->H[(size_t)j * n + j], floor_ = hjj > 0.0 ? 1e-13 * hjj : 1e-12 * w->dscale;
        if (!(d > floor_))
            d = floor_;
    }
    w->R[(size_t)k * n + k] = sqrt(d);
    w->ord[k] = j;
    w->at[j] = k;
    w->k = k + 1;
}

/* The Givens rotation of rows x and y over columns [c, end) that zeroes
 * y[c] and leaves x[c] = hypot(x[c], y[c]) >= 0; both removals use it. */
static void rotate_into(double *restrict x, double *restrict y, int c, int end)
{
    double a = x[c], b = y[c], aa = fabs(a), ab = fabs(b);
    double mx = aa > ab ? aa : ab;
    /* hypot without its call where squares cannot over- or underflow */
    double h = mx > 1e-150 && mx < 1e150 ? sqrt(a * a + b * b) : hypot(a, b);
    double cs = h > 0 ? a / h : 1.0, sn = h > 0 ? b / h : 0.0;
#pragma omp simd
    for (int col = c; col < end; col++) {
        double u = x[col], v = y[col];
        x[col] = cs * u + sn * v;
        y[col] = -sn * u + cs * v;
    }
}

/* Remove the variable at position p: its column leaves, Givens rotations
 * restore the triangle. */
void lsq_chol_remove(const lsq_problem *pr, lsq_work *w, int p)
{
    int n = pr->n, k = w->k;
    w->at[w->ord[p]] = -1;
    for (int c = p; c < k - 1; c++) {
        w->ord[c] = w->ord[c + 1];
        w->at[w->ord[c]] = c;
    }
    /* the column leaves: each row's tail moves left (contiguous) */
    for (int r = 0; r < k; r++)
        memmove(w->R + (size_t)r * n + p, w->R + (size_t)r * n + p + 1,
                (size_t)(k - 1 - p) * sizeof *w->R);
    for (int c = p; c < k - 1; c++)
        rotate_into(w->R + (size_t)c * n, w->R + (size_t)(c + 1) * n, c, k - 1);
    w->k = k - 1;
}

/* Remove every variable of the factor that is no longer free (isfree 0)
 * at once: each row of R is read once with those columns left out, and
 * the rows of the removed variables, kept aside, are rotated into each
 * kept row in turn (Givens), which restores the triangle.  The same
 * rotations as removing the columns one by one, without a shift of every
 * row per column. */
void lsq_chol_remove_unfree(const lsq_problem *pr, lsq_work *w)
{
    int n = pr->n, k = w->k, kk = 0, nz = 0;
    double *restrict v = w->col, *Z = w->K;
    int *keep = w->freev; /* the kept positions (freev is refilled per iteration) */

    for (int p = 0; p < k; p++)
        if (w->isfree[w->ord[p]])
            keep[kk++] = p;
    if (kk == k)
        return;
    for (int r = 0, c = 0; r < k; r++) {
        const double *rr = w->R + (size_t)r * n;
        int kept = w->isfree[w->ord[r]];
        /* row r on the kept columns: zero before column c (the first kept
         * position at or after r) */
        for (int a = 0; a < c; a++)
            v[a] = 0.0;
        for (int a = c; a < kk; a++)
            v[a] = rr[keep[a]];
        if (!kept) {
            if (c < kk) /* a removed row after the last kept one is zero */
                memcpy(Z + (size_t)nz++ * kk, v, (size_t)kk * sizeof *v);
            continue;
        }
        /* the rows set aside start at column c: rotate each into row r */
        for (int z = 0; z < nz; z++) {
            double *zr = Z + (size_t)z * kk;
            if (zr[c] != 0.0)
                rotate_into(v, zr, c, kk);
        }
        /* row r becomes row c of the factor (c <= r: that row was read) */
        memcpy(w->R + (size_t)c * n, v, (size_t)kk * sizeof *v);
        c++;
    }
    for (int p = 0; p < k; p++)
        if (!w->isfree[w->ord[p]])
            w->at[w->ord[p]] = -1;
    for (int a = 0; a < kk; a++) {
        w->ord[a] = w->ord[keep[a]];
        w->at[w->ord[a]] = a;
    }
    w->k = kk;
}

/* The factor of H over ord[0..k) into R (stride ld): a right-looking
 * Cholesky over contiguous rows, each pivot with lsq_chol_add's floor. */
static void chol_factor(const double *H, int n, const int *ord, int k, double dscale,
                        double *R, int ld)
{
    for (int i = 0; i < k; i++) {
        const double *h = H + (size_t)ord[i] * n;
        double *ri = R + (size_t)i * ld;
        for (int c = i; c < k; c++)
            ri[c] = h[ord[c]];
    }
    for (int i = 0; i < k; i++) {
        double *ri = R + (size_t)i * ld, d = ri[i];
        double hjj = H[(size_t)ord[i] * n + ord[i]];
        double floor_ = hjj > 0.0 ? 1e-13 * hjj : 1e-12 * dscale;
        if (!(d > floor_))
            d = floor_;
        d = sqrt(d);
        ri[i] = d;
        for (int c = i + 1; c < k; c++)
            ri[c] /= d;
        for (int r = i + 1; r < k; r++) {
            double *rr = R + (size_t)r * ld, f = ri[r];
            if (f == 0.0)
                continue;
#pragma omp simd
            for (int c = r; c < k; c++)
                rr[c] -= f * ri[c];
        }
    }
}

double lsq_diag_scale(const double *H, int n)
{
    double d = 0.0;
    for (int k = 0; k < n; k++)
        d = fmax(d, fabs(H[(size_t)k * n + k]));
    return d > 0.0 ? d : 1.0;
}

int lsq_factor(const double *H, int n, double *R, glint_err *err)
{
    int *ord;
    double z = 0.0;
    if (n < 1 || n > LSQ_MAX_N || !H || !R)
        return glint_err_set(err, GLINT_EINVAL, "lsq: factor of %d unknowns (1..%d)", n,
                             LSQ_MAX_N);
#pragma omp simd reduction(+ : z)
    for (size_t k = 0; k < (size_t)n * n; k++)
        z += 0.0 * H[k];
    if (z != 0.0)
        return glint_err_set(err, GLINT_EINVAL, "lsq: H is not finite");
    if (!(ord = malloc((size_t)n * sizeof *ord)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int j = 0; j < n; j++)
        ord[j] = j;
    memset(R, 0, (size_t)n * n * sizeof *R);
    chol_factor(H, n, ord, n, lsq_diag_scale(H, n), R, n);
    free(ord);
    return 0;
}

/* A new factor over the free variables (after a block step changed many of
 * them), in index order.  With the factor of the whole H at hand (pr->R0)
 * and few variables bound, that factor less the bound columns (each
 * removal about k^2/2 flops) costs less than factoring anew (k^3/3). */
void lsq_chol_rebuild(const lsq_problem *pr, lsq_work *w)
{
    int n = pr->n, k = 0;
    for (int j = 0; j < n; j++) {
        w->at[j] = -1;
        if (w->isfree[j]) {
            w->ord[k] = j;
            w->at[j] = k++;
        }
    }
    if (pr->R0 && 3.0 * (n - k) * n * n < 2.0 * k * k * k) {
        for (int j = 0; j < n; j++) {
            w->ord[j] = j;
            w->at[j] = j;
            memcpy(w->R + (size_t)j * n + j, pr->R0 + (size_t)j * n + j,
                   (size_t)(n - j) * sizeof *w->R);
        }
        w->k = n;
        lsq_chol_remove_unfree(pr, w);
        return;
    }
    w->k = k;
    chol_factor(pr->H, n, w->ord, k, w->dscale, w->R, n);
}

/* v <- R^-T v and v <- R^-1 v over the factor's k variables. */
void lsq_solve_rt(const lsq_work *w, int n, double *v)
{
    /* by rows of R (contiguous): each solved v_i updates the rest */
    for (int i = 0; i < w->k; i++) {
        const double *restrict ri = w->R + (size_t)i * n;
        double *restrict vv = v;
        double vi = (vv[i] /= ri[i]);
        if (vi != 0.0)
#pragma omp simd
            for (int c = i + 1; c < w->k; c++)
                vv[c] -= ri[c] * vi;
    }
}

void lsq_solve_r(const lsq_work *w, int n, double *v)
{
    for (int i = w->k - 1; i >= 0; i--) {
        const double *ri = w->R + (size_t)i * n;
        v[i] = (v[i] - lsq_dot4(ri + i + 1, v + i + 1, w->k - i - 1)) / ri[i];
    }
}

