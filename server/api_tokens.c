/* api_tokens.c: a session's share links over time (auth.h):
 *
 *   POST /api/v1/sessions/{id}/tokens   revoke and replace its tokens, set
 *                                       or clear when its links expire
 *
 * Body (every member optional): {"revoke": "both" | "paint" | "view"
 * | "none" (default "both"), "expires_in": seconds | null (null: never;
 * absent: unchanged)}.  Allowed to the paint token (while it is valid),
 * the scene's owner key (X-Glint-Owner) and the API key: the owner key
 * renews links that have expired.  The answer is the session as its paint
 * token sees it, with the new links; the old tokens are refused from then
 * on and the session's event streams opened with them end, sending nothing
 * more (events.h). */
#include <string.h>
#include <time.h>

#include "api_common.h"
#include "app.h"
#include "auth.h"
#include "clock.h"
#include "events.h"
#include "ids.h"
#include "log.h"
#include "store.h"

int api_expiry_parse(const json_t *v, json_t *doc, glint_err *e)
{
    json_int_t sec;
    char iso[GLINT_TIME_LEN];
    if (json_is_null(v)) {
        json_object_del(doc, "expires");
        json_object_del(doc, "expires_unix");
        return 0;
    }
    if (!json_is_integer(v) || (sec = json_integer_value(v)) < API_EXPIRES_MIN ||
        sec > API_EXPIRES_MAX)
        return api_reject(e, GLINT_EINVAL, "invalid-input",
                          "expires_in: expected whole seconds in %d..%d (or null: never)",
                          API_EXPIRES_MIN, API_EXPIRES_MAX);
    glint_time_iso(time(NULL) + (time_t)sec, iso);
    json_object_set_new(doc, "expires", json_string(iso));
    json_object_set_new(doc, "expires_unix", json_integer((json_int_t)time(NULL) + sec));
    return 0;
}

/* Who may change the links: the paint token, the scene's owner, the key. */
static int may_manage(http_req *req, const json_t *doc, glint_err *e)
{
    app *a = req->app;
    json_t *scene = NULL;
    glint_err probe;
    int rc;
    if (auth_session(req, doc, 1, &probe) == 0)
        return 0;
    if (http_header_in(req, "X-Glint-Owner") &&
        store_scene_get(a->store, json_string_value(json_object_get(doc, "scene_id")), &scene,
                        e) == 0) {
        rc = auth_scene_owner(req, scene, e);
        json_decref(scene);
        return rc;
    }
    *e = probe;
    return probe.code;
}

static http_resp tokens_post(http_req *req)
{
    app *a = req->app;
    json_t *doc = NULL, *body = NULL, *v, *pub;
    const char *k, *what = "both";
    char pt[33], vt[33];
    glint_err e;
    int rc;

    rc = store_session_get(a->store, req->param[0], &doc, &e);
    if (rc == GLINT_ENOTFOUND)
        glint_err_set(&e, rc, "no session %.40s", req->param[0]);
    if (rc || (rc = may_manage(req, doc, &e)))
        goto done;
    if (req->body_len > 0 && (rc = api_body_json(req, &body, &e)))
        goto done;
    json_object_foreach(body, k, v) {
        if (strcmp(k, "revoke") == 0) {
            what = json_string_value(v);
            if (!what || (strcmp(what, "both") && strcmp(what, "paint") && strcmp(what, "view") &&
                          strcmp(what, "none"))) {
                rc = api_reject(&e, GLINT_EINVAL, "invalid-input",
                                "revoke: one of \"both\", \"paint\", \"view\", \"none\"");
                goto done;
            }
        } else if (strcmp(k, "expires_in") == 0) {
            if ((rc = api_expiry_parse(v, doc, &e)))
                goto done;
        } else {
            rc = api_reject(&e, GLINT_EINVAL, "invalid-input",
                            "unknown key \"%.64s\" (known: revoke, expires_in)", k);
            goto done;
        }
    }
    if ((rc = glint_id_new(pt, &e)) || (rc = glint_id_new(vt, &e)))
        goto done;
    if (!strcmp(what, "both") || !strcmp(what, "paint"))
        json_object_set_new(doc, "paint_token", json_string(pt));
    if (!strcmp(what, "both") || !strcmp(what, "view"))
        json_object_set_new(doc, "view_token", json_string(vt));
    /* the session's token streams send nothing while the tokens change,
     * then check theirs against what was stored */
    events_revoke_begin(a->events, req->param[0]);
    rc = store_session_update(a->store, req->param[0], doc, &e);
    events_revoke_end(a->events, req->param[0]);
    if (rc)
        goto done;
    {
        glint_err ae;
        /* replicas on the same database check their streams' tokens too */
        if (store_announce(a->store, req->param[0], "revoke", &ae))
            log_line("tokens: streams on other replicas keep going until they reconnect: %s",
                     ae.msg);
    }
    pub = api_session_public(a, doc, 1);
    json_decref(doc);
    json_decref(body);
    return pub ? http_json(200, pub) : api_error(&e);
done:
    json_decref(doc);
    json_decref(body);
    return api_error(&e);
}

const http_route api_tokens_routes[] = {
    {"POST", "/api/v1/sessions/{id}/tokens", tokens_post},
};
const int api_tokens_nroutes = sizeof api_tokens_routes / sizeof api_tokens_routes[0];
