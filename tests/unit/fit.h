/* fit.h: the direct path of the hf3 method (method_hf3.h) from paintings
 * to a material, as one call without the memory cache, for the tests and
 * the benchmarks only (built for them, not into glintcore: the command
 * line and the daemon fit through prep.h, which runs the same stages as
 * cache levels):
 *
 *   scene G-buffers -> samples (pattern) -> design -> decomposition
 *   (cached by content hash) -> regularized operator -> fit -> material
 *
 * fit_prepare() does everything that depends only on the scene, the views
 * used and the parameters (the precomputation); fit_run() applies it to one
 * set of paintings and is cheap.  A prepared fit is read-only during
 * fit_run, so several runs may share it.  Ownership: fit_prep owns its
 * samples, design, decomposition and operator; fit_prep_free accepts NULL
 * and half-built objects.  Thread-safety: no global state; a prepared fit
 * is read-only during fit_run, so any number of threads may run fits on
 * one prep at once; preparing or freeing one is its owner's. */
#ifndef GLINT_FIT_H
#define GLINT_FIT_H

#include "err.h"
#include "gbuf.h"
#include "hf.h"
#include "img.h"
#include "material.h"
#include "method_hf3.h"
#include "samples.h"
#include "scene.h"

/* fit_params and fit_params_default: method_hf3.h. */
typedef struct fit_prep {
    fit_params params;
    samples s;
    hf_design d;
    hf_decomp dc;
    hf_op op;
    int cache_hit;         /* 1 decomposition loaded, 0 built, -1 rebuilt (corrupt file) */
    char cache_key[33];
    double t_samples, t_design, t_decomp, t_op; /* seconds */
} fit_prep;

/* Prepare a fit of the views flagged in `use` (NULL: all) of scene `sc`
 * with G-buffers g (one per view).  cache_dir may be NULL (no disk cache). */
int fit_prepare(fit_prep *fp, const scene *sc, const gbuf *g, const unsigned char *use,
                const fit_params *p, const char *cache_dir, glint_err *err);

/* Fit one set of paintings (one img per scene view; unused views ignored).
 * OUT: *out, whose info holds parameters, precomputation report, timings
 * and errors on the painted samples.  `rgb` may be given instead of
 * paintings (3 * n sample values; then paintings is NULL). */
int fit_run(const fit_prep *fp, const img *paintings, const float *rgb, material *out,
            glint_err *err);

void fit_prep_free(fit_prep *fp);

/* Error of a material against reference images on the sample pixels
 * (mask, n.wi > 0, n.wo > 0) of nviews G-buffers: RMS and max |difference|
 * over pixels and RGB channels, radiance scaled by each view's light
 * intensity.  truth[v] must be sized like g[v] (1, 3 or 4 channels).
 * OUT: *rms, *max_abs, *count (pixels compared; any may be NULL). */
int fit_error_views(const material *m, const gbuf *g, const scene_view *views, int nviews,
                    const img *truth, double *rms, double *max_abs, long *count,
                    glint_err *err);

#endif
