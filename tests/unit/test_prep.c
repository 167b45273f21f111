/* Tests of the pipeline through the cache (core/prep) and of what it is
 * built on: patterns rasterized in bands equal patterns of whole
 * G-buffers, subsets of a pattern equal the patterns of their views, a fit
 * through prep equals the direct path (fit.h), materials render in bands
 * exactly as they shade whole G-buffers, and the held-out measurement on
 * samples equals the error measured on G-buffers. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "brdf.h"
#include "cache.h"
#include "check.h"
#include "fit.h"
#include "hf_int.h"
#include "img.h"
#include "material.h"
#include "method_hf3.h"
#include "paint.h"
#include "prep.h"
#include "raster.h"
#include "samples.h"
#include "scene.h"

static scene SC;
static gbuf *G;
static img P[12];
static char HASH[33];

static int setup(void)
{
    scene_params p;
    brdf b;
    glint_err e;
    if (G)
        return 0;
    scene_params_default(&p);
    p.width = 56;
    p.height = 40; /* not square: rows and columns must not be mixed up */
    if (scene_create(&p, &SC, &e) || raster_scene(&SC, &G, &e) ||
        brdf_parse("ct:rough=0.3,kd=0.5/0.4/0.3,f0=0.2", &b, &e) ||
        paint_views(&b, G, SC.views, SC.nviews, 1.0, P, NULL, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    scene_hash(&SC, HASH);
    return 0;
}

static int same_samples(const samples *a, const samples *b)
{
    if (a->n != b->n || a->nviews != b->nviews || a->width != b->width ||
        a->height != b->height || strcmp(a->hash, b->hash) != 0 ||
        memcmp(a->used, b->used, (size_t)a->nviews) != 0)
        return 0;
    return memcmp(a->view, b->view, (size_t)a->n * sizeof *a->view) == 0 &&
           memcmp(a->pixel, b->pixel, (size_t)a->n * sizeof *a->pixel) == 0 &&
           memcmp(a->nrm, b->nrm, (size_t)a->n * 3 * sizeof *a->nrm) == 0 &&
           memcmp(a->wi, b->wi, (size_t)a->n * 3 * sizeof *a->wi) == 0 &&
           memcmp(a->wo, b->wo, (size_t)a->n * 3 * sizeof *a->wo) == 0 &&
           memcmp(a->pos, b->pos, (size_t)a->n * 3 * sizeof *a->pos) == 0 &&
           memcmp(a->uv, b->uv, (size_t)a->n * 2 * sizeof *a->uv) == 0 &&
           memcmp(a->cos_i, b->cos_i, (size_t)a->n * sizeof *a->cos_i) == 0 &&
           memcmp(a->intensity, b->intensity, (size_t)a->n * sizeof *a->intensity) == 0;
}

TEST(bands_of_rows_are_the_rows_of_the_whole_view)
{
    glint_err e;
    ASSERT_OK(setup());
    for (int v = 0; v < 3; v++)
        for (int band = 1; band <= 17; band += 8) {
            for (int row0 = 0; row0 < SC.height; row0 += band) {
                int n = SC.height - row0 < band ? SC.height - row0 : band;
                size_t off = (size_t)row0 * SC.width, np = (size_t)n * SC.width;
                gbuf b;
                ASSERT_OK(raster_view_rows(&SC.mesh, &SC.views[v], SC.width, SC.height, row0, n,
                                           &b, &e));
                ASSERT(memcmp(b.mask, G[v].mask + off, np) == 0);
                ASSERT(memcmp(b.nrm, G[v].nrm + 3 * off, 3 * np * sizeof(float)) == 0);
                ASSERT(memcmp(b.pos, G[v].pos + 3 * off, 3 * np * sizeof(float)) == 0);
                ASSERT(memcmp(b.uv, G[v].uv + 2 * off, 2 * np * sizeof(float)) == 0);
                ASSERT(memcmp(b.wi, G[v].wi + 3 * off, 3 * np * sizeof(float)) == 0);
                ASSERT(memcmp(b.wo, G[v].wo + 3 * off, 3 * np * sizeof(float)) == 0);
                gbuf_free(&b);
            }
        }
    {
        gbuf b;
        ASSERT_EQ(raster_view_rows(&SC.mesh, &SC.views[0], SC.width, SC.height, 30, 11, &b, &e),
                  GLINT_ERANGE);
    }
}

TEST(patterns_built_in_bands_and_subsets_equal_whole_ones)
{
    unsigned char use[12] = {1, 0, 1, 1, 0, 0, 1, 0, 0, 1, 1, 0};
    samples whole, banded, all, sub;
    glint_err e;

    ASSERT_OK(setup());
    ASSERT_OK(samples_build(G, SC.views, SC.nviews, use, HASH, &whole, &e));
    /* the same views, one band of 7 rows at a time */
    ASSERT_OK(samples_begin(&banded, SC.nviews, SC.width, SC.height, &e));
    for (int v = 0; v < SC.nviews; v++) {
        if (!use[v])
            continue;
        for (int row0 = 0; row0 < SC.height; row0 += 7) {
            int n = SC.height - row0 < 7 ? SC.height - row0 : 7;
            gbuf b;
            ASSERT_OK(raster_view_rows(&SC.mesh, &SC.views[v], SC.width, SC.height, row0, n, &b,
                                       &e));
            ASSERT_OK(samples_add(&banded, v, &b, row0, view_light_scale(&SC.views[v]), &e));
            gbuf_free(&b);
        }
    }
    ASSERT_OK(samples_end(&banded, use, HASH, &e));
    ASSERT(same_samples(&whole, &banded));
    /* a subset of every view's pattern is the pattern of those views */
    ASSERT_OK(samples_build(G, SC.views, SC.nviews, NULL, HASH, &all, &e));
    ASSERT_OK(samples_subset(&all, use, HASH, &sub, &e));
    ASSERT(same_samples(&whole, &sub));
    ASSERT_LT(sub.n, all.n);
    samples_free(&whole);
    samples_free(&banded);
    samples_free(&all);
    samples_free(&sub);
}

/* Each sample carries the surface's texture coordinates at its pixel (the
 * G-buffer's, from the mesh's uvs or its automatic atlas), inside the unit
 * square and spread over it. */
TEST(samples_carry_the_texture_coordinates_of_their_pixels)
{
    samples s;
    glint_err e;
    float lo[2] = {1.0f, 1.0f}, hi[2] = {0.0f, 0.0f};
    ASSERT_OK(setup());
    ASSERT_OK(samples_build(G, SC.views, SC.nviews, NULL, HASH, &s, &e));
    ASSERT(s.has_pos);
    for (int i = 0; i < s.n; i++) {
        const float *g = G[s.view[i]].uv + 2 * (size_t)s.pixel[i];
        for (int k = 0; k < 2; k++) {
            float u = s.uv[2 * (size_t)i + k];
            ASSERT_MSG(u == g[k], "sample %d: uv[%d] %g, the G-buffer's %g", i, k, u, g[k]);
            ASSERT(u >= 0.0f && u <= 1.0f);
            lo[k] = u < lo[k] ? u : lo[k];
            hi[k] = u > hi[k] ? u : hi[k];
        }
    }
    ASSERT_MSG(hi[0] - lo[0] > 0.5f && hi[1] - lo[1] > 0.25f, "uv spans [%g,%g] x [%g,%g]",
               lo[0], hi[0], lo[1], hi[1]);
    samples_free(&s);
}

/* A spatially varying truth: the pattern's weight by hand, and a painting
 * of the scene that is exactly a's painting where the weight is 0, b's
 * where it is 1, and between them on soft edges; specs parsed and
 * rejected with the reason. */
TEST(spatially_varying_truths_follow_the_texture_coordinates)
{
    paint_sv sv;
    img pa[12], pb[12], ps[12];
    long na = 0, nb = 0, nmix = 0;
    glint_err e;
    ASSERT_OK(setup());
    ASSERT_OK(paint_sv_parse("stripes:freq=4,duty=0.25|lambert:kd=0.6/0.1/0.1|"
                             "ct:kd=0.1,f0=0.9/0.7/0.3,rough=0.2", &sv, &e));
    ASSERT(sv.pattern == PAINT_SV_STRIPES && sv.freq == 4.0 && sv.duty == 0.25 && sv.soft == 0);
    ASSERT(paint_sv_weight(&sv, 0.03, 0.9) == 1.0 && paint_sv_weight(&sv, 0.1, 0.1) == 0.0);
    ASSERT(paint_sv_weight(&sv, 0.28, 0.5) == 1.0 && paint_sv_weight(&sv, 0.49, 0.5) == 0.0);
    sv.soft = 0.1;
    ASSERT_NEAR(paint_sv_weight(&sv, 0.0625, 0.0), 0.5, 1e-12); /* on the edge at duty */
    ASSERT_NEAR(paint_sv_weight(&sv, 0.0625 + 0.0125, 0.0), 0.0, 1e-12);
    sv.pattern = PAINT_SV_CHECKER;
    sv.soft = 0.0;
    ASSERT(paint_sv_weight(&sv, 0.05, 0.05) == 0.0 && paint_sv_weight(&sv, 0.05, 0.2) == 1.0 &&
           paint_sv_weight(&sv, 0.2, 0.05) == 1.0 && paint_sv_weight(&sv, 0.2, 0.2) == 0.0);
    sv.pattern = PAINT_SV_STRIPES;
    sv.soft = 0.05;
    memset(pa, 0, sizeof pa);
    memset(pb, 0, sizeof pb);
    memset(ps, 0, sizeof ps);
    ASSERT_OK(paint_views(&sv.a, G, SC.views, SC.nviews, 1.0, pa, NULL, &e));
    ASSERT_OK(paint_views(&sv.b, G, SC.views, SC.nviews, 1.0, pb, NULL, &e));
    ASSERT_OK(paint_views_sv(&sv, G, SC.views, SC.nviews, 1.0, ps, NULL, &e));
    for (int v = 0; v < SC.nviews; v++)
        for (int p = 0; p < SC.width * SC.height; p++) {
            double w = paint_sv_weight(&sv, G[v].uv[2 * p], G[v].uv[2 * p + 1]);
            for (int c = 0; c < 3; c++) {
                float a = pa[v].px[3 * p + c], b = pb[v].px[3 * p + c], x = ps[v].px[3 * p + c];
                if (w == 0.0)
                    ASSERT(x == a);
                else if (w == 1.0)
                    ASSERT(x == b);
                else
                    ASSERT(x >= fminf(a, b) * (1 - 1e-6f) && x <= fmaxf(a, b) * (1 + 1e-6f));
            }
            if (G[v].mask[p] && pa[v].px[3 * p] > 0.0f) {
                na += w == 0.0;
                nb += w == 1.0;
                nmix += w > 0.0 && w < 1.0;
            }
        }
    ASSERT_MSG(na > 100 && nb > 100 && nmix > 0, "pixels of a %ld, of b %ld, blended %ld", na,
               nb, nmix);
    for (int v = 0; v < SC.nviews; v++) {
        img_free(&pa[v]);
        img_free(&pb[v]);
        img_free(&ps[v]);
    }
    {
        static const char *bad[] = {"stripes|lambert", "waves|lambert|ct", "stripes:freq=0|lambert|ct",
                                    "stripes:duty=2|lambert|ct", "stripes:hue=1|lambert|ct",
                                    "stripes:freq=x|lambert|ct", "checker|lambert|nope",
                                    "stripes|lambert|ct|ct"};
        for (size_t k = 0; k < sizeof bad / sizeof *bad; k++)
            ASSERT_MSG(paint_sv_parse(bad[k], &sv, &e) != 0, "\"%s\" accepted", bad[k]);
    }
}

static int borrowed(void *cls, const char *id, const scene **out, glint_err *err)
{
    (void)id;
    (void)err;
    *out = cls;
    return 0;
}

TEST(a_fit_through_the_cache_equals_the_direct_path)
{
    prep_scene_source src = {borrowed, NULL, &SC};
    unsigned char use[12];
    fit_params fp;
    fit_prep direct;
    material a, b;
    cache *c;
    cache_entry *se;
    prep *p = NULL, *q = NULL;
    glint_err e;

    ASSERT_OK(setup());
    memset(use, 1, sizeof use);
    use[4] = 0;
    fit_params_default(&fp);
    fp.res = 24;
    ASSERT_OK(fit_prepare(&direct, &SC, G, use, &fp, NULL, &e));
    ASSERT_OK(fit_run(&direct, P, NULL, &a, &e));
    ASSERT_OK(cache_open(NULL, 1 << 30, &c, &e));
    ASSERT_OK(prep_scene_acquire(c, "s", &src, &se, &e));
    {
        prep_request rq = {&method_hf3, &fp, se, use, NULL};
        ASSERT_EQ(prep_try(c, &rq, &q, &e), GLINT_ENOTFOUND);
        ASSERT_OK(prep_acquire(c, &rq, NULL, NULL, &p, &e));
        ASSERT_OK(prep_fit(p, P, NULL, &b, &e));
        ASSERT_OK(prep_try(c, &rq, &q, &e)); /* now in memory */
        ASSERT(prep_was_hit(q) && !prep_was_hit(p));
        prep_release(c, q);
    }
    ASSERT_EQ(prep_samples(p)->n, direct.s.n);
    ASSERT(strcmp(prep_samples(p)->hash, direct.s.hash) == 0);
    for (int i = 0; i < 9 * 24; i++)
        ASSERT_NEAR(hf3_factors(&b)->logf[i], hf3_factors(&a)->logf[i], 1e-12);
    {
        json_t *cr = json_object_get(json_object_get(b.info, "precomputation"), "cache");
        ASSERT(strcmp(json_string_value(json_object_get(cr, "memory")), "built") == 0);
        ASSERT(json_object_get(json_object_get(cr, "levels"), "decomposition") != NULL);
    }
    material_free(&a);
    material_free(&b);
    fit_prep_free(&direct);
    prep_release(c, p);
    cache_release(c, se);
    cache_close(c);
}

/* Copies of the paintings (OUT: q[12]). */
static int copy_paintings(img *q)
{
    glint_err e;
    for (int v = 0; v < 12; v++) {
        size_t n = (size_t)P[v].width * P[v].height * P[v].channels;
        if (img_alloc(&q[v], P[v].width, P[v].height, P[v].channels, &e))
            return -1;
        memcpy(q[v].px, P[v].px, n * sizeof *q[v].px);
    }
    return 0;
}

/* A fit through a memo, against a fit of the same paintings from nothing:
 * 0 when they have the same log-factors (bits) and error figures, and the
 * fit's typed report says what its info says.  OUT: *read, the views it
 * read (values_views_read), and when asked the chunks of its pass the memo
 * gave (stream_chunks_reused) and their count. */
static int memo_fit_counts(const prep *p, const img *q, const uint64_t *tags, method_memo *mm,
                           int *read, int *reused, int *chunks)
{
    json_t *pre;
    material a, b;
    fit_report rep;
    glint_err e;
    int same, res, told;
    if (prep_fit_reusing(p, q, NULL, tags, mm, &a, &rep, &e))
        return -1;
    if (prep_fit(p, q, NULL, &b, &e)) {
        fit_report_free(&rep);
        material_free(&a);
        return -1;
    }
    pre = json_object_get(a.info, "precomputation");
    /* the preparation built every level (no disk layer), pattern included */
    told = rep.errors_ok && rep.levels == 1 + method_hf3.nlevels &&
           rep.levels_built == rep.levels && rep.levels_loaded == 0 && !rep.from_disk &&
           strcmp(rep.memory, "built") == 0 && rep.chosen[0] == '\0' &&
           rep.rms_painted == json_number_value(json_object_get(
                                  json_object_get(a.info, "errors"), "rms_painted")) &&
           rep.stream_chunks == json_integer_value(json_object_get(pre, "stream_chunks")) &&
           rep.stream_chunks_reused ==
               json_integer_value(json_object_get(pre, "stream_chunks_reused")) &&
           json_equal(json_object_get(rep.members, "precomputation"), pre) &&
           json_equal((json_t *)rep.params, json_object_get(a.info, "params")) &&
           json_object_size(rep.members) == 4;
    fit_report_free(&rep);
    if (!told) {
        material_free(&a);
        material_free(&b);
        return 2;
    }
    res = hf3_factors(&a)->res;
    same = res == hf3_factors(&b)->res &&
           memcmp(hf3_factors(&a)->logf, hf3_factors(&b)->logf,
                  (size_t)9 * res * sizeof(double)) == 0 &&
           json_equal(json_object_get(a.info, "errors"), json_object_get(b.info, "errors"));
    *read = (int)json_integer_value(json_object_get(pre, "values_views_read"));
    if (reused)
        *reused = (int)json_integer_value(json_object_get(pre, "stream_chunks_reused"));
    if (chunks)
        *chunks = (int)json_integer_value(json_object_get(pre, "stream_chunks"));
    material_free(&a);
    material_free(&b);
    return same ? 0 : 1;
}

static int memo_fit_same(const prep *p, const img *q, const uint64_t *tags, method_memo *mm,
                         int *read)
{
    return memo_fit_counts(p, q, tags, mm, read, NULL, NULL);
}

/* The memo tests' session: the scene's 12 views prepared for hf3 at res
 * 16 in a cache of their own, the paintings copied into q, tags 1..12,
 * an empty memo. */
typedef struct memo_case {
    prep_scene_source src;
    unsigned char use[12];
    fit_params fp;
    cache *c;
    cache_entry *se;
    prep *p;
    const samples *s;
    img q[12];
    uint64_t tags[12];
    method_memo mm;
} memo_case;

static int memo_case_open(memo_case *mc)
{
    glint_err e;
    memset(mc, 0, sizeof *mc);
    mc->src = (prep_scene_source){borrowed, NULL, &SC};
    memset(mc->use, 1, sizeof mc->use);
    fit_params_default(&mc->fp);
    mc->fp.res = 16;
    for (int v = 0; v < 12; v++)
        mc->tags[v] = 1 + (uint64_t)v;
    if (setup() || cache_open(NULL, 1 << 30, &mc->c, &e) ||
        prep_scene_acquire(mc->c, "s", &mc->src, &mc->se, &e))
        return -1;
    {
        prep_request rq = {&method_hf3, &mc->fp, mc->se, mc->use, NULL};
        if (prep_acquire(mc->c, &rq, NULL, NULL, &mc->p, &e))
            return -1;
    }
    mc->s = prep_samples(mc->p);
    return copy_paintings(mc->q);
}

static void memo_case_close(memo_case *mc)
{
    method_memo_clear(&mc->mm);
    for (int v = 0; v < 12; v++)
        img_free(&mc->q[v]);
    if (mc->p)
        prep_release(mc->c, mc->p);
    if (mc->se)
        cache_release(mc->c, mc->se);
    if (mc->c)
        cache_close(mc->c);
}

TEST(a_memo_reads_again_only_the_views_whose_tags_changed)
{
    memo_case mc;
    method_memo *mm = &mc.mm;
    const prep *p;
    const samples *s;
    uint64_t *tags = mc.tags;
    img *q = mc.q;
    long i5 = -1;
    int read = -1;
    glint_err e;

    ASSERT_OK(memo_case_open(&mc));
    p = mc.p;
    s = mc.s;
    /* the first fit reads every view; the second none */
    ASSERT_OK(memo_fit_same(p, q, tags, mm, &read));
    ASSERT_EQ(read, 12);
    ASSERT_OK(memo_fit_same(p, q, tags, mm, &read));
    ASSERT_EQ(read, 0);
    ASSERT(mm->values && mm->values_n == s->n);
    /* view 3 repainted: read again alone */
    for (long k = 0; k < (long)q[3].width * q[3].height * q[3].channels; k++)
        q[3].px[k] *= 0.7f;
    tags[3] = 100;
    ASSERT_OK(memo_fit_same(p, q, tags, mm, &read));
    ASSERT_EQ(read, 1);
    /* view 5 repainted with a non-finite value in its last sample fails
     * the fit after most of its values were read over the memo's; back to
     * its first painting and tag, it is read again, not taken as kept */
    for (long i = 0; i < s->n; i++)
        if (s->view[i] == 5)
            i5 = i;
    ASSERT(i5 >= 0);
    {
        material m;
        size_t np = (size_t)q[5].width * q[5].height * q[5].channels;
        float *keep = malloc(np * sizeof *keep);
        ASSERT(keep);
        memcpy(keep, q[5].px, np * sizeof *keep);
        for (size_t k = 0; k < np; k++)
            q[5].px[k] *= 0.5f;
        q[5].px[(size_t)s->pixel[i5] * q[5].channels] = NAN;
        tags[5] = 200;
        ASSERT_EQ(prep_fit_reusing(p, q, NULL, tags, mm, &m, NULL, &e), GLINT_ENONFINITE);
        memcpy(q[5].px, keep, np * sizeof *keep);
        free(keep);
        tags[5] = 6;
    }
    ASSERT_OK(memo_fit_same(p, q, tags, mm, &read));
    ASSERT_EQ(read, 1);
    ASSERT_OK(memo_fit_same(p, q, tags, mm, &read));
    ASSERT_EQ(read, 0);
    /* another method's data in the memo is dropped, the values kept */
    method_memo_drop_data(mm);
    ASSERT(mm->values && !mm->data);
    ASSERT_OK(memo_fit_same(p, q, tags, mm, &read));
    ASSERT_EQ(read, 0);
    method_memo_clear(mm);
    ASSERT(!mm->values && !mm->values_ok && !mm->values_key);
    memo_case_close(&mc);
}

TEST(a_memo_sums_again_only_the_chunks_whose_values_changed)
{
    /* a view repainted with what it held, then dabs of one pixel on two
     * views: the values read again are compared with the kept ones, and
     * the pass sums again only the chunks whose values changed */
    memo_case mc;
    method_memo *mm = &mc.mm;
    const prep *p;
    const samples *s;
    uint64_t *tags = mc.tags;
    img *q = mc.q;
    long first1 = -1, last10 = -1;
    int read = -1, reused = -1, chunks = -1, chunk, nchunks;

    ASSERT_OK(memo_case_open(&mc));
    p = mc.p;
    s = mc.s;
    for (long i = 0; i < s->n; i++) {
        if (s->view[i] == 1 && first1 < 0)
            first1 = i;
        if (s->view[i] == 10)
            last10 = i;
    }
    hf_chunking(s->n, &chunk, &nchunks);
    /* the dabs lie in different chunks of the pass, and the first is not
     * the last sample its read reaches */
    ASSERT(nchunks > 1 && first1 >= 0 && last10 >= 0);
    ASSERT(first1 / chunk < last10 / chunk);
    ASSERT_OK(memo_fit_counts(p, q, tags, mm, &read, &reused, &chunks));
    ASSERT(read == 12 && reused == 0 && chunks == nchunks);
    /* view 7 under a new tag, its painting as it was: read, nothing summed */
    tags[7] = 70;
    ASSERT_OK(memo_fit_counts(p, q, tags, mm, &read, &reused, &chunks));
    ASSERT(read == 1 && reused == chunks);
    /* a dab on the pixel of view 1's first sample and one on view 10's
     * last: their two chunks alone */
    for (int ch = 0; ch < q[1].channels; ch++)
        q[1].px[(size_t)s->pixel[first1] * q[1].channels + ch] += 0.25f;
    for (int ch = 0; ch < q[10].channels; ch++)
        q[10].px[(size_t)s->pixel[last10] * q[10].channels + ch] += 0.25f;
    tags[1] = 50;
    tags[10] = 71;
    ASSERT_OK(memo_fit_counts(p, q, tags, mm, &read, &reused, &chunks));
    ASSERT(read == 2 && chunks - reused == 2);
    /* and back: summed again, not the dabs' sums kept */
    for (int v = 1; v <= 10; v += 9)
        memcpy(q[v].px, P[v].px, (size_t)P[v].width * P[v].height * P[v].channels * sizeof *q[v].px);
    tags[1] = 51;
    tags[10] = 72;
    ASSERT_OK(memo_fit_counts(p, q, tags, mm, &read, &reused, &chunks));
    ASSERT(read == 2 && chunks - reused == 2);
    memo_case_close(&mc);
}

TEST(rendering_in_bands_equals_shading_the_whole_view)
{
    fit_params fp;
    fit_prep direct;
    material m;
    img a, b;
    glint_err e;

    ASSERT_OK(setup());
    fit_params_default(&fp);
    fp.res = 16;
    ASSERT_OK(fit_prepare(&direct, &SC, G, NULL, &fp, NULL, &e));
    ASSERT_OK(fit_run(&direct, P, NULL, &m, &e));
    ASSERT_OK(material_shade(&m, &G[3], SC.views[3].light_intensity, 0.0f, &a, &e));
    ASSERT_OK(material_render(&m, &SC.mesh, &SC.views[3], SC.width, SC.height, &b, NULL, &e));
    ASSERT(memcmp(a.px, b.px, (size_t)SC.width * SC.height * 3 * sizeof(float)) == 0);
    img_free(&a);
    img_free(&b);
    material_free(&m);
    fit_prep_free(&direct);
}

TEST(held_out_error_on_samples_equals_the_error_on_the_view)
{
    fit_params fp;
    fit_prep all, fold;
    material m;
    json_t *r = NULL, *pv;
    unsigned char use[12];
    glint_err e;
    double rms, mx;
    long cnt;

    ASSERT_OK(setup());
    fit_params_default(&fp);
    fp.res = 16;
    memset(use, 0, sizeof use);
    use[0] = use[5] = use[9] = 1;
    ASSERT_OK(fit_prepare(&all, &SC, G, use, &fp, NULL, &e));
    ASSERT_OK(prep_holdout(&method_hf3, &fp, &all.s, P, NULL, NULL, NULL, NULL, &r, &e));
    ASSERT_EQ(json_integer_value(json_object_get(r, "views")), 3);
    pv = json_array_get(json_object_get(r, "per_view"), 1); /* view 5 held out */
    ASSERT_EQ(json_integer_value(json_object_get(pv, "view")), 5);
    /* the same fold by the direct path, its error measured on the G-buffer */
    use[5] = 0;
    ASSERT_OK(fit_prepare(&fold, &SC, G, use, &fp, NULL, &e));
    ASSERT_OK(fit_run(&fold, P, NULL, &m, &e));
    ASSERT_OK(material_error_views(&m, &G[5], &SC.views[5], 1, &P[5], &rms, &mx, &cnt, &e));
    ASSERT_NEAR(json_real_value(json_object_get(pv, "rms")), rms, 1e-9 * (1 + rms));
    ASSERT_EQ(json_integer_value(json_object_get(pv, "pixels")), cnt);
    json_decref(r);
    material_free(&m);
    fit_prep_free(&all);
    fit_prep_free(&fold);
    /* one painted view cannot be held out */
    {
        fit_prep one;
        memset(use, 0, sizeof use);
        use[2] = 1;
        ASSERT_OK(fit_prepare(&one, &SC, G, use, &fp, NULL, &e));
        ASSERT_EQ(prep_holdout(&method_hf3, &fp, &one.s, P, NULL, NULL, NULL, NULL, &r, &e),
                  GLINT_EINVAL);
        fit_prep_free(&one);
    }
}

TEST(sample_counts_equal_the_pattern)
{
    long per[12], total;
    samples s;
    glint_err e;
    ASSERT_OK(setup());
    ASSERT_OK(prep_sample_counts(&SC, per, &total, &e));
    ASSERT_OK(samples_build(G, SC.views, SC.nviews, NULL, HASH, &s, &e));
    ASSERT_EQ(total, s.n);
    for (int v = 0; v < 12; v++) {
        long n = 0;
        for (int i = 0; i < s.n; i++)
            n += s.view[i] == v;
        ASSERT_EQ(per[v], n);
    }
    samples_free(&s);
}

TEST_LIST{
    TEST_ENTRY(bands_of_rows_are_the_rows_of_the_whole_view),
    TEST_ENTRY(patterns_built_in_bands_and_subsets_equal_whole_ones),
    TEST_ENTRY(samples_carry_the_texture_coordinates_of_their_pixels),
    TEST_ENTRY(spatially_varying_truths_follow_the_texture_coordinates),
    TEST_ENTRY(a_fit_through_the_cache_equals_the_direct_path),
    TEST_ENTRY(a_memo_reads_again_only_the_views_whose_tags_changed),
    TEST_ENTRY(a_memo_sums_again_only_the_chunks_whose_values_changed),
    TEST_ENTRY(rendering_in_bands_equals_shading_the_whole_view),
    TEST_ENTRY(held_out_error_on_samples_equals_the_error_on_the_view),
    TEST_ENTRY(sample_counts_equal_the_pattern),
};

TEST_MAIN()
