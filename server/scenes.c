/* scenes.c: core scenes of stored scenes and their base renders
 * (scenes.h). */
#include "scenes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "api_common.h"
#include "cancel.h"
#include "fitsvc.h"
#include "ids.h"
#include "mesh.h"
#include "prep.h"
#include "render.h"
#include "store.h"

void scenes_unload(const scene *sc)
{
    if (!sc)
        return;
    scene_free((scene *)sc);
    free((scene *)sc);
}

int scenes_load(store *st, const char *id, const scene **out, glint_err *err)
{
    json_t *doc = NULL, *js = NULL;
    const char *mesh_id;
    char *text = NULL, format[16];
    void *data = NULL;
    size_t len = 0;
    scene *sc;
    int rc;

    *out = NULL;
    if (!(sc = calloc(1, sizeof *sc)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory loading a scene");
    if ((rc = store_scene_get(st, id, &doc, err)))
        goto done;
    js = json_deep_copy(json_object_get(doc, "scene"));
    if (!json_is_object(js)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene %s: stored document has no scene", id);
        goto done;
    }
    mesh_id = json_string_value(json_object_get(doc, "mesh_id"));
    /* An uploaded mesh is not a built-in: parse the views with a stand-in
     * built-in (a few ms), then put the uploaded mesh in its place. */
    if (mesh_id)
        json_object_set_new(js, "mesh", json_string("sphere"));
    if (!(text = json_dumps(js, JSON_COMPACT | JSON_REAL_PRECISION(17)))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory loading a scene");
        goto done;
    }
    if ((rc = scene_from_json(text, sc, err)))
        goto done;
    if (mesh_id) {
        mesh_free(&sc->mesh);
        if ((rc = store_mesh_data(st, mesh_id, &data, &len, format, err)) ||
            (rc = mesh_load_mem(data, len, format, &sc->mesh, &sc->mesh_info, err))) {
            glint_err_prefix(err, "scene %s: mesh %s", id, mesh_id);
            goto done;
        }
        snprintf(sc->mesh_name, sizeof sc->mesh_name, "upload:%s", mesh_id);
        rc = scene_validate(sc, err);
    }
done:
    free(data);
    free(text);
    json_decref(js);
    json_decref(doc);
    if (rc)
        scenes_unload(sc);
    else
        *out = sc;
    return rc;
}

int scenes_paint_scale(const json_t *doc)
{
    json_int_t s = json_integer_value(json_object_get(doc, "paint_scale"));
    return s >= 1 && s <= 16 ? (int)s : 1;
}

size_t scenes_base_bytes(int width, int height, int scale, int env_lights)
{
    int W = width * scale, H = height * scale;
    return render_peak_bytes(RENDER_CPU, 1, W, H) +
           (env_lights > 0 ? (size_t)W * H * 8 * (size_t)((env_lights + 63) / 64) : 0);
}

int scenes_base(app *a, const char *id, int view, int scale, img *out, glint_err *err)
{
    char name[128];
    void *data = NULL;
    size_t len = 0, bytes;
    json_t *doc = NULL, *base, *jenv;
    cache_entry *se = NULL;
    const scene *sc;
    const char *spec;
    double bscale, cost = 0.0;
    render_env env;
    glint_cancel cancel;
    int rc, W, H;

    memset(out, 0, sizeof *out);
    if (!glint_id_valid(id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no scene with id \"%.40s\"", id ? id : "");
    if (scale < 1 || scale > 16)
        return glint_err_set(err, GLINT_EINVAL, "base render at scale %d: expected 1..16", scale);
    if (scale == 1)
        snprintf(name, sizeof name, "scenes/%s/base%d.exr", id, view);
    else
        snprintf(name, sizeof name, "scenes/%s/base%dx%d.exr", id, view, scale);
    if (view >= 0 && store_blob_get(a->store, name, &data, &len, NULL) == 0) {
        rc = img_read_mem(data, len, out, NULL);
        free(data);
        data = NULL;
        if (rc == 0 && out->channels == 3)
            return 0;
        img_free(out); /* an unreadable cache file: render again */
    }
    if ((rc = store_scene_get(a->store, id, &doc, err)) ||
        (rc = fitsvc_scene(a->fits, id, &se, err)))
        goto done;
    sc = prep_scene_of(se)->sc;
    if (view < 0 || view >= sc->nviews) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "scene %s has no view %d (views 0..%d)", id, view,
                           sc->nviews - 1);
        goto done;
    }
    base = json_object_get(doc, "base");
    spec = json_string_value(json_object_get(base, "brdf"));
    bscale = json_number_value(json_object_get(base, "scale"));
    if (!spec || !(bscale > 0.0)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene %s: stored document has no base brdf/scale",
                           id);
        goto done;
    }
    jenv = json_object_get(base, "env");
    if (jenv && (rc = api_env_parse(jenv, "base.env", &env, err)))
        goto done;
    W = sc->width * scale;
    H = sc->height * scale;
    bytes = scenes_base_bytes(sc->width, sc->height, scale, jenv ? env.lights : 0);
    if ((rc = render_base_cost(NULL, RENDER_CPU, NULL, &sc->mesh, spec, jenv ? &env : NULL, W, H,
                               &cost, err)) ||
        (rc = admit_cost(a->work, cost, "the scene's base render", err)) ||
        (rc = admit_enter(a->work, bytes, "the base render", err)))
        goto done;
    /* on the CPU: at scale 1 the pixels are exactly those a painting is sampled at;
     * kept for every session, so it stops only when the daemon does */
    api_stop_cancel_init(a, &cancel);
    rc = jenv ? render_base_env(NULL, RENDER_CPU, NULL, &sc->mesh, spec, bscale, &env,
                                &sc->views[view], W, H, out, NULL, NULL, &cancel, err)
              : render_base(NULL, RENDER_CPU, NULL, &sc->mesh, &sc->views[view], W, H, spec,
                            bscale, out, NULL, &cancel, err);
    if (rc == GLINT_ECANCELLED)
        admit_cancelled(a->work);
    admit_leave(a->work, bytes);
    if (rc)
        goto done;
    if (img_write_mem("exr", out, &data, &len, NULL) == 0)
        store_blob_put(a->store, name, data, len, NULL); /* a cache: failure costs time only */
done:
    free(data);
    cache_release(a->cache, se);
    json_decref(doc);
    if (rc)
        img_free(out);
    return rc;
}
