/* gltf_khr.c: the glTF 2.0 metallic-roughness model with the KHR material
 * extensions glint writes (gltf.h's gltf_khr): what a viewer that knows
 * them computes, so that an export's error can be measured against the
 * material it came from.
 *
 * The model, per colour channel c, at unit n, L = wi, V = wo above the
 * surface (glTF 2.0 Appendix B and the extensions' "Implementation"
 * sections, KhronosGroup/glTF extensions/2.0/Khronos/):
 *
 *   S = D(alpha) G / (4 |N.L| |N.V|), alpha = roughness^2, D and the
 *       separable Smith G as gltf.h states them (Appendix B's forms)
 *   w = (1 - |V.H|)^5
 *
 *   dielectric (fresnel_mix with KHR_materials_ior and _specular):
 *     f0_c = min(((ior - 1) / (ior + 1))^2 specularColor_c, 1) specular
 *     F_c  = f0_c + (specular - f0_c) w
 *     dielectric_c = F_c S + (1 - max_c F_c) baseColor_c / pi
 *   metal (conductor_fresnel):
 *     metal_c = (baseColor_c + (1 - baseColor_c) w) S
 *   material_c = (1 - metallic) dielectric_c + metallic metal_c
 *
 *   coat (KHR_materials_clearcoat, its own ior 1.5, its Fresnel at N.V
 *   as the extension states, not at V.H):
 *     Fc = 0.04 + 0.96 (1 - |N.V|)^5,  Sc = S at clearcoatRoughness^2
 *     f_c = material_c (1 - clearcoat Fc) + clearcoat Fc Sc
 *
 * Without an extension ior is 1.5, specular 1, specularColor 1 and the
 * coat absent: the core model.  It is gltf.h's model exactly where
 * metallic is 0 or 1; between them Appendix B's layered form (used here)
 * and gltf.h's single-Fresnel form (which the fit uses) differ in the
 * diffuse's weight (1 - F of the mixed f0 against the mix of 1 - F):
 * gltf_brdf keeps the core form for materials without extensions.
 *
 * Thread-safety: no state. */
#include <math.h>

#include "gltf.h"
#include "internal/gltf_int.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

int gltf_khr_any(const gltf_pbr *p)
{
    return p->khr.ior_used || p->khr.specular_used || p->khr.clearcoat_used;
}

int gltf_khr_names(const gltf_pbr *p, const char *names[GLTF_KHR_MAX])
{
    int k = 0;
    if (p->khr.ior_used)
        names[k++] = "KHR_materials_ior";
    if (p->khr.specular_used)
        names[k++] = "KHR_materials_specular";
    if (p->khr.clearcoat_used)
        names[k++] = "KHR_materials_clearcoat";
    if (p->aniso.used)
        names[k++] = "KHR_materials_anisotropy";
    return k;
}

/* The dielectric's Fresnel per channel at w (OUT: F[3]): fresnel_mix's
 * with the ior and specular extensions. */
static void dielectric_fresnel(const gltf_khr *k, double w, double F[3])
{
    double f0i = 0.04, spec = 1.0;
    if (k->ior_used) {
        double r = (k->ior - 1.0) / (k->ior + 1.0);
        f0i = r * r;
    }
    if (k->specular_used)
        spec = k->specular;
    for (int c = 0; c < 3; c++) {
        double f0 = f0i * (k->specular_used ? k->specular_color[c] : 1.0);
        f0 = (f0 < 1.0 ? f0 : 1.0) * spec;
        F[c] = f0 + (spec - f0) * w;
    }
}

/* S = D G / (4 ci co) and w of gltf_spec_terms, with G in the form asked:
 * Appendix B's separable one, or the height-correlated one (S times the
 * ratio of the two V's) */
static void spec_terms(int smith, double alpha, const double n[3], const double wi[3],
                       const double wo[3], double ci, double co, double *S, double *w)
{
    double a2 = alpha * alpha, li, lo;
    gltf_spec_terms(alpha, n, wi, wo, ci, co, S, w);
    if (smith != GLTF_SMITH_CORRELATED)
        return;
    li = sqrt(a2 + (1.0 - a2) * ci * ci);
    lo = sqrt(a2 + (1.0 - a2) * co * co);
    /* separable V = 1 / ((ci + li)(co + lo)); correlated V = 0.5 / (co li + ci lo) */
    *S *= 0.5 * (ci + li) * (co + lo) / (co * li + ci * lo);
}

void gltf_khr_brdf(const gltf_pbr *p, const double n[3], const double wi[3], const double wo[3],
                   double rgb[3])
{
    gltf_khr_brdf_smith(p, GLTF_SMITH_SEPARABLE, n, wi, wo, rgb);
}

void gltf_khr_brdf_smith(const gltf_pbr *p, int smith, const double n[3], const double wi[3],
                         const double wo[3], double rgb[3])
{
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    double co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2], S, w, F[3], fmax, m = p->metallic;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(ci > 0.0) || !(co > 0.0))
        return;
    spec_terms(smith, p->roughness * p->roughness, n, wi, wo, ci, co, &S, &w);
    dielectric_fresnel(&p->khr, w, F);
    fmax = F[0] > F[1] ? F[0] : F[1];
    fmax = fmax > F[2] ? fmax : F[2];
    for (int c = 0; c < 3; c++) {
        double b = p->base[c];
        double diel = F[c] * S + (1.0 - fmax) * b / M_PI, metal = (b + (1.0 - b) * w) * S;
        rgb[c] = (1.0 - m) * diel + m * metal;
    }
    if (p->khr.clearcoat_used && p->khr.clearcoat > 0.0) {
        double r = p->khr.clearcoat_roughness, Sc, wc, t = 1.0 - co, fc, cc = p->khr.clearcoat;
        spec_terms(smith, r * r, n, wi, wo, ci, co, &Sc, &wc);
        fc = 0.04 + 0.96 * t * t * t * t * t;
        for (int c = 0; c < 3; c++)
            rgb[c] = rgb[c] * (1.0 - cc * fc) + cc * fc * Sc;
    }
}
