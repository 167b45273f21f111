/* readable.c: a fitted material summarized for people (readable.h). */
#include "readable.h"

#include <math.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define DEG (M_PI / 180.0)

static const double N_UP[3] = {0.0, 0.0, 1.0};

/* Unit direction at theta off +Z, azimuth phi. */
static void dir(double theta, double phi, double d[3])
{
    d[0] = sin(theta) * cos(phi);
    d[1] = sin(theta) * sin(phi);
    d[2] = cos(theta);
}

/* f (the BRDF) of m for a light at (ti, 0) and the eye at (to, po). */
static void brdf_at(const material *m, double ti, double to, double po, double f[3])
{
    double wi[3], wo[3], ci;
    dir(ti, 0.0, wi);
    dir(to, po, wo);
    material_eval_at(m, NULL, N_UP, wi, wo, f);
    ci = cos(ti);
    for (int c = 0; c < 3; c++)
        f[c] = ci > 0.0 ? f[c] / ci : 0.0;
}

static double lum(const double v[3])
{
    return 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
}

void material_albedo(const material *m, double theta_i, int nt, double rgb[3])
{
    double dt = 0.5 * M_PI / nt, dp = M_PI / nt;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (int a = 0; a < nt; a++) {
        double to = (a + 0.5) * dt, w = cos(to) * sin(to) * dt * dp;
        for (int b = 0; b < 2 * nt; b++) {
            double f[3];
            brdf_at(m, theta_i, to, (b + 0.5) * dp, f);
            for (int c = 0; c < 3; c++)
                rgb[c] += f[c] * w;
        }
    }
}

static json_t *rgb_json(const double v[3])
{
    return json_pack("[f,f,f]", v[0], v[1], v[2]);
}

int material_readable(const material *m, json_t **out, glint_err *err)
{
    static const double albedo_deg[4] = {0.0, 30.0, 60.0, 75.0};
    static const double polar_deg[3] = {15.0, 45.0, 75.0};
    double base[3], basef[3], peak[3], spec, half = -1.0;
    json_t *o, *hl, *alb, *pol;

    *out = NULL;
    if (!m || !m->method || !m->data)
        return glint_err_set(err, GLINT_EINVAL, "empty material");
    /* the base: light and eye at 45 degrees on the same side */
    brdf_at(m, 45.0 * DEG, 45.0 * DEG, 0.0, basef);
    for (int c = 0; c < 3; c++)
        base[c] = M_PI * basef[c];
    /* the highlight for a light at 30 degrees: peak and half width */
    brdf_at(m, 30.0 * DEG, 30.0 * DEG, M_PI, peak);
    spec = lum(peak) - lum(basef);
    if (spec > 0.05 * lum(basef) && spec > 0.0) {
        for (int k = 1; k <= 220; k++) { /* 0.25 degree steps, up to 55 (the eye at 85) */
            double d = 0.25 * k, f[3];
            brdf_at(m, 30.0 * DEG, (30.0 + d) * DEG, M_PI, f);
            if (lum(f) - lum(basef) <= 0.5 * spec) {
                half = d;
                break;
            }
        }
    }
    o = json_object();
    hl = json_object();
    alb = json_array();
    pol = json_array();
    if (!o || !hl || !alb || !pol) {
        json_decref(o);
        json_decref(hl);
        json_decref(alb);
        json_decref(pol);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    json_object_set_new(o, "conventions",
                        json_string("n = +Z, plane of incidence x-z; f = value per unit "
                                    "light / n.wi; base_colour = pi f with light and eye at 45 "
                                    "degrees on the same side; highlight for a light at 30 "
                                    "degrees (strength: (peak - base) / base in luminance; "
                                    "half width at half maximum in degrees); albedo: integral "
                                    "of f cos over the hemisphere; polar: f in the plane of "
                                    "incidence, eye angles negative towards the light"));
    json_object_set_new(o, "base_colour", rgb_json(base));
    json_object_set_new(hl, "incidence_deg", json_real(30.0));
    json_object_set_new(hl, "peak", rgb_json(peak));
    json_object_set_new(hl, "strength", json_real(lum(basef) > 0.0 ? spec / lum(basef) : 0.0));
    json_object_set_new(hl, "half_width_deg", half > 0.0 ? json_real(half) : json_null());
    json_object_set_new(o, "highlight", hl);
    for (int k = 0; k < 4; k++) {
        double a[3];
        material_albedo(m, albedo_deg[k] * DEG, READABLE_ALBEDO_THETA, a);
        json_array_append_new(alb, json_pack("{s:f, s:o}", "theta_deg", albedo_deg[k], "rgb",
                                             rgb_json(a)));
    }
    json_object_set_new(o, "albedo", alb);
    for (int k = 0; k < 3; k++) {
        json_t *th = json_array(), *fs = json_array();
        for (int t = -85; t <= 85; t += 5) {
            double f[3];
            /* negative: the eye on the light's side (azimuth 0) */
            brdf_at(m, polar_deg[k] * DEG, fabs((double)t) * DEG, t < 0 ? 0.0 : M_PI, f);
            json_array_append_new(th, json_real(t));
            json_array_append_new(fs, rgb_json(f));
        }
        json_array_append_new(pol, json_pack("{s:f, s:o, s:o}", "theta_i_deg", polar_deg[k],
                                             "theta_o_deg", th, "f", fs));
    }
    json_object_set_new(o, "polar", pol);
    *out = o;
    return 0;
}
