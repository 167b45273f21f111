/* par.h: a small pool of worker threads for the sample-level loops of a
 * fit (the scatter of A^T f, gathers, error diagnostics), which are short
 * (0.1 to a few ms) and bandwidth- or throughput-bound.
 *
 * par_run(ntasks, fn, ctx) calls fn(ctx, task) once for every task in
 * 0..ntasks-1, on the calling thread and on the pool's workers, and returns
 * when all have returned.  Tasks are claimed in order from a shared
 * counter, so which thread runs a task is not fixed: a caller that wants a
 * result independent of the thread count (glint's do) gives every task its
 * own output and combines them afterwards in task order.
 *
 * The pool has par_threads() - 1 workers (the online CPUs, at most
 * PAR_MAX_THREADS; GLINT_THREADS=N in the environment sets N, 1 = no
 * workers), started at the first par_run that can use them.  After a run
 * a worker spins for PAR_SPIN_US (yielding the CPU every few microseconds),
 * then sleeps on a condition variable: a fit's runs follow one another
 * within microseconds, and a daemon that is not fitting costs nothing.  The
 * caller likewise spins that long for a worker still in its last task
 * before it sleeps.  GLINT_POOL_SPIN_US=N in the environment sets the spin
 * (0: none).  One run at a time uses the pool: a par_run that
 * finds it busy (another thread's fit) runs its tasks on its own thread,
 * never waiting for the other (and a thread marked par_background() never
 * takes it).  par_run is therefore safe from any thread,
 * and from inside a task (the nested run is serial).
 *
 * Costs measured (2 vCPUs of a virtual machine; tests/bench/bench_par.c):
 * a run of two 20 us tasks took 55-70 us (medians) with the worker asleep
 * and 20-21 us with it spinning; loops under about 0.1 ms of work run
 * serially (par_worth()). */
#ifndef GLINT_PAR_H
#define GLINT_PAR_H

#include <stddef.h>

#define PAR_MAX_THREADS 16
#define PAR_SPIN_US 200

typedef void (*par_fn)(void *ctx, int task);

/* Threads a par_run may use (the caller included), >= 1. */
int par_threads(void);

/* Run tasks 0..ntasks-1 (ntasks <= 0: nothing). */
void par_run(int ntasks, par_fn fn, void *ctx);

/* Background work (a measurement no one waits for) on the calling thread:
 * while on, this thread's par_run runs every task itself and never takes
 * the pool, which stays free for the fits people wait for.  Per thread. */
void par_background(int on);

/* Wake the pool's workers to spin (PAR_SPIN_US) without a run: a caller
 * that is about to start a run after some serial work (a fit, before its
 * first pass over the samples) calls it first, so that the wake-up
 * overlaps that work.  Nothing for a background thread or one thread. */
void par_warm(void);

/* BLAS on the calling thread only, for a process whose own loops are
 * parallel (par_run) and whose BLAS calls are small: OpenBLAS's idle
 * threads spin (sched_yield) for about 0.1 s after its start and after
 * each call it splits, taking a core from whatever runs next (measured:
 * the first fit after glintd starts, 64-72 ms with them, 46-47 ms
 * without).  Calls openblas_set_num_threads(1) when the process's BLAS is
 * OpenBLAS and the environment does not say otherwise
 * (OPENBLAS_NUM_THREADS, GOTO_NUM_THREADS, OMP_NUM_THREADS win).  Returns
 * 1 if it did. */
int par_blas_single(void);

/* Whether `work` units (e.g. samples times channels) are enough to be
 * worth waking the pool for (at least PAR_MIN_WORK). */
#define PAR_MIN_WORK 60000
static inline int par_worth(size_t work)
{
    return work >= PAR_MIN_WORK && par_threads() > 1;
}

#endif
