/* method_pbr_maps.c: the pbr_maps method, material maps of physically
 * based products (method_pbr_maps.h): parameters, checks, resource rules
 * and registration.  The fit is method_pbr_maps_fit.c's; the material is
 * the maps' (method_maps_material.c, with what pbr products have of their
 * own in method_maps_pbr.c). */
#include "method_pbr_maps.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "internal/method_maps_int.h"

static const char *const fresnel_values[] = {"dielectric", "conductor", NULL};

static const method_param pbr_maps_params_table[] = {
    {.name = "lobes", .label = "highlight layers", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "GGX lobes of each material: 1 (one highlight) or 2 (a sharp highlight "
                    "over a broad sheen)",
     .offset = offsetof(pbr_maps_params, pbr.lobes), .min = 1, .max = PBR_MAX_LOBES},
    {.name = "fresnel", .label = "kind of surface", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_ENUM, .affects = "fit",
     .description = "each material's Fresnel: dielectric (plastic, paint, wood) or conductor "
                    "(metal: a reflectance per colour channel)",
     .offset = offsetof(pbr_maps_params, pbr.fresnel), .values = fresnel_values},
    {.name = "starts", .label = "roughnesses tried", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "starting roughnesses of each material's search; the best fit of them is "
                    "kept",
     .offset = offsetof(pbr_maps_params, pbr.starts), .min = 1, .max = PBR_MAX_STARTS},
    {.name = "components", .label = "materials, at most", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "at most this many physical materials over the surface; each costs a few "
                    "fits",
     .offset = offsetof(pbr_maps_params, components), .min = 1, .max = MATMAP_MAX},
    {.name = "map_res", .label = "detail of where each finish is", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "coefficient texture resolution (texels per side) over the surface's "
                    "texture coordinates",
     .offset = offsetof(pbr_maps_params, map_res), .min = MAPS_RES_MIN, .max = MAPS_RES_MAX},
    {.name = "rounds", .label = "rounds of regrouping", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "rounds of giving each texel its best material and refitting every "
                    "material to its texels; stops earlier when no texel changes",
     .offset = offsetof(pbr_maps_params, rounds), .min = 0, .max = PBR_MAPS_ROUNDS_MAX},
    {.name = "tolerance", .label = "one finish below this error", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "no second finish when one leaves an RMS of at most this fraction of the "
                    "painting's",
     .offset = offsetof(pbr_maps_params, tol), .min = 0.0, .max = 1.0},
};

static void pbr_maps_params_default(void *p)
{
    pbr_maps_params *pp = p;
    memset(pp, 0, sizeof *pp);
    method_pbr.params_default(&pp->pbr);
    pp->components = 3;
    pp->map_res = 128;
    pp->rounds = 10;
    pp->tol = 0.002;
}

/* ---- the level: pbr's, on the params' first member -------------------------------------- */

static void geom_key(const void *params, const samples *s, const char *prev_key, char *key,
                     size_t len)
{
    method_pbr.levels[0].key(params, s, prev_key, key, len);
}

static int geom_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    return method_pbr.levels[0].build(in, out, err);
}

static const method_level pbr_maps_levels[] = {
    {.name = "pbr-geom", .progress = 0.05, .key = geom_key, .build = geom_build},
};

/* ---- checks and resources ------------------------------------------------------------ */

static int pbr_maps_params_check(const void *params, glint_err *err)
{
    const pbr_maps_params *pp = params;
    if ((long)pp->components * pp->map_res > MAPS_ROWS_MAX)
        return glint_err_set(err, GLINT_EINVAL,
                             "components x map_res = %ld exceeds %d: lower one of them",
                             (long)pp->components * pp->map_res, MAPS_ROWS_MAX);
    return 0;
}

/* pbr's fit, and per sample its texel and a flag, per texel the counts,
 * assignment, errors per product and the coefficients. */
static size_t pbr_maps_fit_bytes(const void *params, long nsamples)
{
    const pbr_maps_params *pp = params;
    size_t T = (size_t)pp->map_res * pp->map_res;
    return method_fit_bytes(&method_pbr, &pp->pbr, nsamples) + (size_t)nsamples * 8 +
           T * (16 + 12 * (size_t)pp->components);
}

/* A pbr fit per product per round, at most (fewer when no texel changes). */
static double pbr_maps_fit_seconds(const void *params, long nsamples)
{
    const pbr_maps_params *pp = params;
    return method_fit_seconds(&method_pbr, &pp->pbr, nsamples) * (1 + pp->rounds) +
           (double)pp->components * (1 + pp->rounds) * nsamples * METHOD_SECONDS_PER_SAMPLE;
}

static const char *const pbr_maps_surface[] = {"coefficients", NULL};

const method method_pbr_maps = {
    .name = "pbr_maps",
    .label = "Physical, varying over the surface",
    .summary = "Several physical finishes on one object (a diffuse colour, a roughness and a "
        "reflectance each), blended over the surface by masks.",
    .when = "Use it for stripes, logos or regions of different materials when the object "
        "will be seen from views and under lights you did not paint.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_NONE,
    .surface = pbr_maps_surface,
    .title = "Material maps of physically based BRDFs (Lambert + GGX, height-correlated "
             "Smith, Schlick Fresnel)",
    .reference = "Jaroszkiewicz & McCool, Fast Extraction of BRDFs and Material Maps from "
                 "Images, GI 2003, section 4.2; Walter, Marschner, Li & Torrance, Microfacet "
                 "Models for Refraction through Rough Surfaces, 2007",
    .description =
        "f(x) = sum over k of c_k(uv) f_k(wi, wo): each f_k a physically based material of "
        "the pbr method (kd/pi plus GGX lobes), c_k a coefficient texture over the surface's "
        "texture coordinates, 1 where product k holds. The first material is the pbr fit of "
        "the whole painting, each next one the pbr fit of the texels the others fit worst; "
        "then, k-means fashion, every texel takes the material that fits its samples best and "
        "every material is refitted to its texels, until no texel changes. Texels no sample "
        "reaches blend their neighbours' materials. Points: fit_seconds is the warm fit, "
        "rms_painted the RMS error on the painted samples.",
    .schema = "FitParamsPbrMaps.json",
    .params_size = sizeof(pbr_maps_params),
    .params = pbr_maps_params_table,
    .nparams = (int)(sizeof pbr_maps_params_table / sizeof pbr_maps_params_table[0]),
    .params_default = pbr_maps_params_default,
    .params_check = pbr_maps_params_check,
    .levels = pbr_maps_levels,
    .nlevels = (int)(sizeof pbr_maps_levels / sizeof pbr_maps_levels[0]),
    .fit = pbr_maps_fit_in,
    .mat = &maps_material_ops,
    .fit_bytes = pbr_maps_fit_bytes,
    .fit_seconds = pbr_maps_fit_seconds,
};
