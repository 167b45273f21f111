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

int mtlx_write(const gltf_pbr *p, const char *name, const char *note, char **text,
               glint_err *err)
{
    glint_buf b = {0};
    char nm[64];
    double ior, col[3], weight;
    int rc = 0;

    *text = NULL;
    if (!p || !pbr_valid(p))
        return glint_err_set(err, GLINT_EINVAL,
                             "a metallic-roughness material with a value outside its range");
    node_name(name, nm, sizeof nm);
    specular_of(p, &ior, col, &weight);
    rc |= glint_buf_printf(&b, "<?xml version=\"1.0\"?>\n<materialx version=\"1.38\">\n  <!--\n");
    rc |= origin_text(&b, p);
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
        "    <input name=\"specular\" type=\"float\" value=\"%.6g\" />\n"
        "    <input name=\"specular_color\" type=\"color3\" value=\"%.6g, %.6g, %.6g\" />\n"
        "    <input name=\"specular_roughness\" type=\"float\" value=\"%.6g\" />\n"
        "    <input name=\"specular_IOR\" type=\"float\" value=\"%.6g\" />\n",
        nm, p->base[0], p->base[1], p->base[2], p->metallic, weight, col[0], col[1], col[2],
        p->roughness, ior);
    if (p->khr.clearcoat_used)
        rc |= glint_buf_printf(
            &b,
            "    <input name=\"coat\" type=\"float\" value=\"%.6g\" />\n"
            "    <input name=\"coat_roughness\" type=\"float\" value=\"%.6g\" />\n"
            "    <input name=\"coat_IOR\" type=\"float\" value=\"1.5\" />\n",
            p->khr.clearcoat, p->khr.clearcoat_roughness);
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
