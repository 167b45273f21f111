/* mpi_compare: compare two hf3 decompositions stored under one key in two
 * cache directories (pcache.h), e.g. the single-process route's and
 * glint-mpi's, through the operators they give.
 *
 *   mpi_compare DIR_A DIR_B KEY
 *
 * Checks: the same sizes (res, n, samples), the same decisions (rank,
 * gauge, null and barely reached directions); singular values to
 * 64 n eps relative to s_max (the eigensolvers' backward error on
 * B^T B, |d s| <= n eps s_max^2 / (2 s)); the operator
 * M = V diag(1 / s^2) V^T (trunc:full) to
 *     ||M_A - M_B||_F / ||M_A||_F <= 64 n eps (s_max / s_min)^2,
 * the perturbation bound of a symmetric inverse whose matrix moved by
 * n eps ||B^T B|| (the sums are taken in another order).  Prints the
 * figures as one JSON line; exit 0 when within tolerance, 1 when not,
 * 2 on an unreadable file. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "hf.h"
#include "pcache.h"

int main(int argc, char **argv)
{
    hf_decomp a, b;
    hf_op oa, ob;
    hf_reg reg;
    glint_err e;
    double num = 0.0, den = 0.0, ds = 0.0, rel, tol_m, tol_s;
    int ok;

    if (argc != 4) {
        fprintf(stderr, "usage: mpi_compare DIR_A DIR_B KEY\n");
        return 2;
    }
    if (pcache_decomp_load(argv[1], argv[3], &a, &e) ||
        pcache_decomp_load(argv[2], argv[3], &b, &e)) {
        fprintf(stderr, "mpi_compare: %s\n", e.msg);
        return 2;
    }
    if (a.res != b.res || a.n != b.n || a.nsamples != b.nsamples || a.rank != b.rank ||
        a.gauge_dims != b.gauge_dims || a.null_dims != b.null_dims ||
        a.weak_dims != b.weak_dims) {
        printf("{\"same_decisions\": false, \"res\": [%d, %d], \"samples\": [%d, %d], "
               "\"rank\": [%d, %d], \"null\": [%d, %d], \"weak\": [%d, %d]}\n", a.res, b.res,
               a.nsamples, b.nsamples, a.rank, b.rank, a.null_dims, b.null_dims, a.weak_dims,
               b.weak_dims);
        return 1;
    }
    for (int k = 0; k < a.rank; k++)
        if (fabs(a.s[k] - b.s[k]) > ds)
            ds = fabs(a.s[k] - b.s[k]);
    if (hf_reg_parse("trunc:full", &reg, &e) || hf_op_build(&a, &reg, HF_F64, &oa, &e) ||
        hf_op_build(&b, &reg, HF_F64, &ob, &e)) {
        fprintf(stderr, "mpi_compare: %s\n", e.msg);
        return 2;
    }
    for (size_t i = 0; i < (size_t)a.n * a.n; i++) {
        double d = oa.M[i] - ob.M[i];
        num += d * d;
        den += oa.M[i] * oa.M[i];
    }
    rel = sqrt(num / den);
    tol_m = 64.0 * a.n * DBL_EPSILON * (a.s[0] / a.s[a.rank - 1]) * (a.s[0] / a.s[a.rank - 1]);
    tol_s = 64.0 * a.n * DBL_EPSILON * a.s[0] * a.s[0] / a.s[a.rank - 1];
    ok = rel <= tol_m && ds <= tol_s;
    printf("{\"same_decisions\": true, \"rank\": %d, \"samples\": %d, \"s_max\": %.6g, "
           "\"s_min\": %.6g, \"s_abs_diff\": %.3g, \"s_tol\": %.3g, \"op_rel_diff\": %.3g, "
           "\"op_tol\": %.3g, \"ok\": %s}\n", a.rank, a.nsamples, a.s[0], a.s[a.rank - 1], ds,
           tol_s, rel, tol_m, ok ? "true" : "false");
    hf_op_free(&oa);
    hf_op_free(&ob);
    hf_decomp_free(&a);
    hf_decomp_free(&b);
    return ok ? 0 : 1;
}
