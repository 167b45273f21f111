/* method_hybrid.h: material maps of four-factor products as a method
 * (seed 000, section 4.2, "the hybrid"): "hybrid".
 *
 *     f(x, wi, wo) = sum_k c_k(uv(x)) f_k(uv(x), wi, wo)
 *
 * each f_k a four-factor product p q r s(u, v) (method_hf4.h) and c_k a
 * coefficient texture, fitted by the maps' iterative residual
 * factorization, joint refinement and back-fitting rounds (matmap.h).
 * The coefficient textures say which material holds where (gold stripes
 * against red plastic); each product's spatial factor lets that material's
 * brightness and colour drift within its region (worn gold, a painted
 * gradient), which the products of the maps method (one BRDF each) cannot.
 *
 * Parameters: hf4's (an hf4_params_t first: the products are fitted by
 * hf4's cached decomposition, keyed as hf4 keys it, so an hf4 fit and a
 * hybrid fit of the same views share it), then the maps' (components,
 * merge, map_res, tolerance, refine, rounds, smooth; method_maps.h).
 *
 * The material is a maps_material (method_maps.h) whose products are hf4
 * materials; on disk as the maps method writes it, with "product": "hf4",
 * the products' log_s in material.json, and spatial.exr / .png holding
 * every product's spatial factor. */
#ifndef GLINT_METHOD_HYBRID_H
#define GLINT_METHOD_HYBRID_H

#include "method.h"
#include "method_hf4.h"

extern const method method_hybrid;

typedef struct hybrid_params {
    hf4_params_t h;    /* first: hf4's level reads it (method_hf4_parts.h) */
    int components;
    int merge;         /* MATMAP_MERGE_LSQ or MATMAP_MERGE_MIN */
    int map_res;
    double tol;
    int refine;
    int rounds;
    double smooth;
} hybrid_params;

#endif
