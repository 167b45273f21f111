/* admit.c: admission of expensive work (admit.h). */
#include "admit.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* One client's running work (admit_ticket.client): at most `slots` rows
 * are in use, one per client with work running. */
typedef struct admit_client {
    char key[ADMIT_CLIENT_MAX];
    int n_by[ADMIT_CLASSES];
} admit_client;

struct admit {
    pthread_mutex_t lock;
    pthread_cond_t room;
    double wait_s; /* how long a request may wait for room */
    int stopping;  /* admit_stop */
    size_t held_bg; /* bytes held by background work */
    admit_client *clients; /* slots rows */
    admit_stats st;
};

/* Why a ticket cannot enter now (lock held). */
enum { ROOM_OK = 0, ROOM_FULL, ROOM_RESERVED, ROOM_CLIENT };

/* CLOCK_MONOTONIC now plus s seconds. */
static struct timespec mono_after(double s)
{
    struct timespec ts;
    long ns;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    ts.tv_sec += (time_t)s;
    ns = ts.tv_nsec + (long)((s - (double)(time_t)s) * 1e9);
    ts.tv_sec += ns / 1000000000L;
    ts.tv_nsec = ns % 1000000000L;
    return ts;
}

static int mono_passed(const struct timespec *t)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return now.tv_sec > t->tv_sec || (now.tv_sec == t->tv_sec && now.tv_nsec >= t->tv_nsec);
}

static int mono_before(const struct timespec *x, const struct timespec *y)
{
    return x->tv_sec < y->tv_sec || (x->tv_sec == y->tv_sec && x->tv_nsec < y->tv_nsec);
}

int admit_open(size_t budget, int slots, double wait_s, admit **out, glint_err *err)
{
    admit *a = calloc(1, sizeof *a);
    pthread_condattr_t ca;
    *out = NULL;
    if (!a)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (budget == 0 || slots < 1 || !(wait_s >= 0.0 && wait_s <= 3600.0)) {
        free(a);
        return glint_err_set(err, GLINT_EINVAL, "admission needs a budget and a slot");
    }
    if (!(a->clients = calloc((size_t)slots, sizeof *a->clients))) {
        free(a);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    pthread_mutex_init(&a->lock, NULL);
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&a->room, &ca);
    pthread_condattr_destroy(&ca);
    a->st.budget = budget;
    a->st.slots = slots;
    a->st.reserve = slots > 1 ? 1 : 0;
    a->st.per_client = slots / 2 > 1 ? slots / 2 : 1;
    a->wait_s = wait_s;
    *out = a;
    return 0;
}

void admit_close(admit *a)
{
    if (!a)
        return;
    pthread_cond_destroy(&a->room);
    pthread_mutex_destroy(&a->lock);
    free(a->clients);
    free(a);
}

void admit_limit_classes(admit *a, int reserve, int per_client)
{
    if (!a)
        return;
    pthread_mutex_lock(&a->lock);
    a->st.reserve = reserve < 0 ? 0 : reserve >= a->st.slots ? a->st.slots - 1 : reserve;
    a->st.per_client = per_client < 1 ? 1 : per_client > a->st.slots ? a->st.slots : per_client;
    pthread_cond_broadcast(&a->room);
    pthread_mutex_unlock(&a->lock);
}

/* The row of a client's running work, or NULL (lock held).  make: take a
 * free row when it has none. */
static admit_client *client_row(admit *a, const char *key, int make)
{
    admit_client *free_row = NULL;
    for (int i = 0; i < a->st.slots; i++) {
        admit_client *c = &a->clients[i];
        int used = c->n_by[0] + c->n_by[1];
        if (used && strcmp(c->key, key) == 0)
            return c;
        if (!used && !free_row)
            free_row = c;
    }
    if (make && free_row) {
        snprintf(free_row->key, sizeof free_row->key, "%s", key);
        return free_row;
    }
    return NULL;
}

static int client_running(admit *a, const char *key)
{
    admit_client *c = key[0] ? client_row(a, key, 0) : NULL;
    return c ? c->n_by[0] + c->n_by[1] : 0;
}

static int too_big(admit *a, size_t bytes, const char *what, glint_err *err)
{
    a->st.refused_size++;
    glint_err_set(err, GLINT_ETOOBIG,
                  "%s needs up to %.0f MiB, beyond the %.0f MiB this daemon gives expensive work "
                  "(glintd --work-mb): ask for less (a smaller size, fewer views, a lower res)",
                  what, (double)bytes / 1048576.0, (double)a->st.budget / 1048576.0);
    glint_err_kind(err, "over-budget");
    return GLINT_ETOOBIG;
}

/* Why t cannot enter now, or ROOM_OK (lock held).  Background work leaves
 * the reserved slots and its share of the memory to interactive work, and
 * yields to interactive work that waits. */
static int room_for(admit *a, const admit_ticket *t)
{
    const admit_stats *s = &a->st;
    if (s->running >= s->slots || t->bytes > s->budget - s->held)
        return ROOM_FULL;
    if (t->client[0] && client_running(a, t->client) >= s->per_client)
        return ROOM_CLIENT;
    if (t->cls == ADMIT_BACKGROUND && s->waiting_by[ADMIT_INTERACTIVE] > 0)
        return ROOM_RESERVED;
    if (t->cls == ADMIT_BACKGROUND && s->reserve > 0) {
        /* its share of the memory too, but the first piece of background
         * work may take more (so one larger than the share is not starved
         * while interactive work comes and goes) */
        size_t share = s->budget / (size_t)s->slots * (size_t)(s->slots - s->reserve);
        if (s->running_by[ADMIT_BACKGROUND] >= s->slots - s->reserve ||
            (s->running_by[ADMIT_BACKGROUND] > 0 && a->held_bg + t->bytes > share))
            return ROOM_RESERVED;
    }
    return ROOM_OK;
}

/* Lock held. */
static void take(admit *a, admit_ticket *t)
{
    a->st.held += t->bytes;
    a->st.running++;
    a->st.running_by[t->cls]++;
    a->st.admitted++;
    if (t->cls == ADMIT_BACKGROUND)
        a->held_bg += t->bytes;
    if (a->st.held > a->st.peak)
        a->st.peak = a->st.held;
    if (t->client[0]) {
        admit_client *c = client_row(a, t->client, 1);
        if (c) /* always: rows in use <= running <= slots */
            c->n_by[t->cls]++;
    }
    t->held = 1;
}

/* The refusal once admit_stop was called. */
static int stopping(const char *what, glint_err *err)
{
    glint_err_set(err, GLINT_EBUSY, "the daemon is stopping: %s is not started", what);
    return glint_err_kind(err, "stopping");
}

/* The busy refusal, in words that say what happens and what to do
 * (lock held).  The problem type stays "busy" for programs. */
static int busy(admit *a, const admit_ticket *t, int why, const char *what, glint_err *err)
{
    const admit_stats *s = &a->st;
    a->st.refused_busy++;
    a->st.refused_by[t->cls]++;
    if (why == ROOM_CLIENT) {
        const admit_client *c = client_row(a, t->client, 0);
        int bg = c ? c->n_by[ADMIT_BACKGROUND] : 0, n = c ? c->n_by[0] + c->n_by[1] : 0;
        a->st.refused_client++;
        glint_err_set(err, GLINT_EBUSY,
                      "the server is %s (%d at once for one client, glintd --work-per-client); "
                      "%s will follow: try again in a few seconds",
                      bg == n ? "rendering your reference images and exports"
                              : "still working on your other renders and fits",
                      s->per_client, what);
    } else if (why == ROOM_RESERVED) {
        glint_err_set(err, GLINT_EBUSY,
                      "the server keeps room for painting, fitting and previews, which people "
                      "are waiting on (%d of %d pieces of work at once, %d kept for them): %s "
                      "will follow: try again in a few seconds",
                      s->running, s->slots, s->reserve, what);
    } else {
        glint_err_set(err, GLINT_EBUSY,
                      "the server is busy with other renders and fits (%d of %d at once, %.0f of "
                      "%.0f MiB in use): %s will follow: try again in a few seconds",
                      s->running, s->slots, (double)s->held / 1048576.0,
                      (double)s->budget / 1048576.0, what);
    }
    return glint_err_kind(err, "busy");
}

/* The waiter of class cls stopped waiting (lock held): background waiters
 * may go now that no interactive one waits. */
static void unwait(admit *a, admit_class cls)
{
    if (--a->st.waiting_by[cls] == 0 && cls == ADMIT_INTERACTIVE)
        pthread_cond_broadcast(&a->room);
}

/* The wait of admit_take (lock held): until room is made, the client
 * goes, the daemon stops or (unless forever) wait_s passed. */
static int wait_room(admit *a, admit_ticket *t, const char *what, int forever, glint_err *err)
{
    struct timespec until = mono_after(a->wait_s);
    int why, rc = 0, waited = 0;
    a->st.waiting_by[t->cls]++;
    for (;;) {
        struct timespec tick = mono_after(0.1);
        if (a->stopping) {
            rc = stopping(what, err);
            break;
        }
        if (!(why = room_for(a, t))) {
            take(a, t);
            break;
        }
        if (t->gone && t->gone(t->gone_cls)) {
            a->st.gone_waiting++;
            glint_err_set(err, GLINT_EBUSY, "cancelled while waiting for room for %s", what);
            rc = glint_err_kind(err, "cancelled");
            break;
        }
        if (!forever && (a->wait_s <= 0.0 || mono_passed(&until))) {
            rc = busy(a, t, why, what, err);
            break;
        }
        if (!waited) /* counted as it starts waiting (the tests watch for it) */
            a->st.waited++;
        waited = 1;
        pthread_cond_timedwait(&a->room, &a->lock,
                               !forever && mono_before(&until, &tick) ? &until : &tick);
    }
    unwait(a, t->cls);
    return rc;
}

int admit_take(admit *a, admit_ticket *t, const char *what, int forever, glint_err *err)
{
    int rc;
    t->held = 0;
    if (!a)
        return 0;
    if ((unsigned)t->cls >= ADMIT_CLASSES)
        t->cls = ADMIT_BACKGROUND;
    pthread_mutex_lock(&a->lock);
    if (t->bytes > a->st.budget)
        rc = too_big(a, t->bytes, what, err);
    else
        rc = wait_room(a, t, what, forever, err);
    pthread_mutex_unlock(&a->lock);
    return rc;
}

void admit_give(admit *a, admit_ticket *t)
{
    if (!a || !t->held)
        return;
    pthread_mutex_lock(&a->lock);
    a->st.held = t->bytes <= a->st.held ? a->st.held - t->bytes : 0;
    if (a->st.running > 0)
        a->st.running--;
    if (a->st.running_by[t->cls] > 0)
        a->st.running_by[t->cls]--;
    if (t->cls == ADMIT_BACKGROUND)
        a->held_bg = t->bytes <= a->held_bg ? a->held_bg - t->bytes : 0;
    if (t->client[0]) {
        admit_client *c = client_row(a, t->client, 0);
        if (c && c->n_by[t->cls] > 0)
            c->n_by[t->cls]--;
    }
    t->held = 0;
    pthread_cond_broadcast(&a->room);
    pthread_mutex_unlock(&a->lock);
}

int admit_enter(admit *a, size_t bytes, const char *what, glint_err *err)
{
    admit_ticket t = {.bytes = bytes, .cls = ADMIT_INTERACTIVE};
    return admit_take(a, &t, what, 0, err);
}

int admit_wait(admit *a, size_t bytes, const char *what, int (*cancelled)(void *), void *cls,
               glint_err *err)
{
    admit_ticket t = {.bytes = bytes, .cls = ADMIT_INTERACTIVE, .gone = cancelled,
                      .gone_cls = cls};
    return admit_take(a, &t, what, 1, err);
}

void admit_leave(admit *a, size_t bytes)
{
    admit_ticket t = {.bytes = bytes, .cls = ADMIT_INTERACTIVE, .held = 1};
    admit_give(a, &t);
}

void admit_limit_seconds(admit *a, double seconds)
{
    if (!a)
        return;
    pthread_mutex_lock(&a->lock);
    a->st.max_seconds = seconds > 0.0 ? seconds : 0.0;
    pthread_mutex_unlock(&a->lock);
}

int admit_cost(admit *a, double seconds, const char *what, glint_err *err)
{
    int rc = 0;
    if (!a)
        return 0;
    pthread_mutex_lock(&a->lock);
    if (a->st.max_seconds > 0.0 && !(seconds <= a->st.max_seconds)) {
        a->st.refused_cost++;
        glint_err_set(err, GLINT_ETOOBIG,
                      "%s is estimated at %.0f s of work (one core), beyond the %.0f s this "
                      "daemon gives one piece of work (glintd --work-max-seconds): ask for less "
                      "(a smaller size, fewer lights or views, a lower res)",
                      what, seconds, a->st.max_seconds);
        rc = glint_err_kind(err, "too-expensive");
    }
    pthread_mutex_unlock(&a->lock);
    return rc;
}

void admit_cancelled(admit *a)
{
    if (!a)
        return;
    pthread_mutex_lock(&a->lock);
    a->st.cancelled++;
    pthread_mutex_unlock(&a->lock);
}

void admit_stop(admit *a)
{
    if (!a)
        return;
    pthread_mutex_lock(&a->lock);
    a->stopping = 1;
    pthread_cond_broadcast(&a->room);
    pthread_mutex_unlock(&a->lock);
}

void admit_get_stats(admit *a, admit_stats *out)
{
    pthread_mutex_lock(&a->lock);
    *out = a->st;
    pthread_mutex_unlock(&a->lock);
}

void admit_metrics(admit *a, FILE *o)
{
    admit_stats s;
    if (!a)
        return;
    admit_get_stats(a, &s);
    fprintf(o, "# HELP glintd_work_budget_bytes Memory budget of expensive work (--work-mb).\n"
               "# TYPE glintd_work_budget_bytes gauge\nglintd_work_budget_bytes %zu\n",
            s.budget);
    fprintf(o, "# HELP glintd_work_held_bytes Memory bounds of the work in flight.\n"
               "# TYPE glintd_work_held_bytes gauge\nglintd_work_held_bytes %zu\n",
            s.held);
    fprintf(o, "# HELP glintd_work_peak_bytes Highest glintd_work_held_bytes since start.\n"
               "# TYPE glintd_work_peak_bytes gauge\nglintd_work_peak_bytes %zu\n",
            s.peak);
    fprintf(o, "# HELP glintd_work_running Expensive work in flight (of --work-slots).\n"
               "# TYPE glintd_work_running gauge\nglintd_work_running %d\n",
            s.running);
    fprintf(o, "# HELP glintd_work_total Expensive work by outcome.\n"
               "# TYPE glintd_work_total counter\n"
               "glintd_work_total{outcome=\"admitted\"} %lld\n"
               "glintd_work_total{outcome=\"busy\"} %lld\n"
               "glintd_work_total{outcome=\"over_budget\"} %lld\n"
               "glintd_work_total{outcome=\"too_expensive\"} %lld\n"
               "glintd_work_total{outcome=\"cancelled\"} %lld\n",
            s.admitted, s.refused_busy, s.refused_size, s.refused_cost, s.cancelled);
    fprintf(o, "# HELP glintd_work_running_by_class Expensive work in flight by class "
               "(interactive: what people wait on; background: reference renders, exports).\n"
               "# TYPE glintd_work_running_by_class gauge\n"
               "glintd_work_running_by_class{class=\"interactive\"} %d\n"
               "glintd_work_running_by_class{class=\"background\"} %d\n",
            s.running_by[ADMIT_INTERACTIVE], s.running_by[ADMIT_BACKGROUND]);
    fprintf(o, "# HELP glintd_work_waiting_by_class Requests and jobs waiting for room now.\n"
               "# TYPE glintd_work_waiting_by_class gauge\n"
               "glintd_work_waiting_by_class{class=\"interactive\"} %d\n"
               "glintd_work_waiting_by_class{class=\"background\"} %d\n",
            s.waiting_by[ADMIT_INTERACTIVE], s.waiting_by[ADMIT_BACKGROUND]);
    fprintf(o, "# HELP glintd_work_refused_total Busy refusals (503) by class.\n"
               "# TYPE glintd_work_refused_total counter\n"
               "glintd_work_refused_total{class=\"interactive\"} %lld\n"
               "glintd_work_refused_total{class=\"background\"} %lld\n",
            s.refused_by[ADMIT_INTERACTIVE], s.refused_by[ADMIT_BACKGROUND]);
    fprintf(o, "# HELP glintd_work_refused_per_client_total Busy refusals because the client "
               "already held its share (--work-per-client).\n"
               "# TYPE glintd_work_refused_per_client_total counter\n"
               "glintd_work_refused_per_client_total %lld\n",
            s.refused_client);
    fprintf(o, "# HELP glintd_work_gone_waiting_total Requests whose client went away while "
               "they waited for room (they never took a slot).\n"
               "# TYPE glintd_work_gone_waiting_total counter\n"
               "glintd_work_gone_waiting_total %lld\n",
            s.gone_waiting);
    fprintf(o, "# HELP glintd_work_max_seconds Largest estimate of one piece of work admitted, "
               "seconds of one core (--work-max-seconds; 0: none).\n"
               "# TYPE glintd_work_max_seconds gauge\nglintd_work_max_seconds %g\n",
            s.max_seconds);
    fprintf(o, "# HELP glintd_work_waited_total Expensive work that had to wait for room "
               "(then admitted or busy).\n# TYPE glintd_work_waited_total counter\n"
               "glintd_work_waited_total %lld\n",
            s.waited);
}
