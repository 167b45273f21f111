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

int uvtex_splat(const float *uv, const float *val, int n, int ch, int res, float *tex, int *hits,
                glint_err *err)
{
    size_t nt = (size_t)res * (size_t)res;
    double *sum;

    if (n < 1 || !uv || !val || !tex || !hits)
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
    if (!(sum = calloc(nt * (size_t)ch, sizeof *sum)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d texture", res, res);
    memset(hits, 0, nt * sizeof *hits);
    for (int s = 0; s < n; s++) {
        size_t t = (size_t)texel_of(uv[2 * (size_t)s + 1], res) * res +
                   (size_t)texel_of(uv[2 * (size_t)s], res);
        for (int c = 0; c < ch; c++)
            sum[t * ch + c] += val[(size_t)s * ch + c];
        hits[t]++;
    }
    for (size_t t = 0; t < nt; t++)
        for (int c = 0; c < ch; c++)
            tex[t * ch + c] = hits[t] ? (float)(sum[t * ch + c] / hits[t]) : 0.0f;
    free(sum);
    return 0;
}

int uvtex_fill(float *tex, const int *hits, int res, int ch, uvtex_report *rep, glint_err *err)
{
    size_t nt = (size_t)res * (size_t)res;
    img im = {0};
    uvtex_report r = {0, 0, 0};
    int rc;

    if (rep)
        memset(rep, 0, sizeof *rep);
    if (ch < 1 || ch > 3 || res < 1 || res > UVTEX_MAX_RES || !tex || !hits)
        return glint_err_set(err, GLINT_EINVAL, "fill: %d channels at %d^2", ch, res);
    for (size_t t = 0; t < nt; t++) {
        if (hits[t]) {
            r.texels_reached++;
            r.most_per_texel = hits[t] > r.most_per_texel ? hits[t] : r.most_per_texel;
        } else {
            r.texels_filled++;
        }
    }
    if (!r.texels_reached)
        return glint_err_set(err, GLINT_EINVAL, "fill: no texel is reached");
    if (r.texels_filled) {
        if ((rc = img_alloc(&im, res, res, ch + 1, err)))
            return rc;
        for (size_t t = 0; t < nt; t++) {
            float *px = im.px + t * (size_t)(ch + 1);
            if (!hits[t])
                continue; /* zero value and coverage: a hole */
            for (int c = 0; c < ch; c++)
                px[c] = tex[t * ch + c];
            px[ch] = 1.0f;
        }
        if ((rc = img_fill_holes(&im, err))) {
            img_free(&im);
            return rc;
        }
        for (size_t t = 0; t < nt; t++)
            if (!hits[t])
                for (int c = 0; c < ch; c++)
                    tex[t * ch + c] = im.px[t * (size_t)(ch + 1) + c];
        img_free(&im);
    }
    if (rep)
        *rep = r;
    return 0;
}

int uvtex_from_samples(const float *uv, const float *val, int n, int ch, int res, float *tex,
                       int *hits, uvtex_report *rep, glint_err *err)
{
    int *cnt = hits, rc;
    if (rep)
        memset(rep, 0, sizeof *rep);
    if (res < 1 || res > UVTEX_MAX_RES)
        return glint_err_set(err, GLINT_ERANGE, "texture resolution %d outside 1..%d", res,
                             UVTEX_MAX_RES);
    if (!cnt &&
        !(cnt = malloc((size_t)res * res * sizeof *cnt)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d texture", res, res);
    rc = uvtex_splat(uv, val, n, ch, res, tex, cnt, err);
    if (!rc)
        rc = uvtex_fill(tex, cnt, res, ch, rep, err);
    if (cnt != hits)
        free(cnt);
    return rc;
}

void uvtex_merge_min(float *dst, int *dst_hits, const float *src, const int *src_hits,
                     size_t texels, int ch)
{
    for (size_t t = 0; t < texels; t++) {
        if (!src_hits[t])
            continue;
        for (int c = 0; c < ch; c++) {
            float *d = dst + t * ch + c, v = src[t * ch + c];
            *d = dst_hits[t] && *d < v ? *d : v;
        }
        dst_hits[t] += src_hits[t];
    }
}

double uvtex_lookup(const float *t, int res, double u, double v)
{
    double x;
    uvtex_bilinear(t, res, 1, u * res - 0.5, v * res - 0.5, &x);
    return x;
}
