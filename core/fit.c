/* fit.c: paintings -> material, with the precomputation cached. */
#include "fit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hf_int.h"
#include "pcache.h"

void fit_params_default(fit_params *p)
{
    memset(p, 0, sizeof *p);
    p->res = 128;
    p->lambda = 0.1;
    p->reg.kind = HF_REG_TRUNC;
    hf_map_default(&p->map, HF_MAP_ADD);
    p->model = HF_MODEL_RADIANCE;
    p->prec = HF_F64;
    p->route = HF_ROUTE_EIG;
    p->rcond = 0.0;
}

json_t *fit_params_to_json(const fit_params *p)
{
    char reg[64], map[96];
    hf_reg_format(&p->reg, reg, sizeof reg);
    hf_map_format(&p->map, map, sizeof map);
    return json_pack("{s:i, s:f, s:s, s:s, s:s, s:s, s:s, s:f}", "res", p->res, "lambda",
                     p->lambda, "regularization", reg, "mapping", map, "model",
                     p->model == HF_MODEL_BRDF ? "brdf" : "radiance", "precision",
                     p->prec == HF_F32 ? "single" : "double", "route",
                     p->route == HF_ROUTE_SVD ? "svd" : "eig", "rcond",
                     p->rcond > 0.0 ? p->rcond : hf_rcond_default(p->route));
}

void fit_prep_free(fit_prep *fp)
{
    if (!fp)
        return;
    samples_free(&fp->s);
    hf_design_free(&fp->d);
    hf_decomp_free(&fp->dc);
    hf_op_free(&fp->op);
    memset(fp, 0, sizeof *fp);
}

static int prepare_rest(fit_prep *fp, const char *cache_dir, glint_err *err)
{
    double t0 = hf_now();
    int rc = hf_design_build(&fp->s, fp->params.res, &fp->d, err);
    if (rc)
        return rc;
    fp->t_design = hf_now() - t0;
    t0 = hf_now();
    pcache_key_hf(fp->s.hash, fp->params.res, fp->params.lambda, fp->params.route,
                  fp->params.rcond, fp->cache_key);
    rc = pcache_decomp_get(cache_dir, &fp->d, fp->s.hash, fp->params.lambda, fp->params.route,
                           fp->params.rcond, &fp->dc, &fp->cache_hit, err);
    if (rc)
        return rc;
    fp->t_decomp = hf_now() - t0;
    t0 = hf_now();
    rc = hf_op_build(&fp->dc, &fp->params.reg, fp->params.prec, &fp->op, err);
    fp->t_op = hf_now() - t0;
    return rc;
}

int fit_prepare(fit_prep *fp, const scene *sc, const gbuf *g, const unsigned char *use,
                const fit_params *p, const char *cache_dir, glint_err *err)
{
    char hash[33];
    double t0 = hf_now();
    int rc;

    memset(fp, 0, sizeof *fp);
    fp->params = *p;
    scene_hash(sc, hash);
    rc = samples_build(g, sc->views, sc->nviews, use, hash, &fp->s, err);
    if (rc)
        return rc;
    fp->t_samples = hf_now() - t0;
    rc = prepare_rest(fp, cache_dir, err);
    if (rc)
        fit_prep_free(fp);
    return rc;
}

int fit_prepare_samples(fit_prep *fp, samples *s, const fit_params *p, const char *cache_dir,
                        glint_err *err)
{
    int rc;
    memset(fp, 0, sizeof *fp);
    fp->params = *p;
    fp->s = *s;
    memset(s, 0, sizeof *s);
    rc = prepare_rest(fp, cache_dir, err);
    if (rc)
        fit_prep_free(fp);
    return rc;
}

int fit_run(const fit_prep *fp, const img *paintings, const float *rgb_in, material *out,
            glint_err *err)
{
    float *rgb = NULL;
    hf_factors fac;
    hf_fit_stats st;
    json_t *info, *pre, *tim, *errs;
    double t0 = hf_now();
    int rc;
    char key[33];

    memset(out, 0, sizeof *out);
    if (!rgb_in) {
        rgb = malloc((size_t)3 * fp->s.n * sizeof *rgb);
        if (!rgb)
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d samples", fp->s.n);
        rc = samples_gather(&fp->s, paintings, rgb, err);
        if (rc) {
            free(rgb);
            return rc;
        }
    }
    rc = hf_fit(&fp->d, &fp->op, &fp->params.map, fp->params.model, rgb_in ? rgb_in : rgb,
                &fac, &st, err);
    free(rgb);
    if (rc)
        return rc;
    memcpy(key, fp->cache_key, sizeof key);
    pre = json_pack("{s:s, s:s, s:i, s:i, s:i, s:i, s:i, s:f, s:f, s:f, s:f, s:i, s:I}",
                    "pattern_hash", fp->s.hash, "cache_key", key, "cache_hit", fp->cache_hit,
                    "samples", fp->s.n, "unknowns", fp->dc.n, "numerical_rank", fp->dc.rank,
                    "gauge_dims", fp->dc.gauge_dims, "rcond", fp->dc.rcond, "s_max",
                    fp->dc.s[0], "s_first_used", fp->op.s_first, "s_last_used",
                    fp->op.s_last, "rank_kept", fp->op.k, "operator_bytes",
                    (json_int_t)hf_op_bytes(&fp->op, &fp->d));
    json_object_set_new(pre, "condition_used", json_real(fp->op.s_first / fp->op.s_last));
    tim = json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f}", "samples", fp->t_samples,
                    "design", fp->t_design, "decomposition", fp->t_decomp, "operator",
                    fp->t_op, "map", st.map_seconds, "apply", st.apply_seconds,
                    "factorization", st.total_seconds, "diagnostics", st.diag_seconds,
                    "fit", hf_now() - t0);
    errs = json_pack("{s:f, s:f, s:f, s:[i,i,i]}", "rms_painted", st.rms, "max_abs_painted",
                     st.max_abs, "log_residual_rms", st.log_residual, "clamped", st.clamped[0],
                     st.clamped[1], st.clamped[2]);
    info = json_pack("{s:o, s:o, s:o, s:o}", "params", fit_params_to_json(&fp->params),
                     "precomputation", pre, "seconds", tim, "errors", errs);
    material_init(out, &fac, info);
    return 0;
}

int fit_error_views(const material *m, const gbuf *g, const scene_view *views, int nviews,
                    const img *truth, double *rms, double *max_abs, long *count,
                    glint_err *err)
{
    double ss = 0.0, mx = 0.0;
    long cnt = 0;

    for (int v = 0; v < nviews; v++) {
        const gbuf *gb = &g[v];
        const img *t = &truth[v];
        size_t np = (size_t)gb->width * gb->height;
        double I = views ? views[v].light_intensity : 1.0;
        if (!t->px || t->width != gb->width || t->height != gb->height || t->channels < 1 ||
            t->channels == 2 || t->channels > 4)
            return glint_err_set(err, GLINT_EINVAL, "reference image %d does not match its view",
                                 v);
        for (size_t p = 0; p < np; p++) {
            double n[3], wi[3], wo[3], rgb[3], ci, co;
            if (!gb->mask[p])
                continue;
            for (int c = 0; c < 3; c++) {
                n[c] = gb->nrm[3 * p + c];
                wi[c] = gb->wi[3 * p + c];
                wo[c] = gb->wo[3 * p + c];
            }
            ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
            co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
            if (!(ci > 0.0 && co > 0.0))
                continue;
            hf_factors_eval(&m->fac, n, wi, wo, rgb);
            for (int c = 0; c < 3; c++) {
                double ref = t->px[p * t->channels + (t->channels == 1 ? 0 : c)];
                double d = rgb[c] * I - ref;
                ss += d * d;
                if (fabs(d) > mx)
                    mx = fabs(d);
            }
            cnt++;
        }
    }
    if (rms)
        *rms = cnt ? sqrt(ss / (3.0 * cnt)) : 0.0;
    if (max_abs)
        *max_abs = mx;
    if (count)
        *count = cnt;
    return 0;
}
