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
 * The joint refinement ("refine" sweeps, after the last product): with the
 * products fixed, every coefficient texel of every product is adjusted
 * together to minimize the model's own squared error over all samples,
 * sum_i |painting_i - sum_k c_k(uv_i) f_k(i)|^2, with the bilinear reads a
 * renderer makes and each coefficient kept in [0, 1]: projected coordinate
 * descent (Gauss-Seidel over texels and products, a convex problem, so
 * every sweep lowers the error), stopping after `refine` sweeps or when a
 * sweep gains less than 1e-4 of the error.  The greedy products leave
 * their texels fitted one at a time to a clamped residual; the refinement
 * lets them share the painting (tests/unit/test_maps.c prints both).
 * With smooth > 0 the refinement also minimizes
 * mu sum_k sum_{neighbouring texels t, t'} (c_k(t) - c_k(t'))^2, mu =
 * smooth times the mean data weight of a reached texel (sum of w^2 f^2
 * over its samples), and moves the texels no sample reaches with their
 * neighbours.  A texel sees a few directions only, and without it the
 * coefficients of five products fit those few: on 12 views of the sphere
 * at 64x64, held-out views (tests/unit/test_auto.c) went from 0.0285 to
 * 0.0101 RMS on a one-material painting and from 0.0079 to 0.0050 on soft
 * stripes of two colours with smooth 0.1 (the default), the painted views'
 * barely moving (0.0015 -> 0.0030, 0.0013 -> 0.0017).
 *
 * Back-fitting ("rounds", after the refinement): the greedy products were
 * each fitted to a clamped residual and never revisited.  A round refits
 * every product k in turn to what the others leave, divided by its own
 * coefficient, (painting - sum_{j != k} c_j f_j) / c_k, on the samples
 * where c_k >= MATMAP_BACKFIT_MIN_COEF (elsewhere the target is f_k's own
 * prediction, so those samples do not pull it), then refines the
 * coefficients again (MATMAP_ROUND_SWEEPS sweeps: the rounds iterate).  Rounds stop at `rounds` or when one gains less than
 * MATMAP_ROUND_MIN_GAIN.  On red plastic with gold stripes (12 views of
 * the sphere at 128^2, 5 products) the painted-view RMS went 0.021 -> 0.0085
 * with 6 rounds (the model's relative RMS 0.46 -> 0.18).
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
    int refine;        /* sweeps of the joint refinement, 0..MATMAP_REFINE_MAX (0: none) */
    int rounds;        /* back-fitting rounds, 0..MATMAP_ROUNDS_MAX (need refine > 0) */
    double smooth;     /* smoothness of the coefficients in the refinement, 0..MATMAP_SMOOTH_MAX */
} matmap_params;

#define MATMAP_SMOOTH_MAX 1e3

#define MATMAP_ROUNDS_MAX 50
/* Back-fitting: a product is refitted to the samples where its coefficient
 * is at least this; rounds stop when one lowers the model's relative RMS
 * by less than this fraction. */
#define MATMAP_BACKFIT_MIN_COEF 0.25
#define MATMAP_ROUND_MIN_GAIN 0.01
/* sweeps of the refinement within a round (at most `refine`) */
#define MATMAP_ROUND_SWEEPS 3

#define MATMAP_REFINE_MAX 200
/* The model's residual and the joint refinement need every product's
 * prediction at every sample: above this many bytes they are skipped (and
 * the result says so: model_rel_rms -1, refine "skipped: memory"). */
#define MATMAP_REFINE_MAX_BYTES ((size_t)512 << 20)

typedef struct matmap {
    int k, res;
    material comp[MATMAP_MAX];     /* the products, each a material of the prep's method */
    float *coef;                   /* k x res x res coefficient textures */
    double rel_rms[MATMAP_MAX + 1];/* the residual's relative RMS: [0] the painting, [i] after i */
    long clamped[MATMAP_MAX];      /* samples whose residual the texture took below 0 */
    const char *stop;              /* "tolerance", "components" or "no-gain" */
    /* the model's own residual, painting - sum c_k(uv) f_k (not clamped),
     * relative RMS before and after the joint refinement */
    double model_rel_rms[2];
    int refine_sweeps;             /* sweeps the refinement ran, all rounds (0: none) */
    int rounds;                    /* back-fitting rounds run */
    double round_rel_rms[MATMAP_ROUNDS_MAX + 1]; /* the model's after the refinement [0]
                                                    and after each round */
    const char *refine;            /* "done", "off" or "skipped: memory" */
    double seconds;
} matmap;

/* Where the products come from: a method's fit of painted values and its
 * prediction at the samples.  matmap_fit takes them from a prep; a method
 * built on material maps (method_maps.c) from the levels of its fit. */
typedef struct matmap_source {
    const samples *s;    /* the samples, with texture coordinates */
    /* fit values rgb[3 n] (per unit light) into a material */
    int (*fit)(void *cls, const float *rgb, material *out, glint_err *err);
    /* OUT f[3 n]: material m's value per unit light at every sample, NaN
     * where it models none */
    int (*predict)(void *cls, const material *m, float *f, glint_err *err);
    void *cls;
} matmap_source;

void matmap_params_default(matmap_params *mp);
/* The fit from any source (matmap_fit's rules). */
int matmap_fit_source(const matmap_source *src, const float *rgb, const matmap_params *mp,
                      matmap *out, glint_err *err);
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
