/* Tests of the OpenEXR encoder (core/img_exr.h), read back by OpenImageIO
 * (img_read_mem): RGB and RGBA images of many sizes (one pixel, heights
 * that are not a multiple of a block's 16 lines, wide and narrow) holding
 * smooth values, noise that deflate cannot shrink (blocks stored as they
 * are) and every kind of finite float (subnormals, -0, the largest) read
 * back the same bits, in the same channels; the encoder gives the same
 * file on one thread and on the pool; what it refuses. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "img.h"
#include "img_exr.h"
#include "par.h"

static uint64_t RNG = 0x2545f4914f6cdd1dull;

static uint32_t rnd(void)
{
    RNG ^= RNG << 13;
    RNG ^= RNG >> 7;
    RNG ^= RNG << 17;
    return (uint32_t)(RNG >> 11);
}

enum { SMOOTH, NOISE, BITS };

static float value(int kind, int x, int y, int c)
{
    uint32_t u;
    float f;
    switch (kind) {
    case SMOOTH:
        return (float)(0.5 + 0.4 * sin(0.05 * x + c) * cos(0.03 * y));
    case NOISE:
        return (float)(rnd() % 1000003) / 1000003.0f;
    default: /* any finite float */
        do {
            u = rnd() ^ (rnd() << 21);
            memcpy(&f, &u, sizeof f);
        } while (!isfinite(f));
        return f;
    }
}

static void fill(img *im, int kind)
{
    for (int y = 0; y < im->height; y++)
        for (int x = 0; x < im->width; x++)
            for (int c = 0; c < im->channels; c++)
                im->px[((size_t)y * im->width + x) * im->channels + c] = value(kind, x, y, c);
}

/* im through img_write_mem("exr") and img_read_mem: the same bits. */
static void round_trip(const img *im, int kind)
{
    glint_err e;
    void *data = NULL;
    size_t len = 0;
    img back;
    ASSERT_OK(img_write_mem("exr", im, &data, &len, &e));
    ASSERT(len > 8 && memcmp(data, "\x76\x2f\x31\x01", 4) == 0);
    ASSERT_OK(img_read_mem(data, len, &back, &e));
    ASSERT_EQ(back.width, im->width);
    ASSERT_EQ(back.height, im->height);
    ASSERT_EQ(back.channels, im->channels);
    if (back.px && back.channels == im->channels && back.width == im->width &&
        back.height == im->height)
        ASSERT_MSG(memcmp(back.px, im->px, ((size_t)im->width * im->height * im->channels * sizeof(float))) == 0,
                   "%dx%dx%d kind %d: the pixels read back differ", im->width, im->height,
                   im->channels, kind);
    img_free(&back);
    free(data);
}

TEST(images_read_back_the_same_bits)
{
    static const int sizes[][2] = {{1, 1}, {3, 17}, {256, 256}, {100, 33}, {1000, 5},
                                   {7, 16}, {5, 48}, {2, 1000}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (int nch = 3; nch <= 4; nch++)
            for (int kind = SMOOTH; kind <= BITS; kind++) {
                img im;
                glint_err e;
                ASSERT_OK(img_alloc(&im, sizes[s][0], sizes[s][1], nch, &e));
                fill(&im, kind);
                round_trip(&im, kind);
                img_free(&im);
            }
}

TEST(special_values_read_back)
{
    img im;
    glint_err e;
    const float special[] = {0.0f, -0.0f, 1e-45f, -1e-45f, 1.17549421e-38f, 3.40282347e38f,
                             -3.40282347e38f, 1.0f, -1.0f, 65504.0f, 6.1e-5f};
    ASSERT_OK(img_alloc(&im, 11, 19, 4, &e));
    for (size_t i = 0; i < ((size_t)im.width * im.height * im.channels); i++)
        im.px[i] = special[i % (sizeof special / sizeof special[0])];
    round_trip(&im, -1);
    img_free(&im);
}

TEST(one_thread_or_the_pool_the_same_file)
{
    img im;
    glint_err e;
    void *a = NULL, *b = NULL;
    size_t la = 0, lb = 0;
    ASSERT_OK(img_alloc(&im, 512, 300, 3, &e)); /* worth the pool */
    fill(&im, SMOOTH);
    for (int i = 0; i < 512 * 20 * 3; i++) /* a band of noise: blocks of both kinds */
        im.px[i] = value(NOISE, 0, 0, 0);
    ASSERT_OK(img_exr_encode(&im, &a, &la, &e));
    par_background(1); /* every block on this thread */
    ASSERT_OK(img_exr_encode(&im, &b, &lb, &e));
    par_background(0);
    ASSERT(la == lb && memcmp(a, b, la) == 0);
    round_trip(&im, SMOOTH);
    free(a);
    free(b);
    img_free(&im);
}

TEST(what_it_refuses)
{
    img im, grey;
    glint_err e;
    void *data = (void *)1;
    size_t len = 1;
    ASSERT_OK(img_alloc(&grey, 4, 4, 1, &e));
    ASSERT_EQ(img_exr_encode(&grey, &data, &len, &e), GLINT_EINVAL);
    ASSERT(data == NULL && len == 0);
    ASSERT_EQ(img_exr_encode(NULL, &data, &len, &e), GLINT_EINVAL);
    /* a grey image still writes as EXR (through OpenImageIO) */
    fill(&grey, SMOOTH);
    round_trip(&grey, SMOOTH);
    img_free(&grey);
    /* non-finite values are refused before any encoding */
    ASSERT_OK(img_alloc(&im, 4, 4, 3, &e));
    im.px[5] = NAN;
    ASSERT_EQ(img_write_mem("exr", &im, &data, &len, &e), GLINT_ENONFINITE);
    img_free(&im);
}

TEST_LIST {
    TEST_ENTRY(images_read_back_the_same_bits),
    TEST_ENTRY(special_values_read_back),
    TEST_ENTRY(one_thread_or_the_pool_the_same_file),
    TEST_ENTRY(what_it_refuses),
};
TEST_MAIN()
