/* api_common.h: what every api_* handler module shares: the one mapping
 * from glint errors to HTTP answers, and the access checks.
 *
 * Error convention in server/: functions return 0 or a negative GLINT_E*
 * code with a glint_err (err.h), never an HTTP answer; a handler turns a
 * failure into its answer with api_error() only.  The status comes from
 * the code (and, for a few kinds, from err->kind); the problem's type is
 * /problems/<kind> (the code's default kind when none was named); the
 * detail is the message, with the daemon's own paths removed.  Server
 * errors (5xx other than 503) are logged with the full message. */
#ifndef GLINTD_API_COMMON_H
#define GLINTD_API_COMMON_H

#include <jansson.h>

#include "err.h"
#include "http.h"
#include "memo.h"

/* The HTTP status of a glint error (code and kind). */
int api_status(const glint_err *e);

/* The problem+json answer of an error. */
http_resp api_error(const glint_err *e);
/* 201 with body (taken) and Location: /api/v1/<what>/<id>. */
http_resp api_created(json_t *body, const char *what, const char *id);

/* Set *err to `code` with kind `kind` and a printf-style message; returns
 * code (for "return api_reject(err, GLINT_EINVAL, "invalid-input", ...)"). */
int api_reject(glint_err *err, int code, const char *kind, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* The environment of a render request (api_envs.c): env=SPEC (a built-in
 * or data:NAME), env_rotation (degrees), env_intensity, lights (1..1024),
 * shadows and background (0 or 1).  *has: env was given; the others
 * without env are an error.  Kind "invalid-parameter". */
struct render_env;
struct render_env_info;
int api_env_query(http_req *req, struct render_env *out, int *has, glint_err *e);
/* Around a scene creation that may name an uploaded environment, from
 * resolving it to storing the scene: a deletion of an upload waits for
 * the creations in progress, and the next ones wait for it, so that it
 * never misses a scene that names the upload (api_envs.c; within one
 * glintd process). */
void api_envs_use_begin(void);
void api_envs_use_end(void);
/* X-Glint-Env: what an environment render did. */
void api_env_header(http_resp *r, const struct render_env_info *info);
/* A scene's base-render environment, {"spec", "rotation", "intensity",
 * "lights", "shadows", "background"} (all but spec optional, defaults of
 * render_env_init): parsed and checked (GLINT_EINVAL, kind
 * "invalid-input", naming `what`); api_env_json writes it back whole. */
int api_env_parse(const json_t *j, const char *what, struct render_env *out, glint_err *e);
json_t *api_env_json(const struct render_env *env);

/* The same with context: detail "<context>: <message>". */
http_resp api_fail(const glint_err *e, const char *context);

/* The cancel (cancel.h) of a request's work: it says to stop once the
 * client has gone (http_req_gone) or the daemon stops (app.stopping).
 * OUT: *c, valid while req is. */
struct glint_cancel;
void api_cancel_init(http_req *req, struct glint_cancel *c);

/* The cancel of work no one client waits for (a scene's base render, kept
 * for every session): it says to stop once the daemon stops. */
struct app;
void api_stop_cancel_init(struct app *a, struct glint_cancel *c);

/* A ticket (admit.h) for a request's work of `bytes`: the client is the
 * owner key the request sends (X-Glint-Owner, a browser's), else its
 * address (http_client_key); the wait gives up once the client has gone
 * or the daemon stops.  The class is background when `background` is set
 * or the request asks for low priority (RFC 9218's Priority header with an
 * urgency of 4 to 7, less urgent than the default 3: the studio's
 * reference renders), else interactive.  OUT: *t, valid while req is. */
struct admit_ticket;
void api_work_ticket(http_req *req, size_t bytes, int background, struct admit_ticket *t);

/* 1 when the request's Priority header (RFC 9218) states an urgency of 4
 * or more (u=4 .. u=7). */
int api_low_priority(http_req *req);

/* After admitted work (admit.h) ended with rc: a cancelled one is counted
 * (admit_cancelled). */
void api_work_ended(http_req *req, int rc);

/* The request body as a JSON object: Content-Type application/json (or
 * none), not empty, nesting within API_JSON_MAX_DEPTH (counted before
 * parsing), no duplicate keys.  OUT: *out (decref).  Errors: kinds
 * "unsupported-media-type" (415), "invalid-json" (400), "json-too-deep" and
 * "body-too-large" (GLINT_ETOOBIG, 413), "invalid-input" for a non-object
 * (422).
 *
 * The parsed tree is work like a render: jansson takes about 64 bytes a
 * value (measured: 3 million numbers of 1.5 million points, 286 MB), so a
 * body of compact small numbers grows about 30 times when parsed.  The
 * values are counted with the depth, before parsing, and a body whose tree
 * may pass API_JSON_FREE_BYTES holds API_JSON_VALUE_BYTES a value against
 * the work budget (admit.h: 413 over-budget, 503 busy) until the handler
 * returns (the request's release hook, http.h). */
#define API_JSON_MAX_DEPTH 32
#define API_JSON_VALUE_BYTES 96
#define API_JSON_FREE_BYTES ((size_t)4 << 20)
int api_body_json(http_req *req, json_t **out, glint_err *err);

/* 413 naming the body limit and the option that sets it. */
http_resp api_body_too_large(http_req *req, const char *what);

/* Access: the session `sid` if the request may read it (need_paint 0) or
 * write it (1).  OUT: *doc (decref).  GLINT_ENOTFOUND, GLINT_EAUTH,
 * GLINT_EDENIED. */
int api_session(http_req *req, const char *sid, int need_paint, json_t **doc, glint_err *err);

/* The public form of a session doc for the access granted (paint 1: with
 * the paint token and link).  api_sessions.c. */
struct app;
json_t *api_session_public(struct app *a, const json_t *doc, int paint);

/* A session's link lifetime: expires_in seconds from now (expires,
 * expires_unix set in doc) or null (never: removed).  GLINT_EINVAL (kind
 * invalid-input) otherwise.  api_tokens.c. */
#define API_EXPIRES_MIN 1
#define API_EXPIRES_MAX 315360000 /* ten years */
int api_expiry_parse(const json_t *v, json_t *doc, glint_err *e);

/* The links of a material object, the same for every material however it
 * was fitted: self, factors_png, factors_exr, shader, package, eval, merl;
 * a material fitted through a session (session_id and scene_id non-empty)
 * adds session, scene, preview_png and preview_exr; one fitted from a
 * G-buffer set (set_id non-empty; it has no scene to preview on) adds
 * gbuffer_set.  The one place they are made: the fit service takes it as
 * its fitsvc_config.links.  A new object (NULL: out of memory). */
json_t *api_material_links(const char *id, const char *session_id, const char *scene_id,
                           const char *set_id);
/* The same set on a material document as stored (its links of today,
 * whatever it was stored with); 0, or -1 out of memory. */
int api_material_relink(json_t *doc);

/* The material `mid` if the request may read its session.  OUT: *doc (free
 * doc->text). */
int api_material(http_req *req, const char *mid, memo_doc *doc, glint_err *err);
/* Load a stored material (OUT: *m, material_free; api_materials.c). */
struct app;
struct material;
int api_material_load(struct app *a, const char *mid, struct material *m, glint_err *err);
/* Both: the material `mid` loaded if the request may read it (OUT: *m). */
int api_material_read(http_req *req, const char *mid, struct material *m, glint_err *err);

/* A download's file name: "<the scene's mesh>-<the id's first 8
 * characters>.<ext>" ("glint-..." for a material without a scene), cut to
 * [A-Za-z0-9._-] (OUT: out, at most cap - 1 characters).  api_common.c. */
void api_export_filename(struct app *a, const char *mid, const char *scene_id, const char *ext,
                         char *out, size_t cap);
/* Content-Disposition: attachment; filename="<name>" on r (name as
 * api_export_filename makes it: nothing to quote). */
void api_attachment(http_resp *r, const char *name);

/* A scene's base render when its creation names none (api_scenes.c,
 * api_views.c): kd cos(theta_i) I, the Lambert 1/pi undone by the scale. */
#define API_BASE_BRDF "lambert:kd=0.6"
#define API_BASE_SCALE 1.0 /* scene.h's radiance: a white Lambertian facing the light reads I */

/* The method and parameters of a fit request's body {"method", "params"},
 * checked once, before anything is read or queued, for sessions and
 * G-buffer sets alike: every parameter by the method's table, then what
 * they name and need (method_params_usable: an environment the daemon
 * resolves; has_mesh 0, samples from a G-buffer set, refuses what needs a
 * scene's mesh).  Kind "invalid-parameter" (422).  OUT: *m, *params
 * (malloc'ed: free).  api_fits.c. */
struct method;
int api_fit_body(const json_t *body, int has_mesh, const struct method **m, void **params,
                 glint_err *e);

/* The answer to a fit request: 201 with the material `doc` (fitted now;
 * the reference is taken) and its Location, else 202 with job `job_id`
 * and its links.  api_fits.c. */
/* warnings: NULL, or an array of plain sentences (its reference passes to
 * the answer, as "warnings" in the material or beside the job). */
http_resp api_fit_answer(http_req *req, json_t *doc, const char *job_id, json_t *warnings);

/* The warnings of a fit of method m to views that are (point_lit 1) lit
 * by point lights, `why` saying how that is known: a method lit by an
 * environment fitted to them assumes a lighting they were not painted
 * under.  NULL when there is none. */
json_t *api_lighting_warning(const struct method *m, int point_lit, const char *why);

/* G-buffer sets (api_gbuffers.c): 1 when the set `id` exists; 0 when the
 * request may use it (the API key, when one is set), else GLINT_EAUTH. */
int api_gbuffer_set_exists(struct app *a, const char *id);
int api_gbuffer_set_access(http_req *req, const char *id, glint_err *err);

/* A view index from a path segment: decimal digits, 0..n-1 (0), else -1. */
int api_view_index(const char *text, int n, int *k);

/* A non-negative decimal integer of at most 18 digits (0), else -1. */
int api_parse_count(const char *text, long long *out);

/* A file a directory offers (--env-dir, --measured-dir): NAME of
 * [A-Za-z0-9._-], 1..60 bytes, not starting with '.', a regular file whose
 * real path lies inside `dir` (itself a real path; no traversal, no
 * symbolic link out of it).  OUT: real (its real path), *size.  0, else -1. */
int api_dir_file(const char *dir, const char *name, char *real, size_t len, long long *size);

#endif
