/* brdf.h: analytic BRDFs, the test truths glint paints with.
 *
 * Every model returns f(wi, wo) per steradian (no cosine), RGB, and is zero
 * unless n.wi > 0 and n.wo > 0.  Vectors are unit, pointing away from the
 * surface.  Definitions (kd, ks, F0 are RGB):
 *   lambert : kd / pi
 *   phong   : kd/pi + ks (e+2)/(2pi) max(0, r.wo)^e,  r = 2(n.wi)n - wi
 *   blinn   : kd/pi + ks (e+8)/(8pi) max(0, n.h)^e   (normalized Blinn-Phong)
 *   ct      : kd/pi + D G F / (4 (n.wi)(n.wo)), GGX D with alpha = roughness,
 *             separable Smith-GGX G1(x) = 2x / (x + sqrt(a^2 + (1-a^2)x^2)),
 *             Schlick F = F0 + (1-F0)(1 - h.wi)^5
 *   ward    : kd/pi + ks exp(-tan^2(th_h)/a^2) / (4 pi a^2 sqrt(cos_i cos_o))
 *             (isotropic Ward with roughness a); with rough_y = b != a the
 *             anisotropic Ward, kd/pi + ks exp(-((h.t/a)^2 + (h.b/b)^2) /
 *             (h.n)^2) / (4 pi a b sqrt(cos_i cos_o)), t and b vec3.h's
 *             v3_frame(n) (t runs around the world's up axis, Z)
 * These match ../shared/reference/hf_ref.py (lambert, phong, blinn, ct).
 *
 * A brdf is a small value (no pointers; copy it freely).  Every function is
 * pure and thread-safe. */
#ifndef GLINT_BRDF_H
#define GLINT_BRDF_H

#include <stdint.h>

#include "env.h"
#include "err.h"

typedef enum {
    BRDF_LAMBERT = 0,
    BRDF_PHONG,
    BRDF_BLINN,
    BRDF_CT,
    BRDF_WARD
} brdf_kind;

typedef struct brdf {
    brdf_kind kind;
    double kd[3];      /* diffuse albedo */
    double ks[3];      /* specular weight (phong, blinn, ward) */
    double f0[3];      /* Fresnel reflectance at normal incidence (ct) */
    double exponent;   /* phong / blinn exponent, > 0 */
    double roughness;  /* ct GGX alpha, ward alpha (along t), in (0, 1] */
    double roughness_y; /* ward alpha along b; 0: isotropic (= roughness) */
} brdf;

/* Parse a spec "NAME[:key=value,...]", NAME in lambert|phong|blinn|ct|ward,
 * keys kd, ks, f0 (one number or r/g/b as "0.5/0.4/0.3"), e (exponent),
 * rough, rough_y (ward only).  Defaults (the reference truths): lambert kd 0.8; phong kd 0.7
 * ks 0.3 e 32; blinn kd 0.7 ks 0.3 e 20; ct kd 0.5 f0 0.3 rough 0.2;
 * ward kd 0.5 ks 0.3 rough 0.2.  Also the named presets of the reference:
 * phong32, blinn20, blinn100, ct0.2, ct0.5.  Every value is range-checked
 * (finite, kd/ks/f0 in [0,1], e in (0, 10000], rough in [0.01, 1]). */
int brdf_parse(const char *spec, brdf *out, glint_err *err);

/* Canonical text of a brdf (parseable by brdf_parse) into buf. */
void brdf_format(const brdf *b, char *buf, int len);

/* Evaluate f at unit n, wi, wo (OUT: rgb[3]).  Zero below either horizon. */
void brdf_eval(const brdf *b, const double n[3], const double wi[3],
               const double wo[3], double rgb[3]);

/* Radiance per unit light under an environment's light (envlit.h's
 * envlit_fn; ctx: a const brdf *; uv unused): brdf_eval() x n.wi. */
void brdf_envlit(const void *ctx, const double uv[2], const double n[3], const double wi[3],
                 const double wo[3], double rgb[3]);

/* brdf_envlit summed over an environment's lights (envlit.h's
 * envlit_sum_fn; ctx: a const brdf *): the same sum, term for term and in
 * the same order (the same digits), without a call a light, and with what
 * holds for every light of a point (the view's cosine and its GGX G1, the
 * diffuse kd / pi) taken once: ct and lambert; the other models a call a
 * light. */
void brdf_envlit_sum(const void *ctx, const env_lights *l, const uint64_t *bits,
                     const double uv[2], const double n[3], const double wo[3], double acc[3]);

#endif
