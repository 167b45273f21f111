/* sv_fixture.h: what the tests of spatially varying fits share
 * (test_matmap.c, test_maps.c, test_hf4.c, test_auto.c): a scene source
 * lending a static scene to the cache, and paintings of a truth spec (one
 * analytic BRDF, or two blended over the texture coordinates: paint.h). */
#ifndef GLINT_SV_FIXTURE_H
#define GLINT_SV_FIXTURE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdf.h"
#include "paint.h"
#include "cache.h"
#include "prep.h"
#include "raster.h"

/* prep_scene_source.load lending the scene in cls. */
static inline int sv_borrowed(void *cls, const char *id, const scene **out, glint_err *err)
{
    (void)id;
    (void)err;
    *out = cls;
    return 0;
}

/* The fixture of the tests of spatially varying models: the default scene
 * at size x size, its G-buffers, a cache of 1 GiB and the scene's entry in
 * it (id "s", lending *sc).  Once: a second call with *se set does nothing. */
static inline int sv_setup(int size, scene *sc, gbuf **g, cache **c, cache_entry **se)
{
    scene_params sp;
    prep_scene_source src = {sv_borrowed, NULL, sc};
    glint_err e;
    if (*se)
        return 0;
    scene_params_default(&sp);
    sp.width = sp.height = size;
    if (scene_create(&sp, sc, &e) || raster_scene(sc, g, &e) ||
        cache_open(NULL, (size_t)1 << 30, c, &e) || prep_scene_acquire(*c, "s", &src, se, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

/* Paint every view of sc (G-buffers g) with spec.  OUT: im[sc->nviews]. */
static inline int sv_paint(const char *spec, const scene *sc, const gbuf *g, img *im,
                           glint_err *e)
{
    paint_sv sv;
    brdf b;
    memset(im, 0, sizeof(img) * (size_t)sc->nviews);
    if (strchr(spec, '|'))
        return paint_sv_parse(spec, &sv, e) ||
               paint_views_sv(&sv, g, sc->views, sc->nviews, 1.0, im, NULL, e);
    return brdf_parse(spec, &b, e) || paint_views(&b, g, sc->views, sc->nviews, 1.0, im, NULL, e);
}

/* The painted values of prep pp's samples (malloc'ed, 3 n), or NULL. */
static inline float *sv_painted(const prep *pp, const char *spec, const scene *sc,
                                const gbuf *g)
{
    img im[SCENE_MAX_VIEWS];
    glint_err e;
    const samples *s = prep_samples(pp);
    float *rgb = malloc(3 * (size_t)s->n * sizeof *rgb);
    if (sv_paint(spec, sc, g, im, &e) || !rgb || samples_gather(s, im, rgb, &e)) {
        fprintf(stderr, "painting %s: %s\n", spec, e.msg);
        free(rgb);
        rgb = NULL;
    }
    for (int v = 0; v < sc->nviews; v++)
        img_free(&im[v]);
    return rgb;
}

/* Fit every view of sc, painted with spec, by method meth with its
 * parameters (through the cache entry se).  OUT: *out. */
static inline int sv_fit(const method *meth, const void *params, const char *spec,
                         const scene *sc, const gbuf *g, cache *c, cache_entry *se,
                         material *out)
{
    unsigned char all[SCENE_MAX_VIEWS];
    prep_request rq = {meth, params, se, all, NULL};
    prep *pp = NULL;
    img im[SCENE_MAX_VIEWS];
    glint_err e;
    int rc;
    memset(all, 1, sizeof all);
    rc = sv_paint(spec, sc, g, im, &e) || prep_acquire(c, &rq, NULL, NULL, &pp, &e) ||
         prep_fit(pp, im, NULL, out, &e);
    if (rc)
        fprintf(stderr, "fitting %s: %s\n", spec, e.msg);
    for (int v = 0; v < sc->nviews; v++)
        img_free(&im[v]);
    prep_release(c, pp);
    return rc;
}

#endif
