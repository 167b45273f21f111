/* events.c: server-sent event streams per session (events.h).
 *
 * One hub per session with listeners: a generation counter bumped by every
 * publish and the presence list.  A stream runs on its connection's own
 * thread (libmicrohttpd thread per connection): MHD calls the content
 * reader (stream_read), which asks events_stream_next for the next bytes:
 * buffered bytes or, when it has none, the session's log after the last
 * sequence number it sent, the presence list when it changed, or a wait on
 * the module's condition variable.  Waits are short (EVENTS_POLL_MS) so a
 * stream notices at once when its client has gone (the socket reads EOF or
 * hangs up) or the daemon stops. */
#include "events.h"

#include <errno.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>

#include "app.h"
#include "buf.h"
#include "ids.h"
#include "json_text.h"
#include "log.h"
#include "store.h"

#define EVENTS_TOKEN_MAX 128   /* longest token kept (tokens are 32 hex digits) */
#define EVENTS_BATCH 64        /* log rows read per wake-up, at most */

typedef struct ev_hub {
    char session[33];
    unsigned long gen;         /* bumped by every publish / notify */
    unsigned long presence;    /* bumped when a listener joins or leaves */
    unsigned long revoked;     /* bumped when the session's tokens changed */
    unsigned revoking;         /* changes of the tokens under way (events_revoke_begin) */
    unsigned nlisteners;
    ev_stream *listeners;
    struct ev_hub *next;
} ev_hub;

/* A client with streams open (for the per-client limit). */
typedef struct ev_client {
    char key[HTTP_CLIENT_KEY_MAX];
    unsigned streams;
    struct ev_client *next;
} ev_client;

struct events {
    pthread_mutex_t lock;
    pthread_cond_t cond;       /* broadcast on every change */
    ev_hub *hubs;
    ev_client *clients;
    unsigned max_per_session, max_per_client;
    store *st;
    int stopping;
};

struct ev_stream {
    events *ev;
    ev_hub *hub;
    ev_stream *next;           /* in hub->listeners */
    int fd;                    /* the client's socket, for hang-up checks (-1: unknown) */
    int64_t last;              /* last sequence number sent */
    unsigned long seen_gen;
    unsigned long seen_presence;
    unsigned long revoked;     /* the hub's count when the token was last checked */
    int started;
    /* the session token the stream was admitted with ("": none, never checked) */
    char token[EVENTS_TOKEN_MAX + 1];
    events_check_fn check;
    void *check_ctx;
    time_t expires;            /* the token expires then (0: never) */
    ev_client *client;         /* counted for this client (NULL: not counted) */
    char id[17];               /* this listener's id in presence */
    char name[EVENTS_NAME_MAX + 1];
    glint_buf buf;             /* pending output */
    size_t off;
    struct timespec last_write;
};

int events_open(store *st, events **out)
{
    events *ev = calloc(1, sizeof *ev);
    pthread_condattr_t ca;
    *out = NULL;
    if (!ev)
        return GLINT_ENOMEM;
    ev->st = st;
    ev->max_per_session = EVENTS_MAX_PER_SESSION_DEFAULT;
    ev->max_per_client = EVENTS_MAX_PER_CLIENT_DEFAULT;
    pthread_mutex_init(&ev->lock, NULL);
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&ev->cond, &ca);
    pthread_condattr_destroy(&ca);
    *out = ev;
    return 0;
}

void events_set_limits(events *ev, unsigned max_per_session, unsigned max_per_client)
{
    ev->max_per_session = max_per_session ? max_per_session : EVENTS_MAX_PER_SESSION_DEFAULT;
    ev->max_per_client = max_per_client ? max_per_client : EVENTS_MAX_PER_CLIENT_DEFAULT;
}

void events_shutdown(events *ev)
{
    if (!ev)
        return;
    pthread_mutex_lock(&ev->lock);
    ev->stopping = 1;
    pthread_cond_broadcast(&ev->cond);
    pthread_mutex_unlock(&ev->lock);
}

void events_close(events *ev)
{
    ev_hub *h, *n;
    ev_client *c, *cn;
    if (!ev)
        return;
    /* glintd stops the HTTP server first, so no stream is left */
    for (h = ev->hubs; h; h = n) {
        n = h->next;
        free(h);
    }
    for (c = ev->clients; c; c = cn) {
        cn = c->next;
        free(c);
    }
    pthread_cond_destroy(&ev->cond);
    pthread_mutex_destroy(&ev->lock);
    free(ev);
}

/* The hub of a session (created on demand); ev->lock held. */
static ev_hub *events_hub(events *ev, const char *session, int create)
{
    ev_hub *h;
    for (h = ev->hubs; h; h = h->next)
        if (strcmp(h->session, session) == 0)
            return h;
    if (!create)
        return NULL;
    h = calloc(1, sizeof *h);
    if (!h)
        return NULL;
    snprintf(h->session, sizeof h->session, "%s", session);
    h->next = ev->hubs;
    ev->hubs = h;
    return h;
}

/* Drop a hub nobody listens to (and nobody is changing the tokens of);
 * ev->lock held. */
static void events_hub_release(events *ev, ev_hub *hub)
{
    ev_hub **p;
    if (hub->listeners || hub->revoking)
        return;
    for (p = &ev->hubs; *p; p = &(*p)->next)
        if (*p == hub) {
            *p = hub->next;
            free(hub);
            return;
        }
}

/* The client's entry, made if new (NULL: out of memory); ev->lock held. */
static ev_client *events_client(events *ev, const char *key)
{
    ev_client *c;
    for (c = ev->clients; c; c = c->next)
        if (strcmp(c->key, key) == 0)
            return c;
    c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    snprintf(c->key, sizeof c->key, "%s", key);
    c->next = ev->clients;
    ev->clients = c;
    return c;
}

/* Drop a client with no stream left; ev->lock held. */
static void events_client_release(events *ev, ev_client *client)
{
    ev_client **p;
    if (!client || client->streams)
        return;
    for (p = &ev->clients; *p; p = &(*p)->next)
        if (*p == client) {
            *p = client->next;
            free(client);
            return;
        }
}

void events_revoke_begin(events *ev, const char *session)
{
    ev_hub *h;
    if (!ev || !session)
        return;
    pthread_mutex_lock(&ev->lock);
    h = events_hub(ev, session, 1);
    if (h)
        h->revoking++;
    pthread_mutex_unlock(&ev->lock);
}

/* The session's tokens changed: its token streams check theirs again
 * (ending: this ends an events_revoke_begin of this process). */
static void events_tokens_changed(events *ev, const char *session, int ending)
{
    ev_hub *h;
    pthread_mutex_lock(&ev->lock);
    h = events_hub(ev, session, 0);
    if (h) {
        h->revoked++;
        if (ending && h->revoking)
            h->revoking--;
        events_hub_release(ev, h);
    }
    pthread_cond_broadcast(&ev->cond);
    pthread_mutex_unlock(&ev->lock);
}

void events_revoke_end(events *ev, const char *session)
{
    if (ev && session)
        events_tokens_changed(ev, session, 1);
}

void events_notify(events *ev, const char *session)
{
    ev_hub *h;
    if (!ev || !session)
        return;
    pthread_mutex_lock(&ev->lock);
    h = events_hub(ev, session, 0);
    if (h) {
        h->gen++;
        pthread_cond_broadcast(&ev->cond);
    }
    pthread_mutex_unlock(&ev->lock);
}

void events_notify_all(events *ev)
{
    if (!ev)
        return;
    pthread_mutex_lock(&ev->lock);
    for (ev_hub *h = ev->hubs; h; h = h->next)
        h->gen++;
    pthread_cond_broadcast(&ev->cond);
    pthread_mutex_unlock(&ev->lock);
}

void events_on_store_change(void *ctx, const char *session, const char *what)
{
    events *ev = ctx;
    if (!session) {
        /* notifications were missed: tokens may have changed too */
        pthread_mutex_lock(&ev->lock);
        for (ev_hub *h = ev->hubs; h; h = h->next)
            h->revoked++;
        pthread_mutex_unlock(&ev->lock);
        events_notify_all(ev);
    } else if (!strcmp(what, "revoke"))
        events_tokens_changed(ev, session, 0);
    else
        events_notify(ctx, session);
}

void events_publish(events *ev, const char *session, const char *type, json_t *data)
{
    glint_err e;
    store *st;

    if (!ev || !session || !type) {
        json_decref(data);
        return;
    }
    if (strcmp(type, "stroke") == 0 || strcmp(type, "painting") == 0) {
        json_decref(data);
        events_notify(ev, session);
        return;
    }
    if (strcmp(type, "presence") == 0) {
        json_decref(data);
        return;
    }
    st = ev->st;
    if (!json_is_object(data)) {
        log_line("events: \"%s\" event of session %s has no JSON object, lost", type,
                 session);
    } else if (store_event_append(st, session, type, -1, data, NULL, &e)) {
        log_line("events: \"%s\" event of session %s lost: %s", type, session, e.msg);
    } else {
        events_notify(ev, session);
    }
    json_decref(data);
}

/* ------------------------------------------------------------------------ */
/* Streams                                                                   */
/* ------------------------------------------------------------------------ */

/* One SSE event: optional id, type, one line of JSON. */
static int stream_event(ev_stream *s, long long id, const char *type, const json_t *data)
{
    char *text = json_text(data, 0);
    int rc;
    if (!text)
        return -1;
    rc = (id > 0 ? glint_buf_printf(&s->buf, "id: %lld\n", id) : 0) ||
         glint_buf_printf(&s->buf, "event: %s\ndata: %s\n\n", type, text);
    free(text);
    return rc ? -1 : 0;
}

/* The presence event of the stream's hub; ev->lock held. */
static json_t *events_presence(ev_hub *hub)
{
    json_t *clients = json_array(), *o;
    int n = 0;
    for (ev_stream *l = hub->listeners; l; l = l->next) {
        json_array_append_new(clients, json_pack("{s:s, s:s}", "id", l->id, "name", l->name));
        n++;
    }
    o = json_pack("{s:s, s:o, s:i}", "type", "presence", "clients", clients, "count", n);
    return o;
}

/* 1 when the client has gone (EOF, hang-up, error) or cannot be checked. */
static int stream_client_gone(const ev_stream *s)
{
    struct pollfd p;
    char c;
    if (s->fd < 0)
        return 0;
    p.fd = s->fd;
    p.events = POLLIN;
    p.revents = 0;
    if (poll(&p, 1, 0) <= 0)
        return 0;
    if (p.revents & (POLLHUP | POLLERR | POLLNVAL))
        return 1;
    if (p.revents & POLLIN) {
        ssize_t n = recv(s->fd, &c, 1, MSG_PEEK | MSG_DONTWAIT);
        if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR))
            return 1;
    }
    return 0;
}

/* Whether text can go into an SSE frame as it is: one line, and (quoted)
 * no character a JSON string would escape. */
static int frame_safe(const char *text, int quoted)
{
    for (const unsigned char *c = (const unsigned char *)text; *c; c++)
        if (*c == '\n' || *c == '\r' || (quoted && (*c < 0x20 || *c == '"' || *c == '\\')))
            return 0;
    return 1;
}

/* store_event_fn: one event of the log into the stream's buffer, its data
 * text as stored (compact JSON, one line: what json_text would write
 * again), so reading costs no JSON tree.  Text that would not frame is
 * parsed and written again. */
static int stream_row(void *ctx, const store_event_row *r, glint_err *err)
{
    ev_stream *s = ctx;
    char view[32] = "";
    int rc;

    if (r->view >= 0)
        snprintf(view, sizeof view, ",\"view\":%lld", (long long)r->view);
    if (r->data[0] && frame_safe(r->data, 0) && frame_safe(r->type, 1) &&
        frame_safe(r->created, 1)) {
        rc = glint_buf_printf(&s->buf, "id: %lld\nevent: %s\ndata: {\"seq\":%lld,\"type\":\"%s\"%s,"
                                       "\"data\":",
                              (long long)r->seq, r->type, (long long)r->seq, r->type, view) ||
             glint_buf_append(&s->buf, r->data, strlen(r->data)) ||
             glint_buf_printf(&s->buf, ",\"created\":\"%s\"}\n\n", r->created);
    } else {
        json_error_t je;
        json_t *data = json_loads(r->data, 0, &je), *rec;
        if (!data)
            return glint_err_set(err, GLINT_EFORMAT, "event %lld holds malformed JSON: %s",
                                 (long long)r->seq, je.text);
        rec = json_pack("{s:I, s:s, s:o, s:s}", "seq", (json_int_t)r->seq, "type", r->type,
                        "data", data, "created", r->created);
        if (rec && r->view >= 0)
            json_object_set_new(rec, "view", json_integer((json_int_t)r->view));
        rc = !rec || stream_event(s, r->seq, r->type, rec);
        json_decref(rec);
    }
    if (rc)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory writing event %lld",
                             (long long)r->seq);
    s->last = r->seq;
    return 0;
}

/* Read the log after s->last into the buffer, about EVENTS_STREAM_BUF
 * bytes of it at most (one event when it is larger).  Returns 1 when more
 * may be left, 0 when the log was read to its end, -1 on a store error. */
static int stream_read_log(ev_stream *s, store *st)
{
    glint_err e;
    int more = 0;

    if (store_events_each(st, s->hub->session, s->last, EVENTS_BATCH, EVENTS_STREAM_BUF,
                          stream_row, s, &more, &e)) {
        log_line("events of session %s: %s", s->hub->session, e.msg);
        return -1;
    }
    return more;
}

#define TOKEN_OK 0       /* stream_token_state: go on */
#define TOKEN_REFUSED 1  /* ... end, sending nothing more */
#define TOKEN_HOLD 2     /* ... a change of the tokens is under way: send nothing yet */

/* Whether the stream may go on sending: checked against the store when
 * the session's tokens changed since the last check, or the token's
 * expiry passed.  While a change of the tokens is under way, waits for it
 * once (up to EVENTS_POLL_MS) and answers TOKEN_HOLD if it goes on. */
static int stream_token_state(ev_stream *s)
{
    events *ev = s->ev;
    unsigned long revoked;
    time_t expires = 0;
    int stopping, hold;

    if (!s->token[0])
        return TOKEN_OK;
    pthread_mutex_lock(&ev->lock);
    if (s->hub->revoking && !ev->stopping) {
        struct timespec until;
        clock_gettime(CLOCK_MONOTONIC, &until);
        until.tv_nsec += (long)EVENTS_POLL_MS * 1000000L;
        if (until.tv_nsec >= 1000000000L) {
            until.tv_sec++;
            until.tv_nsec -= 1000000000L;
        }
        pthread_cond_timedwait(&ev->cond, &ev->lock, &until);
    }
    hold = s->hub->revoking != 0;
    revoked = s->hub->revoked;
    stopping = ev->stopping;
    pthread_mutex_unlock(&ev->lock);
    if (stopping)
        return TOKEN_OK; /* the caller ends the stream anyway */
    if (hold)
        return TOKEN_HOLD;
    if (revoked == s->revoked && !(s->expires && time(NULL) >= s->expires))
        return TOKEN_OK;
    /* the count read before the session: a change after it is seen next time */
    if (s->check(s->check_ctx, s->hub->session, s->token, &expires))
        return TOKEN_REFUSED;
    s->revoked = revoked;
    s->expires = expires;
    return TOKEN_OK;
}

ssize_t events_stream_next(ev_stream *s, char *out, size_t max)
{
    events *ev = s->ev;
    int waited = 0;

    for (;;) {
        unsigned long gen, presence;
        int stopping, recheck, gone;
        store *st;

        switch (stream_token_state(s)) {
        case TOKEN_REFUSED: /* nothing more goes to a client whose token was refused */
            s->off = 0;
            glint_buf_free(&s->buf);
            return EVENTS_STREAM_END;
        case TOKEN_HOLD:
            if (waited)
                return 0;
            waited = 1;
            continue;
        default:
            break;
        }
        if (s->off < s->buf.len) {
            size_t n = s->buf.len - s->off;
            if (n > max)
                n = max;
            memcpy(out, s->buf.data + s->off, n);
            s->off += n;
            if (s->off == s->buf.len) {
                s->off = 0;
                /* keep a usual buffer, not one a large event grew */
                if (s->buf.cap > 2 * EVENTS_STREAM_BUF)
                    glint_buf_free(&s->buf);
                else
                    glint_buf_clear(&s->buf);
            }
            clock_gettime(CLOCK_MONOTONIC, &s->last_write);
            return (ssize_t)n;
        }

        pthread_mutex_lock(&ev->lock);
        stopping = ev->stopping;
        gen = s->hub->gen;
        presence = s->hub->presence;
        st = ev->st;
        recheck = s->token[0] && (s->hub->revoked != s->revoked || s->hub->revoking);
        if (!stopping && !recheck && s->started && gen == s->seen_gen &&
            presence == s->seen_presence) {
            struct timespec until;
            if (waited) { /* a whole wait without news: let the caller decide */
                pthread_mutex_unlock(&ev->lock);
                return 0;
            }
            /* nothing new: wait a little, then check the client and the clock */
            clock_gettime(CLOCK_MONOTONIC, &until);
            until.tv_nsec += (long)EVENTS_POLL_MS * 1000000L;
            if (until.tv_nsec >= 1000000000L) {
                until.tv_sec++;
                until.tv_nsec -= 1000000000L;
            }
            pthread_cond_timedwait(&ev->cond, &ev->lock, &until);
            waited = 1;
            stopping = ev->stopping;
            gen = s->hub->gen;
            presence = s->hub->presence;
            recheck = s->token[0] && (s->hub->revoked != s->revoked || s->hub->revoking);
        }
        pthread_mutex_unlock(&ev->lock);
        if (stopping)
            return EVENTS_STREAM_END;
        if (recheck)
            continue; /* the token is checked at the top */

        if (!s->started) {
            s->started = 1;
            if (glint_buf_printf(&s->buf, "retry: 2000\n: glintd session\n\n"))
                return EVENTS_STREAM_ERROR;
            s->seen_gen = gen - 1; /* read the log at once (replay) */
        }
        if (gen != s->seen_gen) {
            /* Note the generation before reading: a publish after this
             * point bumps it again and triggers another read. */
            int more = stream_read_log(s, st);
            if (more < 0)
                return EVENTS_STREAM_ERROR;
            if (!more)
                s->seen_gen = gen;
        }
        if (presence != s->seen_presence) {
            json_t *p;
            pthread_mutex_lock(&ev->lock);
            p = events_presence(s->hub);
            s->seen_presence = s->hub->presence;
            pthread_mutex_unlock(&ev->lock);
            if (!p || stream_event(s, 0, "presence", p)) {
                json_decref(p);
                return EVENTS_STREAM_ERROR;
            }
            json_decref(p);
        }
        if (s->buf.len > 0)
            continue;
        gone = stream_client_gone(s);
        if (gone)
            return EVENTS_STREAM_END;
        {
            struct timespec now;
            clock_gettime(CLOCK_MONOTONIC, &now);
            if ((double)(now.tv_sec - s->last_write.tv_sec) +
                    1e-9 * (double)(now.tv_nsec - s->last_write.tv_nsec) >=
                EVENTS_KEEPALIVE_S) {
                if (glint_buf_printf(&s->buf, ": keep-alive\n\n"))
                    return EVENTS_STREAM_ERROR;
            }
        }
    }
}

void events_stream_close(ev_stream *s)
{
    events *ev;
    ev_stream **p;

    if (!s)
        return;
    ev = s->ev;
    pthread_mutex_lock(&ev->lock);
    for (p = &s->hub->listeners; *p; p = &(*p)->next)
        if (*p == s) {
            *p = s->next;
            break;
        }
    s->hub->nlisteners--;
    if (s->client) {
        s->client->streams--;
        events_client_release(ev, s->client);
    }
    s->hub->presence++;
    pthread_cond_broadcast(&ev->cond);
    events_hub_release(ev, s->hub);
    pthread_mutex_unlock(&ev->lock);
    glint_buf_free(&s->buf);
    free(s);
}

/* A presence name: printable, at most EVENTS_NAME_MAX bytes of valid
 * UTF-8 (anything else becomes "anonymous"). */
static void events_clean_name(const char *in, char *out)
{
    size_t n = 0;
    json_t *probe;
    if (in)
        for (const unsigned char *c = (const unsigned char *)in; *c && n < EVENTS_NAME_MAX; c++)
            if (*c >= 0x20 && *c != 0x7f)
                out[n++] = (char)*c;
    out[n] = '\0';
    /* a cut in the middle of a multi-byte character: drop the tail */
    while (n > 0 && !(probe = json_string(out)))
        out[--n] = '\0';
    if (n > 0)
        json_decref(probe);
    else
        snprintf(out, EVENTS_NAME_MAX + 1, "anonymous");
}

/* Count the stream in for its session and client, within the limits;
 * ev->lock held.  0, GLINT_EBUSY or GLINT_ENOMEM (err says which). */
static int events_admit(events *ev, ev_stream *s, const char *session, const char *client,
                        glint_err *err)
{
    s->hub = events_hub(ev, session, 1);
    if (!s->hub)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory opening an event stream");
    if (s->hub->nlisteners >= ev->max_per_session) {
        glint_err_set(err, GLINT_EBUSY,
                      "session %.32s already has %u event streams open, the most one session "
                      "may have (glintd --max-streams-per-session %u)",
                      session, s->hub->nlisteners, ev->max_per_session);
        events_hub_release(ev, s->hub);
        return glint_err_kind(err, "too-many-streams");
    }
    if (client && client[0]) {
        s->client = events_client(ev, client);
        if (!s->client) {
            events_hub_release(ev, s->hub);
            return glint_err_set(err, GLINT_ENOMEM, "out of memory opening an event stream");
        }
        if (s->client->streams >= ev->max_per_client) {
            glint_err_set(err, GLINT_EBUSY,
                          "this client (%.64s) already has %u event streams open, the most one "
                          "client may have (glintd --max-streams-per-client %u)",
                          client, s->client->streams, ev->max_per_client);
            events_client_release(ev, s->client);
            events_hub_release(ev, s->hub);
            return glint_err_kind(err, "too-many-streams");
        }
        s->client->streams++;
    }
    s->hub->nlisteners++;
    return 0;
}

int events_stream_open(events *ev, const char *session, long long since, const char *name,
                       int fd, const events_access *acc, ev_stream **out, glint_err *err)
{
    ev_stream *s;
    char id[33];
    int rc;

    *out = NULL;
    if (acc && acc->token && (!acc->check || strlen(acc->token) > EVENTS_TOKEN_MAX))
        return glint_err_set(err, GLINT_EINVAL, "events: a token stream needs a check and a "
                                                "token of at most %d bytes", EVENTS_TOKEN_MAX);
    s = calloc(1, sizeof *s);
    if (!s)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory opening an event stream");
    if ((rc = glint_id_new(id, err))) {
        free(s);
        return rc;
    }
    s->ev = ev;
    s->fd = fd;
    s->last = since > 0 ? since : 0;
    memcpy(s->id, id, 16);
    s->id[16] = '\0';
    events_clean_name(name, s->name);
    clock_gettime(CLOCK_MONOTONIC, &s->last_write);
    if (acc && acc->token) {
        snprintf(s->token, sizeof s->token, "%s", acc->token);
        s->check = acc->check;
        s->check_ctx = acc->ctx;
    }

    pthread_mutex_lock(&ev->lock);
    if ((rc = events_admit(ev, s, session, acc ? acc->client : NULL, err))) {
        pthread_mutex_unlock(&ev->lock);
        free(s);
        return rc;
    }
    /* the token was checked before the stream joined: a change of the
     * tokens in between would go unseen, so check it again first thing */
    s->revoked = s->hub->revoked - (s->token[0] ? 1 : 0);
    s->next = s->hub->listeners;
    s->hub->listeners = s;
    s->hub->presence++;
    s->seen_presence = s->hub->presence - 1; /* send presence first thing */
    pthread_cond_broadcast(&ev->cond);
    pthread_mutex_unlock(&ev->lock);
    *out = s;
    return 0;
}

/* MHD's content reader: the stream's next bytes, waiting as long as it
 * takes (events_stream_next returns 0 after each quiet poll). */
static ssize_t stream_read(void *cls, uint64_t pos, char *out, size_t max)
{
    ssize_t n;
    (void)pos;
    while ((n = events_stream_next(cls, out, max)) == 0)
        ;
    if (n == EVENTS_STREAM_END) /* (END_WITH_ERROR would log an "application error") */
        return MHD_CONTENT_READER_END_OF_STREAM;
    if (n < 0)
        return MHD_CONTENT_READER_END_WITH_ERROR;
    return n;
}

static void stream_free(void *cls)
{
    events_stream_close(cls);
}

http_resp events_stream(events *ev, http_req *req, const char *session, long long since,
                        const char *client_name, const events_access *acc)
{
    const union MHD_ConnectionInfo *ci;
    events_access who = {0};
    char client[HTTP_CLIENT_KEY_MAX];
    ev_stream *s;
    glint_err e;
    http_resp r;
    int fd = -1;

    ci = MHD_get_connection_info(req->conn, MHD_CONNECTION_INFO_CONNECTION_FD);
    if (ci)
        fd = ci->connect_fd;
    if (acc)
        who = *acc;
    http_client_key(req, client, sizeof client);
    who.client = client;
    if (events_stream_open(ev, session, since, client_name, fd, &who, &s, &e)) {
        if (e.code == GLINT_EBUSY) {
            r = http_problem(429, "too-many-streams", "%s", e.msg);
            http_header(&r, "Retry-After", "5");
            /* a client that opens streams without end gets no connection to keep */
            http_header(&r, MHD_HTTP_HEADER_CONNECTION, "close");
            return r;
        }
        log_line("events: %s", e.msg);
        return http_problem(500, NULL, "cannot open the event stream: %s", e.msg);
    }
    r = http_stream(200, "text/event-stream", stream_read, s, stream_free);
    if (!r.r) {
        events_stream_close(s);
        return http_problem(500, NULL, "cannot create the event stream");
    }
    http_header(&r, "X-Accel-Buffering", "no");
    return r;
}
