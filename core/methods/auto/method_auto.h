/* method_auto.h: "auto", the model a painting requires (seed 000 offers
 * the models; the choice among them is glint's).
 *
 * One painted view in `every` is held out (the views at every/2,
 * every/2 + every, ... of the painted ones: lights and directions inside
 * the painted range), and with four or more painted also the view whose
 * light lies farthest from its eye (the smallest mean wi.wo): a light
 * beyond the range the others paint.  At least two views are kept.  With
 * one view painted, one tile of 8x8 pixels in `every` (a hash of the
 * tile: the same split for every painting of a pattern).  The candidates,
 * cheapest first, each at the settings a fit of its own would have, are
 * fitted to the rest:
 *   hf3   one material (method_hf3.h)
 *   pbr   one physically based material: Lambert + GGX (method_pbr.h),
 *         which extrapolates to new light by construction
 *   pbr_detail  pbr times a three-factor detail of what it leaves
 *         (method_pbr_detail.h; pbr's level and hf3's, shared)
 *   tab   an isotropic BRDF tabulated over the half and difference angles
 *         with a smoothness prior (method_tab.h)
 *   tab_prior  that table continued along theta_d as measured materials go
 *         on (method_tab_prior.h; tab's levels shared): a candidate only
 *         where the host has the measured materials' fits, otherwise listed
 *         with "skipped" and the reason (learning from the materials
 *         params.learn_exclude names left out)
 *   pbr_tab  pbr corrected by such a table, pulled back to pbr where no
 *         painted sample reaches (method_pbr_tab.h; pbr's level and tab's
 *         design, shared)
 *   hf2d  one material whose q is 2D over the half vector's parabolic map:
 *         a highlight that depends on direction around the normal
 *         (method_hf2d.h)
 *   hf4   one material times a spatial factor s(u, v) (method_hf4.h)
 *   maps  a sum of products weighted by coefficient textures (method_maps.h)
 *   hybrid  maps whose products are hf4's (method_hybrid.h)
 *   pbr_maps  maps whose products are pbr materials, one holding at each
 *         texel (method_pbr_maps.h; pbr's level, shared)
 * and each is measured on the held-out pixels (RMS, per unit light, RGB,
 * the material evaluated at each pixel's texture coordinates; pooled, and
 * apart for the views inside the range and the one beyond it).  A
 * candidate is judged by the geometric mean of those two parts when both
 * are held out (so that the beyond view, whose error is the larger, does
 * not hide a gain on new views), else by the pooled RMS.  The choice
 * starts at hf3; a richer candidate replaces it only when its judged RMS
 * is below the current choice's by more than `threshold` (a fraction) and
 * by more than `floor` times the painting's RMS (1e-3 by default: a
 * smaller gain is noise; an absolute floor, a quarter of an 8-bit step per
 * unit light, held every dark measured material at hf3).  Held-out views are the
 * measure that matters: on held-out pixels of painted views a spatial
 * model fills a pixel from its painted neighbours, and on a uniform
 * painting of 12 views hf4 and maps fit the painted views 2-5 times
 * better than hf3 and the held-out views worse or barely better
 * (tests/unit/test_auto.c prints every candidate).
 * pbr, pbr_detail, tab, tab_prior, pbr_tab, hf2d, hf4, maps, hybrid and pbr_maps are alternatives, not
 * steps of one chain, so each is measured against the choice so far; every take lowers
 * the judged RMS, so the answer is never worse on the held-out samples, so
 * judged, than hf3, the simplest.  The material is the chosen
 * method refitted to every painted sample, held-out ones included (its
 * manifest names that method); info.choice lists
 * every candidate's held-out and painted RMS, fit time and whether it was
 * taken, and info.chosen_params its parameters.
 *
 * Levels: split; on the kept pixels (a pattern of its own: samples_pick)
 * hf3's decomposition and operator and hf4's decomposition (maps reuses
 * hf3's, hybrid hf4's); then the same three on every sample, keyed and
 * built as hf3 and hf4 key and build them (the same cache entries, on disk
 * too, as a direct fit of either), for the refit; hf2d's decomposition on
 * the kept pixels and on every sample likewise, and pbr's one level (its
 * per-sample angles) and tab's two (its design and operator) too, and
 * tab_prior's learned prior (one level: it depends on no pattern).  The
 * auto method makes
 * no material of its own (method.mat is NULL). */
#ifndef GLINT_METHOD_AUTO_H
#define GLINT_METHOD_AUTO_H

#include "method.h"
#include "method_tab_prior.h"

extern const method method_auto;

typedef struct auto_params {
    int res;           /* texels per 1D factor, every candidate */
    int sres;          /* hf4's (and hybrid's) spatial nodes per side */
    int res_2d;        /* hf2d's q nodes per side */
    int components;    /* maps' and hybrid's most products */
    double threshold;  /* fraction a richer model must gain on held-out pixels */
    double floor;      /* and at least this fraction of the painting's RMS */
    int every;         /* one pixel in this many held out */
    char learn_exclude[TAB_PRIOR_EXCLUDE_MAX]; /* tab_prior's params.exclude */
} auto_params;

#endif
