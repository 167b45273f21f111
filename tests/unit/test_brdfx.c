/* BRDF Explorer .brdf files for every method (brdfx_material; the
 * methods without a hand-written one through brdfx.c).
 *
 * Each method fits a painting of the default scene (a spatially varying
 * truth for the methods that vary over the surface); its .brdf file's
 * shader section is compiled as GLSL ES 3.00 and run as a fragment stage
 * (radiance = BRDF(L, V, N, X, Y) n.L I, as BRDF Explorer's lit views
 * compute it), its parameters declared as BRDF Explorer declares them
 * (uniforms at their values: constants here), and the image compared with
 * the CPU's evaluation of the material (material_shade) on the same view:
 * at the surface point (surface_u, surface_v) set in the parameters for
 * the materials that vary, at each pixel's own point otherwise. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdfx.h"
#include "glr_fixture.h"
#include "glsl_parts.h"
#include "method_small.h"
#include "sv_fixture.h"

#define W 128
#define STRIPES                                                                                 \
    "stripes:freq=3,duty=0.5,soft=0.3|ct:kd=0.6/0.3/0.2,f0=0.04,rough=0.3|"                     \
    "ct:kd=0.05,f0=0.9/0.7/0.3,rough=0.25"

static scene sc;
static gbuf *gb;
static cache *cc;
static cache_entry *se;

/* The parameters section as constants at `uv` (surface_u, surface_v) or at
 * their defaults; every parameter must be "float NAME MIN MAX DEFAULT". */
static int declare_params(const char *text, const double *uv, char *out, size_t len)
{
    const char *a = strstr(text, "::begin parameters\n"), *b = strstr(text, "::end parameters");
    size_t used = 0;
    out[0] = '\0';
    if (!a || !b || b < a)
        return -1;
    for (a += strlen("::begin parameters\n"); a < b;) {
        const char *e = strchr(a, '\n');
        char name[64];
        double lo, hi, def;
        if (sscanf(a, "float %63s %lf %lf %lf", name, &lo, &hi, &def) != 4 || !(lo <= def) ||
            !(def <= hi))
            return -1;
        if (uv && !strcmp(name, "surface_u"))
            def = uv[0];
        if (uv && !strcmp(name, "surface_v"))
            def = uv[1];
        used += (size_t)snprintf(out + used, len - used, "const float %s = %.9e;\n", name, def);
        if (used >= len)
            return -1;
        a = e ? e + 1 : b;
    }
    return 0;
}

/* The .brdf text as a fragment stage for glr_render_fragment. */
static char *as_stage(const char *text, const double *uv)
{
    const char *a = strstr(text, "::begin shader\n"), *b = strstr(text, "::end shader");
    char params[1024];
    size_t len;
    char *frag;
    if (!a || !b || b < a || declare_params(text, uv, params, sizeof params))
        return NULL;
    a += strlen("::begin shader\n");
    len = strlen(params) + (size_t)(b - a) + 4096;
    if (!(frag = malloc(len)))
        return NULL;
    snprintf(frag, len,
             "#version 300 es\n" GLSL_PRECISION GLSL_STAGE_IO "%s%.*s\n"
             "void main()\n"
             "{\n"
             "    vec3 n = normalize(v_nrm), l = normalize(u_light - v_pos),"
             " e = normalize(u_eye - v_pos);\n"
             "    vec3 x = normalize(abs(n.z) < 0.9 ? cross(vec3(0.0, 0.0, 1.0), n)"
             " : cross(vec3(1.0, 0.0, 0.0), n));\n"
             "    o_color = vec4(BRDF(l, e, n, x, cross(n, x)) * max(dot(n, l), 0.0) *"
             " u_light_intensity, 1.0);\n"
             "}\n",
             params, (int)(b - a), a);
    return frag;
}

/* The CPU's render of m on view v, at the surface point uv (NULL: each
 * pixel's own). */
static int cpu_render(const material *m, const scene_view *v, const double *uv, img *out)
{
    gbuf g;
    glint_err e;
    int rc = raster_view(&sc.mesh, v, W, W, &g, &e);
    if (!rc && uv && g.uv)
        for (long p = 0; p < (long)W * W; p++) {
            g.uv[2 * p] = (float)uv[0];
            g.uv[2 * p + 1] = (float)uv[1];
        }
    if (!rc)
        rc = material_shade(m, &g, v->light_intensity, 0.0f, out, &e);
    if (rc)
        fprintf(stderr, "cpu render: %s\n", e.msg);
    gbuf_free(&g);
    return rc;
}

static double largest(const img *a)
{
    double mx = 0.0;
    for (size_t i = 0; i < (size_t)a->width * a->height * 3; i++)
        mx = a->px[i] > mx ? a->px[i] : mx;
    return mx;
}

/* Render the .brdf `text` and the material on view v; 0 when they agree
 * (mean |difference| < 1/255 and something lit).  OUT: *d the difference. */
static int compare(glr *g, const glr_mesh *gm, const material *m, const char *text,
                   const scene_view *v, const double *uv, double *d, img *gpu)
{
    char *frag = as_stage(text, uv);
    img ref;
    glint_err e;
    int rc;
    if (!frag) {
        printf("  the .brdf text has no shader or parameters section as expected\n");
        return -1;
    }
    if ((rc = glr_render_fragment(g, gm, frag, v, W, W, gpu, &e))) {
        printf("  compile/render: %.2000s\n", e.msg);
        free(frag);
        return rc;
    }
    free(frag);
    if ((rc = cpu_render(m, v, material_spatial(m) ? uv : NULL, &ref))) {
        img_free(gpu);
        return rc;
    }
    *d = mad(&ref, gpu);
    rc = !(*d < 1.0 / 255) || !(largest(&ref) > 0.05);
    img_free(&ref);
    return rc;
}

static int setup(void)
{
    return method_small_measured() || sv_setup(48, &sc, &gb, &cc, &se);
}

TEST(every_method_renders_as_the_material)
{
    glr *g = need_glr();
    glr_mesh *gm = NULL;
    glint_err e;
    int bad = 0;

    ASSERT_OK(setup());
    ASSERT_OK(glr_mesh_upload(g, &sc.mesh, &gm, &e));
    for (int i = 0; i < METHOD_SMALL_N; i++) {
        const method *meth = method_find(method_small[i][0]);
        void *params = calloc(1, meth->params_size);
        material m;
        /* the methods whose materials vary over the surface paint stripes */
        int spatial_method = meth->mat && meth->mat->spatial;
        ASSERT(params);
        meth->params_default(params);
        ASSERT_OK(method_small_set(meth, params, method_small[i][1], &e));
        memset(&m, 0, sizeof m);
        ASSERT_OK(sv_fit(meth, params, spatial_method ? STRIPES : "ct:rough=0.3,kd=0.5,f0=0.3",
                         &sc, gb, cc, se, &m));
        free(params);
        for (int path = 0; path < 2; path++) {
            /* path 0: brdfx_material (the method's own where it has
             * one); path 1: the file written from the GPU form, for hf3 */
            static const double uv0[2] = {0.3, 0.62}, uv1[2] = {0.71, 0.4};
            char *text = NULL;
            double t0 = now(), d0 = 0, d1 = 0, apart = 0;
            img a, b;
            int r0, r1 = 0;
            if (path == 1 && !m.method->mat->brdf_explorer)
                break;
            ASSERT_MSG((path ? brdfx_from_gpu(&m, &text, &e)
                             : brdfx_material(&m, &text, &e)) == 0,
                       "%s: %s", meth->name, e.msg);
            ASSERT(!strncmp(text, "analytic\n", 9));
            ASSERT(strstr(text, "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"));
            ASSERT(!strstr(text, "texelFetch") && !strstr(text, "sampler2D") &&
                   !strstr(text, "void main()") && !strstr(text, "o_color"));
            ASSERT_EQ(strstr(text, "float surface_u 0 1 0.5") != NULL, material_spatial(&m));
            r0 = compare(g, gm, &m, text, &sc.views[1], uv0, &d0, &a);
            if (!r0 && material_spatial(&m)) {
                /* the sliders walk the surface: another point, another image */
                r1 = compare(g, gm, &m, text, &sc.views[1], uv1, &d1, &b);
                if (!r1) {
                    apart = mad(&a, &b);
                    img_free(&b);
                }
            }
            if (!r0)
                img_free(&a);
            printf("  %-6s %s: %7zu bytes, %.2f s, mean |BRDF() rendered - cpu| = %.2e%s",
                   meth->name, path ? "(from its GPU form)" : "                   ",
                   strlen(text), now() - t0, d0, material_spatial(&m) ? "" : "\n");
            if (material_spatial(&m))
                printf(", at a second point %.2e (the two points' images %.2e apart)\n", d1,
                       apart);
            free(text);
            if (r0 || r1 || (material_spatial(&m) && !(apart > 1e-3 && apart > 100 * (d0 + d1)))) {
                printf("  %s: the .brdf file does not render as the material\n", meth->name);
                bad++;
            }
        }
        material_free(&m);
    }
    glr_mesh_free(g, gm);
    ASSERT_EQ(bad, 0);
}

/* What cannot be written is refused with the alternative named. */
TEST(refusals_name_the_merl_table)
{
    glint_err e;
    material m;
    char *text = (char *)"x";
    memset(&m, 0, sizeof m);
    ASSERT_EQ(brdfx_material(&m, &text, &e), GLINT_EINVAL);
    ASSERT(text == NULL);
    /* a maps material with more texels than a .brdf embeds */
    {
        const method *meth = method_find("maps");
        void *params = calloc(1, meth->params_size);
        ASSERT_OK(setup());
        ASSERT(params);
        meth->params_default(params);
        ASSERT_OK(method_small_set(meth, params, "res=8,components=4,map_res=64,rounds=1",
                                   &e));
        ASSERT_OK(sv_fit(meth, params, STRIPES, &sc, gb, cc, se, &m));
        free(params);
        ASSERT_EQ(brdfx_material(&m, &text, &e), GLINT_EUNSUPPORTED);
        printf("  refused: %s\n", e.msg);
        ASSERT(strstr(e.msg, "merl.binary") && strstr(e.msg, "map_res"));
        material_free(&m);
    }
}

TEST_LIST{
    TEST_ENTRY(every_method_renders_as_the_material),
    TEST_ENTRY(refusals_name_the_merl_table),
};

TEST_MAIN()
