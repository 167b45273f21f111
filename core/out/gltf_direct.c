/* gltf_direct.c: a pbr material's own parameters as glTF's, with the KHR
 * extensions, instead of a fit (gltf.h, gltf_fit_material).
 *
 * pbr's model (method_pbr.h, pbr.h), per channel c:
 *   f_c = kd_c / pi + sum over lobes  ks_c D V (F0_c + (1 - F0_c) (1 - wi.h)^5)
 * (GGX D, height-correlated Smith V, Schlick F).  The KHR model is
 * gltf_khr.c's.  The mapping, lobe by lobe:
 *
 *   roughness = sqrt(alpha): both take GGX's alpha as roughness^2.
 *   One dielectric lobe (F0 = ((ior - 1) / (ior + 1))^2, ks per channel):
 *     metallic 0; KHR_materials_ior ior; KHR_materials_specular with
 *     specularFactor s = min(max_c ks_c, 1) and specularColorFactor ks_c /
 *     s, so that the KHR f0_c = min(F0 ks_c / s, 1) s is pbr's ks_c F0 at
 *     normal incidence (exact unless F0 ks_c / s > 1, which the note
 *     says).  At grazing incidence KHR's F90 is s for every channel where
 *     pbr's reflectance is ks_c: exact when ks is grey and at most 1.
 *     baseColor_c = kd_c / (1 - max_c f0_c): KHR weighs the diffuse by
 *     1 - max_c F_c, which this undoes at normal incidence (exactly there,
 *     less than fully towards grazing); clamped to [0, 1] (the note says).
 *   Conductor (F0 per channel, one ks): metallic 1, baseColor_c = min(ks
 *     F0_c, 1): normal incidence exact, grazing 1 where pbr's is ks.  KHR's
 *     metal has no diffuse: kd is left out (the note says, when kd > 0).
 *   Two lobes: the sharper (smaller alpha) as KHR_materials_clearcoat,
 *     the other as above: clearcoatRoughnessFactor sqrt(alpha) and
 *     clearcoatFactor min(mean_c(ks_c F0_c) / 0.04, 1), the coat's normal
 *     reflectance (KHR's coat is white, ior 1.5, its Fresnel at N.V); or
 *     the sharper lobe left out.  Both are measured and the closer kept.
 *   pbr_detail, pbr_tab: the pbr base is mapped; the detail (an hf3
 *     factorization, or a table over half and difference angles, on top)
 *     has no glTF counterpart and is left out (the note says); the error
 *     is measured against the whole material, so it counts.
 *
 * Measured in which model.  Appendix B writes Smith's G in its separable
 * form (gltf_brdf, what the fit minimizes); Khronos's glTF-Sample-Viewer
 * and three.js render the height-correlated form, which is also pbr's.
 * Under the separable form even a material glTF represents exactly (a
 * conductor with ks 1) shows 16% over the hemisphere's pairs, all of it
 * at grazing angles, that no such viewer renders; so for a pbr material
 * both the mapping and the fit are measured with the height-correlated G
 * (gltf_khr_brdf_smith; out->smith says so) and the closer is kept.  What
 * stays inexact then: KHR's diffuse weight varies with the angle where
 * pbr's kd does not (0.1% for a grey dielectric), a tinted ks or one above
 * 1 at grazing angles, a conductor's diffuse, and a second lobe: KHR's
 * coat darkens everything under it by its Fresnel at N.V (to nothing at
 * grazing), where pbr adds its lobes.  The relative RMS over the painted
 * directions (the fit's pairs) says how much; gltf_fit_material keeps the
 * mapping unless the fit is closer.
 *
 * Thread-safety: reads the material only. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "gltf.h"
#include "internal/gltf_int.h"
#include "method_pbr.h"
#include "method_pbr_detail.h"
#include "method_pbr_tab.h"

/* append a sentence to the note (cut at its size) */
static void note_add(char *note, const char *fmt, ...)
{
    size_t k = strlen(note);
    va_list ap;
    if (k + 2 >= GLTF_NOTE_MAX)
        return;
    if (k)
        note[k++] = ' ', note[k] = 0;
    va_start(ap, fmt);
    vsnprintf(note + k, GLTF_NOTE_MAX - k, fmt, ap);
    va_end(ap);
}

static double clamp01(double x, int *clamped)
{
    if (x > 1.0 || x < 0.0 || !isfinite(x)) {
        *clamped = 1;
        return x > 1.0 ? 1.0 : 0.0;
    }
    return x;
}

/* A dielectric lobe l of pm as the core lobe with ior and specular. */
static void map_dielectric(const pbr_material *pm, int l, gltf_pbr *out)
{
    const pbr_lobe *lb = &pm->lobe[l];
    double ior = pm->p[3 + 5 * l + 4], f0 = lb->f0[0], ksmax = 0.0, s, f0max = 0.0;
    int clamped = 0;
    for (int c = 0; c < 3; c++)
        ksmax = lb->ks[c] > ksmax ? lb->ks[c] : ksmax;
    s = ksmax < 1.0 ? ksmax : 1.0;
    out->metallic = 0.0;
    out->khr.ior_used = 1;
    out->khr.ior = ior;
    out->khr.specular_used = 1;
    out->khr.specular = s;
    for (int c = 0; c < 3; c++) {
        double sc = s > 0.0 ? lb->ks[c] / s : 1.0, g = f0 * sc;
        out->khr.specular_color[c] = sc;
        if (g > 1.0)
            clamped = 1, g = 1.0;
        f0max = g * s > f0max ? g * s : f0max;
    }
    if (ksmax > 1.0)
        note_add(out->note,
                 "ks above 1 (max %.3g): specularFactor 1 and specularColorFactor carry it at "
                 "normal incidence; at grazing incidence the reflectance is 1, not ks.",
                 ksmax);
    else if (ksmax - fmin(lb->ks[0], fmin(lb->ks[1], lb->ks[2])) > 1e-9)
        note_add(out->note,
                 "ks tinted: its tint is exact at normal incidence; at grazing incidence the "
                 "reflectance is %.3g in every channel.",
                 s);
    if (clamped)
        note_add(out->note, "F0 ks above 1 in some channel: KHR clamps it at 1.");
    clamped = 0;
    for (int c = 0; c < 3; c++)
        out->base[c] = clamp01(pm->kd[c] / (1.0 - f0max), &clamped);
    if (clamped)
        note_add(out->note,
                 "baseColor kd / (1 - f0) clamped to [0, 1] (kd max %.3g, f0 %.3g).",
                 fmax(pm->kd[0], fmax(pm->kd[1], pm->kd[2])), f0max);
}

/* A conductor lobe l of pm as the core model's metal. */
static void map_conductor(const pbr_material *pm, int l, gltf_pbr *out)
{
    const pbr_lobe *lb = &pm->lobe[l];
    int clamped = 0;
    out->metallic = 1.0;
    for (int c = 0; c < 3; c++)
        out->base[c] = clamp01(lb->ks[c] * lb->f0[c], &clamped);
    if (clamped)
        note_add(out->note, "baseColor ks F0 clamped to [0, 1] (ks %.3g).", lb->ks[0]);
    if (fabs(lb->ks[0] - 1.0) > 1e-9)
        note_add(out->note,
                 "ks %.3g: the metal's colour ks F0 is exact at normal incidence; at grazing "
                 "incidence the reflectance is 1, not ks.",
                 lb->ks[0]);
    if (pm->kd[0] > 0.0 || pm->kd[1] > 0.0 || pm->kd[2] > 0.0)
        note_add(out->note,
                 "The diffuse kd (max %.3g) is left out: glTF's metal has none.",
                 fmax(pm->kd[0], fmax(pm->kd[1], pm->kd[2])));
}

/* Lobe l of pm as KHR_materials_clearcoat. */
static void map_coat(const pbr_material *pm, int l, gltf_pbr *out)
{
    const pbr_lobe *lb = &pm->lobe[l];
    double r0 = (lb->ks[0] * lb->f0[0] + lb->ks[1] * lb->f0[1] + lb->ks[2] * lb->f0[2]) / 3.0;
    double cc = r0 / 0.04;
    out->khr.clearcoat_used = 1;
    out->khr.clearcoat = cc < 1.0 ? (cc > 0.0 ? cc : 0.0) : 1.0;
    out->khr.clearcoat_roughness = sqrt(lb->alpha);
    note_add(out->note,
             "The sharper lobe is the clearcoat (white, ior 1.5): its normal reflectance %.3g "
             "as clearcoatFactor %.3g.",
             r0, out->khr.clearcoat);
    if (cc > 1.0)
        note_add(out->note, "The coat's reflectance is above a clearcoat's 0.04 (clamped).");
}

void gltf_direct_map(const pbr_material *pm, int coat, gltf_pbr *out)
{
    int b = 0, c = -1;
    memset(&out->khr, 0, sizeof out->khr);
    out->note[0] = 0;
    if (pm->sp.nlobes > 1) { /* the sharper lobe is the coat's candidate */
        c = pm->lobe[1].alpha < pm->lobe[0].alpha ? 1 : 0;
        b = 1 - c;
    }
    out->roughness = sqrt(pm->lobe[b].alpha);
    if (pm->sp.fresnel == PBR_DIELECTRIC)
        map_dielectric(pm, b, out);
    else
        map_conductor(pm, b, out);
    if (c >= 0 && coat)
        map_coat(pm, c, out);
    else if (c >= 0)
        note_add(out->note, "The sharper lobe (alpha %.3g) is left out.", pm->lobe[c].alpha);
}

double gltf_pairs_rel_rms(const gltf_pairs *P, const gltf_pbr *p, int smith)
{
    double num = 0.0, den = 0.0;
    for (int i = 0; i < P->n; i++) {
        double f[3];
        if (smith == GLTF_SMITH_SEPARABLE)
            gltf_brdf(p, P->nn[i], P->wi[i], P->wo[i], f);
        else
            gltf_khr_brdf_smith(p, smith, P->nn[i], P->wi[i], P->wo[i], f);
        for (int c = 0; c < 3; c++) {
            double d = f[c] * P->ci[i] - P->y[i][c];
            num += d * d;
            den += P->y[i][c] * P->y[i][c];
        }
    }
    return den > 0.0 ? sqrt(num / den) : 0.0;
}

static void material_fn(const void *ctx, const double n[3], const double wi[3],
                        const double wo[3], double rad[3])
{
    material_eval(ctx, n, wi, wo, rad);
}

/* The pbr parameters of m (pbr, pbr_env, or pbr_detail's or pbr_tab's
 * base; NULL for others), and whether a detail is on top (OUT: *detail:
 * 1 pbr_detail's factors, 2 pbr_tab's table). */
static const pbr_material *pbr_of(const material *m, int *detail)
{
    const pbr_detail_material *dm = pbr_detail_material_of(m);
    const pbr_tab_material *tm = pbr_tab_material_of(m);
    *detail = dm ? 1 : tm ? 2 : 0;
    return dm ? &dm->base : tm ? &tm->base : pbr_material_of(m);
}

int gltf_direct_choose(const material *m, const samples *smp, gltf_pbr *out, glint_err *err)
{
    gltf_pairs P;
    gltf_pbr cand[2], *best = NULL;
    int detail, rc, cap = smp ? (smp->n < GLTF_FIT_MAX_SAMPLES ? smp->n : GLTF_FIT_MAX_SAMPLES)
                                : GLTF_FIT_PAIRS;
    const pbr_material *pm = pbr_of(m, &detail);

    out->rel_rms_fitted = out->rel_rms;
    out->rel_rms_exact = NAN;
    out->exact = 0;
    if (!pm || pm->sp.nlobes < 1 || pm->sp.nlobes > PBR_MAX_LOBES)
        return 0;
    if ((rc = gltf_pairs_alloc(&P, cap, err)))
        return rc;
    gltf_pairs_fill(&P, smp, cap, material_fn, m);
    /* every figure from here in the form viewers render and pbr's model has */
    out->smith = GLTF_SMITH_CORRELATED;
    out->rel_rms = out->rel_rms_fitted = gltf_pairs_rel_rms(&P, out, GLTF_SMITH_CORRELATED);
    for (int k = 0; k < pm->sp.nlobes; k++) { /* with the coat, then (two lobes) without */
        cand[k] = *out;
        gltf_direct_map(pm, k == 0, &cand[k]);
        cand[k].rel_rms = gltf_pairs_rel_rms(&P, &cand[k], GLTF_SMITH_CORRELATED);
        if (!best || cand[k].rel_rms < best->rel_rms)
            best = &cand[k];
    }
    gltf_pairs_free(&P);
    if (detail == 1) {
        const double *w = pbr_detail_material_of(m)->weight;
        note_add(best->note,
                 "The detail on top of the pbr base (weights %.3g, %.3g, %.3g) is left out: "
                 "the error counts it.",
                 w[0], w[1], w[2]);
    } else if (detail == 2) {
        note_add(best->note, "The correction table on the pbr base is left out: the error "
                             "counts it.");
    }
    best->rel_rms_exact = best->rel_rms;
    if (!(best->rel_rms <= out->rel_rms_fitted)) { /* the fit is closer: keep it */
        out->rel_rms_exact = best->rel_rms;
        snprintf(out->note, sizeof out->note, "%s", best->note);
        return 0;
    }
    best->exact = 1;
    *out = *best;
    return 0;
}
