/* srbf_tool.c: recompute a problem exported by the reference
 * (../shared/reference/srbf_ref.py export) with glint's code and print the
 * differences as JSON (test_srbf_reference.py asserts them).
 *
 *   srbf_tool EXPORT_DIR ENVMAP_FILE
 *
 * Compared: the basis (lambda, centres), the environment's lat-long
 * compression at the reference's resolution (K lights, as many as
 * light_dirs.f64 holds: directions and powers, from ENVMAP_FILE read by
 * glint), the
 * energy rows g at the reference's outgoing directions, the transfer
 * matrices T and irradiance E of the reference's G-buffer under the
 * reference's lights, and the constrained fit per channel (lsq.h on the
 * reference's T, target B - rho_d E and rows g) against the reference's
 * cvxopt coefficients and objective. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "env.h"
#include "lsq.h"
#include "srbf.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static double *load(const char *dir, const char *name, size_t n)
{
    char path[2048];
    FILE *f;
    double *a = malloc(n * sizeof *a);
    snprintf(path, sizeof path, "%s/%s.f64", dir, name);
    if (!a || !(f = fopen(path, "rb")) || fread(a, sizeof *a, n, f) != n) {
        fprintf(stderr, "cannot read %zu values from %s\n", n, path);
        exit(2);
    }
    fclose(f);
    return a;
}

/* The number of 3-vectors in dir/name.f64, or -1. */
static long count3(const char *dir, const char *name)
{
    char path[2048];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s.f64", dir, name);
    if (stat(path, &st) || st.st_size % (3 * sizeof(double)))
        return -1;
    return (long)(st.st_size / (3 * sizeof(double)));
}

static double maxabs(const double *a, size_t n)
{
    double m = 0;
    for (size_t i = 0; i < n; i++)
        m = fmax(m, fabs(a[i]));
    return m;
}

int main(int argc, char **argv)
{
    enum { J = 147, NL = 192, N = 2644 };
    long nk;
    int K;
    const char *dir;
    srbf_basis b;
    srbf_static st = {SRBF_STATIC_PAPER, 0.25, 0.3};
    glint_err e;
    double rho[3] = {0.35, 0.25, 0.15};
    double *xi, *g, *wo_l, *ld, *lp, *n, *wo, *T, *E, *B, *cref, *gg, *Eg;
    float *nf, *wf, *Tg;
    double d_xi = 0, d_g, d_T = 0, d_E = 0, d_c = 0, d_obj = 0, d_ldir = 0, d_lpow = 0, cmax = 0;
    env_lights l;
    env_map m;

    if (argc < 3) {
        fprintf(stderr, "usage: srbf_tool EXPORT_DIR ENVMAP_FILE\n");
        return 2;
    }
    dir = argv[1];
    if ((nk = count3(dir, "light_dirs")) < 1 || nk > 65536) {
        fprintf(stderr, "%s/light_dirs.f64: not a list of directions\n", dir);
        return 2;
    }
    K = (int)nk;
    if (srbf_basis_make(7, M_PI / 40.0, &b, &e) || b.J != J) {
        fprintf(stderr, "basis: %s\n", e.msg);
        return 2;
    }
    xi = load(dir, "xi", 3 * J);
    g = load(dir, "g", (size_t)NL * J);
    wo_l = load(dir, "wo_l", 3 * NL);
    ld = load(dir, "light_dirs", 3 * K);
    lp = load(dir, "light_power", 3 * K);
    n = load(dir, "n", 3 * N);
    wo = load(dir, "wo", 3 * N);
    T = load(dir, "T", (size_t)3 * N * J);
    E = load(dir, "E", 3 * N);
    B = load(dir, "B_ggx", 3 * N);
    cref = load(dir, "c_cvxopt", 3 * J);
    for (int i = 0; i < 3 * J; i++)
        d_xi = fmax(d_xi, fabs(xi[i] - b.xi[i]));

    /* the environment compressed by glint, against the reference's lights */
    if (env_load(argv[2], &m, &e) || env_compress(&m, ENV_CUT_LATLONG, K, 0.0, 1.0, &l, &e)) {
        fprintf(stderr, "env: %s\n", e.msg);
        return 2;
    }
    for (int k = 0; k < K; k++)
        for (int c = 0; c < 3; c++) {
            d_ldir = fmax(d_ldir, fabs(l.dir[3 * k + c] - ld[3 * k + c]));
            d_lpow = fmax(d_lpow, fabs(l.power[3 * k + c] - lp[3 * k + c]));
        }
    d_lpow /= maxabs(lp, 3 * K);

    /* energy rows at the reference's directions, its quadrature (128 nodes) */
    gg = malloc((size_t)NL * J * sizeof *gg);
    if (srbf_energy_rows(&b, &st, NL, wo_l, 128, gg, 0, NULL, &e)) {
        fprintf(stderr, "energy: %s\n", e.msg);
        return 2;
    }
    d_g = 0;
    for (size_t i = 0; i < (size_t)NL * J; i++)
        d_g = fmax(d_g, fabs(gg[i] - g[i]));
    d_g /= maxabs(g, (size_t)NL * J);

    /* transfer under the reference's lights and G-buffer */
    env_lights_free(&l);
    l.k = K;
    l.dir = ld;
    l.power = lp;
    nf = malloc(3 * N * sizeof *nf);
    wf = malloc(3 * N * sizeof *wf);
    Tg = malloc((size_t)3 * N * J * sizeof *Tg);
    Eg = malloc(3 * N * sizeof *Eg);
    for (int i = 0; i < 3 * N; i++) {
        nf[i] = (float)n[i];
        wf[i] = (float)wo[i];
    }
    if (srbf_transfer(&b, &st, N, nf, wf, &l, NULL, Tg, Eg, NULL, 0, NULL, NULL, &e)) {
        fprintf(stderr, "transfer: %s\n", e.msg);
        return 2;
    }
    for (size_t i = 0; i < (size_t)3 * N * J; i++)
        d_T = fmax(d_T, fabs(Tg[i] - T[i]));
    d_T /= maxabs(T, (size_t)3 * N * J);
    for (int i = 0; i < 3 * N; i++)
        d_E = fmax(d_E, fabs(Eg[i] - E[i]));
    d_E /= maxabs(E, 3 * N);

    /* the fit per channel on the reference's T and g */
    for (int ch = 0; ch < 3; ch++) {
        double *H = calloc((size_t)J * J, sizeof *H), q[J], c[J], u[NL], f[N], ff = 0, oref = 0;
        const double *Tc = T + (size_t)ch * N * J;
        lsq_problem pr;
        lsq_result r;
        for (int i = 0; i < N; i++) {
            f[i] = B[3 * i + ch] - rho[ch] * E[3 * i + ch];
            ff += f[i] * f[i];
        }
        for (int a = 0; a < J; a++) {
            q[a] = 0;
            for (int i = 0; i < N; i++)
                q[a] += Tc[(size_t)i * J + a] * f[i];
            for (int bb = a; bb < J; bb++) {
                double s = 0;
                for (int i = 0; i < N; i++)
                    s += Tc[(size_t)i * J + a] * Tc[(size_t)i * J + bb];
                H[(size_t)a * J + bb] = H[(size_t)bb * J + a] = s;
            }
        }
        for (int l2 = 0; l2 < NL; l2++)
            u[l2] = 1.0 - rho[ch];
        pr = (lsq_problem){.n = J, .H = H, .q = q, .ff = ff, .m = NL, .G = g, .u = u};
        if (lsq_solve(&pr, LSQ_ENERGY, 0, NULL, c, &r, &e)) {
            fprintf(stderr, "solve: %s\n", e.msg);
            return 2;
        }
        for (int i = 0; i < N; i++) {
            double s = -f[i];
            for (int a = 0; a < J; a++)
                s += Tc[(size_t)i * J + a] * cref[(size_t)ch * J + a];
            oref += s * s;
        }
        {
            double og = 0;
            for (int i = 0; i < N; i++) {
                double s = -f[i];
                for (int a = 0; a < J; a++)
                    s += Tc[(size_t)i * J + a] * c[a];
                og += s * s;
            }
            d_obj = fmax(d_obj, (og - oref) / oref);
        }
        for (int a = 0; a < J; a++) {
            d_c = fmax(d_c, fabs(c[a] - cref[(size_t)ch * J + a]));
            cmax = fmax(cmax, fabs(cref[(size_t)ch * J + a]));
        }
        free(H);
    }
    printf("{\"lambda\": %.15g, \"xi_max_abs\": %.3g, \"light_dir_max_abs\": %.3g, "
           "\"light_power_rel\": %.3g, \"g_rel\": %.3g, \"T_rel\": %.3g, \"E_rel\": %.3g, "
           "\"c_rel\": %.3g, \"objective_rel\": %.3g}\n",
           b.lambda, d_xi, d_ldir, d_lpow, d_g, d_T, d_E, d_c / cmax, d_obj);
    return 0;
}
