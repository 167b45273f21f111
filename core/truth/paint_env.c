/* paint_env.c: truths painted under an environment (paint.h), shaded by
 * envlit_gbuf (envlit.h). */
#include <math.h>
#include <string.h>

#include "envlit.h"
#include "paint.h"

int paint_views_env(const brdf *b, const gbuf *g, int nviews, const mesh *m,
                    const env_lights *l, int shadows, double scale, img *out, glint_err *err)
{
    int rc = 0;
    if (!(scale > 0.0) || !isfinite(scale))
        return glint_err_set(err, GLINT_EINVAL, "scale %g must be a positive number", scale);
    for (int v = 0; v < nviews; v++)
        memset(&out[v], 0, sizeof out[v]);
    for (int v = 0; v < nviews && !rc; v++)
        rc = envlit_gbuf_summed(&g[v], m, l, shadows, brdf_envlit_sum, b, scale, &out[v], NULL,
                                err);
    return rc;
}

typedef struct fn_ctx {
    paint_fn fn;
    const void *ctx;
} fn_ctx;

/* envlit_fn from a paint_fn: f cos(n.wi) */
static void fn_cos(const void *ctx, const double uv[2], const double n[3], const double wi[3],
                   const double wo[3], double rgb[3])
{
    const fn_ctx *x = ctx;
    double c = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    (void)uv;
    x->fn(x->ctx, n, wi, wo, rgb);
    for (int e = 0; e < 3; e++)
        rgb[e] *= c > 0.0 ? c : 0.0;
}

int paint_views_env_fn(paint_fn fn, const void *ctx, const gbuf *g, int nviews,
                       const mesh *m, const env_lights *l, int shadows, double scale,
                       img *out, glint_err *err)
{
    fn_ctx x = {fn, ctx};
    int rc = 0;
    if (!fn)
        return glint_err_set(err, GLINT_EINVAL, "paint: NULL truth function");
    if (!(scale > 0.0) || !isfinite(scale))
        return glint_err_set(err, GLINT_EINVAL, "scale %g must be a positive number", scale);
    for (int v = 0; v < nviews; v++)
        memset(&out[v], 0, sizeof out[v]);
    for (int v = 0; v < nviews && !rc; v++)
        rc = envlit_gbuf(&g[v], m, l, shadows, fn_cos, &x, scale, &out[v], NULL, err);
    return rc;
}
