/* mtlx_export.c: MaterialX packages (mtlx.h): a material's glTF fit and
 * bake (gltf.h), their textures as PNG, the MaterialX document reading
 * them, packed as a zip (zip.h). */
#include <stdlib.h>
#include <string.h>

#include "mtlx.h"
#include "zip.h"

#define DOC "glint.mtlx"
#define TEX_BASE "textures/base_color.png"
#define TEX_MR "textures/metallic_roughness.png"

int mtlx_export_scene(const material *m, const scene *sc, const unsigned char *use,
                      int bake_res, const char *name, const char *note, void **out,
                      size_t *len, gltf_pbr *p, gltf_export_info *info, glint_err *err)
{
    static const mtlx_textures tex = {TEX_BASE, TEX_MR};
    zip_entry files[3] = {{DOC, NULL, 0}, {TEX_BASE, NULL, 0}, {TEX_MR, NULL, 0}};
    gltf_export_info dummy;
    gltf_pngs png;
    char *text = NULL;
    int rc;

    *out = NULL;
    *len = 0;
    if (!info)
        info = &dummy;
    if ((rc = gltf_bake_scene_png(m, sc, use, bake_res, p, &png, info, err)) ||
        (rc = mtlx_write_textured(p, name, note ? note : info->note, info->baked ? &tex : NULL,
                                  &text, err)))
        goto done;
    files[0].data = text, files[0].len = strlen(text);
    files[1].data = png.base, files[1].len = png.base_len;
    files[2].data = png.mr, files[2].len = png.mr_len;
    rc = zip_pack(files, info->baked ? 3 : 1, out, len, err);
done:
    free(text);
    gltf_pngs_free(&png);
    return rc;
}
