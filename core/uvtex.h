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

/* dst = min(dst, src) per entry (len entries): coefficient textures of
 * several views merged by keeping the smallest value, so that the BRDF
 * they scale stays under every view's samples (seed 000, section 4.2). */
void uvtex_merge_min(float *dst, const float *src, size_t len);

#endif
