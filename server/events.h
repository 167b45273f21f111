/* events.h: per-session event streams (server-sent events).
 *
 * Every event of a session has a session-wide sequence number; a client
 * that reconnects with Last-Event-ID (or ?since=N) receives what it missed,
 * without duplicates or gaps.  Event types: "stroke" (data: the stored
 * stroke record), "painting" (a view's painting replaced), "fit" (a
 * material is ready: its id and summary), "presence" (who is connected).
 * Stroke events are replayed from the store; the others are kept in a
 * bounded in-memory ring per session. */
#ifndef GLINTD_EVENTS_H
#define GLINTD_EVENTS_H

#include <jansson.h>

#include "http.h"

typedef struct events events;

int events_open(events **out);
void events_close(events *ev);

/* Publish an event to the session's listeners (steals `data`). */
void events_publish(events *ev, const char *session, const char *type, json_t *data);

/* An SSE response for a session (used by GET /sessions/{id}/events). */
http_resp events_stream(events *ev, void *app, const char *session, long long since,
                        const char *client_name);

#endif
