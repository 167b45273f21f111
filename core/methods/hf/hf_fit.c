/* hf_fit.c: apply a precomputed operator to painted samples (the fast
 * factorization), keep the log-factors within range, invert the mapping,
 * evaluate factors. */
#include <cblas.h>
#include <float.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal/hf_int.h"
#include "vmath.h"

#define COS_FLOOR 1e-6

/* y = M t for 3 channels.  M is symmetric, so row k of M is column k: the
 * loop streams M once, row by row, and updates three accumulators per
 * element (an axpy per row and channel; vectorizes without reassociation). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
/* by feature: "arch=haswell" would pick the clone by CPU model, and AMD
 * processors with AVX2 never got it */
#define GLINT_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GLINT_CLONES
#endif

GLINT_CLONES static void apply_f64(const double *restrict M, int n, const double *restrict t,
                      double *restrict y)
{
    double *y0 = y, *y1 = y + n, *y2 = y + 2 * n;

    memset(y, 0, (size_t)3 * n * sizeof *y);
    for (int k = 0; k < n; k++) {
        const double *restrict row = M + (size_t)n * k;
        double a = t[3 * k], b = t[3 * k + 1], c = t[3 * k + 2];
        for (int i = 0; i < n; i++) {
            double m = row[i];
            y0[i] += m * a;
            y1[i] += m * b;
            y2[i] += m * c;
        }
    }
}

GLINT_CLONES static void apply_f32(const float *restrict M, int n, const double *restrict t,
                      float *restrict y)
{
    float *y0 = y, *y1 = y + n, *y2 = y + 2 * n;

    memset(y, 0, (size_t)3 * n * sizeof *y);
    for (int k = 0; k < n; k++) {
        const float *restrict row = M + (size_t)n * k;
        float a = (float)t[3 * k], b = (float)t[3 * k + 1], c = (float)t[3 * k + 2];
        for (int i = 0; i < n; i++) {
            float m = row[i];
            y0[i] += m * a;
            y1[i] += m * b;
            y2[i] += m * c;
        }
    }
}

void hf_factors_canonicalize(double *logf, int res)
{
    for (int c = 0; c < 3; c++) {
        double mean[3], all = 0.0;
        for (int j = 0; j < 3; j++) {
            double s = 0.0;
            for (int k = 0; k < res; k++)
                s += logf[(j * res + k) * 3 + c];
            mean[j] = s / res;
            all += mean[j];
        }
        all /= 3.0;
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < res; k++)
                logf[(j * res + k) * 3 + c] += all - mean[j];
    }
}

static double map_inverse(const hf_factors *fac, int c, double prod)
{
    return hf_map_inverse(&fac->map, fac->a_used[c], prod);
}

static double clamp_exp(double x)
{
    /* exp of a log-factor sum.  A fit's factors sum to at most
     * 3 HF_LOG_FACTOR_MAX; the bound only matters for factors read from
     * elsewhere (a material file). */
    if (x > 700.0)
        x = 700.0;
    return exp(x);
}

void hf_factors_eval_design(const hf_factors *fac, const hf_design *d, float *rgb)
{
    double *ly = malloc((size_t)3 * d->n * sizeof *ly);
    if (!ly) {
        memset(rgb, 0, (size_t)3 * d->n * sizeof *rgb);
        return;
    }
    hf_A_y(d, fac->logf, ly);
    for (size_t i = 0; i < (size_t)3 * d->n; i++)
        if (ly[i] > 700.0)
            ly[i] = 700.0;
    vmath_exp(ly, ly, (size_t)3 * d->n);
    for (int i = 0; i < d->n; i++) {
        double w = fac->model == HF_MODEL_BRDF ? d->cos_i[i] : 1.0;
        for (int c = 0; c < 3; c++)
            rgb[3 * i + c] = (float)(w * map_inverse(fac, c, ly[3 * i + c]));
    }
    free(ly);
}

void hf_factors_eval(const hf_factors *fac, const double n[3], const double wi[3],
                     const double wo[3], double rgb[3])
{
    double pi[3], ci, co, acc[3] = {0.0, 0.0, 0.0};
    int R = fac->res;

    ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    if (!(ci > 0.0) || !(co > 0.0)) {
        rgb[0] = rgb[1] = rgb[2] = 0.0;
        return;
    }
    hf_project(n, wi, wo, pi);
    for (int j = 0; j < 3; j++) {
        int k;
        double t;
        hf_hat(pi[j], R, &k, &t);
        for (int c = 0; c < 3; c++)
            acc[c] += (1.0 - t) * fac->logf[(j * R + k) * 3 + c] +
                      t * fac->logf[(j * R + k + 1) * 3 + c];
    }
    for (int c = 0; c < 3; c++) {
        double v = map_inverse(fac, c, clamp_exp(acc[c]));
        rgb[c] = fac->model == HF_MODEL_BRDF ? v * ci : v;
    }
}

static double log_abs_max(const double *logf, int len)
{
    double mx = 0.0;
    for (int k = 0; k < len; k++)
        if (fabs(logf[k]) > mx)
            mx = fabs(logf[k]);
    return mx;
}

/* Damping of hf.h (hf_fit): with M = Q diag(d) Q^T and z = Q^T y,
 * y(beta) = Q diag(1 / (1 + beta d)) z, beta = alpha^2.  Evaluates y(beta)
 * into y (3 channels, channel-minor) and returns its largest |entry|. */
typedef struct damp_ws {
    int n;
    const double *Q, *d, *z; /* n x n column-major, n, n x 3 */
    double *zs, *yb;         /* n x 3 each */
} damp_ws;

static double damp_eval(damp_ws *w, double beta, double *y)
{
    int n = w->n;
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < n; i++)
            w->zs[i + (size_t)n * c] =
                w->z[i + (size_t)n * c] / (1.0 + beta * (w->d[i] > 0.0 ? w->d[i] : 0.0));
    cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, n, 3, n, 1.0, w->Q, n, w->zs, n,
                0.0, w->yb, n);
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < n; k++)
            y[3 * k + c] = w->yb[k + (size_t)n * c];
    return log_abs_max(y, 3 * n);
}

/* Bring the log-factors y (in the range of M) within `limit` with the
 * smallest damping found by bisection to 1% in alpha.  OUT: *alpha. */
static int damp_to_limit(const hf_op *op, double *y, double limit, double *alpha,
                         glint_err *err)
{
    int n = op->n, rc = 0;
    size_t nn = (size_t)n * n;
    double *Q = malloc(nn * sizeof *Q), *d = malloc((size_t)n * sizeof *d);
    double *z = malloc((size_t)3 * n * sizeof *z), *zs = malloc((size_t)3 * n * sizeof *zs);
    double *yb = malloc((size_t)3 * n * sizeof *yb), *yt = malloc((size_t)3 * n * sizeof *yt);
    double dmax = 0.0, lo = 0.0, hi;
    damp_ws w;
    lapack_int info;

    if (!Q || !d || !z || !zs || !yb || !yt) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory damping a %dx%d operator", n, n);
        goto done;
    }
    for (size_t i = 0; i < nn; i++) /* symmetric: row- and column-major agree */
        Q[i] = op->prec == HF_F32 ? (double)op->Mf[i] : op->M[i];
    info = LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'U', n, Q, n, d);
    if (info != 0) {
        rc = glint_err_set(err, GLINT_ENUMERIC,
                           "LAPACKE_dsyevd failed (info %d) damping a %dx%d operator",
                           (int)info, n, n);
        goto done;
    }
    for (int i = 0; i < n; i++)
        if (d[i] > dmax)
            dmax = d[i];
    /* z = Q^T y */
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < n; k++)
            yb[k + (size_t)n * c] = y[3 * k + c];
    cblas_dgemm(CblasColMajor, CblasTrans, CblasNoTrans, n, 3, n, 1.0, Q, n, yb, n, 0.0, z, n);
    w.n = n;
    w.Q = Q;
    w.d = d;
    w.z = z;
    w.zs = zs;
    w.yb = yb;
    /* Bracket: beta = 1 / dmax puts alpha at about the smallest singular
     * value the operator uses; grow by 4 until within the limit (y(beta)
     * -> 0), then bisect. */
    hi = dmax > 0.0 ? 1.0 / dmax : 1.0;
    while (damp_eval(&w, hi, yt) > limit) {
        lo = hi;
        hi *= 4.0;
        if (hi > 1e300) {
            rc = glint_err_set(err, GLINT_ENUMERIC,
                               "log-factors stay beyond %g under any damping", limit);
            goto done;
        }
    }
    for (int it = 0; lo == 0.0 && it < 64; it++) {
        double mid = hi / 16.0;
        if (damp_eval(&w, mid, yt) > limit)
            lo = mid;
        else
            hi = mid;
    }
    while (lo > 0.0 && hi > 1.0201 * lo) { /* alpha to 1% */
        double mid = sqrt(lo * hi);
        if (damp_eval(&w, mid, yt) > limit)
            lo = mid;
        else
            hi = mid;
    }
    damp_eval(&w, hi, y);
    *alpha = sqrt(hi);
done:
    free(Q);
    free(d);
    free(z);
    free(zs);
    free(yb);
    free(yt);
    return rc;
}

void hf_factors_free(hf_factors *f)
{
    if (!f)
        return;
    free(f->logf);
    memset(f, 0, sizeof *f);
}

int hf_fit(const hf_design *d, const hf_op *op, const hf_map *map, hf_model model,
           const float *rgb, hf_factors *fac, hf_fit_stats *stats, glint_err *err)
{
    return hf_fit_with(d, op, map, model, rgb, NULL, fac, stats, err);
}

int hf_fit_with(const hf_design *d, const hf_op *op, const hf_map *map, hf_model model,
                const float *rgb, const hf_fit_reuse *reuse, hf_factors *fac,
                hf_fit_stats *stats, glint_err *err)
{
    double t0 = hf_now(), t1, t2;
    int n, N, rc = 0;
    double *t = NULL, *y = NULL;
    float *yf = NULL;
    hf_fit_stats st;
    hf_stream x;

    memset(fac, 0, sizeof *fac);
    memset(&st, 0, sizeof st);
    if (!d || !op || !map || !rgb || d->res != op->res)
        return glint_err_set(err, GLINT_EINVAL,
                             "fit needs a design and an operator of the same resolution");
    if (!(map->eps > 0.0) || !isfinite(map->eps) || !isfinite(map->a) ||
        !isfinite(map->margin) || map->margin < 0.0 ||
        (map->kind == HF_MAP_ADD && !(map->a > 0.0)))
        return glint_err_set(err, GLINT_EINVAL, "invalid mapping parameters");
    n = op->n;
    N = d->n;

    t = malloc((size_t)3 * n * sizeof *t);
    y = malloc((size_t)3 * n * sizeof *y);
    yf = malloc((size_t)3 * n * sizeof *yf);
    fac->logf = malloc((size_t)3 * n * sizeof *fac->logf);
    if (!t || !y || !yf || !fac->logf) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory fitting %d samples", N);
        goto fail;
    }
    fac->res = d->res;
    fac->model = model;
    fac->map = *map;

    /* The mapping's offsets: SUB's needs the largest value per channel. */
    if (map->kind == HF_MAP_SUB) {
        double vmax[3] = {0.0, 0.0, 0.0};
        for (int i = 0; i < N; i++) {
            double cosd = d->cos_i[i] > COS_FLOOR ? d->cos_i[i] : COS_FLOOR;
            for (int c = 0; c < 3; c++) {
                double v = rgb[3 * i + c];
                if (model == HF_MODEL_BRDF)
                    v /= cosd;
                if (v > vmax[c])
                    vmax[c] = v;
            }
        }
        for (int c = 0; c < 3; c++)
            fac->a_used[c] = hf_map_offset(map, vmax[c]);
    } else {
        for (int c = 0; c < 3; c++)
            fac->a_used[c] = hf_map_offset(map, 0.0);
    }
    t1 = hf_now();
    st.map_seconds = t1 - t0;
    x.d = d;
    x.rgb = rgb;
    x.map = map;
    x.model = model;
    x.a = fac->a_used;
    x.single = op->prec == HF_F32;
    {
        int chunk;
        hf_chunking(N, &chunk, &st.stream_chunks);
    }
    if ((rc = hf_stream_forward(&x, reuse, t, st.clamped, &st.stream_chunks_reused)) < 0) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory fitting %d samples", N);
        goto fail;
    }
    if (rc > 0) { /* a non-finite sample: name the first */
        for (long i = 0; i < 3L * N; i++)
            if (!isfinite(rgb[i])) {
                rc = glint_err_set(err, GLINT_ENONFINITE, "sample %ld channel %ld is not finite",
                                   i / 3, i % 3);
                goto fail;
            }
        rc = 0;
    }
    t2 = hf_now();
    st.stream_seconds = t2 - t1;
    if (op->prec == HF_F32) {
        apply_f32(op->Mf, n, t, yf);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < n; k++)
                fac->logf[3 * k + c] = yf[c * n + k];
    } else {
        apply_f64(op->M, n, t, y);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < n; k++)
                fac->logf[3 * k + c] = y[c * n + k];
    }
    st.op_seconds = hf_now() - t2;
    st.apply_seconds = hf_now() - t1;
    hf_factors_canonicalize(fac->logf, d->res);
    for (int c = 0; c < 3; c++)
        st.a_used[c] = fac->a_used[c];
    for (int k = 0; k < 3 * n; k++) {
        if (!isfinite(fac->logf[k])) {
            rc = glint_err_set(err, GLINT_ENUMERIC,
                               "fit produced a non-finite log-factor (texel %d); "
                               "the operator is unusable", k / 3);
            goto fail;
        }
    }
    /* Range: decided here, before anything is exponentiated (hf.h). */
    st.log_max = st.log_max_undamped = log_abs_max(fac->logf, 3 * n);
    if (st.log_max > HF_LOG_FACTOR_MAX) {
        rc = damp_to_limit(op, fac->logf, HF_LOG_FACTOR_MAX, &st.damping, err);
        if (rc)
            goto fail;
        st.log_max = log_abs_max(fac->logf, 3 * n);
    }
    st.total_seconds = hf_now() - t0;

    /* Diagnostics (not part of the timed fit), only when asked for. */
    if (stats) {
        t1 = hf_now();
        hf_stream_diagnostics(&x, fac, &st);
        st.diag_seconds = hf_now() - t1;
        *stats = st;
    }
    free(t);
    free(y);
    free(yf);
    return 0;
fail:
    free(t);
    free(y);
    free(yf);
    hf_factors_free(fac);
    return rc;
}
