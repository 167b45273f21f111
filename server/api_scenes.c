/* api_scenes.c: scenes and uploaded meshes (proto/openapi.yaml, section
 * "scenes, meshes, sessions...").
 *
 *   POST   /api/v1/meshes?format=ply|obj|off|gltf|glb|dae   raw mesh file   (API key)
 *   GET    /api/v1/meshes/{id}
 *   POST   /api/v1/scenes                                   SceneCreate     (API key)
 *   GET    /api/v1/scenes                                                   (API key)
 *   GET    /api/v1/scenes/{id}
 *   DELETE /api/v1/scenes/{id}                                              (API key)
 *   GET    /api/v1/scenes/{id}/views/{k}/base.png[?format=exr&brdf=&scale=&intensity=]
 *   GET    /api/v1/scenes/{id}/views/{k}/gbuffer.exr
 *
 * Reading a scene or mesh by id needs no key: ids are 128 random bits.
 * Everything numerical is core's: scene_create / scene_from_json build and
 * validate, raster_* and samples_build count samples, paint_views renders
 * base images, mesh_load_mem reads uploads. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "api_common.h"
#include "app.h"
#include "auth.h"
#include "brdf.h"
#include "fsio.h"
#include "gbuf.h"
#include "img.h"
#include "mesh.h"
#include "paint.h"
#include "raster.h"
#include "samples.h"
#include "scene.h"
#include "store.h"

#define API_DEFAULT_SIZE 128
#define API_BASE_BRDF "lambert:kd=0.6"
/* Base renders show kd cos(theta_i) I: the Lambert 1/pi undone by the scale. */
#define API_BASE_SCALE 3.14159265358979323846

/* ---- shared helpers ---------------------------------------------------------- */

/* A view index from a path segment: decimal digits, 0..n-1. */
static int api_view_index(const char *text, int n, int *k)
{
    long v = 0;
    if (!text || !*text || strlen(text) > 6)
        return -1;
    for (const char *c = text; *c; c++) {
        if (*c < '0' || *c > '9')
            return -1;
        v = 10 * v + (*c - '0');
    }
    if (v >= n)
        return -1;
    *k = (int)v;
    return 0;
}

static const char *api_kind(const json_t *j)
{
    switch (json_typeof(j)) {
    case JSON_OBJECT: return "an object";
    case JSON_ARRAY: return "an array";
    case JSON_STRING: return "a string";
    case JSON_INTEGER: return "an integer";
    case JSON_REAL: return "a number";
    case JSON_TRUE:
    case JSON_FALSE: return "a boolean";
    default: return "null";
    }
}

/* The public form of a scene doc: everything but the internal "scene". */
static json_t *api_scene_public(const json_t *doc)
{
    json_t *pub = json_deep_copy(doc);
    if (pub)
        json_object_del(pub, "scene");
    return pub;
}

/* ---- meshes ------------------------------------------------------------------ */

static const char *const api_mesh_formats[] = {"ply", "obj", "off", "gltf", "glb", "dae", NULL};

static http_resp mesh_create(http_req *req)
{
    app *a = req->app;
    http_resp deny;
    const char *fmt = http_query(req, "format");
    mesh m;
    mesh_report rep;
    glint_err e;
    char id[33], now[32];
    json_t *info;
    int ok = 0, rc;

    if (auth_require_key(req, &deny))
        return deny;
    if (req->body_too_large)
        return api_body_too_large(req, "the mesh file");
    if (!fmt)
        return http_problem(400, "missing-parameter",
                            "query parameter format is required: ply, obj, off, gltf, glb or dae");
    for (int i = 0; api_mesh_formats[i]; i++)
        if (strcmp(fmt, api_mesh_formats[i]) == 0)
            ok = 1;
    if (!ok)
        return http_problem(422, "invalid-input",
                            "format \"%.32s\" is not one of ply, obj, off, gltf, glb, dae", fmt);
    if (req->body_len == 0)
        return http_problem(400, "empty-body", "the body must be the mesh file (%s)", fmt);
    rc = mesh_load_mem(req->body, req->body_len, fmt, &m, &rep, &e);
    if (rc == GLINT_ERANGE)
        return http_problem(413, "mesh-too-large", "mesh file rejected: %s", e.msg);
    if (rc == GLINT_ENOMEM || rc == GLINT_EIO || rc == GLINT_EINTERNAL)
        return api_fail(&e, "loading the mesh");
    if (rc)
        return http_problem(422, "invalid-mesh", "the %s file cannot be used: %s", fmt, e.msg);
    if (m.ntris > a->cfg.lim.max_mesh_tris) {
        int n = m.ntris;
        mesh_free(&m);
        return http_problem(413, "mesh-too-large",
                            "the mesh has %d triangles, more than the limit of %d (max_mesh_tris, "
                            "glintd --max-mesh-tris)",
                            n, a->cfg.lim.max_mesh_tris);
    }
    if (store_new_id(id, &e)) {
        mesh_free(&m);
        return api_fail(&e, "creating a mesh id");
    }
    store_now(now);
    info = json_pack("{s:s, s:s, s:i, s:i, s:I, s:s, s:{s:i, s:b, s:b, s:i, s:i, s:i, s:f, "
                     "s:[fff], s:f}}",
                     "id", id, "format", fmt, "triangles", m.ntris, "vertices", m.nverts,
                     "bytes", (json_int_t)req->body_len, "created", now, "report",
                     "dropped_degenerate", rep.dropped_degenerate, "normals_generated",
                     rep.normals_generated, "uvs_generated", rep.uvs_generated,
                     "nonmanifold_edges", rep.nonmanifold_edges, "boundary_edges",
                     rep.boundary_edges, "dropped_primitives", rep.dropped_primitives, "scale",
                     rep.scale, "center", rep.center[0], rep.center[1], rep.center[2],
                     "uv_coverage", rep.uv_coverage);
    mesh_free(&m);
    if (!info)
        return http_problem(500, NULL, "cannot build the mesh record");
    if (store_mesh_put(a->store, id, info, req->body, req->body_len, &e)) {
        json_decref(info);
        return api_fail(&e, "storing the mesh");
    }
    {
        char loc[96];
        http_resp r;
        snprintf(loc, sizeof loc, "/api/v1/meshes/%s", id);
        r = http_json(201, info);
        http_header(&r, "Location", loc);
        return r;
    }
}

static http_resp mesh_get(http_req *req)
{
    app *a = req->app;
    json_t *info;
    glint_err e;
    if (store_mesh_get(a->store, req->param[0], &info, &e))
        return api_fail(&e, "mesh");
    return http_json(200, info);
}

/* ---- scenes ------------------------------------------------------------------------ */

/* Fill the defaults of one explicit view (a copy of the request's object):
 * target [0,0,0]; half_fov framing the unit ball with the default margin
 * 1.1 from the eye's distance to the target, atan(1.1 / sqrt(d^2 - 1)),
 * when that distance exceeds 1.1 (else half_fov is required). */
static json_t *scene_view_defaults(const json_t *in)
{
    json_t *v = json_deep_copy(in), *eye, *target;
    if (!json_is_object(v))
        return v;
    if (!json_object_get(v, "target"))
        json_object_set_new(v, "target", json_pack("[fff]", 0.0, 0.0, 0.0));
    eye = json_object_get(v, "eye");
    target = json_object_get(v, "target");
    if (!json_object_get(v, "half_fov") && json_is_array(eye) && json_is_array(target) &&
        json_array_size(eye) == 3 && json_array_size(target) == 3) {
        double d2 = 0.0;
        int ok = 1;
        for (int i = 0; i < 3; i++) {
            json_t *a = json_array_get(eye, (size_t)i), *b = json_array_get(target, (size_t)i);
            if (!json_is_number(a) || !json_is_number(b)) {
                ok = 0;
                break;
            }
            d2 += (json_number_value(a) - json_number_value(b)) *
                  (json_number_value(a) - json_number_value(b));
        }
        if (ok && isfinite(d2) && d2 > 1.1 * 1.1)
            json_object_set_new(v, "half_fov", json_real(atan(1.1 / sqrt(d2 - 1.0))));
    }
    return v;
}

/* Build the core scene a creation request asks for.  OUT: *sc (scene_free),
 * *view_set ("ico12", "ico20", "explicit"). */
static http_resp scene_build(app *a, const json_t *body, scene *sc, char *mesh_label,
                             size_t label_len, const char **view_set)
{
    static const char *const keys[] = {"mesh", "mesh_id", "width", "height", "views",
                                       "light_angles", "base", NULL};
    const char *k;
    json_t *v, *jmesh = json_object_get(body, "mesh"), *jmesh_id = json_object_get(body, "mesh_id");
    json_t *jviews = json_object_get(body, "views"), *jangles = json_object_get(body, "light_angles");
    const char *builtin = "sphere", *mesh_id = NULL;
    long long width = API_DEFAULT_SIZE, height = API_DEFAULT_SIZE;
    int max_dim = a->cfg.lim.max_image_dim < SCENE_MAX_SIZE ? a->cfg.lim.max_image_dim
                                                            : SCENE_MAX_SIZE;
    glint_err e;
    int rc;

    memset(sc, 0, sizeof *sc);
    json_object_foreach((json_t *)body, k, v) {
        int known = 0;
        for (int i = 0; keys[i]; i++)
            known |= strcmp(k, keys[i]) == 0;
        if (!known)
            return http_problem(422, "invalid-input",
                                "unknown key \"%.64s\" (known: mesh, mesh_id, width, height, "
                                "views, light_angles, base)", k);
    }
    if (jmesh && jmesh_id)
        return http_problem(422, "invalid-input",
                            "give either mesh (a built-in) or mesh_id (an uploaded mesh), not both");
    if (jmesh) {
        if (!json_is_string(jmesh))
            return http_problem(422, "invalid-input",
                                "mesh: expected a string (sphere, torus or teapot), got %s",
                                api_kind(jmesh));
        builtin = json_string_value(jmesh);
        if (strcmp(builtin, "sphere") && strcmp(builtin, "torus") && strcmp(builtin, "teapot"))
            return http_problem(422, "invalid-input",
                                "mesh: \"%.64s\" is not a built-in (sphere, torus, teapot); "
                                "upload a file with POST /api/v1/meshes and pass mesh_id",
                                builtin);
    }
    if (jmesh_id) {
        json_t *info;
        if (!json_is_string(jmesh_id))
            return http_problem(422, "invalid-input", "mesh_id: expected a string, got %s",
                                api_kind(jmesh_id));
        mesh_id = json_string_value(jmesh_id);
        if (store_mesh_get(a->store, mesh_id, &info, &e))
            return http_problem(e.code == GLINT_ENOTFOUND ? 422 : 500,
                                e.code == GLINT_ENOTFOUND ? "unknown-mesh" : NULL, "mesh_id: %s",
                                e.msg);
        json_decref(info);
    }
    {
        const char *names[2] = {"width", "height"};
        long long *dst[2] = {&width, &height};
        for (int i = 0; i < 2; i++) {
            json_t *j = json_object_get(body, names[i]);
            if (!j)
                continue;
            if (!json_is_integer(j))
                return http_problem(422, "invalid-input", "%s: expected an integer, got %s",
                                    names[i], api_kind(j));
            *dst[i] = json_integer_value(j);
            if (*dst[i] > max_dim)
                return http_problem(422, "image-too-large",
                                    "%s %lld exceeds the limit of %d pixels (max_image_dim, "
                                    "glintd --max-image-dim)",
                                    names[i], *dst[i], max_dim);
            if (*dst[i] < SCENE_MIN_SIZE)
                return http_problem(422, "invalid-input", "%s %lld is below the minimum of %d",
                                    names[i], *dst[i], SCENE_MIN_SIZE);
        }
    }

    if (!jviews || json_is_string(jviews)) {
        scene_params p;
        const char *set = jviews ? json_string_value(jviews) : "ico12";
        scene_params_default(&p);
        if (strcmp(set, "ico12") == 0)
            p.view_set = SCENE_VIEWS_ICO12;
        else if (strcmp(set, "ico20") == 0)
            p.view_set = SCENE_VIEWS_ICO20;
        else
            return http_problem(422, "invalid-input",
                                "views: \"%.32s\" is not \"ico12\", \"ico20\" or an array of "
                                "views", set);
        *view_set = p.view_set == SCENE_VIEWS_ICO12 ? "ico12" : "ico20";
        if ((p.view_set == SCENE_VIEWS_ICO12 ? 12 : 20) > a->cfg.lim.max_views)
            return http_problem(422, "too-many-views",
                                "views: %s has more views than the limit of %d (max_views)", set,
                                a->cfg.lim.max_views);
        if (jangles) {
            if (!json_is_array(jangles) || json_array_size(jangles) != 2 ||
                !json_is_number(json_array_get(jangles, 0)) ||
                !json_is_number(json_array_get(jangles, 1)))
                return http_problem(422, "invalid-input",
                                    "light_angles: expected [lo, hi] in degrees");
            p.light_lo_deg = json_number_value(json_array_get(jangles, 0));
            p.light_hi_deg = json_number_value(json_array_get(jangles, 1));
        }
        snprintf(p.mesh_name, sizeof p.mesh_name, "%s", mesh_id ? "sphere" : builtin);
        p.width = (int)width;
        p.height = (int)height;
        rc = scene_create(&p, sc, &e);
        if (rc)
            return api_fail(&e, "scene");
    } else if (json_is_array(jviews)) {
        json_t *doc, *arr;
        char *text;
        size_t n = json_array_size(jviews), i;
        if (jangles)
            return http_problem(422, "invalid-input",
                                "light_angles applies to the ico12 and ico20 view sets; explicit "
                                "views give each light");
        if (n == 0)
            return http_problem(422, "invalid-input", "views: empty (give 1 view or more)");
        if (n > (size_t)a->cfg.lim.max_views)
            return http_problem(422, "too-many-views",
                                "views: %zu views, more than the limit of %d (max_views)", n,
                                a->cfg.lim.max_views);
        *view_set = "explicit";
        arr = json_array();
        json_array_foreach(jviews, i, v)
            json_array_append_new(arr, scene_view_defaults(v));
        doc = json_pack("{s:s, s:i, s:s, s:I, s:I, s:o}", "format", "glint-scene", "version", 1,
                        "mesh", mesh_id ? "sphere" : builtin, "width", (json_int_t)width,
                        "height", (json_int_t)height, "views", arr);
        text = doc ? json_dumps(doc, JSON_COMPACT | JSON_REAL_PRECISION(17)) : NULL;
        json_decref(doc);
        if (!text)
            return http_problem(500, NULL, "out of memory building the scene");
        rc = scene_from_json(text, sc, &e);
        free(text);
        if (rc) {
            /* scene_from_json names fields "scene.views[k].x"; the API's are "views[k].x" */
            const char *msg = strncmp(e.msg, "scene.", 6) == 0 ? e.msg + 6 : e.msg;
            return http_problem(api_status(rc), "invalid-input", "%s", msg);
        }
    } else {
        return http_problem(422, "invalid-input",
                            "views: expected \"ico12\", \"ico20\" or an array of views, got %s",
                            api_kind(jviews));
    }

    if (mesh_id) {
        void *data = NULL;
        size_t len = 0;
        char fmt[16];
        mesh_free(&sc->mesh);
        rc = store_mesh_data(a->store, mesh_id, &data, &len, fmt, &e);
        if (!rc)
            rc = mesh_load_mem(data, len, fmt, &sc->mesh, &sc->mesh_info, &e);
        free(data);
        if (rc) {
            scene_free(sc);
            return api_fail(&e, "loading the uploaded mesh");
        }
        snprintf(sc->mesh_name, sizeof sc->mesh_name, "upload:%s", mesh_id);
        if ((rc = scene_validate(sc, &e))) {
            scene_free(sc);
            return api_fail(&e, "scene");
        }
    }
    snprintf(mesh_label, label_len, "%s", mesh_id ? "upload" : builtin);
    return (http_resp){0, NULL};
}

/* The base-render settings of a creation request: {"brdf", "scale"}. */
static http_resp scene_base_settings(const json_t *body, const char **spec, double *scale)
{
    json_t *b = json_object_get(body, "base"), *j;
    brdf tmp;
    glint_err e;
    *spec = API_BASE_BRDF;
    *scale = API_BASE_SCALE;
    if (!b)
        return (http_resp){0, NULL};
    if (!json_is_object(b))
        return http_problem(422, "invalid-input", "base: expected {\"brdf\": spec, \"scale\": s}");
    if ((j = json_object_get(b, "brdf"))) {
        if (!json_is_string(j))
            return http_problem(422, "invalid-input", "base.brdf: expected a string, got %s",
                                api_kind(j));
        *spec = json_string_value(j);
        if (brdf_parse(*spec, &tmp, &e))
            return http_problem(422, "invalid-input", "base.brdf: %s", e.msg);
    }
    if ((j = json_object_get(b, "scale"))) {
        if (!json_is_number(j) || !(json_number_value(j) > 0.0) || json_number_value(j) > 1e6)
            return http_problem(422, "invalid-input", "base.scale: expected a number in (0, 1e6]");
        *scale = json_number_value(j);
    }
    return (http_resp){0, NULL};
}

static http_resp scene_create_h(http_req *req)
{
    app *a = req->app;
    http_resp deny, fail;
    json_t *body, *views = NULL, *doc = NULL, *js = NULL;
    scene sc;
    gbuf *g = NULL;
    samples smp;
    char hash[33], id[33], now[32], label[16];
    const char *view_set = "ico12", *base_spec;
    double base_scale;
    char *text = NULL;
    long *counts = NULL;
    glint_err e;
    http_resp out;
    int rc;

    memset(&smp, 0, sizeof smp);
    if (auth_require_key(req, &deny))
        return deny;
    if (req->body_too_large)
        return api_body_too_large(req, "the scene request");
    body = http_body_json(req, &fail);
    if (!body)
        return fail;
    fail = scene_base_settings(body, &base_spec, &base_scale);
    if (fail.r) {
        json_decref(body);
        return fail;
    }
    fail = scene_build(a, body, &sc, label, sizeof label, &view_set);
    if (fail.r) {
        json_decref(body);
        return fail;
    }
    scene_hash(&sc, hash);

    /* samples per view: what a fit of this scene will see */
    counts = calloc((size_t)sc.nviews, sizeof *counts);
    if (!counts) {
        out = http_problem(500, NULL, "out of memory");
        goto done;
    }
    if ((rc = raster_scene(&sc, &g, &e))) {
        out = api_fail(&e, "rasterizing the views");
        goto done;
    }
    rc = samples_build(g, sc.views, sc.nviews, NULL, hash, &smp, &e);
    if (rc == GLINT_EINVAL) {
        out = http_problem(422, "no-samples",
                           "no view sees a lit surface pixel (check the cameras and lights): %s",
                           e.msg);
        goto done;
    } else if (rc) {
        out = api_fail(&e, "sampling the views");
        goto done;
    }
    for (int i = 0; i < smp.n; i++)
        counts[smp.view[i]]++;

    if (store_new_id(id, &e)) {
        out = api_fail(&e, "creating a scene id");
        goto done;
    }
    store_now(now);
    text = scene_to_json(&sc, &e);
    js = text ? json_loads(text, 0, NULL) : NULL;
    views = json_array();
    if (!js || !views) {
        out = http_problem(500, NULL, "cannot serialize the scene");
        goto done;
    }
    for (int k = 0; k < sc.nviews; k++) {
        const scene_view *v = &sc.views[k];
        char base[128], gb[128];
        json_t *jv;
        snprintf(base, sizeof base, "/api/v1/scenes/%s/views/%d/base.png", id, k);
        snprintf(gb, sizeof gb, "/api/v1/scenes/%s/views/%d/gbuffer.exr", id, k);
        jv = json_pack("{s:i, s:[fff], s:[fff], s:[fff], s:f, s:f, s:I, s:s, s:s}", "index", k,
                       "eye", v->eye[0], v->eye[1], v->eye[2], "target", v->target[0],
                       v->target[1], v->target[2], "light", v->light[0], v->light[1],
                       v->light[2], "half_fov", v->half_fov, "light_intensity",
                       v->light_intensity, "samples", (json_int_t)counts[k], "base", base,
                       "gbuffer", gb);
        if (jv && v->light_deg >= 0.0)
            json_object_set_new(jv, "light_deg", json_real(v->light_deg));
        if (!jv || json_array_append_new(views, jv)) {
            out = http_problem(500, NULL, "cannot serialize the scene");
            goto done;
        }
    }
    doc = json_pack("{s:s, s:s, s:s, s:i, s:i, s:s, s:O, s:I, s:s, s:{s:s, s:f}, s:O}", "id", id,
                    "hash", hash, "mesh", label, "width", sc.width, "height", sc.height, "view_set", view_set, "views", views,
                    "samples", (json_int_t)smp.n, "created", now, "base", "brdf", base_spec,
                    "scale", base_scale, "scene", js);
    if (doc && strcmp(label, "upload") == 0)
        json_object_set_new(doc, "mesh_id", json_string(sc.mesh_name + 7));
    if (!doc) {
        out = http_problem(500, NULL, "cannot build the scene record");
        goto done;
    }
    if (store_scene_put(a->store, id, doc, &e)) {
        out = api_fail(&e, "storing the scene");
        goto done;
    }
    {
        char loc[96];
        snprintf(loc, sizeof loc, "/api/v1/scenes/%s", id);
        out = http_json(201, api_scene_public(doc));
        http_header(&out, "Location", loc);
    }
done:
    json_decref(doc);
    json_decref(views);
    json_decref(js);
    free(text);
    free(counts);
    samples_free(&smp);
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
    json_decref(body);
    return out;
}

static http_resp scene_list(http_req *req)
{
    app *a = req->app;
    http_resp deny;
    json_t *arr, *pub;
    size_t i;
    json_t *v;
    glint_err e;

    if (auth_require_key(req, &deny))
        return deny;
    if (store_scene_list(a->store, &arr, &e))
        return api_fail(&e, "listing scenes");
    pub = json_array();
    json_array_foreach(arr, i, v)
        json_array_append_new(pub, api_scene_public(v));
    json_decref(arr);
    return http_json(200, json_pack("{s:o, s:I}", "scenes", pub, "count",
                                    (json_int_t)json_array_size(pub)));
}

static http_resp scene_get(http_req *req)
{
    app *a = req->app;
    json_t *doc;
    glint_err e;
    if (store_scene_get(a->store, req->param[0], &doc, &e))
        return api_fail(&e, "scene");
    {
        http_resp r = http_json(200, api_scene_public(doc));
        json_decref(doc);
        return r;
    }
}

static http_resp scene_delete(http_req *req)
{
    app *a = req->app;
    http_resp deny;
    glint_err e;
    if (auth_require_key(req, &deny))
        return deny;
    if (store_scene_delete(a->store, req->param[0], &e))
        return api_fail(&e, "scene");
    return http_bytes(204, NULL, "", 0);
}

/* ---- per-view images ------------------------------------------------------------------ */

/* The scene doc and a view index from the path (404 when either is unknown). */
static http_resp scene_view_arg(http_req *req, json_t **doc, int *k)
{
    app *a = req->app;
    glint_err e;
    int n;
    if (store_scene_get(a->store, req->param[0], doc, &e))
        return api_fail(&e, "scene");
    n = (int)json_array_size(json_object_get(*doc, "views"));
    if (api_view_index(req->param[1], n, k)) {
        json_decref(*doc);
        *doc = NULL;
        return http_problem(404, "not-found", "scene %s has no view \"%.16s\" (views 0..%d)",
                            req->param[0], req->param[1], n - 1);
    }
    return (http_resp){0, NULL};
}

static http_resp image_response(const img *im, const char *format)
{
    void *data = NULL;
    size_t len = 0;
    glint_err e;
    int exr = strcmp(format, "exr") == 0;
    if (img_write_mem(exr ? "exr" : "png", im, &data, &len, &e))
        return api_fail(&e, "encoding the image");
    return http_bytes_owned(200, exr ? "image/x-exr" : "image/png", data, len);
}

static http_resp scene_base(http_req *req)
{
    app *a = req->app;
    json_t *doc = NULL;
    const char *fmt = http_query(req, "format"), *spec = http_query(req, "brdf"),
               *scale_q = http_query(req, "scale"), *int_q = http_query(req, "intensity");
    http_resp r;
    img im;
    glint_err e;
    int k;

    memset(&im, 0, sizeof im);
    if (!fmt)
        fmt = "png";
    if (strcmp(fmt, "png") && strcmp(fmt, "exr"))
        return http_problem(422, "invalid-input", "format \"%.16s\" is not png or exr", fmt);
    r = scene_view_arg(req, &doc, &k);
    if (r.r)
        return r;
    if (!spec && !scale_q && !int_q) {
        /* the base every session paints over (cached) */
        if (store_scene_base(a->store, req->param[0], k, &im, &e))
            r = api_fail(&e, "base render");
        else
            r = image_response(&im, fmt);
    } else {
        const scene *sc = NULL;
        scene_view view;
        brdf b;
        gbuf g;
        double scale = json_number_value(json_object_get(json_object_get(doc, "base"), "scale"));
        char *end;
        memset(&g, 0, sizeof g);
        if (!spec)
            spec = json_string_value(json_object_get(json_object_get(doc, "base"), "brdf"));
        if (brdf_parse(spec ? spec : API_BASE_BRDF, &b, &e)) {
            r = http_problem(422, "invalid-input", "brdf: %s", e.msg);
            goto custom_done;
        }
        if (scale_q) {
            scale = strtod(scale_q, &end);
            if (end == scale_q || *end || !isfinite(scale) || !(scale > 0.0) || scale > 1e6) {
                r = http_problem(422, "invalid-input", "scale \"%.32s\" is not a number in (0, 1e6]",
                                 scale_q);
                goto custom_done;
            }
        }
        if (store_scene_acquire(a->store, req->param[0], &sc, &e)) {
            r = api_fail(&e, "scene");
            goto custom_done;
        }
        view = sc->views[k];
        if (int_q) {
            view.light_intensity = strtod(int_q, &end);
            if (end == int_q || *end || !isfinite(view.light_intensity) ||
                !(view.light_intensity > 0.0) || view.light_intensity > 1e6) {
                r = http_problem(422, "invalid-input",
                                 "intensity \"%.32s\" is not a number in (0, 1e6]", int_q);
                goto custom_done;
            }
        }
        if (raster_view(&sc->mesh, &view, sc->width, sc->height, &g, &e) ||
            paint_views(&b, &g, &view, 1, scale, &im, NULL, &e))
            r = api_fail(&e, "rendering");
        else
            r = image_response(&im, fmt);
custom_done:
        gbuf_free(&g);
        store_scene_release(a->store, sc);
    }
    img_free(&im);
    json_decref(doc);
    return r;
}

static http_resp scene_gbuffer(http_req *req)
{
    app *a = req->app;
    json_t *doc = NULL;
    const scene *sc = NULL;
    gbuf g;
    char dir[4200], path[4300], rnd[33];
    char *data = NULL;
    size_t len = 0;
    glint_err e;
    http_resp r;
    int k;

    memset(&g, 0, sizeof g);
    r = scene_view_arg(req, &doc, &k);
    if (r.r)
        return r;
    json_decref(doc);
    snprintf(dir, sizeof dir, "%s/tmp", a->cfg.data_dir);
    if (store_new_id(rnd, &e) || fsio_mkdirs(dir, &e))
        return api_fail(&e, "G-buffer");
    snprintf(path, sizeof path, "%s/gbuffer-%s.exr", dir, rnd);
    if (store_scene_acquire(a->store, req->param[0], &sc, &e))
        return api_fail(&e, "scene");
    if (raster_view(&sc->mesh, &sc->views[k], sc->width, sc->height, &g, &e) ||
        gbuf_write_exr(&g, path, &e) || fsio_read_all(path, (size_t)1 << 31, &data, &len, &e))
        r = api_fail(&e, "G-buffer");
    else
        r = http_bytes_owned(200, "image/x-exr", data, len);
    unlink(path);
    gbuf_free(&g);
    store_scene_release(a->store, sc);
    return r;
}

const http_route api_scenes_routes[] = {
    {"POST", "/api/v1/meshes", mesh_create},
    {"GET", "/api/v1/meshes/{id}", mesh_get},
    {"POST", "/api/v1/scenes", scene_create_h},
    {"GET", "/api/v1/scenes", scene_list},
    {"GET", "/api/v1/scenes/{id}", scene_get},
    {"DELETE", "/api/v1/scenes/{id}", scene_delete},
    {"GET", "/api/v1/scenes/{id}/views/{k}/base.png", scene_base},
    {"GET", "/api/v1/scenes/{id}/views/{k}/gbuffer.exr", scene_gbuffer},
};
const int api_scenes_nroutes = sizeof api_scenes_routes / sizeof api_scenes_routes[0];
