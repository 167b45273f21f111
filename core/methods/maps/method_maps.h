/* method_maps.h: material maps of three-factor products as a method
 * (seed 000, section 4.2): "maps".
 *
 * A painting of several materials on one object (a gold logo on red
 * plastic, veins in marble) is fitted as
 *
 *     f(x, wi, wo) = sum_k c_k(uv(x)) f_k(wi, wo)
 *
 * each f_k a three-factor product (method_hf3.h) and c_k a coefficient
 * texture over the surface's texture coordinates, by iterative residual
 * factorization (matmap.h: the rules, the stopping reasons, why least
 * squares per texel is the default merge).
 *
 * Parameters: hf3's (a fit_params first: the products are fitted by hf3's
 * levels, keyed as hf3 keys them, so an hf3 fit and a maps fit of the same
 * views share one cached decomposition and operator, and every product
 * reuses it), then
 *   components  at most this many products (1..MATMAP_MAX)
 *   merge       lsq | min: how a product's per-sample scales become a texture
 *   map_res     coefficient texture resolution (MAPS_RES_MIN..MAPS_RES_MAX)
 *   tolerance   stop below this relative RMS of the residual
 *   refine      sweeps of the joint refinement of the coefficients (0: none)
 *   rounds      back-fitting rounds: every product refitted to what the others
 *               leave (0: none)
 *   smooth      smoothness of the coefficient textures in the refinement
 * The mapping of each product's fit defaults to hf3's add:a: the residuals
 * after the first product are clamped at 0 over much of the surface, and a
 * pure log mapping would make those near-zero values dominate the fit
 * (section 3.4); the offset keeps them at log a.
 *
 * The material's data is a maps_material; evaluated at a surface point it
 * reads the coefficients there (bilinear between texel centres, clamped at
 * the border, as uvtex_lookup); without texture coordinates it takes each
 * coefficient's mean over the texture (the average material).  On disk:
 * material.json holds the products' log-factors (as hf3 writes them) and
 * the coefficients' layout; coefficients.exr (float, one channel, map_res
 * wide, components x map_res high: product k's texture in rows
 * k map_res .. (k + 1) map_res - 1, texture row 0 at v = 0 first) holds the
 * textures, and coefficients.png the same in 8 bits. */
#ifndef GLINT_METHOD_MAPS_H
#define GLINT_METHOD_MAPS_H

#include "material.h"
#include "matmap.h"
#include "method.h"
#include "method_hf3.h"

#define MAPS_RES_MIN 2
#define MAPS_RES_MAX 1024
/* components x map_res: the height of coefficients.exr and of the GPU's
 * coefficient rows stay within a texture's usual limit */
#define MAPS_ROWS_MAX 16384

extern const method method_maps;

typedef struct maps_params {
    fit_params hf;     /* first: hf3's levels read it (method_hf3_parts.h) */
    int components;
    int merge;         /* MATMAP_MERGE_LSQ or MATMAP_MERGE_MIN */
    int map_res;
    double tol;
    int refine;        /* sweeps of the joint refinement (matmap.h) */
    int rounds;        /* back-fitting rounds (matmap.h) */
    double smooth;     /* smoothness of the coefficient textures (matmap.h) */
} maps_params;

typedef struct maps_material {
    matmap mm;                   /* products (hf3, hf4 or pbr materials) and coefficient
                                    textures */
    const method *product;       /* the products' method */
    double mean[MATMAP_MAX];     /* each texture's mean: the coefficients without uv */
} maps_material;

/* The maps of a material of maps (method maps, hybrid or pbr_maps; NULL
 * for another method's). */
const matmap *maps_matmap(const material *m);

/* A material of method `self` (maps, hybrid or pbr_maps) from a fitted matmap
 * (moved: *mm is zeroed; its products all of one method) and info (one
 * reference stolen; may be NULL).  GLINT_ENOMEM leaves *m empty. */
int maps_material_init(material *m, const method *self, matmap *mm, json_t *info,
                       glint_err *err);

/* The fragment stage of a maps material (GLSL ES 3.00). */
extern const char maps_glsl_frag[];

#endif
