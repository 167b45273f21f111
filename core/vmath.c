#include "vmath.h"

#include <math.h>
#include <string.h>

#if defined(__x86_64__) && defined(__GLIBC__) && defined(GLINT_HAVE_LIBMVEC)
#include <immintrin.h>

/* glibc libmvec vector variants (x86-64 vector ABI names). */
__m128d _ZGVbN2v_log(__m128d x);
__m128d _ZGVbN2v_exp(__m128d x);
/* the AVX2 variants take and return ymm registers: declared for avx2 code */
__attribute__((target("avx2"))) __m256d _ZGVdN4v_log(__m256d x);
__attribute__((target("avx2"))) __m256d _ZGVdN4v_exp(__m256d x);

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

static int have_fma(void)
{
    static int v = -1;
    if (v < 0) {
        __builtin_cpu_init();
        v = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") ? 1 : 0;
    }
    return v;
}

/* log on AVX2 + FMA, four lanes at a time: x = 2^k (1 + f) with 1 + f in
 * [sqrt(2)/2, sqrt(2)), s = f / (2 + f), log(1 + f) = f - f^2/2 + s (f^2/2
 * + R(s^2)), R the degree-7 minimax polynomial of fdlibm's e_log.c (its
 * coefficients Lg1..Lg7, evaluated in two halves for parallelism), k log 2
 * added in two parts, with fused multiply-adds (contraction is on for these
 * functions alone).  Within 1 ulp of libm's log over [DBL_MIN, DBL_MAX]
 * (tests/unit/test_vmath.c); a lane outside the normal positive range (0,
 * subnormal, negative, inf, NaN) sends its group of four to libm.  About
 * 1.5 times the throughput of libmvec's _ZGVdN4v_log here (bench_hf
 * --warm prints which is in use). */
typedef double v4d __attribute__((vector_size(32)));
typedef long long v4l __attribute__((vector_size(32)));
typedef unsigned long long v4u __attribute__((vector_size(32)));

__attribute__((target("avx2,fma"), always_inline, optimize("fp-contract=fast"))) static inline v4d
log4(v4d x)
{
    const double Lg1 = 6.666666666666735130e-01, Lg2 = 3.999999999940941908e-01,
                 Lg3 = 2.857142874366239149e-01, Lg4 = 2.222219843214978396e-01,
                 Lg5 = 1.818357216161805012e-01, Lg6 = 1.531383769920937332e-01,
                 Lg7 = 1.479819860511658591e-01, ln2_hi = 6.93147180369123816490e-01,
                 ln2_lo = 1.90821492927058770002e-10;
    const v4l expmask = {(long long)0xfff0000000000000ULL, (long long)0xfff0000000000000ULL,
                         (long long)0xfff0000000000000ULL, (long long)0xfff0000000000000ULL};
    v4l u = (v4l)x;
    /* the exponent k such that x / 2^k lies in [sqrt(2)/2, sqrt(2)) */
    v4l tmp = u - 0x3fe6a09e667f3bcdLL;
    v4u k12 = (((v4u)tmp) >> 52) + 2048;                  /* k + 2048, 12 bits */
    v4d k = (v4d)((v4l)(k12 & 4095) | 0x4330000000000000LL) - (4503599627370496.0 + 2048.0);
    v4d f = (v4d)(u - (tmp & expmask)) - 1.0;
    v4d s = f / (2.0 + f), z = s * s, w = z * z;
    v4d r = w * (Lg2 + w * (Lg4 + w * Lg6)) + z * (Lg1 + w * (Lg3 + w * (Lg5 + w * Lg7)));
    v4d hfsq = 0.5 * f * f;
    return k * ln2_hi - ((hfsq - (s * (hfsq + r) + k * ln2_lo)) - f);
}

__attribute__((target("avx2,fma"), optimize("fp-contract=fast"))) static void log_fma(const double *in, double *out, size_t n)
{
    size_t i = 0;
    for (; i + 4 <= n; i += 4) {
        v4d x;
        v4u u, ok;
        memcpy(&x, in + i, sizeof x);
        u = (v4u)x;
        /* normal, positive, finite: 0x0010.. <= bits < 0x7ff0.. */
        ok = (u - 0x0010000000000000ULL) < 0x7fe0000000000000ULL;
        if (ok[0] & ok[1] & ok[2] & ok[3]) {
            x = log4(x);
            memcpy(out + i, &x, sizeof x);
        } else {
            for (size_t j = i; j < i + 4; j++)
                out[j] = log(in[j]);
        }
    }
    for (; i < n; i++)
        out[i] = log(in[i]);
}

static int log_map3_generic(const double *in, double *out, size_t n, const double off[3],
                            double sign, double floor, long clamped[3]);
static int logf_map3_generic(const float *in, float *out, size_t n, const float off[3],
                             float sign, float floor, long clamped[3]);

/* vmath_log_map3 on AVX2: twelve values (three vectors, four channel
 * periods) per step, so each lane's channel is fixed: vector k lane l is
 * channel (4k + l) % 3. */
__attribute__((target("avx2,fma"), optimize("fp-contract=fast"))) static int log_map3_fma(const double *in, double *out,
                                                            size_t n, const double off[3],
                                                            double sign, double floor,
                                                            long clamped[3])
{
    const v4d fl = {floor, floor, floor, floor};
    v4d o[3];
    v4l cnt[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}}, bad = {0, 0, 0, 0};
    size_t i = 0;
    int nonfinite = 0;
    for (int k = 0; k < 3; k++)
        for (int l = 0; l < 4; l++)
            o[k][l] = off[(4 * k + l) % 3];
    for (; i + 12 <= n; i += 12) {
        v4d a[3];
        v4u ok = {~0ULL, ~0ULL, ~0ULL, ~0ULL};
        for (int k = 0; k < 3; k++) {
            v4d x;
            v4l low;
            memcpy(&x, in + i + 4 * k, sizeof x);
            bad |= (v4l)((x - x) != 0.0);         /* inf - inf, NaN: not 0 */
            a[k] = o[k] + sign * x;
            low = ~(v4l)(a[k] > fl);              /* NaN too */
            cnt[k] -= low;
            a[k] = (v4d)(((v4l)a[k] & ~low) | ((v4l)fl & low));
            ok &= ((v4u)a[k] - 0x0010000000000000ULL) < 0x7fe0000000000000ULL;
        }
        if (ok[0] & ok[1] & ok[2] & ok[3]) {
            for (int k = 0; k < 3; k++) {
                v4d y = log4(a[k]);
                memcpy(out + i + 4 * k, &y, sizeof y);
            }
        } else {
            for (int k = 0; k < 3; k++)
                for (int l = 0; l < 4; l++)
                    out[i + 4 * k + l] = log(a[k][l]);
        }
    }
    for (int k = 0; k < 3; k++)
        for (int l = 0; l < 4; l++)
            clamped[(4 * k + l) % 3] += cnt[k][l];
    nonfinite = (bad[0] | bad[1] | bad[2] | bad[3]) != 0;
    /* the rest (i is a multiple of 3: the channels line up) */
    return nonfinite | log_map3_generic(in + i, out + i, n - i, off, sign, floor, clamped);
}

/* logf in eight lanes: the same reduction as log4 in single precision,
 * with fdlibm's e_logf.c minimax (Lg1..Lg4). */
typedef float v8f __attribute__((vector_size(32)));
typedef int v8i __attribute__((vector_size(32)));

__attribute__((target("avx2,fma"), always_inline, optimize("fp-contract=fast"))) static inline v8f
logf8(v8f x)
{
    const float Lg1 = 6.6666662693e-01f, Lg2 = 4.0000972152e-01f, Lg3 = 2.8498786688e-01f,
                Lg4 = 2.4279078841e-01f, ln2_hi = 6.9313812256e-01f, ln2_lo = 9.0580006145e-06f;
    v8i u = (v8i)x;
    v8i tmp = u - 0x3f3504f3;                 /* sqrt(0.5) */
    v8i ki = tmp >> 23;                       /* arithmetic: the exponent k */
    v8f k = __builtin_convertvector(ki, v8f);
    v8f f = (v8f)(u - (tmp & (int)0xff800000)) - 1.0f;
    v8f s = f / (2.0f + f), z = s * s, w = z * z;
    v8f r = w * (Lg2 + w * Lg4) + z * (Lg1 + w * Lg3);
    v8f hfsq = 0.5f * f * f;
    return k * ln2_hi - ((hfsq - (s * (hfsq + r) + k * ln2_lo)) - f);
}

__attribute__((target("avx2,fma"), optimize("fp-contract=fast"))) static int
logf_map3_fma(const float *in, float *out, size_t n, const float off[3], float sign, float floor,
              long clamped[3])
{
    const v8f fl = {floor, floor, floor, floor, floor, floor, floor, floor};
    v8f o[3];
    v8i cnt[3], bad = {0};
    size_t i = 0;
    int nonfinite = 0;
    memset(cnt, 0, sizeof cnt);
    for (int k = 0; k < 3; k++)
        for (int l = 0; l < 8; l++)
            o[k][l] = off[(8 * k + l) % 3];
    for (; i + 24 <= n; i += 24) {
        v8f a[3];
        v8i ok = {~0, ~0, ~0, ~0, ~0, ~0, ~0, ~0};
        for (int k = 0; k < 3; k++) {
            v8f x;
            v8i low;
            memcpy(&x, in + i + 8 * k, sizeof x);
            bad |= (v8i)((x - x) != 0.0f);
            a[k] = o[k] + sign * x;
            low = ~(v8i)(a[k] > fl);
            cnt[k] -= low;
            a[k] = (v8f)(((v8i)a[k] & ~low) | ((v8i)fl & low));
            /* normal, positive, finite: 0x00800000 <= bits < 0x7f800000 */
            ok &= (v8i)(((v8i)a[k] - 0x00800000) < 0x7f000000) &
                  (v8i)((v8i)a[k] >= 0x00800000);
        }
        {
            int all = 1;
            for (int l = 0; l < 8; l++)
                all &= ok[l] != 0;
            if (all) {
                for (int k = 0; k < 3; k++) {
                    v8f y = logf8(a[k]);
                    memcpy(out + i + 8 * k, &y, sizeof y);
                }
            } else {
                for (int k = 0; k < 3; k++)
                    for (int l = 0; l < 8; l++)
                        out[i + 8 * k + l] = logf(a[k][l]);
            }
        }
    }
    for (int k = 0; k < 3; k++)
        for (int l = 0; l < 8; l++)
            clamped[(8 * k + l) % 3] += cnt[k][l];
    for (int l = 0; l < 8; l++)
        nonfinite |= bad[l] != 0;
    return nonfinite | logf_map3_generic(in + i, out + i, n - i, off, sign, floor, clamped);
}

void vmath_log(const double *in, double *out, size_t n)
{
    if (have_fma())
        log_fma(in, out, n);
    else if (have_avx2())
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

int vmath_log_map3(const double *in, double *out, size_t n, const double off[3], double sign,
                   double floor, long clamped[3])
{
    if (have_fma())
        return log_map3_fma(in, out, n, off, sign, floor, clamped);
    return log_map3_generic(in, out, n, off, sign, floor, clamped);
}

int vmath_logf_map3(const float *in, float *out, size_t n, const float off[3], float sign,
                    float floor, long clamped[3])
{
    if (have_fma())
        return logf_map3_fma(in, out, n, off, sign, floor, clamped);
    return logf_map3_generic(in, out, n, off, sign, floor, clamped);
}

const char *vmath_impl(void)
{
    return have_fma() ? "log: glint-avx2-fma, exp: libmvec-avx2"
                      : have_avx2() ? "libmvec-avx2" : "libmvec-sse2";
}

#else

void vmath_log(const double *in, double *out, size_t n)
{
    for (size_t i = 0; i < n; i++)
        out[i] = log(in[i]);
}

static int log_map3_generic(const double *in, double *out, size_t n, const double off[3],
                            double sign, double floor, long clamped[3]);
static int logf_map3_generic(const float *in, float *out, size_t n, const float off[3],
                             float sign, float floor, long clamped[3]);

int vmath_log_map3(const double *in, double *out, size_t n, const double off[3], double sign,
                   double floor, long clamped[3])
{
    return log_map3_generic(in, out, n, off, sign, floor, clamped);
}

int vmath_logf_map3(const float *in, float *out, size_t n, const float off[3], float sign,
                    float floor, long clamped[3])
{
    return logf_map3_generic(in, out, n, off, sign, floor, clamped);
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

/* The portable vmath_log_map3: the mapping, then vmath_log. */
static int log_map3_generic(const double *in, double *out, size_t n, const double off[3],
                            double sign, double floor, long clamped[3])
{
    int nonfinite = 0;
    for (size_t i = 0; i < n; i++) {
        double x = in[i], arg = off[i % 3] + sign * x;
        nonfinite |= !(x - x == 0.0);
        if (!(arg > floor)) {
            arg = floor;
            clamped[i % 3]++;
        }
        out[i] = arg;
    }
    vmath_log(out, out, n);
    return nonfinite;
}

static int logf_map3_generic(const float *in, float *out, size_t n, const float off[3],
                             float sign, float floor, long clamped[3])
{
    int nonfinite = 0;
    for (size_t i = 0; i < n; i++) {
        float x = in[i], arg = off[i % 3] + sign * x;
        nonfinite |= !(x - x == 0.0f);
        if (!(arg > floor)) {
            arg = floor;
            clamped[i % 3]++;
        }
        out[i] = logf(arg);
    }
    return nonfinite;
}
