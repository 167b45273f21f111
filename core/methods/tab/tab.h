/* tab.h: an isotropic BRDF tabulated over Rusinkiewicz's half and
 * difference angles, and its fit to point-lit samples by regularized
 * non-negative least squares.
 *
 * Conventions.
 *   Angles: h = (wi + wo) / |wi + wo|, theta_h = acos(n.h), theta_d =
 *   acos(wi.h) (Rusinkiewicz 1998).  Both lie in [0, pi/2] for a light and
 *   an eye above the surface.  The difference azimuth phi_d is ignored: the
 *   table is f(theta_h, theta_d), which is what a microfacet BRDF's
 *   distribution and Fresnel terms depend on; what depends on phi_d (the
 *   shadowing of grazing pairs, retro-reflection) is averaged over it by
 *   the fit.  Reciprocity holds by construction: swapping wi and wo leaves
 *   h, theta_h and theta_d unchanged.
 *   Grid: res_h x res_d nodes.  Along theta_h the nodes are uniform in
 *   u = sqrt(theta_h / (pi/2)) (MERL's spacing: dense near the specular
 *   peak), node i at u = i / (res_h - 1); along theta_d uniform in
 *   v = theta_d / (pi/2), node j at v = j / (res_d - 1).  Node (i, j) is
 *   index k = j res_h + i; a table holds 3 doubles a node (RGB, k-major).
 *   Evaluation is bilinear in (u, v); f per unit light, the painted value
 *   is f n.wi.
 *
 * The fit (tab_fit.c).  A painted value y = f(theta_h, theta_d) cos_i is
 * linear in the table: y = sum_k w_k t_k cos_i with the four bilinear
 * weights w_k of the sample's cell.  Per channel
 *
 *   minimize  (1/N) ||A t - y||^2 + lambda ||L t||^2 + ridge ||t||^2,  t >= 0
 *
 * where N is the number of samples and ||L t||^2 = sum over the nodes of
 * (t_uu^2 + t_vv^2) du dv with the second differences divided by the node
 * spacing squared (so ||L t||^2 approximates the integral of the squared
 * second derivatives over the unit square, and lambda means the same at
 * every resolution and sample count).  The prior fills the nodes no sample
 * reaches: its null space is spanned by 1, u, v and uv, so an unreached
 * node takes the value that continues its reached neighbours linearly
 * (then clamped at 0 by t >= 0).  The ridge makes the Gram matrix definite
 * when neither the data nor the prior determine a direction (a single
 * sample, one theta_d): there the table tends to 0.  It is TAB_RIDGE_PRIOR
 * times the prior's weaker axis weight (far below what the prior asks of
 * the nodes it alone sets: a Lambertian's table stays constant within
 * 2e-4), or without a prior (lambda = 0) TAB_RIDGE_DATA times H's largest
 * diagonal entry (the unreached nodes are then 0).
 *
 * Solved on the Gram form H = A'A/N + lambda L'L + ridge I (nodes x nodes,
 * independent of the painting, cached with its Cholesky factor), q = A'y/N:
 * the active-set solver of srbf's lsq.h (LSQ_NONNEG, warm from the factor),
 * or without the constraint two triangular solves with the factor.
 *
 * Ownership: tab_* allocate what their OUT structs point to; the _free
 * functions accept NULL and half-built structs.  Thread-safety: no global
 * state; designs and operators are read-only once built. */
#ifndef GLINT_TAB_H
#define GLINT_TAB_H

#include "err.h"
#include "samples.h"

#define TAB_RES_H_MIN 4
#define TAB_RES_H_MAX 90
#define TAB_RES_D_MIN 2
#define TAB_RES_D_MAX 64
#define TAB_MAX_NODES 4096 /* lsq.h's LSQ_MAX_N */
#define TAB_RIDGE_PRIOR 1e-6
#define TAB_RIDGE_DATA 1e-9

typedef struct tab_grid {
    int res_h, res_d;
} tab_grid;

static inline int tab_nodes(const tab_grid *g)
{
    return g->res_h * g->res_d;
}

/* cos theta_h and cos theta_d of a direction pair (unit vectors): 0, or -1
 * when wi + wo vanishes (no half vector). */
int tab_angles(const double n[3], const double wi[3], const double wo[3], double *cos_h,
               double *cos_d);

/* The cell of (cos_h, cos_d): OUT *k0 the node at its lower corner (the
 * others are k0 + 1, k0 + res_h, k0 + res_h + 1) and the fractions *fu,
 * *fv in [0, 1] along u and v. */
void tab_locate(const tab_grid *g, double cos_h, double cos_d, int *k0, double *fu, double *fv);

/* theta_h of column i and theta_d of row j (radians). */
double tab_theta_h(const tab_grid *g, int i);
double tab_theta_d(const tab_grid *g, int j);

/* The table t (3 tab_nodes doubles) at (cos_h, cos_d), bilinear (OUT: f[3]). */
void tab_lookup(const tab_grid *g, const double *t, double cos_h, double cos_d, double f[3]);

/* ---- the fit ---------------------------------------------------------------------------- */

/* The samples' cells and the Gram matrix of their design (the pattern's
 * part, independent of the painting and of lambda). */
typedef struct tab_design {
    tab_grid g;
    int n;          /* samples */
    int *k0;        /* n: the cell's lower corner (tab_locate) */
    float *fu, *fv; /* n: the fractions in the cell */
    double *ci;     /* n: n.wi */
    double *gram;   /* nodes x nodes, row-major: A'A (not divided by n) */
    int reached;    /* nodes with a positive weight from some sample */
} tab_design;

int tab_design_build(const tab_grid *g, const samples *s, tab_design *out, glint_err *err);
void tab_design_free(tab_design *d);

/* The four weights of sample i (bilinear times n.wi), in the order k0,
 * k0 + 1, k0 + res_h, k0 + res_h + 1. */
void tab_design_weights(const tab_design *d, int i, double w[4]);

/* The operator of one lambda: H and its upper Cholesky factor (lsq.h's
 * lsq_factor). */
typedef struct tab_operator {
    int nodes;
    double lambda, ridge; /* the ridge used (see the header) */
    double *H;            /* nodes x nodes, row-major */
    double *R;            /* nodes x nodes, upper, row-major */
} tab_operator;

/* The weights of the squared second differences along u and v (OUT: *wu,
 * *wv): lambda du dv / du^4 and lambda du dv / dv^4. */
void tab_prior_weights(const tab_grid *g, double lambda, double *wu, double *wv);

/* Add lambda L'L (the prior of the header) to H (nodes x nodes). */
void tab_prior_add(const tab_grid *g, double lambda, double *H);

int tab_operator_build(const tab_design *d, double lambda, tab_operator *out, glint_err *err);
void tab_operator_free(tab_operator *op);

/* What a solve decided, per channel. */
typedef struct tab_solve_report {
    int iterations[3];   /* active-set iterations (0 without the constraint) */
    int at_zero[3];      /* nodes held at 0 by t >= 0 */
    int negative[3];     /* nodes below 0 (without the constraint) */
    double kkt[3];       /* the active-set solver's KKT residual */
    int scale_zero[3];   /* tab_solve_scaled: the scale is 0 on every sample (t = target) */
} tab_solve_report;

/* Fit the table to painted values rgb (3 n floats, finite) with the
 * operator op of design d: OUT t[3 nodes], *rep (may be NULL).  nonneg: 1
 * for t >= 0. */
int tab_solve(const tab_design *d, const tab_operator *op, const float *rgb, int nonneg,
              double *t, tab_solve_report *rep, glint_err *err);

/* ---- a table that multiplies a known function ------------------------------------------- */

/* A table r that multiplies a known function b: the painted value is
 * y_c = b_c(sample) (w . r_c), w the sample's four weights (with n.wi).
 * Per channel
 *
 *   minimize  (1/N) ||B A r - y||^2 / m_c + lambda ||L r||^2 + pull ||r - target||^2
 *
 * (r >= 0 when nonneg), B the diagonal of b_c over the samples and m_c =
 * mean of (b_c cos_i)^2: the data term is normalized so that lambda and
 * pull mean the same for a dark material and a bright one.  pull ties the
 * nodes no sample reaches to target (a ratio to a base: 1), where
 * lambda's linear continuation would run on; it is also the ridge (0: the
 * ridge of tab_operator_build).  Where b_c is 0 on every sample, r_c =
 * target and rep->scale_zero[c] = 1.  The Gram matrix depends on b, so it
 * is built and factored per call (nodes^2 doubles twice). */
typedef struct tab_scaled_opts {
    double lambda, pull, target;
    int nonneg;
} tab_scaled_opts;

int tab_solve_scaled(const tab_design *d, const tab_scaled_opts *o, const float *scale,
                     const float *rgb, double *t, tab_solve_report *rep, glint_err *err);

/* ---- a table whose rows are sums ------------------------------------------------------------ */

/* Rows that are not one cell each: a pixel lit by an environment sums its
 * lights, each with its own cell (and a known function b_c and the
 * light's power as its scale).  fill writes rows i0 .. i0 + m - 1: A holds
 * three m x nodes blocks, channel-major and zeroed before the call, with
 * the row's weight of every node (row i of channel c at A[(c m + i - i0)
 * nodes]), y[3 (i - i0) + c] the painted value.  Returns 0 or an error. */
typedef int (*tab_rows_fill)(void *cls, int i0, int m, double *A, float *y, glint_err *err);

/* tab_solve_scaled's problem on such rows: per channel
 *
 *   minimize  (1/N) ||A r - y||^2 / m_c + lambda ||L r||^2 + pull ||r - target||^2
 *
 * m_c the mean square of the rows' sums (each row's sum of weights: its
 * scale, as b_c ci is a sample's).  Where every row's weights are 0 in a
 * channel, r_c = target and rep->scale_zero[c] = 1.  The Gram matrices are
 * summed a block of rows at a time (BLAS dsyrk: N nodes^2 per channel);
 * memory 4 nodes^2 doubles and three blocks of rows. */
int tab_solve_rows(const tab_grid *g, int n, const tab_scaled_opts *o, tab_rows_fill fill,
                   void *cls, double *t, tab_solve_report *rep, glint_err *err);

#endif
