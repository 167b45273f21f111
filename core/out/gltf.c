/* gltf.c: glTF 2.0 metallic-roughness materials fitted to glint materials,
 * and binary glTF files (gltf.h). */
#include "gltf.h"

#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal/gltf_int.h"
#include "raster.h"
#include "vec3.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---- the model ------------------------------------------------------------------------ */

/* D G / (4 ci co) and s = (1 - |V.H|)^5 of a pair (ci, co > 0) */
void gltf_spec_terms(double alpha, const double n[3], const double wi[3], const double wo[3],
                     double ci, double co, double *S, double *s)
{
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]}, hl, nh, vh, a2 = alpha * alpha;
    double d, g1i, g1o;
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int e = 0; e < 3; e++)
        h[e] /= hl;
    nh = n[0] * h[0] + n[1] * h[1] + n[2] * h[2];
    vh = fabs(wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2]);
    d = nh * nh * (a2 - 1.0) + 1.0;
    d = a2 / (M_PI * d * d);
    g1i = 2.0 * ci / (ci + sqrt(a2 + (1.0 - a2) * ci * ci));
    g1o = 2.0 * co / (co + sqrt(a2 + (1.0 - a2) * co * co));
    *S = d * g1i * g1o / (4.0 * ci * co);
    *s = pow(1.0 - vh, 5.0);
}

/* f = A + B x + C x^2 in the base colour x of one channel (gltf.h's model) */
static void coefs(double S, double s, double m, double *A, double *B, double *C)
{
    *A = S * s + 0.04 * S * (1.0 - s) * (1.0 - m);
    *B = S * (1.0 - s) * m + (1.0 - s) * (1.0 - m) * (1.0 - 0.04 * (1.0 - m)) / M_PI;
    *C = -(1.0 - s) * (1.0 - m) * m / M_PI;
}

void gltf_brdf(const gltf_pbr *p, const double n[3], const double wi[3], const double wo[3],
               double rgb[3])
{
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    double co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2], S, s, A, B, C;
    if (gltf_khr_any(p)) {
        gltf_khr_brdf(p, n, wi, wo, rgb);
        return;
    }
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(ci > 0.0) || !(co > 0.0))
        return;
    gltf_spec_terms(p->roughness * p->roughness, n, wi, wo, ci, co, &S, &s);
    coefs(S, s, p->metallic, &A, &B, &C);
    for (int c = 0; c < 3; c++)
        rgb[c] = A + B * p->base[c] + C * p->base[c] * p->base[c];
}

/* ---- the fit ---------------------------------------------------------------------------- */

static void fib(int i, int n, double out[3])
{
    double z = 1.0 - (i + 0.5) / n, r = sqrt(1.0 - z * z), ph = i * M_PI * (3.0 - sqrt(5.0));
    out[0] = r * cos(ph), out[1] = r * sin(ph), out[2] = z;
}

/* min over x in [0, 1] of q0 + q1 x + q2 x^2 + q3 x^3 + q4 x^4 (OUT: *x) */
static double quartic_min(const double q[5], double *x)
{
    double best = INFINITY, bx = 0.0;
    for (int k = 0; k <= 200; k++) {
        double t = k / 200.0, v = q[0] + t * (q[1] + t * (q[2] + t * (q[3] + t * q[4])));
        if (v < best)
            best = v, bx = t;
    }
    for (int it = 0; it < 20; it++) { /* Newton on the derivative, kept inside [0, 1] */
        double d1 = q[1] + bx * (2 * q[2] + bx * (3 * q[3] + bx * 4 * q[4]));
        double d2 = 2 * q[2] + bx * (6 * q[3] + bx * 12 * q[4]), t, v;
        if (!(d2 > 0.0))
            break;
        t = bx - d1 / d2;
        t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
        v = q[0] + t * (q[1] + t * (q[2] + t * (q[3] + t * q[4])));
        if (!(v < best))
            break;
        best = v, bx = t;
    }
    *x = bx;
    return best;
}

double gltf_pairs_error(const gltf_pairs *P, const double *S, const double *s, double m,
                        double base[3])
{
    double q[3][5] = {{0}}, total = 0.0;
    for (int i = 0; i < P->n; i++) {
        double A, B, C, ci = P->ci[i];
        coefs(S[i], s[i], m, &A, &B, &C);
        for (int c = 0; c < 3; c++) {
            double a = ci * A - P->y[i][c], b = ci * B, cc = ci * C;
            q[c][0] += a * a;
            q[c][1] += 2 * a * b;
            q[c][2] += b * b + 2 * a * cc;
            q[c][3] += 2 * b * cc;
            q[c][4] += cc * cc;
        }
    }
    for (int c = 0; c < 3; c++)
        total += quartic_min(q[c], &base[c]);
    return total;
}

/* the squared error of (m, r) with the best base colour (OUT: base) */
static double try_mr(gltf_pairs *P, double m, double r, double base[3])
{
    for (int i = 0; i < P->n; i++)
        gltf_spec_terms(r * r, P->nn[i], P->wi[i], P->wo[i], P->ci[i], P->co[i], &P->S[i],
                        &P->s[i]);
    return gltf_pairs_error(P, P->S, P->s, m, base);
}

void gltf_pairs_free(gltf_pairs *P)
{
    free(P->nn), free(P->wi), free(P->wo), free(P->y), free(P->ci), free(P->co), free(P->S),
        free(P->s);
    memset(P, 0, sizeof *P);
}

int gltf_pairs_alloc(gltf_pairs *P, int cap, glint_err *err)
{
    memset(P, 0, sizeof *P);
    if (cap < 1)
        return glint_err_set(err, GLINT_EINVAL, "no direction pair to fit a glTF material at");
    P->nn = malloc((size_t)cap * sizeof *P->nn);
    P->wi = malloc((size_t)cap * sizeof *P->wi);
    P->wo = malloc((size_t)cap * sizeof *P->wo);
    P->y = calloc((size_t)cap, sizeof *P->y);
    P->ci = malloc((size_t)cap * sizeof *P->ci);
    P->co = malloc((size_t)cap * sizeof *P->co);
    P->S = malloc((size_t)cap * sizeof *P->S);
    P->s = malloc((size_t)cap * sizeof *P->s);
    if (!P->nn || !P->wi || !P->wo || !P->y || !P->ci || !P->co || !P->S || !P->s) {
        gltf_pairs_free(P);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d glTF fit pairs", cap);
    }
    P->cap = cap;
    return 0;
}

void gltf_pairs_fill(gltf_pairs *P, const samples *smp, int cap, gltf_fn fn, const void *ctx)
{
    int k = 0, total = smp ? smp->n : GLTF_FIT_PAIRS;
    if (cap > P->cap)
        cap = P->cap;
    if (cap > total)
        cap = total;
    for (int j = 0; j < cap; j++) {
        long i = (long)((double)j * total / cap); /* every (total / cap)-th */
        if (smp) { /* the painted directions */
            for (int e = 0; e < 3; e++) {
                P->nn[k][e] = smp->nrm[3 * i + e];
                P->wi[k][e] = smp->wi[3 * i + e];
                P->wo[k][e] = smp->wo[3 * i + e];
            }
        } else {
            P->nn[k][0] = P->nn[k][1] = 0.0, P->nn[k][2] = 1.0;
            fib((int)(i / GLTF_FIT_VIEWS), GLTF_FIT_LIGHTS, P->wi[k]);
            fib((int)(i % GLTF_FIT_VIEWS), GLTF_FIT_VIEWS, P->wo[k]);
        }
        P->ci[k] = P->nn[k][0] * P->wi[k][0] + P->nn[k][1] * P->wi[k][1] +
                   P->nn[k][2] * P->wi[k][2];
        P->co[k] = P->nn[k][0] * P->wo[k][0] + P->nn[k][1] * P->wo[k][1] +
                   P->nn[k][2] * P->wo[k][2];
        if (!(P->ci[k] > 0.0 && P->co[k] > 0.0))
            continue;
        if (fn) {
            double y[3];
            fn(ctx, P->nn[k], P->wi[k], P->wo[k], y);
            if (!isfinite(y[0] + y[1] + y[2]))
                continue;
            memcpy(P->y[k], y, sizeof y);
        }
        k++;
    }
    P->n = k;
}

static void material_fn(const void *ctx, const double n[3], const double wi[3],
                        const double wo[3], double rad[3])
{
    material_eval(ctx, n, wi, wo, rad);
}

/* The note of an anisotropic material (out->anisotropy above
 * GLTF_ANISO_NOTE): what the .glb and the other files hold of it. */
static void aniso_note(gltf_pbr *out)
{
    size_t k = strlen(out->note);
    if (out->aniso.used)
        snprintf(out->note + k, sizeof out->note - k,
                 "%sThe material is anisotropic (turned %.0f degrees about the normal, it "
                 "changes by %.0f%%): the .glb carries it with KHR_materials_anisotropy "
                 "(strength %.2f, rotation %.0f degrees from glint's tangent; relative RMS "
                 "%.4f against the isotropic fit's %.4f); MaterialX and USD hold the "
                 "isotropic fit.",
                 k ? " " : "", GLTF_ANISO_TURN * 180.0 / M_PI, 100.0 * out->anisotropy,
                 out->aniso.strength, out->aniso.rotation * 180.0 / M_PI, out->aniso.rel_rms,
                 out->rel_rms);
    else
        snprintf(out->note + k, sizeof out->note - k,
                 "%sThe material is anisotropic (turned %.0f degrees about the normal, it "
                 "changes by %.0f%%): the glTF material is its isotropic fit%s.",
                 k ? " " : "", GLTF_ANISO_TURN * 180.0 / M_PI, 100.0 * out->anisotropy,
                 out->spatial ? " (KHR_materials_anisotropy is written for a material "
                                "uniform over the surface only)"
                              : "");
}

int gltf_fit_material(const material *m, const samples *s, gltf_pbr *out, glint_err *err)
{
    double aniso;
    int rc;
    memset(out, 0, sizeof *out);
    if (!m || !m->method)
        return glint_err_set(err, GLINT_EINVAL, "no material to fit");
    if ((rc = gltf_fit(material_fn, m, s, out, err)))
        return rc;
    out->spatial = material_spatial(m);
    aniso = out->anisotropy;
    if ((rc = gltf_direct_choose(m, s, out, err)))
        return rc;
    out->anisotropy = aniso;
    if (aniso > GLTF_ANISO_NOTE && !out->spatial && !out->exact &&
        (rc = gltf_fit_aniso(material_fn, m, s, out, err)))
        return rc;
    if (aniso > GLTF_ANISO_NOTE)
        aniso_note(out);
    return 0;
}

/* How much fn changes over P's pairs when both directions turn
 * GLTF_ANISO_TURN about the normal (Rodrigues' rotation): the relative RMS
 * of the change of f cos (its cosine unchanged by the turn). */
static double anisotropy_of(gltf_fn fn, const void *ctx, const gltf_pairs *P, double den)
{
    double c = cos(GLTF_ANISO_TURN), sn = sin(GLTF_ANISO_TURN), num = 0.0;
    for (int k = 0; k < P->n; k++) {
        const double *n = P->nn[k];
        double d[2][3], y[3];
        for (int w = 0; w < 2; w++) {
            const double *v = w ? P->wo[k] : P->wi[k];
            double nv = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
            double x[3] = {n[1] * v[2] - n[2] * v[1], n[2] * v[0] - n[0] * v[2],
                           n[0] * v[1] - n[1] * v[0]};
            for (int e = 0; e < 3; e++)
                d[w][e] = v[e] * c + x[e] * sn + n[e] * nv * (1.0 - c);
        }
        fn(ctx, n, d[0], d[1], y);
        for (int e = 0; e < 3; e++)
            if (isfinite(y[e]))
                num += (y[e] - P->y[k][e]) * (y[e] - P->y[k][e]);
    }
    return den > 0.0 ? sqrt(num / den) : 0.0;
}

int gltf_fit(gltf_fn fn, const void *ctx, const samples *smp, gltf_pbr *out, glint_err *err)
{
    gltf_pairs P;
    double den = 0.0, best = INFINITY, bm = 0.0, br = 0.5, base[3];
    int rc, cap = smp ? (smp->n < GLTF_FIT_MAX_SAMPLES ? smp->n : GLTF_FIT_MAX_SAMPLES)
                      : GLTF_FIT_PAIRS;

    memset(out, 0, sizeof *out);
    if (!fn || cap < 1)
        return glint_err_set(err, GLINT_EINVAL, "nothing to fit a glTF material to");
    if ((rc = gltf_pairs_alloc(&P, cap, err)))
        return rc;
    gltf_pairs_fill(&P, smp, cap, fn, ctx);
    if (!P.n) {
        gltf_pairs_free(&P);
        return glint_err_set(err, GLINT_EINVAL, "no direction pair above the surface to fit");
    }
    for (int i = 0; i < P.n; i++)
        den += P.y[i][0] * P.y[i][0] + P.y[i][1] * P.y[i][1] + P.y[i][2] * P.y[i][2];
    for (int mi = 0; mi <= 20; mi++) /* a grid, then a finer one around its best */
        for (int ri = 1; ri <= 50; ri++) {
            double e = try_mr(&P, mi / 20.0, ri / 50.0, base);
            if (e < best)
                best = e, bm = mi / 20.0, br = ri / 50.0;
        }
    {
        double m0 = bm, r0 = br;
        for (int mi = -10; mi <= 10; mi++)
            for (int ri = -10; ri <= 10; ri++) {
                double mm = m0 + 0.005 * mi, rr = r0 + 0.002 * ri, e;
                if (mm < 0.0 || mm > 1.0 || rr < 0.01 || rr > 1.0)
                    continue;
                if ((e = try_mr(&P, mm, rr, base)) < best)
                    best = e, bm = mm, br = rr;
            }
    }
    try_mr(&P, bm, br, out->base);
    out->metallic = bm;
    out->roughness = br;
    out->rel_rms = den > 0.0 ? sqrt(best / den) : 0.0;
    out->rel_rms_fitted = out->rel_rms;
    out->rel_rms_exact = NAN;
    out->pairs = P.n;
    out->anisotropy = anisotropy_of(fn, ctx, &P, den);
    gltf_pairs_free(&P);
    return 0;
}

/* ---- the file ------------------------------------------------------------------------------ */

static void put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v, p[1] = (unsigned char)(v >> 8), p[2] = (unsigned char)(v >> 16),
    p[3] = (unsigned char)(v >> 24);
}

static json_t *view_of(size_t off, size_t len, int target)
{
    return json_pack("{s:i, s:I, s:I, s:i}", "buffer", 0, "byteOffset", (json_int_t)off,
                     "byteLength", (json_int_t)len, "target", target);
}

/* The material's KHR extensions (gltf_khr) and the document's
 * extensionsUsed naming them; nothing when p uses none. */
static int add_extensions(json_t *root, json_t *mat, const gltf_pbr *p)
{
    const gltf_khr *k = &p->khr;
    const char *names[GLTF_KHR_MAX];
    json_t *ext, *used;
    int n = gltf_khr_names(p, names), rc = 0;
    if (!n)
        return 0;
    ext = json_object();
    used = json_array();
    for (int i = 0; i < n; i++)
        rc |= json_array_append_new(used, json_string(names[i]));
    if (k->ior_used)
        rc |= json_object_set_new(ext, "KHR_materials_ior", json_pack("{s:f}", "ior", k->ior));
    if (k->specular_used)
        rc |= json_object_set_new(
            ext, "KHR_materials_specular",
            json_pack("{s:f, s:[f,f,f]}", "specularFactor", k->specular, "specularColorFactor",
                      k->specular_color[0], k->specular_color[1], k->specular_color[2]));
    if (k->clearcoat_used)
        rc |= json_object_set_new(ext, "KHR_materials_clearcoat",
                                  json_pack("{s:f, s:f}", "clearcoatFactor", k->clearcoat,
                                            "clearcoatRoughnessFactor", k->clearcoat_roughness));
    if (p->aniso.used)
        rc |= json_object_set_new(ext, "KHR_materials_anisotropy",
                                  json_pack("{s:f, s:f}", "anisotropyStrength", p->aniso.strength,
                                            "anisotropyRotation", p->aniso.rotation));
    rc |= json_object_set_new(mat, "extensions", ext);
    rc |= json_object_set_new(root, "extensionsUsed", used);
    return rc ? -1 : 0;
}

/* The mesh's TANGENT (glint's frame, KHR_materials_anisotropy's direction
 * before its rotation): buffer view and accessor 4, VEC4 floats. */
static int add_tangents(json_t *root, size_t off_tan, size_t nv)
{
    json_t *prim = json_array_get(
        json_object_get(json_array_get(json_object_get(root, "meshes"), 0), "primitives"), 0);
    int rc = 0;
    rc |= json_array_append_new(json_object_get(root, "bufferViews"),
                                view_of(off_tan, 16 * nv, 34962));
    rc |= json_array_append_new(json_object_get(root, "accessors"),
                                json_pack("{s:i, s:i, s:I, s:s}", "bufferView", 4,
                                          "componentType", 5126, "count", (json_int_t)nv,
                                          "type", "VEC4"));
    rc |= json_object_set_new(json_object_get(prim, "attributes"), "TANGENT",
                              json_integer(4));
    return rc ? -1 : 0;
}

/* The textures' part of the document: images in buffer views 4 and 5,
 * one sampler (linear, clamped at the edges: glint clamps uv to [0,1]),
 * and the material's pbrMetallicRoughness reading them with factors 1. */
static int add_textures(json_t *root, json_t *mat, size_t off_bc, size_t len_bc,
                        size_t off_mr, size_t len_mr)
{
    json_t *pbr = json_object_get(mat, "pbrMetallicRoughness");
    int rc = 0;
    rc |= json_array_append_new(json_object_get(root, "bufferViews"),
                                json_pack("{s:i, s:I, s:I}", "buffer", 0, "byteOffset",
                                          (json_int_t)off_bc, "byteLength", (json_int_t)len_bc));
    rc |= json_array_append_new(json_object_get(root, "bufferViews"),
                                json_pack("{s:i, s:I, s:I}", "buffer", 0, "byteOffset",
                                          (json_int_t)off_mr, "byteLength", (json_int_t)len_mr));
    rc |= json_object_set_new(root, "images",
                              json_pack("[{s:i, s:s, s:s}, {s:i, s:s, s:s}]", "bufferView", 4,
                                        "mimeType", "image/png", "name", "baseColor (sRGB)",
                                        "bufferView", 5, "mimeType", "image/png", "name",
                                        "metallicRoughness (linear: G roughness, B metallic)"));
    rc |= json_object_set_new(root, "samplers",
                              json_pack("[{s:i, s:i, s:i, s:i}]", "magFilter", 9729, "minFilter",
                                        9729, "wrapS", 33071, "wrapT", 33071));
    rc |= json_object_set_new(root, "textures",
                              json_pack("[{s:i, s:i}, {s:i, s:i}]", "sampler", 0, "source", 0,
                                        "sampler", 0, "source", 1));
    rc |= json_object_set_new(pbr, "baseColorTexture",
                              json_pack("{s:i, s:i}", "index", 0, "texCoord", 0));
    rc |= json_object_set_new(pbr, "metallicRoughnessTexture",
                              json_pack("{s:i, s:i}", "index", 1, "texCoord", 0));
    rc |= json_object_set_new(pbr, "baseColorFactor", json_pack("[f,f,f,f]", 1.0, 1.0, 1.0, 1.0));
    rc |= json_object_set_new(pbr, "metallicFactor", json_real(1.0));
    rc |= json_object_set_new(pbr, "roughnessFactor", json_real(1.0));
    return rc ? -1 : 0;
}

int gltf_write_glb(const mesh *msh, const gltf_pbr *p, const gltf_bake *bake, const char *name,
                   const char *extras_json, void **glb, size_t *len, glint_err *err)
{
    size_t nv, nt, off_pos, off_nrm, off_uv, off_idx, off_bc = 0, off_mr = 0, bin_len, json_len,
                                                      json_pad, bin_pad, total, off_tan = 0;
    int aniso = p && p->aniso.used && !bake;
    gltf_pbr core_p;
    const gltf_pbr *core = &core_p;
    size_t len_bc = 0, len_mr = 0;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    json_t *root, *extras = NULL, *mat;
    unsigned char *out, *bin;
    void *png_bc = NULL, *png_mr = NULL;
    char *text;
    int rc;

    *glb = NULL;
    *len = 0;
    if (!msh || msh->nverts < 3 || msh->ntris < 1 || !msh->pos || !msh->nrm || !msh->tri)
        return glint_err_set(err, GLINT_EINVAL, "no mesh to write");
    if (!p)
        return glint_err_set(err, GLINT_EINVAL, "no glTF material to write");
    core_p = *p; /* the core parameters written: the anisotropic fit's where it is kept */
    if (aniso) {
        memcpy(core_p.base, p->aniso.base, sizeof core_p.base);
        core_p.metallic = p->aniso.metallic;
        core_p.roughness = p->aniso.roughness;
    } else
        core_p.aniso.used = 0;
    if (bake && !msh->uv)
        return glint_err_set(err, GLINT_EINVAL,
                             "the mesh has no texture coordinates to map baked textures with");
    if (bake && (rc = gltf_bake_png(bake, &png_bc, &len_bc, &png_mr, &len_mr, err)))
        return rc;
    if (extras_json && !(extras = json_loads(extras_json, 0, NULL))) {
        free(png_bc), free(png_mr);
        return glint_err_set(err, GLINT_EINVAL, "the material's extras are not JSON");
    }
    nv = (size_t)msh->nverts;
    nt = (size_t)msh->ntris;
    off_pos = 0;
    off_nrm = off_pos + 12 * nv;
    off_uv = off_nrm + 12 * nv;
    off_idx = off_uv + 8 * nv;
    bin_len = off_idx + 12 * nt;
    if (aniso) { /* the tangents after the indices (an anisotropic material has no bake) */
        off_tan = bin_len;
        bin_len = off_tan + 16 * nv;
    }
    if (bake) { /* the images after the indices, each at a multiple of 4 */
        off_bc = bin_len;
        off_mr = off_bc + len_bc + (4 - len_bc % 4) % 4;
        bin_len = off_mr + len_mr;
    }
    for (size_t i = 0; i < nv; i++)
        for (int e = 0; e < 3; e++) {
            float v = msh->pos[3 * i + e];
            lo[e] = v < lo[e] ? v : lo[e];
            hi[e] = v > hi[e] ? v : hi[e];
        }
    mat = json_pack("{s:s, s:{s:[f,f,f,f], s:f, s:f}}", "name", name ? name : "glint",
                    "pbrMetallicRoughness", "baseColorFactor", core->base[0], core->base[1],
                    core->base[2], 1.0, "metallicFactor", core->metallic, "roughnessFactor",
                    core->roughness);
    if (!mat)
        json_decref(extras);
    else if (extras)
        json_object_set_new(mat, "extras", extras);
    root = json_pack(
        "{s:{s:s, s:s}, s:i, s:[{s:[i]}], s:[{s:i, s:s}], "
        "s:[{s:s, s:[{s:{s:i, s:i, s:i}, s:i, s:i, s:i}]}], s:[o], s:[{s:I}], "
        "s:[o, o, o, o], "
        "s:[{s:i, s:i, s:I, s:s, s:[f,f,f], s:[f,f,f]}, {s:i, s:i, s:I, s:s}, "
        "{s:i, s:i, s:I, s:s}, {s:i, s:i, s:I, s:s}]}",
        "asset", "version", "2.0", "generator", "glint", "scene", 0, "scenes", "nodes", 0,
        "nodes", "mesh", 0, "name", name ? name : "glint", "meshes", "name",
        name ? name : "glint", "primitives", "attributes", "POSITION", 0, "NORMAL", 1,
        "TEXCOORD_0", 2, "indices", 3, "material", 0, "mode", 4, "materials", mat, "buffers",
        "byteLength", (json_int_t)bin_len, "bufferViews", view_of(off_pos, 12 * nv, 34962),
        view_of(off_nrm, 12 * nv, 34962), view_of(off_uv, 8 * nv, 34962),
        view_of(off_idx, 12 * nt, 34963), "accessors", "bufferView", 0, "componentType", 5126,
        "count", (json_int_t)nv, "type", "VEC3", "min", (double)lo[0], (double)lo[1],
        (double)lo[2], "max", (double)hi[0], (double)hi[1], (double)hi[2], "bufferView", 1,
        "componentType", 5126, "count", (json_int_t)nv, "type", "VEC3", "bufferView", 2,
        "componentType", 5126, "count", (json_int_t)nv, "type", "VEC2", "bufferView", 3,
        "componentType", 5125, "count", (json_int_t)(3 * nt), "type", "SCALAR");
    if (root && (add_extensions(root, mat, core) || (aniso && add_tangents(root, off_tan, nv)) ||
                 (bake && add_textures(root, mat, off_bc, len_bc, off_mr, len_mr)))) {
        json_decref(root);
        root = NULL;
    }
    text = root ? json_dumps(root, JSON_COMPACT | JSON_REAL_PRECISION(9)) : NULL;
    json_decref(root);
    if (!text) {
        free(png_bc), free(png_mr);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the glTF document");
    }
    json_len = strlen(text);
    json_pad = (4 - json_len % 4) % 4;
    bin_pad = (4 - bin_len % 4) % 4;
    total = 12 + 8 + json_len + json_pad + 8 + bin_len + bin_pad;
    if (total > UINT32_MAX || !(out = malloc(total))) {
        free(text);
        free(png_bc), free(png_mr);
        return glint_err_set(err, GLINT_ENOMEM, "a glTF file of %zu bytes", total);
    }
    put_u32(out, 0x46546C67u); /* "glTF" */
    put_u32(out + 4, 2);
    put_u32(out + 8, (uint32_t)total);
    put_u32(out + 12, (uint32_t)(json_len + json_pad));
    put_u32(out + 16, 0x4E4F534Au); /* "JSON" */
    memcpy(out + 20, text, json_len);
    memset(out + 20 + json_len, ' ', json_pad);
    free(text);
    bin = out + 20 + json_len + json_pad;
    put_u32(bin, (uint32_t)(bin_len + bin_pad));
    put_u32(bin + 4, 0x004E4942u); /* "BIN" */
    bin += 8;
    memcpy(bin + off_pos, msh->pos, 12 * nv);
    memcpy(bin + off_nrm, msh->nrm, 12 * nv);
    for (size_t i = 0; i < nv; i++) { /* glTF's texture origin is the top left: v down */
        float uv[2] = {msh->uv ? msh->uv[2 * i] : 0.0f, msh->uv ? 1.0f - msh->uv[2 * i + 1] : 0.0f};
        memcpy(bin + off_uv + 8 * i, uv, 8);
    }
    memcpy(bin + off_idx, msh->tri, 12 * nt);
    for (size_t i = 0; aniso && i < nv; i++) { /* glint's tangent frame, w 1: b = n x t */
        v3 t, b;
        float tw[4];
        v3_frame(v3_make(msh->nrm[3 * i], msh->nrm[3 * i + 1], msh->nrm[3 * i + 2]), &t, &b);
        tw[0] = (float)t.x, tw[1] = (float)t.y, tw[2] = (float)t.z, tw[3] = 1.0f;
        memcpy(bin + off_tan + 16 * i, tw, 16);
    }
    if (bake) {
        memcpy(bin + off_bc, png_bc, len_bc);
        memset(bin + off_bc + len_bc, 0, off_mr - off_bc - len_bc);
        memcpy(bin + off_mr, png_mr, len_mr);
    }
    memset(bin + bin_len, 0, bin_pad);
    free(png_bc), free(png_mr);
    *glb = out;
    *len = total;
    return 0;
}

/* ---- a material on its scene ------------------------------------------------------------ */

/* Which path the material took (the pbr parameters mapped, or the fit),
 * both errors and what the mapping leaves out, into the extras' object g. */
static int extras_path(json_t *g, const gltf_pbr *p)
{
    int rc = 0;
    rc |= json_object_set_new(g, "export", json_string(p->exact ? "exact parameters" : "fitted"));
    rc |= json_object_set_new(g, "rel_rms_fitted", json_real(p->rel_rms_fitted));
    rc |= json_object_set_new(g, "errors_smith",
                              json_string(p->smith == GLTF_SMITH_CORRELATED
                                              ? "height-correlated (as glTF-Sample-Viewer and "
                                                "three.js render)"
                                              : "separable (Appendix B's text)"));
    rc |= json_object_set_new(g, "rel_rms_exact", isfinite(p->rel_rms_exact)
                                                      ? json_real(p->rel_rms_exact)
                                                      : json_null());
    if (p->exact)
        rc |= json_object_set_new(
            g, "fit", json_string("the pbr material's own parameters mapped onto glTF with the "
                                  "KHR extensions (closer than the fit: rel_rms_exact against "
                                  "rel_rms_fitted at the painted views' samples)"));
    rc |= json_object_set_new(g, "anisotropy", json_real(p->anisotropy));
    if (p->aniso.used)
        rc |= json_object_set_new(
            g, "anisotropic_fit",
            json_pack("{s:f, s:f, s:[f,f,f], s:f, s:f, s:f, s:s}", "strength", p->aniso.strength,
                      "rotation", p->aniso.rotation, "base_color", p->aniso.base[0],
                      p->aniso.base[1], p->aniso.base[2], "metallic", p->aniso.metallic,
                      "roughness", p->aniso.roughness, "rel_rms", p->aniso.rel_rms, "tangent",
                      "glint's: normalize(Z x n), +X at the poles; TANGENT w 1 (b = n x t)"));
    if (p->note[0])
        rc |= json_object_set_new(g, "note", json_string(p->note));
    return rc ? -1 : 0;
}

static char *extras_text(const material *m, const gltf_pbr *p, const gltf_bake *bake,
                         const char *note)
{
    json_t *o = json_pack("{s:{s:s, s:s, s:f, s:i, s:s, s:b, s:s}}", "glint", "method",
                          material_method_name(m), "model",
                          p->exact ? "glTF 2.0 metallic-roughness (Appendix B) with the KHR extensions used; "
                                     "alpha = roughness^2"
                                   : "glTF 2.0 metallic-roughness (Appendix B); alpha = roughness^2",
                          "fit_rel_rms", p->rel_rms, "fit_pairs", p->pairs, "fit",
                          "least squares of f cos at the painted views' samples", "spatial_average",
                          p->spatial && !bake, "units",
                          "the BRDF of what was painted: a painted value is pi I f cos under a "
                          "light of intensity I (a white Lambertian facing it reads I)");
    json_t *g = json_object_get(o, "glint");
    char *t;
    if (g && extras_path(g, p))
        g = NULL;
    if (g && bake) {
        json_object_set_new(
            g, "textures",
            json_pack("{s:i, s:i, s:i, s:f, s:f, s:I, s:f, s:s, s:s, s:s}", "res", bake->res,
                      "pairs_per_texel", bake->pairs, "far_texels", bake->far_texels,
                      "texel_rel_rms_median",
                      bake->rel_rms_median, "texel_rel_rms_max", bake->rel_rms_max,
                      "nonfinite_values", (json_int_t)bake->nonfinite, "seconds", bake->seconds,
                      "base_color", "8-bit PNG, sRGB-encoded, baseColorFactor 1",
                      "metallic_roughness",
                      "8-bit PNG, linear: G roughness, B metallic, R 1; factors 1",
                      "fit", "per texel at its centre over the directions painted in and "
                             "around it (far texels: over all painted directions), from the "
                             "average's fit (fit_rel_rms and average) and a coarse grid"));
        json_object_set_new(g, "average",
                            json_pack("{s:[f,f,f], s:f, s:f}", "base_color", p->base[0],
                                      p->base[1], p->base[2], "metallic", p->metallic,
                                      "roughness", p->roughness));
    }
    if (g && note && *note)
        json_object_set_new(g, "textures_not_baked", json_string(note));
    t = o ? json_dumps(o, JSON_COMPACT | JSON_REAL_PRECISION(6)) : NULL;
    json_decref(o);
    return t;
}

/* The samples of the views flagged in `use` (NULL: all) of sc (OUT: *s,
 * samples_free; the G-buffers are freed here: samples copy what they need). */
static int scene_samples(const scene *sc, const unsigned char *use, samples *s, glint_err *err)
{
    gbuf *g = NULL;
    char hash[33];
    int rc;
    scene_hash(sc, hash);
    if (!(rc = raster_scene(sc, &g, err)))
        rc = samples_build(g, sc->views, sc->nviews, use, hash, s, err);
    raster_free_all(g, sc->nviews);
    return rc;
}

int gltf_fit_scene(const material *m, const scene *sc, const unsigned char *use, gltf_pbr *out,
                   glint_err *err)
{
    samples s;
    int rc;
    memset(&s, 0, sizeof s);
    memset(out, 0, sizeof *out);
    if (!(rc = scene_samples(sc, use, &s, err)))
        rc = gltf_fit_material(m, &s, out, err);
    samples_free(&s);
    return rc;
}

int gltf_bake_scene(const material *m, const scene *sc, const unsigned char *use, int bake_res,
                    gltf_pbr *out, gltf_bake *bake, gltf_export_info *info, glint_err *err)
{
    samples s;
    int rc;

    memset(info, 0, sizeof *info);
    memset(&s, 0, sizeof s);
    memset(bake, 0, sizeof *bake);
    if (bake_res < 0 || bake_res > GLTF_BAKE_RES_MAX)
        return glint_err_set(err, GLINT_ERANGE, "texture size %d outside 0..%d (0: no textures)",
                             bake_res, GLTF_BAKE_RES_MAX);
    if ((rc = scene_samples(sc, use, &s, err)) || (rc = gltf_fit_material(m, &s, out, err)))
        goto done;
    if (out->spatial && !bake_res)
        snprintf(info->note, sizeof info->note, "textures were not asked for: the average only");
    else if (out->spatial && !sc->mesh.uv)
        snprintf(info->note, sizeof info->note,
                 "the mesh has no texture coordinates: the average only");
    else if (out->spatial) {
        if ((rc = gltf_bake_material(m, &s, out, bake_res, bake, err)))
            goto done;
        info->baked = 1;
        info->res = bake->res;
        info->pairs = bake->pairs;
        info->rel_rms_median = bake->rel_rms_median;
        info->rel_rms_max = bake->rel_rms_max;
        info->seconds = bake->seconds;
    }
done:
    samples_free(&s);
    return rc;
}

int gltf_bake_scene_png(const material *m, const scene *sc, const unsigned char *use,
                        int bake_res, gltf_pbr *out, gltf_pngs *png, gltf_export_info *info,
                        glint_err *err)
{
    gltf_bake bake;
    int rc;
    memset(png, 0, sizeof *png);
    if (!(rc = gltf_bake_scene(m, sc, use, bake_res, out, &bake, info, err)) && info->baked)
        rc = gltf_bake_png(&bake, &png->base, &png->base_len, &png->mr, &png->mr_len, err);
    gltf_bake_free(&bake);
    return rc;
}

void gltf_pngs_free(gltf_pngs *png)
{
    if (!png)
        return;
    free(png->base);
    free(png->mr);
    memset(png, 0, sizeof *png);
}

int gltf_export_scene(const material *m, const scene *sc, const unsigned char *use,
                      int bake_res, void **glb, size_t *len, gltf_pbr *out,
                      gltf_export_info *info, glint_err *err)
{
    gltf_bake bake;
    gltf_export_info dummy;
    char *extras = NULL;
    int rc;

    *glb = NULL;
    *len = 0;
    if (!info)
        info = &dummy;
    if ((rc = gltf_bake_scene(m, sc, use, bake_res, out, &bake, info, err)))
        goto done;
    if (!(extras = extras_text(m, out, info->baked ? &bake : NULL, info->note))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    rc = gltf_write_glb(&sc->mesh, out, info->baked ? &bake : NULL, "glint material", extras,
                        glb, len, err);
done:
    free(extras);
    gltf_bake_free(&bake);
    return rc;
}
