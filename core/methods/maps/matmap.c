/* matmap.c: material maps by iterative residual factorization (matmap.h). */
#include "matmap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "samples.h"
#include "uvtex.h"

void matmap_params_default(matmap_params *mp)
{
    mp->components = 5;
    mp->merge = MATMAP_MERGE_LSQ;
    mp->res = 128;
    mp->tol = 0.01;
    mp->refine = 20;
    mp->rounds = 8;
    mp->smooth = 0.1;
}

void matmap_free(matmap *m)
{
    if (!m)
        return;
    for (int k = 0; k < m->k; k++)
        material_free(&m->comp[k]);
    free(m->coef);
    memset(m, 0, sizeof *m);
}

double matmap_coef(const matmap *m, int k, double u, double v)
{
    return uvtex_lookup(m->coef + (size_t)k * m->res * m->res, m->res, u, v);
}

static double rel_rms(const float *r, const float *f, size_t n3)
{
    double a = 0.0, b = 0.0;
    for (size_t i = 0; i < n3; i++) {
        a += (double)r[i] * r[i];
        b += (double)f[i] * f[i];
    }
    return b > 0.0 ? sqrt(a / b) : 0.0;
}

/* Component k's texture from the per-sample scales c: each view's samples
 * splatted, merged by the smallest value where several views reach a
 * texel, then the texels no view reaches filled */
static int coef_texture(const samples *s, const float *c, int res, float *tex, float *scratch,
                        int *hits, int *shits, float *uvv, float *cv, glint_err *err)
{
    int rc;
    size_t nt = (size_t)res * res;
    memset(hits, 0, nt * sizeof *hits);
    for (int v = 0; v < s->nviews; v++) {
        int m = 0;
        for (int i = 0; i < s->n; i++)
            if (s->view[i] == v) {
                uvv[2 * m] = s->uv[2 * (size_t)i];
                uvv[2 * m + 1] = s->uv[2 * (size_t)i + 1];
                cv[m++] = c[i];
            }
        if (!m)
            continue;
        if ((rc = uvtex_splat(uvv, cv, m, 1, res, scratch, shits, err)))
            return rc;
        uvtex_merge_min(tex, hits, scratch, shits, nt, 1);
    }
    return uvtex_fill(tex, hits, res, 1, NULL, err);
}

/* Component k's texture by least squares: per texel sum(r.f) / sum(f.f)
 * over its samples (all views, all channels), in [0, 1]; the means of the
 * two products per texel give the same ratio as their sums */
static int coef_lsq(const samples *s, const float *r, const float *fk, int res, float *tex,
                    float *two, int *hits, float *pair, glint_err *err)
{
    size_t nt = (size_t)res * res;
    int rc;
    for (int i = 0; i < s->n; i++) {
        double rf = 0.0, ff = 0.0;
        for (int ch = 0; ch < 3; ch++) {
            double f = fk[3 * (size_t)i + ch];
            if (isfinite(f)) {
                rf += r[3 * (size_t)i + ch] * f;
                ff += f * f;
            }
        }
        pair[2 * (size_t)i] = (float)rf;
        pair[2 * (size_t)i + 1] = (float)ff;
    }
    if ((rc = uvtex_splat(s->uv, pair, s->n, 2, res, two, hits, err)))
        return rc;
    for (size_t t = 0; t < nt; t++) {
        double x = two[2 * t + 1] > 0.0f ? (double)two[2 * t] / two[2 * t + 1] : 0.0;
        if (!(two[2 * t + 1] > 0.0f))
            hits[t] = 0; /* nothing to scale here: filled from the neighbours */
        tex[t] = (float)(x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x);
    }
    return uvtex_fill(tex, hits, res, 1, NULL, err);
}

/* The model's value at every sample from products' predictions F (K x 3n,
 * per unit light) and the coefficient textures: OUT r = rgb - model, and
 * the relative RMS of r. */
static double model_residual(const samples *s, const float *rgb, const float *F, int K,
                             const float *coef, int res, float *r)
{
    size_t n3 = 3 * (size_t)s->n, nt = (size_t)res * res;
    for (size_t i = 0; i < n3; i++)
        r[i] = rgb[i];
    for (int k = 0; k < K; k++)
        for (size_t i = 0; i < (size_t)s->n; i++) {
            double c = uvtex_lookup(coef + k * nt, res, s->uv[2 * i], s->uv[2 * i + 1]);
            for (int ch = 0; ch < 3; ch++) {
                float f = F[k * n3 + 3 * i + ch];
                if (isfinite(f))
                    r[3 * i + ch] -= (float)(c * f);
            }
        }
    return rel_rms(r, rgb, n3);
}

/* Each texel's samples with their bilinear weights, as uvtex_lookup reads
 * them: texel t's entries are start[t] .. start[t + 1] - 1. */
typedef struct texel_lists {
    size_t *start;  /* nt + 1 */
    int *idx;       /* each entry's sample */
    float *wt;      /* and its weight */
} texel_lists;

/* The lists by a counting sort of (sample, weight) by texel: two passes
 * over the samples' four corners. */
static void texel_lists_make(const samples *s, int res, texel_lists *tl)
{
    size_t n = (size_t)s->n, nt = (size_t)res * res, *start = tl->start;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t i = 0; i < n; i++) {
            size_t t[4];
            double w[4];
            uvtex_footprint(s->uv[2 * i], s->uv[2 * i + 1], res, t, w);
            for (int c = 0; c < 4; c++) {
                if (!(w[c] > 0.0))
                    continue;
                if (pass == 0) {
                    start[t[c] + 1]++;
                } else {
                    size_t e = start[t[c]]++;
                    tl->idx[e] = (int)i;
                    tl->wt[e] = (float)w[c];
                }
            }
        }
        if (pass == 0) {
            for (size_t t = 0; t < nt; t++)
                start[t + 1] += start[t];
        } else { /* start[t] now holds the end of t: shift back */
            memmove(start + 1, start, nt * sizeof *start);
            start[0] = 0;
        }
    }
}

/* The smoothness weight mu: smooth times the mean data weight (the
 * diagonal of the normal equations) of a reached texel and product. */
static double smooth_weight(const float *F, int K, size_t n3, size_t nt, const texel_lists *tl,
                            double smooth)
{
    double hs = 0.0;
    long cnt = 0;
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < K; k++) {
            double h = 0.0;
            for (size_t e = tl->start[t]; e < tl->start[t + 1]; e++)
                for (int ch = 0; ch < 3; ch++) {
                    double fv = F[k * n3 + 3 * (size_t)tl->idx[e] + ch];
                    if (isfinite(fv))
                        h += (double)tl->wt[e] * tl->wt[e] * fv * fv;
                }
            if (h > 0.0) {
                hs += h;
                cnt++;
            }
        }
    return cnt ? smooth * hs / (double)cnt : 0.0;
}

/* One coordinate of the descent: texel t of product k (coefficients ck,
 * predictions f) moved to the minimum of the squared error plus mu times
 * the squared differences to its grid neighbours, within [0, 1]; the
 * residual r follows. */
static void refine_texel(const texel_lists *tl, const float *f, float *ck, size_t t, int res,
                         double mu, float *r)
{
    float *c = ck + t;
    double g = 0.0, h = 0.0, cn, d;
    for (size_t e = tl->start[t]; e < tl->start[t + 1]; e++) {
        size_t i = (size_t)tl->idx[e];
        double w = tl->wt[e];
        for (int ch = 0; ch < 3; ch++) {
            double fv = f[3 * i + ch];
            if (!isfinite(fv))
                continue;
            g += w * fv * r[3 * i + ch];
            h += w * w * fv * fv;
        }
    }
    if (mu > 0.0) { /* mu sum over grid neighbours of (c - c')^2 */
        int ti = (int)(t % (size_t)res), tj = (int)(t / (size_t)res), deg = 0;
        double sd = 0.0;
        if (ti > 0)
            sd += *c - ck[t - 1], deg++;
        if (ti + 1 < res)
            sd += *c - ck[t + 1], deg++;
        if (tj > 0)
            sd += *c - ck[t - res], deg++;
        if (tj + 1 < res)
            sd += *c - ck[t + res], deg++;
        g -= mu * sd;
        h += mu * deg;
    }
    if (!(h > 0.0))
        return;
    cn = *c + g / h;
    cn = cn < 0.0 ? 0.0 : cn > 1.0 ? 1.0 : cn;
    d = cn - *c;
    if (d == 0.0)
        return;
    *c = (float)cn;
    for (size_t e = tl->start[t]; e < tl->start[t + 1]; e++) {
        size_t i = (size_t)tl->idx[e];
        double w = tl->wt[e];
        for (int ch = 0; ch < 3; ch++) {
            double fv = f[3 * i + ch];
            if (isfinite(fv))
                r[3 * i + ch] -= (float)(d * w * fv);
        }
    }
}

/* The joint refinement (matmap.h): projected coordinate descent over every
 * texel and product on the model's squared error, the bilinear weights of
 * each sample's four texels as uvtex_lookup reads them.  r: the residual
 * of the current coefficients (updated).  OUT: *sweeps. */
static int refine_joint(const samples *s, const float *rgb, const float *F, int K, int res,
                        int max_sweeps, double smooth, float *coef, float *r, int *sweeps,
                        glint_err *err)
{
    double mu = 0.0;
    size_t n = (size_t)s->n, n3 = 3 * n, nt = (size_t)res * res;
    texel_lists tl;
    double prev = 0.0;
    (void)rgb;

    *sweeps = 0;
    tl.start = calloc(nt + 1, sizeof *tl.start);
    tl.idx = malloc(4 * n * sizeof *tl.idx);
    tl.wt = malloc(4 * n * sizeof *tl.wt);
    if (!tl.start || !tl.idx || !tl.wt) {
        free(tl.start);
        free(tl.idx);
        free(tl.wt);
        return glint_err_set(err, GLINT_ENOMEM, "material map: out of memory to refine");
    }
    texel_lists_make(s, res, &tl);
    for (size_t i = 0; i < n3; i++)
        prev += (double)r[i] * r[i];
    if (smooth > 0.0)
        mu = smooth_weight(F, K, n3, nt, &tl, smooth);
    for (int sw = 0; sw < max_sweeps; sw++) {
        double now = 0.0;
        for (size_t t = 0; t < nt; t++) {
            if (tl.start[t] == tl.start[t + 1] && mu == 0.0)
                continue;
            for (int k = 0; k < K; k++)
                refine_texel(&tl, F + k * n3, coef + k * nt, t, res, mu, r);
        }
        for (size_t i = 0; i < n3; i++)
            now += (double)r[i] * r[i];
        *sweeps = sw + 1;
        if (!(now < prev * (1.0 - 1e-4)))
            break;
        prev = now;
    }
    free(tl.start);
    free(tl.idx);
    free(tl.wt);
    return 0;
}

static int prep_src_fit(void *cls, const float *rgb, material *out, glint_err *err)
{
    return prep_fit(cls, NULL, rgb, out, err);
}

static int prep_src_predict(void *cls, const material *m, float *f, glint_err *err)
{
    const samples *s = prep_samples(cls);
    int rc = prep_predict(cls, m, f, err);
    for (size_t i = 0; rc == 0 && i < 3 * (size_t)s->n; i++) /* per unit light */
        f[i] = (float)(f[i] / s->intensity[i / 3]);
    return rc;
}

int matmap_fit(const prep *p, const float *rgb, const matmap_params *mp, matmap *out,
               glint_err *err)
{
    matmap_source src = {prep_samples(p), prep_src_fit, prep_src_predict, (void *)p};
    return matmap_fit_source(&src, rgb, mp, out, err);
}

/* A fit's input and working buffers, from one stage to the next
 * (matmap_fit_source). */
typedef struct fit_state {
    const matmap_source *src;
    const samples *s;
    const float *rgb;
    const matmap_params *mp;
    size_t n, n3, nt;    /* samples, their values, texels */
    float *r;            /* n3: the residual */
    float *fk;           /* n3: a product's predictions per unit light (a back-fit's target) */
    float *c;            /* n: a product's scale per sample */
    float *scratch;      /* 2 nt */
    float *uvv, *cv;     /* 2 n, n: one view's coordinates and scales (the smallest-value
                            merge); uvv also holds coef_lsq's pairs */
    int *hits, *shits;   /* nt each */
    float *F;            /* components x n3: every product's predictions, kept for the
                            model's residual and the refinement; NULL over
                            MATMAP_REFINE_MAX_BYTES */
} fit_state;

/* The parameters' ranges, texture coordinates, and painted values that
 * are finite and not negative. */
static int fit_input_check(const samples *s, const float *rgb, const matmap_params *mp,
                           glint_err *err)
{
    size_t n3 = 3 * (size_t)s->n;
    if (!mp || mp->components < 1 || mp->components > MATMAP_MAX || mp->res < 1 ||
        mp->res > UVTEX_MAX_RES || !(mp->tol >= 0.0) ||
        (mp->merge != MATMAP_MERGE_LSQ && mp->merge != MATMAP_MERGE_MIN) || mp->refine < 0 ||
        mp->refine > MATMAP_REFINE_MAX || mp->rounds < 0 || mp->rounds > MATMAP_ROUNDS_MAX ||
        !(mp->smooth >= 0.0 && mp->smooth <= MATMAP_SMOOTH_MAX) ||
        (mp->rounds > 0 && mp->refine < 1))
        return glint_err_set(err, GLINT_EINVAL,
                             "material map: components 1..%d, res 1..%d, tol >= 0, merge "
                             "lsq or min, refine 0..%d, rounds 0..%d (rounds need refine) and "
                             "smooth 0..%g", MATMAP_MAX, UVTEX_MAX_RES, MATMAP_REFINE_MAX,
                             MATMAP_ROUNDS_MAX, MATMAP_SMOOTH_MAX);
    if (!s->has_pos || !s->uv)
        return glint_err_set(err, GLINT_EINVAL,
                             "material map: the samples carry no texture coordinates "
                             "(imported samples): paint a scene's views");
    for (size_t i = 0; i < n3; i++)
        if (!(rgb[i] >= 0.0f) || !isfinite(rgb[i]))
            return glint_err_set(err, GLINT_EINVAL,
                                 "material map: sample %zu has a negative or non-finite value",
                                 i / 3);
    return 0;
}

/* The buffers and out's coefficient textures; F only within
 * MATMAP_REFINE_MAX_BYTES (out->refine then says why the refinement is
 * skipped). */
static int fit_alloc(fit_state *fs, matmap *out, glint_err *err)
{
    const matmap_params *mp = fs->mp;
    size_t n = fs->n, n3 = fs->n3, nt = fs->nt;
    fs->r = malloc(n3 * sizeof *fs->r);
    fs->fk = malloc(n3 * sizeof *fs->fk);
    fs->c = malloc(n * sizeof *fs->c);
    fs->scratch = malloc(2 * nt * sizeof *fs->scratch);
    fs->uvv = malloc(2 * n * sizeof *fs->uvv);
    fs->cv = malloc(n * sizeof *fs->cv);
    fs->hits = malloc(nt * sizeof *fs->hits);
    fs->shits = malloc(nt * sizeof *fs->shits);
    out->coef = malloc((size_t)mp->components * nt * sizeof *out->coef);
    out->refine = mp->refine > 0 ? "skipped: memory" : "off";
    {
        size_t fb = (size_t)mp->components * n3 * sizeof *fs->F;
        if (fb / mp->components / sizeof *fs->F == n3 && fb <= MATMAP_REFINE_MAX_BYTES)
            fs->F = malloc(fb);
    }
    if (!fs->r || !fs->fk || !fs->c || !fs->scratch || !fs->uvv || !fs->cv || !fs->hits ||
        !fs->shits || !out->coef)
        return glint_err_set(err, GLINT_ENOMEM, "material map: out of memory for %zu samples",
                             n);
    return 0;
}

static void fit_state_free(fit_state *fs)
{
    free(fs->r);
    free(fs->fk);
    free(fs->c);
    free(fs->scratch);
    free(fs->uvv);
    free(fs->cv);
    free(fs->hits);
    free(fs->shits);
    free(fs->F);
}

/* Equation 18: per sample, the largest scale of the product's prediction
 * fk that keeps each channel of the residual >= 0 (OUT: fs->c). */
static void min_scales(fit_state *fs)
{
    const float *r = fs->r, *fk = fs->fk;
    for (size_t i = 0; i < fs->n; i++) {
        double ci = 1.0;
        for (int ch = 0; ch < 3; ch++) {
            double f = fk[3 * i + ch];
            if (!isfinite(f)) {
                ci = 0.0;
                break;
            }
            if (f > 0.0 && r[3 * i + ch] < ci * f)
                ci = r[3 * i + ch] / f;
        }
        fs->c[i] = (float)(ci > 0.0 ? ci : 0.0);
    }
}

/* The residual less the product's prediction fk scaled by its texture,
 * clamped at 0; returns the samples where some channel went below. */
static long subtract_product(fit_state *fs, const float *tex)
{
    const samples *s = fs->s;
    const float *fk = fs->fk;
    float *r = fs->r;
    long clamped = 0;
    for (size_t i = 0; i < fs->n; i++) {
        double ct = uvtex_lookup(tex, fs->mp->res, s->uv[2 * i], s->uv[2 * i + 1]);
        int neg = 0;
        for (int ch = 0; ch < 3; ch++) {
            double f = fk[3 * i + ch], x = r[3 * i + ch] - (isfinite(f) ? ct * f : 0.0);
            neg |= x < 0.0;
            r[3 * i + ch] = (float)(x > 0.0 ? x : 0.0);
        }
        clamped += neg;
    }
    return clamped;
}

/* Product k of the greedy stage: a material fitted to the residual, its
 * predictions (kept in F), its coefficient texture by the merge rule, and
 * the residual without it. */
static int greedy_product(fit_state *fs, int k, matmap *out, glint_err *err)
{
    const matmap_params *mp = fs->mp;
    float *tex = out->coef + (size_t)k * fs->nt;
    int rc;
    if ((rc = fs->src->fit(fs->src->cls, fs->r, &out->comp[k], err)))
        return rc;
    out->k = k + 1;
    if ((rc = fs->src->predict(fs->src->cls, &out->comp[k], fs->fk, err)))
        return rc;
    if (fs->F)
        memcpy(fs->F + (size_t)k * fs->n3, fs->fk, fs->n3 * sizeof *fs->F);
    if (mp->merge == MATMAP_MERGE_MIN)
        min_scales(fs);
    if ((rc = mp->merge == MATMAP_MERGE_LSQ
                  ? coef_lsq(fs->s, fs->r, fs->fk, mp->res, tex, fs->scratch, fs->hits, fs->uvv,
                             err)
                  : coef_texture(fs->s, fs->c, mp->res, tex, fs->scratch, fs->hits, fs->shits,
                                 fs->uvv, fs->cv, err)))
        return rc;
    out->clamped[k] += subtract_product(fs, tex);
    return 0;
}

/* The greedy stage: products one at a time on the residual, until the
 * count, the tolerance, or a product that lowers the relative RMS by
 * under 0.1% (OUT: out->stop, rel_rms). */
static int greedy(fit_state *fs, matmap *out, glint_err *err)
{
    const matmap_params *mp = fs->mp;
    int rc;
    memcpy(fs->r, fs->rgb, fs->n3 * sizeof *fs->r);
    out->rel_rms[0] = rel_rms(fs->r, fs->rgb, fs->n3);
    out->stop = "components";
    for (int k = 0; k < mp->components; k++) {
        double now;
        if (k > 0 && out->rel_rms[k] <= mp->tol) { /* one product at least: a material */
            out->stop = "tolerance";
            break;
        }
        if ((rc = greedy_product(fs, k, out, err)))
            return rc;
        now = rel_rms(fs->r, fs->rgb, fs->n3);
        out->rel_rms[k + 1] = now;
        if (now <= mp->tol) {
            out->stop = "tolerance";
            break;
        }
        if (!(now < out->rel_rms[k] * (1.0 - 1e-3))) {
            out->stop = "no-gain";
            break;
        }
    }
    return 0;
}

/* Back-fitting of product k: its material refitted, and the residual and
 * F[k] moved from the old one's predictions to the new one's. */
static int backfit_product(fit_state *fs, int k, matmap *out, glint_err *err)
{
    const samples *s = fs->s;
    size_t n3 = fs->n3;
    float *Fk = fs->F + (size_t)k * n3, *fk = fs->fk, *r = fs->r, *c = fs->c;
    const float *tex = out->coef + (size_t)k * fs->nt;
    material m;
    int rc;
    /* product k's target: what the others leave, per unit of its
     * coefficient where that is large enough to say; elsewhere
     * its own prediction, which does not pull it */
    for (size_t i = 0; i < fs->n; i++) {
        double ct = uvtex_lookup(tex, fs->mp->res, s->uv[2 * i], s->uv[2 * i + 1]);
        c[i] = (float)ct;
        for (int ch = 0; ch < 3; ch++) {
            double f = isfinite(Fk[3 * i + ch]) ? Fk[3 * i + ch] : 0.0, t;
            t = ct >= MATMAP_BACKFIT_MIN_COEF ? (r[3 * i + ch] + ct * f) / ct : f;
            fk[3 * i + ch] = (float)(t > 0.0 ? t : 0.0);
        }
    }
    if ((rc = fs->src->fit(fs->src->cls, fk, &m, err)))
        return rc;
    material_free(&out->comp[k]);
    out->comp[k] = m;
    if ((rc = fs->src->predict(fs->src->cls, &out->comp[k], fk, err)))
        return rc;
    /* the residual without the old product k, with the new one */
    for (size_t i = 0; i < n3; i++) {
        double fo = isfinite(Fk[i]) ? Fk[i] : 0.0, fn = isfinite(fk[i]) ? fk[i] : 0.0;
        r[i] = (float)(r[i] + c[i / 3] * (fo - fn));
        Fk[i] = fk[i];
    }
    return 0;
}

/* The joint refinement of the textures, then back-fitting rounds (every
 * product refitted, a short refinement after) while a round lowers the
 * model's relative RMS by MATMAP_ROUND_MIN_GAIN.  r: the model's residual
 * (updated). */
static int refine_rounds(fit_state *fs, matmap *out, glint_err *err)
{
    const matmap_params *mp = fs->mp;
    int rc;
    if ((rc = refine_joint(fs->s, fs->rgb, fs->F, out->k, mp->res, mp->refine, mp->smooth,
                           out->coef, fs->r, &out->refine_sweeps, err)))
        return rc;
    out->round_rel_rms[0] = rel_rms(fs->r, fs->rgb, fs->n3);
    for (int round = 0; round < mp->rounds; round++) {
        int sweeps;
        for (int k = 0; k < out->k; k++)
            if ((rc = backfit_product(fs, k, out, err)))
                return rc;
        if ((rc = refine_joint(fs->s, fs->rgb, fs->F, out->k, mp->res,
                               mp->refine < MATMAP_ROUND_SWEEPS ? mp->refine
                                                                : MATMAP_ROUND_SWEEPS,
                               mp->smooth, out->coef, fs->r, &sweeps, err)))
            return rc;
        out->refine_sweeps += sweeps;
        out->rounds = round + 1;
        out->round_rel_rms[round + 1] = rel_rms(fs->r, fs->rgb, fs->n3);
        if (!(out->round_rel_rms[round + 1] <
              out->round_rel_rms[round] * (1.0 - MATMAP_ROUND_MIN_GAIN)))
            break;
    }
    out->model_rel_rms[1] = rel_rms(fs->r, fs->rgb, fs->n3);
    out->refine = "done";
    return 0;
}

int matmap_fit_source(const matmap_source *src, const float *rgb, const matmap_params *mp,
                      matmap *out, glint_err *err)
{
    fit_state fs;
    double t0 = glint_now();
    int rc;

    memset(out, 0, sizeof *out);
    if ((rc = fit_input_check(src->s, rgb, mp, err)))
        return rc;
    memset(&fs, 0, sizeof fs);
    fs.src = src;
    fs.s = src->s;
    fs.rgb = rgb;
    fs.mp = mp;
    fs.n = (size_t)src->s->n;
    fs.n3 = 3 * fs.n;
    fs.nt = (size_t)mp->res * mp->res;
    out->res = mp->res;
    if (!(rc = fit_alloc(&fs, out, err)) && !(rc = greedy(&fs, out, err))) {
        if (fs.F)
            out->model_rel_rms[0] = out->model_rel_rms[1] =
                model_residual(fs.s, rgb, fs.F, out->k, out->coef, mp->res, fs.r);
        else /* without the predictions kept the model's residual is not measured */
            out->model_rel_rms[0] = out->model_rel_rms[1] = -1.0;
        if (fs.F && mp->refine > 0)
            rc = refine_rounds(&fs, out, err);
        if (!rc)
            out->seconds = glint_now() - t0;
    }
    fit_state_free(&fs);
    if (rc)
        matmap_free(out);
    return rc;
}
