/* method_pbr.c: the pbr method's table (method_pbr.h): parameters, the
 * pbr-geom level, the fit (pbr_fit.c) and its report.
 *
 * The report (the material's info) adds to params, precomputation, seconds
 * and errors what the views determine: each parameter inside its bounds
 * with its standard error, the ones the views leave undetermined, the ones
 * held at a bound, and plain sentences on what those mean. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_pbr.h"

static const char *const fresnel_values[] = {"dielectric", "conductor", NULL};

static const method_param pbr_params_table[] = {
    {.name = "lobes", .label = "highlight layers", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "GGX lobes: 1 (one highlight) or 2 (a sharp highlight over a broad sheen)",
     .offset = offsetof(pbr_params, lobes), .min = 1, .max = PBR_MAX_LOBES},
    {.name = "fresnel", .label = "kind of surface", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_ENUM, .affects = "fit",
     .description = "dielectric (plastic, paint, wood: one index of refraction, a tinted "
                    "highlight weight) or conductor (metal: a reflectance per colour channel)",
     .offset = offsetof(pbr_params, fresnel), .values = fresnel_values},
    {.name = "starts", .label = "roughnesses tried", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "starting roughnesses of the search (0.05, 0.15, 0.4, then 0.01, 0.7, "
                    "0.1, 0.25, 0.03); the best fit of them is kept",
     .offset = offsetof(pbr_params, starts), .min = 1, .max = PBR_MAX_STARTS},
    {.name = "max_iter", .label = "iterations per start", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "Levenberg-Marquardt iterations allowed per start and for the final "
                    "refinement",
     .offset = offsetof(pbr_params, max_iter), .min = 1, .max = 10000},
    {.name = "start_iter", .label = "iterations per start on its samples",
     .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "Levenberg-Marquardt iterations of each start on its samples (it only has "
                    "to find the basin the refinement then converges in)",
     .offset = offsetof(pbr_params, start_iter), .min = 1, .max = 10000},
    {.name = "start_samples", .label = "samples per start", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "samples each start is fitted on (the brightest eighth and an even "
                    "draw of the rest) before the best is refined; 0: all",
     .offset = offsetof(pbr_params, start_samples), .min = 0, .max = 1 << 24},
    {.name = "refine_samples", .label = "samples refined on", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "samples the best start is refined on (drawn as the starts' are, when "
                    "more than they); 0: all.  The errors, the uncertainties and what the "
                    "views determine are computed on every sample",
     .offset = offsetof(pbr_params, refine_samples), .min = 0, .max = 1 << 24},
};

static void pbr_params_default(void *p)
{
    pbr_params *pp = p;
    pp->lobes = 1;
    pp->fresnel = PBR_DIELECTRIC;
    pp->starts = 3;
    pp->max_iter = 100;
    pp->start_iter = 25;
    pp->start_samples = 4096;
    pp->refine_samples = 16384;
}

/* ---- the pbr-geom level ------------------------------------------------------------- */

static void geom_key(const void *p, const samples *s, const char *prev, char *key, size_t len)
{
    (void)p;
    (void)s;
    snprintf(key, len, "pbr-geom:%s", prev);
}

static void geom_free(void *data)
{
    pbr_geom *g = data;
    if (g)
        free(g->ci);
    free(g);
}

static int geom_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const samples *s = in->s;
    pbr_geom *g = calloc(1, sizeof *g);
    size_t n = (size_t)s->n;
    if (!g || !(g->ci = malloc(4 * n * sizeof(double)))) {
        free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (pbr-geom, %d samples)", s->n);
    }
    if (in->progress)
        in->progress(in->progress_cls, "pbr-geom", 0.5);
    g->n = s->n;
    g->co = g->ci + n;
    g->ch = g->ci + 2 * n;
    g->cd = g->ci + 3 * n;
    for (size_t i = 0; i < n; i++) {
        const float *nr = s->nrm + 3 * i, *wi = s->wi + 3 * i, *wo = s->wo + 3 * i;
        double h[3], hl;
        for (int e = 0; e < 3; e++)
            h[e] = (double)wi[e] + wo[e];
        hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        if (hl > 0.0)
            for (int e = 0; e < 3; e++)
                h[e] /= hl;
        g->ci[i] = s->cos_i[i];
        g->co[i] = (double)nr[0] * wo[0] + (double)nr[1] * wo[1] + (double)nr[2] * wo[2];
        g->ch[i] = nr[0] * h[0] + nr[1] * h[1] + nr[2] * h[2];
        g->cd[i] = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2];
    }
    out->data = g;
    out->bytes = sizeof *g + 4 * n * sizeof(double);
    out->free = geom_free;
    return 0;
}

static const method_level pbr_levels[] = {
    {.name = "pbr-geom", .progress = 0.5, .key = geom_key, .build = geom_build},
};

/* ---- the report ----------------------------------------------------------------------- */

/* The view angles the highlight's energy is checked at (degrees). */
static const double ENERGY_DEG[] = {0.0, 30.0, 60.0, 75.0, 85.0};

/* How much light the fitted highlight reflects (pbr_spec_albedo at the
 * angles above): its largest directional albedo, where, in which channel;
 * above 1 (with 2% for the sampling) a note says so (ks is bounded only
 * by PBR_KS_MAX: the fit follows the painting rather than clamp it, and
 * where no grazing view was painted, ks and F0 trade against each other:
 * sgd:nickel from 12 point-lit views comes back at 401% at 85 degrees,
 * dielectric or conductor). */
static json_t *energy_report(const pbr_spec *sp, const double *p, json_t *notes)
{
    static const char *const ch = "rgb";
    pbr_lobe lobes[PBR_MAX_LOBES];
    double mx = 0.0, at = 0.0;
    int mc = 0;
    pbr_lobes_of(sp, p, lobes);
    for (size_t a = 0; a < sizeof ENERGY_DEG / sizeof *ENERGY_DEG; a++) {
        double e[3];
        pbr_spec_albedo(lobes, sp->nlobes, cos(ENERGY_DEG[a] * M_PI / 180.0), e);
        for (int c = 0; c < 3; c++)
            if (e[c] > mx) {
                mx = e[c];
                at = ENERGY_DEG[a];
                mc = c;
            }
    }
    if (mx > 1.02) {
        char buf[400];
        snprintf(buf, sizeof buf,
                 "the highlight reflects more light than arrives: %.0f%% in %c for a view %.0f "
                 "degrees from the normal, where a physical one reflects at most 100%%. The "
                 "painting asks for a brighter highlight than a physical material has, or no "
                 "painted view shows those angles and the fit's highlight strength and Fresnel "
                 "term trade against each other there",
                 100.0 * mx, ch[mc], at);
        json_array_append_new(notes, json_string(buf));
    }
    return json_pack("{s:f, s:f, s:s#}", "specular_albedo_max", mx, "view_deg", at, "channel",
                     ch + mc, 1);
}

json_t *pbr_report_determination(const pbr_spec *sp, const pbr_fit_result *r, int black)
{
    json_t *det = json_object(), *und = json_array(), *bnd = json_array(), *notes = json_array();
    double lo[PBR_MAXP], hi[PBR_MAXP];
    int np = pbr_np(sp), kd_hi = 0, alpha_lo = 0;

    pbr_bounds(sp, lo, hi);
    for (int k = 0; k < np; k++) {
        char name[16];
        pbr_param_name(sp, k, name, sizeof name);
        if (r->undetermined[k])
            json_array_append_new(und, json_string(name));
        else if (!r->at_bound[k])
            json_object_set_new(det, name, json_pack("{s:f, s:f}", "value", r->p[k], "sigma",
                                                     isfinite(r->sigma[k]) ? r->sigma[k] : 0.0));
        if (r->at_bound[k] && !r->undetermined[k])
            json_array_append_new(bnd, json_pack("{s:s, s:s, s:f}", "name", name, "bound",
                                                 r->at_bound[k] < 0 ? "lower" : "upper",
                                                 "value", r->p[k]));
        kd_hi |= k < 3 && r->at_bound[k] > 0;
        alpha_lo |= k >= 3 && (k - 3) % 5 == 0 && r->at_bound[k] < 0 && !r->undetermined[k];
    }
    if (black)
        json_array_append_new(notes, json_string(
            "the painting is black on every lit sample: the material is black (kd = ks = 0) "
            "and its roughness and Fresnel are undetermined"));
    if (kd_hi)
        json_array_append_new(notes, json_string(
            "the painting is brighter than a physical diffuse surface can be: the diffuse "
            "colour is clamped at 1 (energy conservation) in the channels listed in at_bound"));
    if (alpha_lo)
        json_array_append_new(notes, json_string(
            "the highlight is as sharp as the model allows (mirror-like): the roughness is at "
            "its lower bound 0.002"));
    if (json_array_size(und) && !black)
        json_array_append_new(notes, json_string(
            "the views do not determine the parameters listed in undetermined (no highlight, "
            "or no grazing view for the Fresnel term): their values are arbitrary"));
    return json_pack("{s:o, s:o, s:o, s:o, s:o}", "determined", det, "undetermined", und,
                     "at_bound", bnd, "energy", energy_report(sp, r->p, notes), "notes", notes);
}

json_t *pbr_report_fit(const pbr_fit_result *r)
{
    json_t *starts = json_array();
    for (int s = 0; s < r->nstarts; s++)
        json_array_append_new(starts, json_pack("{s:f, s:f, s:i, s:b}", "alpha0",
                                                r->start[s].alpha0, "cost", r->start[s].cost,
                                                "iterations", r->start[s].iters, "converged",
                                                r->start[s].converged));
    return json_pack("{s:o, s:i, s:i, s:b, s:i, s:f, s:f, s:i}", "starts", starts,
                     "best_start", r->best_start, "iterations", r->iters, "converged",
                     r->converged, "refine_samples", r->refine_samples, "cost", r->cost,
                     "residual_variance", r->resid_var, "lit_samples", r->nsamples_lit);
}

/* ---- the fit ----------------------------------------------------------------------------- */

static int pbr_method_fit(const method_fit_in *in, material *out, glint_err *err)
{
    const pbr_params *pp = in->params;
    const pbr_geom *g = in->levels[0];
    double t0 = glint_now();
    pbr_spec sp = {pp->lobes, pp->fresnel};
    pbr_fit_opts o = {.starts = pp->starts, .max_iter = pp->max_iter, .start_iter = pp->start_iter,
                      .subset = pp->start_samples, .refine = pp->refine_samples,
                      .view = in->s->view};
    pbr_fit_result *r = malloc(sizeof *r);
    pbr_material *pm = NULL;
    json_t *info, *det;
    int rc;

    if (!r)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (long i = 0; i < 3L * in->s->n; i++)
        if (!isfinite(in->rgb[i])) {
            free(r);
            return glint_err_set(err, GLINT_ENONFINITE, "pbr: painted value %ld is not finite",
                                 i / 3);
        }
    if ((rc = pbr_fit(&sp, g, in->rgb, &o, r, err))) {
        free(r);
        return rc;
    }
    if (!(pm = calloc(1, sizeof *pm))) {
        free(r);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    pm->sp = sp;
    memcpy(pm->p, r->p, sizeof pm->p);
    pbr_material_sync(pm);
    det = pbr_report_determination(&sp, r, r->nsamples_lit == 0);
    info = json_pack("{s:o, s:{s:s, s:s, s:i}, s:{s:f, s:f}, s:{s:f, s:o}, s:o}", "params",
                     method_params_to_json(&method_pbr, pp), "precomputation", "pattern_hash",
                     in->s->hash, "cache_key", in->keys[0], "samples", in->s->n, "seconds",
                     "samples", in->pattern_seconds, "fit", glint_now() - t0, "errors",
                     "rms_painted", r->rms, "rms_by_view",
                     method_rms_by_view(r->view_se, r->view_n, in->s->nviews), "fit",
                     pbr_report_fit(r));
    if (!info || !det) {
        json_decref(info);
        json_decref(det);
        free(pm);
        free(r);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    json_object_update(info, det);
    json_decref(det);
    free(r);
    material_init(out, &method_pbr, pm, info);
    return 0;
}

static size_t pbr_fit_bytes(const void *params, long nsamples)
{
    const pbr_params *pp = params;
    long np = 3 + 5 * pp->lobes;
    /* the pattern (about 100 bytes a sample), pbr-geom (32) and GSL's
     * workspace over every sample: J (3 np doubles) and about 8 vectors of
     * 3 n doubles */
    return (size_t)nsamples * (size_t)(160 + 24 * (np + 8));
}

const method method_pbr = {
    .name = "pbr",
    .label = "Physically based",
    .summary = "One material as a few physical numbers: a diffuse colour, a roughness and a "
        "reflectance (how mirror-like it is, seen head-on).",
    .when = "Use it when you want a compact, standard material (the kind game engines and "
        "renderers take) and the painting looks like plastic, paint or metal.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_NONE,
    .title = "Physically based parametric BRDF (Lambert + GGX, height-correlated Smith, "
        "Schlick Fresnel)",
    .reference = "Walter, Marschner, Li & Torrance, Microfacet Models for Refraction through "
                 "Rough Surfaces, 2007; Heitz, Understanding the Masking-Shadowing Function "
                 "in Microfacet-Based BRDFs, 2014",
    .description =
        "f = kd/pi + sum over one or two lobes of ks D V F: GGX distribution D, "
        "height-correlated Smith visibility V, Schlick Fresnel F of a dielectric (one index "
        "of refraction, ks per channel) or a conductor (F0 per channel, one ks). Fitted by "
        "nonlinear least squares (GSL multifit_nlinear, Levenberg-Marquardt) from a few "
        "starting roughnesses, kd and ks of each start from a linear solve; bounds kd in "
        "[0,1], alpha in [0.002,1], ior in [1.01,3], F0 in [0,1]. The report gives each "
        "parameter's standard error from the Jacobian at the solution and names those the "
        "views do not determine. Points: fit_seconds is the warm fit, rms_painted the RMS "
        "error on the painted samples.",
    .schema = "FitParamsPbr.json",
    .params_size = sizeof(pbr_params),
    .params = pbr_params_table,
    .nparams = (int)(sizeof pbr_params_table / sizeof pbr_params_table[0]),
    .params_default = pbr_params_default,
    .levels = pbr_levels,
    .nlevels = (int)(sizeof pbr_levels / sizeof pbr_levels[0]),
    .fit = pbr_method_fit,
    .mat = &pbr_material_ops,
    .fit_bytes = pbr_fit_bytes,
};
