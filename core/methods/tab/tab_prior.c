/* tab_prior.c: the learned prior over tables and the completion of a
 * fitted table with it (tab_prior.h). */
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "tab_prior.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---- the learning tables ------------------------------------------------------------------ */

/* wi and wo of the pair with half angle th (h in the x-z plane), difference
 * angle td and difference azimuth pd, about n = z. */
static void pair_at(double th, double td, double pd, double wi[3], double wo[3])
{
    double h[3] = {sin(th), 0.0, cos(th)};
    double d[3] = {sin(td) * cos(pd), sin(td) * sin(pd), cos(td)};
    double ct = cos(th), st = sin(th), hd;
    /* d is wi in the frame whose z is h: turn that frame about y by th */
    wi[0] = ct * d[0] + st * d[2];
    wi[1] = d[1];
    wi[2] = -st * d[0] + ct * d[2];
    hd = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2];
    for (int e = 0; e < 3; e++)
        wo[e] = 2.0 * hd * h[e] - wi[e];
}

void tab_prior_table(const tab_grid *g, const measured_truth *mt, double *t)
{
    const double n[3] = {0.0, 0.0, 1.0}, top = 0.5 * M_PI - PRIOR_EDGE;
    for (int j = 0; j < g->res_d; j++)
        for (int i = 0; i < g->res_h; i++) {
            double th = fmin(tab_theta_h(g, i), top), td = fmin(tab_theta_d(g, j), top);
            double acc[3] = {0.0, 0.0, 0.0};
            int used = 0;
            for (int a = 0; a < PRIOR_PHI; a++) {
                double wi[3], wo[3], f[3];
                pair_at(th, td, M_PI * (a + 0.5) / PRIOR_PHI, wi, wo);
                if (!(wi[2] > 1e-6 && wo[2] > 1e-6))
                    continue;
                measured_eval(mt, n, wi, wo, f);
                for (int c = 0; c < 3; c++)
                    acc[c] += f[c];
                used++;
            }
            if (!used) {
                /* h near the horizon: only phi_d = pi/2 keeps both above it */
                double wi[3], wo[3];
                pair_at(th, td, 0.5 * M_PI, wi, wo);
                measured_eval(mt, n, wi, wo, acc);
                used = 1;
            }
            for (int c = 0; c < 3; c++)
                t[3 * (size_t)(j * g->res_h + i) + c] = fmax(acc[c], 0.0) / used;
        }
}

/* ---- learning ------------------------------------------------------------------------------- */

void tab_prior_free(tab_prior *p)
{
    if (!p)
        return;
    free(p->mu);
    free(p->Q);
    memset(p, 0, sizeof *p);
}

/* The samples' log tables, one row per material and channel (OUT: X, m
 * rows of nodes). */
static void sample_rows(const tab_grid *g, int nodes, const measured_set *s,
                        measured_model model, const int *use, int nuse, double *tbuf, double *X)
{
    for (int a = 0; a < nuse; a++) {
        measured_truth mt;
        measured_truth_of(&s->m[use[a]], model, &mt);
        tab_prior_table(g, &mt, tbuf);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < nodes; k++)
                X[(size_t)(3 * a + c) * nodes + k] = log(tbuf[3 * (size_t)k + c] + PRIOR_EPS);
    }
}

/* Centre X's columns (OUT: mu), then its thin SVD: OUT sv[min(m, nodes)],
 * VT (min(m, nodes) x nodes). */
static int principal(double *X, int m, int nodes, double *mu, double *sv, double *VT,
                     glint_err *err)
{
    int r = m < nodes ? m : nodes, info;
    double *U = malloc((size_t)m * r * sizeof *U);
    if (!U)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab prior)");
    for (int k = 0; k < nodes; k++) {
        double sum = 0.0;
        for (int i = 0; i < m; i++)
            sum += X[(size_t)i * nodes + k];
        mu[k] = sum / m;
        for (int i = 0; i < m; i++)
            X[(size_t)i * nodes + k] -= mu[k];
    }
    info = LAPACKE_dgesdd(LAPACK_ROW_MAJOR, 'S', m, nodes, X, nodes, sv, U, r, VT, nodes);
    free(U);
    if (info)
        return glint_err_set(err, GLINT_ENUMERIC, "tab prior: LAPACKE_dgesdd failed (info %d)",
                             info);
    return 0;
}

/* The rows of theta_d a prior on g covers. */
static int prior_rows(const tab_grid *g)
{
    int rows = 0;
    while (rows < g->res_d && tab_theta_d(g, rows) <= PRIOR_TD_MAX * M_PI / 180.0 + 1e-9)
        rows++;
    return rows;
}

int tab_prior_learn(const tab_grid *g, const measured_set *s, measured_model model,
                    tab_prior_keep keep, const void *keep_cls, int k, tab_prior *out,
                    glint_err *err)
{
    int nodes = prior_rows(g) * g->res_h, nuse = 0, m, r, rc = 0;
    int *use = NULL;
    double *X = NULL, *tbuf = NULL, *sv = NULL, *VT = NULL, total = 0.0, kept = 0.0;

    memset(out, 0, sizeof *out);
    if (k < 1 || k > PRIOR_K_MAX)
        return glint_err_set(err, GLINT_EINVAL, "tab prior: components must be 1..%d, got %d",
                             PRIOR_K_MAX, k);
    if (!(use = malloc((size_t)(s->n > 0 ? s->n : 1) * sizeof *use)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab prior)");
    for (int i = 0; i < s->n; i++)
        if (!keep || keep(keep_cls, i, &s->m[i]))
            use[nuse++] = i;
    if (nuse < 2) {
        free(use);
        return glint_err_set(err, GLINT_EINVAL,
                             "tab prior: %d of the %d measured materials are left to learn "
                             "from; at least 2 are needed", nuse, s->n);
    }
    m = 3 * nuse;
    r = m < nodes ? m : nodes;
    if (k > r - 1)
        k = r - 1;
    X = malloc((size_t)m * nodes * sizeof *X);
    tbuf = malloc(3 * (size_t)tab_nodes(g) * sizeof *tbuf);
    sv = malloc((size_t)r * sizeof *sv);
    VT = malloc((size_t)r * nodes * sizeof *VT);
    out->mu = malloc((size_t)nodes * sizeof *out->mu);
    out->Q = malloc((size_t)nodes * k * sizeof *out->Q);
    if (!X || !tbuf || !sv || !VT || !out->mu || !out->Q) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory (tab prior)");
        goto done;
    }
    sample_rows(g, nodes, s, model, use, nuse, tbuf, X);
    if ((rc = principal(X, m, nodes, out->mu, sv, VT, err)))
        goto done;
    for (int j = 0; j < r; j++) {
        total += sv[j] * sv[j];
        if (j < k)
            kept += sv[j] * sv[j];
    }
    for (int a = 0; a < nodes; a++)
        for (int j = 0; j < k; j++)
            out->Q[(size_t)a * k + j] = VT[(size_t)j * nodes + a] * sv[j] / sqrt(m - 1.0);
    out->g = *g;
    out->nodes = nodes;
    out->k = k;
    out->materials = nuse;
    /* floor the residual so that a prior whose k directions hold every
     * sample still lets the data move the nodes it observes */
    out->s2 = fmax((total - kept) / (m - 1.0) / nodes, 1e-8);
    out->explained = total > 0.0 ? kept / total : 1.0;
done:
    free(use);
    free(X);
    free(tbuf);
    free(sv);
    free(VT);
    if (rc)
        tab_prior_free(out);
    return rc;
}

/* ---- the completion ------------------------------------------------------------------------- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Observation variances from the design's data weights (OUT: v[nodes], the
 * covered nodes,
 * INFINITY where unobserved); returns the observed count, or -1 when out
 * of memory. */
static int obs_variances(const tab_design *d, int nodes, double noise, double *v)
{
    int nall = tab_nodes(&d->g), nobs = 0;
    double *w = malloc((size_t)nodes * sizeof *w), med;
    if (!w)
        return -1;
    for (int k = 0; k < nodes; k++) {
        double wk = d->gram[(size_t)k * nall + k];
        if (wk > 0.0)
            w[nobs++] = wk;
    }
    if (nobs) {
        qsort(w, (size_t)nobs, sizeof *w, cmp_double);
        med = w[nobs / 2];
        for (int k = 0; k < nodes; k++) {
            double wk = d->gram[(size_t)k * nall + k];
            v[k] = wk > 0.0 ? noise * noise * med / wk : INFINITY;
        }
    }
    free(w);
    return nobs;
}

/* One channel: OUT g (p->nodes), the prediction mu + Q c with c's
 * posterior mean given the observed g0; A and b are k x k and k scratch.
 * Returns |c|, or -1 when the solve fails. */
static double predict_channel(const tab_prior *p, const double *v, const double *g0, double *g,
                              double *A, double *b)
{
    int nodes = p->nodes, k = p->k;
    double norm = 0.0;
    memset(A, 0, (size_t)k * k * sizeof *A);
    memset(b, 0, (size_t)k * sizeof *b);
    for (int j = 0; j < k; j++)
        A[(size_t)j * k + j] = 1.0;
    for (int a = 0; a < nodes; a++) {
        const double *q = p->Q + (size_t)a * k;
        double iv, r;
        if (!isfinite(v[a]))
            continue;
        iv = 1.0 / (p->s2 + v[a]);
        r = (g0[a] - p->mu[a]) * iv;
        for (int i = 0; i < k; i++) {
            b[i] += q[i] * r;
            for (int j = 0; j <= i; j++)
                A[(size_t)i * k + j] += q[i] * q[j] * iv;
        }
    }
    if (LAPACKE_dposv(LAPACK_ROW_MAJOR, 'L', k, 1, A, k, b, 1))
        return -1.0;
    for (int a = 0; a < nodes; a++) {
        const double *q = p->Q + (size_t)a * k;
        g[a] = p->mu[a];
        for (int i = 0; i < k; i++)
            g[a] += q[i] * b[i];
    }
    for (int i = 0; i < k; i++)
        norm += b[i] * b[i];
    return sqrt(norm);
}

int tab_prior_predict(const tab_prior *p, const tab_design *d, double noise, const double *t0,
                      double *t, tab_prior_report *rep, glint_err *err)
{
    int nodes = p->nodes, nall = tab_nodes(&d->g), nobs, rc = 0;
    double *v, *g0, *g, *A, *b;
    if (p->g.res_h != d->g.res_h || p->g.res_d != d->g.res_d)
        return glint_err_set(err, GLINT_EINTERNAL, "tab prior: a prior of another grid");
    if (!(noise > 0.0) || !isfinite(noise))
        return glint_err_set(err, GLINT_EINVAL, "tab prior: noise must be > 0");
    v = malloc((size_t)nodes * sizeof *v);
    g0 = malloc((size_t)nodes * sizeof *g0);
    g = malloc((size_t)nodes * sizeof *g);
    A = malloc((size_t)p->k * p->k * sizeof *A);
    b = malloc((size_t)p->k * sizeof *b);
    if (!v || !g0 || !g || !A || !b || (nobs = obs_variances(d, nodes, noise, v)) < 0) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory (tab prior)");
        goto done;
    }
    memcpy(t, t0, 3 * (size_t)nall * sizeof *t);
    if (rep)
        memset(rep, 0, sizeof *rep), rep->observed = nobs;
    for (int c = 0; c < 3 && nobs; c++) {
        double cn;
        for (int a = 0; a < nodes; a++)
            g0[a] = log(fmax(t0[3 * (size_t)a + c], 0.0) + PRIOR_EPS);
        if ((cn = predict_channel(p, v, g0, g, A, b)) < 0.0) {
            rc = glint_err_set(err, GLINT_ENUMERIC, "tab prior: the posterior is not definite");
            goto done;
        }
        for (int a = 0; a < nodes; a++)
            t[3 * (size_t)a + c] = fmax(exp(g[a]) - PRIOR_EPS, 0.0);
        if (rep)
            rep->coef_norm[c] = cn;
    }
done:
    free(v);
    free(g0);
    free(g);
    free(A);
    free(b);
    return rc;
}

/* Per column, the first and last rows of theta_d whose nodes the
 * painting weighs on at least `painted` times as much as the column's
 * most weighed node (OUT: lo[res_h], hi[res_h]; -1 for a column no sample
 * reaches).  Per column because the cells are of unequal size (narrow near
 * the highlight): there a node is weighed on less and painted as well. */
static void painted_rows(const tab_design *d, int rows, double painted, int *lo, int *hi)
{
    int rh = d->g.res_h, nall = tab_nodes(&d->g);
    for (int i = 0; i < rh; i++) {
        double top = 0.0;
        for (int j = 0; j < rows; j++) {
            size_t k = (size_t)j * rh + i;
            top = fmax(top, d->gram[k * nall + k]);
        }
        lo[i] = hi[i] = -1;
        for (int j = 0; j < rows && top > 0.0; j++) {
            size_t k = (size_t)j * rh + i;
            if (d->gram[k * nall + k] > 0.0 && d->gram[k * nall + k] >= painted * top) {
                if (lo[i] < 0)
                    lo[i] = j;
                hi[i] = j;
            }
        }
    }
}

int tab_prior_complete(const tab_prior *p, const tab_design *d, const tab_prior_opts *o,
                       double *t, tab_prior_report *rep, glint_err *err)
{
    int nall = tab_nodes(&d->g), rh = d->g.res_h, rows = p->nodes / rh, rc;
    double *pred = malloc(3 * (size_t)nall * sizeof *pred);
    int *lo = malloc((size_t)rh * sizeof *lo), *hi = malloc((size_t)rh * sizeof *hi);
    if (!(o->painted >= 0.0 && o->painted <= 1.0)) {
        rc = glint_err_set(err, GLINT_EINVAL, "tab prior: painted must be in [0, 1]");
        goto done;
    }
    if (!pred || !lo || !hi) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory (tab prior)");
        goto done;
    }
    painted_rows(d, rows, o->painted, lo, hi);
    if ((rc = tab_prior_predict(p, d, o->noise, t, pred, rep, err)))
        goto done;

    for (int c = 0; c < 3; c++) {
        double top = 0.0, moved = 0.0;
        for (int a = 0; a < nall; a++)
            top = fmax(top, fabs(t[3 * (size_t)a + c]));
        for (int i = 0; i < rh; i++) {
            if (lo[i] < 0)
                continue;
            for (int j = 0; j < rows; j++) {
                int anchor = j < lo[i] ? lo[i] : j > hi[i] ? hi[i] : -1;
                size_t e = 3 * (size_t)(j * rh + i) + c, ea;
                double x;
                if (anchor < 0)
                    continue;
                /* continue the fitted table from its last painted row along
                 * the prediction's shape */
                ea = 3 * (size_t)(anchor * rh + i) + c;
                x = fmax(t[ea], 0.0) * (pred[e] + PRIOR_EPS) / (pred[ea] + PRIOR_EPS);
                moved = fmax(moved, fabs(x - t[e]));
                t[e] = x;
            }
        }
        if (rep)
            rep->changed[c] = top > 0.0 ? moved / top : 0.0;
    }
done:
    free(pred);
    free(lo);
    free(hi);
    return rc;
}
