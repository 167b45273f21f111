/* method_pbr_detail.h: the pbr_detail method: a physically based fit
 * (method_pbr.h) as the base, multiplied by a three-factor homomorphic
 * factorization (method_hf3.h) of what the base leaves over, the ratio
 * painted / base.
 *
 * Conventions.  Painted values are radiance per unit light, f ci (method.h).
 * The material is
 *
 *   value_c(wi, wo) = f_base_c(wi, wo) * (ci + t_c (detail_c(wi, wo) - ci))
 *
 * with f_base the pbr BRDF (without the cosine) and detail an hf3 material
 * (which carries the cosine: hf3's brdf model multiplies its factors by ci,
 * its radiance model holds ci in them).  The detail is
 * fitted to y_c / max(f_base_c, floor_c) per sample and channel: a value
 * f ci over f_base is ratio ci, which hf3's brdf model (this method's
 * default) divides by ci to fit the ratio itself.  floor_c is
 * PBR_DETAIL_FLOOR_FRAC of the base's mean f_c over the samples (or
 * PBR_DETAIL_FLOOR_MIN where that mean is 0: a black base), so that a
 * near-black base does not make the ratio blow up; the report counts the
 * samples held at the floor.  When the base is exact the ratio is 1 and,
 * with the brdf model, the factors are constant.
 *
 * t_c in [0, 1], the detail's weight, is the least-squares fit of the
 * product to the painting once the detail is fitted (clamped): the detail
 * is kept where it pays on the painted samples (t = 1), left out where it
 * does not (t = 0: the base alone), so the product's painted error is
 * never above the base's.  A separable detail fitted in log space weighs
 * every sample alike, while the product's error weighs it by f_base: where
 * the ratio is beyond three factors (a Phong lobe under a GGX one) the
 * whole detail can double the base's error.
 *
 * Levels, each keyed exactly as the method it comes from keys it, so a
 * direct pbr or hf3 fit of the same views shares the cache entries:
 *   pbr-geom       pbr's per-sample cosines
 *   decomposition  hf3's, from the hf3 parameters (res, lambda, route, rcond)
 *   operator       hf3's
 *
 * The material's info: "params"; "base": the pbr fit's own report
 * (determined and undetermined parameters, at_bound, notes, its errors);
 * "blend": the weight and the painted errors of the base alone, the whole
 * detail and the product (per unit light);
 * "detail": the factorization's report (precomputation, seconds, errors of
 * the ratio); "floor": {"fraction", "value": [r, g, b], "samples_at_floor":
 * [r, g, b]}; "errors" of the product on the painted samples (rms_painted,
 * max_abs_painted, rms_by_view, and rms_painted_base: the base alone);
 * "precomputation" and "seconds".
 *
 * Manifest members (material.json): "base": pbr's members (fresnel,
 * diffuse, lobes), "detail": hf3's members (res, model, mapping, a_used,
 * log_factors, png_scale); each validated on reading by its own method;
 * "detail_weight": [r, g, b] in [0, 1].
 *
 * Thread-safety: as method.h. */
#ifndef GLINT_METHOD_PBR_DETAIL_H
#define GLINT_METHOD_PBR_DETAIL_H

#include "hf.h"
#include "material.h"
#include "method.h"
#include "method_hf3.h"
#include "method_pbr.h"

#define PBR_DETAIL_FLOOR_FRAC 0.01
#define PBR_DETAIL_FLOOR_MIN 1e-6

extern const method method_pbr_detail;
extern const material_ops pbr_detail_material_ops;

/* Parameters: hf3's first (its levels read a fit_params at the start of
 * the params struct), then pbr's. */
typedef struct pbr_detail_params {
    fit_params hf;
    pbr_params pbr;
} pbr_detail_params;

/* A material's data: the base and the detail, both owned. */
typedef struct pbr_detail_material {
    pbr_material base;
    hf_factors detail;
    double weight[3];   /* the detail's weight per channel, in [0, 1] */
} pbr_detail_material;

/* The data of a pbr_detail material, or NULL for another method's. */
const pbr_detail_material *pbr_detail_material_of(const material *m);

/* The base BRDF (no cosine) at unit n, wi, wo (OUT f[3]); 0 unless n.wi > 0
 * and n.wo > 0. */
void pbr_detail_base_brdf(const pbr_material *pm, const double n[3], const double wi[3],
                          const double wo[3], double f[3]);

/* A material of this method from a pbr material's data and an hf3
 * material's factors (both moved out: *base is copied, *detail zeroed) and
 * info (one reference stolen).  GLINT_ENOMEM: all released. */
int pbr_detail_material_init(material *m, const pbr_material *base, hf_factors *detail,
                             const double weight[3], json_t *info, glint_err *err);

#endif
