/* cmd_demo.c: glint demo: paint the built-in sphere from the 12
 * icosahedron views with a Cook-Torrance material, fit it, and measure and
 * render views whose camera and light were never painted. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdf.h"
#include "cli.h"
#include "fsio.h"
#include "paint.h"
#include "raster.h"

int cmd_demo(int argc, char **argv)
{
    const char *out = argc > 2 && strcmp(argv[1], "-o") == 0 ? argv[2] : "glint-demo";
    const char *spec = "ct:rough=0.3,kd=0.6/0.35/0.2,f0=0.04";
    scene_params sp;
    scene train, novel;
    gbuf *gt = NULL, *gn = NULL;
    img *pt = NULL, *pn = NULL;
    brdf b;
    fit_opts o;
    material m;
    glint_err e;
    double scale = 0, rms_n = 0, max_n = 0;
    char path[4096];
    int rc = 0;

    if (argc > 1 && !(argc == 3 && strcmp(argv[1], "-o") == 0))
        return fail(1, "usage: glint demo [-o DIR]");
    memset(&m, 0, sizeof m);
    fit_opts_init(&o);
    memset(&train, 0, sizeof train);
    memset(&novel, 0, sizeof novel);
    scene_params_default(&sp);
    if (brdf_parse(spec, &b, &e) || scene_create(&sp, &train, &e) || fsio_mkdirs(out, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    sp.view_set = SCENE_VIEWS_ICO20;
    sp.light_mid = 1;
    if (scene_create(&sp, &novel, &e) || raster_scene(&train, &gt, &e) ||
        raster_scene(&novel, &gn, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    pt = calloc((size_t)train.nviews, sizeof *pt);
    pn = calloc((size_t)novel.nviews, sizeof *pn);
    if (!pt || !pn) {
        rc = fail(1, "out of memory");
        goto done;
    }
    printf("glint demo: painting the built-in sphere from %d views with %s\n", train.nviews, spec);
    if (paint_views(&b, gt, train.views, train.nviews, 0.0, pt, &scale, &e) ||
        paint_views(&b, gn, novel.views, novel.nviews, scale, pn, NULL, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    snprintf(path, sizeof path, "%s/scene.json", out);
    if (scene_save(&train, path, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    snprintf(path, sizeof path, "%s/paintings", out);
    if (fsio_mkdirs(path, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    for (int v = 0; v < train.nviews; v++) {
        snprintf(path, sizeof path, "%s/paintings/view_%02d.png", out, v);
        if (img_write(path, &pt[v], &e)) {
            rc = fail_err(&e);
            goto done;
        }
    }
    {
        unsigned char use[SCENE_MAX_VIEWS];
        memset(use, 1, sizeof use);
        if ((rc = fit_opts_resolve(&o)) || (rc = cli_fit_scene(&o, &train, use, pt, &m)))
            goto done;
    }
    if (material_error_views(&m, gn, novel.views, novel.nviews, pn, &rms_n, &max_n, NULL, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    json_object_set_new(m.info, "novel_views",
                        json_pack("{s:i, s:f, s:f}", "views", novel.nviews, "rms", rms_n,
                                  "max_abs", max_n));
    snprintf(path, sizeof path, "%s/material", out);
    if ((rc = save_material(&m, path)))
        goto done;
    for (int v = 0; v < 4; v++) {
        img im = {0};
        snprintf(path, sizeof path, "%s/render_novel_%02d.png", out, v);
        if (material_shade(&m, &gn[v], novel.views[v].light_intensity, 0.0f, &im, &e) ||
            img_write(path, &im, &e)) {
            img_free(&im);
            rc = fail_err(&e);
            goto done;
        }
        img_free(&im);
    }
    {
        json_t *j = json_object_get(m.info, "errors"), *s = json_object_get(m.info, "seconds");
        json_t *pre = json_object_get(m.info, "precomputation");
        json_t *cc = json_object_get(pre, "cache");
        const char *disk = json_string_value(json_object_get(cc, "disk"));
        printf("  %d samples, %d texels per factor, precomputation %.3f s (%s), fit %.3f ms\n",
               (int)json_integer_value(json_object_get(pre, "samples")),
               (int)json_integer_value(json_object_get(json_object_get(m.info, "params"), "res")),
               json_real_value(json_object_get(cc, "cold_seconds")),
               disk && strcmp(disk, "loaded") == 0 ? "loaded from cache" : "computed",
               1e3 * json_real_value(json_object_get(s, "fit")));
        printf("  RMS on painted pixels %.4f, on %d novel views %.4f (max %.3f)\n",
               json_real_value(json_object_get(j, "rms_painted")), novel.nviews, rms_n, max_n);
        printf("  wrote %s/material (factors.exr, factors.png, material.json), %s/paintings, "
               "%s/render_novel_*.png\n", out, out, out);
    }
done:
    material_free(&m);
    fit_opts_free(&o);
    free_imgs(pt, train.nviews);
    free_imgs(pn, novel.nviews);
    raster_free_all(gt, train.nviews);
    raster_free_all(gn, novel.nviews);
    scene_free(&train);
    scene_free(&novel);
    return rc;
}
