/* method_pbr_maps.h: material maps of physically based products as a
 * method: "pbr_maps".
 *
 *     f(x, wi, wo) = sum_k c_k(uv(x)) f_k(wi, wo)
 *
 * each f_k a pbr material (method_pbr.h: kd / pi plus one or two GGX
 * lobes, height-correlated Smith, Schlick Fresnel) and c_k a coefficient
 * texture over the surface's texture coordinates (map_res x map_res,
 * bilinear between texel centres, clamped at the border, as the maps
 * method reads its coefficients).  The fit (method_pbr_maps_fit.c) finds
 * which product holds at each texel by alternating assignment and pbr
 * refits, k-means fashion: c_k is 1 where product k holds, 0 where another
 * does, and blends the neighbours' products on texels no sample reaches.
 *
 * Why whole products and not per-texel parameters: a texel is seen from
 * one or two directions, too few to fit a roughness or a highlight of its
 * own.  Which of a few whole materials holds there is decided by what the
 * texel shows (its colour off the highlight is enough), and its highlight
 * then comes with the material.  On seed 000's Table 4 (the triceratops,
 * gold stripes on red, 12 views; tests/bench/bench_maps) per-texel maps of
 * diffuse colour and lobe strength over one shared lobe predicted 20 new
 * views at 0.21-0.28 RMS, products fitted to residuals with coefficients
 * refined freely in [0, 1] (the maps method's fit) at 0.21-0.25, against
 * one pbr material's 0.29; BENCHMARKS.md has what the assignment gives.
 *
 * Parameters: pbr's (a pbr_params first: the products are fitted on pbr's
 * level, keyed as pbr keys it, so a pbr fit of the same views shares it),
 * then components (at most this many products), map_res, rounds (of
 * assignment and refits; it stops earlier when no texel changes) and
 * tolerance: when the first product (the pbr fit of everything) leaves an
 * RMS of at most this fraction of the painting's, the painting is one
 * material and no other product is made (the maps' rule; default 0.002:
 * a finish painted from one of glint's physical presets stops there,
 * where three products split one material among themselves, 3.7 times
 * slower, for nothing).
 *
 * The material is a maps_material (method_maps.h) whose products are pbr
 * materials: on disk as the maps method writes it, with "product": "pbr"
 * and each product's pbr members (validated by pbr on reading), and
 * coefficients.exr / .png.  Every product is a physical material, so a
 * glTF or MaterialX export of a product is that material itself.
 *
 * The info: "params", "precomputation", "seconds", "maps" (components,
 * stop: "tolerance" or "components", one_product_rel_rms: the first
 * product's RMS over the painting's, rounds, texels_changed per round, per
 * product its texels and its pbr fit's report: samples, rms, determined and
 * undetermined parameters),
 * "errors" (rms_painted, max_abs_painted, rms_by_view: the material as it
 * renders, coefficients read bilinearly). */
#ifndef GLINT_METHOD_PBR_MAPS_H
#define GLINT_METHOD_PBR_MAPS_H

#include "method.h"
#include "method_pbr.h"

extern const method method_pbr_maps;

#define PBR_MAPS_ROUNDS_MAX 50

typedef struct pbr_maps_params {
    pbr_params pbr;    /* first: pbr's level reads it */
    int components;    /* at most this many products, 1..MATMAP_MAX */
    int map_res;       /* coefficient texels per side, MAPS_RES_MIN..MAPS_RES_MAX */
    int rounds;        /* rounds of assignment and refits, 0..PBR_MAPS_ROUNDS_MAX */
    double tol;        /* one product when its RMS is at most this fraction of the painting's */
} pbr_maps_params;

#endif
