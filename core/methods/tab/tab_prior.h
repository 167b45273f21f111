/* tab_prior.h: a prior over tab.h's tables learned from measured
 * materials, and the continuation of a fitted table with it: beyond the
 * difference angles a painting's lights reach (grazing light, and the
 * retro-reflection below them), the table goes on as materials like the
 * painted part are seen to go on.
 *
 * Conventions.
 *   The tables are tab.h's: f(theta_h, theta_d) on its grid, per
 *   steradian, as a fitted table holds it (tab.h: f per unit light).
 *   A learning material's table at a node is f of its published fit
 *   (measured.h) averaged over the difference azimuth phi_d (PRIOR_PHI
 *   values uniform in (0, pi); the pairs below either horizon left out),
 *   at theta_h and theta_d clamped below pi/2 - PRIOR_EDGE (the last row
 *   and column read the pairs just above the horizon; where none of the
 *   PRIOR_PHI pairs is above both, h near the horizon, the node reads the
 *   pair at phi_d = pi/2, which is).  Each channel of
 *   each material is one sample of the prior.
 *   The prior covers the rows of theta_d up to PRIOR_TD_MAX (beyond, the
 *   published fits' 1 / (ci co) runs to orders of magnitude no painting
 *   reaches and would take the principal directions).  It is Gaussian on
 *   g = log(t + eps), eps = PRIOR_EPS:
 *     g = mu + Q c + e,  c ~ N(0, I_k),  e ~ N(0, s2 I),
 *   mu the samples' mean, Q their first k principal directions scaled by
 *   their standard deviations (the singular values over sqrt(samples - 1)),
 *   s2 the variance the other directions leave, per node, averaged over the
 *   nodes (Tipping and Bishop's probabilistic PCA).  In the log the
 *   materials' orders of magnitude (a diffuse plastic and a mirror) weigh
 *   alike (Nielsen, Jensen and Ramamoorthi 2015 map measured BRDFs the same
 *   way before their PCA).
 *
 * The prediction (tab_prior_predict).  A fitted table t0 is read as an
 * observation of g at each covered node, g0 = log(max(t0, 0) + eps), with
 * the variance noise^2 med / w_k, w_k the node's data weight (the diagonal
 * of the design's Gram matrix: the squared bilinear weights times cos_i^2
 * of its samples) and med the median of the positive w_k: a node the
 * painting weighs on as much as the median one is known to `noise` in the
 * log.  Nodes with w_k = 0 are not observed.  Per channel the posterior
 * mean of c given the observed nodes (a k x k solve, the observation
 * variance s2 + v_k), and the prediction exp(mu + Q c) - eps.
 *
 * The continuation (tab_prior_complete) keeps the painted rows of each
 * column as fitted and continues the fit from the last painted row along
 * the prediction's shape (a ratio): a prediction that misses the level of
 * a material still gives its trend.  Measured against replacing the
 * weakly painted nodes by the prediction, and against the prediction plus
 * a correction fitted to what it leaves, it was the only form that did not
 * raise the painted or new-view errors (docs/methods.md).
 *
 * Ownership: tab_prior_learn allocates what *out points to;
 * tab_prior_free accepts NULL and zeroed structs.  Thread-safety: a prior
 * is read-only once learned. */
#ifndef GLINT_TAB_PRIOR_H
#define GLINT_TAB_PRIOR_H

#include "err.h"
#include "measured.h"
#include "tab.h"

#define PRIOR_EPS 1e-3     /* the log map's offset, per steradian */
#define PRIOR_PHI 24       /* difference azimuths a node averages */
#define PRIOR_EDGE 1e-2    /* radians kept from the horizon */
#define PRIOR_K_MAX 64     /* components */
#define PRIOR_TD_MAX 60.0  /* degrees of theta_d the prior covers */

typedef struct tab_prior {
    tab_grid g;
    int nodes;         /* nodes covered: the rows of theta_d <= PRIOR_TD_MAX */
    int k;             /* components kept (at most samples - 1) */
    int materials;     /* materials learned from (3 samples each) */
    double s2;         /* the residual variance e (see the header) */
    double explained;  /* the fraction of the samples' variance the k directions hold */
    double *mu;        /* nodes */
    double *Q;         /* nodes x k, row-major */
} tab_prior;

/* 1 when material m (index i of its set) is learned from under the
 * caller's rule, 0 when it is left out. */
typedef int (*tab_prior_keep)(const void *cls, int i, const measured_material *m);

/* Learn a prior on grid g from model's fits (MEASURED_SGD or MEASURED_ABC)
 * of the materials of set s that keep (may be NULL: all) accepts, k
 * components (1..PRIOR_K_MAX; fewer when there are fewer samples).
 * GLINT_EINVAL for k out of range or fewer than two materials. */
int tab_prior_learn(const tab_grid *g, const measured_set *s, measured_model model,
                    tab_prior_keep keep, const void *keep_cls, int k, tab_prior *out,
                    glint_err *err);
void tab_prior_free(tab_prior *p);

/* The learning table of one fit (OUT: t[3 tab_nodes], f averaged as the
 * header says). */
void tab_prior_table(const tab_grid *g, const measured_truth *mt, double *t);

/* What a completion did, per channel. */
typedef struct tab_prior_report {
    int observed;        /* covered nodes with a positive data weight */
    double coef_norm[3]; /* |c|: how far from the learning materials' mean (about sqrt(k) is typical) */
    double changed[3];   /* the largest |t - t0| over the nodes, relative to max |t0| */
} tab_prior_report;

/* The prediction (OUT: t[3 tab_nodes]): exp(mu + Q c) - eps (at least 0)
 * on the covered nodes, c's posterior mean given t0 (fitted on design d,
 * same grid) as the header says; t0 elsewhere.  rep may be NULL. */
int tab_prior_predict(const tab_prior *p, const tab_design *d, double noise, const double *t0,
                      double *t, tab_prior_report *rep, glint_err *err);

typedef struct tab_prior_opts {
    double noise;      /* the prediction's (see the header), > 0 */
    double painted;    /* a node is painted where its data weight is at least this
                          fraction of the median positive one's, in [0, 1] */
} tab_prior_opts;

/* Complete t (3 tab_nodes doubles, tab's fit on design d) along theta_d:
 * in each column, the covered rows before the first and after the last
 * painted row continue the fitted table from that row along the
 * prediction's shape:  t_j = t_anchor (pred_j + eps) / (pred_anchor + eps)
 * (a table of 0 stays 0).
 * The rows between, and the columns with no painted row, keep the fit.
 * rep may be NULL. */
int tab_prior_complete(const tab_prior *p, const tab_design *d, const tab_prior_opts *o,
                       double *t, tab_prior_report *rep, glint_err *err);

#endif
