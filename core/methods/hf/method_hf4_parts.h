/* method_hf4_parts.h: what the methods built on the four-factor product
 * (method_hybrid.c) share with it: its parameter rows, levels, material
 * operations and resource rules.  Not part of core's interface. */
#ifndef GLINT_METHOD_HF4_PARTS_H
#define GLINT_METHOD_HF4_PARTS_H

#include <stddef.h>

#include "method_hf3_parts.h"
#include "method_hf4.h"

/* The parameter rows of hf4 for a params struct T holding an hf4_params_t
 * at member path P ("" for hf4_params_t itself, "h." for one inside). */
#define HF4_PARAM_ROWS(T, P)                                                                  \
    {.name = "res", .label = "detail", .type = METHOD_PARAM_INT, .affects = "precomputation",                                        \
     .description = "texels per 1D factor (p, q, r)", .offset = offsetof(T, P res),           \
     .min = HF_RES_MIN, .max = HF_RES_MAX},                                                   \
    {.name = "s_res", .label = "colour texture size", .type = METHOD_PARAM_INT, .affects = "precomputation",                  \
     .description = "nodes per side of the spatial factor s(u, v) over the texture "          \
                    "coordinates: the unknowns grow as s_res^2 and the precomputation as "    \
                    "their cube",                                                             \
     .offset = offsetof(T, P sres), .min = HF4_SRES_MIN, .max = HF4_SRES_MAX},                \
    {.name = "lambda", .label = "smoothing", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "precomputation",              \
     .description = "weight of the smoothing rows of p, q and r",                             \
     .offset = offsetof(T, P lambda), .min = 0.0, .max = HF_LAMBDA_MAX},                      \
    {.name = "lambda_s", .label = "colour texture smoothing", .type = METHOD_PARAM_NUMBER, .affects = "precomputation",            \
     .description = "weight of the 2D Laplacian of s: it also fills the nodes no sample "     \
                    "reaches",                                                                \
     .offset = offsetof(T, P lambda_s), .min = 0.0, .max = HF_LAMBDA_MAX},                    \
    {.name = "mapping", .label = "log mapping", .group = METHOD_GROUP_ADVANCED, .option = "map", .type = METHOD_PARAM_TEXT, .affects = "fit",         \
     .description = "mapping to log space (section 3.4)",                                     \
     .offset = offsetof(T, P map),                                                            \
     .syntax = "log | add[:a] | sub[:margin], optionally ,eps=E",                             \
     .examples = hf3_map_examples, .parse = hf3_map_parse, .format = hf3_map_format},         \
    {.name = "model", .label = "what the factors fit", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "fit",                            \
     .description = "radiance: factors approximate the painted value; brdf: painted / cos_i", \
     .offset = offsetof(T, P model), .values = hf3_model_values},                             \
    {.name = "rcond", .label = "rank cutoff", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "precomputation",               \
     .description = "relative singular-value cutoff: the gauge and nodes no sample or "       \
                    "smoothing reaches fall under it",                                        \
     .offset = offsetof(T, P rcond), .min = 1e-16, .max = 1.0, .max_exclusive = 1}

#define HF4_NLEVELS 1
/* the decomposition (method_hf4.h): keyed from the hf4_params_t at the
 * start of the params struct, so that a method whose params begin with one
 * shares hf4's cached level */
extern const method_level hf4_levels[HF4_NLEVELS];
extern const material_ops hf4_material_ops;
int hf4_holdout_ok(const void *params);
size_t hf4_fit_bytes(const void *params, long nsamples);
double hf4_fit_seconds(const void *params, long nsamples);

#endif
