/* pattern_raster.c: a scene's sampling pattern rasterized on several
 * threads (pattern.h).
 *
 * The used views are numbered k = 0..nused-1 in view order.  Workers take
 * the next k from a shared counter, rasterize that view band by band into
 * part[k] and mark it ready; the calling thread appends ready parts in k
 * order, frees them and reports progress.  A worker may start part k only
 * while k < committed + WINDOW * workers, which bounds the parts held.
 * Everything shared is under one mutex, except `stop`, an atomic flag the
 * workers poll between bands. */
#include "pattern.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "raster.h"

/* Parts a worker may run ahead of the appending, per worker. */
#define WINDOW 2

/* View v's samples, a band of band_rows rows at a time, into s (begun);
 * stops early (returning 0) when *stop is set. */
static int view_samples(const scene *sc, int v, int band_rows, samples *s, atomic_int *stop,
                        glint_err *err)
{
    int rc = 0;
    for (int row0 = 0; row0 < sc->height && !rc; row0 += band_rows) {
        int nrows = sc->height - row0 < band_rows ? sc->height - row0 : band_rows;
        gbuf g;
        if (stop && atomic_load(stop))
            return 0;
        if ((rc = raster_view_rows(&sc->mesh, &sc->views[v], sc->width, sc->height, row0, nrows,
                                   &g, err)))
            break;
        rc = samples_add(s, v, &g, row0, view_light_scale(&sc->views[v]), err);
        gbuf_free(&g);
    }
    if (rc)
        glint_err_prefix(err, "rasterizing view %d", v);
    return rc;
}

typedef struct shared {
    const pattern_in *in;
    int band_rows;
    int nused;
    const int *views;        /* nused: the used views in order */
    samples *part;           /* nused */
    unsigned char *ready;    /* nused: part k finished */
    int next;                /* the next part to take */
    int committed;           /* parts appended to the pattern */
    int window;              /* parts that may run ahead of the appending */
    int rc;                  /* the first error (0: none) */
    glint_err err;
    atomic_int stop;         /* set with rc: workers stop at their next band */
    pthread_mutex_t lock;
    pthread_cond_t cond;
} shared;

/* The first error wins (lock held). */
static void fail_locked(shared *sh, int rc, const glint_err *e)
{
    if (sh->rc)
        return;
    sh->rc = rc;
    sh->err = *e;
    atomic_store(&sh->stop, 1);
    pthread_cond_broadcast(&sh->cond);
}

static void *worker(void *arg)
{
    shared *sh = arg;
    const scene *sc = sh->in->sc;

    pthread_mutex_lock(&sh->lock);
    for (;;) {
        glint_err e;
        int k, rc;
        while (!sh->rc && sh->next < sh->nused && sh->next >= sh->committed + sh->window)
            pthread_cond_wait(&sh->cond, &sh->lock);
        if (sh->rc || sh->next >= sh->nused)
            break;
        k = sh->next++;
        pthread_mutex_unlock(&sh->lock);

        glint_err_clear(&e);
        rc = samples_begin(&sh->part[k], sc->nviews, sc->width, sc->height, &e);
        if (!rc) {
            samples_set_rule(&sh->part[k], sh->in->rule);
            rc = view_samples(sc, sh->views[k], sh->band_rows, &sh->part[k], &sh->stop, &e);
        }

        pthread_mutex_lock(&sh->lock);
        if (rc) {
            fail_locked(sh, rc, &e);
            break;
        }
        sh->ready[k] = 1;
        pthread_cond_broadcast(&sh->cond);
    }
    pthread_mutex_unlock(&sh->lock);
    return NULL;
}

/* On the calling thread alone, view after view. */
static int raster_serial(const pattern_in *in, int band_rows, int nused, samples *s,
                         glint_err *err)
{
    const scene *sc = in->sc;
    int rc, done = 0;

    if ((rc = samples_begin(s, sc->nviews, sc->width, sc->height, err)))
        return rc;
    samples_set_rule(s, in->rule);
    for (int v = 0; v < sc->nviews && !rc; v++) {
        if (!in->use[v])
            continue;
        if (!(rc = view_samples(sc, v, band_rows, s, NULL, err)) && in->progress)
            in->progress(in->cls, ++done, nused);
    }
    return rc ? rc : samples_end(s, in->use, in->scene_hash, err);
}

/* Append the parts in order as the workers finish them (the calling
 * thread's share of a parallel build). */
static void append_parts(shared *sh, samples *s)
{
    const pattern_in *in = sh->in;

    pthread_mutex_lock(&sh->lock);
    while (!sh->rc && sh->committed < sh->nused) {
        int k = sh->committed, rc;
        glint_err e;
        while (!sh->rc && !sh->ready[k])
            pthread_cond_wait(&sh->cond, &sh->lock);
        if (sh->rc)
            break;
        pthread_mutex_unlock(&sh->lock);

        glint_err_clear(&e);
        rc = samples_append(s, &sh->part[k], &e);
        samples_free(&sh->part[k]);
        if (!rc && in->progress)
            in->progress(in->cls, k + 1, sh->nused);

        pthread_mutex_lock(&sh->lock);
        if (rc) {
            fail_locked(sh, rc, &e);
            break;
        }
        sh->committed++;
        pthread_cond_broadcast(&sh->cond); /* the window moves on */
    }
    pthread_mutex_unlock(&sh->lock);
}

static int raster_parallel(const pattern_in *in, int band_rows, int nused, int nt, samples *s,
                           int *threaded, glint_err *err)
{
    const scene *sc = in->sc;
    pthread_t th[PATTERN_MAX_THREADS];
    int views[SCENE_MAX_VIEWS], started = 0, rc;
    shared sh;

    *threaded = 0;
    memset(&sh, 0, sizeof sh);
    sh.in = in;
    sh.band_rows = band_rows;
    sh.nused = nused;
    sh.views = views;
    atomic_init(&sh.stop, 0);
    for (int v = 0, k = 0; v < sc->nviews; v++)
        if (in->use[v])
            views[k++] = v;
    sh.part = calloc((size_t)nused, sizeof *sh.part);
    sh.ready = calloc((size_t)nused, 1);
    if (!sh.part || !sh.ready) {
        free(sh.part);
        free(sh.ready);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    if ((rc = samples_begin(s, sc->nviews, sc->width, sc->height, err))) {
        free(sh.part);
        free(sh.ready);
        return rc;
    }
    samples_set_rule(s, in->rule);
    sh.window = WINDOW * nt;
    pthread_mutex_init(&sh.lock, NULL);
    pthread_cond_init(&sh.cond, NULL);
    for (int t = 0; t < nt; t++) {
        if (pthread_create(&th[t], NULL, worker, &sh))
            break; /* fewer workers: the queue shares the views among those started */
        started++;
    }
    if (started) {
        *threaded = 1;
        append_parts(&sh, s);
        for (int t = 0; t < started; t++)
            pthread_join(th[t], NULL);
        rc = sh.rc; /* every thread is done: no lock needed */
        if (rc && err)
            *err = sh.err;
    }
    for (int k = 0; k < nused; k++)
        samples_free(&sh.part[k]);
    free(sh.part);
    free(sh.ready);
    pthread_cond_destroy(&sh.cond);
    pthread_mutex_destroy(&sh.lock);
    if (!started) {
        samples_free(s);
        return 0; /* no thread at all: the caller goes serial */
    }
    return rc ? rc : samples_end(s, in->use, in->scene_hash, err);
}

int pattern_raster(const pattern_in *in, samples *out, glint_err *err)
{
    const scene *sc = in->sc;
    int band_pixels = in->band_pixels > 0 ? in->band_pixels : PATTERN_BAND_PIXELS;
    int band_rows, nused = 0, rc, threaded = 0;
    long nt = in->nthreads > 0 ? in->nthreads : sysconf(_SC_NPROCESSORS_ONLN);

    memset(out, 0, sizeof *out);
    if (!sc || !in->use || sc->nviews < 1 || sc->nviews > SCENE_MAX_VIEWS || sc->width < 1)
        return glint_err_set(err, GLINT_EINVAL, "pattern_raster: no scene or no views");
    band_rows = band_pixels / sc->width;
    if (band_rows < 1)
        band_rows = 1;
    for (int v = 0; v < sc->nviews; v++)
        nused += in->use[v] != 0;
    if (nt > nused)
        nt = nused;
    if (nt > PATTERN_MAX_THREADS)
        nt = PATTERN_MAX_THREADS;
    if (nt > 1) {
        rc = raster_parallel(in, band_rows, nused, (int)nt, out, &threaded, err);
        if (threaded) {
            if (rc)
                samples_free(out);
            return rc;
        }
    }
    if ((rc = raster_serial(in, band_rows, nused, out, err)))
        samples_free(out);
    return rc;
}
