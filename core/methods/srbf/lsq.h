/* lsq.h: constrained linear least squares on the Gram form, the solver of
 * environment-lit BRDF fits (Iwasaki et al. eq. 17-19):
 *
 *   minimize  ||T c - f||^2 = c'Hc - 2 q'c + f'f,   H = T'T, q = T'f
 *   subject to  c >= 0            (LSQ_NONNEG and LSQ_ENERGY)
 *               G c <= u          (LSQ_ENERGY: m rows)
 *
 * or unconstrained (LSQ_NONE: the minimum-norm least-squares solution,
 * through an eigendecomposition of H with a relative cut `rcond`).
 *
 * The constrained modes use a primal active-set method started at c = 0
 * (feasible whenever u >= 0), or at a given feasible c0 (a warm start: a
 * repaint from the previous fit's answer; the optimum is the same, the
 * rounding of the path is not): each step solves the equality-constrained
 * subproblem on the free variables with the active rows (the Cholesky
 * factor of H over the free variables, updated in place), moves as far as
 * feasibility allows, and at a stationary point releases constraints by
 * their multipliers.  Block steps: at a stationary point every bound whose
 * multiplier is negative is released at once, and free variables at zero
 * that the next step would take negative are bound again together, so a
 * dense solution (a painted fit uses most lobes) takes about ten steps,
 * not one per lobe; a block that brings no decrease of the objective by
 * the next stationary point switches the method back to one release per
 * step (the classic rule, which terminates).  It stops at a KKT point:
 * with H positive definite on the free variables this is the unique
 * minimum.  Degenerate steps are guarded against cycling (Bland's rule
 * after a stall); linearly dependent active rows are never added.
 *
 * Infeasibility: some u_l < 0 (a diffuse albedo >= 1) makes c >= 0,
 * G c <= u infeasible when G >= 0: reported as LSQ_INFEASIBLE with the row,
 * never a guess.  u_l = 0 is feasible (c = 0 on the rows' support).
 *
 * Thread-safety: no global state; lsq_work is one caller's scratch. */
#ifndef GLINT_LSQ_H
#define GLINT_LSQ_H

#include "err.h"

typedef enum { LSQ_ENERGY = 0, LSQ_NONNEG = 1, LSQ_NONE = 2 } lsq_mode;

typedef enum {
    LSQ_OK = 0,
    LSQ_INFEASIBLE = 1,       /* no c satisfies the constraints */
    LSQ_MAXITER = 2           /* stopped at the iteration limit (c feasible, not optimal) */
} lsq_status;

typedef struct lsq_problem {
    int n;                    /* unknowns, 1..LSQ_MAX_N */
    const double *H;          /* n x n, row-major, symmetric positive semidefinite */
    const double *q;          /* n */
    double ff;                /* f'f (for the objective; 0 if unknown) */
    int m;                    /* energy rows (LSQ_ENERGY), 0..LSQ_MAX_M */
    const double *G;          /* m x n, row-major */
    const double *u;          /* m */
    const double *gmax;       /* m: max_j |G_rj| from lsq_rows_check, which also vouches
                                 that G is finite; NULL: checked and computed per call */
    const double *Gt;         /* n x m: G transposed (lsq_rows_check); NULL: made per call */
    const double *gblk;       /* 2 LSQ_NBLK(n) x m: the rows' block maxima (lsq_rows_blocks);
                                 NULL: made per call */
    const double *R0;         /* n x n: lsq_factor of this H, kept by a caller that solves
                                 with one H many times; NULL: factors made per call */
    const double *c0;         /* n: a start (an earlier solution with the same G and u:
                                 a warm start); used when c0 >= 0 and G c0 <= u, else
                                 ignored; NULL: start at 0 */
    double *gc;               /* OUT when not NULL (LSQ_ENERGY): G c at the answer, m
                                 entries, as the result's slack and violation see it */
} lsq_problem;

#define LSQ_MAX_N 4096
#define LSQ_MAX_M 8192

typedef struct lsq_result {
    lsq_status status;
    int iterations;
    int free_vars;            /* c_j > 0 at the end */
    int active_rows;          /* energy rows holding with equality */
    int infeasible_row;       /* LSQ_INFEASIBLE: the offending row, else -1 */
    double objective;         /* ||T c - f||^2 = c'Hc - 2q'c + ff */
    double max_violation;     /* max(0, max_l (G c - u)_l, max_j -c_j) */
    double kkt_residual;      /* ||H c - q - multipliers' terms||_inf / max(1, ||q||_inf) */
    double min_slack;         /* min_l (u_l - (G c)_l), energy mode; else 0 */
    int rank;                 /* LSQ_NONE: eigenvalues kept */
    int warm;                 /* 1: started at c0 (lsq_problem.c0), 0: at c = 0 */
} lsq_result;

/* Check the rows G (m x n) once for many solves that share them (the
 * three channels of a fit): OUT gmax[m], the largest |G_rj| of each row,
 * and Gt[n x m], G transposed; either may be NULL.  Returns 0, or
 * GLINT_EINVAL when some entry is not finite (Gt is then not written). */
int lsq_rows_check(const double *G, int m, int n, double *gmax, double *Gt, glint_err *err);

/* The rows' maxima over blocks of LSQ_BLK consecutive unknowns, which bound
 * G p for a step p without a pass over G: OUT gblk (2 nb x m, nb =
 * LSQ_NBLK(n)), row b < nb holding max(0, max_j G_rj) over j in block b for
 * each row r, row nb + b max(0, max_j -G_rj).  G must have passed
 * lsq_rows_check. */
#define LSQ_BLK 8
#define LSQ_NBLK(n) (((n) + LSQ_BLK - 1) / LSQ_BLK)
void lsq_rows_blocks(const double *G, int m, int n, double *gblk);

/* The upper Cholesky factor of H (n x n, row-major, below the diagonal
 * zero) as lsq_solve makes it, pivots that vanish raised to 1e-13 of their
 * diagonal: for lsq_problem.R0.  Returns 0, GLINT_EINVAL (H not finite, n
 * out of range) or GLINT_ENOMEM. */
int lsq_factor(const double *H, int n, double *R, glint_err *err);
/* max |H_kk| (1 when H has no positive diagonal): the scale of the floors */
double lsq_diag_scale(const double *H, int n);

/* Scratch sized for n unknowns and m rows (malloc'ed; lsq_work_free). */
typedef struct lsq_work lsq_work;
lsq_work *lsq_work_new(int n, int m);
void lsq_work_free(lsq_work *w);

/* Solve (OUT: c[n], *res).  w may be NULL (allocated per call).  Returns 0
 * (see res->status: LSQ_INFEASIBLE is not an error code, so callers can
 * report it), or GLINT_EINVAL for bad sizes or non-finite data,
 * GLINT_ENOMEM. rcond: LSQ_NONE's cut (<= 0: 1e-12). */
int lsq_solve(const lsq_problem *p, lsq_mode mode, double rcond, lsq_work *w, double *c,
              lsq_result *res, glint_err *err);

const char *lsq_status_name(lsq_status s);  /* "optimal", "infeasible", "max_iterations" */

#endif
