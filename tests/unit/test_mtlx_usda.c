/* test_mtlx_usda.c: the MaterialX and USD writers and their packages
 * (mtlx.h, usda.h, usdz.h, zip.h).
 * - The numbers written are the fit's, in the inputs the specifications
 *   name, at the extremes of their range (0 and 1) too.
 * - What is not a material (a value outside [0, 1], NaN, a negative
 *   error) and what is not a mesh (no normals, no triangle) are refused
 *   with GLINT_EINVAL, nothing written.
 * - Names and notes cannot break the documents: node names cut to
 *   identifiers, "--" kept out of an XML comment, quotes out of a USD doc.
 * - A pbr material's mapping: KHR ior, specular and clearcoat as
 *   specular_IOR, specular, specular_color, coat, coat_roughness
 *   (MaterialX) and the specular workflow's specularColor, ior,
 *   clearcoat, clearcoatRoughness (USD); refused outside their ranges.
 * - A mesh: one triangle with its points, normals, st and indices; without
 *   uv, no st.
 * - Textures: the readers (primvars:st, two UsdUVTexture) connected to
 *   diffuseColor, metallic and roughness in the metallic workflow; refused
 *   without texture coordinates or with an asset path USD cannot read.
 * - MaterialX textures: a nodegraph whose image nodes read the two
 *   files (the base colour as srgb_texture, the other raw) and whose
 *   extract nodes take roughness (G) and metalness (B), its outputs
 *   connected to base_color, specular_roughness and metalness; specular_IOR
 *   1.5 (glTF's core model); refused for a path the document cannot name.
 * - A USDZ package: stored files whose data start at multiples of 64
 *   bytes, in order, the central directory after them; refused when the
 *   first file is no USD layer, for a path outside the package, and for
 *   0 or too many files.  The plain zip (zip.h) takes any first file.  The spec checks of whole files are tests/integration/
 *   export_specs.py's (run by the CLI and integration tests). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "mtlx.h"
#include "usda.h"
#include "usdz.h"

static gltf_pbr pbr(double r, double g, double b, double m, double rough)
{
    gltf_pbr p;
    memset(&p, 0, sizeof p);
    p.base[0] = r, p.base[1] = g, p.base[2] = b;
    p.metallic = m;
    p.roughness = rough;
    p.rel_rms = 0.0123;
    p.pairs = 77;
    return p;
}

TEST(mtlx_carries_the_fit)
{
    gltf_pbr p = pbr(0.25, 0.5, 0.75, 0.125, 0.5);
    char *t = NULL;
    glint_err e;
    ASSERT_OK(mtlx_write(&p, "glint_ab", NULL, &t, &e));
    ASSERT(strstr(t, "<standard_surface name=\"SR_glint_ab\" type=\"surfaceshader\">"));
    ASSERT(strstr(t, "name=\"base_color\" type=\"color3\" value=\"0.25, 0.5, 0.75\""));
    ASSERT(strstr(t, "name=\"metalness\" type=\"float\" value=\"0.125\""));
    ASSERT(strstr(t, "name=\"specular_roughness\" type=\"float\" value=\"0.5\""));
    ASSERT(strstr(t, "name=\"specular_IOR\" type=\"float\" value=\"1.5\""));
    ASSERT(strstr(t, "nodename=\"SR_glint_ab\""));
    ASSERT(strstr(t, "fit_rel_rms 0.0123") && strstr(t, "(77 pairs)"));
    ASSERT(!strstr(t, "average")); /* not spatial: no word of an average */
    free(t);
    p.spatial = 1;
    ASSERT_OK(mtlx_write(&p, NULL, NULL, &t, &e));
    ASSERT(strstr(t, "this is its average") && strstr(t, "SR_glint\""));
    free(t);
}

TEST(mtlx_extremes_and_refusals)
{
    gltf_pbr lo = pbr(0, 0, 0, 0, 0), hi = pbr(1, 1, 1, 1, 1), bad;
    char *t = NULL;
    glint_err e;
    ASSERT_OK(mtlx_write(&lo, "x", NULL, &t, &e));
    ASSERT(strstr(t, "value=\"0, 0, 0\"") && strstr(t, "name=\"metalness\" type=\"float\" value=\"0\""));
    free(t);
    ASSERT_OK(mtlx_write(&hi, "x", NULL, &t, &e));
    ASSERT(strstr(t, "value=\"1, 1, 1\"") && strstr(t, "name=\"specular_roughness\" type=\"float\" value=\"1\""));
    free(t);
    double *field[] = {&bad.base[1], &bad.metallic, &bad.roughness, &bad.rel_rms};
    double vals[] = {NAN, 1.0000001, -1e-9, INFINITY};
    for (int f = 0; f < 4; f++)
        for (int v = 0; v < 4; v++) {
            bad = pbr(0.5, 0.5, 0.5, 0.5, 0.5);
            *field[f] = vals[v];
            if (f == 3 && v == 1)
                continue; /* an error above 1 is an error, not a bad material */
            t = (char *)1;
            ASSERT_EQ(mtlx_write(&bad, "x", NULL, &t, &e), GLINT_EINVAL);
            ASSERT(t == NULL);
            ASSERT_EQ(usda_write(&bad, NULL, NULL, &t, &(size_t){0}, &e), GLINT_EINVAL);
            ASSERT(t == NULL);
        }
}

TEST(names_and_notes_cannot_break_the_documents)
{
    gltf_pbr p = pbr(0.5, 0.5, 0.5, 0, 0.5);
    char *t = NULL;
    size_t n;
    glint_err e;
    ASSERT_OK(mtlx_write(&p, "9 bad\"<name>", "a -- note --> with an end", &t, &e));
    ASSERT(strstr(t, "name=\"SR_m9_bad__name_\""));
    ASSERT(!strstr(t, "note --")); /* the comment holds no "--" of the note */
    ASSERT(strstr(t, "a -  note - > with an end")); /* each "--" cut to "- " */
    {
        const char *c0 = strstr(t, "<!--"), *c1 = strstr(c0 + 4, "-->");
        ASSERT(c0 && c1);
        for (const char *q = c0 + 4; q < c1; q++)
            ASSERT(!(q[0] == '-' && q[1] == '-'));
        ASSERT(strstr(c1, "<standard_surface")); /* the comment ends before the nodes */
    }
    free(t);
    ASSERT_OK(usda_write(&p, NULL, "a \"\"\" quote \\ and\nline", &t, &n, &e));
    ASSERT_EQ(n, strlen(t));
    {
        const char *d0 = strstr(t, "doc = \"\"\""), *d1 = strstr(d0 + 9, "\"\"\"");
        ASSERT(d0 && d1 && strstr(d1, "metersPerUnit")); /* the doc ends where it should */
    }
    free(t);
}

TEST(usda_material_and_mesh)
{
    gltf_pbr p = pbr(0.2, 0.4, 0.6, 1, 0.3);
    float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, nrm[] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    float uv[] = {0, 0, 1, 0, 0, 1};
    uint32_t tri[] = {0, 1, 2};
    mesh m = {3, 1, pos, nrm, uv, tri};
    char *t = NULL;
    size_t n;
    glint_err e;
    ASSERT_OK(usda_write(&p, NULL, NULL, &t, &n, &e));
    ASSERT(strstr(t, "#usda 1.0") == t && !strstr(t, "def Mesh"));
    ASSERT(strstr(t, "uniform token info:id = \"UsdPreviewSurface\""));
    ASSERT(strstr(t, "color3f inputs:diffuseColor = (0.2, 0.4, 0.6)"));
    ASSERT(strstr(t, "float inputs:metallic = 1\n") && strstr(t, "float inputs:roughness = 0.3\n"));
    ASSERT(strstr(t, "int inputs:useSpecularWorkflow = 0") && strstr(t, "float inputs:ior = 1.5"));
    ASSERT(strstr(t, "outputs:surface.connect = </glint/material/surface.outputs:surface>"));
    free(t);
    ASSERT_OK(usda_write(&p, &m, NULL, &t, &n, &e));
    ASSERT(strstr(t, "int[] faceVertexCounts = [3]\n"));
    ASSERT(strstr(t, "int[] faceVertexIndices = [0, 1, 2]\n"));
    ASSERT(strstr(t, "point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n"));
    ASSERT(strstr(t, "normal3f[] normals = [(0, 0, 1), (0, 0, 1), (0, 0, 1)] ("));
    ASSERT(strstr(t, "texCoord2f[] primvars:st = [(0, 0), (1, 0), (0, 1)] ("));
    ASSERT(strstr(t, "rel material:binding = </glint/material>"));
    free(t);
    m.uv = NULL;
    ASSERT_OK(usda_write(&p, &m, NULL, &t, &n, &e));
    ASSERT(!strstr(t, "primvars:st") && strstr(t, "def Mesh"));
    free(t);
    m.nrm = NULL;
    ASSERT_EQ(usda_write(&p, &m, NULL, &t, &n, &e), GLINT_EINVAL);
    m.nrm = nrm;
    m.ntris = 0;
    ASSERT_EQ(usda_write(&p, &m, NULL, &t, &n, &e), GLINT_EINVAL);
    ASSERT(t == NULL);
}

TEST(usda_textures_connected)
{
    static const usda_textures tex = {"textures/base_color.png", "textures/metallic_roughness.png"};
    usda_textures bad = {"a@b.png", "mr.png"};
    gltf_pbr p = pbr(0.2, 0.4, 0.6, 1, 0.3);
    float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, nrm[] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    float uv[] = {0, 0, 1, 0, 0, 1};
    uint32_t tri[] = {0, 1, 2};
    mesh m = {3, 1, pos, nrm, uv, tri};
    char *t = NULL;
    size_t n;
    glint_err e;
    p.spatial = 1;
    p.khr.specular_used = 1; /* the bake is glTF's core model: the metallic workflow */
    p.khr.specular = 1.0;
    p.khr.specular_color[0] = p.khr.specular_color[1] = p.khr.specular_color[2] = 1.0;
    ASSERT_OK(usda_write_textured(&p, &m, &tex, NULL, &t, &n, &e));
    ASSERT(strstr(t, "uniform token info:id = \"UsdPrimvarReader_float2\""));
    ASSERT(strstr(t, "asset inputs:file = @textures/base_color.png@"));
    ASSERT(strstr(t, "asset inputs:file = @textures/metallic_roughness.png@"));
    ASSERT(strstr(t, "token inputs:sourceColorSpace = \"sRGB\""));
    ASSERT(strstr(t, "token inputs:sourceColorSpace = \"raw\""));
    ASSERT(strstr(t, "color3f inputs:diffuseColor.connect = </glint/material/base_color.outputs:rgb>"));
    ASSERT(strstr(t, "float inputs:metallic.connect = </glint/material/metallic_roughness.outputs:b>"));
    ASSERT(strstr(t, "float inputs:roughness.connect = </glint/material/metallic_roughness.outputs:g>"));
    ASSERT(strstr(t, "int inputs:useSpecularWorkflow = 0") && !strstr(t, "specularColor"));
    ASSERT(strstr(t, "baked textures") && strstr(t, "metallic workflow"));
    free(t);
    /* textures need texture coordinates, and asset paths USD can read */
    ASSERT_EQ(usda_write_textured(&p, NULL, &tex, NULL, &t, &n, &e), GLINT_EINVAL);
    m.uv = NULL;
    ASSERT_EQ(usda_write_textured(&p, &m, &tex, NULL, &t, &n, &e), GLINT_EINVAL);
    m.uv = uv;
    ASSERT_EQ(usda_write_textured(&p, &m, &bad, NULL, &t, &n, &e), GLINT_EINVAL);
    ASSERT(t == NULL);
}

TEST(mtlx_textures_connected)
{
    static const mtlx_textures tex = {"textures/base_color.png", "textures/metallic_roughness.png"};
    static const char *const bad_paths[] = {"a<b.png", "../x.png", "/abs.png", "q\"x.png", ""};
    gltf_pbr p = pbr(0.2, 0.4, 0.6, 1, 0.3);
    char *t = NULL;
    glint_err e;
    p.spatial = 1;
    ASSERT_OK(mtlx_write_textured(&p, "glint_ab", NULL, &tex, &t, &e));
    ASSERT(strstr(t, "<nodegraph name=\"NG_glint_ab\">"));
    ASSERT(strstr(t, "<image name=\"base_color_image\" type=\"color3\">"));
    ASSERT(strstr(t, "value=\"textures/base_color.png\" colorspace=\"srgb_texture\""));
    ASSERT(strstr(t, "<image name=\"metallic_roughness_image\" type=\"vector3\">"));
    ASSERT(strstr(t, "value=\"textures/metallic_roughness.png\" />"));
    ASSERT(strstr(t, "<extract name=\"roughness\" type=\"float\">\n"
                     "      <input name=\"in\" type=\"vector3\" nodename=\"metallic_roughness_image\" />\n"
                     "      <input name=\"index\" type=\"integer\" value=\"1\" />"));
    ASSERT(strstr(t, "<extract name=\"metalness\" type=\"float\">\n"
                     "      <input name=\"in\" type=\"vector3\" nodename=\"metallic_roughness_image\" />\n"
                     "      <input name=\"index\" type=\"integer\" value=\"2\" />"));
    ASSERT(strstr(t, "<input name=\"base_color\" type=\"color3\" nodegraph=\"NG_glint_ab\" "
                     "output=\"base_color_out\" />"));
    ASSERT(strstr(t, "<input name=\"metalness\" type=\"float\" nodegraph=\"NG_glint_ab\" "
                     "output=\"metalness_out\" />"));
    ASSERT(strstr(t, "<input name=\"specular_roughness\" type=\"float\" nodegraph=\"NG_glint_ab\" "
                     "output=\"roughness_out\" />"));
    ASSERT(strstr(t, "name=\"specular_IOR\" type=\"float\" value=\"1.5\""));
    ASSERT(strstr(t, "<output name=\"roughness_out\" type=\"float\" nodename=\"roughness\" />"));
    ASSERT(strstr(t, "read from the .glb's baked textures") && !strstr(t, "this is its average"));
    ASSERT(!strstr(t, "value=\"0.2, 0.4, 0.6\"")); /* the average is not an input */
    free(t);
    for (size_t i = 0; i < sizeof bad_paths / sizeof bad_paths[0]; i++) {
        mtlx_textures b = {bad_paths[i], "mr.png"};
        ASSERT_EQ(mtlx_write_textured(&p, "g", NULL, &b, &t, &e), GLINT_EINVAL);
        b.base_color = "bc.png", b.metallic_roughness = bad_paths[i];
        ASSERT_EQ(mtlx_write_textured(&p, "g", NULL, &b, &t, &e), GLINT_EINVAL);
    }
    ASSERT(t == NULL);
}

/* Read a little-endian integer of k bytes at p. */
static unsigned long le(const unsigned char *p, int k)
{
    unsigned long v = 0;
    for (int i = k - 1; i >= 0; i--)
        v = v << 8 | p[i];
    return v;
}

TEST(usdz_packages_are_stored_and_aligned)
{
    static const char layer[] = "#usda 1.0\n", png[] = "\x89PNG\r\n\x1a\n....";
    zip_entry f[3] = {{"glint.usda", layer, sizeof layer - 1},
                      {"textures/base_color.png", png, sizeof png - 1},
                      {"t.png", png, 3}};
    unsigned char *z = NULL;
    void *out;
    size_t len, at = 0;
    glint_err e;
    ASSERT_OK(usdz_pack(f, 3, &out, &len, &e));
    z = out;
    for (int i = 0; i < 3; i++) { /* each local header's data at a multiple of 64 */
        unsigned long nl, el, sz;
        ASSERT_EQ(le(z + at, 4), 0x04034b50UL);
        ASSERT_EQ(le(z + at + 8, 2), 0UL); /* stored */
        sz = le(z + at + 18, 4);
        ASSERT_EQ(sz, (unsigned long)f[i].len);
        ASSERT_EQ(le(z + at + 22, 4), sz);
        nl = le(z + at + 26, 2);
        el = le(z + at + 28, 2);
        ASSERT(memcmp(z + at + 30, f[i].path, nl) == 0);
        ASSERT_EQ((at + 30 + nl + el) % ZIP_ALIGN, 0UL);
        ASSERT(memcmp(z + at + 30 + nl + el, f[i].data, f[i].len) == 0);
        at += 30 + nl + el + sz;
    }
    ASSERT_EQ(le(z + at, 4), 0x02014b50UL); /* the central directory follows */
    ASSERT_EQ(le(z + len - 22, 4), 0x06054b50UL);
    ASSERT_EQ(le(z + len - 22 + 10, 2), 3UL);
    ASSERT_EQ(le(z + len - 22 + 16, 4), (unsigned long)at);
    free(out);
    /* refused: a first file that is no layer, bad paths, too many files */
    f[0].path = "a.png";
    ASSERT_EQ(usdz_pack(f, 3, &out, &len, &e), GLINT_EINVAL);
    f[0].path = "glint.mtlx"; /* a plain zip takes any first file */
    ASSERT_OK(zip_pack(f, 3, &out, &len, &e));
    ASSERT_EQ(le((unsigned char *)out + 26, 2), 10UL);
    ASSERT(memcmp((unsigned char *)out + 30, "glint.mtlx", 10) == 0);
    free(out);
    f[0].path = "glint.usda";
    f[1].path = "../x.png";
    ASSERT_EQ(usdz_pack(f, 3, &out, &len, &e), GLINT_EINVAL);
    f[1].path = "/abs.png";
    ASSERT_EQ(usdz_pack(f, 3, &out, &len, &e), GLINT_EINVAL);
    f[1].path = "ok.png";
    ASSERT_EQ(usdz_pack(f, 0, &out, &len, &e), GLINT_ERANGE);
    ASSERT_EQ(usdz_pack(f, ZIP_MAX_FILES + 1, &out, &len, &e), GLINT_ERANGE);
    ASSERT(out == NULL);
}

/* a pbr material's mapping with the three KHR extensions (gltf_direct.c) */
static gltf_pbr pbr_khr(void)
{
    gltf_pbr p = pbr(0.5, 0.25, 0.125, 0.0, 0.3);
    p.exact = 1;
    p.rel_rms_fitted = 0.05;
    p.khr.ior_used = p.khr.specular_used = p.khr.clearcoat_used = 1;
    p.khr.ior = 1.7;
    p.khr.specular = 0.8;
    p.khr.specular_color[0] = 1.0, p.khr.specular_color[1] = 0.5, p.khr.specular_color[2] = 0.25;
    p.khr.clearcoat = 0.5, p.khr.clearcoat_roughness = 0.2;
    return p;
}

TEST(the_khr_extensions_in_both_documents)
{
    gltf_pbr p = pbr_khr();
    double f0 = pow(0.7 / 2.7, 2.0);
    char *t = NULL, want[160];
    size_t len;
    glint_err e;
    ASSERT_OK(mtlx_write(&p, "g", NULL, &t, &e));
    /* F0 of the brightest channel (specularColor 1) is the ior's own */
    ASSERT(strstr(t, "name=\"specular_IOR\" type=\"float\" value=\"1.7\""));
    ASSERT(strstr(t, "name=\"specular\" type=\"float\" value=\"0.8\""));
    ASSERT(strstr(t, "name=\"specular_color\" type=\"color3\" value=\"1, 0.5, 0.25\""));
    ASSERT(strstr(t, "name=\"coat\" type=\"float\" value=\"0.5\""));
    ASSERT(strstr(t, "name=\"coat_roughness\" type=\"float\" value=\"0.2\""));
    ASSERT(strstr(t, "own parameters") && strstr(t, "the fit's: 0.0500"));
    free(t);
    ASSERT_OK(usda_write(&p, NULL, NULL, &t, &len, &e));
    ASSERT(strstr(t, "int inputs:useSpecularWorkflow = 1"));
    snprintf(want, sizeof want, "color3f inputs:specularColor = (%.6g, %.6g, %.6g)",
             0.8 * f0, 0.8 * 0.5 * f0, 0.8 * 0.25 * f0);
    ASSERT(strstr(t, want));
    ASSERT(strstr(t, "float inputs:ior = 1.7\n"));
    ASSERT(strstr(t, "float inputs:clearcoat = 0.5\n") &&
           strstr(t, "float inputs:clearcoatRoughness = 0.2\n"));
    free(t);
    /* a specular colour above 1: the ior rises to hold its F0 */
    p.khr.specular_color[0] = 2.0;
    ASSERT_OK(mtlx_write(&p, "g", NULL, &t, &e));
    {
        double r = sqrt(2.0 * f0);
        snprintf(want, sizeof want, "name=\"specular_IOR\" type=\"float\" value=\"%.6g\"",
                 (1.0 + r) / (1.0 - r));
        ASSERT(strstr(t, want));
        ASSERT(strstr(t, "value=\"1, 0.25, 0.125\""));
    }
    free(t);
    /* refused: an ior below 1, a negative specular colour, a coat above 1 */
    p = pbr_khr();
    p.khr.ior = 0.5;
    ASSERT_EQ(mtlx_write(&p, "g", NULL, &t, &e), GLINT_EINVAL);
    ASSERT_EQ(usda_write(&p, NULL, NULL, &t, &len, &e), GLINT_EINVAL);
    p = pbr_khr();
    p.khr.specular_color[1] = -0.1;
    ASSERT_EQ(mtlx_write(&p, "g", NULL, &t, &e), GLINT_EINVAL);
    p = pbr_khr();
    p.khr.clearcoat = 1.5;
    ASSERT_EQ(usda_write(&p, NULL, NULL, &t, &len, &e), GLINT_EINVAL);
    ASSERT(t == NULL);
}

TEST_LIST{
    TEST_ENTRY(mtlx_carries_the_fit),
    TEST_ENTRY(mtlx_extremes_and_refusals),
    TEST_ENTRY(names_and_notes_cannot_break_the_documents),
    TEST_ENTRY(usda_material_and_mesh),
    TEST_ENTRY(the_khr_extensions_in_both_documents),
    TEST_ENTRY(usda_textures_connected),
    TEST_ENTRY(mtlx_textures_connected),
    TEST_ENTRY(usdz_packages_are_stored_and_aligned),
};
TEST_MAIN()
