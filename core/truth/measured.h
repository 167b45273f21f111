/* measured.h: measured materials as published analytic fits, truths to
 * paint with where no MERL table is at hand.
 *
 * A fits file (../shared/data/measured/merl56_fits.json; its README.md is
 * the definition followed here) holds, per material of the MERL database,
 * the parameters of two published fits:
 *   abc  Low, Kronander, Ynnerman and Unger 2012 (microfacet variant):
 *        f = kD/pi + F(cos_d) D G / (pi ci co),
 *        D = A / (1 + B (1 - cos_h))^C (A per channel), G the Cook-Torrance
 *        V-groove min(1, 2 cos_h ci / cos_d, 2 cos_h co / cos_d), F the
 *        exact unpolarized Fresnel reflectance of a dielectric of index ior
 *        (1 where ior^2 - 1 + cos_d^2 <= 0);
 *   sgd  Bagher, Soler and Holzschuch 2012 (shifted gamma distribution),
 *        per channel: f = (rhoD + rhoS F D G / (ci co)) / pi,
 *        D = kap exp(-s) / (pi s^p cos_h^4), s = alpha + tan^2(th_h) / alpha,
 *        F = f0 - f1 cos_d + (1 - f0)(1 - cos_d)^5, G = G1(th_i) G1(th_o),
 *        G1(t) = clamp(1 + lambda (1 - exp(c max(0, t - theta0)^k)), 0, 1)
 *        (t in radians; where c max(..)^k overflows exp, G1 is its limit:
 *        0 for lambda > 0).
 * Directions point away from the surface, h = normalize(wi + wo),
 * cos_h = n.h, cos_d = wi.h, ci = n.wi, co = n.wo; f is RGB, per steradian
 * (no cosine), MERL's per-channel scale included, and 0 unless ci > 0 and
 * co > 0.  Both fits are evaluated exactly as published: no renormalization
 * (chrome's sgd lobe integrates to 0.37/0.60/0.30, not 1) and no clamping.
 *
 * Specs: "sgd:NAME" and "abc:NAME" name one fit of one material of the
 * host's fits file (measured_set_file), wherever an analytic truth or
 * "merl:FILE" is accepted (paint, base renders, previews' references).
 *
 * Thread-safety: a measured_set is read-only once loaded; the process's
 * file is set before threads start and read once, under a lock, on first
 * use; a measured_truth is a small value (no pointers; copy it freely) and
 * its evaluation is pure. */
#ifndef GLINT_MEASURED_H
#define GLINT_MEASURED_H

#include <jansson.h>

#include "err.h"

/* The file a host's measured directory holds (glintd --measured-dir, the
 * command line's $GLINT_MEASURED_DIR). */
#define MEASURED_FITS_FILE "merl56_fits.json"
#define MEASURED_NAME_MAX 64     /* a name's bytes, with its terminator */
#define MEASURED_MAX 1024        /* materials in one file */

typedef struct measured_abc {
    double kd[3], a[3], b, c, ior;
} measured_abc;

typedef struct measured_sgd {
    double rho_d[3], rho_s[3], alpha[3], p[3], f0[3], f1[3], kap[3], lambda[3], c[3], k[3],
        theta0[3];
} measured_sgd;

typedef struct measured_material {
    char name[MEASURED_NAME_MAX];  /* [a-z0-9._-], unique in its file */
    measured_abc abc;
    measured_sgd sgd;
} measured_material;

typedef struct measured_set {
    measured_material *m;          /* n materials, in the file's order (malloc'ed) */
    int n;
} measured_set;

/* ---- the file ------------------------------------------------------------------------ */

/* Read a fits document: {"materials": [{"name", "abc": {kD[3], A[3], B, C,
 * ior}, "sgd": {rhoD[3], rhoS[3], alpha[3], p[3], f0[3], f1[3], kap[3],
 * lambda[3], c[3], k[3], theta0[3], error[3] (optional, unused)}}, ...]}
 * (other top-level members ignored).  Every field is checked: present, of
 * its type and length, finite, in its range (kD, A, rhoD, rhoS, lambda,
 * c >= 0; B, C, alpha, kap, k > 0; ior > 0), no other member in a
 * material, names valid and unique; GLINT_EFORMAT names the material and
 * field otherwise ("merl56_fits.json: materials[3] (aventurnine): sgd.kap[1]
 * must be > 0, got -2").  `file` names the source in messages.  OUT: *out
 * (measured_free). */
int measured_parse(const char *text, size_t len, const char *file, measured_set *out,
                   glint_err *err);
int measured_from_json(const json_t *root, const char *file, measured_set *out, glint_err *err);
/* measured_parse of a file's contents (GLINT_EIO when unreadable). */
int measured_load(const char *path, measured_set *out, glint_err *err);
/* Accepts NULL and a zeroed set; leaves it zeroed. */
void measured_free(measured_set *s);
/* By name; NULL when absent. */
const measured_material *measured_find(const measured_set *s, const char *name);

/* ---- truths --------------------------------------------------------------------------- */

typedef enum { MEASURED_ABC = 0, MEASURED_SGD = 1 } measured_model;

typedef struct measured_truth {
    measured_model model;
    char name[MEASURED_NAME_MAX];
    measured_abc abc;              /* the model's parameters (the other one unused) */
    measured_sgd sgd;
} measured_truth;

/* One fit of one material of s. */
void measured_truth_of(const measured_material *m, measured_model model, measured_truth *out);

/* f at unit n, wi, wo (OUT: rgb[3], per steradian, no cosine; 0 below
 * either horizon).  Isotropic: no tangent frame. */
void measured_eval(const measured_truth *t, const double n[3], const double wi[3],
                   const double wo[3], double rgb[3]);

/* sgd's distribution term D of channel c at cos_h in (0, 1] (per
 * steradian of half vectors; for tests of its normalization). */
double measured_sgd_d(const measured_sgd *p, int c, double cos_h);

/* measured_eval as paint.h's paint_fn (ctx: const measured_truth *). */
void measured_truth_fn(const void *ctx, const double n[3], const double wi[3],
                       const double wo[3], double f[3]);
/* measured_eval times n.wi, as envlit.h's envlit_fn (ctx: const measured_truth *). */
void measured_envlit(const void *ctx, const double uv[2], const double n[3], const double wi[3],
                     const double wo[3], double rgb[3]);

/* ---- the process's fits file and specs -------------------------------------------------- */

/* Where "sgd:NAME" and "abc:NAME" find their parameters: a fits file
 * (NULL or "": none), read on first use.  `hint` (may be NULL) ends the
 * message of a spec used when there is none ("glintd --measured-dir").
 * Call before threads start; a new file drops the one read. */
void measured_set_file(const char *path, const char *hint);

/* How many times measured_set_file was called: what a cache of something
 * made from the process's set keys on. */
unsigned measured_generation(void);

/* The process's set (OUT: *out, valid until measured_set_file): read on
 * first use; GLINT_ENOTFOUND when no file is set, the file's error
 * otherwise (a later call reads it again). */
int measured_current(const measured_set **out, glint_err *err);

/* 1 when spec names a measured fit ("sgd:..." or "abc:..."), else 0. */
int measured_spec_is(const char *spec);

/* Parse "sgd:NAME" or "abc:NAME" against the process's set (OUT: *out):
 * GLINT_ENOTFOUND for an unknown name (the message says how many there
 * are and where they come from) or when no file is set, GLINT_EINVAL for
 * a spec that is not a measured one. */
int measured_truth_parse(const char *spec, measured_truth *out, glint_err *err);

#endif
