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
        rc = envlit_gbuf(&g[v], m, l, shadows, envlit_brdf, b, scale, &out[v], err);
    return rc;
}
