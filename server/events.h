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
 * A stream ends when the client goes away or the daemon stops, and a
 * stream admitted by a session token (events_access.token) when that
 * token stops granting access: its tokens replaced (events_revoke_end,
 * or another replica's "revoke"), its links expired.  Such a stream checks
 * its token again, against the stored session, before it sends anything
 * more whenever the session's tokens changed or its expiry passed, and
 * sends nothing once the token is refused: what it had read but not sent
 * is dropped.
 *
 * Memory.  A stream reads the log only when it has sent everything it
 * read, at most EVENTS_STREAM_BUF bytes of event data at a time (one event
 * when a single one is larger), so a client that stops reading holds that
 * much and no more: the rest waits in the store, and libmicrohttpd drops
 * the connection once it has taken nothing for its idle timeout.  At most
 * max_per_session streams are open on one session and max_per_client for
 * one client (events_set_limits): beyond, events_stream answers 429
 * "too-many-streams". */
#ifndef GLINTD_EVENTS_H
#define GLINTD_EVENTS_H

#include <jansson.h>
#include <sys/types.h>
#include <time.h>

#include "err.h"

#include "http.h"

#define EVENTS_KEEPALIVE_S 15
#define EVENTS_STREAM_BUF (64u << 10)          /* event data read at a time */
#define EVENTS_MAX_PER_SESSION_DEFAULT 32      /* glintd --max-streams-per-session */
#define EVENTS_MAX_PER_CLIENT_DEFAULT 16       /* glintd --max-streams-per-client */

typedef struct events events;
struct store;

/* st: the store holding the sessions' event logs (it must outlive ev).
 * The limits start at their defaults. */
int events_open(struct store *st, events **out);
void events_close(events *ev);

/* Streams open at once on one session and for one client (0: the
 * default).  Call before streams open. */
void events_set_limits(events *ev, unsigned max_per_session, unsigned max_per_client);

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
 * session: "log" wakes its streams, "revoke" has them check their tokens;
 * session NULL: anything may have changed, every stream reads its log and
 * checks its token again. */
void events_on_store_change(void *ctx, const char *session, const char *what);
/* The session's tokens or their expiry are about to change: its streams
 * admitted by a token send nothing until events_revoke_end (always call
 * it after, whether the change was stored or not). */
void events_revoke_begin(events *ev, const char *session);
/* The change is over (stored, or not): every stream of the session
 * admitted by a token checks it again and ends if it no longer grants
 * access (a client that still holds a valid token reconnects with it,
 * from its Last-Event-ID). */
void events_revoke_end(events *ev, const char *session);

/* ---- a stream without its transport ------------------------------------------ */
/* The core of one client's stream, which events_stream() serves over HTTP
 * (and tests drive directly).  One thread at a time per stream. */
#define EVENTS_POLL_MS 250           /* longest single wait of events_stream_next */
#define EVENTS_STREAM_END (-1)       /* events_stream_next: the stream is over */
#define EVENTS_STREAM_ERROR (-2)     /* events_stream_next: it failed (logged) */
#define EVENTS_NAME_MAX 64           /* bytes of a presence name */

typedef struct ev_stream ev_stream;

/* Whether `token` still grants reading `session` (0), or not (non-zero:
 * replaced, expired, the session gone, the store unreadable).  OUT:
 * *expires: when it stops granting it by itself (0: never). */
typedef int (*events_check_fn)(void *ctx, const char *session, const char *token,
                               time_t *expires);

/* Who a stream serves (every member may be NULL). */
typedef struct events_access {
    /* The session token the stream was admitted with, checked with
     * check(ctx, ...) as said above; NULL: admitted otherwise (the API
     * key), never checked. */
    const char *token;
    events_check_fn check;
    void *ctx;
    /* The client, for the per-client limit (http_client_key); NULL or "":
     * not counted. */
    const char *client;
} events_access;

/* Join the session's listeners (every listener of the session gets a new
 * presence event) and start after sequence number `since` (<= 0: the
 * whole log).  name: shown in presence (may be NULL), cleaned: control
 * characters dropped, at most EVENTS_NAME_MAX bytes of valid UTF-8,
 * "anonymous" when nothing is left.  fd: the client's socket, polled for
 * hang-ups, or -1.  acc: who it serves (NULL: no token, no client).  The
 * session is not checked (the caller has); a token is checked again
 * before the first byte.  OUT: *out, released with events_stream_close.
 * 0; GLINT_EBUSY (kind "too-many-streams", the message naming the limit)
 * when the session or the client has its most streams open; GLINT_ENOMEM;
 * or the error of the random id. */
int events_stream_open(events *ev, const char *session, long long since, const char *name,
                       int fd, const events_access *acc, ev_stream **out, glint_err *err);

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
 * be NULL) is shown in presence.  The caller has checked access; acc says
 * with what (its client is filled in here).  429 too-many-streams beyond
 * the limits.  The response streams with events_stream_open / _next /
 * _close above. */
http_resp events_stream(events *ev, http_req *req, const char *session, long long since,
                        const char *client_name, const events_access *acc);

#endif
