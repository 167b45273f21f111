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
 *   chunk agree with the mesh. */
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
#include "sv_fixture.h"

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

TEST(a_metal_is_glints_cook_torrance_with_alpha_roughness_squared)
{
    gltf_pbr p = {{0.9, 0.6, 0.3}, 1.0, 0.4, 0, 0, 0};
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
    static const gltf_pbr truths[2] = {{{0.9, 0.6, 0.3}, 1.0, 0.3, 0, 0, 0},
                                       {{0.5, 0.3, 0.2}, 0.0, 0.5, 0, 0, 0}};
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
    ASSERT_OK(sv_setup(48, &SC, &G, &C, &SE));
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
    gltf_pbr p = {{0.5, 0.25, 0.125}, 0.25, 0.75, 0.01, 10, 0};
    void *glb;
    size_t len;
    glint_err e;
    const unsigned char *b;
    uint32_t jl, bl;
    json_t *doc, *acc, *mat;
    ASSERT_OK(sv_setup(48, &SC, &G, &C, &SE));
    ASSERT_OK(gltf_write_glb(&SC.mesh, &p, "test", "{\"k\": 1}", &glb, &len, &e));
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
    ASSERT_EQ(gltf_write_glb(&SC.mesh, &p, "x", "{not json", &glb, &len, &e), GLINT_EINVAL);
}

TEST_LIST{
    TEST_ENTRY(a_metal_is_glints_cook_torrance_with_alpha_roughness_squared),
    TEST_ENTRY(the_fit_recovers_what_the_model_can_represent),
    TEST_ENTRY(a_fitted_material_at_its_painted_samples),
    TEST_ENTRY(the_glb_file_holds_the_mesh_and_the_material),
};

TEST_MAIN()
