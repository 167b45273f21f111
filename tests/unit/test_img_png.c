/* test_img_png.c: the direct PNG decoder (core/img/internal/img_png.h) against
 * OpenImageIO's, on PNGs made here with libpng: the ones it takes give the
 * same floats bit for bit (every 8-bit level among them), the others and
 * every damaged file go to OpenImageIO and come back as they did before
 * (the same floats, or the same error code). */
#include <png.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "img.h"
#include "img_oiio.h"
#include "img_png.h"

typedef struct obuf {
    unsigned char *p;
    size_t len, cap;
} obuf;

static void put(png_structp png, png_bytep data, size_t n)
{
    obuf *b = png_get_io_ptr(png);
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 4096;
        while (cap < b->len + n)
            cap *= 2;
        b->p = realloc(b->p, cap);
        b->cap = cap;
    }
    memcpy(b->p + b->len, data, n);
    b->len += n;
}

static void flush(png_structp png)
{
    (void)png;
}

enum { EXTRA_NONE = 0, EXTRA_GAMA = 1, EXTRA_SRGB = 2, EXTRA_TRNS = 4, EXTRA_TEXT = 8 };

/* A w x h PNG of color type `ctype` at `depth` bits (interlaced or not),
 * its samples a pattern that runs through every level (malloc'ed; *len). */
static unsigned char *make_png(int w, int h, int ctype, int depth, int interlace, int extra,
                               size_t *len)
{
    obuf b = {0};
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    int nch = ctype == PNG_COLOR_TYPE_RGB         ? 3
              : ctype == PNG_COLOR_TYPE_RGB_ALPHA ? 4
              : ctype == PNG_COLOR_TYPE_GA        ? 2
                                                  : 1;
    size_t rowbytes = (size_t)w * nch * (depth == 16 ? 2 : 1);
    unsigned char *row = malloc(rowbytes + 1);
    if (setjmp(png_jmpbuf(png)))
        abort();
    png_set_write_fn(png, &b, put, flush);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, depth, ctype,
                 interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (ctype == PNG_COLOR_TYPE_PALETTE) {
        png_color pal[256];
        for (int i = 0; i < 256; i++)
            pal[i].red = (png_byte)i, pal[i].green = (png_byte)(255 - i),
            pal[i].blue = (png_byte)(i * 7);
        png_set_PLTE(png, info, pal, 256);
    }
    if (extra & EXTRA_GAMA)
        png_set_gAMA(png, info, 1.0 / 2.2);
    if (extra & EXTRA_SRGB)
        png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    if (extra & EXTRA_TRNS) {
        png_color_16 t = {0, 10, 20, 30, 0};
        png_set_tRNS(png, info, NULL, 0, &t);
    }
    if (extra & EXTRA_TEXT) {
        png_text tx = {PNG_TEXT_COMPRESSION_NONE, "Software", "glint test", 10, 0, NULL, NULL};
        png_set_text(png, info, &tx, 1);
    }
    png_write_info(png, info);
    if (depth == 16)
        png_set_swap(png); /* the rows below are in the machine's order */
    {
        int passes = interlace ? png_set_interlace_handling(png) : 1;
        for (int pass = 0; pass < passes; pass++)
            for (int y = 0; y < h; y++) {
                for (size_t i = 0; i < (size_t)w * nch; i++) {
                    unsigned v = (unsigned)((size_t)y * w * nch + i) * 37u + (unsigned)y;
                    if (depth == 16)
                        ((uint16_t *)row)[i] = (uint16_t)(v * 257u + i);
                    else
                        row[i] = (unsigned char)v;
                }
                png_write_row(png, row);
            }
    }
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    free(row);
    *len = b.len;
    return b.p;
}

/* OpenImageIO's decode of the same bytes (rc; *out when 0). */
static int oiio(const unsigned char *d, size_t len, int max_dim, img_oiio_pixels *out)
{
    glint_err e;
    return img_oiio_read("png", NULL, d, len, "test", max_dim, 4, 0, NULL, NULL, out, &e);
}

static int same_pixels(const img *a, const img_oiio_pixels *b)
{
    return a->width == b->width && a->height == b->height && a->channels == b->channels &&
           memcmp(a->px, b->px, (size_t)a->width * a->height * a->channels * sizeof(float)) ==
               0;
}

TEST(the_pngs_it_takes_decode_as_openimageio_does)
{
    static const struct {
        int w, h, ctype, extra;
    } cases[] = {
        {257, 5, PNG_COLOR_TYPE_RGB, EXTRA_NONE}, /* 3855 samples: every level, many times */
        {64, 64, PNG_COLOR_TYPE_RGB_ALPHA, EXTRA_NONE},
        {1, 1, PNG_COLOR_TYPE_RGB, EXTRA_NONE},
        {3, 200, PNG_COLOR_TYPE_RGB_ALPHA, EXTRA_TEXT}, /* a chunk that changes nothing */
    };
    for (unsigned k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        size_t len;
        unsigned char *d = make_png(cases[k].w, cases[k].h, cases[k].ctype, 8, 0,
                                    cases[k].extra, &len);
        img_oiio_pixels direct, ref;
        img a;
        glint_err e;
        ASSERT_MSG(img_png_read(d, len, IMG_MAX_DIM, 4, &direct) == 0, "case %u", k);
        ASSERT_OK(oiio(d, len, IMG_MAX_DIM, &ref));
        ASSERT_OK(img_read_mem(d, len, &a, &e));
        ASSERT_MSG(same_pixels(&a, &ref), "case %u", k);
        ASSERT(direct.width == ref.width && direct.channels == ref.channels &&
               memcmp(direct.px, ref.px,
                      (size_t)ref.width * ref.height * ref.channels * sizeof(float)) == 0);
        if (k == 0) { /* every level q is the float nearest q / 255 */
            int seen[256] = {0};
            for (int i = 0; i < 257 * 5 * 3; i++) {
                int q = (int)(a.px[i] * 255.0f + 0.5f);
                ASSERT(a.px[i] == (float)q / 255.0f);
                seen[q] = 1;
            }
            for (int q = 0; q < 256; q++)
                ASSERT(seen[q]);
        }
        img_free(&a);
        img_oiio_pixels_free(&direct);
        img_oiio_pixels_free(&ref);
        free(d);
    }
}

/* What the direct path leaves to OpenImageIO: it says so, and the image
 * decodes as OpenImageIO decodes it. */
TEST(the_others_go_to_openimageio)
{
    static const struct {
        int ctype, depth, interlace, extra;
    } cases[] = {
        {PNG_COLOR_TYPE_RGB, 16, 0, EXTRA_NONE},
        {PNG_COLOR_TYPE_RGB, 8, 1, EXTRA_NONE},
        {PNG_COLOR_TYPE_GRAY, 8, 0, EXTRA_NONE},
        {PNG_COLOR_TYPE_GA, 8, 0, EXTRA_NONE},
        {PNG_COLOR_TYPE_PALETTE, 8, 0, EXTRA_NONE},
        {PNG_COLOR_TYPE_RGB, 8, 0, EXTRA_TRNS},
        {PNG_COLOR_TYPE_RGB, 8, 0, EXTRA_GAMA},
        {PNG_COLOR_TYPE_RGB_ALPHA, 8, 0, EXTRA_SRGB},
    };
    for (unsigned k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        size_t len;
        unsigned char *d = make_png(33, 17, cases[k].ctype, cases[k].depth,
                                    cases[k].interlace, cases[k].extra, &len);
        img_oiio_pixels direct, ref;
        img a;
        glint_err e;
        ASSERT_MSG(img_png_read(d, len, IMG_MAX_DIM, 4, &direct) == 1, "case %u", k);
        ASSERT(direct.px == NULL);
        ASSERT_OK(oiio(d, len, IMG_MAX_DIM, &ref));
        ASSERT_OK(img_read_mem(d, len, &a, &e));
        ASSERT_MSG(same_pixels(&a, &ref), "case %u", k);
        img_free(&a);
        img_oiio_pixels_free(&ref);
        free(d);
    }
}

/* Damaged files, and one over the size limit: the direct path declines,
 * and the answer is OpenImageIO's as before (the same code; the same
 * floats where it decodes what is there). */
TEST(damaged_and_oversized_pngs_answer_as_before)
{
    size_t len;
    unsigned char *d = make_png(40, 30, PNG_COLOR_TYPE_RGB, 8, 0, EXTRA_TEXT, &len);
    unsigned char *c = malloc(len + 64);
    const size_t cuts[] = {8, 20, 33, 50, len / 2, len - 20, len - 12, len - 1};
    img_oiio_pixels direct, ref;
    img a;
    glint_err e;
    for (unsigned k = 0; k < sizeof cuts / sizeof cuts[0]; k++) {
        int r1, r2;
        ASSERT_MSG(img_png_read(d, cuts[k], IMG_MAX_DIM, 4, &direct) == 1, "cut at %zu",
                   cuts[k]);
        r1 = oiio(d, cuts[k], IMG_MAX_DIM, &ref);
        r2 = img_read_mem(d, cuts[k], &a, &e);
        ASSERT_MSG(r1 == r2, "cut at %zu: %d against %d", cuts[k], r2, r1);
        if (!r1) {
            ASSERT(same_pixels(&a, &ref));
            img_free(&a);
            img_oiio_pixels_free(&ref);
        }
    }
    /* a byte flipped in every chunk in turn (CRCs, lengths, data; the text
     * chunk's too, which libpng alone would only warn about) */
    for (size_t at = 8; at < len; at += 7) {
        int r1, r2, r0;
        memcpy(c, d, len);
        c[at] ^= 0x21;
        r0 = img_png_read(c, len, IMG_MAX_DIM, 4, &direct);
        r1 = oiio(c, len, IMG_MAX_DIM, &ref);
        r2 = img_read_mem(c, len, &a, &e);
        ASSERT_MSG(r1 == r2, "flip at %zu: %d against %d", at, r2, r1);
        if (r0 == 0) { /* taken: only where OpenImageIO decodes it the same */
            ASSERT_MSG(r1 == 0 && memcmp(direct.px, ref.px, 40 * 30 * 3 * sizeof(float)) == 0,
                       "flip at %zu", at);
            img_oiio_pixels_free(&direct);
        }
        if (!r1) {
            ASSERT(same_pixels(&a, &ref));
            img_free(&a);
            img_oiio_pixels_free(&ref);
        }
    }
    /* bytes after IEND */
    memcpy(c, d, len);
    memset(c + len, 0xab, 64);
    ASSERT_EQ(img_read_mem(c, len + 64, &a, &e), oiio(c, len + 64, IMG_MAX_DIM, &ref));
    if (a.px) {
        ASSERT(same_pixels(&a, &ref));
        img_free(&a);
        img_oiio_pixels_free(&ref);
    }
    /* over the limit: refused before any pixel is decoded */
    ASSERT_EQ(img_png_read(d, len, 39, 4, &direct), 1);
    ASSERT_EQ(img_read_mem_max(d, len, 39, &a, &e), GLINT_ERANGE);
    ASSERT_EQ(img_png_read(d, len, IMG_MAX_DIM, 2, &direct), 1); /* too many channels */
    free(c);
    free(d);
}

/* What a header check saw (check_record), and what it answers. */
typedef struct seen {
    int calls, answer;
    img_header hd;
} seen;

static int check_record(void *cls, const img_header *hd, glint_err *err)
{
    seen *s = cls;
    s->calls++;
    s->hd = *hd;
    if (s->answer)
        return glint_err_set(err, s->answer, "refused by the test");
    return 0;
}

/* The header an upload's check sees (img_read_mem_checked) is the image
 * the decode returns, for every PNG kind (those of the direct path and
 * OpenImageIO's, tRNS turned into alpha) and OpenImageIO's other formats;
 * the check sees it once, and a refusal decodes nothing. */
TEST(the_header_is_checked_once_before_any_pixel)
{
    static const struct {
        int ctype, depth, interlace, extra;
    } cases[] = {
        {PNG_COLOR_TYPE_RGB, 8, 0, EXTRA_NONE},      {PNG_COLOR_TYPE_RGB_ALPHA, 8, 0, EXTRA_TEXT},
        {PNG_COLOR_TYPE_RGB, 16, 0, EXTRA_NONE},     {PNG_COLOR_TYPE_RGB, 8, 1, EXTRA_NONE},
        {PNG_COLOR_TYPE_GRAY, 8, 0, EXTRA_NONE},     {PNG_COLOR_TYPE_GRAY, 4, 0, EXTRA_NONE},
        {PNG_COLOR_TYPE_GRAY, 16, 0, EXTRA_TRNS},    {PNG_COLOR_TYPE_GA, 8, 0, EXTRA_NONE},
        {PNG_COLOR_TYPE_PALETTE, 8, 0, EXTRA_NONE},  {PNG_COLOR_TYPE_RGB, 8, 0, EXTRA_TRNS},
        {PNG_COLOR_TYPE_RGB, 8, 0, EXTRA_GAMA},      {PNG_COLOR_TYPE_RGB_ALPHA, 16, 1, EXTRA_SRGB},
    };
    static const char *const formats[] = {"exr", "jpg", "hdr"};
    img src;
    glint_err e;
    for (unsigned k = 0; k < sizeof cases / sizeof cases[0] + 3; k++) {
        size_t len;
        unsigned char *d;
        seen s = {0, 0, {0}};
        img a;
        if (k < sizeof cases / sizeof cases[0]) {
            d = make_png(33, 17, cases[k].ctype, cases[k].depth, cases[k].interlace,
                         cases[k].extra, &len);
        } else {
            ASSERT_OK(img_alloc(&src, 33, 17, 3, &e));
            for (size_t i = 0; i < (size_t)33 * 17 * 3; i++)
                src.px[i] = (float)(i % 7) / 7.0f;
            ASSERT_OK(img_write_mem(formats[k - sizeof cases / sizeof cases[0]], &src,
                                    (void **)&d, &len, &e));
            img_free(&src);
        }
        ASSERT_MSG(img_read_mem_checked(d, len, 0, check_record, &s, &a, &e) == 0,
                   "case %u: %s", k, e.msg);
        ASSERT_MSG(s.calls == 1, "case %u: %d calls", k, s.calls);
        ASSERT_MSG(s.hd.width == a.width && s.hd.height == a.height &&
                       s.hd.channels == a.channels,
                   "case %u: header %dx%dx%d, decoded %dx%dx%d", k, s.hd.width, s.hd.height,
                   s.hd.channels, a.width, a.height, a.channels);
        ASSERT_MSG(s.hd.decode_bytes >= (size_t)a.width * a.height * a.channels * 4 +
                                            IMG_DECODE_FIXED_BYTES,
                   "case %u: bound %zu", k, s.hd.decode_bytes);
        img_free(&a);
        s.calls = 0;
        s.answer = GLINT_ETOOBIG;
        ASSERT_EQ(img_read_mem_checked(d, len, 0, check_record, &s, &a, &e), GLINT_ETOOBIG);
        ASSERT(s.calls == 1 && a.px == NULL && strcmp(e.msg, "refused by the test") == 0);
        free(d);
    }
}

/* A header that declares 16384 x 16384 in a few bytes: the check sees the
 * size and the decode's bound (6 bytes a sample: 4.5 GiB) before a row is
 * read; a file that is not a PNG past its signature never reaches it. */
TEST(a_huge_header_is_seen_before_its_rows)
{
    size_t len;
    unsigned char *d = make_png(4, 4, PNG_COLOR_TYPE_RGB, 8, 0, EXTRA_NONE, &len);
    seen s = {0, GLINT_ETOOBIG, {0}};
    img a;
    glint_err e;
    d[16] = d[20] = 0, d[17] = d[21] = 0, d[18] = d[22] = 0x40, d[19] = d[23] = 0;
    ASSERT_EQ(img_read_mem_checked(d, len, 0, check_record, &s, &a, &e), GLINT_ETOOBIG);
    ASSERT(s.calls == 1 && s.hd.width == 16384 && s.hd.height == 16384 && s.hd.channels == 3);
    ASSERT_EQ(s.hd.decode_bytes, (size_t)16384 * 16384 * 3 * 6 + IMG_DECODE_FIXED_BYTES);
    s.calls = 0;
    ASSERT(img_read_mem_checked("\x89PNG\r\n\x1a\nnot", 11, 0, check_record, &s, &a, &e) != 0);
    ASSERT_EQ(s.calls, 0);
    free(d);
}

TEST_LIST {
    TEST_ENTRY(the_pngs_it_takes_decode_as_openimageio_does),
    TEST_ENTRY(the_header_is_checked_once_before_any_pixel),
    TEST_ENTRY(a_huge_header_is_seen_before_its_rows),
    TEST_ENTRY(the_others_go_to_openimageio),
    TEST_ENTRY(damaged_and_oversized_pngs_answer_as_before),
};
TEST_MAIN()
