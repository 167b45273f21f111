/* cmd_scene.c: the glint commands that make a scene and what an artist
 * starts from: scene (create, show), gbuffer, paint (views painted with an
 * analytic BRDF) and base-render (the images painted over). */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdf.h"
#include "cli.h"
#include "env.h"
#include "vis.h"
#include "fsio.h"
#include "measured.h"
#include "merl.h"
#include "paint.h"
#include "raster.h"

/* ---- scene ------------------------------------------------------------------ */

static json_t *scene_describe(const scene *sc, const gbuf *g)
{
    char hash[33];
    json_t *views = json_array();
    long total = 0;
    scene_hash(sc, hash);
    for (int v = 0; v < sc->nviews; v++) {
        const scene_view *sv = &sc->views[v];
        long cnt = 0;
        if (g) {
            size_t np = (size_t)g[v].width * g[v].height;
            for (size_t p = 0; p < np; p++) {
                const float *n = g[v].nrm + 3 * p, *wi = g[v].wi + 3 * p, *wo = g[v].wo + 3 * p;
                if (g[v].mask[p] && n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2] > 0 &&
                    n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2] > 0)
                    cnt++;
            }
            total += cnt;
        }
        json_array_append_new(
            views, json_pack("{s:[f,f,f], s:[f,f,f], s:f, s:f, s:i}", "eye", sv->eye[0],
                             sv->eye[1], sv->eye[2], "light", sv->light[0], sv->light[1],
                             sv->light[2], "light_deg", sv->light_deg, "light_intensity",
                             sv->light_intensity, "samples", (int)cnt));
    }
    return json_pack("{s:s, s:s, s:i, s:i, s:i, s:i, s:i, s:I, s:o}", "hash", hash, "mesh",
                     sc->mesh_name, "vertices", sc->mesh.nverts, "triangles", sc->mesh.ntris,
                     "width", sc->width, "height", sc->height, "views", sc->nviews, "samples",
                     (json_int_t)total, "view_list", views);
}

int cmd_scene(int argc, char **argv)
{
    static const struct option lo[] = {
        {"mesh", required_argument, 0, 'm'}, {"size", required_argument, 0, 's'},
        {"views", required_argument, 0, 'v'}, {"light-angles", required_argument, 0, 'l'},
        {"distance", required_argument, 0, 'd'}, {"out", required_argument, 0, 'o'},
        {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    scene_params p;
    const char *out = NULL;
    int c, rc;
    glint_err e;
    scene sc;
    gbuf *g = NULL;

    if (argc < 2 || (strcmp(argv[1], "create") != 0 && strcmp(argv[1], "show") != 0))
        return fail(1, "usage: glint scene create [options] -o scene.json | glint scene show scene.json");
    if (strcmp(argv[1], "show") == 0) {
        json_t *d;
        if (argc != 3)
            return fail(1, "usage: glint scene show scene.json");
        if ((rc = load_scene(argv[2], &sc)))
            return rc;
        if ((rc = raster_all(&sc, &g))) {
            scene_free(&sc);
            return rc;
        }
        d = scene_describe(&sc, g);
        print_json(d);
        json_decref(d);
        raster_free_all(g, sc.nviews);
        scene_free(&sc);
        return 0;
    }
    scene_params_default(&p);
    optind = 2;
    while ((c = getopt_long(argc, argv, "m:s:v:l:d:o:h", lo, NULL)) != -1) {
        switch (c) {
        case 'm': {
            /* a built-in name, or a mesh file (anything with a '/' or a '.') */
            if (strchr(optarg, '/') || strchr(optarg, '.')) {
                const char *base = strrchr(optarg, '/');
                if (strlen(optarg) >= sizeof p.mesh_path)
                    return fail(1, "--mesh path too long");
                strcpy(p.mesh_path, optarg);
                snprintf(p.mesh_name, sizeof p.mesh_name, "%.*s", (int)sizeof p.mesh_name - 1,
                         base ? base + 1 : optarg);
            } else {
                if (strlen(optarg) >= sizeof p.mesh_name)
                    return fail(1, "--mesh name too long");
                strcpy(p.mesh_name, optarg);
            }
            break;
        }
        case 's':
            if ((rc = parse_size(optarg, &p.width, &p.height)))
                return rc;
            break;
        case 'v':
            if (strcmp(optarg, "ico12") == 0) p.view_set = SCENE_VIEWS_ICO12;
            else if (strcmp(optarg, "ico20") == 0) p.view_set = SCENE_VIEWS_ICO20;
            else return fail(1, "--views '%s': ico12 or ico20", optarg);
            break;
        case 'l': {
            double lo_, hi_;
            char mid[8] = "";
            if (sscanf(optarg, "%lf:%lf:%7s", &lo_, &hi_, mid) < 2 || !isfinite(lo_) ||
                !isfinite(hi_) || lo_ < 0 || hi_ > 180 || lo_ > hi_ ||
                (mid[0] && strcmp(mid, "mid") != 0))
                return fail(1, "--light-angles '%s' must be LO:HI or LO:HI:mid in degrees, 0 <= LO <= HI <= 180", optarg);
            p.light_lo_deg = lo_;
            p.light_hi_deg = hi_;
            p.light_mid = mid[0] != 0;
            break;
        }
        case 'd':
            if ((rc = parse_double(optarg, "--distance", 1.5, 1000.0, &p.distance)))
                return rc;
            break;
        case 'o': out = optarg; break;
        default:
            return fail(1, "usage: glint scene create [--mesh sphere|torus|teapot|FILE] [--size N|WxH] [--views ico12|ico20] [--light-angles LO:HI[:mid]] [--distance D] -o scene.json");
        }
    }
    if (!out)
        return fail(1, "scene create needs -o scene.json");
    if (optind != argc)
        return fail(1, "unexpected argument '%s'", argv[optind]);
    if (scene_create(&p, &sc, &e))
        return fail_err(&e);
    rc = scene_save(&sc, out, &e) ? fail_err(&e) : 0;
    if (!rc) {
        char hash[33];
        scene_hash(&sc, hash);
        printf("%s\n", hash);
    }
    scene_free(&sc);
    return rc;
}

/* ---- gbuffer ---------------------------------------------------------------- */

int cmd_gbuffer(int argc, char **argv)
{
    static const struct option lo[] = {{"out", required_argument, 0, 'o'},
                                       {"view", required_argument, 0, 'v'},
                                       {0, 0, 0, 0}};
    const char *out = NULL;
    int c, rc = 0, only = -1;
    scene sc;
    gbuf *g = NULL;
    glint_err e;

    optind = 1;
    while ((c = getopt_long(argc, argv, "o:v:", lo, NULL)) != -1) {
        if (c == 'o') out = optarg;
        else if (c == 'v') { if ((rc = parse_int(optarg, "--view", 0, SCENE_MAX_VIEWS - 1, &only))) return rc; }
        else return fail(1, "usage: glint gbuffer scene.json -o DIR [--view K]");
    }
    if (!out || optind != argc - 1)
        return fail(1, "usage: glint gbuffer scene.json -o DIR [--view K]");
    if ((rc = load_scene(argv[optind], &sc)))
        return rc;
    if (only >= sc.nviews) {
        rc = fail(1, "--view %d: the scene has %d views", only, sc.nviews);
        goto done;
    }
    if ((rc = raster_all(&sc, &g)))
        goto done;
    if (fsio_mkdirs(out, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    for (int v = 0; v < sc.nviews; v++) {
        char path[4096];
        if (only >= 0 && v != only)
            continue;
        snprintf(path, sizeof path, "%s/view_%02d.exr", out, v);
        if (gbuf_write_exr(&g[v], path, &e)) {
            rc = fail_err(&e);
            goto done;
        }
        printf("%s\n", path);
    }
done:
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
    return rc;
}

/* ---- paint ------------------------------------------------------------------ */

int cmd_paint(int argc, char **argv)
{
    static const struct option lo[] = {
        {"brdf", required_argument, 0, 'b'}, {"out", required_argument, 0, 'o'},
        {"scale", required_argument, 0, 's'}, {"format", required_argument, 0, 'f'},
        {"env", required_argument, 0, 'E'}, {"env-rotation", required_argument, 0, 'R'},
        {"lights", required_argument, 0, 'K'}, {"shadows", required_argument, 0, 'S'},
        {0, 0, 0, 0}};
    const char *out = NULL, *fmt = "exr", *spec = NULL, *env = NULL, *shadows = "auto";
    double scale = 1.0, used = 0.0, rot = 0.0, kl = 256; /* 1: the radiance fits assume */
    int c, rc, is_sv, is_merl, is_fit;
    paint_sv sv;
    merl_table mt = {0};
    measured_truth mf;
    paint_fn fn = NULL;
    const void *fn_ctx = NULL;
    scene sc;
    gbuf *g = NULL;
    img *imgs = NULL;
    brdf b;
    glint_err e;

    optind = 1;
    while ((c = getopt_long(argc, argv, "b:o:s:f:", lo, NULL)) != -1) {
        switch (c) {
        case 'E': env = optarg; break;
        case 'R':
            if ((rc = parse_double(optarg, "--env-rotation", -360, 360, &rot)))
                return rc;
            break;
        case 'K':
            if ((rc = parse_double(optarg, "--lights", 1, 4096, &kl)))
                return rc;
            break;
        case 'S':
            if (strcmp(optarg, "auto") && strcmp(optarg, "on") && strcmp(optarg, "off"))
                return fail(1, "--shadows '%s': auto, on or off", optarg);
            shadows = optarg;
            break;
        case 'b': spec = optarg; break;
        case 'o': out = optarg; break;
        case 's': /* auto: the maximum over the views reads 1 (for 8-bit images) */
            if (!strcmp(optarg, "auto"))
                scale = 0.0;
            else if ((rc = parse_double(optarg, "--scale", 1e-12, 1e12, &scale)))
                return rc;
            break;
        case 'f':
            if (strcmp(optarg, "exr") && strcmp(optarg, "png") && strcmp(optarg, "hdr"))
                return fail(1, "--format '%s': exr, png or hdr", optarg);
            fmt = optarg;
            break;
        default:
            return fail(1, "usage: glint paint scene.json --brdf SPEC -o DIR [--scale S|auto] [--format exr|png|hdr] [--env SPEC [--env-rotation DEG] [--lights K] [--shadows auto|on|off]]");
        }
    }
    if (!out || !spec || optind != argc - 1)
        return fail(1, "usage: glint paint scene.json --brdf SPEC -o DIR [--scale S|auto] [--format exr|png|hdr]");
    /* PATTERN|BRDF|BRDF: a spatially varying truth over the texture coordinates */
    is_sv = strchr(spec, '|') != NULL;
    /* merl:FILE: a measured material, a table in the MERL layout (merl.h) */
    is_merl = !is_sv && strncmp(spec, "merl:", 5) == 0;
    /* sgd:NAME, abc:NAME: a published fit of a measured material (measured.h) */
    is_fit = !is_sv && measured_spec_is(spec);
    if (is_merl ? merl_read(spec + 5, &mt, &e)
        : is_fit ? measured_truth_parse(spec, &mf, &e)
        : is_sv  ? paint_sv_parse(spec, &sv, &e)
                 : brdf_parse(spec, &b, &e))
        return fail_err(&e);
    if (is_merl || is_fit) {
        fn = is_merl ? merl_truth : measured_truth_fn;
        fn_ctx = is_merl ? (const void *)&mt : (const void *)&mf;
    }
    if (is_sv && env)
        return fail(1, "--brdf: a spatially varying truth paints under the views' lights "
                       "(leave out --env)");
    if ((rc = load_scene(argv[optind], &sc))) {
        merl_free(&mt);
        return rc;
    }
    if ((rc = raster_all(&sc, &g)))
        goto done;
    imgs = calloc((size_t)sc.nviews, sizeof *imgs);
    if (!imgs) {
        rc = fail(1, "out of memory");
        goto done;
    }
    if (env) {
        env_map em;
        env_lights el;
        int sh = !strcmp(shadows, "on") ||
                 (!strcmp(shadows, "auto") && !vis_mesh_convex(&sc.mesh, 1e-6));
        memset(&el, 0, sizeof el);
        if (env_resolve(env, &em, &e) ||
            env_compress(&em, ENV_CUT_MEDIAN, (int)kl, rot * 3.14159265358979323846 / 180.0,
                         1.0, &el, &e)) {
            rc = fail_err(&e);
            goto done;
        }
        env_map_free(&em);
        used = scale > 0.0 ? scale : 1.0;
        rc = fn ? paint_views_env_fn(fn, fn_ctx, g, sc.nviews, &sc.mesh, &el, sh, used, imgs, &e)
                : paint_views_env(&b, g, sc.nviews, &sc.mesh, &el, sh, used, imgs, &e);
        env_lights_free(&el);
        if (rc) {
            rc = fail_err(&e);
            goto done;
        }
    } else if (fn ? paint_views_fn(fn, fn_ctx, g, sc.views, sc.nviews, scale, imgs, &used, &e)
               : is_sv ? paint_views_sv(&sv, g, sc.views, sc.nviews, scale, imgs, &used, &e)
                       : paint_views(&b, g, sc.views, sc.nviews, scale, imgs, &used, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if (fsio_mkdirs(out, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    for (int v = 0; v < sc.nviews; v++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/view_%02d.%s", out, v, fmt);
        if (img_write(path, &imgs[v], &e)) {
            rc = fail_err(&e);
            goto done;
        }
    }
    {
        char path[4096], bs[256];
        json_t *j;
        if (is_sv || fn)
            snprintf(bs, sizeof bs, "%s", spec);
        else
            brdf_format(&b, bs, sizeof bs);
        snprintf(path, sizeof path, "%s/paint.json", out);
        j = json_pack("{s:s, s:f, s:s, s:i}", "brdf", bs, "scale", used, "format", fmt, "views",
                      sc.nviews);
        rc = write_json_file(path, j);
        if (!rc)
            print_json(j);
        json_decref(j);
    }
done:
    free_imgs(imgs, sc.nviews);
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
    merl_free(&mt);
    return rc;
}

/* ---- base renders ----------------------------------------------------------- */

int cmd_base_render(int argc, char **argv)
{
    static const struct option lo[] = {{"out", required_argument, 0, 'o'},
                                       {"brdf", required_argument, 0, 'b'},
                                       {"scale", required_argument, 0, 's'},
                                       {"engine", required_argument, 0, 'g'},
                                       {"format", required_argument, 0, 'f'},
                                       {0, 0, 0, 0}};
    static const char usage_base[] =
        "usage: glint base-render scene.json -o DIR [--brdf SPEC] [--scale S] "
        "[--engine auto|egl|cpu] [--format png|exr]";
    const char *out = NULL, *spec = "lambert:kd=0.6", *fmt = "png";
    render_engine engine = RENDER_AUTO;
    double scale = 1.0; /* scene.h's radiance: a white Lambertian facing the light reads I */
    int c, rc = 0;
    scene sc;
    glint_err e;

    optind = 1;
    while ((c = getopt_long(argc, argv, "o:b:s:g:f:", lo, NULL)) != -1) {
        if (c == 'o') out = optarg;
        else if (c == 'b') spec = optarg;
        else if (c == 's') { if ((rc = parse_double(optarg, "--scale", 1e-9, 1e9, &scale))) return rc; }
        else if (c == 'g') { if (render_engine_parse(optarg, &engine, &e)) return fail(1, "--%s", e.msg); }
        else if (c == 'f') fmt = optarg;
        else return fail(1, "%s", usage_base);
    }
    if (!out || optind != argc - 1)
        return fail(1, "%s", usage_base);
    if (strcmp(fmt, "png") && strcmp(fmt, "exr"))
        return fail(1, "--format '%s': png or exr", fmt);
    if (render_brdf_check(spec, &e))
        return fail_err(&e);
    if ((rc = load_scene(argv[optind], &sc)))
        return rc;
    if (fsio_mkdirs(out, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    for (int v = 0; v < sc.nviews; v++) {
        img im = {0};
        char path[4096];
        snprintf(path, sizeof path, "%s/view_%02d.%s", out, v, fmt);
        if (render_base(cli_render(), engine, "scene", &sc.mesh, &sc.views[v], sc.width,
                        sc.height, spec, scale, &im, NULL, NULL, &e) ||
            img_write(path, &im, &e)) {
            img_free(&im);
            rc = fail_err(&e);
            goto done;
        }
        img_free(&im);
        printf("%s\n", path);
    }
done:
    scene_free(&sc);
    return rc;
}
