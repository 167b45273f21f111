/* usdz_export.c: USDZ packages (usdz.h): a material's glTF fit and bake
 * (gltf.h), their textures as PNG, the USD layer naming them (usda.h),
 * packed as a stored zip (zip.h) that starts with the layer. */
#include <stdlib.h>
#include <string.h>

#include "usda.h"
#include "usdz.h"

#define LAYER "glint.usda"
#define TEX_BASE "textures/base_color.png"
#define TEX_MR "textures/metallic_roughness.png"

static int is_layer(const char *p)
{
    size_t n = p ? strlen(p) : 0;
    return n > 5 && (strcmp(p + n - 5, ".usda") == 0 || strcmp(p + n - 5, ".usdc") == 0);
}

int usdz_pack(const zip_entry *files, int n, void **out, size_t *len, glint_err *err)
{
    *out = NULL;
    *len = 0;
    if (n >= 1 && !is_layer(files[0].path))
        return glint_err_set(err, GLINT_EINVAL, "a USDZ package starts with a USD layer, not %s",
                             files[0].path ? files[0].path : "(none)");
    return zip_pack(files, n, out, len, err);
}

int usdz_export_scene(const material *m, const scene *sc, const unsigned char *use,
                      int bake_res, const char *note, void **out, size_t *len, gltf_pbr *p,
                      gltf_export_info *info, glint_err *err)
{
    static const usda_textures tex = {TEX_BASE, TEX_MR};
    zip_entry files[3] = {{LAYER, NULL, 0}, {TEX_BASE, NULL, 0}, {TEX_MR, NULL, 0}};
    gltf_export_info dummy;
    gltf_pngs png;
    size_t text_len = 0;
    char *text = NULL;
    int rc;

    *out = NULL;
    *len = 0;
    if (!info)
        info = &dummy;
    if ((rc = gltf_bake_scene_png(m, sc, use, bake_res, p, &png, info, err)))
        goto done;
    rc = info->baked ? usda_write_textured(p, &sc->mesh, &tex, note, &text, &text_len, err)
                     : usda_write(p, &sc->mesh, note ? note : info->note, &text, &text_len, err);
    if (rc)
        goto done;
    files[0].data = text, files[0].len = text_len;
    files[1].data = png.base, files[1].len = png.base_len;
    files[2].data = png.mr, files[2].len = png.mr_len;
    rc = usdz_pack(files, info->baked ? 3 : 1, out, len, err);
done:
    free(text);
    gltf_pngs_free(&png);
    return rc;
}
