/* test_matmap.c: material maps by iterative residual factorization over a
 * prepared three-factor fit: a two-material painting (stripes over the
 * texture coordinates) against one material, the stop rules and bad input. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cache.h"
#include "check.h"
#include "fit.h"
#include "matmap.h"
#include "method_hf3.h"
#include "paint.h"
#include "prep.h"
#include "raster.h"
#include "samples.h"
#include "sv_fixture.h"

static scene SC;
static gbuf *G;
static cache *C;
static cache_entry *SE;
static prep *P;    /* view 0 painted */
static prep *PA;   /* every view painted */

static int setup(void)
{
    fit_params fp;
    unsigned char use[SCENE_MAX_VIEWS];
    glint_err e;
    if (P)
        return 0;
    fit_params_default(&fp);
    fp.res = 32;
    memset(use, 0, sizeof use);
    use[0] = 1; /* one painted view (see matmap.h on merging several) */
    if (sv_setup(64, &SC, &G, &C, &SE))
        return -1;
    {
        prep_request rq = {&method_hf3, &fp, SE, use, NULL};
        unsigned char all[SCENE_MAX_VIEWS];
        prep_request ra = {&method_hf3, &fp, SE, all, NULL};
        memset(all, 1, sizeof all);
        if (prep_acquire(C, &rq, NULL, NULL, &P, &e) ||
            prep_acquire(C, &ra, NULL, NULL, &PA, &e)) {
            fprintf(stderr, "setup: %s\n", e.msg);
            return -1;
        }
    }
    return 0;
}

static double coef_mean(const matmap *mm, int k)
{
    double m = 0.0;
    size_t nt = (size_t)mm->res * mm->res;
    for (size_t t = 0; t < nt; t++)
        m += mm->coef[(size_t)k * nt + t];
    return m / nt;
}

/* One material: one product holds it (its coefficients near 1), and a
 * tolerance stops the fit there. */
TEST(one_material_is_one_product)
{
    matmap mm;
    matmap_params mp;
    float *rgb;
    glint_err e;
    ASSERT_OK(setup());
    ASSERT((rgb = sv_painted(P, "lambert:kd=0.5/0.4/0.3", &SC, G)));
    matmap_params_default(&mp);
    mp.res = 64;
    mp.tol = 0.02;
    ASSERT_OK(matmap_fit(P, rgb, &mp, &mm, &e));
    printf("  lambert: %d product(s), stop %s, rel rms %.4f -> %.4f, mean coefficient %.3f\n",
           mm.k, mm.stop, mm.rel_rms[0], mm.rel_rms[mm.k], coef_mean(&mm, 0));
    ASSERT_EQ(mm.k, 1);
    ASSERT(strcmp(mm.stop, "tolerance") == 0);
    ASSERT_NEAR(mm.rel_rms[0], 1.0, 1e-12);
    ASSERT_LT(mm.rel_rms[1], 0.02);
    ASSERT_LT(0.85, coef_mean(&mm, 0));
    ASSERT(coef_mean(&mm, 0) <= 1.0);
    matmap_free(&mm);
    free(rgb);
}

/* Red plastic with gold stripes: one product cannot hold both; more
 * products lower the residual every time, down to the most allowed, under
 * either rule; on one painted view and on twelve, least squares per texel
 * ends lower than the smallest-value merge (the reason it is the default,
 * matmap.h). */
TEST(two_materials_need_more_than_one_product)
{
    static const char *spec = "stripes:freq=3,duty=0.5|lambert:kd=0.7/0.15/0.1|"
                              "ct:kd=0.05,f0=0.9/0.7/0.3,rough=0.25";
    for (int views = 0; views < 2; views++) {
        const prep *pp;
        double last[2];
        float *rgb;
        glint_err e;
        ASSERT_OK(setup());
        pp = views ? PA : P;
        ASSERT((rgb = sv_painted(pp, spec, &SC, G)));
        for (int merge = 0; merge < 2; merge++) {
            matmap mm;
            matmap_params mp;
            matmap_params_default(&mp);
            mp.merge = merge ? MATMAP_MERGE_MIN : MATMAP_MERGE_LSQ;
            mp.components = 5;
            mp.res = 64;
            mp.tol = 0.0;
            ASSERT_OK(matmap_fit(pp, rgb, &mp, &mm, &e));
            printf("  stripes, %s, merge %s: %d products, stop %s, %.3f s, rel rms:",
                   views ? "12 views" : "1 view", merge ? "min" : "lsq", mm.k, mm.stop,
                   mm.seconds);
            for (int k = 0; k <= mm.k; k++)
                printf(" %.4f", mm.rel_rms[k]);
            printf("\n");
            ASSERT_EQ(mm.k, 5);
            ASSERT(strcmp(mm.stop, "components") == 0);
            ASSERT_LT(0.05, mm.rel_rms[1]);
            for (int k = 1; k <= mm.k; k++)
                ASSERT_LT(mm.rel_rms[k], mm.rel_rms[k - 1]);
            for (int k = 0; k < mm.k; k++) /* coefficients are scales in [0, 1] */
                for (int t = 0; t < mm.res * mm.res; t++) {
                    float c = mm.coef[(size_t)k * mm.res * mm.res + t];
                    ASSERT(c >= -1e-6f && c <= 1.0f + 1e-6f);
                }
            last[merge] = mm.rel_rms[5];
            matmap_free(&mm);
        }
        ASSERT_LT(last[0], 0.5 * last[1]);
        free(rgb);
    }
}

TEST(bad_input_is_refused)
{
    matmap mm;
    matmap_params mp;
    float *rgb;
    glint_err e;
    ASSERT_OK(setup());
    ASSERT((rgb = sv_painted(P, "lambert", &SC, G)));
    matmap_params_default(&mp);
    mp.components = 0;
    ASSERT_EQ(matmap_fit(P, rgb, &mp, &mm, &e), GLINT_EINVAL);
    matmap_params_default(&mp);
    mp.res = 0;
    ASSERT_EQ(matmap_fit(P, rgb, &mp, &mm, &e), GLINT_EINVAL);
    matmap_params_default(&mp);
    rgb[7] = -0.5f;
    ASSERT_EQ(matmap_fit(P, rgb, &mp, &mm, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "sample 2") != NULL);
    rgb[7] = NAN;
    ASSERT_EQ(matmap_fit(P, rgb, &mp, &mm, &e), GLINT_EINVAL);
    free(rgb);
}

TEST_LIST{
    TEST_ENTRY(one_material_is_one_product),
    TEST_ENTRY(two_materials_need_more_than_one_product),
    TEST_ENTRY(bad_input_is_refused),
};

TEST_MAIN()
