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

#define EVENTS_BATCH 64        /* log rows read per wake-up */

typedef struct ev_hub {
    char session[33];
    unsigned long gen;         /* bumped by every publish / notify */
    unsigned long presence;    /* bumped when a listener joins or leaves */
    unsigned long revoked;     /* bumped when the session's tokens are revoked */
    ev_stream *listeners;
    struct ev_hub *next;
} ev_hub;

struct events {
    pthread_mutex_t lock;
    pthread_cond_t cond;       /* broadcast on every change */
    ev_hub *hubs;
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
    unsigned long revoked;     /* the hub's count when this stream opened */
    int started;
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
    pthread_mutex_init(&ev->lock, NULL);
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&ev->cond, &ca);
    pthread_condattr_destroy(&ca);
    *out = ev;
    return 0;
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
    if (!ev)
        return;
    /* glintd stops the HTTP server first, so no stream is left */
    for (h = ev->hubs; h; h = n) {
        n = h->next;
        free(h);
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

/* Drop a hub nobody listens to; ev->lock held. */
static void events_hub_release(events *ev, ev_hub *hub)
{
    ev_hub **p;
    if (hub->listeners)
        return;
    for (p = &ev->hubs; *p; p = &(*p)->next)
        if (*p == hub) {
            *p = hub->next;
            free(hub);
            return;
        }
}

void events_revoke(events *ev, const char *session)
{
    ev_hub *h;
    pthread_mutex_lock(&ev->lock);
    for (h = ev->hubs; h; h = h->next)
        if (strcmp(h->session, session) == 0) {
            h->revoked++;
            break;
        }
    pthread_cond_broadcast(&ev->cond);
    pthread_mutex_unlock(&ev->lock);
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
    if (!session)
        events_notify_all(ctx);
    else if (!strcmp(what, "revoke"))
        events_revoke(ctx, session);
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

/* Read the log after s->last into the buffer.  Returns the number of rows
 * read (EVENTS_BATCH means: maybe more), or -1 on a store error. */
static int stream_read_log(ev_stream *s, store *st)
{
    json_t *arr = NULL, *rec;
    glint_err e;
    size_t i;
    int n;

    if (store_events_since(st, s->hub->session, s->last, EVENTS_BATCH, &arr, NULL, &e)) {
        log_line("events of session %s: %s", s->hub->session, e.msg);
        return -1;
    }
    n = (int)json_array_size(arr);
    json_array_foreach(arr, i, rec) {
        long long seq = json_integer_value(json_object_get(rec, "seq"));
        const char *type = json_string_value(json_object_get(rec, "type"));
        if (stream_event(s, seq, type ? type : "event", rec)) {
            json_decref(arr);
            return -1;
        }
        s->last = seq;
    }
    json_decref(arr);
    return n;
}

ssize_t events_stream_next(ev_stream *s, char *out, size_t max)
{
    events *ev = s->ev;
    int waited = 0;

    for (;;) {
        unsigned long gen, presence;
        int stopping, gone;
        store *st;

        if (s->off < s->buf.len) {
            size_t n = s->buf.len - s->off;
            if (n > max)
                n = max;
            memcpy(out, s->buf.data + s->off, n);
            s->off += n;
            if (s->off == s->buf.len) {
                s->off = 0;
                glint_buf_clear(&s->buf);
            }
            clock_gettime(CLOCK_MONOTONIC, &s->last_write);
            return (ssize_t)n;
        }

        pthread_mutex_lock(&ev->lock);
        stopping = ev->stopping || s->hub->revoked != s->revoked;
        gen = s->hub->gen;
        presence = s->hub->presence;
        st = ev->st;
        if (!stopping && s->started && gen == s->seen_gen && presence == s->seen_presence) {
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
            stopping = ev->stopping || s->hub->revoked != s->revoked;
            gen = s->hub->gen;
            presence = s->hub->presence;
        }
        pthread_mutex_unlock(&ev->lock);
        if (stopping)
            return EVENTS_STREAM_END;

        if (!s->started) {
            s->started = 1;
            if (glint_buf_printf(&s->buf, "retry: 2000\n: glintd session\n\n"))
                return EVENTS_STREAM_ERROR;
            s->seen_gen = gen - 1; /* read the log at once (replay) */
        }
        if (gen != s->seen_gen) {
            /* Note the generation before reading: a publish after this
             * point bumps it again and triggers another read. */
            int n;
            n = stream_read_log(s, st);
            if (n < 0)
                return EVENTS_STREAM_ERROR;
            if (n < EVENTS_BATCH)
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

int events_stream_open(events *ev, const char *session, long long since, const char *name,
                       int fd, ev_stream **out)
{
    ev_stream *s;
    char id[33];
    int rc;

    *out = NULL;
    s = calloc(1, sizeof *s);
    if (!s)
        return GLINT_ENOMEM;
    if ((rc = glint_id_new(id, NULL))) {
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

    pthread_mutex_lock(&ev->lock);
    s->hub = events_hub(ev, session, 1);
    if (!s->hub) {
        pthread_mutex_unlock(&ev->lock);
        free(s);
        return GLINT_ENOMEM;
    }
    s->revoked = s->hub->revoked;
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
                        const char *client_name)
{
    const union MHD_ConnectionInfo *ci;
    ev_stream *s;
    http_resp r;
    int fd = -1;

    ci = MHD_get_connection_info(req->conn, MHD_CONNECTION_INFO_CONNECTION_FD);
    if (ci)
        fd = ci->connect_fd;
    if (events_stream_open(ev, session, since, client_name, fd, &s))
        return http_problem(500, NULL, "out of memory opening an event stream");
    r = http_stream(200, "text/event-stream", stream_read, s, stream_free);
    if (!r.r) {
        events_stream_close(s);
        return http_problem(500, NULL, "cannot create the event stream");
    }
    http_header(&r, "X-Accel-Buffering", "no");
    return r;
}
