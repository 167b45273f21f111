/* pbr.c: the physically based model of pbr.h, its derivatives and the
 * bounds of its parameters.  Conventions in pbr.h: values are f ci per unit
 * light, parameters direct (kd, alpha, ks, ior or F0), derivatives with
 * respect to those (the fit's transforms are pbr_fit.c's). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "pbr.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

int pbr_np(const pbr_spec *sp)
{
    return 3 + 5 * sp->nlobes;
}

double pbr_f0_of_ior(double ior)
{
    double r = (ior - 1.0) / (ior + 1.0);
    return r * r;
}

void pbr_param_name(const pbr_spec *sp, int k, char *buf, size_t len)
{
    static const char ch[3] = {'r', 'g', 'b'};
    const char *suffix;
    int l, j;
    if (k < 3) {
        snprintf(buf, len, "kd_%c", ch[k]);
        return;
    }
    l = (k - 3) / 5;
    j = (k - 3) % 5;
    suffix = l ? "_2" : "";
    if (j == 0)
        snprintf(buf, len, "alpha%s", suffix);
    else if (sp->fresnel == PBR_DIELECTRIC)
        j < 4 ? snprintf(buf, len, "ks_%c%s", ch[j - 1], suffix)
              : snprintf(buf, len, "ior%s", suffix);
    else
        j == 1 ? snprintf(buf, len, "ks%s", suffix)
               : snprintf(buf, len, "f0_%c%s", ch[j - 2], suffix);
}

void pbr_bounds(const pbr_spec *sp, double *lo, double *hi)
{
    for (int c = 0; c < 3; c++) {
        lo[c] = 0.0;
        hi[c] = 1.0;
    }
    for (int l = 0; l < sp->nlobes; l++) {
        int b = 3 + 5 * l;
        lo[b] = PBR_ALPHA_MIN;
        hi[b] = PBR_ALPHA_MAX;
        if (sp->fresnel == PBR_DIELECTRIC) {
            for (int c = 0; c < 3; c++) {
                lo[b + 1 + c] = 0.0;
                hi[b + 1 + c] = PBR_KS_MAX;
            }
            lo[b + 4] = PBR_IOR_MIN;
            hi[b + 4] = PBR_IOR_MAX;
        } else {
            lo[b + 1] = 0.0;
            hi[b + 1] = PBR_KS_MAX;
            for (int c = 0; c < 3; c++) {
                lo[b + 2 + c] = 0.0;
                hi[b + 2 + c] = 1.0;
            }
        }
    }
}

/* D V (V = G2 / (4 ci co), height-correlated) and, when ddv is not NULL,
 * its derivative with respect to alpha. */
static inline void ggx_dv(double alpha, double ci, double co, double ch, double *dv, double *ddv)
{
    double a2 = alpha * alpha, ch2 = ch * ch, d = ch2 * (a2 - 1.0) + 1.0;
    double D = a2 / (M_PI * d * d);
    double si = sqrt(a2 + (1.0 - a2) * ci * ci), so = sqrt(a2 + (1.0 - a2) * co * co);
    double Q = co * si + ci * so, V = 0.5 / Q;
    *dv = D * V;
    if (ddv) {
        /* d/d(a2), then times d(a2)/d(alpha) = 2 alpha */
        double dD = (d - 2.0 * a2 * ch2) / (M_PI * d * d * d);
        double dQ = co * (1.0 - ci * ci) / (2.0 * si) + ci * (1.0 - co * co) / (2.0 * so);
        double dV = -0.5 * dQ / (Q * Q);
        *ddv = (dD * V + D * dV) * 2.0 * alpha;
    }
}

void pbr_eval(const pbr_spec *sp, const double *p, double ci, double co, double ch, double cd,
              double m[3], double J[3][PBR_MAXP])
{
    double w5 = 1.0 - cd, f[3];
    int np = pbr_np(sp);
    w5 = w5 * w5 * w5 * w5 * w5;
    if (J)
        for (int c = 0; c < 3; c++)
            memset(J[c], 0, sizeof(double) * (size_t)np);
    for (int c = 0; c < 3; c++) {
        f[c] = p[c] / M_PI;
        if (J)
            J[c][c] = ci / M_PI;
    }
    for (int l = 0; l < sp->nlobes; l++) {
        int b = 3 + 5 * l;
        double dv, ddv;
        ggx_dv(p[b], ci, co, ch, &dv, J ? &ddv : NULL);
        if (sp->fresnel == PBR_DIELECTRIC) {
            double n = p[b + 4], r = (n - 1.0) / (n + 1.0), F0 = r * r;
            double F = F0 + (1.0 - F0) * w5;
            double dF0 = 4.0 * r / ((n + 1.0) * (n + 1.0));
            for (int c = 0; c < 3; c++) {
                double ks = p[b + 1 + c];
                f[c] += ks * dv * F;
                if (J) {
                    J[c][b] = ci * ks * ddv * F;
                    J[c][b + 1 + c] = ci * dv * F;
                    J[c][b + 4] = ci * ks * dv * (1.0 - w5) * dF0;
                }
            }
        } else {
            double ks = p[b + 1];
            for (int c = 0; c < 3; c++) {
                double F0 = p[b + 2 + c], F = F0 + (1.0 - F0) * w5;
                f[c] += ks * dv * F;
                if (J) {
                    J[c][b] = ci * ks * ddv * F;
                    J[c][b + 1] = ci * dv * F;
                    J[c][b + 2 + c] = ci * ks * dv * (1.0 - w5);
                }
            }
        }
    }
    for (int c = 0; c < 3; c++)
        m[c] = f[c] * ci;
}

void pbr_lobes_of(const pbr_spec *sp, const double *p, pbr_lobe *lobes)
{
    for (int l = 0; l < sp->nlobes; l++) {
        int b = 3 + 5 * l;
        lobes[l].alpha = p[b];
        for (int c = 0; c < 3; c++) {
            if (sp->fresnel == PBR_DIELECTRIC) {
                lobes[l].ks[c] = p[b + 1 + c];
                lobes[l].f0[c] = pbr_f0_of_ior(p[b + 4]);
            } else {
                lobes[l].ks[c] = p[b + 1];
                lobes[l].f0[c] = p[b + 2 + c];
            }
        }
    }
}

void pbr_brdf(const double kd[3], const pbr_lobe *lobes, int nlobes, double ci, double co,
              double ch, double cd, double f[3])
{
    double w5 = 1.0 - cd;
    w5 = w5 * w5 * w5 * w5 * w5;
    for (int c = 0; c < 3; c++)
        f[c] = kd[c] / M_PI;
    for (int l = 0; l < nlobes; l++) {
        double dv;
        ggx_dv(lobes[l].alpha, ci, co, ch, &dv, NULL);
        for (int c = 0; c < 3; c++)
            f[c] += lobes[l].ks[c] * dv * (lobes[l].f0[c] + (1.0 - lobes[l].f0[c]) * w5);
    }
}

long pbr_geom_terms(const pbr_geom *g)
{
    return g->off ? g->off[g->n] : g->n;
}

void pbr_sample_eval(const pbr_spec *sp, const double *p, const pbr_geom *g, int i, double m[3],
                     double J[3][PBR_MAXP])
{
    int np = pbr_np(sp);
    if (!g->off) {
        pbr_eval(sp, p, g->ci[i], g->co[i], g->ch[i], g->cd[i], m, J);
        return;
    }
    m[0] = m[1] = m[2] = 0.0;
    if (J)
        for (int c = 0; c < 3; c++)
            memset(J[c], 0, sizeof(double) * (size_t)np);
    for (int t = g->off[i]; t < g->off[i + 1]; t++) {
        double mt[3], Jt[3][PBR_MAXP];
        const float *w = g->w + 3 * (size_t)t;
        pbr_eval(sp, p, g->ci[t], g->co[t], g->ch[t], g->cd[t], mt, J ? Jt : NULL);
        for (int c = 0; c < 3; c++) {
            double wc = w[c];
            m[c] += wc * mt[c];
            if (J)
                for (int k = 0; k < np; k++)
                    J[c][k] += wc * Jt[c][k];
        }
    }
}
