/* srbf.h: the distribution-based BRDF of Iwasaki et al. 2009 (seed 004)
 * with p(h) a non-negative sum of spherical Gaussians, and what its fit
 * under environment light needs: the basis, the static terms, the energy
 * rows and the transfer matrices.
 *
 *   f(wi, wo) = rho_d / pi + p(h) s(wi, wo),   p(h) = sum_j c_j G(h . xi_j)
 *
 * Conventions (those of ../shared/reference/srbf_ref.py, SRBF_README.md):
 *  - Shading frame: t = normalize(+z x n), b = n x t, local z = n; at the
 *    poles (|+z x n| < 1e-9) t = normalize(+x x n).  Centres xi_j and the
 *    energy rows' outgoing directions are in this local frame; h is taken
 *    there as (h.t, h.b, h.n).
 *  - G(x) = exp(lambda (x - 1)), peak-normalized (G(1) = 1, c in 1/sr).
 *    sigma -> lambda by the coth reading of the paper's relation:
 *    sigma^2 = 1 - (coth(2 lambda) - 1/(2 lambda)); sigma = pi/40 gives
 *    lambda = 81.056947.  (The printed cosh gives 0.60: a flat basis.)
 *  - Centres: the pixel centres of a hemicube of resolution r, J = 3 r^2:
 *    the top face (u_a, u_b, 1), b outer, a inner; the side faces +x, +y,
 *    -x, -y in turn with rows of z > 0 in increasing z and columns
 *    counter-clockwise: +x (1, u_a, z), +y (-u_a, 1, z), -x (-1, -u_a, z),
 *    -y (u_a, -1, z); for odd r, every other horizon pixel (z = 0, ring
 *    index 0, 2, ...); u_a = -1 + (2a+1)/r; all normalized.  r = 7 gives the
 *    reference's 147 centres in its order.
 *  - Static terms s: SRBF_STATIC_PAPER is eq. 11, F(wi.h) / (a + b - ab)
 *    with a = wi.n, b = wo.n; SRBF_STATIC_SMITH is the microfacet term
 *    F(wi.h) G2(wi, wo) / (4 a b) with the height-correlated Smith-GGX G2
 *    of roughness alpha (then p(h) plays D(h)).  F is Schlick's with F0.
 *  - Energy rows (eq. 15 with the cosine of eqs. 10 and 13):
 *    g[l][j] = int G(h.xi_j) s(wi, wo_l) (wi.n) dwi over the hemisphere,
 *    so the directional albedo at wo_l is rho_d + sum_j g[l][j] c_j.
 *  - Transfer (eq. 6 / 21), per pixel i, light k and channel ch:
 *    T[ch][i][j] = sum_k V_ik power_k,ch max(0, n_i.d_k) s(d_k, wo_i)
 *                  G(h_ik . xi_j),
 *    E[i][ch] = (1/pi) sum_k V_ik power_k,ch max(0, n_i.d_k) (irradiance/pi),
 *    so a pixel renders as rho_d E + T c.
 *
 * Thread-safety: no global state; functions with nthreads use that many
 * threads of their own (<= 0: the machine's cores). */
#ifndef GLINT_SRBF_H
#define GLINT_SRBF_H

#include <stdint.h>

#include "cancel.h"
#include "env.h"
#include "err.h"

#define SRBF_MIN_RES 2
#define SRBF_MAX_RES 16           /* J up to 768 */
#define SRBF_MIN_SIGMA 0.005      /* radians */
#define SRBF_MAX_SIGMA 0.9         /* sigma^2 < 1: the relation has no root beyond */

typedef enum { SRBF_STATIC_PAPER = 0, SRBF_STATIC_SMITH = 1 } srbf_static_kind;

typedef struct srbf_static {
    srbf_static_kind kind;
    double f0;                    /* Schlick's F0, [0, 1] */
    double alpha;                 /* SMITH: GGX roughness of G2, (0, 1] */
} srbf_static;

typedef struct srbf_basis {
    int res;                      /* hemicube resolution r */
    int J;                        /* 3 r^2 */
    double sigma, lambda;
    double *xi;                   /* 3J unit centres, local frame */
} srbf_basis;

/* lambda for sigma (radians, SRBF_MIN_SIGMA..SRBF_MAX_SIGMA), by bisection
 * on the coth relation to 1e-12 relative; GLINT_ERANGE outside. */
int srbf_lambda(double sigma, double *lambda, glint_err *err);

/* The basis (OUT: *b, b->xi malloc'ed; srbf_basis_free). */
int srbf_basis_make(int res, double sigma, srbf_basis *b, glint_err *err);
void srbf_basis_free(srbf_basis *b);

/* The hemicube centres of resolution r (OUT: xi[3 * 3r^2]); returns J. */
int srbf_hemicube(int res, double *xi);

/* The local frame of a normal (OUT: t, b). */
void srbf_frame(const double n[3], double t[3], double b[3]);

/* s(wi, wo) for unit vectors in the local frame (z = n): 0 unless
 * wi.z > 0 and wo.z > 0. */
double srbf_static_eval(const srbf_static *s, const double wi[3], const double wo[3]);

/* p(h) for h in the local frame (OUT: rgb), c: 3 x J (channel-major). */
void srbf_p(const srbf_basis *b, const double *c, const double h[3], double rgb[3]);

/* The outgoing directions of the energy rows (local frame, unit): the
 * pixel centres of a hemicube of resolution 8 (192: the reference's N_l
 * rows, same order), then SRBF_ENERGY_FIB directions on a Fibonacci
 * spiral uniform in solid angle (between the hemicube's rows the albedo
 * of narrow lobes rises by up to 1%), then `grazing` rings of 64
 * directions at elevations 0.5, 2.5, 4.5, ... degrees, where the albedo
 * of narrow lobes peaks.  Returns the count; wo may be NULL to ask for it. */
#define SRBF_ENERGY_FIB 512
int srbf_energy_dirs(int grazing, double *wo);

/* The energy rows (OUT: g[nl * J]) at nl local outgoing directions wo by
 * quadrature over wi (Gauss-Legendre panels in cos theta graded toward the
 * horizon, [0, .02], [.02, .2], [.2, 1] with nq/4, nq/4, nq/2 nodes, x the
 * midpoint rule with 3 nq steps in phi; nq 8..1024, <= 0: 96).  Below
 * wo.n = 0.1 the nodes are half vectors instead (wi = 2 (wo.h) h - wo,
 * dwi = 4 (wo.h) dh): near a grazing wo, h swings across the hemisphere as
 * wi passes the mirror direction, which no grid in wi resolves.  Against
 * 288 nodes (tests/unit/test_srbf.c, sigma = pi/40): 1e-7 of the largest
 * entry above 5.7 degrees elevation, 2e-4 below; narrower lobes need more
 * nodes.  cancel (may be NULL) is asked between rows (cancel.h):
 * GLINT_ECANCELLED once it says to stop. */
int srbf_energy_rows(const srbf_basis *b, const srbf_static *s, int nl, const double *wo,
                     int nq, double *g, int nthreads, const glint_cancel *cancel,
                     glint_err *err);

/* Directional albedo of a fitted p at one local outgoing direction:
 * int f_spec (wi.n) dwi by the same quadrature (OUT: rgb, without rho_d). */
void srbf_albedo(const srbf_basis *b, const srbf_static *s, const double *c, const double wo[3],
                 int nq, double rgb[3]);

/* Transfer matrices and irradiance of npix pixels (world normals and
 * directions to the eye, 3 floats each) under lights, with visibility bits
 * (vis.h layout, VIS_WORDS(l->k) words per pixel) or NULL (every light
 * with n.d > 0 seen).  OUT: T[3 * npix * J] (channel, pixel, lobe),
 * E[npix * 3]; reach[J] (may be NULL): 1 where some pixel's T column is
 * above 1e-6 of the largest.  Counts of terms evaluated in *terms (may be
 * NULL).  cancel (may be NULL) is asked about every GLINT_CANCEL_WORK
 * light-lobe pairs (cancel.h): GLINT_ECANCELLED once it says to stop. */
int srbf_transfer(const srbf_basis *b, const srbf_static *s, int npix, const float *nrm,
                  const float *wo, const env_lights *l, const uint64_t *vis, float *T,
                  double *E, unsigned char *reach, int nthreads, long *terms,
                  const glint_cancel *cancel, glint_err *err);

#endif
