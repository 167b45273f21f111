/* usdz_export.c: a material as a USDZ package (usdz.h): the glTF fit and
 * bake (gltf.h), their textures as PNG, the USD layer naming them
 * (usda.h), packed. */
#include <stdlib.h>
#include <string.h>

#include "usda.h"
#include "usdz.h"

#define LAYER "glint.usda"
#define TEX_BASE "textures/base_color.png"
#define TEX_MR "textures/metallic_roughness.png"

int usdz_export_scene(const material *m, const scene *sc, const unsigned char *use,
                      int bake_res, const char *note, void **out, size_t *len, gltf_pbr *p,
                      gltf_export_info *info, glint_err *err)
{
    static const usda_textures tex = {TEX_BASE, TEX_MR};
    gltf_bake bake;
    gltf_export_info dummy;
    void *bc = NULL, *mr = NULL;
    size_t bc_len = 0, mr_len = 0, text_len = 0;
    char *text = NULL;
    int rc;

    *out = NULL;
    *len = 0;
    if (!info)
        info = &dummy;
    if ((rc = gltf_bake_scene(m, sc, use, bake_res, p, &bake, info, err)))
        goto done;
    if (info->baked) {
        usdz_file files[3] = {{LAYER, NULL, 0}, {TEX_BASE, NULL, 0}, {TEX_MR, NULL, 0}};
        if ((rc = gltf_bake_png(&bake, &bc, &bc_len, &mr, &mr_len, err)) ||
            (rc = usda_write_textured(p, &sc->mesh, &tex, note, &text, &text_len, err)))
            goto done;
        files[0].data = text, files[0].len = text_len;
        files[1].data = bc, files[1].len = bc_len;
        files[2].data = mr, files[2].len = mr_len;
        rc = usdz_pack(files, 3, out, len, err);
    } else {
        usdz_file layer = {LAYER, NULL, 0};
        if ((rc = usda_write(p, &sc->mesh, note ? note : info->note, &text, &text_len, err)))
            goto done;
        layer.data = text, layer.len = text_len;
        rc = usdz_pack(&layer, 1, out, len, err);
    }
done:
    free(text);
    free(bc);
    free(mr);
    gltf_bake_free(&bake);
    return rc;
}
