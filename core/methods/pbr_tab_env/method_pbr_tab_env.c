/* method_pbr_tab_env.c: the pbr_tab_env method's table
 * (method_pbr_tab_env.h): parameters (pbr_env's, the grid, lambda and the
 * pull), pbr_env's levels under their own keys, the fit (the base, the
 * table's rows, the solve, the product's errors), its report and the
 * prediction of held-out views.
 *
 * Defaults: pbr_env's but two lobes, tab's 32 x 16 grid, lambda 1e-8 and
 * pull 1e-6.  Two lobes: on fourteen measured materials under the
 * courtyard (bench_env_measured --every 4, BENCHMARKS.md) the two-lobe base
 * was better on five of the six medians: from 3 views rotated 8.8% against
 * 12.5% and other environment 12.3% against 19.2% (new views worse, 35.6%
 * against 31.0%); from 1 view new views 15.2% against 36.2%, rotated 10.7%
 * against 11.1%, other 14.9% against 15.4%.  On a one-lobe base and four
 * measured materials painted under the courtyard (bench_env_measured
 * --every 14 --lights 256), lambda 1e-10 with pull 1e-10 fitted the
 * painted views closer (0.3% to 2.3% against 0.8% to 3.1%) and predicted
 * new views no better (2.5%, 26.8%, 2.8%, 60.5% against 2.9%, 17.7%,
 * 3.9%, 66.5%); lambda 1e-6 with pull 1e-4 smoothed the table into the
 * base (new views 9.7%, 20.6%, 7.7%, 27.7%).
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_pbr_tab.h"
#include "method_pbr_tab_env.h"

/* ---- parameters ------------------------------------------------------------------------ */

#define ENVP(m) offsetof(pbr_tab_env_params, base.env.m)
#define PBRP(m) offsetof(pbr_tab_env_params, base.pbr.m)

static const method_param pbr_tab_env_params_table[] = {
    PBR_ENV_PARAMS(ENVP, PBRP),
    {.name = "starts", .label = "roughnesses tried", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "starting roughnesses of the base's search; the best fit of them is kept",
     .offset = PBRP(starts), .min = 1, .max = PBR_MAX_STARTS},
    {.name = "res_h", .label = "half-angle nodes", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "nodes of the correction table along the half angle theta_h (uniform in "
                    "sqrt(theta_h), dense near the highlight)",
     .offset = offsetof(pbr_tab_env_params, tab.res_h), .min = TAB_RES_H_MIN,
     .max = TAB_RES_H_MAX},
    {.name = "res_d", .label = "difference-angle nodes", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "nodes of the correction table along the difference angle theta_d",
     .offset = offsetof(pbr_tab_env_params, tab.res_d), .min = TAB_RES_D_MIN,
     .max = TAB_RES_D_MAX},
    {.name = "lambda", .label = "smoothness", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "weight of the correction's smoothness prior (squared second derivatives "
                    "over its grid) against the painting's normalized mean squared error",
     .offset = offsetof(pbr_tab_env_params, tab.lambda), .min = 0.0, .max = 1e3},
    {.name = "pull", .label = "pull to the physical fit", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "weight that draws the correction to 1 (the physical fit alone); it "
                    "decides where the painting says nothing",
     .offset = offsetof(pbr_tab_env_params, pull), .min = 0.0, .max = 1e3},
};

static void pbr_tab_env_params_default(void *p)
{
    pbr_tab_env_params *pp = p;
    memset(pp, 0, sizeof *pp);
    method_pbr_env.params_default(&pp->base);
    method_tab.params_default(&pp->tab);
    pp->base.pbr.lobes = 2;
    pp->tab.lambda = 1e-8;
    pp->tab.nonneg = 1;
    pp->pull = 1e-6;
}

static int pbr_tab_env_params_check(const void *p, glint_err *err)
{
    const pbr_tab_env_params *pp = p;
    int rc = method_pbr_env.params_check ? method_pbr_env.params_check(&pp->base, err) : 0;
    if (!rc && tab_nodes(&(tab_grid){pp->tab.res_h, pp->tab.res_d}) > TAB_MAX_NODES)
        rc = glint_err_set(err, GLINT_EINVAL, "pbr_tab_env: res_h x res_d above %d nodes",
                           TAB_MAX_NODES);
    return rc;
}

static int pbr_tab_env_params_usable(const void *p, const method_source *src,
                                     const char **param, glint_err *err)
{
    return method_pbr_env.params_usable(&((const pbr_tab_env_params *)p)->base, src, param,
                                        err);
}

/* ---- levels: pbr_env's, under pbr_env's params ---------------------------------------- */

enum { LV_LIGHTS, LV_ROWS, LV_TERMS, LV_N };

static void base_key(int k, const void *params, const samples *s, const char *prev, char *key,
                     size_t len)
{
    method_pbr_env.levels[k].key(&((const pbr_tab_env_params *)params)->base, s, prev, key, len);
}

static int base_build(int k, const method_build_in *in, cache_value *out, glint_err *err)
{
    method_build_in c = *in;
    c.params = &((const pbr_tab_env_params *)in->params)->base;
    return method_pbr_env.levels[k].build(&c, out, err);
}

#define BASE_LEVEL(K, NAME)                                                                   \
    static void NAME##_key(const void *params, const samples *s, const char *prev, char *key, \
                           size_t len)                                                        \
    {                                                                                         \
        base_key(K, params, s, prev, key, len);                                               \
    }                                                                                         \
    static int NAME##_build(const method_build_in *in, cache_value *out, glint_err *err)     \
    {                                                                                         \
        return base_build(K, in, out, err);                                                   \
    }
BASE_LEVEL(LV_LIGHTS, lights)
BASE_LEVEL(LV_ROWS, rows)
BASE_LEVEL(LV_TERMS, terms)

static const method_level pbr_tab_env_levels[LV_N] = {
    {.name = "lights", .progress = 0.05, .key = lights_key, .build = lights_build},
    {.name = "rows", .progress = 0.15, .key = rows_key, .build = rows_build},
    {.name = "pbr-env-terms", .progress = 0.25, .key = terms_key, .build = terms_build},
};

/* ---- the table's rows ------------------------------------------------------------------ */

/* What tab_solve_rows' fill reads: the kept rows, their terms, the base
 * and the grid. */
typedef struct rows_ctx {
    const method_fit_in *in;
    const pbr_geom *g;
    const pbr_material *pm;
    tab_grid grid;
    const int *kept;          /* row of the fit's i-th */
    unsigned char *reached;   /* nodes some term weighs (OUT) */
    double scale;             /* painted value to radiance over the intensity */
} rows_ctx;

/* The painted value of row r over the environment's intensity, channel c. */
static double row_target(const rows_ctx *x, int r, int c)
{
    const srbf_visdata *vd = x->in->levels[LV_ROWS];
    int si = vd->rows[r];
    return (double)x->in->rgb[3 * (size_t)si + c] * x->in->s->intensity[si] * x->scale;
}

static int rows_fill(void *cls, int i0, int m, double *A, float *y, glint_err *err)
{
    rows_ctx *x = cls;
    const pbr_geom *g = x->g;
    const pbr_material *pm = x->pm;
    int nodes = tab_nodes(&x->grid), rh = x->grid.res_h;
    const int off[4] = {0, 1, rh, rh + 1};
    (void)err;
    for (int i = 0; i < m; i++) {
        int r = x->kept[i0 + i];
        for (int c = 0; c < 3; c++)
            y[3 * (size_t)i + c] = (float)row_target(x, r, c);
        for (int t = g->off[r]; t < g->off[r + 1]; t++) {
            double f[3], fu, fv, bw[4];
            int k0;
            pbr_brdf(pm->kd, pm->lobe, pm->sp.nlobes, g->ci[t], g->co[t], g->ch[t], g->cd[t], f);
            tab_locate(&x->grid, g->ch[t], g->cd[t], &k0, &fu, &fv);
            bw[0] = (1.0 - fu) * (1.0 - fv);
            bw[1] = fu * (1.0 - fv);
            bw[2] = (1.0 - fu) * fv;
            bw[3] = fu * fv;
            for (int c = 0; c < 3; c++) {
                double v = g->w[3 * (size_t)t + c] * f[c] * g->ci[t];
                double *row = A + ((size_t)c * m + i) * nodes + k0;
                for (int a = 0; a < 4; a++)
                    row[off[a]] += v * bw[a];
            }
            for (int a = 0; a < 4; a++)
                x->reached[k0 + off[a]] |= bw[a] > 0.0;
        }
    }
    return 0;
}

/* Row r's value under the product (OUT v[3], radiance over the
 * intensity); the base's alone in vb[3]. */
static void row_value(const pbr_geom *g, const pbr_material *pm, const tab_grid *grid,
                      const double *table, int r, double v[3], double vb[3])
{
    v[0] = v[1] = v[2] = vb[0] = vb[1] = vb[2] = 0.0;
    for (int t = g->off[r]; t < g->off[r + 1]; t++) {
        double f[3], q[3];
        pbr_brdf(pm->kd, pm->lobe, pm->sp.nlobes, g->ci[t], g->co[t], g->ch[t], g->cd[t], f);
        tab_lookup(grid, table, g->ch[t], g->cd[t], q);
        for (int c = 0; c < 3; c++) {
            double b = g->w[3 * (size_t)t + c] * f[c] * g->ci[t];
            vb[c] += b;
            v[c] += b * fmax(q[c], 0.0);
        }
    }
}

/* ---- the fit ---------------------------------------------------------------------------- */

/* The product's and the base's errors over the kept rows, in the
 * painting's units. */
typedef struct product_err {
    double rms, rms_base, max_abs;
    double view_se[SCENE_MAX_VIEWS];
    long view_n[SCENE_MAX_VIEWS];
} product_err;

static void product_errors(const rows_ctx *x, int n, const double *table, double k,
                           product_err *e)
{
    const srbf_visdata *vd = x->in->levels[LV_ROWS];
    double ss = 0.0, sb = 0.0;
    memset(e, 0, sizeof *e);
    for (int i = 0; i < n; i++) {
        int r = x->kept[i], v = x->in->s->view[vd->rows[r]];
        double p[3], b[3], sq = 0.0;
        row_value(x->g, x->pm, &x->grid, table, r, p, b);
        for (int c = 0; c < 3; c++) {
            double y = row_target(x, r, c), d = (p[c] - y) * k;
            sq += d * d;
            sb += (b[c] - y) * (b[c] - y) * k * k;
            e->max_abs = fmax(e->max_abs, fabs(d));
        }
        ss += sq;
        if (v >= 0 && v < SCENE_MAX_VIEWS) {
            e->view_se[v] += sq;
            e->view_n[v]++;
        }
    }
    e->rms = n ? sqrt(ss / (3.0 * n)) : 0.0;
    e->rms_base = n ? sqrt(sb / (3.0 * n)) : 0.0;
}

/* The table's range over the nodes the rows reach (OUT lo, hi; 1 when none). */
static void table_range(const tab_grid *grid, const double *t, const unsigned char *reached,
                        double lo[3], double hi[3])
{
    for (int c = 0; c < 3; c++) {
        lo[c] = INFINITY;
        hi[c] = -INFINITY;
    }
    for (int k = 0; k < tab_nodes(grid); k++)
        for (int c = 0; c < 3 && reached[k]; c++) {
            lo[c] = fmin(lo[c], t[3 * (size_t)k + c]);
            hi[c] = fmax(hi[c], t[3 * (size_t)k + c]);
        }
    for (int c = 0; c < 3; c++)
        if (lo[c] > hi[c])
            lo[c] = hi[c] = 1.0;
}

static json_t *report(const method_fit_in *in, json_t *base_info, const rows_ctx *x,
                      const double *t, const tab_solve_report *sr, const product_err *e,
                      double t_base, double t0)
{
    int nodes = tab_nodes(&x->grid), reached = 0;
    double lo[3], hi[3];
    for (int k = 0; k < nodes; k++)
        reached += x->reached[k];
    table_range(&x->grid, t, x->reached, lo, hi);
    return json_pack(
        "{s:o, s:o*, s:{s:s, s:i, s:i, s:{s:[i,i,i], s:[i,i,i], s:[f,f,f], s:[i,i,i]}, "
        "s:{s:[f,f,f], s:[f,f,f]}, s:f, s:f, s:s}, s:{s:s, s:s, s:i}, "
        "s:{s:f, s:f, s:f}, s:{s:f, s:f, s:o}}",
        "params", method_params_to_json(&method_pbr_tab_env, in->params), "base", base_info,
        "correction", "combine", "multiply", "nodes", nodes, "reached", reached, "solve",
        "iterations", sr->iterations[0], sr->iterations[1], sr->iterations[2], "at_zero",
        sr->at_zero[0], sr->at_zero[1], sr->at_zero[2], "kkt_residual", sr->kkt[0], sr->kkt[1],
        sr->kkt[2], "base_black", sr->scale_zero[0], sr->scale_zero[1], sr->scale_zero[2],
        "range", "min", lo[0], lo[1], lo[2], "max", hi[0], hi[1], hi[2], "rms_painted_base",
        e->rms_base, "rms_painted", e->rms, "rule",
        "value = sum over the lights of P f_base ci r(theta_h, theta_d) per channel; r fitted "
        "to the painting with a smoothness prior and a pull to 1 where no light reaches",
        "precomputation", "pattern_hash", in->s->hash, "cache_key", in->keys[LV_TERMS],
        "samples", in->s->n, "seconds", "samples",
        in->pattern_seconds, "base", t_base, "fit", glint_now() - t0, "errors", "rms_painted",
        e->rms, "max_abs_painted", e->max_abs, "rms_by_view",
        method_rms_by_view(e->view_se, e->view_n, in->s->nviews));
}

/* The base: pbr_env's fit on its own params (the same levels). */
static int fit_base(const method_fit_in *in, material *bm, glint_err *err)
{
    method_fit_in c = *in;
    c.params = &((const pbr_tab_env_params *)in->params)->base;
    c.memo = NULL;
    c.view_tags = NULL;
    c.values_change = NULL;
    return method_pbr_env.fit(&c, bm, err);
}

/* The rows the table is fitted to: those not held out (OUT kept, *n). */
static int *kept_rows(const method_fit_in *in, int *n)
{
    const srbf_visdata *vd = in->levels[LV_ROWS];
    int *kept = malloc(sizeof(int) * (size_t)(vd->nrows ? vd->nrows : 1)), k = 0;
    for (int r = 0; kept && r < vd->nrows; r++)
        if (!in->held || !in->held[vd->rows[r]])
            kept[k++] = r;
    *n = k;
    return kept;
}

static int pbr_tab_env_fit(const method_fit_in *in, material *out, glint_err *err)
{
    const pbr_tab_env_params *p = in->params;
    const pbr_env_terms *terms = in->levels[LV_TERMS];
    tab_scaled_opts o = {.lambda = p->tab.lambda, .pull = p->pull, .target = 1.0, .nonneg = 1};
    double t0 = glint_now(), t1;
    material bm = {0};
    tab_material table = {{p->tab.res_h, p->tab.res_d}, NULL};
    rows_ctx x = {.in = in, .g = &terms->g, .grid = table.g,
                  .scale = 1.0 / p->base.env.env_intensity};
    tab_solve_report sr;
    product_err e;
    json_t *info;
    int n = 0, rc;

    memset(out, 0, sizeof *out);
    if ((rc = fit_base(in, &bm, err))) /* checks the painting's values */
        return rc;
    t1 = glint_now();
    x.pm = pbr_material_of(&bm);
    x.kept = kept_rows(in, &n);
    x.reached = calloc((size_t)tab_nodes(&table.g), 1);
    table.t = malloc(3 * sizeof(double) * (size_t)tab_nodes(&table.g));
    if (!x.kept || !x.reached || !table.t) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory (%d rows)", terms->g.n);
        goto done;
    }
    if ((rc = tab_solve_rows(&table.g, n, &o, rows_fill, &x, table.t, &sr, err))) {
        glint_err_prefix(err, "pbr_tab_env: the correction's fit");
        goto done;
    }
    product_errors(&x, n, table.t, p->base.env.env_intensity, &e);
    info = report(in, json_incref(bm.info), &x, table.t, &sr, &e, t1 - t0, t0);
    if (!info) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the report");
        goto done;
    }
    if (in->held)
        json_object_set_new(info, "rows_held_out", json_integer(terms->g.n - n));
    /* what the base says of the painting (black, brighter than physical) */
    if (json_object_get(bm.info, "notes"))
        json_object_set(info, "notes", json_object_get(bm.info, "notes"));
    if (!(rc = pbr_tab_material_init(out, x.pm, &table, PBR_TAB_MULTIPLY, info, err)))
        out->method = &method_pbr_tab_env; /* a pbr_tab material, made by this method */
done:
    free((void *)x.kept);
    free(x.reached);
    free(table.t);
    material_free(&bm);
    return rc;
}

/* The painted values the material gives the fitted pixels under the
 * environment (NaN elsewhere), as pbr_env's predict. */
static int pbr_tab_env_predict(const method_fit_in *in, const material *m, float *rgb,
                               glint_err *err)
{
    const pbr_tab_env_params *p = in->params;
    const srbf_visdata *vd = in->levels[LV_ROWS];
    const pbr_env_terms *terms = in->levels[LV_TERMS];
    const pbr_tab_material *tm = pbr_tab_material_of(m);
    const samples *s = in->s;

    if (!tm || tm->combine != PBR_TAB_MULTIPLY)
        return glint_err_set(err, GLINT_EINVAL, "the material is not a multiplied pbr_tab "
                                                "material");
    for (size_t i = 0; i < (size_t)3 * s->n; i++)
        rgb[i] = NAN;
    for (int r = 0; r < terms->g.n; r++) {
        int si = vd->rows[r];
        double v[3], vb[3];
        row_value(&terms->g, &tm->base, &tm->table.g, tm->table.t, r, v, vb);
        for (int c = 0; c < 3; c++)
            rgb[3 * (size_t)si + c] = (float)(v[c] * p->base.env.env_intensity);
    }
    return 0;
}

/* ---- what a fit costs ------------------------------------------------------------------ */

/* pbr_env's, the table's Gram matrices, factor and solver scratch (4
 * nodes^2 doubles), three blocks of 128 rows, and the product's report. */
static size_t pbr_tab_env_fit_bytes(const void *params, long nsamples)
{
    const pbr_tab_env_params *p = params;
    double nodes = (double)p->tab.res_h * p->tab.res_d;
    double b = (double)method_fit_bytes(&method_pbr_env, &p->base, nsamples) +
               8.0 * (4.0 * nodes * nodes + 3.0 * 128.0 * nodes) + 16.0 * nodes;
    return b >= (double)SIZE_MAX ? SIZE_MAX : (size_t)b;
}

/* pbr_env's, the rows' terms twice more (the table's rows and the
 * errors: 60 ns a term), and three dsyrk of rows x nodes^2 at 5 GFLOP/s.
 * Rows: at most the raster's pixels in 12 views, as pbr_env counts them. */
static double pbr_tab_env_fit_seconds(const void *params, long nsamples)
{
    const pbr_tab_env_params *p = params;
    double nodes = (double)p->tab.res_h * p->tab.res_d, rows = (double)nsamples;
    if (p->base.env.raster.w > 0 && rows > 12.0 * p->base.env.raster.w * p->base.env.raster.h)
        rows = 12.0 * p->base.env.raster.w * p->base.env.raster.h;
    return method_fit_seconds(&method_pbr_env, &p->base, nsamples) +
           rows * p->base.env.lights / 2.0 * 60e-9 + 3.0 * rows * nodes * nodes * 2.0 / 5e9;
}

static int pbr_tab_env_holdout_ok(const void *params)
{
    return method_pbr_env.holdout_ok(&((const pbr_tab_env_params *)params)->base);
}

const method method_pbr_tab_env = {
    .name = "pbr_tab_env",
    .label = "Physical with a painted correction, under an environment",
    .summary = "A physically based material (diffuse colour, roughness, reflectance) with a "
        "smooth correction that keeps what the painting shows beyond it, fitted to views "
        "painted under an environment.",
    .when = "Use it on a scene painted under an environment when the physical fit is close "
        "but misses some of the look, and the material will be seen from other views or "
        "under other light.",
    .lighting = METHOD_LIGHT_ENV,
    .shows = METHOD_SHOWS_NONE,
    .fits_held = 1,
    .title = "Physically based BRDF times a table over half and difference angles, fitted "
             "under environment light",
    .reference = "Walter, Marschner, Li & Torrance, Microfacet Models for Refraction through "
                 "Rough Surfaces, 2007; Rusinkiewicz, A New Change of Variables for Efficient "
                 "BRDF Representation, 1998; the environment's lights and visibility as in "
                 "Iwasaki, Dobashi, Yoshimoto & Nishita 2009",
    .description =
        "f = f_pbr(wi, wo) max(r(theta_h, theta_d), 0): f_pbr the pbr_env method's fit, r a "
        "table per colour channel on a res_h x res_d grid over the half and difference "
        "angles (bilinear, phi_d ignored: reciprocal). Each fitted pixel sums the lights it "
        "sees, each light with its own cell, so the pixel is linear in r: r is fitted by "
        "non-negative least squares on the normal equations with a smoothness prior "
        "(lambda) and a pull (pull) to 1 that returns the material to the physical fit "
        "where no light and eye of a painted pixel reach. The material is a pbr_tab "
        "material (combine multiply). Points: fit_seconds is the warm fit, rms_painted the "
        "RMS error of the product on the fitted pixels.",
    .held_out = "each painted view left out in turn, predicted under the environment from "
                "the material fitted to the others",
    .schema = "FitParamsPbrTabEnv.json",
    .params_size = sizeof(pbr_tab_env_params),
    .params = pbr_tab_env_params_table,
    .nparams = (int)(sizeof pbr_tab_env_params_table / sizeof pbr_tab_env_params_table[0]),
    .params_default = pbr_tab_env_params_default,
    .params_check = pbr_tab_env_params_check,
    .params_usable = pbr_tab_env_params_usable,
    .pattern_rule = SAMPLES_SEEN,
    .levels = pbr_tab_env_levels,
    .nlevels = LV_N,
    .fit = pbr_tab_env_fit,
    .predict = pbr_tab_env_predict,
    .mat = &pbr_tab_material_ops,
    .holdout_ok = pbr_tab_env_holdout_ok,
    .fit_bytes = pbr_tab_env_fit_bytes,
    .fit_seconds = pbr_tab_env_fit_seconds,
};
