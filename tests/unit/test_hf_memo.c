/* test_hf_memo.c: a three-factor fit through a memo of its pass's chunk
 * sums (hf_fit_with): which chunks it takes from the memo, by the views'
 * tags and by where the values changed (samples_change), and that every
 * fit through it is the same bits as a fit from nothing. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fit_case.h"
#include "hf.h"
#include "hf_int.h"
#include "samples.h"

/* The samples' views with the first sample's moved to view 11: out of
 * order, as samples_build never makes them (malloc'ed; NULL out of memory). */
static int *views_out_of_order(const fit_case *fc)
{
    int *v = malloc((size_t)fc->s.n * sizeof *v);
    if (v) {
        memcpy(v, fc->s.view, (size_t)fc->s.n * sizeof *v);
        v[0] = 11;
    }
    return v;
}

/* One fit through a memo against one without, the same bits: OUT: the
 * chunks the memo gave. */
static int fit_pair(const fit_case *fc, const hf_map *map, const float *rgb,
                    const hf_fit_reuse *r, int *reused, int *chunks)
{
    hf_factors a, b;
    hf_fit_stats sa, sb;
    int same;
    if (hf_fit(&fc->d, &fc->op, map, HF_MODEL_RADIANCE, rgb, &a, &sa, NULL) ||
        hf_fit_with(&fc->d, &fc->op, map, HF_MODEL_RADIANCE, rgb, r, &b, &sb, NULL))
        return -1;
    same = memcmp(a.logf, b.logf, (size_t)9 * fc->d.res * sizeof *a.logf) == 0 &&
           memcmp(sa.clamped, sb.clamped, sizeof sa.clamped) == 0 && sa.rms == sb.rms &&
           sa.stream_chunks_reused == 0;
    *reused = sb.stream_chunks_reused;
    *chunks = sb.stream_chunks;
    hf_factors_free(&a);
    hf_factors_free(&b);
    return same ? 0 : 1;
}

TEST(a_memo_gives_unchanged_views_sums_and_the_same_bits)
{
    fit_case fc;
    uint64_t tags[12];
    hf_memo *memo = hf_memo_new();
    hf_fit_reuse r;
    hf_map eps2;
    int reused, chunks, *shuffled;
    long first3 = -1, n3 = 0;

    ASSERT(memo);
    ASSERT_OK(fit_case_make(&fc, 96, 16));
    for (int v = 0; v < 12; v++)
        tags[v] = 100 + v;
    r = (hf_fit_reuse){memo, "sphere96/res16", fc.s.view, tags, 12, NULL};
    /* the first fit fills the memo; the second takes every chunk from it */
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(reused, 0);
    ASSERT(chunks > 4);
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(reused, chunks);
    /* view 3 repainted: its chunks are summed again, the others not */
    for (long i = 0; i < fc.s.n; i++)
        if (fc.s.view[i] == 3) {
            if (first3 < 0)
                first3 = i;
            n3++;
            for (int c = 0; c < 3; c++)
                fc.rgb[3 * i + c] *= 0.7f;
        }
    ASSERT(n3 > 0);
    tags[3] = 7;
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    printf("  view 3 repainted (%ld of %d samples): %d of %d chunks from the memo\n", n3,
           fc.s.n, reused, chunks);
    ASSERT(reused > 0 && reused < chunks);
    ASSERT(chunks - reused <= (int)(n3 / (fc.s.n / chunks)) + 2);
    /* another mapping: nothing reused, the memo starts again */
    eps2 = fc.map;
    eps2.eps *= 2.0;
    ASSERT_OK(fit_pair(&fc, &eps2, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(reused, 0);
    /* another key: the same */
    r.key = "sphere96/res16/other";
    ASSERT_OK(fit_pair(&fc, &eps2, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(reused, 0);
    /* views out of order (not as samples_build makes them): nothing reused */
    ASSERT((shuffled = views_out_of_order(&fc)));
    r.view = shuffled;
    r.key = "shuffled";
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(reused, 0);
    free(shuffled);
    /* a non-finite value: the fit fails, and its chunk is not kept */
    r.view = fc.s.view;
    r.key = "nan";
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    {
        hf_factors f;
        float keep = fc.rgb[3 * first3];
        fc.rgb[3 * first3] = NAN;
        tags[3] = 9;
        ASSERT(hf_fit_with(&fc.d, &fc.op, &fc.map, HF_MODEL_RADIANCE, fc.rgb, &r, &f, NULL,
                           NULL) == GLINT_ENONFINITE);
        /* the same painting again: found again, not taken from the memo */
        ASSERT(hf_fit_with(&fc.d, &fc.op, &fc.map, HF_MODEL_RADIANCE, fc.rgb, &r, &f, NULL,
                           NULL) == GLINT_ENONFINITE);
        fc.rgb[3 * first3] = keep;
        tags[3] = 8; /* the painting as it was, under a new tag */
        ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
        ASSERT(reused < chunks);
    }
    hf_memo_free(memo);
    hf_memo_free(NULL);
    fit_case_free(&fc);
}

/* How many of the pass's chunks (hf_chunking) hold a sample of spans
 * k0..k1, or (k0 < 0) of view v. */
static int chunks_over(const fit_case *fc, long k0, long k1, int v)
{
    int chunk, nchunks, count = 0;
    hf_chunking(fc->s.n, &chunk, &nchunks);
    for (int c = 0; c < nchunks; c++) {
        long i0 = (long)c * chunk, i1 = i0 + chunk < fc->s.n ? i0 + chunk : fc->s.n;
        int hit = 0;
        for (long i = i0; i < i1 && !hit; i++)
            hit = k0 >= 0 ? i / SAMPLES_SPAN >= k0 && i / SAMPLES_SPAN <= k1
                          : fc->s.view[i] == v;
        count += hit;
    }
    return count;
}

TEST(a_memo_sums_again_only_the_chunks_a_stroke_touched)
{
    fit_case fc;
    uint64_t tags[12], *gen;
    hf_memo *memo = hf_memo_new();
    samples_change ch;
    hf_fit_reuse r;
    long nspans, first3 = -1, last3 = -1, i0, i1, k0, k1;
    int reused, chunks, over, by_tags3, by_tags5;
    float *was;

    ASSERT(memo);
    ASSERT_OK(fit_case_make(&fc, 128, 16));
    nspans = (fc.s.n + SAMPLES_SPAN - 1) / SAMPLES_SPAN;
    gen = calloc((size_t)nspans, sizeof *gen);
    ASSERT(gen);
    for (int v = 0; v < 12; v++)
        tags[v] = 1 + (uint64_t)v;
    ch = (samples_change){samples_change_id(), 1, gen};
    r = (hf_fit_reuse){memo, "sphere128/res16", fc.s.view, tags, 12, &ch};
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(reused, 0);
    for (long i = 0; i < fc.s.n; i++)
        if (fc.s.view[i] == 3) {
            if (first3 < 0)
                first3 = i;
            last3 = i;
        }
    /* a stroke: 300 samples in the middle of view 3 changed, in one or
     * two spans; view 3's tag is new, and so is the read */
    i0 = (first3 + last3) / 2;
    i1 = i0 + 300;
    k0 = i0 / SAMPLES_SPAN;
    k1 = (i1 - 1) / SAMPLES_SPAN;
    over = chunks_over(&fc, k0, k1, 0);
    by_tags3 = chunks_over(&fc, -1, -1, 3);
    by_tags5 = chunks_over(&fc, -1, -1, 5);
    ASSERT(over >= 1 && over < by_tags3); /* else the case shows nothing */
    was = malloc((size_t)3 * (i1 - i0) * sizeof *was);
    ASSERT(was);
    memcpy(was, fc.rgb + 3 * i0, (size_t)3 * (i1 - i0) * sizeof *was);
    for (long i = 3 * i0; i < 3 * i1; i++)
        fc.rgb[i] *= 0.5f;
    tags[3] = 50;
    ch.epoch = 2;
    for (long k = k0; k <= k1; k++)
        gen[k] = 2;
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    printf("  a stroke over spans %ld..%ld of view 3: %d of %d chunks summed again (its "
           "tag alone: %d)\n",
           k0, k1, chunks - reused, chunks, by_tags3);
    ASSERT_EQ(chunks - reused, over);
    /* back as it was (a new tag and read): those chunks summed again, not
     * the stroke's sums kept */
    memcpy(fc.rgb + 3 * i0, was, (size_t)3 * (i1 - i0) * sizeof *was);
    free(was);
    tags[3] = 51;
    ch.epoch = 3;
    for (long k = k0; k <= k1; k++)
        gen[k] = 3;
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(chunks - reused, over);
    /* a new tag whose painting changed no value: every chunk kept */
    tags[3] = 52;
    ch.epoch = 4;
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(reused, chunks);
    /* a fit without the history goes by tags, and the memo forgets it:
     * the next fit with it goes by tags too, the one after by spans */
    r.change = NULL;
    tags[3] = 53;
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(chunks - reused, by_tags3);
    r.change = &ch;
    ch.epoch = 5;
    tags[5] = 60;
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(chunks - reused, by_tags5);
    ch.epoch = 6;
    tags[5] = 61;
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(reused, chunks);
    /* another history (values read anew into another buffer): by tags */
    ch.id = samples_change_id();
    ch.epoch = 1;
    memset(gen, 0, (size_t)nspans * sizeof *gen);
    tags[5] = 62;
    ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
    ASSERT_EQ(chunks - reused, by_tags5);
    /* views out of order: tags reuse nothing, spans still do */
    {
        int *shuffled = views_out_of_order(&fc);
        ASSERT(shuffled);
        r.view = shuffled;
        r.key = "shuffled";
        ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
        ASSERT_EQ(reused, 0);
        ch.epoch = 2;
        gen[k0] = 2;
        ASSERT_OK(fit_pair(&fc, &fc.map, fc.rgb, &r, &reused, &chunks));
        ASSERT_EQ(chunks - reused, chunks_over(&fc, k0, k0, 0));
        free(shuffled);
    }
    free(gen);
    hf_memo_free(memo);
    fit_case_free(&fc);
}

TEST_LIST {
    TEST_ENTRY(a_memo_gives_unchanged_views_sums_and_the_same_bits),
    TEST_ENTRY(a_memo_sums_again_only_the_chunks_a_stroke_touched),
};

TEST_MAIN()
