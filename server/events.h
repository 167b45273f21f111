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

#include "http.h"

#define EVENTS_KEEPALIVE_S 15

typedef struct events events;
struct store;

int events_open(events **out);
void events_close(events *ev);

/* The store holding the sessions' event logs.  Call once after both are
 * open (glintd.c); until then the module learns it from the first
 * events_stream or auth_session call (both see the app). */
void events_attach_store(events *ev, struct store *s);

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

/* An SSE response for a session (used by GET /sessions/{id}/events):
 * replays the log after `since`, then follows it live.  client_name (may
 * be NULL) is shown in presence.  The caller has checked access. */
http_resp events_stream(events *ev, http_req *req, const char *session, long long since,
                        const char *client_name);

#endif
