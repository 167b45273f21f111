/* cmd_render.c: the glint commands that use a fitted material: render
 * (any camera and light, on EGL or the CPU), eval (at given directions)
 * and export-shader; and the process's renderer (render.h). */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdf.h"
#include "brdfx.h"
#include "cli.h"
#include "env.h"
#include "fsio.h"
#include "glr.h"
#include "gltf.h"
#include "mtlx.h"
#include "usda.h"
#include "usdz.h"
#include "measured.h"
#include "merl.h"
#include "merl_material.h"
#include "readable.h"
#include "samples.h"
#include "raster.h"

/* ---- the renderer ------------------------------------------------------------- */

static render *the_render;

render *cli_render(void)
{
    glint_err e;
    if (!the_render && render_open(4, 0, &the_render, &e))
        the_render = NULL;
    return the_render;
}

void cli_render_close(void)
{
    render_close(the_render);
    the_render = NULL;
}

/* ---- render ----------------------------------------------------------------- */

static const char usage_render[] =
    "usage: glint render MATDIR --scene scene.json (--view K | --eye X,Y,Z --light X,Y,Z) "
    "[--size WxH] [--engine auto|egl|cpu] [--env SPEC [--env-rotation DEG] "
    "[--env-intensity X] [--lights K] [--no-shadows] [--no-background]] -o image.png|exr\n"
    "  --env: light with an environment (a built-in sky, or file:PATH of an HDR map) "
    "instead of the point light; --eye then needs no --light";

int cmd_render(int argc, char **argv)
{
    static const struct option lo[] = {
        {"scene", required_argument, 0, 's'}, {"view", required_argument, 0, 'v'},
        {"eye", required_argument, 0, 'e'}, {"target", required_argument, 0, 't'},
        {"light", required_argument, 0, 'l'}, {"fov", required_argument, 0, 'f'},
        {"intensity", required_argument, 0, 'i'}, {"size", required_argument, 0, 'z'},
        {"engine", required_argument, 0, 'g'}, {"out", required_argument, 0, 'o'},
        {"env", required_argument, 0, 1000}, {"env-rotation", required_argument, 0, 1001},
        {"env-intensity", required_argument, 0, 1002}, {"lights", required_argument, 0, 1003},
        {"no-shadows", no_argument, 0, 1004}, {"no-background", no_argument, 0, 1005},
        {0, 0, 0, 0}};
    const char *scene_path = NULL, *out = NULL;
    int c, rc = 0, view = -1, w = 0, h = 0;
    render_engine engine = RENDER_AUTO;
    render_camera cam;
    render_env env;
    render_env_info info;
    int has_env = 0;
    scene sc;
    material m;
    scene_view v;
    img im = {0};
    glint_err e;

    memset(&sc, 0, sizeof sc);
    render_camera_init(&cam);
    render_env_init(&env);
    optind = 1;
    while ((c = getopt_long(argc, argv, "s:v:o:", lo, NULL)) != -1) {
        switch (c) {
        case 's': scene_path = optarg; break;
        case 'v': if ((rc = parse_int(optarg, "--view", 0, SCENE_MAX_VIEWS - 1, &view))) return rc; break;
        case 'e': if ((rc = parse_vec3(optarg, "--eye", cam.eye))) return rc; cam.has_eye = 1; break;
        case 't': if ((rc = parse_vec3(optarg, "--target", cam.target))) return rc; cam.has_target = 1; break;
        case 'l': if ((rc = parse_vec3(optarg, "--light", cam.light))) return rc; cam.has_light = 1; break;
        case 'f': if ((rc = parse_double(optarg, "--fov", 1.0, 170.0, &cam.fov_deg))) return rc; break;
        case 'i': if ((rc = parse_double(optarg, "--intensity", 0.0, 1e6, &cam.intensity))) return rc; break;
        case 'z': if ((rc = parse_size(optarg, &w, &h))) return rc; break;
        case 'g': if (render_engine_parse(optarg, &engine, &e)) return fail(1, "--%s", e.msg); break;
        case 'o': out = optarg; break;
        case 1000:
            if (env_spec_check(optarg, &e))
                return fail(1, "--env: %s", e.msg);
            snprintf(env.spec, sizeof env.spec, "%s", optarg);
            has_env = 1;
            break;
        case 1001: if ((rc = parse_double(optarg, "--env-rotation", -360.0, 360.0, &env.rotation_deg))) return rc; break;
        case 1002: if ((rc = parse_double(optarg, "--env-intensity", 1e-12, 1e6, &env.intensity))) return rc; break;
        case 1003: if ((rc = parse_int(optarg, "--lights", 1, RENDER_ENV_MAX_LIGHTS, &env.lights))) return rc; break;
        case 1004: env.shadows = 0; break;
        case 1005: env.background = 0; break;
        default: return fail(1, "%s", usage_render);
        }
    }
    if (!out || !scene_path || optind != argc - 1)
        return fail(1, "%s", usage_render);
    if (view < 0 && !(cam.has_eye && (cam.has_light || has_env)))
        return fail(1, "render needs --view K, or both --eye and --light (--eye alone with --env)");
    if (has_env && cam.has_eye && !cam.has_light) { /* the environment lights it */
        memcpy(cam.light, cam.eye, sizeof cam.light);
        cam.has_light = 1;
    }
    if (material_load(argv[optind], &m, &e))
        return fail_err(&e);
    if ((rc = load_scene(scene_path, &sc)))
        goto done;
    if (view >= sc.nviews) {
        rc = fail(1, "--view %d: the scene has %d views", view, sc.nviews);
        goto done;
    }
    cam.view = view;
    if (render_camera_view(&sc, &cam, &v, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if (!w) {
        w = sc.width;
        h = sc.height;
    }
    if ((has_env ? render_material_env(cli_render(), engine, NULL, &sc.mesh, &m, &env, &v, w, h,
                                       &im, &info, NULL, NULL, &e)
                 : render_material(cli_render(), engine, NULL, &sc.mesh, &m, &v, w, h, &im, NULL,
                                   NULL, &e)) ||
        img_write(out, &im, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if (has_env)
        printf("%s  (%s, %d lights, shadows %s, %.0f ms shading)\n", out, info.env, info.lights,
               !env.shadows ? "off" : info.convex ? "none: the mesh is convex" : "cast",
               1e3 * info.shade_s);
    else
        printf("%s\n", out);
done:
    img_free(&im);
    material_free(&m);
    scene_free(&sc);
    return rc;
}

/* ---- eval ------------------------------------------------------------------- */

int cmd_eval(int argc, char **argv)
{
    material m;
    glint_err e;
    FILE *in, *outf = stdout;
    char line[1024];
    long lineno = 0;
    int rc = 0;
    const char *dirs = NULL, *out = NULL;

    for (int i = 2; i < argc; i++) {
        if (strcmp(argv[i], "--dirs") == 0 && i + 1 < argc) dirs = argv[++i];
        else if (strcmp(argv[i], "-o") == 0 && i + 1 < argc) out = argv[++i];
        else return fail(1, "usage: glint eval MATDIR --dirs FILE [-o OUT]");
    }
    if (argc < 2 || !dirs)
        return fail(1, "usage: glint eval MATDIR --dirs FILE [-o OUT]  (FILE: lines 'nx ny nz wix wiy wiz wox woy woz [u v]', or 'wix wiy wiz wox woy woz' with n = +z; u v: texture coordinates, for materials that vary over the surface)");
    if (material_load(argv[1], &m, &e))
        return fail_err(&e);
    in = strcmp(dirs, "-") == 0 ? stdin : fopen(dirs, "r");
    if (!in) {
        material_free(&m);
        return fail(2, "cannot read %s: %s", dirs, strerror(errno));
    }
    if (out && !(outf = fopen(out, "w"))) {
        rc = fail(2, "cannot write %s: %s", out, strerror(errno));
        goto done;
    }
    while (fgets(line, sizeof line, in)) {
        double v[11], n[3], wi[3], wo[3], rgb[3];
        int got;
        lineno++;
        if (line[0] == '#' || line[strspn(line, " \t\r\n")] == '\0')
            continue;
        got = sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2],
                     &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10]);
        if (got != 6 && got != 9 && got != 11) {
            rc = fail(1, "%s line %ld: expected 6, 9 or 11 numbers", dirs, lineno);
            goto done;
        }
        if (got == 11 && !(v[9] >= 0.0 && v[9] <= 1.0 && v[10] >= 0.0 && v[10] <= 1.0)) {
            rc = fail(1, "%s line %ld: texture coordinates u v must be in [0, 1]", dirs, lineno);
            goto done;
        }
        for (int k = 0; k < got; k++)
            if (!isfinite(v[k])) {
                rc = fail(1, "%s line %ld: number %d is not finite", dirs, lineno, k + 1);
                goto done;
            }
        if (got == 6) {
            n[0] = n[1] = 0; n[2] = 1;
            memcpy(wi, v, sizeof wi);
            memcpy(wo, v + 3, sizeof wo);
        } else {
            memcpy(n, v, sizeof n);
            memcpy(wi, v + 3, sizeof wi);
            memcpy(wo, v + 6, sizeof wo);
        }
        {
            double *vs[3] = {n, wi, wo};
            for (int k = 0; k < 3; k++) {
                double l = sqrt(vs[k][0] * vs[k][0] + vs[k][1] * vs[k][1] + vs[k][2] * vs[k][2]);
                if (!(l > 1e-12)) {
                    rc = fail(1, "%s line %ld: zero-length direction", dirs, lineno);
                    goto done;
                }
                for (int c = 0; c < 3; c++)
                    vs[k][c] /= l;
            }
        }
        material_eval_at(&m, got == 11 ? v + 9 : NULL, n, wi, wo, rgb);
        fprintf(outf, "%.9g %.9g %.9g\n", rgb[0], rgb[1], rgb[2]);
    }
done:
    if (in != stdin)
        fclose(in);
    if (outf != stdout && outf && fclose(outf) != 0 && !rc)
        rc = fail(2, "writing %s failed", out);
    material_free(&m);
    return rc;
}

/* ---- shader export ---------------------------------------------------------- */

int cmd_export_shader(int argc, char **argv)
{
    material m;
    glint_err e;
    int rc = 0;
    if (argc != 4 || strcmp(argv[2], "-o") != 0)
        return fail(1, "usage: glint export-shader MATDIR -o DIR");
    if (material_load(argv[1], &m, &e))
        return fail_err(&e);
    if (glr_shader_export(&m, argv[3], &e))
        rc = fail_err(&e);
    else
        printf("%s/glint_material.frag, .vert, glint_factors.exr, shader.json\n", argv[3]);
    material_free(&m);
    return rc;
}

/* glint summary MATDIR: the material in words and numbers (readable.h), as
 * JSON on stdout. */
int cmd_summary(int argc, char **argv)
{
    material m;
    glint_err e;
    json_t *o;
    if (argc != 2)
        return fail(1, "usage: glint summary MATDIR");
    if (material_load(argv[1], &m, &e))
        return fail_err(&e);
    if (material_readable(&m, &o, &e)) {
        material_free(&m);
        return fail_err(&e);
    }
    json_dumpf(o, stdout, JSON_INDENT(2) | JSON_REAL_PRECISION(6));
    fputc('\n', stdout);
    json_decref(o);
    material_free(&m);
    return 0;
}

/* brdf_eval as a merl_fn */
static void merl_brdf(const void *ctx, const double n[3], const double wi[3], const double wo[3],
                      double f[3])
{
    brdf_eval(ctx, n, wi, wo, f);
}

/* glint export-merl (MATDIR | --brdf SPEC) -o FILE.binary: a material, or
 * an analytic truth, tabulated in the MERL layout (merl.h), with what
 * tabulating did on stdout as JSON. */
int cmd_export_merl(int argc, char **argv)
{
    material m;
    merl_table t;
    merl_stats st;
    glint_err e;
    int rc = 0;
    brdf b;
    measured_truth mf;
    int truth = argc == 5 && strcmp(argv[1], "--brdf") == 0;
    int fit = truth && measured_spec_is(argv[2]);
    if (!(argc == 4 || truth) || strcmp(argv[argc - 2], "-o") != 0)
        return fail(1, "usage: glint export-merl (MATDIR | --brdf SPEC) -o FILE.binary");
    memset(&m, 0, sizeof m);
    if (fit ? measured_truth_parse(argv[2], &mf, &e)
        : truth ? brdf_parse(argv[2], &b, &e)
                : material_load(argv[1], &m, &e))
        return fail_err(&e);
    if ((fit ? merl_tabulate(measured_truth_fn, &mf, 0, &t, &st, &e)
         : truth ? merl_tabulate(merl_brdf, &b, 0, &t, &st, &e)
               : merl_from_material(&m, 0, &t, &st, &e)) ||
        merl_write(&t, argv[argc - 1], &e))
        rc = fail_err(&e);
    else
        printf("{\"file\": \"%s\", \"layout\": \"MERL 90x90x180\", \"anisotropic\": %s, "
               "\"azimuths_averaged\": %d, \"spatial_average\": %s, \"bins_below_horizon\": %ld, "
               "\"bins_nonfinite\": %ld, \"bins_negative\": %ld, \"max_f\": %.6g, "
               "\"seconds\": %.3f}\n",
               argv[argc - 1], st.anisotropic ? "true" : "false", st.azimuths,
               st.spatial ? "true" : "false", st.below_horizon, st.nonfinite, st.negative,
               st.max_f, st.seconds);
    merl_free(&t);
    material_free(&m);
    return rc;
}

/* glint export-brdf MATDIR -o FILE.brdf: the material as BRDF Explorer's
 * analytic .brdf file (brdfx_material). */
int cmd_export_brdf(int argc, char **argv)
{
    material m;
    glint_err e;
    char *text = NULL;
    int rc = 0;
    if (argc != 4 || strcmp(argv[2], "-o") != 0)
        return fail(1, "usage: glint export-brdf MATDIR -o FILE.brdf");
    if (material_load(argv[1], &m, &e))
        return fail_err(&e);
    if (brdfx_material(&m, &text, &e) ||
        fsio_write_atomic(argv[3], text, strlen(text), &e))
        rc = fail_err(&e);
    else
        printf("%s: BRDF Explorer analytic BRDF, %zu bytes\n", argv[3], strlen(text));
    free(text);
    material_free(&m);
    return rc;
}

/* ", \"export\": ..., \"rel_rms_fitted\": ..., \"rel_rms_exact\": ...,
 * \"extensions\": [...]" of the printed JSON: which path the material took
 * (its pbr parameters mapped, or the fit), both errors and the KHR
 * extensions (gltf.h), and an anisotropic material's fit.  Returns buf. */
static const char *path_json(const gltf_pbr *p, char *buf, size_t cap)
{
    const char *names[GLTF_KHR_MAX];
    int n = gltf_khr_names(p, names), k;
    k = snprintf(buf, cap, ", \"export\": \"%s\", \"rel_rms_fitted\": %.4f",
                 p->exact ? "exact parameters" : "fitted", p->rel_rms_fitted);
    if (k > 0 && (size_t)k < cap && isfinite(p->rel_rms_exact))
        k += snprintf(buf + k, cap - (size_t)k, ", \"rel_rms_exact\": %.4f", p->rel_rms_exact);
    if (k > 0 && (size_t)k < cap)
        k += snprintf(buf + k, cap - (size_t)k, ", \"extensions\": [");
    for (int i = 0; i < n && k > 0 && (size_t)k < cap; i++)
        k += snprintf(buf + k, cap - (size_t)k, "%s\"%s\"", i ? ", " : "", names[i]);
    if (k > 0 && (size_t)k < cap)
        k += snprintf(buf + k, cap - (size_t)k, "]");
    if (k > 0 && (size_t)k < cap && p->aniso.used) /* the .glb's, in place of the numbers above */
        snprintf(buf + k, cap - (size_t)k,
                 ", \"anisotropic_fit\": {\"strength\": %.4f, \"rotation\": %.4f, "
                 "\"base_color\": [%.4f, %.4f, %.4f], \"metallic\": %.4f, \"roughness\": %.4f, "
                 "\"rel_rms\": %.4f}",
                 p->aniso.strength, p->aniso.rotation, p->aniso.base[0], p->aniso.base[1],
                 p->aniso.base[2], p->aniso.metallic, p->aniso.roughness, p->aniso.rel_rms);
    return buf;
}

/* What export_baked writes. */
enum { BAKED_GLB, BAKED_USDZ, BAKED_MTLX };

/* glint export-gltf | export-usdz | export-mtlx-zip MATDIR --scene
 * scene.json [--paintings DIR] [--bake-res N] -o FILE: the scene's mesh
 * with the glTF metallic-roughness material fitted to MATDIR at the
 * samples of the painted views (those with a file in DIR; every view
 * without it), baked into N x N textures (default GLTF_BAKE_RES_DEFAULT,
 * 0: the average only) where the material varies over the surface
 * (gltf.h), as a .glb, as a USDZ package: a USD layer with a
 * UsdPreviewSurface reading the same textures (usdz.h), or as a MaterialX
 * package: a standard_surface reading them (mtlx.h). */
static int export_baked(int argc, char **argv, int kind)
{
    static const char *const usages[] = {
        "usage: glint export-gltf MATDIR --scene scene.json [--paintings DIR] [--bake-res N] "
        "-o FILE.glb",
        "usage: glint export-usdz MATDIR --scene scene.json [--paintings DIR] [--bake-res N] "
        "-o FILE.usdz",
        "usage: glint export-mtlx-zip MATDIR --scene scene.json [--paintings DIR] "
        "[--bake-res N] -o FILE.zip"};
    static const struct option lo[] = {{"scene", required_argument, 0, 's'},
                                       {"paintings", required_argument, 0, 'p'},
                                       {"out", required_argument, 0, 'o'},
                                       {"bake-res", required_argument, 0, 'b'},
                                       {0, 0, 0, 0}};
    const char *usage = usages[kind];
    const char *scn = NULL, *pdir = NULL, *out = NULL;
    unsigned char use[SCENE_MAX_VIEWS];
    material m;
    scene sc;
    gltf_pbr p;
    gltf_export_info gi;
    char pj[700];
    long bake_res = GLTF_BAKE_RES_DEFAULT;
    char *end;
    glint_err e;
    void *glb = NULL;
    size_t len = 0;
    char path[4096];
    int c, rc = 0;

    optind = 1;
    while ((c = getopt_long(argc, argv, "o:", lo, NULL)) != -1) {
        if (c == 's') scn = optarg;
        else if (c == 'p') pdir = optarg;
        else if (c == 'o') out = optarg;
        else if (c == 'b') {
            bake_res = strtol(optarg, &end, 10);
            if (end == optarg || *end || bake_res < 0 || bake_res > GLTF_BAKE_RES_MAX)
                return fail(1, "--bake-res must be an integer in 0..%d (0: no textures), not '%s'",
                            GLTF_BAKE_RES_MAX, optarg);
        } else return fail(1, "%s", usage);
    }
    if (!scn || !out || optind != argc - 1)
        return fail(1, "%s", usage);
    if (material_load(argv[optind], &m, &e))
        return fail_err(&e);
    if ((rc = load_scene(scn, &sc))) {
        material_free(&m);
        return rc;
    }
    for (int v = 0; v < sc.nviews; v++)
        use[v] = !pdir || find_painting(pdir, v, path, sizeof path);
    if ((kind == BAKED_USDZ
             ? usdz_export_scene(&m, &sc, use, (int)bake_res, NULL, &glb, &len, &p, &gi, &e)
         : kind == BAKED_MTLX ? mtlx_export_scene(&m, &sc, use, (int)bake_res, "glint", NULL,
                                                  &glb, &len, &p, &gi, &e)
                              : gltf_export_scene(&m, &sc, use, (int)bake_res, &glb, &len, &p,
                                                  &gi, &e)) ||
        fsio_write_atomic(out, glb, len, &e))
        rc = fail_err(&e);
    else if (gi.baked)
        printf("{\"file\": \"%s\", \"bytes\": %zu, \"average\": {\"base_color\": [%.4f, "
               "%.4f, %.4f], \"metallic\": %.4f, \"roughness\": %.4f, \"fit_rel_rms\": %.4f}, "
               "\"pairs\": %d%s, \"textures\": {\"res\": %d, \"pairs_per_texel\": %d, "
               "\"texel_rel_rms_median\": %.4f, \"texel_rel_rms_max\": %.4f, "
               "\"seconds\": %.3f}}\n",
               out, len, p.base[0], p.base[1], p.base[2], p.metallic, p.roughness, p.rel_rms,
               p.pairs, path_json(&p, pj, sizeof pj), gi.res, gi.pairs, gi.rel_rms_median,
               gi.rel_rms_max, gi.seconds);
    else
        printf("{\"file\": \"%s\", \"bytes\": %zu, \"base_color\": [%.4f, %.4f, %.4f], "
               "\"metallic\": %.4f, \"roughness\": %.4f, \"fit_rel_rms\": %.4f, "
               "\"pairs\": %d%s%s%s%s}\n",
               out, len, p.base[0], p.base[1], p.base[2], p.metallic, p.roughness, p.rel_rms,
               p.pairs, path_json(&p, pj, sizeof pj), gi.note[0] ? ", \"textures_not_baked\": \"" : "", gi.note,
               gi.note[0] ? "\"" : "");
    free(glb);
    scene_free(&sc);
    material_free(&m);
    return rc;
}

int cmd_export_gltf(int argc, char **argv) { return export_baked(argc, argv, BAKED_GLB); }
int cmd_export_usdz(int argc, char **argv) { return export_baked(argc, argv, BAKED_USDZ); }
int cmd_export_mtlx_zip(int argc, char **argv) { return export_baked(argc, argv, BAKED_MTLX); }

/* glint export-mtlx | export-usda MATDIR --scene scene.json [--paintings DIR]
 * [--no-mesh] -o FILE: the metallic-roughness fit export-gltf makes (the
 * samples of the painted views), as a MaterialX standard_surface (mtlx.h)
 * or a USD layer with a UsdPreviewSurface and the scene's mesh (usda.h;
 * --no-mesh: the material alone).  Both carry the average over the
 * surface (no textures: export-usdz and export-mtlx-zip carry them).  Prints the fit and its
 * relative RMS as JSON. */
static int export_fitted(int argc, char **argv, int usd)
{
    static const struct option lo[] = {{"scene", required_argument, 0, 's'},
                                       {"paintings", required_argument, 0, 'p'},
                                       {"out", required_argument, 0, 'o'},
                                       {"no-mesh", no_argument, 0, 'n'},
                                       {0, 0, 0, 0}};
    const char *scn = NULL, *pdir = NULL, *out = NULL;
    unsigned char use[SCENE_MAX_VIEWS];
    material m;
    scene sc;
    gltf_pbr p;
    glint_err e;
    char *text = NULL, path[4096], pj[700];
    size_t len = 0;
    int c, rc = 0, no_mesh = 0;

    optind = 1;
    while ((c = getopt_long(argc, argv, "o:", lo, NULL)) != -1) {
        if (c == 's') scn = optarg;
        else if (c == 'p') pdir = optarg;
        else if (c == 'o') out = optarg;
        else if (c == 'n' && usd) no_mesh = 1;
        else scn = NULL, optind = argc; /* usage below */
    }
    if (!scn || !out || optind != argc - 1)
        return fail(1, "usage: glint %s MATDIR --scene scene.json [--paintings DIR]%s -o FILE%s",
                    usd ? "export-usda" : "export-mtlx", usd ? " [--no-mesh]" : "",
                    usd ? ".usda" : ".mtlx");
    if (material_load(argv[optind], &m, &e))
        return fail_err(&e);
    if ((rc = load_scene(scn, &sc))) {
        material_free(&m);
        return rc;
    }
    for (int v = 0; v < sc.nviews; v++)
        use[v] = !pdir || find_painting(pdir, v, path, sizeof path);
    if (gltf_fit_scene(&m, &sc, use, &p, &e) ||
        (usd ? usda_write(&p, no_mesh ? NULL : &sc.mesh, NULL, &text, &len, &e)
             : mtlx_write(&p, "glint", NULL, &text, &e)) ||
        fsio_write_atomic(out, text, strlen(text), &e))
        rc = fail_err(&e);
    else
        printf("{\"file\": \"%s\", \"bytes\": %zu, \"base_color\": [%.4f, %.4f, %.4f], "
               "\"metallic\": %.4f, \"roughness\": %.4f, \"fit_rel_rms\": %.4f, \"pairs\": %d%s, "
               "\"spatial_average\": %s}\n",
               out, strlen(text), p.base[0], p.base[1], p.base[2], p.metallic, p.roughness,
               p.rel_rms, p.pairs, path_json(&p, pj, sizeof pj), p.spatial ? "true" : "false");
    free(text);
    scene_free(&sc);
    material_free(&m);
    return rc;
}

int cmd_export_mtlx(int argc, char **argv) { return export_fitted(argc, argv, 0); }
int cmd_export_usda(int argc, char **argv) { return export_fitted(argc, argv, 1); }
