/* hfx_int.h: internals of hfx.c, for hfx*.c only. */
#ifndef GLINT_HFX_INT_H
#define GLINT_HFX_INT_H

#include "hfx.h"

/* The kernel form (hfx.h) of the reduced problem: idx[n] maps unknowns to
 * the nr reached ones (-1: unreached).  Fills dc->M, form, rank, s_max,
 * s_min_kept.  Returns 1 (dc untouched) when the form does not apply (no
 * factors given, a smoothing row across factors, a large null space of
 * the smoothing), else 0 or an error code. */
int hfx_kernel_build(const hfx_rows *x, const int *idx, int nr, double rcond, hfx_decomp *dc,
                     glint_err *err);

#endif
