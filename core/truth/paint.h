/* paint.h: paint a scene's views with an analytic BRDF, producing exactly
 * what a perfect artist would paint: per pixel radiance
 *   scale * pi I * f(wi, wo) * max(0, n.wi)   (scene.h's radiance: at scale 1
 *   a white Lambertian facing a light of intensity I reads I)
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
 *   > 0  : multiply by it (1: the radiance every fit assumes);
 *   <= 0 : choose the scale that makes the maximum over these views 1 (for
 *          8-bit images; a fit of such views is off by that scale); the chosen scale is written to *scale_out.
 *          If no pixel is lit (every value 0) the chosen scale is 1.
 * *scale_out receives the scale used in both cases.  Errors: NaN scale,
 * light intensity not > 0, non-finite G-buffer vectors on covered pixels.
 * out must point to nviews zeroed imgs; they are allocated here (caller
 * frees each with img_free).  scale_out may be NULL. */
int paint_views(const brdf *b, const gbuf *g, const scene_view *views,
                int nviews, double scale, img *out, double *scale_out,
                glint_err *err);

/* A spatially varying truth: two BRDFs blended over the surface's texture
 * coordinates by a pattern, f = (1 - w(u,v)) a + w(u,v) b (gold stripes on
 * red plastic; seed 000, section 4.2).  PAINT_SV_STRIPES: bands across u,
 * `freq` periods per unit of u, b on the first `duty` of each period;
 * PAINT_SV_CHECKER: squares of 1/(2 freq), b on every other one (duty 0:
 * all a, 1: all b).  `soft`: the width of a linear blend centred on each
 * edge, in periods (0: a hard material edge). */
enum { PAINT_SV_STRIPES = 1, PAINT_SV_CHECKER = 2 };
typedef struct paint_sv {
    brdf a, b;
    int pattern;
    double freq;   /* (0, 1024] */
    double duty;   /* [0, 1] */
    double soft;   /* [0, 0.5] */
} paint_sv;

/* Parse "PATTERN[:freq=F,duty=D,soft=S]|BRDF_A|BRDF_B", PATTERN stripes or
 * checker (defaults freq 8, duty 0.5, soft 0), the BRDFs as brdf_parse
 * reads them. */
int paint_sv_parse(const char *spec, paint_sv *out, glint_err *err);
int paint_sv_check(const paint_sv *sv, glint_err *err);
/* The weight w of b at (u, v), in [0, 1]. */
double paint_sv_weight(const paint_sv *sv, double u, double v);
/* paint_views with a spatially varying truth: each pixel's BRDF is the
 * blend at its G-buffer texture coordinates. */
int paint_views_sv(const paint_sv *sv, const gbuf *g, const scene_view *views, int nviews,
                   double scale, img *out, double *scale_out, glint_err *err);

/* A truth given as a function: f at unit (n, wi, wo), per steradian, no
 * cosine, RGB (merl_eval's shape: a measured material); it must be 0 below
 * either horizon and finite. */
typedef void (*paint_fn)(const void *ctx, const double n[3], const double wi[3],
                         const double wo[3], double f[3]);
int paint_views_fn(paint_fn fn, const void *ctx, const gbuf *g, const scene_view *views,
                   int nviews, double scale, img *out, double *scale_out, glint_err *err);

/* Paint nviews views under an environment's lights instead of the views'
 * point lights: each covered pixel seen from its camera gets
 *   scale * sum_k V_k power_k f(d_k, wo) max(0, n.d_k),
 * V_k the visibility of light k from the pixel, cast against mesh `m`
 * (vis.h) when `shadows` is set.  Background pixels get 0.  out as for
 * paint_views. */
struct env_lights;
struct mesh;
int paint_views_env(const brdf *b, const gbuf *g, int nviews, const struct mesh *m,
                    const struct env_lights *l, int shadows, double scale, img *out,
                    glint_err *err);
/* The same with a truth function (paint_fn). */
int paint_views_env_fn(paint_fn fn, const void *ctx, const gbuf *g, int nviews,
                       const struct mesh *m, const struct env_lights *l, int shadows,
                       double scale, img *out, glint_err *err);

#endif
