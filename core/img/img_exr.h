/* img_exr.h: an RGB(A) image encoded as an OpenEXR file in memory, fast.
 *
 * What img_write_mem("exr") gives for 3 and 4 channels: a single-part
 * scanline file of 32-bit float channels R, G, B (and A), ZIP compression
 * (blocks of 16 lines; each block's bytes split into even and odd halves,
 * differenced, then deflated in zlib's format), increasing lines, the
 * data and display windows the image.  The file is OpenEXR 2's layout
 * (openexr.com, "OpenEXR File Layout"); any reader decodes it to the same
 * floats, bit for bit.
 *
 * Written here rather than through OpenImageIO for a painting's strokes,
 * which store the painting again at every stroke: the deflate is
 * libdeflate's (level 1), the blocks are compressed on the worker pool
 * (par.h).  A stored stroke's 256x256 RGB painting took 5.1 ms through
 * OpenImageIO and OpenEXR, 1.7 ms here (3.3 ms on one thread); the
 * figures and their command are in BENCHMARKS.md (bench_img_exr).  A
 * stroke touches a few lines: img_exr_encode_reusing copies the blocks it
 * missed from the file it replaces (a dab of diameter 12 within one block
 * of a 256x256 painting: 0.17 against 1.5 ms).
 *
 * The caller has checked the image (img_validate, finite values). */
#ifndef GLINT_IMG_EXR_H
#define GLINT_IMG_EXR_H

#include <stddef.h>

#include "err.h"
#include "img.h"

/* im (3 or 4 channels) as an OpenEXR file (OUT: *out, malloc'd, *len
 * bytes).  GLINT_EINVAL for other channel counts, GLINT_ENOMEM. */
int img_exr_encode(const img *im, void **out, size_t *len, glint_err *err);

/* img_exr_encode's file of im, made from prev (prev_len bytes) where it
 * can: prev is the file of an image that differs from im in lines y0..y1
 * at most (y1 < y0: in none), which a stroke's bounding box gives.  When
 * prev starts with the header img_exr_encode writes for im and its every
 * block is where its table says, of the right line and no larger than the
 * block's raw bytes, the blocks clear of lines y0..y1 are copied from it
 * and the others encoded; otherwise all are encoded.  When prev is a file
 * img_exr_encode made, the result is the bytes img_exr_encode(im) gives
 * (tests/unit/test_img_exr.c).  The caller answers for prev's image:
 * copied blocks are not decoded.  OUT: *reused (may be NULL), the blocks
 * copied.  GLINT_EINVAL, GLINT_ENOMEM as img_exr_encode. */
int img_exr_encode_reusing(const img *im, const void *prev, size_t prev_len, int y0, int y1,
                           void **out, size_t *len, int *reused, glint_err *err);

#endif
