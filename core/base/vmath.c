#include "vmath.h"

#include <float.h>
#include <math.h>
#include <string.h>
#include <stdlib.h>

#include "err.h"

static int log_map3_generic(const double *in, double *out, size_t n, const double off[3],
                            double sign, double floor, long clamped[3]);

typedef int (*map3_fn)(const double *, double *, size_t, const double[3], double, double, long[3]);

/* in[0..n-1] widened into a buffer, FN over it, 240 values at a time: a
 * multiple of every loop's step (24, 12) and of 3, so FN sees the same
 * steps, channels and tail as over the whole array. */
static int log_map3_f32_widen(const float *in, double *out, size_t n, const double off[3],
                              double sign, double floor, long clamped[3], map3_fn fn)
{
    double buf[240];
    int nonfinite = 0;
    for (size_t i = 0; i < n; i += 240) {
        size_t m = n - i < 240 ? n - i : 240;
        for (size_t j = 0; j < m; j++)
            buf[j] = in[i + j];
        nonfinite |= fn(buf, out + i, m, off, sign, floor, clamped);
    }
    return nonfinite;
}

#if defined(__x86_64__) && defined(__GLIBC__) && defined(GLINT_HAVE_LIBMVEC)
#include <immintrin.h>

/* glibc libmvec vector variants (x86-64 vector ABI names). */
__m128d _ZGVbN2v_log(__m128d x);
__m128d _ZGVbN2v_exp(__m128d x);
/* the AVX2 variants take and return ymm registers: declared for avx2 code */
__attribute__((target("avx2"))) __m256d _ZGVdN4v_log(__m256d x);
__attribute__((target("avx2"))) __m256d _ZGVdN4v_exp(__m256d x);
/* ... and the AVX-512 exp, eight lanes (zmm registers) */
__attribute__((target("avx512f"))) __m512d _ZGVeN8v_exp(__m512d x);

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

/* libmvec's AVX-512 exp: the same bits as its AVX2 variant over every value
 * tests/unit/test_vmath.c tries, at about 0.75 times the time per value
 * (0.84 against 1.12 ns in a throwaway harness, 4M values over [-700,
 * 700]); the diagnostics take one exp per value. */
__attribute__((target("avx512f"))) static void exp_512(const double *in, double *out, size_t n)
{
    size_t i = 0;
    for (; i + 8 <= n; i += 8)
        _mm512_storeu_pd(out + i, _ZGVeN8v_exp(_mm512_loadu_pd(in + i)));
    exp_avx2(in + i, out + i, n - i);
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

/* The instruction sets in use: what the CPU has, capped by GLINT_VMATH
 * (read once; see vmath.h). */
enum { ISA_NONE, ISA_AVX2, ISA_FMA, ISA_512 };

static int isa_cpu(void)
{
    int lv = ISA_NONE;
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx2")) {
        lv = ISA_AVX2;
        if (__builtin_cpu_supports("fma")) {
            lv = ISA_FMA;
            if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                __builtin_cpu_supports("avx512vl"))
                lv = ISA_512;
        }
    }
    return lv;
}

static int isa_cap(const char *cap)
{
    if (cap && strcmp(cap, "avx2") == 0)
        return ISA_FMA;
    if (cap && strcmp(cap, "sse2") == 0)
        return ISA_NONE;
    return ISA_512;
}

static int isa_now = -1;

static int isa_level(void)
{
    if (isa_now < 0) {
        int lv = isa_cpu(), mx = isa_cap(getenv("GLINT_VMATH"));
        isa_now = lv < mx ? lv : mx;
    }
    return isa_now;
}

int vmath_limit(const char *cap)
{
    int lv = isa_cpu(), mx = isa_cap(cap ? cap : getenv("GLINT_VMATH"));
    if (cap && strcmp(cap, "avx2") && strcmp(cap, "sse2") && strcmp(cap, "avx512"))
        return GLINT_EINVAL;
    isa_now = lv < mx ? lv : mx;
    return 0;
}

static int have_avx2(void)
{
    return isa_level() >= ISA_AVX2;
}

static int have_fma(void)
{
    return isa_level() >= ISA_FMA;
}

static int have_512(void)
{
    return isa_level() >= ISA_512;
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
typedef float v4f __attribute__((vector_size(16)));

/* The exponent k as a double, from tmp = x's bits less the reduction's
 * offset: through the 2^52 + 2048 magic (AVX2 has no conversion from
 * int64), or converted directly (AVX-512 DQ, three instructions fewer).
 * Both are exact, so they give the same k. */
#define GLINT_K_MAGIC(VD, VL, VU, tmp)                                                         \
    ((VD)((VL)(((((VU)(tmp)) >> 52) + 2048) & 4095) | 0x4330000000000000LL) -                 \
     (4503599627370496.0 + 2048.0))
#define GLINT_K_CVT(VD, VL, VU, tmp) __builtin_convertvector((tmp) >> 52, VD)

/* The reduction and polynomial of log4 and log8, on vectors of type VD
 * (doubles) with VL / VU the signed / unsigned 64-bit integer vectors of
 * the same width, KF one of the two above: the same operations lane for
 * lane, so both give the same bits. */
#define GLINT_LOG_BODY(VD, VL, VU, x, KF)                                                      \
    do {                                                                                       \
        const double Lg1 = 6.666666666666735130e-01, Lg2 = 3.999999999940941908e-01,           \
                     Lg3 = 2.857142874366239149e-01, Lg4 = 2.222219843214978396e-01,           \
                     Lg5 = 1.818357216161805012e-01, Lg6 = 1.531383769920937332e-01,           \
                     Lg7 = 1.479819860511658591e-01, ln2_hi = 6.93147180369123816490e-01,      \
                     ln2_lo = 1.90821492927058770002e-10;                                      \
        VL u_ = (VL)(x);                                                                       \
        /* the exponent k such that x / 2^k lies in [sqrt(2)/2, sqrt(2)) */                    \
        VL tmp_ = u_ - 0x3fe6a09e667f3bcdLL;                                                   \
        VD k_ = KF(VD, VL, VU, tmp_);                                                          \
        VD m_ = (VD)(u_ - (tmp_ & (long long)0xfff0000000000000ULL));                          \
        /* f = m - 1 is exact (Sterbenz: m lies in [sqrt(2)/2, sqrt(2))), so 2 + f              \
         * is m + 1, the same bits, with one add less before the division */                    \
        VD f_ = m_ - 1.0;                                                                      \
        VD s_ = f_ / (m_ + 1.0), z_ = s_ * s_, w_ = z_ * z_;                                  \
        VD r_ = w_ * (Lg2 + w_ * (Lg4 + w_ * Lg6)) + z_ * (Lg1 + w_ * (Lg3 + w_ * (Lg5 + w_ * Lg7))); \
        VD hfsq_ = 0.5 * f_ * f_;                                                              \
        (x) = k_ * ln2_hi - ((hfsq_ - (s_ * (hfsq_ + r_) + k_ * ln2_lo)) - f_);                \
    } while (0)

__attribute__((target("avx2,fma"), always_inline, optimize("fp-contract=fast"))) static inline v4d
log4(v4d x)
{
    GLINT_LOG_BODY(v4d, v4l, v4u, x, GLINT_K_MAGIC);
    return x;
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

/* The loop of vmath_log_map3 / vmath_logf_map3 on W-lane vectors of type
 * VD (VI: integers of the lanes' width): 3W values (three vectors, W
 * channel periods) per step, so each lane's channel is fixed: vector k
 * lane l is channel (W k + l) % 3.  OK(a) is all-ones in the lanes whose
 * value the vector log LOGV takes (positive, normal, finite); ANY(v) tells
 * whether a lane of v is not zero.  A step with a lane outside LOGV's range
 * goes to FIX (GLINT_MAP3_FIX), which gives that lane libm's log, so a
 * value's log does not depend on its neighbours or on W.  The three
 * vectors are named, not an array, and the rare step is out of line: an
 * array indexed lane by lane kept them in memory (about 15% of the loop's
 * time).  Sets i to the first value left and nonfinite when an input was
 * inf or NaN. */
#define GLINT_MAP3_LOOP(VD, VI, W, LOGV, OK, ANY, FIX, LOAD)                                       \
    do {                                                                                       \
        VD fl_, o0_, o1_, o2_;                                                                 \
        VI c0_, c1_, c2_, bad_;                                                                \
        memset(&c0_, 0, sizeof c0_);                                                           \
        c1_ = c2_ = bad_ = c0_;                                                                \
        for (int l = 0; l < (W); l++) {                                                        \
            fl_[l] = floor;                                                                    \
            o0_[l] = off[l % 3];                                                               \
            o1_[l] = off[((W) + l) % 3];                                                       \
            o2_[l] = off[(2 * (W) + l) % 3];                                                   \
        }                                                                                      \
        for (; i + 3 * (W) <= n; i += 3 * (W)) {                                               \
            VD a0_, a1_, a2_;                                                                  \
            VI k0_, k1_, k2_;                                                                  \
            GLINT_MAP3_ARG(VD, VI, in + i, o0_, a0_, c0_, k0_, OK, LOAD);                      \
            GLINT_MAP3_ARG(VD, VI, in + i + (W), o1_, a1_, c1_, k1_, OK, LOAD);                      \
            GLINT_MAP3_ARG(VD, VI, in + i + 2 * (W), o2_, a2_, c2_, k2_, OK, LOAD);                  \
            if (!ANY(~k0_ | ~k1_ | ~k2_)) {                                                    \
                VD y0_ = LOGV(a0_), y1_ = LOGV(a1_), y2_ = LOGV(a2_);                          \
                memcpy(out + i, &y0_, sizeof y0_);                                             \
                memcpy(out + i + (W), &y1_, sizeof y1_);                                       \
                memcpy(out + i + 2 * (W), &y2_, sizeof y2_);                                   \
            } else {                                                                           \
                FIX(a0_, k0_, out + i);                                                        \
                FIX(a1_, k1_, out + i + (W));                                                  \
                FIX(a2_, k2_, out + i + 2 * (W));                                              \
            }                                                                                  \
        }                                                                                      \
        for (int l = 0; l < (W); l++) {                                                        \
            clamped[l % 3] += c0_[l];                                                          \
            clamped[((W) + l) % 3] += c1_[l];                                                  \
            clamped[(2 * (W) + l) % 3] += c2_[l];                                              \
            nonfinite |= bad_[l] != 0;                                                         \
        }                                                                                      \
    } while (0)

/* one vector of GLINT_MAP3_LOOP's arguments: A = max(O + sign X, floor)
 * (NaN floored), CNT counting the floored lanes, K the lanes LOGV takes */
#define GLINT_MAP3_ARG(VD, VI, src, O, A, CNT, K, OK, LOAD)                                    \
    do {                                                                                       \
        VD x_;                                                                                 \
        VI low_;                                                                               \
        LOAD(x_, (src));                                                                       \
        bad_ |= (VI)((x_ - x_) != 0); /* inf - inf, NaN: not 0 */                             \
        A = O + sign * x_;                                                                     \
        low_ = ~(VI)(A > fl_); /* NaN too */                                                   \
        CNT -= low_;                                                                           \
        A = (VD)(((VI)A & ~low_) | ((VI)fl_ & low_));                                          \
        K = OK(A);                                                                             \
    } while (0)

/* LOAD of GLINT_MAP3_LOOP: a vector of the input's own type, or four
 * floats widened to doubles (exactly) */
#define GLINT_LOAD_SAME(x, src) memcpy(&(x), (src), sizeof(x))
#define GLINT_LOAD_W4(x, src)                                                                  \
    do {                                                                                       \
        v4f w_;                                                                                \
        memcpy(&w_, (src), sizeof w_);                                                         \
        (x) = __builtin_convertvector(w_, v4d);                                                \
    } while (0)

/* The rare step of GLINT_MAP3_LOOP with a lane outside the vector log's
 * range: that lane's log from libm, the others' from the vector log. */
#define GLINT_MAP3_FIX(NAME, ATTR, VD, VI, W, LOGV, SLOG, T)                                   \
    ATTR __attribute__((noinline)) static void NAME(VD a, VI ok, T *out)                       \
    {                                                                                          \
        VD y = LOGV(a);                                                                        \
        for (int l = 0; l < (W); l++)                                                          \
            if (!ok[l])                                                                        \
                y[l] = SLOG(a[l]);                                                             \
        memcpy(out, &y, sizeof y);                                                             \
    }

/* normal, positive, finite: 0x0010.. <= bits < 0x7ff0.. (one unsigned
 * compare), as lane masks */
#define GLINT_OK_D(VI, VU, a) ((VI)(((VU)(a) - 0x0010000000000000ULL) < 0x7fe0000000000000ULL))
/* the same in single precision: 0x00800000 <= bits < 0x7f800000 */
#define GLINT_OK_F(VI, a)                                                                      \
    ((VI)(((VI)(a) - 0x00800000) < 0x7f000000) & (VI)((VI)(a) >= 0x00800000))

#define OK4(a) GLINT_OK_D(v4l, v4u, a)
/* a lane not zero: one test instruction (a loop over the lanes took eight
 * moves out of the vector) */
#define ANY256(v) (!_mm256_testz_si256((__m256i)(v), (__m256i)(v)))
#define ANY512D(v) (_mm512_test_epi64_mask((__m512i)(v), (__m512i)(v)) != 0)
#define ANY512F(v) (_mm512_test_epi32_mask((__m512i)(v), (__m512i)(v)) != 0)

#define GLINT_FMA_FN __attribute__((target("avx2,fma"), optimize("fp-contract=fast")))
#define GLINT_512_FN __attribute__((target(GLINT_512), optimize("fp-contract=fast")))

GLINT_MAP3_FIX(fix4, GLINT_FMA_FN, v4d, v4l, 4, log4, log, double)

/* vmath_log_map3 on AVX2 + FMA: twelve values per step. */
__attribute__((target("avx2,fma"), optimize("fp-contract=fast"))) static int
log_map3_fma(const double *in, double *out, size_t n, const double off[3], double sign,
             double floor, long clamped[3])
{
    size_t i = 0;
    int nonfinite = 0;
    GLINT_MAP3_LOOP(v4d, v4l, 4, log4, OK4, ANY256, fix4, GLINT_LOAD_SAME);
    /* the rest (i is a multiple of 3: the channels line up) */
    return nonfinite | log_map3_generic(in + i, out + i, n - i, off, sign, floor, clamped);
}

/* ... and on AVX-512 (avx512f, dq, vl): the same loop at twice the width,
 * 24 values per step, lane for lane the same operations as log_map3_fma,
 * so the same bits (tests/unit/test_vmath.c checks it). */
typedef double v8d __attribute__((vector_size(64)));
typedef long long v8l __attribute__((vector_size(64)));
typedef unsigned long long v8u __attribute__((vector_size(64)));

#define GLINT_512 "avx512f,avx512dq,avx512vl,fma"

__attribute__((target(GLINT_512), always_inline, optimize("fp-contract=fast"))) static inline v8d
log8(v8d x)
{
    GLINT_LOG_BODY(v8d, v8l, v8u, x, GLINT_K_CVT);
    return x;
}

#define OK8(a) GLINT_OK_D(v8l, v8u, a)
GLINT_MAP3_FIX(fix8, GLINT_512_FN, v8d, v8l, 8, log8, log, double)

__attribute__((target(GLINT_512), optimize("fp-contract=fast"))) static int
log_map3_512(const double *in, double *out, size_t n, const double off[3], double sign,
             double floor, long clamped[3])
{
    size_t i = 0;
    int nonfinite = 0;
    GLINT_MAP3_LOOP(v8d, v8l, 8, log8, OK8, ANY512D, fix8, GLINT_LOAD_SAME);
    return nonfinite | log_map3_fma(in + i, out + i, n - i, off, sign, floor, clamped);
}

/* ---- vmath_log_map3_f32 ------------------------------------------------------------------ */

/* On AVX2 + FMA: log_map3_fma's loop, each vector widened as it is loaded. */
__attribute__((target("avx2,fma"), optimize("fp-contract=fast"))) static int
log_map3_f32_fma(const float *in, double *out, size_t n, const double off[3], double sign,
                 double floor, long clamped[3])
{
    size_t i = 0;
    int nonfinite = 0;
    GLINT_MAP3_LOOP(v4d, v4l, 4, log4, OK4, ANY256, fix4, GLINT_LOAD_W4);
    return nonfinite | log_map3_f32_widen(in + i, out + i, n - i, off, sign, floor, clamped,
                                          log_map3_generic);
}

/* On AVX-512, one vector of arguments: eight floats widened, a = o + sign
 * x (x itself when PLAIN: no offset, sign +1, which gives the same floored
 * value), NF the lanes where a is inf or NaN (one class test), a floored
 * where !(a > floor) (NaN too), CNT counting those lanes.  The same values
 * as GLINT_MAP3_ARG's. */
__attribute__((target(GLINT_512), always_inline, optimize("fp-contract=fast"))) static inline v8d
argw8(const float *src, v8d o, v8d sg, v8d fl, int plain, v8l *cnt, __mmask8 *nf)
{
    __m512d x = _mm512_cvtps_pd(_mm256_loadu_ps(src)), a;
    __mmask8 low;
    a = plain ? x : _mm512_fmadd_pd((__m512d)sg, x, (__m512d)o);
    *nf = _mm512_fpclass_pd_mask(a, 0x99); /* QNaN, +inf, -inf, SNaN */
    low = _mm512_cmp_pd_mask(a, (__m512d)fl, _CMP_NGT_UQ);
    *cnt = (v8l)_mm512_mask_sub_epi64((__m512i)*cnt, low, (__m512i)*cnt, _mm512_set1_epi64(-1));
    return (v8d)_mm512_mask_mov_pd(a, low, (__m512d)fl);
}

/* The loop of log_map3_f32_512, 24 values a step, for a normal floor: a
 * floored argument then lies in log8's range unless it is +inf, and an
 * input that is inf or NaN makes its argument inf or NaN, so a step
 * without such an argument needs neither libm nor the test of the inputs.
 * A step with one tests its inputs and gives the lanes outside log8's
 * range libm's log (fix8), as log_map3_512 does.  Sets *done to the
 * values handled. */
__attribute__((target(GLINT_512), always_inline, optimize("fp-contract=fast"))) static inline int
f32_512_loop(const float *in, double *out, size_t n, const double off[3], double sign,
             double floor, long clamped[3], int plain, size_t *done)
{
    v8d o0, o1, o2, fl, sg;
    v8l c0, c1, c2;
    size_t i = 0;
    int nonfinite = 0;
    memset(&c0, 0, sizeof c0);
    c1 = c2 = c0;
    for (int l = 0; l < 8; l++) {
        fl[l] = floor;
        sg[l] = sign;
        o0[l] = off[l % 3];
        o1[l] = off[(8 + l) % 3];
        o2[l] = off[(16 + l) % 3];
    }
    for (; i + 24 <= n; i += 24) {
        __mmask8 n0, n1, n2;
        v8d a0 = argw8(in + i, o0, sg, fl, plain, &c0, &n0);
        v8d a1 = argw8(in + i + 8, o1, sg, fl, plain, &c1, &n1);
        v8d a2 = argw8(in + i + 16, o2, sg, fl, plain, &c2, &n2);
        if (!(n0 | n1 | n2)) {
            v8d y0 = log8(a0), y1 = log8(a1), y2 = log8(a2);
            memcpy(out + i, &y0, sizeof y0);
            memcpy(out + i + 8, &y1, sizeof y1);
            memcpy(out + i + 16, &y2, sizeof y2);
        } else {
            for (int l = 0; l < 24; l++)
                nonfinite |= !isfinite(in[i + l]);
            fix8(a0, OK8(a0), out + i);
            fix8(a1, OK8(a1), out + i + 8);
            fix8(a2, OK8(a2), out + i + 16);
        }
    }
    for (int l = 0; l < 8; l++) {
        clamped[l % 3] += c0[l];
        clamped[(8 + l) % 3] += c1[l];
        clamped[(16 + l) % 3] += c2[l];
    }
    *done = i;
    return nonfinite;
}

__attribute__((target(GLINT_512), optimize("fp-contract=fast"))) static int
log_map3_f32_512(const float *in, double *out, size_t n, const double off[3], double sign,
                 double floor, long clamped[3])
{
    size_t i = 0;
    int nonfinite;
    if (!(floor >= DBL_MIN && floor <= DBL_MAX)) /* not normal: log_map3_512's own tests */
        return log_map3_f32_widen(in, out, n, off, sign, floor, clamped, log_map3_512);
    if (off[0] == 0.0 && off[1] == 0.0 && off[2] == 0.0 && sign == 1.0)
        nonfinite = f32_512_loop(in, out, n, off, sign, floor, clamped, 1, &i);
    else
        nonfinite = f32_512_loop(in, out, n, off, sign, floor, clamped, 0, &i);
    return nonfinite | log_map3_f32_widen(in + i, out + i, n - i, off, sign, floor, clamped,
                                          log_map3_fma);
}

/* logf in eight (sixteen) lanes: the same reduction as log4 in single
 * precision, with fdlibm's e_logf.c minimax (Lg1..Lg4). */
#define GLINT_LOGF_BODY(VF, VI, x)                                                             \
    do {                                                                                       \
        const float Lg1 = 6.6666662693e-01f, Lg2 = 4.0000972152e-01f,                          \
                    Lg3 = 2.8498786688e-01f, Lg4 = 2.4279078841e-01f,                          \
                    ln2_hi = 6.9313812256e-01f, ln2_lo = 9.0580006145e-06f;                    \
        VI u_ = (VI)(x);                                                                       \
        VI tmp_ = u_ - 0x3f3504f3;             /* sqrt(0.5) */                                \
        VI ki_ = tmp_ >> 23;                   /* arithmetic: the exponent k */               \
        VF k_ = __builtin_convertvector(ki_, VF);                                              \
        VF m_ = (VF)(u_ - (tmp_ & (int)0xff800000));                                           \
        VF f_ = m_ - 1.0f; /* exact: 2 + f is m + 1, as in GLINT_LOG_BODY */                  \
        VF s_ = f_ / (m_ + 1.0f), z_ = s_ * s_, w_ = z_ * z_;                                 \
        VF r_ = w_ * (Lg2 + w_ * Lg4) + z_ * (Lg1 + w_ * Lg3);                                 \
        VF hfsq_ = 0.5f * f_ * f_;                                                             \
        (x) = k_ * ln2_hi - ((hfsq_ - (s_ * (hfsq_ + r_) + k_ * ln2_lo)) - f_);                \
    } while (0)

typedef float v8f __attribute__((vector_size(32)));
typedef int v8i __attribute__((vector_size(32)));
typedef float v16f __attribute__((vector_size(64)));
typedef int v16i __attribute__((vector_size(64)));

__attribute__((target("avx2,fma"), always_inline, optimize("fp-contract=fast"))) static inline v8f
logf8(v8f x)
{
    GLINT_LOGF_BODY(v8f, v8i, x);
    return x;
}

__attribute__((target(GLINT_512), always_inline, optimize("fp-contract=fast"))) static inline v16f
logf16(v16f x)
{
    GLINT_LOGF_BODY(v16f, v16i, x);
    return x;
}

#define OKF8(a) GLINT_OK_F(v8i, a)
#define OKF16(a) GLINT_OK_F(v16i, a)
GLINT_MAP3_FIX(fixf8, GLINT_FMA_FN, v8f, v8i, 8, logf8, logf, float)
GLINT_MAP3_FIX(fixf16, GLINT_512_FN, v16f, v16i, 16, logf16, logf, float)

__attribute__((target("avx2,fma"), optimize("fp-contract=fast"))) static int
logf_map3_fma(const float *in, float *out, size_t n, const float off[3], float sign, float floor,
              long clamped[3])
{
    size_t i = 0;
    int nonfinite = 0;
    GLINT_MAP3_LOOP(v8f, v8i, 8, logf8, OKF8, ANY256, fixf8, GLINT_LOAD_SAME);
    return nonfinite | logf_map3_generic(in + i, out + i, n - i, off, sign, floor, clamped);
}

__attribute__((target(GLINT_512), optimize("fp-contract=fast"))) static int
logf_map3_512(const float *in, float *out, size_t n, const float off[3], float sign, float floor,
              long clamped[3])
{
    size_t i = 0;
    int nonfinite = 0;
    GLINT_MAP3_LOOP(v16f, v16i, 16, logf16, OKF16, ANY512F, fixf16, GLINT_LOAD_SAME);
    return nonfinite | logf_map3_fma(in + i, out + i, n - i, off, sign, floor, clamped);
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
    if (have_512())
        exp_512(in, out, n);
    else if (have_avx2())
        exp_avx2(in, out, n);
    else
        exp_sse2(in, out, n);
}

int vmath_log_map3(const double *in, double *out, size_t n, const double off[3], double sign,
                   double floor, long clamped[3])
{
    if (have_512())
        return log_map3_512(in, out, n, off, sign, floor, clamped);
    if (have_fma())
        return log_map3_fma(in, out, n, off, sign, floor, clamped);
    return log_map3_generic(in, out, n, off, sign, floor, clamped);
}

int vmath_log_map3_f32(const float *in, double *out, size_t n, const double off[3], double sign,
                       double floor, long clamped[3])
{
    if (have_512())
        return log_map3_f32_512(in, out, n, off, sign, floor, clamped);
    if (have_fma())
        return log_map3_f32_fma(in, out, n, off, sign, floor, clamped);
    return log_map3_f32_widen(in, out, n, off, sign, floor, clamped, log_map3_generic);
}

int vmath_logf_map3(const float *in, float *out, size_t n, const float off[3], float sign,
                    float floor, long clamped[3])
{
    if (have_512())
        return logf_map3_512(in, out, n, off, sign, floor, clamped);
    if (have_fma())
        return logf_map3_fma(in, out, n, off, sign, floor, clamped);
    return logf_map3_generic(in, out, n, off, sign, floor, clamped);
}

const char *vmath_impl(void)
{
    return have_512()   ? "log: glint-avx512, exp: libmvec-avx512"
           : have_fma()  ? "log: glint-avx2-fma, exp: libmvec-avx2"
           : have_avx2() ? "libmvec-avx2"
                         : "libmvec-sse2";
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

int vmath_log_map3_f32(const float *in, double *out, size_t n, const double off[3], double sign,
                       double floor, long clamped[3])
{
    return log_map3_f32_widen(in, out, n, off, sign, floor, clamped, log_map3_generic);
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

int vmath_limit(const char *cap)
{
    if (cap && strcmp(cap, "avx2") && strcmp(cap, "sse2") && strcmp(cap, "avx512"))
        return GLINT_EINVAL;
    return 0;
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
