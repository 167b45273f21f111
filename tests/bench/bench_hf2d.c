/* bench_hf2d: three factors with 2D factors over parabolic maps (hf2d.h)
 * beside seed 000, Table 2's three-factor column (three 2D factors, 317
 * samples: 1 min 43 s at 16x16 and 101 min at 32x32 by SVD; 0.031 s and
 * 0.105 s per fit).
 *
 *   bench_hf2d [--reps N] [--samples M] [--lambda L] [--dims pqr] [--size P]
 *
 * The built-in sphere at P x P (default 64), its first views whose samples
 * reach 7884, painted with an anisotropic Ward highlight
 * (ward:kd=0.3,ks=0.5,rough=0.1,rough_y=0.35); every k-th sample kept so
 * that about M remain (default 317, Table 2's count; 0 keeps all).  For
 * 2D resolutions 16, 32, 48 and 64 (1D factors at 32): the design, the
 * decomposition (form, unknowns, rank), one fit, the RMS on the painted
 * samples and on every sample of the other views (new views, lit at the
 * same angles), each time the best of N (default 3).  --dims says which
 * factors are 2D ("222": all three, the default; "121": q alone);
 * --lambda the weight of every smoothing row (default 0.1).  Nothing is
 * asserted: the figures go to BENCHMARKS.md. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdf.h"
#include "clock.h"
#include "hf2d.h"
#include "raster.h"
#include "samples.h"

#define SPEC "ward:kd=0.3,ks=0.5,rough=0.1,rough_y=0.35"

static float *paint(const brdf *b, const samples *s)
{
    float *rgb = malloc(3 * (size_t)s->n * sizeof *rgb);
    for (int i = 0; rgb && i < s->n; i++) {
        double n[3], wi[3], wo[3], f[3];
        for (int a = 0; a < 3; a++) {
            n[a] = s->nrm[3 * (size_t)i + a];
            wi[a] = s->wi[3 * (size_t)i + a];
            wo[a] = s->wo[3 * (size_t)i + a];
        }
        brdf_eval(b, n, wi, wo, f);
        for (int c = 0; c < 3; c++)
            rgb[3 * (size_t)i + c] = (float)(f[c] * s->cos_i[i]);
    }
    return rgb;
}

static double rms_on(const hf2d_factors *f, const brdf *b, const samples *s)
{
    double se = 0.0;
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], x[3], t[3];
        for (int a = 0; a < 3; a++) {
            n[a] = s->nrm[3 * (size_t)i + a];
            wi[a] = s->wi[3 * (size_t)i + a];
            wo[a] = s->wo[3 * (size_t)i + a];
        }
        hf2d_factors_eval(f, n, wi, wo, x);
        brdf_eval(b, n, wi, wo, t);
        for (int c = 0; c < 3; c++)
            se += (x[c] - t[c] * s->cos_i[i]) * (x[c] - t[c] * s->cos_i[i]);
    }
    return s->n ? sqrt(se / (3.0 * s->n)) : 0.0;
}

int main(int argc, char **argv)
{
    static const int sres[4] = {16, 32, 48, 64};
    scene_params sp;
    scene sc;
    gbuf *g = NULL;
    unsigned char use[SCENE_MAX_VIEWS] = {0}, rest[SCENE_MAX_VIEWS] = {0};
    samples s, other;
    brdf truth;
    hf_map map;
    float *rgb = NULL;
    char hash[33], dims[8] = "222";
    glint_err e;
    long total = 0;
    int reps = 3, nv = 0, want = 317, size = 64;
    double lambda = 0.1;

    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--reps") && i + 1 < argc && atoi(argv[i + 1]) > 0) {
            reps = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--samples") && i + 1 < argc && atoi(argv[i + 1]) >= 0) {
            want = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--lambda") && i + 1 < argc && atof(argv[i + 1]) >= 0) {
            lambda = atof(argv[++i]);
        } else if (!strcmp(argv[i], "--size") && i + 1 < argc && atoi(argv[i + 1]) >= 16 &&
                   atoi(argv[i + 1]) <= 512) {
            size = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--dims") && i + 1 < argc &&
                   strspn(argv[i + 1], "12") == 3 && strlen(argv[i + 1]) == 3) {
            snprintf(dims, sizeof dims, "%s", argv[++i]);
        } else {
            fprintf(stderr, "usage: bench_hf2d [--reps N] [--samples M] [--lambda L] "
                            "[--dims pqr] [--size P]\n");
            return 2;
        }
    }
    scene_params_default(&sp);
    sp.width = sp.height = size;
    if (scene_create(&sp, &sc, &e) || raster_scene(&sc, &g, &e) || brdf_parse(SPEC, &truth, &e))
        goto fail;
    while (nv < sc.nviews && total < 7884) {
        total += samples_count(&g[nv]);
        use[nv++] = 1;
    }
    for (int v = nv; v < sc.nviews; v++)
        rest[v] = 1;
    scene_hash(&sc, hash);
    if (samples_build(g, sc.views, sc.nviews, use, hash, &s, &e) ||
        samples_build(g, sc.views, sc.nviews, rest, hash, &other, &e))
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
    if (!(rgb = paint(&truth, &s)))
        goto fail;
    hf_map_default(&map, HF_MAP_ADD);
    printf("## 2D factors over parabolic maps (sphere %dx%d, %d views, %d samples, %d on the "
           "other %d views; dims %s, res 32, lambda %g; best of %d; %s)\n\n", size, size, nv,
           s.n, other.n, sc.nviews - nv, dims, lambda, reps, SPEC);
    printf("| res_2d | unknowns | form | rank | null dims | design s | decomposition s | fit s | "
           "painted RMS | new views RMS |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < 4; k++) {
        hf2d_shape sh = {.res = 32, .sres = sres[k]};
        double td = 1e30, tc = 1e30, tf = 1e30, rms = 0.0, rnew = 0.0;
        int n = 0, rank = 0, nulls = 0;
        const char *form = "";
        for (int j = 0; j < 3; j++)
            sh.dims[j] = dims[j] - '0';
        for (int r = 0; r < reps; r++) {
            hf2d_design d;
            hf2d_decomp dc;
            hf2d_factors f;
            hfx_fit_stats st;
            double t0 = glint_now(), t1;
            if (hf2d_design_build(&s, &sh, &d, &e))
                goto fail;
            t1 = glint_now();
            td = t1 - t0 < td ? t1 - t0 : td;
            if (hf2d_decomp_build(&d, lambda, lambda, 0, &dc, &e))
                goto fail;
            tc = glint_now() - t1 < tc ? glint_now() - t1 : tc;
            t1 = glint_now();
            if (hf2d_fit(&d, &dc, &map, HF_MODEL_RADIANCE, rgb, NULL, &f, &st, &e))
                goto fail;
            tf = glint_now() - t1 < tf ? glint_now() - t1 : tf;
            n = dc.x.n;
            rank = dc.x.rank;
            nulls = dc.x.null_dims;
            form = dc.x.form;
            rms = st.rms;
            if (r == 0)
                rnew = rms_on(&f, &truth, &other);
            hf2d_factors_free(&f);
            hf2d_decomp_free(&dc);
            hf2d_design_free(&d);
        }
        printf("| %d | %d | %s | %d | %d | %.4f | %.3f | %.4f | %.4f | %.4f |\n", sres[k], n,
               form, rank, nulls, td, tc, tf, rms, rnew);
        fflush(stdout);
    }
    free(rgb);
    samples_free(&s);
    samples_free(&other);
    return 0;
fail:
    fprintf(stderr, "bench_hf2d: %s\n", e.msg);
    return 1;
}
