/* bench_matmap: material maps (core/methods/maps/matmap.c) beside seed 000, Table 3.
 *
 *   bench_matmap [--reps N]
 *
 * Seed 000 Table 3 recovers material maps of 5, 10, 15 and 20 BRDFs from
 * 7884 samples at coefficient resolutions 32 and 128 (2.44-12.09 s and
 * 3.96-17.79 s).  Here: the built-in sphere at 64x64, the first views whose
 * samples reach 7884 or more, painted with red plastic and gold stripes
 * (two materials over the texture coordinates); the three-factor method at
 * its default parameters, prepared once (its cold time printed); then
 * matmap_fit with 5, 10, 15 and 20 products (tolerance 0, so only the count
 * or a product that gains under 0.1% stops it) at coefficient resolutions
 * 32 and 128, under both coefficient rules.  Each time is the best of N
 * fits (default 5); the relative RMS is the residual's after the last
 * product.  Nothing is asserted: the figures go to BENCHMARKS.md. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cache.h"
#include "clock.h"
#include "fit.h"
#include "matmap.h"
#include "method_hf3.h"
#include "paint.h"
#include "prep.h"
#include "raster.h"
#include "samples.h"

static int borrowed(void *cls, const char *id, const scene **out, glint_err *err)
{
    (void)id;
    (void)err;
    *out = cls;
    return 0;
}

int main(int argc, char **argv)
{
    static const char *spec = "stripes:freq=3,duty=0.5|lambert:kd=0.7/0.15/0.1|"
                              "ct:kd=0.05,f0=0.9/0.7/0.3,rough=0.25";
    static const int ks[4] = {5, 10, 15, 20}, resv[2] = {32, 128};
    scene_params sp;
    scene sc;
    gbuf *g = NULL;
    fit_params fp;
    unsigned char use[SCENE_MAX_VIEWS] = {0};
    prep_scene_source src = {borrowed, NULL, &sc};
    cache *c = NULL;
    cache_entry *se = NULL;
    prep *p = NULL;
    img im[SCENE_MAX_VIEWS];
    paint_sv sv;
    float *rgb = NULL;
    glint_err e;
    long total = 0;
    int reps = 5, nv = 0;
    double t0;

    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--reps") && i + 1 < argc && atoi(argv[i + 1]) > 0) {
            reps = atoi(argv[++i]);
        } else {
            fprintf(stderr, "usage: bench_matmap [--reps N]\n");
            return 2;
        }
    }
    scene_params_default(&sp);
    sp.width = sp.height = 64;
    fit_params_default(&fp);
    memset(im, 0, sizeof im);
    if (scene_create(&sp, &sc, &e) || raster_scene(&sc, &g, &e) ||
        paint_sv_parse(spec, &sv, &e) ||
        paint_views_sv(&sv, g, sc.views, sc.nviews, 1.0, im, NULL, &e))
        goto fail;
    while (nv < sc.nviews && total < 7884) {
        total += samples_count(&g[nv]);
        use[nv++] = 1;
    }
    if (cache_open(NULL, (size_t)1 << 30, &c, &e) || prep_scene_acquire(c, "s", &src, &se, &e))
        goto fail;
    {
        prep_request rq = {&method_hf3, &fp, se, use, NULL};
        t0 = glint_now();
        if (prep_acquire(c, &rq, NULL, NULL, &p, &e))
            goto fail;
        t0 = glint_now() - t0;
    }
    {
        const samples *s = prep_samples(p);
        if (!(rgb = malloc(3 * (size_t)s->n * sizeof *rgb)) || samples_gather(s, im, rgb, &e))
            goto fail;
        printf("## material maps beside seed 000 Table 3 (sphere 64x64, %d views, %d samples, "
               "three factors at res %d, prepared in %.3f s)\n\n", nv, s->n, fp.res, t0);
    }
    printf("| rule | products asked | coefficient res | stage | products made | stop | "
           "seconds (best of %d) | rel RMS after 1 | model rel RMS |\n", reps);
    printf("|---|---|---|---|---|---|---|---|---|\n");
    for (int rule = 0; rule < 2; rule++)
        for (int ri = 0; ri < 2; ri++)
            for (int stage = 0; stage < (rule ? 1 : 2); stage++)
                for (int ki = 0; ki < 4; ki++) {
                    matmap_params mp;
                    matmap mm;
                    double best = 1e30, r1 = 0.0, rl = 0.0;
                    int made = 0, rounds = 0;
                    const char *stop = "";
                    matmap_params_default(&mp);
                    mp.merge = rule ? MATMAP_MERGE_MIN : MATMAP_MERGE_LSQ;
                    mp.components = ks[ki];
                    mp.res = resv[ri];
                    mp.tol = 0.0;
                    if (stage == 0) /* the greedy products alone */
                        mp.refine = mp.rounds = 0;
                    for (int r = 0; r < reps; r++) {
                        if (matmap_fit(p, rgb, &mp, &mm, &e))
                            goto fail;
                        best = mm.seconds < best ? mm.seconds : best;
                        made = mm.k;
                        stop = mm.stop;
                        r1 = mm.rel_rms[1];
                        rl = mm.model_rel_rms[1];
                        rounds = mm.rounds;
                        matmap_free(&mm);
                    }
                    printf("| %s | %d | %d | %s | %d | %s | %.4f | %.4f | %.4f |\n",
                           rule ? "min" : "lsq", ks[ki], resv[ri],
                           stage ? (rounds ? "refined, back-fitted" : "refined") : "greedy",
                           made, stop, best, r1, rl);
                }
    free(rgb);
    for (int v = 0; v < sc.nviews; v++)
        img_free(&im[v]);
    prep_release(c, p);
    cache_release(c, se);
    cache_close(c);
    return 0;
fail:
    fprintf(stderr, "bench_matmap: %s\n", e.msg);
    return 1;
}
