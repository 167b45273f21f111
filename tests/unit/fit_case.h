/* fit_case.h: a three-factor fit's inputs on the analytic sphere
 * (sphere_fixture.h) for tests of the fit's passes: the pattern, design,
 * decomposition, operator, mapping and a random painting. */
#ifndef GLINT_FIT_CASE_H
#define GLINT_FIT_CASE_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "hf.h"
#include "samples.h"
#include "sphere_fixture.h"

/* A fit on the sphere seen from the 12 icosahedron views at size x size
 * pixels, res texels, a random painting (the same one every time). */
typedef struct fit_case {
    samples s;
    hf_design d;
    hf_decomp dc;
    hf_op op;
    hf_map map;
    float *rgb;
} fit_case;

static inline int fit_case_make(fit_case *fc, int size, int res)
{
    double dirs[12][3];
    gbuf g[12];
    hf_reg reg;
    uint64_t x = 0x9e3779b97f4a7c15ULL; /* xorshift64 */
    int rc;
    memset(fc, 0, sizeof *fc);
    fixture_ico(dirs);
    if (fixture_sphere_gbufs(g, 12, (const double(*)[3])dirs, 20.0, 70.0, size, size))
        return -1;
    rc = samples_build(g, NULL, 12, NULL, "0123456789abcdef0123456789abcdef", &fc->s, NULL);
    for (int v = 0; v < 12; v++)
        gbuf_free(&g[v]);
    if (rc || !(fc->rgb = malloc((size_t)3 * fc->s.n * sizeof *fc->rgb)))
        return -1;
    for (int i = 0; i < 3 * fc->s.n; i++) {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        fc->rgb[i] = (float)(0.05 + 0.9 * ((double)(x >> 11) * (1.0 / 9007199254740992.0)));
    }
    hf_map_default(&fc->map, HF_MAP_LOG);
    if (hf_reg_parse("trunc:full", &reg, NULL) || hf_design_build(&fc->s, res, &fc->d, NULL) ||
        hf_decomp_build(&fc->d, 0.1, HF_ROUTE_EIG, 0, &fc->dc, NULL) ||
        hf_op_build(&fc->dc, &reg, HF_F64, &fc->op, NULL))
        return -1;
    return 0;
}

static inline void fit_case_free(fit_case *fc)
{
    hf_op_free(&fc->op);
    hf_decomp_free(&fc->dc);
    hf_design_free(&fc->d);
    samples_free(&fc->s);
    free(fc->rgb);
}

#endif
