/* method_tab.h: the tab method: an isotropic BRDF tabulated over half and
 * difference angles (tab.h), fitted to point-lit paintings by regularized
 * non-negative least squares, inside glint's method interface (method.h).
 *
 * Levels (each in the cache under its own key):
 *   tab-design    per sample the cell and its bilinear weights, and the
 *                 Gram matrix A'A of the pattern on the grid (res_h, res_d)
 *   tab-operator  H = A'A/N + lambda L'L + ridge I and its Cholesky factor
 *                 (lambda), so that a repaint costs A'y and a solve
 *
 * The material's info holds params, precomputation, seconds and errors
 * (rms_painted, rms_by_view), "cells": {"nodes", "reached", "filled"} (the
 * nodes some sample weighs on, and those the prior alone sets), "solve":
 * per channel the active-set iterations, nodes held at 0 and KKT residual
 * (or the nodes below 0 without the constraint), and "notes": sentences
 * for people (a black painting, one brighter than physical).
 *
 * Manifest members (material.json): "res_h", "res_d", "table": res_d rows
 * (theta_d ascending) of res_h [r, g, b] (theta_h ascending), f per unit
 * light at the nodes of tab.h's grid.
 *
 * Thread-safety: as method.h. */
#ifndef GLINT_METHOD_TAB_H
#define GLINT_METHOD_TAB_H

#include "material.h"
#include "method.h"
#include "tab.h"

extern const method method_tab;
extern const material_ops tab_material_ops;

typedef struct tab_params {
    int res_h, res_d;   /* grid (tab.h) */
    double lambda;      /* smoothness prior */
    int nonneg;         /* 1: t >= 0 */
} tab_params;

/* A material's data: the grid and its table (3 tab_nodes doubles). */
typedef struct tab_material {
    tab_grid g;
    double *t;
} tab_material;

/* ---- for methods built on tab (their params begin with a tab_params) -------------------- */

/* The levels tab-design and tab-operator (method_level's key and build). */
void tab_level_design_key(const void *p, const samples *s, const char *prev, char *key,
                          size_t len);
int tab_level_design_build(const method_build_in *in, cache_value *out, glint_err *err);
void tab_level_operator_key(const void *p, const samples *s, const char *prev, char *key,
                            size_t len);
int tab_level_operator_build(const method_build_in *in, cache_value *out, glint_err *err);

/* Changes a fitted table; OUT *more: what it reports (a new object, or
 * NULL).  Returns 0 or an error. */
typedef int (*tab_adjust_fn)(const method_fit_in *in, tab_material *tm, json_t **more,
                             glint_err *err);

/* tab's fit as method m (in->levels[0..1] tab's levels): the table, then
 * adjust (may be NULL) on it, then tab's report of the result with adjust's
 * report as member adjust_name. */
int tab_fit_as(const method *m, const method_fit_in *in, tab_adjust_fn adjust,
               const char *adjust_name, material *out, glint_err *err);

/* The data of a tab material, or NULL for another method's. */
const tab_material *tab_material_of(const material *m);

void tab_material_free(void *data);

#endif
