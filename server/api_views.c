/* api_views.c: a scene's per-view images (proto/openapi.yaml, section
 * "scenes, meshes, sessions...").
 *
 *   GET /api/v1/scenes/{id}/views/{k}/base.png[?format=exr&brdf=&scale=&intensity=&env=&size=]
 *   GET /api/v1/scenes/{id}/views/{k}/gbuffer.exr
 *
 * Reading them needs no key: scene ids are 128 random bits.  Everything
 * numerical is core's: render.h draws base images and G-buffers. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "api_common.h"
#include "app.h"
#include "cancel.h"
#include "fitsvc.h"
#include "img.h"
#include "prep.h"
#include "render.h"
#include "scene.h"
#include "scenes.h"
#include "store.h"

/* ---- per-view images ------------------------------------------------------------------ */

/* The scene doc and a view index from the path (GLINT_ENOTFOUND for either). */
static int scene_view_arg(http_req *req, json_t **doc, int *k, glint_err *e)
{
    app *a = req->app;
    int n;
    if (store_scene_get(a->store, req->param[0], doc, e))
        return glint_err_prefix(e, "scene");
    n = (int)json_array_size(json_object_get(*doc, "views"));
    if (api_view_index(req->param[1], n, k)) {
        json_decref(*doc);
        *doc = NULL;
        return api_reject(e, GLINT_ENOTFOUND, "not-found",
                          "scene %s has no view \"%.16s\" (views 0..%d)", req->param[0],
                          req->param[1], n - 1);
    }
    return 0;
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

/* A number in (0, 1e6] from a query value (0), else -1. */
static int positive_query(const char *text, double *out)
{
    char *end;
    double v = strtod(text, &end);
    if (end == text || *end || !isfinite(v) || !(v > 0.0) || v > 1e6)
        return -1;
    *out = v;
    return 0;
}

/* A base render with other settings than the scene's (not cached), at
 * `ps` times the raster a side. */
static int scene_base_custom(http_req *req, const json_t *doc, int k, int ps, img *im,
                             glint_err *e)
{
    app *a = req->app;
    const char *spec = http_query(req, "brdf"), *scale_q = http_query(req, "scale"),
               *int_q = http_query(req, "intensity");
    double scale = json_number_value(json_object_get(json_object_get(doc, "base"), "scale"));
    cache_entry *se = NULL;
    const scene *sc;
    scene_view view;
    render_env env;
    size_t bytes;
    int rc, has_env, W, H;
    double cost = 0.0;
    glint_cancel cancel;
    admit_ticket ticket;

    api_cancel_init(req, &cancel);
    if ((rc = api_env_query(req, &env, &has_env, e)))
        return rc;
    if (!spec)
        spec = json_string_value(json_object_get(json_object_get(doc, "base"), "brdf"));
    if (!spec)
        spec = API_BASE_BRDF;
    if (render_brdf_check(spec, e))
        return api_reject(e, GLINT_EINVAL, "invalid-input", "brdf: %.400s", e->msg);
    if (scale_q && positive_query(scale_q, &scale))
        return api_reject(e, GLINT_EINVAL, "invalid-input",
                          "scale \"%.32s\" is not a number in (0, 1e6]", scale_q);
    if ((rc = fitsvc_scene(a->fits, req->param[0], &se, e)))
        return glint_err_prefix(e, "scene");
    sc = prep_scene_of(se)->sc;
    view = sc->views[k];
    if (int_q && positive_query(int_q, &view.light_intensity))
        rc = api_reject(e, GLINT_EINVAL, "invalid-input",
                        "intensity \"%.32s\" is not a number in (0, 1e6]", int_q);
    W = sc->width * ps;
    H = sc->height * ps;
    bytes = render_peak_bytes(RENDER_CPU, 1, W, H) +
            (has_env ? (size_t)W * H * 8 * (size_t)((env.lights + 63) / 64) : 0);
    api_work_ticket(req, bytes, 0, &ticket);
    if (!rc && !(rc = render_base_cost(NULL, RENDER_CPU, NULL, &sc->mesh, spec,
                                       has_env ? &env : NULL, W, H, &cost, e)) &&
        !(rc = admit_cost(a->work, cost, "the base render", e)) &&
        !(rc = admit_take(a->work, &ticket, "the base render", 0, e))) {
        /* on the CPU: at scale 1 the pixels are exactly those a painting is sampled at */
        if ((rc = has_env ? render_base_env(NULL, RENDER_CPU, NULL, &sc->mesh, spec, scale, &env,
                                            &view, W, H, im, NULL, NULL, &cancel, e)
                          : render_base(NULL, RENDER_CPU, NULL, &sc->mesh, &view, W, H, spec,
                                        scale, im, NULL, &cancel, e)))
            glint_err_prefix(e, "rendering");
        api_work_ended(req, rc);
        admit_give(a->work, &ticket);
    }
    cache_release(a->cache, se);
    return rc;
}

static http_resp scene_base(http_req *req)
{
    app *a = req->app;
    const char *fmt = http_query(req, "format"), *size = http_query(req, "size");
    json_t *doc = NULL;
    http_resp r;
    glint_err e;
    img im;
    int k, rc, ps;

    memset(&im, 0, sizeof im);
    if (!fmt)
        fmt = "png";
    if (strcmp(fmt, "png") && strcmp(fmt, "exr"))
        return http_problem(422, "invalid-input", "format \"%.16s\" is not png or exr", fmt);
    if (size && strcmp(size, "paint") && strcmp(size, "raster"))
        return http_problem(422, "invalid-input", "size \"%.16s\" is not paint or raster", size);
    if (scene_view_arg(req, &doc, &k, &e))
        return api_error(&e);
    /* the painting's size (the scene's paint_scale times the raster), or the raster's */
    ps = size && !strcmp(size, "raster") ? 1 : scenes_paint_scale(doc);
    if (!http_query(req, "brdf") && !http_query(req, "scale") && !http_query(req, "intensity") &&
        !http_query(req, "env"))
        rc = scenes_base(a, req->param[0], k, ps, &im, &e); /* what every session paints over */
    else
        rc = scene_base_custom(req, doc, k, ps, &im, &e);
    r = rc ? api_fail(&e, "base render") : image_response(&im, fmt);
    img_free(&im);
    json_decref(doc);
    return r;
}

static http_resp scene_gbuffer(http_req *req)
{
    app *a = req->app;
    json_t *doc = NULL;
    cache_entry *se = NULL;
    const scene *sc;
    void *data = NULL;
    size_t len = 0, bytes;
    glint_err e;
    int k, rc;
    admit_ticket ticket;

    if (scene_view_arg(req, &doc, &k, &e))
        return api_error(&e);
    json_decref(doc);
    if (fitsvc_scene(a->fits, req->param[0], &se, &e))
        return api_fail(&e, "scene");
    sc = prep_scene_of(se)->sc;
    bytes = render_gbuffer_peak_bytes(sc->width, sc->height);
    api_work_ticket(req, bytes, 0, &ticket);
    if ((rc = admit_take(a->work, &ticket, "the G-buffer", 0, &e)) == 0) {
        rc = render_gbuffer_exr(&sc->mesh, &sc->views[k], sc->width, sc->height, &data, &len,
                                &e);
        admit_give(a->work, &ticket);
    }
    cache_release(a->cache, se);
    if (rc)
        return api_fail(&e, "G-buffer");
    return http_bytes_owned(200, "image/x-exr", data, len);
}

const http_route api_views_routes[] = {
    {"GET", "/api/v1/scenes/{id}/views/{k}/base.png", scene_base},
    {"GET", "/api/v1/scenes/{id}/views/{k}/gbuffer.exr", scene_gbuffer},
};
const int api_views_nroutes = sizeof api_views_routes / sizeof api_views_routes[0];
