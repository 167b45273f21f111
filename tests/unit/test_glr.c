/* Tests of the headless EGL renderer (core/glr): previews against the CPU
 * reference (material.c), size and argument checks, context reuse, calls
 * from other threads, shader export, and a contact sheet of the bunny
 * written for a person to look at.  G-buffers and base renders are in
 * test_glr_gbuffer.c.
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
#include "brdfx.h"
#include "glr.h"
#include "glr_fixture.h"
#include "glsl_parts.h"
#include "glr_shaders.h"
#include "method_hf3.h"
#include "material.h"
#include "paint.h"
#include "raster.h"
#include "scene.h"

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
        if (material_render(mat, m, &v[k], SIZE, SIZE, &ref, NULL, &e) ||
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
    hf_factors fac;

    ASSERT(mat && m);
    test_views(v);
    ASSERT_OK(glr_mesh_upload(g, m, &gm, &e));
    fac = *hf3_factors(mat); /* shallow: shares logf, never freed */
    alt = *mat;
    alt.data = &fac;
    for (int kind = 0; kind < 4; kind++) {
        img ref, out;
        double d;
        fac.map.kind = kind == 3 ? HF_MAP_ADD : (hf_map_kind)kind;
        fac.model = kind == 3 ? HF_MODEL_BRDF : HF_MODEL_RADIANCE;
        for (int c = 0; c < 3; c++)
            fac.a_used[c] = kind == 2 ? 1.5 : hf3_factors(mat)->a_used[c];
        ASSERT_OK(material_render(&alt, m, &v[1], 128, 128, &ref, NULL, &e));
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
#if defined(__SANITIZE_ADDRESS__)
    /* ASan's quarantine keeps every freed frame (1 MiB at 256^2) resident, so
     * RSS says nothing here; LeakSanitizer checks the same promise at exit. */
    printf("  (RSS bound not checked under AddressSanitizer: freed frames sit in its quarantine)\n");
#else
    ASSERT_LT(rss1 - rss0, 8 * 1024);
#endif
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

/* The BRDF Explorer export (brdfx_material): its shader section,
 * compiled as GLSL ES 3.00 and run by the renderer as a preview's fragment
 * stage (radiance = BRDF(L, V, N, X, Y) n.L I, X and Y any tangents),
 * against the CPU's render of the material, for every mapping and both
 * models. */
TEST(brdf_explorer_export_renders_as_the_material)
{
    glr *g = need_glr();
    material *mat = need_material();
    mesh *m = need_sphere();
    glr_mesh *gm = NULL;
    scene_view v[3];
    glint_err e;
    material alt;
    hf_factors fac;

    ASSERT(mat && m);
    test_views(v);
    ASSERT_OK(glr_mesh_upload(g, m, &gm, &e));
    fac = *hf3_factors(mat); /* shallow: shares logf, never freed */
    alt = *mat;
    alt.data = &fac;
    for (int kind = 0; kind < 4; kind++) {
        char *text = NULL, frag[200000];
        const char *a, *b;
        img ref, out;
        double d, mx = 0.0;
        fac.map.kind = kind == 3 ? HF_MAP_ADD : (hf_map_kind)kind;
        fac.model = kind == 3 ? HF_MODEL_BRDF : HF_MODEL_RADIANCE;
        for (int c = 0; c < 3; c++)
            fac.a_used[c] = kind == 2 ? 1.5 : hf3_factors(mat)->a_used[c];
        ASSERT_MSG(brdfx_material(&alt, &text, &e) == 0, "%s", e.msg);
        ASSERT(!strncmp(text, "analytic\n", 9));
        a = strstr(text, "::begin shader\n");
        b = strstr(text, "::end shader");
        ASSERT(a && b && b > a && strstr(text, "::begin parameters") < a);
        a += strlen("::begin shader\n");
        snprintf(frag, sizeof frag,
                 "#version 300 es\n" GLSL_PRECISION GLSL_STAGE_IO "%.*s\n"
                 "void main()\n"
                 "{\n"
                 "    vec3 n = normalize(v_nrm), l = normalize(u_light - v_pos),"
                 " e = normalize(u_eye - v_pos);\n"
                 "    vec3 x = normalize(abs(n.z) < 0.9 ? cross(vec3(0.0, 0.0, 1.0), n)"
                 " : cross(vec3(1.0, 0.0, 0.0), n));\n"
                 "    o_color = vec4(BRDF(l, e, n, x, cross(n, x)) * max(dot(n, l), 0.0) *"
                 " u_light_intensity, 1.0);\n"
                 "}\n",
                 (int)(b - a), a);
        ASSERT_OK(material_render(&alt, m, &v[1], 128, 128, &ref, NULL, &e));
        ASSERT_MSG(glr_render_fragment(g, gm, frag, &v[1], 128, 128, &out, &e) == 0, "%s", e.msg);
        d = mad(&ref, &out);
        for (size_t i = 0; i < (size_t)128 * 128 * 3; i++)
            mx = ref.px[i] > mx ? ref.px[i] : mx;
        printf("  .brdf, mapping %d%s: %zu bytes, mean |its BRDF() rendered - cpu| = %.2e "
               "(largest value %.3f)\n",
               kind, kind == 3 ? " (brdf model)" : "", strlen(text), d, mx);
        img_free(&ref);
        img_free(&out);
        free(text);
        ASSERT_LT(d, 1.0 / 255);
        ASSERT_LT(0.05, mx);
    }
    /* a broken fragment stage is refused with the compiler's words */
    {
        img out;
        ASSERT_EQ(glr_render_fragment(g, gm, "#version 300 es\nvoid main() { nonsense; }\n",
                                      &v[1], 16, 16, &out, &e),
                  GLINT_EFORMAT);
    }
    glr_mesh_free(g, gm);
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
    R = hf3_factors(mat)->res;
    snprintf(dir, sizeof dir, "/tmp/glint-glr-XXXXXX");
    ASSERT(mkdtemp(dir));
    ASSERT_MSG(glr_shader_export(mat, dir, &e) == 0, "%s", e.msg);
    snprintf(path, sizeof path, "%s/glint_material.vert", dir);
    ASSERT_OK(fsio_read_all(path, 1 << 20, &vert, &vl, &e));
    snprintf(path, sizeof path, "%s/glint_material.frag", dir);
    ASSERT_OK(fsio_read_all(path, 1 << 20, &frag, &fl, &e));
    /* the exported text is the preview's, and it builds in this context */
    ASSERT(strcmp(frag, hf3_glsl_frag) == 0);
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
                    hf3_factors(mat)->a_used[c], 0.0);
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
        ASSERT_NEAR(exr.px[i], hf3_factors(mat)->logf[i], 1e-6 * (1 + fabs(hf3_factors(mat)->logf[i])));
    img_free(&exr);
    snprintf(path, sizeof path, "%s/glint_factors_rgba16f.bin", dir);
    ASSERT_OK(fsio_read_all(path, 1 << 20, &bin, &bl, &e));
    ASSERT_EQ(bl, (size_t)R * 3 * 4 * 2);
    for (int t = 0; t < 3 * R; t++)
        for (int c = 0; c < 3; c++) {
            const unsigned char *b = (const unsigned char *)bin + 2 * (4 * t + c);
            float h = half_to_float((uint16_t)(b[0] | b[1] << 8));
            ASSERT_NEAR(h, hf3_factors(mat)->logf[3 * t + c], 1e-3 * (1 + fabs(hf3_factors(mat)->logf[3 * t + c])));
        }
    free(bin);
    /* the 16-bit PNG decodes, with shader.json's range, to the factors within
     * half a step of 65535 */
    {
        json_t *p16;
        img png;
        snprintf(path, sizeof path, "%s/shader.json", dir);
        root = json_load_file(path, 0, &je);
        ASSERT(root && (p16 = json_object_get(root, "texture_png16")));
        snprintf(path, sizeof path, "%s/%s", dir,
                 json_string_value(json_object_get(p16, "file")));
        ASSERT_MSG(img_read(path, &png, &e) == 0, "%s", e.msg);
        ASSERT(png.width == R && png.height == 3 && png.channels == 3);
        for (int i = 0; i < 9 * R; i++) {
            double lo = json_real_value(json_array_get(json_object_get(p16, "min"), i % 3));
            double hi = json_real_value(json_array_get(json_object_get(p16, "max"), i % 3));
            double v = lo + (hi - lo) * png.px[i];
            ASSERT_NEAR(v, hf3_factors(mat)->logf[i], (hi - lo) / 131070.0 * 1.01 + 1e-12);
        }
        img_free(&png);
        /* the desktop stages: the same text after the #version line */
        for (int k = 0; k < 2; k++) {
            const char *es = k ? hf3_glsl_frag : GLR_VERT_SRC;
            char *gl = NULL;
            size_t gll;
            snprintf(path, sizeof path, "%s/%s", dir,
                     json_string_value(json_object_get(json_object_get(root, "desktop"),
                                                       k ? "fragment" : "vertex")));
            ASSERT_OK(fsio_read_all(path, 1 << 20, &gl, &gll, &e));
            ASSERT(strncmp(gl, "#version 330 core\n", 18) == 0);
            ASSERT(strcmp(strchr(gl, '\n'), strchr(es, '\n')) == 0);
            free(gl);
        }
        json_decref(root);
    }
    /* no material: an error, not a crash */
    ASSERT_EQ(glr_shader_export(NULL, dir, &e), GLINT_EINVAL);
    /* passed: the export goes (kept above when a check failed) */
    snprintf(path, sizeof path, "rm -rf '%s'", dir);
    ASSERT_EQ(system(path), 0);
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
        snprintf(dir, sizeof dir, "%s/artifacts", glint_test_build_dir);
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
    TEST_ENTRY(preview_sphere),
    TEST_ENTRY(preview_bunny),
    TEST_ENTRY(preview_other_mappings),
    TEST_ENTRY(preview_4096),
    TEST_ENTRY(bad_sizes_and_meshes),
    TEST_ENTRY(egl_device_choice),
    TEST_ENTRY(repeated_previews_reuse_everything),
    TEST_ENTRY(calls_from_other_threads),
    TEST_ENTRY(shader_export),
    TEST_ENTRY(brdf_explorer_export_renders_as_the_material),
    TEST_ENTRY(contact_sheet_bunny),
    TEST_ENTRY(close_everything),
};
TEST_MAIN()
