/* gltf_int.h: what gltf.c shares with gltf_bake.c (and the tests): the
 * direction pairs a fit runs over and the error of one (metallic,
 * roughness) with its best base colour.  Not part of gltf.h's contract.
 *
 * A gltf_pairs holds n direction pairs above the surface (n, wi, wo, their
 * cosines) and the radiance per unit light y to fit at each; S and s are
 * scratch for the roughness being tried (gltf.h's model: S = D G / (4 ci
 * co), s = (1 - |V.H|)^5).  Ownership: gltf_pairs_alloc allocates every
 * array, gltf_pairs_free releases them and accepts a zeroed or half-built
 * set.  Thread-safety: a set is written by one thread; gltf_pairs_error
 * writes only S and s. */
#ifndef GLINT_GLTF_INT_H
#define GLINT_GLTF_INT_H

#include "gltf.h"
#include "method_pbr.h"

typedef struct gltf_pairs {
    int n;                                   /* pairs kept (ci, co > 0, finite y) */
    int cap;                                 /* room */
    double (*nn)[3], (*wi)[3], (*wo)[3], *ci, *co, (*y)[3];
    double *S, *s;
} gltf_pairs;

/* Room for cap pairs (OUT: *P, zeroed first).  GLINT_ENOMEM. */
int gltf_pairs_alloc(gltf_pairs *P, int cap, glint_err *err);
void gltf_pairs_free(gltf_pairs *P);

/* The geometry of up to cap pairs: every (smp->n / cap)-th sample of smp
 * (its n, wi, wo), or with smp NULL the GLTF_FIT_LIGHTS x GLTF_FIT_VIEWS
 * pairs over the hemisphere about +z, every (GLTF_FIT_PAIRS / cap)-th of
 * them.  Pairs with a light or eye at or below the horizon are dropped;
 * with fn set, so are pairs whose value is not finite, and y is filled
 * (fn NULL: y is left 0 for the caller).  OUT: P->n. */
void gltf_pairs_fill(gltf_pairs *P, const samples *smp, int cap, gltf_fn fn, const void *ctx);

/* S and s of the pair (ci, co > 0) at GGX alpha (gltf.h's model). */
void gltf_spec_terms(double alpha, const double n[3], const double wi[3], const double wo[3],
                     double ci, double co, double *S, double *s);

/* The squared error over the pairs of metallic m with the specular terms
 * S[i], s[i] (of the roughness tried) and the best base colour in [0, 1]^3
 * for them (OUT: base).  y of P; S, s may be any arrays of P->n. */
double gltf_pairs_error(const gltf_pairs *P, const double *S, const double *s, double m,
                        double base[3]);

/* The relative RMS of p's f cos against y over P's pairs: by gltf_brdf
 * (smith GLTF_SMITH_SEPARABLE) or gltf_khr_brdf_smith (the other form). */
double gltf_pairs_rel_rms(const gltf_pairs *P, const gltf_pbr *p, int smith);

/* pm's parameters as the KHR model's (gltf_direct.c says how): OUT
 * out->base, metallic, roughness, khr and note (cleared first); the rest of
 * *out untouched.  coat: with two lobes, the sharper as the clearcoat (1)
 * or left out (0). */
void gltf_direct_map(const pbr_material *pm, int coat, gltf_pbr *out);

/* After the fit in *out: when m is a pbr material (pbr, pbr_env, or
 * pbr_detail's base), its mapping, measured over the fit's pairs at smp,
 * replaces the fit unless its relative RMS is above the fit's.  Sets
 * out->rel_rms_fitted, rel_rms_exact (NaN: no mapping), exact, note. */
int gltf_direct_choose(const material *m, const samples *smp, gltf_pbr *out, glint_err *err);

#endif
