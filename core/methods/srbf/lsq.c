/* lsq.c: constrained least squares on the Gram form (lsq.h).
 *
 * Primal active set (Nocedal & Wright, Algorithm 16.3) on
 *   minimize 1/2 c'Hc - q'c  subject to c >= 0, G c <= u,
 * which has the minimizer of ||Tc - f||^2.  The working set holds bounds
 * (c_j = 0: j not free) and rows (G_r c = u_r).  The upper Cholesky factor
 * R of H over the free variables is kept across iterations (a column added
 * or removed per bound that changes, refactored when a block changes many);
 * each iteration solves the equality-constrained problem on the free
 * variables in the range space of R: W = R^-T G_RF', (W'W) mu = W'z - u_R,
 * x_F = R^-1 (z - W mu) with z = R^-T q_F.  A pivot of R that vanishes (H
 * semidefinite on the free variables) is raised to 1e-13 of its diagonal,
 * a ridge on that variable alone, and rows that depend on others leave the
 * working set, so each step stays well defined.  A step to x that leaves
 * the feasible set stops at the first constraint it meets, which joins the
 * working set; at x itself the multipliers decide: the most negative one
 * (rows' mu, bounds' nu = (Hc - q + G_R' mu)_j) leaves the set (or every
 * negative bound at once, a block step, while blocks make progress), and
 * when none is negative (below -tol) c is optimal.  The iteration limit
 * is 20 (n + m) + 100. */
#include "lsq.h"
#include "internal/lsq_impl.h"

#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A block step that frees b variables onto a factor of k updates it one
 * column at a time (about b k^2 flops) while that costs less than a new
 * factor (k^3/3); one that binds b updates it while b is under 2k/3 (a
 * removal costs about k^2/2). */
static int block_incremental(int b, int k, int adding)
{
    return b <= 4 || b < (adding ? (k + b) / 3.0 : 2.0 * k / 3.0);
}

lsq_work *lsq_work_new(int n, int m)
{
    lsq_work *w = calloc(1, sizeof *w);
    size_t k = (size_t)n + (size_t)m + 1;
    if (!w)
        return NULL;
    w->n = n;
    w->m = m;
    w->freev = malloc((n + 1) * sizeof *w->freev);
    w->rows = malloc((m + 1) * sizeof *w->rows);
    w->isfree = malloc(n + 1);
    w->cand = malloc(n + 1);
    w->inrow = malloc(m + 1);
    w->noblock = calloc(m + 1, 1);
    /* eqp's W (rows x (free + 1)) and S (rows x rows): the working rows
     * are independent on the free variables, so at most n of them */
    w->K = malloc(((size_t)n * (n + 1) + (size_t)n * n + 1) * sizeof *w->K);
    w->rhs = malloc(k * sizeof *w->rhs);
    w->x = malloc((n + 1) * sizeof *w->x);
    w->p = malloc((n + 1) * sizeof *w->p);
    w->grad = malloc((n + 1) * sizeof *w->grad);
    w->gp = malloc((m + 1) * sizeof *w->gp);
    w->mu = malloc((m + 1) * sizeof *w->mu);
    w->up = malloc((m + 1) * sizeof *w->up);
    w->R = malloc(((size_t)n * n + 1) * sizeof *w->R);
    w->col = malloc((n + 1) * sizeof *w->col);
    w->gcu = malloc((m + 1) * sizeof *w->gcu);
    w->gpx = malloc((m + 1) * sizeof *w->gpx);
    w->gmax = malloc((m + 1) * sizeof *w->gmax);
    w->pblk = malloc(((size_t)2 * LSQ_NBLK(n) + 1) * sizeof *w->pblk);
    w->bnz = malloc((size_t)2 * LSQ_NBLK(n) + 1);
    w->bnd = malloc((m + 1) * sizeof *w->bnd);
    w->ord = malloc((n + 1) * sizeof *w->ord);
    w->at = malloc((n + 1) * sizeof *w->at);
    w->Q = malloc(((size_t)n + 1) * ((size_t)n + 1) * sizeof *w->Q);
    if (!w->gcu || !w->gpx || !w->gmax || !w->pblk || !w->bnz || !w->bnd || !w->up || !w->R ||
        !w->col || !w->ord ||
        !w->at || !w->Q || !w->freev || !w->rows || !w->isfree || !w->cand || !w->inrow ||
        !w->noblock || !w->K || !w->rhs || !w->x || !w->p || !w->grad || !w->gp || !w->mu) {
        lsq_work_free(w);
        return NULL;
    }
    return w;
}

void lsq_work_free(lsq_work *w)
{
    if (!w)
        return;
    free(w->freev);
    free(w->rows);
    free(w->isfree);
    free(w->cand);
    free(w->inrow);
    free(w->noblock);
    free(w->K);
    free(w->rhs);
    free(w->x);
    free(w->p);
    free(w->grad);
    free(w->gp);
    free(w->mu);
    free(w->Q);
    free(w->up);
    free(w->R);
    free(w->col);
    free(w->Gtw);
    free(w->gcu);
    free(w->gpx);
    free(w->gmax);
    free(w->gblkw);
    free(w->pblk);
    free(w->bnz);
    free(w->bnd);
    free(w->ord);
    free(w->at);
    free(w);
}

const char *lsq_status_name(lsq_status s)
{
    return s == LSQ_INFEASIBLE ? "infeasible" : s == LSQ_MAXITER ? "max_iterations" : "optimal";
}

/* Solve K x = b in place (k x k, row-major) by LU with partial pivoting:
 * the systems here are small (free variables plus active rows), where
 * a library call's threading costs more than the arithmetic.  Returns -1
 * when a pivot vanishes. */
static int lu_solve(double *K, double *b, int k, double tiny)
{
    for (int col = 0; col < k; col++) {
        int piv = col;
        double best = fabs(K[(size_t)col * k + col]);
        for (int r = col + 1; r < k; r++)
            if (fabs(K[(size_t)r * k + col]) > best) {
                best = fabs(K[(size_t)r * k + col]);
                piv = r;
            }
        if (!(best > tiny))
            return -1;
        if (piv != col) {
            for (int c = 0; c < k; c++) {
                double t = K[(size_t)col * k + c];
                K[(size_t)col * k + c] = K[(size_t)piv * k + c];
                K[(size_t)piv * k + c] = t;
            }
            double t = b[col];
            b[col] = b[piv];
            b[piv] = t;
        }
        for (int r = col + 1; r < k; r++) {
            double f = K[(size_t)r * k + col] / K[(size_t)col * k + col];
            if (f == 0.0)
                continue;
            for (int c = col; c < k; c++)
                K[(size_t)r * k + c] -= f * K[(size_t)col * k + c];
            b[r] -= f * b[col];
        }
    }
    for (int r = k - 1; r >= 0; r--) {
        double v = b[r];
        for (int c = r + 1; c < k; c++)
            v -= K[(size_t)r * k + c] * b[c];
        b[r] = v / K[(size_t)r * k + r];
    }
    return 0;
}

/* Row r of G restricted to the free variables, made orthogonal to the nq
 * rows of Q (modified Gram-Schmidt, twice); appended to Q and 1 returned
 * when it is independent of them (relative residual above 1e-9), else 0. */
static int add_to_basis(const lsq_problem *pr, lsq_work *w, int nf, int r, int nq)
{
    double *v = w->Q + (size_t)nq * nf, n0 = 0.0, n1 = 0.0;
    if (nq >= nf)
        return 0;
    for (int a = 0; a < nf; a++) {
        v[a] = pr->G[(size_t)r * pr->n + w->freev[a]];
        n0 += v[a] * v[a];
    }
    if (n0 <= 0.0)
        return 0;
    for (int pass = 0; pass < 2; pass++)
        for (int q = 0; q < nq; q++) {
            const double *u = w->Q + (size_t)q * nf;
            double d = 0.0;
            for (int a = 0; a < nf; a++)
                d += u[a] * v[a];
            for (int a = 0; a < nf; a++)
                v[a] -= d * u[a];
        }
    for (int a = 0; a < nf; a++)
        n1 += v[a] * v[a];
    if (n1 <= 1e-18 * n0)
        return 0;
    n1 = sqrt(n1);
    for (int a = 0; a < nf; a++)
        v[a] /= n1;
    return 1;
}

/* Solve the equality-constrained subproblem of the working set with the
 * factor: z = R^-T q_F, W = R^-T G_RF', (W'W) mu = W'z - u_R,
 * x_F = R^-1 (z - W mu).  OUT w->x (zero on bounds), w->mu. */
static int eqp(const lsq_problem *pr, lsq_work *w, int nf, int nr, double dscale)
{
    int n = pr->n, k = w->k;
    double *z = w->rhs, *W = w->K, *S = w->K + (size_t)nr * (k + 1);
    (void)nf;
    (void)dscale;
    for (int i = 0; i < k; i++)
        z[i] = pr->q[w->ord[i]];
    lsq_solve_rt(w, n, z);
    for (int r = 0; r < nr; r++) {
        double *wr = W + (size_t)r * (k + 1);
        for (int i = 0; i < k; i++)
            wr[i] = pr->G[(size_t)w->rows[r] * n + w->ord[i]];
        lsq_solve_rt(w, n, wr);
    }
    if (nr) {
        double *rhs = w->mu;
        for (int a = 0; a < nr; a++) {
            const double *wa = W + (size_t)a * (k + 1);
            rhs[a] = lsq_dot4(wa, z, k) - w->up[w->rows[a]];
            for (int b = 0; b < nr; b++)
                S[(size_t)a * nr + b] = lsq_dot4(wa, W + (size_t)b * (k + 1), k);
        }
        if (lu_solve(S, rhs, nr, 0.0))
            return -1;
        for (int a = 0; a < nr; a++) {
            const double *wa = W + (size_t)a * (k + 1);
            for (int i = 0; i < k; i++)
                z[i] -= rhs[a] * wa[i];
        }
    }
    lsq_solve_r(w, n, z);
    memset(w->x, 0, (size_t)n * sizeof *w->x);
    for (int i = 0; i < k; i++)
        w->x[w->ord[i]] = z[i];
    return 0;
}

static int solve_none(const lsq_problem *p, double rcond, double *c, lsq_result *res,
                      glint_err *err)
{
    int n = p->n, rank = 0;
    double *A = malloc((size_t)n * n * sizeof *A), *ev = malloc((size_t)n * sizeof *ev);
    lapack_int info;
    if (!A || !ev) {
        free(A);
        free(ev);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    memcpy(A, p->H, (size_t)n * n * sizeof *A);
    info = LAPACKE_dsyevd(LAPACK_ROW_MAJOR, 'V', 'U', n, A, n, ev);
    if (info) {
        free(A);
        free(ev);
        return glint_err_set(err, GLINT_ENUMERIC, "eigendecomposition failed (info %d)",
                             (int)info);
    }
    memset(c, 0, (size_t)n * sizeof *c);
    for (int k = 0; k < n; k++) {
        double proj = 0.0;
        if (!(ev[k] > rcond * ev[n - 1]) || ev[k] <= 0.0)
            continue;
        rank++;
        for (int i = 0; i < n; i++)
            proj += A[(size_t)i * n + k] * p->q[i];
        proj /= ev[k];
        for (int i = 0; i < n; i++)
            c[i] += proj * A[(size_t)i * n + k];
    }
    res->rank = rank;
    free(A);
    free(ev);
    return 0;
}

static void finish(const lsq_problem *p, lsq_mode mode, const double *c, lsq_result *res)
{
    int n = p->n;
    double obj = p->ff, viol = 0.0, slack = INFINITY;
    for (int i = 0; i < n; i++) {
        double hc = lsq_dot4(p->H + (size_t)i * n, c, n);
        obj += c[i] * hc - 2.0 * p->q[i] * c[i];
        if (mode != LSQ_NONE && -c[i] > viol)
            viol = -c[i];
        res->free_vars += c[i] > 0.0;
    }
    if (mode == LSQ_ENERGY)
        for (int r = 0; r < p->m; r++) {
            double g = lsq_dot4(p->G + (size_t)r * n, c, n);
            if (p->gc)
                p->gc[r] = g;
            if (g - p->u[r] > viol)
                viol = g - p->u[r];
            if (p->u[r] - g < slack)
                slack = p->u[r] - g;
        }
    res->objective = obj < 0.0 && obj > -1e-12 * (p->ff > 0 ? p->ff : 1.0) ? 0.0 : obj;
    res->max_violation = viol;
    res->min_slack = mode == LSQ_ENERGY && p->m > 0 ? slack : 0.0;
}

int lsq_rows_check(const double *G, int m, int n, double *gmax, double *Gt, glint_err *err)
{
    for (int r = 0; r < m; r++) {
        const double *g = G + (size_t)r * n;
        double gm = 0.0, z = 0.0;
        for (int j = 0; j < n; j++) {
            double a = fabs(g[j]);
            z += 0.0 * g[j]; /* NaN exactly when some entry is not finite */
            gm = a > gm ? a : gm;
        }
        if (z != 0.0)
            return glint_err_set(err, GLINT_EINVAL, "lsq: G is not finite (row %d)", r);
        if (gmax)
            gmax[r] = gm;
    }
    if (Gt) /* by blocks of rows, so that the writes stay in cache */
        for (int r0 = 0; r0 < m; r0 += 16)
            for (int j = 0; j < n; j++)
                for (int r = r0; r < m && r < r0 + 16; r++)
                    Gt[(size_t)j * m + r] = G[(size_t)r * n + j];
    return 0;
}

void lsq_rows_blocks(const double *G, int m, int n, double *gblk)
{
    int nb = LSQ_NBLK(n);
    for (int r = 0; r < m; r++) {
        const double *g = G + (size_t)r * n;
        for (int b = 0; b < nb; b++) {
            double hi = 0.0, lo = 0.0;
            for (int j = b * LSQ_BLK; j < n && j < (b + 1) * LSQ_BLK; j++) {
                hi = g[j] > hi ? g[j] : hi;
                lo = -g[j] > lo ? -g[j] : lo;
            }
            gblk[(size_t)b * m + r] = hi;
            gblk[(size_t)(nb + b) * m + r] = lo;
        }
    }
}

/* Start at p->c0 when it is feasible (c0 >= 0 and G c0 <= u, the caller's
 * budgets): c = c0, its positive entries free, G c exact.  Rows at their
 * budget (within the tightening of up) join the working set when the
 * first step would cross them, as any row does.  Returns 0 (c left at 0)
 * when c0 is not a feasible start. */
static int warm_start(const lsq_problem *p, lsq_work *w, int m, double *c)
{
    int n = p->n, nfree = 0;
    for (int j = 0; j < n; j++) {
        if (!(p->c0[j] >= 0.0) || !isfinite(p->c0[j]))
            return 0;
        nfree += p->c0[j] > 0.0;
    }
    if (!nfree)
        return 0;
    for (int r = 0; r < m; r++) {
        double g = lsq_dot4(p->G + (size_t)r * n, p->c0, n);
        if (!(g <= p->u[r]))
            return 0;
        w->gcu[r] = g;
    }
    memcpy(c, p->c0, (size_t)n * sizeof *c);
    for (int j = 0; j < n; j++)
        w->isfree[j] = c[j] > 0.0;
    lsq_chol_rebuild(p, w);
    return 1;
}

/* What the iteration carries from one step to the next, and the measures
 * of the step under way. */
typedef struct iter {
    int m;              /* rows enforced (LSQ_ENERGY's, else 0) */
    double qscale;      /* max |q_j| */
    double tol;         /* a multiplier below -tol is negative: 1e-11 qscale */
    int stalls;         /* steps that did not move c */
    int bland;          /* Bland's rule for this step (after more than 3 stalls) */
    int multi;          /* release every negative bound at once (see release) */
    double multi_obj;   /* the objective where the last block was released */
    int nnoblock;       /* rows marked in w->noblock */
    int keep_noblock;   /* the marks hold through the next step */
    int nf, nr;         /* the step's free variables and working rows */
    double pn, cn;      /* max |p_j| of the step, max |c_j| before it */
} iter;

/* A step's end along p: alpha in [0, 1], and the constraint that stops it
 * there (block -1: none, the step reaches x). */
typedef struct step {
    double alpha;
    int block;
    int block_row;      /* 1: block is a row, 0: a bound */
} step;

/* The constraints the multipliers release at a stationary point. */
typedef struct release {
    int drop;           /* the most negative multiplier's variable or row, -1: none */
    int drop_row;       /* 1: drop is a row */
    int nneg;           /* bounds with a negative multiplier (w->cand) */
    double obj;         /* c'Hc - 2 q'c there */
} release;

/* Sizes and finiteness of the problem; G's rows are checked here unless
 * the caller brings their maxima (lsq_rows_check vouched for them).
 * OUT: *qscale = max |q_j|, *dscale = max |H_jj|. */
static int check_problem(const lsq_problem *p, int m, double *qscale, double *dscale,
                         glint_err *err)
{
    int n = p->n, rc;
    double qs = 0.0, ds = 0.0;

    if (n < 1 || n > LSQ_MAX_N || m < 0 || m > LSQ_MAX_M || !p->H || !p->q ||
        (m && (!p->G || !p->u)))
        return glint_err_set(err, GLINT_EINVAL, "lsq: %d unknowns and %d rows (1..%d, 0..%d)",
                             n, m, LSQ_MAX_N, LSQ_MAX_M);
    {
        double z = 0.0;
#pragma omp simd reduction(+ : z)
        for (size_t k = 0; k < (size_t)n * n; k++)
            z += 0.0 * p->H[k];
        if (z != 0.0)
            return glint_err_set(err, GLINT_EINVAL, "lsq: H is not finite");
    }
    for (int k = 0; k < n; k++) {
        if (!isfinite(p->q[k]))
            return glint_err_set(err, GLINT_EINVAL, "lsq: q is not finite");
        qs = fmax(qs, fabs(p->q[k]));
        ds = fmax(ds, fabs(p->H[(size_t)k * n + k]));
    }
    if (m && !p->gmax && (rc = lsq_rows_check(p->G, m, n, NULL, NULL, err)))
        return rc;
    for (int r = 0; r < m; r++)
        if (!isfinite(p->u[r]))
            return glint_err_set(err, GLINT_EINVAL, "lsq: u is not finite");
    *qscale = qs;
    *dscale = ds;
    return 0;
}

/* Degeneracy: many rows can become tight at one point (a fitted diffuse
 * albedo enters every energy row alike), where an active-set method may
 * cycle.  Tightening each budget by a distinct amount below 1e-10 of the
 * largest separates them; the result holds the original budgets with that
 * much to spare.  OUT: w->up. */
static void tighten_budgets(const lsq_problem *p, lsq_work *w, int m)
{
    double umax = 0.0;
    for (int r = 0; r < m; r++)
        umax = fmax(umax, fabs(p->u[r]));
    for (int r = 0; r < m; r++)
        w->up[r] = p->u[r] - 1e-10 * umax * (1.0 + (double)r / m) * (p->u[r] > 0.0);
}

/* The cold start: c = 0, every variable bound, no working row, an empty
 * factor. */
static void start_empty(const lsq_problem *p, lsq_work *w, int m, double dscale, double *c)
{
    int n = p->n;
    memset(c, 0, (size_t)n * sizeof *c);
    memset(w->isfree, 0, (size_t)n);
    memset(w->inrow, 0, (size_t)m);
    memset(w->noblock, 0, (size_t)m);
    w->k = 0;
    w->dscale = dscale;
    for (int j = 0; j < n; j++)
        w->at[j] = -1;
}

/* The rows' tables the ratio test reads: max |G_rj| raised by 1e-12 (the
 * bound's rounding), G transposed and the block maxima, each the caller's
 * where it brings them, else made in the workspace; and the bound of G c
 * at c = 0. */
static int row_tables(const lsq_problem *p, lsq_work *w, int m, glint_err *err)
{
    int n = p->n;
    if (p->gmax)
        memcpy(w->gmax, p->gmax, (size_t)m * sizeof *w->gmax);
    /* sized for any problem the workspace fits */
    if (m && !p->Gt && !w->Gtw && !(w->Gtw = malloc((size_t)w->n * w->m * sizeof *w->Gtw)))
        return glint_err_set(err, GLINT_ENOMEM, "lsq: out of memory for %d rows", m);
    if (!p->gmax || (m && !p->Gt))
        lsq_rows_check(p->G, m, n, p->gmax ? NULL : w->gmax, p->Gt ? NULL : w->Gtw, NULL);
    w->Gt = p->Gt ? p->Gt : w->Gtw;
    if (m && !p->gblk) {
        if (!w->gblkw &&
            !(w->gblkw = malloc(((size_t)w->m * 2 * LSQ_NBLK(w->n) + 1) * sizeof *w->gblkw)))
            return glint_err_set(err, GLINT_ENOMEM, "lsq: out of memory for %d rows", m);
        lsq_rows_blocks(p->G, m, n, w->gblkw);
    }
    w->gblk = p->gblk ? p->gblk : w->gblkw;
    for (int b = 0; b < 2 * LSQ_NBLK(n) && m; b++) {
        const double *gb = w->gblk + (size_t)b * m;
        int nz = 0;
        for (int r = 0; r < m && !nz; r++)
            nz = gb[r] != 0.0;
        w->bnz[b] = (unsigned char)nz;
    }
    for (int r = 0; r < m; r++) {
        w->gmax[r] *= 1.0 + 1e-12;
        w->gcu[r] = 0.0;
    }
    return 0;
}

/* The step's working set: the free variables in the factor's order, and
 * the working rows that stay independent of each other on them; rows that
 * depend on others leave the working set, since they stay satisfied with
 * equality along any step it allows.  The rows marked not to block lose
 * the mark unless the last step asked to keep it. */
static void working_set(const lsq_problem *p, lsq_work *w, iter *it)
{
    if (it->nnoblock && !it->keep_noblock) {
        memset(w->noblock, 0, (size_t)it->m);
        it->nnoblock = 0;
    }
    it->keep_noblock = 0;
    it->nf = w->k;
    it->nr = 0;
    memcpy(w->freev, w->ord, (size_t)it->nf * sizeof *w->freev);
    for (int r = 0; r < it->m; r++)
        if (w->inrow[r]) {
            if (add_to_basis(p, w, it->nf, r, it->nr))
                w->rows[it->nr++] = r;
            else
                w->inrow[r] = 0;
        }
}

/* The step toward the subproblem's answer x: p = x - c; OUT it->pn, it->cn. */
static void direction(const lsq_problem *p, lsq_work *w, const double *c, iter *it)
{
    double pn = 0.0, cn = 0.0;
    for (int j = 0; j < p->n; j++) {
        w->p[j] = w->x[j] - c[j];
        double ap = fabs(w->p[j]), ac = fabs(c[j]); /* finite: no fmax call */
        pn = ap > pn ? ap : pn;
        cn = ac > cn ? ac : cn;
    }
    it->pn = pn;
    it->cn = cn;
}

/* At a stationary point of the working set, the multipliers: the bounds'
 * nu = (Hc - q + G_R' mu)_j (OUT: w->grad, and w->cand the bounds whose
 * nu is negative) and the rows' mu; OUT rl: the constraint to release
 * (the most negative multiplier, or under Bland's rule the lowest index,
 * bounds first), the count of negative bounds and the objective. */
static void multipliers(const lsq_problem *p, lsq_work *w, const double *c, const iter *it,
                        release *rl)
{
    int n = p->n, nr = it->nr, bland = it->bland;
    double tol = it->tol, worst = -tol, obj = 0.0;
    int drop = -1, drop_row = 0, nneg = 0;
    for (int j = 0; j < n; j++) {
        double gr = -p->q[j], hc = lsq_dot4(p->H + (size_t)j * n, c, n);
        gr += hc;
        obj += c[j] * (hc - 2.0 * p->q[j]);
        for (int r = 0; r < nr; r++)
            gr += p->G[(size_t)w->rows[r] * n + j] * w->mu[r];
        w->grad[j] = gr;
        /* Bland's rule after stalls: the lowest index, bounds first */
        /* a bound's multiplier counts relative to its column's
         * scale: ||T_j|| ||f|| (a weakly reached column gains much
         * from a small gradient) */
        double tj = p->ff > 0.0 ? 1e-12 * sqrt(fmax(p->H[(size_t)j * n + j], 0.0) * p->ff)
                                : tol;
        w->cand[j] = !w->isfree[j] && gr < -fmin(tol, tj);
        nneg += w->cand[j];
        if (w->cand[j] && (gr < worst || worst >= -tol) && !(bland && drop >= 0)) {
            worst = gr;
            drop = j;
            drop_row = 0;
        }
    }
    for (int r = 0; r < nr; r++)
        if (w->mu[r] < (bland ? -tol : worst) && !(bland && drop >= 0)) {
            worst = w->mu[r];
            drop = w->rows[r];
            drop_row = 1;
        }
    rl->drop = drop;
    rl->drop_row = drop_row;
    rl->nneg = nneg;
    rl->obj = obj;
}

/* c is optimal: the KKT residual over the free variables and the rows
 * that hold it. */
static void report_optimum(const lsq_problem *p, const lsq_work *w, const iter *it,
                           lsq_result *res)
{
    double kkt = 0.0;
    for (int j = 0; j < p->n; j++)
        if (w->isfree[j])
            kkt = fmax(kkt, fabs(w->grad[j]));
    res->kkt_residual = kkt / fmax(1.0, it->qscale);
    res->active_rows = it->nr;
    res->status = LSQ_OK;
}

/* Release what the multipliers chose: a row leaves the working set, or
 * bounds are freed.  Several bounds at once: every variable whose gradient
 * points into the feasible set is freed together (a block step, as block
 * pivoting does), which takes the dense solutions of painted fits in tens
 * of steps instead of one per lobe.  The step that follows can only lower
 * the objective; when a block brings no decrease by the next stationary
 * point (the freed variables all fell back at once), the method frees one
 * variable per step from then on, the classic rule, which terminates. */
static void release_constraints(const lsq_problem *p, lsq_work *w, iter *it, const release *rl)
{
    if (it->multi && it->multi_obj < HUGE_VAL &&
        !(rl->obj < it->multi_obj - 1e-13 * fabs(it->multi_obj)))
        it->multi = 0;
    if (rl->drop_row)
        w->inrow[rl->drop] = 0;
    else if (it->multi && !it->bland && rl->nneg > 1) {
        int inc = block_incremental(rl->nneg, w->k, 1);
        it->multi_obj = rl->obj;
        for (int j = 0; j < p->n; j++)
            if (w->cand[j]) {
                w->isfree[j] = 1;
                if (inc)
                    lsq_chol_add(p, w, j);
            }
        if (!inc)
            lsq_chol_rebuild(p, w);
    } else {
        w->isfree[rl->drop] = 1;
        lsq_chol_add(p, w, rl->drop);
    }
}

/* Free variables at zero that the step would take negative block it at
 * once: they all leave together (each holds its bound at the current
 * point, so c does not move).  Returns 1 when two or more were bound so. */
static int bind_zero_block(const lsq_problem *p, lsq_work *w, const double *c, const iter *it)
{
    int nz = 0, nf = it->nf;
    for (int a = 0; a < nf; a++) {
        int j = w->freev[a];
        if (c[j] == 0.0 && w->p[j] < 0.0)
            nz++;
    }
    if (nz <= 1)
        return 0;
    for (int a = 0; a < nf; a++) {
        int j = w->freev[a];
        if (c[j] == 0.0 && w->p[j] < 0.0)
            w->isfree[j] = 0;
    }
    if (block_incremental(nz, w->k, 0))
        lsq_chol_remove_unfree(p, w);
    else
        lsq_chol_rebuild(p, w);
    return 1;
}

/* The bounds' ratio test: the step stops at the first free variable it
 * takes to zero. */
static void bound_ratio(const lsq_work *w, const double *c, const iter *it, step *s)
{
    for (int a = 0; a < it->nf; a++) {
        int j = w->freev[a];
        if (w->p[j] < 0.0) {
            double t = -c[j] / w->p[j];
            if (t < s->alpha) { /* ties keep the lowest index (bounds before rows) */
                s->alpha = t;
                s->block = j;
                s->block_row = 0;
            }
        }
    }
}

/* Few free variables: G p for every row at once (OUT: w->gp), as a sum of
 * the free columns of G (contiguous rows of G', no reduction chain),
 * which costs less than any row skipped. */
static void rows_gp_by_columns(lsq_work *w, int m, int nf)
{
    /* four columns per pass: a load and a store of each sum per four
     * terms, not per term */
    double *restrict gpv = w->gp;
    int a = 0;
    memset(gpv, 0, (size_t)m * sizeof *gpv);
    for (; a + 4 <= nf; a += 4) {
        const double *restrict g0 = w->Gt + (size_t)w->freev[a] * m;
        const double *restrict g1 = w->Gt + (size_t)w->freev[a + 1] * m;
        const double *restrict g2 = w->Gt + (size_t)w->freev[a + 2] * m;
        const double *restrict g3 = w->Gt + (size_t)w->freev[a + 3] * m;
        double p0 = w->p[w->freev[a]], p1_ = w->p[w->freev[a + 1]];
        double p2 = w->p[w->freev[a + 2]], p3 = w->p[w->freev[a + 3]];
#pragma omp simd
        for (int r = 0; r < m; r++)
            gpv[r] += (p0 * g0[r] + p1_ * g1[r]) + (p2 * g2[r] + p3 * g3[r]);
    }
    for (; a < nf; a++) {
        const double *restrict gt = w->Gt + (size_t)w->freev[a] * m;
        double pj = w->p[w->freev[a]];
#pragma omp simd
        for (int r = 0; r < m; r++)
            gpv[r] += pj * gt[r];
    }
}

/* The bound of G p for every row at once (OUT: w->bnd): sums of the rows
 * of gblk weighted by the step's positive and negative mass per block
 * (contiguous, no reduction chain). */
static void rows_gp_bound(lsq_work *w, int n, int m, int nf)
{
    double *restrict bnd = w->bnd;
    int nb = LSQ_NBLK(n);
    memset(w->pblk, 0, (size_t)2 * nb * sizeof *w->pblk);
    for (int a = 0; a < nf; a++) {
        int j = w->freev[a];
        double pj = w->p[j];
        w->pblk[j / LSQ_BLK + (pj < 0.0) * nb] += fabs(pj);
    }
    memset(bnd, 0, (size_t)m * sizeof *bnd);
    for (int b = 0; b < 2 * nb; b++) {
        const double *restrict gb = w->gblk + (size_t)b * m;
        double pb = w->pblk[b] * (1.0 + 1e-12); /* the sums' rounding */
        if (pb == 0.0 || !w->bnz[b])
            continue;
#pragma omp simd
        for (int r = 0; r < m; r++)
            bnd[r] += pb * gb[r];
    }
}

/* The rows' ratio test: a row whose bound on G c plus the most this step
 * can add (from the rows' block maxima and the step's positive and
 * negative mass per block) stays under its budget cannot block; the
 * others' G p is computed exactly (OUT: w->gpx, NaN where skipped, and
 * w->gp the bound used there). */
static void row_ratio(const lsq_problem *p, lsq_work *w, const double *c, const iter *it,
                      step *s)
{
    int n = p->n, m = it->m, nf = it->nf, bycol = m && 2 * nf <= n;
    double p1 = 0.0, x1 = 0.0;
    for (int a = 0; a < nf; a++) {
        p1 += fabs(w->p[w->freev[a]]);
        x1 += fabs(w->x[w->freev[a]]);
    }
    if (bycol)
        rows_gp_by_columns(w, m, nf);
    else if (m)
        rows_gp_bound(w, n, m, nf);
    for (int r = 0; r < m; r++) {
        double gp, gc;
        if (w->inrow[r]) {
            w->gcu[r] = w->up[r];
            w->gpx[r] = 0.0;
            continue;
        }
        if (w->noblock[r]) {
            w->gpx[r] = NAN;
            w->gp[r] = w->gmax[r] * p1;
            continue;
        }
        if (bycol) {
            gp = w->gp[r];
        } else {
            double bound = w->bnd[r];
            if (w->gcu[r] + s->alpha * bound < w->up[r]) {
                w->gpx[r] = NAN; /* skipped: bounded */
                w->gp[r] = bound;
                continue;
            }
            /* p is zero on the bounds: a whole row, contiguous */
            gp = lsq_dot4(p->G + (size_t)r * n, w->p, n);
        }
        w->gpx[r] = gp;
        /* a gp at the rounding level of x (the step's end, whose
         * rounding G p inherits: a row that depends on the working rows
         * has G p = 0 up to that) has no sign, and the row cannot
         * block; it is then crossed by at most 1e-12 gmax |x|_1 */
        double eps = 1e-12 * w->gmax[r] * (p1 + x1);
        /* gcu bounds G c from above (to that rounding), so a row whose
         * step to the bound by gcu is no shorter than alpha cannot
         * block; the others' G c is computed exactly */
        if (gp > eps && w->up[r] - w->gcu[r] < s->alpha * gp + eps) {
            gc = lsq_dot4(p->G + (size_t)r * n, c, n);
            w->gcu[r] = gc;
            double t = (w->up[r] - gc) / gp;
            if (t < 0.0)
                t = 0.0;
            if (t < s->alpha) {
                s->alpha = t;
                s->block = r;
                s->block_row = 1;
            }
        }
    }
}

/* Move c by alpha p (and the bounds of G c with it); the constraint that
 * stopped the step joins the working set. */
static void move(const lsq_problem *p, lsq_work *w, double *c, iter *it, const step *s)
{
    double alpha = s->alpha;
    int block = s->block;
    for (int a = 0; a < it->nf; a++) {
        int j = w->freev[a];
        c[j] += alpha * w->p[j];
    }
    for (int r = 0; r < it->m; r++)
        w->gcu[r] += alpha * (isnan(w->gpx[r]) ? w->gp[r] : w->gpx[r]);
    if (alpha * it->pn <= 1e-14 * fmax(it->cn, 1e-300))
        it->stalls++;
    if (block < 0)
        return;
    if (s->block_row) {
        if (add_to_basis(p, w, it->nf, block, it->nr)) {
            w->inrow[block] = 1;
        } else if (alpha == 0.0) {
            /* a row that depends on the working rows has G p = 0:
             * what blocked is rounding, and it would block again
             * (until the working set or c changes) */
            w->noblock[block] = 1;
            it->nnoblock++;
            it->keep_noblock = 1;
        }
    } else {
        w->isfree[block] = 0;
        lsq_chol_remove(p, w, w->at[block]);
        c[block] = 0.0;
    }
}

/* The active-set iteration from the start in c and w: each step solves
 * the working set's subproblem, and at its answer releases constraints by
 * the multipliers (res->status LSQ_OK when none is negative), or moves
 * toward it as far as feasibility allows; LSQ_MAXITER after 20 (n + m) +
 * 100 steps. */
static int iterate(const lsq_problem *p, lsq_work *w, double *c, iter *it, lsq_result *res,
                   glint_err *err)
{
    int maxit = 20 * (p->n + it->m) + 100;
    res->status = LSQ_MAXITER;
    for (int k = 0; k < maxit; k++) {
        step s = {1.0, -1, 0};
        it->bland = it->stalls > 3;
        res->iterations = k + 1;
        working_set(p, w, it);
        if (eqp(p, w, it->nf, it->nr, w->dscale))
            return glint_err_set(err, GLINT_ENUMERIC, "lsq: the working-set system is singular");
        direction(p, w, c, it);
        if (it->pn <= 1e-10 * fmax(it->cn, 1e-300) || it->pn == 0.0) {
            release rl;
            multipliers(p, w, c, it, &rl);
            if (rl.drop < 0) {
                report_optimum(p, w, it, res);
                break;
            }
            release_constraints(p, w, it, &rl);
            continue;
        }
        if (!it->bland && bind_zero_block(p, w, c, it))
            continue;
        bound_ratio(w, c, it, &s);
        row_ratio(p, w, c, it, &s);
        move(p, w, c, it, &s);
    }
    return 0;
}

int lsq_solve(const lsq_problem *p, lsq_mode mode, double rcond, lsq_work *w, double *c,
              lsq_result *res, glint_err *err)
{
    int n = p->n, m = mode == LSQ_ENERGY ? p->m : 0, own = 0, rc;
    double dscale = 0.0, qscale = 0.0;
    iter it;

    memset(res, 0, sizeof *res);
    res->infeasible_row = -1;
    if ((rc = check_problem(p, m, &qscale, &dscale, err)))
        return rc;
    if (mode == LSQ_NONE) {
        if ((rc = solve_none(p, rcond > 0.0 ? rcond : 1e-12, c, res, err)))
            return rc;
        finish(p, mode, c, res);
        return 0;
    }
    /* c = 0 is the start: it must be feasible */
    for (int r = 0; r < m; r++)
        if (p->u[r] < 0.0) {
            memset(c, 0, (size_t)n * sizeof *c);
            res->status = LSQ_INFEASIBLE;
            res->infeasible_row = r;
            return 0;
        }
    if (!w) {
        if (!(w = lsq_work_new(n, m)))
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        own = 1;
    } else if (w->n < n || w->m < m) {
        return glint_err_set(err, GLINT_EINVAL, "lsq: workspace for %d x %d, problem %d x %d",
                             w->n, w->m, n, m);
    }
    memset(&it, 0, sizeof it);
    it.m = m;
    it.qscale = qscale;
    it.tol = 1e-11 * fmax(qscale, 1e-300);
    it.multi = 1;
    it.multi_obj = HUGE_VAL;
    tighten_budgets(p, w, m);
    start_empty(p, w, m, dscale > 0.0 ? dscale : 1.0, c);
    if (!(rc = row_tables(p, w, m, err))) {
        if (p->c0 && warm_start(p, w, m, c))
            res->warm = 1;
        rc = iterate(p, w, c, &it, res, err);
    }
    if (!rc)
        for (int j = 0; j < n; j++)
            if (c[j] < 0.0)
                c[j] = 0.0;
    if (own)
        lsq_work_free(w);
    if (!rc)
        finish(p, mode, c, res);
    return rc;
}
