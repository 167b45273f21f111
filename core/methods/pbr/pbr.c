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

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define PBR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define PBR_CLONES
#endif

/* One lobe's D V (and d(D V)/d alpha when ddv is not NULL) across n
 * samples: ggx_dv's expressions. */
PBR_CLONES static void dv_chunk(double alpha, const double *restrict ci, const double *restrict co,
                                const double *restrict ch, int n, double *restrict dv,
                                double *restrict ddv)
{
    const double a2 = alpha * alpha;
#pragma omp simd
    for (int i = 0; i < n; i++) {
        double ch2 = ch[i] * ch[i], d = ch2 * (a2 - 1.0) + 1.0;
        double D = a2 / (M_PI * d * d);
        double si = sqrt(a2 + (1.0 - a2) * ci[i] * ci[i]),
               so = sqrt(a2 + (1.0 - a2) * co[i] * co[i]);
        double Q = co[i] * si + ci[i] * so, V = 0.5 / Q;
        dv[i] = D * V;
        if (ddv) {
            double dD = (d - 2.0 * a2 * ch2) / (M_PI * d * d * d);
            double dQ = co[i] * (1.0 - ci[i] * ci[i]) / (2.0 * si) +
                        ci[i] * (1.0 - co[i] * co[i]) / (2.0 * so);
            double dV = -0.5 * dQ / (Q * Q);
            ddv[i] = (dD * V + D * dV) * 2.0 * alpha;
        }
    }
}

PBR_CLONES void pbr_eval_chunk(const pbr_spec *sp, const double *p, const double *ci,
                               const double *co, const double *ch, const double *cd, int n,
                               double m[3][PBR_CHUNK], double (*J)[PBR_MAXP][PBR_CHUNK])
{
    double w5[PBR_CHUNK], f[3][PBR_CHUNK], dv[PBR_CHUNK], ddv[PBR_CHUNK];
#pragma omp simd
    for (int i = 0; i < n; i++) {
        double w = 1.0 - cd[i];
        w5[i] = w * w * w * w * w;
    }
    for (int c = 0; c < 3; c++) {
        const double kd = p[c] / M_PI;
#pragma omp simd
        for (int i = 0; i < n; i++) {
            f[c][i] = kd;
            if (J)
                J[c][c][i] = ci[i] / M_PI;
        }
    }
    for (int l = 0; l < sp->nlobes; l++) {
        /* dielectric: ks per channel, F0 of the ior (dF0/dior); conductor:
         * one ks, F0 per channel (d/dF0: the same with a factor 1, exact) */
        const int b = 3 + 5 * l, die = sp->fresnel == PBR_DIELECTRIC;
        const double nr = p[b + 4], r = (nr - 1.0) / (nr + 1.0);
        const double dF0 = die ? 4.0 * r / ((nr + 1.0) * (nr + 1.0)) : 1.0;
        dv_chunk(p[b], ci, co, ch, n, dv, J ? ddv : NULL);
        for (int c = 0; c < 3; c++) {
            const double ks = die ? p[b + 1 + c] : p[b + 1], F0 = die ? r * r : p[b + 2 + c];
            const int kk = die ? b + 1 + c : b + 1, kf = die ? b + 4 : b + 2 + c;
#pragma omp simd
            for (int i = 0; i < n; i++) {
                double F = F0 + (1.0 - F0) * w5[i];
                f[c][i] += ks * dv[i] * F;
                if (J) {
                    J[c][b][i] = ci[i] * ks * ddv[i] * F;
                    J[c][kk][i] = ci[i] * dv[i] * F;
                    J[c][kf][i] = ci[i] * ks * dv[i] * (1.0 - w5[i]) * dF0;
                }
            }
        }
    }
    for (int c = 0; c < 3; c++)
#pragma omp simd
        for (int i = 0; i < n; i++)
            m[c][i] = f[c][i] * ci[i];
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

/* The GGX lobe's two halves of the white-furnace integral at a view cos_o
 * (OUT A: times 1 - w5, B: times w5), by importance sampling of D: h
 * drawn with density D (n.h), wi its mirror of wo, each sample weighing
 * f ci / pdf(wi) = 4 V ci (wo.h) / (n.h). */
#define ALBEDO_N 4096
static void lobe_split(double alpha, double cos_o, double *A, double *B)
{
    double a2 = alpha * alpha, so = sqrt(fmax(0.0, 1.0 - cos_o * cos_o)), sa = 0.0, sb = 0.0;
    double sqo = sqrt(a2 + (1.0 - a2) * cos_o * cos_o);
    for (unsigned k = 0; k < ALBEDO_N; k++) {
        unsigned r = k; /* the radical inverse of k in base 2 */
        double u1 = (k + 0.5) / ALBEDO_N, u2;
        r = (r << 16) | (r >> 16);
        r = ((r & 0x00ff00ffu) << 8) | ((r & 0xff00ff00u) >> 8);
        r = ((r & 0x0f0f0f0fu) << 4) | ((r & 0xf0f0f0f0u) >> 4);
        r = ((r & 0x33333333u) << 2) | ((r & 0xccccccccu) >> 2);
        r = ((r & 0x55555555u) << 1) | ((r & 0xaaaaaaaau) >> 1);
        u2 = r * 2.3283064365386963e-10;
        double ch = sqrt((1.0 - u1) / (1.0 + (a2 - 1.0) * u1)), sh = sqrt(fmax(0.0, 1.0 - ch * ch));
        double hx = sh * cos(2.0 * M_PI * u2), hz = ch;
        double voh = so * hx + cos_o * hz, ci = 2.0 * voh * hz - cos_o;
        if (!(ci > 0.0 && voh > 0.0))
            continue;
        double si = sqrt(a2 + (1.0 - a2) * ci * ci), V = 0.5 / (cos_o * si + ci * sqo);
        double w = 4.0 * V * ci * voh / ch, m = 1.0 - voh, w5 = m * m * m * m * m;
        sa += w * (1.0 - w5);
        sb += w * w5;
    }
    *A = sa / ALBEDO_N;
    *B = sb / ALBEDO_N;
}

void pbr_spec_albedo(const pbr_lobe *lobes, int nlobes, double cos_o, double spec[3])
{
    spec[0] = spec[1] = spec[2] = 0.0;
    for (int l = 0; l < nlobes; l++) {
        double A, B;
        lobe_split(lobes[l].alpha, cos_o, &A, &B);
        for (int c = 0; c < 3; c++)
            spec[c] += lobes[l].ks[c] * (lobes[l].f0[c] * A + B);
    }
}

long pbr_geom_terms(const pbr_geom *g)
{
    return g->off ? g->off[g->n] : g->n;
}

/* Sample i's terms summed in the few sums the model is linear in (OUT:
 * S1[c] = sum w ci; per lobe l and channel c, A = sum w ci dv (1 - w5), B =
 * sum w ci dv w5 and, with derivatives, Ad and Bd the same with ddv): as
 * F = F0 (1 - w5) + w5, every value and derivative is a combination of
 * them, so a term costs its D V (and derivative) and these sums, not a
 * Jacobian of its own. */
typedef struct term_sums {
    double S1[3];
    double A[PBR_MAX_LOBES][3], B[PBR_MAX_LOBES][3];
    double Ad[PBR_MAX_LOBES][3], Bd[PBR_MAX_LOBES][3];
} term_sums;

static void sums_of(const pbr_spec *sp, const double *p, const pbr_geom *g, int i, int deriv,
                    term_sums *S)
{
    /* each lobe's D V (and its derivative) for a chunk of terms at once
     * (dv_chunk: ggx_dv's expressions), then the sums term by term in
     * order, as one term at a time would make them */
    double w5[PBR_CHUNK], dv[PBR_MAX_LOBES][PBR_CHUNK], ddv[PBR_MAX_LOBES][PBR_CHUNK];
    memset(S, 0, sizeof *S);
    for (int t0 = g->off[i]; t0 < g->off[i + 1]; t0 += PBR_CHUNK) {
        int n = g->off[i + 1] - t0 < PBR_CHUNK ? g->off[i + 1] - t0 : PBR_CHUNK;
        for (int j = 0; j < n; j++) {
            double w = 1.0 - g->cd[t0 + j];
            w5[j] = w * w * w * w * w;
        }
        for (int l = 0; l < sp->nlobes; l++)
            dv_chunk(p[3 + 5 * l], g->ci + t0, g->co + t0, g->ch + t0, n, dv[l],
                     deriv ? ddv[l] : NULL);
        for (int j = 0; j < n; j++) {
            const float *w = g->w + 3 * (size_t)(t0 + j);
            double ci = g->ci[t0 + j];
            double wc[3] = {w[0] * ci, w[1] * ci, w[2] * ci};
            for (int c = 0; c < 3; c++)
                S->S1[c] += wc[c];
            for (int l = 0; l < sp->nlobes; l++)
                for (int c = 0; c < 3; c++) {
                    double a = wc[c] * dv[l][j];
                    S->A[l][c] += a * (1.0 - w5[j]);
                    S->B[l][c] += a * w5[j];
                    if (deriv) {
                        double ad = wc[c] * ddv[l][j];
                        S->Ad[l][c] += ad * (1.0 - w5[j]);
                        S->Bd[l][c] += ad * w5[j];
                    }
                }
        }
    }
}

void pbr_sample_eval(const pbr_spec *sp, const double *p, const pbr_geom *g, int i, double m[3],
                     double J[3][PBR_MAXP])
{
    int np = pbr_np(sp);
    term_sums S;
    if (!g->off) {
        pbr_eval(sp, p, g->ci[i], g->co[i], g->ch[i], g->cd[i], m, J);
        return;
    }
    sums_of(sp, p, g, i, J != NULL, &S);
    if (J)
        for (int c = 0; c < 3; c++)
            memset(J[c], 0, sizeof(double) * (size_t)np);
    for (int c = 0; c < 3; c++) {
        m[c] = p[c] / M_PI * S.S1[c];
        if (J)
            J[c][c] = S.S1[c] / M_PI;
    }
    for (int l = 0; l < sp->nlobes; l++) {
        int b = 3 + 5 * l;
        if (sp->fresnel == PBR_DIELECTRIC) {
            double n = p[b + 4], r = (n - 1.0) / (n + 1.0), F0 = r * r;
            double dF0 = 4.0 * r / ((n + 1.0) * (n + 1.0));
            for (int c = 0; c < 3; c++) {
                double ks = p[b + 1 + c], val = F0 * S.A[l][c] + S.B[l][c];
                m[c] += ks * val;
                if (J) {
                    J[c][b] = ks * (F0 * S.Ad[l][c] + S.Bd[l][c]);
                    J[c][b + 1 + c] = val;
                    J[c][b + 4] = ks * S.A[l][c] * dF0;
                }
            }
        } else {
            double ks = p[b + 1];
            for (int c = 0; c < 3; c++) {
                double F0 = p[b + 2 + c], val = F0 * S.A[l][c] + S.B[l][c];
                m[c] += ks * val;
                if (J) {
                    J[c][b] = ks * (F0 * S.Ad[l][c] + S.Bd[l][c]);
                    J[c][b + 1] = val;
                    J[c][b + 2 + c] = ks * S.A[l][c];
                }
            }
        }
    }
}

void pbr_sample_sums(const pbr_spec *sp, const double *p, const pbr_geom *g, int i, double d[3],
                     double A[PBR_MAX_LOBES][3], double B[PBR_MAX_LOBES][3])
{
    if (g->off) {
        term_sums S;
        sums_of(sp, p, g, i, 0, &S);
        memcpy(d, S.S1, sizeof S.S1);
        memcpy(A, S.A, sizeof S.A);
        memcpy(B, S.B, sizeof S.B);
        return;
    }
    {
        double w = 1.0 - g->cd[i], w5 = w * w * w * w * w, ci = g->ci[i];
        for (int c = 0; c < 3; c++)
            d[c] = ci;
        for (int l = 0; l < sp->nlobes; l++) {
            double dv;
            dv_chunk(p[3 + 5 * l], g->ci + i, g->co + i, g->ch + i, 1, &dv, NULL);
            for (int c = 0; c < 3; c++) {
                A[l][c] = ci * dv * (1.0 - w5);
                B[l][c] = ci * dv * w5;
            }
        }
    }
}
