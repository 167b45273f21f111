/* tab_fit.c: the fit of the tabulated BRDF (tab.h): the samples' design
 * and its Gram matrix, the smoothness prior, the operator of one lambda
 * and the per-channel solve. */
#include <cblas.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lsq.h"
#include "tab.h"

/* ---- the design ------------------------------------------------------------------------- */

void tab_design_free(tab_design *d)
{
    if (!d)
        return;
    free(d->k0);
    free(d->fu);
    free(d->fv);
    free(d->ci);
    free(d->gram);
    memset(d, 0, sizeof *d);
}

void tab_design_weights(const tab_design *d, int i, double w[4])
{
    double fu = d->fu[i], fv = d->fv[i], ci = d->ci[i];
    w[0] = (1.0 - fu) * (1.0 - fv) * ci;
    w[1] = fu * (1.0 - fv) * ci;
    w[2] = (1.0 - fu) * fv * ci;
    w[3] = fu * fv * ci;
}

/* A'A of the design's samples into d->gram, and the nodes reached. */
static void design_gram(tab_design *d)
{
    int nodes = tab_nodes(&d->g), rh = d->g.res_h;
    const int off[4] = {0, 1, rh, rh + 1};
    double *G = d->gram;
    d->reached = 0;
    for (int i = 0; i < d->n; i++) {
        double w[4];
        tab_design_weights(d, i, w);
        for (int a = 0; a < 4; a++) {
            double *row = G + (size_t)(d->k0[i] + off[a]) * nodes + d->k0[i];
            for (int b = 0; b < 4; b++)
                row[off[b]] += w[a] * w[b];
        }
    }
    for (int k = 0; k < nodes; k++)
        d->reached += G[(size_t)k * nodes + k] > 0.0;
}

int tab_design_build(const tab_grid *g, const samples *s, tab_design *out, glint_err *err)
{
    int nodes = tab_nodes(g);
    size_t n = (size_t)s->n;
    memset(out, 0, sizeof *out);
    if (g->res_h < TAB_RES_H_MIN || g->res_h > TAB_RES_H_MAX || g->res_d < TAB_RES_D_MIN ||
        g->res_d > TAB_RES_D_MAX || nodes > TAB_MAX_NODES)
        return glint_err_set(err, GLINT_EINVAL,
                             "tab: grid %d x %d out of range (%d..%d x %d..%d, at most %d nodes)",
                             g->res_h, g->res_d, TAB_RES_H_MIN, TAB_RES_H_MAX, TAB_RES_D_MIN,
                             TAB_RES_D_MAX, TAB_MAX_NODES);
    if (s->n < 1)
        return glint_err_set(err, GLINT_EINVAL, "tab: no samples");
    out->g = *g;
    out->n = s->n;
    out->k0 = malloc(n * sizeof *out->k0);
    out->fu = malloc(n * sizeof *out->fu);
    out->fv = malloc(n * sizeof *out->fv);
    out->ci = malloc(n * sizeof *out->ci);
    out->gram = calloc((size_t)nodes * nodes, sizeof *out->gram);
    if (!out->k0 || !out->fu || !out->fv || !out->ci || !out->gram) {
        tab_design_free(out);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab design, %d samples, %d nodes)",
                             s->n, nodes);
    }
    for (size_t i = 0; i < n; i++) {
        double nr[3], wi[3], wo[3], ch = 1.0, cd = 1.0, fu, fv;
        for (int e = 0; e < 3; e++) {
            nr[e] = s->nrm[3 * i + e];
            wi[e] = s->wi[3 * i + e];
            wo[e] = s->wo[3 * i + e];
        }
        /* wi + wo = 0 cannot happen for a lit and seen sample; the node at
         * theta_h = theta_d = 0 takes it if it does */
        tab_angles(nr, wi, wo, &ch, &cd);
        tab_locate(g, ch, cd, &out->k0[i], &fu, &fv);
        out->fu[i] = (float)fu;
        out->fv[i] = (float)fv;
        out->ci[i] = s->cos_i[i];
    }
    design_gram(out);
    return 0;
}

/* ---- the prior and the operator ----------------------------------------------------------- */

/* Add w c c' to H for the second difference c = (1, -2, 1) at nodes a, b, e. */
static void add_second(double *H, int nodes, int a, int b, int e, double w)
{
    const int k[3] = {a, b, e};
    const double c[3] = {1.0, -2.0, 1.0};
    for (int x = 0; x < 3; x++)
        for (int y = 0; y < 3; y++)
            H[(size_t)k[x] * nodes + k[y]] += w * c[x] * c[y];
}

void tab_prior_weights(const tab_grid *g, double lambda, double *wu, double *wv)
{
    double hu = 1.0 / (g->res_h - 1), hv = 1.0 / (g->res_d - 1), area = hu * hv;
    /* (t_uu)^2 du dv with t_uu = second difference / hu^2, and the same in v */
    *wu = lambda * area / (hu * hu * hu * hu);
    *wv = lambda * area / (hv * hv * hv * hv);
}

void tab_prior_add(const tab_grid *g, double lambda, double *H)
{
    int rh = g->res_h, rd = g->res_d, nodes = tab_nodes(g);
    double wu, wv;
    if (!(lambda > 0.0))
        return;
    tab_prior_weights(g, lambda, &wu, &wv);
    for (int j = 0; j < rd; j++)
        for (int i = 1; i + 1 < rh; i++) {
            int k = j * rh + i;
            add_second(H, nodes, k - 1, k, k + 1, wu);
        }
    for (int j = 1; j + 1 < rd; j++)
        for (int i = 0; i < rh; i++) {
            int k = j * rh + i;
            add_second(H, nodes, k - rh, k, k + rh, wv);
        }
}

/* The ridge: TAB_RIDGE_PRIOR of the prior's weakest weight (so that it
 * never competes with the prior where the prior alone sets the nodes), or
 * without a prior TAB_RIDGE_DATA of H's largest diagonal entry. */
static double operator_ridge(const tab_grid *g, double lambda, const double *H)
{
    int nodes = tab_nodes(g);
    double wu, wv, dmax = 0.0;
    if (lambda > 0.0) {
        tab_prior_weights(g, lambda, &wu, &wv);
        return TAB_RIDGE_PRIOR * (g->res_d > 2 ? fmin(wu, wv) : wu);
    }
    for (int k = 0; k < nodes; k++)
        dmax = fmax(dmax, H[(size_t)k * nodes + k]);
    return TAB_RIDGE_DATA * (dmax > 0.0 ? dmax : 1.0);
}

void tab_operator_free(tab_operator *op)
{
    if (!op)
        return;
    free(op->H);
    free(op->R);
    memset(op, 0, sizeof *op);
}

int tab_operator_build(const tab_design *d, double lambda, tab_operator *out, glint_err *err)
{
    int nodes = tab_nodes(&d->g), rc;
    size_t nn = (size_t)nodes * nodes;
    memset(out, 0, sizeof *out);
    if (!isfinite(lambda) || lambda < 0.0)
        return glint_err_set(err, GLINT_EINVAL, "tab: lambda %g must be finite and >= 0", lambda);
    out->nodes = nodes;
    out->lambda = lambda;
    out->H = malloc(nn * sizeof *out->H);
    out->R = malloc(nn * sizeof *out->R);
    if (!out->H || !out->R) {
        tab_operator_free(out);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab operator, %d nodes)", nodes);
    }
    for (size_t k = 0; k < nn; k++)
        out->H[k] = d->gram[k] / d->n;
    tab_prior_add(&d->g, lambda, out->H);
    out->ridge = operator_ridge(&d->g, lambda, out->H);
    for (int k = 0; k < nodes; k++)
        out->H[(size_t)k * nodes + k] += out->ridge;
    if ((rc = lsq_factor(out->H, nodes, out->R, err))) {
        tab_operator_free(out);
        return rc;
    }
    return 0;
}

/* ---- the solve ------------------------------------------------------------------------------ */

/* q = A'y / n per channel (OUT: q[3 nodes], channel-major) and y'y / n. */
static void solve_rhs(const tab_design *d, const float *rgb, double *q, double ff[3])
{
    int nodes = tab_nodes(&d->g), rh = d->g.res_h;
    const int off[4] = {0, 1, rh, rh + 1};
    memset(q, 0, 3 * (size_t)nodes * sizeof *q);
    ff[0] = ff[1] = ff[2] = 0.0;
    for (int i = 0; i < d->n; i++) {
        double w[4];
        tab_design_weights(d, i, w);
        for (int c = 0; c < 3; c++) {
            double y = rgb[3 * (size_t)i + c];
            double *qc = q + (size_t)c * nodes + d->k0[i];
            for (int a = 0; a < 4; a++)
                qc[off[a]] += w[a] * y;
            ff[c] += y * y;
        }
    }
    for (size_t k = 0; k < 3 * (size_t)nodes; k++)
        q[k] /= d->n;
    for (int c = 0; c < 3; c++)
        ff[c] /= d->n;
}

/* R'R x = q with the upper factor R (row-major), x overwriting q. */
static void solve_factored(const tab_operator *op, double *x)
{
    cblas_dtrsv(CblasRowMajor, CblasUpper, CblasTrans, CblasNonUnit, op->nodes, op->R,
                op->nodes, x, 1);
    cblas_dtrsv(CblasRowMajor, CblasUpper, CblasNoTrans, CblasNonUnit, op->nodes, op->R,
                op->nodes, x, 1);
}

/* One channel under t >= 0 (OUT: x[nodes]; x0: nodes of scratch).  The
 * active set starts from the unconstrained answer clipped at 0 (feasible,
 * and most nodes of a painted table are positive: fewer steps than from 0). */
static int solve_nonneg(const tab_operator *op, const double *q, double ff, lsq_work *w,
                        double *x, double *x0, tab_solve_report *rep, int c, glint_err *err)
{
    lsq_problem p = {.n = op->nodes, .H = op->H, .q = q, .ff = ff, .R0 = op->R, .c0 = x0};
    lsq_result res;
    int rc;
    memcpy(x0, q, (size_t)op->nodes * sizeof *x0);
    solve_factored(op, x0);
    for (int k = 0; k < op->nodes; k++)
        x0[k] = fmax(x0[k], 0.0);
    rc = lsq_solve(&p, LSQ_NONNEG, 0.0, w, x, &res, err);
    if (rc)
        return rc;
    if (res.status != LSQ_OK)
        return glint_err_set(err, GLINT_ENUMERIC, "tab: channel %d: the solver stopped (%s)",
                             c, lsq_status_name(res.status));
    rep->iterations[c] = res.iterations;
    rep->at_zero[c] = op->nodes - res.free_vars;
    rep->kkt[c] = res.kkt_residual;
    return 0;
}

int tab_solve(const tab_design *d, const tab_operator *op, const float *rgb, int nonneg,
              double *t, tab_solve_report *rep, glint_err *err)
{
    int nodes = tab_nodes(&d->g), rc = 0;
    double *q = malloc(5 * (size_t)nodes * sizeof *q), *x, *x0, ff[3];
    lsq_work *w = nonneg ? lsq_work_new(nodes, 0) : NULL;
    tab_solve_report r;
    memset(&r, 0, sizeof r);
    if (!q || (nonneg && !w)) {
        free(q);
        lsq_work_free(w);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab solve, %d nodes)", nodes);
    }
    x = q + 3 * (size_t)nodes;
    x0 = x + nodes;
    solve_rhs(d, rgb, q, ff);
    for (int c = 0; c < 3 && !rc; c++) {
        const double *qc = q + (size_t)c * nodes;
        if (nonneg) {
            rc = solve_nonneg(op, qc, ff[c], w, x, x0, &r, c, err);
        } else {
            memcpy(x, qc, (size_t)nodes * sizeof *x);
            solve_factored(op, x);
        }
        for (int k = 0; k < nodes && !rc; k++) {
            t[3 * (size_t)k + c] = x[k];
            r.negative[c] += x[k] < 0.0;
        }
    }
    free(q);
    lsq_work_free(w);
    if (rep)
        *rep = r;
    return rc;
}

/* ---- a table that multiplies a known function ----------------------------------------------- */

/* Per channel c, the scaled design's Gram matrix and right-hand side
 * (sums over the samples, OUT: H, q), the painted values' mean square
 * (*ff) and the rows' scale's, scale ci (*msq). */
static void scaled_normal(const tab_design *d, const float *scale, const float *rgb, int c,
                          double *H, double *q, double *ff, double *msq)
{
    int nodes = tab_nodes(&d->g), rh = d->g.res_h;
    const int off[4] = {0, 1, rh, rh + 1};
    double m = 0.0, yy = 0.0;
    memset(H, 0, (size_t)nodes * nodes * sizeof *H);
    memset(q, 0, (size_t)nodes * sizeof *q);
    for (int i = 0; i < d->n; i++) {
        double w[4], sc = scale[3 * (size_t)i + c], y = rgb[3 * (size_t)i + c];
        tab_design_weights(d, i, w);
        for (int a = 0; a < 4; a++)
            w[a] *= sc;
        for (int a = 0; a < 4; a++) {
            double *row = H + (size_t)(d->k0[i] + off[a]) * nodes + d->k0[i];
            for (int b = 0; b < 4; b++)
                row[off[b]] += w[a] * w[b];
            q[d->k0[i] + off[a]] += w[a] * y;
        }
        m += sc * sc * d->ci[i] * d->ci[i];
        yy += y * y;
    }
    *msq = m / d->n;
    *ff = yy / d->n;
}

/* One channel's solve from its normal equations: H (nodes x nodes) and q
 * hold the sums over the samples of the design and its products with the
 * painting, ff the painting's mean square and msq the mean square of the
 * rows' scale; the data term is divided by n msq, the prior and the pull
 * added, the result in x (R, x0: nodes^2 and nodes of scratch). */
static int solve_channel(const tab_grid *g, const tab_scaled_opts *o, int n, double msq,
                         double ff, double *H, double *q, double *R, double *x, double *x0,
                         lsq_work *w, tab_solve_report *r, int c, glint_err *err)
{
    int nodes = tab_nodes(g), rc;
    size_t nn = (size_t)nodes * nodes;
    double ridge;
    for (size_t k = 0; k < nn; k++)
        H[k] /= n * msq;
    for (int k = 0; k < nodes; k++)
        q[k] = q[k] / (n * msq) + o->pull * o->target;
    ff /= msq;
    tab_prior_add(g, o->lambda, H);
    ridge = o->pull > 0.0 ? o->pull : operator_ridge(g, o->lambda, H);
    for (int k = 0; k < nodes; k++)
        H[(size_t)k * nodes + k] += ridge;
    if ((rc = lsq_factor(H, nodes, R, err)))
        return rc;
    memcpy(x0, q, (size_t)nodes * sizeof *x0);
    cblas_dtrsv(CblasRowMajor, CblasUpper, CblasTrans, CblasNonUnit, nodes, R, nodes, x0, 1);
    cblas_dtrsv(CblasRowMajor, CblasUpper, CblasNoTrans, CblasNonUnit, nodes, R, nodes, x0, 1);
    if (o->nonneg) {
        lsq_problem p = {.n = nodes, .H = H, .q = q, .ff = ff, .R0 = R, .c0 = x0};
        lsq_result res;
        for (int k = 0; k < nodes; k++)
            x0[k] = fmax(x0[k], 0.0);
        if ((rc = lsq_solve(&p, LSQ_NONNEG, 0.0, w, x, &res, err)))
            return rc;
        if (res.status != LSQ_OK)
            return glint_err_set(err, GLINT_ENUMERIC, "tab: channel %d: the solver stopped (%s)",
                                 c, lsq_status_name(res.status));
        r->iterations[c] = res.iterations;
        r->at_zero[c] = nodes - res.free_vars;
        r->kkt[c] = res.kkt_residual;
    } else {
        memcpy(x, x0, (size_t)nodes * sizeof *x);
    }
    for (int k = 0; k < nodes; k++)
        r->negative[c] += x[k] < 0.0;
    return 0;
}

static int scaled_opts_check(const tab_scaled_opts *o, glint_err *err)
{
    if (!isfinite(o->lambda) || o->lambda < 0.0 || !isfinite(o->pull) || o->pull < 0.0 ||
        !isfinite(o->target))
        return glint_err_set(err, GLINT_EINVAL,
                             "tab: lambda %g and pull %g must be finite and >= 0, target %g "
                             "finite",
                             o->lambda, o->pull, o->target);
    return 0;
}

/* Channel c's table is the target everywhere: the rows' scale is 0. */
static void scale_zero(int nodes, const tab_scaled_opts *o, int c, double *t,
                       tab_solve_report *r)
{
    for (int k = 0; k < nodes; k++)
        t[3 * (size_t)k + c] = o->target;
    r->scale_zero[c] = 1;
}

int tab_solve_scaled(const tab_design *d, const tab_scaled_opts *o, const float *scale,
                     const float *rgb, double *t, tab_solve_report *rep, glint_err *err)
{
    int nodes = tab_nodes(&d->g), rc = 0;
    size_t nn = (size_t)nodes * nodes;
    double *H = malloc(2 * nn * sizeof *H), *q = malloc(3 * (size_t)nodes * sizeof *q);
    lsq_work *w = o->nonneg ? lsq_work_new(nodes, 0) : NULL;
    tab_solve_report r;
    memset(&r, 0, sizeof r);
    if ((rc = scaled_opts_check(o, err)))
        goto done;
    if (!H || !q || (o->nonneg && !w)) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory (tab scaled solve, %d nodes)", nodes);
        goto done;
    }
    for (int c = 0; c < 3 && !rc; c++) {
        double *x = q + nodes, ff, msq;
        scaled_normal(d, scale, rgb, c, H, q, &ff, &msq);
        if (!(msq > 0.0) || !isfinite(msq)) {
            /* the known function is 0 on every sample: nothing to scale */
            scale_zero(nodes, o, c, t, &r);
            continue;
        }
        rc = solve_channel(&d->g, o, d->n, msq, ff, H, q, H + nn, x, q + 2 * (size_t)nodes, w,
                           &r, c, err);
        for (int k = 0; k < nodes && !rc; k++)
            t[3 * (size_t)k + c] = x[k];
    }
done:
    free(H);
    free(q);
    lsq_work_free(w);
    if (rep)
        *rep = r;
    return rc;
}

/* ---- a table whose rows are sums -------------------------------------------------------- */

#define ROWS_BLOCK 128 /* rows filled and added to the Gram matrices at a time */

/* The three channels' normal equations of every row (OUT H: 3 nodes^2,
 * q: 3 nodes, ff[3], msq[3]: sums, not means), a block of rows at a time. */
static int rows_normal(const tab_grid *g, int n, tab_rows_fill fill, void *cls, double *A,
                       float *y, double *H, double *q, double ff[3], double msq[3],
                       glint_err *err)
{
    int nodes = tab_nodes(g), rc;
    size_t nn = (size_t)nodes * nodes;
    memset(H, 0, 3 * nn * sizeof *H);
    memset(q, 0, 3 * (size_t)nodes * sizeof *q);
    for (int c = 0; c < 3; c++)
        ff[c] = msq[c] = 0.0;
    for (int i0 = 0; i0 < n; i0 += ROWS_BLOCK) {
        int m = n - i0 < ROWS_BLOCK ? n - i0 : ROWS_BLOCK;
        memset(A, 0, 3 * (size_t)m * nodes * sizeof *A);
        if ((rc = fill(cls, i0, m, A, y, err)))
            return rc;
        for (int c = 0; c < 3; c++) {
            const double *Ac = A + (size_t)c * m * nodes;
            for (int i = 0; i < m; i++) {
                double s = 0.0, yi = y[3 * (size_t)i + c];
                const double *row = Ac + (size_t)i * nodes;
                for (int k = 0; k < nodes; k++)
                    s += row[k];
                cblas_daxpy(nodes, yi, row, 1, q + (size_t)c * nodes, 1);
                msq[c] += s * s;
                ff[c] += yi * yi;
            }
            cblas_dsyrk(CblasRowMajor, CblasUpper, CblasTrans, nodes, m, 1.0, Ac, nodes, 1.0,
                        H + c * nn, nodes);
        }
    }
    for (int c = 0; c < 3; c++) /* dsyrk wrote the upper triangle */
        for (int a = 0; a < nodes; a++)
            for (int b = 0; b < a; b++)
                H[c * nn + (size_t)a * nodes + b] = H[c * nn + (size_t)b * nodes + a];
    return 0;
}

int tab_solve_rows(const tab_grid *g, int n, const tab_scaled_opts *o, tab_rows_fill fill,
                   void *cls, double *t, tab_solve_report *rep, glint_err *err)
{
    int nodes = tab_nodes(g), rc = 0;
    size_t nn = (size_t)nodes * nodes;
    double *H = malloc(4 * nn * sizeof *H), *q = malloc(5 * (size_t)nodes * sizeof *q);
    double *A = malloc(3 * (size_t)ROWS_BLOCK * nodes * sizeof *A), ff[3], msq[3];
    float *y = malloc(3 * (size_t)ROWS_BLOCK * sizeof *y);
    lsq_work *w = o->nonneg ? lsq_work_new(nodes, 0) : NULL;
    tab_solve_report r;
    memset(&r, 0, sizeof r);
    if ((rc = scaled_opts_check(o, err)))
        goto done;
    if (n < 1) {
        rc = glint_err_set(err, GLINT_EINVAL, "tab: no rows");
        goto done;
    }
    if (!H || !q || !A || !y || (o->nonneg && !w)) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory (tab solve, %d rows, %d nodes)", n,
                           nodes);
        goto done;
    }
    if ((rc = rows_normal(g, n, fill, cls, A, y, H, q, ff, msq, err)))
        goto done;
    for (int c = 0; c < 3 && !rc; c++) {
        double *x = q + 3 * (size_t)nodes, m = msq[c] / n;
        if (!(m > 0.0) || !isfinite(m)) {
            scale_zero(nodes, o, c, t, &r);
            continue;
        }
        rc = solve_channel(g, o, n, m, ff[c] / n, H + c * nn, q + (size_t)c * nodes, H + 3 * nn,
                           x, x + nodes, w, &r, c, err);
        for (int k = 0; k < nodes && !rc; k++)
            t[3 * (size_t)k + c] = x[k];
    }
done:
    free(H);
    free(q);
    free(A);
    free(y);
    lsq_work_free(w);
    if (rep)
        *rep = r;
    return rc;
}
