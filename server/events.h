/* events.h: per-session event streams (server-sent events).
 *
 * Every durable event of a session has a session-wide sequence number, the
 * same numbering as its strokes (store.h: the session's event log), sent
 * as the SSE "id:".  Durable types: "stroke" (a stroke applied to a view),
 * "painting" (a view's painting replaced by an upload), "fit" (a material
 * is ready) and any other type published here.  A stream always reads the
 * log from the store in sequence order (replay and live alike: a publish
 * only wakes the streams), so a client that reconnects with Last-Event-ID
 * (or ?since=N) receives exactly the events after N: no duplicates, no
 * gaps, across daemon restarts too.
 *
 * "presence" (who is connected to the session's stream, with the ?name=
 * each client gave) is not durable: it carries no id (so it does not move
 * a client's Last-Event-ID), is sent to a client when it connects and to
 * every client when someone joins or leaves.
 *
 * Wire format, one event:
 *   id: 17
 *   event: stroke
 *   data: {"seq":17,"type":"stroke","view":3,"data":{...the stroke...},"created":"..."}
 * (data is one line of JSON: proto/schemas/SessionEvent.json;
 * presence: proto/schemas/Presence.json), a "retry: 2000" first, and a
 * ": keep-alive" comment every EVENTS_KEEPALIVE_S seconds of silence.
 * A stream ends when the client goes away or the daemon stops. */
#ifndef GLINTD_EVENTS_H
#define GLINTD_EVENTS_H

#include <jansson.h>
#include <sys/types.h>

#include "http.h"

#define EVENTS_KEEPALIVE_S 15

typedef struct events events;
struct store;

/* st: the store holding the sessions' event logs (it must outlive ev). */
int events_open(struct store *st, events **out);
void events_close(events *ev);

/* End every stream promptly (call before http_server_stop, so stopping
 * does not wait for the streams' next keep-alive). */
void events_shutdown(events *ev);

/* Publish an event to the session's listeners (steals `data`, a JSON
 * object).  "stroke" and "painting" are appended to the log by the store
 * calls that make them (store_strokes_append, store_painting_put): for
 * those this only wakes the streams.  Any other type (e.g. "fit") is
 * appended to the session's log here, taking the next sequence number,
 * then sent.  "presence" is reserved.  Failures are logged, not returned:
 * the event is lost, the caller's request is not. */
void events_publish(events *ev, const char *session, const char *type, json_t *data);

/* Wake the session's streams after its log grew. */
void events_notify(events *ev, const char *session);
/* Wake every stream (any log may have grown: another replica's changes
 * could not be heard for a while). */
void events_notify_all(events *ev);
/* For store_listen (ctx: the events): another process's change of a
 * session: "log" wakes its streams, "revoke" ends them; session NULL:
 * anything may have changed, every stream reads its log again. */
void events_on_store_change(void *ctx, const char *session, const char *what);
/* The session's tokens were revoked: every stream open now ends (a client
 * still holding a valid token reconnects with it, from its Last-Event-ID). */
void events_revoke(events *ev, const char *session);

/* ---- a stream without its transport ------------------------------------------ */
/* The core of one client's stream, which events_stream() serves over HTTP
 * (and tests drive directly).  One thread at a time per stream. */
#define EVENTS_POLL_MS 250           /* longest single wait of events_stream_next */
#define EVENTS_STREAM_END (-1)       /* events_stream_next: the stream is over */
#define EVENTS_STREAM_ERROR (-2)     /* events_stream_next: it failed (logged) */
#define EVENTS_NAME_MAX 64           /* bytes of a presence name */

typedef struct ev_stream ev_stream;

/* Join the session's listeners (every listener of the session gets a new
 * presence event) and start after sequence number `since` (<= 0: the
 * whole log).  name: shown in presence (may be NULL), cleaned: control
 * characters dropped, at most EVENTS_NAME_MAX bytes of valid UTF-8,
 * "anonymous" when nothing is left.  fd: the client's socket, polled for
 * hang-ups, or -1.  The session is not checked (the caller has).  OUT:
 * *out, released with events_stream_close.  0, GLINT_ENOMEM, or the error
 * of the random id. */
int events_stream_open(events *ev, const char *session, long long since, const char *name,
                       int fd, ev_stream **out);

/* The stream's next bytes into out[0..max) (max > 0), in wire format: the
 * "retry:" preamble first, then the log after `since` and the presence
 * list, then what comes, with a keep-alive after EVENTS_KEEPALIVE_S quiet
 * seconds.  Returns the number of bytes written (> 0); 0 when nothing came
 * within one wait of up to EVENTS_POLL_MS (call again); EVENTS_STREAM_END
 * once events_shutdown was called or the client on fd went away;
 * EVENTS_STREAM_ERROR when the log cannot be read or memory ran out. */
ssize_t events_stream_next(ev_stream *s, char *out, size_t max);

/* Leave the session's listeners (the others get a new presence event) and
 * free the stream.  Accepts NULL. */
void events_stream_close(ev_stream *s);

/* An SSE response for a session (used by GET /sessions/{id}/events):
 * replays the log after `since`, then follows it live.  client_name (may
 * be NULL) is shown in presence.  The caller has checked access.  The
 * response streams with events_stream_open / _next / _close above. */
http_resp events_stream(events *ev, http_req *req, const char *session, long long since,
                        const char *client_name);

#endif
