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
 * the base render), in order, with core/stroke.h's brush; erase strokes
 * bring back the base render.  Strokes and the painting they produce are
 * stored in one transaction before the answer (store.h), and each stroke
 * takes the session's next sequence number.  Writes to one session are
 * serialized here (a striped lock), so two requests never paint over the
 * same starting image. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api_common.h"
#include "app.h"
#include "auth.h"
#include "events.h"
#include "fitsvc.h"
#include "img.h"
#include "store.h"
#include "stroke.h"

#define SESSION_STRIPES 64
#define STROKES_PAGE_DEFAULT 1000
#define STROKES_PAGE_MAX 10000

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

/* A non-negative decimal integer (at most 18 digits). */
static int api_parse_count(const char *text, long long *out)
{
    long long v = 0;
    if (!text || !*text || strlen(text) > 18)
        return -1;
    for (const char *c = text; *c; c++) {
        if (*c < '0' || *c > '9')
            return -1;
        v = 10 * v + (*c - '0');
    }
    *out = v;
    return 0;
}

/* The session in the path, checked for access.  OUT: *doc (decref). */
static http_resp session_load(http_req *req, int need_paint, json_t **doc)
{
    app *a = req->app;
    http_resp deny;
    glint_err e;
    *doc = NULL;
    if (store_session_get(a->store, req->param[0], doc, &e))
        return api_fail(&e, "session");
    if (auth_session(req, *doc, need_paint, &deny)) {
        json_decref(*doc);
        *doc = NULL;
        return deny;
    }
    return (http_resp){0, NULL};
}

/* The session's scene doc and the view index of the path.  OUT: *scene_doc,
 * *k, *w, *h. */
static http_resp session_view(http_req *req, const json_t *sdoc, json_t **scene_doc, int *k,
                              int *w, int *h)
{
    app *a = req->app;
    const char *scene_id = json_string_value(json_object_get(sdoc, "scene_id"));
    glint_err e;
    long long v;
    int n;

    *scene_doc = NULL;
    if (store_scene_get(a->store, scene_id, scene_doc, &e)) {
        if (e.code == GLINT_ENOTFOUND)
            return http_problem(404, "not-found", "the scene of session %s no longer exists",
                                req->param[0]);
        return api_fail(&e, "scene");
    }
    n = (int)json_array_size(json_object_get(*scene_doc, "views"));
    if (api_parse_count(req->param[1], &v) || v >= n) {
        json_decref(*scene_doc);
        *scene_doc = NULL;
        return http_problem(404, "not-found", "session %s has no view \"%.16s\" (views 0..%d)",
                            req->param[0], req->param[1], n - 1);
    }
    *k = (int)v;
    *w = (int)json_integer_value(json_object_get(*scene_doc, "width"));
    *h = (int)json_integer_value(json_object_get(*scene_doc, "height"));
    return (http_resp){0, NULL};
}

/* Any decoded image as float RGB (grey replicated, alpha dropped). */
static int to_rgb(img *im, glint_err *e)
{
    img out;
    size_t n = (size_t)im->width * (size_t)im->height;
    int c = im->channels, rc;
    if (c == 3)
        return 0;
    if ((rc = img_alloc(&out, im->width, im->height, 3, e)))
        return rc;
    for (size_t p = 0; p < n; p++)
        for (int ch = 0; ch < 3; ch++)
            out.px[3 * p + (size_t)ch] = im->px[(size_t)c * p + (size_t)(c >= 3 ? ch : 0)];
    img_free(im);
    *im = out;
    return 0;
}

/* The current image of a view: its painting, or the base render.  OUT:
 * *im (RGB), *version (0 for the base). */
static int view_current(app *a, const char *session, const char *scene_id, int k, img *im,
                        int64_t *version, glint_err *e)
{
    void *exr = NULL;
    size_t len = 0;
    int rc = store_painting_get(a->store, session, k, &exr, &len, version, e);
    memset(im, 0, sizeof *im);
    if (rc == GLINT_ENOTFOUND) {
        *version = 0;
        return store_scene_base(a->store, scene_id, k, im, e);
    }
    if (rc)
        return rc;
    rc = img_read_mem(exr, len, im, e);
    free(exr);
    if (!rc)
        rc = to_rgb(im, e);
    if (rc)
        glint_err_prefix(e, "stored painting of view %d", k);
    return rc;
}

/* ---- sessions --------------------------------------------------------------------- */

/* The public form of a session for the access granted. */
static json_t *session_public(app *a, const json_t *doc, int paint)
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
    if (a && store_paintings_list(a->store, id, &paintings, &e) == 0)
        json_object_set_new(o, "paintings", paintings);
    return o;
}

static http_resp session_create(http_req *req)
{
    app *a = req->app;
    http_resp deny, fail;
    json_t *body, *doc, *jscene, *scene_doc = NULL;
    const char *k;
    json_t *v;
    char id[33], pt[33], vt[33], now[32];
    glint_err e;

    if (auth_require_key(req, &deny))
        return deny;
    if (req->body_too_large)
        return api_body_too_large(req, "the session request");
    body = http_body_json(req, &fail);
    if (!body)
        return fail;
    json_object_foreach(body, k, v)
        if (strcmp(k, "scene_id") != 0) {
            fail = http_problem(422, "invalid-input", "unknown key \"%.64s\" (known: scene_id)", k);
            json_decref(body);
            return fail;
        }
    jscene = json_object_get(body, "scene_id");
    if (!json_is_string(jscene)) {
        fail = http_problem(422, "invalid-input", "scene_id: %s",
                            jscene ? "expected a string (a scene's id)" : "missing");
        json_decref(body);
        return fail;
    }
    if (store_scene_get(a->store, json_string_value(jscene), &scene_doc, &e)) {
        fail = e.code == GLINT_ENOTFOUND
                   ? http_problem(422, "unknown-scene", "scene_id: %s", e.msg)
                   : api_fail(&e, "scene");
        json_decref(body);
        return fail;
    }
    json_decref(scene_doc);
    if (store_new_id(id, &e) || store_new_id(pt, &e) || store_new_id(vt, &e)) {
        json_decref(body);
        return api_fail(&e, "creating a session");
    }
    store_now(now);
    doc = json_pack("{s:s, s:O, s:s, s:s, s:s}", "id", id, "scene_id", jscene, "paint_token", pt,
                    "view_token", vt, "created", now);
    json_decref(body);
    if (!doc)
        return http_problem(500, NULL, "out of memory");
    if (store_session_put(a->store, id, doc, &e)) {
        json_decref(doc);
        return e.code == GLINT_ENOTFOUND ? http_problem(422, "unknown-scene", "scene_id: %s", e.msg)
                                         : api_fail(&e, "storing the session");
    }
    json_object_set_new(doc, "last_seq", json_integer(0));
    {
        char loc[96];
        http_resp r;
        json_t *pub = session_public(a, doc, 1);
        json_decref(doc);
        snprintf(loc, sizeof loc, "/api/v1/sessions/%s", id);
        r = http_json(201, pub);
        http_header(&r, "Location", loc);
        return r;
    }
}

static http_resp session_get(http_req *req)
{
    app *a = req->app;
    json_t *doc;
    http_resp r = session_load(req, 0, &doc);
    http_resp probe = {0, NULL};
    int paint;
    if (r.r)
        return r;
    /* paint access: ask auth whether this request could write */
    paint = auth_session(req, doc, 1, &probe) == 0;
    if (!paint && probe.r)
        MHD_destroy_response(probe.r);
    r = http_json(200, session_public(a, doc, paint));
    json_decref(doc);
    return r;
}

/* ---- paintings ---------------------------------------------------------------------- */

static http_resp painting_put(http_req *req)
{
    app *a = req->app;
    json_t *sdoc = NULL, *scene_doc = NULL;
    http_resp r;
    img im;
    void *exr = NULL;
    size_t len = 0;
    int64_t version = 0, seq = 0;
    glint_err e;
    int k, w, h, rc;

    memset(&im, 0, sizeof im);
    r = session_load(req, 1, &sdoc);
    if (r.r)
        return r;
    r = session_view(req, sdoc, &scene_doc, &k, &w, &h);
    if (r.r)
        goto done;
    if (req->body_too_large) {
        r = api_body_too_large(req, "the painting");
        goto done;
    }
    if (req->body_len == 0) {
        r = http_problem(400, "empty-body",
                         "the body must be the painting: PNG, JPEG or OpenEXR bytes, %dx%d", w, h);
        goto done;
    }
    rc = img_read_mem(req->body, req->body_len, &im, &e);
    if (rc == GLINT_ENONFINITE) {
        r = http_problem(422, "non-finite", "the painting has non-finite pixels: %s", e.msg);
        goto done;
    } else if (rc == GLINT_ENOMEM) {
        r = api_fail(&e, "decoding the painting");
        goto done;
    } else if (rc) {
        r = http_problem(422, "invalid-image",
                         "the body is not a readable PNG, JPEG or OpenEXR image: %s", e.msg);
        goto done;
    }
    if (im.width > a->cfg.lim.max_image_dim || im.height > a->cfg.lim.max_image_dim) {
        r = http_problem(413, "image-too-large",
                         "the painting is %dx%d, beyond the limit of %d pixels a side "
                         "(max_image_dim, glintd --max-image-dim); this view expects %dx%d",
                         im.width, im.height, a->cfg.lim.max_image_dim, w, h);
        goto done;
    }
    if (im.width != w || im.height != h) {
        r = http_problem(422, "wrong-size",
                         "the painting is %dx%d; view %d of this scene expects exactly %dx%d "
                         "(the scene's raster size)",
                         im.width, im.height, k, w, h);
        goto done;
    }
    if ((rc = to_rgb(&im, &e)) || (rc = img_check_finite(&im, &e)) ||
        (rc = img_write_mem("exr", &im, &exr, &len, &e))) {
        r = rc == GLINT_ENONFINITE
                ? http_problem(422, "non-finite", "the painting has non-finite pixels: %s", e.msg)
                : api_fail(&e, "encoding the painting");
        goto done;
    }
    pthread_mutex_lock(session_lock(req->param[0]));
    {
        /* Conditional replace: If-Match names the painting version the client
         * built its image from ("0" for a view never painted).  Checked under
         * the session lock, so no stroke can slip in between. */
        const char *im_hdr = http_header_in(req, "If-Match");
        if (im_hdr) {
            char *end;
            long long want = strtoll(im_hdr + (im_hdr[0] == '"'), &end, 10);
            int64_t cur = 0;
            json_t *list = NULL;
            if (end == im_hdr + (im_hdr[0] == '"') || want < 0) {
                pthread_mutex_unlock(session_lock(req->param[0]));
                r = http_problem(400, "bad-if-match",
                                 "If-Match must be a painting version (a whole number), got '%s'",
                                 im_hdr);
                goto done;
            }
            if (store_paintings_list(a->store, req->param[0], &list, &e) == 0) {
                size_t i;
                json_t *it;
                json_array_foreach(list, i, it) {
                    if (json_integer_value(json_object_get(it, "view")) == k)
                        cur = json_integer_value(json_object_get(it, "version"));
                }
                json_decref(list);
            }
            if (cur != want) {
                pthread_mutex_unlock(session_lock(req->param[0]));
                r = http_problem(412, "painting-changed",
                                 "view %d is at painting version %lld, not %lld (If-Match): "
                                 "someone changed it; read it again", k, (long long)cur, want);
                goto done;
            }
        }
    }
    rc = store_painting_put(a->store, req->param[0], k, exr, len, &version, &seq, &e);
    pthread_mutex_unlock(session_lock(req->param[0]));
    if (rc) {
        r = api_fail(&e, "storing the painting");
        goto done;
    }
    fitsvc_painting_offer(a->fits, req->param[0], k, (long long)version, &im);
    events_notify(a->events, req->param[0]);
    r = http_json(200, json_pack("{s:i, s:I, s:I}", "view", k, "version", (json_int_t)version,
                                 "seq", (json_int_t)seq));
done:
    free(exr);
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
    http_resp r;
    void *exr = NULL, *data = NULL;
    size_t len = 0;
    int64_t version = 0;
    char vbuf[32];
    glint_err e;
    img im;
    int k, w, h, rc;

    memset(&im, 0, sizeof im);
    if (!fmt)
        fmt = "png";
    if (strcmp(fmt, "png") && strcmp(fmt, "exr"))
        return http_problem(422, "invalid-input", "format \"%.16s\" is not png or exr", fmt);
    r = session_load(req, 0, &sdoc);
    if (r.r)
        return r;
    r = session_view(req, sdoc, &scene_doc, &k, &w, &h);
    if (r.r)
        goto done;
    rc = store_painting_get(a->store, req->param[0], k, &exr, &len, &version, &e);
    if (rc == 0 && strcmp(fmt, "exr") == 0) {
        r = http_bytes_owned(200, "image/x-exr", exr, len);
        exr = NULL;
    } else if (rc == 0 || rc == GLINT_ENOTFOUND) {
        const char *scene_id = json_string_value(json_object_get(sdoc, "scene_id"));
        rc = rc == 0 ? img_read_mem(exr, len, &im, &e)
                     : store_scene_base(a->store, scene_id, k, &im, &e);
        if (rc || (rc = img_write_mem(fmt, &im, &data, &len, &e))) {
            r = api_fail(&e, "painting");
            goto done;
        }
        r = http_bytes_owned(200, strcmp(fmt, "exr") ? "image/png" : "image/x-exr", data, len);
    } else {
        r = api_fail(&e, "painting");
        goto done;
    }
    snprintf(vbuf, sizeof vbuf, "%lld", (long long)version);
    http_header(&r, "X-Glint-Painted", version > 0 ? "1" : "0");
    http_header(&r, "X-Glint-Version", vbuf);
    http_header(&r, "Cache-Control", "no-store");
done:
    free(exr);
    img_free(&im);
    json_decref(scene_doc);
    json_decref(sdoc);
    return r;
}

/* ---- strokes ------------------------------------------------------------------------ */

static http_resp strokes_post(http_req *req)
{
    app *a = req->app;
    json_t *sdoc = NULL, *scene_doc = NULL, *body = NULL, *canon = NULL;
    stroke *list = NULL;
    int n = 0, k, w, h, rc, need_base = 0, locked = 0;
    stroke_limits lim = {a->cfg.lim.max_strokes, a->cfg.lim.max_stroke_points};
    img cur, base;
    void *exr = NULL;
    size_t len = 0;
    int64_t first = 0, last = 0, version = 0;
    long pixels = 0;
    const char *scene_id;
    glint_err e;
    http_resp r;

    memset(&cur, 0, sizeof cur);
    memset(&base, 0, sizeof base);
    r = session_load(req, 1, &sdoc);
    if (r.r)
        return r;
    r = session_view(req, sdoc, &scene_doc, &k, &w, &h);
    if (r.r)
        goto done;
    if (req->body_too_large) {
        r = api_body_too_large(req, "the strokes");
        goto done;
    }
    body = http_body_json(req, &r);
    if (!body)
        goto done;
    r.r = NULL;
    {
        const char *key;
        json_t *v;
        json_object_foreach(body, key, v)
            if (strcmp(key, "strokes") != 0) {
                r = http_problem(422, "invalid-input", "unknown key \"%.64s\" (known: strokes)",
                                 key);
                goto done;
            }
    }
    if (!json_object_get(body, "strokes")) {
        r = http_problem(422, "invalid-input", "strokes: missing (an array of strokes)");
        goto done;
    }
    rc = stroke_list_from_json(json_object_get(body, "strokes"), &lim, &list, &n, &e);
    if (rc == GLINT_ERANGE) {
        r = http_problem(413, "too-many-strokes",
                         "%s (limits: max_strokes %d per request, glintd --max-strokes; "
                         "max_stroke_points %d per stroke)",
                         e.msg, lim.max_strokes, lim.max_points);
        goto done;
    } else if (rc) {
        r = http_problem(rc == GLINT_ENOMEM ? 500 : 422,
                         rc == GLINT_ENONFINITE ? "non-finite" : "invalid-stroke", "%s", e.msg);
        goto done;
    }
    canon = json_array();
    for (int i = 0; i < n; i++) {
        json_t *j = stroke_to_json(&list[i]);
        if (!j || json_array_append_new(canon, j)) {
            r = http_problem(500, NULL, "out of memory");
            goto done;
        }
        need_base |= list[i].mode == STROKE_ERASE;
    }
    scene_id = json_string_value(json_object_get(sdoc, "scene_id"));

    pthread_mutex_lock(session_lock(req->param[0]));
    locked = 1;
    if ((rc = view_current(a, req->param[0], scene_id, k, &cur, &version, &e))) {
        r = api_fail(&e, "reading the view's image");
        goto done;
    }
    if (need_base && (rc = store_scene_base(a->store, scene_id, k, &base, &e))) {
        r = api_fail(&e, "base render");
        goto done;
    }
    if (cur.width != w || cur.height != h) {
        r = http_problem(500, NULL, "the stored image of view %d is %dx%d, not %dx%d", k,
                         cur.width, cur.height, w, h);
        goto done;
    }
    rc = stroke_apply_list(list, n, &cur, need_base ? &base : NULL, &pixels, &e);
    if (rc) {
        r = http_problem(rc == GLINT_ENOMEM ? 500 : 422,
                         rc == GLINT_ENONFINITE ? "non-finite" : "invalid-stroke",
                         "%s (nothing was applied)", e.msg);
        goto done;
    }
    if ((rc = img_write_mem("exr", &cur, &exr, &len, &e)) ||
        (rc = store_strokes_append(a->store, req->param[0], k, canon, exr, len, &first, &last,
                                   &version, &e))) {
        r = api_fail(&e, "storing the strokes");
        goto done;
    }
    pthread_mutex_unlock(session_lock(req->param[0]));
    locked = 0;
    /* the fit service keeps the decoded image, so a fit need not decode it */
    fitsvc_painting_offer(a->fits, req->param[0], k, (long long)version, &cur);
    events_notify(a->events, req->param[0]);
    r = http_json(200, json_pack("{s:i, s:I, s:I, s:I, s:i, s:I}", "view", k, "first_seq",
                                 (json_int_t)first, "last_seq", (json_int_t)last, "version",
                                 (json_int_t)version, "strokes", n, "pixels",
                                 (json_int_t)pixels));
done:
    if (locked)
        pthread_mutex_unlock(session_lock(req->param[0]));
    free(exr);
    img_free(&cur);
    img_free(&base);
    stroke_list_free(list, n);
    json_decref(canon);
    json_decref(body);
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
    http_resp r;

    if (since_q && api_parse_count(since_q, &since))
        return http_problem(422, "invalid-input",
                            "since \"%.32s\" is not a whole number >= 0 (a sequence number)",
                            since_q);
    if (limit_q && (api_parse_count(limit_q, &limit) || limit < 1 || limit > STROKES_PAGE_MAX))
        return http_problem(422, "invalid-input", "limit \"%.32s\" is not a whole number in 1..%d",
                            limit_q, STROKES_PAGE_MAX);
    r = session_load(req, 0, &sdoc);
    if (r.r)
        return r;
    json_decref(sdoc);
    if (store_strokes_page(a->store, req->param[0], since, (int)limit, &arr, &more, &last, &e))
        return api_fail(&e, "strokes");
    return http_json(200, json_pack("{s:o, s:I, s:b}", "strokes", arr, "last_seq",
                                    (json_int_t)last, "more", more));
}

/* ---- events ----------------------------------------------------------------------------- */

static http_resp events_get(http_req *req)
{
    app *a = req->app;
    json_t *sdoc = NULL;
    const char *since_q = http_query(req, "since");
    const char *last_id = http_header_in(req, "Last-Event-ID");
    long long since = 0;
    http_resp r;

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
    r = session_load(req, 0, &sdoc);
    if (r.r)
        return r;
    json_decref(sdoc);
    return events_stream(a->events, req, req->param[0], since, http_query(req, "name"));
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
