/* vmath.h: elementwise log and exp over arrays of doubles, vectorized where
 * the C library offers vector variants (glibc's libmvec on x86-64, picked at
 * run time for the CPU), plain libm loops elsewhere.  Results agree with
 * libm to a few ulp; in and out may be the same array. */
#ifndef GLINT_VMATH_H
#define GLINT_VMATH_H

#include <stddef.h>

void vmath_log(const double *in, double *out, size_t n);
void vmath_exp(const double *in, double *out, size_t n);

/* Which implementation is in use ("libmvec-avx2", "libmvec-sse2", "libm"). */
const char *vmath_impl(void);

#endif
