/* method_hf3_parts.h: what the methods built on the three-factor one
 * (method_maps.c) share with it: its parameter rows, levels, material
 * operations and resource rules.  Not part of core's interface. */
#ifndef GLINT_METHOD_HF3_PARTS_H
#define GLINT_METHOD_HF3_PARTS_H

#include <stddef.h>

#include "method_hf3.h"

int hf3_reg_parse(const char *text, void *field, glint_err *err);
void hf3_reg_format(const void *field, char *buf, size_t len);
int hf3_map_parse(const char *text, void *field, glint_err *err);
void hf3_map_format(const void *field, char *buf, size_t len);
extern const char *const hf3_model_values[], *const hf3_precision_values[],
    *const hf3_route_values[], *const hf3_reg_examples[], *const hf3_map_examples[];

/* The parameter rows of hf3 for a params struct T holding a fit_params at
 * member path P ("" for fit_params itself, "hf." for one inside). */
#define HF3_PARAM_ROWS(T, P)                                                                    \
    {.name = "res", .label = "detail", .type = METHOD_PARAM_INT, .affects = "precomputation",                                          \
     .description = "texels per factor: accuracy up to about 128 at a 128x128 raster; "         \
                    "precomputation grows as res^3",                                            \
     .offset = offsetof(T, P res), .min = HF_RES_MIN, .max = HF_RES_MAX},                       \
    {.name = "lambda", .label = "smoothing", .type = METHOD_PARAM_NUMBER, .affects = "precomputation",                \
     .description = "weight of the Laplacian smoothing rows",                                   \
     .offset = offsetof(T, P lambda), .min = 0.0, .max = HF_LAMBDA_MAX},                        \
    {.name = "regularization", .label = "pseudo-inverse", .group = METHOD_GROUP_ADVANCED, .option = "reg", .type = METHOD_PARAM_TEXT,                      \
     .affects = "operator",                                                                     \
     .description = "regularized pseudo-inverse (paper eq. 6-8); full rank is the measured best", \
     .offset = offsetof(T, P reg),                                                              \
     .syntax = "trunc[:full|:K|:P%|:relT] | tikhonov:ALPHA|:relT | linear[:full|:K|:P%]",       \
     .examples = hf3_reg_examples, .parse = hf3_reg_parse, .format = hf3_reg_format},           \
    {.name = "mapping", .label = "log mapping", .group = METHOD_GROUP_ADVANCED, .option = "map", .type = METHOD_PARAM_TEXT, .affects = "fit",           \
     .description = "mapping to log space (section 3.4)", .offset = offsetof(T, P map),         \
     .syntax = "log | add[:a] | sub[:margin], optionally ,eps=E", .examples = hf3_map_examples, \
     .parse = hf3_map_parse, .format = hf3_map_format},                                         \
    {.name = "model", .label = "what the factors fit", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "fit",                              \
     .description = "radiance: factors approximate the painted value; brdf: painted / cos_i",   \
     .offset = offsetof(T, P model), .values = hf3_model_values},                               \
    {.name = "precision", .label = "operator precision", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "operator",                     \
     .description = "precision of the stored operator", .offset = offsetof(T, P prec),          \
     .values = hf3_precision_values},                                                           \
    {.name = "route", .label = "decomposition route", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "precomputation",                   \
     .description = "eig: eigendecomposition of B^T B (fast); svd: dense SVD of B (reference)", \
     .offset = offsetof(T, P route), .values = hf3_route_values},                               \
    {.name = "rcond", .label = "rank cutoff", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "precomputation",                 \
     .description = "relative singular-value cutoff of the numerical rank",                     \
     .offset = offsetof(T, P rcond), .min = 1e-16, .max = 1.0, .max_exclusive = 1}

#define HF3_NLEVELS 2
/* decomposition, operator (method_hf3.h): keyed from the fit_params at the
 * start of the params struct, so that a method whose params begin with
 * one shares hf3's cached levels */
extern const method_level hf3_levels[HF3_NLEVELS];
extern const material_ops hf3_material_ops;
int hf3_holdout_ok(const void *params);
size_t hf3_fit_bytes(const void *params, long nsamples);
double hf3_fit_seconds(const void *params, long nsamples);

#endif
