/* bench_maps: accuracy beside seed 000, Table 4: a spatially varying
 * material on the triceratops, fitted with one three-factor material and
 * with the four-factor product, with material maps of 1 to 5 products and
 * with the hybrid (maps of 1 to 5 four-factor products).
 *
 *   bench_maps [--data DIR] [--size N] [--res R] [--map-res M] [--only pbr]
 *
 * The mesh: DIR/meshes/triceratops.off (default DIR ../shared/data; the
 * benchmark says so and exits 0 when it is absent); its texture
 * coordinates are the automatic atlas (an OFF file has none).  The truth:
 * gold Cook-Torrance stripes on a red diffuse base over the texture
 * coordinates.  The painted scene: the 12 icosahedron views at N x N
 * (default 128), lights at 20-70 degrees from the view (the end points of
 * 12 steps).  New views: the 20 icosahedron face directions, lights at the
 * midpoints of 20 steps over 20-70 degrees (directions and light angles
 * never painted), the truth painted on them for reference.
 * Then the physically based fits: pbr (one material) and pbr_maps (its
 * lobes with maps of colour and lobe strength) at a few settings; --only
 * pbr measures those alone.
 * For each fit: the seconds of the fit (the precomputation is shared and
 * timed once), RMS and max |fitted - truth| on the painted views' samples
 * and on the new views' samples (material_error_views: radiance, RGB), and
 * the RMS over the truth's RMS.  Nothing is asserted: the figures go to
 * BENCHMARKS.md. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cache.h"
#include "clock.h"
#include "material.h"
#include "method_hf3.h"
#include "method_hf4.h"
#include "method_hybrid.h"
#include "method_maps.h"
#include "method_pbr.h"
#include "method_pbr_maps.h"
#include "paint.h"
#include "prep.h"
#include "raster.h"
#include "samples.h"

#define SPEC                                                                                    \
    "stripes:freq=6,duty=0.35|lambert:kd=0.6/0.08/0.05|ct:kd=0.05,f0=0.95/0.75/0.35,rough=0.2"

static int borrowed(void *cls, const char *id, const scene **out, glint_err *err)
{
    (void)id;
    (void)err;
    *out = cls;
    return 0;
}

typedef struct views {
    scene sc;
    gbuf *g;
    img im[SCENE_MAX_VIEWS];
    double truth_rms;
} views;

static int make_views(const char *mesh_path, int size, int set, double lo, double hi, int mid,
                      const paint_sv *sv, views *v, glint_err *e)
{
    scene_params sp;
    double ss = 0.0;
    long cnt = 0;
    scene_params_default(&sp);
    snprintf(sp.mesh_path, sizeof sp.mesh_path, "%s", mesh_path);
    sp.width = sp.height = size;
    sp.view_set = set;
    sp.light_lo_deg = lo;
    sp.light_hi_deg = hi;
    sp.light_mid = mid;
    memset(v->im, 0, sizeof v->im);
    if (scene_create(&sp, &v->sc, e) || raster_scene(&v->sc, &v->g, e) ||
        paint_views_sv(sv, v->g, v->sc.views, v->sc.nviews, 1.0, v->im, NULL, e))
        return -1;
    for (int k = 0; k < v->sc.nviews; k++) /* the truth's RMS over the same samples */
        for (size_t p = 0; p < (size_t)size * size; p++) {
            const gbuf *g = &v->g[k];
            double ci = 0.0, co = 0.0;
            if (!g->mask[p])
                continue;
            for (int c = 0; c < 3; c++) {
                ci += g->nrm[3 * p + c] * g->wi[3 * p + c];
                co += g->nrm[3 * p + c] * g->wo[3 * p + c];
            }
            if (!(ci > 0.0 && co > 0.0))
                continue;
            for (int c = 0; c < 3; c++)
                ss += (double)v->im[k].px[p * v->im[k].channels + c] *
                      v->im[k].px[p * v->im[k].channels + c];
            cnt++;
        }
    v->truth_rms = cnt ? sqrt(ss / (3.0 * cnt)) : 0.0;
    return 0;
}

static void row(const char *name, const material *m, double seconds, const views *pv,
                const views *nv)
{
    double r[2], mx[2];
    long n[2];
    glint_err e;
    if (material_error_views(m, pv->g, pv->sc.views, pv->sc.nviews, pv->im, &r[0], &mx[0],
                             &n[0], &e) ||
        material_error_views(m, nv->g, nv->sc.views, nv->sc.nviews, nv->im, &r[1], &mx[1],
                             &n[1], &e)) {
        printf("| %s | error: %s |\n", name, e.msg);
        return;
    }
    printf("| %s | %.3f | %.4f | %.3f | %.4f | %.4f | %.3f | %.4f |\n", name, seconds, r[0],
           mx[0], r[0] / pv->truth_rms, r[1], mx[1], r[1] / nv->truth_rms);
}

/* One method's fit of the painted views (prepared, fitted, timed: the fit
 * alone) as a row named `name`. */
static int method_row(cache *c, cache_entry *se, const unsigned char *all, const method *m,
                      const void *params, const float *rgb, const char *name, const views *pv,
                      const views *nv, glint_err *e)
{
    prep_request rq = {m, params, se, all, NULL};
    prep *p = NULL;
    material mat;
    double t0;
    if (prep_acquire(c, &rq, NULL, NULL, &p, e))
        return -1;
    t0 = glint_now();
    if (prep_fit(p, NULL, rgb, &mat, e)) {
        prep_release(c, p);
        return -1;
    }
    row(name, &mat, glint_now() - t0, pv, nv);
    material_free(&mat);
    prep_release(c, p);
    return 0;
}

/* pbr and pbr_maps at a few settings. */
static int pbr_rows(cache *c, cache_entry *se, const unsigned char *all, const float *rgb,
                    const views *pv, const views *nv, glint_err *e)
{
    static const struct {
        int lobes, fresnel, components, map_res;
    } set[] = {
        {1, PBR_DIELECTRIC, 3, 128}, {1, PBR_DIELECTRIC, 2, 128}, {1, PBR_DIELECTRIC, 5, 128},
        {1, PBR_CONDUCTOR, 3, 128}, {2, PBR_DIELECTRIC, 3, 128}, {1, PBR_DIELECTRIC, 3, 64},
        {1, PBR_DIELECTRIC, 3, 256},
    };
    pbr_params bp;
    method_pbr.params_default(&bp);
    if (method_row(c, se, all, &method_pbr, &bp, rgb, "pbr (one material)", pv, nv, e))
        return -1;
    for (size_t k = 0; k < sizeof set / sizeof set[0]; k++) {
        pbr_maps_params mp;
        char name[128];
        method_pbr_maps.params_default(&mp);
        mp.pbr.lobes = set[k].lobes;
        mp.pbr.fresnel = set[k].fresnel;
        mp.components = set[k].components;
        mp.map_res = set[k].map_res;
        snprintf(name, sizeof name, "pbr_maps, %d product%s of %d %s lobe%s, map_res %d",
                 mp.components, mp.components > 1 ? "s" : "", mp.pbr.lobes,
                 mp.pbr.fresnel == PBR_CONDUCTOR ? "conductor" : "dielectric",
                 mp.pbr.lobes > 1 ? "s" : "", mp.map_res);
        if (method_row(c, se, all, &method_pbr_maps, &mp, rgb, name, pv, nv, e))
            return -1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *data = "../shared/data";
    char path[4096];
    int size = 128, res = 64, map_res = 128, only_pbr = 0;
    views pv, nv;
    paint_sv sv;
    cache *c = NULL;
    cache_entry *se = NULL;
    prep_scene_source src = {borrowed, NULL, &pv.sc};
    unsigned char all[SCENE_MAX_VIEWS];
    fit_params fp;
    maps_params mp;
    prep *p = NULL;
    float *rgb = NULL;
    glint_err e;
    double t0, tprep;

    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--data") && i + 1 < argc)
            data = argv[++i];
        else if (!strcmp(argv[i], "--size") && i + 1 < argc && atoi(argv[i + 1]) >= 16)
            size = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--res") && i + 1 < argc && atoi(argv[i + 1]) >= 4)
            res = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--map-res") && i + 1 < argc && atoi(argv[i + 1]) >= 2)
            map_res = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--only") && i + 1 < argc && !strcmp(argv[i + 1], "pbr")) {
            only_pbr = 1;
            i++;
        } else {
            fprintf(stderr, "usage: bench_maps [--data DIR] [--size N] [--res R] "
                            "[--map-res M] [--only pbr]\n");
            return 2;
        }
    }
    snprintf(path, sizeof path, "%s/meshes/triceratops.off", data);
    if (access(path, R_OK) != 0) {
        printf("bench_maps: %s is absent: nothing measured\n", path);
        return 0;
    }
    if (paint_sv_parse(SPEC, &sv, &e) ||
        make_views(path, size, SCENE_VIEWS_ICO12, 20.0, 70.0, 0, &sv, &pv, &e) ||
        make_views(path, size, SCENE_VIEWS_ICO20, 20.0, 70.0, 1, &sv, &nv, &e))
        goto fail;
    memset(all, 1, sizeof all);
    fit_params_default(&fp);
    fp.res = res;
    method_maps.params_default(&mp);
    mp.hf.res = res;
    mp.map_res = map_res;
    t0 = glint_now();
    {
        prep_request rq = {&method_hf3, &fp, NULL, all, NULL};
        if (cache_open(NULL, (size_t)2 << 30, &c, &e) ||
            prep_scene_acquire(c, "s", &src, &se, &e))
            goto fail;
        rq.scene = se;
        if (prep_acquire(c, &rq, NULL, NULL, &p, &e))
            goto fail;
    }
    tprep = glint_now() - t0;
    {
        const samples *s = prep_samples(p);
        if (!(rgb = malloc(3 * (size_t)s->n * sizeof *rgb)) || samples_gather(s, pv.im, rgb, &e))
            goto fail;
        printf("## Seed 000 Table 4 beside: triceratops, %s\n\n", SPEC);
        printf("%dx%d, 12 painted views (lights 20-70 deg, end points), %d samples, truth RMS "
               "%.4f; 20 new views (the icosahedron's face directions, lights at the midpoints "
               "of 20 steps over 20-70 deg), truth RMS %.4f; three factors at res %d prepared "
               "in %.3f s; coefficient res %d\n\n",
               size, size, s->n, pv.truth_rms, nv.truth_rms, res, tprep, map_res);
    }
    printf("| model | fit seconds | painted RMS | painted max | painted RMS / truth RMS | new "
           "views RMS | new views max | new RMS / truth RMS |\n");
    printf("|---|---|---|---|---|---|---|---|\n");
    if (only_pbr) {
        if (pbr_rows(c, se, all, rgb, &pv, &nv, &e))
            goto fail;
        prep_release(c, p);
        free(rgb);
        cache_release(c, se);
        cache_close(c);
        return 0;
    }
    {
        material m;
        t0 = glint_now();
        if (prep_fit(p, NULL, rgb, &m, &e))
            goto fail;
        row("hf3 (one material)", &m, glint_now() - t0, &pv, &nv);
        material_free(&m);
    }
    prep_release(c, p);
    p = NULL;
    {
        hf4_params_t hp;
        prep_request rq = {&method_hf4, &hp, se, all, NULL};
        material m;
        char name[64];
        method_hf4.params_default(&hp);
        hp.res = res < 64 ? res : 64;
        t0 = glint_now();
        if (prep_acquire(c, &rq, NULL, NULL, &p, &e))
            goto fail;
        tprep = glint_now() - t0;
        t0 = glint_now();
        if (prep_fit(p, NULL, rgb, &m, &e))
            goto fail;
        snprintf(name, sizeof name, "hf4 (s_res %d, prepared in %.2f s)", hp.sres, tprep);
        row(name, &m, glint_now() - t0, &pv, &nv);
        material_free(&m);
        prep_release(c, p);
        p = NULL;
    }
    for (int stage = 0; stage < 2; stage++)
        for (int k = 1; k <= 5; k++) {
            prep_request rq = {&method_maps, &mp, se, all, NULL};
            material m;
            char name[96];
            mp.components = k;
            mp.tol = 0.0;
            mp.refine = stage ? 20 : 0;
            mp.rounds = stage ? 8 : 0;
            if (prep_acquire(c, &rq, NULL, NULL, &p, &e))
                goto fail;
            t0 = glint_now();
            if (prep_fit(p, NULL, rgb, &m, &e))
                goto fail;
            snprintf(name, sizeof name, "maps, %d product%s, %s", k, k > 1 ? "s" : "",
                     stage ? "refined + 8 rounds" : "greedy");
            row(name, &m, glint_now() - t0, &pv, &nv);
            material_free(&m);
            prep_release(c, p);
            p = NULL;
        }
    for (int k = 1; k <= 5; k++) {
        hybrid_params yp;
        prep_request rq = {&method_hybrid, &yp, se, all, NULL};
        material m;
        char name[96];
        method_hybrid.params_default(&yp);
        yp.h.res = res < 64 ? res : 64;
        yp.map_res = map_res;
        yp.components = k;
        yp.tol = 0.0;
        if (prep_acquire(c, &rq, NULL, NULL, &p, &e))
            goto fail;
        t0 = glint_now();
        if (prep_fit(p, NULL, rgb, &m, &e))
            goto fail;
        snprintf(name, sizeof name, "hybrid, %d product%s (s_res %d), refined + 8 rounds", k,
                 k > 1 ? "s" : "", yp.h.sres);
        row(name, &m, glint_now() - t0, &pv, &nv);
        material_free(&m);
        prep_release(c, p);
        p = NULL;
    }
    if (pbr_rows(c, se, all, rgb, &pv, &nv, &e))
        goto fail;
    free(rgb);
    cache_release(c, se);
    cache_close(c);
    return 0;
fail:
    fprintf(stderr, "bench_maps: %s\n", e.msg);
    return 1;
}
