/* vmath.h: elementwise log and exp over arrays of doubles, vectorized where
 * the C library offers vector variants (glibc's libmvec on x86-64, picked at
 * run time for the CPU), plain libm loops elsewhere.  Results agree with
 * libm to a few ulp; in and out may be the same array.  And the dot product
 * the solvers' scans use. */
#ifndef GLINT_VMATH_H
#define GLINT_VMATH_H

#include <stddef.h>

void vmath_log(const double *in, double *out, size_t n);
void vmath_exp(const double *in, double *out, size_t n);

/* The forward mapping of glint's factorizations, fused with the log: for
 * n values (n a multiple of 3, channel-minor: value j is of channel j % 3),
 *     arg = off[j % 3] + sign * in[j],
 *     out[j] = log(arg > floor ? arg : floor)   (NaN floored too),
 * adding to clamped[c] the values of channel c that were floored.  Returns
 * 1 when an input value is not finite (inf or NaN), else 0.  sign is +1 or
 * -1; floor > 0.  The arithmetic is exactly that of the loop above (a sign
 * of -1 gives off - in), so results equal the scalar loop's bit for bit
 * except for vmath_log's own rounding; in and out may be the same array. */
int vmath_log_map3(const double *in, double *out, size_t n, const double off[3], double sign,
                   double floor, long clamped[3]);

/* vmath_log_map3 on single-precision values: in[j] widened to double
 * (exactly), then the same mapping and logs, so the same bits, clamped
 * counts and return value as widening into a buffer and calling
 * vmath_log_map3 on it.  It saves that buffer's store and load, and on
 * AVX-512 the mapping tests a vector's lanes with fewer instructions: a
 * finite argument above a normal floor always lies in the vector log's
 * range, so one class test of the arguments (inf or NaN) decides whether
 * a step needs libm for some lane.  in and out may not overlap. */
int vmath_log_map3_f32(const float *in, double *out, size_t n, const double off[3], double sign,
                       double floor, long clamped[3]);

/* The same in single precision, for fits that ask for it (hf's
 * HF_F32): logf of arg, eight lanes at a time on AVX2 (within 1 ulp of
 * libm's logf), libm's logf elsewhere.
 *
 * Both run twice as wide on AVX-512 (avx512f, dq and vl), with the same
 * operations lane for lane, so a fit gives the same bits on an AVX2 or an
 * AVX-512 machine (about 1.2 times the throughput of the AVX2 loops on the
 * Zen 4 here; BENCHMARKS.md). */
int vmath_logf_map3(const float *in, float *out, size_t n, const float off[3], float sign,
                    float floor, long clamped[3]);

/* Which implementation is in use ("log: glint-avx512, exp: libmvec-avx512",
 * "log: glint-avx2-fma, ...", "libmvec-avx2", "libmvec-sse2", "libm"). */
const char *vmath_impl(void);

/* The instruction sets in use are what the CPU has, up to a cap: "avx512"
 * (no cap), "avx2" (AVX2 + FMA at most) or "sse2"; NULL restores the cap
 * of the environment variable GLINT_VMATH (same names; read at the first
 * call otherwise).  For tests and benchmarks that compare the
 * implementations; not thread-safe against calls running meanwhile.
 * Returns GLINT_EINVAL for an unknown name (nothing changes). */
int vmath_limit(const char *cap);

/* a . b over n in four partial sums: independent chains, so a long scan is
 * not bound by the latency of one add per term (and it vectorizes). */
static inline double vmath_dot4(const double *restrict a, const double *restrict b, int n)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        s0 += a[i] * b[i];
        s1 += a[i + 1] * b[i + 1];
        s2 += a[i + 2] * b[i + 2];
        s3 += a[i + 3] * b[i + 3];
    }
    for (; i < n; i++)
        s0 += a[i] * b[i];
    return (s0 + s1) + (s2 + s3);
}

#endif
