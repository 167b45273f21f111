/* merl_material.h: a fitted material tabulated in the MERL BRDF database's
 * layout (merl.h), the file BRDF Explorer, Mitsuba, PBRT and dj_brdf read:
 * a material made in glint, taken elsewhere. */
#ifndef GLINT_MERL_MATERIAL_H
#define GLINT_MERL_MATERIAL_H

#include "err.h"
#include "material.h"
#include "merl.h"

/* Tabulate m (OUT: *out, merl_free; *st may be NULL) at each bin's centre
 * (merl.h): f = the material's value divided by n.wi (the BRDF).  A
 * material that varies over the surface is taken at its average (st->spatial).
 * nthreads <= 0: one per processor.  Thread-safety: reads m only. */
int merl_from_material(const material *m, int nthreads, merl_table *out, merl_stats *st,
                       glint_err *err);

#endif
