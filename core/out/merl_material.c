/* merl_material.c: a fitted material as a MERL table (merl_material.h). */
#include "merl_material.h"

#include <string.h>

/* a material's f: its value divided by n.wi */
static void material_f(const void *ctx, const double n[3], const double wi[3],
                       const double wo[3], double f[3])
{
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    material_eval(ctx, n, wi, wo, f);
    for (int c = 0; c < 3; c++)
        f[c] = ci > 0.0 ? f[c] / ci : 0.0;
}


int merl_from_material(const material *m, int nthreads, merl_table *out, merl_stats *st,
                       glint_err *err)
{
    int rc;
    memset(out, 0, sizeof *out);
    if (!m || !m->method) {
        if (st)
            memset(st, 0, sizeof *st);
        return glint_err_set(err, GLINT_EINVAL, "no material to tabulate");
    }
    rc = merl_tabulate(material_f, m, nthreads, out, st, err);
    if (!rc && st)
        st->spatial = material_spatial(m);
    return rc;
}

