/* points.h: what fits measured on each scene (speed against accuracy), for
 * GET /methods?scene_id=: per scene content hash and configuration (a
 * method, its parameters and the views used), one point:
 *   {"method", "params", "views", "samples", "fits", "fit_seconds" (median
 *    of the last 16 warm fits: the fit alone), "cold_seconds"
 *    (precomputation built from scratch, last measured) | null,
 *    "disk_seconds" (built with the decomposition loaded from disk) | null,
 *    "rms_painted" (last fit), "held_out_rms" | null, "held_out" {...} |
 *    null, "material_id" (last), "updated"}
 * Points are a record, not user data: kept in memory and written behind to
 * dir/<scene hash>.json (atomically) at most every POINTS_SAVE_PERIOD_S
 * seconds (points_flush, from an idle worker) and at close; a crash loses
 * at most the last seconds of records.  An unreadable file is started
 * again.
 *
 * Thread-safety: every function may be called from any thread. */
#ifndef GLINTD_POINTS_H
#define GLINTD_POINTS_H

#include <jansson.h>

#include "err.h"
#include "method.h"

#define POINTS_SAVE_PERIOD_S 2.0

typedef struct points points;

/* dir: where the files go (NULL: memory only). */
int points_open(const char *dir, points **out, glint_err *err);
void points_close(points *p); /* writes what is pending; accepts NULL */

/* Write the scenes recorded since the last write (force: whatever the
 * period).  Errors are logged. */
void points_flush(points *p, int force);

/* The key of a configuration: the method, every parameter in its canonical
 * spelling and the views used (OUT: buf). */
void points_key(const method *m, const void *params, const unsigned char *use, int nviews,
                char *buf, size_t len);

/* Record one fit: cold < 0 when the precomputation was in memory;
 * from_disk: it was built with its disk layer's answer. */
int points_record(points *p, const char *scene_hash, const char *key, const char *method_name,
                  const json_t *params, const json_t *views, int nsamples, double fit_seconds,
                  double cold, int from_disk, double rms_painted, const char *material_id,
                  glint_err *err);

/* 1 if the point has a held-out error already. */
int points_has_holdout(points *p, const char *scene_hash, const char *key);

/* Set the held-out error (steals `held_out`, an object with "rms"). */
int points_set_holdout(points *p, const char *scene_hash, const char *key, json_t *held_out,
                       glint_err *err);

/* The points of a scene (a new array, empty if none). */
json_t *points_get(points *p, const char *scene_hash);

#endif
