/* bench_hf4: the four-factor product (hf4.h) beside seed 000, Table 1's
 * four-factor columns (247-506 s by SVD, 1.26-1.69 s by the fast method).
 *
 *   bench_hf4 [--reps N] [--samples M] [--lambda-s L] [--rcond C]
 *
 * The built-in sphere at 64x64, its first views whose samples reach 7884
 * (seed 000's count), painted with one finish whose colour varies over the
 * texture coordinates (soft stripes of two diffuse colours under the same
 * highlight).  For 1D resolution 32 and spatial resolutions 16, 32, 48 and
 * 64: the design, the decomposition (its form, unknowns, rank), one fit,
 * and the painted-view RMS, each time the best of N (default 3).  With
 * --samples M every k-th sample is kept so that about M remain (Table 2
 * of seed 000 used 317); --lambda-s sets the weight of s's Laplacian
 * (default 0.1; 0 leaves fewer rows than unknowns on few samples, and the
 * dense form is taken); --rcond the relative cut of the kept singular
 * values (default HF4_RCOND_DEFAULT).  Nothing is asserted: the figures go to
 * BENCHMARKS.md. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "hf4.h"
#include "paint.h"
#include "raster.h"
#include "samples.h"

#define SPEC                                                                                    \
    "stripes:freq=3,duty=0.5,soft=0.3|ct:kd=0.6/0.3/0.2,f0=0.04,rough=0.3|"                     \
    "ct:kd=0.2/0.1/0.07,f0=0.013,rough=0.3"

int main(int argc, char **argv)
{
    static const int sres[4] = {16, 32, 48, 64};
    scene_params sp;
    scene sc;
    gbuf *g = NULL;
    img im[SCENE_MAX_VIEWS];
    unsigned char use[SCENE_MAX_VIEWS] = {0};
    samples s;
    paint_sv sv;
    hf_map map;
    float *rgb = NULL;
    char hash[33];
    glint_err e;
    long total = 0;
    int reps = 3, nv = 0, want = 0;
    double lambda_s = 0.1, rcond = 0.0;

    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--reps") && i + 1 < argc && atoi(argv[i + 1]) > 0) {
            reps = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--samples") && i + 1 < argc && atoi(argv[i + 1]) > 0) {
            want = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--lambda-s") && i + 1 < argc && atof(argv[i + 1]) >= 0) {
            lambda_s = atof(argv[++i]);
        } else if (!strcmp(argv[i], "--rcond") && i + 1 < argc && atof(argv[i + 1]) > 0 &&
                   atof(argv[i + 1]) < 1) {
            rcond = atof(argv[++i]);
        } else {
            fprintf(stderr, "usage: bench_hf4 [--reps N] [--samples M] [--lambda-s L] [--rcond C]\n");
            return 2;
        }
    }
    scene_params_default(&sp);
    sp.width = sp.height = 64;
    memset(im, 0, sizeof im);
    if (scene_create(&sp, &sc, &e) || raster_scene(&sc, &g, &e) || paint_sv_parse(SPEC, &sv, &e) ||
        paint_views_sv(&sv, g, sc.views, sc.nviews, 1.0, im, NULL, &e))
        goto fail;
    while (nv < sc.nviews && total < 7884) {
        total += samples_count(&g[nv]);
        use[nv++] = 1;
    }
    scene_hash(&sc, hash);
    if (samples_build(g, sc.views, sc.nviews, use, hash, &s, &e))
        goto fail;
    if (want > 0 && want < s.n) { /* every k-th sample */
        unsigned char *keep = calloc((size_t)s.n, 1);
        samples sub;
        int stride = s.n / want;
        if (!keep)
            goto fail;
        for (int i = 0; i < s.n; i++)
            keep[i] = i % stride == 0 && i / stride < want;
        if (samples_pick(&s, keep, "bench-every-k", &sub, &e)) {
            free(keep);
            goto fail;
        }
        free(keep);
        samples_free(&s);
        s = sub;
    }
    if (!(rgb = malloc(3 * (size_t)s.n * sizeof *rgb)) || samples_gather(&s, im, rgb, &e))
        goto fail;
    hf_map_default(&map, HF_MAP_ADD);
    printf("## four-factor product (sphere 64x64, %d views, %d samples, res 32, lambda 0.1, "
           "lambda_s %g, rcond %g; best of %d)\n\n", nv, s.n, lambda_s,
           rcond > 0 ? rcond : HF4_RCOND_DEFAULT, reps);
    printf("| s_res | unknowns | form | rank | null dims | design s | decomposition s | fit s | "
           "painted RMS |\n|---|---|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < 4; k++) {
        double td = 1e30, tc = 1e30, tf = 1e30, rms = 0.0;
        int n = 0, rank = 0, nulls = 0;
        const char *form = "";
        for (int r = 0; r < reps; r++) {
            hf4_design d;
            hf4_decomp dc;
            hf4_factors f;
            hf4_fit_stats st;
            double t0 = glint_now(), t1;
            if (hf4_design_build(&s, 32, sres[k], &d, &e))
                goto fail;
            t1 = glint_now();
            td = t1 - t0 < td ? t1 - t0 : td;
            if (hf4_decomp_build(&d, 0.1, lambda_s, rcond, &dc, &e))
                goto fail;
            tc = glint_now() - t1 < tc ? glint_now() - t1 : tc;
            t1 = glint_now();
            if (hf4_fit(&d, &dc, &map, HF_MODEL_RADIANCE, rgb, NULL, &f, &st, &e))
                goto fail;
            tf = glint_now() - t1 < tf ? glint_now() - t1 : tf;
            n = dc.x.n;
            rank = dc.x.rank;
            nulls = dc.x.null_dims;
            form = dc.x.form;
            rms = st.rms;
            hf4_factors_free(&f);
            hf4_decomp_free(&dc);
            hf4_design_free(&d);
        }
        printf("| %d | %d | %s | %d | %d | %.4f | %.3f | %.4f | %.4f |\n", sres[k], n, form, rank,
               nulls, td, tc, tf, rms);
    }
    free(rgb);
    samples_free(&s);
    for (int v = 0; v < sc.nviews; v++)
        img_free(&im[v]);
    return 0;
fail:
    fprintf(stderr, "bench_hf4: %s\n", e.msg);
    return 1;
}
