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
#include <unistd.h>

#include "err.h"

#define SWEEP_DENSE 400
#define SWEEP_RUNS 400

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

static int sweep_dense = SWEEP_DENSE, sweep_runs = SWEEP_RUNS;

/* Sweep op; returns the number of bad runs (printed). */
static int sweep(const char *name, op_fn op)
{
    long total, n, step, runs = 0, count;
    char msg[GLINT_ERR_MSG_MAX];
    int bad = 0, r;
    const char *at = getenv("GLINT_ALLOC_FAIL_AT"); /* N: one run, in this process (a debugger) */
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
    step = total <= sweep_dense ? 1 : (total - sweep_dense) / sweep_runs + 1;
    for (n = 0; n < total; n += n < sweep_dense ? 1 : step) {
        r = run_once(op, n, &count, msg, sizeof msg);
        runs++;
        if (r == RUN_FAILED_OK || r == RUN_CLEAN)
            continue;
        bad++;
        if (bad <= 8)
            fprintf(stderr, "  %s: allocation %ld of %ld failing: %s %s\n", name, n + 1, total,
                    r >= 100 ? "killed by signal" : "error without a fault", r >= 100 ? strsignal(r - 100) : msg);
    }
    printf("  %s: %ld allocations, %ld runs with one failing, %d bad\n", name, total, runs, bad);
    return bad;
}

#endif
