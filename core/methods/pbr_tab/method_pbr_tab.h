/* method_pbr_tab.h: the pbr_tab method: a physically based fit
 * (method_pbr.h) as the base, corrected by a table over half and
 * difference angles (tab.h) fitted to what the base leaves.
 *
 * Conventions.  Painted values are radiance per unit light, f ci
 * (method.h).  The material is, per channel c,
 *
 *   add (the default):  value_c = max(f_base_c(wi, wo) + r_c(theta_h, theta_d), 0) ci
 *   multiply:           value_c = f_base_c(wi, wo) ci max(r_c(theta_h, theta_d), 0)
 *
 * with f_base the pbr BRDF (without the cosine) and r a table over
 * Rusinkiewicz's half and difference angles on tab.h's grid (bilinear;
 * phi_d ignored, so the product is reciprocal as both parts are).  r is
 * linear in the painting (tab_solve_scaled): per channel it minimizes the
 * squared error of the value itself, normalized by the mean square of
 * the table's rows, plus lambda times the table's squared second
 * differences plus pull ||r - identity||^2 (identity: 0 added, 1
 * multiplied), r >= 0 when multiplied.  Where painted samples reach, r
 * follows them as the tab method's table does; where none does (lights or
 * views beyond the painted range), the pull returns r to its identity, the
 * base alone, which extrapolates by its physics.  An exact base leaves r
 * at its identity on every node.
 *
 * Why add is the default: on seven measured materials (docs/methods.md,
 * "The physical fit with a painted table") the added table predicted new
 * views at 1.4% median (2.4% at the 90th percentile), the multiplied one at
 * 2.0% to 3.3% (3.2% to 7.4%).  Multiplied, r must hold painted / f_base,
 * which varies within a cell by as much as f_base does where the base is
 * dark (a metal's kd near 0 off its lobe).
 *
 * Levels, each keyed exactly as the method it comes from keys it, so a
 * direct pbr or tab fit of the same views shares the cache entries:
 *   pbr-geom    pbr's per-sample cosines
 *   tab-design  tab's per-sample cells and weights (grid res_h x res_d)
 * The table's Gram matrix depends on the base when multiplied (its rows
 * are scaled by f_base), so it is built and factored in the fit: 2 nodes^2
 * doubles.
 *
 * The material's info: "params"; "base": the pbr fit's own report
 * (determined and undetermined parameters, at_bound, notes, its errors);
 * "correction": {"combine", "nodes", "reached", "solve" (per channel
 * iterations, nodes at 0, KKT residual, base_black: the base is 0 on every
 * sample), "range" of r over the reached nodes, "rms_painted_base" and
 * "rms_painted": the base alone and the product on the painted samples,
 * per unit light}; "errors" of the product (rms_painted, max_abs_painted,
 * rms_by_view); "precomputation" and "seconds".
 *
 * Manifest members (material.json): "base": pbr's members (fresnel,
 * diffuse, lobes), "table": tab's members (res_h, res_d, table), each
 * validated on reading by its own method, "combine": "add"|"multiply".
 *
 * Thread-safety: as method.h. */
#ifndef GLINT_METHOD_PBR_TAB_H
#define GLINT_METHOD_PBR_TAB_H

#include "material.h"
#include "method.h"
#include "method_pbr.h"
#include "method_tab.h"

extern const method method_pbr_tab;
extern const material_ops pbr_tab_material_ops;

/* Parameters: pbr's, tab's (grid, lambda, nonneg), the pull to the
 * identity and how the table applies. */
enum { PBR_TAB_ADD = 0, PBR_TAB_MULTIPLY = 1 };

typedef struct pbr_tab_params {
    pbr_params pbr;
    tab_params tab;
    double pull;
    int combine;        /* PBR_TAB_ADD or PBR_TAB_MULTIPLY */
} pbr_tab_params;

/* A material's data: the base and the correction table, both owned. */
typedef struct pbr_tab_material {
    pbr_material base;
    tab_material table;  /* the correction, added or multiplied (combine) */
    int combine;
} pbr_tab_material;

/* The data of a pbr_tab material, or NULL for another method's. */
const pbr_tab_material *pbr_tab_material_of(const material *m);

/* A material of this method from a pbr material's data and a correction
 * table (its values moved in, table->t set to NULL) and info (one reference
 * stolen).  GLINT_ENOMEM: all released. */
int pbr_tab_material_init(material *m, const pbr_material *base, tab_material *table,
                          int combine, json_t *info, glint_err *err);

#endif
