/* method_maps_int.h: what a method of material maps over another
 * method's products (maps: hf3 products; hybrid: hf4 products) shares:
 * the maps' parameter rows, the method described by a maps_kind (its
 * checks, fit and report, resource rules: method_maps_kind.c), the
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
    {.name = "map_res", .label = "detail of where each finish is", .type = METHOD_PARAM_INT, .affects = "fit",                        \
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

/* matmap_params q as the knobs of T: what MAPS_KNOBS reads. */
#define MAPS_KNOBS_SET(mp, q)                                                                    \
    do {                                                                                         \
        (mp)->components = (q)->components;                                                      \
        (mp)->merge = (q)->merge;                                                                \
        (mp)->map_res = (q)->res;                                                                \
        (mp)->tol = (q)->tol;                                                                    \
        (mp)->refine = (q)->refine;                                                              \
        (mp)->rounds = (q)->rounds;                                                              \
        (mp)->smooth = (q)->smooth;                                                              \
    } while (0)

/* A method of material maps: the maps' knobs over the products of another
 * method.  Its params struct begins with the product method's (so that the
 * product's levels, keyed from the start of the params, are its levels,
 * and a fit of either shares them) and holds the knobs after it.  maps
 * and hybrid are two of these; each method's table takes its callbacks
 * from the maps_kind_* functions of its own kind. */
typedef struct maps_kind {
    const method *self;          /* the method of maps */
    const method *product;       /* the method of its products */
    /* The knobs of a params struct of self (OUT: *q): MAPS_KNOBS of its type. */
    void (*knobs)(const void *params, matmap_params *q);
} maps_kind;

/* method.params_check: the checks across the knobs (rounds need refine;
 * texture rows). */
int maps_kind_params_check(const maps_kind *k, const void *params, glint_err *err);

/* method.fit: in->rgb as maps whose products are fits of k->product, the
 * material one of k->self; its report as the maps give it. */
int maps_kind_fit(const maps_kind *k, const method_fit_in *in, material *out, glint_err *err);

/* method.holdout_ok, fit_bytes, fit_seconds: the product method's, and
 * what the maps add per sample and per texel. */
int maps_kind_holdout_ok(const maps_kind *k, const void *params);
size_t maps_kind_fit_bytes(const maps_kind *k, const void *params, long nsamples);
double maps_kind_fit_seconds(const maps_kind *k, const void *params, long nsamples);

extern const material_ops maps_material_ops;

/* A maps material whose products are pbr materials (method_maps_pbr.c):
 * its GPU binding (material_ops.gpu) and its summary. */
int maps_pbr_gpu(const maps_material *x, material_gpu *g, glint_err *err);
json_t *maps_pbr_summary(const maps_material *x);

/* The pbr_maps method's fit (method_pbr_maps_fit.c). */
int pbr_maps_fit_in(const method_fit_in *in, material *out, glint_err *err);

#endif
