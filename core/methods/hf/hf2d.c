/* hf2d.c: three factors, any of them 2D over parabolic maps (hf2d.h). */
#include "hf2d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hf4.h"
#include "vec3.h"

int hf2d_shape_check(const hf2d_shape *sh, glint_err *err)
{
    if (sh->res < HF_RES_MIN || sh->res > HF_RES_MAX)
        return glint_err_set(err, GLINT_ERANGE, "1D factor resolution %d outside %d..%d",
                             sh->res, HF_RES_MIN, HF_RES_MAX);
    if (sh->sres < HF2D_SRES_MIN || sh->sres > HF2D_SRES_MAX)
        return glint_err_set(err, GLINT_ERANGE, "2D factor resolution %d outside %d..%d",
                             sh->sres, HF2D_SRES_MIN, HF2D_SRES_MAX);
    for (int j = 0; j < 3; j++)
        if (sh->dims[j] != 1 && sh->dims[j] != 2)
            return glint_err_set(err, GLINT_ERANGE, "factor %c: dimensions must be 1 or 2",
                                 "pqr"[j]);
    return 0;
}

int hf2d_offsets(const hf2d_shape *sh, int off[4])
{
    off[0] = 0;
    for (int j = 0; j < 3; j++)
        off[j + 1] = off[j] + (sh->dims[j] == 2 ? sh->sres * sh->sres : sh->res);
    return off[3];
}

void hf2d_parabolic(const double nrm[3], const double d[3], double uv[2])
{
    v3 n = v3_load(nrm), dv = v3_load(d), t, b;
    double c;
    v3_frame(n, &t, &b);
    c = v3_dot(dv, n);
    if (!(c > 0.0))
        c = 0.0;
    uv[0] = 0.5 * (v3_dot(dv, t) / (1.0 + c) + 1.0);
    uv[1] = 0.5 * (v3_dot(dv, b) / (1.0 + c) + 1.0);
}

/* The three vectors of a sample's factors and their 1D projections. */
static void sample_vectors(const double n[3], const double wi[3], const double wo[3],
                           double vec[3][3], double pi[3])
{
    v3 h = v3_normalize(v3_add(v3_load(wi), v3_load(wo)));
    memcpy(vec[0], wi, sizeof vec[0]);
    v3_store(h, vec[1]);
    memcpy(vec[2], wo, sizeof vec[2]);
    hf_project(n, wi, wo, pi);
}

/* The hats of factor j at one sample (OUT: k[2], t[2]). */
static void factor_hats(const hf2d_shape *sh, int j, const double n[3], const double vec[3],
                        double pi, int32_t k[2], double t[2])
{
    if (sh->dims[j] == 1) {
        int k0;
        hf_hat(pi, sh->res, &k0, &t[0]);
        k[0] = k0;
        k[1] = 0;
        t[1] = 0.0;
    } else {
        double uv[2];
        int a, b;
        hf2d_parabolic(n, vec, uv);
        hf_hat(uv[0], sh->sres, &a, &t[0]);
        hf_hat(uv[1], sh->sres, &b, &t[1]);
        k[0] = a;
        k[1] = b;
    }
}

void hf2d_design_free(hf2d_design *d)
{
    if (!d)
        return;
    free(d->k);
    free(d->t);
    free(d->cos_i);
    memset(d, 0, sizeof *d);
}

int hf2d_design_build(const samples *s, const hf2d_shape *sh, hf2d_design *out, glint_err *err)
{
    int rc;
    memset(out, 0, sizeof *out);
    if ((rc = hf2d_shape_check(sh, err)))
        return rc;
    out->sh = *sh;
    out->n = s->n;
    hf2d_offsets(sh, out->off);
    out->k = malloc(6 * (size_t)(s->n ? s->n : 1) * sizeof *out->k);
    out->t = malloc(6 * (size_t)(s->n ? s->n : 1) * sizeof *out->t);
    out->cos_i = malloc((size_t)(s->n ? s->n : 1) * sizeof *out->cos_i);
    if (!out->k || !out->t || !out->cos_i) {
        hf2d_design_free(out);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d samples", s->n);
    }
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], vec[3][3], pi[3];
        for (int a = 0; a < 3; a++) {
            n[a] = s->nrm[3 * (size_t)i + a];
            wi[a] = s->wi[3 * (size_t)i + a];
            wo[a] = s->wo[3 * (size_t)i + a];
        }
        sample_vectors(n, wi, wo, vec, pi);
        for (int j = 0; j < 3; j++)
            factor_hats(sh, j, n, vec[j], pi[j], out->k + 6 * (size_t)i + 2 * j,
                        out->t + 6 * (size_t)i + 2 * j);
        out->cos_i[i] = s->cos_i[i];
    }
    return 0;
}

/* ---- rows ------------------------------------------------------------------------ */

typedef hf2d_rows_ctx rows_ctx;

static int data_row(const hf2d_design *x, int i, int *col, double *w)
{
    int m = 0, S = x->sh.sres;
    for (int j = 0; j < 3; j++) {
        const int32_t *k = x->k + 6 * (size_t)i + 2 * j;
        const double *t = x->t + 6 * (size_t)i + 2 * j;
        int c = x->off[j];
        if (x->sh.dims[j] == 1) {
            col[m] = c + k[0];
            w[m++] = 1.0 - t[0];
            col[m] = c + k[0] + 1;
            w[m++] = t[0];
        } else {
            c += k[1] * S + k[0];
            col[m] = c;
            w[m++] = (1.0 - t[0]) * (1.0 - t[1]);
            col[m] = c + 1;
            w[m++] = t[0] * (1.0 - t[1]);
            col[m] = c + S;
            w[m++] = (1.0 - t[0]) * t[1];
            col[m] = c + S + 1;
            w[m++] = t[0] * t[1];
        }
    }
    return m;
}

static int any_row(const void *ctx, int r, int *col, double *w)
{
    const rows_ctx *c = ctx;
    const hf2d_design *x = c->x;
    int j = 0;
    if (r < x->n)
        return data_row(x, r, col, w);
    r -= x->n;
    while (j < 2 && r >= c->start[j + 1])
        j++;
    r -= c->start[j];
    if (x->sh.dims[j] == 1)
        return hfx_smooth_1d(x->off[j], c->lambda, r, col, w);
    return hfx_smooth_2d(x->off[j], x->sh.sres, c->lambda_2d, r, col, w);
}

hfx_rows hf2d_rows(const hf2d_design *d, double lambda, double lambda_2d, hf2d_rows_ctx *c)
{
    const hf2d_design *x = d;
    c->x = d;
    c->lambda = lambda;
    c->lambda_2d = lambda_2d;
    hfx_rows r = {.ctx = c, .n = x->off[3], .nsamples = x->n, .row = any_row, .nfactors = 3,
                  .off = x->off, .grid = c->grid};
    c->start[0] = 0;
    for (int j = 0; j < 3; j++) {
        c->grid[j] = x->sh.dims[j] == 2 && c->lambda_2d > 0.0 ? x->sh.sres : 0;
        int m = x->sh.dims[j] == 1 ? (c->lambda > 0.0 ? x->sh.res - 2 : 0)
                                   : (c->lambda_2d > 0.0 ? x->sh.sres * x->sh.sres : 0);
        c->start[j + 1] = c->start[j] + m;
    }
    r.nsmooth = c->start[3];
    return r;
}

/* ---- decomposition and fit ---------------------------------------------------------- */

static int lambda_ok(double l)
{
    return l >= 0.0 && isfinite(l) && l <= HF_LAMBDA_MAX;
}

void hf2d_decomp_free(hf2d_decomp *dc)
{
    if (!dc)
        return;
    hfx_decomp_free(&dc->x);
    memset(dc, 0, sizeof *dc);
}

int hf2d_decomp_build(const hf2d_design *d, double lambda, double lambda_2d, double rcond,
                      hf2d_decomp *dc, glint_err *err)
{
    rows_ctx c;
    hfx_rows r;
    memset(dc, 0, sizeof *dc);
    if (!lambda_ok(lambda) || !lambda_ok(lambda_2d))
        return glint_err_set(err, GLINT_ERANGE, "lambda %g and lambda_2d %g must be in 0..%g",
                             lambda, lambda_2d, HF_LAMBDA_MAX);
    if (!(rcond > 0.0))
        rcond = HF4_RCOND_DEFAULT;
    if (!(rcond < 1.0) || !isfinite(rcond))
        return glint_err_set(err, GLINT_ERANGE, "rcond %g must be below 1", rcond);
    r = hf2d_rows(d, lambda, lambda_2d, &c);
    dc->sh = d->sh;
    dc->lambda = lambda;
    dc->lambda_2d = lambda_2d;
    return hfx_decomp_build(&r, rcond, 2, &dc->x, err);
}

void hf2d_factors_free(hf2d_factors *f)
{
    if (!f)
        return;
    free(f->logy);
    memset(f, 0, sizeof *f);
}

int hf2d_fit(const hf2d_design *x, const hf2d_decomp *dc, const hf_map *map, hf_model model,
             const float *rgb, const int *view, hf2d_factors *fac, hfx_fit_stats *st,
             glint_err *err)
{
    rows_ctx c;
    hfx_rows r = hf2d_rows(x, dc->lambda, dc->lambda_2d, &c);
    hfx_problem pb = {.map = map, .model = model, .cos_i = x->cos_i, .nfactors = 3,
                      .off = x->off, .log_max = HF2D_LOG_MAX, .view = view};
    int n = x->off[3], rc;
    double *y;

    memset(fac, 0, sizeof *fac);
    if (memcmp(&dc->sh, &x->sh, sizeof x->sh) != 0 || dc->x.nsamples != x->n)
        return glint_err_set(err, GLINT_EINVAL, "decomposition and design do not match");
    y = malloc(3 * (size_t)n * sizeof *y);
    fac->logy = malloc(3 * (size_t)n * sizeof *fac->logy);
    if (!y || !fac->logy) {
        free(y);
        hf2d_factors_free(fac);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory fitting %d samples", x->n);
    }
    fac->sh = x->sh;
    memcpy(fac->off, x->off, sizeof fac->off);
    fac->model = model;
    fac->map = *map;
    if ((rc = hfx_fit(&r, &dc->x, &pb, rgb, y, fac->a_used, st, err))) {
        free(y);
        hf2d_factors_free(fac);
        return rc;
    }
    for (int ch = 0; ch < 3; ch++)
        for (int t = 0; t < n; t++)
            fac->logy[(size_t)t * 3 + ch] = y[(size_t)n * ch + t];
    free(y);
    return 0;
}

void hf2d_factors_eval(const hf2d_factors *f, const double n[3], const double wi[3],
                       const double wo[3], double rgb[3])
{
    double vec[3][3], pi[3], acc[3] = {0.0, 0.0, 0.0}, ci, co;
    int S = f->sh.sres;

    ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    if (!(ci > 0.0) || !(co > 0.0)) {
        rgb[0] = rgb[1] = rgb[2] = 0.0;
        return;
    }
    sample_vectors(n, wi, wo, vec, pi);
    for (int j = 0; j < 3; j++) {
        int32_t k[2];
        double t[2];
        const double *L = f->logy + 3 * (size_t)f->off[j];
        factor_hats(&f->sh, j, n, vec[j], pi[j], k, t);
        for (int c = 0; c < 3; c++) {
            if (f->sh.dims[j] == 1) {
                acc[c] += (1.0 - t[0]) * L[3 * (size_t)k[0] + c] + t[0] * L[3 * (size_t)(k[0] + 1) + c];
            } else {
                size_t q = (size_t)k[1] * S + k[0];
                acc[c] += (1.0 - t[1]) * ((1.0 - t[0]) * L[3 * q + c] + t[0] * L[3 * (q + 1) + c]) +
                          t[1] * ((1.0 - t[0]) * L[3 * (q + S) + c] + t[0] * L[3 * (q + S + 1) + c]);
            }
        }
    }
    for (int c = 0; c < 3; c++) {
        double v = hf_map_inverse(&f->map, f->a_used[c], exp(acc[c] > 700.0 ? 700.0 : acc[c]));
        rgb[c] = f->model == HF_MODEL_BRDF ? v * ci : v;
    }
}
