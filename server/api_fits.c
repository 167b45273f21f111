/* api_fits.c: fits, jobs, materials and methods (proto/openapi.yaml, section
 * "fits, jobs, materials, methods").
 *
 *   POST /api/v1/sessions/{id}/fits        fit the session's paintings: 201 with the
 *                                           material when the precomputation is in
 *                                           memory, else 202 with a job
 *   GET  /api/v1/sessions/{id}/materials   the session's materials
 *   GET  /api/v1/jobs/{id}                 poll a job
 *   GET  /api/v1/jobs/{id}/events          the job's progress as server-sent events
 *   GET  /api/v1/materials/{id}            the material object
 *   GET  /api/v1/materials/{id}/factors.png|factors.exr
 *   GET  /api/v1/materials/{id}/shader     GLSL sources + binding manifest (JSON)
 *   GET  /api/v1/materials/{id}/shader/{file}
 *   GET  /api/v1/materials/{id}/package    tar of manifest, factors and shader
 *   GET  /api/v1/materials/{id}/preview.png|preview.exr
 *   POST /api/v1/materials/{id}/eval       BRDF values at direction pairs
 *   GET  /api/v1/methods[?scene_id=]       fit methods, parameters, measured points
 *
 * Numerics are core's (fit, material, glr); the cache and the jobs are
 * fitsvc's.  A fit reads the session's paintings when it is requested (a
 * snapshot: strokes arriving while a job runs are not in that fit); the
 * painted views form the sampling pattern.
 *
 * Material files are blobs "materials/<id>/": material.json, factors.png,
 * factors.exr (material_save), written atomically before the material's row
 * is committed.  The shader export (shader/, glr_shader_export) is a pure
 * function of material.json and is written on first use (GET shader,
 * shader files, package): it would cost a fit 3 ms of file writes. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "app.h"
#include "auth.h"
#include "events.h"
#include "fit.h"
#include "fitsvc.h"
#include "glr.h"
#include "img.h"
#include "material.h"
#include "raster.h"
#include "store.h"

#define EVAL_MAX_PAIRS 65536
#define PREVIEW_MAX GLR_MAX_SIZE
#define PREVIEW_DEFAULT 512
#define PREVIEW_CPU_MAX 1024
#define SSE_KEEPALIVE_S 15.0
#define GL_MESHES 8

static double mono_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void iso_now(char buf[32])
{
    time_t t = time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(buf, 32, "%Y-%m-%dT%H:%M:%SZ", &tm);
}

/* A glint error as a problem response: the client's mistakes are 4xx. */
static http_resp problem_of(int rc, const glint_err *e)
{
    const char *msg = e && e->msg[0] ? e->msg : glint_strerror(rc);
    switch (rc) {
    case GLINT_ENOTFOUND: return http_problem(404, "not-found", "%s", msg);
    case GLINT_EINVAL:
    case GLINT_ERANGE:
    case GLINT_ENONFINITE:
    case GLINT_ENUMERIC: return http_problem(422, "invalid-input", "%s", msg);
    case GLINT_EUNSUPPORTED: return http_problem(503, "unavailable", "%s", msg);
    case GLINT_ENOMEM: return http_problem(503, "out-of-memory", "%s", msg);
    default: return http_problem(500, "internal", "%s", msg);
    }
}

static int is_id(const char *s)
{
    if (!s || strlen(s) != 32)
        return 0;
    for (int i = 0; i < 32; i++)
        if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f')))
            return 0;
    return 1;
}

/* ---- access ---------------------------------------------------------------------- */

/* The session `sid` if the request may read it (need_paint 0) or write it
 * (1).  OUT: *doc (caller decrefs).  On refusal returns -1 with *deny. */
static int session_access(http_req *req, const char *sid, int need_paint, json_t **doc,
                          http_resp *deny)
{
    app *a = req->app;
    glint_err e;
    int rc;

    *doc = NULL;
    if (!is_id(sid)) {
        *deny = http_problem(404, "not-found", "no session %s", sid);
        return -1;
    }
    rc = store_session_get(a->store, sid, doc, &e);
    if (rc == GLINT_ENOTFOUND) {
        *deny = http_problem(404, "not-found", "no session %s", sid);
        return -1;
    }
    if (rc) {
        *deny = problem_of(rc, &e);
        return -1;
    }
    if (auth_session(req, *doc, need_paint, deny)) {
        json_decref(*doc);
        *doc = NULL;
        return -1;
    }
    return 0;
}

static json_t *material_links(const char *id, const char *sid, const char *scid);

/* The material `mid` if the request may read its session.  OUT: *doc, the
 * serialized material with its session and scene ids (free doc->text);
 * served from fitsvc's document cache when it is there (materials never
 * change), else read from the store and cached. */
static int material_access(http_req *req, const char *mid, fitsvc_doc *doc, http_resp *deny)
{
    app *a = req->app;
    glint_err e;
    json_t *sdoc = NULL, *j = NULL;
    int rc;

    memset(doc, 0, sizeof *doc);
    if (!is_id(mid)) {
        *deny = http_problem(404, "not-found", "no material %s", mid);
        return -1;
    }
    if (fitsvc_doc_get(a->fits, mid, doc) != 0) {
        const char *sid, *scid;
        rc = store_material_get(a->store, mid, &j, &e);
        if (rc) {
            *deny = rc == GLINT_ENOTFOUND ? http_problem(404, "not-found", "no material %s", mid)
                                          : problem_of(rc, &e);
            return -1;
        }
        sid = json_string_value(json_object_get(j, "session_id"));
        scid = json_string_value(json_object_get(j, "scene_id"));
        if (!sid || !scid) {
            json_decref(j);
            *deny = http_problem(500, "internal", "material %s names no session or scene", mid);
            return -1;
        }
        if (!json_object_get(j, "links"))
            json_object_set_new(j, "links", material_links(mid, sid, scid));
        snprintf(doc->session, sizeof doc->session, "%s", sid);
        snprintf(doc->scene, sizeof doc->scene, "%s", scid);
        doc->text = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(17));
        json_decref(j);
        if (!doc->text) {
            *deny = http_problem(503, "out-of-memory", "out of memory");
            return -1;
        }
        doc->len = strlen(doc->text);
        fitsvc_doc_put(a->fits, mid, doc->session, doc->scene, doc->text, doc->len);
    }
    if (session_access(req, doc->session, 0, &sdoc, deny)) {
        free(doc->text);
        doc->text = NULL;
        return -1;
    }
    json_decref(sdoc);
    return 0;
}

/* ---- scenes through the cache ------------------------------------------------------ */

/* Scenes come from the store (which builds built-in meshes and loads
 * uploaded ones); fitsvc keeps the ones in use with their content hash. */
static int src_scene_load(void *cls, const char *scene_id, const scene **out, glint_err *err)
{
    app *a = cls;
    return store_scene_acquire(a->store, scene_id, out, err);
}

static void src_scene_unload(void *cls, const scene *sc)
{
    app *a = cls;
    store_scene_release(a->store, sc);
}

static int scene_get(app *a, const char *scene_id, fitsvc_scene **out, glint_err *err)
{
    fitsvc_scene_source src = {src_scene_load, src_scene_unload, a};
    *out = NULL;
    if (!is_id(scene_id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no scene %s", scene_id ? scene_id : "");
    return fitsvc_scene_acquire(a->fits, scene_id, &src, out, err);
}

/* ---- fit parameters ------------------------------------------------------------------ */

static const char *const param_names[] = {"res", "lambda", "regularization", "mapping", "model",
                                          "precision", "route", "rcond"};

/* Validate the body of POST /fits into *p.  On error: -1 and msg. */
static int parse_fit_body(const json_t *body, fit_params *p, char *msg, size_t len)
{
    const char *k;
    json_t *v, *params;
    glint_err e;

    fit_params_default(p);
    json_object_foreach((json_t *)body, k, v) {
        if (strcmp(k, "method") != 0 && strcmp(k, "params") != 0) {
            snprintf(msg, len, "unknown member '%s' (a fit takes \"method\" and \"params\")", k);
            return -1;
        }
    }
    v = json_object_get(body, "method");
    if (v && !json_is_string(v)) {
        snprintf(msg, len, "method must be a string (\"hf3\")");
        return -1;
    }
    if (v && strcmp(json_string_value(v), "hf3") != 0) {
        snprintf(msg, len, "method '%.64s' is not available (available: hf3)",
                 json_string_value(v));
        return -1;
    }
    params = json_object_get(body, "params");
    if (!params)
        return 0;
    if (!json_is_object(params)) {
        snprintf(msg, len, "params must be an object");
        return -1;
    }
    json_object_foreach(params, k, v) {
        size_t i;
        for (i = 0; i < sizeof param_names / sizeof param_names[0]; i++)
            if (strcmp(k, param_names[i]) == 0)
                break;
        if (i == sizeof param_names / sizeof param_names[0]) {
            snprintf(msg, len,
                     "unknown parameter params.%.64s (hf3 takes res, lambda, regularization, "
                     "mapping, model, precision, route, rcond)", k);
            return -1;
        }
    }
    if ((v = json_object_get(params, "res"))) {
        if (!json_is_integer(v) || json_integer_value(v) < HF_RES_MIN ||
            json_integer_value(v) > HF_RES_MAX) {
            snprintf(msg, len, "params.res must be an integer in %d..%d", HF_RES_MIN,
                     HF_RES_MAX);
            return -1;
        }
        p->res = (int)json_integer_value(v);
    }
    if ((v = json_object_get(params, "lambda"))) {
        double x = json_number_value(v);
        if (!json_is_number(v) || !isfinite(x) || x < 0.0 || x > HF_LAMBDA_MAX) {
            snprintf(msg, len, "params.lambda must be a number in [0, %g]", HF_LAMBDA_MAX);
            return -1;
        }
        p->lambda = x;
    }
    if ((v = json_object_get(params, "rcond"))) {
        double x = json_number_value(v);
        if (!json_is_number(v) || !isfinite(x) || x <= 0.0 || x >= 1.0) {
            snprintf(msg, len, "params.rcond must be a number in (0, 1)");
            return -1;
        }
        p->rcond = x;
    }
    if ((v = json_object_get(params, "regularization"))) {
        if (!json_is_string(v)) {
            snprintf(msg, len, "params.regularization must be a string such as \"trunc:full\", "
                               "\"trunc:50%%\", \"tikhonov:rel1e-2\" or \"linear:40\"");
            return -1;
        }
        if (hf_reg_parse(json_string_value(v), &p->reg, &e)) {
            snprintf(msg, len, "params.regularization: %.400s", e.msg);
            return -1;
        }
    }
    if ((v = json_object_get(params, "mapping"))) {
        if (!json_is_string(v)) {
            snprintf(msg, len, "params.mapping must be a string such as \"log\", \"add:0.1\" or "
                               "\"sub:0.01\"");
            return -1;
        }
        if (hf_map_parse(json_string_value(v), &p->map, &e)) {
            snprintf(msg, len, "params.mapping: %.400s", e.msg);
            return -1;
        }
    }
    if ((v = json_object_get(params, "model"))) {
        const char *s = json_string_value(v);
        if (!s || (strcmp(s, "radiance") && strcmp(s, "brdf"))) {
            snprintf(msg, len, "params.model must be \"radiance\" or \"brdf\"");
            return -1;
        }
        p->model = strcmp(s, "brdf") == 0 ? HF_MODEL_BRDF : HF_MODEL_RADIANCE;
    }
    if ((v = json_object_get(params, "precision"))) {
        const char *s = json_string_value(v);
        if (!s || (strcmp(s, "double") && strcmp(s, "single"))) {
            snprintf(msg, len, "params.precision must be \"double\" or \"single\"");
            return -1;
        }
        p->prec = strcmp(s, "single") == 0 ? HF_F32 : HF_F64;
    }
    if ((v = json_object_get(params, "route"))) {
        const char *s = json_string_value(v);
        if (!s || (strcmp(s, "eig") && strcmp(s, "svd"))) {
            snprintf(msg, len, "params.route must be \"eig\" or \"svd\"");
            return -1;
        }
        p->route = strcmp(s, "svd") == 0 ? HF_ROUTE_SVD : HF_ROUTE_EIG;
    }
    return 0;
}

/* The configuration key of a speed-accuracy point: parameters + views. */
static void point_key(const fit_params *p, const unsigned char *use, int nviews, char *buf,
                      size_t len)
{
    char reg[64], map[96];
    int n;
    hf_reg_format(&p->reg, reg, sizeof reg);
    hf_map_format(&p->map, map, sizeof map);
    n = snprintf(buf, len, "res=%d;lambda=%.17g;reg=%s;map=%s;model=%s;prec=%s;route=%s;"
                 "rcond=%.17g;views=", p->res, p->lambda, reg, map,
                 p->model == HF_MODEL_BRDF ? "brdf" : "radiance",
                 p->prec == HF_F32 ? "single" : "double",
                 p->route == HF_ROUTE_SVD ? "svd" : "eig",
                 p->rcond > 0.0 ? p->rcond : hf_rcond_default(p->route));
    for (int v = 0; v < nviews && n > 0 && (size_t)n + 8 < len; v++)
        if (use[v])
            n += snprintf(buf + n, len - (size_t)n, "%d,", v);
}

static json_t *views_json(const unsigned char *use, int nviews)
{
    json_t *a = json_array();
    for (int v = 0; v < nviews; v++)
        if (use[v])
            json_array_append_new(a, json_integer(v));
    return a;
}

/* ---- fit tasks -------------------------------------------------------------------------- */

/* Everything a fit needs, owned by the request or by its job. */
typedef struct fit_task {
    app *a;
    char session_id[33], scene_id[33];
    fitsvc_scene *scene;     /* pinned */
    int nviews, nused;
    img *paintings;          /* nviews; views never painted are zeroed */
    fitsvc_painting **pins;  /* nviews: paintings shared with the cache (not ours to free) */
    unsigned char *use;      /* nviews: painted */
    long long *versions;     /* nviews: painting versions used */
    fit_params params;
} fit_task;

static void fit_task_free(void *p)
{
    fit_task *t = p;
    if (!t)
        return;
    if (t->paintings)
        for (int v = 0; v < t->nviews; v++) {
            if (t->pins && t->pins[v])
                fitsvc_painting_release(t->a->fits, t->pins[v]);
            else
                img_free(&t->paintings[v]);
        }
    free(t->paintings);
    free(t->pins);
    free(t->use);
    free(t->versions);
    fitsvc_scene_release(t->a->fits, t->scene);
    free(t);
}

/* Read the session's paintings (a snapshot).  OUT: t->paintings, use,
 * versions; GLINT_EINVAL when nothing is painted. */
static int task_read_paintings(fit_task *t, glint_err *err)
{
    const scene *sc = fitsvc_scene_get(t->scene);
    int nused = 0, rc;

    t->nviews = sc->nviews;
    t->paintings = calloc((size_t)sc->nviews, sizeof *t->paintings);
    t->use = calloc((size_t)sc->nviews, 1);
    t->versions = calloc((size_t)sc->nviews, sizeof *t->versions);
    t->pins = calloc((size_t)sc->nviews, sizeof *t->pins);
    if (!t->paintings || !t->use || !t->versions || !t->pins)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int v = 0; v < sc->nviews; v++) {
        void *data = NULL;
        size_t len = 0;
        int64_t version = 0;
        glint_err e;
        rc = store_painting_get(t->a->store, t->session_id, v, &data, &len, &version, &e);
        if (rc == GLINT_ENOTFOUND)
            continue; /* never painted: not in the pattern */
        if (rc) {
            *err = e;
            return rc;
        }
        if (fitsvc_painting_get(t->a->fits, t->session_id, v, version, &t->pins[v]) != 0) {
            img im;
            rc = img_read_mem(data, len, &im, err);
            if (rc) {
                free(data);
                return glint_err_prefix(err, "painting of view %d", v);
            }
            if (fitsvc_painting_put(t->a->fits, t->session_id, v, version, &im, &t->pins[v]))
                t->paintings[v] = im; /* not cached: the task's own */
        }
        free(data);
        if (t->pins[v]) /* shared read-only with the cache */
            t->paintings[v] = *fitsvc_painting_img(t->pins[v]);
        t->nused = nused + 1; /* (this one is painted, if not usable) */
        if (t->paintings[v].width != sc->width || t->paintings[v].height != sc->height)
            return glint_err_set(err, GLINT_EINVAL,
                                 "painting of view %d is %dx%d, the scene's raster is %dx%d", v,
                                 t->paintings[v].width, t->paintings[v].height, sc->width,
                                 sc->height);
        t->use[v] = 1;
        t->versions[v] = version;
        t->nused = ++nused;
    }
    if (!nused)
        return glint_err_set(err, GLINT_EINVAL,
                             "session %s has no painting yet: paint or upload at least one view "
                             "before fitting", t->session_id);
    return 0;
}

static json_t *material_links(const char *id, const char *sid, const char *scid)
{
    char b[10][160];
    snprintf(b[0], sizeof b[0], "/api/v1/materials/%s", id);
    snprintf(b[1], sizeof b[1], "/api/v1/materials/%s/factors.png", id);
    snprintf(b[2], sizeof b[2], "/api/v1/materials/%s/factors.exr", id);
    snprintf(b[3], sizeof b[3], "/api/v1/materials/%s/shader", id);
    snprintf(b[4], sizeof b[4], "/api/v1/materials/%s/package", id);
    snprintf(b[5], sizeof b[5], "/api/v1/materials/%s/preview.png", id);
    snprintf(b[6], sizeof b[6], "/api/v1/materials/%s/eval", id);
    snprintf(b[7], sizeof b[7], "/api/v1/sessions/%s", sid);
    snprintf(b[8], sizeof b[8], "/api/v1/scenes/%s", scid);
    snprintf(b[9], sizeof b[9], "/api/v1/materials/%s/preview.exr", id);
    return json_pack("{s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:s}", "self", b[0],
                     "factors_png", b[1], "factors_exr", b[2], "shader", b[3], "package", b[4],
                     "preview_png", b[5], "preview_exr", b[9], "eval", b[6], "session", b[7],
                     "scene", b[8]);
}

static void holdout_schedule(fit_task *t, const char *material_id, const char *pkey);

/* Fit the task's paintings with a prepared fit and store the material.
 * OUT: *doc, the API's material object (caller decrefs). */
static int fit_execute(fit_task *t, fitsvc_prep *prep, fitsvc_job *job, json_t **doc,
                       glint_err *err)
{
    app *a = t->a;
    const fit_prep *fp = fitsvc_prep_fit(prep);
    material m;
    char mid[33], name[128], dir[4096], created[32], pkey[1024];
    json_t *d = NULL, *paintings, *report, *pre;
    double t0 = mono_now(), fit_s;
    int rc, nused = 0;

    *doc = NULL;
    memset(&m, 0, sizeof m);
    if (job)
        fitsvc_job_progress(job, "fit", 0.9);
    rc = fit_run(fp, t->paintings, NULL, &m, err);
    if (rc)
        return rc;
    fit_s = mono_now() - t0;
    report = fitsvc_prep_report(prep);
    pre = json_object_get(m.info, "precomputation");
    if (json_is_object(pre))
        json_object_set(pre, "cache", report);
    if ((rc = store_new_id(mid, err)))
        goto done;
    snprintf(name, sizeof name, "materials/%s", mid);
    if ((rc = store_blob_path(a->store, name, dir, sizeof dir, err)))
        goto done;
    if ((rc = material_save(&m, dir, err)))
        goto done;

    paintings = json_array();
    for (int v = 0; v < t->nviews; v++)
        if (t->use[v]) {
            json_array_append_new(paintings, json_pack("{s:i, s:I}", "view", v, "version",
                                                       (json_int_t)t->versions[v]));
            nused++;
        }
    iso_now(created);
    d = json_pack("{s:s, s:s, s:s, s:s, s:s, s:i, s:O, s:o, s:o, s:O, s:O, s:O}", "id", mid,
                  "session_id", t->session_id, "scene_id", t->scene_id, "created", created,
                  "method", m.method[0] ? m.method : "hf3", "res", m.fac.res, "params",
                  json_object_get(m.info, "params"), "views_used", views_json(t->use, t->nviews),
                  "paintings", paintings, "errors", json_object_get(m.info, "errors"), "seconds",
                  json_object_get(m.info, "seconds"), "precomputation", pre);
    if (!d) {
        rc = glint_err_set(err, GLINT_ENOMEM, "cannot build the material object");
        goto done;
    }
    json_object_set_new(d, "links", material_links(mid, t->session_id, t->scene_id));
    if ((rc = store_material_put(a->store, mid, t->session_id, d, err)))
        goto done;
    {
        char *text = json_dumps(d, JSON_COMPACT | JSON_REAL_PRECISION(17));
        if (text)
            fitsvc_doc_put(a->fits, mid, t->session_id, t->scene_id, text, strlen(text));
        free(text);
    }

    /* the studio hears of it; the scene's speed-accuracy record grows */
    {
        json_t *errs = json_object_get(m.info, "errors");
        double rms = json_number_value(json_object_get(errs, "rms_painted"));
        const char *memory = json_string_value(json_object_get(report, "memory"));
        const char *disk = json_string_value(json_object_get(report, "disk"));
        double cold = memory && strcmp(memory, "built") == 0 ? fitsvc_prep_cold_seconds(prep)
                                                              : -1.0;
        glint_err pe;
        events_publish(a->events, t->session_id, "fit",
                       json_pack("{s:s, s:s, s:{s:s, s:i, s:f, s:f, s:i, s:s}}", "material_id",
                                 mid, "href", json_string_value(json_object_get(
                                                  json_object_get(d, "links"), "self")),
                                 "summary", "method", "hf3", "res", m.fac.res, "rms_painted", rms,
                                 "fit_seconds", fit_s, "views", nused, "cache",
                                 memory ? memory : "?"));
        point_key(&t->params, t->use, t->nviews, pkey, sizeof pkey);
        if (fitsvc_points_record(a->fits, fitsvc_scene_hash(t->scene), pkey,
                                 json_object_get(m.info, "params"), json_object_get(d, "views_used"),
                                 fp->s.n, fit_s, cold, disk && strcmp(disk, "loaded") == 0, rms,
                                 mid, &pe))
            fprintf(stderr, "glintd: recording a fit point: %s\n", pe.msg);
        /* held-out error: eig route only (the svd route's dense matrices make
         * one decomposition per painted view too costly in the background) */
        if (nused >= 2 && t->params.route == HF_ROUTE_EIG &&
            !fitsvc_points_has_holdout(a->fits, fitsvc_scene_hash(t->scene), pkey))
            holdout_schedule(t, mid, pkey);
    }
    *doc = d;
    d = NULL;
done:
    json_decref(report);
    json_decref(d);
    material_free(&m);
    return rc;
}

static void job_progress_cb(void *cls, const char *stage, double p)
{
    fitsvc_job_progress(cls, stage, p);
}

/* The job of a fit whose precomputation was not in memory. */
static int fit_job(fitsvc_job *job, void *arg, json_t **result, glint_err *err)
{
    fit_task *t = arg;
    fitsvc_request rq;
    fitsvc_prep *prep = NULL;
    json_t *doc = NULL;
    int rc;

    rq.scene = t->scene;
    rq.use = t->use;
    rq.params = t->params;
    rc = fitsvc_prep_acquire(t->a->fits, &rq, job_progress_cb, job, &prep, err);
    if (rc)
        return rc;
    rc = fit_execute(t, prep, job, &doc, err);
    fitsvc_prep_release(t->a->fits, prep);
    if (rc)
        return rc;
    *result = json_pack("{s:O}", "material_id", json_object_get(doc, "id"));
    json_decref(doc);
    return 0;
}

/* ---- held-out error: leave one painted view out --------------------------------------- */

typedef struct holdout_task {
    app *a;
    fitsvc_scene *scene;
    int nviews;
    img *paintings;
    unsigned char *use;
    fit_params params;
    char material_id[33];
    char pkey[1024];
} holdout_task;

static void holdout_free(void *p)
{
    holdout_task *h = p;
    if (!h)
        return;
    if (h->paintings)
        for (int v = 0; v < h->nviews; v++)
            img_free(&h->paintings[v]);
    free(h->paintings);
    free(h->use);
    fitsvc_scene_release(h->a->fits, h->scene);
    free(h);
}

/* For each painted view k: fit the other painted views (a precomputation of
 * its own, not cached) and measure the error on view k's painted samples.
 * The pooled RMS over all held-out pixels is the point's held-out error. */
static int holdout_job(fitsvc_job *job, void *arg, json_t **result, glint_err *err)
{
    holdout_task *h = arg;
    const scene *sc = fitsvc_scene_get(h->scene);
    gbuf *g = calloc((size_t)h->nviews, sizeof *g);
    unsigned char *use2 = malloc((size_t)h->nviews);
    json_t *per = json_array();
    double ss = 0.0, mx = 0.0, t0 = mono_now();
    long total = 0;
    int rc = 0, nused = 0, done = 0;

    if (!g || !use2 || !per) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto out;
    }
    for (int v = 0; v < h->nviews; v++) {
        g[v].width = sc->width;
        g[v].height = sc->height;
        if (!h->use[v])
            continue;
        nused++;
        if ((rc = raster_view(&sc->mesh, &sc->views[v], sc->width, sc->height, &g[v], err)))
            goto out;
    }
    for (int k = 0; k < h->nviews; k++) {
        fit_prep fp;
        material m;
        double rms = 0.0, mabs = 0.0;
        long cnt = 0;
        if (!h->use[k])
            continue;
        if (fitsvc_job_cancelled(job)) {
            rc = glint_err_set(err, GLINT_EUNSUPPORTED, "the daemon is stopping");
            goto out;
        }
        memcpy(use2, h->use, (size_t)h->nviews);
        use2[k] = 0;
        fitsvc_job_progress(job, "holdout", (double)done / nused);
        rc = fit_prepare(&fp, sc, g, use2, &h->params, NULL, err);
        if (rc == 0) {
            rc = fit_run(&fp, h->paintings, NULL, &m, err);
            fit_prep_free(&fp);
        }
        if (rc == 0) {
            rc = fit_error_views(&m, &g[k], &sc->views[k], 1, &h->paintings[k], &rms, &mabs,
                                 &cnt, err);
            material_free(&m);
        }
        if (rc) {
            glint_err_prefix(err, "holding out view %d", k);
            goto out;
        }
        json_array_append_new(per, json_pack("{s:i, s:f, s:I}", "view", k, "rms", rms, "pixels",
                                             (json_int_t)cnt));
        ss += rms * rms * 3.0 * (double)cnt;
        total += cnt;
        if (mabs > mx)
            mx = mabs;
        done++;
    }
    rc = fitsvc_points_set_holdout(
        h->a->fits, fitsvc_scene_hash(h->scene), h->pkey,
        json_pack("{s:s, s:f, s:f, s:I, s:i, s:o, s:s, s:f}", "method", "leave-one-view-out",
                  "rms", total ? sqrt(ss / (3.0 * (double)total)) : 0.0, "max_abs", mx, "pixels",
                  (json_int_t)total, "views", nused, "per_view", per, "material_id",
                  h->material_id, "seconds", mono_now() - t0),
        err);
    per = NULL;
out:
    json_decref(per);
    if (g)
        raster_free_all(g, h->nviews);
    free(use2);
    (void)result;
    return rc;
}

static void holdout_schedule(fit_task *t, const char *material_id, const char *pkey)
{
    holdout_task *h = calloc(1, sizeof *h);
    glint_err e;
    char id[33];

    if (!h)
        return;
    h->a = t->a;
    h->nviews = t->nviews;
    h->params = t->params;
    snprintf(h->material_id, sizeof h->material_id, "%s", material_id);
    snprintf(h->pkey, sizeof h->pkey, "%s", pkey);
    h->paintings = calloc((size_t)t->nviews, sizeof *h->paintings);
    h->use = malloc((size_t)t->nviews);
    if (!h->paintings || !h->use) {
        holdout_free(h);
        return;
    }
    memcpy(h->use, t->use, (size_t)t->nviews);
    for (int v = 0; v < t->nviews; v++) {
        const img *s = &t->paintings[v];
        if (!t->use[v])
            continue;
        if (img_alloc(&h->paintings[v], s->width, s->height, s->channels, &e)) {
            holdout_free(h);
            return;
        }
        memcpy(h->paintings[v].px, s->px, (size_t)s->width * s->height * s->channels *
                                              sizeof(float));
    }
    h->scene = fitsvc_scene_ref(t->a->fits, t->scene);
    if (fitsvc_job_submit(t->a->fits, "holdout", "", holdout_job, h, holdout_free, id, &e))
        fprintf(stderr, "glintd: held-out evaluation not scheduled: %s\n", e.msg);
}

/* ---- POST /sessions/{id}/fits ------------------------------------------------------------ */

static json_t *job_with_links(json_t *job)
{
    char b[3][160];
    const char *id = json_string_value(json_object_get(job, "id"));
    const char *mid = json_string_value(json_object_get(job, "material_id"));
    json_t *links;
    snprintf(b[0], sizeof b[0], "/api/v1/jobs/%s", id ? id : "");
    snprintf(b[1], sizeof b[1], "/api/v1/jobs/%s/events", id ? id : "");
    links = json_pack("{s:s, s:s}", "self", b[0], "events", b[1]);
    if (mid) {
        snprintf(b[2], sizeof b[2], "/api/v1/materials/%s", mid);
        json_object_set_new(links, "material", json_string(b[2]));
    }
    json_object_set_new(job, "links", links);
    return job;
}

static http_resp fits_create(http_req *req)
{
    app *a = req->app;
    const char *sid = req->param[0];
    json_t *sdoc = NULL, *body = NULL, *doc = NULL;
    http_resp resp;
    fit_task *t = NULL;
    fitsvc_prep *prep = NULL;
    fitsvc_request rq;
    glint_err e;
    char msg[512], loc[128];
    const char *scid;
    int rc;

    if (session_access(req, sid, 1, &sdoc, &resp))
        return resp;
    body = http_body_json(req, &resp);
    if (!body)
        goto out;
    t = calloc(1, sizeof *t);
    if (!t) {
        resp = http_problem(503, "out-of-memory", "out of memory");
        goto out;
    }
    t->a = a;
    if (parse_fit_body(body, &t->params, msg, sizeof msg)) {
        resp = http_problem(422, "invalid-parameter", "%s", msg);
        goto out;
    }
    snprintf(t->session_id, sizeof t->session_id, "%s", sid);
    scid = json_string_value(json_object_get(sdoc, "scene_id"));
    if (!scid) {
        resp = http_problem(500, "internal", "session %s names no scene", sid);
        goto out;
    }
    snprintf(t->scene_id, sizeof t->scene_id, "%s", scid);
    rc = scene_get(a, scid, &t->scene, &e);
    if (rc) {
        resp = rc == GLINT_ENOTFOUND
                   ? http_problem(409, "scene-gone", "the session's scene %s no longer exists",
                                  scid)
                   : problem_of(rc, &e);
        goto out;
    }
    if ((rc = task_read_paintings(t, &e))) {
        resp = rc != GLINT_EINVAL ? problem_of(rc, &e)
               : t->nused ? http_problem(422, "invalid-painting", "%s", e.msg)
                          : http_problem(422, "no-paintings", "%s", e.msg);
        goto out;
    }
    rq.scene = t->scene;
    rq.use = t->use;
    rq.params = t->params;
    if (fitsvc_prep_try(a->fits, &rq, &prep, &e) == 0) {
        /* cached: fit now */
        rc = fit_execute(t, prep, NULL, &doc, &e);
        fitsvc_prep_release(a->fits, prep);
        if (rc) {
            resp = problem_of(rc, &e);
            goto out;
        }
        snprintf(loc, sizeof loc, "/api/v1/materials/%s",
                 json_string_value(json_object_get(doc, "id")));
        resp = http_json(201, doc);
        http_header(&resp, "Location", loc);
        goto out;
    } else {
        char id[33];
        json_t *job;
        rc = fitsvc_job_submit(a->fits, "fit", sid, fit_job, t, fit_task_free, id, &e);
        t = NULL; /* the job owns it (freed even on failure) */
        if (rc) {
            resp = problem_of(rc, &e);
            if (rc == GLINT_EUNSUPPORTED)
                http_header(&resp, "Retry-After", "2");
            goto out;
        }
        if ((rc = fitsvc_job_get(a->fits, id, &job, NULL, &e))) {
            resp = problem_of(rc, &e);
            goto out;
        }
        snprintf(loc, sizeof loc, "/api/v1/jobs/%s", id);
        resp = http_json(202, json_pack("{s:o}", "job", job_with_links(job)));
        http_header(&resp, "Location", loc);
    }
out:
    fit_task_free(t);
    json_decref(body);
    json_decref(sdoc);
    return resp;
}

static http_resp session_materials(http_req *req)
{
    app *a = req->app;
    json_t *sdoc, *list = NULL;
    http_resp resp;
    glint_err e;
    int rc;

    if (session_access(req, req->param[0], 0, &sdoc, &resp))
        return resp;
    json_decref(sdoc);
    rc = store_material_list(a->store, req->param[0], &list, &e);
    if (rc)
        return problem_of(rc, &e);
    return http_json(200, json_pack("{s:o}", "materials", list));
}

/* ---- jobs ------------------------------------------------------------------------------- */

/* The job `id` if the request may read its session.  OUT: *job. */
static int job_access(http_req *req, const char *id, json_t **job, http_resp *deny)
{
    app *a = req->app;
    char owner[33];
    glint_err e;
    json_t *sdoc;

    *job = NULL;
    if (!is_id(id) || fitsvc_job_get(a->fits, id, job, owner, &e)) {
        *deny = http_problem(404, "not-found", "no job %s (unknown, or finished over an hour ago)",
                             id);
        return -1;
    }
    if (!owner[0] || session_access(req, owner, 0, &sdoc, deny)) {
        if (!owner[0]) /* internal jobs are not visible */
            *deny = http_problem(404, "not-found", "no job %s", id);
        json_decref(*job);
        *job = NULL;
        return -1;
    }
    json_decref(sdoc);
    return 0;
}

static http_resp job_get(http_req *req)
{
    json_t *job;
    http_resp resp;
    if (job_access(req, req->param[0], &job, &resp))
        return resp;
    return http_json(200, json_pack("{s:o}", "job", job_with_links(job)));
}

/* SSE stream of a job: "progress" events, then one "done" or "failed". */
typedef struct job_stream {
    fitsvc *f;
    char id[33];
    long long since;
    char *buf;
    size_t len, off;
    int final_queued;
} job_stream;

static void job_stream_free(void *cls)
{
    job_stream *s = cls;
    if (s) {
        free(s->buf);
        free(s);
    }
}

static ssize_t job_stream_read(void *cls, uint64_t pos, char *out, size_t max)
{
    job_stream *s = cls;
    (void)pos;
    while (s->off >= s->len) {
        json_t *evs = NULL, *ev;
        int final = 0;
        size_t i;
        char *mem = NULL;
        size_t mlen = 0;
        FILE *f;

        if (s->final_queued)
            return MHD_CONTENT_READER_END_OF_STREAM;
        if (fitsvc_job_events(s->f, s->id, s->since, SSE_KEEPALIVE_S, &evs, &final, NULL))
            return MHD_CONTENT_READER_END_OF_STREAM; /* expired */
        f = open_memstream(&mem, &mlen);
        if (!f) {
            json_decref(evs);
            return MHD_CONTENT_READER_END_WITH_ERROR;
        }
        if (json_array_size(evs) == 0)
            fputs(": keep-alive\n\n", f);
        json_array_foreach(evs, i, ev) {
            json_t *job = json_deep_copy(json_object_get(ev, "job"));
            const char *type = json_string_value(json_object_get(ev, "type"));
            char *text = json_dumps(job_with_links(job), JSON_COMPACT);
            s->since = json_integer_value(json_object_get(ev, "seq"));
            fprintf(f, "id: %lld\nevent: %s\ndata: %s\n\n", s->since, type ? type : "progress",
                    text ? text : "{}");
            free(text);
            json_decref(job);
            if (type && (strcmp(type, "done") == 0 || strcmp(type, "failed") == 0))
                s->final_queued = 1;
        }
        if (final && !s->final_queued && json_array_size(evs) == 0)
            s->final_queued = 1; /* (cannot happen: the last event is terminal) */
        json_decref(evs);
        fclose(f);
        free(s->buf);
        s->buf = mem;
        s->len = mlen;
        s->off = 0;
    }
    {
        size_t n = s->len - s->off;
        if (n > max)
            n = max;
        memcpy(out, s->buf + s->off, n);
        s->off += n;
        return (ssize_t)n;
    }
}

static http_resp job_events(http_req *req)
{
    app *a = req->app;
    json_t *job;
    http_resp resp;
    job_stream *s;
    const char *last = http_header_in(req, "Last-Event-ID");
    const char *since = http_query(req, "since");

    if (job_access(req, req->param[0], &job, &resp))
        return resp;
    json_decref(job);
    s = calloc(1, sizeof *s);
    if (!s)
        return http_problem(503, "out-of-memory", "out of memory");
    s->f = a->fits;
    snprintf(s->id, sizeof s->id, "%s", req->param[0]);
    if (last || since) {
        char *end;
        long long v = strtoll(last ? last : since, &end, 10);
        if (*end || v < 0) {
            free(s);
            return http_problem(400, "bad-request", "%s must be a non-negative integer",
                                last ? "Last-Event-ID" : "since");
        }
        s->since = v;
    }
    resp = http_stream(200, "text/event-stream", job_stream_read, s, job_stream_free);
    return resp;
}

/* ---- materials ---------------------------------------------------------------------------- */

static http_resp material_get(http_req *req)
{
    fitsvc_doc doc;
    http_resp resp;
    if (material_access(req, req->param[0], &doc, &resp))
        return resp;
    return http_bytes_owned(200, "application/json", doc.text, doc.len);
}

static http_resp blob_resp(app *a, const char *mid, const char *file, const char *ctype)
{
    char name[256];
    void *data = NULL;
    size_t len = 0;
    glint_err e;
    int rc;
    snprintf(name, sizeof name, "materials/%s/%s", mid, file);
    rc = store_blob_get(a->store, name, &data, &len, &e);
    if (rc)
        return rc == GLINT_ENOTFOUND
                   ? http_problem(404, "not-found", "material %s has no file %s", mid, file)
                   : problem_of(rc, &e);
    return http_bytes_owned(200, ctype, data, len);
}

static http_resp material_file(http_req *req, const char *file, const char *ctype)
{
    fitsvc_doc doc;
    http_resp resp;
    if (material_access(req, req->param[0], &doc, &resp))
        return resp;
    free(doc.text);
    return blob_resp(req->app, req->param[0], file, ctype);
}

static http_resp factors_png(http_req *req)
{
    return material_file(req, "factors.png", "image/png");
}

static http_resp factors_exr(http_req *req)
{
    return material_file(req, "factors.exr", "image/x-exr");
}

/* Files of the shader export, in package order. */
static const struct {
    const char *name, *ctype;
} shader_files[] = {
    {"shader.json", "application/json"},
    {"glint_material.vert", "text/plain; charset=utf-8"},
    {"glint_material.frag", "text/plain; charset=utf-8"},
    {"glint_factors.exr", "image/x-exr"},
    {"glint_factors_rgba16f.bin", "application/octet-stream"},
};
#define N_SHADER_FILES (sizeof shader_files / sizeof shader_files[0])

static int blob_text(app *a, const char *mid, const char *file, char **text, glint_err *err)
{
    char name[256];
    void *data = NULL;
    size_t len = 0;
    int rc;
    snprintf(name, sizeof name, "materials/%s/%s", mid, file);
    *text = NULL;
    if ((rc = store_blob_get(a->store, name, &data, &len, err)))
        return rc;
    *text = malloc(len + 1);
    if (!*text) {
        free(data);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    memcpy(*text, data, len);
    (*text)[len] = '\0';
    free(data);
    return 0;
}

/* Write the material's shader export if it is not there yet (shader.json
 * is written last, so its presence means the export is complete). */
static pthread_mutex_t export_lock = PTHREAD_MUTEX_INITIALIZER;

static int shader_ensure(app *a, const char *mid, glint_err *err)
{
    char name[128], dir[4096], path[4200];
    material m;
    FILE *f;
    int rc;

    snprintf(name, sizeof name, "materials/%s", mid);
    if ((rc = store_blob_path(a->store, name, dir, sizeof dir, err)))
        return rc;
    snprintf(path, sizeof path, "%s/shader/shader.json", dir);
    pthread_mutex_lock(&export_lock);
    if ((f = fopen(path, "rb"))) {
        fclose(f);
        pthread_mutex_unlock(&export_lock);
        return 0;
    }
    rc = material_load(dir, &m, err);
    if (rc == 0) {
        snprintf(path, sizeof path, "%s/shader", dir);
        rc = glr_shader_export(&m, path, err);
        material_free(&m);
    }
    pthread_mutex_unlock(&export_lock);
    return rc;
}

static http_resp shader_get(http_req *req)
{
    app *a = req->app;
    const char *mid = req->param[0];
    fitsvc_doc doc;
    json_t *manifest, *files;
    http_resp resp;
    char *man = NULL, *vert = NULL, *frag = NULL, href[200];
    glint_err e;
    int rc;

    if (material_access(req, mid, &doc, &resp))
        return resp;
    free(doc.text);
    if ((rc = shader_ensure(a, mid, &e)) ||
        (rc = blob_text(a, mid, "shader/shader.json", &man, &e)) ||
        (rc = blob_text(a, mid, "shader/glint_material.vert", &vert, &e)) ||
        (rc = blob_text(a, mid, "shader/glint_material.frag", &frag, &e))) {
        resp = problem_of(rc, &e);
        goto out;
    }
    manifest = json_loads(man, 0, NULL);
    if (!manifest) {
        resp = http_problem(500, "internal", "material %s: unreadable shader manifest", mid);
        goto out;
    }
    files = json_object();
    for (size_t i = 0; i < N_SHADER_FILES; i++) {
        snprintf(href, sizeof href, "/api/v1/materials/%s/shader/%s", mid, shader_files[i].name);
        json_object_set_new(files, shader_files[i].name, json_string(href));
    }
    resp = http_json(200, json_pack("{s:s, s:s, s:s, s:o, s:o}", "language", "GLSL ES 3.00",
                                    "vertex", vert, "fragment", frag, "manifest", manifest,
                                    "files", files));
out:
    free(man);
    free(vert);
    free(frag);
    return resp;
}

static http_resp shader_file(http_req *req)
{
    char file[128];
    for (size_t i = 0; i < N_SHADER_FILES; i++)
        if (strcmp(req->param[1], shader_files[i].name) == 0) {
            fitsvc_doc doc;
            http_resp resp;
            glint_err e;
            int rc;
            if (material_access(req, req->param[0], &doc, &resp))
                return resp;
            free(doc.text);
            if ((rc = shader_ensure(req->app, req->param[0], &e)))
                return problem_of(rc, &e);
            snprintf(file, sizeof file, "shader/%s", shader_files[i].name);
            return blob_resp(req->app, req->param[0], file, shader_files[i].ctype);
        }
    return http_problem(404, "not-found", "a shader export has no file %s", req->param[1]);
}

/* ---- package: an uncompressed POSIX ustar archive --------------------------------------- */

/* Append one regular file to a tar image in memory (f: open_memstream). */
static void tar_add(FILE *f, const char *name, const void *data, size_t len, time_t mtime)
{
    unsigned char h[512];
    unsigned sum = 0;
    static const unsigned char zero[512];

    memset(h, 0, sizeof h);
    memcpy(h, name, strnlen(name, 99)); /* callers keep names under 100 bytes */
    snprintf((char *)h + 100, 8, "%07o", 0644);
    snprintf((char *)h + 108, 8, "%07o", 0);
    snprintf((char *)h + 116, 8, "%07o", 0);
    snprintf((char *)h + 124, 12, "%011llo", (unsigned long long)len);
    snprintf((char *)h + 136, 12, "%011llo", (unsigned long long)mtime);
    memset(h + 148, ' ', 8); /* the checksum counts its own field as spaces */
    h[156] = '0';
    memcpy(h + 257, "ustar", 6);
    memcpy(h + 263, "00", 2);
    snprintf((char *)h + 265, 32, "glint");
    snprintf((char *)h + 297, 32, "glint");
    for (int i = 0; i < 512; i++)
        sum += h[i];
    snprintf((char *)h + 148, 8, "%06o", sum);
    h[155] = ' ';
    fwrite(h, 1, 512, f);
    fwrite(data, 1, len, f);
    if (len % 512)
        fwrite(zero, 1, 512 - len % 512, f);
}

static http_resp package_get(http_req *req)
{
    app *a = req->app;
    const char *mid = req->param[0];
    static const char *const top[] = {"material.json", "factors.png", "factors.exr"};
    fitsvc_doc doc;
    http_resp resp;
    char *mem = NULL, name[256], path[160], disp[160];
    size_t mlen = 0;
    FILE *f;
    time_t now = time(NULL);
    static const unsigned char zero[1024];

    if (material_access(req, mid, &doc, &resp))
        return resp;
    free(doc.text);
    {
        glint_err e;
        int rc = shader_ensure(a, mid, &e);
        if (rc)
            return problem_of(rc, &e);
    }
    f = open_memstream(&mem, &mlen);
    if (!f)
        return http_problem(503, "out-of-memory", "out of memory");
    for (size_t i = 0; i < 3 + N_SHADER_FILES; i++) {
        void *data = NULL;
        size_t len = 0;
        glint_err e;
        int rc;
        if (i < 3)
            snprintf(path, sizeof path, "%s", top[i]);
        else
            snprintf(path, sizeof path, "shader/%s", shader_files[i - 3].name);
        snprintf(name, sizeof name, "materials/%s/%s", mid, path);
        rc = store_blob_get(a->store, name, &data, &len, &e);
        if (rc) {
            fclose(f);
            free(mem);
            return problem_of(rc, &e);
        }
        snprintf(name, sizeof name, "glint-material-%.8s/%s", mid, path);
        tar_add(f, name, data, len, now);
        free(data);
    }
    fwrite(zero, 1, sizeof zero, f); /* end of archive: two zero blocks */
    fclose(f);
    resp = http_bytes_owned(200, "application/x-tar", mem, mlen);
    snprintf(disp, sizeof disp, "attachment; filename=\"glint-material-%s.tar\"", mid);
    http_header(&resp, "Content-Disposition", disp);
    return resp;
}

/* ---- preview ------------------------------------------------------------------------------- */

static int parse_vec(const char *s, double v[3])
{
    char *end;
    for (int i = 0; i < 3; i++) {
        v[i] = strtod(s, &end);
        if (end == s || !isfinite(v[i]))
            return -1;
        s = end;
        if (i < 2) {
            if (*s != ',')
                return -1;
            s++;
        }
    }
    return *s ? -1 : 0;
}

static int parse_num(const char *s, double lo, double hi, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (end == s || *end || !isfinite(v) || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

/* GL meshes uploaded for previews, by scene id (used under app->gl_lock;
 * the app has one GL context, so one table per process). */
static struct {
    char scene_id[33];
    glr_mesh *m;
    unsigned long used;
} gl_meshes[GL_MESHES];
static unsigned long gl_tick;

/* Render through EGL (0), or GLINT_EUNSUPPORTED when there is no context.
 * Called with a->gl_lock held. */
static int preview_gl(app *a, fitsvc_scene *sh, const material *m, const scene_view *v, int w,
                      int h, img *out, glint_err *err)
{
    int slot = -1, rc;
    const scene *sc = fitsvc_scene_get(sh);

    if (!a->gl && !a->gl_failed) {
        glint_err ge;
        if (glr_open(&a->gl, &ge)) {
            a->gl_failed = 1;
            a->gl = NULL;
            fprintf(stderr, "glintd: EGL unavailable, previews render on the CPU: %s\n", ge.msg);
        } else {
            fprintf(stderr, "glintd: previews render through %s\n", glr_describe(a->gl));
        }
    }
    if (!a->gl)
        return glint_err_set(err, GLINT_EUNSUPPORTED, "no EGL context");
    for (int i = 0; i < GL_MESHES; i++)
        if (gl_meshes[i].m && strcmp(gl_meshes[i].scene_id, fitsvc_scene_id(sh)) == 0)
            slot = i;
    if (slot < 0) {
        unsigned long oldest = ~0ul;
        for (int i = 0; i < GL_MESHES; i++) {
            if (!gl_meshes[i].m) {
                slot = i;
                break;
            }
            if (gl_meshes[i].used < oldest) {
                oldest = gl_meshes[i].used;
                slot = i;
            }
        }
        if (gl_meshes[slot].m)
            glr_mesh_free(a->gl, gl_meshes[slot].m);
        gl_meshes[slot].m = NULL;
        if ((rc = glr_mesh_upload(a->gl, &sc->mesh, &gl_meshes[slot].m, err)))
            return rc;
        snprintf(gl_meshes[slot].scene_id, sizeof gl_meshes[slot].scene_id, "%s",
                 fitsvc_scene_id(sh));
    }
    gl_meshes[slot].used = ++gl_tick;
    return glr_preview(a->gl, gl_meshes[slot].m, m, v, w, h, 0.0f, out, err);
}

static http_resp preview(http_req *req, const char *format)
{
    app *a = req->app;
    const char *mid = req->param[0];
    const char *q_view = http_query(req, "view"), *q_eye = http_query(req, "eye"),
               *q_light = http_query(req, "light"), *q_target = http_query(req, "target"),
               *q_fov = http_query(req, "fov"), *q_size = http_query(req, "size"),
               *q_int = http_query(req, "intensity"), *q_rend = http_query(req, "renderer");
    fitsvc_doc doc = {{0}, {0}, NULL, 0};
    http_resp resp;
    fitsvc_scene *sh = NULL;
    material m;
    scene_view v;
    img im = {0};
    glint_err e;
    char dir[4096], name[128], rname[300];
    void *data = NULL;
    size_t len = 0;
    int rc, size = 0, w = 0, h = 0, use_gl;
    double x;

    memset(&m, 0, sizeof m);
    glint_err_clear(&e);
    if (material_access(req, mid, &doc, &resp))
        return resp;
    if (q_rend && strcmp(q_rend, "cpu") && strcmp(q_rend, "egl") && strcmp(q_rend, "auto")) {
        resp = http_problem(422, "invalid-parameter", "renderer must be auto, egl or cpu");
        goto out;
    }
    if (q_size) {
        if (parse_num(q_size, SCENE_MIN_SIZE, PREVIEW_MAX, &x) || x != floor(x)) {
            resp = http_problem(422, "invalid-parameter", "size must be an integer in %d..%d",
                                SCENE_MIN_SIZE, PREVIEW_MAX);
            goto out;
        }
        size = (int)x;
    }
    if (!q_view && !(q_eye && q_light)) {
        resp = http_problem(422, "invalid-parameter",
                            "a preview needs view=K, or eye=x,y,z and light=x,y,z");
        goto out;
    }
    rc = scene_get(a, doc.scene, &sh, &e);
    if (rc) {
        resp = rc == GLINT_ENOTFOUND
                   ? http_problem(409, "scene-gone", "the material's scene no longer exists")
                   : problem_of(rc, &e);
        goto out;
    }
    {
        const scene *sc = fitsvc_scene_get(sh);
        memset(&v, 0, sizeof v);
        v.half_fov = sc->views[0].half_fov;
        v.light_intensity = 1.0;
        v.light_deg = -1.0;
        if (q_view) {
            if (parse_num(q_view, 0, sc->nviews - 1, &x) || x != floor(x)) {
                resp = http_problem(422, "invalid-parameter",
                                    "view must be an integer in 0..%d (the scene has %d views)",
                                    sc->nviews - 1, sc->nviews);
                goto out;
            }
            v = sc->views[(int)x];
        }
        if (q_eye && parse_vec(q_eye, v.eye)) {
            resp = http_problem(422, "invalid-parameter", "eye must be x,y,z (finite numbers)");
            goto out;
        }
        if (q_eye && !q_target)
            v.target[0] = v.target[1] = v.target[2] = 0.0;
        if (q_light && parse_vec(q_light, v.light)) {
            resp = http_problem(422, "invalid-parameter", "light must be x,y,z (finite numbers)");
            goto out;
        }
        if (q_target && parse_vec(q_target, v.target)) {
            resp = http_problem(422, "invalid-parameter", "target must be x,y,z (finite numbers)");
            goto out;
        }
        if (q_fov) {
            if (parse_num(q_fov, 1.0, 170.0, &x)) {
                resp = http_problem(422, "invalid-parameter",
                                    "fov must be a vertical field of view in degrees, 1..170");
                goto out;
            }
            v.half_fov = 0.5 * x * M_PI / 180.0;
        }
        if (q_int) {
            if (parse_num(q_int, 0.0, 1e6, &x)) {
                resp = http_problem(422, "invalid-parameter", "intensity must be in [0, 1e6]");
                goto out;
            }
            v.light_intensity = x;
        }
        {
            double d[3] = {v.target[0] - v.eye[0], v.target[1] - v.eye[1],
                           v.target[2] - v.eye[2]};
            if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < 1e-12) {
                resp = http_problem(422, "invalid-parameter", "eye and target coincide");
                goto out;
            }
        }
        if (!size)
            size = q_view && !q_eye ? (sc->width > sc->height ? sc->width : sc->height)
                                    : PREVIEW_DEFAULT;
        /* a view keeps the scene's aspect (size is the longer side); a free
         * camera renders a square */
        w = h = size;
        if (q_view && !q_eye && sc->width != sc->height) {
            if (sc->width > sc->height)
                h = (int)lround((double)size * sc->height / sc->width);
            else
                w = (int)lround((double)size * sc->width / sc->height);
            if (w < SCENE_MIN_SIZE)
                w = SCENE_MIN_SIZE;
            if (h < SCENE_MIN_SIZE)
                h = SCENE_MIN_SIZE;
        }
    }
    snprintf(name, sizeof name, "materials/%s", mid);
    if ((rc = store_blob_path(a->store, name, dir, sizeof dir, &e)) ||
        (rc = material_load(dir, &m, &e))) {
        resp = problem_of(rc == GLINT_EFORMAT ? GLINT_EINTERNAL : rc, &e);
        goto out;
    }
    use_gl = !q_rend || strcmp(q_rend, "cpu") != 0;
    rc = GLINT_EUNSUPPORTED;
    snprintf(rname, sizeof rname, "cpu");
    if (use_gl) {
        pthread_mutex_lock(&a->gl_lock);
        rc = preview_gl(a, sh, &m, &v, w, h, &im, &e);
        if (rc == 0)
            snprintf(rname, sizeof rname, "egl; %s", glr_describe(a->gl));
        pthread_mutex_unlock(&a->gl_lock);
        if (rc && rc != GLINT_EUNSUPPORTED)
            fprintf(stderr, "glintd: EGL preview failed, using the CPU: %s\n", e.msg);
        if (rc && q_rend && strcmp(q_rend, "egl") == 0) {
            resp = http_problem(503, "egl-unavailable", "EGL rendering is unavailable: %s",
                                e.msg);
            goto out;
        }
    }
    if (rc && size > PREVIEW_CPU_MAX) {
        /* the CPU reference keeps a full G-buffer (57 bytes a pixel) */
        resp = http_problem(503, "egl-unavailable",
                            "previews above %d pixels need EGL, which is unavailable here%s%s",
                            PREVIEW_CPU_MAX, e.msg[0] ? ": " : "", e.msg);
        goto out;
    }
    if (rc) {
        rc = material_render(&m, &fitsvc_scene_get(sh)->mesh, &v, w, h, &im, &e);
        if (rc) {
            resp = problem_of(rc, &e);
            goto out;
        }
    }
    if ((rc = img_write_mem(format, &im, &data, &len, &e))) {
        resp = problem_of(rc, &e);
        goto out;
    }
    resp = http_bytes_owned(200, strcmp(format, "png") == 0 ? "image/png" : "image/x-exr", data,
                            len);
    http_header(&resp, "X-Glint-Renderer", rname);
out:
    img_free(&im);
    material_free(&m);
    fitsvc_scene_release(a->fits, sh);
    free(doc.text);
    return resp;
}

static http_resp preview_png(http_req *req)
{
    return preview(req, "png");
}

static http_resp preview_exr(http_req *req)
{
    return preview(req, "exr");
}

/* ---- eval ------------------------------------------------------------------------------------ */

/* A unit vector from a JSON array of 3 finite numbers, not all zero (any
 * length: scaled by its largest entry first, so nothing overflows). */
static int unit_vec(const json_t *a, double v[3])
{
    double n = 0.0, mx = 0.0;
    if (!json_is_array(a) || json_array_size(a) != 3)
        return -1;
    for (int i = 0; i < 3; i++) {
        json_t *x = json_array_get(a, (size_t)i);
        if (!json_is_number(x) || !isfinite(json_number_value(x)))
            return -1;
        v[i] = json_number_value(x);
        if (fabs(v[i]) > mx)
            mx = fabs(v[i]);
    }
    if (!(mx > 0.0))
        return -2;
    for (int i = 0; i < 3; i++) {
        v[i] /= mx;
        n += v[i] * v[i];
    }
    n = sqrt(n);
    for (int i = 0; i < 3; i++)
        v[i] /= n;
    return 0;
}

static http_resp eval_post(http_req *req)
{
    app *a = req->app;
    const char *mid = req->param[0];
    fitsvc_doc doc;
    json_t *body = NULL, *pairs, *values = NULL, *p;
    http_resp resp;
    material m;
    char dir[4096], name[128];
    glint_err e;
    size_t i;
    const char *k;
    json_t *x;
    int rc;

    memset(&m, 0, sizeof m);
    if (material_access(req, mid, &doc, &resp))
        return resp;
    free(doc.text);
    body = http_body_json(req, &resp);
    if (!body)
        return resp;
    json_object_foreach(body, k, x) {
        if (strcmp(k, "pairs") != 0) {
            resp = http_problem(422, "invalid-parameter", "unknown member '%s' (eval takes \"pairs\")",
                                k);
            goto out;
        }
    }
    pairs = json_object_get(body, "pairs");
    if (!json_is_array(pairs) || json_array_size(pairs) == 0) {
        resp = http_problem(422, "invalid-parameter",
                            "pairs must be a non-empty array of {\"n\", \"wi\", \"wo\"}");
        goto out;
    }
    if (json_array_size(pairs) > EVAL_MAX_PAIRS) {
        resp = http_problem(413, "too-many-pairs", "%zu pairs exceed the limit of %d per request",
                            json_array_size(pairs), EVAL_MAX_PAIRS);
        goto out;
    }
    snprintf(name, sizeof name, "materials/%s", mid);
    if ((rc = store_blob_path(a->store, name, dir, sizeof dir, &e)) ||
        (rc = material_load(dir, &m, &e))) {
        resp = problem_of(rc == GLINT_EFORMAT ? GLINT_EINTERNAL : rc, &e);
        goto out;
    }
    values = json_array();
    json_array_foreach(pairs, i, p) {
        static const char *const names[3] = {"n", "wi", "wo"};
        double d[3][3], rgb[3];
        if (!json_is_object(p) || json_object_size(p) != 3) {
            resp = http_problem(422, "invalid-parameter",
                                "pairs[%zu] must be an object with exactly n, wi and wo", i);
            goto out;
        }
        for (int j = 0; j < 3; j++) {
            int r = unit_vec(json_object_get(p, names[j]), d[j]);
            if (r) {
                resp = http_problem(422, "invalid-parameter",
                                    r == -2 ? "pairs[%zu].%s must not be a zero vector"
                                            : "pairs[%zu].%s must be an array of 3 finite numbers",
                                    i, names[j]);
                goto out;
            }
        }
        material_eval(&m, d[0], d[1], d[2], rgb);
        json_array_append_new(values, json_pack("[f, f, f]", rgb[0], rgb[1], rgb[2]));
    }
    resp = http_json(200, json_pack("{s:o}", "values", values));
    values = NULL;
out:
    json_decref(values);
    json_decref(body);
    material_free(&m);
    return resp;
}

/* ---- methods ---------------------------------------------------------------------------------- */

static json_t *hf3_description(void)
{
    fit_params d;
    char reg[64], map[96];
    fit_params_default(&d);
    hf_reg_format(&d.reg, reg, sizeof reg);
    hf_map_format(&d.map, map, sizeof map);
    return json_pack(
        "{s:s, s:s, s:s, s:s, s:[o, o, o, o, o, o, o, o], s:[o, o, o, o], s:s}",
        "name", "hf3", "title", "Homomorphic factorization into three 1D factors",
        "reference",
        "Jaroszkiewicz & McCool, Fast Extraction of BRDFs and Material Maps from Images, GI 2003",
        "description",
        "Painted pixels are BRDF samples; the constraint matrix of the painted views (the "
        "sampling pattern) is decomposed once and cached, and each fit applies the "
        "regularized pseudo-inverse in log space: p(pi_p) q(pi_q) r(pi_r). Parameters marked "
        "precomputation change the cache key (a new precomputation runs as a job); the others "
        "are free. Points: fit_seconds is the warm fit (precomputation in memory), "
        "cold_seconds the precomputation from scratch, rms_painted the RMS error on the "
        "painted pixels, held_out_rms the pooled RMS error on each painted view when it is "
        "left out of the fit (leave-one-view-out; measured in the background after the first "
        "fit of a configuration with at least 2 painted views).",
        "params",
        json_pack("{s:s, s:s, s:i, s:i, s:i, s:s, s:s}", "name", "res", "type", "integer",
                  "default", d.res, "minimum", HF_RES_MIN, "maximum", HF_RES_MAX, "affects",
                  "precomputation", "description",
                  "texels per factor: accuracy up to about 128 at a 128x128 raster; "
                  "precomputation grows as res^3"),
        json_pack("{s:s, s:s, s:f, s:f, s:f, s:s, s:s}", "name", "lambda", "type", "number",
                  "default", d.lambda, "minimum", 0.0, "maximum", HF_LAMBDA_MAX, "affects",
                  "precomputation", "description", "weight of the Laplacian smoothing rows"),
        json_pack("{s:s, s:s, s:s, s:s, s:s, s:[s, s, s, s, s], s:s}", "name", "regularization",
                  "type", "string", "default", reg, "affects", "operator", "syntax",
                  "trunc[:full|:K|:P%|:relT] | tikhonov:ALPHA|:relT | linear[:full|:K|:P%]",
                  "examples", "trunc:full", "trunc:50%", "trunc:rel1e-3", "tikhonov:rel1e-2",
                  "linear:40", "description",
                  "regularized pseudo-inverse (paper eq. 6-8); full rank is the measured best"),
        json_pack("{s:s, s:s, s:s, s:s, s:s, s:[s, s, s, s], s:s}", "name", "mapping", "type",
                  "string", "default", map, "affects", "fit", "syntax",
                  "log | add[:a] | sub[:margin], optionally ,eps=E", "examples", "log",
                  "add:0.1", "sub:0.01", "add:0.05,eps=1e-4", "description",
                  "mapping to log space (section 3.4)"),
        json_pack("{s:s, s:s, s:s, s:[s, s], s:s, s:s}", "name", "model", "type", "string",
                  "default", d.model == HF_MODEL_BRDF ? "brdf" : "radiance", "enum", "radiance",
                  "brdf", "affects", "fit", "description",
                  "radiance: factors approximate the painted value; brdf: painted / cos_i"),
        json_pack("{s:s, s:s, s:s, s:[s, s], s:s, s:s}", "name", "precision", "type", "string",
                  "default", d.prec == HF_F32 ? "single" : "double", "enum", "double", "single",
                  "affects", "operator", "description", "precision of the stored operator"),
        json_pack("{s:s, s:s, s:s, s:[s, s], s:s, s:s}", "name", "route", "type", "string",
                  "default", d.route == HF_ROUTE_SVD ? "svd" : "eig", "enum", "eig", "svd",
                  "affects", "precomputation", "description",
                  "eig: eigendecomposition of B^T B (fast); svd: dense SVD of B (reference)"),
        json_pack("{s:s, s:s, s:f, s:f, s:f, s:s, s:s}", "name", "rcond", "type", "number",
                  "default", hf_rcond_default(d.route), "exclusiveMinimum", 0.0,
                  "exclusiveMaximum", 1.0, "affects", "precomputation", "description",
                  "relative singular-value cutoff of the numerical rank"),
        "presets",
        json_pack("{s:s, s:{s:i}}", "name", "draft", "params", "res", 32),
        json_pack("{s:s, s:{s:i}}", "name", "fast", "params", "res", 64),
        json_pack("{s:s, s:{s:i}}", "name", "default", "params", "res", d.res),
        json_pack("{s:s, s:{s:i}}", "name", "fine", "params", "res", 256),
        "held_out",
        "leave-one-view-out: for each painted view, fit the others and measure the RMS error "
        "on that view's painted pixels; pooled over views");
}

/* GET /methods[?scene_id=ID | ?session_id=ID]: the points of a scene are
 * readable by scene id like the scene itself (ids are 128 random bits);
 * with session_id, by the session's view or paint token.  Points never
 * show material ids (those belong to sessions). */
static http_resp methods_get(http_req *req)
{
    app *a = req->app;
    const char *scid = http_query(req, "scene_id"), *sid = http_query(req, "session_id");
    json_t *out, *sdoc = NULL, *points;
    http_resp deny;
    fitsvc_scene *sh = NULL;
    glint_err e;
    size_t i;
    json_t *pt;
    int rc;

    if (scid && sid)
        return http_problem(422, "invalid-parameter", "give scene_id or session_id, not both");
    if (sid) {
        if (session_access(req, sid, 0, &sdoc, &deny))
            return deny;
        scid = json_string_value(json_object_get(sdoc, "scene_id"));
    }
    out = json_pack("{s:[o]}", "methods", hf3_description());
    if (scid) {
        rc = scene_get(a, scid, &sh, &e);
        if (rc) {
            json_decref(out);
            json_decref(sdoc);
            return rc == GLINT_ENOTFOUND ? http_problem(404, "not-found", "no scene %s", scid)
                                         : problem_of(rc, &e);
        }
        points = fitsvc_points_get(a->fits, fitsvc_scene_hash(sh));
        /* material ids belong to sessions: not shown here */
        json_array_foreach(points, i, pt) {
            json_object_del(pt, "material_id");
            json_object_del(json_object_get(pt, "held_out"), "material_id");
        }
        json_object_set_new(out, "scene", json_pack("{s:s, s:s, s:o}", "id", scid, "hash",
                                                    fitsvc_scene_hash(sh), "points", points));
        fitsvc_scene_release(a->fits, sh);
    }
    json_decref(sdoc);
    return http_json(200, out);
}

const http_route api_fits_routes[] = {
    {"POST", "/api/v1/sessions/{id}/fits", fits_create},
    {"GET", "/api/v1/sessions/{id}/materials", session_materials},
    {"GET", "/api/v1/jobs/{id}", job_get},
    {"GET", "/api/v1/jobs/{id}/events", job_events},
    {"GET", "/api/v1/materials/{id}", material_get},
    {"GET", "/api/v1/materials/{id}/factors.png", factors_png},
    {"GET", "/api/v1/materials/{id}/factors.exr", factors_exr},
    {"GET", "/api/v1/materials/{id}/shader", shader_get},
    {"GET", "/api/v1/materials/{id}/shader/{file}", shader_file},
    {"GET", "/api/v1/materials/{id}/package", package_get},
    {"GET", "/api/v1/materials/{id}/preview.png", preview_png},
    {"GET", "/api/v1/materials/{id}/preview.exr", preview_exr},
    {"POST", "/api/v1/materials/{id}/eval", eval_post},
    {"GET", "/api/v1/methods", methods_get},
};
const int api_fits_nroutes = sizeof api_fits_routes / sizeof api_fits_routes[0];
