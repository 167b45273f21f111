/* points.c: speed-accuracy points per scene (points.h). */
#include "points.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "clock.h"
#include "fsio.h"
#include "ids.h"
#include "log.h"

#define POINT_RECENT 16
#define POINTS_FILE_MAX ((size_t)16 << 20)

struct points {
    char *dir;
    pthread_mutex_t lock;
    json_t *all;       /* scene hash -> {key -> point} */
    json_t *dirty;     /* scene hashes not yet written */
    double saved_at;
};

int points_open(const char *dir, points **out, glint_err *err)
{
    points *p = calloc(1, sizeof *p);
    *out = NULL;
    if (!p || (dir && !(p->dir = strdup(dir))) || !(p->all = json_object()) ||
        !(p->dirty = json_object())) {
        if (p) {
            free(p->dir);
            json_decref(p->all);
        }
        free(p);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    pthread_mutex_init(&p->lock, NULL);
    *out = p;
    return 0;
}

/* The points of a scene (lock held), read from disk the first time; NULL
 * only when out of memory. */
static json_t *scene_points(points *p, const char *hash)
{
    json_t *pts = json_object_get(p->all, hash);
    char path[4096], *text = NULL;
    size_t len;

    if (pts)
        return pts;
    if (p->dir && snprintf(path, sizeof path, "%s/%s.json", p->dir, hash) < (int)sizeof path &&
        fsio_read_all(path, POINTS_FILE_MAX, &text, &len, NULL) == 0) {
        pts = json_loadb(text, len, 0, NULL);
        free(text);
        if (!json_is_object(pts)) { /* unreadable: start again (it is only a record) */
            json_decref(pts);
            pts = NULL;
        }
    }
    if (!pts)
        pts = json_object();
    if (!pts || json_object_set_new(p->all, hash, pts))
        return NULL;
    return pts;
}

static int write_scene(points *p, const char *hash, json_t *pts, glint_err *err)
{
    char path[4200], *text;
    int rc;
    if (!p->dir)
        return 0;
    if ((rc = fsio_mkdirs(p->dir, err)))
        return rc;
    snprintf(path, sizeof path, "%s/%s.json", p->dir, hash);
    text = json_dumps(pts, JSON_COMPACT | JSON_REAL_PRECISION(9));
    if (!text)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory saving fit points");
    rc = fsio_write_atomic(path, text, strlen(text), err);
    free(text);
    return rc;
}

/* lock held */
static void flush_locked(points *p, int force)
{
    const char *k;
    json_t *v;
    double now = glint_now();

    if (!force && now - p->saved_at < POINTS_SAVE_PERIOD_S)
        return;
    json_object_foreach(p->dirty, k, v) {
        json_t *pts = json_object_get(p->all, k);
        glint_err e;
        if (pts && write_scene(p, k, pts, &e))
            log_line("saving fit points: %s", e.msg);
    }
    json_object_clear(p->dirty);
    p->saved_at = now;
}

void points_flush(points *p, int force)
{
    pthread_mutex_lock(&p->lock);
    if (json_object_size(p->dirty))
        flush_locked(p, force);
    pthread_mutex_unlock(&p->lock);
}

void points_close(points *p)
{
    if (!p)
        return;
    flush_locked(p, 1);
    pthread_mutex_destroy(&p->lock);
    json_decref(p->all);
    json_decref(p->dirty);
    free(p->dir);
    free(p);
}

void points_key(const method *m, const void *params, const unsigned char *use, int nviews,
                char *buf, size_t len)
{
    int n = snprintf(buf, len, "method=%s;", m->name);
    for (int i = 0; i < m->nparams && n > 0 && (size_t)n < len; i++) {
        char v[256];
        method_param_format(&m->params[i], params, v, sizeof v);
        n += snprintf(buf + n, len - (size_t)n, "%s=%s;", m->params[i].name, v);
    }
    if (n > 0 && (size_t)n < len)
        n += snprintf(buf + n, len - (size_t)n, "views=");
    for (int v = 0; v < nviews && n > 0 && (size_t)n + 8 < len; v++)
        if (use[v])
            n += snprintf(buf + n, len - (size_t)n, "%d,", v);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int points_record(points *p, const char *hash, const char *key, const char *method_name,
                  const json_t *params, const json_t *views, int nsamples, double fit_seconds,
                  double cold, int from_disk, double rms_painted, const char *material_id,
                  glint_err *err)
{
    json_t *pts, *pt, *recent;
    double v[POINT_RECENT];
    char t[GLINT_TIME_LEN];
    size_t n;

    if (!glint_id_valid(hash))
        return glint_err_set(err, GLINT_EINVAL, "bad scene hash");
    pthread_mutex_lock(&p->lock);
    pts = scene_points(p, hash);
    pt = pts ? json_object_get(pts, key) : NULL;
    if (pts && !pt) {
        pt = json_pack("{s:s, s:O, s:O, s:i, s:n, s:n, s:n, s:n, s:[]}", "method", method_name,
                       "params", (json_t *)params, "views", (json_t *)views, "fits", 0,
                       "cold_seconds", "disk_seconds", "held_out_rms", "held_out", "_recent");
        if (pt && json_object_set_new(pts, key, pt))
            pt = NULL;
    }
    if (!pt) {
        pthread_mutex_unlock(&p->lock);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    json_object_set_new(pt, "samples", json_integer(nsamples));
    json_object_set_new(pt, "fits",
                        json_integer(json_integer_value(json_object_get(pt, "fits")) + 1));
    recent = json_object_get(pt, "_recent");
    if (!json_is_array(recent)) {
        recent = json_array();
        json_object_set_new(pt, "_recent", recent);
    }
    json_array_append_new(recent, json_real(fit_seconds));
    while (json_array_size(recent) > POINT_RECENT)
        json_array_remove(recent, 0);
    n = json_array_size(recent);
    for (size_t i = 0; i < n; i++)
        v[i] = json_number_value(json_array_get(recent, i));
    qsort(v, n, sizeof v[0], cmp_double);
    json_object_set_new(pt, "fit_seconds",
                        json_real(n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2])));
    if (cold >= 0.0)
        json_object_set_new(pt, from_disk ? "disk_seconds" : "cold_seconds", json_real(cold));
    json_object_set_new(pt, "rms_painted", json_real(rms_painted));
    if (material_id)
        json_object_set_new(pt, "material_id", json_string(material_id));
    glint_time_iso(time(NULL), t);
    json_object_set_new(pt, "updated", json_string(t));
    json_object_set_new(p->dirty, hash, json_true());
    flush_locked(p, 0);
    pthread_mutex_unlock(&p->lock);
    return 0;
}

int points_has_holdout(points *p, const char *hash, const char *key)
{
    json_t *pts, *pt;
    int has;
    if (!glint_id_valid(hash))
        return 0;
    pthread_mutex_lock(&p->lock);
    pts = scene_points(p, hash);
    pt = pts ? json_object_get(pts, key) : NULL;
    has = pt && json_is_object(json_object_get(pt, "held_out"));
    pthread_mutex_unlock(&p->lock);
    return has;
}

int points_set_holdout(points *p, const char *hash, const char *key, json_t *held_out,
                       glint_err *err)
{
    json_t *pts, *pt, *rms;
    if (!glint_id_valid(hash) || !json_is_object(held_out)) {
        json_decref(held_out);
        return glint_err_set(err, GLINT_EINVAL, "bad held-out record");
    }
    pthread_mutex_lock(&p->lock);
    pts = scene_points(p, hash);
    pt = pts ? json_object_get(pts, key) : NULL;
    if (!pt) {
        pthread_mutex_unlock(&p->lock);
        json_decref(held_out);
        return glint_err_set(err, GLINT_ENOTFOUND, "no such fit point");
    }
    rms = json_object_get(held_out, "rms");
    json_object_set_new(pt, "held_out_rms", json_is_number(rms) ? json_incref(rms) : json_null());
    json_object_set_new(pt, "held_out", held_out);
    json_object_set_new(p->dirty, hash, json_true());
    flush_locked(p, 0);
    pthread_mutex_unlock(&p->lock);
    return 0;
}

json_t *points_get(points *p, const char *hash)
{
    json_t *out = json_array(), *pts, *pt;
    const char *k;
    if (!glint_id_valid(hash))
        return out;
    pthread_mutex_lock(&p->lock);
    pts = scene_points(p, hash);
    if (pts) {
        json_object_foreach(pts, k, pt) {
            json_t *c = json_deep_copy(pt);
            json_object_del(c, "_recent");
            json_array_append_new(out, c);
        }
    }
    pthread_mutex_unlock(&p->lock);
    return out;
}
