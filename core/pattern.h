/* pattern.h: a scene's sampling pattern (samples.h), rasterized on several
 * threads.
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

#endif
