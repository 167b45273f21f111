/* auth.c: the API key and session tokens (auth.h). */
#include "auth.h"

#include <ctype.h>
#include <string.h>
#include <time.h>

#include "app.h"
#include "ids.h"

/* The API key the request presents, or NULL. */
static const char *auth_key_given(http_req *req)
{
    const char *h = http_header_in(req, "Authorization");
    if (h && strncmp(h, "Bearer ", 7) == 0) {
        h += 7;
        while (*h == ' ')
            h++;
        return h;
    }
    return http_header_in(req, "X-Api-Key");
}

int auth_has_key(http_req *req)
{
    app *a = req->app;
    const char *k;
    if (!a->cfg.api_key[0])
        return 0;
    k = auth_key_given(req);
    return k && glint_secret_equal(k, a->cfg.api_key);
}

int auth_require_key(http_req *req, glint_err *err)
{
    app *a = req->app;
    const char *k;
    if (!a->cfg.api_key[0])
        return 0;
    k = auth_key_given(req);
    if (k && glint_secret_equal(k, a->cfg.api_key))
        return 0;
    if (k)
        glint_err_set(err, GLINT_EAUTH, "the API key presented does not match this daemon's key");
    else
        glint_err_set(err, GLINT_EAUTH,
                      "this daemon requires its API key for %s %s: send \"Authorization: Bearer "
                      "KEY\" or \"X-Api-Key: KEY\"", req->method, req->path);
    return glint_err_kind(err, "api-key-required");
}

const char *auth_token_given(http_req *req)
{
    const char *tok = http_header_in(req, "X-Glint-Token");
    return tok ? tok : http_query(req, "token");
}

int auth_token_current(const json_t *session_doc, const char *token, time_t now,
                       time_t *expires)
{
    const char *paint = json_string_value(json_object_get(session_doc, "paint_token"));
    const char *view = json_string_value(json_object_get(session_doc, "view_token"));
    json_t *ex = json_object_get(session_doc, "expires_unix");

    if (expires)
        *expires = json_is_integer(ex) ? (time_t)json_integer_value(ex) : 0;
    if (!token || !paint || !view ||
        !(glint_secret_equal(token, paint) || glint_secret_equal(token, view)))
        return 0;
    return !(json_is_integer(ex) && (json_int_t)now >= json_integer_value(ex));
}

int auth_session(http_req *req, const json_t *session_doc, int need_paint, glint_err *err)
{
    const char *tok = auth_token_given(req);
    const char *paint = json_string_value(json_object_get(session_doc, "paint_token"));
    const char *view = json_string_value(json_object_get(session_doc, "view_token"));

    if (auth_has_key(req))
        return 0;
    if (!paint || !view)
        return glint_err_set(err, GLINT_EINTERNAL, "session record has no tokens");
    {
        json_t *ex = json_object_get(session_doc, "expires_unix");
        if (json_is_integer(ex) && (json_int_t)time(NULL) >= json_integer_value(ex) && tok &&
            (glint_secret_equal(tok, paint) || glint_secret_equal(tok, view))) {
            glint_err_set(err, GLINT_EDENIED,
                          "this session's links expired at %s: its scene's owner key or the "
                          "API key can issue new ones (POST /api/v1/sessions/{id}/tokens)",
                          json_string_value(json_object_get(session_doc, "expires")));
            return glint_err_kind(err, "link-expired");
        }
    }
    if (!tok || !*tok) {
        glint_err_set(err, GLINT_EAUTH,
                      "this session needs its token: send \"X-Glint-Token: TOKEN\" or "
                      "?token=TOKEN (the paint token from the session's share link, or the "
                      "view token for reading)");
        return glint_err_kind(err, "token-required");
    }
    if (glint_secret_equal(tok, paint))
        return 0;
    if (glint_secret_equal(tok, view)) {
        if (!need_paint)
            return 0;
        glint_err_set(err, GLINT_EDENIED,
                      "the view token grants reading only: %s %s needs the paint token",
                      req->method, req->path);
        return glint_err_kind(err, "read-only-token");
    }
    glint_err_set(err, GLINT_EDENIED, "the token does not grant access to this session");
    return glint_err_kind(err, "wrong-token");
}

int auth_owner_key(http_req *req, const char **key, glint_err *err)
{
    const char *k = http_header_in(req, "X-Glint-Owner");
    size_t n = 0;

    *key = NULL;
    if (!k)
        return 0;
    for (; k[n]; n++)
        if (!isalnum((unsigned char)k[n]) && k[n] != '_' && k[n] != '-')
            break;
    if (k[n] || n < AUTH_OWNER_MIN || n > AUTH_OWNER_MAX) {
        glint_err_set(err, GLINT_EINVAL,
                      "X-Glint-Owner must be %d to %d characters of A-Z a-z 0-9 _ - "
                      "(a secret you keep: it lists and deletes your scenes and uploads)",
                      AUTH_OWNER_MIN, AUTH_OWNER_MAX);
        return glint_err_kind(err, "invalid-owner-key");
    }
    *key = k;
    return 0;
}

int auth_owner_new(http_req *req, char made[33], const char **key, glint_err *err)
{
    int rc;
    if ((rc = auth_owner_key(req, key, err)) || *key)
        return rc;
    if ((rc = glint_id_new(made, err)))
        return rc;
    *key = made;
    return 0;
}

int auth_owned_by(const json_t *doc, const char *key)
{
    const char *owner = json_string_value(json_object_get(doc, "owner"));
    return key && owner && glint_secret_equal(key, owner);
}

int auth_owner(http_req *req, const json_t *doc, const char *what, glint_err *err)
{
    const char *k;
    int rc;

    if (auth_has_key(req))
        return 0;
    if ((rc = auth_owner_key(req, &k, err)))
        return rc;
    if (!k) {
        glint_err_set(err, GLINT_EAUTH,
                      "%s %s needs the %s's owner key (\"X-Glint-Owner: KEY\", answered when "
                      "the %s was created) or the daemon's API key", req->method, req->path,
                      what, what);
        return glint_err_kind(err, "owner-key-required");
    }
    if (auth_owned_by(doc, k))
        return 0;
    glint_err_set(err, GLINT_EDENIED, "the owner key does not own this %s", what);
    return glint_err_kind(err, "not-owner");
}

int auth_scene_owner(http_req *req, const json_t *scene_doc, glint_err *err)
{
    return auth_owner(req, scene_doc, "scene", err);
}
