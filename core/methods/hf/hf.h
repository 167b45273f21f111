/* hf.h: fast homomorphic factorization (Jaroszkiewicz & McCool 2003,
 * sections 3-4.1) of painted samples into three 1D factors,
 *
 *     f(wi, wo) ~ p(pi_p) q(pi_q) r(pi_r),
 *
 * pi_p, pi_q, pi_r = length of wi, h, wo projected on the tangent plane.
 *
 * Pipeline and ownership
 *   hf_design_build : samples -> design (per sample: texel index and hat
 *                     weight per factor; the sparse rows of A).
 *   hf_decomp_build : design, res, lambda -> decomposition of
 *                     B = [A; lambda L] (singular values, right singular
 *                     vectors).  The expensive step: cache it (pcache.h).
 *   hf_op_build     : decomposition + regularization -> operator
 *                     M = V diag(c_i / s_i) V^T, so that the regularized
 *                     pseudo-inverse is B^+ g = M A^T f (eq. 9-11 with the
 *                     analysis vectors u'_i = A v_i / s_i applied implicitly).
 *   hf_fit          : operator + painted RGB samples + mapping -> factors.
 * Each stage owns what it allocates; every *_free accepts NULL and zeroed or
 * half-built objects.  A decomposition may be shared read-only by any number
 * of operators and threads; an operator likewise by any number of fits.
 *
 * Conventions (shared with ../shared/reference so numbers compare):
 *  - Texels: node convention, texel k at u = k / (R-1); hat weights,
 *    x = u, k0 = min(floor(x), R-2), t = x - k0, weights (1-t, t).
 *    An R-texel texture sampled with linear filtering at (x + 0.5) / R gives
 *    the same function.
 *  - Unknowns y = [log p (R), log q (R), log r (R)], n = 3R.
 *  - Laplacian: interior second differences [1 -2 1], (R-2) rows per
 *    factor, unscaled; lambda multiplies them raw; data rows unweighted.
 *  - Gauge: a constant moves freely between factors (hat weights sum to 1,
 *    L kills constants), so B has an exact 2-dimensional null space for every
 *    lambda.  glint removes it explicitly: the decomposition is taken on
 *    the complement of the gauge directions, and every solution is
 *    canonicalized so that mean(log p) = mean(log q) = mean(log r) (the
 *    minimum-norm gauge).  Factors are therefore normalized the same way
 *    every time; reports say so (gauge_dims).
 *  - Numerical rank: singular values at or below rcond * s_max count as
 *    zero (never the LAPACK default, which can keep noise and return
 *    factors 1e10 too large).
 *  - Barely reached directions: a direction v_i of the unknowns that the
 *    samples reach only through tiny hat weights (a texel hit by a handful
 *    of samples near the far end of their hats, two neighbouring texels
 *    that the samples never tell apart) is cut like a null direction, by
 *    its data gain (hf_decomp below), whatever rcond says.
 *  - Range: a fit never returns a log-factor beyond HF_LOG_FACTOR_MAX, so
 *    that every factor and every product of the three is a finite
 *    single-precision number; when a painting would drive the solution
 *    past it, the fit damps the operator and says so (hf_fit). */
#ifndef GLINT_HF_H
#define GLINT_HF_H

#include <stddef.h>
#include <stdint.h>

#include "err.h"
#include "samples.h"

#define HF_RES_MIN 4
#define HF_RES_MAX 512
#define HF_LAMBDA_MAX 1e8
#define HF_NFACTORS 3

/* Largest |log-factor| a fit returns.  Factor textures and renderers work
 * in single precision, and a render multiplies one texel of each factor:
 * with |log p|, |log q|, |log r| <= 29.5 the product stays below
 * exp(88.5) < FLT_MAX (log FLT_MAX = 88.72) and every factor is a finite,
 * non-zero float. */
#define HF_LOG_FACTOR_MAX 29.5

/* Data-gain cutoff of the decomposition (see hf_decomp): a direction whose
 * log-factor moves by more than HF_LOG_FACTOR_MAX per unit of log-space
 * misfit on the samples that reach it is barely reached, and cut. */
#define HF_GAIN_MAX HF_LOG_FACTOR_MAX

/* Samples the error diagnostics of a fit are computed over, at most
 * (hf_fit_stats), in runs of HF_DIAG_RUN consecutive samples. */
#define HF_DIAG_SAMPLES 65536
#define HF_DIAG_RUN 64

/* ---- Design: the sparse data rows of A ----------------------------------- */

typedef struct hf_design {
    int n;             /* samples (rows of A) */
    int res;           /* texels per factor */
    int32_t *k0;       /* 3n: first texel of the hat pair, per factor (0..R-2) */
    double *t;         /* 3n: weight of texel k0+1 (texel k0 gets 1 - t) */
    double *cos_i;     /* n: n.wi of each sample (borrowed copy) */
} hf_design;

/* Build the design for `res` texels per factor from the samples' geometry.
 * GLINT_ERANGE for res outside HF_RES_MIN..HF_RES_MAX. */
int hf_design_build(const samples *s, int res, hf_design *out, glint_err *err);
void hf_design_free(hf_design *d);

/* The projections of equations 2-4 for one direction pair (unit vectors),
 * each clipped to [0, 1] (OUT: pi[3] = pi_p, pi_q, pi_r). */
void hf_project(const double n[3], const double wi[3], const double wo[3],
                double pi[3]);

/* Hat interpolation position for u in [0,1] (OUT: *k0, *t). */
void hf_hat(double u, int res, int *k0, double *t);

/* ---- Decomposition of B --------------------------------------------------- */

typedef enum {
    HF_ROUTE_EIG = 0, /* eigendecomposition of B^T B (assembled sparsely) */
    HF_ROUTE_SVD = 1  /* dense SVD of B (LAPACK gesdd): the reference */
} hf_route;

/* What the decomposition keeps.  Of the n unknowns' directions,
 *     n = gauge_dims + null_dims + weak_dims + rank:
 *  - gauge_dims (2): the exact null space of B for every lambda, deflated.
 *  - null_dims: s_i <= rcond * s_max, numerically zero: rounding reaches
 *    them amplified by (s_max / s_i)^2 (hf_rcond_default).  With lambda = 0
 *    these are the texels no sample reaches.
 *  - weak_dims: barely reached.  A least-squares fit puts
 *        y_i = (A v_i . f~) / s_i^2
 *    on direction v_i (f~: the log-mapped samples), so the log-factors move
 *    along v_i by up to
 *        gain_i = ||A v_i|| / s_i^2
 *    per unit of log-space data on the samples that reach v_i (the norm of
 *    the map f~ -> y_i).  Paintings are not exact products of three
 *    factors: a misfit of one log unit (a factor e) on a few samples is
 *    ordinary.  A direction with gain_i above gain_max = HF_GAIN_MAX turns
 *    such a misfit into a log-factor beyond HF_LOG_FACTOR_MAX, where exp
 *    leaves the single-precision range.  (On the default sphere at 128
 *    texels and lambda = 0, two texel pairs of r have gains 2400 and 7600;
 *    Cook-Torrance GGX paintings put log-factors of 110 to 490 on them.)
 *    Such a direction carries misfit, not information, and is cut like a
 *    null direction.
 *    With lambda = 0, gain_i = 1 / s_i: relative to the data it is the
 *    s_max / s_i amplification of data noise, measured against one
 *    unit-weight sample (rows are unweighted and their hat weights sum to
 *    1 per factor) instead of against s_max: a direction is cut when the
 *    samples reach it less than 1/gain_max of one sample, s_i^2 < 1.1e-3.
 *    With lambda > 0 the Laplacian rows raise s_i without feeding data
 *    into v_i, so a texel tied to its neighbours by smoothing has a small
 *    gain and is kept.  The rule is independent of rcond: a caller's rcond
 *    decides null_dims exactly as given, and a tiny one no longer lets
 *    through a direction whose data the fit would amplify past the range.
 * Since ||A v_i|| <= s_i, gain_i <= 1 / s_i: a cut needs s_i < 1 / gain_max,
 * and gain_i is computed (one pass over the samples) only where it can
 * exceed 1, for the few directions with s_i < 1. */
typedef struct hf_decomp {
    int res, n;        /* texels per factor, unknowns (3 res) */
    int nsamples;      /* data rows used */
    double lambda;
    hf_route route;
    double rcond;      /* relative cutoff used for the numerical rank (as given, or the default) */
    int rank;          /* directions kept: s_i > rcond * s_max and gain_i <= gain_max */
    int gauge_dims;    /* gauge directions removed (2) */
    int null_dims;     /* directions with s_i <= rcond * s_max */
    int weak_dims;     /* directions cut as barely reached: gain_i > gain_max */
    double s_null;     /* the absolute cutoff rcond * s_max */
    double gain_max;   /* the data-gain cutoff used (HF_GAIN_MAX) */
    double gain_kept;  /* largest gain_i kept (exact where s_i < 1; gain_i <= 1 / s_i elsewhere) */
    double s_weak;     /* largest singular value cut as barely reached (0: none) */
    double *s;         /* rank singular values of B, descending */
    double *V;         /* n x rank right singular vectors, column-major (V[i + n*k]) */
    double build_seconds;
} hf_decomp;

/* Default relative cutoff (1e-6 for both routes): the operator is applied
 * as M A^T f, which amplifies rounding along direction i by
 * (s_max / s_i)^2 eps; below 1e-6 s_max that exceeds 2e-4, and the eig
 * route cannot resolve values under about sqrt(n eps) s_max anyway. */
double hf_rcond_default(hf_route route);

/* Decompose B = [A; lambda L] for a design.  rcond <= 0 picks the
 * default; a given rcond is used as it is.  Barely reached directions are
 * cut in both cases (see hf_decomp).  GLINT_ERANGE on lambda < 0 or
 * > HF_LAMBDA_MAX or non-finite; GLINT_ENUMERIC if LAPACK fails (its info
 * in the message). */
int hf_decomp_build(const hf_design *d, double lambda, hf_route route,
                    double rcond, hf_decomp *out, glint_err *err);
void hf_decomp_free(hf_decomp *dc);

/* ---- Regularized operator -------------------------------------------------- */

typedef enum {
    HF_REG_TRUNC = 0,   /* eq. 6: c_i = 1/s_i for i < K */
    HF_REG_TIKHONOV,    /* eq. 7: c_i = s_i / (s_i^2 + alpha^2) */
    HF_REG_LINEAR       /* eq. 8: c_i = pos(1 - i/K) / s_i */
} hf_reg_kind;

typedef struct hf_reg {
    hf_reg_kind kind;
    /* How K is chosen (trunc, linear): the first non-zero of
     *   rank > 0   : K = rank (clamped to the numerical rank)
     *   frac > 0   : K = round(frac * numerical rank), at least 1
     *   rel > 0    : K = #{ s_i > rel * s_max }
     *   otherwise  : K = numerical rank ("full") */
    int rank;
    double frac;
    double rel;
    /* Tikhonov damping: alpha, or alpha_rel * s_max when alpha_rel > 0. */
    double alpha;
    double alpha_rel;
} hf_reg;

/* Parse "trunc[:full|:K|:P%|:relT]", "tikhonov:ALPHA|:relT",
 * "linear[:full|:K|:P%]" (e.g. "trunc:50%", "trunc:rel1e-3",
 * "tikhonov:rel0.01", "linear:37"). */
int hf_reg_parse(const char *spec, hf_reg *out, glint_err *err);
void hf_reg_format(const hf_reg *r, char *buf, size_t len);

typedef enum { HF_F64 = 0, HF_F32 = 1 } hf_precision;

typedef struct hf_op {
    int res, n;
    hf_precision prec;
    int k;             /* singular triplets with non-zero weight */
    double s_first, s_last; /* largest and smallest singular value used */
    double weight_sum; /* sum of c_i / s_i (informative) */
    double *M;         /* n x n, row-major, when prec == HF_F64 */
    float *Mf;         /* n x n, row-major, when prec == HF_F32 */
    double build_seconds;
} hf_op;

int hf_op_build(const hf_decomp *dc, const hf_reg *reg, hf_precision prec,
                hf_op *out, glint_err *err);
void hf_op_free(hf_op *op);

/* Bytes read when applying: the operator plus the design's sparse rows. */
size_t hf_op_bytes(const hf_op *op, const hf_design *d);

/* ---- Mapping between linear and log space (section 3.4) -------------------- */

typedef enum {
    HF_MAP_LOG = 0,  /* log(max(f, eps));        inverse p q r            */
    HF_MAP_ADD,      /* log(max(a + f, eps));    inverse max(pqr - a, 0)  (eq. 12-13) */
    HF_MAP_SUB       /* log(max(a - f, eps)), a = (1 + margin) max f per channel;
                        inverse max(a - pqr, 0)  (eq. 14-15) */
} hf_map_kind;

typedef struct hf_map {
    hf_map_kind kind;
    double a;        /* ADD: the offset (default 0.1) */
    double eps;      /* floor before the log (default 1e-3, a quarter 8-bit step) */
    double margin;   /* SUB: a = (1 + margin) * max sample (default 0.01) */
} hf_map;

void hf_map_default(hf_map *m, hf_map_kind kind);
/* The offset a of a channel whose largest value is vmax (ADD: m->a; SUB:
 * (1 + margin) vmax, at most FLT_MAX, 1 when vmax <= 0; LOG: 0). */
double hf_map_offset(const hf_map *m, double vmax);
/* The argument of the log for value v (ADD: a + v; SUB: a - v; LOG: v),
 * before the floor at eps. */
double hf_map_arg(const hf_map *m, double a, double v);
/* Back to linear from a product of factors: max(prod - a, 0) (ADD),
 * max(a - prod, 0) (SUB), max(prod, 0) (LOG). */
double hf_map_inverse(const hf_map *m, double a, double prod);
/* Parse "log", "add", "add:0.05", "sub", "sub:0.02" (margin), with
 * ",eps=1e-4" optionally appended.  Values must be finite and in range. */
int hf_map_parse(const char *spec, hf_map *out, glint_err *err);
void hf_map_format(const hf_map *m, char *buf, size_t len);

/* ---- Fit -------------------------------------------------------------------- */

typedef enum {
    HF_MODEL_RADIANCE = 0, /* factors approximate the painted pixel (f cos I) */
    HF_MODEL_BRDF = 1      /* factors approximate painted / cos_i; render multiplies by cos_i */
} hf_model;

typedef struct hf_fit_stats {
    int clamped[3];        /* samples per channel floored at eps before the log */
    double a_used[3];      /* mapping offset per channel (ADD: a, SUB: chosen a) */
    double log_max;        /* largest |log-factor| returned (<= HF_LOG_FACTOR_MAX) */
    double log_max_undamped; /* largest |log-factor| of the operator's own solution */
    double damping;        /* Tikhonov alpha the fit added to stay within
                              HF_LOG_FACTOR_MAX (0: none was needed) */
    /* Diagnostics: over every sample when there are at most HF_DIAG_SAMPLES,
     * else over diag_runs = HF_DIAG_SAMPLES / HF_DIAG_RUN runs of
     * HF_DIAG_RUN consecutive samples, run k from sample k s (s =
     * diag_stride = floor(n / diag_runs)): an estimate of the RMS figures
     * over samples spread evenly over the views, and a lower bound for
     * max_abs.  Runs, not every s-th sample: a run reads its samples' data
     * in whole cache lines, where every s-th sample read nearly every line
     * of the design (BENCHMARKS.md, the warm path's sixth pass). */
    double log_residual;   /* RMS of (A y - f~) over the data rows, log space, mean over channels */
    double rms;            /* RMS of (reconstruction - sample) over samples and channels, linear */
    double max_abs;        /* max |reconstruction - sample| */
    long diag_samples;     /* samples the three figures above are over */
    long diag_stride;      /* 1: every sample; else the first samples of two runs apart */
    long diag_runs;        /* runs of consecutive samples (1: every sample) */
    double map_seconds;    /* the mapping's offsets (SUB: a pass for the largest values) */
    double stream_seconds; /* the pass over the samples: mapping, logs and A^T f, fused */
    double op_seconds;     /* M t */
    double apply_seconds;  /* stream + op: the operator's application to the painting */
    double total_seconds;  /* the fast factorization: offsets + application + gauge
                              (+ damping, when needed) */
    double diag_seconds;   /* the diagnostics above, not in total */
    int stream_chunks;     /* chunks of the pass over the samples (hf_chunking) */
    int stream_chunks_reused; /* of those, taken from a memo (hf_fit_with) */
} hf_fit_stats;

/* The fitted log-factors in the canonical gauge, with what is needed to
 * invert the mapping.  logf[(j * res + k) * 3 + c]: factor j (p, q, r),
 * texel k, channel c. */
typedef struct hf_factors {
    int res;
    hf_model model;
    hf_map map;
    double a_used[3];
    double *logf;          /* 3 * res * 3 */
} hf_factors;

/* Fit RGB samples (3 * d->n values, sample-major) with an operator built for
 * this design.  OUT: *fac (allocated here), *stats (may be NULL).
 * Non-finite input gives GLINT_ENONFINITE; outputs are always finite.
 *
 * Range of the log-factors.  The largest |log-factor| is checked against
 * HF_LOG_FACTOR_MAX before anything is exponentiated.  The decomposition
 * has cut the barely reached directions, so a painting within a few log
 * units of a product of factors stays far inside; one that is not (say
 * isolated 1e30 pixels on black) can still push a weakly determined
 * direction past it.  Then the fit applies
 *     y(alpha) = (I + alpha^2 M)^-1 y,
 * which turns every operator weight w_i = c_i / s_i into
 * 1 / (1 / w_i + alpha^2) (for truncation, 1 / (s_i^2 + alpha^2)):
 * Tikhonov damping on top of the chosen regularization, which shrinks the
 * weak directions first and leaves those with s_i >> alpha as they were.
 * alpha is found by bisection, to 1%, as the smallest that brings every
 * log-factor within the bound; stats report it (damping) with the
 * undamped maximum.  This costs an eigendecomposition of M (about 15 ms at
 * 128 texels, half a second at 512) and happens only for such paintings.
 * SUB's offset a is at most FLT_MAX, so that a - pqr is a float too
 * (samples above it, possible with the BRDF model's division by cos_i,
 * are floored at eps and counted in clamped). */
int hf_fit(const hf_design *d, const hf_op *op, const hf_map *map,
           hf_model model, const float *rgb, hf_factors *fac,
           hf_fit_stats *stats, glint_err *err);

/* hf_fit again after some views' paintings changed.  The pass over the
 * samples sums A^T f in chunks of samples fixed by the sample count
 * (hf_chunking), and adds the chunks' sums in chunk order.  A chunk whose
 * samples all come from views whose paintings have not changed since an
 * earlier fit through the same memo, with the same key and parameters,
 * has the same sums: they are taken from the memo instead of reading and
 * mapping its samples again, and the result is the same bits as hf_fit's.
 *
 * The caller owns the memo (hf_memo_new / hf_memo_free) and must not use
 * one in two fits at once.  What the sums depend on besides the values is
 * named by key (the caller's: the design, e.g. its pattern and
 * resolution) and by the fit's own mapping, offsets, model and precision
 * (the memo adds those).  Which values a view holds is named by tags[v]:
 * equal tags promise equal values of every sample of view v (view[i]: the
 * view of sample i, nondecreasing over i, as samples_build makes them;
 * otherwise tags reuse nothing).  change (optional) says span by span
 * where the values changed since earlier fits (samples.h): a chunk whose
 * spans did not change since its sums were made is reused too, whatever
 * its views' tags, so a fit after a brush stroke passes over the chunks
 * the stroke touched.  A fit with no change forgets the memo's history.
 * A memo whose key differs is emptied. */
typedef struct hf_memo hf_memo;
hf_memo *hf_memo_new(void);
void hf_memo_free(hf_memo *m);

typedef struct hf_fit_reuse {
    hf_memo *memo;
    const char *key;
    const int *view;         /* d->n */
    const uint64_t *tags;    /* nviews */
    int nviews;
    const samples_change *change; /* NULL: none */
} hf_fit_reuse;

/* hf_fit with reuse (NULL: hf_fit); stats->stream_chunks_reused says how
 * many of stats->stream_chunks came from the memo. */
int hf_fit_with(const hf_design *d, const hf_op *op, const hf_map *map, hf_model model,
                const float *rgb, const hf_fit_reuse *reuse, hf_factors *fac,
                hf_fit_stats *stats, glint_err *err);

/* Evaluate fitted factors at the design's samples (OUT: rgb[3 * d->n]). */
void hf_factors_eval_design(const hf_factors *fac, const hf_design *d, float *rgb);

/* Evaluate at one direction pair (unit vectors; OUT: rgb[3]).  Zero when
 * n.wi <= 0 or n.wo <= 0. */
void hf_factors_eval(const hf_factors *fac, const double n[3],
                     const double wi[3], const double wo[3], double rgb[3]);

/* Shift the log-factors into the canonical gauge (equal mean log per factor,
 * channel by channel).  The product is unchanged. */
void hf_factors_canonicalize(double *logf, int res);

void hf_factors_free(hf_factors *f);

#endif
