/* test_gltf.c: glTF 2.0 metallic-roughness materials (gltf.h).
 * - The model is the specification's: for a metal (metallic 1, no diffuse)
 *   it is exactly glint's Cook-Torrance truth with kd 0, f0 = base colour
 *   and alpha = roughness^2 (the two conventions side by side).
 * - The fit recovers a metal and a dielectric it can represent from their
 *   own values (to the grid's step), and reports the error of one it
 *   cannot (a Phong lobe).
 * - A fitted hf3 material (Cook-Torrance painting) at its painted samples
 *   reads the truth's base colour and roughness.
 * - The .glb file: header, chunks, the document's accessors and the binary
 *   chunk agree with the mesh.
 * - The roughness convention, by rendering: the glint material (material_render)
 *   and the .glb's material, read back from the file (its JSON chunk, its
 *   mesh and, when baked, its PNG textures) and shaded by an evaluation of
 *   the glTF specification's BRDF written here (not gltf_brdf), in the
 *   same views: alpha = roughness^2 matches, alpha = roughness measurably
 *   does not.  For one material (a Cook-Torrance plastic, a metal) and for
 *   a material of maps (red plastic with gold stripes, and squares) baked per
 *   texel, whose textures read mirrored in s or t render worse (the
 *   orientation of glTF's texture coordinates).  A material the same
 *   everywhere bakes its average. */
#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdf.h"
#include "check.h"
#include "gltf.h"
#include "method_hf3.h"
#include "method_maps.h"
#include "raster.h"
#include "sv_fixture.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* the fixture's views, SIZE x SIZE: at 48 a material of maps of the
 * stripes is 30 to 70% from its truth in renders, at 64 under 30% */
#define SIZE 64

static scene SC;
static gbuf *G;
static cache *C;
static cache_entry *SE;

typedef struct cosf_ctx {
    const gltf_pbr *p;
    const brdf *b;
} cosf_ctx;

/* radiance per unit light of a glTF material or a truth */
static void rad(const void *ctx, const double n[3], const double wi[3], const double wo[3],
                double out[3])
{
    const cosf_ctx *x = ctx;
    double c = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    if (x->p)
        gltf_brdf(x->p, n, wi, wo, out);
    else
        brdf_eval(x->b, n, wi, wo, out);
    for (int e = 0; e < 3; e++)
        out[e] *= c > 0.0 ? c : 0.0;
}

/* radiance per unit light of an anisotropic glTF material */
static void rad_aniso(const void *ctx, const double n[3], const double wi[3], const double wo[3],
                      double out[3])
{
    double c = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    gltf_aniso_brdf(ctx, n, wi, wo, out);
    for (int e = 0; e < 3; e++)
        out[e] *= c > 0.0 ? c : 0.0;
}

TEST(a_metal_is_glints_cook_torrance_with_alpha_roughness_squared)
{
    gltf_pbr p = {.base = {0.9, 0.6, 0.3}, .metallic = 1.0, .roughness = 0.4};
    brdf b;
    glint_err e;
    double worst = 0.0;
    unsigned s = 3;
    ASSERT_OK(brdf_parse("ct:kd=0,f0=0.9/0.6/0.3,rough=0.16", &b, &e));
    for (int q = 0; q < 2000; q++) {
        double n[3] = {0, 0, 1}, wi[3], wo[3], f[3], g[3], t1, t2, p1, p2;
        s = s * 1664525u + 1013904223u, t1 = acos((s >> 8) / 16777216.0);
        s = s * 1664525u + 1013904223u, t2 = acos((s >> 8) / 16777216.0);
        s = s * 1664525u + 1013904223u, p1 = 6.283185307 * (s >> 8) / 16777216.0;
        s = s * 1664525u + 1013904223u, p2 = 6.283185307 * (s >> 8) / 16777216.0;
        wi[0] = sin(t1) * cos(p1), wi[1] = sin(t1) * sin(p1), wi[2] = cos(t1);
        wo[0] = sin(t2) * cos(p2), wo[1] = sin(t2) * sin(p2), wo[2] = cos(t2);
        gltf_brdf(&p, n, wi, wo, g);
        brdf_eval(&b, n, wi, wo, f);
        for (int c = 0; c < 3; c++)
            worst = fmax(worst, fabs(f[c] - g[c]) / (fabs(f[c]) + 1e-12));
    }
    printf("  glTF metal (roughness 0.4) against ct (alpha 0.16): worst relative %.2e\n", worst);
    ASSERT_LT(worst, 1e-12);
}

TEST(the_fit_recovers_what_the_model_can_represent)
{
    static const gltf_pbr truths[2] = {
        {.base = {0.9, 0.6, 0.3}, .metallic = 1.0, .roughness = 0.3},
        {.base = {0.5, 0.3, 0.2}, .metallic = 0.0, .roughness = 0.5}};
    for (int t = 0; t < 2; t++) {
        cosf_ctx x = {&truths[t], NULL};
        gltf_pbr got;
        glint_err e;
        ASSERT_OK(gltf_fit(rad, &x, NULL, &got, &e));
        printf("  truth base %.2f/%.2f/%.2f metallic %.2f roughness %.2f: fitted %.4f/%.4f/%.4f, "
               "%.4f, %.4f, relative RMS %.2e over %d pairs\n",
               truths[t].base[0], truths[t].base[1], truths[t].base[2], truths[t].metallic,
               truths[t].roughness, got.base[0], got.base[1], got.base[2], got.metallic,
               got.roughness, got.rel_rms, got.pairs);
        ASSERT_NEAR(got.metallic, truths[t].metallic, 0.006);
        ASSERT_NEAR(got.roughness, truths[t].roughness, 0.003);
        for (int c = 0; c < 3; c++)
            ASSERT_NEAR(got.base[c], truths[t].base[c], 0.01);
        ASSERT_LT(got.rel_rms, 0.01);
    }
    {
        brdf b;
        cosf_ctx x = {NULL, &b};
        gltf_pbr got;
        glint_err e;
        ASSERT_OK(brdf_parse("phong:kd=0.3,ks=0.6,e=8", &b, &e));
        ASSERT_OK(gltf_fit(rad, &x, NULL, &got, &e));
        printf("  a Phong lobe: relative RMS %.4f (what the glTF model cannot hold)\n",
               got.rel_rms);
        ASSERT_LT(0.01, got.rel_rms);
        ASSERT_LT(got.anisotropy, 1e-9); /* isotropic: the same when the pairs turn */
    }
}

/* An anisotropic material is measured as one (the glTF model is isotropic):
 * Ward's lobe 0.1 along the tangent and 0.4 along the bitangent changes by
 * far more than GLTF_ANISO_NOTE when the pairs turn about the normal; the
 * same lobe at 0.2 both ways does not change at all. */
TEST(anisotropy_is_measured)
{
    static const char *const specs[2] = {"ward:kd=0.2,ks=0.5,rough=0.1,rough_y=0.4",
                                         "ward:kd=0.2,ks=0.5,rough=0.2,rough_y=0.2"};
    double got_a[2];
    for (int t = 0; t < 2; t++) {
        brdf b;
        cosf_ctx x = {NULL, &b};
        gltf_pbr got;
        glint_err e;
        ASSERT_OK(brdf_parse(specs[t], &b, &e));
        ASSERT_OK(gltf_fit(rad, &x, NULL, &got, &e));
        got_a[t] = got.anisotropy;
        printf("  %s: anisotropy %.4f, fit relative RMS %.4f\n", specs[t], got.anisotropy,
               got.rel_rms);
    }
    ASSERT_LT(GLTF_ANISO_NOTE * 5, got_a[0]);
    ASSERT_LT(got_a[1], 1e-9);
}

/* KHR_materials_anisotropy's model: with strength 0 it is the isotropic
 * model with the height-correlated G (the lobe's V); a material it holds
 * is fitted back (rotation, strength, roughness, metallic, base colour)
 * and kept, far closer than the isotropic fit; Ward 0.1 by 0.4 (its grooves
 * across the tangent) comes back turned a quarter and closer too. */
TEST(the_anisotropic_fit)
{
    gltf_aniso truth = {.used = 1, .strength = 0.7, .rotation = 0.5, .base = {0.9, 0.6, 0.3},
                        .metallic = 1.0, .roughness = 0.3};
    gltf_aniso iso = truth;
    gltf_pbr p = {.base = {0.9, 0.6, 0.3}, .metallic = 1.0, .roughness = 0.3}, got;
    double n[3] = {0, 0, 1}, wi[3] = {0.3, 0.2, 0.933}, wo[3] = {-0.5, 0.1, 0.86}, f[3], g[3];
    glint_err e;
    double l = sqrt(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2]);
    for (int k = 0; k < 3; k++)
        wi[k] /= l;
    l = sqrt(wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]);
    for (int k = 0; k < 3; k++)
        wo[k] /= l;
    iso.strength = 0.0;
    gltf_aniso_brdf(&iso, n, wi, wo, f);
    p.khr.ior_used = 1, p.khr.ior = 1.5; /* the layered form */
    gltf_khr_brdf_smith(&p, GLTF_SMITH_CORRELATED, n, wi, wo, g);
    for (int c = 0; c < 3; c++)
        ASSERT_NEAR(f[c], g[c], 1e-12 * (1.0 + fabs(g[c])));
    ASSERT_OK(gltf_fit(rad_aniso, &truth, NULL, &got, &e));
    ASSERT_OK(gltf_fit_aniso(rad_aniso, &truth, NULL, &got, &e));
    printf("  truth strength 0.7 rotation 0.5 roughness 0.3: isotropic fit %.4f; anisotropic "
           "%.4f (strength %.3f, rotation %.3f, roughness %.3f, metallic %.2f)\n",
           got.rel_rms, got.aniso.rel_rms, got.aniso.strength, got.aniso.rotation,
           got.aniso.roughness, got.aniso.metallic);
    ASSERT(got.aniso.used);
    ASSERT_LT(got.aniso.rel_rms, 0.01);
    ASSERT_LT(got.aniso.rel_rms * 10.0, got.rel_rms);
    ASSERT_NEAR(got.aniso.strength, 0.7, 0.03);
    ASSERT_NEAR(got.aniso.rotation, 0.5, 0.03);
    ASSERT_NEAR(got.aniso.roughness, 0.3, 0.02);
    for (int c = 0; c < 3; c++)
        ASSERT_NEAR(got.aniso.base[c], truth.base[c], 0.02);
    {
        brdf b;
        cosf_ctx x = {NULL, &b};
        ASSERT_OK(brdf_parse("ward:kd=0.2,ks=0.5,rough=0.1,rough_y=0.4", &b, &e));
        ASSERT_OK(gltf_fit(rad, &x, NULL, &got, &e));
        ASSERT_OK(gltf_fit_aniso(rad, &x, NULL, &got, &e));
        printf("  Ward 0.1 by 0.4: isotropic fit %.4f; anisotropic %.4f (strength %.3f, "
               "rotation %.3f)\n", got.rel_rms, got.aniso.rel_rms, got.aniso.strength,
               got.aniso.rotation);
        ASSERT(got.aniso.used);
        ASSERT_LT(got.aniso.rel_rms, 0.8 * got.rel_rms);
        ASSERT_NEAR(got.aniso.rotation, M_PI / 2, 0.15); /* rougher along b */
    }
}

TEST(a_fitted_material_at_its_painted_samples)
{
    unsigned char all[SCENE_MAX_VIEWS];
    fit_params fp;
    material m;
    samples s;
    gltf_pbr got;
    glint_err e;
    char hash[33];
    ASSERT_OK(sv_setup(SIZE, &SC, &G, &C, &SE));
    fit_params_default(&fp);
    fp.res = 64;
    ASSERT_OK(sv_fit(&method_hf3, &fp, "ct:kd=0.5/0.3/0.2,f0=0.04,rough=0.25", &SC, G, C, SE, &m));
    memset(all, 1, sizeof all);
    scene_hash(&SC, hash);
    ASSERT_OK(samples_build(G, SC.views, SC.nviews, all, hash, &s, &e));
    ASSERT_OK(gltf_fit_material(&m, &s, &got, &e));
    printf("  hf3 of ct kd 0.5/0.3/0.2, f0 0.04, alpha 0.25: base %.4f/%.4f/%.4f, metallic "
           "%.4f, roughness %.4f (truth 0.5), relative RMS %.4f over %d samples\n",
           got.base[0], got.base[1], got.base[2], got.metallic, got.roughness, got.rel_rms,
           got.pairs);
    ASSERT_NEAR(got.roughness, 0.5, 0.05);
    ASSERT_LT(got.metallic, 0.15);
    ASSERT_NEAR(got.base[0], 0.5, 0.05);
    ASSERT_NEAR(got.base[2], 0.2, 0.03);
    ASSERT_LT(got.rel_rms, 0.05);
    samples_free(&s);
    material_free(&m);
}

static uint32_t u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

TEST(the_glb_file_holds_the_mesh_and_the_material)
{
    gltf_pbr p = {.base = {0.5, 0.25, 0.125}, .metallic = 0.25, .roughness = 0.75, .rel_rms = 0.01,
                  .pairs = 10};
    void *glb;
    size_t len;
    glint_err e;
    const unsigned char *b;
    uint32_t jl, bl;
    json_t *doc, *acc, *mat;
    ASSERT_OK(sv_setup(SIZE, &SC, &G, &C, &SE));
    ASSERT_OK(gltf_write_glb(&SC.mesh, &p, NULL, "test", "{\"k\": 1}", &glb, &len, &e));
    b = glb;
    ASSERT_EQ(u32(b), 0x46546C67u);
    ASSERT_EQ(u32(b + 4), 2);
    ASSERT_EQ(u32(b + 8), len);
    jl = u32(b + 12);
    ASSERT_EQ(u32(b + 16), 0x4E4F534Au);
    ASSERT_EQ(jl % 4, 0);
    bl = u32(b + 20 + jl);
    ASSERT_EQ(u32(b + 24 + jl), 0x004E4942u);
    ASSERT_EQ(20 + jl + 8 + bl, len);
    doc = json_loadb((const char *)b + 20, jl, 0, NULL);
    ASSERT(doc != NULL);
    acc = json_object_get(doc, "accessors");
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(acc, 0), "count")), SC.mesh.nverts);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(acc, 3), "count")),
              3 * SC.mesh.ntris);
    ASSERT(json_integer_value(json_object_get(json_array_get(json_object_get(doc, "buffers"), 0),
                                              "byteLength")) <= (json_int_t)bl);
    mat = json_object_get(json_array_get(json_object_get(doc, "materials"), 0),
                          "pbrMetallicRoughness");
    ASSERT_NEAR(json_real_value(json_object_get(mat, "roughnessFactor")), 0.75, 1e-9);
    ASSERT_NEAR(json_real_value(json_array_get(json_object_get(mat, "baseColorFactor"), 1)), 0.25,
                1e-9);
    {
        float first[3];
        memcpy(first, b + 28 + jl, sizeof first); /* POSITION's first vertex */
        ASSERT(first[0] == SC.mesh.pos[0] && first[1] == SC.mesh.pos[1] &&
               first[2] == SC.mesh.pos[2]);
    }
    json_decref(doc);
    free(glb);
    ASSERT_EQ(gltf_write_glb(&SC.mesh, &p, NULL, "x", "{not json", &glb, &len, &e), GLINT_EINVAL);
}

/* ---- the glTF side, read back from the file and shaded by the specification --------- */

typedef struct glb_doc {
    json_t *doc;
    const unsigned char *bin;
    size_t bin_len;
} glb_doc;

/* the JSON and BIN chunks of a .glb (0, or -1 when it is not one) */
static int glb_open(const void *glb, size_t len, glb_doc *out)
{
    const unsigned char *b = glb;
    uint32_t jl, bl;
    memset(out, 0, sizeof *out);
    if (len < 28 || u32(b) != 0x46546C67u || u32(b + 8) != len || u32(b + 16) != 0x4E4F534Au)
        return -1;
    jl = u32(b + 12);
    if ((size_t)jl + 28 > len || u32(b + 24 + jl) != 0x004E4942u)
        return -1;
    bl = u32(b + 20 + jl);
    if ((size_t)jl + 28 + bl > len || !(out->doc = json_loadb((const char *)b + 20, jl, 0, NULL)))
        return -1;
    out->bin = b + 28 + jl;
    out->bin_len = bl;
    return 0;
}

static json_t *jpath(const json_t *o, const char *key, int index)
{
    json_t *v = json_object_get(o, key);
    return index >= 0 ? json_array_get(v, (size_t)index) : v;
}

static int jint(const json_t *o, const char *key)
{
    json_t *v = json_object_get(o, key);
    return json_is_integer(v) ? (int)json_integer_value(v) : -1;
}

/* the bytes of buffer view k (NULL when out of the BIN chunk) */
static const unsigned char *glb_view(const glb_doc *d, int k, size_t *len)
{
    json_t *bv = jpath(d->doc, "bufferViews", k);
    json_int_t off = json_integer_value(json_object_get(bv, "byteOffset"));
    json_int_t n = json_integer_value(json_object_get(bv, "byteLength"));
    if (!bv || off < 0 || n < 1 || (size_t)(off + n) > d->bin_len)
        return NULL;
    *len = (size_t)n;
    return d->bin + off;
}

/* accessor k's data, checked to hold count x comps values of `ctype` */
static const unsigned char *glb_accessor(const glb_doc *d, int k, int ctype, int comps,
                                         size_t *count)
{
    json_t *a = jpath(d->doc, "accessors", k);
    const char *type = json_string_value(json_object_get(a, "type"));
    int want = !type ? 0 : !strcmp(type, "SCALAR") ? 1 : !strcmp(type, "VEC2") ? 2
                                                        : !strcmp(type, "VEC3") ? 3 : 0;
    size_t len;
    const unsigned char *p = glb_view(d, jint(a, "bufferView"), &len);
    *count = (size_t)json_integer_value(json_object_get(a, "count"));
    if (!p || jint(a, "componentType") != ctype || want != comps || *count * 4 * comps > len)
        return NULL;
    return p;
}

/* the .glb's own mesh: POSITION, NORMAL, TEXCOORD_0 (glTF's texture
 * coordinates, kept as they are: a G-buffer of it holds them) and indices */
static int glb_mesh(const glb_doc *d, mesh *out)
{
    json_t *prim = jpath(jpath(d->doc, "meshes", 0), "primitives", 0);
    json_t *at = json_object_get(prim, "attributes");
    size_t nv, nn, nu, ni;
    const unsigned char *pos = glb_accessor(d, jint(at, "POSITION"), 5126, 3, &nv);
    const unsigned char *nrm = glb_accessor(d, jint(at, "NORMAL"), 5126, 3, &nn);
    const unsigned char *uv = glb_accessor(d, jint(at, "TEXCOORD_0"), 5126, 2, &nu);
    const unsigned char *idx = glb_accessor(d, jint(prim, "indices"), 5125, 1, &ni);
    memset(out, 0, sizeof *out);
    if (!pos || !nrm || !uv || !idx || nn != nv || nu != nv || ni % 3)
        return -1;
    out->nverts = (int)nv;
    out->ntris = (int)(ni / 3);
    out->pos = malloc(12 * nv);
    out->nrm = malloc(12 * nv);
    out->uv = malloc(8 * nv);
    out->tri = malloc(4 * ni);
    if (!out->pos || !out->nrm || !out->uv || !out->tri)
        return -1;
    memcpy(out->pos, pos, 12 * nv);
    memcpy(out->nrm, nrm, 12 * nv);
    memcpy(out->uv, uv, 8 * nv);
    memcpy(out->tri, idx, 4 * ni);
    return 0;
}

/* the image of a textureInfo ({"index": k}), decoded from its PNG */
static int glb_texture(const glb_doc *d, const json_t *info, img *out)
{
    json_t *tex = jpath(d->doc, "textures", jint(info, "index"));
    json_t *im = jpath(d->doc, "images", jint(tex, "source"));
    size_t len;
    const unsigned char *png = glb_view(d, jint(im, "bufferView"), &len);
    glint_err e;
    memset(out, 0, sizeof *out);
    if (!png || strcmp(json_string_value(json_object_get(im, "mimeType")), "image/png") != 0 ||
        memcmp(png, "\x89PNG\r\n\x1a\n", 8) != 0)
        return -1;
    return img_read_mem(png, len, out, &e) || img_to_rgb(out, &e) ? -1 : 0;
}

/* sRGB's decoding (IEC 61966-2-1), what a viewer applies to baseColorTexture */
static double srgb_decode(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

/* a texture at glTF texture coordinates (s, t), bilinear between texel
 * centres, clamped at the edges (the file's sampler) */
static void tex_sample(const img *im, double s, double t, double out[3])
{
    double x = s * im->width - 0.5, y = t * im->height - 0.5, fx, fy;
    int x0, y0, x1, y1;
    x = x < 0.0 ? 0.0 : x > im->width - 1 ? im->width - 1 : x;
    y = y < 0.0 ? 0.0 : y > im->height - 1 ? im->height - 1 : y;
    x0 = (int)x, y0 = (int)y;
    x1 = x0 + 1 < im->width ? x0 + 1 : x0, y1 = y0 + 1 < im->height ? y0 + 1 : y0;
    fx = x - x0, fy = y - y0;
    for (int c = 0; c < 3; c++) {
        const float *p = im->px;
        int w = im->width;
        out[c] = (1 - fy) * ((1 - fx) * p[3 * (y0 * w + x0) + c] + fx * p[3 * (y0 * w + x1) + c]) +
                 fy * ((1 - fx) * p[3 * (y1 * w + x0) + c] + fx * p[3 * (y1 * w + x1) + c]);
    }
}

/* The glTF 2.0 specification's BRDF, Appendix B, as its implementation
 * section writes it: the GGX distribution, the height-uncorrelated Smith
 * visibility in its V form V = G / (4 |N.L| |N.V|), Schlick's Fresnel with
 * f0 = mix(0.04, baseColor, metallic), c_diff = mix(baseColor, 0,
 * metallic), f = (1 - F) c_diff / pi + F D V; alpha is given. */
static void spec_brdf(const double base[3], double metallic, double alpha, const double n[3],
                      const double l[3], const double v[3], double f[3])
{
    double h[3], hl, nl, nv, nh, vh, a2 = alpha * alpha, dd, D, V;
    for (int e = 0; e < 3; e++)
        h[e] = l[e] + v[e];
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    nl = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
    nv = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
    nh = (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl;
    vh = fabs(v[0] * h[0] + v[1] * h[1] + v[2] * h[2]) / hl;
    dd = nh * nh * (a2 - 1.0) + 1.0;
    D = nh > 0.0 ? a2 / (M_PI * dd * dd) : 0.0;
    V = 1.0 / ((nl + sqrt(a2 + (1.0 - a2) * nl * nl)) * (nv + sqrt(a2 + (1.0 - a2) * nv * nv)));
    for (int c = 0; c < 3; c++) {
        double f0 = 0.04 * (1.0 - metallic) + base[c] * metallic;
        double F = f0 + (1.0 - f0) * pow(1.0 - vh, 5.0);
        f[c] = (1.0 - F) * base[c] * (1.0 - metallic) / M_PI + F * D * V;
    }
}

/* the .glb's material: factors and, when it has them, textures */
typedef struct gltf_side {
    double base[4], metallic, roughness;
    img bc, mr;
} gltf_side;

static int side_read(const glb_doc *d, gltf_side *g)
{
    json_t *pbr = json_object_get(jpath(d->doc, "materials", 0), "pbrMetallicRoughness");
    json_t *bcf = json_object_get(pbr, "baseColorFactor"), *x;
    memset(g, 0, sizeof *g);
    if (!pbr)
        return -1;
    g->base[0] = g->base[1] = g->base[2] = g->base[3] = 1.0; /* the specification's defaults */
    g->metallic = g->roughness = 1.0;
    for (int c = 0; c < 4 && bcf; c++)
        g->base[c] = json_number_value(json_array_get(bcf, (size_t)c));
    if ((x = json_object_get(pbr, "metallicFactor")))
        g->metallic = json_number_value(x);
    if ((x = json_object_get(pbr, "roughnessFactor")))
        g->roughness = json_number_value(x);
    if ((x = json_object_get(pbr, "baseColorTexture")) && glb_texture(d, x, &g->bc))
        return -1;
    if ((x = json_object_get(pbr, "metallicRoughnessTexture")) && glb_texture(d, x, &g->mr))
        return -1;
    return 0;
}

static void side_free(gltf_side *g)
{
    img_free(&g->bc);
    img_free(&g->mr);
}

/* Render view v of the .glb's mesh with its material, alpha = roughness^expo:
 * radiance I f cos on lit and seen pixels, 0 elsewhere (OUT: *out, RGB).
 * flip 1 or 2 reads the textures at 1 - s or 1 - t (what a texture
 * written upside down or mirrored would show); 0 as the file says. */
static int side_render(const gltf_side *g, const mesh *gm, const scene_view *v, int w, int h,
                       int expo, int flip, img *out)
{
    gbuf gb;
    glint_err e;
    if (raster_view(gm, v, w, h, &gb, &e) || img_alloc(out, w, h, 3, &e))
        return -1;
    for (size_t p = 0; p < (size_t)w * h; p++) {
        double n[3], wi[3], wo[3], base[3], m = g->metallic, r = g->roughness, f[3], t[3], ci, co;
        double st[2];
        if (!gb.mask[p])
            continue;
        for (int e2 = 0; e2 < 3; e2++)
            n[e2] = gb.nrm[3 * p + e2], wi[e2] = gb.wi[3 * p + e2], wo[e2] = gb.wo[3 * p + e2];
        ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
        co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
        if (!(ci > 0.0 && co > 0.0))
            continue;
        st[0] = flip == 1 ? 1.0 - gb.uv[2 * p] : gb.uv[2 * p];
        st[1] = flip == 2 ? 1.0 - gb.uv[2 * p + 1] : gb.uv[2 * p + 1];
        for (int c = 0; c < 3; c++)
            base[c] = g->base[c];
        if (g->bc.px) {
            tex_sample(&g->bc, st[0], st[1], t);
            for (int c = 0; c < 3; c++)
                base[c] *= srgb_decode(t[c]);
        }
        if (g->mr.px) { /* G roughness, B metallic, linear */
            tex_sample(&g->mr, st[0], st[1], t);
            r *= t[1];
            m *= t[2];
        }
        spec_brdf(base, m, expo == 2 ? r * r : r, n, wi, wo, f);
        for (int c = 0; c < 3; c++)
            out->px[3 * p + c] = (float)(M_PI * v->light_intensity * f[c] * ci); /* scene.h */
    }
    gbuf_free(&gb);
    return 0;
}

/* The truth (sv_paint's spec) painted in view v at 96 x 96 (OUT: *out). */
static int paint_truth(const char *spec, const scene_view *v, img *out)
{
    scene one = SC;
    gbuf g;
    glint_err e;
    int rc;
    memset(out, 0, sizeof *out);
    one.views = (scene_view *)v;
    one.nviews = 1;
    if (raster_view(&SC.mesh, v, 96, 96, &g, &e))
        return -1;
    rc = sv_paint(spec, &one, &g, out, &e);
    gbuf_free(&g);
    return rc ? -1 : 0;
}

/* Export m on the fixture's scene (textures bake_res), read the file back
 * and render it and m in 4 of the views at 96 x 96: the relative RMS
 * difference of the images, sqrt(sum d^2 / sum glint^2), with alpha =
 * roughness^2, with alpha = roughness, and with the textures read mirrored
 * in s and in t (OUT: diff[4], *doc); with
 * `truth` (a spec, or NULL) also the material's and the glTF's (alpha =
 * roughness^2) relative to the truth painted in those views (OUT:
 * vs_truth[2]). */
static int compare(const material *m, int bake_res, const char *truth, double diff[4],
                   double vs_truth[2], json_t **doc)
{
    void *glb;
    size_t len;
    gltf_pbr p;
    glb_doc d;
    gltf_side g;
    mesh gm;
    glint_err e;
    static const int expo[4] = {2, 1, 2, 2}, flip[4] = {0, 0, 1, 2};
    double ss[4] = {0, 0, 0, 0}, ref = 0.0, tt[3] = {0, 0, 0};
    if (gltf_export_scene(m, &SC, NULL, bake_res, &glb, &len, &p, NULL, &e)) {
        fprintf(stderr, "export: %s\n", e.msg);
        return -1;
    }
    if (glb_open(glb, len, &d) || glb_mesh(&d, &gm) || side_read(&d, &g))
        return -1;
    for (int k = 0; k < 4; k++) {
        const scene_view *v = &SC.views[(k * SC.nviews) / 4];
        img a, b[4], tr = {0};
        if (material_render(m, &SC.mesh, v, 96, 96, &a, NULL, &e))
            return -1;
        for (int w = 0; w < 4; w++)
            if (side_render(&g, &gm, v, 96, 96, expo[w], flip[w], &b[w]))
                return -1;
        if (truth && paint_truth(truth, v, &tr))
            return -1;
        for (size_t i = 0; i < (size_t)96 * 96 * 3; i++) {
            ref += (double)a.px[i] * a.px[i];
            for (int w = 0; w < 4; w++)
                ss[w] += ((double)a.px[i] - b[w].px[i]) * ((double)a.px[i] - b[w].px[i]);
            if (truth) {
                tt[0] += ((double)tr.px[i] - a.px[i]) * ((double)tr.px[i] - a.px[i]);
                tt[1] += ((double)tr.px[i] - b[0].px[i]) * ((double)tr.px[i] - b[0].px[i]);
                tt[2] += (double)tr.px[i] * tr.px[i];
            }
        }
        for (int w = 0; w < 4; w++)
            img_free(&b[w]);
        img_free(&a), img_free(&tr);
    }
    for (int w = 0; w < 4; w++)
        diff[w] = sqrt(ss[w] / ref);
    if (truth) {
        vs_truth[0] = sqrt(tt[0] / tt[2]);
        vs_truth[1] = sqrt(tt[1] / tt[2]);
    }
    *doc = d.doc;
    side_free(&g);
    mesh_free(&gm);
    free(glb);
    return 0;
}

TEST(the_roughness_convention_by_rendering_both)
{
    static const char *truths[2] = {"ct:kd=0.5/0.3/0.2,f0=0.04,rough=0.25",
                                    "ct:kd=0,f0=0.9/0.6/0.3,rough=0.09"};
    static const double within[2] = {0.03, 0.1}; /* the hf3 material's own error dominates */
    fit_params fp;
    ASSERT_OK(sv_setup(SIZE, &SC, &G, &C, &SE));
    fit_params_default(&fp);
    fp.res = 64;
    for (int t = 0; t < 2; t++) {
        material m;
        double d[4], right, wrong, vt[2];
        json_t *doc, *mat, *pbr;
        ASSERT_OK(sv_fit(&method_hf3, &fp, truths[t], &SC, G, C, SE, &m));
        ASSERT_OK(compare(&m, GLTF_BAKE_RES_DEFAULT, truths[t], d, vt, &doc));
        right = d[0], wrong = d[1];
        mat = jpath(doc, "materials", 0);
        pbr = json_object_get(mat, "pbrMetallicRoughness");
        printf("  hf3 of %s: glTF roughness %.4f, metallic %.4f, fit relative RMS %.4f; renders "
               "differ by %.4f (alpha = roughness^2), %.4f (alpha = roughness); from the "
               "truth: the material %.4f, the glTF %.4f\n",
               truths[t], json_number_value(json_object_get(pbr, "roughnessFactor")),
               json_number_value(json_object_get(pbr, "metallicFactor")),
               json_number_value(json_object_get(json_object_get(json_object_get(mat, "extras"),
                                                                 "glint"),
                                                 "fit_rel_rms")),
               right, wrong, vt[0], vt[1]);
        ASSERT(!json_object_get(doc, "images")); /* one BRDF everywhere: no textures */
        ASSERT_LT(right, within[t]);
        ASSERT_LT(4.0 * right, wrong);
        json_decref(doc);
        material_free(&m);
    }
}

/* Red plastic with gold stripes across u, and in squares (the squares tell
 * a texture upside down from the right one; stripes across u cannot), both
 * GGX: what per-texel glTF parameters can hold, but at the edges, where the
 * material blends, and where the material of maps is far from its truth
 * (10 to 45% at the painted samples of a stripe's edge). */
#define GLTF_STRIPES                                                                            \
    "stripes:freq=3,duty=0.5|ct:kd=0.6/0.1/0.08,f0=0.04,rough=0.3|"                             \
    "ct:kd=0,f0=0.9/0.7/0.3,rough=0.25"
#define GLTF_SQUARES                                                                            \
    "checker:freq=1,duty=0.5|ct:kd=0.6/0.1/0.08,f0=0.04,rough=0.3|"                             \
    "ct:kd=0,f0=0.9/0.7/0.3,rough=0.25"

TEST(baked_textures_by_rendering_both)
{
    static const char *truths[2] = {GLTF_STRIPES, GLTF_SQUARES};
    static const double within[2] = {0.15, 0.25};
    maps_params mp;
    ASSERT_OK(sv_setup(SIZE, &SC, &G, &C, &SE));
    method_maps.params_default(&mp);
    mp.hf.res = 32;
    mp.map_res = 32;
    for (int k = 0; k < 2; k++) {
        material m;
        double d[4], avg[4], vt[2], avg_vt[2];
        json_t *doc, *pbr, *tex, *glint;
        ASSERT_OK(sv_fit(&method_maps, &mp, truths[k], &SC, G, C, SE, &m));
        ASSERT(material_spatial(&m));
        /* the average alone (textures not asked for) */
        ASSERT_OK(compare(&m, 0, truths[k], avg, avg_vt, &doc));
        ASSERT(!json_object_get(doc, "images"));
        glint = json_object_get(json_object_get(jpath(doc, "materials", 0), "extras"), "glint");
        ASSERT(json_is_string(json_object_get(glint, "textures_not_baked")));
        ASSERT(json_is_true(json_object_get(glint, "spatial_average")));
        json_decref(doc);
        ASSERT_OK(compare(&m, GLTF_BAKE_RES_DEFAULT, truths[k], d, vt, &doc));
        pbr = json_object_get(jpath(doc, "materials", 0), "pbrMetallicRoughness");
        glint = json_object_get(json_object_get(jpath(doc, "materials", 0), "extras"), "glint");
        tex = json_object_get(glint, "textures");
        printf("  maps of %s, %dx%d texels (at most %d pairs each, %d far texels, %.2f s): "
               "texel relative RMS median %.4f, max %.4f; renders differ by %.4f (alpha = "
               "roughness^2), %.4f (alpha = roughness), %.4f and %.4f (textures mirrored in s, "
               "in t); the average alone %.4f; from the truth: the material %.4f, the baked "
               "glTF %.4f, the average alone %.4f\n",
               k ? "gold squares on red plastic" : "gold stripes on red plastic",
               (int)json_integer_value(json_object_get(tex, "res")),
               (int)json_integer_value(json_object_get(tex, "res")),
               (int)json_integer_value(json_object_get(tex, "pairs_per_texel")),
               (int)json_integer_value(json_object_get(tex, "far_texels")),
               json_number_value(json_object_get(tex, "seconds")),
               json_number_value(json_object_get(tex, "texel_rel_rms_median")),
               json_number_value(json_object_get(tex, "texel_rel_rms_max")), d[0], d[1], d[2],
               d[3], avg[0], vt[0], vt[1], avg_vt[1]);
        ASSERT_EQ(json_array_size(json_object_get(doc, "images")), 2);
        ASSERT(json_is_false(json_object_get(glint, "spatial_average")));
        ASSERT_NEAR(json_number_value(json_object_get(pbr, "roughnessFactor")), 1.0, 0.0);
        ASSERT_NEAR(json_number_value(json_object_get(pbr, "metallicFactor")), 1.0, 0.0);
        ASSERT_EQ(jint(json_object_get(pbr, "baseColorTexture"), "texCoord"), 0);
        ASSERT_LT(json_number_value(json_object_get(tex, "texel_rel_rms_median")), 0.15);
        ASSERT_LT(d[0], within[k]);
        ASSERT_LT(d[0], 0.4 * avg[0]); /* the textures hold what the average cannot */
        ASSERT_LT(2.5 * d[0], d[1]);  /* alpha = roughness^2, not roughness */
        ASSERT_LT(2.0 * d[0], d[2]);  /* the texture's columns the right way round */
        if (k == 1)
            ASSERT_LT(2.0 * d[0], d[3]); /* and its rows */
        ASSERT_LT(vt[1], 0.5 * avg_vt[1]);
        json_decref(doc);
        material_free(&m);
    }
}

/* A material that is the same everywhere bakes textures of its average's
 * fit, over the directions painted around each texel and, without the
 * samples, over the hemisphere's pairs (every texel then far). */
TEST(a_uniform_material_bakes_its_average)
{
    fit_params fp;
    material m;
    samples s;
    gltf_pbr avg;
    gltf_bake b;
    glint_err e;
    char hash[33];
    ASSERT_OK(sv_setup(SIZE, &SC, &G, &C, &SE));
    fit_params_default(&fp);
    fp.res = 64;
    ASSERT_OK(sv_fit(&method_hf3, &fp, "ct:kd=0.5/0.3/0.2,f0=0.04,rough=0.25", &SC, G, C, SE, &m));
    scene_hash(&SC, hash);
    ASSERT_OK(samples_build(G, SC.views, SC.nviews, NULL, hash, &s, &e));
    ASSERT_OK(gltf_fit_material(&m, &s, &avg, &e));
    for (int pass = 0; pass < 2; pass++) {
        double worst[3] = {0, 0, 0};
        ASSERT_OK(gltf_bake_material(&m, pass ? NULL : &s, &avg, 6, &b, &e));
        for (int t = 0; t < 36; t++) {
            for (int c = 0; c < 3; c++)
                worst[0] = fmax(worst[0], fabs(b.base[3 * t + c] - avg.base[c]));
            worst[1] = fmax(worst[1], fabs(b.metallic[t] - avg.metallic));
            worst[2] = fmax(worst[2], fabs(b.roughness[t] - avg.roughness));
        }
        printf("  hf3 plastic baked at 6x6 over %s: %d far texels, from the average (base "
               "%.3f/%.3f/%.3f, metallic %.3f, roughness %.3f) at most %.4f (base), %.4f "
               "(metallic), %.4f (roughness); texel relative RMS median %.4f, max %.4f\n",
               pass ? "the hemisphere" : "the painted directions", b.far_texels, avg.base[0],
               avg.base[1], avg.base[2], avg.metallic, avg.roughness, worst[0], worst[1],
               worst[2], b.rel_rms_median, b.rel_rms_max);
        ASSERT_EQ(b.far_texels, pass ? 36 : 0);
        ASSERT_EQ(b.nonfinite, 0);
        if (!pass) { /* the same directions (locally) as the average's fit */
            ASSERT_LT(worst[0], 0.02);
            ASSERT_LT(worst[1], 0.03);
            ASSERT_LT(worst[2], 0.08);
            ASSERT_LT(b.rel_rms_max, 0.05);
        } else { /* the same pairs everywhere: the same texels */
            for (int t = 1; t < 36; t++)
                ASSERT(b.base[3 * t] == b.base[0] && b.base[3 * t + 2] == b.base[2] &&
                       b.metallic[t] == b.metallic[0] && b.roughness[t] == b.roughness[0] &&
                       b.rel_rms[t] == b.rel_rms[0]);
        }
        gltf_bake_free(&b);
    }
    samples_free(&s);
    material_free(&m);
}

TEST(baking_refuses_what_it_cannot_do)
{
    gltf_pbr p = {.base = {0.5, 0.5, 0.5}, .metallic = 0.0, .roughness = 0.5, .spatial = 1};
    gltf_bake b;
    material none = {0};
    mesh bare;
    void *glb = NULL;
    size_t len;
    glint_err e;
    ASSERT_OK(sv_setup(SIZE, &SC, &G, &C, &SE));
    ASSERT_EQ(gltf_bake_material(&none, NULL, &p, 32, &b, &e), GLINT_EINVAL);
    ASSERT_EQ(gltf_export_scene(&none, &SC, NULL, -1, &glb, &len, &p, NULL, &e), GLINT_ERANGE);
    ASSERT_EQ(gltf_export_scene(&none, &SC, NULL, GLTF_BAKE_RES_MAX + 1, &glb, &len, &p, NULL,
                                &e),
              GLINT_ERANGE);
    printf("  %s\n", e.msg);
    memset(&b, 0, sizeof b);
    b.res = 2;
    ASSERT_EQ(gltf_bake_png(&b, &glb, &len, &glb, &len, &e), GLINT_EINVAL);
    bare = SC.mesh;
    bare.uv = NULL;
    {
        float base[12] = {0}, m[4] = {0}, r[4] = {0.5f, 0.5f, 0.5f, 0.5f}, rel[4] = {0};
        b.base = base, b.metallic = m, b.roughness = r, b.rel_rms = rel;
        ASSERT_EQ(gltf_write_glb(&bare, &p, &b, "x", NULL, &glb, &len, &e), GLINT_EINVAL);
        printf("  %s\n", e.msg);
        ASSERT_OK(gltf_write_glb(&SC.mesh, &p, &b, "x", NULL, &glb, &len, &e));
        free(glb);
    }
}

TEST_LIST{
    TEST_ENTRY(a_metal_is_glints_cook_torrance_with_alpha_roughness_squared),
    TEST_ENTRY(the_fit_recovers_what_the_model_can_represent),
    TEST_ENTRY(anisotropy_is_measured),
    TEST_ENTRY(the_anisotropic_fit),
    TEST_ENTRY(a_fitted_material_at_its_painted_samples),
    TEST_ENTRY(the_glb_file_holds_the_mesh_and_the_material),
    TEST_ENTRY(the_roughness_convention_by_rendering_both),
    TEST_ENTRY(baked_textures_by_rendering_both),
    TEST_ENTRY(a_uniform_material_bakes_its_average),
    TEST_ENTRY(baking_refuses_what_it_cannot_do),
};

TEST_MAIN()
