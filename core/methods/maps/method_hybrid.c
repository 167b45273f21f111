/* method_hybrid.c: the hybrid method, material maps of four-factor
 * products (method_hybrid.h): parameters and registration.  Its checks, fit
 * and resource rules are those of a maps_kind over hf4
 * (method_maps_kind.c); the material is the maps' (method_maps_material.c). */
#include "method_hybrid.h"

#include <stddef.h>
#include <string.h>

#include "method_hf4_parts.h"
#include "internal/method_maps_int.h"

static const method_param hybrid_params_table[] = {
    HF4_PARAM_ROWS(hybrid_params, h.),
    MAPS_PARAM_ROWS(hybrid_params),
};

static const method_preset hybrid_presets[] = {
    {"draft", "{\"res\": 32, \"s_res\": 8, \"components\": 3, \"map_res\": 64}"},
    {"default", "{\"res\": 32, \"s_res\": 16, \"components\": 4, \"map_res\": 128}"},
    {"fine", "{\"res\": 64, \"s_res\": 32, \"components\": 6, \"map_res\": 256}"},
};

static void hybrid_params_default(void *p)
{
    hybrid_params *hp = p;
    matmap_params d;
    memset(hp, 0, sizeof *hp);
    method_hf4.params_default(&hp->h);
    hp->h.sres = 16;
    matmap_params_default(&d);
    MAPS_KNOBS_SET(hp, &d);
    hp->components = 4;
}

/* ---- the kind: maps over hf4 ---------------------------------------------------------- */

static void hybrid_knobs(const void *params, matmap_params *q)
{
    MAPS_KNOBS(q, (const hybrid_params *)params);
}

static const maps_kind maps_of_hf4 = {&method_hybrid, &method_hf4, hybrid_knobs};

static int hybrid_params_check(const void *params, glint_err *err)
{
    return maps_kind_params_check(&maps_of_hf4, params, err);
}

static int hybrid_fit(const method_fit_in *in, material *out, glint_err *err)
{
    return maps_kind_fit(&maps_of_hf4, in, out, err);
}

static int hybrid_holdout_ok(const void *params)
{
    return maps_kind_holdout_ok(&maps_of_hf4, params);
}

static size_t hybrid_fit_bytes(const void *params, long nsamples)
{
    return maps_kind_fit_bytes(&maps_of_hf4, params, nsamples);
}

static double hybrid_fit_seconds(const void *params, long nsamples)
{
    return maps_kind_fit_seconds(&maps_of_hf4, params, nsamples);
}

static const char *const hybrid_surface[] = {"coefficients", "spatial", NULL};

const method method_hybrid = {
    .name = "hybrid",
    .label = "Varies over the surface, with texture",
    .summary = "Several finishes on one object, each free to change colour and "
        "brightness within its region: masks of finishes, each with "
        "a colour texture of its own.",
    .when = "Use it for worn gold on red plastic and the like; the richest and "
        "slowest model lit by lamps.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_FACTORS,
    .surface = hybrid_surface,
    .title = "Hybrid: material maps of four-factor products",
    .reference = "Jaroszkiewicz & McCool, Fast Extraction of BRDFs and Material Maps from "
                 "Images, GI 2003, section 4.2",
    .description =
        "Material maps whose products are four-factor ones: coefficient textures say where "
        "each material is (gold stripes on red plastic), and each material's own spatial "
        "factor s(u, v) lets its colour and brightness drift within that region. Each product "
        "fits what the previous ones left with the cached decomposition of the four-factor "
        "method, which it shares.",
    .held_out = "leave-one-view-out: for each painted view, fit the others and measure the RMS "
                "error on that view's painted pixels; pooled over views",
    .schema = "FitParamsHybrid.json",
    .params_size = sizeof(hybrid_params),
    .params = hybrid_params_table,
    .nparams = (int)(sizeof hybrid_params_table / sizeof hybrid_params_table[0]),
    .presets = hybrid_presets,
    .npresets = (int)(sizeof hybrid_presets / sizeof hybrid_presets[0]),
    .params_default = hybrid_params_default,
    .params_check = hybrid_params_check,
    .levels = hf4_levels,
    .nlevels = HF4_NLEVELS,
    .fit = hybrid_fit,
    .mat = &maps_material_ops,
    .holdout_ok = hybrid_holdout_ok,
    .fit_bytes = hybrid_fit_bytes,
    .fit_seconds = hybrid_fit_seconds,
};
