/* fitsvc.h: fits as a service.  Runs a fit from a session's paintings (or
 * a G-buffer set's samples) to a stored material, with what the app owns
 * and lends it: the precomputation cache (core cache.h, one for the
 * daemon: scenes, patterns, every method's levels; on disk under
 * data_dir/cache), the job pool (jobs.h), the decoded paintings and
 * material documents (memo.h) and the speed-accuracy record (points.h):
 *
 *   read the session's paintings (a snapshot; the painted views form the
 *   sampling pattern) -> the precomputation (prep.h): in memory now, the
 *   fit runs in the request; else it runs as a job that builds what is
 *   missing -> the material's files (blobs "materials/<id>/", written before
 *   its row) -> its row and document -> a "fit" event for the session ->
 *   a point of the scene's record, and once per configuration a held-out
 *   measurement in the background.
 *
 * Numerics are core's (prep.h, method.h, material.h); this module only
 * orchestrates.  Thread-safety: every function may be called from any
 * thread. */
#ifndef GLINTD_FITSVC_H
#define GLINTD_FITSVC_H

#include <jansson.h>
#include <stddef.h>
#include <stdio.h>

#include "cache.h"
#include "err.h"
#include "jobs.h"
#include "memo.h"
#include "method.h"
#include "points.h"
#include "scene.h"
#include "timing.h"

struct store;
struct events;

typedef struct fitsvc fitsvc;

/* The links of a material object (the API's: api_material_links): id, and
 * either its session and scene or its G-buffer set ("" for the other). */
typedef json_t *(*fitsvc_links_fn)(const char *id, const char *session_id,
                                   const char *scene_id, const char *set_id);

/* What the service uses and does not own: the app opens them before
 * fitsvc_open and closes them after fitsvc_close, the jobs first of all
 * (jobs_close: running jobs hold cache entries and record their fits
 * here). */
typedef struct fitsvc_config {
    cache *cache;            /* the precomputation cache */
    jobs *jobs;              /* the job pool: cold fits, held-out measurements */
    memo *memo;              /* decoded paintings and material documents */
    points *points;          /* the speed-accuracy record */
    struct admit *work;      /* admission of fits (admit.h); NULL: none */
    int background;          /* FITSVC_BG_*: the held-out measurements' CPU priority */
    fitsvc_links_fn links;   /* every material object's links (NULL: none) */
} fitsvc_config;

/* The CPU priority of work no one waits for (a fit point's held-out
 * measurement, scheduled after the fit): its own thread, at
 *   FITSVC_BG_IDLE    SCHED_IDLE on Linux: it runs only on a core that
 *                     would otherwise idle, so it takes no time from the
 *                     fits, uploads and strokes people wait for, but under
 *                     a load that never lets up it waits for the load to end;
 *   FITSVC_BG_LOW     nice 19: a small share of a busy core, never starved;
 *   FITSVC_BG_NORMAL  the requests' own priority.
 * The default is FITSVC_BG_IDLE (glintd --background-priority).  Apart
 * from its priority, the measurement waits before each of its views until
 * no fit has run and no painting has been stored for a second
 * (fitsvc_holdout.c, HOLDOUT_REST_S). */
enum { FITSVC_BG_IDLE = 0, FITSVC_BG_LOW = 1, FITSVC_BG_NORMAL = 2 };

/* Also sets glibc's malloc thresholds for the process (a fit allocates and
 * frees arrays of 0.1 to 30 MiB; kept in the heap they cost no page faults
 * each time): call it once, at startup. */
int fitsvc_open(const fitsvc_config *cfg, struct store *st, struct events *ev, fitsvc **out,
                glint_err *err);
/* Free the service (the app closed its jobs before).  Accepts NULL. */
void fitsvc_close(fitsvc *f);

/* The core scene of a stored scene, through the cache (scenes never change:
 * loaded once, shared).  GLINT_ENOTFOUND for unknown ids; "" (the scene of
 * a material fitted from a G-buffer set: none) GLINT_EUNSUPPORTED with
 * kind "no-scene".  OUT: *out, one
 * reference (cache_release on the cache it was lent, *out)). */
int fitsvc_scene(fitsvc *f, const char *scene_id, cache_entry **out, glint_err *err);

/* Fit the session's paintings with method m and params (copied).  0 with
 * either *doc (the API's material object, a new reference: the fit ran
 * now) or job_id set (the precomputation is being built: poll the job).  GLINT_EINVAL with kind "no-paintings" when nothing is painted,
 * "invalid-painting" for a painting that cannot be used; GLINT_ENOTFOUND
 * with kind "scene-gone" when the session's scene was deleted; GLINT_EBUSY
 * when too many jobs wait.  tm (may be NULL) receives the steps of a fit
 * run now (timing.h). */
int fitsvc_fit(fitsvc *f, const char *session_id, const char *scene_id, const method *m,
               const void *params, json_t **doc, char job_id[33], srv_timing *tm,
               glint_err *err);
/* (A fit queued as a job: of owner session_id, target the method's name,
 * so it supersedes the session's queued fits of the same method (jobs.h);
 * refused before it is queued, with GLINT_ETOOBIG kind "too-expensive",
 * when method_fit_seconds exceeds the daemon's limit (admit_cost).) */

/* Fit the samples and painted values of a G-buffer set (core gbfit.h)
 * with method m and params (copied): as fitsvc_fit, 0 with *doc (fitted
 * now: the precomputation was in memory) or job_id (a job of owner set_id
 * builds it and fits).  *s and *rgb are moved in (zeroed and NULL on return,
 * whatever it is).  The material object names gbuffer_set_id, no session
 * or scene; it is listed under set_id (store_material_list).  No fit point
 * or held-out measurement is recorded (they are a scene's).
 * fitsvc_gbuf.c. */
struct samples;
int fitsvc_fit_gbuffers(fitsvc *f, const char *set_id, const method *m, const void *params,
                        struct samples *s, float **rgb, json_t **doc, char job_id[33],
                        srv_timing *tm, glint_err *err);

/* The serialized material `id` with its session and scene (from memory when
 * there, else from the store with its links made again, fitsvc_config.links;
 * a copy: free out->text).  GLINT_ENOTFOUND. */
int fitsvc_material_doc(fitsvc *f, const char *id, memo_doc *out, glint_err *err);

/* Prometheus text for /metrics: fit requests, cache levels, jobs, memos. */
void fitsvc_metrics(fitsvc *f, FILE *out);

/* A painting was stored as `version` of (session, view) and offered to the
 * memo: its decoded pixels are written beside its blob, behind, once the
 * view rests (store.h, "Decoded paintings"; fitsvc_pixels.c). */
void fitsvc_painting_stored(fitsvc *f, const char *session, int view, long long version);

#endif
