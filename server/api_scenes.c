/* api_scenes.c: scenes and uploaded meshes (proto/openapi.yaml, section
 * "scenes, meshes, sessions...").
 *
 *   POST   /api/v1/meshes?format=ply|obj|off|gltf|glb|dae   raw mesh file   (API key)
 *   GET    /api/v1/meshes/{id}
 *   POST   /api/v1/scenes                                   SceneCreate     (API key)
 *   GET    /api/v1/scenes                                                   (API key)
 *   GET    /api/v1/scenes/{id}
 *   DELETE /api/v1/scenes/{id}                                              (API key)
 * (a view's base render and G-buffer: api_views.c)
 *
 * Reading a scene or mesh by id needs no key: ids are 128 random bits.
 * Everything numerical is core's: scene_create / scene_from_json build and
 * validate, prep_sample_counts counts samples, mesh_refs_check and
 * mesh_load_mem read uploads (one that names any other file is refused).
 * Helpers return 0 or a code with a glint_err; handlers answer failures
 * with api_error(). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "api_common.h"
#include "app.h"
#include "auth.h"
#include "clock.h"
#include "env.h"
#include "fitsvc.h"
#include "ids.h"
#include "img.h"
#include "mesh.h"
#include "prep.h"
#include "render.h"
#include "scene.h"
#include "scenes.h"
#include "store.h"

#define API_DEFAULT_SIZE 128
#define API_MAX_PAINT_SCALE 4

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
    if (pub) {
        json_object_del(pub, "scene");
        json_object_del(pub, "owner");
    }
    return pub;
}

/* ---- meshes ------------------------------------------------------------------ */

static const char *const api_mesh_formats[] = {"ply", "obj", "off", "gltf", "glb", "dae", NULL};

static int mesh_create_do(http_req *req, json_t **info, char id[33], glint_err *e)
{
    app *a = req->app;
    const char *fmt = http_query(req, "format");
    char now[GLINT_TIME_LEN];
    mesh_report rep;
    mesh m;
    int ok = 0, rc;

    if ((rc = auth_require_key(req, e)))
        return rc;
    if (req->body_too_large)
        return api_reject(e, GLINT_ETOOBIG, "body-too-large",
                          "the mesh file exceeds the request body limit of %zu bytes "
                          "(max_body, glintd --max-body-mb %zu)",
                          a->cfg.lim.max_body, a->cfg.lim.max_body >> 20);
    if (!fmt)
        return api_reject(e, GLINT_EINVAL, "missing-parameter",
                          "query parameter format is required: ply, obj, off, gltf, glb or dae");
    for (int i = 0; api_mesh_formats[i]; i++)
        ok |= strcmp(fmt, api_mesh_formats[i]) == 0;
    if (!ok)
        return api_reject(e, GLINT_EINVAL, "invalid-input",
                          "format \"%.32s\" is not one of ply, obj, off, gltf, glb, dae", fmt);
    if (req->body_len == 0)
        return api_reject(e, GLINT_EINVAL, "empty-body", "the body must be the mesh file (%s)",
                          fmt);
    /* every reference to another file is refused, used by the import or not */
    if ((rc = mesh_refs_check(req->body, req->body_len, fmt, e)))
        return api_reject(e, GLINT_EINVAL, "invalid-mesh", "the %s file cannot be used: %.400s",
                          fmt, e->msg);
    /* counts over the limit are refused before the import (mesh_prescan.c) */
    rc = mesh_load_mem_max(req->body, req->body_len, fmt, a->cfg.lim.max_mesh_tris, &m, &rep, e);
    if (rc == GLINT_ERANGE)
        return api_reject(e, GLINT_ETOOBIG, "mesh-too-large",
                          "mesh file rejected: %.400s (max_mesh_tris, glintd --max-mesh-tris "
                          "%d)", e->msg, a->cfg.lim.max_mesh_tris);
    if (rc == GLINT_ENOMEM || rc == GLINT_EIO || rc == GLINT_EINTERNAL)
        return glint_err_prefix(e, "loading the mesh");
    if (rc)
        return api_reject(e, GLINT_EINVAL, "invalid-mesh", "the %s file cannot be used: %.400s",
                          fmt, e->msg);
    if (m.ntris > a->cfg.lim.max_mesh_tris) {
        int n = m.ntris;
        mesh_free(&m);
        return api_reject(e, GLINT_ETOOBIG, "mesh-too-large",
                          "the mesh has %d triangles, more than the limit of %d (max_mesh_tris, "
                          "glintd --max-mesh-tris)",
                          n, a->cfg.lim.max_mesh_tris);
    }
    if ((rc = glint_id_new(id, e))) {
        mesh_free(&m);
        return rc;
    }
    glint_time_iso_ms(now);
    *info = json_pack("{s:s, s:s, s:i, s:i, s:I, s:s, s:{s:i, s:b, s:b, s:i, s:i, s:i, s:f, "
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
    if (!*info)
        return glint_err_set(e, GLINT_ENOMEM, "cannot build the mesh record");
    if ((rc = store_mesh_put(a->store, id, *info, req->body, req->body_len, e))) {
        json_decref(*info);
        *info = NULL;
        return glint_err_prefix(e, "storing the mesh");
    }
    return 0;
}

static http_resp mesh_create(http_req *req)
{
    json_t *info = NULL;
    char id[33];
    glint_err e;
    if (mesh_create_do(req, &info, id, &e))
        return api_error(&e);
    return api_created(info, "meshes", id);
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

/* The raster size of a creation request (OUT: *w, *h). */
static int scene_size(app *a, const json_t *body, long long *w, long long *h, glint_err *e)
{
    const char *names[2] = {"width", "height"};
    long long *dst[2] = {w, h};
    int max_dim = a->cfg.lim.max_image_dim < SCENE_MAX_SIZE ? a->cfg.lim.max_image_dim
                                                            : SCENE_MAX_SIZE;
    *w = *h = API_DEFAULT_SIZE;
    for (int i = 0; i < 2; i++) {
        json_t *j = json_object_get(body, names[i]);
        if (!j)
            continue;
        if (!json_is_integer(j))
            return api_reject(e, GLINT_EINVAL, "invalid-input", "%s: expected an integer, got %s",
                              names[i], api_kind(j));
        *dst[i] = json_integer_value(j);
        if (*dst[i] > max_dim)
            return api_reject(e, GLINT_EINVAL, "image-too-large",
                              "%s %lld exceeds the limit of %d pixels (max_image_dim, "
                              "glintd --max-image-dim)",
                              names[i], *dst[i], max_dim);
        if (*dst[i] < SCENE_MIN_SIZE)
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "%s %lld is below the minimum of %d", names[i], *dst[i],
                              SCENE_MIN_SIZE);
    }
    return 0;
}

/* The painting's scale of a creation request: "paint_scale", 1 (the
 * default: paint at the raster) to API_MAX_PAINT_SCALE, with the painted
 * image within max_image_dim.  OUT: *s. */
static int scene_paint_scale(app *a, const json_t *body, int w, int h, int *s, glint_err *e)
{
    json_t *j = json_object_get(body, "paint_scale");
    long long v;
    *s = 1;
    if (!j)
        return 0;
    if (!json_is_integer(j) || (v = json_integer_value(j)) < 1 || v > API_MAX_PAINT_SCALE)
        return api_reject(e, GLINT_EINVAL, "invalid-input",
                          "paint_scale: expected an integer 1..%d (the painted image is that "
                          "many times the raster a side)", API_MAX_PAINT_SCALE);
    if (v * (w > h ? w : h) > a->cfg.lim.max_image_dim)
        return api_reject(e, GLINT_EINVAL, "image-too-large",
                          "paint_scale %lld makes %lldx%lld paintings, beyond the limit of %d "
                          "pixels a side (max_image_dim, glintd --max-image-dim)",
                          v, v * w, v * h, a->cfg.lim.max_image_dim);
    *s = (int)v;
    return 0;
}

/* The base render at the paint size (what every session paints over, and
 * every view shows) within the work budget: a scene whose base renders
 * could never be admitted is refused when it is made (413, over-budget),
 * not left to answer 413 for every view. */
static int scene_within_budget(app *a, const scene *sc, int ps, const json_t *base_env,
                               glint_err *e)
{
    int lights = base_env ? (int)json_integer_value(json_object_get(base_env, "lights")) : 0;
    size_t bytes = scenes_base_bytes(sc->width, sc->height, ps, lights);
    admit_stats st;

    if (!a->work)
        return 0;
    admit_get_stats(a->work, &st);
    if (bytes <= st.budget)
        return 0;
    return api_reject(e, GLINT_ETOOBIG, "over-budget",
                      "paint_scale %d makes %dx%d base renders (what every view shows and "
                      "sessions paint over), which need up to %.0f MiB, beyond the %.0f MiB "
                      "this daemon gives expensive work (glintd --work-mb): ask for a smaller "
                      "width, height or paint_scale",
                      ps, ps * sc->width, ps * sc->height, (double)bytes / 1048576.0,
                      (double)st.budget / 1048576.0);
}

/* The mesh of a creation request: a built-in name or an uploaded mesh id
 * (checked to exist).  OUT: *builtin, *mesh_id (borrowed from body). */
static int scene_mesh(app *a, const json_t *body, const char **builtin, const char **mesh_id,
                      glint_err *e)
{
    json_t *jmesh = json_object_get(body, "mesh"), *jmesh_id = json_object_get(body, "mesh_id");
    json_t *info;

    *builtin = "sphere";
    *mesh_id = NULL;
    if (jmesh && jmesh_id)
        return api_reject(e, GLINT_EINVAL, "invalid-input",
                          "give either mesh (a built-in) or mesh_id (an uploaded mesh), not both");
    if (jmesh) {
        if (!json_is_string(jmesh))
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "mesh: expected a string (sphere, torus or teapot), got %s",
                              api_kind(jmesh));
        *builtin = json_string_value(jmesh);
        if (strcmp(*builtin, "sphere") && strcmp(*builtin, "torus") && strcmp(*builtin, "teapot"))
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "mesh: \"%.64s\" is not a built-in (sphere, torus, teapot); "
                              "upload a file with POST /api/v1/meshes and pass mesh_id",
                              *builtin);
    }
    if (jmesh_id) {
        if (!json_is_string(jmesh_id))
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "mesh_id: expected a string, got %s", api_kind(jmesh_id));
        *mesh_id = json_string_value(jmesh_id);
        if (store_mesh_get(a->store, *mesh_id, &info, e))
            return e->code == GLINT_ENOTFOUND
                       ? api_reject(e, GLINT_EINVAL, "unknown-mesh", "mesh_id: %.400s", e->msg)
                       : glint_err_prefix(e, "mesh_id");
        json_decref(info);
    }
    return 0;
}

/* The views of a creation request (a view set with light angles, or
 * explicit views) on the mesh named `builtin`.  OUT: *sc, *view_set. */
static int scene_views(app *a, const json_t *body, const char *builtin, long long width,
                       long long height, scene *sc, const char **view_set, glint_err *e)
{
    json_t *jviews = json_object_get(body, "views"), *jangles = json_object_get(body, "light_angles");
    int rc;

    if (!jviews || json_is_string(jviews)) {
        scene_params p;
        const char *set = jviews ? json_string_value(jviews) : "ico12";
        scene_params_default(&p);
        if (strcmp(set, "ico12") == 0)
            p.view_set = SCENE_VIEWS_ICO12;
        else if (strcmp(set, "ico20") == 0)
            p.view_set = SCENE_VIEWS_ICO20;
        else
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "views: \"%.32s\" is not \"ico12\", \"ico20\" or an array of views",
                              set);
        *view_set = p.view_set == SCENE_VIEWS_ICO12 ? "ico12" : "ico20";
        if ((p.view_set == SCENE_VIEWS_ICO12 ? 12 : 20) > a->cfg.lim.max_views)
            return api_reject(e, GLINT_EINVAL, "too-many-views",
                              "views: %s has more views than the limit of %d (max_views)", set,
                              a->cfg.lim.max_views);
        if (jangles) {
            if (!json_is_array(jangles) || json_array_size(jangles) != 2 ||
                !json_is_number(json_array_get(jangles, 0)) ||
                !json_is_number(json_array_get(jangles, 1)))
                return api_reject(e, GLINT_EINVAL, "invalid-input",
                                  "light_angles: expected [lo, hi] in degrees");
            p.light_lo_deg = json_number_value(json_array_get(jangles, 0));
            p.light_hi_deg = json_number_value(json_array_get(jangles, 1));
        }
        snprintf(p.mesh_name, sizeof p.mesh_name, "%s", builtin);
        p.width = (int)width;
        p.height = (int)height;
        if ((rc = scene_create(&p, sc, e)))
            return glint_err_prefix(e, "scene");
        return 0;
    }
    if (json_is_array(jviews)) {
        json_t *doc, *arr, *v;
        char *text;
        size_t n = json_array_size(jviews), i;
        if (jangles)
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "light_angles applies to the ico12 and ico20 view sets; explicit "
                              "views give each light");
        if (n == 0)
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "views: empty (give 1 view or more)");
        if (n > (size_t)a->cfg.lim.max_views)
            return api_reject(e, GLINT_EINVAL, "too-many-views",
                              "views: %zu views, more than the limit of %d (max_views)", n,
                              a->cfg.lim.max_views);
        *view_set = "explicit";
        arr = json_array();
        json_array_foreach(jviews, i, v)
            json_array_append_new(arr, scene_view_defaults(v));
        doc = json_pack("{s:s, s:i, s:s, s:I, s:I, s:o}", "format", "glint-scene", "version", 1,
                        "mesh", builtin, "width", (json_int_t)width, "height",
                        (json_int_t)height, "views", arr);
        text = doc ? json_dumps(doc, JSON_COMPACT | JSON_REAL_PRECISION(17)) : NULL;
        json_decref(doc);
        if (!text)
            return glint_err_set(e, GLINT_ENOMEM, "out of memory building the scene");
        rc = scene_from_json(text, sc, e);
        free(text);
        if (rc) {
            /* scene_from_json names fields "scene.views[k].x"; the API's are "views[k].x" */
            if (strncmp(e->msg, "scene.", 6) == 0)
                memmove(e->msg, e->msg + 6, strlen(e->msg + 6) + 1);
            return glint_err_kind(e, "invalid-input");
        }
        return 0;
    }
    return api_reject(e, GLINT_EINVAL, "invalid-input",
                      "views: expected \"ico12\", \"ico20\" or an array of views, got %s",
                      api_kind(jviews));
}

/* Build the core scene a creation request asks for.  OUT: *sc (scene_free),
 * mesh_label ("sphere", ..., "upload"), *view_set. */
static int scene_build(app *a, const json_t *body, scene *sc, char *mesh_label,
                       size_t label_len, const char **view_set, glint_err *e)
{
    static const char *const keys[] = {"mesh", "mesh_id", "width", "height", "views",
                                       "light_angles", "base", "paint_scale", NULL};
    const char *k, *builtin, *mesh_id;
    long long width, height;
    json_t *v;
    int rc;

    memset(sc, 0, sizeof *sc);
    json_object_foreach((json_t *)body, k, v) {
        int known = 0;
        for (int i = 0; keys[i]; i++)
            known |= strcmp(k, keys[i]) == 0;
        if (!known)
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "unknown key \"%.64s\" (known: mesh, mesh_id, width, height, "
                              "views, light_angles, base, paint_scale)", k);
    }
    if ((rc = scene_mesh(a, body, &builtin, &mesh_id, e)) ||
        (rc = scene_size(a, body, &width, &height, e)) ||
        (rc = scene_views(a, body, mesh_id ? "sphere" : builtin, width, height, sc, view_set,
                          e)))
        return rc;
    if (mesh_id) {
        void *data = NULL;
        size_t len = 0;
        char fmt[16];
        mesh_free(&sc->mesh);
        rc = store_mesh_data(a->store, mesh_id, &data, &len, fmt, e);
        if (!rc)
            rc = mesh_load_mem(data, len, fmt, &sc->mesh, &sc->mesh_info, e);
        free(data);
        if (rc) {
            scene_free(sc);
            return glint_err_prefix(e, "loading the uploaded mesh");
        }
        snprintf(sc->mesh_name, sizeof sc->mesh_name, "upload:%s", mesh_id);
        if ((rc = scene_validate(sc, e))) {
            scene_free(sc);
            return glint_err_prefix(e, "scene");
        }
    }
    snprintf(mesh_label, label_len, "%s", mesh_id ? "upload" : builtin);
    return 0;
}

/* The base-render settings of a creation request: {"brdf", "scale",
 * "env"}; OUT *env: the environment's record (NULL: the views' point
 * lights), checked to resolve. */
static int scene_base_settings(const json_t *body, const char **spec, double *scale,
                               json_t **env, glint_err *e)
{
    json_t *b = json_object_get(body, "base"), *j;
    *spec = API_BASE_BRDF;
    *scale = API_BASE_SCALE;
    *env = NULL;
    if (!b)
        return 0;
    if (!json_is_object(b))
        return api_reject(e, GLINT_EINVAL, "invalid-input",
                          "base: expected {\"brdf\": spec, \"scale\": s, \"env\": {...}}");
    if ((j = json_object_get(b, "env"))) {
        render_env re;
        env_map m;
        int rc;
        if ((rc = api_env_parse(j, "base.env", &re, e)))
            return rc;
        if ((rc = env_resolve(re.spec, &m, e)))
            return rc == GLINT_ENOTFOUND ? api_reject(e, GLINT_ENOTFOUND, "not-found",
                                                      "base.env: %.400s", e->msg)
                                         : glint_err_prefix(e, "base.env");
        env_map_free(&m);
        if (!(*env = api_env_json(&re)))
            return glint_err_set(e, GLINT_ENOMEM, "out of memory");
    }
    if ((j = json_object_get(b, "brdf"))) {
        if (!json_is_string(j))
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "base.brdf: expected a string, got %s", api_kind(j));
        *spec = json_string_value(j);
        if (render_brdf_check(*spec, e))
            return api_reject(e, GLINT_EINVAL, "invalid-input", "base.brdf: %.400s", e->msg);
    }
    if ((j = json_object_get(b, "scale"))) {
        if (!json_is_number(j) || !(json_number_value(j) > 0.0) || json_number_value(j) > 1e6)
            return api_reject(e, GLINT_EINVAL, "invalid-input",
                              "base.scale: expected a number in (0, 1e6]");
        *scale = json_number_value(j);
    }
    return 0;
}

/* The scene document: ids, sizes, views with their sample counts and links. */
static json_t *scene_doc(const scene *sc, const char *id, const char *label,
                         const char *view_set, const long *counts, long total,
                         const char *base_spec, double base_scale, json_t *base_env,
                         glint_err *e)
{
    char hash[33], now[GLINT_TIME_LEN], *text;
    json_t *views = json_array(), *js, *doc;

    scene_hash(sc, hash);
    glint_time_iso_ms(now);
    text = scene_to_json(sc, e);
    js = text ? json_loads(text, 0, NULL) : NULL;
    free(text);
    for (int k = 0; views && k < sc->nviews; k++) {
        const scene_view *v = &sc->views[k];
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
        json_array_append_new(views, jv);
    }
    if (!js || !views) {
        json_decref(js);
        json_decref(views);
        glint_err_set(e, GLINT_ENOMEM, "cannot serialize the scene");
        return NULL;
    }
    doc = json_pack("{s:s, s:s, s:s, s:i, s:i, s:s, s:o, s:I, s:s, s:{s:s, s:f}, s:o, s:s}",
                    "id", id, "hash", hash, "mesh", label, "width", sc->width, "height",
                    sc->height, "view_set", view_set, "views", views, "samples",
                    (json_int_t)total, "created", now, "base", "brdf", base_spec, "scale",
                    base_scale, "scene", js, "radiance", STORE_SCENE_RADIANCE);
    if (doc && strcmp(label, "upload") == 0)
        json_object_set_new(doc, "mesh_id", json_string(sc->mesh_name + 7));
    if (doc && base_env)
        json_object_set(json_object_get(doc, "base"), "env", base_env);
    if (!doc)
        glint_err_set(e, GLINT_ENOMEM, "cannot build the scene record");
    return doc;
}

static int scene_create_do(http_req *req, json_t **pub, char id[33], glint_err *e)
{
    app *a = req->app;
    json_t *body = NULL, *doc = NULL;
    const char *view_set = "ico12", *base_spec, *owner;
    char label[16], made[33];
    double base_scale;
    json_t *base_env = NULL;
    long *counts = NULL, total = 0;
    scene sc;
    int rc, ps = 1;

    memset(&sc, 0, sizeof sc);
    if ((rc = auth_require_key(req, e)) || (rc = auth_owner_key(req, &owner, e)))
        return rc;
    if (req->body_too_large)
        return api_reject(e, GLINT_ETOOBIG, "body-too-large",
                          "the scene request exceeds the request body limit of %zu bytes "
                          "(max_body, glintd --max-body-mb %zu)",
                          a->cfg.lim.max_body, a->cfg.lim.max_body >> 20);
    if ((rc = api_body_json(req, &body, e)))
        return rc;
    if ((rc = scene_base_settings(body, &base_spec, &base_scale, &base_env, e)) ||
        (rc = scene_build(a, body, &sc, label, sizeof label, &view_set, e)) ||
        (rc = scene_paint_scale(a, body, sc.width, sc.height, &ps, e)) ||
        (rc = scene_within_budget(a, &sc, ps, base_env, e)))
        goto done;
    /* samples per view: what a fit of this scene will see */
    if (!(counts = calloc((size_t)sc.nviews, sizeof *counts))) {
        rc = glint_err_set(e, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    rc = prep_sample_counts(&sc, counts, &total, e);
    if (rc == GLINT_EINVAL) {
        rc = api_reject(e, GLINT_EINVAL, "no-samples",
                        "no view sees a lit surface pixel (check the cameras and lights): %.400s",
                        e->msg);
        goto done;
    }
    if (rc || (rc = glint_id_new(id, e)) || (!owner && (rc = glint_id_new(made, e))))
        goto done;
    if (!owner)
        owner = made;
    if (!(doc = scene_doc(&sc, id, label, view_set, counts, total, base_spec, base_scale,
                          base_env, e)) ||
        json_object_set_new(doc, "owner", json_string(owner)) ||
        json_object_set_new(doc, "paint_scale", json_integer(ps)) ||
        json_object_set_new(doc, "paint_width", json_integer((json_int_t)ps * sc.width)) ||
        json_object_set_new(doc, "paint_height", json_integer((json_int_t)ps * sc.height))) {
        rc = doc ? glint_err_set(e, GLINT_ENOMEM, "out of memory") : e->code;
        goto done;
    }
    if ((rc = store_scene_put(a->store, id, doc, e))) {
        glint_err_prefix(e, "storing the scene");
        goto done;
    }
    /* the one answer that carries the owner key */
    if ((*pub = api_scene_public(doc)))
        json_object_set_new(*pub, "owner_key", json_string(owner));
done:
    json_decref(doc);
    json_decref(base_env);
    free(counts);
    scene_free(&sc);
    json_decref(body);
    return rc;
}

static http_resp scene_create_h(http_req *req)
{
    json_t *pub = NULL;
    char id[33];
    glint_err e;
    int rc;
    api_envs_use_begin(); /* base.env may name an upload: not deleted meanwhile */
    rc = scene_create_do(req, &pub, id, &e);
    api_envs_use_end();
    if (rc)
        return api_error(&e);
    return api_created(pub, "scenes", id);
}

static http_resp scene_list(http_req *req)
{
    app *a = req->app;
    json_t *arr, *pub, *v;
    const char *owner = NULL, *o;
    glint_err e;
    size_t i;
    int all = auth_has_key(req);

    if (!all && auth_owner_key(req, &owner, &e))
        return api_error(&e);
    if (!all && !owner) {
        api_reject(&e, GLINT_EAUTH, "owner-key-required",
                   "listing scenes shows your own: send your owner key (\"X-Glint-Owner: "
                   "KEY\", the one your scenes were created with)%s",
                   a->cfg.api_key[0] ? ", or the daemon's API key for all of them" : "");
        return api_error(&e);
    }
    if (store_scene_list(a->store, &arr, &e))
        return api_fail(&e, "listing scenes");
    pub = json_array();
    json_array_foreach(arr, i, v) {
        o = json_string_value(json_object_get(v, "owner"));
        if (all || (o && glint_secret_equal(owner, o)))
            json_array_append_new(pub, api_scene_public(v));
    }
    json_decref(arr);
    return http_json(200, json_pack("{s:o, s:I}", "scenes", pub, "count",
                                    (json_int_t)json_array_size(pub)));
}

static http_resp scene_get(http_req *req)
{
    app *a = req->app;
    json_t *doc;
    glint_err e;
    http_resp r;
    if (store_scene_get(a->store, req->param[0], &doc, &e))
        return api_fail(&e, "scene");
    r = http_json(200, api_scene_public(doc));
    json_decref(doc);
    return r;
}

static http_resp scene_delete(http_req *req)
{
    app *a = req->app;
    json_t *doc;
    glint_err e;
    int rc;
    if (store_scene_get(a->store, req->param[0], &doc, &e))
        return api_fail(&e, "scene");
    rc = auth_scene_owner(req, doc, &e);
    json_decref(doc);
    if (rc)
        return api_error(&e);
    if (store_scene_delete(a->store, req->param[0], &e))
        return api_fail(&e, "scene");
    return http_bytes(204, NULL, "", 0);
}

const http_route api_scenes_routes[] = {
    {"POST", "/api/v1/meshes", mesh_create},
    {"GET", "/api/v1/meshes/{id}", mesh_get},
    {"POST", "/api/v1/scenes", scene_create_h},
    {"GET", "/api/v1/scenes", scene_list},
    {"GET", "/api/v1/scenes/{id}", scene_get},
    {"DELETE", "/api/v1/scenes/{id}", scene_delete},
};
const int api_scenes_nroutes = sizeof api_scenes_routes / sizeof api_scenes_routes[0];
