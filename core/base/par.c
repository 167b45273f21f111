/* par.c: the worker pool of par.h. */
#include "par.h"

#include <dlfcn.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

static struct {
    pthread_mutex_t lock;
    pthread_cond_t go, done;
    int nworkers;        /* started */
    int started;         /* start attempted */
    unsigned long gen;   /* run generation (written under lock, read by spinners) */
    unsigned long warm;  /* par_warm calls */
    int open;            /* the current run still takes workers */
    int working;         /* workers inside the current run (written under
                          * lock, read by the spinning caller) */
    par_fn fn;
    void *ctx;
    int ntasks;
    atomic_int next;     /* next task to claim */
    atomic_int busy;     /* a run holds the pool */
} P = {.lock = PTHREAD_MUTEX_INITIALIZER, .go = PTHREAD_COND_INITIALIZER, .done = PTHREAD_COND_INITIALIZER};

static int nthreads = -1;
static long spin_ns = PAR_SPIN_US * 1000L;
static __thread int background;

void par_background(int on)
{
    background = on != 0;
}
static pthread_once_t threads_once = PTHREAD_ONCE_INIT;

static void threads_init(void)
{
    const char *env = getenv("GLINT_THREADS");
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    if (env && *env) {
        char *end;
        long v = strtol(env, &end, 10);
        if (*end == '\0' && v >= 1)
            n = v;
    }
    if (n < 1)
        n = 1;
    if (n > PAR_MAX_THREADS)
        n = PAR_MAX_THREADS;
    nthreads = (int)n;
    env = getenv("GLINT_POOL_SPIN_US");
    if (env && *env) {
        char *end;
        long v = strtol(env, &end, 10);
        if (*end == '\0' && v >= 0 && v <= 1000000)
            spin_ns = v * 1000L;
    }
}

int par_threads(void)
{
    pthread_once(&threads_once, threads_init);
    return nthreads;
}

static void claim_loop(par_fn fn, void *ctx, int ntasks)
{
    int t;
    while ((t = atomic_fetch_add(&P.next, 1)) < ntasks)
        fn(ctx, t);
}

static long now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1000000000L + ts.tv_nsec;
}

/* Spin, up to spin_ns, while *gen == x (gen not NULL) or while *cnt != 0;
 * the caller then checks under the lock, and sleeps if it must.  Yields
 * the CPU every few microseconds, so a spinner gives way to runnable
 * threads. */
static void spin_on(const unsigned long *gen, unsigned long x, const int *cnt)
{
    long t0 = 0;
    if (spin_ns <= 0)
        return;
    for (unsigned k = 0;; k++) {
        if (gen ? __atomic_load_n(gen, __ATOMIC_ACQUIRE) != x
                : __atomic_load_n(cnt, __ATOMIC_ACQUIRE) == 0)
            return;
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
        if ((k & 63) == 0) {
            long t = now_ns();
            if (k == 0)
                t0 = t;
            else if (t - t0 > spin_ns)
                return;
            else
                sched_yield();
        }
    }
}

static void *worker(void *arg)
{
    unsigned long seen = 0, seen_warm = 0;
    (void)arg;
    pthread_mutex_lock(&P.lock);
    for (;;) {
        par_fn fn;
        void *ctx;
        int ntasks;
        if (!(P.open && P.gen != seen)) { /* the next run may come at once */
            seen_warm = P.warm;
            pthread_mutex_unlock(&P.lock);
            spin_on(&P.gen, seen, NULL);
            pthread_mutex_lock(&P.lock);
        }
        while (!(P.open && P.gen != seen) && P.warm == seen_warm)
            pthread_cond_wait(&P.go, &P.lock);
        if (!(P.open && P.gen != seen))
            continue; /* par_warm: spin */
        seen = P.gen;
        __atomic_add_fetch(&P.working, 1, __ATOMIC_RELAXED);
        fn = P.fn;
        ctx = P.ctx;
        ntasks = P.ntasks;
        pthread_mutex_unlock(&P.lock);
        claim_loop(fn, ctx, ntasks);
        pthread_mutex_lock(&P.lock);
        if (__atomic_sub_fetch(&P.working, 1, __ATOMIC_RELEASE) == 0)
            pthread_cond_broadcast(&P.done);
    }
    return NULL;
}

/* Under P.lock.  Workers block every signal: signals go to the threads the
 * program made itself. */
static void start_workers(void)
{
    sigset_t all, old;
    P.started = 1;
    sigfillset(&all);
    pthread_sigmask(SIG_SETMASK, &all, &old);
    for (int i = 0; i < par_threads() - 1; i++) {
        pthread_t th;
        pthread_attr_t at;
        pthread_attr_init(&at);
        pthread_attr_setdetachstate(&at, PTHREAD_CREATE_DETACHED);
        if (pthread_create(&th, &at, worker, NULL) == 0)
            P.nworkers++;
        pthread_attr_destroy(&at);
    }
    pthread_sigmask(SIG_SETMASK, &old, NULL);
}

void par_run(int ntasks, par_fn fn, void *ctx)
{
    if (ntasks <= 0)
        return;
    if (ntasks == 1 || background || par_threads() == 1 || atomic_exchange(&P.busy, 1)) {
        for (int t = 0; t < ntasks; t++)
            fn(ctx, t);
        return;
    }
    pthread_mutex_lock(&P.lock);
    if (!P.started)
        start_workers();
    P.fn = fn;
    P.ctx = ctx;
    P.ntasks = ntasks;
    atomic_store(&P.next, 0);
    __atomic_store_n(&P.gen, P.gen + 1, __ATOMIC_RELEASE);
    P.open = P.nworkers > 0;
    if (P.open)
        pthread_cond_broadcast(&P.go);
    pthread_mutex_unlock(&P.lock);
    claim_loop(fn, ctx, ntasks);
    /* workers that have not woken by now are not waited for */
    pthread_mutex_lock(&P.lock);
    P.open = 0;
    if (P.working > 0) { /* a worker's last task: about to end, most often */
        pthread_mutex_unlock(&P.lock);
        spin_on(NULL, 0, &P.working);
        pthread_mutex_lock(&P.lock);
    }
    while (P.working > 0)
        pthread_cond_wait(&P.done, &P.lock);
    pthread_mutex_unlock(&P.lock);
    atomic_store(&P.busy, 0);
}

void par_warm(void)
{
    if (background || par_threads() == 1)
        return;
    pthread_mutex_lock(&P.lock);
    if (!P.started)
        start_workers();
    P.warm++;
    pthread_cond_broadcast(&P.go);
    pthread_mutex_unlock(&P.lock);
}

int par_blas_single(void)
{
    void (*set)(int);
    if (getenv("OPENBLAS_NUM_THREADS") || getenv("GOTO_NUM_THREADS") ||
        getenv("OMP_NUM_THREADS"))
        return 0;
    int (*shutdown)(void);
    /* looked up, not linked: the BLAS is whichever the system provides */
    *(void **)&set = dlsym(RTLD_DEFAULT, "openblas_set_num_threads");
    if (!set)
        return 0;
    set(1);
    /* its threads, started when it loaded, would spin out their timeout
     * first: stopped now (OpenBLAS's own shutdown, which a fork also
     * uses; one thread never starts them again) */
    *(void **)&shutdown = dlsym(RTLD_DEFAULT, "blas_thread_shutdown_");
    if (shutdown)
        shutdown();
    return 1;
}
