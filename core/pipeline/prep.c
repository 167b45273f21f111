/* prep.c: a fit's precomputation through the cache (prep.h). */
#include "prep.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "internal/prep_int.h"
#include "pattern.h"
#include "raster.h"

struct prep {
    const method *m;
    void *params;                         /* a copy */
    cache_entry *pattern;
    cache_how pattern_how;
    double pattern_spent;
    cache_entry *lv[METHOD_MAX_LEVELS];
    cache_how how[METHOD_MAX_LEVELS];
    double spent[METHOD_MAX_LEVELS];
};

/* ---- scene level ---------------------------------------------------------------- */

typedef struct scene_ctx {
    const char *id;
    const prep_scene_source *src;
} scene_ctx;

static size_t mesh_bytes(const mesh *m)
{
    return (size_t)m->nverts * 8 * sizeof(float) + (size_t)m->ntris * 3 * sizeof(uint32_t);
}

static void scene_free_value(void *data)
{
    prep_scene *ps = data;
    if (ps->sc && ps->src.unload)
        ps->src.unload(ps->src.cls, ps->sc);
    free(ps);
}

static int scene_build(void *ctx, cache_value *out, glint_err *err)
{
    scene_ctx *x = ctx;
    prep_scene *ps = calloc(1, sizeof *ps);
    int rc;
    if (!ps)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = x->src->load(x->src->cls, x->id, &ps->sc, err))) {
        free(ps);
        return rc;
    }
    ps->src = *x->src;
    snprintf(ps->id, sizeof ps->id, "%s", x->id);
    scene_hash(ps->sc, ps->hash);
    out->data = ps;
    out->bytes = sizeof *ps + mesh_bytes(&ps->sc->mesh) +
                 (size_t)ps->sc->nviews * sizeof(scene_view);
    out->free = scene_free_value;
    return 0;
}

int prep_scene_acquire(cache *c, const char *id, const prep_scene_source *src,
                       cache_entry **out, glint_err *err)
{
    static const cache_level level = {.name = "scene", .build = scene_build};
    scene_ctx x = {id, src};
    char key[CACHE_KEY_MAX];
    *out = NULL;
    if (!id || strlen(id) >= sizeof((prep_scene *)0)->id)
        return glint_err_set(err, GLINT_EINVAL, "scene id too long");
    snprintf(key, sizeof key, "scene:%s", id);
    return cache_acquire(c, &level, key, &x, NULL, out, NULL, NULL, err);
}

const prep_scene *prep_scene_of(const cache_entry *e)
{
    return cache_data(e);
}

/* ---- pattern level ---------------------------------------------------------------- */

typedef struct pattern_ctx {
    const prep_scene *ps;
    const unsigned char *use;
    samples *given;          /* samples made by the caller, moved into the value */
    int rule;                /* SAMPLES_LIT or SAMPLES_SEEN (the method's) */
    prep_progress_fn cb;
    void *cls;
} pattern_ctx;

static size_t samples_bytes(const samples *s)
{
    return sizeof *s + (size_t)s->n * (2 * sizeof(int) + 14 * sizeof(float) + 2 * sizeof(double)) +
           (size_t)s->nviews;
}

static void samples_free_value(void *data)
{
    samples_free(data);
    free(data);
}

static void pattern_starting(void *ctx, int how)
{
    pattern_ctx *x = ctx;
    if (x->cb)
        x->cb(x->cls, "samples", 0.0);
    (void)how;
}

/* Rasterize view v of sc in bands of rows (at most PREP_BAND_PIXELS of
 * G-buffer at a time) and hand each band to fn. */
typedef int (*band_fn)(void *cls, int view, const gbuf *band, int row0, glint_err *err);

static int raster_bands(const scene *sc, int v, band_fn fn, void *cls, glint_err *err)
{
    int band = PREP_BAND_PIXELS / sc->width, rc = 0;
    if (band < 1)
        band = 1;
    for (int row0 = 0; row0 < sc->height && !rc; row0 += band) {
        int nrows = sc->height - row0 < band ? sc->height - row0 : band;
        gbuf g;
        if ((rc = raster_view_rows(&sc->mesh, &sc->views[v], sc->width, sc->height, row0, nrows,
                                   &g, err)))
            break;
        rc = fn(cls, v, &g, row0, err);
        gbuf_free(&g);
    }
    if (rc)
        glint_err_prefix(err, "rasterizing view %d", v);
    return rc;
}

static void pattern_progress(void *cls, int done, int nused)
{
    pattern_ctx *x = cls;
    if (x->cb)
        x->cb(x->cls, "samples", 0.25 * done / nused);
}

static void pattern_value(samples *s, cache_value *out)
{
    out->data = s;
    out->bytes = samples_bytes(s);
    out->free = samples_free_value;
}

static int pattern_build(void *ctx, cache_value *out, glint_err *err)
{
    pattern_ctx *x = ctx;
    samples *s = calloc(1, sizeof *s);
    int rc = 0;

    if (!s)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (x->given) {
        *s = *x->given;
        memset(x->given, 0, sizeof *x->given);
    } else {
        /* views not used are left out of the pattern; the machine's cores
         * rasterize the others, a view per thread at a time */
        pattern_in in = {x->ps->sc, x->use, x->rule, x->ps->hash, PREP_BAND_PIXELS, 0,
                         pattern_progress, x};
        rc = pattern_raster(&in, s, err);
    }
    if (rc) {
        samples_free(s);
        free(s);
        return rc;
    }
    pattern_value(s, out);
    return 0;
}

/* The disk layer of scene patterns (pattern.h): a file is checked against
 * the scene and the views it was asked for. */
static int pattern_disk_load(void *ctx, const char *dir, const char *key, cache_value *out,
                             glint_err *err)
{
    pattern_ctx *x = ctx;
    samples *s = calloc(1, sizeof *s);
    int rc;
    if (!s)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = pattern_load(dir, key, x->ps->sc, x->ps->hash, x->use, x->rule, s, err))) {
        free(s);
        return rc;
    }
    pattern_value(s, out);
    return 0;
}

static int pattern_disk_save(void *ctx, const char *dir, const char *key, const cache_value *v,
                             glint_err *err)
{
    (void)ctx;
    return pattern_save(v->data, dir, key, err);
}

void prep_pattern_key(const prep_scene *ps, const unsigned char *use, int rule, char *key)
{
    int n = snprintf(key, CACHE_KEY_MAX, "pattern%s:%s:", rule == SAMPLES_SEEN ? "-seen" : "",
                     ps->hash);
    /* the used-view flags as hex digits, 4 views per digit */
    for (int v = 0; v < ps->sc->nviews && n + 2 < CACHE_KEY_MAX; v += 4) {
        int nib = 0;
        for (int k = 0; k < 4 && v + k < ps->sc->nviews; k++)
            nib |= (use[v + k] ? 1 : 0) << k;
        key[n++] = "0123456789abcdef"[nib];
    }
    key[n] = '\0';
}

/* ---- the method's levels ------------------------------------------------------------ */

typedef struct level_ctx {
    const method_level *lv;
    method_build_in in;
} level_ctx;

static void level_starting(void *ctx, int how)
{
    level_ctx *x = ctx;
    /* a build reports its own stages; a wait shows the level's */
    if (how == CACHE_JOINED && x->in.progress)
        x->in.progress(x->in.progress_cls, x->lv->name, x->lv->progress);
}

static int level_build(void *ctx, cache_value *out, glint_err *err)
{
    level_ctx *x = ctx;
    return x->lv->build(&x->in, out, err);
}

static int level_load(void *ctx, const char *dir, const char *key, cache_value *out,
                      glint_err *err)
{
    level_ctx *x = ctx;
    return x->lv->load(&x->in, dir, key, out, err);
}

static int level_save(void *ctx, const char *dir, const char *key, const cache_value *v,
                      glint_err *err)
{
    level_ctx *x = ctx;
    return x->lv->save(&x->in, dir, key, v, err);
}

/* ---- prepared fits ------------------------------------------------------------------ */

static prep *prep_new(const method *m, const void *params, glint_err *err)
{
    prep *p = calloc(1, sizeof *p);
    if (p && !(p->params = malloc(m->params_size ? m->params_size : 1))) {
        free(p);
        p = NULL;
    }
    if (!p) {
        glint_err_set(err, GLINT_ENOMEM, "out of memory");
        return NULL;
    }
    if (m->nlevels > METHOD_MAX_LEVELS) {
        free(p->params);
        free(p);
        glint_err_set(err, GLINT_EINTERNAL, "method %s has %d levels (at most %d)", m->name,
                      m->nlevels, METHOD_MAX_LEVELS);
        return NULL;
    }
    p->m = m;
    memcpy(p->params, params, m->params_size);
    return p;
}

void prep_release(cache *c, prep *p)
{
    if (!p)
        return;
    /* a pattern cut short under it is dropped with what was built from it */
    if (p->pattern && samples_torn(cache_data(p->pattern)))
        cache_forget(c, p->pattern);
    for (int i = p->m->nlevels - 1; i >= 0; i--)
        cache_release(c, p->lv[i]);
    cache_release(c, p->pattern);
    free(p->params);
    free(p);
}

/* cache_acquire for a caller whose own cancel did not say to stop: a
 * build it joined that its builder's cancel stopped (GLINT_ECANCELLED) is
 * asked for again (now built by this caller, or joined anew).  A caller
 * told to stop gets GLINT_ECANCELLED before anything is built. */
#define PREP_REJOINS 8
static int acquire_uncancelled(cache *c, const cache_level *lv, const char *key, void *ctx,
                               cache_entry *parent, cache_entry **out, cache_how *how,
                               double *seconds, const glint_cancel *cancel, glint_err *err)
{
    int rc = GLINT_ECANCELLED;
    for (int k = 0; k < PREP_REJOINS && rc == GLINT_ECANCELLED; k++) {
        if (glint_cancelled(cancel))
            return glint_cancel_err(err, "the precomputation");
        rc = cache_acquire(c, lv, key, ctx, parent, out, how, seconds, err);
    }
    return rc;
}

/* The method's levels after the pattern (p->pattern set); sc: the scene
 * the pattern came from, or NULL. */
static int acquire_levels(cache *c, prep *p, const scene *sc, prep_progress_fn cb, void *cls,
                          const glint_cancel *cancel, glint_err *err)
{
    const samples *s = cache_data(p->pattern);
    const void *prev[METHOD_MAX_LEVELS];
    char key[CACHE_KEY_MAX], prev_key[CACHE_KEY_MAX];
    int rc;

    snprintf(prev_key, sizeof prev_key, "%s", s->hash);
    for (int i = 0; i < p->m->nlevels; i++) {
        const method_level *ml = &p->m->levels[i];
        cache_level cl = {.name = ml->name, .starting = level_starting, .build = level_build};
        level_ctx x;
        memset(&x, 0, sizeof x);
        x.lv = ml;
        x.in.params = p->params;
        x.in.s = s;
        x.in.sc = sc;
        x.in.prev = prev;
        x.in.level = i;
        x.in.progress = cb;
        x.in.progress_cls = cls;
        x.in.cancel = cancel;
        if (ml->load && ml->save) {
            cl.load = level_load;
            cl.save = level_save;
        }
        ml->key(p->params, s, prev_key, key, sizeof key);
        rc = acquire_uncancelled(c, &cl, key, &x, i ? p->lv[i - 1] : p->pattern, &p->lv[i],
                                 &p->how[i], &p->spent[i], cancel, err);
        if (rc)
            return rc;
        prev[i] = cache_data(p->lv[i]);
        snprintf(prev_key, sizeof prev_key, "%s", key);
    }
    return 0;
}

int prep_acquire(cache *c, const prep_request *rq, prep_progress_fn cb, void *cls, prep **out,
                 glint_err *err)
{
    /* a scene's pattern is kept on disk too */
    static const cache_level pattern_level = {.name = "pattern", .starting = pattern_starting,
                                              .build = pattern_build,
                                              .load = pattern_disk_load,
                                              .save = pattern_disk_save};
    const prep_scene *ps = cache_data(rq->scene);
    pattern_ctx px = {ps, rq->use, NULL, rq->m->pattern_rule, cb, cls};
    char key[CACHE_KEY_MAX];
    prep *p;
    int rc;

    *out = NULL;
    if (!(p = prep_new(rq->m, rq->params, err)))
        return GLINT_ENOMEM;
    prep_pattern_key(ps, rq->use, rq->m->pattern_rule, key);
    rc = acquire_uncancelled(c, &pattern_level, key, &px, NULL, &p->pattern, &p->pattern_how,
                             &p->pattern_spent, rq->cancel, err);
    if (!rc && samples_torn(cache_data(p->pattern))) { /* cut short under another fit */
        cache_forget(c, p->pattern);
        cache_release(c, p->pattern);
        p->pattern = NULL;
        rc = acquire_uncancelled(c, &pattern_level, key, &px, NULL, &p->pattern,
                                 &p->pattern_how, &p->pattern_spent, rq->cancel, err);
    }
    if (!rc)
        rc = acquire_levels(c, p, ps->sc, cb, cls, rq->cancel, err);
    if (rc) {
        prep_release(c, p);
        return rc;
    }
    *out = p;
    return 0;
}

int prep_acquire_samples(cache *c, const method *m, const void *params, samples *s,
                         prep_progress_fn cb, void *cls, const glint_cancel *cancel,
                         prep **out, glint_err *err)
{
    /* samples of the caller's are not a scene's: memory only */
    static const cache_level pattern_level = {.name = "pattern", .starting = pattern_starting,
                                              .build = pattern_build};
    pattern_ctx px = {NULL, NULL, s, m->pattern_rule, cb, cls};
    char key[CACHE_KEY_MAX];
    prep *p;
    int rc;

    *out = NULL;
    if (!(p = prep_new(m, params, err)))
        return GLINT_ENOMEM;
    snprintf(key, sizeof key, "samples:%s", s->hash);
    rc = cache_acquire(c, &pattern_level, key, &px, NULL, &p->pattern, &p->pattern_how,
                       &p->pattern_spent, err);
    samples_free(s); /* when the cache had them already, or the build failed */
    if (!rc)
        rc = acquire_levels(c, p, NULL, cb, cls, cancel, err);
    if (rc) {
        prep_release(c, p);
        return rc;
    }
    *out = p;
    return 0;
}

/* The prepared fit whose pattern has `key`, if it and every level are in
 * memory now. */
static int try_key(cache *c, const method *m, const void *params, const char *pattern_key,
                   prep **out, glint_err *err)
{
    char key[CACHE_KEY_MAX], prev_key[CACHE_KEY_MAX];
    const samples *s;
    prep *p;

    *out = NULL;
    if (!(p = prep_new(m, params, err)))
        return GLINT_ENOMEM;
    if (cache_find(c, pattern_key, &p->pattern))
        goto miss;
    s = cache_data(p->pattern);
    snprintf(prev_key, sizeof prev_key, "%s", s->hash);
    for (int i = 0; i < p->m->nlevels; i++) {
        p->m->levels[i].key(p->params, s, prev_key, key, sizeof key);
        if (cache_find(c, key, &p->lv[i]))
            goto miss;
        snprintf(prev_key, sizeof prev_key, "%s", key);
    }
    cache_hit(c, p->pattern);
    for (int i = 0; i < p->m->nlevels; i++)
        cache_hit(c, p->lv[i]);
    *out = p;
    return 0;
miss:
    prep_release(c, p);
    return glint_err_set(err, GLINT_ENOTFOUND, "the precomputation is not in memory");
}

int prep_try(cache *c, const prep_request *rq, prep **out, glint_err *err)
{
    char key[CACHE_KEY_MAX];
    prep_pattern_key(cache_data(rq->scene), rq->use, rq->m->pattern_rule, key);
    return try_key(c, rq->m, rq->params, key, out, err);
}

int prep_try_samples(cache *c, const method *m, const void *params, const samples *s,
                     prep **out, glint_err *err)
{
    char key[CACHE_KEY_MAX];
    snprintf(key, sizeof key, "samples:%s", s->hash);
    return try_key(c, m, params, key, out, err);
}

const samples *prep_samples(const prep *p)
{
    return cache_data(p->pattern);
}

cache_entry *prep_pattern(const prep *p)
{
    return p->pattern;
}

double prep_cold_seconds(const prep *p)
{
    return cache_cold_seconds(p->m->nlevels ? p->lv[p->m->nlevels - 1] : p->pattern);
}

static cache_disk first_disk(const prep *p)
{
    for (int i = 0; i < p->m->nlevels; i++)
        if (cache_disk_of(p->lv[i]) != CACHE_DISK_OFF)
            return cache_disk_of(p->lv[i]);
    return CACHE_DISK_OFF;
}

int prep_from_disk(const prep *p)
{
    return first_disk(p) == CACHE_DISK_LOADED;
}

int prep_was_hit(const prep *p)
{
    if (p->pattern_how != CACHE_HIT)
        return 0;
    for (int i = 0; i < p->m->nlevels; i++)
        if (p->how[i] != CACHE_HIT)
            return 0;
    return 1;
}

static json_t *level_report(const cache_entry *e, cache_how how, double spent)
{
    return json_pack("{s:s, s:s, s:s, s:I, s:f, s:f}", "key", cache_key(e), "memory",
                     cache_how_names[how], "disk", cache_disk_names[cache_disk_of(e)], "bytes",
                     (json_int_t)cache_bytes(e), "build_seconds", cache_build_seconds(e),
                     "waited_seconds", how == CACHE_JOINED ? spent : 0.0);
}

/* How the preparation as a whole got its levels: built if any was built,
 * else joined if any was waited for, else hit. */
static cache_how overall_how(const prep *p)
{
    cache_how overall = p->pattern_how;
    for (int i = 0; i < p->m->nlevels; i++) {
        if (p->how[i] == CACHE_BUILT || overall == CACHE_BUILT)
            overall = CACHE_BUILT;
        else if (p->how[i] == CACHE_JOINED)
            overall = CACHE_JOINED;
    }
    return overall;
}

json_t *prep_report(const prep *p)
{
    json_t *r = json_object(), *levels = json_object();
    const cache_entry *last = p->m->nlevels ? p->lv[p->m->nlevels - 1] : p->pattern;

    json_object_set_new(levels, "pattern",
                        level_report(p->pattern, p->pattern_how, p->pattern_spent));
    for (int i = 0; i < p->m->nlevels; i++)
        json_object_set_new(levels, p->m->levels[i].name,
                            level_report(p->lv[i], p->how[i], p->spent[i]));
    json_object_set_new(r, "memory", json_string(cache_how_names[overall_how(p)]));
    json_object_set_new(r, "disk", json_string(cache_disk_names[first_disk(p)]));
    json_object_set_new(r, "key", json_string(cache_key(last)));
    json_object_set_new(r, "cold_seconds", json_real(cache_cold_seconds(last)));
    json_object_set_new(r, "levels", levels);
    return r;
}

void fit_report_free(fit_report *r)
{
    if (!r)
        return;
    json_decref(r->members);
    free(r->view_errors);
    memset(r, 0, sizeof *r);
}

/* The members of the material document that a fit's info gives: the ones
 * every method writes, and those of a method's own that people read (auto:
 * what it chose and why).  The rest of the info stays in material.json. */
static const char *const doc_members[] = {"params", "errors", "seconds", "precomputation",
                                          "choice"};

/* The errors by view a method gave (errors.rms_by_view, method_rms_by_view)
 * into r; entries not of that form are skipped. */
static int view_errors_of(const json_t *errors, fit_report *r, glint_err *err)
{
    const json_t *a = json_object_get(errors, "rms_by_view");
    size_t i;

    if (!json_is_array(a) || json_array_size(a) == 0)
        return 0;
    if (!(r->view_errors = malloc(json_array_size(a) * sizeof *r->view_errors)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (i = 0; i < json_array_size(a); i++) {
        const json_t *e = json_array_get(a, i), *v = json_object_get(e, "view"), *x = json_object_get(e, "rms"),
                     *n = json_object_get(e, "samples");
        if (!json_is_integer(v) || !json_is_number(x) || !json_is_integer(n))
            continue;
        r->view_errors[r->nview_errors].view = (int)json_integer_value(v);
        r->view_errors[r->nview_errors].rms = json_number_value(x);
        r->view_errors[r->nview_errors].samples = (long)json_integer_value(n);
        r->nview_errors++;
    }
    return 0;
}

/* A method lit by point lights fits the painted values over each sample's
 * intensity (samples_gather: f cos_i, scene.h) and gives its errors in
 * those units; the material states them in the painting's, times each
 * view's pi I: exactly, view by view, for errors.rms_by_view and, when
 * every sample has one intensity, for rms_painted and max_abs_painted;
 * else rms_painted pooled from the views' when they are given.  srbf, lit
 * by an environment, fits and reports the painting's own values. */
static void errors_in_painted_units(const prep *p, material *m)
{
    json_t *errors = json_object_get(m->info, "errors"), *byv, *x;
    const samples *s = prep_samples(p);
    double iv[SCENE_MAX_VIEWS], I, ss = 0.0;
    long n = 0;
    int uniform = 1;
    size_t k;

    if (p->m->lighting != METHOD_LIGHT_POINT || !json_is_object(errors) || !s || s->n == 0)
        return;
    I = s->intensity[0];
    for (int v = 0; v < SCENE_MAX_VIEWS; v++)
        iv[v] = NAN;
    for (int i = 0; i < s->n; i++) {
        iv[s->view[i]] = s->intensity[i];
        uniform &= s->intensity[i] == I;
    }
    byv = json_object_get(errors, "rms_by_view");
    json_array_foreach(byv, k, x) {
        json_t *v = json_object_get(x, "view"), *r = json_object_get(x, "rms");
        json_int_t vk = json_integer_value(v);
        double rv;
        if (!json_is_integer(v) || !json_is_number(r) || vk < 0 || vk >= SCENE_MAX_VIEWS ||
            isnan(iv[vk]))
            continue;
        rv = json_number_value(r) * iv[vk];
        json_object_set_new(x, "rms", json_real(rv));
        ss += rv * rv * (double)json_integer_value(json_object_get(x, "samples"));
        n += (long)json_integer_value(json_object_get(x, "samples"));
    }
    if (uniform) {
        static const char *const keys[] = {"rms_painted", "max_abs_painted"};
        for (int i = 0; i < 2; i++)
            if (json_is_number(x = json_object_get(errors, keys[i])))
                json_object_set_new(errors, keys[i], json_real(json_number_value(x) * I));
    } else if (n > 0) {
        json_object_set_new(errors, "rms_painted", json_real(sqrt(ss / (double)n)));
    }
}

/* The report of a fit of preparation p that made material m. */
static int report_of(const prep *p, const material *m, fit_report *r, glint_err *err)
{
    const json_t *info = m->info, *errors = json_object_get(info, "errors");
    const json_t *pre = json_object_get(info, "precomputation");
    const json_t *rms = json_object_get(errors, "rms_painted");
    const char *chosen = json_string_value(json_object_get(json_object_get(info, "choice"),
                                                           "chosen"));
    int rc;

    memset(r, 0, sizeof *r);
    r->errors_ok = json_is_object(errors);
    r->rms_painted = json_is_number(rms) ? json_number_value(rms) : NAN;
    r->fit_seconds = json_number_value(json_object_get(json_object_get(info, "seconds"), "fit"));
    r->memory = cache_how_names[overall_how(p)];
    r->cold_seconds = prep_cold_seconds(p);
    r->from_disk = prep_from_disk(p);
    r->levels = 1 + p->m->nlevels;
    r->levels_built = p->pattern_how == CACHE_BUILT;
    r->levels_loaded = r->levels_built && cache_disk_of(p->pattern) == CACHE_DISK_LOADED;
    for (int i = 0; i < p->m->nlevels; i++)
        if (p->how[i] == CACHE_BUILT) {
            r->levels_built++;
            r->levels_loaded += cache_disk_of(p->lv[i]) == CACHE_DISK_LOADED;
        }
    r->stream_chunks = (int)json_integer_value(json_object_get(pre, "stream_chunks"));
    r->stream_chunks_reused =
        (int)json_integer_value(json_object_get(pre, "stream_chunks_reused"));
    snprintf(r->chosen, sizeof r->chosen, "%s", chosen ? chosen : "");
    r->params = json_object_get(info, "params");
    if ((rc = view_errors_of(errors, r, err)))
        return rc;
    if (!(r->members = json_object())) {
        fit_report_free(r);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    for (size_t i = 0; i < sizeof doc_members / sizeof doc_members[0]; i++) {
        json_t *v = json_object_get(info, doc_members[i]);
        if (v && json_object_set(r->members, doc_members[i], v)) {
            fit_report_free(r);
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        }
    }
    return 0;
}

/* The fit's inputs from a preparation (the arrays are the caller's). */
static void fit_in_of(const prep *p, const float *rgb, const void **levels, const char **keys,
                      cache_disk *disk, method_fit_in *in)
{
    for (int i = 0; i < p->m->nlevels; i++) {
        levels[i] = cache_data(p->lv[i]);
        keys[i] = cache_key(p->lv[i]);
        disk[i] = cache_disk_of(p->lv[i]);
    }
    memset(in, 0, sizeof *in);
    in->params = p->params;
    in->s = cache_data(p->pattern);
    in->rgb = rgb;
    in->levels = levels;
    in->keys = keys;
    in->how = p->how;
    in->spent = p->spent;
    in->disk = disk;
    in->pattern_seconds = p->pattern_how == CACHE_HIT ? 0.0 : p->pattern_spent;
}

int prep_predict(const prep *p, const material *m, float *rgb, glint_err *err)
{
    const samples *s = cache_data(p->pattern);
    const void *levels[METHOD_MAX_LEVELS];
    const char *keys[METHOD_MAX_LEVELS];
    cache_disk disk[METHOD_MAX_LEVELS];
    method_fit_in in;

    if (p->m->predict) {
        fit_in_of(p, NULL, levels, keys, disk, &in);
        return p->m->predict(&in, m, rgb, err);
    }
    prep_point_lit(s, m, -1, rgb);
    return 0;
}

int prep_fit(const prep *p, const img *paintings, const float *rgb, material *out,
             glint_err *err)
{
    return prep_fit_reusing(p, paintings, rgb, NULL, NULL, out, NULL, err);
}

int prep_fit_held(const prep *p, const float *rgb, const unsigned char *held, material *out,
                  glint_err *err)
{
    const void *levels[METHOD_MAX_LEVELS];
    const char *keys[METHOD_MAX_LEVELS];
    cache_disk disk[METHOD_MAX_LEVELS];
    method_fit_in in;

    memset(out, 0, sizeof *out);
    if (!p->m->fits_held)
        return glint_err_set(err, GLINT_EINVAL, "method %s cannot leave samples out of a fit",
                             p->m->name);
    fit_in_of(p, rgb, levels, keys, disk, &in);
    in.held = held;
    return p->m->fit(&in, out, err);
}

/* The most a memo keeps of a pattern's painted values (3 n floats): 16
 * MiB, 1.4 million samples (12 views of 256x256 of the built-in sphere
 * hold 393,512: 4.7 MB).  Larger patterns gather every view each fit. */
#define PREP_MEMO_VALUES_MAX ((size_t)16 << 20)

/* Make mm's values those of pattern `key` (n samples, nviews views),
 * every view's invalid when they were another's: 0 when they were this
 * pattern's already, 1 when the values are new (a new history), or -1 out
 * of memory (mm's values are then freed). */
static int values_for(method_memo *mm, const char *key, int n, int nviews)
{
    if (mm->values && mm->values_n == n && mm->values_nviews == nviews && mm->values_key &&
        strcmp(mm->values_key, key) == 0)
        return 0;
    method_memo_drop_values(mm);
    /* zeroed (pages the kernel gives zeroed, untouched): a read after one
     * that failed part way compares with defined values */
    mm->values = calloc((size_t)3 * n, sizeof *mm->values);
    mm->values_tags = calloc((size_t)nviews, sizeof *mm->values_tags);
    mm->values_ok = calloc((size_t)nviews, 1);
    mm->values_key = strdup(key);
    mm->values_gen = calloc(((size_t)n + SAMPLES_SPAN - 1) / SAMPLES_SPAN,
                            sizeof *mm->values_gen);
    mm->values_n = n;
    mm->values_nviews = nviews;
    mm->values_epoch = 0;
    mm->values_id = samples_change_id();
    if (mm->values && mm->values_tags && mm->values_ok && mm->values_key && mm->values_gen)
        return 1;
    method_memo_drop_values(mm);
    return -1;
}

/* The samples' values through the memo: read again from the paintings
 * only for the views whose tags changed since the memo's values were
 * read (equal tags promise equal paintings, method.h), so the values are
 * those samples_gather gives.  The read is numbered (values_epoch) and
 * the spans whose values it changed get its number (values_gen); a read
 * that fails gives the memo a new history (values_id).  OUT: *rgb (the
 * memo's), *read (views read).  1: the memo cannot hold them (too large,
 * out of memory): gather apart. */
static int gather_reusing(const prep *p, const samples *s, const img *paintings,
                          const uint64_t *tags, method_memo *mm, const float **rgb, int *read,
                          glint_err *err)
{
    size_t nspans = ((size_t)s->n + SAMPLES_SPAN - 1) / SAMPLES_SPAN;
    unsigned char *which, *changed;
    int rc, fresh;

    if ((size_t)3 * s->n * sizeof(float) > PREP_MEMO_VALUES_MAX ||
        (fresh = values_for(mm, cache_key(p->pattern), s->n, s->nviews)) < 0)
        return 1;
    which = calloc((size_t)s->nviews, 1);
    changed = calloc(nspans, 1);
    if (!which || !changed) {
        free(which);
        free(changed);
        return 1;
    }
    mm->values_epoch++;
    *read = 0;
    for (int v = 0; v < s->nviews; v++)
        if (s->used[v] && (!mm->values_ok[v] || mm->values_tags[v] != tags[v])) {
            which[v] = 1;
            mm->values_ok[v] = 0; /* until read whole */
            (*read)++;
        }
    /* New values are not compared with the zeros they replace: a history
     * starts there, and reading pages never written faults each in twice
     * (the zero page mapped, then replaced on the write, which flushes the
     * other threads' TLBs).  In glintd's first fit of 12 views of 256x256
     * after a restart the gather took 12.7-16.1 ms so, 2.5-2.8 without. */
    if (fresh)
        memset(changed, 1, nspans);
    rc = *read ? samples_gather_views(s, paintings, which, mm->values, fresh ? NULL : changed,
                                      err)
               : 0;
    for (size_t k = 0; k < nspans; k++)
        if (changed[k])
            mm->values_gen[k] = mm->values_epoch;
    if (!rc) {
        for (int v = 0; v < s->nviews; v++)
            if (which[v]) {
                mm->values_ok[v] = 1;
                mm->values_tags[v] = tags[v];
            }
    } else {
        mm->values_id = samples_change_id();
    }
    free(which);
    free(changed);
    if (rc)
        return rc; /* a glint error (< 0) */
    *rgb = mm->values;
    return 0;
}

int prep_fit_reusing(const prep *p, const img *paintings, const float *rgb,
                     const uint64_t *tags, method_memo *memo, material *out, fit_report *rep,
                     glint_err *err)
{
    const samples *s = cache_data(p->pattern);
    const void *levels[METHOD_MAX_LEVELS];
    const char *keys[METHOD_MAX_LEVELS];
    cache_disk disk[METHOD_MAX_LEVELS];
    method_fit_in in;
    samples_change change;
    float *own = NULL;
    json_t *pre;
    double t0 = glint_now(), t_gather = -1.0;
    int rc, read = -1;

    memset(out, 0, sizeof *out);
    if (!rgb && memo && tags) {
        if ((rc = gather_reusing(p, s, paintings, tags, memo, &rgb, &read, err)) < 0)
            return rc;
        if (rc == 0)
            t_gather = glint_now() - t0;
    }
    if (!rgb) {
        own = malloc((size_t)3 * s->n * sizeof *own);
        if (!own)
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d samples", s->n);
        if ((rc = samples_gather(s, paintings, own, err))) {
            free(own);
            return rc;
        }
        rgb = own;
        t_gather = glint_now() - t0;
    }
    fit_in_of(p, rgb, levels, keys, disk, &in);
    if (memo && tags) {
        in.memo = memo;
        in.view_tags = tags;
        if (read >= 0) { /* the values are the memo's */
            change.id = memo->values_id;
            change.epoch = memo->values_epoch;
            change.gen = memo->values_gen;
            in.values_change = &change;
        }
    }
    rc = p->m->fit(&in, out, err);
    free(own);
    if (rc)
        return rc;
    if (samples_torn(s)) {
        if (read >= 0) { /* what was read from a torn pattern is not kept */
            memset(memo->values_ok, 0, (size_t)s->nviews);
            memo->values_id = samples_change_id();
        }
        material_free(out);
        return prep_torn_error(err, "this fit");
    }
    /* the fit's own time includes reading the paintings (gather: the
     * samples' values read from them, when this call read them) */
    {
        json_t *sec = json_object_get(out->info, "seconds");
        if (json_is_object(sec)) {
            json_object_set_new(sec, "fit", json_real(glint_now() - t0));
            if (t_gather >= 0.0)
                json_object_set_new(sec, "gather", json_real(t_gather));
        }
    }
    pre = json_object_get(out->info, "precomputation");
    if (!json_is_object(pre)) {
        pre = json_object();
        json_object_set_new(out->info, "precomputation", pre);
    }
    json_object_set_new(pre, "cache", prep_report(p));
    if (read >= 0)
        json_object_set_new(pre, "values_views_read", json_integer(read));
    errors_in_painted_units(p, out);
    if (rep && (rc = report_of(p, out, rep, err)))
        material_free(out);
    return rc;
}

typedef struct count_ctx {
    long *per_view;
} count_ctx;

static int count_band(void *cls, int v, const gbuf *band, int row0, glint_err *err)
{
    count_ctx *c = cls;
    (void)row0;
    (void)err;
    c->per_view[v] += samples_count(band);
    return 0;
}

int prep_sample_counts(const scene *sc, long *per_view, long *total, glint_err *err)
{
    count_ctx c = {per_view};
    int rc;

    *total = 0;
    if ((rc = scene_validate(sc, err)))
        return rc;
    memset(per_view, 0, (size_t)sc->nviews * sizeof *per_view);
    for (int v = 0; v < sc->nviews; v++) {
        if ((rc = raster_bands(sc, v, count_band, &c, err)))
            return rc;
        *total += per_view[v];
    }
    if (*total < 1)
        return glint_err_set(err, GLINT_EINVAL,
                             "the chosen views have no lit, visible pixel: nothing to fit");
    return 0;
}
