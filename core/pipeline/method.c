/* method.c: the registry of methods and their parameter tables (method.h). */
#include "method.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "material.h"

#define METHOD_MAX 64 /* built-in and a test build's together */

/* The methods every build has (method_registry.c). */
extern const method *const method_builtin[];

/* Methods a program adds at link time (a test build's): a NULL-terminated
 * array defined by an object linked into that program, absent otherwise. */
extern const method *const method_extra[] __attribute__((weak));

static const method *registry[METHOD_MAX];
static int nregistry;
static pthread_once_t registry_once = PTHREAD_ONCE_INIT;
static pthread_mutex_t registry_lock = PTHREAD_MUTEX_INITIALIZER;

static int name_ok(const char *n)
{
    size_t len = n ? strlen(n) : 0;
    if (len == 0 || len > 15)
        return 0;
    for (const char *c = n; *c; c++)
        if (!((*c >= 'a' && *c <= 'z') || (*c >= '0' && *c <= '9') || *c == '_' || *c == '-'))
            return 0;
    return 1;
}

static void add_locked(const method *m)
{
    if (nregistry >= METHOD_MAX) {
        /* a build's own table outgrew the registry: say so, never drop it quietly */
        fprintf(stderr, "glint: more than %d methods; %s is not registered\n", METHOD_MAX,
                m->name ? m->name : "(unnamed)");
        return;
    }
    if (name_ok(m->name))
        registry[nregistry++] = m;
}

static void registry_init(void)
{
    for (int i = 0; method_builtin[i]; i++)
        add_locked(method_builtin[i]);
    if (method_extra)
        for (int i = 0; method_extra[i]; i++)
            add_locked(method_extra[i]);
}

int method_count(void)
{
    int n;
    pthread_once(&registry_once, registry_init);
    pthread_mutex_lock(&registry_lock);
    n = nregistry;
    pthread_mutex_unlock(&registry_lock);
    return n;
}

const method *method_at(int i)
{
    const method *m = NULL;
    pthread_once(&registry_once, registry_init);
    pthread_mutex_lock(&registry_lock);
    if (i >= 0 && i < nregistry)
        m = registry[i];
    pthread_mutex_unlock(&registry_lock);
    return m;
}

void method_memo_drop_data(method_memo *mm)
{
    if (!mm)
        return;
    if (mm->data && mm->free)
        mm->free(mm->data);
    mm->owner = NULL;
    mm->data = NULL;
    mm->free = NULL;
}

void method_memo_drop_values(method_memo *mm)
{
    if (!mm)
        return;
    free(mm->values);
    free(mm->values_tags);
    free(mm->values_ok);
    free(mm->values_key);
    free(mm->values_gen);
    mm->values = NULL;
    mm->values_tags = NULL;
    mm->values_ok = NULL;
    mm->values_key = NULL;
    mm->values_gen = NULL;
    mm->values_n = mm->values_nviews = 0;
    mm->values_epoch = mm->values_id = 0;
}

void method_memo_clear(method_memo *mm)
{
    if (!mm)
        return;
    method_memo_drop_data(mm);
    method_memo_drop_values(mm);
    memset(mm, 0, sizeof *mm);
}

const method *method_find(const char *name)
{
    const method *m = NULL;
    pthread_once(&registry_once, registry_init);
    if (!name)
        return NULL;
    pthread_mutex_lock(&registry_lock);
    for (int i = 0; i < nregistry && !m; i++)
        if (strcmp(registry[i]->name, name) == 0)
            m = registry[i];
    pthread_mutex_unlock(&registry_lock);
    return m;
}

void method_names(char *buf, size_t len)
{
    size_t used = 0;
    int n = method_count();
    buf[0] = '\0';
    for (int i = 0; i < n && used < len; i++) {
        int w = snprintf(buf + used, len - used, "%s%s", i ? ", " : "", method_at(i)->name);
        if (w < 0)
            break;
        used += (size_t)w;
    }
}

/* ---- parameters ------------------------------------------------------------------ */

void *method_params_new(const method *m)
{
    void *p = calloc(1, m->params_size ? m->params_size : 1);
    if (p)
        m->params_default(p);
    return p;
}

const method_param *method_param_find(const method *m, const char *name)
{
    for (int i = 0; i < m->nparams; i++)
        if (strcmp(m->params[i].name, name) == 0 ||
            (m->params[i].option && strcmp(m->params[i].option, name) == 0))
            return &m->params[i];
    return NULL;
}

static void *field_of(const method_param *p, void *params)
{
    return (char *)params + p->offset;
}

static const void *cfield_of(const method_param *p, const void *params)
{
    return (const char *)params + p->offset;
}

/* "[0, 1e+08]", "(0, 1)", "4..512" */
static void range_text(const method_param *p, char *buf, size_t len)
{
    if (p->type == METHOD_PARAM_INT)
        snprintf(buf, len, "%.0f..%.0f", p->min, p->max);
    else
        snprintf(buf, len, "%c%g, %g%c", p->min_exclusive ? '(' : '[', p->min, p->max,
                 p->max_exclusive ? ')' : ']');
}

static void values_text(const method_param *p, char *buf, size_t len)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; p->values[i] && used < len; i++) {
        int w = snprintf(buf + used, len - used, "%s\"%s\"", i ? ", " : "", p->values[i]);
        if (w < 0)
            break;
        used += (size_t)w;
    }
}

static int in_range(const method_param *p, double x)
{
    if (!isfinite(x))
        return 0;
    if (p->min_exclusive ? !(x > p->min) : !(x >= p->min))
        return 0;
    if (p->max_exclusive ? !(x < p->max) : !(x <= p->max))
        return 0;
    return 1;
}

/* Set a checked value; `label` names the parameter in messages. */
static int set_int(const method_param *p, void *params, double x, const char *label,
                   glint_err *err)
{
    char r[96];
    if (!in_range(p, x) || x != floor(x)) {
        range_text(p, r, sizeof r);
        return glint_err_set(err, GLINT_EINVAL, "%s must be an integer in %s", label, r);
    }
    *(int *)field_of(p, params) = (int)x;
    return 0;
}

static int set_number(const method_param *p, void *params, double x, const char *label,
                      glint_err *err)
{
    char r[96];
    if (!in_range(p, x)) {
        range_text(p, r, sizeof r);
        return glint_err_set(err, GLINT_EINVAL, "%s must be a finite number in %s", label, r);
    }
    *(double *)field_of(p, params) = x;
    return 0;
}

static int set_enum(const method_param *p, void *params, const char *s, const char *label,
                    glint_err *err)
{
    char v[256];
    for (int i = 0; s && p->values[i]; i++)
        if (strcmp(s, p->values[i]) == 0) {
            *(int *)field_of(p, params) = i;
            return 0;
        }
    values_text(p, v, sizeof v);
    return glint_err_set(err, GLINT_EINVAL, "%s must be one of %s", label, v);
}

static int set_text(const method_param *p, void *params, const char *s, const char *label,
                    glint_err *err)
{
    glint_err e;
    if (p->parse(s, field_of(p, params), &e))
        return glint_err_set(err, e.code ? e.code : GLINT_EINVAL, "%s: %s", label, e.msg);
    return 0;
}

static void unknown_param(const method *m, const char *label, glint_err *err)
{
    char names[512];
    size_t used = 0;
    names[0] = '\0';
    for (int i = 0; i < m->nparams && used < sizeof names; i++) {
        int w = snprintf(names + used, sizeof names - used, "%s%s", i ? ", " : "",
                         m->params[i].name);
        if (w < 0)
            break;
        used += (size_t)w;
    }
    glint_err_set(err, GLINT_EINVAL, "unknown parameter %s (%s takes %s)", label, m->name,
                  names);
}

int method_param_set_json(const method *m, void *params, const char *name, const json_t *v,
                          glint_err *err)
{
    const method_param *p = NULL;
    char label[96];

    for (int i = 0; i < m->nparams && !p; i++)
        if (strcmp(m->params[i].name, name) == 0)
            p = &m->params[i];
    snprintf(label, sizeof label, "params.%.64s", name);
    if (!p) {
        unknown_param(m, label, err);
        return GLINT_EINVAL;
    }
    switch (p->type) {
    case METHOD_PARAM_INT:
        if (!json_is_integer(v)) {
            char r[96];
            range_text(p, r, sizeof r);
            return glint_err_set(err, GLINT_EINVAL, "%s must be an integer in %s", label, r);
        }
        return set_int(p, params, (double)json_integer_value(v), label, err);
    case METHOD_PARAM_NUMBER:
        if (!json_is_number(v)) {
            char r[96];
            range_text(p, r, sizeof r);
            return glint_err_set(err, GLINT_EINVAL, "%s must be a finite number in %s", label,
                                 r);
        }
        return set_number(p, params, json_number_value(v), label, err);
    case METHOD_PARAM_ENUM:
        return set_enum(p, params, json_string_value(v), label, err);
    case METHOD_PARAM_TEXT:
        if (!json_is_string(v))
            return glint_err_set(err, GLINT_EINVAL, "%s must be a string (%s)", label,
                                 p->syntax ? p->syntax : "see GET /api/v1/methods");
        return set_text(p, params, json_string_value(v), label, err);
    }
    return glint_err_set(err, GLINT_EINTERNAL, "%s: bad parameter table", label);
}

int method_params_from_json(const method *m, void *params, const json_t *obj, glint_err *err)
{
    const char *k;
    json_t *v;
    int rc;

    if (!json_is_object(obj))
        return glint_err_set(err, GLINT_EINVAL, "params must be an object");
    json_object_foreach((json_t *)obj, k, v) {
        if ((rc = method_param_set_json(m, params, k, v, err)))
            return rc;
    }
    return m->params_check ? m->params_check(params, err) : 0;
}

int method_params_usable(const method *m, const void *params, const method_source *src,
                         glint_err *err)
{
    const char *param = NULL;
    glint_err e = {0};
    if (!m->params_usable || !m->params_usable(params, src, &param, &e))
        return 0;
    return glint_err_set(err, GLINT_EINVAL, "params.%s: %s", param ? param : "?", e.msg);
}

int method_param_set_text(const method *m, void *params, const char *name, const char *text,
                          glint_err *err)
{
    const method_param *p = method_param_find(m, name);
    char label[160];
    char *end;
    double x;

    snprintf(label, sizeof label, "--%.32s '%.64s'", name, text ? text : "");
    if (!p) {
        char opt[48];
        snprintf(opt, sizeof opt, "--%.32s", name);
        unknown_param(m, opt, err);
        return GLINT_EINVAL;
    }
    if (!text)
        text = "";
    switch (p->type) {
    case METHOD_PARAM_INT:
    case METHOD_PARAM_NUMBER:
        x = strtod(text, &end);
        if (end == text || *end) {
            char r[96];
            range_text(p, r, sizeof r);
            return glint_err_set(err, GLINT_EINVAL, "%s must be %s in %s", label,
                                 p->type == METHOD_PARAM_INT ? "an integer" : "a finite number",
                                 r);
        }
        return p->type == METHOD_PARAM_INT ? set_int(p, params, x, label, err)
                                           : set_number(p, params, x, label, err);
    case METHOD_PARAM_ENUM:
        return set_enum(p, params, text, label, err);
    case METHOD_PARAM_TEXT:
        return set_text(p, params, text, label, err);
    }
    return glint_err_set(err, GLINT_EINTERNAL, "%s: bad parameter table", label);
}

void method_param_format(const method_param *p, const void *params, char *buf, size_t len)
{
    const void *f = cfield_of(p, params);
    switch (p->type) {
    case METHOD_PARAM_INT: snprintf(buf, len, "%d", *(const int *)f); break;
    case METHOD_PARAM_NUMBER: {
        /* the shortest spelling that reads back exactly */
        double x = *(const double *)f;
        for (int prec = 6; prec <= 17; prec++) {
            snprintf(buf, len, "%.*g", prec, x);
            if (strtod(buf, NULL) == x)
                break;
        }
        break;
    }
    case METHOD_PARAM_ENUM: snprintf(buf, len, "%s", p->values[*(const int *)f]); break;
    case METHOD_PARAM_TEXT: p->format(f, buf, len); break;
    }
}

static json_t *param_value_json(const method_param *p, const void *params)
{
    const void *f = cfield_of(p, params);
    char buf[256];
    switch (p->type) {
    case METHOD_PARAM_INT: return json_integer(*(const int *)f);
    case METHOD_PARAM_NUMBER: return json_real(*(const double *)f);
    case METHOD_PARAM_ENUM: return json_string(p->values[*(const int *)f]);
    case METHOD_PARAM_TEXT: p->format(f, buf, sizeof buf); return json_string(buf);
    }
    return json_null();
}

json_t *method_rms_by_view(const double *se, const long *n, int nviews)
{
    json_t *a = json_array();
    for (int k = 0; a && k < nviews; k++) {
        if (n[k] <= 0)
            continue;
        if (json_array_append_new(a, json_pack("{s:i, s:f, s:I}", "view", k, "rms",
                                               sqrt(se[k] / (3.0 * n[k])), "samples",
                                               (json_int_t)n[k]))) {
            json_decref(a);
            return NULL;
        }
    }
    return a;
}

json_t *method_params_to_json(const method *m, const void *params)
{
    json_t *o = json_object();
    for (int i = 0; o && i < m->nparams; i++)
        json_object_set_new(o, m->params[i].name, param_value_json(&m->params[i], params));
    return o;
}

static json_t *strings_json(const char *const *list)
{
    json_t *a = json_array();
    for (int i = 0; list && list[i]; i++)
        json_array_append_new(a, json_string(list[i]));
    return a;
}

static const char *type_name(const method_param *p)
{
    switch (p->type) {
    case METHOD_PARAM_INT: return "integer";
    case METHOD_PARAM_NUMBER: return "number";
    default: return "string";
    }
}

int method_available(const method *m, glint_err *why)
{
    glint_err_clear(why);
    return m->available ? m->available(why) : 0;
}

static void describe_availability(const method *m, json_t *o)
{
    glint_err why;
    int rc = method_available(m, &why);
    json_object_set_new(o, "available", json_boolean(!rc));
    if (rc)
        json_object_set_new(o, "unavailable", json_string(why.msg));
}

json_t *method_describe(const method *m)
{
    void *def = method_params_new(m);
    json_t *o, *params = json_array(), *presets = json_array();

    if (!def || !params || !presets) {
        free(def);
        json_decref(params);
        json_decref(presets);
        return NULL;
    }
    for (int i = 0; i < m->nparams; i++) {
        const method_param *p = &m->params[i];
        json_t *d = json_object();
        json_object_set_new(d, "name", json_string(p->name));
        json_object_set_new(d, "label", json_string(p->label ? p->label : p->name));
        json_object_set_new(d, "group",
                            json_string(p->group == METHOD_GROUP_ADVANCED ? "advanced" : "basic"));
        json_object_set_new(d, "type", json_string(type_name(p)));
        json_object_set_new(d, "default", param_value_json(p, def));
        if (p->type == METHOD_PARAM_INT || p->type == METHOD_PARAM_NUMBER) {
            json_t *lo = p->type == METHOD_PARAM_INT ? json_integer((json_int_t)p->min)
                                                     : json_real(p->min);
            json_t *hi = p->type == METHOD_PARAM_INT ? json_integer((json_int_t)p->max)
                                                     : json_real(p->max);
            json_object_set_new(d, p->min_exclusive ? "exclusiveMinimum" : "minimum", lo);
            json_object_set_new(d, p->max_exclusive ? "exclusiveMaximum" : "maximum", hi);
        }
        if (p->type == METHOD_PARAM_ENUM)
            json_object_set_new(d, "enum", strings_json(p->values));
        if (p->type == METHOD_PARAM_TEXT) {
            if (p->syntax)
                json_object_set_new(d, "syntax", json_string(p->syntax));
            if (p->examples)
                json_object_set_new(d, "examples", strings_json(p->examples));
        }
        json_object_set_new(d, "affects", json_string(p->affects));
        json_object_set_new(d, "description", json_string(p->description));
        json_array_append_new(params, d);
    }
    for (int i = 0; i < m->npresets; i++) {
        json_t *pp = json_loads(m->presets[i].params, 0, NULL);
        json_array_append_new(presets, json_pack("{s:s, s:o}", "name", m->presets[i].name,
                                                 "params", pp ? pp : json_object()));
    }
    free(def);
    o = json_pack("{s:s, s:s}", "name", m->name, "title", m->title);
    json_object_set_new(o, "label", json_string(m->label ? m->label : m->title));
    json_object_set_new(o, "summary", json_string(m->summary ? m->summary : m->description));
    if (m->when)
        json_object_set_new(o, "when", json_string(m->when));
    json_object_set_new(o, "lighting",
                        json_string(m->lighting == METHOD_LIGHT_ENV ? "environment" : "point"));
    json_object_set_new(o, "varies", json_boolean(m->mat && m->mat->spatial));
    json_object_set_new(o, "surface", strings_json(m->surface));
    json_object_set_new(o, "shows", json_string(m->shows == METHOD_SHOWS_LOBES     ? "lobes"
                                                : m->shows == METHOD_SHOWS_FACTORS ? "factors"
                                                                                   : "none"));
    json_object_set_new(o, "chooses", json_boolean(m->chooses));
    if (m->reference)
        json_object_set_new(o, "reference", json_string(m->reference));
    json_object_set_new(o, "description", json_string(m->description));
    json_object_set_new(o, "params", params);
    json_object_set_new(o, "presets", presets);
    if (m->held_out)
        json_object_set_new(o, "held_out", json_string(m->held_out));
    describe_availability(m, o);
    return o;
}

json_t *method_params_schema(const method *m)
{
    void *def = method_params_new(m);
    json_t *props = json_object(), *root;
    char desc[512];

    for (int i = 0; def && i < m->nparams; i++) {
        const method_param *p = &m->params[i];
        json_t *s = json_object();
        char dv[256];
        method_param_format(p, def, dv, sizeof dv);
        switch (p->type) {
        case METHOD_PARAM_INT:
        case METHOD_PARAM_NUMBER:
            json_object_set_new(s, "type", json_string(type_name(p)));
            json_object_set_new(s, p->min_exclusive ? "exclusiveMinimum" : "minimum",
                                p->type == METHOD_PARAM_INT ? json_integer((json_int_t)p->min)
                                                            : json_real(p->min));
            json_object_set_new(s, p->max_exclusive ? "exclusiveMaximum" : "maximum",
                                p->type == METHOD_PARAM_INT ? json_integer((json_int_t)p->max)
                                                            : json_real(p->max));
            break;
        case METHOD_PARAM_ENUM:
            json_object_set_new(s, "enum", strings_json(p->values));
            break;
        case METHOD_PARAM_TEXT:
            json_object_set_new(s, "type", json_string("string"));
            json_object_set_new(s, "minLength", json_integer(1));
            break;
        }
        snprintf(desc, sizeof desc, "%s%s%s (default %s; affects the %s)", p->description,
                 p->syntax ? ": " : "", p->syntax ? p->syntax : "", dv, p->affects);
        json_object_set_new(s, "description", json_string(desc));
        json_object_set_new(props, p->name, s);
    }
    free(def);
    snprintf(desc, sizeof desc,
             "Parameters of the %s method (%s). Every member is optional in a request; a "
             "material reports all of them. Generated from the method's parameter table "
             "(glint methods --schema %s).", m->name, m->title, m->name);
    {
        char id[64], title[64];
        snprintf(id, sizeof id, "%s", m->schema ? m->schema : "");
        if (!m->schema)
            snprintf(id, sizeof id, "FitParams-%s.json", m->name);
        snprintf(title, sizeof title, "%.*s", (int)(strlen(id) > 5 ? strlen(id) - 5 : 0), id);
        root = json_pack("{s:s, s:s, s:s, s:s, s:s, s:b, s:o}", "$schema",
                         "https://json-schema.org/draft/2020-12/schema", "$id", id, "title",
                         title, "description", desc, "type", "object",
                         "additionalProperties", 0, "properties", props);
    }
    return root;
}

void material_gpu_free(material_gpu *g)
{
    if (!g)
        return;
    free(g->tex);
    json_decref(g->manifest);
    memset(g, 0, sizeof *g);
}

double method_fit_seconds(const method *m, const void *params, long nsamples)
{
    if (nsamples < 0)
        nsamples = 0;
    if (m->fit_seconds)
        return m->fit_seconds(params, nsamples);
    return (double)nsamples * METHOD_SECONDS_PER_SAMPLE;
}

double method_dense_seconds(double n)
{
    return n * n * n * METHOD_SECONDS_PER_FLOP;
}

size_t method_fit_bytes(const method *m, const void *params, long nsamples)
{
    if (nsamples < 0)
        nsamples = 0;
    if (m->fit_bytes)
        return m->fit_bytes(params, nsamples);
    return (size_t)nsamples * METHOD_FIT_BYTES_PER_SAMPLE;
}
