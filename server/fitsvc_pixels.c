/* fitsvc_pixels.c: paintings' decoded pixels written behind (store.h,
 * "Decoded paintings").
 *
 * A painting stored by a PUT or a stroke is decoded once and held by the
 * memo; after a restart it would be decoded again from its PNG or OpenEXR
 * (1.5 to 4 ms a view, on the path of the first fit).  One thread writes
 * the pixels the memo holds beside the blob, off every request's path and
 * at a lower priority, once the view has rested PIXELS_REST_S (a burst of
 * strokes or uploads is written once, at its newest version, after it;
 * a view painted without pause is written every PIXELS_MAX_WAIT_S).  A
 * painting the memo no longer holds is not written (the next fit that
 * decodes it offers it again).  Pending writes are dropped at shutdown:
 * the pixels are a cache. */
#define _GNU_SOURCE
#include <pthread.h>
#include <string.h>
#include <time.h>
#include <sys/resource.h>
#include <unistd.h>

#include "clock.h"
#include "fitsvc_int.h"
#include "log.h"

#define PIXELS_QUEUE 64
#define PIXELS_REST_S 0.25
#define PIXELS_MAX_WAIT_S 10.0

typedef struct pix_item {
    char session[33];
    int view;
    long long version;
    double first, due;  /* glint_now(): first offered, to be written */
} pix_item;

struct pix_writer {
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t cond;
    pix_item q[PIXELS_QUEUE];
    int n, busy, stop;
    unsigned long long written, skipped, dropped, failed, read, decoded;
};

static void *writer_main(void *arg)
{
    fitsvc *f = arg;
    pix_writer *w = f->pix;

#ifdef __linux__
    /* below the requests' threads: on Linux a thread's own nice value */
    (void)setpriority(PRIO_PROCESS, (id_t)gettid(), 10);
#endif
    pthread_mutex_lock(&w->lock);
    for (;;) {
        pix_item it;
        memo_painting *pin = NULL;
        glint_err e;
        int rc;

        int k = 0;
        double now = glint_now();

        if (w->stop)
            break;
        if (!w->n) {
            pthread_cond_wait(&w->cond, &w->lock);
            continue;
        }
        for (int i = 1; i < w->n; i++)
            if (w->q[i].due < w->q[k].due)
                k = i;
        if (w->q[k].due > now) { /* not rested yet */
            struct timespec ts;
            double at;
            clock_gettime(CLOCK_MONOTONIC, &ts);
            at = (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec + (w->q[k].due - now);
            ts.tv_sec = (time_t)at;
            ts.tv_nsec = (long)((at - (double)ts.tv_sec) * 1e9);
            pthread_cond_timedwait(&w->cond, &w->lock, &ts);
            continue;
        }
        it = w->q[k];
        memmove(w->q + k, w->q + k + 1, (size_t)(--w->n - k) * sizeof *w->q);
        w->busy = 1;
        pthread_mutex_unlock(&w->lock);
        rc = memo_painting_get(f->memo, it.session, it.view, it.version, &pin);
        if (rc == 0) {
            rc = store_painting_pixels_put(f->st, it.session, it.view, it.version,
                                           memo_painting_img(pin), &e);
            memo_painting_release(f->memo, pin);
            if (rc && rc != GLINT_ECONFLICT && rc != GLINT_ENOTFOUND)
                log_line("keeping the pixels of session %s view %d: %s", it.session, it.view,
                         e.msg);
        }
        pthread_mutex_lock(&w->lock);
        w->busy = 0;
        if (rc == 0)
            w->written++;
        else if (rc == GLINT_ENOTFOUND || rc == GLINT_ECONFLICT)
            w->skipped++;
        else
            w->failed++;
        pthread_cond_broadcast(&w->cond);
    }
    pthread_mutex_unlock(&w->lock);
    return NULL;
}

int fitsvc_pixels_start(fitsvc *f, glint_err *err)
{
    pix_writer *w = calloc(1, sizeof *w);
    pthread_condattr_t ca;
    if (!w)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    pthread_mutex_init(&w->lock, NULL);
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC); /* glint_now's clock */
    pthread_cond_init(&w->cond, &ca);
    pthread_condattr_destroy(&ca);
    f->pix = w;
    if (pthread_create(&w->thread, NULL, writer_main, f) != 0) {
        pthread_cond_destroy(&w->cond);
        pthread_mutex_destroy(&w->lock);
        free(w);
        f->pix = NULL;
        return glint_err_set(err, GLINT_EIO, "cannot start the pixel writer's thread");
    }
    return 0;
}

void fitsvc_pixels_stop(fitsvc *f)
{
    pix_writer *w = f->pix;
    if (!w)
        return;
    pthread_mutex_lock(&w->lock);
    w->stop = 1;
    pthread_cond_broadcast(&w->cond);
    pthread_mutex_unlock(&w->lock);
    pthread_join(w->thread, NULL);
    pthread_cond_destroy(&w->cond);
    pthread_mutex_destroy(&w->lock);
    free(w);
    f->pix = NULL;
}

void fitsvc_painting_stored(fitsvc *f, const char *session, int view, long long version)
{
    pix_writer *w = f ? f->pix : NULL;
    double now = glint_now();
    int i;
    if (f)
        fitsvc_busy(f, 0); /* the painters are at work: held-out measurements wait */
    if (!w || strlen(session) >= sizeof w->q[0].session)
        return;
    pthread_mutex_lock(&w->lock);
    for (i = 0; i < w->n; i++)
        if (w->q[i].view == view && strcmp(w->q[i].session, session) == 0)
            break;
    if (i == w->n) {
        if (w->n == PIXELS_QUEUE) { /* the oldest goes: a fit decodes it if it must */
            memmove(w->q, w->q + 1, (size_t)(--w->n) * sizeof *w->q);
            w->dropped++;
            i = w->n;
        }
        w->n++;
        strcpy(w->q[i].session, session);
        w->q[i].view = view;
        w->q[i].first = now;
    } else {
        w->skipped++; /* the queued older version is not written */
    }
    w->q[i].version = version;
    w->q[i].due = now + PIXELS_REST_S;
    if (w->q[i].due > w->q[i].first + PIXELS_MAX_WAIT_S)
        w->q[i].due = w->q[i].first + PIXELS_MAX_WAIT_S;
    pthread_cond_broadcast(&w->cond);
    pthread_mutex_unlock(&w->lock);
}

void fitsvc_pixels_count(fitsvc *f, int read, int decoded)
{
    pix_writer *w = f->pix;
    if (!w)
        return;
    pthread_mutex_lock(&w->lock);
    w->read += (unsigned long long)read;
    w->decoded += (unsigned long long)decoded;
    pthread_mutex_unlock(&w->lock);
}

void fitsvc_pixels_metrics(fitsvc *f, FILE *o)
{
    pix_writer *w = f->pix;
    unsigned long long c[6];
    int queued, writing;
    if (!w)
        return;
    pthread_mutex_lock(&w->lock);
    queued = w->n;
    writing = w->busy;
    c[0] = w->written;
    c[1] = w->skipped;
    c[2] = w->dropped;
    c[3] = w->failed;
    c[4] = w->read;
    c[5] = w->decoded;
    pthread_mutex_unlock(&w->lock);
    fprintf(o, "# HELP glintd_painting_pixels_writes_total Decoded paintings kept beside their "
               "uploads, by outcome (skipped: painted again or gone first; dropped: the queue "
               "was full).\n# TYPE glintd_painting_pixels_writes_total counter\n");
    fprintf(o, "glintd_painting_pixels_writes_total{outcome=\"written\"} %llu\n", c[0]);
    fprintf(o, "glintd_painting_pixels_writes_total{outcome=\"skipped\"} %llu\n", c[1]);
    fprintf(o, "glintd_painting_pixels_writes_total{outcome=\"dropped\"} %llu\n", c[2]);
    fprintf(o, "glintd_painting_pixels_writes_total{outcome=\"failed\"} %llu\n", c[3]);
    fprintf(o, "# HELP glintd_painting_pixels_queue Decoded paintings waiting to be kept, and "
               "being written.\n# TYPE glintd_painting_pixels_queue gauge\n");
    fprintf(o, "glintd_painting_pixels_queue{state=\"queued\"} %d\n", queued);
    fprintf(o, "glintd_painting_pixels_queue{state=\"writing\"} %d\n", writing);
    fprintf(o, "# HELP glintd_painting_reads_total Paintings a fit read from the store (not "
               "the memo), by how: their kept pixels, or decoded from the upload.\n"
               "# TYPE glintd_painting_reads_total counter\n");
    fprintf(o, "glintd_painting_reads_total{from=\"pixels\"} %llu\n", c[4]);
    fprintf(o, "glintd_painting_reads_total{from=\"decoded\"} %llu\n", c[5]);
}
