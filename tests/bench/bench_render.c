/* bench_render: frame times of the headless EGL renderer (core/glr).
 *
 *   bench_render [--frames N] [--quick]
 *
 * For the bunny (../shared/data/meshes/bunny.ply or $GLINT_DATA_DIR, when
 * present) and a ~100k-triangle sphere, at 256^2, 512^2 and 1024^2:
 *   preview  : glr_preview, one call = uniforms + draw + finish + readback
 *              into a float image (context creation, program compilation,
 *              mesh upload and the factor upload happen before timing);
 *   G-buffer : glr_gbuffer, draw + readback of three float targets + the
 *              per-pixel wi/wo on the CPU;
 *   CPU      : material_render (raster_view + material_shade), the
 *              reference the preview replaces, for scale.
 * Each figure is the median over N frames (default 30; CPU: 3).  Also the
 * time to open the context and the first preview after it.  Floor checked:
 * the bunny's 512^2 preview under 50 ms (exit status 1 if not). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "glr.h"
#include "material.h"
#include "method_hf3.h"
#include "mesh.h"
#include "scene.h"

#define NSIZES 3
#define FLOOR_MS 50.0

static const int sizes[NSIZES] = {256, 512, 1024};

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *t, int n)
{
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}

/* A synthetic Blinn-like material (frame time does not depend on values):
 * res 128, add mapping, a bright lobe in q. */
static int make_material(material *m, glint_err *err)
{
    hf_factors f;
    const int R = 128;

    memset(&f, 0, sizeof f);
    f.res = R;
    f.model = HF_MODEL_RADIANCE;
    hf_map_default(&f.map, HF_MAP_ADD);
    f.logf = malloc((size_t)9 * R * sizeof *f.logf);
    if (!f.logf)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int c = 0; c < 3; c++)
        f.a_used[c] = f.map.a;
    for (int k = 0; k < R; k++) {
        double u = (double)k / (R - 1);
        for (int c = 0; c < 3; c++) {
            f.logf[(0 * R + k) * 3 + c] = log(0.6 - 0.3 * u * u) - 0.1 * c;
            f.logf[(1 * R + k) * 3 + c] = log(0.2 + 2.0 * exp(-40.0 * u * u));
            f.logf[(2 * R + k) * 3 + c] = log(1.0 - 0.2 * u);
        }
    }
    if (hf3_material_init(m, &f, NULL, NULL))
        return -1;
    return 0;
}

/* ../shared/data/meshes/bunny.ply from $GLINT_DATA_DIR, the working
 * directory or the executable's place in a build tree. */
static int load_bunny(mesh *m, char *why, size_t whylen)
{
    const char *env = getenv("GLINT_DATA_DIR");
    char exe[2048], cand[6][2300];
    int nc = 0;
    ssize_t n;
    glint_err e;

    if (env && *env)
        snprintf(cand[nc++], sizeof cand[0], "%s/meshes/bunny.ply", env);
    snprintf(cand[nc++], sizeof cand[0], "../shared/data/meshes/bunny.ply");
    snprintf(cand[nc++], sizeof cand[0], "../../shared/data/meshes/bunny.ply");
    n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) {
        char *slash;
        exe[n] = '\0';
        /* <src>/<build>/tests/bench/bench_render -> <src>/../shared/data */
        for (int up = 0; up < 4 && (slash = strrchr(exe, '/')) != NULL; up++)
            *slash = '\0';
        snprintf(cand[nc++], sizeof cand[0], "%s/../shared/data/meshes/bunny.ply", exe);
    }
    for (int i = 0; i < nc; i++) {
        if (access(cand[i], R_OK) != 0)
            continue;
        if (mesh_load(cand[i], m, NULL, &e) == 0)
            return 0;
        snprintf(why, whylen, "%.1024s: %s", cand[i], e.msg);
        return -1;
    }
    snprintf(why, whylen, "bunny.ply not found (set GLINT_DATA_DIR)");
    return -1;
}

typedef struct row {
    const char *mesh;
    int ntris, size;
    double preview_ms, gbuf_ms, cpu_ms;
} row;

int main(int argc, char **argv)
{
    int frames = 30, quick = 0, nrows = 0, rc = 0, floor_checked = 0;
    glr *g = NULL;
    material mat;
    mesh meshes[2];
    const char *names[2] = {"bunny", "sphere"};
    int have[2] = {0, 0};
    row rows[2 * NSIZES];
    glint_err e;
    char why[2600];
    double t0, t_open, t_first = 0.0;
    scene_view v;
    double dir[3] = {0.55, -0.62, 0.56};

    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--frames") == 0 && i + 1 < argc)
            frames = atoi(argv[++i]);
        else if (strcmp(argv[i], "--quick") == 0)
            quick = 1;
        else {
            fprintf(stderr, "usage: %s [--frames N] [--quick]\n", argv[0]);
            return 2;
        }
    }
    if (frames < 1 || frames > 10000)
        frames = 30;
    if (quick)
        frames = frames > 10 ? 10 : frames;

    memset(meshes, 0, sizeof meshes);
    memset(&mat, 0, sizeof mat);
    t0 = now();
    if (glr_open(&g, &e)) {
        printf("skipped: %s\n", e.msg);
        return 77;
    }
    t_open = now() - t0;
    printf("renderer: %s\n", glr_describe(g));
    printf("context + programs: %.0f ms\n", 1e3 * t_open);

    if (make_material(&mat, &e)) {
        fprintf(stderr, "material: %s\n", e.msg);
        glr_close(g);
        return 1;
    }
    if (load_bunny(&meshes[0], why, sizeof why) == 0)
        have[0] = 1;
    else
        printf("bunny: skipped (%s)\n", why);
    /* latitude-longitude sphere: 2 nlon (nlat - 1) triangles */
    if (mesh_sphere(&meshes[1], 224, 224, &e) == 0)
        have[1] = 1;
    else
        fprintf(stderr, "sphere: %s\n", e.msg);

    scene_view_make(dir, 3.5, 1.1, 40.0, &v);
    for (int k = 0; k < 2; k++) {
        glr_mesh *gm = NULL;
        if (!have[k])
            continue;
        if (glr_mesh_upload(g, &meshes[k], &gm, &e)) {
            fprintf(stderr, "%s upload: %s\n", names[k], e.msg);
            rc = 1;
            continue;
        }
        for (int s = 0; s < NSIZES; s++) {
            int S = sizes[s], ncpu = quick ? 1 : 3;
            double *t = malloc((size_t)frames * sizeof *t), tc[3];
            row *r = &rows[nrows];
            img out;
            gbuf gb;

            if (!t) {
                rc = 1;
                break;
            }
            /* first frame at this size: target allocation, factor upload,
             * shader variants; reported once, never timed below */
            t0 = now();
            if (glr_preview(g, gm, &mat, &v, S, S, 0.0f, &out, &e)) {
                fprintf(stderr, "%s preview %d: %s\n", names[k], S, e.msg);
                free(t);
                rc = 1;
                continue;
            }
            if (nrows == 0)
                t_first = now() - t0;
            img_free(&out);
            for (int f = 0; f < frames; f++) {
                t0 = now();
                if (glr_preview(g, gm, &mat, &v, S, S, 0.0f, &out, &e)) {
                    fprintf(stderr, "%s preview %d: %s\n", names[k], S, e.msg);
                    rc = 1;
                    break;
                }
                t[f] = now() - t0;
                img_free(&out);
            }
            r->preview_ms = 1e3 * median(t, frames);
            if (glr_gbuffer(g, gm, &v, S, S, &gb, &e) == 0)
                gbuf_free(&gb);
            for (int f = 0; f < frames; f++) {
                t0 = now();
                if (glr_gbuffer(g, gm, &v, S, S, &gb, &e)) {
                    fprintf(stderr, "%s gbuffer %d: %s\n", names[k], S, e.msg);
                    rc = 1;
                    break;
                }
                t[f] = now() - t0;
                gbuf_free(&gb);
            }
            r->gbuf_ms = 1e3 * median(t, frames);
            for (int f = 0; f < ncpu; f++) {
                t0 = now();
                if (material_render(&mat, &meshes[k], &v, S, S, &out, NULL, &e)) {
                    fprintf(stderr, "%s cpu %d: %s\n", names[k], S, e.msg);
                    rc = 1;
                    break;
                }
                tc[f] = now() - t0;
                img_free(&out);
            }
            r->cpu_ms = 1e3 * median(tc, ncpu);
            r->mesh = names[k];
            r->ntris = meshes[k].ntris;
            r->size = S;
            printf("%-7s %7d tris %5d^2: preview %7.2f ms  G-buffer %7.2f ms  CPU reference "
                   "%8.1f ms\n",
                   r->mesh, r->ntris, S, r->preview_ms, r->gbuf_ms, r->cpu_ms);
            fflush(stdout);
            if (k == 0 && S == 512) {
                floor_checked = 1;
                if (!(r->preview_ms < FLOOR_MS)) {
                    printf("FAIL: bunny 512^2 preview %.2f ms, floor %.0f ms\n", r->preview_ms,
                           FLOOR_MS);
                    rc = 1;
                }
            }
            nrows++;
            free(t);
        }
        glr_mesh_free(g, gm);
    }

    printf("\nfirst preview after opening (shader variants, targets, factor upload): %.0f ms\n",
           1e3 * t_first);
    printf("\n| mesh | triangles | size | preview (ms) | G-buffer (ms) | CPU reference (ms) |\n");
    printf("|---|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < nrows; i++)
        printf("| %s | %d | %d^2 | %.2f | %.2f | %.1f |\n", rows[i].mesh, rows[i].ntris,
               rows[i].size, rows[i].preview_ms, rows[i].gbuf_ms, rows[i].cpu_ms);
    printf("\nmedian of %d frames (CPU: %d); preview = uniforms + draw + finish + readback "
           "into a float RGB image.\n",
           frames, quick ? 1 : 3);
    if (floor_checked)
        printf("floor: bunny 512^2 preview < %.0f ms: %s\n", FLOOR_MS, rc ? "FAIL" : "ok");
    else
        printf("floor: not checked (no bunny)\n");

    material_free(&mat);
    mesh_free(&meshes[0]);
    mesh_free(&meshes[1]);
    glr_close(g);
    return rc;
}
