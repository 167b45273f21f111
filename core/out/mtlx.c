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

/* Is p a material the file can carry (every value finite, in [0, 1]; an
 * ior at least 1, a specular colour finite and not negative)? */
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

/* Standard Surface's dielectric specular from p's (mtlx.h): specular_IOR
 * whose F0 is the largest channel's KHR f0 / specular, specular_color the
 * channels' ratios to it (OUT: *ior, col[3], *weight). */
static void specular_of(const gltf_pbr *p, double *ior, double col[3], double *weight)
{
    double f0i = 0.04, f0[3], fmax = 0.0, r;
    if (p->khr.ior_used) {
        r = (p->khr.ior - 1.0) / (p->khr.ior + 1.0);
        f0i = r * r;
    }
    for (int c = 0; c < 3; c++) {
        f0[c] = f0i * (p->khr.specular_used ? p->khr.specular_color[c] : 1.0);
        f0[c] = f0[c] < MTLX_F0_MAX ? f0[c] : MTLX_F0_MAX;
        fmax = f0[c] > fmax ? f0[c] : fmax;
    }
    *weight = p->khr.specular_used ? p->khr.specular : 1.0;
    if (!(fmax > 0.0)) { /* no reflection at normal incidence: a weight of 0 */
        *ior = p->khr.ior_used ? p->khr.ior : MTLX_IOR;
        col[0] = col[1] = col[2] = 1.0;
        *weight = 0.0;
        return;
    }
    r = sqrt(fmax);
    *ior = (1.0 + r) / (1.0 - r);
    for (int c = 0; c < 3; c++)
        col[c] = f0[c] / fmax;
}

/* The leading comment's account of where the numbers come from. */
static int origin_text(glint_buf *b, const gltf_pbr *p)
{
    if (p->exact)
        return glint_buf_printf(
            b,
            "    glint: the material as Autodesk Standard Surface, from the pbr\n"
            "    material's own parameters as the .glb carries them (glTF\n"
            "    metallic-roughness with KHR ior, specular and clearcoat).\n"
            "    rel_rms %.4f: the relative RMS error of the glTF model against\n"
            "    the material on the painted views (%d pairs; the fit's: %.4f).\n",
            p->rel_rms, p->pairs, p->rel_rms_fitted);
    return glint_buf_printf(b,
                            "    glint: the material as Autodesk Standard Surface, from the\n"
                            "    glTF 2.0 metallic-roughness fit (the .glb's numbers):\n"
                            "    least squares of f cos at the painted views' samples (%d pairs).\n"
                            "    fit_rel_rms %.4f: the relative RMS error of that fit against\n"
                            "    the material on the painted views.\n",
                            p->pairs, p->rel_rms);
}

/* An image node of graph nm reading `file` (colour space cs, NULL: raw
 * data), clamped at the edges. */
static int image_node(glint_buf *b, const char *node, const char *type, const char *file,
                      const char *cs)
{
    return glint_buf_printf(
        b,
        "    <image name=\"%s\" type=\"%s\">\n"
        "      <input name=\"file\" type=\"filename\" value=\"%s\"%s%s%s />\n"
        "      <input name=\"uaddressmode\" type=\"string\" value=\"clamp\" />\n"
        "      <input name=\"vaddressmode\" type=\"string\" value=\"clamp\" />\n"
        "    </image>\n",
        node, type, file, cs ? " colorspace=\"" : "", cs ? cs : "", cs ? "\"" : "");
}

/* The node graph reading the baked textures: base_color (sRGB), and the
 * metallic-roughness image's G (roughness) and B (metalness). */
static int texture_graph(glint_buf *b, const char *nm, const mtlx_textures *t)
{
    int rc = glint_buf_printf(b, "  <nodegraph name=\"NG_%s\">\n", nm);
    rc |= image_node(b, "base_color_image", "color3", t->base_color, "srgb_texture");
    rc |= image_node(b, "metallic_roughness_image", "vector3", t->metallic_roughness, NULL);
    rc |= glint_buf_printf(
        b,
        "    <extract name=\"roughness\" type=\"float\">\n"
        "      <input name=\"in\" type=\"vector3\" nodename=\"metallic_roughness_image\" />\n"
        "      <input name=\"index\" type=\"integer\" value=\"1\" />\n"
        "    </extract>\n"
        "    <extract name=\"metalness\" type=\"float\">\n"
        "      <input name=\"in\" type=\"vector3\" nodename=\"metallic_roughness_image\" />\n"
        "      <input name=\"index\" type=\"integer\" value=\"2\" />\n"
        "    </extract>\n"
        "    <output name=\"base_color_out\" type=\"color3\" nodename=\"base_color_image\" />\n"
        "    <output name=\"roughness_out\" type=\"float\" nodename=\"roughness\" />\n"
        "    <output name=\"metalness_out\" type=\"float\" nodename=\"metalness\" />\n"
        "  </nodegraph>\n");
    return rc;
}

/* The standard_surface's inputs that carry the average's values, or with
 * tex its textures (the bake's glTF core model: specular_IOR 1.5, no coat). */
static int surface_inputs(glint_buf *b, const gltf_pbr *p, const char *nm,
                          const mtlx_textures *tex)
{
    double ior, col[3], weight;
    int rc;
    if (tex)
        return glint_buf_printf(
            b,
            "    <input name=\"base\" type=\"float\" value=\"1\" />\n"
            "    <input name=\"base_color\" type=\"color3\" nodegraph=\"NG_%s\" "
            "output=\"base_color_out\" />\n"
            "    <input name=\"metalness\" type=\"float\" nodegraph=\"NG_%s\" "
            "output=\"metalness_out\" />\n"
            "    <input name=\"specular\" type=\"float\" value=\"1\" />\n"
            "    <input name=\"specular_color\" type=\"color3\" value=\"1, 1, 1\" />\n"
            "    <input name=\"specular_roughness\" type=\"float\" nodegraph=\"NG_%s\" "
            "output=\"roughness_out\" />\n"
            "    <input name=\"specular_IOR\" type=\"float\" value=\"%.6g\" />\n",
            nm, nm, nm, MTLX_IOR);
    specular_of(p, &ior, col, &weight);
    rc = glint_buf_printf(
        b,
        "    <input name=\"base\" type=\"float\" value=\"1\" />\n"
        "    <input name=\"base_color\" type=\"color3\" value=\"%.6g, %.6g, %.6g\" />\n"
        "    <input name=\"metalness\" type=\"float\" value=\"%.6g\" />\n"
        "    <input name=\"specular\" type=\"float\" value=\"%.6g\" />\n"
        "    <input name=\"specular_color\" type=\"color3\" value=\"%.6g, %.6g, %.6g\" />\n"
        "    <input name=\"specular_roughness\" type=\"float\" value=\"%.6g\" />\n"
        "    <input name=\"specular_IOR\" type=\"float\" value=\"%.6g\" />\n",
        p->base[0], p->base[1], p->base[2], p->metallic, weight, col[0], col[1], col[2],
        p->roughness, ior);
    if (p->khr.clearcoat_used)
        rc |= glint_buf_printf(
            b,
            "    <input name=\"coat\" type=\"float\" value=\"%.6g\" />\n"
            "    <input name=\"coat_roughness\" type=\"float\" value=\"%.6g\" />\n"
            "    <input name=\"coat_IOR\" type=\"float\" value=\"1.5\" />\n",
            p->khr.clearcoat, p->khr.clearcoat_roughness);
    return rc;
}

/* a texture's name as a filename value: relative, printable, no XML
 * metacharacters, no ".." */
static int tex_path_ok(const char *s)
{
    if (!s || !*s || *s == '/' || strstr(s, ".."))
        return 0;
    for (; *s; s++)
        if ((unsigned char)*s < 32 || (unsigned char)*s > 126 || strchr("<>&\"'\\", *s))
            return 0;
    return 1;
}

int mtlx_write_textured(const gltf_pbr *p, const char *name, const char *note,
                        const mtlx_textures *tex, char **text, glint_err *err)
{
    glint_buf b = {0};
    char nm[64];
    int rc = 0;

    *text = NULL;
    if (!p || !pbr_valid(p))
        return glint_err_set(err, GLINT_EINVAL,
                             "a metallic-roughness material with a value outside its range");
    if (tex && !(tex_path_ok(tex->base_color) && tex_path_ok(tex->metallic_roughness)))
        return glint_err_set(err, GLINT_EINVAL, "a texture path MaterialX cannot name");
    node_name(name, nm, sizeof nm);
    rc |= glint_buf_printf(&b, "<?xml version=\"1.0\"?>\n<materialx version=\"1.38\" "
                               "colorspace=\"lin_rec709\">\n  <!--\n");
    rc |= origin_text(&b, p);
    if (tex)
        rc |= glint_buf_printf(
            &b,
            "    The material varies over the surface: base_color, metalness and\n"
            "    specular_roughness are read from the .glb's baked textures, one\n"
            "    fit per texel over the mesh's texture coordinates (the image's\n"
            "    lower-left corner at uv (0, 0)); the numbers above are the average's.\n");
    else if (p->spatial)
        rc |= glint_buf_printf(&b, "    The material varies over the surface: this is its average\n"
                                   "    (no textures; the package and the .glb carry them).\n");
    if (note && *note) {
        rc |= glint_buf_printf(&b, "    ");
        rc |= comment_text(&b, note);
        rc |= glint_buf_printf(&b, "\n");
    }
    rc |= glint_buf_printf(&b, "  -->\n");
    if (tex)
        rc |= texture_graph(&b, nm, tex);
    rc |= glint_buf_printf(&b, "  <standard_surface name=\"SR_%s\" type=\"surfaceshader\">\n",
                           nm);
    rc |= surface_inputs(&b, p, nm, tex);
    rc |= glint_buf_printf(
        &b,
        "  </standard_surface>\n"
        "  <surfacematerial name=\"M_%s\" type=\"material\">\n"
        "    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"SR_%s\" />\n"
        "  </surfacematerial>\n"
        "</materialx>\n",
        nm, nm);
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

int mtlx_write(const gltf_pbr *p, const char *name, const char *note, char **text,
               glint_err *err)
{
    return mtlx_write_textured(p, name, note, NULL, text, err);
}
