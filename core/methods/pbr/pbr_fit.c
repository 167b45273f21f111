/* pbr_fit.c: the fit of pbr.h's model by GSL's nonlinear least squares
 * (trust region, Levenberg-Marquardt steps, Cholesky solves, More
 * scaling), in its large-problem form (gsl_multilarge_nlinear): the
 * Jacobian is never stored, each pass over the samples accumulates J'J
 * (p x p) and J'f, so an iteration costs two passes over the samples and
 * O(p^2) memory beyond the residual vector (multifit_nlinear's stored J,
 * 3n x p, and its column norms took most of the time).
 *
 * Protocol:
 *   1. starts: for each of o->starts roughnesses (PBR_START_ALPHA, in
 *      order), kd and ks from a linear least-squares solve with that
 *      roughness and a fixed Fresnel (ior 1.5; conductor F0 0.5), the
 *      coefficients kept >= 0 (every subset of the at most three columns
 *      tried); then Levenberg-Marquardt on o->subset samples (the brightest
 *      eighth, where the highlight is, and an even stride over the rest).
 *      The starts run side by side on the pool (par.h), each in its own
 *      workspace; the best is taken in start order, so the answer is the
 *      one they give one after another;
 *   2. the start of least cost refined on o->refine samples drawn as the
 *      starts' are (16,384 by default: one pass over 98,434 samples costs
 *      about 20 ms, and 8 parameters are well measured by a sixth of them),
 *      or on every sample, with the bounds as an active set: after
 *      PBR_PIN_AFTER iterations the weights (kd, ks, F0), in which the
 *      model is linear at a given roughness and ior, are solved exactly
 *      with their bounds, and the parameters the answer puts on a bound
 *      are held there while the search goes on (refine_pinned; one lobe);
 *   3. parameters within PBR_BOUND_TOL of a bound (in the sigmoid) set to
 *      it; the cost, J'J and the residual variance s^2 computed on every
 *      sample;
 *   4. what the views determine: on J'J scaled by the parameters' ranges
 *      (D J'J D), eigenvalues below PBR_NULL_REL times the largest span
 *      directions the samples do not see; a parameter mostly (weight > 1/2)
 *      in those is undetermined, and so is one whose standard error exceeds
 *      half its range, and a lobe's roughness and Fresnel when its ks is 0.
 *      Standard errors of the parameters inside their bounds from the
 *      pseudo-inverse: sigma_k = sqrt(s^2 (D (DJ'JD)^+ D)_kk).
 *
 * Residuals are plain differences of values f ci (no weights, no robust
 * loss: the paintings are the truth here, not measurements with outliers). */
#include <gsl/gsl_blas.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_multilarge_nlinear.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "lsq.h"
#include "par.h"
#include "pbr.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define PBR_NULL_REL 1e-10
/* GSL's tests: step (relative, in u), gradient, cost change; a start stops
 * after PBR_START_ITER iterations at most (it only has to find the basin).
 * A step of a millionth of the position is far below any parameter's
 * standard error: at 1e-8 the last iterations of most fits changed no
 * figure bench_pbr prints (12 to 9 iterations on sgd:gray-plastic).  The
 * gradient and cost tests stay at 1e-8: at 1e-6 a mirror's roughness
 * stopped 3% above its floor instead of at it. */
#define PBR_XTOL 1e-6
#define PBR_GTOL 1e-8
#define PBR_FTOL 1e-8
#define PBR_START_ITER 25
/* The refinement's active set (refine_pinned): after PBR_PIN_AFTER
 * iterations, a weight (kd, ks, F0) within PBR_PIN_WEIGHT of a bound (of
 * its range) is held there, and a roughness within PBR_PROBE_ALPHA or an
 * ior within PBR_PROBE_IOR of one is tried on it (the weights solved anew)
 * and held there when the cost is no higher; a pin the cost does not hold
 * is released.  A roughness of 0.0147 tried on the floor (0.002) cost a
 * plastic 15% of its fit for nothing; an ior at 2.9 went on to 3. */
#define PBR_PIN_AFTER 10
#define PBR_PIN_WEIGHT 1e-4
#define PBR_PROBE_ALPHA 0.01
#define PBR_PROBE_IOR 0.1

static const double PBR_START_ALPHA[PBR_MAX_STARTS] = {0.05, 0.15, 0.4, 0.01, 0.7,
                                                       0.1,  0.25, 0.03};

/* Samples the LM runs over: cosines and values (pointers into the caller's
 * arrays, or a subset's copies). */
typedef struct pbr_set {
    pbr_geom g;
    const float *y;
    /* a subset's own copies (NULL for the caller's arrays): set_free */
    double *own_d;
    float *own_y;
} pbr_set;

static void set_free(pbr_set *s)
{
    free(s->own_d);
    free(s->own_y);
    if (s->own_d) { /* a subset's off and w are its own too */
        free(s->g.off);
        free(s->g.w);
    }
    memset(s, 0, sizeof *s);
}

typedef struct lm_ctx {
    const pbr_spec *sp;
    const pbr_set *s;
    double lo[PBR_MAXP], hi[PBR_MAXP];
    int np;
    const int *view; /* every sample's view (pbr_fit_opts), NULL: none */
    /* the refinement's pins (refine_pinned): -1 or +1 holds parameter k at
     * its lower or upper bound, out of the search (dp/du 0); 0 free */
    int pin[PBR_MAXP];
} lm_ctx;

static pthread_once_t gsl_handler_once = PTHREAD_ONCE_INIT;

static void gsl_handler_off(void)
{
    gsl_set_error_handler_off();
}

static double sigm(double x)
{
    return 1.0 / (1.0 + exp(-x));
}

static void u_to_p(const lm_ctx *cx, const double *u, double *p, double *dpdu)
{
    for (int k = 0; k < cx->np; k++) {
        double s = sigm(u[k]), r = cx->hi[k] - cx->lo[k];
        if (cx->pin[k]) {
            p[k] = cx->pin[k] < 0 ? cx->lo[k] : cx->hi[k];
            if (dpdu)
                dpdu[k] = 0.0;
            continue;
        }
        p[k] = cx->lo[k] + r * s;
        if (dpdu)
            dpdu[k] = r * s * (1.0 - s);
    }
}

static void p_to_u(const lm_ctx *cx, const double *p, double *u)
{
    for (int k = 0; k < cx->np; k++) {
        double y = (p[k] - cx->lo[k]) / (cx->hi[k] - cx->lo[k]);
        y = fmin(fmax(y, 1e-12), 1.0 - 1e-12);
        u[k] = log(y / (1.0 - y));
    }
}

/* The passes over the samples run as PBR_BLOCKS blocks of consecutive
 * samples, each with its own sums, combined in block order: the result does
 * not depend on how many threads ran them (par.h).  They run on the pool
 * when the terms are worth it (par_worth), otherwise in turn here. */
#define PBR_BLOCKS 16

typedef struct pass {
    const lm_ctx *cx;
    const double *p, *dpdu;
    const gsl_vector *u;          /* df: the vector J or J' multiplies (NULL: none) */
    gsl_vector *v;                /* df: the product; f: the residuals */
    int trans;                    /* df: 1 for J'u */
    int want_jtj;
    double ss[PBR_BLOCKS];        /* f: each block's sum of squared residuals */
    double jtu[PBR_BLOCKS][PBR_MAXP];
    double A[PBR_BLOCKS][PBR_MAXP][PBR_MAXP];
} pass;

static void block_range(int n, int b, int *i0, int *i1)
{
    *i0 = (int)((long)n * b / PBR_BLOCKS);
    *i1 = (int)((long)n * (b + 1) / PBR_BLOCKS);
}

static void pass_run(pass *ps, par_fn fn)
{
    const pbr_geom *g = &ps->cx->s->g;
    if (par_worth((size_t)pbr_geom_terms(g) * 8))
        par_run(PBR_BLOCKS, fn, ps);
    else
        for (int b = 0; b < PBR_BLOCKS; b++)
            fn(ps, b);
}

static void f_block(void *ctx, int b)
{
    pass *ps = ctx;
    const lm_ctx *cx = ps->cx;
    const pbr_geom *g = &cx->s->g;
    double ss = 0.0;
    int i0, i1;
    block_range(g->n, b, &i0, &i1);
    if (!g->off) { /* point lights: the values a chunk at a time, summed as below */
        double mc[3][PBR_CHUNK];
        for (int i = i0; i < i1; i += PBR_CHUNK) {
            int n = i1 - i < PBR_CHUNK ? i1 - i : PBR_CHUNK;
            pbr_eval_chunk(cx->sp, ps->p, g->ci + i, g->co + i, g->ch + i, g->cd + i, n, mc, NULL);
            for (int j = 0; j < n; j++)
                for (int c = 0; c < 3; c++) {
                    size_t o = 3 * (size_t)(i + j) + c;
                    double r = mc[c][j] - cx->s->y[o];
                    ps->v->data[o] = r;
                    ss += r * r;
                }
        }
        ps->ss[b] = ss;
        return;
    }
    for (int i = i0; i < i1; i++) {
        double m[3];
        pbr_sample_eval(cx->sp, ps->p, g, i, m, NULL);
        for (int c = 0; c < 3; c++) {
            double r = m[c] - cx->s->y[3 * (size_t)i + c];
            ps->v->data[3 * (size_t)i + c] = r;
            ss += r * r;
        }
    }
    ps->ss[b] = ss;
}

static int lm_f(const gsl_vector *x, void *data, gsl_vector *f)
{
    const lm_ctx *cx = data;
    double p[PBR_MAXP], ss = 0.0;
    pass *ps = malloc(sizeof *ps);
    if (!ps)
        return GSL_ENOMEM;
    u_to_p(cx, x->data, p, NULL);
    ps->cx = cx;
    ps->p = p;
    ps->v = f;
    pass_run(ps, f_block);
    for (int b = 0; b < PBR_BLOCKS; b++)
        ss += ps->ss[b];
    free(ps);
    return isfinite(ss) ? GSL_SUCCESS : GSL_EDOM;
}

/* Sample i's rows of J (times dp/du, in place) into J'u or Ju, and J'J. */
static void df_sample(const pass *ps, int i, double J[3][PBR_MAXP], double (*A)[PBR_MAXP],
                      double *jtu)
{
    int np = ps->cx->np;
    for (int c = 0; c < 3; c++) {
        double *row = J[c];
        size_t r = 3 * (size_t)i + c;
        for (int k = 0; k < np; k++)
            row[k] *= ps->dpdu[k];
        if (ps->u && ps->v) {
            if (ps->trans) {
                double ur = gsl_vector_get(ps->u, r);
                for (int k = 0; k < np; k++)
                    jtu[k] += row[k] * ur;
            } else {
                double sv = 0.0;
                for (int k = 0; k < np; k++)
                    sv += row[k] * gsl_vector_get(ps->u, (size_t)k);
                gsl_vector_set(ps->v, r, sv);
            }
        }
        if (ps->want_jtj)
            for (int a = 0; a < np; a++)
                if (row[a] != 0.0)
                    for (int q = 0; q <= a; q++)
                        A[a][q] += row[a] * row[q];
    }
}

static void df_block(void *ctx, int b)
{
    pass *ps = ctx;
    const lm_ctx *cx = ps->cx;
    const pbr_geom *g = &cx->s->g;
    int np = cx->np, i0, i1;
    double (*A)[PBR_MAXP] = ps->A[b], *jtu = ps->jtu[b];
    memset(ps->A[b], 0, sizeof ps->A[b]);
    memset(ps->jtu[b], 0, sizeof ps->jtu[b]);
    block_range(g->n, b, &i0, &i1);
    if (!g->off) {
        /* point lights: J a chunk at a time (zeroed once: pbr_eval_chunk
         * writes the same entries every time), each sample's rows then
         * taken in order as below */
        double mc[3][PBR_CHUNK], Jc[3][PBR_MAXP][PBR_CHUNK];
        memset(Jc, 0, sizeof Jc);
        for (int i = i0; i < i1; i += PBR_CHUNK) {
            int n = i1 - i < PBR_CHUNK ? i1 - i : PBR_CHUNK;
            pbr_eval_chunk(cx->sp, ps->p, g->ci + i, g->co + i, g->ch + i, g->cd + i, n, mc, Jc);
            for (int j = 0; j < n; j++) {
                double J[3][PBR_MAXP];
                for (int c = 0; c < 3; c++)
                    for (int k = 0; k < np; k++)
                        J[c][k] = Jc[c][k][j];
                df_sample(ps, i + j, J, A, jtu);
            }
        }
        return;
    }
    for (int i = i0; i < i1; i++) {
        double m[3], J[3][PBR_MAXP];
        pbr_sample_eval(cx->sp, ps->p, g, i, m, J);
        df_sample(ps, i, J, A, jtu);
    }
}

/* J'u (TransJ = CblasTrans, u: 3n residuals, v: p) or J u (CblasNoTrans,
 * u: p, v: 3n), and J'J when JTJ is not NULL, J with respect to u. */
static int lm_df(CBLAS_TRANSPOSE_t TransJ, const gsl_vector *x, const gsl_vector *u, void *data,
                 gsl_vector *v, gsl_matrix *JTJ)
{
    const lm_ctx *cx = data;
    double p[PBR_MAXP], dpdu[PBR_MAXP];
    int np = cx->np;
    pass *ps = malloc(sizeof *ps);
    if (!ps)
        return GSL_ENOMEM;
    u_to_p(cx, x->data, p, dpdu);
    ps->cx = cx;
    ps->p = p;
    ps->dpdu = dpdu;
    ps->u = u;
    ps->v = v;
    ps->trans = TransJ == CblasTrans;
    ps->want_jtj = JTJ != NULL;
    pass_run(ps, df_block);
    if (u && v && ps->trans)
        for (int k = 0; k < np; k++) {
            double sk = 0.0;
            for (int b = 0; b < PBR_BLOCKS; b++)
                sk += ps->jtu[b][k];
            gsl_vector_set(v, (size_t)k, sk);
        }
    if (JTJ)
        for (int a = 0; a < np; a++)
            for (int q = 0; q <= a; q++) {
                double sa = 0.0;
                for (int b = 0; b < PBR_BLOCKS; b++)
                    sa += ps->A[b][a][q];
                gsl_matrix_set(JTJ, (size_t)a, (size_t)q, sa);
                gsl_matrix_set(JTJ, (size_t)q, (size_t)a, sa);
            }
    free(ps);
    return GSL_SUCCESS;
}

/* Levenberg-Marquardt from p (in and out) on cx's samples with workspace w
 * (sized for them). */
static void lm_run(const lm_ctx *cx, gsl_multilarge_nlinear_workspace *w, int max_iter, double *p,
                   pbr_start_report *rep)
{
    gsl_multilarge_nlinear_fdf fdf;
    double u[PBR_MAXP], nr;
    gsl_vector_view xv;
    int info = 0, status;

    rep->converged = 0;

    p_to_u(cx, p, u);
    xv = gsl_vector_view_array(u, (size_t)cx->np);
    memset(&fdf, 0, sizeof fdf);
    fdf.f = lm_f;
    fdf.df = lm_df;
    fdf.n = 3 * (size_t)cx->s->g.n;
    fdf.p = (size_t)cx->np;
    fdf.params = (void *)cx; /* read only: lm_f, lm_df */
    status = gsl_multilarge_nlinear_init(&xv.vector, &fdf, w);
    if (status == GSL_SUCCESS)
        status = gsl_multilarge_nlinear_driver((size_t)max_iter, PBR_XTOL, PBR_GTOL, PBR_FTOL,
                                               NULL, NULL, &info, w);
    rep->converged = status == GSL_SUCCESS;
    memcpy(u, gsl_multilarge_nlinear_position(w)->data, sizeof(double) * (size_t)cx->np);
    u_to_p(cx, u, p, NULL);
    nr = gsl_blas_dnrm2(gsl_multilarge_nlinear_residual(w));
    rep->cost = 0.5 * nr * nr;
    rep->iters = (int)gsl_multilarge_nlinear_niter(w);
    /* no progress possible at a minimum met exactly counts as converged */
    rep->converged = (rep->converged || status == GSL_ENOPROG) && isfinite(rep->cost);
    if (!isfinite(rep->cost))
        rep->cost = INFINITY;
}

/* Solve the k x k system G x = b (k <= 3) by Gaussian elimination with
 * partial pivoting; 0, or -1 when singular. */
static int small_solve(int k, const double G[3][3], const double *b, double *x)
{
    double A[3][4];
    for (int i = 0; i < k; i++) {
        for (int j = 0; j < k; j++)
            A[i][j] = G[i][j];
        A[i][k] = b[i];
    }
    for (int c = 0; c < k; c++) {
        int piv = c;
        for (int r = c + 1; r < k; r++)
            if (fabs(A[r][c]) > fabs(A[piv][c]))
                piv = r;
        if (!(fabs(A[piv][c]) > 1e-300))
            return -1;
        for (int j = 0; j <= k; j++) {
            double t = A[c][j];
            A[c][j] = A[piv][j];
            A[piv][j] = t;
        }
        for (int r = c + 1; r < k; r++) {
            double f = A[r][c] / A[c][c];
            for (int j = c; j <= k; j++)
                A[r][j] -= f * A[c][j];
        }
    }
    for (int r = k - 1; r >= 0; r--) {
        double s = A[r][k];
        for (int j = r + 1; j < k; j++)
            s -= A[r][j] * x[j];
        x[r] = s / A[r][r];
    }
    return 0;
}

/* min x'Gx - 2 x'b over x >= 0 (k <= 3 columns): every subset of columns
 * solved, the best feasible one kept (x = 0 at worst). */
static void small_nnls(int k, const double G[3][3], const double *b, double *x)
{
    double best = 0.0;
    memset(x, 0, sizeof(double) * (size_t)k);
    for (int mask = 1; mask < (1 << k); mask++) {
        int idx[3], m = 0, ok = 1;
        double Gs[3][3], bs[3], xs[3], full[3] = {0, 0, 0}, obj = 0.0;
        for (int j = 0; j < k; j++)
            if (mask & (1 << j))
                idx[m++] = j;
        for (int a = 0; a < m; a++) {
            bs[a] = b[idx[a]];
            for (int c = 0; c < m; c++)
                Gs[a][c] = G[idx[a]][idx[c]];
        }
        if (small_solve(m, (const double(*)[3])Gs, bs, xs))
            continue;
        for (int a = 0; a < m; a++) {
            if (!(xs[a] >= 0.0))
                ok = 0;
            full[idx[a]] = xs[a];
        }
        if (!ok)
            continue;
        for (int a = 0; a < k; a++) {
            obj -= 2.0 * full[a] * b[a];
            for (int c = 0; c < k; c++)
                obj += full[a] * G[a][c] * full[c];
        }
        if (obj < best) {
            best = obj;
            memcpy(x, full, sizeof(double) * (size_t)k);
        }
    }
}

/* A start: the roughnesses given in p (lobe l at 3 + 5 l), kd and ks from
 * the linear solve (see the protocol above), every value moved inside its
 * bounds by 1e-4 of its range so that the sigmoid can leave it. */
static void linear_start(const lm_ctx *cx, double *p)
{
    const pbr_spec *sp = cx->sp;
    const pbr_geom *g = &cx->s->g;
    int L = sp->nlobes, k = 1 + L;
    double G[3][3][3] = {{{0}}}, b[3][3] = {{0}};

    for (int l = 0; l < L; l++) {
        int o = 3 + 5 * l;
        if (sp->fresnel == PBR_DIELECTRIC) {
            p[o + 1] = p[o + 2] = p[o + 3] = 1.0;
            p[o + 4] = 1.5;
        } else {
            p[o + 1] = 1.0;
            p[o + 2] = p[o + 3] = p[o + 4] = 0.5;
        }
    }
    for (int i = 0; i < g->n; i++) {
        /* each channel's columns: the diffuse term and each lobe alone, the
         * channel's weights of the sample's lights applied */
        double col[3][3] = {{0}};
        int t0 = g->off ? g->off[i] : i, t1 = g->off ? g->off[i + 1] : i + 1;
        for (int t = t0; t < t1; t++) {
            double v[3];
            v[0] = g->ci[t] / M_PI;
            for (int l = 0; l < L; l++) {
                /* lobe l alone: its value in channel 0 with the others off */
                pbr_spec one = {1, sp->fresnel};
                double q[8] = {0, 0, 0}, m[3];
                memcpy(q + 3, p + 3 + 5 * l, 5 * sizeof(double));
                pbr_eval(&one, q, g->ci[t], g->co[t], g->ch[t], g->cd[t], m, NULL);
                v[1 + l] = m[0];
            }
            for (int c = 0; c < 3; c++) {
                double w = g->off ? g->w[3 * (size_t)t + c] : 1.0;
                for (int a = 0; a < k; a++)
                    col[c][a] += w * v[a];
            }
        }
        for (int c = 0; c < 3; c++)
            for (int a = 0; a < k; a++) {
                b[c][a] += col[c][a] * cx->s->y[3 * (size_t)i + c];
                for (int e = 0; e < k; e++)
                    G[c][a][e] += col[c][a] * col[c][e];
            }
    }
    {
        double x[3][3], mx[PBR_MAX_LOBES] = {0};
        for (int c = 0; c < 3; c++) {
            small_nnls(k, (const double(*)[3])G[c], b[c], x[c]);
            p[c] = x[c][0];
            for (int l = 0; l < L; l++) {
                if (sp->fresnel == PBR_DIELECTRIC)
                    p[3 + 5 * l + 1 + c] = x[c][1 + l];
                mx[l] = fmax(mx[l], x[c][1 + l]);
            }
        }
        for (int l = 0; l < L; l++)
            if (sp->fresnel == PBR_CONDUCTOR) {
                /* per-channel scales s_c at F0 0.5: ks the largest, F0_c from the ratio */
                p[3 + 5 * l + 1] = mx[l];
                for (int c = 0; c < 3; c++)
                    p[3 + 5 * l + 2 + c] = mx[l] > 0.0 ? 0.5 * x[c][1 + l] / mx[l] : 0.5;
            }
    }
    for (int j = 0; j < cx->np; j++) {
        double m = 1e-4 * (cx->hi[j] - cx->lo[j]);
        p[j] = fmin(fmax(p[j], cx->lo[j] + m), cx->hi[j] - m);
    }
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

/* The k-th smallest of a[0..n-1] (0-based; a reordered): what a sort
 * would put at a[k], found by quickselect with a three-way partition
 * (equal values, as a black or flat painting gives, in one pass) about the
 * median of three; after 2 log2(n) + 8 rounds it sorts what is left
 * instead, so no input makes it quadratic.  O(n) on average: a sort of
 * the 98,434 samples of 12 views at 128 x 128 took 4 ms a subset. */
static float select_kth(float *a, int n, int k)
{
    int lo = 0, hi = n - 1, rounds = 8;
    for (int m = n; m > 1; m >>= 1)
        rounds += 2;
    while (hi > lo) {
        float x = a[lo], y = a[lo + (hi - lo) / 2], z = a[hi], piv;
        int lt = lo, gt = hi, i = lo;
        if (--rounds < 0) {
            qsort(a + lo, (size_t)(hi - lo + 1), sizeof *a, cmp_float);
            return a[k];
        }
        piv = x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
        while (i <= gt) { /* a[lo..lt-1] < piv, a[lt..i-1] == piv, a[gt+1..hi] > piv */
            float v = a[i];
            if (v < piv) {
                a[i++] = a[lt];
                a[lt++] = v;
            } else if (v > piv) {
                a[i] = a[gt];
                a[gt--] = v;
            } else {
                i++;
            }
        }
        if (k < lt)
            hi = lt - 1;
        else if (k > gt)
            lo = gt + 1;
        else
            return piv;
    }
    return a[k];
}

/* Which m samples the subset takes: the brightest m/8 and an even stride
 * over the others (OUT: take[n], 1 where taken; returns how many). */
static int subset_pick(const pbr_set *all, int m, float *lum, unsigned char *take)
{
    int n = all->g.n, nb = m / 8, k = 0, rest, step;
    float thr;
    for (int i = 0; i < n; i++)
        lum[i] = all->y[3 * (size_t)i] + all->y[3 * (size_t)i + 1] + all->y[3 * (size_t)i + 2];
    thr = select_kth(lum, n, n - 1 - nb);
    for (int i = 0; i < n && k < nb; i++) {
        float v = all->y[3 * (size_t)i] + all->y[3 * (size_t)i + 1] + all->y[3 * (size_t)i + 2];
        if (v > thr) {
            take[i] = 1;
            k++;
        }
    }
    rest = n - k;
    step = rest / (m - k) > 1 ? rest / (m - k) : 1;
    for (int i = 0, j = 0; i < n && k < m; i++)
        if (!take[i] && j++ % step == 0) {
            take[i] = 1;
            k++;
        }
    return k;
}

int pbr_geom_pick(const pbr_geom *g, const float *y, const unsigned char *take, pbr_geom *out,
                  float **yout)
{
    int n = g->n, k = 0;
    long nt = 0;
    float *yo = NULL, *w = NULL;
    double *d = NULL;
    int *off = NULL;
    for (int i = 0; i < n; i++)
        if (take[i]) {
            k++;
            nt += g->off ? g->off[i + 1] - g->off[i] : 1;
        }
    d = malloc(4 * sizeof(double) * (size_t)(nt ? nt : 1));
    yo = malloc(3 * sizeof(float) * (size_t)(k ? k : 1));
    if (!d || !yo)
        goto oom;
    if (g->off && (!(off = malloc(sizeof(int) * ((size_t)k + 1))) ||
                   !(w = malloc(3 * sizeof(float) * (size_t)(nt ? nt : 1)))))
        goto oom;
    memset(out, 0, sizeof *out);
    out->n = k;
    out->ci = d;
    out->co = d + nt;
    out->ch = d + 2 * (size_t)nt;
    out->cd = d + 3 * (size_t)nt;
    out->off = off;
    out->w = w;
    if (off)
        off[0] = 0;
    for (int i = 0, j = 0, t = 0; i < n; i++)
        if (take[i]) {
            int t0 = g->off ? g->off[i] : i, t1 = g->off ? g->off[i + 1] : i + 1;
            for (int s = t0; s < t1; s++, t++) {
                out->ci[t] = g->ci[s];
                out->co[t] = g->co[s];
                out->ch[t] = g->ch[s];
                out->cd[t] = g->cd[s];
                if (w)
                    memcpy(w + 3 * (size_t)t, g->w + 3 * (size_t)s, 3 * sizeof *w);
            }
            for (int c = 0; c < 3; c++)
                yo[3 * (size_t)j + c] = y[3 * (size_t)i + c];
            j++;
            if (off)
                off[j] = t;
        }
    *yout = yo;
    return 0;
oom:
    free(d);
    free(yo);
    free(off);
    free(w);
    return GLINT_ENOMEM;
}

void pbr_geom_free(pbr_geom *g)
{
    free(g->ci); /* co, ch and cd share its block */
    free(g->off);
    free(g->w);
    memset(g, 0, sizeof *g);
}

/* The subset of the starts (subset_pick), copied with its terms (OUT: sub,
 * released by set_free). */
static int subset_make(const pbr_set *all, int m, pbr_set *sub)
{
    int n = all->g.n, rc;
    float *lum = malloc(sizeof(float) * (size_t)n), *y = NULL;
    unsigned char *take = calloc((size_t)n, 1);
    if (!lum || !take) {
        free(lum);
        free(take);
        return GLINT_ENOMEM;
    }
    subset_pick(all, m, lum, take);
    memset(sub, 0, sizeof *sub);
    rc = pbr_geom_pick(&all->g, all->y, take, &sub->g, &y);
    if (!rc) {
        sub->y = sub->own_y = y;
        sub->own_d = sub->g.ci;
    }
    free(lum);
    free(take);
    return rc;
}

static gsl_multilarge_nlinear_workspace *lm_alloc(int n, int np)
{
    gsl_multilarge_nlinear_parameters fp = gsl_multilarge_nlinear_default_parameters();
    fp.trs = gsl_multilarge_nlinear_trs_lm;
    fp.solver = gsl_multilarge_nlinear_solver_cholesky;
    fp.scale = gsl_multilarge_nlinear_scale_more;
    return gsl_multilarge_nlinear_alloc(gsl_multilarge_nlinear_trust, &fp, 3 * (size_t)n,
                                      (size_t)np);
}

/* Step 3's pass over every sample in PBR_BLOCKS blocks, each with its own
 * sums (the squared residuals, D J'J D's upper triangle, by view). */
typedef struct det_pass {
    const lm_ctx *cx;
    const double *p, *D;
    double ss[PBR_BLOCKS];
    double A[PBR_BLOCKS][PBR_MAXP * PBR_MAXP];
    double vse[PBR_BLOCKS][PBR_MAX_VIEWS];
    long vn[PBR_BLOCKS][PBR_MAX_VIEWS];
} det_pass;

static void det_block(void *ctx, int b)
{
    det_pass *dp = ctx;
    const lm_ctx *cx = dp->cx;
    const pbr_geom *g = &cx->s->g;
    const double *D = dp->D;
    double *A = dp->A[b], ss = 0.0;
    int np = cx->np, i0, i1;
    memset(dp->A[b], 0, sizeof dp->A[b]);
    if (cx->view) {
        memset(dp->vse[b], 0, sizeof dp->vse[b]);
        memset(dp->vn[b], 0, sizeof dp->vn[b]);
    }
    block_range(g->n, b, &i0, &i1);
    for (int i = i0; i < i1; i++) {
        double m[3], J[3][PBR_MAXP];
        pbr_sample_eval(cx->sp, dp->p, g, i, m, J);
        for (int c = 0; c < 3; c++) {
            double d = m[c] - cx->s->y[3 * (size_t)i + c];
            ss += d * d;
            if (cx->view)
                dp->vse[b][cx->view[i]] += d * d;
            for (int a = 0; a < np; a++)
                if (J[c][a] != 0.0)
                    for (int q = a; q < np; q++)
                        A[a * np + q] += J[c][a] * J[c][q] * D[a] * D[q];
        }
        if (cx->view)
            dp->vn[b][cx->view[i]]++;
    }
    dp->ss[b] = ss;
}

/* Steps 3 and 4 of the protocol on every sample (r->p set, bounds snapped). */
static int determine(const lm_ctx *cx, pbr_fit_result *r)
{
    const pbr_geom *g = &cx->s->g;
    int np = cx->np, nfree = 0, status;
    double A[PBR_MAXP * PBR_MAXP] = {0}, A0[PBR_MAXP * PBR_MAXP], D[PBR_MAXP], ss = 0.0, lmax = 0.0;
    det_pass *dp;
    gsl_matrix_view Av = gsl_matrix_view_array(A, (size_t)np, (size_t)np);
    gsl_vector *eval = gsl_vector_alloc((size_t)np);
    gsl_matrix *evec = gsl_matrix_alloc((size_t)np, (size_t)np);
    gsl_eigen_symmv_workspace *ew = gsl_eigen_symmv_alloc((size_t)np);

    if (!eval || !evec || !ew) {
        gsl_vector_free(eval);
        gsl_matrix_free(evec);
        gsl_eigen_symmv_free(ew);
        return GLINT_ENOMEM;
    }
    for (int k = 0; k < np; k++)
        D[k] = cx->hi[k] - cx->lo[k];
    if (!(dp = malloc(sizeof *dp))) {
        gsl_vector_free(eval);
        gsl_matrix_free(evec);
        gsl_eigen_symmv_free(ew);
        return GLINT_ENOMEM;
    }
    dp->cx = cx;
    dp->p = r->p;
    dp->D = D;
    if (par_worth((size_t)pbr_geom_terms(g) * 8))
        par_run(PBR_BLOCKS, det_block, dp);
    else
        for (int b = 0; b < PBR_BLOCKS; b++)
            det_block(dp, b);
    for (int b = 0; b < PBR_BLOCKS; b++) { /* in block order: the same on any thread count */
        ss += dp->ss[b];
        for (int k = 0; k < np * np; k++)
            A[k] += dp->A[b][k];
        if (cx->view)
            for (int v = 0; v < PBR_MAX_VIEWS; v++) {
                r->view_se[v] += dp->vse[b][v];
                r->view_n[v] += dp->vn[b][v];
            }
    }
    free(dp);
    for (int a = 0; a < np; a++)
        for (int b = 0; b < a; b++)
            A[a * np + b] = A[b * np + a];
    memcpy(A0, A, sizeof A0); /* gsl_eigen_symmv overwrites A */
    r->cost = 0.5 * ss;
    r->rms = g->n ? sqrt(ss / (3.0 * g->n)) : 0.0;
    status = gsl_eigen_symmv(&Av.matrix, eval, evec, ew);
    for (int k = 0; k < np; k++)
        lmax = fmax(lmax, gsl_vector_get(eval, (size_t)k));
    for (int k = 0; k < np; k++) {
        double null_w = 0.0;
        for (int e = 0; e < np; e++)
            if (!(gsl_vector_get(eval, (size_t)e) > PBR_NULL_REL * lmax)) {
                double v = gsl_matrix_get(evec, (size_t)k, (size_t)e);
                null_w += v * v;
            }
        r->undetermined[k] = status != GSL_SUCCESS || !(lmax > 0.0) || null_w > 0.5;
        nfree += !r->at_bound[k];
    }
    r->resid_var = 3 * g->n > nfree ? ss / (3.0 * g->n - nfree) : 0.0;
    /* sigma over the parameters inside their bounds: the pseudo-inverse of
     * their block of D J'J D (the same eigen-analysis on that block; eval
     * and evec reused as its workspace) */
    {
        int idx[PBR_MAXP], m = 0;
        double B[PBR_MAXP * PBR_MAXP];
        for (int k = 0; k < np; k++) {
            r->sigma[k] = NAN;
            if (!r->at_bound[k])
                idx[m++] = k;
        }
        if (m > 0 && status == GSL_SUCCESS) {
            gsl_matrix_view Bv = gsl_matrix_view_array(B, (size_t)m, (size_t)m);
            gsl_vector_view ev = gsl_vector_subvector(eval, 0, (size_t)m);
            gsl_matrix_view vv = gsl_matrix_submatrix(evec, 0, 0, (size_t)m, (size_t)m);
            gsl_eigen_symmv_workspace *bw = gsl_eigen_symmv_alloc((size_t)m);
            double bmax = 0.0;
            for (int a = 0; a < m; a++)
                for (int b = 0; b < m; b++)
                    B[a * m + b] = A0[idx[a] * np + idx[b]];
            if (bw && gsl_eigen_symmv(&Bv.matrix, &ev.vector, &vv.matrix, bw) == GSL_SUCCESS) {
                for (int e = 0; e < m; e++)
                    bmax = fmax(bmax, gsl_vector_get(&ev.vector, (size_t)e));
                for (int a = 0; a < m; a++) {
                    double v = 0.0;
                    for (int e = 0; e < m; e++) {
                        double le = gsl_vector_get(&ev.vector, (size_t)e);
                        double x = gsl_matrix_get(&vv.matrix, (size_t)a, (size_t)e);
                        if (le > PBR_NULL_REL * bmax)
                            v += x * x / le;
                    }
                    r->sigma[idx[a]] = D[idx[a]] * sqrt(r->resid_var * v);
                }
            }
            gsl_eigen_symmv_free(bw);
        }
    }
    for (int k = 0; k < np; k++)
        if (isfinite(r->sigma[k]) && r->sigma[k] > 0.5 * D[k])
            r->undetermined[k] = 1;
    /* a lobe without weight says nothing of its shape */
    for (int l = 0; l < cx->sp->nlobes; l++) {
        int o = 3 + 5 * l, nks = cx->sp->fresnel == PBR_DIELECTRIC ? 3 : 1;
        double ks = 0.0;
        for (int c = 0; c < nks; c++)
            ks = fmax(ks, r->p[o + 1 + c]);
        if (!(ks > 0.0)) {
            r->undetermined[o] = 1;
            if (cx->sp->fresnel == PBR_DIELECTRIC)
                r->undetermined[o + 4] = 1;
            else
                for (int c = 0; c < 3; c++)
                    r->undetermined[o + 2 + c] = 1;
        }
    }
    for (int k = 0; k < np; k++)
        if (r->undetermined[k])
            r->sigma[k] = NAN;
    gsl_vector_free(eval);
    gsl_matrix_free(evec);
    gsl_eigen_symmv_free(ew);
    return 0;
}

/* 1 when parameter k is a weight (kd or ks), which a black painting sets to 0. */
static int is_weight(const pbr_spec *sp, int k)
{
    int j = (k - 3) % 5;
    if (k < 3)
        return 1;
    return sp->fresnel == PBR_CONDUCTOR ? j == 1 : j >= 1 && j <= 3;
}

/* 0.5 sum of squared residuals at p on cx's samples (r: 3 n, scratch). */
static double set_cost(const lm_ctx *cx, const double *p, gsl_vector *r)
{
    pass *ps = malloc(sizeof *ps);
    double ss = 0.0;
    if (!ps)
        return NAN;
    ps->cx = cx;
    ps->p = p;
    ps->v = r;
    pass_run(ps, f_block);
    for (int b = 0; b < PBR_BLOCKS; b++)
        ss += ps->ss[b];
    free(ps);
    return 0.5 * ss;
}

/* 1 for a parameter the model is nonlinear in: a lobe's roughness, a
 * dielectric's ior (the others are lin_project's). */
static int is_shape(const pbr_spec *sp, int k)
{
    int j = (k - 3) % 5;
    return k >= 3 && (j == 0 || (sp->fresnel == PBR_DIELECTRIC && j == 4));
}

/* Pin the weights of p within PBR_PIN_WEIGHT of a bound at it (cx->pin,
 * p; those pinned already stay); returns how many. */
static int pins_set(lm_ctx *cx, double *p)
{
    int n = 0;
    for (int k = 0; k < cx->np; k++) {
        double t = (p[k] - cx->lo[k]) / (cx->hi[k] - cx->lo[k]);
        if (cx->pin[k] || is_shape(cx->sp, k))
            continue; /* lin_project's, pins_probe's */
        cx->pin[k] = t <= PBR_PIN_WEIGHT ? -1 : t >= 1.0 - PBR_PIN_WEIGHT ? 1 : 0;
        if (cx->pin[k]) {
            p[k] = cx->pin[k] < 0 ? cx->lo[k] : cx->hi[k];
            n++;
        }
    }
    return n;
}

/* Release the pins the cost does not hold at their bounds: where a step of
 * a millionth of the range inward lowers it (the gradient points in).
 * Returns how many were released, -1 when out of memory. */
static int pins_check(lm_ctx *cx, const double *p)
{
    gsl_vector *r = gsl_vector_alloc(3 * (size_t)cx->s->g.n);
    double q[PBR_MAXP], c0;
    int pins[PBR_MAXP], rel = 0;
    if (!r)
        return -1;
    memcpy(pins, cx->pin, sizeof pins);
    memset(cx->pin, 0, sizeof cx->pin); /* p itself holds the bounds */
    c0 = set_cost(cx, p, r);
    for (int k = 0; k < cx->np; k++) {
        if (!pins[k])
            continue;
        memcpy(q, p, sizeof q);
        q[k] -= pins[k] * 1e-6 * (cx->hi[k] - cx->lo[k]);
        if (!(set_cost(cx, q, r) >= c0)) {
            pins[k] = 0;
            rel++;
        }
    }
    memcpy(cx->pin, pins, sizeof pins);
    gsl_vector_free(r);
    return rel;
}

/* ---- the linear parameters at a given shape (refine_pinned) ---------------------------- */

/* At a given roughness (and ior) the model is linear in its weights.  Per
 * sample and channel the columns are the diffuse term ci / pi and per lobe
 *   dielectric: g = D V F(ior) ci                  (weight ks_c)
 *   conductor:  a = D V (1 - w5) ci, b = D V w5 ci (weights s_c = ks F0_c
 *               and e = ks: ks F = s_c (1 - w5) + e w5)
 * summed over the sample's terms with their weights.  The conductor's
 * s_c <= e is F0 <= 1, so its ks and F0 trade along no valley here. */
#define LIN_MAXC (1 + 2 * PBR_MAX_LOBES)      /* columns a channel */
#define LIN_MAXU (3 + 4 * PBR_MAX_LOBES)      /* unknowns, all channels */

static int lin_ncols(const pbr_spec *sp)
{
    return 1 + (sp->fresnel == PBR_CONDUCTOR ? 2 : 1) * sp->nlobes;
}

/* Sample i's columns per channel at p's shape (OUT X[c][a]). */
static void lin_sample(const lm_ctx *cx, const double *p, int i, double X[3][LIN_MAXC])
{
    const pbr_spec *sp = cx->sp;
    double d[3], A[PBR_MAX_LOBES][3], B[PBR_MAX_LOBES][3];
    pbr_sample_sums(sp, p, &cx->s->g, i, d, A, B);
    for (int c = 0; c < 3; c++) {
        X[c][0] = d[c] / M_PI;
        for (int l = 0; l < sp->nlobes; l++) {
            if (sp->fresnel == PBR_CONDUCTOR) {
                X[c][1 + 2 * l] = A[l][c];
                X[c][2 + 2 * l] = B[l][c];
            } else {
                X[c][1 + l] = pbr_f0_of_ior(p[3 + 5 * l + 4]) * A[l][c] + B[l][c];
            }
        }
    }
}

/* Where column a of channel c goes among the unknowns: kd_c, then per lobe
 * (dielectric) ks_lc, or (conductor) s_lc and e_l. */
static int lin_unknown(const pbr_spec *sp, int c, int a)
{
    if (a == 0)
        return c;
    if (sp->fresnel == PBR_DIELECTRIC)
        return 3 + 3 * (a - 1) + c;
    return 3 + 4 * ((a - 1) / 2) + ((a - 1) % 2 ? 3 : c);
}

/* The unknowns' bounds as rows G z <= u (lsq.h; z >= 0 is its own):
 * kd_c <= 1, ks <= PBR_KS_MAX, and a conductor's s_lc - e_l <= 0.
 * Returns the number of rows. */
static int lin_rows(const pbr_spec *sp, int nu, double *G, double *u)
{
    int m = 0;
    memset(G, 0, sizeof(double) * (size_t)nu * (3 + 4 * PBR_MAX_LOBES));
    for (int c = 0; c < 3; c++, m++) {
        G[(size_t)m * nu + c] = 1.0;
        u[m] = 1.0;
    }
    for (int l = 0; l < sp->nlobes; l++) {
        if (sp->fresnel == PBR_DIELECTRIC) {
            for (int c = 0; c < 3; c++, m++) {
                G[(size_t)m * nu + 3 + 3 * l + c] = 1.0;
                u[m] = PBR_KS_MAX;
            }
        } else {
            int e = 3 + 4 * l + 3;
            for (int c = 0; c < 3; c++, m++) {
                G[(size_t)m * nu + 3 + 4 * l + c] = 1.0;
                G[(size_t)m * nu + e] = -1.0;
                u[m] = 0.0;
            }
            G[(size_t)m * nu + e] = 1.0;
            u[m++] = PBR_KS_MAX;
        }
    }
    return m;
}

/* The weights' normal equations at p's shape on cx's samples: OUT H (nu x
 * nu), q (nu) and *yy, the painting's sum of squares. */
static void lin_normal(const lm_ctx *cx, const double *p, int nu, double *H, double *q,
                       double *yy)
{
    const pbr_spec *sp = cx->sp;
    const pbr_geom *g = &cx->s->g;
    int nc = lin_ncols(sp);
    double Gc[3][LIN_MAXC][LIN_MAXC] = {{{0}}}, qc[3][LIN_MAXC] = {{0}};
    *yy = 0.0;
    for (int i = 0; i < g->n; i++) {
        double X[3][LIN_MAXC];
        lin_sample(cx, p, i, X);
        for (int c = 0; c < 3; c++) {
            double y = cx->s->y[3 * (size_t)i + c];
            *yy += y * y;
            for (int a = 0; a < nc; a++) {
                qc[c][a] += X[c][a] * y;
                for (int b = 0; b < nc; b++)
                    Gc[c][a][b] += X[c][a] * X[c][b];
            }
        }
    }
    memset(H, 0, sizeof(double) * (size_t)nu * nu);
    memset(q, 0, sizeof(double) * (size_t)nu);
    for (int c = 0; c < 3; c++)
        for (int a = 0; a < nc; a++) {
            int ia = lin_unknown(sp, c, a);
            q[ia] += qc[c][a];
            for (int b = 0; b < nc; b++)
                H[ia * nu + lin_unknown(sp, c, b)] += Gc[c][a][b];
        }
}

/* The weights z (lin_unknown's order) as parameters: p with its kd, ks and
 * F0 from z, within their bounds (OUT: out). */
static void lin_to_params(const pbr_spec *sp, const double *z, const double *p, double *out)
{
    memcpy(out, p, sizeof(double) * PBR_MAXP);
    for (int c = 0; c < 3; c++)
        out[c] = fmin(z[c], 1.0);
    for (int l = 0; l < sp->nlobes; l++) {
        int o = 3 + 5 * l;
        if (sp->fresnel == PBR_DIELECTRIC) {
            for (int c = 0; c < 3; c++)
                out[o + 1 + c] = fmin(z[3 + 3 * l + c], PBR_KS_MAX);
        } else {
            double e = fmin(z[3 + 4 * l + 3], PBR_KS_MAX);
            out[o + 1] = e;
            for (int c = 0; c < 3 && e > 0.0; c++)
                out[o + 2 + c] = fmin(1.0, z[3 + 4 * l + c] / e);
        }
    }
}

/* The weights of p's shape solved exactly on cx's samples (lsq.h's
 * active set: the bounds are met, not approached as the sigmoid does),
 * written into p; those the solve puts on a bound are pinned there
 * (cx->pin).  Kept only when the cost does not rise above c0, the cost at
 * p (the search's own; infinite for a trial, which is kept whatever it
 * costs); OUT: *cost, the cost at the p returned (c0 when not kept).
 * Returns 1 when kept, 0 when not, -1 when out of memory. */
static int lin_project(lm_ctx *cx, double *p, double c0, double *cost)
{
    const pbr_spec *sp = cx->sp;
    int nu = 3 + (sp->fresnel == PBR_CONDUCTOR ? 4 : 3) * sp->nlobes, keep = 0, pin0[PBR_MAXP];
    double H[LIN_MAXU * LIN_MAXU], q[LIN_MAXU], z[LIN_MAXU], yy;
    double G[(3 + 4 * PBR_MAX_LOBES) * LIN_MAXU], u[3 + 4 * PBR_MAX_LOBES];
    double pn[PBR_MAXP], c1;
    lsq_problem pr;
    lsq_result res;
    gsl_vector *r = gsl_vector_alloc(3 * (size_t)cx->s->g.n);

    if (!r)
        return -1;
    lin_normal(cx, p, nu, H, q, &yy);
    pr = (lsq_problem){.n = nu, .H = H, .q = q, .ff = yy, .G = G, .u = u};
    pr.m = lin_rows(sp, nu, G, u);
    memcpy(pin0, cx->pin, sizeof pin0);
    memset(cx->pin, 0, sizeof cx->pin); /* the cost at pn as it stands */
    if (lsq_solve(&pr, LSQ_ENERGY, 0.0, NULL, z, &res, NULL) || res.status != LSQ_OK) {
        memcpy(cx->pin, pin0, sizeof pin0);
        gsl_vector_free(r);
        *cost = c0;
        return 0;
    }
    lin_to_params(sp, z, p, pn);
    c1 = set_cost(cx, pn, r);
    if (c1 <= c0) {
        memcpy(p, pn, sizeof pn);
        keep = 1;
    }
    gsl_vector_free(r);
    *cost = keep ? c1 : c0;
    /* the pins: the shape's as they were, the weights where the solve put a
     * bound (a conductor's F0 at 1: its s_c met e) */
    memcpy(cx->pin, pin0, sizeof pin0);
    for (int k = 0; k < cx->np && keep; k++) {
        double span = cx->hi[k] - cx->lo[k];
        if (is_shape(sp, k))
            continue;
        cx->pin[k] = p[k] <= cx->lo[k] + 1e-12 * span   ? -1
                     : p[k] >= cx->hi[k] - 1e-12 * span ? 1
                                                        : 0;
        if (cx->pin[k])
            p[k] = cx->pin[k] < 0 ? cx->lo[k] : cx->hi[k];
    }
    return keep;
}

/* Try each roughness and ior of p near a bound (PBR_PROBE_ALPHA,
 * PBR_PROBE_IOR of the range) on it, the weights solved anew there
 * (lin_project): where the cost (*cost, at p in and out) is no higher, p
 * moves there and the parameter is pinned.  The sigmoid approaches a bound
 * only in the limit: an ior at 2.9 took 76 iterations to reach 3.  Returns
 * how many were pinned, -1 when out of memory. */
static int pins_probe(lm_ctx *cx, double *p, double *cost)
{
    int n = 0;
    for (int k = 0; k < cx->np; k++) {
        double t = (p[k] - cx->lo[k]) / (cx->hi[k] - cx->lo[k]), q[PBR_MAXP], cq;
        double near = (k - 3) % 5 ? PBR_PROBE_IOR : PBR_PROBE_ALPHA;
        int pin0[PBR_MAXP], side = t <= near ? -1 : t >= 1.0 - near ? 1 : 0;
        if (!is_shape(cx->sp, k) || !side || cx->pin[k])
            continue;
        memcpy(q, p, sizeof q);
        memcpy(pin0, cx->pin, sizeof pin0);
        q[k] = side < 0 ? cx->lo[k] : cx->hi[k];
        cx->pin[k] = side;
        if (lin_project(cx, q, INFINITY, &cq) < 0)
            return -1;
        if (cq <= *cost) {
            memcpy(p, q, sizeof q);
            *cost = cq;
            n++;
        } else {
            memcpy(cx->pin, pin0, sizeof pin0);
        }
    }
    return n;
}

/* The refinement's Levenberg-Marquardt with the bounds as an active set.
 * After PBR_PIN_AFTER iterations without convergence: the weights solved
 * exactly at the shape reached (lin_project: a conductor's ks and F0 then
 * sit where a search would crawl along their valley), the roughnesses and
 * iors near a bound tried on it (pins_probe), the parameters on a bound or
 * near one held there (pins_set), the others searched on (the sigmoid
 * reaches a bound only in the limit: a metal's kd crawled to 3e-13 in 100
 * iterations); a pin the cost does not hold there is released (pins_check)
 * and the search resumed.  The iterations add up to max_iter at most.
 * One lobe only: with two, the pins led 4 of 28 environment-lit fits of
 * measured materials (bench_env_measured, pbr_tab_env) to other minima,
 * three with a painted error 1-6% higher (the one-view median on new views
 * 15.8% against 15.2%), one 22% lower, so two lobes keep the plain search.  p in and out;
 * cx->pin cleared on return; -1 when out of memory. */
static int refine_pinned(lm_ctx *cx, gsl_multilarge_nlinear_workspace *w, int max_iter,
                         double *p, pbr_start_report *rep)
{
    int used, rel;
    double cost;
    pbr_start_report more;
    memset(cx->pin, 0, sizeof cx->pin);
    if (cx->sp->nlobes > 1) { /* the plain search (see above) */
        lm_run(cx, w, max_iter, p, rep);
        return 0;
    }
    lm_run(cx, w, max_iter < PBR_PIN_AFTER ? max_iter : PBR_PIN_AFTER, p, rep);
    used = rep->iters;
    if (rep->converged || used >= max_iter)
        return 0;
    if (lin_project(cx, p, rep->cost, &cost) < 0 || pins_probe(cx, p, &cost) < 0) {
        memset(cx->pin, 0, sizeof cx->pin);
        return -1;
    }
    pins_set(cx, p);
    lm_run(cx, w, max_iter - used, p, &more);
    used += more.iters;
    if ((rel = pins_check(cx, p)) < 0) {
        memset(cx->pin, 0, sizeof cx->pin);
        return -1;
    }
    if (rel > 0 && used < max_iter) {
        pbr_start_report last;
        lm_run(cx, w, max_iter - used, p, &last);
        used += last.iters;
        more = last;
    }
    memset(cx->pin, 0, sizeof cx->pin);
    *rep = more;
    rep->iters = used;
    return 0;
}

/* Step 2: the best start refined on o->refine samples (drawn as the
 * starts' subset is, more of them) or on every sample.  *w: the starts'
 * workspace, replaced. */
static int refine(lm_ctx *cx, const pbr_set *all, const pbr_fit_opts *o,
                  gsl_multilarge_nlinear_workspace **w, pbr_fit_result *out, glint_err *err)
{
    pbr_start_report fin;
    pbr_set ref;
    int use = o->refine > 0 && all->g.n > o->refine && o->refine > o->subset;
    gsl_multilarge_nlinear_free(*w);
    *w = NULL;
    memset(&ref, 0, sizeof ref);
    if (use && subset_make(all, o->refine, &ref))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    cx->s = use ? &ref : all;
    if (!(*w = lm_alloc(cx->s->g.n, cx->np))) {
        set_free(&ref);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (GSL workspace)");
    }
    if (refine_pinned(cx, *w, o->max_iter, out->p, &fin)) {
        set_free(&ref);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    out->iters = fin.iters;
    out->converged = fin.converged;
    out->refine_samples = cx->s->g.n;
    cx->s = all;
    set_free(&ref);
    return 0;
}

/* Step 1's starts, one task each (par_run): start s from the roughness
 * PBR_START_ALPHA[k] and the linear fit of the weights, or from o->p0. */
typedef struct start_job {
    const lm_ctx *cx;
    const pbr_fit_opts *o;
    pbr_fit_result *out;
    int lit, max_iter;
    double p[PBR_MAX_STARTS][PBR_MAXP];
    int nomem[PBR_MAX_STARTS]; /* each start's own: tasks write only theirs */
} start_job;

static void start_task(void *ctx, int s)
{
    start_job *job = ctx;
    const lm_ctx *cx = job->cx;
    const pbr_fit_opts *o = job->o;
    const pbr_spec *sp = cx->sp;
    double *p = job->p[s];
    pbr_start_report *sr = &job->out->start[s];
    int np = cx->np, k = s - (o->p0 != NULL); /* the roughness start; -1: p0 */
    gsl_multilarge_nlinear_workspace *w;

    if (k < 0) {
        for (int j = 0; j < np; j++) { /* a thousandth of the range inside the bounds:
                                          at a bound the sigmoid's slope is 0 */
            double t = (o->p0[j] - cx->lo[j]) / (cx->hi[j] - cx->lo[j]);
            t = isfinite(t) ? fmin(fmax(t, 1e-3), 1.0 - 1e-3) : 0.5;
            p[j] = cx->lo[j] + t * (cx->hi[j] - cx->lo[j]);
        }
        sr->alpha0 = p[3];
    } else {
        for (int l = 0; l < sp->nlobes; l++)
            p[3 + 5 * l] = l ? fmin(0.9, 5.0 * PBR_START_ALPHA[k]) : PBR_START_ALPHA[k];
        linear_start(cx, p);
        sr->alpha0 = PBR_START_ALPHA[k];
    }
    if (!job->lit) { /* a black painting: the start (kd = ks = 0 within 1e-4) is the answer */
        sr->cost = 0.0;
        sr->converged = 1;
        return;
    }
    if (!(w = lm_alloc(cx->s->g.n, np))) {
        sr->cost = INFINITY;
        job->nomem[s] = 1;
        return;
    }
    lm_run(cx, w, job->max_iter, p, sr);
    gsl_multilarge_nlinear_free(w);
}

int pbr_fit(const pbr_spec *sp, const pbr_geom *g, const float *y, const pbr_fit_opts *o,
            pbr_fit_result *out, glint_err *err)
{
    pbr_set all = {*g, y, NULL, NULL}, sub;
    lm_ctx cx;
    double best = INFINITY;
    gsl_multilarge_nlinear_workspace *w = NULL;
    int np = pbr_np(sp), starts, lit = 0, rc = 0;
    int use_sub = o->subset > 0 && g->n > o->subset;
    int cap = o->start_iter > 0 ? o->start_iter : PBR_START_ITER;

    memset(out, 0, sizeof *out);
    memset(&sub, 0, sizeof sub);
    if (sp->nlobes < 1 || sp->nlobes > PBR_MAX_LOBES)
        return glint_err_set(err, GLINT_EINVAL, "pbr: %d lobes (1 or 2)", sp->nlobes);
    if (g->n < np)
        return glint_err_set(err, GLINT_EINVAL,
                             "pbr: %d lit sample%s, the model's %d parameters need at least %d",
                             g->n, g->n == 1 ? "" : "s", np, np);
    pthread_once(&gsl_handler_once, gsl_handler_off);
    starts = o->starts < (o->p0 ? 0 : 1) ? (o->p0 ? 0 : 1) : o->starts;
    starts = starts > PBR_MAX_STARTS - (o->p0 != NULL) ? PBR_MAX_STARTS - (o->p0 != NULL) : starts;
    starts += o->p0 != NULL;
    memset(&cx, 0, sizeof cx);
    cx.sp = sp;
    cx.np = np;
    pbr_bounds(sp, cx.lo, cx.hi);
    for (int i = 0; i < g->n; i++)
        lit += y[3 * (size_t)i] > 0.0f || y[3 * (size_t)i + 1] > 0.0f ||
               y[3 * (size_t)i + 2] > 0.0f;
    out->nsamples_lit = lit;

    if (use_sub && (rc = subset_make(&all, o->subset, &sub)))
        return glint_err_set(err, rc, "out of memory");
    cx.s = use_sub ? &sub : &all;
    out->nstarts = starts;
    {
        start_job job = {&cx, o, out, lit, use_sub && o->max_iter > cap ? cap : o->max_iter,
                         {{0}}, {0}};
        int nomem = 0;
        /* the starts are independent: run side by side on the pool (their
         * passes then serial), each in its own workspace; the best is taken
         * in start order, as one after another would */
        par_run(starts, start_task, &job);
        for (int s = 0; s < starts; s++)
            nomem |= job.nomem[s];
        if (nomem) {
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory (GSL workspace)");
            goto done;
        }
        for (int s = 0; s < starts; s++)
            if (out->start[s].cost < best) {
                best = out->start[s].cost;
                out->best_start = s;
                memcpy(out->p, job.p[s], sizeof job.p[s]);
            }
    }
    if (!isfinite(best)) {
        rc = glint_err_set(err, GLINT_ENUMERIC, "pbr: no start gave a finite cost");
        goto done;
    }
    out->iters = out->start[out->best_start].iters;
    out->converged = out->start[out->best_start].converged;
    if (use_sub && lit && (rc = refine(&cx, &all, o, &w, out, err)))
        goto done;
    cx.s = &all;
    cx.view = o->view; /* the errors by view, on every sample */
    for (int k = 0; k < np; k++) {
        double t = (out->p[k] - cx.lo[k]) / (cx.hi[k] - cx.lo[k]);
        out->at_bound[k] = t <= PBR_BOUND_TOL ? -1 : t >= 1.0 - PBR_BOUND_TOL ? 1 : 0;
        if (!lit && is_weight(sp, k))
            out->at_bound[k] = -1; /* kd and ks of a black painting: 0 */
        if (out->at_bound[k])
            out->p[k] = out->at_bound[k] < 0 ? cx.lo[k] : cx.hi[k];
    }
    if ((rc = determine(&cx, out)))
        rc = glint_err_set(err, rc, "out of memory");
done:
    gsl_multilarge_nlinear_free(w);
    set_free(&sub);
    return rc;
}
