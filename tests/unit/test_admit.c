/* Tests of glintd's admission of expensive work (server/admit.h): the budget
 * and the slots are never exceeded, what can never fit is told apart from
 * what cannot fit now, waiting work enters as soon as room is made and gives
 * up when cancelled, many threads entering and leaving at once keep the
 * books exact, estimates beyond the time limit are refused with both
 * numbers, and a stop ends every wait.  Classes and clients: background work
 * leaves the reserved slots to interactive work and yields to interactive
 * work that waits; one client holds at most its share; a request whose
 * client went away while it waited gives up at once and takes nothing. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "admit.h"
#include "check.h"
#include "clock.h"

#define MB ((size_t)1 << 20)

static void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

TEST(enter_and_leave_within_the_budget)
{
    admit *a;
    admit_stats st;
    glint_err e;
    ASSERT_OK(admit_open(100 * MB, 4, 0, &a, NULL));
    ASSERT_OK(admit_enter(a, 60 * MB, "first", NULL));
    ASSERT_OK(admit_enter(a, 40 * MB, "second", NULL)); /* exactly the budget */
    ASSERT_EQ(admit_enter(a, 1, "third", &e), GLINT_EBUSY);
    ASSERT(strcmp(e.kind, "busy") == 0);
    ASSERT(strstr(e.msg, "third") && strstr(e.msg, "100 of 100 MiB"));
    admit_get_stats(a, &st);
    ASSERT_EQ(st.held, 100 * MB);
    ASSERT_EQ(st.running, 2);
    ASSERT_EQ(st.refused_busy, 1);
    admit_leave(a, 60 * MB);
    ASSERT_OK(admit_enter(a, 60 * MB, "third", NULL));
    admit_leave(a, 60 * MB);
    admit_leave(a, 40 * MB);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.held, 0);
    ASSERT_EQ(st.running, 0);
    ASSERT_EQ(st.peak, 100 * MB);
    ASSERT_EQ(st.admitted, 3);
    admit_close(a);
}

TEST(beyond_the_whole_budget_is_too_big_not_busy)
{
    admit *a;
    admit_stats st;
    glint_err e;
    ASSERT_OK(admit_open(100 * MB, 1, 0, &a, NULL));
    ASSERT_EQ(admit_enter(a, 100 * MB + 1, "a 4096x4096 preview", &e), GLINT_ETOOBIG);
    ASSERT(strcmp(e.kind, "over-budget") == 0);
    ASSERT(strstr(e.msg, "a 4096x4096 preview") && strstr(e.msg, "--work-mb"));
    /* also while the budget is busy, and for a waiter: it would wait forever */
    ASSERT_OK(admit_enter(a, 10 * MB, "x", NULL));
    ASSERT_EQ(admit_enter(a, 200 * MB, "y", NULL), GLINT_ETOOBIG);
    ASSERT_EQ(admit_wait(a, 200 * MB, "y", NULL, NULL, &e), GLINT_ETOOBIG);
    admit_leave(a, 10 * MB);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.refused_size, 3);
    ASSERT_EQ(st.held, 0);
    admit_close(a);
}

TEST(slots_bound_the_pieces_of_work)
{
    admit *a;
    glint_err e;
    ASSERT_OK(admit_open(100 * MB, 2, 0, &a, NULL));
    ASSERT_OK(admit_enter(a, 0, "a", NULL));
    ASSERT_OK(admit_enter(a, 0, "b", NULL));
    ASSERT_EQ(admit_enter(a, 0, "c", &e), GLINT_EBUSY);
    ASSERT(strstr(e.msg, "2 of 2 at once"));
    admit_leave(a, 0);
    ASSERT_OK(admit_enter(a, 0, "c", NULL));
    admit_leave(a, 0);
    admit_leave(a, 0);
    admit_close(a);
}

/* Leaves `bytes` once the budget has counted `waited` waits: the thread
 * that could not enter is inside its wait by then (the count is taken
 * under the lock the wait releases). */
typedef struct holder {
    admit *a;
    size_t bytes;
    long long waited;
} holder;

static void *leave_when_waited_main(void *arg)
{
    holder *h = arg;
    admit_stats st;
    for (admit_get_stats(h->a, &st); st.waited < h->waited; admit_get_stats(h->a, &st))
        sleep_s(1e-3);
    admit_leave(h->a, h->bytes);
    return NULL;
}

TEST(a_request_waits_up_to_wait_s_then_is_busy)
{
    admit *a;
    admit_stats st;
    pthread_t t;
    holder h;
    glint_err e;
    double t0;
    /* room made while it waits: admitted.  The wait (an hour) can only end
     * by the wake-up that admit_leave sends: were it missing, this would
     * hang until the test's timeout. */
    ASSERT_OK(admit_open(100 * MB, 1, 3600, &a, NULL));
    ASSERT_OK(admit_enter(a, 10 * MB, "first", NULL));
    h = (holder){a, 10 * MB, 1};
    ASSERT_OK(pthread_create(&t, NULL, leave_when_waited_main, &h));
    ASSERT_OK(admit_enter(a, 10 * MB, "second", NULL));
    pthread_join(t, NULL);
    admit_leave(a, 10 * MB);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.waited, 1);
    ASSERT_EQ(st.admitted, 2);
    ASSERT_EQ(st.refused_busy, 0);
    ASSERT_EQ(st.held, 0);
    admit_close(a);
    /* no room within the wait: busy, and not before wait_s had passed (a
     * lower bound: a busy machine only makes the wait longer) */
    ASSERT_OK(admit_open(100 * MB, 1, 0.3, &a, NULL));
    ASSERT_OK(admit_enter(a, 10 * MB, "first", NULL));
    t0 = glint_now();
    ASSERT_EQ(admit_enter(a, 10 * MB, "third", &e), GLINT_EBUSY);
    ASSERT(glint_now() - t0 >= 0.29);
    ASSERT(strcmp(e.kind, "busy") == 0);
    admit_leave(a, 10 * MB);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.waited, 1);
    ASSERT_EQ(st.refused_busy, 1);
    ASSERT_EQ(st.held, 0);
    admit_close(a);
}

typedef struct waiter {
    admit *a;
    size_t bytes;
    atomic_int cancel, entered, rc;
    atomic_int polls;          /* calls of cancelled(): one per round of the wait */
} waiter;

static int cancelled(void *cls)
{
    waiter *w = cls;
    atomic_fetch_add(&w->polls, 1);
    return atomic_load(&w->cancel);
}

static void *wait_main(void *arg)
{
    waiter *w = arg;
    glint_err e;
    int rc = admit_wait(w->a, w->bytes, "a fit", cancelled, w, &e);
    atomic_store(&w->rc, rc);
    atomic_store(&w->entered, rc == 0);
    return NULL;
}

/* Until the waiter has asked cancelled() n times: it is in its wait loop
 * (the first call comes before its first wait, the second after it). */
static void until_polled(waiter *w, int n)
{
    while (atomic_load(&w->polls) < n)
        sleep_s(1e-3);
}

TEST(a_waiter_enters_when_room_is_made)
{
    waiter w = {0};
    pthread_t t;
    admit_stats st;
    ASSERT_OK(admit_open(100 * MB, 4, 0, &w.a, NULL));
    w.bytes = 70 * MB;
    ASSERT_OK(admit_enter(w.a, 50 * MB, "render", NULL));
    ASSERT_OK(pthread_create(&t, NULL, wait_main, &w));
    until_polled(&w, 2);
    ASSERT_EQ(atomic_load(&w.entered), 0); /* 50 + 70 > 100: still waiting */
    admit_leave(w.a, 50 * MB);
    pthread_join(t, NULL);
    ASSERT_EQ(atomic_load(&w.entered), 1);
    ASSERT_EQ(atomic_load(&w.rc), 0);
    admit_get_stats(w.a, &st);
    ASSERT_EQ(st.held, 70 * MB);
    ASSERT_EQ(st.waited, 1);
    admit_leave(w.a, 70 * MB);
    admit_close(w.a);
}

TEST(a_cancelled_waiter_gives_up)
{
    waiter w = {0};
    pthread_t t;
    admit_stats st;
    ASSERT_OK(admit_open(100 * MB, 1, 0, &w.a, NULL));
    w.bytes = 10 * MB;
    ASSERT_OK(admit_enter(w.a, 1 * MB, "render", NULL)); /* the only slot */
    ASSERT_OK(pthread_create(&t, NULL, wait_main, &w));
    until_polled(&w, 2);
    atomic_store(&w.cancel, 1);
    pthread_join(t, NULL); /* at its next round: the test's timeout catches a hang */
    ASSERT_EQ(atomic_load(&w.entered), 0);
    ASSERT_EQ(atomic_load(&w.rc), GLINT_EBUSY);
    admit_get_stats(w.a, &st);
    ASSERT_EQ(st.held, 1 * MB); /* the waiter took nothing */
    ASSERT_EQ(st.running, 1);
    ASSERT_EQ(st.admitted, 1);
    admit_leave(w.a, 1 * MB);
    admit_close(w.a);
}

TEST(an_estimate_beyond_the_limit_is_refused_with_both_numbers)
{
    admit *a;
    admit_stats st;
    glint_err e;
    ASSERT_OK(admit_open(100 * MB, 1, 0, &a, NULL));
    ASSERT_OK(admit_cost(a, 1e9, "anything", &e)); /* no limit by default */
    admit_limit_seconds(a, 600);
    ASSERT_OK(admit_cost(a, 600.0, "a 512x512 preview", &e));
    ASSERT_EQ(admit_cost(a, 1234.4, "a 2048x2048 preview", &e), GLINT_ETOOBIG);
    ASSERT(strcmp(e.kind, "too-expensive") == 0);
    ASSERT_MSG(strstr(e.msg, "a 2048x2048 preview") && strstr(e.msg, "1234 s") &&
                   strstr(e.msg, "600 s") && strstr(e.msg, "--work-max-seconds"),
               "%s", e.msg);
    ASSERT_EQ(admit_cost(a, 0.0 / 0.0, "nan", &e), GLINT_ETOOBIG);
    admit_cancelled(a);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.refused_cost, 2);
    ASSERT_EQ(st.cancelled, 1);
    ASSERT_EQ(st.running, 0); /* an estimate holds nothing */
    ASSERT(st.max_seconds == 600.0);
    ASSERT_OK(admit_cost(NULL, 1e30, "x", &e));
    admit_close(a);
}

TEST(stop_ends_the_waits_and_refuses_new_work)
{
    waiter w = {0};
    pthread_t t;
    glint_err e;
    ASSERT_OK(admit_open(100 * MB, 1, 3600, &w.a, NULL));
    w.bytes = 10 * MB;
    ASSERT_OK(admit_enter(w.a, 1 * MB, "render", NULL)); /* the only slot */
    ASSERT_OK(pthread_create(&t, NULL, wait_main, &w));
    until_polled(&w, 2);
    admit_stop(w.a);
    pthread_join(t, NULL); /* returns (it would wait for ever): the test's timeout catches a hang */
    ASSERT_EQ(atomic_load(&w.entered), 0);
    ASSERT_EQ(atomic_load(&w.rc), GLINT_EBUSY);
    ASSERT_EQ(admit_enter(w.a, 0, "a preview", &e), GLINT_EBUSY); /* would wait an hour */
    ASSERT(strcmp(e.kind, "stopping") == 0);
    admit_leave(w.a, 1 * MB);
    admit_close(w.a);
}

/* A ticket's waiter on its own thread: admit_take with its class and
 * client, polling gone. */
typedef struct taker {
    admit *a;
    admit_ticket t;
    int forever;
    atomic_int gone, polls, done, rc;
    glint_err e;
} taker;

static int taker_gone(void *cls)
{
    taker *k = cls;
    atomic_fetch_add(&k->polls, 1);
    return atomic_load(&k->gone);
}

static void *take_main(void *arg)
{
    taker *k = arg;
    int rc;
    k->t.gone = taker_gone;
    k->t.gone_cls = k;
    rc = admit_take(k->a, &k->t, "a render", k->forever, &k->e);
    atomic_store(&k->rc, rc);
    atomic_store(&k->done, 1);
    return NULL;
}

static void taker_polled(taker *k, int n)
{
    while (atomic_load(&k->polls) < n)
        sleep_s(1e-3);
}

static admit_ticket ticket(size_t bytes, admit_class cls, const char *client)
{
    admit_ticket t = {.bytes = bytes, .cls = cls};
    snprintf(t.client, sizeof t.client, "%s", client ? client : "");
    return t;
}

TEST(background_work_leaves_the_reserved_slot)
{
    admit *a;
    admit_stats st;
    glint_err e;
    admit_ticket b1 = ticket(MB, ADMIT_BACKGROUND, NULL), b2 = b1, b3 = b1;
    admit_ticket i1 = ticket(MB, ADMIT_INTERACTIVE, NULL);
    ASSERT_OK(admit_open(100 * MB, 3, 0, &a, NULL));
    admit_get_stats(a, &st);
    ASSERT_EQ(st.reserve, 1); /* the defaults: one slot kept, half the slots a client */
    ASSERT_EQ(st.per_client, 1);
    ASSERT_OK(admit_take(a, &b1, "reference render 1", 0, &e));
    ASSERT_OK(admit_take(a, &b2, "reference render 2", 0, &e));
    ASSERT_EQ(admit_take(a, &b3, "reference render 3", 0, &e), GLINT_EBUSY);
    ASSERT(strcmp(e.kind, "busy") == 0);
    ASSERT_MSG(strstr(e.msg, "reference render 3 will follow") && strstr(e.msg, "keeps room"),
               "%s", e.msg);
    ASSERT_EQ(b3.held, 0);
    ASSERT_OK(admit_take(a, &i1, "a preview", 0, &e)); /* the kept slot */
    admit_get_stats(a, &st);
    ASSERT_EQ(st.running, 3);
    ASSERT_EQ(st.running_by[ADMIT_BACKGROUND], 2);
    ASSERT_EQ(st.running_by[ADMIT_INTERACTIVE], 1);
    ASSERT_EQ(st.refused_by[ADMIT_BACKGROUND], 1);
    ASSERT_EQ(st.refused_by[ADMIT_INTERACTIVE], 0);
    admit_give(a, &b1);
    admit_give(a, &b1); /* once only */
    admit_get_stats(a, &st);
    ASSERT_EQ(st.running, 2);
    admit_give(a, &b2);
    admit_give(a, &i1);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.running, 0);
    ASSERT_EQ(st.held, 0);
    /* its share of the memory, (3 - 1) / 3 of the budget, once some runs:
     * the first piece may take more */
    admit_limit_classes(a, 1, 3);
    b1.bytes = 80 * MB;
    b2.bytes = 1 * MB;
    i1.bytes = 19 * MB;
    ASSERT_OK(admit_take(a, &b1, "an export", 0, &e));
    ASSERT_EQ(admit_take(a, &b2, "a reference render", 0, &e), GLINT_EBUSY);
    ASSERT_OK(admit_take(a, &i1, "a preview", 0, &e));
    admit_give(a, &b1);
    ASSERT_OK(admit_take(a, &b2, "a reference render", 0, &e));
    admit_give(a, &b2);
    admit_give(a, &i1);
    b1.bytes = b2.bytes = b3.bytes = MB;
    /* with no reserve, background work takes every slot */
    admit_limit_classes(a, 0, 3);
    ASSERT_OK(admit_take(a, &b1, "1", 0, &e));
    ASSERT_OK(admit_take(a, &b2, "2", 0, &e));
    ASSERT_OK(admit_take(a, &b3, "3", 0, &e));
    admit_give(a, &b1);
    admit_give(a, &b2);
    admit_give(a, &b3);
    admit_close(a);
}

TEST(background_work_yields_to_interactive_work_that_waits)
{
    admit *a;
    admit_stats st;
    admit_ticket running = ticket(MB, ADMIT_INTERACTIVE, NULL);
    taker bg = {0}, fit = {0};
    pthread_t tb, tf;
    ASSERT_OK(admit_open(100 * MB, 1, 0, &a, NULL)); /* one slot: nothing reserved */
    ASSERT_OK(admit_take(a, &running, "a fit", 0, NULL));
    bg.a = fit.a = a;
    bg.forever = fit.forever = 1;
    bg.t = ticket(MB, ADMIT_BACKGROUND, NULL);
    fit.t = ticket(MB, ADMIT_INTERACTIVE, NULL);
    ASSERT_OK(pthread_create(&tb, NULL, take_main, &bg)); /* the render waits first */
    taker_polled(&bg, 2);
    ASSERT_OK(pthread_create(&tf, NULL, take_main, &fit));
    taker_polled(&fit, 2);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.waiting_by[ADMIT_BACKGROUND], 1);
    ASSERT_EQ(st.waiting_by[ADMIT_INTERACTIVE], 1);
    admit_give(a, &running);
    pthread_join(tf, NULL); /* the fit enters first, though it came second */
    ASSERT_EQ(atomic_load(&fit.rc), 0);
    ASSERT_EQ(atomic_load(&bg.done), 0);
    taker_polled(&bg, atomic_load(&bg.polls) + 2); /* it went round and still waits */
    ASSERT_EQ(atomic_load(&bg.done), 0);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.running_by[ADMIT_INTERACTIVE], 1);
    ASSERT_EQ(st.running_by[ADMIT_BACKGROUND], 0);
    admit_give(a, &fit.t);
    pthread_join(tb, NULL);
    ASSERT_EQ(atomic_load(&bg.rc), 0);
    admit_give(a, &bg.t);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.running, 0);
    ASSERT_EQ(st.waiting_by[0] + st.waiting_by[1], 0);
    admit_close(a);
}

TEST(one_client_holds_at_most_its_share)
{
    admit *a;
    admit_stats st;
    glint_err e;
    admit_ticket x1 = ticket(MB, ADMIT_BACKGROUND, "o:artist-x"), x2 = x1;
    admit_ticket x3 = ticket(MB, ADMIT_INTERACTIVE, "o:artist-x");
    admit_ticket y1 = ticket(MB, ADMIT_INTERACTIVE, "o:artist-y");
    admit_ticket anon = ticket(MB, ADMIT_INTERACTIVE, NULL);
    ASSERT_OK(admit_open(100 * MB, 5, 0, &a, NULL));
    admit_limit_classes(a, 1, 2);
    ASSERT_OK(admit_take(a, &x1, "reference render 1", 0, &e));
    ASSERT_OK(admit_take(a, &x2, "reference render 2", 0, &e));
    ASSERT_EQ(admit_take(a, &x3, "your preview", 0, &e), GLINT_EBUSY);
    ASSERT(strcmp(e.kind, "busy") == 0);
    ASSERT_MSG(strstr(e.msg, "rendering your reference images") &&
                   strstr(e.msg, "your preview will follow") && strstr(e.msg, "--work-per-client"),
               "%s", e.msg);
    ASSERT_OK(admit_take(a, &y1, "another artist's preview", 0, &e));
    ASSERT_OK(admit_take(a, &anon, "a fit", 0, &e)); /* no client: not counted */
    admit_get_stats(a, &st);
    ASSERT_EQ(st.refused_client, 1);
    ASSERT_EQ(st.running, 4);
    admit_give(a, &x1);
    ASSERT_OK(admit_take(a, &x3, "your preview", 0, &e)); /* its share has room again */
    admit_give(a, &x2);
    admit_give(a, &x3);
    admit_give(a, &y1);
    admit_give(a, &anon);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.running, 0);
    /* the rows of clients are reused: many clients one after another */
    for (int i = 0; i < 50; i++) {
        char who[16];
        snprintf(who, sizeof who, "a:10.0.0.%d", i);
        x1 = ticket(MB, ADMIT_INTERACTIVE, who);
        ASSERT_OK(admit_take(a, &x1, "a preview", 0, &e));
        admit_give(a, &x1);
    }
    admit_close(a);
}

TEST(a_request_whose_client_went_away_while_waiting_takes_nothing)
{
    admit *a;
    admit_stats st;
    glint_err e;
    admit_ticket render = ticket(10 * MB, ADMIT_INTERACTIVE, "a:10.0.0.1"), next;
    taker k = {0};
    pthread_t t;
    /* a request waits up to an hour: only its client's going ends the wait */
    ASSERT_OK(admit_open(100 * MB, 1, 3600, &a, NULL));
    ASSERT_OK(admit_take(a, &render, "a render", 0, &e));
    k.a = a;
    k.t = ticket(10 * MB, ADMIT_INTERACTIVE, "a:10.0.0.2");
    ASSERT_OK(pthread_create(&t, NULL, take_main, &k));
    taker_polled(&k, 2);
    atomic_store(&k.gone, 1);
    pthread_join(t, NULL); /* at its next round: the test's timeout catches a hang */
    ASSERT_EQ(atomic_load(&k.rc), GLINT_EBUSY);
    ASSERT(strcmp(k.e.kind, "cancelled") == 0);
    ASSERT_EQ(k.t.held, 0);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.gone_waiting, 1);
    ASSERT_EQ(st.running, 1);
    ASSERT_EQ(st.held, 10 * MB);
    ASSERT_EQ(st.waiting_by[ADMIT_INTERACTIVE], 0);
    admit_give(a, &render); /* the slot is free for the next request at once */
    next = ticket(10 * MB, ADMIT_INTERACTIVE, "a:10.0.0.3");
    ASSERT_OK(admit_take(a, &next, "the next preview", 0, &e));
    admit_give(a, &next);
    admit_close(a);
}

TEST(class_limits_are_clamped)
{
    admit *a;
    admit_stats st;
    ASSERT_OK(admit_open(100 * MB, 4, 0, &a, NULL));
    admit_limit_classes(a, 9, 0);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.reserve, 3); /* background work keeps one slot */
    ASSERT_EQ(st.per_client, 1);
    admit_limit_classes(a, -1, 99);
    admit_get_stats(a, &st);
    ASSERT_EQ(st.reserve, 0);
    ASSERT_EQ(st.per_client, 4);
    admit_limit_classes(NULL, 1, 1);
    admit_close(a);
}

/* Many threads entering (or waiting) and leaving: the held bytes never pass
 * the budget and the books end at zero. */
typedef struct churn {
    admit *a;
    int seed;
    atomic_int *over;
} churn;

static void *churn_main(void *arg)
{
    churn *c = arg;
    unsigned s = (unsigned)c->seed;
    for (int i = 0; i < 500; i++) {
        size_t b = (size_t)(1 + (s = s * 1103515245u + 12345u) % 40) * MB;
        admit_stats st;
        int wait = (s >> 16) & 1;
        if (wait ? admit_wait(c->a, b, "w", NULL, NULL, NULL) : admit_enter(c->a, b, "e", NULL))
            continue;
        admit_get_stats(c->a, &st);
        if (st.held > st.budget || st.running > st.slots)
            atomic_fetch_add(c->over, 1);
        sleep_s(1e-4); /* hold it a moment: the others meet a full budget */
        admit_leave(c->a, b);
    }
    return NULL;
}

TEST(concurrent_books_stay_exact)
{
    admit *a;
    admit_stats st;
    atomic_int over = 0;
    pthread_t t[8];
    churn c[8];
    ASSERT_OK(admit_open(100 * MB, 3, 0, &a, NULL));
    for (int i = 0; i < 8; i++) {
        c[i] = (churn){a, i + 1, &over};
        ASSERT_OK(pthread_create(&t[i], NULL, churn_main, &c[i]));
    }
    for (int i = 0; i < 8; i++)
        pthread_join(t[i], NULL);
    admit_get_stats(a, &st);
    ASSERT_EQ(atomic_load(&over), 0);
    ASSERT_EQ(st.held, 0);
    ASSERT_EQ(st.running, 0);
    ASSERT_LE(st.peak, 100 * MB);
    ASSERT(st.admitted > 0 && st.refused_busy > 0);
    admit_close(a);
}

TEST(null_admits_everything)
{
    ASSERT_OK(admit_enter(NULL, (size_t)-1, "x", NULL));
    ASSERT_OK(admit_wait(NULL, (size_t)-1, "x", NULL, NULL, NULL));
    admit_leave(NULL, 1);
    admit_metrics(NULL, stdout);
    ASSERT_EQ(admit_open(0, 1, 0, &(admit *){NULL}, NULL), GLINT_EINVAL);
    ASSERT_EQ(admit_open(1, 1, -1.0, &(admit *){NULL}, NULL), GLINT_EINVAL);
    ASSERT_EQ(admit_open(1, 0, 0, &(admit *){NULL}, NULL), GLINT_EINVAL);
    ASSERT_EQ(admit_open(1, 1, -1.0, &(admit *){NULL}, NULL), GLINT_EINVAL);
}

TEST_LIST{
    TEST_ENTRY(enter_and_leave_within_the_budget),
    TEST_ENTRY(beyond_the_whole_budget_is_too_big_not_busy),
    TEST_ENTRY(slots_bound_the_pieces_of_work),
    TEST_ENTRY(a_request_waits_up_to_wait_s_then_is_busy),
    TEST_ENTRY(a_waiter_enters_when_room_is_made),
    TEST_ENTRY(a_cancelled_waiter_gives_up),
    TEST_ENTRY(concurrent_books_stay_exact),
    TEST_ENTRY(null_admits_everything),
    TEST_ENTRY(an_estimate_beyond_the_limit_is_refused_with_both_numbers),
    TEST_ENTRY(stop_ends_the_waits_and_refuses_new_work),
    TEST_ENTRY(background_work_leaves_the_reserved_slot),
    TEST_ENTRY(background_work_yields_to_interactive_work_that_waits),
    TEST_ENTRY(one_client_holds_at_most_its_share),
    TEST_ENTRY(a_request_whose_client_went_away_while_waiting_takes_nothing),
    TEST_ENTRY(class_limits_are_clamped),
};
TEST_MAIN()
