/* Tests of the OpenEXR encoder (core/img/img_exr.h), read back by OpenImageIO
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

/* Lines y0..y1 of im (and of no other line) given new values. */
static void change_lines(img *im, int y0, int y1)
{
    for (int y = y0 < 0 ? 0 : y0; y <= y1 && y < im->height; y++)
        for (int x = 0; x < im->width; x++)
            for (int c = 0; c < im->channels; c++)
                im->px[((size_t)y * im->width + x) * im->channels + c] =
                    value(rnd() % 2 ? SMOOTH : NOISE, x + 7, y, c);
}

/* A file made from the last one where only lines y0..y1 changed is the
 * file img_exr_encode makes of the new image, byte for byte, with the
 * blocks clear of the lines copied: across block edges, at the first and
 * the last (short) block, no line, every line. */
TEST(from_the_last_file_the_same_bytes)
{
    static const int sizes[][3] = {{256, 256, 3}, {97, 83, 4}, {5, 16, 3}, {300, 1, 3}};
    static const int spans[][2] = {{40, 60},  {0, 0},   {15, 16}, {16, 31}, {70, 82},
                                   {82, 82},  {255, 255}, {3, 2},  {0, 300}, {-5, 3},
                                   {100, 900}, {31, 32}};
    for (size_t z = 0; z < sizeof sizes / sizeof sizes[0]; z++) {
        img im;
        glint_err e;
        void *prev = NULL;
        size_t plen = 0;
        int W = sizes[z][0], H = sizes[z][1], nb = (H + 15) / 16;
        ASSERT_OK(img_alloc(&im, W, H, sizes[z][2], &e));
        fill(&im, SMOOTH);
        ASSERT_OK(img_exr_encode(&im, &prev, &plen, &e));
        for (size_t t = 0; t < sizeof spans / sizeof spans[0]; t++) {
            int y0 = spans[t][0], y1 = spans[t][1], reused = -1, want = 0;
            void *got = NULL, *fresh = NULL;
            size_t glen = 0, flen = 0;
            change_lines(&im, y0, y1);
            for (int b = 0; b < nb; b++)
                want += y1 < y0 || 16 * b + 15 < y0 || 16 * b > y1;
            ASSERT_OK(img_exr_encode_reusing(&im, prev, plen, y0, y1, &got, &glen, &reused, &e));
            ASSERT_OK(img_exr_encode(&im, &fresh, &flen, &e));
            ASSERT_MSG(glen == flen && memcmp(got, fresh, flen) == 0, "%dx%d lines %d..%d", W, H,
                       y0, y1);
            ASSERT_EQ(reused, want);
            free(prev);
            free(fresh);
            prev = got; /* the next change starts from this file */
            plen = glen;
        }
        round_trip(&im, -1);
        free(prev);
        img_free(&im);
    }
}

/* A previous file that is not the layout img_exr_encode writes for the
 * image (another size or channel count, OpenImageIO's, cut short, a table
 * or block header altered) gives nothing: every block is encoded and the
 * file is img_exr_encode's. */
TEST(from_a_file_of_another_layout_nothing)
{
    img im, other;
    glint_err e;
    void *prev = NULL, *fresh = NULL, *oiio = NULL;
    size_t plen = 0, flen = 0, olen = 0;
    unsigned char *bad;
    ASSERT_OK(img_alloc(&im, 64, 50, 3, &e));
    fill(&im, SMOOTH);
    ASSERT_OK(img_exr_encode(&im, &prev, &plen, &e));
    change_lines(&im, 20, 21);
    ASSERT_OK(img_exr_encode(&im, &fresh, &flen, &e));
    ASSERT_OK(img_alloc(&other, 64, 49, 3, &e));
    fill(&other, SMOOTH);
    ASSERT_OK(img_write_mem("png", &im, &oiio, &olen, &e));
    bad = malloc(plen);
    ASSERT(bad != NULL);
    /* 0: another height; 1: a PNG; 2..: prev cut short, or one byte of
     * its table or of a block's line or size changed */
    for (int t = 0; t < 2 + 6 + 64; t++) {
        const void *p = bad;
        size_t len = plen;
        void *got = NULL, *o = NULL;
        size_t glen = 0, ol = 0;
        int reused = -1;
        memcpy(bad, prev, plen);
        if (t == 0) {
            ASSERT_OK(img_exr_encode(&other, &o, &ol, &e));
            p = o;
            len = ol;
        } else if (t == 1) {
            p = oiio;
            len = olen;
        } else if (t < 8) {
            static const size_t cut[5] = {0, 1, 100, 300, 400};
            len = t == 7 ? plen - 1 : cut[t - 2];
        } else {
            /* the table starts after the header; the first block after it */
            size_t table = 0, at;
            uint64_t first;
            for (size_t i = 8; i + 1 < plen; i++) /* the header ends with a 0 after the last attribute */
                if (memcmp(bad + i, "screenWindowWidth", 17) == 0) {
                    table = i + 18 + 6 + 4 + 4 + 1; /* name, "float", size, value, end */
                    break;
                }
            ASSERT(table > 0);
            memcpy(&first, bad + table, 8);
            ASSERT_EQ(first, table + 8 * 4); /* 4 blocks of 16 lines */
            at = (t - 8) % 2 ? table + (size_t)((t - 8) / 2) % 32 /* the table */
                             : (size_t)first + (size_t)((t - 8) / 2) % 8; /* block 0's line, size */
            bad[at] ^= (unsigned char)(1u << ((t - 8) / 2 % 8));
        }
        ASSERT_OK(img_exr_encode_reusing(&im, p, len, 20, 21, &got, &glen, &reused, &e));
        ASSERT_EQ(reused, 0);
        ASSERT(glen == flen && memcmp(got, fresh, flen) == 0);
        free(got);
        free(o);
    }
    /* no previous file */
    {
        void *got = NULL;
        size_t glen = 0;
        int reused = -1;
        ASSERT_OK(img_exr_encode_reusing(&im, NULL, 0, 20, 21, &got, &glen, &reused, &e));
        ASSERT(reused == 0 && glen == flen && memcmp(got, fresh, flen) == 0);
        free(got);
    }
    free(bad);
    free(prev);
    free(fresh);
    free(oiio);
    img_free(&im);
    img_free(&other);
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
    TEST_ENTRY(from_the_last_file_the_same_bytes),
    TEST_ENTRY(from_a_file_of_another_layout_nothing),
    TEST_ENTRY(what_it_refuses),
};
TEST_MAIN()
