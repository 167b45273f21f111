/* img_oiio.h: private interface between img.c and the OpenImageIO shim
 * (img_oiio.cpp).  Only img.c and tests include it.
 *
 * The shim is the one place that sees C++: every function here is
 * extern "C", catches every exception, and turns OpenImageIO failures into
 * glint codes whose message keeps OpenImageIO's own text.  It does no
 * format detection, extension parsing, finiteness checks or temp-file
 * handling: img.c does those and tells the shim which OpenImageIO format
 * ("png", "jpeg", "openexr", "hdr") to use. */
#ifndef GLINT_IMG_OIIO_H
#define GLINT_IMG_OIIO_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#include "err.h"

/* Decoded pixels.  px is malloc'ed (width x height x channels floats,
 * interleaved, row 0 at the top); names, when asked for, is a malloc'ed
 * array of `channels` malloc'ed strings.  Free with img_oiio_pixels_free
 * (accepts NULL and zeroed structs), or take ownership of px / names. */
typedef struct img_oiio_pixels {
    int width, height, channels;
    float *px;
    char **names;
} img_oiio_pixels;

/* Called by img_oiio_read once the header is read and found within
 * max_dim and max_channels, before any pixel memory is allocated: the
 * size, the channels, the bytes of one stored sample (the largest of the
 * channels': 1 for 8-bit data, 2 for half or 16-bit, 4 for float), and
 * as_float: 1 when every channel is stored as float (read without a
 * copy).  Returns 0 to decode, or a glint code with err set: img_oiio_read
 * then returns that code, having decoded nothing. */
typedef int (*img_oiio_header_fn)(void *cls, int width, int height, int channels,
                                  int sample_bytes, int as_float, glint_err *err);

/* Decode subimage 0, mip level 0 of an image in OpenImageIO format
 * `format`, from the open stream `fp` (read from its start; the caller
 * keeps and closes it) or, when fp is NULL, from the `len` bytes at `mem`.
 * `source` names the input in messages.  Sizes outside 1..max_dim give
 * GLINT_ERANGE and channel counts outside 1..max_channels GLINT_ERANGE,
 * both before any pixel memory is allocated; deep or volume images
 * GLINT_EUNSUPPORTED; a file the decoder rejects (truncated, corrupt)
 * GLINT_EFORMAT.  8-bit and 16-bit data are scaled to [0,1] linearly, alpha
 * is returned unassociated (as stored).  Finiteness is NOT checked.
 * want_names != 0 also fills out->names.  on_header (may be NULL) sees
 * the header first, with cls.  (OUT: *out, zeroed first.) */
int img_oiio_read(const char *format, FILE *fp, const void *mem, size_t len,
                  const char *source, int max_dim, int max_channels,
                  int want_names, img_oiio_header_fn on_header, void *cls,
                  img_oiio_pixels *out, glint_err *err);

void img_oiio_pixels_free(img_oiio_pixels *p);

/* Encode width x height x nch interleaved pixels, float (u8 == 0),
 * unsigned 8-bit (u8 == 1) or unsigned 16-bit (u8 == 2, native byte order),
 * in OpenImageIO format `format`, to the open
 * stream `fp` (the caller flushes, syncs and closes it) or, when fp is
 * NULL, to memory: *mem is then malloc'ed (caller frees) and *mem_len set.
 * names: NULL for the default R, G, B, A, or nch channel names.  OpenEXR is
 * written with zip compression.  `dest` names the output in messages.
 * GLINT_EIO when the encoder fails, with its message. */
int img_oiio_write(const char *format, FILE *fp, void **mem, size_t *mem_len,
                   const char *dest, int width, int height, int nch,
                   const char *const *names, int u8, const void *data,
                   glint_err *err);

/* Fill the holes of width x height x nch interleaved float pixels in place
 * by OpenImageIO's push-pull (ImageBufAlgo::fillholes_pushpull): channel
 * nch - 1 is the coverage (alpha in [0,1]), the others are premultiplied by
 * it.  Afterwards every pixel's alpha is 1 and pixels whose alpha was below
 * 1 hold a smooth blend of their covered neighbours at every scale.
 * nch 2..4.  GLINT_EINTERNAL with OpenImageIO's message if it fails. */
int img_oiio_fill_holes(float *px, int width, int height, int nch, glint_err *err);

#ifdef __cplusplus
}
#endif

#endif
