/* paint.h: paint a scene's views with an analytic BRDF, producing exactly
 * what a perfect artist would paint: per pixel radiance
 *   scale * I * f(wi, wo) * max(0, n.wi)
 * on the pixels glint samples (mask, n.wi > 0, n.wo > 0), 0 elsewhere.
 * Images are RGB (3 channels), one per view, sized like the gbufs.
 * Pure and thread-safe: the output images are the caller's. */
#ifndef GLINT_PAINT_H
#define GLINT_PAINT_H

#include "brdf.h"
#include "err.h"
#include "gbuf.h"
#include "img.h"
#include "scene.h"

/* Paint nviews views.  `scale`:
 *   > 0  : multiply by it (HDR painting or a scale shared with other views);
 *   <= 0 : choose the scale that makes the maximum over these views 1 (the
 *          [0,1] convention); the chosen scale is written to *scale_out.
 *          If no pixel is lit (every value 0) the chosen scale is 1.
 * *scale_out receives the scale used in both cases.  Errors: NaN scale,
 * light intensity not > 0, non-finite G-buffer vectors on covered pixels.
 * out must point to nviews zeroed imgs; they are allocated here (caller
 * frees each with img_free).  scale_out may be NULL. */
int paint_views(const brdf *b, const gbuf *g, const scene_view *views,
                int nviews, double scale, img *out, double *scale_out,
                glint_err *err);

#endif
