/* test_gbuf.c: G-buffers read back (gbuf.h: gbuf_read_exr, gbuf_from_named):
 * a G-buffer written by gbuf_write_exr reads back as it was written; one
 * made elsewhere (lower-case and short channel names, no mask, unnormalized
 * vectors, no uv) reads as covered where its vectors are, normalized; what
 * cannot be read is refused naming the channel or the pixel; the content
 * hash changes with the content.  Without wi (gbuf_from_named_ex, need_wi
 * 0) the light's direction is left zero; gbfit_samples makes the samples
 * of the painted views by the method's rule (gbfit.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "gbfit.h"
#include "gbuf.h"
#include "img.h"
#include "raster.h"
#include "scene.h"

TEST(a_written_gbuffer_reads_back_as_written)
{
    scene_params sp;
    scene sc;
    gbuf g, back;
    glint_err e;
    char dir[] = "/tmp/glint_test_gbuf_XXXXXX", path[128], h1[33], h2[33];
    int has_uv = 0;
    long diff = 0;

    ASSERT(mkdtemp(dir));
    scene_params_default(&sp);
    sp.width = sp.height = 32;
    ASSERT_OK(scene_create(&sp, &sc, &e));
    ASSERT_OK(raster_view(&sc.mesh, &sc.views[3], 32, 32, &g, &e));
    snprintf(path, sizeof path, "%s/view_03.exr", dir);
    ASSERT_OK(gbuf_write_exr(&g, path, &e));
    ASSERT_OK(gbuf_read_exr(path, &back, &has_uv, &e));
    ASSERT_EQ(has_uv, 1);
    ASSERT_EQ(gbuf_count(&back), gbuf_count(&g));
    for (size_t p = 0; p < 32 * 32; p++) {
        diff += g.mask[p] != back.mask[p];
        for (int k = 0; k < 3 && g.mask[p]; k++)
            diff += fabsf(g.nrm[3 * p + k] - back.nrm[3 * p + k]) > 1e-6f ||
                    fabsf(g.wi[3 * p + k] - back.wi[3 * p + k]) > 1e-6f ||
                    fabsf(g.wo[3 * p + k] - back.wo[3 * p + k]) > 1e-6f ||
                    g.pos[3 * p + k] != back.pos[3 * p + k];
        for (int k = 0; k < 2 && g.mask[p]; k++)
            diff += g.uv[2 * p + k] != back.uv[2 * p + k];
    }
    printf("  %ld covered pixels, %ld values differ\n", gbuf_count(&g), diff);
    ASSERT_EQ(diff, 0);
    gbuf_hash(&back, 1, h1);
    back.nrm[3 * 500] += 1e-3f;
    gbuf_hash(&back, 1, h2);
    ASSERT(strcmp(h1, h2) != 0);
    gbuf_free(&g);
    gbuf_free(&back);
    scene_free(&sc);
    unlink(path);
    rmdir(dir);
}

/* A 4 x 1 image of channels names[nch], pixel values vals[4][nch]. */
static img_named make(int nch, const char *const *names, const float *vals)
{
    img_named im;
    im.width = 4;
    im.height = 1;
    im.channels = nch;
    im.names = calloc((size_t)nch, sizeof *im.names);
    im.px = malloc(4 * (size_t)nch * sizeof *im.px);
    for (int c = 0; c < nch; c++)
        im.names[c] = strdup(names[c]);
    memcpy(im.px, vals, 4 * (size_t)nch * sizeof *im.px);
    return im;
}

TEST(a_gbuffer_made_elsewhere_reads)
{
    static const char *const names[9] = {"Nx", "Ny", "Nz", "wi.x", "wi.y", "wi.z",
                                         "WO.X", "WO.Y", "WO.Z"};
    const float vals[4][9] = {{0, 0, 2, 0, 1, 1, 0, -3, 3},  /* covered, unnormalized */
                              {0, 0, 0, 0, 0, 0, 0, 0, 0},   /* background */
                              {1, 0, 0, 1, 0, 0, 1, 0, 0},   /* covered */
                              {0, 0, 1, 0, 0, 1, 0, 0, 1}};
    img_named im = make(9, names, &vals[0][0]);
    gbuf g;
    glint_err e;
    int has_uv = 1;
    ASSERT_OK(gbuf_from_named(&im, "aov.exr", &g, &has_uv, &e));
    ASSERT_EQ(has_uv, 0);
    ASSERT(g.mask[0] && !g.mask[1] && g.mask[2] && g.mask[3]);
    ASSERT_NEAR(g.nrm[2], 1.0, 1e-7);
    ASSERT_NEAR(g.wi[1], sqrt(0.5), 1e-7);
    ASSERT_NEAR(g.wo[1], -sqrt(0.5), 1e-7);
    gbuf_free(&g);
    img_named_free(&im);
}

TEST(what_cannot_be_read_is_refused_naming_it)
{
    static const char *const some[6] = {"N.X", "N.Y", "N.Z", "wi.X", "wi.Y", "wi.Z"};
    static const char *const masked[10] = {"mask", "N.X", "N.Y", "N.Z", "wi.X",
                                           "wi.Y", "wi.Z", "wo.X", "wo.Y", "wo.Z"};
    float six[4][6] = {{0}}, ten[4][10] = {{0}};
    img_named a = make(6, some, &six[0][0]), b;
    gbuf g;
    glint_err e;
    int has_uv;
    ASSERT_EQ(gbuf_from_named(&a, "a.exr", &g, &has_uv, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "wo.X") != NULL);
    for (int p = 0; p < 4; p++)
        ten[p][0] = 1, ten[p][3] = ten[p][6] = ten[p][9] = 1;
    ten[2][6] = 0; /* in the mask, wi = 0 */
    b = make(10, masked, &ten[0][0]);
    ASSERT_EQ(gbuf_from_named(&b, "b.exr", &g, &has_uv, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "x 2") != NULL && strstr(e.msg, "wi") != NULL);
    b.px[2 * 10 + 6] = NAN;
    ASSERT_EQ(gbuf_from_named(&b, "b.exr", &g, &has_uv, &e), GLINT_ENONFINITE);
    ASSERT(g.mask == NULL); /* nothing half-built is left */
    img_named_free(&a);
    img_named_free(&b);
    ASSERT(gbuf_read_exr("/nonexistent/view_00.exr", &g, &has_uv, &e) != 0);
}

TEST(wi_is_optional_where_the_method_needs_none)
{
    static const char *const names[6] = {"N.X", "N.Y", "N.Z", "wo.X", "wo.Y", "wo.Z"};
    const float vals[4][6] = {{0, 0, 1, 0, 0.6f, 0.8f},  /* covered, seen */
                              {0, 0, 0, 0, 0, 0},        /* background */
                              {0, 0, 1, 0, 0, -1},       /* covered, facing away */
                              {0, 0, 2, 0, 0, 3}};       /* covered, unnormalized */
    img_named im = make(6, names, &vals[0][0]);
    gbuf g;
    glint_err e;
    int has_uv = 1, has_wi = 1;
    ASSERT_EQ(gbuf_from_named_ex(&im, "nowi.exr", 1, &g, &has_uv, &has_wi, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "no channel wi.X") != NULL && strstr(e.msg, "srbf") != NULL);
    ASSERT_OK(gbuf_from_named_ex(&im, "nowi.exr", 0, &g, &has_uv, &has_wi, &e));
    ASSERT_EQ(has_wi, 0);
    ASSERT_EQ(has_uv, 0);
    ASSERT(g.mask[0] && !g.mask[1] && g.mask[2] && g.mask[3]);
    ASSERT_NEAR(g.wo[3 * 3 + 2], 1.0, 1e-7);
    for (int i = 0; i < 12; i++)
        ASSERT_EQ(g.wi[i], 0.0f); /* left zero: n.wi = 0 */
    ASSERT_EQ(samples_count_rule(&g, SAMPLES_SEEN), 2);
    ASSERT_EQ(samples_count_rule(&g, SAMPLES_LIT), 0);
    gbuf_free(&g);
    img_named_free(&im);
}

/* gbfit_samples: the method's rule, the painted views only, sizes checked. */
TEST(a_set_of_gbuffers_makes_samples_by_the_methods_rule)
{
    static const char *const names[9] = {"N.X", "N.Y", "N.Z", "wi.X", "wi.Y", "wi.Z",
                                         "wo.X", "wo.Y", "wo.Z"};
    const float vals[4][9] = {{0, 0, 1, 0, 0, 1, 0, 0, 1},   /* lit and seen */
                              {0, 0, 1, 0, 0, -1, 0, 0, 1},  /* seen, not lit */
                              {0, 0, 1, 0, 0, 1, 0, 0, -1},  /* lit, not seen */
                              {0, 0, 0, 0, 0, 0, 0, 0, 0}};  /* background */
    img_named im = make(9, names, &vals[0][0]);
    const method *lit = method_find("hf3"), *seen = method_find("srbf");
    gbuf g[2];
    img p[2];
    unsigned char use[2] = {0, 1};
    samples s;
    float *rgb = NULL;
    glint_err e;
    int uv, wi;
    ASSERT(lit && seen && lit->pattern_rule == SAMPLES_LIT && seen->pattern_rule == SAMPLES_SEEN);
    memset(g, 0, sizeof g);
    memset(p, 0, sizeof p);
    ASSERT_OK(gbuf_from_named_ex(&im, "v1.exr", 1, &g[1], &uv, &wi, &e));
    ASSERT_OK(img_alloc(&p[1], 4, 1, 3, &e));
    for (int i = 0; i < 12; i++)
        p[1].px[i] = 0.25f * (float)(i / 3) + 0.01f * (float)(i % 3);
    ASSERT_OK(gbfit_samples(lit, g, p, use, 2, 0, &s, &rgb, &e));
    ASSERT_EQ(s.n, 1);
    ASSERT_EQ(s.view[0], 1);
    ASSERT_EQ(s.pixel[0], 0);
    ASSERT(!s.used[0] && s.used[1]);
    ASSERT_NEAR(rgb[2], 0.02 / M_PI, 1e-7); /* over the light of intensity 1: pi (scene.h) */
    samples_free(&s);
    free(rgb);
    ASSERT_OK(gbfit_samples(seen, g, p, use, 2, 0, &s, &rgb, &e));
    ASSERT_EQ(s.n, 2); /* pixels 0 and 1: seen, lit or not */
    ASSERT_EQ(s.pixel[1], 1);
    ASSERT_NEAR(rgb[3], 0.25 / M_PI, 1e-7);
    samples_free(&s);
    free(rgb);
    ASSERT(method_find("hf4") != NULL);
    ASSERT_EQ(gbfit_samples(method_find("hf4"), g, p, use, 2, 0, &s, &rgb, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "uv.U uv.V") != NULL && rgb == NULL);
    use[1] = 0;
    ASSERT_EQ(gbfit_samples(lit, g, p, use, 2, 0, &s, &rgb, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "painting") != NULL);
    use[1] = 1;
    img_free(&p[1]);
    ASSERT_OK(img_alloc(&p[1], 2, 2, 3, &e));
    ASSERT_EQ(gbfit_samples(lit, g, p, use, 2, 0, &s, &rgb, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "2x2") != NULL && rgb == NULL);
    img_free(&p[1]);
    gbuf_free(&g[1]);
    img_named_free(&im);
}

TEST_LIST{
    TEST_ENTRY(a_written_gbuffer_reads_back_as_written),
    TEST_ENTRY(a_gbuffer_made_elsewhere_reads),
    TEST_ENTRY(what_cannot_be_read_is_refused_naming_it),
    TEST_ENTRY(wi_is_optional_where_the_method_needs_none),
    TEST_ENTRY(a_set_of_gbuffers_makes_samples_by_the_methods_rule),
};

TEST_MAIN()
