/* mtlx.c: MaterialX documents of glTF metallic-roughness fits (mtlx.h). */
#include "mtlx.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "buf.h"

/* name cut to an XML and MaterialX identifier: [A-Za-z0-9_], a letter first */
static void node_name(const char *name, char *out, size_t cap)
{
    size_t k = 0;
    if (!name || !*name)
        name = "glint";
    if (!isalpha((unsigned char)name[0]))
        out[k++] = 'm';
    for (; *name && k + 1 < cap; name++)
        out[k++] = isalnum((unsigned char)*name) ? *name : '_';
    out[k] = 0;
}

/* text safe inside an XML comment: no "--", no control characters */
static int comment_text(glint_buf *b, const char *s)
{
    int rc = 0;
    for (char prev = 0; s && *s && !rc; prev = *s++) {
        char c = (unsigned char)*s < 32 ? ' ' : *s;
        if (c == '-' && prev == '-')
            c = ' ';
        rc = glint_buf_append(b, &c, 1);
    }
    return rc;
}

/* Is p a material the file can carry (every value finite, in [0, 1])? */
static int pbr_valid(const gltf_pbr *p)
{
    double v[5] = {p->base[0], p->base[1], p->base[2], p->metallic, p->roughness};
    for (int i = 0; i < 5; i++)
        if (!(v[i] >= 0.0 && v[i] <= 1.0))
            return 0;
    return isfinite(p->rel_rms) && p->rel_rms >= 0.0;
}

int mtlx_write(const gltf_pbr *p, const char *name, const char *note, char **text,
               glint_err *err)
{
    glint_buf b = {0};
    char nm[64];
    int rc = 0;

    *text = NULL;
    if (!p || !pbr_valid(p))
        return glint_err_set(err, GLINT_EINVAL,
                             "a metallic-roughness material with a value outside [0, 1]");
    node_name(name, nm, sizeof nm);
    rc |= glint_buf_printf(&b, "<?xml version=\"1.0\"?>\n<materialx version=\"1.38\">\n  <!--\n"
                               "    glint: the material as Autodesk Standard Surface, from the\n"
                               "    glTF 2.0 metallic-roughness fit (the .glb's numbers):\n"
                               "    least squares of f cos at the painted views' samples (%d pairs).\n"
                               "    fit_rel_rms %.4f: the relative RMS error of that fit against\n"
                               "    the material on the painted views.\n",
                           p->pairs, p->rel_rms);
    if (p->spatial)
        rc |= glint_buf_printf(&b, "    The material varies over the surface: this is its average\n"
                                   "    (no textures; the .glb carries them).\n");
    if (note && *note) {
        rc |= glint_buf_printf(&b, "    ");
        rc |= comment_text(&b, note);
        rc |= glint_buf_printf(&b, "\n");
    }
    rc |= glint_buf_printf(
        &b,
        "  -->\n"
        "  <standard_surface name=\"SR_%s\" type=\"surfaceshader\">\n"
        "    <input name=\"base\" type=\"float\" value=\"1\" />\n"
        "    <input name=\"base_color\" type=\"color3\" value=\"%.6g, %.6g, %.6g\" />\n"
        "    <input name=\"metalness\" type=\"float\" value=\"%.6g\" />\n"
        "    <input name=\"specular\" type=\"float\" value=\"1\" />\n"
        "    <input name=\"specular_color\" type=\"color3\" value=\"1, 1, 1\" />\n"
        "    <input name=\"specular_roughness\" type=\"float\" value=\"%.6g\" />\n"
        "    <input name=\"specular_IOR\" type=\"float\" value=\"%.6g\" />\n"
        "  </standard_surface>\n"
        "  <surfacematerial name=\"M_%s\" type=\"material\">\n"
        "    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"SR_%s\" />\n"
        "  </surfacematerial>\n"
        "</materialx>\n",
        nm, p->base[0], p->base[1], p->base[2], p->metallic, p->roughness, MTLX_IOR, nm, nm);
    if (rc || !b.data) {
        glint_buf_free(&b);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a MaterialX document");
    }
    {
        size_t len;
        *text = glint_buf_steal(&b, &len);
    }
    return 0;
}
