/* bench_pattern: the sampling pattern of a scene, made and kept (pattern.h).
 *
 * For the default 12-view sphere scene at SIZE x SIZE (default 256) with
 * every view used: rasterizing its pattern on one thread and on the
 * machine's cores (and checking both are the same, bit for bit), writing
 * its cache file, and loading it back (pattern_load, and through the
 * cache the way a restarted daemon does).  Times are medians; loads read a
 * file the page cache holds, as a daemon's recent files are.
 *
 * usage: bench_pattern [--size N] [--reps R] [--dir DIR]
 *   (DIR: where the file goes, default a new directory under /tmp) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cache.h"
#include "clock.h"
#include "method.h"
#include "pattern.h"
#include "prep.h"
#include "samples.h"
#include "scene.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static void die(const char *what, const glint_err *e)
{
    fprintf(stderr, "bench_pattern: %s: %s\n", what, e ? e->msg : "failed");
    exit(1);
}

static int same(const samples *a, const samples *b)
{
    size_t n = (size_t)a->n;
    return a->n == b->n && strcmp(a->hash, b->hash) == 0 &&
           memcmp(a->view, b->view, n * sizeof *a->view) == 0 &&
           memcmp(a->pixel, b->pixel, n * sizeof *a->pixel) == 0 &&
           memcmp(a->nrm, b->nrm, 3 * n * sizeof *a->nrm) == 0 &&
           memcmp(a->wi, b->wi, 3 * n * sizeof *a->wi) == 0 &&
           memcmp(a->wo, b->wo, 3 * n * sizeof *a->wo) == 0 &&
           memcmp(a->pos, b->pos, 3 * n * sizeof *a->pos) == 0 &&
           memcmp(a->uv, b->uv, 2 * n * sizeof *a->uv) == 0 &&
           memcmp(a->cos_i, b->cos_i, n * sizeof *a->cos_i) == 0 &&
           memcmp(a->intensity, b->intensity, n * sizeof *a->intensity) == 0;
}

static int no_fit(const method_fit_in *in, struct material *out, glint_err *err)
{
    (void)in;
    (void)out;
    return glint_err_set(err, GLINT_EUNSUPPORTED, "no fit");
}

/* A method of no level of its own: its preparation is the pattern. */
static const method M = {.name = "pattern-only", .params_size = sizeof(int), .fit = no_fit};

static int borrowed(void *cls, const char *id, const scene **out, glint_err *err)
{
    (void)id;
    (void)err;
    *out = cls;
    return 0;
}

int main(int argc, char **argv)
{
    int size = 256, reps = 5, param = 0, made = 0;
    char dir[512] = "", key[CACHE_KEY_MAX], name[64], path[600];
    double t_ser[64], t_par[64], t_load[64], t_cache[64], t_save;
    unsigned char use[SCENE_MAX_VIEWS];
    scene_params sp;
    scene sc;
    char hash[33];
    samples ser, par, ld;
    struct stat st;
    glint_err e;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);

    for (int a = 1; a < argc; a++) {
        if (strcmp(argv[a], "--size") == 0 && a + 1 < argc)
            size = atoi(argv[++a]);
        else if (strcmp(argv[a], "--reps") == 0 && a + 1 < argc)
            reps = atoi(argv[++a]);
        else if (strcmp(argv[a], "--dir") == 0 && a + 1 < argc)
            snprintf(dir, sizeof dir, "%s", argv[++a]);
        else {
            fprintf(stderr, "usage: bench_pattern [--size N] [--reps R] [--dir DIR]\n");
            return 2;
        }
    }
    if (reps < 1 || reps > 64 || size < SCENE_MIN_SIZE || size > SCENE_MAX_SIZE) {
        fprintf(stderr, "bench_pattern: --reps 1..64, --size %d..%d\n", SCENE_MIN_SIZE,
                SCENE_MAX_SIZE);
        return 2;
    }
    if (!*dir) {
        snprintf(dir, sizeof dir, "/tmp/glint-bench-pattern-XXXXXX");
        if (!mkdtemp(dir)) {
            perror("mkdtemp");
            return 1;
        }
        made = 1;
    }
    scene_params_default(&sp);
    sp.width = sp.height = size;
    if (scene_create(&sp, &sc, &e))
        die("scene", &e);
    scene_hash(&sc, hash);
    memset(use, 1, sizeof use);

    for (int r = 0; r < reps; r++) {
        pattern_in in = {&sc, use, SAMPLES_LIT, hash, PREP_BAND_PIXELS, 1, NULL, NULL};
        double t0 = glint_now();
        if (pattern_raster(&in, &ser, &e))
            die("serial", &e);
        t_ser[r] = glint_now() - t0;
        in.nthreads = 0;
        t0 = glint_now();
        if (pattern_raster(&in, &par, &e))
            die("parallel", &e);
        t_par[r] = glint_now() - t0;
        if (!same(&ser, &par))
            die("the parallel pattern differs from the serial one", NULL);
        if (r + 1 < reps) {
            samples_free(&ser);
            samples_free(&par);
        }
    }

    /* the file, under the key prep gives this pattern */
    {
        prep_scene ps;
        memset(&ps, 0, sizeof ps);
        ps.sc = &sc;
        memcpy(ps.hash, hash, sizeof ps.hash);
        prep_pattern_key(&ps, use, SAMPLES_LIT, key);
    }
    pattern_file_name(key, name, sizeof name);
    snprintf(path, sizeof path, "%s/%s", dir, name);
    {
        double t0 = glint_now();
        if (pattern_save(&par, dir, key, &e))
            die("save", &e);
        t_save = glint_now() - t0;
    }
    if (stat(path, &st))
        die("stat of the file", NULL);
    for (int r = 0; r < reps; r++) {
        double t0 = glint_now();
        if (pattern_load(dir, key, &sc, hash, use, SAMPLES_LIT, &ld, &e))
            die("load", &e);
        t_load[r] = glint_now() - t0;
        if (!same(&ld, &par))
            die("the loaded pattern differs", NULL);
        samples_free(&ld);
    }
    /* through the cache, as after a restart: a new cache each time */
    for (int r = 0; r < reps; r++) {
        prep_scene_source src = {borrowed, NULL, &sc};
        cache *c;
        cache_entry *se;
        prep *p;
        prep_request rq = {&M, &param, NULL, use, NULL};
        double t0;
        if (cache_open(dir, (size_t)1 << 30, &c, &e) || prep_scene_acquire(c, "s", &src, &se, &e))
            die("cache", &e);
        rq.scene = se;
        t0 = glint_now();
        if (prep_acquire(c, &rq, NULL, NULL, &p, &e))
            die("prep_acquire", &e);
        t_cache[r] = glint_now() - t0;
        if (cache_disk_of(prep_pattern(p)) != CACHE_DISK_LOADED)
            die("the pattern was not loaded from disk", NULL);
        prep_release(c, p);
        cache_release(c, se);
        cache_close(c);
    }

    printf("pattern of the %d-view sphere scene at %dx%d: %d samples, %d cores\n", sc.nviews,
           size, size, par.n, (int)cores);
    printf("  rasterize, 1 thread         %8.1f ms\n", 1e3 * median(t_ser, reps));
    printf("  rasterize, %2ld threads       %8.1f ms  (same bits)\n",
           cores > sc.nviews ? sc.nviews : cores > PATTERN_MAX_THREADS ? PATTERN_MAX_THREADS : cores,
           1e3 * median(t_par, reps));
    printf("  write the file              %8.1f ms  (%.1f MB, fsync included)\n", 1e3 * t_save,
           (double)st.st_size / 1e6);
    printf("  load the file (pattern_load)%8.1f ms\n", 1e3 * median(t_load, reps));
    printf("  load through the cache      %8.1f ms  (prep_acquire after a restart)\n",
           1e3 * median(t_cache, reps));
    samples_free(&ser);
    samples_free(&par);
    unlink(path);
    if (made)
        rmdir(dir);
    scene_free(&sc);
    return 0;
}
