/* test_envrender.c: renders under an environment (envlit.h, render.h's
 * render_*_env, glr_vertex_colors): the furnace, vertex shading through
 * EGL against the per-pixel CPU reference, shadows, rotation, the cache,
 * the background and bad requests.  The EGL tests skip (print and pass
 * nothing) when no EGL platform works; the CPU ones always run. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "asan_reexec.h"
#include "check.h"
#include "clock.h"
#include "envlit.h"
#include "glr.h"
#include "method_srbf.h"
#include "mesh.h"
#include "render.h"
#include "scene.h"

static render *R;
static int egl_ok = -1;

static void view_of(scene_view *v, double x, double y, double z)
{
    double d[3] = {x, y, z};
    scene_view_make(d, 3.5, 1.1, 30.0, v);
}

/* Mean relative RMS difference of a and b over pixels covered in both
 * (RGB summed), and how many. */
static double rel_rms(const img *a, const img *b, long *n)
{
    double num = 0.0, den = 0.0;
    *n = 0;
    for (long p = 0; p < (long)a->width * a->height; p++) {
        double sa = 0.0, sb = 0.0;
        for (int c = 0; c < 3; c++) {
            sa += a->px[3 * p + c];
            sb += b->px[3 * p + c];
        }
        if (sa <= 0.0 || sb <= 0.0)
            continue;
        num += (sa - sb) * (sa - sb);
        den += sb * sb;
        (*n)++;
    }
    return den > 0.0 ? sqrt(num / den) : INFINITY;
}

static int have_egl(void)
{
    if (egl_ok < 0) {
        mesh m;
        scene_view v;
        img out;
        render_env e;
        glint_err err;
        render_env_init(&e);
        e.lights = 4;
        mesh_sphere(&m, 8, 16, NULL);
        view_of(&v, 0, 0, 1);
        egl_ok = render_base_env(R, RENDER_EGL, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 8, 8,
                                 &out, NULL, NULL, NULL, &err) == 0;
        if (!egl_ok)
            printf("  (EGL unavailable: %s; EGL checks skipped)\n", err.msg);
        img_free(&out);
        mesh_free(&m);
    }
    return egl_ok;
}

/* A white environment (radiance 1) on a Lambertian kd: every point that
 * sees the whole sky leaves kd (irradiance pi, f = kd / pi). */
TEST(furnace_on_the_sphere_both_engines)
{
    mesh m;
    scene_view v;
    img cpu, gl;
    render_env e;
    render_env_info info;
    glint_err err;
    double s = 0.0, mx = 0.0;
    long n = 0;
    ASSERT_OK(mesh_sphere(&m, 48, 96, &err));
    render_env_init(&e);
    snprintf(e.spec, sizeof e.spec, "white");
    e.background = 0;
    view_of(&v, 0.3, 0.4, 1.0);
    ASSERT_OK(render_base_env(R, RENDER_CPU, "sphere", &m, "lambert:kd=0.5", 1.0, &e, &v, 96,
                              96, &cpu, &info, NULL, NULL, &err));
    ASSERT_EQ(info.lights, 256);
    ASSERT_EQ(info.convex, 1); /* shadows asked, none cast on a sphere */
    ASSERT_EQ(info.rays, 0);
    for (long p = 0; p < 96L * 96; p++)
        if (cpu.px[3 * p] > 0.0f) {
            double d = fabs(cpu.px[3 * p] - 0.5);
            s += cpu.px[3 * p];
            mx = d > mx ? d : mx;
            n++;
        }
    ASSERT_LT(1000, n);
    /* 256 median-cut lights integrate the cosine to within a few percent */
    ASSERT_NEAR(s / n, 0.5, 0.01);
    ASSERT_LT(mx, 0.05);
    if (have_egl()) {
        ASSERT_OK(render_base_env(R, RENDER_EGL, "sphere", &m, "lambert:kd=0.5", 1.0, &e, &v,
                                  96, 96, &gl, &info, NULL, NULL, &err));
        ASSERT_LT(rel_rms(&gl, &cpu, &n), 0.02);
        img_free(&gl);
    }
    img_free(&cpu);
    mesh_free(&m);
}

/* The interpolated vertex shading against the per-pixel reference: on a
 * finely tessellated sphere with a glossy BRDF under the sky (a sun). */
TEST(vertex_shading_agrees_with_the_pixel_reference)
{
    mesh m;
    scene_view v;
    img cpu, gl;
    render_env e;
    glint_err err;
    long n;
    double r;
    if (!have_egl())
        return;
    ASSERT_OK(mesh_sphere(&m, 128, 256, &err));
    render_env_init(&e);
    snprintf(e.spec, sizeof e.spec, "sky");
    e.background = 0;
    view_of(&v, 0.2, -1.0, 0.5);
    ASSERT_OK(render_base_env(R, RENDER_CPU, NULL, &m, "blinn:kd=0.4,ks=0.3,e=20", 1.0, &e, &v,
                              128, 128, &cpu, NULL, NULL, NULL, &err));
    ASSERT_OK(render_base_env(R, RENDER_EGL, NULL, &m, "blinn:kd=0.4,ks=0.3,e=20", 1.0, &e, &v,
                              128, 128, &gl, NULL, NULL, NULL, &err));
    r = rel_rms(&gl, &cpu, &n);
    printf("  sphere 128x256, blinn e=20 under sky: vertex vs pixel shading rel RMS %.4f over "
           "%ld px\n", r, n);
    ASSERT_LT(5000, n);
    ASSERT_LT(r, 0.03);
    img_free(&cpu);
    img_free(&gl);
    mesh_free(&m);
}

/* A torus shadows its own inner side: with shadows on, a tenth of its
 * vertices or more get darker and none brighter. */
TEST(shadows_darken_what_is_covered)
{
    mesh m;
    render_env e;
    env_map map;
    env_lights l;
    envlit_vis on, off;
    glint_err err;
    double eye[3] = {0, -3, 3};
    ASSERT_OK(mesh_builtin("torus", &m, &err)); /* a torus shadows its inner side */
    render_env_init(&e);
    ASSERT_OK(env_builtin("sky", 128, 64, &map, &err));
    ASSERT_OK(env_compress(&map, ENV_CUT_MEDIAN, 64, 0.0, 1.0, &l, &err));
    ASSERT_OK(envlit_vis_vertices(&m, &l, 1, &on, NULL, &err));
    ASSERT_OK(envlit_vis_vertices(&m, &l, 0, &off, NULL, &err));
    ASSERT_EQ(on.convex, 0);
    ASSERT_LT((long)m.nverts * 16, on.rays); /* one per light above a vertex's horizon */
    ASSERT_LE(on.rays, (long)m.nverts * 64);
    ASSERT(on.bits != NULL);
    ASSERT(off.bits == NULL);
    {
        float *a = malloc(3 * (size_t)m.nverts * sizeof *a), *b = malloc(3 * (size_t)m.nverts * sizeof *b);
        brdf br;
        long darker = 0, brighter = 0;
        ASSERT_OK(brdf_parse("lambert:kd=0.5", &br, &err));
        ASSERT_OK(envlit_vertices(&m, &l, &on, brdf_envlit, &br, eye, 1.0, 2, a, NULL, &err));
        ASSERT_OK(envlit_vertices(&m, &l, &off, brdf_envlit, &br, eye, 1.0, 1, b, NULL, &err));
        for (int i = 0; i < m.nverts; i++) {
            darker += a[3 * i] < b[3 * i] - 1e-6f;
            brighter += a[3 * i] > b[3 * i] + 1e-6f;
        }
        ASSERT_LT(m.nverts / 10, darker);
        ASSERT_EQ(brighter, 0);
        free(a);
        free(b);
    }
    envlit_vis_free(&on);
    envlit_vis_free(&off);
    env_lights_free(&l);
    env_map_free(&map);
    mesh_free(&m);
}

/* The cache: the second render of the same mesh and environment reuses
 * lights and visibility and gives the same image; 360 degrees of rotation
 * changes nothing, 90 degrees moves the sun. */
TEST(cache_and_rotation)
{
    mesh m;
    scene_view v;
    img a, b, c;
    render_env e;
    render_env_info i1, i2;
    glint_err err;
    long n;
    double same, turned;
    if (!have_egl())
        return;
    ASSERT_OK(mesh_builtin("torus", &m, &err));
    render_env_init(&e);
    snprintf(e.spec, sizeof e.spec, "sky");
    e.lights = 64; /* each rotation casts its rays anew: a quarter of the default's */
    view_of(&v, 0.0, -1.0, 0.6);
    ASSERT_OK(render_base_env(R, RENDER_EGL, "torus", &m, "lambert:kd=0.5", 1.0, &e, &v, 64, 64,
                              &a, &i1, NULL, NULL, &err));
    ASSERT_OK(render_base_env(R, RENDER_EGL, "torus", &m, "lambert:kd=0.5", 1.0, &e, &v, 64, 64,
                              &b, &i2, NULL, NULL, &err));
    ASSERT_EQ(i1.cached, 0);
    ASSERT_LT(0, i1.rays);
    ASSERT_EQ(i2.cached, 1);
    ASSERT_EQ(i2.rays, 0);
    ASSERT(memcmp(a.px, b.px, 3 * 64 * 64 * sizeof *a.px) == 0);
    img_free(&b);
    e.rotation_deg = 360.0;
    ASSERT_OK(render_base_env(R, RENDER_EGL, "torus", &m, "lambert:kd=0.5", 1.0, &e, &v, 64, 64,
                              &b, NULL, NULL, NULL, &err));
    same = rel_rms(&b, &a, &n);
    e.rotation_deg = 90.0;
    ASSERT_OK(render_base_env(R, RENDER_EGL, "torus", &m, "lambert:kd=0.5", 1.0, &e, &v, 64, 64,
                              &c, NULL, NULL, NULL, &err));
    turned = rel_rms(&c, &a, &n);
    printf("  %ld lights, %ld rays: rotated 360 degrees rel RMS %.2e, 90 degrees %.3f\n",
           (long)e.lights, i1.rays, same, turned);
    ASSERT_LT(same, 1e-3);
    ASSERT_LT(0.05, turned);
    img_free(&a);
    img_free(&b);
    img_free(&c);
    mesh_free(&m);
}

/* Pixels the mesh leaves uncovered show the environment along their ray. */
TEST(background_is_the_environment)
{
    mesh m;
    scene_view v;
    img out;
    render_env e;
    env_map map;
    glint_err err;
    double rgb[3], fwd[3], right[3], up[3];
    ASSERT_OK(mesh_sphere(&m, 16, 32, &err));
    render_env_init(&e);
    snprintf(e.spec, sizeof e.spec, "sunset");
    e.rotation_deg = 30.0;
    e.intensity = 2.0;
    view_of(&v, 1.0, 0.0, 0.0);
    ASSERT_OK(render_base_env(R, RENDER_CPU, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 32, 32,
                              &out, NULL, NULL, NULL, &err));
    ASSERT_OK(env_resolve("sunset", &map, &err));
    scene_view_frame(&v, fwd, right, up);
    { /* pixel (0, 0): the top-left corner's ray */
        double t = tan(v.half_fov), sx = (2.0 * 0.5 / 32 - 1.0), sy = 1.0 - 2.0 * 0.5 / 32;
        double d[3], l = 0;
        for (int k = 0; k < 3; k++) {
            d[k] = fwd[k] + t * (sx * right[k] + sy * up[k]);
            l += d[k] * d[k];
        }
        for (int k = 0; k < 3; k++)
            d[k] /= sqrt(l);
        env_radiance(&map, d, 30.0 * M_PI / 180.0, 2.0, rgb);
        for (int k = 0; k < 3; k++)
            ASSERT_NEAR(out.px[k], rgb[k], 1e-5 * (1.0 + rgb[k]));
    }
    env_map_free(&map);
    img_free(&out);
    mesh_free(&m);
}

/* A material of method srbf (one lobe on the normal and a diffuse part):
 * the render shades with material_eval, which is what the fit fitted. */
TEST(a_fitted_srbf_material_under_the_environment)
{
    mesh m;
    scene_view v;
    img cpu, gl;
    render_env e;
    material mat;
    srbf_material sm;
    glint_err err;
    long n;
    memset(&sm, 0, sizeof sm);
    ASSERT_OK(srbf_basis_make(3, M_PI / 20, &sm.b, &err));
    sm.st.kind = SRBF_STATIC_PAPER;
    sm.st.f0 = 0.05;
    sm.c = calloc(3 * (size_t)sm.b.J, sizeof *sm.c);
    for (int c = 0; c < 3; c++) {
        sm.c[(size_t)c * sm.b.J] = 0.5 + 0.1 * c;
        sm.rho[c] = 0.3;
    }
    ASSERT_OK(srbf_material_init(&mat, &sm, NULL, NULL));
    ASSERT(mat.method != NULL);
    ASSERT_OK(mesh_sphere(&m, 96, 192, &err));
    render_env_init(&e);
    snprintf(e.spec, sizeof e.spec, "studio");
    e.background = 0;
    view_of(&v, 0.5, 0.2, 1.0);
    ASSERT_OK(render_material_env(R, RENDER_CPU, NULL, &m, &mat, &e, &v, 96, 96, &cpu, NULL, NULL,
                                  NULL, &err));
    if (have_egl()) {
        ASSERT_OK(render_material_env(R, RENDER_EGL, NULL, &m, &mat, &e, &v, 96, 96, &gl, NULL,
                                      NULL, NULL, &err));
        ASSERT_LT(rel_rms(&gl, &cpu, &n), 0.03);
        ASSERT_LT(3000, n);
        img_free(&gl);
    }
    img_free(&cpu);
    material_free(&mat);
    mesh_free(&m);
}

/* A cancel that says to stop from its `after`-th question on. */
typedef struct stop_after {
    int after, asked;
} stop_after;

static int stop_after_fn(void *cls)
{
    stop_after *s = cls;
    return __atomic_add_fetch(&s->asked, 1, __ATOMIC_RELAXED) >= s->after;
}

/* Renders ask their cancel in their loops and stop (GLINT_ECANCELLED,
 * nothing left behind); the estimate of a render grows with its pixels and
 * lights. */
TEST(renders_stop_when_cancelled_and_are_estimated)
{
    mesh m;
    scene_view v;
    img out;
    render_env e;
    material mat;
    srbf_material sm;
    glint_err err;
    stop_after s = {2, 0};
    glint_cancel c = {stop_after_fn, &s};
    double c1, c2, c3;
    memset(&sm, 0, sizeof sm);
    ASSERT_OK(srbf_basis_make(3, M_PI / 20, &sm.b, &err));
    sm.st.kind = SRBF_STATIC_PAPER;
    sm.c = calloc(3 * (size_t)sm.b.J, sizeof *sm.c);
    ASSERT_OK(srbf_material_init(&mat, &sm, NULL, NULL));
    ASSERT_OK(mesh_sphere(&m, 96, 192, &err));
    render_env_init(&e);
    e.lights = 64;
    view_of(&v, 0.5, 0.2, 1.0);
    /* the first question is before the work: stopping at the second shows a loop asks */
    ASSERT_EQ(render_material_env(R, RENDER_CPU, NULL, &m, &mat, &e, &v, 96, 96, &out, NULL, NULL,
                                  &c, &err), GLINT_ECANCELLED);
    ASSERT(out.px == NULL);
    ASSERT(strstr(err.msg, "cancelled") != NULL);
    ASSERT(s.asked >= 2);
    s.asked = 0;
    s.after = 1;
    ASSERT_EQ(render_material(R, RENDER_CPU, NULL, &m, &mat, &v, 96, 96, &out, NULL, &c, &err),
              GLINT_ECANCELLED);
    ASSERT(out.px == NULL);
    if (have_egl()) {
        s.asked = 0;
        s.after = 1;
        ASSERT_EQ(render_material_env(R, RENDER_EGL, "cancel-sphere", &m, &mat, &e, &v, 96, 96,
                                      &out, NULL, NULL, &c, &err), GLINT_ECANCELLED);
        ASSERT(out.px == NULL);
    }
    /* not cancelled: the same renders run */
    s.asked = 0;
    s.after = 1 << 30;
    ASSERT_OK(render_material_env(R, RENDER_CPU, NULL, &m, &mat, &e, &v, 32, 32, &out, NULL, NULL,
                                  &c, &err));
    img_free(&out);
    /* the estimate: its terms (render.h), then timed evaluations */
    c1 = render_cost_seconds(NULL, RENDER_CPU, NULL, &m, &e, 1e-6, 1e-6, 64, 64);
    ASSERT_NEAR(c1, 64.0 * 64.0 * (RENDER_COST_PIXEL_S + 32.0 * (1e-6 + RENDER_COST_RAY_S)),
                1e-12);
    c2 = render_cost_seconds(NULL, RENDER_CPU, NULL, &m, &e, 1e-6, 1e-6, 128, 128);
    ASSERT_NEAR(c2 / c1, 4.0, 1e-9);
    e.shadows = 0;
    c3 = render_cost_seconds(NULL, RENDER_CPU, NULL, &m, &e, 1e-6, 1e-6, 128, 128);
    ASSERT_NEAR(c3, 128.0 * 128.0 * (RENDER_COST_PIXEL_S + 32.0 * 1e-6), 1e-12);
    c3 = render_cost_seconds(NULL, RENDER_EGL, NULL, &m, &e, 1e-6, 5e-7, 128, 128);
    ASSERT_NEAR(c3, 128.0 * 128.0 * RENDER_COST_PIXEL_S + m.nverts * 32.0 * 5e-7, 1e-12);
    ASSERT_NEAR(render_cost_seconds(NULL, RENDER_CPU, NULL, &m, NULL, 1e-6, 1e-6, 10, 10),
                100.0 * (RENDER_COST_PIXEL_S + 1e-6), 1e-15);
    c1 = render_material_cost(NULL, RENDER_CPU, NULL, &m, &mat, &e, 64, 64);
    ASSERT(c1 > 64.0 * 64.0 * RENDER_COST_PIXEL_S && c1 < 1e3);
    material_free(&mat);
    mesh_free(&m);
}

/* The srbf preview evaluation (p(h) from a table) against the exact one:
 * the error, relative to the largest value met, stays within twice the
 * table's design tolerance for sharp, default and broad lobes. */
TEST(srbf_preview_table_error)
{
    double sigmas[3] = {M_PI / 80, M_PI / 40, M_PI / 8};
    for (int si = 0; si < 3; si++) {
        srbf_material sm;
        material mat;
        glint_err err;
        unsigned s = 777;
        double mx = 0.0, emax = 0.0;
        memset(&sm, 0, sizeof sm);
        ASSERT_OK(srbf_basis_make(7, sigmas[si], &sm.b, &err));
        sm.st.kind = SRBF_STATIC_SMITH;
        sm.st.f0 = 0.04;
        sm.st.alpha = 0.3;
        sm.c = calloc(3 * (size_t)sm.b.J, sizeof *sm.c);
        for (int i = 0; i < 3 * sm.b.J; i++) {
            s = s * 1103515245u + 12345u;
            sm.c[i] = ((s >> 9) & 3) == 0 ? ((s >> 12) & 1023) / 1023.0 : 0.0; /* sparse */
        }
        ASSERT_OK(srbf_material_init(&mat, &sm, NULL, NULL));
        for (int k = 0; k < 40000; k++) {
            double n[3] = {0, 0, 1}, wi[3], wo[3], a[3], b[3];
            double *d[2] = {wi, wo};
            for (int q = 0; q < 2; q++) {
                double z, ph;
                s = s * 1103515245u + 12345u;
                z = ((s >> 8) & 0xffff) / 65536.0;
                s = s * 1103515245u + 12345u;
                ph = 2.0 * M_PI * ((s >> 8) & 0xffff) / 65536.0;
                d[q][0] = sqrt(1 - z * z) * cos(ph);
                d[q][1] = sqrt(1 - z * z) * sin(ph);
                d[q][2] = z;
            }
            material_eval(&mat, n, wi, wo, a);
            material_eval_preview(&mat, n, wi, wo, b);
            for (int c = 0; c < 3; c++) {
                mx = a[c] > mx ? a[c] : mx;
                emax = fabs(a[c] - b[c]) > emax ? fabs(a[c] - b[c]) : emax;
            }
        }
        printf("  sigma %.4f (lambda %.1f, table %d^2): max |preview - exact| = %.2e of the "
               "largest value\n",
               sigmas[si], srbf_material_of(&mat)->b.lambda, srbf_table_n(srbf_material_of(&mat)->b.lambda),
               emax / mx);
        ASSERT_LT(emax / mx, 2 * SRBF_TABLE_TOL);
        material_free(&mat);
    }
}

TEST(bad_requests)
{
    mesh m;
    scene_view v;
    img out;
    render_env e;
    glint_err err;
    ASSERT_OK(mesh_sphere(&m, 8, 16, &err));
    view_of(&v, 0, 0, 1);
    render_env_init(&e);
    e.lights = 0;
    ASSERT_EQ(render_base_env(R, RENDER_CPU, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 16, 16,
                              &out, NULL, NULL, NULL, &err), GLINT_EINVAL);
    ASSERT(strstr(err.msg, "lights") != NULL);
    e.lights = RENDER_ENV_MAX_LIGHTS + 1;
    ASSERT_EQ(render_base_env(R, RENDER_CPU, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 16, 16,
                              &out, NULL, NULL, NULL, &err), GLINT_EINVAL);
    render_env_init(&e);
    e.rotation_deg = 400.0;
    ASSERT_EQ(render_base_env(R, RENDER_CPU, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 16, 16,
                              &out, NULL, NULL, NULL, &err), GLINT_EINVAL);
    e.rotation_deg = NAN;
    ASSERT_EQ(render_base_env(R, RENDER_CPU, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 16, 16,
                              &out, NULL, NULL, NULL, &err), GLINT_EINVAL);
    render_env_init(&e);
    e.intensity = 0.0;
    ASSERT_EQ(render_base_env(R, RENDER_CPU, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 16, 16,
                              &out, NULL, NULL, NULL, &err), GLINT_EINVAL);
    render_env_init(&e);
    snprintf(e.spec, sizeof e.spec, "../etc/passwd");
    ASSERT(render_base_env(R, RENDER_CPU, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 16, 16, &out,
                           NULL, NULL, NULL, &err) != 0);
    snprintf(e.spec, sizeof e.spec, "nosuchsky");
    ASSERT_EQ(render_base_env(R, RENDER_CPU, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 16, 16,
                              &out, NULL, NULL, NULL, &err), GLINT_ENOTFOUND);
    render_env_init(&e);
    ASSERT_EQ(render_base_env(R, RENDER_CPU, NULL, &m, "lambert:kd=0.5", 1.0, &e, &v, 0, 16,
                              &out, NULL, NULL, NULL, &err), GLINT_ERANGE);
    ASSERT_EQ(render_material_env(R, RENDER_CPU, NULL, &m, NULL, &e, &v, 16, 16, &out, NULL, NULL,
                                  NULL, &err), GLINT_EINVAL);
    mesh_free(&m);
}

TEST(vertex_colours_are_checked)
{
    mesh m;
    scene_view v;
    img out;
    glint_err err;
    glr *g;
    glr_mesh *gm;
    float *rgb;
    uint8_t mask[16 * 16];
    long covered = 0;
    if (!have_egl())
        return;
    ASSERT_OK(glr_open(&g, &err));
    ASSERT_OK(mesh_sphere(&m, 8, 16, &err));
    ASSERT_OK(glr_mesh_upload(g, &m, &gm, &err));
    rgb = calloc(3 * (size_t)m.nverts, sizeof *rgb);
    for (int i = 0; i < 3 * m.nverts; i++)
        rgb[i] = 0.25f;
    view_of(&v, 0, 0, 1);
    ASSERT_OK(glr_vertex_colors(g, gm, &v, 16, 16, rgb, m.nverts, -1.0f, &out, mask, &err));
    for (long p = 0; p < 16L * 16; p++) {
        covered += mask[p];
        ASSERT_NEAR(out.px[3 * p], mask[p] ? 0.25 : -1.0, 1e-6);
    }
    ASSERT_LT(50, covered);
    ASSERT_LT(covered, 256);
    img_free(&out);
    ASSERT_EQ(glr_vertex_colors(g, gm, &v, 16, 16, rgb, m.nverts - 1, 0.0f, &out, NULL, &err),
              GLINT_EINVAL);
    rgb[7] = NAN;
    ASSERT_EQ(glr_vertex_colors(g, gm, &v, 16, 16, rgb, m.nverts, 0.0f, &out, NULL, &err),
              GLINT_ENONFINITE);
    free(rgb);
    glr_mesh_free(g, gm);
    glr_close(g);
    mesh_free(&m);
}

static void setup(void)
{
    glint_err err;
    if (render_open(4, 1, &R, &err)) {
        fprintf(stderr, "render_open: %s\n", err.msg);
        exit(1);
    }
}

TEST_LIST{
    TEST_ENTRY(furnace_on_the_sphere_both_engines),
    TEST_ENTRY(vertex_shading_agrees_with_the_pixel_reference),
    TEST_ENTRY(shadows_darken_what_is_covered),
    TEST_ENTRY(cache_and_rotation),
    TEST_ENTRY(background_is_the_environment),
    TEST_ENTRY(a_fitted_srbf_material_under_the_environment),
    TEST_ENTRY(srbf_preview_table_error),
    TEST_ENTRY(renders_stop_when_cancelled_and_are_estimated),
    TEST_ENTRY(bad_requests),
    TEST_ENTRY(vertex_colours_are_checked),
};

static int run(int argc, char **argv);
#define main run
TEST_MAIN()
#undef main

int main(int argc, char **argv)
{
    int rc;
    setup();
    rc = run(argc, argv);
    render_close(R);
    return rc;
}
