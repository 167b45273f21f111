/* pbr.h: a physically based parametric BRDF and its fit by nonlinear least
 * squares (GSL's multifit_nlinear).
 *
 * The model, isotropic, per colour channel c:
 *
 *   f_c = kd_c / pi + sum over lobes l of  ks_lc D(alpha_l) V(alpha_l) F_lc
 *
 *   D = a2 / (pi ((n.h)^2 (a2 - 1) + 1)^2)                    GGX, a2 = alpha^2
 *   V = 0.5 / (co sqrt(a2 + (1 - a2) ci^2) + ci sqrt(a2 + (1 - a2) co^2))
 *       (height-correlated Smith G2 / (4 ci co)), ci = n.wi, co = n.wo
 *   F = F0 + (1 - F0) (1 - wi.h)^5                             Schlick
 *
 * with one or two lobes, each either
 *   dielectric: ks per channel (the highlight's tint), one ior: F0 =
 *               ((ior - 1) / (ior + 1))^2 for every channel, or
 *   conductor:  one ks, F0 per channel (the metal's colour).
 *
 * Values are radiance per unit light: f_c ci, as the samples a method
 * receives (scene.h's radiance pi I f ci divided by pi I).
 *
 * Parameters ("direct", p): kd[3], then per lobe 5 values: alpha, then
 *   dielectric: ks[3], ior        conductor: ks, F0[3]
 * each bounded (pbr_bounds): kd in [0, 1] (energy), alpha in [PBR_ALPHA_MIN,
 * 1], ior in [PBR_IOR_MIN, PBR_IOR_MAX], F0 in [0, 1], ks in [0, PBR_KS_MAX]
 * (a painted highlight may be brighter than a physical one: ks is bounded
 * only to keep the problem finite).  The fit works on unconstrained u with
 * p = lo + (hi - lo) sigmoid(u), so a parameter reaches a bound only in the
 * limit; one whose sigmoid is within PBR_BOUND_TOL of 0 or 1 at the end is
 * set to the bound and reported there (1e-5 of the range: a mirror's
 * roughness, refined on a subset of the samples, stops 1.1e-6 of the range
 * above its floor, 0.06% of it).
 *
 * Thread-safety: no global state except GSL's error handler, which the first
 * fit turns off once for the process (pthread_once; GSL's default aborts);
 * any number of fits may run at once on different data. */
#ifndef GLINT_PBR_H
#define GLINT_PBR_H

#include <jansson.h>

#include "err.h"

#define PBR_MAX_LOBES 2
#define PBR_MAXP (3 + 5 * PBR_MAX_LOBES)
#define PBR_ALPHA_MIN 0.002
#define PBR_ALPHA_MAX 1.0
#define PBR_IOR_MIN 1.01
#define PBR_IOR_MAX 3.0
#define PBR_KS_MAX 10.0
#define PBR_BOUND_TOL 1e-5

enum { PBR_DIELECTRIC = 0, PBR_CONDUCTOR = 1 };

typedef struct pbr_spec {
    int nlobes;  /* 1 or 2 */
    int fresnel; /* PBR_DIELECTRIC or PBR_CONDUCTOR (both lobes) */
} pbr_spec;

/* The samples' geometry.  Point lights (off NULL): one light a sample,
 * its cosines at index i of four arrays of n doubles: ci = n.wi > 0,
 * co = n.wo > 0, ch = n.h, cd = wi.h, h the unit half vector.
 *
 * Several lights a sample (an environment compressed into lights): sample
 * i sums the terms off[i] .. off[i + 1] - 1 (off: n + 1 entries, off[0] =
 * 0); the cosine arrays are indexed by term (off[n] entries each) and
 * w[3 t + c] is term t's weight in channel c (the light's power times its
 * visibility from the sample).  A sample's value is then
 *
 *   m_c = sum over its terms t of w_tc (f_c ci)_t
 *
 * the radiance it reflects in units of the lights' powers. */
typedef struct pbr_geom {
    int n;
    double *ci, *co, *ch, *cd;
    int *off;   /* NULL: one term a sample, weight 1 */
    float *w;   /* 3 off[n] weights (with off) */
} pbr_geom;

/* Terms of g (n without off). */
long pbr_geom_terms(const pbr_geom *g);

/* The samples of g where take[i] (n flags), with their terms, weights and
 * values (y: 3 per sample), copied into arrays of their own (OUT: out,
 * released by pbr_geom_free; *yout, free()).  GLINT_ENOMEM. */
int pbr_geom_pick(const pbr_geom *g, const float *y, const unsigned char *take, pbr_geom *out,
                  float **yout);
void pbr_geom_free(pbr_geom *g);

/* Number of direct parameters (3 + 5 nlobes). */
int pbr_np(const pbr_spec *sp);

/* The name of parameter k ("kd_r", "alpha", "ks_g", "ior", "f0_b"; the
 * second lobe's end in "_2"); OUT buf. */
void pbr_param_name(const pbr_spec *sp, int k, char *buf, size_t len);

/* Bounds of the direct parameters (OUT lo, hi: pbr_np values). */
void pbr_bounds(const pbr_spec *sp, double *lo, double *hi);

/* The value (OUT m[3]: f_c ci) at one sample's cosines and, when J is not
 * NULL, its derivatives with respect to the direct parameters (OUT J[c][k],
 * k < pbr_np). */
void pbr_eval(const pbr_spec *sp, const double *p, double ci, double co, double ch, double cd,
              double m[3], double J[3][PBR_MAXP]);

/* pbr_eval over n <= PBR_CHUNK point-lit samples at once, their cosines
 * ci[0..n-1] and so on: OUT m[c][i] and, when J is not NULL, J[c][k][i]
 * for the k pbr_eval sets (the caller zeroes J once: the others are never
 * written).  pbr_eval's expressions in its order, sample by sample, so the
 * values are its to the last digit; the samples are taken with vector
 * instructions. */
#define PBR_CHUNK 64
void pbr_eval_chunk(const pbr_spec *sp, const double *p, const double *ci, const double *co,
                    const double *ch, const double *cd, int n, double m[3][PBR_CHUNK],
                    double (*J)[PBR_MAXP][PBR_CHUNK]);

/* The value of sample i of g (OUT m[3]) and, when J is not NULL, its
 * derivatives (OUT J[c][k]): pbr_eval at its one light, or the weighted sum
 * over its terms. */
void pbr_sample_eval(const pbr_spec *sp, const double *p, const pbr_geom *g, int i, double m[3],
                     double J[3][PBR_MAXP]);

/* The sums sample i's value is linear in at p's roughnesses: OUT d[c] =
 * sum over its terms of w_tc ci, and per lobe l A[l][c] = sum of w_tc ci
 * D V (1 - w5) and B[l][c] = sum of w_tc ci D V w5, w5 = (1 - wi.h)^5 (w
 * = 1 for a point light).  The value is then kd_c d_c / pi + sum over the
 * lobes of ks_c (F0_c A + B): the weights kd, ks and F0 enter only there. */
void pbr_sample_sums(const pbr_spec *sp, const double *p, const pbr_geom *g, int i, double d[3],
                     double A[PBR_MAX_LOBES][3], double B[PBR_MAX_LOBES][3]);

/* The same per lobe in one common form, for materials: per lobe alpha,
 * ks[3] and F0[3] (dielectric: F0 from the ior; conductor: ks the same in
 * every channel).  OUT f[3] (f itself, not times ci). */
typedef struct pbr_lobe {
    double alpha, ks[3], f0[3];
} pbr_lobe;
void pbr_lobes_of(const pbr_spec *sp, const double *p, pbr_lobe *lobes);
void pbr_brdf(const double kd[3], const pbr_lobe *lobes, int nlobes, double ci, double co,
              double ch, double cd, double f[3]);

/* F0 of a dielectric of index ior. */
double pbr_f0_of_ior(double ior);

/* The directional albedo of the lobes at a view cos_o from the normal
 * (OUT spec[3]): the fraction of light arriving from everywhere (a white
 * furnace) that the lobes reflect toward it, the integral of the specular
 * part of f times n.wi over the hemisphere, by reciprocity also what they
 * reflect of light arriving from that direction.  Per lobe ks (F0 A + B),
 * A and B the GGX lobe's Schlick split (B the part weighted by w5),
 * integrated by importance sampling of D (4,096 Hammersley points; within
 * 0.5% of a quadrature of 2.9 million cells at alpha 0.1..1, test_pbr).  The
 * lobes of a physical material stay at or below 1 (F <= 1, and one GGX
 * lobe with Smith shadowing loses energy); the Lambert term adds kd. */
void pbr_spec_albedo(const pbr_lobe *lobes, int nlobes, double cos_o, double spec[3]);

/* ---- the fit ----------------------------------------------------------------------- */

typedef struct pbr_fit_opts {
    int starts;    /* starts over the roughness (1..PBR_MAX_STARTS) */
    int max_iter;  /* iterations per start */
    int start_iter; /* iterations of each start when it runs on a subset (it only has to
                       find the basin); 0: PBR_START_ITER */
    int subset;    /* samples the starts are fitted on (the brightest eighth and an even
                      draw of the rest); the best is then refined.  0: all */
    int refine;    /* samples the best start is refined on, drawn alike (used when above
                      subset); 0: all.  The
                      errors, the uncertainties and what the views determine are computed
                      on every sample whatever it is */
    const int *view; /* n: each sample's view (< PBR_MAX_VIEWS), for the errors by view in
                        the result; NULL: none */
    const double *p0; /* a start of its own (pbr_np direct parameters, inside the bounds),
                         tried first: a refit from a previous answer; then `starts` of the
                         roughness starts, 0 allowed with p0.  NULL: none */
} pbr_fit_opts;

#define PBR_MAX_VIEWS 256 /* scene.h's SCENE_MAX_VIEWS */

#define PBR_MAX_STARTS 8

typedef struct pbr_start_report {
    double alpha0;    /* the first lobe's roughness it started from */
    double cost;      /* 0.5 sum of squared residuals on the samples it was fitted to */
    int iters, converged;
} pbr_start_report;

typedef struct pbr_fit_result {
    double p[PBR_MAXP];     /* the parameters (bounds applied) */
    double sigma[PBR_MAXP]; /* standard errors: sqrt(diag((J'J)^-1) s^2), s^2 the residual
                               variance; NaN for a parameter at a bound or undetermined */
    int at_bound[PBR_MAXP]; /* -1 lower, +1 upper, 0 inside */
    int undetermined[PBR_MAXP]; /* 1: the views do not determine it */
    int nstarts, best_start;
    pbr_start_report start[PBR_MAX_STARTS];
    int iters, converged;   /* the final refinement */
    int refine_samples;     /* the samples it ran on (0: no refinement, the starts ran on
                               every sample) */
    double cost;            /* 0.5 sum of squared residuals, all samples */
    double rms;             /* RMS over samples and channels */
    double resid_var;       /* s^2 = 2 cost / (3 n - free parameters) (0 when not positive) */
    int nsamples_lit;       /* samples with a value above zero in some channel */
    double view_se[PBR_MAX_VIEWS]; /* with opts' view: the squared residuals of each view's
                                      samples over the channels (rms's sums, view by view) */
    long view_n[PBR_MAX_VIEWS];    /* and its samples */
} pbr_fit_result;

/* Fit spec to the values y[3 n] (f_c ci per sample, sample-major) at
 * geometry g.  GLINT_EINVAL when there are fewer than pbr_np samples (the
 * message says how many there are and how many are needed), GLINT_ENUMERIC
 * when no start gives a finite cost, GLINT_ENOMEM. */
int pbr_fit(const pbr_spec *sp, const pbr_geom *g, const float *y, const pbr_fit_opts *o,
            pbr_fit_result *out, glint_err *err);

#endif
