/* fuzz_image.c: image bytes from outside, decoded as glintd decodes an
 * upload.  The first byte picks the reader, the rest is the file:
 *   0  a painting or photo (PUT .../paintings/K, the photo bar):
 *      img_read_mem_checked with a header check as the server's (sides
 *      up to the limit), through the OpenImageIO shim or, for the common
 *      PNGs, libpng directly (img_png.h), which must then give
 *      OpenImageIO's floats bit for bit; what decodes is the image its
 *      header declared, seen once before; when byte 0 / 3 is odd, the
 *      file is a well-formed PNG built from the rest (png_build);
 *   1  an environment map (POST /environments): env_load_mem, lat-long or
 *      cube cross, then its texels must be finite and non-negative;
 *   2  a MERL table (glintd --measured-dir, paint --brdf merl:FILE):
 *      merl_read_mem, then every entry must be finite.
 * What decodes must keep to the size limit it was given. */
#include <libdeflate.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "env.h"
#include "fuzz.h"
#include "img.h"
#include "img_oiio.h"
#include "img_png.h"
#include "merl.h"

#define MAX_DIM 512

/* The header check of case 0: sides up to MAX_DIM, as the server's
 * upload gate holds them to its limit; it records what it saw. */
typedef struct header_seen {
    int calls;
    img_header hd;
} header_seen;

static int header_check(void *cls, const img_header *hd, glint_err *err)
{
    header_seen *s = cls;
    s->calls++;
    s->hd = *hd;
    if (hd->width > MAX_DIM || hd->height > MAX_DIM)
        return glint_err_set(err, GLINT_ERANGE, "a header of %dx%d", hd->width, hd->height);
    return 0;
}

/* ---- PNGs built from the fuzzer's bytes --------------------------------------------- */

/* Mutated PNGs mostly fail their chunks' CRCs or zlib's check, and both
 * decoders then refuse them.  png_build makes a well-formed PNG of what
 * the bytes describe, so that the direct path's choices (the header's
 * fields, the ancillary chunks that decline it) and its pixels are
 * compared with OpenImageIO's:
 *   in[0]: width - 1 (mod 48), in[1]: height - 1 (mod 48);
 *   in[2]: colour type and bit depth (one of PNG's 15 pairs, 8-bit RGB
 *     and RGBA the likelier);
 *   in[3]: bit 0 interlaced (Adam7); bits 1-6 add gAMA, sRGB, tRNS, cHRM,
 *     a tEXt and an oFFs chunk; bit 7 leaves the palette out;
 *   in[4..]: the filtered scanlines, each filter byte taken mod 5,
 *     repeated to the length the image needs (zeros when there are none).
 * OUT: the file (malloc'd) and *len; NULL when out of memory. */
static uint8_t *put_chunk(uint8_t *q, const char *type, const uint8_t *d, uint32_t n)
{
    uint32_t crc;
    q[0] = (uint8_t)(n >> 24);
    q[1] = (uint8_t)(n >> 16);
    q[2] = (uint8_t)(n >> 8);
    q[3] = (uint8_t)n;
    memcpy(q + 4, type, 4);
    if (n)
        memcpy(q + 8, d, n);
    crc = libdeflate_crc32(0, q + 4, 4 + (size_t)n);
    q[8 + n] = (uint8_t)(crc >> 24);
    q[9 + n] = (uint8_t)(crc >> 16);
    q[10 + n] = (uint8_t)(crc >> 8);
    q[11 + n] = (uint8_t)crc;
    return q + 12 + n;
}

static uint8_t *png_build(const uint8_t *in, size_t n, size_t *len)
{
    static const uint8_t pairs[][2] = {{2, 8}, {6, 8}, {2, 8}, {6, 8}, {0, 1}, {0, 2}, {0, 4},
                                       {0, 8}, {0, 16}, {2, 16}, {3, 1}, {3, 2}, {3, 4},
                                       {3, 8}, {4, 8}, {4, 16}, {6, 16}};
    static const uint8_t spp[7] = {1, 0, 3, 1, 2, 0, 4};
    static const int x0[7] = {0, 4, 0, 2, 0, 1, 0}, dx[7] = {8, 8, 4, 4, 2, 2, 1},
                     y0[7] = {0, 0, 4, 0, 2, 0, 1}, dy[7] = {8, 8, 8, 4, 4, 2, 2};
    uint8_t ihdr[13], pal[768], trns[256], *raw, *z, *file, *q;
    int w, h, ct, depth, interlace, flags, npal = 256;
    size_t rawlen = 0, zcap, zlen, k = 0;
    struct libdeflate_compressor *c;

    if (n < 4)
        return NULL;
    w = 1 + in[0] % 48;
    h = 1 + in[1] % 48;
    ct = pairs[in[2] % (sizeof pairs / sizeof pairs[0])][0];
    depth = pairs[in[2] % (sizeof pairs / sizeof pairs[0])][1];
    interlace = in[3] & 1;
    flags = in[3];
    in += 4;
    n -= 4;
    /* the scanlines: one filter byte and the row's bytes, per pass */
    for (int p = 0; p < (interlace ? 7 : 1); p++) {
        int pw = interlace ? (w - x0[p] + dx[p] - 1) / dx[p] : w;
        int ph = interlace ? (h - y0[p] + dy[p] - 1) / dy[p] : h;
        if (pw > 0 && ph > 0)
            rawlen += (size_t)ph * (1 + ((size_t)pw * spp[ct] * depth + 7) / 8);
    }
    if (!(raw = malloc(rawlen)))
        return NULL;
    for (size_t i = 0; i < rawlen; i++)
        raw[i] = n ? in[i % n] : 0;
    for (int p = 0; p < (interlace ? 7 : 1); p++) {
        int pw = interlace ? (w - x0[p] + dx[p] - 1) / dx[p] : w;
        int ph = interlace ? (h - y0[p] + dy[p] - 1) / dy[p] : h;
        if (pw <= 0 || ph <= 0)
            continue;
        for (int y = 0; y < ph; y++) {
            raw[k] %= 5;
            k += 1 + ((size_t)pw * spp[ct] * depth + 7) / 8;
        }
    }
    c = libdeflate_alloc_compressor(1);
    zcap = c ? libdeflate_zlib_compress_bound(c, rawlen) : 0;
    z = c ? malloc(zcap) : NULL;
    zlen = z ? libdeflate_zlib_compress(c, raw, rawlen, z, zcap) : 0;
    libdeflate_free_compressor(c);
    free(raw);
    if (!zlen || !(file = malloc(8 + 25 + 780 + 268 + 44 + 16 + 24 + 40 + 21 + zlen + 12 + 12))) {
        free(z);
        return NULL;
    }
    memcpy(file, "\x89PNG\r\n\x1a\n", 8);
    ihdr[0] = ihdr[1] = ihdr[2] = 0;
    ihdr[3] = (uint8_t)w;
    ihdr[4] = ihdr[5] = ihdr[6] = 0;
    ihdr[7] = (uint8_t)h;
    ihdr[8] = (uint8_t)depth;
    ihdr[9] = (uint8_t)ct;
    ihdr[10] = ihdr[11] = 0;
    ihdr[12] = (uint8_t)interlace;
    q = put_chunk(file + 8, "IHDR", ihdr, 13);
    if (flags & 2) {
        static const uint8_t g[4] = {0, 0, 0xb1, 0x8f}; /* 1 / 2.2 */
        q = put_chunk(q, "gAMA", g, 4);
    }
    if (flags & 4) {
        static const uint8_t intent = 0;
        q = put_chunk(q, "sRGB", &intent, 1);
    }
    if (flags & 16) {
        static const uint32_t chrm[8] = {31270, 32900, 64000, 33000, 30000, 60000, 15000, 6000};
        uint8_t b[32];
        for (int i = 0; i < 8; i++) {
            b[4 * i] = (uint8_t)(chrm[i] >> 24);
            b[4 * i + 1] = (uint8_t)(chrm[i] >> 16);
            b[4 * i + 2] = (uint8_t)(chrm[i] >> 8);
            b[4 * i + 3] = (uint8_t)chrm[i];
        }
        q = put_chunk(q, "cHRM", b, 32);
    }
    if (ct == 3 && !(flags & 128)) {
        for (int i = 0; i < npal; i++) {
            pal[3 * i] = (uint8_t)i;
            pal[3 * i + 1] = (uint8_t)(255 - i);
            pal[3 * i + 2] = (uint8_t)(7 * i);
        }
        q = put_chunk(q, "PLTE", pal, 3 * (uint32_t)npal);
    }
    if (flags & 8) { /* grey, RGB or palette alpha; also where PNG has none */
        for (int i = 0; i < 256; i++)
            trns[i] = (uint8_t)(i * 37);
        q = put_chunk(q, "tRNS", trns, ct == 3 ? 256u : ct == 2 ? 6u : 2u);
    }
    if (flags & 32)
        q = put_chunk(q, "tEXt", (const uint8_t *)"Software\0glint", 14);
    if (flags & 64) {
        static const uint8_t offs[9] = {0, 0, 0, 3, 0, 0, 0, 5, 0};
        q = put_chunk(q, "oFFs", offs, 9);
    }
    q = put_chunk(q, "IDAT", z, (uint32_t)zlen);
    q = put_chunk(q, "IEND", NULL, 0);
    free(z);
    *len = (size_t)(q - file);
    return file;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    glint_err e;
    if (size < 1 || size > (size_t)64 << 20)
        return 0;
    switch (data[0] % 3) {
    case 0: {
        img im = {0};
        img_oiio_pixels direct = {0};
        uint8_t *built = NULL;
        const uint8_t *file = data + 1;
        size_t len = size - 1;
        if (data[0] / 3 % 2 == 1) { /* a PNG built from the rest */
            if (!(built = png_build(data + 1, size - 1, &len)))
                break;
            file = built;
        }
        /* the direct PNG path (img_png.h) takes a file only to give
         * OpenImageIO's floats bit for bit */
        if (img_png_read(file, len, MAX_DIM, 4, &direct) == 0) {
            img_oiio_pixels ref = {0};
            FUZZ_CHECK(img_oiio_read("png", NULL, file, len, "fuzz", MAX_DIM, 4, 0, NULL, NULL,
                                     &ref, &e) == 0);
            FUZZ_CHECK(ref.width == direct.width && ref.height == direct.height &&
                       ref.channels == direct.channels);
            FUZZ_CHECK(memcmp(ref.px, direct.px,
                              (size_t)ref.width * ref.height * ref.channels * sizeof(float)) == 0);
            img_oiio_pixels_free(&ref);
            img_oiio_pixels_free(&direct);
            fuzz_note("image", "a PNG decoded directly, as OpenImageIO decodes it");
        }
        header_seen seen = {0, {NULL, 0, 0, 0, 0}};
        if (img_read_mem_checked(file, len, 0, header_check, &seen, &im, &e) == 0) {
            FUZZ_CHECK(im.width >= 1 && im.width <= MAX_DIM && im.height >= 1 &&
                       im.height <= MAX_DIM && im.channels >= 1 && im.channels <= 4);
            FUZZ_CHECK(im.px != NULL);
            FUZZ_CHECK(seen.calls == 1 && seen.hd.width == im.width &&
                       seen.hd.height == im.height && seen.hd.channels >= im.channels);
            FUZZ_CHECK(seen.hd.decode_bytes >= (size_t)im.width * im.height * im.channels * 4);
            img_free(&im);
        } else {
            FUZZ_CHECK(e.msg[0] != '\0' && seen.calls <= 1);
            fuzz_note("image", e.msg);
        }
        free(built);
        break;
    }
    case 1: {
        env_map m = {0};
        if (env_load_mem(data + 1, size - 1, "upload", MAX_DIM, NULL, NULL, &m, &e) == 0) {
            size_t n = (size_t)m.width * m.height * 3;
            FUZZ_CHECK(m.width == 2 * m.height && m.height >= 1);
            for (size_t i = 0; i < n; i++)
                FUZZ_CHECK(isfinite(m.rgb[i]) && m.rgb[i] >= 0);
            env_map_free(&m);
        } else {
            FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("image", e.msg);
        }
        break;
    }
    default: {
        merl_table t = {0};
        if (merl_read_mem(data + 1, size - 1, &t, &e) == 0)
            merl_free(&t);
        else
            FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("image", e.msg);
        break;
    }
    }
    return 0;
}
