/* bench_envrender.c: previews under an environment (render.h's
 * render_material_env): time and error side by side.
 *
 * For the sphere, the bunny and the cow (DIR/meshes), under two CC0 maps
 * (DIR/envmaps: courtyard.exr, sunset.exr; the built-in sky and studio
 * when absent), with and without shadows, at 512x512: the preview of an
 * srbf material with all 147 lobes non-zero (the costliest evaluation a
 * fit can give) through EGL (vertex shading, seed 004 equation 22) cold
 * (lights, visibility) and warm (a new view: shading + draw, median of
 * 15), against the per-pixel CPU reference (its own shadow rays per pixel):
 * the relative RMS difference over covered pixels.
 *
 *   ./build/tests/bench/bench_envrender [--quick] [--data DIR] [--size N]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "bench_env.h"
#include "env.h"
#include "material.h"
#include "method_srbf.h"
#include "render.h"
#include "scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* An srbf material: 147 lobes (res 7, sigma pi/40), every coefficient
 * non-zero (random, fixed seed), a diffuse part, the microfacet term. */
static void make_material(material *m)
{
    srbf_material sm;
    unsigned s = 12345;
    memset(&sm, 0, sizeof sm);
    srbf_basis_make(7, M_PI / 40, &sm.b, NULL);
    sm.st.kind = SRBF_STATIC_SMITH;
    sm.st.f0 = 0.04;
    sm.st.alpha = 0.3;
    sm.c = malloc(3 * (size_t)sm.b.J * sizeof *sm.c);
    for (int i = 0; i < 3 * sm.b.J; i++) {
        s = s * 1103515245u + 12345u;
        sm.c[i] = 0.05 * ((s >> 8) & 0xffff) / 65535.0;
    }
    for (int c = 0; c < 3; c++)
        sm.rho[c] = 0.2 + 0.1 * c;
    if (srbf_material_init(m, &sm, NULL, NULL)) {
        fprintf(stderr, "bench_envrender: out of memory\n");
        exit(1);
    }
}

static double rel_rms(const img *a, const img *b, const img *mask_src)
{
    double num = 0.0, den = 0.0;
    (void)mask_src;
    for (long p = 0; p < (long)a->width * a->height; p++)
        for (int c = 0; c < 3; c++) {
            double d = a->px[3 * p + c] - b->px[3 * p + c];
            num += d * d;
            den += (double)b->px[3 * p + c] * b->px[3 * p + c];
        }
    return den > 0.0 ? sqrt(num / den) : 0.0;
}

static void row(render *r, const material *mat, const char *mesh_file, const char *env,
                int shadows, int size, int quick)
{
    scene_params p;
    scene sc;
    scene_view v;
    render_env e;
    render_env_info info;
    img gl, cpu;
    glint_err err;
    double t0, cold, warm[15], shade[15], draw[15], tcpu = 0.0, err_rel = NAN;
    int nw = quick ? 5 : 15;
    char key[128];

    const mesh *msh;
    scene_params_default(&p);
    if (strcmp(mesh_file, "sphere") && strcmp(mesh_file, "ball")) {
        snprintf(p.mesh_path, sizeof p.mesh_path, "%s/meshes/%s", DATA, mesh_file);
        struct stat st;
        if (stat(p.mesh_path, &st)) {
            printf("| %s | %s | %s | absent |\n", mesh_file, env, shadows ? "on" : "off");
            return;
        }
    }
    if (scene_create(&p, &sc, &err)) {
        printf("| %s | %s | error: %s |\n", mesh_file, env, err.msg);
        return;
    }
    msh = &sc.mesh;
    if (!strcmp(mesh_file, "ball") && render_ball(&msh, &err)) {
        printf("| ball | error: %s |\n", err.msg);
        scene_free(&sc);
        return;
    }
    render_env_init(&e);
    snprintf(e.spec, sizeof e.spec, "%s", env);
    e.shadows = shadows;
    e.background = 0;
    snprintf(key, sizeof key, "%s", mesh_file);
    v = sc.views[0];
    t0 = now();
    if (render_material_env(r, RENDER_EGL, key, msh, mat, &e, &v, size, size, &gl, &info,
                            NULL, NULL, &err)) {
        printf("| %s | %s | EGL failed: %s |\n", mesh_file, env, err.msg);
        scene_free(&sc);
        return;
    }
    cold = now() - t0;
    img_free(&gl);
    for (int i = 0; i < nw; i++) {
        v = sc.views[(i + 1) % sc.nviews];
        t0 = now();
        render_material_env(r, RENDER_EGL, key, msh, mat, &e, &v, size, size, &gl, &info,
                            NULL, NULL, &err);
        warm[i] = now() - t0;
        shade[i] = info.shade_s;
        draw[i] = info.draw_s;
        if (i + 1 < nw)
            img_free(&gl);
    }
    /* the last warm view against the CPU reference */
    t0 = now();
    if (render_material_env(r, RENDER_CPU, key, msh, mat, &e, &v, size, size, &cpu, NULL,
                            NULL, NULL, &err) == 0) {
        tcpu = now() - t0;
        err_rel = rel_rms(&gl, &cpu, NULL);
        img_free(&cpu);
    }
    img_free(&gl);
    qsort(warm, nw, sizeof *warm, cmp_d);
    qsort(shade, nw, sizeof *shade, cmp_d);
    qsort(draw, nw, sizeof *draw, cmp_d);
    printf("| %s | %d | %s | %s | %d | %.0f | %.1f | %.1f | %.1f | %.0f | %.4f |\n", mesh_file,
           msh->nverts, env, shadows ? (info.convex ? "on (convex: none)" : "on") : "off",
           info.lights, 1e3 * cold, 1e3 * shade[nw / 2], 1e3 * draw[nw / 2], 1e3 * warm[nw / 2],
           1e3 * tcpu, err_rel);
    fflush(stdout);
    scene_free(&sc);
}

int main(int argc, char **argv)
{
    /* the material ball (render_ball) under the studio's default light and
     * a captured one, then the built-in sphere and two meshes */
    const char *meshes[] = {"ball", "sphere", "bunny.ply", "cow.off"};
    const char *envs[2] = {"data:courtyard.exr", "data:sunset.exr"};
    int quick = 0, size = 512;
    struct stat st;
    char probe[1200];
    render *r;
    material mat;
    glint_err err;

    bench_env_data_default();
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick"))
            quick = 1;
        else if (!strcmp(argv[i], "--data") && i + 1 < argc)
            snprintf(DATA, sizeof DATA, "%s", argv[++i]);
        else if (!strcmp(argv[i], "--size") && i + 1 < argc)
            size = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_envrender [--quick] [--data DIR] [--size N]\n");
            return 2;
        }
    }
    if (size < 16 || size > 4096) {
        fprintf(stderr, "bench_envrender: --size must be in 16..4096\n");
        return 2;
    }
    env_set_resolver(data_resolver);
    snprintf(probe, sizeof probe, "%s/envmaps/courtyard.exr", DATA);
    if (stat(probe, &st)) {
        envs[0] = "sky";
        envs[1] = "studio";
    }
    if (render_open(8, 0, &r, &err)) {
        fprintf(stderr, "render_open: %s\n", err.msg);
        return 1;
    }
    make_material(&mat);
    printf("## srbf previews under an environment, %dx%d, 256 lights, J = 147 (all lobes "
           "non-zero)\n\n",
           size, size);
    printf("| mesh | vertices | environment | shadows | lights | cold ms | shade ms | draw ms | "
           "warm preview ms | CPU reference ms | rel RMS vs reference |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    row(r, &mat, "ball", "studio", 1, size, quick);
    for (int mi = 0; mi < 4; mi++)
        for (int ei = 0; ei < 2; ei++)
            for (int s = 1; s >= 0; s--) {
                if (mi <= 1 && s == 0)
                    continue; /* spheres are convex: the same row */
                row(r, &mat, meshes[mi], envs[ei], s, size, quick);
                if (quick)
                    break;
            }
    material_free(&mat);
    render_close(r);
    return 0;
}
