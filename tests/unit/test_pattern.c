/* Tests of the sampling pattern's parallel rasterization (core/pattern.h):
 * a pattern made by several threads is the serial one bit for bit (rules
 * LIT and SEEN, views left out, bands of rows), and an error on any thread
 * is reported. */
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "pattern.h"
#include "raster.h"
#include "samples.h"
#include "scene.h"

static scene SC; /* 56x40 */
static gbuf *G;
static char HASH[33];
static const unsigned char USE[12] = {1, 0, 1, 1, 0, 0, 1, 0, 1, 1, 1, 0};

static int setup(void)
{
    scene_params p;
    glint_err e;
    if (G)
        return 0;
    scene_params_default(&p);
    p.width = 56;
    p.height = 40;
    if (scene_create(&p, &SC, &e) || raster_scene(&SC, &G, &e))
        goto fail;
    scene_hash(&SC, HASH);
    return 0;
fail:
    fprintf(stderr, "setup: %s\n", e.msg);
    return -1;
}

/* Every field and array of a and b equal, bit for bit. */
static int same_samples(const samples *a, const samples *b)
{
    size_t n = (size_t)a->n;
    if (a->n != b->n || a->nviews != b->nviews || a->width != b->width ||
        a->height != b->height || a->rule != b->rule || a->has_pos != b->has_pos ||
        strcmp(a->hash, b->hash) != 0 || memcmp(a->used, b->used, (size_t)a->nviews) != 0)
        return 0;
    return memcmp(a->view, b->view, n * sizeof *a->view) == 0 &&
           memcmp(a->pixel, b->pixel, n * sizeof *a->pixel) == 0 &&
           memcmp(a->nrm, b->nrm, 3 * n * sizeof *a->nrm) == 0 &&
           memcmp(a->wi, b->wi, 3 * n * sizeof *a->wi) == 0 &&
           memcmp(a->wo, b->wo, 3 * n * sizeof *a->wo) == 0 &&
           memcmp(a->pos, b->pos, 3 * n * sizeof *a->pos) == 0 &&
           memcmp(a->uv, b->uv, 2 * n * sizeof *a->uv) == 0 &&
           memcmp(a->cos_i, b->cos_i, n * sizeof *a->cos_i) == 0 &&
           memcmp(a->intensity, b->intensity, n * sizeof *a->intensity) == 0;
}

typedef struct progress_log {
    pthread_t caller;
    int calls, last, total, wrong_thread;
} progress_log;

static void on_progress(void *cls, int done, int nused)
{
    progress_log *l = cls;
    if (!pthread_equal(pthread_self(), l->caller))
        l->wrong_thread++;
    if (done != l->last + 1)
        l->last = -1000; /* out of order: stays wrong */
    else
        l->last = done;
    l->total = nused;
    l->calls++;
}

static int raster(const scene *sc, const char *hash, const unsigned char *use, int rule,
                  int nthreads, int band_rows, progress_log *log, samples *out, glint_err *e)
{
    pattern_in in = {sc, use, rule, hash, band_rows * sc->width, nthreads,
                     log ? on_progress : NULL, log};
    if (log) {
        memset(log, 0, sizeof *log);
        log->caller = pthread_self();
    }
    return pattern_raster(&in, out, e);
}

TEST(parallel_rasterization_is_the_serial_one_bit_for_bit)
{
    static const int threads[] = {2, 3, 4, 12, 0};
    samples whole, serial, par;
    progress_log log;
    glint_err e;

    ASSERT_OK(setup());
    for (int rule = SAMPLES_LIT; rule <= SAMPLES_SEEN; rule++) {
        /* the serial path is samples_build's pattern of whole G-buffers */
        ASSERT_OK(samples_begin(&whole, SC.nviews, SC.width, SC.height, &e));
        samples_set_rule(&whole, rule);
        for (int v = 0; v < SC.nviews; v++)
            if (USE[v])
                ASSERT_OK(samples_add(&whole, v, &G[v], 0, SC.views[v].light_intensity, &e));
        ASSERT_OK(samples_end(&whole, USE, HASH, &e));
        ASSERT_OK(raster(&SC, HASH, USE, rule, 1, 7, &log, &serial, &e));
        ASSERT(same_samples(&whole, &serial));
        ASSERT(log.calls == 7 && log.last == 7 && log.total == 7 && !log.wrong_thread);
        for (size_t t = 0; t < sizeof threads / sizeof *threads; t++)
            for (int band = 1; band <= 40; band += 13) {
                ASSERT_OK(raster(&SC, HASH, USE, rule, threads[t], band, &log, &par, &e));
                ASSERT_MSG(same_samples(&serial, &par), "rule %d, %d threads, bands of %d rows",
                           rule, threads[t], band);
                ASSERT_MSG(log.calls == 7 && log.last == 7 && log.total == 7 &&
                               !log.wrong_thread,
                           "progress: %d calls, last %d of %d, %d on other threads", log.calls,
                           log.last, log.total, log.wrong_thread);
                samples_free(&par);
            }
        if (rule == SAMPLES_SEEN) /* the SEEN rule takes unlit pixels too */
            ASSERT(serial.n > 0);
        samples_free(&whole);
        samples_free(&serial);
    }
    {
        samples lit, seen;
        ASSERT_OK(raster(&SC, HASH, USE, SAMPLES_LIT, 2, 40, NULL, &lit, &e));
        ASSERT_OK(raster(&SC, HASH, USE, SAMPLES_SEEN, 2, 40, NULL, &seen, &e));
        ASSERT_LT(lit.n, seen.n);
        ASSERT(strcmp(lit.hash, seen.hash) != 0);
        samples_free(&lit);
        samples_free(&seen);
    }
    /* one view alone, and no view with a sample */
    {
        unsigned char one[12] = {0}, none[12] = {0};
        one[6] = 1;
        ASSERT_OK(raster(&SC, HASH, one, SAMPLES_LIT, 0, 40, NULL, &par, &e));
        ASSERT(par.n > 0 && par.used[6] && par.view[0] == 6 && par.view[par.n - 1] == 6);
        samples_free(&par);
        ASSERT_EQ(raster(&SC, HASH, none, SAMPLES_LIT, 2, 40, NULL, &par, &e), GLINT_EINVAL);
        ASSERT(par.n == 0 && par.view == NULL);
    }
}

TEST(an_error_on_any_thread_is_reported)
{
    scene bad;
    samples s;
    glint_err e;

    ASSERT_OK(setup());
    bad = SC;
    bad.views = malloc((size_t)SC.nviews * sizeof *bad.views);
    ASSERT(bad.views);
    memcpy(bad.views, SC.views, (size_t)SC.nviews * sizeof *bad.views);
    /* a degenerate camera in view 8 (used), late in the pattern */
    memcpy(bad.views[8].target, bad.views[8].eye, sizeof bad.views[8].eye);
    for (int nt = 1; nt <= 4; nt++)
        for (int band = 1; band <= 40; band += 39) {
            glint_err_clear(&e);
            ASSERT_EQ(raster(&bad, HASH, USE, SAMPLES_LIT, nt, band, NULL, &s, &e), GLINT_EINVAL);
            ASSERT_MSG(strstr(e.msg, "rasterizing view 8") != NULL, "%d threads: %s", nt,
                       e.msg);
            ASSERT(s.n == 0 && s.view == NULL && s.used == NULL);
        }
    /* two: either may be first, one is reported */
    memcpy(bad.views[2].target, bad.views[2].eye, sizeof bad.views[2].eye);
    ASSERT_EQ(raster(&bad, HASH, USE, SAMPLES_LIT, 2, 3, NULL, &s, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "rasterizing view 8") || strstr(e.msg, "rasterizing view 2"));
    free(bad.views);
}

TEST_LIST{
    TEST_ENTRY(parallel_rasterization_is_the_serial_one_bit_for_bit),
    TEST_ENTRY(an_error_on_any_thread_is_reported),
};

TEST_MAIN()
