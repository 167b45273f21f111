/* measured.c: the published abc and sgd fits of measured materials
 * (measured.h), their file and their specs. */
#include "measured.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fsio.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define MEASURED_FILE_MAX (16L << 20) /* bytes of a fits file */

/* ---- evaluation ---------------------------------------------------------------------- */

/* The exact unpolarized Fresnel reflectance of a dielectric of relative
 * index ior at cos_d = c (README: g = sqrt(ior^2 - 1 + c^2)); 1 where g is
 * not real (total internal reflection, ior < 1). */
static double fresnel_dielectric(double c, double ior)
{
    double g2 = ior * ior - 1.0 + c * c, g, a, b;
    if (!(g2 > 0.0))
        return 1.0;
    g = sqrt(g2);
    a = (g - c) / (g + c);
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
}

static void abc_eval(const measured_abc *p, double ci, double co, double ch, double cd,
                     double rgb[3])
{
    double g = fmin(1.0, fmin(2.0 * ch * ci / cd, 2.0 * ch * co / cd));
    double fg = fresnel_dielectric(cd, p->ior) * g / (M_PI * ci * co);
    double shape = pow(1.0 + p->b * (1.0 - ch), -p->c);
    for (int c = 0; c < 3; c++)
        rgb[c] = p->kd[c] / M_PI + fg * p->a[c] * shape;
}

double measured_sgd_d(const measured_sgd *p, int c, double ch)
{
    double c2 = ch * ch, t2 = (1.0 - c2) / c2, s = p->alpha[c] + t2 / p->alpha[c];
    return p->kap[c] * exp(-s) / (M_PI * pow(s, p->p[c]) * c2 * c2);
}

/* G1 at polar angle t (radians) of channel c. */
static double sgd_g1(const measured_sgd *p, int c, double t)
{
    double x = t - p->theta0[c], e, g;
    if (!(x > 0.0))
        return 1.0;
    e = p->c[c] * pow(x, p->k[c]);
    if (!(e < 700.0)) /* exp overflows: its limit */
        return p->lambda[c] > 0.0 ? 0.0 : 1.0;
    g = 1.0 + p->lambda[c] * (1.0 - exp(e));
    return g < 0.0 ? 0.0 : g > 1.0 ? 1.0 : g;
}

static void sgd_eval(const measured_sgd *p, double ci, double co, double ch, double cd,
                     double rgb[3])
{
    double ti = acos(fmin(ci, 1.0)), to = acos(fmin(co, 1.0)), m5 = 1.0 - cd;
    m5 = m5 * m5 * m5 * m5 * m5;
    for (int c = 0; c < 3; c++) {
        double f = p->f0[c] - p->f1[c] * cd + (1.0 - p->f0[c]) * m5;
        double g = sgd_g1(p, c, ti) * sgd_g1(p, c, to);
        double spec = g > 0.0 ? p->rho_s[c] * f * measured_sgd_d(p, c, ch) * g / (ci * co) : 0.0;
        rgb[c] = (p->rho_d[c] + spec) / M_PI;
    }
}

void measured_eval(const measured_truth *t, const double n[3], const double wi[3],
                   const double wo[3], double rgb[3])
{
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    double co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]}, hl, ch, cd;

    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(ci > 0.0 && co > 0.0))
        return;
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    ch = (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl;
    cd = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl;
    /* both above the horizon: h is too, and wi.h = |wi + wo| / 2 > 0 */
    ch = ch > 1.0 ? 1.0 : ch;
    cd = cd > 1.0 ? 1.0 : cd;
    if (!(ch > 0.0 && cd > 0.0))
        return;
    if (t->model == MEASURED_ABC)
        abc_eval(&t->abc, ci, co, ch, cd, rgb);
    else
        sgd_eval(&t->sgd, ci, co, ch, cd, rgb);
}

void measured_truth_fn(const void *ctx, const double n[3], const double wi[3],
                       const double wo[3], double f[3])
{
    measured_eval(ctx, n, wi, wo, f);
}

void measured_envlit(const void *ctx, const double uv[2], const double n[3], const double wi[3],
                     const double wo[3], double rgb[3])
{
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    (void)uv;
    measured_eval(ctx, n, wi, wo, rgb);
    for (int c = 0; c < 3; c++)
        rgb[c] *= ci > 0.0 ? ci : 0.0;
}

void measured_truth_of(const measured_material *m, measured_model model, measured_truth *out)
{
    memset(out, 0, sizeof *out);
    out->model = model;
    snprintf(out->name, sizeof out->name, "%s", m->name);
    if (model == MEASURED_ABC)
        out->abc = m->abc;
    else
        out->sgd = m->sgd;
}

/* ---- the file -------------------------------------------------------------------------- */

/* The range a field must lie in. */
typedef enum { ANY, NONNEG, POS } range;

typedef struct field {
    const char *name;
    size_t offset;     /* of the double (or double[3]) in its struct */
    int len;           /* 1 or 3 */
    range r;
} field;

#define ABC_F(n, m, l, r) {n, offsetof(measured_abc, m), l, r}
#define SGD_F(n, m, r) {n, offsetof(measured_sgd, m), 3, r}

static const field ABC_FIELDS[] = {
    ABC_F("kD", kd, 3, NONNEG), ABC_F("A", a, 3, NONNEG), ABC_F("B", b, 1, POS),
    ABC_F("C", c, 1, POS), ABC_F("ior", ior, 1, POS),
};
static const field SGD_FIELDS[] = {
    SGD_F("rhoD", rho_d, NONNEG), SGD_F("rhoS", rho_s, NONNEG), SGD_F("alpha", alpha, POS),
    SGD_F("p", p, ANY), SGD_F("f0", f0, ANY), SGD_F("f1", f1, ANY),
    SGD_F("kap", kap, POS), SGD_F("lambda", lambda, NONNEG), SGD_F("c", c, NONNEG),
    SGD_F("k", k, POS), SGD_F("theta0", theta0, ANY),
};
#define NFIELDS(a) ((int)(sizeof a / sizeof a[0]))

/* Where a message is: "FILE: materials[I] (NAME): " */
typedef struct where {
    const char *file;
    int index;
    const char *name;  /* NULL before the name is read */
    glint_err *err;
} where;

static int bad(const where *w, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int bad(const where *w, const char *fmt, ...)
{
    char msg[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (w->name)
        return glint_err_set(w->err, GLINT_EFORMAT, "%s: materials[%d] (%.64s): %s", w->file,
                             w->index, w->name, msg);
    return glint_err_set(w->err, GLINT_EFORMAT, "%s: materials[%d]: %s", w->file, w->index,
                         msg);
}

static const char *kind(const json_t *v)
{
    switch (json_typeof(v)) {
    case JSON_OBJECT: return "an object";
    case JSON_ARRAY: return "an array";
    case JSON_STRING: return "a string";
    case JSON_INTEGER:
    case JSON_REAL: return "a number";
    case JSON_TRUE:
    case JSON_FALSE: return "a boolean";
    default: return "null";
    }
}

/* One number of a field (`what`, e.g. "sgd.kap[1]"). */
static int number(const json_t *v, range r, const where *w, const char *what, double *out)
{
    double x;
    if (!json_is_number(v))
        return bad(w, "%s must be a number, got %s", what, kind(v));
    x = json_number_value(v);
    if (!isfinite(x)) /* jansson reads none, but a caller's tree may hold one */
        return bad(w, "%s must be finite, got %g", what, x);
    if (r == NONNEG && !(x >= 0.0))
        return bad(w, "%s must be >= 0, got %.6g", what, x);
    if (r == POS && !(x > 0.0))
        return bad(w, "%s must be > 0, got %.6g", what, x);
    *out = x;
    return 0;
}

/* The fields of one model's object (`model`: "abc" or "sgd") into the
 * struct at base; `optional` names a member accepted and not read. */
static int model_fields(const json_t *obj, const char *model, const field *fs, int nf,
                        const char *optional, const where *w, void *base)
{
    const char *key;
    const json_t *v;
    char what[64];
    int rc;

    if (!obj)
        return bad(w, "no %s object", model);
    if (!json_is_object(obj))
        return bad(w, "%s must be an object, got %s", model, kind(obj));
    json_object_foreach((json_t *)obj, key, v) {
        int known = optional && !strcmp(key, optional);
        for (int i = 0; i < nf && !known; i++)
            known = !strcmp(key, fs[i].name);
        if (!known)
            return bad(w, "%s has an unknown member '%.40s'", model, key);
    }
    for (int i = 0; i < nf; i++) {
        double *dst = (double *)((char *)base + fs[i].offset);
        v = json_object_get(obj, fs[i].name);
        snprintf(what, sizeof what, "%s.%s", model, fs[i].name);
        if (!v)
            return bad(w, "%s is missing", what);
        if (fs[i].len == 1) {
            if ((rc = number(v, fs[i].r, w, what, dst)))
                return rc;
            continue;
        }
        if (!json_is_array(v) || json_array_size(v) != 3)
            return bad(w, "%s must be an array of 3 numbers (r, g, b), got %s%s", what,
                       kind(v), json_is_array(v) ? " of another length" : "");
        for (int c = 0; c < 3; c++) {
            snprintf(what, sizeof what, "%s.%s[%d]", model, fs[i].name, c);
            if ((rc = number(json_array_get(v, c), fs[i].r, w, what, &dst[c])))
                return rc;
        }
    }
    if (optional && (v = json_object_get(obj, optional))) { /* checked, not kept */
        double unused;
        snprintf(what, sizeof what, "%s.%s", model, optional);
        if (!json_is_array(v) || json_array_size(v) != 3)
            return bad(w, "%s must be an array of 3 numbers, got %s", what, kind(v));
        for (int c = 0; c < 3; c++) {
            snprintf(what, sizeof what, "%s.%s[%d]", model, optional, c);
            if ((rc = number(json_array_get(v, c), ANY, w, what, &unused)))
                return rc;
        }
    }
    return 0;
}

static int name_ok(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n >= MEASURED_NAME_MAX || s[0] == '.' || s[0] == '-')
        return 0;
    for (size_t i = 0; i < n; i++)
        if (!((s[i] >= 'a' && s[i] <= 'z') || (s[i] >= '0' && s[i] <= '9') || s[i] == '.' ||
              s[i] == '_' || s[i] == '-'))
            return 0;
    return 1;
}

static int material_read(const json_t *jm, where *w, measured_material *out)
{
    const char *key;
    const json_t *v, *name;
    int rc;

    if (!json_is_object(jm))
        return bad(w, "must be an object, got %s", kind(jm));
    name = json_object_get(jm, "name");
    if (!name)
        return bad(w, "no name");
    if (!json_is_string(name))
        return bad(w, "name must be a string, got %s", kind(name));
    if (!name_ok(json_string_value(name)))
        return bad(w, "name '%.64s' must be 1 to %d of a-z 0-9 . _ - (not starting with . or -)",
                   json_string_value(name), MEASURED_NAME_MAX - 1);
    snprintf(out->name, sizeof out->name, "%s", json_string_value(name));
    w->name = out->name;
    json_object_foreach((json_t *)jm, key, v) {
        if (strcmp(key, "name") && strcmp(key, "abc") && strcmp(key, "sgd"))
            return bad(w, "unknown member '%.40s' (name, abc and sgd are read)", key);
    }
    if ((rc = model_fields(json_object_get(jm, "abc"), "abc", ABC_FIELDS, NFIELDS(ABC_FIELDS),
                           NULL, w, &out->abc)) ||
        (rc = model_fields(json_object_get(jm, "sgd"), "sgd", SGD_FIELDS, NFIELDS(SGD_FIELDS),
                           "error", w, &out->sgd)))
        return rc;
    return 0;
}

int measured_from_json(const json_t *root, const char *file, measured_set *out, glint_err *err)
{
    const json_t *mats;
    measured_set s = {NULL, 0};
    size_t n;
    int rc;

    memset(out, 0, sizeof *out);
    file = file ? file : "measured fits";
    if (!json_is_object(root))
        return glint_err_set(err, GLINT_EFORMAT, "%s: expected an object with \"materials\", "
                             "got %s", file, kind(root));
    mats = json_object_get(root, "materials");
    if (!json_is_array(mats))
        return glint_err_set(err, GLINT_EFORMAT, "%s: \"materials\" must be an array, got %s",
                             file, mats ? kind(mats) : "nothing");
    n = json_array_size(mats);
    if (n == 0 || n > MEASURED_MAX)
        return glint_err_set(err, GLINT_EFORMAT, "%s: %zu materials (1 to %d are read)", file,
                             n, MEASURED_MAX);
    s.m = calloc(n, sizeof *s.m);
    if (!s.m)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (size_t i = 0; i < n; i++) {
        where w = {file, (int)i, NULL, err};
        if ((rc = material_read(json_array_get(mats, i), &w, &s.m[i]))) {
            free(s.m);
            return rc;
        }
        for (size_t j = 0; j < i; j++)
            if (!strcmp(s.m[j].name, s.m[i].name)) {
                rc = bad(&w, "name repeats materials[%zu]", j);
                free(s.m);
                return rc;
            }
        s.n++;
    }
    *out = s;
    return 0;
}

int measured_parse(const char *text, size_t len, const char *file, measured_set *out,
                   glint_err *err)
{
    json_error_t jerr;
    json_t *root;
    int rc;

    memset(out, 0, sizeof *out);
    file = file ? file : "measured fits";
    root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    if (!root)
        return glint_err_set(err, GLINT_EFORMAT, "%s: line %d: %s", file, jerr.line, jerr.text);
    rc = measured_from_json(root, file, out, err);
    json_decref(root);
    return rc;
}

int measured_load(const char *path, measured_set *out, glint_err *err)
{
    char *text = NULL;
    size_t len = 0;
    int rc;

    memset(out, 0, sizeof *out);
    if ((rc = fsio_read_all(path, MEASURED_FILE_MAX, &text, &len, err)))
        return rc;
    rc = measured_parse(text, len, path, out, err);
    free(text);
    return rc;
}

void measured_free(measured_set *s)
{
    if (!s)
        return;
    free(s->m);
    s->m = NULL;
    s->n = 0;
}

const measured_material *measured_find(const measured_set *s, const char *name)
{
    for (int i = 0; s && name && i < s->n; i++)
        if (!strcmp(s->m[i].name, name))
            return &s->m[i];
    return NULL;
}

/* ---- the process's file ------------------------------------------------------------------ */

static pthread_mutex_t lock_ = PTHREAD_MUTEX_INITIALIZER;
static char path_[4096], hint_[256];
static measured_set set_;
static unsigned generation_;   /* calls of measured_set_file */
static int loaded_;

void measured_set_file(const char *path, const char *hint)
{
    pthread_mutex_lock(&lock_);
    measured_free(&set_);
    loaded_ = 0;
    generation_++;
    snprintf(path_, sizeof path_, "%s", path ? path : "");
    snprintf(hint_, sizeof hint_, "%s", hint ? hint : "");
    pthread_mutex_unlock(&lock_);
}

unsigned measured_generation(void)
{
    unsigned g;
    pthread_mutex_lock(&lock_);
    g = generation_;
    pthread_mutex_unlock(&lock_);
    return g;
}

int measured_current(const measured_set **out, glint_err *err)
{
    int rc = 0;
    *out = NULL;
    pthread_mutex_lock(&lock_);
    if (!path_[0])
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no measured fits here%s%s",
                           hint_[0] ? ": " : "", hint_);
    else if (!loaded_ && (rc = measured_load(path_, &set_, err)) == 0)
        loaded_ = 1;
    if (!rc)
        *out = &set_;
    pthread_mutex_unlock(&lock_);
    return rc;
}

int measured_spec_is(const char *spec)
{
    return spec && (!strncmp(spec, "sgd:", 4) || !strncmp(spec, "abc:", 4));
}

int measured_truth_parse(const char *spec, measured_truth *out, glint_err *err)
{
    const measured_set *s;
    const measured_material *m;
    int rc;

    memset(out, 0, sizeof *out);
    if (!measured_spec_is(spec))
        return glint_err_set(err, GLINT_EINVAL, "'%.100s' is not a measured fit (sgd:NAME or "
                             "abc:NAME)", spec ? spec : "");
    if (!spec[4])
        return glint_err_set(err, GLINT_EINVAL, "%.3s: a measured material needs a name", spec);
    if ((rc = measured_current(&s, err)))
        return glint_err_prefix(err, "%.100s", spec);
    if (!(m = measured_find(s, spec + 4)))
        return glint_err_set(err, GLINT_ENOTFOUND,
                             "%.100s: no measured material '%.64s' among the %d of %.200s", spec,
                             spec + 4, s->n, path_);
    measured_truth_of(m, spec[0] == 's' ? MEASURED_SGD : MEASURED_ABC, out);
    return 0;
}
