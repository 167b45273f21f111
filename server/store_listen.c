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
    void (*fn)(void *ctx, const char *session);
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
                l->fn(l->ctx, NULL);
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
            if (glint_id_valid(n->extra))
                l->fn(l->ctx, n->extra);
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

int store_listen(store *s, void (*fn)(void *ctx, const char *session), void *ctx,
                 glint_err *err)
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
