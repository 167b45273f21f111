/* api_exports.c: a material in the formats other tools read (proto/openapi.yaml,
 * "fits, jobs, materials, methods").
 *
 *   GET /api/v1/materials/{id}/merl.binary    a MERL table (merl.h)
 *   GET /api/v1/materials/{id}/material.brdf  BRDF Explorer's analytic .brdf
 *   GET /api/v1/materials/{id}/material.glb   the scene's mesh with a glTF 2.0
 *                                             metallic-roughness material (gltf.h),
 *                                             textures baked where it varies over
 *                                             the surface (?bake_res=N)
 *
 * Each reads the material as GET /materials/{id} does (the session's
 * token), computes on request and holds its memory against the work budget
 * where that is large. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "api_common.h"
#include "app.h"
#include "fitsvc.h"
#include "gltf.h"
#include "brdfx.h"
#include "material.h"
#include "merl.h"
#include "merl_material.h"
#include "prep.h"
#include "scene.h"

/* The material as a MERL table (merl.h): 35 MB, computed on request
 * (about 0.5 s for hf3 on two cores, eight times that for an anisotropic
 * material, averaged over half-vector azimuths), held against the work
 * budget while it is made. */
static http_resp merl_get(http_req *req)
{
    app *a = req->app;
    memo_doc doc;
    material m = {0};
    merl_table t = {0};
    merl_stats st;
    void *data = NULL;
    size_t len = 0, bytes = 2 * MERL_FILE_BYTES;
    http_resp r;
    glint_err e;
    char info[200];
    int rc;
    admit_ticket ticket = {0};

    if ((rc = api_material(req, req->param[0], &doc, &e)))
        return api_error(&e);
    free(doc.text);
    api_work_ticket(req, bytes, 1, &ticket);
    if ((rc = admit_take(a->work, &ticket, "a MERL table", 0, &e)))
        return api_error(&e);
    if ((rc = api_material_load(a, req->param[0], &m, &e)) ||
        (rc = merl_from_material(&m, 0, &t, &st, &e)) ||
        (rc = merl_write_mem(&t, &data, &len, &e)))
        goto done;
    r = http_bytes_owned(200, "application/octet-stream", data, len);
    snprintf(info, sizeof info,
             "anisotropic=%d; azimuths=%d; spatial_average=%d; below_horizon=%ld; nonfinite=%ld; "
             "negative=%ld; max_f=%.6g; ms=%.1f",
             st.anisotropic, st.azimuths, st.spatial, st.below_horizon, st.nonfinite,
             st.negative, st.max_f, 1e3 * st.seconds);
    http_header(&r, "X-Glint-Merl", info);
    http_header(&r, "Content-Disposition", "attachment; filename=\"material.binary\"");
done:
    if (rc)
        r = api_error(&e);
    merl_free(&t);
    material_free(&m);
    admit_give(a->work, &ticket);
    return r;
}

/* The material as BRDF Explorer's analytic .brdf file (every method; 422
 * naming the MERL table for a texture too large to embed, brdfx.h). */
static http_resp brdf_get(http_req *req)
{
    material m = {0};
    char *text = NULL;
    http_resp r;
    glint_err e;
    int rc;

    if ((rc = api_material_read(req, req->param[0], &m, &e)))
        return api_error(&e);
    rc = brdfx_material(&m, &text, &e);
    material_free(&m);
    if (rc)
        return rc == GLINT_EUNSUPPORTED ? http_problem(422, "unsupported", "%s", e.msg)
                                        : api_error(&e);
    r = http_bytes_owned(200, "text/plain; charset=utf-8", text, strlen(text));
    http_header(&r, "Content-Disposition", "attachment; filename=\"material.brdf\"");
    return r;
}

/* The glTF 2.0 file: the scene's mesh with the metallic-roughness material
 * fitted at the samples of the views the material was fitted to
 * (views_used), and baked into textures of bake_res x bake_res texels
 * (query, 0..GLTF_BAKE_RES_MAX, default GLTF_BAKE_RES_DEFAULT; 0: the
 * average only) where the material varies over the surface. */
static http_resp glb_get(http_req *req)
{
    app *a = req->app;
    const char *mid = req->param[0];
    memo_doc doc = {{0}, {0}, NULL, 0};
    material m = {0};
    cache_entry *se = NULL;
    const scene *sc;
    unsigned char use[SCENE_MAX_VIEWS];
    json_t *d = NULL, *vu, *x;
    gltf_pbr p;
    gltf_export_info gi;
    const char *bq = http_query(req, "bake_res");
    long long bake_res = GLTF_BAKE_RES_DEFAULT;
    void *glb = NULL;
    size_t len = 0, bytes = 0, i;
    http_resp r;
    glint_err e;
    char info[400];
    int rc;
    admit_ticket ticket = {0};

    if (bq && (api_parse_count(bq, &bake_res) || bake_res > GLTF_BAKE_RES_MAX))
        return http_problem(400, "invalid-parameter",
                            "bake_res must be an integer in 0..%d (0: no textures)",
                            GLTF_BAKE_RES_MAX);
    if ((rc = api_material(req, mid, &doc, &e)))
        return api_error(&e);
    if ((rc = fitsvc_scene(a->fits, doc.scene, &se, &e))) {
        if (rc == GLINT_ENOTFOUND)
            api_reject(&e, rc, "scene-gone", "the material's scene no longer exists");
        goto done;
    }
    sc = prep_scene_of(se)->sc;
    memset(use, 0, sizeof use);
    d = json_loadb(doc.text, doc.len, 0, NULL);
    vu = d ? json_object_get(d, "views_used") : NULL;
    if (json_array_size(vu) == 0) {
        memset(use, 1, sizeof use);
    } else {
        json_array_foreach(vu, i, x)
            if (json_is_integer(x) && json_integer_value(x) >= 0 &&
                json_integer_value(x) < sc->nviews)
                use[json_integer_value(x)] = 1;
    }
    bytes = (size_t)sc->nviews * sc->width * sc->height * 64 +
            (size_t)sc->mesh.nverts * 32 + (size_t)sc->mesh.ntris * 12 +
            (size_t)bake_res * (size_t)bake_res * 64 + ((size_t)2 << 20); /* textures, tables */
    api_work_ticket(req, bytes, 1, &ticket);
    if ((rc = admit_take(a->work, &ticket, "a glTF export", 0, &e)))
        goto done;
    if ((rc = api_material_load(a, mid, &m, &e)) ||
        (rc = gltf_export_scene(&m, sc, use, (int)bake_res, &glb, &len, &p, &gi, &e)))
        goto done;
    r = http_bytes_owned(200, "model/gltf-binary", glb, len);
    snprintf(info, sizeof info,
             "base_color=%.4f,%.4f,%.4f; metallic=%.4f; roughness=%.4f; fit_rel_rms=%.4f; "
             "pairs=%d; spatial=%d; textures=%d",
             p.base[0], p.base[1], p.base[2], p.metallic, p.roughness, p.rel_rms, p.pairs,
             p.spatial, gi.baked ? gi.res : 0);
    if (gi.baked)
        snprintf(info + strlen(info), sizeof info - strlen(info),
                 "; texel_rel_rms_median=%.4f; texel_rel_rms_max=%.4f; bake_seconds=%.3f",
                 gi.rel_rms_median, gi.rel_rms_max, gi.seconds);
    http_header(&r, "X-Glint-Gltf", info);
    http_header(&r, "Content-Disposition", "attachment; filename=\"material.glb\"");
done:
    if (rc)
        r = api_error(&e);
    admit_give(a->work, &ticket);
    json_decref(d);
    material_free(&m);
    cache_release(a->cache, se);
    free(doc.text);
    return r;
}

const http_route api_exports_routes[] = {
    {"GET", "/api/v1/materials/{id}/merl.binary", merl_get},
    {"GET", "/api/v1/materials/{id}/material.brdf", brdf_get},
    {"GET", "/api/v1/materials/{id}/material.glb", glb_get},
};
const int api_exports_nroutes = sizeof api_exports_routes / sizeof api_exports_routes[0];
