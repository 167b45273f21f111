/* method_pbr_env.h: the pbr_env method: the physically based BRDF of pbr.h
 * (kd / pi plus one or two GGX lobes, height-correlated Smith, Schlick
 * Fresnel of a dielectric or a conductor) fitted to views painted under an
 * environment, inside glint's method interface (method.h).
 *
 * The environment is srbf's: compressed into lights by median cut, with
 * each light's visibility from each fitted pixel cast with Embree unless
 * the mesh is convex (method_srbf.h).  A fitted pixel (a row, on srbf's
 * raster grid) is lit by every light above its horizon that it sees; its
 * value is
 *
 *   b_c = sum over those lights k of  P_kc f_c(wi_k, wo) (n.wi_k)
 *
 * P_kc the light's power in channel c (radiance times solid angle) and b_c
 * the painted radiance over the environment's intensity (env_intensity),
 * as srbf's rows are (no 1/pi: a white Lambertian under a uniform sky of
 * radiance 1 reads 1).  The fit is pbr's (pbr_fit: starts, bounds,
 * Levenberg-Marquardt, what the views determine) with each sample summing
 * its lights (pbr.h's pbr_geom with terms).
 *
 * The material is a pbr material (method_pbr.h: the same manifest, files,
 * shader and exports): a renderer lights it with any environment or lamp,
 * which is what the fit is for.
 *
 * Levels (each in the cache under its own key):
 *   lights          srbf's (the same key: a scene fitted by srbf shares it)
 *   rows            srbf's (the same key)
 *   pbr-env-terms   per row the lights it sees above its horizon: their
 *                   cosines (n.wi, n.wo, n.h, wi.h) and powers (44 bytes a
 *                   term, about half the lights a row), the shadow rays cast
 *
 * Thread-safety: as method.h. */
#ifndef GLINT_METHOD_PBR_ENV_H
#define GLINT_METHOD_PBR_ENV_H

#include "method.h"
#include "method_pbr.h"
#include "method_srbf.h"

extern const method method_pbr_env;

typedef struct pbr_env_params {
    /* the environment, its lights, the visibility and the raster (srbf's
     * members of those names; the others keep srbf's defaults, unused) */
    srbf_params env;
    /* the model and its fit (pbr's; start_samples and refine_samples count
     * rows) */
    pbr_params pbr;
} pbr_env_params;

/* The terms level's data. */
typedef struct pbr_env_terms {
    pbr_geom g;           /* the rows as samples, each with its lights (pbr.h) */
    int shadows;          /* 1: visibility cast (rays below) */
    long rays;
    double seconds;
} pbr_env_terms;

#endif
