/* Tests of glintd's background jobs (server/jobs.h): results and failures,
 * the progress log and waiting for it, scheduling (fits before queued
 * holdouts, one holdout at a time, owners in turn), the queue limits (all
 * owners, one owner, background apart), superseding, cancelling, stopping
 * and closing, the idle callback, and that every job's argument is freed
 * exactly once.  Jobs run on the module's real worker threads and block on
 * gates the test opens. */
#include <pthread.h>
#include <stdatomic.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "clock.h"
#include "jobs.h"

#define WAIT_S 30.0 /* longest wait for something that must happen (only catches a hang) */
/* A wait for events that only a wake-up can end (longer than the test's
 * timeout): were the wake-up missing, the test would hang there. */
#define FOREVER_S 3600.0

/* ---- gates and a journal of what ran ---------------------------------------- */

typedef struct gate {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int open;
} gate;

static void gate_init(gate *g)
{
    pthread_mutex_init(&g->mu, NULL);
    pthread_cond_init(&g->cv, NULL);
    g->open = 0;
}

static void gate_open(gate *g)
{
    pthread_mutex_lock(&g->mu);
    g->open = 1;
    pthread_cond_broadcast(&g->cv);
    pthread_mutex_unlock(&g->mu);
}

static void deadline_in(struct timespec *t, double s)
{
    clock_gettime(CLOCK_REALTIME, t);
    t->tv_sec += (time_t)s;
    t->tv_nsec += (long)((s - (double)(time_t)s) * 1e9);
    if (t->tv_nsec >= 1000000000L) {
        t->tv_sec++;
        t->tv_nsec -= 1000000000L;
    }
}

/* 0 once open, -1 after WAIT_S. */
static int gate_wait(gate *g)
{
    struct timespec dl;
    int rc = 0;
    deadline_in(&dl, WAIT_S);
    pthread_mutex_lock(&g->mu);
    while (!g->open && rc == 0)
        rc = pthread_cond_timedwait(&g->cv, &g->mu, &dl);
    rc = g->open ? 0 : -1;
    pthread_mutex_unlock(&g->mu);
    return rc;
}

static void gate_destroy(gate *g)
{
    pthread_cond_destroy(&g->cv);
    pthread_mutex_destroy(&g->mu);
}

typedef struct journal {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    char order[512];           /* labels of the jobs, in the order they started */
    int started;
    int holdouts, max_holdouts; /* holdout jobs running now, at most */
} journal;

static journal J;

static void journal_reset(void)
{
    memset(&J, 0, sizeof J);
    pthread_mutex_init(&J.mu, NULL);
    pthread_cond_init(&J.cv, NULL);
}

/* 0 once n jobs have started, -1 after WAIT_S. */
static int journal_wait_started(int n)
{
    struct timespec dl;
    int rc = 0;
    deadline_in(&dl, WAIT_S);
    pthread_mutex_lock(&J.mu);
    while (J.started < n && rc == 0)
        rc = pthread_cond_timedwait(&J.cv, &J.mu, &dl);
    rc = J.started >= n ? 0 : -1;
    pthread_mutex_unlock(&J.mu);
    return rc;
}

/* ---- a job --------------------------------------------------------------------- */

typedef struct targ {
    char label;            /* written to the journal when it starts */
    int holdout;           /* counts in J.holdouts while it runs */
    gate *gate;            /* waits on it before finishing (NULL: does not wait) */
    int fail;              /* returns this code (0: success) */
    const char *msg;       /* with this message (NULL: none set) */
    json_t *result;        /* hands this back (stolen) */
    void (*body)(job *j, struct targ *a); /* runs first, if set */
    atomic_int ran, freed;
    /* close_test: what the job saw */
    jobs *js;
    char queued_ids[2][33];
    int cancelled_at_start, saw_cancel, finished;
    char queued_state[2][16], queued_error[2][GLINT_ERR_MSG_MAX];
    int submit_rc;
    struct targ *late;     /* submitted while stopping */
    gate *ready;           /* opened once cancelled_at_start is known */
} targ;

static void targ_free(void *p)
{
    atomic_fetch_add(&((targ *)p)->freed, 1);
}

static int run(job *j, void *arg, json_t **result, glint_err *err)
{
    targ *a = arg;
    int rc = 0;
    atomic_fetch_add(&a->ran, 1);
    pthread_mutex_lock(&J.mu);
    if (strlen(J.order) + 1 < sizeof J.order)
        J.order[strlen(J.order)] = a->label;
    J.started++;
    if (a->holdout && ++J.holdouts > J.max_holdouts)
        J.max_holdouts = J.holdouts;
    pthread_cond_broadcast(&J.cv);
    pthread_mutex_unlock(&J.mu);
    if (a->body)
        a->body(j, a);
    if (a->gate && gate_wait(a->gate))
        rc = glint_err_set(err, GLINT_EINTERNAL, "the test never opened the gate");
    pthread_mutex_lock(&J.mu);
    J.holdouts -= a->holdout;
    pthread_mutex_unlock(&J.mu);
    if (rc)
        return rc;
    *result = a->result;
    a->result = NULL;
    if (a->fail)
        return a->msg ? glint_err_set(err, a->fail, "%s", a->msg) : a->fail;
    return 0;
}

#define OWNER "0123456789abcdef0123456789abcdef"

static int submit(jobs *js, const char *kind, targ *a, char id[33])
{
    return jobs_submit(js, kind, OWNER, NULL, run, a, targ_free, id, NULL);
}

/* A job of `owner` for `target` (NULL: none). */
static int submit_as(jobs *js, const char *owner, const char *target, targ *a, char id[33],
                     glint_err *e)
{
    return jobs_submit(js, "fit", owner, target, run, a, targ_free, id, e);
}

/* Wait for the job's last event (OUT: *log, every event; NULL on timeout). */
static int wait_final(jobs *js, const char *id, json_t **log)
{
    double end = glint_now() + WAIT_S;
    long long since = 0;
    int final = 0;
    *log = NULL;
    while (!final && glint_now() < end) {
        json_t *ev;
        int rc = jobs_events(js, id, since, 1.0, &ev, &final, NULL);
        if (rc)
            return rc;
        if (json_array_size(ev))
            since = json_integer_value(
                json_object_get(json_array_get(ev, json_array_size(ev) - 1), "seq"));
        json_decref(ev);
    }
    if (!final)
        return -1;
    return jobs_events(js, id, 0, 0, log, &final, NULL);
}

static const char *ev_type(json_t *log, size_t i)
{
    return json_string_value(json_object_get(json_array_get(log, i), "type"));
}

static json_t *ev_job(json_t *log, size_t i)
{
    return json_object_get(json_array_get(log, i), "job");
}

static const char *str(json_t *o, const char *key)
{
    const char *s = json_string_value(json_object_get(o, key));
    return s ? s : "(none)";
}

/* ---- results -------------------------------------------------------------------- */

TEST(job_runs_and_reports_done_with_its_result)
{
    jobs *js;
    targ a = {.label = 'a'}, b = {.label = 'b'};
    char id[33], id2[33], owner[33];
    json_t *log, *o;
    jobs_stats st;
    journal_reset();
    a.result = json_pack("{s:s, s:i}", "material_id", "m1", "views", 12);
    b.result = json_integer(5); /* not an object: nothing merged */
    ASSERT_OK(jobs_open(2, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &a, id));
    ASSERT_EQ(strlen(id), 32);
    ASSERT_OK(wait_final(js, id, &log));
    ASSERT_EQ(json_array_size(log), 3);
    ASSERT(strcmp(ev_type(log, 0), "progress") == 0);
    ASSERT(strcmp(str(ev_job(log, 0), "state"), "queued") == 0);
    ASSERT(strcmp(ev_type(log, 1), "progress") == 0);
    ASSERT(strcmp(str(ev_job(log, 1), "state"), "running") == 0);
    ASSERT(strcmp(str(ev_job(log, 1), "stage"), "started") == 0);
    ASSERT(strcmp(ev_type(log, 2), "done") == 0);
    o = ev_job(log, 2);
    ASSERT(strcmp(str(o, "state"), "done") == 0);
    ASSERT(strcmp(str(o, "material_id"), "m1") == 0);
    ASSERT_EQ(json_integer_value(json_object_get(o, "views")), 12);
    ASSERT(json_real_value(json_object_get(o, "progress")) == 1.0);
    ASSERT(json_object_get(o, "error") == NULL);
    json_decref(log);
    ASSERT_OK(jobs_get(js, id, &o, owner, NULL));
    ASSERT(strcmp(str(o, "id"), id) == 0);
    ASSERT(strcmp(str(o, "kind"), "fit") == 0);
    ASSERT(strcmp(str(o, "state"), "done") == 0);
    ASSERT(strcmp(str(o, "material_id"), "m1") == 0);
    ASSERT(json_is_string(json_object_get(o, "started")));
    ASSERT(json_is_string(json_object_get(o, "finished")));
    ASSERT(json_real_value(json_object_get(o, "seconds")) >= 0);
    ASSERT(strcmp(owner, "0123456789abcdef0123456789abcdef") == 0);
    json_decref(o);
    ASSERT_EQ(atomic_load(&a.ran), 1);
    ASSERT_EQ(atomic_load(&a.freed), 1);
    /* a result that is no object is dropped */
    ASSERT_OK(submit(js, NULL, &b, id2));
    ASSERT_OK(wait_final(js, id2, &log));
    o = ev_job(log, json_array_size(log) - 1);
    ASSERT(strcmp(str(o, "state"), "done") == 0);
    ASSERT(strcmp(str(o, "kind"), "fit") == 0); /* the default kind */
    ASSERT_EQ(json_object_size(o), 9); /* id kind state progress stage created started seconds finished */
    json_decref(log);
    ASSERT_EQ(atomic_load(&b.freed), 1);
    jobs_stats_get(js, &st);
    ASSERT_EQ(st.done, 2);
    ASSERT_EQ(st.failed, 0);
    ASSERT_EQ(st.queued, 0);
    ASSERT_EQ(st.running, 0);
    /* unknown jobs */
    ASSERT_EQ(jobs_get(js, "ffffffffffffffffffffffffffffffff", &o, NULL, NULL), GLINT_ENOTFOUND);
    ASSERT(o == NULL);
    {
        int final;
        ASSERT_EQ(jobs_events(js, "nope", 0, 0.1, &log, &final, NULL), GLINT_ENOTFOUND);
    }
    jobs_close(js);
    ASSERT_EQ(atomic_load(&a.freed), 1);
    ASSERT_EQ(atomic_load(&b.freed), 1);
    jobs_close(NULL);
}

TEST(failing_job_reports_its_message)
{
    jobs *js;
    targ a = {.label = 'a', .fail = GLINT_EINVAL, .msg = "view 3 is painted black"};
    targ b = {.label = 'b', .fail = GLINT_ENUMERIC};
    char id[33], id2[33];
    json_t *log, *o;
    jobs_stats st;
    journal_reset();
    a.result = json_pack("{s:s}", "material_id", "never");
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &a, id));
    ASSERT_OK(submit(js, "fit", &b, id2));
    ASSERT_OK(wait_final(js, id, &log));
    ASSERT(strcmp(ev_type(log, json_array_size(log) - 1), "failed") == 0);
    o = ev_job(log, json_array_size(log) - 1);
    ASSERT(strcmp(str(o, "state"), "failed") == 0);
    ASSERT(strcmp(str(o, "error"), "view 3 is painted black") == 0);
    ASSERT(json_object_get(o, "material_id") == NULL);
    json_decref(log);
    ASSERT_OK(jobs_get(js, id, &o, NULL, NULL));
    ASSERT(strcmp(str(o, "error"), "view 3 is painted black") == 0);
    json_decref(o);
    /* no message: the code's name */
    ASSERT_OK(wait_final(js, id2, &log));
    o = ev_job(log, json_array_size(log) - 1);
    ASSERT(strcmp(str(o, "state"), "failed") == 0);
    ASSERT(strcmp(str(o, "error"), glint_strerror(GLINT_ENUMERIC)) == 0);
    json_decref(log);
    jobs_stats_get(js, &st);
    ASSERT_EQ(st.failed, 2);
    ASSERT_EQ(st.done, 0);
    ASSERT_EQ(atomic_load(&a.freed), 1);
    ASSERT_EQ(atomic_load(&b.freed), 1);
    jobs_close(js);
    ASSERT_EQ(atomic_load(&a.freed), 1);
    ASSERT_EQ(atomic_load(&b.freed), 1);
}

/* ---- progress ------------------------------------------------------------------- */

static void progress_body(job *j, targ *a)
{
    for (int k = 0; k <= 20; k++)          /* load: 0.00 .. 0.20 */
        job_progress(j, "load", k / 100.0);
    job_progress(j, "solve", 0.21);        /* a new stage, 0.01 further */
    for (int k = 21; k <= 60; k++)
        job_progress(j, "solve", k / 100.0);
    job_progress(j, "solve", 0.3);         /* progress never goes back */
    job_progress(j, "write", 0.6);         /* a new stage at the same progress */
    job_progress(j, "write", 0.62);
    job_progress(j, "write", -1.0);        /* clamped */
    job_progress(j, "write", 7.0);         /* clamped to 1 */
    (void)a;
}

TEST(progress_is_logged_by_stage_and_in_steps)
{
    jobs *js;
    targ a = {.label = 'p', .body = progress_body};
    char id[33];
    json_t *log;
    size_t n, load = 0;
    double prev = -1;
    const char *prev_stage = "";
    journal_reset();
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &a, id));
    ASSERT_OK(wait_final(js, id, &log));
    n = json_array_size(log);
    ASSERT(n > 4);
    for (size_t i = 0; i < n; i++) {
        json_t *o = ev_job(log, i);
        const char *stage = str(o, "stage");
        double p = json_real_value(json_object_get(o, "progress"));
        ASSERT_EQ(json_integer_value(json_object_get(json_array_get(log, i), "seq")),
                  (long long)i + 1);
        ASSERT(strcmp(ev_type(log, i), i + 1 < n ? "progress" : "done") == 0);
        ASSERT_MSG(p >= prev, "progress went back at event %zu: %g after %g", i, p, prev);
        if (i >= 2 && i + 1 < n && strcmp(stage, prev_stage) == 0) {
            /* within a stage: steps of at least 5%; where the job moves in
             * steps of 1% (load, solve), no 5% step is left out */
            ASSERT_MSG(p - prev >= 0.05 - 1e-9, "event %zu: %g after %g", i, p, prev);
            if (strcmp(stage, "write") != 0)
                ASSERT_MSG(p - prev <= 0.06 + 1e-9, "event %zu: %g after %g", i, p, prev);
        }
        load += strcmp(stage, "load") == 0;
        prev = p;
        prev_stage = stage;
    }
    /* queued, started, then every stage from its first call */
    ASSERT(strcmp(str(ev_job(log, 2), "stage"), "load") == 0);
    ASSERT(json_real_value(json_object_get(ev_job(log, 2), "progress")) == 0.0);
    ASSERT(load >= 4 && load <= 5);
    {
        size_t solve = 0, write = 0;
        for (size_t i = 0; i < n; i++) {
            const char *stage = str(ev_job(log, i), "stage");
            if (!solve && strcmp(stage, "solve") == 0) {
                solve = i;
                ASSERT_NEAR(json_real_value(json_object_get(ev_job(log, i), "progress")), 0.21,
                            1e-12);
            }
            if (!write && strcmp(stage, "write") == 0) {
                write = i;
                ASSERT_NEAR(json_real_value(json_object_get(ev_job(log, i), "progress")), 0.60,
                            1e-12);
            }
        }
        ASSERT(solve > 0 && write > solve);
        /* "write" logged 0.6 (new stage) and 1.0 (clamped, +0.38), not 0.62 */
        ASSERT_EQ(n - write, 3);
        ASSERT(json_real_value(json_object_get(ev_job(log, n - 2), "progress")) == 1.0);
    }
    json_decref(log);
    jobs_close(js);
    ASSERT_EQ(atomic_load(&a.freed), 1);
}

static gate G1, G2;

static void two_gates_body(job *j, targ *a)
{
    job_progress(j, "first", 0.1);
    if (gate_wait(&G1) == 0)
        job_progress(j, "second", 0.5);
    (void)a;
}

static long long last_seq(json_t *ev)
{
    return json_integer_value(json_object_get(json_array_get(ev, json_array_size(ev) - 1), "seq"));
}

TEST(events_wait_and_return_only_new_ones)
{
    jobs *js;
    targ a = {.label = 'w', .body = two_gates_body, .gate = &G2};
    char id[33];
    json_t *ev;
    int final = -1;
    long long since;
    double t0;
    journal_reset();
    gate_init(&G1);
    gate_init(&G2);
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &a, id));
    /* from 0: at once, whatever is there */
    ASSERT_OK(jobs_events(js, id, 0, 5.0, &ev, &final, NULL));
    ASSERT(json_array_size(ev) >= 1);
    ASSERT_EQ(final, 0);
    json_decref(ev);
    /* wait until the job parks at G1 with stage "first" logged */
    since = 0;
    for (double end = glint_now() + WAIT_S; glint_now() < end;) {
        ASSERT_OK(jobs_events(js, id, since, 1.0, &ev, &final, NULL));
        if (json_array_size(ev)) {
            since = last_seq(ev);
            if (strcmp(str(ev_job(ev, json_array_size(ev) - 1), "stage"), "first") == 0) {
                json_decref(ev);
                break;
            }
        }
        json_decref(ev);
    }
    ASSERT_EQ(since, 3); /* queued, started, first */
    /* nothing new: waits the whole timeout (a lower bound: a busy machine
     * only makes it longer), answers an empty array */
    t0 = glint_now();
    ASSERT_OK(jobs_events(js, id, since, 0.3, &ev, &final, NULL));
    ASSERT_LE(0.25, glint_now() - t0);
    ASSERT_EQ(json_array_size(ev), 0);
    ASSERT_EQ(final, 0);
    json_decref(ev);
    /* something new while waiting: woken (nothing else ends this wait),
     * only what is new */
    gate_open(&G1);
    ASSERT_OK(jobs_events(js, id, since, FOREVER_S, &ev, &final, NULL));
    ASSERT_EQ(json_array_size(ev), 1);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(ev, 0), "seq")), since + 1);
    ASSERT(strcmp(str(ev_job(ev, 0), "stage"), "second") == 0);
    ASSERT_EQ(final, 0);
    since = last_seq(ev);
    json_decref(ev);
    /* done: final, and after the last event it answers at once */
    gate_open(&G2);
    ASSERT_OK(jobs_events(js, id, since, WAIT_S, &ev, &final, NULL));
    if (!final) { /* (the done event may come in a second answer) */
        since = json_array_size(ev) ? last_seq(ev) : since;
        json_decref(ev);
        ASSERT_OK(jobs_events(js, id, since, WAIT_S, &ev, &final, NULL));
    }
    ASSERT_EQ(final, 1);
    ASSERT(strcmp(ev_type(ev, json_array_size(ev) - 1), "done") == 0);
    since = last_seq(ev);
    json_decref(ev);
    /* (a wait here would last FOREVER_S: the test's timeout reports it) */
    ASSERT_OK(jobs_events(js, id, since, FOREVER_S, &ev, &final, NULL));
    ASSERT_EQ(json_array_size(ev), 0);
    ASSERT_EQ(final, 1);
    json_decref(ev);
    jobs_close(js);
    gate_destroy(&G1);
    gate_destroy(&G2);
}

/* jobs_shutdown ends waits promptly; jobs still run. */
typedef struct waiter {
    jobs *js;
    const char *id;
    int rc;
} waiter;

/* Waits for an event that never comes: only jobs_shutdown ends it. */
static void *waiter_main(void *arg)
{
    waiter *w = arg;
    json_t *ev = NULL;
    int final;
    w->rc = jobs_events(w->js, w->id, 100, FOREVER_S, &ev, &final, NULL);
    json_decref(ev);
    return NULL;
}

TEST(shutdown_ends_event_waits_and_jobs_go_on)
{
    jobs *js;
    gate g;
    targ a = {.label = 'a'}, b = {.label = 'b'};
    char id[33], id2[33];
    pthread_t t;
    waiter w;
    json_t *o;
    journal_reset();
    gate_init(&g);
    a.gate = &g;
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &a, id));
    w.js = js;
    w.id = id;
    w.rc = 1;
    ASSERT_EQ(pthread_create(&t, NULL, waiter_main, &w), 0);
    ASSERT_OK(journal_wait_started(1));
    usleep(100 * 1000); /* let the waiter block (if not yet, it is refused at once) */
    jobs_shutdown(js);
    pthread_join(t, NULL); /* woken: nothing else ends its wait */
    ASSERT_EQ(w.rc, GLINT_EUNSUPPORTED);
    {
        json_t *ev;
        int final;
        ASSERT_EQ(jobs_events(js, id, 0, 0, &ev, &final, NULL), GLINT_EUNSUPPORTED);
    }
    /* the running job finishes and new ones run */
    ASSERT_OK(submit(js, "fit", &b, id2));
    gate_open(&g);
    ASSERT_OK(journal_wait_started(2));
    for (double end = glint_now() + WAIT_S; glint_now() < end;) {
        ASSERT_OK(jobs_get(js, id2, &o, NULL, NULL));
        int done = strcmp(str(o, "state"), "done") == 0;
        json_decref(o);
        if (done)
            break;
        usleep(10 * 1000);
    }
    ASSERT_OK(jobs_get(js, id2, &o, NULL, NULL));
    ASSERT(strcmp(str(o, "state"), "done") == 0);
    json_decref(o);
    jobs_close(js);
    gate_destroy(&g);
    ASSERT_EQ(atomic_load(&a.freed), 1);
    ASSERT_EQ(atomic_load(&b.freed), 1);
}

/* ---- scheduling ----------------------------------------------------------------- */

TEST(fits_run_before_queued_holdouts)
{
    jobs *js;
    gate g1, g2;
    targ f1 = {.label = '1'}, f2 = {.label = '2'}, h = {.label = 'H', .holdout = 1},
         f3 = {.label = '3'};
    char id[4][33];
    json_t *log;
    journal_reset();
    gate_init(&g1);
    gate_init(&g2);
    f1.gate = &g1;
    f2.gate = &g2;
    ASSERT_OK(jobs_open(2, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &f1, id[0]));
    ASSERT_OK(submit(js, "fit", &f2, id[1]));
    ASSERT_OK(journal_wait_started(2)); /* both workers busy */
    ASSERT_OK(submit(js, "holdout", &h, id[2]));
    ASSERT_OK(submit(js, "fit", &f3, id[3])); /* submitted later, runs first */
    {
        jobs_stats st;
        jobs_stats_get(js, &st);
        ASSERT_EQ(st.queued, 2);
        ASSERT_EQ(st.queued_fits, 1); /* the held-out measurement apart */
    }
    gate_open(&g1);
    ASSERT_OK(wait_final(js, id[3], &log));
    json_decref(log);
    ASSERT_OK(wait_final(js, id[2], &log));
    json_decref(log);
    pthread_mutex_lock(&J.mu);
    ASSERT_MSG(strcmp(J.order + 2, "3H") == 0, "start order %s", J.order);
    pthread_mutex_unlock(&J.mu);
    gate_open(&g2);
    jobs_close(js);
    gate_destroy(&g1);
    gate_destroy(&g2);
    ASSERT(atomic_load(&f1.freed) == 1 && atomic_load(&f2.freed) == 1 &&
           atomic_load(&h.freed) == 1 && atomic_load(&f3.freed) == 1);
}

TEST(one_holdout_at_a_time)
{
    jobs *js;
    gate g1, g2;
    targ h1 = {.label = 'A', .holdout = 1}, h2 = {.label = 'B', .holdout = 1},
         f = {.label = 'f'};
    char id1[33], id2[33], idf[33];
    json_t *log, *ev, *o;
    int final;
    journal_reset();
    gate_init(&g1);
    gate_init(&g2);
    h1.gate = &g1;
    h2.gate = &g2;
    ASSERT_OK(jobs_open(2, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "holdout", &h1, id1));
    ASSERT_OK(journal_wait_started(1));
    ASSERT_OK(submit(js, "holdout", &h2, id2));
    /* the second worker is free: it serves a fit, not the holdout */
    ASSERT_OK(submit(js, "fit", &f, idf));
    ASSERT_OK(wait_final(js, idf, &log));
    json_decref(log);
    /* and still leaves the holdout queued */
    ASSERT_OK(jobs_events(js, id2, 1, 0.3, &ev, &final, NULL));
    ASSERT_EQ(json_array_size(ev), 0);
    json_decref(ev);
    ASSERT_OK(jobs_get(js, id2, &o, NULL, NULL));
    ASSERT(strcmp(str(o, "state"), "queued") == 0);
    json_decref(o);
    /* when the first ends, the second starts */
    gate_open(&g1);
    ASSERT_OK(journal_wait_started(3));
    gate_open(&g2);
    ASSERT_OK(wait_final(js, id2, &log));
    json_decref(log);
    pthread_mutex_lock(&J.mu);
    ASSERT_MSG(strcmp(J.order, "AfB") == 0, "start order %s", J.order);
    ASSERT_EQ(J.max_holdouts, 1);
    pthread_mutex_unlock(&J.mu);
    jobs_close(js);
    gate_destroy(&g1);
    gate_destroy(&g2);
}

/* ---- limits and closing ----------------------------------------------------------- */

/* An owner id for owner number k (32 hex digits). */
static void owner_id(int k, char out[33])
{
    snprintf(out, 33, "%032x", k + 1);
}

TEST(people_and_background_queues_have_limits_of_their_own)
{
    jobs *js;
    gate g;
    static targ a[JOBS_MAX_QUEUED + 2], h[2];
    char id[33], own[33];
    glint_err e;
    jobs_stats st;
    journal_reset();
    gate_init(&g);
    memset(a, 0, sizeof a);
    memset(h, 0, sizeof h);
    a[0].gate = &g;
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &a[0], id));
    ASSERT_OK(journal_wait_started(1));
    /* the people's queue fills up from many owners, a few jobs each */
    for (int i = 1; i <= JOBS_MAX_QUEUED; i++) {
        owner_id(i % 64, own);
        ASSERT_OK(submit_as(js, own, NULL, &a[i], id, NULL));
    }
    jobs_stats_get(js, &st);
    ASSERT_EQ(st.queued, JOBS_MAX_QUEUED);
    ASSERT_EQ(st.queued_fits, JOBS_MAX_QUEUED);
    ASSERT_EQ(st.owners, 64);
    ASSERT_EQ(st.running, 1);
    owner_id(999, own);
    ASSERT_EQ(submit_as(js, own, NULL, &a[JOBS_MAX_QUEUED + 1], id, &e), GLINT_EBUSY);
    ASSERT(strstr(e.msg, "256") != NULL);
    ASSERT(strcmp(e.kind, "owner-queue-full") != 0);
    ASSERT_EQ(atomic_load(&a[JOBS_MAX_QUEUED + 1].freed), 1); /* at once */
    ASSERT_EQ(atomic_load(&a[JOBS_MAX_QUEUED + 1].ran), 0);
    /* background measurements wait apart: a full people's queue takes none of their room */
    ASSERT_OK(submit(js, "holdout", &h[0], id));
    ASSERT_OK(submit(js, "holdout", &h[1], id));
    jobs_stats_get(js, &st);
    ASSERT_EQ(st.queued_background, 2);
    ASSERT_EQ(st.queued, JOBS_MAX_QUEUED + 2);
    gate_open(&g);
    jobs_close(js);
    gate_destroy(&g);
    for (int i = 0; i < JOBS_MAX_QUEUED + 2; i++)
        ASSERT_MSG(atomic_load(&a[i].freed) == 1, "argument %d freed %d times", i,
                   atomic_load(&a[i].freed));
    ASSERT(atomic_load(&h[0].freed) == 1 && atomic_load(&h[1].freed) == 1);
}

TEST(one_owner_cannot_fill_the_queue)
{
    jobs *js;
    gate g;
    static targ a[JOBS_MAX_QUEUED_PER_OWNER + 3];
    char id[33], other[33], tg[16];
    glint_err e;
    journal_reset();
    gate_init(&g);
    memset(a, 0, sizeof a);
    a[0].gate = &g;
    owner_id(7, other);
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &a[0], id));
    ASSERT_OK(journal_wait_started(1));
    for (int i = 1; i <= JOBS_MAX_QUEUED_PER_OWNER; i++) { /* distinct targets: none replaced */
        snprintf(tg, sizeof tg, "m%d", i);
        ASSERT_OK(submit_as(js, OWNER, tg, &a[i], id, NULL));
    }
    ASSERT_EQ(submit_as(js, OWNER, "another", &a[JOBS_MAX_QUEUED_PER_OWNER + 1], id, &e),
              GLINT_EBUSY);
    ASSERT(strcmp(e.kind, "owner-queue-full") == 0);
    ASSERT_MSG(strstr(e.msg, "8 jobs of owner " OWNER) != NULL, "%s", e.msg);
    ASSERT_EQ(atomic_load(&a[JOBS_MAX_QUEUED_PER_OWNER + 1].freed), 1);
    /* another owner is not refused */
    ASSERT_OK(submit_as(js, other, "m1", &a[JOBS_MAX_QUEUED_PER_OWNER + 2], id, NULL));
    gate_open(&g);
    jobs_close(js);
    gate_destroy(&g);
    for (int i = 0; i < JOBS_MAX_QUEUED_PER_OWNER + 3; i++)
        ASSERT_EQ(atomic_load(&a[i].freed), 1);
}

TEST(owners_take_turns)
{
    jobs *js;
    gate g;
    targ a0 = {.label = '0'}, a1 = {.label = 'a'}, a2 = {.label = 'b'}, a3 = {.label = 'c'},
         b1 = {.label = 'B'}, c1 = {.label = 'C'};
    char id[6][33], ob[33], oc[33];
    json_t *log;
    journal_reset();
    gate_init(&g);
    a0.gate = &g;
    owner_id(1, ob);
    owner_id(2, oc);
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit_as(js, OWNER, NULL, &a0, id[0], NULL));
    ASSERT_OK(journal_wait_started(1));
    /* one owner floods the queue before the others come */
    ASSERT_OK(submit_as(js, OWNER, NULL, &a1, id[1], NULL));
    ASSERT_OK(submit_as(js, OWNER, NULL, &a2, id[2], NULL));
    ASSERT_OK(submit_as(js, OWNER, NULL, &a3, id[3], NULL));
    ASSERT_OK(submit_as(js, ob, NULL, &b1, id[4], NULL));
    ASSERT_OK(submit_as(js, oc, NULL, &c1, id[5], NULL));
    gate_open(&g);
    for (int i = 0; i < 6; i++) {
        ASSERT_OK(wait_final(js, id[i], &log));
        json_decref(log);
    }
    pthread_mutex_lock(&J.mu);
    ASSERT_MSG(strcmp(J.order, "0BCabc") == 0, "start order %s", J.order);
    pthread_mutex_unlock(&J.mu);
    jobs_close(js);
    gate_destroy(&g);
}

TEST(a_newer_job_supersedes_the_queued_ones_of_its_owner_and_target)
{
    jobs *js;
    gate g;
    targ r = {.label = 'r'}, q1 = {.label = '1'}, q2 = {.label = '2'}, q3 = {.label = '3'},
         q4 = {.label = '4'};
    char idr[33], id1[33], id2[33], id3[33], id4[33], ob[33];
    json_t *o, *log;
    journal_reset();
    gate_init(&g);
    r.gate = &g;
    owner_id(1, ob);
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit_as(js, OWNER, "hf3", &r, idr, NULL)); /* running: not superseded */
    ASSERT_OK(journal_wait_started(1));
    ASSERT_OK(submit_as(js, OWNER, "hf3", &q1, id1, NULL));
    ASSERT_OK(submit_as(js, OWNER, "srbf", &q3, id3, NULL)); /* another target */
    ASSERT_OK(submit_as(js, ob, "hf3", &q4, id4, NULL));     /* another owner */
    ASSERT_OK(submit_as(js, OWNER, "hf3", &q2, id2, NULL));  /* replaces q1 */
    ASSERT_OK(jobs_get(js, id1, &o, NULL, NULL));
    ASSERT(strcmp(str(o, "state"), "failed") == 0);
    ASSERT(strcmp(str(o, "cancelled"), "superseded") == 0);
    ASSERT(strcmp(str(o, "stage"), "superseded") == 0);
    ASSERT_MSG(strstr(str(o, "error"), id2) != NULL, "%s", str(o, "error"));
    json_decref(o);
    ASSERT_EQ(atomic_load(&q1.freed), 1); /* at once */
    {
        jobs_stats st;
        jobs_stats_get(js, &st);
        ASSERT_EQ(st.queued, 3);
        ASSERT_EQ(st.cancelled, 1);
    }
    gate_open(&g);
    ASSERT_OK(wait_final(js, idr, &log));
    ASSERT(strcmp(str(ev_job(log, json_array_size(log) - 1), "state"), "done") == 0);
    json_decref(log);
    ASSERT_OK(wait_final(js, id2, &log));
    json_decref(log);
    ASSERT_OK(wait_final(js, id3, &log));
    json_decref(log);
    ASSERT_OK(wait_final(js, id4, &log));
    json_decref(log);
    ASSERT_EQ(atomic_load(&q1.ran), 0);
    ASSERT(atomic_load(&q2.ran) == 1 && atomic_load(&q3.ran) == 1 && atomic_load(&q4.ran) == 1);
    jobs_close(js);
    gate_destroy(&g);
    ASSERT_EQ(atomic_load(&q1.freed), 1);
}

/* Runs until told to stop (or WAIT_S), then fails as a stopped job does. */
static void until_cancelled_body(job *j, targ *a)
{
    double end = glint_now() + WAIT_S;
    while (!job_cancelled(j) && glint_now() < end)
        usleep(2000);
    a->saw_cancel = job_cancelled(j);
    a->fail = a->saw_cancel ? GLINT_ECANCELLED : 0;
}

TEST(jobs_are_cancelled_queued_or_running)
{
    jobs *js;
    targ r = {.label = 'r', .body = until_cancelled_body}, q = {.label = 'q'};
    char idr[33], idq[33];
    json_t *o, *log;
    glint_err e;
    journal_reset();
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &r, idr));
    ASSERT_OK(journal_wait_started(1));
    ASSERT_OK(submit(js, "fit", &q, idq));
    /* queued: it fails now and never runs */
    ASSERT_OK(jobs_cancel(js, idq, &o, &e));
    ASSERT(strcmp(str(o, "state"), "failed") == 0);
    ASSERT(strcmp(str(o, "cancelled"), "deleted") == 0);
    json_decref(o);
    ASSERT_EQ(atomic_load(&q.freed), 1);
    /* running: told, and it fails once it stops */
    ASSERT_OK(jobs_cancel(js, idr, &o, &e));
    ASSERT(strcmp(str(o, "state"), "running") == 0);
    ASSERT(strcmp(str(o, "cancelled"), "deleted") == 0);
    json_decref(o);
    ASSERT_OK(wait_final(js, idr, &log));
    o = ev_job(log, json_array_size(log) - 1);
    ASSERT(strcmp(str(o, "state"), "failed") == 0);
    ASSERT(strcmp(str(o, "cancelled"), "deleted") == 0);
    ASSERT_MSG(strstr(str(o, "error"), "cancelled") != NULL, "%s", str(o, "error"));
    json_decref(log);
    ASSERT_EQ(r.saw_cancel, 1);
    /* finished, unknown */
    ASSERT_EQ(jobs_cancel(js, idr, &o, &e), GLINT_ECONFLICT);
    ASSERT(o == NULL);
    ASSERT_EQ(jobs_cancel(js, "ffffffffffffffffffffffffffffffff", &o, &e), GLINT_ENOTFOUND);
    ASSERT_EQ(atomic_load(&q.ran), 0);
    jobs_close(js);
    ASSERT_EQ(atomic_load(&r.freed), 1);
}

TEST(stop_tells_running_jobs_and_returns_at_once)
{
    jobs *js;
    targ r = {.label = 'r', .body = until_cancelled_body};
    char id[33];
    json_t *o, *log;
    journal_reset();
    ASSERT_OK(jobs_open(2, NULL, NULL, 0, &js, NULL));
    ASSERT_OK(submit(js, "fit", &r, id));
    ASSERT_OK(journal_wait_started(1));
    jobs_stop(js);
    ASSERT_OK(wait_final(js, id, &log));
    o = ev_job(log, json_array_size(log) - 1);
    ASSERT(strcmp(str(o, "state"), "failed") == 0);
    ASSERT(strcmp(str(o, "cancelled"), "stopping") == 0);
    ASSERT_MSG(strstr(str(o, "error"), "stopped while the job ran") != NULL, "%s",
               str(o, "error"));
    json_decref(log);
    ASSERT_EQ(submit(js, "fit", &(targ){.label = 'z'}, id), GLINT_EBUSY);
    jobs_close(js);
    ASSERT_EQ(r.saw_cancel, 1);
    ASSERT_EQ(atomic_load(&r.freed), 1);
}

static void close_body(job *j, targ *a)
{
    double end = glint_now() + WAIT_S;
    a->cancelled_at_start = job_cancelled(j);
    gate_open(a->ready);
    while (!job_cancelled(j) && glint_now() < end)
        usleep(2000);
    a->saw_cancel = job_cancelled(j);
    /* jobs_close has failed the queued jobs before cancelling this one */
    for (int i = 0; i < 2; i++) {
        json_t *o;
        if (jobs_get(a->js, a->queued_ids[i], &o, NULL, NULL) == 0) {
            snprintf(a->queued_state[i], sizeof a->queued_state[i], "%s", str(o, "state"));
            snprintf(a->queued_error[i], sizeof a->queued_error[i], "%s", str(o, "error"));
            json_decref(o);
        }
    }
    /* no new job once stopping */
    {
        char id[33];
        a->submit_rc = submit(a->js, "fit", a->late, id);
    }
    a->finished = 1;
}

TEST(close_fails_queued_jobs_and_lets_running_ones_finish)
{
    jobs *js;
    targ r = {.label = 'r', .body = close_body}, q1 = {.label = 'x'}, q2 = {.label = 'y'},
         late = {.label = 'z'};
    char id[33];
    gate ready;
    journal_reset();
    gate_init(&ready);
    ASSERT_OK(jobs_open(1, NULL, NULL, 0, &js, NULL));
    r.js = js;
    r.late = &late;
    r.ready = &ready;
    ASSERT_OK(submit(js, "fit", &r, id));
    ASSERT_OK(gate_wait(&ready));
    ASSERT_OK(submit(js, "fit", &q1, r.queued_ids[0]));
    ASSERT_OK(submit(js, "holdout", &q2, r.queued_ids[1]));
    jobs_close(js); /* returns once r has finished */
    ASSERT_EQ(r.finished, 1);
    ASSERT_EQ(r.cancelled_at_start, 0);
    ASSERT_EQ(r.saw_cancel, 1);
    for (int i = 0; i < 2; i++) {
        ASSERT_MSG(strcmp(r.queued_state[i], "failed") == 0, "queued job %d: %s", i,
                   r.queued_state[i]);
        ASSERT_MSG(strstr(r.queued_error[i], "stopped before the job ran") != NULL,
                   "queued job %d: %s", i, r.queued_error[i]);
    }
    ASSERT_EQ(r.submit_rc, GLINT_EBUSY);
    ASSERT_EQ(atomic_load(&q1.ran), 0);
    ASSERT_EQ(atomic_load(&q2.ran), 0);
    ASSERT_EQ(atomic_load(&late.ran), 0);
    ASSERT_EQ(atomic_load(&r.freed), 1);
    ASSERT_EQ(atomic_load(&q1.freed), 1);
    ASSERT_EQ(atomic_load(&q2.freed), 1);
    ASSERT_EQ(atomic_load(&late.freed), 1);
    gate_destroy(&ready);
}

/* ---- idle ------------------------------------------------------------------------ */

static atomic_int idle_calls, idle_cls_wrong;

static void on_idle(void *cls)
{
    if (*(int *)cls != 42)
        atomic_fetch_add(&idle_cls_wrong, 1);
    atomic_fetch_add(&idle_calls, 1);
}

static int wait_idle_calls_above(int n)
{
    for (double end = glint_now() + WAIT_S; glint_now() < end; usleep(10 * 1000))
        if (atomic_load(&idle_calls) > n)
            return 0;
    return -1;
}

TEST(idle_callback_runs_when_nothing_runs)
{
    jobs *js;
    gate g;
    targ a = {.label = 'a'};
    int cls = 42, before;
    char id[33];
    journal_reset();
    gate_init(&g);
    a.gate = &g;
    atomic_store(&idle_calls, 0);
    ASSERT_OK(jobs_open(1, on_idle, &cls, 0.05, &js, NULL));
    ASSERT_OK(wait_idle_calls_above(0));
    /* the only worker is busy: no idle call */
    ASSERT_OK(submit(js, "fit", &a, id));
    ASSERT_OK(journal_wait_started(1));
    before = atomic_load(&idle_calls);
    usleep(1300 * 1000); /* longer than the module's shortest idle period (1 s) */
    ASSERT_EQ(atomic_load(&idle_calls), before);
    gate_open(&g);
    ASSERT_OK(wait_idle_calls_above(before));
    jobs_close(js);
    gate_destroy(&g);
    ASSERT_EQ(atomic_load(&idle_cls_wrong), 0);
}

TEST(open_checks_thread_count)
{
    jobs *js = (jobs *)(void *)&J;
    ASSERT_EQ(jobs_open(0, NULL, NULL, 0, &js, NULL), GLINT_ERANGE);
    ASSERT(js == NULL);
    ASSERT_EQ(jobs_open(65, NULL, NULL, 0, &js, NULL), GLINT_ERANGE);
}

TEST_LIST{
    TEST_ENTRY(job_runs_and_reports_done_with_its_result),
    TEST_ENTRY(failing_job_reports_its_message),
    TEST_ENTRY(progress_is_logged_by_stage_and_in_steps),
    TEST_ENTRY(events_wait_and_return_only_new_ones),
    TEST_ENTRY(shutdown_ends_event_waits_and_jobs_go_on),
    TEST_ENTRY(fits_run_before_queued_holdouts),
    TEST_ENTRY(one_holdout_at_a_time),
    TEST_ENTRY(people_and_background_queues_have_limits_of_their_own),
    TEST_ENTRY(one_owner_cannot_fill_the_queue),
    TEST_ENTRY(owners_take_turns),
    TEST_ENTRY(a_newer_job_supersedes_the_queued_ones_of_its_owner_and_target),
    TEST_ENTRY(jobs_are_cancelled_queued_or_running),
    TEST_ENTRY(stop_tells_running_jobs_and_returns_at_once),
    TEST_ENTRY(close_fails_queued_jobs_and_lets_running_ones_finish),
    TEST_ENTRY(idle_callback_runs_when_nothing_runs),
    TEST_ENTRY(open_checks_thread_count),
};

TEST_MAIN()
