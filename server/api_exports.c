/* api_exports.c: a material in the formats other tools read (proto/openapi.yaml,
 * "fits, jobs, materials, methods").
 *
 *   GET /api/v1/materials/{id}/merl.binary    a MERL table (merl.h)
 *   GET /api/v1/materials/{id}/material.brdf  BRDF Explorer's analytic .brdf
 *   GET /api/v1/materials/{id}/material.glb   the scene's mesh with a glTF 2.0
 *                                             metallic-roughness material (gltf.h),
 *                                             textures baked where it varies over
 *                                             the surface (?bake_res=N)
 *   GET /api/v1/materials/{id}/material.mtlx  that fit as MaterialX standard_surface
 *                                             (mtlx.h)
 *   GET /api/v1/materials/{id}/material.mtlx.zip  the same in a zip with the .glb's
 *                                             textures, read by the document, where
 *                                             it varies (mtlx.h; ?bake_res=N)
 *   GET /api/v1/materials/{id}/material.usda  that fit as a UsdPreviewSurface with
 *                                             the scene's mesh (usda.h)
 *   GET /api/v1/materials/{id}/material.usdz  the same in a USDZ package with the
 *                                             .glb's textures where it varies
 *                                             (usdz.h; ?bake_res=N)
 *   GET /api/v1/materials/{id}/exports        the list of them: file name, what
 *                                             each carries, how close it comes
 *
 * Each reads the material as GET /materials/{id} does (the session's
 * token), computes on request and holds its memory against the work budget
 * where that is large.  Every file is an attachment named
 * "<mesh>-<id8>.<ext>" (api_export_filename).  How close: the glb, mtlx and
 * usda files carry one metallic-roughness fit (gltf_fit_scene), whose
 * relative RMS error against the material on the painted views each
 * states (X-Glint-Gltf / X-Glint-Fit and in the file); merl, brdf and the
 * package carry the material itself. */
#include <math.h>
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
#include "mtlx.h"
#include "prep.h"
#include "scene.h"
#include "usda.h"
#include "usdz.h"

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
    char info[200], fname[128];
    int rc;
    admit_ticket ticket = {0};

    if ((rc = api_material(req, req->param[0], &doc, &e)))
        return api_error(&e);
    free(doc.text);
    doc.text = NULL;
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
    api_export_filename(a, req->param[0], doc.scene, "binary", fname, sizeof fname);
    api_attachment(&r, fname);
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
    memo_doc doc;
    char *text = NULL, fname[128];
    http_resp r;
    glint_err e;
    int rc;

    if ((rc = api_material(req, req->param[0], &doc, &e)))
        return api_error(&e);
    free(doc.text);
    if ((rc = api_material_load(req->app, req->param[0], &m, &e)))
        return api_error(&e);
    rc = brdfx_material(&m, &text, &e);
    material_free(&m);
    if (rc)
        return rc == GLINT_EUNSUPPORTED ? http_problem(422, "unsupported", "%s", e.msg)
                                        : api_error(&e);
    r = http_bytes_owned(200, "text/plain; charset=utf-8", text, strlen(text));
    api_export_filename(req->app, req->param[0], doc.scene, "brdf", fname, sizeof fname);
    api_attachment(&r, fname);
    return r;
}

/* ---- the metallic-roughness exports (glb, mtlx, usda) ---------------------------------------- */

/* What they share: the material's document, its scene (held in the fit
 * service's cache until export_src_close) and the views it was fitted to
 * (views_used; all when it names none). */
typedef struct export_src {
    memo_doc doc;
    cache_entry *se;
    const scene *sc;
    unsigned char use[SCENE_MAX_VIEWS];
} export_src;

static void export_src_close(app *a, export_src *x)
{
    cache_release(a->cache, x->se);
    free(x->doc.text);
    memset(x, 0, sizeof *x);
}

/* the views of views_used (OUT: x->use) */
static void export_src_views(export_src *x)
{
    json_t *d = json_loadb(x->doc.text, x->doc.len, 0, NULL), *vu, *v;
    size_t i;
    memset(x->use, 0, sizeof x->use);
    vu = d ? json_object_get(d, "views_used") : NULL;
    if (json_array_size(vu) == 0)
        memset(x->use, 1, sizeof x->use);
    json_array_foreach(vu, i, v)
        if (json_is_integer(v) && json_integer_value(v) >= 0 &&
            json_integer_value(v) < x->sc->nviews)
            x->use[json_integer_value(v)] = 1;
    json_decref(d);
}

/* The material `mid` if the request may read it, with its scene (OUT: *x;
 * export_src_close, also after a failure). */
static int export_src_open(http_req *req, const char *mid, export_src *x, glint_err *e)
{
    int rc;
    memset(x, 0, sizeof *x);
    if ((rc = api_material(req, mid, &x->doc, e)))
        return rc;
    if ((rc = fitsvc_scene(((app *)req->app)->fits, x->doc.scene, &x->se, e))) {
        if (rc == GLINT_ENOTFOUND)
            api_reject(e, rc, "scene-gone", "the material's scene no longer exists");
        return rc;
    }
    x->sc = prep_scene_of(x->se)->sc;
    export_src_views(x);
    return 0;
}

/* The memory a fit at the scene's samples holds (G-buffers, samples,
 * tables), and what a glTF export adds: the mesh and bake_res^2 texels. */
static size_t export_bytes(const scene *sc, long long bake_res)
{
    return (size_t)sc->nviews * sc->width * sc->height * 64 + (size_t)sc->mesh.nverts * 32 +
           (size_t)sc->mesh.ntris * 12 + (size_t)bake_res * (size_t)bake_res * 64 +
           ((size_t)2 << 20);
}

/* The material fitted as gltf_fit_scene does, held against the work
 * budget while it runs (OUT: *p). */
static int export_fit(http_req *req, const char *mid, const export_src *x, gltf_pbr *p,
                      glint_err *e)
{
    app *a = req->app;
    material m = {0};
    admit_ticket ticket = {0};
    int rc;
    api_work_ticket(req, export_bytes(x->sc, 0), 1, &ticket);
    if ((rc = admit_take(a->work, &ticket, "a material fit for export", 0, e)))
        return rc;
    if (!(rc = api_material_load(a, mid, &m, e)))
        rc = gltf_fit_scene(&m, x->sc, x->use, p, e);
    material_free(&m);
    admit_give(a->work, &ticket);
    return rc;
}

/* "; export=exact|fitted; rel_rms_exact=...; rel_rms_fitted=...;
 * extensions=..." of the headers: which path the material took (its pbr
 * parameters mapped, or the fit) and both errors (gltf.h). */
static void path_info(const gltf_pbr *p, char *out, size_t cap)
{
    const char *names[GLTF_KHR_MAX];
    int n = gltf_khr_names(p, names), k;
    k = snprintf(out, cap, "; export=%s; rel_rms_fitted=%.4f", p->exact ? "exact" : "fitted",
                 p->rel_rms_fitted);
    if (k > 0 && (size_t)k < cap && isfinite(p->rel_rms_exact))
        k += snprintf(out + k, cap - (size_t)k, "; rel_rms_exact=%.4f", p->rel_rms_exact);
    for (int i = 0; i < n && k > 0 && (size_t)k < cap; i++)
        k += snprintf(out + k, cap - (size_t)k, "%s%s", i ? "," : "; extensions=", names[i]);
}

/* X-Glint-Fit: the fit a mtlx or usda file carries. */
static void fit_header(http_resp *r, const gltf_pbr *p)
{
    char info[500];
    int k = snprintf(info, sizeof info,
                     "base_color=%.4f,%.4f,%.4f; metallic=%.4f; roughness=%.4f; fit_rel_rms=%.4f; "
                     "pairs=%d; spatial=%d; textures=0",
                     p->base[0], p->base[1], p->base[2], p->metallic, p->roughness, p->rel_rms,
                     p->pairs, p->spatial);
    path_info(p, info + k, sizeof info - (size_t)k);
    http_header(r, "X-Glint-Fit", info);
}

/* What baked_get answers: its file name's extension, media type, what the
 * work budget calls it, and the header its figures go in. */
typedef struct baked_kind {
    const char *ext, *type, *what, *header;
} baked_kind;

static const baked_kind baked_glb = {"glb", "model/gltf-binary", "a glTF export",
                                     "X-Glint-Gltf"};
static const baked_kind baked_usdz = {"usdz", "model/vnd.usdz+zip", "a USDZ export",
                                      "X-Glint-Fit"};
static const baked_kind baked_mtlx = {"mtlx.zip", "application/zip", "a MaterialX export",
                                      "X-Glint-Fit"};

/* The glTF 2.0 file, the USDZ package or the MaterialX package (kind):
 * the metallic-roughness material fitted at the samples of the views the
 * material was fitted to (views_used), and baked into textures of bake_res
 * x bake_res texels (query, 0..GLTF_BAKE_RES_MAX, default
 * GLTF_BAKE_RES_DEFAULT; 0: the average only) where the material varies
 * over the surface; the .glb and the USD layer with the scene's mesh, the
 * packages' USD layer and MaterialX document reading the same textures. */
static http_resp baked_get(http_req *req, const baked_kind *kind)
{
    app *a = req->app;
    const char *mid = req->param[0];
    export_src x;
    material m = {0};
    gltf_pbr p;
    gltf_export_info gi;
    const char *bq = http_query(req, "bake_res");
    long long bake_res = GLTF_BAKE_RES_DEFAULT;
    void *glb = NULL;
    size_t len = 0, bytes = 0;
    http_resp r;
    glint_err e;
    char info[600], fname[128], name[64];
    int rc, usdz = kind == &baked_usdz;
    admit_ticket ticket = {0};

    if (bq && (api_parse_count(bq, &bake_res) || bake_res > GLTF_BAKE_RES_MAX))
        return http_problem(400, "invalid-parameter",
                            "bake_res must be an integer in 0..%d (0: no textures)",
                            GLTF_BAKE_RES_MAX);
    if ((rc = export_src_open(req, mid, &x, &e)))
        goto done;
    bytes = export_bytes(x.sc, bake_res);
    if (usdz) /* the layer's text (about 80 bytes a vertex, 24 a triangle), then its copy */
        bytes += 2 * ((size_t)x.sc->mesh.nverts * 80 + (size_t)x.sc->mesh.ntris * 24);
    api_work_ticket(req, bytes, 1, &ticket);
    if ((rc = admit_take(a->work, &ticket, kind->what, 0, &e)))
        goto done;
    snprintf(info, sizeof info, "glint material %s.", mid);
    snprintf(name, sizeof name, "glint_%.8s", mid);
    if ((rc = api_material_load(a, mid, &m, &e)) ||
        (rc = usdz ? usdz_export_scene(&m, x.sc, x.use, (int)bake_res, info, &glb, &len, &p,
                                       &gi, &e)
         : kind == &baked_mtlx ? mtlx_export_scene(&m, x.sc, x.use, (int)bake_res, name, info,
                                                   &glb, &len, &p, &gi, &e)
                               : gltf_export_scene(&m, x.sc, x.use, (int)bake_res, &glb, &len,
                                                   &p, &gi, &e)))
        goto done;
    r = http_bytes_owned(200, kind->type, glb, len);
    snprintf(info, sizeof info,
             "base_color=%.4f,%.4f,%.4f; metallic=%.4f; roughness=%.4f; fit_rel_rms=%.4f; "
             "pairs=%d; spatial=%d; textures=%d",
             p.base[0], p.base[1], p.base[2], p.metallic, p.roughness, p.rel_rms, p.pairs,
             p.spatial, gi.baked ? gi.res : 0);
    path_info(&p, info + strlen(info), sizeof info - strlen(info));
    if (gi.baked)
        snprintf(info + strlen(info), sizeof info - strlen(info),
                 "; texel_rel_rms_median=%.4f; texel_rel_rms_max=%.4f; bake_seconds=%.3f",
                 gi.rel_rms_median, gi.rel_rms_max, gi.seconds);
    http_header(&r, kind->header, info);
    api_export_filename(a, mid, x.doc.scene, kind->ext, fname, sizeof fname);
    api_attachment(&r, fname);
done:
    if (rc)
        r = api_error(&e);
    admit_give(a->work, &ticket);
    material_free(&m);
    export_src_close(a, &x);
    return r;
}

static http_resp glb_get(http_req *req) { return baked_get(req, &baked_glb); }
static http_resp usdz_get(http_req *req) { return baked_get(req, &baked_usdz); }
static http_resp mtlx_zip_get(http_req *req) { return baked_get(req, &baked_mtlx); }

/* The MaterialX document of the same fit (the average over the surface). */
static http_resp mtlx_get(http_req *req)
{
    app *a = req->app;
    const char *mid = req->param[0];
    export_src x;
    gltf_pbr p;
    char *text = NULL, fname[128], name[64], note[80];
    http_resp r;
    glint_err e;
    int rc;

    if (!(rc = export_src_open(req, mid, &x, &e)) && !(rc = export_fit(req, mid, &x, &p, &e))) {
        snprintf(name, sizeof name, "glint_%.8s", mid);
        snprintf(note, sizeof note, "glint material %s.", mid);
        rc = mtlx_write(&p, name, note, &text, &e);
    }
    if (rc) {
        export_src_close(a, &x);
        return api_error(&e);
    }
    r = http_bytes_owned(200, "application/xml; charset=utf-8", text, strlen(text));
    fit_header(&r, &p);
    api_export_filename(a, mid, x.doc.scene, "mtlx", fname, sizeof fname);
    api_attachment(&r, fname);
    export_src_close(a, &x);
    return r;
}

/* The USD layer of the same fit, with the scene's mesh (?mesh=0: the
 * material alone). */
static http_resp usda_get(http_req *req)
{
    app *a = req->app;
    const char *mid = req->param[0], *mq = http_query(req, "mesh");
    export_src x;
    gltf_pbr p;
    char *text = NULL, fname[128], note[80];
    size_t len = 0;
    http_resp r;
    glint_err e;
    int rc, with_mesh = 1;

    if (mq && strcmp(mq, "0") && strcmp(mq, "1"))
        return http_problem(400, "invalid-parameter", "mesh must be 0 or 1");
    with_mesh = !mq || strcmp(mq, "0");
    if (!(rc = export_src_open(req, mid, &x, &e)) && !(rc = export_fit(req, mid, &x, &p, &e))) {
        /* the text, twice over while its buffer grows: about 75 bytes a
         * vertex (point, normal, st) and 20 a triangle */
        size_t bytes = with_mesh ? 2 * ((size_t)x.sc->mesh.nverts * 80 +
                                        (size_t)x.sc->mesh.ntris * 24) + ((size_t)1 << 16)
                                 : 0;
        admit_ticket ticket = {0};
        snprintf(note, sizeof note, "glint material %s.", mid);
        api_work_ticket(req, bytes, 1, &ticket);
        if (!(rc = admit_take(a->work, &ticket, "a USD layer", 0, &e))) {
            rc = usda_write(&p, with_mesh ? &x.sc->mesh : NULL, note, &text, &len, &e);
            admit_give(a->work, &ticket);
        }
    }
    if (rc) {
        export_src_close(a, &x);
        return api_error(&e);
    }
    r = http_bytes_owned(200, "model/vnd.usda; charset=utf-8", text, len);
    fit_header(&r, &p);
    api_export_filename(a, mid, x.doc.scene, "usda", fname, sizeof fname);
    api_attachment(&r, fname);
    export_src_close(a, &x);
    return r;
}

/* ---- the list ------------------------------------------------------------------------------ */

/* One format of GET /materials/{id}/exports. */
typedef struct export_kind {
    const char *format, *ext, *path, *carries, *use_in;
    int fitted;    /* carries the metallic-roughness fit (else the material itself) */
    int expensive; /* 1 always, 2 when the material varies over the surface */
} export_kind;

static const export_kind export_kinds[] = {
    {"glb", "glb", "material.glb",
     "the mesh with a glTF 2.0 metallic-roughness material; baked textures where the material "
     "varies over the surface",
     "Blender, game engines, three.js", 1, 2},
    {"mtlx", "mtlx", "material.mtlx",
     "a MaterialX standard_surface with its surfacematerial: the same fit, its average over the "
     "surface (no textures)",
     "MaterialX: Houdini, Maya, Substance", 1, 0},
    {"mtlx_zip", "mtlx.zip", "material.mtlx.zip",
     "a zip of the same MaterialX document and, where the material varies over the surface, "
     "the .glb's baked textures, which it reads",
     "MaterialX: Houdini, Maya, Substance, MaterialX Viewer", 1, 2},
    {"usda", "usda", "material.usda",
     "a USD layer: the mesh bound to a UsdPreviewSurface with the same fit, its average over "
     "the surface (no textures)",
     "USD: Omniverse, Houdini, Blender 4+", 1, 0},
    {"usdz", "usdz", "material.usdz",
     "a USDZ package: the same USD layer with the .glb's baked textures where the material "
     "varies over the surface",
     "USD: Omniverse, Houdini, Blender 4+, Apple Quick Look", 1, 2},
    {"merl", "binary", "merl.binary",
     "the material tabulated as a MERL BRDF table (its average over the surface where it "
     "varies, over half-vector azimuths where it is anisotropic)",
     "measured-BRDF tools: Mitsuba, BRDF Explorer", 0, 1},
    {"brdf", "brdf", "material.brdf", "the material's own formula as an analytic .brdf file",
     "BRDF Explorer", 0, 0},
    {"package", "tar", "package",
     "the manifest (every parameter, error and timing), the factor textures and a GLSL shader",
     "glint, your own shaders", 0, 0},
};

/* How close an export of kind k comes to the material: the fit's relative
 * RMS (p NULL: not known, `why`), or exact. */
static json_t *export_how_close(const export_kind *k, const gltf_pbr *p, int spatial,
                                const char *why)
{
    if (!k->fitted)
        return json_pack("{s:n, s:b, s:s}", "rel_rms", "exact", 1, "note",
                         strcmp(k->format, "merl") == 0
                             ? "the material itself, sampled at the table's directions"
                             : "the material itself");
    if (!p)
        return json_pack("{s:n, s:b, s:s}", "rel_rms", "exact", 0, "note", why);
    if (p->aniso.used && strcmp(k->format, "glb") == 0)
        return json_pack("{s:f, s:b, s:s}", "rel_rms", p->aniso.rel_rms, "exact", 0, "note",
                         "the anisotropic fit (KHR_materials_anisotropy) against the material "
                         "on the painted views (relative RMS)");
    if (p->exact)
        return json_pack("{s:f, s:b, s:s}", "rel_rms", p->rel_rms, "exact", 0, "note",
                         "the pbr material's own parameters (with KHR extensions in the .glb), "
                         "against the material on the painted views (relative RMS)");
    return json_pack("{s:f, s:b, s:s}", "rel_rms", p->rel_rms, "exact", 0, "note",
                     k->expensive == 2 && spatial
                         ? "the average's fit on the painted views; the baked textures come "
                           "closer (their figures come with the download: X-Glint-Gltf, "
                           "X-Glint-Fit)"
                         : "the metallic-roughness fit against the material on the painted "
                           "views (relative RMS)");
}

static json_t *export_entry(const export_kind *k, const char *mid, const char *scene_id,
                            app *a, const gltf_pbr *p, int spatial, const char *why,
                            const char *unavailable)
{
    char fname[128], url[160];
    json_t *o;
    api_export_filename(a, mid, scene_id, k->ext, fname, sizeof fname);
    snprintf(url, sizeof url, "/api/v1/materials/%s/%s", mid, k->path);
    o = json_pack("{s:s, s:s, s:s, s:s, s:s, s:o, s:b, s:b}", "format", k->format, "file_name",
                  fname, "url", url, "carries", k->carries, "use_in", k->use_in, "how_close",
                  export_how_close(k, p, spatial, why), "expensive",
                  k->expensive == 1 || (k->expensive == 2 && spatial), "available",
                  unavailable == NULL);
    if (o && unavailable)
        json_object_set_new(o, "reason", json_string(unavailable));
    return o;
}

/* Can BRDF Explorer's file be made (NULL) or why not (into buf)? */
static const char *brdf_unavailable(app *a, const char *mid, char *buf, size_t cap)
{
    material m = {0};
    char *text = NULL;
    glint_err e;
    int rc = api_material_load(a, mid, &m, &e);
    if (!rc)
        rc = brdfx_material(&m, &text, &e);
    free(text);
    material_free(&m);
    if (!rc)
        return NULL;
    snprintf(buf, cap, "%s", e.msg);
    return buf;
}

/* The "fit" member of the exports list: what the metallic-roughness
 * exports carry, which path made it and both errors (gltf.h). */
static json_t *fit_json(const gltf_pbr *p)
{
    const char *names[GLTF_KHR_MAX];
    int n = gltf_khr_names(p, names);
    json_t *o = json_pack("{s:[f,f,f], s:f, s:f, s:f, s:i, s:b, s:s, s:f, s:o, s:s, s:[]}",
                          "base_color", p->base[0], p->base[1], p->base[2], "metallic",
                          p->metallic, "roughness", p->roughness, "rel_rms", p->rel_rms,
                          "pairs", p->pairs, "spatial", p->spatial, "export",
                          p->exact ? "exact parameters" : "fitted", "rel_rms_fitted",
                          p->rel_rms_fitted, "rel_rms_exact",
                          isfinite(p->rel_rms_exact) ? json_real(p->rel_rms_exact) : json_null(),
                          "smith", p->smith == GLTF_SMITH_CORRELATED ? "height-correlated"
                                                                     : "separable",
                          "extensions");
    json_t *ext = json_object_get(o, "extensions");
    for (int i = 0; i < n; i++)
        json_array_append_new(ext, json_string(names[i]));
    if (o)
        json_object_set_new(o, "anisotropy", json_real(p->anisotropy));
    if (o && p->aniso.used)
        json_object_set_new(
            o, "anisotropic_fit",
            json_pack("{s:f, s:f, s:[f,f,f], s:f, s:f, s:f}", "strength", p->aniso.strength,
                      "rotation", p->aniso.rotation, "base_color", p->aniso.base[0],
                      p->aniso.base[1], p->aniso.base[2], "metallic", p->aniso.metallic,
                      "roughness", p->aniso.roughness, "rel_rms", p->aniso.rel_rms));
    if (o && p->note[0])
        json_object_set_new(o, "note", json_string(p->note));
    return o;
}

/* Every format a material exports to, with how close each comes: the fit
 * is computed here (as the mtlx and usda downloads do: 0.1 to 1 s). */
static http_resp exports_get(http_req *req)
{
    app *a = req->app;
    const char *mid = req->param[0];
    export_src x;
    gltf_pbr p;
    json_t *out, *list;
    glint_err e;
    char why[GLINT_ERR_MSG_MAX] = "", nobrdf[GLINT_ERR_MSG_MAX];
    const char *no_fit = NULL, *no_brdf;
    int rc, have_fit = 0;

    memset(&x, 0, sizeof x);
    if ((rc = api_material(req, mid, &x.doc, &e)))
        return api_error(&e);
    if (!x.doc.scene[0]) {
        no_fit = "the material has no scene (fitted from G-buffers): no mesh to export";
    } else {
        free(x.doc.text);
        if (!(rc = export_src_open(req, mid, &x, &e)) && !(rc = export_fit(req, mid, &x, &p, &e)))
            have_fit = 1;
        else if (e.code == GLINT_EBUSY) {
            export_src_close(a, &x);
            return api_error(&e);
        } else
            snprintf(why, sizeof why, "%s", e.msg);
    }
    no_brdf = brdf_unavailable(a, mid, nobrdf, sizeof nobrdf);
    out = json_pack("{s:s, s:[]}", "material_id", mid, "exports");
    list = json_object_get(out, "exports");
    if (out && have_fit)
        json_object_set_new(out, "fit", fit_json(&p));
    for (size_t k = 0; out && k < sizeof export_kinds / sizeof export_kinds[0]; k++) {
        const export_kind *ek = &export_kinds[k];
        const char *un = ek->fitted ? (no_fit ? no_fit : have_fit ? NULL : why)
                         : strcmp(ek->format, "brdf") == 0 ? no_brdf : NULL;
        json_array_append_new(list, export_entry(ek, mid, x.doc.scene, a, have_fit ? &p : NULL,
                                                 have_fit && p.spatial, no_fit ? no_fit : why,
                                                 un));
    }
    export_src_close(a, &x);
    if (!out)
        return http_problem(503, "out-of-memory", "out of memory");
    return http_json(200, out);
}

const http_route api_exports_routes[] = {
    {"GET", "/api/v1/materials/{id}/merl.binary", merl_get},
    {"GET", "/api/v1/materials/{id}/material.brdf", brdf_get},
    {"GET", "/api/v1/materials/{id}/material.glb", glb_get},
    {"GET", "/api/v1/materials/{id}/material.mtlx", mtlx_get},
    {"GET", "/api/v1/materials/{id}/material.mtlx.zip", mtlx_zip_get},
    {"GET", "/api/v1/materials/{id}/material.usda", usda_get},
    {"GET", "/api/v1/materials/{id}/material.usdz", usdz_get},
    {"GET", "/api/v1/materials/{id}/exports", exports_get},
};
const int api_exports_nroutes = sizeof api_exports_routes / sizeof api_exports_routes[0];
