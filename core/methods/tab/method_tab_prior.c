/* method_tab_prior.c: the tab_prior method's table (method_tab_prior.h):
 * parameters (tab's and the prior's), the levels (tab's two and the
 * learned prior), the fit (tab's, then the completion) and its report. */
#include <ctype.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "measured.h"
#include "method_tab_prior.h"

/* ---- parameters ------------------------------------------------------------------------ */

static const char *const learn_values[] = {"abc", "sgd", NULL};
static const char *const exclude_examples[] = {"", "every/4", "alum-bronze+nickel", NULL};

/* "every/N" (OUT: *every = N) or NAME[+NAME...] (*every = 0); "" is valid. */
static int exclude_syntax(const char *text, int *every, glint_err *err)
{
    *every = 0;
    if (!strncmp(text, "every/", 6)) {
        char *end;
        long n = strtol(text + 6, &end, 10);
        if (end == text + 6 || *end || n < 1 || n > MEASURED_MAX)
            return glint_err_set(err, GLINT_EINVAL, "\"every/N\" takes N in 1..%d, got \"%s\"",
                                 MEASURED_MAX, text + 6);
        *every = (int)n;
        return 0;
    }
    for (const char *p = text; *p; p++) {
        if (!(islower((unsigned char)*p) || isdigit((unsigned char)*p) || strchr("._-+", *p)))
            return glint_err_set(err, GLINT_EINVAL,
                                 "names are [a-z0-9._-] joined by '+', got '%c'", *p);
        if (*p == '+' && (p == text || p[1] == '+' || !p[1]))
            return glint_err_set(err, GLINT_EINVAL, "an empty name between '+'");
    }
    return 0;
}

int tab_prior_exclude_parse(const char *text, void *field, glint_err *err)
{
    int every, rc;
    if (strlen(text) >= TAB_PRIOR_EXCLUDE_MAX)
        return glint_err_set(err, GLINT_EINVAL, "at most %d bytes", TAB_PRIOR_EXCLUDE_MAX - 1);
    if ((rc = exclude_syntax(text, &every, err)))
        return rc;
    strcpy(field, text);
    return 0;
}

void tab_prior_exclude_format(const void *field, char *buf, size_t len)
{
    snprintf(buf, len, "%s", (const char *)field);
}

static const method_param tab_prior_params_table[] = {
    {.name = "res_h", .label = "half-angle nodes", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes of the table along the half angle theta_h (uniform in "
                    "sqrt(theta_h), dense near the highlight)",
     .offset = offsetof(tab_prior_params, tab.res_h), .min = TAB_RES_H_MIN,
     .max = TAB_RES_H_MAX},
    {.name = "res_d", .label = "difference-angle nodes", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes of the table along the difference angle theta_d (uniform)",
     .offset = offsetof(tab_prior_params, tab.res_d), .min = TAB_RES_D_MIN,
     .max = TAB_RES_D_MAX},
    {.name = "lambda", .label = "smoothness", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_NUMBER, .affects = "operator",
     .description = "weight of the table's smoothness prior against the mean squared error of "
                    "the painted samples (tab's lambda)",
     .offset = offsetof(tab_prior_params, tab.lambda), .min = 0.0, .max = 1e3},
    {.name = "learn", .label = "learned from", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_ENUM, .affects = "precomputation",
     .description = "which published fit of the measured materials the prior learns from: "
                    "sgd (Bagher et al. 2012) or abc (Low et al. 2012)",
     .offset = offsetof(tab_prior_params, learn), .values = learn_values},
    {.name = "exclude", .label = "materials left out", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_TEXT, .affects = "precomputation",
     .description = "measured materials the prior does not learn from: names joined by '+', "
                    "or every/N for materials 0, N, 2N, ... of the fits file (the ones a "
                    "benchmark run with --every N judges); empty: none",
     .offset = offsetof(tab_prior_params, exclude), .syntax = "\"\" | every/N | NAME[+NAME...]",
     .examples = exclude_examples, .parse = tab_prior_exclude_parse,
     .format = tab_prior_exclude_format},
    {.name = "components", .label = "learned directions", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "principal directions of the learned tables (in the log) the completion "
                    "may move along",
     .offset = offsetof(tab_prior_params, components), .min = 1, .max = PRIOR_K_MAX},
    {.name = "noise", .label = "trust in the painting", .group = METHOD_GROUP_BASIC,
     .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "the log error of a node the painting weighs on as much as the median "
                    "one; larger: the prior decides more of the table",
     .offset = offsetof(tab_prior_params, noise), .min = 1e-6, .max = 1e3},
    {.name = "painted", .label = "painted threshold", .group = METHOD_GROUP_ADVANCED,
     .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "a node of the table counts as painted where the painting weighs on it "
                    "at least this fraction of the median node's weight; the rows beyond "
                    "the painted ones are continued by the prior",
     .offset = offsetof(tab_prior_params, painted), .min = 0.0, .max = 1.0},
};

static void tab_prior_params_default(void *p)
{
    tab_prior_params *tp = p;
    tp->tab.res_h = 32;
    tp->tab.res_d = 16;
    tp->tab.lambda = 1e-10;
    tp->tab.nonneg = 1;
    tp->learn = MEASURED_SGD;
    tp->exclude[0] = '\0';
    tp->components = 32;
    tp->noise = 0.1;
    tp->painted = 0.01;
}

static int tab_prior_params_check(const void *p, glint_err *err)
{
    const tab_prior_params *tp = p;
    if (tp->tab.res_h * tp->tab.res_d > TAB_MAX_NODES)
        return glint_err_set(err, GLINT_EINVAL,
                             "params.res_h x params.res_d (%d x %d) must be at most %d nodes",
                             tp->tab.res_h, tp->tab.res_d, TAB_MAX_NODES);
    return 0;
}

/* ---- the prior's level ------------------------------------------------------------------- */

static uint64_t fnv1a(const char *s)
{
    uint64_t h = 1469598103934665603ULL;
    for (; *s; s++)
        h = (h ^ (unsigned char)*s) * 1099511628211ULL;
    return h;
}

void tab_prior_level_key(const void *p, const samples *s, const char *prev, char *key,
                         size_t len)
{
    const tab_prior_params *tp = p;
    (void)s;
    /* the set's generation: a new fits file is a new prior */
    snprintf(key, len, "tab-prior:%s:%d:%016llx:%u:%s", learn_values[tp->learn],
             tp->components, (unsigned long long)fnv1a(tp->exclude), measured_generation(),
             prev);
}

/* Which materials are left out: every (0: by name), or the names. */
typedef struct exclude_rule {
    int every;
    const char *names; /* NAME[+NAME...] */
} exclude_rule;

static int named(const char *names, const char *name)
{
    size_t n = strlen(name);
    for (const char *p = names; *p;) {
        const char *e = strchr(p, '+');
        size_t l = e ? (size_t)(e - p) : strlen(p);
        if (l == n && !strncmp(p, name, n))
            return 1;
        p += l + (e ? 1 : 0);
    }
    return 0;
}

static int keep_material(const void *cls, int i, const measured_material *m)
{
    const exclude_rule *r = cls;
    if (r->every)
        return i % r->every != 0;
    return !named(r->names, m->name);
}

/* Every name of a rule by names is a material of s. */
static int check_names(const char *names, const measured_set *s, glint_err *err)
{
    char name[MEASURED_NAME_MAX];
    for (const char *p = names; *p;) {
        const char *e = strchr(p, '+');
        size_t l = e ? (size_t)(e - p) : strlen(p);
        snprintf(name, sizeof name, "%.*s", (int)(l < sizeof name ? l : sizeof name - 1), p);
        if (!measured_find(s, name))
            return glint_err_set(err, GLINT_EINVAL,
                                 "\"%s\" is not one of the %d measured materials", name,
                                 s->n);
        p += l + (e ? 1 : 0);
    }
    return 0;
}

/* The host has a fits file with at least two materials to learn from. */
static int tab_prior_available(glint_err *why)
{
    const measured_set *set;
    int rc;
    if ((rc = measured_current(&set, why))) {
        char msg[GLINT_ERR_MSG_MAX];
        snprintf(msg, sizeof msg, "%s", why->msg);
        return glint_err_set(why, rc,
                             "tab_prior learns from the measured materials' fits, and there "
                             "are none: %s", msg);
    }
    if (set->n < 2)
        return glint_err_set(why, GLINT_ENOTFOUND,
                             "tab_prior learns from at least 2 measured materials; the host's "
                             "fits file holds %d", set->n);
    return 0;
}

/* Before any work: the names `exclude` lists are measured materials. */
static int tab_prior_params_usable(const void *params, const method_source *src,
                                   const char **param, glint_err *err)
{
    const tab_prior_params *tp = params;
    const measured_set *set;
    int every = 0, rc;
    (void)src;
    if (measured_current(&set, NULL) || exclude_syntax(tp->exclude, &every, NULL) || every)
        return 0; /* said by tab_prior_available, by the parameter's parse */
    if ((rc = check_names(tp->exclude, set, err)))
        *param = "exclude";
    return rc;
}

static void prior_free(void *data)
{
    tab_prior_free(data);
    free(data);
}

int tab_prior_level_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const tab_prior_params *tp = in->params;
    tab_grid g = {tp->tab.res_h, tp->tab.res_d};
    const measured_set *set;
    exclude_rule rule = {0, tp->exclude};
    tab_prior *p;
    int rc;
    if ((rc = tab_prior_available(err)) || (rc = measured_current(&set, err)))
        return rc;
    if ((rc = exclude_syntax(tp->exclude, &rule.every, err)) ||
        (!rule.every && (rc = check_names(tp->exclude, set, err))))
        return glint_err_prefix(err, "params.exclude");
    if (!(p = malloc(sizeof *p)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (tab prior)");
    if (in->progress)
        in->progress(in->progress_cls, "tab-prior", 0.85);
    if ((rc = tab_prior_learn(&g, set, (measured_model)tp->learn, keep_material, &rule,
                              tp->components, p, err))) {
        free(p);
        return rc;
    }
    out->data = p;
    out->bytes = sizeof *p + (size_t)tab_nodes(&g) * (1 + p->k) * sizeof(double);
    out->free = prior_free;
    return 0;
}

static const method_level tab_prior_levels[] = {
    {.name = "tab-design", .progress = 0.4, .key = tab_level_design_key,
     .build = tab_level_design_build},
    {.name = "tab-operator", .progress = 0.7, .key = tab_level_operator_key,
     .build = tab_level_operator_build},
    {.name = "tab-prior", .progress = 0.85, .key = tab_prior_level_key,
     .build = tab_prior_level_build},
};

/* ---- the fit --------------------------------------------------------------------------------- */

static int complete(const method_fit_in *in, tab_material *tm, json_t **more, glint_err *err)
{
    const tab_prior_params *tp = in->params;
    const tab_prior *p = in->levels[2];
    tab_prior_report r;
    int rc;
    tab_prior_opts o = {.noise = tp->noise, .painted = tp->painted};
    if ((rc = tab_prior_complete(p, in->levels[0], &o, tm->t, &r, err)))
        return rc;
    *more = json_pack("{s:i, s:s, s:i, s:f, s:i, s:[f,f,f], s:[f,f,f]}", "learned_from",
                      p->materials, "fit", learn_values[tp->learn], "components", p->k,
                      "explained", p->explained, "observed", r.observed, "coef_norm",
                      r.coef_norm[0], r.coef_norm[1], r.coef_norm[2], "changed", r.changed[0],
                      r.changed[1], r.changed[2]);
    return *more ? 0 : glint_err_set(err, GLINT_ENOMEM, "out of memory (tab prior report)");
}

static int tab_prior_fit(const method_fit_in *in, material *out, glint_err *err)
{
    return tab_fit_as(&method_tab_prior, in, complete, "prior", out, err);
}

#define PRIOR_BYTES_MATERIALS 128

static size_t tab_prior_fit_bytes(const void *params, long nsamples)
{
    const tab_prior_params *tp = params;
    size_t nodes = (size_t)tp->tab.res_h * tp->tab.res_d;
    /* tab's, and learning: the samples' rows (3 a material), U and VT of
     * their SVD, for a fits file of up to PRIOR_BYTES_MATERIALS materials
     * (../shared's holds 56) */
    return (size_t)nsamples * 160 + 6 * nodes * nodes * sizeof(double) +
           3 * 3 * PRIOR_BYTES_MATERIALS * nodes * sizeof(double);
}

static double tab_prior_fit_seconds(const void *params, long nsamples)
{
    const tab_prior_params *tp = params;
    double nodes = (double)tp->tab.res_h * tp->tab.res_d;
    /* tab's, and learning: 56 materials at 512 nodes took about 0.1 s */
    return METHOD_SECONDS_PER_SAMPLE * nsamples + 0.2 * method_dense_seconds(nodes) +
           0.1 * nodes / 512.0;
}

const method method_tab_prior = {
    .name = "tab_prior",
    .label = "Table with a learned prior",
    .summary = "A table over the angles of the highlight, continued where the painting "
        "says little (light at grazing angles) as measured materials like it go on.",
    .when = "Use it when the host has the measured materials' fits and the material will be "
        "lit from directions the painting never showed.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_NONE,
    .title = "Isotropic BRDF table with a Gaussian prior learned from measured materials",
    .reference = "Rusinkiewicz 1998; Nielsen, Jensen & Ramamoorthi, On Optimal, Minimal BRDF "
                 "Sampling for Reflectance Acquisition, 2015; Tipping & Bishop, Probabilistic "
                 "Principal Component Analysis, 1999",
    .description =
        "tab's fit, then its continuation along theta_d. The measured materials' published "
        "fits, tabulated on the same grid (averaged over phi_d, theta_d up to 60 degrees), "
        "give in log(f + 0.001) a mean, `components` principal directions and a residual "
        "variance (probabilistic PCA); conditioned on the fitted table's painted nodes (each "
        "known to `noise` in the log at the median node's data weight), their posterior mean "
        "predicts the whole table. In each column the rows before the first and after the "
        "last painted one (data weight at least `painted` times the column's largest) "
        "continue the fitted table from that row along the prediction's shape; the painted "
        "rows keep the fit. Points: fit_seconds is the warm fit, rms_painted the RMS error on "
        "the painted samples.",
    .schema = "FitParamsTabPrior.json",
    .params_size = sizeof(tab_prior_params),
    .params = tab_prior_params_table,
    .nparams = (int)(sizeof tab_prior_params_table / sizeof tab_prior_params_table[0]),
    .params_default = tab_prior_params_default,
    .params_check = tab_prior_params_check,
    .params_usable = tab_prior_params_usable,
    .available = tab_prior_available,
    .levels = tab_prior_levels,
    .nlevels = (int)(sizeof tab_prior_levels / sizeof tab_prior_levels[0]),
    .fit = tab_prior_fit,
    .mat = &tab_material_ops,
    .fit_bytes = tab_prior_fit_bytes,
    .fit_seconds = tab_prior_fit_seconds,
};
