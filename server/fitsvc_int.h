/* fitsvc_int.h: what the files of the fit service share: fitsvc.c (life
 * cycle, scenes, material documents, metrics), fitsvc_task.c (a session
 * fit's paintings and bounds), fitsvc_session.c (session fits),
 * fitsvc_gbuf.c (G-buffer set fits), fitsvc_record.c (recording every
 * fit), fitsvc_memo.c, fitsvc_holdout.c and fitsvc_pixels.c.  Not part of
 * the server's interface. */
#ifndef GLINT_FITSVC_INT_H
#define GLINT_FITSVC_INT_H

#include <pthread.h>

#include "admit.h"
#include "events.h"
#include "fitsvc.h"
#include "jobs.h"
#include "lru.h"
#include "memo.h"
#include "points.h"
#include "prep.h"
#include "store.h"
#include "timing.h"

typedef struct pix_writer pix_writer;

/* A session's fit memo (fitsvc_memo.c): its session and fit point
 * (points.h's key).  A slot that holds one is in fitsvc's memo_lru (lru.h:
 * the least recently put back makes room); a free one is in no list. */
#define FITSVC_MEMOS 8
typedef struct fit_memo_slot {
    lru_node node;
    int held;
    char session[33];
    char key[1024];
    method_memo mm;
} fit_memo_slot;

/* A scene's samples per view, for the fits' memory bound (task_bytes):
 * scenes never change once made, so their documents need not be read and
 * parsed again on every fit.  A slot in use is in fitsvc's counts_lru. */
#define FITSVC_SCENES 8
typedef struct fit_scene_counts {
    lru_node node;
    char id[33];             /* "": empty slot (in no list) */
    int nviews;
    long n[SCENE_MAX_VIEWS];
} fit_scene_counts;

struct fitsvc {
    cache *cache;
    jobs *jobs;
    memo *memo;
    points *points;
    store *st;
    events *ev;
    admit *work;                     /* NULL: no admission */
    int background;                  /* FITSVC_BG_*: held-out measurements' priority */
    int active;                      /* fits running now (under lock) */
    double last_active;              /* glint_now() when a fit began or ended or a painting
                                        was stored, last (under lock) */
    pthread_mutex_t lock;
    unsigned long long hits, misses; /* fit requests: precomputation in memory or not */
    json_t *holdouts;                /* held-out measurements scheduled, by scene hash/key */
    pix_writer *pix;                 /* fitsvc_pixels.c; NULL: none */
    fit_memo_slot memos[FITSVC_MEMOS]; /* under lock */
    lru_list memo_lru;                 /* the slots that hold a memo (under lock) */
    unsigned long long memo_chunks, memo_reused;
    fit_scene_counts counts[FITSVC_SCENES]; /* under lock */
    lru_list counts_lru;                    /* the slots in use (under lock) */
    fitsvc_links_fn links;           /* a material's links (fitsvc_config.links) */
};

/* Everything a fit needs, owned by the request or by its job. */
typedef struct fit_task {
    fitsvc *f;
    const method *m;
    void *params;
    char session_id[33], scene_id[33];
    cache_entry *scene;      /* held */
    int nviews, nused;
    img *paintings;          /* nviews; views never painted are zeroed */
    memo_painting **pins;    /* nviews: paintings shared with the memo (not ours to free) */
    unsigned char *use;      /* nviews: painted */
    long long *versions;     /* nviews: painting versions used */
    size_t bytes;            /* the fit's memory bound (admit.h) */
    long nsamples;           /* samples of the painted views (task_bytes) */
    srv_timing *tm;          /* steps of a fit run now (NULL in a job) */
} fit_task;

/* The task's paintings, read as a snapshot (the painted views form the
 * pattern).  OUT: t->nviews, paintings, pins, use, versions, nused.
 * GLINT_EINVAL with kind "no-paintings" when nothing is painted,
 * "invalid-painting" for one that cannot be used (fitsvc_task.c). */
int fit_task_read_paintings(fit_task *t, glint_err *err);
/* The fit's memory bound: the method's for the samples of the painted
 * views, and the paintings.  OUT: t->nsamples, t->bytes. */
int fit_task_bytes(fit_task *t, glint_err *err);
/* Free a task and release what it holds (accepts NULL; a job's free). */
void fit_task_free(void *t);

/* A fit to record (fit_record): the method asked for (auto's, not the one
 * it chose), where the fit came from (a session and its scene, or a
 * G-buffer set), the views fitted and its time. */
typedef struct fit_record_in {
    const method *method;
    const char *session_id, *scene_id; /* a session's fit; NULL or "" for a set's */
    const char *set_id;                /* a G-buffer set's fit; NULL for a session's */
    const unsigned char *use;          /* nviews: the views fitted */
    const long long *versions;         /* nviews: their paintings' versions (a session's) */
    int nviews;
    double fit_seconds;                /* the fit's own time, for the "fit" event */
    srv_timing *tm;                    /* steps "save" and "record" (NULL: none) */
} fit_record_in;

/* Record a fitted material m with its report r, every fit's one path
 * (fitsvc_record.c): its files saved under blobs "materials/<id>/" (id new,
 * near the session's or set's), its document (the API's material object:
 * the method's members of it passed on from r->members unread, links by
 * fitsvc_config.links), its row stored under the session or set (a
 * session's with its "fit" event, in one commit), the document offered to
 * the memo, and the session's streams notified.  OUT: mid, *doc (a new
 * reference).  m and r stay the caller's. */
int fit_record(fitsvc *f, const fit_record_in *in, const material *m, const fit_report *r,
               char mid[33], json_t **doc, glint_err *err);

/* Schedule the held-out measurement of a fit point (key: the point's) in
 * the background, unless one for it is pending; failures are logged. */
void fitsvc_holdout_schedule(fit_task *t, prep *p, const char *material_id, const char *key);

/* The writer of paintings' pixels (fitsvc_pixels.c): started after the
 * memo, stopped before it; count: paintings a fit read from the store, by
 * how; metrics: its counters. */
int fitsvc_pixels_start(fitsvc *f, glint_err *err);
void fitsvc_pixels_stop(fitsvc *f);
void fitsvc_pixels_count(fitsvc *f, int read, int decoded);
void fitsvc_pixels_metrics(fitsvc *f, FILE *o);

/* The fit memos (fitsvc_memo.c): take the one of (session, point key) for
 * a fit (OUT: *mm, zeroed when there is none) and put it back after (its
 * stream chunks, reused of chunks, are counted for /metrics); close frees
 * them all. */
void fitsvc_memo_take(fitsvc *f, const char *session, const char *key, method_memo *mm);
void fitsvc_memo_put(fitsvc *f, const char *session, const char *key, method_memo *mm,
                     int reused, int chunks);
void fitsvc_memo_close(fitsvc *f);
void fitsvc_memo_metrics(fitsvc *f, FILE *o);

/* A cold fit's estimate against the limit (admit_cost), before its job is
 * queued: 0, or GLINT_ETOOBIG naming the method, the samples, the estimate
 * and the limit. */
int fitsvc_cost_check(fitsvc *f, const method *m, const void *params, long nsamples,
                      glint_err *err);

/* What every stored material's record holds (proto/schemas/Material.json):
 * the fit's error statistics.  A fit whose statistics could not be written
 * (not finite) is refused with GLINT_ENUMERIC, kind "numerical-failure",
 * rather than stored without them. */
int fitsvc_material_check(const material *m, const fit_report *r, glint_err *err);

/* Job callbacks for the precomputation (cls: the job); the first is a
 * glint_cancel's stop (the job was cancelled or the daemon stops). */
int fitsvc_job_cancelled(void *cls);
void fitsvc_job_progress(void *cls, const char *stage, double p);

/* The painters' activity, which held-out measurements wait out
 * (fitsvc_holdout.c): delta +1 when a fit begins, -1 when it ends, 0 for a
 * painting stored.  fitsvc_quiet_for: seconds since the last of them, 0
 * while a fit runs. */
void fitsvc_busy(fitsvc *f, int delta);
double fitsvc_quiet_for(fitsvc *f);

#endif
