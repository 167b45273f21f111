/* upload.h: a painting uploaded whole (PUT .../painting): the checks of
 * its body, its decode, and its blob written while it is decoded. */
#ifndef GLINT_UPLOAD_H
#define GLINT_UPLOAD_H

#include <pthread.h>
#include <stddef.h>

#include "err.h"
#include "http.h"
#include "img.h"
#include "store.h"

/* The checks before decoding: the body's size (max_body), that it is not
 * empty, and its Content-Type against its first bytes (PNG, JPEG or
 * OpenEXR).  An error set for api_error (413, 422 or 415). */
int upload_precheck(http_req *req, int w, int h, glint_err *e);

/* Decode the body and check it as a painting of view k: w x h (the
 * scene's paint scale ps times its raster) or the raster's size, at most
 * max_image_dim a side, RGB, finite.  The size and the decode's memory are
 * checked from the header before any pixel (upload_gate.h: 413, 422, 503).
 * Times "decode" and "validate" in the request's Server-Timing.  OUT: *im
 * (img_free; zeroed on failure). */
int upload_decode(http_req *req, int k, int w, int h, int ps, img *im, glint_err *e);

/* The upload's blob (store_painting_blob_put), written on a thread of its
 * own while the request's thread decodes and checks the image: the durable
 * write (file, fsync, rename, directory) and the decode take about as
 * long, and neither needs the other.  When the thread has not started by
 * the join (both cores busy: a held-out measurement, another fit), the
 * join writes the blob itself and the thread, when it runs, finds nothing
 * to do: never later than writing it after the decode.  Written at join
 * too when no thread could be made.  data and session must outlive the
 * join.  After a join that returned 0, name is a blob nothing names yet:
 * commit it (store_painting_commit_at) or remove it (store_blob_delete). */
typedef struct upload_job upload_job;
typedef struct upload_blob {
    store *s;
    const char *session;
    int view;
    const void *data;
    size_t len;
    char name[160];
    glint_err err;   /* when join returned non-zero */
    int rc;
    int by_thread;   /* after the join: 1 when the thread wrote it */
    upload_job *job; /* shared with the thread; NULL: none */
} upload_blob;

void upload_blob_start(upload_blob *b, store *s, const char *session, int view,
                       const void *data, size_t len);
int upload_blob_join(upload_blob *b);

#endif
