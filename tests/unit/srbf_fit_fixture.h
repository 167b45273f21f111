/* srbf_fit_fixture.h: the scene, cache and truths of the srbf fit tests
 * (test_srbf_fit.c, test_srbf_repaint.c): an 80x60 sphere scene (every
 * pixel a row: a quarter of the paper's 160x120, with the same lights and
 * basis), one cache for the binary, truths rendered by a plain loop over
 * the samples and the environment's lights (sum_k power_k f(d_k, wo)
 * max(0, n.d_k)), with the same lights the method uses, so the errors are
 * the model's and the fit's, not the compression's.  The sphere is convex:
 * no visibility. */
#ifndef GLINT_SRBF_FIT_FIXTURE_H
#define GLINT_SRBF_FIT_FIXTURE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "brdf.h"
#include "cache.h"
#include "check.h"
#include "env.h"
#include "img.h"
#include "material.h"
#include "method_srbf.h"
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
    p.width = 80;
    p.height = 60;
    if (scene_create(&p, &SC, &e) || cache_open(NULL, (size_t)4 << 30, &C, &e) ||
        prep_scene_acquire(C, "sphere", &src, &SE, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

typedef void (*truth_fn)(const void *cls, const double n[3], const double wi[3],
                         const double wo[3], double rgb[3]);

static inline void srbf_truth(const void *cls, const double n[3], const double wi[3],
                              const double wo[3], double rgb[3])
{
    srbf_material_eval(cls, n, wi, wo, rgb);
}

static inline void brdf_truth(const void *cls, const double n[3], const double wi[3],
                              const double wo[3], double rgb[3])
{
    brdf_eval(cls, n, wi, wo, rgb);
}

/* prep_fit of painted radiance rgb[3 s->n]: a method is given the painted
 * values over each sample's intensity (samples_gather), so they are made
 * so here, as the pipeline makes them. */
static inline int fit_painted(prep *pp, const float *rgb, material *out, glint_err *e)
{
    const samples *s = prep_samples(pp);
    float *v = malloc((size_t)3 * (s->n ? s->n : 1) * sizeof *v);
    int rc;
    if (!v)
        return glint_err_set(e, GLINT_ENOMEM, "out of memory");
    for (int i = 0; i < 3 * s->n; i++)
        v[i] = (float)(rgb[i] * (1.0 / s->intensity[i / 3]));
    rc = prep_fit(pp, NULL, v, out, e);
    free(v);
    return rc;
}

/* Radiance of every sample of s under lights l with BRDF f (OUT: rgb). */
static inline void render_samples(const samples *s, const env_lights *l, truth_fn f,
                                  const void *cls, float *rgb)
{
    for (int i = 0; i < s->n; i++) {
        double n[3], wo[3], acc[3] = {0, 0, 0};
        for (int e = 0; e < 3; e++) {
            n[e] = s->nrm[3 * i + e];
            wo[e] = s->wo[3 * i + e];
        }
        for (int k = 0; k < l->k; k++) {
            const double *d = l->dir + 3 * k;
            double cs = n[0] * d[0] + n[1] * d[1] + n[2] * d[2], v[3];
            if (cs <= 0.0)
                continue;
            f(cls, n, d, wo, v);
            for (int c = 0; c < 3; c++)
                acc[c] += l->power[3 * k + c] * v[c] * cs;
        }
        for (int c = 0; c < 3; c++)
            rgb[3 * i + c] = (float)acc[c];
    }
}

static inline double rel_rms(const float *a, const float *b, int n)
{
    double num = 0.0, den = 0.0;
    for (int i = 0; i < 3 * n; i++) {
        num += ((double)a[i] - b[i]) * ((double)a[i] - b[i]);
        den += (double)b[i] * b[i];
    }
    return den > 0.0 ? sqrt(num / den) : sqrt(num);
}

/* The pattern of one view (a prep of method srbf with default params). */
static inline int view_samples(int view, srbf_params *p, prep **out)
{
    unsigned char use[SCENE_MAX_VIEWS];
    glint_err e;
    prep_request rq;
    memset(use, 0, sizeof use);
    use[view] = 1;
    rq.m = &method_srbf;
    rq.params = p;
    rq.scene = SE;
    rq.use = use;
    rq.cancel = NULL;
    if (prep_acquire(C, &rq, NULL, NULL, out, &e)) {
        fprintf(stderr, "  prep: %s\n", e.msg);
        return -1;
    }
    return 0;
}

static inline int lights_for(const srbf_params *p, double rot_deg, env_lights *l)
{
    env_map m;
    glint_err e;
    int rc = env_resolve(p->env, &m, &e);
    if (!rc)
        rc = env_compress(&m, ENV_CUT_MEDIAN, p->lights, rot_deg * M_PI / 180.0, 1.0, l, &e);
    env_map_free(&m);
    if (rc)
        fprintf(stderr, "  lights: %s\n", e.msg);
    return rc;
}

/* The energy rows at srbf_energy_dirs(0) of the basis of hemicube
 * resolution res, sigma pi/40 and the paper's static term (f0 0.25, alpha
 * 0.3): made once per resolution for the binary (OUT: *nl). */
static inline const double *known_rows(int res, int *nl)
{
    static double *rows[SRBF_MAX_RES + 1];
    static srbf_basis basis[SRBF_MAX_RES + 1];
    srbf_static st = {SRBF_STATIC_PAPER, 0.25, 0.3};
    glint_err e;
    double *wo;
    *nl = srbf_energy_dirs(0, NULL);
    if (res < SRBF_MIN_RES || res > SRBF_MAX_RES)
        return NULL;
    if (rows[res])
        return rows[res];
    if (srbf_basis_make(res, M_PI / 40.0, &basis[res], &e))
        return NULL;
    wo = malloc((size_t)3 * *nl * sizeof *wo);
    rows[res] = malloc((size_t)*nl * basis[res].J * sizeof *rows[res]);
    srbf_energy_dirs(0, wo);
    if (srbf_energy_rows(&basis[res], &st, *nl, wo, 0, rows[res], 0, NULL, &e)) {
        free(rows[res]);
        rows[res] = NULL;
    }
    free(wo);
    return rows[res];
}

/* The reference's known coefficients on the basis of hemicube resolution
 * res (7: the reference's 147 lobes): lobes near the normal and a tilted
 * one, small weights cut, scaled so that the brightest energy row holds
 * `budget` of 1 - rho. */
static inline int known_material(double budget, int res, srbf_material *sm)
{
    static const double rho[3] = {0.35, 0.25, 0.15};
    double tilt[3] = {0.45, 0.15, 1.0}, tl, mx = 0.0;
    glint_err e;
    int J, nl;
    const double *g;

    memset(sm, 0, sizeof *sm);
    if (srbf_basis_make(res, M_PI / 40.0, &sm->b, &e) || !(g = known_rows(res, &nl)))
        return -1;
    J = sm->b.J;
    sm->st.kind = SRBF_STATIC_PAPER;
    sm->st.f0 = 0.25;
    sm->st.alpha = 0.3;
    memcpy(sm->rho, rho, sizeof rho);
    sm->c = calloc((size_t)3 * J, sizeof *sm->c);
    tl = sqrt(tilt[0] * tilt[0] + tilt[1] * tilt[1] + tilt[2] * tilt[2]);
    for (int j = 0; j < J; j++) {
        const double *x = sm->b.xi + 3 * j;
        double v = exp(-(1.0 - x[2]) / 0.03) +
                   0.6 * exp(-(1.0 - (x[0] * tilt[0] + x[1] * tilt[1] + x[2] * tilt[2]) / tl) /
                             0.01);
        if (v > mx)
            mx = v;
        sm->c[j] = v;
    }
    for (int j = 0; j < J; j++)
        sm->c[j] = sm->c[j] < 0.03 * mx ? 0.0 : sm->c[j];
    {
        double gm = 0.0;
        for (int l = 0; l < nl; l++) {
            double a = 0.0;
            for (int j = 0; j < J; j++)
                a += g[(size_t)l * J + j] * sm->c[j];
            gm = a > gm ? a : gm;
        }
        /* channel 0 holds the shape: scale the other channels from it first */
        for (int ch = 2; ch >= 0; ch--)
            for (int j = 0; j < J; j++)
                sm->c[(size_t)ch * J + j] = sm->c[j] * budget * (1.0 - rho[ch]) / gm;
    }
    return 0;
}

static inline void params_default(srbf_params *p)
{
    method_srbf.params_default(p);
}

static inline const json_t *info_get(const material *m, const char *a, const char *b)
{
    return json_object_get(json_object_get(m->info, a), b);
}

#endif
