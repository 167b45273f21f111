/* alloc_fail.h: the allocation-failure harness of test_alloc_fail.c and
 * test_alloc_fail_server.c (see the first for what it does and why only
 * glint's own allocations fail).  Defines malloc, calloc, realloc and free
 * for the program that includes it: include it in one file of a program
 * built without the sanitizers. */
#ifndef GLINT_ALLOC_FAIL_H
#define GLINT_ALLOC_FAIL_H

#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "err.h"

/* An operation with at most SWEEP_ALL allocations is swept at every one;
 * a longer one at about SWEEP_RUNS of them: every k-th from an offset
 * (k = ceil(total / SWEEP_RUNS)), the offset drawn anew for each run of the
 * program so that successive runs cover the whole path.  Each sweep prints
 * its k and offset; GLINT_ALLOC_FAIL_OFFSET=O and GLINT_ALLOC_FAIL_STRIDE=K
 * replay it (the offset is taken modulo k; K applies to the longer
 * operations only, and GLINT_ALLOC_FAIL_STRIDE=1 sweeps every allocation of
 * every operation). */
#define SWEEP_ALL 400
#define SWEEP_RUNS 200

/* ---- the replacement allocator -------------------------------------------------------- */

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);

static long fi_countdown = -1; /* >= 0: allocations left before the one that fails */
static long fi_count;          /* allocations made while armed */
static int fi_fired;

extern char __executable_start, etext;

/* Is an allocation made at `caller` one that may fail? */
static int fi_in_scope(const void *caller)
{
    return (const char *)caller >= &__executable_start && (const char *)caller < &etext;
}

/* An allocation a library made through glint's choice of allocator
 * (SQLite's sqlite3_config, test_alloc_fail_server.c) passes NULL: it may
 * fail, the library being one that survives it. */
static int fi_fail(const void *caller)
{
    if (fi_countdown < 0 || (caller && !fi_in_scope(caller)))
        return 0;
    fi_count++;
    if (fi_countdown-- == 0) {
        fi_fired = 1;
        return 1;
    }
    return 0;
}

void *malloc(size_t n)
{
    return fi_fail(__builtin_return_address(0)) ? NULL : __libc_malloc(n);
}

void *calloc(size_t a, size_t b)
{
    return fi_fail(__builtin_return_address(0)) ? NULL : __libc_calloc(a, b);
}

void *realloc(void *p, size_t n)
{
    return fi_fail(__builtin_return_address(0)) ? NULL : __libc_realloc(p, n);
}

void free(void *p)
{
    __libc_free(p);
}

/* A process the operation forks runs without failures (see the top). */
static void fi_disarm(void)
{
    fi_countdown = -1;
}

__attribute__((constructor)) static void fi_init(void)
{
    pthread_atfork(NULL, NULL, fi_disarm);
}

/* ---- the sweep ------------------------------------------------------------------------ */

enum { RUN_CLEAN = 0, RUN_FAILED_OK = 1, RUN_ERROR_WITHOUT_FAULT = 2, RUN_COUNT = 3 };

typedef int (*op_fn)(glint_err *e);

/* One run in a child: fail allocation n (n < 0: none, and report how many
 * allocations the operation made through a pipe). */
static int run_once(op_fn op, long n, long *count, char *msg, size_t msg_len)
{
    int fds[2], status;
    pid_t pid;
    if (pipe(fds))
        return -1;
    fflush(NULL);
    pid = fork();
    if (pid < 0)
        return -1;
    if (pid == 0) {
        glint_err e;
        int rc, code;
        close(fds[0]);
        alarm(60);
        memset(&e, 0, sizeof e);
        fi_count = 0;
        fi_fired = 0;
        fi_countdown = n < 0 ? (long)1 << 60 : n;
        rc = op(&e);
        fi_countdown = -1;
        code = !fi_fired ? (rc ? RUN_ERROR_WITHOUT_FAULT : RUN_CLEAN) : RUN_FAILED_OK;
        if (write(fds[1], &fi_count, sizeof fi_count) < 0 ||
            write(fds[1], e.msg, strlen(e.msg) + 1) < 0)
            _exit(99);
        _exit(code);
    }
    close(fds[1]);
    memset(msg, 0, msg_len);
    if (read(fds[0], count, sizeof *count) != (ssize_t)sizeof *count)
        *count = -1;
    else if (read(fds[0], msg, msg_len - 1) < 0)
        msg[0] = '\0';
    close(fds[0]);
    if (waitpid(pid, &status, 0) < 0)
        return -1;
    if (WIFSIGNALED(status))
        return 100 + WTERMSIG(status);
    return WEXITSTATUS(status);
}

static int sweep_all = SWEEP_ALL, sweep_runs = SWEEP_RUNS;

/* The offset of the strided sweeps: $GLINT_ALLOC_FAIL_OFFSET, else drawn
 * from the time and the process id (printed once). */
static long sweep_offset(void)
{
    static long off = -1;
    const char *env;
    if (off >= 0)
        return off;
    env = getenv("GLINT_ALLOC_FAIL_OFFSET");
    if (env && *env)
        off = atol(env) < 0 ? 0 : atol(env);
    else {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        off = (long)(((unsigned long)ts.tv_sec * 1000003u ^ (unsigned long)ts.tv_nsec ^
                      (unsigned long)getpid() * 7919u) % 1000000007u);
    }
    printf("  strided sweeps from offset %ld (GLINT_ALLOC_FAIL_OFFSET=%ld replays them)\n", off,
           off);
    return off;
}

/* Sweep op; returns the number of bad runs (printed). */
static int sweep(const char *name, op_fn op)
{
    long total, n, stride = 1, first = 0, runs = 0, count;
    char msg[GLINT_ERR_MSG_MAX];
    int bad = 0, r;
    const char *at = getenv("GLINT_ALLOC_FAIL_AT"); /* N: one run, in this process (a debugger) */
    const char *k = getenv("GLINT_ALLOC_FAIL_STRIDE");
    if (at) {
        glint_err e;
        fi_countdown = atol(at) - 1;
        r = op(&e);
        fi_countdown = -1;
        printf("  %s: allocation %s failing: rc %d, %s\n", name, at, r, r ? e.msg : "");
        return 0;
    }
    r = run_once(op, -1, &total, msg, sizeof msg);
    if (r != RUN_CLEAN) {
        fprintf(stderr, "  %s: the operation fails without any fault (%d): %s\n", name, r, msg);
        return 1;
    }
    if (total > sweep_all)
        stride = k && *k ? (atol(k) < 1 ? 1 : atol(k)) : (total + sweep_runs - 1) / sweep_runs;
    if (stride > 1)
        first = sweep_offset() % stride;
    for (n = first; n < total; n += stride) {
        r = run_once(op, n, &count, msg, sizeof msg);
        runs++;
        if (r == RUN_FAILED_OK || r == RUN_CLEAN)
            continue;
        bad++;
        if (bad <= 8)
            fprintf(stderr, "  %s: allocation %ld of %ld failing (GLINT_ALLOC_FAIL_AT=%ld): %s %s\n",
                    name, n + 1, total, n + 1, r >= 100 ? "killed by signal" : "error without a fault",
                    r >= 100 ? strsignal(r - 100) : msg);
    }
    if (stride > 1)
        printf("  %s: %ld allocations, one in %ld from allocation %ld (GLINT_ALLOC_FAIL_STRIDE=%ld "
               "GLINT_ALLOC_FAIL_OFFSET=%ld), %ld runs with one failing, %d bad\n",
               name, total, stride, first + 1, stride, first, runs, bad);
    else
        printf("  %s: %ld allocations, every one failing in turn, %ld runs, %d bad\n", name,
               total, runs, bad);
    return bad;
}

#endif
