/* paint.c: paint views with an analytic BRDF (paint.h).
 *
 * A pixel's value is scale * I * f(wi, wo) * cos_i, evaluated in double
 * and stored as float.  With an automatic scale the views are evaluated
 * twice (once for the maximum, once to write), so every stored value is
 * the correctly rounded product rather than a rescaled float. */
#include "paint.h"

#include <math.h>
#include <string.h>

/* The BRDF is one brdf_eval can evaluate: a known kind, finite values. */
static int paint_check_brdf(const brdf *b, glint_err *err)
{
    if (b->kind < BRDF_LAMBERT || b->kind > BRDF_WARD)
        return glint_err_set(err, GLINT_EINVAL, "paint: unknown brdf kind %d", (int)b->kind);
    for (int c = 0; c < 3; c++)
        if (!isfinite(b->kd[c]) || !isfinite(b->ks[c]) || !isfinite(b->f0[c]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "paint: brdf has a non-finite kd, ks or f0");
    if (!isfinite(b->exponent) || !isfinite(b->roughness))
        return glint_err_set(err, GLINT_ENONFINITE,
                             "paint: brdf has a non-finite exponent or roughness");
    if ((b->kind == BRDF_PHONG || b->kind == BRDF_BLINN) && !(b->exponent > 0.0))
        return glint_err_set(err, GLINT_ERANGE, "paint: brdf exponent %g is not > 0",
                             b->exponent);
    if ((b->kind == BRDF_CT || b->kind == BRDF_WARD) && !(b->roughness > 0.0))
        return glint_err_set(err, GLINT_ERANGE, "paint: brdf roughness %g is not > 0",
                             b->roughness);
    return 0;
}

static int paint_check_view(const gbuf *g, const scene_view *v, int k, glint_err *err)
{
    if (g->width < 1 || g->height < 1 || !g->mask || !g->nrm || !g->wi || !g->wo)
        return glint_err_set(err, GLINT_EINVAL, "paint: view %d has an empty G-buffer", k);
    if (!isfinite(v->light_intensity) || !(v->light_intensity > 0.0))
        return glint_err_set(err, GLINT_EINVAL,
                             "paint: view %d light intensity %g is not finite and > 0", k,
                             v->light_intensity);
    return 0;
}

/* Unscaled radiance I f cos_i of one pixel (OUT: rgb[3]); zero unless
 * mask, cos_i > 0 and cos_o > 0.  GLINT_ENONFINITE for a covered pixel with
 * non-finite geometry or a non-finite result. */
static int paint_pixel(const brdf *b, const gbuf *g, double intensity, size_t p, int k,
                       double rgb[3], glint_err *err)
{
    double n[3], wi[3], wo[3], ci = 0.0, co = 0.0;

    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!g->mask[p])
        return 0;
    for (int c = 0; c < 3; c++) {
        n[c] = g->nrm[3 * p + c];
        wi[c] = g->wi[3 * p + c];
        wo[c] = g->wo[3 * p + c];
        ci += n[c] * wi[c];
        co += n[c] * wo[c];
    }
    if (!isfinite(ci) || !isfinite(co))
        return glint_err_set(err, GLINT_ENONFINITE,
                             "paint: view %d pixel (x %d, y %d) has non-finite normal or "
                             "directions",
                             k, (int)(p % (size_t)g->width), (int)(p / (size_t)g->width));
    if (!(ci > 0.0 && co > 0.0))
        return 0;
    brdf_eval(b, n, wi, wo, rgb);
    for (int c = 0; c < 3; c++) {
        rgb[c] *= intensity * ci;
        if (!isfinite(rgb[c]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "paint: view %d pixel (x %d, y %d) radiance is not finite",
                                 k, (int)(p % (size_t)g->width),
                                 (int)(p / (size_t)g->width));
    }
    return 0;
}

int paint_views(const brdf *b, const gbuf *g, const scene_view *views, int nviews,
                double scale, img *out, double *scale_out, glint_err *err)
{
    double rgb[3];
    int k, done = 0, rc;

    if (!b || !g || !views || !out)
        return glint_err_set(err, GLINT_EINVAL, "paint: NULL brdf, gbufs, views or output");
    if (nviews < 1 || nviews > SCENE_MAX_VIEWS)
        return glint_err_set(err, GLINT_ERANGE, "paint: %d views, supported 1..%d", nviews,
                             SCENE_MAX_VIEWS);
    if (!isfinite(scale))
        return glint_err_set(err, GLINT_ENONFINITE, "paint: scale %g is not finite", scale);
    rc = paint_check_brdf(b, err);
    if (rc)
        return rc;
    for (k = 0; k < nviews; k++) {
        rc = paint_check_view(&g[k], &views[k], k, err);
        if (rc)
            return rc;
    }

    if (scale <= 0.0) {
        double vmax = 0.0;
        for (k = 0; k < nviews; k++) {
            size_t np = (size_t)g[k].width * (size_t)g[k].height;
            for (size_t p = 0; p < np; p++) {
                rc = paint_pixel(b, &g[k], views[k].light_intensity, p, k, rgb, err);
                if (rc)
                    return rc;
                for (int c = 0; c < 3; c++)
                    if (rgb[c] > vmax)
                        vmax = rgb[c];
            }
        }
        /* Nothing lit: every value is 0 under any scale; report scale 1. */
        scale = vmax > 0.0 ? 1.0 / vmax : 1.0;
    }

    for (k = 0; k < nviews; k++) {
        const gbuf *gk = &g[k];
        size_t np = (size_t)gk->width * (size_t)gk->height;

        rc = img_alloc(&out[k], gk->width, gk->height, 3, err);
        if (rc)
            goto fail_views;
        done = k + 1;
        for (size_t p = 0; p < np; p++) {
            rc = paint_pixel(b, gk, views[k].light_intensity, p, k, rgb, err);
            if (rc)
                goto fail_views;
            for (int c = 0; c < 3; c++) {
                float v = (float)(scale * rgb[c]);
                if (!isfinite(v)) {
                    rc = glint_err_set(err, GLINT_ERANGE,
                                       "paint: view %d pixel (x %d, y %d): scale %g * "
                                       "radiance %g overflows a float",
                                       k, (int)(p % (size_t)gk->width),
                                       (int)(p / (size_t)gk->width), scale, rgb[c]);
                    goto fail_views;
                }
                out[k].px[3 * p + c] = v;
            }
        }
    }
    if (scale_out)
        *scale_out = scale;
    return 0;

fail_views:
    for (k = 0; k < done; k++)
        img_free(&out[k]);
    return rc;
}
