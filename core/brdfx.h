/* brdfx.h: BRDF Explorer's analytic .brdf file for a material of any method
 * with a GPU evaluation, written from the method's own fragment stage
 * (brdfx.c says how).  Methods with a hand-written file (hf3) are served
 * by theirs through material_brdf_explorer(). */
#ifndef GLINT_BRDFX_H
#define GLINT_BRDFX_H

#include "err.h"
#include "material.h"

/* OUT: *text (free()).  GLINT_EUNSUPPORTED, naming the MERL table as the
 * alternative, for materials without a GPU form or with a texture of more
 * than 8,192 texels (compilers take long over more). */
int brdfx_from_gpu(const material *m, char **text, glint_err *err);

#endif
