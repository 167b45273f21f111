/* memo.h: two small caches of what glintd would otherwise read and decode
 * again and again, each under its own byte budget, least recently used
 * evicted (lru.h):
 *
 *  - decoded paintings: a fit needs every painted view, and decoding a
 *    stored painting (OpenEXR) costs milliseconds.  The latest decoded image
 *    of each (session, view) is kept with its version.  Images handed out
 *    are pinned and shared read-only (no copy): release each handle; an image
 *    replaced or evicted while pinned is freed at its last release.
 *  - material documents: a material never changes once stored, and
 *    printing its JSON (a few KiB of numbers) costs more than the database
 *    read: the serialized answer of GET /materials/{id} is kept with the ids
 *    that access checks need.
 *
 * Thread-safety: every function may be called from any thread. */
#ifndef GLINTD_MEMO_H
#define GLINTD_MEMO_H

#include <stddef.h>
#include <stdio.h>

#include "err.h"
#include "img.h"

typedef struct memo memo;
typedef struct memo_painting memo_painting;

int memo_open(size_t painting_budget, size_t doc_budget, memo **out, glint_err *err);
/* Every pin must have been released.  Accepts NULL. */
void memo_close(memo *m);

/* Offer a decoded painting just stored as `version` (copied): replaces an
 * older version of the same view. */
void memo_painting_offer(memo *m, const char *session, int view, long long version,
                         const img *im);

/* Put a painting the caller decoded, taking it over (*im zeroed), and get
 * it back pinned (OUT: *out).  GLINT_ETOOBIG when it exceeds the budget
 * (then *im is left to the caller). */
int memo_painting_put(memo *m, const char *session, int view, long long version, img *im,
                      memo_painting **out);

/* The painting of (session, view) at exactly `version`, pinned: 0, or
 * GLINT_ENOTFOUND. */
int memo_painting_get(memo *m, const char *session, int view, long long version,
                      memo_painting **out);
const img *memo_painting_img(const memo_painting *p);
void memo_painting_release(memo *m, memo_painting *p); /* accepts NULL */

/* A material document and the ids access checks need. */
typedef struct memo_doc {
    char session[33], scene[33];
    char *text;     /* the JSON text (malloc'ed, NUL-terminated; the caller frees) */
    size_t len;
} memo_doc;

/* Keep a copy (documents never change: a second put of an id is ignored). */
void memo_doc_put(memo *m, const char *id, const char *session, const char *scene,
                  const char *text, size_t len);
/* 0 with *out filled (a copy), or GLINT_ENOTFOUND. */
int memo_doc_get(memo *m, const char *id, memo_doc *out);

/* Prometheus text for /metrics. */
void memo_metrics(memo *m, FILE *out);

#endif
