#include "vmath.h"

#include <math.h>

#if defined(__x86_64__) && defined(__GLIBC__) && defined(GLINT_HAVE_LIBMVEC)
#include <immintrin.h>

/* glibc libmvec vector variants (x86-64 vector ABI names). */
__m128d _ZGVbN2v_log(__m128d x);
__m128d _ZGVbN2v_exp(__m128d x);
__m256d _ZGVdN4v_log(__m256d x);
__m256d _ZGVdN4v_exp(__m256d x);

__attribute__((target("avx2"))) static void log_avx2(const double *in, double *out, size_t n)
{
    size_t i = 0;
    for (; i + 4 <= n; i += 4)
        _mm256_storeu_pd(out + i, _ZGVdN4v_log(_mm256_loadu_pd(in + i)));
    for (; i < n; i++)
        out[i] = log(in[i]);
}

__attribute__((target("avx2"))) static void exp_avx2(const double *in, double *out, size_t n)
{
    size_t i = 0;
    for (; i + 4 <= n; i += 4)
        _mm256_storeu_pd(out + i, _ZGVdN4v_exp(_mm256_loadu_pd(in + i)));
    for (; i < n; i++)
        out[i] = exp(in[i]);
}

static void log_sse2(const double *in, double *out, size_t n)
{
    size_t i = 0;
    for (; i + 2 <= n; i += 2)
        _mm_storeu_pd(out + i, _ZGVbN2v_log(_mm_loadu_pd(in + i)));
    for (; i < n; i++)
        out[i] = log(in[i]);
}

static void exp_sse2(const double *in, double *out, size_t n)
{
    size_t i = 0;
    for (; i + 2 <= n; i += 2)
        _mm_storeu_pd(out + i, _ZGVbN2v_exp(_mm_loadu_pd(in + i)));
    for (; i < n; i++)
        out[i] = exp(in[i]);
}

static int have_avx2(void)
{
    static int v = -1;
    if (v < 0) {
        __builtin_cpu_init();
        v = __builtin_cpu_supports("avx2") ? 1 : 0;
    }
    return v;
}

void vmath_log(const double *in, double *out, size_t n)
{
    if (have_avx2())
        log_avx2(in, out, n);
    else
        log_sse2(in, out, n);
}

void vmath_exp(const double *in, double *out, size_t n)
{
    if (have_avx2())
        exp_avx2(in, out, n);
    else
        exp_sse2(in, out, n);
}

const char *vmath_impl(void)
{
    return have_avx2() ? "libmvec-avx2" : "libmvec-sse2";
}

#else

void vmath_log(const double *in, double *out, size_t n)
{
    for (size_t i = 0; i < n; i++)
        out[i] = log(in[i]);
}

void vmath_exp(const double *in, double *out, size_t n)
{
    for (size_t i = 0; i < n; i++)
        out[i] = exp(in[i]);
}

const char *vmath_impl(void)
{
    return "libm";
}

#endif
