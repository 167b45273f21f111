/* Allocation failure along glint's core paths, as SQLite tests it: each
 * operation is run again and again with its Nth allocation failing (N = 1,
 * 2, ... up to the allocations it makes; every k-th N of a long operation),
 * each run in a child process.  Every run must end in the operation's error
 * or its success, never a crash, a hang or an error without an injected
 * failure.
 *
 * malloc, calloc and realloc are replaced in this program (forwarding to
 * glibc's own).  The allocations that fail are those glint's own code makes;
 * the libraries' never fail here, because they do not survive it: this
 * test found OpenImageIO 2.4 throwing std::bad_alloc through libpng's C
 * frames (std::terminate), assimp 5.2 freeing twice after a failure in its
 * post-processing, and jansson 2.14's parser crashing inside json_loadb.
 * glintd imports meshes in a child process (mesh_child.c), which such a
 * crash cannot take down, and its admission budget (admit.h) keeps the
 * work it takes on within memory.  A process the operation forks (the mesh
 * importer's child) runs without failures: its own failures reach the
 * parent as an error this test could not tell from a bug.
 *
 * Not built under the sanitizers, whose runtime owns malloc (meson.build).
 * An operation with more allocations than SWEEP_ALL is swept at every k-th
 * from an offset that changes from run to run (alloc_fail.h: the line each
 * sweep prints names the GLINT_ALLOC_FAIL_STRIDE and GLINT_ALLOC_FAIL_OFFSET
 * that replay it).  GLINT_ALLOC_FAIL_AT=N runs each operation once, in this
 * process, with allocation N failing (for a debugger). */
#define _GNU_SOURCE
#include <pthread.h>
#include <jansson.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cache.h"
#include "check.h"
#include "method.h"
#include "method_small.h"
#include "prep.h"
#include "env.h"
#include "fit.h"
#include "img.h"
#include "material.h"
#include "mesh.h"
#include "paint.h"
#include "raster.h"
#include "scene.h"
#include "stroke.h"

#include "alloc_fail.h"

/* ---- the operations --------------------------------------------------------------------- */

static int op_strokes(glint_err *e)
{
    const char *text = "[{\"mode\": \"paint\", \"color\": [1, 0.5, 0], \"diameter\": 8,"
                       " \"kappa\": 0.5, \"points\": [[1, 2], [3, 4], [5, 6]], \"tag\": \"a\"},"
                       " {\"mode\": \"scale\", \"scale\": 2, \"diameter\": 3, \"points\": [[0, 0]]}]";
    stroke_limits lim = {10, 100};
    stroke *list;
    int n, rc;
    json_t *j = json_loads(text, 0, NULL), *back;
    if (!j)
        return glint_err_set(e, GLINT_ENOMEM, "json_loads failed");
    rc = stroke_list_from_json(j, &lim, &list, &n, e);
    json_decref(j);
    if (rc)
        return rc;
    back = stroke_to_json(&list[0]);
    stroke_list_free(list, n);
    if (!back)
        return glint_err_set(e, GLINT_ENOMEM, "stroke_to_json failed");
    json_decref(back);
    return 0;
}

static int op_scene(glint_err *e)
{
    scene_params p;
    scene a, b;
    char *text;
    int rc;
    scene_params_default(&p);
    p.width = p.height = 8;
    if ((rc = scene_create(&p, &a, e)))
        return rc;
    text = scene_to_json(&a, e);
    scene_free(&a);
    if (!text)
        return e->code ? e->code : GLINT_ENOMEM;
    rc = scene_from_json(text, &b, e);
    free(text);
    if (rc == 0)
        scene_free(&b);
    return rc;
}

static void *png_data, *hdr_data;
static size_t png_len, hdr_len;

static int op_image(glint_err *e)
{
    img im;
    int rc = img_read_mem(png_data, png_len, &im, e);
    if (rc == 0)
        img_free(&im);
    return rc;
}

/* A painting as a stroke stores it: OpenEXR (core/img/img_exr.h), read back. */
static int op_exr(glint_err *e)
{
    img im, back;
    void *data = NULL;
    size_t len = 0;
    int rc = img_alloc(&im, 40, 37, 4, e);
    if (rc)
        return rc;
    for (int i = 0; i < 40 * 37 * 4; i++)
        im.px[i] = (float)(i % 11) / 11.0f;
    if ((rc = img_write_mem("exr", &im, &data, &len, e)) == 0 &&
        (rc = img_read_mem(data, len, &back, e)) == 0)
        img_free(&back);
    free(data);
    img_free(&im);
    return rc;
}

static int op_env(glint_err *e)
{
    env_map m;
    int rc = env_load_mem(hdr_data, hdr_len, "sky.hdr", 64, NULL, NULL, &m, e);
    if (rc == 0)
        env_map_free(&m);
    return rc;
}

static int op_mesh(glint_err *e)
{
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                              "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    mesh m;
    mesh_report rep;
    int rc = mesh_load_mem(obj, sizeof obj - 1, "obj", &m, &rep, e);
    if (rc == 0)
        mesh_free(&m);
    return rc;
}

/* A whole hf3 fit of a small scene: G-buffers, paintings, samples, design,
 * decomposition, operator, fit, and the material written and read back. */
static scene fit_scene;
static char fit_dir[64];

static int op_fit(glint_err *e)
{
    gbuf *g = NULL;
    img paint[12];
    brdf b;
    fit_params p;
    fit_prep fp;
    material m, back;
    int rc, k;
    memset(paint, 0, sizeof paint);
    memset(&fp, 0, sizeof fp);
    if ((rc = raster_scene(&fit_scene, &g, e)))
        return rc;
    if ((rc = brdf_parse("ct:rough=0.3,kd=0.5", &b, e)) ||
        (rc = paint_views(&b, g, fit_scene.views, fit_scene.nviews, 0, paint, NULL, e)))
        goto done;
    fit_params_default(&p);
    p.res = 8;
    if ((rc = fit_prepare(&fp, &fit_scene, g, NULL, &p, NULL, e)) ||
        (rc = fit_run(&fp, paint, NULL, &m, e)))
        goto done;
    rc = material_save(&m, fit_dir, e);
    if (rc == 0 && (rc = material_load(fit_dir, &back, e)) == 0)
        material_free(&back);
    material_free(&m);
done:
    fit_prep_free(&fp);
    for (k = 0; k < fit_scene.nviews; k++) {
        img_free(&paint[k]);
        if (g)
            gbuf_free(&g[k]);
    }
    free(g);
    return rc;
}

/* Every method as glintd fits: the scene lent to a cache, the method's
 * levels built through it (pattern, design, decompositions, transfer
 * matrices), the fit, the material written and read back.  Small
 * parameters: the paths are the same at any size. */
static const method *cur_method;
static void *cur_params;
static img method_paint[SCENE_MAX_VIEWS];

static int lend_scene(void *cls, const char *id, const scene **out, glint_err *err)
{
    *out = cls;
    return 0;
}

/* A cache lent to every run (NULL: each run opens its own).  Each run is a
 * child with its own copy: what one run builds in it, no other sees. */
static cache *lent_cache;

static int op_method(glint_err *e)
{
    unsigned char all[SCENE_MAX_VIEWS];
    prep_scene_source src = {lend_scene, NULL, &fit_scene};
    prep_request rq = {cur_method, cur_params, NULL, all, NULL};
    cache *c = NULL;
    cache_entry *se = NULL;
    prep *pp = NULL;
    material m, back;
    int rc;
    memset(all, 1, sizeof all);
    if (lent_cache)
        c = lent_cache;
    else if ((rc = cache_open(NULL, (size_t)1 << 30, &c, e)))
        goto done;
    if ((rc = prep_scene_acquire(c, "s", &src, &se, e)))
        goto done;
    rq.scene = se;
    if ((rc = prep_acquire(c, &rq, NULL, NULL, &pp, e)) ||
        (rc = prep_fit(pp, method_paint, NULL, &m, e)))
        goto done;
    rc = material_save(&m, fit_dir, e);
    if (rc == 0 && (rc = material_load(fit_dir, &back, e)) == 0)
        material_free(&back);
    material_free(&m);
done:
    if (pp)
        prep_release(c, pp);
    if (se)
        cache_release(c, se);
    if (c != lent_cache)
        cache_close(c);
    return rc;
}

/* srbf's energy rows take seconds at any size (their quadrature is fixed,
 * and they are built before the rest of its levels): the whole path of a
 * method that builds them (srbf, auto_env) is swept at a few points, and
 * the path after them at as many as the other methods', with the rows
 * built once in a cache lent to every run (by a preparation with other
 * lights, so that the runs build their own lights, rows and transfer
 * matrices).  Returns the number of bad runs. */
static int sweep_srbf(const char *small, glint_err *e)
{
    char whole[64], after[96];
    unsigned char all[SCENE_MAX_VIEWS];
    prep_scene_source src = {lend_scene, NULL, &fit_scene};
    void *other = method_params_new(cur_method);
    prep_request rq = {cur_method, other, NULL, all, NULL};
    cache_entry *se = NULL;
    prep *pp = NULL;
    int bad, rc, runs = sweep_runs;
    snprintf(whole, sizeof whole, "%s fit", cur_method->name);
    snprintf(after, sizeof after, "%s fit, its energy rows built", cur_method->name);
    sweep_all = sweep_runs = 8;
    bad = sweep(whole, op_method);
    sweep_all = sweep_runs = runs;
    memset(all, 1, sizeof all);
    if (!other)
        return bad + 1;
    if ((rc = method_small_set(cur_method, other, small, e)) ||
        (rc = method_param_set_text(cur_method, other, "lights", "9", e)) ||
        (rc = cache_open(NULL, (size_t)1 << 30, &lent_cache, e)) ||
        (rc = prep_scene_acquire(lent_cache, "s", &src, &se, e)))
        goto done;
    rq.scene = se;
    if ((rc = prep_acquire(lent_cache, &rq, NULL, NULL, &pp, e)))
        goto done;
    prep_release(lent_cache, pp);
    bad += sweep(after, op_method);
done:
    if (se)
        cache_release(lent_cache, se);
    cache_close(lent_cache);
    lent_cache = NULL;
    free(other);
    if (rc)
        fprintf(stderr, "  %s: %s\n", cur_method->name, e->msg);
    return bad + (rc != 0);
}

/* ---- tests ------------------------------------------------------------------------------ */

TEST(stroke_json)
{
    ASSERT_EQ(sweep("strokes", op_strokes), 0);
}

TEST(scene_documents)
{
    ASSERT_EQ(sweep("scene", op_scene), 0);
}

TEST(image_decoding)
{
    img im;
    glint_err e;
    ASSERT_OK(img_alloc(&im, 16, 8, 3, &e));
    for (int i = 0; i < 16 * 8 * 3; i++)
        im.px[i] = (float)(i % 7) / 7.0f;
    ASSERT_OK(img_write_mem("png", &im, &png_data, &png_len, &e));
    ASSERT_OK(img_write_mem("hdr", &im, &hdr_data, &hdr_len, &e));
    img_free(&im);
    ASSERT_EQ(sweep("png", op_image), 0);
    ASSERT_EQ(sweep("exr", op_exr), 0);
    ASSERT_EQ(sweep("environment", op_env), 0);
}

/* As glintd loads an upload: pre-scan, the import in a child, cleaning,
 * normals, uvs. */
TEST(mesh_upload)
{
    ASSERT_EQ(sweep("mesh", op_mesh), 0);
}

TEST(hf3_fit_end_to_end)
{
    scene_params p;
    glint_err e;
    scene_params_default(&p);
    p.width = p.height = 16;
    ASSERT_OK(scene_create(&p, &fit_scene, &e));
    snprintf(fit_dir, sizeof fit_dir, "/tmp/glint-allocfail-XXXXXX");
    ASSERT(mkdtemp(fit_dir) != NULL);
    ASSERT_EQ(sweep("hf3 fit", op_fit), 0);
    {
        char cmd[128];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", fit_dir);
        ASSERT_EQ(system(cmd), 0);
    }
    scene_free(&fit_scene);
}

TEST(every_method_through_the_cache)
{
    scene_params p;
    glint_err e;
    gbuf *g = NULL;
    brdf b;
    char name[64];
    int bad = 0;
    scene_params_default(&p);
    p.width = p.height = 16;
    ASSERT_OK(scene_create(&p, &fit_scene, &e));
    ASSERT_OK(raster_scene(&fit_scene, &g, &e));
    ASSERT_OK(brdf_parse("ct:rough=0.3,kd=0.5", &b, &e));
    ASSERT_OK(paint_views(&b, g, fit_scene.views, fit_scene.nviews, 0, method_paint, NULL, &e));
    ASSERT_OK(method_small_measured());
    snprintf(fit_dir, sizeof fit_dir, "/tmp/glint-allocfail-XXXXXX");
    ASSERT(mkdtemp(fit_dir) != NULL);
    sweep_all = 64; /* eight methods: fewer runs each */
    sweep_runs = 64;
    for (int i = 0; i < METHOD_SMALL_N; i++) {
        cur_method = method_find(method_small[i][0]);
        ASSERT(cur_method && (cur_params = method_params_new(cur_method)));
        ASSERT_MSG(method_small_set(cur_method, cur_params, method_small[i][1], &e) == 0,
                   "%s: %s", method_small[i][0], e.msg);
        snprintf(name, sizeof name, "%s fit", method_small[i][0]);
        if (strcmp(cur_method->name, "srbf") && strcmp(cur_method->name, "auto_env"))
            bad += sweep(name, op_method);
        else
            bad += sweep_srbf(method_small[i][1], &e);
        free(cur_params);
    }
    sweep_all = SWEEP_ALL;
    sweep_runs = SWEEP_RUNS;
    ASSERT_EQ(bad, 0);
    {
        char cmd[128];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", fit_dir);
        ASSERT_EQ(system(cmd), 0);
    }
    for (int k = 0; k < fit_scene.nviews; k++) {
        img_free(&method_paint[k]);
        gbuf_free(&g[k]);
    }
    free(g);
    scene_free(&fit_scene);
}

TEST_LIST {
    TEST_ENTRY(stroke_json),
    TEST_ENTRY(scene_documents),
    TEST_ENTRY(image_decoding),
    TEST_ENTRY(mesh_upload),
    TEST_ENTRY(hf3_fit_end_to_end),
    TEST_ENTRY(every_method_through_the_cache),
};

TEST_MAIN()
