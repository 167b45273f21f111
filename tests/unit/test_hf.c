/* Unit tests of the fast homomorphic factorization numerics (core/hf*):
 * projections, hat weights and rows, the pseudo-inverse against LAPACK,
 * regularizations, mappings, RGB and precision.  Extreme inputs and the
 * range of the log-factors are in test_hf_range.c. */
#include <float.h>
#include <lapacke.h>
#include <unistd.h>

#include "check.h"
#include "hf.h"
#include "hf_fixture.h"
#include "hf_int.h"
#include "pcache.h"
#include "samples.h"
#include "sphere_fixture.h"

/* Reference least-squares solve of B y = [f~; 0] with gelsd, explicit rcond.
 * f: 3n values (sample-major); OUT y: 3R x 3 channel-minor. */
static int gelsd_solve(const hf_design *d, double lambda, const double *f, double *y,
                       double rcond, int *rank_out)
{
    int rows, ldb, n = 3 * d->res;
    double *B = hf_dense_B(d, lambda, &rows, &ldb);
    double *rhs = calloc((size_t)rows * 3, sizeof *rhs);
    double *sv = malloc((size_t)n * sizeof *sv);
    lapack_int rank = 0, info;
    for (int i = 0; i < d->n; i++)
        for (int c = 0; c < 3; c++)
            rhs[i + (size_t)rows * c] = f[3 * i + c];
    info = LAPACKE_dgelsd(LAPACK_COL_MAJOR, rows, n, 3, B, ldb, rhs, rows, sv, rcond, &rank);
    for (int k = 0; k < n; k++)
        for (int c = 0; c < 3; c++)
            y[3 * k + c] = rhs[k + (size_t)rows * c];
    if (rank_out)
        *rank_out = (int)rank;
    free(B);
    free(rhs);
    free(sv);
    return (int)info;
}

static double rel_diff(const double *a, const double *b, int len)
{
    double num = 0.0, den = 0.0;
    for (int i = 0; i < len; i++) {
        num += (a[i] - b[i]) * (a[i] - b[i]);
        den += b[i] * b[i];
    }
    return sqrt(num / (den > 0 ? den : 1.0));
}

/* Log-mapped values of a painting as the fit sees them (mapping add:0.1). */
static double *mapped(const samples *s, const float *rgb)
{
    double *f = malloc((size_t)3 * s->n * sizeof *f);
    for (int i = 0; i < 3 * s->n; i++)
        f[i] = log(0.1 + rgb[i]);
    return f;
}

/* ---- projections, hat weights, rows ---------------------------------------- */

TEST(projections_known_vectors)
{
    double n[3] = {0, 0, 1}, pi[3];
    double a = 0.6;
    double wi[3] = {sin(a), 0, cos(a)}, wo[3] = {0, 0, 1};
    hf_project(n, wi, wo, pi);
    ASSERT_NEAR(pi[0], sin(a), 1e-15);
    ASSERT_NEAR(pi[1], sin(a / 2), 1e-15); /* h bisects wi and wo */
    ASSERT_NEAR(pi[2], 0.0, 1e-15);
    /* grazing: wi in the tangent plane gives 1; mirror pair gives pi_q = 0 */
    double wg[3] = {1, 0, 0}, wm[3] = {-sin(a), 0, cos(a)};
    hf_project(n, wg, wm, pi);
    ASSERT_NEAR(pi[0], 1.0, 1e-15);
    hf_project(n, wi, wm, pi);
    ASSERT_NEAR(pi[1], 0.0, 1e-15);
    ASSERT_NEAR(pi[0], pi[2], 1e-15);
    /* a tilted normal: invariance under rotation of the whole frame */
    double n2[3] = {0, sin(0.3), cos(0.3)};
    v3 R_wi = v3_rotate(v3_load(wi), v3_make(1, 0, 0), -0.3);
    v3 R_wo = v3_rotate(v3_load(wo), v3_make(1, 0, 0), -0.3);
    double wi2[3], wo2[3], pi2[3];
    v3_store(R_wi, wi2);
    v3_store(R_wo, wo2);
    hf_project(n, wi, wo, pi);
    hf_project(n2, wi2, wo2, pi2);
    for (int j = 0; j < 3; j++)
        ASSERT_NEAR(pi[j], pi2[j], 1e-14);
}

TEST(hat_weights)
{
    int k;
    double t;
    hf_hat(0.0, 8, &k, &t);
    ASSERT_EQ(k, 0);
    ASSERT_NEAR(t, 0.0, 0);
    hf_hat(1.0, 8, &k, &t);
    ASSERT_EQ(k, 6);
    ASSERT_NEAR(t, 1.0, 0);
    hf_hat(0.5, 3, &k, &t);
    ASSERT_EQ(k, 1);
    ASSERT_NEAR(t, 0.0, 0);
    hf_hat(3.5 / 7.0, 8, &k, &t);
    ASSERT_EQ(k, 3);
    ASSERT_NEAR(t, 0.5, 1e-15);
    hf_hat(NAN, 8, &k, &t); /* never an out-of-range index */
    ASSERT(k >= 0 && k <= 6 && isfinite(t));
    hf_hat(-2.0, 8, &k, &t);
    ASSERT_EQ(k, 0);
}

/* hf_design_build's vectorized loop against hf_project and hf_hat, sample
 * by sample and bit for bit, on random directions and on the inputs where
 * the two could part: a half vector of zero length (wi = -wo), lengths
 * whose squares underflow or overflow, NaN and infinities, -0, vectors
 * longer than 1 (the tangent length clamped), texel boundaries; at the
 * smallest, a middle and the largest resolution.  The count is odd, so the
 * loop's remainder runs too, and large enough to take the worker pool. */
TEST(design_matches_project_and_hat)
{
    enum { N = 200003 };
    static const float odd[][9] = {
        {0, 0, 1, 0.6f, 0, 0.8f, -0.6f, 0, -0.8f},      /* wi = -wo: h = 0 */
        {0, 0, 1, 1e-30f, 0, 0, -1e-30f, 1e-30f, 0},    /* |h|^2 underflows */
        {0, 0, 1, 3e30f, 0, 0, 0, 3e30f, 0},            /* |h|^2 overflows */
        {0, 0, 0, 0.6f, 0, 0.8f, 0, 0.6f, 0.8f},        /* zero normal */
        {NAN, 0, 1, 0.6f, 0, 0.8f, 0, 0.6f, 0.8f},
        {0, 0, 1, NAN, 0, 0.8f, 0, 0.6f, 0.8f},
        {0, 0, 1, 0.6f, 0, 0.8f, 0, INFINITY, 0.8f},
        {0, 0, 1, -INFINITY, 0, 0.8f, 0, 0.6f, 0.8f},
        {-0.0f, -0.0f, 1, -0.0f, 0, 1, 0, -0.0f, 1},    /* all along n */
        {0, 0, 1, 2, 0, 0, 0, 3, 0},                     /* tangents > 1: clamped */
        {0, 0, 1, 0.5f, 0, 0.8660254f, 0, 0.25f, 0.9682458f},
        {0, 0, 1, 1, 0, 0, 0, 1, 0},                     /* u = 1 exactly */
        {0, 0, -1, 0.6f, 0, 0.8f, 0, 0.6f, 0.8f},       /* back-facing */
    };
    const int nodd = (int)(sizeof odd / sizeof odd[0]), res[] = {HF_RES_MIN, 64, HF_RES_MAX};
    samples s;
    unsigned rng = 12345u;
    memset(&s, 0, sizeof s);
    s.n = N;
    s.nrm = malloc((size_t)3 * N * sizeof *s.nrm);
    s.wi = malloc((size_t)3 * N * sizeof *s.wi);
    s.wo = malloc((size_t)3 * N * sizeof *s.wo);
    s.cos_i = malloc((size_t)N * sizeof *s.cos_i);
    ASSERT(s.nrm && s.wi && s.wo && s.cos_i);
    for (int i = 0; i < N; i++) {
        float *v[3] = {s.nrm + 3 * i, s.wi + 3 * i, s.wo + 3 * i};
        if (i < nodd || i >= N - nodd) {
            const float *o = odd[i < nodd ? i : i - (N - nodd)];
            for (int k = 0; k < 9; k++)
                v[k / 3][k % 3] = o[k];
        } else {
            for (int a = 0; a < 3; a++) {
                double x[3], l = 0;
                for (int k = 0; k < 3; k++) {
                    rng = rng * 1664525u + 1013904223u;
                    x[k] = (double)(rng >> 8) / 8388608.0 - 1.0;
                    l += x[k] * x[k];
                }
                l = sqrt(l) > 1e-3 ? sqrt(l) : 1.0;
                for (int k = 0; k < 3; k++)
                    v[a][k] = (float)(x[k] / l);
            }
        }
        s.cos_i[i] = 0.25 + (double)(i % 7);
    }
    for (unsigned r = 0; r < sizeof res / sizeof res[0]; r++) {
        hf_design d;
        long mism = 0;
        ASSERT_OK(hf_design_build(&s, res[r], &d, NULL));
        for (int i = 0; i < N; i++) {
            double n[3], wi[3], wo[3], pi[3];
            for (int k = 0; k < 3; k++) {
                n[k] = s.nrm[3 * i + k];
                wi[k] = s.wi[3 * i + k];
                wo[k] = s.wo[3 * i + k];
            }
            hf_project(n, wi, wo, pi);
            for (int j = 0; j < 3; j++) {
                int k;
                double t;
                hf_hat(pi[j], res[r], &k, &t);
                if (d.k0[3 * i + j] != k || memcmp(&d.t[3 * i + j], &t, sizeof t) != 0) {
                    if (mism++ < 5)
                        fprintf(stderr, "res %d sample %d factor %d: k0 %d t %.17g, expected "
                                "%d %.17g\n", res[r], i, j, d.k0[3 * i + j], d.t[3 * i + j], k, t);
                }
                ASSERT(d.k0[3 * i + j] >= 0 && d.k0[3 * i + j] <= res[r] - 2);
            }
            ASSERT(memcmp(&d.cos_i[i], &s.cos_i[i], sizeof(double)) == 0);
        }
        ASSERT_EQ(mism, 0);
        hf_design_free(&d);
    }
    free(s.nrm);
    free(s.wi);
    free(s.wo);
    free(s.cos_i);
}

TEST(constraint_rows)
{
    const samples *s = sphere_samples();
    hf_design d;
    int rows, ldb, R = 16, n = 48;
    ASSERT(s);
    ASSERT_OK(hf_design_build(s, R, &d, NULL));
    ASSERT_EQ(d.n, s->n);
    double *B = hf_dense_B(&d, 0.5, &rows, &ldb);
    ASSERT(B);
    ASSERT_EQ(rows, d.n + 3 * (R - 2));
    /* each data row: six non-zeros at most, each factor block sums to 1 */
    for (int i = 0; i < d.n; i++) {
        for (int j = 0; j < 3; j++) {
            double sum = 0;
            int nz = 0;
            for (int k = 0; k < R; k++) {
                double v = B[i + (size_t)ldb * (j * R + k)];
                sum += v;
                nz += v != 0.0;
                ASSERT(v >= 0.0 && v <= 1.0);
            }
            ASSERT_NEAR(sum, 1.0, 1e-15);
            ASSERT(nz >= 1 && nz <= 2);
        }
    }
    /* the row of sample i predicts log p(pi_p) + log q(pi_q) + log r(pi_r) */
    double y[3 * 48], pred[3];
    for (int k = 0; k < n; k++)
        y[3 * k] = y[3 * k + 1] = y[3 * k + 2] = 0.1 * k - 0.002 * k * k;
    double *ay = malloc((size_t)3 * d.n * sizeof *ay);
    hf_A_y(&d, y, ay);
    for (int i = 0; i < d.n; i += 97) {
        double acc = 0;
        for (int k = 0; k < n; k++)
            acc += B[i + (size_t)ldb * k] * y[3 * k];
        pred[0] = acc;
        ASSERT_NEAR(ay[3 * i], pred[0], 1e-12);
    }
    free(ay);
    free(B);
    hf_design_free(&d);
}

TEST(laplacian_rows)
{
    const samples *s = sphere_samples();
    hf_design d;
    int rows, ldb, R = 12, n = 36;
    double lambda = 0.7;
    ASSERT_OK(hf_design_build(s, R, &d, NULL));
    double *B = hf_dense_B(&d, lambda, &rows, &ldb);
    /* a constant, a linear and a quadratic function per factor */
    for (int r = d.n; r < rows; r++) {
        double c0 = 0, c1 = 0, c2 = 0;
        int nz = 0;
        for (int k = 0; k < n; k++) {
            double v = B[r + (size_t)ldb * k];
            int kk = k % R;
            c0 += v;
            c1 += v * kk;
            c2 += v * kk * kk;
            nz += v != 0.0;
        }
        ASSERT_EQ(nz, 3);
        ASSERT_NEAR(c0, 0.0, 1e-15);
        ASSERT_NEAR(c1, 0.0, 1e-13);
        ASSERT_NEAR(c2, 2.0 * lambda, 1e-13);
    }
    /* the normal matrix assembled sparsely equals B^T B */
    double *G = malloc((size_t)n * n * sizeof *G);
    hf_normal_matrix(&d, lambda, G);
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) {
            double acc = 0;
            for (int r = 0; r < rows; r++)
                acc += B[r + (size_t)ldb * a] * B[r + (size_t)ldb * b];
            ASSERT_NEAR(G[a + (size_t)n * b], acc, 1e-9 * (1 + fabs(acc)));
        }
    free(G);
    free(B);
    hf_design_free(&d);
}

TEST(gauge_is_null_for_every_lambda)
{
    const samples *s = sphere_samples();
    hf_design d;
    int R = 16, n = 48;
    double Z[2 * 48];
    const double lambdas[] = {0.0, 0.1, 10.0, 1e6};
    ASSERT_OK(hf_design_build(s, R, &d, NULL));
    hf_gauge_vectors(R, Z);
    for (unsigned li = 0; li < sizeof lambdas / sizeof lambdas[0]; li++) {
        int rows, ldb;
        double *B = hf_dense_B(&d, lambdas[li], &rows, &ldb);
        for (int g = 0; g < 2; g++) {
            double nrm = 0;
            for (int r = 0; r < rows; r++) {
                double acc = 0;
                for (int k = 0; k < n; k++)
                    acc += B[r + (size_t)ldb * k] * Z[g * n + k];
                nrm += acc * acc;
            }
            ASSERT_LE(sqrt(nrm), 1e-12 * (1 + lambdas[li]));
        }
        free(B);
        /* the decomposition excludes it: V^T Z = 0 */
        hf_decomp dc;
        glint_err e;
        ASSERT_OK(hf_decomp_build(&d, lambdas[li], HF_ROUTE_EIG, 0, &dc, &e));
        ASSERT_EQ(dc.gauge_dims, 2);
        for (int k = 0; k < dc.rank; k++)
            for (int g = 0; g < 2; g++) {
                double acc = 0;
                for (int r = 0; r < n; r++)
                    acc += dc.V[r + (size_t)n * k] * Z[g * n + r];
                ASSERT_LE(fabs(acc), 1e-8);
            }
        hf_decomp_free(&dc);
    }
    hf_design_free(&d);
}

/* ---- pseudo-inverse against the reference solve ------------------------------ */

static void check_against_gelsd(int R, double lambda)
{
    const samples *s = sphere_samples();
    hf_design d;
    hf_decomp de, ds;
    hf_op oe, os;
    hf_reg reg;
    hf_map map;
    hf_factors fe, fs;
    glint_err e;
    int n = 3 * R, rank = 0;
    float *rgb = paint_blinn(s);
    double *f = mapped(s, rgb), *yref = malloc((size_t)3 * n * sizeof(double));

    hf_reg_parse("trunc:full", &reg, NULL);
    hf_map_default(&map, HF_MAP_ADD);
    ASSERT_OK(hf_design_build(s, R, &d, &e));
    ASSERT_OK(hf_decomp_build(&d, lambda, HF_ROUTE_EIG, 0, &de, &e));
    ASSERT_OK(hf_decomp_build(&d, lambda, HF_ROUTE_SVD, 0, &ds, &e));
    ASSERT_EQ(de.rank, 3 * R - 2);
    ASSERT_EQ(ds.rank, 3 * R - 2);
    ASSERT_OK(hf_op_build(&de, &reg, HF_F64, &oe, &e));
    ASSERT_OK(hf_op_build(&ds, &reg, HF_F64, &os, &e));
    ASSERT_OK(hf_fit(&d, &oe, &map, HF_MODEL_RADIANCE, rgb, &fe, NULL, &e));
    ASSERT_OK(hf_fit(&d, &os, &map, HF_MODEL_RADIANCE, rgb, &fs, NULL, &e));
    ASSERT_EQ(gelsd_solve(&d, lambda, f, yref, 1e-10, &rank), 0);
    ASSERT_EQ(rank, 3 * R - 2);
    hf_factors_canonicalize(yref, R); /* minimum norm is canonical already */
    double cond = ds.s[0] / ds.s[ds.rank - 1];
    double eps = DBL_EPSILON;
    double err_svd = rel_diff(fs.logf, yref, 3 * n);
    double err_eig = rel_diff(fe.logf, yref, 3 * n);
    /* Both routes apply the operator as M A^T f (B^T g formed implicitly), so
     * rounding is amplified by up to cond^2: error <= C cond^2 eps.  The SVD
     * route's singular vectors are more accurate, the apply is the same. */
    double tol_svd = 10.0 * cond * cond * eps, tol_eig = 10.0 * cond * cond * eps;
    printf("  R=%d lambda=%g cond=%.3g  |svd-gelsd|=%.2e (tol %.1e)  |eig-gelsd|=%.2e (tol %.1e)\n",
           R, lambda, cond, err_svd, tol_svd, err_eig, tol_eig);
    ASSERT_LE(err_svd, tol_svd);
    ASSERT_LE(err_eig, tol_eig);
    /* the eig route's singular values agree with the SVD's */
    for (int k = 0; k < ds.rank; k++)
        ASSERT_NEAR(de.s[k], ds.s[k], 1e-7 * ds.s[0]);
    hf_factors_free(&fe);
    hf_factors_free(&fs);
    hf_op_free(&oe);
    hf_op_free(&os);
    hf_decomp_free(&de);
    hf_decomp_free(&ds);
    hf_design_free(&d);
    free(rgb);
    free(f);
    free(yref);
}

TEST(pinv_matches_gelsd)
{
    check_against_gelsd(16, 0.1);
    check_against_gelsd(32, 0.01);
    check_against_gelsd(48, 1.0);
}

/* ---- regularizations ------------------------------------------------------------ */

static double fit_norm(const hf_design *d, const hf_decomp *dc, const char *spec,
                       const float *rgb, int *k_out)
{
    hf_reg reg;
    hf_op op;
    hf_map map;
    hf_factors fac;
    double nrm = 0;
    hf_map_default(&map, HF_MAP_ADD);
    if (hf_reg_parse(spec, &reg, NULL) || hf_op_build(dc, &reg, HF_F64, &op, NULL))
        return NAN;
    if (hf_fit(d, &op, &map, HF_MODEL_RADIANCE, rgb, &fac, NULL, NULL)) {
        hf_op_free(&op);
        return NAN;
    }
    /* the canonical gauge is the minimum-norm one: ||y|| is the norm of the
     * solution's coefficients on the kept singular vectors */
    for (int k = 0; k < 9 * d->res; k++)
        nrm += fac.logf[k] * fac.logf[k];
    if (k_out)
        *k_out = op.k;
    hf_factors_free(&fac);
    hf_op_free(&op);
    return sqrt(nrm);
}

TEST(regularizations_rank_and_monotone_smoothing)
{
    const samples *s = sphere_samples();
    hf_design d;
    hf_decomp dc;
    int R = 32, full = 3 * R - 2, k;
    float *rgb = paint_blinn(s);
    ASSERT_OK(hf_design_build(s, R, &d, NULL));
    ASSERT_OK(hf_decomp_build(&d, 0.1, HF_ROUTE_EIG, 0, &dc, NULL));
    ASSERT_EQ(dc.rank, full);

    fit_norm(&d, &dc, "trunc:full", rgb, &k);
    ASSERT_EQ(k, full);
    fit_norm(&d, &dc, "trunc:50%", rgb, &k);
    ASSERT_EQ(k, (int)floor(0.5 * full + 0.5));
    fit_norm(&d, &dc, "trunc:10", rgb, &k);
    ASSERT_EQ(k, 10);
    fit_norm(&d, &dc, "trunc:1", rgb, &k); /* rank 1 */
    ASSERT_EQ(k, 1);
    fit_norm(&d, &dc, "trunc:rel1e-2", rgb, &k);
    {
        int expect = 0;
        while (expect < dc.rank && dc.s[expect] > 1e-2 * dc.s[0])
            expect++;
        ASSERT_EQ(k, expect);
    }
    fit_norm(&d, &dc, "linear:20", rgb, &k);
    ASSERT_EQ(k, 20); /* pos(1 - i/K), i = 0..K-1: K non-zero weights */

    /* Monotone smoothing: the solution norm never grows as truncation keeps
     * fewer components, as linear damping narrows, or as alpha grows. */
    const char *trunc[] = {"trunc:full", "trunc:75%", "trunc:50%", "trunc:20%", "trunc:10%", "trunc:1"};
    const char *lin[] = {"linear:full", "linear:75%", "linear:50%", "linear:20%", "linear:5"};
    const char *tik[] = {"tikhonov:rel1e-4", "tikhonov:rel1e-3", "tikhonov:rel1e-2",
                         "tikhonov:rel0.1", "tikhonov:rel1"};
    double prev = INFINITY;
    for (unsigned i = 0; i < 6; i++) {
        double v = fit_norm(&d, &dc, trunc[i], rgb, NULL);
        ASSERT_FINITE(v);
        ASSERT_LE(v, prev * (1 + 1e-12));
        prev = v;
    }
    prev = INFINITY;
    for (unsigned i = 0; i < 5; i++) {
        double v = fit_norm(&d, &dc, lin[i], rgb, NULL);
        ASSERT_FINITE(v);
        ASSERT_LE(v, prev * (1 + 1e-12));
        prev = v;
    }
    prev = INFINITY;
    for (unsigned i = 0; i < 5; i++) {
        double v = fit_norm(&d, &dc, tik[i], rgb, NULL);
        ASSERT_FINITE(v);
        ASSERT_LT(v, prev);
        prev = v;
    }
    /* Tikhonov with a tiny alpha equals the full pseudo-inverse */
    ASSERT_NEAR(fit_norm(&d, &dc, "tikhonov:rel1e-9", rgb, NULL),
                fit_norm(&d, &dc, "trunc:full", rgb, NULL), 1e-8);
    hf_decomp_free(&dc);
    hf_design_free(&d);
    free(rgb);
}

TEST(reg_parse_errors)
{
    hf_reg r;
    glint_err e;
    char buf[64];
    ASSERT_EQ(hf_reg_parse("bogus", &r, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "bogus"));
    ASSERT_EQ(hf_reg_parse("trunc:0", &r, &e), GLINT_EINVAL);
    ASSERT_EQ(hf_reg_parse("trunc:150%", &r, &e), GLINT_ERANGE);
    ASSERT_EQ(hf_reg_parse("trunc:nan", &r, &e), GLINT_EINVAL);
    ASSERT_EQ(hf_reg_parse("tikhonov", &r, &e), GLINT_EINVAL);
    ASSERT_EQ(hf_reg_parse("tikhonov:-1", &r, &e), GLINT_EINVAL);
    ASSERT_EQ(hf_reg_parse("tikhonov:inf", &r, &e), GLINT_EINVAL);
    ASSERT_OK(hf_reg_parse("trunc:rel1e-3", &r, &e));
    hf_reg_format(&r, buf, sizeof buf);
    ASSERT(strcmp(buf, "trunc:rel0.001") == 0);
    ASSERT_OK(hf_reg_parse("linear:50%", &r, &e));
    hf_reg_format(&r, buf, sizeof buf);
    ASSERT(strcmp(buf, "linear:50%") == 0);
}

/* ---- mappings ----------------------------------------------------------------------- */

/* Data generated from known factors must be reproduced by the fit for each
 * mapping (lambda 0, full rank: the system is consistent). */
static void round_trip(hf_map_kind kind)
{
    const samples *s = sphere_samples();
    hf_design d;
    hf_decomp dc;
    hf_op op;
    hf_reg reg;
    hf_map map;
    hf_factors fac;
    hf_fit_stats st;
    glint_err e;
    int R = 24;
    double *y = malloc((size_t)9 * R * sizeof *y), *z = malloc((size_t)3 * s->n * sizeof *z);
    float *rgb = malloc((size_t)3 * s->n * sizeof *rgb), *rec = malloc((size_t)3 * s->n * sizeof *rec);
    ASSERT_OK(hf_design_build(s, R, &d, &e));
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < R; k++)
            for (int c = 0; c < 3; c++)
                y[(j * R + k) * 3 + c] = 0.3 * sin(0.2 * k + j + c) - 0.4;
    hf_A_y(&d, y, z); /* log of a product of factors */
    double zmin = INFINITY;
    for (int i = 0; i < 3 * s->n; i++) {
        z[i] = exp(z[i]);
        if (z[i] < zmin) zmin = z[i];
    }
    hf_map_default(&map, kind);
    map.eps = 1e-9;
    for (int i = 0; i < 3 * s->n; i++) {
        if (kind == HF_MAP_LOG) rgb[i] = (float)z[i];
        else if (kind == HF_MAP_ADD) rgb[i] = (float)(z[i] - map.a);
        else rgb[i] = (float)z[i]; /* replaced below */
    }
    if (kind == HF_MAP_ADD) {
        /* the product must exceed a: shift factors so it does */
        map.a = 0.5 * zmin;
        for (int i = 0; i < 3 * s->n; i++) rgb[i] = (float)(z[i] - map.a);
    }
    if (kind == HF_MAP_SUB) {
        /* data = a - z with a = (1 + margin) max(data): a = (1+m)/m min z */
        double m = map.margin, a = (1 + m) / m * zmin;
        for (int i = 0; i < 3 * s->n; i++) rgb[i] = (float)(a - z[i]);
    }
    hf_reg_parse("trunc:full", &reg, NULL);
    ASSERT_OK(hf_decomp_build(&d, 1e-6, HF_ROUTE_SVD, 0, &dc, &e));
    ASSERT_OK(hf_op_build(&dc, &reg, HF_F64, &op, &e));
    ASSERT_OK(hf_fit(&d, &op, &map, HF_MODEL_RADIANCE, rgb, &fac, &st, &e));
    hf_factors_eval_design(&fac, &d, rec);
    double maxd = 0, maxv = 0;
    for (int i = 0; i < 3 * s->n; i++) {
        maxd = fmax(maxd, fabs(rec[i] - rgb[i]));
        maxv = fmax(maxv, fabs(rgb[i]));
    }
    printf("  mapping %d: max |reconstruction - data| = %.2e (data max %.3g) rank %d logres %.3g\n", (int)kind, maxd, maxv, dc.rank, st.log_residual);
    ASSERT_LE(maxd, 1e-4 * maxv);
    ASSERT_EQ(st.clamped[0] + st.clamped[1] + st.clamped[2], 0);
    hf_factors_free(&fac);
    hf_op_free(&op);
    hf_decomp_free(&dc);
    hf_design_free(&d);
    free(y); free(z); free(rgb); free(rec);
}

TEST(mapping_round_trips)
{
    round_trip(HF_MAP_LOG);
    round_trip(HF_MAP_ADD);
    round_trip(HF_MAP_SUB);
}

TEST(map_parse)
{
    hf_map m;
    glint_err e;
    ASSERT_OK(hf_map_parse("add:0.05,eps=1e-4", &m, &e));
    ASSERT(m.kind == HF_MAP_ADD);
    ASSERT_NEAR(m.a, 0.05, 0);
    ASSERT_NEAR(m.eps, 1e-4, 0);
    ASSERT_OK(hf_map_parse("sub:0.02", &m, &e));
    ASSERT_NEAR(m.margin, 0.02, 0);
    ASSERT_EQ(hf_map_parse("log:3", &m, &e), GLINT_EINVAL);
    ASSERT_EQ(hf_map_parse("add:-1", &m, &e), GLINT_EINVAL);
    ASSERT_EQ(hf_map_parse("add:nan", &m, &e), GLINT_EINVAL);
    ASSERT_EQ(hf_map_parse("exp", &m, &e), GLINT_EINVAL);
}

/* ---- RGB and precision ------------------------------------------------------------------- */

TEST(rgb_channels_are_independent_fits)
{
    const samples *s = sphere_samples();
    fitcase fc;
    hf_map map;
    hf_factors f3, f1;
    int N = s->n;
    float *rgb = paint_blinn(s), *grey = malloc((size_t)3 * N * sizeof *grey);
    ASSERT_OK(fitcase_make(&fc, 32, 0.1, "trunc:full", HF_F64));
    hf_map_default(&map, HF_MAP_ADD);
    ASSERT_OK(hf_fit(&fc.d, &fc.op, &map, HF_MODEL_RADIANCE, rgb, &f3, NULL, NULL));
    for (int c = 0; c < 3; c++) {
        for (int i = 0; i < N; i++)
            grey[3 * i] = grey[3 * i + 1] = grey[3 * i + 2] = rgb[3 * i + c];
        ASSERT_OK(hf_fit(&fc.d, &fc.op, &map, HF_MODEL_RADIANCE, grey, &f1, NULL, NULL));
        for (int k = 0; k < 3 * 32; k++) {
            ASSERT_NEAR(f1.logf[3 * k], f1.logf[3 * k + 2], 0); /* identical channels */
            ASSERT_NEAR(f1.logf[3 * k], f3.logf[3 * k + c], 1e-12);
        }
        hf_factors_free(&f1);
    }
    hf_factors_free(&f3);
    fitcase_free(&fc);
    free(rgb);
    free(grey);
}

TEST(single_precision_operator)
{
    const samples *s = sphere_samples();
    fitcase f64, f32;
    hf_map map;
    hf_factors a, b;
    hf_fit_stats sa, sb;
    float *rgb = paint_blinn(s);
    ASSERT_OK(fitcase_make(&f64, 64, 0.1, "trunc:full", HF_F64));
    ASSERT_OK(fitcase_make(&f32, 64, 0.1, "trunc:full", HF_F32));
    hf_map_default(&map, HF_MAP_ADD);
    ASSERT_OK(hf_fit(&f64.d, &f64.op, &map, HF_MODEL_RADIANCE, rgb, &a, &sa, NULL));
    ASSERT_OK(hf_fit(&f32.d, &f32.op, &map, HF_MODEL_RADIANCE, rgb, &b, &sb, NULL));
    double cond = f64.dc.s[0] / f64.dc.s[f64.dc.rank - 1];
    double rd = rel_diff(b.logf, a.logf, 9 * 64);
    printf("  float operator: rel. log-factor difference %.2e (cond %.3g); rms %.5f vs %.5f\n",
           rd, cond, sb.rms, sa.rms);
    ASSERT_LE(rd, cond * cond * FLT_EPSILON); /* the same cond^2 amplification */
    ASSERT_LE(fabs(sb.rms - sa.rms), 1e-4);
    ASSERT_EQ(hf_op_bytes(&f32.op, NULL) * 2, hf_op_bytes(&f64.op, NULL));
    hf_factors_free(&a);
    hf_factors_free(&b);
    fitcase_free(&f64);
    fitcase_free(&f32);
    free(rgb);
}

TEST(eval_matches_design_eval)
{
    const samples *s = sphere_samples();
    fitcase fc;
    hf_map map;
    hf_factors fac;
    float *rgb = paint_blinn(s), *rec = malloc((size_t)3 * s->n * sizeof *rec);
    ASSERT_OK(fitcase_make(&fc, 32, 0.1, "trunc:full", HF_F64));
    hf_map_default(&map, HF_MAP_ADD);
    ASSERT_OK(hf_fit(&fc.d, &fc.op, &map, HF_MODEL_BRDF, rgb, &fac, NULL, NULL));
    hf_factors_eval_design(&fac, &fc.d, rec);
    for (int i = 0; i < s->n; i += 13) {
        double n[3], wi[3], wo[3], out[3];
        for (int c = 0; c < 3; c++) {
            n[c] = s->nrm[3 * i + c]; wi[c] = s->wi[3 * i + c]; wo[c] = s->wo[3 * i + c];
        }
        hf_factors_eval(&fac, n, wi, wo, out);
        for (int c = 0; c < 3; c++)
            ASSERT_NEAR(out[c], rec[3 * i + c], 1e-5 * (1 + fabs(out[c])));
    }
    /* below the horizon: zero */
    double n[3] = {0, 0, 1}, wi[3] = {0, 0.6, -0.8}, wo[3] = {0, 0, 1}, out[3];
    hf_factors_eval(&fac, n, wi, wo, out);
    ASSERT_NEAR(out[0], 0.0, 0);
    hf_factors_free(&fac);
    fitcase_free(&fc);
    free(rgb);
    free(rec);
}

TEST_LIST {
    TEST_ENTRY(projections_known_vectors),
    TEST_ENTRY(hat_weights),
    TEST_ENTRY(design_matches_project_and_hat),
    TEST_ENTRY(constraint_rows),
    TEST_ENTRY(laplacian_rows),
    TEST_ENTRY(gauge_is_null_for_every_lambda),
    TEST_ENTRY(pinv_matches_gelsd),
    TEST_ENTRY(regularizations_rank_and_monotone_smoothing),
    TEST_ENTRY(reg_parse_errors),
    TEST_ENTRY(mapping_round_trips),
    TEST_ENTRY(map_parse),
    TEST_ENTRY(rgb_channels_are_independent_fits),
    TEST_ENTRY(single_precision_operator),
    TEST_ENTRY(eval_matches_design_eval),
};

TEST_MAIN()
