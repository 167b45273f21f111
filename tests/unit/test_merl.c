/* test_merl.c: materials tabulated in the MERL layout (merl.h).
 *
 * - The bins: direction pairs built here from each bin's half/difference
 *   angles (this file's own construction, not merl.c's) fall in that bin.
 * - A fitted hf3 material (a Cook-Torrance painting) written to bytes and
 *   read back: at bin centres, in any frame, the table gives the material's
 *   f to rounding; at random direction pairs the nearest-bin lookup is
 *   close (the figures printed); isotropy detected.
 * - An anisotropic hf2d material (brushed Ward) is detected as such and each
 *   bin holds its average over the 8 half-vector azimuths (computed here).
 * - A table of an analytic truth paints the views as the truth does (under
 *   the point lights and under a sky) but for the bins' quantization.
 * - Bad files are refused with a reason: short, wrong dimensions, padded,
 *   non-finite entries, a missing path. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "brdf.h"
#include "check.h"
#include "env.h"
#include "merl.h"
#include "merl_material.h"
#include "paint.h"
#include "method_hf2d.h"
#include "method_hf3.h"
#include "sv_fixture.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static scene SC;
static gbuf *G;
static cache *C;
static cache_entry *SE;
static int ready;

static int setup(void)
{
    if (!ready)
        ready = sv_setup(48, &SC, &G, &C, &SE) == 0;
    return ready ? 0 : -1;
}

static int fit(const method *meth, const void *params, const char *spec, material *out)
{
    return sv_fit(meth, params, spec, &SC, G, C, SE, out);
}

/* The centre of bin (i, j, k) with the half vector at azimuth ph, built
 * from spherical angles: h at (theta_h, ph), and wi = cos(td) h +
 * sin(td) (cos(pd) u + sin(pd) v), u and v the unit directions in which h
 * moves as theta_h and ph grow; wo the mirror of wi about h. */
static void centre(int i, int j, int k, double ph, double wi[3], double wo[3])
{
    double th = pow((i + 0.5) / 90.0, 2) * M_PI / 2, td = (j + 0.5) * M_PI / 180.0,
           pd = (k + 0.5) * M_PI / 180.0;
    double h[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
    double u[3] = {cos(th) * cos(ph), cos(th) * sin(ph), -sin(th)};
    double v[3] = {-sin(ph), cos(ph), 0.0};
    for (int e = 0; e < 3; e++)
        wi[e] = cos(td) * h[e] + sin(td) * (cos(pd) * u[e] + sin(pd) * v[e]);
    for (int e = 0; e < 3; e++)
        wo[e] = 2.0 * cos(td) * h[e] - wi[e];
}

static unsigned rnd(unsigned *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

static double urand(unsigned *s)
{
    return rnd(s) / 16777216.0;
}

/* a rotation taking +Z to a random unit n (columns t, b, n) */
static void random_frame(unsigned *s, double R[3][3])
{
    double z = 2 * urand(s) - 1, p = 2 * M_PI * urand(s), r = sqrt(1 - z * z);
    double n[3] = {r * cos(p), r * sin(p), z}, a[3] = {0, 0, 1}, t[3], b[3], l;
    if (fabs(n[2]) > 0.9)
        a[0] = 1, a[2] = 0;
    t[0] = a[1] * n[2] - a[2] * n[1], t[1] = a[2] * n[0] - a[0] * n[2],
    t[2] = a[0] * n[1] - a[1] * n[0];
    l = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int e = 0; e < 3; e++)
        t[e] /= l;
    b[0] = n[1] * t[2] - n[2] * t[1], b[1] = n[2] * t[0] - n[0] * t[2],
    b[2] = n[0] * t[1] - n[1] * t[0];
    for (int e = 0; e < 3; e++)
        R[e][0] = t[e], R[e][1] = b[e], R[e][2] = n[e];
}

static void apply(double R[3][3], const double v[3], double out[3])
{
    for (int e = 0; e < 3; e++)
        out[e] = R[e][0] * v[0] + R[e][1] * v[1] + R[e][2] * v[2];
}

TEST(every_bin_centre_falls_in_its_bin)
{
    long wrong = 0, n = 0;
    for (int i = 0; i < 90; i++)
        for (int j = 0; j < 90; j++)
            for (int k = 0; k < 180; k += 7) {
                double wi[3], wo[3];
                centre(i, j, k, 0.37 * i, wi, wo);
                wrong += merl_index(wi, wo) != k + 180L * (j + 90L * i);
                n++;
            }
    printf("  %ld bin centres, %ld in another bin\n", n, wrong);
    ASSERT_EQ(wrong, 0);
}

TEST(an_hf3_material_round_trips_through_the_file)
{
    material m;
    merl_table t, back;
    merl_stats st;
    void *data;
    size_t len;
    fit_params fp;
    glint_err e;
    unsigned s = 7;
    double worst = 0.0, errs[2000];
    int ne = 0;

    ASSERT_OK(setup());
    fit_params_default(&fp);
    fp.res = 64;
    ASSERT_OK(fit(&method_hf3, &fp, "ct:kd=0.4/0.3/0.2,f0=0.2,rough=0.3", &m));
    ASSERT_OK(merl_from_material(&m, 2, &t, &st, &e));
    printf("  tabulated in %.3f s: anisotropic %d, azimuths %d, below the horizon %ld, "
           "non-finite %ld, largest f %.4g\n",
           st.seconds, st.anisotropic, st.azimuths, st.below_horizon, st.nonfinite, st.max_f);
    ASSERT_EQ(st.anisotropic, 0);
    ASSERT_EQ(st.azimuths, 1);
    ASSERT_EQ(st.nonfinite, 0);
    ASSERT_OK(merl_write_mem(&t, &data, &len, &e));
    ASSERT_EQ(len, MERL_FILE_BYTES);
    {
        int dims[3];
        double first;
        memcpy(dims, data, sizeof dims);
        memcpy(&first, (char *)data + 12, 8);
        ASSERT(dims[0] == 90 && dims[1] == 90 && dims[2] == 180);
        ASSERT_NEAR(first * merl_scale[0], t.f[0], 1e-15 + 1e-13 * fabs(t.f[0]));
    }
    ASSERT_OK(merl_read_mem(data, len, &back, &e));
    free(data);
    /* bin centres, in random frames: the material's f to rounding */
    for (int q = 0; q < 3000; q++) {
        int i = (int)(rnd(&s) % 90), j = (int)(rnd(&s) % 80), k = (int)(rnd(&s) % 180);
        double R[3][3], wi[3], wo[3], a[3], b[3], n[3], g[3], f[3];
        centre(i, j, k, 2 * M_PI * urand(&s), wi, wo);
        if (wi[2] < 0.02 || wo[2] < 0.02)
            continue;
        random_frame(&s, R);
        apply(R, wi, a);
        apply(R, wo, b);
        n[0] = R[0][2], n[1] = R[1][2], n[2] = R[2][2];
        merl_eval(&back, n, a, b, g);
        material_eval(&m, n, a, b, f);
        for (int c = 0; c < 3; c++) {
            double want = f[c] / wi[2], d = fabs(g[c] - want) / (fabs(want) + 1e-9);
            if (d > worst)
                worst = d;
        }
    }
    printf("  at bin centres in random frames: worst relative difference %.2e\n", worst);
    ASSERT_LT(worst, 1e-9);
    /* random pairs: the nearest bin against the material (luminance) */
    while (ne < 2000) {
        double wi[3], wo[3], n[3] = {0, 0, 1}, g[3], f[3], yf, yg;
        double ti = acos(urand(&s) * 0.97 + 0.03), to = acos(urand(&s) * 0.97 + 0.03);
        double pi = 2 * M_PI * urand(&s), po = 2 * M_PI * urand(&s);
        wi[0] = sin(ti) * cos(pi), wi[1] = sin(ti) * sin(pi), wi[2] = cos(ti);
        wo[0] = sin(to) * cos(po), wo[1] = sin(to) * sin(po), wo[2] = cos(to);
        merl_eval(&back, n, wi, wo, g);
        material_eval(&m, n, wi, wo, f);
        yf = (0.2126 * f[0] + 0.7152 * f[1] + 0.0722 * f[2]) / wi[2];
        yg = 0.2126 * g[0] + 0.7152 * g[1] + 0.0722 * g[2];
        errs[ne++] = fabs(yg - yf) / (yf + 1e-6);
    }
    for (int a = 1; a < ne; a++) /* insertion sort: 2000 values */
        for (int b = a; b > 0 && errs[b] < errs[b - 1]; b--) {
            double x = errs[b];
            errs[b] = errs[b - 1], errs[b - 1] = x;
        }
    printf("  random pairs, nearest bin against the material: median %.4f, 90th percentile "
           "%.4f relative\n",
           errs[ne / 2], errs[ne * 9 / 10]);
    /* the layout's own limit: one value per bin (1 degree in theta_d and
     * phi_d), read at the nearest bin as every MERL reader does; across a
     * highlight that is a few percent to tens of percent */
    ASSERT_LT(errs[ne / 2], 0.03);
    ASSERT_LT(errs[ne * 9 / 10], 0.3);
    merl_free(&t);
    merl_free(&back);
    material_free(&m);
}

TEST(an_anisotropic_material_is_averaged_over_azimuths)
{
    material m;
    merl_table t;
    merl_stats st;
    hf2d_params_t hp;
    glint_err e;
    unsigned s = 11;
    double worst = 0.0, spread = 0.0;

    ASSERT_OK(setup());
    method_hf2d.params_default(&hp);
    ASSERT_OK(fit(&method_hf2d, &hp, "ward:kd=0.3,ks=0.5,rough=0.1,rough_y=0.35", &m));
    ASSERT_OK(merl_from_material(&m, 0, &t, &st, &e));
    printf("  anisotropic %d, azimuths %d, %.3f s\n", st.anisotropic, st.azimuths, st.seconds);
    ASSERT_EQ(st.anisotropic, 1);
    ASSERT_EQ(st.azimuths, MERL_AZIMUTHS);
    for (int q = 0; q < 300; q++) {
        int i = 5 + (int)(rnd(&s) % 60), j = (int)(rnd(&s) % 60), k = (int)(rnd(&s) % 180);
        double avg[3] = {0, 0, 0}, lo = INFINITY, hi = 0.0, wi[3], wo[3], f[3];
        long idx = k + 180L * (j + 90L * i);
        for (int a = 0; a < MERL_AZIMUTHS; a++) {
            centre(i, j, k, 2 * M_PI * a / MERL_AZIMUTHS, wi, wo);
            if (wi[2] <= 1e-12 || wo[2] <= 1e-12) {
                f[0] = f[1] = f[2] = 0.0;
            } else {
                double n[3] = {0, 0, 1};
                material_eval(&m, n, wi, wo, f);
                for (int c = 0; c < 3; c++)
                    f[c] /= wi[2];
            }
            for (int c = 0; c < 3; c++)
                avg[c] += f[c] / MERL_AZIMUTHS;
            lo = f[0] < lo ? f[0] : lo;
            hi = f[0] > hi ? f[0] : hi;
        }
        for (int c = 0; c < 3; c++) {
            double d = fabs(t.f[(size_t)c * MERL_N + idx] - avg[c]) / (fabs(avg[c]) + 1e-9);
            worst = d > worst ? d : worst;
        }
        if (hi > 0 && (hi - lo) / hi > spread)
            spread = (hi - lo) / hi;
    }
    printf("  each bin against the 8-azimuth average computed here: worst %.2e (the azimuths "
           "differ by up to %.0f%%)\n",
           worst, 100 * spread);
    ASSERT_LT(worst, 1e-9);
    ASSERT_LT(0.1, spread); /* the average hides a real anisotropy */
    merl_free(&t);
    material_free(&m);
}

static void brdf_f(const void *ctx, const double n[3], const double wi[3], const double wo[3],
                   double f[3])
{
    brdf_eval(ctx, n, wi, wo, f);
}

static double rel_rms(const img *a, const img *b)
{
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < (size_t)3 * a->width * a->height; i++) {
        double d = a->px[i] - b->px[i];
        num += d * d;
        den += (double)b->px[i] * b->px[i];
    }
    return den > 0 ? sqrt(num / den) : INFINITY;
}

TEST(a_measured_table_paints_as_the_truth_it_holds)
{
    brdf b;
    merl_table t;
    merl_stats st;
    img ref[SCENE_MAX_VIEWS], got[SCENE_MAX_VIEWS];
    env_map em;
    env_lights el;
    glint_err e;
    double worst = 0.0, worst_env = 0.0;

    ASSERT_OK(setup());
    ASSERT_OK(brdf_parse("ct:kd=0.4/0.3/0.2,f0=0.2,rough=0.3", &b, &e));
    ASSERT_OK(merl_tabulate(brdf_f, &b, 0, &t, &st, &e));
    ASSERT_EQ(st.anisotropic, 0);
    memset(ref, 0, sizeof ref);
    memset(got, 0, sizeof got);
    ASSERT_OK(paint_views(&b, G, SC.views, SC.nviews, 1.0, ref, NULL, &e));
    ASSERT_OK(paint_views_fn(merl_truth, &t, G, SC.views, SC.nviews, 1.0, got, NULL, &e));
    for (int v = 0; v < SC.nviews; v++) {
        double r = rel_rms(&got[v], &ref[v]);
        worst = r > worst ? r : worst;
        img_free(&ref[v]);
        img_free(&got[v]);
    }
    ASSERT_OK(env_resolve("sky", &em, &e));
    ASSERT_OK(env_compress(&em, ENV_CUT_MEDIAN, 64, 0.0, 1.0, &el, &e));
    ASSERT_OK(paint_views_env(&b, G, 3, &SC.mesh, &el, 0, 1.0, ref, &e));
    ASSERT_OK(paint_views_env_fn(merl_truth, &t, G, 3, &SC.mesh, &el, 0, 1.0, got, &e));
    for (int v = 0; v < 3; v++) {
        double r = rel_rms(&got[v], &ref[v]);
        worst_env = r > worst_env ? r : worst_env;
        img_free(&ref[v]);
        img_free(&got[v]);
    }
    printf("  painted from the table against the truth: worst view %.4f relative RMS under "
           "the point lights, %.4f under the sky\n",
           worst, worst_env);
    ASSERT_LT(worst, 0.02);
    ASSERT_LT(worst_env, 0.02);
    ASSERT_EQ(paint_views_fn(NULL, &t, G, SC.views, SC.nviews, 1.0, got, NULL, &e), GLINT_EINVAL);
    env_lights_free(&el);
    env_map_free(&em);
    merl_free(&t);
}

/* A BRDF negative where the half vector is near the normal (what an srbf
 * fit with constraints none can make), positive elsewhere. */
static void negative_near_normal(const void *ctx, const double n[3], const double wi[3],
                                 const double wo[3], double f[3])
{
    double h[3], hl, c;
    (void)ctx;
    for (int e = 0; e < 3; e++)
        h[e] = wi[e] + wo[e];
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    c = (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl;
    for (int e = 0; e < 3; e++)
        f[e] = c > 0.9 ? -0.5 : 0.25;
}

TEST(negative_values_are_written_as_zero_and_counted)
{
    merl_table t;
    merl_stats st;
    glint_err e;
    long zero = 0, neg = 0;
    ASSERT_OK(merl_tabulate(negative_near_normal, NULL, 2, &t, &st, &e));
    for (size_t i = 0; i < (size_t)3 * MERL_N; i++) {
        neg += t.f[i] < 0.0;
        zero += t.f[i] == 0.0;
    }
    printf("  %ld bins negative (written 0), %ld below the horizon\n", st.negative,
           st.below_horizon);
    /* a table's readers take entries below 0 for "no data" */
    ASSERT_EQ(neg, 0);
    ASSERT(st.negative > 1000 && st.negative < MERL_N);
    ASSERT(zero >= 3 * st.negative);
    merl_free(&t);
}

TEST(bad_files_are_refused_with_a_reason)
{
    merl_table t;
    glint_err e;
    size_t len = MERL_FILE_BYTES;
    unsigned char *p = calloc(1, len + 8);
    int dims[3] = {90, 90, 180}, bad[3] = {90, 90, 360};
    double nan_v = NAN;
    ASSERT(p != NULL);
    ASSERT_EQ(merl_read_mem(p, 8, &t, &e), GLINT_EFORMAT);
    memcpy(p, bad, sizeof bad);
    ASSERT_EQ(merl_read_mem(p, len, &t, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "90 x 90 x 360") != NULL);
    memcpy(p, dims, sizeof dims);
    ASSERT_EQ(merl_read_mem(p, len - 8, &t, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "truncated") != NULL);
    ASSERT_EQ(merl_read_mem(p, len + 8, &t, &e), GLINT_EFORMAT);
    ASSERT_OK(merl_read_mem(p, len, &t, &e)); /* all zero: a black material */
    merl_free(&t);
    memcpy(p + 12 + 8 * (size_t)(MERL_N + 5), &nan_v, 8);
    ASSERT_EQ(merl_read_mem(p, len, &t, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "green") != NULL);
    ASSERT(t.f == NULL);
    free(p);
    ASSERT(merl_read("/nonexistent/glint.binary", &t, &e) != 0);
    {
        material empty;
        memset(&empty, 0, sizeof empty);
        ASSERT_EQ(merl_from_material(&empty, 1, &t, NULL, &e), GLINT_EINVAL);
    }
}

TEST_LIST{
    TEST_ENTRY(every_bin_centre_falls_in_its_bin),
    TEST_ENTRY(an_hf3_material_round_trips_through_the_file),
    TEST_ENTRY(an_anisotropic_material_is_averaged_over_azimuths),
    TEST_ENTRY(a_measured_table_paints_as_the_truth_it_holds),
    TEST_ENTRY(negative_values_are_written_as_zero_and_counted),
    TEST_ENTRY(bad_files_are_refused_with_a_reason),
};

TEST_MAIN()
