/* img_exr.c: an RGB(A) image as an OpenEXR file in memory (img_exr.h).
 *
 * The layout (OpenEXR 2, single-part scanline):
 *   magic 76 2f 31 01, version 2 (no flags);
 *   the header: attributes (name, type, size, value), then a 0 byte;
 *   the line offset table: one uint64 per block, from the file's start;
 *   the blocks: int32 first line, int32 size, the data.
 * A block holds 16 lines (ZIP_COMPRESSION); per line, the channels in
 * the order of their names (A, B, G, R), each the line's floats.  The
 * block's bytes are split (bytes 0, 2, 4, ... then 1, 3, 5, ...), each
 * byte but the first replaced by (byte - previous + 128) mod 256, and
 * deflated in zlib's format.  A block that does not get smaller is
 * stored as it is (readers tell by its size).  Numbers are little-endian,
 * as on the machines glint builds for (checked below). */
#include "img_exr.h"

#include <libdeflate.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "par.h"

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "img_exr.c writes its numbers in the machine's order: little-endian only"
#endif

#define EXR_LINES 16          /* lines per block of ZIP_COMPRESSION */
#define EXR_ZIP 3             /* ZIP_COMPRESSION */
#define EXR_FLOAT 2           /* pixel type FLOAT */
#define EXR_DEFLATE_LEVEL 1

typedef struct block {
    unsigned char *data; /* what the file holds for the block */
    size_t size;
} block;

typedef struct encode_ctx {
    const img *im;
    int nblocks, ntasks;
    block *blocks;
    const int *todo; /* the blocks to encode, ntodo of them */
    int ntodo;
    int failed; /* a task ran out of memory */
} encode_ctx;

/* The channel of the file's c-th (A, B, G, R order) in the image's. */
static int file_channel(int nch, int c)
{
    static const int rgb[3] = {2, 1, 0}, rgba[4] = {3, 2, 1, 0};
    return nch == 3 ? rgb[c] : rgba[c];
}

/* Block b's bytes as the file lays them out (OUT: raw, n bytes). */
static size_t block_raw(const img *im, int b, unsigned char *raw)
{
    int W = im->width, nch = im->channels, y0 = b * EXR_LINES;
    int y1 = y0 + EXR_LINES < im->height ? y0 + EXR_LINES : im->height;
    size_t k = 0;
    for (int y = y0; y < y1; y++)
        for (int c = 0; c < nch; c++) {
            const float *p = im->px + (size_t)y * W * nch + file_channel(nch, c);
            for (int x = 0; x < W; x++, k += 4)
                memcpy(raw + k, p + (size_t)x * nch, 4);
        }
    return k;
}

/* Block b split and differenced (OUT: pred; split is scratch), n bytes.
 * The m-th float of the block's bytes, b0 b1 b2 b3, goes to split[2m],
 * split[2m + 1] (b0, b2) and split[n/2 + 2m], split[n/2 + 2m + 1]
 * (b1, b3): n is a multiple of 4. */
static size_t block_pred(const img *im, int b, unsigned char *restrict split,
                         unsigned char *restrict pred)
{
    int W = im->width, nch = im->channels, y0 = b * EXR_LINES;
    int y1 = y0 + EXR_LINES < im->height ? y0 + EXR_LINES : im->height;
    size_t n = (size_t)(y1 - y0) * W * nch * 4, m = 0;
    unsigned char *lo = split, *hi = split + n / 2;
    for (int y = y0; y < y1; y++)
        for (int c = 0; c < nch; c++) {
            const float *p = im->px + (size_t)y * W * nch + file_channel(nch, c);
            for (int x = 0; x < W; x++, m++) {
                uint32_t u;
                memcpy(&u, p + (size_t)x * nch, sizeof u);
                lo[2 * m] = (unsigned char)u;
                lo[2 * m + 1] = (unsigned char)(u >> 16);
                hi[2 * m] = (unsigned char)(u >> 8);
                hi[2 * m + 1] = (unsigned char)(u >> 24);
            }
        }
    pred[0] = split[0];
    for (size_t i = 1; i < n; i++)
        pred[i] = (unsigned char)(split[i] - split[i - 1] + 128);
    return n;
}

/* Task t: the blocks todo[t], todo[t + ntasks], ... with a compressor of
 * its own. */
static void encode_task(void *vctx, int t)
{
    encode_ctx *x = vctx;
    const img *im = x->im;
    size_t cap = (size_t)EXR_LINES * im->width * im->channels * 4;
    struct libdeflate_compressor *z = libdeflate_alloc_compressor(EXR_DEFLATE_LEVEL);
    unsigned char *split = malloc(cap), *pred = malloc(cap);
    size_t bound = z ? libdeflate_zlib_compress_bound(z, cap) : 0;

    for (int j = t; z && split && pred && j < x->ntodo; j += x->ntasks) {
        int b = x->todo[j];
        size_t n = block_pred(im, b, split, pred), got;
        unsigned char *out = malloc(bound > n ? bound : n);
        if (!out)
            break;
        got = libdeflate_zlib_compress(z, pred, n, out, bound);
        if (got == 0 || got >= n) /* not smaller: stored as it is */
            got = block_raw(im, b, out);
        x->blocks[b].data = out;
        x->blocks[b].size = got;
    }
    for (int j = t; j < x->ntodo; j += x->ntasks)
        if (!x->blocks[x->todo[j]].data)
            x->failed = 1;
    free(split);
    free(pred);
    libdeflate_free_compressor(z);
}

static unsigned char *put32(unsigned char *q, uint32_t v)
{
    memcpy(q, &v, 4);
    return q + 4;
}

/* An attribute's name, type and size; the value follows. */
static unsigned char *put_attr(unsigned char *q, const char *name, const char *type,
                               uint32_t size)
{
    size_t a = strlen(name) + 1, t = strlen(type) + 1;
    memcpy(q, name, a);
    memcpy(q + a, type, t);
    return put32(q + a + t, size);
}

/* The magic, version and header of im (OUT: h, at most 512 bytes);
 * returns its size. */
static size_t header(const img *im, unsigned char *h)
{
    static const char *const names[4] = {"A", "B", "G", "R"};
    int nch = im->channels, first = nch == 3 ? 1 : 0;
    uint32_t box[4] = {0, 0, (uint32_t)(im->width - 1), (uint32_t)(im->height - 1)};
    float one = 1.0f, zero2[2] = {0.0f, 0.0f};
    unsigned char *q = h;

    q = put32(q, 20000630u); /* 76 2f 31 01 */
    q = put32(q, 2u);
    q = put_attr(q, "channels", "chlist", (uint32_t)(nch * 18 + 1));
    for (int c = first; c < 4; c++) {
        *q++ = (unsigned char)names[c][0];
        *q++ = 0;
        q = put32(q, EXR_FLOAT);
        memset(q, 0, 4); /* pLinear, reserved */
        q = put32(put32(q + 4, 1u), 1u); /* x and y sampling */
    }
    *q++ = 0;
    q = put_attr(q, "compression", "compression", 1);
    *q++ = EXR_ZIP;
    q = put_attr(q, "dataWindow", "box2i", 16);
    memcpy(q, box, 16);
    q += 16;
    q = put_attr(q, "displayWindow", "box2i", 16);
    memcpy(q, box, 16);
    q += 16;
    q = put_attr(q, "lineOrder", "lineOrder", 1);
    *q++ = 0; /* INCREASING_Y */
    q = put_attr(q, "pixelAspectRatio", "float", 4);
    memcpy(q, &one, 4);
    q += 4;
    q = put_attr(q, "screenWindowCenter", "v2f", 8);
    memcpy(q, zero2, 8);
    q += 8;
    q = put_attr(q, "screenWindowWidth", "float", 4);
    memcpy(q, &one, 4);
    q += 4;
    *q++ = 0;
    return (size_t)(q - h);
}

/* Where block b of a file of NBLOCKS blocks lies in prev: at prev[*at ..
 * *at + 8 + *size) (its line and size, then its data), when the offset
 * table (after a header of HSIZE bytes) points at a block of line 16 b
 * whose data lies within the file and is no larger than the block's raw
 * bytes; -1 when it does not. */
static int prev_block(const img *im, const unsigned char *prev, size_t prev_len, size_t hsize,
                      int nblocks, int b, size_t *at, size_t *size)
{
    size_t table = hsize + 8 * (size_t)nblocks, raw;
    uint64_t off;
    uint32_t line, sz;
    int y1 = (b + 1) * EXR_LINES < im->height ? (b + 1) * EXR_LINES : im->height;

    if (prev_len < table)
        return -1;
    memcpy(&off, prev + hsize + 8 * (size_t)b, 8);
    if (off < table || off > prev_len || prev_len - off < 8)
        return -1;
    memcpy(&line, prev + off, 4);
    memcpy(&sz, prev + off + 4, 4);
    raw = (size_t)(y1 - b * EXR_LINES) * im->width * im->channels * 4;
    if (line != (uint32_t)(b * EXR_LINES) || sz == 0 || sz > raw || sz > prev_len - off - 8)
        return -1;
    *at = (size_t)off;
    *size = sz;
    return 0;
}

/* The file of x->im from its blocks: those in x->blocks, and where
 * x->blocks[b].data is NULL, block b's bytes in prev at from[b]. */
static int assemble(const encode_ctx *x, const unsigned char *prev, const size_t *from,
                    void **out, size_t *len, glint_err *err)
{
    unsigned char h[512], *file, *q;
    size_t hsize = header(x->im, h), total = hsize + 8 * (size_t)x->nblocks;

    for (int b = 0; b < x->nblocks; b++) {
        uint32_t sz;
        if (x->blocks[b].data)
            sz = (uint32_t)x->blocks[b].size;
        else
            memcpy(&sz, prev + from[b] + 4, 4);
        total += 8 + (size_t)sz;
    }
    if (!(file = malloc(total)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory encoding an OpenEXR image");
    memcpy(file, h, hsize);
    q = file + hsize + 8 * (size_t)x->nblocks;
    for (int b = 0; b < x->nblocks; b++) {
        uint64_t at = (uint64_t)(q - file);
        memcpy(file + hsize + 8 * (size_t)b, &at, 8);
        if (x->blocks[b].data) {
            q = put32(q, (uint32_t)(b * EXR_LINES));
            q = put32(q, (uint32_t)x->blocks[b].size);
            memcpy(q, x->blocks[b].data, x->blocks[b].size);
            q += x->blocks[b].size;
        } else {
            uint32_t sz;
            memcpy(&sz, prev + from[b] + 4, 4);
            memcpy(q, prev + from[b], 8 + (size_t)sz);
            q += 8 + (size_t)sz;
        }
    }
    *out = file;
    *len = total;
    return 0;
}

int img_exr_encode_reusing(const img *im, const void *prev, size_t prev_len, int y0, int y1,
                           void **out, size_t *len, int *reused, glint_err *err)
{
    encode_ctx x;
    unsigned char h[512];
    size_t hsize, *from = NULL;
    int *todo = NULL, rc = 0, nreused = 0;

    *out = NULL;
    *len = 0;
    if (reused)
        *reused = 0;
    if (!im || !im->px || (im->channels != 3 && im->channels != 4) || im->width < 1 ||
        im->height < 1)
        return glint_err_set(err, GLINT_EINVAL, "img_exr_encode: an RGB or RGBA image expected");
    memset(&x, 0, sizeof x);
    x.im = im;
    x.nblocks = (im->height + EXR_LINES - 1) / EXR_LINES;
    x.blocks = calloc((size_t)x.nblocks, sizeof *x.blocks);
    todo = malloc((size_t)x.nblocks * sizeof *todo);
    from = malloc((size_t)x.nblocks * sizeof *from);
    if (!x.blocks || !todo || !from) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory encoding an OpenEXR image");
        goto done;
    }
    hsize = header(im, h);
    /* prev's blocks serve when all of its table is well formed and its
     * blocks follow one another from the table's end to the file's, as
     * img_exr_encode lays them out */
    if (prev && (prev_len < hsize || memcmp(prev, h, hsize) != 0))
        prev = NULL;
    {
        size_t next = hsize + 8 * (size_t)x.nblocks;
        for (int b = 0; prev && b < x.nblocks; b++) {
            size_t size;
            if (prev_block(im, prev, prev_len, hsize, x.nblocks, b, &from[b], &size) ||
                from[b] != next)
                prev = NULL;
            else
                next = from[b] + 8 + size;
        }
        if (next != prev_len)
            prev = NULL;
    }
    /* the blocks of lines y0..y1 encoded, the others prev's */
    for (int b = 0; b < x.nblocks; b++) {
        int first = b * EXR_LINES, last = first + EXR_LINES - 1;
        if (prev && (y1 < y0 || last < y0 || first > y1))
            nreused++;
        else
            todo[x.ntodo++] = b;
    }
    x.todo = todo;
    /* a task per thread, each with its compressor (level 1: about 300 KB) */
    x.ntasks = par_worth((size_t)x.ntodo * EXR_LINES * im->width * im->channels) ? par_threads()
                                                                                  : 1;
    if (x.ntasks > x.ntodo)
        x.ntasks = x.ntodo;
    if (x.ntasks > 1)
        par_run(x.ntasks, encode_task, &x);
    else if (x.ntodo > 0)
        encode_task(&x, 0);
    if (x.failed) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory encoding an OpenEXR image");
        goto done;
    }
    if (!(rc = assemble(&x, prev, from, out, len, err)) && reused)
        *reused = nreused;
done:
    for (int b = 0; x.blocks && b < x.nblocks; b++)
        free(x.blocks[b].data);
    free(x.blocks);
    free(todo);
    free(from);
    return rc;
}

int img_exr_encode(const img *im, void **out, size_t *len, glint_err *err)
{
    return img_exr_encode_reusing(im, NULL, 0, 0, -1, out, len, NULL, err);
}
