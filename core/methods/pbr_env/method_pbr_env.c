/* method_pbr_env.c: the pbr_env method's table (method_pbr_env.h):
 * parameters, srbf's lights and rows levels, the terms level, the fit and
 * the prediction of held-out views. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_pbr_env.h"
#include "vis.h"

const char *const pbr_env_fresnel_values[] = {"dielectric", "conductor", NULL};

#define ENVP(m) offsetof(pbr_env_params, env.m)
#define PBRP(m) offsetof(pbr_env_params, pbr.m)

static const method_param pbr_env_params_table[] = {
    PBR_ENV_PARAMS(ENVP, PBRP),
    {.name = "starts", .label = "roughnesses tried", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "starting roughnesses of the search (0.05, 0.15, 0.4, then 0.01, 0.7, "
                    "0.1, 0.25, 0.03); the best fit of them is kept",
     .offset = PBRP(starts), .min = 1, .max = PBR_MAX_STARTS},
    {.name = "max_iter", .label = "iterations per start", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "Levenberg-Marquardt iterations allowed per start and for the final "
                    "refinement",
     .offset = PBRP(max_iter), .min = 1, .max = 10000},
    {.name = "start_iter", .label = "iterations per start on its pixels",
     .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "Levenberg-Marquardt iterations of each start on its pixels (it only has "
                    "to find the basin the refinement then converges in)",
     .offset = PBRP(start_iter), .min = 1, .max = 10000},
    {.name = "start_samples", .label = "pixels per start", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "fitted pixels each start is fitted on (the brightest eighth and an even "
                    "draw of the rest) before the best is refined; 0: all",
     .offset = PBRP(start_samples), .min = 0, .max = 1 << 24},
    {.name = "refine_samples", .label = "pixels refined on", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "fitted pixels the best start is refined on (drawn as the starts' are, "
                    "when more than they); 0: all.  The errors, the uncertainties and what "
                    "the views determine are computed on every fitted pixel",
     .offset = PBRP(refine_samples), .min = 0, .max = 1 << 24},
};

static const method_preset pbr_env_presets[] = {
    {"draft", "{\"lights\": 64, \"raster\": \"32x24\"}"},
    {"default", "{\"lights\": 256, \"raster\": \"64x48\"}"},
    {"fine", "{\"lights\": 1024, \"raster\": \"160x120\", \"refine_samples\": 0}"},
};

static void pbr_env_params_default(void *p)
{
    pbr_env_params *pp = p;
    memset(pp, 0, sizeof *pp);
    method_srbf.params_default(&pp->env);
    method_pbr.params_default(&pp->pbr);
    /* each fitted pixel sums about half the lights: 64 x 48 a view keeps a
     * fit of 3 views near 450,000 terms (20 MB) where srbf's 160 x 120
     * would hold 2.8 million; the parameters are 8, not srbf's hundreds of
     * lobe weights */
    pp->env.raster.w = 64;
    pp->env.raster.h = 48;
    pp->pbr.start_samples = 512;
    pp->pbr.refine_samples = 2048;
    /* ten iterations find the basin: on every eighth measured material under
     * the courtyard (bench_env_measured --every 8 --views 3) the errors were
     * those of 25 to the digit, the warm fit 671 ms against 1152 */
    pp->pbr.start_iter = 10;
}

static int pbr_env_params_usable(const void *p, const method_source *src, const char **param,
                                 glint_err *err)
{
    return method_srbf.params_usable(&((const pbr_env_params *)p)->env, src, param, err);
}

/* ---- levels: srbf's lights and rows, then the terms --------------------------------- */

enum { SRBF_LV_LIGHTS = 1, SRBF_LV_ROWS = 2 };
enum { LV_LIGHTS, LV_ROWS, LV_TERMS, LV_N };

static void lights_key(const void *params, const samples *s, const char *prev, char *key,
                       size_t len)
{
    method_srbf.levels[SRBF_LV_LIGHTS].key(&((const pbr_env_params *)params)->env, s, prev, key,
                                           len);
}

static void rows_key(const void *params, const samples *s, const char *prev, char *key,
                     size_t len)
{
    method_srbf.levels[SRBF_LV_ROWS].key(&((const pbr_env_params *)params)->env, s, prev, key,
                                         len);
}

/* srbf's level k, seeing srbf's params (its lights and rows builds read no
 * level before them). */
static int srbf_level_build(const method_build_in *in, int k, cache_value *out, glint_err *err)
{
    method_build_in c = *in;
    c.params = &((const pbr_env_params *)in->params)->env;
    c.prev = NULL;
    c.level = k;
    return method_srbf.levels[k].build(&c, out, err);
}

static int lights_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    return srbf_level_build(in, SRBF_LV_LIGHTS, out, err);
}

static int rows_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    return srbf_level_build(in, SRBF_LV_ROWS, out, err);
}

static void terms_key(const void *params, const samples *s, const char *prev, char *key,
                      size_t len)
{
    (void)params;
    (void)s;
    /* prev: the rows' key, which names the pattern, the lights and the
     * visibility; nothing else shapes the terms */
    snprintf(key, len, "pbr-env-terms:%s", prev);
}

static void terms_free(void *d)
{
    pbr_env_terms *x = d;
    if (x) {
        free(x->g.ci);
        free(x->g.off);
        free(x->g.w);
    }
    free(x);
}

/* Row i's local geometry (OUT n, wo; returns n.wo). */
static double row_geom(const samples *s, int si, double n[3], double wo[3])
{
    double nl = 0.0;
    for (int e = 0; e < 3; e++) {
        n[e] = s->nrm[3 * (size_t)si + e];
        wo[e] = s->wo[3 * (size_t)si + e];
        nl += n[e] * n[e];
    }
    nl = sqrt(nl);
    if (nl > 0.0)
        for (int e = 0; e < 3; e++)
            n[e] /= nl;
    return n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
}

/* Whether light k lights row i: above its horizon (and facing it: n.wo >
 * 0) and seen from it (bits: NULL when no shadows are cast). */
static int row_sees(const uint64_t *bits, int words, int i, int k, double ci, double co)
{
    if (!(ci > 0.0) || !(co > 0.0))
        return 0;
    return !bits || ((bits[(size_t)i * words + (k >> 6)] >> (k & 63)) & 1);
}

/* The terms of every row: counted, then filled (OUT x->g). */
static int terms_fill(const samples *s, const srbf_visdata *vd, const env_lights *l,
                      const uint64_t *bits, pbr_env_terms *x, glint_err *err)
{
    int K = l->k, words = VIS_WORDS(K), n = vd->nrows;
    long nt = 0;
    pbr_geom *g = &x->g;

    if (!(g->off = malloc(((size_t)n + 1) * sizeof *g->off)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d rows", n);
    for (int i = 0; i < n; i++) {
        double nr[3], wo[3], co = row_geom(s, vd->rows[i], nr, wo);
        g->off[i] = (int)nt;
        for (int k = 0; k < K; k++) {
            const double *d = l->dir + 3 * k;
            nt += row_sees(bits, words, i, k, nr[0] * d[0] + nr[1] * d[1] + nr[2] * d[2], co);
        }
        if (nt > (long)1 << 30)
            return glint_err_set(err, GLINT_ERANGE,
                                 "%d rows x %d lights are too many terms: lower lights or "
                                 "the raster", n, K);
    }
    g->off[n] = (int)nt;
    g->n = n;
    g->ci = malloc(4 * sizeof(double) * (size_t)(nt ? nt : 1));
    g->w = malloc(3 * sizeof(float) * (size_t)(nt ? nt : 1));
    if (!g->ci || !g->w)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %ld terms", nt);
    g->co = g->ci + nt;
    g->ch = g->ci + 2 * nt;
    g->cd = g->ci + 3 * nt;
    for (int i = 0; i < n; i++) {
        double nr[3], wo[3], co = row_geom(s, vd->rows[i], nr, wo);
        long t = g->off[i];
        for (int k = 0; k < K; k++) {
            const double *d = l->dir + 3 * k;
            double ci = nr[0] * d[0] + nr[1] * d[1] + nr[2] * d[2], h[3], hl;
            if (!row_sees(bits, words, i, k, ci, co))
                continue;
            for (int e = 0; e < 3; e++)
                h[e] = d[e] + wo[e];
            hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            for (int e = 0; e < 3 && hl > 0.0; e++)
                h[e] /= hl;
            g->ci[t] = ci;
            g->co[t] = co;
            g->ch[t] = nr[0] * h[0] + nr[1] * h[1] + nr[2] * h[2];
            g->cd[t] = d[0] * h[0] + d[1] * h[1] + d[2] * h[2];
            for (int c = 0; c < 3; c++)
                g->w[3 * t + c] = (float)l->power[3 * k + c];
            t++;
        }
    }
    return 0;
}

static int terms_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const srbf_lightset *ls = in->prev[LV_LIGHTS];
    const srbf_visdata *vd = in->prev[LV_ROWS];
    pbr_env_terms *x = calloc(1, sizeof *x);
    uint64_t *bits = NULL;
    double t0 = glint_now();
    int rc = 0;

    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (in->progress)
        in->progress(in->progress_cls, "pbr-env-terms", 0.4);
    if (vd->on)
        rc = srbf_cast_shadows(in, vd, &ls->l, &bits, &x->rays, err);
    x->shadows = vd->on;
    if (!rc)
        rc = terms_fill(in->s, vd, &ls->l, bits, x, err);
    free(bits);
    if (rc) {
        terms_free(x);
        return rc;
    }
    x->seconds = glint_now() - t0;
    out->data = x;
    out->bytes = sizeof *x + ((size_t)x->g.n + 1) * sizeof(int) +
                 (size_t)pbr_geom_terms(&x->g) * (4 * sizeof(double) + 3 * sizeof(float));
    out->free = terms_free;
    return 0;
}

static const method_level pbr_env_levels[LV_N] = {
    {.name = "lights", .progress = 0.05, .key = lights_key, .build = lights_build},
    {.name = "rows", .progress = 0.15, .key = rows_key, .build = rows_build},
    {.name = "pbr-env-terms", .progress = 0.25, .key = terms_key, .build = terms_build},
};

/* ---- the fit ------------------------------------------------------------------------- */

/* The rows' painted radiance over the environment's intensity (OUT y[3 n])
 * and views (OUT view[n]); GLINT_ENONFINITE names a painted value that is
 * not finite (any sample's, fitted or not, but those held out: their
 * values are not read). */
static int rows_target(const method_fit_in *in, float *y, int *view, glint_err *err)
{
    const pbr_env_params *pp = in->params;
    const srbf_visdata *vd = in->levels[LV_ROWS];
    const samples *s = in->s;
    for (long i = 0; i < 3L * s->n; i++)
        if ((!in->held || !in->held[i / 3]) && !isfinite(in->rgb[i]))
            return glint_err_set(err, GLINT_ENONFINITE, "pbr_env: painted value %ld is not finite",
                                 i / 3);
    for (int i = 0; i < vd->nrows; i++) {
        int si = vd->rows[i];
        for (int c = 0; c < 3; c++)
            y[3 * (size_t)i + c] =
                in->held && in->held[si]
                    ? 0.0f
                    : (float)((double)in->rgb[3 * (size_t)si + c] * s->intensity[si] /
                              pp->env.env_intensity);
        view[i] = s->view[si];
    }
    return 0;
}

/* The rows the fit reads: every one, or (in->held) those not held out,
 * copied (OUT: *g, *y and *view point at the copies, kept in own, or at
 * the callers' arrays). */
typedef struct rows_kept {
    pbr_geom g;
    float *y;
    int *view;
} rows_kept;

static int rows_keep(const method_fit_in *in, const pbr_env_terms *x, const float *y,
                     const int *view, rows_kept *own, const pbr_geom **g, const float **yk,
                     const int **vk)
{
    const srbf_visdata *vd = in->levels[LV_ROWS];
    unsigned char *take;
    int n = x->g.n, rc;
    *g = &x->g;
    *yk = y;
    *vk = view;
    if (!in->held)
        return 0;
    if (!(take = malloc((size_t)(n ? n : 1))) ||
        !(own->view = malloc(sizeof(int) * (size_t)(n ? n : 1)))) {
        free(take);
        return GLINT_ENOMEM;
    }
    for (int i = 0, k = 0; i < n; i++)
        if ((take[i] = !in->held[vd->rows[i]]))
            own->view[k++] = view[i];
    rc = pbr_geom_pick(&x->g, y, take, &own->g, &own->y);
    free(take);
    if (!rc) {
        *g = &own->g;
        *yk = own->y;
        *vk = own->view;
    }
    return rc;
}

static void rows_kept_free(rows_kept *own)
{
    pbr_geom_free(&own->g);
    free(own->y);
    free(own->view);
}

/* The report: params, precomputation, seconds, errors in the painting's
 * units (rms over the fitted pixels), and pbr's members on what the views
 * determine.  NULL when out of memory. */
static json_t *fit_report(const method_fit_in *in, const pbr_spec *sp, const pbr_fit_result *r,
                          double seconds)
{
    const pbr_env_params *pp = in->params;
    const srbf_lightset *ls = in->levels[LV_LIGHTS];
    const pbr_env_terms *x = in->levels[LV_TERMS];
    double k = pp->env.env_intensity, se[PBR_MAX_VIEWS];
    json_t *info, *det;
    for (int v = 0; v < PBR_MAX_VIEWS; v++)
        se[v] = r->view_se[v] * k * k;
    info = json_pack(
        "{s:o, s:{s:s, s:s, s:i, s:i, s:I, s:i, s:I, s:s, s:f}, s:{s:f, s:f, s:f},"
        " s:{s:f, s:o}, s:o}",
        "params", method_params_to_json(&method_pbr_env, pp), "precomputation", "pattern_hash",
        in->s->hash, "cache_key", in->keys[LV_TERMS], "samples", in->s->n, "rows", x->g.n,
        "terms", (json_int_t)pbr_geom_terms(&x->g), "lights", ls->l.k, "shadow_rays",
        (json_int_t)x->rays, "environment", ls->name, "light_cut_error", ls->e.glossy_rel_rms,
        "seconds", "samples", in->pattern_seconds, "terms", x->seconds, "fit", seconds,
        "errors", "rms_painted", r->rms * k, "rms_by_view",
        method_rms_by_view(se, r->view_n, in->s->nviews), "fit", pbr_report_fit(r));
    det = pbr_report_determination(sp, r, r->nsamples_lit == 0);
    if (!info || !det) {
        json_decref(info);
        json_decref(det);
        return NULL;
    }
    json_object_update(info, det);
    json_decref(det);
    return info;
}

static int pbr_env_fit(const method_fit_in *in, material *out, glint_err *err)
{
    const pbr_env_params *pp = in->params;
    const pbr_env_terms *x = in->levels[LV_TERMS];
    double t0 = glint_now();
    pbr_spec sp = {pp->pbr.lobes, pp->pbr.fresnel};
    int n = x->g.n, rc;
    float *y = malloc(3 * sizeof(float) * (size_t)(n ? n : 1));
    int *view = malloc(sizeof(int) * (size_t)(n ? n : 1));
    pbr_fit_result *r = malloc(sizeof *r);
    pbr_material *pm = NULL;
    json_t *info = NULL;
    rows_kept own = {0};
    const pbr_geom *g;
    const float *yk;
    const int *vk;

    if (!y || !view || !r) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    if ((rc = rows_target(in, y, view, err)))
        goto done;
    if ((rc = rows_keep(in, x, y, view, &own, &g, &yk, &vk))) {
        rc = glint_err_set(err, rc, "out of memory");
        goto done;
    }
    {
        pbr_fit_opts o = {.starts = pp->pbr.starts, .max_iter = pp->pbr.max_iter,
                          .start_iter = pp->pbr.start_iter,
                          .subset = pp->pbr.start_samples, .refine = pp->pbr.refine_samples,
                          .view = vk};
        if ((rc = pbr_fit(&sp, g, yk, &o, r, err)))
            goto done;
    }
    if (!(pm = calloc(1, sizeof *pm)) || !(info = fit_report(in, &sp, r, glint_now() - t0))) {
        free(pm);
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    if (in->held)
        json_object_set_new(info, "rows_held_out", json_integer(n - g->n));
    pm->sp = sp;
    memcpy(pm->p, r->p, sizeof pm->p);
    pbr_material_sync(pm);
    material_init(out, &method_pbr_env, pm, info);
done:
    rows_kept_free(&own);
    free(y);
    free(view);
    free(r);
    return rc;
}

/* The painted values the model gives the fitted pixels under the
 * environment (NaN elsewhere): radiance, what a held-out view's painting
 * holds and is compared with (method.h: prep_predict). */
static int pbr_env_predict(const method_fit_in *in, const material *m, float *rgb,
                           glint_err *err)
{
    const pbr_env_params *pp = in->params;
    const srbf_visdata *vd = in->levels[LV_ROWS];
    const pbr_env_terms *x = in->levels[LV_TERMS];
    const pbr_material *pm = pbr_material_of(m);
    const samples *s = in->s;

    if (!pm)
        return glint_err_set(err, GLINT_EINVAL, "the material is not a pbr material");
    for (size_t i = 0; i < (size_t)3 * s->n; i++)
        rgb[i] = NAN;
    for (int i = 0; i < x->g.n; i++) {
        int si = vd->rows[i];
        double v[3];
        pbr_sample_eval(&pm->sp, pm->p, &x->g, i, v, NULL);
        for (int c = 0; c < 3; c++)
            rgb[3 * (size_t)si + c] = (float)(v[c] * pp->env.env_intensity);
    }
    return 0;
}

/* ---- what a fit costs ------------------------------------------------------------------ */

/* Rows as srbf counts them: at most the raster's pixels in 12 views. */
static double rows_of(const pbr_env_params *p, long nsamples)
{
    double rows = (double)nsamples;
    if (p->env.raster.w > 0 && rows > 12.0 * p->env.raster.w * p->env.raster.h)
        rows = 12.0 * p->env.raster.w * p->env.raster.h;
    return rows;
}

/* Memory of a cold fit: the pattern (about 100 bytes a sample), the terms
 * (half the lights a row, 44 bytes each), the shadow bits, a subset's copy
 * of the terms and GSL's workspace; a third on top. */
static size_t pbr_env_fit_bytes(const void *params, long nsamples)
{
    const pbr_env_params *p = params;
    double rows = rows_of(p, nsamples), L = p->env.lights;
    double b = 100.0 * nsamples + rows * (L / 2.0 * 44.0 + L / 8.0 + 64.0) +
               (double)p->pbr.refine_samples * L / 2.0 * 44.0 + (double)(16 << 20);
    b *= 4.0 / 3.0;
    return b >= (double)SIZE_MAX ? SIZE_MAX : (size_t)b;
}

/* A cold fit: the pattern, shadow rays (half the lights a row, 2 us each,
 * as srbf_fit_seconds), the terms (50 ns a term), and the fit's passes at
 * 40 ns a term: each start's iterations about three passes over its
 * pixels, the refinement about 30 passes over its own and two over every
 * row.  Checked on the 160x120 sphere, 3 views under the courtyard, 256
 * lights (3,126 rows, 437,226 terms): the passes measured 200-208 ms on two
 * threads of the development machine; the estimate, which counts every
 * sample as a row (the raster's stride is not known here), says 0.8 s. */
static double pbr_env_fit_seconds(const void *params, long nsamples)
{
    const pbr_env_params *p = params;
    double rows = rows_of(p, nsamples), half = p->env.lights / 2.0;
    double st = p->pbr.start_samples > 0 && p->pbr.start_samples < rows ? p->pbr.start_samples
                                                                       : rows;
    double rf = p->pbr.refine_samples > 0 && p->pbr.refine_samples < rows
                    ? p->pbr.refine_samples
                    : rows;
    double s = (double)nsamples * METHOD_SECONDS_PER_SAMPLE + rows * half * 50e-9 +
               (3.0 * p->pbr.starts * p->pbr.start_iter * st + 30.0 * rf + 2.0 * rows) * half *
                   40e-9;
    if (p->env.visibility != SRBF_VIS_OFF)
        s += rows * half * 2e-6;
    return s;
}

/* A held-out measurement (prep_holdout) makes the terms of every painted
 * view once and fits each view's leave-out on them (fits_held):
 * affordable on a fit grid, not on every pixel. */
static int pbr_env_holdout_ok(const void *params)
{
    return ((const pbr_env_params *)params)->env.raster.w > 0;
}

const method method_pbr_env = {
    .name = "pbr_env",
    .label = "Physically based, under an environment",
    .summary = "One material as a few physical numbers (a diffuse colour, a roughness and a "
        "reflectance), fitted to views painted under an environment.",
    .when = "Use it on a scene painted under an environment when you want a standard "
        "material that holds up under other light and from other views.",
    .lighting = METHOD_LIGHT_ENV,
    .shows = METHOD_SHOWS_NONE,
    .fits_held = 1,
    .title = "Physically based parametric BRDF (Lambert + GGX) fitted under environment light",
    .reference = "Walter, Marschner, Li & Torrance, Microfacet Models for Refraction through "
                 "Rough Surfaces, 2007; the environment's lights and visibility as in "
                 "Iwasaki, Dobashi, Yoshimoto & Nishita 2009",
    .description =
        "The pbr method's model (kd/pi plus one or two GGX lobes with height-correlated Smith "
        "visibility and Schlick Fresnel) fitted to views lit by an environment: the "
        "environment compressed into lights (median cut), each fitted pixel summing the "
        "lights above its horizon that it sees (shadow rays unless the mesh is convex). "
        "Nonlinear least squares (GSL, Levenberg-Marquardt) from a few starting "
        "roughnesses; bounds and the report of what the views determine as pbr's. The "
        "material is a pbr material: every renderer and export reads it as it is.",
    .held_out = "each painted view left out in turn, predicted under the environment from "
                "the material fitted to the others",
    .schema = "FitParamsPbrEnv.json",
    .params_size = sizeof(pbr_env_params),
    .params = pbr_env_params_table,
    .nparams = (int)(sizeof pbr_env_params_table / sizeof pbr_env_params_table[0]),
    .presets = pbr_env_presets,
    .npresets = (int)(sizeof pbr_env_presets / sizeof pbr_env_presets[0]),
    .params_default = pbr_env_params_default,
    .params_usable = pbr_env_params_usable,
    .pattern_rule = SAMPLES_SEEN,
    .levels = pbr_env_levels,
    .nlevels = LV_N,
    .fit = pbr_env_fit,
    .predict = pbr_env_predict,
    .mat = &pbr_material_ops,
    .holdout_ok = pbr_env_holdout_ok,
    .fit_bytes = pbr_env_fit_bytes,
    .fit_seconds = pbr_env_fit_seconds,
};
