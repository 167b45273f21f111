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

static int header(glint_buf *b, const gltf_pbr *p, const char *note)
{
    int rc = glint_buf_printf(
        b,
        "#usda 1.0\n(\n    defaultPrim = \"glint\"\n    doc = \"\"\"glint: the material as a "
        "UsdPreviewSurface (%s workflow), from ",
        p->khr.specular_used ? "specular" : "metallic");
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
    if (p->spatial)
        rc |= glint_buf_printf(b, " The material varies over the surface: this is its average "
                                  "(no textures; the .glb carries them).");
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

static int material_prim(glint_buf *b, const gltf_pbr *p)
{
    double f0[3];
    int rc;
    dielectric_f0(p, f0);
    rc = glint_buf_printf(
        b,
        "    def Material \"material\"\n    {\n"
        "        token outputs:surface.connect = </glint/material/surface.outputs:surface>\n\n"
        "        def Shader \"surface\"\n        {\n"
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

int usda_write(const gltf_pbr *p, const mesh *msh, const char *note, char **text, size_t *len,
               glint_err *err)
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
    rc = header(&b, p, note);
    if (!rc && msh)
        rc = mesh_prim(&b, msh);
    if (!rc)
        rc = material_prim(&b, p);
    if (rc || !b.data) {
        glint_buf_free(&b);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a USD layer");
    }
    *text = glint_buf_steal(&b, len);
    return 0;
}
