/* img_raw.h: a decoded image as a checksummed cache file.
 *
 * Decoding a 256x256 OpenEXR through OpenImageIO takes about 4 ms and a
 * PNG about 1.5 ms; reading back pixels already decoded takes a tenth of
 * that.  The server keeps a painting's decoded pixels beside its upload
 * this way, so a restart reads pixels rather than decoding them again.
 *
 * Format (cfile.h frame: magic "GLIMGR01", kind 1, XXH64 checksum): u32
 * width, height, channels, then width x height x channels floats,
 * interleaved, rows top first (img.h's layout).  Written atomically and not
 * fsynced: a file is rebuildable from the image it was decoded from, and a
 * torn or flipped one fails its checksum (GLINT_EFORMAT).  Loading checks
 * the sizes against max_dim (1..IMG_MAX_DIM) and channels 1..4 before any
 * pixel is read, and that every value is finite. */
#ifndef GLINT_IMG_RAW_H
#define GLINT_IMG_RAW_H

#include "err.h"
#include "img.h"

/* Write im to dir/name (dir created). */
int img_raw_save(const img *im, const char *dir, const char *name, glint_err *err);

/* Read dir/name (OUT: *out, zeroed first, the caller's).  GLINT_ENOTFOUND
 * when there is no file, GLINT_EFORMAT when it is not one of these, is
 * torn, or holds sizes beyond max_dim or values that are not finite. */
int img_raw_load(const char *dir, const char *name, int max_dim, img *out, glint_err *err);

#endif
