/* tab.c: the grid of the tabulated BRDF (tab.h): half and difference
 * angles, cells, node angles and the bilinear lookup. */
#include <math.h>

#include "tab.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

int tab_angles(const double n[3], const double wi[3], const double wo[3], double *cos_h,
               double *cos_d)
{
    double h[3], hl;
    for (int e = 0; e < 3; e++)
        h[e] = wi[e] + wo[e];
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    if (!(hl > 0.0))
        return -1;
    *cos_h = (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl;
    *cos_d = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl;
    return 0;
}

/* x in [0, 1] scaled to res - 1 intervals: the lower node and the fraction. */
static void cell_of(double x, int res, int *k, double *f)
{
    double p;
    int i;
    if (!(x > 0.0))
        x = 0.0;
    if (x > 1.0)
        x = 1.0;
    p = x * (res - 1);
    i = (int)floor(p);
    if (i > res - 2)
        i = res - 2;
    *k = i;
    *f = p - i;
}

void tab_locate(const tab_grid *g, double cos_h, double cos_d, int *k0, double *fu, double *fv)
{
    double th = acos(fmax(-1.0, fmin(1.0, cos_h)));
    double td = acos(fmax(-1.0, fmin(1.0, cos_d)));
    int i, j;
    /* theta_h beyond pi/2 (a normal facing away from h) reads the last column */
    cell_of(sqrt(th / (0.5 * M_PI)), g->res_h, &i, fu);
    cell_of(td / (0.5 * M_PI), g->res_d, &j, fv);
    *k0 = j * g->res_h + i;
}

double tab_theta_h(const tab_grid *g, int i)
{
    double u = (double)i / (g->res_h - 1);
    return 0.5 * M_PI * u * u;
}

double tab_theta_d(const tab_grid *g, int j)
{
    return 0.5 * M_PI * (double)j / (g->res_d - 1);
}

void tab_lookup(const tab_grid *g, const double *t, double cos_h, double cos_d, double f[3])
{
    int k0;
    double fu, fv, w[4];
    const int off[4] = {0, 1, g->res_h, g->res_h + 1};
    tab_locate(g, cos_h, cos_d, &k0, &fu, &fv);
    w[0] = (1.0 - fu) * (1.0 - fv);
    w[1] = fu * (1.0 - fv);
    w[2] = (1.0 - fu) * fv;
    w[3] = fu * fv;
    f[0] = f[1] = f[2] = 0.0;
    for (int a = 0; a < 4; a++)
        for (int c = 0; c < 3; c++)
            f[c] += w[a] * t[3 * (size_t)(k0 + off[a]) + c];
}
