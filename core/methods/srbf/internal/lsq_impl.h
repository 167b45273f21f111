/* lsq_impl.h: the solver's workspace and its Cholesky factor, shared by
 * lsq.c (the active-set iteration) and lsq_chol.c (the factor of H over
 * the free variables).  Not part of the interface (lsq.h). */
#ifndef GLINT_LSQ_IMPL_H
#define GLINT_LSQ_IMPL_H

#include "lsq.h"
#include "vmath.h"

/* the scans' dot product (four partial sums) */
#define lsq_dot4 vmath_dot4

struct lsq_work {
    int n, m;
    int *freev, *rows;
    unsigned char *isfree, *inrow, *cand;
    unsigned char *noblock; /* m: rows found to depend on the working rows at a
                               stalled step; they cannot block until it moves */
    double *K, *rhs, *x, *p, *grad, *gp, *mu;
    double *up;    /* the budgets tightened by distinct tiny amounts */
    double *gcu;   /* m: an upper bound of G c (exact where last computed) */
    double *gpx;   /* m: G p of the last step, NaN where skipped */
    double *gmax;  /* m: max |G_rj| */
    double *gblkw; /* 2 nb x m: the rows' block maxima when the problem brings none */
    const double *gblk;
    double *pblk;  /* 2 nb: a step's sums of max(p, 0) and max(-p, 0) per block */
    unsigned char *bnz; /* 2 nb: rows of gblk with a nonzero entry */
    double *bnd;   /* m: the step's bound on G p from gblk and pblk */
    double *R;     /* n x n: upper Cholesky factor of H over the free variables */
    double *col;   /* n: a column of R being formed (chol_add) */
    double *Gtw;   /* n x m: G transposed when the problem brings none (on first use) */
    const double *Gt;
    int *ord;      /* the free variables in the factor's order */
    int *at;       /* position of each variable in ord, -1 when bound */
    int k;         /* free variables (the factor's size) */
    double dscale;
    double *Q;     /* orthonormal basis of the working rows on the free variables */
};

/* The factor (lsq_chol.c).  R is n x n row-major with stride pr->n: the
 * upper triangle of its first k rows and columns is the factor of H over
 * ord[0..k).  A pivot that vanishes is raised to 1e-13 H_jj (1e-12 dscale
 * when H_jj <= 0), a ridge on that variable alone. */
void lsq_chol_add(const lsq_problem *pr, lsq_work *w, int j);
void lsq_chol_remove(const lsq_problem *pr, lsq_work *w, int p);
void lsq_chol_remove_unfree(const lsq_problem *pr, lsq_work *w);
void lsq_chol_rebuild(const lsq_problem *pr, lsq_work *w);
void lsq_solve_rt(const lsq_work *w, int n, double *v);
void lsq_solve_r(const lsq_work *w, int n, double *v);

#endif
