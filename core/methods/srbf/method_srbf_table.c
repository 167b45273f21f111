/* method_srbf_table.c: p(h) tabulated for previews (method_srbf.h,
 * srbf_material_eval_preview).
 *
 * Interpolation error.  Bilinear interpolation of exp(lambda (cos d - 1))
 * over texels of angular size D errs by about D^2 lambda / 8 at a peak
 * (second derivative lambda there).  The hemi-octahedral map spreads pi
 * radians over N texels, up to 1.4 times more at its diagonals, so N =
 * 1.4 pi sqrt(lambda / (8 tol)).  The error is measured in
 * tests/unit/test_envrender.c. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "method_srbf.h"
#include "uvtex.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

int srbf_table_n(double lambda)
{
    double n = 1.4 * M_PI * sqrt(lambda / (8.0 * SRBF_TABLE_TOL));
    if (!(n <= SRBF_TABLE_MAX))
        return 0; /* too sharp to tabulate: evaluate exactly */
    return n < 32.0 ? 32 : (int)ceil(n);
}

/* Texel centre (i, j) of an N x N map to a unit h with z >= 0. */
static void texel_dir(int n, int i, int j, double h[3])
{
    double s = 2.0 * (i + 0.5) / n - 1.0, t = 2.0 * (j + 0.5) / n - 1.0;
    double u = 0.5 * (s + t), v = 0.5 * (s - t), z = 1.0 - fabs(u) - fabs(v), l;
    h[0] = u;
    h[1] = v;
    h[2] = z > 0.0 ? z : 0.0;
    l = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int e = 0; e < 3; e++)
        h[e] /= l;
}

typedef struct tjob {
    const srbf_material *sm;
    float *tab;
    int n, j0, j1;
} tjob;

static void *build_rows(void *arg)
{
    tjob *t = arg;
    for (int j = t->j0; j < t->j1; j++)
        for (int i = 0; i < t->n; i++) {
            double h[3], p[3];
            texel_dir(t->n, i, j, h);
            srbf_p(&t->sm->b, t->sm->c, h, p);
            for (int e = 0; e < 3; e++)
                t->tab[3 * ((size_t)j * t->n + i) + e] = (float)p[e];
        }
    return NULL;
}

/* The table (built on first use; NULL when out of memory or too sharp). */
static const float *table_get(const srbf_material *sm_c)
{
    srbf_material *sm = (srbf_material *)sm_c; /* the cache is mutable */
    float *tab = __atomic_load_n(&sm->ptab, __ATOMIC_ACQUIRE), *expected = NULL;
    int n;
    tjob jobs[2];
    pthread_t th;
    int threaded;

    if (tab)
        return tab;
    if (!(n = srbf_table_n(sm->b.lambda)))
        return NULL;
    if (!(tab = malloc((size_t)n * n * 3 * sizeof *tab)))
        return NULL;
    for (int k = 0; k < 2; k++)
        jobs[k] = (tjob){sm, tab, n, k * n / 2, (k + 1) * n / 2};
    threaded = sysconf(_SC_NPROCESSORS_ONLN) > 1 && pthread_create(&th, NULL, build_rows, &jobs[1]) == 0;
    build_rows(&jobs[0]);
    if (threaded)
        pthread_join(th, NULL);
    else
        build_rows(&jobs[1]);
    __atomic_store_n(&sm->ptab_n, n, __ATOMIC_RELEASE);
    if (!__atomic_compare_exchange_n(&sm->ptab, &expected, tab, 0, __ATOMIC_ACQ_REL,
                                     __ATOMIC_ACQUIRE)) {
        free(tab); /* another thread built it first */
        tab = expected;
    }
    return tab;
}

static void table_p(const float *tab, int n, const double h[3], double p[3])
{
    double d = fabs(h[0]) + fabs(h[1]) + (h[2] > 0.0 ? h[2] : 0.0);
    double u = h[0] / d, v = h[1] / d, s = u + v, t = u - v;
    uvtex_bilinear(tab, n, 3, 0.5 * (s + 1.0) * n - 0.5, 0.5 * (t + 1.0) * n - 0.5, p);
}

void srbf_material_eval_preview(const srbf_material *sm, const double n[3], const double wi[3],
                                const double wo[3], double rgb[3])
{
    const float *tab = table_get(sm);
    double t[3], b[3], li[3], lo[3], h[3], hl, s, p[3];
    srbf_frame(n, t, b);
    li[0] = t[0] * wi[0] + t[1] * wi[1] + t[2] * wi[2];
    li[1] = b[0] * wi[0] + b[1] * wi[1] + b[2] * wi[2];
    li[2] = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    lo[0] = t[0] * wo[0] + t[1] * wo[1] + t[2] * wo[2];
    lo[1] = b[0] * wo[0] + b[1] * wo[1] + b[2] * wo[2];
    lo[2] = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(li[2] > 0.0) || !(lo[2] > 0.0))
        return;
    for (int e = 0; e < 3; e++)
        h[e] = li[e] + lo[e];
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    if (hl > 0.0)
        for (int e = 0; e < 3; e++)
            h[e] /= hl;
    s = srbf_static_eval(&sm->st, li, lo);
    if (tab)
        table_p(tab, __atomic_load_n(&sm->ptab_n, __ATOMIC_ACQUIRE), h, p);
    else
        srbf_p(&sm->b, sm->c, h, p);
    for (int c = 0; c < 3; c++)
        rgb[c] = (sm->rho[c] / M_PI + p[c] * s) * li[2];
}
