/* point_fixture.h: what the tests of point-lit methods fitted through the
 * precomputation cache share (test_pbr_detail.c, test_pbr_tab.c): the
 * built-in sphere (12 point-lit views) at 64 x 64 in a cache of its own; a
 * method's preparation of the views flagged; truths as functions of the
 * directions and their values f ci at a preparation's samples; and the
 * checks both make of a material (its evaluation finite and non-negative,
 * two materials compared over a grid of directions).  Include it in one
 * test file of a program (static data). */
#ifndef GLINT_TEST_POINT_FIXTURE_H
#define GLINT_TEST_POINT_FIXTURE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "brdf.h"
#include "cache.h"
#include "check.h"
#include "material.h"
#include "measured.h"
#include "prep.h"
#include "samples.h"
#include "scene.h"

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
    p.width = p.height = 64;
    if (scene_create(&p, &SC, &e) || cache_open(NULL, (size_t)2 << 30, &C, &e) ||
        prep_scene_acquire(C, "sphere", &src, &SE, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

/* A preparation of method m (params) for the views flagged in use (NULL:
 * every view). */
static inline prep *prep_of(const method *m, const void *params, const unsigned char *use)
{
    unsigned char all[SCENE_MAX_VIEWS];
    prep_request rq;
    prep *pp = NULL;
    glint_err e;
    memset(all, 0, sizeof all);
    for (int v = 0; v < SC.nviews; v++)
        all[v] = 1;
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

static inline void dirs_of(const samples *s, int i, double n[3], double wi[3], double wo[3])
{
    for (int a = 0; a < 3; a++) {
        n[a] = s->nrm[3 * (size_t)i + a];
        wi[a] = s->wi[3 * (size_t)i + a];
        wo[a] = s->wo[3 * (size_t)i + a];
    }
}

/* A truth: f (without the cosine) at unit n, wi, wo. */
typedef void (*truth_fn)(const void *cls, const double n[3], const double wi[3],
                         const double wo[3], double f[3]);

static inline void brdf_truth(const void *cls, const double n[3], const double wi[3],
                              const double wo[3], double f[3])
{
    brdf_eval(cls, n, wi, wo, f);
}

static inline void measured_fn(const void *cls, const double n[3], const double wi[3],
                               const double wo[3], double f[3])
{
    measured_eval(cls, n, wi, wo, f);
}

/* f ci of a truth at every sample (malloc'ed, 3 n). */
static inline float *values_of(truth_fn f, const void *cls, const samples *s)
{
    float *v = malloc(3 * sizeof(float) * (size_t)(s->n ? s->n : 1));
    for (int i = 0; v && i < s->n; i++) {
        double n[3], wi[3], wo[3], x[3];
        dirs_of(s, i, n, wi, wo);
        f(cls, n, wi, wo, x);
        for (int c = 0; c < 3; c++)
            v[3 * (size_t)i + c] = (float)(x[c] * s->cos_i[i]);
    }
    return v;
}

/* Each of three measured materials' sgd fits (gold-metallic-paint2,
 * red-specular-plastic, pickled-oak-260, from ../shared/data/measured)
 * given to check as a truth named "sgd:NAME".  0, or 1 when the shared
 * data is absent (said); a fits file that does not read fails the test. */
static inline int each_measured(void (*check)(truth_fn f, const void *cls, const char *what))
{
    static const char *const names[] = {"gold-metallic-paint2", "red-specular-plastic",
                                        "pickled-oak-260"};
    measured_set set = {0};
    const char *data = check_data_dir();
    char path[4200];
    glint_err e;
    if (!data ||
        (size_t)snprintf(path, sizeof path, "%s/measured/%s", data, MEASURED_FITS_FILE) >=
            sizeof path ||
        access(path, R_OK) != 0) {
        printf("  skipped: no measured fits under the shared data\n");
        return 1;
    }
    if (measured_load(path, &set, &e)) {
        fprintf(stderr, "  %s: %s\n", path, e.msg);
        check_failed_ = 1;
        return 0;
    }
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
        const measured_material *mm = measured_find(&set, names[k]);
        measured_truth t;
        char what[96];
        if (!mm) {
            printf("  %s: not in the fits file\n", names[k]);
            continue;
        }
        measured_truth_of(mm, MEASURED_SGD, &t);
        snprintf(what, sizeof what, "sgd:%s", names[k]);
        check(measured_fn, &t, what);
    }
    measured_free(&set);
    return 0;
}

static inline double values_rms(const float *v, int n)
{
    double ss = 0.0;
    for (int i = 0; i < 3 * n; i++)
        ss += (double)v[i] * v[i];
    return n ? sqrt(ss / (3.0 * n)) : 0.0;
}

/* The largest |a - b| / (|b| + 1e-12) of two materials over a grid of
 * direction pairs (normal +Z). */
static inline double materials_diff(const material *a, const material *b)
{
    const double n[3] = {0, 0, 1};
    double worst = 0.0;
    for (int ti = 0; ti < 9; ti++)
        for (int to = 0; to < 9; to++)
            for (int ph = 0; ph < 8; ph++) {
                double t1 = 0.17 * ti + 0.01, t2 = 0.17 * to + 0.02, p = 0.8 * ph;
                double wi[3] = {sin(t1), 0, cos(t1)};
                double wo[3] = {sin(t2) * cos(p), sin(t2) * sin(p), cos(t2)};
                double x[3], y[3];
                material_eval(a, n, wi, wo, x);
                material_eval(b, n, wi, wo, y);
                for (int c = 0; c < 3; c++)
                    worst = fmax(worst, fabs(x[c] - y[c]) / (fabs(y[c]) + 1e-12));
            }
    return worst;
}

/* Evaluation finite (and >= 0) over a grid of direction pairs. */
static inline int eval_finite(const material *m)
{
    const double n[3] = {0, 0, 1};
    for (int ti = 0; ti < 10; ti++)
        for (int to = 0; to < 10; to++) {
            double t1 = 0.157 * ti, t2 = 0.157 * to + 0.05;
            double wi[3] = {sin(t1), 0, cos(t1)}, wo[3] = {-sin(t2), 0.1, cos(t2)}, x[3];
            material_eval(m, n, wi, wo, x);
            for (int c = 0; c < 3; c++)
                if (!isfinite(x[c]) || x[c] < 0.0)
                    return 0;
        }
    return 1;
}

#endif
