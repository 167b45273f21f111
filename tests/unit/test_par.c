/* test_par: the worker pool (par.h).  Every task of a run is called once
 * and has returned when par_run returns, whether the worker is spinning
 * when the run comes (runs back to back), asleep (gaps longer than the
 * spin) or woken by par_warm; runs from two threads at once and nested
 * runs each call every task once.  meson runs it twice: with the default
 * spin and with GLINT_POOL_SPIN_US=0. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "par.h"
#include "check.h"

#define MAX_TASKS 97

typedef struct counts {
    atomic_int hits[MAX_TASKS];
    atomic_int done; /* tasks that have returned */
    int work_us;     /* per task: busy for (task % 3) * work_us */
    int nested;      /* each task runs a par_run of its own */
} counts;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static void busy_us(double us)
{
    double t0 = now();
    while (now() - t0 < us * 1e-6)
        ;
}

static void inner(void *ctx, int t)
{
    atomic_fetch_add(&((atomic_int *)ctx)[t], 1);
}

static void task(void *ctx, int t)
{
    counts *c = ctx;
    atomic_fetch_add(&c->hits[t], 1);
    busy_us((t % 3) * c->work_us);
    if (c->nested) {
        atomic_int in[4];
        for (int k = 0; k < 4; k++)
            atomic_init(&in[k], 0);
        par_run(4, inner, in);
        for (int k = 0; k < 4; k++)
            if (atomic_load(&in[k]) != 1)
                atomic_fetch_add(&c->hits[t], 100); /* seen as a bad count */
    }
    atomic_fetch_add(&c->done, 1);
}

/* One run of n tasks: 0 when every task ran once and all had returned. */
static int one_run(counts *c, int n)
{
    for (int k = 0; k < MAX_TASKS; k++)
        atomic_store(&c->hits[k], 0);
    atomic_store(&c->done, 0);
    par_run(n, task, c);
    if (atomic_load(&c->done) != n)
        return 1;
    for (int k = 0; k < MAX_TASKS; k++)
        if (atomic_load(&c->hits[k]) != (k < n))
            return 1;
    return 0;
}

TEST(every_task_runs_once_back_to_back_and_after_gaps)
{
    counts c;
    int bad = 0;
    memset(&c, 0, sizeof c);
    c.work_us = 3;
    srand(7);
    for (int r = 0; r < 3000; r++) {
        int n = 1 + rand() % MAX_TASKS, gap = rand() % 4;
        bad += one_run(&c, n);
        /* back to back, within the spin, past it, long past it */
        busy_us(gap == 0 ? 0 : gap == 1 ? 20 : gap == 2 ? 300 : 1500);
    }
    ASSERT(bad == 0);
}

/* The caller's tasks are short and a worker's long: par_run must wait for
 * the worker (its join), spinning or asleep. */
TEST(the_run_waits_for_the_workers_last_task)
{
    counts c;
    int bad = 0;
    memset(&c, 0, sizeof c);
    c.work_us = 400; /* longer than the spin */
    for (int r = 0; r < 40; r++)
        bad += one_run(&c, 2 + r % 5);
    ASSERT(bad == 0);
}

TEST(par_warm_before_a_run_or_none)
{
    counts c;
    int bad = 0;
    memset(&c, 0, sizeof c);
    c.work_us = 2;
    for (int r = 0; r < 300; r++) {
        busy_us(r % 2 ? 1200 : 50);
        par_warm();
        if (r % 3 == 0)
            par_warm(); /* twice: one spin */
        busy_us(r % 5 * 30);
        bad += one_run(&c, 1 + r % 20);
    }
    par_warm(); /* with no run after it */
    busy_us(1000);
    ASSERT(bad == 0);
}

TEST(nested_runs_are_serial_and_whole)
{
    counts c;
    int bad = 0;
    memset(&c, 0, sizeof c);
    c.nested = 1;
    for (int r = 0; r < 200; r++)
        bad += one_run(&c, 1 + r % 9);
    ASSERT(bad == 0);
}

typedef struct racer {
    int bad;
    int background;
} racer;

static void *race(void *arg)
{
    racer *z = arg;
    counts *c = calloc(1, sizeof *c);
    if (!c) {
        z->bad = 1;
        return NULL;
    }
    c->work_us = 5;
    par_background(z->background);
    for (int r = 0; r < 500; r++) {
        if (r % 7 == 0)
            par_warm();
        z->bad += one_run(c, 1 + r % MAX_TASKS);
    }
    free(c);
    return NULL;
}

/* Two threads' runs at once (one takes the pool, the other runs its tasks
 * itself), and a background thread beside them. */
TEST(two_callers_and_a_background_thread_at_once)
{
    pthread_t th[3];
    racer z[3] = {{0, 0}, {0, 0}, {0, 1}};
    for (int i = 0; i < 3; i++)
        ASSERT(pthread_create(&th[i], NULL, race, &z[i]) == 0);
    for (int i = 0; i < 3; i++)
        pthread_join(th[i], NULL);
    ASSERT(z[0].bad == 0 && z[1].bad == 0 && z[2].bad == 0);
}

TEST_LIST {
    TEST_ENTRY(every_task_runs_once_back_to_back_and_after_gaps),
    TEST_ENTRY(the_run_waits_for_the_workers_last_task),
    TEST_ENTRY(par_warm_before_a_run_or_none),
    TEST_ENTRY(nested_runs_are_serial_and_whole),
    TEST_ENTRY(two_callers_and_a_background_thread_at_once),
};
TEST_MAIN()
