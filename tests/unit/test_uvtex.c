/* test_uvtex.c: textures over texture coordinates from samples: means of
 * the samples in reached texels, push-pull between them, the merge of
 * several views, and bad input. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "img.h"
#include "uvtex.h"

static unsigned rng = 2463534242u;
static float frand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return (float)(rng >> 8) / 16777216.0f;
}

/* One value everywhere gives that value in every texel, reached or not. */
TEST(a_constant_fills_the_whole_texture)
{
    int n = 500, res = 64;
    float *uv = malloc(2 * (size_t)n * sizeof *uv), *val = malloc(3 * (size_t)n * sizeof *val);
    float *tex = malloc(3 * (size_t)res * res * sizeof *tex);
    uvtex_report rep;
    glint_err e;
    rng = 2463534242u; /* the same samples whatever ran before */
    ASSERT(uv && val && tex);
    for (int s = 0; s < n; s++) {
        uv[2 * s] = frand();
        uv[2 * s + 1] = frand();
        val[3 * s] = 0.25f;
        val[3 * s + 1] = 0.5f;
        val[3 * s + 2] = 2.0f;
    }
    ASSERT_OK(uvtex_from_samples(uv, val, n, 3, res, tex, NULL, &rep, &e));
    ASSERT_EQ(rep.texels_reached + rep.texels_filled, res * res);
    ASSERT_LE(rep.texels_reached, n);
    ASSERT(rep.texels_filled > 0 && rep.most_per_texel >= 1);
    for (int t = 0; t < res * res; t++) {
        ASSERT_NEAR(tex[3 * t], 0.25, 1e-6);
        ASSERT_NEAR(tex[3 * t + 1], 0.5, 1e-6);
        ASSERT_NEAR(tex[3 * t + 2], 2.0, 1e-6);
    }
    free(uv);
    free(val);
    free(tex);
}

/* Samples of a ramp over the left half only: a reached texel holds the
 * mean of its own samples (counted by hand), and every texel, the right
 * half's included, lies between the smallest and largest reached value. */
TEST(reached_texels_hold_means_and_holes_lie_between_them)
{
    int n = 4000, res = 32;
    float *uv = malloc(2 * (size_t)n * sizeof *uv), *val = malloc((size_t)n * sizeof *val);
    float *tex = malloc((size_t)res * res * sizeof *tex);
    int *hits = malloc((size_t)res * res * sizeof *hits);
    double lo = 1e30, hi = -1e30;
    uvtex_report rep;
    glint_err e;
    rng = 2463534242u; /* the same samples whatever ran before */
    ASSERT(uv && val && tex && hits);
    for (int s = 0; s < n; s++) {
        uv[2 * s] = 0.5f * frand();
        uv[2 * s + 1] = frand();
        val[s] = 1.0f + 3.0f * uv[2 * s + 1] + (float)(s % 5) * 0.01f;
    }
    ASSERT_OK(uvtex_from_samples(uv, val, n, 1, res, tex, hits, &rep, &e));
    ASSERT(rep.texels_filled >= res * res / 2);
    for (int j = 0; j < res; j++)
        for (int i = 0; i < res; i++) {
            int t = j * res + i, k = 0;
            double sum = 0.0;
            for (int s = 0; s < n; s++)
                if ((int)(uv[2 * s] * res) == i && (int)(uv[2 * s + 1] * res) == j) {
                    sum += val[s];
                    k++;
                }
            ASSERT_EQ(hits[t], k);
            if (k) {
                ASSERT_NEAR(tex[t], sum / k, 1e-5);
                lo = fmin(lo, tex[t]);
                hi = fmax(hi, tex[t]);
            } else {
                ASSERT(i >= res / 2 - 1); /* only the unsampled half has holes */
            }
        }
    for (int t = 0; t < res * res; t++)
        ASSERT_MSG(tex[t] >= lo - 1e-5 && tex[t] <= hi + 1e-5, "texel %d: %g outside [%g, %g]",
                   t, tex[t], lo, hi);
    /* the far right follows the ramp in v, not one flat value */
    ASSERT_LT(tex[2 * res - 1] + 1.0, tex[(res - 2) * res + res - 1]);
    free(uv);
    free(val);
    free(tex);
    free(hits);
}

/* A texture far finer than the sampling (128^2 from 10 samples), and one
 * sample alone, still define every texel. */
TEST(more_texels_than_samples_and_a_single_sample)
{
    int res = 128;
    float uv[20], val[10], *tex = malloc((size_t)res * res * sizeof *tex);
    uvtex_report rep;
    glint_err e;
    rng = 2463534242u; /* the same samples whatever ran before */
    ASSERT(tex);
    for (int s = 0; s < 10; s++) {
        uv[2 * s] = frand();
        uv[2 * s + 1] = frand();
        val[s] = (float)s;
    }
    ASSERT_OK(uvtex_from_samples(uv, val, 10, 1, res, tex, NULL, &rep, &e));
    ASSERT_LE(rep.texels_reached, 10);
    for (int t = 0; t < res * res; t++)
        ASSERT(tex[t] >= -1e-5 && tex[t] <= 9.0 + 1e-5);
    ASSERT_OK(uvtex_from_samples(uv, val + 7, 1, 1, res, tex, NULL, &rep, &e));
    ASSERT_EQ(rep.texels_reached, 1);
    for (int t = 0; t < res * res; t++)
        ASSERT_NEAR(tex[t], 7.0, 1e-5);
    /* the edges: u = 1 and v = 1 fall in the last column and row */
    {
        float c[4] = {1.0f, 1.0f, 0.0f, 0.0f}, v2[2] = {5.0f, 1.0f};
        int h[4];
        ASSERT_OK(uvtex_from_samples(c, v2, 2, 1, 2, tex, h, &rep, &e));
        ASSERT(h[0] == 1 && h[3] == 1 && h[1] == 0 && h[2] == 0);
        ASSERT_NEAR(tex[3], 5.0, 1e-6);
        ASSERT_NEAR(tex[0], 1.0, 1e-6);
    }
    free(tex);
}

/* Texels both views reach keep the smaller value; one only a view reaches
 * takes that view's; the counts add; a texel neither reaches stays a hole. */
TEST(the_merge_keeps_the_smallest_value_where_views_reach)
{
    float a[5] = {1, 2, 3, 0, 7}, b[5] = {0.5f, 3, 9, -2, 8};
    int ha[5] = {1, 1, 0, 0, 2}, hb[5] = {2, 1, 1, 0, 0};
    uvtex_merge_min(a, ha, b, hb, 5, 1);
    ASSERT(a[0] == 0.5f && a[1] == 2 && a[2] == 9 && a[3] == 0 && a[4] == 7);
    ASSERT(ha[0] == 3 && ha[1] == 2 && ha[2] == 1 && ha[3] == 0 && ha[4] == 2);
}

TEST(bad_input_is_named)
{
    float uv[4] = {0.5f, 0.5f, 1.5f, 0.2f}, val[2] = {1.0f, 2.0f}, tex[16];
    glint_err e;
    ASSERT_EQ(uvtex_from_samples(uv, val, 2, 1, 4, tex, NULL, NULL, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "sample 1") != NULL);
    uv[2] = NAN;
    ASSERT_EQ(uvtex_from_samples(uv, val, 2, 1, 4, tex, NULL, NULL, &e), GLINT_EINVAL);
    uv[2] = 0.1f;
    val[0] = INFINITY;
    ASSERT_EQ(uvtex_from_samples(uv, val, 2, 1, 4, tex, NULL, NULL, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "sample 0") != NULL);
    val[0] = 1.0f;
    ASSERT_EQ(uvtex_from_samples(uv, val, 0, 1, 4, tex, NULL, NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(uvtex_from_samples(uv, val, 2, 4, 4, tex, NULL, NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(uvtex_from_samples(uv, val, 2, 1, 0, tex, NULL, NULL, &e), GLINT_ERANGE);
    ASSERT_EQ(uvtex_from_samples(uv, val, 2, 1, UVTEX_MAX_RES + 1, tex, NULL, NULL, &e),
              GLINT_ERANGE);
    /* push-pull needs a coverage channel and something covered */
    {
        img im;
        ASSERT_OK(img_alloc(&im, 4, 4, 2, &e));
        ASSERT_EQ(img_fill_holes(&im, &e), GLINT_EINVAL);
        img_free(&im);
        ASSERT_OK(img_alloc(&im, 4, 4, 1, &e));
        ASSERT_EQ(img_fill_holes(&im, &e), GLINT_EINVAL);
        img_free(&im);
    }
}

TEST_LIST{
    TEST_ENTRY(a_constant_fills_the_whole_texture),
    TEST_ENTRY(reached_texels_hold_means_and_holes_lie_between_them),
    TEST_ENTRY(more_texels_than_samples_and_a_single_sample),
    TEST_ENTRY(the_merge_keeps_the_smallest_value_where_views_reach),
    TEST_ENTRY(bad_input_is_named),
};

TEST_MAIN()
