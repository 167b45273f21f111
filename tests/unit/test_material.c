/* Tests of fitted materials: files, evaluation, CPU shading (core/material,
 * core/fit). */
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "fit.h"
#include "fsio.h"
#include "material.h"
#include "method_hf3.h"
#include "raster.h"
#include "scene.h"

static scene sc;
static gbuf *G;
static material M;
static char dir[64];

/* A material fitted to a Blinn-Phong-like painting of a small sphere scene. */
static int setup(void)
{
    scene_params p;
    fit_params fpar;
    fit_prep fp;
    img imgs[12];
    glint_err e;
    if (dir[0])
        return 0;
    snprintf(dir, sizeof dir, "/tmp/glint-mat-XXXXXX");
    if (!mkdtemp(dir))
        return -1;
    scene_params_default(&p);
    p.width = p.height = 40;
    if (scene_create(&p, &sc, &e) || raster_scene(&sc, &G, &e))
        return -1;
    for (int v = 0; v < 12; v++) {
        img_alloc(&imgs[v], 40, 40, 3, NULL);
        for (int i = 0; i < 40 * 40; i++) {
            const float *n = G[v].nrm + 3 * i, *wi = G[v].wi + 3 * i;
            double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
            for (int c = 0; c < 3; c++)
                imgs[v].px[3 * i + c] = G[v].mask[i] && ci > 0 ? (float)((0.2 + 0.2 * c) * ci) : 0;
        }
    }
    fit_params_default(&fpar);
    fpar.res = 32;
    if (fit_prepare(&fp, &sc, G, NULL, &fpar, NULL, &e) || fit_run(&fp, imgs, NULL, &M, &e)) {
        fprintf(stderr, "%s\n", e.msg);
        return -1;
    }
    fit_prep_free(&fp);
    for (int v = 0; v < 12; v++)
        img_free(&imgs[v]);
    return 0;
}

TEST(save_load_round_trip)
{
    material b;
    glint_err e;
    char path[256];
    ASSERT_OK(setup());
    ASSERT_OK(material_save(&M, dir, &e));
    snprintf(path, sizeof path, "%s/factors.png", dir);
    ASSERT(access(path, R_OK) == 0);
    snprintf(path, sizeof path, "%s/factors.exr", dir);
    ASSERT(access(path, R_OK) == 0);
    ASSERT_OK(material_load(dir, &b, &e));
    ASSERT_EQ(hf3_factors(&b)->res, hf3_factors(&M)->res);
    ASSERT(hf3_factors(&b)->map.kind == hf3_factors(&M)->map.kind);
    for (int k = 0; k < 9 * hf3_factors(&M)->res; k++)
        ASSERT_NEAR(hf3_factors(&b)->logf[k], hf3_factors(&M)->logf[k], 1e-15 * (1 + fabs(hf3_factors(&M)->logf[k])));
    ASSERT(json_object_get(b.info, "params") != NULL);
    /* and the factors.exr holds exp(log factors) */
    img ex;
    ASSERT_OK(img_read(path, &ex, &e));
    ASSERT_EQ(ex.width, hf3_factors(&M)->res);
    ASSERT_EQ(ex.height, 3);
    ASSERT_NEAR(ex.px[(1 * hf3_factors(&M)->res + 5) * 3 + 2], exp(hf3_factors(&M)->logf[(hf3_factors(&M)->res + 5) * 3 + 2]), 1e-5);
    img_free(&ex);
    material_free(&b);
}

/* The bytes of dir/name (OUT: *len), NULL when unreadable. */
static char *slurp(const char *d, const char *name, size_t *len)
{
    char path[512], *data = NULL;
    snprintf(path, sizeof path, "%s/%s", d, name);
    if (fsio_read_all(path, 1u << 26, &data, len, NULL))
        return NULL;
    return data;
}

static ino_t inode_of(const char *d, const char *name)
{
    char path[512];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", d, name);
    return stat(path, &st) == 0 ? st.st_ino : 0;
}

/* A deferred save writes material.json alone, the same bytes as a full
 * save's; material_files_ensure then writes the files a full save writes
 * (the same PNG bytes, the same EXR pixels), only those that are missing. */
TEST(deferred_save_writes_the_files_on_first_use)
{
    char full[300], lazy[300], path[400], *a, *b;
    size_t la, lb;
    int written = -1;
    img x, y;
    glint_err e;
    ASSERT_OK(setup());
    snprintf(full, sizeof full, "%s/full", dir);
    snprintf(lazy, sizeof lazy, "%s/lazy", dir);
    ASSERT_OK(material_save(&M, full, &e));
    ASSERT_OK(material_save_deferred(&M, lazy, &e));
    ASSERT(inode_of(lazy, "material.json") != 0);
    ASSERT(inode_of(lazy, "factors.exr") == 0);
    ASSERT(inode_of(lazy, "factors.png") == 0);
    ASSERT((a = slurp(full, "material.json", &la)) && (b = slurp(lazy, "material.json", &lb)));
    ASSERT(la == lb && memcmp(a, b, la) == 0);
    free(a);
    free(b);

    ASSERT_OK(material_files_ensure(lazy, &written, &e));
    ASSERT_EQ(written, 2);
    ASSERT((a = slurp(full, "factors.png", &la)) && (b = slurp(lazy, "factors.png", &lb)));
    ASSERT(la == lb && memcmp(a, b, la) == 0);
    free(a);
    free(b);
    snprintf(path, sizeof path, "%s/factors.exr", full);
    ASSERT_OK(img_read(path, &x, &e));
    snprintf(path, sizeof path, "%s/factors.exr", lazy);
    ASSERT_OK(img_read(path, &y, &e));
    ASSERT(x.width == y.width && x.height == y.height && x.channels == y.channels);
    ASSERT(memcmp(x.px, y.px, (size_t)x.width * x.height * x.channels * sizeof *x.px) == 0);
    img_free(&x);
    img_free(&y);
    /* the manifest is not rewritten */
    ASSERT((b = slurp(lazy, "material.json", &lb)) && (a = slurp(full, "material.json", &la)));
    ASSERT(la == lb && memcmp(a, b, la) == 0);
    free(a);
    free(b);

    /* when all are there nothing is written; when one is missing it is */
    ino_t exr = inode_of(lazy, "factors.exr"), png = inode_of(lazy, "factors.png");
    ASSERT_OK(material_files_ensure(lazy, &written, &e));
    ASSERT_EQ(written, 0);
    ASSERT(inode_of(lazy, "factors.exr") == exr && inode_of(lazy, "factors.png") == png);
    snprintf(path, sizeof path, "%s/factors.png", lazy);
    ASSERT(unlink(path) == 0);
    ASSERT_OK(material_files_ensure(lazy, &written, &e));
    ASSERT_EQ(written, 1);
    ASSERT(inode_of(lazy, "factors.png") != 0);

    /* something else in a file's place, and no manifest: errors */
    ASSERT(unlink(path) == 0 && mkdir(path, 0755) == 0);
    ASSERT_EQ(material_files_ensure(lazy, &written, &e), GLINT_EIO);
    ASSERT(strstr(e.msg, "factors.png") != NULL);
    ASSERT(rmdir(path) == 0);
    snprintf(path, sizeof path, "%s/material.json", lazy);
    ASSERT(unlink(path) == 0);
    ASSERT_EQ(material_files_ensure(lazy, &written, &e), GLINT_ENOTFOUND);
}

static int write_text(const char *name, const char *text)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return fsio_write_atomic(path, text, strlen(text), NULL);
}

TEST(corrupt_manifests_are_rejected)
{
    material b;
    glint_err e;
    char path[256];
    static const char *cases[] = {
        "{",                                                                  /* truncated */
        "[]",                                                                 /* not an object */
        "{\"format\":\"something\"}",                                         /* wrong format */
        "{\"format\":\"glint-material\",\"version\":2}",                      /* version */
        "{\"format\":\"glint-material\",\"version\":1,\"method\":\"hf3\",\"res\":3}", /* res */
        "{\"format\":\"glint-material\",\"version\":1,\"method\":\"hf3\",\"res\":4,"
        "\"model\":\"radiance\",\"mapping\":\"add:0.1\",\"a_used\":[0.1,0.1,0.1],"
        "\"log_factors\":{\"p\":[[0,0,0]]}}",                                 /* short factor */
        "{\"format\":\"glint-material\",\"version\":1,\"method\":\"hf3\",\"res\":4,"
        "\"model\":\"radiance\",\"mapping\":\"add:0.1\",\"a_used\":[0.1,0.1,0.1],"
        "\"log_factors\":{\"p\":[[0,0,0],[0,0,0],[0,0,0],[0,0,1e300]],"
        "\"q\":[[0,0,0],[0,0,0],[0,0,0],[0,0,0]],\"r\":[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]}}",
        "{\"format\":\"glint-material\",\"format\":\"glint-material\"}",      /* duplicate key */
    };
    ASSERT_OK(setup());
    snprintf(path, sizeof path, "%s/bad.json", dir);
    for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ASSERT_OK(write_text("bad.json", cases[i]));
        int rc = material_load(path, &b, &e);
        ASSERT_MSG(rc == GLINT_EFORMAT || rc == GLINT_ENONFINITE, "case %u: rc %d", i, rc);
        ASSERT(e.msg[0] != '\0');
        ASSERT(b.data == NULL);
    }
    ASSERT_EQ(material_load("/nonexistent/dir", &b, &e), GLINT_ENOTFOUND);
}

TEST(shading_matches_evaluation)
{
    img out;
    glint_err e;
    ASSERT_OK(setup());
    ASSERT_OK(material_shade(&M, &G[2], 2.0, 0.25f, &out, &e));
    int lit = 0, unlit = 0;
    for (int i = 0; i < 40 * 40; i++) {
        const float *n = G[2].nrm + 3 * i, *wi = G[2].wi + 3 * i, *wo = G[2].wo + 3 * i;
        if (!G[2].mask[i]) {
            ASSERT_NEAR(out.px[3 * i], 0.25, 0);
            continue;
        }
        double nd[3] = {n[0], n[1], n[2]}, wid[3] = {wi[0], wi[1], wi[2]},
               wod[3] = {wo[0], wo[1], wo[2]}, rgb[3];
        material_eval(&M, nd, wid, wod, rgb);
        for (int c = 0; c < 3; c++)
            ASSERT_NEAR(out.px[3 * i + c], 2.0 * M_PI * rgb[c], 1e-6); /* pi I f cos (scene.h) */
        if (rgb[0] > 0) lit++; else unlit++;
    }
    ASSERT(lit > 100 && unlit > 10);
    img_free(&out);
    ASSERT_EQ(material_shade(&M, &G[2], NAN, 0, &out, &e), GLINT_EINVAL);
}

TEST(render_reproduces_the_fit_on_its_own_views)
{
    img out, truth[12];
    double rms, mx;
    long cnt;
    glint_err e;
    ASSERT_OK(setup());
    ASSERT_OK(material_render(&M, &sc.mesh, &sc.views[5], 40, 40, &out, NULL, &e));
    /* the material's own render is a perfect "truth" for itself */
    for (int v = 0; v < 12; v++)
        ASSERT_OK(material_shade(&M, &G[v], 1.0, 0.0f, &truth[v], &e));
    ASSERT_OK(fit_error_views(&M, G, sc.views, 12, truth, &rms, &mx, &cnt, &e));
    ASSERT_LE(mx, 1e-6);
    ASSERT(cnt > 1000);
    for (int i = 0; i < 40 * 40 * 3; i++)
        ASSERT_NEAR(out.px[i], truth[5].px[i], 1e-6);
    for (int v = 0; v < 12; v++)
        img_free(&truth[v]);
    img_free(&out);
}

TEST(cleanup)
{
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    ASSERT_EQ(system(cmd), 0);
    material_free(&M);
    raster_free_all(G, sc.nviews);
    scene_free(&sc);
}

TEST_LIST {
    TEST_ENTRY(save_load_round_trip),
    TEST_ENTRY(deferred_save_writes_the_files_on_first_use),
    TEST_ENTRY(corrupt_manifests_are_rejected),
    TEST_ENTRY(shading_matches_evaluation),
    TEST_ENTRY(render_reproduces_the_fit_on_its_own_views),
    TEST_ENTRY(cleanup),
};
TEST_MAIN()
