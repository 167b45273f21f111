/* Tests of the samples' values read from the paintings (samples_gather,
 * samples_gather_views in core/pipeline/samples.h) against one sample at a time,
 * written here as the contract states it: value = (float)(p * (1.0 /
 * intensity)), p the pixel's channel (its grey for one channel).  Samples
 * in runs of views and shuffled, and in runs of consecutive pixels (the
 * raster order that takes the gather's path for runs), intensities per
 * view and per sample,
 * paintings of 1, 3 and 4 channels holding subnormals, -0 and values that
 * overflow a float: the same bits.  Views left out are not written; the
 * spans flagged as changed are those whose bits changed; the first
 * non-finite pixel is the one named. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "img.h"
#include "samples.h"

#define W 61
#define H 47
#define NV 5

static uint64_t RNG = 0x9e3779b97f4a7c15ull;

static uint32_t rnd(void)
{
    RNG ^= RNG << 13;
    RNG ^= RNG >> 7;
    RNG ^= RNG << 17;
    return (uint32_t)(RNG >> 11);
}

/* A float of many kinds: ordinary, subnormal, -0, huge. */
static float rnd_value(void)
{
    uint32_t k = rnd() % 16, bits;
    float f;
    switch (k) {
    case 0:
        bits = rnd() & 0x807fffffu; /* subnormal or zero, either sign */
        memcpy(&f, &bits, sizeof f);
        return f;
    case 1:
        return -0.0f;
    case 2:
        return 3.0e38f * ((float)(rnd() % 1000) / 999.0f);
    default:
        return (float)(rnd() % 100000) / 25000.0f - 0.5f;
    }
}

typedef struct fixture {
    samples s;
    img im[NV];
} fixture;

/* The layouts of the samples: views shuffled; in runs of one view, the
 * pixels at random; in runs of one view, the pixels in runs of consecutive
 * pixels of random lengths (as a pattern's raster order gives them). */
enum { SHUFFLED, SORTED, RASTER, LAYOUTS };

/* n samples over NV views (view v of channels chans[v]) laid out as
 * `layout` says; intensity per view, or per sample when per_sample (in
 * RASTER, changing every few dozen samples on average, so that runs of
 * consecutive pixels break there too). */
static void make(fixture *f, int n, int layout, int per_sample)
{
    int sorted = layout != SHUFFLED, at = 0;
    double cur = 1.0;
    static const int chans[NV] = {3, 1, 4, 3, 3};
    static const double inten[NV] = {1.0, 0.37, 3.3, 1e-30, 7.0};
    memset(f, 0, sizeof *f);
    f->s.n = n;
    f->s.nviews = NV;
    f->s.width = W;
    f->s.height = H;
    f->s.used = malloc(NV);
    f->s.view = malloc((size_t)n * sizeof(int));
    f->s.pixel = malloc((size_t)n * sizeof(int));
    f->s.intensity = malloc((size_t)n * sizeof(double));
    memset(f->s.used, 1, NV);
    for (int i = 0; i < n; i++) {
        int v = sorted ? (int)((long)i * NV / n) : (int)(rnd() % NV);
        f->s.view[i] = v;
        if (layout == RASTER) { /* the next pixel, or a jump (a new run) */
            at = rnd() % 23 == 0 || at + 1 >= W * H ? (int)(rnd() % (W * H)) : at + 1;
            f->s.pixel[i] = at;
            if (rnd() % 37 == 0)
                cur = 0.01 + (double)(rnd() % 1000) / 77.0;
            f->s.intensity[i] = per_sample ? cur : inten[v];
        } else {
            f->s.pixel[i] = (int)(rnd() % (W * H));
            f->s.intensity[i] = per_sample ? 0.01 + (double)(rnd() % 1000) / 77.0 : inten[v];
        }
    }
    for (int v = 0; v < NV; v++) {
        glint_err e;
        if (img_alloc(&f->im[v], W, H, chans[v], &e) == 0)
            for (size_t p = 0; p < (size_t)W * H * chans[v]; p++)
                f->im[v].px[p] = rnd_value();
    }
}

static void drop(fixture *f)
{
    free(f->s.used);
    free(f->s.view);
    free(f->s.pixel);
    free(f->s.intensity);
    for (int v = 0; v < NV; v++)
        img_free(&f->im[v]);
}

/* One sample at a time, as the header states it; views with which[v] == 0
 * are not written. */
static void reference(const fixture *f, const unsigned char *which, float *rgb)
{
    for (int i = 0; i < f->s.n; i++) {
        const img *im = &f->im[f->s.view[i]];
        const float *px = im->px + (size_t)f->s.pixel[i] * im->channels;
        if (which && !which[f->s.view[i]])
            continue;
        for (int ch = 0; ch < 3; ch++)
            rgb[3 * i + ch] = (float)((im->channels == 1 ? px[0] : px[ch]) *
                                      (1.0 / f->s.intensity[i]));
    }
}

TEST(the_values_are_one_sample_at_a_time_bit_for_bit)
{
    /* 3 sizes: within one chunk; several chunks (run on the pool) */
    static const int sizes[] = {1, 999, 70001};
    for (int si = 0; si < 3; si++)
        for (int layout = 0; layout < LAYOUTS; layout++)
            for (int per = 0; per < 2; per++) {
                fixture f;
                glint_err e;
                int n = sizes[si];
                float *got, *want;
                make(&f, n, layout, per);
                got = malloc((size_t)3 * n * sizeof *got);
                want = malloc((size_t)3 * n * sizeof *want);
                ASSERT_OK(samples_gather(&f.s, f.im, got, &e));
                reference(&f, NULL, want);
                ASSERT_MSG(memcmp(got, want, (size_t)3 * n * sizeof *got) == 0,
                           "n %d layout %d per-sample %d: values differ", n, layout, per);
                free(got);
                free(want);
                drop(&f);
            }
}

TEST(views_left_out_are_not_written_and_changed_spans_are_flagged)
{
    for (int layout = 0; layout < LAYOUTS; layout++) {
        fixture f;
        glint_err e;
        int n = 50000;
        size_t nspans = ((size_t)n + SAMPLES_SPAN - 1) / SAMPLES_SPAN;
        unsigned char which[NV] = {1, 0, 1, 1, 0}, *changed = calloc(nspans, 1),
                      *want_changed = calloc(nspans, 1);
        float *got = malloc((size_t)3 * n * sizeof *got), *want = malloc((size_t)3 * n * sizeof *want);
        int nchanged = 0;
        make(&f, n, layout, 0);
        reference(&f, NULL, got);
        memcpy(want, got, (size_t)3 * n * sizeof *got);
        /* change a few pixels of views read and of a view left out */
        for (int k = 0; k < 6; k++) {
            int i = (int)(rnd() % (unsigned)n);
            img *im = &f.im[f.s.view[i]];
            im->px[(size_t)f.s.pixel[i] * im->channels] += 1.0f;
        }
        {
            float *before = malloc((size_t)3 * n * sizeof *before);
            memcpy(before, want, (size_t)3 * n * sizeof *want);
            reference(&f, which, want);
            for (int i = 0; i < 3 * n; i++)
                if (memcmp(&before[i], &want[i], sizeof(float)))
                    want_changed[i / 3 / SAMPLES_SPAN] = 1;
            free(before);
        }
        ASSERT_OK(samples_gather_views(&f.s, f.im, which, got, changed, &e));
        ASSERT(memcmp(got, want, (size_t)3 * n * sizeof *got) == 0);
        ASSERT(memcmp(changed, want_changed, nspans) == 0);
        for (size_t k = 0; k < nspans; k++)
            nchanged += want_changed[k];
        ASSERT(nchanged > 0); /* the case has something to flag */
        /* nothing changed: nothing flagged */
        memset(changed, 0, nspans);
        ASSERT_OK(samples_gather_views(&f.s, f.im, which, got, changed, &e));
        for (size_t k = 0; k < nspans; k++)
            ASSERT(changed[k] == 0);
        free(got);
        free(want);
        free(changed);
        free(want_changed);
        drop(&f);
    }
}

TEST(the_first_non_finite_pixel_is_named)
{
    static const float bad[3] = {NAN, INFINITY, -INFINITY};
    for (int t = 0; t < 18; t++) {
        fixture f;
        glint_err e;
        int n = 40000, first = -1, fch = -1;
        float *got = malloc((size_t)3 * n * sizeof *got);
        char want[160];
        make(&f, n, t % LAYOUTS, 0);
        for (int k = 0; k < 1 + t % 3; k++) { /* 1 to 3 bad pixels */
            int i = (int)(rnd() % (unsigned)n), ch = (int)(rnd() % 3);
            img *im = &f.im[f.s.view[i]];
            im->px[(size_t)f.s.pixel[i] * im->channels + (im->channels == 1 ? 0 : ch)] =
                bad[k];
        }
        for (int i = 0; i < n && first < 0; i++) { /* the first sample reading one */
            const img *im = &f.im[f.s.view[i]];
            for (int ch = 0; ch < 3 && first < 0; ch++)
                if (!isfinite(im->px[(size_t)f.s.pixel[i] * im->channels +
                                     (im->channels == 1 ? 0 : ch)])) {
                    first = i;
                    fch = ch;
                }
        }
        ASSERT(first >= 0);
        snprintf(want, sizeof want, "painting of view %d: pixel (%d, %d) channel %d is not finite",
                 f.s.view[first], f.s.pixel[first] / W, f.s.pixel[first] % W, fch);
        ASSERT_EQ(samples_gather(&f.s, f.im, got, &e), GLINT_ENONFINITE);
        ASSERT_MSG(strcmp(e.msg, want) == 0, "got \"%s\", want \"%s\"", e.msg, want);
        free(got);
        drop(&f);
    }
}

TEST_LIST {
    TEST_ENTRY(the_values_are_one_sample_at_a_time_bit_for_bit),
    TEST_ENTRY(views_left_out_are_not_written_and_changed_spans_are_flagged),
    TEST_ENTRY(the_first_non_finite_pixel_is_named),
};
TEST_MAIN()
