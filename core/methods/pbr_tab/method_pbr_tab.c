/* method_pbr_tab.c: the pbr_tab method's table (method_pbr_tab.h):
 * parameters (pbr's, tab's grid and prior, the pull to 1), the levels of
 * both keyed as they key them, the fit (the base, the correction table, the
 * product's errors) and its report.
 *
 * Defaults, measured on seven measured materials' published fits painted
 * on the 64 x 64 sphere from 12 views (docs/methods.md, "The physical fit
 * with a painted table"): pbr's single dielectric lobe, tab's 32 x 16 grid
 * and lambda 1e-10, the table added, pull 1e-10.  New views' median error (and
 * beyond the painted range) by pull: 3.0% (25.4%) at 1e-4, 1.6% (25.2%)
 * at 1e-6, 1.5% (24.2%) at 1e-8, 1.4% (23.5%, 22.6%) at 1e-9 and 1e-10.
 * Multiplied, at 1e-8: 3.3% (25.1%). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_pbr_tab.h"

/* ---- parameters ------------------------------------------------------------------------ */

static const char *const fresnel_values[] = {"dielectric", "conductor", NULL};
static const char *const combine_values[] = {"add", "multiply", NULL};

static const method_param pbr_tab_params_table[] = {
    {.name = "lobes", .label = "highlight layers", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "GGX lobes of the base: 1 (one highlight) or 2 (a sharp highlight over a "
                    "broad sheen)",
     .offset = offsetof(pbr_tab_params, pbr.lobes), .min = 1, .max = PBR_MAX_LOBES},
    {.name = "fresnel", .label = "kind of surface", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_ENUM, .affects = "fit",
     .description = "the base's Fresnel: dielectric (plastic, paint, wood) or conductor "
                    "(metal: a reflectance per colour channel)",
     .offset = offsetof(pbr_tab_params, pbr.fresnel), .values = fresnel_values},
    {.name = "starts", .label = "roughnesses tried", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "starting roughnesses of the base's search; the best fit of them is kept",
     .offset = offsetof(pbr_tab_params, pbr.starts), .min = 1, .max = PBR_MAX_STARTS},
    {.name = "res_h", .label = "half-angle nodes", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes of the correction table along the half angle theta_h (uniform in "
                    "sqrt(theta_h), dense near the highlight)",
     .offset = offsetof(pbr_tab_params, tab.res_h), .min = TAB_RES_H_MIN, .max = TAB_RES_H_MAX},
    {.name = "res_d", .label = "difference-angle nodes", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes of the correction table along the difference angle theta_d",
     .offset = offsetof(pbr_tab_params, tab.res_d), .min = TAB_RES_D_MIN, .max = TAB_RES_D_MAX},
    {.name = "lambda", .label = "smoothness", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "weight of the correction's smoothness prior (squared second derivatives "
                    "over its grid) against the painting's normalized mean squared error",
     .offset = offsetof(pbr_tab_params, tab.lambda), .min = 0.0, .max = 1e3},
    {.name = "pull", .label = "pull to the physical fit", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "weight that draws the correction to its identity (the physical fit "
                    "alone); it decides where the painting says nothing (lights and views "
                    "beyond the painted range)",
     .offset = offsetof(pbr_tab_params, pull), .min = 0.0, .max = 1e3},
    {.name = "combine", .label = "how the correction applies", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_ENUM, .affects = "fit",
     .description = "add: the table is added to the physical BRDF (robust where the physical "
                    "fit is dark); multiply: the table scales it",
     .offset = offsetof(pbr_tab_params, combine), .values = combine_values},
};

static void pbr_tab_params_default(void *p)
{
    pbr_tab_params *pp = p;
    method_pbr.params_default(&pp->pbr);
    method_tab.params_default(&pp->tab);
    pp->pull = 1e-10;
    pp->combine = PBR_TAB_ADD;
}

static int pbr_tab_params_check(const void *p, glint_err *err)
{
    const pbr_tab_params *pp = p;
    int rc = method_pbr.params_check ? method_pbr.params_check(&pp->pbr, err) : 0;
    return rc ? rc : method_tab.params_check(&pp->tab, err);
}

/* ---- levels: pbr's, then tab's design, each under its own params ----------------------- */

static void geom_key(const void *params, const samples *s, const char *prev_key, char *key,
                     size_t len)
{
    method_pbr.levels[0].key(&((const pbr_tab_params *)params)->pbr, s, prev_key, key, len);
}

static int geom_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    method_build_in c = *in;
    c.params = &((const pbr_tab_params *)in->params)->pbr;
    c.prev = NULL;
    c.level = 0;
    return method_pbr.levels[0].build(&c, out, err);
}

static void design_key(const void *params, const samples *s, const char *prev_key, char *key,
                       size_t len)
{
    (void)prev_key; /* tab keys its design from the pattern alone */
    method_tab.levels[0].key(&((const pbr_tab_params *)params)->tab, s, s->hash, key, len);
}

static int design_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    method_build_in c = *in;
    c.params = &((const pbr_tab_params *)in->params)->tab;
    c.prev = NULL;
    c.level = 0;
    return method_tab.levels[0].build(&c, out, err);
}

enum { LV_GEOM, LV_DESIGN, LV_N };

static const method_level pbr_tab_levels[LV_N] = {
    {.name = "pbr-geom", .progress = 0.05, .key = geom_key, .build = geom_build},
    {.name = "tab-design", .progress = 0.3, .key = design_key, .build = design_build},
};

/* ---- the fit ---------------------------------------------------------------------------- */

/* The product's errors on the painted samples (per unit light). */
typedef struct product_err {
    double rms, max_abs, rms_base;
    double view_se[SCENE_MAX_VIEWS];
    long view_n[SCENE_MAX_VIEWS];
} product_err;

static int check_finite(const method_fit_in *in, glint_err *err)
{
    for (long i = 0; i < 3L * in->s->n; i++)
        if (!isfinite(in->rgb[i]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "pbr_tab: painted value %ld (sample %ld, channel %ld) is not "
                                 "finite",
                                 i, i / 3, i % 3);
    return 0;
}

/* The base: pbr's fit on its own level and params. */
static int fit_base(const method_fit_in *in, material *bm, glint_err *err)
{
    method_fit_in c = *in;
    c.params = &((const pbr_tab_params *)in->params)->pbr;
    c.memo = NULL;
    c.view_tags = NULL;
    c.values_change = NULL;
    return method_pbr.fit(&c, bm, err);
}

/* f_base at every sample and channel (OUT fb[3 n]), from pbr-geom's cosines. */
static void base_values(const method_fit_in *in, const pbr_material *pm, float *fb)
{
    const pbr_geom *g = in->levels[LV_GEOM];
    for (long i = 0; i < in->s->n; i++) {
        double f[3] = {0, 0, 0};
        if (g->ci[i] > 0.0 && g->co[i] > 0.0)
            pbr_brdf(pm->kd, pm->lobe, pm->sp.nlobes, g->ci[i], g->co[i], g->ch[i], g->cd[i], f);
        for (int c = 0; c < 3; c++)
            fb[3 * i + c] = (float)f[c];
    }
}

/* What the table is fitted to (OUT scale[3 n], y[3 n]): with multiply,
 * the painting itself with f_base as each row's scale; with add, the
 * painting less the base's value, rows unscaled. */
static void correction_problem(const method_fit_in *in, int combine, const float *fb,
                               const double *ci, float *scale, float *y)
{
    for (long i = 0; i < 3L * in->s->n; i++) {
        if (combine == PBR_TAB_MULTIPLY) {
            scale[i] = fb[i];
            y[i] = in->rgb[i];
        } else {
            scale[i] = 1.0f;
            y[i] = (float)(in->rgb[i] - fb[i] * ci[i / 3]);
        }
    }
}

/* The product's errors: the table at each sample's cell. */
static void product_errors(const method_fit_in *in, const tab_design *d, int combine,
                           const float *fb, const double *t, product_err *e)
{
    const samples *s = in->s;
    const int off[4] = {0, 1, d->g.res_h, d->g.res_h + 1};
    double ss = 0.0, sb = 0.0;
    memset(e, 0, sizeof *e);
    for (long i = 0; i < s->n; i++) {
        double w[4], sq = 0.0;
        int v = s->view ? s->view[i] : 0;
        tab_design_weights(d, (int)i, w);
        for (int c = 0; c < 3; c++) {
            double r = 0.0, y = in->rgb[3 * i + c], b = fb[3 * i + c] * d->ci[i];
            if (combine == PBR_TAB_MULTIPLY) {
                for (int a = 0; a < 4; a++)
                    r += w[a] * fmax(t[3 * (size_t)(d->k0[i] + off[a]) + c], 0.0);
                r = fb[3 * i + c] * r - y; /* w carries ci */
            } else {
                for (int a = 0; a < 4; a++)
                    r += w[a] * t[3 * (size_t)(d->k0[i] + off[a]) + c];
                r = fmax(b + r, 0.0) - y;
            }
            sq += r * r;
            sb += (b - y) * (b - y);
            e->max_abs = fmax(e->max_abs, fabs(r));
        }
        ss += sq;
        if (v >= 0 && v < SCENE_MAX_VIEWS) {
            e->view_se[v] += sq;
            e->view_n[v]++;
        }
    }
    e->rms = s->n ? sqrt(ss / (3.0 * (double)s->n)) : 0.0;
    e->rms_base = s->n ? sqrt(sb / (3.0 * (double)s->n)) : 0.0;
}

/* The range of the table over the nodes some sample reaches (OUT lo[3], hi[3]). */
static void table_range(const tab_design *d, const double *t, double lo[3], double hi[3])
{
    int nodes = tab_nodes(&d->g);
    for (int c = 0; c < 3; c++) {
        lo[c] = INFINITY;
        hi[c] = -INFINITY;
    }
    for (int k = 0; k < nodes; k++) {
        if (!(d->gram[(size_t)k * nodes + k] > 0.0))
            continue;
        for (int c = 0; c < 3; c++) {
            lo[c] = fmin(lo[c], t[3 * (size_t)k + c]);
            hi[c] = fmax(hi[c], t[3 * (size_t)k + c]);
        }
    }
    for (int c = 0; c < 3; c++)
        if (lo[c] > hi[c])
            lo[c] = hi[c] = 1.0;
}

static json_t *report_correction(const tab_design *d, const double *t,
                                 const tab_solve_report *sr, const product_err *e, int combine)
{
    double lo[3], hi[3];
    table_range(d, t, lo, hi);
    return json_pack("{s:s, s:i, s:i, s:{s:[i,i,i], s:[i,i,i], s:[f,f,f], s:[i,i,i]}, "
                     "s:{s:[f,f,f], s:[f,f,f]}, s:f, s:f, s:s}",
                     "combine", combine == PBR_TAB_MULTIPLY ? "multiply" : "add", "nodes",
                     tab_nodes(&d->g), "reached", d->reached, "solve", "iterations",
                     sr->iterations[0], sr->iterations[1], sr->iterations[2], "at_zero",
                     sr->at_zero[0], sr->at_zero[1], sr->at_zero[2], "kkt_residual", sr->kkt[0],
                     sr->kkt[1], sr->kkt[2], "base_black", sr->scale_zero[0],
                     sr->scale_zero[1], sr->scale_zero[2], "range", "min", lo[0], lo[1], lo[2],
                     "max", hi[0], hi[1], hi[2], "rms_painted_base", e->rms_base,
                     "rms_painted", e->rms, "rule",
                     combine == PBR_TAB_MULTIPLY
                         ? "value = f_base ci r(theta_h, theta_d) per channel; r fitted to the "
                           "painting with a smoothness prior and a pull to 1 where the "
                           "painting says nothing (errors per unit light)"
                         : "value = max(f_base + r(theta_h, theta_d), 0) ci per channel; r "
                           "fitted to what the base leaves with a smoothness prior and a pull "
                           "to 0 where the painting says nothing (errors per unit light)");
}

static json_t *report(const method_fit_in *in, json_t *base_info, const tab_design *d,
                      const double *t, const tab_solve_report *sr, const product_err *e,
                      double t_base, double t0)
{
    int nv = in->s->nviews < SCENE_MAX_VIEWS ? in->s->nviews : SCENE_MAX_VIEWS;
    const pbr_tab_params *p = in->params;
    return json_pack(
        "{s:o, s:o*, s:o, s:{s:s, s:s, s:[s, s], s:i}, s:{s:f, s:f, s:f}, s:{s:f, s:f, s:o}}",
        "params", method_params_to_json(&method_pbr_tab, in->params), "base", base_info,
        "correction", report_correction(d, t, sr, e, p->combine), "precomputation",
        "pattern_hash", in->s->hash, "cache_key", in->keys[LV_DESIGN], "cache_keys",
        in->keys[LV_GEOM], in->keys[LV_DESIGN],
        "samples", in->s->n, "seconds", "samples", in->pattern_seconds, "base", t_base, "fit",
        glint_now() - t0, "errors", "rms_painted", e->rms, "max_abs_painted", e->max_abs,
        "rms_by_view", method_rms_by_view(e->view_se, e->view_n, nv));
}

static int pbr_tab_fit(const method_fit_in *in, material *out, glint_err *err)
{
    const pbr_tab_params *p = in->params;
    const tab_design *d = in->levels[LV_DESIGN];
    int mul = p->combine == PBR_TAB_MULTIPLY;
    tab_scaled_opts o = {.lambda = p->tab.lambda, .pull = p->pull, .target = mul ? 1.0 : 0.0,
                         .nonneg = mul && p->tab.nonneg};
    double t0 = glint_now(), t1;
    material bm = {0};
    tab_material table = {d->g, NULL};
    tab_solve_report sr;
    product_err e;
    float *fb = NULL, *scale, *y;
    json_t *info;
    int rc;

    memset(out, 0, sizeof *out);
    if ((rc = check_finite(in, err)))
        return rc;
    if (d->n != in->s->n)
        return glint_err_set(err, GLINT_EINTERNAL, "pbr_tab: levels of another pattern");
    if ((rc = fit_base(in, &bm, err))) {
        glint_err_prefix(err, "pbr_tab: the base's fit");
        return rc;
    }
    t1 = glint_now();
    fb = malloc((size_t)9 * (in->s->n ? in->s->n : 1) * sizeof *fb);
    table.t = malloc(3 * (size_t)tab_nodes(&d->g) * sizeof *table.t);
    if (!fb || !table.t) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory (%d samples)", in->s->n);
        goto done;
    }
    base_values(in, pbr_material_of(&bm), fb);
    scale = fb + 3 * (size_t)in->s->n;
    y = scale + 3 * (size_t)in->s->n;
    correction_problem(in, p->combine, fb, d->ci, scale, y);
    if ((rc = tab_solve_scaled(d, &o, scale, y, table.t, &sr, err))) {
        glint_err_prefix(err, "pbr_tab: the correction's fit");
        goto done;
    }
    product_errors(in, d, p->combine, fb, table.t, &e);
    info = report(in, json_incref(bm.info), d, table.t, &sr, &e, t1 - t0, t0);
    if (!info) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the report");
        goto done;
    }
    rc = pbr_tab_material_init(out, pbr_material_of(&bm), &table, p->combine, info, err);
done:
    free(fb);
    free(table.t);
    material_free(&bm);
    return rc;
}

/* ---- resources -------------------------------------------------------------------------- */

/* The base's bound, the design's (tab's) and the table's Gram matrix,
 * factor and solver scratch (about 4 nodes^2 doubles), f_base (12 bytes a
 * sample). */
static size_t pbr_tab_fit_bytes(const void *params, long nsamples)
{
    const pbr_tab_params *p = params;
    size_t a = method_fit_bytes(&method_pbr, &p->pbr, nsamples);
    size_t b = method_fit_bytes(&method_tab, &p->tab, nsamples);
    size_t c = (size_t)nsamples * 12;
    return a > SIZE_MAX - b - c ? SIZE_MAX : a + b + c;
}

/* The base's estimate and tab's (its operator is built per fit here). */
static double pbr_tab_fit_seconds(const void *params, long nsamples)
{
    const pbr_tab_params *p = params;
    return method_fit_seconds(&method_pbr, &p->pbr, nsamples) +
           method_fit_seconds(&method_tab, &p->tab, nsamples) +
           (double)nsamples * METHOD_SECONDS_PER_SAMPLE;
}

const method method_pbr_tab = {
    .name = "pbr_tab",
    .label = "Physical, with a painted correction table",
    .summary = "A physically based material (diffuse colour, roughness, Fresnel) with a "
        "smooth correction that keeps what the painting shows beyond it, and fades back to "
        "the physical material where nothing was painted.",
    .when = "Use it when the physical fit is close but misses some of the look, and the "
        "material will be seen under lights or from views you did not paint.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_NONE,
    .title = "Physically based BRDF corrected by a table over half and difference angles",
    .reference = "Walter, Marschner, Li & Torrance, Microfacet Models for Refraction through "
                 "Rough Surfaces, 2007; Rusinkiewicz, A New Change of Variables for Efficient "
                 "BRDF Representation, 1998",
    .description =
        "f = max(f_pbr(wi, wo) + r(theta_h, theta_d), 0) (combine add, the default) or "
        "f_pbr(wi, wo) r(theta_h, theta_d) (multiply): f_pbr the pbr method's fit (kd/pi "
        "plus GGX lobes, height-correlated Smith, Schlick Fresnel), r a table per colour "
        "channel on a res_h x res_d grid over the half and difference angles (bilinear, "
        "phi_d ignored: reciprocal), fitted to the painting by least squares with a "
        "smoothness prior (lambda) and a pull (pull) to the identity that returns the "
        "material to the physical fit where no painted sample reaches. The base's level and "
        "tab's design are shared with direct pbr and tab fits. Points: fit_seconds is the "
        "warm fit, rms_painted the RMS error of the product on the painted samples.",
    .schema = "FitParamsPbrTab.json",
    .params_size = sizeof(pbr_tab_params),
    .params = pbr_tab_params_table,
    .nparams = (int)(sizeof pbr_tab_params_table / sizeof pbr_tab_params_table[0]),
    .params_default = pbr_tab_params_default,
    .params_check = pbr_tab_params_check,
    .levels = pbr_tab_levels,
    .nlevels = LV_N,
    .fit = pbr_tab_fit,
    .mat = &pbr_tab_material_ops,
    .fit_bytes = pbr_tab_fit_bytes,
    .fit_seconds = pbr_tab_fit_seconds,
};
