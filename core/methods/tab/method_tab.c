/* method_tab.c: the tab method's table (method_tab.h): parameters, the
 * tab-design and tab-operator levels, the fit (tab_fit.c) and its report.
 *
 * Defaults, measured on the 64 x 64 sphere painted with six of the MERL
 * materials' published fits (sgd: alum-bronze, gold-metallic-paint2,
 * red-specular-plastic, white-paint, chrome-steel, black-obsidian), errors
 * of new views and of lights beyond the painted range: res_h 32, res_d 16
 * (512 nodes a channel), lambda 1e-10 (1e-8 and above blunt the highlights,
 * 1e-12 and below let the unreached nodes run away: docs/methods.md). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_tab.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const method_param tab_params_table[] = {
    {.name = "res_h", .label = "half-angle nodes", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes of the table along the half angle theta_h (uniform in "
                    "sqrt(theta_h), dense near the highlight)",
     .offset = offsetof(tab_params, res_h), .min = TAB_RES_H_MIN, .max = TAB_RES_H_MAX},
    {.name = "res_d", .label = "difference-angle nodes", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes of the table along the difference angle theta_d (uniform)",
     .offset = offsetof(tab_params, res_d), .min = TAB_RES_D_MIN, .max = TAB_RES_D_MAX},
    {.name = "lambda", .label = "smoothness", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_NUMBER, .affects = "operator",
     .description = "weight of the smoothness prior (the squared second derivatives of the "
                    "table over the unit square of its coordinates) against the mean squared "
                    "error of the painted samples; it also fills the nodes no sample reaches",
     .offset = offsetof(tab_params, lambda), .min = 0.0, .max = 1e3},
    {.name = "nonneg", .label = "non-negative", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "1: the table is kept >= 0 (active-set least squares); 0: unconstrained "
                    "(negative values are read as 0)",
     .offset = offsetof(tab_params, nonneg), .min = 0, .max = 1},
};

static void tab_params_default(void *p)
{
    tab_params *tp = p;
    tp->res_h = 32;
    tp->res_d = 16;
    tp->lambda = 1e-10;
    tp->nonneg = 1;
}

static int tab_params_check(const void *p, glint_err *err)
{
    const tab_params *tp = p;
    if (tp->res_h * tp->res_d > TAB_MAX_NODES)
        return glint_err_set(err, GLINT_EINVAL,
                             "params.res_h x params.res_d (%d x %d) must be at most %d nodes",
                             tp->res_h, tp->res_d, TAB_MAX_NODES);
    return 0;
}

/* ---- the levels ------------------------------------------------------------------------- */

void tab_level_design_key(const void *p, const samples *s, const char *prev, char *key,
                          size_t len)
{
    const tab_params *tp = p;
    (void)s;
    snprintf(key, len, "tab-design:%dx%d:%s", tp->res_h, tp->res_d, prev);
}

static void design_free(void *data)
{
    tab_design_free(data);
    free(data);
}

int tab_level_design_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const tab_params *tp = in->params;
    tab_grid g = {tp->res_h, tp->res_d};
    tab_design *d = malloc(sizeof *d);
    int rc, nodes = tab_nodes(&g);
    if (!d)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab design)");
    if (in->progress)
        in->progress(in->progress_cls, "tab-design", 0.4);
    if ((rc = tab_design_build(&g, in->s, d, err))) {
        free(d);
        return rc;
    }
    out->data = d;
    out->bytes = sizeof *d + (size_t)d->n * 20 + (size_t)nodes * nodes * sizeof(double);
    out->free = design_free;
    return 0;
}

void tab_level_operator_key(const void *p, const samples *s, const char *prev, char *key,
                            size_t len)
{
    const tab_params *tp = p;
    (void)s;
    snprintf(key, len, "tab-operator:%.17g:%s", tp->lambda, prev);
}

static void operator_free(void *data)
{
    tab_operator_free(data);
    free(data);
}

int tab_level_operator_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const tab_params *tp = in->params;
    const tab_design *d = in->prev[0];
    tab_operator *op = malloc(sizeof *op);
    int rc;
    if (!op)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab operator)");
    if (in->progress)
        in->progress(in->progress_cls, "tab-operator", 0.7);
    if ((rc = tab_operator_build(d, tp->lambda, op, err))) {
        free(op);
        return rc;
    }
    out->data = op;
    out->bytes = sizeof *op + 2 * (size_t)op->nodes * op->nodes * sizeof(double);
    out->free = operator_free;
    return 0;
}

static const method_level tab_levels[] = {
    {.name = "tab-design", .progress = 0.4, .key = tab_level_design_key,
     .build = tab_level_design_build},
    {.name = "tab-operator", .progress = 0.7, .key = tab_level_operator_key,
     .build = tab_level_operator_build},
};

/* ---- the report ------------------------------------------------------------------------------ */

/* The directional albedo at normal incidence, integral of f cos_o over the
 * hemisphere of wo with wi = n: there theta_h = theta_d = theta_o / 2. */
static void albedo_normal(const tab_material *tm, double a[3])
{
    const int nt = 256;
    a[0] = a[1] = a[2] = 0.0;
    for (int k = 0; k < nt; k++) {
        double to = (k + 0.5) * 0.5 * M_PI / nt, f[3], c = cos(0.5 * to);
        double w = 2.0 * M_PI * cos(to) * sin(to) * 0.5 * M_PI / nt;
        tab_lookup(&tm->g, tm->t, c, c, f);
        for (int e = 0; e < 3; e++)
            a[e] += fmax(f[e], 0.0) * w;
    }
}

/* Squared residuals of the fitted table per view (the values eval gives:
 * negative interpolants read as 0).  OUT: se[nviews], n[nviews], *rms. */
static void fit_errors(const tab_design *d, const samples *s, const float *rgb,
                       const double *t, double *se, long *n, double *rms)
{
    int rh = d->g.res_h;
    const int off[4] = {0, 1, rh, rh + 1};
    double all = 0.0;
    for (int i = 0; i < d->n; i++) {
        double w[4], sq = 0.0;
        tab_design_weights(d, i, w);
        for (int c = 0; c < 3; c++) {
            double p = 0.0;
            for (int a = 0; a < 4; a++)
                p += w[a] * t[3 * (size_t)(d->k0[i] + off[a]) + c];
            p = fmax(p, 0.0) - rgb[3 * (size_t)i + c];
            sq += p * p;
        }
        se[s->view[i]] += sq;
        n[s->view[i]]++;
        all += sq;
    }
    *rms = sqrt(all / (3.0 * d->n));
}

static json_t *report_notes(const float *rgb, int nsamples, const double alb[3])
{
    json_t *notes = json_array();
    int black = 1;
    for (long i = 0; i < 3L * nsamples && black; i++)
        black = rgb[i] == 0.0f;
    if (black)
        json_array_append_new(notes, json_string(
            "the painting is black on every lit sample: the table is 0"));
    if (alb[0] > 1.0 || alb[1] > 1.0 || alb[2] > 1.0)
        json_array_append_new(notes, json_string(
            "the painting is brighter than a physical surface can be: the table's albedo at "
            "normal incidence (albedo_normal) exceeds 1; the table keeps the painted values "
            "(it has no energy bound)"));
    return notes;
}

static json_t *report_solve(const tab_solve_report *r, int nonneg)
{
    if (nonneg)
        return json_pack("{s:s, s:[i,i,i], s:[i,i,i], s:[f,f,f]}", "solver", "active set",
                         "iterations", r->iterations[0], r->iterations[1], r->iterations[2],
                         "at_zero", r->at_zero[0], r->at_zero[1], r->at_zero[2], "kkt_residual",
                         r->kkt[0], r->kkt[1], r->kkt[2]);
    return json_pack("{s:s, s:[i,i,i]}", "solver", "cholesky", "negative", r->negative[0],
                     r->negative[1], r->negative[2]);
}

/* The material's info (a new object, NULL when out of memory). */
static json_t *report(const method *m, const method_fit_in *in, const tab_design *d,
                      const tab_operator *op, const tab_material *tm,
                      const tab_solve_report *sr, double seconds)
{
    const tab_params *tp = in->params;
    int nv = in->s->nviews, nodes = tab_nodes(&d->g);
    double *se = calloc((size_t)nv, sizeof *se), rms = 0.0, alb[3];
    long *n = calloc((size_t)nv, sizeof *n);
    json_t *info = NULL;
    if (se && n) {
        fit_errors(d, in->s, in->rgb, tm->t, se, n, &rms);
        albedo_normal(tm, alb);
        info = json_pack(
            "{s:o, s:{s:s, s:s, s:s, s:s, s:i, s:f}, s:{s:f, s:f}, s:{s:f, s:o}, s:{s:i, s:i, s:i},"
            " s:o, s:[f,f,f], s:o}",
            "params", method_params_to_json(m, in->params), "precomputation", "pattern_hash",
            in->s->hash, "cache_key", in->keys[1], "design_key", in->keys[0], "operator_key",
            in->keys[1], "samples",
            in->s->n, "ridge", op->ridge, "seconds", "samples", in->pattern_seconds, "fit",
            seconds, "errors", "rms_painted", rms, "rms_by_view", method_rms_by_view(se, n, nv),
            "cells", "nodes", nodes, "reached", d->reached, "filled", nodes - d->reached,
            "solve", report_solve(sr, tp->nonneg), "albedo_normal", alb[0], alb[1], alb[2],
            "notes", report_notes(in->rgb, in->s->n, alb));
    }
    free(se);
    free(n);
    return info;
}

/* ---- the fit ---------------------------------------------------------------------------------- */

int tab_fit_as(const method *m, const method_fit_in *in, tab_adjust_fn adjust,
               const char *adjust_name, material *out, glint_err *err)
{
    const tab_params *tp = in->params;
    const tab_design *d = in->levels[0];
    const tab_operator *op = in->levels[1];
    double t0 = glint_now();
    tab_solve_report sr;
    tab_material *tm;
    json_t *info, *more = NULL;
    int rc;

    for (long i = 0; i < 3L * in->s->n; i++)
        if (!isfinite(in->rgb[i]))
            return glint_err_set(err, GLINT_ENONFINITE, "%s: painted value %ld is not finite",
                                 m->name, i / 3);
    if (d->n != in->s->n || op->nodes != tab_nodes(&d->g))
        return glint_err_set(err, GLINT_EINTERNAL, "%s: levels of another pattern", m->name);
    if (!(tm = calloc(1, sizeof *tm)) ||
        !(tm->t = malloc(3 * (size_t)op->nodes * sizeof *tm->t))) {
        tab_material_free(tm);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab table)");
    }
    tm->g = d->g;
    if ((rc = tab_solve(d, op, in->rgb, tp->nonneg, tm->t, &sr, err)) ||
        (adjust && (rc = adjust(in, tm, &more, err)))) {
        tab_material_free(tm);
        return rc;
    }
    if (!(info = report(m, in, d, op, tm, &sr, glint_now() - t0)) ||
        (more && json_object_set_new(info, adjust_name, more))) {
        if (!info)
            json_decref(more);
        json_decref(info);
        tab_material_free(tm);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab report)");
    }
    material_init(out, m, tm, info);
    return 0;
}

static int tab_method_fit(const method_fit_in *in, material *out, glint_err *err)
{
    return tab_fit_as(&method_tab, in, NULL, NULL, out, err);
}

static size_t tab_fit_bytes(const void *params, long nsamples)
{
    const tab_params *tp = params;
    size_t nodes = (size_t)tp->res_h * tp->res_d;
    /* the pattern (about 100 bytes a sample), the design (20), the painted
     * values; A'A, H, its factor and the active set's scratch (about 3 more
     * nodes x nodes) */
    return (size_t)nsamples * 160 + 6 * nodes * nodes * sizeof(double);
}

static double tab_fit_seconds(const void *params, long nsamples)
{
    const tab_params *tp = params;
    double nodes = (double)tp->res_h * tp->res_d;
    /* the passes over the samples, then the factor and three solves: cold
     * fits of the 64 x 64 sphere (11 views, about 22,500 samples) took 0.05 s at
     * 512 nodes, 0.6 s at 1152, 3 to 6 s at 2048 and 22 to 27 s at 4050
     * with the constraint (the active set's steps grow as nodes^3: 0.2 of
     * method_dense_seconds), 0.2 s at 2048 and 1.2 s at 4050 without it */
    return METHOD_SECONDS_PER_SAMPLE * nsamples +
           (tp->nonneg ? 0.2 : 0.01) * method_dense_seconds(nodes);
}

const method method_tab = {
    .name = "tab",
    .label = "Measured-style table",
    .summary = "One material as a table over the angles of the highlight (half and "
        "difference angles), smooth where the painting says nothing.",
    .when = "Use it when no physical model fits the look but the material is the same in "
        "every direction around the normal: the table follows the painting more freely.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_NONE,
    .title = "Isotropic BRDF tabulated over half and difference angles, smoothness prior, "
        "non-negative least squares",
    .reference = "Rusinkiewicz, A New Change of Variables for Efficient BRDF Representation, "
                 "1998; Matusik, Pfister, Brand & McMillan, A Data-Driven Reflectance Model, "
                 "2003",
    .description =
        "f(theta_h, theta_d) per colour channel on a res_h x res_d grid (theta_h uniform in "
        "its square root as MERL's tables are, theta_d uniform; phi_d ignored), bilinear "
        "between nodes; reciprocal by construction. The painted values are linear in the "
        "table; per channel it minimizes the mean squared error plus lambda times the "
        "squared second differences along both axes (which also fills the nodes no sample "
        "reaches, continuing their neighbours linearly), subject to t >= 0, on the Gram form "
        "(nodes x nodes, cached with its factor: a repaint costs one pass over the samples "
        "and three solves). Points: fit_seconds is the warm fit, rms_painted the RMS error "
        "on the painted samples.",
    .schema = "FitParamsTab.json",
    .params_size = sizeof(tab_params),
    .params = tab_params_table,
    .nparams = (int)(sizeof tab_params_table / sizeof tab_params_table[0]),
    .params_default = tab_params_default,
    .params_check = tab_params_check,
    .levels = tab_levels,
    .nlevels = (int)(sizeof tab_levels / sizeof tab_levels[0]),
    .fit = tab_method_fit,
    .mat = &tab_material_ops,
    .fit_bytes = tab_fit_bytes,
    .fit_seconds = tab_fit_seconds,
};
