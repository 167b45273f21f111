/* readable.h: a fitted material in words and numbers an artist reads
 * (BRDF Explorer's plots, Substance's parameters), from the material's own
 * evaluation (material_eval), so that every method gets the same summary.
 *
 * Conventions
 *  - The surface is the plane z = 0 with n = +Z; the plane of incidence is
 *    x-z (the light at azimuth 0, the mirror direction at azimuth 180
 *    degrees).  For a material whose factors depend on direction around
 *    the normal (hf2d) this plane runs along t = +X (vec3.h: the frame's
 *    pole fallback).  Spatially varying materials are read at their
 *    average over the surface (uv NULL).
 *  - f is the BRDF (per steradian): the material's value divided by n.wi
 *    (a painted value is pi I f n.wi, scene.h).
 *  - base_colour = pi f with the light and the eye both at 45 degrees on
 *    the same side (the half vector 45 degrees off the normal, away from
 *    any highlight but the widest): a Lambertian surface of albedo kd
 *    reads kd.
 *  - highlight, light at 30 degrees: peak = f at the mirror direction;
 *    strength = (peak - base) / base in luminance (Rec. 709 weights); the
 *    half width at half maximum of peak - base, in degrees, scanning the
 *    eye away from the mirror direction in the plane of incidence in steps
 *    of 0.25 degrees towards the horizon (null when the highlight is under
 *    5% of the base, or does not fall to half before the eye is at 85
 *    degrees).
 *  - albedo(theta_i) = integral over the hemisphere of f cos(theta_o),
 *    midpoint rule on READABLE_ALBEDO_THETA x 2 READABLE_ALBEDO_THETA
 *    cells of (theta_o, phi_o) (error under 1% for lobes wider than about
 *    0.1 rad; tests/unit/test_readable.c); above 1 the material reflects
 *    more than it receives at that angle.
 *  - polar: f in the plane of incidence for lights at 15, 45 and 75
 *    degrees, the eye from -85 (towards the light's side) to 85 degrees in
 *    steps of 5, as BRDF Explorer's polar plot shows it.
 * Thread-safety: reads the material only. */
#ifndef GLINT_READABLE_H
#define GLINT_READABLE_H

#include <jansson.h>

#include "err.h"
#include "material.h"

#define READABLE_ALBEDO_THETA 32

/* The summary as a new JSON object (OUT: *out). */
int material_readable(const material *m, json_t **out, glint_err *err);

/* The directional albedo of m for a light theta_i radians off the normal,
 * over an nt x 2 nt midpoint grid (OUT: rgb[3]). */
void material_albedo(const material *m, double theta_i, int nt, double rgb[3]);

#endif
