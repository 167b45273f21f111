/* method_pbr.h: the pbr method: a physically based parametric BRDF (pbr.h:
 * kd / pi plus one or two GGX lobes, height-correlated Smith, Schlick
 * Fresnel of a dielectric or a conductor) fitted to point-lit paintings by
 * nonlinear least squares (GSL), inside glint's method interface (method.h).
 *
 * Levels (each in the cache under its own key):
 *   pbr-geom   per sample n.wi, n.wo, n.h and wi.h (pbr_geom; 32 bytes a
 *              sample), so that a repaint costs the fit alone
 *
 * The material's info says, besides params, precomputation, seconds and
 * errors, what the views determine (pbr_fit.c): "determined": {name:
 * {"value", "sigma"}}, "undetermined": [names], "at_bound": [{"name",
 * "bound": "lower"|"upper", "value"}], "fit": the starts, iterations and
 * convergence, and "notes": sentences for people on what the above means
 * (a black painting, a roughness at its floor, a colour clamped at 1).
 *
 * Manifest members (material.json): "fresnel": "dielectric"|"conductor",
 * "diffuse": [r, g, b] (kd), "lobes": [{"alpha", "ks": [r, g, b], "ior"}]
 * (dielectric) or [{"alpha", "ks", "f0": [r, g, b]}] (conductor).
 *
 * Thread-safety: as method.h. */
#ifndef GLINT_METHOD_PBR_H
#define GLINT_METHOD_PBR_H

#include "material.h"
#include "method.h"
#include "pbr.h"

extern const method method_pbr;
extern const material_ops pbr_material_ops;

typedef struct pbr_params {
    int lobes;          /* 1 or 2 */
    int fresnel;        /* PBR_DIELECTRIC or PBR_CONDUCTOR */
    int starts;         /* roughnesses started from */
    int max_iter;       /* iterations per start */
    int start_iter;     /* iterations of each start on its subset (pbr_fit_opts) */
    int start_samples;  /* samples the starts are fitted on (0: all) */
    int refine_samples; /* samples the best start is refined on (0: all) */
} pbr_params;

/* A material's data: the fitted parameters and their common form. */
typedef struct pbr_material {
    pbr_spec sp;
    double p[PBR_MAXP];   /* direct parameters (pbr.h) */
    double kd[3];
    pbr_lobe lobe[PBR_MAX_LOBES];
} pbr_material;

/* Fill the common form (kd, lobe) of pm from pm->sp and pm->p. */
void pbr_material_sync(pbr_material *pm);

/* The data of a pbr material (of a method whose materials are pbr's: pbr,
 * pbr_env), or NULL for another method's. */
const pbr_material *pbr_material_of(const material *m);

/* The report's members on what the views determine ("determined",
 * "undetermined", "at_bound", "notes"; black: the painting is black on every
 * lit sample) and on the fit itself (starts, iterations, convergence,
 * cost): new objects, for methods that fit pbr's model. */
json_t *pbr_report_determination(const pbr_spec *sp, const pbr_fit_result *r, int black);
json_t *pbr_report_fit(const pbr_fit_result *r);

#endif
