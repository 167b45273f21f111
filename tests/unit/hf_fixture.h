/* hf_fixture.h: the fixture of the tests of the fast homomorphic
 * factorization numerics (test_hf.c, test_hf_range.c): samples of the
 * analytic sphere (sphere_fixture.h) at a small raster, a smooth painting
 * of them, and a design, decomposition and operator built on them. */
#ifndef GLINT_HF_FIXTURE_H
#define GLINT_HF_FIXTURE_H

#include <math.h>
#include <stdlib.h>

#include "hf.h"
#include "hf_int.h"
#include "samples.h"
#include "sphere_fixture.h"

/* ---- fixture: analytic sphere samples at a small raster ------------------ */

static samples S;
static int S_ready;

static inline const samples *sphere_samples(void)
{
    if (!S_ready) {
        double dirs[12][3];
        gbuf g[12];
        fixture_ico(dirs);
        if (fixture_sphere_gbufs(g, 12, (const double(*)[3])dirs, 20.0, 70.0, 36, 36))
            return NULL;
        if (samples_build(g, NULL, 12, NULL, "0123456789abcdef0123456789abcdef", &S, NULL))
            return NULL;
        for (int v = 0; v < 12; v++)
            gbuf_free(&g[v]);
        S_ready = 1;
    }
    return &S;
}

/* A smooth positive test painting: Blinn-Phong e=20 times cos_i, RGB tinted. */
static inline float *paint_blinn(const samples *s)
{
    float *rgb = malloc((size_t)3 * s->n * sizeof *rgb);
    for (int i = 0; i < s->n; i++) {
        v3 n = v3_loadf(s->nrm + 3 * i), wi = v3_loadf(s->wi + 3 * i), wo = v3_loadf(s->wo + 3 * i);
        v3 h = v3_normalize(v3_add(wi, wo));
        double ci = v3_dot(n, wi), nh = v3_dot(n, h);
        double spec = 0.3 * 28.0 / (8 * M_PI) * pow(nh > 0 ? nh : 0, 20.0);
        const double kd[3] = {0.7, 0.5, 0.3};
        for (int c = 0; c < 3; c++)
            rgb[3 * i + c] = (float)(0.5 * (kd[c] / M_PI + spec) * ci);
    }
    return rgb;
}

/* ---- a design, its decomposition and an operator on the samples ------------ */

typedef struct fitcase { hf_design d; hf_decomp dc; hf_op op; } fitcase;

static inline int fitcase_make(fitcase *fc, int R, double lambda, const char *reg_spec,
                               hf_precision p)
{
    hf_reg reg;
    glint_err e;
    if (hf_design_build(sphere_samples(), R, &fc->d, &e)) return -1;
    if (hf_decomp_build(&fc->d, lambda, HF_ROUTE_EIG, 0, &fc->dc, &e)) return -1;
    if (hf_reg_parse(reg_spec, &reg, &e)) return -1;
    if (hf_op_build(&fc->dc, &reg, p, &fc->op, &e)) return -1;
    return 0;
}

static inline void fitcase_free(fitcase *fc)
{
    hf_op_free(&fc->op);
    hf_decomp_free(&fc->dc);
    hf_design_free(&fc->d);
}

#endif
