/* test_raster.c: the rasterizer against the analytic ray/sphere G-buffer of
 * ../shared/reference/hf_ref.py (gbuffer()), exact coverage on shared
 * edges, near-plane clipping, determinism and argument checks. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "gbuf.h"
#include "mesh.h"
#include "raster.h"
#include "scene.h"
#include "vec3.h"

#define PI 3.14159265358979323846

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* ---- analytic reference (hf_ref.py gbuffer(), perspective) -------------- */

typedef struct ref_gbuf {
    int W, H;
    uint8_t *mask;
    double *P, *n, *wi, *wo; /* 3 per pixel */
} ref_gbuf;

static void ref_free(ref_gbuf *r)
{
    free(r->mask);
    free(r->P);
    free(r->n);
    free(r->wi);
    free(r->wo);
    memset(r, 0, sizeof *r);
}

/* Unit sphere at the origin; ray through each pixel centre exactly as in
 * scene.h: dir = normalize(fwd + tan(half_fov) (sx right + sy up)). */
static int ref_sphere(const scene_view *v, int W, int H, ref_gbuf *r)
{
    double f[3], rt[3], u[3], t = tan(v->half_fov);
    size_t n = (size_t)W * H;
    v3 o = v3_load(v->eye), L = v3_load(v->light);

    scene_view_frame(v, f, rt, u);
    r->W = W;
    r->H = H;
    r->mask = calloc(n, 1);
    r->P = calloc(3 * n, sizeof(double));
    r->n = calloc(3 * n, sizeof(double));
    r->wi = calloc(3 * n, sizeof(double));
    r->wo = calloc(3 * n, sizeof(double));
    if (!r->mask || !r->P || !r->n || !r->wi || !r->wo)
        return -1;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            size_t p = (size_t)j * W + i;
            double sx = (2.0 * (i + 0.5) / W - 1.0) * ((double)W / H);
            double sy = 1.0 - 2.0 * (j + 0.5) / H;
            v3 d = v3_normalize(v3_add(v3_load(f), v3_add(v3_scale(v3_load(rt), t * sx),
                                                          v3_scale(v3_load(u), t * sy))));
            double b = v3_dot(o, d), c = v3_dot(o, o) - 1.0, disc = b * b - c, tt;
            v3 P;
            if (!(disc > 0.0))
                continue;
            tt = -b - sqrt(disc);
            P = v3_add(o, v3_scale(d, tt));
            r->mask[p] = 1;
            v3_store(P, r->P + 3 * p);
            v3_store(v3_normalize(P), r->n + 3 * p);
            v3_store(v3_normalize(v3_sub(L, P)), r->wi + 3 * p);
            v3_store(v3_scale(d, -1.0), r->wo + 3 * p);
        }
    return 0;
}

/* All 8 neighbours (and the pixel) have analytic mask m; off-image counts as 0. */
static int ref_nbhd_all(const ref_gbuf *r, int i, int j, int m)
{
    for (int dj = -1; dj <= 1; dj++)
        for (int di = -1; di <= 1; di++) {
            int x = i + di, y = j + dj;
            int v = (x >= 0 && y >= 0 && x < r->W && y < r->H) ? r->mask[(size_t)y * r->W + x] : 0;
            if (v != m)
                return 0;
        }
    return 1;
}

static double diff3(const float *a, const double *b)
{
    return fmax(fmax(fabs(a[0] - b[0]), fabs(a[1] - b[1])), fabs(a[2] - b[2]));
}

typedef struct cmp_stats {
    double n, P, wi, wo, uv, unit;
    long interior, mask_diff, mask_diff_nonsil, lit;
} cmp_stats;

/* Compare one rasterized view with the analytic sphere. */
static int compare_view(const gbuf *g, const ref_gbuf *r, cmp_stats *st)
{
    for (int j = 0; j < g->height; j++)
        for (int i = 0; i < g->width; i++) {
            size_t p = (size_t)j * g->width + i;
            const float *gn = g->nrm + 3 * p;
            if (g->mask[p] != r->mask[p]) {
                st->mask_diff++;
                if (ref_nbhd_all(r, i, j, r->mask[p]))
                    st->mask_diff_nonsil++;
            }
            if (g->mask[p]) {
                v3 n = v3_loadf(gn);
                double ci = v3_dot(n, v3_loadf(g->wi + 3 * p));
                double co = v3_dot(n, v3_loadf(g->wo + 3 * p));
                st->lit += ci > 0.0 && co > 0.0;
                st->unit = fmax(st->unit, fabs(v3_len(n) - 1.0));
            } else {
                /* outside the mask every channel is zero */
                for (int k = 0; k < 3; k++)
                    if (g->pos[3 * p + k] != 0.0f || gn[k] != 0.0f || g->wi[3 * p + k] != 0.0f ||
                        g->wo[3 * p + k] != 0.0f)
                        return -1;
            }
            if (!ref_nbhd_all(r, i, j, 1))
                continue;
            st->interior++;
            if (!g->mask[p])
                return -2;
            st->n = fmax(st->n, diff3(gn, r->n + 3 * p));
            st->P = fmax(st->P, diff3(g->pos + 3 * p, r->P + 3 * p));
            st->wi = fmax(st->wi, diff3(g->wi + 3 * p, r->wi + 3 * p));
            st->wo = fmax(st->wo, diff3(g->wo + 3 * p, r->wo + 3 * p));
            {
                /* uv = (phi / 2pi, theta / pi) away from the seam and poles */
                const double *P = r->P + 3 * p;
                double theta = acos(P[2]), phi = atan2(P[1], P[0]);
                if (phi < 0)
                    phi += 2 * PI;
                if (phi > 0.02 && phi < 2 * PI - 0.02 && theta > 0.05 && theta < PI - 0.05) {
                    st->uv = fmax(st->uv, fabs(g->uv[2 * p] - phi / (2 * PI)));
                    st->uv = fmax(st->uv, fabs(g->uv[2 * p + 1] - theta / PI));
                }
            }
        }
    return 0;
}

TEST(sphere_matches_analytic_128)
{
    scene s;
    scene_params p;
    glint_err e;
    gbuf *g = NULL;
    cmp_stats st;
    double t0, t1;

    memset(&st, 0, sizeof st);
    scene_params_default(&p);
    ASSERT_OK(scene_create(&p, &s, &e));
    t0 = now_s();
    ASSERT_OK(raster_scene(&s, &g, &e));
    t1 = now_s();
    printf("  12 views of %d triangles at 128x128: %.3f s\n", s.mesh.ntris, t1 - t0);
    for (int k = 0; k < s.nviews; k++) {
        ref_gbuf r;
        int rc;
        memset(&r, 0, sizeof r);
        ASSERT(g[k].width == 128 && g[k].height == 128);
        ASSERT_OK(ref_sphere(&s.views[k], 128, 128, &r));
        rc = compare_view(&g[k], &r, &st);
        ref_free(&r);
        ASSERT_MSG(rc == 0, "view %d: %s", k,
                   rc == -1 ? "non-zero channel outside the mask"
                            : "interior pixel not covered");
    }
    printf("  max |dn| %.2e |dP| %.2e |dwi| %.2e |dwo| %.2e |duv| %.2e, |n|-1 %.1e; "
           "%ld interior px, %ld mask diffs, %ld lit+visible (reference 98434)\n",
           st.n, st.P, st.wi, st.wo, st.uv, st.unit, st.interior, st.mask_diff, st.lit);
    ASSERT_LT(100000, st.interior);
    ASSERT_LE(st.n, 1e-3);
    ASSERT_LE(st.P, 1e-3);
    ASSERT_LE(st.wi, 1e-3);
    ASSERT_LE(st.wo, 1e-3);
    ASSERT_LE(st.uv, 1e-3);
    ASSERT_LE(st.unit, 1e-6);
    ASSERT_EQ(st.mask_diff_nonsil, 0);
    ASSERT_LE(fabs(st.lit - 98434.0), 0.005 * 98434.0);
    raster_free_all(g, s.nviews);
    raster_free_all(NULL, 3);
    scene_free(&s);
}

/* One view at 1024x1024: still within tolerance of the analytic sphere. */
TEST(sphere_matches_analytic_1024)
{
    scene s;
    scene_params p;
    glint_err e;
    gbuf g;
    ref_gbuf r;
    cmp_stats st;
    double t0, t1;

    memset(&st, 0, sizeof st);
    memset(&r, 0, sizeof r);
    scene_params_default(&p);
    p.width = p.height = 1024;
    ASSERT_OK(scene_create(&p, &s, &e));
    t0 = now_s();
    ASSERT_OK(raster_view(&s.mesh, &s.views[7], 1024, 1024, &g, &e));
    t1 = now_s();
    printf("  one view at 1024x1024: %.3f s\n", t1 - t0);
    ASSERT_OK(ref_sphere(&s.views[7], 1024, 1024, &r));
    ASSERT_OK(compare_view(&g, &r, &st));
    printf("  max |dn| %.2e |dP| %.2e |dwi| %.2e |dwo| %.2e |duv| %.2e; %ld mask diffs\n",
           st.n, st.P, st.wi, st.wo, st.uv, st.mask_diff);
    ASSERT_LE(st.n, 1e-3);
    ASSERT_LE(st.P, 1e-3);
    ASSERT_LE(st.wi, 1e-3);
    ASSERT_LE(st.wo, 1e-3);
    ASSERT_EQ(st.mask_diff_nonsil, 0);
    ref_free(&r);
    gbuf_free(&g);
    scene_free(&s);
}

static int gbuf_equal(const gbuf *a, const gbuf *b)
{
    size_t n = (size_t)a->width * a->height;
    return a->width == b->width && a->height == b->height && !memcmp(a->mask, b->mask, n) &&
           !memcmp(a->pos, b->pos, 12 * n) && !memcmp(a->nrm, b->nrm, 12 * n) &&
           !memcmp(a->uv, b->uv, 8 * n) && !memcmp(a->wi, b->wi, 12 * n) &&
           !memcmp(a->wo, b->wo, 12 * n);
}

TEST(deterministic)
{
    scene s;
    scene_params p;
    glint_err e;
    gbuf *g1 = NULL, *g2 = NULL, one;

    scene_params_default(&p);
    p.width = 96;
    p.height = 64;
    ASSERT_OK(scene_create(&p, &s, &e));
    ASSERT_OK(raster_scene(&s, &g1, &e));
    ASSERT_OK(raster_scene(&s, &g2, &e));
    for (int k = 0; k < s.nviews; k++)
        ASSERT_MSG(gbuf_equal(&g1[k], &g2[k]), "view %d differs between runs", k);
    /* a single view gives the same bits as the same view in a scene */
    ASSERT_OK(raster_view(&s.mesh, &s.views[5], 96, 64, &one, &e));
    ASSERT(gbuf_equal(&one, &g1[5]));
    /* a non-square raster keeps the sphere round: widest row == tallest column */
    {
        int wmax = 0, hmax = 0;
        for (int j = 0; j < 64; j++) {
            int c = 0;
            for (int i = 0; i < 96; i++)
                c += one.mask[j * 96 + i];
            wmax = c > wmax ? c : wmax;
        }
        for (int i = 0; i < 96; i++) {
            int c = 0;
            for (int j = 0; j < 64; j++)
                c += one.mask[j * 96 + i];
            hmax = c > hmax ? c : hmax;
        }
        ASSERT_LE(abs(wmax - hmax), 1);
        ASSERT_LT(50, wmax);
    }
    gbuf_free(&one);
    raster_free_all(g1, s.nviews);
    raster_free_all(g2, s.nviews);
    scene_free(&s);
}

/* ---- small custom meshes ---------------------------------------------------
 * Camera at the origin looking down -z (world up switches to +y, so right =
 * +x, up = +y), 64x64, tan(half_fov) = 0.5: a point (x, y, -4) lands on pixel
 * coordinates (32 + 16 x, 32 - 16 y).  Vertices are given in pixel
 * coordinates on that plane. */

#define PW 64
static const scene_view flat_view = {
    .eye = {0, 0, 0}, .target = {0, 0, -1}, .half_fov = 0.46364760900080611621,
    .light = {0, 0, 1}, .light_intensity = 1, .light_deg = -1};

static int make_mesh(mesh *m, const double (*px)[2], int nv, const uint32_t *tri, int nt)
{
    memset(m, 0, sizeof *m);
    m->pos = calloc((size_t)nv * 3, sizeof(float));
    m->nrm = calloc((size_t)nv * 3, sizeof(float));
    m->uv = calloc((size_t)nv * 2, sizeof(float));
    m->tri = calloc((size_t)nt * 3, sizeof(uint32_t));
    if (!m->pos || !m->nrm || !m->uv || !m->tri)
        return -1;
    m->nverts = nv;
    m->ntris = nt;
    for (int i = 0; i < nv; i++) {
        m->pos[3 * i] = (float)((px[i][0] - 32.0) / 16.0);
        m->pos[3 * i + 1] = (float)((32.0 - px[i][1]) / 16.0);
        m->pos[3 * i + 2] = -4.0f;
        m->nrm[3 * i + 2] = 1.0f;
        m->uv[2 * i] = (float)(px[i][0] / PW);
        m->uv[2 * i + 1] = (float)(px[i][1] / PW);
    }
    memcpy(m->tri, tri, (size_t)nt * 3 * sizeof(uint32_t));
    return 0;
}

static long render_count(const mesh *m, gbuf *keep)
{
    gbuf g;
    long c;
    if (raster_view(m, &flat_view, PW, PW, &g, NULL) != 0)
        return -1;
    c = gbuf_count(&g);
    if (keep)
        *keep = g;
    else
        gbuf_free(&g);
    return c;
}

/* Render each triangle alone: the counts must add up to the whole mesh's
 * count (no pixel centre on a shared edge drawn twice) and the whole must
 * equal `expect` (none missed). */
static int check_partition(const double (*px)[2], int nv, const uint32_t *tri, int nt,
                           long expect, long *sum_out, long *all_out)
{
    mesh m;
    long sum = 0, all;
    if (make_mesh(&m, px, nv, tri, nt))
        return -1;
    all = render_count(&m, NULL);
    for (int t = 0; t < nt; t++) {
        mesh one = m;
        one.tri = m.tri + 3 * t;
        one.ntris = 1;
        sum += render_count(&one, NULL);
    }
    mesh_free(&m);
    *sum_out = sum;
    *all_out = all;
    return sum == expect && all == expect ? 0 : 1;
}

TEST(quad_shared_edge_exactly_once)
{
    /* corners at .25 (no centre on the outline); the diagonal X - Y = 2
     * runs through 30 pixel centres */
    static const double px[4][2] = {{10.25, 8.25}, {40.25, 8.25}, {40.25, 38.25},
                                    {10.25, 38.25}};
    static const uint32_t ccw[6] = {0, 2, 1, 0, 3, 2};
    static const uint32_t mixed[6] = {0, 1, 2, 0, 3, 2}; /* one of each winding */
    long sum, all;
    mesh m;
    gbuf g;

    ASSERT_EQ(check_partition(px, 4, ccw, 2, 30 * 30, &sum, &all), 0);
    ASSERT_EQ(check_partition(px, 4, mixed, 2, 30 * 30, &sum, &all), 0);
    /* pixel centres i + .5 in (10.25, 40.25): columns 10..39, rows 8..37 */
    ASSERT_OK(make_mesh(&m, px, 4, ccw, 2));
    ASSERT_EQ(render_count(&m, &g), 900);
    for (int j = 0; j < PW; j++)
        for (int i = 0; i < PW; i++) {
            int in = i >= 10 && i <= 39 && j >= 8 && j <= 37;
            size_t p = (size_t)j * PW + i;
            ASSERT_EQ(g.mask[p], in);
            if (in) {
                /* on the plane z = -4 and on the pixel's ray */
                ASSERT_NEAR(g.pos[3 * p + 2], -4.0, 1e-6);
                ASSERT_NEAR(g.pos[3 * p], (i + 0.5 - 32.0) / 16.0, 1e-5);
                ASSERT_NEAR(g.pos[3 * p + 1], (32.0 - (j + 0.5)) / 16.0, 1e-5);
                ASSERT_NEAR(g.uv[2 * p], (i + 0.5) / PW, 1e-5);
                ASSERT_NEAR(g.nrm[3 * p + 2], 1.0, 1e-7);
            }
        }
    gbuf_free(&g);
    mesh_free(&m);
}

/* Diagonals through the view centre with inexact pixel coordinates: the
 * centre pixel lies within rounding error of the shared edge, where only
 * a canonical evaluation of the edge function keeps the two triangles
 * from both taking it or both leaving it. */
TEST(shared_edge_rounding)
{
    uint64_t seed = 0x9e3779b97f4a7c15ull;
    long fails = 0;
    for (int trial = 0; trial < 400; trial++) {
        double r[5];
        mesh m;
        gbuf g[3];
        scene_view v = flat_view;
        static const uint32_t tri[6] = {0, 2, 1, 0, 1, 3};
        float x0, y0, z;
        for (int k = 0; k < 5; k++) {
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            r[k] = (double)(seed >> 11) / 9007199254740992.0;
        }
        v.half_fov = 0.2 + r[0];
        z = (float)(-1.0 - 4.0 * r[1]);
        x0 = (float)((0.5 + 3.0 * r[2]) * -z * tan(v.half_fov) / 4.5);
        y0 = (float)((0.5 + 3.0 * r[3]) * -z * tan(v.half_fov) / 4.5);
        if (r[4] < 0.5)
            y0 = -y0;
        memset(&m, 0, sizeof m);
        m.nverts = 4;
        m.ntris = 2;
        m.pos = malloc(12 * sizeof(float));
        m.nrm = calloc(12, sizeof(float));
        m.uv = calloc(8, sizeof(float));
        m.tri = malloc(sizeof tri);
        ASSERT(m.pos && m.nrm && m.uv && m.tri);
        {
            const float P[4][3] = {{-x0, -y0, z}, {x0, y0, z}, {x0, -y0, z}, {-x0, y0, z}};
            memcpy(m.pos, P, sizeof P);
        }
        memcpy(m.tri, tri, sizeof tri);
        ASSERT_OK(raster_view(&m, &v, 9, 9, &g[0], NULL));
        m.ntris = 1;
        ASSERT_OK(raster_view(&m, &v, 9, 9, &g[1], NULL));
        m.tri[0] = 0;
        m.tri[1] = 1;
        m.tri[2] = 3;
        ASSERT_OK(raster_view(&m, &v, 9, 9, &g[2], NULL));
        /* centre pixel (4, 4) is inside the quad: taken exactly once */
        if (g[0].mask[4 * 9 + 4] != 1 || g[1].mask[4 * 9 + 4] + g[2].mask[4 * 9 + 4] != 1 ||
            gbuf_count(&g[1]) + gbuf_count(&g[2]) != gbuf_count(&g[0]))
            fails++;
        for (int k = 0; k < 3; k++)
            gbuf_free(&g[k]);
        mesh_free(&m);
    }
    ASSERT_EQ(fails, 0);
}

/* Eight triangles around a vertex on a pixel centre, spokes along rows,
 * columns and diagonals through pixel centres. */
TEST(fan_around_pixel_centre)
{
    double px[9][2];
    uint32_t tri[24];
    static const int ring[8][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1},
                                   {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
    long sum, all;
    px[0][0] = px[0][1] = 32.5;
    for (int k = 0; k < 8; k++) {
        px[k + 1][0] = 32.5 + 10.25 * ring[k][0];
        px[k + 1][1] = 32.5 + 10.25 * ring[k][1];
    }
    for (int k = 0; k < 8; k++) {
        tri[3 * k] = 0;
        tri[3 * k + 1] = (uint32_t)(k + 1);
        tri[3 * k + 2] = (uint32_t)((k + 1) % 8 + 1);
    }
    /* centres in (22.25, 42.75): 21 x 21 */
    ASSERT_MSG(check_partition((const double(*)[2])px, 9, tri, 8, 21 * 21, &sum, &all) == 0,
               "sum of triangles %ld, whole %ld, expected %d", sum, all, 21 * 21);
}

/* Coverage does not depend on the vertex order or the winding. */
TEST(winding_invariant)
{
    static const double px[3][2] = {{5.5, 7.25}, {50.5, 20.5}, {17.75, 60.5}};
    static const uint32_t orders[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1},
                                          {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
    gbuf ref;
    mesh m;
    long c0;
    ASSERT_OK(make_mesh(&m, px, 3, orders[0], 1));
    c0 = render_count(&m, &ref);
    ASSERT_LT(500, c0);
    for (int o = 1; o < 6; o++) {
        gbuf g;
        memcpy(m.tri, orders[o], sizeof orders[o]);
        ASSERT_EQ(render_count(&m, &g), c0);
        ASSERT(memcmp(g.mask, ref.mask, PW * PW) == 0);
        gbuf_free(&g);
    }
    gbuf_free(&ref);
    mesh_free(&m);
}

/* The nearer of two overlapping surfaces wins, whatever the order. */
TEST(depth_test)
{
    static const double px[6][2] = {{4.25, 4.25}, {60.25, 4.25}, {4.25, 60.25},
                                    {4.25, 4.25}, {60.25, 4.25}, {4.25, 60.25}};
    static const uint32_t tri[6] = {0, 1, 2, 3, 4, 5};
    for (int near_first = 0; near_first < 2; near_first++) {
        mesh m;
        gbuf g;
        long c;
        ASSERT_OK(make_mesh(&m, px, 6, tri, 2));
        /* move one copy to z = -2 (nearer, the same screen footprint) */
        for (int v = near_first ? 0 : 3; v < (near_first ? 3 : 6); v++)
            for (int k = 0; k < 3; k++)
                m.pos[3 * v + k] *= 0.5f;
        c = render_count(&m, &g);
        ASSERT_LT(1000, c);
        for (size_t p = 0; p < (size_t)PW * PW; p++)
            if (g.mask[p])
                ASSERT_NEAR(g.pos[3 * p + 2], -2.0, 1e-6);
        gbuf_free(&g);
        mesh_free(&m);
    }
}

/* A floor through the camera position (most of it in front, some behind):
 * the clipped part renders exactly where the floor is seen. */
TEST(clip_behind_camera)
{
    mesh m;
    gbuf g;
    glint_err e;
    static const float pos[4][3] = {{-10, -1, 10}, {10, -1, 10}, {10, -1, -100},
                                    {-10, -1, -100}};
    static const uint32_t tri[6] = {0, 1, 2, 0, 2, 3};
    const int W = 64, H = 48;
    double t = 0.5;
    long seen = 0, bad = 0;

    memset(&m, 0, sizeof m);
    m.nverts = 4;
    m.ntris = 2;
    m.pos = malloc(sizeof pos);
    m.nrm = calloc(12, sizeof(float));
    m.uv = calloc(8, sizeof(float));
    m.tri = malloc(sizeof tri);
    ASSERT(m.pos && m.nrm && m.uv && m.tri);
    memcpy(m.pos, pos, sizeof pos);
    memcpy(m.tri, tri, sizeof tri);
    for (int v = 0; v < 4; v++)
        m.nrm[3 * v + 1] = 1.0f;
    ASSERT_OK(raster_view(&m, &flat_view, W, H, &g, &e));
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            size_t p = (size_t)j * W + i;
            double sx = (2.0 * (i + 0.5) / W - 1.0) * ((double)W / H);
            double sy = 1.0 - 2.0 * (j + 0.5) / H;
            /* ray (t sx, t sy, -1) meets y = -1 at lambda = 1 / (-t sy) */
            int expect = 0, margin = 0;
            if (sy < 0) {
                double lam = 1.0 / (-t * sy), x = lam * t * sx;
                expect = fabs(x) < 10 && lam < 100;
                margin = fabs(fabs(x) - 10) < 0.5 || fabs(lam - 100) < 5;
                if (g.mask[p]) {
                    ASSERT_NEAR(g.pos[3 * p + 1], -1.0, 1e-6);
                    ASSERT_NEAR(g.pos[3 * p], x, 1e-4 * lam);
                    ASSERT_NEAR(g.pos[3 * p + 2], -lam, 1e-4 * lam);
                    ASSERT_NEAR(g.nrm[3 * p + 1], 1.0, 1e-7);
                }
            }
            seen += g.mask[p];
            if (!margin && g.mask[p] != expect)
                bad++;
        }
    ASSERT_EQ(bad, 0);
    ASSERT_LT(W * H / 3, seen); /* most of the lower half */
    gbuf_free(&g);
    /* the shared diagonal is clipped at the same point for both triangles:
     * drawn alone, the two halves add up to the whole */
    {
        long sum = 0;
        uint32_t *all = m.tri;
        for (int k = 0; k < 2; k++) {
            m.tri = all + 3 * k;
            m.ntris = 1;
            ASSERT_OK(raster_view(&m, &flat_view, W, H, &g, &e));
            sum += gbuf_count(&g);
            gbuf_free(&g);
        }
        m.tri = all;
        m.ntris = 2;
        ASSERT_EQ(sum, seen);
    }

    /* A wall straddling the camera plane and the whole mesh behind: fine. */
    for (int v = 0; v < 4; v++)
        m.pos[3 * v + 2] += 200.0f; /* everything behind the camera */
    ASSERT_OK(raster_view(&m, &flat_view, W, H, &g, &e));
    ASSERT_EQ(gbuf_count(&g), 0);
    gbuf_free(&g);
    mesh_free(&m);
}

/* A camera inside the sphere sees the inside (both faces are drawn). */
TEST(camera_inside_open_side)
{
    mesh m;
    gbuf g;
    glint_err e;
    scene_view v = flat_view;
    ASSERT_OK(mesh_sphere(&m, 32, 64, &e));
    ASSERT_OK(raster_view(&m, &v, 32, 32, &g, &e));
    ASSERT_EQ(gbuf_count(&g), 32 * 32);
    for (size_t p = 0; p < 32 * 32; p++)
        ASSERT_NEAR(v3_len(v3_loadf(g.pos + 3 * p)), 1.0, 2e-3);
    gbuf_free(&g);
    mesh_free(&m);
}

TEST(errors)
{
    scene s;
    scene_params p;
    glint_err e;
    gbuf g, *gs = NULL;
    scene_view v;

    scene_params_default(&p);
    p.width = p.height = 16;
    ASSERT_OK(scene_create(&p, &s, &e));
    ASSERT_EQ(raster_view(&s.mesh, &s.views[0], SCENE_MIN_SIZE - 1, 16, &g, &e), GLINT_ERANGE);
    ASSERT(g.mask == NULL);
    ASSERT_EQ(raster_view(&s.mesh, &s.views[0], 16, SCENE_MAX_SIZE + 1, &g, &e), GLINT_ERANGE);
    ASSERT_EQ(raster_view(&s.mesh, &s.views[0], 0, 0, &g, &e), GLINT_ERANGE);
    v = s.views[0];
    memcpy(v.target, v.eye, sizeof v.eye);
    ASSERT_EQ(raster_view(&s.mesh, &v, 16, 16, &g, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "camera") != NULL);
    v = s.views[0];
    v.half_fov = PI / 2;
    ASSERT_EQ(raster_view(&s.mesh, &v, 16, 16, &g, &e), GLINT_EINVAL);
    v.half_fov = NAN;
    ASSERT_EQ(raster_view(&s.mesh, &v, 16, 16, &g, &e), GLINT_EINVAL);
    v = s.views[0];
    v.eye[1] = INFINITY;
    ASSERT_EQ(raster_view(&s.mesh, &v, 16, 16, &g, &e), GLINT_EINVAL);
    ASSERT_EQ(raster_view(NULL, &v, 16, 16, &g, &e), GLINT_EINVAL);
    s.mesh.tri[10] = 1u << 30;
    ASSERT_EQ(raster_view(&s.mesh, &s.views[0], 16, 16, &g, &e), GLINT_EFORMAT);
    ASSERT_EQ(raster_scene(&s, &gs, &e), GLINT_EFORMAT);
    ASSERT(gs == NULL);
    s.mesh.tri[10] = 0;
    s.width = 5000;
    ASSERT_EQ(raster_scene(&s, &gs, &e), GLINT_ERANGE);
    ASSERT(gs == NULL);
    ASSERT_EQ(raster_scene(NULL, &gs, &e), GLINT_EINVAL);
    scene_free(&s);
}

TEST_LIST {
    TEST_ENTRY(sphere_matches_analytic_128),
    TEST_ENTRY(sphere_matches_analytic_1024),
    TEST_ENTRY(deterministic),
    TEST_ENTRY(quad_shared_edge_exactly_once),
    TEST_ENTRY(fan_around_pixel_centre),
    TEST_ENTRY(shared_edge_rounding),
    TEST_ENTRY(winding_invariant),
    TEST_ENTRY(depth_test),
    TEST_ENTRY(clip_behind_camera),
    TEST_ENTRY(camera_inside_open_side),
    TEST_ENTRY(errors),
};

TEST_MAIN()
