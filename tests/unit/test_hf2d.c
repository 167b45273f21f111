/* test_hf2d.c: three factors with 2D factors over parabolic maps (hf2d.h,
 * method_hf2d.h) and the anisotropic Ward truth (brdf.h): the frame and
 * the map; the fit against an independent minimum-norm least-squares solve
 * (LAPACK dgelsd on the dense system written out here, the frame and the
 * map computed here too); an anisotropic painting needs the 2D factor, on
 * the painted views and on views that were not painted, and an isotropic
 * one is not hurt by it; a uniform painting; the dense form with
 * unreached nodes; bad shapes refused; the method's material saved, read
 * back and damaged; the decomposition on disk; the GPU against the CPU
 * (skipped without EGL). */
#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "gpu_check.h"
#include "hf2d.h"
#include "method_hf2d.h"
#include "sv_fixture.h"
#include "vec3.h"

static scene SC;
static gbuf *G;
static cache *C;
static cache_entry *SE;
static samples SFIT, STEST; /* even views, odd views */

static int setup(void)
{
    unsigned char even[SCENE_MAX_VIEWS] = {0}, odd[SCENE_MAX_VIEWS] = {0};
    char h[33];
    glint_err e;
    if (SE)
        return 0;
    if (sv_setup(48, &SC, &G, &C, &SE))
        return -1;
    for (int v = 0; v < SC.nviews; v++)
        (v % 2 ? odd : even)[v] = 1;
    scene_hash(&SC, h);
    if (samples_build(G, SC.views, SC.nviews, even, h, &SFIT, &e) ||
        samples_build(G, SC.views, SC.nviews, odd, h, &STEST, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

static void sample_dirs(const samples *s, int i, double n[3], double wi[3], double wo[3])
{
    for (int a = 0; a < 3; a++) {
        n[a] = s->nrm[3 * (size_t)i + a];
        wi[a] = s->wi[3 * (size_t)i + a];
        wo[a] = s->wo[3 * (size_t)i + a];
    }
}

/* The truth's values at the samples (per unit light: f cos_i). */
static float *paint_samples(const brdf *b, const samples *s)
{
    float *rgb = malloc(3 * (size_t)s->n * sizeof *rgb);
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], f[3];
        sample_dirs(s, i, n, wi, wo);
        brdf_eval(b, n, wi, wo, f);
        for (int c = 0; c < 3; c++)
            rgb[3 * i + c] = (float)(f[c] * s->cos_i[i]);
    }
    return rgb;
}

TEST(frame_and_parabolic_map)
{
    unsigned seed = 1;
    double uv[2];
    for (int k = 0; k < 2000; k++) {
        double z = 2.0 * rand_r(&seed) / RAND_MAX - 1.0, ph = 6.283 * rand_r(&seed) / RAND_MAX;
        v3 n = k < 2 ? v3_make(0, 0, k ? -1 : 1)
                     : v3_make(sqrt(1 - z * z) * cos(ph), z, sqrt(1 - z * z) * sin(ph)), t, b;
        double nn[3], d[3];
        v3_frame(n, &t, &b);
        ASSERT_NEAR(v3_len(t), 1.0, 1e-12);
        ASSERT_NEAR(v3_len(b), 1.0, 1e-12);
        ASSERT_NEAR(v3_dot(t, n), 0.0, 1e-12);
        ASSERT_NEAR(v3_dot(b, n), 0.0, 1e-12);
        ASSERT_NEAR(v3_dot(v3_cross(t, b), n), 1.0, 1e-12); /* right-handed */
        v3_store(n, nn);
        hf2d_parabolic(nn, nn, uv); /* the normal: the centre */
        ASSERT_NEAR(uv[0], 0.5, 1e-12);
        ASSERT_NEAR(uv[1], 0.5, 1e-12);
        v3_store(v3_add(v3_scale(t, cos(ph)), v3_scale(b, sin(ph))), d); /* horizon: radius 1/2 */
        hf2d_parabolic(nn, d, uv);
        ASSERT_NEAR(hypot(uv[0] - 0.5, uv[1] - 0.5), 0.5, 1e-12);
        ASSERT_NEAR(atan2(uv[1] - 0.5, uv[0] - 0.5), atan2(sin(ph), cos(ph)), 1e-9);
    }
    { /* facing +X: t = +Y (around the up axis Z), b = +Z */
        double n[3] = {1, 0, 0}, d[3] = {cos(0.5), sin(0.5), 0}, e[3] = {cos(0.5), 0, sin(0.5)};
        hf2d_parabolic(n, d, uv);
        ASSERT_NEAR(uv[0], 0.5 * (tan(0.25) + 1.0), 1e-12); /* r = tan(theta / 2) */
        ASSERT_NEAR(uv[1], 0.5, 1e-12);
        hf2d_parabolic(n, e, uv);
        ASSERT_NEAR(uv[0], 0.5, 1e-12);
        ASSERT_NEAR(uv[1], 0.5 * (tan(0.25) + 1.0), 1e-12);
    }
    { /* at the pole +Z: t = +X, b = +Y */
        double n[3] = {0, 0, 1}, d[3] = {sin(0.5), 0, cos(0.5)};
        hf2d_parabolic(n, d, uv);
        ASSERT_NEAR(uv[0], 0.5 * (tan(0.25) + 1.0), 1e-12);
        ASSERT_NEAR(uv[1], 0.5, 1e-12);
    }
}

TEST(anisotropic_ward_truth)
{
    brdf iso, same, an;
    glint_err e;
    char buf[160];
    unsigned seed = 5;
    ASSERT_OK(brdf_parse("ward:rough=0.2", &iso, &e));
    ASSERT_OK(brdf_parse("ward:rough=0.2,rough_y=0.2", &same, &e));
    ASSERT_OK(brdf_parse("ward:rough=0.1,rough_y=0.4", &an, &e));
    brdf_format(&an, buf, sizeof buf);
    ASSERT(strstr(buf, "rough_y=0.4"));
    brdf_format(&iso, buf, sizeof buf);
    ASSERT(!strstr(buf, "rough_y"));
    ASSERT_EQ(brdf_parse("ward:rough_y=0", &an, &e), GLINT_ERANGE);
    ASSERT_EQ(brdf_parse("ct:rough_y=0.3", &an, &e), GLINT_EINVAL);
    ASSERT_OK(brdf_parse("ward:rough=0.1,rough_y=0.4", &an, &e));
    for (int k = 0; k < 500; k++) {
        double n[3] = {0, 0, 1}, wi[3], wo[3], a[3], b[3], th, ph;
        th = 1.4 * rand_r(&seed) / RAND_MAX, ph = 6.283 * rand_r(&seed) / RAND_MAX;
        wi[0] = sin(th) * cos(ph), wi[1] = sin(th) * sin(ph), wi[2] = cos(th);
        th = 1.4 * rand_r(&seed) / RAND_MAX, ph = 6.283 * rand_r(&seed) / RAND_MAX;
        wo[0] = sin(th) * cos(ph), wo[1] = sin(th) * sin(ph), wo[2] = cos(th);
        brdf_eval(&iso, n, wi, wo, a);
        brdf_eval(&same, n, wi, wo, b);
        ASSERT_NEAR(a[0], b[0], 1e-15 * (1 + a[0]));
        brdf_eval(&an, n, wi, wo, a); /* reciprocal */
        brdf_eval(&an, n, wo, wi, b);
        ASSERT_NEAR(a[1], b[1], 1e-12 * (1 + a[1]));
    }
    { /* the lobe is wider along b (Y here) than along t (X) */
        double n[3] = {0, 0, 1}, wo[3] = {0, 0, 1}, ax[3], ay[3];
        double wx[3] = {sin(0.3), 0, cos(0.3)}, wy[3] = {0, sin(0.3), cos(0.3)};
        brdf_eval(&an, n, wx, wo, ax);
        brdf_eval(&an, n, wy, wo, ay);
        ASSERT_LT(4.0 * (ax[0] - 0.5 / M_PI), ay[0] - 0.5 / M_PI); /* kd 0.5 */
    }
}

/* The fit of samples s with p and q 2D (S nodes per side), r 1D (R)
 * against an independent solve of the dense system by dgelsd (its cut at
 * rcond_ref); the form taken must be `form`. */
static void dense_compare(const samples *ss, int R, int S, double rcond, double rcond_ref,
                          const char *form)
{
    const int n = 2 * S * S + R;
    const double lam = 0.3, lam2 = 0.2;
    hf2d_shape sh = {.res = R, .sres = S, .dims = {2, 2, 1}};
    hf2d_design d;
    hf2d_decomp dc;
    hf2d_factors f;
    hf_map map;
    float *rgb;
    glint_err e;
    int rows, N, ldb, rank, r;
    double *B, *rhs, *sv, worst = 0.0;
    brdf truth;
    N = ss->n;
    ASSERT_OK(brdf_parse("ward:kd=0.3,ks=0.6,rough=0.15,rough_y=0.4", &truth, &e));
    rgb = paint_samples(&truth, ss);
    hf_map_default(&map, HF_MAP_LOG);
    ASSERT_OK(hf2d_design_build(ss, &sh, &d, &e));
    ASSERT_OK(hf2d_decomp_build(&d, lam, lam2, rcond, &dc, &e));
    ASSERT_OK(hf2d_fit(&d, &dc, &map, HF_MODEL_RADIANCE, rgb, NULL, &f, NULL, &e));
    rows = N + (R - 2) + 2 * S * S;
    ldb = rows > n ? rows : n;
    B = calloc((size_t)rows * n, sizeof *B);
    rhs = calloc((size_t)ldb * 3, sizeof *rhs);
    sv = malloc((size_t)n * sizeof *sv);
    for (int i = 0; i < N; i++) {
        double nn[3], wi[3], wo[3], h[3], *vec[3] = {wi, h, wo}, hl = 0.0;
        double t[3], bb[3], l;
        sample_dirs(ss, i, nn, wi, wo);
        for (int a = 0; a < 3; a++)
            h[a] = wi[a] + wo[a], hl += h[a] * h[a];
        for (int a = 0; a < 3; a++)
            h[a] /= sqrt(hl);
        /* the frame: t = Z x n normalized, b = n x t */
        t[0] = -nn[1], t[1] = nn[0], t[2] = 0.0;
        l = sqrt(t[0] * t[0] + t[1] * t[1]);
        t[0] /= l, t[1] /= l;
        bb[0] = nn[1] * t[2] - nn[2] * t[1];
        bb[1] = nn[2] * t[0] - nn[0] * t[2];
        bb[2] = nn[0] * t[1] - nn[1] * t[0];
        for (int j = 0; j < 2; j++) { /* p, q: 2D, bilinear on the parabolic map */
            double *v = vec[j], c = fmax(0.0, v[0] * nn[0] + v[1] * nn[1] + v[2] * nn[2]);
            double x = (0.5 * ((v[0] * t[0] + v[1] * t[1] + v[2] * t[2]) / (1 + c) + 1)) * (S - 1);
            double y = (0.5 * ((v[0] * bb[0] + v[1] * bb[1] + v[2] * bb[2]) / (1 + c) + 1)) *
                       (S - 1);
            int a = (int)floor(x) > S - 2 ? S - 2 : (int)floor(x);
            int b = (int)floor(y) > S - 2 ? S - 2 : (int)floor(y);
            double tx = x - a, ty = y - b;
            int o = j * S * S;
            B[i + (size_t)rows * (o + b * S + a)] += (1 - tx) * (1 - ty);
            B[i + (size_t)rows * (o + b * S + a + 1)] += tx * (1 - ty);
            B[i + (size_t)rows * (o + (b + 1) * S + a)] += (1 - tx) * ty;
            B[i + (size_t)rows * (o + (b + 1) * S + a + 1)] += tx * ty;
        }
        { /* r: 1D over |wo on the tangent plane| */
            double c = wo[0] * nn[0] + wo[1] * nn[1] + wo[2] * nn[2], s2 = 0.0, x;
            int k;
            for (int a = 0; a < 3; a++)
                s2 += (wo[a] - c * nn[a]) * (wo[a] - c * nn[a]);
            x = fmin(sqrt(s2), 1.0) * (R - 1);
            k = (int)floor(x) > R - 2 ? R - 2 : (int)floor(x);
            B[i + (size_t)rows * (2 * S * S + k)] += 1 - (x - k);
            B[i + (size_t)rows * (2 * S * S + k + 1)] += x - k;
        }
        for (int c = 0; c < 3; c++)
            rhs[i + (size_t)ldb * c] = log(rgb[3 * i + c] > map.eps ? rgb[3 * i + c] : map.eps);
    }
    r = N;
    for (int j = 0; j < 2; j++)
        for (int b = 0; b < S; b++)
            for (int a = 0; a < S; a++, r++) {
                static const int di[4] = {-1, 1, 0, 0}, dj[4] = {0, 0, -1, 1};
                int deg = 0;
                for (int q = 0; q < 4; q++) {
                    int ai = a + di[q], bj = b + dj[q];
                    if (ai < 0 || ai >= S || bj < 0 || bj >= S)
                        continue;
                    B[r + (size_t)rows * (j * S * S + bj * S + ai)] = lam2;
                    deg++;
                }
                B[r + (size_t)rows * (j * S * S + b * S + a)] = -deg * lam2;
            }
    for (int k = 0; k + 2 < R; k++, r++) {
        B[r + (size_t)rows * (2 * S * S + k)] = lam;
        B[r + (size_t)rows * (2 * S * S + k + 1)] = -2 * lam;
        B[r + (size_t)rows * (2 * S * S + k + 2)] = lam;
    }
    ASSERT_EQ(r, rows);
    ASSERT_EQ(LAPACKE_dgelsd(LAPACK_COL_MAJOR, rows, n, 3, B, rows, rhs, ldb, sv, rcond_ref,
                             &rank), 0);
    for (int c = 0; c < 3; c++) {
        int off[4] = {0, S * S, 2 * S * S, n};
        double m[3] = {0, 0, 0}, all;
        double *y = rhs + (size_t)ldb * c;
        for (int j = 0; j < 3; j++)
            for (int t = off[j]; t < off[j + 1]; t++)
                m[j] += y[t] / (off[j + 1] - off[j]);
        all = (m[0] + m[1] + m[2]) / 3;
        for (int j = 0; j < 3; j++)
            for (int t = off[j]; t < off[j + 1]; t++) {
                double ref = y[t] + all - m[j], got = f.logy[(size_t)t * 3 + c];
                worst = fabs(ref - got) > worst ? fabs(ref - got) : worst;
            }
    }
    printf("  n %d, rows %d, dgelsd rank %d, ours %d (+%d gauge, %s form): max |difference| "
           "of the log nodes %.2e\n", n, rows, rank, dc.x.rank, dc.x.gauge_dims, dc.x.form,
           worst);
    ASSERT_EQ(dc.x.gauge_dims, 2);
    ASSERT_EQ(rank, dc.x.rank);
    ASSERT(strcmp(dc.x.form, form) == 0);
    if (strcmp(form, "kernel") == 0) /* p's and q's grid: one block, written down */
        ASSERT_EQ(dc.x.grid_blocks, 1);
    ASSERT_LT(worst, 1e-6);
    free(B);
    free(rhs);
    free(sv);
    free(rgb);
    hf2d_factors_free(&f);
    hf2d_decomp_free(&dc);
    hf2d_design_free(&d);
}

/* Many samples: the normal form, cut at 1e-6 like dgelsd. */
TEST(equals_a_dense_least_squares_solve)
{
    ASSERT_OK(setup());
    dense_compare(&SFIT, 8, 6, 1e-6, 1e-6, "normal");
}

/* Fewer samples than unknowns, smoothing on every factor: the kernel form
 * (an N x N Cholesky), which keeps every direction the smoothing reaches:
 * dgelsd with a cut far below any of them gives the same solution. */
TEST(kernel_form_equals_a_dense_least_squares_solve)
{
    unsigned char one[SCENE_MAX_VIEWS] = {0};
    samples few;
    glint_err e;
    char h[33];
    ASSERT_OK(setup());
    one[3] = 1;
    scene_hash(&SC, h);
    ASSERT_OK(samples_build(G, SC.views, SC.nviews, one, h, &few, &e));
    {
        unsigned char *keep = calloc((size_t)few.n, 1);
        samples sub;
        for (int i = 0; i < few.n; i += 7)
            keep[i] = 1;
        ASSERT_OK(samples_pick(&few, keep, "every-7th", &sub, &e));
        free(keep);
        samples_free(&few);
        few = sub;
    }
    ASSERT_LT(few.n, 2 * 12 * 12 + 8);
    dense_compare(&few, 8, 12, 0, 1e-12, "kernel");
    samples_free(&few);
}

/* Fit the even views with shape sh; RMS on them and on the odd views. */
static int fit_and_measure(const brdf *truth, const hf2d_shape *sh, double *rms_fit,
                           double *rms_new)
{
    hf2d_design d;
    hf2d_decomp dc;
    hf2d_factors f;
    hfx_fit_stats st;
    hf_map map;
    glint_err e;
    float *rgb = paint_samples(truth, &SFIT);
    double se = 0.0;
    hf_map_default(&map, HF_MAP_ADD);
    if (hf2d_design_build(&SFIT, sh, &d, &e) || hf2d_decomp_build(&d, 0.1, 0.1, 0, &dc, &e) ||
        hf2d_fit(&d, &dc, &map, HF_MODEL_RADIANCE, rgb, NULL, &f, &st, &e)) {
        fprintf(stderr, "fit: %s\n", e.msg);
        free(rgb);
        return -1;
    }
    *rms_fit = st.rms;
    for (int i = 0; i < STEST.n; i++) {
        double n[3], wi[3], wo[3], a[3], b[3];
        sample_dirs(&STEST, i, n, wi, wo);
        hf2d_factors_eval(&f, n, wi, wo, a);
        brdf_eval(truth, n, wi, wo, b);
        for (int c = 0; c < 3; c++)
            se += (a[c] - b[c] * STEST.cos_i[i]) * (a[c] - b[c] * STEST.cos_i[i]);
    }
    *rms_new = sqrt(se / (3.0 * STEST.n));
    free(rgb);
    hf2d_factors_free(&f);
    hf2d_decomp_free(&dc);
    hf2d_design_free(&d);
    return 0;
}

/* A highlight stretched along b: a 2D q holds it and 1D factors cannot, on
 * the painted views and on the views that were not painted; on an
 * isotropic highlight the 2D q costs little (its nodes are as far apart
 * over the disc as the 1D factor's over its radius, and the parabolic map
 * spends them over the whole hemisphere). */
TEST(anisotropy_needs_a_2d_factor)
{
    brdf an, iso;
    glint_err e;
    hf2d_shape one = {.res = 32, .sres = 32, .dims = {1, 1, 1}};
    hf2d_shape two = {.res = 32, .sres = 32, .dims = {1, 2, 1}};
    double f1, n1, f2, n2, fi1, ni1, fi2, ni2;
    ASSERT_OK(setup());
    ASSERT_OK(brdf_parse("ward:kd=0.3,ks=0.5,rough=0.1,rough_y=0.35", &an, &e));
    ASSERT_OK(brdf_parse("ward:kd=0.3,ks=0.5,rough=0.2", &iso, &e));
    ASSERT_OK(fit_and_measure(&an, &one, &f1, &n1));
    ASSERT_OK(fit_and_measure(&an, &two, &f2, &n2));
    ASSERT_OK(fit_and_measure(&iso, &one, &fi1, &ni1));
    ASSERT_OK(fit_and_measure(&iso, &two, &fi2, &ni2));
    printf("  anisotropic Ward, %d samples fitted, %d new: 1D q rms %.4f (new views %.4f), "
           "2D q %.4f (%.4f)\n", SFIT.n, STEST.n, f1, n1, f2, n2);
    printf("  isotropic Ward: 1D q rms %.4f (new views %.4f), 2D q %.4f (%.4f)\n", fi1, ni1,
           fi2, ni2);
    ASSERT_LT(f2, 0.7 * f1);
    ASSERT_LT(n2, 0.7 * n1);
    ASSERT_LT(ni2, 1.5 * ni1);
}

/* A uniform painting is a constant: reproduced everywhere. */
TEST(uniform_painting)
{
    hf2d_shape sh = {.res = 16, .sres = 12, .dims = {2, 2, 2}};
    hf2d_design d;
    hf2d_decomp dc;
    hf2d_factors f;
    hfx_fit_stats st;
    hf_map map;
    glint_err e;
    float *rgb;
    ASSERT_OK(setup());
    rgb = malloc(3 * (size_t)SFIT.n * sizeof *rgb);
    for (int i = 0; i < 3 * SFIT.n; i++)
        rgb[i] = 0.25f + 0.25f * (float)(i % 3);
    hf_map_default(&map, HF_MAP_ADD);
    ASSERT_OK(hf2d_design_build(&SFIT, &sh, &d, &e));
    ASSERT_OK(hf2d_decomp_build(&d, 0.1, 0.1, 0, &dc, &e));
    ASSERT_OK(hf2d_fit(&d, &dc, &map, HF_MODEL_RADIANCE, rgb, NULL, &f, &st, &e));
    printf("  uniform: rms %.2e, log_max %.3f\n", st.rms, st.log_max);
    ASSERT_LT(st.rms, 1e-9);
    ASSERT_EQ(st.log_clamped, 0);
    for (int k = 0; k < 50; k++) {
        double n[3] = {0, 0, 1}, wi[3] = {sin(0.02 * k), 0, cos(0.02 * k)}, wo[3] = {0, 0.6, 0.8};
        double v[3];
        hf2d_factors_eval(&f, n, wi, wo, v);
        for (int c = 0; c < 3; c++)
            ASSERT_NEAR(v[c], 0.25 + 0.25 * c, 1e-9);
    }
    free(rgb);
    hf2d_factors_free(&f);
    hf2d_decomp_free(&dc);
    hf2d_design_free(&d);
}

/* Few samples, fine 2D factors, no smoothing: more unknowns than rows, so
 * the dense form, the unreached nodes counted (those outside the disc
 * among them); the fit finite and close on the samples.  Bad shapes are
 * refused. */
TEST(dense_form_unreached_nodes_and_bad_shapes)
{
    hf2d_shape sh = {.res = 16, .sres = 24, .dims = {2, 2, 2}};
    unsigned char one[SCENE_MAX_VIEWS] = {0};
    samples few;
    hf2d_design d;
    hf2d_decomp dc;
    hf2d_factors f;
    hfx_fit_stats st;
    hf_map map;
    glint_err e;
    float *rgb;
    brdf truth;
    char h[33];
    scene_params sp;
    scene sc;
    gbuf *g;
    ASSERT_OK(setup());
    scene_params_default(&sp);
    sp.width = sp.height = 12;
    ASSERT_OK(scene_create(&sp, &sc, &e));
    ASSERT_OK(raster_scene(&sc, &g, &e));
    one[0] = 1;
    scene_hash(&sc, h);
    ASSERT_OK(samples_build(g, sc.views, sc.nviews, one, h, &few, &e));
    ASSERT_OK(brdf_parse("ward:rough=0.2,rough_y=0.3", &truth, &e));
    rgb = paint_samples(&truth, &few);
    hf_map_default(&map, HF_MAP_ADD);
    ASSERT_OK(hf2d_design_build(&few, &sh, &d, &e));
    ASSERT_OK(hf2d_decomp_build(&d, 0.0, 0.0, 0, &dc, &e));
    ASSERT_OK(hf2d_fit(&d, &dc, &map, HF_MODEL_RADIANCE, rgb, NULL, &f, &st, &e));
    printf("  %d samples, n %d: %s form, rank %d, unreached %d, null %d; rms %.2e, log_max "
           "%.2f\n", few.n, dc.x.n, dc.x.form, dc.x.rank, dc.x.unreached, dc.x.null_dims,
           st.rms, st.log_max);
    ASSERT(strcmp(dc.x.form, "dense") == 0);
    ASSERT_LT(dc.x.n / 2, dc.x.unreached);
    ASSERT_LT(st.rms, 0.05);
    for (int t = 0; t < 3 * dc.x.n; t++)
        ASSERT(isfinite(f.logy[t]) && fabs(f.logy[t]) <= HF2D_LOG_MAX);
    hf2d_factors_free(&f);
    hf2d_decomp_free(&dc);
    hf2d_design_free(&d);
    sh.sres = HF2D_SRES_MAX + 1;
    ASSERT_EQ(hf2d_design_build(&few, &sh, &d, &e), GLINT_ERANGE);
    printf("  %s\n", e.msg);
    sh.sres = 8;
    sh.dims[1] = 3;
    ASSERT_EQ(hf2d_design_build(&few, &sh, &d, &e), GLINT_ERANGE);
    printf("  %s\n", e.msg);
    free(rgb);
    samples_free(&few);
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
}

/* Fit `spec` over every view through the method. */
static int fit_spec(const hf2d_params_t *p, const char *spec, material *out)
{
    unsigned char all[SCENE_MAX_VIEWS];
    prep_request rq = {&method_hf2d, p, SE, all, NULL};
    prep *pp = NULL;
    img im[SCENE_MAX_VIEWS];
    glint_err e;
    int rc;
    memset(all, 1, sizeof all);
    rc = sv_paint(spec, &SC, G, im, &e) || prep_acquire(C, &rq, NULL, NULL, &pp, &e) ||
         prep_fit(pp, im, NULL, out, &e);
    if (rc)
        fprintf(stderr, "fit: %s\n", e.msg);
    for (int v = 0; v < SC.nviews; v++)
        img_free(&im[v]);
    prep_release(C, pp);
    return rc;
}

#define ANISO "ward:kd=0.4/0.3/0.2,ks=0.5,rough=0.1,rough_y=0.3"

TEST(the_method_saves_loads_and_renders)
{
    hf2d_params_t hp;
    material m, back;
    glint_err e;
    char dir[] = "/tmp/glint_test_hf2d_XXXXXX", path[160], cmd[300];
    unsigned seed = 9;
    ASSERT_OK(setup());
    method_hf2d.params_default(&hp);
    hp.sres = 24;
    hp.dims[0] = 1; /* p and q 2D */
    ASSERT_OK(fit_spec(&hp, ANISO, &m));
    {
        char *txt = json_dumps(json_object_get(m.info, "errors"), JSON_COMPACT);
        printf("  %s\n", txt ? txt : "?");
        free(txt);
    }
    ASSERT(mkdtemp(dir));
    ASSERT_OK(material_save(&m, dir, &e));
    ASSERT_MSG(material_load(dir, &back, &e) == 0, "%s", e.msg);
    for (int t = 0; t < 1000; t++) {
        double n[3] = {0.3, 0.5, 0.0}, wi[3], wo[3], a[3], b[3], th, ph;
        n[2] = sqrt(1 - n[0] * n[0] - n[1] * n[1]);
        th = 1.5 * rand_r(&seed) / RAND_MAX, ph = 6.28 * rand_r(&seed) / RAND_MAX;
        wi[0] = sin(th) * cos(ph), wi[1] = sin(th) * sin(ph), wi[2] = cos(th);
        th = 1.5 * rand_r(&seed) / RAND_MAX, ph = 6.28 * rand_r(&seed) / RAND_MAX;
        wo[0] = sin(th) * cos(ph), wo[1] = sin(th) * sin(ph), wo[2] = cos(th);
        material_eval(&m, n, wi, wo, a);
        material_eval(&back, n, wi, wo, b);
        for (int ch = 0; ch < 3; ch++)
            ASSERT_NEAR(a[ch], b[ch], 1e-12 * (1.0 + fabs(a[ch])));
    }
    material_free(&back);
    for (int i = 0; i < 3; i++) {
        static const char *const files[] = {"material.json", "factors.exr", "factors.png"};
        snprintf(path, sizeof path, "%s/%s", dir, files[i]);
        ASSERT_MSG(access(path, R_OK) == 0, "%s missing", files[i]);
    }
    /* damaged manifests: a clear error each */
    {
        static const char *const edits[] = {
            "s/\"res_2d\": 24/\"res_2d\": 999/",
            "s/\"dims\": \\[/\"dims\": [7, /",
            "s/\"mapping\": \"[^\"]*\"/\"mapping\": \"cube\"/",
        };
        for (int k = 0; k < 3; k++) {
            snprintf(cmd, sizeof cmd, "cp %s/material.json %s/m.bak && sed -i '%s' %s/material.json",
                     dir, dir, edits[k], dir);
            ASSERT_EQ(system(cmd), 0);
            ASSERT(material_load(dir, &back, &e) != 0);
            printf("  damaged: %s\n", e.msg);
            snprintf(cmd, sizeof cmd, "mv %s/m.bak %s/material.json", dir, dir);
            ASSERT_EQ(system(cmd), 0);
        }
    }
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    ASSERT_EQ(system(cmd), 0);
    /* the GPU evaluates what the CPU does */
    gpu_check_agrees(&m, &SC, 0, 5, 12, 96);
    material_free(&m);
}

/* The decomposition on disk, for scene sc (G-buffers g) and params hp: a
 * fresh cache over the same directory reads it and the fit is the same to
 * the last bit; a flipped byte is caught and the level rebuilt.  The form
 * the fit reports must be `form`. */
static void disk_rounds(const scene *sc, const gbuf *g, const hf2d_params_t *hp,
                        const char *form)
{
    char dir[] = "/tmp/glint_test_hf2d_cache_XXXXXX", cmd[300];
    prep_scene_source src = {sv_borrowed, NULL, (void *)sc};
    material m[3];
    glint_err e;
    ASSERT(mkdtemp(dir));
    for (int round = 0; round < 3; round++) {
        cache *c;
        cache_entry *se;
        unsigned char all[SCENE_MAX_VIEWS];
        prep_request rq = {&method_hf2d, hp, NULL, all, NULL};
        prep *pp = NULL;
        img im[SCENE_MAX_VIEWS];
        json_t *rep;
        memset(all, 1, sizeof all);
        ASSERT_OK(cache_open(dir, (size_t)1 << 30, &c, &e));
        ASSERT_OK(prep_scene_acquire(c, "s", &src, &se, &e));
        rq.scene = se;
        ASSERT_OK(sv_paint(ANISO, sc, g, im, &e));
        ASSERT_MSG(prep_acquire(c, &rq, NULL, NULL, &pp, &e) == 0, "%s", e.msg);
        ASSERT_OK(prep_fit(pp, im, NULL, &m[round], &e));
        rep = prep_report(pp);
        printf("  round %d: %s form, disk %s, cold %.3f s\n", round,
               json_string_value(json_object_get(json_object_get(m[round].info,
                                                                 "precomputation"), "form")),
               json_string_value(json_object_get(rep, "disk")), prep_cold_seconds(pp));
        ASSERT(strcmp(json_string_value(json_object_get(
                          json_object_get(m[round].info, "precomputation"), "form")),
                      form) == 0);
        ASSERT_EQ(prep_from_disk(pp), round == 1);
        if (round == 2)
            ASSERT(strcmp(json_string_value(json_object_get(rep, "disk")), "rebuilt") == 0);
        json_decref(rep);
        for (int v = 0; v < sc->nviews; v++)
            img_free(&im[v]);
        prep_release(c, pp);
        cache_release(c, se);
        cache_close(c);
        if (round == 1) {
            snprintf(cmd, sizeof cmd,
                     "for f in $(find %s -name '*.hf2d'); do printf 'X' | dd of=$f bs=1 "
                     "seek=$(( $(stat -c %%s $f) / 2 )) conv=notrunc status=none; done", dir);
            ASSERT_EQ(system(cmd), 0);
        }
    }
    {
        const hf2d_factors *a = hf2d_of(&m[0]), *b = hf2d_of(&m[1]), *c3 = hf2d_of(&m[2]);
        ASSERT(a && b && c3);
        ASSERT(memcmp(a->logy, b->logy, 3 * (size_t)a->off[3] * sizeof *a->logy) == 0);
        ASSERT(memcmp(a->logy, c3->logy, 3 * (size_t)a->off[3] * sizeof *a->logy) == 0);
    }
    for (int k = 0; k < 3; k++)
        material_free(&m[k]);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    ASSERT_EQ(system(cmd), 0);
}

TEST(decomposition_on_disk)
{
    hf2d_params_t hp;
    ASSERT_OK(setup());
    method_hf2d.params_default(&hp);
    hp.sres = 16;
    disk_rounds(&SC, G, &hp, "normal");
}

/* The kernel form's operator on disk: a small raster (fewer samples than
 * the unknowns of three 2D factors). */
TEST(kernel_operator_on_disk)
{
    hf2d_params_t hp;
    scene_params sp;
    scene sc;
    gbuf *g;
    glint_err e;
    scene_params_default(&sp);
    sp.width = sp.height = 12;
    ASSERT_OK(scene_create(&sp, &sc, &e));
    ASSERT_OK(raster_scene(&sc, &g, &e));
    method_hf2d.params_default(&hp);
    hp.sres = 24;
    hp.dims[0] = hp.dims[1] = hp.dims[2] = 1;
    disk_rounds(&sc, g, &hp, "kernel");
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
}

TEST_LIST{
    TEST_ENTRY(frame_and_parabolic_map),
    TEST_ENTRY(anisotropic_ward_truth),
    TEST_ENTRY(equals_a_dense_least_squares_solve),
    TEST_ENTRY(kernel_form_equals_a_dense_least_squares_solve),
    TEST_ENTRY(anisotropy_needs_a_2d_factor),
    TEST_ENTRY(uniform_painting),
    TEST_ENTRY(dense_form_unreached_nodes_and_bad_shapes),
    TEST_ENTRY(the_method_saves_loads_and_renders),
    TEST_ENTRY(decomposition_on_disk),
    TEST_ENTRY(kernel_operator_on_disk),
};

TEST_MAIN()
