/* method_maps.c: the maps method, material maps of three-factor products
 * (method_maps.h): parameters and registration.  Its checks, fit and
 * resource rules are those of a maps_kind over hf3 (method_maps_kind.c);
 * the material is the maps' (method_maps_material.c). */
#include "method_maps.h"

#include <stddef.h>
#include <string.h>

#include "method_hf3_parts.h"
#include "internal/method_maps_int.h"

static const method_param maps_params_table[] = {
    HF3_PARAM_ROWS(maps_params, hf.),
    MAPS_PARAM_ROWS(maps_params),
};

static const method_preset maps_presets[] = {
    {"draft", "{\"res\": 32, \"components\": 3, \"map_res\": 64}"},
    {"default", "{\"res\": 64, \"components\": 5, \"map_res\": 128}"},
    {"fine", "{\"res\": 128, \"components\": 8, \"map_res\": 256}"},
};

static void maps_params_default(void *p)
{
    maps_params *mp = p;
    matmap_params d;
    memset(mp, 0, sizeof *mp);
    method_hf3.params_default(&mp->hf);
    mp->hf.res = 64;
    matmap_params_default(&d);
    MAPS_KNOBS_SET(mp, &d);
}

/* ---- the kind: maps over hf3 ---------------------------------------------------------- */

static void maps_knobs(const void *params, matmap_params *q)
{
    MAPS_KNOBS(q, (const maps_params *)params);
}

static const maps_kind maps_of_hf3 = {&method_maps, &method_hf3, maps_knobs};

static int maps_params_check(const void *params, glint_err *err)
{
    return maps_kind_params_check(&maps_of_hf3, params, err);
}

static int maps_fit(const method_fit_in *in, material *out, glint_err *err)
{
    return maps_kind_fit(&maps_of_hf3, in, out, err);
}

static int maps_holdout_ok(const void *params)
{
    return maps_kind_holdout_ok(&maps_of_hf3, params);
}

static size_t maps_fit_bytes(const void *params, long nsamples)
{
    return maps_kind_fit_bytes(&maps_of_hf3, params, nsamples);
}

static double maps_fit_seconds(const void *params, long nsamples)
{
    return maps_kind_fit_seconds(&maps_of_hf3, params, nsamples);
}

static const char *const maps_surface[] = {"coefficients", NULL};

const method method_maps = {
    .name = "maps",
    .label = "Varies over the surface",
    .summary = "Several finishes on one object: a few lamp-lit finishes blended "
        "over the surface by painted-in masks.",
    .when = "Use it for a logo on plastic, stripes or veins: paint each region as "
        "it should look, and the fit finds the materials and where each one is.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_FACTORS,
    .surface = maps_surface,
    .title = "Material maps: a sum of three-factor products weighted by textures",
    .reference = "Jaroszkiewicz & McCool, Fast Extraction of BRDFs and Material Maps from "
                 "Images, GI 2003, section 4.2",
    .description =
        "For objects painted with several materials (a logo on plastic, veins in marble): the "
        "painting is fitted as a sum of three-factor products, each weighted over the surface "
        "by a coefficient texture on the texture coordinates. Each product fits what the "
        "previous ones left (iterative residual factorization) with the cached operator of "
        "the three-factor method, which it shares; it stops at the tolerance, at the most "
        "components, or when a product no longer helps, and the material says which.",
    .held_out = "leave-one-view-out: for each painted view, fit the others and measure the RMS "
                "error on that view's painted pixels; pooled over views",
    .schema = "FitParamsMaps.json",
    .params_size = sizeof(maps_params),
    .params = maps_params_table,
    .nparams = (int)(sizeof maps_params_table / sizeof maps_params_table[0]),
    .presets = maps_presets,
    .npresets = (int)(sizeof maps_presets / sizeof maps_presets[0]),
    .params_default = maps_params_default,
    .params_check = maps_params_check,
    .levels = hf3_levels,
    .nlevels = HF3_NLEVELS,
    .fit = maps_fit,
    .mat = &maps_material_ops,
    .holdout_ok = maps_holdout_ok,
    .fit_bytes = maps_fit_bytes,
    .fit_seconds = maps_fit_seconds,
};
