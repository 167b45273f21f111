/* env_fixture.h: what the tests of the methods fitted under an environment
 * share (test_pbr_env.c, test_auto_env.c): the built-in sphere, 48 x 48,
 * in a cache of its own; a preparation of views 0, 4 and 8 (or those
 * given); the built-in sky compressed into lights; a pbr material of known
 * parameters; and paintings rendered here, independently of any method's
 * terms: at every sample, the sum over the lights above its horizon of
 * power x f x cos, f the material's own evaluation, divided by the
 * sample's intensity as a painting is.  The sphere is convex: no shadow is
 * cast.  Include it in one test file of a program (static data). */
#ifndef GLINT_TEST_ENV_FIXTURE_H
#define GLINT_TEST_ENV_FIXTURE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cache.h"
#include "env.h"
#include "material.h"
#include "method_pbr_env.h"
#include "prep.h"
#include "samples.h"
#include "scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static scene SC;
static cache *C;
static cache_entry *SE;

static inline int borrowed(void *cls, const char *id, const scene **out, glint_err *err)
{
    (void)id;
    (void)err;
    *out = cls;
    return 0;
}

static inline int setup(void)
{
    scene_params p;
    glint_err e;
    prep_scene_source src = {borrowed, NULL, &SC};
    if (C)
        return 0;
    scene_params_default(&p);
    p.width = p.height = 48;
    if (scene_create(&p, &SC, &e) || cache_open(NULL, (size_t)2 << 30, &C, &e) ||
        prep_scene_acquire(C, "sphere", &src, &SE, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

/* Method m's preparation of the views flagged in use (NULL: 0, 4 and 8). */
static inline prep *prep_method(const method *m, const void *params, const unsigned char *use)
{
    unsigned char all[SCENE_MAX_VIEWS];
    prep_request rq;
    prep *pp = NULL;
    glint_err e;
    memset(all, 0, sizeof all);
    for (int v = 0; v < 3; v++)
        all[4 * v] = 1;
    rq.m = m;
    rq.params = params;
    rq.scene = SE;
    rq.use = use ? use : all;
    rq.cancel = NULL;
    if (prep_acquire(C, &rq, NULL, NULL, &pp, &e)) {
        fprintf(stderr, "prep: %s\n", e.msg);
        return NULL;
    }
    return pp;
}

/* The sky, turned rot_deg degrees, compressed into k lights. */
static inline int lights_of(double rot_deg, int k, env_lights *l)
{
    env_map m;
    glint_err e;
    int rc = env_resolve("sky", &m, &e);
    if (!rc)
        rc = env_compress(&m, ENV_CUT_MEDIAN, k, rot_deg * M_PI / 180.0, 1.0, l, &e);
    env_map_free(&m);
    return rc;
}

/* A pbr material of known parameters (dielectric, one lobe). */
static inline void known(material *m, double kd0, double kd1, double kd2, double alpha,
                         double ks, double ior)
{
    pbr_material *pm = calloc(1, sizeof *pm);
    pm->sp.nlobes = 1;
    pm->sp.fresnel = PBR_DIELECTRIC;
    pm->p[0] = kd0;
    pm->p[1] = kd1;
    pm->p[2] = kd2;
    pm->p[3] = alpha;
    pm->p[4] = pm->p[5] = pm->p[6] = ks;
    pm->p[7] = ior;
    pbr_material_sync(pm);
    material_init(m, &method_pbr_env, pm, json_object());
}

/* The radiance of m at every sample of s under l, over the sample's
 * intensity (a painting; malloc'ed, 3 n). */
static inline float *paint(const material *m, const samples *s, const env_lights *l)
{
    float *v = malloc(3 * sizeof(float) * (size_t)(s->n ? s->n : 1));
    for (int i = 0; v && i < s->n; i++) {
        double n[3], wo[3], acc[3] = {0, 0, 0};
        for (int e = 0; e < 3; e++) {
            n[e] = s->nrm[3 * (size_t)i + e];
            wo[e] = s->wo[3 * (size_t)i + e];
        }
        for (int k = 0; k < l->k; k++) {
            double f[3];
            material_eval(m, n, l->dir + 3 * k, wo, f); /* f cos; 0 below the horizon */
            for (int c = 0; c < 3; c++)
                acc[c] += l->power[3 * k + c] * f[c];
        }
        for (int c = 0; c < 3; c++)
            v[3 * (size_t)i + c] = (float)(acc[c] / s->intensity[i]);
    }
    return v;
}

/* ||a - b|| / ||b|| over n values (||a - b|| when b is 0). */
static inline double rel_diff(const float *a, const float *b, long n)
{
    double num = 0.0, den = 0.0;
    for (long i = 0; i < n; i++) {
        num += ((double)a[i] - b[i]) * ((double)a[i] - b[i]);
        den += (double)b[i] * b[i];
    }
    return den > 0.0 ? sqrt(num / den) : sqrt(num);
}

/* The relative difference between a method's prediction of its fitted
 * pixels (prep_predict) and the independent render of material m under l
 * there (OUT *fitted: the values predicted); -1 when out of memory or when
 * the prediction fails. */
static inline double predicted_vs_render(const prep *pp, const material *m,
                                         const env_lights *l, long *fitted)
{
    const samples *s = prep_samples(pp);
    float *pred = malloc(3 * sizeof(float) * (size_t)(s->n ? s->n : 1)), *ref = paint(m, s, l);
    double num = 0.0, den = 0.0;
    glint_err e;
    *fitted = 0;
    if (!pred || !ref || prep_predict(pp, m, pred, &e)) {
        free(pred);
        free(ref);
        return -1.0;
    }
    for (long i = 0; i < 3L * s->n; i++) {
        double r = ref[i] * s->intensity[i / 3]; /* a prediction is radiance */
        if (isnan(pred[i]))
            continue;
        num += ((double)pred[i] - r) * ((double)pred[i] - r);
        den += r * r;
        (*fitted)++;
    }
    free(pred);
    free(ref);
    *fitted /= 3;
    return den > 0.0 ? sqrt(num / den) : sqrt(num);
}

/* m saved into a directory of its own and read back into *back (the
 * directory removed): the largest relative difference of the two
 * materials' evaluations at a few direction pairs, or -1 when saving or
 * reading failed (*back then empty). */
static inline double saved_and_read_back(const material *m, material *back)
{
    char dir[] = "/tmp/glint-env-material-XXXXXX", cmd[128];
    const double n[3] = {0, 0, 1}, pairs[3][2][3] = {
        {{0.3, 0.1, 0.948683}, {-0.2, 0.1, 0.974679}},
        {{0.0, 0.6, 0.8}, {0.0, -0.6, 0.8}},
        {{0.9, 0.0, 0.43589}, {-0.5, 0.5, 0.707107}}};
    double worst = 0.0;
    glint_err e;
    int rc;
    memset(back, 0, sizeof *back);
    if (!mkdtemp(dir))
        return -1.0;
    rc = material_save(m, dir, &e) || material_load(dir, back, &e);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0 || rc)
        return -1.0;
    for (int k = 0; k < 3; k++) {
        double fa[3], fb[3];
        material_eval(m, n, pairs[k][0], pairs[k][1], fa);
        material_eval(back, n, pairs[k][0], pairs[k][1], fb);
        for (int c = 0; c < 3; c++)
            worst = fmax(worst, fabs(fa[c] - fb[c]) / (fabs(fa[c]) + 1e-300));
    }
    return worst;
}

#endif
