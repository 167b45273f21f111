/* gpu_check.h: the GPU evaluates a material as the CPU does (the tests of
 * the methods with a GPU binding: test_hf4.c, test_hf2d.c, test_maps.c,
 * test_hybrid.c).  The default sphere rendered at size x size for views
 * v0, v0 + step, ... below nviews by the CPU renderer (material_render)
 * and by EGL (glr_preview): the mean |gl - cpu| over pixels and channels
 * must stay under 1/255 and the image must not be dark (its largest value
 * above 0.05).  Skipped without EGL, and under AddressSanitizer
 * (LeakSanitizer's exit scan crashed once on llvmpipe's threads). */
#ifndef GLINT_GPU_CHECK_H
#define GLINT_GPU_CHECK_H

#include <math.h>
#include <stdio.h>

#include "check.h"
#include "glr.h"
#include "material.h"
#include "mesh.h"
#include "scene.h"

static inline void gpu_check_agrees(const material *m, const scene *sc, int v0, int step,
                                    int nviews, int size)
{
    glr *g = NULL;
    glr_mesh *gm = NULL;
    mesh sph;
    glint_err e;
#if defined(__SANITIZE_ADDRESS__)
    (void)m, (void)sc, (void)v0, (void)step, (void)nviews, (void)size, (void)g, (void)gm;
    (void)sph, (void)e;
    printf("  gpu: skipped under AddressSanitizer\n");
#else
    if (glr_open(&g, &e)) {
        printf("  gpu: skipped: %s\n", e.msg);
        return;
    }
    if (mesh_sphere_default(&sph, &e)) {
        glr_close(g);
        ASSERT_MSG(0, "%s", e.msg);
    }
    if (glr_mesh_upload(g, &sph, &gm, &e)) {
        mesh_free(&sph);
        glr_close(g);
        ASSERT_MSG(0, "%s", e.msg);
    }
    for (int v = v0; v < nviews; v += step) {
        img ref, out;
        double d = 0.0, mx = 0.0;
        int bad = material_render(m, &sph, &sc->views[v], size, size, &ref, NULL, &e) != 0;
        if (!bad && glr_preview(g, gm, m, &sc->views[v], size, size, 0.0f, &out, &e) != 0) {
            img_free(&ref);
            bad = 1;
        }
        if (bad) {
            glr_mesh_free(g, gm);
            glr_close(g);
            mesh_free(&sph);
            ASSERT_MSG(0, "view %d: %s", v, e.msg);
        }
        for (size_t i = 0; i < (size_t)size * size * 3; i++) {
            d += fabs(ref.px[i] - out.px[i]);
            mx = ref.px[i] > mx ? ref.px[i] : mx;
        }
        d /= (double)size * size * 3;
        img_free(&ref);
        img_free(&out);
        printf("  gpu view %d: mean |gl - cpu| %.2e (1/255 = %.2e), max value %.3f\n", v, d,
               1.0 / 255, mx);
        if (!(d < 1.0 / 255) || !(mx > 0.05)) {
            glr_mesh_free(g, gm);
            glr_close(g);
            mesh_free(&sph);
            ASSERT_MSG(0, "view %d: the GPU differs from the CPU by %.3g on average (max value "
                          "%.3g)", v, d, mx);
        }
    }
    glr_mesh_free(g, gm);
    glr_close(g);
    mesh_free(&sph);
#endif
}

#endif
