/* api_envs.c: the environments the daemon offers to environment-lit fits
 * (proto/openapi.yaml, "environments").
 *
 *   GET    /api/v1/environments          built-ins, data: maps, the caller's uploads
 *   POST   /api/v1/environments?name=LABEL   raw OpenEXR or Radiance HDR  (API key)
 *   DELETE /api/v1/environments/{id}         (the upload's owner key, or the API key)
 *
 * The built-in skies, the HDR maps of the directory given by --env-dir
 * (none without it), named "data:<file>", and uploads, named
 * "upload:<id>": decoded and checked before they are kept (sides at most
 * ENV_UPLOAD_MAX_DIM, a layout env.h reads), stored in the data store as
 * blobs environments/<id>.exr|hdr with a record environments/<id>.json.
 * An upload belongs to the owner key it was made with (X-Glint-Owner, or
 * one made and answered once, as scenes do: auth.h), kept in its record as
 * "owner" and never shown: it is listed to that key (every upload to the
 * API key) and deleted by it or the API key, and never while a scene's
 * base renders are lit by it (409 environment-in-use: deleting the map
 * would break the scene and its sessions).  Materials fitted under it do
 * not hold it: a material is its own BRDF, and reads, renders and exports
 * without the map.  Built-ins and data: maps are everyone's and are never
 * deleted.  The resolver registered here (env.h) is the only way a fit's `env`
 * parameter reaches a file: data:NAME of [A-Za-z0-9._-] not starting with
 * '.', a regular file whose real path lies inside the directory (no
 * traversal, no symbolic link out of it); upload:ID of a valid id whose
 * blob is a regular file.  Thread-safety: the directories are set once
 * before threads start. */
#include <dirent.h>
#include <math.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "api_common.h"
#include "app.h"
#include "auth.h"
#include "clock.h"
#include "env.h"
#include "ids.h"
#include "render.h"
#include "store.h"
#include "upload_gate.h"

static char env_dir[PATH_MAX]; /* real path, "" when none */
static char up_dir[PATH_MAX];  /* the uploads' blob directory, "" before the store opens */

/* Scene creations hold it shared from resolving their base environment to
 * storing the scene; a deletion holds it exclusively from counting the
 * scenes that name the upload to removing it (api_common.h). */
static pthread_rwlock_t env_use_lock = PTHREAD_RWLOCK_INITIALIZER;

void api_envs_use_begin(void)
{
    pthread_rwlock_rdlock(&env_use_lock);
}

void api_envs_use_end(void)
{
    pthread_rwlock_unlock(&env_use_lock);
}

/* An upload's sides: 4096 x 2048 lat-long (or a 4096-wide cross).  Its
 * decode's bound by its header, and the map made from it (3 floats a
 * pixel of the file at most), are admitted against the work budget
 * (upload_gate.h). */
#define ENV_UPLOAD_MAX_DIM 4096

/* The file of data:NAME inside the directory (OUT: real path), or -1. */
static int data_file(const char *name, char *real, size_t len)
{
    return api_dir_file(env_dir, name, real, len, NULL);
}

/* The file of upload:ID (OUT: path; ext: "exr" or "hdr" when not NULL), or -1. */
static int upload_file(const char *id, char *path, size_t len, const char **ext)
{
    static const char *const exts[] = {"exr", "hdr"};
    if (!up_dir[0] || !glint_id_valid(id))
        return -1;
    for (int i = 0; i < 2; i++) {
        struct stat st;
        snprintf(path, len, "%s/%s.%s", up_dir, id, exts[i]);
        if (lstat(path, &st) == 0 && S_ISREG(st.st_mode)) {
            if (ext)
                *ext = exts[i];
            return 0;
        }
    }
    return -1;
}

static int resolve(const char *spec, char *path, size_t len, glint_err *err)
{
    if (!strncmp(spec, "data:", 5) && data_file(spec + 5, path, len) == 0)
        return 0;
    if (!strncmp(spec, "upload:", 7) && upload_file(spec + 7, path, len, NULL) == 0)
        return 0;
    return glint_err_set(err, GLINT_ENOTFOUND,
                         "no environment '%s': a built-in (%s)%s or upload:ID of POST "
                         "/api/v1/environments", spec, env_builtin_names(),
                         env_dir[0] ? ", data:NAME of GET /api/v1/environments" : "");
}

int api_envs_init(const char *dir, glint_err *err)
{
    env_dir[0] = '\0';
    if (dir && dir[0] && !realpath(dir, env_dir)) {
        env_dir[0] = '\0';
        return glint_err_set(err, GLINT_ENOTFOUND, "--env-dir %s: no such directory", dir);
    }
    env_set_resolver(resolve);
    return 0;
}

int api_envs_store(store *s, glint_err *err)
{
    int rc = store_blob_path(s, "environments", up_dir, sizeof up_dir, err);
    if (rc)
        up_dir[0] = '\0';
    return rc;
}

static int query_num(const char *s, double lo, double hi, double *out)
{
    char *end;
    double v;
    if (!s)
        return 0;
    v = strtod(s, &end);
    if (end == s || *end || !isfinite(v) || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

int api_env_query(http_req *req, render_env *out, int *has, glint_err *e)
{
    const char *spec = http_query(req, "env"), *rot = http_query(req, "env_rotation"),
               *inten = http_query(req, "env_intensity"), *lights = http_query(req, "lights"),
               *shadows = http_query(req, "shadows"), *bg = http_query(req, "background");
    double x = 0.0;
    render_env_init(out);
    *has = spec != NULL;
    if (!spec) {
        if (rot || inten || lights || shadows || bg)
            return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                              "env_rotation, env_intensity, lights, shadows and background "
                              "need env=SPEC");
        return 0;
    }
    if (env_spec_check(spec, e))
        return glint_err_kind(e, "invalid-parameter");
    snprintf(out->spec, sizeof out->spec, "%s", spec);
    if (query_num(rot, -360.0, 360.0, &out->rotation_deg))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "env_rotation must be degrees in [-360, 360]");
    if (query_num(inten, 1e-12, 1e6, &out->intensity))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "env_intensity must be in (0, 1e6]");
    if (lights && (query_num(lights, 1, RENDER_ENV_MAX_LIGHTS, &x) || x != floor(x)))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "lights must be an integer in 1..%d", RENDER_ENV_MAX_LIGHTS);
    if (lights)
        out->lights = (int)x;
    if (shadows && strcmp(shadows, "0") && strcmp(shadows, "1"))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter", "shadows must be 0 or 1");
    if (shadows)
        out->shadows = shadows[0] == '1';
    if (bg && strcmp(bg, "0") && strcmp(bg, "1"))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter", "background must be 0 or 1");
    if (bg)
        out->background = bg[0] == '1';
    return 0;
}

int api_env_parse(const json_t *j, const char *what, render_env *out, glint_err *e)
{
    const char *k;
    json_t *v;
    render_env_init(out);
    if (!json_is_object(j) || !json_is_string(json_object_get(j, "spec")))
        return api_reject(e, GLINT_EINVAL, "invalid-input",
                          "%s: expected {\"spec\": environment, \"rotation\", \"intensity\", "
                          "\"lights\", \"shadows\", \"background\"}", what);
    json_object_foreach((json_t *)j, k, v) {
        int ok = 1;
        if (!strcmp(k, "spec")) {
            if (env_spec_check(json_string_value(v), e))
                return api_reject(e, GLINT_EINVAL, "invalid-input", "%s.spec: %.300s", what,
                                  e->msg);
            snprintf(out->spec, sizeof out->spec, "%s", json_string_value(v));
        } else if (!strcmp(k, "rotation") || !strcmp(k, "intensity")) {
            ok = json_is_number(v) && isfinite(json_number_value(v));
            if (ok)
                *(k[0] == 'r' ? &out->rotation_deg : &out->intensity) = json_number_value(v);
        } else if (!strcmp(k, "lights")) {
            ok = json_is_integer(v) && json_integer_value(v) >= 1 &&
                 json_integer_value(v) <= RENDER_ENV_MAX_LIGHTS;
            if (ok)
                out->lights = (int)json_integer_value(v);
        } else if (!strcmp(k, "shadows") || !strcmp(k, "background")) {
            ok = json_is_boolean(v);
            if (ok)
                *(k[0] == 's' ? &out->shadows : &out->background) = json_is_true(v);
        } else {
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "%s: unknown field \"%.40s\" (spec, rotation, intensity, lights, "
                              "shadows, background)", what, k);
        }
        if (!ok)
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "%s.%s: a number (rotation, intensity), an integer 1..%d (lights) "
                              "or true/false (shadows, background)", what, k,
                              RENDER_ENV_MAX_LIGHTS);
    }
    if (render_env_check(out, e))
        return api_reject(e, GLINT_EINVAL, "invalid-input", "%s: %.300s", what, e->msg);
    return 0;
}

json_t *api_env_json(const render_env *env)
{
    return json_pack("{s:s, s:f, s:f, s:i, s:b, s:b}", "spec", env->spec, "rotation",
                     env->rotation_deg, "intensity", env->intensity, "lights", env->lights,
                     "shadows", env->shadows, "background", env->background);
}

void api_env_header(http_resp *r, const render_env_info *info)
{
    char h[200];
    snprintf(h, sizeof h, "env=%s; lights=%d; cached=%d; convex=%d; rays=%ld; prepare_ms=%.1f; "
             "shade_ms=%.1f; draw_ms=%.1f",
             info->env, info->lights, info->cached, info->convex, info->rays,
             1e3 * info->prepare_s, 1e3 * info->shade_s, 1e3 * info->draw_s);
    http_header(r, "X-Glint-Env", h);
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The public form of an upload's record: everything but its owner. */
static json_t *env_public(json_t *rec)
{
    json_object_del(rec, "owner");
    return rec;
}

static http_resp envs_get(http_req *req)
{
    json_t *list;
    char names[] = "studio,sky,sunset,overcast,white", *save = NULL;
    const char *owner = NULL;
    int all = auth_has_key(req);
    glint_err e;

    /* uploads are listed to their owner key (all of them to the API key) */
    if (!all && auth_owner_key(req, &owner, &e))
        return api_error(&e);
    list = json_array();
    for (char *t = strtok_r(names, ",", &save); t; t = strtok_r(NULL, ",", &save))
        json_array_append_new(list, json_pack("{s:s, s:s, s:s}", "spec", t, "name", t,
                                              "kind", "builtin"));
    if (env_dir[0]) {
        DIR *d = opendir(env_dir);
        struct dirent *de;
        char *found[512], real[PATH_MAX];
        int n = 0;
        while (d && (de = readdir(d)) && n < 512) {
            const char *x = strrchr(de->d_name, '.');
            if (x && (!strcmp(x, ".exr") || !strcmp(x, ".hdr")) &&
                data_file(de->d_name, real, sizeof real) == 0)
                found[n++] = strdup(de->d_name);
        }
        if (d)
            closedir(d);
        qsort(found, (size_t)n, sizeof *found, cmp_str);
        for (int i = 0; i < n; i++) {
            char spec[80];
            if (!found[i])
                continue;
            snprintf(spec, sizeof spec, "data:%s", found[i]);
            json_array_append_new(list, json_pack("{s:s, s:s, s:s}", "spec", spec, "name",
                                                  found[i], "kind", "data"));
            free(found[i]);
        }
    }
    if (up_dir[0] && (all || owner)) {
        app *a = req->app;
        json_t *blobs = NULL, *v;
        size_t i;
        if (!store_blob_list(a->store, "environments", &blobs, NULL))
            json_array_foreach(blobs, i, v) {
                const char *nm = json_string_value(v);
                char blob[128];
                void *data = NULL;
                size_t len = 0;
                json_t *rec;
                if (!nm || strlen(nm) < 6 || strcmp(nm + strlen(nm) - 5, ".json"))
                    continue;
                snprintf(blob, sizeof blob, "environments/%s", nm);
                if (store_blob_get(a->store, blob, &data, &len, NULL))
                    continue;
                if ((rec = json_loadb(data, len, 0, NULL)) && json_is_object(rec) &&
                    (all || auth_owned_by(rec, owner)))
                    json_array_append_new(list, env_public(rec));
                else
                    json_decref(rec);
                free(data);
            }
        json_decref(blobs);
    }
    return http_json(200, json_pack("{s:o}", "environments", list));
}

static int label_ok(const char *s)
{
    size_t n = s ? strlen(s) : 0;
    if (n == 0 || n > 60)
        return 0;
    for (size_t i = 0; i < n; i++)
        if ((unsigned char)s[i] < 0x20 || s[i] == 0x7f || s[i] == '"' || s[i] == '\\')
            return 0;
    return 1;
}

static int env_post_do(http_req *req, json_t **rec, char id[GLINT_ID_LEN], glint_err *e)
{
    app *a = req->app;
    const char *label = http_query(req, "name"), *ext, *owner;
    const unsigned char *b = (const unsigned char *)req->body;
    char blob[128], now[GLINT_TIME_LEN], made[GLINT_ID_LEN], *txt;
    upload_gate gate;
    env_map m;
    int rc;

    if ((rc = auth_require_key(req, e)) || (rc = auth_owner_new(req, made, &owner, e)))
        return rc;
    if (!up_dir[0])
        return glint_err_set(e, GLINT_EINTERNAL, "no store for uploads");
    if (req->body_too_large)
        return api_reject(e, GLINT_ETOOBIG, "body-too-large",
                          "the map exceeds the request body limit of %zu bytes (max_body, "
                          "glintd --max-body-mb %zu)",
                          a->cfg.lim.max_body, a->cfg.lim.max_body >> 20);
    if (label && !http_utf8_valid(label))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "name must be UTF-8 text (it holds bytes that are not)");
    if (label && !label_ok(label))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "name must be 1 to 60 printable characters without quotes");
    if (req->body_len < 4)
        return api_reject(e, GLINT_EINVAL, "empty-body",
                          "the body must be the map: an OpenEXR or Radiance HDR file");
    if (!memcmp(b, "\x76\x2f\x31\x01", 4))
        ext = "exr";
    else if (req->body_len >= 2 && b[0] == '#' && b[1] == '?')
        ext = "hdr";
    else
        return api_reject(e, GLINT_EINVAL, "invalid-environment",
                          "the body is neither OpenEXR nor Radiance HDR (by its first bytes)");
    upload_gate_init(&gate, a, "the map");
    gate.max_dim = ENV_UPLOAD_MAX_DIM;
    gate.max_dim_name = "an environment's limit";
    gate.too_large_code = GLINT_EINVAL;
    gate.too_large_kind = "invalid-environment";
    gate.invalid_kind = "invalid-environment";
    snprintf(gate.expect, sizeof gate.expect,
             "the map cannot be used (sides up to %d, lat-long 2:1 or a cube cross)",
             ENV_UPLOAD_MAX_DIM);
    gate.per_pixel = 3 * sizeof(float);
    rc = env_load_mem(req->body, req->body_len, label ? label : "upload", 0, upload_gate_check,
                      &gate, &m, e);
    upload_gate_leave(&gate);
    if (rc == GLINT_ENOMEM || (rc && gate.refused))
        return rc;
    if (rc)
        return api_reject(e, GLINT_EINVAL, "invalid-environment",
                          "the map cannot be used (sides up to %d, lat-long 2:1 or a cube "
                          "cross): %.400s",
                          ENV_UPLOAD_MAX_DIM, e->msg);
    if ((rc = glint_id_new(id, e))) {
        env_map_free(&m);
        return rc;
    }
    glint_time_iso_ms(now);
    {
        char spec[64];
        snprintf(spec, sizeof spec, "upload:%s", id);
        *rec = json_pack("{s:s, s:s, s:s, s:s, s:i, s:i, s:s, s:I, s:I, s:I, s:s, s:s, s:s}",
                         "id", id, "spec", spec, "name", label ? label : id, "kind", "upload",
                         "width", m.width, "height", m.height, "layout", m.layout, "bytes",
                         (json_int_t)req->body_len, "clamped", (json_int_t)m.clamped,
                         "nonfinite", (json_int_t)m.nonfinite, "format", ext, "created", now,
                         "owner", owner);
    }
    env_map_free(&m);
    if (!*rec || !(txt = json_dumps(*rec, JSON_COMPACT))) {
        json_decref(*rec);
        *rec = NULL;
        return glint_err_set(e, GLINT_ENOMEM, "cannot build the environment record");
    }
    /* the map first, its record last: a record names a map that is there */
    snprintf(blob, sizeof blob, "environments/%s.%s", id, ext);
    if (!(rc = store_blob_put(a->store, blob, req->body, req->body_len, e))) {
        char rb[128];
        snprintf(rb, sizeof rb, "environments/%s.json", id);
        if ((rc = store_blob_put(a->store, rb, txt, strlen(txt), e)))
            store_blob_delete(a->store, blob, NULL);
    }
    free(txt);
    if (rc) {
        json_decref(*rec);
        *rec = NULL;
        return glint_err_prefix(e, "storing the environment");
    }
    /* the one answer that carries the owner key */
    json_object_set_new(env_public(*rec), "owner_key", json_string(owner));
    return 0;
}

static http_resp envs_post(http_req *req)
{
    json_t *rec = NULL;
    char id[GLINT_ID_LEN];
    glint_err e;
    if (env_post_do(req, &rec, id, &e))
        return api_error(&e);
    return api_created(rec, "environments", id);
}

/* The record of upload `id` (OUT: *rec), or GLINT_ENOTFOUND. */
static int env_record(app *a, const char *id, json_t **rec, glint_err *e)
{
    char blob[128];
    void *data = NULL;
    size_t len = 0;
    int rc;

    *rec = NULL;
    snprintf(blob, sizeof blob, "environments/%s.json", id);
    if ((rc = store_blob_get(a->store, blob, &data, &len, e)))
        return rc;
    *rec = json_loadb(data, len, 0, NULL);
    free(data);
    if (!json_is_object(*rec)) {
        json_decref(*rec);
        *rec = NULL;
        return glint_err_set(e, GLINT_EINTERNAL, "environment %s: unreadable record", id);
    }
    return 0;
}

/* Is `name` a built-in or a data: map (everyone's, never deleted)? */
static int env_public_name(const char *name)
{
    const char *n = !strncmp(name, "builtin:", 8) ? name + 8 : name;
    const char *b = env_builtin_names();
    size_t len = strlen(n);
    if (!strncmp(name, "data:", 5) || (n != name && len))
        return 1;
    for (const char *p = strstr(b, n); len && p; p = strstr(p + 1, n))
        if ((p == b || p[-1] == ' ') && (p[len] == ',' || p[len] == '\0'))
            return 1;
    return 0;
}

/* Delete upload `id` unless a scene's base renders are lit by it. */
static int env_delete_locked(app *a, const char *id, const char *ext, glint_err *e)
{
    char blob[128];
    long long n = 0;
    int rc;

    snprintf(blob, sizeof blob, "\"upload:%s\"", id);
    if ((rc = store_scene_count_naming(a->store, blob, &n, e)))
        return glint_err_prefix(e, "looking for the scenes lit by environment %s", id);
    if (n > 0)
        return api_reject(e, GLINT_ECONFLICT, "environment-in-use",
                          "environment upload:%s lights the base renders of %lld scene%s, which "
                          "would break without it: delete %s first (DELETE /api/v1/scenes/{id}; "
                          "their sessions and materials go with them)",
                          id, n, n == 1 ? "" : "s", n == 1 ? "that scene" : "those scenes");
    /* the record first: a map without one is not listed */
    snprintf(blob, sizeof blob, "environments/%s.json", id);
    if ((rc = store_blob_delete(a->store, blob, e)))
        return rc;
    snprintf(blob, sizeof blob, "environments/%s.%s", id, ext);
    return store_blob_delete(a->store, blob, e);
}

static int env_delete_do(http_req *req, glint_err *e)
{
    app *a = req->app;
    const char *id = req->param[0] ? req->param[0] : "", *ext;
    char path[PATH_MAX + 64];
    json_t *rec = NULL;
    int rc;

    if (env_public_name(id))
        return api_reject(e, GLINT_EDENIED, "not-deletable",
                          "\"%.64s\" is a built-in or a map of the daemon's --env-dir: those are "
                          "everyone's and cannot be deleted (only uploads, by their owner key)",
                          id);
    if (upload_file(id, path, sizeof path, &ext) || env_record(a, id, &rec, e) == GLINT_ENOTFOUND)
        return api_reject(e, GLINT_ENOTFOUND, "not-found", "no uploaded environment \"%.40s\"",
                          id);
    if (!rec)
        return e->code;
    rc = auth_owner(req, rec, "environment", e);
    json_decref(rec);
    if (rc)
        return rc;
    pthread_rwlock_wrlock(&env_use_lock);
    rc = env_delete_locked(a, id, ext, e);
    pthread_rwlock_unlock(&env_use_lock);
    return rc;
}

static http_resp envs_delete(http_req *req)
{
    glint_err e;
    if (env_delete_do(req, &e))
        return api_error(&e);
    return http_bytes(204, NULL, "", 0);
}

const http_route api_envs_routes[] = {
    {"GET", "/api/v1/environments", envs_get},
    {"POST", "/api/v1/environments", envs_post},
    {"DELETE", "/api/v1/environments/{id}", envs_delete},
};
const int api_envs_nroutes = sizeof api_envs_routes / sizeof api_envs_routes[0];
