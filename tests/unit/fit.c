/* fit.c: the direct path of the hf3 method, paintings -> material in one call
 * (fit.h), for the tests and the benchmarks; the same stages as the
 * method's levels (method_hf3.c). */
#include "fit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_hf3.h"
#include "pcache.h"

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
    const fit_params *p = &fp->params;
    double t0;
    int rc;

    pcache_key_hf(fp->s.hash, p->res, p->lambda, p->route, p->rcond, fp->cache_key);
    if (cache_dir) {
        /* the disk layer alone (no memory cache): prep.h is the cached path */
        t0 = glint_now();
        if ((rc = hf_design_build(&fp->s, p->res, &fp->d, err)))
            return rc;
        fp->t_design = glint_now() - t0;
        t0 = glint_now();
        rc = pcache_decomp_get(cache_dir, &fp->d, fp->s.hash, p->lambda, p->route, p->rcond,
                               &fp->dc, &fp->cache_hit, err);
        if (rc)
            return rc;
        fp->t_decomp = glint_now() - t0;
    } else {
        hf3_decomp x;
        if ((rc = hf3_decomp_make(p, &fp->s, NULL, NULL, &x, err)))
            return rc;
        fp->d = x.d;
        fp->dc = x.dc;
        fp->t_design = x.t_design;
        fp->t_decomp = x.t_decomp;
    }
    t0 = glint_now();
    rc = hf_op_build(&fp->dc, &p->reg, p->prec, &fp->op, err);
    fp->t_op = glint_now() - t0;
    return rc;
}

int fit_prepare(fit_prep *fp, const scene *sc, const gbuf *g, const unsigned char *use,
                const fit_params *p, const char *cache_dir, glint_err *err)
{
    char hash[33];
    double t0 = glint_now();
    int rc;

    memset(fp, 0, sizeof *fp);
    fp->params = *p;
    scene_hash(sc, hash);
    rc = samples_build(g, sc->views, sc->nviews, use, hash, &fp->s, err);
    if (rc)
        return rc;
    fp->t_samples = glint_now() - t0;
    rc = prepare_rest(fp, cache_dir, err);
    if (rc)
        fit_prep_free(fp);
    return rc;
}

int fit_run(const fit_prep *fp, const img *paintings, const float *rgb_in, material *out,
            glint_err *err)
{
    float *rgb = NULL;
    hf3_prepared pp;
    double t0 = glint_now();
    int rc;

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
    memset(&pp, 0, sizeof pp);
    pp.params = &fp->params;
    pp.s = &fp->s;
    pp.d = &fp->d;
    pp.dc = &fp->dc;
    pp.op = &fp->op;
    pp.cache_key = fp->cache_key;
    pp.cache_hit = fp->cache_hit;
    pp.t_samples = fp->t_samples;
    pp.t_design = fp->t_design;
    pp.t_decomp = fp->t_decomp;
    pp.t_op = fp->t_op;
    rc = hf3_fit_material(&pp, rgb_in ? rgb_in : rgb, t0, out, err);
    free(rgb);
    return rc;
}

int fit_error_views(const material *m, const gbuf *g, const scene_view *views, int nviews,
                    const img *truth, double *rms, double *max_abs, long *count,
                    glint_err *err)
{
    return material_error_views(m, g, views, nviews, truth, rms, max_abs, count, err);
}
