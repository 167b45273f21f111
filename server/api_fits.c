/* api_fits.c: fits and jobs (proto/openapi.yaml, section "fits, jobs,
 * materials, methods").
 *
 *   POST /api/v1/sessions/{id}/fits        fit the session's paintings: 201 with the
 *                                           material when the precomputation is in
 *                                           memory, else 202 with a job
 *   GET  /api/v1/sessions/{id}/materials   the session's materials
 *   GET  /api/v1/jobs/{id}                 poll a job
 *   GET  /api/v1/jobs/{id}/events          the job's progress as server-sent events
 *   DELETE /api/v1/jobs/{id}               cancel the job (paint rights on its session)
 *
 * The body names a method of the registry (method.h; default: the first)
 * and its params, checked against the method's parameter table; fitsvc
 * runs the fit. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api_common.h"
#include "app.h"
#include "buf.h"
#include "fitsvc.h"
#include "ids.h"
#include "jobs.h"
#include "method.h"
#include "store.h"

#define SSE_KEEPALIVE_S 15.0

/* The method and parameters of a fit request (api_common.h). */
int api_fit_body(const json_t *body, int has_mesh, const method **m, void **params,
                 glint_err *e)
{
    const method_source src = {has_mesh};
    const char *k;
    json_t *v;
    char names[256];
    int rc;

    *params = NULL;
    *m = method_at(0);
    json_object_foreach((json_t *)body, k, v) {
        if (strcmp(k, "method") != 0 && strcmp(k, "params") != 0)
            return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                              "unknown member '%.64s' (a fit takes \"method\" and \"params\")", k);
    }
    method_names(names, sizeof names);
    if ((v = json_object_get(body, "method"))) {
        if (!json_is_string(v))
            return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                              "method must be a string (one of %s)", names);
        if (!(*m = method_find(json_string_value(v))))
            return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                              "method '%.64s' is not available (available: %s)",
                              json_string_value(v), names);
    }
    if (method_available(*m, e))
        return api_reject(e, GLINT_EINVAL, "method-unavailable",
                          "%s cannot fit on this host: %s", (*m)->name, e->msg);
    if (!(*params = method_params_new(*m)))
        return glint_err_set(e, GLINT_ENOMEM, "out of memory");
    if (((v = json_object_get(body, "params")) &&
         (rc = method_params_from_json(*m, *params, v, e))) ||
        (rc = method_params_usable(*m, *params, &src, e))) {
        free(*params);
        *params = NULL;
        return glint_err_kind(e, "invalid-parameter");
    }
    return 0;
}

static json_t *job_with_links(json_t *jdoc);

http_resp api_fit_answer(http_req *req, json_t *doc, const char *job_id, json_t *warnings)
{
    json_t *jdoc = NULL, *body;
    char loc[128];
    glint_err e;
    http_resp r;

    if (doc) { /* fitted now */
        snprintf(loc, sizeof loc, "/api/v1/materials/%s",
                 json_string_value(json_object_get(doc, "id")));
        if (warnings)
            json_object_set_new(doc, "warnings", warnings);
        r = http_json(201, doc);
        http_header(&r, "Location", loc);
        return r;
    }
    if (jobs_get(((app *)req->app)->jobs, job_id, &jdoc, NULL, &e)) {
        json_decref(warnings);
        return api_error(&e);
    }
    snprintf(loc, sizeof loc, "/api/v1/jobs/%s", job_id);
    body = json_pack("{s:o}", "job", job_with_links(jdoc));
    if (warnings)
        json_object_set_new(body, "warnings", warnings);
    r = http_json(202, body);
    http_header(&r, "Location", loc);
    return r;
}

json_t *api_lighting_warning(const method *m, int point_lit, const char *why)
{
    char msg[512];
    if (m->lighting != METHOD_LIGHT_ENV || !point_lit)
        return NULL;
    snprintf(msg, sizeof msg,
             "%s fits views painted under an environment, but these are lit by point lights "
             "(%s): unless your paintings were made under the environment it names, fit them "
             "with a method lit by lamps", m->label ? m->label : m->name, why);
    return json_pack("[s]", msg);
}

static json_t *job_with_links(json_t *jdoc)
{
    char b[3][160];
    const char *id = json_string_value(json_object_get(jdoc, "id"));
    const char *mid = json_string_value(json_object_get(jdoc, "material_id"));
    json_t *links;
    snprintf(b[0], sizeof b[0], "/api/v1/jobs/%s", id ? id : "");
    snprintf(b[1], sizeof b[1], "/api/v1/jobs/%s/events", id ? id : "");
    links = json_pack("{s:s, s:s}", "self", b[0], "events", b[1]);
    if (mid) {
        snprintf(b[2], sizeof b[2], "/api/v1/materials/%s", mid);
        json_object_set_new(links, "material", json_string(b[2]));
    }
    json_object_set_new(jdoc, "links", links);
    return jdoc;
}

/* A session's paintings are lit as its scene's base is (the views' point
 * lights, or base.env): a method lit otherwise would fit them to a light
 * they were not painted under, so it is refused before any work.  (The
 * reverse, a method lit by an environment on a scene whose base has point
 * lights, stays open, with a warning in the answer: paintings made
 * elsewhere under an environment are uploaded to such sessions, the
 * environment named by the method's env.)  OUT *point_lit: the base is lit
 * by the views' point lights. */
static int fit_lighting_check(app *a, const char *scene_id, const method *m, int *point_lit,
                              glint_err *e)
{
    json_t *doc = NULL, *env;
    const char *spec;
    char names[256];
    size_t len = 0;
    int rc;

    if ((rc = store_scene_get(a->store, scene_id, &doc, e)))
        return rc;
    env = json_object_get(json_object_get(doc, "base"), "env");
    *point_lit = !env;
    if (!env || m->lighting != METHOD_LIGHT_POINT) {
        json_decref(doc);
        return 0;
    }
    names[0] = '\0';
    for (int i = 0; method_at(i); i++) {
        const method *x = method_at(i);
        if (x->lighting == METHOD_LIGHT_ENV && len + strlen(x->name) + 3 < sizeof names)
            len += (size_t)snprintf(names + len, sizeof names - len, "%s%s", len ? ", " : "",
                                    x->name);
    }
    spec = json_string_value(json_object_get(env, "spec"));
    rc = api_reject(e, GLINT_EINVAL, "lighting-mismatch",
                    "method %s fits views lit by their point lights, but this scene is painted "
                    "under an environment (%.64s): fit it with a method lit by one (%s)",
                    m->name, spec ? spec : "its base",
                    names[0] ? names : "none is available");
    json_decref(doc);
    return rc;
}

static http_resp fits_create(http_req *req)
{
    app *a = req->app;
    const char *sid = req->param[0], *scid;
    json_t *sdoc = NULL, *body = NULL, *doc = NULL;
    const method *m = NULL;
    void *params = NULL;
    char job_id[33];
    http_resp r;
    glint_err e;
    int rc, point_lit = 0;

    if ((rc = api_session(req, sid, 1, &sdoc, &e)) || (rc = api_body_json(req, &body, &e)) ||
        (rc = api_fit_body(body, 1, &m, &params, &e)))
        goto done;
    if (!(scid = json_string_value(json_object_get(sdoc, "scene_id")))) {
        rc = glint_err_set(&e, GLINT_EINTERNAL, "session %s names no scene", sid);
        goto done;
    }
    if (!(rc = fit_lighting_check(a, scid, m, &point_lit, &e)) &&
        !(rc = fitsvc_fit(a->fits, sid, scid, m, params, &doc, job_id, &req->timing, &e)))
        r = api_fit_answer(req, doc, job_id,
                           api_lighting_warning(m, point_lit, "the scene's base renders, which "
                                                              "the studio paints over"));
done:
    if (rc)
        r = api_error(&e);
    free(params);
    json_decref(body);
    json_decref(sdoc);
    return r;
}

static http_resp session_materials(http_req *req)
{
    app *a = req->app;
    json_t *sdoc, *list = NULL;
    glint_err e;

    if (api_session(req, req->param[0], 0, &sdoc, &e))
        return api_error(&e);
    json_decref(sdoc);
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

/* ---- jobs ------------------------------------------------------------------------------- */

/* The job `id` if the request may read its session (need_paint: paint in
 * it) or use its G-buffer set, whose fits it runs (api_gbuffers.c).  OUT:
 * *jdoc. */
static int job_access(http_req *req, const char *id, int need_paint, json_t **jdoc, glint_err *e)
{
    app *a = req->app;
    char owner[33];
    json_t *sdoc;
    int rc;

    *jdoc = NULL;
    if (!glint_id_valid(id) || jobs_get(a->jobs, id, jdoc, owner, e) ||
        !owner[0]) { /* internal jobs are not visible */
        json_decref(*jdoc);
        *jdoc = NULL;
        return api_reject(e, GLINT_ENOTFOUND, "not-found",
                          "no job %.40s (unknown, or finished over an hour ago)", id);
    }
    rc = api_session(req, owner, need_paint, &sdoc, e);
    if (rc == GLINT_ENOTFOUND && api_gbuffer_set_exists(req->app, owner))
        rc = api_gbuffer_set_access(req, owner, e);
    else
        json_decref(sdoc);
    if (rc) {
        json_decref(*jdoc);
        *jdoc = NULL;
        return rc;
    }
    return 0;
}

static http_resp job_get(http_req *req)
{
    json_t *jdoc;
    glint_err e;
    if (job_access(req, req->param[0], 0, &jdoc, &e))
        return api_error(&e);
    return http_json(200, json_pack("{s:o}", "job", job_with_links(jdoc)));
}

/* DELETE: a queued job fails now (200), a running one is told and stops at
 * its next question (202: poll it for "failed"); 409 once finished. */
static http_resp job_delete(http_req *req)
{
    app *a = req->app;
    json_t *jdoc;
    glint_err e;
    int running;
    if (job_access(req, req->param[0], 1, &jdoc, &e))
        return api_error(&e);
    json_decref(jdoc);
    if (jobs_cancel(a->jobs, req->param[0], &jdoc, &e))
        return api_error(&e);
    running = strcmp(json_string_value(json_object_get(jdoc, "state")), "running") == 0;
    return http_json(running ? 202 : 200, json_pack("{s:o}", "job", job_with_links(jdoc)));
}

/* SSE stream of a job: "progress" events, then one "done" or "failed". */
typedef struct job_stream {
    jobs *js;
    char id[33];
    long long since;
    glint_buf buf;
    size_t off;
    int final_queued;
} job_stream;

static void job_stream_free(void *cls)
{
    job_stream *s = cls;
    if (s) {
        glint_buf_free(&s->buf);
        free(s);
    }
}

/* Format the job's next events into s->buf (waiting up to the keep-alive
 * period).  0, or -1 when the job is gone or the daemon stops. */
static int job_stream_fill(job_stream *s)
{
    json_t *evs = NULL, *ev;
    int final = 0;
    size_t i;

    if (jobs_events(s->js, s->id, s->since, SSE_KEEPALIVE_S, &evs, &final, NULL))
        return -1;
    glint_buf_clear(&s->buf);
    s->off = 0;
    if (json_array_size(evs) == 0 && final) { /* finished before: nothing more to say */
        json_decref(evs);
        return -1;
    }
    if (json_array_size(evs) == 0)
        glint_buf_printf(&s->buf, ": keep-alive\n\n");
    json_array_foreach(evs, i, ev) {
        json_t *jdoc = json_deep_copy(json_object_get(ev, "job"));
        const char *type = json_string_value(json_object_get(ev, "type"));
        char *text = json_dumps(job_with_links(jdoc), JSON_COMPACT);
        s->since = json_integer_value(json_object_get(ev, "seq"));
        glint_buf_printf(&s->buf, "id: %lld\nevent: %s\ndata: %s\n\n", s->since,
                         type ? type : "progress", text ? text : "{}");
        free(text);
        json_decref(jdoc);
        if (type && (strcmp(type, "done") == 0 || strcmp(type, "failed") == 0))
            s->final_queued = 1;
    }
    json_decref(evs);
    return 0;
}

static ssize_t job_stream_read(void *cls, uint64_t pos, char *out, size_t max)
{
    job_stream *s = cls;
    size_t n;
    (void)pos;
    while (s->off >= s->buf.len) {
        if (s->final_queued || job_stream_fill(s))
            return MHD_CONTENT_READER_END_OF_STREAM;
    }
    n = s->buf.len - s->off;
    if (n > max)
        n = max;
    memcpy(out, s->buf.data + s->off, n);
    s->off += n;
    return (ssize_t)n;
}

static http_resp job_events(http_req *req)
{
    app *a = req->app;
    const char *last = http_header_in(req, "Last-Event-ID"), *since = http_query(req, "since");
    job_stream *s;
    json_t *jdoc;
    glint_err e;

    if (job_access(req, req->param[0], 0, &jdoc, &e))
        return api_error(&e);
    json_decref(jdoc);
    if (!(s = calloc(1, sizeof *s)))
        return http_problem(503, "out-of-memory", "out of memory");
    s->js = a->jobs;
    snprintf(s->id, sizeof s->id, "%s", req->param[0]);
    if (last || since) {
        char *end;
        long long v = strtoll(last ? last : since, &end, 10);
        if (*end || v < 0) {
            free(s);
            return http_problem(400, "bad-request", "%s must be a non-negative integer",
                                last ? "Last-Event-ID" : "since");
        }
        s->since = v;
    }
    return http_stream(200, "text/event-stream", job_stream_read, s, job_stream_free);
}

const http_route api_fits_routes[] = {
    {"POST", "/api/v1/sessions/{id}/fits", fits_create},
    {"GET", "/api/v1/sessions/{id}/materials", session_materials},
    {"GET", "/api/v1/jobs/{id}", job_get},
    {"DELETE", "/api/v1/jobs/{id}", job_delete},
    {"GET", "/api/v1/jobs/{id}/events", job_events},
};
const int api_fits_nroutes = sizeof api_fits_routes / sizeof api_fits_routes[0];
