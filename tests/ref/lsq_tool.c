/* lsq_tool.c: solve one constrained least-squares problem from a text file
 * with lsq.h, for the cross-check against cvxopt (test_lsq_cvxopt.py).
 *
 *   lsq_tool PROBLEM [REPEATS]
 *
 * PROBLEM: whitespace-separated numbers: n m mode (0 energy, 1 nonneg,
 * 2 none), then H (n x n, row-major), q (n), ff, G (m x n), u (m).
 * Prints one JSON object: status, objective, iterations, max_violation,
 * kkt_residual, active_rows, ms (the best time per solve over REPEATS), c,
 * and c_kept: the solution when the caller keeps the rows' check and
 * transpose and the factor of H (lsq_rows_check, lsq_factor), as a fit's
 * repaints do. */
#include <stdio.h>
#include <stdlib.h>

#include "clock.h"
#include "lsq.h"

static int rd(FILE *f, double *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (fscanf(f, "%lf", &v[i]) != 1)
            return -1;
    return 0;
}

int main(int argc, char **argv)
{
    FILE *f;
    int n, m, mode, reps = argc > 2 ? atoi(argv[2]) : 1;
    double *H, *q, *G, *u, *c, ff, best = 1e30;
    lsq_problem p;
    lsq_result r;
    lsq_work *w;
    glint_err e;

    if (argc < 2 || !(f = fopen(argv[1], "r"))) {
        fprintf(stderr, "usage: lsq_tool PROBLEM [REPEATS]\n");
        return 2;
    }
    if (fscanf(f, "%d %d %d", &n, &m, &mode) != 3 || n < 1 || m < 0) {
        fprintf(stderr, "bad header\n");
        return 2;
    }
    H = malloc((size_t)n * n * sizeof *H);
    q = malloc((size_t)n * sizeof *q);
    G = malloc(((size_t)m * n + 1) * sizeof *G);
    u = malloc(((size_t)m + 1) * sizeof *u);
    c = malloc((size_t)n * sizeof *c);
    if (rd(f, H, (size_t)n * n) || rd(f, q, n) || rd(f, &ff, 1) || rd(f, G, (size_t)m * n) ||
        rd(f, u, m)) {
        fprintf(stderr, "short problem file\n");
        return 2;
    }
    fclose(f);
    p = (lsq_problem){.n = n, .H = H, .q = q, .ff = ff, .m = m, .G = G, .u = u};
    w = lsq_work_new(n, m);
    for (int k = 0; k < (reps < 1 ? 1 : reps); k++) {
        double t0 = glint_now();
        if (lsq_solve(&p, (lsq_mode)mode, 0.0, w, c, &r, &e)) {
            printf("{\"error\": \"%s\"}\n", e.msg);
            return 1;
        }
        t0 = glint_now() - t0;
        best = t0 < best ? t0 : best;
    }
    printf("{\"status\": \"%s\", \"objective\": %.17g, \"iterations\": %d, \"max_violation\": "
           "%.17g, \"kkt_residual\": %.17g, \"active_rows\": %d, \"infeasible_row\": %d, "
           "\"ms\": %.6f, \"c\": [",
           lsq_status_name(r.status), r.objective, r.iterations, r.max_violation, r.kkt_residual,
           r.active_rows, r.infeasible_row, best * 1e3);
    for (int i = 0; i < n; i++)
        printf("%s%.17g", i ? ", " : "", c[i]);
    printf("], \"c_kept\": [");
    {
        double *gmax = malloc(((size_t)m + 1) * sizeof *gmax);
        double *Gt = malloc(((size_t)m * n + 1) * sizeof *Gt);
        double *R0 = malloc((size_t)n * n * sizeof *R0);
        if (!gmax || !Gt || !R0 || lsq_rows_check(G, m, n, gmax, Gt, &e) ||
            lsq_factor(H, n, R0, &e)) {
            printf("]}\n");
            fprintf(stderr, "kept rows or factor failed\n");
            return 1;
        }
        p.gmax = gmax;
        p.Gt = Gt;
        p.R0 = R0;
        if (lsq_solve(&p, (lsq_mode)mode, 0.0, w, c, &r, &e)) {
            printf("]}\n");
            fprintf(stderr, "solve with the kept factor: %s\n", e.msg);
            return 1;
        }
        for (int i = 0; i < n; i++)
            printf("%s%.17g", i ? ", " : "", c[i]);
        free(gmax);
        free(Gt);
        free(R0);
    }
    printf("]}\n");
    lsq_work_free(w);
    free(H);
    free(q);
    free(G);
    free(u);
    free(c);
    return 0;
}
