/* uvtex.h: textures over the surface's texture coordinates, made from
 * samples (seed 000, section 4.1 and Figure 3): the coefficient textures of
 * material maps and the spatial factor of the four-factor product.
 *
 * Conventions: a res x res texture, row-major, `ch` interleaved channels.
 * Texel (i, j), column i and row j, covers u in [i/res, (i+1)/res) and v in
 * [j/res, (j+1)/res); u = 1 and v = 1 fall in the last column and row.
 * Row 0 is v = 0, as the first row of an OpenGL texture is t = 0.
 *
 * Samples fall sparsely on the texture when it is finer than the sampling
 * (a 128^2 map from a few thousand pixels): each texel that samples reach
 * holds the mean of their values, and the texels between them are filled
 * from their reached neighbours at every scale by push-pull (OpenImageIO's
 * fillholes_pushpull, through img_fill_holes).  Seed 000 fills them by
 * rasterizing the samples in a p-buffer; push-pull also fills the texels
 * outside the atlas's charts, so bilinear filtering at a chart's border
 * reads no unset texel.  A filled texel is a convex blend of reached ones:
 * it lies between their smallest and largest values.
 *
 * Thread-safety: no global state; concurrent calls on distinct outputs. */
#ifndef GLINT_UVTEX_H
#define GLINT_UVTEX_H

#include <stddef.h>

#include "err.h"

#define UVTEX_MAX_RES 4096

typedef struct uvtex_report {
    int texels_reached;  /* texels holding the mean of their samples */
    int texels_filled;   /* texels no sample reaches, filled from neighbours */
    int most_per_texel;  /* the most samples in one texel */
} uvtex_report;

/* The texture of n samples' values (val: n x ch floats, ch 1..3) at their
 * texture coordinates (uv: 2n floats in [0,1]).  OUT: tex (res x res x ch
 * floats), hits (res x res sample counts; may be NULL), *rep (may be NULL).
 * GLINT_EINVAL: n < 1, ch outside 1..3, a uv outside [0,1] or not finite, a
 * value not finite (each naming the sample); GLINT_ERANGE: res outside
 * 1..UVTEX_MAX_RES; GLINT_ENOMEM. */
int uvtex_from_samples(const float *uv, const float *val, int n, int ch, int res, float *tex,
                       int *hits, uvtex_report *rep, glint_err *err);

/* Bilinear lookup of an n x n texture of ch interleaved channels at texel
 * coordinates (x, y) (texel centres at integers, clamped to the border):
 * out[ch].  uvtex_lookup reads it at texture coordinates (u, v). */
static inline void uvtex_bilinear(const float *t, int n, int ch, double x, double y, double *out)
{
    double fx, fy;
    int i0, j0, i1, j1;
    x = x < 0.0 ? 0.0 : x > n - 1 ? n - 1 : x;
    y = y < 0.0 ? 0.0 : y > n - 1 ? n - 1 : y;
    i0 = (int)x;
    j0 = (int)y;
    i1 = i0 + 1 < n ? i0 + 1 : i0;
    j1 = j0 + 1 < n ? j0 + 1 : j0;
    fx = x - i0;
    fy = y - j0;
    for (int e = 0; e < ch; e++) {
        double a = t[ch * ((size_t)j0 * n + i0) + e], b = t[ch * ((size_t)j0 * n + i1) + e];
        double c = t[ch * ((size_t)j1 * n + i0) + e], q = t[ch * ((size_t)j1 * n + i1) + e];
        out[e] = (1.0 - fy) * ((1.0 - fx) * a + fx * b) + fy * ((1.0 - fx) * c + fx * q);
    }
}
double uvtex_lookup(const float *t, int res, double u, double v);

/* The four texels (OUT t[4], row-major indices) and weights (OUT w[4],
 * summing to 1) that uvtex_lookup reads at texture coordinates (u, v) of
 * a res x res texture: bilinear between texel centres, clamped at the
 * border (a coordinate that is not a number reads the first texel). */
static inline void uvtex_footprint(double u, double v, int res, size_t t[4], double w[4])
{
    double x = u * res - 0.5, y = v * res - 0.5, fx, fy;
    int i0, j0, i1, j1;
    x = !(x > 0.0) ? 0.0 : x > res - 1 ? res - 1 : x;
    y = !(y > 0.0) ? 0.0 : y > res - 1 ? res - 1 : y;
    i0 = (int)x;
    j0 = (int)y;
    i1 = i0 + 1 < res ? i0 + 1 : i0;
    j1 = j0 + 1 < res ? j0 + 1 : j0;
    fx = x - i0;
    fy = y - j0;
    t[0] = (size_t)j0 * res + i0;
    t[1] = (size_t)j0 * res + i1;
    t[2] = (size_t)j1 * res + i0;
    t[3] = (size_t)j1 * res + i1;
    w[0] = (1.0 - fx) * (1.0 - fy);
    w[1] = fx * (1.0 - fy);
    w[2] = (1.0 - fx) * fy;
    w[3] = fx * fy;
}

/* The two steps of uvtex_from_samples, for callers that merge before
 * filling: uvtex_splat writes the means into reached texels (0 elsewhere)
 * and the sample count of every texel into hits (both res x res); uvtex_fill
 * fills the texels whose count is 0 (GLINT_EINVAL when none is reached). */
int uvtex_splat(const float *uv, const float *val, int n, int ch, int res, float *tex, int *hits,
                glint_err *err);
int uvtex_fill(float *tex, const int *hits, int res, int ch, uvtex_report *rep, glint_err *err);

/* Merge the splat of another view into dst: a texel both reach keeps the
 * smallest value, one only src reaches takes src's, and the counts add
 * (coefficient textures of several views, seed 000 section 4.2: the
 * smallest keeps the component under every view's samples; a view that
 * does not see a texel has no say in it).  Fill after merging. */
void uvtex_merge_min(float *dst, int *dst_hits, const float *src, const int *src_hits,
                     size_t texels, int ch);

#endif
