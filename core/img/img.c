/* img.c: the C side of img.h.  Allocation, validation, finiteness checks,
 * format detection (by content for reading, by extension for writing) and
 * atomic file replacement live here; the pixels go through the
 * OpenImageIO shim in img_oiio.cpp (img_oiio.h). */
#include "img.h"
#include "img_exr.h"
#include "fsio.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "internal/img_oiio.h"
#include "internal/img_png.h"

/* Longest channel name img_write_exr_named accepts (OpenEXR's own limit). */
#define IMG_MAX_NAME_LEN 255

int img_alloc(img *im, int width, int height, int channels, glint_err *err)
{
    if (!im)
        return glint_err_set(err, GLINT_EINVAL, "img_alloc: NULL image");
    memset(im, 0, sizeof *im);
    if (width < 1 || height < 1 || width > IMG_MAX_DIM || height > IMG_MAX_DIM)
        return glint_err_set(err, GLINT_ERANGE, "image size %dx%d outside 1..%d",
                             width, height, IMG_MAX_DIM);
    if (channels < 1 || channels > 4)
        return glint_err_set(err, GLINT_ERANGE, "image with %d channels, supported 1..4",
                             channels);
    im->px = calloc((size_t)width * (size_t)height * (size_t)channels, sizeof(float));
    if (!im->px)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%dx%d image",
                             width, height, channels);
    im->width = width;
    im->height = height;
    im->channels = channels;
    return 0;
}

void img_free(img *im)
{
    if (!im)
        return;
    free(im->px);
    memset(im, 0, sizeof *im);
}

void img_named_free(img_named *im)
{
    if (!im)
        return;
    if (im->names) {
        for (int c = 0; c < im->channels; c++)
            free(im->names[c]);
        free(im->names);
    }
    free(im->px);
    memset(im, 0, sizeof *im);
}

/* An image a caller hands in: sizes in range and pixels present. */
static int img_validate(const img *im, glint_err *err)
{
    if (!im || !im->px)
        return glint_err_set(err, GLINT_EINVAL, "image is NULL or has no pixels");
    if (im->width < 1 || im->height < 1 || im->width > IMG_MAX_DIM ||
        im->height > IMG_MAX_DIM)
        return glint_err_set(err, GLINT_ERANGE, "image size %dx%d outside 1..%d",
                             im->width, im->height, IMG_MAX_DIM);
    if (im->channels < 1 || im->channels > 4)
        return glint_err_set(err, GLINT_ERANGE, "image with %d channels, supported 1..4",
                             im->channels);
    return 0;
}

/* First non-finite value of an interleaved float array, reported with its
 * pixel position and channel (named when names are given). */
static int img_check_finite_array(const float *px, int width, int height, int nch,
                                  const char *const *names, const char *what,
                                  glint_err *err)
{
    static const char *const rgba[] = {"R", "G", "B", "A"};
    size_t n = (size_t)width * (size_t)height * (size_t)nch;
    int bad = 0;

    /* a reduction without an early exit (it vectorizes: 0.3 ms -> a few
     * us for a 256x256 RGB upload here), then the first fault, named */
#pragma omp simd reduction(| : bad)
    for (size_t i = 0; i < n; i++)
        bad |= !(fabsf(px[i]) <= FLT_MAX);
    if (!bad)
        return 0;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(px[i])) {
            size_t pixel = i / (size_t)nch;
            int c = (int)(i % (size_t)nch);
            const char *cname = names ? names[c] : (nch <= 4 ? rgba[c] : "?");
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "%s: non-finite value %g at pixel (x %d, y %d), "
                                 "channel %d (%s)",
                                 what, (double)px[i], (int)(pixel % (size_t)width),
                                 (int)(pixel / (size_t)width), c, cname);
        }
    }
    return 0;
}

int img_check_finite(const img *im, glint_err *err)
{
    int rc = img_validate(im, err);
    if (rc)
        return rc;
    return img_check_finite_array(im->px, im->width, im->height, im->channels, NULL,
                                  "image", err);
}

int img_fill_holes(img *im, glint_err *err)
{
    int rc = img_validate(im, err), any = 0;
    size_t np;
    if (rc)
        return rc;
    if (im->channels < 2)
        return glint_err_set(err, GLINT_EINVAL, "fill holes: the image needs a coverage channel");
    np = (size_t)im->width * im->height;
    for (size_t i = 0; i < np && !any; i++)
        any = im->px[i * im->channels + im->channels - 1] > 0.0f;
    if (!any)
        return glint_err_set(err, GLINT_EINVAL, "fill holes: no pixel is covered");
    return img_oiio_fill_holes(im->px, im->width, im->height, im->channels, err);
}

/* ---- reading ----------------------------------------------------------- */

/* OpenImageIO format name from the first bytes, or NULL. */
static const char *img_sniff(const unsigned char *b, size_t n)
{
    static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    static const unsigned char exr[4] = {0x76, 0x2f, 0x31, 0x01};

    if (n >= 8 && memcmp(b, png, 8) == 0)
        return "png";
    if (n >= 4 && memcmp(b, exr, 4) == 0)
        return "openexr";
    if (n >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff)
        return "jpeg";
    if (n >= 2 && b[0] == '#' && b[1] == '?')
        return "hdr";
    return NULL;
}

static int img_unrecognized(const char *what, const unsigned char *b, size_t n,
                            glint_err *err)
{
    char hex[3 * 8 + 1] = "";
    for (size_t i = 0; i < n && i < 8; i++)
        snprintf(hex + 3 * i, sizeof hex - 3 * i, "%02x ", b[i]);
    if (n)
        hex[strlen(hex) - 1] = '\0';
    return glint_err_set(err, GLINT_EFORMAT,
                         "%s: not a PNG, JPEG, OpenEXR or Radiance HDR image "
                         "(first bytes %s)",
                         what, n ? hex : "none");
}

/* ---- headers (img_header) ---------------------------------------------- */

/* A read's check of the header: the caller's function, and the header once
 * a decoder (or png_header) has read it. */
typedef struct img_gate {
    img_header_check check;
    void *cls;
    int seen;
    img_header hd;
} img_gate;

/* The most memory a decode of fmt takes (img_header): nch channels of
 * w x h, each stored sample sample_bytes, as_float when every channel is
 * stored as float.  SIZE_MAX beyond IMG_MAX_DIM (no decoder takes it). */
static size_t img_decode_bound(const char *fmt, int w, int h, int nch, int sample_bytes,
                               int as_float)
{
    size_t n, per;
    if (w < 1 || h < 1 || nch < 1 || w > IMG_MAX_DIM || h > IMG_MAX_DIM ||
        nch > IMG_MAX_NAMED_CHANNELS)
        return SIZE_MAX;
    n = (size_t)w * (size_t)h * (size_t)nch;
    if (strcmp(fmt, "png") == 0) /* OpenImageIO's whole image as stored, a copy, floats */
        per = sample_bytes > 1 ? 8 : 6;
    else if (strcmp(fmt, "openexr") == 0) /* floats, and the stored samples converted */
        per = 4 + (as_float ? 0 : (size_t)(sample_bytes < 4 ? sample_bytes : 4));
    else /* JPEG: a progressive file's coefficients; HDR: its converted lines */
        per = 8;
    return n * per + IMG_DECODE_FIXED_BYTES;
}

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* A PNG's header from its IHDR and the chunks before IDAT, as OpenImageIO's
 * reader turns it (a palette into RGB, a tRNS chunk into an alpha, depths
 * under 8 into 8).  0, or -1 when the bytes do not begin as a PNG's do: the
 * decoder then says what is wrong. */
static int png_header(const unsigned char *b, size_t n, img_header *hd)
{
    static const int nch_of[7] = {1, 0, 3, 3, 2, 0, 4};
    uint32_t w, h;
    int depth, ctype, nch, trns = 0;
    size_t at;

    if (n < 33 || be32(b + 8) != 13 || memcmp(b + 12, "IHDR", 4) != 0)
        return -1;
    w = be32(b + 16);
    h = be32(b + 20);
    depth = b[24];
    ctype = b[25];
    if (w < 1 || h < 1 || w > INT32_MAX || h > INT32_MAX || ctype > 6 || !nch_of[ctype] ||
        (depth != 1 && depth != 2 && depth != 4 && depth != 8 && depth != 16))
        return -1;
    nch = nch_of[ctype];
    for (at = 33; n - at >= 12;) { /* length, type, data, CRC */
        uint32_t clen = be32(b + at);
        if (memcmp(b + at + 4, "IDAT", 4) == 0 || clen > n - at - 12)
            break;
        trns |= memcmp(b + at + 4, "tRNS", 4) == 0;
        at += 12 + (size_t)clen;
    }
    if (trns && (ctype == 0 || ctype == 2 || ctype == 3))
        nch++;
    hd->format = "png";
    hd->width = (int)w;
    hd->height = (int)h;
    hd->channels = nch;
    hd->decode_bytes = img_decode_bound("png", hd->width, hd->height, nch, depth == 16 ? 2 : 1,
                                        0);
    return 0;
}

/* The header as read; the caller's check sees it once. */
static int gate_seen(img_gate *g, glint_err *err)
{
    g->seen = 1;
    return g->check ? g->check(g->cls, &g->hd, err) : 0;
}

/* img_oiio_header_fn: the header OpenImageIO read, checked once; when
 * png_header read it first, what OpenImageIO found must agree. */
static int gate_oiio(void *cls, int w, int h, int nch, int sample_bytes, int as_float,
                     glint_err *err)
{
    img_gate *g = cls;
    if (g->seen) {
        if (w != g->hd.width || h != g->hd.height || nch > g->hd.channels)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "the decoder found a %dx%d image of %d channels where the "
                                 "header says %dx%d, %d channels",
                                 w, h, nch, g->hd.width, g->hd.height, g->hd.channels);
        return 0;
    }
    g->hd.width = w;
    g->hd.height = h;
    g->hd.channels = nch;
    g->hd.decode_bytes = img_decode_bound(g->hd.format, w, h, nch, sample_bytes, as_float);
    return gate_seen(g, err);
}

/* Decode a file (path != NULL) or a buffer, then check finiteness unless
 * keep_nonfinite.  gate (may be NULL): the header's check, before any pixel.
 * (OUT: *pix, zeroed first; freed on failure.) */
static int img_read_common(const char *path, const void *data, size_t len, int max_dim,
                           int max_channels, int want_names, int keep_nonfinite,
                           img_gate *gate, img_oiio_pixels *pix, glint_err *err)
{
    unsigned char head[16];
    size_t nhead;
    const char *fmt;
    const char *what = path ? path : "image in memory";
    FILE *fp = NULL;
    struct stat st;
    int rc;

    memset(pix, 0, sizeof *pix);
    if (path) {
        fp = fopen(path, "rb");
        if (!fp) {
            int e = errno;
            return glint_err_set(err, e == ENOENT ? GLINT_ENOTFOUND : GLINT_EIO,
                                 "%s: cannot open: %s", path, strerror(e));
        }
        if (fstat(fileno(fp), &st) != 0) {
            rc = glint_err_set(err, GLINT_EIO, "%s: cannot stat: %s", path,
                               strerror(errno));
            goto fail_file;
        }
        if (!S_ISREG(st.st_mode)) {
            rc = glint_err_set(err, GLINT_EIO, "%s: not a regular file", path);
            goto fail_file;
        }
        nhead = fread(head, 1, sizeof head, fp);
        if (nhead == 0 && ferror(fp)) {
            rc = glint_err_set(err, GLINT_EIO, "%s: read error: %s", path,
                               strerror(errno));
            goto fail_file;
        }
    } else {
        if (!data)
            return glint_err_set(err, GLINT_EINVAL, "image data is NULL");
        nhead = len < sizeof head ? len : sizeof head;
        memcpy(head, data, nhead);
    }
    if (nhead == 0) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: empty (0 bytes)", what);
        goto fail_file;
    }
    fmt = img_sniff(head, nhead);
    if (!fmt) {
        rc = img_unrecognized(what, head, nhead, err);
        goto fail_file;
    }

    /* the header first where the caller checks it: a PNG's here, the
     * others' as OpenImageIO opens them */
    if (gate) {
        gate->hd.format = fmt;
        if (!fp && strcmp(fmt, "png") == 0 && png_header(data, len, &gate->hd) == 0 &&
            (rc = gate_seen(gate, err)))
            goto fail_file;
    }
    /* the uploads' common PNGs directly, the rest (and every failure)
     * through OpenImageIO (img_png.h) */
    if (fp || want_names || strcmp(fmt, "png") != 0 ||
        img_png_read(data, len, max_dim, max_channels, pix) != 0)
        rc = img_oiio_read(fmt, fp, data, len, what, max_dim, max_channels, want_names,
                           gate ? gate_oiio : NULL, gate, pix, err);
    else
        rc = 0;
    if (fp)
        fclose(fp);
    fp = NULL;
    if (rc)
        return rc;
    if (gate && (pix->width != gate->hd.width || pix->height != gate->hd.height ||
                 pix->channels > gate->hd.channels)) {
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: decoded as %dx%d, %d channels, where the header says %dx%d, "
                           "%d channels",
                           what, pix->width, pix->height, pix->channels, gate->hd.width,
                           gate->hd.height, gate->hd.channels);
        goto fail_pixels;
    }
    if (keep_nonfinite)
        return 0;

    rc = img_check_finite_array(pix->px, pix->width, pix->height, pix->channels,
                                (const char *const *)pix->names, what, err);
    if (rc)
        goto fail_pixels;
    return 0;

fail_pixels:
    img_oiio_pixels_free(pix);
fail_file:
    if (fp)
        fclose(fp);
    return rc;
}

static void img_take(img *out, img_oiio_pixels *pix)
{
    out->width = pix->width;
    out->height = pix->height;
    out->channels = pix->channels;
    out->px = pix->px;
    pix->px = NULL;
    img_oiio_pixels_free(pix);
}

static int img_read_file(const char *path, int keep_nonfinite, img *out, glint_err *err)
{
    img_oiio_pixels pix;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "img_read: NULL output");
    memset(out, 0, sizeof *out);
    if (!path || !*path)
        return glint_err_set(err, GLINT_EINVAL, "img_read: empty path");
    rc = img_read_common(path, NULL, 0, IMG_MAX_DIM, 4, 0, keep_nonfinite, NULL, &pix, err);
    if (rc)
        return rc;
    img_take(out, &pix);
    return 0;
}

int img_read(const char *path, img *out, glint_err *err)
{
    return img_read_file(path, 0, out, err);
}

int img_read_keep_nonfinite(const char *path, img *out, glint_err *err)
{
    return img_read_file(path, 1, out, err);
}

int img_read_mem(const void *data, size_t len, img *out, glint_err *err)
{
    return img_read_mem_max(data, len, IMG_MAX_DIM, out, err);
}

/* The checks of an in-memory read (`what` names the caller); *max_dim
 * brought into 1..IMG_MAX_DIM.  The output was zeroed by the caller. */
static int mem_read_args(const char *what, const void *data, size_t len, int *max_dim,
                         glint_err *err)
{
    if (!data && len)
        return glint_err_set(err, GLINT_EINVAL, "%s: NULL data", what);
    if (len == 0)
        return glint_err_set(err, GLINT_EFORMAT, "image in memory: empty (0 bytes)");
    if (*max_dim < 1 || *max_dim > IMG_MAX_DIM)
        *max_dim = IMG_MAX_DIM;
    return 0;
}

int img_read_mem_max(const void *data, size_t len, int max_dim, img *out, glint_err *err)
{
    return img_read_mem_checked(data, len, max_dim, NULL, NULL, out, err);
}

int img_read_named(const char *path, img_named *out, glint_err *err)
{
    img_oiio_pixels pix;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "img_read_named: NULL output");
    memset(out, 0, sizeof *out);
    if (!path || !*path)
        return glint_err_set(err, GLINT_EINVAL, "img_read_named: empty path");
    rc = img_read_common(path, NULL, 0, IMG_MAX_DIM, IMG_MAX_NAMED_CHANNELS, 1, 0, NULL, &pix,
                         err);
    if (rc)
        return rc;
    out->width = pix.width;
    out->height = pix.height;
    out->channels = pix.channels;
    out->names = pix.names;
    out->px = pix.px;
    return 0;
}

int img_read_named_mem(const void *data, size_t len, int max_dim, int max_channels,
                       img_named *out, glint_err *err)
{
    return img_read_named_mem_checked(data, len, max_dim, max_channels, NULL, NULL, out, err);
}

static int img_read_mem_gated(const void *data, size_t len, int max_dim, img_header_check check,
                              void *cls, int keep_nonfinite, img *out, glint_err *err)
{
    img_gate gate = {check, cls, 0, {NULL, 0, 0, 0, 0}};
    img_oiio_pixels pix;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "img_read_mem: NULL output");
    memset(out, 0, sizeof *out);
    if ((rc = mem_read_args("img_read_mem", data, len, &max_dim, err)))
        return rc;
    rc = img_read_common(NULL, data, len, max_dim, 4, 0, keep_nonfinite, check ? &gate : NULL,
                         &pix, err);
    if (rc)
        return rc;
    img_take(out, &pix);
    return 0;
}

int img_read_mem_checked(const void *data, size_t len, int max_dim, img_header_check check,
                         void *cls, img *out, glint_err *err)
{
    return img_read_mem_gated(data, len, max_dim, check, cls, 0, out, err);
}

int img_read_mem_keep_nonfinite(const void *data, size_t len, int max_dim,
                                img_header_check check, void *cls, img *out, glint_err *err)
{
    return img_read_mem_gated(data, len, max_dim, check, cls, 1, out, err);
}

int img_read_named_mem_checked(const void *data, size_t len, int max_dim, int max_channels,
                               img_header_check check, void *cls, img_named *out,
                               glint_err *err)
{
    img_gate gate = {check, cls, 0, {NULL, 0, 0, 0, 0}};
    img_oiio_pixels pix;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "img_read_named_mem: NULL output");
    memset(out, 0, sizeof *out);
    if ((rc = mem_read_args("img_read_named_mem", data, len, &max_dim, err)))
        return rc;
    if (max_channels < 1 || max_channels > IMG_MAX_NAMED_CHANNELS)
        max_channels = IMG_MAX_NAMED_CHANNELS;
    rc = img_read_common(NULL, data, len, max_dim, max_channels, 1, 0, check ? &gate : NULL, &pix,
                         err);
    if (rc)
        return rc;
    out->width = pix.width;
    out->height = pix.height;
    out->channels = pix.channels;
    out->names = pix.names;
    out->px = pix.px;
    return 0;
}

/* ---- writing ----------------------------------------------------------- */

typedef struct img_fmt {
    const char *key;  /* extension or img_write_mem format name */
    const char *oiio; /* OpenImageIO format name */
    int u8;           /* 1: 8-bit quantized, 0: float */
} img_fmt;

static const img_fmt img_formats[] = {
    {"png", "png", 1},     {"exr", "openexr", 0}, {"hdr", "hdr", 0},
    {"jpg", "jpeg", 1},    {"jpeg", "jpeg", 1},
};

static const img_fmt *img_fmt_find(const char *key)
{
    for (size_t i = 0; i < sizeof img_formats / sizeof img_formats[0]; i++)
        if (strcasecmp(key, img_formats[i].key) == 0)
            return &img_formats[i];
    return NULL;
}

/* Channel counts a format can store without dropping or inventing data. */
static int img_fmt_check_channels(const img_fmt *f, int nch, const char *what,
                                  glint_err *err)
{
    if (strcmp(f->oiio, "hdr") == 0 && nch != 3)
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "%s: Radiance HDR stores 3 channels, image has %d", what,
                             nch);
    if (strcmp(f->oiio, "jpeg") == 0 && nch != 1 && nch != 3)
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "%s: JPEG stores 1 or 3 channels, image has %d", what, nch);
    return 0;
}

/* 8-bit copy of an image: clamp to [0,1], round x*255 + 0.5, no transfer
 * curve.  Returns a malloc'ed buffer or NULL. */
static uint8_t *img_quantize(const img *im)
{
    size_t n = (size_t)im->width * (size_t)im->height * (size_t)im->channels;
    uint8_t *q = malloc(n ? n : 1);
    if (!q)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        double x = im->px[i];
        x = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
        q[i] = (uint8_t)(x * 255.0 + 0.5);
    }
    return q;
}

/* Float copy with negatives set to 0, for RGBE, which has no sign (OpenImageIO
 * 2.4 would wrap a negative component to a large positive one).  Returns
 * a malloc'ed buffer or NULL. */
static float *img_clamp_negative(const img *im)
{
    size_t n = (size_t)im->width * (size_t)im->height * (size_t)im->channels;
    float *q = malloc(n * sizeof(float));
    if (!q)
        return NULL;
    for (size_t i = 0; i < n; i++)
        q[i] = im->px[i] > 0.0f ? im->px[i] : 0.0f;
    return q;
}

/* Encode into a temporary file next to `path` and commit it over `path`
 * (fsio.h): on any failure `path` is untouched. */
static int img_write_atomic(const char *path, const char *oiio_fmt, int width,
                            int height, int nch, const char *const *names, int u8,
                            const void *data, glint_err *err)
{
    fsio_atomic a;
    int rc = fsio_atomic_open(&a, path, err);

    if (rc)
        return rc;
    rc = img_oiio_write(oiio_fmt, a.fp, NULL, NULL, path, width, height, nch, names, u8,
                        data, err);
    if (rc) {
        fsio_atomic_abort(&a);
        return rc;
    }
    return fsio_atomic_commit(&a, err);
}

/* Validate, check finiteness and channel support, quantize if 8-bit, then
 * write to a file (path) or to memory (mem/mem_len). */
static int img_encode(const img_fmt *f, const img *im, const char *path, void **mem,
                      size_t *mem_len, glint_err *err)
{
    const char *what = path ? path : "encoding to memory";
    const void *pixels;
    void *q = NULL;
    int rc;

    rc = img_validate(im, err);
    if (rc)
        return rc;
    rc = img_fmt_check_channels(f, im->channels, what, err);
    if (rc)
        return rc;
    rc = img_check_finite_array(im->px, im->width, im->height, im->channels, NULL,
                                what, err);
    if (rc) {
        if (err)
            glint_err_prefix(err, "refusing to write");
        return rc;
    }
    if (f->u8)
        q = img_quantize(im);
    else if (strcmp(f->oiio, "hdr") == 0)
        q = img_clamp_negative(im);
    if ((f->u8 || strcmp(f->oiio, "hdr") == 0) && !q)
        return glint_err_set(err, GLINT_ENOMEM, "%s: out of memory", what);
    pixels = q ? q : (const void *)im->px;
    if (!path && !q && strcmp(f->oiio, "openexr") == 0 && (im->channels == 3 || im->channels == 4))
        rc = img_exr_encode(im, mem, mem_len, err); /* a stroke's painting, the API's EXRs */
    else if (path)
        rc = img_write_atomic(path, f->oiio, im->width, im->height, im->channels, NULL,
                              f->u8, pixels, err);
    else
        rc = img_oiio_write(f->oiio, NULL, mem, mem_len, "<memory>", im->width,
                            im->height, im->channels, NULL, f->u8, pixels, err);
    free(q);
    return rc;
}

int img_write_png16(const char *path, const img *im, glint_err *err)
{
    size_t n;
    uint16_t *q;
    int rc = img_validate(im, err);
    if (rc)
        return rc;
    if ((rc = img_check_finite_array(im->px, im->width, im->height, im->channels, NULL, path,
                                     err)))
        return glint_err_prefix(err, "refusing to write");
    n = (size_t)im->width * im->height * im->channels;
    if (!(q = malloc(n * sizeof *q)))
        return glint_err_set(err, GLINT_ENOMEM, "%s: out of memory", path);
    for (size_t i = 0; i < n; i++) {
        double x = im->px[i];
        x = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
        q[i] = (uint16_t)(x * 65535.0 + 0.5);
    }
    rc = img_write_atomic(path, "png", im->width, im->height, im->channels, NULL, 2, q, err);
    free(q);
    return rc;
}

int img_write_pair(const char *dir, const char *stem, const img *lin, const img *png,
                   glint_err *err)
{
    char name[256], path[4096];
    int rc;
    snprintf(name, sizeof name, "%s.exr", stem);
    if ((rc = fsio_join(path, sizeof path, dir, name, err)) || (rc = img_write(path, lin, err)))
        return rc;
    snprintf(name, sizeof name, "%s.png", stem);
    if ((rc = fsio_join(path, sizeof path, dir, name, err)) || (rc = img_write(path, png, err)))
        return rc;
    return 0;
}

int img_write(const char *path, const img *im, glint_err *err)
{
    const char *base, *dot;
    const img_fmt *f;

    if (!path || !*path)
        return glint_err_set(err, GLINT_EINVAL, "img_write: empty path");
    base = strrchr(path, '/');
    base = base ? base + 1 : path;
    dot = strrchr(base, '.');
    f = dot ? img_fmt_find(dot + 1) : NULL;
    if (!f)
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "%s: unsupported extension '%s' (use .png, .exr, .hdr, "
                             ".jpg)",
                             path, dot ? dot : "");
    return img_encode(f, im, path, NULL, NULL, err);
}

int img_write_mem(const char *format, const img *im, void **out_data, size_t *out_len,
                  glint_err *err)
{
    const img_fmt *f;

    if (!out_data || !out_len)
        return glint_err_set(err, GLINT_EINVAL, "img_write_mem: NULL output");
    *out_data = NULL;
    *out_len = 0;
    if (!format)
        return glint_err_set(err, GLINT_EINVAL, "img_write_mem: NULL format");
    f = img_fmt_find(format);
    if (!f)
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "unsupported image format '%s' (use png, exr, hdr, jpg)",
                             format);
    return img_encode(f, im, NULL, out_data, out_len, err);
}

int img_write_exr_mem_reusing(const img *im, const void *prev, size_t prev_len, int y0, int y1,
                              void **out_data, size_t *out_len, int *reused, glint_err *err)
{
    int rc;
    if (reused)
        *reused = 0;
    if (!out_data || !out_len)
        return glint_err_set(err, GLINT_EINVAL, "img_write_exr_mem_reusing: NULL output");
    *out_data = NULL;
    *out_len = 0;
    if ((rc = img_validate(im, err)))
        return rc;
    if (im->channels != 3 && im->channels != 4)
        return glint_err_set(err, GLINT_EINVAL,
                             "encoding to memory: %d channels, 3 or 4 expected", im->channels);
    if ((rc = img_check_finite_array(im->px, im->width, im->height, im->channels, NULL,
                                     "encoding to memory", err))) {
        if (err)
            glint_err_prefix(err, "refusing to write");
        return rc;
    }
    return img_exr_encode_reusing(im, prev, prev_len, y0, y1, out_data, out_len, reused, err);
}

/* Checks of img_write_exr_named(_mem); `what` names the output. */
static int exr_named_check(const char *what, int width, int height, int nch,
                           const char *const *names, const float *data, glint_err *err)
{
    if (!names || !data)
        return glint_err_set(err, GLINT_EINVAL, "%s: NULL names or data", what);
    if (width < 1 || height < 1 || width > IMG_MAX_DIM || height > IMG_MAX_DIM)
        return glint_err_set(err, GLINT_ERANGE, "%s: image size %dx%d outside 1..%d",
                             what, width, height, IMG_MAX_DIM);
    if (nch < 1 || nch > IMG_MAX_NAMED_CHANNELS)
        return glint_err_set(err, GLINT_ERANGE, "%s: %d channels, supported 1..%d",
                             what, nch, IMG_MAX_NAMED_CHANNELS);
    for (int c = 0; c < nch; c++) {
        size_t len = names[c] ? strlen(names[c]) : 0;
        if (len == 0 || len > IMG_MAX_NAME_LEN)
            return glint_err_set(err, GLINT_EINVAL,
                                 "%s: channel %d name is empty, NULL or longer than %d",
                                 what, c, IMG_MAX_NAME_LEN);
        for (int d = 0; d < c; d++)
            if (strcmp(names[c], names[d]) == 0)
                return glint_err_set(err, GLINT_EINVAL,
                                     "%s: channel name '%s' used twice (%d and %d)", what,
                                     names[c], d, c);
    }
    return img_check_finite_array(data, width, height, nch, names, what, err);
}

int img_write_exr_named(const char *path, int width, int height, int nch,
                        const char *const *names, const float *data, glint_err *err)
{
    int rc;
    if (!path || !*path)
        return glint_err_set(err, GLINT_EINVAL, "img_write_exr_named: NULL path");
    if ((rc = exr_named_check(path, width, height, nch, names, data, err)))
        return rc;
    return img_write_atomic(path, "openexr", width, height, nch, names, 0, data, err);
}

int img_write_exr_named_mem(int width, int height, int nch, const char *const *names,
                            const float *data, void **out_data, size_t *out_len,
                            glint_err *err)
{
    int rc;
    *out_data = NULL;
    *out_len = 0;
    if ((rc = exr_named_check("encoding to memory", width, height, nch, names, data, err)))
        return rc;
    return img_oiio_write("openexr", NULL, out_data, out_len, "encoding to memory", width,
                          height, nch, names, 0, data, err);
}

int img_to_rgb(img *im, glint_err *err)
{
    img out;
    size_t n = (size_t)im->width * (size_t)im->height;
    int c = im->channels, rc;
    if (c == 3)
        return 0;
    if (c < 1 || c > 4)
        return glint_err_set(err, GLINT_EINVAL, "an image of %d channels has no RGB", c);
    if ((rc = img_alloc(&out, im->width, im->height, 3, err)))
        return rc;
    for (size_t p = 0; p < n; p++)
        for (int ch = 0; ch < 3; ch++)
            out.px[3 * p + (size_t)ch] = im->px[(size_t)c * p + (size_t)(c >= 3 ? ch : 0)];
    img_free(im);
    *im = out;
    return 0;
}

int img_raster_scale(int pw, int ph, int w, int h)
{
    if (w < 1 || h < 1 || pw < w || pw % w || ph % h || pw / w != ph / h)
        return 0;
    return pw / w;
}

int img_to_raster(const img *in, int w, int h, img *out, glint_err *err)
{
    int rc, s, C;

    memset(out, 0, sizeof *out);
    if ((rc = img_validate(in, err)))
        return rc;
    if (!(s = img_raster_scale(in->width, in->height, w, h)))
        return glint_err_set(err, GLINT_EINVAL,
                             "the painting is %dx%d: expected the raster's %dx%d or a whole "
                             "multiple of it (2x: %dx%d)",
                             in->width, in->height, w, h, 2 * w, 2 * h);
    C = in->channels;
    if ((rc = img_alloc(out, w, h, C, err)))
        return rc;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *o = out->px + ((size_t)y * w + x) * C;
            if (s % 2) { /* the centre pixel */
                const float *p =
                    in->px + ((size_t)(y * s + s / 2) * in->width + (size_t)(x * s + s / 2)) * C;
                memcpy(o, p, (size_t)C * sizeof *o);
                continue;
            }
            /* the four pixels around the centre: (x s + s/2 - 1 .. x s + s/2, same in y) */
            for (int c = 0; c < C; c++) {
                double acc = 0.0;
                for (int dy = 0; dy < 2; dy++)
                    for (int dx = 0; dx < 2; dx++)
                        acc += in->px[((size_t)(y * s + s / 2 - 1 + dy) * in->width +
                                       (size_t)(x * s + s / 2 - 1 + dx)) * C + (size_t)c];
                o[c] = (float)(0.25 * acc);
            }
        }
    return 0;
}
