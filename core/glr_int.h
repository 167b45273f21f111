/* glr_int.h: internals shared by glr.c (rendering) and glr_export.c (shader
 * export).  Not part of core's contract. */
#ifndef GLINT_GLR_INT_H
#define GLINT_GLR_INT_H

#include "err.h"
#include "material.h"

/* A material the preview shader can evaluate (method, sizes, finite
 * factors); 0 or GLINT_EINVAL / GLINT_ENONFINITE with a message. */
int glr_material_ok(const material *mat, glint_err *err);

#endif
