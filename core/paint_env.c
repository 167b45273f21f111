/* paint_env.c: truths painted under an environment (paint.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "env.h"
#include "mesh.h"
#include "paint.h"
#include "vis.h"

int paint_views_env(const brdf *b, const gbuf *g, int nviews, const mesh *m,
                    const env_lights *l, int shadows, double scale, img *out, glint_err *err)
{
    vis_scene *vs = NULL;
    int rc = 0, words = VIS_WORDS(l->k);

    if (!(scale > 0.0) || !isfinite(scale))
        return glint_err_set(err, GLINT_EINVAL, "scale %g must be a positive number", scale);
    if (shadows && (rc = vis_open(m, &vs, err)))
        return rc;
    for (int v = 0; v < nviews && !rc; v++) {
        const gbuf *gb = &g[v];
        size_t np = (size_t)gb->width * gb->height, n = 0;
        int *pix = malloc((np ? np : 1) * sizeof *pix);
        uint64_t *bits = NULL;
        float *pos = NULL, *nrm = NULL;
        if (!pix || (rc = img_alloc(&out[v], gb->width, gb->height, 3, err))) {
            free(pix);
            rc = rc ? rc : glint_err_set(err, GLINT_ENOMEM, "out of memory");
            break;
        }
        for (size_t p = 0; p < np; p++)
            if (gb->mask[p])
                pix[n++] = (int)p;
        if (vs && n) {
            pos = malloc(3 * n * sizeof *pos);
            nrm = malloc(3 * n * sizeof *nrm);
            bits = malloc(n * words * sizeof *bits);
            if (!pos || !nrm || !bits)
                rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for shadow rays");
            for (size_t i = 0; i < n && !rc; i++) {
                memcpy(pos + 3 * i, gb->pos + 3 * (size_t)pix[i], 3 * sizeof *pos);
                memcpy(nrm + 3 * i, gb->nrm + 3 * (size_t)pix[i], 3 * sizeof *nrm);
            }
            if (!rc)
                rc = vis_compute(vs, (int)n, pos, nrm, l->k, l->dir, bits, 0, NULL, err);
        }
        for (size_t i = 0; i < n && !rc; i++) {
            size_t p = (size_t)pix[i];
            double nn[3], wo[3], acc[3] = {0, 0, 0};
            for (int e = 0; e < 3; e++) {
                nn[e] = gb->nrm[3 * p + e];
                wo[e] = gb->wo[3 * p + e];
            }
            for (int k = 0; k < l->k; k++) {
                const double *d = l->dir + 3 * k;
                double c = nn[0] * d[0] + nn[1] * d[1] + nn[2] * d[2], f[3];
                if (c <= 0.0 || (bits && !((bits[i * words + (k >> 6)] >> (k & 63)) & 1)))
                    continue;
                brdf_eval(b, nn, d, wo, f);
                for (int ch = 0; ch < 3; ch++)
                    acc[ch] += l->power[3 * k + ch] * f[ch] * c;
            }
            for (int ch = 0; ch < 3; ch++)
                out[v].px[3 * p + ch] = (float)(scale * acc[ch]);
        }
        free(pix);
        free(pos);
        free(nrm);
        free(bits);
    }
    vis_close(vs);
    return rc;
}
