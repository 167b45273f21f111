/* test_mesh_io.c: meshes from files (every format glint documents, written
 * here into a temporary directory, plus the shared data meshes): formats,
 * node transforms, normals and uvs from the file, cleaning, the automatic
 * parameterization of the shared meshes (coverage, no overlaps, area
 * distortion), scenes on them, and concurrent loads.  Hostile input and
 * references to other files are in test_mesh_refs.c, the parameterization
 * on its own and the built-in shapes in test_mesh_gen.c. */
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "gbuf.h"
#include "mesh.h"
#include "mesh_checks.h"
#include "mesh_fixture.h"
#include "raster.h"
#include "scene.h"
#include "vec3.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Under memcheck (the valgrind setup, tests/meson.build) the importer runs in
 * this process instead of a forked child, so that memcheck sees the import
 * itself: a child ends with _exit, and memcheck's exit-time leak check there
 * counts every block the test's frames hold as lost, failing the child. */
__attribute__((constructor)) static void import_mode(void)
{
    const char *v = getenv("GLINT_TEST_MESH_IN_PROCESS");
    if (v && strcmp(v, "1") == 0)
        mesh_import_in_process(1);
}

/* ---- loading every format ----------------------------------------------------- */

static int load_file(const char *path, mesh *m, mesh_report *r, glint_err *e)
{
    memset(e, 0, sizeof *e);
    return mesh_load(path, m, r, e);
}

TEST(formats_box)
{
    /* half extents (2, 1, 3) / |(2, 1, 3)| after normalization */
    const double s = 1.0 / sqrt(14.0), want[3] = {2 * s, 1 * s, 3 * s};
    static const struct { const char *name; const char *text; const char *fmt; } cases[] = {
        {"box.obj", box_obj, "obj"}, {"box.off", box_off, "off"}, {"box.ply", box_ply, "ply"}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        mesh m, mm;
        mesh_report r, rm;
        glint_err e;
        double lo[3], hi[3];
        char why[256];
        const char *path = tmp_path(cases[i].name);
        ASSERT(write_text(path, cases[i].text) == 0);
        ASSERT_MSG(load_file(path, &m, &r, &e) == 0, "%s: %s", cases[i].name, e.msg);
        ASSERT_MSG(check_loaded(&m, why, sizeof why), "%s: %s", cases[i].name, why);
        ASSERT_EQ(m.ntris, 12);
        ASSERT_EQ(r.ntris, 12);
        ASSERT_EQ(m.nverts, 24); /* 6 charts of 4 corners: every face on its own */
        ASSERT_EQ(r.uv_charts, 6);
        ASSERT_EQ(r.normals_generated, 1);
        ASSERT_EQ(r.uvs_generated, 1);
        ASSERT_EQ(r.dropped_degenerate, 0);
        ASSERT_EQ(r.boundary_edges, 0);
        ASSERT_EQ(r.nonmanifold_edges, 0);
        ASSERT(strcmp(r.format, cases[i].fmt) == 0);
        ASSERT_NEAR(r.scale, s, 1e-7);
        ASSERT_NEAR(r.center[0], 2.0, 1e-6);
        ASSERT_NEAR(r.center[1], 1.0, 1e-6);
        ASSERT_NEAR(r.center[2], 3.0, 1e-6);
        bbox(&m, lo, hi);
        for (int k = 0; k < 3; k++) {
            ASSERT_NEAR(lo[k], -want[k], 1e-6);
            ASSERT_NEAR(hi[k], want[k], 1e-6);
        }
        /* smooth normals of a box corner point along the diagonal */
        for (int v = 0; v < m.nverts; v++) {
            v3 p = v3_loadf(m.pos + 3 * v), n = v3_loadf(m.nrm + 3 * v);
            ASSERT(v3_dot(p, n) > 0.0);
        }
        /* the same bytes from memory */
        ASSERT_MSG(mesh_load_mem(cases[i].text, strlen(cases[i].text), cases[i].fmt, &mm, &rm,
                                 &e) == 0, "%s from memory: %s", cases[i].name, e.msg);
        ASSERT_EQ(mm.nverts, m.nverts);
        ASSERT_EQ(mm.ntris, m.ntris);
        ASSERT(memcmp(mm.pos, m.pos, 3 * sizeof(float) * (size_t)m.nverts) == 0);
        ASSERT(memcmp(mm.uv, m.uv, 2 * sizeof(float) * (size_t)m.nverts) == 0);
        ASSERT(memcmp(mm.tri, m.tri, 3 * sizeof(uint32_t) * (size_t)m.ntris) == 0);
        mesh_free(&m);
        mesh_free(&mm);
    }
}

TEST(formats_tetrahedron)
{
    const double h = 0.5 / sqrt(0.75); /* normalized half extent */
    buf b[6] = {{0}};
    static const char *names[6] = {"tet.ply", "tet.gltf", "tet.glb", "tet.dae", "tet.stl",
                                   "tetbe.ply"};
    static const char *fmts[6] = {"ply", "gltf", "glb", "dae", "stl", "ply"};
    tet_ply_bin(&b[0], -1, NULL);
    tet_gltf(&b[1], -1, NULL, 4, NULL);
    tet_glb(&b[2]);
    buf_str(&b[3], tet_dae);
    buf_str(&b[4], tet_stl);
    /* big-endian PLY, written by hand */
    {
        const char *head = "ply\nformat binary_big_endian 1.0\nelement vertex 4\n"
                           "property float x\nproperty float y\nproperty float z\n"
                           "element face 4\nproperty list uchar int vertex_indices\n"
                           "end_header\n";
        buf_str(&b[5], head);
        for (int v = 0; v < 4; v++)
            for (int k = 0; k < 3; k++) {
                uint32_t u;
                unsigned char c[4];
                memcpy(&u, &tet_v[v][k], 4);
                for (int i = 0; i < 4; i++)
                    c[i] = (unsigned char)(u >> (24 - 8 * i));
                buf_put(&b[5], c, 4);
            }
        for (int f = 0; f < 4; f++) {
            unsigned char c = 3;
            buf_put(&b[5], &c, 1);
            for (int k = 0; k < 3; k++) {
                unsigned char d[4] = {0, 0, 0, (unsigned char)tet_f[f][k]};
                buf_put(&b[5], d, 4);
            }
        }
    }
    for (int i = 0; i < 6; i++) {
        mesh m, mm;
        mesh_report r, rm;
        glint_err e;
        double lo[3], hi[3];
        char why[256];
        const char *path = tmp_path(names[i]);
        ASSERT(write_file(path, b[i].p, b[i].n) == 0);
        ASSERT_MSG(load_file(path, &m, &r, &e) == 0, "%s: %s", names[i], e.msg);
        ASSERT_MSG(check_loaded(&m, why, sizeof why), "%s: %s", names[i], why);
        ASSERT_MSG(m.ntris == 4, "%s: %d triangles", names[i], m.ntris);
        ASSERT_MSG(m.nverts == 12, "%s: %d vertices", names[i], m.nverts);
        ASSERT(strcmp(r.format, fmts[i]) == 0);
        bbox(&m, lo, hi);
        for (int k = 0; k < 3; k++) {
            ASSERT_NEAR(lo[k], -h, 1e-6);
            ASSERT_NEAR(hi[k], h, 1e-6);
        }
        /* faces keep their outward orientation through every loader */
        for (int t = 0; t < m.ntris; t++) {
            const uint32_t *f = m.tri + 3 * t;
            v3 a = v3_loadf(m.pos + 3 * f[0]), bb = v3_loadf(m.pos + 3 * f[1]),
               c = v3_loadf(m.pos + 3 * f[2]);
            v3 n = v3_cross(v3_sub(bb, a), v3_sub(c, a));
            v3 cen = v3_scale(v3_add(v3_add(a, bb), c), 1.0 / 3.0);
            /* the tetrahedron's centroid (1/4, 1/4, 1/4) normalized */
            v3 mid = v3_scale(v3_make(-0.25, -0.25, -0.25), 1.0 / sqrt(0.75));
            ASSERT_MSG(v3_dot(n, v3_sub(cen, mid)) > 0.0, "%s: triangle %d faces inwards",
                       names[i], t);
        }
        ASSERT_MSG(mesh_load_mem(b[i].p, b[i].n, fmts[i], &mm, &rm, &e) == 0,
                   "%s from memory: %s", names[i], e.msg);
        ASSERT_EQ(mm.ntris, 4);
        ASSERT(memcmp(mm.pos, m.pos, 3 * sizeof(float) * (size_t)m.nverts) == 0);
        mesh_free(&m);
        mesh_free(&mm);
        free(b[i].p);
    }
}

/* Node transforms: three instances of one mesh, one mirrored. */
TEST(node_transforms)
{
    buf b = {0};
    mesh m;
    mesh_report r;
    glint_err e;
    const char *path = tmp_path("inst.gltf");
    tet_gltf(&b, -1,
             "[{\"mesh\":0},{\"mesh\":0,\"translation\":[3,0,0]},"
             "{\"mesh\":0,\"scale\":[-1,1,1],\"translation\":[-3,0,0]}]",
             4, NULL);
    ASSERT(write_file(path, b.p, b.n) == 0);
    free(b.p);
    ASSERT_MSG(load_file(path, &m, &r, &e) == 0, "%s", e.msg);
    ASSERT_EQ(m.ntris, 12);
    /* raw bounding box x [-4, 4], y, z [0, 1] */
    ASSERT_NEAR(r.center[0], 0.0, 1e-6);
    ASSERT_NEAR(r.center[1], 0.5, 1e-6);
    ASSERT_NEAR(r.center[2], 0.5, 1e-6);
    ASSERT_NEAR(r.scale, 1.0 / sqrt(16.5), 1e-7);
    for (int t = 0; t < m.ntris; t++) {
        const uint32_t *f = m.tri + 3 * t;
        v3 a = v3_loadf(m.pos + 3 * f[0]), bb = v3_loadf(m.pos + 3 * f[1]),
           c = v3_loadf(m.pos + 3 * f[2]);
        v3 n = v3_cross(v3_sub(bb, a), v3_sub(c, a));
        v3 cen = v3_scale(v3_add(v3_add(a, bb), c), 1.0 / 3.0);
        double x = cen.x / r.scale + r.center[0]; /* back to file units */
        double ix = x < -2 ? -3.25 : x > 2 ? 3.25 : 0.25;
        v3 mid = v3_scale(v3_sub(v3_make(ix, 0.25, 0.25), v3_load(r.center)), r.scale);
        /* winding flipped under the mirror: still outwards */
        ASSERT_MSG(v3_dot(n, v3_sub(cen, mid)) > 0.0, "triangle %d (instance x %g) faces inwards",
                   t, ix);
    }
    mesh_free(&m);
}

/* Normals and uvs from the file are kept (normals renormalized, uvs moved
 * into [0,1] when they leave it); unusable ones are regenerated. */
TEST(file_normals_and_uvs)
{
    static const char quad_head[] =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\n";
    char text[1024];
    mesh m;
    mesh_report r;
    glint_err e;

    /* a pyramid with file normals of length 2 and uvs in [0,1] */
    snprintf(text, sizeof text,
             "%svn 0 0 2\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
             "f 1/1/1 2/2/1 5/5/1\nf 2/2/1 3/3/1 5/5/1\nf 3/3/1 4/4/1 5/5/1\nf 4/4/1 1/1/1 5/5/1\n",
             quad_head);
    ASSERT_OK(mesh_load_mem(text, strlen(text), "obj", &m, &r, &e));
    ASSERT_EQ(r.normals_generated, 0);
    ASSERT_EQ(r.uvs_generated, 0);
    ASSERT_EQ(r.uvs_rescaled, 0);
    ASSERT_EQ(r.boundary_edges, 4); /* open at the bottom */
    for (int v = 0; v < m.nverts; v++) {
        ASSERT_NEAR(m.nrm[3 * v + 2], 1.0, 1e-7);
        /* uv = (x, y) of the file before normalization */
        ASSERT_NEAR(m.uv[2 * v], m.pos[3 * v] / r.scale + r.center[0], 1e-6);
        ASSERT_NEAR(m.uv[2 * v + 1], m.pos[3 * v + 1] / r.scale + r.center[1], 1e-6);
    }
    mesh_free(&m);

    /* tiling uvs in [0, 4] x [0, 2]: scaled by 1/4 into [0,1]^2 */
    snprintf(text, sizeof text,
             "%svt 0 0\nvt 4 0\nvt 4 2\nvt 0 2\nvt 2 1\n"
             "f 1/1 2/2 5/5\nf 2/2 3/3 5/5\nf 3/3 4/4 5/5\nf 4/4 1/1 5/5\n", quad_head);
    ASSERT_OK(mesh_load_mem(text, strlen(text), "obj", &m, &r, &e));
    ASSERT_EQ(r.normals_generated, 1);
    ASSERT_EQ(r.uvs_generated, 0);
    ASSERT_EQ(r.uvs_rescaled, 1);
    for (int v = 0; v < m.nverts; v++) {
        ASSERT_NEAR(m.uv[2 * v], m.pos[3 * v] / r.scale + r.center[0], 1e-6);
        ASSERT_NEAR(m.uv[2 * v + 1], 0.5 * (m.pos[3 * v + 1] / r.scale + r.center[1]), 1e-6);
    }
    mesh_free(&m);

    /* a zero normal and all-equal uvs: both regenerated */
    snprintf(text, sizeof text,
             "%svn 0 0 1\nvn 0 0 0\nvt 0.5 0.5\n"
             "f 1/1/1 2/1/1 5/1/2\nf 2/1/1 3/1/1 5/1/2\nf 3/1/1 4/1/1 5/1/2\nf 4/1/1 1/1/1 5/1/2\n",
             quad_head);
    ASSERT_OK(mesh_load_mem(text, strlen(text), "obj", &m, &r, &e));
    ASSERT_EQ(r.normals_generated, 1);
    ASSERT_EQ(r.uvs_generated, 1);
    ASSERT(r.uv_charts >= 1);
    for (int v = 0; v < m.nverts; v++)
        ASSERT(m.nrm[3 * v + 2] > 0.0f); /* the apex and the rim lean up */
    mesh_free(&m);
}

/* Degenerate triangles are dropped and counted; edges are counted. */
TEST(cleaning)
{
    static const char text[] =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 2 0 0\nv 0 0 0\n"
        "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
        "f 1 2 5\n"  /* collinear: zero area */
        "f 1 2 6\n"  /* vertex 6 repeats vertex 1's position */
        "f 2 3 4\n"; /* a second copy of a face: its edges become non-manifold */
    mesh m;
    mesh_report r;
    glint_err e;
    ASSERT_OK(mesh_load_mem(text, strlen(text), "obj", &m, &r, &e));
    ASSERT_EQ(r.dropped_degenerate, 2);
    ASSERT_EQ(m.ntris, 5);
    ASSERT_EQ(r.nonmanifold_edges, 3);
    ASSERT_EQ(r.boundary_edges, 0);
    mesh_free(&m);
    /* a lone point and a line are not triangles */
    {
        static const char pts[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\nl 1 4\np 4\n";
        ASSERT_OK(mesh_load_mem(pts, strlen(pts), "obj", &m, &r, &e));
        ASSERT_EQ(m.ntris, 1);
        ASSERT(r.dropped_primitives >= 1);
        ASSERT_EQ(r.boundary_edges, 3);
        mesh_free(&m);
    }
}

/* ---- the shared data meshes ---------------------------------------------------- */

static const char *const shared_meshes[] = {"bunny.ply", "teapot.ply", "cow.off",
                                            "triceratops.off"};

TEST(shared_meshes)
{
    const char *dir = check_data_dir();
    if (!dir) {
        printf("  skipped: no shared data\n");
        return;
    }
    for (size_t i = 0; i < sizeof shared_meshes / sizeof shared_meshes[0]; i++) {
        char path[4200], why[256];
        mesh m;
        mesh_report r;
        glint_err e;
        double t0, t1, within4, within25, neg;
        long covered, over;
        snprintf(path, sizeof path, "%s/meshes/%s", dir, shared_meshes[i]);
        t0 = now_s();
        ASSERT_MSG(load_file(path, &m, &r, &e) == 0, "%s: %s", path, e.msg);
        t1 = now_s();
        ASSERT_MSG(check_loaded(&m, why, sizeof why), "%s: %s", shared_meshes[i], why);
        ASSERT_EQ(r.normals_generated, 1);
        ASSERT_EQ(r.uvs_generated, 1);
        ASSERT(r.ntris > 900 && r.nverts >= r.ntris / 2);
        over = uv_overlaps(&m, 2048, &covered);
        within4 = uv_within(&m, 4.0, &neg);
        within25 = uv_within(&m, 2.5, NULL);
        printf("  %-16s %6.1f ms: %d vertices, %d triangles, %d dropped, %d boundary, "
               "%d non-manifold edges; uv: %d charts, coverage %.3f (sampled %.3f), "
               "area ratio within x2.5 %.4f, x4 %.4f\n",
               shared_meshes[i], 1e3 * (t1 - t0), r.nverts, r.ntris, r.dropped_degenerate,
               r.boundary_edges, r.nonmanifold_edges, r.uv_charts, r.uv_coverage,
               (double)covered / (2048.0 * 2048.0), within25, within4);
        ASSERT_MSG(over == 0, "%s: %ld uv samples covered twice", shared_meshes[i], over);
        ASSERT_LT(0.25, r.uv_coverage);
        ASSERT_NEAR((double)covered / (2048.0 * 2048.0), r.uv_coverage, 0.01);
        ASSERT_LT(0.9, within4);
        ASSERT_LT(0.99, within25);
        ASSERT_NEAR(neg, 0.0, 0.0); /* every uv triangle counter-clockwise */
        mesh_free(&m);
    }
}

/* Each shared mesh through a scene (mesh_path): all 12 default views
 * see a good part of it. */
TEST(shared_meshes_raster)
{
    const char *dir = check_data_dir();
    if (!dir) {
        printf("  skipped: no shared data\n");
        return;
    }
    for (size_t i = 0; i < sizeof shared_meshes / sizeof shared_meshes[0]; i++) {
        scene_params p;
        scene s;
        glint_err e;
        double lo = 1.0, hi = 0.0;
        scene_params_default(&p);
        if (snprintf(p.mesh_path, sizeof p.mesh_path, "%.3000s/meshes/%s", dir,
                     shared_meshes[i]) >= (int)sizeof p.mesh_path)
            continue;
        ASSERT_MSG(scene_create(&p, &s, &e) == 0, "%s: %s", shared_meshes[i], e.msg);
        ASSERT(strcmp(s.mesh_name, shared_meshes[i]) == 0);
        ASSERT(s.mesh_path[0] == '/');
        for (int k = 0; k < s.nviews; k++) {
            gbuf g;
            double c;
            int rlo = s.height, rhi = -1, clo = s.width, chi = -1;
            ASSERT_OK(raster_view(&s.mesh, &s.views[k], s.width, s.height, &g, &e));
            c = (double)gbuf_count(&g) / ((double)s.width * s.height);
            lo = fmin(lo, c);
            hi = fmax(hi, c);
            for (int y = 0; y < s.height; y++)
                for (int x = 0; x < s.width; x++)
                    if (g.mask[y * s.width + x]) {
                        size_t px = (size_t)y * s.width + x;
                        rlo = y < rlo ? y : rlo;
                        rhi = y > rhi ? y : rhi;
                        clo = x < clo ? x : clo;
                        chi = x > chi ? x : chi;
                        ASSERT(isfinite(g.uv[2 * px]) && isfinite(g.nrm[3 * px]));
                    }
            /* the silhouette spans at least 40% of the frame one way
             * (the triceratops seen end-on is the narrowest) */
            ASSERT_MSG(rhi - rlo > 0.4 * s.height || chi - clo > 0.4 * s.width,
                       "%s view %d: silhouette %dx%d pixels", shared_meshes[i], k,
                       chi - clo + 1, rhi - rlo + 1);
            gbuf_free(&g);
        }
        printf("  %-16s coverage over the 12 views: %.3f .. %.3f\n", shared_meshes[i], lo, hi);
        ASSERT_MSG(lo > 0.08, "%s: a view covers only %.3f of the frame", shared_meshes[i], lo);
        ASSERT(hi < 0.66);
        scene_free(&s);
    }
}

/* Loading the same bytes concurrently gives identical meshes. */
typedef struct thread_job {
    const char *data;
    size_t len;
    mesh m;
    int rc;
    glint_err e;
} thread_job;

static void *load_thread(void *arg)
{
    thread_job *j = arg;
    j->rc = mesh_load_mem(j->data, j->len, "ply", &j->m, NULL, &j->e);
    return NULL;
}

TEST(concurrent_loads)
{
    pthread_t th[4];
    thread_job jobs[4];
#if defined(__SANITIZE_ADDRESS__)
    /* Imports run in a forked child.  GCC 12's ASan allocator is not
     * fork-safe: a thread that allocates (even while merely starting) at the
     * moment another forks leaves the child's allocator locked forever.
     * Sanitized builds serialize loads, but cannot stop other threads from
     * allocating, so this test only runs in normal builds. */
    printf("  skipped under AddressSanitizer (fork + concurrent allocation)\n");
    return;
#endif
    for (int i = 0; i < 4; i++) {
        jobs[i].data = box_ply;
        jobs[i].len = strlen(box_ply);
        ASSERT(pthread_create(&th[i], NULL, load_thread, &jobs[i]) == 0);
    }
    for (int i = 0; i < 4; i++)
        pthread_join(th[i], NULL);
    for (int i = 0; i < 4; i++) {
        ASSERT_MSG(jobs[i].rc == 0, "thread %d: %s", i, jobs[i].e.msg);
        ASSERT_EQ(jobs[i].m.nverts, jobs[0].m.nverts);
        ASSERT(memcmp(jobs[i].m.pos, jobs[0].m.pos, 12 * (size_t)jobs[0].m.nverts) == 0);
        ASSERT(memcmp(jobs[i].m.uv, jobs[0].m.uv, 8 * (size_t)jobs[0].m.nverts) == 0);
    }
    for (int i = 0; i < 4; i++)
        mesh_free(&jobs[i].m);
}

static void test_cleanup(void) { tmp_cleanup(); }

/* The host's triangle limit holds before the import: what OBJ face lines
 * (fan-triangulated) and PLY/OFF headers say is counted first. */
TEST(triangle_limit_before_the_import)
{
    static const char quads[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
                                "f 1 2 3 4\nf 1 2 5\n  f 2 3 5\n# f 1 2 3\nl 1 2\n";
    static const char ply[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                              "property float y\nproperty float z\nelement face 2\n"
                              "property list uchar int vertex_indices\nend_header\n"
                              "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n3 0 1 3\n";
    static const char off[] = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
    mesh m;
    glint_err e;

    /* 2 + 1 triangles: assimp skips the indented line, and so does the count */
    ASSERT_EQ(mesh_load_mem_max(quads, strlen(quads), "obj", 2, &m, NULL, &e), GLINT_ERANGE);
    ASSERT_MSG(strstr(e.msg, "3 triangles") && strstr(e.msg, "limit of 2"), "%s", e.msg);
    ASSERT_OK(mesh_load_mem_max(quads, strlen(quads), "obj", 3, &m, NULL, &e));
    ASSERT_EQ(m.ntris, 3);
    mesh_free(&m);
    /* a quad and a triangle: within 2 faces, over 2 triangles */
    ASSERT_EQ(mesh_load_mem_max(ply, strlen(ply), "ply", 2, &m, NULL, &e), GLINT_ERANGE);
    ASSERT_MSG(strstr(e.msg, "limit of 2"), "%s", e.msg);
    ASSERT_EQ(mesh_load_mem_max(ply, strlen(ply), "ply", 1, &m, NULL, &e), GLINT_ERANGE);
    ASSERT_MSG(strstr(e.msg, "declares 2 \"face\""), "%s", e.msg);
    ASSERT_OK(mesh_load_mem_max(ply, strlen(ply), "ply", 3, &m, NULL, &e));
    mesh_free(&m);
    ASSERT_EQ(mesh_load_mem_max(off, strlen(off), "off", 1, &m, NULL, &e), GLINT_ERANGE);
    ASSERT_OK(mesh_load_mem_max(off, strlen(off), "off", 2, &m, NULL, &e));
    mesh_free(&m);
}

/* PLY headers assimp reads slowly: too many properties, too many lines. */
TEST(ply_headers_beyond_the_limits)
{
    size_t cap = 1 << 20, n;
    char *b = malloc(cap);
    mesh m;
    glint_err e;
    ASSERT(b != NULL);
    n = (size_t)snprintf(b, cap, "ply\nformat ascii 1.0\nelement vertex 3\n");
    for (int i = 0; i < 65; i++)
        n += (size_t)snprintf(b + n, cap - n, "property float p%d\n", i);
    n += (size_t)snprintf(b + n, cap - n, "end_header\n");
    ASSERT_EQ(mesh_load_mem(b, n, "ply", &m, NULL, &e), GLINT_ERANGE);
    ASSERT_MSG(strstr(e.msg, "more than 64 properties"), "%s", e.msg);
    n = (size_t)snprintf(b, cap, "ply\nformat ascii 1.0\n");
    for (int i = 0; i < 5000; i++)
        n += (size_t)snprintf(b + n, cap - n, "comment %d\n", i);
    n += (size_t)snprintf(b + n, cap - n, "element vertex 0\nend_header\n");
    ASSERT_EQ(mesh_load_mem(b, n, "ply", &m, NULL, &e), GLINT_ERANGE);
    ASSERT_MSG(strstr(e.msg, "more than 4096 lines"), "%s", e.msg);
    free(b);
}

TEST(zz_cleanup) { test_cleanup(); }

TEST_LIST {
    TEST_ENTRY(formats_box),
    TEST_ENTRY(formats_tetrahedron),
    TEST_ENTRY(node_transforms),
    TEST_ENTRY(file_normals_and_uvs),
    TEST_ENTRY(cleaning),
    TEST_ENTRY(shared_meshes),
    TEST_ENTRY(shared_meshes_raster),
    TEST_ENTRY(concurrent_loads),
    TEST_ENTRY(triangle_limit_before_the_import),
    TEST_ENTRY(ply_headers_beyond_the_limits),
    TEST_ENTRY(zz_cleanup),
};

TEST_MAIN()
