/* auth.c: the API key and session tokens (auth.h). */
#include "auth.h"

#include <string.h>

#include "app.h"
#include "events.h"

/* Constant-time string equality: the time depends on the lengths only. */
static int auth_equal(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b), n = la > lb ? la : lb;
    unsigned char diff = (unsigned char)(la != lb);
    for (size_t i = 0; i < n; i++) {
        unsigned char ca = i < la ? (unsigned char)a[i] : 0;
        unsigned char cb = i < lb ? (unsigned char)b[i] : 0;
        diff |= (unsigned char)(ca ^ cb);
    }
    return diff == 0;
}

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

/* 1 when an API key is configured and the request presents it. */
static int auth_has_key(http_req *req)
{
    app *a = req->app;
    const char *k;
    if (!a->cfg.api_key[0])
        return 0;
    k = auth_key_given(req);
    return k && auth_equal(k, a->cfg.api_key);
}

int auth_require_key(http_req *req, http_resp *deny)
{
    app *a = req->app;
    const char *k;
    if (!a->cfg.api_key[0])
        return 0;
    k = auth_key_given(req);
    if (k && auth_equal(k, a->cfg.api_key))
        return 0;
    *deny = http_problem(401, "api-key-required",
                         k ? "the API key presented does not match this daemon's key"
                           : "this daemon requires its API key for %s %s: send "
                             "\"Authorization: Bearer KEY\" or \"X-Api-Key: KEY\"",
                         req->method, req->path);
    http_header(deny, "WWW-Authenticate", "Bearer realm=\"glintd\"");
    return -1;
}

int auth_session(http_req *req, const json_t *session_doc, int need_paint, http_resp *deny)
{
    app *a = req->app;
    const char *tok = http_header_in(req, "X-Glint-Token");
    const char *paint = json_string_value(json_object_get(session_doc, "paint_token"));
    const char *view = json_string_value(json_object_get(session_doc, "view_token"));

    /* Every handler that touches a session passes here with the app: the
     * events module learns the store from it (see events_attach_store). */
    events_attach_store(a->events, a->store);

    if (!tok)
        tok = http_query(req, "token");
    if (auth_has_key(req))
        return 0;
    if (!paint || !view) {
        *deny = http_problem(500, NULL, "session record has no tokens");
        return -1;
    }
    if (!tok || !*tok) {
        *deny = http_problem(401, "token-required",
                             "this session needs its token: send \"X-Glint-Token: TOKEN\" or "
                             "?token=TOKEN (the paint token from the session's share link, or "
                             "the view token for reading)");
        http_header(deny, "WWW-Authenticate", "Bearer realm=\"glint-session\"");
        return -1;
    }
    if (auth_equal(tok, paint))
        return 0;
    if (auth_equal(tok, view)) {
        if (!need_paint)
            return 0;
        *deny = http_problem(403, "read-only-token",
                             "the view token grants reading only: %s %s needs the paint token",
                             req->method, req->path);
        return -1;
    }
    *deny = http_problem(403, "wrong-token", "the token does not grant access to this session");
    return -1;
}
