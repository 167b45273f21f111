/* method_maps_int.h: what a method of material maps over another
 * method's products (maps: hf3 products; hybrid: hf4 products) shares:
 * the maps' parameter rows and checks, the fit over a product method, the
 * material.  Not part of core's interface. */
#ifndef GLINT_METHOD_MAPS_INT_H
#define GLINT_METHOD_MAPS_INT_H

#include <stddef.h>

#include "method_maps.h"

extern const char *const maps_merge_values[];

/* The maps' parameter rows for a params struct T with the members
 * components, merge, map_res, tol, refine, rounds and smooth (as
 * maps_params has them). */
#define MAPS_PARAM_ROWS(T)                                                                     \
    {.name = "components", .label = "materials, at most", .type = METHOD_PARAM_INT, .affects = "fit",                         \
     .description = "at most this many products (materials) summed over the surface; each "    \
                    "costs one fit on the cached operator",                                    \
     .offset = offsetof(T, components), .min = 1, .max = MATMAP_MAX},                          \
    {.name = "merge", .label = "how coefficients merge views", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "fit",                             \
     .description = "how per-sample scales become a coefficient texture: lsq, least squares "  \
                    "per texel over every view (the measured best); min, the smallest value "  \
                    "over views (seed 000)",                                                   \
     .offset = offsetof(T, merge), .values = maps_merge_values},                                    \
    {.name = "map_res", .label = "map size (texels per side)", .type = METHOD_PARAM_INT, .affects = "fit",                            \
     .description = "coefficient texture resolution (texels per side) over the surface's "     \
                    "texture coordinates",                                                     \
     .offset = offsetof(T, map_res), .min = MAPS_RES_MIN, .max = MAPS_RES_MAX},                \
    {.name = "tolerance", .label = "stop below this error", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "fit",                       \
     .description = "stop adding products once the residual's RMS falls below this fraction "  \
                    "of the painting's",                                                       \
     .offset = offsetof(T, tol), .min = 0.0, .max = 1.0},                                      \
    {.name = "refine", .label = "refinement sweeps", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_INT, .affects = "fit",                             \
     .description = "sweeps of the joint refinement: every coefficient of every product "      \
                    "adjusted together to the painting once the products are found (0: none)", \
     .offset = offsetof(T, refine), .min = 0, .max = MATMAP_REFINE_MAX},                       \
    {.name = "rounds", .label = "back-fitting rounds", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_INT, .affects = "fit",                             \
     .description = "back-fitting rounds: every product refitted to what the others leave, "   \
                    "then the coefficients again; stops early when a round gains under 1% "    \
                    "(0: none; needs refine)",                                                 \
     .offset = offsetof(T, rounds), .min = 0, .max = MATMAP_ROUNDS_MAX},                       \
    {.name = "smooth", .label = "map smoothing", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "fit",                          \
     .description = "how strongly neighbouring coefficient texels are held together in the "   \
                    "refinement: higher predicts new views better, lower fits the painted "    \
                    "ones closer (0: not at all)",                                             \
     .offset = offsetof(T, smooth), .min = 0.0, .max = MATMAP_SMOOTH_MAX}

/* The knobs of T (as MAPS_PARAM_ROWS reads them) as matmap_params. */
#define MAPS_KNOBS(q, mp)                                                                        \
    do {                                                                                         \
        (q)->components = (mp)->components;                                                      \
        (q)->merge = (mp)->merge;                                                                \
        (q)->res = (mp)->map_res;                                                                \
        (q)->tol = (mp)->tol;                                                                    \
        (q)->refine = (mp)->refine;                                                              \
        (q)->rounds = (mp)->rounds;                                                              \
        (q)->smooth = (mp)->smooth;                                                              \
    } while (0)

/* The checks across the knobs (rounds need refine; texture rows). */
int maps_knobs_check(const matmap_params *q, glint_err *err);

/* Fit in->rgb as maps whose products are fits of `product` (whose params
 * struct begins in->params, and whose levels in->levels are), the
 * material being one of method `self` (info.params from in->params). */
int maps_fit_with(const method_fit_in *in, const method *self, const method *product,
                  const matmap_params *q, material *out, glint_err *err);

/* Resources of a fit beyond the product method's: per sample and per
 * texel. */
size_t maps_extra_bytes(const matmap_params *q, long nsamples);

extern const material_ops maps_material_ops;

#endif
