/* auth.h: who may do what.
 *
 * - The daemon-wide API key (glintd --api-key), when set, is required for
 *   creation and scripting (creating scenes, meshes, sessions; listing);
 *   sent as "Authorization: Bearer KEY" or "X-Api-Key: KEY".
 * - A session has two tokens (128 random bits each): the paint token grants
 *   reading and writing everything of the session (paintings, strokes, fits,
 *   its materials); the view token grants reading only.  Sent as
 *   "X-Glint-Token: TOKEN" or "?token=TOKEN".  The API key, when set, also
 *   grants everything.
 * Comparisons are constant-time.  Without the right token nothing of a
 * session is readable or writable (404 for unknown ids, 401 without a token,
 * 403 with a token that does not grant the access). */
#ifndef GLINTD_AUTH_H
#define GLINTD_AUTH_H

#include <jansson.h>

#include "http.h"

/* 0 if allowed; else -1 and *deny holds the 401 problem. */
int auth_require_key(http_req *req, http_resp *deny);

/* Access to a session (doc from store_session_get).  need_paint: 1 for
 * writes.  0 if allowed; else -1 and *deny holds a 401/403 problem. */
int auth_session(http_req *req, const json_t *session_doc, int need_paint, http_resp *deny);

#endif
