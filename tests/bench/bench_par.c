/* bench_par: what a run of the worker pool (par.h) costs beyond its work.
 *
 *   ./build/tests/bench/bench_par [ROUNDS]
 *
 * A run of two tasks of 20 us each (ideal: 20 us on two threads), timed
 * after a gap of serial work of 0, 50 and 1000 us (the worker still
 * spinning, or asleep), and after the 1000 us gap with par_warm() called
 * 100 us before the run (as a fit does before its first pass).  Each
 * setting of the spin runs in a process of its own (GLINT_POOL_SPIN_US is
 * read once), alternating, ROUNDS times (default 3).  Prints medians and
 * 90th percentiles of 400 runs. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "par.h"

#define RUNS 400

static volatile double sink;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static void busy(double s)
{
    double t0 = now();
    while (now() - t0 < s)
        sink += 1.0;
}

static void task(void *ctx, int k)
{
    (void)ctx;
    (void)k;
    busy(20e-6);
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* median and p90 in us of RUNS runs after `gap` s of serial work, with
 * par_warm() `warm` s before the run's start (0: not called) */
static void measure(double gap, double warm, double *med, double *p90)
{
    static double t[RUNS];
    for (int r = 0; r < RUNS; r++) {
        double t0;
        busy(gap - warm);
        if (warm > 0) {
            par_warm();
            busy(warm);
        }
        t0 = now();
        par_run(2, task, NULL);
        t[r] = now() - t0;
    }
    qsort(t, RUNS, sizeof *t, cmp);
    *med = 1e6 * t[RUNS / 2];
    *p90 = 1e6 * t[RUNS * 9 / 10];
}

static void child(void)
{
    static const double gaps[][2] = {{0, 0}, {50e-6, 0}, {1000e-6, 0}, {1000e-6, 100e-6}};
    const char *sp = getenv("GLINT_POOL_SPIN_US");
    printf("| %-9s |", sp ? sp : "default");
    /* the worker started, and placed: a new thread can share its parent's
     * CPU for the first few thousand microseconds, until the scheduler
     * moves one of them */
    for (int r = 0; r < 2000; r++)
        par_run(2, task, NULL);
    for (size_t g = 0; g < sizeof gaps / sizeof gaps[0]; g++) {
        double m, p;
        measure(gaps[g][0], gaps[g][1], &m, &p);
        printf(" %5.1f / %5.1f |", m, p);
    }
    printf("\n");
    fflush(stdout);
}

int main(int argc, char **argv)
{
    int rounds = 3;
    if (argc > 1 && strcmp(argv[1], "--child") == 0) {
        child();
        return 0;
    }
    if (argc > 1 && ((rounds = atoi(argv[1])) < 1 || rounds > 100)) {
        fprintf(stderr, "usage: bench_par [ROUNDS (1-100)]\n");
        return 2;
    }
    printf("threads %d; a run of 2 tasks of 20 us; median / p90 of %d runs, us\n\n",
           par_threads(), RUNS);
    printf("| spin (us) | back to back | after 50 us | after 1000 us | after 1000 us, "
           "par_warm 100 us before |\n|---|---|---|---|---|\n");
    fflush(stdout);
    for (int r = 0; r < rounds; r++)
        for (int s = 0; s < 2; s++) {
            pid_t pid = fork();
            if (pid < 0) {
                perror("fork");
                return 1;
            }
            if (pid == 0) {
                if (s == 0)
                    setenv("GLINT_POOL_SPIN_US", "0", 1);
                else
                    unsetenv("GLINT_POOL_SPIN_US");
                execl("/proc/self/exe", argv[0], "--child", (char *)NULL);
                perror("exec");
                _exit(127);
            }
            if (waitpid(pid, NULL, 0) < 0) {
                perror("waitpid");
                return 1;
            }
        }
    return 0;
}
