/* test_gltf_pbr.c: a pbr material's own parameters as glTF with the KHR
 * extensions (gltf_direct.c, gltf_khr.c) instead of a fit.
 * - The numbers written are the material's: roughness sqrt(alpha), ior,
 *   specularFactor and specularColorFactor from ks, metallic 1 and ks F0
 *   for a conductor, the sharper of two lobes as the clearcoat.
 * - The error reported is computed, and this file computes it again on
 *   its own (the KHR formulas written out here with the height-correlated
 *   G, the pbr model by pbr.h's pbr_brdf) over the same directions: the
 *   two agree to rounding; it is at rounding for a conductor glTF holds
 *   exactly and small for a dielectric (KHR's angle-dependent diffuse
 *   weight), and the mapping is then kept over the fit.
 * - The core model: with the extensions at their defaults the KHR model is
 *   gltf_brdf's at metallic 0 and 1.
 * - Extremes: kd above 1 (clamped, the note says so), alpha at its floor,
 *   a black material (no NaN, error 0), a material that is not pbr's (the
 *   fit, no mapping).
 * - The .glb declares each extension it uses in extensionsUsed and holds
 *   its values. */
#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gltf.h"
#include "internal/gltf_int.h"
#include "method_pbr.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* a pbr material: kd, then per lobe alpha, ks[3] (a conductor: ks[0]),
 * ior (dielectric) or f0[3] (conductor) */
static void pbr_make(material *m, int fresnel, int nlobes, const double kd[3],
                     const double alpha[2], const double ks[2][3], const double ior[2],
                     const double f0[2][3])
{
    pbr_material *pm = calloc(1, sizeof *pm);
    pm->sp.nlobes = nlobes;
    pm->sp.fresnel = fresnel;
    memcpy(pm->p, kd, 3 * sizeof *kd);
    for (int l = 0; l < nlobes; l++) {
        double *q = pm->p + 3 + 5 * l;
        q[0] = alpha[l];
        if (fresnel == PBR_DIELECTRIC) {
            q[1] = ks[l][0], q[2] = ks[l][1], q[3] = ks[l][2], q[4] = ior[l];
        } else {
            q[1] = ks[l][0], q[2] = f0[l][0], q[3] = f0[l][1], q[4] = f0[l][2];
        }
    }
    pbr_material_sync(pm);
    material_init(m, &method_pbr, pm, NULL);
}

/* the fit's directions without samples: light i over 24, eye j over 96 on
 * Fibonacci spirals about +z (gltf.h's GLTF_FIT_PAIRS) */
static void fib(int i, int n, double out[3])
{
    double z = 1.0 - (i + 0.5) / n, r = sqrt(1.0 - z * z), ph = i * M_PI * (3.0 - sqrt(5.0));
    out[0] = r * cos(ph), out[1] = r * sin(ph), out[2] = z;
}

/* The KHR model written out from the extensions' texts, independently of
 * gltf_khr.c, with the height-correlated V the mapping is measured with
 * (glTF-Sample-Viewer's V_GGX): 0.5 / (co sqrt(a2 + (1 - a2) ci^2) + ci
 * sqrt(a2 + (1 - a2) co^2)). */
static double ggx_s(double a, double ci, double co, double nh)
{
    double a2 = a * a, d = nh * nh * (a2 - 1.0) + 1.0;
    double v = 0.5 / (co * sqrt(a2 + (1.0 - a2) * ci * ci) + ci * sqrt(a2 + (1.0 - a2) * co * co));
    return a2 / (M_PI * d * d) * v;
}

static void khr_ref(const gltf_pbr *p, const double wi[3], const double wo[3], double f[3])
{
    double h[3], hl, nh, vh, ci = wi[2], co = wo[2], w, F[3], Fm = 0.0, S;
    double r = p->khr.ior_used ? (p->khr.ior - 1) / (p->khr.ior + 1) : 0.2;
    double spec = p->khr.specular_used ? p->khr.specular : 1.0;
    for (int e = 0; e < 3; e++)
        h[e] = wi[e] + wo[e];
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    nh = h[2] / hl;
    vh = (wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2]) / hl;
    w = pow(1.0 - vh, 5.0);
    S = ggx_s(p->roughness * p->roughness, ci, co, nh);
    for (int c = 0; c < 3; c++) {
        double f0 = fmin(r * r * (p->khr.specular_used ? p->khr.specular_color[c] : 1.0), 1.0);
        F[c] = spec * (f0 + (1.0 - f0) * w);
        Fm = fmax(Fm, F[c]);
    }
    for (int c = 0; c < 3; c++)
        f[c] = (1.0 - p->metallic) * (F[c] * S + (1.0 - Fm) * p->base[c] / M_PI) +
               p->metallic * (p->base[c] + (1.0 - p->base[c]) * w) * S;
    if (p->khr.clearcoat_used) {
        double cf = 0.04 + 0.96 * pow(1.0 - co, 5.0), cc = p->khr.clearcoat;
        double Sc = ggx_s(p->khr.clearcoat_roughness * p->khr.clearcoat_roughness, ci, co, nh);
        for (int c = 0; c < 3; c++)
            f[c] = f[c] * (1.0 - cc * cf) + cc * cf * Sc;
    }
}

/* the relative RMS of p's f ci against m's over the 24 x 96 pairs */
static double ref_rel_rms(const material *m, const gltf_pbr *p)
{
    const pbr_material *pm = pbr_material_of(m);
    double num = 0.0, den = 0.0;
    for (int i = 0; i < GLTF_FIT_LIGHTS; i++)
        for (int j = 0; j < GLTF_FIT_VIEWS; j++) {
            double wi[3], wo[3], h[3], hl, g[3], f[3];
            fib(i, GLTF_FIT_LIGHTS, wi);
            fib(j, GLTF_FIT_VIEWS, wo);
            for (int e = 0; e < 3; e++)
                h[e] = wi[e] + wo[e];
            hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            pbr_brdf(pm->kd, pm->lobe, pm->sp.nlobes, wi[2], wo[2], h[2] / hl,
                     (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl, f);
            khr_ref(p, wi, wo, g);
            for (int c = 0; c < 3; c++) {
                num += (g[c] - f[c]) * (g[c] - f[c]) * wi[2] * wi[2];
                den += f[c] * f[c] * wi[2] * wi[2];
            }
        }
    return den > 0.0 ? sqrt(num / den) : 0.0;
}

static const double NO3[2][3] = {{0}};

TEST(one_dielectric_lobe_maps_to_ior_and_specular)
{
    const double kd[3] = {0.5, 0.3, 0.2}, al[2] = {0.09, 0}, ks[2][3] = {{1, 1, 1}},
                 ior[2] = {1.6, 0};
    double f0 = pow(0.6 / 2.6, 2.0), ref;
    material m;
    gltf_pbr p;
    glint_err e;
    pbr_make(&m, PBR_DIELECTRIC, 1, kd, al, ks, ior, NO3);
    ASSERT_OK(gltf_fit_material(&m, NULL, &p, &e));
    ASSERT_EQ(p.exact, 1);
    ASSERT_NEAR(p.roughness, 0.3, 1e-15);
    ASSERT_NEAR(p.metallic, 0.0, 0.0);
    ASSERT(p.khr.ior_used && p.khr.specular_used && !p.khr.clearcoat_used);
    ASSERT_NEAR(p.khr.ior, 1.6, 1e-15);
    ASSERT_NEAR(p.khr.specular, 1.0, 1e-15);
    for (int c = 0; c < 3; c++) {
        ASSERT_NEAR(p.khr.specular_color[c], 1.0, 1e-15);
        ASSERT_NEAR(p.base[c], kd[c] / (1.0 - f0), 1e-12);
    }
    ref = ref_rel_rms(&m, &p);
    printf("  one dielectric lobe: rel RMS %.5f (recomputed %.5f), the fit's %.5f\n",
           p.rel_rms, ref, p.rel_rms_fitted);
    ASSERT_NEAR(p.rel_rms, ref, 1e-9);
    ASSERT_NEAR(p.rel_rms_exact, p.rel_rms, 0.0);
    ASSERT_LE(p.rel_rms, p.rel_rms_fitted);
    ASSERT_EQ(p.smith, GLTF_SMITH_CORRELATED);
    ASSERT_LT(p.rel_rms, 0.01); /* the diffuse's weight only */
    ASSERT(p.pairs == GLTF_FIT_PAIRS);
    material_free(&m);
}

TEST(a_tinted_highlight_is_exact_at_normal_incidence)
{
    const double kd[3] = {0.1, 0.1, 0.1}, al[2] = {0.04, 0}, ks[2][3] = {{0.8, 0.4, 0.2}},
                 ior[2] = {1.45, 0};
    double f0 = pow(0.45 / 2.45, 2.0);
    material m;
    gltf_pbr p;
    memset(&p, 0, sizeof p);
    pbr_make(&m, PBR_DIELECTRIC, 1, kd, al, ks, ior, NO3);
    gltf_direct_map(pbr_material_of(&m), 1, &p);
    ASSERT_NEAR(p.khr.specular, 0.8, 1e-15);
    /* the KHR f0: min(F0 color, 1) specular = ks F0 */
    for (int c = 0; c < 3; c++)
        ASSERT_NEAR(fmin(f0 * p.khr.specular_color[c], 1.0) * p.khr.specular, ks[0][c] * f0,
                    1e-15);
    ASSERT(strstr(p.note, "tinted"));
    material_free(&m);
}

TEST(a_conductor_maps_to_metallic_one)
{
    const double kd[3] = {0, 0, 0}, al[2] = {0.16, 0}, ks[2][3] = {{1}},
                 f0[2][3] = {{0.95, 0.64, 0.54}};
    material m;
    gltf_pbr p;
    glint_err e;
    double ref;
    pbr_make(&m, PBR_CONDUCTOR, 1, kd, al, ks, NULL, f0);
    ASSERT_OK(gltf_fit_material(&m, NULL, &p, &e));
    ASSERT_EQ(p.exact, 1);
    ASSERT_NEAR(p.metallic, 1.0, 0.0);
    ASSERT_NEAR(p.roughness, 0.4, 1e-15);
    for (int c = 0; c < 3; c++)
        ASSERT_NEAR(p.base[c], f0[0][c], 1e-15);
    ASSERT(!gltf_khr_any(&p));
    ASSERT_EQ(p.note[0], 0);
    ref = ref_rel_rms(&m, &p);
    printf("  conductor: rel RMS %.5f (recomputed %.5f), the fit's %.5f\n", p.rel_rms, ref,
           p.rel_rms_fitted);
    ASSERT_NEAR(p.rel_rms, ref, 1e-9);
    ASSERT_LT(p.rel_rms, 1e-9); /* the same model */
    material_free(&m);
}

TEST(a_conductor_with_a_diffuse_says_it_is_left_out)
{
    const double kd[3] = {0.2, 0.1, 0.05}, al[2] = {0.16, 0}, ks[2][3] = {{0.7}},
                 f0[2][3] = {{0.9, 0.8, 0.5}};
    material m;
    gltf_pbr p;
    glint_err e;
    pbr_make(&m, PBR_CONDUCTOR, 1, kd, al, ks, NULL, f0);
    ASSERT_OK(gltf_fit_material(&m, NULL, &p, &e));
    printf("  conductor with kd: %s, exact %.5f, fitted %.5f\n", p.exact ? "exact" : "fitted",
           p.rel_rms_exact, p.rel_rms_fitted);
    ASSERT(strstr(p.note, "left out"));
    ASSERT_FINITE(p.rel_rms_exact);
    /* whichever is kept is the closer one */
    ASSERT_NEAR(p.rel_rms, fmin(p.rel_rms_exact, p.rel_rms_fitted), 0.0);
    ASSERT_EQ(p.exact, p.rel_rms_exact <= p.rel_rms_fitted);
    material_free(&m);
}

TEST(two_lobes_carry_the_sharper_as_the_clearcoat)
{
    const double kd[3] = {0.4, 0.1, 0.05}, al[2] = {0.25, 0.01},
                 ks[2][3] = {{1, 1, 1}, {1, 1, 1}}, ior[2] = {1.5, 1.5};
    material m;
    gltf_pbr p, q;
    glint_err e;
    double ref;
    pbr_make(&m, PBR_DIELECTRIC, 2, kd, al, ks, ior, NO3);
    memset(&q, 0, sizeof q);
    gltf_direct_map(pbr_material_of(&m), 1, &q);
    ASSERT(q.khr.clearcoat_used);
    ASSERT_NEAR(q.khr.clearcoat_roughness, 0.1, 1e-15);
    ASSERT_NEAR(q.khr.clearcoat, 1.0, 1e-12); /* F0 0.04: a clearcoat's own */
    ASSERT_NEAR(q.roughness, 0.5, 1e-15);
    ASSERT_OK(gltf_fit_material(&m, NULL, &p, &e));
    ref = ref_rel_rms(&m, &p);
    printf("  two lobes: %s (%s), rel RMS %.5f (recomputed %.5f); mapped %.5f, the fit's "
           "%.5f\n",
           p.exact ? "exact" : "fitted", p.khr.clearcoat_used ? "clearcoat" : "no coat",
           p.rel_rms, ref, p.rel_rms_exact, p.rel_rms_fitted);
    ASSERT_NEAR(p.rel_rms, ref, 1e-9);
    ASSERT_FINITE(p.rel_rms_exact);
    ASSERT_EQ(p.exact, p.rel_rms_exact <= p.rel_rms_fitted);
    ASSERT_NEAR(p.rel_rms, fmin(p.rel_rms_exact, p.rel_rms_fitted), 0.0);
    material_free(&m);
}

TEST(the_core_model_is_the_khr_model_at_its_defaults)
{
    gltf_pbr a = {.base = {0.7, 0.4, 0.2}, .roughness = 0.35}, b;
    for (int mt = 0; mt <= 1; mt++) {
        a.metallic = mt;
        b = a;
        b.khr.ior_used = b.khr.specular_used = 1;
        b.khr.ior = 1.5;
        b.khr.specular = 1.0;
        b.khr.specular_color[0] = b.khr.specular_color[1] = b.khr.specular_color[2] = 1.0;
        for (int i = 0; i < 24; i++)
            for (int j = 0; j < 24; j++) {
                double n[3] = {0, 0, 1}, wi[3], wo[3], fa[3], fb[3];
                fib(i, 24, wi);
                fib(j, 24, wo);
                gltf_brdf(&a, n, wi, wo, fa);
                gltf_brdf(&b, n, wi, wo, fb);
                for (int c = 0; c < 3; c++)
                    ASSERT_NEAR(fb[c], fa[c], 1e-12 * (1.0 + fabs(fa[c])));
            }
    }
}

TEST(extremes_kd_above_one_alpha_at_its_floor_and_black)
{
    const double kd[3] = {1.5, 0.5, 0.0}, al[2] = {PBR_ALPHA_MIN, 0}, ks[2][3] = {{2, 2, 2}},
                 ior[2] = {PBR_IOR_MAX, 0}, zero[3] = {0, 0, 0}, ks0[2][3] = {{0, 0, 0}};
    material m;
    gltf_pbr p;
    glint_err e;
    pbr_make(&m, PBR_DIELECTRIC, 1, kd, al, ks, ior, NO3);
    memset(&p, 0, sizeof p);
    gltf_direct_map(pbr_material_of(&m), 1, &p);
    ASSERT_NEAR(p.base[0], 1.0, 0.0);
    ASSERT(p.base[1] > 0.5 && p.base[1] <= 1.0);
    ASSERT_NEAR(p.base[2], 0.0, 0.0);
    ASSERT(strstr(p.note, "clamped"));
    ASSERT(strstr(p.note, "ks above 1"));
    ASSERT_NEAR(p.roughness, sqrt(PBR_ALPHA_MIN), 1e-15);
    ASSERT_NEAR(p.khr.specular, 1.0, 0.0);
    ASSERT_NEAR(p.khr.specular_color[0], 2.0, 1e-15);
    ASSERT_OK(gltf_fit_material(&m, NULL, &p, &e));
    ASSERT_FINITE(p.rel_rms);
    ASSERT_FINITE(p.rel_rms_exact);
    material_free(&m);

    pbr_make(&m, PBR_DIELECTRIC, 1, zero, al, ks0, ior, NO3);
    ASSERT_OK(gltf_fit_material(&m, NULL, &p, &e));
    ASSERT_NEAR(p.rel_rms_exact, 0.0, 0.0); /* nothing to miss */
    ASSERT_EQ(p.exact, 1);
    ASSERT_NEAR(p.khr.specular, 0.0, 0.0);
    for (int c = 0; c < 3; c++)
        ASSERT(p.base[c] == 0.0 && isfinite(p.khr.specular_color[c]));
    material_free(&m);
}

static void grey(const void *ctx, const double n[3], const double wi[3], const double wo[3],
                 double rad[3])
{
    double c = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    (void)ctx, (void)wo;
    rad[0] = rad[1] = rad[2] = 0.5 / M_PI * (c > 0.0 ? c : 0.0);
}

TEST(what_is_not_a_pbr_material_is_fitted)
{
    gltf_pbr p;
    glint_err e;
    ASSERT_OK(gltf_fit(grey, NULL, NULL, &p, &e));
    ASSERT_EQ(p.exact, 0);
    ASSERT(isnan(p.rel_rms_exact));
    ASSERT(!gltf_khr_any(&p));
    ASSERT_NEAR(p.rel_rms_fitted, p.rel_rms, 0.0);
}

static uint32_t u32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

TEST(the_glb_declares_and_holds_its_extensions)
{
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    uint32_t tri[3] = {0, 1, 2};
    mesh msh = {3, 1, pos, nrm, NULL, tri};
    gltf_pbr p = {.base = {0.5, 0.3, 0.2}, .roughness = 0.3, .exact = 1};
    void *glb = NULL;
    size_t len = 0;
    glint_err e;
    json_t *doc, *used, *ext;
    p.khr.ior_used = p.khr.specular_used = p.khr.clearcoat_used = 1;
    p.khr.ior = 1.7;
    p.khr.specular = 0.75;
    p.khr.specular_color[0] = 1.25, p.khr.specular_color[1] = 1.0, p.khr.specular_color[2] = 0.5;
    p.khr.clearcoat = 0.5, p.khr.clearcoat_roughness = 0.125;
    ASSERT_OK(gltf_write_glb(&msh, &p, NULL, "t", NULL, &glb, &len, &e));
    doc = json_loadb((const char *)glb + 20, u32((const unsigned char *)glb + 12), 0, NULL);
    ASSERT(doc);
    used = json_object_get(doc, "extensionsUsed");
    ASSERT_EQ(json_array_size(used), 3);
    ASSERT(!strcmp(json_string_value(json_array_get(used, 0)), "KHR_materials_ior"));
    ASSERT(!strcmp(json_string_value(json_array_get(used, 1)), "KHR_materials_specular"));
    ASSERT(!strcmp(json_string_value(json_array_get(used, 2)), "KHR_materials_clearcoat"));
    ext = json_object_get(json_array_get(json_object_get(doc, "materials"), 0), "extensions");
    ASSERT_NEAR(json_number_value(json_object_get(json_object_get(ext, "KHR_materials_ior"), "ior")),
                1.7, 1e-7);
    {
        json_t *s = json_object_get(ext, "KHR_materials_specular"), *c;
        json_t *cc = json_object_get(ext, "KHR_materials_clearcoat");
        ASSERT_NEAR(json_number_value(json_object_get(s, "specularFactor")), 0.75, 1e-7);
        c = json_object_get(s, "specularColorFactor");
        ASSERT_NEAR(json_number_value(json_array_get(c, 0)), 1.25, 1e-7);
        ASSERT_NEAR(json_number_value(json_array_get(c, 2)), 0.5, 1e-7);
        ASSERT_NEAR(json_number_value(json_object_get(cc, "clearcoatFactor")), 0.5, 1e-7);
        ASSERT_NEAR(json_number_value(json_object_get(cc, "clearcoatRoughnessFactor")), 0.125,
                    1e-7);
    }
    json_decref(doc);
    free(glb);
    /* none used: no extensionsUsed */
    memset(&p.khr, 0, sizeof p.khr);
    ASSERT_OK(gltf_write_glb(&msh, &p, NULL, "t", NULL, &glb, &len, &e));
    doc = json_loadb((const char *)glb + 20, u32((const unsigned char *)glb + 12), 0, NULL);
    ASSERT(doc && !json_object_get(doc, "extensionsUsed"));
    json_decref(doc);
    free(glb);
}

TEST_LIST{
    TEST_ENTRY(one_dielectric_lobe_maps_to_ior_and_specular),
    TEST_ENTRY(a_tinted_highlight_is_exact_at_normal_incidence),
    TEST_ENTRY(a_conductor_maps_to_metallic_one),
    TEST_ENTRY(a_conductor_with_a_diffuse_says_it_is_left_out),
    TEST_ENTRY(two_lobes_carry_the_sharper_as_the_clearcoat),
    TEST_ENTRY(the_core_model_is_the_khr_model_at_its_defaults),
    TEST_ENTRY(extremes_kd_above_one_alpha_at_its_floor_and_black),
    TEST_ENTRY(what_is_not_a_pbr_material_is_fitted),
    TEST_ENTRY(the_glb_declares_and_holds_its_extensions),
};

TEST_MAIN()
