/* prep.h: a fit's precomputation through the cache, for any method:
 *
 *   scene    "scene:<id>"                   the scene and its content hash
 *   pattern  "pattern:<scene hash>:<views>" the samples of the views used
 *                                           (rasterized on the CPU, by the
 *                                           machine's cores: the rasterizer
 *                                           defines the pattern; pattern.h),
 *                                           kept on disk when the cache has a
 *                                           directory; <views>: the used-view
 *                                           flags in hex ("pattern-seen:..."
 *                                           for the SEEN rule)
 *   levels   the method's own (method.h), each keyed from the one before
 *
 * then the fit of one set of paintings.  The daemon, the command line and
 * the held-out measurement all go through here, so a method's levels are
 * built, shared, kept and reported one way.  A prepared fit (struct prep)
 * holds a reference on each of its levels: they stay in memory, read-only,
 * until prep_release.  Several fits may use one prep at once.
 *
 * Thread-safety: every function may be called from any thread (the cache
 * serializes what must be).  Progress callbacks run on the building
 * thread (a pattern's worker threads never call them). */
#ifndef GLINT_PREP_H
#define GLINT_PREP_H

#include <jansson.h>

#include "cache.h"
#include "cancel.h"
#include "err.h"
#include "gbuf.h"
#include "img.h"
#include "material.h"
#include "method.h"
#include "samples.h"
#include "scene.h"

/* ---- the scene level ------------------------------------------------------------ */

/* Where scenes come from: `load` sets *out to a read-only scene valid until
 * `unload(cls, *out)` (0, or a code with a message; GLINT_ENOTFOUND: no such
 * scene). */
typedef struct prep_scene_source {
    int (*load)(void *cls, const char *id, const scene **out, glint_err *err);
    void (*unload)(void *cls, const scene *sc);
    void *cls;
} prep_scene_source;

/* The scene level's value. */
typedef struct prep_scene {
    const scene *sc;
    char id[64];
    char hash[33];       /* scene_hash() */
    prep_scene_source src;
} prep_scene;

/* The scene `id` (at most 63 bytes), from the cache or loaded once through
 * `src` (scenes never change once created: the id is the key).  OUT: *out,
 * one reference. */
int prep_scene_acquire(cache *c, const char *id, const prep_scene_source *src,
                       cache_entry **out, glint_err *err);
const prep_scene *prep_scene_of(const cache_entry *scene_entry);

/* ---- preparing a fit -------------------------------------------------------------- */

typedef void (*prep_progress_fn)(void *cls, const char *stage, double fraction);

typedef struct prep_request {
    const method *m;
    const void *params;          /* the method's params struct (copied) */
    cache_entry *scene;          /* a scene entry the caller holds */
    const unsigned char *use;    /* one flag per scene view: the views that take part */
    /* Asked before each level and by the builds' loops (cancel.h; NULL:
     * never).  A build this caller waits for (joined) that another caller
     * cancelled is built again by this one. */
    const glint_cancel *cancel;
} prep_request;

/* Patterns are rasterized a view per thread at a time in bands of rows of
 * at most this many pixels: a thread never holds more G-buffer than a
 * band (pattern.h). */
#define PREP_BAND_PIXELS (1 << 18)

typedef struct prep prep;

/* The pattern key of a request (OUT: key[CACHE_KEY_MAX]); rule: the
 * method's (samples.h). */
void prep_pattern_key(const prep_scene *s, const unsigned char *use, int rule, char *key);

/* The prepared fit if every level is in memory now (nothing is built or
 * waited for): 0 with *out, else GLINT_ENOTFOUND. */
int prep_try(cache *c, const prep_request *rq, prep **out, glint_err *err);

/* The prepared fit, built where missing (levels in memory are shared, levels
 * being built by another caller are waited for).  Blocks for as long as the
 * builds take. */
int prep_acquire(cache *c, const prep_request *rq, prep_progress_fn cb, void *cls, prep **out,
                 glint_err *err);

/* The same from samples the caller made (e.g. imported from a file): they
 * form the pattern level, keyed "samples:<their hash>", in memory only (*s
 * is moved in, zeroed).  cancel: as prep_request's. */
int prep_acquire_samples(cache *c, const method *m, const void *params, samples *s,
                         prep_progress_fn cb, void *cls, const glint_cancel *cancel,
                         prep **out, glint_err *err);
/* prep_try for such samples (they are only read: keyed by s->hash). */
int prep_try_samples(cache *c, const method *m, const void *params, const samples *s,
                     prep **out, glint_err *err);

/* Fit one set of paintings (one img per scene view; unused views are not
 * read) or, when paintings is NULL, the values rgb[3 n] directly.  The
 * material's info gets precomputation.cache (prep_report). */
int prep_fit(const prep *p, const img *paintings, const float *rgb, material *out,
             glint_err *err);

/* A fit of values rgb (3 n, as prep_fit's) that leaves the samples where
 * held[i] out (method_fit_in.held: their values are not read), on the
 * preparation of every sample, so that prep_predict then gives the held
 * ones the material's values.  GLINT_EINVAL when the method does not
 * honour it (method.fits_held). */
int prep_fit_held(const prep *p, const float *rgb, const unsigned char *held, material *out,
                  glint_err *err);

/* What a fit reports, typed: the figures a service records and shows,
 * read here once from the preparation and from the method's info, and the
 * method's own JSON for the material document, which a service passes on
 * without reading its keys.  Free with fit_report_free. */
/* One painted view's share of rms_painted: sqrt(sum of view k's samples'
 * squared residuals / (3 samples)). */
typedef struct fit_view_error {
    int view;
    double rms;
    long samples;
} fit_view_error;

typedef struct fit_report {
    int errors_ok;            /* the method gave its error statistics (all finite): a
                                 material without them is not worth keeping */
    double rms_painted;       /* RMS of fitted minus painted over the painted samples
                                 (NaN without statistics) */
    double fit_seconds;       /* the fit's own time, reading the paintings included */
    const char *memory;       /* the preparation as a whole: "hit", "built" (a level was
                                 built) or "joined" (one was waited for); static */
    double cold_seconds;      /* prep_cold_seconds */
    int from_disk;            /* prep_from_disk */
    int levels;               /* the preparation's levels, its pattern included */
    int levels_built;         /* of those, made for this fit (from disk or computed) */
    int levels_loaded;        /* of those made, read from the disk layer */
    int stream_chunks;        /* the method's pass over the samples in chunks (0: none) */
    int stream_chunks_reused; /* of those, the sums a memo's earlier fit gave */
    char chosen[16];          /* a method that picks another to fit (auto): the one it
                                 picked; "" otherwise */
    int nview_errors;         /* the method's errors by painted view (errors.rms_by_view),
                                 views with samples in ascending order; 0: none given */
    fit_view_error *view_errors; /* nview_errors; owned */
    const json_t *params;     /* the parameters fitted with (the material's: valid while
                                 it lives) */
    json_t *members;          /* the material document's members the fit gives, as the
                                 method wrote them (proto/schemas/Material.json): params,
                                 errors, seconds, precomputation and the method's own
                                 (auto: choice); owned */
} fit_report;

/* Free what *r owns and zero it (accepts NULL and a zeroed report). */
void fit_report_free(fit_report *r);

/* prep_fit for a caller that fits the same views again and again (a
 * painter's session): tags (s->nviews, one per view) name each view's
 * painting, memo keeps what the method may reuse for the views whose tag
 * did not change (method_memo; one fit at a time).  The material is the
 * same bits as prep_fit's.  tags or memo NULL: prep_fit.  rep (may be
 * NULL): OUT the fit's report (fit_report_free, after a success only). */
int prep_fit_reusing(const prep *p, const img *paintings, const float *rgb,
                     const uint64_t *tags, method_memo *memo, material *out, fit_report *rep,
                     glint_err *err);

/* The painted values the method's own model gives the preparation's
 * samples with material m (fitted by the same method): OUT rgb[3 n], NaN
 * where it models no value (method.predict; without one, the material
 * under each sample's point light times its intensity). */
int prep_predict(const prep *p, const struct material *m, float *rgb, glint_err *err);

/* What the preparation found (a new object):
 * {"memory": "hit"|"built"|"joined", "disk": "loaded"|"built"|"rebuilt"|"off",
 *  "key": the last level's key, "cold_seconds": the precomputation's cold
 *  time, "levels": {<name>: {"key", "memory", "disk", "bytes",
 *  "build_seconds", "waited_seconds"}}}.  "memory" is "built" if any level
 * was built, else "joined" if any was waited for, else "hit".  The top
 * "disk" is the method's first disk-backed level's (the pattern's is in
 * its own level report); a level's "disk" is what the disk layer answered
 * when that entry was made. */
json_t *prep_report(const prep *p);

/* The precomputation's cold time: every level as it was built (disk
 * loads included). */
double prep_cold_seconds(const prep *p);
/* 1 if the first disk-backed level was loaded from disk when made. */
int prep_from_disk(const prep *p);
/* 1 if everything was in memory already. */
int prep_was_hit(const prep *p);
const samples *prep_samples(const prep *p);
/* The pattern's cache entry (for cache_ref: keeping the samples alive
 * beyond the prep, e.g. for a held-out measurement). */
cache_entry *prep_pattern(const prep *p);

void prep_release(cache *c, prep *p); /* accepts NULL */

/* What a fit of scene sc will see: the samples of each view (lit and seen
 * pixels; OUT: per_view[sc->nviews]) and their total (*total).
 * GLINT_EINVAL when no view has one. */
int prep_sample_counts(const scene *sc, long *per_view, long *total, glint_err *err);

/* ---- held-out error ----------------------------------------------------------------- */

/* Leave-one-view-out: for each used view k of the pattern `all` (the
 * samples of every painted view, e.g. prep_samples() of the fit being
 * measured), fit the other views' samples (samples_subset: the pattern
 * those views alone make; a precomputation of its own in a private cache,
 * nothing kept; a method with fits_held fits them on one preparation of
 * every sample with view k's left out, prep_fit_held) and measure the RMS
 * error on view k's samples against its painting; the pooled RMS over all held-out pixels is the result.  Needs
 * 2 used views or more.  `cancelled` (may be NULL) is asked between views
 * (it may wait there, e.g. for a quiet moment), `cancel` (may be NULL) by
 * the views' builds (cancel.h); either stops it with GLINT_ECANCELLED;
 * progress as ("holdout", fraction).  OUT: *result {"method":
 * "leave-one-view-out", "rms", "max_abs", "pixels", "views", "per_view":
 * [{"view", "rms", "pixels"}], "seconds"}. */
int prep_holdout(const method *m, const void *params, const samples *all,
                 const img *paintings, int (*cancelled)(void *cls), prep_progress_fn cb,
                 void *cls, const glint_cancel *cancel, json_t **result, glint_err *err);

#endif
