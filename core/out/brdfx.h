/* brdfx.h: BRDF Explorer's analytic .brdf file for a material: the
 * method's own where it writes one (hf3), else one written from the
 * method's GPU fragment stage (brdfx.c says how). */
#ifndef GLINT_BRDFX_H
#define GLINT_BRDFX_H

#include "err.h"
#include "material.h"

/* OUT: *text (free()).  GLINT_EUNSUPPORTED, naming the MERL table as the
 * alternative, for materials without a GPU form or with a texture of more
 * than 8,192 texels (compilers take long over more). */
int brdfx_from_gpu(const material *m, char **text, glint_err *err);

/* The material as BRDF Explorer's analytic .brdf file (OUT: *text,
 * free()): the method's own (material_ops.brdf_explorer), else
 * brdfx_from_gpu's; GLINT_EUNSUPPORTED naming the alternative (the MERL
 * table, merl_material.h, which BRDF Explorer reads too) when neither can
 * be made. */
int brdfx_material(const material *m, char **text, glint_err *err);

#endif
