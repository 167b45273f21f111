/* test_vis.c: visibility by ray casting (vis.h) and convexity. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "clock.h"
#include "mesh.h"
#include "vis.h"

static int bit(const uint64_t *b, int words, int i, int k)
{
    return (int)((b[(size_t)i * words + (k >> 6)] >> (k & 63)) & 1);
}

/* A floor quad (z = 0, 4 x 4) and a floating square (z = 1, 1 x 1) above
 * the origin, both facing up. */
static void floor_and_roof(mesh *m)
{
    static const float P[] = {-2, -2, 0, 2, -2, 0, 2, 2, 0, -2, 2, 0,
                              -.5f, -.5f, 1, .5f, -.5f, 1, .5f, .5f, 1, -.5f, .5f, 1};
    static const uint32_t T[] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
    memset(m, 0, sizeof *m);
    m->nverts = 8;
    m->ntris = 4;
    m->pos = malloc(sizeof P);
    m->nrm = calloc(24, sizeof(float));
    m->uv = calloc(16, sizeof(float));
    m->tri = malloc(sizeof T);
    memcpy(m->pos, P, sizeof P);
    memcpy(m->tri, T, sizeof T);
}

TEST(an_occluder_blocks_what_is_behind_it)
{
    mesh m;
    vis_scene *v;
    glint_err e;
    float pos[6] = {0, 0, 0, 1.5f, 1.5f, 0}, nrm[6] = {0, 0, 1, 0, 0, 1};
    double dirs[3 * 65];
    uint64_t bits[4];
    long rays;
    floor_and_roof(&m);
    for (int k = 0; k < 65; k++) { /* k = 0: straight up; others: 60 deg off, around */
        double a = 2 * 3.14159265358979 * k / 65, s = k ? sin(1.05) : 0, c = k ? cos(1.05) : 1;
        dirs[3 * k] = s * cos(a);
        dirs[3 * k + 1] = s * sin(a);
        dirs[3 * k + 2] = c;
    }
    ASSERT_OK(vis_open(&m, &v, &e));
    ASSERT_OK(vis_compute(v, 2, pos, nrm, 65, dirs, bits, 1, &rays, NULL, &e));
    ASSERT_EQ(rays, 130);
    ASSERT_EQ(bit(bits, 2, 0, 0), 0); /* under the roof: up is blocked */
    ASSERT_EQ(bit(bits, 2, 1, 0), 1); /* far away: up is open */
    ASSERT_EQ(bit(bits, 2, 0, 64), 1); /* 60 degrees off passes beside the roof */
    for (int k = 1; k < 65; k++)
        ASSERT_EQ(bit(bits, 2, 0, k), 1);
    /* a direction below the surface is never seen */
    dirs[2] = -1;
    ASSERT_OK(vis_compute(v, 2, pos, nrm, 65, dirs, bits, 2, NULL, NULL, &e));
    ASSERT_EQ(bit(bits, 2, 1, 0), 0);
    vis_close(v);
    mesh_free(&m);
}

TEST(a_sphere_never_shadows_itself_and_threads_agree)
{
    mesh m;
    vis_scene *v;
    glint_err e;
    enum { NP = 400, K = 130 };
    float *pos = malloc(3 * NP * sizeof(float)), *nrm = malloc(3 * NP * sizeof(float));
    double dirs[3 * K];
    uint64_t *b1 = malloc(NP * VIS_WORDS(K) * sizeof(uint64_t)),
             *b2 = malloc(NP * VIS_WORDS(K) * sizeof(uint64_t));
    int mism = 0, near = 0;
    ASSERT_OK(mesh_sphere(&m, 64, 128, &e));
    for (int i = 0; i < NP; i++) { /* vertices of the mesh: exactly on the surface */
        int vi = (int)((long)i * m.nverts / NP);
        memcpy(pos + 3 * i, m.pos + 3 * vi, 3 * sizeof(float));
        memcpy(nrm + 3 * i, m.nrm + 3 * vi, 3 * sizeof(float));
    }
    for (int k = 0; k < K; k++) {
        double z = 1 - (2.0 * k + 1) / K, r = sqrt(1 - z * z), a = k * 2.39996;
        dirs[3 * k] = r * cos(a);
        dirs[3 * k + 1] = r * sin(a);
        dirs[3 * k + 2] = z;
    }
    ASSERT_OK(vis_open(&m, &v, &e));
    ASSERT_OK(vis_compute(v, NP, pos, nrm, K, dirs, b1, 1, NULL, NULL, &e));
    ASSERT_OK(vis_compute(v, NP, pos, nrm, K, dirs, b2, 2, NULL, NULL, &e));
    ASSERT(memcmp(b1, b2, NP * VIS_WORDS(K) * sizeof(uint64_t)) == 0);
    for (int i = 0; i < NP; i++)
        for (int k = 0; k < K; k++) {
            double c = nrm[3 * i] * dirs[3 * k] + nrm[3 * i + 1] * dirs[3 * k + 1] +
                       nrm[3 * i + 2] * dirs[3 * k + 2];
            if (bit(b1, VIS_WORDS(K), i, k) != (c > 0)) {
                if (fabs(c) < 0.05)
                    near++; /* grazing: the facets, not the sphere, decide */
                else
                    mism++;
            }
        }
    printf("  %d of %d pairs differ from n.d > 0, all within 3 degrees of the horizon\n", near,
           NP * K);
    ASSERT_EQ(mism, 0);
    vis_close(v);
    mesh_free(&m);
    free(pos);
    free(nrm);
    free(b1);
    free(b2);
}

TEST(convexity_of_the_built_ins)
{
    mesh m;
    glint_err e;
    ASSERT_OK(mesh_builtin("sphere", &m, &e));
    ASSERT_EQ(vis_mesh_convex(&m, 1e-6), 1);
    mesh_free(&m);
    ASSERT_OK(mesh_builtin("torus", &m, &e));
    ASSERT_EQ(vis_mesh_convex(&m, 1e-6), 0);
    mesh_free(&m);
    ASSERT_OK(mesh_builtin("teapot", &m, &e));
    ASSERT_EQ(vis_mesh_convex(&m, 1e-6), 0);
    mesh_free(&m);
    floor_and_roof(&m);
    ASSERT_EQ(vis_mesh_convex(&m, 1e-6), 0); /* open */
    mesh_free(&m);
}

/* The answers are kept by the mesh's contents: asked again, the same; a
 * mesh that differs by one vertex (a dent) gets its own answer, and the
 * original's is still right after it; another tolerance is asked anew. */
TEST(convexity_is_kept_by_content)
{
    mesh m, dent;
    glint_err e;
    ASSERT_OK(mesh_sphere(&m, 24, 48, &e));
    ASSERT_OK(mesh_sphere(&dent, 24, 48, &e));
    for (int c = 0; c < 3; c++)
        dent.pos[3 * (dent.nverts / 2) + c] *= 0.5f; /* a vertex on the equator pulled in */
    for (int pass = 0; pass < 2; pass++) {
        ASSERT_EQ(vis_mesh_convex(&m, 1e-6), 1);
        ASSERT_EQ(vis_mesh_convex(&dent, 1e-6), 0);
    }
    ASSERT_EQ(vis_mesh_convex(&dent, 10.0), 1); /* a dihedral tolerance that lets it pass */
    ASSERT_EQ(vis_mesh_convex(&dent, 1e-6), 0);
    /* changed in place after an answer (meshes are read-only once made, but
     * the answer must follow the contents, not the address) */
    memcpy(m.pos, dent.pos, (size_t)m.nverts * 3 * sizeof *m.pos);
    ASSERT_EQ(vis_mesh_convex(&m, 1e-6), 0);
    mesh_free(&m);
    mesh_free(&dent);
}

TEST(the_bunny_when_present)
{
    mesh m;
    glint_err e;
    vis_scene *v;
    char path[4096];
    snprintf(path, sizeof path, "%s/../shared/data/meshes/bunny.ply", glint_test_source_dir);
    enum { K = 256 };
    double dirs[3 * K], t0;
    uint64_t *bits;
    long rays;
    if (access(path, R_OK)) {
        printf("  SKIP: %s absent\n", path);
        return;
    }
    ASSERT_OK(mesh_load(path, &m, NULL, &e));
    ASSERT_EQ(vis_mesh_convex(&m, 1e-6), 0);
    for (int k = 0; k < K; k++) {
        double z = 1 - (2.0 * k + 1) / K, r = sqrt(1 - z * z), a = k * 2.39996;
        dirs[3 * k] = r * cos(a);
        dirs[3 * k + 1] = r * sin(a);
        dirs[3 * k + 2] = z;
    }
    t0 = glint_now();
    ASSERT_OK(vis_open(&m, &v, &e));
    printf("  bunny: %d triangles, built in %.1f ms\n", m.ntris, 1e3 * (glint_now() - t0));
    bits = malloc((size_t)m.nverts * VIS_WORDS(K) * sizeof *bits);
    t0 = glint_now();
    ASSERT_OK(vis_compute(v, m.nverts, m.pos, m.nrm, K, dirs, bits, 0, &rays, NULL, &e));
    t0 = glint_now() - t0;
    printf("  %ld rays from %d vertices in %.3f s (%.1f M rays/s)\n", rays, m.nverts, t0,
           rays / t0 / 1e6);
    {
        long seen = 0;
        for (int i = 0; i < m.nverts; i++)
            for (int k = 0; k < K; k++)
                seen += bit(bits, VIS_WORDS(K), i, k);
        ASSERT(seen < rays); /* the bunny shadows itself somewhere */
        ASSERT(seen > rays / 2);
    }
    free(bits);
    vis_close(v);
    mesh_free(&m);
}

static int stop_now(void *cls)
{
    __atomic_add_fetch((int *)cls, 1, __ATOMIC_RELAXED);
    return 1;
}

/* Told to stop, every thread stops at its first question: the rays of
 * those that asked are not cast. */
TEST(a_cancelled_computation_stops)
{
    mesh m;
    vis_scene *v;
    glint_err e;
    enum { NP = 4096, K = 64 };
    static float pos[3 * NP], nrm[3 * NP];
    static uint64_t bits[NP];
    double dirs[3 * K];
    long rays = -1;
    int asked = 0;
    glint_cancel c = {stop_now, &asked};
    floor_and_roof(&m);
    ASSERT_OK(vis_open(&m, &v, &e));
    for (int i = 0; i < NP; i++) {
        pos[3 * i] = (float)(i % 64) / 64.0f - 0.5f;
        pos[3 * i + 1] = (float)(i / 64) / 64.0f - 0.5f;
        nrm[3 * i + 2] = 1.0f;
    }
    for (int k = 0; k < K; k++) { /* upwards, unit */
        double x = 0.1 * (k % 8 - 4), y = 0.1 * (k / 8 - 4), l = sqrt(x * x + y * y + 1.0);
        dirs[3 * k] = x / l;
        dirs[3 * k + 1] = y / l;
        dirs[3 * k + 2] = 1.0 / l;
    }
    ASSERT_EQ(vis_compute(v, NP, pos, nrm, K, dirs, bits, 2, &rays, &c, &e), GLINT_ECANCELLED);
    ASSERT(strstr(e.msg, "cancelled") != NULL);
    ASSERT(asked >= 1 && asked <= 2);
    ASSERT_EQ(rays, 0);
    vis_close(v);
    mesh_free(&m);
}

TEST(bad_input)
{
    mesh m;
    vis_scene *v;
    glint_err e;
    float p[3] = {NAN, 0, 0}, n[3] = {0, 0, 1};
    double d[3] = {0, 0, 1};
    uint64_t b;
    memset(&m, 0, sizeof m);
    ASSERT_EQ(vis_open(&m, &v, &e), GLINT_EINVAL);
    floor_and_roof(&m);
    ASSERT_OK(vis_open(&m, &v, &e));
    ASSERT_EQ(vis_compute(v, 1, p, n, 1, d, &b, 1, NULL, NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(vis_compute(v, 1, n, n, 0, d, &b, 1, NULL, NULL, &e), GLINT_EINVAL);
    vis_close(v);
    mesh_free(&m);
}

TEST_LIST{
    TEST_ENTRY(an_occluder_blocks_what_is_behind_it),
    TEST_ENTRY(a_sphere_never_shadows_itself_and_threads_agree),
    TEST_ENTRY(convexity_of_the_built_ins),
    TEST_ENTRY(convexity_is_kept_by_content),
    TEST_ENTRY(the_bunny_when_present),
    TEST_ENTRY(a_cancelled_computation_stops),
    TEST_ENTRY(bad_input),
};

TEST_MAIN()
