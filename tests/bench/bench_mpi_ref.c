/* bench_mpi_ref: the single-process route that glint-mpi is measured
 * against (tests/bench/bench_mpi.sh): the pattern of every view of a scene
 * (pattern_raster on T threads), hf3's design and its eig-route
 * decomposition (hf_decomp_build), saved under the key `glint fit` uses,
 * with the time of each step and the process's peak resident memory, as
 * one JSON line.
 *
 * usage: bench_mpi_ref scene.json CACHE_DIR RES LAMBDA [THREADS] */
#include <stdio.h>
#include <stdlib.h>

#include <sys/resource.h>

#include "clock.h"
#include "hf.h"
#include "pattern.h"
#include "pcache.h"
#include "samples.h"
#include "scene.h"

static void die(const char *what, const glint_err *e)
{
    fprintf(stderr, "bench_mpi_ref: %s: %s\n", what, e ? e->msg : "failed");
    exit(1);
}

int main(int argc, char **argv)
{
    scene sc;
    samples s;
    hf_design d;
    hf_decomp dc;
    glint_err e;
    struct rusage ru;
    unsigned char *use;
    char shash[33], key[33];
    int res, threads = 0;
    double lambda, t0, t_pattern, t_design, t_decomp, t_save;

    if (argc < 5 || argc > 6) {
        fprintf(stderr, "usage: bench_mpi_ref scene.json CACHE_DIR RES LAMBDA [THREADS]\n");
        return 1;
    }
    res = atoi(argv[3]);
    lambda = atof(argv[4]);
    if (argc == 6)
        threads = atoi(argv[5]);
    if (scene_load(argv[1], &sc, &e))
        die("scene", &e);
    if (!(use = malloc((size_t)sc.nviews)))
        die("out of memory", NULL);
    for (int v = 0; v < sc.nviews; v++)
        use[v] = 1;
    scene_hash(&sc, shash);
    t0 = glint_now();
    {
        pattern_in in = {&sc, use, SAMPLES_LIT, shash, 0, threads, NULL, NULL};
        if (pattern_raster(&in, &s, &e))
            die("pattern", &e);
    }
    t_pattern = glint_now() - t0;
    t0 = glint_now();
    if (hf_design_build(&s, res, &d, &e))
        die("design", &e);
    t_design = glint_now() - t0;
    t0 = glint_now();
    if (hf_decomp_build(&d, lambda, HF_ROUTE_EIG, 0.0, &dc, &e))
        die("decomposition", &e);
    t_decomp = glint_now() - t0;
    pcache_key_hf(s.hash, res, lambda, HF_ROUTE_EIG, 0.0, key);
    t0 = glint_now();
    if (pcache_decomp_save(argv[2], key, &dc, &e))
        die("save", &e);
    t_save = glint_now() - t0;
    getrusage(RUSAGE_SELF, &ru);
    printf("{\"key\": \"%s\", \"samples\": %d, \"res\": %d, \"rank\": %d, \"seconds\": "
           "{\"pattern\": %.4f, \"design\": %.4f, \"decomposition\": %.4f, \"save\": %.4f, "
           "\"total\": %.4f}, \"peak_rss_mb\": %.1f}\n", key, s.n, res, dc.rank, t_pattern,
           t_design, t_decomp, t_save, t_pattern + t_design + t_decomp + t_save,
           ru.ru_maxrss / 1024.0);
    hf_decomp_free(&dc);
    hf_design_free(&d);
    samples_free(&s);
    free(use);
    scene_free(&sc);
    return 0;
}
