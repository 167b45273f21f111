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

/* The parameters of the environment and the model every method fitted on
 * pbr_env's levels takes (env, env_rotation, env_intensity, lights, lobes,
 * fresnel, visibility, raster), at offsets ENVP(member of srbf_params) and
 * PBRP(member of pbr_params) of its own params. */
extern const char *const pbr_env_fresnel_values[];
#define PBR_ENV_PARAMS(ENVP, PBRP)                                                            \
    SRBF_ENV_LIGHT_PARAMS(ENVP),                                                              \
    {.name = "lights", .label = "light samples of the environment", .type = METHOD_PARAM_INT, \
     .affects = "precomputation",                                                             \
     .description = "lights the environment is compressed into (median cut): each fitted "   \
                    "pixel sums about half of them, so a fit's time grows linearly with it",  \
     .offset = ENVP(lights), .min = 1, .max = 4096},                                          \
    {.name = "lobes", .label = "highlight layers", .group = METHOD_GROUP_BASIC,               \
     .type = METHOD_PARAM_INT, .affects = "fit",                                              \
     .description = "GGX lobes: 1 (one highlight) or 2 (a sharp highlight over a broad "      \
                    "sheen)",                                                                 \
     .offset = PBRP(lobes), .min = 1, .max = PBR_MAX_LOBES},                                  \
    {.name = "fresnel", .label = "kind of surface", .group = METHOD_GROUP_BASIC,              \
     .type = METHOD_PARAM_ENUM, .affects = "fit",                                             \
     .description = "dielectric (plastic, paint, wood: one index of refraction, a tinted "    \
                    "highlight weight) or conductor (metal: a reflectance per colour "        \
                    "channel)",                                                               \
     .offset = PBRP(fresnel), .values = pbr_env_fresnel_values},                              \
    SRBF_VIS_PARAM(ENVP),                                                                     \
    {.name = "raster", .label = "pixels per view fitted", .group = METHOD_GROUP_ADVANCED,     \
     .type = METHOD_PARAM_TEXT, .affects = "precomputation",                                  \
     .description = "grid of pixels per view that are fitted (each sums the lights it "       \
                    "sees); full: every painted pixel",                                       \
     .offset = ENVP(raster), .syntax = "WxH | full", .examples = srbf_raster_examples,        \
     .parse = srbf_raster_parse, .format = srbf_raster_format}

#endif
