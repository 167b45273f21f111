/* test_mesh_gen.c: what core/mesh computes itself: the automatic
 * parameterization on its own (no overlaps, bounded distortion), normals
 * and normalization, and the procedural torus and teapot (and the
 * teapot's transcribed control data). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "mesh.h"
#include "mesh_checks.h"
#include "vec3.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* ---- parameterization on its own ------------------------------------------------ */

/* A helicoid ramp of two turns: every triangle faces nearly +z, and its
 * orthographic projection covers itself twice, so one chart per axis is
 * not enough: the overlap test must split it. */
TEST(uv_self_overlap_split)
{
    const int nu = 96, nv = 4;
    mesh m;
    glint_err e;
    long over, covered;
    memset(&m, 0, sizeof m);
    m.nverts = (nu + 1) * (nv + 1);
    m.ntris = 2 * nu * nv;
    m.pos = malloc(3 * sizeof(float) * (size_t)m.nverts);
    m.nrm = malloc(3 * sizeof(float) * (size_t)m.nverts);
    m.tri = malloc(3 * sizeof(uint32_t) * (size_t)m.ntris);
    ASSERT(m.pos && m.nrm && m.tri);
    for (int i = 0; i <= nu; i++)
        for (int j = 0; j <= nv; j++) {
            double th = 4.0 * 3.14159265358979 * i / nu, r = 0.5 + 0.5 * j / nv;
            float *p = m.pos + 3 * (i * (nv + 1) + j);
            p[0] = (float)(r * cos(th));
            p[1] = (float)(r * sin(th));
            p[2] = (float)(0.02 * th);
        }
    {
        uint32_t *t = m.tri;
        for (int i = 0; i < nu; i++)
            for (int j = 0; j < nv; j++) {
                uint32_t a = (uint32_t)(i * (nv + 1) + j), b = a + (uint32_t)(nv + 1);
                *t++ = a; *t++ = a + 1; *t++ = b + 1;
                *t++ = a; *t++ = b + 1; *t++ = b;
            }
    }
    ASSERT_OK(mesh_compute_normals(&m, &e));
    ASSERT_OK(mesh_generate_uvs(&m, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    over = uv_overlaps(&m, 1024, &covered);
    ASSERT_MSG(over == 0, "%ld samples covered twice", over);
    ASSERT(covered > 1024 * 1024 / 20);
    mesh_free(&m);
}

/* Built-in shapes re-parameterized: no overlap, bounded distortion. */
TEST(uv_generate_builtins)
{
    mesh m;
    glint_err e;
    long over, covered;
    double neg;
    ASSERT_OK(mesh_sphere(&m, 24, 48, &e));
    ASSERT_OK(mesh_generate_uvs(&m, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    over = uv_overlaps(&m, 1024, &covered);
    ASSERT_EQ(over, 0);
    ASSERT_LT(0.99, uv_within(&m, 2.5, &neg));
    ASSERT_NEAR(neg, 0.0, 0.0);
    mesh_free(&m);
    ASSERT_OK(mesh_torus(&m, 0.7, 0.3, 64, 32, &e));
    ASSERT_OK(mesh_generate_uvs(&m, &e));
    over = uv_overlaps(&m, 1024, &covered);
    ASSERT_EQ(over, 0);
    ASSERT_LT(0.99, uv_within(&m, 2.5, &neg));
    mesh_free(&m);
}

/* ---- normals and normalization ------------------------------------------------ */

TEST(normals_and_normalize)
{
    mesh m;
    glint_err e;
    double scale, c[3], maxdev = 0.0, meandev = 0.0;
    ASSERT_OK(mesh_sphere(&m, 32, 64, &e));
    /* smooth normals agree with the exact ones, also on the duplicated seam */
    ASSERT_OK(mesh_compute_normals(&m, &e));
    for (int v = 0; v < m.nverts; v++) {
        v3 p = v3_loadf(m.pos + 3 * v), n = v3_loadf(m.nrm + 3 * v);
        double d = v3_len(v3_sub(p, n));
        maxdev = fmax(maxdev, d);
        meandev += d / m.nverts;
        /* on the seam (phi = 0, copies at u = 0 and u = 1) both copies agree */
        if (m.uv[2 * v] == 1.0f && fabs(p.z) < 0.999) {
            int twin = v - 64; /* the u = 0 copy of the same ring (nlon = 64) */
            ASSERT(m.pos[3 * twin] == m.pos[3 * v] && m.pos[3 * twin + 1] == m.pos[3 * v + 1]);
            ASSERT(memcmp(m.nrm + 3 * twin, m.nrm + 3 * v, 3 * sizeof(float)) == 0);
        }
    }
    /* area weighting on a latitude-longitude grid leans by O(cell size)
     * where the cells are thin (near the poles) */
    ASSERT_LT(maxdev, 0.03);
    ASSERT_LT(meandev, 5e-3);
    /* move and scale, then normalize back */
    for (int i = 0; i < 3 * m.nverts; i++)
        m.pos[i] = m.pos[i] * 5.0f + (float)(i % 3) - 7.0f;
    mesh_normalize(&m, &scale, c);
    ASSERT_NEAR(scale, 0.2, 1e-6);
    ASSERT_NEAR(c[0], -7.0, 1e-5);
    ASSERT_NEAR(c[1], -6.0, 1e-5);
    ASSERT_NEAR(c[2], -5.0, 1e-5);
    ASSERT_NEAR(max_norm(&m), 1.0, 1e-6);
    ASSERT_LE(max_norm(&m), 1.0);
    mesh_free(&m);
}

/* ---- procedural built-ins --------------------------------------------------- */

TEST(torus)
{
    mesh m;
    glint_err e;
    long nb, nn;
    const int nu = 48, nv = 24;
    ASSERT_OK(mesh_torus(&m, 0.7, 0.3, nu, nv, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    ASSERT_EQ(m.nverts, (nu + 1) * (nv + 1));
    ASSERT_EQ(m.ntris, 2 * nu * nv);
    ASSERT_NEAR(max_norm(&m), 1.0, 1e-6);
    edge_counts(&m, &nb, &nn);
    ASSERT_EQ(nb, 0); /* closed: the seams are bit-identical */
    ASSERT_EQ(nn, 0);
    for (int v = 0; v < m.nverts; v++) {
        v3 p = v3_loadf(m.pos + 3 * v), n = v3_loadf(m.nrm + 3 * v);
        /* the nearest point of the core circle (radius 0.7) */
        double rho = hypot(p.x, p.y);
        v3 core = v3_make(0.7 * p.x / rho, 0.7 * p.y / rho, 0.0);
        ASSERT_NEAR(v3_len(n), 1.0, 1e-6);
        ASSERT_NEAR(v3_len(v3_sub(v3_scale(n, 0.3), v3_sub(p, core))), 0.0, 1e-6);
        ASSERT(m.uv[2 * v] >= 0.0f && m.uv[2 * v] <= 1.0f);
    }
    for (int t = 0; t < m.ntris; t++) {
        const uint32_t *f = m.tri + 3 * t;
        v3 a = v3_loadf(m.pos + 3 * f[0]), b = v3_loadf(m.pos + 3 * f[1]),
           c = v3_loadf(m.pos + 3 * f[2]);
        v3 fnrm = v3_cross(v3_sub(b, a), v3_sub(c, a));
        ASSERT_MSG(v3_dot(fnrm, v3_loadf(m.nrm + 3 * f[0])) > 0.0, "triangle %d inverted", t);
    }
    ASSERT_LT(0.98, outward_share(&m, 200));
    mesh_free(&m);
    /* errors */
    ASSERT_EQ(mesh_torus(&m, 0.3, 0.7, 8, 8, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_torus(&m, 0.7, 0.0, 8, 8, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_torus(&m, NAN, 0.3, 8, 8, &e), GLINT_ENONFINITE);
    ASSERT_EQ(mesh_torus(&m, 0.7, 0.3, 2, 8, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_torus(&m, 0.7, 0.3, 8, MESH_SPHERE_MAX_SEG + 1, &e), GLINT_ERANGE);
    ASSERT(m.pos == NULL);
}

/* The transcribed control data: counts, bounding box, coordinate sums,
 * and the symmetries of the published patches (4-fold rotations of rim,
 * body, lid and bottom; mirror pairs of handle and spout), which any typo
 * would break. */
TEST(teapot_data)
{
    const double (*pt)[3];
    const uint16_t (*pa)[16];
    int np, nk;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double sum[3] = {0, 0, 0};
    /* first patch of each group and its turn: -1 for -90 degrees about z,
     * (x, y) -> (y, -x); +1 for +90 degrees, (x, y) -> (-y, x) */
    static const int rot_groups[6][2] = {{0, -1}, {4, -1}, {8, -1}, {20, -1}, {24, -1}, {28, 1}};
    mesh_teapot_data(&pt, &np, &pa, &nk);
    ASSERT_EQ(np, 306);
    ASSERT_EQ(nk, 32);
    for (int i = 0; i < np; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], pt[i][k]);
            hi[k] = fmax(hi[k], pt[i][k]);
            sum[k] += pt[i][k];
        }
    ASSERT_NEAR(lo[0], -3.0, 0.0);
    ASSERT_NEAR(hi[0], 3.525, 0.0);
    ASSERT_NEAR(lo[1], -2.0, 0.0);
    ASSERT_NEAR(hi[1], 2.0, 0.0);
    ASSERT_NEAR(lo[2], 0.0, 0.0);
    ASSERT_NEAR(hi[2], 3.15, 0.0);
    ASSERT_NEAR(sum[0], 15.275, 1e-9);
    ASSERT_NEAR(sum[1], 0.0, 1e-9);
    ASSERT_NEAR(sum[2], 510.95625, 1e-9);
    for (int k = 0; k < nk; k++)
        for (int i = 0; i < 16; i++)
            ASSERT(pa[k][i] < np);
    /* rim, body, lid, bottom: patch k + 1 is patch k turned by 90 degrees
     * about z, point by point */
    for (size_t g = 0; g < sizeof rot_groups / sizeof rot_groups[0]; g++)
        for (int q = 0; q < 3; q++) {
            int a = rot_groups[g][0] + q, b = a + 1, s = rot_groups[g][1];
            for (int i = 0; i < 16; i++) {
                const double *p = pt[pa[a][i]], *r = pt[pa[b][i]];
                ASSERT_MSG(fabs(r[0] + s * p[1]) < 1e-12 && fabs(r[1] - s * p[0]) < 1e-12 &&
                               fabs(r[2] - p[2]) < 1e-12,
                           "patch %d point %d is not patch %d's turned", b, i, a);
            }
        }
    /* handle and spout: patch k + 1 mirrors patch k in y, columns reversed */
    for (int k = 12; k < 20; k += 2)
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++) {
                const double *p = pt[pa[k][4 * i + 3 - j]], *r = pt[pa[k + 1][4 * i + j]];
                ASSERT_MSG(r[0] == p[0] && r[1] == -p[1] && r[2] == p[2],
                           "patch %d point %d does not mirror patch %d", k + 1, 4 * i + j, k);
            }
}

TEST(teapot)
{
    mesh m;
    glint_err e;
    long nb, nn, over, covered;
    int outward = 0, agree = 0;
    v3 cen = v3_make(0, 0, 0);
    const int seg = 16;
    ASSERT_OK(mesh_teapot(&m, seg, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    ASSERT_EQ(m.nverts, 32 * (seg + 1) * (seg + 1));
    /* 8 patches have a collapsed edge: their first row keeps one triangle
     * per quad */
    ASSERT_EQ(m.ntris, 2 * 32 * seg * seg - 8 * seg);
    ASSERT_NEAR(max_norm(&m), 1.0, 1e-6);
    ASSERT_LE(max_norm(&m), 1.0);
    for (int v = 0; v < m.nverts; v++)
        cen = v3_add(cen, v3_loadf(m.pos + 3 * v));
    cen = v3_scale(cen, 1.0 / m.nverts);
    for (int v = 0; v < m.nverts; v++) {
        v3 p = v3_loadf(m.pos + 3 * v), n = v3_loadf(m.nrm + 3 * v);
        ASSERT_NEAR(v3_len(n), 1.0, 1e-6);
        outward += v3_dot(n, v3_sub(p, cen)) > 0.0;
    }
    for (int t = 0; t < m.ntris; t++) {
        const uint32_t *f = m.tri + 3 * t;
        v3 a = v3_loadf(m.pos + 3 * f[0]), b = v3_loadf(m.pos + 3 * f[1]),
           c = v3_loadf(m.pos + 3 * f[2]);
        v3 fn = v3_cross(v3_sub(b, a), v3_sub(c, a));
        int ok = 1;
        for (int k = 0; k < 3; k++)
            ok &= v3_dot(fn, v3_loadf(m.nrm + 3 * f[k])) > 0.0;
        agree += ok;
    }
    printf("  teapot: %d vertices, %d triangles; normals away from the centroid at %.3f of "
           "the vertices, agreeing with the winding on %.4f of the triangles\n",
           m.nverts, m.ntris, (double)outward / m.nverts, (double)agree / m.ntris);
    /* the inner sides of the handle, the spout and the rim's lip face the
     * body: about a fifth of the vertices; ray parity below is the real test */
    ASSERT_LT(0.75, (double)outward / m.nverts);
    ASSERT_EQ(agree, m.ntris);
    ASSERT_LT(0.95, outward_share(&m, 300));
    /* welded: open only at the lid gap, the rim, the spout's tip and the
     * handle and spout ends (each one patch edge of seg segments) */
    edge_counts(&m, &nb, &nn);
    printf("  teapot: %ld boundary edges, %ld non-manifold\n", nb, nn);
    ASSERT_EQ(nn, 0);
    ASSERT_LE(nb, 24 * seg);
    /* atlas: one cell per patch, no overlap */
    over = uv_overlaps(&m, 1024, &covered);
    ASSERT_EQ(over, 0);
    for (int v = 0; v < m.nverts; v++)
        ASSERT(m.uv[2 * v] >= 0.0f && m.uv[2 * v] <= 1.0f && m.uv[2 * v + 1] >= 0.0f &&
               m.uv[2 * v + 1] <= 1.0f);
    mesh_free(&m);
    ASSERT_EQ(mesh_teapot(&m, 0, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_teapot(&m, MESH_TEAPOT_MAX_SEG + 1, &e), GLINT_ERANGE);
    ASSERT_OK(mesh_teapot(&m, 1, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    mesh_free(&m);
}

TEST(builtins)
{
    static const char *names[] = {"sphere", "torus", "teapot"};
    for (int i = 0; i < 3; i++) {
        mesh m;
        glint_err e;
        double t0 = now_s();
        ASSERT_OK(mesh_builtin(names[i], &m, &e));
        ASSERT_OK(mesh_validate(&m, &e));
        ASSERT_NEAR(max_norm(&m), 1.0, 1e-6);
        printf("  %-6s %7d vertices %7d triangles, %.1f ms\n", names[i], m.nverts, m.ntris,
               1e3 * (now_s() - t0));
        mesh_free(&m);
    }
    {
        mesh m;
        glint_err e;
        ASSERT_EQ(mesh_builtin("cube", &m, &e), GLINT_ENOTFOUND);
        ASSERT(strstr(e.msg, "sphere") && strstr(e.msg, "torus") && strstr(e.msg, "teapot"));
    }
}

TEST_LIST {
    TEST_ENTRY(uv_self_overlap_split),
    TEST_ENTRY(uv_generate_builtins),
    TEST_ENTRY(normals_and_normalize),
    TEST_ENTRY(torus),
    TEST_ENTRY(teapot_data),
    TEST_ENTRY(teapot),
    TEST_ENTRY(builtins),
};

TEST_MAIN()
