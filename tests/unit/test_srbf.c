/* test_srbf.c: the SRBF basis and transfer (srbf.h): the sigma-lambda
 * relation, the hemicube layout, the frame, static terms, energy rows
 * against a finer quadrature, and transfer matrices against a plain loop. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "srbf.h"
#include "vis.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

TEST(lambda_from_sigma_and_the_variance_of_g_squared)
{
    double lam, num = 0, den = 0;
    glint_err e;
    ASSERT_OK(srbf_lambda(M_PI / 40, &lam, &e));
    ASSERT_NEAR(lam, 81.056947, 1e-6);
    /* 1 - E[x] of the density proportional to G^2 = exp(2 lam (x - 1)), by a
     * fine midpoint rule in x = cos theta */
    for (int i = 0; i < 2000000; i++) {
        double x = -1 + (i + 0.5) * 2.0 / 2000000, g = exp(2 * lam * (x - 1));
        num += x * g;
        den += g;
    }
    ASSERT_NEAR(1 - num / den, (M_PI / 40) * (M_PI / 40), 1e-9);
    ASSERT_EQ(srbf_lambda(1.0, &lam, &e), GLINT_ERANGE);
    ASSERT_EQ(srbf_lambda(0.001, &lam, &e), GLINT_ERANGE);
}

TEST(hemicube_layout)
{
    double xi[3 * 3 * 16 * 16];
    for (int r = 2; r <= 10; r++)
        ASSERT_EQ(srbf_hemicube(r, xi), 3 * r * r);
    ASSERT_EQ(srbf_hemicube(7, xi), 147);
    {
        double l = sqrt(36.0 / 49 * 2 + 1);
        ASSERT_NEAR(xi[0], -6.0 / 7 / l, 1e-15);
        ASSERT_NEAR(xi[1], -6.0 / 7 / l, 1e-15);
        ASSERT_NEAR(xi[2], 1 / l, 1e-15);
    }
    ASSERT_NEAR(xi[3 * 133 + 2], 0.0, 1e-15); /* the horizon ring starts at 133 */
    for (int j = 0; j < 147; j++) {
        double *x = xi + 3 * j;
        ASSERT_NEAR(x[0] * x[0] + x[1] * x[1] + x[2] * x[2], 1.0, 1e-14);
        ASSERT(x[2] >= 0);
        /* 180-degree symmetry: (-x, -y, z) is a centre too */
        int found = 0;
        for (int k = 0; k < 147; k++)
            found |= fabs(xi[3 * k] + x[0]) < 1e-12 && fabs(xi[3 * k + 1] + x[1]) < 1e-12 &&
                     fabs(xi[3 * k + 2] - x[2]) < 1e-12;
        ASSERT(found);
    }
}

TEST(frame_and_static_terms)
{
    double ns[3][3] = {{0, 0, 1}, {0, 0, -1}, {0.6, 0, 0.8}}, t[3], b[3];
    srbf_static p = {SRBF_STATIC_PAPER, 0.25, 0.3}, s = {SRBF_STATIC_SMITH, 0.25, 0.3};
    double wi[3] = {0.6, 0, 0.8}, wo[3] = {-0.28, 0.0, 0.96};
    for (int i = 0; i < 3; i++) {
        srbf_frame(ns[i], t, b);
        ASSERT_NEAR(t[0] * t[0] + t[1] * t[1] + t[2] * t[2], 1, 1e-14);
        ASSERT_NEAR(t[0] * ns[i][0] + t[1] * ns[i][1] + t[2] * ns[i][2], 0, 1e-14);
        ASSERT_NEAR(t[0] * b[0] + t[1] * b[1] + t[2] * b[2], 0, 1e-14);
    }
    {
        /* by hand: h = normalize(wi + wo) = (0.32, 0, 1.76)/|.|, wi.h, F, a + b - ab */
        double hl = sqrt(0.32 * 0.32 + 1.76 * 1.76), c = (0.6 * 0.32 + 0.8 * 1.76) / hl;
        double F = 0.25 + 0.75 * pow(1 - c, 5), a = 0.8, bb = 0.96;
        ASSERT_NEAR(srbf_static_eval(&p, wi, wo), F / (a + bb - a * bb), 1e-14);
    }
    ASSERT_NEAR(srbf_static_eval(&s, wi, wo), srbf_static_eval(&s, wo, wi), 1e-14);
    ASSERT(srbf_static_eval(&s, wi, wo) * 4 * 0.8 * 0.96 <= 1.0); /* F G2 <= 1 */
    wo[2] = -0.1;
    ASSERT(srbf_static_eval(&p, wi, wo) == 0.0);
}

TEST(energy_rows_converge)
{
    srbf_basis b;
    srbf_static st = {SRBF_STATIC_PAPER, 0.25, 0.3};
    glint_err e;
    int nl = srbf_energy_dirs(2, NULL);
    double *wo = malloc(3 * nl * sizeof *wo), *g1, *g2, mx = 0, d = 0;
    ASSERT_EQ(nl, 192 + SRBF_ENERGY_FIB + 128);
    srbf_energy_dirs(2, wo);
    ASSERT_OK(srbf_basis_make(7, M_PI / 40, &b, &e));
    g1 = malloc((size_t)8 * b.J * sizeof *g1);
    g2 = malloc((size_t)8 * b.J * sizeof *g2);
    /* a few rows, grazing ones included, at the default and at 3x nodes */
    double pick[24];
    int idx[8] = {0, 50, 100, 191, 300, 700, 192 + SRBF_ENERGY_FIB, nl - 1};
    for (int i = 0; i < 8; i++)
        memcpy(pick + 3 * i, wo + 3 * idx[i], 3 * sizeof(double));
    ASSERT_OK(srbf_energy_rows(&b, &st, 8, pick, getenv("NQ") ? atoi(getenv("NQ")) : 0, g1, 0,
                               NULL, &e));

    ASSERT_OK(srbf_energy_rows(&b, &st, 8, pick, 288, g2, 0, NULL, &e));
    for (int i = 0; i < 8 * b.J; i++) {
        mx = fmax(mx, g2[i]);
        d = fmax(d, fabs(g1[i] - g2[i]));
    }
    if (getenv("NQ"))
        for (int i = 0; i < 8; i++) {
            double dm = 0;
            for (int j = 0; j < b.J; j++)
                dm = fmax(dm, fabs(g1[i * b.J + j] - g2[i * b.J + j]));
            printf("row %d (z %.4f): %.3e\n", idx[i], pick[3 * i + 2], dm / mx);
        }
    printf("  energy rows at 96 nodes against 288: max difference %.2e of the largest\n",
           d / mx);
    /* below 5.7 degrees (h-space quadrature, whose cut at wi.n = 0 converges
     * slowly) 2e-4; above, 1e-7: the fit keeps a margin of 1e-3 */
    ASSERT(d <= 5e-4 * mx);
    srbf_basis_free(&b);
    free(wo);
    free(g1);
    free(g2);
}

TEST(transfer_matches_a_plain_loop_and_visibility_masks)
{
    srbf_basis b;
    srbf_static st = {SRBF_STATIC_SMITH, 0.1, 0.4};
    glint_err e;
    enum { NP = 50, K = 70 };
    float nrm[3 * NP], wo[3 * NP], *T = malloc(3 * NP * 147 * sizeof(float)),
                                   *T2 = malloc(3 * NP * 147 * sizeof(float));
    double dir[3 * K], pow_[3 * K], E[3 * NP], E2[3 * NP], c[3 * 147];
    uint64_t bits[NP * VIS_WORDS(K)];
    unsigned char reach[147];
    env_lights l = {K, dir, pow_, {0, 0, 0}};
    srand(3);
    for (int i = 0; i < 3 * 147; i++)
        c[i] = (rand() % 5 == 0) ? rand() / (double)RAND_MAX : 0.0;
    for (int k = 0; k < K; k++) {
        double z = 1 - (2.0 * k + 1) / K, r = sqrt(1 - z * z), a = k * 2.39996;
        dir[3 * k] = r * cos(a);
        dir[3 * k + 1] = r * sin(a);
        dir[3 * k + 2] = z;
        for (int ch = 0; ch < 3; ch++)
            pow_[3 * k + ch] = 0.1 + 0.05 * ch + 0.01 * (k % 7);
    }
    for (int i = 0; i < NP; i++) {
        double th = 0.05 + 1.4 * i / NP, ph = 0.3 * i;
        double n[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
        double v[3] = {0.2, -0.3, 1}, vl = sqrt(1.13);
        for (int k = 0; k < 3; k++) {
            nrm[3 * i + k] = (float)n[k];
            wo[3 * i + k] = (float)(v[k] / vl);
        }
    }
    ASSERT_OK(srbf_basis_make(7, M_PI / 40, &b, &e));
    ASSERT_OK(srbf_transfer(&b, &st, NP, nrm, wo, &l, NULL, T, E, reach, 2, NULL, NULL, &e));
    for (int i = 0; i < NP; i++) {
        double n[3], w[3], t[3], bt[3], lo[3], acc[3] = {0, 0, 0}, tc[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++) {
            n[k] = nrm[3 * i + k];
            w[k] = wo[3 * i + k];
        }
        double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++)
            n[k] /= nl;
        srbf_frame(n, t, bt);
        lo[0] = t[0] * w[0] + t[1] * w[1] + t[2] * w[2];
        lo[1] = bt[0] * w[0] + bt[1] * w[1] + bt[2] * w[2];
        lo[2] = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
        for (int k = 0; k < K; k++) {
            const double *d = dir + 3 * k;
            double li[3] = {t[0] * d[0] + t[1] * d[1] + t[2] * d[2],
                            bt[0] * d[0] + bt[1] * d[1] + bt[2] * d[2],
                            n[0] * d[0] + n[1] * d[1] + n[2] * d[2]},
                   h[3], hl, p[3];
            if (li[2] <= 0 || lo[2] <= 0)
                continue;
            for (int q = 0; q < 3; q++)
                h[q] = li[q] + lo[q];
            hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            for (int q = 0; q < 3; q++)
                h[q] /= hl;
            srbf_p(&b, c, h, p);
            for (int ch = 0; ch < 3; ch++) {
                acc[ch] += pow_[3 * k + ch] * li[2] * srbf_static_eval(&st, li, lo) * p[ch];
            }
        }
        for (int ch = 0; ch < 3; ch++) {
            for (int j = 0; j < 147; j++)
                tc[ch] += T[((size_t)ch * NP + i) * 147 + j] * c[ch * 147 + j];
            ASSERT_NEAR(tc[ch], acc[ch], 1e-6 * (1 + fabs(acc[ch])));
        }
    }
    /* visibility: only even lights seen -> the same as dropping odd lights */
    for (int i = 0; i < NP * VIS_WORDS(K); i++)
        bits[i] = 0x5555555555555555ULL;
    ASSERT_OK(srbf_transfer(&b, &st, NP, nrm, wo, &l, bits, T2, E2, NULL, 1, NULL, NULL, &e));
    for (int k = 1; k < K; k += 2)
        for (int ch = 0; ch < 3; ch++)
            pow_[3 * k + ch] = 0;
    ASSERT_OK(srbf_transfer(&b, &st, NP, nrm, wo, &l, NULL, T, E, NULL, 1, NULL, NULL, &e));
    for (int i = 0; i < 3 * NP * 147; i++)
        ASSERT_NEAR(T[i], T2[i], 1e-6 * (1 + fabs(T[i])));
    for (int i = 0; i < 3 * NP; i++)
        ASSERT_NEAR(E[i], E2[i], 1e-12);
    {
        int nr = 0;
        for (int j = 0; j < 147; j++)
            nr += reach[j];
        ASSERT(nr > 0 && nr < 147); /* normals up to 80 degrees: not every lobe */
    }
    srbf_basis_free(&b);
    free(T);
    free(T2);
}

TEST_LIST{
    TEST_ENTRY(lambda_from_sigma_and_the_variance_of_g_squared),
    TEST_ENTRY(hemicube_layout),
    TEST_ENTRY(frame_and_static_terms),
    TEST_ENTRY(energy_rows_converge),
    TEST_ENTRY(transfer_matches_a_plain_loop_and_visibility_masks),
};

TEST_MAIN()
