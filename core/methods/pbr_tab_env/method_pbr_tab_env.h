/* method_pbr_tab_env.h: the pbr_tab_env method: pbr_tab's material (a
 * physically based base times a table over half and difference angles,
 * method_pbr_tab.h) fitted to views painted under an environment.
 *
 * Conventions.  As pbr_env's (method_pbr_env.h): a fitted pixel (a row)
 * is lit by the lights above its horizon that it sees, and its painted
 * radiance over the environment's intensity is
 *
 *   b_c = sum over its lights k of  P_kc f_base_c(wi_k, wo) (n.wi_k) max(r_c(theta_h,k, theta_d,k), 0)
 *
 * f_base the pbr_env fit of the same rows, r a table per channel on tab.h's
 * grid (bilinear in sqrt(theta_h) and theta_d).  b is linear in r, each
 * row summing its lights' cells, so r is the minimizer of tab.h's
 * tab_solve_rows problem: the squared error over the rows normalized by
 * the mean square of the base's values, lambda times the table's squared
 * second differences, pull ||r - 1||^2, r >= 0.  Where the rows' lights
 * reach the table follows the painting; where none does (directions no
 * painted pixel's lights and eye make), the pull returns r to 1 and the
 * material to its physical base.
 *
 * Why multiply, where pbr_tab adds: under point lights a row is one cell
 * and an added table fits the base's residual cell by cell; under an
 * environment a row sums a hundred cells, and the added table's rows
 * (P ci, without the base's shape) leave the highlight's cells to be set
 * by many rows' differences.  On four measured materials painted under
 * the courtyard (bench_env_measured --every 14, truths with the fit's own
 * 256 lights) the multiplied table's new-view errors were 2.9%, 17.7%,
 * 3.9% and 66.5% against the added one's 35.5%, 25.4%, 19.0% and 33.6%.
 *
 * The material is pbr_tab's (combine multiply): the same manifest, files,
 * shader and exports.
 *
 * Levels: pbr_env's (lights, rows, pbr-env-terms) under pbr_env's keys, so
 * a pbr_env fit of the same views shares them.  The table's Gram matrices
 * depend on the base, so they are summed in the fit: rows x nodes^2
 * multiply-adds a channel (BLAS dsyrk).
 *
 * The material's info: "params", "base" (pbr_env's report), "correction"
 * (nodes, reached, the solve's iterations and nodes at 0, the table's
 * range over the reached nodes, rms_painted_base and rms_painted),
 * "errors" (rms_painted, rms_by_view, in the painting's units),
 * "precomputation", "seconds".
 *
 * Thread-safety: as method.h. */
#ifndef GLINT_METHOD_PBR_TAB_ENV_H
#define GLINT_METHOD_PBR_TAB_ENV_H

#include "method.h"
#include "method_pbr_env.h"
#include "method_tab.h"

extern const method method_pbr_tab_env;

typedef struct pbr_tab_env_params {
    pbr_env_params base;  /* the environment, the rows and the physical fit */
    tab_params tab;       /* the grid and lambda (nonneg: always) */
    double pull;          /* to 1 where the rows say nothing */
} pbr_tab_env_params;

#endif
