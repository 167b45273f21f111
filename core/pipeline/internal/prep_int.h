/* prep_int.h: what prep.c and prep_holdout.c share. */
#ifndef GLINT_PREP_INT_H
#define GLINT_PREP_INT_H

#include "err.h"
#include "material.h"
#include "samples.h"

/* A pattern's cache file was cut short while `who` read it (samples.h):
 * sets err (GLINT_EIO) and returns its code. */
int prep_torn_error(glint_err *err, const char *who);

/* The material under each sample's point light, times its intensity, for
 * the samples of view k (every sample when k < 0; the others untouched). */
void prep_point_lit(const samples *s, const material *m, int k, float *rgb);

#endif
