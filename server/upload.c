/* upload.c: a painting uploaded whole (upload.h). */
#include "upload.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api_common.h"
#include "app.h"
#include "clock.h"
#include "upload_gate.h"

/* The image formats a painting may come in: what their bytes begin with and
 * the media types that name them. */
static const struct {
    const char *name, *magic, *types[3];
    size_t magic_len;
} painting_formats[] = {
    {"PNG", "\x89PNG\r\n\x1a\n", {"image/png", NULL}, 8},
    {"JPEG", "\xff\xd8\xff", {"image/jpeg", "image/jpg", NULL}, 3},
    {"OpenEXR", "\x76\x2f\x31\x01", {"image/x-exr", "image/exr", NULL}, 4},
};
enum { PAINTING_NFORMATS = sizeof painting_formats / sizeof painting_formats[0] };

/* The body's format by its first bytes (-1: none of them). */
static int painting_sniff(const void *body, size_t len)
{
    for (int i = 0; i < PAINTING_NFORMATS; i++)
        if (len >= painting_formats[i].magic_len &&
            memcmp(body, painting_formats[i].magic, painting_formats[i].magic_len) == 0)
            return i;
    return -1;
}

/* Content-Type against the body: none or application/octet-stream leaves
 * the bytes to tell; an image type must name the format the bytes are in;
 * anything else is refused (415).  Only PNG, JPEG and OpenEXR bytes reach the
 * image decoder. */
static int painting_check_type(http_req *req, int w, int h, glint_err *e)
{
    const char *ct = http_header_in(req, "Content-Type");
    int f = painting_sniff(req->body, req->body_len);
    char type[64];
    size_t n = 0;

    if (ct) {
        while (*ct == ' ')
            ct++;
        while (ct[n] && ct[n] != ';' && ct[n] != ' ' && n + 1 < sizeof type) {
            type[n] = (char)tolower((unsigned char)ct[n]);
            n++;
        }
        type[n] = 0;
    }
    if (ct && n && strcmp(type, "application/octet-stream")) {
        int named = -1;
        for (int i = 0; i < PAINTING_NFORMATS && named < 0; i++)
            for (int j = 0; painting_formats[i].types[j]; j++)
                if (strcmp(type, painting_formats[i].types[j]) == 0)
                    named = i;
        if (named < 0)
            return api_reject(e, GLINT_EUNSUPPORTED, "unsupported-media-type",
                              "Content-Type \"%.64s\" is not a painting's: send image/png, "
                              "image/jpeg, image/x-exr or application/octet-stream", ct);
        if (f != named)
            return api_reject(e, GLINT_EUNSUPPORTED, "unsupported-media-type",
                              "Content-Type says %s but the body is %s", type,
                              f < 0 ? "none of PNG, JPEG or OpenEXR" : painting_formats[f].name);
    }
    if (f < 0)
        return api_reject(e, GLINT_EINVAL, "invalid-image",
                          "the body is not a PNG, JPEG or OpenEXR image (its first bytes say "
                          "none of them); this view expects %dx%d", w, h);
    return 0;
}

/* Decode and check an uploaded painting: the view's image size w x h (the
 * scene's paint_scale ps times its raster), or the raster's (accepted at
 * any ps: the fit reads both, img_to_raster). */
/* The checks before decoding: the body's size and type. */
int upload_precheck(http_req *req, int w, int h, glint_err *e)
{
    app *a = req->app;
    if (req->body_too_large)
        return api_reject(e, GLINT_ETOOBIG, "body-too-large",
                          "the painting exceeds the request body limit of %zu bytes "
                          "(max_body, glintd --max-body-mb %zu)",
                          a->cfg.lim.max_body, a->cfg.lim.max_body >> 20);
    if (req->body_len == 0)
        return api_reject(e, GLINT_EINVAL, "empty-body",
                          "the body must be the painting: PNG, JPEG or OpenEXR bytes, %dx%d", w,
                          h);
    return painting_check_type(req, w, h, e);
}

/* Decode and check an uploaded painting (upload_precheck passed): its
 * header through the upload gate, then its pixels. */
int upload_decode(http_req *req, int k, int w, int h, int ps, img *im, glint_err *e)
{
    upload_gate g;
    double t0;
    int rc;

    memset(im, 0, sizeof *im);
    upload_gate_init(&g, req->app, "the painting");
    upload_gate_size(&g, w, h);
    if (ps > 1) {
        upload_gate_size(&g, w / ps, h / ps);
        snprintf(g.expect, sizeof g.expect,
                 "view %d of this scene expects %dx%d (the painting's size: %d times the "
                 "raster) or %dx%d (the raster's)",
                 k, w, h, ps, w / ps, h / ps);
    } else {
        snprintf(g.expect, sizeof g.expect,
                 "view %d of this scene expects exactly %dx%d (the scene's raster size)", k, w,
                 h);
    }
    g.per_pixel = 3 * sizeof(float); /* img_to_rgb's copy */
    t0 = glint_now();
    rc = img_read_mem_checked(req->body, req->body_len, 0, upload_gate_check, &g, im, e);
    t0 = srv_timing_step(&req->timing, "decode", t0);
    if (rc == GLINT_ENONFINITE)
        rc = api_reject(e, rc, "non-finite", "the painting has non-finite pixels: %.400s",
                        e->msg);
    else if (rc == GLINT_ENOMEM)
        glint_err_prefix(e, "decoding the painting");
    else if (rc && !g.refused)
        rc = api_reject(e, GLINT_EINVAL, "invalid-image",
                        "the body is not a readable PNG, JPEG or OpenEXR image: %.400s", e->msg);
    else if (!rc && ((rc = img_to_rgb(im, e)) || (rc = img_check_finite(im, e))))
        rc = rc == GLINT_ENONFINITE ? api_reject(e, rc, "non-finite",
                                                 "the painting has non-finite pixels: %.400s",
                                                 e->msg)
                                    : rc;
    upload_gate_leave(&g);
    srv_timing_step(&req->timing, "validate", t0);
    if (rc)
        img_free(im);
    return rc;
}

/* What the caller and the thread share: who writes the blob (the first
 * to claim it), and when it is written. */
enum { JOB_WAITING, JOB_THREAD, JOB_CALLER, JOB_DONE };
struct upload_job {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int state, refs;
    upload_blob *b; /* the caller's: read and written only by whoever claimed it */
};

static void job_unref(upload_job *j)
{
    int left;
    pthread_mutex_lock(&j->mu);
    left = --j->refs;
    pthread_mutex_unlock(&j->mu);
    if (!left) {
        pthread_cond_destroy(&j->cv);
        pthread_mutex_destroy(&j->mu);
        free(j);
    }
}

static void blob_write(upload_blob *b)
{
    b->rc = store_painting_blob_put(b->s, b->session, b->view, b->data, b->len, b->name,
                                    sizeof b->name, &b->err);
}

static void *blob_main(void *arg)
{
    upload_job *j = arg;
    pthread_mutex_lock(&j->mu);
    if (j->state == JOB_WAITING) {
        j->state = JOB_THREAD;
        pthread_mutex_unlock(&j->mu);
        blob_write(j->b);
        pthread_mutex_lock(&j->mu);
        j->state = JOB_DONE;
        pthread_cond_broadcast(&j->cv);
    }
    pthread_mutex_unlock(&j->mu);
    job_unref(j);
    return NULL;
}

void upload_blob_start(upload_blob *bw, store *s, const char *session, int view,
                       const void *data, size_t len)
{
    upload_job *j;
    pthread_attr_t at;
    pthread_t th;

    memset(bw, 0, sizeof *bw);
    bw->s = s;
    bw->session = session;
    bw->view = view;
    bw->data = data;
    bw->len = len;
    if (!(j = calloc(1, sizeof *j)))
        return; /* written at the join */
    pthread_mutex_init(&j->mu, NULL);
    pthread_cond_init(&j->cv, NULL);
    j->state = JOB_WAITING;
    j->refs = 2;
    j->b = bw;
    bw->job = j;
    if (pthread_attr_init(&at) == 0) {
        pthread_attr_setdetachstate(&at, PTHREAD_CREATE_DETACHED);
        if (pthread_create(&th, &at, blob_main, j) != 0)
            j->refs = 1; /* no thread: the join writes it */
        pthread_attr_destroy(&at);
    } else {
        j->refs = 1;
    }
}

int upload_blob_join(upload_blob *bw)
{
    upload_job *j = bw->job;
    int mine = 1;

    if (j) {
        pthread_mutex_lock(&j->mu);
        if (j->state == JOB_WAITING)
            j->state = JOB_CALLER;
        else {
            mine = 0;
            while (j->state != JOB_DONE)
                pthread_cond_wait(&j->cv, &j->mu);
        }
        pthread_mutex_unlock(&j->mu);
    }
    if (mine)
        blob_write(bw);
    bw->by_thread = !mine;
    if (j)
        job_unref(j);
    bw->job = NULL;
    return bw->rc;
}
