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

int matmap_fit(const prep *p, const float *rgb, const matmap_params *mp, matmap *out,
               glint_err *err)
{
    const samples *s = prep_samples(p);
    size_t n = (size_t)s->n, n3 = 3 * n, nt;
    float *r = NULL, *fk = NULL, *c = NULL, *scratch = NULL, *uvv = NULL, *cv = NULL;
    int *hits = NULL, *shits = NULL;
    double t0 = glint_now();
    int rc = 0;

    memset(out, 0, sizeof *out);
    if (!mp || mp->components < 1 || mp->components > MATMAP_MAX || mp->res < 1 ||
        mp->res > UVTEX_MAX_RES || !(mp->tol >= 0.0) ||
        (mp->merge != MATMAP_MERGE_LSQ && mp->merge != MATMAP_MERGE_MIN))
        return glint_err_set(err, GLINT_EINVAL,
                             "material map: components 1..%d, res 1..%d, tol >= 0 and merge "
                             "lsq or min", MATMAP_MAX, UVTEX_MAX_RES);
    if (!s->has_pos || !s->uv)
        return glint_err_set(err, GLINT_EINVAL,
                             "material map: the samples carry no texture coordinates "
                             "(imported samples): paint a scene's views");
    for (size_t i = 0; i < n3; i++)
        if (!(rgb[i] >= 0.0f) || !isfinite(rgb[i]))
            return glint_err_set(err, GLINT_EINVAL,
                                 "material map: sample %zu has a negative or non-finite value",
                                 i / 3);
    nt = (size_t)mp->res * mp->res;
    out->res = mp->res;
    r = malloc(n3 * sizeof *r);
    fk = malloc(n3 * sizeof *fk);
    c = malloc(n * sizeof *c);
    scratch = malloc(2 * nt * sizeof *scratch);
    uvv = malloc(2 * n * sizeof *uvv);
    cv = malloc(n * sizeof *cv);
    hits = malloc(nt * sizeof *hits);
    shits = malloc(nt * sizeof *shits);
    out->coef = malloc((size_t)mp->components * nt * sizeof *out->coef);
    if (!r || !fk || !c || !scratch || !uvv || !cv || !hits || !shits || !out->coef) {
        rc = glint_err_set(err, GLINT_ENOMEM, "material map: out of memory for %zu samples", n);
        goto done;
    }
    memcpy(r, rgb, n3 * sizeof *r);
    out->rel_rms[0] = rel_rms(r, rgb, n3);
    out->stop = "components";
    for (int k = 0; k < mp->components; k++) {
        float *tex = out->coef + (size_t)k * nt;
        double now;
        if (out->rel_rms[k] <= mp->tol) {
            out->stop = "tolerance";
            break;
        }
        if ((rc = prep_fit(p, NULL, r, &out->comp[k], err)))
            goto done;
        out->k = k + 1;
        if ((rc = prep_predict(p, &out->comp[k], fk, err)))
            goto done;
        for (size_t i = 0; i < n3; i++) /* painted values: per unit light, as r */
            fk[i] = (float)(fk[i] / s->intensity[i / 3]);
        /* equation 18: the largest scale that keeps each channel >= 0 */
        for (size_t i = 0; i < n && mp->merge == MATMAP_MERGE_MIN; i++) {
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
            c[i] = (float)(ci > 0.0 ? ci : 0.0);
        }
        if ((rc = mp->merge == MATMAP_MERGE_LSQ
                      ? coef_lsq(s, r, fk, mp->res, tex, scratch, hits, uvv, err)
                      : coef_texture(s, c, mp->res, tex, scratch, hits, shits, uvv, cv, err)))
            goto done;
        for (size_t i = 0; i < n; i++) {
            double ct = uvtex_lookup(tex, mp->res, s->uv[2 * i], s->uv[2 * i + 1]);
            int neg = 0;
            for (int ch = 0; ch < 3; ch++) {
                double f = fk[3 * i + ch], x = r[3 * i + ch] - (isfinite(f) ? ct * f : 0.0);
                neg |= x < 0.0;
                r[3 * i + ch] = (float)(x > 0.0 ? x : 0.0);
            }
            out->clamped[k] += neg;
        }
        now = rel_rms(r, rgb, n3);
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
    out->seconds = glint_now() - t0;
done:
    free(r);
    free(fk);
    free(c);
    free(scratch);
    free(uvv);
    free(cv);
    free(hits);
    free(shits);
    if (rc)
        matmap_free(out);
    return rc;
}
