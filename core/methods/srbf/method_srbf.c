/* method_srbf.c: the srbf method's parameters and precomputation levels
 * (method_srbf.h).  The fit is in method_srbf_fit.c, the material in
 * method_srbf_material.c, the disk layer in method_srbf_disk.c. */
#include "method_srbf.h"

#include <assert.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <pthread.h>
#include <xxhash.h>

#include "clock.h"
#include "scene.h"
#include "vis.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

int srbf_fit(const method_fit_in *in, material *out, glint_err *err);
int srbf_predict(const method_fit_in *in, const material *m, float *rgb, glint_err *err);

static_assert(sizeof(srbf_static_kind) == sizeof(int) && sizeof(lsq_mode) == sizeof(int),
              "enum parameters are stored as int");

/* ---- parameters -------------------------------------------------------------------- */

int srbf_env_parse(const char *text, void *field, glint_err *err)
{
    int rc = env_spec_check(text, err);
    if (!rc)
        snprintf(field, ENV_NAME_MAX, "%s", text);
    return rc;
}

void srbf_env_format(const void *field, char *buf, size_t len)
{
    snprintf(buf, len, "%s", (const char *)field);
}

int srbf_raster_parse(const char *text, void *field, glint_err *err)
{
    srbf_raster *r = field;
    int w, h, n = 0;
    if (!strcmp(text, "full")) {
        r->w = r->h = 0;
        return 0;
    }
    if (sscanf(text, "%dx%d%n", &w, &h, &n) != 2 || text[n] != '\0')
        return glint_err_set(err, GLINT_EINVAL, "expected WxH (e.g. 160x120) or full");
    if (w < 8 || h < 8 || w > SCENE_MAX_SIZE || h > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "%dx%d outside 8..%d per side", w, h,
                             SCENE_MAX_SIZE);
    r->w = w;
    r->h = h;
    return 0;
}

void srbf_raster_format(const void *field, char *buf, size_t len)
{
    const srbf_raster *r = field;
    if (r->w <= 0)
        snprintf(buf, len, "full");
    else
        snprintf(buf, len, "%dx%d", r->w, r->h);
}

static int diffuse_parse(const char *text, void *field, glint_err *err)
{
    srbf_diffuse *d = field;
    double v[3];
    int n = 0, got;
    if (!strcmp(text, "fit")) {
        d->fit = 1;
        d->rgb[0] = d->rgb[1] = d->rgb[2] = 0.0;
        return 0;
    }
    got = sscanf(text, "%lf,%lf,%lf%n", &v[0], &v[1], &v[2], &n);
    if (got != 3 || text[n] != '\0') {
        n = 0;
        if (sscanf(text, "%lf%n", &v[0], &n) != 1 || text[n] != '\0')
            return glint_err_set(err, GLINT_EINVAL,
                                 "expected fit, an albedo (0.3) or r,g,b (0.35,0.25,0.15)");
        v[1] = v[2] = v[0];
    }
    for (int c = 0; c < 3; c++)
        if (!isfinite(v[c]) || v[c] < 0.0 || v[c] > 1.0)
            return glint_err_set(err, GLINT_ERANGE,
                                 "albedo %g outside [0, 1] (1 leaves no energy for the "
                                 "highlight; above 1 reflects more light than arrives)",
                                 v[c]);
    d->fit = 0;
    memcpy(d->rgb, v, sizeof v);
    return 0;
}

/* The shortest spelling of x that reads back exactly. */
static void shortest(double x, char *buf, size_t len)
{
    for (int prec = 1; prec <= 17; prec++) {
        snprintf(buf, len, "%.*g", prec, x);
        if (strtod(buf, NULL) == x)
            return;
    }
}

static void diffuse_format(const void *field, char *buf, size_t len)
{
    const srbf_diffuse *d = field;
    char a[32], b[32], c[32];
    if (d->fit) {
        snprintf(buf, len, "fit");
        return;
    }
    shortest(d->rgb[0], a, sizeof a);
    shortest(d->rgb[1], b, sizeof b);
    shortest(d->rgb[2], c, sizeof c);
    if (d->rgb[0] == d->rgb[1] && d->rgb[1] == d->rgb[2])
        snprintf(buf, len, "%s", a);
    else
        snprintf(buf, len, "%s,%s,%s", a, b, c);
}

static const char *const static_values[] = {"paper", "smith", NULL};
static const char *const constraint_values[] = {"energy", "nonneg", "none", NULL};
const char *const srbf_vis_values[] = {"auto", "on", "off", NULL};
static const char *const start_values[] = {"warm", "cold", NULL}; /* SRBF_START_* */
const char *const srbf_env_examples[] = {"studio", "sky", "sunset", "builtin:white",
                                           "data:courtyard.exr", NULL};
const char *const srbf_raster_examples[] = {"160x120", "320x240", "full", NULL};
static const char *const diffuse_examples[] = {"fit", "0.3", "0.35,0.25,0.15", NULL};

static const method_param srbf_params_table[] = {
    {.name = "env", .label = "environment", .type = METHOD_PARAM_TEXT, .affects = "precomputation",
     .description = "the environment lighting the painted views: a built-in (studio, sky, "
                    "sunset, overcast, white), data:FILE of glintd's --env-dir or upload:ID "
                    "of POST /api/v1/environments (HDR lat-long maps or cube crosses); the "
                    "command line reads a map by its path instead (file:PATH)",
     .offset = offsetof(srbf_params, env),
     .syntax = "NAME | builtin:NAME | data:FILE | upload:ID",
     .examples = srbf_env_examples, .parse = srbf_env_parse, .format = srbf_env_format},
    {.name = "env_rotation", .label = "environment turned (degrees)", .type = METHOD_PARAM_NUMBER, .affects = "precomputation",
     .description = "rotation of the environment about the up (+z) axis, degrees",
     .offset = offsetof(srbf_params, env_rotation), .min = -360.0, .max = 360.0},
    {.name = "env_intensity", .label = "environment brightness", .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "scale of the environment's radiance (the painting is divided by it)",
     .offset = offsetof(srbf_params, env_intensity), .min = SRBF_MIN_ENV_INTENSITY,
     .max = SRBF_MAX_ENV_INTENSITY},
    {.name = "lights", .label = "light samples of the environment", .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "lights the environment is compressed into (median cut): the speed-accuracy "
                    "knob; transfer time grows linearly with it",
     .offset = offsetof(srbf_params, lights), .min = 1, .max = 4096},
    {.name = "basis_res", .label = "highlight detail", .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "hemicube resolution r of the lobe centres: J = 3 r^2 lobes (7: 147)",
     .offset = offsetof(srbf_params, basis_res), .min = SRBF_MIN_RES, .max = SRBF_MAX_RES},
    {.name = "sigma", .label = "lobe width (radians)", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "precomputation",
     .description = "width of each spherical Gaussian lobe, radians (pi/40 = 0.0785: half "
                    "maximum at 7.5 degrees)",
     .offset = offsetof(srbf_params, sigma), .min = SRBF_MIN_SIGMA, .max = SRBF_MAX_SIGMA},
    {.name = "static", .label = "highlight shape term", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "precomputation",
     .description = "static term: paper = F/(a+b-ab) (eq. 11); smith = F G2/(4ab), a microfacet "
                    "term with Smith shadowing-masking",
     .offset = offsetof(srbf_params, static_term), .values = static_values},
    {.name = "f0", .label = "reflectance head-on", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "precomputation",
     .description = "Fresnel reflectance at normal incidence (Schlick)",
     .offset = offsetof(srbf_params, f0), .min = 0.0, .max = 1.0},
    {.name = "alpha", .label = "shadowing roughness", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "precomputation",
     .description = "roughness of the Smith shadowing-masking term (static smith only)",
     .offset = offsetof(srbf_params, alpha), .min = 0.01, .max = 1.0},
    {.name = "constraints", .label = "energy constraints", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "fit",
     .description = "energy: c >= 0 and albedo <= 1 (physical); nonneg: c >= 0 only; none: "
                    "unconstrained least squares (physically impossible looks allowed)",
     .offset = offsetof(srbf_params, constraints), .values = constraint_values},
    {.name = "visibility", .label = "self-shadowing", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "precomputation",
     .description = "shadows of the object on itself: auto casts rays unless the mesh is "
                    "convex",
     .offset = offsetof(srbf_params, visibility), .values = srbf_vis_values},
    {.name = "raster", .label = "pixels per view fitted", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_TEXT, .affects = "precomputation",
     .description = "grid of pixels per view that become rows of the fit (the paper: 160x120); "
                    "full: every painted pixel",
     .offset = offsetof(srbf_params, raster), .syntax = "WxH | full",
     .examples = srbf_raster_examples, .parse = srbf_raster_parse, .format = srbf_raster_format},
    {.name = "diffuse", .label = "diffuse colour", .type = METHOD_PARAM_TEXT, .affects = "fit",
     .description = "diffuse albedo rho_d: fitted jointly (fit) or given (grey or r,g,b)",
     .offset = offsetof(srbf_params, diffuse), .syntax = "fit | A | R,G,B",
     .examples = diffuse_examples, .parse = diffuse_parse, .format = diffuse_format},
    {.name = "smooth", .label = "lobe smoothing", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "weight of the smoothness prior on p(h) (relative to the data): steadies "
                    "what the painted views do not determine",
     .offset = offsetof(srbf_params, smooth), .min = 0.0, .max = 1e3},
    {.name = "grazing", .label = "grazing energy rings", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "rings of energy rows near the horizon (64 each) beside the 192 of the "
                    "hemicube, so energy holds at grazing angles too",
     .offset = offsetof(srbf_params, grazing), .min = 0, .max = 8},
    {.name = "start", .label = "solver start", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_ENUM, .affects = "fit",
     .description = "where the constrained solver starts: cold = at zero (the same answer to "
                    "the bit for the same painting); warm = at the scene's previous answer with "
                    "these parameters (the same optimum, its last digits may differ): fewer "
                    "steps when a fit from zero takes many (most lobes used, energy rows "
                    "active), more when it takes few (see BENCHMARKS.md)",
     .offset = offsetof(srbf_params, start), .values = start_values},
};

static const method_preset srbf_presets[] = {
    {"draft", "{\"lights\": 64, \"basis_res\": 5}"},
    {"default", "{\"lights\": 256, \"basis_res\": 7}"},
    {"fine", "{\"lights\": 1024, \"basis_res\": 9, \"raster\": \"full\"}"},
};

static void srbf_params_default(void *pv)
{
    srbf_params *p = pv;
    memset(p, 0, sizeof *p);
    snprintf(p->env, sizeof p->env, "studio");
    p->env_rotation = 0.0;
    p->env_intensity = 1.0;
    p->lights = 256;
    p->basis_res = 7;
    p->sigma = M_PI / 40.0;
    p->static_term = SRBF_STATIC_SMITH; /* generalizes several times better (docs/methods.md) */
    p->f0 = 0.25;
    p->alpha = 0.3;
    p->constraints = LSQ_ENERGY;
    p->visibility = SRBF_VIS_AUTO;
    p->raster.w = 160;
    p->raster.h = 120;
    p->diffuse.fit = 1;
    p->smooth = 1e-4;
    p->grazing = 2;
    p->start = SRBF_START_COLD;
}

/* What a fit with these parameters needs outside them: the environment
 * (resolved by the host, not read), and for visibility on the scene's mesh. */
static int srbf_params_usable(const void *pv, const method_source *src, const char **param,
                              glint_err *err)
{
    const srbf_params *p = pv;
    int rc;
    if ((rc = env_spec_lookup(p->env, err))) {
        *param = "env";
        return rc;
    }
    if (p->visibility == SRBF_VIS_ON && !src->has_mesh) {
        *param = "visibility";
        return glint_err_set(err, GLINT_EINVAL,
                             "on casts shadows with the scene's mesh, and these samples have "
                             "none (made elsewhere: a G-buffer set): set visibility auto or off");
    }
    return 0;
}

/* ---- keys ------------------------------------------------------------------------------ */

static void hashed(const char *text, const char *prefix, char *key, size_t len)
{
    XXH128_hash_t h = XXH3_128bits(text, strlen(text));
    snprintf(key, len, "%s%016llx%016llx", prefix, (unsigned long long)h.high64,
             (unsigned long long)h.low64);
}

static void energy_text(const srbf_params *p, char *buf, size_t len)
{
    snprintf(buf, len, "r%d:s%.17g:st%d:f%.17g:a%.17g:g%d", p->basis_res, p->sigma,
             p->static_term, p->f0, p->static_term == SRBF_STATIC_SMITH ? p->alpha : 0.0,
             p->grazing);
}

static void lights_text(const srbf_params *p, char *buf, size_t len)
{
    snprintf(buf, len, "%s:rot%.17g:k%d", p->env, p->env_rotation, p->lights);
}

static void energy_key(const void *params, const samples *s, const char *prev, char *key,
                       size_t len)
{
    char t[256];
    (void)s;
    (void)prev;
    energy_text(params, t, sizeof t);
    hashed(t, "srbf-energy-", key, len);
}

static void lights_key(const void *params, const samples *s, const char *prev, char *key,
                       size_t len)
{
    char t[256];
    (void)s;
    (void)prev;
    lights_text(params, t, sizeof t);
    hashed(t, "srbf-lights-", key, len);
}

static void vis_text(const srbf_params *p, const samples *s, char *buf, size_t len)
{
    char l[256];
    lights_text(p, l, sizeof l);
    snprintf(buf, len, "%s:%s:v%d:%dx%d", s->hash, l, p->visibility, p->raster.w, p->raster.h);
}

static void vis_key(const void *params, const samples *s, const char *prev, char *key,
                    size_t len)
{
    char t[512];
    (void)prev;
    vis_text(params, s, t, sizeof t);
    hashed(t, "srbf-rows-", key, len);
}

static void transfer_key(const void *params, const samples *s, const char *prev, char *key,
                         size_t len)
{
    char t[1024], e[256];
    const srbf_params *p = params;
    (void)prev;
    vis_text(p, s, t, sizeof t);
    energy_text(p, e, sizeof e);
    snprintf(t + strlen(t), sizeof t - strlen(t), ":%s", e);
    hashed(t, "srbf-transfer-", key, len);
}

static void progress(const method_build_in *in, const char *stage, double f)
{
    if (in->progress)
        in->progress(in->progress_cls, stage, f);
}

/* ---- energy -------------------------------------------------------------------------- */

void srbf_energy_clear(srbf_energy *x)
{
    if (!x)
        return;
    srbf_basis_free(&x->b);
    free(x->wo);
    free(x->g);
    memset(x, 0, sizeof *x);
}

/* Energy rows depend on the basis, the static term and the rings, not on a
 * scene: every cache of the process (a held-out measurement opens its own)
 * shares one copy per parameter set while any of them holds it.  A shared
 * copy starts with its srbf_energy, so the level's data is the same. */
typedef struct shared_energy {
    srbf_energy e;
    char text[160];
    int refs;
    struct shared_energy *next;
} shared_energy;

static pthread_mutex_t shared_lock = PTHREAD_MUTEX_INITIALIZER;
static shared_energy *shared_list;

static shared_energy *energy_shared_get(const srbf_params *p)
{
    char text[160];
    shared_energy *x;
    energy_text(p, text, sizeof text);
    pthread_mutex_lock(&shared_lock);
    for (x = shared_list; x && strcmp(x->text, text); x = x->next)
        ;
    if (x)
        x->refs++;
    pthread_mutex_unlock(&shared_lock);
    return x;
}

/* x (refs 0, not listed) joins the list, unless another thread listed the
 * same rows meanwhile: that copy is taken and x freed. */
static shared_energy *energy_shared_put(const srbf_params *p, shared_energy *x)
{
    shared_energy *y;
    energy_text(p, x->text, sizeof x->text);
    pthread_mutex_lock(&shared_lock);
    for (y = shared_list; y && strcmp(y->text, x->text); y = y->next)
        ;
    if (!y) {
        x->next = shared_list;
        shared_list = x;
        y = x;
        x = NULL;
    }
    y->refs++;
    pthread_mutex_unlock(&shared_lock);
    if (x) {
        srbf_energy_clear(&x->e);
        free(x);
    }
    return y;
}

static void energy_free(void *d)
{
    shared_energy *x = d, **pp;
    if (!x)
        return;
    pthread_mutex_lock(&shared_lock);
    if (x->refs > 0 && --x->refs > 0) {
        pthread_mutex_unlock(&shared_lock);
        return;
    }
    for (pp = &shared_list; *pp && *pp != x; pp = &(*pp)->next)
        ;
    if (*pp)
        *pp = x->next;
    pthread_mutex_unlock(&shared_lock);
    srbf_energy_clear(&x->e);
    free(x);
}

static size_t energy_bytes(const srbf_energy *x)
{
    return sizeof *x + (size_t)x->b.J * 3 * sizeof(double) +
           (size_t)x->nl * (3 + (size_t)x->b.J) * sizeof(double);
}

static void static_of(const srbf_params *p, srbf_static *st)
{
    st->kind = (srbf_static_kind)p->static_term;
    st->f0 = p->f0;
    st->alpha = p->alpha;
}

static void energy_value(shared_energy *x, cache_value *out)
{
    out->data = x;
    out->bytes = energy_bytes(&x->e);
    out->free = energy_free;
}

static int energy_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const srbf_params *p = in->params;
    shared_energy *sx = energy_shared_get(p);
    srbf_energy *x;
    double t0 = glint_now();
    int rc;

    if (sx) {
        energy_value(sx, out);
        return 0;
    }
    if (!(sx = calloc(1, sizeof *sx)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    x = &sx->e;
    progress(in, "energy", 0.02);
    static_of(p, &x->st);
    if ((rc = srbf_basis_make(p->basis_res, p->sigma, &x->b, err)))
        goto fail;
    x->nl = srbf_energy_dirs(p->grazing, NULL);
    x->wo = malloc((size_t)3 * x->nl * sizeof *x->wo);
    x->g = malloc((size_t)x->nl * x->b.J * sizeof *x->g);
    if (!x->wo || !x->g) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the energy rows");
        goto fail;
    }
    srbf_energy_dirs(p->grazing, x->wo);
    if ((rc = srbf_energy_rows(&x->b, &x->st, x->nl, x->wo, 0, x->g, 0, in->cancel, err)))
        goto fail;
    x->seconds = glint_now() - t0;
    energy_value(energy_shared_put(p, sx), out);
    return 0;
fail:
    energy_free(sx);
    return rc;
}

static int energy_load(const method_build_in *in, const char *dir, const char *key,
                       cache_value *out, glint_err *err)
{
    const srbf_params *p = in->params;
    shared_energy *sx = energy_shared_get(p);
    srbf_energy *x;
    int rc;
    if (sx) {
        energy_value(sx, out);
        return 0;
    }
    if (!(sx = calloc(1, sizeof *sx)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    x = &sx->e;
    if ((rc = srbf_energy_load(dir, key, x, err)))
        goto fail;
    if (x->b.res != p->basis_res || x->nl != srbf_energy_dirs(p->grazing, NULL)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "cached energy rows %s do not match", key);
        goto fail;
    }
    static_of(p, &x->st);
    energy_value(energy_shared_put(p, sx), out);
    return 0;
fail:
    energy_free(sx);
    return rc;
}

static int energy_save(const method_build_in *in, const char *dir, const char *key,
                       const cache_value *v, glint_err *err)
{
    (void)in;
    return srbf_energy_save(dir, key, &((const shared_energy *)v->data)->e, err);
}

/* ---- lights ---------------------------------------------------------------------------- */

static void lights_free(void *d)
{
    srbf_lightset *x = d;
    env_lights_free(&x->l);
    free(x);
}

static int lights_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const srbf_params *p = in->params;
    srbf_lightset *x = calloc(1, sizeof *x);
    double t0 = glint_now(), psi = p->env_rotation * M_PI / 180.0;
    env_map m;
    int rc;

    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    memset(&m, 0, sizeof m);
    progress(in, "environment", 0.1);
    /* (kept by env_prepare: the scene's base renders under the same map at
     * the same settings cut it already) */
    if ((rc = env_prepare(p->env, ENV_CUT_MEDIAN, p->lights, psi, 1.0, &m, &x->l, err))) {
        glint_err_prefix(err, "params.env '%s'", p->env);
        free(x);
        return rc;
    }
    rc = env_compress_error(&m, &x->l, psi, 1.0, &x->e, err);
    snprintf(x->name, sizeof x->name, "%s", m.name);
    x->clamped = m.clamped;
    x->nonfinite = m.nonfinite;
    x->map_w = m.width;
    x->map_h = m.height;
    env_map_free(&m);
    if (rc) {
        lights_free(x);
        return rc;
    }
    x->seconds = glint_now() - t0;
    out->data = x;
    out->bytes = sizeof *x + (size_t)x->l.k * 6 * sizeof(double);
    out->free = lights_free;
    return 0;
}

/* ---- visibility ---------------------------------------------------------------------- */

static void visdata_free(void *d)
{
    srbf_visdata *x = d;
    free(x->rows);
    free(x);
}

/* The rows of the fit: samples on a grid of at most raster.w x raster.h
 * pixels per view (stride = the smallest integer that fits; the grid's
 * points sit at stride/2 within each cell), or every sample. */
static int select_rows(const srbf_params *p, const samples *s, srbf_visdata *x, glint_err *err)
{
    int stride = 1;
    if (p->raster.w > 0) {
        int sx = (s->width + p->raster.w - 1) / p->raster.w;
        int sy = (s->height + p->raster.h - 1) / p->raster.h;
        stride = sx > sy ? sx : sy;
        if (stride < 1)
            stride = 1;
    }
    if (!(x->rows = malloc((size_t)(s->n ? s->n : 1) * sizeof *x->rows)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d rows", s->n);
    for (int i = 0; i < s->n; i++) {
        int r = s->pixel[i] / s->width, c = s->pixel[i] % s->width;
        if (stride == 1 || (r % stride == stride / 2 && c % stride == stride / 2))
            x->rows[x->nrows++] = i;
    }
    if (x->nrows == 0)
        return glint_err_set(err, GLINT_EINVAL,
                             "no painted pixel falls on the %dx%d fit grid: use raster full",
                             p->raster.w, p->raster.h);
    return 0;
}

static int vis_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const srbf_params *p = in->params;
    const samples *s = in->s;
    srbf_visdata *x = calloc(1, sizeof *x);
    double t0 = glint_now();
    int rc;

    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    progress(in, "rows", 0.2);
    x->convex = -1;
    if ((rc = select_rows(p, s, x, err)))
        goto fail;
    if (in->sc)
        x->convex = vis_mesh_convex(&in->sc->mesh, 1e-6);
    x->on = p->visibility == SRBF_VIS_ON || (p->visibility == SRBF_VIS_AUTO && x->convex == 0);
    if (x->on && (!in->sc || !s->has_pos)) {
        rc = glint_err_set(err, GLINT_EINVAL,
                           "visibility needs the scene's mesh and the samples' positions "
                           "(samples from elsewhere have neither): set visibility off");
        goto fail;
    }
    x->seconds = glint_now() - t0;
    out->data = x;
    out->bytes = sizeof *x + (size_t)x->nrows * sizeof(int);
    out->free = visdata_free;
    return 0;
fail:
    visdata_free(x);
    return rc;
}

/* Shadow bits of every light from every row (OUT: *bits malloc'ed). */
int srbf_cast_shadows(const method_build_in *in, const srbf_visdata *vd, const env_lights *l,
                        uint64_t **bits, long *rays, glint_err *err)
{
    const samples *s = in->s;
    size_t n = (size_t)vd->nrows, words = (size_t)VIS_WORDS(l->k);
    float *pos = malloc(3 * n * sizeof *pos), *nrm = malloc(3 * n * sizeof *nrm);
    vis_scene *vs = NULL;
    int rc;

    *bits = malloc(n * words * sizeof **bits);
    if (!pos || !nrm || !*bits) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for visibility of %zu rows", n);
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        memcpy(pos + 3 * i, s->pos + 3 * (size_t)vd->rows[i], 3 * sizeof *pos);
        memcpy(nrm + 3 * i, s->nrm + 3 * (size_t)vd->rows[i], 3 * sizeof *nrm);
    }
    if (!(rc = vis_open(&in->sc->mesh, &vs, err)))
        rc = vis_compute(vs, vd->nrows, pos, nrm, l->k, l->dir, *bits, 0, rays, in->cancel,
                         err);
done:
    vis_close(vs);
    free(pos);
    free(nrm);
    if (rc) {
        free(*bits);
        *bits = NULL;
    }
    return rc;
}

static const method_level srbf_levels[] = {
    {.name = "energy", .progress = 0.02, .key = energy_key, .build = energy_build,
     .load = energy_load, .save = energy_save},
    {.name = "lights", .progress = 0.1, .key = lights_key, .build = lights_build},
    {.name = "rows", .progress = 0.2, .key = vis_key, .build = vis_build},
    {.name = "transfer", .progress = 0.4, .key = transfer_key, .build = srbf_transfer_build,
     .load = srbf_transfer_level_load, .save = srbf_transfer_level_save},
};

/* A held-out measurement (prep_holdout) prepares every painted sample
 * once and fits each view's leave-out on it (fits_held), predicting the
 * left-out view under the environment (srbf_predict): one transfer level
 * of every painted view, affordable on a fit grid, not on every pixel. */
static int srbf_holdout_ok(const void *params)
{
    return ((const srbf_params *)params)->raster.w > 0;
}

/* Memory of a cold fit: the pattern (about 100 bytes a sample), T in float
 * and its copies while the Gram matrices are made (3 channels x J x 4
 * bytes a row, bounded by the samples), visibility bits, the lights and the
 * energy rows; the bound leaves a third on top. */
static size_t srbf_fit_bytes(const void *params, long nsamples)
{
    const srbf_params *p = params;
    double J = 3.0 * p->basis_res * p->basis_res, n = (double)nsamples;
    double rows = n;
    if (p->raster.w > 0 && rows > 12.0 * p->raster.w * p->raster.h)
        rows = 12.0 * p->raster.w * p->raster.h;
    double b = 100.0 * n + rows * (3.0 * J * 4.0 + 24.0 + 4.0 + p->lights / 8.0 + 32.0) +
               3.0 * J * J * 8.0 + 1000.0 * (J + 8.0) * 8.0 + (double)(64 << 20);
    b *= 4.0 / 3.0;
    return b >= (double)SIZE_MAX ? SIZE_MAX : (size_t)b;
}

/* A cold fit at the rates measured through glintd (seconds of one core,
 * 2-vCPU development machine; 2 views of a sphere under the built-in sky:
 * basis_res 5 and 64 lights at 48 x 48, energy 38 s on 2 threads,
 * estimated 78 core seconds; basis_res 8, 256 lights, raster full at
 * 128 x 128 (about 21,000 rows), with other work on the machine: transfer
 * 39 s on 2 threads and Gram 7.4 s, estimated 52 and 7 s):
 *   energy    its rows (192 + 512 + 64 grazing) x 27,648 quadrature nodes x J
 *             lobes, 45 ns each (shared by every scene and kept on disk, but
 *             counted: the estimate is of a cold fit);
 *   visibility half the lights per row, 2 us a shadow ray (Embree; unless
 *             visibility is off: auto may find the mesh convex and cast none);
 *   transfer  rows x lights x J, 50 ns;
 *   Gram      3 channels x rows x J^2 / 2, 6 ns;
 *   solve     3 channels x 10 dense steps of J unknowns.
 * Rows as srbf_fit_bytes counts them. */
static double srbf_fit_seconds(const void *params, long nsamples)
{
    const srbf_params *p = params;
    double J = 3.0 * p->basis_res * p->basis_res, n = (double)nsamples, rows = n;
    double nl = srbf_energy_dirs(p->grazing, NULL), L = p->lights, s;
    if (p->raster.w > 0 && rows > 12.0 * p->raster.w * p->raster.h)
        rows = 12.0 * p->raster.w * p->raster.h;
    s = n * METHOD_SECONDS_PER_SAMPLE + nl * 27648.0 * J * 45e-9 + rows * L * J * 50e-9 +
        3.0 * rows * J * J / 2.0 * 6e-9 + 3.0 * 10.0 * method_dense_seconds(J);
    if (p->visibility != SRBF_VIS_OFF)
        s += rows * L / 2.0 * 2e-6;
    return s;
}

const method method_srbf = {
    .name = "srbf",
    .label = "Under an environment",
    .summary = "One finish seen under an environment: the highlight is built from many "
        "small soft spots of light, never reflecting more light than it receives.",
    .when = "Use it when you paint how the object looks under an environment (sky, "
        "studio, an HDR map) rather than under a point light.",
    .lighting = METHOD_LIGHT_ENV,
    .fits_held = 1,
    .shows = METHOD_SHOWS_LOBES,
    .title = "Spherical-Gaussian distribution BRDF under environment light",
    .reference = "Iwasaki, Dobashi, Yoshimoto & Nishita, Interactive BRDF Modeling under "
                 "Environment Lighting, 2009",
    .description =
        "The painted views are lit by an environment (compressed into lights); the BRDF is "
        "rho_d/pi + p(h) s(wi, wo), p a non-negative sum of spherical Gaussian lobes around "
        "fixed centres. Transfer matrices of the painted pixels (with shadows cast by the "
        "mesh unless it is convex) and their Gram matrices are precomputed and cached; a fit "
        "solves a constrained least-squares problem per colour channel: lobe weights >= 0 and "
        "energy conservation (directional albedo <= 1) at 192 + 64 x grazing outgoing "
        "directions. Points: fit_seconds is the warm fit, cold_seconds the precomputation, "
        "rms_painted the RMS error on the fitted pixels, held_out_rms the pooled RMS on each "
        "painted view left out of the fit (its pixels on the fit grid, rendered under the "
        "environment with the transfer matrices of that view).",
    .held_out = "leave-one-view-out: for each painted view, fit the others and measure the RMS "
                "error on that view's pixels; pooled over views",
    .schema = "FitParamsSrbf.json",
    .params_size = sizeof(srbf_params),
    .params = srbf_params_table,
    .nparams = (int)(sizeof srbf_params_table / sizeof srbf_params_table[0]),
    .presets = srbf_presets,
    .npresets = (int)(sizeof srbf_presets / sizeof srbf_presets[0]),
    .params_default = srbf_params_default,
    .params_usable = srbf_params_usable,
    .pattern_rule = SAMPLES_SEEN,
    .levels = srbf_levels,
    .nlevels = (int)(sizeof srbf_levels / sizeof srbf_levels[0]),
    .fit = srbf_fit,
    .predict = srbf_predict,
    .mat = &srbf_material_ops,
    .holdout_ok = srbf_holdout_ok,
    .fit_bytes = srbf_fit_bytes,
    .fit_seconds = srbf_fit_seconds,
};
