/* test_readable.c: the readable summary of a material (readable.h) against
 * the analytic truths it was fitted to and against the material's own
 * evaluation: a Lambertian painting reads its albedo as the base colour and
 * the directional albedo, with no highlight; a Cook-Torrance painting reads
 * a base colour, highlight width and albedo near the truth's, computed here
 * from brdf_eval by code of this file; the summary's albedo agrees with a
 * four times finer quadrature of the same material; the polar data has its
 * peak at the mirror direction. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "method_hf3.h"
#include "readable.h"
#include "sv_fixture.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static scene SC;
static gbuf *G;
static cache *C;
static cache_entry *SE;

static int setup(void)
{
    return sv_setup(64, &SC, &G, &C, &SE);
}

static int fit(const char *spec, material *out)
{
    unsigned char all[SCENE_MAX_VIEWS];
    fit_params fp;
    prep_request rq = {&method_hf3, &fp, SE, all, NULL};
    prep *pp = NULL;
    img im[SCENE_MAX_VIEWS];
    glint_err e;
    int rc;
    fit_params_default(&fp);
    fp.res = 64;
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

static double num(const json_t *o, const char *path1, const char *path2)
{
    const json_t *x = json_object_get(o, path1);
    if (path2)
        x = json_object_get(x, path2);
    return json_is_number(x) ? json_number_value(x) : NAN;
}

static double rgb_at(const json_t *a, int c)
{
    return json_number_value(json_array_get(a, (size_t)c));
}

static double lum3(double r, double g, double b)
{
    return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

/* The truth's numbers, from brdf_eval: base colour (light and eye at 45
 * degrees, same side), half width of the highlight for a light at 30
 * degrees (0.05 degree steps), albedo at normal incidence (a 256 x 512
 * grid). */
static void truth_numbers(const brdf *b, double base[3], double *half, double alb[3])
{
    double n[3] = {0, 0, 1}, wi[3], wo[3], f[3], peak, fb;
    wi[0] = sin(M_PI / 4), wi[1] = 0, wi[2] = cos(M_PI / 4);
    brdf_eval(b, n, wi, wi, f);
    for (int c = 0; c < 3; c++)
        base[c] = M_PI * f[c];
    fb = lum3(f[0], f[1], f[2]);
    wi[0] = sin(M_PI / 6), wi[2] = cos(M_PI / 6);
    wo[0] = -wi[0], wo[1] = 0, wo[2] = wi[2];
    brdf_eval(b, n, wi, wo, f);
    peak = lum3(f[0], f[1], f[2]) - fb;
    *half = NAN;
    for (int k = 1; k < 1100; k++) {
        double t = (30.0 + 0.05 * k) * M_PI / 180.0;
        wo[0] = -sin(t), wo[2] = cos(t);
        brdf_eval(b, n, wi, wo, f);
        if (lum3(f[0], f[1], f[2]) - fb <= 0.5 * peak) {
            *half = 0.05 * k;
            break;
        }
    }
    alb[0] = alb[1] = alb[2] = 0.0;
    for (int a = 0; a < 256; a++)
        for (int p = 0; p < 512; p++) {
            double to = (a + 0.5) * M_PI / 512, po = (p + 0.5) * M_PI / 256;
            double w = cos(to) * sin(to) * (M_PI / 512) * (M_PI / 256);
            wo[0] = sin(to) * cos(po), wo[1] = sin(to) * sin(po), wo[2] = cos(to);
            brdf_eval(b, n, n, wo, f);
            for (int c = 0; c < 3; c++)
                alb[c] += f[c] * w;
        }
}

TEST(a_lambertian_painting_reads_its_albedo)
{
    material m;
    json_t *o, *a0;
    glint_err e;
    ASSERT_OK(setup());
    ASSERT_OK(fit("lambert:kd=0.5/0.3/0.2", &m));
    ASSERT_OK(material_readable(&m, &o, &e));
    a0 = json_object_get(json_array_get(json_object_get(o, "albedo"), 0), "rgb");
    printf("  base colour %.4f %.4f %.4f, albedo(0) %.4f %.4f %.4f, highlight strength %.4f\n",
           rgb_at(json_object_get(o, "base_colour"), 0),
           rgb_at(json_object_get(o, "base_colour"), 1),
           rgb_at(json_object_get(o, "base_colour"), 2), rgb_at(a0, 0), rgb_at(a0, 1),
           rgb_at(a0, 2), num(o, "highlight", "strength"));
    for (int c = 0; c < 3; c++) {
        double kd = c == 0 ? 0.5 : c == 1 ? 0.3 : 0.2;
        ASSERT_NEAR(rgb_at(json_object_get(o, "base_colour"), c), kd, 0.05 * kd);
        ASSERT_NEAR(rgb_at(a0, c), kd, 0.05 * kd);
    }
    ASSERT_LT(fabs(num(o, "highlight", "strength")), 0.1);
    ASSERT(json_is_null(json_object_get(json_object_get(o, "highlight"), "half_width_deg")));
    json_decref(o);
    material_free(&m);
}

TEST(a_cook_torrance_painting_reads_near_the_truth)
{
    static const char *const specs[] = {"ct:kd=0.3/0.2/0.1,f0=0.3,rough=0.2",
                                        "ct:kd=0.2,f0=0.1,rough=0.3"};
    for (int s = 0; s < 2; s++) {
        material m;
        json_t *o, *a0, *pol;
        brdf b;
        glint_err e;
        double base[3], half, alb[3], fine[3], hw;
        ASSERT_OK(setup());
        ASSERT_OK(brdf_parse(specs[s], &b, &e));
        truth_numbers(&b, base, &half, alb);
        ASSERT_OK(fit(specs[s], &m));
        ASSERT_OK(material_readable(&m, &o, &e));
        a0 = json_object_get(json_array_get(json_object_get(o, "albedo"), 0), "rgb");
        hw = num(o, "highlight", "half_width_deg");
        printf("  %s: base %.3f (truth %.3f), half width %.2f deg (truth %.2f), albedo(0) "
               "%.3f (truth %.3f), strength %.2f\n", specs[s], rgb_at(json_object_get(o,
               "base_colour"), 0), base[0], hw, half, rgb_at(a0, 0), alb[0],
               num(o, "highlight", "strength"));
        for (int c = 0; c < 3; c++) {
            ASSERT_NEAR(rgb_at(json_object_get(o, "base_colour"), c), base[c], 0.15 * base[c]);
            ASSERT_NEAR(rgb_at(a0, c), alb[c], 0.1 * alb[c]);
        }
        ASSERT_NEAR(hw, half, 0.3 * half);
        /* the summary's albedo against the material's own, four times finer */
        material_albedo(&m, 0.0, 4 * READABLE_ALBEDO_THETA, fine);
        for (int c = 0; c < 3; c++)
            ASSERT_NEAR(rgb_at(a0, c), fine[c], 0.01 * fine[c]);
        /* polar: at 45 degrees the largest value is at the mirror (+45) */
        pol = json_array_get(json_object_get(o, "polar"), 1);
        {
            json_t *th = json_object_get(pol, "theta_o_deg"), *fs = json_object_get(pol, "f");
            size_t best = 0;
            for (size_t i = 0; i < json_array_size(fs); i++)
                if (rgb_at(json_array_get(fs, i), 1) > rgb_at(json_array_get(fs, best), 1))
                    best = i;
            ASSERT_NEAR(json_number_value(json_array_get(th, best)), 45.0, 5.0);
        }
        json_decref(o);
        material_free(&m);
    }
}

TEST(an_empty_material_is_refused)
{
    material m;
    json_t *o;
    glint_err e;
    memset(&m, 0, sizeof m);
    ASSERT_EQ(material_readable(&m, &o, &e), GLINT_EINVAL);
    ASSERT(o == NULL);
}

TEST_LIST{
    TEST_ENTRY(a_lambertian_painting_reads_its_albedo),
    TEST_ENTRY(a_cook_torrance_painting_reads_near_the_truth),
    TEST_ENTRY(an_empty_material_is_refused),
};

TEST_MAIN()
