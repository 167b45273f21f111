/* glr_fixture.h: the fixture of the tests of the headless EGL renderer
 * (test_glr.c, test_glr_gbuffer.c): the shared renderer (without EGL the
 * whole program is skipped, exit 77), the meshes and the fitted material
 * the tests draw, three views, and the mean absolute difference of two
 * images.  Everything is closed and freed at exit, or before by
 * test_glr.c's close_everything. */
#ifndef GLINT_GLR_FIXTURE_H
#define GLINT_GLR_FIXTURE_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "asan_reexec.h"
#include "check.h"
#include "fit.h"
#include "glr.h"
#include "img.h"
#include "material.h"
#include "mesh.h"
#include "paint.h"
#include "raster.h"
#include "scene.h"

#define SIZE 256

static glr *G;
static mesh sphere, bunny, blobs;
static int have_sphere, have_bunny = -1, have_blobs;
static material MAT;
static int have_mat;

static inline double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}


/* At exit: what close_everything does, when it has not run (G is NULL
 * after it).  A mesh still uploaded is reported and fails the program, as
 * close_everything's check does. */
static inline void glr_fixture_close(void)
{
    glr_stats s;
    if (!G)
        return;
    glr_get_stats(G, &s);
    glr_close(G);
    G = NULL;
    if (have_mat)
        material_free(&MAT);
    mesh_free(&sphere);
    mesh_free(&bunny);
    mesh_free(&blobs);
    have_mat = have_sphere = have_blobs = 0;
    have_bunny = -1;
    if (s.meshes != 0) {
        printf("%ld mesh(es) still uploaded at exit\n", s.meshes);
        fflush(stdout);
        _exit(1);
    }
}

/* The shared renderer; without EGL the whole program is skipped. */
static inline glr *need_glr(void)
{
    static int registered;
    glint_err e;
    if (G)
        return G;
    asan_fast_unwind_reexec();
    if (glr_open(&G, &e)) {
        printf("skipped: %s\n", e.msg);
        fflush(stdout);
        exit(77);
    }
    printf("  renderer: %s\n", glr_describe(G));
    if (!registered) {
        atexit(glr_fixture_close);
        registered = 1;
    }
    return G;
}

static inline mesh *need_sphere(void)
{
    if (!have_sphere && mesh_sphere_default(&sphere, NULL) == 0)
        have_sphere = 1;
    return have_sphere ? &sphere : NULL;
}

/* A non-convex scene: a big sphere with a small one in front of it and a
 * third one half buried in it (occlusion edges and creases). */
static inline mesh *need_blobs(void)
{
    static const double c[3][4] = {{0, 0, -0.2, 0.75}, {0.45, 0.35, 0.55, 0.3},
                                   {-0.5, -0.3, 0.3, 0.4}};
    mesh parts[3];
    int nv = 0, nt = 0;

    if (have_blobs)
        return &blobs;
    for (int k = 0; k < 3; k++)
        if (mesh_sphere(&parts[k], 48, 96, NULL))
            return NULL;
    for (int k = 0; k < 3; k++) {
        nv += parts[k].nverts;
        nt += parts[k].ntris;
    }
    blobs.nverts = nv;
    blobs.ntris = nt;
    blobs.pos = malloc((size_t)nv * 3 * sizeof(float));
    blobs.nrm = malloc((size_t)nv * 3 * sizeof(float));
    blobs.uv = malloc((size_t)nv * 2 * sizeof(float));
    blobs.tri = malloc((size_t)nt * 3 * sizeof(uint32_t));
    nv = nt = 0;
    for (int k = 0; k < 3; k++) {
        mesh *p = &parts[k];
        for (int i = 0; i < p->nverts; i++) {
            for (int d = 0; d < 3; d++) {
                blobs.pos[3 * (nv + i) + d] = (float)(c[k][d] + c[k][3] * p->pos[3 * i + d]);
                blobs.nrm[3 * (nv + i) + d] = p->nrm[3 * i + d];
            }
            blobs.uv[2 * (nv + i)] = p->uv[2 * i];
            blobs.uv[2 * (nv + i) + 1] = p->uv[2 * i + 1];
        }
        for (int t = 0; t < 3 * p->ntris; t++)
            blobs.tri[3 * nt + t] = p->tri[t] + (uint32_t)nv;
        nv += p->nverts;
        nt += p->ntris;
        mesh_free(p);
    }
    have_blobs = 1;
    return &blobs;
}

/* The bunny from the shared data, or NULL (message printed once). */
static inline mesh *need_bunny(void)
{
    const char *dir;
    char path[4200];
    glint_err e;

    if (have_bunny >= 0)
        return have_bunny ? &bunny : NULL;
    have_bunny = 0;
    dir = check_data_dir();
    if (!dir) {
        printf("  bunny: skipped (no test data directory: set GLINT_DATA_DIR)\n");
        return NULL;
    }
    if ((size_t)snprintf(path, sizeof path, "%s/meshes/bunny.ply", dir) >= sizeof path)
        return NULL;
    if (mesh_load(path, &bunny, NULL, &e)) {
        printf("  bunny: skipped (mesh_load %s: %s)\n", path, e.msg);
        return NULL;
    }
    have_bunny = 1;
    return &bunny;
}

/* A Blinn-Phong material fitted on the default sphere scene (res 64). */
static inline material *need_material(void)
{
    scene_params p;
    scene sc;
    gbuf *g = NULL;
    img imgs[12];
    fit_params fpar;
    fit_prep fp;
    brdf b;
    glint_err e;
    double scale;
    int ok = 0;

    if (have_mat)
        return &MAT;
    memset(&sc, 0, sizeof sc);
    memset(&fp, 0, sizeof fp);
    memset(imgs, 0, sizeof imgs);
    scene_params_default(&p);
    if (scene_create(&p, &sc, &e) || raster_scene(&sc, &g, &e) ||
        brdf_parse("blinn:kd=0.75/0.5/0.3,ks=0.25,e=40", &b, &e) ||
        paint_views(&b, g, sc.views, sc.nviews, 0.0, imgs, &scale, &e)) {
        fprintf(stderr, "  material setup: %s\n", e.msg);
        goto done;
    }
    fit_params_default(&fpar);
    fpar.res = 64;
    if (fit_prepare(&fp, &sc, g, NULL, &fpar, NULL, &e) || fit_run(&fp, imgs, NULL, &MAT, &e)) {
        fprintf(stderr, "  fit: %s\n", e.msg);
        goto done;
    }
    ok = 1;
done:
    fit_prep_free(&fp);
    for (int v = 0; v < 12; v++)
        img_free(&imgs[v]);
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
    have_mat = ok;
    return ok ? &MAT : NULL;
}

/* Views: two of the default scene's and one that is in no scene. */
static inline void test_views(scene_view v[3])
{
    double dirs[12][3], d[3] = {0.62, -0.45, 0.64};
    scene_icosahedron(dirs);
    scene_view_make(dirs[0], 3.5, 1.1, 20.0, &v[0]);
    scene_view_make(dirs[7], 3.5, 1.1, 55.0, &v[1]);
    scene_view_make(d, 3.2, 1.15, -35.0, &v[2]);
    v[2].light_intensity = 1.3;
}

static inline double mad(const img *a, const img *b)
{
    double s = 0.0;
    size_t n = (size_t)a->width * a->height * 3;
    for (size_t i = 0; i < n; i++)
        s += fabs((double)a->px[i] - b->px[i]);
    return s / (double)n;
}

#endif
