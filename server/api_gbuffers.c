/* api_gbuffers.c: G-buffer sets, fits of G-buffers and paintings made
 * elsewhere (proto/openapi.yaml, "G-buffer sets").  Creating one needs the
 * API key (when glintd has one); a set belongs to the owner key it was
 * created with (X-Glint-Owner, or one made and answered once: auth.h), and
 * every other route, the set's materials and jobs included, needs that
 * owner key or the API key.
 *
 *   POST   /api/v1/gbuffer-sets                         {"views", "width", "height"}
 *   GET    /api/v1/gbuffer-sets/{id}                    the set and what each view holds
 *   DELETE /api/v1/gbuffer-sets/{id}                    the set and its materials
 *   PUT    /api/v1/gbuffer-sets/{id}/views/{k}/gbuffer.exr  OpenEXR, named channels
 *   PUT    /api/v1/gbuffer-sets/{id}/views/{k}/painting     PNG, JPEG, OpenEXR or HDR, RGB
 *   POST   /api/v1/gbuffer-sets/{id}/fits               {"method", "params"}: 201 material,
 *                                                       or 202 job
 *   GET    /api/v1/gbuffer-sets/{id}/materials          the set's materials
 *
 * A set lives in the store's blobs (durable once answered, like paintings):
 * gbuffer-sets/<id>/set.json (its record, written first and deleted
 * first), gbuffer<k>.exr and gbuffer<k>.json (the upload as it came, and
 * what was found in it), painting<k> (as it came); the record holds the
 * owner key ("owner", never answered but once).  Uploads are decoded and
 * checked before they are kept (size, the set's raster, channels, finite
 * values); a fit decodes the painted views again (core gbfit.h makes the
 * samples and values, with the method's rule: point-light methods need
 * wi), and fitsvc runs it.  Writes to one set are serialized with its
 * deletion (striped locks). */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "api_common.h"
#include "app.h"
#include "auth.h"
#include "clock.h"
#include "fitsvc.h"
#include "gbfit.h"
#include "ids.h"
#include "method.h"
#include "store.h"
#include "upload_gate.h"

/* Channels of an uploaded G-buffer: glint's own have 17; a renderer's AOV
 * file may carry a few more.  Bounds the decode's memory with its sides. */
#define GB_MAX_CHANNELS 32
/* Bytes a decoded pixel of one view can take while a set is fitted: the
 * G-buffer (57), the painting (12 decoded + 12 RGB), the samples and values
 * (about 120 where every pixel is one). */
#define GB_FIT_PIXEL_BYTES 200

#define GB_STRIPES 16
static pthread_mutex_t gb_stripes[GB_STRIPES];
static pthread_once_t gb_stripes_once = PTHREAD_ONCE_INIT;

static void gb_stripes_init(void)
{
    for (int i = 0; i < GB_STRIPES; i++)
        pthread_mutex_init(&gb_stripes[i], NULL);
}

static pthread_mutex_t *gb_lock(const char *id)
{
    unsigned h = 0;
    pthread_once(&gb_stripes_once, gb_stripes_init);
    for (const char *c = id; *c; c++)
        h = h * 31u + (unsigned char)*c;
    return &gb_stripes[h % GB_STRIPES];
}

/* ---- the set's record ------------------------------------------------------------ */

static void gb_blob(char *buf, size_t len, const char *id, const char *file)
{
    snprintf(buf, len, "gbuffer-sets/%s/%s", id, file);
}

/* The set's record {"id", "views", "width", "height", "created"}.  OUT:
 * *doc.  GLINT_ENOTFOUND for unknown or malformed ids. */
static int gb_record(app *a, const char *id, json_t **doc, glint_err *e)
{
    char name[128];
    void *data = NULL;
    size_t len = 0;
    int rc;

    *doc = NULL;
    if (!glint_id_valid(id))
        return api_reject(e, GLINT_ENOTFOUND, "not-found", "no G-buffer set %.40s",
                          id ? id : "");
    gb_blob(name, sizeof name, id, "set.json");
    if ((rc = store_blob_get(a->store, name, &data, &len, e)))
        return rc == GLINT_ENOTFOUND
                   ? api_reject(e, rc, "not-found", "no G-buffer set %s", id)
                   : rc;
    *doc = json_loadb(data, len, 0, NULL);
    free(data);
    if (!json_is_object(*doc)) {
        json_decref(*doc);
        *doc = NULL;
        return glint_err_set(e, GLINT_EINTERNAL, "G-buffer set %s: unreadable record", id);
    }
    return 0;
}

int api_gbuffer_set_exists(app *a, const char *id)
{
    json_t *doc;
    glint_err e;
    if (gb_record(a, id, &doc, &e))
        return 0;
    json_decref(doc);
    return 1;
}

int api_gbuffer_set_access(http_req *req, const char *id, glint_err *err)
{
    json_t *doc;
    int rc;
    if ((rc = gb_record(req->app, id, &doc, err)))
        return rc;
    rc = auth_owner(req, doc, "G-buffer set", err);
    json_decref(doc);
    return rc;
}

/* The set `id` if the request may use it (its owner key or the API key).
 * OUT: *doc, *views, *w, *h. */
static int gb_open(http_req *req, const char *id, json_t **doc, int *views, int *w, int *h,
                   glint_err *e)
{
    int rc;
    *doc = NULL;
    if ((rc = gb_record(req->app, id, doc, e)))
        return rc;
    if ((rc = auth_owner(req, *doc, "G-buffer set", e))) {
        json_decref(*doc);
        *doc = NULL;
        return rc;
    }
    *views = (int)json_integer_value(json_object_get(*doc, "views"));
    *w = (int)json_integer_value(json_object_get(*doc, "width"));
    *h = (int)json_integer_value(json_object_get(*doc, "height"));
    return 0;
}

static json_t *gb_links(const char *id)
{
    char b[3][160];
    snprintf(b[0], sizeof b[0], "/api/v1/gbuffer-sets/%s", id);
    snprintf(b[1], sizeof b[1], "/api/v1/gbuffer-sets/%s/fits", id);
    snprintf(b[2], sizeof b[2], "/api/v1/gbuffer-sets/%s/materials", id);
    return json_pack("{s:s, s:s, s:s}", "self", b[0], "fits", b[1], "materials", b[2]);
}

/* The API's set object: the record, each view's state, links. */
static json_t *gb_public(app *a, const char *id, const json_t *rec)
{
    json_t *d = json_deep_copy(rec), *names = NULL, *views = json_array();
    int n = (int)json_integer_value(json_object_get(rec, "views"));
    char dir[128];

    json_object_del(d, "owner");
    snprintf(dir, sizeof dir, "gbuffer-sets/%s", id);
    if (store_blob_list(a->store, dir, &names, NULL))
        names = json_array();
    for (int k = 0; k < n; k++) {
        char gname[32], pname[32], info[32], blob[160];
        int has_g = 0, has_p = 0;
        size_t i;
        json_t *it, *v;
        snprintf(gname, sizeof gname, "gbuffer%d.exr", k);
        snprintf(info, sizeof info, "gbuffer%d.json", k);
        snprintf(pname, sizeof pname, "painting%d", k);
        json_array_foreach(names, i, it) {
            const char *s = json_string_value(it);
            has_g |= s && !strcmp(s, gname);
            has_p |= s && !strcmp(s, pname);
        }
        v = json_pack("{s:i, s:b, s:b}", "view", k, "gbuffer", has_g, "painting", has_p);
        if (has_g) {
            void *data = NULL;
            size_t len = 0;
            json_t *j;
            gb_blob(blob, sizeof blob, id, info);
            if (!store_blob_get(a->store, blob, &data, &len, NULL) &&
                (j = json_loadb(data, len, 0, NULL))) {
                json_object_update(v, j);
                json_decref(j);
            }
            free(data);
        }
        json_array_append_new(views, v);
    }
    json_decref(names);
    json_object_set_new(d, "view_state", views);
    json_object_set_new(d, "links", gb_links(id));
    return d;
}

/* ---- create, read, delete ------------------------------------------------------------ */

static int int_member(const json_t *body, const char *name, int lo, int hi, const char *why,
                      int *out, glint_err *e)
{
    json_t *v = json_object_get(body, name);
    if (!v)
        return api_reject(e, GLINT_EINVAL, "invalid-input", "%s is required (%d..%d)", name, lo,
                          hi);
    if (!json_is_integer(v) || json_integer_value(v) < lo || json_integer_value(v) > hi)
        return api_reject(e, GLINT_EINVAL, "invalid-input", "%s must be an integer in %d..%d%s", name, lo, hi,
                          why);
    *out = (int)json_integer_value(v);
    return 0;
}

static http_resp sets_create(http_req *req)
{
    app *a = req->app;
    json_t *body = NULL, *rec = NULL;
    const char *k;
    json_t *v, *pub;
    const char *owner;
    char id[GLINT_ID_LEN], created[GLINT_TIME_LEN], name[128], made[GLINT_ID_LEN];
    int views, w, h, rc, maxv = a->cfg.lim.max_views < SCENE_MAX_VIEWS ? a->cfg.lim.max_views
                                                                         : SCENE_MAX_VIEWS;
    int maxd = a->cfg.lim.max_image_dim < SCENE_MAX_SIZE ? a->cfg.lim.max_image_dim
                                                         : SCENE_MAX_SIZE;
    char *text = NULL;
    http_resp r;
    glint_err e;

    if ((rc = auth_require_key(req, &e)) || (rc = auth_owner_new(req, made, &owner, &e)) ||
        (rc = api_body_json(req, &body, &e)))
        goto done;
    json_object_foreach(body, k, v) {
        if (strcmp(k, "views") && strcmp(k, "width") && strcmp(k, "height")) {
            rc = api_reject(&e, GLINT_EINVAL, "invalid-input",
                            "unknown member '%.64s' (a G-buffer set takes \"views\", \"width\" "
                            "and \"height\")", k);
            goto done;
        }
    }
    if ((rc = int_member(body, "views", 1, maxv, " (max_views, glintd --max-views)", &views,
                         &e)) ||
        (rc = int_member(body, "width", SCENE_MIN_SIZE, maxd,
                         " (max_image_dim, glintd --max-image-dim)", &w, &e)) ||
        (rc = int_member(body, "height", SCENE_MIN_SIZE, maxd,
                         " (max_image_dim, glintd --max-image-dim)", &h, &e)) ||
        (rc = glint_id_new(id, &e)))
        goto done;
    glint_time_iso(time(NULL), created);
    rec = json_pack("{s:s, s:i, s:i, s:i, s:s, s:s}", "id", id, "views", views, "width", w,
                    "height", h, "created", created, "owner", owner);
    if (!rec || !(text = json_dumps(rec, JSON_COMPACT))) {
        rc = glint_err_set(&e, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    gb_blob(name, sizeof name, id, "set.json");
    if ((rc = store_blob_put(a->store, name, text, strlen(text), &e)))
        goto done;
    /* the one answer that carries the owner key */
    if ((pub = gb_public(a, id, rec)))
        json_object_set_new(pub, "owner_key", json_string(owner));
    r = api_created(pub, "gbuffer-sets", id);
done:
    if (rc)
        r = api_error(&e);
    free(text);
    json_decref(rec);
    json_decref(body);
    return r;
}

static http_resp sets_get(http_req *req)
{
    json_t *rec;
    glint_err e;
    int n, w, h;
    http_resp r;
    if (gb_open(req, req->param[0], &rec, &n, &w, &h, &e))
        return api_error(&e);
    r = http_json(200, gb_public(req->app, req->param[0], rec));
    json_decref(rec);
    return r;
}

static http_resp sets_delete(http_req *req)
{
    app *a = req->app;
    const char *id = req->param[0];
    json_t *rec = NULL;
    char name[160], dir[128];
    glint_err e;
    int n, w, h, rc;

    if ((rc = gb_open(req, id, &rec, &n, &w, &h, &e)))
        return api_error(&e);
    json_decref(rec);
    pthread_mutex_lock(gb_lock(id));
    /* its materials first (only the set's owner could read them): a crash
     * after leaves the set without them, never materials without their set */
    rc = store_materials_delete(a->store, id, &e);
    gb_blob(name, sizeof name, id, "set.json"); /* then: the set is gone from here on */
    if (!rc)
        rc = store_blob_delete(a->store, name, &e);
    snprintf(dir, sizeof dir, "gbuffer-sets/%s", id);
    if (!rc) /* what a crash leaves of it is swept when the store opens */
        store_blob_rmtree(a->store, dir);
    pthread_mutex_unlock(gb_lock(id));
    if (rc)
        return api_error(&e);
    return http_bytes(204, NULL, "", 0);
}

/* ---- uploads ------------------------------------------------------------------------- */

/* The view of an upload's path and the checks every upload shares. */
static int upload_start(http_req *req, const char *what, json_t **rec, int *k, int *w, int *h,
                        glint_err *e)
{
    app *a = req->app;
    int n;
    if (gb_open(req, req->param[0], rec, &n, w, h, e))
        return e->code;
    if (api_view_index(req->param[1], n, k))
        return api_reject(e, GLINT_ENOTFOUND, "not-found",
                          "view must be an integer in 0..%d (the set has %d views)", n - 1, n);
    if (req->body_too_large)
        return api_reject(e, GLINT_ETOOBIG, "body-too-large",
                          "the %s exceeds the request body limit of %zu bytes (max_body, "
                          "glintd --max-body-mb %zu)",
                          what, a->cfg.lim.max_body, a->cfg.lim.max_body >> 20);
    if (req->body_len == 0)
        return api_reject(e, GLINT_EINVAL, "empty-body", "the body must be the %s (%dx%d)", what,
                          *w, *h);
    return 0;
}

/* Store blobs of view k of set id under its lock, the set still there. */
static int upload_store(app *a, const char *id, const char *file, const void *data, size_t len,
                        const char *info_file, const char *info, glint_err *e)
{
    char name[160];
    int rc;
    pthread_mutex_lock(gb_lock(id));
    gb_blob(name, sizeof name, id, "set.json");
    {
        void *d = NULL;
        size_t l = 0;
        rc = store_blob_get(a->store, name, &d, &l, e);
        free(d);
    }
    if (rc == GLINT_ENOTFOUND)
        rc = api_reject(e, rc, "not-found", "the G-buffer set %s was deleted", id);
    gb_blob(name, sizeof name, id, file);
    if (!rc)
        rc = store_blob_put(a->store, name, data, len, e);
    gb_blob(name, sizeof name, id, info_file ? info_file : "");
    if (!rc && info_file)
        rc = store_blob_put(a->store, name, info, strlen(info), e);
    pthread_mutex_unlock(gb_lock(id));
    return rc;
}

static http_resp gbuffer_put(http_req *req)
{
    app *a = req->app;
    json_t *rec = NULL, *info = NULL;
    char file[32], ifile[32], *text = NULL;
    upload_gate gate;
    gbuf g = {0};
    http_resp r;
    glint_err e;
    int k, w, h, rc, uv = 0, wi = 0;

    upload_gate_init(&gate, a, "the image");
    if ((rc = upload_start(req, "G-buffer", &rec, &k, &w, &h, &e)))
        goto done;
    /* the header first: the set's size, and the decode's memory with the
     * G-buffer it makes (57 bytes a pixel) held in the work budget */
    upload_gate_size(&gate, w, h);
    snprintf(gate.expect, sizeof gate.expect, "this set's views are %dx%d", w, h);
    gate.max_channels = GB_MAX_CHANNELS;
    gate.invalid_kind = "invalid-gbuffer";
    gate.per_pixel = 64;
    rc = gbfit_gbuf_mem(NULL, req->body, req->body_len, 0, GB_MAX_CHANNELS, upload_gate_check,
                        &gate, "the G-buffer", &g, &uv, &wi, &e);
    if (rc == GLINT_ENOMEM || (rc && gate.refused))
        goto done;
    if (rc) {
        rc = api_reject(&e, rc == GLINT_ENONFINITE ? rc : GLINT_EINVAL,
                        rc == GLINT_ENONFINITE ? "non-finite" : "invalid-gbuffer",
                        "%.400s (an OpenEXR file with named float channels N.X N.Y N.Z, wo.X "
                        "wo.Y wo.Z, and wi.X wi.Y wi.Z for point-light methods; mask, P.X P.Y "
                        "P.Z, uv.U uv.V optional; at most %d channels, %dx%d)",
                        e.msg, GB_MAX_CHANNELS, w, h);
        goto done;
    }
    info = json_pack("{s:b, s:b, s:I, s:I, s:I}", "has_wi", wi, "has_uv", uv, "covered",
                     (json_int_t)gbuf_count(&g), "samples_lit",
                     (json_int_t)(wi ? samples_count_rule(&g, SAMPLES_LIT) : 0), "samples_seen",
                     (json_int_t)samples_count_rule(&g, SAMPLES_SEEN));
    if (!info || !(text = json_dumps(info, JSON_COMPACT))) {
        rc = glint_err_set(&e, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    snprintf(file, sizeof file, "gbuffer%d.exr", k);
    snprintf(ifile, sizeof ifile, "gbuffer%d.json", k);
    if ((rc = upload_store(a, req->param[0], file, req->body, req->body_len, ifile, text, &e)))
        goto done;
    json_object_set_new(info, "view", json_integer(k));
    r = http_json(200, info);
    info = NULL;
done:
    if (rc)
        r = api_error(&e);
    upload_gate_leave(&gate);
    gbuf_free(&g);
    free(text);
    json_decref(info);
    json_decref(rec);
    return r;
}

static http_resp painting_put(http_req *req)
{
    app *a = req->app;
    json_t *rec = NULL;
    char file[32];
    upload_gate gate;
    img im = {0};
    http_resp r;
    glint_err e;
    int k, w, h, rc;

    upload_gate_init(&gate, a, "the painting");
    if ((rc = upload_start(req, "painting", &rec, &k, &w, &h, &e)))
        goto done;
    upload_gate_size(&gate, w, h);
    snprintf(gate.expect, sizeof gate.expect, "this set's views are %dx%d", w, h);
    rc = img_read_mem_checked(req->body, req->body_len, 0, upload_gate_check, &gate, &im, &e);
    if (rc == GLINT_ENOMEM || (rc && gate.refused))
        goto done;
    if (rc) {
        rc = api_reject(&e, rc == GLINT_ENONFINITE ? rc : GLINT_EINVAL,
                        rc == GLINT_ENONFINITE ? "non-finite" : "invalid-image",
                        "the painting: %.400s (PNG, JPEG, OpenEXR or Radiance HDR, %dx%d)",
                        e.msg, w, h);
        goto done;
    }
    snprintf(file, sizeof file, "painting%d", k);
    if ((rc = upload_store(a, req->param[0], file, req->body, req->body_len, NULL, NULL, &e)))
        goto done;
    r = http_json(200, json_pack("{s:i, s:i, s:i, s:i}", "view", k, "width", im.width,
                                 "height", im.height, "channels", im.channels));
done:
    if (rc)
        r = api_error(&e);
    upload_gate_leave(&gate);
    img_free(&im);
    json_decref(rec);
    return r;
}

/* ---- fits ---------------------------------------------------------------------------- */

/* Decode the painted views of a set for method m and make its samples and
 * values (core gbfit.h).  OUT: *s, *rgb. */
/* OUT *all_wi: 1 when every painted view's G-buffer names its light's
 * direction (views lit by point lights). */
static int gb_samples(app *a, const char *id, const method *m, int n, int w, int h,
                      samples *s, float **rgb, int *all_wi, glint_err *e)
{
    gbuf *g = calloc((size_t)n, sizeof *g);
    img *im = calloc((size_t)n, sizeof *im);
    unsigned char *use = calloc((size_t)n, 1);
    int rc = 0, has_uv = 1, painted = 0, dim = w > h ? w : h;
    char name[160], what[64];

    if (!g || !im || !use) {
        rc = glint_err_set(e, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    for (int k = 0; k < n && !rc; k++) {
        void *data = NULL;
        size_t len = 0;
        int uv = 0, wi = 0;
        snprintf(name, sizeof name, "gbuffer-sets/%s/painting%d", id, k);
        if ((rc = store_blob_get(a->store, name, &data, &len, e)) == GLINT_ENOTFOUND) {
            rc = 0;
            continue; /* not painted: not in the pattern */
        }
        if (!rc && (rc = img_read_mem_max(data, len, dim, &im[k], e)))
            glint_err_prefix(e, "the painting of view %d", k);
        free(data);
        if (rc)
            break;
        snprintf(name, sizeof name, "gbuffer-sets/%s/gbuffer%d.exr", id, k);
        if ((rc = store_blob_get(a->store, name, &data, &len, e)) == GLINT_ENOTFOUND) {
            rc = api_reject(e, GLINT_EINVAL, "missing-gbuffer",
                            "view %d has a painting but no G-buffer: PUT "
                            "/api/v1/gbuffer-sets/%s/views/%d/gbuffer.exr before fitting",
                            k, id, k);
            break;
        }
        snprintf(what, sizeof what, "the G-buffer of view %d", k);
        if (!rc && (rc = gbfit_gbuf_mem(m, data, len, dim, GB_MAX_CHANNELS, NULL, NULL, what,
                                        &g[k], &uv, &wi, e)) &&
            rc != GLINT_ENOMEM)
            rc = glint_err_kind(e, "invalid-gbuffer");
        free(data);
        has_uv &= uv;
        *all_wi &= wi;
        use[k] = 1;
        painted++;
    }
    if (!rc && !painted)
        rc = api_reject(e, GLINT_EINVAL, "no-paintings",
                        "G-buffer set %s has no painting yet: PUT at least one view's painting "
                        "(and its gbuffer.exr) before fitting", id);
    if (!rc && (rc = gbfit_samples(m, g, im, use, n, has_uv, s, rgb, e)) &&
        rc != GLINT_ENOMEM && !e->kind[0])
        glint_err_kind(e, "invalid-input");
done:
    for (int k = 0; k < n && g && im; k++) {
        gbuf_free(&g[k]);
        img_free(&im[k]);
    }
    free(g);
    free(im);
    free(use);
    return rc;
}

static http_resp sets_fit(http_req *req)
{
    app *a = req->app;
    const char *id = req->param[0];
    json_t *rec = NULL, *body = NULL, *doc = NULL;
    const method *m = NULL;
    void *params = NULL;
    samples s;
    float *rgb = NULL;
    char job_id[33];
    size_t bytes = 0;
    http_resp r;
    glint_err e;
    int n, w, h, rc, admitted = 0, all_wi = 1;

    memset(&s, 0, sizeof s);
    if ((rc = gb_open(req, id, &rec, &n, &w, &h, &e)) ||
        (rc = api_body_json(req, &body, &e)) || (rc = api_fit_body(body, 0, &m, &params, &e)))
        goto done;
    bytes = (size_t)n * w * h * GB_FIT_PIXEL_BYTES + (size_t)w * h * GB_MAX_CHANNELS * 4;
    if ((rc = admit_enter(a->work, bytes, "decoding a G-buffer set", &e)))
        goto done;
    admitted = 1;
    rc = gb_samples(a, id, m, n, w, h, &s, &rgb, &all_wi, &e);
    admit_leave(a->work, bytes);
    admitted = 0;
    if (!rc && !(rc = fitsvc_fit_gbuffers(a->fits, id, m, params, &s, &rgb, &doc, job_id,
                                          &req->timing, &e)))
        r = api_fit_answer(req, doc, job_id,
                           api_lighting_warning(m, all_wi, "every view's G-buffer names a "
                                                               "light direction"));
done:
    if (rc)
        r = api_error(&e);
    if (admitted)
        admit_leave(a->work, bytes);
    samples_free(&s);
    free(rgb);
    free(params);
    json_decref(body);
    json_decref(rec);
    return r;
}

static http_resp sets_materials(http_req *req)
{
    app *a = req->app;
    json_t *rec, *list = NULL;
    glint_err e;
    int n, w, h;

    if (gb_open(req, req->param[0], &rec, &n, &w, &h, &e))
        return api_error(&e);
    json_decref(rec);
    if (store_material_list(a->store, req->param[0], &list, &e))
        return api_error(&e);
    for (size_t i = 0; i < json_array_size(list); i++)
        if (api_material_relink(json_array_get(list, i))) {
            json_decref(list);
            glint_err_set(&e, GLINT_ENOMEM, "out of memory");
            return api_error(&e);
        }
    return http_json(200, json_pack("{s:o}", "materials", list));
}

const http_route api_gbuffers_routes[] = {
    {"POST", "/api/v1/gbuffer-sets", sets_create},
    {"GET", "/api/v1/gbuffer-sets/{id}", sets_get},
    {"DELETE", "/api/v1/gbuffer-sets/{id}", sets_delete},
    {"PUT", "/api/v1/gbuffer-sets/{id}/views/{k}/gbuffer.exr", gbuffer_put},
    {"PUT", "/api/v1/gbuffer-sets/{id}/views/{k}/painting", painting_put},
    {"POST", "/api/v1/gbuffer-sets/{id}/fits", sets_fit},
    {"GET", "/api/v1/gbuffer-sets/{id}/materials", sets_materials},
};
const int api_gbuffers_nroutes = sizeof api_gbuffers_routes / sizeof api_gbuffers_routes[0];
