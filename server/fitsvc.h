/* fitsvc.h: fits as a service: the precomputation cache and fit jobs.
 *
 * Precomputations (core fit_prep: samples, design, decomposition, operator)
 * are keyed by the content hash of everything they depend on (pcache.h),
 * built lazily on first use, shared by every session that uses the same key,
 * computed once even when many requests ask at the same moment (single
 * flight), kept in memory under a byte budget (least recently used evicted)
 * and on disk (data_dir/cache, checksummed: a corrupt file is rebuilt).
 * A fit whose precomputation is cached runs at once in the request; one
 * that must build it runs as a job with progress (jobs can be polled or
 * streamed).
 *
 * Cache levels (one table, one LRU list, one byte budget).  Each level's
 * entry pins the one it was built from (a counted reference), so a parent
 * is never evicted under a child:
 *
 *   scene      "scene:<scene id>"             the scene (mesh, views) as the
 *                                              store loaded it, and its
 *                                              content hash
 *   pattern    "pattern:<scene hash>:<views>"  samples of the painted views
 *                                              (rasterized on the CPU: the
 *                                              rasterizer defines the pattern);
 *                                              <views> = used-view flags in hex
 *   decomp     pcache_key_hf(pattern hash, res, lambda, route, rcond)
 *                                              design + decomposition (disk
 *                                              layer: pcache_decomp_get)
 *   operator   "<decomp key>/<reg>/<precision>" regularized operator
 *
 * The pattern level exists because a decomposition's key needs the
 * pattern hash, which samples_build derives from the scene hash and the
 * views used: with it in memory, a warm fit rasterizes nothing.  Memory
 * hits are the rule for a fit; the disk layer answers only when the
 * decomposition itself is missing from memory (a restart, an eviction).
 *
 * Entry life cycle: BUILDING (one thread builds, outside the lock; others
 * asking for the key wait on a condition variable: single flight) ->
 * READY (or FAILED: waiters receive the builder's error; the entry leaves
 * the table so a later request retries).  Every holder owns one reference
 * (refs); an entry with refs > 0 is pinned (never evicted).  Budget: after
 * a build or a release, READY entries with refs == 0 are evicted from the
 * least recently used end until the bytes fit; pinned entries may keep the
 * total above the budget for as long as they are held (reported by
 * fitsvc_stats.bytes).  Using an operator touches its whole chain.
 *
 * Thread-safety: every function may be called from any thread.  Handles
 * (fitsvc_scene, fitsvc_prep) are owned by the caller until released; the
 * data they expose is read-only and valid until then. */
#ifndef GLINTD_FITSVC_H
#define GLINTD_FITSVC_H

#include <jansson.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "err.h"
#include "fit.h"
#include "img.h"
#include "scene.h"

typedef struct fitsvc fitsvc;

/* cache_dir: the disk layer (NULL: memory only).  budget_bytes: in-memory
 * budget of the precomputations (decoded paintings get an eighth of it
 * more, material documents a thirty-second).  threads: job workers
 * (1..64).  Also sets glibc's malloc thresholds for the process
 * (M_MMAP_THRESHOLD 32 MiB, M_TRIM_THRESHOLD 64 MiB; see fitsvc.c): call
 * it once, at startup. */
int fitsvc_open(const char *cache_dir, size_t budget_bytes, int threads, fitsvc **out,
                glint_err *err);

/* Stop: queued jobs fail ("daemon stopping"), running jobs finish, workers
 * are joined, every cache entry is freed (handles still held by callers
 * must have been released before).  Accepts NULL. */
void fitsvc_close(fitsvc *f);

/* End the job event streams promptly (fitsvc_job_events answers
 * GLINT_EUNSUPPORTED from now on): call before http_server_stop, so that
 * stopping does not wait for running jobs through their streams.  Jobs
 * themselves go on until fitsvc_close. */
void fitsvc_shutdown(fitsvc *f);

/* ---- scenes ------------------------------------------------------------------ */

typedef struct fitsvc_scene fitsvc_scene;

/* Where scenes come from (store_scene_acquire in glintd): `load` sets *out
 * to a read-only scene that stays valid until `unload(cls, *out)`; 0, or a
 * negative GLINT_E* code with a message (GLINT_ENOTFOUND: no such scene). */
typedef struct fitsvc_scene_source {
    int (*load)(void *cls, const char *scene_id, const scene **out, glint_err *err);
    void (*unload)(void *cls, const scene *sc);
    void *cls;
} fitsvc_scene_source;

/* The scene `scene_id` with its content hash, from the cache or loaded once
 * through `src` (single flight; the loaded scene is held until the entry
 * is evicted).  Scenes never change once created, so the scene id is the
 * key.  OUT: *out, a pinned handle: release it. */
int fitsvc_scene_acquire(fitsvc *f, const char *scene_id, const fitsvc_scene_source *src,
                         fitsvc_scene **out, glint_err *err);
const scene *fitsvc_scene_get(const fitsvc_scene *h);
const char *fitsvc_scene_hash(const fitsvc_scene *h); /* 32 hex digits */
const char *fitsvc_scene_id(const fitsvc_scene *h);
/* Take one more reference (for handing a handle to a job). */
fitsvc_scene *fitsvc_scene_ref(fitsvc *f, fitsvc_scene *h);
void fitsvc_scene_release(fitsvc *f, fitsvc_scene *h); /* accepts NULL */

/* ---- prepared fits ----------------------------------------------------------- */

typedef struct fitsvc_prep fitsvc_prep;

/* What a prepared fit depends on: the scene, the views taking part (one
 * flag per scene view: the painted views) and the parameters (mapping and
 * model do not enter the precomputation). */
typedef struct fitsvc_request {
    fitsvc_scene *scene;
    const unsigned char *use;
    fit_params params;
} fitsvc_request;

/* Progress of a build: stage is "samples", "design", "decomposition" or
 * "operator"; progress in [0, 1] over the whole preparation. */
typedef void (*fitsvc_progress_fn)(void *cls, const char *stage, double progress);

/* The prepared fit for `rq` if it is in memory and ready now (nothing is
 * built and nothing waited for): 0 with *out pinned, GLINT_ENOTFOUND
 * otherwise. */
int fitsvc_prep_try(fitsvc *f, const fitsvc_request *rq, fitsvc_prep **out, glint_err *err);

/* The prepared fit for `rq`, built where missing (levels already in
 * memory are shared, levels being built by another thread are waited
 * for).  Blocks for as long as the build takes: call it from a job. */
int fitsvc_prep_acquire(fitsvc *f, const fitsvc_request *rq, fitsvc_progress_fn cb, void *cls,
                        fitsvc_prep **out, glint_err *err);

/* A read-only fit_prep for fit_run.  Its arrays belong to the cache
 * entries (never fit_prep_free it); valid until fitsvc_prep_release.  Its
 * t_* fields hold the time THIS acquisition spent per stage (0 for a
 * level found in memory), cache_hit the disk layer's answer for the
 * decomposition when it was built (1 loaded, 0 built, -1 rebuilt). */
const fit_prep *fitsvc_prep_fit(const fitsvc_prep *p);

/* The cache report of this acquisition (a new object; caller decrefs):
 * {"memory": "hit"|"built"|"joined", per level {"key", "memory", "bytes",
 * "build_seconds"}, "disk": "loaded"|"built"|"rebuilt"|"off",
 * "cold_seconds": precomputation time when it was built}. */
json_t *fitsvc_prep_report(const fitsvc_prep *p);

/* The precomputation's cold build time (samples + design + decomposition
 * + operator, as measured when each level was built, disk load included). */
double fitsvc_prep_cold_seconds(const fitsvc_prep *p);

void fitsvc_prep_release(fitsvc *f, fitsvc_prep *p); /* accepts NULL */

/* ---- jobs --------------------------------------------------------------------- */

typedef struct fitsvc_job fitsvc_job;

/* The work of a job, run on a worker thread.  Returns 0 and may set
 * *result (an object whose members are added to the job's JSON, e.g.
 * {"material_id": ...}; stolen), or a negative code with *err set (the
 * job fails with err->msg). */
typedef int (*fitsvc_job_fn)(fitsvc_job *job, void *arg, json_t **result, glint_err *err);

/* Queue a job of `kind` ("fit", "holdout") owned by `owner` (a session id:
 * who may read it; "" for internal jobs).  `arg` is handed to fn and then
 * to arg_free (also when the job never runs).  Fit jobs run in submission
 * order, before any queued holdout job (background measurements), and at
 * most one holdout job runs at a time (with two workers or more, one is
 * always free for fits).
 * OUT: id[33] (128 random bits).  GLINT_EUNSUPPORTED if stopping or when
 * FITSVC_MAX_QUEUED jobs wait already (the message says which). */
#define FITSVC_MAX_QUEUED 256
int fitsvc_job_submit(fitsvc *f, const char *kind, const char *owner, fitsvc_job_fn fn,
                      void *arg, void (*arg_free)(void *), char id[33], glint_err *err);

/* 1 once the service is stopping: a long job may give up early (its
 * result is lost anyway). */
int fitsvc_job_cancelled(fitsvc_job *job);

/* From the job's own thread: enter `stage` at overall progress p in [0,1].
 * Stage changes are always kept in the job's event log; progress within a
 * stage is logged in steps of 5% at least. */
void fitsvc_job_progress(fitsvc_job *job, const char *stage, double progress);

/* The job as JSON {"id", "state", "progress", "stage", "created", ...,
 * "material_id"?, "error"?} (a new object) and its owner (OUT: owner[33]).
 * GLINT_ENOTFOUND for unknown (or expired) ids. */
int fitsvc_job_get(fitsvc *f, const char *id, json_t **job, char owner[33], glint_err *err);

/* Events of a job after sequence number `since` (0: from the start): blocks
 * up to timeout_s for one to appear.  OUT: *events, a JSON array of
 * {"seq", "type": "progress"|"done"|"failed", "job": {...}} (possibly empty
 * on timeout); *final = 1 once the returned array ends with the job's last
 * event.  GLINT_ENOTFOUND for unknown ids. */
int fitsvc_job_events(fitsvc *f, const char *id, long long since, double timeout_s,
                      json_t **events, int *final, glint_err *err);

/* ---- decoded paintings ------------------------------------------------------------
 *
 * Decoding a stored painting (OpenEXR) costs milliseconds; a fit needs
 * every painted view.  This small cache keeps the latest decoded image of
 * each (session, view) with its version, under its own byte budget (an
 * eighth of the precomputation budget), least recently used evicted.
 * Images handed out are pinned and shared read-only (no copy): release
 * each handle; an image replaced or evicted while pinned is freed at its
 * last release. */

typedef struct fitsvc_painting fitsvc_painting;

/* Offer a decoded painting (e.g. right after an upload or strokes stored
 * it as `version`; the image is copied): replaces an older version of the
 * same view. */
void fitsvc_painting_offer(fitsvc *f, const char *session, int view, long long version,
                           const img *im);

/* Put a painting the caller decoded, taking it over (*im is zeroed), and
 * get it back pinned.  GLINT_ERANGE when it exceeds the budget (then *im
 * is left to the caller). */
int fitsvc_painting_put(fitsvc *f, const char *session, int view, long long version, img *im,
                        fitsvc_painting **out);

/* The cached painting of (session, view) at exactly `version`, pinned:
 * 0, or GLINT_ENOTFOUND. */
int fitsvc_painting_get(fitsvc *f, const char *session, int view, long long version,
                        fitsvc_painting **out);
const img *fitsvc_painting_img(const fitsvc_painting *p);
void fitsvc_painting_release(fitsvc *f, fitsvc_painting *p); /* accepts NULL */

/* ---- material documents ------------------------------------------------------------
 *
 * A material never changes once stored, and parsing and printing its JSON
 * (a few KiB of numbers) costs more than the database read: the serialized
 * answer of GET /materials/{id} is kept here with the ids access checks
 * need, under a byte budget (a thirty-second of the precomputation
 * budget), least recently used evicted. */

typedef struct fitsvc_doc {
    char session[33], scene[33];
    char *text;   /* the JSON text (malloc'ed, NUL-terminated; the caller frees) */
    size_t len;
} fitsvc_doc;

void fitsvc_doc_put(fitsvc *f, const char *id, const char *session, const char *scene_id,
                    const char *text, size_t len);
/* 0 with *out filled (a copy), or GLINT_ENOTFOUND. */
int fitsvc_doc_get(fitsvc *f, const char *id, fitsvc_doc *out);

/* ---- speed-accuracy points ------------------------------------------------------
 *
 * What fits measured on a scene, by scene content hash and configuration
 * (`point_key`: parameters + views used), for GET /methods?scene_id=.  Kept
 * in memory and written through to cache_dir/points/<scene hash>.json
 * (atomic writes), so they survive a restart.  A point is an object:
 *   {"params", "views", "samples", "fits", "fit_seconds" (median of the
 *    last 16 warm fits: fit_run alone), "cold_seconds" (precomputation
 *    built from scratch, last measured) | null, "disk_seconds" (built with
 *    the decomposition loaded from disk) | null, "rms_painted" (last fit),
 *    "held_out_rms" | null, "held_out" {...} | null, "material_id" (last),
 *    "updated"} */

/* Record one fit: `cold` < 0 when the precomputation was in memory, and
 * `from_disk` says whether the decomposition was loaded from disk. */
int fitsvc_points_record(fitsvc *f, const char *scene_hash, const char *point_key,
                         const json_t *params, const json_t *views, int nsamples,
                         double fit_seconds, double cold, int from_disk, double rms_painted,
                         const char *material_id, glint_err *err);

/* 1 if the point has a held-out error already, 0 if not (or unknown). */
int fitsvc_points_has_holdout(fitsvc *f, const char *scene_hash, const char *point_key);

/* Set the held-out error of a point (steals `held_out`, an object with at
 * least "rms"). */
int fitsvc_points_set_holdout(fitsvc *f, const char *scene_hash, const char *point_key,
                              json_t *held_out, glint_err *err);

/* The points of a scene as a new array (empty if none). */
json_t *fitsvc_points_get(fitsvc *f, const char *scene_hash);

/* ---- statistics --------------------------------------------------------------- */

enum { FITSVC_LEVEL_SCENE, FITSVC_LEVEL_PATTERN, FITSVC_LEVEL_DECOMP, FITSVC_LEVEL_OP,
       FITSVC_NLEVELS };
extern const char *const fitsvc_level_names[FITSVC_NLEVELS];

/* Counters for /metrics.  hits / misses count fit requests (operator
 * level: was the whole precomputation in memory?); builds, evictions,
 * bytes and entries are totals over the levels; per level below. */
typedef struct fitsvc_stats {
    unsigned long long hits, misses, builds, evictions;
    size_t bytes, entries, budget;
    int jobs_queued, jobs_running;
    unsigned long long jobs_done, jobs_failed;
    unsigned long long lvl_hits[FITSVC_NLEVELS];   /* found ready in memory */
    unsigned long long lvl_joins[FITSVC_NLEVELS];  /* waited for another thread's build */
    unsigned long long lvl_builds[FITSVC_NLEVELS]; /* built here (misses = joins + builds) */
    unsigned long long lvl_failures[FITSVC_NLEVELS];
    unsigned long long lvl_evictions[FITSVC_NLEVELS];
    size_t lvl_bytes[FITSVC_NLEVELS], lvl_entries[FITSVC_NLEVELS];
    unsigned long long disk_loads, disk_builds, disk_rebuilds; /* decompositions */
    double build_seconds[FITSVC_NLEVELS];           /* summed build time */
    unsigned long long painting_hits, painting_misses;
    size_t painting_bytes;
    unsigned long long doc_hits, doc_misses;
    size_t doc_bytes;
} fitsvc_stats;
void fitsvc_stats_get(fitsvc *f, fitsvc_stats *out);

/* Write the counters in Prometheus text format (for GET /metrics). */
void fitsvc_metrics(fitsvc *f, FILE *out);

#endif
