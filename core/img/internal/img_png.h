/* img_png.h: a direct decoder for the PNGs painters upload most (private to
 * img.c and tests).
 *
 * An upload's decode through OpenImageIO took 1.2-1.6 ms for a 256x256 RGB
 * PNG here, a third of the PUT, much of it the reader's own set-up; libpng
 * alone decodes it in about two thirds of that (BENCHMARKS.md).  This path
 * takes only PNGs whose pixels OpenImageIO returns as stored, with no
 * transform to match: 8 bits per sample, RGB or RGBA, not interlaced,
 * without a tRNS, gAMA, sRGB, iCCP or cHRM chunk.  Levels are divided by
 * 255 as img_oiio.cpp does (q / 255.0f, the float nearest q/255), alpha is
 * returned as stored (OpenImageIO's unassociated alpha), row 0 at the top:
 * the same floats bit for bit (test_img checks them against OpenImageIO).
 *
 * img_png_read returns 0 with *out filled, or 1 when the image is not for
 * this path or libpng stops on it (damaged, truncated, over max_dim or
 * max_channels): the caller then decodes through OpenImageIO, which makes
 * the error its callers already know.  Never an error of its own. */
#ifndef GLINT_IMG_PNG_H
#define GLINT_IMG_PNG_H

#include <stddef.h>

#include "img_oiio.h"

int img_png_read(const void *mem, size_t len, int max_dim, int max_channels,
                 img_oiio_pixels *out);

#endif
