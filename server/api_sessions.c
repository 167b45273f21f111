/* api_sessions.c: painting sessions (proto/openapi.yaml, section "scenes,
 * meshes, sessions...").
 *
 *   POST /api/v1/sessions                                {"scene_id"}      (API key)
 *   GET  /api/v1/sessions/{id}                                             (token)
 *   PUT  /api/v1/sessions/{id}/views/{k}/painting        PNG, JPEG or EXR  (paint token)
 *   GET  /api/v1/sessions/{id}/views/{k}/painting[?format=png|exr]         (token)
 *   POST /api/v1/sessions/{id}/views/{k}/strokes         {"strokes": [...]} (paint token)
 *   GET  /api/v1/sessions/{id}/strokes?since=N[&limit=L]                   (token)
 *   GET  /api/v1/sessions/{id}/events[?since=N&name=...] (SSE)             (token)
 *
 * A view that was never painted reads as the scene's base render (header
 * X-Glint-Painted: 0); strokes apply to the current image (the painting, or
 * the base render), in order, with core/truth/stroke.h's brush; erase strokes
 * bring back the base render.  Strokes and the painting they produce are
 * stored in one transaction before the answer (store.h), and each stroke
 * takes the session's next sequence number.  Writes to one session are
 * serialized here (a striped lock), so two requests never paint over the
 * same starting image.  Helpers return 0 or a code with a glint_err;
 * handlers answer failures with api_error(). */
#include <ctype.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "api_common.h"
#include "app.h"
#include "auth.h"
#include "clock.h"
#include "events.h"
#include "fitsvc.h"
#include "ids.h"
#include "img.h"
#include "memo.h"
#include "par.h"
#include "upload.h"
#include "scenes.h"
#include "store.h"
#include "stroke.h"

#define SESSION_STRIPES 64
#define STROKES_PAGE_DEFAULT 1000
#define STROKES_PAGE_MAX 10000
/* A page of GET .../strokes holds at most this many bytes of strokes (or
 * one stroke, at most max_stroke_points points): what one reader costs the
 * daemon is a page, however long the history. */
#define STROKES_PAGE_BYTES ((size_t)1 << 20)

static pthread_mutex_t session_stripes[SESSION_STRIPES];
static pthread_once_t session_stripes_once = PTHREAD_ONCE_INIT;

static void session_stripes_init(void)
{
    for (int i = 0; i < SESSION_STRIPES; i++)
        pthread_mutex_init(&session_stripes[i], NULL);
}

/* The write lock of a session (ids are random: any 2 hex digits spread). */
static pthread_mutex_t *session_lock(const char *id)
{
    unsigned h = 0;
    pthread_once(&session_stripes_once, session_stripes_init);
    for (const char *c = id; *c; c++)
        h = h * 31u + (unsigned char)*c;
    return &session_stripes[h % SESSION_STRIPES];
}

/* ---- helpers -------------------------------------------------------------------- */

/* The session's scene doc and the view index of the path.  OUT: *scene_doc,
 * *k, *w, *h: the size of the view's image (the painting: the scene's
 * paint_scale times its raster), *ps: that scale. */
static int session_view(http_req *req, const json_t *sdoc, json_t **scene_doc, int *k, int *w,
                        int *h, int *ps, glint_err *e)
{
    app *a = req->app;
    const char *scene_id = json_string_value(json_object_get(sdoc, "scene_id"));
    int n, rc;

    *scene_doc = NULL;
    if ((rc = store_scene_get(a->store, scene_id, scene_doc, e)))
        return rc == GLINT_ENOTFOUND
                   ? api_reject(e, rc, "not-found", "the scene of session %s no longer exists",
                                req->param[0])
                   : glint_err_prefix(e, "scene");
    n = (int)json_array_size(json_object_get(*scene_doc, "views"));
    if (api_view_index(req->param[1], n, k)) {
        json_decref(*scene_doc);
        *scene_doc = NULL;
        return api_reject(e, GLINT_ENOTFOUND, "not-found",
                          "session %s has no view \"%.16s\" (views 0..%d)", req->param[0],
                          req->param[1], n - 1);
    }
    *ps = scenes_paint_scale(*scene_doc);
    *w = *ps * (int)json_integer_value(json_object_get(*scene_doc, "width"));
    *h = *ps * (int)json_integer_value(json_object_get(*scene_doc, "height"));
    return 0;
}

/* The current image of a view: its painting, or the base render.  OUT:
 * *im (RGB), *version (0 for the base), and when file is not NULL,
 * *file / *flen: the stored file of that version where it can be read
 * (else NULL, not an error), for img_write_exr_mem_reusing. */
static int view_current(app *a, const char *session, const char *scene_id, int k, int ps,
                        img *im, int64_t *version, void **file, size_t *flen, glint_err *e)
{
    void *exr = NULL;
    size_t len = 0;
    json_t *list = NULL, *it;
    memo_painting *pin = NULL;
    int64_t listed = 0;
    size_t i;
    int rc;

    memset(im, 0, sizeof *im);
    if (file) {
        *file = NULL;
        *flen = 0;
    }
    /* the memo's decoded copy of the current version, when it has it */
    if (store_paintings_list(a->store, session, &list, NULL) == 0) {
        json_array_foreach(list, i, it) {
            if (json_integer_value(json_object_get(it, "view")) == k)
                listed = json_integer_value(json_object_get(it, "version"));
        }
        json_decref(list);
    }
    if (listed > 0 &&
        memo_painting_get(a->memo, session, k, (long long)listed, &pin) == 0) {
        const img *m = memo_painting_img(pin);
        rc = img_alloc(im, m->width, m->height, m->channels, e);
        if (!rc) {
            memcpy(im->px, m->px, (size_t)m->width * m->height * m->channels * sizeof(float));
            rc = img_to_rgb(im, e);
        }
        memo_painting_release(a->memo, pin);
        *version = listed;
        if (!rc && file) { /* the file of that version, if it is still the current one */
            int64_t v = 0;
            glint_err fe;
            if (store_painting_get(a->store, session, k, &exr, &len, &v, &fe) == 0 &&
                v == listed) {
                *file = exr;
                *flen = len;
            } else {
                free(exr);
            }
        }
        return rc;
    }
    rc = store_painting_get(a->store, session, k, &exr, &len, version, e);
    if (rc == GLINT_ENOTFOUND) {
        *version = 0;
        return scenes_base(a, scene_id, k, ps, im, e);
    }
    if (rc)
        return rc;
    rc = img_read_mem(exr, len, im, e);
    if (!rc)
        rc = img_to_rgb(im, e);
    if (rc)
        glint_err_prefix(e, "stored painting of view %d", k);
    if (!rc && file) {
        *file = exr;
        *flen = len;
    } else {
        free(exr);
    }
    return rc;
}

/* ---- sessions --------------------------------------------------------------------- */

/* The public form of a session for the access granted (api_common.h). */
json_t *api_session_public(app *a, const json_t *doc, int paint)
{
    const char *id = json_string_value(json_object_get(doc, "id"));
    const char *pt = json_string_value(json_object_get(doc, "paint_token"));
    const char *vt = json_string_value(json_object_get(doc, "view_token"));
    char link[160];
    json_t *o, *links, *paintings = NULL;
    glint_err e;

    o = json_pack("{s:s, s:O, s:s, s:O, s:I, s:s}", "id", id, "scene_id",
                  json_object_get(doc, "scene_id"), "view_token", vt, "created",
                  json_object_get(doc, "created"), "last_seq",
                  (json_int_t)json_integer_value(json_object_get(doc, "last_seq")), "access",
                  paint ? "paint" : "view");
    links = json_object();
    if (!o || !links) {
        json_decref(o);
        json_decref(links);
        return NULL;
    }
    if (paint) {
        json_object_set_new(o, "paint_token", json_string(pt));
        snprintf(link, sizeof link, "/#/session/%s?token=%s", id, pt);
        json_object_set_new(links, "paint", json_string(link));
    }
    snprintf(link, sizeof link, "/#/session/%s?token=%s", id, vt);
    json_object_set_new(links, "view", json_string(link));
    snprintf(link, sizeof link, "/api/v1/sessions/%s/events", id);
    json_object_set_new(links, "events", json_string(link));
    json_object_set_new(o, "links", links);
    if (json_is_string(json_object_get(doc, "expires")))
        json_object_set(o, "expires", json_object_get(doc, "expires"));
    if (a && store_paintings_list(a->store, id, &paintings, &e) == 0)
        json_object_set_new(o, "paintings", paintings);
    return o;
}

static int session_create_do(http_req *req, json_t **out, char id[33], glint_err *e)
{
    app *a = req->app;
    json_t *body = NULL, *doc = NULL, *jscene, *scene_doc = NULL, *v;
    char pt[33], vt[33], now[GLINT_TIME_LEN];
    const char *k;
    int rc;

    if ((rc = auth_require_key(req, e)))
        return rc;
    if (req->body_too_large)
        return api_reject(e, GLINT_ETOOBIG, "body-too-large",
                          "the session request exceeds the request body limit of %zu bytes "
                          "(max_body, glintd --max-body-mb %zu)",
                          a->cfg.lim.max_body, a->cfg.lim.max_body >> 20);
    if ((rc = api_body_json(req, &body, e)))
        return rc;
    json_object_foreach(body, k, v)
        if (strcmp(k, "scene_id") != 0 && strcmp(k, "expires_in") != 0) {
            rc = api_reject(e, GLINT_EINVAL, "invalid-input",
                            "unknown key \"%.64s\" (known: scene_id, expires_in)", k);
            goto done;
        }
    jscene = json_object_get(body, "scene_id");
    if (!json_is_string(jscene)) {
        rc = api_reject(e, GLINT_EINVAL, "invalid-input", "scene_id: %s",
                        jscene ? "expected a string (a scene's id)" : "missing");
        goto done;
    }
    if ((rc = store_scene_get(a->store, json_string_value(jscene), &scene_doc, e))) {
        if (rc == GLINT_ENOTFOUND)
            rc = api_reject(e, GLINT_EINVAL, "unknown-scene", "scene_id: %.400s", e->msg);
        goto done;
    }
    if ((rc = glint_id_new_near(json_string_value(jscene), id, e)) ||
        (rc = glint_id_new(pt, e)) || (rc = glint_id_new(vt, e)))
        goto done;
    glint_time_iso_ms(now);
    doc = json_pack("{s:s, s:O, s:s, s:s, s:s}", "id", id, "scene_id", jscene, "paint_token", pt,
                    "view_token", vt, "created", now);
    if (!doc) {
        rc = glint_err_set(e, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    if ((v = json_object_get(body, "expires_in")) && (rc = api_expiry_parse(v, doc, e)))
        goto done;
    if ((rc = store_session_put(a->store, id, doc, e))) {
        if (rc == GLINT_ENOTFOUND)
            rc = api_reject(e, GLINT_EINVAL, "unknown-scene", "scene_id: %.400s", e->msg);
        goto done;
    }
    json_object_set_new(doc, "last_seq", json_integer(0));
    *out = api_session_public(a, doc, 1);
done:
    json_decref(doc);
    json_decref(scene_doc);
    json_decref(body);
    return rc;
}

static http_resp session_create(http_req *req)
{
    json_t *pub = NULL;
    char id[33];
    glint_err e;
    if (session_create_do(req, &pub, id, &e))
        return api_error(&e);
    return api_created(pub, "sessions", id);
}

static http_resp session_get(http_req *req)
{
    app *a = req->app;
    json_t *doc;
    glint_err e, probe;
    http_resp r;
    if (api_session(req, req->param[0], 0, &doc, &e))
        return api_error(&e);
    /* paint access: could this request write? */
    r = http_json(200, api_session_public(a, doc, auth_session(req, doc, 1, &probe) == 0));
    json_decref(doc);
    return r;
}

/* ---- paintings ---------------------------------------------------------------------- */

/* Conditional replace: If-Match names the painting version the client built
 * its image from ("0" for a view never painted).  Called under the session
 * lock, so no stroke can slip in between. */
static int if_match(http_req *req, int k, int64_t *base, glint_err *e)
{
    app *a = req->app;
    const char *hdr = http_header_in(req, "If-Match");
    const char *p = hdr && hdr[0] == '"' ? hdr + 1 : hdr;
    json_t *list = NULL, *it;
    long long want;
    int64_t cur = 0;
    char *end;
    size_t i;

    *base = -1;
    if (!hdr)
        return 0;
    want = strtoll(p, &end, 10);
    if (end == p || want < 0)
        return api_reject(e, GLINT_EINVAL, "bad-if-match",
                          "If-Match must be a painting version (a whole number), got '%.40s'",
                          hdr);
    if (store_paintings_list(a->store, req->param[0], &list, e) == 0) {
        json_array_foreach(list, i, it) {
            if (json_integer_value(json_object_get(it, "view")) == k)
                cur = json_integer_value(json_object_get(it, "version"));
        }
        json_decref(list);
    }
    if (cur != want)
        return api_reject(e, GLINT_ECONFLICT, "painting-changed",
                          "view %d is at painting version %lld, not %lld (If-Match): someone "
                          "changed it; read it again", k, (long long)cur, want);
    *base = want; /* checked again in the store's transaction: another replica */
    return 0;
}

static http_resp painting_put(http_req *req)
{
    app *a = req->app;
    json_t *sdoc = NULL, *scene_doc = NULL;
    http_resp r = {0, NULL};
    img im = {0};
    int64_t version = 0, seq = 0, base = -1;
    glint_err e;
    upload_blob bw;
    double t0 = glint_now();
    int k, w, h, ps, rc, wrc;

    if ((rc = api_session(req, req->param[0], 1, &sdoc, &e)) ||
        (rc = session_view(req, sdoc, &scene_doc, &k, &w, &h, &ps, &e)))
        goto done;
    srv_timing_step(&req->timing, "session", t0);
    if ((rc = upload_precheck(req, w, h, &e)))
        goto done;
    /* the upload is stored as it came: it is decoded and checked while its
     * blob is written, committed only when it passed, and decodes to the
     * same pixels whenever it is read */
    upload_blob_start(&bw, a->store, req->param[0], k, req->body, req->body_len);
    rc = upload_decode(req, k, w, h, ps, &im, &e);
    t0 = glint_now();
    wrc = upload_blob_join(&bw);
    t0 = srv_timing_step(&req->timing, "write", t0);
    if (rc || wrc) {
        if (!wrc) /* a blob no row will name */
            store_blob_delete(a->store, bw.name, NULL);
        else if (!rc) {
            e = bw.err;
            rc = wrc;
            glint_err_prefix(&e, "storing the painting");
        }
        goto done;
    }
    pthread_mutex_lock(session_lock(req->param[0]));
    if ((rc = if_match(req, k, &base, &e)))
        store_blob_delete(a->store, bw.name, NULL);
    else if ((rc = store_painting_commit_at(a->store, req->param[0], k, base, bw.name, &version,
                                            &seq, &e))) {
        if (rc == GLINT_ECONFLICT) {
            char msg[GLINT_ERR_MSG_MAX];
            snprintf(msg, sizeof msg, "%.400s (If-Match): read it again", e.msg);
            api_reject(&e, rc, "painting-changed", "%s", msg);
        } else
            glint_err_prefix(&e, "storing the painting");
    }
    pthread_mutex_unlock(session_lock(req->param[0]));
    if (rc)
        goto done;
    t0 = srv_timing_step(&req->timing, "store", t0);
    memo_painting_offer(a->memo, req->param[0], k, (long long)version, &im);
    fitsvc_painting_stored(a->fits, req->param[0], k, (long long)version);
    events_notify(a->events, req->param[0]);
    srv_timing_step(&req->timing, "notify", t0);
    r = http_json(200, json_pack("{s:i, s:I, s:I}", "view", k, "version", (json_int_t)version,
                                 "seq", (json_int_t)seq));
done:
    if (rc)
        r = api_error(&e);
    img_free(&im);
    json_decref(scene_doc);
    json_decref(sdoc);
    return r;
}

static http_resp painting_get(http_req *req)
{
    app *a = req->app;
    json_t *sdoc = NULL, *scene_doc = NULL;
    const char *fmt = http_query(req, "format");
    http_resp r = {0, NULL};
    void *exr = NULL, *data = NULL;
    size_t len = 0;
    int64_t version = 0;
    char vbuf[32];
    glint_err e;
    img im = {0};
    int k, w, h, ps, rc;

    if (!fmt)
        fmt = "png";
    if (strcmp(fmt, "png") && strcmp(fmt, "exr"))
        return http_problem(422, "invalid-input", "format \"%.16s\" is not png or exr", fmt);
    if ((rc = api_session(req, req->param[0], 0, &sdoc, &e)) ||
        (rc = session_view(req, sdoc, &scene_doc, &k, &w, &h, &ps, &e)))
        goto done;
    rc = store_painting_get(a->store, req->param[0], k, &exr, &len, &version, &e);
    if (rc == 0 && strcmp(fmt, "exr") == 0 && len >= 4 && memcmp(exr, "\x76\x2f\x31\x01", 4) == 0) {
        r = http_bytes_owned(200, "image/x-exr", exr, len);
        exr = NULL;
    } else if (rc == 0 || rc == GLINT_ENOTFOUND) {
        const char *scene_id = json_string_value(json_object_get(sdoc, "scene_id"));
        rc = rc == 0 ? img_read_mem(exr, len, &im, &e)
                     : scenes_base(a, scene_id, k, ps, &im, &e);
        if (rc || (rc = img_to_rgb(&im, &e)) || (rc = img_write_mem(fmt, &im, &data, &len, &e))) {
            glint_err_prefix(&e, "painting");
            goto done;
        }
        r = http_bytes_owned(200, strcmp(fmt, "exr") ? "image/png" : "image/x-exr", data, len);
    } else {
        glint_err_prefix(&e, "painting");
        goto done;
    }
    snprintf(vbuf, sizeof vbuf, "%lld", (long long)version);
    http_header(&r, "X-Glint-Painted", version > 0 ? "1" : "0");
    http_header(&r, "X-Glint-Version", vbuf);
    http_header(&r, "Cache-Control", "no-store");
done:
    if (rc)
        r = api_error(&e);
    free(exr);
    img_free(&im);
    json_decref(scene_doc);
    json_decref(sdoc);
    return r;
}

/* ---- strokes ------------------------------------------------------------------------ */

/* The strokes of the body, validated and in canonical form.  OUT: *list, *n,
 * *canon (the stroke objects to store). */
static int strokes_parse(http_req *req, stroke **list, int *n, json_t **canon, glint_err *e)
{
    app *a = req->app;
    stroke_limits lim = {a->cfg.lim.max_strokes, a->cfg.lim.max_stroke_points};
    json_t *body = NULL, *v;
    const char *key;
    int rc;

    *list = NULL;
    *n = 0;
    *canon = NULL;
    if (req->body_too_large)
        return api_reject(e, GLINT_ETOOBIG, "body-too-large",
                          "the strokes exceed the request body limit of %zu bytes "
                          "(max_body, glintd --max-body-mb %zu)",
                          a->cfg.lim.max_body, a->cfg.lim.max_body >> 20);
    if ((rc = api_body_json(req, &body, e)))
        return rc;
    json_object_foreach(body, key, v)
        if (strcmp(key, "strokes") != 0) {
            rc = api_reject(e, GLINT_EINVAL, "invalid-input",
                            "unknown key \"%.64s\" (known: strokes)", key);
            goto done;
        }
    if (!json_object_get(body, "strokes")) {
        rc = api_reject(e, GLINT_EINVAL, "invalid-input",
                        "strokes: missing (an array of strokes)");
        goto done;
    }
    rc = stroke_list_from_json(json_object_get(body, "strokes"), &lim, list, n, e);
    if (rc == GLINT_ERANGE) {
        rc = api_reject(e, GLINT_ETOOBIG, "too-many-strokes",
                        "%.300s (limits: max_strokes %d per request, glintd --max-strokes; "
                        "max_stroke_points %d per stroke)",
                        e->msg, lim.max_strokes, lim.max_points);
        goto done;
    }
    if (rc) {
        if (rc != GLINT_ENOMEM)
            glint_err_kind(e, rc == GLINT_ENONFINITE ? "non-finite" : "invalid-stroke");
        goto done;
    }
    /* the parsed body goes before its canonical copy is made: one tree of
     * the request at a time (what api_body_json admitted) */
    json_decref(body);
    body = NULL;
    *canon = json_array();
    for (int i = 0; i < *n && !rc; i++) {
        json_t *j = stroke_to_json(&(*list)[i]);
        if (!j || json_array_append_new(*canon, j))
            rc = glint_err_set(e, GLINT_ENOMEM, "out of memory");
    }
done:
    json_decref(body);
    return rc;
}

/* How long a stroke request tries again while another replica keeps
 * changing its view (seconds), before it answers 409. */
#define STROKES_RETRY_S 15.0

static http_resp strokes_post(http_req *req)
{
    app *a = req->app;
    json_t *sdoc = NULL, *scene_doc = NULL, *canon = NULL;
    stroke *list = NULL;
    int n = 0, k, w, h, ps, rc, need_base = 0, locked = 0, attempts = 0;
    img cur = {0}, base = {0};
    void *exr = NULL, *prev = NULL;
    size_t len = 0, prev_len = 0;
    stroke_report box;
    int64_t first = 0, last = 0, version = 0;
    long pixels = 0;
    const char *scene_id;
    glint_err e;
    http_resp r = {0, NULL};
    double t0 = glint_now(), t_first = t0;

    if ((rc = api_session(req, req->param[0], 1, &sdoc, &e)) ||
        (rc = session_view(req, sdoc, &scene_doc, &k, &w, &h, &ps, &e)))
        goto done;
    t0 = srv_timing_step(&req->timing, "session", t0);
    if ((rc = strokes_parse(req, &list, &n, &canon, &e)))
        goto done;
    t0 = srv_timing_step(&req->timing, "parse", t0);
    par_warm(); /* the encode's workers wake while the brush runs */
    for (int i = 0; i < n; i++)
        need_base |= list[i].mode == STROKE_ERASE;
    {
        /* bound the work before taking the session's lock */
        double cost = stroke_list_cost(list, n, w, h);
        if (cost > a->cfg.lim.max_stroke_work) {
            rc = api_reject(&e, GLINT_ETOOBIG, "too-much-brush-work",
                            "these strokes need %.3g brush evaluations (points times the pixels "
                            "their diameter covers), over the limit of %.3g per request "
                            "(max_stroke_work, glintd --max-stroke-work %.0f): send fewer points "
                            "or a smaller diameter, or split the request",
                            cost, a->cfg.lim.max_stroke_work, a->cfg.lim.max_stroke_work / 1e6);
            goto done;
        }
    }
    scene_id = json_string_value(json_object_get(sdoc, "scene_id"));

    pthread_mutex_lock(session_lock(req->param[0]));
    locked = 1;
    t0 = srv_timing_step(&req->timing, "lock", t0);
again:
    if ((rc = view_current(a, req->param[0], scene_id, k, ps, &cur, &version, &prev, &prev_len,
                           &e))) {
        glint_err_prefix(&e, "reading the view's image");
        goto done;
    }
    t0 = srv_timing_step(&req->timing, "read", t0);
    /* the image is the painting's size, or the raster's where a painting of
     * that size was uploaded: strokes are in its pixels either way */
    if ((cur.width != w || cur.height != h) && (cur.width != w / ps || cur.height != h / ps)) {
        rc = glint_err_set(&e, GLINT_EINTERNAL, "the stored image of view %d is %dx%d, not %dx%d",
                           k, cur.width, cur.height, w, h);
        goto done;
    }
    if (need_base &&
        (rc = scenes_base(a, scene_id, k, cur.width == w ? ps : 1, &base, &e))) {
        glint_err_prefix(&e, "base render");
        goto done;
    }
    if ((rc = stroke_apply_list(list, n, &cur, need_base ? &base : NULL, &box, &e))) {
        if (rc != GLINT_ENOMEM) {
            char msg[GLINT_ERR_MSG_MAX];
            snprintf(msg, sizeof msg, "%.400s (nothing was applied)", e.msg);
            api_reject(&e, rc, rc == GLINT_ENONFINITE ? "non-finite" : "invalid-stroke", "%s",
                       msg);
        }
        goto done;
    }
    pixels = box.pixels;
    t0 = srv_timing_step(&req->timing, "apply", t0);
    /* the stored file's blocks of 16 lines the strokes missed are used
     * again: the encode's cost is the lines they changed */
    if ((rc = img_write_exr_mem_reusing(&cur, prev, prev_len, box.y0, box.y1, &exr, &len, NULL,
                                        &e))) {
        glint_err_prefix(&e, "storing the strokes");
        goto done;
    }
    t0 = srv_timing_step(&req->timing, "encode", t0);
    /* this process's lock serializes its own writers; another replica on
     * the same database may still have painted the view since it was read:
     * then the strokes go onto the new image */
    if ((rc = store_strokes_append_at(a->store, req->param[0], k, version, canon, exr, len,
                                      &first, &last, &version, &e))) {
        if (rc == GLINT_ECONFLICT && glint_now() - t_first < STROKES_RETRY_S) {
            /* back off a random while (up to 2^attempts ms, at most 64), so
             * two replicas that keep colliding fall out of step */
            unsigned span = 1u << (attempts < 6 ? attempts : 6);
            unsigned jitter = (unsigned)((glint_now() - t_first) * 1e9) ^ (unsigned)attempts;
            attempts++;
            free(exr);
            exr = NULL;
            free(prev);
            prev = NULL;
            img_free(&cur);
            img_free(&base);
            usleep(1000u * (jitter % (span + 1)));
            goto again;
        }
        glint_err_prefix(&e, "storing the strokes");
        goto done;
    }
    t0 = srv_timing_step(&req->timing, "store", t0);
    pthread_mutex_unlock(session_lock(req->param[0]));
    locked = 0;
    /* the memo keeps the decoded image, so a fit need not decode it */
    memo_painting_offer(a->memo, req->param[0], k, (long long)version, &cur);
    fitsvc_painting_stored(a->fits, req->param[0], k, (long long)version);
    events_notify(a->events, req->param[0]);
    r = http_json(200, json_pack("{s:i, s:I, s:I, s:I, s:i, s:I}", "view", k, "first_seq",
                                 (json_int_t)first, "last_seq", (json_int_t)last, "version",
                                 (json_int_t)version, "strokes", n, "pixels",
                                 (json_int_t)pixels));
done:
    if (locked)
        pthread_mutex_unlock(session_lock(req->param[0]));
    if (rc)
        r = api_error(&e);
    free(exr);
    free(prev);
    img_free(&cur);
    img_free(&base);
    stroke_list_free(list, n);
    json_decref(canon);
    json_decref(scene_doc);
    json_decref(sdoc);
    return r;
}

static http_resp strokes_get(http_req *req)
{
    app *a = req->app;
    json_t *sdoc = NULL, *arr = NULL;
    const char *since_q = http_query(req, "since"), *limit_q = http_query(req, "limit");
    long long since = 0, limit = STROKES_PAGE_DEFAULT;
    int64_t last = 0;
    int more = 0;
    glint_err e;

    if (since_q && api_parse_count(since_q, &since))
        return http_problem(422, "invalid-input",
                            "since \"%.32s\" is not a whole number >= 0 (a sequence number)",
                            since_q);
    if (limit_q && (api_parse_count(limit_q, &limit) || limit < 1 || limit > STROKES_PAGE_MAX))
        return http_problem(422, "invalid-input", "limit \"%.32s\" is not a whole number in 1..%d",
                            limit_q, STROKES_PAGE_MAX);
    if (api_session(req, req->param[0], 0, &sdoc, &e))
        return api_error(&e);
    json_decref(sdoc);
    if (store_strokes_page(a->store, req->param[0], since, (int)limit, STROKES_PAGE_BYTES, &arr,
                           &more, &last, &e))
        return api_fail(&e, "strokes");
    return http_json(200, json_pack("{s:o, s:I, s:b}", "strokes", arr, "last_seq",
                                    (json_int_t)last, "more", more));
}

/* ---- events ----------------------------------------------------------------------------- */

/* events_check_fn of a session's stream (ctx: the app): whether the token
 * it was opened with still grants reading the session. */
static int stream_token_check(void *ctx, const char *session, const char *token,
                              time_t *expires)
{
    app *a = ctx;
    json_t *doc = NULL;
    int rc = store_session_get(a->store, session, &doc, NULL);
    if (rc)
        return rc;
    rc = auth_token_current(doc, token, time(NULL), expires) ? 0 : GLINT_EDENIED;
    json_decref(doc);
    return rc;
}

static http_resp events_get(http_req *req)
{
    app *a = req->app;
    json_t *sdoc = NULL;
    const char *since_q = http_query(req, "since");
    const char *last_id = http_header_in(req, "Last-Event-ID");
    events_access acc = {0};
    long long since = 0;
    glint_err e;

    /* a reconnecting EventSource sends Last-Event-ID: it wins over ?since */
    if (last_id && *last_id) {
        if (api_parse_count(last_id, &since))
            return http_problem(422, "invalid-input",
                                "Last-Event-ID \"%.32s\" is not a sequence number", last_id);
    } else if (since_q && api_parse_count(since_q, &since)) {
        return http_problem(422, "invalid-input",
                            "since \"%.32s\" is not a whole number >= 0 (a sequence number)",
                            since_q);
    }
    if (api_session(req, req->param[0], 0, &sdoc, &e))
        return api_error(&e);
    json_decref(sdoc);
    /* admitted by a token (not the API key): the stream lasts as long as it */
    if (!auth_has_key(req)) {
        acc.token = auth_token_given(req);
        acc.check = stream_token_check;
        acc.ctx = a;
    }
    return events_stream(a->events, req, req->param[0], since, http_query(req, "name"), &acc);
}

const http_route api_sessions_routes[] = {
    {"POST", "/api/v1/sessions", session_create},
    {"GET", "/api/v1/sessions/{id}", session_get},
    {"PUT", "/api/v1/sessions/{id}/views/{k}/painting", painting_put},
    {"GET", "/api/v1/sessions/{id}/views/{k}/painting", painting_get},
    {"POST", "/api/v1/sessions/{id}/views/{k}/strokes", strokes_post},
    {"GET", "/api/v1/sessions/{id}/strokes", strokes_get},
    {"GET", "/api/v1/sessions/{id}/events", events_get},
};
const int api_sessions_nroutes = sizeof api_sessions_routes / sizeof api_sessions_routes[0];
