/* matmap.h: material maps (seed 000, section 4.2, equations 16-19): a
 * painting as a sum of products, f(x, uv) = sum_k c_k(uv) f_k(wi, wo), each
 * f_k one fit of a prepared method (the three-factor one: its cached
 * operator serves every iteration) and c_k a coefficient texture over the
 * surface's texture coordinates.
 *
 * The fit (matmap_fit) is iterative residual factorization.  Starting from
 * the painting, each iteration fits the residual r and predicts it at every
 * sample (prep_predict: f_k).  The coefficient texture c_k comes from one
 * of two rules:
 *   MATMAP_MERGE_MIN (seed 000): per sample the largest scale that keeps
 *     every channel of the residual non-negative (equation 18: c =
 *     min(1, r / f_k) over the channels), so the next residual can be
 *     factorized in log space again; the scales become a texture (uvtex:
 *     means where samples fall), one per view, merged by keeping the
 *     smallest value so that the component stays under every view.
 *   MATMAP_MERGE_LSQ (the default): per texel the least-squares scale of
 *     f_k to r over every sample in it, all views together, in [0, 1].
 * Texels no sample reaches are filled by push-pull.  The residual is then
 * r - c_k(uv) f_k, with c_k read back from the texture (bilinear, as a
 * renderer reads it); where it goes below 0 (interpolation, or the least
 * squares scale) it is clamped to 0, so that it stays factorizable, and the
 * samples are counted.  It stops when the residual's
 * relative RMS falls below a tolerance ("tolerance"), at the most
 * components ("components"), or when a component lowers it by less than
 * 0.1% ("no-gain"), and says which.
 *
 * Why least squares by default (tests/unit/test_matmap.c prints these:
 * relative RMS of the residual of red plastic with gold stripes, after one
 * and after five products): with the smallest-value rule, where the
 * three-factor fit overshoots in one view (grazing light), that view's
 * scale holds the texel down for every view: 0.105 -> 0.077 on one painted
 * view of the sphere, 0.70 -> 0.63 on twelve.  Least squares per texel:
 * 0.079 -> 0.028 on one view, 0.49 -> 0.11 on twelve.
 *
 * Conventions: textures as uvtex.h (res x res, row 0 at v = 0); lookups
 * bilinear between texel centres, clamped at the border.  Values per unit
 * light, sample-major RGB, as prep_fit takes them. */
#ifndef GLINT_MATMAP_H
#define GLINT_MATMAP_H

#include "err.h"
#include "material.h"
#include "prep.h"

#define MATMAP_MAX 32

enum { MATMAP_MERGE_LSQ = 0, MATMAP_MERGE_MIN = 1 };

typedef struct matmap_params {
    int components;    /* at most this many products, 1..MATMAP_MAX */
    int merge;         /* MATMAP_MERGE_LSQ (default) or MATMAP_MERGE_MIN */
    int res;           /* coefficient texture resolution, 1..UVTEX_MAX_RES */
    double tol;        /* stop below this relative RMS of the residual, >= 0 */
} matmap_params;

typedef struct matmap {
    int k, res;
    material comp[MATMAP_MAX];     /* the products, each a material of the prep's method */
    float *coef;                   /* k x res x res coefficient textures */
    double rel_rms[MATMAP_MAX + 1];/* the residual's relative RMS: [0] the painting, [i] after i */
    long clamped[MATMAP_MAX];      /* samples whose residual the texture took below 0 */
    const char *stop;              /* "tolerance", "components" or "no-gain" */
    double seconds;
} matmap;

void matmap_params_default(matmap_params *mp);
/* Fit the painted values rgb[3 n] (n: the prep's samples, which must carry
 * texture coordinates) with prep p's method.  OUT: *out (matmap_free).
 * GLINT_EINVAL: bad parameters, samples without texture coordinates, a
 * negative or non-finite painted value; the method's errors otherwise. */
int matmap_fit(const prep *p, const float *rgb, const matmap_params *mp, matmap *out,
               glint_err *err);
void matmap_free(matmap *m);
/* Component k's coefficient at (u, v). */
double matmap_coef(const matmap *m, int k, double u, double v);

#endif
