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
 * - A scene belongs to the owner key it was created with: a secret the
 *   client chooses (16 to 128 characters of A-Z a-z 0-9 _ -), sent as
 *   "X-Glint-Owner: KEY"; when a creation sends none, the daemon makes one
 *   (32 hex digits) and answers it once.  Listing scenes shows the caller's
 *   own (everything with the API key); deleting one needs its owner key or
 *   the API key.  Reading a scene by id needs nothing: ids are 128 random
 *   bits, and only their owners can list them.  Uploaded environments and
 *   G-buffer sets belong to an owner key the same way (auth_owner).
 * - A session's links may expire (created with expires_in): after that
 *   both tokens are refused (403, kind "link-expired"); and its tokens may
 *   be revoked and replaced (POST /sessions/{id}/tokens, by the paint
 *   token, the scene's owner key or the API key): the old links are then
 *   refused (403 "wrong-token"), and event streams opened with a token
 *   end once it no longer grants access (revoked, or expired).
 * Comparisons are constant-time.  Without the right token nothing of a
 * session is readable or writable (404 for unknown ids, 401 without a token,
 * 403 with a token that does not grant the access). */
#ifndef GLINTD_AUTH_H
#define GLINTD_AUTH_H

#include <jansson.h>
#include <time.h>

#include "err.h"
#include "http.h"

/* Length bounds of an owner key (characters). */
#define AUTH_OWNER_MIN 16
#define AUTH_OWNER_MAX 128

/* 0 if allowed; else GLINT_EAUTH (kind "api-key-required"). */
int auth_require_key(http_req *req, glint_err *err);

/* 1 when a key is configured and the request presents it. */
int auth_has_key(http_req *req);

/* Access to a session (doc from store_session_get).  need_paint: 1 for
 * writes.  0 if allowed; else GLINT_EAUTH (kind "token-required") or
 * GLINT_EDENIED (kinds "read-only-token", "wrong-token", "link-expired"). */
int auth_session(http_req *req, const json_t *session_doc, int need_paint, glint_err *err);

/* The session token the request presents (X-Glint-Token, else ?token=),
 * or NULL. */
const char *auth_token_given(http_req *req);

/* Whether `token` is the session's paint or view token (doc from
 * store_session_get) and its links have not expired at `now`: 1 or 0.
 * OUT: *expires (may be NULL): when the links expire (0: never). */
int auth_token_current(const json_t *session_doc, const char *token, time_t now,
                       time_t *expires);

/* The owner key the request presents (X-Glint-Owner): *key NULL when none
 * is sent; GLINT_EINVAL (kind "invalid-owner-key") when it is malformed. */
int auth_owner_key(http_req *req, const char **key, glint_err *err);

/* The owner key a creation records: the one the request presents, else a
 * new one (32 hex digits) made in `made`.  OUT: *key (the header's or
 * `made`).  GLINT_EINVAL (kind "invalid-owner-key") for a malformed one. */
int auth_owner_new(http_req *req, char made[33], const char **key, glint_err *err);

/* Whether the request may administer the thing whose record is `doc`
 * ("owner": its owner key; a record without one is the API key's only):
 * the API key, or that owner key.  `what` names it in messages ("scene",
 * "environment", "G-buffer set").  0 if allowed; else GLINT_EAUTH (kind
 * "owner-key-required") or GLINT_EDENIED (kind "not-owner"). */
int auth_owner(http_req *req, const json_t *doc, const char *what, glint_err *err);

/* Whether a record belongs to the owner key `key` (NULL: none presented,
 * 0): a constant-time comparison with its "owner". */
int auth_owned_by(const json_t *doc, const char *key);

/* auth_owner for a scene (doc from store_scene_get). */
int auth_scene_owner(http_req *req, const json_t *scene_doc, glint_err *err);

#endif
