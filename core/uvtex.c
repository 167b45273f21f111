/* uvtex.c: textures over texture coordinates from samples (uvtex.h). */
#include "uvtex.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "img.h"

static int texel_of(float t, int res)
{
    int i = (int)(t * (float)res);
    return i < res ? i : res - 1;
}

int uvtex_from_samples(const float *uv, const float *val, int n, int ch, int res, float *tex,
                       int *hits, uvtex_report *rep, glint_err *err)
{
    size_t nt = (size_t)res * (size_t)res;
    double *sum = NULL;
    int *cnt = NULL, rc = 0;
    img im = {0};
    uvtex_report r = {0, 0, 0};

    if (rep)
        memset(rep, 0, sizeof *rep);
    if (n < 1 || !uv || !val || !tex)
        return glint_err_set(err, GLINT_EINVAL, "a texture needs at least one sample");
    if (ch < 1 || ch > 3)
        return glint_err_set(err, GLINT_EINVAL, "%d channels: 1 to 3", ch);
    if (res < 1 || res > UVTEX_MAX_RES)
        return glint_err_set(err, GLINT_ERANGE, "texture resolution %d outside 1..%d", res,
                             UVTEX_MAX_RES);
    for (int s = 0; s < n; s++) {
        float u = uv[2 * (size_t)s], v = uv[2 * (size_t)s + 1];
        if (!(u >= 0.0f && u <= 1.0f && v >= 0.0f && v <= 1.0f))
            return glint_err_set(err, GLINT_EINVAL,
                                 "sample %d: texture coordinates (%g, %g) outside [0,1]", s,
                                 (double)u, (double)v);
        for (int c = 0; c < ch; c++)
            if (!isfinite(val[(size_t)s * ch + c]))
                return glint_err_set(err, GLINT_EINVAL, "sample %d: value %d is not finite", s,
                                     c);
    }
    sum = calloc(nt * (size_t)ch, sizeof *sum);
    cnt = hits ? hits : malloc(nt * sizeof *cnt);
    if (!sum || !cnt) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d texture", res, res);
        goto done;
    }
    memset(cnt, 0, nt * sizeof *cnt);
    for (int s = 0; s < n; s++) {
        size_t t = (size_t)texel_of(uv[2 * (size_t)s + 1], res) * res +
                   (size_t)texel_of(uv[2 * (size_t)s], res);
        for (int c = 0; c < ch; c++)
            sum[t * ch + c] += val[(size_t)s * ch + c];
        cnt[t]++;
    }
    if ((rc = img_alloc(&im, res, res, ch + 1, err)))
        goto done;
    for (size_t t = 0; t < nt; t++) {
        float *px = im.px + t * (size_t)(ch + 1);
        if (!cnt[t]) {
            r.texels_filled++;
            continue; /* zero value and coverage: a hole */
        }
        r.texels_reached++;
        r.most_per_texel = cnt[t] > r.most_per_texel ? cnt[t] : r.most_per_texel;
        for (int c = 0; c < ch; c++)
            px[c] = (float)(sum[t * ch + c] / cnt[t]);
        px[ch] = 1.0f;
    }
    if (r.texels_filled && (rc = img_fill_holes(&im, err)))
        goto done;
    for (size_t t = 0; t < nt; t++)
        for (int c = 0; c < ch; c++)
            tex[t * ch + c] = im.px[t * (size_t)(ch + 1) + c];
    if (rep)
        *rep = r;
done:
    img_free(&im);
    free(sum);
    if (cnt != hits)
        free(cnt);
    return rc;
}

void uvtex_merge_min(float *dst, const float *src, size_t len)
{
    for (size_t k = 0; k < len; k++)
        dst[k] = src[k] < dst[k] ? src[k] : dst[k];
}
