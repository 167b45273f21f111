/* api_common.c: errors to HTTP answers, access checks (api_common.h). */
#include "api_common.h"

#include <limits.h>
#include <malloc.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "admit.h"
#include "app.h"
#include "auth.h"
#include "cancel.h"
#include "fitsvc.h"
#include "log.h"
#include "store.h"

static const struct {
    int code, status;
    const char *kind;
} codes[] = {
    {GLINT_ENOTFOUND, 404, "not-found"},
    {GLINT_EINVAL, 422, "invalid-input"},
    {GLINT_EFORMAT, 422, "invalid-input"},
    {GLINT_ENONFINITE, 422, "non-finite"},
    {GLINT_ERANGE, 422, "invalid-input"},
    {GLINT_ENUMERIC, 422, "numerical-failure"},
    {GLINT_EUNSUPPORTED, 422, "unsupported"},
    {GLINT_EAUTH, 401, "unauthorized"},
    {GLINT_EDENIED, 403, "forbidden"},
    {GLINT_ECONFLICT, 409, "conflict"},
    {GLINT_EBUSY, 503, "busy"},
    {GLINT_ETOOBIG, 413, "too-large"},
    {GLINT_ECANCELLED, 503, "cancelled"},
    {GLINT_ENOMEM, 503, "out-of-memory"},
};

/* Kinds whose status is not their code's. */
static const struct {
    const char *kind;
    int status;
} kinds[] = {
    {"painting-changed", 412},
    {"egl-unavailable", 503},
    {"scene-gone", 409},
    {"bad-request", 400},
    {"missing-parameter", 400},
    {"empty-body", 400},
    {"invalid-json", 400},
    {"bad-if-match", 400},
    {"unsupported-media-type", 415},
    {"storage-full", 507},      /* the data directory's disk (fsio_err_kind) */
    {"storage-read-only", 503},
    {"owner-queue-full", 429},  /* one owner's jobs (jobs.h) */
    {"demo-file-invalid", 500}, /* the operator's --demo-session file (api_demo.c) */
};

int api_status(const glint_err *e)
{
    for (size_t i = 0; e->kind[0] && i < sizeof kinds / sizeof kinds[0]; i++)
        if (strcmp(e->kind, kinds[i].kind) == 0)
            return kinds[i].status;
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++)
        if (codes[i].code == e->code)
            return codes[i].status;
    return 500;
}

static const char *default_kind(int code)
{
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++)
        if (codes[i].code == code)
            return codes[i].kind;
    return NULL;
}

int api_reject(glint_err *err, int code, const char *kind, const char *fmt, ...)
{
    char msg[GLINT_ERR_MSG_MAX]; /* the arguments may point into err->msg */
    va_list ap;
    if (!err)
        return code;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    memcpy(err->msg, msg, sizeof msg);
    err->code = code;
    snprintf(err->kind, sizeof err->kind, "%s", kind ? kind : "");
    return code;
}

http_resp api_fail(const glint_err *e, const char *context)
{
    char msg[GLINT_ERR_MSG_MAX + 160];
    const char *kind = e->kind[0] ? e->kind : default_kind(e->code);
    int st = api_status(e);
    http_resp r;

    if (context)
        snprintf(msg, sizeof msg, "%s: %s", context, e->msg[0] ? e->msg : glint_strerror(e->code));
    else
        snprintf(msg, sizeof msg, "%s", e->msg[0] ? e->msg : glint_strerror(e->code));
    if (st >= 500 && st != 503)
        log_line("%s", msg);
    log_redact_paths(msg, sizeof msg);
    r = http_problem(st, kind, "%s", msg);
    if (st == 401)
        http_header(&r, "WWW-Authenticate",
                    strcmp(e->kind, "api-key-required") == 0     ? "Bearer realm=\"glintd\""
                    : strcmp(e->kind, "owner-key-required") == 0 ? "Bearer realm=\"glint-owner\""
                                                                 : "Bearer realm=\"glint-session\"");
    if (e->code == GLINT_EBUSY)
        http_header(&r, "Retry-After", "2");
    return r;
}

static int request_stop(void *cls)
{
    http_req *req = cls;
    app *a = req->app;
    return __atomic_load_n(&a->stopping, __ATOMIC_RELAXED) || http_req_gone(req);
}

static int app_stop(void *cls)
{
    return __atomic_load_n(&((app *)cls)->stopping, __ATOMIC_RELAXED);
}

void api_stop_cancel_init(app *a, glint_cancel *c)
{
    c->stop = app_stop;
    c->cls = a;
}

void api_cancel_init(http_req *req, glint_cancel *c)
{
    c->stop = request_stop;
    c->cls = req;
}

int api_low_priority(http_req *req)
{
    const char *p = http_header_in(req, "Priority");
    /* a Structured Field dictionary: "u=5", "u=5, i", "i, u=6" */
    for (const char *s = p; s && *s; s++) {
        if (s[0] == 'u' && s[1] == '=' && s[2] >= '0' && s[2] <= '7' &&
            (s == p || s[-1] == ' ' || s[-1] == ',') &&
            (s[3] == '\0' || s[3] == ',' || s[3] == ' ' || s[3] == ';'))
            return s[2] >= '4';
    }
    return 0;
}

void api_work_ticket(http_req *req, size_t bytes, int background, admit_ticket *t)
{
    const char *owner = NULL;
    glint_err ignored;
    memset(t, 0, sizeof *t);
    t->bytes = bytes;
    t->cls = background || api_low_priority(req) ? ADMIT_BACKGROUND : ADMIT_INTERACTIVE;
    if (auth_owner_key(req, &owner, &ignored) == 0 && owner)
        snprintf(t->client, sizeof t->client, "o:%s", owner);
    else {
        char addr[HTTP_CLIENT_KEY_MAX];
        http_client_key(req, addr, sizeof addr);
        if (addr[0])
            snprintf(t->client, sizeof t->client, "a:%s", addr);
    }
    t->gone = request_stop;
    t->gone_cls = req;
}

void api_work_ended(http_req *req, int rc)
{
    if (rc == GLINT_ECANCELLED)
        admit_cancelled(((app *)req->app)->work);
}

http_resp api_created(json_t *body, const char *what, const char *id)
{
    char loc[128];
    http_resp r;
    snprintf(loc, sizeof loc, "/api/v1/%s/%s", what, id);
    r = http_json(201, body);
    http_header(&r, "Location", loc);
    return r;
}

http_resp api_error(const glint_err *e)
{
    return api_fail(e, NULL);
}

http_resp api_body_too_large(http_req *req, const char *what)
{
    app *a = req->app;
    return http_problem(413, "body-too-large",
                        "%s exceeds the request body limit of %zu bytes (max_body, glintd "
                        "--max-body-mb %zu)",
                        what, a->cfg.lim.max_body, a->cfg.lim.max_body >> 20);
}

/* Nesting depth of JSON text, counted before parsing (so a hostile document
 * cannot make the parser recurse deeply). */
/* The nesting depth of JSON text and (OUT) an upper bound of the values
 * its tree holds: one per opening bracket, comma and colon, plus one. */
static int text_shape(const char *s, size_t n, size_t *values)
{
    int depth = 0, best = 0, in_str = 0;
    size_t count = 1;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (in_str) {
            if (c == '\\')
                i++;
            else if (c == '"')
                in_str = 0;
        } else if (c == '"') {
            in_str = 1;
        } else if (c == '{' || c == '[') {
            count++;
            if (++depth > best)
                best = depth;
        } else if (c == '}' || c == ']') {
            depth--;
        } else if (c == ',' || c == ':') {
            count++;
        }
    }
    *values = count;
    return best;
}

/* http_req's release hook: what api_body_json held of the work budget.
 * The tree is freed by then; its pages go back to the system (malloc_trim),
 * or the arena its thread used would keep them, and the next large body,
 * on another thread's arena, would add its own. */
static void body_release(http_req *req)
{
    app *a = req->app;
    malloc_trim(0);
    admit_leave(a->work, req->held);
    req->held = 0;
}

int api_body_json(http_req *req, json_t **out, glint_err *err)
{
    const char *ct = http_header_in(req, "Content-Type");
    json_error_t je;
    json_t *j;
    size_t values, tree;
    int rc;

    *out = NULL;
    if (req->body_too_large)
        return api_reject(err, GLINT_ETOOBIG, "body-too-large", "request body exceeds the limit");
    if (ct && strncmp(ct, "application/json", 16) != 0)
        return api_reject(err, GLINT_EINVAL, "unsupported-media-type",
                          "expected Content-Type application/json, got %.100s", ct);
    if (req->body_len == 0)
        return api_reject(err, GLINT_EINVAL, "invalid-json",
                          "empty body: a JSON object is required");
    if (text_shape(req->body, req->body_len, &values) > API_JSON_MAX_DEPTH)
        return api_reject(err, GLINT_ETOOBIG, "json-too-deep",
                          "JSON nesting deeper than the limit of %d", API_JSON_MAX_DEPTH);
    tree = values * API_JSON_VALUE_BYTES;
    if (tree > API_JSON_FREE_BYTES && !req->held) {
        app *a = req->app;
        char what[96];
        snprintf(what, sizeof what, "parsing a JSON body of %zu values (%.1f MB)", values,
                 (double)req->body_len / 1e6);
        if ((rc = admit_enter(a->work, tree, what, err)))
            return rc;
        req->held = tree;
        req->release = body_release;
    }
    j = json_loadb(req->body, req->body_len, JSON_REJECT_DUPLICATES, &je);
    if (!j)
        return api_reject(err, GLINT_EINVAL, "invalid-json",
                          "malformed JSON at line %d column %d: %.200s", je.line, je.column,
                          je.text);
    if (!json_is_object(j)) {
        json_decref(j);
        return api_reject(err, GLINT_EINVAL, "invalid-input", "the body must be a JSON object");
    }
    *out = j;
    return 0;
}

/* ---- access ------------------------------------------------------------------------ */

int api_session(http_req *req, const char *sid, int need_paint, json_t **doc, glint_err *err)
{
    app *a = req->app;
    int rc;

    *doc = NULL;
    rc = store_session_get(a->store, sid, doc, err);
    if (rc == GLINT_ENOTFOUND)
        return glint_err_set(err, rc, "no session %.40s", sid ? sid : "");
    if (rc)
        return rc;
    if ((rc = auth_session(req, *doc, need_paint, err))) {
        json_decref(*doc);
        *doc = NULL;
    }
    return rc;
}

json_t *api_material_links(const char *id, const char *sid, const char *scid,
                           const char *set)
{
    static const char *const files[][2] = {
        {"factors_png", "factors.png"}, {"factors_exr", "factors.exr"}, {"shader", "shader"},
        {"package", "package"},         {"eval", "eval"},               {"merl", "merl.binary"},
    };
    json_t *l = json_object();
    char b[160];
    int bad = !l;

    snprintf(b, sizeof b, "/api/v1/materials/%s", id);
    bad |= json_object_set_new(l, "self", json_string(b));
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        snprintf(b, sizeof b, "/api/v1/materials/%s/%s", id, files[i][1]);
        bad |= json_object_set_new(l, files[i][0], json_string(b));
    }
    if (sid && sid[0] && scid && scid[0]) {
        snprintf(b, sizeof b, "/api/v1/materials/%s/preview.png", id);
        bad |= json_object_set_new(l, "preview_png", json_string(b));
        snprintf(b, sizeof b, "/api/v1/materials/%s/preview.exr", id);
        bad |= json_object_set_new(l, "preview_exr", json_string(b));
        snprintf(b, sizeof b, "/api/v1/sessions/%s", sid);
        bad |= json_object_set_new(l, "session", json_string(b));
        snprintf(b, sizeof b, "/api/v1/scenes/%s", scid);
        bad |= json_object_set_new(l, "scene", json_string(b));
    }
    if (set && set[0]) {
        snprintf(b, sizeof b, "/api/v1/gbuffer-sets/%s", set);
        bad |= json_object_set_new(l, "gbuffer_set", json_string(b));
    }
    if (bad) {
        json_decref(l);
        return NULL;
    }
    return l;
}

int api_material_relink(json_t *doc)
{
    const char *id = json_string_value(json_object_get(doc, "id"));
    const char *sid = json_string_value(json_object_get(doc, "session_id"));
    const char *scid = json_string_value(json_object_get(doc, "scene_id"));
    const char *set = json_string_value(json_object_get(doc, "gbuffer_set_id"));
    json_t *l;
    if (!id)
        return 0;
    if (!(l = api_material_links(id, sid, scid, set)))
        return -1;
    return json_object_set_new(doc, "links", l);
}

int api_material(http_req *req, const char *mid, memo_doc *doc, glint_err *err)
{
    app *a = req->app;
    json_t *sdoc = NULL;
    int rc;

    if ((rc = fitsvc_material_doc(a->fits, mid, doc, err)))
        return rc;
    if (!doc->session[0]) { /* fitted from a G-buffer set: its owner's */
        json_t *j = json_loadb(doc->text, doc->len, 0, NULL);
        const char *set = json_string_value(json_object_get(j, "gbuffer_set_id"));
        rc = set ? api_gbuffer_set_access(req, set, err)
                 : glint_err_set(err, GLINT_EINTERNAL, "material %s names no G-buffer set", mid);
        json_decref(j);
        if (rc) {
            free(doc->text);
            doc->text = NULL;
        }
        return rc;
    }
    if ((rc = api_session(req, doc->session, 0, &sdoc, err))) {
        free(doc->text);
        doc->text = NULL;
        return rc;
    }
    json_decref(sdoc);
    return 0;
}

int api_view_index(const char *text, int n, int *k)
{
    long long v;
    if (strlen(text ? text : "") > 6 || api_parse_count(text, &v) || v >= n)
        return -1;
    *k = (int)v;
    return 0;
}

int api_parse_count(const char *text, long long *out)
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

int api_dir_file(const char *dir, const char *name, char *real, size_t len, long long *size)
{
    char path[PATH_MAX + 64], r[PATH_MAX];
    struct stat st;
    size_t dl = strlen(dir), n = strlen(name);
    if (!dir[0] || n == 0 || n > 60 || name[0] == '.')
        return -1;
    for (size_t i = 0; i < n; i++) {
        char c = name[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '.' || c == '_' || c == '-'))
            return -1;
    }
    snprintf(path, sizeof path, "%s/%s", dir, name);
    if (!realpath(path, r) || strncmp(r, dir, dl) || r[dl] != '/' || stat(r, &st) ||
        !S_ISREG(st.st_mode))
        return -1;
    snprintf(real, len, "%s", r);
    if (size)
        *size = (long long)st.st_size;
    return 0;
}

/* ---- downloads ------------------------------------------------------------------------------ */

/* s cut to [A-Za-z0-9._-] into out (at most cap - 1 characters) */
static void filename_part(const char *s, char *out, size_t cap)
{
    size_t k = 0;
    for (; s && *s && k + 1 < cap; s++) {
        char c = *s;
        int ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                 c == '.' || c == '_' || c == '-';
        out[k++] = ok ? c : '_';
    }
    out[k] = 0;
}

void api_export_filename(struct app *a, const char *mid, const char *scene_id, const char *ext,
                         char *out, size_t cap)
{
    char stem[48] = "glint", name[128];
    json_t *doc = NULL;
    glint_err e;
    if (scene_id && scene_id[0] && !store_scene_get(a->store, scene_id, &doc, &e)) {
        const char *mname = json_string_value(json_object_get(doc, "mesh"));
        if (mname && *mname)
            snprintf(stem, sizeof stem, "%s", strcmp(mname, "upload") ? mname : "mesh");
    }
    json_decref(doc);
    snprintf(name, sizeof name, "%s-%.8s.%s", stem, mid ? mid : "", ext ? ext : "bin");
    filename_part(name, out, cap);
}

void api_attachment(http_resp *r, const char *name)
{
    char disp[200];
    snprintf(disp, sizeof disp, "attachment; filename=\"%s\"", name);
    http_header(r, "Content-Disposition", disp);
}
