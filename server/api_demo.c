/* api_demo.c: the daemon's demo session (proto/openapi.yaml, "demo").
 *
 *   GET /api/v1/demo    the demo session, with its paint token      (no key)
 *
 * glintd --demo-session FILE names it: FILE holds the answer of
 * POST /api/v1/sessions for the session every visitor of the studio may
 * open and paint (setup.sh's main job creates it through the API once the
 * daemon listens, and writes it there).  As the file is written after the
 * daemon starts, and replaced when its session is gone (a new data
 * directory), it is read at each request; only its "id" is used, and the
 * tokens answered are the store's current ones (a revoked link is replaced
 * there, not in the file).
 *
 * Answers: 200 Session (access "paint"); 204 when there is none (no
 * option, or the file not written yet: the studio asks on every start
 * page, and a browser reports every 404 in its console); 404 "not-found"
 * when the file names a session that is not in this daemon's store; 403
 * "link-expired" when the session's links have expired; 500
 * "demo-file-invalid" naming what is wrong with the file (too large, not a
 * JSON object, no id of 32 hex digits), logged for the operator, the
 * daemon serving on. */
#include <jansson.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "api_common.h"
#include "app.h"
#include "auth.h"
#include "fsio.h"
#include "ids.h"
#include "store.h"

/* A session's answer is a few hundred bytes; a file far larger is not one. */
#define API_DEMO_MAX_FILE ((size_t)64 << 10)

int api_demo_read(const char *path, char id[GLINT_ID_LEN], glint_err *err)
{
    char *text = NULL;
    size_t len = 0;
    json_error_t je;
    json_t *root;
    const char *sid;
    int rc = fsio_read_all(path, API_DEMO_MAX_FILE, &text, &len, err);

    if (rc == GLINT_ENOTFOUND)
        return api_reject(err, rc, "no-demo", "the demo session is not created yet (%s)", path);
    if (rc)
        return api_reject(err, rc, "demo-file-invalid", "the demo session file: %s", err->msg);
    root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &je);
    free(text);
    if (!root)
        return api_reject(err, GLINT_EFORMAT, "demo-file-invalid",
                          "the demo session file %s: line %d: %s", path, je.line, je.text);
    sid = json_string_value(json_object_get(root, "id"));
    if (!json_is_object(root) || !glint_id_valid(sid))
        rc = api_reject(err, GLINT_EFORMAT, "demo-file-invalid",
                        "the demo session file %s: expected a session (a JSON object whose "
                        "\"id\" is 32 lowercase hex digits)",
                        path);
    else
        memcpy(id, sid, GLINT_ID_LEN);
    json_decref(root);
    return rc;
}

/* The demo session's record (OUT: *doc, decref), its links current. */
static int demo_session(app *a, json_t **doc, glint_err *err)
{
    char id[GLINT_ID_LEN];
    const char *pt;
    int rc;

    *doc = NULL;
    if (!a->cfg.demo_session[0])
        return api_reject(err, GLINT_ENOTFOUND, "no-demo",
                          "this daemon has no demo session (glintd --demo-session FILE)");
    if ((rc = api_demo_read(a->cfg.demo_session, id, err)))
        return rc;
    rc = store_session_get(a->store, id, doc, err);
    if (rc == GLINT_ENOTFOUND)
        return api_reject(err, rc, NULL,
                          "the demo session %s is not on this server (the file names a session "
                          "of another data directory)",
                          id);
    if (rc)
        return rc;
    pt = json_string_value(json_object_get(*doc, "paint_token"));
    if (!auth_token_current(*doc, pt ? pt : "", time(NULL), NULL)) {
        json_decref(*doc);
        *doc = NULL;
        return api_reject(err, GLINT_EDENIED, "link-expired",
                          "the demo session's links have expired");
    }
    return 0;
}

static http_resp demo_get(http_req *req)
{
    app *a = req->app;
    json_t *doc;
    glint_err e;
    http_resp r;

    if (demo_session(a, &doc, &e))
        return strcmp(e.kind, "no-demo") == 0 ? http_bytes(204, NULL, "", 0) : api_error(&e);
    r = http_json(200, api_session_public(a, doc, 1));
    json_decref(doc);
    /* it carries a paint token, and the demo may be replaced */
    http_header(&r, "Cache-Control", "no-store");
    return r;
}

const http_route api_demo_routes[] = {
    {"GET", "/api/v1/demo", demo_get},
};
const int api_demo_nroutes = sizeof api_demo_routes / sizeof api_demo_routes[0];
