/* img.h: float images and image file I/O (PNG, JPEG, OpenEXR, Radiance HDR)
 * behind a small C interface; the implementation wraps OpenImageIO in a C++
 * shim (img_oiio.cpp) that core/ never sees.
 *
 * An img owns its pixel array: width x height x channels floats,
 * interleaved, row 0 at the top.  img_free() accepts NULL and zeroed images.
 *
 * Value conventions: 8-bit formats (PNG, JPEG) map 0..255 to 0..1 linearly
 * (no transfer curve is applied: a painting's pixel value is the radiance
 * glint fits); PNG output clamps to [0,1] and rounds.  EXR and HDR carry
 * floats unchanged.  Readers reject non-finite pixels with GLINT_ENONFINITE
 * (the message gives the first offending pixel and channel), sizes above
 * IMG_MAX_DIM, and channel counts outside 1..4 (GLINT_ERANGE).
 *
 * Thread-safety: every function may be called from any thread at once on
 * different images (OpenImageIO's own caches are thread-safe; no global
 * state here); an img is read-only while shared. */
#ifndef GLINT_IMG_H
#define GLINT_IMG_H

#include <stddef.h>

#include "err.h"

#define IMG_MAX_DIM 16384
#define IMG_MAX_NAMED_CHANNELS 256 /* img_write_exr_named, img_read_named */

typedef struct img {
    int width, height, channels;
    float *px;
} img;

/* Allocate a zeroed image (OUT: *im).  GLINT_ERANGE for sizes outside
 * 1..IMG_MAX_DIM or channels outside 1..4. */
int img_alloc(img *im, int width, int height, int channels, glint_err *err);
void img_free(img *im);

/* Read an image file; format by content (OpenImageIO's detection).  *out is
 * zeroed first and owned by the caller. */
int img_read(const char *path, img *out, glint_err *err);

/* Decode an image held in memory (an upload).  Same checks as img_read. */
int img_read_mem(const void *data, size_t len, img *out, glint_err *err);
/* The same with sides at most max_dim (1..IMG_MAX_DIM), checked from the
 * header before any pixel is decoded: what bounds an upload's memory. */
int img_read_mem_max(const void *data, size_t len, int max_dim, img *out, glint_err *err);
/* img_read and img_read_mem_checked (below) without the finiteness check:
 * NaN and infinite values come back as the file holds them, for a caller
 * that deals with them itself (env.h reads them as 0 and counts them). */
int img_read_keep_nonfinite(const char *path, img *out, glint_err *err);
/* (img_read_mem_keep_nonfinite: below, with img_read_mem_checked.) */

/* Write by file extension: .png (8-bit, clamped), .exr (half or float as
 * chosen: float), .hdr.  GLINT_EUNSUPPORTED for other extensions.
 * Also .jpg / .jpeg (8-bit like PNG, 1 or 3 channels; lossy).  .hdr takes
 * exactly 3 channels (RGBE cannot store negatives: they are written as 0).
 * Non-finite pixels are refused (GLINT_ENONFINITE).  The file appears
 * atomically: it is written to a temporary name in the same directory and
 * renamed, so a crash never leaves a half-written file at `path`. */
int img_write(const char *path, const img *im, glint_err *err);

/* A 16-bit PNG (any extension): each value clamped to [0, 1] and rounded
 * to x * 65535, no transfer curve; written atomically like img_write. */
int img_write_png16(const char *path, const img *im, glint_err *err);

/* A texture as a material directory holds it: dir/stem.exr (float, `lin`)
 * and dir/stem.png (8-bit, `png`), each written as img_write does. */
int img_write_pair(const char *dir, const char *stem, const img *lin, const img *png,
                   glint_err *err);

/* Encode to memory in format "png" or "exr" (also "hdr", "jpg"/"jpeg",
 * with the rules of img_write).  *out_data is malloc'ed (caller frees),
 * *out_len its size. */
int img_write_mem(const char *format, const img *im, void **out_data,
                  size_t *out_len, glint_err *err);

/* img_write_mem("exr", im) (3 or 4 channels) given prev, the file of an
 * image that differs from im in lines y0..y1 at most (y1 < y0: none), as a
 * stroke's bounding box gives: prev's compressed blocks clear of those
 * lines are used again when prev has the layout img_write_mem("exr")
 * writes for im (img_exr.h, img_exr_encode_reusing), so the cost is that
 * of the lines changed.  prev may be NULL.  OUT: *reused (may be NULL), the
 * blocks of 16 lines taken from prev. */
int img_write_exr_mem_reusing(const img *im, const void *prev, size_t prev_len, int y0, int y1,
                              void **out_data, size_t *out_len, int *reused, glint_err *err);

/* Write an OpenEXR file with `nch` named float channels (names[i], e.g.
 * "N.X"), data interleaved width x height x nch.  nch in
 * 1..IMG_MAX_NAMED_CHANNELS, names non-empty and distinct, data finite;
 * written atomically like img_write. */
int img_write_exr_named(const char *path, int width, int height, int nch,
                        const char *const *names, const float *data,
                        glint_err *err);
/* The same to memory (OUT: *out_data malloc'ed, *out_len). */
int img_write_exr_named_mem(int width, int height, int nch, const char *const *names,
                            const float *data, void **out_data, size_t *out_len,
                            glint_err *err);

/* Make *im RGB: grey replicated, alpha dropped (3 channels: unchanged). */
int img_to_rgb(img *im, glint_err *err);

/* Check every value is finite (GLINT_ENONFINITE naming the first bad one). */
int img_check_finite(const img *im, glint_err *err);

/* A painting made at a multiple of the raster, read at the raster: `in` is
 * w x h (copied) or (s w) x (s h) for an integer s >= 2, and out(x, y) is
 * in's value at the raster pixel's centre, interpolated bilinearly (s
 * even: the mean of the 2 x 2 pixels around the centre; s odd: the centre
 * pixel itself).  The fit samples the geometry at pixel centres, so that
 * is the value it must match; a box over the whole pixel would blend in
 * what the sample's geometry does not have (a silhouette, a highlight
 * narrower than a pixel).  GLINT_EINVAL naming both sizes for any other
 * size.  OUT: *out (allocated here). */
int img_to_raster(const img *in, int w, int h, img *out, glint_err *err);

/* The scale s of a painting of size pw x ph over a w x h raster: 1, the
 * integer s >= 2 with pw = s w and ph = s h, or 0 for any other size. */
int img_raster_scale(int pw, int ph, int w, int h);
/* Fill an image's holes in place (OpenImageIO's push-pull): the last
 * channel is the coverage in [0,1] and the others are premultiplied by it;
 * afterwards the coverage is 1 everywhere and each uncovered pixel holds a
 * smooth blend of its covered neighbours.  Channels 2..4; GLINT_EINVAL for
 * fewer, or for an image with no covered pixel (nothing to fill from). */
int img_fill_holes(img *im, glint_err *err);

/* Every channel of an image file with its name, e.g. an OpenEXR file from
 * img_write_exr_named.  Channels come in the file's order, which need not
 * be the order they were written in (OpenEXR sorts names; R, G, B, A come
 * first): look them up by name.  Other formats name theirs R, G, B, A.
 * Owns names (nch malloc'ed strings) and px; img_named_free() accepts
 * NULL and zeroed structs. */
typedef struct img_named {
    int width, height, channels;
    char **names;
    float *px;       /* width x height x channels, interleaved */
} img_named;

/* Read with the checks of img_read, channels 1..IMG_MAX_NAMED_CHANNELS.
 * (OUT: *out, zeroed first.) */
int img_read_named(const char *path, img_named *out, glint_err *err);
/* The same from memory (an upload), sides at most max_dim (1..IMG_MAX_DIM)
 * and channels at most max_channels (1..IMG_MAX_NAMED_CHANNELS), checked
 * from the header before any pixel is decoded: what bounds its memory. */
int img_read_named_mem(const void *data, size_t len, int max_dim, int max_channels,
                       img_named *out, glint_err *err);
void img_named_free(img_named *im);

/* What an image in memory declares, read from its header before any pixel
 * is decoded or any memory for pixels is allocated: the format (by
 * content), the size, the channels the decode returns (at most; a PNG's
 * colour type, with an alpha for a tRNS chunk), and decode_bytes, the most
 * memory its decode takes: the floats it returns and the decoder's own
 * buffers (per sample: 6 bytes for an 8-bit PNG, 8 for a 16-bit one
 * (OpenImageIO keeps the whole image as stored, then a copy), 8 for JPEG
 * (a progressive file's coefficients), 4 plus the stored sample's size for
 * OpenEXR, 8 for Radiance HDR; plus IMG_DECODE_FIXED_BYTES for the
 * decoders' state and rows; tests/bench/bench_memory.py measures the
 * peaks against these: 1.05 to 1.5 times below them at 2048 x 2048). */
#define IMG_DECODE_FIXED_BYTES ((size_t)8 << 20)
typedef struct img_header {
    const char *format; /* "png", "jpeg", "openexr", "hdr" */
    int width, height, channels;
    size_t decode_bytes;
} img_header;

/* A reader's check of an upload's header (the caller's: the size its
 * target holds, the memory it may take): 0 to decode, or a glint code
 * with err set, which the read returns having decoded nothing. */
typedef int (*img_header_check)(void *cls, const img_header *hd, glint_err *err);

/* img_read_mem_max and img_read_named_mem with the header checked first:
 * check(cls, header) (NULL: none) is called exactly once, before any pixel
 * is decoded, whichever decoder takes the image (the direct PNG path,
 * OpenImageIO); a decode that meets another size or more channels than
 * the header said fails with GLINT_EFORMAT.  A file whose header cannot be
 * read fails as img_read_mem does, without calling check.  max_dim 0:
 * IMG_MAX_DIM, so that check sees any size first (OpenImageIO's formats
 * are held to max_dim before check is called, a PNG after). */
int img_read_mem_checked(const void *data, size_t len, int max_dim, img_header_check check,
                         void *cls, img *out, glint_err *err);
int img_read_named_mem_checked(const void *data, size_t len, int max_dim, int max_channels,
                               img_header_check check, void *cls, img_named *out,
                               glint_err *err);
int img_read_mem_keep_nonfinite(const void *data, size_t len, int max_dim,
                                img_header_check check, void *cls, img *out, glint_err *err);

#endif
