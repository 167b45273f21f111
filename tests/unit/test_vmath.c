/* test_vmath: the vectorized log and exp (core/base/vmath.c) against libm, over
 * the whole double range and at the special values, and the worker pool
 * (core/base/par.c) and the streamed passes of a fit, whose results must not
 * depend on the number of threads. */
#include <cblas.h>
#include <dirent.h>
#include <dlfcn.h>
#include <float.h>
#include <stdlib.h>
#include <pthread.h>
#include <stdatomic.h>
#include <time.h>
#include <unistd.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "hf.h"
#include "samples.h"
#include "fit_case.h"
#include "par.h"
#include "vmath.h"

/* distance in units in the last place of b */
static double ulps(double a, double b)
{
    double u;
    if (a == b)
        return 0.0;
    u = nextafter(fabs(b), INFINITY) - fabs(b);
    return fabs(a - b) / u;
}

static uint64_t rng = 88172645463325252ULL;
static double uniform(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

TEST(log_within_one_ulp_everywhere)
{
    enum { N = 1 << 20 };
    double *x = malloc(N * sizeof *x), *y = malloc(N * sizeof *y), worst = 0.0, at = 0.0;
    ASSERT(x && y);
    for (int i = 0; i < N; i++) {
        /* a quarter each: the whole exponent range, near 1, [0.5, 2), 8-bit levels */
        switch (i & 3) {
        case 0: x[i] = exp((uniform() - 0.5) * 1415.0); break;
        case 1: x[i] = 1.0 + (uniform() - 0.5) * 1e-6; break;
        case 2: x[i] = 0.5 + 1.5 * uniform(); break;
        default: x[i] = (double)((i >> 2) % 256) / 255.0 + 1e-3; break;
        }
        if (!(x[i] >= DBL_MIN && x[i] <= DBL_MAX))
            x[i] = 1.5;
    }
    vmath_log(x, y, N);
    for (int i = 0; i < N; i++) {
        double e = ulps(y[i], log(x[i]));
        if (e > worst) {
            worst = e;
            at = x[i];
        }
    }
    printf("  %s: worst %.2f ulp (at x = %.17g)\n", vmath_impl(), worst, at);
    free(x);
    free(y);
    ASSERT_MSG(worst <= 1.0, "log off by %.2f ulp at %.17g", worst, at);
}

TEST(log_special_values_as_libm)
{
    /* every position in a group of four, so the vector path meets each */
    const double sp[] = {0.0, -0.0, -1.0, INFINITY, -INFINITY, NAN, DBL_MIN, DBL_MAX,
                         DBL_TRUE_MIN, 1e-310, 1.0, 2.0, 0.5, M_SQRT2, M_SQRT1_2, 1e-3};
    enum { NS = sizeof sp / sizeof sp[0] };
    for (int shift = 0; shift < 4; shift++) {
        double x[NS + 4], y[NS + 4];
        for (int i = 0; i < NS + 4; i++)
            x[i] = i < shift ? 1.25 : sp[(i - shift) % NS];
        vmath_log(x, y, NS + 4);
        for (int i = 0; i < NS + 4; i++) {
            double r = log(x[i]);
            if (isnan(r))
                ASSERT_MSG(isnan(y[i]), "log(%g) = %g, not NaN", x[i], y[i]);
            else
                ASSERT_MSG(y[i] == r || ulps(y[i], r) <= 1.0, "log(%.17g) = %.17g, libm %.17g",
                           x[i], y[i], r);
        }
    }
    {
        double one = 1.0, z;
        vmath_log(&one, &z, 1);
        ASSERT(z == 0.0);
    }
}

TEST(log_map3_as_the_scalar_mapping)
{
    /* the fused mapping against its definition, for the three mappings,
     * with values below the floor, negative, NaN and inf mixed in, at
     * lengths that are and are not multiples of the vector step (12) */
    enum { N = 3 * 1001 };
    static double in[N], out[N];
    const double offs[3][3] = {{0.0, 0.0, 0.0}, {0.1, 0.1, 0.1}, {1.2, 0.9, 3.5}};
    const double signs[3] = {1.0, 1.0, -1.0};
    const double eps = 1e-3;
    for (int i = 0; i < N; i++) {
        double u = uniform();
        in[i] = u < 0.05 ? -u : u < 0.1 ? 1e-5 * u : u < 0.12 ? 0.0 : 3.0 * u;
    }
    for (int mk = 0; mk < 3; mk++)
        for (int len = 3; len <= N; len += len < 48 ? 3 : 999) {
            long cl[3] = {0, 0, 0}, want[3] = {0, 0, 0};
            int bad = vmath_log_map3(in, out, (size_t)len, offs[mk], signs[mk], eps, cl);
            ASSERT(bad == 0);
            for (int j = 0; j < len; j++) {
                double arg = offs[mk][j % 3] + signs[mk] * in[j];
                if (!(arg > eps)) {
                    arg = eps;
                    want[j % 3]++;
                }
                ASSERT_MSG(ulps(out[j], log(arg)) <= 1.0, "map %d len %d value %d: %.17g, %.17g",
                           mk, len, j, out[j], log(arg));
            }
            for (int c = 0; c < 3; c++)
                ASSERT_EQ(cl[c], want[c]);
        }
    /* a non-finite value anywhere is reported, and floored like the rest */
    for (int at = 0; at < 30; at++) {
        long cl[3] = {0, 0, 0};
        double save = in[at];
        in[at] = at % 2 ? NAN : INFINITY;
        ASSERT(vmath_log_map3(in, out, 30, offs[0], 1.0, eps, cl) == 1);
        ASSERT(isfinite(out[at]) || in[at] == INFINITY);
        in[at] = save;
    }
    {
        /* lanes outside the vector log's range (a subnormal floor, +inf)
         * take libm's log, their neighbours the vector log's */
        const double zero[3] = {0.0, 0.0, 0.0}, tiny = 1e-310;
        double x[48], y[48];
        long cl[3] = {0, 0, 0};
        for (int i = 0; i < 48; i++)
            x[i] = i % 11 == 3 ? 0.0 : i % 13 == 5 ? INFINITY : 0.25 + 0.1 * i;
        ASSERT(vmath_log_map3(x, y, 48, zero, 1.0, tiny, cl) == 1);
        for (int i = 0; i < 48; i++) {
            double arg = x[i] > tiny ? x[i] : tiny;
            if (arg == tiny || isinf(arg))
                ASSERT_MSG(y[i] == log(arg), "value %d: %.17g, libm %.17g", i, y[i], log(arg));
            else
                ASSERT_MSG(ulps(y[i], log(arg)) <= 1.0, "value %d: %.17g", i, y[i]);
        }
    }
}

static double ulpsf(float a, float b)
{
    float u;
    if (a == b)
        return 0.0;
    u = nextafterf(fabsf(b), INFINITY) - fabsf(b);
    return fabs((double)a - (double)b) / u;
}

TEST(logf_map3_as_the_scalar_mapping)
{
    enum { N = 3 * 1001 };
    static float in[N], out[N];
    const float offs[3][3] = {{0.0f, 0.0f, 0.0f}, {0.1f, 0.1f, 0.1f}, {1.2f, 0.9f, 3.5f}};
    const float signs[3] = {1.0f, 1.0f, -1.0f};
    const float eps = 1e-3f;
    double worst = 0.0;
    for (int i = 0; i < N; i++) {
        double u = uniform();
        in[i] = (float)(u < 0.05 ? -u : u < 0.1 ? 1e-5 * u : u < 0.12 ? 0.0 : 3.0 * u);
    }
    for (int mk = 0; mk < 3; mk++)
        for (int len = 3; len <= N; len += len < 72 ? 3 : 999) {
            long cl[3] = {0, 0, 0}, want[3] = {0, 0, 0};
            ASSERT(vmath_logf_map3(in, out, (size_t)len, offs[mk], signs[mk], eps, cl) == 0);
            for (int j = 0; j < len; j++) {
                float arg = offs[mk][j % 3] + signs[mk] * in[j];
                if (!(arg > eps)) {
                    arg = eps;
                    want[j % 3]++;
                }
                if (ulpsf(out[j], logf(arg)) > worst)
                    worst = ulpsf(out[j], logf(arg));
                ASSERT_MSG(ulpsf(out[j], logf(arg)) <= 1.0, "map %d value %d: %.9g, %.9g", mk,
                           j, out[j], logf(arg));
            }
            for (int c = 0; c < 3; c++)
                ASSERT_EQ(cl[c], want[c]);
        }
    {
        /* every float in [0.5, 2) at a stride, and the exponent range */
        static float x[1 << 16], y[1 << 16];
        long cl[3] = {0, 0, 0};
        const float zero[3] = {0.0f, 0.0f, 0.0f};
        for (int i = 0; i < (1 << 16); i++)
            x[i] = i < (1 << 15) ? 0.5f + 1.5f * (float)i / (1 << 15)
                                 : (float)exp((uniform() - 0.5) * 170.0);
        ASSERT(vmath_logf_map3(x, y, 3 * ((1 << 16) / 3), zero, 1.0f, 1e-30f, cl) == 0);
        for (int i = 0; i < 3 * ((1 << 16) / 3); i++) {
            float r = logf(x[i] > 1e-30f ? x[i] : 1e-30f);
            if (ulpsf(y[i], r) > worst)
                worst = ulpsf(y[i], r);
        }
    }
    printf("  logf: worst %.2f ulp\n", worst);
    ASSERT(worst <= 1.0);
    for (int at = 0; at < 48; at++) {
        long cl[3] = {0, 0, 0};
        float save = in[at];
        in[at] = at % 2 ? NAN : INFINITY;
        ASSERT(vmath_logf_map3(in, out, 48, offs[0], 1.0f, eps, cl) == 1);
        in[at] = save;
    }
    {
        /* lanes outside the vector logf's range (a subnormal floor, +inf)
         * take libm's logf, their neighbours the vector logf's */
        const float zero[3] = {0.0f, 0.0f, 0.0f}, tiny = 1e-40f;
        float x[96], y[96];
        long cl[3] = {0, 0, 0};
        for (int i = 0; i < 96; i++)
            x[i] = i % 11 == 3 ? 0.0f : i % 13 == 5 ? INFINITY : 0.25f + 0.1f * (float)i;
        ASSERT(vmath_logf_map3(x, y, 96, zero, 1.0f, tiny, cl) == 1);
        for (int i = 0; i < 96; i++) {
            float arg = x[i] > tiny ? x[i] : tiny;
            if (arg == tiny || isinf(arg))
                ASSERT_MSG(y[i] == logf(arg), "value %d: %.9g, libm %.9g", i, y[i], logf(arg));
            else
                ASSERT_MSG(ulpsf(y[i], logf(arg)) <= 1.0, "value %d: %.9g", i, y[i]);
        }
    }
}

/* The AVX-512 and AVX2 paths of the fused mappings give the same bits,
 * value for value, whatever else shares their vector (a lane outside the
 * vector log's range takes libm's log alone, not its neighbours). */
TEST(log_map3_same_bits_on_avx2_and_avx512)
{
    enum { N = 3 * 20011 };
    static double in[N], o512[N], o2[N];
    static float fin[N], f512[N], f2[N];
    const double offs[2][3] = {{0.0, 0.0, 0.0}, {1.2, 0.9, 3.5}};
    const double signs[2] = {1.0, -1.0};
    const char *impl512, *impl2;
    long diff = 0, fdiff = 0;
    for (int i = 0; i < N; i++) {
        double u = uniform();
        in[i] = u < 0.002 ? INFINITY : u < 0.004 ? NAN : u < 0.05 ? -u
                : exp((uniform() - 0.5) * 200.0);
        fin[i] = (float)in[i];
    }
    ASSERT(vmath_limit("avx512") == 0);
    impl512 = vmath_impl();
    ASSERT(vmath_limit("avx2") == 0);
    impl2 = vmath_impl();
    printf("  %s against %s\n", impl512, impl2);
    for (int mk = 0; mk < 2; mk++) {
        long c512[3] = {0, 0, 0}, c2[3] = {0, 0, 0}, g512[3] = {0, 0, 0}, g2[3] = {0, 0, 0};
        const float fo[3] = {(float)offs[mk][0], (float)offs[mk][1], (float)offs[mk][2]};
        int r512, r2, s512, s2;
        vmath_limit("avx512");
        r512 = vmath_log_map3(in, o512, N, offs[mk], signs[mk], 1e-6, c512);
        s512 = vmath_logf_map3(fin, f512, N, fo, (float)signs[mk], 1e-6f, g512);
        vmath_limit("avx2");
        r2 = vmath_log_map3(in, o2, N, offs[mk], signs[mk], 1e-6, c2);
        s2 = vmath_logf_map3(fin, f2, N, fo, (float)signs[mk], 1e-6f, g2);
        ASSERT(r512 == 1 && r2 == 1 && s512 == 1 && s2 == 1);
        for (int c = 0; c < 3; c++) {
            ASSERT_EQ(c512[c], c2[c]);
            ASSERT_EQ(g512[c], g2[c]);
        }
        for (int i = 0; i < N; i++) {
            diff += memcmp(&o512[i], &o2[i], sizeof o2[i]) != 0;
            fdiff += memcmp(&f512[i], &f2[i], sizeof f2[i]) != 0;
        }
    }
    vmath_limit(NULL);
    ASSERT_MSG(diff == 0 && fdiff == 0, "%ld doubles and %ld floats differ", diff, fdiff);
    ASSERT(vmath_limit("avx9") == -1);
}

/* vmath_log_map3_f32 against its definition: the floats widened into a
 * buffer and vmath_log_map3 over it, the same bits, clamped counts and
 * return, on every instruction set the CPU has.  The values mix every
 * class (NaN, +-inf, +-0, subnormal and the largest floats, negatives,
 * values at and around the floor); the mappings are the plain log (with a
 * -0 offset too), an offset and a sign of -1, and an offset so large that
 * every argument is inf; the floors normal and subnormal; the lengths
 * leave every tail of the 24- and 12-value steps. */
TEST(log_map3_f32_as_the_widened_mapping)
{
    enum { N = 3 * 4001 };
    static float in[N];
    static double wide[N], want[N], got[N];
    const double offs[5][3] = {{0.0, 0.0, 0.0},
                               {-0.0, 0.0, -0.0},
                               {1.2, 0.9, 3.5},
                               {0.1, 0.1, 0.1},
                               {INFINITY, 1.0, 2.0}};
    const double signs[5] = {1.0, 1.0, -1.0, 1.0, 1.0};
    const double floors[3] = {1e-6, (double)FLT_MIN, 1e-310};
    const char *caps[3] = {"avx512", "avx2", "sse2"};
    long differ = 0, runs = 0;
    for (int i = 0; i < N; i++) {
        double u = uniform();
        in[i] = u < 0.002   ? NAN
                : u < 0.004 ? INFINITY
                : u < 0.006 ? -INFINITY
                : u < 0.010 ? 0.0f
                : u < 0.012 ? -0.0f
                : u < 0.016 ? FLT_MAX
                : u < 0.020 ? 1e-40f /* subnormal float */
                : u < 0.040 ? (float)(1e-6 * (0.5 + uniform()))
                : u < 0.080 ? (float)-u
                            : (float)exp((uniform() - 0.5) * 60.0);
    }
    /* one run of 240 with no special value at all: the fast steps alone */
    for (int i = 0; i < 240; i++)
        in[i] = (float)(0.01 + i * 0.37);
    for (int c = 0; c < 3; c++) {
        ASSERT(vmath_limit(caps[c]) == 0);
        for (int mk = 0; mk < 5; mk++)
            for (int fk = 0; fk < 3; fk++)
                for (int len = 0; len <= N; len += len < 96 ? 3 : len < 240 ? 144 : 3 * 1253) {
                    long cw[3] = {0, 0, 0}, cg[3] = {0, 0, 0};
                    int rw, rg;
                    for (int j = 0; j < len; j++)
                        wide[j] = in[j];
                    rw = vmath_log_map3(wide, want, (size_t)len, offs[mk], signs[mk],
                                        floors[fk], cw);
                    rg = vmath_log_map3_f32(in, got, (size_t)len, offs[mk], signs[mk],
                                            floors[fk], cg);
                    ASSERT_MSG(rw == rg, "%s map %d floor %d len %d: returned %d, want %d",
                               caps[c], mk, fk, len, rg, rw);
                    for (int k = 0; k < 3; k++)
                        ASSERT_EQ(cg[k], cw[k]);
                    for (int j = 0; j < len; j++)
                        differ += memcmp(&got[j], &want[j], sizeof got[j]) != 0;
                    runs++;
                }
    }
    vmath_limit(NULL);
    ASSERT_MSG(differ == 0, "%ld values differ over %ld runs", differ, runs);
    for (int c = 0; c < 3; c++) {
        /* one non-finite value alone, at every place of two steps, is
         * reported (each class), and floored like its definition */
        const float bad[4] = {NAN, -NAN, INFINITY, -INFINITY};
        float x[48];
        vmath_limit(caps[c]);
        for (int at = 0; at < 48; at++)
            for (int b = 0; b < 4; b++) {
                long cw[3] = {0, 0, 0}, cg[3] = {0, 0, 0};
                for (int j = 0; j < 48; j++)
                    x[j] = 0.5f + 0.25f * (float)j;
                x[at] = bad[b];
                for (int j = 0; j < 48; j++)
                    wide[j] = x[j];
                ASSERT(vmath_log_map3(wide, want, 48, offs[0], 1.0, 1e-6, cw) == 1);
                ASSERT_MSG(vmath_log_map3_f32(x, got, 48, offs[0], 1.0, 1e-6, cg) == 1,
                           "%s: value %d class %d not reported", caps[c], at, b);
                ASSERT(memcmp(got, want, 48 * sizeof *got) == 0);
                ASSERT(memcmp(cg, cw, sizeof cg) == 0);
            }
    }
    vmath_limit(NULL);
    {
        /* and the fast steps give what they should: the log of the value */
        long cl[3] = {0, 0, 0};
        ASSERT(vmath_log_map3_f32(in, got, 240, offs[0], 1.0, 1e-6, cl) == 0);
        for (int j = 0; j < 240; j++)
            ASSERT_MSG(ulps(got[j], log((double)in[j])) <= 1.0, "value %d", j);
        ASSERT(cl[0] + cl[1] + cl[2] == 0);
    }
}

/* vmath_exp (libmvec) on AVX-512 and on AVX2: the same bits, over the
 * range the diagnostics use (below 700), past it, and at lengths that
 * leave a tail for the narrower loop. */
TEST(exp_same_bits_on_avx2_and_avx512)
{
    enum { N = 100003 };
    static double x[N], e512[N], e2[N];
    long diff = 0;
    for (int i = 0; i < N; i++) {
        double u = uniform();
        x[i] = u < 0.001 ? INFINITY : u < 0.002 ? -INFINITY : u < 0.003 ? NAN
               : u < 0.5 ? (uniform() - 0.5) * 1500.0 : (uniform() - 0.5) * 8.0;
    }
    for (int len = N - 7; len <= N; len += 7) {
        ASSERT(vmath_limit("avx512") == 0);
        vmath_exp(x, e512, (size_t)len);
        ASSERT(vmath_limit("avx2") == 0);
        vmath_exp(x, e2, (size_t)len);
        for (int i = 0; i < len; i++)
            diff += memcmp(&e512[i], &e2[i], sizeof e2[i]) != 0;
    }
    vmath_limit(NULL);
    ASSERT_MSG(diff == 0, "%ld values differ", diff);
}

TEST(exp_matches_libm)
{
    enum { N = 4096 };
    double x[N], y[N], worst = 0.0;
    for (int i = 0; i < N; i++)
        x[i] = (uniform() - 0.5) * 1400.0;
    vmath_exp(x, y, N);
    for (int i = 0; i < N; i++) {
        double r = exp(x[i]);
        if (r > 0.0 && r < INFINITY && ulps(y[i], r) > worst)
            worst = ulps(y[i], r);
    }
    ASSERT_MSG(worst <= 4.0, "exp off by %.2f ulp", worst);
}

typedef struct sum_ctx {
    long n;
    double part[64];
    int calls[64];
} sum_ctx;

static void sum_task(void *ctx, int t)
{
    sum_ctx *s = ctx;
    double acc = 0.0;
    for (long i = t; i < s->n; i += 64)
        acc += sqrt((double)i);
    s->part[t] = acc;
    s->calls[t]++;
}

static void nested_task(void *ctx, int t)
{
    sum_ctx *inner = (sum_ctx *)ctx + 1 + t;
    par_run(64, sum_task, inner); /* runs serially inside a task */
}

TEST(pool_runs_every_task_once)
{
    sum_ctx s, many[3];
    memset(&s, 0, sizeof s);
    s.n = 1 << 20;
    par_run(64, sum_task, &s);
    for (int t = 0; t < 64; t++)
        ASSERT_EQ(s.calls[t], 1);
    /* again: the pool is reused */
    par_run(64, sum_task, &s);
    for (int t = 0; t < 64; t++)
        ASSERT_EQ(s.calls[t], 2);
    /* a run from inside a task */
    memset(many, 0, sizeof many);
    many[1].n = many[2].n = 1000;
    par_run(2, nested_task, many);
    for (int k = 1; k < 3; k++)
        for (int t = 0; t < 64; t++)
            ASSERT_EQ(many[k].calls[t], 1);
    par_run(0, sum_task, &s); /* nothing */
    ASSERT(par_threads() >= 1);
}

/* A thread marked par_background runs its tasks itself and leaves the pool
 * free: a run started meanwhile on another thread gets the pool's worker.
 * (With the mark ignored, the background run holds the pool, the second
 * run is serial, and its first task waits out the 20 s cap alone.) */
typedef struct meet_ctx {
    pthread_t who[8];
    atomic_int arrived, started, release;
} meet_ctx;

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static void record_task(void *ctx, int t)
{
    ((meet_ctx *)ctx)->who[t] = pthread_self();
}

static void block_task(void *ctx, int t)
{
    meet_ctx *m = ctx;
    double t0 = now_s();
    (void)t;
    atomic_fetch_add(&m->started, 1);
    while (!atomic_load(&m->release) && now_s() - t0 < 20.0)
        usleep(200);
}

/* each task waits (at most 20 s) until both tasks have begun */
static void meet_task(void *ctx, int t)
{
    meet_ctx *m = ctx;
    double t0 = now_s();
    m->who[t] = pthread_self();
    atomic_fetch_add(&m->arrived, 1);
    while (atomic_load(&m->arrived) < 2 && now_s() - t0 < 20.0)
        usleep(200);
}

static void *background_run(void *ctx)
{
    par_background(1);
    par_run(2, block_task, ctx);
    par_background(0);
    return NULL;
}

TEST(background_runs_leave_the_pool_free)
{
    meet_ctx bg, fg, own;
    pthread_t th;
    double t0;

    if (par_threads() < 2) {
        printf("  one thread here (GLINT_THREADS or one CPU): nothing to check\n");
        return;
    }
    memset(&own, 0, sizeof own);
    par_background(1);
    par_run(8, record_task, &own);
    par_background(0);
    for (int t = 0; t < 8; t++)
        ASSERT(pthread_equal(own.who[t], pthread_self()));

    memset(&bg, 0, sizeof bg);
    memset(&fg, 0, sizeof fg);
    ASSERT_EQ(pthread_create(&th, NULL, background_run, &bg), 0);
    for (t0 = now_s(); atomic_load(&bg.started) == 0 && now_s() - t0 < 20.0;)
        usleep(200);
    ASSERT_EQ(atomic_load(&bg.started), 1); /* its first task, on its own thread */
    par_run(2, meet_task, &fg);
    atomic_store(&bg.release, 1);
    pthread_join(th, NULL);
    ASSERT_EQ(atomic_load(&fg.arrived), 2);
    ASSERT(!pthread_equal(fg.who[0], fg.who[1])); /* the worker took one */
    ASSERT_EQ(atomic_load(&bg.started), 2);        /* and the background ran both */
}

typedef struct fit_ctx {
    const fit_case *fc;
    hf_factors fac;
    hf_fit_stats st;
    int rc;
} fit_ctx;

static void fit_in_task(void *ctx, int t)
{
    fit_ctx *f = ctx;
    const fit_case *fc = f->fc;
    if (t == 0) /* the pool is held by this run: the fit's own runs go serial */
        f->rc = hf_fit(&fc->d, &fc->op, &fc->map, HF_MODEL_RADIANCE, fc->rgb, &f->fac, &f->st,
                       NULL);
}

TEST(fit_same_bits_on_any_thread_count)
{
    /* the streamed passes split the samples into chunks fixed by their
     * count, so a fit on the pool and one with every chunk on one thread
     * (what a busy pool gives) are the same bits */
    fit_case fc;
    hf_factors a;
    hf_fit_stats sa;
    fit_ctx f;

    ASSERT_OK(fit_case_make(&fc, 100, 32));
    ASSERT(fc.s.n > PAR_MIN_WORK / 3 && fc.s.n > HF_DIAG_SAMPLES / 2);
    ASSERT_OK(hf_fit(&fc.d, &fc.op, &fc.map, HF_MODEL_RADIANCE, fc.rgb, &a, &sa, NULL));
    memset(&f, 0, sizeof f);
    f.fc = &fc;
    f.rc = -1;
    par_run(2, fit_in_task, &f);
    ASSERT_OK(f.rc);
    ASSERT(memcmp(a.logf, f.fac.logf, (size_t)9 * fc.d.res * sizeof *a.logf) == 0);
    ASSERT(sa.rms == f.st.rms && sa.log_residual == f.st.log_residual);
    ASSERT(sa.diag_samples == fc.s.n && sa.diag_stride == 1 && sa.diag_runs == 1);
    hf_factors_free(&a);
    hf_factors_free(&f.fac);
    fit_case_free(&fc);
}

TEST(diagnostics_subsample_above_the_limit)
{
    /* more samples than HF_DIAG_SAMPLES: runs of consecutive samples,
     * counted and labelled */
    fit_case fc;
    hf_factors a;
    hf_fit_stats st;

    ASSERT_OK(fit_case_make(&fc, 128, 16));
    ASSERT(fc.s.n > HF_DIAG_SAMPLES);
    ASSERT_OK(hf_fit(&fc.d, &fc.op, &fc.map, HF_MODEL_RADIANCE, fc.rgb, &a, &st, NULL));
    ASSERT_EQ(st.diag_runs, HF_DIAG_SAMPLES / HF_DIAG_RUN);
    ASSERT_EQ(st.diag_stride, fc.s.n / st.diag_runs);
    ASSERT_EQ(st.diag_samples, HF_DIAG_SAMPLES);
    ASSERT(st.diag_stride >= HF_DIAG_RUN); /* the runs do not overlap */
    {
        /* the figures are those of exactly these samples: the maximum error
         * over the runs, recomputed here, against the fit's */
        float *rec = malloc((size_t)3 * fc.s.n * sizeof *rec);
        double mx = 0.0, se = 0.0, sl = 0.0, rms, lres;
        ASSERT(rec);
        hf_factors_eval_design(&a, &fc.d, rec);
        for (long i = 0; i < 3L * fc.s.n; i++) {
            double e = (double)rec[i] - fc.rgb[i];
            /* the log residual from the reconstruction as stored (float):
             * within about 1e-7 of the fit's, which is before rounding */
            double l = log((double)rec[i]) - log(fmax(fc.rgb[i], fc.map.eps));
            long smp = i / 3, k = smp / st.diag_stride;
            if (k < st.diag_runs && smp - k * st.diag_stride < HF_DIAG_RUN) {
                se += e * e;
                sl += l * l;
                mx = fabs(e) > mx ? fabs(e) : mx;
            }
        }
        free(rec);
        rms = sqrt(se / (3.0 * HF_DIAG_SAMPLES));
        lres = sqrt(sl / (3.0 * HF_DIAG_SAMPLES));
        printf("  over the runs, recomputed: RMS %.12g (the fit's %.12g), max %.9g (%.9g), "
               "log residual %.9g (%.9g)\n",
               rms, st.rms, mx, st.max_abs, lres, st.log_residual);
        ASSERT_NEAR(st.rms / rms, 1.0, 1e-9);
        ASSERT(mx == st.max_abs);
        ASSERT_NEAR(st.log_residual / lres, 1.0, 1e-6);
    }
    {
        /* the estimate against the exact RMS over every sample */
        float *rec = malloc((size_t)3 * fc.s.n * sizeof *rec);
        double se = 0.0, exact;
        ASSERT(rec);
        hf_factors_eval_design(&a, &fc.d, rec);
        for (long i = 0; i < 3L * fc.s.n; i++)
            se += ((double)rec[i] - fc.rgb[i]) * ((double)rec[i] - fc.rgb[i]);
        exact = sqrt(se / (3.0 * fc.s.n));
        free(rec);
        printf("  RMS over %ld of %d samples %.6f, over all %.6f\n", st.diag_samples, fc.s.n,
               st.rms, exact);
        ASSERT_NEAR(st.rms / exact, 1.0, 0.02);
    }
    hf_factors_free(&a);
    fit_case_free(&fc);
}

/* Threads of this process now. */
static int task_count(void)
{
    DIR *d = opendir("/proc/self/task");
    struct dirent *e;
    int n = 0;
    if (!d)
        return -1;
    while ((e = readdir(d)))
        n += e->d_name[0] != '.';
    closedir(d);
    return n;
}

/* par_blas_single: OpenBLAS to one thread and its idle threads stopped,
 * unless the environment names a count; BLAS still right after. */
TEST(blas_can_be_kept_on_the_calling_thread)
{
    int (*get)(void);
    int before, threads;
    double a[64 * 64], b[64 * 64], c[64 * 64], worst = 0.0;

    *(void **)&get = dlsym(RTLD_DEFAULT, "openblas_get_num_threads");
    if (!get) {
        printf("  (this BLAS is not OpenBLAS: nothing to check)\n");
        ASSERT_EQ(par_blas_single(), 0);
        return;
    }
    threads = get();
    before = task_count();
    ASSERT_OK(setenv("OPENBLAS_NUM_THREADS", "3", 1));
    ASSERT_EQ(par_blas_single(), 0); /* the environment's word wins */
    ASSERT_EQ(get(), threads);
    ASSERT_OK(unsetenv("OPENBLAS_NUM_THREADS"));
    ASSERT_OK(unsetenv("GOTO_NUM_THREADS"));
    ASSERT_OK(unsetenv("OMP_NUM_THREADS"));
    ASSERT_EQ(par_blas_single(), 1);
    ASSERT_EQ(get(), 1);
    /* its idle threads are gone (none were there if it started with one) */
    ASSERT_EQ(task_count(), before - (threads - 1));
    for (int i = 0; i < 64 * 64; i++) {
        a[i] = (double)((i * 7) % 13) - 6.0;
        b[i] = (double)((i * 5) % 11) - 5.0;
    }
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, 64, 64, 64, 1.0, a, 64, b, 64, 0.0,
                c, 64);
    for (int i = 0; i < 64; i++)
        for (int j = 0; j < 64; j++) {
            double want = 0.0;
            for (int k = 0; k < 64; k++)
                want += a[i * 64 + k] * b[k * 64 + j];
            worst = fmax(worst, fabs(want - c[i * 64 + j]));
        }
    ASSERT(worst == 0.0); /* small integers: exact */
    ASSERT_EQ(task_count(), before - (threads - 1)); /* and none started again */
}

TEST_LIST {
    TEST_ENTRY(log_within_one_ulp_everywhere),
    TEST_ENTRY(log_special_values_as_libm),
    TEST_ENTRY(log_map3_as_the_scalar_mapping),
    TEST_ENTRY(logf_map3_as_the_scalar_mapping),
    TEST_ENTRY(log_map3_same_bits_on_avx2_and_avx512),
    TEST_ENTRY(log_map3_f32_as_the_widened_mapping),
    TEST_ENTRY(exp_matches_libm),
    TEST_ENTRY(exp_same_bits_on_avx2_and_avx512),
    TEST_ENTRY(pool_runs_every_task_once),
    TEST_ENTRY(background_runs_leave_the_pool_free),
    TEST_ENTRY(blas_can_be_kept_on_the_calling_thread),
    TEST_ENTRY(fit_same_bits_on_any_thread_count),
    TEST_ENTRY(diagnostics_subsample_above_the_limit),
};

TEST_MAIN()
