/* admit.c: admission of expensive work (admit.h). */
#include "admit.h"

#include <pthread.h>
#include <stdlib.h>
#include <time.h>

struct admit {
    pthread_mutex_t lock;
    pthread_cond_t room;
    double wait_s; /* how long a request may wait for room */
    int stopping;  /* admit_stop */
    admit_stats st;
};

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
    pthread_mutex_init(&a->lock, NULL);
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&a->room, &ca);
    pthread_condattr_destroy(&ca);
    a->st.budget = budget;
    a->st.slots = slots;
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
    free(a);
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

/* Lock held. */
static int fits_now(const admit *a, size_t bytes)
{
    return a->st.running < a->st.slots && bytes <= a->st.budget - a->st.held;
}

/* Lock held. */
static void take(admit *a, size_t bytes)
{
    a->st.held += bytes;
    a->st.running++;
    a->st.admitted++;
    if (a->st.held > a->st.peak)
        a->st.peak = a->st.held;
}

/* The refusal once admit_stop was called. */
static int stopping(const char *what, glint_err *err)
{
    glint_err_set(err, GLINT_EBUSY, "the daemon is stopping: %s is not started", what);
    return glint_err_kind(err, "stopping");
}

int admit_enter(admit *a, size_t bytes, const char *what, glint_err *err)
{
    int rc = 0;
    if (!a)
        return 0;
    pthread_mutex_lock(&a->lock);
    if (bytes > a->st.budget) {
        rc = too_big(a, bytes, what, err);
        pthread_mutex_unlock(&a->lock);
        return rc;
    }
    if (!fits_now(a, bytes) && a->wait_s > 0.0 && !a->stopping) {
        struct timespec until = mono_after(a->wait_s);
        a->st.waited++;
        while (!fits_now(a, bytes) && !mono_passed(&until) && !a->stopping)
            pthread_cond_timedwait(&a->room, &a->lock, &until);
    }
    if (a->stopping) {
        rc = stopping(what, err);
    } else if (!fits_now(a, bytes)) {
        a->st.refused_busy++;
        glint_err_set(err, GLINT_EBUSY,
                      "%s needs up to %.0f MiB and this daemon's budget for expensive work is "
                      "taken now (%.0f of %.0f MiB, %d of %d at once): try again shortly",
                      what, (double)bytes / 1048576.0, (double)a->st.held / 1048576.0,
                      (double)a->st.budget / 1048576.0, a->st.running, a->st.slots);
        glint_err_kind(err, "busy");
        rc = GLINT_EBUSY;
    } else {
        take(a, bytes);
    }
    pthread_mutex_unlock(&a->lock);
    return rc;
}

int admit_wait(admit *a, size_t bytes, const char *what, int (*cancelled)(void *), void *cls,
               glint_err *err)
{
    int rc = 0, waited = 0;
    if (!a)
        return 0;
    pthread_mutex_lock(&a->lock);
    if (bytes > a->st.budget) {
        rc = too_big(a, bytes, what, err);
        pthread_mutex_unlock(&a->lock);
        return rc;
    }
    while (!fits_now(a, bytes) || a->stopping) {
        struct timespec ts = mono_after(0.1);
        if (a->stopping) {
            rc = stopping(what, err);
            break;
        }
        if (cancelled && cancelled(cls)) {
            glint_err_set(err, GLINT_EBUSY, "cancelled while waiting for room for %s", what);
            glint_err_kind(err, "cancelled");
            rc = GLINT_EBUSY;
            break;
        }
        waited = 1;
        pthread_cond_timedwait(&a->room, &a->lock, &ts);
    }
    if (!rc) {
        take(a, bytes);
        a->st.waited += waited;
    }
    pthread_mutex_unlock(&a->lock);
    return rc;
}

void admit_leave(admit *a, size_t bytes)
{
    if (!a)
        return;
    pthread_mutex_lock(&a->lock);
    a->st.held = bytes <= a->st.held ? a->st.held - bytes : 0;
    if (a->st.running > 0)
        a->st.running--;
    pthread_cond_broadcast(&a->room);
    pthread_mutex_unlock(&a->lock);
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
    fprintf(o, "# HELP glintd_work_max_seconds Largest estimate of one piece of work admitted, "
               "seconds of one core (--work-max-seconds; 0: none).\n"
               "# TYPE glintd_work_max_seconds gauge\nglintd_work_max_seconds %g\n",
            s.max_seconds);
    fprintf(o, "# HELP glintd_work_waited_total Expensive work that had to wait for room "
               "(then admitted or busy).\n# TYPE glintd_work_waited_total counter\n"
               "glintd_work_waited_total %lld\n",
            s.waited);
}
