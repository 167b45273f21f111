/* api_methods.c: the methods catalogue (proto/openapi.yaml, section "fits,
 * jobs, materials, methods").
 *
 *   GET /api/v1/methods[?scene_id=ID | ?session_id=ID]
 *
 * Every registered method described from its own table (method_describe:
 * parameters with types, defaults, ranges and costs, presets), and with a
 * scene the speed-accuracy points measured on it (points.h).  The points
 * of a scene are readable by scene id like the scene itself (ids are 128
 * random bits); with session_id, by the session's view or paint token.
 * Points never show material ids (those belong to sessions). */
#include <string.h>

#include "api_common.h"
#include "app.h"
#include "fitsvc.h"
#include "method.h"
#include "points.h"
#include "prep.h"

static http_resp methods_get(http_req *req)
{
    app *a = req->app;
    const char *scid = http_query(req, "scene_id"), *sid = http_query(req, "session_id");
    json_t *out, *list, *sdoc = NULL, *pts, *pt;
    cache_entry *se = NULL;
    const char *hash;
    glint_err e;
    size_t i;

    if (scid && sid)
        return http_problem(422, "invalid-parameter", "give scene_id or session_id, not both");
    if (sid) {
        if (api_session(req, sid, 0, &sdoc, &e))
            return api_error(&e);
        scid = json_string_value(json_object_get(sdoc, "scene_id"));
    }
    list = json_array();
    for (int k = 0; k < method_count(); k++)
        json_array_append_new(list, method_describe(method_at(k)));
    out = json_pack("{s:o}", "methods", list);
    if (scid) {
        if (fitsvc_scene(a->fits, scid, &se, &e)) {
            json_decref(out);
            json_decref(sdoc);
            return e.code == GLINT_ENOTFOUND
                       ? http_problem(404, "not-found", "no scene %.40s", scid)
                       : api_error(&e);
        }
        hash = prep_scene_of(se)->hash;
        pts = points_get(a->points, hash);
        json_array_foreach(pts, i, pt) {
            json_object_del(pt, "material_id");
            json_object_del(json_object_get(pt, "held_out"), "material_id");
        }
        json_object_set_new(out, "scene",
                            json_pack("{s:s, s:s, s:o}", "id", scid, "hash", hash, "points",
                                      pts));
        cache_release(a->cache, se);
    }
    json_decref(sdoc);
    return http_json(200, out);
}

const http_route api_methods_routes[] = {
    {"GET", "/api/v1/methods", methods_get},
};
const int api_methods_nroutes = sizeof api_methods_routes / sizeof api_methods_routes[0];
