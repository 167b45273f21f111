/* hf4.c: the four-factor product (hf4.h). */
#include "hf4.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hfx.h"


void hf4_design_free(hf4_design *d)
{
    if (!d)
        return;
    hf_design_free(&d->d);
    free(d->ij);
    free(d->txy);
    memset(d, 0, sizeof *d);
}

int hf4_design_build(const samples *s, int res, int sres, hf4_design *out, glint_err *err)
{
    int rc;
    memset(out, 0, sizeof *out);
    if (sres < HF4_SRES_MIN || sres > HF4_SRES_MAX)
        return glint_err_set(err, GLINT_ERANGE, "spatial factor resolution %d outside %d..%d",
                             sres, HF4_SRES_MIN, HF4_SRES_MAX);
    if (!s->has_pos || !s->uv)
        return glint_err_set(err, GLINT_EINVAL,
                             "the four-factor product needs the samples' texture coordinates "
                             "(imported samples have none): paint a scene's views");
    if ((rc = hf_design_build(s, res, &out->d, err)))
        return rc;
    out->sres = sres;
    out->ij = malloc(2 * (size_t)s->n * sizeof *out->ij);
    out->txy = malloc(2 * (size_t)s->n * sizeof *out->txy);
    if (!out->ij || !out->txy) {
        hf4_design_free(out);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d samples", s->n);
    }
    for (int i = 0; i < s->n; i++)
        for (int a = 0; a < 2; a++) {
            int k;
            double t;
            hf_hat(s->uv[2 * (size_t)i + a], sres, &k, &t);
            out->ij[2 * (size_t)i + a] = k;
            out->txy[2 * (size_t)i + a] = t;
        }
    return 0;
}

/* Data row i of A: its nonzeros (OUT: col, w; returns their count). */
static int data_row(const hf4_design *x, int i, int *col, double *w)
{
    int R = x->d.res, S = x->sres, m = 0, base = 3 * R;
    int i0 = x->ij[2 * (size_t)i], j0 = x->ij[2 * (size_t)i + 1];
    double tx = x->txy[2 * (size_t)i], ty = x->txy[2 * (size_t)i + 1];
    for (int j = 0; j < 3; j++) {
        int c = j * R + x->d.k0[3 * (size_t)i + j];
        double t = x->d.t[3 * (size_t)i + j];
        col[m] = c;
        w[m++] = 1.0 - t;
        col[m] = c + 1;
        w[m++] = t;
    }
    col[m] = base + j0 * S + i0;
    w[m++] = (1.0 - tx) * (1.0 - ty);
    col[m] = base + j0 * S + i0 + 1;
    w[m++] = tx * (1.0 - ty);
    col[m] = base + (j0 + 1) * S + i0;
    w[m++] = (1.0 - tx) * ty;
    col[m] = base + (j0 + 1) * S + i0 + 1;
    w[m++] = tx * ty;
    return m;
}

/* Smoothing rows: those of p, q, r when lambda > 0, those of s when
 * lambda_s > 0 (a zero weight adds no row). */
static int rows_1d(int R, double lambda)
{
    return lambda > 0.0 ? 3 * (R - 2) : 0;
}

static int any_row(const void *ctx, int r, int *col, double *w)
{
    const hf4_rows_ctx *c = ctx;
    int R = c->x->d.res;
    if (r < c->x->d.n)
        return data_row(c->x, r, col, w);
    r -= c->x->d.n;
    if (r < rows_1d(R, c->lambda))
        return hfx_smooth_1d(r / (R - 2) * R, c->lambda, r % (R - 2), col, w);
    return hfx_smooth_2d(3 * R, c->x->sres, c->lambda_s, r - rows_1d(R, c->lambda), col, w);
}

static hfx_rows rows_of(hf4_rows_ctx *c);

hfx_rows hf4_rows(const hf4_design *x, double lambda, double lambda_s, hf4_rows_ctx *c)
{
    c->x = x;
    c->lambda = lambda;
    c->lambda_s = lambda_s;
    return rows_of(c);
}

static hfx_rows rows_of(hf4_rows_ctx *c)
{
    int R = c->x->d.res, S = c->x->sres;
    hfx_rows r = {.ctx = c, .n = 3 * R + S * S, .nsamples = c->x->d.n, .row = any_row,
                  .nfactors = 4, .off = c->off, .grid = c->grid};
    for (int j = 0; j < 4; j++)
        c->off[j] = j * R, c->grid[j] = 0;
    c->grid[3] = c->lambda_s > 0.0 ? S : 0;
    c->off[4] = 3 * R + S * S;
    r.nsmooth = rows_1d(R, c->lambda) + (c->lambda_s > 0.0 ? S * S : 0);
    return r;
}

void hf4_decomp_free(hf4_decomp *dc)
{
    if (!dc)
        return;
    hfx_decomp_free(&dc->x);
    memset(dc, 0, sizeof *dc);
}

static int lambda_ok(double l)
{
    return l >= 0.0 && isfinite(l) && l <= HF_LAMBDA_MAX;
}

int hf4_decomp_build(const hf4_design *x, double lambda, double lambda_s, double rcond,
                     hf4_decomp *dc, glint_err *err)
{
    hf4_rows_ctx c = {.x = x, .lambda = lambda, .lambda_s = lambda_s};
    hfx_rows r;

    memset(dc, 0, sizeof *dc);
    if (!lambda_ok(lambda) || !lambda_ok(lambda_s))
        return glint_err_set(err, GLINT_ERANGE, "lambda %g and lambda_s %g must be in 0..%g",
                             lambda, lambda_s, HF_LAMBDA_MAX);
    if (!(rcond > 0.0))
        rcond = HF4_RCOND_DEFAULT;
    if (!(rcond < 1.0) || !isfinite(rcond))
        return glint_err_set(err, GLINT_ERANGE, "rcond %g must be below 1", rcond);
    r = rows_of(&c);
    dc->res = x->d.res;
    dc->sres = x->sres;
    dc->lambda = lambda;
    dc->lambda_s = lambda_s;
    return hfx_decomp_build(&r, rcond, 3, &dc->x, err);
}

void hf4_factors_free(hf4_factors *f)
{
    if (!f)
        return;
    free(f->logf);
    free(f->logs);
    memset(f, 0, sizeof *f);
}

void hf4_factors_means(hf4_factors *f)
{
    size_t nn = (size_t)f->sres * f->sres;
    for (int c = 0; c < 3; c++) {
        double s = 0.0;
        for (size_t i = 0; i < nn; i++)
            s += exp(f->logs[3 * i + c] > 700.0 ? 700.0 : f->logs[3 * i + c]);
        f->mean_s[c] = s / (double)nn;
    }
}

static double map_inverse(const hf4_factors *f, int c, double prod)
{
    return hf_map_inverse(&f->map, f->a_used[c], prod);
}

void hf4_factors_eval(const hf4_factors *f, const double uv[2], const double n[3],
                      const double wi[3], const double wo[3], double rgb[3])
{
    double pi[3], ci, co, acc[3] = {0.0, 0.0, 0.0}, lin[3] = {1.0, 1.0, 1.0};
    int R = f->res, S = f->sres;

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
            acc[c] += (1.0 - t) * f->logf[(j * R + k) * 3 + c] +
                      t * f->logf[(j * R + k + 1) * 3 + c];
    }
    if (uv && isfinite(uv[0]) && isfinite(uv[1])) {
        int i0, j0;
        double tx, ty;
        const double *L = f->logs;
        hf_hat(uv[0], S, &i0, &tx);
        hf_hat(uv[1], S, &j0, &ty);
        for (int c = 0; c < 3; c++)
            acc[c] += (1.0 - ty) * ((1.0 - tx) * L[((size_t)j0 * S + i0) * 3 + c] +
                                    tx * L[((size_t)j0 * S + i0 + 1) * 3 + c]) +
                      ty * ((1.0 - tx) * L[((size_t)(j0 + 1) * S + i0) * 3 + c] +
                            tx * L[((size_t)(j0 + 1) * S + i0 + 1) * 3 + c]);
    } else {
        for (int c = 0; c < 3; c++)
            lin[c] = f->mean_s[c];
    }
    for (int c = 0; c < 3; c++) {
        double v = map_inverse(f, c, exp(acc[c] > 700.0 ? 700.0 : acc[c]) * lin[c]);
        rgb[c] = f->model == HF_MODEL_BRDF ? v * ci : v;
    }
}

int hf4_fit(const hf4_design *x, const hf4_decomp *dc, const hf_map *map, hf_model model,
            const float *rgb, const int *view, hf4_factors *fac, hf4_fit_stats *st,
            glint_err *err)
{
    int R = x->d.res, S = x->sres, n = dc->x.n, rc;
    int off[5] = {0, R, 2 * R, 3 * R, 3 * R + S * S};
    hf4_rows_ctx c = {.x = x, .lambda = dc->lambda, .lambda_s = dc->lambda_s};
    hfx_rows r = rows_of(&c);
    hfx_problem pb = {.map = map, .model = model, .cos_i = x->d.cos_i, .nfactors = 4,
                      .off = off, .log_max = HF4_LOG_MAX, .view = view};
    double *y;

    memset(fac, 0, sizeof *fac);
    if (dc->res != R || dc->sres != S || dc->x.nsamples != x->d.n)
        return glint_err_set(err, GLINT_EINVAL, "decomposition and design do not match");
    y = malloc(3 * (size_t)n * sizeof *y);
    fac->logf = malloc(9 * (size_t)R * sizeof *fac->logf);
    fac->logs = malloc(3 * (size_t)S * S * sizeof *fac->logs);
    if (!y || !fac->logf || !fac->logs) {
        free(y);
        hf4_factors_free(fac);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory fitting %d samples", x->d.n);
    }
    fac->res = R;
    fac->sres = S;
    fac->model = model;
    fac->map = *map;
    if ((rc = hfx_fit(&r, &dc->x, &pb, rgb, y, fac->a_used, st, err))) {
        free(y);
        hf4_factors_free(fac);
        return rc;
    }
    for (int ch = 0; ch < 3; ch++)
        for (int t = 0; t < n; t++) {
            double v = y[(size_t)n * ch + t];
            if (t < 3 * R)
                fac->logf[(size_t)t * 3 + ch] = v;
            else
                fac->logs[(size_t)(t - 3 * R) * 3 + ch] = v;
        }
    free(y);
    hf4_factors_means(fac);
    return 0;
}
