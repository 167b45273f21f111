/* method_auto_env.h: "auto_env", the model a painting made under an
 * environment requires: the choice of method_auto.h for the methods lit by
 * an environment.
 *
 * The candidates, simplest first, each at the settings a fit of its own
 * would have (the environment, its turn, brightness, the lights it is
 * compressed into and self-shadowing are auto_env's, shared):
 *   pbr_env             one lobe, a dielectric (method_pbr_env.h)
 *   pbr_env conductor   one lobe, a metal's reflectance per channel
 *   pbr_env two lobes   a sharp highlight over a broad sheen, dielectric
 *   pbr_tab_env         pbr_env times a painted table over half and
 *                       difference angles (method_pbr_tab_env.h)
 *   pbr_tab_env two     the same on a two-lobe base
 *   srbf                the SRBF lobes of Iwasaki et al. (method_srbf.h)
 *
 * Held out: one painted view in `every` (the views at every/2, every/2 +
 * every, ... of the painted ones; at least one, at least one kept), whole;
 * with one view painted, the band of its covered columns farthest to the
 * right, one in `every` (normals the kept pixels lack, as a new view shows
 * them; scattered tiles, as method_auto.h holds out, measure
 * interpolation, and a band of grazing pixels asked the table candidates
 * for difference angles beyond the fitted ones: method_auto_env.c says
 * what each chose).  There are no lights beyond the painted
 * range to hold out: the light is the environment, the same in every view.
 * The hold-out is made `folds` times (default 2), each holding other
 * samples out: the views before those of the first in turn (with two
 * painted views, each in turn; fewer hold-outs when fewer views are
 * painted), or the one view's right, left, bottom and top bands; every
 * candidate is fitted to each hold-out's kept samples and judged by its
 * RMS over all the held-out samples together.  On the 14 measured
 * materials of BENCHMARKS.md (bench_env_measured --every 4 --set
 * folds=N), one hold-out against two: from one view new views 23.2%
 * against 18.6% median (rotated 12.0%, other environment 14.2% both);
 * from three views rotated 9.6% against 7.3% (new views 31.0% against
 * 31.3%, other environment 12.3% both).  Three from three views chose
 * as two did; four from one view changed four choices, two for the
 * better and two for the worse (the same medians; 90th percentile on new
 * views 57.1% against 45.7%), at 1.7 times two's cost.
 *
 * Every candidate reads the same levels as a fit of its own (the same
 * cache keys, in memory and on disk): pbr_env's lights, rows and terms
 * (shared by its three variants and pbr_tab_env's two) and srbf's energy, lights (pbr_env's, the
 * same key), rows and transfer, all on every sample.  A candidate is
 * fitted with the held-out samples left out (method_fit_in.held: both
 * methods honour it, so nothing is prepared twice), and measured on them
 * with its own prediction (method.predict: the material under the
 * environment's lights with the pixel's visibility), RMS in the
 * painting's units over the held-out samples each method models (its own
 * raster's pixels: pbr_env's 64 x 48 and srbf's 160 x 120 of each held
 * view).  The choice starts at the first (`start` simplest), or from
 * pbr_tab_env on two lobes where its held-out RMS is no worse than the
 * first's (`start` correction; `views`, the default: correction when one
 * view is painted, simplest otherwise); every other candidate replaces
 * the current choice when its held-out RMS is below the current choice's
 * by more than `threshold` (a fraction) and `floor` times the painting's
 * RMS (1e-3; reported as floor_value), so the answer is never worse on
 * the held-out samples than the simplest.  Why one view starts from the
 * correction: its held-out bands are pixels of the painted view, which
 * rank the candidates' new views poorly, and the correction is the best
 * single method from one view.  On the 14 measured materials of
 * BENCHMARKS.md and the 14 others from the third, medians of new views,
 * rotated and other environment from one view: 15.2%, 10.7%, 14.9% and
 * 27.0%, 20.4%, 18.8% against the simplest start's 18.6%, 12.0%, 14.2%
 * and 40.1%, 19.9%, 27.5%; from three views the correction start was
 * worse on new views on both (35.8% against 31.3%, 39.3% against 33.6%),
 * so three views keep the simplest.  The material is the chosen candidate refitted
 * to every painted sample; info.choice lists every candidate's held-out
 * and painted RMS, fit time, its parameters and whether it was taken.
 *
 * The auto_env method makes no material of its own (method.mat is NULL).
 * Thread-safety: as method.h. */
#ifndef GLINT_METHOD_AUTO_ENV_H
#define GLINT_METHOD_AUTO_ENV_H

#include "method.h"
#include "method_srbf.h"

extern const method method_auto_env;

typedef struct auto_env_params {
    /* env, env_rotation, env_intensity, lights and visibility, given to
     * every candidate (the rest of srbf's members unused) */
    srbf_params env;
    double threshold;  /* fraction a later candidate must gain on held-out samples */
    double floor;      /* and at least this fraction of the painting's RMS */
    int every;         /* one view (or a band of the one view) in this many held out */
    int folds;         /* hold-outs the candidates are judged on together (1-4) */
    int start;         /* AUTO_ENV_START_*: the candidate the others must beat */
} auto_env_params;

enum { AUTO_ENV_START_VIEWS, AUTO_ENV_START_SIMPLEST, AUTO_ENV_START_CORRECTION };

#endif
