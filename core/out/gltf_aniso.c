/* gltf_aniso.c: an anisotropic material as glTF's metallic-roughness model
 * with KHR_materials_anisotropy (gltf.h's gltf_aniso): the model and its
 * fit.
 *
 * The lobe (the extension's "Implementation" section, KhronosGroup/glTF
 * extensions/2.0/Khronos/KHR_materials_anisotropy): T the direction (the
 * tangent turned by the rotation towards the bitangent), B = n x T,
 *   alpha_t = mix(alpha, 1, strength^2), alpha_b = alpha = roughness^2,
 *   D = a2 w2^2 / pi, a2 = alpha_t alpha_b, w2 = a2 / |(alpha_b T.h,
 *       alpha_t B.h, a2 n.h)|^2,
 *   V = 0.5 / (n.l |(alpha_t T.v, alpha_b B.v, n.v)| + n.v |(alpha_t T.l,
 *       alpha_b B.l, n.l)|), clamped to [0, 1],
 * and S = D V in place of the isotropic D G / (4 n.l n.v); the Fresnel and
 * the diffuse as the core model's layered form (gltf_khr.c). The tangent
 * frame is glint's (vec3.h's v3_frame), which the .glb writes as TANGENT.
 *
 * The fit: rotation (axial: [0, pi)), strength and roughness on a grid at
 * the isotropic fit's metallic over every fourth pair, then around the best
 * on every pair with metallic too, then each of the four in turn with
 * halving steps; each candidate's base colour is exact (least squares per
 * channel, clamped to [0, 1]: the layered form, in which the file is read,
 * is linear in it).  Thread-safety: no state. */
#include <math.h>
#include <string.h>

#include "gltf.h"
#include "internal/gltf_int.h"
#include "vec3.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define ROT_STEPS 12     /* the coarse rotations: 15 degrees apart */
#define STR_STEPS 10     /* strengths 0.1 .. 1 */
#define ROUGH_STEPS 25   /* roughnesses 0.04 .. 1 */

/* S = D V and w = (1 - |v.h|)^5 of the anisotropic lobe (ci, co > 0). */
static void aniso_terms(double strength, double rotation, double roughness, const double n[3],
                        const double wi[3], const double wo[3], double ci, double co,
                        double *S, double *w)
{
    v3 N = v3_load(n), t0, b0, T, B, L = v3_load(wi), V = v3_load(wo), H;
    double ab = roughness * roughness, at, a2, th, bh, nh, gv, gl, vis, w2, d, vh;
    ab = ab > 1e-3 ? ab : 1e-3;
    at = ab + (1.0 - ab) * strength * strength;
    v3_frame(N, &t0, &b0);
    T = v3_add(v3_scale(t0, cos(rotation)), v3_scale(b0, sin(rotation)));
    B = v3_cross(N, T);
    H = v3_normalize(v3_add(L, V));
    th = v3_dot(T, H), bh = v3_dot(B, H), nh = v3_dot(N, H);
    a2 = at * ab;
    d = (ab * th) * (ab * th) + (at * bh) * (at * bh) + (a2 * nh) * (a2 * nh);
    w2 = a2 / d;
    gv = ci * sqrt(at * at * v3_dot(T, V) * v3_dot(T, V) + ab * ab * v3_dot(B, V) * v3_dot(B, V) +
                   co * co);
    gl = co * sqrt(at * at * v3_dot(T, L) * v3_dot(T, L) + ab * ab * v3_dot(B, L) * v3_dot(B, L) +
                   ci * ci);
    vis = 0.5 / (gv + gl);
    vis = vis < 1.0 ? vis : 1.0;
    *S = a2 * w2 * w2 / M_PI * vis;
    vh = fabs(v3_dot(V, H));
    vh = 1.0 - (vh < 1.0 ? vh : 1.0);
    *w = vh * vh * vh * vh * vh;
}

void gltf_aniso_brdf(const gltf_aniso *a, const double n[3], const double wi[3],
                     const double wo[3], double rgb[3])
{
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    double co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2], S, w, F, m = a->metallic;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(ci > 0.0) || !(co > 0.0))
        return;
    aniso_terms(a->strength, a->rotation, a->roughness, n, wi, wo, ci, co, &S, &w);
    F = 0.04 + 0.96 * w;
    for (int c = 0; c < 3; c++) {
        double b = a->base[c];
        double diel = F * S + (1.0 - F) * b / M_PI, metal = (b + (1.0 - b) * w) * S;
        rgb[c] = (1.0 - m) * diel + m * metal;
    }
}

/* The squared error over P's pairs of metallic m with the lobe's S[i] and
 * w[i] and the best base colour in [0, 1] per channel (OUT: base).  In the
 * layered form f = A + B b is linear in the base colour b: A = ((1 - m) F +
 * m w) S, B = (1 - m)(1 - F) / pi + m (1 - w) S, F = 0.04 + 0.96 w. */
static double layered_error(const gltf_pairs *P, const double *S, const double *w, double m,
                            double base[3])
{
    double rr[3] = {0}, rg[3] = {0}, gg[3] = {0}, total = 0.0;
    for (int i = 0; i < P->n; i++) {
        double F = 0.04 + 0.96 * w[i], ci = P->ci[i];
        double A = ((1.0 - m) * F + m * w[i]) * S[i];
        double B = (1.0 - m) * (1.0 - F) / M_PI + m * (1.0 - w[i]) * S[i];
        for (int c = 0; c < 3; c++) {
            double r = P->y[i][c] - ci * A, g = ci * B;
            rr[c] += r * r, rg[c] += r * g, gg[c] += g * g;
        }
    }
    for (int c = 0; c < 3; c++) {
        double b = gg[c] > 0.0 ? rg[c] / gg[c] : 0.0;
        b = b < 0.0 ? 0.0 : b > 1.0 ? 1.0 : b;
        base[c] = b;
        total += rr[c] - 2.0 * b * rg[c] + b * b * gg[c];
    }
    return total;
}

/* The squared error of (rotation, strength, roughness, metallic) over P's
 * pairs with its best base colour (OUT: base); P's S and s are scratch. */
static double try_aniso(gltf_pairs *P, double rot, double str, double rough, double m,
                        double base[3])
{
    for (int i = 0; i < P->n; i++)
        aniso_terms(str, rot, rough, P->nn[i], P->wi[i], P->wo[i], P->ci[i], P->co[i], &P->S[i],
                    &P->s[i]);
    return layered_error(P, P->S, P->s, m, base);
}

/* Every k-th pair of P into Q (allocated here). */
static int pairs_every(const gltf_pairs *P, int k, gltf_pairs *Q, glint_err *err)
{
    int rc = gltf_pairs_alloc(Q, (P->n + k - 1) / k, err);
    if (rc)
        return rc;
    for (int i = 0; i < P->n; i += k, Q->n++) {
        memcpy(Q->nn[Q->n], P->nn[i], sizeof P->nn[i]);
        memcpy(Q->wi[Q->n], P->wi[i], sizeof P->wi[i]);
        memcpy(Q->wo[Q->n], P->wo[i], sizeof P->wo[i]);
        memcpy(Q->y[Q->n], P->y[i], sizeof P->y[i]);
        Q->ci[Q->n] = P->ci[i];
        Q->co[Q->n] = P->co[i];
    }
    return 0;
}

/* The search: a coarse grid on Q at metallic m0, then a finer one on P
 * around its best with metallic on a grid (OUT: a's parameters; returns the
 * squared error on P). */
static double search(gltf_pairs *P, gltf_pairs *Q, double m0, gltf_aniso *a)
{
    double best = INFINITY, br = 0.0, bs = 0.5, bg = 0.5, bm = m0, base[3];
    for (int i = 0; i < ROT_STEPS; i++)
        for (int j = 1; j <= STR_STEPS; j++)
            for (int k = 1; k <= ROUGH_STEPS; k++) {
                double rot = M_PI * i / ROT_STEPS, str = (double)j / STR_STEPS;
                double rough = (double)k / ROUGH_STEPS, e = try_aniso(Q, rot, str, rough, m0, base);
                if (e < best)
                    best = e, br = rot, bs = str, bg = rough;
            }
    best = INFINITY;
    {
        double r0 = br, s0 = bs, g0 = bg;
        for (int i = -5; i <= 5; i++)
            for (int j = -5; j <= 5; j++)
                for (int k = -4; k <= 4; k++) {
                    double rot = r0 + i * (M_PI / ROT_STEPS / 5.0), str = s0 + 0.02 * j;
                    double rough = g0 + 0.01 * k, e;
                    if (str < 0.0 || str > 1.0 || rough < 0.01 || rough > 1.0)
                        continue;
                    if ((e = try_aniso(P, rot, str, rough, m0, base)) < best)
                        best = e, br = rot, bs = str, bg = rough;
                }
    }
    for (int mi = 0; mi <= 20; mi++) {
        double e = try_aniso(P, br, bs, bg, mi / 20.0, base);
        if (e < best)
            best = e, bm = mi / 20.0;
    }
    { /* then each parameter in turn, its step halved when neither side is better */
        double x[4] = {br, bs, bg, bm}, step[4] = {M_PI / ROT_STEPS / 10.0, 0.01, 0.005, 0.025};
        static const double lo[4] = {-1e9, 0.0, 0.01, 0.0}, hi[4] = {1e9, 1.0, 1.0, 1.0};
        for (int it = 0; it < 12; it++)
            for (int q = 0; q < 4; q++)
                for (int sgn = -1; sgn <= 1; sgn += 2) {
                    double y[4] = {x[0], x[1], x[2], x[3]}, e;
                    y[q] += sgn * step[q];
                    if (y[q] < lo[q] || y[q] > hi[q])
                        continue;
                    if ((e = try_aniso(P, y[0], y[1], y[2], y[3], base)) < best) {
                        best = e, x[q] = y[q];
                        break;
                    }
                    if (sgn == 1)
                        step[q] *= 0.5;
                }
        br = x[0], bs = x[1], bg = x[2], bm = x[3];
    }
    br = fmod(br, M_PI);
    a->rotation = br < 0.0 ? br + M_PI : br;
    a->strength = bs;
    a->roughness = bg;
    a->metallic = bm;
    try_aniso(P, a->rotation, bs, bg, bm, a->base);
    return best;
}

int gltf_fit_aniso(gltf_fn fn, const void *ctx, const samples *smp, gltf_pbr *out,
                   glint_err *err)
{
    gltf_pairs P, Q;
    gltf_aniso a;
    double den = 0.0, num = 0.0;
    int rc, cap = smp ? (smp->n < GLTF_FIT_MAX_SAMPLES ? smp->n : GLTF_FIT_MAX_SAMPLES)
                      : GLTF_FIT_PAIRS;
    memset(&out->aniso, 0, sizeof out->aniso);
    memset(&Q, 0, sizeof Q);
    if (!fn || cap < 1)
        return glint_err_set(err, GLINT_EINVAL, "nothing to fit a glTF material to");
    if ((rc = gltf_pairs_alloc(&P, cap, err)))
        return rc;
    gltf_pairs_fill(&P, smp, cap, fn, ctx);
    if (P.n < 1 || (rc = pairs_every(&P, 4, &Q, err))) {
        gltf_pairs_free(&P);
        return rc;
    }
    memset(&a, 0, sizeof a);
    search(&P, &Q, out->metallic, &a);
    for (int i = 0; i < P.n; i++) { /* measured in the layered form the file means */
        double f[3];
        gltf_aniso_brdf(&a, P.nn[i], P.wi[i], P.wo[i], f);
        for (int c = 0; c < 3; c++) {
            double d = f[c] * P.ci[i] - P.y[i][c];
            num += d * d;
            den += P.y[i][c] * P.y[i][c];
        }
    }
    a.rel_rms = den > 0.0 ? sqrt(num / den) : 0.0;
    a.used = a.rel_rms < out->rel_rms;
    out->aniso = a;
    gltf_pairs_free(&Q);
    gltf_pairs_free(&P);
    return 0;
}
