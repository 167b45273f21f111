/* store_listen.c: other processes' changes to the sessions' logs, heard
 * through PostgreSQL's LISTEN/NOTIFY (store.h: store_listen).
 *
 * One thread with a connection of its own: LISTEN on STORE_CHANNEL, then
 * poll the connection's socket (at most LISTEN_POLL_MS at a time, so a stop
 * is noticed), read what arrived and call fn for each notification.  A lost
 * connection is made again every second; once it is back, fn(ctx, NULL)
 * says that notifications may have been missed meanwhile. */
#include <libpq-fe.h>
#include <poll.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ids.h"
#include "log.h"
#include "store_int.h"

#define LISTEN_POLL_MS 250
#define LISTEN_RETRY_MS 1000

struct store_listener {
    pthread_t thread;
    pthread_mutex_t lock;
    int stop;
    char *conninfo;
    void (*fn)(void *ctx, const char *session, const char *what);
    char instance[GLINT_ID_LEN];     /* this process's announcements carry it */
    void *ctx;
};

static int listener_stopping(store_listener *l)
{
    int stop;
    pthread_mutex_lock(&l->lock);
    stop = l->stop;
    pthread_mutex_unlock(&l->lock);
    return stop;
}

/* A connection listening on the channel, or NULL (logged once per outage). */
static PGconn *listener_connect(store_listener *l, int *warned)
{
    PGconn *c = PQconnectdb(l->conninfo);
    PGresult *r = NULL;
    if (PQstatus(c) == CONNECTION_OK) {
        r = PQexec(c, "LISTEN " STORE_CHANNEL);
        if (PQresultStatus(r) == PGRES_COMMAND_OK) {
            PQclear(r);
            *warned = 0;
            return c;
        }
    }
    if (!*warned) {
        char msg[256];
        size_t n;
        snprintf(msg, sizeof msg, "%s",
                 r ? PQresultErrorMessage(r) : c ? PQerrorMessage(c) : "out of memory");
        n = strcspn(msg, "\n");
        msg[n] = '\0';
        log_line("store: listening for other replicas' changes failed (retrying every %d ms): "
                  "%s", LISTEN_RETRY_MS, msg);
        *warned = 1;
    }
    PQclear(r);
    PQfinish(c);
    return NULL;
}

/* A notification's payload: "<session>" (its log grew) or
 * "<what>:<session>:<instance>" (store_announce; our own are skipped). */
static void listener_heard(store_listener *l, const char *payload)
{
    char what[17], session[GLINT_ID_LEN], instance[GLINT_ID_LEN];
    const char *c1 = strchr(payload, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
    size_t wl;
    if (!c1) {
        if (glint_id_valid(payload))
            l->fn(l->ctx, payload, "log");
        return;
    }
    wl = (size_t)(c1 - payload);
    if (!c2 || wl == 0 || wl >= sizeof what || (size_t)(c2 - c1 - 1) != GLINT_ID_LEN - 1 ||
        strlen(c2 + 1) != GLINT_ID_LEN - 1)
        return;
    memcpy(what, payload, wl);
    what[wl] = '\0';
    memcpy(session, c1 + 1, GLINT_ID_LEN - 1);
    session[GLINT_ID_LEN - 1] = '\0';
    memcpy(instance, c2 + 1, GLINT_ID_LEN);
    if (glint_id_valid(session) && glint_id_valid(instance) && strcmp(instance, l->instance))
        l->fn(l->ctx, session, what);
}

static void *listener_main(void *arg)
{
    store_listener *l = arg;
    PGconn *c = NULL;
    int warned = 0, missed = 0;

    while (!listener_stopping(l)) {
        struct pollfd p;
        PGnotify *n;
        if (!c) {
            if (!(c = listener_connect(l, &warned))) {
                missed = 1;
                for (int t = 0; t < LISTEN_RETRY_MS / LISTEN_POLL_MS && !listener_stopping(l);
                     t++)
                    usleep(LISTEN_POLL_MS * 1000);
                continue;
            }
            if (missed) {
                l->fn(l->ctx, NULL, NULL);
                missed = 0;
            }
        }
        p.fd = PQsocket(c);
        p.events = POLLIN;
        p.revents = 0;
        if (p.fd < 0 || poll(&p, 1, LISTEN_POLL_MS) < 0)
            continue;
        if (p.revents && !PQconsumeInput(c)) {
            PQfinish(c); /* the server went away: connect again */
            c = NULL;
            missed = 1;
            continue;
        }
        while ((n = PQnotifies(c))) {
            listener_heard(l, n->extra);
            PQfreemem(n);
        }
        if (PQstatus(c) != CONNECTION_OK) {
            PQfinish(c);
            c = NULL;
            missed = 1;
        }
    }
    PQfinish(c);
    return NULL;
}

int store_announce(store *s, const char *session, const char *what, glint_err *err)
{
    char payload[96];
    db_stmt *st;
    int rc;
    if (db_kind_of(s->db) != DB_POSTGRES)
        return 0;
    if (!glint_id_valid(session) || !what || !*what || strlen(what) > 16 ||
        strspn(what, "abcdefghijklmnopqrstuvwxyz") != strlen(what))
        return glint_err_set(err, GLINT_EINVAL, "store_announce: bad session or kind");
    snprintf(payload, sizeof payload, "%s:%s:%s", what, session, s->instance);
    pthread_mutex_lock(&s->lock);
    if (!(st = store_prep(s, "SELECT pg_notify('" STORE_CHANNEL "', ?1)", err))) {
        pthread_mutex_unlock(&s->lock);
        return GLINT_EIO;
    }
    db_bind_text(st, 1, payload);
    rc = db_step(st, "announcing", err);
    db_finalize(st);
    pthread_mutex_unlock(&s->lock);
    return rc < 0 ? rc : 0;
}

int store_listen(store *s, void (*fn)(void *ctx, const char *session, const char *what),
                 void *ctx, glint_err *err)
{
    store_listener *l;
    if (db_kind_of(s->db) != DB_POSTGRES)
        return 0;
    if (s->listener)
        return glint_err_set(err, GLINT_EINVAL, "the store already has a listener");
    if (!(l = calloc(1, sizeof *l)) || !(l->conninfo = strdup(s->conninfo))) {
        free(l);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory starting the store's listener");
    }
    l->fn = fn;
    l->ctx = ctx;
    memcpy(l->instance, s->instance, GLINT_ID_LEN);
    pthread_mutex_init(&l->lock, NULL);
    if (pthread_create(&l->thread, NULL, listener_main, l)) {
        pthread_mutex_destroy(&l->lock);
        free(l->conninfo);
        free(l);
        return glint_err_set(err, GLINT_ENOMEM, "cannot start the store's listener thread");
    }
    s->listener = l;
    return 0;
}

void store_listen_stop(store *s)
{
    store_listener *l = s->listener;
    if (!l)
        return;
    pthread_mutex_lock(&l->lock);
    l->stop = 1;
    pthread_mutex_unlock(&l->lock);
    pthread_join(l->thread, NULL);
    pthread_mutex_destroy(&l->lock);
    free(l->conninfo);
    free(l);
    s->listener = NULL;
}
