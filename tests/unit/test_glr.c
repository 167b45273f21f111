/* Tests of the headless EGL renderer (core/glr): G-buffers, base renders and
 * previews against the CPU reference (raster.c, paint.c, material.c), size
 * and argument checks, context reuse, shader export, and a contact sheet of
 * the bunny written for a person to look at.
 *
 * Without any EGL (no driver at all) the program prints "skipped: <why>"
 * and exits 77, meson's skip code. */
#include <pthread.h>
#include <time.h>
#include <unistd.h>

#include <jansson.h>

#include "check.h"
#include "fit.h"
#include "fsio.h"
#include "glr.h"
#include "glr_shaders.h"
#include "material.h"
#include "paint.h"
#include "raster.h"
#include "scene.h"

#define SIZE 256

static glr *G;
static mesh sphere, bunny, blobs;
static int have_sphere, have_bunny = -1, have_blobs;
static material MAT;
static int have_mat;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#if defined(__SANITIZE_ADDRESS__)
/* AddressSanitizer with fast_unwind_on_malloc=0 (as ./setup.sh runs the
 * sanitizer build) deadlocks inside llvmpipe: LLVM's JIT registers
 * exception frames, libgcc's _Unwind_Find_FDE allocates while holding its
 * lock, and ASan's slow unwinder re-enters _Unwind_Find_FDE from malloc.
 * Re-run this program once with the fast unwinder (leak checking stays on). */
static void asan_fast_unwind_reexec(void)
{
    const char *opt = getenv("ASAN_OPTIONS");
    static char env[2048], cmd[8192];
    char *argv[64];
    size_t n = 0;
    int argc = 0;
    FILE *f;

    if (!opt || !strstr(opt, "fast_unwind_on_malloc=0") || getenv("GLINT_GLR_REEXEC"))
        return;
    f = fopen("/proc/self/cmdline", "rb");
    if (!f)
        return;
    n = fread(cmd, 1, sizeof cmd - 1, f);
    fclose(f);
    cmd[n] = '\0';
    for (size_t i = 0; i < n && argc < 63; i += strlen(cmd + i) + 1)
        argv[argc++] = cmd + i;
    argv[argc] = NULL;
    snprintf(env, sizeof env, "%s:fast_unwind_on_malloc=1", opt);
    setenv("ASAN_OPTIONS", env, 1);
    setenv("GLINT_GLR_REEXEC", "1", 1);
    printf("  (re-running with ASAN_OPTIONS=%s: llvmpipe's JIT deadlocks with the slow "
           "unwinder)\n",
           env);
    fflush(stdout);
    execv("/proc/self/exe", argv);
    /* exec failed: carry on (and probably hang, as before) */
}
#else
static void asan_fast_unwind_reexec(void) {}
#endif

/* The shared renderer; without EGL the whole program is skipped. */
static glr *need_glr(void)
{
    glint_err e;
    if (G)
        return G;
    asan_fast_unwind_reexec();
    if (glr_open(&G, &e)) {
        printf("skipped: %s\n", e.msg);
        fflush(stdout);
        exit(77);
    }
    printf("  renderer: %s\n", glr_describe(G));
    return G;
}

static mesh *need_sphere(void)
{
    if (!have_sphere && mesh_sphere_default(&sphere, NULL) == 0)
        have_sphere = 1;
    return have_sphere ? &sphere : NULL;
}

/* A non-convex scene: a big sphere with a small one in front of it and a
 * third one half buried in it (occlusion edges and creases). */
static mesh *need_blobs(void)
{
    static const double c[3][4] = {{0, 0, -0.2, 0.75}, {0.45, 0.35, 0.55, 0.3},
                                   {-0.5, -0.3, 0.3, 0.4}};
    mesh parts[3];
    int nv = 0, nt = 0;

    if (have_blobs)
        return &blobs;
    for (int k = 0; k < 3; k++)
        if (mesh_sphere(&parts[k], 48, 96, NULL))
            return NULL;
    for (int k = 0; k < 3; k++) {
        nv += parts[k].nverts;
        nt += parts[k].ntris;
    }
    blobs.nverts = nv;
    blobs.ntris = nt;
    blobs.pos = malloc((size_t)nv * 3 * sizeof(float));
    blobs.nrm = malloc((size_t)nv * 3 * sizeof(float));
    blobs.uv = malloc((size_t)nv * 2 * sizeof(float));
    blobs.tri = malloc((size_t)nt * 3 * sizeof(uint32_t));
    nv = nt = 0;
    for (int k = 0; k < 3; k++) {
        mesh *p = &parts[k];
        for (int i = 0; i < p->nverts; i++) {
            for (int d = 0; d < 3; d++) {
                blobs.pos[3 * (nv + i) + d] = (float)(c[k][d] + c[k][3] * p->pos[3 * i + d]);
                blobs.nrm[3 * (nv + i) + d] = p->nrm[3 * i + d];
            }
            blobs.uv[2 * (nv + i)] = p->uv[2 * i];
            blobs.uv[2 * (nv + i) + 1] = p->uv[2 * i + 1];
        }
        for (int t = 0; t < 3 * p->ntris; t++)
            blobs.tri[3 * nt + t] = p->tri[t] + (uint32_t)nv;
        nv += p->nverts;
        nt += p->ntris;
        mesh_free(p);
    }
    have_blobs = 1;
    return &blobs;
}

/* The bunny from the shared data, or NULL (message printed once). */
static mesh *need_bunny(void)
{
    const char *dir;
    char path[4200];
    glint_err e;

    if (have_bunny >= 0)
        return have_bunny ? &bunny : NULL;
    have_bunny = 0;
    dir = check_data_dir();
    if (!dir) {
        printf("  bunny: skipped (no test data directory: set GLINT_DATA_DIR)\n");
        return NULL;
    }
    if ((size_t)snprintf(path, sizeof path, "%s/meshes/bunny.ply", dir) >= sizeof path)
        return NULL;
    if (mesh_load(path, &bunny, NULL, &e)) {
        printf("  bunny: skipped (mesh_load %s: %s)\n", path, e.msg);
        return NULL;
    }
    have_bunny = 1;
    return &bunny;
}

/* A Blinn-Phong material fitted on the default sphere scene (res 64). */
static material *need_material(void)
{
    scene_params p;
    scene sc;
    gbuf *g = NULL;
    img imgs[12];
    fit_params fpar;
    fit_prep fp;
    brdf b;
    glint_err e;
    double scale;
    int ok = 0;

    if (have_mat)
        return &MAT;
    memset(&sc, 0, sizeof sc);
    memset(&fp, 0, sizeof fp);
    memset(imgs, 0, sizeof imgs);
    scene_params_default(&p);
    if (scene_create(&p, &sc, &e) || raster_scene(&sc, &g, &e) ||
        brdf_parse("blinn:kd=0.75/0.5/0.3,ks=0.25,e=40", &b, &e) ||
        paint_views(&b, g, sc.views, sc.nviews, 0.0, imgs, &scale, &e)) {
        fprintf(stderr, "  material setup: %s\n", e.msg);
        goto done;
    }
    fit_params_default(&fpar);
    fpar.res = 64;
    if (fit_prepare(&fp, &sc, g, NULL, &fpar, NULL, &e) || fit_run(&fp, imgs, NULL, &MAT, &e)) {
        fprintf(stderr, "  fit: %s\n", e.msg);
        goto done;
    }
    ok = 1;
done:
    fit_prep_free(&fp);
    for (int v = 0; v < 12; v++)
        img_free(&imgs[v]);
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
    have_mat = ok;
    return ok ? &MAT : NULL;
}

/* Views: two of the default scene's and one that is in no scene. */
static void test_views(scene_view v[3])
{
    double dirs[12][3], d[3] = {0.62, -0.45, 0.64};
    scene_icosahedron(dirs);
    scene_view_make(dirs[0], 3.5, 1.1, 20.0, &v[0]);
    scene_view_make(dirs[7], 3.5, 1.1, 55.0, &v[1]);
    scene_view_make(d, 3.2, 1.15, -35.0, &v[2]);
    v[2].light_intensity = 1.3;
}

/* ---- G-buffer cross-check ------------------------------------------------ */

typedef struct gb_cmp {
    long cpu_px, gl_px, mask_diff, mask_diff_bad, interior;
    long flips, flips_bad; /* interior pixels where a different surface won */
    double nrm_max, pos_max, wi_max, wo_max, uv_max;
} gb_cmp;

static int mask_at(const gbuf *g, int i, int j)
{
    if (i < 0 || j < 0 || i >= g->width || j >= g->height)
        return 0;
    return g->mask[(size_t)j * g->width + i];
}

static double vdiff(const float *a, const float *b, int n)
{
    double m = 0.0;
    for (int k = 0; k < n; k++) {
        double d = fabs((double)a[k] - b[k]);
        m = d > m ? d : m;
    }
    return m;
}

#define NSHIFT 8

/* The CPU G-buffers of view v with the image shifted by 1/256 pixel in 8
 * directions (the target moved sideways: a tiny rotation of the camera). */
static int shifted_cpu(const mesh *m, const scene_view *v, int W, int H, gbuf sh[NSHIFT])
{
    static const int d[NSHIFT][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1},
                                     {1, 1}, {1, -1}, {-1, 1}, {-1, -1}};
    double F[3], R[3], U[3], dist = 0.0, px;
    scene_view_frame(v, F, R, U);
    for (int c = 0; c < 3; c++)
        dist += (v->target[c] - v->eye[c]) * (v->target[c] - v->eye[c]);
    px = 2.0 * tan(v->half_fov) * sqrt(dist) / H; /* one pixel at the target */
    for (int k = 0; k < NSHIFT; k++) {
        scene_view w = *v;
        for (int c = 0; c < 3; c++)
            w.target[c] += px / 256.0 * (d[k][0] * R[c] + d[k][1] * U[c]);
        if (raster_view(m, &w, W, H, &sh[k], NULL)) {
            while (k-- > 0)
                gbuf_free(&sh[k]);
            return -1;
        }
    }
    return 0;
}

/* Compare a G-buffer from glr with raster_view's.  Masks may differ only on
 * the CPU silhouette.  On interior pixels (3x3 covered in both) every
 * channel must agree to 1e-3, except where the rasterizers picked
 * different surfaces: GPUs snap vertices to a sub-pixel grid (llvmpipe:
 * 1/256 pixel), so a pixel centre closer than that to an occluding edge
 * can land on either side.  Such a pixel counts as a flip, and is
 * accepted only if the CPU rasterizer itself returns the GPU's surface
 * when the image moves by 1/256 pixel. */
static void gb_compare(const mesh *m, const scene_view *v, const gbuf *cpu, const gbuf *gl,
                       gb_cmp *r)
{
    int W = cpu->width, H = cpu->height, have_sh = 0;
    gbuf sh[NSHIFT];
    memset(r, 0, sizeof *r);
    for (int j = 0; j < H; j++) {
        for (int i = 0; i < W; i++) {
            size_t p = (size_t)j * W + i;
            int mc = cpu->mask[p], mg = gl->mask[p], interior = 1, edge = 0;
            double dn, dp, di, dw, du;
            r->cpu_px += mc;
            r->gl_px += mg;
            for (int dj = -1; dj <= 1; dj++)
                for (int dx = -1; dx <= 1; dx++) {
                    interior &= mask_at(cpu, i + dx, j + dj) && mask_at(gl, i + dx, j + dj);
                    edge |= mask_at(cpu, i + dx, j + dj) != mc;
                }
            if (mc != mg) {
                r->mask_diff++;
                if (!edge)
                    r->mask_diff_bad++;
            }
            if (!interior)
                continue;
            r->interior++;
            dn = vdiff(cpu->nrm + 3 * p, gl->nrm + 3 * p, 3);
            dp = vdiff(cpu->pos + 3 * p, gl->pos + 3 * p, 3);
            if (dn >= 1e-3 || dp >= 1e-3) {
                int explained = 0;
                r->flips++;
                if (!have_sh)
                    have_sh = shifted_cpu(m, v, W, H, sh) == 0 ? 1 : -1;
                for (int k = 0; k < NSHIFT && have_sh > 0 && !explained; k++)
                    explained = sh[k].mask[p] &&
                                vdiff(sh[k].nrm + 3 * p, gl->nrm + 3 * p, 3) < 1e-3 &&
                                vdiff(sh[k].pos + 3 * p, gl->pos + 3 * p, 3) < 1e-3;
                if (!explained)
                    r->flips_bad++;
                printf("    flip at pixel (row %d, col %d): |dN| %.3f |dP| %.3f, %s\n", j, i,
                       dn, dp,
                       explained ? "the CPU gives the GPU's surface with the image moved by "
                                   "1/256 pixel"
                                 : "NOT explained by a 1/256 pixel shift");
                continue;
            }
            di = vdiff(cpu->wi + 3 * p, gl->wi + 3 * p, 3);
            dw = vdiff(cpu->wo + 3 * p, gl->wo + 3 * p, 3);
            du = vdiff(cpu->uv + 2 * p, gl->uv + 2 * p, 2);
            r->nrm_max = dn > r->nrm_max ? dn : r->nrm_max;
            r->pos_max = dp > r->pos_max ? dp : r->pos_max;
            r->wi_max = di > r->wi_max ? di : r->wi_max;
            r->wo_max = dw > r->wo_max ? dw : r->wo_max;
            r->uv_max = du > r->uv_max ? du : r->uv_max;
        }
    }
    if (have_sh > 0)
        for (int k = 0; k < NSHIFT; k++)
            gbuf_free(&sh[k]);
}

/* Compare glr_gbuffer with raster_view for views v[0..n-1]. */
static void gbuffer_check(const char *name, const mesh *m, const scene_view *v, int n, int W,
                          int H, int *failed)
{
    glr *g = need_glr();
    glr_mesh *gm = NULL;
    glint_err e;

    *failed = 1;
    if (glr_mesh_upload(g, m, &gm, &e)) {
        fprintf(stderr, "  upload %s: %s\n", name, e.msg);
        return;
    }
    for (int k = 0; k < n; k++) {
        gbuf cpu, gl;
        gb_cmp r;
        double t0 = now(), t1, t2;
        if (raster_view(m, &v[k], W, H, &cpu, &e)) {
            fprintf(stderr, "  raster %s: %s\n", name, e.msg);
            glr_mesh_free(g, gm);
            return;
        }
        t1 = now();
        if (glr_gbuffer(g, gm, &v[k], W, H, &gl, &e)) {
            fprintf(stderr, "  glr_gbuffer %s: %s\n", name, e.msg);
            gbuf_free(&cpu);
            glr_mesh_free(g, gm);
            return;
        }
        t2 = now();
        gb_compare(m, &v[k], &cpu, &gl, &r);
        printf("  %s view %d %dx%d: covered cpu %ld gl %ld, mask diffs %ld (%ld off the "
               "silhouette); %ld interior pixels, %ld surface flips (%ld unexplained), on "
               "the rest max |dN| %.2e |dP| %.2e |dwi| %.2e |dwo| %.2e |duv| %.2e "
               "(cpu %.0f ms, gl %.0f ms)\n",
               name, k, W, H, r.cpu_px, r.gl_px, r.mask_diff, r.mask_diff_bad, r.interior,
               r.flips, r.flips_bad, r.nrm_max, r.pos_max, r.wi_max, r.wo_max, r.uv_max,
               1e3 * (t1 - t0), 1e3 * (t2 - t1));
        gbuf_free(&cpu);
        gbuf_free(&gl);
        if (r.mask_diff_bad || r.flips_bad || r.flips > r.interior / 1000 ||
            !(r.nrm_max < 1e-3) || !(r.pos_max < 1e-3) || !(r.wi_max < 1e-3) ||
            !(r.wo_max < 1e-3) || r.interior < r.cpu_px / 2) {
            glr_mesh_free(g, gm);
            return;
        }
    }
    glr_mesh_free(g, gm);
    *failed = 0;
}

TEST(gbuffer_sphere)
{
    scene_view v[3];
    int failed;
    mesh *m = need_sphere();
    ASSERT(m);
    test_views(v);
    gbuffer_check("sphere", m, v, 3, SIZE, SIZE, &failed);
    ASSERT(!failed);
    /* not square */
    gbuffer_check("sphere", m, v, 1, 320, 200, &failed);
    ASSERT(!failed);
}

TEST(gbuffer_culling)
{
    /* Closed meshes seen from outside draw front faces only; from inside
     * (the eye in the sphere) both, and either way the result is raster.c's. */
    glr *g = need_glr();
    mesh *m = need_sphere();
    glr_mesh *gm = NULL;
    scene_view v[3], in;
    glr_stats s0, s1, s2;
    gbuf gb;
    glint_err e;
    int failed;

    ASSERT(m);
    test_views(v);
    ASSERT_OK(glr_mesh_upload(g, m, &gm, &e));
    glr_get_stats(g, &s0);
    ASSERT_OK(glr_gbuffer(g, gm, &v[0], 64, 64, &gb, &e));
    gbuf_free(&gb);
    glr_get_stats(g, &s1);
    ASSERT_EQ(s1.culled_frames, s0.culled_frames + 1);
    memset(&in, 0, sizeof in);
    in.eye[0] = 0.2;
    in.eye[1] = -0.1;
    in.eye[2] = 0.3;
    in.target[0] = -0.4;
    in.target[1] = 0.5;
    in.target[2] = -0.2;
    in.half_fov = 0.6;
    in.light[2] = 0.5;
    in.light_intensity = 1.0;
    ASSERT_OK(glr_gbuffer(g, gm, &in, 64, 64, &gb, &e));
    gbuf_free(&gb);
    glr_get_stats(g, &s2);
    ASSERT_EQ(s2.culled_frames, s1.culled_frames);
    glr_mesh_free(g, gm);
    gbuffer_check("inside the sphere", m, &in, 1, SIZE, SIZE, &failed);
    ASSERT(!failed);
}

TEST(gbuffer_nonconvex)
{
    scene_view v[3];
    int failed;
    mesh *m = need_blobs();
    ASSERT(m);
    test_views(v);
    gbuffer_check("blobs", m, v, 3, SIZE, SIZE, &failed);
    ASSERT(!failed);
}

TEST(gbuffer_bunny)
{
    scene_view v[3];
    int failed;
    mesh *m = need_bunny();
    if (!m)
        return;
    test_views(v);
    gbuffer_check("bunny", m, v, 3, SIZE, SIZE, &failed);
    ASSERT(!failed);
}

/* ---- base render ----------------------------------------------------------- */

static double mad(const img *a, const img *b)
{
    double s = 0.0;
    size_t n = (size_t)a->width * a->height * 3;
    for (size_t i = 0; i < n; i++)
        s += fabs((double)a->px[i] - b->px[i]);
    return s / (double)n;
}

TEST(base_render_matches_paint)
{
    static const char *const specs[] = {"lambert", "phong", "blinn:e=60", "ct", "ct0.5",
                                        "ward"};
    glr *g = need_glr();
    mesh *m = need_blobs();
    glr_mesh *gm = NULL;
    scene_view v[3];
    gbuf cpu;
    glint_err e;

    ASSERT(m);
    test_views(v);
    ASSERT_OK(glr_mesh_upload(g, m, &gm, &e));
    ASSERT_OK(raster_view(m, &v[2], SIZE, SIZE, &cpu, &e));
    for (size_t s = 0; s < sizeof specs / sizeof specs[0]; s++) {
        brdf b;
        img ref, out;
        double scale, d;
        memset(&ref, 0, sizeof ref);
        ASSERT_OK(brdf_parse(specs[s], &b, &e));
        ASSERT_OK(paint_views(&b, &cpu, &v[2], 1, 0.0, &ref, &scale, &e));
        ASSERT_MSG(glr_base_render(g, gm, &v[2], SIZE, SIZE, &b, scale, 0.0f, &out, &e) == 0,
                   "%s", e.msg);
        d = mad(&ref, &out);
        printf("  base render %-10s: mean |gl - paint| = %.2e (scale %.3g)\n", specs[s], d,
               scale);
        img_free(&ref);
        img_free(&out);
        ASSERT_LT(d, 1e-3);
    }
    /* background where nothing is drawn */
    {
        brdf b;
        img out;
        ASSERT_OK(brdf_parse("lambert", &b, &e));
        ASSERT_OK(glr_base_render(g, gm, &v[2], 64, 64, &b, 1.0, 0.25f, &out, &e));
        ASSERT_NEAR(out.px[0], 0.25, 0.0);
        img_free(&out);
    }
    gbuf_free(&cpu);
    glr_mesh_free(g, gm);
}

/* ---- preview ----------------------------------------------------------------- */

static void preview_check(const char *name, const mesh *m, int *failed)
{
    glr *g = need_glr();
    material *mat = need_material();
    glr_mesh *gm = NULL;
    scene_view v[3];
    glint_err e;

    *failed = 1;
    if (!mat)
        return;
    test_views(v);
    if (glr_mesh_upload(g, m, &gm, &e)) {
        fprintf(stderr, "  %s\n", e.msg);
        return;
    }
    for (int k = 0; k < 3; k++) {
        img ref, out;
        double d, mx = 0.0;
        if (material_render(mat, m, &v[k], SIZE, SIZE, &ref, &e) ||
            glr_preview(g, gm, mat, &v[k], SIZE, SIZE, 0.0f, &out, &e)) {
            fprintf(stderr, "  %s\n", e.msg);
            glr_mesh_free(g, gm);
            return;
        }
        d = mad(&ref, &out);
        for (size_t i = 0; i < (size_t)SIZE * SIZE * 3; i++)
            mx = ref.px[i] > mx ? ref.px[i] : mx;
        printf("  preview %s view %d%s: mean |gl - cpu| = %.2e (1/255 = %.2e), max value "
               "%.3f\n",
               name, k, k == 2 ? " (novel)" : "", d, 1.0 / 255, mx);
        img_free(&ref);
        img_free(&out);
        if (!(d < 1.0 / 255) || !(mx > 0.1)) {
            glr_mesh_free(g, gm);
            return;
        }
    }
    glr_mesh_free(g, gm);
    *failed = 0;
}

TEST(preview_sphere)
{
    int failed;
    mesh *m = need_sphere();
    ASSERT(m);
    ASSERT(need_material());
    preview_check("sphere", m, &failed);
    ASSERT(!failed);
}

TEST(preview_bunny)
{
    int failed;
    mesh *m = need_bunny();
    if (!m)
        return;
    ASSERT(need_material());
    preview_check("bunny", m, &failed);
    ASSERT(!failed);
}

TEST(preview_other_mappings)
{
    /* The same factors read through log, sub and the brdf model: the
     * shader's inverse mappings against hf_factors_eval. */
    glr *g = need_glr();
    material *mat = need_material();
    mesh *m = need_sphere();
    glr_mesh *gm = NULL;
    scene_view v[3];
    glint_err e;
    material alt;

    ASSERT(mat && m);
    test_views(v);
    ASSERT_OK(glr_mesh_upload(g, m, &gm, &e));
    alt = *mat; /* shallow: shares logf, never freed */
    for (int kind = 0; kind < 4; kind++) {
        img ref, out;
        double d;
        alt.fac.map.kind = kind == 3 ? HF_MAP_ADD : (hf_map_kind)kind;
        alt.fac.model = kind == 3 ? HF_MODEL_BRDF : HF_MODEL_RADIANCE;
        for (int c = 0; c < 3; c++)
            alt.fac.a_used[c] = kind == 2 ? 1.5 : mat->fac.a_used[c];
        ASSERT_OK(material_render(&alt, m, &v[1], 128, 128, &ref, &e));
        ASSERT_OK(glr_preview(g, gm, &alt, &v[1], 128, 128, 0.0f, &out, &e));
        d = mad(&ref, &out);
        printf("  mapping %d%s: mean |gl - cpu| = %.2e\n", kind, kind == 3 ? " (brdf)" : "", d);
        img_free(&ref);
        img_free(&out);
        ASSERT_LT(d, 1.0 / 255);
    }
    glr_mesh_free(g, gm);
}

TEST(preview_4096)
{
    glr *g = need_glr();
    material *mat = need_material();
    mesh *m = need_sphere();
    glr_mesh *gm = NULL;
    scene_view v[3];
    img big, small;
    glint_err e;
    double t0, t1, d = 0.0;
    long cov = 0;
    const int F = 4096 / SIZE;

    ASSERT(mat && m);
    test_views(v);
    ASSERT_OK(glr_mesh_upload(g, m, &gm, &e));
    ASSERT_OK(glr_preview(g, gm, mat, &v[2], SIZE, SIZE, 0.0f, &small, &e));
    t0 = now();
    ASSERT_MSG(glr_preview(g, gm, mat, &v[2], 4096, 4096, 0.0f, &big, &e) == 0, "%s", e.msg);
    t1 = now();
    ASSERT_EQ(big.width, 4096);
    ASSERT_EQ(big.height, 4096);
    ASSERT_OK(img_check_finite(&big, &e));
    /* Box-filtered down by 16 it is the 256 preview, up to silhouettes. */
    for (int j = 0; j < SIZE; j++)
        for (int i = 0; i < SIZE; i++)
            for (int c = 0; c < 3; c++) {
                double s = 0.0;
                for (int y = 0; y < F; y++)
                    for (int x = 0; x < F; x++)
                        s += big.px[(((size_t)(j * F + y)) * 4096 + (size_t)(i * F + x)) * 3 + c];
                d += fabs(s / (F * F) - small.px[((size_t)j * SIZE + i) * 3 + c]);
                cov += c == 0 && small.px[((size_t)j * SIZE + i) * 3] > 0.0f;
            }
    d /= (double)SIZE * SIZE * 3;
    printf("  4096^2 preview in %.0f ms; box-filtered to 256^2 it differs from the 256^2 "
           "preview by %.2e on average (%ld lit pixels)\n",
           1e3 * (t1 - t0), d, cov);
    ASSERT_LT(d, 5e-3);
    ASSERT(cov > 1000);
    img_free(&big);
    img_free(&small);
    glr_mesh_free(g, gm);
}

/* ---- argument checks --------------------------------------------------------- */

TEST(bad_sizes_and_meshes)
{
    glr *g = need_glr();
    material *mat = need_material();
    mesh *m = need_sphere(), bad;
    glr_mesh *gm = NULL, *gm2 = NULL;
    scene_view v[3], vb;
    img out;
    gbuf gb;
    glint_err e;
    brdf b;
    glr *g2 = NULL;

    ASSERT(mat && m);
    test_views(v);
    ASSERT_OK(brdf_parse("lambert", &b, &e));
    ASSERT_OK(glr_mesh_upload(g, m, &gm, &e));
    ASSERT_EQ(glr_preview(g, gm, mat, &v[0], 0, 0, 0.0f, &out, &e), GLINT_ERANGE);
    ASSERT_EQ(glr_preview(g, gm, mat, &v[0], 5000, 5000, 0.0f, &out, &e), GLINT_ERANGE);
    ASSERT_EQ(glr_preview(g, gm, mat, &v[0], 256, 5000, 0.0f, &out, &e), GLINT_ERANGE);
    ASSERT_EQ(glr_preview(g, gm, mat, &v[0], -3, 256, 0.0f, &out, &e), GLINT_ERANGE);
    ASSERT_EQ(glr_gbuffer(g, gm, &v[0], 0, 16, &gb, &e), GLINT_ERANGE);
    ASSERT_EQ(glr_base_render(g, gm, &v[0], 5000, 16, &b, 1.0, 0.0f, &out, &e), GLINT_ERANGE);
    printf("  size 5000: %s\n", e.msg);
    /* NULL and invalid meshes */
    ASSERT_EQ(glr_preview(g, NULL, mat, &v[0], 64, 64, 0.0f, &out, &e), GLINT_EINVAL);
    ASSERT_EQ(glr_gbuffer(g, NULL, &v[0], 64, 64, &gb, &e), GLINT_EINVAL);
    ASSERT_EQ(glr_mesh_upload(g, NULL, &gm2, &e), GLINT_EINVAL);
    ASSERT(gm2 == NULL);
    bad = *m;
    bad.tri = malloc((size_t)3 * m->ntris * sizeof *bad.tri);
    ASSERT(bad.tri);
    memcpy(bad.tri, m->tri, (size_t)3 * m->ntris * sizeof *bad.tri);
    bad.tri[7] = (uint32_t)m->nverts + 5;
    ASSERT_EQ(glr_mesh_upload(g, &bad, &gm2, &e), GLINT_EFORMAT);
    printf("  bad index: %s\n", e.msg);
    free(bad.tri);
    bad = *m;
    bad.nverts = 0;
    ASSERT_EQ(glr_mesh_upload(g, &bad, &gm2, &e), GLINT_EFORMAT);
    /* degenerate views */
    vb = v[0];
    memcpy(vb.target, vb.eye, sizeof vb.eye);
    ASSERT_EQ(glr_preview(g, gm, mat, &vb, 64, 64, 0.0f, &out, &e), GLINT_EINVAL);
    vb = v[0];
    vb.half_fov = 2.0;
    ASSERT_EQ(glr_preview(g, gm, mat, &vb, 64, 64, 0.0f, &out, &e), GLINT_EINVAL);
    vb = v[0];
    vb.eye[1] = NAN;
    ASSERT_EQ(glr_gbuffer(g, gm, &vb, 64, 64, &gb, &e), GLINT_EINVAL);
    ASSERT_EQ(glr_preview(g, gm, NULL, &v[0], 64, 64, 0.0f, &out, &e), GLINT_EINVAL);
    ASSERT_EQ(glr_preview(NULL, gm, mat, &v[0], 64, 64, 0.0f, &out, &e), GLINT_EINVAL);
    /* a mesh of another renderer (a second context in the same process) */
    ASSERT_MSG(glr_open(&g2, &e) == 0, "%s", e.msg);
    ASSERT_OK(glr_mesh_upload(g2, m, &gm2, &e));
    ASSERT_EQ(glr_preview(g, gm2, mat, &v[0], 64, 64, 0.0f, &out, &e), GLINT_EINVAL);
    printf("  foreign mesh: %s\n", e.msg);
    ASSERT_OK(glr_preview(g2, gm2, mat, &v[0], 64, 64, 0.0f, &out, &e));
    img_free(&out);
    glr_mesh_free(g2, gm2);
    glr_close(g2);
    /* the first renderer still works after the second closed */
    ASSERT_MSG(glr_preview(g, gm, mat, &v[0], 64, 64, 0.0f, &out, &e) == 0, "%s", e.msg);
    img_free(&out);
    glr_mesh_free(g, gm);
    glr_mesh_free(g, NULL);
    glr_close(NULL);
}

TEST(egl_device_choice)
{
    glr *g2 = NULL;
    glint_err e;
    char *old = getenv("GLINT_EGL_DEVICE") ? strdup(getenv("GLINT_EGL_DEVICE")) : NULL;

    need_glr();
    setenv("GLINT_EGL_DEVICE", "x1", 1);
    ASSERT_EQ(glr_open(&g2, &e), GLINT_EINVAL);
    setenv("GLINT_EGL_DEVICE", "15", 1);
    ASSERT_EQ(glr_open(&g2, &e), GLINT_EUNSUPPORTED);
    printf("  device 15: %s\n", e.msg);
    setenv("GLINT_EGL_DEVICE", "0", 1);
    if (glr_open(&g2, &e) == 0) {
        printf("  device 0: %s\n", glr_describe(g2));
        glr_close(g2);
    } else {
        printf("  device 0: %s\n", e.msg);
    }
    if (old) {
        setenv("GLINT_EGL_DEVICE", old, 1);
        free(old);
    } else {
        unsetenv("GLINT_EGL_DEVICE");
    }
}

/* ---- context reuse ----------------------------------------------------------- */

static long rss_kib(void)
{
    long pages = 0, rss = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    if (!f)
        return -1;
    if (fscanf(f, "%ld %ld", &pages, &rss) != 2)
        rss = -1;
    fclose(f);
    return rss < 0 ? -1 : rss * (sysconf(_SC_PAGESIZE) / 1024);
}

TEST(repeated_previews_reuse_everything)
{
    glr *g = need_glr();
    material *mat = need_material();
    mesh *m = need_sphere();
    glr_mesh *gm = NULL;
    scene_view v[3];
    glr_stats s0, s1, s2;
    glint_err e;
    img out;
    double t[20], t0;
    long rss0, rss1;

    ASSERT(mat && m);
    test_views(v);
    ASSERT_OK(glr_mesh_upload(g, m, &gm, &e));
    /* warm up at this size */
    ASSERT_OK(glr_preview(g, gm, mat, &v[0], SIZE, SIZE, 0.0f, &out, &e));
    img_free(&out);
    glr_get_stats(g, &s0);
    rss0 = rss_kib();
    for (int k = 0; k < 20; k++) {
        t0 = now();
        ASSERT_OK(glr_preview(g, gm, mat, &v[k % 3], SIZE, SIZE, 0.0f, &out, &e));
        t[k] = now() - t0;
        img_free(&out);
    }
    rss1 = rss_kib();
    glr_get_stats(g, &s1);
    {
        double tot = 0.0, mx = 0.0;
        for (int k = 0; k < 20; k++) {
            tot += t[k];
            mx = t[k] > mx ? t[k] : mx;
        }
        printf("  20 previews at %d^2: mean %.1f ms, max %.1f ms; GL objects %ld -> %ld, "
               "target allocations %ld -> %ld, factor uploads %ld -> %ld, RSS %+ld KiB\n",
               SIZE, 1e3 * tot / 20, 1e3 * mx, s0.gl_objects, s1.gl_objects,
               s0.target_allocs, s1.target_allocs, s0.factor_uploads, s1.factor_uploads,
               rss1 - rss0);
    }
    ASSERT_EQ(s1.gl_objects, s0.gl_objects);
    ASSERT_EQ(s1.target_allocs, s0.target_allocs);
    ASSERT_EQ(s1.factor_uploads, s0.factor_uploads);
    ASSERT_EQ(s1.frames, s0.frames + 20);
    ASSERT_LT(rss1 - rss0, 8 * 1024);
    /* uploading and freeing meshes leaves no GL object behind */
    glr_mesh_free(g, gm);
    glr_get_stats(g, &s2);
    ASSERT_EQ(s2.gl_objects, s1.gl_objects - 5);
    ASSERT_EQ(s2.meshes, s1.meshes - 1);
}

/* ---- calls from several threads ----------------------------------------------- */

typedef struct thread_job {
    glr *g;
    glr_mesh *gm;
    const material *mat;
    scene_view v;
    int rc;
    float centre;
    char msg[GLINT_ERR_MSG_MAX];
} thread_job;

static void *thread_preview(void *arg)
{
    thread_job *j = arg;
    glint_err e;
    img out;
    j->rc = glr_preview(j->g, j->gm, j->mat, &j->v, 64, 64, 0.0f, &out, &e);
    if (j->rc) {
        snprintf(j->msg, sizeof j->msg, "%s", e.msg);
        return NULL;
    }
    j->centre = out.px[(32 * 64 + 32) * 3];
    img_free(&out);
    return NULL;
}

TEST(calls_from_other_threads)
{
    /* A daemon serializes calls with a lock but makes them from whichever
     * worker thread holds it: each call must find the context free. */
    glr *g = need_glr();
    material *mat = need_material();
    mesh *m = need_sphere();
    scene_view v[3];
    thread_job j;
    glint_err e;
    img ref;

    ASSERT(mat && m);
    test_views(v);
    memset(&j, 0, sizeof j);
    j.g = g;
    j.mat = mat;
    j.v = v[0];
    ASSERT_OK(glr_mesh_upload(g, m, &j.gm, &e));
    ASSERT_OK(glr_preview(g, j.gm, mat, &v[0], 64, 64, 0.0f, &ref, &e));
    for (int k = 0; k < 3; k++) {
        pthread_t t;
        j.rc = -100;
        ASSERT_EQ(pthread_create(&t, NULL, thread_preview, &j), 0);
        ASSERT_EQ(pthread_join(t, NULL), 0);
        ASSERT_MSG(j.rc == 0, "preview from thread %d: %s", k, j.msg);
        ASSERT_NEAR(j.centre, ref.px[(32 * 64 + 32) * 3], 0.0);
    }
    img_free(&ref);
    glr_mesh_free(g, j.gm);
}

/* ---- shader export ------------------------------------------------------------ */

static float half_to_float(uint16_t h)
{
    int s = h >> 15, e = (h >> 10) & 31, f = h & 1023;
    double v = e == 0 ? ldexp(f, -24) : e == 31 ? INFINITY : ldexp(1024 + f, e - 25);
    return (float)(s ? -v : v);
}

TEST(shader_export)
{
    glr *g = need_glr();
    material *mat = need_material();
    char dir[64], path[256];
    char *vert = NULL, *frag = NULL, *bin = NULL;
    size_t vl, fl, bl;
    json_t *root, *tex, *map;
    json_error_t je;
    glint_err e;
    img exr;
    int R;

    ASSERT(mat);
    R = mat->fac.res;
    snprintf(dir, sizeof dir, "/tmp/glint-glr-XXXXXX");
    ASSERT(mkdtemp(dir));
    ASSERT_MSG(glr_shader_export(mat, dir, &e) == 0, "%s", e.msg);
    snprintf(path, sizeof path, "%s/glint_material.vert", dir);
    ASSERT_OK(fsio_read_all(path, 1 << 20, &vert, &vl, &e));
    snprintf(path, sizeof path, "%s/glint_material.frag", dir);
    ASSERT_OK(fsio_read_all(path, 1 << 20, &frag, &fl, &e));
    /* the exported text is the preview's, and it builds in this context */
    ASSERT(strcmp(frag, GLR_PREVIEW_FRAG_SRC) == 0);
    ASSERT(strcmp(vert, GLR_VERT_SRC) == 0);
    ASSERT_MSG(glr_program_check(g, vert, frag, &e) == 0, "%s", e.msg);
    /* a broken shader is reported with the compiler's log */
    frag[strlen(frag) - 3] = '@';
    ASSERT_EQ(glr_program_check(g, vert, frag, &e), GLINT_EFORMAT);
    printf("  broken shader: %.120s\n", e.msg);
    free(vert);
    free(frag);

    snprintf(path, sizeof path, "%s/shader.json", dir);
    root = json_load_file(path, 0, &je);
    ASSERT_MSG(root, "shader.json: %s", je.text);
    ASSERT_EQ(json_integer_value(json_object_get(root, "res")), R);
    map = json_object_get(root, "mapping");
    ASSERT(map && strcmp(json_string_value(json_object_get(map, "kind")), "add") == 0);
    ASSERT_EQ(json_integer_value(json_object_get(map, "u_map_kind")), 1);
    for (int c = 0; c < 3; c++)
        ASSERT_NEAR(json_real_value(json_array_get(json_object_get(map, "a_used"), (size_t)c)),
                    mat->fac.a_used[c], 0.0);
    tex = json_object_get(root, "texture");
    ASSERT(tex);
    ASSERT_EQ(json_integer_value(json_object_get(tex, "width")), R);
    ASSERT_EQ(json_integer_value(json_object_get(tex, "height")), 3);
    ASSERT_EQ(json_array_size(json_object_get(root, "attributes")), 3);
    ASSERT(json_array_size(json_object_get(root, "uniforms")) >= 10);
    json_decref(root);

    /* factor files hold the log-factors */
    snprintf(path, sizeof path, "%s/glint_factors.exr", dir);
    ASSERT_MSG(img_read(path, &exr, &e) == 0, "%s", e.msg);
    ASSERT_EQ(exr.width, R);
    ASSERT_EQ(exr.height, 3);
    for (int i = 0; i < 9 * R; i++)
        ASSERT_NEAR(exr.px[i], mat->fac.logf[i], 1e-6 * (1 + fabs(mat->fac.logf[i])));
    img_free(&exr);
    snprintf(path, sizeof path, "%s/glint_factors_rgba16f.bin", dir);
    ASSERT_OK(fsio_read_all(path, 1 << 20, &bin, &bl, &e));
    ASSERT_EQ(bl, (size_t)R * 3 * 4 * 2);
    for (int t = 0; t < 3 * R; t++)
        for (int c = 0; c < 3; c++) {
            const unsigned char *b = (const unsigned char *)bin + 2 * (4 * t + c);
            float h = half_to_float((uint16_t)(b[0] | b[1] << 8));
            ASSERT_NEAR(h, mat->fac.logf[3 * t + c], 1e-3 * (1 + fabs(mat->fac.logf[3 * t + c])));
        }
    free(bin);
    /* no material: an error, not a crash */
    ASSERT_EQ(glr_shader_export(NULL, dir, &e), GLINT_EINVAL);
}

/* ---- contact sheet ------------------------------------------------------------ */

TEST(contact_sheet_bunny)
{
    glr *g = need_glr();
    material *mat = need_material();
    mesh *m = need_bunny();
    glr_mesh *gm = NULL;
    double dirs[12][3];
    const char *env = getenv("GLINT_ARTIFACTS_DIR");
    char dir[4096], path[4200];
    img sheet, cell;
    glint_err e;
    const int C = 256;

    if (!m)
        return;
    ASSERT(mat);
    if (env && *env)
        snprintf(dir, sizeof dir, "%s", env);
    else
        snprintf(dir, sizeof dir, "%s/artifacts", GLINT_BUILD_DIR);
    ASSERT_MSG(fsio_mkdirs(dir, &e) == 0, "%s", e.msg);
    ASSERT_OK(glr_mesh_upload(g, m, &gm, &e));
    ASSERT_OK(img_alloc(&sheet, 4 * C, 3 * C, 3, &e));
    scene_icosahedron(dirs);
    for (int k = 0; k < 12; k++) {
        scene_view v;
        scene_view_make(dirs[k], 3.0, 1.05, 35.0, &v);
        ASSERT_MSG(glr_preview(g, gm, mat, &v, C, C, 0.03f, &cell, &e) == 0, "%s", e.msg);
        /* Linear radiance, encoded with the sRGB curve for viewing only. */
        for (int j = 0; j < C; j++) {
            float *dst = sheet.px + (((size_t)(k / 4) * C + j) * 4 * C + (size_t)(k % 4) * C) * 3;
            const float *src = cell.px + (size_t)j * C * 3;
            for (int i = 0; i < 3 * C; i++) {
                double x = src[i] < 0.0f ? 0.0 : src[i] > 1.0f ? 1.0 : src[i];
                dst[i] = (float)(x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1 / 2.4) - 0.055);
            }
        }
        img_free(&cell);
    }
    snprintf(path, sizeof path, "%s/contact_sheet_bunny.png", dir);
    ASSERT_MSG(img_write(path, &sheet, &e) == 0, "%s", e.msg);
    printf("  contact sheet: %s\n", path);
    img_free(&sheet);
    glr_mesh_free(g, gm);
}

TEST(close_everything)
{
    glr_stats s;
    need_glr();
    glr_get_stats(G, &s);
    ASSERT_EQ(s.meshes, 0);
    glr_close(G);
    G = NULL;
    if (have_mat)
        material_free(&MAT);
    mesh_free(&sphere);
    mesh_free(&bunny);
    mesh_free(&blobs);
    have_mat = have_sphere = have_blobs = 0;
    have_bunny = -1;
}

TEST_LIST{
    TEST_ENTRY(gbuffer_sphere),
    TEST_ENTRY(gbuffer_culling),
    TEST_ENTRY(gbuffer_nonconvex),
    TEST_ENTRY(gbuffer_bunny),
    TEST_ENTRY(base_render_matches_paint),
    TEST_ENTRY(preview_sphere),
    TEST_ENTRY(preview_bunny),
    TEST_ENTRY(preview_other_mappings),
    TEST_ENTRY(preview_4096),
    TEST_ENTRY(bad_sizes_and_meshes),
    TEST_ENTRY(egl_device_choice),
    TEST_ENTRY(repeated_previews_reuse_everything),
    TEST_ENTRY(calls_from_other_threads),
    TEST_ENTRY(shader_export),
    TEST_ENTRY(contact_sheet_bunny),
    TEST_ENTRY(close_everything),
};
TEST_MAIN()
