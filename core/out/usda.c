/* usda.c: text USD layers of glTF metallic-roughness fits (usda.h). */
#include "usda.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "buf.h"

static int pbr_valid(const gltf_pbr *p)
{
    double v[7] = {p->base[0], p->base[1], p->base[2], p->metallic, p->roughness,
                   p->khr.clearcoat_used ? p->khr.clearcoat : 0.0,
                   p->khr.clearcoat_used ? p->khr.clearcoat_roughness : 0.0};
    for (int i = 0; i < 7; i++)
        if (!(v[i] >= 0.0 && v[i] <= 1.0))
            return 0;
    if (p->khr.ior_used && !(p->khr.ior >= 1.0 && isfinite(p->khr.ior)))
        return 0;
    if (p->khr.specular_used) {
        if (!(p->khr.specular >= 0.0 && p->khr.specular <= 1.0))
            return 0;
        for (int c = 0; c < 3; c++)
            if (!(p->khr.specular_color[c] >= 0.0 && isfinite(p->khr.specular_color[c])))
                return 0;
    }
    return isfinite(p->rel_rms) && p->rel_rms >= 0.0;
}

/* text safe inside a USD triple-quoted string: no '"' runs, no backslash */
static int doc_text(glint_buf *b, const char *s)
{
    int rc = 0;
    for (; s && *s && !rc; s++) {
        char c = *s == '"' || *s == '\\' || (unsigned char)*s < 32 ? ' ' : *s;
        rc = glint_buf_append(b, &c, 1);
    }
    return rc;
}

static int header(glint_buf *b, const gltf_pbr *p, int textured, const char *note)
{
    int rc = glint_buf_printf(
        b,
        "#usda 1.0\n(\n    defaultPrim = \"glint\"\n    doc = \"\"\"glint: the material as a "
        "UsdPreviewSurface (%s workflow), from ",
        p->khr.specular_used && !textured ? "specular" : "metallic");
    if (p->exact)
        rc |= glint_buf_printf(
            b,
            "the pbr material's own parameters as the .glb carries them (glTF metallic-roughness "
            "with KHR ior, specular and clearcoat). rel_rms %.4f: the relative RMS error of the "
            "glTF model against the material on the painted views (%d pairs; the fit's: %.4f).",
            p->rel_rms, p->pairs, p->rel_rms_fitted);
    else
        rc |= glint_buf_printf(
            b,
            "the glTF 2.0 metallic-roughness fit (the .glb's numbers): least squares of f cos at "
            "the painted views' samples (%d pairs). fit_rel_rms %.4f: the relative RMS error of "
            "that fit against the material on the painted views.",
            p->pairs, p->rel_rms);
    if (p->spatial && textured)
        rc |= glint_buf_printf(b, " The material varies over the surface: its base colour, "
                                  "metallic and roughness are the baked textures of the .glb "
                                  "(glTF's core model, without the KHR extensions of the "
                                  "average), read at primvars:st.");
    else if (p->spatial)
        rc |= glint_buf_printf(b, " The material varies over the surface: this is its average "
                                  "(no textures; the .glb and the .usdz carry them).");
    if (note && *note) {
        rc |= glint_buf_printf(b, " ");
        rc |= doc_text(b, note);
    }
    rc |= glint_buf_printf(b, "\"\"\"\n    metersPerUnit = 1\n    upAxis = \"Z\"\n)\n\n"
                              "def Xform \"glint\"\n{\n");
    return rc;
}

/* n tuples of k floats, as USD's array of tuples "[(a, b), ...]" */
static int tuples(glint_buf *b, const float *v, long n, int k)
{
    int rc = glint_buf_printf(b, "[");
    for (long i = 0; i < n && !rc; i++) {
        rc |= glint_buf_printf(b, "%s(", i ? ", " : "");
        for (int e = 0; e < k; e++)
            rc |= glint_buf_printf(b, "%s%.7g", e ? ", " : "", (double)v[k * i + e]);
        rc |= glint_buf_printf(b, ")");
    }
    return rc | glint_buf_printf(b, "]");
}

static int mesh_prim(glint_buf *b, const mesh *m)
{
    int rc = glint_buf_printf(b, "    def Mesh \"mesh\" (\n        prepend apiSchemas = "
                                 "[\"MaterialBindingAPI\"]\n    )\n    {\n"
                                 "        int[] faceVertexCounts = [");
    for (int t = 0; t < m->ntris && !rc; t++)
        rc |= glint_buf_printf(b, t ? ", 3" : "3");
    rc |= glint_buf_printf(b, "]\n        int[] faceVertexIndices = [");
    for (long i = 0; i < 3L * m->ntris && !rc; i++)
        rc |= glint_buf_printf(b, "%s%u", i ? ", " : "", (unsigned)m->tri[i]);
    rc |= glint_buf_printf(b, "]\n        rel material:binding = </glint/material>\n"
                              "        normal3f[] normals = ");
    rc |= tuples(b, m->nrm, m->nverts, 3);
    rc |= glint_buf_printf(b, " (\n            interpolation = \"vertex\"\n        )\n"
                              "        uniform token orientation = \"rightHanded\"\n"
                              "        point3f[] points = ");
    rc |= tuples(b, m->pos, m->nverts, 3);
    rc |= glint_buf_printf(b, "\n");
    if (m->uv) {
        rc |= glint_buf_printf(b, "        texCoord2f[] primvars:st = ");
        rc |= tuples(b, m->uv, m->nverts, 2);
        rc |= glint_buf_printf(b, " (\n            interpolation = \"vertex\"\n        )\n");
    }
    return rc | glint_buf_printf(b, "        uniform token subdivisionScheme = \"none\"\n    }\n\n");
}

/* KHR's dielectric f0 per channel: min(F0(ior) specularColor, 1) specular */
static void dielectric_f0(const gltf_pbr *p, double f0[3])
{
    double r = p->khr.ior_used ? (p->khr.ior - 1.0) / (p->khr.ior + 1.0) : 0.2;
    for (int c = 0; c < 3; c++) {
        double f = r * r * (p->khr.specular_used ? p->khr.specular_color[c] : 1.0);
        f0[c] = (f < 1.0 ? f : 1.0) * (p->khr.specular_used ? p->khr.specular : 1.0);
    }
}

/* The texture readers: primvars:st, then one UsdUVTexture per image. */
static int texture_prims(glint_buf *b, const usda_textures *t)
{
    static const char *const fmt =
        "        def Shader \"%s\"\n        {\n"
        "            uniform token info:id = \"UsdUVTexture\"\n"
        "            asset inputs:file = @%s@\n"
        "            token inputs:sourceColorSpace = \"%s\"\n"
        "            float2 inputs:st.connect = </glint/material/st.outputs:result>\n"
        "            token inputs:wrapS = \"clamp\"\n"
        "            token inputs:wrapT = \"clamp\"\n"
        "%s        }\n\n";
    int rc = glint_buf_printf(b, "        def Shader \"st\"\n        {\n"
                                 "            uniform token info:id = \"UsdPrimvarReader_float2\"\n"
                                 "            string inputs:varname = \"st\"\n"
                                 "            float2 outputs:result\n        }\n\n");
    rc |= glint_buf_printf(b, fmt, "base_color", t->base_color, "sRGB",
                           "            float3 outputs:rgb\n");
    rc |= glint_buf_printf(b, fmt, "metallic_roughness", t->metallic_roughness, "raw",
                           "            float outputs:b\n            float outputs:g\n");
    return rc;
}

/* The surface reading the textures (metallic workflow, ior 1.5). */
static int textured_surface(glint_buf *b)
{
    return glint_buf_printf(
        b,
        "        def Shader \"surface\"\n        {\n"
        "            uniform token info:id = \"UsdPreviewSurface\"\n"
        "            color3f inputs:diffuseColor.connect = "
        "</glint/material/base_color.outputs:rgb>\n"
        "            float inputs:ior = %.6g\n"
        "            float inputs:metallic.connect = "
        "</glint/material/metallic_roughness.outputs:b>\n"
        "            float inputs:roughness.connect = "
        "</glint/material/metallic_roughness.outputs:g>\n"
        "            int inputs:useSpecularWorkflow = 0\n"
        "            token outputs:surface\n        }\n    }\n}\n",
        USDA_IOR);
}

static int material_prim(glint_buf *b, const gltf_pbr *p, const usda_textures *tex)
{
    double f0[3];
    int rc;
    dielectric_f0(p, f0);
    rc = glint_buf_printf(
        b,
        "    def Material \"material\"\n    {\n"
        "        token outputs:surface.connect = </glint/material/surface.outputs:surface>\n\n");
    if (tex)
        return rc | texture_prims(b, tex) | textured_surface(b);
    rc |= glint_buf_printf(b, "        def Shader \"surface\"\n        {\n"
                              "            uniform token info:id = \"UsdPreviewSurface\"\n");
    if (p->khr.clearcoat_used)
        rc |= glint_buf_printf(b,
                               "            float inputs:clearcoat = %.6g\n"
                               "            float inputs:clearcoatRoughness = %.6g\n",
                               p->khr.clearcoat, p->khr.clearcoat_roughness);
    rc |= glint_buf_printf(b,
                           "            color3f inputs:diffuseColor = (%.6g, %.6g, %.6g)\n"
                           "            float inputs:ior = %.6g\n"
                           "            float inputs:metallic = %.6g\n"
                           "            float inputs:roughness = %.6g\n",
                           p->base[0], p->base[1], p->base[2],
                           p->khr.ior_used ? p->khr.ior : USDA_IOR, p->metallic, p->roughness);
    if (p->khr.specular_used)
        rc |= glint_buf_printf(b, "            color3f inputs:specularColor = (%.6g, %.6g, %.6g)\n",
                               f0[0], f0[1], f0[2]);
    return rc | glint_buf_printf(b,
                                 "            int inputs:useSpecularWorkflow = %d\n"
                                 "            token outputs:surface\n        }\n    }\n}\n",
                                 p->khr.specular_used ? 1 : 0);
}

/* an asset path USD reads between @ signs: no '@', no control bytes */
static int asset_ok(const char *s)
{
    if (!s || !*s)
        return 0;
    for (; *s; s++)
        if (*s == '@' || (unsigned char)*s < 32)
            return 0;
    return 1;
}

int usda_write(const gltf_pbr *p, const mesh *msh, const char *note, char **text, size_t *len,
               glint_err *err)
{
    return usda_write_textured(p, msh, NULL, note, text, len, err);
}

int usda_write_textured(const gltf_pbr *p, const mesh *msh, const usda_textures *tex,
                        const char *note, char **text, size_t *len, glint_err *err)
{
    glint_buf b = {0};
    int rc;

    *text = NULL;
    *len = 0;
    if (!p || !pbr_valid(p))
        return glint_err_set(err, GLINT_EINVAL,
                             "a metallic-roughness material with a value outside [0, 1]");
    if (msh && (msh->nverts < 3 || msh->ntris < 1 || !msh->pos || !msh->nrm || !msh->tri))
        return glint_err_set(err, GLINT_EINVAL, "no mesh to write");
    if (tex && (!msh || !msh->uv || !asset_ok(tex->base_color) ||
                !asset_ok(tex->metallic_roughness)))
        return glint_err_set(err, GLINT_EINVAL,
                             "textures need the mesh with texture coordinates and two asset "
                             "paths");
    rc = header(&b, p, tex != NULL, note);
    if (!rc && msh)
        rc = mesh_prim(&b, msh);
    if (!rc)
        rc = material_prim(&b, p, tex);
    if (rc || !b.data) {
        glint_buf_free(&b);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a USD layer");
    }
    *text = glint_buf_steal(&b, len);
    return 0;
}
