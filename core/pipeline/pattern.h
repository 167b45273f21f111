/* pattern.h: a scene's sampling pattern (samples.h), rasterized on several
 * threads and kept in a cache file.
 *
 * Rasterizing.  pattern_raster() makes the pattern of the used views of a
 * scene exactly as samples_begin / samples_add / samples_end do on one
 * thread, view after view: the same samples in the same order, bit for bit,
 * with the same hash.  Each worker thread rasterizes whole views, a band of
 * rows at a time (never more than one band of G-buffer per thread), into a
 * part of its own; the calling thread appends the parts in view order
 * (samples_append) as they are finished, and workers run at most a few
 * views ahead of it, so the parts waiting are bounded too.  The first error
 * of any thread wins; the others stop at their next band.
 *
 * Files.  pattern_save() writes a pattern to <dir>/<hash of key>.pattern,
 * a checksummed cache file (cfile.h, magic "GLPATT01", kind 2):
 *   u32 n, nviews, width, height, rule, has_pos, key length; the key;
 *   the pattern hash (32 hex digits); used[nviews];
 *   view[n], pixel[n] (i32); nrm[3n], wi[3n], wo[3n] (f32);
 *   cos_i[n], intensity[n] (f64); pos[3n] (f32); uv[2n] (f32), each array
 *   starting at a multiple of 64 bytes from the file's start (zeros
 *   between);
 *   the XXH64 checksum of every byte before it.
 * 80 bytes a sample (31.5 MB for 12 views of a sphere at 256x256).  A
 * kind 1 file (the arrays unaligned) is GLINT_EFORMAT: rebuilt.
 * pattern_load() maps it and uses the arrays where they lie (the samples
 * hold the mapping: samples.h, map), and trusts
 * nothing in it: the checksum must match, the key, the counts and sizes
 * must be the scene's, the used flags the request's, the hash what
 * samples_end would compute; every sample must lie in a used view, in
 * order (views non-decreasing, pixels increasing within a view), inside the
 * raster, with finite values, unit normal and view direction, n.wo >= 0
 * and cos_i = n.wi (to rounding; cos_i > 0 for the LIT rule) and the
 * view's light intensity.  Anything else is GLINT_EFORMAT (the cache then
 * rebuilds the pattern and overwrites the file).
 *
 * Ownership: the samples made are the caller's (samples_free).  Thread-
 * safety: no global state; the scene is only read. */
#ifndef GLINT_PATTERN_H
#define GLINT_PATTERN_H

#include "err.h"
#include "samples.h"
#include "scene.h"

/* G-buffer pixels a thread holds at once, unless told otherwise. */
#define PATTERN_BAND_PIXELS (1 << 18)
/* Most threads pattern_raster() uses. */
#define PATTERN_MAX_THREADS 16

typedef struct pattern_in {
    const scene *sc;
    const unsigned char *use;    /* sc->nviews flags: the views that take part */
    int rule;                    /* SAMPLES_LIT or SAMPLES_SEEN */
    const char *scene_hash;      /* scene_hash(sc): 32 hex digits */
    int band_pixels;             /* G-buffer pixels per band (<= 0: PATTERN_BAND_PIXELS) */
    int nthreads;                /* 1: on the calling thread alone; <= 0: the machine's cores
                                    (never more than the views used or PATTERN_MAX_THREADS) */
    /* Optional: told on the calling thread after each used view is in the
     * pattern (done of nused, in order). */
    void (*progress)(void *cls, int done, int nused);
    void *cls;
} pattern_in;

/* The pattern of in->sc's used views (OUT: *out; on failure *out is left
 * freed).  GLINT_EINVAL when no view gives a sample. */
int pattern_raster(const pattern_in *in, samples *out, glint_err *err);

/* Write s, the pattern cached under `key`, to its file in dir (created). */
int pattern_save(const samples *s, const char *dir, const char *key, glint_err *err);

/* The pattern cached under `key` in dir, which must be the pattern of
 * scene sc (hash scene_hash) for the views flagged in use[sc->nviews] and
 * `rule` (OUT: *out).  GLINT_ENOTFOUND when there is no file,
 * GLINT_EFORMAT when it is short, damaged or not that pattern. */
int pattern_load(const char *dir, const char *key, const scene *sc, const char scene_hash[33],
                 const unsigned char *use, int rule, samples *out, glint_err *err);

/* The file name pattern_save uses for `key` (OUT: name, at least 48 bytes). */
void pattern_file_name(const char *key, char *name, size_t len);

#endif
