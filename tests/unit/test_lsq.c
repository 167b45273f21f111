/* test_lsq.c: the constrained least-squares solver (lsq.h) against brute
 * force: for small problems every subset of constraints held with equality
 * is solved, the feasible candidates compared, and the best one must be
 * what lsq_solve finds.  Also the modes, infeasibility and bad input.
 * (The comparison with an independent solver, cvxopt, is
 * tests/ref/test_lsq_cvxopt.py.) */
#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "lsq.h"
#include "lsq_impl.h"

static double urand(void)
{
    return rand() / (double)RAND_MAX;
}

/* 1/2 c'Hc - q'c */
static double f(int n, const double *H, const double *q, const double *c)
{
    double v = 0;
    for (int i = 0; i < n; i++) {
        double hc = 0;
        for (int j = 0; j < n; j++)
            hc += H[i * n + j] * c[j];
        v += 0.5 * c[i] * hc - q[i] * c[i];
    }
    return v;
}

/* The best feasible point over every set of active constraints (bounds
 * c_j = 0 for j in the mask's low n bits, rows G_r c = u_r for the high
 * bits), each solved as an equality-constrained QP by LAPACK. */
static double brute(int n, int m, const double *H, const double *q, const double *G,
                    const double *u, double *best_c)
{
    double best = INFINITY;
    for (long mask = 0; mask < (1L << (n + m)); mask++) {
        int k = 0, free_[16], nf = 0, rows[16], nr = 0;
        double K[32 * 32], rhs[32], c[16];
        lapack_int piv[32];
        for (int j = 0; j < n; j++)
            if (!(mask >> j & 1))
                free_[nf++] = j;
        for (int r = 0; r < m; r++)
            if (mask >> (n + r) & 1)
                rows[nr++] = r;
        k = nf + nr;
        memset(K, 0, sizeof K);
        for (int a = 0; a < nf; a++) {
            for (int b = 0; b < nf; b++)
                K[a * k + b] = H[free_[a] * n + free_[b]];
            for (int r = 0; r < nr; r++)
                K[a * k + nf + r] = K[(nf + r) * k + a] = G[rows[r] * n + free_[a]];
            rhs[a] = q[free_[a]];
        }
        for (int r = 0; r < nr; r++)
            rhs[nf + r] = u[rows[r]];
        if (k && LAPACKE_dgesv(LAPACK_ROW_MAJOR, k, 1, K, k, piv, rhs, 1))
            continue;
        memset(c, 0, sizeof c);
        for (int a = 0; a < nf; a++)
            c[free_[a]] = rhs[a];
        int ok = 1;
        for (int j = 0; j < n; j++)
            ok &= c[j] >= -1e-10;
        for (int r = 0; r < m; r++) {
            double g = 0;
            for (int j = 0; j < n; j++)
                g += G[r * n + j] * c[j];
            ok &= g <= u[r] + 1e-10;
        }
        if (ok && f(n, H, q, c) < best) {
            best = f(n, H, q, c);
            memcpy(best_c, c, n * sizeof *c);
        }
    }
    return best;
}

static void random_problem(int n, int m, int N, double *H, double *q, double *G, double *u)
{
    double A[64 * 8], b[64];
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < n; j++)
            A[i * n + j] = urand() - 0.3;
        b[i] = urand() * 2 - 0.2;
    }
    for (int i = 0; i < n; i++) {
        q[i] = 0;
        for (int k = 0; k < N; k++)
            q[i] += A[k * n + i] * b[k];
        for (int j = 0; j < n; j++) {
            H[i * n + j] = 0;
            for (int k = 0; k < N; k++)
                H[i * n + j] += A[k * n + i] * A[k * n + j];
        }
    }
    for (int r = 0; r < m; r++) {
        for (int j = 0; j < n; j++)
            G[r * n + j] = urand();
        u[r] = 0.05 + 0.3 * urand();
    }
}

TEST(matches_brute_force_on_small_problems)
{
    srand(11);
    for (int trial = 0; trial < 300; trial++) {
        int n = 1 + trial % 5, m = trial % 4;
        double H[64], q[8], G[64], u[8], c[8], cb[8], fb, gmax[8], Gt[64], c2[8], R0[64];
        lsq_problem p;
        lsq_result r, r2;
        glint_err e;
        random_problem(n, m, 12, H, q, G, u);
        p = (lsq_problem){.n = n, .H = H, .q = q, .m = m, .G = G, .u = u};
        ASSERT_OK(lsq_solve(&p, m ? LSQ_ENERGY : LSQ_NONNEG, 0, NULL, c, &r, &e));
        /* rows checked once and shared (as a fit's three channels do): the
         * same steps, the same answer to the bit */
        ASSERT_OK(lsq_rows_check(G, m, n, gmax, Gt, &e));
        p.gmax = gmax;
        p.Gt = Gt;
        ASSERT_OK(lsq_solve(&p, m ? LSQ_ENERGY : LSQ_NONNEG, 0, NULL, c2, &r2, &e));
        ASSERT(r2.iterations == r.iterations);
        for (int j = 0; j < n; j++)
            ASSERT_MSG(c2[j] == c[j], "trial %d: c[%d] %.17g with shared rows, %.17g without",
                       trial, j, c2[j], c[j]);
        /* and with the factor of H kept by the caller: the same optimum */
        ASSERT_OK(lsq_factor(H, n, R0, &e));
        p.R0 = R0;
        ASSERT_OK(lsq_solve(&p, m ? LSQ_ENERGY : LSQ_NONNEG, 0, NULL, c2, &r2, &e));
        ASSERT_MSG(fabs(f(n, H, q, c2) - f(n, H, q, c)) <= 1e-10 * (1 + fabs(f(n, H, q, c))),
                   "trial %d: %.12g with the kept factor, %.12g without", trial,
                   f(n, H, q, c2), f(n, H, q, c));
        ASSERT(r2.max_violation <= 1e-9);
        ASSERT_MSG(r.status == LSQ_OK, "trial %d: %s", trial, lsq_status_name(r.status));
        fb = brute(n, m, H, q, G, u, cb);
        ASSERT_MSG(f(n, H, q, c) <= fb + 1e-9 * (1 + fabs(fb)),
                   "trial %d (n %d, m %d): %.12g against brute force %.12g", trial, n, m,
                   f(n, H, q, c), fb);
        ASSERT(r.max_violation <= 1e-9);
        /* warm starts: from this optimum (of another q: a repaint) and from
         * a point that breaks the rows or the bounds (ignored): the same
         * optimum as the brute force */
        {
            double q2[8], c3[8], cbad[9]; /* cbad + 1 is a start of n entries too */
            lsq_problem p2 = p;
            lsq_result r3;
            for (int j = 0; j < n; j++)
                q2[j] = q[j] + 0.3 * (2.0 * urand() - 1.0);
            for (int j = 0; j <= n; j++)
                cbad[j] = j == 0 ? -1.0 : 1e3;
            p2.q = q2;
            p2.R0 = NULL;
            for (int start = 0; start < 3; start++) {
                double fb2;
                p2.c0 = start == 0 ? c : start == 1 ? cbad : cbad + 1;
                if (start == 2 && n < 2)
                    continue;
                ASSERT_OK(lsq_solve(&p2, m ? LSQ_ENERGY : LSQ_NONNEG, 0, NULL, c3, &r3, &e));
                {
                    /* usable: c0 >= 0, not all zero, G c0 <= u */
                    int ok = 0;
                    for (int j = 0; j < n; j++) {
                        ok |= p2.c0[j] > 0.0;
                        if (p2.c0[j] < 0.0)
                            ok = -n - 1;
                    }
                    for (int k = 0; k < m && ok > 0; k++) {
                        double g = 0.0;
                        for (int j = 0; j < n; j++)
                            g += G[k * n + j] * p2.c0[j];
                        ok = g <= u[k];
                    }
                    ASSERT_MSG(r3.warm == (ok > 0), "trial %d start %d: warm %d", trial, start,
                               r3.warm);
                }
                fb2 = brute(n, m, H, q2, G, u, cb);
                ASSERT_MSG(fabs(f(n, H, q2, c3) - fb2) <= 1e-9 * (1 + fabs(fb2)),
                           "trial %d start %d: %.12g against brute force %.12g", trial, start,
                           f(n, H, q2, c3), fb2);
                ASSERT(r3.max_violation <= 1e-9 && r3.status == LSQ_OK);
            }
        }
    }
}

TEST(modes_infeasibility_and_bad_input)
{
    double H[4] = {2, 0, 0, 1}, q[2] = {-1, 3}, G[2] = {1, 1}, u[1] = {1}, c[2];
    lsq_problem p = {.n = 2, .H = H, .q = q, .m = 1, .G = G, .u = u};
    lsq_result r;
    glint_err e;
    /* none: the unconstrained minimum H^-1 q */
    ASSERT_OK(lsq_solve(&p, LSQ_NONE, 0, NULL, c, &r, &e));
    ASSERT_NEAR(c[0], -0.5, 1e-12);
    ASSERT_NEAR(c[1], 3.0, 1e-12);
    ASSERT_EQ(r.rank, 2);
    /* nonneg: c0 clamps at 0 */
    ASSERT_OK(lsq_solve(&p, LSQ_NONNEG, 0, NULL, c, &r, &e));
    ASSERT_NEAR(c[0], 0.0, 1e-15);
    ASSERT_NEAR(c[1], 3.0, 1e-12);
    /* energy: c0 + c1 <= 1 binds */
    ASSERT_OK(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e));
    ASSERT_NEAR(c[1], 1.0, 1e-8);
    ASSERT_EQ(r.active_rows, 1);
    /* a negative budget: infeasible, reported with its row */
    u[0] = -0.1;
    ASSERT_OK(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e));
    ASSERT_EQ(r.status, LSQ_INFEASIBLE);
    ASSERT_EQ(r.infeasible_row, 0);
    /* a zero budget: c = 0 is the only point */
    u[0] = 0.0;
    ASSERT_OK(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e));
    ASSERT(r.status == LSQ_OK && c[0] == 0.0 && c[1] == 0.0);
    /* all-zero data: c = 0 */
    q[0] = q[1] = 0.0;
    u[0] = 1.0;
    ASSERT_OK(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e));
    ASSERT(c[0] == 0.0 && c[1] == 0.0);
    H[3] = NAN;
    ASSERT_EQ(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e), GLINT_EINVAL);
    H[3] = 1;
    /* non-finite rows, each alone: G, u; and an infinite H entry */
    G[1] = INFINITY;
    ASSERT_EQ(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e), GLINT_EINVAL);
    ASSERT_EQ(lsq_rows_check(G, 1, 2, NULL, NULL, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "not finite") != NULL);
    G[1] = 1;
    u[0] = NAN;
    ASSERT_EQ(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e), GLINT_EINVAL);
    u[0] = 1.0;
    H[0] = -INFINITY;
    ASSERT_EQ(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e), GLINT_EINVAL);
    H[0] = 2;
    ASSERT_OK(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e));
    p.n = 0;
    ASSERT_EQ(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e), GLINT_EINVAL);
}

/* Many columns leave the factor at once (lsq_chol_remove_unfree, a block
 * step): the result must be the Cholesky factor of H over the variables
 * left, which LAPACK's dpotrf computes independently (the factor with a
 * positive diagonal is unique).  None, the first, the last, all but one,
 * all, every other one and random halves, at sizes 1 to 147. */
TEST(many_columns_leave_the_factor_at_once)
{
    static const int sizes[] = {1, 2, 7, 40, 147};
    srand(5);
    for (int si = 0; si < 5; si++) {
        int n = sizes[si];
        for (int pat = 0; pat < 8; pat++) {
            double *A = malloc((size_t)n * n * sizeof *A), *H = malloc((size_t)n * n * sizeof *H);
            double *S = malloc((size_t)n * n * sizeof *S);
            int *keep = malloc((size_t)n * sizeof *keep), kk = 0;
            lsq_work *w = lsq_work_new(n, 0);
            lsq_problem p = {.n = n};
            glint_err e;
            ASSERT(A && H && S && keep && w);
            /* H = A'A + n I: well conditioned, dense */
            for (int i = 0; i < n * n; i++)
                A[i] = urand() - 0.5;
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++) {
                    double s = i == j ? n : 0.0;
                    for (int k = 0; k < n; k++)
                        s += A[k * n + i] * A[k * n + j];
                    H[i * n + j] = s;
                }
            p.H = H;
            ASSERT_OK(lsq_factor(H, n, w->R, &e));
            w->k = n;
            w->dscale = 1.0;
            for (int j = 0; j < n; j++) {
                int free_ = pat == 0   ? 1
                            : pat == 1 ? j != 0
                            : pat == 2 ? j != n - 1
                            : pat == 3 ? j == n / 2
                            : pat == 4 ? 0
                            : pat == 5 ? j % 2
                                       : urand() < 0.5;
                w->ord[j] = j;
                w->at[j] = j;
                w->isfree[j] = (unsigned char)free_;
                if (free_)
                    keep[kk++] = j;
            }
            lsq_chol_remove_unfree(&p, w);
            ASSERT_EQ(w->k, kk);
            for (int a = 0; a < kk; a++) {
                ASSERT_EQ(w->ord[a], keep[a]);
                ASSERT_EQ(w->at[keep[a]], a);
                for (int b = 0; b < kk; b++)
                    S[a * kk + b] = H[keep[a] * n + keep[b]];
            }
            if (kk) {
                double worst = 0.0, big = 0.0;
                ASSERT_EQ(LAPACKE_dpotrf(LAPACK_ROW_MAJOR, 'U', kk, S, kk), 0);
                for (int a = 0; a < kk; a++)
                    for (int b = a; b < kk; b++) {
                        worst = fmax(worst, fabs(w->R[(size_t)a * n + b] - S[a * kk + b]));
                        big = fmax(big, fabs(S[a * kk + b]));
                    }
                ASSERT_MSG(worst <= 1e-12 * big, "n %d pattern %d: %d kept, |R - dpotrf| %.3g of %.3g",
                           n, pat, kk, worst, big);
            }
            lsq_work_free(w);
            free(A);
            free(H);
            free(S);
            free(keep);
        }
    }
}

/* lsq_problem.gc: the solver hands back G c at its answer, as computed
 * here from c. */
TEST(the_rows_at_the_answer_are_handed_back)
{
    srand(7);
    for (int trial = 0; trial < 50; trial++) {
        int n = 2 + trial % 5, m = 1 + trial % 4;
        double H[64], q[8], G[64], u[8], c[8], gc[8];
        lsq_problem p;
        lsq_result r;
        glint_err e;
        random_problem(n, m, 12, H, q, G, u);
        p = (lsq_problem){.n = n, .H = H, .q = q, .m = m, .G = G, .u = u, .gc = gc};
        ASSERT_OK(lsq_solve(&p, LSQ_ENERGY, 0, NULL, c, &r, &e));
        for (int l = 0; l < m; l++) {
            double g = 0.0;
            for (int j = 0; j < n; j++)
                g += G[l * n + j] * c[j];
            ASSERT_NEAR(gc[l], g, 1e-14 * (1.0 + fabs(g)));
            ASSERT_LE(gc[l], u[l] + 1e-9);
        }
    }
}

TEST_LIST{
    TEST_ENTRY(matches_brute_force_on_small_problems),
    TEST_ENTRY(modes_infeasibility_and_bad_input),
    TEST_ENTRY(many_columns_leave_the_factor_at_once),
    TEST_ENTRY(the_rows_at_the_answer_are_handed_back),
};

TEST_MAIN()
